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
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "fsio.h"
#include "method_srbf.h"

#define MAGIC "GLSRBF01"
#define MAX_FILE ((size_t)16 << 30)

typedef struct wbuf {
    unsigned char *p;
    size_t len, cap;
    int oom;
} wbuf;

static void put(wbuf *b, const void *src, size_t n)
{
    if (b->oom)
        return;
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        unsigned char *q;
        while (cap < b->len + n)
            cap *= 2;
        if (!(q = realloc(b->p, cap))) {
            b->oom = 1;
            return;
        }
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->len, src, n);
    b->len += n;
}

static void put_u32(wbuf *b, uint32_t v)
{
    put(b, &v, sizeof v);
}

static int finish(wbuf *b, const char *dir, const char *key, glint_err *err)
{
    char name[CACHE_KEY_MAX + 8], path[4096];
    uint64_t h;
    int rc;
    if (!b->oom) {
        h = XXH64(b->p, b->len, 0);
        put(b, &h, sizeof h);
    }
    if (b->oom) {
        free(b->p);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory writing %s", key);
    }
    snprintf(name, sizeof name, "%s.srbf", key);
    if (!(rc = fsio_mkdirs(dir, err)) && !(rc = fsio_join(path, sizeof path, dir, name, err)))
        rc = fsio_write_atomic(path, b->p, b->len, err);
    free(b->p);
    return rc;
}

typedef struct rbuf {
    const unsigned char *p;
    size_t len, at;
} rbuf;

static int get(rbuf *b, void *dst, size_t n)
{
    if (b->len - b->at < n)
        return -1;
    memcpy(dst, b->p + b->at, n);
    b->at += n;
    return 0;
}

/* Read and check the file; OUT: *data (malloc'ed) and a reader past the
 * header's magic and kind. */
static int open_file(const char *dir, const char *key, uint32_t kind, char **data, rbuf *r,
                     glint_err *err)
{
    char name[CACHE_KEY_MAX + 8], path[4096];
    size_t len;
    uint64_t h;
    uint32_t k;
    int rc;

    snprintf(name, sizeof name, "%s.srbf", key);
    if ((rc = fsio_join(path, sizeof path, dir, name, err)))
        return rc;
    if ((rc = fsio_read_all(path, MAX_FILE, data, &len, err)))
        return rc;
    if (len < 8 + 4 + 8 || memcmp(*data, MAGIC, 8)) {
        free(*data);
        return glint_err_set(err, GLINT_EFORMAT, "%s is not a glint srbf cache file", name);
    }
    memcpy(&h, *data + len - 8, 8);
    if (XXH64(*data, len - 8, 0) != h) {
        free(*data);
        return glint_err_set(err, GLINT_EFORMAT, "%s: checksum mismatch (damaged file)", name);
    }
    r->p = (const unsigned char *)*data;
    r->len = len - 8;
    r->at = 8;
    if (get(r, &k, 4) || k != kind) {
        free(*data);
        return glint_err_set(err, GLINT_EFORMAT, "%s holds another kind of level", name);
    }
    return 0;
}

int srbf_energy_save(const char *dir, const char *key, const srbf_energy *x, glint_err *err)
{
    wbuf b = {0};
    size_t J = (size_t)x->b.J;
    put(&b, MAGIC, 8);
    put_u32(&b, 1);
    put_u32(&b, (uint32_t)x->b.res);
    put_u32(&b, (uint32_t)x->nl);
    put(&b, &x->b.sigma, sizeof(double));
    put(&b, &x->b.lambda, sizeof(double));
    put(&b, x->wo, 3 * (size_t)x->nl * sizeof(double));
    put(&b, x->g, (size_t)x->nl * J * sizeof(double));
    return finish(&b, dir, key, err);
}

int srbf_energy_load(const char *dir, const char *key, srbf_energy *x, glint_err *err)
{
    char *data = NULL;
    rbuf r;
    uint32_t res, nl;
    double sigma, lambda;
    int rc;

    memset(x, 0, sizeof *x);
    if ((rc = open_file(dir, key, 1, &data, &r, err)))
        return rc;
    if (get(&r, &res, 4) || get(&r, &nl, 4) || get(&r, &sigma, 8) || get(&r, &lambda, 8) ||
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
    if (get(&r, x->wo, (size_t)3 * nl * sizeof(double)) ||
        get(&r, x->g, (size_t)nl * x->b.J * sizeof(double)) || r.at != r.len)
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: energy file has the wrong size", key);
done:
    free(data);
    if (rc)
        srbf_energy_clear(x);
    return rc;
}

int srbf_transfer_save(const char *dir, const char *key, const srbf_transfer_data *x,
                       glint_err *err)
{
    wbuf b = {0};
    size_t J = (size_t)x->J, n = (size_t)x->nrows;
    put(&b, MAGIC, 8);
    put_u32(&b, 2);
    put_u32(&b, (uint32_t)x->nrows);
    put_u32(&b, (uint32_t)x->J);
    put(&b, x->T, 3 * n * J * sizeof(float));
    put(&b, x->E, 3 * n * sizeof(double));
    put(&b, x->H, 3 * J * J * sizeof(double));
    put(&b, x->TE, 3 * J * sizeof(double));
    put(&b, x->EE, 3 * sizeof(double));
    put(&b, x->reach, J);
    put(&b, &x->terms, sizeof x->terms);
    put(&b, &x->rays, sizeof x->rays);
    put(&b, &x->vis_seconds, sizeof x->vis_seconds);
    put(&b, &x->seconds, sizeof x->seconds);
    put(&b, &x->gram_seconds, sizeof x->gram_seconds);
    return finish(&b, dir, key, err);
}

int srbf_transfer_load(const char *dir, const char *key, srbf_transfer_data *x, glint_err *err)
{
    char *data = NULL;
    rbuf r;
    uint32_t n, J;
    int rc;

    memset(x, 0, sizeof *x);
    if ((rc = open_file(dir, key, 2, &data, &r, err)))
        return rc;
    if (get(&r, &n, 4) || get(&r, &J, 4) || n < 1 || n > SAMPLES_MAX || J < 1 ||
        J > 3 * SRBF_MAX_RES * SRBF_MAX_RES ||
        (size_t)n * J * 3 * sizeof(float) > r.len) {
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
    if (get(&r, x->T, (size_t)3 * n * J * sizeof(float)) ||
        get(&r, x->E, (size_t)3 * n * sizeof(double)) ||
        get(&r, x->H, (size_t)3 * J * J * sizeof(double)) ||
        get(&r, x->TE, (size_t)3 * J * sizeof(double)) || get(&r, x->EE, 3 * sizeof(double)) ||
        get(&r, x->reach, J) || get(&r, &x->terms, sizeof x->terms) ||
        get(&r, &x->rays, sizeof x->rays) || get(&r, &x->vis_seconds, sizeof x->vis_seconds) ||
        get(&r, &x->seconds, sizeof x->seconds) ||
        get(&r, &x->gram_seconds, sizeof x->gram_seconds) || r.at != r.len) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: transfer file has the wrong size", key);
        goto done;
    }
    for (uint32_t j = 0; j < J; j++)
        x->nreach += x->reach[j] != 0;
done:
    free(data);
    if (rc)
        srbf_transfer_clear(x);
    return rc;
}
