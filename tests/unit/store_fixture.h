/* store_fixture.h: the fixture of the tests of glintd's store
 * (test_store.c, test_store_log.c): a store in a fresh temporary directory
 * with one scene and one session, a look at the database through a
 * connection of our own, and two images' bytes.
 *
 * The same tests run on both engines: with GLINT_TEST_PG set (a libpq
 * connection string to a PostgreSQL server the test command started,
 * tests/with_postgres.sh), every fixture gets a fresh database of its own
 * on that server; without it, SQLite in the fixture's directory. */
#ifndef GLINT_STORE_FIXTURE_H
#define GLINT_STORE_FIXTURE_H

#include <libpq-fe.h>
#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "ids.h"
#include "store.h"

/* ---- fixture: a store with one scene and one session ---------------------- */

typedef struct fixture {
    char dir[64];
    char db[1024]; /* PostgreSQL connection string, "" for SQLite */
    store *s;
    char scene[33], session[33];
} fixture;

static inline int fx_pg(const fixture *f)
{
    return f->db[0] != '\0';
}

/* One statement on the PostgreSQL server at conninfo (0 or -1). */
static inline int fx_pg_exec(const char *conninfo, const char *sql)
{
    PGconn *c = PQconnectdb(conninfo);
    PGresult *r;
    int ok;
    if (PQstatus(c) != CONNECTION_OK) {
        fprintf(stderr, "  PostgreSQL: %s", PQerrorMessage(c));
        PQfinish(c);
        return -1;
    }
    r = PQexec(c, sql);
    ok = PQresultStatus(r) == PGRES_COMMAND_OK || PQresultStatus(r) == PGRES_TUPLES_OK;
    if (!ok)
        fprintf(stderr, "  PostgreSQL: %s: %s", sql, PQresultErrorMessage(r));
    PQclear(r);
    PQfinish(c);
    return ok ? 0 : -1;
}

/* A fresh directory and, on PostgreSQL, a fresh database named after it. */
static inline int fx_mkdir(fixture *f)
{
    const char *pg = getenv("GLINT_TEST_PG");
    char sql[128];
    snprintf(f->dir, sizeof f->dir, "/tmp/glint-store-XXXXXX");
    f->db[0] = '\0';
    if (!mkdtemp(f->dir))
        return -1;
    if (!pg || !*pg)
        return 0;
    snprintf(sql, sizeof sql, "CREATE DATABASE \"fx_%s\"", f->dir + strlen("/tmp/glint-store-"));
    if (fx_pg_exec(pg, sql))
        return -1;
    snprintf(f->db, sizeof f->db, "%s dbname=fx_%s", pg, f->dir + strlen("/tmp/glint-store-"));
    return 0;
}

/* store_open on the fixture's engine. */
static inline int fx_store_open(fixture *f, store **s, glint_err *e)
{
    return store_open_db(f->dir, fx_pg(f) ? f->db : NULL, s, e);
}

/* A scene document and a session on it (the documents the API stores). */
static inline int fx_scene(store *s, char id[33])
{
    json_t *doc;
    int rc = glint_id_new(id, NULL);
    if (rc)
        return rc;
    doc = json_pack("{s:s, s:{s:i}}", "id", id, "scene", "width", 64);
    rc = store_scene_put(s, id, doc, NULL);
    json_decref(doc);
    return rc;
}

static inline int fx_session(store *s, const char *scene, char id[33])
{
    json_t *doc;
    int rc = glint_id_new(id, NULL);
    if (rc)
        return rc;
    doc = json_pack("{s:s, s:s, s:s, s:s}", "id", id, "scene_id", scene, "paint_token",
                    "p0", "view_token", "v0");
    rc = store_session_put(s, id, doc, NULL);
    json_decref(doc);
    return rc;
}

static inline int fx_open(fixture *f)
{
    int rc;
    if (fx_mkdir(f))
        return -1;
    if ((rc = fx_store_open(f, &f->s, NULL)) || (rc = fx_scene(f->s, f->scene)) ||
        (rc = fx_session(f->s, f->scene, f->session)))
        return rc;
    return 0;
}

static inline void fx_close(fixture *f)
{
    char cmd[128];
    store_close(f->s);
    f->s = NULL;
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", f->dir);
    if (system(cmd) != 0)
        fprintf(stderr, "  could not remove %s\n", f->dir);
}

/* One integer from the database through a connection of our own (-1 when
 * the query fails). */
static inline long long db_int(const fixture *f, const char *sql)
{
    char path[256];
    sqlite3 *db = NULL;
    sqlite3_stmt *st = NULL;
    long long v = -1;
    if (fx_pg(f)) {
        PGconn *c = PQconnectdb(f->db);
        PGresult *r = PQstatus(c) == CONNECTION_OK ? PQexec(c, sql) : NULL;
        if (PQresultStatus(r) == PGRES_TUPLES_OK && PQntuples(r) == 1 && !PQgetisnull(r, 0, 0))
            v = strtoll(PQgetvalue(r, 0, 0), NULL, 10);
        PQclear(r);
        PQfinish(c);
        return v;
    }
    snprintf(path, sizeof path, "%s/glint.db", f->dir);
    if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
        sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
        v = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(db);
    return v;
}


/* Run SQL on the fixture's database through a connection of our own (0 or
 * nonzero). */
static inline int fx_sql(const fixture *f, const char *sql)
{
    char path[256];
    sqlite3 *db = NULL;
    int rc;
    if (fx_pg(f))
        return fx_pg_exec(f->db, sql);
    snprintf(path, sizeof path, "%s/glint.db", f->dir);
    rc = sqlite3_open_v2(path, &db, SQLITE_OPEN_READWRITE, NULL);
    if (rc == SQLITE_OK)
        rc = sqlite3_exec(db, sql, NULL, NULL, NULL);
    sqlite3_close(db);
    return rc;
}

/* Every file and directory under blobs/ made older than the sweep's grace
 * for shared blob directories (0 or nonzero). */
static inline int fx_age_blobs(const fixture *f)
{
    char cmd[256];
    snprintf(cmd, sizeof cmd, "find '%s/blobs' -exec touch -h -d @%lld {} +", f->dir,
             (long long)time(NULL) - 2 * STORE_SHARED_SWEEP_GRACE);
    return system(cmd);
}

static inline int path_exists(const char *dir, const char *rel)
{
    char path[8192];
    struct stat st;
    snprintf(path, sizeof path, "%s/%s", dir, rel);
    return stat(path, &st) == 0;
}

static const char exr1[] = "not really an EXR, the store never decodes";
static const char exr2[] = "the second image of the view";

#endif
