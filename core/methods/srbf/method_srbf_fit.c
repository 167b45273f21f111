/* method_srbf_fit.c: the srbf fit (method_srbf.h): per colour channel, the
 * constrained least-squares problem on the cached Gram matrices, over the
 * lobes the painted pixels reach, with the diffuse albedo given or fitted
 * as one more unknown. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_srbf.h"
#include "par.h"
#include "vmath.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int srbf_fit(const method_fit_in *in, material *out, glint_err *err);
int srbf_predict(const method_fit_in *in, const material *m, float *rgb, glint_err *err);

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
    const char *factor;        /* "kept" (from an earlier fit), "made" (kept from now), "none" */
    int tb_rows;               /* rows of T read for T'b (srbf_painted_tb) */
} chan_report;

/* One colour channel's problem and answer: the buffers are its own, so
 * channels are solved on threads at once (chan_task). */
typedef struct chan_job {
    const method_fit_in *in;
    int ch, nu;
    double *f, *H, *q, *u, *c, *c0;
    double *gc;                /* the solver's G c at the answer (nl) */
    const int *bins;           /* each energy row's elevation bin, shared */
    const double *G;           /* the energy rows on the unknowns, shared by the channels */
    const double *gmax, *Gt;   /* their row maxima and transpose (lsq_rows_check), shared */
    const double *gblk;        /* their block maxima (lsq_rows_blocks), shared */
    lsq_work *w;
    chan_report rep;
    double *csm;               /* sm.c (3 x J): this channel's J entries are written */
    double rho;                /* the channel's diffuse albedo (fitted or given) */
    double ss_res, ss_b, max_albedo, prof[NPROF];
    int rc;
    glint_err err;
} chan_job;

static void chan_free(chan_job *j)
{
    free(j->f);
    free(j->H);
    free(j->q);
    free(j->u);
    free(j->c);
    free(j->c0);
    free(j->gc);
    lsq_work_free(j->w);
}

