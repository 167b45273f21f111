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
 * reads the fields in order (GLINT_EFORMAT past the end); cfile_done says whether
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
 * of fields into dst (GLINT_EFORMAT past the fields, GLINT_EIO when the
 * read fails or the file ends early; GLINT_EINVAL when r is not open);
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

/* Being mapped (a large level used in place: nothing copied, no memory of
 * the process's own zeroed for it): cfile_map_open maps dir/name and
 * checks its size, magic, kind and checksum before returning;
 * cfile_map_take gives the next n bytes of fields where they lie (NULL
 * past the fields); cfile_map_align skips to the next multiple of `a`
 * bytes from the file's start (GLINT_EFORMAT past the fields; the writer put the
 * same padding with cfile_pad).  The mapping is private and writable (a
 * write stays the process's own).  cfile_map_keep makes it the caller's
 * (base, size) until cfile_unmap (GLINT_ERANGE when the process keeps 4096 already:
 * the caller copies what it needs, then cfile_map_close unmaps).
 *
 * Cut short.  glint replaces cache files by rename and never truncates
 * one in place, but another process may.  Reading a page of a kept
 * mapping beyond its file's new end would kill the process (SIGBUS); a
 * handler installed by the first cfile_map_keep maps a zeroed page there
 * instead and marks the mapping torn (cfile_map_torn): what was read from
 * it since may be zeros, and its owner must drop it (prep.c drops the
 * pattern and what was built from it, and fails the fit that read it).
 * The handler takes SIGSEGV too (valgrind reports the access so); a
 * fault anywhere else goes to the action there was before. */
typedef struct cfile_m {
    unsigned char *base;   /* the mapping; NULL: none */
    size_t size;           /* bytes mapped (the file's) */
    size_t len, at;        /* field bytes (the checksum excluded), bytes taken */
} cfile_m;

int cfile_map_open(const char *dir, const char *name, const char magic[8], uint32_t kind,
                   size_t max_bytes, cfile_m *m, glint_err *err);
const void *cfile_map_take(cfile_m *m, size_t n);
int cfile_map_align(cfile_m *m, size_t a);
/* The mapping is the caller's now (OUT: *base, *size; m forgets it). */
int cfile_map_keep(cfile_m *m, void **base, size_t *size);
/* Was a kept mapping cut short under the process (see above)? */
int cfile_map_torn(const void *base);
void cfile_map_close(cfile_m *m);
void cfile_unmap(void *base, size_t size);
/* Zeros up to the next multiple of `a` bytes of the file (a mapped
 * reader's arrays then lie aligned). */
void cfile_pad(cfile_w *b, size_t a);

/* A file name for a cache key of any characters: 32 hex digits of its
 * XXH3-128, then `ext` (OUT: name, at least 34 + strlen(ext) bytes). */
void cfile_name(const char *key, const char *ext, char *name, size_t len);

#endif
