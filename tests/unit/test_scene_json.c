/* test_scene_json.c: scenes as JSON (round trips, minimal and explicit
 * documents, malformed and hostile ones: errors, never a crash),
 * validation, the content hash and its golden value, and saving and
 * loading scene files. */
#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "mesh.h"
#include "scene.h"

/* scene_hash of the default scene (scene_params_default) */
#define GOLDEN_HASH "6e3b3eb975337b6b6aa9355d46c3deda"

/* ---- JSON and hash ------------------------------------------------------- */

static int is_hex32(const char *h)
{
    if (strlen(h) != 32)
        return 0;
    for (int i = 0; i < 32; i++)
        if (!isxdigit((unsigned char)h[i]) || isupper((unsigned char)h[i]))
            return 0;
    return 1;
}

TEST(json_round_trip_and_hash)
{
    scene s, t;
    scene_params p;
    glint_err e;
    char h1[33], h2[33], h3[33];
    char *text, *text2;

    scene_params_default(&p);
    ASSERT_OK(scene_create(&p, &s, &e));
    scene_hash(&s, h1);
    ASSERT_MSG(is_hex32(h1), "hash \"%s\" is not 32 lowercase hex digits", h1);
    text = scene_to_json(&s, &e);
    ASSERT(text != NULL);
    ASSERT(strstr(text, "\"glint-scene\"") != NULL);
    ASSERT_OK(scene_from_json(text, &t, &e));
    scene_hash(&t, h2);
    ASSERT_MSG(strcmp(h1, h2) == 0, "hash changed in a round trip: %s vs %s", h1, h2);
    ASSERT_EQ(t.nviews, 12);
    for (int k = 0; k < 12; k++) {
        ASSERT(memcmp(t.views[k].eye, s.views[k].eye, sizeof t.views[k].eye) == 0);
        ASSERT(memcmp(t.views[k].light, s.views[k].light, sizeof t.views[k].light) == 0);
        ASSERT(t.views[k].half_fov == s.views[k].half_fov);
        ASSERT(t.views[k].light_deg == s.views[k].light_deg);
    }
    /* serializing again gives the same text */
    text2 = scene_to_json(&t, &e);
    ASSERT(text2 != NULL);
    ASSERT(strcmp(text, text2) == 0);
    free(text);
    free(text2);

    /* light_deg is informative: not hashed; a light coordinate is */
    t.views[3].light_deg = 99.0;
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) == 0);
    t.views[3].light[1] = nextafter(t.views[3].light[1], 10.0);
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) != 0);
    t.views[3].light[1] = s.views[3].light[1];
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) == 0);
    /* raster size, intensity, fov, target and mesh are hashed */
    t.width = 64;
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) != 0);
    t.width = 128;
    t.views[11].light_intensity = 2.0;
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) != 0);
    t.views[11].light_intensity = 1.0;
    t.views[0].half_fov *= 1.0000001;
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) != 0);
    t.views[0].half_fov = s.views[0].half_fov;
    t.views[0].target[2] = -0.0; /* the same geometry as +0 */
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) == 0);
    t.mesh.uv[1000] += 0.25f;
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) != 0);
    t.mesh.uv[1000] = s.mesh.uv[1000];
    t.mesh.tri[7] ^= 1u;
    scene_hash(&t, h3);
    ASSERT(strcmp(h1, h3) != 0);
    scene_free(&t);
    scene_free(&s);
}

/* The hash of the default scene is the key of every cached precomputation:
 * it must not change by accident (a change here invalidates all caches). */
TEST(hash_golden)
{
    scene s;
    scene_params p;
    glint_err e;
    char h[33];
    scene_params_default(&p);
    ASSERT_OK(scene_create(&p, &s, &e));
    scene_hash(&s, h);
    printf("  default scene hash %s\n", h);
    ASSERT_MSG(strcmp(h, GOLDEN_HASH) == 0, "default scene hash %s, expected %s", h,
               GOLDEN_HASH);
    scene_free(&s);
}

static const char good_view[] =
    "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":0.4,\"light\":[1,0,3]}";

/* Parse a document built from a views array and the given top-level extras. */
static int parse_doc(const char *fmt, const char *a, glint_err *e)
{
    char buf[4096];
    scene s;
    int rc;
    snprintf(buf, sizeof buf, fmt, a);
    memset(e, 0, sizeof *e);
    rc = scene_from_json(buf, &s, e);
    if (rc == 0)
        scene_free(&s);
    else
        /* a failed parse leaves a zeroed scene */
        if (s.views || s.mesh.pos || s.nviews)
            return 1000;
    return rc;
}

