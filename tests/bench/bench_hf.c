/* bench_hf: speed and accuracy of the fast homomorphic factorization.
 *
 * Part 1 reproduces Table 1 of Jaroszkiewicz & McCool 2003 (three 1D
 * factors, about 7884 samples, resolutions 32..128): preinversion time by
 * both routes (eig of B^T B, the default; dense SVD of B, the reference)
 * and the fast factorization of one RGB painting, beside the paper's 2003
 * figures and the memory-bandwidth bound for the operator's size.
 *
 * Part 2 sweeps the speed-accuracy trade a user makes: resolution 16..256,
 * ranks kept, the three regularizations, single and double precision; for
 * each it prints preinversion time, fit time, operator bytes and RMS error
 * on 20 novel views, writes a CSV and (with gnuplot) a PNG of error against
 * fit time.
 *
 * Part 0 (--warm alone) times the warm fit of a painter's stroke at the
 * full 128x128 raster (98,434 samples): the pass over the samples, the
 * operator, the diagnostics, against the bytes read at the bandwidth
 * measured in the same run; and the fit after a stroke through a
 * session's memo, which sums again only the chunks the stroke changed
 * (bench_hf_stroke.c).
 *
 * usage: bench_hf [--quick] [--warm] [--out DIR]   (DIR default: bench-out)
 * Timings are medians of repeated runs; the machine is shared and noisy. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "bench_hf.h"
#include "brdf.h"
#include "fit.h"
#include "fsio.h"
#include "hf.h"
#include "hf_int.h"
#include "paint.h"
#include "par.h"
#include "vmath.h"
#include "raster.h"
#include "scene.h"

double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void die(const char *what, const glint_err *e)
{
    fprintf(stderr, "bench_hf: %s: %s\n", what, e ? e->msg : "failed");
    exit(1);
}

/* Single-thread STREAM-style triad bandwidth in bytes/s. */
static double triad_bandwidth(void)
{
    size_t n = (size_t)1 << 24; /* 3 x 128 MiB */
    double *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b), *c = malloc(n * sizeof *c);
    double best = 0.0;
    if (!a || !b || !c)
        return 0.0;
    for (size_t i = 0; i < n; i++) {
        a[i] = 0.0;
        b[i] = 1.0;
        c[i] = 2.0;
    }
    for (int r = 0; r < 5; r++) {
        double t0 = now(), dt;
        for (size_t i = 0; i < n; i++)
            a[i] = b[i] + 3.0 * c[i];
        dt = now() - t0;
        if (3.0 * n * sizeof(double) / dt > best)
            best = 3.0 * n * sizeof(double) / dt;
    }
    if (a[n / 2] != 7.0)
        best = 0.0;
    free(a);
    free(b);
    free(c);
    return best;
}

typedef struct triad_ctx {
    double *a, *b, *c;
    size_t n;
    int parts;
} triad_ctx;

static void triad_part(void *ctx, int k)
{
    triad_ctx *t = ctx;
    size_t lo = t->n * (size_t)k / (size_t)t->parts, hi = t->n * (size_t)(k + 1) / (size_t)t->parts;
    for (size_t i = lo; i < hi; i++)
        t->a[i] = t->b[i] + 3.0 * t->c[i];
}

/* The triad on every thread of the pool (par.h): what the fit's own
 * threads can draw, bytes/s. */
static double triad_bandwidth_pool(void)
{
    triad_ctx t;
    double best = 0.0;
    t.n = (size_t)1 << 24;
    t.parts = par_threads();
    t.a = malloc(t.n * sizeof *t.a);
    t.b = malloc(t.n * sizeof *t.b);
    t.c = malloc(t.n * sizeof *t.c);
    if (!t.a || !t.b || !t.c)
        return 0.0;
    for (size_t i = 0; i < t.n; i++) {
        t.a[i] = 0.0;
        t.b[i] = 1.0;
        t.c[i] = 2.0;
    }
    for (int r = 0; r < 5; r++) {
        double t0 = now(), dt;
        par_run(t.parts, triad_part, &t);
        dt = now() - t0;
        if (3.0 * t.n * sizeof(double) / dt > best)
            best = 3.0 * t.n * sizeof(double) / dt;
    }
    if (t.a[t.n / 2] != 7.0)
        best = 0.0;
    free(t.a);
    free(t.b);
    free(t.c);
    return best;
}

typedef struct setup {
    scene sc;
    gbuf *g;
    img *paint;
    double scale;
} setup;

