/* Unit tests of the fast homomorphic factorization numerics (core/hf*) at
 * their limits: extreme paintings, grazing angles, non-finite input,
 * extreme lambdas and range errors (every output finite), and barely
 * reached directions and the range of the log-factors (the data-gain cut,
 * damping, the SUB offset, the cut report through the cache). */
#include <float.h>
#include <unistd.h>

#include "check.h"
#include "hf.h"
#include "hf_fixture.h"
#include "hf_int.h"
#include "pcache.h"
#include "samples.h"

/* ---- extremes: every output finite ------------------------------------------------------ */

static int all_finite_fit(fitcase *fc, const char *map_spec, hf_model model, const float *rgb,
                          hf_fit_stats *st)
{
    hf_map map;
    hf_factors fac;
    glint_err e;
    int rc, N = fc->d.n;
    hf_map_parse(map_spec, &map, NULL);
    rc = hf_fit(&fc->d, &fc->op, &map, model, rgb, &fac, st, &e);
    if (rc) {
        printf("  fit failed: %s\n", e.msg);
        return 0;
    }
    float *rec = malloc((size_t)3 * N * sizeof *rec);
    hf_factors_eval_design(&fac, &fc->d, rec);
    int ok = 1;
    for (int k = 0; k < 9 * fac.res; k++) ok &= isfinite(fac.logf[k]);
    for (int i = 0; i < 3 * N; i++) ok &= isfinite(rec[i]) && rec[i] >= 0;
    ok &= isfinite(st->rms) && isfinite(st->log_residual);
    free(rec);
    hf_factors_free(&fac);
    return ok;
}

TEST(extreme_paintings)
{
    const samples *s = sphere_samples();
    fitcase fc;
    hf_fit_stats st;
    int N = s->n;
    float *rgb = calloc((size_t)3 * N, sizeof *rgb);
    const char *maps[] = {"log", "add", "sub"};
    ASSERT_OK(fitcase_make(&fc, 32, 0.1, "trunc:full", HF_F64));
    for (int m = 0; m < 3; m++) {
        /* all black */
        memset(rgb, 0, (size_t)3 * N * sizeof *rgb);
        ASSERT(all_finite_fit(&fc, maps[m], HF_MODEL_RADIANCE, rgb, &st));
        ASSERT_LE(st.max_abs, 1.01e-3); /* at most eps, the log floor */
        if (m == 0) ASSERT_EQ(st.clamped[0], N);
        /* a single painted pixel */
        rgb[3 * (N / 2)] = rgb[3 * (N / 2) + 1] = rgb[3 * (N / 2) + 2] = 1.0f;
        ASSERT(all_finite_fit(&fc, maps[m], HF_MODEL_RADIANCE, rgb, &st));
        /* saturated everywhere */
        for (int i = 0; i < 3 * N; i++) rgb[i] = 1.0f;
        ASSERT(all_finite_fit(&fc, maps[m], HF_MODEL_RADIANCE, rgb, &st));
        if (m != 2) ASSERT_LE(st.rms, 1e-6); /* a constant is representable exactly */
        /* HDR: 1e3 highlights on a dim base */
        for (int i = 0; i < N; i++)
            for (int c = 0; c < 3; c++) rgb[3 * i + c] = (i % 50 == 0) ? 1e3f : 0.05f;
        ASSERT(all_finite_fit(&fc, maps[m], HF_MODEL_RADIANCE, rgb, &st));
        ASSERT(all_finite_fit(&fc, maps[m], HF_MODEL_BRDF, rgb, &st));
        /* negative paint (an HDR file may hold it) is floored, not NaN */
        for (int i = 0; i < 3 * N; i++) rgb[i] = (i % 7 == 0) ? -0.5f : 0.3f;
        ASSERT(all_finite_fit(&fc, maps[m], HF_MODEL_RADIANCE, rgb, &st));
    }
    fitcase_free(&fc);
    free(rgb);
}

/* Grazing light and view: make a tenth of the samples nearly tangent
 * (cos_i and cos_o down to 1e-9): projections reach 1, the brdf model divides
 * by a floored cosine, and everything stays finite. */
