/* cache.c: the precomputation cache (cache.h). */
#include "cache.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "lru.h"

#define NBUCKETS 256

const char *const cache_how_names[3] = {"hit", "built", "joined"};
const char *const cache_disk_names[4] = {"off", "loaded", "built", "rebuilt"};

enum { E_BUILDING, E_READY, E_FAILED };

struct cache_entry {
    char key[CACHE_KEY_MAX];
    int level;               /* index into the statistics */
    int state;
    int refs;                /* holders: callers and child entries */
    int in_table;            /* findable (and, when READY, in the LRU list) */
    cache_entry *parent;     /* one reference held on it */
    cache_entry *hnext;
    lru_node lru;
    cache_value val;
    double build_seconds, cold_seconds;
    cache_disk disk;
    glint_err err;           /* FAILED: why */
};

struct cache {
    char *dir;
    size_t budget;
    pthread_mutex_t lock;
    pthread_cond_t built;
    cache_entry *table[NBUCKETS];
    lru_list lru;            /* READY entries in the table */
    cache_stats st;
};

static unsigned bucket_of(const char *s)
{
    unsigned h = 2166136261u;
    while (*s)
        h = (h ^ (unsigned char)*s++) * 16777619u;
    return h % NBUCKETS;
}

int cache_open(const char *dir, size_t budget, cache **out, glint_err *err)
{
    cache *c = calloc(1, sizeof *c);
    *out = NULL;
    if (!c)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the cache");
    if (dir && !(c->dir = strdup(dir))) {
        free(c);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the cache");
    }
    c->budget = budget;
    pthread_mutex_init(&c->lock, NULL);
    pthread_cond_init(&c->built, NULL);
    *out = c;
    return 0;
}

const char *cache_dir(const cache *c)
{
    return c->dir;
}

/* The statistics slot of a level name (lock held); the last slot collects
 * names beyond CACHE_MAX_LEVELS. */
static int level_index(cache *c, const char *name)
{
    int i;
    for (i = 0; i < c->st.nlevels; i++)
        if (strcmp(c->st.level[i].name, name) == 0)
            return i;
    if (c->st.nlevels == CACHE_MAX_LEVELS)
        return CACHE_MAX_LEVELS - 1;
    i = c->st.nlevels++;
    snprintf(c->st.level[i].name, sizeof c->st.level[i].name, "%s", name);
    return i;
}

void cache_declare_level(cache *c, const char *name)
{
    pthread_mutex_lock(&c->lock);
    level_index(c, name);
    pthread_mutex_unlock(&c->lock);
}

static cache_entry *table_find(cache *c, const char *key)
{
    for (cache_entry *e = c->table[bucket_of(key)]; e; e = e->hnext)
        if (strcmp(e->key, key) == 0)
            return e;
    return NULL;
}

static void table_remove(cache *c, cache_entry *e)
{
    cache_entry **pp = &c->table[bucket_of(e->key)];
    while (*pp && *pp != e)
        pp = &(*pp)->hnext;
    if (*pp)
        *pp = e->hnext;
    e->hnext = NULL;
    e->in_table = 0;
}

/* Mark e and its parents as just used (parents first, so e ends first). */
static void touch(cache *c, cache_entry *e)
{
    if (!e || e->state != E_READY || !e->in_table)
        return;
    touch(c, e->parent);
    lru_touch(&c->lru, &e->lru);
}

static void release_locked(cache *c, cache_entry *e);

/* Free an entry nobody holds and nobody can find. */
static void destroy_locked(cache *c, cache_entry *e)
{
    cache_entry *parent = e->parent;
    if (e->val.free)
        e->val.free(e->val.data);
    free(e);
    if (parent)
        release_locked(c, parent);
}

/* Take a READY entry out of the table, the LRU list and the counts (it
 * is freed by whoever drops its last reference). */
static void unlist_locked(cache *c, cache_entry *e)
{
    lru_remove(&c->lru, &e->lru);
    table_remove(c, e);
    c->st.bytes -= e->val.bytes;
    c->st.entries--;
    c->st.level[e->level].bytes -= e->val.bytes;
    c->st.level[e->level].entries--;
}

/* Evict unpinned READY entries, least recently used first, until the
 * bytes fit.  Evicting a child may unpin its parent: scan again from the
 * tail after each eviction. */
static void evict_locked(cache *c)
{
    while (c->st.bytes > c->budget) {
        lru_node *n = lru_oldest(&c->lru);
        cache_entry *e = NULL;
        for (; n; n = n->prev) {
            cache_entry *x = lru_entry(n, cache_entry, lru);
            if (x->refs == 0) {
                e = x;
                break;
            }
        }
        if (!e)
            return; /* everything left is pinned */
        unlist_locked(c, e);
        c->st.level[e->level].evictions++;
        destroy_locked(c, e);
    }
}

