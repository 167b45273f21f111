/* test_img.c: image I/O through img.h (and the OpenImageIO shim).
 * Every test works in one temporary directory, removed at exit. */
#include <dirent.h>
#include <math.h>
#include <errno.h>
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "gbuf.h"
#include "img.h"
#include "img_oiio.h"
#include "img_raw.h"

/* ---- helpers ----------------------------------------------------------- */

static char tmp_dir[256];

static void tmp_cleanup(void)
{
    DIR *d;
    struct dirent *e;
    char p[512];

    if (!tmp_dir[0])
        return;
    d = opendir(tmp_dir);
    if (d) {
        while ((e = readdir(d)) != NULL) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
                continue;
            snprintf(p, sizeof p, "%s/%s", tmp_dir, e->d_name);
            if (rmdir(p) != 0)
                unlink(p);
        }
        closedir(d);
    }
    rmdir(tmp_dir);
}

/* Path of `name` inside the test's temporary directory. */
static const char *tmp_path(const char *name)
{
    static char buf[4][512];
    static int which;
    if (!tmp_dir[0]) {
        const char *base = getenv("TMPDIR");
        snprintf(tmp_dir, sizeof tmp_dir, "%s/glint-test-img-XXXXXX",
                 base && *base ? base : "/tmp");
        if (!mkdtemp(tmp_dir)) {
            fprintf(stderr, "mkdtemp: %s\n", strerror(errno));
            exit(2);
        }
        atexit(tmp_cleanup);
    }
    which = (which + 1) % 4;
    snprintf(buf[which], sizeof buf[which], "%s/%s", tmp_dir, name);
    return buf[which];
}

/* Number of entries in the temp dir whose name contains `needle`. */
static int tmp_count(const char *needle)
{
    DIR *d = opendir(tmp_dir);
    struct dirent *e;
    int n = 0;
    if (!d)
        return -1;
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, needle))
            n++;
    closedir(d);
    return n;
}

static int file_write(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    size_t w = fwrite(data, 1, len, f);
    return (fclose(f) == 0 && w == len) ? 0 : -1;
}

/* Whole file into a malloc'ed buffer. */
static unsigned char *file_read(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    unsigned char *b;
    long n;
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    n = ftell(f);
    fseek(f, 0, SEEK_SET);
    b = malloc(n > 0 ? (size_t)n : 1);
    if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
        free(b);
        b = NULL;
    }
    fclose(f);
    *len = (size_t)n;
    return b;
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* Deterministic pseudo-random numbers in [0, 1). */
static uint64_t rng_state = 0x9e3779b97f4a7c15ull;
static double rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

static float quant8(float x)
{
    double c = x < 0.0f ? 0.0 : (x > 1.0f ? 1.0 : x);
    int q = (int)(c * 255.0 + 0.5);
    return (float)q / 255.0f;
}

/* A test image with values in [lo, hi). */
static int make_img(img *im, int w, int h, int c, double lo, double hi)
{
    int rc = img_alloc(im, w, h, c, NULL);
    if (rc)
        return rc;
    for (size_t i = 0; i < (size_t)w * h * c; i++)
        im->px[i] = (float)(lo + (hi - lo) * rnd());
    return 0;
}

/* ---- allocation -------------------------------------------------------- */

TEST(alloc_limits)
{
    img im;
    glint_err e;

    ASSERT_EQ(img_alloc(&im, 0, 4, 3, &e), GLINT_ERANGE);
    ASSERT(im.px == NULL && im.width == 0);
    ASSERT_EQ(img_alloc(&im, 4, IMG_MAX_DIM + 1, 3, &e), GLINT_ERANGE);
    ASSERT(strstr(e.msg, "16384") != NULL);
    ASSERT_EQ(img_alloc(&im, IMG_MAX_DIM + 1, IMG_MAX_DIM + 1, 1, &e), GLINT_ERANGE);
    ASSERT_EQ(img_alloc(&im, -5, 4, 3, NULL), GLINT_ERANGE);
    ASSERT_EQ(img_alloc(&im, 4, 4, 0, &e), GLINT_ERANGE);
    ASSERT_EQ(img_alloc(&im, 4, 4, 5, &e), GLINT_ERANGE);
    ASSERT_OK(img_alloc(&im, 3, 2, 4, &e));
    ASSERT(im.width == 3 && im.height == 2 && im.channels == 4);
    for (int i = 0; i < 24; i++)
        ASSERT(im.px[i] == 0.0f);
    img_free(&im);
    ASSERT(im.px == NULL);
    img_free(&im);  /* twice: zeroed struct */
    img_free(NULL);
}

