/* test_scene.c: meshes, default views (against ../shared/reference/hf_ref.py),
 * scene creation and its errors, and scenes whose mesh is a file or another
 * built-in.  JSON I/O, validation, the content hash and saving and loading
 * are in test_scene_json.c. */
#include <ctype.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "mesh.h"
#include "scene.h"
#include "vec3.h"

#define PHI 1.6180339887498949
#define TOL (64 * DBL_EPSILON)

static double deg(double rad) { return rad * 180.0 / 3.14159265358979323846; }

/* ---- meshes ------------------------------------------------------------ */

TEST(sphere_counts_and_validity)
{
    mesh m;
    glint_err e;
    ASSERT_OK(mesh_sphere(&m, 4, 6, &e));
    /* 2 poles x 6 copies + 3 rings x 7 vertices; 6 + 6 cap triangles + 2 bands x 12 */
    ASSERT_EQ(m.nverts, 2 * 6 + 3 * 7);
    ASSERT_EQ(m.ntris, 2 * 6 + 2 * 6 * 2);
    ASSERT_OK(mesh_validate(&m, &e));
    mesh_free(&m);
    ASSERT(m.pos == NULL && m.ntris == 0);
    mesh_free(&m); /* twice is fine */
    mesh_free(NULL);

    ASSERT_OK(mesh_sphere_default(&m, &e));
    ASSERT_EQ(m.nverts, 2 * 512 + 255 * 513);
    ASSERT_EQ(m.ntris, 2 * 512 + 2 * 512 * 254);
    ASSERT_OK(mesh_validate(&m, &e));
    mesh_free(&m);
}

/* Every triangle has positive area and faces outwards (CCW from outside);
 * normals are unit and equal the positions; uv follow (phi/2pi, theta/pi). */
TEST(sphere_geometry)
{
    mesh m;
    glint_err e;
    double min_area = INFINITY;
    ASSERT_OK(mesh_sphere(&m, 16, 24, &e));
    for (int t = 0; t < m.ntris; t++) {
        const uint32_t *f = m.tri + 3 * t;
        v3 a = v3_loadf(m.pos + 3 * f[0]), b = v3_loadf(m.pos + 3 * f[1]),
           c = v3_loadf(m.pos + 3 * f[2]);
        v3 n = v3_cross(v3_sub(b, a), v3_sub(c, a));
        v3 cen = v3_add(v3_add(a, b), c);
        double area = 0.5 * v3_len(n);
        if (area < min_area)
            min_area = area;
        ASSERT_MSG(v3_dot(n, cen) > 0.0, "triangle %d faces inwards", t);
    }
    ASSERT_LT(1e-4, min_area);
    for (int v = 0; v < m.nverts; v++) {
        v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
        double theta = acos(fmax(-1.0, fmin(1.0, p.z)));
        ASSERT_NEAR(v3_len(n), 1.0, 1e-6);
        ASSERT_NEAR(v3_len(v3_sub(p, n)), 0.0, 0.0);
        ASSERT_NEAR(m.uv[2 * v + 1], theta / 3.14159265358979323846, 1e-6);
        ASSERT(m.uv[2 * v] >= 0.0f && m.uv[2 * v] <= 1.0f);
        if (fabs(p.z) < 0.999) {
            double phi = atan2(p.y, p.x);
            double u = m.uv[2 * v];
            if (phi < 0)
                phi += 2 * 3.14159265358979323846;
            /* u == 1 on the duplicated seam, where phi reads 0 */
            ASSERT(fabs(u - phi / (2 * 3.14159265358979323846)) < 1e-6 ||
                   (u == 1.0f && phi < 1e-6));
        }
    }
    mesh_free(&m);
}

