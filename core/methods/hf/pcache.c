/* pcache.c: checksummed on-disk precomputations. */
#include "pcache.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "fsio.h"

#define PCACHE_MAGIC "GLINTPC1"
/* 2: the decomposition cuts barely reached directions and records what it
 * cut (null_dims, weak_dims, s_null, gain_max, gain_kept, s_weak). */
#define PCACHE_VERSION 2u
#define PCACHE_KIND_HF_DECOMP 1u
#define PCACHE_MAX_FILE ((size_t)1 << 32)

/* Little-endian writer into a growing buffer. */
typedef struct wbuf { unsigned char *p; size_t len, cap; int oom; } wbuf;

static void wb_put(wbuf *b, const void *src, size_t n)
{
    if (b->oom)
        return;
    if (b->len + n > b->cap) {
        size_t ncap = b->cap ? b->cap : 4096;
        while (ncap < b->len + n)
            ncap *= 2;
        unsigned char *np = realloc(b->p, ncap);
        if (!np) {
            b->oom = 1;
            return;
        }
        b->p = np;
        b->cap = ncap;
    }
    memcpy(b->p + b->len, src, n);
    b->len += n;
}

static void wb_u32(wbuf *b, uint32_t v)
{
    unsigned char t[4] = {(unsigned char)v, (unsigned char)(v >> 8), (unsigned char)(v >> 16),
                          (unsigned char)(v >> 24)};
    wb_put(b, t, 4);
}

static void wb_u64(wbuf *b, uint64_t v)
{
    wb_u32(b, (uint32_t)v);
    wb_u32(b, (uint32_t)(v >> 32));
}

static void wb_f64(wbuf *b, double d)
{
    uint64_t u;
    memcpy(&u, &d, 8);
    wb_u64(b, u);
}

typedef struct rbuf { const unsigned char *p; size_t len, pos; int bad; } rbuf;

static uint32_t rb_u32(rbuf *b)
{
    uint32_t v;
    if (b->pos + 4 > b->len) {
        b->bad = 1;
        return 0;
    }
    v = (uint32_t)b->p[b->pos] | (uint32_t)b->p[b->pos + 1] << 8 |
        (uint32_t)b->p[b->pos + 2] << 16 | (uint32_t)b->p[b->pos + 3] << 24;
    b->pos += 4;
    return v;
}

static uint64_t rb_u64(rbuf *b)
{
    uint64_t lo = rb_u32(b);
    return lo | (uint64_t)rb_u32(b) << 32;
}

static double rb_f64(rbuf *b)
{
    uint64_t u = rb_u64(b);
    double d;
    memcpy(&d, &u, 8);
    return d;
}

void pcache_key_hf(const char pattern_hash[33], int res, double lambda, hf_route route,
                   double rcond, char key[33])
{
    wbuf b = {0};
    XXH128_hash_t h;
    static const char tag[] = "glint-hf-decomp-v1";

    wb_put(&b, tag, sizeof tag);
    wb_put(&b, pattern_hash, 32);
    wb_u32(&b, (uint32_t)res);
    wb_f64(&b, lambda);
    wb_u32(&b, (uint32_t)route);
    wb_f64(&b, rcond > 0.0 ? rcond : hf_rcond_default(route));
    h = b.oom ? XXH3_128bits(tag, sizeof tag) : XXH3_128bits(b.p, b.len);
    free(b.p);
    snprintf(key, 33, "%016llx%016llx", (unsigned long long)h.high64,
             (unsigned long long)h.low64);
}

int pcache_path(const char *dir, const char key[33], char *buf, size_t len, glint_err *err)
{
    int n = snprintf(buf, len, "%s/%.32s.hfd", dir, key);
    if (n < 0 || (size_t)n >= len)
        return glint_err_set(err, GLINT_ERANGE, "cache path too long");
    return 0;
}

size_t pcache_decomp_bytes(const hf_decomp *dc)
{
    return (size_t)dc->rank * sizeof(double) * (1 + (size_t)dc->n);
}

int pcache_decomp_save(const char *dir, const char key[33], const hf_decomp *dc,
                       glint_err *err)
{
    wbuf b = {0};
    char path[4096];
    int rc;

    if ((rc = fsio_mkdirs(dir, err)) || (rc = pcache_path(dir, key, path, sizeof path, err)))
        return rc;
    wb_put(&b, PCACHE_MAGIC, 8);
    wb_u32(&b, PCACHE_VERSION);
    wb_u32(&b, PCACHE_KIND_HF_DECOMP);
    wb_put(&b, key, 32);
    wb_u32(&b, (uint32_t)dc->res);
    wb_u32(&b, (uint32_t)dc->n);
    wb_u32(&b, (uint32_t)dc->nsamples);
    wb_u32(&b, (uint32_t)dc->rank);
    wb_u32(&b, (uint32_t)dc->gauge_dims);
    wb_u32(&b, (uint32_t)dc->route);
    wb_f64(&b, dc->lambda);
    wb_f64(&b, dc->rcond);
    wb_f64(&b, dc->build_seconds);
    wb_u32(&b, (uint32_t)dc->null_dims);
    wb_u32(&b, (uint32_t)dc->weak_dims);
    wb_f64(&b, dc->s_null);
    wb_f64(&b, dc->gain_max);
    wb_f64(&b, dc->gain_kept);
    wb_f64(&b, dc->s_weak);
    for (int k = 0; k < dc->rank; k++)
        wb_f64(&b, dc->s[k]);
    for (size_t i = 0; i < (size_t)dc->n * dc->rank; i++)
        wb_f64(&b, dc->V[i]);
    wb_u64(&b, b.oom ? 0 : XXH3_64bits(b.p, b.len));
    if (b.oom) {
        free(b.p);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory serializing a decomposition");
    }
    rc = fsio_write_rebuildable(path, b.p, b.len, err);
    free(b.p);
    return rc;
}

