/* The numerical extremes the fit accepts, swept on the default scene (the
 * built-in sphere, 12 icosahedron views at 128x128): res {4, 16, 128, 512}
 * x lambda {0, 1e-3, 1e8} x regularization {trunc:full, tikhonov:rel1e-2}
 * x mapping {log, add, sub} x three paintings (Cook-Torrance GGX 0.2 with
 * its brightest pixel at 1, an HDR near-mirror painted at scale 50, all
 * black).  Every case must give log-factors within HF_LOG_FACTOR_MAX,
 * factor values that are finite single-precision numbers (the factor
 * textures and the renderers are single precision) and a finite
 * reconstruction on the samples.  One line per decomposition says
 * what it cut (null and barely reached directions, cutoffs, the smallest
 * singular value kept), one line per case what the operator and the fit
 * decided.  These paintings are within a few log units of a product of
 * factors: the decomposition's cut alone must keep them in range, with no
 * damping by the fit.
 *
 * Decompositions are shared by the regularizations, operators by the
 * mappings and paintings, so the sweep costs 12 decompositions. */
#include "brdf.h"
#include "check.h"
#include "hf.h"
#include "hf_int.h"
#include "paint.h"
#include "raster.h"
#include "samples.h"
#include "scene.h"

#define NPAINT 3

static const char *const paint_names[NPAINT] = {"ct0.2", "mirror50", "black"};

typedef struct sweep_fixture {
    samples s;
    float *rgb[NPAINT]; /* 3 * s.n each */
} sweep_fixture;

static sweep_fixture FX;
static int fx_state; /* 0 not built, 1 ready, -1 failed */

/* Paint the views with `spec` at `scale` (paint_views: <= 0 scales the
 * brightest pixel to 1, > 0 multiplies the radiance, as glint paint
 * --scale) and gather the samples' values (OUT: *out, 3 * FX.s.n). */
static int paint_samples(const scene *sc, const gbuf *g, const char *spec, double scale,
                         float **out, glint_err *e)
{
    brdf b;
    img imgs[12];
    int rc;

    memset(imgs, 0, sizeof imgs);
    if (sc->nviews != 12)
        return glint_err_set(e, GLINT_EINVAL, "expected 12 views, got %d", sc->nviews);
    if ((rc = brdf_parse(spec, &b, e)) ||
        (rc = paint_views(&b, g, sc->views, sc->nviews, scale, imgs, NULL, e)))
        return rc;
    *out = malloc((size_t)3 * FX.s.n * sizeof **out);
    if (!*out)
        rc = glint_err_set(e, GLINT_ENOMEM, "out of memory");
    else
        rc = samples_gather(&FX.s, imgs, *out, e);
    for (int v = 0; v < 12; v++)
        img_free(&imgs[v]);
    return rc;
}

static int fixture(void)
{
    scene_params p;
    scene sc;
    gbuf *g = NULL;
    glint_err e;
    char hash[33];
    int rc;

    if (fx_state)
        return fx_state > 0 ? 0 : -1;
    fx_state = -1;
    memset(&sc, 0, sizeof sc);
    scene_params_default(&p);
    if ((rc = scene_create(&p, &sc, &e)) || (rc = raster_scene(&sc, &g, &e)))
        goto done;
    scene_hash(&sc, hash);
    if ((rc = samples_build(g, sc.views, sc.nviews, NULL, hash, &FX.s, &e)) ||
        (rc = paint_samples(&sc, g, "ct:rough=0.2", 0.0, &FX.rgb[0], &e)) ||
        (rc = paint_samples(&sc, g, "ct:rough=0.05,kd=0,f0=1", 50.0, &FX.rgb[1], &e)))
        goto done;
    FX.rgb[2] = calloc((size_t)3 * FX.s.n, sizeof *FX.rgb[2]);
    if (!FX.rgb[2])
        rc = glint_err_set(&e, GLINT_ENOMEM, "out of memory");
done:
    if (g)
        raster_free_all(g, sc.nviews);
    scene_free(&sc);
    if (rc) {
        fprintf(stderr, "  fixture: %s\n", e.msg);
        return -1;
    }
    fx_state = 1;
    return 0;
}

/* One fit: OUT *st, *max_log (largest |log-factor|).  1 when every output
 * is in range, 0 otherwise (what failed goes to why). */
