/* test_env.c: environment maps (env.h): solid angles, built-ins, reading
 * and clamping, cube crosses, median cut and lat-long compression,
 * rotation, the compression error, bad input, and env_prepare's cache. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "env.h"
#include "img.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void irradiance(const env_lights *l, const double n[3], double rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (int k = 0; k < l->k; k++) {
        const double *d = l->dir + 3 * k;
        double c = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
        if (c > 0)
            for (int ch = 0; ch < 3; ch++)
                rgb[ch] += l->power[3 * k + ch] * c;
    }
}

TEST(white_furnace_total_power_and_irradiance)
{
    env_map m;
    env_lights l;
    glint_err e;
    double tot[3], n[3] = {0.3, -0.5, 0.81}, E[3], nl;
    ASSERT_OK(env_builtin("white", 128, 64, &m, &e));
    env_total_power(&m, tot);
    ASSERT_NEAR(tot[0], 4 * M_PI, 1e-9);
    nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (int i = 0; i < 3; i++)
        n[i] /= nl;
    ASSERT_OK(env_compress(&m, ENV_CUT_LATLONG, 2048, 0.0, 1.0, &l, &e));
    irradiance(&l, n, E);
    ASSERT_NEAR(E[1], M_PI, 2e-3 * M_PI);
    env_lights_free(&l);
    ASSERT_OK(env_compress(&m, ENV_CUT_MEDIAN, 256, 0.3, 2.0, &l, &e));
    ASSERT_EQ(l.k, 256);
    ASSERT_NEAR(l.total[2], 8 * M_PI, 1e-9);
    irradiance(&l, n, E);
    ASSERT_NEAR(E[0], 2 * M_PI, 0.05 * M_PI); /* 256 lights over a uniform sphere */
    env_lights_free(&l);
    env_map_free(&m);
}

TEST(median_cut_keeps_power_and_error_falls_with_more_lights)
{
    env_map m;
    glint_err e;
    double tot[3], prev = 1e30;
    ASSERT_OK(env_resolve("sky", &m, &e));
    env_total_power(&m, tot);
    for (int k = 64; k <= 1024; k *= 4) {
        env_lights l;
        env_cut_error ce;
        ASSERT_OK(env_compress(&m, ENV_CUT_MEDIAN, k, 0.0, 1.0, &l, &e));
        ASSERT_EQ(l.k, k);
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(l.total[c], tot[c], 1e-9 * tot[c]);
        ASSERT_OK(env_compress_error(&m, &l, 0.0, 1.0, &ce, &e));
        printf("  sky, %4d lights: irradiance %.4f, glossy %.4f\n", k, ce.irradiance_rel_rms,
               ce.glossy_rel_rms);
        ASSERT(ce.glossy_rel_rms < prev);
        prev = ce.glossy_rel_rms;
        env_lights_free(&l);
    }
    env_map_free(&m);
}

TEST(rotation_turns_the_lights)
{
    env_map m;
    env_lights a, b;
    glint_err e;
    double psi = 1.1;
    ASSERT_OK(env_resolve("sunset", &m, &e));
    ASSERT_OK(env_compress(&m, ENV_CUT_MEDIAN, 128, 0.0, 1.0, &a, &e));
    ASSERT_OK(env_compress(&m, ENV_CUT_MEDIAN, 128, psi, 1.0, &b, &e));
    env_lights_rotate(&a, psi);
    for (int i = 0; i < 3 * 128; i++)
        ASSERT_NEAR(a.dir[i], b.dir[i], 1e-12);
    env_lights_rotate(&a, 2 * M_PI - psi);
    env_lights_free(&b);
    ASSERT_OK(env_compress(&m, ENV_CUT_MEDIAN, 128, 0.0, 1.0, &b, &e));
    for (int i = 0; i < 3 * 128; i++)
        ASSERT_NEAR(a.dir[i], b.dir[i], 1e-12);
    /* the lookup agrees: the rotated map at Rz(psi) d is the map at d */
    {
        double d[3] = {0.6, 0.0, 0.8}, r[3] = {0.6 * cos(psi), 0.6 * sin(psi), 0.8}, x[3],
               y[3];
        env_radiance(&m, d, 0.0, 1.0, x);
        env_radiance(&m, r, psi, 1.0, y);
        for (int c = 0; c < 3; c++)
            ASSERT_NEAR(x[c], y[c], 1e-9 * (1 + x[c]));
    }
    env_lights_free(&a);
    env_lights_free(&b);
    env_map_free(&m);
}

