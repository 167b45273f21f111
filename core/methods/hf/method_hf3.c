/* method_hf3.c: the hf3 method: parameters, precomputation levels, fit
 * (method_hf3.h).  Its material operations are in method_hf3_material.c. */
#include "method_hf3.h"
#include "method_hf3_parts.h"

#include <assert.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "pcache.h"

static_assert(sizeof(hf_model) == sizeof(int) && sizeof(hf_precision) == sizeof(int) &&
                  sizeof(hf_route) == sizeof(int),
              "enum parameters are stored as int");

/* ---- parameters -------------------------------------------------------------------- */

void fit_params_default(fit_params *p)
{
    memset(p, 0, sizeof *p);
    p->res = 128;
    p->lambda = 0.1;
    p->reg.kind = HF_REG_TRUNC;
    hf_map_default(&p->map, HF_MAP_ADD);
    p->model = HF_MODEL_RADIANCE;
    p->prec = HF_F64;
    p->route = HF_ROUTE_EIG;
    p->rcond = hf_rcond_default(HF_ROUTE_EIG);
}

int hf3_reg_parse(const char *text, void *field, glint_err *err)
{
    return hf_reg_parse(text, field, err);
}

void hf3_reg_format(const void *field, char *buf, size_t len)
{
    hf_reg_format(field, buf, len);
}

int hf3_map_parse(const char *text, void *field, glint_err *err)
{
    return hf_map_parse(text, field, err);
}

void hf3_map_format(const void *field, char *buf, size_t len)
{
    hf_map_format(field, buf, len);
}

const char *const hf3_model_values[] = {"radiance", "brdf", NULL};
const char *const hf3_precision_values[] = {"double", "single", NULL};
const char *const hf3_route_values[] = {"eig", "svd", NULL};
const char *const hf3_reg_examples[] = {"trunc:full", "trunc:50%", "trunc:rel1e-3",
                                        "tikhonov:rel1e-2", "linear:40", NULL};
const char *const hf3_map_examples[] = {"log", "add:0.1", "sub:0.01", "add:0.05,eps=1e-4",
                                        NULL};

static const method_param hf3_params[] = {HF3_PARAM_ROWS(fit_params, )};

static const method_preset hf3_presets[] = {
    {"draft", "{\"res\": 32}"},
    {"fast", "{\"res\": 64}"},
    {"default", "{\"res\": 128}"},
    {"fine", "{\"res\": 256}"},
};

static void hf3_params_default(void *p)
{
    fit_params_default(p);
}

/* ---- levels -------------------------------------------------------------------------- */

void hf3_decomp_clear(hf3_decomp *x)
{
    if (!x)
        return;
    hf_design_free(&x->d);
    hf_decomp_free(&x->dc);
    memset(x, 0, sizeof *x);
}

static int svd_size_check(const fit_params *p, const samples *s, glint_err *err)
{
    size_t rows, cols;
    if (p->route != HF_ROUTE_SVD)
        return 0;
    rows = (size_t)s->n + 3 * (size_t)(p->res - 2);
    cols = 3 * (size_t)p->res;
    if (rows * cols * sizeof(double) > HF3_SVD_MAX_BYTES)
        return glint_err_set(err, GLINT_ERANGE,
                             "route svd needs a dense %zux%zu constraint matrix (%.1f GiB), "
                             "over the limit of %.1f GiB: use route eig",
                             rows, cols, (double)(rows * cols * 8) / (1 << 30),
                             (double)HF3_SVD_MAX_BYTES / (1 << 30));
    return 0;
}

int hf3_decomp_make(const fit_params *p, const samples *s,
                    void (*progress)(void *cls, const char *stage, double fraction), void *cls,
                    hf3_decomp *out, glint_err *err)
{
    double t0 = glint_now();
    int rc;

    memset(out, 0, sizeof *out);
    if (progress)
        progress(cls, "design", 0.25);
    if ((rc = hf_design_build(s, p->res, &out->d, err)))
        return rc;
    out->t_design = glint_now() - t0;
    if ((rc = svd_size_check(p, s, err)))
        goto fail;
    if (progress)
        progress(cls, "decomposition", 0.3);
    t0 = glint_now();
    if ((rc = hf_decomp_build(&out->d, p->lambda, p->route, p->rcond, &out->dc, err)))
        goto fail;
    out->t_decomp = glint_now() - t0;
    return 0;
fail:
    hf3_decomp_clear(out);
    return rc;
}

