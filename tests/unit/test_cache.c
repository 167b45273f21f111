/* Tests of the precomputation cache (core/cache): keys, LRU eviction under
 * a byte budget, pinning by holders and by children, single flight,
 * failures, and the disk layer (load, save, corrupt files rebuilt). */
#include <pthread.h>
#include <stdatomic.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cache.h"
#include "check.h"
#include "fsio.h"

/* A value: a malloc'ed int; frees are counted. */
static atomic_int builds, frees, loads, saves;

typedef struct ctx {
    int value;
    size_t bytes;
    int fail;              /* build returns this code */
    double sleep_s;        /* build takes this long */
} ctx;

static void value_free(void *data)
{
    atomic_fetch_add(&frees, 1);
    free(data);
}

static int build(void *c, cache_value *out, glint_err *err)
{
    ctx *x = c;
    int *v;
    atomic_fetch_add(&builds, 1);
    if (x->sleep_s > 0)
        usleep((useconds_t)(x->sleep_s * 1e6));
    if (x->fail)
        return glint_err_set(err, x->fail, "build failed on purpose (%d)", x->value);
    v = malloc(sizeof *v);
    *v = x->value;
    out->data = v;
    out->bytes = x->bytes;
    out->free = value_free;
    return 0;
}

static const cache_level L = {.name = "test", .build = build};

static void reset(void)
{
    builds = frees = loads = saves = 0;
}

static int get(cache *c, const char *key, int value, size_t bytes, cache_entry *parent,
               cache_entry **e, cache_how *how)
{
    ctx x = {value, bytes, 0, 0};
    return cache_acquire(c, &L, key, &x, parent, e, how, NULL, NULL);
}

TEST(hit_after_build_and_same_value)
{
    cache *c;
    cache_entry *a, *b;
    cache_how how;
    reset();
    ASSERT_OK(cache_open(NULL, 1000, &c, NULL));
    ASSERT_OK(get(c, "k1", 7, 10, NULL, &a, &how));
    ASSERT_EQ(how, CACHE_BUILT);
    ASSERT_EQ(*(const int *)cache_data(a), 7);
    ASSERT_OK(get(c, "k1", 99, 10, NULL, &b, &how)); /* the key decides, not the ctx */
    ASSERT_EQ(how, CACHE_HIT);
    ASSERT(a == b);
    ASSERT_EQ(*(const int *)cache_data(b), 7);
    ASSERT_EQ(builds, 1);
    cache_release(c, a);
    cache_release(c, b);
    cache_close(c);
    ASSERT_EQ(frees, 1);
}

TEST(lru_eviction_under_budget)
{
    cache *c;
    cache_entry *e;
    cache_stats st;
    reset();
    ASSERT_OK(cache_open(NULL, 30, &c, NULL));
    for (int i = 0; i < 3; i++) { /* a, b, c: 30 bytes, fits */
        char k[8] = {(char)('a' + i), 0};
        ASSERT_OK(get(c, k, i, 10, NULL, &e, NULL));
        cache_release(c, e);
    }
    cache_stats_get(c, &st);
    ASSERT_EQ(st.bytes, 30);
    ASSERT_EQ(frees, 0);
    ASSERT_OK(cache_find(c, "a", &e)); /* a becomes the most recent: b is the oldest */
    cache_hit(c, e);
    cache_release(c, e);
    ASSERT_OK(get(c, "d", 3, 10, NULL, &e, NULL));
    cache_release(c, e);
    ASSERT_EQ(frees, 1);
    ASSERT_EQ(cache_find(c, "b", &e), GLINT_ENOTFOUND);
    ASSERT_OK(cache_find(c, "a", &e));
    cache_release(c, e);
    ASSERT_OK(cache_find(c, "c", &e));
    cache_release(c, e);
    cache_stats_get(c, &st);
    ASSERT_EQ(st.bytes, 30);
    ASSERT_EQ(st.level[0].evictions, 1);
    cache_close(c);
    ASSERT_EQ(frees, 4);
}

TEST(pinned_entries_are_never_evicted)
{
    cache *c;
    cache_entry *big, *e;
    cache_stats st;
    reset();
    ASSERT_OK(cache_open(NULL, 10, &c, NULL));
    ASSERT_OK(get(c, "big", 1, 50, NULL, &big, NULL)); /* over budget but held */
    cache_stats_get(c, &st);
    ASSERT_EQ(st.bytes, 50);
    ASSERT_OK(cache_find(c, "big", &e));
    ASSERT(e == big);
    cache_release(c, e);
    ASSERT_EQ(frees, 0);
    cache_release(c, big); /* the last holder: now it goes */
    ASSERT_EQ(frees, 1);
    cache_stats_get(c, &st);
    ASSERT_EQ(st.bytes, 0);
    ASSERT_EQ(st.entries, 0);
    cache_close(c);
}

