/* hf_stream.c: the sample-level passes of a fit (hf_fit), streamed.
 *
 * The forward pass maps every sample's RGB value to log space and scatters
 * it into t = A^T f in one sweep: the samples are cut into chunks whose
 * size depends only on the sample count (hf_chunking), each chunk maps a
 * block of HF_BLOCK samples at a time into a buffer that stays in L1
 * (values, floor, logs) and scatters the block into four interleaved
 * partial sums (sample i into copy i % 4, which breaks the chains of
 * dependent read-modify-writes on a texel that neighbouring samples share),
 * a texel's channels in a slot of their own (fwd_run).
 * Chunks run on the pool's threads (par.h); each chunk's sum is kept apart
 * and the chunks are added in chunk order, so t is the same bits on one
 * thread or many.  Nothing of size n is written: the pass reads the RGB
 * values, the design's texel indices and weights (and n.wi for the BRDF
 * model) once.
 *
 * The diagnostics pass (log residual, linear RMS and maximum error) runs
 * the same way over every sample, or over HF_DIAG_SAMPLES in evenly spaced
 * runs of consecutive samples when there are more (hf.h, hf_fit_stats); its sums
 * are kept in vector lanes (diag_run), in an order fixed by the chunking,
 * so they too are the same bits on any thread count. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "internal/hf_int.h"
#include "par.h"
#include "vmath.h"

#ifndef HF_BLOCK
#define HF_BLOCK 256
#endif

typedef double v4d __attribute__((vector_size(32)));
#define COS_FLOOR 1e-6

void hf_chunking(long n, int *chunk, int *nchunks)
{
    long c = (n + HF_MAX_CHUNKS - 1) / HF_MAX_CHUNKS;
    if (c < HF_MIN_CHUNK)
        c = HF_MIN_CHUNK;
    *chunk = (int)c;
    *nchunks = (int)((n + c - 1) / c);
}

/* Whether idx[0..nb-1] is runs of consecutive samples, each starting at a
 * multiple of 8 in idx and a multiple of 8 long (the diagnostics' runs).
 * Each run's 3 x 8k values are then whole steps of vmath_log_map3's loops,
 * as they are in the block's, so mapping the runs one by one gives the
 * block's bits. */
static int runs_of_eight(const int *idx, int nb)
{
    for (int b = 0, e; b < nb; b = e) {
        for (e = b + 1; e < nb && idx[e] == idx[e - 1] + 1; e++)
            ;
        if ((e - b) % 8)
            return 0;
    }
    return 1;
}

/* The log-mapped values of samples idx[0..nb-1] (or first..first+nb-1 when
 * idx is NULL) into buf[3 nb]; counts floored values into clamped[3] and
 * sets *bad when a value is not finite.  The mapping and logs run over the
 * 3 nb values at once (vmath_log_map3; the arithmetic is hf_map_arg's);
 * consecutive samples of the texture model (a block, or runs of eight
 * samples or more) are mapped straight from the floats (vmath_log_map3_f32,
 * the same bits), the others widened into buf first. */
static void map_block(const hf_stream *x, const int *idx, int first, int nb, double *buf,
                      int *clamped, int *bad)
{
    const hf_design *d = x->d;
    const float *rgb = x->rgb;
    const double eps = x->map->eps, sign = x->map->kind == HF_MAP_SUB ? -1.0 : 1.0;
    /* hf_map_arg: log v, add a + v, sub a - v (a per channel) */
    double off[3] = {0.0, 0.0, 0.0};
    long cl[3] = {0, 0, 0};
    int m = 3 * nb;

    if (x->map->kind != HF_MAP_LOG)
        for (int c = 0; c < 3; c++)
            off[c] = x->a[c];
    if (!idx && x->model != HF_MODEL_BRDF) {
        *bad |= vmath_log_map3_f32(rgb + 3 * (size_t)first, buf, (size_t)m, off, sign, eps, cl);
    } else if (x->model != HF_MODEL_BRDF && runs_of_eight(idx, nb)) {
        for (int b = 0, e; b < nb; b = e) {
            for (e = b + 1; e < nb && idx[e] == idx[e - 1] + 1; e++)
                ;
            *bad |= vmath_log_map3_f32(rgb + 3 * (size_t)idx[b], buf + 3 * b,
                                       (size_t)(3 * (e - b)), off, sign, eps, cl);
        }
    } else {
        if (idx) {
            for (int b = 0; b < nb; b++)
                for (int c = 0; c < 3; c++)
                    buf[3 * b + c] = rgb[3 * (size_t)idx[b] + c];
        } else {
            const float *src = rgb + 3 * (size_t)first;
            for (int j = 0; j < m; j++)
                buf[j] = src[j];
        }
        if (x->model == HF_MODEL_BRDF)
            for (int b = 0; b < nb; b++) {
                int i = idx ? idx[b] : first + b;
                double cosd = d->cos_i[i] > COS_FLOOR ? d->cos_i[i] : COS_FLOOR;
                for (int c = 0; c < 3; c++)
                    buf[3 * b + c] /= cosd;
            }
        *bad |= vmath_log_map3(buf, buf, (size_t)m, off, sign, eps, cl);
    }
    for (int c = 0; c < 3; c++)
        clamped[c] += (int)cl[c];
}

