/* raster.c: deterministic CPU rasterizer producing G-buffers (contract in
 * raster.h, camera conventions in scene.h).
 *
 * Per view:
 *  1. every vertex goes to camera space (x along right, y along up, z along
 *     fwd, relative to the eye) and, when in front of the near plane, to
 *     pixel coordinates X = W/2 + (H/2) x / (z tan), Y = H/2 - (H/2) y / (z tan),
 *     so that the pixel centre (i + .5, j + .5) is exactly the ray of scene.h;
 *  2. triangles entirely in front of the near plane go straight to the
 *     scan; triangles crossing it are clipped in camera space (a triangle or
 *     a quad, fanned into two); triangles entirely behind are dropped;
 *  3. the scan walks the pixel centres of the triangle's bounding box and
 *     evaluates three edge functions in double precision.  Coverage is exact
 *     along shared edges: an edge function is always computed from the edge's
 *     end points in a canonical order (lexicographic in (Y, X)) and only its
 *     sign depends on the triangle, so the two triangles of an edge get
 *     exactly opposite values; a centre exactly on an edge belongs to the
 *     triangle for which the edge is a top or left edge (top-left rule);
 *  4. both faces are drawn (meshes may be open); a depth test on 1/z keeps
 *     the nearest surface (ties: the first triangle in index order);
 *  5. barycentrics are perspective-correct; clipped vertices carry their
 *     barycentrics in the original triangle, so attributes are always
 *     interpolated from the mesh's own vertices.
 * Everything runs in one thread in a fixed order: the output depends only on
 * the inputs. */
#include "raster.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "vec3.h"

#if defined(__clang__)
/* Fused multiply-adds would break the exact antisymmetry of edge functions
 * between copies of the same expression; GCC in ISO C mode never fuses. */
#pragma STDC FP_CONTRACT OFF
#endif

#define RASTER_PI 3.14159265358979323846
/* Near plane at this fraction of the eye-target distance. */
#define RASTER_NEAR_REL 1e-6

/* Per-vertex data of the current view. */
typedef struct raster_vtx {
    double x, y, z; /* camera space */
    double sx, sy;  /* pixel coordinates (valid when z >= znear) */
    double iz;      /* 1 / z (valid when z >= znear) */
} raster_vtx;

/* A vertex of a triangle handed to the scan. */
typedef struct raster_pt {
    double sx, sy, iz;
    double b[3]; /* barycentric coordinates in the original mesh triangle */
} raster_pt;

/* Workspace, grown to the largest mesh / image and reused across views. */
typedef struct raster_ws {
    raster_vtx *vtx;
    size_t vtx_cap;
    double *depth; /* per pixel: 1/z of the nearest surface so far, 0 = none */
    size_t depth_cap;
} raster_ws;

typedef struct raster_ctx {
    const mesh *m;
    gbuf *g;
    double *depth;
    int W, H;
    int j_lo, j_hi;   /* rows drawn: [j_lo, j_hi) of the H rows; gbuf row 0 is j_lo */
    double cx, cy, k; /* projection: X = cx + k x / z, Y = cy - k y / z */
    double znear;
    v3 eye, light;
    const uint32_t *tri; /* vertex indices of the triangle being drawn */
} raster_ctx;

static void raster_ws_free(raster_ws *ws)
{
    free(ws->vtx);
    free(ws->depth);
    memset(ws, 0, sizeof *ws);
}

static int raster_ws_reserve(raster_ws *ws, size_t nverts, size_t npix, glint_err *err)
{
    if (nverts > ws->vtx_cap) {
        raster_vtx *p;
        if (nverts > SIZE_MAX / sizeof *p)
            return glint_err_set(err, GLINT_ERANGE, "mesh of %zu vertices too large", nverts);
        p = realloc(ws->vtx, nverts * sizeof *p);
        if (!p)
            return glint_err_set(err, GLINT_ENOMEM,
                                 "out of memory for %zu rasterizer vertices", nverts);
        ws->vtx = p;
        ws->vtx_cap = nverts;
    }
    if (npix > ws->depth_cap) {
        double *p = realloc(ws->depth, npix * sizeof *p);
        if (!p)
            return glint_err_set(err, GLINT_ENOMEM,
                                 "out of memory for a depth buffer of %zu pixels", npix);
        ws->depth = p;
        ws->depth_cap = npix;
    }
    return 0;
}

