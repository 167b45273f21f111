/* store.c: the store's database: opening, schema, and the documents
 * (meshes, scenes, sessions, materials).  Blobs are in store_blob.c, the
 * session logs (paintings, strokes, events) in store_log.c.
 *
 * One connection, serialized by s->lock: every public function takes the
 * lock for its statements, so a multi-statement transaction (a session's
 * next sequence number, the rows that use it, the commit) is never
 * interleaved with another. */
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "fsio.h"
#include "ids.h"
#include "json_text.h"
#include "scene.h"
#include "store_int.h"

static const char *const store_schema_sqlite[] = {
    "CREATE TABLE schema_version (version INTEGER NOT NULL)",
    "CREATE TABLE meshes (id TEXT PRIMARY KEY, info TEXT NOT NULL, created TEXT NOT NULL)",
    "CREATE TABLE scenes (id TEXT PRIMARY KEY, doc TEXT NOT NULL, created TEXT NOT NULL)",
    "CREATE TABLE sessions (id TEXT PRIMARY KEY, scene_id TEXT NOT NULL, doc TEXT NOT NULL,"
    " created TEXT NOT NULL, last_seq INTEGER NOT NULL DEFAULT 0)",
    "CREATE INDEX sessions_scene ON sessions (scene_id)",
    "CREATE TABLE paintings (session TEXT NOT NULL, view INTEGER NOT NULL,"
    " version INTEGER NOT NULL, blob TEXT NOT NULL, updated TEXT NOT NULL,"
    " PRIMARY KEY (session, view))",
    "CREATE TABLE events (session TEXT NOT NULL, seq INTEGER NOT NULL, type TEXT NOT NULL,"
    " view INTEGER, data TEXT NOT NULL, created TEXT NOT NULL, PRIMARY KEY (session, seq))"
    " WITHOUT ROWID",
    "CREATE TABLE materials (id TEXT PRIMARY KEY, session TEXT, doc TEXT NOT NULL,"
    " created TEXT NOT NULL)",
    "CREATE INDEX materials_session ON materials (session)",
    NULL};

/* The same tables in PostgreSQL: 64-bit integers, and an explicit
 * insertion order (ord) where SQLite's lists use its rowid. */
static const char *const store_schema_postgres[] = {
    "CREATE TABLE schema_version (version INTEGER NOT NULL)",
    "CREATE TABLE meshes (id TEXT PRIMARY KEY, info TEXT NOT NULL, created TEXT NOT NULL)",
    "CREATE TABLE scenes (id TEXT PRIMARY KEY, doc TEXT NOT NULL, created TEXT NOT NULL,"
    " ord BIGSERIAL)",
    "CREATE TABLE sessions (id TEXT PRIMARY KEY, scene_id TEXT NOT NULL, doc TEXT NOT NULL,"
    " created TEXT NOT NULL, last_seq BIGINT NOT NULL DEFAULT 0)",
    "CREATE INDEX sessions_scene ON sessions (scene_id)",
    "CREATE TABLE paintings (session TEXT NOT NULL, view INTEGER NOT NULL,"
    " version BIGINT NOT NULL, blob TEXT NOT NULL, updated TEXT NOT NULL,"
    " PRIMARY KEY (session, view))",
    "CREATE TABLE events (session TEXT NOT NULL, seq BIGINT NOT NULL, type TEXT NOT NULL,"
    " view INTEGER, data TEXT NOT NULL, created TEXT NOT NULL, PRIMARY KEY (session, seq))",
    "CREATE TABLE materials (id TEXT PRIMARY KEY, session TEXT, doc TEXT NOT NULL,"
    " created TEXT NOT NULL, ord BIGSERIAL)",
    "CREATE INDEX materials_session ON materials (session)",
    NULL};

/* ---- helpers ------------------------------------------------------------ */

/* Compact JSON text with every double exact (caller frees). */
char *store_dump(const json_t *j)
{
    return json_text(j, 0);
}

