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

/* The channel's target: each row's painted radiance in units of the
 * environment's intensity, less the given diffuse part rho E (OUT: j->f,
 * its f'f in *ff and the painting's b'b in j->ss_b), and T'f = T'b -
 * rho T'E (OUT: j->q), T'b from the rows a repaint changed, where the
 * level keeps the last painting. */
static void chan_target(chan_job *j, double rho, double *ff)
{
    const method_fit_in *in = j->in;
    const srbf_params *p = in->params;
    const srbf_visdata *vd = in->levels[2];
    const srbf_transfer_data *tr = in->levels[3];
    const samples *s = in->s;
    int J = tr->J, n = tr->nrows, nr = tr->nreach, ch = j->ch;
    const int *idx = tr->idx;
    const double *TE = tr->TE + (size_t)ch * J;
    double *f = j->f, *q = j->q, sum = 0.0;

    for (int i = 0; i < n; i++) {
        int si = vd->rows[i];
        /* a held-out row is left out: b = 0 there adds nothing to T'b, E'b
         * or b'b, and its T and E are taken out of H (chan_gram_held) */
        f[i] = in->held && in->held[si]
                   ? 0.0
                   : (double)in->rgb[3 * (size_t)si + ch] * s->intensity[si] / p->env_intensity;
    }
    j->rep.tb_rows = srbf_painted_tb((srbf_transfer_data *)tr, ch, f, q);
    for (int a = 0; a < nr && rho != 0.0; a++)
        q[a] -= rho * TE[idx[a]];
    for (int i = 0; i < n && rho != 0.0 && in->held; i++) /* T'E over the rows read */
        if (in->held[vd->rows[i]]) {
            const float *t = tr->T + ((size_t)ch * n + i) * J;
            for (int a = 0; a < nr; a++)
                q[a] += rho * t[idx[a]] * tr->E[3 * (size_t)i + ch];
        }
    for (int i = 0; i < n; i++) {
        double b = f[i];
        if (in->held && in->held[vd->rows[i]])
            continue; /* f = 0: no residual there */
        f[i] = b - rho * tr->E[3 * (size_t)i + ch];
        sum += f[i] * f[i];
        j->ss_b += b * b;
    }
    *ff = sum;
}

/* The smoothness term's weight: the parameter times the mean diagonal of
 * the channel's Gram matrix over the reached lobes (of the rows the fit
 * reads; 0: no term). */
static double chan_smooth_weight(const chan_job *j)
{
    const srbf_params *p = j->in->params;
    const srbf_transfer_data *tr = j->in->levels[3];
    int J = tr->J, nr = tr->nreach;
    const double *Hc = tr->H + (size_t)j->ch * J * J;
    double trace = 0.0;
    for (int a = 0; a < nr; a++)
        trace += Hc[(size_t)tr->idx[a] * J + tr->idx[a]];
    if (j->in->held) { /* the Gram matrix of the rows read */
        const srbf_visdata *vd = j->in->levels[2];
        for (int i = 0; i < tr->nrows; i++)
            if (j->in->held[vd->rows[i]]) {
                const float *t = tr->T + ((size_t)j->ch * tr->nrows + i) * J;
                for (int a = 0; a < nr; a++)
                    trace -= (double)t[tr->idx[a]] * t[tr->idx[a]];
            }
    }
    return p->smooth > 0.0 ? p->smooth * trace / nr : 0.0;
}

/* H less the held-out rows' part (method_fit_in.held): each held row's
 * t t' on the reached lobes, and when the diffuse albedo is fitted its
 * t E and E^2, so that H is the Gram matrix of the rows the fit reads. */
static void chan_gram_held(const chan_job *j, double *H)
{
    const srbf_params *p = j->in->params;
    const srbf_visdata *vd = j->in->levels[2];
    const srbf_transfer_data *tr = j->in->levels[3];
    int J = tr->J, n = tr->nrows, nr = tr->nreach, ch = j->ch, nu = j->nu;
    const int *idx = tr->idx;
    for (int i = 0; i < n; i++) {
        const float *t = tr->T + ((size_t)ch * n + i) * J;
        double e = tr->E[3 * (size_t)i + ch];
        if (!j->in->held[vd->rows[i]])
            continue;
        for (int a = 0; a < nr; a++) {
            double ta = t[idx[a]];
            if (ta == 0.0)
                continue;
            for (int b = 0; b < nr; b++)
                H[(size_t)a * nu + b] -= ta * t[idx[b]];
        }
        if (p->diffuse.fit) {
            for (int a = 0; a < nr; a++) {
                H[(size_t)a * nu + nr] -= t[idx[a]] * e;
                H[(size_t)nr * nu + a] -= t[idx[a]] * e;
            }
            H[(size_t)nr * nu + nr] -= e * e;
        }
    }
}

