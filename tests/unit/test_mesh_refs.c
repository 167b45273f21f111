/* test_mesh_refs.c: hostile and corrupt mesh files (empty, non-finite,
 * no triangles, over-limit claims, truncated, garbage, random mutations:
 * an error with a message, never a crash), argument errors, and references
 * to other files (an upload reads nothing but itself, a file on disk
 * nothing outside its directory).  The temporary directory is removed at
 * exit. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "mesh.h"
#include "mesh_checks.h"
#include "mesh_fixture.h"

/* ---- hostile input ---------------------------------------------------------- */

typedef struct bad_case {
    const char *name;  /* file name (extension = format) */
    const char *text;  /* NUL-terminated content, or NULL for bin */
    const buf *bin;
    int code;
    const char *needle;
} bad_case;

static int run_bad(const bad_case *c, glint_err *e, int *rc_mem)
{
    mesh m;
    const char *path = tmp_path(c->name);
    const void *data = c->text ? (const void *)c->text : c->bin->p;
    size_t len = c->text ? strlen(c->text) : c->bin->n;
    const char *dot = strrchr(c->name, '.');
    int rc;
    if (write_file(path, data, len))
        return 1000;
    memset(e, 0, sizeof *e);
    rc = mesh_load(path, &m, NULL, e);
    if (rc == 0 || m.pos || m.nverts)
        return rc == 0 ? 1001 : 1002;
    {
        glint_err e2;
        mesh mm;
        *rc_mem = mesh_load_mem(data, len, dot + 1, &mm, NULL, &e2);
        if (*rc_mem == 0)
            mesh_free(&mm);
    }
    return rc;
}

