/* gltf_bake.c: per-texel glTF metallic-roughness parameters of a material
 * that varies over the surface, and their PNG textures (gltf.h).
 *
 * Each texel is fitted like the average (gltf.c), with the material
 * evaluated at the texel's centre, over the directions painted there: the
 * samples whose texture coordinates fall in the texel or, until they
 * number GLTF_BAKE_MIN_PAIRS, in the square of texels around it grown one
 * ring at a time (up to res / 8 rings; at most GLTF_BAKE_PAIRS of them,
 * evenly strided).  A texel no sample comes near (a part of the surface no
 * view painted, or samples without texture coordinates) is fitted over
 * GLTF_BAKE_PAIRS of all the painted directions, and counted.  Why local:
 * a material of maps holds at a texel what the views painted there; at
 * directions painted only elsewhere it extrapolates a blend of its
 * products, which no GGX lobe need follow.
 *
 * The search: the best of the average's (metallic, roughness) and a
 * coarse grid (metallic by 1/4, roughness by 1/10), then a pattern search
 * over the 8 neighbours (metallic and roughness trade off along a ridge,
 * which steps along one axis at a time stall on), halving its steps down to
 * metallic 1/256 and one of GLTF_BAKE_R_LEVELS roughness levels (about the
 * 8-bit texture's own steps); the specular terms of a level are computed
 * once per texel, when first tried.  Against a brute-force grid (metallic
 * by 1/100, every level) of the same objective (with the pull below) on
 * 12 x 12 texels of the maps material of BENCHMARKS.md: within 1% of its
 * minimum at 137 of 144 texels, 25% above it at worst (the error is not
 * smooth at small steps: the best base colour jumps between the quartic's
 * minima).
 *
 * The pull: a texel's directions may not tell metallic and roughness
 * apart (a patch seen by few views), and a fit of them alone then wanders
 * along the ridge: an hf3 plastic, the same everywhere, baked at 6 x 6
 * came out up to 0.46 in roughness and 0.27 in metallic from its average
 * at under 3% relative RMS.  So the search minimizes the squared error
 * plus GLTF_BAKE_PULL x (sum of y^2) x ((metallic - the average's)^2 +
 * (roughness - the average's)^2): a texel leaves the average only for a
 * gain of that order in squared relative error (1e-3: a move of 0.3 must
 * gain about 1% of relative RMS).  The same plastic then bakes within
 * 0.008 (base colour), 0.016 (metallic) and 0.046 (roughness) of its
 * average; the stripes of the tests move as before (their renders agree
 * to 3e-4).  The relative RMS reported is the error's alone.
 *
 * Texels are independent:
 * the rows of the texture are par_run tasks, each writing its own texels
 * only, so the result does not depend on the thread count. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gltf.h"
#include "internal/gltf_int.h"
#include "par.h"

typedef struct bake_ctx {
    const material *m;
    const samples *s;
    const gltf_pairs *G;       /* strided over every sample: the far texels' pairs */
    int *order;                /* sample indices sorted by texel (NULL: no uv) */
    int *start;                /* res^2 + 1: texel t's samples are order[start[t]..start[t+1]) */
    long *sat;                 /* (res + 1)^2 summed-area table of the counts */
    double m0;                 /* the average's metallic */
    int j0;                    /* the average's roughness level */
    int res;
    gltf_bake *out;
    long *nonfinite;           /* per row */
    int *far;                  /* per row: texels fitted over all the directions */
    int *failed;               /* per row: out of memory */
} bake_ctx;

/* one row task's workspace */
typedef struct bake_ws {
    gltf_pairs P;
    double *S, *s;             /* GLTF_BAKE_R_LEVELS x GLTF_BAKE_PAIRS, filled lazily */
    unsigned char *have;       /* GLTF_BAKE_R_LEVELS */
    double pull, m0, r0;       /* the texel's pull towards the average's (m0, r0) */
} bake_ws;

static double r_of(int j)
{
    return (j + 1.0) / GLTF_BAKE_R_LEVELS;
}

/* the error of (metallic m, roughness level j) over w's pairs (OUT: base),
 * plus the pull towards the average (bake_ctx) */
