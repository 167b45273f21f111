/* pattern_disk.c: a sampling pattern in a cache file (format and checks in
 * pattern.h).
 *
 * Loading maps the file (cfile_map_*: its pages are the page cache's,
 * nothing is copied or zeroed; 31.5 MB of a 12-view pattern map and check
 * in about 3 ms where reading them into fresh memory took 20), checks the
 * header against the scene and the views asked for, points the arrays at
 * the file (each starts at a multiple of 64 bytes), and checks the values
 * in a few passes over the arrays (vectorizable reductions: a flag OR-ed
 * over each array), so a pattern loads at close to the speed of memory. */
#include "pattern.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cache.h"
#include "cfile.h"

#define MAGIC "GLPATT01"
#define KIND 2 /* 1: arrays unaligned, read into memory */
#define ALIGN 64
/* bytes per sample: view, pixel; nrm, wi, wo, pos, uv; cos_i, intensity */
#define PER_SAMPLE (2 * 4 + 14 * 4 + 2 * 8)
#define NARRAYS 9
#define HEADER_MAX (8 + 4 + 7 * 4 + CACHE_KEY_MAX + 32 + SCENE_MAX_VIEWS + ALIGN)
#define MAX_FILE (HEADER_MAX + (size_t)SAMPLES_MAX * PER_SAMPLE + NARRAYS * ALIGN + 8)
/* |n|^2 and |wo|^2 of a stored unit vector (floats of a vector normalized
 * in double); cos_i (n.wi in double) against n.wi recomputed in float, and
 * n.wo so recomputed against 0 */
#define UNIT_TOL 1e-4f
#define COS_TOL 1e-5f

#if defined(__GNUC__)
#define NOINLINE __attribute__((noinline))
#else
#define NOINLINE
#endif
/* the checks over every sample, in 8 lanes where the machine has them
 * (no FMA in either clone: the same comparisons) */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CHECK_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CHECK_CLONES
#endif

void pattern_file_name(const char *key, char *name, size_t len)
{
    cfile_name(key, ".pattern", name, len);
}

/* The arrays in the file's order, and their bytes per sample. */
static const size_t array_bytes[NARRAYS] = {sizeof(int), sizeof(int), 3 * sizeof(float),
                                            3 * sizeof(float), 3 * sizeof(float), sizeof(double),
                                            sizeof(double), 3 * sizeof(float), 2 * sizeof(float)};

int pattern_save(const samples *s, const char *dir, const char *key, glint_err *err)
{
    size_t n = (size_t)s->n, klen = strlen(key);
    uint32_t u[7] = {(uint32_t)s->n, (uint32_t)s->nviews, (uint32_t)s->width,
                     (uint32_t)s->height, (uint32_t)s->rule, (uint32_t)s->has_pos,
                     (uint32_t)klen};
    char name[64];
    cfile_w b;

    if (s->n < 1 || klen >= CACHE_KEY_MAX)
        return glint_err_set(err, GLINT_EINVAL, "pattern_save: %d samples, key of %zu bytes",
                             s->n, klen);
    cfile_begin(&b, MAGIC, KIND);
    cfile_reserve(&b, b.len + sizeof u + klen + 32 + (size_t)s->nviews + n * PER_SAMPLE +
                          NARRAYS * ALIGN + 8);
    cfile_put(&b, u, sizeof u);
    cfile_put(&b, key, klen);
    cfile_put(&b, s->hash, 32);
    cfile_put(&b, s->used, (size_t)s->nviews);
    {
        const void *a[NARRAYS] = {s->view, s->pixel, s->nrm, s->wi, s->wo,
                                  s->cos_i, s->intensity, s->pos, s->uv};
        for (int i = 0; i < NARRAYS; i++) {
            cfile_pad(&b, ALIGN);
            cfile_put(&b, a[i], n * array_bytes[i]);
        }
    }
    pattern_file_name(key, name, sizeof name);
    return cfile_write(&b, dir, name, err);
}