static void setup_make(setup *s, int w, int h, int view_set, int mid, const brdf *b,
                       double scale)
{
    scene_params p;
    glint_err e;
    scene_params_default(&p);
    p.width = w;
    p.height = h;
    p.view_set = view_set;
    p.light_mid = mid;
    if (scene_create(&p, &s->sc, &e) || raster_scene(&s->sc, &s->g, &e))
        die("scene", &e);
    s->paint = calloc((size_t)s->sc.nviews, sizeof *s->paint);
    if (paint_views(b, s->g, s->sc.views, s->sc.nviews, scale, s->paint, &s->scale, &e))
        die("paint", &e);
    if (scale > 0)
        s->scale = scale;
}

static void free_setup(setup *s)
{
    for (int v = 0; v < s->sc.nviews; v++)
        img_free(&s->paint[v]);
    free(s->paint);
    raster_free_all(s->g, s->sc.nviews);
    scene_free(&s->sc);
    memset(s, 0, sizeof *s);
}

static long count_samples(int w, int h)
{
    scene_params p;
    scene sc;
    gbuf *g;
    samples s;
    char hash[33];
    long n;
    scene_params_default(&p);
    p.width = w;
    p.height = h;
    if (scene_create(&p, &sc, NULL) || raster_scene(&sc, &g, NULL))
        return -1;
    scene_hash(&sc, hash);
    n = samples_build(g, sc.views, sc.nviews, NULL, hash, &s, NULL) ? -1 : s.n;
    samples_free(&s);
    raster_free_all(g, sc.nviews);
    scene_free(&sc);
    return n;
}

/* ---- Part 1: Table 1 ------------------------------------------------------------- */

static void table1(FILE *md, int quick)
{
    static const int res[] = {32, 64, 96, 128};
    static const double paper_svd[] = {4.26, 11.08, 21.58, 38.06};
    static const double paper_fast[] = {0.1834, 0.2868, 0.3842, 0.4375};
    int bw_w = 36, bw_h = 36;
    long best = -1;
    brdf b;
    setup s;
    double bw1 = triad_bandwidth();
    const double bw_notes = 30e9;

    /* the raster whose sample count is nearest the paper's 7884 */
    for (int w = 34; w <= 40; w++)
        for (int h = w - 2; h <= w + 2; h++) {
            long n = count_samples(w, h);
            if (n > 0 && (best < 0 || labs(n - 7884) < labs(best - 7884))) {
                best = n;
                bw_w = w;
                bw_h = h;
            }
        }
    brdf_parse("ct0.5", &b, NULL);
    setup_make(&s, bw_w, bw_h, SCENE_VIEWS_ICO12, 0, &b, 0.0);

    printf("\n== Table 1 (seed 000): three 1D factors, %ld samples (%dx%d x 12 views; paper: 7884)\n",
           best, bw_w, bw_h);
    printf("memory bandwidth: measured single-thread triad %.1f GB/s; two-thread figure from "
           "PLATFORM-NOTES 30 GB/s\n", bw1 / 1e9);
    printf("%-4s | %-9s %-9s %-8s | %-8s %-8s %-8s %-8s %-8s %-8s | %-7s %-8s %-6s %-5s\n",
           "res", "pre eig", "pre svd", "paper", "apply", "factor.", "f32", "fit_run", "paper",
           "op KiB", "bound", "ratio", "apply", "<1ms");
    printf("%-4s | %-9s %-9s %-8s | %-8s %-8s %-8s %-8s %-8s %-8s | %-7s %-8s %-6s %-5s\n",
           "", "s", "s", "s", "us", "us", "us", "us", "s", "", "us", "factor.", "/bnd", "");
    fprintf(md, "| res | preinversion eig (s) | preinversion SVD (s) | paper SVD (s) | apply (us) | factorization, double (us) | factorization, single (us) | whole fit_run (us) | paper fast (s) | operator (KiB) | bandwidth bound (us) | factorization / bound | apply / bound |\n");
    fprintf(md, "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (unsigned r = 0; r < sizeof res / sizeof res[0]; r++) {
        double pre_eig[5], pre_svd[3], fit_t[201], app_t[201], fac_t[201], fit32[201];
        int reps_pre = quick ? 2 : 5, reps_fit = quick ? 51 : 201;
        fit_params p;
        fit_prep fp, fp32;
        material m;
        glint_err e;
        double bytes, bound;
        fit_params_default(&p);
        p.res = res[r];
        for (int k = 0; k < reps_pre; k++) {
            double t0 = now();
            if (fit_prepare(&fp, &s.sc, s.g, NULL, &p, NULL, &e))
                die("prepare", &e);
            pre_eig[k] = now() - t0 - fp.t_samples; /* design + decomposition + operator */
            if (k + 1 < reps_pre)
                fit_prep_free(&fp);
        }
        p.route = HF_ROUTE_SVD;
        for (int k = 0; k < (quick ? 1 : 3); k++) {
            fit_prep t;
            double t0 = now();
            if (fit_prepare(&t, &s.sc, s.g, NULL, &p, NULL, &e))
                die("prepare svd", &e);
            pre_svd[k] = now() - t0 - t.t_samples;
            fit_prep_free(&t);
        }
        p.route = HF_ROUTE_EIG;
        p.prec = HF_F32;
        if (fit_prepare(&fp32, &s.sc, s.g, NULL, &p, NULL, &e))
            die("prepare f32", &e);
        for (int k = 0; k < reps_fit; k++) {
            double t0 = now();
            if (fit_run(&fp, s.paint, NULL, &m, &e))
                die("fit", &e);
            fit_t[k] = now() - t0;
            app_t[k] = json_real_value(json_object_get(json_object_get(m.info, "seconds"), "apply"));
            fac_t[k] = json_real_value(
                json_object_get(json_object_get(m.info, "seconds"), "factorization"));
            material_free(&m);
            if (fit_run(&fp32, s.paint, NULL, &m, &e))
                die("fit f32", &e);
            fit32[k] = json_real_value(
                json_object_get(json_object_get(m.info, "seconds"), "factorization"));
            material_free(&m);
        }
        bytes = (double)hf_op_bytes(&fp.op, &fp.d);
        bound = bytes / bw_notes;
        {
            double pe = median(pre_eig, reps_pre), ps = median(pre_svd, quick ? 1 : 3);
            double ft = median(fit_t, reps_fit), at = median(app_t, reps_fit);
            double fa = median(fac_t, reps_fit), f3 = median(fit32, reps_fit);
            printf("%-4d | %-9.4f %-9.3f %-8.2f | %-8.1f %-8.1f %-8.1f %-8.1f %-8.4f %-8.0f | %-7.1f %-8.2f %-6.2f %-5s\n",
                   res[r], pe, ps, paper_svd[r], 1e6 * at, 1e6 * fa, 1e6 * f3, 1e6 * ft,
                   paper_fast[r], bytes / 1024.0, 1e6 * bound, fa / bound, at / bound,
                   fa < 1e-3 ? "yes" : "NO");
            fprintf(md, "| %d | %.4f | %.3f | %.2f | %.1f | %.1f | %.1f | %.1f | %.4f | %.0f | %.1f | %.2f | %.2f |\n",
                    res[r], pe, ps, paper_svd[r], 1e6 * at, 1e6 * fa, 1e6 * f3, 1e6 * ft,
                    paper_fast[r], bytes / 1024.0, 1e6 * bound, fa / bound, at / bound);
        }
        fit_prep_free(&fp);
        fit_prep_free(&fp32);
    }
    printf("(pre: design + decomposition + operator, no cache; apply: A^T f and M t;\n"
           " factorization: log mapping + apply + gauge, the fast factorization of Table 1;\n"
           " fit_run: also reading the painting and the error diagnostics;\n"
           " bound: operator bytes (M and the sparse rows of A) / 30 GB/s)\n");
}