/* A scene stored before it named its radiance (scene.h) had its base
 * rendered at scale pi for what is now scale 1 (a white Lambertian facing
 * the light reads I): read it in today's units, so its base renders and the
 * finishes painted over them keep their brightness. */
static void scene_upgrade(json_t *doc)
{
    json_t *base = json_object_get(doc, "base");
    double s = json_number_value(json_object_get(base, "scale"));

    if (!json_is_object(doc) || json_object_get(doc, "radiance"))
        return;
    if (json_is_object(base) && s > 0.0)
        json_object_set_new(base, "scale", json_real(s / GLINT_LIGHT_UNIT));
    json_object_set_new(doc, "radiance", json_string(STORE_SCENE_RADIANCE));
}

json_t *store_load(const char *text, const char *what, glint_err *err)
{
    json_error_t je;
    json_t *j = text ? json_loads(text, 0, &je) : NULL;
    if (!j)
        glint_err_set(err, GLINT_EFORMAT, "database: %s holds malformed JSON: %s", what,
                      text ? je.text : "NULL");
    else if (!strcmp(what, "scene"))
        scene_upgrade(j);
    return j;
}

int store_exec(store *s, const char *sql, glint_err *err)
{
    return db_exec(s->db, sql, err);
}

db_stmt *store_prep(store *s, const char *sql, glint_err *err)
{
    return db_prep(s->db, sql, err);
}

int store_run(db_stmt *st, const char *what, glint_err *err)
{
    int rc = db_step(st, what, err);
    if (rc == DB_ROW)
        return glint_err_set(err, GLINT_EIO, "database: %s: unexpected row", what);
    return rc;
}

void store_rollback(store *s)
{
    db_rollback(s->db);
}

const char *store_pick(const store *s, const char *sqlite_sql, const char *postgres_sql)
{
    return db_kind_of(s->db) == DB_POSTGRES ? postgres_sql : sqlite_sql;
}

/* ---- open, schema ---------------------------------------------------------- */

/* One integer from a query without parameters (OUT: *v, 0 when no row). */
static int store_int(store *s, const char *sql, int64_t *v, glint_err *err)
{
    db_stmt *st = store_prep(s, sql, err);
    int rc;
    *v = 0;
    if (!st)
        return GLINT_EIO;
    rc = db_step(st, "reading the schema", err);
    if (rc == DB_ROW)
        *v = db_col_int(st, 0);
    db_finalize(st);
    return rc < 0 ? rc : 0;
}

static int store_schema_check(store *s, glint_err *err)
{
    const char *const *schema =
        db_kind_of(s->db) == DB_POSTGRES ? store_schema_postgres : store_schema_sqlite;
    int64_t have = 0, version = 0;
    int rc;

    if ((rc = store_int(s, store_pick(s, "SELECT count(*) FROM sqlite_master WHERE type = "
                                         "'table' AND name = 'schema_version'",
                                      "SELECT count(*) FROM information_schema.tables WHERE "
                                      "table_schema = current_schema() AND "
                                      "table_name = 'schema_version'"),
                        &have, err)))
        return rc;
    if (have) {
        if ((rc = store_int(s, "SELECT max(version) FROM schema_version", &version, err)))
            return rc;
        if (version == STORE_SCHEMA_VERSION)
            return 0;
        if (version > STORE_SCHEMA_VERSION)
            return glint_err_set(err, GLINT_EUNSUPPORTED,
                                 "database schema version %d is newer than this glintd's (%d): "
                                 "use a newer glintd or another data directory",
                                 (int)version, STORE_SCHEMA_VERSION);
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "database schema version %d has no upgrade path to %d", (int)version,
                             STORE_SCHEMA_VERSION);
    }
    if ((rc = db_begin(s->db, err)))
        return rc;
    for (int i = 0; schema[i]; i++)
        if ((rc = store_exec(s, schema[i], err)))
            goto fail;
    {
        char sql[96];
        snprintf(sql, sizeof sql, "INSERT INTO schema_version (version) VALUES (%d)",
                 STORE_SCHEMA_VERSION);
        if ((rc = store_exec(s, sql, err)))
            goto fail;
    }
    if ((rc = db_commit(s->db, err)))
        goto fail;
    return 0;