TEST(grazing_angles)
{
    const samples *s0 = sphere_samples();
    samples s = *s0;
    hf_design d;
    hf_decomp dc;
    hf_op op;
    hf_reg reg;
    hf_map map;
    hf_factors fac;
    hf_fit_stats st;
    glint_err e;
    float *nrm = malloc((size_t)3 * s.n * sizeof *nrm), *wi = malloc((size_t)3 * s.n * sizeof *wi);
    double *ci = malloc((size_t)s.n * sizeof *ci);
    float *rgb = paint_blinn(s0);
    memcpy(nrm, s0->nrm, (size_t)3 * s.n * sizeof *nrm);
    memcpy(wi, s0->wi, (size_t)3 * s.n * sizeof *wi);
    memcpy(ci, s0->cos_i, (size_t)s.n * sizeof *ci);
    for (int i = 0; i < s.n; i += 10) {
        /* wi = tangent direction tilted up by 1e-9 */
        v3 n = v3_loadf(nrm + 3 * i), a = fabs(n.x) < 0.9 ? v3_make(1, 0, 0) : v3_make(0, 1, 0);
        v3 t = v3_normalize(v3_cross(n, a));
        v3 w = v3_normalize(v3_add(t, v3_scale(n, 1e-9)));
        v3_storef(w, wi + 3 * i);
        ci[i] = 1e-9;
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = 0.5f; /* paint that disagrees */
    }
    s.nrm = nrm;
    s.wi = wi;
    s.cos_i = ci;
    hf_reg_parse("trunc:full", &reg, NULL);
    ASSERT_OK(hf_design_build(&s, 32, &d, &e));
    ASSERT_OK(hf_decomp_build(&d, 0.1, HF_ROUTE_EIG, 0, &dc, &e));
    ASSERT_OK(hf_op_build(&dc, &reg, HF_F64, &op, &e));
    for (int model = 0; model < 2; model++) {
        hf_map_default(&map, HF_MAP_ADD);
        ASSERT_OK(hf_fit(&d, &op, &map, (hf_model)model, rgb, &fac, &st, &e));
        for (int k = 0; k < 9 * 32; k++)
            ASSERT_FINITE(fac.logf[k]);
        ASSERT_FINITE(st.rms);
        hf_factors_free(&fac);
    }
    /* evaluation exactly at the horizon and exactly tangent */
    hf_map_default(&map, HF_MAP_LOG);
    ASSERT_OK(hf_fit(&d, &op, &map, HF_MODEL_BRDF, rgb, &fac, &st, &e));
    double n[3] = {0, 0, 1}, w1[3] = {1, 0, 1e-12}, w2[3] = {0, 1, 0}, out[3];
    hf_factors_eval(&fac, n, w1, w1, out);
    ASSERT_FINITE(out[0]);
    hf_factors_eval(&fac, n, w2, w1, out);
    ASSERT_NEAR(out[0], 0.0, 0);
    hf_factors_free(&fac);
    hf_op_free(&op);
    hf_decomp_free(&dc);
    hf_design_free(&d);
    free(nrm);
    free(wi);
    free(ci);
    free(rgb);
}

TEST(nonfinite_input_is_an_error)
{
    const samples *s = sphere_samples();
    fitcase fc;
    hf_map map;
    hf_factors fac;
    glint_err e;
    float *rgb = calloc((size_t)3 * s->n, sizeof *rgb);
    ASSERT_OK(fitcase_make(&fc, 16, 0.1, "trunc:full", HF_F64));
    hf_map_default(&map, HF_MAP_ADD);
    rgb[3 * 10 + 1] = NAN;
    ASSERT_EQ(hf_fit(&fc.d, &fc.op, &map, HF_MODEL_RADIANCE, rgb, &fac, NULL, &e), GLINT_ENONFINITE);
    ASSERT(strstr(e.msg, "sample 10 channel 1"));
    rgb[3 * 10 + 1] = INFINITY;
    ASSERT_EQ(hf_fit(&fc.d, &fc.op, &map, HF_MODEL_RADIANCE, rgb, &fac, NULL, &e), GLINT_ENONFINITE);
    ASSERT(fac.logf == NULL);
    fitcase_free(&fc);
    free(rgb);
}

