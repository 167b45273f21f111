/* http_static.c: the studio's static files (glintd --web-dir). */
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "http.h"

/* ---- static files --------------------------------------------------------------------- */

static const char *mime_of(const char *path)
{
    const char *dot = strrchr(path, '.');
    static const struct { const char *ext, *type; } t[] = {
        {".html", "text/html; charset=utf-8"}, {".js", "text/javascript; charset=utf-8"},
        {".mjs", "text/javascript; charset=utf-8"}, {".css", "text/css; charset=utf-8"},
        {".json", "application/json"}, {".png", "image/png"}, {".svg", "image/svg+xml"},
        {".ico", "image/x-icon"}, {".yaml", "application/yaml"}, {".txt", "text/plain"}};
    if (dot)
        for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++)
            if (strcmp(dot, t[i].ext) == 0)
                return t[i].type;
    return "application/octet-stream";
}

/* Open the file at `path` (below the web root, '/'-separated) for
 * reading, walking it one component at a time with openat(O_NOFOLLOW):
 * a symbolic link anywhere below the root, "." or "..", or anything but a
 * regular file at the end is not served, so nothing outside the root can
 * be reached through the tree.  The root itself may be a link (the
 * operator names it).  Returns the descriptor (OUT: *st, its stat) or -1. */
static int static_open(const char *dir, const char *path, struct stat *st)
{
    char comp[NAME_MAX + 1];
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    const char *p = path;

    while (fd >= 0) {
        size_t n;
        int next, last;
        while (*p == '/')
            p++;
        n = strcspn(p, "/");
        last = p[n] == '\0' || p[n + strspn(p + n, "/")] == '\0';
        if (n == 0 || n > NAME_MAX || (n == 1 && p[0] == '.') ||
            (n == 2 && p[0] == '.' && p[1] == '.'))
            break;
        memcpy(comp, p, n);
        comp[n] = '\0';
        p += n;
        /* O_NONBLOCK: a FIFO at the end must not hold the thread */
        next = openat(fd, comp,
                      O_RDONLY | O_NOFOLLOW | O_CLOEXEC | (last ? O_NONBLOCK : O_DIRECTORY));
        close(fd);
        fd = next;
        if (last) {
            if (fd >= 0 && fstat(fd, st) == 0 && S_ISREG(st->st_mode))
                return fd;
            break;
        }
    }
    if (fd >= 0)
        close(fd);
    return -1;
}

/* Static files are revalidated on every load (Cache-Control: no-cache)
 * with Last-Modified / If-Modified-Since, so an unchanged module costs a
 * 304 and no body. */
http_resp http_static_serve(const char *dir, const char *path, const char *ims)
{
    char lm[64];
    struct stat st;
    struct tm tm;
    char *data;
    size_t got = 0;
    http_resp r;
    int fd;

    if (!dir || strchr(path, '\\'))
        return http_problem(404, "not-found", "no such resource: %s", path);
    if (strcmp(path, "/") == 0)
        path = "/index.html";
    fd = static_open(dir, path, &st);
    if (fd < 0 || st.st_size > (64 << 20)) {
        if (fd >= 0)
            close(fd);
        return http_problem(404, "not-found", "no such resource: %s", path);
    }
    data = malloc((size_t)st.st_size + 1);
    while (data && got < (size_t)st.st_size) {
        ssize_t n = read(fd, data + got, (size_t)st.st_size - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        got += (size_t)n;
    }
    close(fd);
    if (!data || got != (size_t)st.st_size) {
        free(data);
        return http_problem(500, NULL, "cannot read %s", path);
    }
    gmtime_r(&st.st_mtime, &tm);
    strftime(lm, sizeof lm, "%a, %d %b %Y %H:%M:%S GMT", &tm);
    if (ims && strcmp(ims, lm) == 0) {
        free(data);
        r = http_bytes(304, NULL, "", 0);
    } else {
        r = http_bytes_owned(200, mime_of(path), data, (size_t)st.st_size);
    }
    http_header(&r, MHD_HTTP_HEADER_LAST_MODIFIED, lm);
    http_header(&r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache");
    return r;
}