fail:
    store_rollback(s);
    return rc;
}

/* PostgreSQL: replicas starting together create the tables once (a
 * session-level advisory lock around the check and the creation). */
static int store_schema_init(store *s, glint_err *err)
{
    int rc, pg = db_kind_of(s->db) == DB_POSTGRES;
    if (pg && (rc = store_exec(s, "SELECT pg_advisory_lock(74736)", err)))
        return rc;
    rc = store_schema_check(s, err);
    if (pg)
        db_exec(s->db, "SELECT pg_advisory_unlock(74736)", NULL);
    return rc;
}

/* SQLite: WAL with synchronous=FULL: every COMMIT fsyncs the log before it
 * returns, so a committed transaction survives kill -9 and power loss. */
static int store_sqlite_setup(store *s, const char *dbpath, glint_err *err)
{
    db_stmt *st = store_prep(s, "PRAGMA journal_mode = WAL", err);
    const char *mode;
    int rc;
    if (!st)
        return GLINT_EIO;
    rc = db_step(st, "journal mode", err);
    mode = rc == DB_ROW ? db_col_text(st, 0) : NULL;
    if (rc >= 0 && (!mode || strcmp(mode, "wal") != 0))
        rc = glint_err_set(err, GLINT_EIO, "database %s: cannot switch to WAL journal mode",
                           dbpath);
    db_finalize(st);
    if (rc < 0)
        return rc;
    if ((rc = store_exec(s, "PRAGMA synchronous = FULL", err)) ||
        (rc = store_exec(s, "PRAGMA foreign_keys = OFF", err)))
        return rc;
    return 0;
}

int store_open(const char *data_dir, store **out, glint_err *err)
{
    return store_open_db(data_dir, NULL, out, err);
}

int store_open_db(const char *data_dir, const char *database, store **out, glint_err *err)
{
    store *s;
    char dbpath[STORE_PATH_MAX];
    int rc;

    *out = NULL;
    s = calloc(1, sizeof *s);
    if (!s)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory opening the store");
    pthread_mutex_init(&s->lock, NULL);
    store_reap_init(s);
    if (snprintf(s->dir, sizeof s->dir, "%s", data_dir) >= (int)sizeof s->dir ||
        snprintf(s->blobs, sizeof s->blobs, "%s/blobs", data_dir) >= (int)sizeof s->blobs ||
        snprintf(dbpath, sizeof dbpath, "%s/glint.db", data_dir) >= (int)sizeof dbpath) {
        rc = glint_err_set(err, GLINT_ERANGE, "data directory path too long");
        goto fail_paths;
    }
    if ((rc = fsio_mkdirs(s->blobs, err)) || (rc = glint_id_new(s->instance, err)))
        goto fail_paths;
    if (database && *database) {
        /* blobs may be shared with other glintd processes: the sweep
         * spares what is younger than any write in progress could be */
        s->sweep_grace = STORE_SHARED_SWEEP_GRACE;
        if (!(s->conninfo = strdup(database)))
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory opening the store");
        else
            rc = db_open_postgres(database, &s->db, err);
    } else {
        rc = db_open_sqlite(dbpath, &s->db, err);
        if (!rc)
            rc = store_sqlite_setup(s, dbpath, err);
    }
    if (rc || (rc = store_schema_init(s, err)))
        goto fail_db;
    store_sweep(s);
    store_sweep_blobs(s);
    *out = s;
    return 0;

fail_db:
    glint_err_prefix(err, "store %s", data_dir);
    db_close(s->db);
    free(s->conninfo);
fail_paths:
    store_reap_stop(s);
    pthread_mutex_destroy(&s->lock);
    free(s);
    return rc;
}

