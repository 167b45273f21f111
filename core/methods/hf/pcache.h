/* pcache.h: precomputations on disk, keyed by the content hash of
 * everything they depend on.
 *
 * A key is 32 hex digits: XXH3-128 of a tag, the sampling-pattern hash and
 * the parameters of the precomputation.  A file holds a fixed little-endian
 * header, the payload and an XXH3-64 checksum of everything before it; a
 * file whose size, magic, key, sizes, values or checksum do not check out
 * is reported as GLINT_EFORMAT (never trusted: the caller rebuilds and
 * overwrites it).  Files are written atomically, without fsync
 * (fsio_write_rebuildable, fsio.h: a crash may tear one; the checks tell). */
#ifndef GLINT_PCACHE_H
#define GLINT_PCACHE_H

#include <stddef.h>

#include "err.h"
#include "hf.h"

/* Key of an hf decomposition (OUT: key[33]). */
void pcache_key_hf(const char pattern_hash[33], int res, double lambda, hf_route route,
                   double rcond, char key[33]);

/* File name of a key inside a cache directory (OUT: buf). */
int pcache_path(const char *dir, const char key[33], char *buf, size_t len, glint_err *err);

/* Save / load a decomposition under `key` in directory `dir` (created if
 * missing).  Load: 0, GLINT_ENOTFOUND (no file), GLINT_EFORMAT (corrupt or
 * mismatched; message says what), GLINT_EIO.  *out is owned by the caller. */
int pcache_decomp_save(const char *dir, const char key[33], const hf_decomp *dc,
                       glint_err *err);
int pcache_decomp_load(const char *dir, const char key[33], hf_decomp *out, glint_err *err);

/* Bytes a decomposition occupies in memory (arrays only). */
size_t pcache_decomp_bytes(const hf_decomp *dc);

/* Load the decomposition for `key` from `dir` (dir may be NULL: no disk
 * cache), or build it from the design and save it.  *hit says which
 * happened (1 loaded, 0 built); a corrupt file is rebuilt and replaced
 * (reported in *hit = -1). */
int pcache_decomp_get(const char *dir, const hf_design *d, const char pattern_hash[33],
                      double lambda, hf_route route, double rcond, hf_decomp *out, int *hit,
                      glint_err *err);

#endif