/* H over the unknowns.  It is the same for every painting with these
 * parameters: the level keeps it with its factor, and a repaint reads it
 * there; else it is made here (OUT: j->H) from the channel's Gram matrix
 * on the reached lobes, the smoothness term smu L'L, and the diffuse
 * albedo's row and column when that is fitted.  NULL (j->rc set) when out
 * of memory. */
static const double *chan_gram(chan_job *j, double smu)
{
    const srbf_params *p = j->in->params;
    const srbf_transfer_data *tr = j->in->levels[3];
    int J = tr->J, nr = tr->nreach, ch = j->ch, nu = j->nu, fitd = p->diffuse.fit;
    const int *idx = tr->idx;
    const double *LtL = tr->LtL;
    const double *Hc = tr->H + (size_t)ch * J * J, *TE = tr->TE + (size_t)ch * J;
    const double *Hk;
    double *H;

    if (!j->in->held && (Hk = srbf_kept_gram((srbf_transfer_data *)tr, p->smooth, fitd, ch)))
        return Hk;
    if (!(H = j->H = malloc((size_t)nu * nu * sizeof *H))) {
        j->rc = glint_err_set(&j->err, GLINT_ENOMEM, "out of memory for the fit (%d unknowns)",
                              nu);
        return NULL;
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
    if (j->in->held)
        chan_gram_held(j, H);
    return H;
}

/* The rest of the solver's problem on H (pr->H): E'f as the diffuse
 * albedo's entry of q when that is fitted, the energy budgets 1 - margin
 * - rho, the shared rows and their tables, the level's factor of H, and
 * a warm start from the last fit's answer on this level (any painting;
 * the solver checks that it is feasible here). */
static void chan_problem(chan_job *j, double rho, double ff, lsq_problem *pr)
{
    const srbf_params *p = j->in->params;
    const srbf_energy *en = j->in->levels[0];
    const srbf_transfer_data *tr = j->in->levels[3];
    int n = tr->nrows, nr = tr->nreach, nl = en->nl, ch = j->ch, nu = j->nu;
    int fitd = p->diffuse.fit;

    if (fitd) {
        double ef = 0.0;
        for (int i = 0; i < n; i++)
            ef += tr->E[3 * (size_t)i + ch] * j->f[i];
        j->q[nr] = ef;
    }
    for (int l = 0; l < nl; l++)
        j->u[l] = 1.0 - SRBF_ENERGY_MARGIN - rho;
    pr->n = nu;
    pr->q = j->q;
    pr->ff = ff;
    pr->m = p->constraints == LSQ_ENERGY ? nl : 0;
    pr->G = j->G;
    pr->u = j->u;
    pr->gmax = j->gmax;
    pr->gblk = j->gblk;
    pr->Gt = j->Gt;
    pr->gc = pr->m ? j->gc : NULL;
    /* the level keeps the factor of this H (the same for every repaint with
     * these parameters); the level is shared and otherwise read-only, the
     * factors behind its own lock */
    if (j->in->held) { /* H of the rows read: a factor of its own, not kept */
        pr->R0 = NULL;
        j->rep.factor = "none";
    } else {
        int kept = 0;
        pr->R0 = srbf_kept_factor((srbf_transfer_data *)tr, p->smooth, fitd, ch, pr->H, nu, &kept);
        j->rep.factor = kept ? "kept" : pr->R0 ? "made" : "none";
    }
    if (p->start == SRBF_START_WARM && p->constraints != LSQ_NONE &&
        srbf_kept_start((srbf_transfer_data *)tr, p->smooth, fitd, ch, nu, j->c0))
        pr->c0 = j->c0;
}

/* The directional albedo at each energy row, its largest (OUT:
 * j->max_albedo) and the largest per elevation bin (OUT: j->prof, -1
 * where no row falls): the solver's G c where it enforced the rows (G
 * holds the diffuse albedo's column when that is fitted), else computed
 * here. */
static void chan_albedo(chan_job *j, const lsq_problem *pr)
{
    const srbf_params *p = j->in->params;
    const srbf_energy *en = j->in->levels[0];
    const srbf_transfer_data *tr = j->in->levels[3];
    int nr = tr->nreach, fitd = p->diffuse.fit;

    for (int b = 0; b < NPROF; b++)
        j->prof[b] = -1.0; /* no row in the bin */
    for (int l = 0; l < en->nl; l++) {
        double al = pr->gc ? j->gc[l] + (fitd ? 0.0 : j->rho)
                           : j->rho + vmath_dot4(tr->G[0] + (size_t)l * nr, j->c, nr);
        int bn = j->bins[l];
        if (al > j->max_albedo)
            j->max_albedo = al;
        if (al > j->prof[bn])
            j->prof[bn] = al;
    }
}

/* One channel: its target, H and problem, the constrained solve, and its
 * answer (the lobe weights into j->csm, the diffuse albedo, the residual
 * and the albedo at the energy rows).  OUT: j->rc, j->rep. */
static void chan_solve(chan_job *j)
{
    const srbf_params *p = j->in->params;
    const srbf_transfer_data *tr = j->in->levels[3];
    int J = tr->J, nr = tr->nreach, ch = j->ch, nu = j->nu, fitd = p->diffuse.fit;
    const double *LtL = tr->LtL;
    double rho = fitd ? 0.0 : p->diffuse.rgb[ch], ff = 0.0, smu, ct0 = glint_now();
    double *c = j->c;
    lsq_problem pr = {0};

    chan_target(j, rho, &ff);
    smu = chan_smooth_weight(j);
    if (!(pr.H = chan_gram(j, smu)))
        return;
    chan_problem(j, rho, ff, &pr);
    {
        double ts = glint_now();
        j->rc = lsq_solve(&pr, (lsq_mode)p->constraints, 0.0, j->w, c, &j->rep.r, &j->err);
        j->rep.solve_seconds = glint_now() - ts;
        if (j->rc)
            return;
    }
    if (j->rep.r.status == LSQ_INFEASIBLE)
        return;
    if (j->rep.r.status == LSQ_OK && p->constraints != LSQ_NONE && !j->in->held)
        srbf_kept_answer((srbf_transfer_data *)tr, p->smooth, fitd, ch, nu, c);
    for (int a = 0; a < nr; a++)
        j->csm[(size_t)ch * J + tr->idx[a]] = c[a];
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
    chan_albedo(j, &pr);
}

static void chan_task(void *ctx, int ch)
{
    chan_solve((chan_job *)ctx + ch);
}

/* What the channels' answers add up to. */
typedef struct fit_sums {
    chan_report rep[3];
    double ss_res, ss_b;       /* the painted rows' residual and painting, all channels */
    double max_albedo;         /* at the energy rows, all channels */
    double prof[NPROF][3];     /* the largest albedo per elevation bin and channel */
} fit_sums;

/* Each channel's job: its buffers and solver workspace, and the energy
 * rows on the unknowns (the reached lobes, and the diffuse albedo when
 * fitted), made and checked with the level and shared. */
static int jobs_init(const method_fit_in *in, chan_job *jobs, double *csm, const int *rowbin,
                     int nu, glint_err *err)
{
    const srbf_params *p = in->params;
    const srbf_energy *en = in->levels[0];
    const srbf_transfer_data *tr = in->levels[3];
    int n = tr->nrows, nl = en->nl, fitd = p->diffuse.fit;
    for (int ch = 0; ch < 3; ch++) {
        chan_job *j = &jobs[ch];
        j->in = in;
        j->ch = ch;
        j->nu = nu;
        j->csm = csm;
        j->f = malloc((size_t)n * sizeof *j->f);
        j->q = malloc((size_t)nu * sizeof *j->q);
        j->u = malloc((size_t)nl * sizeof *j->u);
        j->c = malloc((size_t)nu * sizeof *j->c);
        j->c0 = malloc((size_t)nu * sizeof *j->c0);
        j->gc = malloc(((size_t)nl + 1) * sizeof *j->gc);
        j->bins = rowbin;
        j->w = lsq_work_new(nu, nl);
        j->G = tr->G[fitd ? 1 : 0];
        j->gmax = tr->gmax[fitd ? 1 : 0];
        j->gblk = tr->gblk[fitd ? 1 : 0];
        j->Gt = tr->Gt;
        if (!j->f || !j->q || !j->u || !j->c || !j->c0 || !j->gc || !j->w)
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for the fit (%d unknowns)",
                                 nu);
    }
    return 0;
}

