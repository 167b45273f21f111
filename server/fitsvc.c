/* fitsvc.c: the precomputation cache (levels, single flight, LRU under a
 * byte budget, disk layer) and the job pool.  The design is described in
 * fitsvc.h; numerics are core's (raster, samples, hf, pcache). */
#include "fitsvc.h"

#include <errno.h>
#include <malloc.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>

#include "fsio.h"
#include "pcache.h"
#include "raster.h"

#define KEY_MAX 192
#define NBUCKETS 256
#define JOBS_KEEP 1024          /* finished jobs kept for polling */
#define JOBS_KEEP_SECONDS 3600.0
#define JOB_LOG_MAX 256         /* events kept per job */
#define SVD_MAX_BYTES ((size_t)1 << 30) /* dense B for the svd route */
#define POINTS_SAVE_EVERY_S 2.0 /* speed-accuracy points: write-behind period */

const char *const fitsvc_level_names[FITSVC_NLEVELS] = {"scene", "pattern", "decomposition",
                                                        "operator"};

enum { E_BUILDING, E_READY, E_FAILED };
enum { HOW_HIT, HOW_BUILT, HOW_JOINED };
static const char *const how_names[3] = {"hit", "built", "joined"};

typedef struct entry {
    char key[KEY_MAX];
    int level;
    int state;
    int refs;              /* holders: callers, jobs, child entries */
    int in_table;          /* in the hash table (and, when READY, the LRU list) */
    struct entry *parent;  /* one reference held on it (decomp -> pattern, op -> decomp) */
    struct entry *hnext;
    struct entry *lprev, *lnext;
    size_t bytes;
    double build_seconds;  /* this level's own build */
    double cold_seconds;   /* this level plus its parents, as built */
    glint_err err;         /* FAILED: why */
    /* payload by level */
    const scene *sc;       /* scene: borrowed from the source until unload */
    fitsvc_scene_source src;
    char scene_id[33], hash[33];
    samples s;             /* pattern */
    double t_samples;
    hf_design d;           /* decomp */
    hf_decomp dc;
    int disk;              /* pcache answer: 1 loaded, 0 built, -1 rebuilt; 2: no disk layer */
    double t_design, t_decomp;
    hf_op op;              /* operator */
} entry;

struct fitsvc_prep {
    entry *op;             /* pinned (pins decomp, which pins pattern) */
    fit_prep fp;           /* shallow view on the chain's arrays */
    int how[FITSVC_NLEVELS];
    double spent[FITSVC_NLEVELS];
};

typedef struct fitsvc_job_rec fitsvc_job_rec;

struct fitsvc_job {
    fitsvc *f;
    char id[33], owner[33], kind[16];
    int state;             /* J_QUEUED, J_RUNNING, J_DONE, J_FAILED */
    char stage[32];
    double progress, logged_progress;
    time_t created, started, finished;
    double t_start, t_end; /* monotonic */
    json_t *result;
    char error[GLINT_ERR_MSG_MAX];
    fitsvc_job_fn fn;
    void *arg;
    void (*arg_free)(void *);
    json_t *log;           /* array of events */
    long long seq;
    struct fitsvc_job *qnext;   /* queue */
    struct fitsvc_job *hnext;   /* hash chain */
    struct fitsvc_job *anext;   /* all jobs, oldest first */
};

enum { J_QUEUED, J_RUNNING, J_DONE, J_FAILED };
static const char *const job_state_names[4] = {"queued", "running", "done", "failed"};

struct fitsvc {
    char *cache_dir;
    size_t budget;
    /* cache */
    pthread_mutex_t lock;
    pthread_cond_t built;
    entry *table[NBUCKETS];
    entry *lru_head, *lru_tail;  /* head: most recently used */
    fitsvc_stats st;             /* cache counters (jobs filled on read) */
    /* jobs */
    pthread_mutex_t jlock;
    pthread_cond_t jwork, jchange;
    fitsvc_job *qhead, *qtail;
    fitsvc_job *jtable[NBUCKETS];
    fitsvc_job *jall_head, *jall_tail;
    int njobs, queued, running, running_holdouts, stopping, streams_stopped;
    unsigned long long jobs_done, jobs_failed;
    pthread_t *workers;
    int nworkers;
    /* speed-accuracy points: scene hash -> {point key -> point} */
    pthread_mutex_t plock;
    json_t *points;
    json_t *points_dirty;       /* scene hashes not yet written */
    double points_saved_at;
    /* decoded paintings */
    pthread_mutex_t imlock;
    struct painting *paintings; /* most recently used first */
    size_t im_bytes, im_budget;
    unsigned long long im_hits, im_misses;
    /* material documents: most recently used first */
    struct doc *docs;
    size_t doc_bytes, doc_budget;
    unsigned long long doc_hits, doc_misses;
};

typedef struct doc {
    char id[33];
    fitsvc_doc d;
    struct doc *next;
} doc;

typedef struct painting {
    char session[33];
    int view;
    long long version;
    img im;
    int refs;              /* the cache's own (while listed) + pins */
    struct painting *next;
} painting;

struct fitsvc_painting {
    painting p;            /* (a handle is the entry itself) */
};

static double mono_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static unsigned hash_str(const char *s)
{
    unsigned h = 2166136261u;
    while (*s)
        h = (h ^ (unsigned char)*s++) * 16777619u;
    return h % NBUCKETS;
}

/* ---- entries: table, LRU, payload ----------------------------------------------- */

static entry *table_find(fitsvc *f, const char *key)
{
    for (entry *e = f->table[hash_str(key)]; e; e = e->hnext)
        if (strcmp(e->key, key) == 0)
            return e;
    return NULL;
}

static void table_remove(fitsvc *f, entry *e)
{
    entry **pp = &f->table[hash_str(e->key)];
    while (*pp && *pp != e)
        pp = &(*pp)->hnext;
    if (*pp)
        *pp = e->hnext;
    e->hnext = NULL;
    e->in_table = 0;
}

static void lru_unlink(fitsvc *f, entry *e)
{
    if (e->lprev)
        e->lprev->lnext = e->lnext;
    else if (f->lru_head == e)
        f->lru_head = e->lnext;
    if (e->lnext)
        e->lnext->lprev = e->lprev;
    else if (f->lru_tail == e)
        f->lru_tail = e->lprev;
    e->lprev = e->lnext = NULL;
}

static void lru_push_head(fitsvc *f, entry *e)
{
    e->lprev = NULL;
    e->lnext = f->lru_head;
    if (f->lru_head)
        f->lru_head->lprev = e;
    f->lru_head = e;
    if (!f->lru_tail)
        f->lru_tail = e;
}

/* Mark e and its chain as just used (parents first, so e ends at the head). */
static void touch(fitsvc *f, entry *e)
{
    if (!e || e->state != E_READY || !e->in_table)
        return;
    touch(f, e->parent);
    lru_unlink(f, e);
    lru_push_head(f, e);
}

static void payload_free(entry *e)
{
    if (e->sc && e->src.unload)
        e->src.unload(e->src.cls, e->sc);
    e->sc = NULL;
    samples_free(&e->s);
    hf_design_free(&e->d);
    hf_decomp_free(&e->dc);
    hf_op_free(&e->op);
}

static void release_locked(fitsvc *f, entry *e);

/* Free an entry that nobody holds and that is out of the table. */
static void entry_destroy(fitsvc *f, entry *e)
{
    entry *parent = e->parent;
    payload_free(e);
    free(e);
    if (parent)
        release_locked(f, parent);
}

/* Evict unpinned READY entries, least recently used first, until the bytes
 * fit the budget.  Evicting a child may unpin its parent: the scan restarts
 * from the tail. */
static void evict_locked(fitsvc *f)
{
    while (f->st.bytes > f->budget) {
        entry *e = f->lru_tail;
        while (e && e->refs > 0)
            e = e->lprev;
        if (!e)
            return; /* everything left is pinned */
        lru_unlink(f, e);
        table_remove(f, e);
        f->st.bytes -= e->bytes;
        f->st.entries--;
        f->st.lvl_bytes[e->level] -= e->bytes;
        f->st.lvl_entries[e->level]--;
        f->st.evictions++;
        f->st.lvl_evictions[e->level]++;
        entry_destroy(f, e);
    }
}

