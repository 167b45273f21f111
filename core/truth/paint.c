/* paint.c: paint views with an analytic BRDF (paint.h).
 *
 * A pixel's value is scale * pi I * f(wi, wo) * cos_i (scene.h: a white
 * Lambertian facing a light of intensity I reads I at scale 1), evaluated in double
 * and stored as float.  With an automatic scale the views are evaluated
 * twice (once for the maximum, once to write), so every stored value is
 * the correctly rounded product rather than a rescaled float. */
#include "paint.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The BRDF is one brdf_eval can evaluate: a known kind, finite values. */
static int paint_check_brdf(const brdf *b, glint_err *err)
{
    if (b->kind < BRDF_LAMBERT || b->kind > BRDF_WARD)
        return glint_err_set(err, GLINT_EINVAL, "paint: unknown brdf kind %d", (int)b->kind);
    for (int c = 0; c < 3; c++)
        if (!isfinite(b->kd[c]) || !isfinite(b->ks[c]) || !isfinite(b->f0[c]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "paint: brdf has a non-finite kd, ks or f0");
    if (!isfinite(b->exponent) || !isfinite(b->roughness))
        return glint_err_set(err, GLINT_ENONFINITE,
                             "paint: brdf has a non-finite exponent or roughness");
    if ((b->kind == BRDF_PHONG || b->kind == BRDF_BLINN) && !(b->exponent > 0.0))
        return glint_err_set(err, GLINT_ERANGE, "paint: brdf exponent %g is not > 0",
                             b->exponent);
    if ((b->kind == BRDF_CT || b->kind == BRDF_WARD) && !(b->roughness > 0.0))
        return glint_err_set(err, GLINT_ERANGE, "paint: brdf roughness %g is not > 0",
                             b->roughness);
    return 0;
}

int paint_sv_check(const paint_sv *sv, glint_err *err)
{
    int rc;
    if (sv->pattern != PAINT_SV_STRIPES && sv->pattern != PAINT_SV_CHECKER)
        return glint_err_set(err, GLINT_EINVAL, "paint: unknown pattern %d", sv->pattern);
    if (!(sv->freq > 0.0 && sv->freq <= 1024.0))
        return glint_err_set(err, GLINT_ERANGE,
                             "paint: pattern frequency %g outside (0, 1024] per unit of uv",
                             sv->freq);
    if (!(sv->duty >= 0.0 && sv->duty <= 1.0) || !(sv->soft >= 0.0 && sv->soft <= 0.5))
        return glint_err_set(err, GLINT_ERANGE,
                             "paint: duty %g must be in [0,1] and soft %g in [0,0.5]", sv->duty,
                             sv->soft);
    if ((rc = paint_check_brdf(&sv->a, err)) || (rc = paint_check_brdf(&sv->b, err)))
        return rc;
    return 0;
}

/* The weight of b in one period coordinate t (periods): 1 on [0, duty),
 * 0 on [duty, 1), with linear ramps of width soft centred on the edges. */
static double band(double t, double duty, double soft)
{
    double f = t - floor(t), d0, d1;
    if (soft <= 0.0)
        return f < duty ? 1.0 : 0.0;
    /* signed distance into the band from its nearer edge (edges at 0 and duty, periodic) */
    d0 = fmin(f, 1.0 - f);             /* to the edge at 0 (or 1) */
    d1 = fabs(f - duty);               /* to the edge at duty */
    {
        double d = fmin(d0, d1), in = f < duty ? 1.0 : -1.0;
        double x = 0.5 + in * d / soft;
        return x <= 0.0 ? 0.0 : x >= 1.0 ? 1.0 : x;
    }
}

double paint_sv_weight(const paint_sv *sv, double u, double v)
{
    if (sv->duty <= 0.0)
        return 0.0;
    if (sv->duty >= 1.0)
        return 1.0;
    if (sv->pattern == PAINT_SV_STRIPES)
        return band(u * sv->freq, sv->duty, sv->soft);
    {   /* a checker: b where exactly one of the two bands holds */
        double a = band(u * sv->freq, 0.5, sv->soft), b = band(v * sv->freq, 0.5, sv->soft);
        return a * (1.0 - b) + b * (1.0 - a);
    }
}

int paint_sv_parse(const char *spec, paint_sv *out, glint_err *err)
{
    char buf[512], *bar1, *bar2, *pat, *kv;
    int rc;
    memset(out, 0, sizeof *out);
    out->freq = 8.0;
    out->duty = 0.5;
    if (!spec || strlen(spec) >= sizeof buf)
        return glint_err_set(err, GLINT_EINVAL, "paint: a pattern spec of at most %zu bytes",
                             sizeof buf - 1);
    strcpy(buf, spec);
    if (!(bar1 = strchr(buf, '|')) || !(bar2 = strchr(bar1 + 1, '|')) || strchr(bar2 + 1, '|'))
        return glint_err_set(err, GLINT_EINVAL,
                             "paint: expected PATTERN[:key=value,...]|BRDF|BRDF, e.g. "
                             "\"stripes:freq=8,duty=0.3|lambert:kd=0.6/0.1/0.1|ct:rough=0.2\"");
    *bar1 = *bar2 = '\0';
    pat = buf;
    if ((kv = strchr(pat, ':')))
        *kv++ = '\0';
    if (!strcmp(pat, "stripes"))
        out->pattern = PAINT_SV_STRIPES;
    else if (!strcmp(pat, "checker"))
        out->pattern = PAINT_SV_CHECKER;
    else
        return glint_err_set(err, GLINT_EINVAL, "paint: unknown pattern \"%.40s\" (stripes, checker)",
                             pat);
    while (kv && *kv) {
        char *next = strchr(kv, ','), *eq, *end;
        double x;
        if (next)
            *next++ = '\0';
        if (!(eq = strchr(kv, '=')))
            return glint_err_set(err, GLINT_EINVAL, "paint: \"%.40s\" is not key=value", kv);
        *eq++ = '\0';
        x = strtod(eq, &end);
        if (end == eq || *end || !isfinite(x))
            return glint_err_set(err, GLINT_EINVAL, "paint: %.20s=\"%.40s\" is not a number", kv,
                                 eq);
        if (!strcmp(kv, "freq"))
            out->freq = x;
        else if (!strcmp(kv, "duty"))
            out->duty = x;
        else if (!strcmp(kv, "soft"))
            out->soft = x;
        else
            return glint_err_set(err, GLINT_EINVAL,
                                 "paint: unknown pattern key \"%.20s\" (freq, duty, soft)", kv);
        kv = next;
    }
    if ((rc = brdf_parse(bar1 + 1, &out->a, err)) || (rc = brdf_parse(bar2 + 1, &out->b, err)))
        return rc;
    return paint_sv_check(out, err);
}

static int paint_check_view(const gbuf *g, const scene_view *v, int k, glint_err *err)
{
    if (g->width < 1 || g->height < 1 || !g->mask || !g->nrm || !g->wi || !g->wo)
        return glint_err_set(err, GLINT_EINVAL, "paint: view %d has an empty G-buffer", k);
    if (!isfinite(v->light_intensity) || !(v->light_intensity > 0.0))
        return glint_err_set(err, GLINT_EINVAL,
                             "paint: view %d light intensity %g is not finite and > 0", k,
                             v->light_intensity);
    return 0;
}

/* Unscaled radiance pi I f cos_i of one pixel (INTENSITY: pi I) (OUT: rgb[3]); zero unless
 * mask, cos_i > 0 and cos_o > 0.  GLINT_ENONFINITE for a covered pixel with
 * non-finite geometry or a non-finite result. */
typedef struct truth {
    const brdf *b;        /* one analytic BRDF, */
    const paint_sv *sv;   /* or two blended over the surface, */
    paint_fn fn;          /* or a function (a measured material) */
    const void *ctx;
} truth;

static int paint_pixel(const truth *t, const gbuf *g, double intensity, size_t p, int k,
                       double rgb[3], glint_err *err)
{
    double n[3], wi[3], wo[3], ci = 0.0, co = 0.0;

    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!g->mask[p])
        return 0;
    for (int c = 0; c < 3; c++) {
        n[c] = g->nrm[3 * p + c];
        wi[c] = g->wi[3 * p + c];
        wo[c] = g->wo[3 * p + c];
        ci += n[c] * wi[c];
        co += n[c] * wo[c];
    }
    if (!isfinite(ci) || !isfinite(co))
        return glint_err_set(err, GLINT_ENONFINITE,
                             "paint: view %d pixel (x %d, y %d) has non-finite normal or "
                             "directions",
                             k, (int)(p % (size_t)g->width), (int)(p / (size_t)g->width));
    if (!(ci > 0.0 && co > 0.0))
        return 0;
    if (t->sv) { /* (1 - w) a + w b, w the pattern's weight at the pixel's uv */
        const paint_sv *sv = t->sv;
        double w = paint_sv_weight(sv, g->uv[2 * p], g->uv[2 * p + 1]), fb[3];
        brdf_eval(&sv->a, n, wi, wo, rgb);
        brdf_eval(&sv->b, n, wi, wo, fb);
        for (int c = 0; c < 3; c++)
            rgb[c] = w == 0.0 ? rgb[c] : w == 1.0 ? fb[c] : (1.0 - w) * rgb[c] + w * fb[c];
    } else if (t->fn) {
        t->fn(t->ctx, n, wi, wo, rgb);
    } else {
        brdf_eval(t->b, n, wi, wo, rgb);
    }
    for (int c = 0; c < 3; c++) {
        rgb[c] *= intensity * ci;
        if (!isfinite(rgb[c]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "paint: view %d pixel (x %d, y %d) radiance is not finite",
                                 k, (int)(p % (size_t)g->width),
                                 (int)(p / (size_t)g->width));
    }
    return 0;
}

static int paint_any(const truth *t, const gbuf *g, const scene_view *views, int nviews,
                     double scale, img *out, double *scale_out, glint_err *err)
{
    const paint_sv *sv = t->sv;
    double rgb[3];
    int k, done = 0, rc;

    if ((!t->b && !sv && !t->fn) || !g || !views || !out)
        return glint_err_set(err, GLINT_EINVAL, "paint: NULL brdf, gbufs, views or output");
    if (nviews < 1 || nviews > SCENE_MAX_VIEWS)
        return glint_err_set(err, GLINT_ERANGE, "paint: %d views, supported 1..%d", nviews,
                             SCENE_MAX_VIEWS);
    if (!isfinite(scale))
        return glint_err_set(err, GLINT_ENONFINITE, "paint: scale %g is not finite", scale);
    rc = sv ? paint_sv_check(sv, err) : t->fn ? 0 : paint_check_brdf(t->b, err);
    if (rc)
        return rc;
    for (k = 0; k < nviews; k++) {
        rc = paint_check_view(&g[k], &views[k], k, err);
        if (!rc && sv && !g[k].uv)
            rc = glint_err_set(err, GLINT_EINVAL, "paint: view %d has no texture coordinates",
                               k);
        if (rc)
            return rc;
    }

    if (scale <= 0.0) {
        double vmax = 0.0;
        for (k = 0; k < nviews; k++) {
            size_t np = (size_t)g[k].width * (size_t)g[k].height;
            for (size_t p = 0; p < np; p++) {
                rc = paint_pixel(t, &g[k], view_light_scale(&views[k]), p, k, rgb, err);
                if (rc)
                    return rc;
                for (int c = 0; c < 3; c++)
                    if (rgb[c] > vmax)
                        vmax = rgb[c];
            }
        }
        /* Nothing lit: every value is 0 under any scale; report scale 1. */
        scale = vmax > 0.0 ? 1.0 / vmax : 1.0;
    }

    for (k = 0; k < nviews; k++) {
        const gbuf *gk = &g[k];
        size_t np = (size_t)gk->width * (size_t)gk->height;

        rc = img_alloc(&out[k], gk->width, gk->height, 3, err);
        if (rc)
            goto fail_views;
        done = k + 1;
        for (size_t p = 0; p < np; p++) {
            rc = paint_pixel(t, gk, view_light_scale(&views[k]), p, k, rgb, err);
            if (rc)
                goto fail_views;
            for (int c = 0; c < 3; c++) {
                float v = (float)(scale * rgb[c]);
                if (!isfinite(v)) {
                    rc = glint_err_set(err, GLINT_ERANGE,
                                       "paint: view %d pixel (x %d, y %d): scale %g * "
                                       "radiance %g overflows a float",
                                       k, (int)(p % (size_t)gk->width),
                                       (int)(p / (size_t)gk->width), scale, rgb[c]);
                    goto fail_views;
                }
                out[k].px[3 * p + c] = v;
            }
        }
    }
    if (scale_out)
        *scale_out = scale;
    return 0;

fail_views:
    for (k = 0; k < done; k++)
        img_free(&out[k]);
    return rc;
}

int paint_views(const brdf *b, const gbuf *g, const scene_view *views, int nviews,
                double scale, img *out, double *scale_out, glint_err *err)
{
    truth t = {b, NULL, NULL, NULL};
    if (!b)
        return glint_err_set(err, GLINT_EINVAL, "paint: NULL brdf");
    return paint_any(&t, g, views, nviews, scale, out, scale_out, err);
}

int paint_views_sv(const paint_sv *sv, const gbuf *g, const scene_view *views, int nviews,
                   double scale, img *out, double *scale_out, glint_err *err)
{
    truth t = {NULL, sv, NULL, NULL};
    if (!sv)
        return glint_err_set(err, GLINT_EINVAL, "paint: NULL spatially varying brdf");
    return paint_any(&t, g, views, nviews, scale, out, scale_out, err);
}

int paint_views_fn(paint_fn fn, const void *ctx, const gbuf *g, const scene_view *views,
                   int nviews, double scale, img *out, double *scale_out, glint_err *err)
{
    truth t = {NULL, NULL, fn, ctx};
    if (!fn)
        return glint_err_set(err, GLINT_EINVAL, "paint: NULL truth function");
    return paint_any(&t, g, views, nviews, scale, out, scale_out, err);
}