static int check_fit(const hf_design *d, const hf_op *op, const char *map_spec,
                     const float *rgb, hf_fit_stats *st, double *max_log, char *why,
                     size_t whylen)
{
    hf_map map;
    hf_factors fac;
    glint_err e;
    float *rec;
    int ok = 1;

    *max_log = NAN;
    if (hf_map_parse(map_spec, &map, &e) ||
        hf_fit(d, op, &map, HF_MODEL_RADIANCE, rgb, &fac, st, &e)) {
        snprintf(why, whylen, "fit failed: %s", e.msg);
        return 0;
    }
    *max_log = 0.0;
    for (int k = 0; k < 9 * fac.res; k++) {
        double l = fac.logf[k];
        float v = (float)exp(l);
        if (!isfinite(l) || !isfinite(v) || !(fabs(l) <= HF_LOG_FACTOR_MAX)) {
            if (ok)
                snprintf(why, whylen, "log-factor %.6g at factor %d texel %d channel %d "
                         "gives a factor of %g", l, k / 3 / fac.res, k / 3 % fac.res, k % 3,
                         (double)v);
            ok = 0;
        }
        if (fabs(l) > *max_log)
            *max_log = fabs(l);
    }
    rec = malloc((size_t)3 * d->n * sizeof *rec);
    if (!rec) {
        hf_factors_free(&fac);
        snprintf(why, whylen, "out of memory");
        return 0;
    }
    hf_factors_eval_design(&fac, d, rec);
    for (int i = 0; i < 3 * d->n; i++) {
        if (!isfinite(rec[i])) {
            if (ok)
                snprintf(why, whylen, "reconstruction of sample %d channel %d is %g", i / 3,
                         i % 3, (double)rec[i]);
            ok = 0;
            break;
        }
    }
    if (!isfinite(st->rms) || !isfinite(st->log_residual)) {
        if (ok)
            snprintf(why, whylen, "rms %g, log residual %g", st->rms, st->log_residual);
        ok = 0;
    }
    free(rec);
    hf_factors_free(&fac);
    return ok;
}

TEST(sweep_every_output_finite)
{
    static const int res[] = {4, 16, 128, 512};
    static const double lambdas[] = {0.0, 1e-3, 1e8};
    static const char *const regs[] = {"trunc:full", "tikhonov:rel1e-2"};
    static const char *const maps[] = {"log", "add", "sub"};
    int ncase = 0, nfail = 0;
    double t0 = hf_now();

    ASSERT_OK(fixture());
    printf("  %d samples\n", FX.s.n);
    for (unsigned ri = 0; ri < sizeof res / sizeof res[0]; ri++) {
        hf_design d;
        glint_err e;
        ASSERT_OK(hf_design_build(&FX.s, res[ri], &d, &e));
        for (unsigned li = 0; li < sizeof lambdas / sizeof lambdas[0]; li++) {
            hf_decomp dc;
            double td = hf_now();
            ASSERT_OK(hf_decomp_build(&d, lambdas[li], HF_ROUTE_EIG, 0, &dc, &e));
            td = hf_now() - td;
            printf("  res %3d lambda %-5g: rank %d of %d (gauge %d); cut %d null "
                   "(s <= %.3g = rcond %.3g s_max %.4g), %d barely reached (gain > %.3g, "
                   "largest s cut %.3g); s_min kept %.4g, largest gain kept %.3g [%.2f s]\n",
                   res[ri], lambdas[li], dc.rank, dc.n - dc.gauge_dims, dc.gauge_dims,
                   dc.null_dims, dc.s_null, dc.rcond, dc.s[0], dc.weak_dims, dc.gain_max,
                   dc.s_weak, dc.s[dc.rank - 1], dc.gain_kept, td);
            ASSERT_EQ(dc.gauge_dims + dc.null_dims + dc.weak_dims + dc.rank, dc.n);
            ASSERT_LE(dc.gain_kept, dc.gain_max);
            /* where the fit used to overflow, the cut is what changed */
            if (lambdas[li] == 0.0 && res[ri] >= 128)
                ASSERT(dc.weak_dims > 0);
            for (unsigned gi = 0; gi < sizeof regs / sizeof regs[0]; gi++) {
                hf_reg reg;
                hf_op op;
                ASSERT_OK(hf_reg_parse(regs[gi], &reg, &e));
                ASSERT_OK(hf_op_build(&dc, &reg, HF_F64, &op, &e));
                for (int pi = 0; pi < NPAINT; pi++) {
                    for (unsigned mi = 0; mi < sizeof maps / sizeof maps[0]; mi++) {
                        hf_fit_stats st;
                        double max_log;
                        char why[GLINT_ERR_MSG_MAX + 64] = "";
                        int ok;
                        memset(&st, 0, sizeof st);
                        ok = check_fit(&d, &op, maps[mi], FX.rgb[pi], &st, &max_log, why,
                                       sizeof why);
                        if (ok && st.damping != 0.0) {
                            snprintf(why, sizeof why, "damped (alpha %.3g) from |log| %.3g",
                                     st.damping, st.log_max_undamped);
                            ok = 0;
                        }
                        ncase++;
                        nfail += !ok;
                        printf("    %-4s res %3d lambda %-5g %-16s %-8s %-3s: k %4d "
                               "s_last %.3g, max|log| %.3g, damping %g, rms %.3g%s%s\n",
                               ok ? "ok" : "FAIL", res[ri], lambdas[li], regs[gi],
                               paint_names[pi], maps[mi], op.k, op.s_last, max_log,
                               st.damping, st.rms, ok ? "" : ": ", why);
                    }
                }
                hf_op_free(&op);
            }
            hf_decomp_free(&dc);
        }
        hf_design_free(&d);
    }
    printf("  %d cases, %d failed [%.1f s]\n", ncase, nfail, hf_now() - t0);
    ASSERT_EQ(ncase, 216);
    ASSERT_EQ(nfail, 0);
}

