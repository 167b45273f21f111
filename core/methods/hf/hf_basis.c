/* hf_basis.c: projections, hat interpolation, the sparse constraint rows
 * (design), the Laplacian and the gauge directions. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "internal/hf_int.h"
#include "par.h"
#include "vec3.h"

double hf_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double tangent_len(v3 v, v3 n)
{
    double l = v3_len(v3_sub(v, v3_scale(n, v3_dot(v, n))));
    return l < 0.0 ? 0.0 : (l > 1.0 ? 1.0 : l);
}

void hf_project(const double n[3], const double wi[3], const double wo[3],
                double pi[3])
{
    v3 N = v3_load(n), I = v3_load(wi), O = v3_load(wo);
    v3 H = v3_normalize(v3_add(I, O));
    pi[0] = tangent_len(I, N);
    pi[1] = tangent_len(H, N);
    pi[2] = tangent_len(O, N);
}

void hf_hat(double u, int res, int *k0, double *t)
{
    double x;
    int k;

    if (!(u > 0.0)) /* also catches NaN */
        u = 0.0;
    if (u > 1.0)
        u = 1.0;
    x = u * (double)(res - 1);
    k = (int)floor(x);
    if (k > res - 2)
        k = res - 2;
    *k0 = k;
    *t = x - (double)k;
}

/* The design's rows, chunk by chunk on the worker pool (each sample's row
 * is its own: the same bits on any number of threads). */
typedef struct design_ctx {
    const samples *s;
    hf_design *out;
    int chunk, nchunks;
} design_ctx;

/* no-trapping-math: GCC if-converts the selects of the loop below (and so
 * vectorizes it) only where no floating-point operation may trap; it
 * changes no value.  With an optimize attribute on the loop, GCC inlines
 * the helpers only when told to always. */
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define DESIGN_CLONES                                                                      \
    __attribute__((target_clones("avx2", "default"), optimize("no-trapping-math")))
#define DESIGN_INLINE static inline __attribute__((always_inline))
#else
#define DESIGN_CLONES
#define DESIGN_INLINE static inline
#endif

/* hf_project's tangent length and hf_hat, written out so that the loop
 * over samples vectorizes: the same operations in the same order (no FMA
 * in either clone), so the same bits as the two functions.  The clamps are
 * selects, the NaN test included (!(u > 0) is true for NaN). */
DESIGN_INLINE double design_tangent(double vx, double vy, double vz, double nx, double ny,
                                   double nz)
{
    double d = vx * nx + vy * ny + vz * nz;
    double ax = vx - nx * d, ay = vy - ny * d, az = vz - nz * d;
    double l = sqrt(ax * ax + ay * ay + az * az);
    l = l < 0.0 ? 0.0 : l;
    return l > 1.0 ? 1.0 : l;
}

DESIGN_INLINE void design_hat(double u, int res, int32_t *k0, double *t)
{
    double x, f;
    int k;
    u = u > 0.0 ? u : 0.0;
    u = u > 1.0 ? 1.0 : u;
    x = u * (double)(res - 1);
    f = floor(x);
    k = (int)f;
    k = k > res - 2 ? res - 2 : k;
    *k0 = k;
    *t = x - (double)k;
}

