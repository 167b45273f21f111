/* mesh_uv.c: glint's automatic parameterization for meshes without
 * texture coordinates (mesh_generate_uvs; the method is described at its
 * definition below). */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "internal/mesh_int.h"
#include "vec3.h"

/* ------------------------------------------------------------------------ */
/* Automatic parameterization                                                */
/* ------------------------------------------------------------------------ */

/* A triangle may join a chart whose axis is within acos(UVG_MIN_COS) = 65
 * degrees of its normal; its uv area is then at least UVG_MIN_COS of its
 * (scaled) 3D area. */
#define UVG_MIN_COS 0.42
#define UVG_SMOOTH_PASSES 3
/* Gap between charts (and half of it at the atlas border), in uv units:
 * two texels of a 1024^2 material map. */
#define UVG_GUTTER (2.0 / 1024.0)
#define UVG_ROT_STEPS 32
/* Triangles spanning more grid cells than this are checked linearly. */
#define UVG_BIG_CELLS 64

/* Orthographic projection onto the plane of axis a (+x, -x, +y, -y, +z,
 * -z), with the in-plane basis chosen so that a triangle facing the axis
 * keeps its counter-clockwise orientation: +x (y, z), -x (-y, z),
 * +y (z, x), -y (-z, x), +z (x, y), -z (-x, y). */
static void uvg_project(int a, const float *p, double *s, double *t)
{
    switch (a) {
    case 0: *s = p[1]; *t = p[2]; break;
    case 1: *s = -(double)p[1]; *t = p[2]; break;
    case 2: *s = p[2]; *t = p[0]; break;
    case 3: *s = -(double)p[2]; *t = p[0]; break;
    case 4: *s = p[0]; *t = p[1]; break;
    default: *s = -(double)p[0]; *t = p[1]; break;
    }
}

static double uvg_axis_dot(int a, const double n[3])
{
    return (a & 1) ? -n[a >> 1] : n[a >> 1];
}

/* Do the interiors of two 2D triangles (x0 y0 x1 y1 x2 y2) overlap by more
 * than `tol`?  Separating-axis test over the six edge normals; touching
 * along a shared edge or vertex is not an overlap. */
static int uvg_overlap(const double *a, const double *b, double tol)
{
    const double *w[2] = {a, b};
    for (int s = 0; s < 2; s++)
        for (int e = 0; e < 3; e++) {
            const double *p = w[s];
            double ex = p[2 * ((e + 1) % 3)] - p[2 * e];
            double ey = p[2 * ((e + 1) % 3) + 1] - p[2 * e + 1];
            double l = hypot(ex, ey), nx, ny, amin = INFINITY, amax = -INFINITY,
                   bmin = INFINITY, bmax = -INFINITY;
            if (!(l > 0.0))
                continue;
            nx = -ey / l;
            ny = ex / l;
            for (int k = 0; k < 3; k++) {
                double da = nx * a[2 * k] + ny * a[2 * k + 1];
                double db = nx * b[2 * k] + ny * b[2 * k + 1];
                amin = fmin(amin, da);
                amax = fmax(amax, da);
                bmin = fmin(bmin, db);
                bmax = fmax(bmax, db);
            }
            if (amax <= bmin + tol || bmax <= amin + tol)
                return 0;
        }
    return 1;
}

/* Hash grid of the triangles of the chart being grown: cell (ix, iy) ->
 * linked list of triangles whose bounding box touches it.  Reset between
 * charts by clearing only the slots used. */
typedef struct uvg_grid {
    size_t cap, used;
    int32_t *kx, *ky;
    uint32_t *head;    /* UINT32_MAX: empty slot */
    uint32_t *touched; /* slots in use, `used` of them */
    uint32_t *etri, *enext;
    size_t nent, entcap;
    double h;          /* cell size */
} uvg_grid;

static void uvg_grid_free(uvg_grid *g)
{
    free(g->kx);
    free(g->ky);
    free(g->head);
    free(g->touched);
    free(g->etri);
    free(g->enext);
    memset(g, 0, sizeof *g);
}

