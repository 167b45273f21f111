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

/* The parameterization's working state, from the labels to the packed
 * charts: each step below fills some of it and reads what earlier steps
 * left.  uvg_work_free releases whatever is allocated. */
typedef struct uvg_work {
    mesh *m;
    size_t nv, nt;
    double diag, mean_edge;
    uint32_t *canon;          /* per vertex: its welded representative */
    unsigned char *lab, *lab2; /* per triangle: axis label; the smoothing's next labels */
    double *fn;               /* 3 per triangle: unit normal */
    double *t2;               /* 6 per triangle: projection onto its label's plane */
    uint32_t *nbo, *nbs;      /* edge neighbours of t: nbs[nbo[t] .. nbo[t + 1]) */
    int32_t *chart;           /* per triangle: its chart, -1 while it has none */
    uint32_t *rej;            /* per triangle: the last chart that refused it */
    uint32_t *ctri, *cstart;  /* chart c's triangles: ctri[cstart[c] .. cstart[c + 1]) */
    unsigned char *caxis;     /* per chart: its axis */
    size_t nch;
    uvg_seed *order;          /* seeds, best aligned with their axis first */
    uvg_ctx x;
    uint32_t *last, *newid;   /* per vertex, while splitting at chart borders */
    uint32_t *orig, *newtri, *vstart; /* split vertices: source vertex, triangles,
                                         chart c's vertices vstart[c] .. vstart[c + 1] */
    size_t nn;                /* vertices after splitting */
    double *ps;               /* 2 per split vertex: position in its laid-out chart */
    uvg_item *items;          /* per chart: extent, then placement */
    double *shx, *shy;        /* shelf packing's scratch */
    double side, gutter;      /* the packed square's side and the gap, chart units */
    float *npos, *nnrm, *nuv; /* the new vertex arrays */
} uvg_work;

static void uvg_work_free(uvg_work *w)
{
    free(w->canon);
    free(w->lab);
    free(w->lab2);
    free(w->fn);
    free(w->t2);
    free(w->nbo);
    free(w->nbs);
    free(w->chart);
    free(w->rej);
    free(w->ctri);
    free(w->cstart);
    free(w->caxis);
    free(w->order);
    free(w->x.stamp);
    free(w->x.big);
    uvg_grid_free(&w->x.grid);
    free(w->last);
    free(w->newid);
    free(w->orig);
    free(w->newtri);
    free(w->vstart);
    free(w->ps);
    free(w->items);
    free(w->shx);
    free(w->shy);
    free(w->npos);
    free(w->nnrm);
    free(w->nuv);
}

/* Every allocation failure of the parameterization reads the same. */
static int uvg_nomem(const uvg_work *w, glint_err *err)
{
    return glint_err_set(err, GLINT_ENOMEM, "out of memory parameterizing %zu triangles",
                         w->nt);
}

/* The per-triangle arrays the labelling and the chart growth need. */
static int uvg_work_alloc(uvg_work *w, glint_err *err)
{
    size_t nv = w->nv, nt = w->nt;
    w->canon = malloc(nv * sizeof *w->canon);
    w->lab = malloc(nt);
    w->lab2 = malloc(nt);
    w->fn = malloc(3 * nt * sizeof *w->fn);
    w->t2 = malloc(6 * nt * sizeof *w->t2);
    w->nbo = calloc(nt + 1, sizeof *w->nbo);
    w->chart = malloc(nt * sizeof *w->chart);
    w->rej = malloc(nt * sizeof *w->rej);
    w->ctri = malloc(nt * sizeof *w->ctri);
    w->cstart = malloc((nt + 1) * sizeof *w->cstart);
    w->caxis = malloc(nt);
    w->order = malloc(nt * sizeof *w->order);
    w->x.stamp = calloc(nt, sizeof *w->x.stamp);
    w->x.big = malloc(nt * sizeof *w->x.big);
    if (!w->canon || !w->lab || !w->lab2 || !w->fn || !w->t2 || !w->nbo || !w->chart ||
        !w->rej || !w->ctri || !w->cstart || !w->caxis || !w->order || !w->x.stamp ||
        !w->x.big)
        return uvg_nomem(w, err);
    return 0;
}