TEST(files_clamp_negatives_and_crosses_resample)
{
    char dir[] = "/tmp/glint-env-XXXXXX", path[256];
    img im;
    env_map m, ref;
    glint_err e;
    ASSERT(mkdtemp(dir) != NULL);
    ASSERT_OK(img_alloc(&im, 64, 32, 3, &e));
    for (int i = 0; i < 64 * 32 * 3; i++)
        im.px[i] = (i % 7 == 0) ? -0.5f : 1.0f;
    snprintf(path, sizeof path, "%s/neg.exr", dir);
    ASSERT_OK(img_write(path, &im, &e));
    img_free(&im);
    ASSERT_OK(env_load(path, &m, &e));
    ASSERT_EQ(m.clamped, (64 * 32 * 3 + 6) / 7);
    ASSERT(strcmp(m.layout, "latlong") == 0);
    env_map_free(&m);
    unlink(path);
    /* a horizontal cross sampled from the sky built-in reads back like it */
    ASSERT_OK(env_builtin("overcast", 256, 128, &ref, &e));
    ASSERT_OK(img_alloc(&im, 4 * 32, 3 * 32, 3, &e));
    {
        env_map tmp;
        /* fill the cross by looking up the built-in at each face texel */
        for (int y = 0; y < 96; y++)
            for (int x = 0; x < 128; x++) {
                int fx = x / 32, fy = y / 32, face = -1;
                double u = ((x % 32) + 0.5) / 32 * 2 - 1, v = ((y % 32) + 0.5) / 32 * 2 - 1,
                       m3[3], d[3], rgb[3];
                if (fy == 0 && fx == 1) face = 2;
                if (fy == 2 && fx == 1) face = 3;
                if (fy == 1) face = fx == 0 ? 1 : fx == 1 ? 4 : fx == 2 ? 0 : 5;
                if (face < 0)
                    continue;
                switch (face) { /* OpenGL cube-map faces (sc, tc) -> direction */
                case 0: m3[0] = 1; m3[1] = -v; m3[2] = -u; break;
                case 1: m3[0] = -1; m3[1] = -v; m3[2] = u; break;
                case 2: m3[0] = u; m3[1] = 1; m3[2] = v; break;
                case 3: m3[0] = u; m3[1] = -1; m3[2] = -v; break;
                case 4: m3[0] = u; m3[1] = -v; m3[2] = 1; break;
                default: m3[0] = -u; m3[1] = -v; m3[2] = -1; break;
                }
                /* map frame (x, y, z) -> world (x, -z, y) */
                d[0] = m3[0];
                d[1] = -m3[2];
                d[2] = m3[1];
                {
                    double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                    for (int k = 0; k < 3; k++)
                        d[k] /= l;
                }
                env_radiance(&ref, d, 0.0, 1.0, rgb);
                for (int c = 0; c < 3; c++)
                    im.px[((size_t)y * 128 + x) * 3 + c] = (float)rgb[c];
            }
        snprintf(path, sizeof path, "%s/cross.exr", dir);
        ASSERT_OK(img_write(path, &im, &e));
        ASSERT_OK(env_load(path, &tmp, &e));
        ASSERT(strcmp(tmp.layout, "cross") == 0);
        ASSERT_EQ(tmp.width, 128);
        {
            double t1[3], t2[3];
            env_total_power(&tmp, t1);
            env_total_power(&ref, t2);
            ASSERT_NEAR(t1[0], t2[0], 0.02 * t2[0]);
            for (int r = 4; r < 60; r += 9)
                for (int c = 0; c < 128; c += 13) {
                    double dd[3], a[3], b[3];
                    double th = M_PI * (r + 0.5) / 64, ph = M_PI - 2 * M_PI * (c + 0.5) / 128;
                    dd[0] = sin(th) * cos(ph);
                    dd[1] = sin(th) * sin(ph);
                    dd[2] = cos(th);
                    env_radiance(&tmp, dd, 0, 1, a);
                    env_radiance(&ref, dd, 0, 1, b);
                    ASSERT_NEAR(a[0], b[0], 0.05);
                }
        }
        env_map_free(&tmp);
        unlink(path);
    }
    img_free(&im);
    env_map_free(&ref);
    rmdir(dir);
}