TEST(check_finite)
{
    img im;
    glint_err e;
    ASSERT_OK(img_alloc(&im, 3, 2, 3, NULL));
    ASSERT_OK(img_check_finite(&im, &e));
    im.px[3 * (1 * 3 + 2) + 1] = INFINITY; /* x 2, y 1, G */
    ASSERT_EQ(img_check_finite(&im, &e), GLINT_ENONFINITE);
    ASSERT_MSG(strstr(e.msg, "x 2, y 1") && strstr(e.msg, "channel 1"), "msg: %s", e.msg);
    img_free(&im);
    ASSERT_EQ(img_check_finite(NULL, &e), GLINT_EINVAL);
}

/* ---- round trips ------------------------------------------------------- */

TEST(png_roundtrip)
{
    img a, b;
    glint_err e;
    const char *p = tmp_path("rt.png");

    for (int nch = 1; nch <= 4; nch++) {
        ASSERT_OK(make_img(&a, 7, 5, nch, -0.2, 1.2));
        if (nch == 4) { /* transparent pixel keeps its colour (no premultiply) */
            a.px[0] = 0.5f; a.px[1] = 0.25f; a.px[2] = 1.0f; a.px[3] = 0.0f;
        }
        ASSERT_MSG(img_write(p, &a, &e) == 0, "write: %s", e.msg);
        ASSERT_MSG(img_read(p, &b, &e) == 0, "read: %s", e.msg);
        ASSERT(b.width == 7 && b.height == 5 && b.channels == nch);
        for (int i = 0; i < 7 * 5 * nch; i++)
            ASSERT_MSG(b.px[i] == quant8(a.px[i]), "nch %d i %d: %g vs %g (from %g)", nch,
                       i, b.px[i], quant8(a.px[i]), a.px[i]);
        img_free(&a);
        img_free(&b);
    }
    /* exact 8-bit levels survive exactly */
    ASSERT_OK(img_alloc(&a, 256, 1, 1, NULL));
    for (int i = 0; i < 256; i++)
        a.px[i] = (float)i / 255.0f;
    ASSERT_OK(img_write(p, &a, &e));
    ASSERT_OK(img_read(p, &b, &e));
    for (int i = 0; i < 256; i++)
        ASSERT_EQ((int)(b.px[i] * 255.0f + 0.5f), i);
    img_free(&a);
    img_free(&b);
    ASSERT_EQ(tmp_count(".tmp-"), 0);
}

TEST(exr_roundtrip_exact)
{
    img a, b;
    glint_err e;
    const char *p = tmp_path("rt.exr");

    for (int nch = 1; nch <= 4; nch++) {
        ASSERT_OK(make_img(&a, 9, 4, nch, -2.0, 2.0));
        a.px[0] = 1e3f;
        a.px[nch] = 12345.678f;
        a.px[2 * nch] = 1e-7f;
        a.px[3 * nch] = -1e30f;
        ASSERT_MSG(img_write(p, &a, &e) == 0, "write: %s", e.msg);
        ASSERT_MSG(img_read(p, &b, &e) == 0, "read: %s", e.msg);
        ASSERT(b.width == 9 && b.height == 4 && b.channels == nch);
        ASSERT_MSG(memcmp(a.px, b.px, sizeof(float) * 9 * 4 * nch) == 0,
                   "EXR float data changed (nch %d)", nch);
        img_free(&a);
        img_free(&b);
    }
}