TEST(corrupt_inputs)
{
    buf ply_nan = {0}, ply_huge = {0}, ply_trunc = {0}, gltf_nan = {0}, glb_trunc = {0},
        gltf_points = {0}, ply_neg = {0}, garbage = {0};
    char *off_long, *obj_trunc, *dae_nocount;
    tet_ply_bin(&ply_nan, 2, NULL);
    tet_ply_bin(&ply_huge, -1, "2147483648");
    tet_ply_bin(&ply_trunc, -1, NULL);
    ply_trunc.n -= 7; /* cut inside the last face */
    tet_gltf(&gltf_nan, 3, NULL, 4, NULL);
    tet_glb(&glb_trunc);
    glb_trunc.n -= 30;
    tet_gltf(&gltf_points, -1, NULL, 0, NULL);
    /* a negative list length in a binary PLY (signed char count) */
    {
        const char *head = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                           "property float x\nproperty float y\nproperty float z\n"
                           "element face 1\nproperty list char int vertex_indices\nend_header\n";
        signed char neg = -3;
        buf_str(&ply_neg, head);
        for (int i = 0; i < 9; i++)
            buf_f32(&ply_neg, (float)(i % 4));
        buf_put(&ply_neg, &neg, 1);
        for (int i = 0; i < 3; i++)
            buf_u32(&ply_neg, (uint32_t)i);
    }
    srand(4242);
    for (int i = 0; i < 4096; i++) {
        unsigned char c = (unsigned char)(rand() & 255);
        buf_put(&garbage, &c, 1);
    }
    off_long = malloc(6000);
    ASSERT(off_long != NULL);
    {
        int n = snprintf(off_long, 6000, "OFF\n3 1 0\n0 0 0");
        memset(off_long + n, ' ', 5000);
        snprintf(off_long + n + 5000, 6000 - (size_t)n - 5000, "\n1 0 0\n0 1 0\n3 0 1 2\n");
    }
    /* assimp 5.2.4 dereferences NULL in its COLLADA reader when a
     * float_array has no count attribute: the import process dies, the
     * caller gets an error */
    dae_nocount = strdup(tet_dae);
    ASSERT(dae_nocount != NULL);
    {
        char *at = strstr(dae_nocount, " count=\"12\"");
        ASSERT(at != NULL);
        at[1] = 'x'; /* "xount" */
    }
    obj_trunc = strdup(box_obj);
    ASSERT(obj_trunc != NULL);
    obj_trunc[20] = '\0'; /* inside the vertex list: no face survives */

    {
        const bad_case cases[] = {
            /* empty files */
            {"empty.obj", "", NULL, GLINT_EFORMAT, "empty"},
            {"empty.ply", "", NULL, GLINT_EFORMAT, "empty"},
            {"empty.off", "", NULL, GLINT_EFORMAT, "empty"},
            {"empty.gltf", "", NULL, GLINT_EFORMAT, "empty"},
            {"empty.glb", "", NULL, GLINT_EFORMAT, "empty"},
            {"empty.dae", "", NULL, GLINT_EFORMAT, "empty"},
            /* non-finite coordinates */
            {"nan.obj", "v 0 0 0\nv 1 0 0\nv nan 0 0\nf 1 2 3\n", NULL, GLINT_ENONFINITE,
             "vertex"},
            {"inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n", NULL, GLINT_ENONFINITE,
             "vertex"},
            {"nan.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
             NULL, GLINT_ENONFINITE, "vertex 1"},
            {"nanbin.ply", NULL, &ply_nan, GLINT_ENONFINITE, "vertex 2"},
            {"nan.off", "OFF\n3 1 0\n0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n", NULL, GLINT_ENONFINITE,
             "vertex"},
            {"nan.gltf", NULL, &gltf_nan, GLINT_ENONFINITE, "vertex"},
            /* no triangles */
            {"notri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", NULL, GLINT_EFORMAT, ""},
            {"lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n", NULL, GLINT_EFORMAT,
             "triangles"},
            {"notri.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 0\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 0 0\n0 1 0\n",
             NULL, GLINT_EFORMAT, ""},
            {"notri.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", NULL, GLINT_EFORMAT, "faces"},
            {"points.gltf", NULL, &gltf_points, GLINT_EFORMAT, ""},
            {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", NULL, GLINT_EFORMAT,
             "zero area"},
            /* over-limit claims */
            {"huge.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 2147483648\n"
             "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
             "3 0 1 2\n",
             NULL, GLINT_ERANGE, "2147483648"},
            {"hugev.ply",
             "ply\nformat ascii 1.0\nelement vertex 1099511627776\nproperty float x\n"
             "property float y\nproperty float z\nend_header\n0 0 0\n",
             NULL, GLINT_ERANGE, "1099511627776"},
            {"hugebin.ply", NULL, &ply_huge, GLINT_ERANGE, "limit"},
            {"huge.off", "OFF\n3 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", NULL,
             GLINT_ERANGE, "4000000000"},
            {"wrap.off", "OFF\n3 4294967297 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", NULL,
             GLINT_ERANGE, "limit"},
            /* truncated */
            {"trunc.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0",
             NULL, GLINT_EFORMAT, "truncated"},
            {"truncbin.ply", NULL, &ply_trunc, GLINT_EFORMAT, "truncated"},
            {"trunc.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n", NULL,
             GLINT_EFORMAT, "truncated"},
            {"trunc.obj", obj_trunc, NULL, GLINT_EFORMAT, ""},
            {"trunc.gltf", "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"no", NULL,
             GLINT_EFORMAT, "assimp"},
            {"trunc.glb", NULL, &glb_trunc, GLINT_EFORMAT, "assimp"},
            {"trunc.dae", "<?xml version=\"1.0\"?>\n<COLLADA xmlns=\"http://www.collada.org/"
                          "2005/11/COLLADASchema\" version=\"1.4.1\"><library_geometries>"
                          "<geometry id=\"g\"><mesh><source id=\"s\"><float_array count=\"9\">"
                          "0 0 0 1",
             NULL, GLINT_EFORMAT, "assimp"},
            /* garbage */
            {"garbage.obj", NULL, &garbage, GLINT_EFORMAT, ""},
            /* named .ply: the pre-scan wants end_header (assimp loops without) */
            {"garbage.ply", NULL, &garbage, GLINT_EFORMAT, "end_header"},
            {"garbage.off", NULL, &garbage, GLINT_EFORMAT, ""},
            {"garbage.gltf", NULL, &garbage, GLINT_EFORMAT, "assimp"},
            {"garbage.glb", NULL, &garbage, GLINT_EFORMAT, "assimp"},
            {"garbage.dae", NULL, &garbage, GLINT_EFORMAT, "assimp"},
            {"garbage.stl", NULL, &garbage, GLINT_EFORMAT, ""},
            /* structural */
            {"neg.ply", NULL, &ply_neg, GLINT_EFORMAT, "list length"},
            {"long.off", off_long, NULL, GLINT_EFORMAT, "bytes long"},
            {"nocount.dae", dae_nocount, NULL, GLINT_EFORMAT, ""},
            {"badlist.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n0 0 0\n1 0 0\n0 1 0\n99999999 0 1 2\n",
             NULL, GLINT_EFORMAT, "list length"},
        };
        for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
            glint_err e;
            int rc_mem = 0, rc = run_bad(&cases[i], &e, &rc_mem);
            ASSERT_MSG(rc == cases[i].code, "%s: got %d, want %d (%s)", cases[i].name, rc,
                       cases[i].code, e.msg);
            ASSERT_MSG(e.code == rc && e.msg[0] && strstr(e.msg, cases[i].needle) != NULL,
                       "%s: message \"%s\" lacks \"%s\"", cases[i].name, e.msg, cases[i].needle);
            if (strcmp(cases[i].name, "nocount.dae") == 0)
                printf("  %s: %s\n", cases[i].name, e.msg);
            /* from memory: the same verdict (the empty buffer is refused as such) */
            ASSERT_MSG(rc_mem == cases[i].code, "%s from memory: got %d, want %d",
                       cases[i].name, rc_mem, cases[i].code);
        }
    }
    free(ply_nan.p);
    free(ply_huge.p);
    free(ply_trunc.p);
    free(gltf_nan.p);
    free(glb_trunc.p);
    free(gltf_points.p);
    free(ply_neg.p);
    free(garbage.p);
    free(off_long);
    free(obj_trunc);
    free(dae_nocount);
}

