/* mesh_fixture.h: mesh files for the tests of core/mesh_io (test_mesh_io.c,
 * test_mesh_refs.c): a temporary directory (removed at exit), a growable
 * byte buffer, and a box and a tetrahedron written in every format glint
 * reads (OBJ, OFF, PLY ascii and binary, glTF, GLB, COLLADA, STL). */
#ifndef GLINT_MESH_FIXTURE_H
#define GLINT_MESH_FIXTURE_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- temporary files ----------------------------------------------------- */

static char tmp_dir[64];

/* Remove the temporary directory (if any); a later tmp_path makes a new one. */
static inline void tmp_cleanup(void)
{
    if (tmp_dir[0]) {
        char cmd[128];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_dir);
        if (system(cmd) != 0)
            fprintf(stderr, "could not remove %s\n", tmp_dir);
        tmp_dir[0] = '\0';
    }
}

/* Path of `name` in the temporary directory, made on first use and removed
 * at exit (and by test_mesh_io.c's zz_cleanup). */
static inline const char *tmp_path(const char *name)
{
    static char buf[8][256];
    static int k;
    k = (k + 1) % 8;
    if (!tmp_dir[0]) {
        snprintf(tmp_dir, sizeof tmp_dir, "/tmp/glint_test_mesh_XXXXXX");
        if (!mkdtemp(tmp_dir)) {
            perror("mkdtemp");
            exit(2);
        }
        atexit(tmp_cleanup);
    }
    snprintf(buf[k], sizeof buf[k], "%s/%s", tmp_dir, name);
    return buf[k];
}

static inline int write_file(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    if (len && fwrite(data, 1, len, f) != len) {
        fclose(f);
        return -1;
    }
    return fclose(f) == 0 ? 0 : -1;
}

static inline int write_text(const char *path, const char *text)
{
    return write_file(path, text, strlen(text));
}

/* A growable byte buffer for building binary files. */
typedef struct buf {
    unsigned char *p;
    size_t n, cap;
} buf;

static inline void buf_put(buf *b, const void *data, size_t len)
{
    if (b->n + len > b->cap) {
        size_t nc = b->cap ? b->cap : 256;
        while (nc < b->n + len)
            nc *= 2;
        b->p = realloc(b->p, nc);
        if (!b->p)
            exit(2);
        b->cap = nc;
    }
    memcpy(b->p + b->n, data, len);
    b->n += len;
}

static inline void buf_str(buf *b, const char *s) { buf_put(b, s, strlen(s)); }
static inline void buf_u32(buf *b, uint32_t x)
{
    unsigned char c[4] = {(unsigned char)x, (unsigned char)(x >> 8), (unsigned char)(x >> 16),
                          (unsigned char)(x >> 24)};
    buf_put(b, c, 4);
}
static inline void buf_f32(buf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    buf_u32(b, u);
}
static inline void buf_u16(buf *b, uint16_t x)
{
    unsigned char c[2] = {(unsigned char)x, (unsigned char)(x >> 8)};
    buf_put(b, c, 2);
}

static inline char *base64(const unsigned char *d, size_t n)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc(4 * ((n + 2) / 3) + 1), *o = out;
    if (!out)
        exit(2);
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)d[i] << 16;
        if (i + 1 < n)
            v |= (uint32_t)d[i + 1] << 8;
        if (i + 2 < n)
            v |= d[i + 2];
        *o++ = tab[(v >> 18) & 63];
        *o++ = tab[(v >> 12) & 63];
        *o++ = i + 1 < n ? tab[(v >> 6) & 63] : '=';
        *o++ = i + 2 < n ? tab[v & 63] : '=';
    }
    *o = '\0';
    return out;
}

/* ---- fixtures: a box and a tetrahedron in every format --------------------- */

/* Box [0,4] x [0,2] x [0,6]: quads, counter-clockwise from outside. */
static const char box_obj[] =
    "# box\n"
    "v 0 0 0\nv 4 0 0\nv 4 2 0\nv 0 2 0\nv 0 0 6\nv 4 0 6\nv 4 2 6\nv 0 2 6\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";