TEST(hdr_roundtrip)
{
    img a, b;
    glint_err e;
    const char *p = tmp_path("rt.hdr");

    ASSERT_OK(make_img(&a, 11, 6, 3, 0.0, 1.0));
    for (int i = 0; i < 11 * 6 * 3; i++) /* 1e-2 .. 1e3, log-uniform */
        a.px[i] = (float)pow(10.0, -2.0 + 5.0 * a.px[i]);
    ASSERT_MSG(img_write(p, &a, &e) == 0, "write: %s", e.msg);
    ASSERT_MSG(img_read(p, &b, &e) == 0, "read: %s", e.msg);
    ASSERT(b.width == 11 && b.height == 6 && b.channels == 3);
    for (int px = 0; px < 11 * 6; px++) {
        /* RGBE: 8-bit mantissas sharing the exponent of the largest
         * component: error below one step of that component's scale */
        float *x = a.px + 3 * px, *y = b.px + 3 * px;
        double m = fmax(x[0], fmax(x[1], x[2]));
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(y[c], x[c], m * 2.0 / 256.0);
    }
    img_free(&b);
    /* RGBE has no sign: negatives are written as 0, not wrapped */
    a.px[0] = 1.0f;
    a.px[1] = -0.5f;
    a.px[2] = 0.25f;
    a.px[3] = a.px[4] = a.px[5] = -3.0f;
    ASSERT_OK(img_write(p, &a, &e));
    ASSERT_OK(img_read(p, &b, &e));
    ASSERT(b.px[0] == 1.0f && b.px[1] == 0.0f && b.px[2] == 0.25f);
    ASSERT(b.px[3] == 0.0f && b.px[4] == 0.0f && b.px[5] == 0.0f);
    img_free(&b);
    img_free(&a);

    ASSERT_OK(make_img(&a, 4, 4, 4, 0.0, 1.0));
    ASSERT_EQ(img_write(tmp_path("rgba.hdr"), &a, &e), GLINT_EUNSUPPORTED);
    ASSERT(!file_exists(tmp_path("rgba.hdr")));
    img_free(&a);
}

TEST(jpeg_read)
{
    img a, b;
    glint_err e;
    const char *p = tmp_path("smooth.jpg");

    ASSERT_OK(img_alloc(&a, 32, 16, 3, NULL));
    for (int y = 0; y < 16; y++)
        for (int x = 0; x < 32; x++) {
            float *q = a.px + 3 * (y * 32 + x);
            q[0] = 0.2f + 0.6f * x / 31.0f;
            q[1] = 0.5f;
            q[2] = 0.8f - 0.5f * y / 15.0f;
        }
    ASSERT_MSG(img_write(p, &a, &e) == 0, "write: %s", e.msg);
    ASSERT_MSG(img_read(p, &b, &e) == 0, "read: %s", e.msg);
    ASSERT(b.width == 32 && b.height == 16 && b.channels == 3);
    for (int i = 0; i < 32 * 16 * 3; i++)
        ASSERT_NEAR(b.px[i], a.px[i], 0.03);
    img_free(&b);
    /* the content decides, not the name */
    ASSERT_EQ(rename(p, tmp_path("really_a_jpeg.png")), 0);
    ASSERT_MSG(img_read(tmp_path("really_a_jpeg.png"), &b, &e) == 0, "read: %s", e.msg);
    ASSERT(b.channels == 3);
    img_free(&b);
    img_free(&a);

    ASSERT_OK(make_img(&a, 4, 4, 4, 0.0, 1.0));
    ASSERT_EQ(img_write(tmp_path("rgba.jpg"), &a, &e), GLINT_EUNSUPPORTED);
    img_free(&a);
}

TEST(memory_roundtrip)
{
    img a, b;
    glint_err e;
    void *data;
    size_t len;

    ASSERT_OK(make_img(&a, 6, 5, 3, -0.5, 1e3));
    ASSERT_MSG(img_write_mem("exr", &a, &data, &len, &e) == 0, "%s", e.msg);
    ASSERT(len > 0);
    ASSERT_MSG(img_read_mem(data, len, &b, &e) == 0, "%s", e.msg);
    ASSERT(b.width == 6 && b.height == 5 && b.channels == 3);
    ASSERT(memcmp(a.px, b.px, sizeof(float) * 6 * 5 * 3) == 0);
    img_free(&b);
    free(data);

    ASSERT_MSG(img_write_mem("png", &a, &data, &len, &e) == 0, "%s", e.msg);
    ASSERT(len > 8 && memcmp(data, "\x89PNG", 4) == 0);
    ASSERT_MSG(img_read_mem(data, len, &b, &e) == 0, "%s", e.msg);
    for (int i = 0; i < 6 * 5 * 3; i++)
        ASSERT(b.px[i] == quant8(a.px[i]));
    img_free(&b);
    free(data);

    /* every format the file writer knows also decodes from memory */
    for (int f = 0; f < 2; f++) {
        const char *fmt = f ? "hdr" : "jpg";
        img c;
        ASSERT_OK(make_img(&c, 8, 8, 3, 0.1, 0.9));
        ASSERT_MSG(img_write_mem(fmt, &c, &data, &len, &e) == 0, "%s: %s", fmt, e.msg);
        ASSERT_MSG(img_read_mem(data, len, &b, &e) == 0, "%s: %s", fmt, e.msg);
        ASSERT(b.width == 8 && b.channels == 3);
        img_free(&b);
        img_free(&c);
        free(data);
    }

    data = (void *)1;
    ASSERT_EQ(img_write_mem("tiff", &a, &data, &len, &e), GLINT_EUNSUPPORTED);
    ASSERT(data == NULL && len == 0);
    ASSERT(strstr(e.msg, "tiff") != NULL);
    img_free(&a);
}

