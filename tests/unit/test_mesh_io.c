/* test_mesh_io.c: meshes from files (every format glint documents, written
 * here into a temporary directory, plus the shared data meshes), hostile
 * and corrupt inputs, the automatic parameterization (coverage, no
 * overlaps, area distortion), normals, normalization, and the procedural
 * torus and teapot. */
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "check.h"
#include "gbuf.h"
#include "mesh.h"
#include "raster.h"
#include "scene.h"
#include "vec3.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* ---- temporary files ----------------------------------------------------- */

static char tmp_dir[64];

static const char *tmp_path(const char *name)
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
    }
    snprintf(buf[k], sizeof buf[k], "%s/%s", tmp_dir, name);
    return buf[k];
}

static int write_file(const char *path, const void *data, size_t len)
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

static int write_text(const char *path, const char *text)
{
    return write_file(path, text, strlen(text));
}

static void tmp_cleanup(void)
{
    if (tmp_dir[0]) {
        char cmd[128];
        snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp_dir);
        if (system(cmd) != 0)
            fprintf(stderr, "could not remove %s\n", tmp_dir);
    }
}

/* A growable byte buffer for building binary files. */
typedef struct buf {
    unsigned char *p;
    size_t n, cap;
} buf;

static void buf_put(buf *b, const void *data, size_t len)
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

static void buf_str(buf *b, const char *s) { buf_put(b, s, strlen(s)); }
static void buf_u32(buf *b, uint32_t x)
{
    unsigned char c[4] = {(unsigned char)x, (unsigned char)(x >> 8), (unsigned char)(x >> 16),
                          (unsigned char)(x >> 24)};
    buf_put(b, c, 4);
}
static void buf_f32(buf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    buf_u32(b, u);
}
static void buf_u16(buf *b, uint16_t x)
{
    unsigned char c[2] = {(unsigned char)x, (unsigned char)(x >> 8)};
    buf_put(b, c, 2);
}

static char *base64(const unsigned char *d, size_t n)
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
static void tet_ply_bin(buf *b, int nan_at, const char *faces)
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
static void tet_gltf_bin(buf *b, int nan_at)
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
static const char *nodes_in_scene(const char *nodes)
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

static char *tet_gltf_json(const char *uri, const char *nodes, int mode, const char *count)
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

static void tet_gltf(buf *out, int nan_at, const char *nodes, int mode, const char *count)
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

static void tet_glb(buf *out)
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

/* ---- geometric checks ----------------------------------------------------------- */

static void bbox(const mesh *m, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (int v = 0; v < m->nverts; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->pos[3 * v + k]);
            hi[k] = fmax(hi[k], m->pos[3 * v + k]);
        }
}

static double max_norm(const mesh *m)
{
    double r = 0.0;
    for (int v = 0; v < m->nverts; v++)
        r = fmax(r, v3_len(v3_loadf(m->pos + 3 * v)));
    return r;
}

static double tri_area3(const mesh *m, int t)
{
    const uint32_t *f = m->tri + 3 * t;
    v3 a = v3_loadf(m->pos + 3 * f[0]), b = v3_loadf(m->pos + 3 * f[1]),
       c = v3_loadf(m->pos + 3 * f[2]);
    return 0.5 * v3_len(v3_cross(v3_sub(b, a), v3_sub(c, a)));
}

static double tri_area_uv(const mesh *m, int t) /* signed */
{
    const uint32_t *f = m->tri + 3 * t;
    const float *a = m->uv + 2 * f[0], *b = m->uv + 2 * f[1], *c = m->uv + 2 * f[2];
    return 0.5 * (((double)b[0] - a[0]) * ((double)c[1] - a[1]) -
                  ((double)c[0] - a[0]) * ((double)b[1] - a[1]));
}

/* Everything a loaded mesh must satisfy: valid, unit normals, uv in
 * [0,1], normalized into the unit ball with max |v| = 1. */
static int check_loaded(const mesh *m, char *why, size_t whylen)
{
    glint_err e;
    double r;
    if (mesh_validate(m, &e)) {
        snprintf(why, whylen, "mesh_validate: %.200s", e.msg);
        return 0;
    }
    for (int v = 0; v < m->nverts; v++) {
        double l = v3_len(v3_loadf(m->nrm + 3 * v));
        if (fabs(l - 1.0) > 1e-5) {
            snprintf(why, whylen, "normal %d has length %g", v, l);
            return 0;
        }
        if (!(m->uv[2 * v] >= 0.0f && m->uv[2 * v] <= 1.0f && m->uv[2 * v + 1] >= 0.0f &&
              m->uv[2 * v + 1] <= 1.0f)) {
            snprintf(why, whylen, "uv %d (%g, %g) outside [0,1]", v, m->uv[2 * v],
                     m->uv[2 * v + 1]);
            return 0;
        }
    }
    r = max_norm(m);
    if (!(fabs(r - 1.0) <= 1e-6 && r <= 1.0)) {
        snprintf(why, whylen, "max |v| = %.9f, expected 1 (and <= 1)", r);
        return 0;
    }
    return 1;
}

/* Canonical edge function of the segment (a, b) at p: the same value, up
 * to sign, for both orders of a and b, so two triangles sharing an edge
 * never both claim a point on it. */
static double edge_fn(const float *a, const float *b, double px, double py)
{
    int swap = a[0] > b[0] || (a[0] == b[0] && a[1] > b[1]);
    const float *lo = swap ? b : a, *hi = swap ? a : b;
    double e = ((double)hi[0] - lo[0]) * (py - lo[1]) - ((double)hi[1] - lo[1]) * (px - lo[0]);
    return swap ? -e : e;
}

/* Samples of a G x G grid over [0,1]^2 strictly inside two or more uv
 * triangles (OUT: *covered, samples inside at least one). */