TEST(mesh_errors)
{
    mesh m;
    glint_err e;
    memset(&e, 0, sizeof e);
    ASSERT_EQ(mesh_sphere(&m, 1, 8, &e), GLINT_ERANGE);
    ASSERT(m.pos == NULL);
    ASSERT_EQ(mesh_sphere(&m, 8, 2, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_sphere(&m, 8, MESH_SPHERE_MAX_SEG + 1, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_builtin("cube", &m, &e), GLINT_ENOTFOUND);
    ASSERT(strstr(e.msg, "cube") && strstr(e.msg, "sphere"));
    ASSERT_EQ(mesh_builtin(NULL, &m, &e), GLINT_EINVAL);

    ASSERT_OK(mesh_sphere(&m, 3, 3, &e));
    m.tri[5] = (uint32_t)m.nverts;
    ASSERT_EQ(mesh_validate(&m, &e), GLINT_EFORMAT);
    ASSERT(strstr(e.msg, "triangle 1") != NULL);
    m.tri[5] = 0;
    ASSERT_OK(mesh_validate(&m, &e));
    m.pos[7] = NAN;
    ASSERT_EQ(mesh_validate(&m, &e), GLINT_ENONFINITE);
    m.pos[7] = 0.0f;
    m.uv[3] = INFINITY;
    ASSERT_EQ(mesh_validate(&m, &e), GLINT_ENONFINITE);
    m.uv[3] = 0.0f;
    m.nrm[4] = -INFINITY;
    ASSERT_EQ(mesh_validate(&m, &e), GLINT_ENONFINITE);
    ASSERT(strstr(e.msg, "vertex 1: normal") != NULL);
    m.nrm[4] = 0.0f;
    ASSERT_OK(mesh_validate(&m, &e));
    m.ntris = 0;
    ASSERT_EQ(mesh_validate(&m, &e), GLINT_EFORMAT);
    mesh_free(&m);
    ASSERT_EQ(mesh_validate(&m, &e), GLINT_EFORMAT);
}

/* ---- icosahedron and views ---------------------------------------------- */

TEST(icosahedron_vertices)
{
    static const double ref[12][3] = {
        {-1, PHI, 0}, {1, PHI, 0}, {-1, -PHI, 0}, {1, -PHI, 0},
        {0, -1, PHI}, {0, 1, PHI}, {0, -1, -PHI}, {0, 1, -PHI},
        {PHI, 0, -1}, {PHI, 0, 1}, {-PHI, 0, -1}, {-PHI, 0, 1}};
    double d[12][3];
    scene_icosahedron(d);
    ASSERT_NEAR(d[0][0], -0.52573111211913359, 1e-15);
    ASSERT_NEAR(d[0][1], 0.85065080835203988, 1e-15);
    ASSERT_NEAR(d[1][0], 0.52573111211913359, 1e-15);
    for (int i = 0; i < 12; i++) {
        v3 r = v3_normalize(v3_load(ref[i]));
        ASSERT_NEAR(v3_len(v3_load(d[i])), 1.0, TOL);
        ASSERT_NEAR(v3_len(v3_sub(r, v3_load(d[i]))), 0.0, TOL);
        for (int j = 0; j < i; j++)
            ASSERT_LT(1.0, v3_len(v3_sub(v3_load(d[i]), v3_load(d[j]))));
    }
}

TEST(icosahedron_faces)
{
    double v[12][3], f[20][3];
    /* first faces of the reference (lexicographic): (0,1,5), (0,1,7), (0,5,11) */
    static const int first[3][3] = {{0, 1, 5}, {0, 1, 7}, {0, 5, 11}};
    scene_icosahedron(v);
    scene_icosahedron_faces(f);
    for (int i = 0; i < 20; i++) {
        int near = 0;
        ASSERT_NEAR(v3_len(v3_load(f[i])), 1.0, TOL);
        for (int j = 0; j < i; j++)
            ASSERT_LT(0.5, v3_len(v3_sub(v3_load(f[i]), v3_load(f[j]))));
        /* a face centre is equidistant from exactly 3 vertices (its face) */
        for (int k = 0; k < 12; k++)
            near += v3_dot(v3_load(f[i]), v3_load(v[k])) > 0.79;
        ASSERT_EQ(near, 3);
    }
    for (int i = 0; i < 3; i++) {
        v3 c = v3_make(0, 0, 0);
        for (int k = 0; k < 3; k++)
            c = v3_add(c, v3_load(v[first[i][k]]));
        ASSERT_NEAR(v3_len(v3_sub(v3_normalize(c), v3_load(f[i]))), 0.0, TOL);
    }
    ASSERT_NEAR(f[0][1], 0.93417235896271578, 1e-15);
    ASSERT_NEAR(f[0][2], 0.35682208977308999, 1e-15);
}

TEST(default_views)
{
    scene s;
    scene_params p;
    glint_err e;
    double d[12][3];
    double tanfov = 1.1 / sqrt(3.5 * 3.5 - 1.0);

    scene_params_default(&p);
    ASSERT_EQ(p.width, 128);
    ASSERT_EQ(p.height, 128);
    ASSERT_OK(scene_create(&p, &s, &e));
    ASSERT_EQ(s.nviews, 12);
    ASSERT(strcmp(s.mesh_name, "sphere") == 0);
    ASSERT_EQ(s.mesh.ntris, 261120);
    scene_icosahedron(d);
    for (int k = 0; k < 12; k++) {
        const scene_view *v = &s.views[k];
        double f[3], r[3], u[3];
        v3 eye = v3_load(v->eye), light = v3_load(v->light);
        double want = 20.0 + 50.0 * k / 11.0;

        scene_view_frame(v, f, r, u);
        /* orthonormal, right-handed (right x up = -fwd), looking at the origin */
        ASSERT_NEAR(v3_len(v3_load(f)), 1.0, TOL);
        ASSERT_NEAR(v3_len(v3_load(r)), 1.0, TOL);
        ASSERT_NEAR(v3_len(v3_load(u)), 1.0, TOL);
        ASSERT_NEAR(v3_dot(v3_load(f), v3_load(r)), 0.0, TOL);
        ASSERT_NEAR(v3_dot(v3_load(f), v3_load(u)), 0.0, TOL);
        ASSERT_NEAR(v3_dot(v3_load(r), v3_load(u)), 0.0, TOL);
        ASSERT_NEAR(v3_len(v3_sub(v3_cross(v3_load(r), v3_load(u)), v3_scale(v3_load(f), -1))),
                    0.0, TOL);
        ASSERT_NEAR(v3_len(v3_add(v3_load(f), v3_load(d[k]))), 0.0, TOL);
        ASSERT_NEAR(r[2], 0.0, TOL); /* world up +z: right is horizontal */
        ASSERT_LT(0.0, u[2]);
        ASSERT_NEAR(v3_len(v3_sub(eye, v3_scale(v3_load(d[k]), 3.5))), 0.0, 4 * TOL);
        ASSERT_NEAR(v3_len(v3_load(v->target)), 0.0, 0.0);
        ASSERT_NEAR(tan(v->half_fov), tanfov, TOL);
        /* light: distance D, angle light_deg from the eye, rotated about up */
        ASSERT_NEAR(v->light_deg, want, 1e-12);
        ASSERT_NEAR(v->light_intensity, 1.0, 0.0);
        ASSERT_NEAR(v3_len(light), 3.5, 4 * TOL);
        ASSERT_NEAR(deg(acos(v3_dot(eye, light) / (3.5 * 3.5))), want, 1e-6);
        ASSERT_NEAR(v3_dot(light, v3_load(u)), 0.0, 4 * TOL);
        /* a positive rotation about up moves the light towards +right */
        ASSERT_LT(0.0, v3_dot(light, v3_load(r)));
    }
    /* exact numbers from hf_ref.py (make_view_set("vertices", 3.5, "20:70", "up")) */
    ASSERT_NEAR(s.views[0].light[0], -2.74737875, 1e-8);
    ASSERT_NEAR(s.views[0].light[1], 2.1683888, 1e-7);
    ASSERT_NEAR(s.views[1].light[0], 0.43697053, 1e-8);
    ASSERT_NEAR(s.views[1].light[1], 3.47261526, 1e-8);
    ASSERT_NEAR(s.views[5].light[0], -2.3747829404499625, 1e-14);
    ASSERT_NEAR(s.views[5].light[1], 1.3516920058110684, 1e-14);
    ASSERT_NEAR(s.views[5].light[2], 2.187083607723829, 1e-14);
    scene_free(&s);
    scene_free(&s);
    scene_free(NULL);
}

TEST(face_views_midpoints)
{
    scene s;
    scene_params p;
    glint_err e;
    double f[20][3];
    scene_params_default(&p);
    p.view_set = SCENE_VIEWS_ICO20;
    p.light_mid = 1;
    p.width = 64;
    p.height = 32;
    ASSERT_OK(scene_create(&p, &s, &e));
    ASSERT_EQ(s.nviews, 20);
    ASSERT_EQ(s.width, 64);
    ASSERT_EQ(s.height, 32);
    scene_icosahedron_faces(f);
    for (int k = 0; k < 20; k++) {
        ASSERT_NEAR(s.views[k].light_deg, 20.0 + 50.0 * (k + 0.5) / 20.0, 1e-12);
        ASSERT_NEAR(v3_len(v3_sub(v3_load(s.views[k].eye), v3_scale(v3_load(f[k]), 3.5))), 0.0,
                    1e-14);
    }
    /* hf_ref.py, make_view_set("faces", 3.5, "20:70:mid", "up")[0] */
    ASSERT_NEAR(s.views[0].eye[1], 3.2696032563695048, 1e-14);
    ASSERT_NEAR(s.views[0].light[0], -1.2685331339929558, 1e-14);
    ASSERT_NEAR(s.views[0].light[1], 3.047295964369042, 1e-14);
    ASSERT_NEAR(s.views[0].light[2], 1.1639634846085856, 1e-14);
    scene_free(&s);
}

/* Looking straight down the z axis switches the world up to +y. */
TEST(frame_near_pole)
{
    scene_view v;
    double dir[3] = {0, 0, 1}, f[3], r[3], u[3];
    scene_view_make(dir, 2.0, 1.0, 30.0, &v);
    scene_view_frame(&v, f, r, u);
    ASSERT_NEAR(f[2], -1.0, TOL);
    ASSERT_NEAR(v3_len(v3_load(r)), 1.0, TOL);
    ASSERT_NEAR(v3_len(v3_load(u)), 1.0, TOL);
    ASSERT_NEAR(v3_dot(v3_load(r), v3_load(u)), 0.0, TOL);
    ASSERT_NEAR(r[0], 1.0, TOL); /* fwd x +y = (0,0,-1) x (0,1,0) = (1,0,0) */
    ASSERT_NEAR(u[1], 1.0, TOL); /* right x fwd = +y */
    ASSERT_NEAR(deg(acos(v3_dot(v3_load(v.eye), v3_load(v.light)) / 4.0)), 30.0, 1e-9);
}

TEST(create_errors)
{
    scene s;
    scene_params p;
    glint_err e;

    scene_params_default(&p);
    p.width = 7;
    ASSERT_EQ(scene_create(&p, &s, &e), GLINT_ERANGE);
    ASSERT(strstr(e.msg, "width") != NULL);
    scene_params_default(&p);
    p.height = SCENE_MAX_SIZE + 1;
    ASSERT_EQ(scene_create(&p, &s, &e), GLINT_ERANGE);
    ASSERT(strstr(e.msg, "height") != NULL);
    scene_params_default(&p);
    p.distance = 1.0;
    ASSERT_EQ(scene_create(&p, &s, &e), GLINT_ERANGE);
    scene_params_default(&p);
    p.margin = NAN;
    ASSERT_EQ(scene_create(&p, &s, &e), GLINT_ERANGE);
    scene_params_default(&p);
    p.light_hi_deg = INFINITY;
    ASSERT_EQ(scene_create(&p, &s, &e), GLINT_ENONFINITE);
    scene_params_default(&p);
    p.view_set = 7;
    ASSERT_EQ(scene_create(&p, &s, &e), GLINT_EINVAL);
    scene_params_default(&p);
    snprintf(p.mesh_name, sizeof p.mesh_name, "cube");
    ASSERT_EQ(scene_create(&p, &s, &e), GLINT_ENOTFOUND);
    ASSERT(strstr(e.msg, "cube") != NULL);
    ASSERT(s.views == NULL && s.mesh.pos == NULL);
    ASSERT_EQ(scene_create(NULL, &s, &e), GLINT_EINVAL);
}

/* ---- meshes from files and the other built-ins ------------------------------ */

static const char tet_obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                              "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

static int put_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fputs(text, f);
    return fclose(f);
}

/* Replace the first occurrence of `from` in *text by `to` (reallocates). */
static void replace_once(char **text, const char *from, const char *to)
{
    char *at = strstr(*text, from), *n;
    size_t a, lf = strlen(from), lt = strlen(to), l = strlen(*text);
    if (!at) {
        fprintf(stderr, "replace_once: \"%s\" not found\n", from);
        exit(2);
    }
    a = (size_t)(at - *text);
    n = malloc(l - lf + lt + 1);
    if (!n)
        exit(2);
    memcpy(n, *text, a);
    memcpy(n + a, to, lt);
    memcpy(n + a + lt, at + lf, l - a - lf + 1);
    free(*text);
    *text = n;
}

TEST(mesh_file_scenes)
{
    char dir[] = "/tmp/glint_test_scene_mesh_XXXXXX";
    char path[512], sub[512], h1[33], h2[33];
    scene_params p;
    scene s, t;
    glint_err e;
    char *text;

    ASSERT(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/tet.obj", dir);
    ASSERT(put_file(path, tet_obj) == 0);
    scene_params_default(&p);
    p.width = p.height = 32;
    snprintf(p.mesh_path, sizeof p.mesh_path, "%s", path);
    ASSERT_OK(scene_create(&p, &s, &e));
    ASSERT(strcmp(s.mesh_name, "tet.obj") == 0); /* the label: the base name */
    ASSERT(strcmp(s.mesh_path, path) == 0);
    ASSERT_EQ(s.mesh.ntris, 4);
    ASSERT_EQ(s.mesh_info.ntris, 4);
    ASSERT_EQ(s.mesh_info.normals_generated, 1);
    ASSERT_EQ(s.mesh_info.uvs_generated, 1);
    scene_hash(&s, h1);

    /* JSON keeps the file; reading it back loads the same mesh */
    text = scene_to_json(&s, &e);
    ASSERT(text != NULL);
    ASSERT(strstr(text, "\"mesh_file\"") != NULL);
    ASSERT(strstr(text, "\"tet.obj\"") != NULL);
    ASSERT_OK(scene_from_json(text, &t, &e));
    scene_hash(&t, h2);
    ASSERT(strcmp(h1, h2) == 0);
    ASSERT(strcmp(t.mesh_path, path) == 0);
    scene_free(&t);

    /* save / load */
    snprintf(sub, sizeof sub, "%s/scene.json", dir);
    ASSERT_OK(scene_save(&s, sub, &e));
    ASSERT_OK(scene_load(sub, &t, &e));
    scene_hash(&t, h2);
    ASSERT(strcmp(h1, h2) == 0);
    scene_free(&t);

    /* a hand-written relative mesh_file is relative to the scene file */
    replace_once(&text, path, "tet.obj");
    ASSERT(strstr(text, "\"mesh_file\": \"tet.obj\"") != NULL);
    snprintf(sub, sizeof sub, "%s/rel.json", dir);
    ASSERT(put_file(sub, text) == 0);
    ASSERT_OK(scene_load(sub, &t, &e));
    ASSERT(strcmp(t.mesh_path, path) == 0);
    scene_hash(&t, h2);
    ASSERT(strcmp(h1, h2) == 0);
    scene_free(&t);
    /* ... also when the scene file's own path is relative */
    {
        int here = open(".", O_RDONLY);
        char want[600];
        ASSERT(here >= 0);
        ASSERT(chdir("/tmp") == 0);
        ASSERT_OK(scene_load(sub + strlen("/tmp/"), &t, &e));
        snprintf(want, sizeof want, "/tmp/%s/tet.obj", dir + strlen("/tmp/"));
        ASSERT_MSG(strcmp(t.mesh_path, want) == 0, "%s vs %s", t.mesh_path, want);
        scene_free(&t);
        /* scene_from_json: relative to the working directory */
        ASSERT(chdir(dir) == 0);
        ASSERT_OK(scene_from_json(text, &t, &e));
        ASSERT(strcmp(t.mesh_path, path) == 0);
        scene_free(&t);
        ASSERT(fchdir(here) == 0);
        close(here);
    }
    /* ... and from a subdirectory, with .. */
    {
        char *t2 = strdup(text), subdir[560];
        ASSERT(t2 != NULL);
        replace_once(&t2, "\"mesh_file\": \"tet.obj\"", "\"mesh_file\": \"../tet.obj\"");
        snprintf(subdir, sizeof subdir, "%s/sub", dir);
        ASSERT(mkdir(subdir, 0755) == 0);
        snprintf(sub, sizeof sub, "%s/sub/up.json", dir);
        ASSERT(put_file(sub, t2) == 0);
        ASSERT_OK(scene_load(sub, &t, &e));
        scene_hash(&t, h2);
        ASSERT(strcmp(h1, h2) == 0);
        scene_free(&t);
        unlink(sub);
        rmdir(subdir);
        free(t2);
    }

    /* the same bytes elsewhere: the same hash; other bytes: another hash */
    {
        char other[600];
        scene u;
        snprintf(other, sizeof other, "%s/copy.obj", dir);
        ASSERT(put_file(other, tet_obj) == 0);
        snprintf(p.mesh_path, sizeof p.mesh_path, "%s", other);
        ASSERT_OK(scene_create(&p, &u, &e));
        scene_hash(&u, h2);
        ASSERT(strcmp(h1, h2) == 0);
        scene_free(&u);
        ASSERT(put_file(other, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1.5\n"
                               "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n") == 0);
        ASSERT_OK(scene_create(&p, &u, &e));
        scene_hash(&u, h2);
        ASSERT(strcmp(h1, h2) != 0);
        scene_free(&u);
        /* a corrupt file: the loader's error, named */
        ASSERT(put_file(other, "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n") == 0);
        ASSERT_EQ(scene_create(&p, &u, &e), GLINT_ENONFINITE);
        ASSERT(strstr(e.msg, "copy.obj") != NULL);
        ASSERT(u.views == NULL && u.mesh.pos == NULL);
        unlink(other);
        /* missing */
        ASSERT_EQ(scene_create(&p, &u, &e), GLINT_ENOTFOUND);
    }

    /* malformed mesh_file fields */
    {
        char *bad = strdup(text);
        ASSERT(bad != NULL);
        replace_once(&bad, "\"mesh_file\": \"tet.obj\"", "\"mesh_file\": \"missing.obj\"");
        ASSERT_EQ(scene_from_json(bad, &t, &e), GLINT_ENOTFOUND);
        ASSERT(strstr(e.msg, "mesh_file") != NULL && strstr(e.msg, "missing.obj") != NULL);
        free(bad);
        bad = strdup(text);
        ASSERT(bad != NULL);
        replace_once(&bad, "\"mesh_file\": \"tet.obj\"", "\"mesh_file\": 7");
        ASSERT_EQ(scene_from_json(bad, &t, &e), GLINT_EFORMAT);
        ASSERT(strstr(e.msg, "mesh_file") != NULL);
        free(bad);
        bad = strdup(text);
        ASSERT(bad != NULL);
        replace_once(&bad, "\"mesh_file\": \"tet.obj\"", "\"mesh_file\": \"\"");
        ASSERT_EQ(scene_from_json(bad, &t, &e), GLINT_EFORMAT);
        free(bad);
        bad = strdup(text);
        ASSERT(bad != NULL);
        replace_once(&bad, "\"mesh_file\": \"tet.obj\"", "\"mesh_file\": \"tet\\u0000.obj\"");
        ASSERT_EQ(scene_from_json(bad, &t, &e), GLINT_EFORMAT);
        free(bad);
    }
    free(text);
    scene_free(&s);
    {
        char cmd[600];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
        ASSERT_EQ(system(cmd), 0);
    }
}

TEST(builtin_scenes)
{
    static const char *names[] = {"torus", "teapot"};
    char hs[33];
    scene s;
    scene_params p;
    glint_err e;
    char *text;
    scene_params_default(&p);
    p.width = p.height = 16;
    ASSERT_OK(scene_create(&p, &s, &e));
    scene_hash(&s, hs);
    text = scene_to_json(&s, &e);
    ASSERT(text && strstr(text, "mesh_file") == NULL); /* built-ins: no file key */
    free(text);
    scene_free(&s);
    for (int i = 0; i < 2; i++) {
        scene t;
        char h1[33], h2[33];
        snprintf(p.mesh_name, sizeof p.mesh_name, "%s", names[i]);
        ASSERT_OK(scene_create(&p, &s, &e));
        ASSERT(s.mesh_path[0] == '\0');
        ASSERT_EQ(s.mesh_info.ntris, 0);
        scene_hash(&s, h1);
        ASSERT(strcmp(h1, hs) != 0);
        text = scene_to_json(&s, &e);
        ASSERT(text != NULL);
        ASSERT_OK(scene_from_json(text, &t, &e));
        scene_hash(&t, h2);
        ASSERT(strcmp(h1, h2) == 0);
        free(text);
        scene_free(&t);
        scene_free(&s);
    }
}

/* The hash keys the precomputations kept on disk: a scene must hash as it
 * did when they were written.  The default scene's, as glint has computed
 * it since the hash's serialization version 1 (one value at a time; the
 * arrays now go in a block at a time); and -0 in a mesh's arrays hashes
 * as +0 on both paths. */
TEST(hash_is_stable)
{
    scene s;
    scene_params p;
    glint_err e;
    char h1[33], h2[33];
    scene_params_default(&p);
    p.width = p.height = 256;
    ASSERT_OK(scene_create(&p, &s, &e));
    scene_hash(&s, h1);
    ASSERT_MSG(strcmp(h1, "bd62a6327e383d8ab61a9a66bd0fa7a0") == 0, "hash %s", h1);
    for (int i = 0; i < 3 * s.mesh.nverts; i++)
        if (s.mesh.pos[i] == 0.0f)
            s.mesh.pos[i] = -0.0f;
    for (int i = 0; i < 2 * s.mesh.nverts; i++)
        if (s.mesh.uv[i] == 0.0f)
            s.mesh.uv[i] = -0.0f;
    scene_hash(&s, h2);
    ASSERT(strcmp(h1, h2) == 0);
    s.mesh.pos[3 * (s.mesh.nverts / 2)] += 1e-6f; /* any other value: another hash */
    scene_hash(&s, h2);
    ASSERT(strcmp(h1, h2) != 0);
    scene_free(&s);
}

TEST_LIST {
    TEST_ENTRY(sphere_counts_and_validity),
    TEST_ENTRY(sphere_geometry),
    TEST_ENTRY(mesh_errors),
    TEST_ENTRY(icosahedron_vertices),
    TEST_ENTRY(icosahedron_faces),
    TEST_ENTRY(default_views),
    TEST_ENTRY(face_views_midpoints),
    TEST_ENTRY(frame_near_pole),
    TEST_ENTRY(create_errors),
    TEST_ENTRY(mesh_file_scenes),
    TEST_ENTRY(builtin_scenes),
    TEST_ENTRY(hash_is_stable),
};

TEST_MAIN()
