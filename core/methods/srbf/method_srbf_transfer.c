/* method_srbf_transfer.c: the srbf method's transfer level (method_srbf.h):
 * shadow rays, transfer matrices, their Gram matrices and the smoothness
 * prior's L'L over the lobes the rows reach. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_srbf.h"
#include "vis.h"

static void progress(const method_build_in *in, const char *stage, double f)
{
    if (in->progress)
        in->progress(in->progress_cls, stage, f);
}

/* ---- transfer ------------------------------------------------------------------------- */

void srbf_transfer_clear(srbf_transfer_data *x)
{
    if (!x)
        return;
    free(x->T);
    free(x->E);
    free(x->H);
    free(x->TE);
    free(x->reach);
    free(x->idx);
    free(x->LtL);
    for (int k = 0; k < 2; k++) {
        free(x->G[k]);
        free(x->gmax[k]);
        free(x->gblk[k]);
    }
    free(x->Gt);
    for (int k = 0; k < x->nkept; k++)
        for (int ch = 0; ch < 3; ch++) {
            free(x->kept[k].R[ch]);
            free(x->kept[k].H[ch]);
            free(x->kept[k].c[ch]);
        }
    for (int ch = 0; ch < 3; ch++) {
        free(x->tb_b[ch]);
        free(x->tb_q[ch]);
    }
    if (x->kept_init) {
        pthread_mutex_destroy(&x->kept_lock);
        for (int ch = 0; ch < 3; ch++)
            pthread_mutex_destroy(&x->tb_lock[ch]);
    }
    memset(x, 0, sizeof *x);
}

size_t srbf_transfer_bytes(const srbf_transfer_data *x)
{
    size_t J = (size_t)x->J, n = (size_t)x->nrows;
    size_t nr = (size_t)x->nreach;
    return sizeof *x + 3 * n * J * sizeof(float) + 3 * n * sizeof(double) +
           4 * J * J * sizeof(double) + 3 * J * sizeof(double) + J * (1 + sizeof(int)) +
           (size_t)x->nl_rows * (3 * nr + 4) * sizeof(double) +
           (size_t)x->nl_rows * 4 * LSQ_NBLK(nr + 1) * sizeof(double) +
           /* kept per slot and channel: R and H (nu x nu) and c (nu) */
           (size_t)SRBF_KEPT_MAX * 3 * (2 * (nr + 1) + 1) * (nr + 1) * sizeof(double) +
           3 * (n + nr) * sizeof(double);
}

static void transfer_free(void *d)
{
    srbf_transfer_clear(d);
    free(d);
}

/* The graph Laplacian of the lobe centres over the reached lobes (OUT:
 * LtL[n x n], n = count of idx): each centre is joined to its 6 nearest
 * reached neighbours with weight 1; L = D - W; LtL = L'L. */
static void laplacian_gram(const srbf_basis *b, const int *idx, int n, double *LtL)
{
    enum { NB = 6 };
    double *L = calloc((size_t)n * n, sizeof *L);
    if (!L) {
        memset(LtL, 0, (size_t)n * n * sizeof *LtL);
        return;
    }
    for (int a = 0; a < n; a++) {
        int best[NB];
        double bd[NB];
        int nb = 0;
        const double *xa = b->xi + 3 * idx[a];
        for (int k = 0; k < n; k++) {
            const double *xk = b->xi + 3 * idx[k];
            double d;
            int pos;
            if (k == a)
                continue;
            d = -(xa[0] * xk[0] + xa[1] * xk[1] + xa[2] * xk[2]);
            if (nb == NB && d >= bd[NB - 1])
                continue;
            pos = nb < NB ? nb++ : NB - 1;
            while (pos > 0 && bd[pos - 1] > d) {
                bd[pos] = bd[pos - 1];
                best[pos] = best[pos - 1];
                pos--;
            }
            bd[pos] = d;
            best[pos] = k;
        }
        for (int q = 0; q < nb; q++) {
            L[(size_t)a * n + best[q]] -= 1.0;
            L[(size_t)a * n + a] += 1.0;
        }
    }
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double s = 0.0;
            for (int k = 0; k < n; k++)
                s += L[(size_t)k * n + i] * L[(size_t)k * n + j];
            LtL[(size_t)i * n + j] = s;
        }
    free(L);
}