static double err_mj(bake_ws *w, double m, int j, double base[3])
{
    gltf_pairs *P = &w->P;
    double *S = w->S + (size_t)j * GLTF_BAKE_PAIRS, *s = w->s + (size_t)j * GLTF_BAKE_PAIRS;
    if (!w->have[j]) {
        double r = r_of(j);
        for (int i = 0; i < P->n; i++)
            gltf_spec_terms(r * r, P->nn[i], P->wi[i], P->wo[i], P->ci[i], P->co[i], &S[i],
                            &s[i]);
        w->have[j] = 1;
    }
    return gltf_pairs_error(P, S, s, m, base) +
           w->pull * ((m - w->m0) * (m - w->m0) + (r_of(j) - w->r0) * (r_of(j) - w->r0));
}

/* samples in texels [r0, r1) x [c0, c1) */
static long window_count(const bake_ctx *x, int r0, int r1, int c0, int c1)
{
    int n = x->res + 1;
    return x->sat[(size_t)r1 * n + c1] - x->sat[(size_t)r0 * n + c1] -
           x->sat[(size_t)r1 * n + c0] + x->sat[(size_t)r0 * n + c0];
}

/* the pairs of a texel no sample comes near: G's (1) */
static int far_pairs(const bake_ctx *x, gltf_pairs *P)
{
    memcpy(P->nn, x->G->nn, (size_t)x->G->n * sizeof *P->nn);
    memcpy(P->wi, x->G->wi, (size_t)x->G->n * sizeof *P->wi);
    memcpy(P->wo, x->G->wo, (size_t)x->G->n * sizeof *P->wo);
    memcpy(P->ci, x->G->ci, (size_t)x->G->n * sizeof *P->ci);
    memcpy(P->co, x->G->co, (size_t)x->G->n * sizeof *P->co);
    P->n = x->G->n;
    return 1;
}

/* w's pairs for texel (row, col): the painted directions around it, else
 * G's.  0, or 1 for a far texel. */
static int texel_pairs(const bake_ctx *x, bake_ws *w, int row, int col)
{
    gltf_pairs *P = &w->P;
    int res = x->res, hmax = res / 8 > 1 ? res / 8 : 1, r0 = row, r1 = row + 1, c0 = col,
        c1 = col + 1, k = 0;
    long cnt = 0, j = 0, q = 0, next = 0;
    if (x->order) {
        for (int h = 0; h <= hmax; h++) {
            r0 = row - h > 0 ? row - h : 0, r1 = row + h + 1 < res ? row + h + 1 : res;
            c0 = col - h > 0 ? col - h : 0, c1 = col + h + 1 < res ? col + h + 1 : res;
            if ((cnt = window_count(x, r0, r1, c0, c1)) >= GLTF_BAKE_MIN_PAIRS)
                break;
        }
    }
    if (cnt < GLTF_BAKE_MIN_PAIRS)
        return far_pairs(x, P);
    /* every (cnt / GLTF_BAKE_PAIRS)-th of the window's samples, row of texels by row */
    for (int r = r0; r < r1; r++)
        for (int i = x->start[(size_t)r * res + c0]; i < x->start[(size_t)r * res + c1]; i++, j++) {
            int si = x->order[i];
            if (j != next)
                continue;
            q++;
            next = cnt > GLTF_BAKE_PAIRS ? (long)((double)q * cnt / GLTF_BAKE_PAIRS) : q;
            for (int e = 0; e < 3; e++) {
                P->nn[k][e] = x->s->nrm[3 * (size_t)si + e];
                P->wi[k][e] = x->s->wi[3 * (size_t)si + e];
                P->wo[k][e] = x->s->wo[3 * (size_t)si + e];
            }
            P->ci[k] = P->nn[k][0] * P->wi[k][0] + P->nn[k][1] * P->wi[k][1] +
                       P->nn[k][2] * P->wi[k][2];
            P->co[k] = P->nn[k][0] * P->wo[k][0] + P->nn[k][1] * P->wo[k][1] +
                       P->nn[k][2] * P->wo[k][2];
            if (P->ci[k] > 0.0 && P->co[k] > 0.0)
                k++;
            if (k == GLTF_BAKE_PAIRS)
                goto full;
        }
full:
    P->n = k;
    return k ? 0 : far_pairs(x, P); /* none above the horizon (SAMPLES_SEEN): the far ones */
}