static void release_locked(fitsvc *f, entry *e)
{
    if (!e)
        return;
    if (--e->refs > 0)
        return;
    if (!e->in_table) { /* failed, or the table was emptied: nobody can find it */
        entry_destroy(f, e);
        return;
    }
    evict_locked(f);
}

static void release(fitsvc *f, entry *e)
{
    if (!e)
        return;
    pthread_mutex_lock(&f->lock);
    release_locked(f, e);
    pthread_mutex_unlock(&f->lock);
}

/* What a build step needs; one function per level. */
typedef struct build_ctx {
    fitsvc *f;
    const fitsvc_request *rq;
    entry *parent;                   /* the level below (pinned by the caller) */
    const fitsvc_scene_source *src;  /* scene level */
    const char *scene_id;
    fitsvc_progress_fn cb;
    void *cls;
} build_ctx;

typedef int (*build_fn)(entry *e, build_ctx *b, glint_err *err);

static void progress(build_ctx *b, const char *stage, double p)
{
    if (b->cb)
        b->cb(b->cls, stage, p);
}

/* Progress points of the stages (fraction of the whole preparation). */
static const double stage_at[FITSVC_NLEVELS] = {0.0, 0.0, 0.3, 0.85};
static const char *const stage_of[FITSVC_NLEVELS] = {"scene", "samples", "decomposition",
                                                     "operator"};

/* Get `key` at `level`, building it with fn where nobody has (single
 * flight).  OUT: *out (one reference), *how. */
static int acquire(fitsvc *f, int level, const char *key, build_fn fn, build_ctx *b,
                   entry **out, int *how, double *spent, glint_err *err)
{
    entry *e;
    double t0 = mono_now();
    int rc;

    *out = NULL;
    if (strlen(key) >= KEY_MAX)
        return glint_err_set(err, GLINT_EINTERNAL, "cache key too long");
    pthread_mutex_lock(&f->lock);
    e = table_find(f, key);
    if (e && e->state == E_READY) {
        e->refs++;
        touch(f, e);
        f->st.lvl_hits[level]++;
        pthread_mutex_unlock(&f->lock);
        *out = e;
        *how = HOW_HIT;
        *spent = 0.0;
        return 0;
    }
    if (e) { /* being built by another thread: wait for it */
        e->refs++;
        f->st.lvl_joins[level]++;
        pthread_mutex_unlock(&f->lock);
        if (b)
            progress(b, stage_of[level], stage_at[level]);
        pthread_mutex_lock(&f->lock);
        while (e->state == E_BUILDING)
            pthread_cond_wait(&f->built, &f->lock);
        if (e->state == E_FAILED) {
            rc = e->err.code ? e->err.code : GLINT_EINTERNAL;
            if (err)
                *err = e->err;
            release_locked(f, e);
            pthread_mutex_unlock(&f->lock);
            return rc;
        }
        touch(f, e);
        pthread_mutex_unlock(&f->lock);
        *out = e;
        *how = HOW_JOINED;
        *spent = mono_now() - t0;
        return 0;
    }
    e = calloc(1, sizeof *e);
    if (!e) {
        pthread_mutex_unlock(&f->lock);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a cache entry");
    }
    snprintf(e->key, sizeof e->key, "%s", key);
    e->level = level;
    e->state = E_BUILDING;
    e->refs = 1;
    e->in_table = 1;
    e->hnext = f->table[hash_str(key)];
    f->table[hash_str(key)] = e;
    f->st.lvl_builds[level]++;
    pthread_mutex_unlock(&f->lock);

    rc = fn(e, b, &e->err);
    e->build_seconds = mono_now() - t0;

    pthread_mutex_lock(&f->lock);
    if (rc == 0) {
        e->state = E_READY;
        e->cold_seconds = e->build_seconds + (e->parent ? e->parent->cold_seconds : 0.0);
        f->st.bytes += e->bytes;
        f->st.entries++;
        f->st.lvl_bytes[level] += e->bytes;
        f->st.lvl_entries[level]++;
        f->st.build_seconds[level] += e->build_seconds;
        lru_push_head(f, e);
        touch(f, e);
    } else {
        e->state = E_FAILED;
        e->err.code = rc;
        table_remove(f, e);
        f->st.lvl_failures[level]++;
        if (err)
            *err = e->err;
    }
    pthread_cond_broadcast(&f->built);
    if (rc) {
        release_locked(f, e);
        pthread_mutex_unlock(&f->lock);
        return rc;
    }
    evict_locked(f); /* e is pinned by us */
    pthread_mutex_unlock(&f->lock);
    *out = e;
    *how = HOW_BUILT;
    *spent = e->build_seconds;
    return 0;
}

/* Pin `parent` for the entry being built. */
static void adopt_parent(fitsvc *f, entry *e, entry *parent)
{
    pthread_mutex_lock(&f->lock);
    parent->refs++;
    e->parent = parent;
    pthread_mutex_unlock(&f->lock);
}

/* ---- builders ----------------------------------------------------------------------- */

static size_t mesh_bytes(const mesh *m)
{
    return (size_t)m->nverts * 8 * sizeof(float) + (size_t)m->ntris * 3 * sizeof(uint32_t);
}

static int build_scene(entry *e, build_ctx *b, glint_err *err)
{
    int rc = b->src->load(b->src->cls, b->scene_id, &e->sc, err);
    if (rc) {
        e->sc = NULL;
        return rc;
    }
    e->src = *b->src;
    scene_hash(e->sc, e->hash);
    snprintf(e->scene_id, sizeof e->scene_id, "%s", b->scene_id);
    e->bytes = sizeof *e + mesh_bytes(&e->sc->mesh) + (size_t)e->sc->nviews * sizeof(scene_view);
    return 0;
}

static size_t samples_bytes(const samples *s)
{
    return (size_t)s->n * (2 * sizeof(int) + 9 * sizeof(float) + 2 * sizeof(double)) +
           (size_t)s->nviews;
}

static int build_pattern(entry *e, build_ctx *b, glint_err *err)
{
    const entry *se = (const entry *)b->rq->scene;
    const scene *sc = se->sc;
    gbuf *g = calloc((size_t)sc->nviews, sizeof *g);
    int rc = 0, nused = 0, done = 0;
    double t0 = mono_now();

    if (!g)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d G-buffers", sc->nviews);
    for (int v = 0; v < sc->nviews; v++)
        nused += b->rq->use[v] != 0;
    progress(b, "samples", 0.0);
    for (int v = 0; v < sc->nviews; v++) {
        if (!b->rq->use[v]) {
            /* not painted: left out of the pattern; samples_build reads only
             * the size of an unused view */
            g[v].width = sc->width;
            g[v].height = sc->height;
            continue;
        }
        rc = raster_view(&sc->mesh, &sc->views[v], sc->width, sc->height, &g[v], err);
        if (rc) {
            glint_err_prefix(err, "rasterizing view %d", v);
            goto done;
        }
        done++;
        progress(b, "samples", 0.25 * done / (nused ? nused : 1));
    }
    rc = samples_build(g, sc->views, sc->nviews, b->rq->use, se->hash, &e->s, err);
    if (rc)
        goto done;
    e->t_samples = mono_now() - t0;
    e->bytes = sizeof *e + samples_bytes(&e->s);
done:
    raster_free_all(g, sc->nviews);
    return rc;
}

