/* store.c: SQLite metadata + blob files (store.h).
 *
 * One connection, serialized by s->lock: every public function takes the
 * lock for its statements, so a multi-statement transaction (a session's
 * next sequence number, the rows that use it, the commit) is never
 * interleaved with another.  Blob files are written before the lock is
 * taken (their names are random, so no coordination is needed) and the
 * files a commit replaced are removed after it. */
#include "store.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "brdf.h"
#include "fsio.h"
#include "gbuf.h"
#include "img.h"
#include "mesh.h"
#include "paint.h"
#include "raster.h"
#include "scene.h"

#define STORE_PATH_MAX 4096
#define STORE_BLOB_MAX ((size_t)1 << 31)
#define STORE_SCENE_CACHE 4

/* A loaded core scene shared by the requests that use it. */
typedef struct store_cached {
    char id[33];
    scene *sc;              /* NULL: empty slot */
    int refs;
    int dead;               /* deleted while in use: freed at the last release */
    unsigned long used;     /* LRU tick */
} store_cached;

struct store {
    sqlite3 *db;
    pthread_mutex_t lock;
    char dir[STORE_PATH_MAX];
    char blobs[STORE_PATH_MAX];
    pthread_mutex_t cache_lock;
    store_cached cache[STORE_SCENE_CACHE];
    unsigned long tick;
};

static const char *const store_schema[] = {
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

/* ------------------------------------------------------------------------ */
/* Small helpers                                                             */
/* ------------------------------------------------------------------------ */

static int store_sqlerr(store *s, glint_err *err, const char *what)
{
    return glint_err_set(err, GLINT_EIO, "database: %s: %s", what, sqlite3_errmsg(s->db));
}

int store_new_id(char id[33], glint_err *err)
{
    unsigned char b[16];
    size_t got = 0;
    static const char hex[] = "0123456789abcdef";

    while (got < sizeof b) {
        ssize_t n = getrandom(b + got, sizeof b - got, 0);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return glint_err_set(err, GLINT_EIO, "getrandom: %s", strerror(errno));
        }
        got += (size_t)n;
    }
    for (int i = 0; i < 16; i++) {
        id[2 * i] = hex[b[i] >> 4];
        id[2 * i + 1] = hex[b[i] & 15];
    }
    id[32] = '\0';
    return 0;
}

int store_id_valid(const char *id)
{
    if (!id || strlen(id) != 32)
        return 0;
    for (int i = 0; i < 32; i++)
        if (!((id[i] >= '0' && id[i] <= '9') || (id[i] >= 'a' && id[i] <= 'f')))
            return 0;
    return 1;
}

void store_now(char buf[32])
{
    struct timespec ts;
    struct tm tm;
    clock_gettime(CLOCK_REALTIME, &ts);
    gmtime_r(&ts.tv_sec, &tm);
    size_t n = strftime(buf, 32, "%Y-%m-%dT%H:%M:%S", &tm);
    unsigned ms = (unsigned)(ts.tv_nsec / 1000000) % 1000u;
    if (n == 0 || n > 24)
        n = 0;
    buf[n] = '.';
    buf[n + 1] = (char)('0' + ms / 100);
    buf[n + 2] = (char)('0' + ms / 10 % 10);
    buf[n + 3] = (char)('0' + ms % 10);
    buf[n + 4] = 'Z';
    buf[n + 5] = '\0';
}

/* Compact JSON text with every double exact (caller frees). */
static char *store_dump(const json_t *j)
{
    return json_dumps(j, JSON_COMPACT | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17));
}

static json_t *store_load(const char *text, const char *what, glint_err *err)
{
    json_error_t je;
    json_t *j = text ? json_loads(text, 0, &je) : NULL;
    if (!j)
        glint_err_set(err, GLINT_EFORMAT, "database: %s holds malformed JSON: %s", what,
                      text ? je.text : "NULL");
    return j;
}

/* Run SQL without results. */
static int store_exec(store *s, const char *sql, glint_err *err)
{
    char *msg = NULL;
    if (sqlite3_exec(s->db, sql, NULL, NULL, &msg) != SQLITE_OK) {
        int rc = glint_err_set(err, GLINT_EIO, "database: %s: %s", sql, msg ? msg : "error");
        sqlite3_free(msg);
        return rc;
    }
    return 0;
}

static sqlite3_stmt *store_prep(store *s, const char *sql, glint_err *err)
{
    sqlite3_stmt *st = NULL;
    if (sqlite3_prepare_v2(s->db, sql, -1, &st, NULL) != SQLITE_OK) {
        store_sqlerr(s, err, "prepare");
        sqlite3_finalize(st);
        return NULL;
    }
    return st;
}

static void store_rollback(store *s)
{
    if (!sqlite3_get_autocommit(s->db))
        sqlite3_exec(s->db, "ROLLBACK", NULL, NULL, NULL);
}

/* ------------------------------------------------------------------------ */
/* Blobs                                                                     */
/* ------------------------------------------------------------------------ */

static int store_blob_name_ok(const char *name)
{
    size_t n;
    if (!name || !*name || name[0] == '/' || strstr(name, "..") || strstr(name, "//"))
        return 0;
    n = strlen(name);
    if (n > 512 || name[n - 1] == '/')
        return 0;
    for (const char *c = name; *c; c++)
        if (!((*c >= 'a' && *c <= 'z') || (*c >= 'A' && *c <= 'Z') || (*c >= '0' && *c <= '9') ||
              *c == '.' || *c == '_' || *c == '-' || *c == '/'))
            return 0;
    return 1;
}

int store_blob_path(store *s, const char *name, char *buf, size_t len, glint_err *err)
{
    if (!store_blob_name_ok(name))
        return glint_err_set(err, GLINT_EINVAL, "invalid blob name \"%.80s\"", name ? name : "");
    return fsio_join(buf, len, s->blobs, name, err);
}