static size_t uvg_slot_hash(int32_t x, int32_t y, size_t cap)
{
    uint64_t h = (uint64_t)(uint32_t)x * 0x9E3779B97F4A7C15ull ^
                 (uint64_t)(uint32_t)y * 0xC2B2AE3D27D4EB4Full;
    h ^= h >> 31;
    return (size_t)h & (cap - 1);
}

static int uvg_grid_init(uvg_grid *g, size_t cap)
{
    memset(g, 0, sizeof *g);
    g->cap = cap;
    g->kx = malloc(cap * sizeof *g->kx);
    g->ky = malloc(cap * sizeof *g->ky);
    g->head = malloc(cap * sizeof *g->head);
    g->touched = malloc(cap * sizeof *g->touched);
    g->entcap = cap;
    g->etri = malloc(g->entcap * sizeof *g->etri);
    g->enext = malloc(g->entcap * sizeof *g->enext);
    if (!g->kx || !g->ky || !g->head || !g->touched || !g->etri || !g->enext)
        return -1;
    memset(g->head, 0xff, cap * sizeof *g->head);
    return 0;
}

static void uvg_grid_reset(uvg_grid *g)
{
    for (size_t i = 0; i < g->used; i++)
        g->head[g->touched[i]] = UINT32_MAX;
    g->used = 0;
    g->nent = 0;
}

/* Slot of cell (x, y), created if absent; SIZE_MAX on allocation failure. */
static size_t uvg_grid_slot(uvg_grid *g, int32_t x, int32_t y, int create)
{
    size_t s;
    if (create && 2 * (g->used + 1) > g->cap) {
        uvg_grid n;
        if (uvg_grid_init(&n, 2 * g->cap)) {
            uvg_grid_free(&n);
            return SIZE_MAX;
        }
        n.h = g->h;
        for (size_t i = 0; i < g->used; i++) {
            size_t o = g->touched[i], t = uvg_slot_hash(g->kx[o], g->ky[o], n.cap);
            while (n.head[t] != UINT32_MAX)
                t = (t + 1) & (n.cap - 1);
            n.kx[t] = g->kx[o];
            n.ky[t] = g->ky[o];
            n.head[t] = g->head[o];
            n.touched[n.used++] = (uint32_t)t;
        }
        free(n.etri);
        free(n.enext);
        n.etri = g->etri;
        n.enext = g->enext;
        n.nent = g->nent;
        n.entcap = g->entcap;
        g->etri = g->enext = NULL;
        uvg_grid_free(g);
        *g = n;
    }
    s = uvg_slot_hash(x, y, g->cap);
    while (g->head[s] != UINT32_MAX) {
        if (g->kx[s] == x && g->ky[s] == y)
            return s;
        s = (s + 1) & (g->cap - 1);
    }
    if (!create)
        return SIZE_MAX - 1; /* absent */
    g->kx[s] = x;
    g->ky[s] = y;
    g->touched[g->used++] = (uint32_t)s;
    return s;
}

static int32_t uvg_cell(double x, double h)
{
    double c = floor(x / h);
    if (c < -1073741824.0)
        c = -1073741824.0;
    if (c > 1073741823.0)
        c = 1073741823.0;
    return (int32_t)c;
}

/* Everything the chart growth needs. */
typedef struct uvg_ctx {
    const double *t2;   /* 6 per triangle: projection onto its label's plane */
    uvg_grid grid;
    uint32_t *stamp;    /* per triangle: last query that tested it */
    uint32_t qid;
    uint32_t *big;      /* triangles of the current chart spanning many cells */
    size_t nbig;
    const uint32_t *ctri; /* current chart's triangles: ctri[c0 .. c1) */
    size_t c0, c1;
    double tol, tiny_area;
    size_t nt;
} uvg_ctx;