TEST(lambda_extremes)
{
    const samples *s = sphere_samples();
    float *rgb = paint_blinn(s);
    hf_fit_stats st;
    fitcase fc;
    /* lambda = 0 at a resolution finer than the samples reach: rank
     * deficiency is reported, the minimum-norm fit stays finite. */
    ASSERT_OK(fitcase_make(&fc, 256, 0.0, "trunc:full", HF_F64));
    printf("  lambda 0, R 256: rank %d of %d (gauge %d, null %d, barely reached %d)\n",
           fc.dc.rank, 3 * 256, fc.dc.gauge_dims, fc.dc.null_dims, fc.dc.weak_dims);
    ASSERT_LT(fc.dc.rank, 3 * 256 - 2);
    ASSERT_EQ(fc.dc.gauge_dims + fc.dc.null_dims + fc.dc.weak_dims + fc.dc.rank, 3 * 256);
    ASSERT(all_finite_fit(&fc, "add", HF_MODEL_RADIANCE, rgb, &st));
    fitcase_free(&fc);
    /* huge lambda: factors forced towards straight lines in log space */
    ASSERT_OK(fitcase_make(&fc, 32, 1e6, "trunc:full", HF_F64));
    ASSERT_EQ(fc.dc.rank, 3 * 32 - 2);
    ASSERT(all_finite_fit(&fc, "add", HF_MODEL_RADIANCE, rgb, &st));
    fitcase_free(&fc);
    /* tiny and huge Tikhonov */
    ASSERT_OK(fitcase_make(&fc, 32, 0.1, "tikhonov:1e-12", HF_F64));
    ASSERT(all_finite_fit(&fc, "add", HF_MODEL_RADIANCE, rgb, &st));
    fitcase_free(&fc);
    ASSERT_OK(fitcase_make(&fc, 32, 0.1, "tikhonov:1e9", HF_F64));
    ASSERT(all_finite_fit(&fc, "add", HF_MODEL_RADIANCE, rgb, &st));
    fitcase_free(&fc);
    free(rgb);
}

TEST(range_errors)
{
    const samples *s = sphere_samples();
    hf_design d;
    hf_decomp dc;
    glint_err e;
    ASSERT_EQ(hf_design_build(s, 2, &d, &e), GLINT_ERANGE);
    ASSERT_EQ(hf_design_build(s, 100000, &d, &e), GLINT_ERANGE);
    ASSERT_OK(hf_design_build(s, 16, &d, &e));
    ASSERT_EQ(hf_decomp_build(&d, -1.0, HF_ROUTE_EIG, 0, &dc, &e), GLINT_ERANGE);
    ASSERT_EQ(hf_decomp_build(&d, NAN, HF_ROUTE_EIG, 0, &dc, &e), GLINT_ERANGE);
    ASSERT_EQ(hf_decomp_build(&d, 0.1, HF_ROUTE_EIG, 2.0, &dc, &e), GLINT_ERANGE);
    hf_design_free(&d);
}

/* ---- barely reached directions and the range of the log-factors -------------------------- */

/* A hand-made design at R = 4: 48 samples reach every texel of p and q and
 * texels 0-2 of r with ordinary hat weights; texel 3 of r is reached by
 * sample 0 alone, with weight w.  Painted 0.5 everywhere except sample 0,
 * painted 0.5 exp(misfit): no product of factors fits it unless r3 takes
 * misfit / w. */
#define DZ_N 48
#define DZ_R 4

static int designed_make(hf_design *d, double w)
{
    memset(d, 0, sizeof *d);
    d->n = DZ_N;
    d->res = DZ_R;
    d->k0 = malloc((size_t)3 * DZ_N * sizeof *d->k0);
    d->t = malloc((size_t)3 * DZ_N * sizeof *d->t);
    d->cos_i = malloc((size_t)DZ_N * sizeof *d->cos_i);
    if (!d->k0 || !d->t || !d->cos_i)
        return -1;
    for (int i = 0; i < DZ_N; i++) {
        d->k0[3 * i] = i % 3;
        d->t[3 * i] = ((i / 3) % 4) / 4.0;
        d->k0[3 * i + 1] = (i / 4) % 3;
        d->t[3 * i + 1] = (i % 5) / 5.0;
        d->k0[3 * i + 2] = i % 3;
        d->t[3 * i + 2] = i % 3 == 2 ? 0.0 : (i % 7) / 7.0; /* never texel 3 */
        d->cos_i[i] = 1.0;
    }
    d->k0[2] = 2; /* sample 0: texel 3 of r with weight w */
    d->t[2] = w;
    return 0;
}

static void designed_paint(float *rgb, double misfit)
{
    for (int i = 0; i < 3 * DZ_N; i++)
        rgb[i] = 0.5f;
    for (int c = 0; c < 3; c++)
        rgb[c] = (float)(0.5 * exp(misfit));
}