/* The one projection used for every vertex, original or clipped, so that a
 * point shared by two triangles lands on bit-identical pixel coordinates. */
static inline void raster_project(const raster_ctx *c, double x, double y, double z,
                                  double *sx, double *sy)
{
    double s = c->k / z;
    *sx = c->cx + x * s;
    *sy = c->cy - y * s;
}

/* Canonical edge: end points ordered by (Y, X); raw(p) = A (py - ly) -
 * B (px - lx) is then the same number for both triangles of the edge. */
typedef struct raster_edge {
    double lx, ly, A, B;
    double sign; /* +1 or -1: orientation of this triangle's traversal */
    int own;     /* a centre exactly on the edge belongs to this triangle */
} raster_edge;

static void raster_edge_setup(raster_edge *e, const raster_pt *from, const raster_pt *to)
{
    int fwd = from->sy < to->sy || (from->sy == to->sy && from->sx < to->sx);
    const raster_pt *lo = fwd ? from : to, *hi = fwd ? to : from;
    e->lx = lo->sx;
    e->ly = lo->sy;
    e->A = hi->sx - lo->sx;
    e->B = hi->sy - lo->sy;
    e->sign = fwd ? 1.0 : -1.0;
    e->own = 0;
}

static inline double raster_edge_eval(const raster_edge *e, double px, double py)
{
    return e->A * (py - e->ly) - e->B * (px - e->lx);
}

/* Write the surface point with original-triangle barycentrics b into pixel
 * p (the depth test has passed). */
static void raster_shade(const raster_ctx *c, size_t p, const double b[3])
{
    const mesh *m = c->m;
    const uint32_t *t = c->tri;
    gbuf *g = c->g;
    v3 P = v3_make(0, 0, 0), N = v3_make(0, 0, 0);
    double u = 0.0, w = 0.0;

    for (int k = 0; k < 3; k++) {
        size_t v = t[k];
        P = v3_add(P, v3_scale(v3_loadf(m->pos + 3 * v), b[k]));
        N = v3_add(N, v3_scale(v3_loadf(m->nrm + 3 * v), b[k]));
        u += b[k] * m->uv[2 * v];
        w += b[k] * m->uv[2 * v + 1];
    }
    g->mask[p] = 1;
    v3_storef(P, g->pos + 3 * p);
    v3_storef(v3_normalize(N), g->nrm + 3 * p);
    g->uv[2 * p] = (float)u;
    g->uv[2 * p + 1] = (float)w;
    v3_storef(v3_normalize(v3_sub(c->light, P)), g->wi + 3 * p);
    v3_storef(v3_normalize(v3_sub(c->eye, P)), g->wo + 3 * p);
}