static int build_decomp(entry *e, build_ctx *b, glint_err *err)
{
    const fit_params *p = &b->rq->params;
    entry *pat = b->parent;
    double t0 = mono_now();
    int rc;

    adopt_parent(b->f, e, pat);
    progress(b, "design", 0.25);
    rc = hf_design_build(&pat->s, p->res, &e->d, err);
    if (rc)
        return rc;
    e->t_design = mono_now() - t0;
    if (p->route == HF_ROUTE_SVD) {
        size_t rows = (size_t)pat->s.n + 3 * (size_t)(p->res - 2), cols = 3 * (size_t)p->res;
        if (rows * cols * sizeof(double) > SVD_MAX_BYTES)
            return glint_err_set(err, GLINT_ERANGE,
                                 "route svd needs a dense %zux%zu constraint matrix (%.1f GiB), "
                                 "over the daemon's limit of %.1f GiB: use route eig",
                                 rows, cols, (double)(rows * cols * 8) / (1 << 30),
                                 (double)SVD_MAX_BYTES / (1 << 30));
    }
    progress(b, "decomposition", 0.3);
    t0 = mono_now();
    rc = pcache_decomp_get(b->f->cache_dir, &e->d, pat->s.hash, p->lambda, p->route, p->rcond,
                           &e->dc, &e->disk, err);
    if (rc)
        return rc;
    if (!b->f->cache_dir)
        e->disk = 2;
    e->t_decomp = mono_now() - t0;
    e->bytes = sizeof *e + (size_t)e->d.n * 3 * (sizeof(int32_t) + sizeof(double)) +
               (size_t)e->d.n * sizeof(double) + pcache_decomp_bytes(&e->dc);
    pthread_mutex_lock(&b->f->lock);
    if (e->disk == 1)
        b->f->st.disk_loads++;
    else if (e->disk == 0)
        b->f->st.disk_builds++;
    else if (e->disk == -1)
        b->f->st.disk_rebuilds++;
    pthread_mutex_unlock(&b->f->lock);
    return 0;
}

static int build_op(entry *e, build_ctx *b, glint_err *err)
{
    const fit_params *p = &b->rq->params;
    int rc;

    adopt_parent(b->f, e, b->parent);
    progress(b, "operator", 0.85);
    rc = hf_op_build(&b->parent->dc, &p->reg, p->prec, &e->op, err);
    if (rc)
        return rc;
    e->bytes = sizeof *e + hf_op_bytes(&e->op, NULL);
    return 0;
}

/* ---- keys ------------------------------------------------------------------------------ */

static void key_pattern(const fitsvc_request *rq, char *key, size_t len)
{
    const entry *se = (const entry *)rq->scene;
    const scene *sc = se->sc;
    int n = snprintf(key, len, "pattern:%s:", se->hash);
    /* the used-view flags as hex digits, 4 views per digit */
    for (int v = 0; v < sc->nviews && (size_t)n + 2 < len; v += 4) {
        int nib = 0;
        for (int k = 0; k < 4 && v + k < sc->nviews; k++)
            nib |= (rq->use[v + k] ? 1 : 0) << k;
        key[n++] = "0123456789abcdef"[nib];
    }
    key[n] = '\0';
}

static void key_op(const char *decomp_key, const fit_params *p, char *key, size_t len)
{
    char reg[64];
    hf_reg_format(&p->reg, reg, sizeof reg);
    snprintf(key, len, "%s/%s/%s", decomp_key, reg, p->prec == HF_F32 ? "single" : "double");
}

static void key_decomp(const entry *pattern, const fit_params *p, char key[33])
{
    pcache_key_hf(pattern->s.hash, p->res, p->lambda, p->route, p->rcond, key);
}

/* ---- scenes ------------------------------------------------------------------------------ */

int fitsvc_scene_acquire(fitsvc *f, const char *scene_id, const fitsvc_scene_source *src,
                         fitsvc_scene **out, glint_err *err)
{
    char key[KEY_MAX];
    build_ctx b;
    entry *e;
    int how;
    double spent;
    int rc;

    memset(&b, 0, sizeof b);
    b.f = f;
    b.src = src;
    b.scene_id = scene_id;
    snprintf(key, sizeof key, "scene:%s", scene_id);
    rc = acquire(f, FITSVC_LEVEL_SCENE, key, build_scene, &b, &e, &how, &spent, err);
    *out = rc ? NULL : (fitsvc_scene *)e;
    return rc;
}

const scene *fitsvc_scene_get(const fitsvc_scene *h)
{
    return ((const entry *)h)->sc;
}

const char *fitsvc_scene_hash(const fitsvc_scene *h)
{
    return ((const entry *)h)->hash;
}

const char *fitsvc_scene_id(const fitsvc_scene *h)
{
    return ((const entry *)h)->scene_id;
}

fitsvc_scene *fitsvc_scene_ref(fitsvc *f, fitsvc_scene *h)
{
    pthread_mutex_lock(&f->lock);
    ((entry *)h)->refs++;
    pthread_mutex_unlock(&f->lock);
    return h;
}

void fitsvc_scene_release(fitsvc *f, fitsvc_scene *h)
{
    release(f, (entry *)h);
}

/* ---- prepared fits ------------------------------------------------------------------------- */

static void prep_fill(fitsvc_prep *p)
{
    entry *op = p->op, *dc = op->parent, *pat = dc->parent;
    fit_prep *fp = &p->fp;

    /* a shallow view: the arrays stay the entries' (never fit_prep_free) */
    fp->s = pat->s;
    fp->d = dc->d;
    fp->dc = dc->dc;
    fp->op = op->op;
    fp->cache_hit = dc->disk == 2 ? 0 : dc->disk;
    snprintf(fp->cache_key, sizeof fp->cache_key, "%.32s", dc->key);
    fp->t_samples = p->how[FITSVC_LEVEL_PATTERN] == HOW_BUILT ? pat->t_samples
                                                              : p->spent[FITSVC_LEVEL_PATTERN];
    fp->t_design = p->how[FITSVC_LEVEL_DECOMP] == HOW_BUILT ? dc->t_design : 0.0;
    fp->t_decomp = p->how[FITSVC_LEVEL_DECOMP] == HOW_BUILT ? dc->t_decomp
                                                            : p->spent[FITSVC_LEVEL_DECOMP];
    fp->t_op = p->spent[FITSVC_LEVEL_OP];
}

static void prep_params(fitsvc_prep *p, const fit_params *params)
{
    p->fp.params = *params;
}