static void store_fsync_dir(const char *dir)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
}

/* Make the directory holding `path` (under s->blobs), fsyncing each parent
 * whose entry was created, so a committed row never names a file in a
 * directory that a crash forgot. */
static int store_mkparents(store *s, const char *path, glint_err *err)
{
    char dir[STORE_PATH_MAX];
    size_t base = strlen(s->blobs);
    char *slash;
    struct stat st;

    snprintf(dir, sizeof dir, "%s", path);
    slash = strrchr(dir, '/');
    if (!slash || (size_t)(slash - dir) <= base)
        return 0;
    *slash = '\0';
    if (stat(dir, &st) == 0 && S_ISDIR(st.st_mode))
        return 0;
    /* create each missing component below blobs/, fsync its parent */
    for (char *p = dir + base + 1; ; p++) {
        if (*p == '/' || *p == '\0') {
            char save = *p;
            *p = '\0';
            if (mkdir(dir, 0755) == 0) {
                char *up = strrchr(dir, '/');
                if (up) {
                    *up = '\0';
                    store_fsync_dir(dir);
                    *up = '/';
                }
            } else if (errno != EEXIST) {
                int e = errno;
                *p = save;
                return glint_err_set(err, GLINT_EIO, "cannot create %s: %s", dir, strerror(e));
            }
            *p = save;
            if (save == '\0')
                break;
        }
    }
    return 0;
}

int store_blob_put(store *s, const char *name, const void *data, size_t len, glint_err *err)
{
    char path[STORE_PATH_MAX];
    int rc = store_blob_path(s, name, path, sizeof path, err);
    if (rc || (rc = store_mkparents(s, path, err)))
        return rc;
    return fsio_write_atomic(path, data, len, err);
}

int store_blob_get(store *s, const char *name, void **data, size_t *len, glint_err *err)
{
    char path[STORE_PATH_MAX];
    char *d = NULL;
    int rc = store_blob_path(s, name, path, sizeof path, err);
    *data = NULL;
    if (rc)
        return rc;
    rc = fsio_read_all(path, STORE_BLOB_MAX, &d, len, err);
    if (rc)
        return rc;
    *data = d;
    return 0;
}

int store_blob_delete(store *s, const char *name, glint_err *err)
{
    char path[STORE_PATH_MAX];
    int rc = store_blob_path(s, name, path, sizeof path, err);
    if (rc)
        return rc;
    if (unlink(path) != 0 && errno != ENOENT)
        return glint_err_set(err, GLINT_EIO, "cannot remove %s: %s", path, strerror(errno));
    return 0;
}

/* Remove a directory tree below blobs/ (best effort; two levels suffice
 * for glint's layout but any depth works). */
static void store_rmtree(const char *path)
{
    DIR *d = opendir(path);
    struct dirent *e;
    if (!d) {
        unlink(path);
        return;
    }
    while ((e = readdir(d))) {
        char sub[STORE_PATH_MAX];
        struct stat st;
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        if (snprintf(sub, sizeof sub, "%s/%s", path, e->d_name) >= (int)sizeof sub)
            continue;
        if (lstat(sub, &st) == 0 && S_ISDIR(st.st_mode))
            store_rmtree(sub);
        else
            unlink(sub);
    }
    closedir(d);
    rmdir(path);
}

static void store_blob_rmtree(store *s, const char *name)
{
    char path[STORE_PATH_MAX];
    if (store_blob_path(s, name, path, sizeof path, NULL) == 0)
        store_rmtree(path);
}

/* A name with a random part: "<prefix><16 hex><suffix>". */
static int store_random_name(char *buf, size_t len, const char *prefix, const char *suffix,
                             glint_err *err)
{
    char id[33];
    int rc = store_new_id(id, err);
    if (rc)
        return rc;
    id[16] = '\0';
    if (snprintf(buf, len, "%s%s%s", prefix, id, suffix) >= (int)len)
        return glint_err_set(err, GLINT_ERANGE, "blob name too long");
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Open, schema, sweep                                                       */
/* ------------------------------------------------------------------------ */

static int store_schema_init(store *s, glint_err *err)
{
    sqlite3_stmt *st;
    int have = 0, version = 0, rc;

    st = store_prep(s, "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND "
                       "name = 'schema_version'", err);
    if (!st)
        return GLINT_EIO;
    if (sqlite3_step(st) == SQLITE_ROW)
        have = sqlite3_column_int(st, 0);
    sqlite3_finalize(st);
    if (have) {
        st = store_prep(s, "SELECT max(version) FROM schema_version", err);
        if (!st)
            return GLINT_EIO;
        if (sqlite3_step(st) == SQLITE_ROW)
            version = sqlite3_column_int(st, 0);
        sqlite3_finalize(st);
        if (version == STORE_SCHEMA_VERSION)
            return 0;
        if (version > STORE_SCHEMA_VERSION)
            return glint_err_set(err, GLINT_EUNSUPPORTED,
                                 "database schema version %d is newer than this glintd's (%d): "
                                 "use a newer glintd or another data directory",
                                 version, STORE_SCHEMA_VERSION);
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "database schema version %d has no upgrade path to %d", version,
                             STORE_SCHEMA_VERSION);
    }
    if ((rc = store_exec(s, "BEGIN IMMEDIATE", err)))
        return rc;
    for (int i = 0; store_schema[i]; i++)
        if ((rc = store_exec(s, store_schema[i], err)))
            goto fail;
    {
        char sql[96];
        snprintf(sql, sizeof sql, "INSERT INTO schema_version (version) VALUES (%d)",
                 STORE_SCHEMA_VERSION);
        if ((rc = store_exec(s, sql, err)))
            goto fail;
    }
    if ((rc = store_exec(s, "COMMIT", err)))
        goto fail;
    return 0;
fail:
    store_rollback(s);
    return rc;
}