/* Scan one triangle whose vertices are all in front of the near plane. */
static void raster_tri(const raster_ctx *c, const raster_pt *v0, const raster_pt *v1,
                       const raster_pt *v2)
{
    const raster_pt *v[3] = {v0, v1, v2};
    raster_edge e[3];
    double minx, maxx, miny, maxy, fi0, fi1, fj0, fj1, area;
    int i0, i1, j0, j1;

    minx = fmin(fmin(v0->sx, v1->sx), v2->sx);
    maxx = fmax(fmax(v0->sx, v1->sx), v2->sx);
    miny = fmin(fmin(v0->sy, v1->sy), v2->sy);
    maxy = fmax(fmax(v0->sy, v1->sy), v2->sy);
    /* Pixel centres i + .5 inside [minx, maxx]; skips empty boxes (most
     * sub-pixel triangles) before any other work.  Written so that NaN
     * or infinite coordinates also land here. */
    fi0 = ceil(minx - 0.5);
    fi1 = floor(maxx - 0.5);
    fj0 = ceil(miny - 0.5);
    fj1 = floor(maxy - 0.5);
    if (fi0 < 0.0)
        fi0 = 0.0;
    if (fj0 < c->j_lo)
        fj0 = c->j_lo;
    if (fi1 > c->W - 1)
        fi1 = c->W - 1;
    if (fj1 > c->j_hi - 1)
        fj1 = c->j_hi - 1;
    if (!(fi0 <= fi1 && fj0 <= fj1))
        return;
    if (!isfinite(minx) || !isfinite(maxx) || !isfinite(miny) || !isfinite(maxy))
        return;
    i0 = (int)fi0;
    i1 = (int)fi1;
    j0 = (int)fj0;
    j1 = (int)fj1;

    /* Edge k is opposite vertex k: v[k+1] -> v[k+2]. */
    for (int k = 0; k < 3; k++)
        raster_edge_setup(&e[k], v[(k + 1) % 3], v[(k + 2) % 3]);
    /* Twice the signed area, from the same canonical evaluation. */
    area = e[0].sign * raster_edge_eval(&e[0], v0->sx, v0->sy);
    if (!(area != 0.0) || !isfinite(area))
        return;
    for (int k = 0; k < 3; k++) {
        double dx, dy;
        if (area < 0.0)
            e[k].sign = -e[k].sign; /* draw both faces: orient it positively */
        /* direction of the edge in the positively oriented traversal */
        dx = e[k].sign * e[k].A;
        dy = e[k].sign * e[k].B;
        e[k].own = dy < 0.0 || (dy == 0.0 && dx > 0.0); /* top or left edge */
    }

    for (int j = j0; j <= j1; j++) {
        double py = j + 0.5;
        double r0 = e[0].A * (py - e[0].ly), r1 = e[1].A * (py - e[1].ly),
               r2 = e[2].A * (py - e[2].ly);
        size_t row = (size_t)(j - c->j_lo) * (size_t)c->W;
        for (int i = i0; i <= i1; i++) {
            double px = i + 0.5, w0, w1, w2, iz, b[3];
            double l0 = e[0].sign * (r0 - e[0].B * (px - e[0].lx));
            double l1, l2;
            size_t p;
            if (!(l0 > 0.0 || (l0 == 0.0 && e[0].own)))
                continue;
            l1 = e[1].sign * (r1 - e[1].B * (px - e[1].lx));
            if (!(l1 > 0.0 || (l1 == 0.0 && e[1].own)))
                continue;
            l2 = e[2].sign * (r2 - e[2].B * (px - e[2].lx));
            if (!(l2 > 0.0 || (l2 == 0.0 && e[2].own)))
                continue;
            /* Perspective-correct: weights l_k / z_k. */
            w0 = l0 * v0->iz;
            w1 = l1 * v1->iz;
            w2 = l2 * v2->iz;
            iz = (w0 + w1 + w2) / (l0 + l1 + l2);
            p = row + (size_t)i;
            if (!(iz > c->depth[p]))
                continue;
            c->depth[p] = iz;
            {
                double s = 1.0 / (w0 + w1 + w2);
                w0 *= s;
                w1 *= s;
                w2 *= s;
            }
            for (int k = 0; k < 3; k++)
                b[k] = w0 * v0->b[k] + w1 * v1->b[k] + w2 * v2->b[k];
            raster_shade(c, p, b);
        }
    }
}

/* Intersection of the segment between camera-space vertices a and b with
 * the near plane, computed from the end points in a canonical order so that
 * both triangles of an edge get the same point.  ba, bb: barycentrics of
 * a and b in the current triangle. */
static void raster_clip_point(const raster_ctx *c, const raster_vtx *a, const double *ba,
                              const raster_vtx *b, const double *bb, raster_pt *out)
{
    int swap = b->z < a->z || (b->z == a->z && (b->x < a->x || (b->x == a->x && b->y < a->y)));
    const raster_vtx *lo = swap ? b : a, *hi = swap ? a : b;
    const double *blo = swap ? bb : ba, *bhi = swap ? ba : bb;
    double t = (c->znear - lo->z) / (hi->z - lo->z);
    double x = lo->x + t * (hi->x - lo->x), y = lo->y + t * (hi->y - lo->y);

    raster_project(c, x, y, c->znear, &out->sx, &out->sy);
    out->iz = 1.0 / c->znear;
    for (int k = 0; k < 3; k++)
        out->b[k] = (1.0 - t) * blo[k] + t * bhi[k];
}

/* A triangle with some vertices behind the near plane: clip (Sutherland-
 * Hodgman against z >= znear), then scan the triangle or the quad's fan. */
