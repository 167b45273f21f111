/* store_log.c: the sessions' logs (store.h): paintings, strokes and
 * events, every change numbered with the session's next sequence number
 * and committed in one transaction with what it changed (store_log_commit),
 * and the sweep of files a crash can leave behind. */
#include <dirent.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "clock.h"
#include "ids.h"
#include "store_int.h"

/* Inside a transaction: the session's last_seq (GLINT_ENOTFOUND if none).
 * for_update: PostgreSQL locks the session's row until the commit, so two
 * processes appending to one session take turns (SQLite's write
 * transaction already holds the whole database). */
static int store_tx_last_seq(store *s, const char *session, int for_update, int64_t *last,
                             glint_err *err)
{
    db_stmt *st = store_prep(s, for_update ? store_pick(s, "SELECT last_seq FROM sessions "
                                                           "WHERE id = ?1",
                                                        "SELECT last_seq FROM sessions "
                                                        "WHERE id = ?1 FOR UPDATE")
                                           : "SELECT last_seq FROM sessions WHERE id = ?1",
                             err);
    int rc;
    if (!st)
        return GLINT_EIO;
    db_bind_text(st, 1, session);
    rc = db_step(st, "reading", err);
    if (rc == DB_ROW) {
        *last = db_col_int(st, 0);
        rc = 0;
    } else if (rc == DB_DONE) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no session with id %s", session);
    }
    db_finalize(st);
    return rc;
}

static int store_tx_set_last_seq(store *s, const char *session, int64_t last, glint_err *err)
{
    db_stmt *st = store_prep(s, "UPDATE sessions SET last_seq = ?2 WHERE id = ?1", err);
    int rc;
    if (!st)
        return GLINT_EIO;
    db_bind_text(st, 1, session);
    db_bind_int(st, 2, last);
    rc = store_run(st, "numbering", err);
    db_finalize(st);
    return rc;
}

/* Inside a transaction: tell other processes on the same database that
 * the session's log grew, when the transaction commits (PostgreSQL's
 * NOTIFY is transactional; store_listen receives it).  SQLite: nothing
 * (one process). */
static int store_tx_notify(store *s, const char *session, glint_err *err)
{
    db_stmt *st;
    int rc;
    if (db_kind_of(s->db) != DB_POSTGRES)
        return 0;
    if (!(st = store_prep(s, "SELECT pg_notify('" STORE_CHANNEL "', ?1)", err)))
        return GLINT_EIO;
    db_bind_text(st, 1, session);
    rc = db_step(st, "notifying", err);
    db_finalize(st);
    return rc < 0 ? rc : 0;
}

/* Inside a transaction: insert one event row (data: JSON text). */
static int store_tx_event(store *s, db_stmt *st, const char *session, int64_t seq,
                          const char *type, int view, const char *data, const char *now,
                          glint_err *err)
{
    db_reset(st);
    db_bind_text(st, 1, session);
    db_bind_int(st, 2, seq);
    db_bind_text(st, 3, type);
    if (view >= 0)
        db_bind_int(st, 4, view);
    else
        db_bind_null(st, 4);
    db_bind_text(st, 5, data);
    db_bind_text(st, 6, now);
    return store_run(st, "appending an event", err);
}

static const char store_sql_event[] =
    "INSERT INTO events (session, seq, type, view, data, created) VALUES (?1, ?2, ?3, ?4, ?5, ?6)";

/* Inside a transaction: replace the painting row; OUT: *version, the old
 * blob name in old[] ("" if none).  base >= 0: the version the new image
 * was made from, GLINT_ECONFLICT if the view is at another one now. */