/* The channels' answers, in channel order: the first that failed or found
 * no feasible material fails the fit; else the diffuse albedos (OUT:
 * sm->rho) and the sums. */
static int jobs_gather(const srbf_params *p, const chan_job *jobs, srbf_material *sm,
                       fit_sums *fs, glint_err *err)
{
    for (int ch = 0; ch < 3; ch++) {
        const chan_job *j = &jobs[ch];
        if (j->rc) {
            if (err)
                *err = j->err;
            return j->rc;
        }
        if (j->rep.r.status == LSQ_INFEASIBLE)
            return glint_err_set(err, GLINT_EINVAL,
                                 "channel %d: no material with a diffuse albedo of %g conserves "
                                 "energy (energy row %d): lower the diffuse albedo below 1 or "
                                 "set constraints nonneg",
                                 ch, p->diffuse.rgb[ch], j->rep.r.infeasible_row);
        fs->rep[ch] = j->rep;
        sm->rho[ch] = j->rho;
        fs->ss_res += j->ss_res;
        fs->ss_b += j->ss_b;
        fs->max_albedo = fmax(fs->max_albedo, j->max_albedo);
        for (int b = 0; b < NPROF; b++)
            fs->prof[b][ch] = j->prof[b];
    }
    return 0;
}

/* What a material holds and reads back (method_srbf_material.c): finite
 * weights and albedos within SRBF_MAX_WEIGHT. */