static void bake_texel(const bake_ctx *x, bake_ws *w, int row, int col)
{
    gltf_pairs *P = &w->P;
    double uv[2] = {(col + 0.5) / x->res, 1.0 - (row + 0.5) / x->res}; /* glTF v is 1 - glint's */
    double den = 0.0, best, bm = x->m0, dm = 0.125, base[3];
    int bj = x->j0, dj = GLTF_BAKE_R_LEVELS / 20, steps = 0;
    size_t t = (size_t)row * x->res + col;

    x->far[row] += texel_pairs(x, w, row, col);
    memset(w->have, 0, GLTF_BAKE_R_LEVELS);
    for (int i = 0; i < P->n; i++) {
        material_eval_at(x->m, uv, P->nn[i], P->wi[i], P->wo[i], P->y[i]);
        if (!isfinite(P->y[i][0] + P->y[i][1] + P->y[i][2])) {
            P->y[i][0] = P->y[i][1] = P->y[i][2] = 0.0; /* counted and reported */
            x->nonfinite[row]++;
        }
        den += P->y[i][0] * P->y[i][0] + P->y[i][1] * P->y[i][1] + P->y[i][2] * P->y[i][2];
    }
    w->m0 = x->m0;
    w->r0 = r_of(x->j0);
    w->pull = GLTF_BAKE_PULL * den;
    best = err_mj(w, bm, bj, base);
    /* a texel may be far from the average, and metallic and roughness trade off along a
     * ridge: a coarse grid (metallic by 1/4, roughness by 1/10) first */
    for (int a = 0; a <= 4; a++)
        for (int b = 1; b <= 10; b++) {
            int j = b * GLTF_BAKE_R_LEVELS / 10 - 1;
            double e = err_mj(w, a / 4.0, j, base);
            if (e < best)
                best = e, bm = a / 4.0, bj = j;
        }
    /* then a pattern search over the 8 neighbours, steps halved where none gains (every
     * move lowers the error on a finite lattice, so it ends; the cap only bounds it) */
    while ((dm >= 1.0 / 256.0 || dj >= 1) && steps++ < 1000) {
        double m1 = bm, e;
        int j1 = bj;
        for (int a = -1; a <= 1; a++)
            for (int b = -1; b <= 1; b++) {
                double tm = bm + a * dm;
                int tj = bj + b * dj;
                if ((!a && !b) || tm < 0.0 || tm > 1.0 || tj < 0 || tj >= GLTF_BAKE_R_LEVELS ||
                    (a && dm < 1.0 / 256.0) || (b && dj < 1))
                    continue;
                if ((e = err_mj(w, tm, tj, base)) < best)
                    best = e, m1 = tm, j1 = tj;
            }
        if (m1 == bm && j1 == bj)
            dm *= 0.5, dj /= 2;
        bm = m1, bj = j1;
    }
    best = gltf_pairs_error(P, w->S + (size_t)bj * GLTF_BAKE_PAIRS,
                            w->s + (size_t)bj * GLTF_BAKE_PAIRS, bm, base); /* without the pull */
    for (int c = 0; c < 3; c++)
        x->out->base[3 * t + c] = (float)base[c];
    x->out->metallic[t] = (float)bm;
    x->out->roughness[t] = (float)r_of(bj);
    x->out->rel_rms[t] = (float)(den > 0.0 ? sqrt(best / den) : 0.0);
}