/* Every log-factor within HF_LOG_FACTOR_MAX and every factor, and the
 * reconstruction, a finite float. */
static int factors_in_range(const hf_factors *fac, const hf_design *d)
{
    float rec[3 * DZ_N];
    for (int k = 0; k < 9 * fac->res; k++)
        if (!(fabs(fac->logf[k]) <= HF_LOG_FACTOR_MAX) || !isfinite((float)exp(fac->logf[k])))
            return 0;
    hf_factors_eval_design(fac, d, rec);
    for (int i = 0; i < 3 * d->n; i++)
        if (!isfinite(rec[i]))
            return 0;
    return 1;
}

TEST(barely_reached_direction_is_cut)
{
    hf_design d;
    hf_decomp dc;
    hf_op op;
    hf_reg reg;
    hf_map map;
    hf_factors fac;
    hf_fit_stats st;
    glint_err e;
    float rgb[3 * DZ_N];
    const hf_route routes[] = {HF_ROUTE_EIG, HF_ROUTE_SVD};

    hf_reg_parse("trunc:full", &reg, NULL);
    hf_map_default(&map, HF_MAP_LOG);
    designed_paint(rgb, 1.0);
    /* w = 0.5: an ordinary sample; everything kept */
    ASSERT_OK(designed_make(&d, 0.5));
    ASSERT_OK(hf_decomp_build(&d, 0.0, HF_ROUTE_EIG, 0, &dc, &e));
    printf("  w 0.5: rank %d, null %d, weak %d, gain kept %.3g\n", dc.rank, dc.null_dims,
           dc.weak_dims, dc.gain_kept);
    ASSERT_EQ(dc.rank, 3 * DZ_R - 2);
    ASSERT_EQ(dc.null_dims + dc.weak_dims, 0);
    ASSERT_LE(dc.gain_kept, dc.gain_max);
    hf_decomp_free(&dc);
    hf_design_free(&d);

    /* w = 1e-3, lambda 0: kept by rcond (s ~ 1e-3 > 1e-6 s_max) but reached
     * by a thousandth of a sample, gain ~ 1e3: cut as barely reached, on
     * both routes.  Kept, it would put log r3 ~ 1000. */
    ASSERT_OK(designed_make(&d, 1e-3));
    for (int ri = 0; ri < 2; ri++) {
        ASSERT_OK(hf_decomp_build(&d, 0.0, routes[ri], 0, &dc, &e));
        printf("  w 1e-3 route %d: rank %d, null %d, weak %d (s %.3g), gain kept %.3g\n",
               ri, dc.rank, dc.null_dims, dc.weak_dims, dc.s_weak, dc.gain_kept);
        ASSERT_EQ(dc.gauge_dims + dc.null_dims + dc.weak_dims + dc.rank, dc.n);
        ASSERT_EQ(dc.null_dims, 0);
        ASSERT_EQ(dc.weak_dims, 1);
        ASSERT_NEAR(dc.gain_max, HF_GAIN_MAX, 0);
        ASSERT(dc.s_weak > 1e-4 && dc.s_weak < 1e-2);
        ASSERT_LE(dc.gain_kept, dc.gain_max);
        ASSERT_LT(dc.s_weak, dc.s[dc.rank - 1]);
        ASSERT_OK(hf_op_build(&dc, &reg, HF_F64, &op, &e));
        ASSERT_OK(hf_fit(&d, &op, &map, HF_MODEL_RADIANCE, rgb, &fac, &st, &e));
        printf("    max |log| %.3g, damping %g\n", st.log_max, st.damping);
        ASSERT(factors_in_range(&fac, &d));
        ASSERT_LE(st.log_max, 3.0); /* the data's own range, not 1/w */
        ASSERT_NEAR(st.damping, 0.0, 0);
        hf_factors_free(&fac);
        hf_op_free(&op);
        hf_decomp_free(&dc);
    }
    /* lambda 0.1: the Laplacian ties r3 to r2 and r1; its gain is small and
     * it is kept */
    ASSERT_OK(hf_decomp_build(&d, 0.1, HF_ROUTE_EIG, 0, &dc, &e));
    ASSERT_EQ(dc.rank, 3 * DZ_R - 2);
    ASSERT_EQ(dc.weak_dims, 0);
    ASSERT_LE(dc.gain_kept, 2.0);
    hf_decomp_free(&dc);
    hf_design_free(&d);

    /* w = 1e-9: the default rcond already calls it null.  A caller's tiny
     * rcond is honoured as given (the direction is no longer null), and the
     * data gain still cuts it.  (The SVD route resolves s = 1e-9; on the
     * eig route it is lost in the rounding of s^2 at ~eps s_max^2.) */
    ASSERT_OK(designed_make(&d, 1e-9));
    ASSERT_OK(hf_decomp_build(&d, 0.0, HF_ROUTE_SVD, 0, &dc, &e));
    ASSERT_EQ(dc.null_dims, 1);
    ASSERT_EQ(dc.weak_dims, 0);
    ASSERT_NEAR(dc.s_null, dc.rcond * dc.s[0], 1e-15 * dc.s[0]);
    hf_decomp_free(&dc);
    ASSERT_OK(hf_decomp_build(&d, 0.0, HF_ROUTE_SVD, 1e-15, &dc, &e));
    printf("  w 1e-9, rcond 1e-15: rank %d, null %d, weak %d (s %.3g)\n", dc.rank,
           dc.null_dims, dc.weak_dims, dc.s_weak);
    ASSERT_NEAR(dc.rcond, 1e-15, 0);
    ASSERT_EQ(dc.null_dims, 0);
    ASSERT_EQ(dc.weak_dims, 1);
    ASSERT_OK(hf_op_build(&dc, &reg, HF_F64, &op, &e));
    ASSERT_OK(hf_fit(&d, &op, &map, HF_MODEL_RADIANCE, rgb, &fac, &st, &e));
    ASSERT(factors_in_range(&fac, &d));
    ASSERT_LE(st.log_max, 3.0);
    hf_factors_free(&fac);
    hf_op_free(&op);
    hf_decomp_free(&dc);
    /* a large rcond is honoured too */
    ASSERT_OK(hf_decomp_build(&d, 0.0, HF_ROUTE_EIG, 0.5, &dc, &e));
    for (int k = 0; k < dc.rank; k++)
        ASSERT_LT(0.5 * dc.s[0], dc.s[k]);
    ASSERT_EQ(dc.gauge_dims + dc.null_dims + dc.weak_dims + dc.rank, dc.n);
    ASSERT(dc.null_dims > 1);
    hf_decomp_free(&dc);
    hf_design_free(&d);
}