#define DOC_HEAD "{\"format\":\"glint-scene\",\"version\":1,\"mesh\":\"sphere\","
#define DOC_VIEWS(v) "\"views\":[" v "]}"

TEST(json_minimal_and_explicit)
{
    glint_err e;
    scene s;
    char buf[1024];
    snprintf(buf, sizeof buf, DOC_HEAD "\"width\":32,\"height\":16," DOC_VIEWS("%s"),
             good_view);
    ASSERT_OK(scene_from_json(buf, &s, &e));
    ASSERT_EQ(s.width, 32);
    ASSERT_EQ(s.height, 16);
    ASSERT_EQ(s.nviews, 1);
    ASSERT_NEAR(s.views[0].light_intensity, 1.0, 0.0); /* default */
    ASSERT_NEAR(s.views[0].light_deg, -1.0, 0.0);      /* explicit light */
    ASSERT_NEAR(s.views[0].eye[2], 3.0, 0.0);
    scene_free(&s);
    /* light at the eye is fine */
    snprintf(buf, sizeof buf,
             DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
                 "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":0.4,\"light\":[0,0,3],"
                 "\"light_intensity\":2.5}"));
    ASSERT_OK(scene_from_json(buf, &s, &e));
    ASSERT_NEAR(s.views[0].light_intensity, 2.5, 0.0);
    scene_free(&s);
}

TEST(json_malformed)
{
    static const struct {
        const char *doc;
        int code;
        const char *needle; /* must appear in the message */
    } cases[] = {
        {"", GLINT_EFORMAT, "JSON"},
        {DOC_HEAD "\"width\":32,", GLINT_EFORMAT, "JSON"}, /* truncated */
        {"[1,2,3]", GLINT_EFORMAT, "object"},
        {"{\"format\":\"other\",\"version\":1}", GLINT_EFORMAT, "format"},
        {"{\"version\":1}", GLINT_EFORMAT, "format"},
        {"{\"format\":\"glint-scene\",\"version\":2,\"mesh\":\"sphere\"}", GLINT_EUNSUPPORTED,
         "version"},
        {"{\"format\":\"glint-scene\",\"version\":\"1\"}", GLINT_EFORMAT, "version"},
        {DOC_HEAD "\"width\":32,\"height\":32,\"views\":[]}", GLINT_ERANGE, "views"},
        {DOC_HEAD "\"width\":1000000,\"height\":32," DOC_VIEWS("%s"), GLINT_ERANGE, "width"},
        {DOC_HEAD "\"width\":32,\"height\":-5," DOC_VIEWS("%s"), GLINT_ERANGE, "height"},
        {DOC_HEAD "\"width\":32," DOC_VIEWS("%s"), GLINT_EFORMAT, "height"},
        {DOC_HEAD "\"width\":32.5,\"height\":32," DOC_VIEWS("%s"), GLINT_EFORMAT, "width"},
        {DOC_HEAD "\"width\":99999999999999999999999,\"height\":32," DOC_VIEWS("%s"),
         GLINT_EFORMAT, "JSON"},
        {DOC_HEAD "\"width\":32,\"height\":32,\"views\":{}}", GLINT_EFORMAT, "views"},
        {DOC_HEAD "\"width\":32,\"height\":32,\"views\":[3]}", GLINT_EFORMAT, "views[0]"},
        {DOC_HEAD "\"width\":32,\"width\":32,\"height\":32," DOC_VIEWS("%s"), GLINT_EFORMAT,
         "duplicate"},
        {DOC_HEAD "\"width\":32,\"height\":32,\"colour\":1," DOC_VIEWS("%s"), GLINT_EFORMAT,
         "colour"},
        {"{\"format\":\"glint-scene\",\"version\":1,\"mesh\":\"cube\",\"width\":32,"
         "\"height\":32," DOC_VIEWS("%s"),
         GLINT_ENOTFOUND, "cube"},
        {"{\"format\":\"glint-scene\",\"version\":1,\"mesh\":7,\"width\":32,"
         "\"height\":32," DOC_VIEWS("%s"),
         GLINT_EFORMAT, "mesh"},
        /* views */
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":\"NaN\",\"light\":[1,0,3]}"),
         GLINT_EFORMAT, "views[0].half_fov"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":NaN,\"light\":[1,0,3]}"),
         GLINT_EFORMAT, "JSON"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":1e999,\"light\":[1,0,3]}"),
         GLINT_EFORMAT, "JSON"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0],\"target\":[0,0,0],\"half_fov\":0.4,\"light\":[1,0,3]}"),
         GLINT_EFORMAT, "views[0].eye"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,null,3],\"target\":[0,0,0],\"half_fov\":0.4,\"light\":[1,0,3]}"),
         GLINT_EFORMAT, "views[0].eye[1]"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"half_fov\":0.4,\"light\":[1,0,3]}"),
         GLINT_EFORMAT, "views[0].target"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "%s,{\"eye\":[1,2,3],\"target\":[1,2,3],\"half_fov\":0.4,\"light\":[1,0,3]}"),
         GLINT_EINVAL, "views[1]"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":0,\"light\":[1,0,3]}"),
         GLINT_ERANGE, "half_fov"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":1.5708,\"light\":[1,0,3]}"),
         GLINT_ERANGE, "half_fov"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":0.4,\"light\":[1,0,3],"
             "\"light_intensity\":0}"),
         GLINT_ERANGE, "light_intensity"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":0.4,\"light\":[1,0,3],"
             "\"ligth_deg\":3}"),
         GLINT_EFORMAT, "ligth_deg"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[1e308,0,3],\"target\":[-1e308,0,0],\"half_fov\":0.4,\"light\":[1,0,3]}"),
         GLINT_ENONFINITE, "views[0]"},
        {DOC_HEAD "\"width\":32,\"height\":32," DOC_VIEWS(
             "{\"eye\":[0,0,3],\"eye\":[0,0,3],\"target\":[0,0,0],\"half_fov\":0.4,"
             "\"light\":[1,0,3]}"),
         GLINT_EFORMAT, "duplicate"},
    };
    glint_err e;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        int rc = parse_doc(cases[i].doc, good_view, &e);
        ASSERT_MSG(rc == cases[i].code, "case %zu: got %d, want %d (%s)", i, rc, cases[i].code,
                   e.msg);
        ASSERT_MSG(e.code == rc && strstr(e.msg, cases[i].needle) != NULL,
                   "case %zu: message \"%s\" lacks \"%s\"", i, e.msg, cases[i].needle);
    }
    ASSERT_EQ(scene_from_json(NULL, &(scene){0}, &e), GLINT_EINVAL);
}

