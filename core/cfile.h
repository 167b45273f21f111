/* cfile.h: checksummed cache files, the common frame of the methods' disk
 * levels (method_srbf_disk.c, method_hf4.c; hf3's decompositions have
 * their own, pcache.h).
 *
 * A file holds an 8-byte magic, a u32 kind, the level's fields as the
 * writer puts them (little-endian values as the machine stores them: glint
 * runs on little-endian hosts) and an XXH64 checksum of every byte before
 * it.  A short, flipped or mismatched file is GLINT_EFORMAT (the cache
 * then rebuilds the level and overwrites it); files are written atomically
 * (fsio.h). */
#ifndef GLINT_CFILE_H
#define GLINT_CFILE_H

#include <stddef.h>
#include <stdint.h>

#include "err.h"

/* Being written: put fields, then cfile_write (which frees the buffer
 * whatever happens).  An allocation failure is remembered and reported by
 * cfile_write. */
typedef struct cfile_w {
    unsigned char *p;
    size_t len, cap;
    int oom;
} cfile_w;

/* Start a file of `magic` (8 bytes) and `kind`. */
void cfile_begin(cfile_w *b, const char magic[8], uint32_t kind);
void cfile_put(cfile_w *b, const void *src, size_t n);
void cfile_put_u32(cfile_w *b, uint32_t v);
/* Append the checksum and write dir/name atomically (dir created). */
int cfile_write(cfile_w *b, const char *dir, const char *name, glint_err *err);

/* Being read: cfile_open checks size, magic, checksum and kind; cfile_get
 * reads the fields in order (-1 past the end); cfile_done says whether
 * every byte was read; cfile_close frees. */
typedef struct cfile_r {
    char *data;
    size_t len, at;
} cfile_r;

int cfile_open(const char *dir, const char *name, const char magic[8], uint32_t kind,
               size_t max_bytes, cfile_r *r, glint_err *err);
int cfile_get(cfile_r *r, void *dst, size_t n);
int cfile_done(const cfile_r *r);
void cfile_close(cfile_r *r);

/* A file name for a cache key of any characters: 32 hex digits of its
 * XXH3-128, then `ext` (OUT: name, at least 34 + strlen(ext) bytes). */
void cfile_name(const char *key, const char *ext, char *name, size_t len);

#endif