/* map_block in single precision (HF_F32): the values, the mapping and the
 * logs in float (vmath_logf_map3); the sums they go into stay double. */
static void map_block_f(const hf_stream *x, int first, int nb, float *buf, int *clamped,
                        int *bad)
{
    const hf_design *d = x->d;
    const float *src = x->rgb + 3 * (size_t)first;
    int m = 3 * nb;
    float off[3] = {0.0f, 0.0f, 0.0f};
    long cl[3] = {0, 0, 0};

    if (x->model == HF_MODEL_BRDF) {
        for (int b = 0; b < nb; b++) {
            double cosd = d->cos_i[first + b] > COS_FLOOR ? d->cos_i[first + b] : COS_FLOOR;
            for (int c = 0; c < 3; c++)
                buf[3 * b + c] = (float)(src[3 * b + c] / cosd);
        }
        src = buf;
    }
    if (x->map->kind != HF_MAP_LOG)
        for (int c = 0; c < 3; c++)
            off[c] = (float)x->a[c];
    *bad |= vmath_logf_map3(src, buf, (size_t)m, off, x->map->kind == HF_MAP_SUB ? -1.0f : 1.0f,
                            (float)x->map->eps, cl);
    for (int c = 0; c < 3; c++)
        clamped[c] += (int)cl[c];
}

typedef struct fwd_task {
    const hf_stream *x;
    int chunk, nchunks;
    const int *todo;     /* the chunks to sum (task k: chunk todo[k]) */
    double *part;        /* nchunks x 9R */
    int *clamped;        /* nchunks x 3 */
    int *bad;            /* nchunks: a non-finite sample was seen */
    int oom;
} fwd_task;

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define HF_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define HF_CLONES
#endif

/* One chunk of the forward pass.  Each copy of the sums keeps a texel's
 * three channels in a 32-byte slot of its own (RGB and a lane that stays
 * 0): a sample adds one four-lane vector to texel k0's slot and one to
 * k0 + 1's, each lane the scalar w * f + sum.  Every load of a slot then
 * matches the last store to it, which the store buffer forwards; with the
 * slots packed (texel k0 + 1 three doubles after k0), a sample's load
 * straddled the stores of the sample four before it on a neighbouring
 * texel, which cannot be forwarded and waits for them to reach the cache.
 * The same sums in the same order as packed slots, so the same bits. */
