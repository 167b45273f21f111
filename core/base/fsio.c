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

/* fsync the directory holding `path`, so the rename itself is durable.
 * Best effort: a file system that refuses loses durability, not data. */

int fsio_err_kind(glint_err *err, int errnum)
{
    if (errnum == ENOSPC || errnum == EDQUOT || errnum == EFBIG)
        return glint_err_kind(err, "storage-full");
    if (errnum == EROFS || errnum == EACCES || errnum == EPERM)
        return glint_err_kind(err, "storage-read-only");
    return err ? err->code : GLINT_EIO;
}

static void sync_dir(const char *path)
{
    const char *slash = strrchr(path, '/');
    char *dir;
    int fd;

    if (!slash)
        dir = strdup(".");
    else if (slash == path)
        dir = strdup("/");
    else
        dir = strndup(path, (size_t)(slash - path));
    if (!dir)
        return;
    fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
    free(dir);
}

static __thread fsio_group *cur_group;

void fsio_group_begin(fsio_group *g)
{
    memset(g, 0, sizeof *g);
    cur_group = g;
}

static void group_add(fsio_group *g, const char *path)
{
    char *p;
    if (g->n == g->cap) {
        int ncap = g->cap ? 2 * g->cap : 8;
        char **np = realloc(g->paths, (size_t)ncap * sizeof *np);
        if (!np) {
            g->failed = 1;
            return;
        }
        g->paths = np;
        g->cap = ncap;
    }
    if (!(p = strdup(path))) {
        g->failed = 1;
        return;
    }
    g->paths[g->n++] = p;
}

static int sync_path(const char *path, int dir)
{
    int fd = open(path, (dir ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC), rc;
    if (fd < 0)
        return -1;
    rc = fsync(fd);
    close(fd);
    return rc;
}

int fsio_group_end(fsio_group *g, glint_err *err)
{
    int rc = 0, nfiles;
    cur_group = NULL;
    if (g->failed)
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory making files durable");
    for (int i = 0; i < g->n && !rc; i++)
        if (sync_path(g->paths[i], 0) != 0) {
            int e = errno;
            rc = glint_err_set(err, GLINT_EIO, "%s: fsync failed: %s", g->paths[i],
                               strerror(e));
            fsio_err_kind(err, e);
        }
    /* then each directory once (best effort, as sync_dir) */
    nfiles = g->n;
    for (int i = 0; i < nfiles && !rc; i++) {
        char *slash = strrchr(g->paths[i], '/');
        int seen = 0;
        if (slash)
            *slash = '\0';
        for (int j = 0; j < i && !seen; j++)
            seen = strcmp(g->paths[j], g->paths[i]) == 0;
        if (!seen) {
            /* the directory, then its parent: the group's directory may be
             * new (a material's), and its own entry must last too */
            char *up = slash ? strrchr(g->paths[i], '/') : NULL;
            (void)sync_path(slash ? g->paths[i] : ".", 1);
            if (up) {
                *up = '\0';
                (void)sync_path(up == g->paths[i] ? "/" : g->paths[i], 1);
                *up = '/';
            }
        }
    }
    for (int i = 0; i < g->n; i++)
        free(g->paths[i]);
    free(g->paths);
    memset(g, 0, sizeof *g);
    return rc;
}

void fsio_atomic_abort(fsio_atomic *a)
{
    if (!a)
        return;
    if (a->fp)
        fclose(a->fp);
    if (a->tmp)
        unlink(a->tmp);
    free(a->tmp);
    free(a->path);
    memset(a, 0, sizeof *a);
}

int fsio_atomic_open(fsio_atomic *a, const char *path, glint_err *err)
{
    static const char suffix[] = ".tmp-XXXXXX";
    size_t plen;
    int fd;

    memset(a, 0, sizeof *a);
    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "empty output path");
    plen = strlen(path);
    a->path = strdup(path);
    a->tmp = malloc(plen + sizeof suffix);
    if (!a->path || !a->tmp) {
        fsio_atomic_abort(a);
        return glint_err_set(err, GLINT_ENOMEM, "%s: out of memory", path);
    }
    memcpy(a->tmp, path, plen);
    memcpy(a->tmp + plen, suffix, sizeof suffix);
    fd = mkstemp(a->tmp);
    if (fd < 0) {
        int e = errno;
        free(a->tmp);
        a->tmp = NULL;
        fsio_atomic_abort(a);
        glint_err_set(err, GLINT_EIO, "%s: cannot create a temporary file: %s", path,
                      strerror(e));
        return fsio_err_kind(err, e);
    }
    (void)fchmod(fd, 0644); /* mkstemp makes 0600; glint's files are not secrets */
    a->fp = fdopen(fd, "wb");
    if (!a->fp) {
        int e = errno;
        close(fd);
        fsio_atomic_abort(a);
        return glint_err_set(err, GLINT_EIO, "%s: fdopen: %s", path, strerror(e));
    }
    return 0;
}