TEST(bad_specs_sizes_and_counts)
{
    env_map m;
    env_lights l;
    glint_err e;
    ASSERT_EQ(env_resolve("nosuch", &m, &e), GLINT_ENOTFOUND);
    ASSERT(strstr(e.msg, "studio") != NULL);
    ASSERT_EQ(env_resolve("builtin:nosuch", &m, &e), GLINT_ENOTFOUND);
    ASSERT_EQ(env_spec_check("a b", &e), GLINT_EINVAL);
    ASSERT_EQ(env_spec_check("x\\y", &e), GLINT_EINVAL);
    ASSERT_EQ(env_resolve("file:/etc/passwd", &m, &e), GLINT_ENOTFOUND); /* no resolver */
    ASSERT_EQ(env_spec_check("", &e), GLINT_EINVAL);
    ASSERT_OK(env_builtin("studio", 64, 32, &m, &e));
    ASSERT_EQ(env_compress(&m, ENV_CUT_MEDIAN, 0, 0, 1, &l, &e), GLINT_ERANGE);
    ASSERT_EQ(env_compress(&m, ENV_CUT_LATLONG, 100, 0, 1, &l, &e), GLINT_EINVAL);
    ASSERT_EQ(env_compress(&m, ENV_CUT_MEDIAN, 8, NAN, 1, &l, &e), GLINT_EINVAL);
    env_map_free(&m);
    {
        img im;
        char dir[] = "/tmp/glint-env-XXXXXX", path[256];
        ASSERT(mkdtemp(dir) != NULL);
        ASSERT_OK(img_alloc(&im, 30, 20, 3, &e));
        snprintf(path, sizeof path, "%s/odd.exr", dir);
        ASSERT_OK(img_write(path, &im, &e));
        ASSERT_EQ(env_load(path, &m, &e), GLINT_EINVAL);
        ASSERT(strstr(e.msg, "2:1") != NULL);
        img_free(&im);
        unlink(path);
        rmdir(dir);
    }
}

TEST(the_cc0_courtyard_when_present)
{
    env_map m;
    env_lights l;
    glint_err e;
    double tot[3];
    char path[4096];
    snprintf(path, sizeof path, "%s/../shared/data/envmaps/courtyard.exr", glint_test_source_dir);
    if (access(path, R_OK)) {
        printf("  SKIP: %s absent\n", path);
        return;
    }
    ASSERT_OK(env_load(path, &m, &e));
    ASSERT_EQ(m.width, 1024);
    ASSERT_EQ(m.clamped, 1818); /* the reference counts the same lossy negatives */
    env_total_power(&m, tot);
    ASSERT_OK(env_compress(&m, ENV_CUT_LATLONG, 2048, 0, 1, &l, &e));
    ASSERT_NEAR(l.total[1], tot[1], 1e-9 * tot[1]);
    env_lights_free(&l);
    env_map_free(&m);
}

/* env_prepare against env_resolve + env_compress: the same lights and map
 * from the cache as computed; a map file rewritten behind the same spec is
 * read again; other settings are other entries; bad specs keep their
 * errors. */
static char prep_path[256];
static int prep_resolver(const char *spec, char *path, size_t len, glint_err *err)
{
    if (strcmp(spec, "upload:x"))
        return glint_err_set(err, GLINT_ENOTFOUND, "no environment '%s'", spec);
    snprintf(path, len, "%s", prep_path);
    return 0;
}

static int same_lights(const env_lights *a, const env_lights *b)
{
    return a->k == b->k && !memcmp(a->dir, b->dir, (size_t)a->k * 3 * sizeof(double)) &&
           !memcmp(a->power, b->power, (size_t)a->k * 3 * sizeof(double));
}

static void write_flat(const char *path, float v, glint_err *e)
{
    img im;
    ASSERT_OK(img_alloc(&im, 64, 32, 3, e));
    for (int i = 0; i < 64 * 32 * 3; i++)
        im.px[i] = v * (1.0f + (float)(i % 5));
    ASSERT_OK(img_write(path, &im, e));
    img_free(&im);
}