/* Too many views, deep nesting and random garbage: errors, never a crash. */
TEST(json_hostile)
{
    glint_err e;
    scene s;
    size_t n = 0, cap = (SCENE_MAX_VIEWS + 2) * 96 + 256;
    char *buf = malloc(cap);
    ASSERT(buf != NULL);
    n += (size_t)snprintf(buf + n, cap - n, DOC_HEAD "\"width\":32,\"height\":32,\"views\":[");
    for (int k = 0; k <= SCENE_MAX_VIEWS; k++)
        n += (size_t)snprintf(buf + n, cap - n, "%s%s", k ? "," : "", good_view);
    snprintf(buf + n, cap - n, "]}");
    ASSERT_EQ(scene_from_json(buf, &s, &e), GLINT_ERANGE);
    ASSERT(strstr(e.msg, "views") != NULL);
    free(buf);

    buf = malloc(200001);
    ASSERT(buf != NULL);
    memset(buf, '[', 100000);
    memset(buf + 100000, ']', 100000);
    buf[200000] = '\0';
    ASSERT_EQ(scene_from_json(buf, &s, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "deep") != NULL);
    /* every prefix of a valid document fails cleanly */
    {
        scene d;
        char *text;
        size_t len;
        ASSERT_OK(scene_create(&(scene_params){.mesh_name = "sphere", .width = 16,
                                               .height = 16, .distance = 3, .margin = 1,
                                               .light_lo_deg = 10, .light_hi_deg = 20},
                               &d, &e));
        text = scene_to_json(&d, &e);
        scene_free(&d);
        ASSERT(text != NULL);
        len = strlen(text);
        for (size_t cut = 0; cut < len; cut += 7) {
            char c = text[cut];
            int rc;
            text[cut] = '\0';
            rc = scene_from_json(text, &s, &e);
            text[cut] = c;
            ASSERT_MSG(rc == GLINT_EFORMAT, "prefix of %zu bytes: rc %d (%s)", cut, rc, e.msg);
        }
        /* bytes flipped at random positions: any error code, or success */
        srand(12345);
        for (int trial = 0; trial < 300; trial++) {
            char *mut = strdup(text);
            int rc;
            ASSERT(mut != NULL);
            for (int f = 0; f < 3; f++)
                mut[(size_t)rand() % len] = (char)(32 + rand() % 95);
            rc = scene_from_json(mut, &s, &e);
            if (rc == 0)
                scene_free(&s);
            else
                ASSERT_MSG(rc < 0 && e.msg[0], "trial %d: rc %d without a message", trial, rc);
            free(mut);
        }
        free(text);
    }
    free(buf);
}