static long uv_overlaps(const mesh *m, int G, long *covered)
{
    unsigned char *cnt = calloc((size_t)G * G, 1);
    long over = 0, cov = 0;
    if (!cnt)
        exit(2);
    for (int t = 0; t < m->ntris; t++) {
        const uint32_t *f = m->tri + 3 * t;
        const float *p[3] = {m->uv + 2 * f[0], m->uv + 2 * f[1], m->uv + 2 * f[2]};
        double lx = fmin(p[0][0], fmin(p[1][0], p[2][0])), hx = fmax(p[0][0], fmax(p[1][0], p[2][0]));
        double ly = fmin(p[0][1], fmin(p[1][1], p[2][1])), hy = fmax(p[0][1], fmax(p[1][1], p[2][1]));
        int x0 = (int)floor(lx * G - 0.5), x1 = (int)ceil(hx * G - 0.5);
        int y0 = (int)floor(ly * G - 0.5), y1 = (int)ceil(hy * G - 0.5);
        for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < G; y++)
            for (int x = x0 < 0 ? 0 : x0; x <= x1 && x < G; x++) {
                double px = (x + 0.5) / G, py = (y + 0.5) / G;
                double e0 = edge_fn(p[1], p[2], px, py), e1 = edge_fn(p[2], p[0], px, py),
                       e2 = edge_fn(p[0], p[1], px, py);
                if ((e0 > 0 && e1 > 0 && e2 > 0) || (e0 < 0 && e1 < 0 && e2 < 0)) {
                    unsigned char *c = cnt + (size_t)y * G + x;
                    if (*c < 255)
                        (*c)++;
                }
            }
    }
    for (long i = 0; i < (long)G * G; i++) {
        over += cnt[i] > 1;
        cov += cnt[i] > 0;
    }
    free(cnt);
    if (covered)
        *covered = cov;
    return over;
}

/* Area-weighted share of the surface whose uv/3D area ratio is within a
 * factor `f` of the global ratio; OUT: *neg, share with clockwise uv. */
static double uv_within(const mesh *m, double f, double *neg)
{
    double a3 = 0.0, auv = 0.0, in = 0.0, ng = 0.0, k;
    for (int t = 0; t < m->ntris; t++) {
        a3 += tri_area3(m, t);
        auv += fabs(tri_area_uv(m, t));
    }
    k = auv / a3;
    for (int t = 0; t < m->ntris; t++) {
        double A = tri_area3(m, t), s = tri_area_uv(m, t), r = fabs(s) / A / k;
        if (r >= 1.0 / f && r <= f)
            in += A;
        if (s <= 0.0)
            ng += A;
    }
    if (neg)
        *neg = ng / a3;
    return in / a3;
}

/* Edges on exactly welded positions: boundary (1 triangle) and
 * non-manifold (> 2) counts. */
typedef struct ekey { float a[3], b[3]; } ekey;

static int pos_cmp(const float *a, const float *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

static int ekey_cmp(const void *x, const void *y)
{
    const ekey *p = x, *q = y;
    int c = pos_cmp(p->a, q->a);
    return c ? c : pos_cmp(p->b, q->b);
}

static void edge_counts(const mesh *m, long *boundary, long *nonmanifold)
{
    size_t ne = 3 * (size_t)m->ntris;
    ekey *e = malloc(ne * sizeof *e);
    long nb = 0, nn = 0;
    if (!e)
        exit(2);
    for (int t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            const float *p = m->pos + 3 * m->tri[3 * t + k], *q = m->pos + 3 * m->tri[3 * t + (k + 1) % 3];
            ekey *o = &e[3 * t + k];
            if (pos_cmp(p, q) > 0) {
                const float *s = p;
                p = q;
                q = s;
            }
            for (int c = 0; c < 3; c++) {
                o->a[c] = p[c] == 0.0f ? 0.0f : p[c];
                o->b[c] = q[c] == 0.0f ? 0.0f : q[c];
            }
        }
    qsort(e, ne, sizeof *e, ekey_cmp);
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && ekey_cmp(&e[i], &e[j]) == 0)
            j++;
        nb += j - i == 1;
        nn += j - i > 2;
        i = j;
    }
    free(e);
    *boundary = nb;
    *nonmanifold = nn;
}

/* Moller-Trumbore: does the ray o + t d (t > eps) hit triangle t? */
static int ray_hits(const mesh *m, int t, v3 o, v3 d)
{
    const uint32_t *f = m->tri + 3 * t;
    v3 a = v3_loadf(m->pos + 3 * f[0]), b = v3_loadf(m->pos + 3 * f[1]),
       c = v3_loadf(m->pos + 3 * f[2]);
    v3 e1 = v3_sub(b, a), e2 = v3_sub(c, a), p = v3_cross(d, e2), s, q;
    double det = v3_dot(e1, p), u, v;
    if (fabs(det) < 1e-14)
        return 0;
    s = v3_sub(o, a);
    u = v3_dot(s, p) / det;
    if (u < 0 || u > 1)
        return 0;
    q = v3_cross(s, e1);
    v = v3_dot(d, q) / det;
    if (v < 0 || u + v > 1)
        return 0;
    return v3_dot(e2, q) / det > 1e-7;
}

/* Share of `nsamples` triangles (evenly spread) whose face normal points
 * out of the mesh by ray parity (an even number of crossings along it). */
static double outward_share(const mesh *m, int nsamples)
{
    int out = 0, n = 0;
    int step = m->ntris / nsamples > 0 ? m->ntris / nsamples : 1;
    for (int t = 0; t < m->ntris; t += step, n++) {
        const uint32_t *f = m->tri + 3 * t;
        v3 a = v3_loadf(m->pos + 3 * f[0]), b = v3_loadf(m->pos + 3 * f[1]),
           c = v3_loadf(m->pos + 3 * f[2]);
        v3 nn = v3_normalize(v3_cross(v3_sub(b, a), v3_sub(c, a)));
        v3 o = v3_scale(v3_add(v3_add(a, b), c), 1.0 / 3.0);
        /* a slightly skewed direction avoids grazing edges exactly */
        v3 d = v3_normalize(v3_add(nn, v3_make(1.3e-3, -0.7e-3, 0.9e-3)));
        int hits = 0;
        o = v3_add(o, v3_scale(d, 1e-6));
        for (int u = 0; u < m->ntris; u++)
            hits += u != t && ray_hits(m, u, o, d);
        out += hits % 2 == 0;
    }
    return (double)out / n;
}

/* ---- loading every format ----------------------------------------------------- */

static int load_file(const char *path, mesh *m, mesh_report *r, glint_err *e)
{
    memset(e, 0, sizeof *e);
    return mesh_load(path, m, r, e);
}

