/* cache.h: precomputations in memory and on disk, keyed by content hash.
 *
 * Every expensive step of a fit (a sampling pattern, a decomposition, an
 * operator, a transfer matrix) depends only on its inputs, so its key is a
 * hash of them and its value never changes: it can be shared by every fit
 * that needs it, built once, kept while memory allows, and kept on disk.
 * The daemon, the command line and the benchmarks use this one cache.
 *
 * Entries.  An entry has a key (a string, at most CACHE_KEY_MAX bytes), a
 * level (its kind, named for statistics: "pattern", "decomposition", ...),
 * a value (data + bytes + a free function) and optionally a parent: the
 * entry it was built from, on which it holds a reference, so a parent is
 * never evicted under its child.
 *
 * Life cycle.  cache_acquire() finds the key or builds it: the first caller
 * builds (outside the cache's lock, on its own thread); callers asking for
 * the same key meanwhile wait for that build and share its result or its
 * error (single flight).  A failed build leaves nothing behind: a later
 * request tries again.  Every holder owns one reference; an entry with
 * references is pinned.  After a build or a release, unpinned entries are
 * evicted from the least recently used end until the bytes held fit the
 * budget; pinned entries may keep the total above the budget for as long
 * as they are held (cache_stats says so).  A budget of 0 keeps nothing
 * that is not held (a private cache for one computation).  Using an entry
 * marks its whole chain of parents as used.
 *
 * Disk layer.  A level may give load and save functions; when the cache
 * has a directory, a missing value is first loaded from disk (the level
 * names its file from the key), else built and saved.  A file the level
 * finds corrupt or mismatched (GLINT_EFORMAT) is rebuilt and replaced, and
 * the entry says so.  Disk errors other than a missing or corrupt file
 * fail the acquisition.
 *
 * Thread-safety: every function may be called from any thread.  An
 * entry's value is read-only while anyone holds the entry.  cache_close()
 * requires that every entry was released. */
#ifndef GLINT_CACHE_H
#define GLINT_CACHE_H

#include <stddef.h>

#include "err.h"

#define CACHE_KEY_MAX 256
#define CACHE_MAX_LEVELS 16

typedef struct cache cache;
typedef struct cache_entry cache_entry;

/* What a build or a load produces.  `free` releases `data` (called once,
 * when the entry goes; may be NULL when data needs no release). */
typedef struct cache_value {
    void *data;
    size_t bytes;              /* memory held, counted against the budget */
    void (*free)(void *data);
} cache_value;

/* How one level is made.  ctx is the caller's, passed through unchanged. */
typedef struct cache_level {
    const char *name;          /* statistics and reports ("decomposition") */
    /* Optional: told, outside the lock, that this caller is about to build
     * (CACHE_BUILT) or to wait for another caller's build (CACHE_JOINED). */
    void (*starting)(void *ctx, int how);
    int (*build)(void *ctx, cache_value *out, glint_err *err);
    /* Optional disk layer: 0 with *out, GLINT_ENOTFOUND when there is no
     * file, GLINT_EFORMAT when it is corrupt or does not match (it is then
     * rebuilt and replaced), other codes fail. */
    int (*load)(void *ctx, const char *dir, const char *key, cache_value *out, glint_err *err);
    int (*save)(void *ctx, const char *dir, const char *key, const cache_value *v,
                glint_err *err);
} cache_level;

/* How an acquisition found its entry. */
typedef enum {
    CACHE_HIT = 0,    /* ready in memory */
    CACHE_BUILT = 1,  /* built (or loaded from disk) by this caller */
    CACHE_JOINED = 2  /* waited for another caller's build */
} cache_how;

/* What the disk layer answered when the entry was made. */
typedef enum {
    CACHE_DISK_OFF = 0,     /* no directory, or the level has no disk layer */
    CACHE_DISK_LOADED = 1,  /* read from disk */
    CACHE_DISK_BUILT = 2,   /* not on disk: built, then saved */
    CACHE_DISK_REBUILT = 3  /* on disk but corrupt: built, then replaced */
} cache_disk;

extern const char *const cache_how_names[3];  /* "hit", "built", "joined" */
extern const char *const cache_disk_names[4]; /* "off", "loaded", "built", "rebuilt" */

/* dir: the disk layer (NULL: memory only; created when first written).
 * budget: bytes of values to keep in memory (0: keep only what is held). */
int cache_open(const char *dir, size_t budget, cache **out, glint_err *err);

/* Free every entry (all must have been released).  Accepts NULL. */
void cache_close(cache *c);

/* The directory of the disk layer (NULL when memory only). */
const char *cache_dir(const cache *c);

/* The entry for `key`, built with `lv` (and ctx) when nobody has it.
 * parent (may be NULL) is what the value was built from: the new entry
 * takes a reference on it.  OUT: *out (one reference: release it), *how
 * and *seconds (time this call spent building or waiting; may be NULL).
 * GLINT_ERANGE for an empty or over-long key. */
int cache_acquire(cache *c, const cache_level *lv, const char *key, void *ctx,
                  cache_entry *parent, cache_entry **out, cache_how *how, double *seconds,
                  glint_err *err);

/* The entry for `key` if it is ready in memory now (nothing is built or
 * waited for): 0 with *out (one reference), else GLINT_ENOTFOUND.  Counts
 * nothing: a caller that uses what it found says so with cache_hit(). */
int cache_find(cache *c, const char *key, cache_entry **out);

/* Count a hit at e's level and mark e and its parents as just used. */
void cache_hit(cache *c, cache_entry *e);

/* One more reference on an entry the caller holds (returns e). */
cache_entry *cache_ref(cache *c, cache_entry *e);

/* Drop e and every entry built from it (its children, theirs, ...) from
 * the cache, e.g. when what e's value read is found damaged: the next
 * acquisition of their keys builds them again.  Holders keep what they
 * hold until they release it.  Accepts NULL. */
void cache_forget(cache *c, cache_entry *e);

/* Drop one reference.  Accepts NULL. */
void cache_release(cache *c, cache_entry *e);

/* About an entry (valid while it is held). */
const void *cache_data(const cache_entry *e);
const char *cache_key(const cache_entry *e);
cache_entry *cache_parent(const cache_entry *e);
size_t cache_bytes(const cache_entry *e);
double cache_build_seconds(const cache_entry *e); /* this level's own build or load */
double cache_cold_seconds(const cache_entry *e);  /* this level and its parents, as made */
cache_disk cache_disk_of(const cache_entry *e);

/* Counters, per level (levels are numbered in the order first seen;
 * cache_declare_level registers a name up front so that it is reported
 * before its first use). */
typedef struct cache_level_stats {
    char name[32];
    unsigned long long hits, joins, builds, failures, evictions;
    unsigned long long disk_loads, disk_builds, disk_rebuilds;
    size_t bytes, entries;
    double build_seconds;
} cache_level_stats;

typedef struct cache_stats {
    size_t bytes, entries, budget;
    int nlevels;
    cache_level_stats level[CACHE_MAX_LEVELS];
} cache_stats;

void cache_declare_level(cache *c, const char *name);
void cache_stats_get(cache *c, cache_stats *out);

#endif
