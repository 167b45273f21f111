/* Tests of glintd's memo (server/memo.h): decoded paintings by (session,
 * view, version) with replacement by newer versions, LRU eviction under the
 * byte budget and pins that outlive eviction; material documents kept as
 * copies under their own budget.  Pixels of pinned images are read in full
 * after they left the cache, so a sanitizer build catches an early free. */
#include <pthread.h>
#include <stdatomic.h>

#include "check.h"
#include "clock.h"
#include "memo.h"

#define W 8
#define H 8
#define C 3
#define IMG_BYTES ((size_t)W * H * C * sizeof(float))

static const char S1[] = "0123456789abcdef0123456789abcdef";
static const char S2[] = "fedcba9876543210fedcba9876543210";

/* An image whose every pixel holds `value` + its index. */
static int make(img *im, float value)
{
    int rc = img_alloc(im, W, H, C, NULL);
    if (rc)
        return rc;
    for (int i = 0; i < W * H * C; i++)
        im->px[i] = value + (float)i;
    return 0;
}

/* 1 when every pixel of the image is what make(value) wrote. */
static int holds(const img *im, float value)
{
    if (!im || im->width != W || im->height != H || im->channels != C || !im->px)
        return 0;
    for (int i = 0; i < W * H * C; i++)
        if (im->px[i] != value + (float)i)
            return 0;
    return 1;
}

/* 1 when (session, view, version) is cached and holds `value`. */
static int cached(memo *m, const char *session, int view, long long version, float value)
{
    memo_painting *p;
    int ok;
    if (memo_painting_get(m, session, view, version, &p))
        return 0;
    ok = holds(memo_painting_img(p), value);
    memo_painting_release(m, p);
    return ok;
}

static int offer(memo *m, const char *session, int view, long long version, float value)
{
    img im;
    int rc = make(&im, value);
    if (rc)
        return rc;
    memo_painting_offer(m, session, view, version, &im);
    img_free(&im);
    return 0;
}

/* The value of the sample line that starts with `sample` in memo_metrics'
 * text (-1 when there is none). */
static long long metric(memo *m, const char *sample)
{
    char *text = NULL, *at;
    size_t len = 0;
    long long v = -1;
    FILE *f = open_memstream(&text, &len);
    if (!f)
        return -1;
    memo_metrics(m, f);
    fclose(f);
    for (at = text; at && *at; at = strchr(at, '\n') ? strchr(at, '\n') + 1 : NULL)
        if (strncmp(at, sample, strlen(sample)) == 0) {
            v = strtoll(at + strlen(sample), NULL, 10);
            break;
        }
    free(text);
    return v;
}

TEST(put_and_get_by_session_view_version)
{
    memo *m;
    img im;
    memo_painting *p, *q;
    ASSERT_OK(memo_open(10 * IMG_BYTES, 4096, &m, NULL));
    ASSERT_OK(make(&im, 1.0f));
    ASSERT_OK(memo_painting_put(m, S1, 2, 7, &im, &p));
    ASSERT(im.px == NULL); /* taken over */
    ASSERT(holds(memo_painting_img(p), 1.0f));
    ASSERT_OK(memo_painting_get(m, S1, 2, 7, &q));
    ASSERT(memo_painting_img(q)->px == memo_painting_img(p)->px); /* shared, no copy */
    memo_painting_release(m, q);
    memo_painting_release(m, p);
    /* only the exact key */
    q = (memo_painting *)(void *)&im;
    ASSERT_EQ(memo_painting_get(m, S1, 2, 6, &q), GLINT_ENOTFOUND);
    ASSERT(q == NULL);
    ASSERT_EQ(memo_painting_get(m, S1, 2, 8, &q), GLINT_ENOTFOUND);
    ASSERT_EQ(memo_painting_get(m, S1, 3, 7, &q), GLINT_ENOTFOUND);
    ASSERT_EQ(memo_painting_get(m, S2, 2, 7, &q), GLINT_ENOTFOUND);
    /* an offered image is copied: the caller's stays the caller's */
    ASSERT_OK(make(&im, 5.0f));
    memo_painting_offer(m, S2, 2, 1, &im);
    im.px[0] = -1.0f;
    ASSERT(cached(m, S2, 2, 1, 5.0f));
    img_free(&im);
    ASSERT(cached(m, S1, 2, 7, 1.0f));
    ASSERT_EQ(metric(m, "glintd_painting_cache_bytes "), 2 * IMG_BYTES);
    ASSERT_EQ(metric(m, "glintd_painting_cache_total{outcome=\"hit\"} "), 3);
    ASSERT_EQ(metric(m, "glintd_painting_cache_total{outcome=\"miss\"} "), 4);
    memo_painting_release(m, NULL);
    memo_close(m);
    memo_close(NULL);
}