TEST(prepare_keeps_what_it_computed_and_reads_a_changed_file)
{
    char dir[] = "/tmp/glint-envprep-XXXXXX";
    env_map m, ref, m2;
    env_lights l, lref, l2;
    glint_err e;
    env_cache_clear();
    /* a built-in, twice (computed, then kept): both equal the direct calls */
    ASSERT_OK(env_resolve("sky", &ref, &e));
    ASSERT_OK(env_compress(&ref, ENV_CUT_MEDIAN, 64, 0.7, 2.0, &lref, &e));
    for (int pass = 0; pass < 2; pass++) {
        ASSERT_OK(env_prepare("sky", ENV_CUT_MEDIAN, 64, 0.7, 2.0, &m, &l, &e));
        ASSERT(same_lights(&l, &lref));
        ASSERT(m.width == ref.width && m.height == ref.height && !strcmp(m.name, ref.name));
        ASSERT(!memcmp(m.rgb, ref.rgb, (size_t)m.width * m.height * 3 * sizeof(float)));
        env_map_free(&m); /* the copies are the caller's */
        env_lights_free(&l);
    }
    /* another rotation, count or cut is another entry */
    ASSERT_OK(env_prepare("sky", ENV_CUT_MEDIAN, 64, 0.8, 2.0, &m, &l, &e));
    ASSERT(!same_lights(&l, &lref));
    env_map_free(&m);
    env_lights_free(&l);
    ASSERT_OK(env_prepare("sky", ENV_CUT_MEDIAN, 32, 0.7, 2.0, &m, &l, &e));
    ASSERT_EQ(l.k, 32);
    env_map_free(&m);
    env_lights_free(&l);
    env_map_free(&ref);
    env_lights_free(&lref);
    /* a file behind a spec: kept, and read again once it changes */
    ASSERT(mkdtemp(dir) != NULL);
    snprintf(prep_path, sizeof prep_path, "%s/map.exr", dir);
    write_flat(prep_path, 1.0f, &e);
    env_set_resolver(prep_resolver);
    ASSERT_OK(env_prepare("upload:x", ENV_CUT_MEDIAN, 16, 0.0, 1.0, &m, &l, &e));
    ASSERT(!strcmp(m.name, "upload:x"));
    ASSERT_OK(env_prepare("upload:x", ENV_CUT_MEDIAN, 16, 0.0, 1.0, &m2, &l2, &e));
    ASSERT(same_lights(&l, &l2));
    env_map_free(&m2);
    env_lights_free(&l2);
    unlink(prep_path);
    write_flat(prep_path, 3.0f, &e); /* a new file (another inode, or size and time) */
    ASSERT_OK(env_prepare("upload:x", ENV_CUT_MEDIAN, 16, 0.0, 1.0, &m2, &l2, &e));
    ASSERT_NEAR(l2.total[0], 3.0 * l.total[0], 1e-6 * l2.total[0]);
    ASSERT_NEAR(m2.rgb[0], 3.0 * m.rgb[0], 1e-6);
    env_map_free(&m);
    env_lights_free(&l);
    env_map_free(&m2);
    env_lights_free(&l2);
    /* gone: the resolver's path no longer reads; nothing stale is answered */
    unlink(prep_path);
    ASSERT_EQ(env_prepare("upload:x", ENV_CUT_MEDIAN, 16, 0.0, 1.0, &m, &l, &e), GLINT_ENOTFOUND);
    ASSERT(m.rgb == NULL && l.dir == NULL);
    ASSERT_EQ(env_prepare("nosuch", ENV_CUT_MEDIAN, 16, 0.0, 1.0, &m, &l, &e), GLINT_ENOTFOUND);
    ASSERT_EQ(env_prepare("bad spec", ENV_CUT_MEDIAN, 16, 0.0, 1.0, &m, &l, &e), GLINT_EINVAL);
    ASSERT_EQ(env_prepare("sky", ENV_CUT_MEDIAN, 0, 0.0, 1.0, &m, &l, &e), GLINT_ERANGE);
    env_set_resolver(NULL);
    env_cache_clear();
    rmdir(dir);
}

TEST_LIST{
    TEST_ENTRY(white_furnace_total_power_and_irradiance),
    TEST_ENTRY(median_cut_keeps_power_and_error_falls_with_more_lights),
    TEST_ENTRY(rotation_turns_the_lights),
    TEST_ENTRY(files_clamp_negatives_and_crosses_resample),
    TEST_ENTRY(bad_specs_sizes_and_counts),
    TEST_ENTRY(the_cc0_courtyard_when_present),
    TEST_ENTRY(prepare_keeps_what_it_computed_and_reads_a_changed_file),
};

TEST_MAIN()