static void release_locked(cache *c, cache_entry *e)
{
    if (!e || --e->refs > 0)
        return;
    if (!e->in_table) { /* failed or orphaned: nobody can find it */
        destroy_locked(c, e);
        return;
    }
    evict_locked(c);
}

/* Is x a or built from it (a among its parents)? */
static int built_from(const cache_entry *x, const cache_entry *a)
{
    for (; x; x = x->parent)
        if (x == a)
            return 1;
    return 0;
}

void cache_forget(cache *c, cache_entry *e)
{
    if (!e)
        return;
    pthread_mutex_lock(&c->lock);
    for (;;) {
        /* one at a time: destroying an entry may release others */
        cache_entry *x = NULL;
        for (int b = 0; b < NBUCKETS && !x; b++)
            for (x = c->table[b]; x; x = x->hnext)
                if (x->state == E_READY && built_from(x, e))
                    break;
        if (!x)
            break;
        unlist_locked(c, x);
        if (x->refs == 0)
            destroy_locked(c, x);
    }
    pthread_mutex_unlock(&c->lock);
}

void cache_release(cache *c, cache_entry *e)
{
    if (!e)
        return;
    pthread_mutex_lock(&c->lock);
    release_locked(c, e);
    pthread_mutex_unlock(&c->lock);
}

cache_entry *cache_ref(cache *c, cache_entry *e)
{
    pthread_mutex_lock(&c->lock);
    e->refs++;
    pthread_mutex_unlock(&c->lock);
    return e;
}

int cache_find(cache *c, const char *key, cache_entry **out)
{
    cache_entry *e;
    *out = NULL;
    pthread_mutex_lock(&c->lock);
    e = table_find(c, key);
    if (!e || e->state != E_READY) {
        pthread_mutex_unlock(&c->lock);
        return GLINT_ENOTFOUND;
    }
    e->refs++;
    pthread_mutex_unlock(&c->lock);
    *out = e;
    return 0;
}

void cache_hit(cache *c, cache_entry *e)
{
    pthread_mutex_lock(&c->lock);
    touch(c, e);
    c->st.level[e->level].hits++;
    pthread_mutex_unlock(&c->lock);
}

/* Make the value: from disk when the level has a disk layer, else built.
 * Runs without the lock. */
static int make_value(cache *c, const cache_level *lv, cache_entry *e, void *ctx)
{
    int rc;
    glint_err lerr;

    e->disk = CACHE_DISK_OFF;
    if (c->dir && lv->load && lv->save) {
        rc = lv->load(ctx, c->dir, e->key, &e->val, &lerr);
        if (rc == 0) {
            e->disk = CACHE_DISK_LOADED;
            return 0;
        }
        if (rc != GLINT_ENOTFOUND && rc != GLINT_EFORMAT) {
            e->err = lerr;
            return rc;
        }
        e->disk = rc == GLINT_EFORMAT ? CACHE_DISK_REBUILT : CACHE_DISK_BUILT;
    }
    rc = lv->build(ctx, &e->val, &e->err);
    if (rc)
        return rc;
    if (e->disk != CACHE_DISK_OFF && (rc = lv->save(ctx, c->dir, e->key, &e->val, &e->err))) {
        if (e->val.free)
            e->val.free(e->val.data);
        memset(&e->val, 0, sizeof e->val);
        return rc;
    }
    return 0;
}