static void uvg_tri_cells(const uvg_ctx *x, uint32_t t, int32_t *x0, int32_t *y0, int32_t *x1,
                          int32_t *y1)
{
    const double *p = x->t2 + 6 * (size_t)t;
    double lx = fmin(p[0], fmin(p[2], p[4])), hx = fmax(p[0], fmax(p[2], p[4]));
    double ly = fmin(p[1], fmin(p[3], p[5])), hy = fmax(p[1], fmax(p[3], p[5]));
    *x0 = uvg_cell(lx - x->tol, x->grid.h);
    *x1 = uvg_cell(hx + x->tol, x->grid.h);
    *y0 = uvg_cell(ly - x->tol, x->grid.h);
    *y1 = uvg_cell(hy + x->tol, x->grid.h);
}

static double uvg_area2(const double *p)
{
    return (p[2] - p[0]) * (p[5] - p[1]) - (p[4] - p[0]) * (p[3] - p[1]);
}

static int uvg_is_big(int32_t x0, int32_t y0, int32_t x1, int32_t y1)
{
    return ((int64_t)x1 - x0 + 1) * ((int64_t)y1 - y0 + 1) > UVG_BIG_CELLS;
}

/* 1 if triangle u overlaps a triangle of the current chart. */
static int uvg_conflicts(uvg_ctx *x, uint32_t u)
{
    const double *pu = x->t2 + 6 * (size_t)u;
    int32_t x0, y0, x1, y1;

    if (fabs(uvg_area2(pu)) <= x->tiny_area)
        return 0; /* no area: can cover nothing */
    if (++x->qid == UINT32_MAX) { /* wrapped: forget every stamp */
        x->qid = 1;
        memset(x->stamp, 0, x->nt * sizeof *x->stamp);
    }
    uvg_tri_cells(x, u, &x0, &y0, &x1, &y1);
    if (uvg_is_big(x0, y0, x1, y1)) {
        for (size_t i = x->c0; i < x->c1; i++)
            if (uvg_overlap(pu, x->t2 + 6 * (size_t)x->ctri[i], x->tol))
                return 1;
        return 0;
    }
    for (size_t i = 0; i < x->nbig; i++)
        if (uvg_overlap(pu, x->t2 + 6 * (size_t)x->big[i], x->tol))
            return 1;
    for (int32_t cy = y0; cy <= y1; cy++)
        for (int32_t cx = x0; cx <= x1; cx++) {
            size_t s = uvg_grid_slot(&x->grid, cx, cy, 0);
            if (s >= SIZE_MAX - 1)
                continue;
            for (uint32_t e = x->grid.head[s]; e != UINT32_MAX; e = x->grid.enext[e]) {
                uint32_t t = x->grid.etri[e];
                if (x->stamp[t] == x->qid)
                    continue;
                x->stamp[t] = x->qid;
                if (uvg_overlap(pu, x->t2 + 6 * (size_t)t, x->tol))
                    return 1;
            }
        }
    return 0;
}

/* Add triangle t to the current chart's grid; -1 on allocation failure. */
static int uvg_insert(uvg_ctx *x, uint32_t t)
{
    int32_t x0, y0, x1, y1;
    uvg_tri_cells(x, t, &x0, &y0, &x1, &y1);
    if (uvg_is_big(x0, y0, x1, y1)) {
        x->big[x->nbig++] = t;
        return 0;
    }
    for (int32_t cy = y0; cy <= y1; cy++)
        for (int32_t cx = x0; cx <= x1; cx++) {
            size_t s = uvg_grid_slot(&x->grid, cx, cy, 1);
            uvg_grid *g = &x->grid;
            if (s == SIZE_MAX)
                return -1;
            if (g->nent == g->entcap) {
                size_t nc = 2 * g->entcap;
                uint32_t *a = realloc(g->etri, nc * sizeof *a), *b;
                if (!a)
                    return -1;
                g->etri = a;
                b = realloc(g->enext, nc * sizeof *b);
                if (!b)
                    return -1;
                g->enext = b;
                g->entcap = nc;
            }
            g->etri[g->nent] = t;
            g->enext[g->nent] = g->head[s];
            g->head[s] = (uint32_t)g->nent++;
        }
    return 0;
}