/* Remove what a crash can leave behind under blobs/sessions: painting
 * files no row names (written, then the commit never happened, or
 * committed and the old file not yet removed) and temporary files of
 * atomic writes.  Runs once at open, before anyone writes. */
static void store_sweep(store *s)
{
    char dir[STORE_PATH_MAX];
    DIR *d;
    struct dirent *e;
    sqlite3_stmt *st;

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
        if (!store_id_valid(e->d_name))
            continue;
        if (snprintf(sdir, sizeof sdir, "%s/%s", dir, e->d_name) >= (int)sizeof sdir)
            continue;
        sd = opendir(sdir);
        if (!sd)
            continue;
        while ((f = readdir(sd))) {
            char name[600], path[STORE_PATH_MAX];
            int keep;
            if (f->d_name[0] == '.')
                continue;
            snprintf(name, sizeof name, "sessions/%s/%s", e->d_name, f->d_name);
            sqlite3_reset(st);
            sqlite3_bind_text(st, 1, e->d_name, -1, SQLITE_TRANSIENT);
            sqlite3_bind_text(st, 2, name, -1, SQLITE_TRANSIENT);
            keep = sqlite3_step(st) == SQLITE_ROW;
            if (!keep && snprintf(path, sizeof path, "%s/%s", sdir, f->d_name) < (int)sizeof path)
                unlink(path);
        }
        closedir(sd);
    }
    sqlite3_finalize(st);
    closedir(d);
}

int store_open(const char *data_dir, store **out, glint_err *err)
{
    store *s;
    char dbpath[STORE_PATH_MAX];
    int rc;
    sqlite3_stmt *st;

    *out = NULL;
    s = calloc(1, sizeof *s);
    if (!s)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory opening the store");
    pthread_mutex_init(&s->lock, NULL);
    pthread_mutex_init(&s->cache_lock, NULL);
    if (snprintf(s->dir, sizeof s->dir, "%s", data_dir) >= (int)sizeof s->dir ||
        snprintf(s->blobs, sizeof s->blobs, "%s/blobs", data_dir) >= (int)sizeof s->blobs ||
        snprintf(dbpath, sizeof dbpath, "%s/glint.db", data_dir) >= (int)sizeof dbpath) {
        rc = glint_err_set(err, GLINT_ERANGE, "data directory path too long");
        goto fail_paths;
    }
    if ((rc = fsio_mkdirs(s->blobs, err)))
        goto fail_paths;
    if (sqlite3_open_v2(dbpath, &s->db,
                        SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                        NULL) != SQLITE_OK) {
        rc = glint_err_set(err, GLINT_EIO, "cannot open database %s: %s", dbpath,
                           s->db ? sqlite3_errmsg(s->db) : "out of memory");
        goto fail_db;
    }
    sqlite3_busy_timeout(s->db, 10000);
    /* WAL with synchronous=FULL: every COMMIT fsyncs the log before it
     * returns, so a committed transaction survives kill -9 and power loss. */
    st = store_prep(s, "PRAGMA journal_mode = WAL", err);
    if (!st) {
        rc = GLINT_EIO;
        goto fail_db;
    }
    if (sqlite3_step(st) != SQLITE_ROW ||
        strcmp((const char *)sqlite3_column_text(st, 0), "wal") != 0) {
        sqlite3_finalize(st);
        rc = glint_err_set(err, GLINT_EIO, "database %s: cannot switch to WAL journal mode",
                           dbpath);
        goto fail_db;
    }
    sqlite3_finalize(st);
    if ((rc = store_exec(s, "PRAGMA synchronous = FULL", err)) ||
        (rc = store_exec(s, "PRAGMA foreign_keys = OFF", err)) ||
        (rc = store_schema_init(s, err)))
        goto fail_db;
    store_sweep(s);
    *out = s;
    return 0;

fail_db:
    glint_err_prefix(err, "store %s", data_dir);
    sqlite3_close(s->db);
fail_paths:
    pthread_mutex_destroy(&s->cache_lock);
    pthread_mutex_destroy(&s->lock);
    free(s);
    return rc;
}

static void store_scene_free(scene *sc)
{
    scene_free(sc);
    free(sc);
}

void store_close(store *s)
{
    if (!s)
        return;
    for (int i = 0; i < STORE_SCENE_CACHE; i++)
        if (s->cache[i].sc)
            store_scene_free(s->cache[i].sc);
    sqlite3_close(s->db);
    pthread_mutex_destroy(&s->cache_lock);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

/* ------------------------------------------------------------------------ */
/* Generic id -> JSON document tables                                        */
/* ------------------------------------------------------------------------ */

/* SELECT one text column by id and parse it. */
static int store_get_doc(store *s, const char *sql, const char *id, const char *what,
                         json_t **doc, glint_err *err)
{
    sqlite3_stmt *st;
    int rc;

    *doc = NULL;
    if (!store_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no %s with id \"%.40s\"", what, id ? id : "");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, sql, err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, id, -1, SQLITE_TRANSIENT);
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        *doc = store_load((const char *)sqlite3_column_text(st, 0), what, err);
        rc = *doc ? 0 : GLINT_EFORMAT;
    } else if (rc == SQLITE_DONE) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no %s with id %s", what, id);
    } else {
        rc = store_sqlerr(s, err, "reading");
    }
out:
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->lock);
    return rc;
}

/* INSERT (id, doc, created [, extra]) with one statement. */
static int store_put_doc(store *s, const char *sql, const char *id, const json_t *doc,
                         const char *extra, glint_err *err)
{
    sqlite3_stmt *st;
    char *text;
    char now[32];
    int rc;

    if (!store_id_valid(id))
        return glint_err_set(err, GLINT_EINVAL, "invalid id \"%.40s\"", id ? id : "");
    text = store_dump(doc);
    if (!text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory serializing a document");
    store_now(now);
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, sql, err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, id, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 2, text, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 3, now, -1, SQLITE_TRANSIENT);
    if (extra)
        sqlite3_bind_text(st, 4, extra, -1, SQLITE_TRANSIENT);
    rc = sqlite3_step(st) == SQLITE_DONE ? 0 : store_sqlerr(s, err, "writing");
out:
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->lock);
    free(text);
    return rc;
}