HF_CLONES static void fwd_run(void *ctx, int task)
{
    fwd_task *w = ctx;
    const hf_design *d = w->x->d;
    int c = w->todo[task], R = d->res, i0 = c * w->chunk, i1 = i0 + w->chunk;
    size_t len = (size_t)9 * R, slen = (size_t)12 * R; /* a copy: 3R slots of 4 */
    double buf[3 * HF_BLOCK], *out = w->part + c * len;
    double *acc = aligned_alloc(64, 4 * slen * sizeof *acc); /* 384 R bytes */
    int *clamped = w->clamped + 3 * c;

    clamped[0] = clamped[1] = clamped[2] = 0;
    w->bad[c] = 0;
    if (i1 > d->n)
        i1 = d->n;
    if (!acc) {
        w->oom = 1;
        return;
    }
    memset(acc, 0, 4 * slen * sizeof *acc);
    for (int b0 = i0; b0 < i1; b0 += HF_BLOCK) {
        int nb = i1 - b0 < HF_BLOCK ? i1 - b0 : HF_BLOCK;
        if (w->x->single) {
            float fbuf[3 * HF_BLOCK];
            map_block_f(w->x, b0, nb, fbuf, clamped, w->bad + c);
            for (int j = 0; j < 3 * nb; j++)
                buf[j] = fbuf[j];
        } else {
            map_block(w->x, NULL, b0, nb, buf, clamped, w->bad + c);
        }
        for (int b = 0; b < nb; b++) {
            int i = b0 + b;
            const double *fi = buf + 3 * b;
            const int32_t *k0 = d->k0 + 3 * (size_t)i;
            const double *tt = d->t + 3 * (size_t)i;
            double *base = acc + (size_t)(i & 3) * slen;
            const v4d f4 = {fi[0], fi[1], fi[2], 0.0}, one = {1.0, 1.0, 1.0, 1.0};
            for (int j = 0; j < 3; j++) {
                double *tk = base + 4 * (j * R + k0[j]);
                v4d w1 = {tt[j], tt[j], tt[j], tt[j]}, w0 = one - w1, s0, s1;
                memcpy(&s0, tk, sizeof s0);
                memcpy(&s1, tk + 4, sizeof s1);
                s0 += w0 * f4;
                s1 += w1 * f4;
                memcpy(tk, &s0, sizeof s0);
                memcpy(tk + 4, &s1, sizeof s1);
            }
        }
    }
    for (size_t k = 0; k < (size_t)3 * R; k++)
        for (int ch = 0; ch < 3; ch++) {
            size_t q = 4 * k + ch;
            out[3 * k + ch] = (acc[q] + acc[slen + q]) + (acc[2 * slen + q] + acc[3 * slen + q]);
        }
    free(acc);
}

/* ---- the memo of a pass's chunk sums (hf.h) -------------------------------------------- */

struct hf_memo {
    char *key;           /* the caller's key and the pass's parameters */
    int nviews, nchunks;
    size_t len;          /* 9R */
    int sorted;          /* the samples' views never decrease: chunks span view ranges */
    double *part;        /* nchunks x len: each chunk's sums */
    int *clamped;        /* nchunks x 3 */
    int *bad;            /* nchunks */
    unsigned char *valid; /* nchunks: part holds the sums for tags[] */
    int *vlo, *vhi;      /* nchunks: the views a chunk's samples come from */
    int *toff;           /* nchunks + 1: chunk c's views' tags at tags[toff[c]..] */
    uint64_t *tags;      /* the paintings' tags the valid sums were made from */
    /* the values' history (samples_change) the valid sums are known in:
     * chunk c's sums are those of the values as of read epoch[c] of the
     * history change_id (0: none) */
    uint64_t change_id;
    uint64_t *epoch;     /* nchunks */
};

hf_memo *hf_memo_new(void)
{
    return calloc(1, sizeof(hf_memo));
}

static void memo_clear(hf_memo *m)
{
    free(m->key);
    free(m->part);
    free(m->clamped);
    free(m->bad);
    free(m->valid);
    free(m->vlo);
    free(m->vhi);
    free(m->toff);
    free(m->tags);
    free(m->epoch);
    memset(m, 0, sizeof *m);
}

void hf_memo_free(hf_memo *m)
{
    if (!m)
        return;
    memo_clear(m);
    free(m);
}

/* The memo's key for this pass: the caller's, and every parameter of the
 * pass besides the paintings (exact bits of the doubles). */
static char *memo_key(const hf_stream *x, const hf_fit_reuse *r)
{
    const hf_design *d = x->d;
    size_t len = strlen(r->key) + 256;
    char *k = malloc(len);
    if (k)
        snprintf(k, len, "%s|n%d|r%d|m%d,%a,%a,%a|a%a,%a,%a|o%d|s%d|v%d", r->key, d->n, d->res,
                 (int)x->map->kind, x->map->eps, x->map->a, x->map->margin, x->a[0], x->a[1],
                 x->a[2], (int)x->model, x->single, r->nviews);
    return k;
}

/* Make m the memo of this pass (key k, taken over), every chunk invalid:
 * 0, or -1 out of memory (m is left empty). */