static void bake_row(void *ctx, int row)
{
    const bake_ctx *x = ctx;
    bake_ws w;
    memset(&w, 0, sizeof w);
    w.S = malloc((size_t)GLTF_BAKE_R_LEVELS * GLTF_BAKE_PAIRS * sizeof *w.S);
    w.s = malloc((size_t)GLTF_BAKE_R_LEVELS * GLTF_BAKE_PAIRS * sizeof *w.s);
    w.have = malloc(GLTF_BAKE_R_LEVELS);
    if (!w.S || !w.s || !w.have || gltf_pairs_alloc(&w.P, GLTF_BAKE_PAIRS, NULL))
        x->failed[row] = 1;
    else
        for (int col = 0; col < x->res; col++)
            bake_texel(x, &w, row, col);
    gltf_pairs_free(&w.P);
    free(w.have);
    free(w.s);
    free(w.S);
}

static int cmp_float(const void *a, const void *b)
{
    float u = *(const float *)a, v = *(const float *)b;
    return (u > v) - (u < v);
}

void gltf_bake_free(gltf_bake *b)
{
    if (!b)
        return;
    free(b->base), free(b->metallic), free(b->roughness), free(b->rel_rms);
    memset(b, 0, sizeof *b);
}

/* the texel of a sample's uv (image rows: row 0 at glint's v = 1) */
static size_t texel_of(const float *uv, int res)
{
    int c = (int)floor(uv[0] * res), r = (int)floor((1.0 - uv[1]) * res);
    c = c < 0 ? 0 : c >= res ? res - 1 : c;
    r = r < 0 ? 0 : r >= res ? res - 1 : r;
    return (size_t)r * res + c;
}

/* the samples sorted by texel and the summed-area table of their counts */
static int bin_samples(bake_ctx *x, glint_err *err)
{
    const samples *s = x->s;
    int res = x->res, n = res + 1;
    size_t nt = (size_t)res * res;
    int *fill;
    if (!s || !s->has_pos || !s->uv || s->n < 1)
        return 0; /* no texture coordinates: every texel is far */
    x->order = malloc((size_t)s->n * sizeof *x->order);
    x->start = calloc(nt + 1, sizeof *x->start);
    x->sat = calloc((size_t)n * n, sizeof *x->sat);
    fill = malloc(nt * sizeof *fill);
    if (!x->order || !x->start || !x->sat || !fill) {
        free(fill);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the samples of %dx%d texels",
                             res, res);
    }
    for (int i = 0; i < s->n; i++)
        x->start[texel_of(s->uv + 2 * (size_t)i, res) + 1]++;
    for (int r = 0; r < res; r++)
        for (int c = 0; c < res; c++)
            x->sat[(size_t)(r + 1) * n + c + 1] = x->start[(size_t)r * res + c + 1] +
                                                  x->sat[(size_t)r * n + c + 1] +
                                                  x->sat[(size_t)(r + 1) * n + c] -
                                                  x->sat[(size_t)r * n + c];
    for (size_t t = 0; t < nt; t++)
        x->start[t + 1] += x->start[t];
    memcpy(fill, x->start, nt * sizeof *fill);
    for (int i = 0; i < s->n; i++)
        x->order[fill[texel_of(s->uv + 2 * (size_t)i, res)]++] = i;
    free(fill);
    return 0;
}

