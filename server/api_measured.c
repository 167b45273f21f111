/* api_measured.c: measured materials the daemon offers as truths to paint
 * from (proto/openapi.yaml, "measured materials").
 *
 *   GET /api/v1/measured     the MERL tables of --measured-dir, and the
 *                            published fits of its merl56_fits.json
 *
 * A table is the spec "merl:<file>" of a base render's brdf parameter
 * (GET /api/v1/scenes/{id}/views/{k}/base.png?brdf=merl:gold.binary): the
 * studio's finishes paint every view with it.  The resolver registered here
 * (merl.h) is the only way such a spec reaches a file: <file> of
 * [A-Za-z0-9._-] not starting with '.', ending in ".binary", a regular file
 * of the MERL size whose real path lies inside the directory (no traversal,
 * no symbolic link out of it).  When the directory holds
 * MEASURED_FITS_FILE (measured.h), each of its materials is also offered as
 * "sgd:<name>" and "abc:<name>", the two published analytic fits (read and
 * checked at startup: a bad file stops glintd with its error).  Without
 * --measured-dir there are none; the analytic truths serve either way.
 * Thread-safety: the directory is set once before threads start. */
#include <dirent.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "api_common.h"
#include "app.h"
#include "measured.h"
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
    char fits[PATH_MAX + 32];
    const measured_set *set;
    struct stat st;

    dir_[0] = '\0';
    measured_set_file(NULL, "glintd offers none without --measured-dir");
    if (dir && dir[0] && !realpath(dir, dir_)) {
        dir_[0] = '\0';
        return glint_err_set(err, GLINT_ENOTFOUND, "--measured-dir %s: no such directory", dir);
    }
    merl_set_resolver(resolve);
    if (!dir_[0])
        return 0;
    snprintf(fits, sizeof fits, "%s/%s", dir_, MEASURED_FITS_FILE);
    if (stat(fits, &st) != 0) {
        measured_set_file(NULL, "--measured-dir holds no " MEASURED_FITS_FILE);
        return 0;
    }
    measured_set_file(fits, NULL);
    if (measured_current(&set, err)) /* read now: a bad file is the operator's to fix */
        return glint_err_prefix(err, "--measured-dir");
    return 0;
}

/* The fits of the measured set, two entries per material (sgd, then abc). */
static void fits_list(json_t *list)
{
    const measured_set *set;
    static const char *const model[2] = {"sgd", "abc"};
    static const char *const layout[2] = {"sgd fit (Bagher et al. 2012)",
                                          "abc fit (Low et al. 2012)"};
    if (!dir_[0] || measured_current(&set, NULL))
        return;
    for (int i = 0; i < set->n; i++)
        for (int k = 0; k < 2; k++) {
            char spec[80];
            snprintf(spec, sizeof spec, "%s:%s", model[k], set->m[i].name);
            json_array_append_new(list, json_pack("{s:s, s:s, s:s}", "spec", spec, "name",
                                                  set->m[i].name, "layout", layout[k]));
        }
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
    fits_list(list);
    return http_json(200, json_pack("{s:o}", "materials", list));
}

const http_route api_measured_routes[] = {
    {"GET", "/api/v1/measured", measured_get},
};
const int api_measured_nroutes = sizeof api_measured_routes / sizeof api_measured_routes[0];