/* 1 if any of x[0..n) is NaN or infinite. */
CHECK_CLONES static int any_nonfinite(const float *x, size_t n)
{
    int bad = 0;
#pragma omp simd reduction(| : bad)
    for (size_t i = 0; i < n; i++)
        bad |= !(fabsf(x[i]) <= FLT_MAX);
    return bad;
}

/* Samples out of order or outside the raster: views non-decreasing and in
 * 0..nviews-1, pixels in 0..npix-1 and increasing within a view. */
CHECK_CLONES static int any_misplaced(const int *view, const int *pixel, size_t n, int nviews,
                                       int npix)
{
    int bad = (unsigned)view[0] >= (unsigned)nviews || (unsigned)pixel[0] >= (unsigned)npix;
#pragma omp simd reduction(| : bad)
    for (size_t i = 1; i < n; i++)
        bad |= ((unsigned)view[i] >= (unsigned)nviews) | ((unsigned)pixel[i] >= (unsigned)npix) |
               (view[i] < view[i - 1]) | ((view[i] == view[i - 1]) & (pixel[i] <= pixel[i - 1]));
    return bad;
}

/* Geometry that no rasterized sample has: a normal or view direction not of
 * unit length, a light direction neither unit nor zero, n.wo < 0 (beyond
 * rounding: a grazing sample's n.wo > 0 in double may round to 0 here),
 * cos_i not n.wi, or (lit rule) not > 0.  NaN and infinities in nrm, wi, wo
 * or cos_i fail it too.  In single precision (the tolerances allow for it)
 * and kept out of line: GCC vectorizes it then (not once inlined). */
CHECK_CLONES static NOINLINE int any_bad_geometry(const samples *s, int lit)
{
    const float *nr = s->nrm, *wi = s->wi, *wo = s->wo;
    const double *ci = s->cos_i;
    size_t n = (size_t)s->n;
    int bad = 0;
#pragma omp simd reduction(| : bad)
    for (size_t i = 0; i < n; i++) {
        float n0 = nr[3 * i], n1 = nr[3 * i + 1], n2 = nr[3 * i + 2];
        float i0 = wi[3 * i], i1 = wi[3 * i + 1], i2 = wi[3 * i + 2];
        float o0 = wo[3 * i], o1 = wo[3 * i + 1], o2 = wo[3 * i + 2];
        float nn = n0 * n0 + n1 * n1 + n2 * n2, ii = i0 * i0 + i1 * i1 + i2 * i2;
        float oo = o0 * o0 + o1 * o1 + o2 * o2;
        float a = n0 * i0 + n1 * i1 + n2 * i2, b = n0 * o0 + n1 * o1 + n2 * o2;
        float c = (float)ci[i];
        int ok = (fabsf(nn - 1.0f) <= UNIT_TOL) & (fabsf(oo - 1.0f) <= UNIT_TOL) &
                 ((fabsf(ii - 1.0f) <= UNIT_TOL) | (ii == 0.0f)) & (b > -COS_TOL) &
                 (fabsf(c - a) <= COS_TOL) & ((ci[i] > 0.0) | !lit);
        bad |= !ok;
    }
    return bad;
}

/* A sample of a view not used, or without its view's light intensity. */
static int any_foreign(const samples *s, const scene *sc)
{
    double li[SCENE_MAX_VIEWS];
    int bad = 0;
    for (int v = 0; v < sc->nviews; v++)
        li[v] = s->used[v] ? view_light_scale(&sc->views[v]) : NAN;
    for (size_t i = 0; i < (size_t)s->n; i++)
        bad |= !(s->intensity[i] == li[s->view[i]]);
    return bad;
}