/* ------------------------------------------------------------------------ */
/* Meshes                                                                    */
/* ------------------------------------------------------------------------ */

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
    if (!store_id_valid(id))
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

/* ------------------------------------------------------------------------ */
/* Scenes                                                                    */
/* ------------------------------------------------------------------------ */

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
    sqlite3_stmt *st;
    json_t *arr = json_array();
    int rc = 0, step;

    *array = NULL;
    if (!arr)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory listing scenes");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, "SELECT doc FROM scenes ORDER BY rowid", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    while ((step = sqlite3_step(st)) == SQLITE_ROW) {
        json_t *d = store_load((const char *)sqlite3_column_text(st, 0), "scene", err);
        if (!d || json_array_append_new(arr, d)) {
            rc = d ? glint_err_set(err, GLINT_ENOMEM, "out of memory listing scenes")
                   : GLINT_EFORMAT;
            goto out;
        }
    }
    if (step != SQLITE_DONE)
        rc = store_sqlerr(s, err, "listing scenes");
out:
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->lock);
    if (rc)
        json_decref(arr);
    else
        *array = arr;
    return rc;
}

int store_scene_delete(store *s, const char *id, glint_err *err)
{
    sqlite3_stmt *st = NULL;
    json_t *sessions = json_array();
    int rc = 0, step;
    static const char *const dels[] = {
        "DELETE FROM events WHERE session IN (SELECT id FROM sessions WHERE scene_id = ?1)",
        "DELETE FROM paintings WHERE session IN (SELECT id FROM sessions WHERE scene_id = ?1)",
        "DELETE FROM sessions WHERE scene_id = ?1",
        "DELETE FROM scenes WHERE id = ?1",
        NULL};

    if (!sessions)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory deleting a scene");
    if (!store_id_valid(id)) {
        json_decref(sessions);
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene with id \"%.40s\"", id ? id : "");
    }
    pthread_mutex_lock(&s->lock);
    if ((rc = store_exec(s, "BEGIN IMMEDIATE", err)))
        goto out;
    st = store_prep(s, "SELECT count(*) FROM scenes WHERE id = ?1", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, id, -1, SQLITE_TRANSIENT);
    if (sqlite3_step(st) != SQLITE_ROW || sqlite3_column_int(st, 0) == 0) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no scene with id %s", id);
        goto out;
    }
    sqlite3_finalize(st);
    st = store_prep(s, "SELECT id FROM sessions WHERE scene_id = ?1", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, id, -1, SQLITE_TRANSIENT);
    while ((step = sqlite3_step(st)) == SQLITE_ROW)
        json_array_append_new(sessions, json_string((const char *)sqlite3_column_text(st, 0)));
    if (step != SQLITE_DONE) {
        rc = store_sqlerr(s, err, "deleting a scene");
        goto out;
    }
    for (int i = 0; dels[i]; i++) {
        sqlite3_finalize(st);
        st = store_prep(s, dels[i], err);
        if (!st) {
            rc = GLINT_EIO;
            goto out;
        }
        sqlite3_bind_text(st, 1, id, -1, SQLITE_TRANSIENT);
        if (sqlite3_step(st) != SQLITE_DONE) {
            rc = store_sqlerr(s, err, "deleting a scene");
            goto out;
        }
    }
    rc = store_exec(s, "COMMIT", err);
out:
    sqlite3_finalize(st);
    if (rc)
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    if (!rc) {
        char name[128];
        pthread_mutex_lock(&s->cache_lock);
        for (int i = 0; i < STORE_SCENE_CACHE; i++) {
            store_cached *c = &s->cache[i];
            if (c->sc && !c->dead && strcmp(c->id, id) == 0) {
                if (c->refs == 0) {
                    store_scene_free(c->sc);
                    memset(c, 0, sizeof *c);
                } else {
                    c->dead = 1;
                }
            }
        }
        pthread_mutex_unlock(&s->cache_lock);
        size_t i;
        json_t *v;
        snprintf(name, sizeof name, "scenes/%s", id);
        store_blob_rmtree(s, name);
        json_array_foreach(sessions, i, v) {
            snprintf(name, sizeof name, "sessions/%s", json_string_value(v));
            store_blob_rmtree(s, name);
        }
    }
    json_decref(sessions);
    return rc;
}

/* Load the core scene of a stored scene (uncached). */
static int store_scene_load(store *s, const char *id, scene **out, glint_err *err)
{
    json_t *doc = NULL, *js = NULL;
    const char *mesh_id;
    char *text = NULL;
    void *data = NULL;
    size_t len = 0;
    char format[16];
    scene *sc;
    int rc;

    *out = NULL;
    sc = calloc(1, sizeof *sc);
    if (!sc)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory loading a scene");
    if ((rc = store_scene_get(s, id, &doc, err)))
        goto done;
    js = json_deep_copy(json_object_get(doc, "scene"));
    if (!json_is_object(js)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene %s: stored document has no scene", id);
        goto done;
    }
    mesh_id = json_string_value(json_object_get(doc, "mesh_id"));
    /* An uploaded mesh is not a built-in: parse the views with a stand-in
     * built-in (a few ms), then put the uploaded mesh in its place. */
    if (mesh_id)
        json_object_set_new(js, "mesh", json_string("sphere"));
    text = json_dumps(js, JSON_COMPACT | JSON_REAL_PRECISION(17));
    if (!text) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory loading a scene");
        goto done;
    }
    if ((rc = scene_from_json(text, sc, err)))
        goto done;
    if (mesh_id) {
        mesh_free(&sc->mesh);
        if ((rc = store_mesh_data(s, mesh_id, &data, &len, format, err)) ||
            (rc = mesh_load_mem(data, len, format, &sc->mesh, &sc->mesh_info, err))) {
            glint_err_prefix(err, "scene %s: mesh %s", id, mesh_id);
            goto done;
        }
        snprintf(sc->mesh_name, sizeof sc->mesh_name, "upload:%s", mesh_id);
        if ((rc = scene_validate(sc, err)))
            goto done;
    }