int gltf_bake_material(const material *m, const samples *s, const gltf_pbr *avg, int res,
                       gltf_bake *out, glint_err *err)
{
    gltf_pairs G;
    bake_ctx x;
    struct timespec t0, t1;
    float *sorted = NULL;
    size_t nt;
    int rc;

    memset(out, 0, sizeof *out);
    memset(&x, 0, sizeof x);
    if (!m || !m->method || !avg)
        return glint_err_set(err, GLINT_EINVAL, "no material to bake");
    if (res < 1 || res > GLTF_BAKE_RES_MAX)
        return glint_err_set(err, GLINT_ERANGE, "texture size %d outside 1..%d", res,
                             GLTF_BAKE_RES_MAX);
    clock_gettime(CLOCK_MONOTONIC, &t0);
    if ((rc = gltf_pairs_alloc(&G, GLTF_BAKE_PAIRS, err)))
        return rc;
    gltf_pairs_fill(&G, s, GLTF_BAKE_PAIRS, NULL, NULL);
    if (!G.n) {
        gltf_pairs_free(&G);
        return glint_err_set(err, GLINT_EINVAL, "no direction pair above the surface to bake");
    }
    nt = (size_t)res * (size_t)res;
    x.m = m;
    x.s = s;
    x.G = &G;
    x.res = res;
    x.out = out;
    x.nonfinite = calloc((size_t)res, sizeof *x.nonfinite);
    x.far = calloc((size_t)res, sizeof *x.far);
    x.failed = calloc((size_t)res, sizeof *x.failed);
    out->base = malloc(3 * nt * sizeof *out->base);
    out->metallic = malloc(nt * sizeof *out->metallic);
    out->roughness = malloc(nt * sizeof *out->roughness);
    out->rel_rms = malloc(nt * sizeof *out->rel_rms);
    sorted = malloc(nt * sizeof *sorted);
    if (!x.nonfinite || !x.far || !x.failed || !out->base || !out->metallic || !out->roughness ||
        !out->rel_rms || !sorted) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for %dx%d glTF textures", res, res);
        goto done;
    }
    if ((rc = bin_samples(&x, err)))
        goto done;
    x.m0 = avg->metallic < 0.0 ? 0.0 : avg->metallic > 1.0 ? 1.0 : avg->metallic;
    x.j0 = (int)lround(avg->roughness * GLTF_BAKE_R_LEVELS) - 1;
    x.j0 = x.j0 < 0 ? 0 : x.j0 >= GLTF_BAKE_R_LEVELS ? GLTF_BAKE_R_LEVELS - 1 : x.j0;
    out->res = res;
    par_run(res, bake_row, &x);
    for (int r = 0; r < res; r++) {
        if (x.failed[r]) {
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory fitting row %d of %dx%d texels",
                               r, res, res);
            goto done;
        }
        out->nonfinite += x.nonfinite[r];
        out->far_texels += x.far[r];
    }
    memcpy(sorted, out->rel_rms, nt * sizeof *sorted);
    qsort(sorted, nt, sizeof *sorted, cmp_float);
    out->rel_rms_median = nt % 2 ? sorted[nt / 2] : 0.5 * (sorted[nt / 2 - 1] + sorted[nt / 2]);
    out->rel_rms_max = sorted[nt - 1];
    out->pairs = GLTF_BAKE_PAIRS;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    out->seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    rc = 0;
done:
    if (rc)
        gltf_bake_free(out);
    free(sorted);
    free(x.failed);
    free(x.far);
    free(x.nonfinite);
    free(x.order);
    free(x.start);
    free(x.sat);
    gltf_pairs_free(&G);
    return rc;
}

/* ---- the textures ------------------------------------------------------------------------ */

/* sRGB's encoding of a linear value in [0, 1] (IEC 61966-2-1) */
static double srgb_encode(double v)
{
    v = v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

int gltf_bake_png(const gltf_bake *b, void **base_png, size_t *base_len, void **mr_png,
                  size_t *mr_len, glint_err *err)
{
    img bc = {0}, mr = {0};
    size_t nt;
    int rc;

    *base_png = *mr_png = NULL;
    *base_len = *mr_len = 0;
    if (!b || b->res < 1 || !b->base || !b->metallic || !b->roughness)
        return glint_err_set(err, GLINT_EINVAL, "no baked textures to encode");
    if ((rc = img_alloc(&bc, b->res, b->res, 3, err)) ||
        (rc = img_alloc(&mr, b->res, b->res, 3, err)))
        goto done;
    nt = (size_t)b->res * (size_t)b->res;
    for (size_t t = 0; t < nt; t++) {
        for (int c = 0; c < 3; c++)
            bc.px[3 * t + c] = (float)srgb_encode(b->base[3 * t + c]);
        mr.px[3 * t] = 1.0f; /* R: unused by the material; 1 reads as unoccluded */
        mr.px[3 * t + 1] = b->roughness[t];
        mr.px[3 * t + 2] = b->metallic[t];
    }
    if ((rc = img_write_mem("png", &bc, base_png, base_len, err)) ||
        (rc = img_write_mem("png", &mr, mr_png, mr_len, err))) {
        free(*base_png);
        *base_png = NULL;
        *base_len = 0;
    }
done:
    img_free(&bc);
    img_free(&mr);
    return rc;
}