/* ---- named channels ---------------------------------------------------- */

static int find_name(const img_named *m, const char *name)
{
    int found = -1;
    for (int c = 0; c < m->channels; c++)
        if (strcmp(m->names[c], name) == 0) {
            if (found >= 0)
                return -2; /* duplicate */
            found = c;
        }
    return found;
}

TEST(named_exr)
{
    static const char *const names[] = {"mask", "N.X", "N.Y", "N.Z", "cos_i", "A"};
    enum { W = 5, H = 3, NCH = 6 };
    float data[W * H * NCH];
    img_named m;
    img im;
    glint_err e;
    const char *p = tmp_path("named.exr");

    for (int i = 0; i < W * H * NCH; i++)
        data[i] = (float)(i % NCH) * 100.0f + (float)(i / NCH) + 0.25f;
    ASSERT_MSG(img_write_exr_named(p, W, H, NCH, names, data, &e) == 0, "%s", e.msg);
    ASSERT_MSG(img_read_named(p, &m, &e) == 0, "%s", e.msg);
    ASSERT(m.width == W && m.height == H && m.channels == NCH);
    for (int c = 0; c < NCH; c++) {
        int k = find_name(&m, names[c]);
        ASSERT_MSG(k >= 0, "channel '%s' missing or duplicated (%d)", names[c], k);
        for (int px = 0; px < W * H; px++)
            ASSERT(m.px[px * NCH + k] == data[px * NCH + c]);
    }
    img_named_free(&m);
    img_named_free(&m);

    /* six channels are more than img_read takes */
    ASSERT_EQ(img_read(p, &im, &e), GLINT_ERANGE);
    ASSERT(strstr(e.msg, "6 channels") != NULL);

    /* bad input to the writer */
    {
        static const char *const dup[] = {"a", "b", "a"};
        static const char *const empty[] = {"a", ""};
        ASSERT_EQ(img_write_exr_named(tmp_path("dup.exr"), 1, 1, 3, dup, data, &e),
                  GLINT_EINVAL);
        ASSERT(strstr(e.msg, "'a'") != NULL);
        ASSERT_EQ(img_write_exr_named(tmp_path("e.exr"), 1, 1, 2, empty, data, &e),
                  GLINT_EINVAL);
        ASSERT_EQ(img_write_exr_named(tmp_path("e.exr"), 0, 1, 2, names, data, &e),
                  GLINT_ERANGE);
        ASSERT_EQ(img_write_exr_named(tmp_path("e.exr"), 1, 1, 0, names, data, &e),
                  GLINT_ERANGE);
        data[7] = NAN; /* pixel 1, channel 1 (N.X) */
        ASSERT_EQ(img_write_exr_named(tmp_path("nan.exr"), W, H, NCH, names, data, &e),
                  GLINT_ENONFINITE);
        ASSERT_MSG(strstr(e.msg, "N.X") && strstr(e.msg, "x 1, y 0"), "msg: %s", e.msg);
        ASSERT(!file_exists(tmp_path("nan.exr")));
        ASSERT(!file_exists(tmp_path("dup.exr")));
    }
}

TEST(gbuf_exr_channels)
{
    gbuf g;
    img_named m;
    glint_err e;
    const char *p = tmp_path("gbuf.exr");
    static const char *const want[] = {"mask", "P.X", "N.Z", "uv.V", "wi.Y", "wo.X",
                                       "cos_i", "cos_o"};

    ASSERT_OK(gbuf_alloc(&g, 4, 3, &e));
    g.mask[5] = 1;
    g.nrm[3 * 5 + 2] = 1.0f;
    g.wi[3 * 5 + 2] = 0.6f;
    g.wi[3 * 5 + 1] = 0.8f;
    g.wo[3 * 5 + 0] = 0.6f;
    g.wo[3 * 5 + 2] = 0.8f;
    g.pos[3 * 5] = 0.5f;
    g.uv[2 * 5 + 1] = 0.75f;
    ASSERT_MSG(gbuf_write_exr(&g, p, &e) == 0, "%s", e.msg);
    ASSERT_MSG(img_read_named(p, &m, &e) == 0, "%s", e.msg);
    ASSERT_EQ(m.channels, 17);
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++)
        ASSERT_MSG(find_name(&m, want[i]) >= 0, "no channel %s", want[i]);
    ASSERT(m.px[5 * 17 + find_name(&m, "mask")] == 1.0f);
    ASSERT(m.px[5 * 17 + find_name(&m, "cos_i")] == 0.6f);
    ASSERT(m.px[5 * 17 + find_name(&m, "cos_o")] == 0.8f);
    ASSERT(m.px[5 * 17 + find_name(&m, "wi.Y")] == 0.8f);
    ASSERT(m.px[5 * 17 + find_name(&m, "P.X")] == 0.5f);
    ASSERT(m.px[5 * 17 + find_name(&m, "uv.V")] == 0.75f);
    ASSERT(m.px[4 * 17 + find_name(&m, "mask")] == 0.0f);
    img_named_free(&m);
    gbuf_free(&g);
}