int fitsvc_prep_try(fitsvc *f, const fitsvc_request *rq, fitsvc_prep **out, glint_err *err)
{
    char kp[KEY_MAX], kd[33], ko[KEY_MAX];
    entry *pat, *dc = NULL, *op = NULL;
    fitsvc_prep *p;

    *out = NULL;
    key_pattern(rq, kp, sizeof kp);
    pthread_mutex_lock(&f->lock);
    pat = table_find(f, kp);
    if (pat && pat->state == E_READY) {
        key_decomp(pat, &rq->params, kd);
        dc = table_find(f, kd);
        if (dc && dc->state == E_READY) {
            key_op(kd, &rq->params, ko, sizeof ko);
            op = table_find(f, ko);
        }
    }
    if (!op || op->state != E_READY) {
        /* not counted: the job that follows counts the request */
        pthread_mutex_unlock(&f->lock);
        return glint_err_set(err, GLINT_ENOTFOUND, "the precomputation is not in memory");
    }
    p = calloc(1, sizeof *p);
    if (!p) {
        pthread_mutex_unlock(&f->lock);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    op->refs++;
    touch(f, op);
    f->st.hits++;
    for (int l = FITSVC_LEVEL_PATTERN; l < FITSVC_NLEVELS; l++)
        f->st.lvl_hits[l]++;
    pthread_mutex_unlock(&f->lock);
    p->op = op;
    for (int l = 0; l < FITSVC_NLEVELS; l++)
        p->how[l] = HOW_HIT;
    prep_params(p, &rq->params);
    prep_fill(p);
    *out = p;
    return 0;
}

int fitsvc_prep_acquire(fitsvc *f, const fitsvc_request *rq, fitsvc_progress_fn cb, void *cls,
                        fitsvc_prep **out, glint_err *err)
{
    char kp[KEY_MAX], kd[33], ko[KEY_MAX];
    entry *pat = NULL, *dc = NULL, *op = NULL;
    fitsvc_prep *p;
    build_ctx b;
    int rc, all_hit;

    *out = NULL;
    p = calloc(1, sizeof *p);
    if (!p)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    memset(&b, 0, sizeof b);
    b.f = f;
    b.rq = rq;
    b.cb = cb;
    b.cls = cls;
    p->how[FITSVC_LEVEL_SCENE] = HOW_HIT;

    key_pattern(rq, kp, sizeof kp);
    rc = acquire(f, FITSVC_LEVEL_PATTERN, kp, build_pattern, &b, &pat, &p->how[1], &p->spent[1],
                 err);
    if (rc)
        goto fail;
    key_decomp(pat, &rq->params, kd);
    b.parent = pat;
    rc = acquire(f, FITSVC_LEVEL_DECOMP, kd, build_decomp, &b, &dc, &p->how[2], &p->spent[2], err);
    if (rc)
        goto fail;
    key_op(kd, &rq->params, ko, sizeof ko);
    b.parent = dc;
    rc = acquire(f, FITSVC_LEVEL_OP, ko, build_op, &b, &op, &p->how[3], &p->spent[3], err);
    if (rc)
        goto fail;
    /* op pins dc, dc pins the pattern: our own references on them go */
    release(f, dc);
    release(f, pat);
    all_hit = p->how[1] == HOW_HIT && p->how[2] == HOW_HIT && p->how[3] == HOW_HIT;
    pthread_mutex_lock(&f->lock);
    if (all_hit)
        f->st.hits++;
    else
        f->st.misses++;
    pthread_mutex_unlock(&f->lock);
    p->op = op;
    prep_params(p, &rq->params);
    prep_fill(p);
    *out = p;
    return 0;
fail:
    release(f, dc);
    release(f, pat);
    free(p);
    return rc;
}

const fit_prep *fitsvc_prep_fit(const fitsvc_prep *p)
{
    return &p->fp;
}

double fitsvc_prep_cold_seconds(const fitsvc_prep *p)
{
    return p->op->cold_seconds;
}

json_t *fitsvc_prep_report(const fitsvc_prep *p)
{
    entry *lv[FITSVC_NLEVELS] = {NULL, p->op->parent->parent, p->op->parent, p->op};
    static const char *const disk_names[4] = {"rebuilt", "built", "loaded", "off"};
    json_t *r = json_object(), *levels = json_object();
    int overall = HOW_HIT;

    for (int l = FITSVC_LEVEL_PATTERN; l < FITSVC_NLEVELS; l++) {
        json_t *o = json_pack("{s:s, s:s, s:I, s:f, s:f}", "key", lv[l]->key, "memory",
                              how_names[p->how[l]], "bytes", (json_int_t)lv[l]->bytes,
                              "build_seconds", lv[l]->build_seconds, "waited_seconds",
                              p->how[l] == HOW_JOINED ? p->spent[l] : 0.0);
        json_object_set_new(levels, fitsvc_level_names[l], o);
        if (p->how[l] == HOW_BUILT)
            overall = HOW_BUILT;
        else if (p->how[l] == HOW_JOINED && overall == HOW_HIT)
            overall = HOW_JOINED;
    }
    json_object_set_new(r, "memory", json_string(how_names[overall]));
    json_object_set_new(r, "disk", json_string(disk_names[p->op->parent->disk + 1]));
    json_object_set_new(r, "key", json_string(p->op->key));
    json_object_set_new(r, "cold_seconds", json_real(p->op->cold_seconds));
    json_object_set_new(r, "levels", levels);
    return r;
}

void fitsvc_prep_release(fitsvc *f, fitsvc_prep *p)
{
    if (!p)
        return;
    release(f, p->op);
    free(p);
}

/* ---- jobs --------------------------------------------------------------------------------------- */

static void iso_time(time_t t, char buf[32])
{
    struct tm tm;
    gmtime_r(&t, &tm);
    strftime(buf, 32, "%Y-%m-%dT%H:%M:%SZ", &tm);
}

/* The job as JSON (called with jlock held). */
static json_t *job_json(const fitsvc_job *j)
{
    char t[32];
    json_t *o = json_object();
    json_object_set_new(o, "id", json_string(j->id));
    json_object_set_new(o, "kind", json_string(j->kind));
    json_object_set_new(o, "state", json_string(job_state_names[j->state]));
    json_object_set_new(o, "progress", json_real(j->progress));
    json_object_set_new(o, "stage", json_string(j->stage));
    iso_time(j->created, t);
    json_object_set_new(o, "created", json_string(t));
    if (j->state != J_QUEUED) {
        iso_time(j->started, t);
        json_object_set_new(o, "started", json_string(t));
        json_object_set_new(o, "seconds",
                            json_real((j->state >= J_DONE ? j->t_end : mono_now()) - j->t_start));
    }
    if (j->state >= J_DONE) {
        iso_time(j->finished, t);
        json_object_set_new(o, "finished", json_string(t));
    }
    if (j->state == J_DONE && j->result)
        json_object_update(o, j->result);
    if (j->state == J_FAILED)
        json_object_set_new(o, "error", json_string(j->error));
    return o;
}

/* Append an event to the job's log and wake the listeners (jlock held). */
static void job_log(fitsvc *f, fitsvc_job *j, const char *type)
{
    json_t *ev;
    if (json_array_size(j->log) >= JOB_LOG_MAX && strcmp(type, "progress") == 0)
        return;
    ev = json_pack("{s:I, s:s, s:o}", "seq", (json_int_t)++j->seq, "type", type, "job",
                   job_json(j));
    if (ev)
        json_array_append_new(j->log, ev);
    j->logged_progress = j->progress;
    pthread_cond_broadcast(&f->jchange);
}

int fitsvc_job_cancelled(fitsvc_job *job)
{
    int stop;
    pthread_mutex_lock(&job->f->jlock);
    stop = job->f->stopping;
    pthread_mutex_unlock(&job->f->jlock);
    return stop;
}

void fitsvc_job_progress(fitsvc_job *job, const char *stage, double p)
{
    fitsvc *f = job->f;
    int changed;
    if (!(p >= 0.0))
        p = 0.0;
    if (p > 1.0)
        p = 1.0;
    pthread_mutex_lock(&f->jlock);
    changed = strcmp(job->stage, stage) != 0;
    if (p > job->progress)
        job->progress = p;
    snprintf(job->stage, sizeof job->stage, "%s", stage);
    if (changed || job->progress - job->logged_progress >= 0.05)
        job_log(f, job, "progress");
    pthread_mutex_unlock(&f->jlock);
}

static void job_free(fitsvc_job *j)
{
    if (!j)
        return;
    if (j->arg_free)
        j->arg_free(j->arg);
    json_decref(j->result);
    json_decref(j->log);
    free(j);
}

static void job_table_remove(fitsvc *f, fitsvc_job *j)
{
    fitsvc_job **pp = &f->jtable[hash_str(j->id)];
    while (*pp && *pp != j)
        pp = &(*pp)->hnext;
    if (*pp)
        *pp = j->hnext;
}

/* Forget finished jobs beyond the retention limits (jlock held). */
static void jobs_expire(fitsvc *f)
{
    fitsvc_job **pp = &f->jall_head, *prev = NULL;
    double now = mono_now();
    while (*pp) {
        fitsvc_job *j = *pp;
        if (j->state >= J_DONE &&
            (f->njobs > JOBS_KEEP || now - j->t_end > JOBS_KEEP_SECONDS)) {
            *pp = j->anext;
            if (f->jall_tail == j)
                f->jall_tail = prev;
            job_table_remove(f, j);
            f->njobs--;
            job_free(j);
            continue;
        }
        prev = j;
        pp = &j->anext;
    }
}

static fitsvc_job *job_find(fitsvc *f, const char *id)
{
    for (fitsvc_job *j = f->jtable[hash_str(id)]; j; j = j->hnext)
        if (strcmp(j->id, id) == 0)
            return j;
    return NULL;
}

static int new_id(char id[33], glint_err *err)
{
    unsigned char r[16];
    size_t got = 0;
    while (got < sizeof r) {
        ssize_t n = getrandom(r + got, sizeof r - got, 0);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return glint_err_set(err, GLINT_EIO, "getrandom: %s", strerror(errno));
        }
        got += (size_t)n;
    }
    for (int i = 0; i < 16; i++)
        snprintf(id + 2 * i, 3, "%02x", r[i]);
    return 0;
}

