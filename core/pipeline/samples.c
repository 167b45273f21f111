/* samples.c: the sampling pattern of a scene and reading painted values. */
#include "samples.h"

#include <errno.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "cfile.h"
#include "par.h"

void samples_free(samples *s)
{
    if (!s)
        return;
    free(s->used);
    if (s->map) {
        cfile_unmap(s->map, s->map_size);
        memset(s, 0, sizeof *s);
        return;
    }
    free(s->view);
    free(s->pixel);
    free(s->nrm);
    free(s->wi);
    free(s->wo);
    free(s->cos_i);
    free(s->intensity);
    free(s->pos);
    free(s->uv);
    memset(s, 0, sizeof *s);
}

int samples_torn(const samples *s)
{
    return s && s->map && cfile_map_torn(s->map);
}

/* Grow every per-sample array of s to hold `cap` samples. */
static int samples_reserve(samples *s, size_t cap, glint_err *err)
{
    void *p;
    if (s->map)
        return glint_err_set(err, GLINT_EINVAL, "a pattern loaded from its cache file is "
                             "read-only");
#define GROW(field, per)                                                            \
    do {                                                                            \
        if (!(p = realloc(s->field, cap * (per) * sizeof *s->field)))                \
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu samples", cap); \
        s->field = p;                                                               \
    } while (0)
    GROW(view, 1);
    GROW(pixel, 1);
    GROW(nrm, 3);
    GROW(wi, 3);
    GROW(wo, 3);
    GROW(cos_i, 1);
    GROW(intensity, 1);
    GROW(pos, 3);
    GROW(uv, 2);
#undef GROW
    s->cap = cap;
    return 0;
}

/* Arrays for n samples of nviews views (the importer's). */
static int samples_alloc(samples *s, int n, int nviews, glint_err *err)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    s->nviews = nviews;
    if (!(s->used = calloc((size_t)nviews, 1)) || samples_reserve(s, (size_t)n, err)) {
        samples_free(s);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", n);
    }
    return 0;
}

static int is_sample(const gbuf *g, size_t p, int rule, double *ci)
{
    const float *n = g->nrm + 3 * p, *wi = g->wi + 3 * p, *wo = g->wo + 3 * p;
    double a, b;
    if (!g->mask[p])
        return 0;
    a = (double)n[0] * wi[0] + (double)n[1] * wi[1] + (double)n[2] * wi[2];
    b = (double)n[0] * wo[0] + (double)n[1] * wo[1] + (double)n[2] * wo[2];
    *ci = a;
    return (rule == SAMPLES_SEEN || a > 0.0) && b > 0.0;
}

long samples_count_rule(const gbuf *g, int rule)
{
    size_t np = (size_t)g->width * g->height;
    long count = 0;
    double ci;
    for (size_t p = 0; p < np; p++)
        count += is_sample(g, p, rule, &ci);
    return count;
}

long samples_count(const gbuf *g)
{
    return samples_count_rule(g, SAMPLES_LIT);
}

void samples_set_rule(samples *s, int rule)
{
    s->rule = rule == SAMPLES_SEEN ? SAMPLES_SEEN : SAMPLES_LIT;
}