/* ---- rejection of bad files ------------------------------------------- */

/* An EXR holding a bad value, written around img_write's own check. */
static int write_bad_exr(const char *path, float bad, int at)
{
    float px[4 * 3 * 3];
    void *mem = NULL;
    size_t len = 0;
    int rc;
    for (int i = 0; i < 36; i++)
        px[i] = 0.5f;
    px[at] = bad;
    rc = img_oiio_write("openexr", NULL, &mem, &len, "test", 4, 3, 3, NULL, 0, px, NULL);
    if (rc == 0)
        rc = file_write(path, mem, len);
    free(mem);
    return rc;
}

TEST(nonfinite_exr_rejected)
{
    img im;
    glint_err e;
    const char *p = tmp_path("nan.exr");
    size_t len;
    unsigned char *bytes;

    /* pixel (x 2, y 1) is index 6; channel 2 */
    ASSERT_OK(write_bad_exr(p, NAN, 3 * 6 + 2));
    im.px = (float *)1;
    ASSERT_EQ(img_read(p, &im, &e), GLINT_ENONFINITE);
    ASSERT(im.px == NULL);
    ASSERT_MSG(strstr(e.msg, "x 2, y 1") && strstr(e.msg, "channel 2"), "msg: %s", e.msg);
    bytes = file_read(p, &len);
    ASSERT(bytes != NULL);
    ASSERT_EQ(img_read_mem(bytes, len, &im, &e), GLINT_ENONFINITE);
    free(bytes);

    ASSERT_OK(write_bad_exr(p, -INFINITY, 0));
    ASSERT_EQ(img_read(p, &im, &e), GLINT_ENONFINITE);
    ASSERT_MSG(strstr(e.msg, "x 0, y 0") && strstr(e.msg, "-inf"), "msg: %s", e.msg);

    /* and the writers refuse them */
    ASSERT_OK(img_alloc(&im, 2, 2, 3, NULL));
    im.px[5] = NAN;
    ASSERT_EQ(img_write(tmp_path("w.exr"), &im, &e), GLINT_ENONFINITE);
    ASSERT(!file_exists(tmp_path("w.exr")));
    {
        void *d = NULL;
        size_t n = 0;
        ASSERT_EQ(img_write_mem("png", &im, &d, &n, &e), GLINT_ENONFINITE);
        ASSERT(d == NULL);
    }
    img_free(&im);
}

/* Truncate a valid file of `ext` to various lengths; each read must fail
 * cleanly (negative code, message, zeroed output). */
static void check_truncations(const char *ext, int *failed)
{
    img a, b;
    glint_err e;
    char name[64];
    unsigned char *bytes;
    size_t len;
    const char *p, *q;

    snprintf(name, sizeof name, "full.%s", ext);
    p = tmp_path(name);
    snprintf(name, sizeof name, "cut.%s", ext);
    q = tmp_path(name);
    if (make_img(&a, 40, 30, 3, 0.0, 1.0) || img_write(p, &a, NULL)) {
        *failed = 1;
        return;
    }
    img_free(&a);
    bytes = file_read(p, &len);
    if (!bytes) {
        *failed = 1;
        return;
    }
    const size_t cuts[] = {1, 7, 20, 60, len / 3, len / 2, len - 16};
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++) {
        size_t n = cuts[k];
        int rc;
        file_write(q, bytes, n);
        e.code = 0;
        e.msg[0] = '\0';
        rc = img_read(q, &b, &e);
        if (rc >= 0 || !e.msg[0] || b.px) {
            fprintf(stderr, "  %s cut to %zu of %zu bytes: rc %d msg '%s'\n", ext, n, len,
                    rc, e.msg);
            *failed = 1;
        }
        img_free(&b);
        rc = img_read_mem(bytes, n, &b, &e);
        if (rc >= 0 || !e.msg[0] || b.px) {
            fprintf(stderr, "  %s (memory) cut to %zu of %zu bytes: rc %d msg '%s'\n", ext,
                    n, len, rc, e.msg);
            *failed = 1;
        }
        img_free(&b);
    }
    free(bytes);
}

