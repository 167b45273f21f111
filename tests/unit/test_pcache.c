/* Tests of the on-disk precomputation cache (core/pcache). */
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "pcache.h"
#include "sphere_fixture.h"

static char dir[256];
static samples S;
static hf_design D;

static int setup(void)
{
    double dirs[12][3];
    gbuf g[12];
    if (dir[0])
        return 0;
    snprintf(dir, sizeof dir, "/tmp/glint-pcache-XXXXXX");
    if (!mkdtemp(dir))
        return -1;
    fixture_ico(dirs);
    if (fixture_sphere_gbufs(g, 12, (const double(*)[3])dirs, 20, 70, 24, 24))
        return -1;
    if (samples_build(g, NULL, 12, NULL, "00000000000000000000000000000000", &S, NULL))
        return -1;
    for (int v = 0; v < 12; v++)
        gbuf_free(&g[v]);
    return hf_design_build(&S, 16, &D, NULL);
}

static void flip_byte(const char *path, long off)
{
    FILE *f = fopen(path, "r+b");
    int c;
    fseek(f, off, off < 0 ? SEEK_END : SEEK_SET);
    c = fgetc(f);
    fseek(f, -1, SEEK_CUR);
    fputc(c ^ 0x5a, f);
    fclose(f);
}

TEST(round_trip_is_bit_identical)
{
    hf_decomp a, b;
    char key[33];
    glint_err e;
    ASSERT_OK(setup());
    ASSERT_OK(hf_decomp_build(&D, 0.1, HF_ROUTE_EIG, 0, &a, &e));
    pcache_key_hf(S.hash, 16, 0.1, HF_ROUTE_EIG, 0, key);
    ASSERT_OK(pcache_decomp_save(dir, key, &a, &e));
    ASSERT_OK(pcache_decomp_load(dir, key, &b, &e));
    ASSERT_EQ(a.rank, b.rank);
    ASSERT_EQ(a.n, b.n);
    ASSERT_EQ(a.nsamples, b.nsamples);
    ASSERT(memcmp(a.s, b.s, (size_t)a.rank * sizeof(double)) == 0);
    ASSERT(memcmp(a.V, b.V, (size_t)a.rank * a.n * sizeof(double)) == 0);
    ASSERT_EQ(pcache_decomp_bytes(&a), (size_t)a.rank * 8 * (1 + a.n));
    hf_decomp_free(&a);
    hf_decomp_free(&b);
}

TEST(keys_depend_on_every_parameter)
{
    char k0[33], k[33];
    const char *h2 = "11111111111111111111111111111111";
    pcache_key_hf("00000000000000000000000000000000", 64, 0.1, HF_ROUTE_EIG, 0, k0);
    ASSERT_EQ(strlen(k0), 32);
    pcache_key_hf("00000000000000000000000000000000", 64, 0.1, HF_ROUTE_EIG, 0, k);
    ASSERT(strcmp(k, k0) == 0);
    pcache_key_hf(h2, 64, 0.1, HF_ROUTE_EIG, 0, k);
    ASSERT(strcmp(k, k0) != 0);
    pcache_key_hf("00000000000000000000000000000000", 32, 0.1, HF_ROUTE_EIG, 0, k);
    ASSERT(strcmp(k, k0) != 0);
    pcache_key_hf("00000000000000000000000000000000", 64, 0.2, HF_ROUTE_EIG, 0, k);
    ASSERT(strcmp(k, k0) != 0);
    pcache_key_hf("00000000000000000000000000000000", 64, 0.1, HF_ROUTE_SVD, 0, k);
    ASSERT(strcmp(k, k0) != 0);
    pcache_key_hf("00000000000000000000000000000000", 64, 0.1, HF_ROUTE_EIG, 1e-8, k);
    ASSERT(strcmp(k, k0) != 0);
    /* rcond 0 means the default: same key as spelling the default out */
    pcache_key_hf("00000000000000000000000000000000", 64, 0.1, HF_ROUTE_EIG,
                  hf_rcond_default(HF_ROUTE_EIG), k);
    ASSERT(strcmp(k, k0) == 0);
}