static int memo_reset(hf_memo *m, char *k, const hf_stream *x, const hf_fit_reuse *r,
                      int chunk, int nchunks)
{
    const hf_design *d = x->d;
    int total = 0;

    memo_clear(m);
    m->key = k;
    m->nviews = r->nviews;
    m->nchunks = nchunks;
    m->len = (size_t)9 * d->res;
    m->sorted = 1;
    for (long i = 1; i < d->n && m->sorted; i++)
        m->sorted = r->view[i] >= r->view[i - 1];
    for (long i = 0; i < d->n && m->sorted; i++)
        m->sorted = r->view[i] >= 0 && r->view[i] < r->nviews;
    m->part = malloc((size_t)nchunks * m->len * sizeof *m->part);
    m->clamped = calloc((size_t)nchunks * 3, sizeof *m->clamped);
    m->bad = calloc((size_t)nchunks, sizeof *m->bad);
    m->valid = calloc((size_t)nchunks, 1);
    m->vlo = malloc((size_t)nchunks * sizeof *m->vlo);
    m->vhi = malloc((size_t)nchunks * sizeof *m->vhi);
    m->toff = malloc(((size_t)nchunks + 1) * sizeof *m->toff);
    m->epoch = calloc((size_t)nchunks, sizeof *m->epoch);
    if (!m->part || !m->clamped || !m->bad || !m->valid || !m->vlo || !m->vhi || !m->toff ||
        !m->epoch) {
        memo_clear(m);
        return -1;
    }
    for (int c = 0; c < nchunks; c++) {
        long i0 = (long)c * chunk, i1 = i0 + chunk < d->n ? i0 + chunk : d->n;
        m->vlo[c] = m->sorted ? r->view[i0] : 0;
        m->vhi[c] = m->sorted ? r->view[i1 - 1] : -1;
        m->toff[c] = total;
        total += m->vhi[c] - m->vlo[c] + 1;
    }
    m->toff[nchunks] = total;
    m->tags = malloc(((size_t)total + 1) * sizeof *m->tags);
    if (!m->tags) {
        memo_clear(m);
        return -1;
    }
    return 0;
}

/* Are chunk c's sums in the memo those of these paintings: its views'
 * tags unchanged, or none of its spans' values changed since the sums
 * were made? */
static int memo_fresh(const hf_memo *m, int c, const hf_fit_reuse *r, int chunk, long n)
{
    const samples_change *ch = r->change;
    int same = m->sorted;

    if (!m->valid[c])
        return 0;
    for (int v = m->vlo[c]; v <= m->vhi[c] && same; v++)
        same = m->tags[m->toff[c] + v - m->vlo[c]] == r->tags[v];
    if (same || !ch || ch->id != m->change_id)
        return same;
    {
        long i0 = (long)c * chunk, i1 = i0 + chunk < n ? i0 + chunk : n;
        for (long k = i0 / SAMPLES_SPAN; k <= (i1 - 1) / SAMPLES_SPAN; k++)
            if (ch->gen[k] > m->epoch[c])
                return 0;
    }
    return 1;
}