static int store_tx_painting(store *s, const char *session, int view, int64_t base,
                             const char *blob, const char *now, int64_t *version, char *old,
                             size_t oldlen, glint_err *err)
{
    db_stmt *st = store_prep(s, "SELECT version, blob FROM paintings WHERE session = ?1 "
                                     "AND view = ?2", err);
    int64_t v = 0;
    int rc;

    old[0] = '\0';
    if (!st)
        return GLINT_EIO;
    db_bind_text(st, 1, session);
    db_bind_int(st, 2, view);
    rc = db_step(st, "reading", err);
    if (rc == DB_ROW) {
        v = db_col_int(st, 0);
        snprintf(old, oldlen, "%s", db_col_text(st, 1));
    } else if (rc != DB_DONE) {
        db_finalize(st);
        return rc;
    }
    db_finalize(st);
    if (base >= 0 && v != base) {
        old[0] = '\0';
        return glint_err_set(err, GLINT_ECONFLICT,
                             "view %d is at painting version %lld, not %lld: another writer "
                             "changed it meanwhile", view, (long long)v, (long long)base);
    }
    st = store_prep(s, "INSERT INTO paintings (session, view, version, blob, updated) "
                       "VALUES (?1, ?2, ?3, ?4, ?5) ON CONFLICT (session, view) DO UPDATE SET "
                       "version = excluded.version, blob = excluded.blob, "
                       "updated = excluded.updated", err);
    if (!st)
        return GLINT_EIO;
    db_bind_text(st, 1, session);
    db_bind_int(st, 2, view);
    db_bind_int(st, 3, v + 1);
    db_bind_text(st, 4, blob);
    db_bind_text(st, 5, now);
    rc = store_run(st, "writing a painting", err);
    db_finalize(st);
    *version = v + 1;
    return rc;
}

/* Write a new painting blob for (session, view) (OUT: name). */
/* The file extension of image bytes, by their magic (store.h). */
static const char *image_suffix(const void *data, size_t len)
{
    const unsigned char *b = data;
    if (len >= 8 && memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0)
        return ".png";
    if (len >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff)
        return ".jpg";
    return ".exr";
}

static int store_painting_blob(store *s, const char *session, int view, const void *exr,
                               size_t len, char *name, size_t namelen, glint_err *err)
{
    char prefix[96];
    if (!glint_id_valid(session))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"", session);
    if (view < 0)
        return glint_err_set(err, GLINT_EINVAL, "view %d is negative", view);
    snprintf(prefix, sizeof prefix, "sessions/%s/view%d-", session, view);
    int rc = store_random_name(name, namelen, prefix, image_suffix(exr, len), err);
    return rc ? rc : store_blob_put(s, name, exr, len, err);
}

static int store_log_commit_blob(store *s, const char *session, int view, int64_t base,
                                 const char *blob, const char *type, char *const *texts,
                                 size_t n, int64_t *first_seq, int64_t *version,
                                 glint_err *err);

/* The one commit of a view's new image: write its blob, then in one
 * transaction replace the painting row and append `n` events of `type`
 * (texts[i]; for type "painting", texts is NULL and the event is
 * {"view", "version"}) numbered after the session's last sequence number;
 * then remove the replaced blob (store_remove_later, on the store's removal
 * thread), or on failure the new one.  A crash between the steps leaves a
 * file no row names: store_sweep removes it.
 * base >= 0: commit only if the view is still at that painting version
 * (GLINT_ECONFLICT otherwise).  OUT: *first_seq, *version (may be NULL). */
static int store_log_commit(store *s, const char *session, int view, int64_t base,
                            const void *exr,
                            size_t len, const char *type, char *const *texts, size_t n,
                            int64_t *first_seq, int64_t *version, glint_err *err)
{
    char blob[160];
    int rc = store_painting_blob(s, session, view, exr, len, blob, sizeof blob, err);
    return rc ? rc
              : store_log_commit_blob(s, session, view, base, blob, type, texts, n, first_seq,
                                      version, err);
}