TEST(corrupt_files_are_detected)
{
    hf_decomp a, b;
    char key[33], path[512];
    glint_err e;
    struct stat st;
    ASSERT_OK(setup());
    ASSERT_OK(hf_decomp_build(&D, 0.3, HF_ROUTE_EIG, 0, &a, &e));
    pcache_key_hf(S.hash, 16, 0.3, HF_ROUTE_EIG, 0, key);
    ASSERT_OK(pcache_path(dir, key, path, sizeof path, &e));
    /* a flipped byte in the payload, in the header, in the checksum */
    const long offsets[] = {200, 20, -3};
    for (int i = 0; i < 3; i++) {
        ASSERT_OK(pcache_decomp_save(dir, key, &a, &e));
        flip_byte(path, offsets[i]);
        ASSERT_EQ(pcache_decomp_load(dir, key, &b, &e), GLINT_EFORMAT);
        ASSERT(strstr(e.msg, "checksum") || strstr(e.msg, "magic"));
        ASSERT(b.s == NULL && b.V == NULL);
    }
    /* truncated */
    ASSERT_OK(pcache_decomp_save(dir, key, &a, &e));
    ASSERT_EQ(stat(path, &st), 0);
    ASSERT_EQ(truncate(path, st.st_size / 2), 0);
    ASSERT_EQ(pcache_decomp_load(dir, key, &b, &e), GLINT_EFORMAT);
    ASSERT_EQ(truncate(path, 5), 0);
    ASSERT_EQ(pcache_decomp_load(dir, key, &b, &e), GLINT_EFORMAT);
    /* a valid file under another key's name */
    {
        char other[33], opath[512];
        pcache_key_hf(S.hash, 16, 0.4, HF_ROUTE_EIG, 0, other);
        ASSERT_OK(pcache_decomp_save(dir, key, &a, &e));
        ASSERT_OK(pcache_path(dir, other, opath, sizeof opath, &e));
        ASSERT_EQ(rename(path, opath), 0);
        ASSERT_EQ(pcache_decomp_load(dir, other, &b, &e), GLINT_EFORMAT);
        ASSERT(strstr(e.msg, "another key"));
    }
    /* missing */
    unlink(path);
    ASSERT_EQ(pcache_decomp_load(dir, key, &b, &e), GLINT_ENOTFOUND);
    hf_decomp_free(&a);
}

TEST(get_builds_hits_and_rebuilds)
{
    hf_decomp a, b, c;
    char key[33], path[512];
    glint_err e;
    int hit = 99;
    ASSERT_OK(setup());
    ASSERT_OK(pcache_decomp_get(dir, &D, S.hash, 0.05, HF_ROUTE_EIG, 0, &a, &hit, &e));
    ASSERT_EQ(hit, 0);
    ASSERT_OK(pcache_decomp_get(dir, &D, S.hash, 0.05, HF_ROUTE_EIG, 0, &b, &hit, &e));
    ASSERT_EQ(hit, 1);
    ASSERT(memcmp(a.V, b.V, (size_t)a.rank * a.n * sizeof(double)) == 0);
    pcache_key_hf(S.hash, 16, 0.05, HF_ROUTE_EIG, 0, key);
    ASSERT_OK(pcache_path(dir, key, path, sizeof path, &e));
    flip_byte(path, 100);
    ASSERT_OK(pcache_decomp_get(dir, &D, S.hash, 0.05, HF_ROUTE_EIG, 0, &c, &hit, &e));
    ASSERT_EQ(hit, -1);
    hf_decomp_free(&c);
    ASSERT_OK(pcache_decomp_get(dir, &D, S.hash, 0.05, HF_ROUTE_EIG, 0, &c, &hit, &e));
    ASSERT_EQ(hit, 1); /* the rebuilt file replaced the corrupt one */
    /* no directory: always built */
    hf_decomp_free(&c);
    ASSERT_OK(pcache_decomp_get(NULL, &D, S.hash, 0.05, HF_ROUTE_EIG, 0, &c, &hit, &e));
    ASSERT_EQ(hit, 0);
    hf_decomp_free(&a);
    hf_decomp_free(&b);
    hf_decomp_free(&c);
}

TEST(cleanup)
{
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    ASSERT_EQ(system(cmd), 0);
}

TEST_LIST {
    TEST_ENTRY(round_trip_is_bit_identical),
    TEST_ENTRY(keys_depend_on_every_parameter),
    TEST_ENTRY(corrupt_files_are_detected),
    TEST_ENTRY(get_builds_hits_and_rebuilds),
    TEST_ENTRY(cleanup),
};
TEST_MAIN()