int pcache_decomp_load(const char *dir, const char key[33], hf_decomp *out, glint_err *err)
{
    char path[4096], *data = NULL;
    size_t len = 0;
    rbuf b;
    int rc;
    uint64_t want, got;

    memset(out, 0, sizeof *out);
    if ((rc = pcache_path(dir, key, path, sizeof path, err)))
        return rc;
    rc = fsio_read_all(path, PCACHE_MAX_FILE, &data, &len, err);
    if (rc)
        return rc;
    rc = GLINT_EFORMAT;
    if (len < 8 + 8 + 32 + 24 + 24 + 40 + 8 || memcmp(data, PCACHE_MAGIC, 8) != 0) {
        glint_err_set(err, rc, "%s: not a glint cache file (bad magic or too short)", path);
        goto fail;
    }
    {
        rbuf t = {(const unsigned char *)data, len, len - 8, 0};
        want = rb_u64(&t);
    }
    got = XXH3_64bits(data, len - 8);
    if (want != got) {
        glint_err_set(err, rc, "%s: checksum mismatch (file corrupt or truncated)", path);
        goto fail;
    }
    b.p = (const unsigned char *)data;
    b.len = len - 8;
    b.pos = 8;
    b.bad = 0;
    if (rb_u32(&b) != PCACHE_VERSION || rb_u32(&b) != PCACHE_KIND_HF_DECOMP) {
        glint_err_set(err, rc, "%s: unsupported cache version or kind", path);
        goto fail;
    }
    if (memcmp(data + b.pos, key, 32) != 0) {
        glint_err_set(err, rc, "%s: holds another key", path);
        goto fail;
    }
    b.pos += 32;
    out->res = (int)rb_u32(&b);
    out->n = (int)rb_u32(&b);
    out->nsamples = (int)rb_u32(&b);
    out->rank = (int)rb_u32(&b);
    out->gauge_dims = (int)rb_u32(&b);
    out->route = (hf_route)rb_u32(&b);
    out->lambda = rb_f64(&b);
    out->rcond = rb_f64(&b);
    out->build_seconds = rb_f64(&b);
    out->null_dims = (int)rb_u32(&b);
    out->weak_dims = (int)rb_u32(&b);
    out->s_null = rb_f64(&b);
    out->gain_max = rb_f64(&b);
    out->gain_kept = rb_f64(&b);
    out->s_weak = rb_f64(&b);
    if (b.bad || out->res < HF_RES_MIN || out->res > HF_RES_MAX || out->n != 3 * out->res ||
        out->rank < 1 || out->rank > out->n || out->nsamples < 1 ||
        out->gauge_dims < 0 || out->null_dims < 0 || out->weak_dims < 0 ||
        (long long)out->gauge_dims + out->null_dims + out->weak_dims + out->rank > out->n ||
        !isfinite(out->s_null) || !isfinite(out->gain_max) || !isfinite(out->gain_kept) ||
        !isfinite(out->s_weak) ||
        b.len - b.pos != (size_t)8 * out->rank * (1 + (size_t)out->n)) {
        glint_err_set(err, rc, "%s: inconsistent sizes in the header", path);
        goto fail;
    }
    out->s = malloc((size_t)out->rank * sizeof *out->s);
    out->V = malloc((size_t)out->n * out->rank * sizeof *out->V);
    if (!out->s || !out->V) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory loading %s", path);
        goto fail;
    }
    for (int k = 0; k < out->rank; k++)
        out->s[k] = rb_f64(&b);
    for (size_t i = 0; i < (size_t)out->n * out->rank; i++)
        out->V[i] = rb_f64(&b);
    for (int k = 0; k < out->rank; k++)
        if (!isfinite(out->s[k]) || out->s[k] <= 0.0 || (k && out->s[k] > out->s[k - 1])) {
            glint_err_set(err, rc, "%s: singular values not positive and descending", path);
            goto fail;
        }
    for (size_t i = 0; i < (size_t)out->n * out->rank; i++)
        if (!isfinite(out->V[i])) {
            glint_err_set(err, rc, "%s: non-finite singular vector entry", path);
            goto fail;
        }
    free(data);
    return 0;
fail:
    free(data);
    hf_decomp_free(out);
    return rc;
}

int pcache_decomp_get(const char *dir, const hf_design *d, const char pattern_hash[33],
                      double lambda, hf_route route, double rcond, hf_decomp *out, int *hit,
                      glint_err *err)
{
    char key[33];
    int rc;
    glint_err lerr;

    *hit = 0;
    pcache_key_hf(pattern_hash, d->res, lambda, route, rcond, key);
    if (dir) {
        rc = pcache_decomp_load(dir, key, out, &lerr);
        if (rc == 0 && out->nsamples == d->n) {
            *hit = 1;
            return 0;
        }
        if (rc == 0)
            hf_decomp_free(out);
        if (rc == GLINT_EFORMAT || rc == 0)
            *hit = -1; /* corrupt or mismatched: rebuilt below and replaced */
    }
    rc = hf_decomp_build(d, lambda, route, rcond, out, err);
    if (rc)
        return rc;
    if (dir && (rc = pcache_decomp_save(dir, key, out, err)) != 0) {
        hf_decomp_free(out);
        return rc;
    }
    return 0;
}