TEST(truncated_files)
{
    int failed = 0;
    check_truncations("png", &failed);
    check_truncations("exr", &failed);
    check_truncations("hdr", &failed);
    check_truncations("jpg", &failed);
    ASSERT(!failed);
}

TEST(garbage_files)
{
    img b;
    glint_err e;
    unsigned char junk[4096];
    const char *p = tmp_path("junk.png");

    for (size_t i = 0; i < sizeof junk; i++)
        junk[i] = (unsigned char)(rnd() * 256.0);
    junk[0] = 'G'; /* not any magic */
    ASSERT_OK(file_write(p, junk, sizeof junk));
    ASSERT_EQ(img_read(p, &b, &e), GLINT_EFORMAT);
    ASSERT_MSG(strstr(e.msg, "junk.png") && strstr(e.msg, "not a PNG"), "msg: %s", e.msg);

    /* every magic followed by garbage */
    static const unsigned char magics[][8] = {
        {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'},
        {0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0},
        {0xff, 0xd8, 0xff, 0xe0, 0, 0x10, 'J', 'F'},
        {'#', '?', 'R', 'A', 'D', 'I', 'A', 'N'},
    };
    for (int m = 0; m < 4; m++) {
        int rc;
        memcpy(junk, magics[m], 8);
        ASSERT_OK(file_write(p, junk, sizeof junk));
        rc = img_read(p, &b, &e);
        ASSERT_MSG(rc < 0 && e.msg[0] && !b.px, "magic %d: rc %d '%s'", m, rc, e.msg);
        rc = img_read_mem(junk, sizeof junk, &b, &e);
        ASSERT_MSG(rc < 0 && e.msg[0] && !b.px, "magic %d (mem): rc %d '%s'", m, rc, e.msg);
    }

    ASSERT_OK(file_write(p, junk, 0));
    ASSERT_EQ(img_read(p, &b, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "empty") != NULL);
    ASSERT_EQ(img_read_mem(junk, 0, &b, &e), GLINT_EFORMAT);
    ASSERT_EQ(img_read_mem(NULL, 5, &b, &e), GLINT_EINVAL);
}

TEST(missing_and_odd_paths)
{
    img b;
    glint_err e;
    int rc = img_read(tmp_path("does-not-exist.png"), &b, &e);
    ASSERT_EQ(rc, GLINT_ENOTFOUND);
    ASSERT(strstr(e.msg, "does-not-exist.png") != NULL);
    ASSERT(b.px == NULL);
    rc = img_read(tmp_dir, &b, &e); /* a directory */
    ASSERT_EQ(rc, GLINT_EIO);
    ASSERT_EQ(img_read(NULL, &b, &e), GLINT_EINVAL);
    ASSERT_EQ(img_read("", &b, NULL), GLINT_EINVAL);
}

TEST(oversize_header)
{
    /* A Radiance header claiming 20000 columns: refused from the header,
     * before any pixel memory is allocated. */
    static const char hdr[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 20000\n";
    unsigned char buf[256];
    img b;
    glint_err e;
    memset(buf, 0, sizeof buf);
    memcpy(buf, hdr, sizeof hdr - 1);
    ASSERT_OK(file_write(tmp_path("wide.hdr"), buf, sizeof buf));
    ASSERT_EQ(img_read(tmp_path("wide.hdr"), &b, &e), GLINT_ERANGE);
    ASSERT_MSG(strstr(e.msg, "20000x2"), "msg: %s", e.msg);
    ASSERT_EQ(img_read_mem(buf, sizeof buf, &b, &e), GLINT_ERANGE);
}

/* ---- writing ----------------------------------------------------------- */

TEST(write_rules)
{
    img a, b;
    glint_err e;

    ASSERT_OK(make_img(&a, 4, 4, 3, 0.0, 1.0));
    ASSERT_EQ(img_write(tmp_path("x.tif"), &a, &e), GLINT_EUNSUPPORTED);
    ASSERT(strstr(e.msg, ".tif") != NULL);
    ASSERT(!file_exists(tmp_path("x.tif")));
    ASSERT_EQ(img_write(tmp_path("noext"), &a, &e), GLINT_EUNSUPPORTED);
    ASSERT_EQ(img_write(tmp_path("dir.png/noext"), &a, &e), GLINT_EUNSUPPORTED);
    /* extension is case-insensitive */
    ASSERT_MSG(img_write(tmp_path("upper.PNG"), &a, &e) == 0, "%s", e.msg);
    ASSERT_OK(img_read(tmp_path("upper.PNG"), &b, &e));
    img_free(&b);
    /* missing directory: EIO, nothing left behind */
    ASSERT_EQ(img_write(tmp_path("no/such/dir.png"), &a, &e), GLINT_EIO);
    ASSERT(e.msg[0] != '\0');
    /* overwrite replaces the file, leaves no temporaries */
    ASSERT_OK(img_write(tmp_path("over.exr"), &a, &e));
    a.px[0] = 42.0f;
    ASSERT_OK(img_write(tmp_path("over.exr"), &a, &e));
    ASSERT_OK(img_read(tmp_path("over.exr"), &b, &e));
    ASSERT(b.px[0] == 42.0f);
    img_free(&b);
    ASSERT_EQ(tmp_count(".tmp-"), 0);
    /* invalid images */
    ASSERT_EQ(img_write(tmp_path("null.png"), NULL, &e), GLINT_EINVAL);
    a.channels = 7;
    ASSERT_EQ(img_write(tmp_path("seven.exr"), &a, &e), GLINT_ERANGE);
    a.channels = 3;
    img_free(&a);
}

/* A painting at a multiple of the raster read at the raster's pixel
 * centres (img_to_raster): 1x copied, 2x and 4x the mean of the 2 x 2
 * pixels around each centre, 3x the centre pixel, a painting replicated
 * from a raster image reads back exactly, other sizes refused with both. */
TEST(paintings_at_a_multiple_of_the_raster)
{
    img lo, hi, back;
    glint_err e;
    const int w = 5, h = 3;
    ASSERT_OK(img_alloc(&lo, w, h, 3, &e));
    for (size_t i = 0; i < (size_t)w * h * 3; i++)
        lo.px[i] = (float)(0.1 * (double)i - 0.7);
    for (int s = 1; s <= 4; s++) {
        ASSERT_OK(img_alloc(&hi, w * s, h * s, 3, &e));
        for (int y = 0; y < h * s; y++) /* replicated, plus a ramp inside each block */
            for (int x = 0; x < w * s; x++)
                for (int c = 0; c < 3; c++)
                    hi.px[((size_t)y * w * s + x) * 3 + c] =
                        lo.px[((size_t)(y / s) * w + x / s) * 3 + c] +
                        (float)(0.01 * ((x % s) - (s - 1) / 2.0) + 0.02 * ((y % s) - (s - 1) / 2.0));
        ASSERT_EQ(img_raster_scale(w * s, h * s, w, h), s);
        ASSERT_OK(img_to_raster(&hi, w, h, &back, &e));
        ASSERT_EQ(back.width, w);
        ASSERT_EQ(back.height, h);
        for (size_t i = 0; i < (size_t)w * h * 3; i++) {
            /* the ramp is zero at the centre: its mean over the 2 x 2 pixels
             * around it (s even) and its value at the centre pixel (s odd) */
            double want = lo.px[i];
            ASSERT_MSG(fabs(back.px[i] - want) < 1e-6, "s %d, value %zu: %g, want %g", s, i,
                       back.px[i], want);
        }
        img_free(&back);
        img_free(&hi);
    }
    /* a 2x painting: exactly the mean of the four around the centre */
    ASSERT_OK(img_alloc(&hi, 2 * w, 2 * h, 1, &e));
    for (size_t i = 0; i < (size_t)4 * w * h; i++)
        hi.px[i] = (float)(i * i % 17);
    ASSERT_OK(img_to_raster(&hi, w, h, &back, &e));
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = hi.px + (size_t)(2 * y) * 2 * w + 2 * x;
            double want = 0.25 * ((double)p[0] + p[1] + p[2 * w] + p[2 * w + 1]);
            ASSERT(fabs(back.px[(size_t)y * w + x] - want) < 1e-6);
        }
    img_free(&back);
    img_free(&hi);
    /* other sizes: refused, naming both */
    ASSERT_EQ(img_raster_scale(2 * w, 3 * h, w, h), 0);
    ASSERT_EQ(img_raster_scale(2 * w + 1, 2 * h, w, h), 0);
    ASSERT_EQ(img_raster_scale(w - 1, h, w, h), 0);
    ASSERT_OK(img_alloc(&hi, 2 * w, 3 * h, 3, &e));
    ASSERT_EQ(img_to_raster(&hi, w, h, &back, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "10x9") && strstr(e.msg, "5x3"));
    img_free(&hi);
    img_free(&lo);
}

/* Decoded pixels as a cache file (img_raw.h): back bit for bit, every
 * channel count; missing, cut, flipped, non-finite and oversize files are
 * told apart and never returned. */
TEST(raw_pixels_roundtrip_and_damage)
{
    const char *dir = tmp_path("raw");
    img im, got;
    glint_err e;
    char path[600];

    for (int c = 1; c <= 4; c++) {
        ASSERT_OK(img_alloc(&im, 7, 5, c, &e));
        for (int i = 0; i < 7 * 5 * c; i++)
            im.px[i] = (float)(i % 11) * 0.37f - 1.5f + (i == 3 ? 1e30f : 0.0f);
        ASSERT_OK(img_raw_save(&im, dir, "a.px", &e));
        ASSERT_OK(img_raw_load(dir, "a.px", 0, &got, &e));
        ASSERT(got.width == 7 && got.height == 5 && got.channels == c);
        ASSERT(memcmp(got.px, im.px, sizeof(float) * 7 * 5 * (size_t)c) == 0);
        img_free(&got);
        img_free(&im);
    }
    ASSERT_EQ(img_raw_load(dir, "none.px", 0, &got, &e), GLINT_ENOTFOUND);
    /* larger than the caller allows: refused from the header */
    ASSERT_EQ(img_raw_load(dir, "a.px", 6, &got, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "limits") != NULL);
    ASSERT_OK(img_raw_load(dir, "a.px", 7, &got, &e));
    img_free(&got);
    /* a flipped bit of a pixel: the checksum */
    snprintf(path, sizeof path, "%s/a.px", dir);
    {
        FILE *fp = fopen(path, "r+b");
        unsigned char b;
        ASSERT(fp && fseek(fp, 60, SEEK_SET) == 0 && fread(&b, 1, 1, fp) == 1);
        b ^= 1;
        ASSERT(fseek(fp, 60, SEEK_SET) == 0 && fwrite(&b, 1, 1, fp) == 1);
        fclose(fp);
    }
    ASSERT_EQ(img_raw_load(dir, "a.px", 0, &got, &e), GLINT_EFORMAT);
    ASSERT(got.px == NULL);
    /* cut short */
    ASSERT_OK(img_alloc(&im, 7, 5, 3, &e));
    ASSERT_OK(img_raw_save(&im, dir, "a.px", &e));
    ASSERT_OK(truncate(path, 100));
    ASSERT_EQ(img_raw_load(dir, "a.px", 0, &got, &e), GLINT_EFORMAT);
    /* a value that is not finite, checksum good */
    im.px[17] = NAN;
    ASSERT_OK(img_raw_save(&im, dir, "a.px", &e));
    ASSERT_EQ(img_raw_load(dir, "a.px", 0, &got, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "finite") != NULL);
    img_free(&im);
    /* not an image */
    ASSERT_EQ(img_raw_save(&im, dir, "b.px", &e), GLINT_EINVAL);
    unlink(path);
    rmdir(dir);
}

TEST_LIST {
    TEST_ENTRY(alloc_limits),
    TEST_ENTRY(check_finite),
    TEST_ENTRY(png_roundtrip),
    TEST_ENTRY(exr_roundtrip_exact),
    TEST_ENTRY(hdr_roundtrip),
    TEST_ENTRY(jpeg_read),
    TEST_ENTRY(memory_roundtrip),
    TEST_ENTRY(named_exr),
    TEST_ENTRY(gbuf_exr_channels),
    TEST_ENTRY(nonfinite_exr_rejected),
    TEST_ENTRY(truncated_files),
    TEST_ENTRY(garbage_files),
    TEST_ENTRY(missing_and_odd_paths),
    TEST_ENTRY(oversize_header),
    TEST_ENTRY(write_rules),
    TEST_ENTRY(paintings_at_a_multiple_of_the_raster),
    TEST_ENTRY(raw_pixels_roundtrip_and_damage),
};

TEST_MAIN()