static int weights_check(const srbf_material *sm, int J, const srbf_params *p, glint_err *err)
{
    for (int k = 0; k < 3 * J + 3; k++) {
        double x = k < 3 * J ? sm->c[k] : sm->rho[k - 3 * J];
        if (!isfinite(x) || fabs(x) > SRBF_MAX_WEIGHT)
            return glint_err_set(err, GLINT_ENUMERIC,
                                 "the fitted %s is %g, beyond the %g a material holds: the "
                                 "painting over env_intensity (%g) is out of scale",
                                 k < 3 * J ? "lobe weight" : "diffuse albedo", x, SRBF_MAX_WEIGHT,
                                 p->env_intensity);
    }
    return 0;
}

/* The solver's report per channel. */
static json_t *channels_json(const fit_sums *fs)
{
    json_t *chans = json_array();
    for (int ch = 0; ch < 3; ch++) {
        const chan_report *rp = &fs->rep[ch];
        const lsq_result *r = &rp->r;
        json_array_append_new(
            chans, json_pack("{s:s, s:i, s:i, s:i, s:f, s:f, s:f, s:f, s:f, s:f, s:s, s:i, s:s}",
                             "status",
                             lsq_status_name(r->status), "iterations", r->iterations,
                             "lobes_used", r->free_vars, "energy_rows_active", r->active_rows,
                             "objective", r->objective, "min_slack", r->min_slack,
                             "max_violation", r->max_violation, "kkt_residual",
                             r->kkt_residual, "seconds", rp->seconds, "solve_seconds",
                             rp->solve_seconds, "factor",
                             rp->factor ? rp->factor : "none", "tb_rows",
                             rp->tb_rows, "start",
                             r->warm ? "warm" : "cold"));
    }
    return chans;
}

/* The precomputation the fit stood on: the pattern, lobes, lights and
 * environment, visibility and transfer, the cache key. */
static json_t *precomputation_json(const method_fit_in *in, const srbf_material *sm)
{
    const srbf_energy *en = in->levels[0];
    const srbf_lightset *ls = in->levels[1];
    const srbf_visdata *vd = in->levels[2];
    const srbf_transfer_data *tr = in->levels[3];
    json_t *pre = json_pack(
        "{s:s, s:i, s:i, s:i, s:i, s:i, s:f, s:i, s:f, s:f, s:s, s:i, s:i, s:I, s:I, s:f}",
        "pattern_hash", in->s->hash, "rows", tr->nrows, "samples", in->s->n, "lobes", tr->J,
        "lobes_reached", tr->nreach, "lights", ls->l.k, "lambda", en->b.lambda, "energy_rows",
        en->nl, "compression_irradiance_rel_rms", ls->e.irradiance_rel_rms,
        "compression_glossy_rel_rms", ls->e.glossy_rel_rms, "environment", ls->name,
        "env_clamped_texels", (int)ls->clamped, "visibility", vd->on,
        (const char *)"rays", (json_int_t)tr->rays, "transfer_terms",
        (json_int_t)tr->terms, "diffuse_albedo_max", fmax(sm->rho[0], fmax(sm->rho[1],
                                                                            sm->rho[2])));
    json_object_set_new(pre, "cache_key", json_string(in->keys[3] ? in->keys[3] : ""));
    json_object_set_new(pre, "mesh_convex",
                        vd->convex < 0 ? json_null() : json_boolean(vd->convex));
    return pre;
}