int srbf_transfer_reach(srbf_transfer_data *x, const srbf_energy *en, glint_err *err)
{
    int k = 0, nr, nl = en->nl, J = x->J;
    size_t n1;
    x->nreach = 0;
    for (int j = 0; j < J; j++)
        x->nreach += x->reach[j] != 0;
    nr = x->nreach;
    n1 = (size_t)nr + 1;
    free(x->idx);
    free(x->LtL);
    x->idx = malloc((size_t)(nr ? nr : 1) * sizeof *x->idx);
    x->LtL = malloc((size_t)(nr ? nr * nr : 1) * sizeof *x->LtL);
    for (int a = 0; a < 2; a++) {
        free(x->G[a]);
        free(x->gmax[a]);
        free(x->gblk[a]);
        x->G[a] = malloc(((size_t)nl * n1 + 1) * sizeof *x->G[a]);
        x->gmax[a] = malloc(((size_t)nl + 1) * sizeof *x->gmax[a]);
        x->gblk[a] = malloc(((size_t)nl * 2 * LSQ_NBLK(n1) + 1) * sizeof *x->gblk[a]);
    }
    free(x->Gt);
    x->Gt = malloc(((size_t)nl * n1 + 1) * sizeof *x->Gt);
    x->nl_rows = nl;
    if (!x->kept_init && pthread_mutex_init(&x->kept_lock, NULL) == 0) {
        int ch = 0;
        while (ch < 3 && pthread_mutex_init(&x->tb_lock[ch], NULL) == 0)
            ch++;
        if (ch == 3)
            x->kept_init = 1;
        else {
            while (ch-- > 0)
                pthread_mutex_destroy(&x->tb_lock[ch]);
            pthread_mutex_destroy(&x->kept_lock);
        }
    }
    if (!x->kept_init || !x->idx || !x->LtL || !x->G[0] || !x->G[1] || !x->gmax[0] ||
        !x->gmax[1] || !x->gblk[0] || !x->gblk[1] || !x->Gt)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int j = 0; j < J; j++)
        if (x->reach[j])
            x->idx[k++] = j;
    if (nr)
        laplacian_gram(&en->b, x->idx, nr, x->LtL);
    /* the energy rows of every fit on this level, checked once */
    for (int l = 0; l < nl; l++) {
        double *g0 = x->G[0] + (size_t)l * nr, *g1 = x->G[1] + (size_t)l * n1;
        for (int a = 0; a < nr; a++)
            g0[a] = g1[a] = en->g[(size_t)l * J + x->idx[a]];
        g1[nr] = 1.0;
    }
    {
        int rc = lsq_rows_check(x->G[0], nl, nr, x->gmax[0], NULL, err);
        if (!rc)
            rc = lsq_rows_check(x->G[1], nl, nr + 1, x->gmax[1], x->Gt, err);
        if (!rc) {
            lsq_rows_blocks(x->G[0], nl, nr, x->gblk[0]);
            lsq_rows_blocks(x->G[1], nl, nr + 1, x->gblk[1]);
        }
        return rc;
    }
}

const double *srbf_kept_factor(srbf_transfer_data *x, double smooth, int fitd, int ch,
                               const double *H, int nu, int *kept)
{
    const double *R = NULL;
    double *made, *Hc = NULL;
    int k, full;
    *kept = 0;
    if (!x->kept_init)
        return NULL;
    pthread_mutex_lock(&x->kept_lock);
    for (k = 0; k < x->nkept; k++)
        if (x->kept[k].smooth == smooth && x->kept[k].fitd == fitd)
            break;
    if (k < x->nkept)
        R = x->kept[k].R[ch];
    full = k == SRBF_KEPT_MAX;
    pthread_mutex_unlock(&x->kept_lock);
    *kept = R != NULL;
    if (R || full)
        return R;
    /* made outside the lock (the channels make theirs at once); a factor
     * another fit kept meanwhile wins */
    if (!(made = malloc((size_t)nu * nu * sizeof *made)) || lsq_factor(H, nu, made, NULL) ||
        !(Hc = malloc((size_t)nu * nu * sizeof *Hc))) {
        free(made);
        return NULL;
    }
    memcpy(Hc, H, (size_t)nu * nu * sizeof *Hc);
    pthread_mutex_lock(&x->kept_lock);
    for (k = 0; k < x->nkept; k++)
        if (x->kept[k].smooth == smooth && x->kept[k].fitd == fitd)
            break;
    if (k == x->nkept && k < SRBF_KEPT_MAX) {
        x->kept[k].smooth = smooth;
        x->kept[k].fitd = fitd;
        memset(x->kept[k].R, 0, sizeof x->kept[k].R);
        memset(x->kept[k].H, 0, sizeof x->kept[k].H);
        memset(x->kept[k].c, 0, sizeof x->kept[k].c);
        x->nkept++;
    }
    if (k < x->nkept) {
        if (!x->kept[k].R[ch]) {
            x->kept[k].R[ch] = made;
            x->kept[k].H[ch] = Hc;
            made = Hc = NULL;
        }
        R = x->kept[k].R[ch];
    }
    pthread_mutex_unlock(&x->kept_lock);
    free(made);
    free(Hc);
    return R;
}