static const char box_off[] =
    "OFF\n# box\n8 6 0\n"
    "0 0 0\n4 0 0\n4 2 0\n0 2 0\n0 0 6\n4 0 6\n4 2 6\n0 2 6\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 3 7 6 2\n4 0 4 7 3\n4 1 2 6 5\n";

static const char box_ply[] =
    "ply\nformat ascii 1.0\ncomment box\nelement vertex 8\nproperty float x\n"
    "property float y\nproperty float z\nelement face 6\n"
    "property list uchar int vertex_indices\nend_header\n"
    "0 0 0\n4 0 0\n4 2 0\n0 2 0\n0 0 6\n4 0 6\n4 2 6\n0 2 6\n"
    "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 3 7 6 2\n4 0 4 7 3\n4 1 2 6 5\n";

static const float tet_v[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
static const uint16_t tet_f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

/* Binary little-endian PLY of the tetrahedron; vertex `nan_at` (if >= 0)
 * gets a NaN x.  `faces` overrides the declared face count if non-NULL. */
static inline void tet_ply_bin(buf *b, int nan_at, const char *faces)
{
    char head[512];
    snprintf(head, sizeof head,
             "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n"
             "property float y\nproperty float z\nelement face %s\n"
             "property list uchar int vertex_indices\nend_header\n",
             faces ? faces : "4");
    buf_str(b, head);
    for (int v = 0; v < 4; v++)
        for (int k = 0; k < 3; k++)
            buf_f32(b, v == nan_at && k == 0 ? NAN : tet_v[v][k]);
    for (int f = 0; f < 4; f++) {
        unsigned char three = 3;
        buf_put(b, &three, 1);
        for (int k = 0; k < 3; k++)
            buf_u32(b, tet_f[f][k]);
    }
}

/* The tetrahedron's binary buffer for glTF: 4 float VEC3 + 12 uint16. */
static inline void tet_gltf_bin(buf *b, int nan_at)
{
    for (int v = 0; v < 4; v++)
        for (int k = 0; k < 3; k++)
            buf_f32(b, v == nan_at && k == 1 ? NAN : tet_v[v][k]);
    for (int f = 0; f < 4; f++)
        for (int k = 0; k < 3; k++)
            buf_u16(b, tet_f[f][k]);
}

/* glTF JSON around that buffer; `uri` NULL for a GLB's own buffer; `nodes`
 * the nodes array (all of them in the scene), `mode` the primitive mode,
 * `count` the index count. */
/* "0,1,...": every node of a nodes array (counted by its "mesh" keys). */
static inline const char *nodes_in_scene(const char *nodes)
{
    static char list[64];
    int n = 0;
    for (const char *p = strstr(nodes, "\"mesh\""); p; p = strstr(p + 1, "\"mesh\""))
        n++;
    list[0] = '\0';
    for (int i = 0; i < n && i < 16; i++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%d", i ? "," : "", i);
    return list;
}

static inline char *tet_gltf_json(const char *uri, const char *nodes, int mode, const char *count)
{
    char *j = malloc(4096);
    char bufdesc[1024];
    if (!j)
        exit(2);
    if (uri)
        snprintf(bufdesc, sizeof bufdesc, "{\"byteLength\":72,\"uri\":\"%s\"}", uri);
    else
        snprintf(bufdesc, sizeof bufdesc, "{\"byteLength\":72}");
    snprintf(j, 4096,
             "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[%s]}],"
             "\"nodes\":%s,"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1,"
             "\"mode\":%d}]}],"
             "\"buffers\":[%s],"
             "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":48},"
             "{\"buffer\":0,\"byteOffset\":48,\"byteLength\":24}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,"
             "\"type\":\"VEC3\",\"min\":[0,0,0],\"max\":[1,1,1]},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":%s,\"type\":\"SCALAR\"}]}",
             nodes_in_scene(nodes), nodes, mode, bufdesc, count ? count : "12");
    return j;
}

static inline void tet_gltf(buf *out, int nan_at, const char *nodes, int mode, const char *count)
{
    buf bin = {0};
    char *b64, *uri, *json;
    tet_gltf_bin(&bin, nan_at);
    b64 = base64(bin.p, bin.n);
    uri = malloc(strlen(b64) + 64);
    if (!uri)
        exit(2);
    sprintf(uri, "data:application/octet-stream;base64,%s", b64);
    json = tet_gltf_json(uri, nodes ? nodes : "[{\"mesh\":0}]", mode, count);
    buf_str(out, json);
    free(json);
    free(uri);
    free(b64);
    free(bin.p);
}

static inline void tet_glb(buf *out)
{
    buf bin = {0};
    char *json = tet_gltf_json(NULL, "[{\"mesh\":0}]", 4, NULL);
    size_t jl = strlen(json), jp = (jl + 3) & ~(size_t)3, bp;
    tet_gltf_bin(&bin, -1);
    bp = (bin.n + 3) & ~(size_t)3;
    buf_u32(out, 0x46546C67u); /* "glTF" */
    buf_u32(out, 2);
    buf_u32(out, (uint32_t)(12 + 8 + jp + 8 + bp));
    buf_u32(out, (uint32_t)jp);
    buf_u32(out, 0x4E4F534Au); /* "JSON" */
    buf_put(out, json, jl);
    for (size_t i = jl; i < jp; i++)
        buf_put(out, " ", 1);
    buf_u32(out, (uint32_t)bp);
    buf_u32(out, 0x004E4942u); /* "BIN\0" */
    buf_put(out, bin.p, bin.n);
    for (size_t i = bin.n; i < bp; i++)
        buf_put(out, "", 1);
    free(json);
    free(bin.p);
}

static const char tet_dae[] =
    "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
    "<COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">\n"
    " <asset><unit name=\"meter\" meter=\"1\"/><up_axis>Y_UP</up_axis></asset>\n"
    " <library_geometries>\n"
    "  <geometry id=\"tet\" name=\"tet\"><mesh>\n"
    "   <source id=\"tet-pos\"><float_array id=\"tet-pos-array\" count=\"12\">"
    "0 0 0 1 0 0 0 1 0 0 0 1</float_array>\n"
    "    <technique_common><accessor source=\"#tet-pos-array\" count=\"4\" stride=\"3\">"
    "<param name=\"X\" type=\"float\"/><param name=\"Y\" type=\"float\"/>"
    "<param name=\"Z\" type=\"float\"/></accessor></technique_common></source>\n"
    "   <vertices id=\"tet-vtx\"><input semantic=\"POSITION\" source=\"#tet-pos\"/></vertices>\n"
    "   <triangles count=\"4\"><input semantic=\"VERTEX\" source=\"#tet-vtx\" offset=\"0\"/>"
    "<p>0 2 1 0 1 3 0 3 2 1 2 3</p></triangles>\n"
    "  </mesh></geometry>\n"
    " </library_geometries>\n"
    " <library_visual_scenes><visual_scene id=\"scene\"><node id=\"n0\">"
    "<instance_geometry url=\"#tet\"/></node></visual_scene></library_visual_scenes>\n"
    " <scene><instance_visual_scene url=\"#scene\"/></scene>\n"
    "</COLLADA>\n";

static const char tet_stl[] =
    "solid tet\n"
    "facet normal 0 0 -1\nouter loop\nvertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\nendloop\nendfacet\n"
    "facet normal 0 -1 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 0 1\nendloop\nendfacet\n"
    "facet normal -1 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0 1\nvertex 0 1 0\nendloop\nendfacet\n"
    "facet normal 1 1 1\nouter loop\nvertex 1 0 0\nvertex 0 1 0\nvertex 0 0 1\nendloop\nendfacet\n"
    "endsolid tet\n";

#endif
