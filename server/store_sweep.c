/* store_sweep.c: what a crash can leave under blobs/, removed when the
 * store opens (before anyone writes).  Every write puts its files first and
 * its row (or record) last, and every deletion removes the row first, so a
 * crash between the steps leaves files nothing names, never a row naming
 * nothing:
 *   - a temporary file of an interrupted atomic write (fsio.h: "*.tmp-*");
 *   - materials/<id>/ or scenes/<id>/ without its row (a fit or a scene
 *     killed before the insert; a scene deletion killed after its commit);
 *   - meshes/<id>.<format> without its row;
 *   - environments/<id>.exr|hdr without its record <id>.json (an upload
 *     killed before the record, a deletion after it), or a record whose
 *     map is gone;
 *   - sessions/<id>/<file> that no painting row names (store_log.c);
 *   - gbuffer-sets/<id>/ without its record set.json (a deletion killed
 *     after removing the record; api_gbuffers.c).
 * Names that are not glint's (no id) are left alone. */
#include <dirent.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "ids.h"
#include "store_int.h"

/* Does table `table` have a row with this id? (-1: cannot tell) */
static int has_row(store *s, const char *table, const char *id)
{
    char sql[96];
    db_stmt *st;
    int r;
    snprintf(sql, sizeof sql, "SELECT 1 FROM %s WHERE id = ?1", table);
    if (!(st = store_prep(s, sql, NULL)))
        return -1;
    db_bind_text(st, 1, id);
    r = db_step(st, "sweeping", NULL);
    db_finalize(st);
    return r == DB_ROW ? 1 : r == DB_DONE ? 0 : -1;
}

int store_sweepable(const store *s, const char *path)
{
    struct stat st;
    if (!s->sweep_grace)
        return 1;
    if (lstat(path, &st))
        return 0;
    return time(NULL) - st.st_mtime >= s->sweep_grace;
}

/* The id at the start of a file name ("<id>.<ext>"), or 0. */
static int id_stem(const char *name, char id[GLINT_ID_LEN])
{
    const char *dot = strchr(name, '.');
    size_t n = dot ? (size_t)(dot - name) : strlen(name);
    if (n != GLINT_ID_LEN - 1)
        return 0;
    memcpy(id, name, n);
    id[n] = '\0';
    return glint_id_valid(id);
}

/* Remove temporary files of interrupted atomic writes, at any depth. */
static void sweep_tmp(const store *s, const char *dir, int depth)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    if (!d)
        return;
    while ((e = readdir(d))) {
        char path[STORE_PATH_MAX];
        struct stat st;
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        if (snprintf(path, sizeof path, "%s/%s", dir, e->d_name) >= (int)sizeof path ||
            lstat(path, &st))
            continue;
        if (S_ISDIR(st.st_mode)) {
            if (depth < 4)
                sweep_tmp(s, path, depth + 1);
        } else if (S_ISREG(st.st_mode) && strstr(e->d_name, ".tmp-") &&
                   store_sweepable(s, path)) {
            unlink(path);
        }
    }
    closedir(d);
}

/* Entries of blobs/<kind> whose id has no row in `table`. */
static void sweep_rows(store *s, const char *kind, const char *table)
{
    char dir[STORE_PATH_MAX], id[GLINT_ID_LEN];
    DIR *d;
    struct dirent *e;
    if (snprintf(dir, sizeof dir, "%s/%s", s->blobs, kind) >= (int)sizeof dir ||
        !(d = opendir(dir)))
        return;
    while ((e = readdir(d))) {
        char name[STORE_PATH_MAX], path[STORE_PATH_MAX];
        if (!id_stem(e->d_name, id) || has_row(s, table, id) != 0 ||
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name) >= (int)sizeof path ||
            !store_sweepable(s, path))
            continue;
        snprintf(name, sizeof name, "%s/%s", kind, e->d_name);
        store_blob_rmtree(s, name);
    }
    closedir(d);
}

/* Is there a file dir/<id><ext>? */
static int env_file(const char *dir, const char *id, const char *ext)
{
    char path[STORE_PATH_MAX];
    struct stat st;
    if (snprintf(path, sizeof path, "%s/%s%s", dir, id, ext) >= (int)sizeof path)
        return 1; /* cannot tell: keep */
    return stat(path, &st) == 0;
}

/* Environment maps without their record, records without their map. */
static void sweep_envs(store *s)
{
    char dir[STORE_PATH_MAX], id[GLINT_ID_LEN];
    DIR *d;
    struct dirent *e;
    if (snprintf(dir, sizeof dir, "%s/environments", s->blobs) >= (int)sizeof dir ||
        !(d = opendir(dir)))
        return;
    while ((e = readdir(d))) {
        char path[STORE_PATH_MAX];
        const char *ext;
        int orphan;
        if (!id_stem(e->d_name, id) || strstr(e->d_name, ".tmp-") ||
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name) >= (int)sizeof path)
            continue;
        ext = e->d_name + GLINT_ID_LEN - 1;
        if (!strcmp(ext, ".json"))
            orphan = !env_file(dir, id, ".exr") && !env_file(dir, id, ".hdr");
        else if (!strcmp(ext, ".exr") || !strcmp(ext, ".hdr"))
            orphan = !env_file(dir, id, ".json");
        else
            orphan = 0;
        if (orphan && store_sweepable(s, path))
            unlink(path);
    }
    closedir(d);
}

/* G-buffer sets whose record is gone. */
static void sweep_gbuffer_sets(store *s)
{
    char dir[STORE_PATH_MAX], id[GLINT_ID_LEN];
    DIR *d;
    struct dirent *e;
    if (snprintf(dir, sizeof dir, "%s/gbuffer-sets", s->blobs) >= (int)sizeof dir ||
        !(d = opendir(dir)))
        return;
    while ((e = readdir(d))) {
        char rec[STORE_PATH_MAX], name[STORE_PATH_MAX];
        struct stat st;
        if (!id_stem(e->d_name, id) || strcmp(e->d_name, id) ||
            snprintf(rec, sizeof rec, "%s/%s/set.json", dir, id) >= (int)sizeof rec ||
            stat(rec, &st) == 0)
            continue;
        if (snprintf(rec, sizeof rec, "%s/%s", dir, id) >= (int)sizeof rec ||
            !store_sweepable(s, rec))
            continue;
        snprintf(name, sizeof name, "gbuffer-sets/%s", id);
        store_blob_rmtree(s, name);
    }
    closedir(d);
}

/* Whole entries first, temporary files after: removing a temporary file
 * makes its directory young again, and with shared blobs (sweep_grace) a
 * young directory is spared as another process's write in progress, so a
 * material's directory that held only an interrupted write would stay. */
void store_sweep_blobs(store *s)
{
    sweep_rows(s, "materials", "materials");
    sweep_rows(s, "scenes", "scenes");
    sweep_rows(s, "meshes", "meshes");
    sweep_envs(s);
    sweep_gbuffer_sets(s);
    sweep_tmp(s, s->blobs, 0);
}
