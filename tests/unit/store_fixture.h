/* store_fixture.h: the fixture of the tests of glintd's store
 * (test_store.c, test_store_log.c): a store in a fresh temporary directory
 * with one scene and one session, a look at the database file through a
 * connection of our own, and two images' bytes. */
#ifndef GLINT_STORE_FIXTURE_H
#define GLINT_STORE_FIXTURE_H

#include <sqlite3.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ids.h"
#include "store.h"

/* ---- fixture: a store with one scene and one session ---------------------- */

typedef struct fixture {
    char dir[64];
    store *s;
    char scene[33], session[33];
} fixture;

static inline int fx_mkdir(fixture *f)
{
    snprintf(f->dir, sizeof f->dir, "/tmp/glint-store-XXXXXX");
    return mkdtemp(f->dir) ? 0 : -1;
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
    if ((rc = store_open(f->dir, &f->s, NULL)) || (rc = fx_scene(f->s, f->scene)) ||
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

/* One integer from the database file through a connection of our own
 * (-1 when the query fails). */
static inline long long db_int(const char *dir, const char *sql)
{
    char path[256];
    sqlite3 *db = NULL;
    sqlite3_stmt *st = NULL;
    long long v = -1;
    snprintf(path, sizeof path, "%s/glint.db", dir);
    if (sqlite3_open_v2(path, &db, SQLITE_OPEN_READONLY, NULL) == SQLITE_OK &&
        sqlite3_prepare_v2(db, sql, -1, &st, NULL) == SQLITE_OK && sqlite3_step(st) == SQLITE_ROW)
        v = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    sqlite3_close(db);
    return v;
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