/* The fused log mappings alone, on 768 values in L1 (fastest of 2000 x
 * 10 calls), under each instruction set this CPU offers (vmath_limit):
 * what the stream's logs cost per value. */
static void log_rates(void)
{
    enum { N = 768 };
    static double in[N], out[N];
    static float fin[N], fout[N];
    const double off[3] = {0.0, 0.0, 0.0};
    const float offf[3] = {0.0f, 0.0f, 0.0f};
    const char *caps[] = {"avx2", "avx512"};
    for (int i = 0; i < N; i++) {
        in[i] = 0.01 + (double)(i * 37 % 1000) / 500.0;
        fin[i] = (float)in[i];
    }
    printf("fused log mapping in L1, ns per value (double / single / double from single):");
    for (int c = 0; c < 2; c++) {
        double bd = 1.0, bf = 1.0, bw = 1.0;
        const char *impl;
        vmath_limit(caps[c]);
        impl = vmath_impl();
        if (c == 1 && !strstr(impl, "avx512"))
            break; /* the CPU has no AVX-512 */
        for (int rep = 0; rep < 2000; rep++) {
            long cl[3] = {0, 0, 0};
            double t0 = now(), t;
            for (int k = 0; k < 10; k++)
                vmath_log_map3(in, out, N, off, 1.0, 1e-6, cl);
            if ((t = now() - t0) < bd)
                bd = t;
            t0 = now();
            for (int k = 0; k < 10; k++)
                vmath_logf_map3(fin, fout, N, offf, 1.0f, 1e-6f, cl);
            if ((t = now() - t0) < bf)
                bf = t;
            t0 = now();
            for (int k = 0; k < 10; k++)
                vmath_log_map3_f32(fin, out, N, off, 1.0, 1e-6, cl);
            if ((t = now() - t0) < bw)
                bw = t;
        }
        printf("  %s %.2f / %.2f / %.2f", caps[c], 1e9 * bd / (10.0 * N), 1e9 * bf / (10.0 * N),
               1e9 * bw / (10.0 * N));
    }
    vmath_limit(NULL);
    printf("\n");
}