static void chan_solve(chan_job *j)
{
    const method_fit_in *in = j->in;
    const srbf_params *p = in->params;
    const srbf_energy *en = in->levels[0];
    const srbf_visdata *vd = in->levels[2];
    const srbf_transfer_data *tr = in->levels[3];
    const samples *s = in->s;
    int J = tr->J, n = tr->nrows, nr = tr->nreach, nl = en->nl, ch = j->ch, nu = j->nu;
    int fitd = p->diffuse.fit;
    const int *idx = tr->idx;
    const double *LtL = tr->LtL;
    const double *Hc = tr->H + (size_t)ch * J * J, *TE = tr->TE + (size_t)ch * J;
    double rho = fitd ? 0.0 : p->diffuse.rgb[ch], ff = 0.0, trace = 0.0, ct0 = glint_now();
    double *f = j->f, *H, *q = j->q, *u = j->u, *c = j->c, smu = 0.0;
    const double *Hk;
    lsq_problem pr = {0};

    for (int b = 0; b < NPROF; b++)
        j->prof[b] = -1.0; /* no row in the bin */
    /* the painted radiance of each row, the given diffuse part off */
    for (int i = 0; i < n; i++) {
        int si = vd->rows[i];
        f[i] = (double)in->rgb[3 * (size_t)si + ch] * s->intensity[si] / p->env_intensity;
    }
    /* T'f = T'b - rho T'E: T'b from the rows a repaint changed, where the
     * level keeps the last painting */
    j->rep.tb_rows = srbf_painted_tb((srbf_transfer_data *)tr, ch, f, q);
    for (int a = 0; a < nr && rho != 0.0; a++)
        q[a] -= rho * TE[idx[a]];
    for (int i = 0; i < n; i++) {
        double b = f[i];
        f[i] = b - rho * tr->E[3 * (size_t)i + ch];
        ff += f[i] * f[i];
        j->ss_b += b * b;
    }
    for (int a = 0; a < nr; a++)
        trace += Hc[(size_t)idx[a] * J + idx[a]];
    if (p->smooth > 0.0)
        smu = p->smooth * trace / nr;
    /* H is the same for every painting with these parameters: the level
     * keeps it with its factor, and a repaint reads it there */
    if (!(Hk = srbf_kept_gram((srbf_transfer_data *)tr, p->smooth, fitd, ch))) {
        if (!(H = j->H = malloc((size_t)nu * nu * sizeof *H))) {
            j->rc = glint_err_set(&j->err, GLINT_ENOMEM, "out of memory for the fit (%d unknowns)",
                                  nu);
            return;
        }
        for (int a = 0; a < nr; a++)
            for (int b = 0; b < nr; b++)
                H[(size_t)a * nu + b] = Hc[(size_t)idx[a] * J + idx[b]];
        for (int a = 0; a < nr && smu > 0.0; a++)
            for (int b = 0; b < nr; b++)
                H[(size_t)a * nu + b] += smu * LtL[(size_t)a * nr + b];
        if (fitd) {
            for (int a = 0; a < nr; a++)
                H[(size_t)a * nu + nr] = H[(size_t)nr * nu + a] = TE[idx[a]];
            H[(size_t)nr * nu + nr] = tr->EE[ch];
        }
    }
    if (fitd) {
        double ef = 0.0;
        for (int i = 0; i < n; i++)
            ef += tr->E[3 * (size_t)i + ch] * f[i];
        q[nr] = ef;
    }
    for (int l = 0; l < nl; l++)
        u[l] = 1.0 - SRBF_ENERGY_MARGIN - rho;
    pr.n = nu;
    pr.H = Hk ? Hk : j->H;
    pr.q = q;
    pr.ff = ff;
    pr.m = p->constraints == LSQ_ENERGY ? nl : 0;
    pr.G = j->G;
    pr.u = u;
    pr.gmax = j->gmax;
    pr.gblk = j->gblk;
    pr.Gt = j->Gt;
    pr.gc = pr.m ? j->gc : NULL;
    /* the level keeps the factor of this H (the same for every repaint with
     * these parameters); the level is shared and otherwise read-only, the
     * factors behind its own lock */
    {
        int kept = 0;
        pr.R0 = srbf_kept_factor((srbf_transfer_data *)tr, p->smooth, fitd, ch, pr.H, nu, &kept);
        j->rep.factor = kept ? "kept" : pr.R0 ? "made" : "none";
    }
    /* a warm start: the answer of the last fit on this level (any
     * painting; the solver checks that it is feasible here) */
    if (p->start == SRBF_START_WARM && p->constraints != LSQ_NONE &&
        srbf_kept_start((srbf_transfer_data *)tr, p->smooth, fitd, ch, nu, j->c0))
        pr.c0 = j->c0;
    {
        double ts = glint_now();
        j->rc = lsq_solve(&pr, (lsq_mode)p->constraints, 0.0, j->w, c, &j->rep.r, &j->err);
        j->rep.solve_seconds = glint_now() - ts;
        if (j->rc)
            return;
    }
    if (j->rep.r.status == LSQ_INFEASIBLE)
        return;
    if (j->rep.r.status == LSQ_OK && p->constraints != LSQ_NONE)
        srbf_kept_answer((srbf_transfer_data *)tr, p->smooth, fitd, ch, nu, c);
    for (int a = 0; a < nr; a++)
        j->csm[(size_t)ch * J + idx[a]] = c[a];
    j->rho = fitd ? c[nr] : rho;
    j->rep.seconds = glint_now() - ct0;
    /* the painted rows' residual ||T x - f||^2 in the Gram form (no pass
     * over T): the solver's objective less the smoothness term */
    {
        double pen = 0.0;
        for (int a = 0; a < nr && smu > 0.0; a++)
            pen += c[a] * vmath_dot4(LtL + (size_t)a * nr, c, nr);
        j->ss_res = fmax(0.0, j->rep.r.objective - smu * pen);
    }
    /* the directional albedo at each energy row: the solver's G c where
     * it enforced the rows (G holds the diffuse albedo's column when that
     * is fitted), else computed here */
    for (int l = 0; l < nl; l++) {
        double al = pr.gc ? j->gc[l] + (fitd ? 0.0 : j->rho)
                          : j->rho + vmath_dot4(tr->G[0] + (size_t)l * nr, c, nr);
        int bn = j->bins[l];
        if (al > j->max_albedo)
            j->max_albedo = al;
        if (al > j->prof[bn])
            j->prof[bn] = al;
    }
    return;
}