done:
    free(data);
    free(text);
    json_decref(js);
    json_decref(doc);
    if (rc)
        store_scene_free(sc);
    else
        *out = sc;
    return rc;
}

int store_scene_acquire(store *s, const char *id, const scene **out, glint_err *err)
{
    scene *sc = NULL;
    store_cached *slot = NULL;
    int rc;

    *out = NULL;
    pthread_mutex_lock(&s->cache_lock);
    for (int i = 0; i < STORE_SCENE_CACHE; i++) {
        store_cached *c = &s->cache[i];
        if (c->sc && !c->dead && strcmp(c->id, id ? id : "") == 0) {
            c->refs++;
            c->used = ++s->tick;
            *out = c->sc;
            pthread_mutex_unlock(&s->cache_lock);
            return 0;
        }
    }
    pthread_mutex_unlock(&s->cache_lock);

    if ((rc = store_scene_load(s, id, &sc, err)))
        return rc;

    pthread_mutex_lock(&s->cache_lock);
    for (int i = 0; i < STORE_SCENE_CACHE; i++) {
        store_cached *c = &s->cache[i];
        if (c->sc && !c->dead && strcmp(c->id, id) == 0) {
            /* loaded by another request meanwhile: use that one */
            c->refs++;
            c->used = ++s->tick;
            *out = c->sc;
            pthread_mutex_unlock(&s->cache_lock);
            store_scene_free(sc);
            return 0;
        }
        if (!c->sc) {
            if (!slot || slot->sc)
                slot = c;
        } else if (c->refs == 0 && (!slot || (slot->sc && c->used < slot->used))) {
            slot = c;
        }
    }
    if (slot) {
        if (slot->sc)
            store_scene_free(slot->sc);
        memset(slot, 0, sizeof *slot);
        snprintf(slot->id, sizeof slot->id, "%s", id);
        slot->sc = sc;
        slot->refs = 1;
        slot->used = ++s->tick;
    }
    /* no free slot: the scene is handed out uncached, freed at release */
    pthread_mutex_unlock(&s->cache_lock);
    *out = sc;
    return 0;
}

void store_scene_release(store *s, const scene *sc)
{
    if (!sc)
        return;
    pthread_mutex_lock(&s->cache_lock);
    for (int i = 0; i < STORE_SCENE_CACHE; i++) {
        store_cached *c = &s->cache[i];
        if (c->sc == sc) {
            if (--c->refs == 0 && c->dead) {
                store_scene_free(c->sc);
                memset(c, 0, sizeof *c);
            }
            pthread_mutex_unlock(&s->cache_lock);
            return;
        }
    }
    pthread_mutex_unlock(&s->cache_lock);
    store_scene_free((scene *)sc);
}

int store_scene_base(store *s, const char *id, int view, img *out, glint_err *err)
{
    char name[128];
    void *data = NULL;
    size_t len = 0;
    json_t *doc = NULL;
    const scene *sc = NULL;
    gbuf g;
    brdf b;
    double scale;
    const char *spec;
    int rc;

    memset(out, 0, sizeof *out);
    memset(&g, 0, sizeof g);
    if (!store_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene with id \"%.40s\"", id ? id : "");
    snprintf(name, sizeof name, "scenes/%s/base%d.exr", id, view);
    if (view >= 0 && store_blob_get(s, name, &data, &len, NULL) == 0) {
        rc = img_read_mem(data, len, out, NULL);
        free(data);
        data = NULL;
        if (rc == 0 && out->channels == 3)
            return 0;
        img_free(out); /* unreadable cache file: render again */
    }
    if ((rc = store_scene_get(s, id, &doc, err)) || (rc = store_scene_acquire(s, id, &sc, err)))
        goto done;
    if (view < 0 || view >= sc->nviews) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "scene %s has no view %d (views 0..%d)", id, view,
                           sc->nviews - 1);
        goto done;
    }
    spec = json_string_value(json_object_get(json_object_get(doc, "base"), "brdf"));
    scale = json_number_value(json_object_get(json_object_get(doc, "base"), "scale"));
    if (!spec || !(scale > 0.0)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene %s: stored document has no base brdf/scale",
                           id);
        goto done;
    }
    if ((rc = brdf_parse(spec, &b, err)) ||
        (rc = raster_view(&sc->mesh, &sc->views[view], sc->width, sc->height, &g, err)) ||
        (rc = paint_views(&b, &g, &sc->views[view], 1, scale, out, NULL, err)))
        goto done;
    if (img_write_mem("exr", out, &data, &len, NULL) == 0)
        store_blob_put(s, name, data, len, NULL); /* a cache: failure only costs time */
done:
    free(data);
    gbuf_free(&g);
    store_scene_release(s, sc);
    json_decref(doc);
    if (rc)
        img_free(out);
    return rc;
}

/* ------------------------------------------------------------------------ */
/* Sessions                                                                  */
/* ------------------------------------------------------------------------ */