int fitsvc_job_submit(fitsvc *f, const char *kind, const char *owner, fitsvc_job_fn fn,
                      void *arg, void (*arg_free)(void *), char id[33], glint_err *err)
{
    fitsvc_job *j = calloc(1, sizeof *j);
    int rc;

    if (!j || !(j->log = json_array())) {
        free(j);
        if (arg_free)
            arg_free(arg);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a job");
    }
    j->f = f;
    j->fn = fn;
    j->arg = arg;
    j->arg_free = arg_free;
    snprintf(j->owner, sizeof j->owner, "%s", owner ? owner : "");
    snprintf(j->kind, sizeof j->kind, "%s", kind ? kind : "fit");
    snprintf(j->stage, sizeof j->stage, "queued");
    if ((rc = new_id(j->id, err))) {
        job_free(j);
        return rc;
    }
    j->created = time(NULL);
    pthread_mutex_lock(&f->jlock);
    if (f->stopping) {
        pthread_mutex_unlock(&f->jlock);
        job_free(j);
        return glint_err_set(err, GLINT_EUNSUPPORTED, "the daemon is stopping");
    }
    if (f->queued >= FITSVC_MAX_QUEUED) {
        pthread_mutex_unlock(&f->jlock);
        job_free(j);
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "%d fit jobs are waiting already (the limit): try again later",
                             FITSVC_MAX_QUEUED);
    }
    jobs_expire(f);
    j->hnext = f->jtable[hash_str(j->id)];
    f->jtable[hash_str(j->id)] = j;
    if (f->jall_tail)
        f->jall_tail->anext = j;
    else
        f->jall_head = j;
    f->jall_tail = j;
    f->njobs++;
    {
        /* fit jobs go before queued holdout jobs (background measurements) */
        fitsvc_job **pp = &f->qhead;
        int is_fit = strcmp(j->kind, "holdout") != 0;
        while (*pp && !(is_fit && strcmp((*pp)->kind, "holdout") == 0))
            pp = &(*pp)->qnext;
        j->qnext = *pp;
        *pp = j;
        if (!j->qnext)
            f->qtail = j;
    }
    f->queued++;
    job_log(f, j, "progress");
    memcpy(id, j->id, 33);
    pthread_cond_signal(&f->jwork);
    pthread_mutex_unlock(&f->jlock);
    return 0;
}

static int points_flush(fitsvc *f, int force, glint_err *err);

static int is_holdout(const fitsvc_job *j)
{
    return strcmp(j->kind, "holdout") == 0;
}

/* The next job a worker may take (jlock held): the first queued one, but a
 * holdout job (a background measurement) only while no other runs, so that
 * with two workers or more one is always free for fits. */
static fitsvc_job *job_next(fitsvc *f)
{
    for (fitsvc_job *j = f->qhead; j; j = j->qnext)
        if (!is_holdout(j) || f->running_holdouts == 0)
            return j;
    return NULL;
}

static void *worker_main(void *arg)
{
    fitsvc *f = arg;
    for (;;) {
        fitsvc_job *j;
        json_t *result = NULL;
        glint_err e;
        int rc;

        pthread_mutex_lock(&f->jlock);
        while (!f->stopping && !(j = job_next(f))) {
            struct timespec dl;
            clock_gettime(CLOCK_REALTIME, &dl);
            dl.tv_sec += (time_t)POINTS_SAVE_EVERY_S;
            if (pthread_cond_timedwait(&f->jwork, &f->jlock, &dl) == ETIMEDOUT &&
                pthread_mutex_trylock(&f->plock) == 0) {
                /* idle: write the speed-accuracy points recorded lately */
                glint_err pe;
                if (json_object_size(f->points_dirty) && points_flush(f, 1, &pe))
                    fprintf(stderr, "glintd: saving fit points: %s\n", pe.msg);
                pthread_mutex_unlock(&f->plock);
            }
        }
        if (f->stopping) {
            pthread_mutex_unlock(&f->jlock);
            return NULL;
        }
        {
            fitsvc_job **pp = &f->qhead, *prev = NULL;
            while (*pp != j) {
                prev = *pp;
                pp = &(*pp)->qnext;
            }
            *pp = j->qnext;
            if (f->qtail == j)
                f->qtail = prev;
            j->qnext = NULL;
        }
        f->queued--;
        f->running++;
        if (is_holdout(j))
            f->running_holdouts++;
        j->state = J_RUNNING;
        j->started = time(NULL);
        j->t_start = mono_now();
        snprintf(j->stage, sizeof j->stage, "started");
        job_log(f, j, "progress");
        pthread_mutex_unlock(&f->jlock);

        glint_err_clear(&e);
        rc = j->fn(j, j->arg, &result, &e);

        pthread_mutex_lock(&f->jlock);
        f->running--;
        if (is_holdout(j)) {
            f->running_holdouts--;
            pthread_cond_signal(&f->jwork); /* a queued holdout may go now */
        }
        j->t_end = mono_now();
        j->finished = time(NULL);
        if (rc == 0) {
            j->state = J_DONE;
            j->progress = 1.0;
            snprintf(j->stage, sizeof j->stage, "done");
            j->result = json_is_object(result) ? result : NULL;
            if (!j->result)
                json_decref(result);
            f->jobs_done++;
            job_log(f, j, "done");
        } else {
            json_decref(result);
            j->state = J_FAILED;
            snprintf(j->error, sizeof j->error, "%s", e.msg[0] ? e.msg : glint_strerror(rc));
            f->jobs_failed++;
            job_log(f, j, "failed");
        }
        /* the job's argument (paintings, scene handle) is not needed any more */
        if (j->arg_free)
            j->arg_free(j->arg);
        j->arg = NULL;
        j->arg_free = NULL;
        pthread_mutex_unlock(&f->jlock);
    }
}

int fitsvc_job_get(fitsvc *f, const char *id, json_t **job, char owner[33], glint_err *err)
{
    fitsvc_job *j;
    *job = NULL;
    pthread_mutex_lock(&f->jlock);
    j = job_find(f, id);
    if (!j) {
        pthread_mutex_unlock(&f->jlock);
        return glint_err_set(err, GLINT_ENOTFOUND, "no job %s (unknown, or finished over an hour ago)",
                             id);
    }
    *job = job_json(j);
    if (owner)
        memcpy(owner, j->owner, 33);
    pthread_mutex_unlock(&f->jlock);
    return 0;
}

int fitsvc_job_events(fitsvc *f, const char *id, long long since, double timeout_s,
                      json_t **events, int *final, glint_err *err)
{
    fitsvc_job *j;
    struct timespec dl;
    json_t *out;
    size_t i;
    json_t *ev;

    *events = NULL;
    *final = 0;
    clock_gettime(CLOCK_REALTIME, &dl);
    {
        double s = (double)dl.tv_sec + 1e-9 * dl.tv_nsec + (timeout_s > 0 ? timeout_s : 0);
        dl.tv_sec = (time_t)s;
        dl.tv_nsec = (long)((s - (double)dl.tv_sec) * 1e9);
    }
    pthread_mutex_lock(&f->jlock);
    for (;;) {
        j = job_find(f, id);
        if (!j) {
            pthread_mutex_unlock(&f->jlock);
            return glint_err_set(err, GLINT_ENOTFOUND, "no job %s", id);
        }
        if (f->streams_stopped) {
            pthread_mutex_unlock(&f->jlock);
            return glint_err_set(err, GLINT_EUNSUPPORTED, "the daemon is stopping");
        }
        if (j->seq > since || j->state >= J_DONE)
            break;
        if (pthread_cond_timedwait(&f->jchange, &f->jlock, &dl) == ETIMEDOUT)
            break;
    }
    out = json_array();
    json_array_foreach(j->log, i, ev) {
        if (json_integer_value(json_object_get(ev, "seq")) > since)
            json_array_append(out, ev);
    }
    *final = j->state >= J_DONE;
    *events = out;
    pthread_mutex_unlock(&f->jlock);
    return 0;
}

/* ---- decoded paintings --------------------------------------------------------------------- */

static size_t img_bytes(const img *im)
{
    return (size_t)im->width * im->height * im->channels * sizeof(float);
}

/* Drop one reference (imlock held). */
static void painting_unref(fitsvc *f, painting *q)
{
    (void)f;
    if (--q->refs == 0) {
        img_free(&q->im);
        free(q);
    }
}

/* Insert p (one reference for the list, `pinned` more for the caller),
 * replacing the same view's older image; then keep the budget (imlock
 * held).  0, or -1 when a newer version is there already. */
static int painting_insert(fitsvc *f, painting *p)
{
    painting **pp;
    for (pp = &f->paintings; *pp;) {
        painting *q = *pp;
        if (q->view == p->view && strcmp(q->session, p->session) == 0) {
            if (q->version >= p->version)
                return -1;
            *pp = q->next;
            f->im_bytes -= img_bytes(&q->im);
            painting_unref(f, q);
            continue;
        }
        pp = &q->next;
    }
    p->next = f->paintings;
    f->paintings = p;
    f->im_bytes += img_bytes(&p->im);
    while (f->im_bytes > f->im_budget && f->paintings->next) {
        painting **last = &f->paintings;
        while ((*last)->next)
            last = &(*last)->next;
        f->im_bytes -= img_bytes(&(*last)->im);
        painting_unref(f, *last);
        *last = NULL;
    }
    return 0;
}