/* ---- Part 0: the warm path at the full raster ---------------------------------------- */

static double secs(const material *m, const char *key)
{
    return json_real_value(json_object_get(json_object_get(m->info, "seconds"), key));
}

/* Two passes over the stream's own arrays, on the pool in the stream's
 * chunks (hf_chunking), each a part of what the stream does: "read" loads
 * every byte the stream reads (the RGB values, texel indices and weights)
 * and folds them with XOR, the rate this layout allows on these threads;
 * "logs" maps the 3n values to log space in blocks of HF_BLOCK as the
 * stream does (vmath_log_map3_f32), and scatters nothing.  The stream costs at
 * least the larger of the two, and about their sum where they do not
 * overlap. */
typedef struct part_pass {
    const float *rgb;
    const hf_design *d;
    const hf_map *map;
    int chunk, n, logs;
    uint64_t sink[64]; /* per chunk: what the pass folded, so it is not optimized away */
} part_pass;

enum { PART_BLOCK = 256 };

static void part_run(void *ctx, int c)
{
    part_pass *w = ctx;
    int i0 = c * w->chunk, i1 = i0 + w->chunk < w->n ? i0 + w->chunk : w->n;
    uint64_t acc = 0;
    if (!w->logs) {
        uint32_t a = 0;
        for (size_t j = 3 * (size_t)i0; j < 3 * (size_t)i1; j++) {
            uint32_t r, k;
            uint64_t t;
            memcpy(&r, w->rgb + j, sizeof r);
            memcpy(&k, w->d->k0 + j, sizeof k);
            memcpy(&t, w->d->t + j, sizeof t);
            a ^= r ^ k;
            acc ^= t;
        }
        acc ^= a;
    } else {
        double buf[3 * PART_BLOCK], off[3];
        long cl[3] = {0, 0, 0};
        for (int c3 = 0; c3 < 3; c3++)
            off[c3] = w->map->kind == HF_MAP_LOG ? 0.0 : w->map->a;
        for (int b0 = i0; b0 < i1; b0 += PART_BLOCK) {
            int m = 3 * (i1 - b0 < PART_BLOCK ? i1 - b0 : PART_BLOCK);
            vmath_log_map3_f32(w->rgb + 3 * (size_t)b0, buf, (size_t)m, off, 1.0, w->map->eps,
                               cl);
            acc += (uint64_t)(buf[0] * 1e6);
        }
    }
    w->sink[c % 64] ^= acc;
}

static double part_time(part_pass *w, int logs)
{
    int nchunks = (w->n + w->chunk - 1) / w->chunk;
    double t0 = now();
    w->logs = logs;
    par_run(nchunks, part_run, w);
    return now() - t0;
}

/* The fast factorization of one RGB painting of the 128x128 x 12-view
 * sphere (98,434 samples), the warm fit of a painter's stroke, against the
 * bytes it must read at the bandwidth measured in the same run. */