/* store_log_commit's transaction and what follows it, the blob written. */
static int store_log_commit_blob(store *s, const char *session, int view, int64_t base,
                                 const char *blob, const char *type, char *const *texts,
                                 size_t n, int64_t *first_seq, int64_t *version,
                                 glint_err *err)
{
    char old[160], now[GLINT_TIME_LEN], data[64];
    db_stmt *st = NULL;
    int64_t last = 0, v = 0;
    int rc;

    old[0] = '\0';
    glint_time_iso_ms(now);
    pthread_mutex_lock(&s->lock);
    if ((rc = db_begin(s->db, err)) ||
        (rc = store_tx_last_seq(s, session, 1, &last, err)) ||
        (rc = store_tx_painting(s, session, view, base, blob, now, &v, old, sizeof old,
                                   err)))
        goto out;
    if (!(st = store_prep(s, store_sql_event, err))) {
        rc = GLINT_EIO;
        goto out;
    }
    if (!texts)
        snprintf(data, sizeof data, "{\"view\":%d,\"version\":%lld}", view, (long long)v);
    for (size_t i = 0; i < n; i++)
        if ((rc = store_tx_event(s, st, session, last + 1 + (int64_t)i, type, view,
                                 texts ? texts[i] : data, now, err)))
            goto out;
    if ((rc = store_tx_set_last_seq(s, session, last + (int64_t)n, err)) ||
        (rc = store_tx_notify(s, session, err)) || (rc = db_commit(s->db, err)))
        goto out;
out:
    db_finalize(st);
    if (rc)
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    if (rc) {
        store_blob_delete(s, blob, NULL);
        return rc;
    }
    if (old[0]) /* nothing names it now: removed off this request's path */
        store_remove_later(s, old);
    if (first_seq)
        *first_seq = last + 1;
    if (version)
        *version = v;
    return 0;
}

int store_painting_put(store *s, const char *session, int view, const void *exr, size_t len,
                       int64_t *version, int64_t *seq, glint_err *err)
{
    return store_painting_put_at(s, session, view, -1, exr, len, version, seq, err);
}

int store_painting_put_at(store *s, const char *session, int view, int64_t base,
                          const void *exr, size_t len, int64_t *version, int64_t *seq,
                          glint_err *err)
{
    return store_log_commit(s, session, view, base, exr, len, "painting", NULL, 1, seq, version,
                            err);
}

int store_painting_blob_put(store *s, const char *session, int view, const void *data,
                            size_t len, char *name, size_t namelen, glint_err *err)
{
    return store_painting_blob(s, session, view, data, len, name, namelen, err);
}

int store_painting_commit_at(store *s, const char *session, int view, int64_t base,
                             const char *blob, int64_t *version, int64_t *seq, glint_err *err)
{
    char prefix[96];
    size_t np;
    /* only a blob of this session's view (store_painting_blob_put's names) */
    snprintf(prefix, sizeof prefix, "sessions/%s/view%d-", session, view);
    np = strlen(prefix);
    if (!blob || strncmp(blob, prefix, np) != 0 || strchr(blob + np, '/'))
        return glint_err_set(err, GLINT_EINVAL, "not a blob of view %d of session %.40s", view,
                             session);
    return store_log_commit_blob(s, session, view, base, blob, "painting", NULL, 1, seq, version,
                                 err);
}

int store_painting_row(store *s, const char *session, int view, int64_t *version, char *blob,
                       size_t len, glint_err *err)
{
    db_stmt *st;
    int rc;

    if (!glint_id_valid(session))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"", session);
    st = store_prep(s, "SELECT version, blob FROM paintings WHERE session = ?1 AND view = ?2",
                    err);
    if (!st)
        return GLINT_EIO;
    db_bind_text(st, 1, session);
    db_bind_int(st, 2, view);
    rc = db_step(st, "reading", err);
    if (rc == DB_ROW) {
        *version = db_col_int(st, 0);
        rc = snprintf(blob, len, "%s", db_col_text(st, 1)) >= (int)len
                 ? glint_err_set(err, GLINT_EFORMAT, "a painting's blob name is too long")
                 : 0;
    } else if (rc == DB_DONE) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "view %d of session %s has no painting", view,
                           session);
    }
    db_finalize(st);
    return rc;
}