const char *store_backend(const store *s)
{
    return db_kind_of(s->db) == DB_POSTGRES ? "postgresql" : "sqlite";
}

void store_close(store *s)
{
    if (!s)
        return;
    store_listen_stop(s);
    store_reap_stop(s);
    db_close(s->db);
    free(s->conninfo);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

/* ---- documents ---------------------------------------------------------------- */

/* SELECT one text column by id and parse it. */
static int store_get_doc(store *s, const char *sql, const char *id, const char *what,
                         json_t **doc, glint_err *err)
{
    db_stmt *st;
    int rc;

    *doc = NULL;
    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no %s with id \"%.40s\"", what, id ? id : "");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, sql, err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    rc = db_step(st, "reading", err);
    if (rc == DB_ROW) {
        *doc = store_load(db_col_text(st, 0), what, err);
        rc = *doc ? 0 : GLINT_EFORMAT;
    } else if (rc == DB_DONE) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no %s with id %s", what, id);
    }
out:
    db_finalize(st);
    pthread_mutex_unlock(&s->lock);
    return rc;
}

/* INSERT (id, doc, created [, extra]) with one statement. */
static int store_put_doc(store *s, const char *sql, const char *id, const json_t *doc,
                         const char *extra, glint_err *err)
{
    db_stmt *st;
    char *text;
    char now[GLINT_TIME_LEN];
    int rc;

    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_EINVAL, "invalid id \"%.40s\"", id ? id : "");
    text = store_dump(doc);
    if (!text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory serializing a document");
    glint_time_iso_ms(now);
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, sql, err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    db_bind_text(st, 2, text);
    db_bind_text(st, 3, now);
    if (extra)
        db_bind_text(st, 4, extra);
    rc = store_run(st, "writing", err);
out:
    db_finalize(st);
    pthread_mutex_unlock(&s->lock);
    free(text);
    return rc;
}