static void warm(FILE *md, int quick)
{
    static const int res[] = {16, 64, 128};
    stroke_row strokes[sizeof res / sizeof res[0]];
    int reps = quick ? 51 : 201;
    brdf b;
    setup s;
    double bw1 = triad_bandwidth(), bwp = triad_bandwidth_pool();
    int wide;

    brdf_parse("ct0.2", &b, NULL);
    setup_make(&s, 128, 128, SCENE_VIEWS_ICO12, 0, &b, 0.0);
    printf("\n== The warm fit at the full raster: 128x128 x 12 views, one RGB painting (ct0.2)\n");
    printf("threads %d (GLINT_THREADS), vector math %s; memory bandwidth (triad) one thread "
           "%.1f GB/s, %d threads %.1f GB/s\n",
           par_threads(), vmath_impl(), bw1 / 1e9, par_threads(), bwp / 1e9);
    log_rates();
    vmath_limit("avx512");
    wide = strstr(vmath_impl(), "avx512") != NULL;
    vmath_limit(NULL);
    wide = wide && strstr(vmath_impl(), "avx512") != NULL; /* not capped by GLINT_VMATH */
    printf("%-4s %-6s | %-9s %-9s %-9s %-9s | %-9s %-9s %-9s | %-8s %-8s %-7s | %-7s %-8s\n",
           "res", "N", "stream", "M t", "factor.", "f32", "gather", "diag", "fit_run", "MB read",
           "bound", "ratio", "diag N", "RMS");
    printf("%-4s %-6s | %-9s %-9s %-9s %-9s | %-9s %-9s %-9s | %-8s %-8s %-7s | %-7s %-8s\n", "",
           "", "ms", "ms", "ms", "ms", "ms", "ms", "ms", "", "ms", "", "", "painted");
    fprintf(md, "\nThe warm fit at the full raster (128x128 x 12 views, one RGB painting): "
                "threads %d, %s, triad %.1f GB/s (one thread) and %.1f GB/s (%d threads)\n\n",
            par_threads(), vmath_impl(), bw1 / 1e9, bwp / 1e9, par_threads());
    fprintf(md, "| res | samples | stream (ms) | M t (ms) | factorization, double (ms) | "
                "factorization, single (ms) | gather (ms) | diagnostics (ms) | fit_run (ms) | "
                "MB read | bound (ms) | factorization / bound | read pass (ms) | logs pass (ms) | "
                "diagnostic samples | RMS painted |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (unsigned r = 0; r < sizeof res / sizeof res[0]; r++) {
        double st[201], mt[201], fa[201], f32[201], dg[201], run[201], ga[201], fa2[201],
            rd[201], lg[201], bytes, bound, rms = 0.0;
        part_pass pw;
        float *grgb;
        long dn = 0;
        fit_params p;
        fit_prep fp, fp32;
        glint_err e;
        fit_params_default(&p);
        p.res = res[r];
        if (fit_prepare(&fp, &s.sc, s.g, NULL, &p, NULL, &e))
            die("prepare", &e);
        p.prec = HF_F32;
        if (fit_prepare(&fp32, &s.sc, s.g, NULL, &p, NULL, &e))
            die("prepare f32", &e);
        if (!(grgb = malloc((size_t)3 * fp.s.n * sizeof *grgb)))
            die("out of memory", NULL);
        memset(&pw, 0, sizeof pw);
        pw.rgb = grgb;
        pw.d = &fp.d;
        pw.map = &p.map;
        pw.n = fp.s.n;
        {
            int nch;
            hf_chunking(fp.s.n, &pw.chunk, &nch);
        }
        for (int k = 0; k < reps; k++) {
            material m;
            double t0 = now();
            if (samples_gather(&fp.s, s.paint, grgb, &e))
                die("gather", &e);
            ga[k] = now() - t0;
            rd[k] = part_time(&pw, 0);
            lg[k] = part_time(&pw, 1);
            t0 = now();
            if (fit_run(&fp, s.paint, NULL, &m, &e))
                die("fit", &e);
            run[k] = now() - t0;
            st[k] = secs(&m, "stream");
            mt[k] = secs(&m, "apply_operator");
            fa[k] = secs(&m, "factorization");
            dg[k] = secs(&m, "diagnostics");
            rms = json_real_value(json_object_get(json_object_get(m.info, "errors"),
                                                  "rms_painted"));
            dn = (long)json_integer_value(json_object_get(json_object_get(m.info, "errors"),
                                                          "diagnostic_samples"));
            material_free(&m);
            if (fit_run(&fp32, s.paint, NULL, &m, &e))
                die("fit f32", &e);
            f32[k] = secs(&m, "factorization");
            material_free(&m);
            if (wide) { /* the same fit with the AVX2 loops, interleaved */
                vmath_limit("avx2");
                if (fit_run(&fp, s.paint, NULL, &m, &e))
                    die("fit avx2", &e);
                fa2[k] = secs(&m, "factorization");
                material_free(&m);
                vmath_limit(NULL);
            }
        }
        /* the bytes the factorization reads: RGB (float), texel indices
         * (int32) and weights (double) per sample and factor, the operator */
        bytes = (double)fp.s.n * (3 * 4 + 3 * 4 + 3 * 8) + (double)hf_op_bytes(&fp.op, NULL);
        bound = bytes / bwp;
        {
            double ms = median(st, reps), mm = median(mt, reps), mf = median(fa, reps);
            double m32 = median(f32, reps), md_ = median(dg, reps), mr = median(run, reps);
            double mg = median(ga, reps), mrd = median(rd, reps), mlg = median(lg, reps);
            printf("%-4d %-6d | %-9.3f %-9.3f %-9.3f %-9.3f | %-9.3f %-9.3f %-9.3f | %-8.2f %-8.3f "
                   "%-7.2f | %-7ld %-8.4f\n",
                   res[r], fp.s.n, 1e3 * ms, 1e3 * mm, 1e3 * mf, 1e3 * m32, 1e3 * mg, 1e3 * md_,
                   1e3 * mr, bytes / 1e6, 1e3 * bound, mf / bound, dn, rms);
            printf("     (parts of the stream on the pool: read pass %.3f ms, %.2f x bound; "
                   "logs pass %.3f ms, %.2f x bound; read + logs %.3f ms; the f32 "
                   "factorization reads the same bytes: %.2f x bound)\n",
                   1e3 * mrd, mrd / bound, 1e3 * mlg, mlg / bound, 1e3 * (mrd + mlg),
                   m32 / bound);
            fprintf(md, "| %d | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f | %.2f | %.3f | "
                        "%.2f | %.3f | %.3f | %ld | %.4f |\n",
                    res[r], fp.s.n, 1e3 * ms, 1e3 * mm, 1e3 * mf, 1e3 * m32, 1e3 * mg, 1e3 * md_,
                    1e3 * mr, bytes / 1e6, 1e3 * bound, mf / bound, 1e3 * mrd, 1e3 * mlg, dn,
                    rms);
            if (wide)
                printf("     (the same fits with the AVX2 loops, interleaved with them: "
                       "factorization %.3f ms)\n",
                       1e3 * median(fa2, reps));
        }
        {
            stroke_row *w = &strokes[r];
            stroke_fits(&fp, s.paint, reps, w);
            stroke_print(w, bwp);
        }
        free(grgb);
        fit_prep_free(&fp);
        fit_prep_free(&fp32);
    }
    stroke_table(md, strokes, (int)(sizeof res / sizeof res[0]), bwp);
    printf("(stream: the pass over the samples (mapping, logs, A^T f); M t: the operator; "
           "factorization: both + offsets + gauge;\n gather: the samples' values read from the "
           "painting (samples_gather, apart); diag: the error diagnostics; fit_run: also "
           "reading the painting; bound: MB read / the %d-thread bandwidth;\n read pass: the "
           "stream's bytes loaded and folded, nothing computed; logs pass: its logs, nothing "
           "read but the values, nothing scattered)\n",
           par_threads());
    free_setup(&s);
}