int store_painting_get(store *s, const char *session, int view, void **exr, size_t *len,
                       int64_t *version, glint_err *err)
{
    char blob[STORE_BLOB_NAME_MAX], again[STORE_BLOB_NAME_MAX];
    int64_t v = 0;
    int rc;

    *exr = NULL;
    /* under the lock, so a concurrent put of this process cannot remove the
     * file between reading its name and reading it */
    pthread_mutex_lock(&s->lock);
    rc = store_painting_row(s, session, view, &v, blob, sizeof blob, err);
    /* Another replica on the same database can: it replaces the row and
     * removes the blob it replaced, which this one may just have read the
     * name of.  Then the row names a newer blob: read that one.  A row
     * still naming a file that is not there is never acceptable. */
    for (int tries = 0; rc == 0; tries++) {
        rc = store_blob_get(s, blob, exr, len, err);
        if (rc != GLINT_ENOTFOUND)
            break;
        rc = store_painting_row(s, session, view, &v, again, sizeof again, err);
        if (rc == 0 && (strcmp(again, blob) == 0 || tries >= 16)) {
            rc = glint_err_set(err, GLINT_EIO, "painting of session %s view %d: file missing",
                               session, view);
            break;
        }
        memcpy(blob, again, sizeof blob);
    }
    if (rc == 0 && version)
        *version = v;
    pthread_mutex_unlock(&s->lock);
    return rc;
}

int store_paintings_list(store *s, const char *session, json_t **array, glint_err *err)
{
    db_stmt *st;
    json_t *arr = json_array();
    int rc = 0, step;

    *array = NULL;
    if (!arr)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory listing paintings");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, "SELECT view, version, updated FROM paintings WHERE session = ?1 "
                       "ORDER BY view", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, session ? session : "");
    while ((step = db_step(st, "reading", err)) == DB_ROW)
        json_array_append_new(arr, json_pack("{s:i, s:I, s:s}", "view", db_col_int(st, 0),
                                             "version", (json_int_t)db_col_int(st, 1),
                                             "updated",
                                             db_col_text(st, 2)));
    if (step < 0)
        rc = step;
out:
    db_finalize(st);
    pthread_mutex_unlock(&s->lock);
    if (rc)
        json_decref(arr);
    else
        *array = arr;
    return rc;
}

/* ------------------------------------------------------------------------ */
/* Strokes and events                                                        */
/* ------------------------------------------------------------------------ */

int store_strokes_append(store *s, const char *session, int view, const json_t *strokes,
                         const void *exr, size_t len, int64_t *first_seq, int64_t *last_seq,
                         int64_t *version, glint_err *err)
{
    return store_strokes_append_at(s, session, view, -1, strokes, exr, len, first_seq, last_seq,
                                   version, err);
}

int store_strokes_append_at(store *s, const char *session, int view, int64_t base,
                            const json_t *strokes, const void *exr, size_t len,
                            int64_t *first_seq, int64_t *last_seq, int64_t *version,
                            glint_err *err)
{
    size_t n = json_array_size(strokes), i;
    int64_t first = 0;
    char **texts;
    int rc = 0;

    if (!json_is_array(strokes) || n == 0)
        return glint_err_set(err, GLINT_EINVAL, "store_strokes_append: no strokes");
    texts = calloc(n, sizeof *texts);
    if (!texts)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu strokes", n);
    for (i = 0; i < n && !rc; i++)
        if (!(texts[i] = store_dump(json_array_get(strokes, i))))
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory serializing strokes");
    if (!rc)
        rc = store_log_commit(s, session, view, base, exr, len, "stroke", texts, n, &first,
                              version,
                              err);
    if (!rc) {
        if (first_seq)
            *first_seq = first;
        if (last_seq)
            *last_seq = first + (int64_t)n - 1;
    }
    for (i = 0; i < n; i++)
        free(texts[i]);
    free(texts);
    return rc;
}

/* The checks and text of an event store_event_append or
 * store_material_put_event appends.  OUT: *text (the caller frees it). */
static int event_text(const char *session, const char *type, const json_t *data, char **text,
                      glint_err *err)
{
    *text = NULL;
    if (!glint_id_valid(session))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"",
                             session ? session : "");
    if (!type || !*type || strlen(type) > 32 || !strcmp(type, "stroke") ||
        !strcmp(type, "painting"))
        return glint_err_set(err, GLINT_EINVAL, "event type \"%.40s\" cannot be appended here",
                             type ? type : "");
    if (!(*text = json_is_object(data) ? store_dump(data) : NULL))
        return glint_err_set(err, GLINT_EINVAL, "event data must be a JSON object");
    return 0;
}

