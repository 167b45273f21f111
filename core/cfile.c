/* cfile.c: checksummed cache files (cfile.h). */
#include "cfile.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

#include "fsio.h"

void cfile_put(cfile_w *b, const void *src, size_t n)
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

void cfile_put_u32(cfile_w *b, uint32_t v)
{
    cfile_put(b, &v, sizeof v);
}

void cfile_begin(cfile_w *b, const char magic[8], uint32_t kind)
{
    memset(b, 0, sizeof *b);
    cfile_put(b, magic, 8);
    cfile_put_u32(b, kind);
}

int cfile_write(cfile_w *b, const char *dir, const char *name, glint_err *err)
{
    char path[4096];
    uint64_t h;
    int rc;
    if (!b->oom) {
        h = XXH64(b->p, b->len, 0);
        cfile_put(b, &h, sizeof h);
    }
    if (b->oom) {
        free(b->p);
        memset(b, 0, sizeof *b);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory writing %s", name);
    }
    if (!(rc = fsio_mkdirs(dir, err)) && !(rc = fsio_join(path, sizeof path, dir, name, err)))
        rc = fsio_write_atomic(path, b->p, b->len, err);
    free(b->p);
    memset(b, 0, sizeof *b);
    return rc;
}

int cfile_open(const char *dir, const char *name, const char magic[8], uint32_t kind,
               size_t max_bytes, cfile_r *r, glint_err *err)
{
    char path[4096];
    size_t len;
    uint64_t h;
    uint32_t k;
    int rc;

    memset(r, 0, sizeof *r);
    if ((rc = fsio_join(path, sizeof path, dir, name, err)))
        return rc;
    if ((rc = fsio_read_all(path, max_bytes, &r->data, &len, err)))
        return rc;
    if (len < 8 + 4 + 8 || memcmp(r->data, magic, 8)) {
        cfile_close(r);
        return glint_err_set(err, GLINT_EFORMAT, "%s is not a glint %.8s cache file", name,
                             magic);
    }
    memcpy(&h, r->data + len - 8, 8);
    if (XXH64(r->data, len - 8, 0) != h) {
        cfile_close(r);
        return glint_err_set(err, GLINT_EFORMAT, "%s: checksum mismatch (damaged file)", name);
    }
    r->len = len - 8;
    r->at = 8;
    if (cfile_get(r, &k, 4) || k != kind) {
        cfile_close(r);
        return glint_err_set(err, GLINT_EFORMAT, "%s holds another kind of level", name);
    }
    return 0;
}

int cfile_get(cfile_r *r, void *dst, size_t n)
{
    if (r->len - r->at < n)
        return -1;
    memcpy(dst, r->data + r->at, n);
    r->at += n;
    return 0;
}

int cfile_done(const cfile_r *r)
{
    return r->at == r->len;
}

void cfile_close(cfile_r *r)
{
    free(r->data);
    memset(r, 0, sizeof *r);
}

void cfile_name(const char *key, const char *ext, char *name, size_t len)
{
    XXH128_hash_t h = XXH3_128bits(key, strlen(key));
    snprintf(name, len, "%016llx%016llx%s", (unsigned long long)h.high64,
             (unsigned long long)h.low64, ext);
}