int hf_stream_forward(const hf_stream *x, const hf_fit_reuse *reuse, double *t,
                      int clamped[3], int *reused)
{
    const hf_design *d = x->d;
    size_t len = (size_t)9 * d->res;
    hf_memo *m = NULL;
    int *todo = NULL, ntodo = 0, rc = 0;
    fwd_task w;

    memset(&w, 0, sizeof w);
    w.x = x;
    *reused = 0;
    hf_chunking(d->n, &w.chunk, &w.nchunks);
    if (reuse && reuse->memo && reuse->key && reuse->view && reuse->tags && reuse->nviews > 0) {
        char *k = memo_key(x, reuse);
        m = reuse->memo;
        if (!k)
            m = NULL;
        else if (m->key && strcmp(m->key, k) == 0 && m->nchunks == w.nchunks)
            free(k);
        else if (memo_reset(m, k, x, reuse, w.chunk, w.nchunks)) /* takes k */
            m = NULL;
    }
    if (m) {
        w.part = m->part;
        w.clamped = m->clamped;
        w.bad = m->bad;
    } else {
        w.part = malloc((size_t)w.nchunks * len * sizeof *w.part);
        w.clamped = calloc((size_t)w.nchunks * 3, sizeof *w.clamped);
        w.bad = calloc((size_t)w.nchunks, sizeof *w.bad);
    }
    todo = malloc((size_t)w.nchunks * sizeof *todo);
    if (!w.part || !w.clamped || !w.bad || !todo) {
        rc = -1;
        goto done;
    }
    for (int c = 0; c < w.nchunks; c++) {
        if (m && memo_fresh(m, c, reuse, w.chunk, d->n))
            continue;
        if (m)
            m->valid[c] = 0;
        todo[ntodo++] = c;
    }
    *reused = w.nchunks - ntodo;
    w.todo = todo;
    if (ntodo > 1 && par_worth((size_t)3 * d->n * ntodo / w.nchunks))
        par_run(ntodo, fwd_run, &w);
    else
        for (int k = 0; k < ntodo; k++)
            fwd_run(&w, k);
    if (w.oom) {
        rc = -1;
        goto done;
    }
    if (m) {
        /* Every valid chunk now holds the sums of these paintings, the
         * values as of this read: the chunks just summed, and those
         * reused, by their tags (equal tags, equal values) or their
         * spans.  A fit without a history forgets the memo's. */
        const samples_change *ch = reuse->change;
        for (int k = 0; k < ntodo; k++)
            m->valid[todo[k]] = !m->bad[todo[k]];
        for (int c = 0; c < w.nchunks; c++) {
            if (!m->valid[c])
                continue;
            for (int v = m->vlo[c]; v <= m->vhi[c]; v++)
                m->tags[m->toff[c] + v - m->vlo[c]] = reuse->tags[v];
            m->epoch[c] = ch ? ch->epoch : 0;
        }
        m->change_id = ch ? ch->id : 0;
    }
    /* the chunks' sums added in chunk order, however they were made */
    memcpy(t, w.part, len * sizeof *t);
    for (int c = 1; c < w.nchunks; c++)
        for (size_t k = 0; k < len; k++)
            t[k] += w.part[c * len + k];
    clamped[0] = clamped[1] = clamped[2] = 0;
    for (int c = 0; c < w.nchunks; c++) {
        for (int ch = 0; ch < 3; ch++)
            clamped[ch] += w.clamped[3 * c + ch];
        rc |= w.bad[c];
    }
done:
    if (!m) {
        free(w.part);
        free(w.clamped);
        free(w.bad);
    } else if (rc < 0) {
        memset(m->valid, 0, (size_t)m->nchunks);
    }
    free(todo);
    return rc;
}

/* ---- diagnostics ---------------------------------------------------------------------- */

typedef struct diag_task {
    const hf_stream *x;
    const hf_factors *fac;
    long stride, count;  /* j < count: sample (j / run) stride + j % run */
    long run;
    int chunk, nchunks;
    double *ss, *se, *mx; /* per chunk */
    double *logf;         /* the factors' logf and one double more, so that a
                           * texel's last channel loads as a four-lane vector */
} diag_task;

typedef float v4f __attribute__((vector_size(16)));
typedef long long v4l __attribute__((vector_size(32)));

/* The start of the cache line holding p. */
static const char *line_of(const void *p)
{
    return (const char *)((uintptr_t)p & ~(uintptr_t)63);
}

/* Ask for the cache lines of the samples of the block at j (before j1)
 * of the diagnostics' runs: its values, texel indices and weights (and
 * n.wi).  Runs far apart start new streams the hardware has not seen;
 * fetched a block ahead, their first lines do not wait for memory. */
static void diag_prefetch(const hf_stream *x, const diag_task *w, long j, long j1)
{
    const hf_design *d = x->d;
    long je = j + HF_BLOCK < j1 ? j + HF_BLOCK : j1;
    while (j < je) {
        long o = j % w->run, len = w->run - o < je - j ? w->run - o : je - j;
        size_t i = (size_t)(j / w->run * w->stride + o), e = i + (size_t)len;
        for (const char *q = line_of(x->rgb + 3 * i); q < (const char *)(x->rgb + 3 * e);
             q += 64)
            __builtin_prefetch(q);
        for (const char *q = line_of(d->k0 + 3 * i); q < (const char *)(d->k0 + 3 * e);
             q += 64)
            __builtin_prefetch(q);
        for (const char *q = line_of(d->t + 3 * i); q < (const char *)(d->t + 3 * e);
             q += 64)
            __builtin_prefetch(q);
        if (x->model == HF_MODEL_BRDF)
            for (const char *q = line_of(d->cos_i + i); q < (const char *)(d->cos_i + e);
                 q += 64)
                __builtin_prefetch(q);
        j += len;
    }
}