typedef struct uvg_seed {
    double key;
    uint32_t t;
} uvg_seed;

static int uvg_seed_cmp(const void *a, const void *b)
{
    const uvg_seed *p = a, *q = b;
    if (p->key != q->key)
        return p->key > q->key ? -1 : 1;
    return p->t < q->t ? -1 : p->t > q->t;
}

typedef struct uvg_item {
    double w, h;   /* chart extent after rotation */
    double x, y;   /* placement (lower-left of the slot) */
    uint32_t c;
} uvg_item;

static int uvg_item_cmp(const void *a, const void *b)
{
    const uvg_item *p = a, *q = b;
    if (p->h != q->h)
        return p->h > q->h ? -1 : 1;
    if (p->w != q->w)
        return p->w > q->w ? -1 : 1;
    return p->c < q->c ? -1 : p->c > q->c;
}

/* First-fit decreasing-height shelf packing of items (sorted by height)
 * into shelves of width W with a gap g: each item goes to the first shelf
 * with room left, else opens a new shelf.  `shelf` has room for n widths.
 * Returns the side of the enclosing square and fills x, y. */
static double uvg_shelf(uvg_item *it, size_t n, double W, double g, double *shelf_x,
                        double *shelf_y)
{
    size_t ns = 0;
    double top = 0.0, usedw = 0.0;
    for (size_t i = 0; i < n; i++) {
        double iw = it[i].w + g, ih = it[i].h + g;
        size_t s = 0;
        while (s < ns && shelf_x[s] + iw > W)
            s++;
        if (s == ns) { /* new shelf, as tall as this (the tallest left) item */
            shelf_x[ns] = 0.0;
            shelf_y[ns] = top;
            top += ih;
            ns++;
        }
        it[i].x = shelf_x[s];
        it[i].y = shelf_y[s];
        shelf_x[s] += iw;
        usedw = fmax(usedw, shelf_x[s]);
    }
    return fmax(usedw, top);
}

/* Best shelf packing over a range of row widths (OUT: positions in it);
 * returns the square side. */
static double uvg_pack(uvg_item *it, size_t n, double g, double *sx, double *sy)
{
    double area = 0.0, wmax = 0.0, best = INFINITY, bestW = 0.0;
    for (size_t i = 0; i < n; i++) {
        area += (it[i].w + g) * (it[i].h + g);
        wmax = fmax(wmax, it[i].w + g);
    }
    for (int k = 0; k <= 40; k++) {
        double W = fmax(sqrt(area) * (1.0 + 0.025 * k), wmax);
        double side = uvg_shelf(it, n, W, g, sx, sy);
        if (side < best) {
            best = side;
            bestW = W;
        }
    }
    return uvg_shelf(it, n, bestW, g, sx, sy);
}

/* glint's automatic parameterization.
 *
 * Method (a segmentation into near-planar charts, each projected
 * orthographically, packed into one square):
 *  1. Each triangle is labelled with the closest of the six axis directions
 *     +-x, +-y, +-z to its normal.  Labels are smoothed over edge neighbours
 *     (welded positions): a triangle takes the label held by at least two
 *     of its neighbours, and by more of them than its own, provided its
 *     normal is within 65 degrees of that axis (3 Jacobi passes).  This
 *     removes the islands and jagged borders that noise in the normals
 *     creates.
 *  2. Charts grow breadth-first over edge neighbours with the same label,
 *     seeded in order of decreasing alignment with their axis.  A triangle
 *     joins only if its projection onto the chart's axis plane overlaps no
 *     triangle already in the chart (separating-axis test against a hash
 *     grid of the chart); otherwise it is left for another chart.  So no
 *     two triangles of a chart overlap in uv, even where a chart's surface
 *     folds over itself along the axis (a spiral ramp, an ear over a
 *     cheek), and triangles seen through each other from the axis end up in
 *     different charts.
 *  3. Vertices are duplicated where a chart border runs through them.
 *  4. Each chart is projected orthographically onto its axis plane with an
 *     orientation-preserving basis (counter-clockwise triangles stay
 *     counter-clockwise in uv), rotated to the smallest bounding rectangle
 *     among 32 angles in [0, 90) degrees, and laid flat (width >= height).
 *  5. Charts are shelf-packed (first-fit decreasing height: tallest first,
 *     each into the first shelf with room; the best of 41 shelf widths)
 *     into a square with a gap of UVG_GUTTER (2 texels at 1024^2) between
 *     charts and half of it at the border; one uniform scale maps the
 *     square onto [0,1]^2.
 * Properties: every triangle has uv; charts do not overlap each other
 * (disjoint packing rectangles) nor themselves (step 2); the map is
 * conformal up to the projection's foreshortening, so the ratio of uv area
 * to 3D area is the same global constant times cos(normal, axis), which is
 * in [0.42, 1]; texel density is therefore uniform within a factor 2.4.
 * The result depends only on the mesh (no randomness, no threads).
 * OUT (optional): *ncharts. */