static size_t decomp_bytes(const hf3_decomp *x)
{
    return sizeof *x + (size_t)x->d.n * 3 * (sizeof(int32_t) + sizeof(double)) +
           (size_t)x->d.n * sizeof(double) + pcache_decomp_bytes(&x->dc);
}

static void decomp_free(void *data)
{
    hf3_decomp_clear(data);
    free(data);
}

static void decomp_key(const void *params, const samples *s, const char *prev_key, char *key,
                       size_t len)
{
    const fit_params *p = params;
    char k[33];
    (void)prev_key;
    pcache_key_hf(s->hash, p->res, p->lambda, p->route, p->rcond, k);
    snprintf(key, len, "%s", k);
}

static void progress(const method_build_in *in, const char *stage, double f)
{
    if (in->progress)
        in->progress(in->progress_cls, stage, f);
}

static int decomp_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    hf3_decomp *x = calloc(1, sizeof *x);
    int rc;
    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = hf3_decomp_make(in->params, in->s, in->progress, in->progress_cls, x, err))) {
        free(x);
        return rc;
    }
    out->data = x;
    out->bytes = decomp_bytes(x);
    out->free = decomp_free;
    return 0;
}

/* The disk layer keeps the decomposition; the design is rebuilt from the
 * pattern (it depends only on the pattern and res).  For 393,512 samples
 * that takes 4 ms in memory already written once, 10-17 ms in glintd's
 * first fit after a restart, most of it the kernel's faults on 17 MB of
 * fresh pages; a design file mapped instead took 5 ms there, but writing
 * it cost the cold fit 15-27 ms (BENCHMARKS.md, "eleventh pass"). */
static int decomp_load(const method_build_in *in, const char *dir, const char *key,
                       cache_value *out, glint_err *err)
{
    const fit_params *p = in->params;
    hf3_decomp *x = calloc(1, sizeof *x);
    double t0 = glint_now();
    int rc;

    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    rc = pcache_decomp_load(dir, key, &x->dc, err);
    if (rc == 0 && (x->dc.nsamples != in->s->n || x->dc.res != p->res))
        rc = glint_err_set(err, GLINT_EFORMAT, "cached decomposition %s does not match", key);
    x->t_decomp = glint_now() - t0;
    if (rc == 0) {
        progress(in, "design", 0.25);
        t0 = glint_now();
        rc = hf_design_build(in->s, p->res, &x->d, err);
        x->t_design = glint_now() - t0;
        progress(in, "decomposition", 0.3);
    }
    if (rc) {
        decomp_free(x);
        return rc;
    }
    out->data = x;
    out->bytes = decomp_bytes(x);
    out->free = decomp_free;
    return 0;
}

static int decomp_save(const method_build_in *in, const char *dir, const char *key,
                       const cache_value *v, glint_err *err)
{
    (void)in;
    return pcache_decomp_save(dir, key, &((const hf3_decomp *)v->data)->dc, err);
}

static void op_key(const void *params, const samples *s, const char *prev_key, char *key,
                   size_t len)
{
    const fit_params *p = params;
    char reg[64];
    (void)s;
    hf_reg_format(&p->reg, reg, sizeof reg);
    snprintf(key, len, "%s/%s/%s", prev_key, reg, p->prec == HF_F32 ? "single" : "double");
}

static void op_free(void *data)
{
    hf_op_free(data);
    free(data);
}

static int op_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const fit_params *p = in->params;
    const hf3_decomp *x = in->prev[0];
    hf_op *op = calloc(1, sizeof *op);
    int rc;
    if (!op)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    progress(in, "operator", 0.85);
    if ((rc = hf_op_build(&x->dc, &p->reg, p->prec, op, err))) {
        free(op);
        return rc;
    }
    out->data = op;
    out->bytes = sizeof *op + hf_op_bytes(op, NULL);
    out->free = op_free;
    return 0;
}

const method_level hf3_levels[HF3_NLEVELS] = {
    {.name = "decomposition", .progress = 0.3, .key = decomp_key, .build = decomp_build,
     .load = decomp_load, .save = decomp_save},
    {.name = "operator", .progress = 0.85, .key = op_key, .build = op_build},
};

/* ---- fit ------------------------------------------------------------------------------ */