/* One chunk of the diagnostics.  Per sample, in scalar code: the three
 * channels' log-space reconstruction (the texel loads are random) and its
 * residual.  Then, four lanes at a time over a block's 3 nb values: the
 * squared residuals, the reconstruction mapped back and rounded to float
 * as a material stores it, its squared error and |error|.  Each of the
 * three vectors of a 12-value step keeps its own lane sums (lane l of
 * vector q sums channel (4q + l) % 3), added in a fixed order at the end
 * of the chunk with the scalar tail's: the sums are those of one chain per
 * figure in another order (the maximum is the same), and the order is a
 * function of the chunking alone, so the figures are the same bits on any
 * thread count and any of the clones.  One chain per figure was a
 * dependent addition per value, which bounded the loop. */
HF_CLONES static void diag_run(void *ctx, int c)
{
    diag_task *w = ctx;
    const hf_stream *x = w->x;
    const hf_design *d = x->d;
    const hf_factors *fac = w->fac;
    int R = d->res, idx[HF_BLOCK], clamped[3] = {0, 0, 0}, bad = 0;
    long j0 = (long)c * w->chunk, j1 = j0 + w->chunk;
    /* one double more in fb, rb and lb: a sample's three channels load
     * and store as a four-lane vector */
    double fb[3 * HF_BLOCK + 1], lb[3 * HF_BLOCK + 1], rb[3 * HF_BLOCK + 1], pb[3 * HF_BLOCK],
        cb[3 * HF_BLOCK];
    double sst = 0.0, set = 0.0, mxt = 0.0;
    const hf_map_kind kind = fac->map.kind;
    const double a3[3] = {fac->a_used[0], fac->a_used[1], fac->a_used[2]};
    const int brdf = fac->model == HF_MODEL_BRDF;
    const v4d zero = {0.0, 0.0, 0.0, 0.0}, cap = {700.0, 700.0, 700.0, 700.0};
    v4d ssv[3], sev[3], mxv[3], av[3];

    for (int q = 0; q < 3; q++) {
        ssv[q] = sev[q] = mxv[q] = zero;
        for (int l = 0; l < 4; l++)
            av[q][l] = a3[(4 * q + l) % 3];
    }
    if (j1 > w->count)
        j1 = w->count;
    for (long b0 = j0; b0 < j1; b0 += HF_BLOCK) {
        int nb = j1 - b0 < HF_BLOCK ? (int)(j1 - b0) : HF_BLOCK, m = 3 * nb, j;
        { /* sample (j / run) stride + j % run, one division per block */
            long r = b0 / w->run, o = b0 % w->run;
            for (int b = 0; b < nb; b++) {
                idx[b] = (int)(r * w->stride + o);
                if (++o == w->run) {
                    o = 0;
                    r++;
                }
            }
            if (w->run < HF_BLOCK) /* runs apart: the next block's, fetched now */
                diag_prefetch(x, w, b0 + HF_BLOCK, j1);
        }
        map_block(x, idx, 0, nb, fb, clamped, &bad);
        for (int b = 0; b < nb; b++) {
            int i = idx[b];
            const float *px = x->rgb + 3 * (size_t)i;
            /* the three channels' sums in the lanes of one vector, each lane
             * the scalar sum: 0 + (w0 y + w1 y') per factor, in factor
             * order; lane 3 is not used (stored, then overwritten by the next
             * sample's) */
            v4d a = zero, f, r, l;
            for (int k = 0; k < 3; k++) {
                const double *yk = w->logf + 3 * (k * R + d->k0[3 * i + k]);
                double w1 = d->t[3 * i + k], w0 = 1.0 - w1;
                v4d y0, y1, w04 = {w0, w0, w0, w0}, w14 = {w1, w1, w1, w1};
                memcpy(&y0, yk, sizeof y0);
                memcpy(&y1, yk + 3, sizeof y1);
                a += w04 * y0 + w14 * y1;
            }
            memcpy(&f, fb + 3 * b, sizeof f);
            r = a - f;
            l = (v4d)(((v4l)a & ~(v4l)(a > cap)) | ((v4l)cap & (v4l)(a > cap)));
            memcpy(rb + 3 * b, &r, sizeof r);
            memcpy(lb + 3 * b, &l, sizeof l);
            pb[3 * b] = px[0];
            pb[3 * b + 1] = px[1];
            pb[3 * b + 2] = px[2];
            if (brdf) /* the radiance model's cosine is 1.0, an exact product */
                cb[3 * b] = cb[3 * b + 1] = cb[3 * b + 2] = d->cos_i[i];
        }
        vmath_exp(lb, lb, (size_t)m);
        /* the reconstruction (hf_map_inverse, inlined), clamped at 0 (NaN
         * too), as the material stores it (float), against the painting */
        for (j = 0; j + 12 <= m; j += 12)
            for (int q = 0; q < 3; q++) {
                v4d r, v, p, e, ae;
                memcpy(&r, rb + j + 4 * q, sizeof r);
                memcpy(&v, lb + j + 4 * q, sizeof v);
                memcpy(&p, pb + j + 4 * q, sizeof p);
                ssv[q] += r * r;
                v = kind == HF_MAP_ADD ? v - av[q] : kind == HF_MAP_SUB ? av[q] - v : v;
                v = (v4d)((v4l)v & (v4l)(v > zero)); /* v > 0 ? v : 0 */
                if (brdf) {
                    v4d cw;
                    memcpy(&cw, cb + j + 4 * q, sizeof cw);
                    v *= cw;
                }
                e = __builtin_convertvector(__builtin_convertvector(v, v4f), v4d) - p;
                sev[q] += e * e;
                ae = (v4d)((v4l)e & 0x7fffffffffffffffLL); /* fabs */
                {
                    v4l gt = (v4l)(ae > mxv[q]);
                    mxv[q] = (v4d)(((v4l)ae & gt) | ((v4l)mxv[q] & ~gt));
                }
            }
        for (; j < m; j++) { /* the block's last values, one by one */
            double v = lb[j], e;
            v = kind == HF_MAP_ADD ? v - a3[j % 3] : kind == HF_MAP_SUB ? a3[j % 3] - v : v;
            v = v > 0.0 ? v : 0.0;
            if (brdf)
                v *= cb[j];
            e = (double)(float)v - pb[j];
            sst += rb[j] * rb[j];
            set += e * e;
            mxt = fabs(e) > mxt ? fabs(e) : mxt;
        }
    }
    for (int q = 0; q < 3; q++)
        for (int l = 0; l < 4; l++) {
            sst += ssv[q][l];
            set += sev[q][l];
            mxt = mxv[q][l] > mxt ? mxv[q][l] : mxt;
        }
    w->ss[c] = sst;
    w->se[c] = set;
    w->mx[c] = mxt;
}