int cache_acquire(cache *c, const cache_level *lv, const char *key, void *ctx,
                  cache_entry *parent, cache_entry **out, cache_how *how, double *seconds,
                  glint_err *err)
{
    cache_entry *e;
    double t0 = glint_now();
    int rc, li;

    *out = NULL;
    if (!key || !*key || strlen(key) >= CACHE_KEY_MAX)
        return glint_err_set(err, GLINT_ERANGE, "cache key of %zu bytes (1..%d allowed)",
                             key ? strlen(key) : 0, CACHE_KEY_MAX - 1);
    pthread_mutex_lock(&c->lock);
    li = level_index(c, lv->name);
    e = table_find(c, key);
    if (e && e->state == E_READY) {
        e->refs++;
        touch(c, e);
        c->st.level[li].hits++;
        pthread_mutex_unlock(&c->lock);
        *out = e;
        if (how)
            *how = CACHE_HIT;
        if (seconds)
            *seconds = 0.0;
        return 0;
    }
    if (e) { /* another caller builds it: wait */
        e->refs++;
        c->st.level[li].joins++;
        if (lv->starting) {
            pthread_mutex_unlock(&c->lock);
            lv->starting(ctx, CACHE_JOINED);
            pthread_mutex_lock(&c->lock);
        }
        while (e->state == E_BUILDING)
            pthread_cond_wait(&c->built, &c->lock);
        if (e->state == E_FAILED) {
            rc = e->err.code ? e->err.code : GLINT_EINTERNAL;
            if (err)
                *err = e->err;
            release_locked(c, e);
            pthread_mutex_unlock(&c->lock);
            return rc;
        }
        touch(c, e);
        pthread_mutex_unlock(&c->lock);
        *out = e;
        if (how)
            *how = CACHE_JOINED;
        if (seconds)
            *seconds = glint_now() - t0;
        return 0;
    }
    e = calloc(1, sizeof *e);
    if (!e) {
        pthread_mutex_unlock(&c->lock);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a cache entry");
    }
    snprintf(e->key, sizeof e->key, "%s", key);
    e->level = li;
    e->state = E_BUILDING;
    e->refs = 1;
    e->in_table = 1;
    if (parent) {
        parent->refs++;
        e->parent = parent;
    }
    e->hnext = c->table[bucket_of(key)];
    c->table[bucket_of(key)] = e;
    c->st.level[li].builds++;
    pthread_mutex_unlock(&c->lock);

    glint_err_clear(&e->err);
    if (lv->starting)
        lv->starting(ctx, CACHE_BUILT);
    rc = make_value(c, lv, e, ctx);
    e->build_seconds = glint_now() - t0;

    pthread_mutex_lock(&c->lock);
    if (rc == 0) {
        cache_level_stats *ls = &c->st.level[li];
        e->state = E_READY;
        e->cold_seconds = e->build_seconds + (parent ? parent->cold_seconds : 0.0);
        c->st.bytes += e->val.bytes;
        c->st.entries++;
        ls->bytes += e->val.bytes;
        ls->entries++;
        ls->build_seconds += e->build_seconds;
        ls->disk_loads += e->disk == CACHE_DISK_LOADED;
        ls->disk_builds += e->disk == CACHE_DISK_BUILT;
        ls->disk_rebuilds += e->disk == CACHE_DISK_REBUILT;
        lru_push(&c->lru, &e->lru);
        touch(c, e);
    } else {
        e->state = E_FAILED;
        if (!e->err.code)
            glint_err_set(&e->err, rc, "%s", glint_strerror(rc));
        e->err.code = rc;
        table_remove(c, e);
        c->st.level[li].failures++;
        if (err)
            *err = e->err;
    }
    pthread_cond_broadcast(&c->built);
    if (rc) {
        release_locked(c, e);
        pthread_mutex_unlock(&c->lock);
        return rc;
    }
    evict_locked(c); /* e itself is pinned by us */
    pthread_mutex_unlock(&c->lock);
    *out = e;
    if (how)
        *how = CACHE_BUILT;
    if (seconds)
        *seconds = e->build_seconds;
    return 0;
}

const void *cache_data(const cache_entry *e)
{
    return e->val.data;
}

const char *cache_key(const cache_entry *e)
{
    return e->key;
}

cache_entry *cache_parent(const cache_entry *e)
{
    return e->parent;
}

size_t cache_bytes(const cache_entry *e)
{
    return e->val.bytes;
}

double cache_build_seconds(const cache_entry *e)
{
    return e->build_seconds;
}

double cache_cold_seconds(const cache_entry *e)
{
    return e->cold_seconds;
}

cache_disk cache_disk_of(const cache_entry *e)
{
    return e->disk;
}

void cache_stats_get(cache *c, cache_stats *out)
{
    pthread_mutex_lock(&c->lock);
    *out = c->st;
    pthread_mutex_unlock(&c->lock);
    out->budget = c->budget;
}

void cache_close(cache *c)
{
    if (!c)
        return;
    /* children hold their parents: free in LRU order until the table is
     * empty (every entry was released, so each reachable one has refs 0
     * or is held only by its children) */
    pthread_mutex_lock(&c->lock);
    c->budget = 0;
    evict_locked(c);
    for (int b = 0; b < NBUCKETS; b++) /* anything left was still held: free it anyway */
        for (cache_entry *e = c->table[b], *next; e; e = next) {
            next = e->hnext;
            if (e->val.free)
                e->val.free(e->val.data);
            free(e);
        }
    pthread_mutex_unlock(&c->lock);
    pthread_cond_destroy(&c->built);
    pthread_mutex_destroy(&c->lock);
    free(c->dir);
    free(c);
}