int pattern_load(const char *dir, const char *key, const scene *sc, const char scene_hash[33],
                 const unsigned char *use, int rule, samples *out, glint_err *err)
{
    char name[64], hash[33];
    size_t n, klen = strlen(key);
    uint32_t u[7];
    const void *p, *arr[NARRAYS];
    cfile_m m;
    const char *why = NULL;
    int rc;

    memset(out, 0, sizeof *out);
    pattern_file_name(key, name, sizeof name);
    if ((rc = cfile_map_open(dir, name, MAGIC, KIND, MAX_FILE, &m, err)))
        return rc;
    rc = GLINT_EFORMAT;
    if (!(p = cfile_map_take(&m, sizeof u))) {
        why = "has the wrong size";
        goto done;
    }
    memcpy(u, p, sizeof u);
    if (u[6] != klen || !(p = cfile_map_take(&m, klen)) || memcmp(p, key, klen) != 0) {
        why = "holds another key's pattern";
        goto done;
    }
    if (u[0] < 1 || u[0] > SAMPLES_MAX || (int)u[1] != sc->nviews || (int)u[2] != sc->width ||
        (int)u[3] != sc->height || (int)u[4] != rule || u[5] != 1) {
        why = "counts, raster size or rule are not the scene's";
        goto done;
    }
    n = u[0];
    if ((rc = samples_begin(out, sc->nviews, sc->width, sc->height, err)))
        goto done;
    rc = GLINT_EFORMAT;
    out->n = (int)n;
    out->rule = rule;
    out->has_pos = 1;
    if (!(p = cfile_map_take(&m, 32))) {
        why = "has the wrong size";
        goto done;
    }
    memcpy(out->hash, p, 32);
    out->hash[32] = '\0';
    if (!(p = cfile_map_take(&m, (size_t)sc->nviews))) {
        why = "has the wrong size";
        goto done;
    }
    memcpy(out->used, p, (size_t)sc->nviews);
    for (int v = 0; v < sc->nviews; v++)
        if (out->used[v] != (use[v] != 0))
            why = "was made from other views";
    if (why)
        goto done;
    if ((rc = samples_pattern_hash(rule, scene_hash, out->used, sc->nviews, hash, err)))
        goto done;
    rc = GLINT_EFORMAT;
    if (strcmp(hash, out->hash) != 0) {
        why = "has another pattern hash";
        goto done;
    }
    /* the arrays where they lie in the file; the checksum covered them */
    for (int i = 0; i < NARRAYS; i++)
        if (cfile_map_align(&m, ALIGN) || !(arr[i] = cfile_map_take(&m, n * array_bytes[i]))) {
            why = "has the wrong size";
            goto done;
        }
    if (m.at != m.len) {
        why = "has the wrong size";
        goto done;
    }
    {
        void **field[NARRAYS] = {(void **)&out->view, (void **)&out->pixel, (void **)&out->nrm,
                                 (void **)&out->wi,   (void **)&out->wo,    (void **)&out->cos_i,
                                 (void **)&out->intensity, (void **)&out->pos,
                                 (void **)&out->uv};
        if (cfile_map_keep(&m, &out->map, &out->map_size) == 0) {
            for (int i = 0; i < NARRAYS; i++)
                *field[i] = (void *)arr[i];
        } else { /* the process keeps too many mappings: copies of its own */
            for (int i = 0; i < NARRAYS; i++) {
                if (!(*field[i] = malloc(n * array_bytes[i]))) {
                    rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu samples", n);
                    goto done;
                }
                memcpy(*field[i], arr[i], n * array_bytes[i]);
            }
        }
    }
    out->cap = n;
    if (any_misplaced(out->view, out->pixel, n, sc->nviews, sc->width * sc->height))
        why = "has samples out of order or outside the raster";
    else if (any_foreign(out, sc))
        why = "has samples of views not used or with another light intensity";
    else if (any_bad_geometry(out, rule != SAMPLES_SEEN)) /* NaN and infinities too */
        why = "has samples no rasterizer makes (directions, cosines)";
    else if (any_nonfinite(out->pos, 3 * n) || any_nonfinite(out->uv, 2 * n))
        why = "has values that are not finite";
    rc = why ? GLINT_EFORMAT : 0;
done:
    cfile_map_close(&m);
    if (why)
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: the cached pattern %s (key %s)", name, why,
                           key);
    if (rc)
        samples_free(out);
    return rc;
}