int fsio_atomic_commit(fsio_atomic *a, glint_err *err)
{
    int rc;
    const char *what = "write";

    if (fflush(a->fp) != 0 || ferror(a->fp))
        goto fail;
    what = "fsync";
    if (!cur_group && fsync(fileno(a->fp)) != 0)
        goto fail;
    what = "close";
    rc = fclose(a->fp);
    a->fp = NULL;
    if (rc != 0)
        goto fail;
    what = "rename";
    if (rename(a->tmp, a->path) != 0)
        goto fail;
    if (cur_group)
        group_add(cur_group, a->path);
    else
        sync_dir(a->path);
    free(a->tmp);
    a->tmp = NULL; /* nothing to unlink */
    fsio_atomic_abort(a);
    return 0;
fail:
    {
        int e = errno;
        glint_err_set(err, GLINT_EIO, "%s: %s failed: %s", a->path, what, strerror(e));
        rc = fsio_err_kind(err, e);
    }
    fsio_atomic_abort(a);
    return rc;
}

int fsio_write_atomic(const char *path, const void *data, size_t len, glint_err *err)
{
    fsio_atomic a;
    int rc = fsio_atomic_open(&a, path, err);
    if (rc)
        return rc;
    if (len && fwrite(data, 1, len, a.fp) != len) {
        int e = errno;
        glint_err_set(err, GLINT_EIO, "%s: write failed: %s", path, strerror(e));
        rc = fsio_err_kind(err, e);
        fsio_atomic_abort(&a);
        return rc;
    }
    return fsio_atomic_commit(&a, err);
}

int fsio_write_rebuildable(const char *path, const void *data, size_t len, glint_err *err)
{
    /* a group that is never ended: commit renames without syncing */
    fsio_group *saved = cur_group, g;
    int rc;
    memset(&g, 0, sizeof g);
    cur_group = &g;
    rc = fsio_write_atomic(path, data, len, err);
    cur_group = saved;
    for (int i = 0; i < g.n; i++)
        free(g.paths[i]);
    free(g.paths);
    return rc;
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
    char buf[4096], *slash;
    size_t n = strlen(path);

    if (n == 0 || n >= sizeof buf)
        return glint_err_set(err, GLINT_EINVAL, "bad directory path '%s'", path);
    memcpy(buf, path, n + 1);
    /* up from the path itself to the first level that is there or made
     * (one call when the parent is there, as for a new material), each
     * level cut off at its last '/'... */
    while (mkdir(buf, 0755) != 0 && errno != EEXIST) {
        int e = errno;
        if (e != ENOENT || !(slash = strrchr(buf, '/')) || slash == buf) {
            glint_err_set(err, GLINT_EIO, "cannot create directory %s: %s", buf, strerror(e));
            return fsio_err_kind(err, e);
        }
        *slash = '\0';
    }
    /* ...then down again, each cut '/' put back in turn */
    for (size_t i = strlen(buf); i < n; i = strlen(buf)) {
        buf[i] = '/';
        if (mkdir(buf, 0755) != 0 && errno != EEXIST) {
            int e = errno;
            glint_err_set(err, GLINT_EIO, "cannot create directory %s: %s", buf, strerror(e));
            return fsio_err_kind(err, e);
        }
    }
    return 0;
}
