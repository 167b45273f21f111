/* Tests of glintd's store (server/store.h), the session log: painting
 * versions, strokes and events in one numbering per session, paging, a
 * session that does not exist, deleting a scene with its sessions, logs
 * and blobs, and concurrent appends.  Every test works on a real SQLite
 * database in a fresh temporary directory (store_fixture.h). */
#include <dirent.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "ids.h"
#include "img.h"
#include "store.h"
#include "store_fixture.h"

/* Entries of a directory besides "." and ".." (0 when it does not exist). */
static int files_in(const char *dir, const char *rel)
{
    char path[512];
    DIR *d;
    struct dirent *e;
    int n = 0;
    snprintf(path, sizeof path, "%s/%s", dir, rel);
    if (!(d = opendir(path)))
        return 0;
    while ((e = readdir(d)))
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return n;
}

static json_t *strokes_of(int n, int tag)
{
    json_t *a = json_array();
    for (int i = 0; i < n; i++)
        json_array_append_new(a, json_pack("{s:i, s:i, s:f, s:[f,f,f]}", "tag", tag, "i", i,
                                           "diameter", 0.125 + i, "color", 0.1, 0.2, 0.3));
    return a;
}

/* ---- the session log -------------------------------------------------------------- */

TEST(painting_versions_and_seq)
{
    fixture f;
    int64_t version = 0, seq = 0;
    void *data;
    size_t len;
    json_t *names, *list, *events;
    char dir[64];
    ASSERT_OK(fx_open(&f));
    ASSERT_EQ(store_painting_get(f.s, f.session, 0, &data, &len, &version, NULL),
              GLINT_ENOTFOUND);
    ASSERT_OK(store_painting_put(f.s, f.session, 0, exr1, sizeof exr1, &version, &seq, NULL));
    ASSERT_EQ(version, 1);
    ASSERT_EQ(seq, 1);
    ASSERT_OK(store_painting_put(f.s, f.session, 0, exr2, sizeof exr2, &version, &seq, NULL));
    ASSERT_EQ(version, 2);
    ASSERT_EQ(seq, 2);
    ASSERT_OK(store_painting_put(f.s, f.session, 5, exr1, sizeof exr1, &version, NULL, NULL));
    ASSERT_EQ(version, 1); /* versions count per view, seq per session */
    version = 0;
    ASSERT_OK(store_painting_get(f.s, f.session, 0, &data, &len, &version, NULL));
    ASSERT_EQ(version, 2);
    ASSERT_EQ(len, sizeof exr2);
    ASSERT(memcmp(data, exr2, len) == 0);
    free(data);
    ASSERT_OK(store_painting_get(f.s, f.session, 5, &data, &len, NULL, NULL));
    ASSERT(memcmp(data, exr1, len) == 0);
    free(data);
    ASSERT_EQ(store_painting_get(f.s, f.session, 1, &data, &len, &version, NULL),
              GLINT_ENOTFOUND);
    /* each version has its own file; the replaced one is gone (removed off
     * the commit's path: waited for) */
    store_reap_wait(f.s);
    snprintf(dir, sizeof dir, "sessions/%s", f.session);
    ASSERT_OK(store_blob_list(f.s, dir, &names, NULL));
    ASSERT_EQ(json_array_size(names), 2);
    ASSERT(strncmp(json_string_value(json_array_get(names, 0)), "view0-", 6) == 0);
    ASSERT(strncmp(json_string_value(json_array_get(names, 1)), "view5-", 6) == 0);
    json_decref(names);
    ASSERT_OK(store_paintings_list(f.s, f.session, &list, NULL));
    ASSERT_EQ(json_array_size(list), 2);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(list, 0), "view")), 0);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(list, 0), "version")), 2);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(list, 1), "view")), 5);
    json_decref(list);
    /* every upload is a "painting" event of the log */
    ASSERT_OK(store_events_since(f.s, f.session, 0, 0, &events, &seq, NULL));
    ASSERT_EQ(seq, 3);
    ASSERT_EQ(json_array_size(events), 3);
    ASSERT(strcmp(json_string_value(json_object_get(json_array_get(events, 1), "type")),
                  "painting") == 0);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(events, 1), "view")), 0);
    ASSERT_EQ(json_integer_value(json_object_get(
                  json_object_get(json_array_get(events, 1), "data"), "version")), 2);
    ASSERT_EQ(json_integer_value(json_object_get(
                  json_object_get(json_array_get(events, 2), "data"), "view")), 5);
    json_decref(events);
    /* refused: negative view, unknown session (no file left behind) */
    ASSERT_EQ(store_painting_put(f.s, f.session, -1, exr1, sizeof exr1, &version, NULL, NULL),
              GLINT_EINVAL);
    {
        char unknown[33], udir[64];
        ASSERT_OK(glint_id_new(unknown, NULL));
        ASSERT_EQ(store_painting_put(f.s, unknown, 0, exr1, sizeof exr1, &version, NULL, NULL),
                  GLINT_ENOTFOUND);
        ASSERT_EQ(store_painting_put(f.s, "zz", 0, exr1, sizeof exr1, &version, NULL, NULL),
                  GLINT_ENOTFOUND);
        snprintf(udir, sizeof udir, "blobs/sessions/%s", unknown);
        ASSERT_EQ(files_in(f.dir, udir), 0);
        ASSERT_EQ(store_painting_get(f.s, unknown, 0, &data, &len, NULL, NULL), GLINT_ENOTFOUND);
    }
    ASSERT_OK(store_session_get(f.s, f.session, &list, NULL));
    ASSERT_EQ(json_integer_value(json_object_get(list, "last_seq")), 3);
    json_decref(list);
    fx_close(&f);
}