TEST(children_pin_their_parents)
{
    cache *c;
    cache_entry *p, *ch, *e;
    reset();
    ASSERT_OK(cache_open(NULL, 5, &c, NULL));
    ASSERT_OK(get(c, "parent", 1, 10, NULL, &p, NULL));
    ASSERT_OK(get(c, "child", 2, 10, p, &ch, NULL));
    ASSERT(cache_parent(ch) == p);
    cache_release(c, p); /* the child still holds it */
    ASSERT_EQ(frees, 0);
    ASSERT_OK(cache_find(c, "parent", &e));
    cache_release(c, e);
    cache_release(c, ch); /* 20 bytes > 5: the child goes, then its parent */
    ASSERT_EQ(frees, 2);
    cache_close(c);
    /* with room for the parent alone, only the child goes */
    reset();
    ASSERT_OK(cache_open(NULL, 15, &c, NULL));
    ASSERT_OK(get(c, "parent", 1, 10, NULL, &p, NULL));
    ASSERT_OK(get(c, "child", 2, 10, p, &ch, NULL));
    cache_release(c, p);
    cache_release(c, ch);
    ASSERT_EQ(frees, 1);
    ASSERT_EQ(cache_find(c, "child", &e), GLINT_ENOTFOUND);
    ASSERT_OK(cache_find(c, "parent", &e));
    cache_release(c, e);
    cache_close(c);
    ASSERT_EQ(frees, 2);
}

TEST(budget_zero_keeps_only_what_is_held)
{
    cache *c;
    cache_entry *e;
    reset();
    ASSERT_OK(cache_open(NULL, 0, &c, NULL));
    ASSERT_OK(get(c, "x", 1, 1, NULL, &e, NULL));
    ASSERT_EQ(frees, 0);
    cache_release(c, e);
    ASSERT_EQ(frees, 1);
    ASSERT_EQ(cache_find(c, "x", &e), GLINT_ENOTFOUND);
    cache_close(c);
}

TEST(failed_builds_are_not_kept)
{
    cache *c;
    cache_entry *e;
    cache_stats st;
    glint_err err;
    ctx bad = {5, 10, GLINT_ENUMERIC, 0};
    reset();
    ASSERT_OK(cache_open(NULL, 100, &c, NULL));
    ASSERT_EQ(cache_acquire(c, &L, "k", &bad, NULL, &e, NULL, NULL, &err), GLINT_ENUMERIC);
    ASSERT(e == NULL);
    ASSERT(strstr(err.msg, "on purpose") != NULL);
    ASSERT_EQ(cache_find(c, "k", &e), GLINT_ENOTFOUND);
    ASSERT_OK(get(c, "k", 6, 10, NULL, &e, NULL)); /* a later request tries again */
    ASSERT_EQ(*(const int *)cache_data(e), 6);
    cache_release(c, e);
    cache_stats_get(c, &st);
    ASSERT_EQ(st.level[0].failures, 1);
    ASSERT_EQ(st.level[0].builds, 2);
    cache_close(c);
}

TEST(keys_are_checked)
{
    cache *c;
    cache_entry *e;
    char longkey[CACHE_KEY_MAX + 1];
    memset(longkey, 'a', CACHE_KEY_MAX);
    longkey[CACHE_KEY_MAX] = '\0';
    ASSERT_OK(cache_open(NULL, 100, &c, NULL));
    ASSERT_EQ(get(c, "", 1, 1, NULL, &e, NULL), GLINT_ERANGE);
    ASSERT_EQ(get(c, longkey, 1, 1, NULL, &e, NULL), GLINT_ERANGE);
    cache_close(c);
}

/* ---- single flight -------------------------------------------------------------- */

typedef struct racer {
    cache *c;
    pthread_barrier_t *bar;
    int fail;
    cache_entry *e;
    cache_how how;
    int rc;
    glint_err err;
} racer;

static void *race(void *arg)
{
    racer *r = arg;
    ctx x = {42, 10, r->fail, 0.2};
    pthread_barrier_wait(r->bar);
    r->rc = cache_acquire(r->c, &L, "slow", &x, NULL, &r->e, &r->how, NULL, &r->err);
    return NULL;
}

static void run_race(int fail, racer *r, int n)
{
    pthread_t t[8];
    pthread_barrier_t bar;
    cache *c;
    cache_open(NULL, 100, &c, NULL);
    pthread_barrier_init(&bar, NULL, (unsigned)n);
    for (int i = 0; i < n; i++) {
        memset(&r[i], 0, sizeof r[i]);
        r[i].c = c;
        r[i].bar = &bar;
        r[i].fail = fail;
        pthread_create(&t[i], NULL, race, &r[i]);
    }
    for (int i = 0; i < n; i++)
        pthread_join(t[i], NULL);
    pthread_barrier_destroy(&bar);
    for (int i = 0; i < n; i++)
        cache_release(c, r[i].e);
    cache_close(c);
}

TEST(single_flight_builds_once)
{
    racer r[8];
    int built = 0, joined = 0;
    reset();
    run_race(0, r, 8);
    ASSERT_EQ(builds, 1);
    for (int i = 0; i < 8; i++) {
        ASSERT_EQ(r[i].rc, 0);
        built += r[i].how == CACHE_BUILT;
        joined += r[i].how == CACHE_JOINED;
    }
    ASSERT_EQ(built, 1);
    ASSERT_EQ(built + joined, 8); /* all started within the 0.2 s build */
    ASSERT_EQ(frees, 1);
}