TEST(newer_version_replaces_older_never_the_reverse)
{
    memo *m;
    img im;
    memo_painting *p;
    ASSERT_OK(memo_open(10 * IMG_BYTES, 4096, &m, NULL));
    ASSERT_OK(offer(m, S1, 0, 1, 1.0f));
    ASSERT_OK(offer(m, S1, 0, 2, 2.0f));
    ASSERT(!cached(m, S1, 0, 1, 1.0f));
    ASSERT(cached(m, S1, 0, 2, 2.0f));
    ASSERT_EQ(metric(m, "glintd_painting_cache_bytes "), IMG_BYTES);
    /* an older version offered late does not replace the newer one */
    ASSERT_OK(offer(m, S1, 0, 1, 1.0f));
    ASSERT(cached(m, S1, 0, 2, 2.0f));
    ASSERT(!cached(m, S1, 0, 1, 1.0f));
    /* nor does the same version again */
    ASSERT_OK(offer(m, S1, 0, 2, 9.0f));
    ASSERT(cached(m, S1, 0, 2, 2.0f));
    /* a put of an older version hands back its own image, pinned, unlisted */
    ASSERT_OK(make(&im, 1.5f));
    ASSERT_OK(memo_painting_put(m, S1, 0, 1, &im, &p));
    ASSERT(holds(memo_painting_img(p), 1.5f));
    ASSERT(!cached(m, S1, 0, 1, 1.5f));
    ASSERT(cached(m, S1, 0, 2, 2.0f));
    memo_painting_release(m, p);
    /* other views and sessions are separate */
    ASSERT_OK(offer(m, S1, 1, 1, 3.0f));
    ASSERT_OK(offer(m, S2, 0, 1, 4.0f));
    ASSERT(cached(m, S1, 0, 2, 2.0f));
    ASSERT(cached(m, S1, 1, 1, 3.0f));
    ASSERT(cached(m, S2, 0, 1, 4.0f));
    ASSERT_EQ(metric(m, "glintd_painting_cache_bytes "), 3 * IMG_BYTES);
    memo_close(m);
}

TEST(least_recently_used_painting_is_evicted)
{
    memo *m;
    ASSERT_OK(memo_open(3 * IMG_BYTES, 4096, &m, NULL));
    ASSERT_OK(offer(m, S1, 0, 1, 10.0f));
    ASSERT_OK(offer(m, S1, 1, 1, 11.0f));
    ASSERT_OK(offer(m, S1, 2, 1, 12.0f));
    ASSERT_EQ(metric(m, "glintd_painting_cache_bytes "), 3 * IMG_BYTES);
    ASSERT(cached(m, S1, 0, 1, 10.0f)); /* view 0 used: view 1 is the oldest now */
    ASSERT_OK(offer(m, S1, 3, 1, 13.0f));
    ASSERT(!cached(m, S1, 1, 1, 11.0f));
    ASSERT(cached(m, S1, 0, 1, 10.0f));
    ASSERT(cached(m, S1, 2, 1, 12.0f));
    ASSERT(cached(m, S1, 3, 1, 13.0f));
    ASSERT_EQ(metric(m, "glintd_painting_cache_bytes "), 3 * IMG_BYTES);
    /* order of use now 3, 2, 0 (oldest): two more push out 0 and 2 */
    ASSERT_OK(offer(m, S2, 0, 1, 20.0f));
    ASSERT_OK(offer(m, S2, 1, 1, 21.0f));
    ASSERT(!cached(m, S1, 0, 1, 10.0f));
    ASSERT(!cached(m, S1, 2, 1, 12.0f));
    ASSERT(cached(m, S1, 3, 1, 13.0f));
    ASSERT(cached(m, S2, 0, 1, 20.0f));
    ASSERT(cached(m, S2, 1, 1, 21.0f));
    ASSERT_LE(metric(m, "glintd_painting_cache_bytes "), 3 * IMG_BYTES);
    memo_close(m);
}