int mio_uv_generate(mesh *m, int *ncharts, glint_err *err)
{
    size_t nv, nt, nch = 0, nn = 0;
    uint32_t *canon = NULL, *nbo = NULL, *nbs = NULL, *ctri = NULL, *cstart = NULL;
    uint32_t *rej = NULL, *last = NULL, *newid = NULL, *orig = NULL, *newtri = NULL;
    uint32_t *vstart = NULL;
    int32_t *chart = NULL;
    unsigned char *lab = NULL, *lab2 = NULL, *caxis = NULL;
    double *fn = NULL, *t2 = NULL, *ps = NULL, *shx = NULL, *shy = NULL;
    mio_pair *edges = NULL;
    uvg_seed *order = NULL;
    uvg_item *items = NULL;
    uvg_ctx x;
    float *npos = NULL, *nnrm = NULL, *nuv = NULL;
    double diag, mean_edge = 0.0;
    int rc;

    memset(&x, 0, sizeof x);
    nv = (size_t)m->nverts;
    nt = (size_t)m->ntris;
    diag = mio_bbox_diag(m->pos, nv);
    if (!(diag > 0.0) || !isfinite(diag))
        diag = 1.0;

    canon = malloc(nv * sizeof *canon);
    lab = malloc(nt);
    lab2 = malloc(nt);
    fn = malloc(3 * nt * sizeof *fn);
    t2 = malloc(6 * nt * sizeof *t2);
    nbo = calloc(nt + 1, sizeof *nbo);
    chart = malloc(nt * sizeof *chart);
    rej = malloc(nt * sizeof *rej);
    ctri = malloc(nt * sizeof *ctri);
    cstart = malloc((nt + 1) * sizeof *cstart);
    caxis = malloc(nt);
    order = malloc(nt * sizeof *order);
    x.stamp = calloc(nt, sizeof *x.stamp);
    x.big = malloc(nt * sizeof *x.big);
    if (!canon || !lab || !lab2 || !fn || !t2 || !nbo || !chart || !rej || !ctri || !cstart ||
        !caxis || !order || !x.stamp || !x.big)
        goto nomem;
    rc = mio_weld(m->pos, nv, canon, err);
    if (rc)
        goto done;

    /* 1. normals, labels */
    for (size_t t = 0; t < nt; t++) {
        v3 n;
        double l = mio_tri_cross_len(m->pos, m->tri + 3 * t, &n), best = -INFINITY;
        int a = 0;
        n = l > 0.0 ? v3_scale(n, 1.0 / l) : v3_make(0, 0, 0);
        v3_store(n, fn + 3 * t);
        for (int k = 0; k < 6; k++) {
            double d = uvg_axis_dot(k, fn + 3 * t);
            if (d > best) {
                best = d;
                a = k;
            }
        }
        lab[t] = (unsigned char)a;
        for (int k = 0; k < 3; k++) {
            const float *p = m->pos + 3 * (size_t)m->tri[3 * t + k];
            const float *q = m->pos + 3 * (size_t)m->tri[3 * t + (k + 1) % 3];
            mean_edge += v3_len(v3_sub(v3_loadf(p), v3_loadf(q)));
        }
    }
    mean_edge /= 3.0 * (double)nt;

    /* adjacency (CSR) from the sorted welded edges: pairs, and chains
     * along non-manifold edges */
    rc = mio_edges_sorted(m, canon, &edges, err);
    if (rc)
        goto done;
    {
        size_t ne = 3 * nt, total = 0;
        for (int pass = 0; pass < 2; pass++) {
            for (size_t i = 0; i < ne;) {
                size_t j = i + 1;
                while (j < ne && edges[j].key == edges[i].key)
                    j++;
                for (size_t k = i; k + 1 < j; k++) {
                    uint32_t a = edges[k].val / 3, b = edges[k + 1].val / 3;
                    if (a == b)
                        continue;
                    if (pass == 0) {
                        nbo[a + 1]++;
                        nbo[b + 1]++;
                    } else {
                        nbs[nbo[a]++] = b;
                        nbs[nbo[b]++] = a;
                    }
                }
                i = j;
            }
            if (pass == 0) {
                for (size_t t = 0; t < nt; t++)
                    nbo[t + 1] += nbo[t];
                total = nbo[nt];
                nbs = malloc((total ? total : 1) * sizeof *nbs);
                if (!nbs)
                    goto nomem;
            } else {
                /* nbo[t] now holds the end of t's list: shift back */
                for (size_t t = nt; t > 0; t--)
                    nbo[t] = nbo[t - 1];
                nbo[0] = 0;
            }
        }
        free(edges);
        edges = NULL;
    }

    /* label smoothing */
    for (int pass = 0; pass < UVG_SMOOTH_PASSES; pass++) {
        size_t changed = 0;
        for (size_t t = 0; t < nt; t++) {
            int cnt[6] = {0, 0, 0, 0, 0, 0}, best = lab[t];
            for (uint32_t k = nbo[t]; k < nbo[t + 1]; k++)
                cnt[lab[nbs[k]]]++;
            for (int a = 0; a < 6; a++)
                if (cnt[a] > cnt[best])
                    best = a;
            lab2[t] = lab[t];
            if (best != lab[t] && cnt[best] >= 2 &&
                uvg_axis_dot(best, fn + 3 * t) >= UVG_MIN_COS) {
                lab2[t] = (unsigned char)best;
                changed++;
            }
        }
        memcpy(lab, lab2, nt);
        if (!changed)
            break;
    }

    /* 2. chart growth */
    for (size_t t = 0; t < nt; t++) {
        for (int k = 0; k < 3; k++)
            uvg_project(lab[t], m->pos + 3 * (size_t)m->tri[3 * t + k], t2 + 6 * t + 2 * k,
                        t2 + 6 * t + 2 * k + 1);
        order[t].key = uvg_axis_dot(lab[t], fn + 3 * t);
        order[t].t = (uint32_t)t;
        chart[t] = -1;
        rej[t] = UINT32_MAX;
    }
    qsort(order, nt, sizeof *order, uvg_seed_cmp);
    x.t2 = t2;
    x.nt = nt;
    x.ctri = ctri;
    x.tol = 1e-9 * diag;
    x.tiny_area = 1e-24 * diag * diag;
    if (uvg_grid_init(&x.grid, 1024))
        goto nomem;
    x.grid.h = 2.0 * mean_edge > 1e-12 * diag ? 2.0 * mean_edge : diag;
    {
        size_t n = 0;
        for (size_t o = 0; o < nt; o++) {
            uint32_t seed = order[o].t;
            int axis;
            if (chart[seed] >= 0)
                continue;
            axis = lab[seed];
            cstart[nch] = (uint32_t)n;
            caxis[nch] = (unsigned char)axis;
            uvg_grid_reset(&x.grid);
            x.nbig = 0;
            x.c0 = n;
            chart[seed] = (int32_t)nch;
            ctri[n++] = seed;
            x.c1 = n;
            if (uvg_insert(&x, seed))
                goto nomem;
            for (size_t head = x.c0; head < n; head++) {
                uint32_t s = ctri[head];
                for (uint32_t k = nbo[s]; k < nbo[s + 1]; k++) {
                    uint32_t u = nbs[k];
                    if (chart[u] >= 0 || lab[u] != axis || rej[u] == (uint32_t)nch)
                        continue;
                    x.c1 = n;
                    if (uvg_conflicts(&x, u)) {
                        rej[u] = (uint32_t)nch;
                        continue;
                    }
                    chart[u] = (int32_t)nch;
                    ctri[n++] = u;
                    x.c1 = n;
                    if (uvg_insert(&x, u))
                        goto nomem;
                }
            }
            nch++;
        }
        cstart[nch] = (uint32_t)n;
    }
    free(nbs);
    nbs = NULL;
    free(t2);
    t2 = NULL;
    uvg_grid_free(&x.grid);

    /* 3. split vertices per chart */
    if (3 * nt > (size_t)INT_MAX / 3) {
        rc = glint_err_set(err, GLINT_ERANGE, "too many triangles (%zu) to parameterize", nt);
        goto done;
    }
    last = calloc(nv, sizeof *last);
    newid = malloc(nv * sizeof *newid);
    orig = malloc(3 * nt * sizeof *orig);
    newtri = malloc(3 * nt * sizeof *newtri);
    vstart = malloc((nch + 1) * sizeof *vstart);
    if (!last || !newid || !orig || !newtri || !vstart)
        goto nomem;
    for (size_t c = 0; c < nch; c++) {
        vstart[c] = (uint32_t)nn;
        for (size_t i = cstart[c]; i < cstart[c + 1]; i++) {
            size_t t = ctri[i];
            for (int k = 0; k < 3; k++) {
                uint32_t v = m->tri[3 * t + k];
                if (last[v] != (uint32_t)c + 1) {
                    last[v] = (uint32_t)c + 1;
                    newid[v] = (uint32_t)nn;
                    orig[nn++] = v;
                }
                newtri[3 * t + k] = newid[v];
            }
        }
    }
    vstart[nch] = (uint32_t)nn;

    /* 4. projection, rotation, extents */
    ps = malloc(2 * nn * sizeof *ps);
    items = malloc((nch ? nch : 1) * sizeof *items);
    shx = malloc((nch ? nch : 1) * sizeof *shx);
    shy = malloc((nch ? nch : 1) * sizeof *shy);
    if (!ps || !items || !shx || !shy)
        goto nomem;
    for (size_t c = 0; c < nch; c++) {
        double bestA = INFINITY, bc = 1.0, bs = 0.0, lx, ly, hx, hy;
        for (size_t i = vstart[c]; i < vstart[c + 1]; i++)
            uvg_project(caxis[c], m->pos + 3 * (size_t)orig[i], ps + 2 * i, ps + 2 * i + 1);
        for (int r = 0; r < UVG_ROT_STEPS; r++) {
            double th = (3.14159265358979323846 / 2) * r / UVG_ROT_STEPS;
            double co = cos(th), si = sin(th), A;
            lx = ly = INFINITY;
            hx = hy = -INFINITY;
            for (size_t i = vstart[c]; i < vstart[c + 1]; i++) {
                double u = co * ps[2 * i] - si * ps[2 * i + 1];
                double v = si * ps[2 * i] + co * ps[2 * i + 1];
                lx = fmin(lx, u);
                hx = fmax(hx, u);
                ly = fmin(ly, v);
                hy = fmax(hy, v);
            }
            A = (hx - lx) * (hy - ly);
            if (A < bestA * (1.0 - 1e-12)) {
                bestA = A;
                bc = co;
                bs = si;
            }
        }
        lx = ly = INFINITY;
        hx = hy = -INFINITY;
        for (size_t i = vstart[c]; i < vstart[c + 1]; i++) {
            double u = bc * ps[2 * i] - bs * ps[2 * i + 1];
            double v = bs * ps[2 * i] + bc * ps[2 * i + 1];
            ps[2 * i] = u;
            ps[2 * i + 1] = v;
            lx = fmin(lx, u);
            hx = fmax(hx, u);
            ly = fmin(ly, v);
            hy = fmax(hy, v);
        }
        if (hy - ly > hx - lx) { /* lay it flat: rotate by +90 degrees */
            for (size_t i = vstart[c]; i < vstart[c + 1]; i++) {
                double u = ps[2 * i];
                ps[2 * i] = -ps[2 * i + 1];
                ps[2 * i + 1] = u;
            }
            {
                double t0 = lx, t1 = hx;
                lx = -hy;
                hx = -ly;
                ly = t0;
                hy = t1;
            }
        }
        for (size_t i = vstart[c]; i < vstart[c + 1]; i++) {
            ps[2 * i] -= lx;
            ps[2 * i + 1] -= ly;
        }
        items[c].w = hx - lx;
        items[c].h = hy - ly;
        items[c].c = (uint32_t)c;
    }

    /* 5. packing, with the gutter in uv units fixed by iteration */
    {
        double sumA = 0.0, side, g;
        for (size_t c = 0; c < nch; c++)
            sumA += items[c].w * items[c].h;
        qsort(items, nch, sizeof *items, uvg_item_cmp);
        side = sqrt(sumA / 0.7);
        if (!(side > 0.0))
            side = diag;
        for (int it = 0; it < 3; it++) {
            g = UVG_GUTTER * side;
            side = uvg_pack(items, nch, g, shx, shy);
        }
        g = UVG_GUTTER * side;
        side = uvg_pack(items, nch, g, shx, shy);
        npos = malloc(3 * nn * sizeof *npos);
        nnrm = malloc(3 * nn * sizeof *nnrm);
        nuv = malloc(2 * nn * sizeof *nuv);
        if (!npos || !nnrm || !nuv)
            goto nomem;
        for (size_t k = 0; k < nch; k++) {
            size_t c = items[k].c;
            double ox = items[k].x + 0.5 * g, oy = items[k].y + 0.5 * g;
            for (size_t i = vstart[c]; i < vstart[c + 1]; i++) {
                double u = (ps[2 * i] + ox) / side, v = (ps[2 * i + 1] + oy) / side;
                nuv[2 * i] = (float)fmin(1.0, fmax(0.0, u));
                nuv[2 * i + 1] = (float)fmin(1.0, fmax(0.0, v));
            }
        }
    }
    for (size_t i = 0; i < nn; i++) {
        memcpy(npos + 3 * i, m->pos + 3 * (size_t)orig[i], 3 * sizeof(float));
        if (m->nrm)
            memcpy(nnrm + 3 * i, m->nrm + 3 * (size_t)orig[i], 3 * sizeof(float));
        else
            nnrm[3 * i] = nnrm[3 * i + 1] = nnrm[3 * i + 2] = 0.0f;
    }
    free(m->pos);
    free(m->nrm);
    free(m->uv);
    m->pos = npos;
    m->nrm = nnrm;
    m->uv = nuv;
    npos = nnrm = nuv = NULL;
    memcpy(m->tri, newtri, 3 * nt * sizeof *newtri);
    m->nverts = (int)nn;
    if (ncharts)
        *ncharts = nch > INT_MAX ? INT_MAX : (int)nch;
    rc = 0;
    goto done;

nomem:
    rc = glint_err_set(err, GLINT_ENOMEM, "out of memory parameterizing %zu triangles", nt);
done:
    free(canon);
    free(lab);
    free(lab2);
    free(fn);
    free(t2);
    free(nbo);
    free(nbs);
    free(chart);
    free(rej);
    free(ctri);
    free(cstart);
    free(caxis);
    free(order);
    free(edges);
    free(x.stamp);
    free(x.big);
    uvg_grid_free(&x.grid);
    free(last);
    free(newid);
    free(orig);
    free(newtri);
    free(vstart);
    free(ps);
    free(items);
    free(shx);
    free(shy);
    free(npos);
    free(nnrm);
    free(nuv);
    return rc;
}