/* A direction the rule keeps (gain ~ 20) under a painting far from any
 * product (six log units on its only sample): the operator's solution
 * puts log r3 near 100, beyond exp's single-precision range; the fit damps
 * it back within HF_LOG_FACTOR_MAX and reports the damping. */
TEST(fit_keeps_log_factors_in_range)
{
    hf_design d;
    hf_decomp dc;
    hf_op op, opf;
    hf_reg reg;
    hf_map map;
    hf_factors fac;
    hf_fit_stats st;
    glint_err e;
    float rgb[3 * DZ_N];

    hf_reg_parse("trunc:full", &reg, NULL);
    hf_map_default(&map, HF_MAP_LOG);
    ASSERT_OK(designed_make(&d, 0.05));
    ASSERT_OK(hf_decomp_build(&d, 0.0, HF_ROUTE_EIG, 0, &dc, &e));
    ASSERT_EQ(dc.weak_dims, 0);
    ASSERT(dc.gain_kept > 10.0 && dc.gain_kept <= dc.gain_max);
    ASSERT_OK(hf_op_build(&dc, &reg, HF_F64, &op, &e));
    ASSERT_OK(hf_op_build(&dc, &reg, HF_F32, &opf, &e));
    /* within range: nothing to do */
    designed_paint(rgb, 1.0);
    ASSERT_OK(hf_fit(&d, &op, &map, HF_MODEL_RADIANCE, rgb, &fac, &st, &e));
    ASSERT_NEAR(st.damping, 0.0, 0);
    ASSERT_NEAR(st.log_max, st.log_max_undamped, 0);
    ASSERT(st.log_max > 10.0); /* misfit x gain */
    hf_factors_free(&fac);
    /* six log units: damped */
    designed_paint(rgb, 6.0);
    for (int p = 0; p < 2; p++) {
        ASSERT_OK(hf_fit(&d, p ? &opf : &op, &map, HF_MODEL_RADIANCE, rgb, &fac, &st, &e));
        printf("  %s operator: max |log| %.4g undamped, %.4g damped (alpha %.3g; s kept %.3g..%.3g)\n",
               p ? "float" : "double", st.log_max_undamped, st.log_max, st.damping, dc.s[0],
               dc.s[dc.rank - 1]);
        ASSERT(st.log_max_undamped > 88.8); /* exp() of it is no float */
        ASSERT_LE(st.log_max, HF_LOG_FACTOR_MAX);
        ASSERT(st.log_max > 0.9 * HF_LOG_FACTOR_MAX); /* no more damping than needed */
        ASSERT(st.damping > 0.0 && st.damping < dc.s[0]);
        ASSERT(factors_in_range(&fac, &d));
        ASSERT_FINITE(st.rms);
        hf_factors_free(&fac);
    }
    hf_op_free(&op);
    hf_op_free(&opf);
    hf_decomp_free(&dc);
    hf_design_free(&d);
}