int hf_stream_diagnostics(const hf_stream *x, const hf_factors *fac, hf_fit_stats *st)
{
    long n = x->d->n;
    diag_task w;
    double ss = 0.0, se = 0.0, mx = 0.0;
    int rc = 0;

    memset(&w, 0, sizeof w);
    w.x = x;
    w.fac = fac;
    if (n > HF_DIAG_SAMPLES) { /* runs of HF_DIAG_RUN, evenly spaced (hf.h) */
        w.run = HF_DIAG_RUN;
        w.stride = n / (HF_DIAG_SAMPLES / HF_DIAG_RUN);
        w.count = HF_DIAG_SAMPLES;
    } else {
        w.run = n > 0 ? n : 1;
        w.stride = 1;
        w.count = n;
    }
    hf_chunking(w.count, &w.chunk, &w.nchunks);
    w.ss = malloc((size_t)w.nchunks * sizeof *w.ss);
    w.se = malloc((size_t)w.nchunks * sizeof *w.se);
    w.mx = malloc((size_t)w.nchunks * sizeof *w.mx);
    w.logf = malloc(((size_t)9 * x->d->res + 1) * sizeof *w.logf);
    if (!w.ss || !w.se || !w.mx || !w.logf) {
        rc = -1;
        goto done;
    }
    memcpy(w.logf, fac->logf, (size_t)9 * x->d->res * sizeof *w.logf);
    w.logf[9 * x->d->res] = 0.0;
    if (par_worth((size_t)3 * w.count))
        par_run(w.nchunks, diag_run, &w);
    else
        for (int c = 0; c < w.nchunks; c++)
            diag_run(&w, c);
    for (int c = 0; c < w.nchunks; c++) {
        ss += w.ss[c];
        se += w.se[c];
        if (w.mx[c] > mx)
            mx = w.mx[c];
    }
    st->log_residual = sqrt(ss / (3.0 * w.count));
    st->rms = sqrt(se / (3.0 * w.count));
    st->max_abs = mx;
    st->diag_samples = w.count;
    st->diag_stride = w.stride;
    st->diag_runs = w.count / w.run;
done:
    free(w.ss);
    free(w.se);
    free(w.mx);
    free(w.logf);
    return rc;
}