DESIGN_CLONES static void design_run(void *ctx, int c)
{
    design_ctx *x = ctx;
    const samples *s = x->s;
    hf_design *out = x->out;
    const float *restrict nrm = s->nrm, *restrict wi = s->wi, *restrict wo = s->wo;
    const double *restrict cos_s = s->cos_i;
    int32_t *restrict k0 = out->k0;
    double *restrict t = out->t, *restrict cos_d = out->cos_i;
    int res = out->res;
    int i0 = c * x->chunk, i1 = (c + 1) * x->chunk < s->n ? (c + 1) * x->chunk : s->n;
#pragma omp simd
    for (int i = i0; i < i1; i++) {
        double nx = nrm[3 * i], ny = nrm[3 * i + 1], nz = nrm[3 * i + 2];
        double ix = wi[3 * i], iy = wi[3 * i + 1], iz = wi[3 * i + 2];
        double ox = wo[3 * i], oy = wo[3 * i + 1], oz = wo[3 * i + 2];
        double hx = ix + ox, hy = iy + oy, hz = iz + oz;
        /* v3_normalize: where the length is 0 (or NaN) the vector stays as
         * it is, and x * 1 is x to the bit; a multiply under a condition
         * would keep the loop from vectorizing (it may trap) */
        double hl = sqrt(hx * hx + hy * hy + hz * hz);
        double r = 1.0 / (hl > 0.0 ? hl : 1.0);
        hx = hx * r;
        hy = hy * r;
        hz = hz * r;
        design_hat(design_tangent(ix, iy, iz, nx, ny, nz), res, &k0[3 * i], &t[3 * i]);
        design_hat(design_tangent(hx, hy, hz, nx, ny, nz), res, &k0[3 * i + 1], &t[3 * i + 1]);
        design_hat(design_tangent(ox, oy, oz, nx, ny, nz), res, &k0[3 * i + 2], &t[3 * i + 2]);
        cos_d[i] = cos_s[i];
    }
}

int hf_design_build(const samples *s, int res, hf_design *out, glint_err *err)
{
    memset(out, 0, sizeof *out);
    if (res < HF_RES_MIN || res > HF_RES_MAX)
        return glint_err_set(err, GLINT_ERANGE,
                             "factor resolution %d outside %d..%d", res,
                             HF_RES_MIN, HF_RES_MAX);
    if (!s || s->n < 1)
        return glint_err_set(err, GLINT_EINVAL, "no samples to build a design from");
    out->n = s->n;
    out->res = res;
    out->k0 = malloc((size_t)3 * s->n * sizeof *out->k0);
    out->t = malloc((size_t)3 * s->n * sizeof *out->t);
    out->cos_i = malloc((size_t)s->n * sizeof *out->cos_i);
    if (!out->k0 || !out->t || !out->cos_i) {
        hf_design_free(out);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a design of %d samples",
                             s->n);
    }
    {
        design_ctx x = {s, out, 0, 0};
        hf_chunking(s->n, &x.chunk, &x.nchunks);
        if (par_worth((size_t)s->n))
            par_run(x.nchunks, design_run, &x);
        else
            for (int c = 0; c < x.nchunks; c++)
                design_run(&x, c);
    }
    return 0;
}

void hf_design_free(hf_design *d)
{
    if (!d)
        return;
    free(d->k0);
    free(d->t);
    free(d->cos_i);
    memset(d, 0, sizeof *d);
}

double *hf_dense_B(const hf_design *d, double lambda, int *rows, int *ldb)
{
    int R = d->res, n = 3 * R;
    int m = d->n + 3 * (R - 2);
    double *B = calloc((size_t)m * n, sizeof *B);

    if (!B)
        return NULL;
    for (int i = 0; i < d->n; i++) {
        for (int j = 0; j < 3; j++) {
            int col = j * R + d->k0[3 * i + j];
            double t = d->t[3 * i + j];
            B[i + (size_t)m * col] += 1.0 - t;
            B[i + (size_t)m * (col + 1)] += t;
        }
    }
    for (int j = 0; j < 3; j++) {
        for (int r = 0; r < R - 2; r++) {
            int row = d->n + j * (R - 2) + r, cols[3];
            double vals[3];
            hf_laplacian_row(r, cols, vals);
            for (int e = 0; e < 3; e++)
                B[row + (size_t)m * (j * R + cols[e])] = lambda * vals[e];
        }
    }
    *rows = m;
    *ldb = m;
    return B;
}