TEST(formats_box)
{
    /* half extents (2, 1, 3) / |(2, 1, 3)| after normalization */
    const double s = 1.0 / sqrt(14.0), want[3] = {2 * s, 1 * s, 3 * s};
    static const struct { const char *name; const char *text; const char *fmt; } cases[] = {
        {"box.obj", box_obj, "obj"}, {"box.off", box_off, "off"}, {"box.ply", box_ply, "ply"}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        mesh m, mm;
        mesh_report r, rm;
        glint_err e;
        double lo[3], hi[3];
        char why[256];
        const char *path = tmp_path(cases[i].name);
        ASSERT(write_text(path, cases[i].text) == 0);
        ASSERT_MSG(load_file(path, &m, &r, &e) == 0, "%s: %s", cases[i].name, e.msg);
        ASSERT_MSG(check_loaded(&m, why, sizeof why), "%s: %s", cases[i].name, why);
        ASSERT_EQ(m.ntris, 12);
        ASSERT_EQ(r.ntris, 12);
        ASSERT_EQ(m.nverts, 24); /* 6 charts of 4 corners: every face on its own */
        ASSERT_EQ(r.uv_charts, 6);
        ASSERT_EQ(r.normals_generated, 1);
        ASSERT_EQ(r.uvs_generated, 1);
        ASSERT_EQ(r.dropped_degenerate, 0);
        ASSERT_EQ(r.boundary_edges, 0);
        ASSERT_EQ(r.nonmanifold_edges, 0);
        ASSERT(strcmp(r.format, cases[i].fmt) == 0);
        ASSERT_NEAR(r.scale, s, 1e-7);
        ASSERT_NEAR(r.center[0], 2.0, 1e-6);
        ASSERT_NEAR(r.center[1], 1.0, 1e-6);
        ASSERT_NEAR(r.center[2], 3.0, 1e-6);
        bbox(&m, lo, hi);
        for (int k = 0; k < 3; k++) {
            ASSERT_NEAR(lo[k], -want[k], 1e-6);
            ASSERT_NEAR(hi[k], want[k], 1e-6);
        }
        /* smooth normals of a box corner point along the diagonal */
        for (int v = 0; v < m.nverts; v++) {
            v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
            ASSERT(v3_dot(p, n) > 0.0);
        }
        /* the same bytes from memory */
        ASSERT_MSG(mesh_load_mem(cases[i].text, strlen(cases[i].text), cases[i].fmt, &mm, &rm,
                                 &e) == 0, "%s from memory: %s", cases[i].name, e.msg);
        ASSERT_EQ(mm.nverts, m.nverts);
        ASSERT_EQ(mm.ntris, m.ntris);
        ASSERT(memcmp(mm.pos, m.pos, 3 * sizeof(float) * (size_t)m.nverts) == 0);
        ASSERT(memcmp(mm.uv, m.uv, 2 * sizeof(float) * (size_t)m.nverts) == 0);
        ASSERT(memcmp(mm.tri, m.tri, 3 * sizeof(uint32_t) * (size_t)m.ntris) == 0);
        mesh_free(&m);
        mesh_free(&mm);
    }
}

TEST(formats_tetrahedron)
{
    const double h = 0.5 / sqrt(0.75); /* normalized half extent */
    buf b[6] = {{0}};
    static const char *names[6] = {"tet.ply", "tet.gltf", "tet.glb", "tet.dae", "tet.stl",
                                   "tetbe.ply"};
    static const char *fmts[6] = {"ply", "gltf", "glb", "dae", "stl", "ply"};
    tet_ply_bin(&b[0], -1, NULL);
    tet_gltf(&b[1], -1, NULL, 4, NULL);
    tet_glb(&b[2]);
    buf_str(&b[3], tet_dae);
    buf_str(&b[4], tet_stl);
    /* big-endian PLY, written by hand */
    {
        const char *head = "ply\nformat binary_big_endian 1.0\nelement vertex 4\n"
                           "property float x\nproperty float y\nproperty float z\n"
                           "element face 4\nproperty list uchar int vertex_indices\n"
                           "end_header\n";
        buf_str(&b[5], head);
        for (int v = 0; v < 4; v++)
            for (int k = 0; k < 3; k++) {
                uint32_t u;
                unsigned char c[4];
                memcpy(&u, &tet_v[v][k], 4);
                for (int i = 0; i < 4; i++)
                    c[i] = (unsigned char)(u >> (24 - 8 * i));
                buf_put(&b[5], c, 4);
            }
        for (int f = 0; f < 4; f++) {
            unsigned char c = 3;
            buf_put(&b[5], &c, 1);
            for (int k = 0; k < 3; k++) {
                unsigned char d[4] = {0, 0, 0, (unsigned char)tet_f[f][k]};
                buf_put(&b[5], d, 4);
            }
        }
    }
    for (int i = 0; i < 6; i++) {
        mesh m, mm;
        mesh_report r, rm;
        glint_err e;
        double lo[3], hi[3];
        char why[256];
        const char *path = tmp_path(names[i]);
        ASSERT(write_file(path, b[i].p, b[i].n) == 0);
        ASSERT_MSG(load_file(path, &m, &r, &e) == 0, "%s: %s", names[i], e.msg);
        ASSERT_MSG(check_loaded(&m, why, sizeof why), "%s: %s", names[i], why);
        ASSERT_MSG(m.ntris == 4, "%s: %d triangles", names[i], m.ntris);
        ASSERT_MSG(m.nverts == 12, "%s: %d vertices", names[i], m.nverts);
        ASSERT(strcmp(r.format, fmts[i]) == 0);
        bbox(&m, lo, hi);
        for (int k = 0; k < 3; k++) {
            ASSERT_NEAR(lo[k], -h, 1e-6);
            ASSERT_NEAR(hi[k], h, 1e-6);
        }
        /* faces keep their outward orientation through every loader */
        for (int t = 0; t < m.ntris; t++) {
            const uint32_t *f = m.tri + 3 * t;
            v3 a = v3_loadf(m.pos + 3 * f[0]), bb = v3_loadf(m.pos + 3 * f[1]),
               c = v3_loadf(m.pos + 3 * f[2]);
            v3 n = v3_cross(v3_sub(bb, a), v3_sub(c, a));
            v3 cen = v3_scale(v3_add(v3_add(a, bb), c), 1.0 / 3.0);
            /* the tetrahedron's centroid (1/4, 1/4, 1/4) normalized */
            v3 mid = v3_scale(v3_make(-0.25, -0.25, -0.25), 1.0 / sqrt(0.75));
            ASSERT_MSG(v3_dot(n, v3_sub(cen, mid)) > 0.0, "%s: triangle %d faces inwards",
                       names[i], t);
        }
        ASSERT_MSG(mesh_load_mem(b[i].p, b[i].n, fmts[i], &mm, &rm, &e) == 0,
                   "%s from memory: %s", names[i], e.msg);
        ASSERT_EQ(mm.ntris, 4);
        ASSERT(memcmp(mm.pos, m.pos, 3 * sizeof(float) * (size_t)m.nverts) == 0);
        mesh_free(&m);
        mesh_free(&mm);
        free(b[i].p);
    }
}

