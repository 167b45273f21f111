/* bench_env.h: what the benchmarks under environment light share: the
 * shared data's folder (../shared/data beside the source tree, or --data),
 * the resolver of "data:FILE" environments in its envmaps/, a scene lent to
 * the cache as it is, and an environment compressed into lights.  Included
 * by one benchmark program each (static definitions). */
#ifndef GLINT_BENCH_ENV_H
#define GLINT_BENCH_ENV_H

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "env.h"
#include "err.h"
#include "scene.h"
#include "test_paths.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* the shared data (bench_env_data_default, or --data) */
static char DATA[1024];

static void bench_env_data_default(void)
{
    snprintf(DATA, sizeof DATA, "%s/../shared/data", glint_test_source_dir);
}

/* "data:FILE" as DATA/envmaps/FILE (no folders in FILE). */
static int data_resolver(const char *spec, char *path, size_t len, glint_err *err)
{
    struct stat st;
    if (strncmp(spec, "data:", 5) || strchr(spec + 5, '/'))
        return glint_err_set(err, GLINT_ENOTFOUND, "unknown environment %s", spec);
    snprintf(path, len, "%s/envmaps/%s", DATA, spec + 5);
    if (stat(path, &st))
        return glint_err_set(err, GLINT_ENOTFOUND, "%s: no such file", path);
    return 0;
}

/* A prep_scene_source's lender of the scene passed as cls. */
static inline int borrowed(void *cls, const char *id, const scene **out, glint_err *err)
{
    (void)id;
    (void)err;
    *out = cls;
    return 0;
}

/* spec turned rot_deg about +z, compressed into k median-cut lights. */
static inline int lights_of(const char *spec, int k, double rot_deg, env_lights *l,
                            glint_err *e)
{
    env_map m;
    int rc = env_resolve(spec, &m, e);
    if (!rc)
        rc = env_compress(&m, ENV_CUT_MEDIAN, k, rot_deg * M_PI / 180.0, 1.0, l, e);
    env_map_free(&m);
    return rc;
}

#endif