const double *srbf_kept_gram(srbf_transfer_data *x, double smooth, int fitd, int ch)
{
    const double *H = NULL;
    if (!x->kept_init)
        return NULL;
    pthread_mutex_lock(&x->kept_lock);
    for (int k = 0; k < x->nkept; k++)
        if (x->kept[k].smooth == smooth && x->kept[k].fitd == fitd)
            H = x->kept[k].H[ch];
    pthread_mutex_unlock(&x->kept_lock);
    return H;
}

static int kept_find(const srbf_transfer_data *x, double smooth, int fitd)
{
    for (int k = 0; k < x->nkept; k++)
        if (x->kept[k].smooth == smooth && x->kept[k].fitd == fitd)
            return k;
    return -1;
}

int srbf_kept_start(srbf_transfer_data *x, double smooth, int fitd, int ch, int nu, double *c0)
{
    int k, got = 0;
    if (!x->kept_init)
        return 0;
    pthread_mutex_lock(&x->kept_lock);
    if ((k = kept_find(x, smooth, fitd)) >= 0 && x->kept[k].c[ch]) {
        memcpy(c0, x->kept[k].c[ch], (size_t)nu * sizeof *c0);
        got = 1;
    }
    pthread_mutex_unlock(&x->kept_lock);
    return got;
}

void srbf_kept_answer(srbf_transfer_data *x, double smooth, int fitd, int ch, int nu,
                      const double *c)
{
    int k;
    if (!x->kept_init)
        return;
    pthread_mutex_lock(&x->kept_lock);
    if ((k = kept_find(x, smooth, fitd)) >= 0) {
        if (!x->kept[k].c[ch])
            x->kept[k].c[ch] = malloc((size_t)nu * sizeof *c);
        if (x->kept[k].c[ch])
            memcpy(x->kept[k].c[ch], c, (size_t)nu * sizeof *c);
    }
    pthread_mutex_unlock(&x->kept_lock);
}

/* q += T_i' w_i over rows i (all n rows when rows is NULL): four rows per
 * pass, so q is loaded and stored once per four products (a pass per row
 * is bound by those loads and stores, not by reading T) */
static void tb_add(const float *T, int J, int nr, const int *idx, const int *rows, int n,
                   const double *w, double *q)
{
    if (nr == J) { /* every lobe reached, the common case: contiguous, vectorized */
        double *restrict qq = q;
        int k = 0;
        for (; k + 4 <= n; k += 4) {
            int i0 = rows ? rows[k] : k, i1 = rows ? rows[k + 1] : k + 1;
            int i2 = rows ? rows[k + 2] : k + 2, i3 = rows ? rows[k + 3] : k + 3;
            const float *restrict t0 = T + (size_t)i0 * J, *restrict t1 = T + (size_t)i1 * J,
                                  *restrict t2 = T + (size_t)i2 * J,
                                  *restrict t3 = T + (size_t)i3 * J;
            double w0 = w[i0], w1 = w[i1], w2 = w[i2], w3 = w[i3];
#pragma omp simd
            for (int a = 0; a < J; a++)
                qq[a] += ((double)t0[a] * w0 + (double)t1[a] * w1) +
                         ((double)t2[a] * w2 + (double)t3[a] * w3);
        }
        for (; k < n; k++) {
            int i = rows ? rows[k] : k;
            const float *restrict t = T + (size_t)i * J;
            double wi = w[i];
#pragma omp simd
            for (int a = 0; a < J; a++)
                qq[a] += (double)t[a] * wi;
        }
        return;
    }
    for (int k = 0; k < n; k++) {
        int i = rows ? rows[k] : k;
        const float *t = T + (size_t)i * J;
        double wi = w[i];
        if (wi == 0.0)
            continue;
        for (int a = 0; a < nr; a++)
            q[a] += (double)t[idx[a]] * wi;
    }
}