/* Step 1: each triangle's unit normal and the axis closest to it, and the
 * mean edge length (which sizes the chart grid's cells). */
static void uvg_label_triangles(uvg_work *w)
{
    const mesh *m = w->m;
    double mean_edge = 0.0;
    for (size_t t = 0; t < w->nt; t++) {
        v3 n;
        double l = mio_tri_cross_len(m->pos, m->tri + 3 * t, &n), best = -INFINITY;
        int a = 0;
        n = l > 0.0 ? v3_scale(n, 1.0 / l) : v3_make(0, 0, 0);
        v3_store(n, w->fn + 3 * t);
        for (int k = 0; k < 6; k++) {
            double d = uvg_axis_dot(k, w->fn + 3 * t);
            if (d > best) {
                best = d;
                a = k;
            }
        }
        w->lab[t] = (unsigned char)a;
        for (int k = 0; k < 3; k++) {
            const float *p = m->pos + 3 * (size_t)m->tri[3 * t + k];
            const float *q = m->pos + 3 * (size_t)m->tri[3 * t + (k + 1) % 3];
            mean_edge += v3_len(v3_sub(v3_loadf(p), v3_loadf(q)));
        }
    }
    w->mean_edge = mean_edge / (3.0 * (double)w->nt);
}

/* Triangle adjacency (CSR in nbo, nbs) from the sorted welded edges: the
 * triangles of an edge are paired, and chained along a non-manifold edge.
 * The first pass counts, the second fills. */
static int uvg_adjacency(uvg_work *w, glint_err *err)
{
    size_t nt = w->nt, ne = 3 * nt, total = 0;
    uint32_t *nbo = w->nbo;
    mio_pair *edges = NULL;
    int rc = mio_edges_sorted(w->m, w->canon, &edges, err);
    if (rc)
        return rc;
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
                    w->nbs[nbo[a]++] = b;
                    w->nbs[nbo[b]++] = a;
                }
            }
            i = j;
        }
        if (pass == 0) {
            for (size_t t = 0; t < nt; t++)
                nbo[t + 1] += nbo[t];
            total = nbo[nt];
            w->nbs = malloc((total ? total : 1) * sizeof *w->nbs);
            if (!w->nbs) {
                free(edges);
                return uvg_nomem(w, err);
            }
        } else {
            /* nbo[t] now holds the end of t's list: shift back */
            for (size_t t = nt; t > 0; t--)
                nbo[t] = nbo[t - 1];
            nbo[0] = 0;
        }
    }
    free(edges);
    return 0;
}

/* Label smoothing (Jacobi passes): a triangle takes the label most of its
 * neighbours hold, if at least two do and its normal is close enough to
 * that axis. */
static void uvg_smooth_labels(uvg_work *w)
{
    for (int pass = 0; pass < UVG_SMOOTH_PASSES; pass++) {
        size_t changed = 0;
        for (size_t t = 0; t < w->nt; t++) {
            int cnt[6] = {0, 0, 0, 0, 0, 0}, best = w->lab[t];
            for (uint32_t k = w->nbo[t]; k < w->nbo[t + 1]; k++)
                cnt[w->lab[w->nbs[k]]]++;
            for (int a = 0; a < 6; a++)
                if (cnt[a] > cnt[best])
                    best = a;
            w->lab2[t] = w->lab[t];
            if (best != w->lab[t] && cnt[best] >= 2 &&
                uvg_axis_dot(best, w->fn + 3 * t) >= UVG_MIN_COS) {
                w->lab2[t] = (unsigned char)best;
                changed++;
            }
        }
        memcpy(w->lab, w->lab2, w->nt);
        if (!changed)
            break;
    }
}

/* Before the growth: every triangle projected onto its label's plane,
 * without a chart, and the seeds in order of decreasing alignment. */
