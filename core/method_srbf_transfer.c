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
    memset(x, 0, sizeof *x);
}

size_t srbf_transfer_bytes(const srbf_transfer_data *x)
{
    size_t J = (size_t)x->J, n = (size_t)x->nrows;
    return sizeof *x + 3 * n * J * sizeof(float) + 3 * n * sizeof(double) +
           4 * J * J * sizeof(double) + 3 * J * sizeof(double) + J * (1 + sizeof(int));
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

int srbf_transfer_reach(srbf_transfer_data *x, const srbf_basis *b, glint_err *err)
{
    int k = 0;
    x->nreach = 0;
    for (int j = 0; j < x->J; j++)
        x->nreach += x->reach[j] != 0;
    free(x->idx);
    free(x->LtL);
    x->idx = malloc((size_t)(x->nreach ? x->nreach : 1) * sizeof *x->idx);
    x->LtL = malloc((size_t)(x->nreach ? x->nreach * x->nreach : 1) * sizeof *x->LtL);
    if (!x->idx || !x->LtL)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int j = 0; j < x->J; j++)
        if (x->reach[j])
            x->idx[k++] = j;
    if (x->nreach)
        laplacian_gram(b, x->idx, x->nreach, x->LtL);
    return 0;
}

/* H = T'T, T'E and E'E per channel, in double, from the float T. */
static int transfer_gram(srbf_transfer_data *x, glint_err *err)
{
    int J = x->J, n = x->nrows;
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
                            x->reach, 0, &x->terms, err)))
        goto done;
    x->seconds = glint_now() - t0;
    progress(in, "gram", 0.9);
    t0 = glint_now();
    if ((rc = transfer_gram(x, err)))
        goto done;
    rc = srbf_transfer_reach(x, &en->b, err);
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
    if ((rc = srbf_transfer_reach(x, &en->b, err)))
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