static int store_mesh_blob(const char *id, const char *format, char *buf, size_t len,
                           glint_err *err)
{
    if (!format || !*format || strlen(format) > 8)
        return glint_err_set(err, GLINT_EINVAL, "mesh format \"%.16s\" invalid", format ? format : "");
    for (const char *c = format; *c; c++)
        if (!((*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9')))
            return glint_err_set(err, GLINT_EINVAL, "mesh format \"%.16s\" invalid", format);
    if (snprintf(buf, len, "meshes/%s.%s", id, format) >= (int)len)
        return glint_err_set(err, GLINT_ERANGE, "mesh blob name too long");
    return 0;
}

int store_mesh_put(store *s, const char *id, const json_t *info, const void *data, size_t len,
                   glint_err *err)
{
    char name[128];
    int rc;
    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_EINVAL, "invalid mesh id \"%.40s\"", id ? id : "");
    rc = store_mesh_blob(id, json_string_value(json_object_get(info, "format")), name,
                         sizeof name, err);
    if (rc || (rc = store_blob_put(s, name, data, len, err)))
        return rc;
    rc = store_put_doc(s, "INSERT INTO meshes (id, info, created) VALUES (?1, ?2, ?3)", id, info,
                       NULL, err);
    if (rc)
        store_blob_delete(s, name, NULL);
    return rc;
}

int store_mesh_get(store *s, const char *id, json_t **info, glint_err *err)
{
    return store_get_doc(s, "SELECT info FROM meshes WHERE id = ?1", id, "mesh", info, err);
}

int store_mesh_data(store *s, const char *id, void **data, size_t *len, char format[16],
                    glint_err *err)
{
    json_t *info = NULL;
    char name[128];
    const char *f;
    int rc;

    *data = NULL;
    if ((rc = store_mesh_get(s, id, &info, err)))
        return rc;
    f = json_string_value(json_object_get(info, "format"));
    rc = store_mesh_blob(id, f, name, sizeof name, err);
    if (!rc) {
        snprintf(format, 16, "%s", f);
        rc = store_blob_get(s, name, data, len, err);
    }
    json_decref(info);
    return rc;
}

int store_scene_put(store *s, const char *id, const json_t *doc, glint_err *err)
{
    return store_put_doc(s, "INSERT INTO scenes (id, doc, created) VALUES (?1, ?2, ?3)", id, doc,
                         NULL, err);
}

int store_scene_get(store *s, const char *id, json_t **doc, glint_err *err)
{
    return store_get_doc(s, "SELECT doc FROM scenes WHERE id = ?1", id, "scene", doc, err);
}

int store_scene_list(store *s, json_t **array, glint_err *err)
{
    db_stmt *st;
    json_t *arr = json_array();
    int rc = 0, step;

    *array = NULL;
    if (!arr)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory listing scenes");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, store_pick(s, "SELECT doc FROM scenes ORDER BY rowid",
                                   "SELECT doc FROM scenes ORDER BY ord"), err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    while ((step = db_step(st, "reading", err)) == DB_ROW) {
        json_t *d = store_load(db_col_text(st, 0), "scene", err);
        if (!d || json_array_append_new(arr, d)) {
            rc = d ? glint_err_set(err, GLINT_ENOMEM, "out of memory listing scenes")
                   : GLINT_EFORMAT;
            goto out;
        }
    }
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

int store_scene_count_naming(store *s, const char *text, long long *n, glint_err *err)
{
    char *pat;
    db_stmt *st;
    size_t len = text ? strlen(text) : 0;
    int rc = 0, step;

    *n = 0;
    if (!len || strpbrk(text, "%_\\"))
        return glint_err_set(err, GLINT_EINVAL, "store_scene_count_naming: \"%.40s\" is empty "
                             "or holds a LIKE wildcard", text ? text : "");
    if (!(pat = malloc(len + 3)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory counting scenes");
    snprintf(pat, len + 3, "%%%s%%", text);
    pthread_mutex_lock(&s->lock);
    if (!(st = store_prep(s, "SELECT count(*) FROM scenes WHERE doc LIKE ?1", err))) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, pat);
    if ((step = db_step(st, "counting scenes", err)) == DB_ROW)
        *n = (long long)db_col_int(st, 0);
    else
        rc = step < 0 ? step : glint_err_set(err, GLINT_EIO, "counting scenes: no answer");
out:
    db_finalize(st);
    pthread_mutex_unlock(&s->lock);
    free(pat);
    return rc;
}

int store_scene_delete(store *s, const char *id, glint_err *err)
{
    db_stmt *st = NULL;
    json_t *sessions = json_array(), *materials = json_array();
    int rc = 0, step;
    static const char *const dels[] = {
        "DELETE FROM materials WHERE session IN (SELECT id FROM sessions WHERE scene_id = ?1)",
        "DELETE FROM events WHERE session IN (SELECT id FROM sessions WHERE scene_id = ?1)",
        "DELETE FROM paintings WHERE session IN (SELECT id FROM sessions WHERE scene_id = ?1)",
        "DELETE FROM sessions WHERE scene_id = ?1",
        "DELETE FROM scenes WHERE id = ?1",
        NULL};

    if (!sessions || !materials) {
        json_decref(sessions);
        json_decref(materials);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory deleting a scene");
    }
    if (!glint_id_valid(id)) {
        json_decref(sessions);
        json_decref(materials);
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene with id \"%.40s\"", id ? id : "");
    }
    pthread_mutex_lock(&s->lock);
    if ((rc = db_begin(s->db, err)))
        goto out;
    /* PostgreSQL: the row locked, so a session created on the scene by
     * another process either commits first (and is deleted here) or waits
     * and finds no scene */
    st = store_prep(s, store_pick(s, "SELECT 1 FROM scenes WHERE id = ?1",
                                  "SELECT 1 FROM scenes WHERE id = ?1 FOR UPDATE"), err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    if ((step = db_step(st, "deleting a scene", err)) != DB_ROW) {
        rc = step < 0 ? step : glint_err_set(err, GLINT_ENOTFOUND, "no scene with id %s", id);
        goto out;
    }
    db_finalize(st);
    st = store_prep(s, "SELECT id FROM sessions WHERE scene_id = ?1", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    while ((step = db_step(st, "reading", err)) == DB_ROW)
        json_array_append_new(sessions, json_string(db_col_text(st, 0)));
    if (step < 0) {
        rc = step;
        goto out;
    }
    db_finalize(st);
    st = store_prep(s, "SELECT id FROM materials WHERE session IN "
                       "(SELECT id FROM sessions WHERE scene_id = ?1)", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    while ((step = db_step(st, "reading", err)) == DB_ROW)
        json_array_append_new(materials, json_string(db_col_text(st, 0)));
    if (step < 0) {
        rc = step;
        goto out;
    }
    for (int i = 0; dels[i]; i++) {
        db_finalize(st);
        st = store_prep(s, dels[i], err);
        if (!st) {
            rc = GLINT_EIO;
            goto out;
        }
        db_bind_text(st, 1, id);
        if ((rc = store_run(st, "deleting a scene", err)))
            goto out;
    }
    rc = db_commit(s->db, err);
out:
    db_finalize(st);
    if (rc)
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    if (!rc) {
        char name[128];
        size_t i;
        json_t *v;
        snprintf(name, sizeof name, "scenes/%s", id);
        store_blob_rmtree(s, name);
        json_array_foreach(sessions, i, v) {
            snprintf(name, sizeof name, "sessions/%s", json_string_value(v));
            store_blob_rmtree(s, name);
        }
        json_array_foreach(materials, i, v) {
            snprintf(name, sizeof name, "materials/%s", json_string_value(v));
            store_blob_rmtree(s, name);
        }
    }
    json_decref(sessions);
    json_decref(materials);
    return rc;
}

int store_session_put(store *s, const char *id, const json_t *doc, glint_err *err)
{
    const char *scene_id = json_string_value(json_object_get(doc, "scene_id"));
    db_stmt *st;
    char *text = NULL;
    char now[GLINT_TIME_LEN];
    int rc;

    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_EINVAL, "invalid session id \"%.40s\"", id ? id : "");
    if (!glint_id_valid(scene_id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene with id \"%.40s\"",
                             scene_id ? scene_id : "");
    text = store_dump(doc);
    if (!text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory serializing a session");
    glint_time_iso_ms(now);
    pthread_mutex_lock(&s->lock);
    /* one statement: the session exists only if its scene does */
    st = store_prep(s, store_pick(s, "INSERT INTO sessions (id, scene_id, doc, created) "
                                     "SELECT ?1, ?2, ?3, ?4 "
                                     "WHERE EXISTS (SELECT 1 FROM scenes WHERE id = ?2)",
                                  "INSERT INTO sessions (id, scene_id, doc, created) "
                                  "SELECT ?1, ?2, ?3, ?4 FROM scenes WHERE id = ?2 FOR SHARE"),
                    err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    db_bind_text(st, 2, scene_id);
    db_bind_text(st, 3, text);
    db_bind_text(st, 4, now);
    if ((rc = store_run(st, "creating a session", err)) < 0)
        ;
    else if (db_changes(st) == 0)
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no scene with id %s", scene_id);
    else
        rc = 0;
out:
    db_finalize(st);
    pthread_mutex_unlock(&s->lock);
    free(text);
    return rc;
}

int store_session_update(store *s, const char *id, const json_t *doc, glint_err *err)
{
    json_t *copy = json_copy((json_t *)doc);
    db_stmt *st;
    char *text = NULL;
    int rc;

    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"", id ? id : "");
    if (copy)
        json_object_del(copy, "last_seq"); /* the log's, added by get */
    text = copy ? store_dump(copy) : NULL;
    json_decref(copy);
    if (!text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory serializing a session");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, "UPDATE sessions SET doc = ?2 WHERE id = ?1", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    db_bind_text(st, 2, text);
    if ((rc = store_run(st, "updating a session", err)) < 0)
        ;
    else if (db_changes(st) == 0)
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no session with id %s", id);
    else
        rc = 0;
out:
    db_finalize(st);
    pthread_mutex_unlock(&s->lock);
    free(text);
    return rc;
}

int store_session_get(store *s, const char *id, json_t **doc, glint_err *err)
{
    db_stmt *st;
    int rc;

    *doc = NULL;
    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"", id ? id : "");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, "SELECT doc, last_seq FROM sessions WHERE id = ?1", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, id);
    rc = db_step(st, "reading", err);
    if (rc == DB_ROW) {
        *doc = store_load(db_col_text(st, 0), "session", err);
        if (*doc) {
            json_object_set_new(*doc, "last_seq", json_integer(db_col_int(st, 1)));
            rc = 0;
        } else {
            rc = GLINT_EFORMAT;
        }
    } else if (rc == DB_DONE) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no session with id %s", id);
    }
out:
    db_finalize(st);
    pthread_mutex_unlock(&s->lock);
    return rc;
}

int store_material_put(store *s, const char *id, const char *session, const json_t *doc,
                       glint_err *err)
{
    return store_put_doc(s, "INSERT INTO materials (id, doc, created, session) "
                            "VALUES (?1, ?2, ?3, ?4)",
                         id, doc, session, err);
}

int store_material_get(store *s, const char *id, json_t **doc, glint_err *err)
{
    return store_get_doc(s, "SELECT doc FROM materials WHERE id = ?1", id, "material", doc, err);
}

int store_material_list(store *s, const char *session, json_t **array, glint_err *err)
{
    db_stmt *st;
    json_t *arr = json_array();
    int rc = 0, step;

    *array = NULL;
    if (!arr)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory listing materials");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, store_pick(s, "SELECT doc FROM materials WHERE session = ?1 ORDER BY rowid",
                                   "SELECT doc FROM materials WHERE session = ?1 ORDER BY ord"),
                    err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, session ? session : "");
    while ((step = db_step(st, "reading", err)) == DB_ROW) {
        json_t *d = store_load(db_col_text(st, 0), "material", err);
        if (!d) {
            rc = GLINT_EFORMAT;
            goto out;
        }
        json_array_append_new(arr, d);
    }
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

int store_materials_delete(store *s, const char *session, glint_err *err)
{
    json_t *ids = json_array(), *v;
    db_stmt *st = NULL;
    size_t i;
    int rc = 0, step;

    if (!ids)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory deleting materials");
    if (!glint_id_valid(session)) {
        json_decref(ids);
        return 0; /* no material names it */
    }
    pthread_mutex_lock(&s->lock);
    if ((rc = db_begin(s->db, err)))
        goto out;
    if (!(st = store_prep(s, "SELECT id FROM materials WHERE session = ?1", err))) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, session);
    while ((step = db_step(st, "reading", err)) == DB_ROW)
        json_array_append_new(ids, json_string(db_col_text(st, 0)));
    if (step < 0) {
        rc = step;
        goto out;
    }
    db_finalize(st);
    if (!(st = store_prep(s, "DELETE FROM materials WHERE session = ?1", err))) {
        rc = GLINT_EIO;
        goto out;
    }
    db_bind_text(st, 1, session);
    if (!(rc = store_run(st, "deleting materials", err)))
        rc = db_commit(s->db, err);
out:
    db_finalize(st);
    if (rc)
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    /* the rows first: a crash leaves directories nothing names (swept) */
    json_array_foreach(ids, i, v) {
        char name[128];
        if (rc || !json_is_string(v))
            break;
        snprintf(name, sizeof name, "materials/%s", json_string_value(v));
        store_blob_rmtree(s, name);
    }
    json_decref(ids);
    return rc;
}
