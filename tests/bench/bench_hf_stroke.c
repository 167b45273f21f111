/* bench_hf_stroke.c: bench_hf --warm's fit after a brush stroke.
 *
 * A painter's session keeps its samples' values and its pass's chunk sums
 * from one fit to the next (prep_fit_reusing, hf_fit_with).  After a
 * stroke the stroked view is read again and compared with what was kept,
 * span by span, and the pass sums again only the chunks whose values
 * changed.  This part makes the strokes glintd's benchmark posts (20
 * points, diameter 12 on a 256-pixel view: tests/bench/bench_daemon.py),
 * scaled to the raster, and times each fit through the memo against the
 * same fit from nothing, interleaved, checking that both are the same
 * bits. */
#include <math.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bench_hf.h"
#include "hf.h"
#include "hf_int.h"
#include "samples.h"

/* Stroke k: 20 discs along a row, the colour alternating from stroke to
 * stroke (so that every stroke changes the values it covers). */
static void stroke(img *im, int k)
{
    double sc = im->width / 256.0, r = 6.0 * sc, y = (40 + (k * 7) % 160) * sc;
    float col[3] = {0.2f + 0.6f * (float)(k % 2), 0.3f, 0.5f};
    int nc = im->channels < 3 ? im->channels : 3;

    for (int j = 0; j < 20; j++) {
        double x = (20 + 10 * j) * sc;
        for (int py = (int)floor(y - r); py <= (int)ceil(y + r); py++)
            for (int px = (int)floor(x - r); px <= (int)ceil(x + r); px++) {
                double dx = px + 0.5 - x, dy = py + 0.5 - y;
                if (px < 0 || py < 0 || px >= im->width || py >= im->height ||
                    dx * dx + dy * dy > r * r)
                    continue;
                for (int c = 0; c < nc; c++)
                    im->px[((size_t)py * im->width + px) * im->channels + c] = col[c];
            }
    }
}

void stroke_fits(const fit_prep *fp, const img *paint, int reps, stroke_row *out)
{
    const samples *s = &fp->s;
    const fit_params *p = &fp->params;
    long nspans = ((long)s->n + SAMPLES_SPAN - 1) / SAMPLES_SPAN;
    size_t npx = (size_t)paint[0].width * paint[0].height * paint[0].channels;
    float *values = calloc((size_t)3 * s->n, sizeof *values);
    uint64_t *gen = calloc((size_t)nspans, sizeof *gen), *tags = calloc((size_t)s->nviews, 8);
    unsigned char *changed = calloc((size_t)nspans, 1), *which = calloc((size_t)s->nviews, 1);
    img *q = calloc((size_t)s->nviews, sizeof *q);
    double *ga = calloc((size_t)reps, sizeof(double)), *st = calloc((size_t)reps, sizeof(double));
    double *fa = calloc((size_t)reps, sizeof(double)), *dg = calloc((size_t)reps, sizeof(double));
    double *fu = calloc((size_t)reps, sizeof(double)), *ag = calloc((size_t)reps, sizeof(double));
    hf_memo *memo = hf_memo_new();
    samples_change ch;
    hf_fit_reuse r;
    hf_factors a, b;
    hf_fit_stats sa, sb;
    glint_err e;
    int chunk, nchunks;
    long again_samples = 0;

    if (!values || !gen || !tags || !changed || !which || !q || !ga || !st || !fa || !dg ||
        !fu || !ag || !memo)
        die("out of memory", NULL);
    /* view 0 copied, to be stroked; the others as they are */
    memcpy(q, paint, (size_t)s->nviews * sizeof *q);
    if (!(q[0].px = malloc(npx * sizeof *q[0].px)))
        die("out of memory", NULL);
    memcpy(q[0].px, paint[0].px, npx * sizeof *q[0].px);
    which[0] = 1;
    for (int v = 0; v < s->nviews; v++)
        tags[v] = 1 + (uint64_t)v;
    ch = (samples_change){samples_change_id(), 1, gen};
    r = (hf_fit_reuse){memo, "bench", s->view, tags, s->nviews, &ch};
    /* the session's first fit: every view read, every chunk summed */
    if (samples_gather_views(s, q, NULL, values, changed, &e))
        die("gather", &e);
    for (long k = 0; k < nspans; k++)
        if (changed[k])
            gen[k] = ch.epoch;
    if (hf_fit_with(&fp->d, &fp->op, &p->map, p->model, values, &r, &a, &sa, &e))
        die("fit", &e);
    hf_factors_free(&a);
    hf_chunking(s->n, &chunk, &nchunks);
    /* what the comparison costs: every view read as it is (no value
     * changes) and from the same paintings halved (every value changes),
     * against the read without it */
    {
        img *half = calloc((size_t)s->nviews, sizeof *half);
        double *t3 = calloc((size_t)3 * reps, sizeof *t3);
        if (!half || !t3)
            die("out of memory", NULL);
        for (int v = 0; v < s->nviews; v++) {
            size_t m = (size_t)paint[v].width * paint[v].height * paint[v].channels;
            half[v] = paint[v];
            if (!paint[v].px)
                continue;
            if (!(half[v].px = malloc(m * sizeof *half[v].px)))
                die("out of memory", NULL);
            for (size_t i = 0; i < m; i++)
                half[v].px[i] = 0.5f * paint[v].px[i];
        }
        for (int k = 0; k < reps; k++) {
            double t0 = now();
            if (samples_gather_views(s, q, NULL, values, NULL, &e))
                die("gather", &e);
            t3[k] = now() - t0;
            t0 = now();
            if (samples_gather_views(s, q, NULL, values, changed, &e))
                die("gather", &e);
            t3[reps + k] = now() - t0;
            t0 = now();
            if (samples_gather_views(s, k % 2 ? q : half, NULL, values, changed, &e))
                die("gather", &e);
            t3[2 * reps + k] = now() - t0;
        }
        /* the kept values as the memo's first read left them */
        if (samples_gather_views(s, q, NULL, values, NULL, &e))
            die("gather", &e);
        out->read_all = median(t3, reps);
        out->same_all = median(t3 + reps, reps);
        out->diff_all = median(t3 + 2 * reps, reps);
        for (int v = 0; v < s->nviews; v++)
            if (paint[v].px)
                free(half[v].px);
        free(half);
        free(t3);
    }
    for (int k = 0; k < reps; k++) {
        double t0;
        stroke(&q[0], k);
        tags[0] = 100 + (uint64_t)k;
        ch.epoch++;
        t0 = now();
        memset(changed, 0, (size_t)nspans);
        if (samples_gather_views(s, q, which, values, changed, &e))
            die("gather", &e);
        for (long j = 0; j < nspans; j++)
            if (changed[j])
                gen[j] = ch.epoch;
        ga[k] = now() - t0;
        if (hf_fit_with(&fp->d, &fp->op, &p->map, p->model, values, &r, &a, &sa, &e) ||
            hf_fit(&fp->d, &fp->op, &p->map, p->model, values, &b, &sb, &e))
            die("fit", &e);
        if (memcmp(a.logf, b.logf, (size_t)9 * a.res * sizeof *a.logf) != 0 || sa.rms != sb.rms)
            die("a fit through the memo differs from the fit from nothing", NULL);
        st[k] = sa.stream_seconds;
        fa[k] = sa.total_seconds;
        dg[k] = sa.diag_seconds;
        fu[k] = sb.total_seconds;
        ag[k] = sa.stream_chunks - sa.stream_chunks_reused;
        again_samples += (long)(ag[k] * chunk);
        hf_factors_free(&a);
        hf_factors_free(&b);
    }
    out->res = fp->d.res;
    out->n = s->n;
    out->chunks = nchunks;
    out->again = median(ag, reps);
    out->gather = median(ga, reps);
    out->stream = median(st, reps);
    out->factor = median(fa, reps);
    out->diag = median(dg, reps);
    out->full = median(fu, reps);
    /* what it reads: the samples of the chunks summed again (values, texel
     * indices, weights: as the full pass, per sample), every chunk's sums
     * (added in chunk order) and the operator */
    out->bytes = (double)again_samples / reps * (3 * 4 + 3 * 4 + 3 * 8) +
                 (double)nchunks * 9 * fp->d.res * sizeof(double) +
                 (double)hf_op_bytes(&fp->op, NULL);
    free(q[0].px);
    free(q);
    free(values);
    free(gen);
    free(tags);
    free(changed);
    free(which);
    free(ga);
    free(st);
    free(fa);
    free(dg);
    free(fu);
    free(ag);
    hf_memo_free(memo);
}