/* Node transforms: three instances of one mesh, one mirrored. */
TEST(node_transforms)
{
    buf b = {0};
    mesh m;
    mesh_report r;
    glint_err e;
    const char *path = tmp_path("inst.gltf");
    tet_gltf(&b, -1,
             "[{\"mesh\":0},{\"mesh\":0,\"translation\":[3,0,0]},"
             "{\"mesh\":0,\"scale\":[-1,1,1],\"translation\":[-3,0,0]}]",
             4, NULL);
    ASSERT(write_file(path, b.p, b.n) == 0);
    free(b.p);
    ASSERT_MSG(load_file(path, &m, &r, &e) == 0, "%s", e.msg);
    ASSERT_EQ(m.ntris, 12);
    /* raw bounding box x [-4, 4], y, z [0, 1] */
    ASSERT_NEAR(r.center[0], 0.0, 1e-6);
    ASSERT_NEAR(r.center[1], 0.5, 1e-6);
    ASSERT_NEAR(r.center[2], 0.5, 1e-6);
    ASSERT_NEAR(r.scale, 1.0 / sqrt(16.5), 1e-7);
    for (int t = 0; t < m.ntris; t++) {
        const uint32_t *f = m.tri + 3 * t;
        v3 a = v3_loadf(m.pos + 3 * f[0]), bb = v3_loadf(m.pos + 3 * f[1]),
           c = v3_loadf(m.pos + 3 * f[2]);
        v3 n = v3_cross(v3_sub(bb, a), v3_sub(c, a));
        v3 cen = v3_scale(v3_add(v3_add(a, bb), c), 1.0 / 3.0);
        double x = cen.x / r.scale + r.center[0]; /* back to file units */
        double ix = x < -2 ? -3.25 : x > 2 ? 3.25 : 0.25;
        v3 mid = v3_scale(v3_sub(v3_make(ix, 0.25, 0.25), v3_load(r.center)), r.scale);
        /* winding flipped under the mirror: still outwards */
        ASSERT_MSG(v3_dot(n, v3_sub(cen, mid)) > 0.0, "triangle %d (instance x %g) faces inwards",
                   t, ix);
    }
    mesh_free(&m);
}

/* Normals and uvs from the file are kept (normals renormalized, uvs moved
 * into [0,1] when they leave it); unusable ones are regenerated. */
TEST(file_normals_and_uvs)
{
    static const char quad_head[] =
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\n";
    char text[1024];
    mesh m;
    mesh_report r;
    glint_err e;

    /* a pyramid with file normals of length 2 and uvs in [0,1] */
    snprintf(text, sizeof text,
             "%svn 0 0 2\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n"
             "f 1/1/1 2/2/1 5/5/1\nf 2/2/1 3/3/1 5/5/1\nf 3/3/1 4/4/1 5/5/1\nf 4/4/1 1/1/1 5/5/1\n",
             quad_head);
    ASSERT_OK(mesh_load_mem(text, strlen(text), "obj", &m, &r, &e));
    ASSERT_EQ(r.normals_generated, 0);
    ASSERT_EQ(r.uvs_generated, 0);
    ASSERT_EQ(r.uvs_rescaled, 0);
    ASSERT_EQ(r.boundary_edges, 4); /* open at the bottom */
    for (int v = 0; v < m.nverts; v++) {
        ASSERT_NEAR(m.nrm[3 * v + 2], 1.0, 1e-7);
        /* uv = (x, y) of the file before normalization */
        ASSERT_NEAR(m.uv[2 * v], m.pos[3 * v] / r.scale + r.center[0], 1e-6);
        ASSERT_NEAR(m.uv[2 * v + 1], m.pos[3 * v + 1] / r.scale + r.center[1], 1e-6);
    }
    mesh_free(&m);

    /* tiling uvs in [0, 4] x [0, 2]: scaled by 1/4 into [0,1]^2 */
    snprintf(text, sizeof text,
             "%svt 0 0\nvt 4 0\nvt 4 2\nvt 0 2\nvt 2 1\n"
             "f 1/1 2/2 5/5\nf 2/2 3/3 5/5\nf 3/3 4/4 5/5\nf 4/4 1/1 5/5\n", quad_head);
    ASSERT_OK(mesh_load_mem(text, strlen(text), "obj", &m, &r, &e));
    ASSERT_EQ(r.normals_generated, 1);
    ASSERT_EQ(r.uvs_generated, 0);
    ASSERT_EQ(r.uvs_rescaled, 1);
    for (int v = 0; v < m.nverts; v++) {
        ASSERT_NEAR(m.uv[2 * v], m.pos[3 * v] / r.scale + r.center[0], 1e-6);
        ASSERT_NEAR(m.uv[2 * v + 1], 0.5 * (m.pos[3 * v + 1] / r.scale + r.center[1]), 1e-6);
    }
    mesh_free(&m);

    /* a zero normal and all-equal uvs: both regenerated */
    snprintf(text, sizeof text,
             "%svn 0 0 1\nvn 0 0 0\nvt 0.5 0.5\n"
             "f 1/1/1 2/1/1 5/1/2\nf 2/1/1 3/1/1 5/1/2\nf 3/1/1 4/1/1 5/1/2\nf 4/1/1 1/1/1 5/1/2\n",
             quad_head);
    ASSERT_OK(mesh_load_mem(text, strlen(text), "obj", &m, &r, &e));
    ASSERT_EQ(r.normals_generated, 1);
    ASSERT_EQ(r.uvs_generated, 1);
    ASSERT(r.uv_charts >= 1);
    for (int v = 0; v < m.nverts; v++)
        ASSERT(m.nrm[3 * v + 2] > 0.0f); /* the apex and the rim lean up */
    mesh_free(&m);
}