TEST(argument_errors)
{
    mesh m;
    mesh_report r;
    glint_err e;
    memset(&r, 0x55, sizeof r);
    ASSERT_EQ(mesh_load(tmp_path("no_such_file.ply"), &m, &r, &e), GLINT_ENOTFOUND);
    ASSERT(strstr(e.msg, "no_such_file.ply") != NULL);
    ASSERT(m.pos == NULL && r.ntris == 0);
    ASSERT_EQ(mesh_load(tmp_dir, &m, NULL, &e), GLINT_EINVAL); /* a directory */
    ASSERT_EQ(mesh_load(NULL, &m, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(mesh_load("", &m, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(mesh_load("x.ply", NULL, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(mesh_load_mem(box_obj, strlen(box_obj), NULL, &m, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(mesh_load_mem(box_obj, strlen(box_obj), "o/bj", &m, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(mesh_load_mem(box_obj, strlen(box_obj), "averyveryverylongextension", &m, NULL,
                            &e), GLINT_EINVAL);
    ASSERT_EQ(mesh_load_mem(NULL, 10, "obj", &m, NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(mesh_load_mem(box_obj, 0, "obj", &m, NULL, &e), GLINT_EFORMAT);
    ASSERT_EQ(mesh_load_mem(box_obj, MESH_MAX_FILE_BYTES + 1, "obj", &m, NULL, &e),
              GLINT_ERANGE);
    /* the hint is the format: OBJ text read as PLY fails */
    ASSERT_EQ(mesh_load_mem(box_obj, strlen(box_obj), "ply", &m, NULL, &e), GLINT_EFORMAT);
    /* ".OBJ" and "OBJ" are fine hints */
    ASSERT_OK(mesh_load_mem(box_obj, strlen(box_obj), ".OBJ", &m, &r, &e));
    ASSERT(strcmp(r.format, "obj") == 0);
    mesh_free(&m);
    /* an over-large file is refused before reading (sparse file) */
    {
        const char *big = tmp_path("big.obj");
        FILE *f = fopen(big, "wb");
        ASSERT(f != NULL);
        ASSERT(fseek(f, (long)MESH_MAX_FILE_BYTES, SEEK_SET) == 0);
        fputc('\n', f);
        fclose(f);
        ASSERT_EQ(mesh_load(big, &m, NULL, &e), GLINT_ERANGE);
        ASSERT(strstr(e.msg, "limit") != NULL);
        unlink(big);
    }
    /* the other entry points */
    ASSERT_EQ(mesh_generate_uvs(NULL, &e), GLINT_EINVAL);
    ASSERT_EQ(mesh_compute_normals(NULL, &e), GLINT_EINVAL);
    mesh_normalize(NULL, NULL, NULL);
}

/* ---- references to other files --------------------------------------------- */

/* The tetrahedron as glTF whose buffer is `buffer_uri` (NULL: the data in a
 * data: URI) and, when `image_uri` is non-NULL, with a material whose base
 * colour texture is that image.  Owned by the caller. */
static char *tet_gltf_refs(const char *buffer_uri, const char *image_uri)
{
    static const char prim[] = "\"mode\":4}";
    buf bin = {0};
    char *b64, *uri, *json, *out, *at;
    size_t n;
    tet_gltf_bin(&bin, -1);
    b64 = base64(bin.p, bin.n);
    uri = malloc(strlen(b64) + 64);
    if (!uri)
        exit(2);
    sprintf(uri, "data:application/octet-stream;base64,%s", b64);
    json = tet_gltf_json(buffer_uri ? buffer_uri : uri, "[{\"mesh\":0}]", 4, NULL);
    n = strlen(json) + (image_uri ? strlen(image_uri) : 0) + 512;
    out = malloc(n);
    if (!out)
        exit(2);
    at = strstr(json, prim);
    if (!image_uri || !at) {
        snprintf(out, n, "%s", json);
    } else {
        json[strlen(json) - 1] = '\0'; /* the closing brace */
        *at = '\0';
        snprintf(out, n,
                 "%s\"mode\":4,\"material\":0}%s,"
                 "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0}}}],"
                 "\"textures\":[{\"source\":0}],\"images\":[{\"uri\":\"%s\"}]}",
                 json, at + strlen(prim), image_uri);
    }
    free(json);
    free(uri);
    free(b64);
    free(bin.p);
    return out;
}

/* The tetrahedron as COLLADA with a material whose diffuse texture is the
 * image at `image` (an <init_from> path).  Owned by the caller. */
static char *tet_dae_image(const char *image)
{
    const char *geo = strstr(tet_dae, " <library_geometries>");
    const char *vis = strstr(tet_dae, " <library_visual_scenes>");
    size_t n = strlen(tet_dae) + strlen(image) + 2048;
    char *out = malloc(n), *tri;
    if (!out || !geo || !vis)
        exit(2);
    snprintf(out, n,
             "%.*s"
             " <library_images><image id=\"img\"><init_from>%s</init_from></image>"
             "</library_images>\n"
             " <library_effects><effect id=\"fx\"><profile_COMMON><technique sid=\"t\"><lambert>"
             "<diffuse><texture texture=\"img\" texcoord=\"uv0\"/></diffuse></lambert>"
             "</technique></profile_COMMON></effect></library_effects>\n"
             " <library_materials><material id=\"mat\"><instance_effect url=\"#fx\"/></material>"
             "</library_materials>\n"
             "%.*s"
             " <library_visual_scenes><visual_scene id=\"scene\"><node id=\"n0\">"
             "<instance_geometry url=\"#tet\"><bind_material><technique_common>"
             "<instance_material symbol=\"m\" target=\"#mat\"/></technique_common>"
             "</bind_material></instance_geometry></node></visual_scene>"
             "</library_visual_scenes>\n"
             " <scene><instance_visual_scene url=\"#scene\"/></scene>\n"
             "</COLLADA>\n",
             (int)(geo - tet_dae), tet_dae, image, (int)(vis - geo), geo);
    /* the triangles use the material */
    {
        static const char plain[] = "<triangles count=\"4\">",
                          bound[] = "<triangles material=\"m\" count=\"4\">";
        tri = strstr(out, plain);
        if (!tri)
            exit(2);
        memmove(tri + strlen(bound), tri + strlen(plain), strlen(tri) - strlen(plain) + 1);
        memcpy(tri, bound, strlen(bound));
    }
    return out;
}

/* `msg` with every occurrence of `ref` replaced by "<ref>": messages about
 * different references compare equal when they have the same shape. */
static void msg_shape(const char *msg, const char *ref, char *out, size_t n)
{
    size_t o = 0, rl = strlen(ref);
    while (*msg && o + 6 < n) {
        if (rl && strncmp(msg, ref, rl) == 0) {
            memcpy(out + o, "<ref>", 5);
            o += 5;
            msg += rl;
        } else {
            out[o++] = *msg++;
        }
    }
    out[o] = '\0';
}

/* Loading an upload that refers to a file is refused with the same code and
 * message shape whatever the reference, whether the file exists or not; the
 * message names the reference and nothing read from anywhere.  The first
 * call stores the shape in shape0, later ones compare with it.  Returns 1
 * if so, else 0 with the reason in why. */
static int upload_refused(const void *data, size_t len, const char *fmt, const char *ref,
                          char *shape0, size_t shapelen, char *why, size_t whylen)
{
    mesh m;
    glint_err e;
    char shape[GLINT_ERR_MSG_MAX];
    int rc;
    memset(&e, 0, sizeof e);
    rc = mesh_load_mem(data, len, fmt, &m, NULL, &e);
    if (rc == 0)
        mesh_free(&m);
    if (rc != GLINT_EINVAL || m.pos || m.nverts) {
        snprintf(why, whylen, "%s upload referring to \"%s\": got %d, want %d (%s)", fmt, ref, rc,
                 GLINT_EINVAL, e.msg);
        return 0;
    }
    if (!strstr(e.msg, "external references are not allowed in uploads") ||
        !strstr(e.msg, ref) || strstr(e.msg, "root:")) {
        snprintf(why, whylen, "%s: the message does not name the reference and the rule, or "
                 "quotes a file: %s", ref, e.msg);
        return 0;
    }
    msg_shape(e.msg, ref, shape, sizeof shape);
    if (!shape0[0])
        snprintf(shape0, shapelen, "%s", shape);
    if (strcmp(shape, shape0) != 0) {
        snprintf(why, whylen, "message shapes differ:\n    %s\n    %s", shape, shape0);
        return 0;
    }
    return 1;
}

/* glTF buffers and images that name files outside the upload, present or
 * not (/etc/passwd exists everywhere this runs), are all refused alike;
 * data: URIs still load, and an image by a plain relative name (never read,
 * glint uses only the geometry) does too. */
TEST(refs_upload_gltf)
{
    static const char *const refs[] = {"/etc/passwd", "../../etc/passwd", "file:///etc/passwd",
                                       "/etc/glint-no-such-file", "../../glint-no-such-dir/x.bin",
                                       "file:///etc/glint-no-such-file"};
    char shape0[GLINT_ERR_MSG_MAX] = "", why[2 * GLINT_ERR_MSG_MAX];
    const size_t nrefs = sizeof refs / sizeof refs[0];
    for (int image = 0; image < 2; image++)
        for (size_t i = 0; i < nrefs; i++) {
            char *g = image ? tet_gltf_refs(NULL, refs[i]) : tet_gltf_refs(refs[i], NULL);
            int ok = upload_refused(g, strlen(g), "gltf", refs[i], shape0, sizeof shape0, why,
                                    sizeof why);
            free(g);
            ASSERT_MSG(ok, "%s %s", image ? "image" : "buffer", why);
        }
    /* a buffer by a relative name: an upload has no files beside it */
    {
        char *g = tet_gltf_refs("tet.bin", NULL);
        int ok = upload_refused(g, strlen(g), "gltf", "tet.bin", shape0, sizeof shape0, why,
                                sizeof why);
        free(g);
        ASSERT_MSG(ok, "buffer %s", why);
    }
    /* a long reference is cut in the message */
    {
        char ref[300], *g;
        mesh m;
        glint_err e;
        ref[0] = '/';
        memset(ref + 1, 'a', sizeof ref - 2);
        ref[sizeof ref - 1] = '\0';
        g = tet_gltf_refs(ref, NULL);
        ASSERT_EQ(mesh_load_mem(g, strlen(g), "gltf", &m, NULL, &e), GLINT_EINVAL);
        free(g);
        ASSERT(strstr(e.msg, "/aaaaaaaaaa") != NULL && strstr(e.msg, "...") != NULL);
        ASSERT(strstr(e.msg, ref) == NULL);
    }
    /* data: URIs (buffer and image) and a relative image name still load */
    {
        static const char png[] = "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAf"
                                  "FcSJAAAADUlEQVR42mNkYPhfDwAChwGA60e6kgAAAABJRU5ErkJggg==";
        const char *images[] = {NULL, png, "tex.png", "textures/tex.png"};
        for (int i = 0; i < 4; i++) {
            char *g = tet_gltf_refs(NULL, images[i]);
            mesh m;
            glint_err e;
            ASSERT_MSG(mesh_load_mem(g, strlen(g), "gltf", &m, NULL, &e) == 0, "image %s: %s",
                       images[i] ? images[i] : "(none)", e.msg);
            ASSERT_EQ(m.ntris, 4);
            mesh_free(&m);
            free(g);
        }
    }
}

/* OBJ material libraries and COLLADA images outside the upload. */
TEST(refs_upload_obj_dae)
{
    static const char *const refs[] = {"/etc/passwd", "../../etc/passwd",
                                       "/etc/glint-no-such-file"};
    char shape_obj[GLINT_ERR_MSG_MAX] = "", shape_dae[GLINT_ERR_MSG_MAX] = "";
    char why[2 * GLINT_ERR_MSG_MAX];
    for (size_t i = 0; i < sizeof refs / sizeof refs[0]; i++) {
        char obj[1024];
        snprintf(obj, sizeof obj, "mtllib %s\nusemtl red\n%s", refs[i], box_obj);
        ASSERT_MSG(upload_refused(obj, strlen(obj), "obj", refs[i], shape_obj, sizeof shape_obj,
                                  why, sizeof why), "%s", why);
    }
    for (size_t i = 0; i < sizeof refs / sizeof refs[0]; i++) {
        char *d = tet_dae_image(refs[i]);
        int ok = upload_refused(d, strlen(d), "dae", refs[i], shape_dae, sizeof shape_dae, why,
                                sizeof why);
        free(d);
        ASSERT_MSG(ok, "%s", why);
    }
    {
        char *d = tet_dae_image("file:///etc/passwd");
        mesh m;
        glint_err e;
        ASSERT_EQ(mesh_load_mem(d, strlen(d), "dae", &m, NULL, &e), GLINT_EINVAL);
        ASSERT(strstr(e.msg, "etc/passwd") && strstr(e.msg, "not allowed in uploads"));
        free(d);
    }
    /* plain relative names: nothing is read, the geometry loads */
    {
        char obj[1024], *d = tet_dae_image("tex.png");
        mesh m;
        glint_err e;
        snprintf(obj, sizeof obj, "mtllib box.mtl\nusemtl red\n%s", box_obj);
        ASSERT_MSG(mesh_load_mem(obj, strlen(obj), "obj", &m, NULL, &e) == 0, "%s", e.msg);
        ASSERT_EQ(m.ntris, 12);
        mesh_free(&m);
        ASSERT_MSG(mesh_load_mem(d, strlen(d), "dae", &m, NULL, &e) == 0, "%s", e.msg);
        ASSERT_EQ(m.ntris, 4);
        mesh_free(&m);
        free(d);
    }
}

/* What an upload's text names, used or not, is found before any import:
 * every reference but data: URIs is refused in mesh_load_mem's words,
 * naming it; files without references, data: URIs, COLLADA ids inside
 * the document ('#', a <surface>'s <init_from>) and metadata pass. */
TEST(refs_upload_text)
{
    static const char *const refused[][3] = {
        /* format, text, the reference the message names */
        {"gltf", "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"tex.png\"}]}",
         "tex.png"},
        {"gltf", "{\"images\": [ {\"name\":\"x\", \"\\u0075ri\" : \"/etc/passwd\"} ]}",
         "/etc/passwd"},
        {"gltf", "{\"extensions\":{\"X\":{\"deep\":[{\"uri\":\"file:///etc/passwd\"}]}}}",
         "file:///etc/passwd"},
        /* escaped quotes in other strings do not end them; escapes in the reference */
        {"gltf", "{\"name\":\"say \\\"uri\\\": \\\"x\\\"\",\"images\":[{\"uri\":\"dir\\/t.png\"}]}",
         "dir/t.png"},
        {"obj", "mtllib model.mtl\nv 0 0 0\n", "model.mtl"},
        {"obj", "v 0 0 0\r\n  maplib  maps.mpl  \r\n", "maps.mpl"},
        {"obj", "call other.obj 1 2\n", "other.obj 1 2"},
        {"dae", "<COLLADA><library_images><image id=\"i\"><init_from>file:///etc/passwd"
                "</init_from></image></library_images></COLLADA>", "file:///etc/passwd"},
        {"dae", "<COLLADA><image><init_from>\n  <![CDATA[../../etc/passwd]]>\n</init_from>"
                "</image></COLLADA>", "../../etc/passwd"},
        {"dae", "<COLLADA><image><init_from><ref>tex.png</ref></init_from></image></COLLADA>",
         "tex.png"},
        {"dae", "<COLLADA><image><init_from><!-- a note -->t.png</init_from></image></COLLADA>",
         "t.png"},
        {"dae", "<COLLADA><node><instance_geometry url='other.dae#geo'/></node></COLLADA>",
         "other.dae#geo"},
        {"dae", "<?xml version=\"1.0\"?><!DOCTYPE c [<!ENTITY x SYSTEM \"/etc/passwd\">]>"
                "<COLLADA/>", "/etc/passwd"},
        {"ply", "ply\nformat ascii 1.0\ncomment TextureFile skin.png\nelement vertex 0\n"
                "end_header\n", "skin.png"},
        /* named as another format: scanned for what it is */
        {"obj", "{\"buffers\":[{\"uri\":\"tet.bin\"}]}", "tet.bin"},
        {"ply", "<COLLADA><image><init_from>t.png</init_from></image></COLLADA>", "t.png"},
    };
    static const char *const passed[][2] = {
        {"gltf", "{\"buffers\":[{\"uri\":\"data:application/octet-stream;base64,AAAA\"}],"
                 "\"images\":[{\"uri\":\"DATA:image/png;base64,AA\"}],\"name\":\"uri\"}"},
        {"obj", "# mtllib commented.mtl\nv 0 0 0\nusemtl red\n"},
        {"dae", "<COLLADA><asset><contributor><source_data>file:///C:/work/model.max"
                "</source_data></contributor></asset><!-- <init_from>/etc/passwd</init_from> -->"
                "<newparam sid=\"s\"><surface type=\"2D\"><init_from>img_id</init_from>"
                "</surface></newparam><input semantic=\"V\" source=\"#v\"/>"
                "<instance_effect url=\"#fx\"/></COLLADA>"},
        {"ply", "ply\nformat ascii 1.0\ncomment made by hand\nend_header\n"
                "comment TextureFile after.png\n"},
        {"off", "OFF\n0 0 0\n"},
    };
    char shape0[GLINT_ERR_MSG_MAX] = "", shape[GLINT_ERR_MSG_MAX];
    glint_err e;
    for (size_t i = 0; i < sizeof refused / sizeof refused[0]; i++) {
        const char *fmt = refused[i][0], *text = refused[i][1], *ref = refused[i][2];
        char what[64];
        memset(&e, 0, sizeof e);
        ASSERT_MSG(mesh_refs_check(text, strlen(text), fmt, &e) == GLINT_EINVAL,
                   "case %zu (%s) not refused", i, ref);
        ASSERT_MSG(strstr(e.msg, ref) && strstr(e.msg, "external references are not allowed "
                                                       "in uploads"),
                   "case %zu: %s", i, e.msg);
        /* the same words for every reference and format */
        msg_shape(e.msg, ref, shape, sizeof shape);
        snprintf(what, sizeof what, "%s data", fmt);
        msg_shape(shape, what, shape, sizeof shape);
        if (!shape0[0])
            snprintf(shape0, sizeof shape0, "%s", shape);
        ASSERT_MSG(strcmp(shape, shape0) == 0, "case %zu: %s / %s", i, shape, shape0);
    }
    for (size_t i = 0; i < sizeof passed / sizeof passed[0]; i++) {
        const char *text = passed[i][1];
        ASSERT_MSG(mesh_refs_check(text, strlen(text), passed[i][0], &e) == 0, "case %zu: %s",
                   i, e.msg);
    }
    /* the fixtures' own files: what earlier tests load */
    {
        char *g = tet_gltf_refs(NULL, NULL), *d = tet_dae_image("tex.png");
        ASSERT_OK(mesh_refs_check(g, strlen(g), "gltf", &e));
        ASSERT_OK(mesh_refs_check(box_obj, strlen(box_obj), "obj", &e));
        ASSERT_EQ(mesh_refs_check(d, strlen(d), "dae", &e), GLINT_EINVAL);
        ASSERT(strstr(e.msg, "\"tex.png\""));
        free(g);
        free(d);
    }
    /* a .glb: its JSON chunk is read, its binary chunk is part of the file */
    {
        static const char json[] = "{\"images\":[{\"uri\":\"t.png\"}]} ";
        unsigned char glb[12 + 8 + sizeof json - 1];
        uint32_t n = sizeof glb, c = sizeof json - 1, t = 0x4E4F534Au, v = 2;
        memcpy(glb, "glTF", 4);
        memcpy(glb + 4, &v, 4); /* the tests run little-endian, as glTF is */
        memcpy(glb + 8, &n, 4);
        memcpy(glb + 12, &c, 4);
        memcpy(glb + 16, &t, 4);
        memcpy(glb + 20, json, c);
        ASSERT_EQ(mesh_refs_check(glb, sizeof glb, "glb", &e), GLINT_EINVAL);
        ASSERT(strstr(e.msg, "t.png"));
        c = 1000; /* a chunk longer than the file: read to its end */
        memcpy(glb + 12, &c, 4);
        ASSERT_EQ(mesh_refs_check(glb, sizeof glb, "glb", &e), GLINT_EINVAL);
        ASSERT_OK(mesh_refs_check(glb, 19, "glb", &e));
    }
    /* truncated text ends the scan without reading past the end */
    {
        static const char cut[] = "{\"images\":[{\"uri\":\"/etc/pass";
        ASSERT_OK(mesh_refs_check(cut, strlen(cut), "gltf", &e));
        ASSERT_OK(mesh_refs_check("<COLLADA><image><init_from", 26, "dae", &e));
        ASSERT_OK(mesh_refs_check("", 0, "obj", &e));
        ASSERT_EQ(mesh_refs_check(NULL, 3, "obj", &e), GLINT_EINVAL);
    }
}

/* From disk, a file may refer to files in its directory and below it; an
 * absolute path, a '..' that leaves the directory or a URI scheme is
 * refused, even when the file it names exists. */
TEST(refs_disk)
{
    buf bin = {0};
    char dir[256], sub[300], path[512], binpath[512], fileuri[600];
    mesh m, ref;
    mesh_report r, rr;
    glint_err e;
    snprintf(dir, sizeof dir, "%s", tmp_path("refs"));
    snprintf(sub, sizeof sub, "%s/sub", dir);
    ASSERT(mkdir(dir, 0700) == 0 && mkdir(sub, 0700) == 0);
    tet_gltf_bin(&bin, -1);
    snprintf(binpath, sizeof binpath, "%s/tet.bin", dir);
    ASSERT(write_file(binpath, bin.p, bin.n) == 0);
    snprintf(path, sizeof path, "%s/tet.bin", sub);
    ASSERT(write_file(path, bin.p, bin.n) == 0);
    free(bin.p);
    /* the reference: the same tetrahedron with its data inline */
    {
        char *g = tet_gltf_refs(NULL, NULL);
        ASSERT_OK(mesh_load_mem(g, strlen(g), "gltf", &ref, &rr, &e));
        free(g);
    }
    {
        /* name, buffer uri, image uri, expected code, message needle */
        const struct {
            const char *name, *buffer, *image;
            int code;
            const char *needle;
        } cases[] = {
            {"sibling.gltf", "tet.bin", NULL, 0, NULL},
            {"below.gltf", "sub/tet.bin", NULL, 0, NULL},
            {"dot.gltf", "./sub/../tet.bin", "tex.png", 0, NULL},
            {"sub/up.gltf", "../tet.bin", NULL, GLINT_EINVAL, "leaves its directory"},
            {"sub/upup.gltf", "../../refs/tet.bin", NULL, GLINT_EINVAL, "leaves its directory"},
            /* out and back in again is out: the parent is not the file's */
            {"sub/back.gltf", "../sub/tet.bin", NULL, GLINT_EINVAL, "leaves its directory"},
            {"abs.gltf", binpath, NULL, GLINT_EINVAL, "absolute path"},
            {"etc.gltf", "/etc/passwd", NULL, GLINT_EINVAL, "absolute path"},
            {"uri.gltf", fileuri, NULL, GLINT_EINVAL, "scheme"},
            {"img.gltf", NULL, "/etc/passwd", GLINT_EINVAL, "absolute path"},
            {"imgup.gltf", NULL, "../../etc/passwd", GLINT_EINVAL, "leaves its directory"},
            /* a missing file is assimp's own error, not a refusal */
            {"missing.gltf", "no-such.bin", NULL, GLINT_EFORMAT, "no-such.bin"},
            {"missingsub.gltf", "sub/no-such.bin", NULL, GLINT_EFORMAT, "no-such.bin"},
        };
        snprintf(fileuri, sizeof fileuri, "file://%s", binpath);
        for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
            char *g = tet_gltf_refs(cases[i].buffer, cases[i].image);
            int rc;
            snprintf(path, sizeof path, "%s/%s", dir, cases[i].name);
            ASSERT(write_text(path, g) == 0);
            free(g);
            memset(&e, 0, sizeof e);
            rc = mesh_load(path, &m, &r, &e);
            ASSERT_MSG(rc == cases[i].code, "%s: got %d, want %d (%s)", cases[i].name, rc,
                       cases[i].code, e.msg);
            if (rc == 0) {
                ASSERT_EQ(m.ntris, ref.ntris);
                ASSERT(memcmp(m.pos, ref.pos, 3 * sizeof(float) * (size_t)m.nverts) == 0);
                mesh_free(&m);
            } else {
                ASSERT_MSG(strstr(e.msg, cases[i].needle) != NULL, "%s: \"%s\" lacks \"%s\"",
                           cases[i].name, e.msg, cases[i].needle);
            }
        }
    }
    /* a path relative to the working directory (the command line's case) */
    {
        char cwd[1024];
        int rc_sib, rc_etc;
        ASSERT(getcwd(cwd, sizeof cwd) != NULL);
        ASSERT(chdir(dir) == 0);
        rc_sib = mesh_load("sibling.gltf", &m, NULL, &e);
        if (rc_sib == 0)
            mesh_free(&m);
        rc_etc = mesh_load("etc.gltf", &m, NULL, &e);
        if (rc_etc == 0)
            mesh_free(&m);
        ASSERT(chdir(cwd) == 0);
        ASSERT_EQ(rc_sib, 0);
        ASSERT_EQ(rc_etc, GLINT_EINVAL);
        ASSERT(strstr(e.msg, "\"/etc/passwd\", an absolute path") != NULL);
    }
    /* OBJ material libraries */
    {
        char obj[1024];
        snprintf(path, sizeof path, "%s/box.mtl", dir);
        ASSERT(write_text(path, "newmtl red\nKd 1 0 0\n") == 0);
        snprintf(obj, sizeof obj, "mtllib box.mtl\nusemtl red\n%s", box_obj);
        snprintf(path, sizeof path, "%s/box.obj", dir);
        ASSERT(write_text(path, obj) == 0);
        ASSERT_MSG(mesh_load(path, &m, NULL, &e) == 0, "%s", e.msg);
        mesh_free(&m);
        snprintf(obj, sizeof obj, "mtllib /etc/passwd\nusemtl red\n%s", box_obj);
        snprintf(path, sizeof path, "%s/boxabs.obj", dir);
        ASSERT(write_text(path, obj) == 0);
        ASSERT_EQ(mesh_load(path, &m, NULL, &e), GLINT_EINVAL);
        ASSERT(strstr(e.msg, "\"/etc/passwd\"") && strstr(e.msg, "absolute path"));
    }
    mesh_free(&ref);
}

/* Random mutations of valid files in every format: an error with a message
 * or a valid mesh, never a crash (run this under ASan). */
TEST(fuzz_mutations)
{
    buf bins[4] = {{0}};
    const char *exts[7] = {"obj", "off", "ply", "ply", "gltf", "glb", "dae"};
    const void *data[7];
    size_t len[7];
    int nok = 0, nerr = 0, ncrash = 0;
    tet_ply_bin(&bins[0], -1, NULL);
    tet_gltf(&bins[1], -1, NULL, 4, NULL);
    tet_glb(&bins[2]);
    data[0] = box_obj;
    len[0] = strlen(box_obj);
    data[1] = box_off;
    len[1] = strlen(box_off);
    data[2] = box_ply;
    len[2] = strlen(box_ply);
    data[3] = bins[0].p;
    len[3] = bins[0].n;
    data[4] = bins[1].p;
    len[4] = bins[1].n;
    data[5] = bins[2].p;
    len[5] = bins[2].n;
    data[6] = tet_dae;
    len[6] = strlen(tet_dae);
    srand(777);
    for (int f = 0; f < 7; f++)
        for (int trial = 0; trial < 40; trial++) {
            unsigned char *mut = malloc(len[f]);
            size_t n = len[f];
            mesh m;
            glint_err e;
            int rc;
            ASSERT(mut != NULL);
            memcpy(mut, data[f], n);
            if (trial % 3 == 0)
                n = (size_t)rand() % n + 1; /* a prefix */
            else
                for (int k = 0; k < 1 + trial % 4; k++) {
                    static const char alphabet[] = "0123456789 .-\n{}[]\",:eE#/nafx";
                    size_t at = (size_t)rand() % n;
                    mut[at] = trial % 2 ? (unsigned char)alphabet[rand() % (sizeof alphabet - 1)]
                                        : (unsigned char)(rand() & 255);
                }
            memset(&e, 0, sizeof e);
            /* the reference scan reads only the bytes given (a copy exactly
             * n long: a read past it is the sanitizers' and valgrind's to see) */
            {
                unsigned char *exact = malloc(n);
                ASSERT(exact != NULL);
                memcpy(exact, mut, n);
                rc = mesh_refs_check(exact, n, exts[f], &e);
                free(exact);
            }
            ASSERT_MSG(rc == 0 || (rc == GLINT_EINVAL && strstr(e.msg, "external references")),
                       "%s trial %d: %d %s", exts[f], trial, rc, e.msg);
            memset(&e, 0, sizeof e);
            rc = mesh_load_mem(mut, n, exts[f], &m, NULL, &e);
            if (rc == 0) {
                char why[256];
                nok++;
                ASSERT_MSG(check_loaded(&m, why, sizeof why), "%s trial %d: %s", exts[f], trial,
                           why);
                mesh_free(&m);
            } else {
                nerr++;
                ncrash += strstr(e.msg, "crashed") != NULL;
                ASSERT_MSG(rc < 0 && e.code == rc && e.msg[0],
                           "%s trial %d: rc %d without a message", exts[f], trial, rc);
                /* a sanitizer report or a broken invariant in the import
                 * child shows up as GLINT_EINTERNAL */
                ASSERT_MSG(rc != GLINT_EINTERNAL, "%s trial %d: %s", exts[f], trial, e.msg);
                ASSERT(m.pos == NULL);
            }
            free(mut);
        }
    printf("  mutations: %d loaded, %d refused (%d of them by an importer crash)\n", nok, nerr,
           ncrash);
    for (int i = 0; i < 4; i++)
        free(bins[i].p);
}

TEST_LIST {
    TEST_ENTRY(corrupt_inputs),
    TEST_ENTRY(argument_errors),
    TEST_ENTRY(refs_upload_gltf),
    TEST_ENTRY(refs_upload_obj_dae),
    TEST_ENTRY(refs_upload_text),
    TEST_ENTRY(refs_disk),
    TEST_ENTRY(fuzz_mutations),
};

TEST_MAIN()