static void uvg_order_seeds(uvg_work *w)
{
    const mesh *m = w->m;
    for (size_t t = 0; t < w->nt; t++) {
        for (int k = 0; k < 3; k++)
            uvg_project(w->lab[t], m->pos + 3 * (size_t)m->tri[3 * t + k],
                        w->t2 + 6 * t + 2 * k, w->t2 + 6 * t + 2 * k + 1);
        w->order[t].key = uvg_axis_dot(w->lab[t], w->fn + 3 * t);
        w->order[t].t = (uint32_t)t;
        w->chart[t] = -1;
        w->rej[t] = UINT32_MAX;
    }
    qsort(w->order, w->nt, sizeof *w->order, uvg_seed_cmp);
}

/* Grow chart w->nch breadth-first from `seed` over neighbours of the same
 * label whose projection overlaps none of the chart's triangles; *n counts
 * the triangles placed in charts so far.  -1 on allocation failure. */
static int uvg_grow_chart(uvg_work *w, uint32_t seed, size_t *n)
{
    uvg_ctx *x = &w->x;
    uint32_t *ctri = w->ctri;
    size_t nch = w->nch;
    int axis = w->lab[seed];

    w->cstart[nch] = (uint32_t)*n;
    w->caxis[nch] = (unsigned char)axis;
    uvg_grid_reset(&x->grid);
    x->nbig = 0;
    x->c0 = *n;
    w->chart[seed] = (int32_t)nch;
    ctri[(*n)++] = seed;
    x->c1 = *n;
    if (uvg_insert(x, seed))
        return -1;
    for (size_t head = x->c0; head < *n; head++) {
        uint32_t s = ctri[head];
        for (uint32_t k = w->nbo[s]; k < w->nbo[s + 1]; k++) {
            uint32_t u = w->nbs[k];
            if (w->chart[u] >= 0 || w->lab[u] != axis || w->rej[u] == (uint32_t)nch)
                continue;
            x->c1 = *n;
            if (uvg_conflicts(x, u)) {
                w->rej[u] = (uint32_t)nch;
                continue;
            }
            w->chart[u] = (int32_t)nch;
            ctri[(*n)++] = u;
            x->c1 = *n;
            if (uvg_insert(x, u))
                return -1;
        }
    }
    return 0;
}

/* Step 2: charts grown from the seeds in order, each from the first seed
 * left without a chart.  What only the growth needs is released after. */
static int uvg_grow_charts(uvg_work *w, glint_err *err)
{
    uvg_ctx *x = &w->x;
    size_t n = 0;

    uvg_order_seeds(w);
    x->t2 = w->t2;
    x->nt = w->nt;
    x->ctri = w->ctri;
    x->tol = 1e-9 * w->diag;
    x->tiny_area = 1e-24 * w->diag * w->diag;
    if (uvg_grid_init(&x->grid, 1024))
        return uvg_nomem(w, err);
    x->grid.h = 2.0 * w->mean_edge > 1e-12 * w->diag ? 2.0 * w->mean_edge : w->diag;
    for (size_t o = 0; o < w->nt; o++) {
        uint32_t seed = w->order[o].t;
        if (w->chart[seed] >= 0)
            continue;
        if (uvg_grow_chart(w, seed, &n))
            return uvg_nomem(w, err);
        w->nch++;
    }
    w->cstart[w->nch] = (uint32_t)n;
    free(w->nbs);
    w->nbs = NULL;
    free(w->t2);
    w->t2 = NULL;
    uvg_grid_free(&x->grid);
    return 0;
}

/* Step 3: one vertex per (vertex, chart) pair, numbered chart by chart;
 * the triangles renumbered to them. */