int store_session_put(store *s, const char *id, const json_t *doc, glint_err *err)
{
    const char *scene_id = json_string_value(json_object_get(doc, "scene_id"));
    sqlite3_stmt *st;
    char *text = NULL;
    char now[32];
    int rc;

    if (!store_id_valid(id))
        return glint_err_set(err, GLINT_EINVAL, "invalid session id \"%.40s\"", id ? id : "");
    if (!store_id_valid(scene_id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene with id \"%.40s\"",
                             scene_id ? scene_id : "");
    text = store_dump(doc);
    if (!text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory serializing a session");
    store_now(now);
    pthread_mutex_lock(&s->lock);
    /* one statement: the session exists only if its scene does */
    st = store_prep(s, "INSERT INTO sessions (id, scene_id, doc, created) SELECT ?1, ?2, ?3, ?4 "
                       "WHERE EXISTS (SELECT 1 FROM scenes WHERE id = ?2)", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, id, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 2, scene_id, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 3, text, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 4, now, -1, SQLITE_TRANSIENT);
    if (sqlite3_step(st) != SQLITE_DONE)
        rc = store_sqlerr(s, err, "creating a session");
    else if (sqlite3_changes(s->db) == 0)
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no scene with id %s", scene_id);
    else
        rc = 0;
out:
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->lock);
    free(text);
    return rc;
}

int store_session_get(store *s, const char *id, json_t **doc, glint_err *err)
{
    sqlite3_stmt *st;
    int rc;

    *doc = NULL;
    if (!store_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"", id ? id : "");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, "SELECT doc, last_seq FROM sessions WHERE id = ?1", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, id, -1, SQLITE_TRANSIENT);
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        *doc = store_load((const char *)sqlite3_column_text(st, 0), "session", err);
        if (*doc) {
            json_object_set_new(*doc, "last_seq", json_integer(sqlite3_column_int64(st, 1)));
            rc = 0;
        } else {
            rc = GLINT_EFORMAT;
        }
    } else if (rc == SQLITE_DONE) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no session with id %s", id);
    } else {
        rc = store_sqlerr(s, err, "reading a session");
    }
out:
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->lock);
    return rc;
}

/* Inside a transaction: the session's last_seq (GLINT_ENOTFOUND if none). */
static int store_tx_last_seq(store *s, const char *session, int64_t *last, glint_err *err)
{
    sqlite3_stmt *st = store_prep(s, "SELECT last_seq FROM sessions WHERE id = ?1", err);
    int rc;
    if (!st)
        return GLINT_EIO;
    sqlite3_bind_text(st, 1, session, -1, SQLITE_TRANSIENT);
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        *last = sqlite3_column_int64(st, 0);
        rc = 0;
    } else if (rc == SQLITE_DONE) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "no session with id %s", session);
    } else {
        rc = store_sqlerr(s, err, "reading a session");
    }
    sqlite3_finalize(st);
    return rc;
}

static int store_tx_set_last_seq(store *s, const char *session, int64_t last, glint_err *err)
{
    sqlite3_stmt *st = store_prep(s, "UPDATE sessions SET last_seq = ?2 WHERE id = ?1", err);
    int rc;
    if (!st)
        return GLINT_EIO;
    sqlite3_bind_text(st, 1, session, -1, SQLITE_TRANSIENT);
    sqlite3_bind_int64(st, 2, last);
    rc = sqlite3_step(st) == SQLITE_DONE ? 0 : store_sqlerr(s, err, "numbering");
    sqlite3_finalize(st);
    return rc;
}

/* Inside a transaction: insert one event row (data: JSON text). */
static int store_tx_event(store *s, sqlite3_stmt *st, const char *session, int64_t seq,
                          const char *type, int view, const char *data, const char *now,
                          glint_err *err)
{
    sqlite3_reset(st);
    sqlite3_bind_text(st, 1, session, -1, SQLITE_TRANSIENT);
    sqlite3_bind_int64(st, 2, seq);
    sqlite3_bind_text(st, 3, type, -1, SQLITE_TRANSIENT);
    if (view >= 0)
        sqlite3_bind_int(st, 4, view);
    else
        sqlite3_bind_null(st, 4);
    sqlite3_bind_text(st, 5, data, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 6, now, -1, SQLITE_TRANSIENT);
    return sqlite3_step(st) == SQLITE_DONE ? 0 : store_sqlerr(s, err, "appending an event");
}

static const char store_sql_event[] =
    "INSERT INTO events (session, seq, type, view, data, created) VALUES (?1, ?2, ?3, ?4, ?5, ?6)";

/* Inside a transaction: replace the painting row; OUT: *version, the old
 * blob name in old[] ("" if none). */
static int store_tx_painting(store *s, const char *session, int view, const char *blob,
                             const char *now, int64_t *version, char *old, size_t oldlen,
                             glint_err *err)
{
    sqlite3_stmt *st = store_prep(s, "SELECT version, blob FROM paintings WHERE session = ?1 "
                                     "AND view = ?2", err);
    int64_t v = 0;
    int rc;

    old[0] = '\0';
    if (!st)
        return GLINT_EIO;
    sqlite3_bind_text(st, 1, session, -1, SQLITE_TRANSIENT);
    sqlite3_bind_int(st, 2, view);
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        v = sqlite3_column_int64(st, 0);
        snprintf(old, oldlen, "%s", (const char *)sqlite3_column_text(st, 1));
    } else if (rc != SQLITE_DONE) {
        sqlite3_finalize(st);
        return store_sqlerr(s, err, "reading a painting");
    }
    sqlite3_finalize(st);
    st = store_prep(s, "INSERT OR REPLACE INTO paintings (session, view, version, blob, updated) "
                       "VALUES (?1, ?2, ?3, ?4, ?5)", err);
    if (!st)
        return GLINT_EIO;
    sqlite3_bind_text(st, 1, session, -1, SQLITE_TRANSIENT);
    sqlite3_bind_int(st, 2, view);
    sqlite3_bind_int64(st, 3, v + 1);
    sqlite3_bind_text(st, 4, blob, -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(st, 5, now, -1, SQLITE_TRANSIENT);
    rc = sqlite3_step(st) == SQLITE_DONE ? 0 : store_sqlerr(s, err, "writing a painting");
    sqlite3_finalize(st);
    *version = v + 1;
    return rc;
}