int fitsvc_painting_put(fitsvc *f, const char *session, int view, long long version, img *im,
                        fitsvc_painting **out)
{
    painting *p;

    *out = NULL;
    if (!im->px || img_bytes(im) > f->im_budget)
        return GLINT_ERANGE;
    p = calloc(1, sizeof(fitsvc_painting));
    if (!p)
        return GLINT_ENOMEM;
    snprintf(p->session, sizeof p->session, "%s", session);
    p->view = view;
    p->version = version;
    p->im = *im;
    p->refs = 2; /* the list's and the caller's */
    memset(im, 0, sizeof *im);
    pthread_mutex_lock(&f->imlock);
    if (painting_insert(f, p))
        p->refs = 1; /* a newer one is listed: the caller's alone */
    pthread_mutex_unlock(&f->imlock);
    *out = (fitsvc_painting *)p;
    return 0;
}

void fitsvc_painting_offer(fitsvc *f, const char *session, int view, long long version,
                           const img *im)
{
    img copy;
    fitsvc_painting *h;

    if (!f || !session || !im || !im->px || img_bytes(im) > f->im_budget ||
        img_alloc(&copy, im->width, im->height, im->channels, NULL))
        return;
    memcpy(copy.px, im->px, img_bytes(im));
    if (fitsvc_painting_put(f, session, view, version, &copy, &h) == 0)
        fitsvc_painting_release(f, h);
    img_free(&copy);
}

int fitsvc_painting_get(fitsvc *f, const char *session, int view, long long version,
                        fitsvc_painting **out)
{
    painting **pp;
    int rc = GLINT_ENOTFOUND;

    *out = NULL;
    pthread_mutex_lock(&f->imlock);
    for (pp = &f->paintings; *pp; pp = &(*pp)->next) {
        painting *q = *pp;
        if (q->view == view && q->version == version && strcmp(q->session, session) == 0) {
            q->refs++;
            *out = (fitsvc_painting *)q;
            rc = 0;
            *pp = q->next; /* to the front: most recently used */
            q->next = f->paintings;
            f->paintings = q;
            break;
        }
    }
    if (rc == 0)
        f->im_hits++;
    else
        f->im_misses++;
    pthread_mutex_unlock(&f->imlock);
    return rc;
}

const img *fitsvc_painting_img(const fitsvc_painting *p)
{
    return &p->p.im;
}

void fitsvc_painting_release(fitsvc *f, fitsvc_painting *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&f->imlock);
    painting_unref(f, &p->p);
    pthread_mutex_unlock(&f->imlock);
}

/* ---- material documents ---------------------------------------------------------------------- */

void fitsvc_doc_put(fitsvc *f, const char *id, const char *session, const char *scene_id,
                    const char *text, size_t len)
{
    doc *n, **pp;
    if (!f || !id || !text || len + sizeof *n > f->doc_budget)
        return;
    n = calloc(1, sizeof *n);
    if (!n || !(n->d.text = malloc(len + 1))) {
        free(n);
        return;
    }
    memcpy(n->d.text, text, len);
    n->d.text[len] = '\0';
    n->d.len = len;
    snprintf(n->id, sizeof n->id, "%s", id);
    snprintf(n->d.session, sizeof n->d.session, "%s", session ? session : "");
    snprintf(n->d.scene, sizeof n->d.scene, "%s", scene_id ? scene_id : "");
    pthread_mutex_lock(&f->imlock);
    for (pp = &f->docs; *pp; pp = &(*pp)->next)
        if (strcmp((*pp)->id, id) == 0) { /* there already (documents never change) */
            pthread_mutex_unlock(&f->imlock);
            free(n->d.text);
            free(n);
            return;
        }
    n->next = f->docs;
    f->docs = n;
    f->doc_bytes += len + sizeof *n;
    while (f->doc_bytes > f->doc_budget) {
        doc **last = &f->docs;
        while ((*last)->next)
            last = &(*last)->next;
        f->doc_bytes -= (*last)->d.len + sizeof **last;
        free((*last)->d.text);
        free(*last);
        *last = NULL;
    }
    pthread_mutex_unlock(&f->imlock);
}

int fitsvc_doc_get(fitsvc *f, const char *id, fitsvc_doc *out)
{
    doc **pp;
    int rc = GLINT_ENOTFOUND;

    memset(out, 0, sizeof *out);
    pthread_mutex_lock(&f->imlock);
    for (pp = &f->docs; *pp; pp = &(*pp)->next) {
        doc *q = *pp;
        if (strcmp(q->id, id) != 0)
            continue;
        *out = q->d;
        out->text = malloc(q->d.len + 1);
        if (!out->text) {
            rc = GLINT_ENOMEM;
            break;
        }
        memcpy(out->text, q->d.text, q->d.len + 1);
        rc = 0;
        *pp = q->next; /* to the front */
        q->next = f->docs;
        f->docs = q;
        break;
    }
    if (rc == 0)
        f->doc_hits++;
    else
        f->doc_misses++;
    pthread_mutex_unlock(&f->imlock);
    return rc;
}

/* ---- speed-accuracy points ------------------------------------------------------------------- */

#define POINT_RECENT 16
#define POINTS_FILE_MAX ((size_t)16 << 20)

static int hex32(const char *s)
{
    if (!s || strlen(s) != 32)
        return 0;
    for (int i = 0; i < 32; i++)
        if (!((s[i] >= '0' && s[i] <= '9') || (s[i] >= 'a' && s[i] <= 'f')))
            return 0;
    return 1;
}

/* The points object of a scene (plock held), loaded from disk the first
 * time; NULL only when out of memory. */
static json_t *points_of(fitsvc *f, const char *scene_hash)
{
    json_t *pts = json_object_get(f->points, scene_hash);
    char path[4096], *text = NULL;
    size_t len;

    if (pts)
        return pts;
    if (f->cache_dir &&
        snprintf(path, sizeof path, "%s/points/%s.json", f->cache_dir, scene_hash) <
            (int)sizeof path &&
        fsio_read_all(path, POINTS_FILE_MAX, &text, &len, NULL) == 0) {
        pts = json_loadb(text, len, 0, NULL);
        free(text);
        if (!json_is_object(pts)) { /* unreadable: start again (it is only a record) */
            json_decref(pts);
            pts = NULL;
        }
    }
    if (!pts)
        pts = json_object();
    if (!pts || json_object_set_new(f->points, scene_hash, pts))
        return NULL;
    return pts;
}