/* Degenerate triangles are dropped and counted; edges are counted. */
TEST(cleaning)
{
    static const char text[] =
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 2 0 0\nv 0 0 0\n"
        "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
        "f 1 2 5\n"  /* collinear: zero area */
        "f 1 2 6\n"  /* vertex 6 repeats vertex 1's position */
        "f 2 3 4\n"; /* a second copy of a face: its edges become non-manifold */
    mesh m;
    mesh_report r;
    glint_err e;
    ASSERT_OK(mesh_load_mem(text, strlen(text), "obj", &m, &r, &e));
    ASSERT_EQ(r.dropped_degenerate, 2);
    ASSERT_EQ(m.ntris, 5);
    ASSERT_EQ(r.nonmanifold_edges, 3);
    ASSERT_EQ(r.boundary_edges, 0);
    mesh_free(&m);
    /* a lone point and a line are not triangles */
    {
        static const char pts[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\nl 1 4\np 4\n";
        ASSERT_OK(mesh_load_mem(pts, strlen(pts), "obj", &m, &r, &e));
        ASSERT_EQ(m.ntris, 1);
        ASSERT(r.dropped_primitives >= 1);
        ASSERT_EQ(r.boundary_edges, 3);
        mesh_free(&m);
    }
}

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
            {"garbage.ply", NULL, &garbage, GLINT_EFORMAT, "assimp"},
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

/* ---- the shared data meshes ---------------------------------------------------- */

static const char *const shared_meshes[] = {"bunny.ply", "teapot.ply", "cow.off",
                                            "triceratops.off"};

TEST(shared_meshes)
{
    const char *dir = check_data_dir();
    if (!dir) {
        printf("  skipped: no shared data\n");
        return;
    }
    for (size_t i = 0; i < sizeof shared_meshes / sizeof shared_meshes[0]; i++) {
        char path[4200], why[256];
        mesh m;
        mesh_report r;
        glint_err e;
        double t0, t1, within4, within25, neg;
        long covered, over;
        snprintf(path, sizeof path, "%s/meshes/%s", dir, shared_meshes[i]);
        t0 = now_s();
        ASSERT_MSG(load_file(path, &m, &r, &e) == 0, "%s: %s", path, e.msg);
        t1 = now_s();
        ASSERT_MSG(check_loaded(&m, why, sizeof why), "%s: %s", shared_meshes[i], why);
        ASSERT_EQ(r.normals_generated, 1);
        ASSERT_EQ(r.uvs_generated, 1);
        ASSERT(r.ntris > 900 && r.nverts >= r.ntris / 2);
        over = uv_overlaps(&m, 2048, &covered);
        within4 = uv_within(&m, 4.0, &neg);
        within25 = uv_within(&m, 2.5, NULL);
        printf("  %-16s %6.1f ms: %d vertices, %d triangles, %d dropped, %d boundary, "
               "%d non-manifold edges; uv: %d charts, coverage %.3f (sampled %.3f), "
               "area ratio within x2.5 %.4f, x4 %.4f\n",
               shared_meshes[i], 1e3 * (t1 - t0), r.nverts, r.ntris, r.dropped_degenerate,
               r.boundary_edges, r.nonmanifold_edges, r.uv_charts, r.uv_coverage,
               (double)covered / (2048.0 * 2048.0), within25, within4);
        ASSERT_MSG(over == 0, "%s: %ld uv samples covered twice", shared_meshes[i], over);
        ASSERT_LT(0.25, r.uv_coverage);
        ASSERT_NEAR((double)covered / (2048.0 * 2048.0), r.uv_coverage, 0.01);
        ASSERT_LT(0.9, within4);
        ASSERT_LT(0.99, within25);
        ASSERT_NEAR(neg, 0.0, 0.0); /* every uv triangle counter-clockwise */
        mesh_free(&m);
    }
}

/* Each shared mesh through a scene (mesh_path): all 12 default views
 * see a good part of it. */
TEST(shared_meshes_raster)
{
    const char *dir = check_data_dir();
    if (!dir) {
        printf("  skipped: no shared data\n");
        return;
    }
    for (size_t i = 0; i < sizeof shared_meshes / sizeof shared_meshes[0]; i++) {
        scene_params p;
        scene s;
        glint_err e;
        double lo = 1.0, hi = 0.0;
        scene_params_default(&p);
        if (snprintf(p.mesh_path, sizeof p.mesh_path, "%.3000s/meshes/%s", dir,
                     shared_meshes[i]) >= (int)sizeof p.mesh_path)
            continue;
        ASSERT_MSG(scene_create(&p, &s, &e) == 0, "%s: %s", shared_meshes[i], e.msg);
        ASSERT(strcmp(s.mesh_name, shared_meshes[i]) == 0);
        ASSERT(s.mesh_path[0] == '/');
        for (int k = 0; k < s.nviews; k++) {
            gbuf g;
            double c;
            int rlo = s.height, rhi = -1, clo = s.width, chi = -1;
            ASSERT_OK(raster_view(&s.mesh, &s.views[k], s.width, s.height, &g, &e));
            c = (double)gbuf_count(&g) / ((double)s.width * s.height);
            lo = fmin(lo, c);
            hi = fmax(hi, c);
            for (int y = 0; y < s.height; y++)
                for (int x = 0; x < s.width; x++)
                    if (g.mask[y * s.width + x]) {
                        size_t px = (size_t)y * s.width + x;
                        rlo = y < rlo ? y : rlo;
                        rhi = y > rhi ? y : rhi;
                        clo = x < clo ? x : clo;
                        chi = x > chi ? x : chi;
                        ASSERT(isfinite(g.uv[2 * px]) && isfinite(g.nrm[3 * px]));
                    }
            /* the silhouette spans at least 40% of the frame one way
             * (the triceratops seen end-on is the narrowest) */
            ASSERT_MSG(rhi - rlo > 0.4 * s.height || chi - clo > 0.4 * s.width,
                       "%s view %d: silhouette %dx%d pixels", shared_meshes[i], k,
                       chi - clo + 1, rhi - rlo + 1);
            gbuf_free(&g);
        }
        printf("  %-16s coverage over the 12 views: %.3f .. %.3f\n", shared_meshes[i], lo, hi);
        ASSERT_MSG(lo > 0.08, "%s: a view covers only %.3f of the frame", shared_meshes[i], lo);
        ASSERT(hi < 0.66);
        scene_free(&s);
    }
}

/* Loading the same bytes concurrently gives identical meshes. */
typedef struct thread_job {
    const char *data;
    size_t len;
    mesh m;
    int rc;
    glint_err e;
} thread_job;

static void *load_thread(void *arg)
{
    thread_job *j = arg;
    j->rc = mesh_load_mem(j->data, j->len, "ply", &j->m, NULL, &j->e);
    return NULL;
}

TEST(concurrent_loads)
{
    pthread_t th[4];
    thread_job jobs[4];
#if defined(__SANITIZE_ADDRESS__)
    /* Imports run in a forked child.  GCC 12's ASan allocator is not
     * fork-safe: a thread that allocates (even while merely starting) at the
     * moment another forks leaves the child's allocator locked forever.
     * Sanitized builds serialize loads, but cannot stop other threads from
     * allocating, so this test only runs in normal builds. */
    printf("  skipped under AddressSanitizer (fork + concurrent allocation)\n");
    return;
#endif
    for (int i = 0; i < 4; i++) {
        jobs[i].data = box_ply;
        jobs[i].len = strlen(box_ply);
        ASSERT(pthread_create(&th[i], NULL, load_thread, &jobs[i]) == 0);
    }
    for (int i = 0; i < 4; i++)
        pthread_join(th[i], NULL);
    for (int i = 0; i < 4; i++) {
        ASSERT_MSG(jobs[i].rc == 0, "thread %d: %s", i, jobs[i].e.msg);
        ASSERT_EQ(jobs[i].m.nverts, jobs[0].m.nverts);
        ASSERT(memcmp(jobs[i].m.pos, jobs[0].m.pos, 12 * (size_t)jobs[0].m.nverts) == 0);
        ASSERT(memcmp(jobs[i].m.uv, jobs[0].m.uv, 8 * (size_t)jobs[0].m.nverts) == 0);
    }
    for (int i = 0; i < 4; i++)
        mesh_free(&jobs[i].m);
}

/* ---- parameterization on its own ------------------------------------------------ */

/* A helicoid ramp of two turns: every triangle faces nearly +z, and its
 * orthographic projection covers itself twice, so one chart per axis is
 * not enough: the overlap test must split it. */
TEST(uv_self_overlap_split)
{
    const int nu = 96, nv = 4;
    mesh m;
    glint_err e;
    long over, covered;
    memset(&m, 0, sizeof m);
    m.nverts = (nu + 1) * (nv + 1);
    m.ntris = 2 * nu * nv;
    m.pos = malloc(3 * sizeof(float) * (size_t)m.nverts);
    m.nrm = malloc(3 * sizeof(float) * (size_t)m.nverts);
    m.tri = malloc(3 * sizeof(uint32_t) * (size_t)m.ntris);
    ASSERT(m.pos && m.nrm && m.tri);
    for (int i = 0; i <= nu; i++)
        for (int j = 0; j <= nv; j++) {
            double th = 4.0 * 3.14159265358979 * i / nu, r = 0.5 + 0.5 * j / nv;
            float *p = m.pos + 3 * (i * (nv + 1) + j);
            p[0] = (float)(r * cos(th));
            p[1] = (float)(r * sin(th));
            p[2] = (float)(0.02 * th);
        }
    {
        uint32_t *t = m.tri;
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                uint32_t a = (uint32_t)(i * (nv + 1) + j), b = a + (uint32_t)(nv + 1);
                *t++ = a; *t++ = a + 1; *t++ = b + 1;
                *t++ = a; *t++ = b + 1; *t++ = b;
            }
    }
    ASSERT_OK(mesh_compute_normals(&m, &e));
    ASSERT_OK(mesh_generate_uvs(&m, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    over = uv_overlaps(&m, 1024, &covered);
    ASSERT_MSG(over == 0, "%ld samples covered twice", over);
    ASSERT(covered > 1024 * 1024 / 20);
    mesh_free(&m);
}

/* Built-in shapes re-parameterized: no overlap, bounded distortion. */
TEST(uv_generate_builtins)
{
    mesh m;
    glint_err e;
    long over, covered;
    double neg;
    ASSERT_OK(mesh_sphere(&m, 24, 48, &e));
    ASSERT_OK(mesh_generate_uvs(&m, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    over = uv_overlaps(&m, 1024, &covered);
    ASSERT_EQ(over, 0);
    ASSERT_LT(0.99, uv_within(&m, 2.5, &neg));
    ASSERT_NEAR(neg, 0.0, 0.0);
    mesh_free(&m);
    ASSERT_OK(mesh_torus(&m, 0.7, 0.3, 64, 32, &e));
    ASSERT_OK(mesh_generate_uvs(&m, &e));
    over = uv_overlaps(&m, 1024, &covered);
    ASSERT_EQ(over, 0);
    ASSERT_LT(0.99, uv_within(&m, 2.5, &neg));
    mesh_free(&m);
}

/* ---- normals and normalization ------------------------------------------------ */

TEST(normals_and_normalize)
{
    mesh m;
    glint_err e;
    double scale, c[3], maxdev = 0.0, meandev = 0.0;
    ASSERT_OK(mesh_sphere(&m, 32, 64, &e));
    /* smooth normals agree with the exact ones, also on the duplicated seam */
    ASSERT_OK(mesh_compute_normals(&m, &e));
    for (int v = 0; v < m.nverts; v++) {
        v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
        double d = v3_len(v3_sub(p, n));
        maxdev = fmax(maxdev, d);
        meandev += d / m.nverts;
        /* on the seam (phi = 0, copies at u = 0 and u = 1) both copies agree */
        if (m.uv[2 * v] == 1.0f && fabs(p.z) < 0.999) {
            int twin = v - 64; /* the u = 0 copy of the same ring (nlon = 64) */
            ASSERT(m.pos[3 * twin] == m.pos[3 * v] && m.pos[3 * twin + 1] == m.pos[3 * v + 1]);
            ASSERT(memcmp(m.nrm + 3 * twin, m.nrm + 3 * v, 3 * sizeof(float)) == 0);
        }
    }
    /* area weighting on a latitude-longitude grid leans by O(cell size)
     * where the cells are thin (near the poles) */
    ASSERT_LT(maxdev, 0.03);
    ASSERT_LT(meandev, 5e-3);
    /* move and scale, then normalize back */
    for (int i = 0; i < 3 * m.nverts; i++)
        m.pos[i] = m.pos[i] * 5.0f + (float)(i % 3) - 7.0f;
    mesh_normalize(&m, &scale, c);
    ASSERT_NEAR(scale, 0.2, 1e-6);
    ASSERT_NEAR(c[0], -7.0, 1e-5);
    ASSERT_NEAR(c[1], -6.0, 1e-5);
    ASSERT_NEAR(c[2], -5.0, 1e-5);
    ASSERT_NEAR(max_norm(&m), 1.0, 1e-6);
    ASSERT_LE(max_norm(&m), 1.0);
    mesh_free(&m);
}

/* ---- procedural built-ins --------------------------------------------------- */

TEST(torus)
{
    mesh m;
    glint_err e;
    long nb, nn;
    const int nu = 48, nv = 24;
    ASSERT_OK(mesh_torus(&m, 0.7, 0.3, nu, nv, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    ASSERT_EQ(m.nverts, (nu + 1) * (nv + 1));
    ASSERT_EQ(m.ntris, 2 * nu * nv);
    ASSERT_NEAR(max_norm(&m), 1.0, 1e-6);
    edge_counts(&m, &nb, &nn);
    ASSERT_EQ(nb, 0); /* closed: the seams are bit-identical */
    ASSERT_EQ(nn, 0);
    for (int v = 0; v < m.nverts; v++) {
        v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
        /* the nearest point of the core circle (radius 0.7) */
        double rho = hypot(p.x, p.y);
        v3 core = v3_make(0.7 * p.x / rho, 0.7 * p.y / rho, 0.0);
        ASSERT_NEAR(v3_len(n), 1.0, 1e-6);
        ASSERT_NEAR(v3_len(v3_sub(v3_scale(n, 0.3), v3_sub(p, core))), 0.0, 1e-6);
        ASSERT(m.uv[2 * v] >= 0.0f && m.uv[2 * v] <= 1.0f);
    }
    for (int t = 0; t < m.ntris; t++) {
        const uint32_t *f = m.tri + 3 * t;
        v3 a = v3_loadf(m.pos + 3 * f[0]), b = v3_loadf(m.pos + 3 * f[1]),
           c = v3_loadf(m.pos + 3 * f[2]);
        v3 fnrm = v3_cross(v3_sub(b, a), v3_sub(c, a));
        ASSERT_MSG(v3_dot(fnrm, v3_loadf(m.nrm + 3 * f[0])) > 0.0, "triangle %d inverted", t);
    }
    ASSERT_LT(0.98, outward_share(&m, 200));
    mesh_free(&m);
    /* errors */
    ASSERT_EQ(mesh_torus(&m, 0.3, 0.7, 8, 8, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_torus(&m, 0.7, 0.0, 8, 8, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_torus(&m, NAN, 0.3, 8, 8, &e), GLINT_ENONFINITE);
    ASSERT_EQ(mesh_torus(&m, 0.7, 0.3, 2, 8, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_torus(&m, 0.7, 0.3, 8, MESH_SPHERE_MAX_SEG + 1, &e), GLINT_ERANGE);
    ASSERT(m.pos == NULL);
}

/* The transcribed control data: counts, bounding box, coordinate sums,
 * and the symmetries of the published patches (4-fold rotations of rim,
 * body, lid and bottom; mirror pairs of handle and spout), which any typo
 * would break. */
TEST(teapot_data)
{
    const double (*pt)[3];
    const uint16_t (*pa)[16];
    int np, nk;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double sum[3] = {0, 0, 0};
    /* first patch of each group and its turn: -1 for -90 degrees about z,
     * (x, y) -> (y, -x); +1 for +90 degrees, (x, y) -> (-y, x) */
    static const int rot_groups[6][2] = {{0, -1}, {4, -1}, {8, -1}, {20, -1}, {24, -1}, {28, 1}};
    mesh_teapot_data(&pt, &np, &pa, &nk);
    ASSERT_EQ(np, 306);
    ASSERT_EQ(nk, 32);
    for (int i = 0; i < np; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], pt[i][k]);
            hi[k] = fmax(hi[k], pt[i][k]);
            sum[k] += pt[i][k];
        }
    ASSERT_NEAR(lo[0], -3.0, 0.0);
    ASSERT_NEAR(hi[0], 3.525, 0.0);
    ASSERT_NEAR(lo[1], -2.0, 0.0);
    ASSERT_NEAR(hi[1], 2.0, 0.0);
    ASSERT_NEAR(lo[2], 0.0, 0.0);
    ASSERT_NEAR(hi[2], 3.15, 0.0);
    ASSERT_NEAR(sum[0], 15.275, 1e-9);
    ASSERT_NEAR(sum[1], 0.0, 1e-9);
    ASSERT_NEAR(sum[2], 510.95625, 1e-9);
    for (int k = 0; k < nk; k++)
        for (int i = 0; i < 16; i++)
            ASSERT(pa[k][i] < np);
    /* rim, body, lid, bottom: patch k + 1 is patch k turned by 90 degrees
     * about z, point by point */
    for (size_t g = 0; g < sizeof rot_groups / sizeof rot_groups[0]; g++)
        for (int q = 0; q < 3; q++) {
            int a = rot_groups[g][0] + q, b = a + 1, s = rot_groups[g][1];
            for (int i = 0; i < 16; i++) {
                const double *p = pt[pa[a][i]], *r = pt[pa[b][i]];
                ASSERT_MSG(fabs(r[0] + s * p[1]) < 1e-12 && fabs(r[1] - s * p[0]) < 1e-12 &&
                               fabs(r[2] - p[2]) < 1e-12,
                           "patch %d point %d is not patch %d's turned", b, i, a);
            }
        }
    /* handle and spout: patch k + 1 mirrors patch k in y, columns reversed */
    for (int k = 12; k < 20; k += 2)
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 4; j++) {
                const double *p = pt[pa[k][4 * i + 3 - j]], *r = pt[pa[k + 1][4 * i + j]];
                ASSERT_MSG(r[0] == p[0] && r[1] == -p[1] && r[2] == p[2],
                           "patch %d point %d does not mirror patch %d", k + 1, 4 * i + j, k);
            }
}

TEST(teapot)
{
    mesh m;
    glint_err e;
    long nb, nn, over, covered;
    int outward = 0, agree = 0;
    v3 cen = v3_make(0, 0, 0);
    const int seg = 16;
    ASSERT_OK(mesh_teapot(&m, seg, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    ASSERT_EQ(m.nverts, 32 * (seg + 1) * (seg + 1));
    /* 8 patches have a collapsed edge: their first row keeps one triangle
     * per quad */
    ASSERT_EQ(m.ntris, 2 * 32 * seg * seg - 8 * seg);
    ASSERT_NEAR(max_norm(&m), 1.0, 1e-6);
    ASSERT_LE(max_norm(&m), 1.0);
    for (int v = 0; v < m.nverts; v++)
        cen = v3_add(cen, v3_loadf(m.pos + 3 * v));
    cen = v3_scale(cen, 1.0 / m.nverts);
    for (int v = 0; v < m.nverts; v++) {
        v3 p = v3_loadf(m.pos + 3 * v), n = v3_loadf(m.nrm + 3 * v);
        ASSERT_NEAR(v3_len(n), 1.0, 1e-6);
        outward += v3_dot(n, v3_sub(p, cen)) > 0.0;
    }
    for (int t = 0; t < m.ntris; t++) {
        const uint32_t *f = m.tri + 3 * t;
        v3 a = v3_loadf(m.pos + 3 * f[0]), b = v3_loadf(m.pos + 3 * f[1]),
           c = v3_loadf(m.pos + 3 * f[2]);
        v3 fn = v3_cross(v3_sub(b, a), v3_sub(c, a));
        int ok = 1;
        for (int k = 0; k < 3; k++)
            ok &= v3_dot(fn, v3_loadf(m.nrm + 3 * f[k])) > 0.0;
        agree += ok;
    }
    printf("  teapot: %d vertices, %d triangles; normals away from the centroid at %.3f of "
           "the vertices, agreeing with the winding on %.4f of the triangles\n",
           m.nverts, m.ntris, (double)outward / m.nverts, (double)agree / m.ntris);
    /* the inner sides of the handle, the spout and the rim's lip face the
     * body: about a fifth of the vertices; ray parity below is the real test */
    ASSERT_LT(0.75, (double)outward / m.nverts);
    ASSERT_EQ(agree, m.ntris);
    ASSERT_LT(0.95, outward_share(&m, 300));
    /* welded: open only at the lid gap, the rim, the spout's tip and the
     * handle and spout ends (each one patch edge of seg segments) */
    edge_counts(&m, &nb, &nn);
    printf("  teapot: %ld boundary edges, %ld non-manifold\n", nb, nn);
    ASSERT_EQ(nn, 0);
    ASSERT_LE(nb, 24 * seg);
    /* atlas: one cell per patch, no overlap */
    over = uv_overlaps(&m, 1024, &covered);
    ASSERT_EQ(over, 0);
    for (int v = 0; v < m.nverts; v++)
        ASSERT(m.uv[2 * v] >= 0.0f && m.uv[2 * v] <= 1.0f && m.uv[2 * v + 1] >= 0.0f &&
               m.uv[2 * v + 1] <= 1.0f);
    mesh_free(&m);
    ASSERT_EQ(mesh_teapot(&m, 0, &e), GLINT_ERANGE);
    ASSERT_EQ(mesh_teapot(&m, MESH_TEAPOT_MAX_SEG + 1, &e), GLINT_ERANGE);
    ASSERT_OK(mesh_teapot(&m, 1, &e));
    ASSERT_OK(mesh_validate(&m, &e));
    mesh_free(&m);
}

TEST(builtins)
{
    static const char *names[] = {"sphere", "torus", "teapot"};
    for (int i = 0; i < 3; i++) {
        mesh m;
        glint_err e;
        double t0 = now_s();
        ASSERT_OK(mesh_builtin(names[i], &m, &e));
        ASSERT_OK(mesh_validate(&m, &e));
        ASSERT_NEAR(max_norm(&m), 1.0, 1e-6);
        printf("  %-6s %7d vertices %7d triangles, %.1f ms\n", names[i], m.nverts, m.ntris,
               1e3 * (now_s() - t0));
        mesh_free(&m);
    }
    {
        mesh m;
        glint_err e;
        ASSERT_EQ(mesh_builtin("cube", &m, &e), GLINT_ENOTFOUND);
        ASSERT(strstr(e.msg, "sphere") && strstr(e.msg, "torus") && strstr(e.msg, "teapot"));
    }
}

static void test_cleanup(void) { tmp_cleanup(); }

TEST(zz_cleanup) { test_cleanup(); }

TEST_LIST {
    TEST_ENTRY(formats_box),
    TEST_ENTRY(formats_tetrahedron),
    TEST_ENTRY(node_transforms),
    TEST_ENTRY(file_normals_and_uvs),
    TEST_ENTRY(cleaning),
    TEST_ENTRY(corrupt_inputs),
    TEST_ENTRY(argument_errors),
    TEST_ENTRY(fuzz_mutations),
    TEST_ENTRY(shared_meshes),
    TEST_ENTRY(shared_meshes_raster),
    TEST_ENTRY(concurrent_loads),
    TEST_ENTRY(uv_self_overlap_split),
    TEST_ENTRY(uv_generate_builtins),
    TEST_ENTRY(normals_and_normalize),
    TEST_ENTRY(torus),
    TEST_ENTRY(teapot_data),
    TEST_ENTRY(teapot),
    TEST_ENTRY(builtins),
    TEST_ENTRY(zz_cleanup),
};

TEST_MAIN()