int hf3_fit_material(const hf3_prepared *pp, const float *rgb, double t_start, material *out,
                     glint_err *err)
{
    hf_factors fac;
    hf_fit_stats st;
    json_t *info, *pre, *tim, *errs;
    char key[33];
    int rc;

    memset(out, 0, sizeof *out);
    rc = hf_fit_with(pp->d, pp->op, &pp->params->map, pp->params->model, rgb, pp->reuse, &fac,
                     &st, err);
    if (rc)
        return rc;
    snprintf(key, sizeof key, "%s", pp->cache_key ? pp->cache_key : "");
    pre = json_pack("{s:s, s:s, s:i, s:i, s:i, s:i, s:i, s:f, s:f, s:f, s:f, s:i, s:I}",
                    "pattern_hash", pp->s->hash, "cache_key", key, "cache_hit", pp->cache_hit,
                    "samples", pp->s->n, "unknowns", pp->dc->n, "numerical_rank", pp->dc->rank,
                    "gauge_dims", pp->dc->gauge_dims, "rcond", pp->dc->rcond, "s_max",
                    pp->dc->s[0], "s_first_used", pp->op->s_first, "s_last_used",
                    pp->op->s_last, "rank_kept", pp->op->k, "operator_bytes",
                    (json_int_t)hf_op_bytes(pp->op, pp->d));
    json_object_set_new(pre, "condition_used", json_real(pp->op->s_first / pp->op->s_last));
    /* what the decomposition cut besides the gauge (hf.h) */
    json_object_set_new(pre, "null_dims", json_integer(pp->dc->null_dims));
    json_object_set_new(pre, "weak_dims", json_integer(pp->dc->weak_dims));
    json_object_set_new(pre, "s_null", json_real(pp->dc->s_null));
    json_object_set_new(pre, "gain_max", json_real(pp->dc->gain_max));
    json_object_set_new(pre, "gain_kept", json_real(pp->dc->gain_kept));
    json_object_set_new(pre, "s_weak", json_real(pp->dc->s_weak));
    /* the pass over the samples: its chunks, and how many an earlier fit's
     * sums served (views whose paintings had not changed, hf_fit_with) */
    json_object_set_new(pre, "stream_chunks", json_integer(st.stream_chunks));
    json_object_set_new(pre, "stream_chunks_reused", json_integer(st.stream_chunks_reused));
    tim = json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f, s:f}", "samples",
                    pp->t_samples, "design", pp->t_design, "decomposition", pp->t_decomp,
                    "operator", pp->t_op, "map", st.map_seconds, "stream", st.stream_seconds,
                    "apply_operator", st.op_seconds, "apply", st.apply_seconds,
                    "factorization", st.total_seconds, "diagnostics", st.diag_seconds, "fit",
                    glint_now() - t_start);
    errs = json_pack("{s:f, s:f, s:f, s:[i,i,i], s:f, s:f}", "rms_painted", st.rms,
                     "max_abs_painted", st.max_abs, "log_residual_rms", st.log_residual,
                     "clamped", st.clamped[0], st.clamped[1], st.clamped[2], "log_max",
                     st.log_max, "damping", st.damping);
    /* over every sample (one run), or evenly spaced runs of consecutive
     * samples (hf.h) */
    json_object_set_new(errs, "diagnostic_samples", json_integer(st.diag_samples));
    json_object_set_new(errs, "diagnostic_runs", json_integer(st.diag_runs));
    info = json_pack("{s:o, s:o, s:o, s:o}", "params",
                     method_params_to_json(&method_hf3, pp->params), "precomputation", pre,
                     "seconds", tim, "errors", errs);
    return hf3_material_init(out, &fac, info, err);
}

static void memo_free(void *data)
{
    hf_memo_free(data);
}

static int hf3_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const hf3_decomp *x = in->levels[0];
    hf3_prepared pp;
    double t0 = glint_now();

    memset(&pp, 0, sizeof pp);
    pp.params = in->params;
    pp.s = in->s;
    pp.d = &x->d;
    pp.dc = &x->dc;
    pp.op = in->levels[1];
    pp.cache_key = in->keys[0];
    pp.cache_hit = in->disk[0] == CACHE_DISK_LOADED    ? 1
                   : in->disk[0] == CACHE_DISK_REBUILT ? -1
                                                       : 0;
    pp.t_samples = in->pattern_seconds;
    pp.t_design = in->how[0] == CACHE_BUILT ? x->t_design : 0.0;
    pp.t_decomp = in->how[0] == CACHE_BUILT ? x->t_decomp : in->spent[0];
    pp.t_op = in->spent[1];
    if (in->memo && in->view_tags) {
        /* the pass's chunk sums of views not repainted since the last fit,
         * or of spans the values did not change in */
        hf_fit_reuse r;
        char key[128];
        if (in->memo->owner != &method_hf3) {
            method_memo_drop_data(in->memo);
            if ((in->memo->data = hf_memo_new())) {
                in->memo->owner = &method_hf3;
                in->memo->free = memo_free;
            }
        }
        if (in->memo->data) {
            /* the design: its pattern and the decomposition's key */
            snprintf(key, sizeof key, "%s/%s", in->s->hash, in->keys[0]);
            r.memo = in->memo->data;
            r.key = key;
            r.view = in->s->view;
            r.tags = in->view_tags;
            r.nviews = in->s->nviews;
            r.change = in->values_change;
            pp.reuse = &r;
            return hf3_fit_material(&pp, in->rgb, t0, out, err);
        }
    }
    return hf3_fit_material(&pp, in->rgb, t0, out, err);
}