/* Write a scene's points (plock held). */
static int points_write(fitsvc *f, const char *scene_hash, json_t *pts, glint_err *err)
{
    char dir[4096], path[4200], *text;
    int rc;
    if (!f->cache_dir)
        return 0;
    snprintf(dir, sizeof dir, "%s/points", f->cache_dir);
    if ((rc = fsio_mkdirs(dir, err)))
        return rc;
    snprintf(path, sizeof path, "%s/%s.json", dir, scene_hash);
    text = json_dumps(pts, JSON_COMPACT | JSON_REAL_PRECISION(9));
    if (!text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory saving fit points");
    rc = fsio_write_atomic(path, text, strlen(text), err);
    free(text);
    return rc;
}

/* Points are a record, not data: they are written at most every
 * POINTS_SAVE_EVERY_S seconds (by an idle worker, and at close), so a fit
 * does not pay for a synchronous write; a crash loses at most the last
 * seconds of records.  (plock held) */
static int points_flush(fitsvc *f, int force, glint_err *err)
{
    const char *k;
    json_t *v;
    int rc = 0;
    double now = mono_now();

    if (!force && now - f->points_saved_at < POINTS_SAVE_EVERY_S)
        return 0;
    json_object_foreach(f->points_dirty, k, v) {
        json_t *pts = json_object_get(f->points, k);
        int r = pts ? points_write(f, k, pts, err) : 0;
        if (r && !rc)
            rc = r;
    }
    json_object_clear(f->points_dirty);
    f->points_saved_at = now;
    return rc;
}

static int points_save(fitsvc *f, const char *scene_hash, json_t *pts, glint_err *err)
{
    (void)pts;
    json_object_set_new(f->points_dirty, scene_hash, json_true());
    return points_flush(f, 0, err);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int fitsvc_points_record(fitsvc *f, const char *scene_hash, const char *point_key,
                         const json_t *params, const json_t *views, int nsamples,
                         double fit_seconds, double cold, int from_disk, double rms_painted,
                         const char *material_id, glint_err *err)
{
    json_t *pts, *pt, *recent;
    double v[POINT_RECENT];
    size_t n, i;
    char t[32];
    int rc;

    if (!hex32(scene_hash))
        return glint_err_set(err, GLINT_EINVAL, "bad scene hash");
    pthread_mutex_lock(&f->plock);
    pts = points_of(f, scene_hash);
    if (!pts) {
        pthread_mutex_unlock(&f->plock);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    pt = json_object_get(pts, point_key);
    if (!pt) {
        pt = json_pack("{s:O, s:O, s:i, s:n, s:n, s:n, s:n, s:[]}", "params",
                       (json_t *)params, "views", (json_t *)views, "fits", 0, "cold_seconds",
                       "disk_seconds", "held_out_rms", "held_out", "_recent");
        if (!pt || json_object_set_new(pts, point_key, pt)) {
            pthread_mutex_unlock(&f->plock);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        }
    }
    json_object_set_new(pt, "samples", json_integer(nsamples));
    json_object_set_new(pt, "fits",
                        json_integer(json_integer_value(json_object_get(pt, "fits")) + 1));
    recent = json_object_get(pt, "_recent");
    if (!json_is_array(recent)) {
        recent = json_array();
        json_object_set_new(pt, "_recent", recent);
    }
    json_array_append_new(recent, json_real(fit_seconds));
    while (json_array_size(recent) > POINT_RECENT)
        json_array_remove(recent, 0);
    n = json_array_size(recent);
    for (i = 0; i < n; i++)
        v[i] = json_number_value(json_array_get(recent, i));
    qsort(v, n, sizeof v[0], cmp_double);
    json_object_set_new(pt, "fit_seconds", json_real(n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2])));
    if (cold >= 0.0)
        json_object_set_new(pt, from_disk ? "disk_seconds" : "cold_seconds", json_real(cold));
    json_object_set_new(pt, "rms_painted", json_real(rms_painted));
    if (material_id)
        json_object_set_new(pt, "material_id", json_string(material_id));
    iso_time(time(NULL), t);
    json_object_set_new(pt, "updated", json_string(t));
    rc = points_save(f, scene_hash, pts, err);
    pthread_mutex_unlock(&f->plock);
    return rc;
}

int fitsvc_points_has_holdout(fitsvc *f, const char *scene_hash, const char *point_key)
{
    json_t *pts, *pt;
    int has = 0;
    if (!hex32(scene_hash))
        return 0;
    pthread_mutex_lock(&f->plock);
    pts = points_of(f, scene_hash);
    pt = pts ? json_object_get(pts, point_key) : NULL;
    has = pt && json_is_object(json_object_get(pt, "held_out"));
    pthread_mutex_unlock(&f->plock);
    return has;
}

int fitsvc_points_set_holdout(fitsvc *f, const char *scene_hash, const char *point_key,
                              json_t *held_out, glint_err *err)
{
    json_t *pts, *pt;
    int rc;
    if (!hex32(scene_hash) || !json_is_object(held_out)) {
        json_decref(held_out);
        return glint_err_set(err, GLINT_EINVAL, "bad held-out record");
    }
    pthread_mutex_lock(&f->plock);
    pts = points_of(f, scene_hash);
    pt = pts ? json_object_get(pts, point_key) : NULL;
    if (!pt) {
        pthread_mutex_unlock(&f->plock);
        json_decref(held_out);
        return glint_err_set(err, GLINT_ENOTFOUND, "no such fit point");
    }
    json_object_set_new(pt, "held_out_rms", json_is_number(json_object_get(held_out, "rms"))
                                                ? json_incref(json_object_get(held_out, "rms"))
                                                : json_null());
    json_object_set_new(pt, "held_out", held_out);
    rc = points_save(f, scene_hash, pts, err);
    pthread_mutex_unlock(&f->plock);
    return rc;
}

json_t *fitsvc_points_get(fitsvc *f, const char *scene_hash)
{
    json_t *out = json_array(), *pts, *pt;
    const char *k;
    if (!hex32(scene_hash))
        return out;
    pthread_mutex_lock(&f->plock);
    pts = points_of(f, scene_hash);
    if (pts) {
        json_object_foreach(pts, k, pt) {
            json_t *c = json_deep_copy(pt);
            json_object_del(c, "_recent");
            json_array_append_new(out, c);
        }
    }
    pthread_mutex_unlock(&f->plock);
    return out;
}

/* ---- life cycle ------------------------------------------------------------------------------ */

int fitsvc_open(const char *cache_dir, size_t budget_bytes, int threads, fitsvc **out,
                glint_err *err)
{
    fitsvc *f;

    *out = NULL;
    if (threads < 1 || threads > 64)
        return glint_err_set(err, GLINT_ERANGE, "worker threads %d outside 1..64", threads);
    /* A fit allocates a few arrays of 0.1 to 30 MiB (samples, log values,
     * diagnostics) and frees them at once.  With glibc's defaults these go
     * to fresh mmaps or trimmed heap tops, and every fit pays the page
     * faults again (measured: 38 -> 22 ms for a warm fit of 393,512
     * samples).  Keep them in the heap.  Process-wide, so it belongs to
     * startup: glintd opens fitsvc once, before serving. */
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 64 << 20);
    f = calloc(1, sizeof *f);
    if (!f)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (cache_dir && !(f->cache_dir = strdup(cache_dir))) {
        free(f);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    f->budget = budget_bytes;
    pthread_mutex_init(&f->lock, NULL);
    pthread_cond_init(&f->built, NULL);
    pthread_mutex_init(&f->jlock, NULL);
    pthread_cond_init(&f->jwork, NULL);
    pthread_cond_init(&f->jchange, NULL);
    pthread_mutex_init(&f->plock, NULL);
    pthread_mutex_init(&f->imlock, NULL);
    f->im_budget = budget_bytes / 8;
    f->doc_budget = budget_bytes / 32;
    f->points = json_object();
    f->points_dirty = json_object();
    f->workers = calloc((size_t)threads, sizeof *f->workers);
    if (!f->workers || !f->points || !f->points_dirty) {
        fitsvc_close(f);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    for (int i = 0; i < threads; i++) {
        int rc = pthread_create(&f->workers[i], NULL, worker_main, f);
        if (rc) {
            fitsvc_close(f);
            return glint_err_set(err, GLINT_EINTERNAL, "cannot start a worker thread: %s",
                                 strerror(rc));
        }
        f->nworkers++;
    }
    *out = f;
    return 0;
}

void fitsvc_shutdown(fitsvc *f)
{
    if (!f)
        return;
    pthread_mutex_lock(&f->jlock);
    f->streams_stopped = 1;
    pthread_cond_broadcast(&f->jchange);
    pthread_mutex_unlock(&f->jlock);
}

void fitsvc_close(fitsvc *f)
{
    if (!f)
        return;
    pthread_mutex_lock(&f->jlock);
    f->stopping = 1;
    /* queued jobs never run */
    for (fitsvc_job *j = f->qhead; j; j = j->qnext) {
        j->state = J_FAILED;
        j->finished = time(NULL);
        j->t_start = j->t_end = mono_now();
        snprintf(j->error, sizeof j->error, "the daemon stopped before the job ran");
        f->jobs_failed++;
        job_log(f, j, "failed");
    }
    f->qhead = f->qtail = NULL;
    f->queued = 0;
    pthread_cond_broadcast(&f->jwork);
    pthread_cond_broadcast(&f->jchange);
    pthread_mutex_unlock(&f->jlock);
    for (int i = 0; i < f->nworkers; i++)
        pthread_join(f->workers[i], NULL); /* running jobs finish */
    free(f->workers);
    for (fitsvc_job *j = f->jall_head, *next; j; j = next) {
        next = j->anext;
        job_free(j);
    }
    /* every entry: children before parents is not needed, the table owns one
     * view of each; free payloads directly */
    pthread_mutex_lock(&f->lock);
    for (int b = 0; b < NBUCKETS; b++) {
        for (entry *e = f->table[b], *next; e; e = next) {
            next = e->hnext;
            payload_free(e);
            free(e);
        }
        f->table[b] = NULL;
    }
    pthread_mutex_unlock(&f->lock);
    pthread_cond_destroy(&f->built);
    pthread_mutex_destroy(&f->lock);
    pthread_cond_destroy(&f->jwork);
    pthread_cond_destroy(&f->jchange);
    pthread_mutex_destroy(&f->jlock);
    if (f->points_dirty) {
        glint_err e;
        if (points_flush(f, 1, &e))
            fprintf(stderr, "glintd: saving fit points: %s\n", e.msg);
    }
    pthread_mutex_destroy(&f->plock);
    json_decref(f->points);
    json_decref(f->points_dirty);
    while (f->paintings) { /* (every pin was released before close) */
        painting *q = f->paintings;
        f->paintings = q->next;
        img_free(&q->im);
        free(q);
    }
    while (f->docs) {
        doc *q = f->docs;
        f->docs = q->next;
        free(q->d.text);
        free(q);
    }
    pthread_mutex_destroy(&f->imlock);
    free(f->cache_dir);
    free(f);
}

/* ---- statistics ---------------------------------------------------------------------------------- */

void fitsvc_stats_get(fitsvc *f, fitsvc_stats *out)
{
    memset(out, 0, sizeof *out);
    if (!f)
        return;
    pthread_mutex_lock(&f->lock);
    *out = f->st;
    pthread_mutex_unlock(&f->lock);
    out->budget = f->budget;
    out->builds = 0;
    for (int l = 0; l < FITSVC_NLEVELS; l++)
        out->builds += out->lvl_builds[l];
    pthread_mutex_lock(&f->imlock);
    out->painting_hits = f->im_hits;
    out->painting_misses = f->im_misses;
    out->painting_bytes = f->im_bytes;
    out->doc_hits = f->doc_hits;
    out->doc_misses = f->doc_misses;
    out->doc_bytes = f->doc_bytes;
    pthread_mutex_unlock(&f->imlock);
    pthread_mutex_lock(&f->jlock);
    out->jobs_queued = f->queued;
    out->jobs_running = f->running;
    out->jobs_done = f->jobs_done;
    out->jobs_failed = f->jobs_failed;
    pthread_mutex_unlock(&f->jlock);
}

void fitsvc_metrics(fitsvc *f, FILE *o)
{
    fitsvc_stats s;
    fitsvc_stats_get(f, &s);
    fprintf(o, "# HELP glintd_fit_requests_total Fit requests by whether the whole "
               "precomputation was in memory.\n# TYPE glintd_fit_requests_total counter\n");
    fprintf(o, "glintd_fit_requests_total{cache=\"hit\"} %llu\n", s.hits);
    fprintf(o, "glintd_fit_requests_total{cache=\"miss\"} %llu\n", s.misses);
    fprintf(o, "# HELP glintd_fitcache_lookups_total Precomputation cache lookups by level and "
               "outcome (hit: in memory; joined: waited for another request's build; built).\n"
               "# TYPE glintd_fitcache_lookups_total counter\n");
    for (int l = 0; l < FITSVC_NLEVELS; l++) {
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"hit\"} %llu\n",
                fitsvc_level_names[l], s.lvl_hits[l]);
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"joined\"} %llu\n",
                fitsvc_level_names[l], s.lvl_joins[l]);
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"built\"} %llu\n",
                fitsvc_level_names[l], s.lvl_builds[l]);
    }
    fprintf(o, "# HELP glintd_fitcache_build_failures_total Builds that failed, by level.\n"
               "# TYPE glintd_fitcache_build_failures_total counter\n");
    for (int l = 0; l < FITSVC_NLEVELS; l++)
        fprintf(o, "glintd_fitcache_build_failures_total{level=\"%s\"} %llu\n",
                fitsvc_level_names[l], s.lvl_failures[l]);
    fprintf(o, "# HELP glintd_fitcache_build_seconds_total Time spent building, by level.\n"
               "# TYPE glintd_fitcache_build_seconds_total counter\n");
    for (int l = 0; l < FITSVC_NLEVELS; l++)
        fprintf(o, "glintd_fitcache_build_seconds_total{level=\"%s\"} %.6f\n",
                fitsvc_level_names[l], s.build_seconds[l]);
    fprintf(o, "# HELP glintd_fitcache_evictions_total Entries evicted (least recently used) to "
               "keep the byte budget.\n# TYPE glintd_fitcache_evictions_total counter\n");
    for (int l = 0; l < FITSVC_NLEVELS; l++)
        fprintf(o, "glintd_fitcache_evictions_total{level=\"%s\"} %llu\n",
                fitsvc_level_names[l], s.lvl_evictions[l]);
    fprintf(o, "# HELP glintd_fitcache_bytes Bytes held in memory, by level.\n"
               "# TYPE glintd_fitcache_bytes gauge\n");
    for (int l = 0; l < FITSVC_NLEVELS; l++)
        fprintf(o, "glintd_fitcache_bytes{level=\"%s\"} %zu\n", fitsvc_level_names[l],
                s.lvl_bytes[l]);
    fprintf(o, "# HELP glintd_fitcache_entries Entries in memory, by level.\n"
               "# TYPE glintd_fitcache_entries gauge\n");
    for (int l = 0; l < FITSVC_NLEVELS; l++)
        fprintf(o, "glintd_fitcache_entries{level=\"%s\"} %zu\n", fitsvc_level_names[l],
                s.lvl_entries[l]);
    fprintf(o, "# HELP glintd_fitcache_budget_bytes The in-memory budget.\n"
               "# TYPE glintd_fitcache_budget_bytes gauge\nglintd_fitcache_budget_bytes %zu\n",
            s.budget);
    fprintf(o, "# HELP glintd_fitcache_disk_total Decompositions by what the disk cache "
               "answered.\n# TYPE glintd_fitcache_disk_total counter\n");
    fprintf(o, "glintd_fitcache_disk_total{outcome=\"loaded\"} %llu\n", s.disk_loads);
    fprintf(o, "glintd_fitcache_disk_total{outcome=\"built\"} %llu\n", s.disk_builds);
    fprintf(o, "glintd_fitcache_disk_total{outcome=\"rebuilt\"} %llu\n", s.disk_rebuilds);
    fprintf(o, "# HELP glintd_painting_cache_total Decoded paintings found in memory or not.\n"
               "# TYPE glintd_painting_cache_total counter\n");
    fprintf(o, "glintd_painting_cache_total{outcome=\"hit\"} %llu\n", s.painting_hits);
    fprintf(o, "glintd_painting_cache_total{outcome=\"miss\"} %llu\n", s.painting_misses);
    fprintf(o, "# HELP glintd_painting_cache_bytes Bytes of decoded paintings held.\n"
               "# TYPE glintd_painting_cache_bytes gauge\nglintd_painting_cache_bytes %zu\n",
            s.painting_bytes);
    fprintf(o, "# HELP glintd_material_doc_cache_total Material documents served from memory "
               "or read from the store.\n# TYPE glintd_material_doc_cache_total counter\n");
    fprintf(o, "glintd_material_doc_cache_total{outcome=\"hit\"} %llu\n", s.doc_hits);
    fprintf(o, "glintd_material_doc_cache_total{outcome=\"miss\"} %llu\n", s.doc_misses);
    fprintf(o, "# HELP glintd_jobs Fit jobs now, by state.\n# TYPE glintd_jobs gauge\n");
    fprintf(o, "glintd_jobs{state=\"queued\"} %d\n", s.jobs_queued);
    fprintf(o, "glintd_jobs{state=\"running\"} %d\n", s.jobs_running);
    fprintf(o, "# HELP glintd_jobs_finished_total Fit jobs finished, by outcome.\n"
               "# TYPE glintd_jobs_finished_total counter\n");
    fprintf(o, "glintd_jobs_finished_total{state=\"done\"} %llu\n", s.jobs_done);
    fprintf(o, "glintd_jobs_finished_total{state=\"failed\"} %llu\n", s.jobs_failed);
}