/* Inside a transaction: the session's next event (text from event_text),
 * numbered, and the word to other processes.  OUT: *seq. */
static int store_tx_append(store *s, const char *session, const char *type, int view,
                           const char *text, const char *now, int64_t *seq, glint_err *err)
{
    int64_t last = 0;
    db_stmt *st = NULL;
    int rc;

    if ((rc = store_tx_last_seq(s, session, 1, &last, err)))
        return rc;
    if (!(st = store_prep(s, store_sql_event, err)))
        return GLINT_EIO;
    if (!(rc = store_tx_event(s, st, session, last + 1, type, view, text, now, err)) &&
        !(rc = store_tx_set_last_seq(s, session, last + 1, err)))
        rc = store_tx_notify(s, session, err);
    db_finalize(st);
    if (!rc)
        *seq = last + 1;
    return rc;
}

int store_event_append(store *s, const char *session, const char *type, int view,
                       const json_t *data, int64_t *seq, glint_err *err)
{
    char now[GLINT_TIME_LEN], *text;
    int64_t at = 0;
    int rc;

    if ((rc = event_text(session, type, data, &text, err)))
        return rc;
    glint_time_iso_ms(now);
    pthread_mutex_lock(&s->lock);
    if ((rc = db_begin(s->db, err)) ||
        (rc = store_tx_append(s, session, type, view, text, now, &at, err)) ||
        (rc = db_commit(s->db, err)))
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    free(text);
    if (!rc && seq)
        *seq = at;
    return rc;
}

int store_material_put_event(store *s, const char *id, const char *session, const json_t *doc,
                             const char *type, const json_t *data, int64_t *seq,
                             glint_err *err)
{
    char now[GLINT_TIME_LEN], *text, *mtext = NULL;
    db_stmt *st = NULL;
    int64_t at = 0;
    int rc;

    if ((rc = event_text(session, type, data, &text, err)))
        return rc;
    if (!glint_id_valid(id)) {
        free(text);
        return glint_err_set(err, GLINT_EINVAL, "invalid id \"%.40s\"", id ? id : "");
    }
    if (!(mtext = store_dump(doc))) {
        free(text);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory serializing a document");
    }
    glint_time_iso_ms(now);
    pthread_mutex_lock(&s->lock);
    if ((rc = db_begin(s->db, err)))
        goto out;
    if (!(st = store_prep(s, "INSERT INTO materials (id, doc, created, session) "
                             "VALUES (?1, ?2, ?3, ?4)", err))) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    db_bind_text(st, 2, mtext);
    db_bind_text(st, 3, now);
    db_bind_text(st, 4, session);
    if (!(rc = store_run(st, "writing", err)) &&
        !(rc = store_tx_append(s, session, type, -1, text, now, &at, err)))
        rc = db_commit(s->db, err);
out:
    db_finalize(st);
    if (rc)
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    free(text);
    free(mtext);
    if (!rc && seq)
        *seq = at;
    return rc;
}

/* Rows of the event log after `since` (only strokes when strokes_only),
 * at most `limit` (<= 0: no limit) and, max_bytes > 0, at most max_bytes of
 * compact JSON over the records (each with its comma; the first is taken
 * whatever its size).  as_stroke: records shaped
 * {"seq","view","stroke","created"}, else {"seq","type","view","data","created"}. */