TEST(pinned_image_outlives_eviction_and_replacement)
{
    memo *m;
    img im;
    memo_painting *evicted, *replaced, *again;
    ASSERT_OK(memo_open(2 * IMG_BYTES, 4096, &m, NULL));
    ASSERT_OK(make(&im, 100.0f));
    ASSERT_OK(memo_painting_put(m, S1, 0, 1, &im, &evicted));
    ASSERT_OK(offer(m, S1, 1, 1, 101.0f));
    ASSERT_OK(memo_painting_get(m, S1, 1, 1, &replaced));
    ASSERT_OK(memo_painting_get(m, S1, 1, 1, &again)); /* two pins on one image */
    /* push view 0 out, replace view 1 */
    ASSERT_OK(offer(m, S2, 0, 1, 102.0f));
    ASSERT(!cached(m, S1, 0, 1, 100.0f));
    ASSERT_OK(offer(m, S1, 1, 2, 103.0f));
    ASSERT(!cached(m, S1, 1, 1, 101.0f));
    ASSERT(cached(m, S1, 1, 2, 103.0f));
    /* the pinned images are intact (every float read) */
    ASSERT(holds(memo_painting_img(evicted), 100.0f));
    ASSERT(holds(memo_painting_img(replaced), 101.0f));
    memo_painting_release(m, replaced);
    ASSERT(holds(memo_painting_img(again), 101.0f)); /* the second pin still holds it */
    memo_painting_release(m, again);
    /* evicted images count no more against the budget */
    ASSERT_LE(metric(m, "glintd_painting_cache_bytes "), 2 * IMG_BYTES);
    ASSERT(holds(memo_painting_img(evicted), 100.0f));
    memo_painting_release(m, evicted);
    memo_close(m);
}

TEST(image_larger_than_budget_is_refused)
{
    memo *m;
    img im;
    memo_painting *p = (memo_painting *)(void *)&im;
    ASSERT_OK(memo_open(IMG_BYTES - 1, 4096, &m, NULL));
    ASSERT_OK(make(&im, 7.0f));
    ASSERT_EQ(memo_painting_put(m, S1, 0, 1, &im, &p), GLINT_ETOOBIG);
    ASSERT(p == NULL);
    ASSERT(holds(&im, 7.0f)); /* left to the caller */
    memo_painting_offer(m, S1, 0, 1, &im);
    ASSERT(!cached(m, S1, 0, 1, 7.0f));
    ASSERT_EQ(metric(m, "glintd_painting_cache_bytes "), 0);
    img_free(&im);
    memo_close(m);
    /* exactly the budget fits */
    ASSERT_OK(memo_open(IMG_BYTES, 4096, &m, NULL));
    ASSERT_OK(make(&im, 7.0f));
    ASSERT_OK(memo_painting_put(m, S1, 0, 1, &im, &p));
    memo_painting_release(m, p);
    ASSERT(cached(m, S1, 0, 1, 7.0f));
    memo_close(m);
}

/* Readers pin the newest version, read it twice and release it, while the
 * writer offers newer versions and other views push images out. */
typedef struct race {
    memo *m;
    atomic_int stop;
    atomic_llong latest;
    atomic_long reads, bad;
} race;

static void *race_reader(void *arg)
{
    race *r = arg;
    while (!atomic_load(&r->stop)) {
        long long v = atomic_load(&r->latest);
        memo_painting *p;
        if (v > 0 && memo_painting_get(r->m, S1, 0, v, &p) == 0) {
            if (!holds(memo_painting_img(p), (float)v) || !holds(memo_painting_img(p), (float)v))
                atomic_fetch_add(&r->bad, 1);
            atomic_fetch_add(&r->reads, 1);
            memo_painting_release(r->m, p);
        }
    }
    return NULL;
}

TEST(pins_across_threads)
{
    race r;
    pthread_t t[2];
    double end = glint_now() + 10.0;
    memset(&r, 0, sizeof r);
    ASSERT_OK(memo_open(3 * IMG_BYTES, 4096, &r.m, NULL));
    for (int i = 0; i < 2; i++)
        ASSERT_EQ(pthread_create(&t[i], NULL, race_reader, &r), 0);
    /* at least 2000 versions, and on until the readers have pinned some */
    for (long long v = 1; v <= 2000 || atomic_load(&r.reads) < 200; v++) {
        if (glint_now() > end)
            break;
        ASSERT_OK(offer(r.m, S1, 0, v, (float)v));
        atomic_store(&r.latest, v);
        if (v % 3 == 0)
            ASSERT_OK(offer(r.m, S2, (int)(v % 7), v, 0.0f));
    }
    atomic_store(&r.stop, 1);
    for (int i = 0; i < 2; i++)
        pthread_join(t[i], NULL);
    ASSERT_EQ(atomic_load(&r.bad), 0);
    ASSERT_LE(200, atomic_load(&r.reads));
    memo_close(r.m);
}

/* ---- material documents -------------------------------------------------------- */

