/* method_hfx.c: the methods of factor products with 2D factors (hf4,
 * hf2d) as methods: their decomposition level, their fit's report and the
 * common parts of their materials (internal/method_hfx_int.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "internal/method_hfx_int.h"

/* ---- the decomposition level -------------------------------------------------------- */

static const hfx_decomp *level_decomp(const hfx_method *m, const void *level)
{
    return (const hfx_decomp *)((const char *)level + m->decomp_at);
}

/* The cache's value of a level made. */
static void level_value(const hfx_method *m, void *level, cache_value *out)
{
    out->data = level;
    out->bytes = m->bytes(level);
    out->free = m->free;
}

int hfx_level_build(const hfx_method *m, const method_build_in *in, cache_value *out,
                    glint_err *err)
{
    void *x = calloc(1, m->level_size);
    hfx_level *t = x;
    double t0 = glint_now();
    int rc;
    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (in->progress)
        in->progress(in->progress_cls, "design", 0.25);
    if ((rc = m->design(in->params, in->s, x, err))) {
        free(x);
        return rc;
    }
    t->t_design = glint_now() - t0;
    if (in->progress)
        in->progress(in->progress_cls, "decomposition", 0.3);
    if ((rc = m->decompose(in->params, x, err))) {
        m->free(x);
        return rc;
    }
    level_value(m, x, out);
    return 0;
}

int hfx_level_load(const hfx_method *m, const method_build_in *in, const char *dir,
                   const char *key, cache_value *out, glint_err *err)
{
    void *x = calloc(1, m->level_size);
    hfx_level *t = x;
    hfx_file_head h;
    double t0 = glint_now();
    int rc, n;

    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    n = m->file_head(in->params, x, &h);
    if ((rc = hfx_decomp_file_load(m->magic, m->ext, h.u, h.nu, h.d, h.nd, n, in->s->n,
                                   (hfx_decomp *)((char *)x + m->decomp_at), dir, key, err)) ||
        (rc = m->design(in->params, in->s, x, err))) {
        m->free(x);
        return rc;
    }
    t->t_load = t->t_design = glint_now() - t0;
    level_value(m, x, out);
    return 0;
}

/* ---- the fit -------------------------------------------------------------------------- */

/* The report's precomputation: the pattern, the level's key and its
 * decomposition in numbers. */
static json_t *precomputation_report(const hfx_method *m, const method_fit_in *in)
{
    const hfx_decomp *g = level_decomp(m, in->levels[0]);
    json_t *pre = json_pack("{s:s, s:s, s:i, s:i, s:i, s:s, s:i, s:i, s:i, s:f, s:f, s:f}",
                            "pattern_hash", in->s->hash, "cache_key", in->keys[0], "samples",
                            in->s->n, "unknowns", g->n, "rows", g->rows, "form", g->form,
                            "numerical_rank", g->rank, "gauge_dims", g->gauge_dims,
                            "null_dims", g->null_dims, "rcond", g->rcond, "s_max", g->s_max,
                            "s_min_kept", g->s_min_kept);
    json_object_set_new(pre, "unreached", json_integer(g->unreached));
    json_object_set_new(pre, "operator_bytes",
                        json_integer((json_int_t)m->operator_bytes(in->levels[0])));
    return pre;
}

/* The report's seconds: the decomposition's those of this fit's
 * preparation when it did not build the level, else of the build (or of
 * the load from disk). */
static json_t *seconds_report(const hfx_method *m, const method_fit_in *in, double t0)
{
    const hfx_level *x = in->levels[0];
    const hfx_decomp *g = level_decomp(m, in->levels[0]);
    return json_pack("{s:f, s:f, s:f, s:f}", "samples", in->pattern_seconds, "design",
                     in->how[0] == CACHE_BUILT ? x->t_design : 0.0, "decomposition",
                     in->how[0] != CACHE_BUILT           ? in->spent[0]
                     : in->disk[0] == CACHE_DISK_LOADED ? x->t_load
                                                         : g->seconds,
                     "fit", glint_now() - t0);
}