static int uvg_split_vertices(uvg_work *w, glint_err *err)
{
    const mesh *m = w->m;
    size_t nt = w->nt, nn = 0;

    if (3 * nt > (size_t)INT_MAX / 3)
        return glint_err_set(err, GLINT_ERANGE, "too many triangles (%zu) to parameterize", nt);
    w->last = calloc(w->nv, sizeof *w->last);
    w->newid = malloc(w->nv * sizeof *w->newid);
    w->orig = malloc(3 * nt * sizeof *w->orig);
    w->newtri = malloc(3 * nt * sizeof *w->newtri);
    w->vstart = malloc((w->nch + 1) * sizeof *w->vstart);
    if (!w->last || !w->newid || !w->orig || !w->newtri || !w->vstart)
        return uvg_nomem(w, err);
    for (size_t c = 0; c < w->nch; c++) {
        w->vstart[c] = (uint32_t)nn;
        for (size_t i = w->cstart[c]; i < w->cstart[c + 1]; i++) {
            size_t t = w->ctri[i];
            for (int k = 0; k < 3; k++) {
                uint32_t v = m->tri[3 * t + k];
                if (w->last[v] != (uint32_t)c + 1) {
                    w->last[v] = (uint32_t)c + 1;
                    w->newid[v] = (uint32_t)nn;
                    w->orig[nn++] = v;
                }
                w->newtri[3 * t + k] = w->newid[v];
            }
        }
    }
    w->vstart[w->nch] = (uint32_t)nn;
    w->nn = nn;
    return 0;
}

/* The rotation (cosine, sine; among UVG_ROT_STEPS angles in [0, 90)
 * degrees) that gives the points ps[2 i0 .. 2 i1) the smallest bounding
 * rectangle; the first of equals (within a relative 1e-12) wins. */
static void uvg_best_rotation(const double *ps, size_t i0, size_t i1, double *bc, double *bs)
{
    double bestA = INFINITY;
    *bc = 1.0;
    *bs = 0.0;
    for (int r = 0; r < UVG_ROT_STEPS; r++) {
        double th = (3.14159265358979323846 / 2) * r / UVG_ROT_STEPS;
        double co = cos(th), si = sin(th), A, lx, ly, hx, hy;
        lx = ly = INFINITY;
        hx = hy = -INFINITY;
        for (size_t i = i0; i < i1; i++) {
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
            *bc = co;
            *bs = si;
        }
    }
}

/* Step 4 for chart c: its vertices projected onto its axis plane, rotated
 * to the smallest bounding rectangle, laid flat (width >= height) and
 * moved to the origin; its extent goes to items[c]. */
