/* Tests of glintd's store (server/store.h): opening and the schema version,
 * documents, blob names and files, and the sweep of files a crash leaves
 * behind.  The session log (paintings, strokes, events, paging, deleting a
 * scene, concurrent appends) is in test_store_log.c.  Every test works on a
 * real database in a fresh temporary directory: SQLite, or PostgreSQL when
 * the test command runs them again with a server (store_fixture.h). */
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "ids.h"
#include "store.h"
#include "store_fixture.h"

static int write_file(const char *dir, const char *rel, const char *text)
{
    char path[8192];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s", dir, rel);
    if (!(f = fopen(path, "w")))
        return -1;
    fputs(text, f);
    return fclose(f);
}

/* The whole file (malloc'ed) or NULL. */
static char *read_file(const char *dir, const char *rel, size_t *len)
{
    char path[512];
    FILE *f;
    char *d;
    long n;
    snprintf(path, sizeof path, "%s/%s", dir, rel);
    if (!(f = fopen(path, "rb")))
        return NULL;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    rewind(f);
    d = malloc((size_t)n + 1);
    if (d && fread(d, 1, (size_t)n, f) != (size_t)n) {
        free(d);
        d = NULL;
    }
    fclose(f);
    *len = (size_t)n;
    return d;
}

/* An address no call returns, to see that an OUT pointer was reset. */
static char sentinel;

/* ---- open, schema ------------------------------------------------------------ */

TEST(open_fresh_records_schema_and_reopens)
{
    fixture f;
    store *s;
    json_t *doc = NULL;
    char scene[33];
    ASSERT_OK(fx_mkdir(&f));
    ASSERT_OK(fx_store_open(&f, &s, NULL));
    ASSERT(s != NULL);
    /* SQLite's file, or none when the metadata is in PostgreSQL */
    ASSERT_EQ(path_exists(f.dir, "glint.db"), !fx_pg(&f));
    ASSERT(path_exists(f.dir, "blobs"));
    ASSERT_OK(fx_scene(s, scene));
    store_close(s);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM schema_version"), 1);
    ASSERT_EQ(db_int(&f, "SELECT version FROM schema_version"), STORE_SCHEMA_VERSION);
    /* reopening keeps the data and does not record the version again */
    ASSERT_OK(fx_store_open(&f, &f.s, NULL));
    ASSERT_OK(store_scene_get(f.s, scene, &doc, NULL));
    ASSERT(strcmp(json_string_value(json_object_get(doc, "id")), scene) == 0);
    json_decref(doc);
    store_close(f.s);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM schema_version"), 1);
    f.s = NULL;
    fx_close(&f);
}

TEST(newer_schema_is_refused_and_left_unchanged)
{
    fixture f;
    store *s = (store *)(void *)&sentinel; /* a failing open sets it to NULL */
    glint_err e;
    json_t *doc;
    char *before, *after;
    size_t nb, na;
    ASSERT_OK(fx_open(&f));
    store_close(f.s);
    f.s = NULL;
    ASSERT_EQ(fx_sql(&f, "UPDATE schema_version SET version = 99"), 0);
    if (!fx_pg(&f))
        ASSERT((before = read_file(f.dir, "glint.db", &nb)) != NULL);
    else
        before = NULL, nb = 0;
    ASSERT_EQ(fx_store_open(&f, &s, &e), GLINT_EUNSUPPORTED);
    ASSERT(s == NULL);
    ASSERT_MSG(strstr(e.msg, "99") != NULL, "message names the version: %s", e.msg);
    if (!fx_pg(&f)) {
        ASSERT((after = read_file(f.dir, "glint.db", &na)) != NULL);
        ASSERT_EQ(na, nb);
        ASSERT(memcmp(before, after, nb) == 0);
        free(before);
        free(after);
    }
    ASSERT_EQ(db_int(&f, "SELECT version FROM schema_version"), 99);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM schema_version"), 1);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM scenes"), 1);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM sessions"), 1);
    /* an older version has no upgrade path either: refused, not rewritten */
    ASSERT_EQ(fx_sql(&f, "UPDATE schema_version SET version = 0"), 0);
    ASSERT_EQ(fx_store_open(&f, &s, &e), GLINT_EUNSUPPORTED);
    ASSERT_EQ(db_int(&f, "SELECT version FROM schema_version"), 0);
    /* back at the current version it opens with its data */
    ASSERT_EQ(fx_sql(&f, "UPDATE schema_version SET version = 1"), 0);
    ASSERT_OK(fx_store_open(&f, &f.s, NULL));
    ASSERT_OK(store_scene_get(f.s, f.scene, &doc, NULL));
    json_decref(doc);
    fx_close(&f);
}