/* ---- Part 2: speed-accuracy sweep -------------------------------------------------- */

typedef struct row {
    int raster, res;
    char reg[32];
    const char *prec;
    int k, n;
    double pre_s, fact_s, run_s, bytes, rms_novel, rms_paint;
} row;

static double novel_rms(const material *m, const setup *nv)
{
    double rms;
    glint_err e;
    if (fit_error_views(m, nv->g, nv->sc.views, nv->sc.nviews, nv->paint, &rms, NULL, NULL, &e))
        die("error", &e);
    return rms;
}

static double info_seconds(const material *m, const char *key)
{
    return json_real_value(json_object_get(json_object_get(m->info, "seconds"), key));
}

/* One configuration on a prepared base (shares samples, design, decomposition). */
static void run_config(row *rw, const fit_prep *base, const setup *train, const setup *novel,
                       const char *regspec, hf_precision prec, double pre_base, int quick)
{
    hf_op op;
    hf_reg reg;
    fit_prep fp = *base;
    material m;
    glint_err e;
    double fa[15], fr[15], t0, tb;
    int reps = quick ? 5 : 15;

    hf_reg_parse(regspec, &reg, NULL);
    t0 = now();
    if (hf_op_build(&base->dc, &reg, prec, &op, &e))
        die("operator", &e);
    tb = now() - t0;
    fp.op = op;
    fp.params.reg = reg;
    fp.params.prec = prec;
    for (int k = 0; k < reps; k++) {
        t0 = now();
        if (fit_run(&fp, train->paint, NULL, &m, &e))
            die("fit", &e);
        fr[k] = now() - t0;
        fa[k] = info_seconds(&m, "factorization");
        if (k + 1 < reps)
            material_free(&m);
    }
    rw->raster = train->sc.width;
    rw->res = base->params.res;
    snprintf(rw->reg, sizeof rw->reg, "%s", regspec);
    rw->prec = prec == HF_F32 ? "single" : "double";
    rw->k = op.k;
    rw->n = base->s.n;
    rw->pre_s = pre_base + tb;
    rw->fact_s = median(fa, reps);
    rw->run_s = median(fr, reps);
    rw->bytes = (double)hf_op_bytes(&op, &base->d);
    rw->rms_novel = novel_rms(&m, novel);
    rw->rms_paint = json_real_value(json_object_get(json_object_get(m.info, "errors"), "rms_painted"));
    printf("%-6d %-4d %-17s %-6s %-5d %-6d | %-8.4f %-8.3f %-8.3f %-9.0f | %-8.4f %-8.4f\n",
           rw->raster, rw->res, rw->reg, rw->prec, rw->k, rw->n, rw->pre_s, 1e3 * rw->fact_s,
           1e3 * rw->run_s, rw->bytes / 1024, rw->rms_novel, rw->rms_paint);
    material_free(&m);
    hf_op_free(&op);
}