void stroke_print(const stroke_row *w, double bwp)
{
    printf("     (after a stroke on view 0, through the session's memo: %.0f of %d chunks "
           "summed again; view read and compared %.3f ms; stream %.3f ms, "
           "factorization %.3f ms (from nothing, interleaved: %.3f ms), %.2f MB read, "
           "%.2f x its bound; diag %.3f ms)\n",
           w->again, w->chunks, 1e3 * w->gather, 1e3 * w->stream, 1e3 * w->factor,
           1e3 * w->full, w->bytes / 1e6, w->factor / (w->bytes / bwp), 1e3 * w->diag);
    printf("     (every view read: %.3f ms; compared with the kept values, none changed "
           "%.3f ms, all changed %.3f ms)\n",
           1e3 * w->read_all, 1e3 * w->same_all, 1e3 * w->diff_all);
}

void stroke_table(FILE *md, const stroke_row *rows, int n, double bwp)
{
    fprintf(md, "\nThe fit after a stroke (20 discs of diameter 12 at 256 pixels, scaled, on "
                "view 0) through a session's memo: the view read again and compared with the "
                "kept values, the chunks whose values changed summed again\n\n"
                "| res | samples | chunks summed again | of | read and compare (ms) | "
                "stream (ms) | factorization (ms) | from nothing (ms) | MB read | bound (ms) | "
                "factorization / bound | diagnostics (ms) | every view read (ms) | "
                "compared, none changed (ms) | compared, all changed (ms) |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int r = 0; r < n; r++) {
        const stroke_row *w = &rows[r];
        fprintf(md,
                "| %d | %d | %.0f | %d | %.3f | %.3f | %.3f | %.3f | %.2f | %.3f | %.2f | %.3f | "
                "%.3f | %.3f | %.3f |\n",
                w->res, w->n, w->again, w->chunks, 1e3 * w->gather, 1e3 * w->stream,
                1e3 * w->factor, 1e3 * w->full, w->bytes / 1e6, 1e3 * w->bytes / bwp,
                w->factor / (w->bytes / bwp), 1e3 * w->diag, 1e3 * w->read_all,
                1e3 * w->same_all, 1e3 * w->diff_all);
    }
}
