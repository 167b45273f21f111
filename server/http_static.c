/* http_static.c: the studio's static files (glintd --web-dir). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

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

/* Static files are revalidated on every load (Cache-Control: no-cache)
 * with Last-Modified / If-Modified-Since, so an unchanged module costs a
 * 304 and no body. */
http_resp http_static_serve(const char *dir, const char *path, const char *ims)
{
    char full[4096], lm[64];
    struct stat st;
    struct tm tm;
    FILE *f;
    char *data;
    http_resp r;

    if (!dir || strstr(path, "..") || strchr(path, '\\'))
        return http_problem(404, "not-found", "no such resource: %s", path);
    if (strcmp(path, "/") == 0)
        path = "/index.html";
    if (snprintf(full, sizeof full, "%s%s", dir, path) >= (int)sizeof full ||
        stat(full, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > (64 << 20))
        return http_problem(404, "not-found", "no such resource: %s", path);
    f = fopen(full, "rb");
    data = malloc((size_t)st.st_size + 1);
    if (!f || !data || fread(data, 1, (size_t)st.st_size, f) != (size_t)st.st_size) {
        if (f)
            fclose(f);
        free(data);
        return http_problem(500, NULL, "cannot read %s", path);
    }
    fclose(f);
    gmtime_r(&st.st_mtime, &tm);
    strftime(lm, sizeof lm, "%a, %d %b %Y %H:%M:%S GMT", &tm);
    if (ims && strcmp(ims, lm) == 0) {
        free(data);
        r = http_bytes(304, NULL, "", 0);
    } else {
        r = http_bytes_owned(200, mime_of(full), data, (size_t)st.st_size);
    }
    http_header(&r, MHD_HTTP_HEADER_LAST_MODIFIED, lm);
    http_header(&r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache");
    return r;
}