/* The svd route's dense matrices make one decomposition per painted view
 * too costly for a background measurement. */
int hf3_holdout_ok(const void *params)
{
    return ((const fit_params *)params)->route == HF_ROUTE_EIG;
}

/* Peak memory of a cold fit (measured: /usr/bin/time -f %M glint fit
 * --no-cache, minus the process's 140 MB of libraries): the eig route
 * took 235 bytes per sample and 143 per res^2 (12-view sphere, 128^2 to
 * 512^2 rasters, res 32 to 512); the svd route adds its dense constraint
 * matrix and a working copy, 16 bytes per sample and factor texel.  The
 * bound leaves a third on top. */
size_t hf3_fit_bytes(const void *params, long nsamples)
{
    const fit_params *fp = params;
    double n = (double)nsamples, res = fp->res, b = 320.0 * n + 192.0 * res * res;
    if (fp->route != HF_ROUTE_EIG)
        b += 2.0 * n * 3.0 * res * 8.0 + 3.0 * (3.0 * res) * (3.0 * res) * 8.0;
    return b >= (double)SIZE_MAX ? SIZE_MAX : (size_t)b;
}

/* A cold fit: passes over the samples, then the decomposition and the
 * operator of 3 res unknowns (measured: res 512 on 18,476 samples 6.9 s,
 * estimated 5.5 s; res 128 0.37 s, estimated 0.29 s). */
double hf3_fit_seconds(const void *params, long nsamples)
{
    const fit_params *fp = params;
    return (double)nsamples * METHOD_SECONDS_PER_SAMPLE + 2.0 * method_dense_seconds(3.0 * fp->res);
}

const method method_hf3 = {
    .name = "hf3",
    .label = "One finish, lit by lamps",
    .summary = "One finish for the whole object, fitted to views lit by their point "
        "light; a painted pattern is blended into one colour.",
    .when = "Use it for a single finish (plastic, metal, paint) painted under the "
        "views' point lights; patterns need several materials.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_FACTORS,
    .title = "Homomorphic factorization into three 1D factors",
    .reference = "Jaroszkiewicz & McCool, Fast Extraction of BRDFs and Material Maps from "
                 "Images, GI 2003",
    .description =
        "Painted pixels are BRDF samples; the constraint matrix of the painted views (the "
        "sampling pattern) is decomposed once and cached, and each fit applies the "
        "regularized pseudo-inverse in log space: p(pi_p) q(pi_q) r(pi_r). Parameters marked "
        "precomputation change the cache key (a new precomputation runs as a job); the others "
        "are free. Points: fit_seconds is the warm fit (precomputation in memory), "
        "cold_seconds the precomputation from scratch, rms_painted the RMS error on the "
        "painted pixels, held_out_rms the pooled RMS error on each painted view when it is "
        "left out of the fit (leave-one-view-out; measured in the background after the first "
        "fit of a configuration with at least 2 painted views).",
    .held_out = "leave-one-view-out: for each painted view, fit the others and measure the RMS "
                "error on that view's painted pixels; pooled over views",
    .schema = "FitParams.json",
    .params_size = sizeof(fit_params),
    .params = hf3_params,
    .nparams = (int)(sizeof hf3_params / sizeof hf3_params[0]),
    .presets = hf3_presets,
    .npresets = (int)(sizeof hf3_presets / sizeof hf3_presets[0]),
    .params_default = hf3_params_default,
    .levels = hf3_levels,
    .nlevels = HF3_NLEVELS,
    .fit = hf3_fit,
    .mat = &hf3_material_ops,
    .holdout_ok = hf3_holdout_ok,
    .fit_bytes = hf3_fit_bytes,
    .fit_seconds = hf3_fit_seconds,
};
