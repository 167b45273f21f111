/* method_srbf_fit.c: the srbf fit (method_srbf.h): per colour channel, the
 * constrained least-squares problem on the cached Gram matrices, over the
 * lobes the painted pixels reach, with the diffuse albedo given or fitted
 * as one more unknown. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_srbf.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int srbf_fit(const method_fit_in *in, material *out, glint_err *err);

/* Elevation bins of the energy profile (degrees). */
static const double prof_edges[] = {0, 1, 3, 10, 20, 40, 60, 90};
#define NPROF ((int)(sizeof prof_edges / sizeof prof_edges[0]) - 1)

static int prof_bin(const double wo[3])
{
    double el = asin(wo[2] > 1.0 ? 1.0 : wo[2]) * 180.0 / M_PI;
    for (int b = 0; b < NPROF; b++)
        if (el <= prof_edges[b + 1])
            return b;
    return NPROF - 1;
}

typedef struct chan_report {
    lsq_result r;
    double seconds, solve_seconds;
} chan_report;

int srbf_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const srbf_params *p = in->params;
    const srbf_energy *en = in->levels[0];
    const srbf_lightset *ls = in->levels[1];
    const srbf_visdata *vd = in->levels[2];
    const srbf_transfer_data *tr = in->levels[3];
    const samples *s = in->s;
    int J = tr->J, n = tr->nrows, nr = tr->nreach, nl = en->nl;
    int fitd = p->diffuse.fit, nu = nr + (fitd ? 1 : 0);
    double t0 = glint_now(), ss_res = 0.0, ss_b = 0.0, max_albedo = 0.0;
    double prof[NPROF][3];
    const int *idx = tr->idx;
    double *f = malloc((size_t)n * sizeof *f);
    double *H = malloc((size_t)nu * nu * sizeof *H), *q = malloc((size_t)nu * sizeof *q);
    double *G = malloc((size_t)nl * nu * sizeof *G), *u = malloc((size_t)nl * sizeof *u);
    double *c = malloc((size_t)nu * sizeof *c);
    const double *LtL = tr->LtL;
    lsq_work *w = lsq_work_new(nu, nl);
    chan_report rep[3];
    srbf_material sm;
    json_t *info, *chans;
    int rc = 0;

    memset(&sm, 0, sizeof sm);
    memset(rep, 0, sizeof rep);
    for (int b = 0; b < NPROF; b++)
        prof[b][0] = prof[b][1] = prof[b][2] = -1.0; /* no row in the bin */
    if (!f || !H || !q || !G || !u || !c || !w) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the fit (%d unknowns)", nu);
        goto done;
    }
    if (nr == 0) {
        rc = glint_err_set(err, GLINT_EINVAL,
                           "no lobe is reached by the painted pixels under this environment "
                           "(nothing is lit): paint a view the environment lights, or raise "
                           "env_intensity");
        goto done;
    }
    if (!(sm.c = calloc((size_t)3 * J, sizeof *sm.c))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    for (int ch = 0; ch < 3; ch++) {
        const double *Hc = tr->H + (size_t)ch * J * J, *TE = tr->TE + (size_t)ch * J;
        const float *T = tr->T + (size_t)ch * n * J;
        double rho = fitd ? 0.0 : p->diffuse.rgb[ch], ff = 0.0, trace = 0.0, ct0 = glint_now();
        lsq_problem pr;

        /* the painted radiance of each row, the given diffuse part off */
        for (int i = 0; i < n; i++) {
            int si = vd->rows[i];
            double b = (double)in->rgb[3 * (size_t)si + ch] * s->intensity[si] / p->env_intensity;
            f[i] = b - rho * tr->E[3 * (size_t)i + ch];
            ff += f[i] * f[i];
        }
        /* q = T'f, streaming T row by row */
        memset(q, 0, (size_t)nu * sizeof *q);
        for (int i = 0; i < n; i++) {
            const float *t = T + (size_t)i * J;
            double fi = f[i];
            if (fi == 0.0)
                continue;
            for (int a = 0; a < nr; a++)
                q[a] += (double)t[idx[a]] * fi;
        }
        for (int a = 0; a < nr; a++) {
            for (int b = 0; b < nr; b++)
                H[(size_t)a * nu + b] = Hc[(size_t)idx[a] * J + idx[b]];
            trace += H[(size_t)a * nu + a];
        }
        if (p->smooth > 0.0) {
            double mu = p->smooth * trace / nr;
            for (int a = 0; a < nr; a++)
                for (int b = 0; b < nr; b++)
                    H[(size_t)a * nu + b] += mu * LtL[(size_t)a * nr + b];
        }
        if (fitd) {
            double ef = 0.0;
            for (int i = 0; i < n; i++)
                ef += tr->E[3 * (size_t)i + ch] * f[i];
            for (int a = 0; a < nr; a++)
                H[(size_t)a * nu + nr] = H[(size_t)nr * nu + a] = TE[idx[a]];
            H[(size_t)nr * nu + nr] = tr->EE[ch];
            q[nr] = ef;
        }
        for (int l = 0; l < nl; l++) {
            for (int a = 0; a < nr; a++)
                G[(size_t)l * nu + a] = en->g[(size_t)l * J + idx[a]];
            if (fitd)
                G[(size_t)l * nu + nr] = 1.0;
            u[l] = 1.0 - SRBF_ENERGY_MARGIN - rho;
        }
        pr.n = nu;
        pr.H = H;
        pr.q = q;
        pr.ff = ff;
        pr.m = p->constraints == LSQ_ENERGY ? nl : 0;
        pr.G = G;
        pr.u = u;
        {
            double ts = glint_now();
            rc = lsq_solve(&pr, (lsq_mode)p->constraints, 0.0, w, c, &rep[ch].r, err);
            rep[ch].solve_seconds = glint_now() - ts;
            if (rc)
                goto done;
        }
        if (rep[ch].r.status == LSQ_INFEASIBLE) {
            rc = glint_err_set(err, GLINT_EINVAL,
                               "channel %d: no material with a diffuse albedo of %g conserves "
                               "energy (energy row %d): lower the diffuse albedo below 1 or "
                               "set constraints nonneg",
                               ch, rho, rep[ch].r.infeasible_row);
            goto done;
        }
        for (int a = 0; a < nr; a++)
            sm.c[(size_t)ch * J + idx[a]] = c[a];
        sm.rho[ch] = fitd ? c[nr] : rho;
        rep[ch].seconds = glint_now() - ct0;
        /* the painted rows re-rendered */
        for (int i = 0; i < n; i++) {
            int si = vd->rows[i];
            double b = (double)in->rgb[3 * (size_t)si + ch] * s->intensity[si] / p->env_intensity;
            double m = sm.rho[ch] * tr->E[3 * (size_t)i + ch];
            const float *t = T + (size_t)i * J;
            for (int a = 0; a < nr; a++)
                m += (double)t[idx[a]] * c[a];
            ss_res += (m - b) * (m - b);
            ss_b += b * b;
        }
        for (int l = 0; l < nl; l++) {
            double al = sm.rho[ch];
            for (int a = 0; a < nr; a++)
                al += en->g[(size_t)l * J + idx[a]] * c[a];
            if (al > max_albedo)
                max_albedo = al;
            {
                int bn = prof_bin(en->wo + 3 * (size_t)l);
                if (al > prof[bn][ch])
                    prof[bn][ch] = al;
            }
        }
    }
    if ((rc = srbf_basis_make(en->b.res, en->b.sigma, &sm.b, err)))
        goto done;
    sm.st = en->st;
    chans = json_array();
    for (int ch = 0; ch < 3; ch++) {
        const lsq_result *r = &rep[ch].r;
        json_array_append_new(
            chans, json_pack("{s:s, s:i, s:i, s:i, s:f, s:f, s:f, s:f, s:f, s:f}", "status",
                             lsq_status_name(r->status), "iterations", r->iterations,
                             "lobes_used", r->free_vars, "energy_rows_active", r->active_rows,
                             "objective", r->objective, "min_slack", r->min_slack,
                             "max_violation", r->max_violation, "kkt_residual",
                             r->kkt_residual, "seconds", rep[ch].seconds, "solve_seconds",
                             rep[ch].solve_seconds));
    }
    {
        json_t *pre = json_pack(
            "{s:s, s:i, s:i, s:i, s:i, s:i, s:f, s:i, s:f, s:f, s:s, s:i, s:i, s:I, s:I, s:f}",
            "pattern_hash", s->hash, "rows", n, "samples", s->n, "lobes", J, "lobes_reached",
            nr, "lights", ls->l.k, "lambda", en->b.lambda, "energy_rows", nl,
            "compression_irradiance_rel_rms", ls->e.irradiance_rel_rms,
            "compression_glossy_rel_rms", ls->e.glossy_rel_rms, "environment", ls->name,
            "env_clamped_texels", (int)ls->clamped, "visibility", vd->on,
            (const char *)"rays", (json_int_t)tr->rays, "transfer_terms",
            (json_int_t)tr->terms, "diffuse_albedo_max", fmax(sm.rho[0], fmax(sm.rho[1],
                                                                               sm.rho[2])));
        json_object_set_new(pre, "cache_key", json_string(in->keys[3] ? in->keys[3] : ""));
        json_object_set_new(pre, "mesh_convex",
                            vd->convex < 0 ? json_null() : json_boolean(vd->convex));
        json_t *tim = json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f}", "energy",
                                in->how[0] == CACHE_BUILT ? en->seconds : in->spent[0],
                                "lights", ls->seconds, "visibility", tr->vis_seconds, "transfer",
                                tr->seconds, "gram", tr->gram_seconds, "samples",
                                in->pattern_seconds, "fit", glint_now() - t0);
        json_t *errs = json_pack("{s:f, s:f, s:f, s:o}", "rel_rms_painted",
                                 ss_b > 0.0 ? sqrt(ss_res / ss_b) : 0.0, "rms_painted",
                                 sqrt(ss_res / (3.0 * n)), "albedo_max_rows", max_albedo,
                                 "channels", chans);
        json_t *bins = json_array(), *alb = json_array();
        for (int b = 0; b < NPROF; b++) {
            json_array_append_new(bins, json_pack("[f,f]", prof_edges[b], prof_edges[b + 1]));
            json_array_append_new(alb, prof[b][0] < 0.0 ? json_null()
                                                        : json_pack("[f,f,f]", prof[b][0],
                                                                    prof[b][1], prof[b][2]));
        }
        json_object_set_new(errs, "energy_profile",
                            json_pack("{s:o, s:o, s:f, s:b}", "elevation_deg", bins,
                                      "albedo_max", alb, "limit", 1.0 - SRBF_ENERGY_MARGIN,
                                      "enforced", p->constraints == LSQ_ENERGY));
        json_t *diff = json_pack("{s:s, s:[f,f,f]}", "mode", fitd ? "fitted" : "given", "rgb",
                                 sm.rho[0], sm.rho[1], sm.rho[2]);
        info = json_pack("{s:o, s:o, s:o, s:o, s:o}", "params",
                         method_params_to_json(&method_srbf, p), "precomputation", pre,
                         "seconds", tim, "errors", errs, "diffuse", diff);
    }
    srbf_material_init(out, &sm, info);
done:
    if (rc) {
        free(sm.c);
        srbf_basis_free(&sm.b);
    }
    lsq_work_free(w);
    free(f);
    free(H);
    free(q);
    free(G);
    free(u);
    free(c);
    return rc;
}
