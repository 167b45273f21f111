/* fsio.h: small file-system helpers with glint error reporting.
 * Writes are atomic: data goes to a temporary file in the same directory,
 * is fsync'ed, then renamed over the target, so a crash leaves either the
 * old file or the new one, never a torn one. */
#ifndef GLINT_FSIO_H
#define GLINT_FSIO_H

#include <stddef.h>
#include <stdio.h>

#include "err.h"

/* An atomic write in progress: a temporary file (mode 0644, unique name
 * "<path>.tmp-XXXXXX") in the target's directory, open for writing on
 * `fp`.  Write to fp, then commit (flush, fsync, rename over the target,
 * fsync the directory) or abort (remove the temporary file).  Either call
 * releases everything; the target is untouched unless commit succeeds. */
typedef struct fsio_atomic {
    FILE *fp;
    char *tmp;   /* temporary path (owned) */
    char *path;  /* target path (owned copy) */
} fsio_atomic;

int fsio_atomic_open(fsio_atomic *a, const char *path, glint_err *err);
int fsio_atomic_commit(fsio_atomic *a, glint_err *err);
void fsio_atomic_abort(fsio_atomic *a);

/* Write len bytes atomically to path (open + fwrite + commit). */
int fsio_write_atomic(const char *path, const void *data, size_t len, glint_err *err);

/* A group of files written together (the files of a new material): between
 * fsio_group_begin and fsio_group_end, atomic writes on this thread are
 * renamed into place at once but made durable together by
 * fsio_group_end, which fsyncs every file of the group and then each of
 * their directories and its parent once (n + 2d fsyncs instead of 2n, and
 * a new directory's own entry is durable too).  A crash before
 * fsio_group_end has returned may leave any of the group's files empty or
 * missing, so nothing may name them durably before it has (glintd records
 * a material only after).  fsio_group_end returns the first failure;
 * without a group, commits are durable one by one.  Groups do not nest. */
typedef struct fsio_group {
    char **paths;    /* files committed, then their directories */
    int n, cap;
    int failed;      /* out of memory recording a path: end reports it */
} fsio_group;

void fsio_group_begin(fsio_group *g);
int fsio_group_end(fsio_group *g, glint_err *err);

/* An atomic write without fsync, for files glint can rebuild and checks on
 * every read (the checksummed cache files): readers never see a torn file
 * while the machine runs, but after a crash the file may be missing, empty
 * or torn, which its reader must detect (and the cache then rebuilds it).
 * Saves the fsync (15-25 ms for a 31 MB sampling pattern here). */
int fsio_write_rebuildable(const char *path, const void *data, size_t len, glint_err *err);

/* Read a whole file (at most max_len bytes, else GLINT_ERANGE) into a
 * malloc'ed buffer with a NUL appended (OUT: *data, *len). */
int fsio_read_all(const char *path, size_t max_len, char **data, size_t *len,
                  glint_err *err);

/* Name the kind of an I/O error from its errno (after glint_err_set):
 * "storage-full" (ENOSPC, EDQUOT, EFBIG) or "storage-read-only" (EROFS,
 * EACCES, EPERM); other errors keep none.  Returns err->code. */
int fsio_err_kind(glint_err *err, int errnum);

/* mkdir -p (mode 0755).  Existing directories are fine. */
int fsio_mkdirs(const char *path, glint_err *err);

/* Join dir and name into buf ("dir/name"); GLINT_ERANGE if it does not fit. */
int fsio_join(char *buf, size_t len, const char *dir, const char *name, glint_err *err);

#endif