static int store_log_read(store *s, const char *session, int64_t since, int limit,
                          size_t max_bytes, int strokes_only, json_t **array, int *more,
                          int64_t *last_seq, glint_err *err)
{
    db_stmt *st = NULL;
    json_t *arr = json_array();
    int rc = 0, step, count = 0;
    int64_t last_here;
    size_t bytes = 0;

    *array = NULL;
    if (!last_seq)
        last_seq = &last_here; /* read anyway: it tells unknown sessions (ENOTFOUND) */
    if (more)
        *more = 0;
    if (!arr)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory reading events");
    if (!glint_id_valid(session)) {
        json_decref(arr);
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"",
                             session ? session : "");
    }
    pthread_mutex_lock(&s->lock);
    /* one read transaction: the rows and last_seq agree */
    if ((rc = db_begin_read(s->db, err)))
        goto out;
    if ((rc = store_tx_last_seq(s, session, 0, last_seq, err)))
        goto out;
    st = store_prep(s, strokes_only
                           ? "SELECT seq, type, view, data, created FROM events WHERE session = ?1 "
                             "AND seq > ?2 AND type = 'stroke' ORDER BY seq LIMIT ?3"
                           : "SELECT seq, type, view, data, created FROM events WHERE session = ?1 "
                             "AND seq > ?2 ORDER BY seq LIMIT ?3",
                    err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, session);
    db_bind_int(st, 2, since);
    db_bind_int(st, 3, limit > 0 ? (int64_t)limit + 1 : INT64_MAX);
    while ((step = db_step(st, "reading", err)) == DB_ROW) {
        json_t *data, *rec;
        if (limit > 0 && count == limit) {
            if (more)
                *more = 1;
            break;
        }
        data = store_load(db_col_text(st, 3), "event", err);
        if (!data) {
            rc = GLINT_EFORMAT;
            goto out;
        }
        rec = json_object();
        if (!rec) {
            json_decref(data);
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory reading events");
            goto out;
        }
        json_object_set_new(rec, "seq", json_integer(db_col_int(st, 0)));
        if (!strokes_only)
            json_object_set_new(rec, "type", json_string(db_col_text(st, 1)));
        if (!db_col_null(st, 2))
            json_object_set_new(rec, "view", json_integer(db_col_int(st, 2)));
        json_object_set_new(rec, strokes_only ? "stroke" : "data", data);
        json_object_set_new(rec, "created", json_string(db_col_text(st, 4)));
        if (max_bytes) {
            size_t size = json_dumpb(rec, NULL, 0, JSON_COMPACT) + 1;
            if (count > 0 && bytes + size > max_bytes) {
                json_decref(rec);
                if (more)
                    *more = 1;
                break;
            }
            bytes += size;
        }
        json_array_append_new(arr, rec);
        count++;
    }
    if (step < 0)
        rc = step;
out:
    db_finalize(st);
    if (db_in_tx(s->db)) {
        if (rc)
            db_rollback(s->db);
        else
            db_commit(s->db, NULL);
    }
    pthread_mutex_unlock(&s->lock);
    if (rc)
        json_decref(arr);
    else
        *array = arr;
    return rc;
}

int store_strokes_since(store *s, const char *session, int64_t since, json_t **array,
                        glint_err *err)
{
    return store_log_read(s, session, since, 0, 0, 1, array, NULL, NULL, err);
}

int store_strokes_page(store *s, const char *session, int64_t since, int limit,
                       size_t max_bytes, json_t **array, int *more, int64_t *last_seq,
                       glint_err *err)
{
    int m = 0;
    int64_t last = 0;
    int rc = store_log_read(s, session, since, limit, max_bytes, 1, array, &m, &last, err);
    if (rc)
        return rc;
    if (m)
        last = json_integer_value(
            json_object_get(json_array_get(*array, json_array_size(*array) - 1), "seq"));
    if (more)
        *more = m;
    if (last_seq)
        *last_seq = last;
    return 0;
}

int store_events_since(store *s, const char *session, int64_t since, int limit,
                       json_t **array, int64_t *last_seq, glint_err *err)
{
    return store_log_read(s, session, since, limit, 0, 0, array, NULL, last_seq, err);
}