/* SUB at the top of the float range: a = (1 + margin) max f would not be a
 * float; it is held at FLT_MAX so that a - pqr is one. */
TEST(sub_offset_stays_a_float)
{
    const samples *s = sphere_samples();
    fitcase fc;
    hf_map map;
    hf_factors fac;
    hf_fit_stats st;
    float *rgb = malloc((size_t)3 * s->n * sizeof *rgb);
    float *rec = malloc((size_t)3 * s->n * sizeof *rec);
    ASSERT_OK(fitcase_make(&fc, 16, 0.1, "trunc:full", HF_F64));
    for (int i = 0; i < 3 * s->n; i++)
        rgb[i] = i % 5 ? 3e38f : 1e37f;
    ASSERT_OK(hf_map_parse("sub:1", &map, NULL));
    ASSERT_OK(hf_fit(&fc.d, &fc.op, &map, HF_MODEL_RADIANCE, rgb, &fac, &st, NULL));
    for (int c = 0; c < 3; c++)
        ASSERT_LE(fac.a_used[c], FLT_MAX);
    ASSERT_LE(st.log_max, HF_LOG_FACTOR_MAX);
    hf_factors_eval_design(&fac, &fc.d, rec);
    for (int i = 0; i < 3 * s->n; i++)
        ASSERT_FINITE(rec[i]);
    hf_factors_free(&fac);
    fitcase_free(&fc);
    free(rgb);
    free(rec);
}

TEST(cut_report_survives_the_cache)
{
    hf_design d;
    hf_decomp a, b;
    glint_err e;
    char dir[64], key[33], path[256];
    snprintf(dir, sizeof dir, "/tmp/glint-hf-XXXXXX");
    ASSERT(mkdtemp(dir));
    ASSERT_OK(designed_make(&d, 1e-3));
    ASSERT_OK(hf_decomp_build(&d, 0.0, HF_ROUTE_EIG, 0, &a, &e));
    ASSERT_EQ(a.weak_dims, 1);
    pcache_key_hf("0123456789abcdef0123456789abcdef", DZ_R, 0.0, HF_ROUTE_EIG, 0, key);
    ASSERT_OK(pcache_decomp_save(dir, key, &a, &e));
    ASSERT_OK(pcache_decomp_load(dir, key, &b, &e));
    ASSERT_EQ(b.rank, a.rank);
    ASSERT_EQ(b.null_dims, a.null_dims);
    ASSERT_EQ(b.weak_dims, a.weak_dims);
    ASSERT_NEAR(b.s_null, a.s_null, 0);
    ASSERT_NEAR(b.gain_max, a.gain_max, 0);
    ASSERT_NEAR(b.gain_kept, a.gain_kept, 0);
    ASSERT_NEAR(b.s_weak, a.s_weak, 0);
    pcache_path(dir, key, path, sizeof path, NULL);
    unlink(path);
    rmdir(dir);
    hf_decomp_free(&a);
    hf_decomp_free(&b);
    hf_design_free(&d);
}

TEST_LIST {
    TEST_ENTRY(extreme_paintings),
    TEST_ENTRY(grazing_angles),
    TEST_ENTRY(nonfinite_input_is_an_error),
    TEST_ENTRY(lambda_extremes),
    TEST_ENTRY(range_errors),
    TEST_ENTRY(barely_reached_direction_is_cut),
    TEST_ENTRY(fit_keeps_log_factors_in_range),
    TEST_ENTRY(sub_offset_stays_a_float),
    TEST_ENTRY(cut_report_survives_the_cache),
};

TEST_MAIN()