void hf_normal_matrix(const hf_design *d, double lambda, double *G)
{
    int R = d->res, n = 3 * R;
    double l2 = lambda * lambda;

    memset(G, 0, (size_t)n * n * sizeof *G);
    for (int i = 0; i < d->n; i++) {
        int idx[6];
        double w[6];
        for (int j = 0; j < 3; j++) {
            int col = j * R + d->k0[3 * i + j];
            double t = d->t[3 * i + j];
            idx[2 * j] = col;
            idx[2 * j + 1] = col + 1;
            w[2 * j] = 1.0 - t;
            w[2 * j + 1] = t;
        }
        for (int a = 0; a < 6; a++)
            for (int b = 0; b < 6; b++)
                G[idx[a] + (size_t)n * idx[b]] += w[a] * w[b];
    }
    if (l2 > 0.0) {
        for (int j = 0; j < 3; j++) {
            for (int r = 0; r < R - 2; r++) {
                int cols[3];
                double vals[3];
                hf_laplacian_row(r, cols, vals);
                for (int a = 0; a < 3; a++)
                    for (int b = 0; b < 3; b++)
                        G[(j * R + cols[a]) + (size_t)n * (j * R + cols[b])] +=
                            l2 * vals[a] * vals[b];
            }
        }
    }
}

void hf_gauge_vectors(int res, double *Z)
{
    /* span{(1,-1,0), (1,0,-1)} (each block constant), orthonormalized:
     * z1 = (1,-1,0)/sqrt(2R), z2 = (1,1,-2)/sqrt(6R). */
    int n = 3 * res;
    double a = 1.0 / sqrt(2.0 * res), b = 1.0 / sqrt(6.0 * res);

    for (int k = 0; k < res; k++) {
        Z[k] = a;
        Z[res + k] = -a;
        Z[2 * res + k] = 0.0;
        Z[n + k] = b;
        Z[n + res + k] = b;
        Z[n + 2 * res + k] = -2.0 * b;
    }
}

void hf_At_f(const hf_design *d, const double *f, double *t)
{
    /* Neighbouring samples usually hit the same texels, so a single
     * accumulator array turns the scatter into chains of dependent
     * read-modify-writes.  Four interleaved partial sums (sample i goes to
     * copy i % 4) break the chains; they are added in a fixed order, so the
     * result is deterministic. */
    enum { NCOPY = 4 };
    int R = d->res;
    size_t len = (size_t)9 * R;
    double *part = calloc(NCOPY * len, sizeof *part);

    if (!part) {
        /* fall back to one accumulator */
        memset(t, 0, len * sizeof *t);
        for (int i = 0; i < d->n; i++) {
            const double *fi = f + 3 * i;
            for (int j = 0; j < 3; j++) {
                double *tk = t + 3 * (j * R + d->k0[3 * i + j]);
                double w1 = d->t[3 * i + j], w0 = 1.0 - w1;
                for (int c = 0; c < 3; c++) {
                    tk[c] += w0 * fi[c];
                    tk[3 + c] += w1 * fi[c];
                }
            }
        }
        return;
    }
    for (int i = 0; i < d->n; i++) {
        const double *fi = f + 3 * i;
        double *base = part + (size_t)(i & (NCOPY - 1)) * len;
        for (int j = 0; j < 3; j++) {
            double *tk = base + 3 * (j * R + d->k0[3 * i + j]);
            double w1 = d->t[3 * i + j], w0 = 1.0 - w1;
            tk[0] += w0 * fi[0];
            tk[1] += w0 * fi[1];
            tk[2] += w0 * fi[2];
            tk[3] += w1 * fi[0];
            tk[4] += w1 * fi[1];
            tk[5] += w1 * fi[2];
        }
    }
    for (size_t k = 0; k < len; k++)
        t[k] = (part[k] + part[len + k]) + (part[2 * len + k] + part[3 * len + k]);
    free(part);
}

void hf_A_y(const hf_design *d, const double *y, double *out)
{
    int R = d->res;

    for (int i = 0; i < d->n; i++) {
        double acc[3] = {0.0, 0.0, 0.0};
        for (int j = 0; j < 3; j++) {
            const double *yk = y + 3 * (j * R + d->k0[3 * i + j]);
            double w1 = d->t[3 * i + j], w0 = 1.0 - w1;
            for (int c = 0; c < 3; c++)
                acc[c] += w0 * yk[c] + w1 * yk[3 + c];
        }
        for (int c = 0; c < 3; c++)
            out[3 * i + c] = acc[c];
    }
}
