/* cfile.h: checksummed cache files, the common frame of the disk levels
 * (the sampling pattern's, pattern_disk.c; the methods', method_srbf_disk.c,
 * method_hf4.c; hf3's decompositions have their own, pcache.h).
 *
 * A file holds an 8-byte magic, a u32 kind, the level's fields as the
 * writer puts them (little-endian values as the machine stores them: glint
 * runs on little-endian hosts) and an XXH64 checksum of every byte before
 * it.  A short, flipped or mismatched file is GLINT_EFORMAT (the cache
 * then rebuilds the level and overwrites it); files are written atomically
 * and not fsynced (fsio_write_rebuildable, fsio.h: a crash may tear one,
 * which its checksum then tells). */
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
/* Room for `total` bytes in all (a hint: a large file is then not copied
 * as it grows). */
void cfile_reserve(cfile_w *b, size_t total);
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

/* Being read straight into the caller's arrays (a large level: no copy of
 * the whole file is held, nothing is copied twice).  cfile_stream_open
 * checks the size, magic and kind; cfile_stream_get reads the next n bytes
 * of fields into dst (-1 past the fields, or when the file ends early);
 * cfile_stream_left: the field bytes not read yet; cfile_stream_end checks
 * that every field was read and that the checksum matches (GLINT_EFORMAT
 * otherwise): until then nothing read is to be trusted.
 * cfile_stream_close closes (accepts a stream never opened, zeroed). */
typedef struct cfile_s {
    int fd;
    size_t len, at;        /* field bytes (the checksum excluded), bytes read */
    void *hash;            /* XXH64 state; NULL: not open */
} cfile_s;

int cfile_stream_open(const char *dir, const char *name, const char magic[8], uint32_t kind,
                      size_t max_bytes, cfile_s *r, glint_err *err);
int cfile_stream_get(cfile_s *r, void *dst, size_t n);
size_t cfile_stream_left(const cfile_s *r);
int cfile_stream_end(cfile_s *r, const char *name, glint_err *err);
void cfile_stream_close(cfile_s *r);

/* A file name for a cache key of any characters: 32 hex digits of its
 * XXH3-128, then `ext` (OUT: name, at least 34 + strlen(ext) bytes). */
void cfile_name(const char *key, const char *ext, char *name, size_t len);

#endif