TEST(strokes_and_events_share_one_numbering)
{
    fixture f;
    json_t *strokes = strokes_of(3, 1), *more = strokes_of(2, 2), *arr, *data;
    int64_t first = 0, last = 0, version = 0, seq = 0;
    void *bytes;
    size_t len;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(store_strokes_append(f.s, f.session, 2, strokes, exr1, sizeof exr1, &first, &last,
                                   &version, NULL));
    ASSERT_EQ(first, 1);
    ASSERT_EQ(last, 3);
    ASSERT_EQ(version, 1);
    /* the painting the strokes produced is committed with them */
    ASSERT_OK(store_painting_get(f.s, f.session, 2, &bytes, &len, &version, NULL));
    ASSERT_EQ(version, 1);
    ASSERT(memcmp(bytes, exr1, sizeof exr1) == 0);
    free(bytes);
    data = json_pack("{s:s}", "material_id", "m");
    ASSERT_OK(store_event_append(f.s, f.session, "fit", -1, data, &seq, NULL));
    ASSERT_EQ(seq, 4);
    ASSERT_OK(store_event_append(f.s, f.session, "note", 7, data, &seq, NULL));
    ASSERT_EQ(seq, 5);
    ASSERT_OK(store_painting_put(f.s, f.session, 2, exr2, sizeof exr2, &version, &seq, NULL));
    ASSERT_EQ(seq, 6);
    ASSERT_EQ(version, 2);
    ASSERT_OK(store_strokes_append(f.s, f.session, 2, more, exr1, sizeof exr1, &first, &last,
                                   &version, NULL));
    ASSERT_EQ(first, 7);
    ASSERT_EQ(last, 8);
    ASSERT_EQ(version, 3);

    /* the whole log, in order */
    ASSERT_OK(store_events_since(f.s, f.session, 0, 0, &arr, &seq, NULL));
    ASSERT_EQ(seq, 8);
    ASSERT_EQ(json_array_size(arr), 8);
    {
        static const char *const types[] = {"stroke", "stroke", "stroke", "fit",
                                            "note",   "painting", "stroke", "stroke"};
        for (size_t i = 0; i < 8; i++) {
            json_t *r = json_array_get(arr, i);
            ASSERT_EQ(json_integer_value(json_object_get(r, "seq")), (long long)i + 1);
            ASSERT_MSG(strcmp(json_string_value(json_object_get(r, "type")), types[i]) == 0,
                       "event %zu is %s", i, json_string_value(json_object_get(r, "type")));
            ASSERT(json_is_string(json_object_get(r, "created")));
        }
        ASSERT(json_object_get(json_array_get(arr, 3), "view") == NULL); /* view -1: none */
        ASSERT_EQ(json_integer_value(json_object_get(json_array_get(arr, 4), "view")), 7);
        ASSERT(json_equal(json_object_get(json_array_get(arr, 3), "data"), data));
        ASSERT(json_equal(json_object_get(json_array_get(arr, 1), "data"),
                          json_array_get(strokes, 1)));
    }
    json_decref(arr);
    /* strokes only, in stroke form */
    ASSERT_OK(store_strokes_since(f.s, f.session, 2, &arr, NULL));
    ASSERT_EQ(json_array_size(arr), 3);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(arr, 0), "seq")), 3);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(arr, 1), "seq")), 7);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(arr, 0), "view")), 2);
    ASSERT(json_equal(json_object_get(json_array_get(arr, 0), "stroke"),
                      json_array_get(strokes, 2)));
    ASSERT(json_equal(json_object_get(json_array_get(arr, 2), "stroke"),
                      json_array_get(more, 1)));
    ASSERT(json_object_get(json_array_get(arr, 0), "type") == NULL);
    json_decref(arr);
    /* an unknown (well-formed) session is ENOTFOUND by every reader */
    {
        static const char nobody[] = "0123456789abcdef0123456789abcdef";
        int64_t nlast = -1;
        arr = NULL;
        ASSERT_EQ(store_strokes_since(f.s, nobody, 0, &arr, NULL), GLINT_ENOTFOUND);
        ASSERT(arr == NULL);
        ASSERT_EQ(store_events_since(f.s, nobody, 0, 0, &arr, NULL, NULL), GLINT_ENOTFOUND);
        ASSERT_EQ(store_events_since(f.s, nobody, 0, 0, &arr, &nlast, NULL), GLINT_ENOTFOUND);
        ASSERT_EQ(store_strokes_page(f.s, nobody, 0, 10, 0, &arr, NULL, NULL, NULL),
                  GLINT_ENOTFOUND);
    }
    ASSERT_OK(store_events_since(f.s, f.session, 8, 0, &arr, NULL, NULL));
    ASSERT_EQ(json_array_size(arr), 0);
    json_decref(arr);

    /* what store_event_append refuses; the numbering does not move */
    ASSERT_EQ(store_event_append(f.s, f.session, "stroke", 0, data, &seq, NULL), GLINT_EINVAL);
    ASSERT_EQ(store_event_append(f.s, f.session, "painting", 0, data, &seq, NULL),
              GLINT_EINVAL);
    ASSERT_EQ(store_event_append(f.s, f.session, "", 0, data, &seq, NULL), GLINT_EINVAL);
    ASSERT_EQ(store_event_append(f.s, f.session, NULL, 0, data, &seq, NULL), GLINT_EINVAL);
    ASSERT_EQ(store_event_append(f.s, f.session, "a-type-name-longer-than-32-bytes!", 0, data,
                                 &seq, NULL), GLINT_EINVAL);
    {
        json_t *notobj = json_integer(3);
        ASSERT_EQ(store_event_append(f.s, f.session, "fit", 0, notobj, &seq, NULL), GLINT_EINVAL);
        ASSERT_EQ(store_event_append(f.s, f.session, "fit", 0, NULL, &seq, NULL), GLINT_EINVAL);
        json_decref(notobj);
    }
    {
        json_t *none = json_array();
        ASSERT_EQ(store_strokes_append(f.s, f.session, 2, none, exr1, 3, &first, &last, NULL,
                                       NULL), GLINT_EINVAL);
        ASSERT_EQ(store_strokes_append(f.s, f.session, 2, data, exr1, 3, &first, &last, NULL,
                                       NULL), GLINT_EINVAL);
        json_decref(none);
    }
    ASSERT_OK(store_session_get(f.s, f.session, &arr, NULL));
    ASSERT_EQ(json_integer_value(json_object_get(arr, "last_seq")), 8);
    json_decref(arr);
    json_decref(data);
    json_decref(strokes);
    json_decref(more);
    fx_close(&f);
}

