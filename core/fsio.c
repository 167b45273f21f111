#include "fsio.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int fsio_join(char *buf, size_t len, const char *dir, const char *name, glint_err *err)
{
    int n = snprintf(buf, len, "%s/%s", dir, name);
    if (n < 0 || (size_t)n >= len)
        return glint_err_set(err, GLINT_ERANGE, "path too long: %s/%s", dir, name);
    return 0;
}

int fsio_write_atomic(const char *path, const void *data, size_t len, glint_err *err)
{
    char tmp[4096];
    const char *p = data;
    int fd, n;

    n = snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid());
    if (n < 0 || (size_t)n >= sizeof tmp)
        return glint_err_set(err, GLINT_ERANGE, "path too long: %s", path);
    fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0)
        return glint_err_set(err, GLINT_EIO, "cannot create %s: %s", tmp, strerror(errno));
    while (len > 0) {
        ssize_t w = write(fd, p, len);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            goto fail;
        }
        p += w;
        len -= (size_t)w;
    }
    if (fsync(fd) != 0)
        goto fail;
    if (close(fd) != 0) {
        fd = -1;
        goto fail;
    }
    fd = -1;
    if (rename(tmp, path) != 0)
        goto fail;
    return 0;
fail:
    n = errno;
    if (fd >= 0)
        close(fd);
    unlink(tmp);
    return glint_err_set(err, GLINT_EIO, "writing %s failed: %s", path, strerror(n));
}

int fsio_read_all(const char *path, size_t max_len, char **data, size_t *len, glint_err *err)
{
    FILE *fp = fopen(path, "rb");
    char *buf = NULL;
    size_t cap = 0, used = 0;

    *data = NULL;
    if (len)
        *len = 0;
    if (!fp)
        return glint_err_set(err, errno == ENOENT ? GLINT_ENOTFOUND : GLINT_EIO,
                             "cannot read %s: %s", path, strerror(errno));
    for (;;) {
        size_t got;
        if (used + 4096 + 1 > cap) {
            size_t ncap = cap ? 2 * cap : 65536;
            char *nb = realloc(buf, ncap);
            if (!nb) {
                free(buf);
                fclose(fp);
                return glint_err_set(err, GLINT_ENOMEM, "out of memory reading %s", path);
            }
            buf = nb;
            cap = ncap;
        }
        got = fread(buf + used, 1, cap - used - 1, fp);
        used += got;
        if (used > max_len) {
            free(buf);
            fclose(fp);
            return glint_err_set(err, GLINT_ERANGE, "%s is larger than %zu bytes", path,
                                 max_len);
        }
        if (got == 0)
            break;
    }
    if (ferror(fp)) {
        free(buf);
        fclose(fp);
        return glint_err_set(err, GLINT_EIO, "reading %s failed", path);
    }
    fclose(fp);
    buf[used] = '\0';
    *data = buf;
    if (len)
        *len = used;
    return 0;
}

int fsio_mkdirs(const char *path, glint_err *err)
{
    char buf[4096];
    size_t n = strlen(path);

    if (n == 0 || n >= sizeof buf)
        return glint_err_set(err, GLINT_EINVAL, "bad directory path '%s'", path);
    memcpy(buf, path, n + 1);
    for (size_t i = 1; i <= n; i++) {
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0755) != 0 && errno != EEXIST)
                return glint_err_set(err, GLINT_EIO, "cannot create directory %s: %s", buf,
                                     strerror(errno));
            buf[i] = c;
        }
    }
    return 0;
}
