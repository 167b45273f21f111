/* api_envs.c: the environments the daemon offers to environment-lit fits
 * (proto/openapi.yaml, "environments").
 *
 *   GET /api/v1/environments
 *
 * The built-in skies, and the HDR maps of the directory given by --env-dir
 * (none without it), named "data:<file>".  The resolver registered here
 * (env.h) is the only way a fit's `env` parameter reaches a file: a name
 * of [A-Za-z0-9._-] not starting with '.', a regular file whose real path
 * lies inside the directory (no traversal, no symbolic link out of it).
 * Thread-safety: the directory is set once before threads start. */
#include <dirent.h>
#include <math.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "api_common.h"
#include "app.h"
#include "env.h"
#include "render.h"

static char env_dir[PATH_MAX]; /* real path, "" when none */

static int name_ok(const char *name)
{
    size_t n = strlen(name);
    if (n == 0 || n > 60 || name[0] == '.')
        return 0;
    for (size_t i = 0; i < n; i++) {
        char c = name[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '.' || c == '_' || c == '-'))
            return 0;
    }
    return 1;
}

/* The file of data:NAME inside the directory (OUT: real path), or -1. */
static int data_file(const char *name, char *real, size_t len)
{
    char path[PATH_MAX + 64], r[PATH_MAX];
    struct stat st;
    size_t dl = strlen(env_dir);
    if (!env_dir[0] || !name_ok(name))
        return -1;
    snprintf(path, sizeof path, "%s/%s", env_dir, name);
    if (!realpath(path, r) || strncmp(r, env_dir, dl) || r[dl] != '/' || stat(r, &st) ||
        !S_ISREG(st.st_mode))
        return -1;
    snprintf(real, len, "%s", r);
    return 0;
}

static int resolve(const char *spec, char *path, size_t len, glint_err *err)
{
    if (!strncmp(spec, "data:", 5) && data_file(spec + 5, path, len) == 0)
        return 0;
    return glint_err_set(err, GLINT_ENOTFOUND,
                         "no environment '%s': a built-in (%s)%s", spec, env_builtin_names(),
                         env_dir[0] ? " or data:NAME of GET /api/v1/environments" : "");
}

int api_envs_init(const char *dir, glint_err *err)
{
    env_dir[0] = '\0';
    if (dir && dir[0] && !realpath(dir, env_dir)) {
        env_dir[0] = '\0';
        return glint_err_set(err, GLINT_ENOTFOUND, "--env-dir %s: no such directory", dir);
    }
    env_set_resolver(resolve);
    return 0;
}

static int query_num(const char *s, double lo, double hi, double *out)
{
    char *end;
    double v;
    if (!s)
        return 0;
    v = strtod(s, &end);
    if (end == s || *end || !isfinite(v) || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int api_env_query(http_req *req, render_env *out, int *has, glint_err *e)
{
    const char *spec = http_query(req, "env"), *rot = http_query(req, "env_rotation"),
               *inten = http_query(req, "env_intensity"), *lights = http_query(req, "lights"),
               *shadows = http_query(req, "shadows"), *bg = http_query(req, "background");
    double x = 0.0;
    render_env_init(out);
    *has = spec != NULL;
    if (!spec) {
        if (rot || inten || lights || shadows || bg)
            return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                              "env_rotation, env_intensity, lights, shadows and background "
                              "need env=SPEC");
        return 0;
    }
    if (env_spec_check(spec, e))
        return glint_err_kind(e, "invalid-parameter");
    snprintf(out->spec, sizeof out->spec, "%s", spec);
    if (query_num(rot, -360.0, 360.0, &out->rotation_deg))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "env_rotation must be degrees in [-360, 360]");
    if (query_num(inten, 1e-12, 1e6, &out->intensity))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "env_intensity must be in (0, 1e6]");
    if (lights && (query_num(lights, 1, RENDER_ENV_MAX_LIGHTS, &x) || x != floor(x)))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "lights must be an integer in 1..%d", RENDER_ENV_MAX_LIGHTS);
    if (lights)
        out->lights = (int)x;
    if (shadows && strcmp(shadows, "0") && strcmp(shadows, "1"))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter", "shadows must be 0 or 1");
    if (shadows)
        out->shadows = shadows[0] == '1';
    if (bg && strcmp(bg, "0") && strcmp(bg, "1"))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter", "background must be 0 or 1");
    if (bg)
        out->background = bg[0] == '1';
    return 0;
}

void api_env_header(http_resp *r, const render_env_info *info)
{
    char h[200];
    snprintf(h, sizeof h, "env=%s; lights=%d; cached=%d; convex=%d; rays=%ld; prepare_ms=%.1f; "
             "shade_ms=%.1f; draw_ms=%.1f",
             info->env, info->lights, info->cached, info->convex, info->rays,
             1e3 * info->prepare_s, 1e3 * info->shade_s, 1e3 * info->draw_s);
    http_header(r, "X-Glint-Env", h);
}

static int cmp_str(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static http_resp envs_get(http_req *req)
{
    json_t *list = json_array();
    char names[] = "studio,sky,sunset,overcast,white", *save = NULL;
    (void)req;
    for (char *t = strtok_r(names, ",", &save); t; t = strtok_r(NULL, ",", &save))
        json_array_append_new(list, json_pack("{s:s, s:s, s:s}", "spec", t, "name", t,
                                              "kind", "builtin"));
    if (env_dir[0]) {
        DIR *d = opendir(env_dir);
        struct dirent *de;
        char *found[512], real[PATH_MAX];
        int n = 0;
        while (d && (de = readdir(d)) && n < 512) {
            const char *x = strrchr(de->d_name, '.');
            if (x && (!strcmp(x, ".exr") || !strcmp(x, ".hdr")) &&
                data_file(de->d_name, real, sizeof real) == 0)
                found[n++] = strdup(de->d_name);
        }
        if (d)
            closedir(d);
        qsort(found, (size_t)n, sizeof *found, cmp_str);
        for (int i = 0; i < n; i++) {
            char spec[80];
            if (!found[i])
                continue;
            snprintf(spec, sizeof spec, "data:%s", found[i]);
            json_array_append_new(list, json_pack("{s:s, s:s, s:s}", "spec", spec, "name",
                                                  found[i], "kind", "data"));
            free(found[i]);
        }
    }
    return http_json(200, json_pack("{s:o}", "environments", list));
}

const http_route api_envs_routes[] = {
    {"GET", "/api/v1/environments", envs_get},
};
const int api_envs_nroutes = sizeof api_envs_routes / sizeof api_envs_routes[0];