static void uvg_flatten_chart(uvg_work *w, size_t c)
{
    double *ps = w->ps, bc, bs, lx, ly, hx, hy;
    size_t i0 = w->vstart[c], i1 = w->vstart[c + 1];

    for (size_t i = i0; i < i1; i++)
        uvg_project(w->caxis[c], w->m->pos + 3 * (size_t)w->orig[i], ps + 2 * i, ps + 2 * i + 1);
    uvg_best_rotation(ps, i0, i1, &bc, &bs);
    lx = ly = INFINITY;
    hx = hy = -INFINITY;
    for (size_t i = i0; i < i1; i++) {
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
        for (size_t i = i0; i < i1; i++) {
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
    for (size_t i = i0; i < i1; i++) {
        ps[2 * i] -= lx;
        ps[2 * i + 1] -= ly;
    }
    w->items[c].w = hx - lx;
    w->items[c].h = hy - ly;
    w->items[c].c = (uint32_t)c;
}

/* Step 4: every chart flattened (uvg_flatten_chart). */
static int uvg_flatten_charts(uvg_work *w, glint_err *err)
{
    size_t nch = w->nch;
    w->ps = malloc(2 * w->nn * sizeof *w->ps);
    w->items = malloc((nch ? nch : 1) * sizeof *w->items);
    w->shx = malloc((nch ? nch : 1) * sizeof *w->shx);
    w->shy = malloc((nch ? nch : 1) * sizeof *w->shy);
    if (!w->ps || !w->items || !w->shx || !w->shy)
        return uvg_nomem(w, err);
    for (size_t c = 0; c < nch; c++)
        uvg_flatten_chart(w, c);
    return 0;
}

/* Step 5: the charts shelf-packed into a square.  The gutter is a fixed
 * fraction of the square's side, which depends on the gutter: three
 * rounds settle it, and a last packing uses the gutter of the side found. */
static void uvg_pack_charts(uvg_work *w)
{
    size_t nch = w->nch;
    double sumA = 0.0, side, g;
    for (size_t c = 0; c < nch; c++)
        sumA += w->items[c].w * w->items[c].h;
    qsort(w->items, nch, sizeof *w->items, uvg_item_cmp);
    side = sqrt(sumA / 0.7);
    if (!(side > 0.0))
        side = w->diag;
    for (int it = 0; it < 3; it++) {
        g = UVG_GUTTER * side;
        side = uvg_pack(w->items, nch, g, w->shx, w->shy);
    }
    g = UVG_GUTTER * side;
    w->side = uvg_pack(w->items, nch, g, w->shx, w->shy);
    w->gutter = g;
}

/* The new vertex arrays: uvs from the packing (one uniform scale maps the
 * square onto [0,1]^2), positions and normals copied from each split
 * vertex's source (zero normals if the mesh has none). */
static int uvg_vertex_arrays(uvg_work *w, glint_err *err)
{
    const mesh *m = w->m;
    size_t nn = w->nn;
    double side = w->side, g = w->gutter;

    w->npos = malloc(3 * nn * sizeof *w->npos);
    w->nnrm = malloc(3 * nn * sizeof *w->nnrm);
    w->nuv = malloc(2 * nn * sizeof *w->nuv);
    if (!w->npos || !w->nnrm || !w->nuv)
        return uvg_nomem(w, err);
    for (size_t k = 0; k < w->nch; k++) {
        size_t c = w->items[k].c;
        double ox = w->items[k].x + 0.5 * g, oy = w->items[k].y + 0.5 * g;
        for (size_t i = w->vstart[c]; i < w->vstart[c + 1]; i++) {
            double u = (w->ps[2 * i] + ox) / side, v = (w->ps[2 * i + 1] + oy) / side;
            w->nuv[2 * i] = (float)fmin(1.0, fmax(0.0, u));
            w->nuv[2 * i + 1] = (float)fmin(1.0, fmax(0.0, v));
        }
    }
    for (size_t i = 0; i < nn; i++) {
        memcpy(w->npos + 3 * i, m->pos + 3 * (size_t)w->orig[i], 3 * sizeof(float));
        if (m->nrm)
            memcpy(w->nnrm + 3 * i, m->nrm + 3 * (size_t)w->orig[i], 3 * sizeof(float));
        else
            w->nnrm[3 * i] = w->nnrm[3 * i + 1] = w->nnrm[3 * i + 2] = 0.0f;
    }
    return 0;
}

/* The mesh takes the new arrays (the work no longer owns them) and the
 * renumbered triangles. */
static void uvg_commit(uvg_work *w, int *ncharts)
{
    mesh *m = w->m;
    free(m->pos);
    free(m->nrm);
    free(m->uv);
    m->pos = w->npos;
    m->nrm = w->nnrm;
    m->uv = w->nuv;
    w->npos = w->nnrm = w->nuv = NULL;
    memcpy(m->tri, w->newtri, 3 * w->nt * sizeof *w->newtri);
    m->nverts = (int)w->nn;
    if (ncharts)
        *ncharts = w->nch > INT_MAX ? INT_MAX : (int)w->nch;
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
    uvg_work w;
    int rc;

    memset(&w, 0, sizeof w);
    w.m = m;
    w.nv = (size_t)m->nverts;
    w.nt = (size_t)m->ntris;
    w.diag = mio_bbox_diag(m->pos, w.nv);
    if (!(w.diag > 0.0) || !isfinite(w.diag))
        w.diag = 1.0;
    rc = uvg_work_alloc(&w, err);
    if (!rc)
        rc = mio_weld(m->pos, w.nv, w.canon, err);
    if (!rc) {
        uvg_label_triangles(&w);
        rc = uvg_adjacency(&w, err);
    }
    if (!rc) {
        uvg_smooth_labels(&w);
        rc = uvg_grow_charts(&w, err);
    }
    if (!rc)
        rc = uvg_split_vertices(&w, err);
    if (!rc)
        rc = uvg_flatten_charts(&w, err);
    if (!rc) {
        uvg_pack_charts(&w);
        rc = uvg_vertex_arrays(&w, err);
    }
    if (!rc)
        uvg_commit(&w, ncharts);
    uvg_work_free(&w);
    return rc;
}