/* A database that cannot be reached is a clear error at open, whatever the
 * connection string says; nothing is made but the data directory. */
TEST(unreachable_postgresql_is_a_clear_error)
{
    fixture f;
    store *s = (store *)(void *)&sentinel;
    glint_err e;
    static const char *const bad[] = {
        "host=/nonexistent-socket-dir port=5 dbname=glint connect_timeout=2",
        "host=127.0.0.1 port=1 dbname=glint connect_timeout=2",
        "not a connection string = = =",
        "postgresql://%zz",
    };
    ASSERT_OK(fx_mkdir(&f));
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        ASSERT(store_open_db(f.dir, bad[i], &s, &e) != 0);
        ASSERT(s == NULL);
        ASSERT_MSG(strstr(e.msg, "PostgreSQL") != NULL, "%s: %s", bad[i], e.msg);
        s = (store *)(void *)&sentinel;
    }
    ASSERT(!path_exists(f.dir, "glint.db"));
    f.s = NULL;
    fx_close(&f);
}

/* ---- documents ------------------------------------------------------------------ */

TEST(scenes_put_get_list_and_unknown_ids)
{
    fixture f;
    char b[33], unknown[33];
    json_t *doc, *list;
    glint_err e;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(fx_scene(f.s, b));
    ASSERT_OK(store_scene_get(f.s, b, &doc, NULL));
    ASSERT_EQ(json_integer_value(json_object_get(json_object_get(doc, "scene"), "width")), 64);
    json_decref(doc);
    ASSERT_OK(store_scene_list(f.s, &list, NULL));
    ASSERT_EQ(json_array_size(list), 2); /* oldest first */
    ASSERT(strcmp(json_string_value(json_object_get(json_array_get(list, 0), "id")), f.scene) == 0);
    ASSERT(strcmp(json_string_value(json_object_get(json_array_get(list, 1), "id")), b) == 0);
    json_decref(list);
    /* the same id twice is refused, the first document kept */
    doc = json_pack("{s:s}", "id", "other");
    ASSERT(store_scene_put(f.s, b, doc, NULL) < 0);
    json_decref(doc);
    ASSERT_OK(store_scene_get(f.s, b, &doc, NULL));
    ASSERT(strcmp(json_string_value(json_object_get(doc, "id")), b) == 0);
    json_decref(doc);
    ASSERT_OK(glint_id_new(unknown, NULL));
    doc = (json_t *)(void *)&sentinel;
    ASSERT_EQ(store_scene_get(f.s, unknown, &doc, &e), GLINT_ENOTFOUND);
    ASSERT(doc == NULL);
    ASSERT(strstr(e.msg, unknown) != NULL);
    ASSERT_EQ(store_scene_get(f.s, "not-an-id", &doc, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_scene_get(f.s, NULL, &doc, NULL), GLINT_ENOTFOUND);
    doc = json_object();
    ASSERT_EQ(store_scene_put(f.s, "ABCDEF0123456789ABCDEF0123456789", doc, NULL), GLINT_EINVAL);
    ASSERT_EQ(store_scene_put(f.s, "0123", doc, NULL), GLINT_EINVAL);
    json_decref(doc);
    ASSERT_OK(store_scene_list(f.s, &list, NULL));
    ASSERT_EQ(json_array_size(list), 2);
    json_decref(list);
    fx_close(&f);
}

TEST(meshes_put_get_data)
{
    fixture f;
    char id[33], other[33], format[16];
    static const char ply[] = "ply\nformat ascii 1.0\nend_header\n";
    json_t *info, *got;
    void *data;
    size_t len;
    char blob[64];
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(glint_id_new(id, NULL));
    info = json_pack("{s:s, s:i, s:i}", "format", "ply", "triangles", 12, "bytes",
                     (int)sizeof ply - 1);
    ASSERT_OK(store_mesh_put(f.s, id, info, ply, sizeof ply - 1, NULL));
    ASSERT_OK(store_mesh_get(f.s, id, &got, NULL));
    ASSERT(json_equal(got, info));
    json_decref(got);
    ASSERT_OK(store_mesh_data(f.s, id, &data, &len, format, NULL));
    ASSERT_EQ(len, sizeof ply - 1);
    ASSERT(memcmp(data, ply, len) == 0);
    ASSERT_EQ(((char *)data)[len], '\0');
    ASSERT(strcmp(format, "ply") == 0);
    free(data);
    snprintf(blob, sizeof blob, "blobs/meshes/%s.ply", id);
    ASSERT(path_exists(f.dir, blob));
    /* a format that is no file extension is refused and writes nothing */
    ASSERT_OK(glint_id_new(other, NULL));
    json_object_set_new(info, "format", json_string("../x"));
    ASSERT_EQ(store_mesh_put(f.s, other, info, ply, sizeof ply - 1, NULL), GLINT_EINVAL);
    json_object_del(info, "format");
    ASSERT_EQ(store_mesh_put(f.s, other, info, ply, sizeof ply - 1, NULL), GLINT_EINVAL);
    ASSERT_EQ(store_mesh_get(f.s, other, &got, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_mesh_data(f.s, other, &data, &len, format, NULL), GLINT_ENOTFOUND);
    ASSERT(data == NULL);
    ASSERT_EQ(store_mesh_put(f.s, "mesh", info, ply, 3, NULL), GLINT_EINVAL);
    json_decref(info);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM meshes"), 1);
    fx_close(&f);
}

TEST(sessions_need_their_scene_and_report_last_seq)
{
    fixture f;
    char id[33], unknown[33];
    json_t *doc;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(store_session_get(f.s, f.session, &doc, NULL));
    ASSERT(strcmp(json_string_value(json_object_get(doc, "scene_id")), f.scene) == 0);
    ASSERT(strcmp(json_string_value(json_object_get(doc, "paint_token")), "p0") == 0);
    ASSERT(json_is_integer(json_object_get(doc, "last_seq")));
    ASSERT_EQ(json_integer_value(json_object_get(doc, "last_seq")), 0);
    json_decref(doc);
    /* a session of a scene that does not exist */
    ASSERT_OK(glint_id_new(id, NULL));
    ASSERT_OK(glint_id_new(unknown, NULL));
    doc = json_pack("{s:s}", "scene_id", unknown);
    ASSERT_EQ(store_session_put(f.s, id, doc, NULL), GLINT_ENOTFOUND);
    json_decref(doc);
    doc = json_pack("{s:s}", "scene_id", "nope");
    ASSERT_EQ(store_session_put(f.s, id, doc, NULL), GLINT_ENOTFOUND);
    json_decref(doc);
    doc = json_object();
    ASSERT_EQ(store_session_put(f.s, id, doc, NULL), GLINT_ENOTFOUND);
    json_decref(doc);
    ASSERT_EQ(store_session_get(f.s, id, &doc, NULL), GLINT_ENOTFOUND);
    ASSERT(doc == NULL);
    ASSERT_EQ(store_session_get(f.s, "x", &doc, NULL), GLINT_ENOTFOUND);
    doc = json_pack("{s:s}", "scene_id", f.scene);
    ASSERT_EQ(store_session_put(f.s, "bad id", doc, NULL), GLINT_EINVAL);
    json_decref(doc);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM sessions"), 1);
    fx_close(&f);
}

TEST(materials_put_get_list)
{
    fixture f;
    char m1[33], m2[33], m3[33], other[33];
    json_t *doc, *list;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(fx_session(f.s, f.scene, other));
    ASSERT_OK(glint_id_new(m1, NULL));
    ASSERT_OK(glint_id_new(m2, NULL));
    ASSERT_OK(glint_id_new(m3, NULL));
    doc = json_pack("{s:s, s:f}", "id", m1, "rms", 0.25);
    ASSERT_OK(store_material_put(f.s, m1, f.session, doc, NULL));
    json_decref(doc);
    doc = json_pack("{s:s, s:f}", "id", m2, "rms", 1.0 / 3.0);
    ASSERT_OK(store_material_put(f.s, m2, f.session, doc, NULL));
    json_decref(doc);
    doc = json_pack("{s:s}", "id", m3);
    ASSERT_OK(store_material_put(f.s, m3, other, doc, NULL));
    json_decref(doc);
    ASSERT_OK(store_material_get(f.s, m2, &doc, NULL));
    /* doubles come back exactly */
    ASSERT(json_real_value(json_object_get(doc, "rms")) == 1.0 / 3.0);
    json_decref(doc);
    ASSERT_OK(store_material_list(f.s, f.session, &list, NULL));
    ASSERT_EQ(json_array_size(list), 2);
    ASSERT(strcmp(json_string_value(json_object_get(json_array_get(list, 0), "id")), m1) == 0);
    ASSERT(strcmp(json_string_value(json_object_get(json_array_get(list, 1), "id")), m2) == 0);
    json_decref(list);
    ASSERT_OK(store_material_list(f.s, other, &list, NULL));
    ASSERT_EQ(json_array_size(list), 1);
    json_decref(list);
    ASSERT_OK(glint_id_new(m3, NULL));
    ASSERT_EQ(store_material_get(f.s, m3, &doc, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_material_get(f.s, "m3", &doc, NULL), GLINT_ENOTFOUND);
    doc = json_object();
    ASSERT_EQ(store_material_put(f.s, "m3", f.session, doc, NULL), GLINT_EINVAL);
    json_decref(doc);
    fx_close(&f);
}

/* ---- blobs ------------------------------------------------------------------------- */

TEST(blob_names_refused)
{
    fixture f;
    char path[4096], longname[600];
    static const char *const bad[] = {
        "",          "..",        "../x",      "a/../b",   "a/..",    "/etc/passwd",
        "a//b",      "a/",        "a b",       "a\\b",     "a;b",     "a\nb",
        "caf\xc3\xa9", "a*",      "~/x",       "a:b",      NULL};
    void *data = NULL;
    size_t len;
    json_t *names;
    ASSERT_OK(fx_open(&f));
    for (int i = 0; bad[i]; i++) {
        ASSERT_MSG(store_blob_put(f.s, bad[i], "x", 1, NULL) == GLINT_EINVAL, "put \"%s\"",
                   bad[i]);
        ASSERT_MSG(store_blob_get(f.s, bad[i], &data, &len, NULL) == GLINT_EINVAL, "get \"%s\"",
                   bad[i]);
        ASSERT_MSG(store_blob_path(f.s, bad[i], path, sizeof path, NULL) == GLINT_EINVAL,
                   "path \"%s\"", bad[i]);
        ASSERT_MSG(store_blob_delete(f.s, bad[i], NULL) == GLINT_EINVAL, "delete \"%s\"", bad[i]);
        ASSERT_MSG(store_blob_list(f.s, bad[i], &names, NULL) == GLINT_EINVAL, "list \"%s\"",
                   bad[i]);
    }
    ASSERT_EQ(store_blob_put(f.s, NULL, "x", 1, NULL), GLINT_EINVAL);
    memset(longname, 'a', sizeof longname - 1);
    longname[sizeof longname - 1] = '\0';
    ASSERT_EQ(store_blob_put(f.s, longname, "x", 1, NULL), GLINT_EINVAL);
    /* nothing escaped the blob directory */
    ASSERT(!path_exists(f.dir, "x"));
    ASSERT(!path_exists(f.dir, "b"));
    /* names that are fine */
    ASSERT_OK(store_blob_put(f.s, "a/b-c_d.E9", "x", 1, NULL));
    ASSERT_OK(store_blob_put(f.s, ".hidden", "x", 1, NULL));
    ASSERT_OK(store_blob_path(f.s, "a/b-c_d.E9", path, sizeof path, NULL));
    ASSERT(strncmp(path, f.dir, strlen(f.dir)) == 0);
    ASSERT(strcmp(path + strlen(f.dir), "/blobs/a/b-c_d.E9") == 0);
    fx_close(&f);
}

TEST(blob_put_get_delete_list)
{
    fixture f;
    void *data;
    size_t len;
    json_t *names;
    unsigned char bin[300];
    ASSERT_OK(fx_open(&f));
    for (int i = 0; i < 300; i++)
        bin[i] = (unsigned char)(i * 7); /* zero bytes included */
    ASSERT_OK(store_blob_put(f.s, "materials/m/factors.bin", bin, sizeof bin, NULL));
    ASSERT_OK(store_blob_put(f.s, "materials/m/b.json", "{}", 2, NULL));
    ASSERT_OK(store_blob_put(f.s, "materials/m/a.json", "[]", 2, NULL));
    ASSERT_OK(store_blob_put(f.s, "materials/m/sub/deeper.txt", "d", 1, NULL));
    ASSERT_OK(store_blob_put(f.s, "materials/m/.dot", "d", 1, NULL));
    ASSERT_OK(store_blob_get(f.s, "materials/m/factors.bin", &data, &len, NULL));
    ASSERT_EQ(len, sizeof bin);
    ASSERT(memcmp(data, bin, len) == 0);
    ASSERT_EQ(((char *)data)[len], '\0');
    free(data);
    /* overwrite */
    ASSERT_OK(store_blob_put(f.s, "materials/m/a.json", "[1, 2]", 6, NULL));
    ASSERT_OK(store_blob_get(f.s, "materials/m/a.json", &data, &len, NULL));
    ASSERT_EQ(len, 6);
    ASSERT(strcmp(data, "[1, 2]") == 0);
    free(data);
    /* empty blob */
    ASSERT_OK(store_blob_put(f.s, "materials/m/empty", "", 0, NULL));
    ASSERT_OK(store_blob_get(f.s, "materials/m/empty", &data, &len, NULL));
    ASSERT_EQ(len, 0);
    free(data);
    /* list: regular files directly inside, sorted, no directories or dot files */
    ASSERT_OK(store_blob_list(f.s, "materials/m", &names, NULL));
    ASSERT_EQ(json_array_size(names), 4);
    ASSERT(strcmp(json_string_value(json_array_get(names, 0)), "a.json") == 0);
    ASSERT(strcmp(json_string_value(json_array_get(names, 1)), "b.json") == 0);
    ASSERT(strcmp(json_string_value(json_array_get(names, 2)), "empty") == 0);
    ASSERT(strcmp(json_string_value(json_array_get(names, 3)), "factors.bin") == 0);
    json_decref(names);
    ASSERT_OK(store_blob_list(f.s, "materials/none", &names, NULL));
    ASSERT_EQ(json_array_size(names), 0);
    json_decref(names);
    /* delete, and deleting what is gone */
    ASSERT_OK(store_blob_delete(f.s, "materials/m/b.json", NULL));
    ASSERT(!path_exists(f.dir, "blobs/materials/m/b.json"));
    data = (void *)bin;
    ASSERT_EQ(store_blob_get(f.s, "materials/m/b.json", &data, &len, NULL), GLINT_ENOTFOUND);
    ASSERT(data == NULL);
    ASSERT_OK(store_blob_delete(f.s, "materials/m/b.json", NULL));
    ASSERT_OK(store_blob_list(f.s, "materials/m", &names, NULL));
    ASSERT_EQ(json_array_size(names), 3);
    json_decref(names);
    fx_close(&f);
}

/* ---- the crash sweep --------------------------------------------------------------- */

TEST(open_sweeps_files_no_row_names)
{
    fixture f;
    char dir[128], orphan[192], tmp[192], other[192], named[256], blob[256], mat[192];
    json_t *names;
    void *img;
    size_t len;
    int64_t version;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(store_painting_put(f.s, f.session, 3, exr1, sizeof exr1, NULL, NULL, NULL));
    snprintf(dir, sizeof dir, "sessions/%s", f.session);
    ASSERT_OK(store_blob_list(f.s, dir, &names, NULL));
    ASSERT_EQ(json_array_size(names), 1);
    snprintf(named, sizeof named, "blobs/%s/%s", dir, json_string_value(json_array_get(names, 0)));
    snprintf(blob, sizeof blob, "%s/%s", dir, json_string_value(json_array_get(names, 0)));
    json_decref(names);
    store_close(f.s);
    f.s = NULL;
    /* what a kill -9 leaves: a painting written but never committed, the
     * temporary file of an interrupted atomic write, a file of another
     * (unknown) session, and a temporary file outside the sessions */
    snprintf(orphan, sizeof orphan, "blobs/%s/view3-00112233aabbccdd.exr", dir);
    snprintf(tmp, sizeof tmp, "blobs/%s/view3-8899aabbccddeeff.exr.tmp-Ab12Cd", dir);
    ASSERT_OK(write_file(f.dir, orphan, "orphan"));
    ASSERT_OK(write_file(f.dir, tmp, "half"));
    {
        char unknown[33], udir[128];
        ASSERT_OK(glint_id_new(unknown, NULL));
        snprintf(udir, sizeof udir, "%s/blobs/sessions/%s", f.dir, unknown);
        ASSERT_EQ(mkdir(udir, 0755), 0);
        snprintf(other, sizeof other, "blobs/sessions/%s/view0-0000000000000000.exr", unknown);
        ASSERT_OK(write_file(f.dir, other, "other"));
    }
    ASSERT_EQ(mkdir(strcat(strcpy(mat, f.dir), "/blobs/materials"), 0755), 0);
    snprintf(mat, sizeof mat, "blobs/materials/keep.json");
    ASSERT_OK(write_file(f.dir, mat, "{}"));
    ASSERT(path_exists(f.dir, orphan) && path_exists(f.dir, tmp) && path_exists(f.dir, other));
    if (fx_pg(&f)) {
        /* shared blobs: a young file may be another process's write in
         * progress and stays; past the grace it goes */
        ASSERT_OK(fx_store_open(&f, &f.s, NULL));
        ASSERT(path_exists(f.dir, orphan) && path_exists(f.dir, tmp) && path_exists(f.dir, other));
        store_close(f.s);
        f.s = NULL;
        ASSERT_OK(fx_age_blobs(&f));
    }

    ASSERT_OK(fx_store_open(&f, &f.s, NULL));
    ASSERT(!path_exists(f.dir, orphan));
    ASSERT(!path_exists(f.dir, tmp));
    ASSERT(!path_exists(f.dir, other));
    ASSERT(path_exists(f.dir, named));
    ASSERT(path_exists(f.dir, mat));
    ASSERT_OK(store_painting_get(f.s, f.session, 3, &img, &len, &version, NULL));
    ASSERT_EQ(version, 1);
    ASSERT_EQ(len, sizeof exr1);
    ASSERT(memcmp(img, exr1, len) == 0);
    free(img);
    ASSERT_OK(store_blob_list(f.s, dir, &names, NULL));
    ASSERT_EQ(json_array_size(names), 1);
    ASSERT(strcmp(blob + strlen(dir) + 1, json_string_value(json_array_get(names, 0))) == 0);
    json_decref(names);
    fx_close(&f);
}

/* The other kinds a crash can leave (store_sweep.c): material and scene
 * directories and mesh files without their row, environment maps without
 * their record and records without their map, temporary files anywhere;
 * what rows and records name stays, and so do names that are not ids. */
TEST(open_sweeps_every_kind_of_blob)
{
    fixture f;
    char keep_m[33], lost_m[33], lost_s[33], keep_e[33], lost_e[33], lost_r[33], mesh[33];
    char tmp_m[33], tmp_s[33];
    char p[40][160];
    int n = 0;
    json_t *doc;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(glint_id_new(keep_m, NULL) || glint_id_new(lost_m, NULL) ||
              glint_id_new(lost_s, NULL) || glint_id_new(keep_e, NULL) ||
              glint_id_new(lost_e, NULL) || glint_id_new(lost_r, NULL) ||
              glint_id_new(mesh, NULL) || glint_id_new(tmp_m, NULL) ||
              glint_id_new(tmp_s, NULL));
    doc = json_pack("{s:s}", "id", keep_m);
    ASSERT_OK(store_material_put(f.s, keep_m, f.session, doc, NULL));
    json_decref(doc);
    doc = json_pack("{s:s, s:s, s:i}", "id", mesh, "format", "ply", "triangles", 1);
    ASSERT_OK(store_mesh_put(f.s, mesh, doc, "ply\n", 4, NULL));
    json_decref(doc);
    store_close(f.s);
    f.s = NULL;
    {
        static const char *const dirs[] = {"blobs/materials", "blobs/scenes", "blobs/environments"};
        char d[160];
        for (int i = 0; i < 3; i++) {
            snprintf(d, sizeof d, "%s/%s", f.dir, dirs[i]);
            mkdir(d, 0755);
        }
    }
#define MKDIR(...) (snprintf(p[n], sizeof p[n], __VA_ARGS__), \
                    mkdir(strcat(strcat(strcpy(p[39], f.dir), "/"), p[n]), 0755), n++)
#define FILE_(...) (snprintf(p[n], sizeof p[n], __VA_ARGS__), write_file(f.dir, p[n], "x"), n++)
    /* kept: 0..5 */
    MKDIR("blobs/materials/%s", keep_m);
    FILE_("blobs/materials/%s/material.json", keep_m);
    MKDIR("blobs/scenes/%s", f.scene);
    FILE_("blobs/environments/%s.hdr", keep_e);
    FILE_("blobs/environments/%s.json", keep_e);
    FILE_("blobs/materials/README");
    const int kept = n;
    /* removed: the rest */
    MKDIR("blobs/materials/%s", lost_m);
    FILE_("blobs/materials/%s/factors.exr", lost_m);
    MKDIR("blobs/scenes/%s", lost_s);
    FILE_("blobs/scenes/%s/base0.exr", lost_s);
    FILE_("blobs/meshes/%s.obj", lost_m);
    FILE_("blobs/environments/%s.exr", lost_e);
    FILE_("blobs/environments/%s.json", lost_r);
    FILE_("blobs/materials/%s/material.json.tmp-Xy12Zw", keep_m);
    FILE_("blobs/environments/%s.hdr.tmp-Ab34Cd", keep_e);
    /* a material's or scene's directory whose first file was still being
     * written: removing the temporary file makes the directory young again,
     * which must not save it (shared blobs: the grace) */
    MKDIR("blobs/materials/%s", tmp_m);
    FILE_("blobs/materials/%s/material.json.tmp-Ef56Gh", tmp_m);
    MKDIR("blobs/scenes/%s", tmp_s);
    FILE_("blobs/scenes/%s/base0.exr.tmp-Ij78Kl", tmp_s);
#undef MKDIR
#undef FILE_
    for (int i = 0; i < n; i++)
        ASSERT_MSG(path_exists(f.dir, p[i]), "not made: %s", p[i]);
    if (fx_pg(&f)) {
        ASSERT_OK(fx_store_open(&f, &f.s, NULL));
        for (int i = 0; i < n; i++)
            ASSERT_MSG(path_exists(f.dir, p[i]), "young, yet removed: %s", p[i]);
        store_close(f.s);
        f.s = NULL;
        ASSERT_OK(fx_age_blobs(&f));
    }
    ASSERT_OK(fx_store_open(&f, &f.s, NULL));
    for (int i = 0; i < n; i++)
        ASSERT_MSG(path_exists(f.dir, p[i]) == (i < kept), "%s: %s", p[i],
                   i < kept ? "removed" : "left");
    {
        char m[160];
        snprintf(m, sizeof m, "blobs/meshes/%s.ply", mesh);
        ASSERT(path_exists(f.dir, m));
    }
    fx_close(&f);
}

TEST_LIST{
    TEST_ENTRY(open_fresh_records_schema_and_reopens),
    TEST_ENTRY(newer_schema_is_refused_and_left_unchanged),
    TEST_ENTRY(unreachable_postgresql_is_a_clear_error),
    TEST_ENTRY(scenes_put_get_list_and_unknown_ids),
    TEST_ENTRY(meshes_put_get_data),
    TEST_ENTRY(sessions_need_their_scene_and_report_last_seq),
    TEST_ENTRY(materials_put_get_list),
    TEST_ENTRY(blob_names_refused),
    TEST_ENTRY(blob_put_get_delete_list),
    TEST_ENTRY(open_sweeps_files_no_row_names),
    TEST_ENTRY(open_sweeps_every_kind_of_blob),
};

TEST_MAIN()
