/* Allocation failure along glintd's own paths (alloc_fail.h; the method
 * there, test_alloc_fail.c for core's): the store (a fresh
 * data directory: scene, session, painting, strokes, material, their reads
 * and lists, a scene deleted, the store reopened and swept) and the memo of
 * decoded paintings and documents.  Each run ends in the operation's error
 * or its success, never a crash.  Besides glint's own allocations, SQLite's
 * fail too: it takes its allocator from sqlite3_config (SQLite's own way of
 * testing this), and reports a failure as SQLITE_NOMEM, which the store must
 * turn into an error.  jansson's do not (its parser crashes: alloc_fail.h). */
#define _GNU_SOURCE
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "ids.h"
#include "img.h"
#include "memo.h"
#include "store.h"

#include "alloc_fail.h"

#include <malloc.h>
#include <sqlite3.h>

static void *sq_malloc(int n)
{
    return fi_fail(NULL) ? NULL : __libc_malloc((size_t)n);
}

static void sq_free(void *p)
{
    __libc_free(p);
}

static void *sq_realloc(void *p, int n)
{
    return fi_fail(NULL) ? NULL : __libc_realloc(p, (size_t)n);
}

static int sq_size(void *p)
{
    return (int)malloc_usable_size(p);
}

static int sq_roundup(int n)
{
    return (n + 15) & ~15;
}

static int sq_init(void *x)
{
    (void)x;
    return SQLITE_OK;
}

static void sq_shutdown(void *x)
{
    (void)x;
}

/* Before SQLite is first used. */
__attribute__((constructor)) static void sq_install(void)
{
    static const sqlite3_mem_methods mm = {sq_malloc, sq_free, sq_realloc, sq_size,
                                           sq_roundup, sq_init, sq_shutdown, NULL};
    if (sqlite3_config(SQLITE_CONFIG_MALLOC, &mm) != SQLITE_OK)
        fprintf(stderr, "sqlite3_config(SQLITE_CONFIG_MALLOC) refused\n");
}

static const unsigned char exr_bytes[] = {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0}; /* not decoded */

static int op_store(glint_err *e)
{
    char dir[] = "/tmp/glint-allocfail-store-XXXXXX", scene[33], sess[33], mat[33], cmd[96];
    store *s = NULL;
    json_t *doc = NULL, *strokes = NULL, *got = NULL;
    int64_t v, a, b;
    void *data = NULL;
    size_t len;
    int rc;

    if (!mkdtemp(dir))
        return glint_err_set(e, GLINT_EIO, "mkdtemp");
    if ((rc = store_open(dir, &s, e)) || (rc = glint_id_new(scene, e)) ||
        (rc = glint_id_new(sess, e)) || (rc = glint_id_new(mat, e)))
        goto done;
    if (!(doc = json_pack("{s:s, s:{s:i}}", "id", scene, "scene", "width", 16))) {
        rc = glint_err_set(e, GLINT_ENOMEM, "json_pack");
        goto done;
    }
    if ((rc = store_scene_put(s, scene, doc, e)))
        goto done;
    json_decref(doc);
    if (!(doc = json_pack("{s:s, s:s}", "id", sess, "scene_id", scene))) {
        rc = glint_err_set(e, GLINT_ENOMEM, "json_pack");
        goto done;
    }
    if ((rc = store_session_put(s, sess, doc, e)) ||
        (rc = store_painting_put(s, sess, 2, exr_bytes, sizeof exr_bytes, &v, NULL, e)))
        goto done;
    if (!(strokes = json_pack("[{s:[f,f,f], s:f, s:[[f,f]]}]", "color", 1.0, 0.5, 0.0,
                              "diameter", 3.0, "points", 1.0, 2.0))) {
        rc = glint_err_set(e, GLINT_ENOMEM, "json_pack");
        goto done;
    }
    if ((rc = store_strokes_append(s, sess, 2, strokes, exr_bytes, sizeof exr_bytes, &a, &b, &v,
                                   e)) ||
        (rc = store_material_put(s, mat, sess, doc, e)) ||
        (rc = store_painting_get(s, sess, 2, &data, &len, &v, e)) ||
        (rc = store_strokes_since(s, sess, 0, &got, e)))
        goto done;
    json_decref(got);
    got = NULL;
    if ((rc = store_material_list(s, sess, &got, e)))
        goto done;
    json_decref(got);
    got = NULL;
    if ((rc = store_scene_delete(s, scene, e)))
        goto done;
    store_close(s);
    s = NULL;
    rc = store_open(dir, &s, e); /* the sweep */
done:
    free(data);
    json_decref(got);
    json_decref(strokes);
    json_decref(doc);
    if (s)
        store_close(s);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
    return rc;
}

static int op_memo(glint_err *e)
{
    static const char sid[] = "0123456789abcdef0123456789abcdef";
    memo *m = NULL;
    memo_painting *p = NULL;
    memo_doc d;
    img im;
    int rc;
    if ((rc = memo_open((size_t)1 << 20, (size_t)1 << 20, &m, e)))
        return rc;
    if ((rc = img_alloc(&im, 8, 8, 3, e))) {
        memo_close(m);
        return rc;
    }
    memo_painting_offer(m, sid, 0, 1, &im); /* copied */
    rc = memo_painting_put(m, sid, 1, 3, &im, &p);
    if (rc)
        img_free(&im);
    memo_painting_release(m, p);
    p = NULL;
    if (memo_painting_get(m, sid, 1, 3, &p) == 0)
        memo_painting_release(m, p);
    memo_doc_put(m, sid, sid, sid, "{\"a\": 1}", 8);
    if (memo_doc_get(m, sid, &d) == 0)
        free(d.text);
    memo_close(m);
    return rc;
}

TEST(store_every_kind_of_write)
{
    ASSERT_EQ(sweep("store", op_store), 0);
}

TEST(memo)
{
    ASSERT_EQ(sweep("memo", op_memo), 0);
}

TEST_LIST {
    TEST_ENTRY(store_every_kind_of_write),
    TEST_ENTRY(memo),
};

TEST_MAIN()