/* The errors on the painted rows, the albedo at the energy rows and its
 * profile by elevation, and the channels' reports (chans, taken). */
static json_t *errors_json(const method_fit_in *in, const fit_sums *fs, json_t *chans)
{
    const srbf_params *p = in->params;
    const srbf_transfer_data *tr = in->levels[3];
    const srbf_visdata *vd = in->levels[2];
    int n = tr->nrows, held = 0;
    json_t *errs;
    for (int i = 0; i < tr->nrows && in->held; i++)
        held += in->held[vd->rows[i]] != 0;
    n -= held; /* the rows the fit read */
    errs = json_pack("{s:f, s:f, s:f, s:o}", "rel_rms_painted",
                             fs->ss_b > 0.0 ? sqrt(fs->ss_res / fs->ss_b) : 0.0, "rms_painted",
                             n ? sqrt(fs->ss_res / (3.0 * n)) : 0.0, "albedo_max_rows",
                             fs->max_albedo, "channels", chans);
    json_t *bins = json_array(), *alb = json_array();
    if (in->held)
        json_object_set_new(errs, "rows_held_out", json_integer(held));
    for (int b = 0; b < NPROF; b++) {
        json_array_append_new(bins, json_pack("[f,f]", prof_edges[b], prof_edges[b + 1]));
        json_array_append_new(alb, fs->prof[b][0] < 0.0
                                       ? json_null()
                                       : json_pack("[f,f,f]", fs->prof[b][0], fs->prof[b][1],
                                                   fs->prof[b][2]));
    }
    json_object_set_new(errs, "energy_profile",
                        json_pack("{s:o, s:o, s:f, s:b}", "elevation_deg", bins,
                                  "albedo_max", alb, "limit", 1.0 - SRBF_ENERGY_MARGIN,
                                  "enforced", p->constraints == LSQ_ENERGY));
    return errs;
}

/* The material's info: parameters, precomputation, times (the fit's from
 * t0), errors and the diffuse albedo. */
static json_t *fit_info(const method_fit_in *in, const srbf_material *sm, const fit_sums *fs,
                        double t0)
{
    const srbf_params *p = in->params;
    const srbf_energy *en = in->levels[0];
    const srbf_lightset *ls = in->levels[1];
    const srbf_transfer_data *tr = in->levels[3];
    json_t *chans = channels_json(fs);
    json_t *pre = precomputation_json(in, sm);
    json_t *tim = json_pack("{s:f, s:f, s:f, s:f, s:f, s:f, s:f}", "energy",
                            in->how[0] == CACHE_BUILT ? en->seconds : in->spent[0],
                            "lights", ls->seconds, "visibility", tr->vis_seconds, "transfer",
                            tr->seconds, "gram", tr->gram_seconds, "samples",
                            in->pattern_seconds, "fit", glint_now() - t0);
    json_t *errs = errors_json(in, fs, chans);
    json_t *diff = json_pack("{s:s, s:[f,f,f]}", "mode", p->diffuse.fit ? "fitted" : "given",
                             "rgb", sm->rho[0], sm->rho[1], sm->rho[2]);
    return json_pack("{s:o, s:o, s:o, s:o, s:o}", "params",
                     method_params_to_json(&method_srbf, p), "precomputation", pre,
                     "seconds", tim, "errors", errs, "diffuse", diff);
}

int srbf_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const srbf_params *p = in->params;
    const srbf_energy *en = in->levels[0];
    const srbf_transfer_data *tr = in->levels[3];
    int J = tr->J, nr = tr->nreach, nl = en->nl;
    int nu = nr + (p->diffuse.fit ? 1 : 0);
    double t0 = glint_now();
    chan_job jobs[3];
    fit_sums fs;
    srbf_material sm;
    int *rowbin = NULL;
    int rc = 0;

    memset(&sm, 0, sizeof sm);
    memset(&fs, 0, sizeof fs);
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
    if ((rc = jobs_init(in, jobs, sm.c, rowbin, nu, err)))
        goto done;
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
    if ((rc = jobs_gather(p, jobs, &sm, &fs, err)) || (rc = weights_check(&sm, J, p, err)) ||
        (rc = srbf_basis_make(en->b.res, en->b.sigma, &sm.b, err)))
        goto done;
    sm.st = en->st;
    rc = srbf_material_init(out, &sm, fit_info(in, &sm, &fs, t0), err);
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
