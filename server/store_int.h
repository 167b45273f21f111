/* store_int.h: internals of the store, shared by store.c, store_blob.c,
 * store_log.c and store_sweep.c only. */
#ifndef GLINTD_STORE_INT_H
#define GLINTD_STORE_INT_H

#include <jansson.h>
#include <pthread.h>

#include "db.h"
#include "store.h"

#define STORE_PATH_MAX 4096
#define STORE_BLOB_MAX ((size_t)1 << 31)

/* The PostgreSQL notification channel of the sessions' logs; the payload
 * is the session id. */
#define STORE_CHANNEL "glint_log"

typedef struct store_listener store_listener;

struct store {
    db *db;
    char *conninfo;                  /* PostgreSQL (for the listener's connection) */
    store_listener *listener;        /* store_listen's thread, or NULL */
    char instance[33];               /* random, per open: whose announcement */
    int sweep_grace;                 /* seconds; 0: the store is alone */
    pthread_mutex_t lock;            /* one statement sequence at a time */
    char dir[STORE_PATH_MAX];
    char blobs[STORE_PATH_MAX];
    /* store_remove_later's queue and thread (store_blob.c), under reap_lock */
    pthread_mutex_t reap_lock;
    pthread_cond_t reap_cond;        /* work queued, or stop */
    pthread_cond_t reap_idle;        /* the queue emptied and nothing in hand */
    char **reap_q;
    int reap_n, reap_cap;
    int reap_busy, reap_stop, reap_on;
    pthread_t reaper;
};

/* Compact JSON text with every double exact (caller frees). */
char *store_dump(const json_t *j);
/* Parse stored JSON text (GLINT_EFORMAT naming `what` when malformed). */
json_t *store_load(const char *text, const char *what, glint_err *err);
/* Run SQL without results / prepare a statement (NULL with *err set). */
int store_exec(store *s, const char *sql, glint_err *err);
db_stmt *store_prep(store *s, const char *sql, glint_err *err);
/* Step a statement that returns no rows: 0 or a negative code. */
int store_run(db_stmt *st, const char *what, glint_err *err);
/* The statement for this store's engine, where the two differ. */
const char *store_pick(const store *s, const char *sqlite_sql, const char *postgres_sql);
/* Is this file old enough for the sweep to remove (sweep_grace)? */
int store_sweepable(const store *s, const char *path);
/* Roll back the open transaction, if any. */
void store_rollback(store *s);

/* A name with a random part: "<prefix><16 hex><suffix>" (OUT: buf). */
int store_random_name(char *buf, size_t len, const char *prefix, const char *suffix,
                      glint_err *err);

/* The painting row of (session, view): its version and blob name (OUT;
 * the lock held).  0, GLINT_ENOTFOUND (no session, never painted) or
 * another code. */
#define STORE_BLOB_NAME_MAX 512
int store_painting_row(store *s, const char *session, int view, int64_t *version, char *blob,
                       size_t len, glint_err *err);

/* A painting's decoded pixels: "<blob>" STORE_PIXELS_SUFFIX (store_pixels.c). */
#define STORE_PIXELS_SUFFIX ".px"
/* Remove the pixels of a blob, if any (best effort). */
void store_pixels_delete(store *s, const char *blob);

/* A replaced painting's blob and its pixels removed on the store's
 * removal thread, off the request's path: a removal waits on the file
 * system's journal, which other processes' writes may hold for
 * milliseconds.  Nothing names the blob any more; a crash before its
 * removal leaves it to store_sweep.  Done at once when the thread cannot
 * be had.  store_reap_init / store_reap_stop (store_close) set up and end
 * the thread, doing what is queued first. */
void store_remove_later(store *s, const char *blob);
void store_reap_init(store *s);
void store_reap_stop(store *s);

/* Remove painting files no row names and temporary files of interrupted
 * writes (at open, before anyone writes). */
void store_sweep(store *s);
/* The other kinds of blobs nothing names after a crash (store_sweep.c). */
void store_sweep_blobs(store *s);

#endif