TEST(single_flight_shares_the_error)
{
    racer r[4];
    reset();
    run_race(GLINT_EIO, r, 4);
    ASSERT_EQ(builds, 1);
    for (int i = 0; i < 4; i++) {
        ASSERT_EQ(r[i].rc, GLINT_EIO);
        ASSERT(r[i].e == NULL);
        ASSERT(strstr(r[i].err.msg, "on purpose") != NULL);
    }
}

/* ---- disk layer ------------------------------------------------------------------- */

static int disk_load(void *c, const char *dir, const char *key, cache_value *out,
                     glint_err *err)
{
    char path[512], *text = NULL;
    size_t len;
    int rc, *v;
    (void)c;
    atomic_fetch_add(&loads, 1);
    snprintf(path, sizeof path, "%s/%s.txt", dir, key);
    if ((rc = fsio_read_all(path, 64, &text, &len, err)))
        return rc;
    if (len < 2 || text[0] != 'v') {
        free(text);
        return glint_err_set(err, GLINT_EFORMAT, "%s is corrupt", path);
    }
    v = malloc(sizeof *v);
    *v = atoi(text + 1);
    free(text);
    out->data = v;
    out->bytes = 4;
    out->free = value_free;
    return 0;
}

static int disk_save(void *c, const char *dir, const char *key, const cache_value *v,
                     glint_err *err)
{
    char path[512], text[32];
    (void)c;
    atomic_fetch_add(&saves, 1);
    if (fsio_mkdirs(dir, err))
        return GLINT_EIO;
    snprintf(path, sizeof path, "%s/%s.txt", dir, key);
    snprintf(text, sizeof text, "v%d", *(const int *)v->data);
    return fsio_write_atomic(path, text, strlen(text), err);
}

static const cache_level LD = {.name = "disk", .build = build, .load = disk_load,
                               .save = disk_save};

TEST(disk_layer_saves_loads_and_rebuilds_corrupt_files)
{
    char dir[] = "/tmp/glint-cache-XXXXXX", path[512];
    cache *c;
    cache_entry *e;
    ctx x = {17, 4, 0, 0};
    FILE *f;
    reset();
    ASSERT(mkdtemp(dir));
    ASSERT_OK(cache_open(dir, 0, &c, NULL));
    ASSERT_OK(cache_acquire(c, &LD, "key1", &x, NULL, &e, NULL, NULL, NULL));
    ASSERT_EQ(cache_disk_of(e), CACHE_DISK_BUILT);
    ASSERT_EQ(builds, 1);
    ASSERT_EQ(saves, 1);
    cache_release(c, e); /* budget 0: gone from memory, kept on disk */
    x.value = 99;
    ASSERT_OK(cache_acquire(c, &LD, "key1", &x, NULL, &e, NULL, NULL, NULL));
    ASSERT_EQ(cache_disk_of(e), CACHE_DISK_LOADED);
    ASSERT_EQ(*(const int *)cache_data(e), 17);
    ASSERT_EQ(builds, 1);
    cache_release(c, e);
    snprintf(path, sizeof path, "%s/key1.txt", dir);
    f = fopen(path, "w");
    fputs("garbage", f);
    fclose(f);
    ASSERT_OK(cache_acquire(c, &LD, "key1", &x, NULL, &e, NULL, NULL, NULL));
    ASSERT_EQ(cache_disk_of(e), CACHE_DISK_REBUILT);
    ASSERT_EQ(*(const int *)cache_data(e), 99);
    ASSERT_EQ(builds, 2);
    cache_release(c, e);
    {
        cache_stats st;
        cache_stats_get(c, &st);
        ASSERT_EQ(st.level[0].disk_builds, 1);
        ASSERT_EQ(st.level[0].disk_loads, 1);
        ASSERT_EQ(st.level[0].disk_rebuilds, 1);
    }
    cache_close(c);
    /* without a directory the disk layer is off */
    ASSERT_OK(cache_open(NULL, 0, &c, NULL));
    ASSERT_OK(cache_acquire(c, &LD, "key1", &x, NULL, &e, NULL, NULL, NULL));
    ASSERT_EQ(cache_disk_of(e), CACHE_DISK_OFF);
    cache_release(c, e);
    cache_close(c);
    unlink(path);
    rmdir(dir);
}

TEST_LIST{
    TEST_ENTRY(hit_after_build_and_same_value),
    TEST_ENTRY(lru_eviction_under_budget),
    TEST_ENTRY(pinned_entries_are_never_evicted),
    TEST_ENTRY(children_pin_their_parents),
    TEST_ENTRY(budget_zero_keeps_only_what_is_held),
    TEST_ENTRY(failed_builds_are_not_kept),
    TEST_ENTRY(keys_are_checked),
    TEST_ENTRY(single_flight_builds_once),
    TEST_ENTRY(single_flight_shares_the_error),
    TEST_ENTRY(disk_layer_saves_loads_and_rebuilds_corrupt_files),
};

TEST_MAIN()