int store_events_each(store *s, const char *session, int64_t since, int limit, size_t max_bytes,
                      store_event_fn fn, void *ctx, int *more, glint_err *err)
{
    db_stmt *st = NULL;
    size_t bytes = 0;
    int rc = 0, step, count = 0;
    int64_t last;

    *more = 0;
    if (!glint_id_valid(session))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"",
                             session ? session : "");
    pthread_mutex_lock(&s->lock);
    if ((rc = db_begin_read(s->db, err)))
        goto out;
    if ((rc = store_tx_last_seq(s, session, 0, &last, err))) /* ENOTFOUND for unknown ones */
        goto out;
    st = store_prep(s, "SELECT seq, type, view, data, created FROM events WHERE session = ?1 "
                       "AND seq > ?2 ORDER BY seq LIMIT ?3",
                    err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, session);
    db_bind_int(st, 2, since);
    db_bind_int(st, 3, limit > 0 ? (int64_t)limit + 1 : INT64_MAX);
    while ((step = db_step(st, "reading", err)) == DB_ROW) {
        store_event_row row;
        if ((limit > 0 && count == limit) || (max_bytes && count > 0 && bytes >= max_bytes)) {
            *more = 1;
            break;
        }
        row.seq = db_col_int(st, 0);
        row.type = db_col_text(st, 1);
        row.view = db_col_null(st, 2) ? -1 : db_col_int(st, 2);
        row.data = db_col_text(st, 3);
        row.created = db_col_text(st, 4);
        if (!row.type || !row.data || !row.created) {
            rc = glint_err_set(err, GLINT_EFORMAT, "database: event %lld of session %s lacks a "
                                                   "column", (long long)row.seq, session);
            goto out;
        }
        bytes += strlen(row.data);
        if ((rc = fn(ctx, &row, err)))
            goto out;
        count++;
    }
    if (step < 0)
        rc = step;
out:
    db_finalize(st);
    if (db_in_tx(s->db)) {
        if (rc)
            db_rollback(s->db);
        else
            db_commit(s->db, NULL);
    }
    pthread_mutex_unlock(&s->lock);
    return rc;
}

/* Remove what a crash can leave behind under blobs/sessions: painting
 * files no row names (written, then the commit never happened, or
 * committed and the old file not yet removed) and temporary files of
 * atomic writes.  Runs once at open, before anyone writes. */
void store_sweep(store *s)
{
    char dir[STORE_PATH_MAX];
    DIR *d;
    struct dirent *e;
    db_stmt *st;

    if (snprintf(dir, sizeof dir, "%s/sessions", s->blobs) >= (int)sizeof dir)
        return;
    d = opendir(dir);
    if (!d)
        return;
    st = store_prep(s, "SELECT 1 FROM paintings WHERE session = ?1 AND blob = ?2", NULL);
    if (!st) {
        closedir(d);
        return;
    }
    while ((e = readdir(d))) {
        char sdir[STORE_PATH_MAX];
        DIR *sd;
        struct dirent *f;
        if (!glint_id_valid(e->d_name))
            continue;
        if (snprintf(sdir, sizeof sdir, "%s/%s", dir, e->d_name) >= (int)sizeof sdir)
            continue;
        sd = opendir(sdir);
        if (!sd)
            continue;
        while ((f = readdir(sd))) {
            char name[600], path[STORE_PATH_MAX];
            int keep, pixels = 0;
            if (f->d_name[0] == '.')
                continue;
            snprintf(name, sizeof name, "sessions/%s/%s", e->d_name, f->d_name);
            {   /* a blob's decoded pixels go with it (store_pixels.c) */
                size_t nl = strlen(name), sl = strlen(STORE_PIXELS_SUFFIX);
                if (nl > sl && strcmp(name + nl - sl, STORE_PIXELS_SUFFIX) == 0) {
                    name[nl - sl] = '\0';
                    pixels = 1;
                }
            }
            db_reset(st);
            db_bind_text(st, 1, e->d_name);
            db_bind_text(st, 2, name);
            keep = db_step(st, "sweeping", NULL) == DB_ROW;
            /* a blob may be another replica's write before its commit (the
             * grace); pixels are written after their blob's commit, so
             * pixels whose blob no row names are left over at any age */
            if (!keep && snprintf(path, sizeof path, "%s/%s", sdir, f->d_name) < (int)sizeof path &&
                (pixels || store_sweepable(s, path)))
                unlink(path);
        }
        closedir(sd);
    }
    db_finalize(st);
    closedir(d);
}