/* Write a new painting blob for (session, view) (OUT: name). */
static int store_painting_blob(store *s, const char *session, int view, const void *exr,
                               size_t len, char *name, size_t namelen, glint_err *err)
{
    char prefix[96];
    int rc;
    if (!store_id_valid(session))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"", session);
    if (view < 0)
        return glint_err_set(err, GLINT_EINVAL, "view %d is negative", view);
    snprintf(prefix, sizeof prefix, "sessions/%s/view%d-", session, view);
    if ((rc = store_random_name(name, namelen, prefix, ".exr", err)))
        return rc;
    return store_blob_put(s, name, exr, len, err);
}

int store_painting_put(store *s, const char *session, int view, const void *exr, size_t len,
                       int64_t *version, int64_t *seq, glint_err *err)
{
    char blob[160], old[160], now[32], data[64];
    sqlite3_stmt *st = NULL;
    int64_t last = 0, v = 0;
    int rc;

    rc = store_painting_blob(s, session, view, exr, len, blob, sizeof blob, err);
    if (rc)
        return rc;
    store_now(now);
    pthread_mutex_lock(&s->lock);
    if ((rc = store_exec(s, "BEGIN IMMEDIATE", err)) ||
        (rc = store_tx_last_seq(s, session, &last, err)) ||
        (rc = store_tx_painting(s, session, view, blob, now, &v, old, sizeof old, err)))
        goto out;
    st = store_prep(s, store_sql_event, err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    snprintf(data, sizeof data, "{\"view\":%d,\"version\":%lld}", view, (long long)v);
    if ((rc = store_tx_event(s, st, session, last + 1, "painting", view, data, now, err)) ||
        (rc = store_tx_set_last_seq(s, session, last + 1, err)) ||
        (rc = store_exec(s, "COMMIT", err)))
        goto out;
out:
    sqlite3_finalize(st);
    if (rc)
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    if (rc) {
        store_blob_delete(s, blob, NULL);
        return rc;
    }
    if (old[0])
        store_blob_delete(s, old, NULL);
    if (version)
        *version = v;
    if (seq)
        *seq = last + 1;
    return 0;
}

int store_painting_get(store *s, const char *session, int view, void **exr, size_t *len,
                       int64_t *version, glint_err *err)
{
    sqlite3_stmt *st;
    int rc;

    *exr = NULL;
    if (!store_id_valid(session))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"", session);
    /* under the lock, so a concurrent put cannot remove the file between
     * reading its name and reading it */
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, "SELECT version, blob FROM paintings WHERE session = ?1 AND view = ?2",
                    err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, session, -1, SQLITE_TRANSIENT);
    sqlite3_bind_int(st, 2, view);
    rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        if (version)
            *version = sqlite3_column_int64(st, 0);
        rc = store_blob_get(s, (const char *)sqlite3_column_text(st, 1), exr, len, err);
        if (rc == GLINT_ENOTFOUND) /* a row without its file: never acceptable */
            rc = glint_err_set(err, GLINT_EIO, "painting of session %s view %d: file missing",
                               session, view);
    } else if (rc == SQLITE_DONE) {
        rc = glint_err_set(err, GLINT_ENOTFOUND, "view %d of session %s has no painting", view,
                           session);
    } else {
        rc = store_sqlerr(s, err, "reading a painting");
    }
out:
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->lock);
    return rc;
}