TEST(paging_strokes_and_events)
{
    fixture f;
    json_t *one, *arr, *data = json_pack("{s:i}", "k", 1);
    int64_t first, last, seq, since;
    int more, pages = 0;
    long long seen = 0;
    ASSERT_OK(fx_open(&f));
    /* log: 10 strokes with an event after the 4th and the 8th: seq 1..12 */
    for (int i = 0; i < 10; i++) {
        one = strokes_of(1, i);
        ASSERT_OK(store_strokes_append(f.s, f.session, 0, one, exr1, 4, &first, &last, NULL,
                                       NULL));
        json_decref(one);
        if (i == 3 || i == 7)
            ASSERT_OK(store_event_append(f.s, f.session, "fit", -1, data, &seq, NULL));
    }
    ASSERT_EQ(seq, 10);
    ASSERT_EQ(last, 12);
    /* strokes 4 at a time */
    since = 0;
    do {
        ASSERT_OK(store_strokes_page(f.s, f.session, since, 4, 0, &arr, &more, &last, NULL));
        ASSERT_LE(json_array_size(arr), 4);
        for (size_t i = 0; i < json_array_size(arr); i++) {
            long long s = json_integer_value(json_object_get(json_array_get(arr, i), "seq"));
            ASSERT(s > since);
            ASSERT(s != 5 && s != 10); /* the events are no strokes */
            ASSERT(s > seen);
            seen = s;
        }
        if (more) {
            ASSERT_EQ(json_array_size(arr), 4);
            ASSERT_EQ(last, seen); /* the last stroke of the page */
        } else {
            ASSERT_EQ(last, 12); /* the session's last number */
        }
        /* page k starts with the (4k)th stroke appended */
        one = json_object_get(json_array_get(arr, 0), "stroke");
        ASSERT_EQ(json_integer_value(json_object_get(one, "tag")), pages * 4);
        pages++;
        json_decref(arr);
        since = last;
    } while (more);
    ASSERT_EQ(pages, 3);
    ASSERT_EQ(seen, 12);
    /* exactly a page's worth: no "more" */
    ASSERT_OK(store_strokes_page(f.s, f.session, 6, 6, 0, &arr, &more, &last, NULL));
    ASSERT_EQ(json_array_size(arr), 5);
    ASSERT_EQ(more, 0);
    ASSERT_EQ(last, 12);
    json_decref(arr);
    ASSERT_OK(store_strokes_page(f.s, f.session, 12, 4, 0, &arr, &more, &last, NULL));
    ASSERT_EQ(json_array_size(arr), 0);
    ASSERT_EQ(more, 0);
    ASSERT_EQ(last, 12);
    json_decref(arr);
    /* every event, 5 at a time, from the middle */
    ASSERT_OK(store_events_since(f.s, f.session, 3, 5, &arr, &seq, NULL));
    ASSERT_EQ(json_array_size(arr), 5);
    ASSERT_EQ(seq, 12);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(arr, 0), "seq")), 4);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(arr, 4), "seq")), 8);
    ASSERT(strcmp(json_string_value(json_object_get(json_array_get(arr, 1), "type")), "fit") == 0);
    json_decref(arr);
    ASSERT_OK(store_events_since(f.s, f.session, 8, 5, &arr, NULL, NULL));
    ASSERT_EQ(json_array_size(arr), 4);
    json_decref(arr);
    json_decref(data);
    fx_close(&f);
}

/* A page stops at max_bytes of records as compact JSON, never before its
 * first stroke: a long history comes in pages of bounded size, each
 * following the last, none empty, none missing a stroke. */