/* The report's errors: the fit's statistics (view by view over the
 * samples' nviews views). */
static json_t *errors_report(const hfx_fit_stats *st, int nviews)
{
    return json_pack("{s:f, s:f, s:f, s:[i,i,i], s:f, s:I, s:o}", "rms_painted", st->rms,
                     "max_abs_painted", st->max_abs, "log_residual_rms", st->log_residual,
                     "clamped", st->clamped[0], st->clamped[1], st->clamped[2], "log_max",
                     st->log_max, "log_clamped", (json_int_t)st->log_clamped, "rms_by_view",
                     method_rms_by_view(st->view_se, st->view_n, nviews));
}

int hfx_method_fit(const hfx_method *m, const method_fit_in *in, material *out,
                   glint_err *err)
{
    void *fac = calloc(1, m->factors_size);
    hfx_fit_stats st;
    json_t *pre, *tim, *errs;
    double t0 = glint_now();
    int rc;

    memset(out, 0, sizeof *out);
    if (!fac)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = m->fit(in->params, in->levels[0], in->rgb, in->s->view, fac, &st, err))) {
        free(fac);
        return rc;
    }
    pre = precomputation_report(m, in);
    tim = seconds_report(m, in, t0);
    errs = errors_report(&st, in->s->nviews);
    material_init(out, m->self, fac,
                  json_pack("{s:o, s:o, s:o, s:o}", "params",
                            method_params_to_json(m->self, in->params), "precomputation", pre,
                            "seconds", tim, "errors", errs));
    return 0;
}

/* ---- the material --------------------------------------------------------------------- */

json_t *hfx_log_nodes_json(const double *v, int count)
{
    json_t *a = json_array();
    for (int k = 0; a && k < count; k++)
        json_array_append_new(a, json_pack("[f,f,f]", v[3 * (size_t)k], v[3 * (size_t)k + 1],
                                           v[3 * (size_t)k + 2]));
    return a;
}

int hfx_log_nodes_get(const json_t *a, int count, double *v, const char *file,
                      const char *what, glint_err *err)
{
    for (int k = 0; k < count; k++) {
        json_t *t = json_array_get(a, (size_t)k);
        for (int c = 0; c < 3; c++) {
            json_t *x = json_array_get(t, (size_t)c);
            double d = json_is_number(x) ? json_number_value(x) : NAN;
            if (!json_is_array(t) || json_array_size(t) != 3 || !isfinite(d) || fabs(d) > 700.0)
                return glint_err_set(err, GLINT_ENONFINITE,
                                     "%s: %s[%d] must be [r, g, b], finite numbers in "
                                     "[-700, 700]", file, what, k);
            v[3 * (size_t)k + c] = d;
        }
    }
    return 0;
}

int hfx_gpu_begin(material_gpu *g, const char *program, const char *frag_src, int w, int h,
                  glint_err *err)
{
    memset(g, 0, sizeof *g);
    g->program = program;
    g->frag_src = frag_src;
    g->tex_uniform = "u_factors";
    g->tex_w = w;
    g->tex_h = h;
    if (!(g->tex = calloc((size_t)w * h * 3, sizeof *g->tex)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the factor texture");
    return 0;
}

void hfx_gpu_mapping(material_gpu_uniform u[3], const hf_map *map, const double a_used[3],
                     hf_model model)
{
    u[0] = (material_gpu_uniform){"u_map_kind", "int", {(int)map->kind, 0, 0},
                                  "inverse mapping: 0 log, 1 add, 2 sub"};
    u[1] = (material_gpu_uniform){"u_a", "vec3", {a_used[0], a_used[1], a_used[2]},
                                  "mapping offset per channel"};
    u[2] = (material_gpu_uniform){"u_model_brdf", "int", {model == HF_MODEL_BRDF, 0, 0},
                                  "1: multiply by n.wi (brdf model)"};
}