int samples_begin(samples *s, int nviews, int width, int height, glint_err *err)
{
    memset(s, 0, sizeof *s);
    if (nviews < 1 || nviews > SCENE_MAX_VIEWS)
        return glint_err_set(err, GLINT_ERANGE, "view count %d outside 1..%d", nviews,
                             SCENE_MAX_VIEWS);
    if (width < 1 || height < 1)
        return glint_err_set(err, GLINT_EINVAL, "raster %dx%d is empty", width, height);
    s->nviews = nviews;
    s->width = width;
    s->height = height;
    if (!(s->used = calloc((size_t)nviews, 1)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    return 0;
}

int samples_add(samples *s, int view, const gbuf *g, int row0, double intensity, glint_err *err)
{
    size_t np = (size_t)g->width * g->height;
    int rc;

    if (view < 0 || view >= s->nviews || g->width != s->width || row0 < 0 ||
        row0 + g->height > s->height)
        return glint_err_set(err, GLINT_EINVAL,
                             "view %d: a %dx%d band at row %d does not fit the %dx%d raster",
                             view, g->width, g->height, row0, s->width, s->height);
    s->used[view] = 1;
    s->has_pos = 1;
    for (size_t p = 0; p < np; p++) {
        double ci;
        size_t k = (size_t)s->n;
        if (!is_sample(g, p, s->rule, &ci))
            continue;
        if (k == (size_t)SAMPLES_MAX)
            return glint_err_set(err, GLINT_ERANGE, "more than %d samples (the limit)",
                                 SAMPLES_MAX);
        if (k == s->cap && (rc = samples_reserve(s, s->cap ? 2 * s->cap : 4096, err)))
            return rc;
        s->view[k] = view;
        s->pixel[k] = (int)((size_t)row0 * (size_t)s->width + p);
        memcpy(s->nrm + 3 * k, g->nrm + 3 * p, 3 * sizeof(float));
        memcpy(s->wi + 3 * k, g->wi + 3 * p, 3 * sizeof(float));
        memcpy(s->wo + 3 * k, g->wo + 3 * p, 3 * sizeof(float));
        memcpy(s->pos + 3 * k, g->pos + 3 * p, 3 * sizeof(float));
        memcpy(s->uv + 2 * k, g->uv + 2 * p, 2 * sizeof(float));
        s->cos_i[k] = ci;
        s->intensity[k] = intensity;
        s->n++;
    }
    return 0;
}

int samples_append(samples *s, const samples *part, glint_err *err)
{
    size_t n = (size_t)s->n, m = (size_t)part->n;
    int rc;

    if (part->nviews != s->nviews || part->width != s->width || part->height != s->height ||
        part->rule != s->rule)
        return glint_err_set(err, GLINT_EINVAL,
                             "a part of %d views %dx%d (rule %d) does not fit a pattern of %d "
                             "views %dx%d (rule %d)", part->nviews, part->width, part->height,
                             part->rule, s->nviews, s->width, s->height, s->rule);
    if (n + m > (size_t)SAMPLES_MAX)
        return glint_err_set(err, GLINT_ERANGE, "more than %d samples (the limit)",
                             SAMPLES_MAX);
    if (n + m > s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 4096;
        if (cap < n + m)
            cap = n + m;
        if ((rc = samples_reserve(s, cap, err)))
            return rc;
    }
    for (int v = 0; v < s->nviews; v++)
        s->used[v] |= part->used[v];
    s->has_pos |= part->has_pos;
    if (!m)
        return 0;
    memcpy(s->view + n, part->view, m * sizeof *s->view);
    memcpy(s->pixel + n, part->pixel, m * sizeof *s->pixel);
    memcpy(s->nrm + 3 * n, part->nrm, 3 * m * sizeof *s->nrm);
    memcpy(s->wi + 3 * n, part->wi, 3 * m * sizeof *s->wi);
    memcpy(s->wo + 3 * n, part->wo, 3 * m * sizeof *s->wo);
    memcpy(s->cos_i + n, part->cos_i, m * sizeof *s->cos_i);
    memcpy(s->intensity + n, part->intensity, m * sizeof *s->intensity);
    memcpy(s->pos + 3 * n, part->pos, 3 * m * sizeof *s->pos);
    memcpy(s->uv + 2 * n, part->uv, 2 * m * sizeof *s->uv);
    s->n += part->n;
    return 0;
}

int samples_pattern_hash(int rule, const char scene_hash[33], const unsigned char *used,
                         int nviews, char out[33], glint_err *err)
{
    static const char lit[] = "glint-samples-v1:mask&cos_i>0&cos_o>0";
    static const char seen[] = "glint-samples-v1:mask&cos_o>0";
    const char *name = rule == SAMPLES_SEEN ? seen : lit;
    size_t name_len = rule == SAMPLES_SEEN ? sizeof seen : sizeof lit;
    XXH3_state_t *st = XXH3_createState();
    XXH128_hash_t h;
    if (!st)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory hashing samples");
    XXH3_128bits_reset(st);
    XXH3_128bits_update(st, name, name_len);
    XXH3_128bits_update(st, scene_hash ? scene_hash : "", scene_hash ? 32 : 0);
    XXH3_128bits_update(st, used, (size_t)nviews);
    h = XXH3_128bits_digest(st);
    XXH3_freeState(st);
    snprintf(out, 33, "%016llx%016llx", (unsigned long long)h.high64,
             (unsigned long long)h.low64);
    return 0;
}

/* The pattern hash: the rule, the scene hash and the views used. */
static int samples_hash(samples *s, const char scene_hash[33], glint_err *err)
{
    return samples_pattern_hash(s->rule, scene_hash, s->used, s->nviews, s->hash, err);
}

int samples_end(samples *s, const unsigned char *use, const char scene_hash[33],
                glint_err *err)
{
    int rc;
    if (use)
        for (int v = 0; v < s->nviews; v++)
            s->used[v] |= use[v] != 0;
    if (s->n < 1)
        return glint_err_set(err, GLINT_EINVAL,
                             "the chosen views have no lit, visible pixel: nothing to fit");
    if ((size_t)s->n < s->cap && (rc = samples_reserve(s, (size_t)s->n, err)))
        return rc; /* give back what growth left over */
    return samples_hash(s, scene_hash, err);
}

int samples_build(const gbuf *g, const scene_view *views, int nviews,
                  const unsigned char *use, const char scene_hash[33],
                  samples *out, glint_err *err)
{
    int rc;

    memset(out, 0, sizeof *out);
    if (nviews < 1 || nviews > SCENE_MAX_VIEWS)
        return glint_err_set(err, GLINT_ERANGE, "view count %d outside 1..%d", nviews,
                             SCENE_MAX_VIEWS);
    for (int v = 0; v < nviews; v++)
        if (g[v].width != g[0].width || g[v].height != g[0].height)
            return glint_err_set(err, GLINT_EINVAL, "view %d has a different raster size", v);
    if ((rc = samples_begin(out, nviews, g[0].width, g[0].height, err)))
        return rc;
    for (int v = 0; v < nviews && !rc; v++)
        if (!use || use[v])
            rc = samples_add(out, v, &g[v], 0, views ? view_light_scale(&views[v]) : GLINT_LIGHT_UNIT, err);
    if (!rc)
        rc = samples_end(out, use, scene_hash, err);
    if (rc)
        samples_free(out);
    return rc;
}

/* Append sample i of `all` to out (room reserved). */
static void copy_sample(samples *out, const samples *all, int i)
{
    size_t k = (size_t)out->n;
    out->view[k] = all->view[i];
    out->pixel[k] = all->pixel[i];
    memcpy(out->nrm + 3 * k, all->nrm + 3 * (size_t)i, 3 * sizeof(float));
    memcpy(out->wi + 3 * k, all->wi + 3 * (size_t)i, 3 * sizeof(float));
    memcpy(out->wo + 3 * k, all->wo + 3 * (size_t)i, 3 * sizeof(float));
    memcpy(out->pos + 3 * k, all->pos + 3 * (size_t)i, 3 * sizeof(float));
    memcpy(out->uv + 2 * k, all->uv + 2 * (size_t)i, 2 * sizeof(float));
    out->cos_i[k] = all->cos_i[i];
    out->intensity[k] = all->intensity[i];
    out->n++;
}

int samples_subset(const samples *all, const unsigned char *use, const char scene_hash[33],
                   samples *out, glint_err *err)
{
    size_t n = 0;
    int rc;

    if ((rc = samples_begin(out, all->nviews, all->width, all->height, err)))
        return rc;
    out->rule = all->rule;
    out->has_pos = all->has_pos;
    for (int i = 0; i < all->n; i++)
        n += use[all->view[i]] != 0;
    if (n && (rc = samples_reserve(out, n, err)))
        goto fail;
    for (int i = 0; i < all->n; i++) {
        if (!use[all->view[i]])
            continue;
        copy_sample(out, all, i);
    }
    for (int v = 0; v < all->nviews; v++)
        out->used[v] = use[v] && all->used[v];
    if ((rc = samples_end(out, NULL, scene_hash, err)))
        goto fail;
    return 0;
fail:
    samples_free(out);
    return rc;
}

void samples_derived_hash(const char hash[33], const char *tag, char out[33])
{
    char buf[128];
    XXH128_hash_t h;
    int len = snprintf(buf, sizeof buf, "%.32s/%s", hash, tag);
    h = XXH3_128bits(buf, (size_t)(len < (int)sizeof buf ? len : (int)sizeof buf - 1));
    snprintf(out, 33, "%016llx%016llx", (unsigned long long)h.high64,
             (unsigned long long)h.low64);
}

int samples_pick(const samples *all, const unsigned char *keep, const char *tag, samples *out,
                 glint_err *err)
{
    size_t n = 0;
    char derived[33];
    int rc;

    if ((rc = samples_begin(out, all->nviews, all->width, all->height, err)))
        return rc;
    out->rule = all->rule;
    out->has_pos = all->has_pos;
    for (int i = 0; i < all->n; i++)
        n += keep[i] != 0;
    if (n && (rc = samples_reserve(out, n, err)))
        goto fail;
    for (int i = 0; i < all->n; i++) {
        if (!keep[i])
            continue;
        copy_sample(out, all, i);
    }
    memcpy(out->used, all->used, (size_t)all->nviews);
    /* the pattern's hash, derived: samples_end hashes it with the views */
    samples_derived_hash(all->hash, tag, derived);
    if ((rc = samples_end(out, NULL, derived, err)))
        goto fail;
    return 0;
fail:
    samples_free(out);
    return rc;
}

/* The gather runs in chunks on the worker pool (par.h); each sample is
 * independent, so the result does not depend on the threads.  A chunk
 * holds whole spans, so no two chunks flag the same one. */
#define GATHER_CHUNK 16384
_Static_assert(GATHER_CHUNK % SAMPLES_SPAN == 0, "a gather chunk holds whole spans");

typedef struct gather_ctx {
    const samples *s;
    const img *paintings;
    const unsigned char *views; /* NULL: every view */
    float *rgb;
    unsigned char *changed;     /* per span, or NULL */
    int chunk, nchunks;
    int *bad; /* per chunk: 3 i + channel of its first non-finite value, or -1 */
} gather_ctx;

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define GATHER_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define GATHER_CLONES
#endif

typedef float v4f __attribute__((vector_size(16)));
typedef double v4d __attribute__((vector_size(32)));
typedef uint32_t v4u __attribute__((vector_size(16)));

/* One value: *dst = (float)(p * inv); *bad gets a nonzero bit when p is
 * inf or NaN; returns the bits that changed against *dst when cmp (else
 * 0). */
static inline uint32_t one_value(float p, double inv, float *dst, int cmp, uint32_t *bad)
{
    float x = (float)(p * inv);
    uint32_t pb, now, was, d = 0;
    memcpy(&pb, &p, sizeof pb);
    *bad |= (pb & 0x7f800000u) == 0x7f800000u; /* inf or NaN */
    if (cmp) {
        memcpy(&now, &x, sizeof now);
        memcpy(&was, dst, sizeof was);
        d = now ^ was;
    }
    *dst = x;
    return d;
}

/* The values of n consecutive floats src[] (the channels of a run of
 * consecutive pixels of a 3-channel painting, one intensity), each
 * (float)(p * inv), into dst[], four at a time: the same operations as
 * gather_values' per value, so the same bits.  *bad and the returned bits
 * as gather_values'. */
GATHER_CLONES static uint32_t run_values(const float *restrict src, float *restrict dst,
                                         size_t n, double inv, int cmp, uint32_t *bad)
{
    const v4d inv4 = {inv, inv, inv, inv};
    const v4u expo = {0x7f800000u, 0x7f800000u, 0x7f800000u, 0x7f800000u};
    v4u diff = {0, 0, 0, 0}, nf = {0, 0, 0, 0};
    size_t k = 0;
    uint32_t d = 0;
    for (; k + 4 <= n; k += 4) {
        v4f p, x, was;
        memcpy(&p, src + k, sizeof p);
        x = __builtin_convertvector(__builtin_convertvector(p, v4d) * inv4, v4f);
        nf |= (v4u)(((v4u)p & expo) == expo); /* inf or NaN: all ones */
        if (cmp) {
            memcpy(&was, dst + k, sizeof was);
            diff |= (v4u)x ^ (v4u)was;
        }
        memcpy(dst + k, &x, sizeof x);
    }
    for (int l = 0; l < 4; l++) {
        d |= diff[l];
        *bad |= nf[l];
    }
    for (; k < n; k++)
        d |= one_value(src[k], inv, &dst[k], cmp, bad);
    return d;
}

/* The values of samples a..b-1 (one view's, within one span) from that
 * view's painting im of nch channels (1: grey, 3, 4), into rgb.  Each
 * value is (float)(p * (1.0 / intensity)), as one sample at a time; the
 * reciprocal is taken once per run of equal intensities (one per view),
 * which is the same bits.  Nothing branches per value: a non-finite pixel
 * read sets *nonfinite (its place is found again apart, gather_bad), and
 * the bits that changed against what rgb held are returned (0 unless cmp).
 * Per value the loop had a branch for the check, a division per sample
 * and the compare's; perf put 15.7-17.7% of a bench_hf --warm run's
 * samples in it then (BENCHMARKS.md, thirteenth pass).  A pattern's
 * samples come in raster order, so a 3-channel painting's values are
 * mostly runs of consecutive pixels: a run of RUN_MIN samples or more with
 * one intensity is mapped as one array of floats (run_values). */
#define RUN_MIN 4
static inline uint32_t gather_values(const samples *s, const img *im, int nch, int a, int b,
                                     float *restrict rgb, int cmp, int *nonfinite)
{
    const float *restrict px0 = im->px;
    const int *restrict pixel = s->pixel;
    const double *restrict intensity = s->intensity;
    uint64_t last;
    double inv = 1.0 / intensity[a];
    uint32_t diff = 0, bad = 0;

    memcpy(&last, &intensity[a], sizeof last);
    for (int i = a, e; i < b; i = e) {
        uint64_t ib;
        memcpy(&ib, &intensity[i], sizeof ib);
        if (ib != last) {
            last = ib;
            inv = 1.0 / intensity[i];
        }
        e = i + 1;
        if (nch == 3) { /* the run of consecutive pixels of one intensity from i */
            for (; e < b && pixel[e] == pixel[e - 1] + 1; e++) {
                uint64_t eb;
                memcpy(&eb, &intensity[e], sizeof eb);
                if (eb != ib)
                    break;
            }
            if (e - i >= RUN_MIN) {
                diff |= run_values(px0 + (size_t)pixel[i] * 3, rgb + 3 * (size_t)i,
                                   (size_t)3 * (e - i), inv, cmp, &bad);
                continue;
            }
            e = i + 1;
        }
        {
            const float *px = px0 + (size_t)pixel[i] * nch;
            for (int ch = 0; ch < 3; ch++)
                diff |= one_value(px[nch == 1 ? 0 : ch], inv, &rgb[3 * (size_t)i + ch], cmp,
                                  &bad);
        }
    }
    *nonfinite = bad != 0;
    return diff;
}

/* 3 i + channel of the first non-finite value read for samples a..b-1
 * (gather_values found one). */
static int gather_bad(const samples *s, const img *im, int a, int b)
{
    for (int i = a; i < b; i++) {
        const float *px = im->px + (size_t)s->pixel[i] * im->channels;
        for (int ch = 0; ch < 3; ch++)
            if (!isfinite(im->channels == 1 ? px[0] : px[ch]))
                return 3 * i + ch;
    }
    return 3 * b; /* not reached */
}

static void gather_run(void *ctx, int c)
{
    gather_ctx *g = ctx;
    const samples *s = g->s;
    int i0 = c * g->chunk, i1 = i0 + g->chunk, cmp = g->changed != NULL;
    if (i1 > s->n)
        i1 = s->n;
    g->bad[c] = -1;
    for (int i = i0, e; i < i1; i = e) {
        /* the run of one view's samples within i's span */
        int v = s->view[i], lim = (i / SAMPLES_SPAN + 1) * SAMPLES_SPAN, nonfinite = 0;
        const img *im = &g->paintings[v];
        uint32_t diff;
        if (lim > i1)
            lim = i1;
        for (e = i + 1; e < lim && s->view[e] == v; e++)
            ;
        if (g->views && !g->views[v])
            continue;
        switch (im->channels) { /* the loop specialised for each layout */
        case 1:
            diff = gather_values(s, im, 1, i, e, g->rgb, cmp, &nonfinite);
            break;
        case 3:
            diff = gather_values(s, im, 3, i, e, g->rgb, cmp, &nonfinite);
            break;
        default:
            diff = gather_values(s, im, 4, i, e, g->rgb, cmp, &nonfinite);
            break;
        }
        if (diff)
            g->changed[i / SAMPLES_SPAN] = 1;
        if (nonfinite) {
            g->bad[c] = gather_bad(s, im, i, e);
            return;
        }
    }
}

int samples_gather(const samples *s, const img *paintings, float *rgb, glint_err *err)
{
    return samples_gather_views(s, paintings, NULL, rgb, NULL, err);
}

uint64_t samples_change_id(void)
{
    static _Atomic uint64_t last;
    return atomic_fetch_add(&last, 1) + 1;
}

int samples_gather_views(const samples *s, const img *paintings, const unsigned char *views,
                         float *rgb, unsigned char *changed, glint_err *err)
{
    for (int v = 0; v < s->nviews; v++) {
        const img *im = &paintings[v];
        if (!s->used[v] || (views && !views[v]))
            continue;
        if (!im->px || im->width != s->width || im->height != s->height)
            return glint_err_set(err, GLINT_EINVAL,
                                 "painting of view %d is %dx%d, the scene's raster is %dx%d", v,
                                 im->px ? im->width : 0, im->px ? im->height : 0, s->width,
                                 s->height);
        if (im->channels < 1 || im->channels > 4 || im->channels == 2)
            return glint_err_set(err, GLINT_EINVAL,
                                 "painting of view %d has %d channels (1, 3 or 4 expected)", v,
                                 im->channels);
    }
    {
        gather_ctx g = {s, paintings, views, rgb, changed, 0, 0, NULL};
        int rc = 0;
        g.chunk = GATHER_CHUNK;
        g.nchunks = (int)(((long)s->n + GATHER_CHUNK - 1) / GATHER_CHUNK);
        g.bad = malloc((size_t)g.nchunks * sizeof *g.bad);
        if (!g.bad)
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        if (par_worth((size_t)s->n))
            par_run(g.nchunks, gather_run, &g);
        else
            for (int c = 0; c < g.nchunks; c++)
                gather_run(&g, c);
        for (int c = 0; c < g.nchunks && !rc; c++) /* the first non-finite sample */
            if (g.bad[c] >= 0) {
                int i = g.bad[c] / 3, ch = g.bad[c] % 3;
                rc = glint_err_set(err, GLINT_ENONFINITE,
                                   "painting of view %d: pixel (%d, %d) channel %d is not finite",
                                   s->view[i], s->pixel[i] / s->width, s->pixel[i] % s->width,
                                   ch);
            }
        free(g.bad);
        return rc;
    }
}

int samples_export(const samples *s, const float *rgb, int channel, const char *path,
                   glint_err *err)
{
    FILE *fp = fopen(path, "w");
    if (!fp)
        return glint_err_set(err, GLINT_EIO, "cannot write %s: %s", path, strerror(errno));
    fprintf(fp, "# glint samples: %d samples, raster %dx%d, pattern %s\n", s->n, s->width,
            s->height, s->hash);
    fprintf(fp, "# view row col nx ny nz wix wiy wiz wox woy woz%s\n", rgb ? " value" : "");
    for (int i = 0; i < s->n; i++) {
        const float *n = s->nrm + 3 * i, *wi = s->wi + 3 * i, *wo = s->wo + 3 * i;
        fprintf(fp, "%d %d %d %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g", s->view[i],
                s->pixel[i] / s->width, s->pixel[i] % s->width, n[0], n[1], n[2], wi[0], wi[1],
                wi[2], wo[0], wo[1], wo[2]);
        if (rgb)
            fprintf(fp, " %.9g", rgb[3 * i + channel]);
        fputc('\n', fp);
    }
    if (fclose(fp) != 0)
        return glint_err_set(err, GLINT_EIO, "writing %s failed: %s", path, strerror(errno));
    return 0;
}

int samples_import(const char *path, samples *out, float **values, glint_err *err)
{
    FILE *fp;
    char line[1024];
    long n = 0, lineno = 0;
    int rc = 0, maxv = 0, maxr = 0, maxc = 0, has_value = -1;
    float *vals = NULL;

    memset(out, 0, sizeof *out);
    if (values)
        *values = NULL;
    fp = fopen(path, "r");
    if (!fp)
        return glint_err_set(err, GLINT_EIO, "cannot read %s: %s", path, strerror(errno));
    while (fgets(line, sizeof line, fp))
        if (line[0] != '#' && line[0] != '\n')
            n++;
    if (n < 1 || n > SAMPLES_MAX) {
        fclose(fp);
        return glint_err_set(err, GLINT_EFORMAT, "%s holds %ld samples (1..%d expected)", path,
                             n, SAMPLES_MAX);
    }
    rewind(fp);
    rc = samples_alloc(out, (int)n, SCENE_MAX_VIEWS, err);
    if (rc) {
        fclose(fp);
        return rc;
    }
    vals = calloc((size_t)3 * n, sizeof *vals);
    if (!vals) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory reading %s", path);
        goto fail;
    }
    for (long i = 0; i < n;) {
        double d[13];
        int v, r, c, got;
        if (!fgets(line, sizeof line, fp)) {
            rc = glint_err_set(err, GLINT_EFORMAT, "%s: file changed while reading", path);
            goto fail;
        }
        lineno++;
        if (line[0] == '#' || line[0] == '\n')
            continue;
        got = sscanf(line, "%d %d %d %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf", &v, &r, &c,
                     &d[0], &d[1], &d[2], &d[3], &d[4], &d[5], &d[6], &d[7], &d[8], &d[9]);
        if (got != 12 && got != 13) {
            rc = glint_err_set(err, GLINT_EFORMAT,
                               "%s line %ld: expected 12 or 13 numbers, got %d", path, lineno,
                               got < 0 ? 0 : got);
            goto fail;
        }
        if (has_value < 0)
            has_value = got == 13;
        if ((got == 13) != has_value) {
            rc = glint_err_set(err, GLINT_EFORMAT, "%s line %ld: column count changed", path,
                               lineno);
            goto fail;
        }
        for (int e = 0; e < got - 3; e++)
            if (!isfinite(d[e])) {
                rc = glint_err_set(err, GLINT_ENONFINITE, "%s line %ld: column %d not finite",
                                   path, lineno, e + 4);
                goto fail;
            }
        if (v < 0 || v >= SCENE_MAX_VIEWS || r < 0 || c < 0 || r >= SCENE_MAX_SIZE ||
            c >= SCENE_MAX_SIZE) {
            rc = glint_err_set(err, GLINT_ERANGE, "%s line %ld: view/row/col out of range", path,
                               lineno);
            goto fail;
        }
        {
            double nn = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            double ci = d[0] * d[3] + d[1] * d[4] + d[2] * d[5];
            double co = d[0] * d[6] + d[1] * d[7] + d[2] * d[8];
            if (fabs(nn - 1.0) > 1e-3 || !(ci > 0.0) || !(co > 0.0)) {
                rc = glint_err_set(err, GLINT_EINVAL,
                                   "%s line %ld: not a lit, visible sample (|n|^2 = %g, "
                                   "n.wi = %g, n.wo = %g)", path, lineno, nn, ci, co);
                goto fail;
            }
            out->cos_i[i] = ci;
        }
        out->view[i] = v;
        out->pixel[i] = r * SCENE_MAX_SIZE + c; /* fixed below once width is known */
        for (int e = 0; e < 3; e++) {
            out->nrm[3 * i + e] = (float)d[e];
            out->wi[3 * i + e] = (float)d[3 + e];
            out->wo[3 * i + e] = (float)d[6 + e];
        }
        out->intensity[i] = 1.0;
        out->pos[3 * i] = out->pos[3 * i + 1] = out->pos[3 * i + 2] = 0.0f;
        out->uv[2 * i] = out->uv[2 * i + 1] = 0.0f;
        if (got == 13)
            vals[3 * i] = vals[3 * i + 1] = vals[3 * i + 2] = (float)d[9];
        out->used[v] = 1;
        if (v > maxv) maxv = v;
        if (r > maxr) maxr = r;
        if (c > maxc) maxc = c;
        i++;
    }
    fclose(fp);
    fp = NULL;
    out->nviews = maxv + 1;
    out->width = maxc + 1;
    out->height = maxr + 1;
    for (int i = 0; i < out->n; i++) {
        int r = out->pixel[i] / SCENE_MAX_SIZE, c = out->pixel[i] % SCENE_MAX_SIZE;
        out->pixel[i] = r * out->width + c;
    }
    {
        XXH3_state_t *st = XXH3_createState();
        XXH128_hash_t h = {0, 0};
        if (st) {
            XXH3_128bits_reset(st);
            XXH3_128bits_update(st, out->nrm, (size_t)3 * n * sizeof(float));
            XXH3_128bits_update(st, out->wi, (size_t)3 * n * sizeof(float));
            XXH3_128bits_update(st, out->wo, (size_t)3 * n * sizeof(float));
            h = XXH3_128bits_digest(st);
            XXH3_freeState(st);
        }
        snprintf(out->hash, sizeof out->hash, "%016llx%016llx", (unsigned long long)h.high64,
                 (unsigned long long)h.low64);
    }
    if (values)
        *values = vals;
    else
        free(vals);
    return 0;
fail:
    if (fp)
        fclose(fp);
    free(vals);
    samples_free(out);
    return rc;
}