TEST(pages_are_bounded_by_bytes)
{
    fixture f;
    json_t *one, *arr;
    int64_t first, last, since = 0;
    int more;
    size_t rec;
    long long seen = 0;
    ASSERT_OK(fx_open(&f));
    /* 12 strokes of one size (the tag and i keep their lengths) */
    for (int i = 0; i < 12; i++) {
        one = strokes_of(1, i % 10);
        ASSERT_OK(store_strokes_append(f.s, f.session, 0, one, exr1, 4, &first, &last, NULL,
                                       NULL));
        json_decref(one);
    }
    ASSERT_OK(store_strokes_page(f.s, f.session, 0, 1, 0, &arr, &more, &last, NULL));
    rec = json_dumpb(json_array_get(arr, 0), NULL, 0, JSON_COMPACT) + 1;
    json_decref(arr);
    /* 2.5 records a page: pages of 2, 6 of them */
    for (int pages = 0;; pages++) {
        ASSERT_OK(store_strokes_page(f.s, f.session, since, 100, rec * 5 / 2, &arr, &more,
                                     &last, NULL));
        ASSERT_EQ(json_array_size(arr), 2);
        for (size_t i = 0; i < json_array_size(arr); i++) {
            long long s = json_integer_value(json_object_get(json_array_get(arr, i), "seq"));
            ASSERT_EQ(s, seen + 1);
            seen = s;
        }
        json_decref(arr);
        since = last;
        if (!more) {
            ASSERT_EQ(pages, 5);
            break;
        }
    }
    ASSERT_EQ(seen, 12);
    /* a limit under one record: one stroke a page all the same */
    ASSERT_OK(store_strokes_page(f.s, f.session, 3, 100, 1, &arr, &more, &last, NULL));
    ASSERT_EQ(json_array_size(arr), 1);
    ASSERT_EQ(more, 1);
    ASSERT_EQ(last, 4);
    json_decref(arr);
    /* the count still bounds it */
    ASSERT_OK(store_strokes_page(f.s, f.session, 0, 3, (size_t)1 << 20, &arr, &more, &last,
                                 NULL));
    ASSERT_EQ(json_array_size(arr), 3);
    ASSERT_EQ(more, 1);
    json_decref(arr);
    fx_close(&f);
}

TEST(session_that_does_not_exist)
{
    fixture f;
    char unknown[33];
    json_t *strokes = strokes_of(2, 0), *arr = NULL, *data = json_object();
    int64_t first = -1, last = -1, seq = -1;
    int more = -1;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(glint_id_new(unknown, NULL));
    ASSERT_EQ(store_strokes_append(f.s, unknown, 0, strokes, exr1, 4, &first, &last, NULL, NULL),
              GLINT_ENOTFOUND);
    ASSERT_EQ(first, -1);
    ASSERT_EQ(store_event_append(f.s, unknown, "fit", -1, data, &seq, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(seq, -1);
    ASSERT_EQ(store_events_since(f.s, unknown, 0, 10, &arr, &seq, NULL), GLINT_ENOTFOUND);
    ASSERT(arr == NULL);
    ASSERT_EQ(store_strokes_page(f.s, unknown, 0, 10, 0, &arr, &more, &last, NULL),
              GLINT_ENOTFOUND);
    ASSERT(arr == NULL);
    ASSERT_EQ(store_events_since(f.s, "../x", 0, 10, &arr, NULL, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_strokes_append(f.s, "x", 0, strokes, exr1, 4, &first, &last, NULL, NULL),
              GLINT_ENOTFOUND);
    /* nothing was written for it */
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM events"), 0);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM paintings"), 0);
    {
        char dir[64];
        snprintf(dir, sizeof dir, "blobs/sessions/%s", unknown);
        ASSERT_EQ(files_in(f.dir, dir), 0);
    }
    json_decref(strokes);
    json_decref(data);
    fx_close(&f);
}

TEST(a_material_and_its_event_commit_together)
{
    fixture f;
    char mid[33], mid2[33], unknown[33];
    json_t *doc = json_pack("{s:s, s:f}", "method", "hf3", "rms", 0.25);
    json_t *ev = json_pack("{s:s}", "material_id", "x"), *got = NULL, *arr = NULL;
    int64_t seq = -1, last = -1;

    ASSERT_OK(fx_open(&f));
    ASSERT_OK(glint_id_new(mid, NULL));
    ASSERT_OK(glint_id_new(mid2, NULL));
    ASSERT_OK(glint_id_new(unknown, NULL));
    ASSERT_OK(store_event_append(f.s, f.session, "note", -1, ev, &seq, NULL));
    ASSERT_EQ(seq, 1);
    ASSERT_OK(store_material_put_event(f.s, mid, f.session, doc, "fit", ev, &seq, NULL));
    ASSERT_EQ(seq, 2); /* numbered after the session's last event */
    ASSERT_OK(store_material_get(f.s, mid, &got, NULL));
    ASSERT_NEAR(json_number_value(json_object_get(got, "rms")), 0.25, 0.0);
    json_decref(got);
    ASSERT_OK(store_events_since(f.s, f.session, 1, 0, &arr, &last, NULL));
    ASSERT_EQ((int)json_array_size(arr), 1);
    ASSERT_EQ(last, 2);
    ASSERT(!strcmp(json_string_value(json_object_get(json_array_get(arr, 0), "type")), "fit"));
    json_decref(arr);
    /* a session that is gone: neither the material nor the event */
    ASSERT_EQ(store_material_put_event(f.s, mid2, unknown, doc, "fit", ev, NULL, NULL),
              GLINT_ENOTFOUND);
    ASSERT_EQ(store_material_get(f.s, mid2, &got, NULL), GLINT_ENOTFOUND);
    /* refused before anything is written: a bad id, a type of the log's own */
    ASSERT_EQ(store_material_put_event(f.s, "../x", f.session, doc, "fit", ev, NULL, NULL),
              GLINT_EINVAL);
    ASSERT_EQ(store_material_put_event(f.s, mid2, f.session, doc, "stroke", ev, NULL, NULL),
              GLINT_EINVAL);
    /* the same id twice: the second insert fails and its event is rolled back */
    ASSERT(store_material_put_event(f.s, mid, f.session, doc, "fit", ev, NULL, NULL) != 0);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM materials"), 1);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM events"), 2);
    ASSERT_OK(store_event_append(f.s, f.session, "note", -1, ev, &seq, NULL));
    ASSERT_EQ(seq, 3); /* no gap left by the refused ones */
    json_decref(doc);
    json_decref(ev);
    fx_close(&f);
}

