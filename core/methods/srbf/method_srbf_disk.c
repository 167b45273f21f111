/* method_srbf_disk.c: the srbf method's cache files (method_srbf.h).
 *
 * A file <dir>/<key>.srbf holds one level:
 *   "GLSRBF01", u32 kind (1 energy, 2 transfer), u32 little-endian sizes,
 *   the arrays (little-endian IEEE doubles and floats, as the machine
 *   stores them: glint runs on little-endian hosts), and an XXH64 checksum
 *   of every byte before it.
 * Energy: res, nl, then sigma, lambda, wo[3 nl], g[nl J].
 * Transfer: nrows, J, then T[3 nrows J] (float), E[3 nrows], H[3 J J],
 *   TE[3 J], EE[3], reach[J], terms, rays, vis_seconds, seconds,
 *   gram_seconds.
 * A short, truncated, flipped or mismatched file is GLINT_EFORMAT (the
 * cache then rebuilds the level).  Files are written atomically (fsio.h). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfile.h"
#include "method_srbf.h"

#define MAGIC "GLSRBF01"
#define MAX_FILE ((size_t)16 << 30)

static int finish(cfile_w *b, const char *dir, const char *key, glint_err *err)
{
    char name[CACHE_KEY_MAX + 8];
    snprintf(name, sizeof name, "%s.srbf", key);
    return cfile_write(b, dir, name, err);
}

static int open_file(const char *dir, const char *key, uint32_t kind, cfile_r *r,
                     glint_err *err)
{
    char name[CACHE_KEY_MAX + 8];
    snprintf(name, sizeof name, "%s.srbf", key);
    return cfile_open(dir, name, MAGIC, kind, MAX_FILE, r, err);
}

int srbf_energy_save(const char *dir, const char *key, const srbf_energy *x, glint_err *err)
{
    cfile_w b;
    size_t J = (size_t)x->b.J;
    cfile_begin(&b, MAGIC, 1);
    cfile_put_u32(&b, (uint32_t)x->b.res);
    cfile_put_u32(&b, (uint32_t)x->nl);
    cfile_put(&b, &x->b.sigma, sizeof(double));
    cfile_put(&b, &x->b.lambda, sizeof(double));
    cfile_put(&b, x->wo, 3 * (size_t)x->nl * sizeof(double));
    cfile_put(&b, x->g, (size_t)x->nl * J * sizeof(double));
    return finish(&b, dir, key, err);
}

int srbf_energy_load(const char *dir, const char *key, srbf_energy *x, glint_err *err)
{
    cfile_r r;
    uint32_t res, nl;
    double sigma, lambda;
    int rc;

    memset(x, 0, sizeof *x);
    if ((rc = open_file(dir, key, 1, &r, err)))
        return rc;
    if (cfile_get(&r, &res, 4) || cfile_get(&r, &nl, 4) || cfile_get(&r, &sigma, 8) || cfile_get(&r, &lambda, 8) ||
        res < SRBF_MIN_RES || res > SRBF_MAX_RES || nl < 1 || nl > 100000) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: bad energy header", key);
        goto done;
    }
    if ((rc = srbf_basis_make((int)res, sigma, &x->b, err)))
        goto done;
    x->nl = (int)nl;
    x->wo = malloc((size_t)3 * nl * sizeof *x->wo);
    x->g = malloc((size_t)nl * x->b.J * sizeof *x->g);
    if (!x->wo || !x->g) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    if (cfile_get(&r, x->wo, (size_t)3 * nl * sizeof(double)) ||
        cfile_get(&r, x->g, (size_t)nl * x->b.J * sizeof(double)) || !cfile_done(&r))
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: energy file has the wrong size", key);
done:
    cfile_close(&r);
    if (rc)
        srbf_energy_clear(x);
    return rc;
}

int srbf_transfer_save(const char *dir, const char *key, const srbf_transfer_data *x,
                       glint_err *err)
{
    cfile_w b;
    size_t J = (size_t)x->J, n = (size_t)x->nrows;
    cfile_begin(&b, MAGIC, 2);
    cfile_put_u32(&b, (uint32_t)x->nrows);
    cfile_put_u32(&b, (uint32_t)x->J);
    cfile_put(&b, x->T, 3 * n * J * sizeof(float));
    cfile_put(&b, x->E, 3 * n * sizeof(double));
    cfile_put(&b, x->H, 3 * J * J * sizeof(double));
    cfile_put(&b, x->TE, 3 * J * sizeof(double));
    cfile_put(&b, x->EE, 3 * sizeof(double));
    cfile_put(&b, x->reach, J);
    cfile_put(&b, &x->terms, sizeof x->terms);
    cfile_put(&b, &x->rays, sizeof x->rays);
    cfile_put(&b, &x->vis_seconds, sizeof x->vis_seconds);
    cfile_put(&b, &x->seconds, sizeof x->seconds);
    cfile_put(&b, &x->gram_seconds, sizeof x->gram_seconds);
    return finish(&b, dir, key, err);
}

int srbf_transfer_load(const char *dir, const char *key, srbf_transfer_data *x, glint_err *err)
{
    cfile_r r;
    uint32_t n, J;
    int rc;

    memset(x, 0, sizeof *x);
    if ((rc = open_file(dir, key, 2, &r, err)))
        return rc;
    if (cfile_get(&r, &n, 4) || cfile_get(&r, &J, 4) || n < 1 || n > SAMPLES_MAX || J < 1 ||
        J > 3 * SRBF_MAX_RES * SRBF_MAX_RES ||
        (size_t)n * J * 3 * sizeof(float) > r.len - r.at) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: bad transfer header", key);
        goto done;
    }
    x->nrows = (int)n;
    x->J = (int)J;
    x->T = malloc((size_t)3 * n * J * sizeof *x->T);
    x->E = malloc((size_t)3 * n * sizeof *x->E);
    x->H = malloc((size_t)3 * J * J * sizeof *x->H);
    x->TE = malloc((size_t)3 * J * sizeof *x->TE);
    x->reach = malloc(J);
    if (!x->T || !x->E || !x->H || !x->TE || !x->reach) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    if (cfile_get(&r, x->T, (size_t)3 * n * J * sizeof(float)) ||
        cfile_get(&r, x->E, (size_t)3 * n * sizeof(double)) ||
        cfile_get(&r, x->H, (size_t)3 * J * J * sizeof(double)) ||
        cfile_get(&r, x->TE, (size_t)3 * J * sizeof(double)) || cfile_get(&r, x->EE, 3 * sizeof(double)) ||
        cfile_get(&r, x->reach, J) || cfile_get(&r, &x->terms, sizeof x->terms) ||
        cfile_get(&r, &x->rays, sizeof x->rays) || cfile_get(&r, &x->vis_seconds, sizeof x->vis_seconds) ||
        cfile_get(&r, &x->seconds, sizeof x->seconds) ||
        cfile_get(&r, &x->gram_seconds, sizeof x->gram_seconds) || !cfile_done(&r)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: transfer file has the wrong size", key);
        goto done;
    }
    for (uint32_t j = 0; j < J; j++)
        x->nreach += x->reach[j] != 0;
done:
    cfile_close(&r);
    if (rc)
        srbf_transfer_clear(x);
    return rc;
}