static void raster_tri_clipped(const raster_ctx *c, const raster_vtx *vt[3])
{
    static const double id[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    raster_pt poly[4];
    int n = 0;

    for (int k = 0; k < 3; k++) {
        const raster_vtx *a = vt[k], *b = vt[(k + 1) % 3];
        int ina = a->z >= c->znear, inb = b->z >= c->znear;
        if (ina) {
            raster_pt *q = &poly[n++];
            q->sx = a->sx;
            q->sy = a->sy;
            q->iz = a->iz;
            memcpy(q->b, id[k], sizeof q->b);
        }
        if (ina != inb && n < 4)
            raster_clip_point(c, a, id[k], b, id[(k + 1) % 3], &poly[n++]);
    }
    if (n >= 3)
        raster_tri(c, &poly[0], &poly[1], &poly[2]);
    if (n == 4)
        raster_tri(c, &poly[0], &poly[2], &poly[3]);
}

static int raster_check_view(const scene_view *v, glint_err *err)
{
    v3 d;
    for (int i = 0; i < 3; i++)
        if (!isfinite(v->eye[i]) || !isfinite(v->target[i]) || !isfinite(v->light[i]))
            return glint_err_set(err, GLINT_EINVAL,
                                 "camera or light position is not finite");
    d = v3_sub(v3_load(v->target), v3_load(v->eye));
    if (!(v3_len(d) > 0.0) || !isfinite(v3_len(d)))
        return glint_err_set(err, GLINT_EINVAL, "degenerate camera: eye equals target");
    if (!(v->half_fov > 0.0 && v->half_fov < RASTER_PI / 2))
        return glint_err_set(err, GLINT_EINVAL,
                             "degenerate camera: half_fov %g outside (0, pi/2)", v->half_fov);
    return 0;
}

/* Rows [row0, row0 + nrows) of raster_view, with a caller's workspace;
 * the mesh is already validated. */
static int raster_rows_ws(const mesh *m, const scene_view *v, int width, int height, int row0,
                          int nrows, raster_ws *ws, gbuf *out, glint_err *err)
{
    double fwd[3], right[3], up[3], t;
    raster_ctx c;
    size_t nv = (size_t)m->nverts, npix;
    int rc;

    if (width < SCENE_MIN_SIZE || width > SCENE_MAX_SIZE || height < SCENE_MIN_SIZE ||
        height > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "raster size %dx%d outside %d..%d", width,
                             height, SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    if (row0 < 0 || nrows < 1 || row0 > height - nrows)
        return glint_err_set(err, GLINT_ERANGE, "rows %d..%d outside the %d rows of the view",
                             row0, row0 + nrows - 1, height);
    rc = raster_check_view(v, err);
    if (rc)
        return rc;
    npix = (size_t)width * (size_t)nrows;
    rc = raster_ws_reserve(ws, nv, npix, err);
    if (rc)
        return rc;
    rc = gbuf_alloc(out, width, nrows, err);
    if (rc)
        return rc;

    scene_view_frame(v, fwd, right, up);
    t = tan(v->half_fov);
    memset(&c, 0, sizeof c);
    c.m = m;
    c.g = out;
    c.depth = ws->depth;
    c.W = width;
    c.H = height;
    c.j_lo = row0;
    c.j_hi = row0 + nrows;
    c.cx = 0.5 * width;
    c.cy = 0.5 * height;
    c.k = 0.5 * height / t;
    c.eye = v3_load(v->eye);
    c.light = v3_load(v->light);
    c.znear = RASTER_NEAR_REL * v3_len(v3_sub(v3_load(v->target), c.eye));
    if (!(c.znear > 0.0) || !isfinite(c.k)) {
        gbuf_free(out);
        return glint_err_set(err, GLINT_EINVAL, "degenerate camera (near plane %g, scale %g)",
                             c.znear, c.k);
    }
    for (size_t p = 0; p < npix; p++)
        ws->depth[p] = 0.0;

    {
        v3 R = v3_load(right), U = v3_load(up), F = v3_load(fwd);
        for (size_t i = 0; i < nv; i++) {
            raster_vtx *q = &ws->vtx[i];
            v3 d = v3_sub(v3_loadf(m->pos + 3 * i), c.eye);
            q->x = v3_dot(d, R);
            q->y = v3_dot(d, U);
            q->z = v3_dot(d, F);
            if (q->z >= c.znear) {
                raster_project(&c, q->x, q->y, q->z, &q->sx, &q->sy);
                q->iz = 1.0 / q->z;
            } else {
                q->sx = q->sy = q->iz = 0.0;
            }
        }
    }

    for (size_t f = 0; f < (size_t)m->ntris; f++) {
        static const double id[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        const uint32_t *tri = m->tri + 3 * f;
        const raster_vtx *vt[3] = {&ws->vtx[tri[0]], &ws->vtx[tri[1]], &ws->vtx[tri[2]]};
        int nin = (vt[0]->z >= c.znear) + (vt[1]->z >= c.znear) + (vt[2]->z >= c.znear);

        c.tri = tri;
        if (nin == 3) {
            raster_pt p[3];
            /* Cheap reject before building anything: does the bounding box
             * hold a pixel centre? */
            double minx = fmin(fmin(vt[0]->sx, vt[1]->sx), vt[2]->sx);
            double maxx = fmax(fmax(vt[0]->sx, vt[1]->sx), vt[2]->sx);
            double miny = fmin(fmin(vt[0]->sy, vt[1]->sy), vt[2]->sy);
            double maxy = fmax(fmax(vt[0]->sy, vt[1]->sy), vt[2]->sy);
            if (!(ceil(minx - 0.5) <= floor(maxx - 0.5) && ceil(miny - 0.5) <= floor(maxy - 0.5)))
                continue;
            if (maxx < 0.5 || maxy < row0 + 0.5 || minx > width - 0.5 ||
                miny > row0 + nrows - 0.5)
                continue;
            for (int k = 0; k < 3; k++) {
                p[k].sx = vt[k]->sx;
                p[k].sy = vt[k]->sy;
                p[k].iz = vt[k]->iz;
                memcpy(p[k].b, id[k], sizeof p[k].b);
            }
            raster_tri(&c, &p[0], &p[1], &p[2]);
        } else if (nin > 0) {
            raster_tri_clipped(&c, vt);
        }
    }
    return 0;
}

static int raster_view_ws(const mesh *m, const scene_view *v, int width, int height,
                          raster_ws *ws, gbuf *out, glint_err *err)
{
    return raster_rows_ws(m, v, width, height, 0, height, ws, out, err);
}

/* Checks and work space around raster_rows_ws (who: the caller, for messages). */
static int raster_rows_checked(const char *who, const mesh *m, const scene_view *v, int width,
                               int height, int row0, int nrows, gbuf *out, glint_err *err)
{
    raster_ws ws;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "%s: output gbuf is NULL", who);
    memset(out, 0, sizeof *out);
    if (!m || !v)
        return glint_err_set(err, GLINT_EINVAL, "%s: mesh or view is NULL", who);
    if (width < SCENE_MIN_SIZE || width > SCENE_MAX_SIZE || height < SCENE_MIN_SIZE ||
        height > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "raster size %dx%d outside %d..%d", width,
                             height, SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    rc = mesh_validate(m, err);
    if (rc)
        return rc;
    memset(&ws, 0, sizeof ws);
    rc = raster_rows_ws(m, v, width, height, row0, nrows, &ws, out, err);
    raster_ws_free(&ws);
    return rc;
}

int raster_view_rows(const mesh *m, const scene_view *v, int width, int height, int row0,
                     int nrows, gbuf *out, glint_err *err)
{
    return raster_rows_checked("raster_view_rows", m, v, width, height, row0, nrows, out, err);
}

int raster_view(const mesh *m, const scene_view *v, int width, int height, gbuf *out,
                glint_err *err)
{
    return raster_rows_checked("raster_view", m, v, width, height, 0, height, out, err);
}

int raster_scene(const scene *s, gbuf **out, glint_err *err)
{
    raster_ws ws;
    gbuf *g;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "raster_scene: output pointer is NULL");
    *out = NULL;
    rc = scene_validate(s, err);
    if (rc)
        return rc;
    g = calloc((size_t)s->nviews, sizeof *g);
    if (!g)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %d G-buffers", s->nviews);
    memset(&ws, 0, sizeof ws);
    for (int k = 0; k < s->nviews; k++) {
        rc = raster_view_ws(&s->mesh, &s->views[k], s->width, s->height, &ws, &g[k], err);
        if (rc) {
            glint_err_prefix(err, "view %d", k);
            raster_ws_free(&ws);
            raster_free_all(g, s->nviews);
            return rc;
        }
    }
    raster_ws_free(&ws);
    *out = g;
    return 0;
}

void raster_free_all(gbuf *g, int n)
{
    if (!g)
        return;
    for (int k = 0; k < n; k++)
        gbuf_free(&g[k]);
    free(g);
}