/* Fewer rows than unknowns (a handful of samples, lambda 0, so m < 3R):
 * the svd route pads its matrix to be square and agrees with the eig route. */
TEST(svd_route_with_fewer_samples_than_unknowns)
{
    static const int counts[] = {1, 3, 10};
    ASSERT_OK(fixture());
    for (unsigned ci = 0; ci < sizeof counts / sizeof counts[0]; ci++) {
        samples few = FX.s;
        hf_design d;
        hf_decomp dc[2];
        hf_op op[2];
        hf_factors fac[2];
        hf_map map;
        hf_reg reg;
        glint_err e;
        double diff = 0.0, mag = 0.0;
        few.n = counts[ci]; /* the first samples only (the arrays are longer) */
        ASSERT_OK(hf_design_build(&few, 8, &d, &e));
        ASSERT_OK(hf_reg_parse("trunc:full", &reg, &e));
        ASSERT_OK(hf_map_parse("add", &map, &e));
        for (int r = 0; r < 2; r++) {
            ASSERT_OK(hf_decomp_build(&d, 0.0, r ? HF_ROUTE_SVD : HF_ROUTE_EIG, 0, &dc[r], &e));
            ASSERT_OK(hf_op_build(&dc[r], &reg, HF_F64, &op[r], &e));
            ASSERT_OK(hf_fit(&d, &op[r], &map, HF_MODEL_RADIANCE, FX.rgb[0], &fac[r], NULL, &e));
        }
        printf("  %2d samples: rank eig %d svd %d of %d\n", counts[ci], dc[0].rank, dc[1].rank,
               dc[0].n);
        ASSERT_EQ(dc[0].rank, dc[1].rank);
        ASSERT(dc[1].rank <= counts[ci]);
        for (int k = 0; k < 9 * fac[0].res; k++) {
            ASSERT_FINITE(fac[1].logf[k]);
            diff = fmax(diff, fabs(fac[1].logf[k] - fac[0].logf[k]));
            mag = fmax(mag, fabs(fac[0].logf[k]));
        }
        ASSERT_LE(diff, 1e-8 * (1.0 + mag));
        for (int r = 0; r < 2; r++) {
            hf_factors_free(&fac[r]);
            hf_op_free(&op[r]);
            hf_decomp_free(&dc[r]);
        }
        hf_design_free(&d);
    }
}

TEST(cleanup)
{
    samples_free(&FX.s);
    for (int p = 0; p < NPAINT; p++)
        free(FX.rgb[p]);
    memset(&FX, 0, sizeof FX);
    fx_state = 0;
}

TEST_LIST {
    TEST_ENTRY(sweep_every_output_finite),
    TEST_ENTRY(svd_route_with_fewer_samples_than_unknowns),
    TEST_ENTRY(cleanup),
};
TEST_MAIN()