TEST(scene_delete_removes_sessions_logs_and_blobs)
{
    fixture f;
    char s2[33], keep_scene[33], keep_session[33], mat[33], keep_mat[33], name[128],
        unknown[33];
    json_t *strokes = strokes_of(2, 0), *data = json_pack("{s:i}", "k", 1), *doc, *arr;
    int64_t first, last;
    void *bytes;
    size_t len;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(fx_session(f.s, f.scene, s2));
    ASSERT_OK(fx_scene(f.s, keep_scene));
    ASSERT_OK(fx_session(f.s, keep_scene, keep_session));
    /* both sessions of the scene have paintings, strokes and events */
    ASSERT_OK(store_strokes_append(f.s, f.session, 0, strokes, exr1, 4, &first, &last, NULL,
                                   NULL));
    ASSERT_OK(store_painting_put(f.s, s2, 1, exr1, 4, NULL, NULL, NULL));
    ASSERT_OK(store_event_append(f.s, s2, "fit", -1, data, NULL, NULL));
    ASSERT_OK(store_strokes_append(f.s, keep_session, 0, strokes, exr2, 4, &first, &last, NULL,
                                   NULL));
    snprintf(name, sizeof name, "scenes/%s/base/view0.png", f.scene);
    ASSERT_OK(store_blob_put(f.s, name, "png", 3, NULL));
    snprintf(name, sizeof name, "scenes/%s/base.png", keep_scene);
    ASSERT_OK(store_blob_put(f.s, name, "png", 3, NULL));
    /* a material of each scene, with its files */
    ASSERT_OK(glint_id_new(mat, NULL));
    doc = json_pack("{s:s}", "id", mat);
    ASSERT_OK(store_material_put(f.s, mat, f.session, doc, NULL));
    json_decref(doc);
    snprintf(name, sizeof name, "materials/%s/material.json", mat);
    ASSERT_OK(store_blob_put(f.s, name, "{}", 2, NULL));
    ASSERT_OK(glint_id_new(keep_mat, NULL));
    doc = json_pack("{s:s}", "id", keep_mat);
    ASSERT_OK(store_material_put(f.s, keep_mat, keep_session, doc, NULL));
    json_decref(doc);
    snprintf(name, sizeof name, "materials/%s/material.json", keep_mat);
    ASSERT_OK(store_blob_put(f.s, name, "{}", 2, NULL));
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM events"), 6);

    ASSERT_OK(store_scene_delete(f.s, f.scene, NULL));
    ASSERT_EQ(store_scene_get(f.s, f.scene, &doc, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_session_get(f.s, f.session, &doc, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_session_get(f.s, s2, &doc, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_painting_get(f.s, f.session, 0, &bytes, &len, NULL, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_painting_get(f.s, s2, 1, &bytes, &len, NULL, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_events_since(f.s, s2, 0, 0, &arr, &last, NULL), GLINT_ENOTFOUND);
    {
        char sql[160];
        snprintf(sql, sizeof sql, "SELECT count(*) FROM events WHERE session IN ('%s', '%s')",
                 f.session, s2);
        ASSERT_EQ(db_int(&f, sql), 0);
        snprintf(sql, sizeof sql, "SELECT count(*) FROM paintings WHERE session IN ('%s', '%s')",
                 f.session, s2);
        ASSERT_EQ(db_int(&f, sql), 0);
    }
    snprintf(name, sizeof name, "blobs/sessions/%s", f.session);
    ASSERT(!path_exists(f.dir, name));
    snprintf(name, sizeof name, "blobs/sessions/%s", s2);
    ASSERT(!path_exists(f.dir, name));
    snprintf(name, sizeof name, "blobs/scenes/%s", f.scene);
    ASSERT(!path_exists(f.dir, name));
    /* the scene's materials went with it, row and files */
    ASSERT_EQ(store_material_get(f.s, mat, &doc, NULL), GLINT_ENOTFOUND);
    snprintf(name, sizeof name, "blobs/materials/%s", mat);
    ASSERT(!path_exists(f.dir, name));
    /* the other scene, its session and its material are untouched */
    ASSERT_OK(store_scene_get(f.s, keep_scene, &doc, NULL));
    json_decref(doc);
    ASSERT_OK(store_painting_get(f.s, keep_session, 0, &bytes, &len, NULL, NULL));
    ASSERT(memcmp(bytes, exr2, 4) == 0);
    free(bytes);
    ASSERT_OK(store_events_since(f.s, keep_session, 0, 0, &arr, &last, NULL));
    ASSERT_EQ(json_array_size(arr), 2);
    ASSERT_EQ(last, 2);
    json_decref(arr);
    snprintf(name, sizeof name, "blobs/scenes/%s/base.png", keep_scene);
    ASSERT(path_exists(f.dir, name));
    ASSERT_OK(store_material_get(f.s, keep_mat, &doc, NULL));
    json_decref(doc);
    snprintf(name, sizeof name, "blobs/materials/%s/material.json", keep_mat);
    ASSERT(path_exists(f.dir, name));
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM events"), 2);
    /* twice, or unknown */
    ASSERT_EQ(store_scene_delete(f.s, f.scene, NULL), GLINT_ENOTFOUND);
    ASSERT_OK(glint_id_new(unknown, NULL));
    ASSERT_EQ(store_scene_delete(f.s, unknown, NULL), GLINT_ENOTFOUND);
    ASSERT_EQ(store_scene_delete(f.s, "..", NULL), GLINT_ENOTFOUND);
    json_decref(strokes);
    json_decref(data);
    fx_close(&f);
}

/* Strokes made on an image of version `base` are stored only while the
 * view is still there (another replica may have painted it meanwhile). */
TEST(strokes_on_a_stale_image_are_refused)
{
    fixture f;
    json_t *strokes = strokes_of(2, 7), *names;
    int64_t first = 0, last = 0, version = 0;
    char dir[64];
    glint_err e;
    ASSERT_OK(fx_open(&f));
    /* never painted: base 0 */
    ASSERT_OK(store_strokes_append_at(f.s, f.session, 1, 0, strokes, exr1, sizeof exr1, &first,
                                      &last, &version, NULL));
    ASSERT_EQ(version, 1);
    ASSERT_EQ(last, 2);
    /* made on version 0 again: refused, nothing stored */
    ASSERT_EQ(store_strokes_append_at(f.s, f.session, 1, 0, strokes, exr2, sizeof exr2, &first,
                                      &last, &version, &e),
              GLINT_ECONFLICT);
    ASSERT_MSG(strstr(e.msg, "version 1") != NULL, "%s", e.msg);
    ASSERT_EQ(db_int(&f, "SELECT count(*) FROM events"), 2);
    ASSERT_EQ(db_int(&f, "SELECT max(version) FROM paintings"), 1);
    snprintf(dir, sizeof dir, "sessions/%s", f.session);
    ASSERT_OK(store_blob_list(f.s, dir, &names, NULL));
    ASSERT_EQ(json_array_size(names), 1); /* the refused image's file is gone */
    json_decref(names);
    /* on the current version it goes through; -1 never checks */
    ASSERT_OK(store_strokes_append_at(f.s, f.session, 1, 1, strokes, exr2, sizeof exr2, &first,
                                      &last, &version, NULL));
    ASSERT_EQ(version, 2);
    ASSERT_EQ(first, 3);
    ASSERT_OK(store_strokes_append_at(f.s, f.session, 1, -1, strokes, exr1, sizeof exr1, &first,
                                      &last, &version, NULL));
    ASSERT_EQ(version, 3);
    /* an upload made against version 2 (If-Match) likewise */
    ASSERT_EQ(store_painting_put_at(f.s, f.session, 1, 2, exr2, sizeof exr2, &version, NULL, &e),
              GLINT_ECONFLICT);
    ASSERT_OK(store_painting_put_at(f.s, f.session, 1, 3, exr2, sizeof exr2, &version, NULL,
                                    NULL));
    ASSERT_EQ(version, 4);
    json_decref(strokes);
    fx_close(&f);
}

/* ---- concurrency -------------------------------------------------------------------- */

#define APPENDERS 4
#define APPENDS 12
#define PER_APPEND 3

typedef struct appender {
    fixture *f;
    store *s; /* the appender's own store (another process's), or NULL */
    int tag;
    int64_t first[APPENDS], last[APPENDS];
    int rc;
} appender;

static void *append_main(void *arg)
{
    appender *a = arg;
    for (int i = 0; i < APPENDS && !a->rc; i++) {
        json_t *strokes = strokes_of(PER_APPEND, a->tag * 1000 + i);
        a->rc = store_strokes_append(a->s ? a->s : a->f->s, a->f->session, a->tag % 2, strokes, exr1, 8,
                                     &a->first[i], &a->last[i], NULL, NULL);
        json_decref(strokes);
    }
    return NULL;
}

/* Appenders on one store (threads of one glintd) or each on its own store
 * opened on the same database (separate glintd processes: with PostgreSQL,
 * replicas; with SQLite, several connections to one file). */
static void appends_numbered(int own_stores)
{
    fixture f;
    appender a[APPENDERS];
    pthread_t t[APPENDERS];
    static unsigned char owner[APPENDERS * APPENDS * PER_APPEND + 1];
    const int total = APPENDERS * APPENDS * PER_APPEND;
    json_t *arr;
    int64_t last;
    ASSERT_OK(fx_open(&f));
    memset(owner, 0, sizeof owner);
    for (int i = 0; i < APPENDERS; i++) {
        memset(&a[i], 0, sizeof a[i]);
        a[i].f = &f;
        a[i].tag = i + 1;
        if (own_stores)
            ASSERT_OK(fx_store_open(&f, &a[i].s, NULL));
    }
    for (int i = 0; i < APPENDERS; i++)
        ASSERT_EQ(pthread_create(&t[i], NULL, append_main, &a[i]), 0);
    for (int i = 0; i < APPENDERS; i++)
        pthread_join(t[i], NULL);
    for (int i = 0; i < APPENDERS; i++)
        store_close(a[i].s);
    for (int i = 0; i < APPENDERS; i++) {
        ASSERT_OK(a[i].rc);
        for (int k = 0; k < APPENDS; k++) {
            ASSERT_EQ(a[i].last[k] - a[i].first[k] + 1, PER_APPEND);
            ASSERT(a[i].first[k] >= 1 && a[i].last[k] <= total);
            if (k > 0)
                ASSERT(a[i].first[k] > a[i].last[k - 1]); /* a thread's own order */
            for (int64_t s = a[i].first[k]; s <= a[i].last[k]; s++) {
                ASSERT_MSG(owner[s] == 0, "seq %lld handed out twice", (long long)s);
                owner[s] = (unsigned char)a[i].tag;
            }
        }
    }
    for (int s = 1; s <= total; s++)
        ASSERT_MSG(owner[s] != 0, "seq %d never handed out", s);
    /* the log agrees with what the callers were told */
    ASSERT_OK(store_events_since(f.s, f.session, 0, 0, &arr, &last, NULL));
    ASSERT_EQ(last, total);
    ASSERT_EQ(json_array_size(arr), total);
    for (int s = 1; s <= total; s++) {
        json_t *r = json_array_get(arr, (size_t)s - 1);
        long long tag = json_integer_value(json_object_get(json_object_get(r, "data"), "tag"));
        ASSERT_EQ(json_integer_value(json_object_get(r, "seq")), s);
        ASSERT_EQ(tag / 1000, owner[s]);
    }
    json_decref(arr);
    /* every append made one version of its view */
    ASSERT_OK(store_paintings_list(f.s, f.session, &arr, NULL));
    ASSERT_EQ(json_array_size(arr), 2);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(arr, 0), "version")),
              APPENDERS / 2 * APPENDS);
    ASSERT_EQ(json_integer_value(json_object_get(json_array_get(arr, 1), "version")),
              APPENDERS / 2 * APPENDS);
    json_decref(arr);
    fx_close(&f);
}

TEST(concurrent_appends_are_numbered_without_gaps)
{
    appends_numbered(0);
}

TEST(appends_from_several_stores_on_one_database_share_one_numbering)
{
    appends_numbered(1);
}

/* ---- a painting's decoded pixels (store_pixels.c) ------------------------------- */

/* The one blob of view `view` and its pixels' path (OUT: rel, under f->dir). */
static int pixels_rel(const fixture *f, char *rel, size_t len)
{
    char dir[64];
    json_t *names;
    size_t i;
    json_t *n;
    int found = -1;
    snprintf(dir, sizeof dir, "sessions/%s", f->session);
    if (store_blob_list(f->s, dir, &names, NULL))
        return -1;
    json_array_foreach(names, i, n) {
        const char *s = json_string_value(n);
        size_t l = strlen(s);
        if (l > 3 && strcmp(s + l - 3, ".px") == 0)
            continue;
        snprintf(rel, len, "blobs/%s/%s.px", dir, s);
        found = 0;
    }
    json_decref(names);
    return found;
}

static int flip_byte(const char *dir, const char *rel, long at)
{
    char path[1024];
    unsigned char b;
    FILE *fp;
    int rc;
    snprintf(path, sizeof path, "%s/%s", dir, rel);
    if (!(fp = fopen(path, "r+b")) || fseek(fp, at, SEEK_SET) || fread(&b, 1, 1, fp) != 1) {
        if (fp)
            fclose(fp);
        return -1;
    }
    b ^= 0x40;
    rc = fseek(fp, at, SEEK_SET) || fwrite(&b, 1, 1, fp) != 1;
    return fclose(fp) || rc ? -1 : 0;
}

TEST(a_paintings_pixels_live_and_go_with_its_blob)
{
    fixture f;
    img im, got;
    int64_t version = 0;
    char rel[256], sdir[128], orphan[256];
    glint_err e;

    ASSERT_OK(fx_open(&f));
    ASSERT_OK(img_alloc(&im, 5, 3, 3, &e));
    for (int i = 0; i < 5 * 3 * 3; i++)
        im.px[i] = 0.25f * (float)i - 1.0f;
    snprintf(sdir, sizeof sdir, "blobs/sessions/%s", f.session);
    /* none before a painting, none kept yet after it */
    ASSERT_EQ(store_painting_pixels_put(f.s, f.session, 0, 1, &im, &e), GLINT_ENOTFOUND);
    ASSERT_OK(store_painting_put(f.s, f.session, 0, exr1, sizeof exr1, &version, NULL, NULL));
    ASSERT_EQ(store_painting_pixels_get(f.s, f.session, 0, 0, &got, &version, &e),
              GLINT_ENOTFOUND);
    /* kept at the view's version only */
    ASSERT_EQ(store_painting_pixels_put(f.s, f.session, 0, 2, &im, &e), GLINT_ECONFLICT);
    ASSERT_EQ(files_in(f.dir, sdir), 1);
    ASSERT_OK(store_painting_pixels_put(f.s, f.session, 0, 1, &im, &e));
    ASSERT_EQ(files_in(f.dir, sdir), 2);
    ASSERT_OK(pixels_rel(&f, rel, sizeof rel));
    ASSERT(path_exists(f.dir, rel));
    version = 0;
    ASSERT_OK(store_painting_pixels_get(f.s, f.session, 0, 0, &got, &version, &e));
    ASSERT_EQ(version, 1);
    ASSERT(got.width == 5 && got.height == 3 && got.channels == 3);
    ASSERT(memcmp(got.px, im.px, sizeof(float) * 45) == 0);
    img_free(&got);
    /* sizes beyond the caller's bound are refused before any pixel is read */
    ASSERT_EQ(store_painting_pixels_get(f.s, f.session, 0, 4, &got, &version, &e),
              GLINT_EFORMAT);
    /* a damaged file is told, never returned */
    ASSERT_OK(flip_byte(f.dir, rel, 40));
    ASSERT_EQ(store_painting_pixels_get(f.s, f.session, 0, 0, &got, &version, &e),
              GLINT_EFORMAT);
    ASSERT(got.px == NULL);
    /* a new painting takes the old one's pixels with its blob */
    ASSERT_OK(store_painting_put(f.s, f.session, 0, exr2, sizeof exr2, &version, NULL, NULL));
    ASSERT_EQ(version, 2);
    store_reap_wait(f.s);
    ASSERT(!path_exists(f.dir, rel));
    ASSERT_EQ(files_in(f.dir, sdir), 1);
    ASSERT_EQ(store_painting_pixels_get(f.s, f.session, 0, 0, &got, &version, &e),
              GLINT_ENOTFOUND);
    ASSERT_OK(store_painting_pixels_put(f.s, f.session, 0, 2, &im, &e));
    ASSERT_OK(pixels_rel(&f, rel, sizeof rel));
    /* the sweep at open: pixels whose blob no row names go, the others stay */
    store_close(f.s);
    f.s = NULL;
    snprintf(orphan, sizeof orphan, "%s/view0-00112233aabbccdd.exr.px", sdir);
    {
        char path[512];
        FILE *fp;
        snprintf(path, sizeof path, "%s/%s", f.dir, orphan);
        ASSERT((fp = fopen(path, "wb")) != NULL);
        fputs("pixels of a blob that is gone", fp);
        fclose(fp);
    }
    if (fx_pg(&f))
        ASSERT_OK(fx_age_blobs(&f));
    ASSERT_OK(fx_store_open(&f, &f.s, NULL));
    ASSERT(!path_exists(f.dir, orphan));
    ASSERT(path_exists(f.dir, rel));
    ASSERT_OK(store_painting_pixels_get(f.s, f.session, 0, 0, &got, &version, &e));
    ASSERT_EQ(version, 2);
    ASSERT(memcmp(got.px, im.px, sizeof(float) * 45) == 0);
    img_free(&got);
    img_free(&im);
    fx_close(&f);
}

/* A replaced painting's files are removed off the commit's path, by the
 * store's removal thread: after store_reap_wait only the views' current
 * blobs (and their pixels) are left; store_close does what is queued
 * before it returns; a store that never replaces starts no thread. */
TEST(replaced_paintings_removed_off_the_commits_path)
{
    fixture f;
    img im;
    int64_t version = 0, first, last;
    char sdir[128];
    json_t *strokes = json_pack("[{s:i}]", "a", 1);
    glint_err e;

    ASSERT_OK(fx_open(&f));
    ASSERT_OK(img_alloc(&im, 2, 2, 3, &e));
    memset(im.px, 0, sizeof(float) * 12);
    snprintf(sdir, sizeof sdir, "blobs/sessions/%s", f.session);
    store_reap_wait(f.s); /* nothing queued: returns */
    for (int round = 0; round < 2; round++) {
        for (int i = 0; i < 40; i++) {
            int view = i % 3;
            if (i % 2)
                ASSERT_OK(store_painting_put(f.s, f.session, view, exr1, sizeof exr1, &version,
                                             NULL, NULL));
            else
                ASSERT_OK(store_strokes_append_at(f.s, f.session, view, -1, strokes, exr2,
                                                  sizeof exr2, &first, &last, &version, NULL));
            /* the new version's pixels, which go with its blob when replaced */
            ASSERT_OK(store_painting_pixels_put(f.s, f.session, view, version, &im, &e));
        }
        if (round == 0) {
            store_reap_wait(f.s);
        } else { /* closed with removals perhaps still queued: done before it returns */
            store_close(f.s);
            f.s = NULL;
        }
        ASSERT_EQ(files_in(f.dir, sdir), 3 * 2); /* three views: a blob and its pixels each */
    }
    ASSERT_OK(fx_store_open(&f, &f.s, NULL));
    ASSERT_EQ(files_in(f.dir, sdir), 3 * 2);
    json_decref(strokes);
    img_free(&im);
    fx_close(&f);
}

TEST_LIST{
    TEST_ENTRY(painting_versions_and_seq),
    TEST_ENTRY(strokes_and_events_share_one_numbering),
    TEST_ENTRY(paging_strokes_and_events),
    TEST_ENTRY(pages_are_bounded_by_bytes),
    TEST_ENTRY(session_that_does_not_exist),
    TEST_ENTRY(a_material_and_its_event_commit_together),
    TEST_ENTRY(scene_delete_removes_sessions_logs_and_blobs),
    TEST_ENTRY(strokes_on_a_stale_image_are_refused),
    TEST_ENTRY(concurrent_appends_are_numbered_without_gaps),
    TEST_ENTRY(appends_from_several_stores_on_one_database_share_one_numbering),
    TEST_ENTRY(a_paintings_pixels_live_and_go_with_its_blob),
    TEST_ENTRY(replaced_paintings_removed_off_the_commits_path),
};

TEST_MAIN()