int store_paintings_list(store *s, const char *session, json_t **array, glint_err *err)
{
    sqlite3_stmt *st;
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
    sqlite3_bind_text(st, 1, session ? session : "", -1, SQLITE_TRANSIENT);
    while ((step = sqlite3_step(st)) == SQLITE_ROW)
        json_array_append_new(arr, json_pack("{s:i, s:I, s:s}", "view", sqlite3_column_int(st, 0),
                                             "version", (json_int_t)sqlite3_column_int64(st, 1),
                                             "updated",
                                             (const char *)sqlite3_column_text(st, 2)));
    if (step != SQLITE_DONE)
        rc = store_sqlerr(s, err, "listing paintings");
out:
    sqlite3_finalize(st);
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
    char blob[160], old[160], now[32];
    sqlite3_stmt *st = NULL;
    int64_t last = 0, v = 0;
    size_t n = json_array_size(strokes), i;
    char **texts;
    int rc = 0;

    if (!json_is_array(strokes) || n == 0)
        return glint_err_set(err, GLINT_EINVAL, "store_strokes_append: no strokes");
    texts = calloc(n, sizeof *texts);
    if (!texts)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu strokes", n);
    for (i = 0; i < n; i++)
        if (!(texts[i] = store_dump(json_array_get(strokes, i)))) {
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory serializing strokes");
            goto free_texts;
        }
    rc = store_painting_blob(s, session, view, exr, len, blob, sizeof blob, err);
    if (rc)
        goto free_texts;
    store_now(now);
    pthread_mutex_lock(&s->lock);
    if ((rc = store_exec(s, "BEGIN IMMEDIATE", err)) ||
        (rc = store_tx_last_seq(s, session, &last, err)) ||
        (rc = store_tx_painting(s, session, view, blob, now, &v, old, sizeof old, err)))
        goto out;
    st = store_prep(s, store_sql_event, err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    for (i = 0; i < n; i++)
        if ((rc = store_tx_event(s, st, session, last + 1 + (int64_t)i, "stroke", view, texts[i],
                                 now, err)))
            goto out;
    if ((rc = store_tx_set_last_seq(s, session, last + (int64_t)n, err)) ||
        (rc = store_exec(s, "COMMIT", err)))
        goto out;
out:
    sqlite3_finalize(st);
    if (rc)
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    if (rc) {
        store_blob_delete(s, blob, NULL);
    } else {
        if (old[0])
            store_blob_delete(s, old, NULL);
        if (first_seq)
            *first_seq = last + 1;
        if (last_seq)
            *last_seq = last + (int64_t)n;
        if (version)
            *version = v;
    }
free_texts:
    for (i = 0; i < n; i++)
        free(texts[i]);
    free(texts);
    return rc;
}

int store_event_append(store *s, const char *session, const char *type, int view,
                       const json_t *data, int64_t *seq, glint_err *err)
{
    char now[32];
    char *text;
    sqlite3_stmt *st = NULL;
    int64_t last = 0;
    int rc;

    if (!store_id_valid(session))
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"",
                             session ? session : "");
    if (!type || !*type || strlen(type) > 32 || !strcmp(type, "stroke") ||
        !strcmp(type, "painting"))
        return glint_err_set(err, GLINT_EINVAL, "event type \"%.40s\" cannot be appended here",
                             type ? type : "");
    text = json_is_object(data) ? store_dump(data) : NULL;
    if (!text)
        return glint_err_set(err, GLINT_EINVAL, "event data must be a JSON object");
    store_now(now);
    pthread_mutex_lock(&s->lock);
    if ((rc = store_exec(s, "BEGIN IMMEDIATE", err)) ||
        (rc = store_tx_last_seq(s, session, &last, err)))
        goto out;
    st = store_prep(s, store_sql_event, err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    if ((rc = store_tx_event(s, st, session, last + 1, type, view, text, now, err)) ||
        (rc = store_tx_set_last_seq(s, session, last + 1, err)) ||
        (rc = store_exec(s, "COMMIT", err)))
        goto out;
out:
    sqlite3_finalize(st);
    if (rc)
        store_rollback(s);
    pthread_mutex_unlock(&s->lock);
    free(text);
    if (!rc && seq)
        *seq = last + 1;
    return rc;
}

/* Rows of the event log after `since` (only strokes when strokes_only),
 * at most `limit` (<= 0: no limit).  as_stroke: records shaped
 * {"seq","view","stroke","created"}, else {"seq","type","view","data","created"}. */
static int store_log_read(store *s, const char *session, int64_t since, int limit,
                          int strokes_only, json_t **array, int *more, int64_t *last_seq,
                          glint_err *err)
{
    sqlite3_stmt *st = NULL;
    json_t *arr = json_array();
    int rc = 0, step, count = 0;

    *array = NULL;
    if (more)
        *more = 0;
    if (!arr)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory reading events");
    if (!store_id_valid(session)) {
        json_decref(arr);
        return glint_err_set(err, GLINT_ENOTFOUND, "no session with id \"%.40s\"",
                             session ? session : "");
    }
    pthread_mutex_lock(&s->lock);
    /* one read transaction: the rows and last_seq agree */
    if ((rc = store_exec(s, "BEGIN", err)))
        goto out;
    if (last_seq && (rc = store_tx_last_seq(s, session, last_seq, err)))
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
    sqlite3_bind_text(st, 1, session, -1, SQLITE_TRANSIENT);
    sqlite3_bind_int64(st, 2, since);
    sqlite3_bind_int64(st, 3, limit > 0 ? (int64_t)limit + 1 : -1);
    while ((step = sqlite3_step(st)) == SQLITE_ROW) {
        json_t *data, *rec;
        if (limit > 0 && count == limit) {
            if (more)
                *more = 1;
            break;
        }
        data = store_load((const char *)sqlite3_column_text(st, 3), "event", err);
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
        json_object_set_new(rec, "seq", json_integer(sqlite3_column_int64(st, 0)));
        if (!strokes_only)
            json_object_set_new(rec, "type", json_string((const char *)sqlite3_column_text(st, 1)));
        if (sqlite3_column_type(st, 2) != SQLITE_NULL)
            json_object_set_new(rec, "view", json_integer(sqlite3_column_int(st, 2)));
        json_object_set_new(rec, strokes_only ? "stroke" : "data", data);
        json_object_set_new(rec, "created", json_string((const char *)sqlite3_column_text(st, 4)));
        json_array_append_new(arr, rec);
        count++;
    }
    if (step != SQLITE_DONE && step != SQLITE_ROW)
        rc = store_sqlerr(s, err, "reading events");
out:
    sqlite3_finalize(st);
    if (!sqlite3_get_autocommit(s->db))
        sqlite3_exec(s->db, rc ? "ROLLBACK" : "COMMIT", NULL, NULL, NULL);
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
    return store_log_read(s, session, since, 0, 1, array, NULL, NULL, err);
}

int store_strokes_page(store *s, const char *session, int64_t since, int limit, json_t **array,
                       int *more, int64_t *last_seq, glint_err *err)
{
    int m = 0;
    int64_t last = 0;
    int rc = store_log_read(s, session, since, limit, 1, array, &m, &last, err);
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
    return store_log_read(s, session, since, limit, 0, array, NULL, last_seq, err);
}

/* ------------------------------------------------------------------------ */
/* Materials                                                                 */
/* ------------------------------------------------------------------------ */

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
    sqlite3_stmt *st;
    json_t *arr = json_array();
    int rc = 0, step;

    *array = NULL;
    if (!arr)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory listing materials");
    pthread_mutex_lock(&s->lock);
    st = store_prep(s, "SELECT doc FROM materials WHERE session = ?1 ORDER BY rowid", err);
    if (!st) {
        rc = GLINT_EIO;
        goto out;
    }
    sqlite3_bind_text(st, 1, session ? session : "", -1, SQLITE_TRANSIENT);
    while ((step = sqlite3_step(st)) == SQLITE_ROW) {
        json_t *d = store_load((const char *)sqlite3_column_text(st, 0), "material", err);
        if (!d) {
            rc = GLINT_EFORMAT;
            goto out;
        }
        json_array_append_new(arr, d);
    }
    if (step != SQLITE_DONE)
        rc = store_sqlerr(s, err, "listing materials");
out:
    sqlite3_finalize(st);
    pthread_mutex_unlock(&s->lock);
    if (rc)
        json_decref(arr);
    else
        *array = arr;
    return rc;
}