static void chan_task(void *ctx, int ch)
{
    chan_solve((chan_job *)ctx + ch);
}

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
    chan_job jobs[3];
    chan_report rep[3];
    srbf_material sm;
    int *rowbin = NULL;
    json_t *info, *chans;
    int rc = 0;

    memset(&sm, 0, sizeof sm);
    memset(rep, 0, sizeof rep);
    memset(jobs, 0, sizeof jobs);
    if (nr == 0)
        return glint_err_set(err, GLINT_EINVAL,
                             "no lobe is reached by the painted pixels under this environment "
                             "(nothing is lit): paint a view the environment lights, or raise "
                             "env_intensity");
    if (!(sm.c = calloc((size_t)3 * J, sizeof *sm.c)) ||
        !(rowbin = malloc(((size_t)nl + 1) * sizeof *rowbin))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    for (int l = 0; l < nl; l++)
        rowbin[l] = prof_bin(en->wo + 3 * (size_t)l);
    for (int ch = 0; ch < 3; ch++) {
        chan_job *j = &jobs[ch];
        j->in = in;
        j->ch = ch;
        j->nu = nu;
        j->csm = sm.c;
        j->f = malloc((size_t)n * sizeof *j->f);
        j->q = malloc((size_t)nu * sizeof *j->q);
        j->u = malloc((size_t)nl * sizeof *j->u);
        j->c = malloc((size_t)nu * sizeof *j->c);
        j->c0 = malloc((size_t)nu * sizeof *j->c0);
        j->gc = malloc(((size_t)nl + 1) * sizeof *j->gc);
        j->bins = rowbin;
        j->w = lsq_work_new(nu, nl);
        /* the energy rows on the unknowns (the reached lobes, and the
         * diffuse albedo when fitted), made and checked with the level */
        j->G = tr->G[fitd ? 1 : 0];
        j->gmax = tr->gmax[fitd ? 1 : 0];
        j->gblk = tr->gblk[fitd ? 1 : 0];
        j->Gt = tr->Gt;
        if (!j->f || !j->q || !j->u || !j->c || !j->c0 || !j->gc || !j->w) {
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for the fit (%d unknowns)", nu);
            goto done;
        }
    }
    /* the three channels on the pool (par.h: one thread per core, the
     * caller's included; each takes the next channel when it is done).
     * Three threads of the fit's own on two cores left one waiting for
     * the scheduler when other work ran: measured here (bench_srbf
     * --table1, BENCHMARKS.md), the median fit then took a whole 4 ms
     * tick, against at most 2 ms on two threads.  The unconstrained mode
     * calls LAPACK, which has threads of its own. */
    if (p->constraints == LSQ_NONE)
        for (int ch = 0; ch < 3; ch++)
            chan_task(jobs, ch);
    else
        par_run(3, chan_task, jobs);
    for (int ch = 0; ch < 3; ch++) {
        chan_job *j = &jobs[ch];
        if (j->rc) {
            rc = j->rc;
            if (err)
                *err = j->err;
            goto done;
        }
        if (j->rep.r.status == LSQ_INFEASIBLE) {
            rc = glint_err_set(err, GLINT_EINVAL,
                               "channel %d: no material with a diffuse albedo of %g conserves "
                               "energy (energy row %d): lower the diffuse albedo below 1 or "
                               "set constraints nonneg",
                               ch, p->diffuse.rgb[ch], j->rep.r.infeasible_row);
            goto done;
        }
        rep[ch] = j->rep;
        sm.rho[ch] = j->rho;
        ss_res += j->ss_res;
        ss_b += j->ss_b;
        max_albedo = fmax(max_albedo, j->max_albedo);
        for (int b = 0; b < NPROF; b++)
            prof[b][ch] = j->prof[b];
    }
    /* what a material holds and reads back (method_srbf_material.c) */
    for (int k = 0; k < 3 * J + 3; k++) {
        double x = k < 3 * J ? sm.c[k] : sm.rho[k - 3 * J];
        if (!isfinite(x) || fabs(x) > SRBF_MAX_WEIGHT) {
            rc = glint_err_set(err, GLINT_ENUMERIC,
                               "the fitted %s is %g, beyond the %g a material holds: the "
                               "painting over env_intensity (%g) is out of scale",
                               k < 3 * J ? "lobe weight" : "diffuse albedo", x, SRBF_MAX_WEIGHT,
                               p->env_intensity);
            goto done;
        }
    }
    if ((rc = srbf_basis_make(en->b.res, en->b.sigma, &sm.b, err)))
        goto done;
    sm.st = en->st;
    chans = json_array();
    for (int ch = 0; ch < 3; ch++) {
        const lsq_result *r = &rep[ch].r;
        json_array_append_new(
            chans, json_pack("{s:s, s:i, s:i, s:i, s:f, s:f, s:f, s:f, s:f, s:f, s:s, s:i, s:s}",
                             "status",
                             lsq_status_name(r->status), "iterations", r->iterations,
                             "lobes_used", r->free_vars, "energy_rows_active", r->active_rows,
                             "objective", r->objective, "min_slack", r->min_slack,
                             "max_violation", r->max_violation, "kkt_residual",
                             r->kkt_residual, "seconds", rep[ch].seconds, "solve_seconds",
                             rep[ch].solve_seconds, "factor",
                             rep[ch].factor ? rep[ch].factor : "none", "tb_rows",
                             rep[ch].tb_rows, "start",
                             r->warm ? "warm" : "cold"));
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
    rc = srbf_material_init(out, &sm, info, err);
done:
    if (rc) {
        free(sm.c);
        srbf_basis_free(&sm.b);
    }
    for (int ch = 0; ch < 3; ch++)
        chan_free(&jobs[ch]);
    free(rowbin);
    return rc;
}

/* The model's painted values (method.predict): at each row, T c + rho E per
 * channel, in the painting's units (times env_intensity); NaN for samples
 * outside the fit grid (not rows). */
int srbf_predict(const method_fit_in *in, const material *m, float *rgb, glint_err *err)
{
    const srbf_params *p = in->params;
    const srbf_visdata *vd = in->levels[2];
    const srbf_transfer_data *tr = in->levels[3];
    const srbf_material *sm = srbf_material_of(m);
    const samples *s = in->s;
    int J = tr->J, n = tr->nrows;

    if (!sm || sm->b.J != J)
        return glint_err_set(err, GLINT_EINVAL,
                             "the material is not an srbf material of %d lobes", J);
    for (size_t i = 0; i < (size_t)3 * s->n; i++)
        rgb[i] = NAN;
    for (int i = 0; i < n; i++) {
        int si = vd->rows[i];
        for (int ch = 0; ch < 3; ch++) {
            const float *t = tr->T + ((size_t)ch * n + i) * J;
            const double *c = sm->c + (size_t)ch * J;
            double v = sm->rho[ch] * tr->E[3 * (size_t)i + ch];
            for (int a = 0; a < J; a++)
                v += (double)t[a] * c[a];
            rgb[3 * (size_t)si + ch] = (float)(v * p->env_intensity);
        }
    }
    return 0;
}
