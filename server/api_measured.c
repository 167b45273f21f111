/* api_measured.c: measured materials the daemon offers as truths to paint
 * from (proto/openapi.yaml, "measured materials").
 *
 *   GET /api/v1/measured     the MERL tables of --measured-dir
 *
 * A table is the spec "merl:<file>" of a base render's brdf parameter
 * (GET /api/v1/scenes/{id}/views/{k}/base.png?brdf=merl:gold.binary): the
 * studio's finishes paint every view with it.  The resolver registered here
 * (merl.h) is the only way such a spec reaches a file: <file> of
 * [A-Za-z0-9._-] not starting with '.', ending in ".binary", a regular file
 * of the MERL size whose real path lies inside the directory (no traversal,
 * no symbolic link out of it).  Without --measured-dir there are none.
 * Thread-safety: the directory is set once before threads start. */
#include <dirent.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "api_common.h"
#include "app.h"
#include "merl.h"

static char dir_[PATH_MAX]; /* real path, "" when none */

/* The file of NAME (*.binary of the MERL size) inside the directory (OUT:
 * real path), or -1. */
static int table_file(const char *name, char *real, size_t len)
{
    size_t n = strlen(name);
    long long size = 0;
    if (n < 8 || strcmp(name + n - 7, ".binary") ||
        api_dir_file(dir_, name, real, len, &size) || size != (long long)MERL_FILE_BYTES)
        return -1;
    return 0;
}

static int resolve(const char *name, char *path, size_t len, glint_err *err)
{
    if (table_file(name, path, len) == 0)
        return 0;
    return glint_err_set(err, GLINT_ENOTFOUND,
                         "no measured material '%.100s'%s", name,
                         dir_[0] ? ": a file of GET /api/v1/measured"
                                 : " (glintd offers none without --measured-dir)");
}

int api_measured_init(const char *dir, glint_err *err)
{
    dir_[0] = '\0';
    if (dir && dir[0] && !realpath(dir, dir_)) {
        dir_[0] = '\0';
        return glint_err_set(err, GLINT_ENOTFOUND, "--measured-dir %s: no such directory", dir);
    }
    merl_set_resolver(resolve);
    return 0;
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static http_resp measured_get(http_req *req)
{
    json_t *list = json_array();
    (void)req;
    if (dir_[0]) {
        DIR *d = opendir(dir_);
        struct dirent *de;
        char *found[512], real[PATH_MAX];
        int n = 0;
        while (d && (de = readdir(d)) && n < 512)
            if (table_file(de->d_name, real, sizeof real) == 0 && (found[n] = strdup(de->d_name)))
                n++;
        if (d)
            closedir(d);
        qsort(found, (size_t)n, sizeof *found, cmp_str);
        for (int i = 0; i < n; i++) {
            char spec[80], label[64];
            snprintf(spec, sizeof spec, "merl:%s", found[i]);
            snprintf(label, sizeof label, "%.*s", (int)(strlen(found[i]) - 7), found[i]);
            json_array_append_new(list, json_pack("{s:s, s:s, s:s}", "spec", spec, "name", label,
                                                  "layout", "MERL 90x90x180"));
            free(found[i]);
        }
    }
    return http_json(200, json_pack("{s:o}", "materials", list));
}

const http_route api_measured_routes[] = {
    {"GET", "/api/v1/measured", measured_get},
};
const int api_measured_nroutes = sizeof api_measured_routes / sizeof api_measured_routes[0];