TEST(document_put_get_returns_a_copy)
{
    memo *m;
    memo_doc d, d2;
    static const char text[] = "{\"id\":\"m1\",\"rms\":0.25}";
    char buf[sizeof text];
    ASSERT_OK(memo_open(4096, 4096, &m, NULL));
    memcpy(buf, text, sizeof text);
    memo_doc_put(m, "m1", S1, S2, buf, sizeof text - 1);
    memset(buf, 'x', sizeof buf - 1); /* the caller's text is not kept */
    ASSERT_OK(memo_doc_get(m, "m1", &d));
    ASSERT_EQ(d.len, sizeof text - 1);
    ASSERT(strcmp(d.text, text) == 0);
    ASSERT(strcmp(d.session, S1) == 0);
    ASSERT(strcmp(d.scene, S2) == 0);
    d.text[1] = 'X'; /* the copy is the caller's */
    ASSERT_OK(memo_doc_get(m, "m1", &d2));
    ASSERT(d2.text != d.text);
    ASSERT(strcmp(d2.text, text) == 0);
    free(d.text);
    free(d2.text);
    /* a second put of an id is ignored */
    memo_doc_put(m, "m1", S2, S1, "{}", 2);
    ASSERT_OK(memo_doc_get(m, "m1", &d));
    ASSERT(strcmp(d.text, text) == 0);
    ASSERT(strcmp(d.session, S1) == 0);
    free(d.text);
    /* no session or scene: empty strings */
    memo_doc_put(m, "m2", NULL, NULL, "[]", 2);
    ASSERT_OK(memo_doc_get(m, "m2", &d));
    ASSERT(d.session[0] == '\0' && d.scene[0] == '\0');
    free(d.text);
    d.text = (char *)buf;
    ASSERT_EQ(memo_doc_get(m, "m3", &d), GLINT_ENOTFOUND);
    ASSERT(d.text == NULL);
    ASSERT_EQ(metric(m, "glintd_material_doc_cache_total{outcome=\"hit\"} "), 4);
    ASSERT_EQ(metric(m, "glintd_material_doc_cache_total{outcome=\"miss\"} "), 1);
    memo_close(m);
}

/* Documents of DOC_LEN bytes; the budget holds three with room for each
 * entry's bookkeeping (which is far below DOC_LEN / 10). */
#define DOC_LEN 4000
#define DOC_BUDGET (3 * DOC_LEN + 3 * (DOC_LEN / 10))

static void doc_put(memo *m, const char *id, char fill)
{
    static char text[DOC_LEN];
    memset(text, fill, sizeof text);
    memo_doc_put(m, id, S1, S2, text, sizeof text);
}

static int doc_has(memo *m, const char *id, char fill)
{
    memo_doc d;
    int ok;
    if (memo_doc_get(m, id, &d))
        return 0;
    ok = d.len == DOC_LEN && d.text[0] == fill && d.text[DOC_LEN - 1] == fill &&
         d.text[DOC_LEN] == '\0';
    free(d.text);
    return ok;
}

TEST(least_recently_used_document_is_evicted)
{
    memo *m;
    ASSERT_OK(memo_open(4096, DOC_BUDGET, &m, NULL));
    doc_put(m, "a", 'a');
    doc_put(m, "b", 'b');
    doc_put(m, "c", 'c');
    ASSERT(doc_has(m, "a", 'a')); /* "b" is the oldest now */
    doc_put(m, "d", 'd');
    ASSERT(!doc_has(m, "b", 'b'));
    ASSERT(doc_has(m, "a", 'a'));
    ASSERT(doc_has(m, "c", 'c'));
    ASSERT(doc_has(m, "d", 'd'));
    doc_put(m, "e", 'e'); /* order of use d, c, a: "a" goes */
    ASSERT(!doc_has(m, "a", 'a'));
    ASSERT(doc_has(m, "c", 'c') && doc_has(m, "d", 'd') && doc_has(m, "e", 'e'));
    memo_close(m);
    /* a document larger than the whole budget is not kept */
    ASSERT_OK(memo_open(4096, DOC_LEN, &m, NULL));
    doc_put(m, "a", 'a');
    ASSERT(!doc_has(m, "a", 'a'));
    memo_close(m);
}

TEST_LIST{
    TEST_ENTRY(put_and_get_by_session_view_version),
    TEST_ENTRY(newer_version_replaces_older_never_the_reverse),
    TEST_ENTRY(least_recently_used_painting_is_evicted),
    TEST_ENTRY(pinned_image_outlives_eviction_and_replacement),
    TEST_ENTRY(image_larger_than_budget_is_refused),
    TEST_ENTRY(pins_across_threads),
    TEST_ENTRY(document_put_get_returns_a_copy),
    TEST_ENTRY(least_recently_used_document_is_evicted),
};

TEST_MAIN()
