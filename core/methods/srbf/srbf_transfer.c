/* srbf_transfer.c: transfer matrices and irradiance of pixels under lights
 * (srbf.h), threaded over pixels.  Per pixel: the local frame, then for
 * each light it sees the half vector, the static term and the weight
 * power x cos x s per channel, accumulated into the lobes whose Gaussian
 * is above e^-30 at that half vector (the others add less than 1e-13 of
 * the peak). */
#include "srbf.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "vis.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct tjob {
    const srbf_basis *b;
    const srbf_static *s;
    const float *nrm, *wo;
    const env_lights *l;
    const uint64_t *vis;
    float *T;
    double *E;
    int npix, i0, i1;
    long terms;
    double *acc;   /* 3J scratch */
    const glint_cancel *cancel;
    int *stopped;  /* shared: set once a thread was told to stop */
} tjob;

static void *tjob_run(void *arg)
{
    tjob *j = arg;
    const srbf_basis *b = j->b;
    int J = b->J, K = j->l->k, words = VIS_WORDS(K);
    double cut = 1.0 - 30.0 / b->lambda, lam = b->lambda;
    long every = glint_cancel_every((long)K * J);
    for (int i = j->i0; i < j->i1; i++) {
        double n[3], wow[3], t[3], bt[3], lo[3], e[3] = {0, 0, 0};
        double *acc = j->acc;
        if (j->cancel && (i - j->i0) % every == 0) {
            if (__atomic_load_n(j->stopped, __ATOMIC_RELAXED))
                break;
            if (glint_cancelled(j->cancel)) {
                __atomic_store_n(j->stopped, 1, __ATOMIC_RELAXED);
                break;
            }
        }
        for (int k = 0; k < 3; k++) {
            n[k] = j->nrm[3 * (size_t)i + k];
            wow[k] = j->wo[3 * (size_t)i + k];
        }
        {
            double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (nl > 0)
                for (int k = 0; k < 3; k++)
                    n[k] /= nl;
        }
        srbf_frame(n, t, bt);
        lo[0] = t[0] * wow[0] + t[1] * wow[1] + t[2] * wow[2];
        lo[1] = bt[0] * wow[0] + bt[1] * wow[1] + bt[2] * wow[2];
        lo[2] = n[0] * wow[0] + n[1] * wow[1] + n[2] * wow[2];
        memset(acc, 0, (size_t)3 * J * sizeof *acc);
        for (int k = 0; k < K && lo[2] > 0.0; k++) {
            const double *d = j->l->dir + 3 * k, *pw = j->l->power + 3 * k;
            double li[3], h[3], hl, s, w0, w1, w2;
            if (j->vis && !((j->vis[(size_t)i * words + (k >> 6)] >> (k & 63)) & 1))
                continue;
            li[2] = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            if (li[2] <= 0.0)
                continue;
            li[0] = t[0] * d[0] + t[1] * d[1] + t[2] * d[2];
            li[1] = bt[0] * d[0] + bt[1] * d[1] + bt[2] * d[2];
            for (int c = 0; c < 3; c++)
                e[c] += pw[c] * li[2];
            s = srbf_static_eval(j->s, li, lo);
            if (s == 0.0)
                continue;
            for (int c = 0; c < 3; c++)
                h[c] = li[c] + lo[c];
            hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
            if (!(hl > 0.0))
                continue;
            h[0] /= hl;
            h[1] /= hl;
            h[2] /= hl;
            w0 = pw[0] * li[2] * s;
            w1 = pw[1] * li[2] * s;
            w2 = pw[2] * li[2] * s;
            for (int q = 0; q < J; q++) {
                const double *x = b->xi + 3 * q;
                double dd = h[0] * x[0] + h[1] * x[1] + h[2] * x[2];
                if (dd > cut) {
                    double g = exp(lam * (dd - 1.0));
                    acc[q] += w0 * g;
                    acc[J + q] += w1 * g;
                    acc[2 * J + q] += w2 * g;
                    j->terms++;
                }
            }
        }
        for (int c = 0; c < 3; c++) {
            float *row = j->T + ((size_t)c * j->npix + i) * J;
            for (int q = 0; q < J; q++)
                row[q] = (float)acc[(size_t)c * J + q];
            j->E[3 * (size_t)i + c] = e[c] / M_PI;
        }
    }
    return NULL;
}

int srbf_transfer(const srbf_basis *b, const srbf_static *s, int npix, const float *nrm,
                  const float *wo, const env_lights *l, const uint64_t *vis, float *T,
                  double *E, unsigned char *reach, int nthreads, long *terms,
                  const glint_cancel *cancel, glint_err *err)
{
    long nc = nthreads > 0 ? nthreads : sysconf(_SC_NPROCESSORS_ONLN);
    int nt = nc < 1 ? 1 : nc > 64 ? 64 : (int)nc, rc = 0, stopped = 0;
    pthread_t th[64];
    tjob jobs[64];
    long total = 0;

    if (npix < 0 || !l || l->k < 0)
        return glint_err_set(err, GLINT_EINVAL, "bad transfer request");
    if (nt > npix)
        nt = npix > 0 ? npix : 1;
    for (int t = 0; t < nt; t++) {
        jobs[t] = (tjob){b, s, nrm, wo, l, vis, T, E, npix, (int)((long)npix * t / nt),
                         (int)((long)npix * (t + 1) / nt), 0,
                         malloc((size_t)3 * b->J * sizeof(double)), cancel, &stopped};
        if (!jobs[t].acc)
            rc = GLINT_ENOMEM;
    }
    if (rc) {
        for (int t = 0; t < nt; t++)
            free(jobs[t].acc);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    for (int t = 1; t < nt; t++)
        if (pthread_create(&th[t], NULL, tjob_run, &jobs[t])) {
            tjob_run(&jobs[t]);
            th[t] = 0;
        }
    tjob_run(&jobs[0]);
    for (int t = 1; t < nt; t++)
        if (th[t])
            pthread_join(th[t], NULL);
    for (int t = 0; t < nt; t++) {
        total += jobs[t].terms;
        free(jobs[t].acc);
    }
    if (terms)
        *terms = total;
    if (stopped)
        return glint_cancel_err(err, "the transfer matrices");
    if (reach) {
        float mx = 0.0f;
        size_t all = (size_t)3 * npix * b->J;
        for (size_t k = 0; k < all; k++)
            mx = T[k] > mx ? T[k] : mx;
        memset(reach, 0, (size_t)b->J);
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < npix; i++) {
                const float *row = T + ((size_t)c * npix + i) * b->J;
                for (int q = 0; q < b->J; q++)
                    if (row[q] > 1e-6f * mx && mx > 0.0f)
                        reach[q] = 1;
            }
    }
    return 0;
}