TEST(validate)
{
    scene s;
    scene_params p;
    glint_err e;
    scene_params_default(&p);
    p.width = p.height = 16;
    ASSERT_OK(scene_create(&p, &s, &e));
    ASSERT_OK(scene_validate(&s, &e));
    s.views[2].eye[0] = NAN;
    ASSERT_EQ(scene_validate(&s, &e), GLINT_ENONFINITE);
    ASSERT(strstr(e.msg, "views[2].eye") != NULL);
    ASSERT(scene_to_json(&s, &e) == NULL);
    ASSERT_EQ(e.code, GLINT_ENONFINITE);
    memcpy(s.views[2].eye, s.views[2].target, sizeof s.views[2].eye);
    ASSERT_EQ(scene_validate(&s, &e), GLINT_EINVAL);
    s.views[2].eye[0] = 3.0;
    ASSERT_OK(scene_validate(&s, &e));
    s.nviews = 0;
    ASSERT_EQ(scene_validate(&s, &e), GLINT_ERANGE);
    s.nviews = 12;
    s.mesh.tri[0] = 0xffffffffu;
    ASSERT_EQ(scene_validate(&s, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "mesh") != NULL);
    ASSERT_EQ(scene_validate(NULL, &e), GLINT_EINVAL);
    scene_free(&s);
}

/* ---- saving and loading ------------------------------------------------------ */

TEST(save_load)
{
    char dir[] = "/tmp/glint_test_scene_XXXXXX";
    char path[256], h1[33], h2[33];
    scene s, t;
    scene_params p;
    glint_err e;
    FILE *f;

    ASSERT(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/views.json", dir);
    scene_params_default(&p);
    p.view_set = SCENE_VIEWS_ICO20;
    p.light_mid = 1;
    ASSERT_OK(scene_create(&p, &s, &e));
    ASSERT_OK(scene_save(&s, path, &e));
    ASSERT_OK(scene_save(&s, path, &e)); /* replacing works too */
    ASSERT_OK(scene_load(path, &t, &e));
    scene_hash(&s, h1);
    scene_hash(&t, h2);
    ASSERT(strcmp(h1, h2) == 0);
    scene_free(&t);
    /* nothing but the file is left in the directory */
    {
        char cmd[512];
        snprintf(cmd, sizeof cmd, "test $(ls -A '%s' | wc -l) -eq 1", dir);
        ASSERT_EQ(system(cmd), 0);
    }
    /* errors */
    f = fopen(path, "w");
    ASSERT(f != NULL);
    fputs("{\"format\":\"glint-scene\",", f);
    fclose(f);
    ASSERT_EQ(scene_load(path, &t, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, path) != NULL);
    unlink(path);
    ASSERT_EQ(scene_load(path, &t, &e), GLINT_ENOTFOUND);
    {
        char bad[300];
        snprintf(bad, sizeof bad, "%s/no/such/dir/x.json", dir);
        ASSERT_EQ(scene_save(&s, bad, &e), GLINT_EIO);
    }
    scene_free(&s);
    rmdir(dir);
}

TEST_LIST {
    TEST_ENTRY(json_round_trip_and_hash),
    TEST_ENTRY(hash_golden),
    TEST_ENTRY(json_minimal_and_explicit),
    TEST_ENTRY(json_malformed),
    TEST_ENTRY(json_hostile),
    TEST_ENTRY(validate),
    TEST_ENTRY(save_load),
};

TEST_MAIN()