static int sweep(FILE *md, const char *outdir, int quick, const char *spec)
{
    static const int res_full[] = {16, 32, 64, 128, 256};
    static const int res_quick[] = {16, 64, 128};
    static const int rasters_full[] = {32, 64, 128, 256};
    static const int rasters_quick[] = {64, 128};
    static const char *regs[] = {"trunc:full", "trunc:50%", "trunc:20%", "trunc:10%",
                                 "tikhonov:rel1e-3", "tikhonov:rel1e-2", "tikhonov:rel1e-1",
                                 "linear:full", "linear:50%"};
    const int *res = quick ? res_quick : res_full;
    const int *rasters = quick ? rasters_quick : rasters_full;
    int nres = quick ? 3 : 5, nregs = quick ? 5 : 9, nrast = quick ? 2 : 4, nrows = 0;
    row rows[256];
    brdf b;
    setup novel;
    char csv[4096], png[4096], gp[4096];
    FILE *f;

    brdf_parse(spec, &b, NULL);
    printf("\n== Speed-accuracy sweep: %s; error on 20 novel views at 128x128 (light angles between the painted ones)\n",
           spec);
    printf("%-6s %-4s %-17s %-6s %-5s %-6s | %-8s %-8s %-8s %-9s | %-8s %-8s\n", "raster",
           "res", "regularization", "prec", "K", "N", "pre s", "fact ms", "run ms", "op KiB",
           "RMS new", "RMS paint");
    for (int ai = 0; ai < nrast; ai++) {
        setup train;
        setup_make(&train, rasters[ai], rasters[ai], SCENE_VIEWS_ICO12, 0, &b, 0.0);
        if (ai == 0)
            setup_make(&novel, 128, 128, SCENE_VIEWS_ICO20, 1, &b, 0.0);
        /* the novel views share the training scale (max over painted views = 1) */
        for (int v = 0; v < novel.sc.nviews; v++)
            img_free(&novel.paint[v]);
        {
            glint_err e;
            if (paint_views(&b, novel.g, novel.sc.views, novel.sc.nviews, train.scale,
                            novel.paint, NULL, &e))
                die("paint novel", &e);
        }
        for (int ri = 0; ri < nres; ri++) {
            fit_params p;
            fit_prep base;
            glint_err e;
            double t0, pre_base;
            fit_params_default(&p);
            p.res = res[ri];
            t0 = now();
            if (fit_prepare(&base, &train.sc, train.g, NULL, &p, NULL, &e))
                die("prepare", &e);
            pre_base = now() - t0 - base.t_samples - base.t_op;
            for (int gi = 0; gi < nregs; gi++) {
                for (int pi = 0; pi < 2; pi++) {
                    /* the full grid at the default raster; elsewhere the default only */
                    if (rasters[ai] != 128 && (gi > 0 || pi > 0))
                        continue;
                    run_config(&rows[nrows++], &base, &train, &novel, regs[gi],
                               pi ? HF_F32 : HF_F64, pre_base, quick);
                }
            }
            fit_prep_free(&base);
        }
        free_setup(&train);
    }
    free_setup(&novel);
    fprintf(md, "\n%s: error on 20 novel views at 128x128\n\n", spec);
    fprintf(md, "| raster | res | regularization | precision | K | samples | preinversion (s) | factorization (ms) | fit_run (ms) | operator (KiB) | RMS novel | RMS painted |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < nrows; i++)
        fprintf(md, "| %d | %d | %s | %s | %d | %d | %.4f | %.3f | %.3f | %.0f | %.4f | %.4f |\n",
                rows[i].raster, rows[i].res, rows[i].reg, rows[i].prec, rows[i].k, rows[i].n,
                rows[i].pre_s, 1e3 * rows[i].fact_s, 1e3 * rows[i].run_s, rows[i].bytes / 1024,
                rows[i].rms_novel, rows[i].rms_paint);
    snprintf(csv, sizeof csv, "%s/sweep_%s.csv", outdir, spec);
    f = fopen(csv, "w");
    if (!f)
        return -1;
    fprintf(f, "raster,res,regularization,precision,K,samples,preinversion_s,factorization_s,fit_run_s,operator_bytes,rms_novel,rms_painted\n");
    /* default-regularization rows first, so the plot draws them as lines */
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < nrows; i++) {
            int base_row = strcmp(rows[i].reg, "trunc:full") == 0 &&
                           strcmp(rows[i].prec, "double") == 0;
            if (base_row != (pass == 0))
                continue;
            fprintf(f, "%d,%d,%s,%s,%d,%d,%.6f,%.6f,%.6f,%.0f,%.6f,%.6f\n", rows[i].raster,
                    rows[i].res, rows[i].reg, rows[i].prec, rows[i].k, rows[i].n, rows[i].pre_s,
                    rows[i].fact_s, rows[i].run_s, rows[i].bytes, rows[i].rms_novel,
                    rows[i].rms_paint);
        }
    fclose(f);
    snprintf(png, sizeof png, "%s/sweep_%s.png", outdir, spec);
    snprintf(gp, sizeof gp, "%s/sweep_%s.gp", outdir, spec);
    f = fopen(gp, "w");
    if (!f)
        return -1;
    fprintf(f,
            "set terminal pngcairo size 1300,560 font ',10'\nset output '%s'\n"
            "set datafile separator ','\nset logscale xy\nset grid\nset key bottom left\n"
            "set ylabel 'RMS error, 20 novel views (radiance on [0,1])'\n"
            "set multiplot layout 1,2 title 'glint fast homomorphic factorization: speed vs accuracy (%s)'\n"
            "full(r) = (strcol(4) eq 'double' && strcol(3) eq 'trunc:full' && $1 == r)\n"
            "set xlabel 'fast factorization of one RGB painting (ms)'\n"
            "plot for [r in '32 64 128 256'] '%s' every ::1 using ($8*1000):(full(r+0) ? $11 : 1/0) with linespoints pt 7 title sprintf('raster %%s^2, trunc:full, double', r), \\\n"
            " '' every ::1 using ($8*1000):(full($1) ? $11 : 1/0):(sprintf('R%%d', $2)) with labels offset 1.6,0.6 font ',8' notitle, \\\n"
            " '' every ::1 using ($8*1000):(strcol(4) eq 'single' ? $11 : 1/0) with points pt 6 ps 1.4 lc rgb 'black' title 'single precision', \\\n"
            " '' every ::1 using ($8*1000):(strstrt(strcol(3),'trunc:') > 0 && strcol(3) ne 'trunc:full' ? $11 : 1/0) with points pt 5 lc rgb '#2ca02c' title 'truncated rank', \\\n"
            " '' every ::1 using ($8*1000):(strstrt(strcol(3),'tikhonov') > 0 ? $11 : 1/0) with points pt 9 lc rgb '#d62728' title 'Tikhonov', \\\n"
            " '' every ::1 using ($8*1000):(strstrt(strcol(3),'linear') > 0 ? $11 : 1/0) with points pt 11 lc rgb '#9467bd' title 'linear damping'\n"
            "set xlabel 'preinversion (s), computed once per scene and parameters, then cached'\n"
            "plot for [r in '32 64 128 256'] '%s' every ::1 using 7:(full(r+0) ? $11 : 1/0) with linespoints pt 7 title sprintf('raster %%s^2', r), \\\n"
            " '' every ::1 using 7:(full($1) ? $11 : 1/0):(sprintf('R%%d', $2)) with labels offset 1.6,0.6 font ',8' notitle\n"
            "unset multiplot\n",
            png, spec, csv, csv);
    fclose(f);
    {
        char cmd[8300];
        snprintf(cmd, sizeof cmd, "gnuplot '%s' 2>&1", gp);
        if (system("command -v gnuplot >/dev/null 2>&1") == 0 && system(cmd) == 0)
            printf("plot: %s\n", png);
        else
            printf("plot: gnuplot not available or failed; data in %s, script %s\n", csv, gp);
    }
    printf("table: %s\n", csv);
    return 0;
}

int main(int argc, char **argv)
{
    int quick = 0, parts = 7;
    const char *out = "bench-out";
    char mdpath[4096];
    FILE *md;
    glint_err e;

    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--quick") == 0)
            quick = 1;
        else if (strcmp(argv[i], "--out") == 0 && i + 1 < argc)
            out = argv[++i];
        else if (strcmp(argv[i], "--warm") == 0)
            parts = 1;
        else {
            fprintf(stderr, "usage: bench_hf [--quick] [--warm] [--out DIR]\n"
                            "  --warm: only the warm fit at the full raster\n");
            return 1;
        }
    }
    if (fsio_mkdirs(out, &e))
        die("output directory", &e);
    snprintf(mdpath, sizeof mdpath, "%s/bench_hf.md", out);
    md = fopen(mdpath, "w");
    if (!md)
        die("cannot write the markdown table", NULL);
    warm(md, quick);
    if (parts & 2) {
        table1(md, quick);
        sweep(md, out, quick, "ct0.2");
        if (!quick)
            sweep(md, out, quick, "ct0.5");
    }
    fclose(md);
    printf("\nmarkdown tables: %s\n", mdpath);
    return 0;
}