int srbf_painted_tb(srbf_transfer_data *x, int ch, const double *b, double *q)
{
    int n = x->nrows, J = x->J, nr = x->nreach, read = n;
    const float *T = x->T + (size_t)ch * n * J;
    double *d = NULL;
    int *rows = NULL;

    if (!x->kept_init) {
        memset(q, 0, (size_t)nr * sizeof *q);
        tb_add(T, J, nr, x->idx, NULL, n, b, q);
        return n;
    }
    pthread_mutex_lock(&x->tb_lock[ch]);
    if (x->tb_b[ch] && x->tb_updates[ch] < SRBF_TB_REFRESH &&
        (d = malloc((size_t)n * sizeof *d)) && (rows = malloc((size_t)n * sizeof *rows))) {
        const double *ob = x->tb_b[ch];
        int nd = 0;
        for (int i = 0; i < n && nd <= n / 4; i++)
            if (b[i] != ob[i]) { /* exact: an unchanged row adds nothing */
                d[i] = b[i] - ob[i];
                rows[nd++] = i;
            }
        if (nd <= n / 4) {
            memcpy(q, x->tb_q[ch], (size_t)nr * sizeof *q);
            tb_add(T, J, nr, x->idx, rows, nd, d, q);
            x->tb_updates[ch] += nd > 0;
            read = nd;
        }
    }
    if (read == n) {
        memset(q, 0, (size_t)nr * sizeof *q);
        tb_add(T, J, nr, x->idx, NULL, n, b, q);
        x->tb_updates[ch] = 0;
    }
    if (!x->tb_b[ch]) {
        x->tb_b[ch] = malloc((size_t)n * sizeof *b);
        x->tb_q[ch] = malloc((size_t)nr * sizeof *q + 1);
    }
    if (x->tb_b[ch] && x->tb_q[ch]) {
        memcpy(x->tb_b[ch], b, (size_t)n * sizeof *b);
        memcpy(x->tb_q[ch], q, (size_t)nr * sizeof *q);
    } else { /* nothing kept: the next call passes over every row */
        free(x->tb_b[ch]);
        free(x->tb_q[ch]);
        x->tb_b[ch] = x->tb_q[ch] = NULL;
    }
    pthread_mutex_unlock(&x->tb_lock[ch]);
    free(d);
    free(rows);
    return read;
}

/* H = T'T, T'E and E'E per channel, in double, from the float T (cancel
 * asked between rows, cancel.h). */
static int transfer_gram(srbf_transfer_data *x, const glint_cancel *cancel, glint_err *err)
{
    int J = x->J, n = x->nrows;
    long every = glint_cancel_every((long)J * (J + 1) / 2);
    double *row = malloc((size_t)J * sizeof *row);
    if (!row)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    memset(x->H, 0, (size_t)3 * J * J * sizeof *x->H);
    memset(x->TE, 0, (size_t)3 * J * sizeof *x->TE);
    for (int ch = 0; ch < 3; ch++) {
        double *H = x->H + (size_t)ch * J * J, *TE = x->TE + (size_t)ch * J, ee = 0.0;
        for (int i = 0; i < n; i++) {
            const float *t = x->T + ((size_t)ch * n + i) * J;
            double e = x->E[3 * (size_t)i + ch];
            int nz = 0;
            if (i % every == 0 && glint_cancelled(cancel)) {
                free(row);
                return glint_cancel_err(err, "the Gram matrices");
            }
            for (int j = 0; j < J; j++) {
                row[j] = t[j];
                nz |= t[j] != 0.0f;
            }
            ee += e * e;
            if (!nz)
                continue;
            for (int a = 0; a < J; a++) {
                double ra = row[a];
                if (ra == 0.0)
                    continue;
                TE[a] += ra * e;
                for (int b = a; b < J; b++)
                    H[(size_t)a * J + b] += ra * row[b];
            }
        }
        for (int a = 0; a < J; a++)
            for (int b = 0; b < a; b++)
                H[(size_t)a * J + b] = H[(size_t)b * J + a];
        x->EE[ch] = ee;
    }
    free(row);
    return 0;
}

int srbf_transfer_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const srbf_energy *en = in->prev[0];
    const srbf_lightset *ls = in->prev[1];
    const srbf_visdata *vd = in->prev[2];
    const samples *s = in->s;
    srbf_transfer_data *x = calloc(1, sizeof *x);
    float *nrm = NULL, *wo = NULL;
    uint64_t *bits = NULL;
    double t0 = glint_now();
    size_t J, n;
    int rc;

    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (vd->on) {
        progress(in, "visibility", 0.25);
        if ((rc = srbf_cast_shadows(in, vd, &ls->l, &bits, &x->rays, err))) {
            free(x);
            return rc;
        }
        x->vis_seconds = glint_now() - t0;
        t0 = glint_now();
    }
    progress(in, "transfer", 0.4);
    x->nrows = vd->nrows;
    x->J = en->b.J;
    J = (size_t)x->J;
    n = (size_t)x->nrows;
    x->T = malloc(3 * n * J * sizeof *x->T);
    x->E = malloc(3 * n * sizeof *x->E);
    x->H = malloc(3 * J * J * sizeof *x->H);
    x->TE = malloc(3 * J * sizeof *x->TE);
    x->reach = malloc(J);
    nrm = malloc(3 * n * sizeof *nrm);
    wo = malloc(3 * n * sizeof *wo);
    if (!x->T || !x->E || !x->H || !x->TE || !x->reach || !nrm || !wo) {
        rc = glint_err_set(err, GLINT_ENOMEM,
                           "out of memory for the transfer matrices (%zu rows x %zu lobes x 3)",
                           n, J);
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        memcpy(nrm + 3 * i, s->nrm + 3 * (size_t)vd->rows[i], 3 * sizeof *nrm);
        memcpy(wo + 3 * i, s->wo + 3 * (size_t)vd->rows[i], 3 * sizeof *wo);
    }
    if ((rc = srbf_transfer(&en->b, &en->st, x->nrows, nrm, wo, &ls->l, bits, x->T, x->E,
                            x->reach, 0, &x->terms, in->cancel, err)))
        goto done;
    x->seconds = glint_now() - t0;
    progress(in, "gram", 0.9);
    t0 = glint_now();
    if ((rc = transfer_gram(x, in->cancel, err)))
        goto done;
    rc = srbf_transfer_reach(x, en, err);
    x->gram_seconds = glint_now() - t0;
done:
    free(bits);
    free(nrm);
    free(wo);
    if (rc) {
        transfer_free(x);
        return rc;
    }
    out->data = x;
    out->bytes = srbf_transfer_bytes(x);
    out->free = transfer_free;
    return 0;
}

int srbf_transfer_level_load(const method_build_in *in, const char *dir, const char *key,
                         cache_value *out, glint_err *err)
{
    const srbf_energy *en = in->prev[0];
    const srbf_visdata *vd = in->prev[2];
    srbf_transfer_data *x = calloc(1, sizeof *x);
    int rc;
    if (!x)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = srbf_transfer_load(dir, key, x, err)))
        goto fail;
    if (x->J != en->b.J || x->nrows != vd->nrows) {
        rc = glint_err_set(err, GLINT_EFORMAT, "cached transfer %s does not match", key);
        goto fail;
    }
    if ((rc = srbf_transfer_reach(x, en, err)))
        goto fail;
    out->data = x;
    out->bytes = srbf_transfer_bytes(x);
    out->free = transfer_free;
    return 0;
fail:
    transfer_free(x);
    return rc;
}

int srbf_transfer_level_save(const method_build_in *in, const char *dir, const char *key,
                         const cache_value *v, glint_err *err)
{
    (void)in;
    return srbf_transfer_save(dir, key, v->data, err);
}

