/* mesh_io.c: meshes from files (assimp), cleaning, smooth normals, glint's
 * automatic parameterization and unit-ball normalization (contract in
 * mesh.h).
 *
 * Loading runs in these steps; each reports what it decided in mesh_report:
 *  1. size checks: the file is stat'ed (missing -> GLINT_ENOTFOUND, larger
 *     than MESH_MAX_FILE_BYTES -> GLINT_ERANGE, empty -> GLINT_EFORMAT);
 *  2. a structural pre-scan of PLY and OFF data (the two formats whose
 *     headers declare element counts): a count over the limits is
 *     GLINT_ERANGE before assimp allocates for it, and data that ends before
 *     the declared elements is GLINT_EFORMAT (assimp 5.2 silently repeats
 *     the last face of a truncated ASCII PLY, zero-fills a truncated OFF and
 *     loops forever on a PLY header without end_header); OFF lines of 4096
 *     bytes or more are refused (assimp 5.2's OFF reader copies lines into a
 *     4096-byte stack buffer and writes one byte past it);
 *  3. assimp imports, in a child process (see "the import in a child
 *     process" below: assimp crashes, aborts or exhausts memory on some
 *     malformed files), with only its structure validation; every
 *     coordinate is checked to be finite (NaN or Inf -> GLINT_ENONFINITE
 *     naming the mesh and vertex), empty faces are refused, then assimp
 *     triangulates, joins identical vertices and sorts primitives by type;
 *  4. every node instance of every mesh is merged with its node transform
 *     (normals by the cofactor matrix, winding flipped under reflections);
 *     points and lines are dropped (counted);
 *  5. cleaning on positions welded bit-exactly (so uv or normal seams do not
 *     count as holes): triangles with two corners at the same position or an
 *     area below 5e-13 of the squared bounding-box diagonal are dropped
 *     (counted), unused vertices removed; boundary and non-manifold edges
 *     are counted (usable, reported);
 *  6. normals: the file's, renormalized, unless any is zero or non-finite;
 *     otherwise smooth area-weighted normals (mesh_compute_normals);
 *  7. centred and scaled into the unit ball (mesh_normalize);
 *  8. uvs: the file's when every vertex has finite ones spanning a non-zero
 *     area (moved uniformly into [0,1]^2 when they leave it); otherwise
 *     glint's parameterization (mesh_generate_uvs, method at its definition).
 *
 * No assimp logger is attached, and the import child's stdout goes to
 * /dev/null and its stderr into the error message: assimp prints nothing.
 * (One file for loading and parameterizing; the parameterization is
 * self-contained from "Automatic parameterization" on and could move to its
 * own mesh_uv.c.) */
#include "mesh.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "vec3.h"

/* Maximum depth of an assimp node hierarchy we walk. */
#define MIO_MAX_NODE_DEPTH 1024
/* Triangles with |cross| below this fraction of the squared bounding-box
 * diagonal are "zero-area" (twice the area threshold of the header). */
#define MIO_DEGENERATE_REL 1e-12
/* Longest list in a PLY element we accept in the pre-scan. */
#define MIO_PLY_MAX_LIST 65536
/* assimp 5.2's line buffer (ParsingUtils.h BufferSize). */
#define MIO_OFF_MAX_LINE 4096

/* ------------------------------------------------------------------------ */
/* Small helpers                                                             */
/* ------------------------------------------------------------------------ */

/* Arrays of a mesh; nrm / uv only when asked for.  *m zeroed on failure. */
static int mio_alloc(mesh *m, size_t nverts, size_t ntris, int with_nrm, int with_uv,
                     glint_err *err)
{
    memset(m, 0, sizeof *m);
    if (nverts > (size_t)INT_MAX / 3 || ntris > (size_t)INT_MAX / 3)
        return glint_err_set(err, GLINT_ERANGE,
                             "mesh with %zu vertices and %zu triangles is too large", nverts,
                             ntris);
    m->pos = malloc((nverts ? nverts : 1) * 3 * sizeof(float));
    m->nrm = with_nrm ? malloc((nverts ? nverts : 1) * 3 * sizeof(float)) : NULL;
    m->uv = with_uv ? malloc((nverts ? nverts : 1) * 2 * sizeof(float)) : NULL;
    m->tri = malloc((ntris ? ntris : 1) * 3 * sizeof(uint32_t));
    if (!m->pos || (with_nrm && !m->nrm) || (with_uv && !m->uv) || !m->tri) {
        mesh_free(m);
        return glint_err_set(err, GLINT_ENOMEM,
                             "out of memory for a mesh of %zu vertices and %zu triangles",
                             nverts, ntris);
    }
    m->nverts = (int)nverts;
    m->ntris = (int)ntris;
    return 0;
}

static double mio_tri_cross_len(const float *pos, const uint32_t *f, v3 *n)
{
    v3 a = v3_loadf(pos + 3 * (size_t)f[0]), b = v3_loadf(pos + 3 * (size_t)f[1]),
       c = v3_loadf(pos + 3 * (size_t)f[2]);
    v3 x = v3_cross(v3_sub(b, a), v3_sub(c, a));
    if (n)
        *n = x;
    return v3_len(x);
}

static double mio_bbox_diag(const float *pos, size_t n)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            double x = pos[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    if (!n)
        return 0.0;
    return sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                (hi[2] - lo[2]) * (hi[2] - lo[2]));
}

/* LSD radix sort of (key, val) pairs by key, 11 bits per pass, skipping
 * passes whose digit is the same for every key.  tmp has room for n pairs. */
typedef struct mio_pair {
    uint64_t key;
    uint32_t val;
} mio_pair;

static void mio_radix_sort(mio_pair *a, mio_pair *tmp, size_t n)
{
    size_t cnt[2048];
    mio_pair *src = a, *dst = tmp;
    for (int shift = 0; shift < 64; shift += 11) {
        size_t sum = 0;
        memset(cnt, 0, sizeof cnt);
        for (size_t i = 0; i < n; i++)
            cnt[(src[i].key >> shift) & 2047]++;
        if (!n || cnt[(src[0].key >> shift) & 2047] == n)
            continue;
        for (size_t d = 0; d < 2048; d++) {
            size_t c = cnt[d];
            cnt[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            dst[cnt[(src[i].key >> shift) & 2047]++] = src[i];
        {
            mio_pair *t = src;
            src = dst;
            dst = t;
        }
    }
    if (src != a)
        memcpy(a, src, n * sizeof *a);
}

/* Weld by exact position (-0 equals +0): canon[i] is the smallest index of
 * a vertex at the same position as vertex i.  Open addressing on the bits. */
static uint32_t mio_fbits(float x)
{
    uint32_t u;
    if (x == 0.0f)
        x = 0.0f;
    memcpy(&u, &x, sizeof u);
    return u;
}

static int mio_weld(const float *pos, size_t n, uint32_t *canon, glint_err *err)
{
    size_t cap = 16;
    uint32_t *slot;
    while (cap < 2 * n)
        cap <<= 1;
    slot = malloc(cap * sizeof *slot);
    if (!slot)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory welding %zu vertices", n);
    memset(slot, 0xff, cap * sizeof *slot);
    for (size_t i = 0; i < n; i++) {
        const float *p = pos + 3 * i;
        uint64_t h = mio_fbits(p[0]) * 0x9E3779B97F4A7C15ull;
        size_t s;
        h ^= (h >> 29) + mio_fbits(p[1]) * 0xBF58476D1CE4E5B9ull;
        h ^= (h >> 31) + mio_fbits(p[2]) * 0x94D049BB133111EBull;
        h ^= h >> 32;
        s = (size_t)h & (cap - 1);
        for (;;) {
            uint32_t j = slot[s];
            if (j == UINT32_MAX) {
                slot[s] = (uint32_t)i;
                canon[i] = (uint32_t)i;
                break;
            }
            if (pos[3 * (size_t)j] == p[0] && pos[3 * (size_t)j + 1] == p[1] &&
                pos[3 * (size_t)j + 2] == p[2]) {
                canon[i] = j;
                break;
            }
            s = (s + 1) & (cap - 1);
        }
    }
    free(slot);
    return 0;
}

/* The 3 ntris edges keyed by their welded end points (smaller first),
 * sorted; val = 3 t + corner.  OUT: *edges (malloc'ed, 3 ntris pairs). */
static int mio_edges_sorted(const mesh *m, const uint32_t *canon, mio_pair **edges,
                            glint_err *err)
{
    size_t ne = 3 * (size_t)m->ntris;
    mio_pair *e = malloc((ne ? ne : 1) * sizeof *e), *tmp = malloc((ne ? ne : 1) * sizeof *tmp);
    *edges = NULL;
    if (!e || !tmp) {
        free(e);
        free(tmp);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu edges", ne);
    }
    for (size_t t = 0; t < (size_t)m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            uint64_t a = canon[m->tri[3 * t + k]], b = canon[m->tri[3 * t + (k + 1) % 3]];
            e[3 * t + k].key = a < b ? (a << 32) | b : (b << 32) | a;
            e[3 * t + k].val = (uint32_t)(3 * t + k);
        }
    mio_radix_sort(e, tmp, ne);
    free(tmp);
    *edges = e;
    return 0;
}

/* Boundary (one triangle) and non-manifold (more than two) edges. */
static void mio_edge_stats(const mio_pair *e, size_t ne, int *boundary, int *nonmanifold)
{
    long long nb = 0, nn = 0;
    for (size_t i = 0; i < ne;) {
        size_t j = i + 1;
        while (j < ne && e[j].key == e[i].key)
            j++;
        if (j - i == 1)
            nb++;
        else if (j - i > 2)
            nn++;
        i = j;
    }
    *boundary = nb > INT_MAX ? INT_MAX : (int)nb;
    *nonmanifold = nn > INT_MAX ? INT_MAX : (int)nn;
}

/* ------------------------------------------------------------------------ */
/* Normalization and normals                                                 */
/* ------------------------------------------------------------------------ */

void mesh_normalize(mesh *m, double *scale, double center[3])
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double c[3] = {0, 0, 0}, r2 = 0.0, s = 1.0;
    size_t n;

    if (scale)
        *scale = 1.0;
    if (center)
        center[0] = center[1] = center[2] = 0.0;
    if (!m || !m->pos || m->nverts < 1)
        return;
    n = (size_t)m->nverts;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            double x = m->pos[3 * i + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    for (int k = 0; k < 3; k++)
        c[k] = 0.5 * (lo[k] + hi[k]);
    if (!isfinite(c[0]) || !isfinite(c[1]) || !isfinite(c[2]))
        return; /* non-finite input: leave it for mesh_validate to report */
    for (size_t i = 0; i < n; i++) {
        double d2 = 0.0;
        for (int k = 0; k < 3; k++) {
            double d = m->pos[3 * i + k] - c[k];
            d2 += d * d;
        }
        r2 = d2 > r2 ? d2 : r2;
    }
    if (r2 > 0.0 && isfinite(r2))
        s = 1.0 / sqrt(r2);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            m->pos[3 * i + k] = (float)((m->pos[3 * i + k] - c[k]) * s);
    /* Rounding to float can leave a vertex a few ulps outside: shrink by the
     * excess (at most a couple of passes). */
    for (int pass = 0; pass < 4; pass++) {
        double mx = 0.0;
        for (size_t i = 0; i < n; i++) {
            v3 p = v3_loadf(m->pos + 3 * i);
            double l = v3_dot(p, p);
            mx = l > mx ? l : mx;
        }
        if (mx <= 1.0)
            break;
        mx = (1.0 - 2.0 * FLT_EPSILON) / sqrt(mx);
        for (size_t i = 0; i < 3 * n; i++)
            m->pos[i] = (float)(m->pos[i] * mx);
        s *= mx;
    }
    if (scale)
        *scale = s;
    if (center)
        for (int k = 0; k < 3; k++)
            center[k] = c[k];
}

/* Smooth normals: every triangle adds its cross product (twice its area
 * times its unit normal) to each of its corners' welded position, so that
 * vertices split for uv or other seams get the same normal.  A position
 * whose sum vanishes (opposite faces cancelling, or only degenerate
 * triangles) takes the normal of its largest incident triangle; a vertex
 * in no non-degenerate triangle points away from the bounding-box centre
 * (or +z at the centre). */
int mesh_compute_normals(mesh *m, glint_err *err)
{
    uint32_t *canon = NULL;
    double *acc = NULL, *big = NULL, *bigw = NULL;
    size_t nv, nt;
    int rc;

    if (!m || !m->pos || !m->tri || m->nverts < 1 || m->ntris < 0)
        return glint_err_set(err, GLINT_EINVAL, "mesh_compute_normals: empty or NULL mesh");
    nv = (size_t)m->nverts;
    nt = (size_t)m->ntris;
    for (size_t i = 0; i < 3 * nt; i++)
        if (m->tri[i] >= (uint32_t)m->nverts)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "mesh triangle %zu: vertex index %u out of range (%zu vertices)",
                                 i / 3, m->tri[i], nv);
    if (!m->nrm) {
        m->nrm = malloc(nv * 3 * sizeof(float));
        if (!m->nrm)
            return glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu normals", nv);
    }
    canon = malloc(nv * sizeof *canon);
    acc = calloc(3 * nv, sizeof *acc);
    big = calloc(3 * nv, sizeof *big);
    bigw = calloc(nv, sizeof *bigw);
    if (!canon || !acc || !big || !bigw) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory computing normals of %zu vertices",
                           nv);
        goto done;
    }
    rc = mio_weld(m->pos, nv, canon, err);
    if (rc)
        goto done;
    for (size_t t = 0; t < nt; t++) {
        v3 n;
        double l = mio_tri_cross_len(m->pos, m->tri + 3 * t, &n);
        if (!(l > 0.0) || !isfinite(l))
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t c = canon[m->tri[3 * t + k]];
            acc[3 * c] += n.x;
            acc[3 * c + 1] += n.y;
            acc[3 * c + 2] += n.z;
            if (l > bigw[c]) {
                bigw[c] = l;
                big[3 * c] = n.x / l;
                big[3 * c + 1] = n.y / l;
                big[3 * c + 2] = n.z / l;
            }
        }
    }
    {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        v3 mid;
        for (size_t i = 0; i < nv; i++)
            for (int k = 0; k < 3; k++) {
                double x = m->pos[3 * i + k];
                lo[k] = x < lo[k] ? x : lo[k];
                hi[k] = x > hi[k] ? x : hi[k];
            }
        mid = v3_make(0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]));
        for (size_t i = 0; i < nv; i++) {
            uint32_t c = canon[i];
            v3 n = v3_load(acc + 3 * (size_t)c);
            double l = v3_len(n);
            if (!(l > 1e-30) || !isfinite(l)) {
                n = v3_load(big + 3 * (size_t)c); /* unit, or zero if none */
                l = v3_len(n);
            }
            if (!(l > 1e-30) || !isfinite(l)) {
                n = v3_sub(v3_loadf(m->pos + 3 * i), mid);
                l = v3_len(n);
                if (!(l > 0.0) || !isfinite(l)) {
                    n = v3_make(0, 0, 1);
                    l = 1.0;
                }
            }
            v3_storef(v3_scale(n, 1.0 / l), m->nrm + 3 * i);
        }
    }
    rc = 0;
done:
    free(canon);
    free(acc);
    free(big);
    free(bigw);
    return rc;
}

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
static int mio_uv_generate(mesh *m, int *ncharts, glint_err *err)
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

/* Arguments every public mesh operation requires. */
static int mio_check_mesh(const mesh *m, const char *who, glint_err *err)
{
    if (!m)
        return glint_err_set(err, GLINT_EINVAL, "%s: mesh is NULL", who);
    if (m->nverts < 1 || m->ntris < 1 || !m->pos || !m->tri)
        return glint_err_set(err, GLINT_EINVAL, "%s: empty mesh (%d vertices, %d triangles)",
                             who, m->nverts, m->ntris);
    if (m->nverts > INT_MAX / 3 || m->ntris > INT_MAX / 3)
        return glint_err_set(err, GLINT_ERANGE, "%s: mesh too large", who);
    for (size_t i = 0; i < 3 * (size_t)m->ntris; i++)
        if (m->tri[i] >= (uint32_t)m->nverts)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s: triangle %zu: vertex index %u out of range (%d vertices)",
                                 who, i / 3, m->tri[i], m->nverts);
    for (size_t i = 0; i < 3 * (size_t)m->nverts; i++)
        if (!isfinite(m->pos[i]))
            return glint_err_set(err, GLINT_ENONFINITE, "%s: vertex %zu: position not finite",
                                 who, i / 3);
    return 0;
}

int mesh_generate_uvs(mesh *m, glint_err *err)
{
    int rc = mio_check_mesh(m, "mesh_generate_uvs", err);
    if (rc)
        return rc;
    return mio_uv_generate(m, NULL, err);
}

/* ------------------------------------------------------------------------ */
/* Pre-scan of PLY and OFF data                                              */
/* ------------------------------------------------------------------------ */

static int mio_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

/* A decimal count (digits only, optional '+'); saturates at ULLONG_MAX.
 * Returns 0 if the token is not a count. */
static int mio_count(const char *s, size_t n, unsigned long long *out)
{
    unsigned long long v = 0;
    size_t i = 0;
    if (n && s[0] == '+')
        i = 1;
    if (i >= n)
        return 0;
    for (; i < n; i++) {
        unsigned d;
        if (s[i] < '0' || s[i] > '9')
            return 0;
        d = (unsigned)(s[i] - '0');
        v = v > (ULLONG_MAX - d) / 10 ? ULLONG_MAX : 10 * v + d;
    }
    *out = v;
    return 1;
}

/* Next whitespace-separated token in [*p, end) (OUT: start, length);
 * 0 at the end. */
static int mio_token(const char **p, const char *end, const char **tok, size_t *len)
{
    const char *s = *p;
    while (s < end && mio_space(*s))
        s++;
    if (s >= end) {
        *p = s;
        return 0;
    }
    *tok = s;
    while (s < end && !mio_space(*s))
        s++;
    *len = (size_t)(s - *tok);
    *p = s;
    return 1;
}

static int mio_tok_is(const char *tok, size_t len, const char *word)
{
    return strlen(word) == len && memcmp(tok, word, len) == 0;
}

#define MIO_PLY_MAX_ELEMS 64
#define MIO_PLY_MAX_PROPS 64

typedef struct mio_ply_prop {
    int list;
    int size;       /* scalar or list item size in bytes */
    int csize;      /* list count size */
    int csigned;    /* list count is a signed type */
} mio_ply_prop;

typedef struct mio_ply_elem {
    char name[32];
    unsigned long long count;
    int nprops;
    mio_ply_prop props[MIO_PLY_MAX_PROPS];
} mio_ply_elem;

/* Size of a PLY scalar type name (0 if unknown), and whether it is signed. */
static int mio_ply_type(const char *tok, size_t len, int *is_signed)
{
    static const struct { const char *name; int size, sgn; } types[] = {
        {"char", 1, 1},   {"int8", 1, 1},    {"uchar", 1, 0},   {"uint8", 1, 0},
        {"short", 2, 1},  {"int16", 2, 1},   {"ushort", 2, 0},  {"uint16", 2, 0},
        {"int", 4, 1},    {"int32", 4, 1},   {"uint", 4, 0},    {"uint32", 4, 0},
        {"float", 4, 1},  {"float32", 4, 1}, {"double", 8, 1},  {"float64", 8, 1}};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
        if (mio_tok_is(tok, len, types[i].name)) {
            if (is_signed)
                *is_signed = types[i].sgn;
            return types[i].size;
        }
    return 0;
}

static int mio_ply_truncated(const char *what, const mio_ply_elem *e, unsigned long long i,
                             glint_err *err)
{
    return glint_err_set(err, GLINT_EFORMAT,
                         "%s: PLY data ends inside element \"%s\" %llu of %llu (truncated file)",
                         what, e->name, i, e->count);
}

/* PLY: header counts against the limits, then a walk over the data that
 * checks every declared element is present.  Headers this scan does not
 * understand are left to assimp. */
static int mio_prescan_ply(const char *buf, size_t len, const char *what, glint_err *err)
{
    mio_ply_elem *el = NULL;
    int nel = 0, fmt = -1, understood = 1, rc = 0; /* fmt: 0 ascii, 1 LE, 2 BE */
    const char *p = buf, *end = buf + len, *data = NULL;

    el = calloc(MIO_PLY_MAX_ELEMS, sizeof *el);
    if (!el)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory scanning %s", what);
    /* header: one declaration per line, up to end_header */
    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p)), *q = p, *tok;
        size_t tl;
        if (!eol)
            eol = end;
        if (mio_token(&q, eol, &tok, &tl)) {
            if (mio_tok_is(tok, tl, "end_header")) {
                data = eol < end ? eol + 1 : end;
                break;
            } else if (mio_tok_is(tok, tl, "format")) {
                if (mio_token(&q, eol, &tok, &tl)) {
                    if (mio_tok_is(tok, tl, "ascii"))
                        fmt = 0;
                    else if (mio_tok_is(tok, tl, "binary_little_endian"))
                        fmt = 1;
                    else if (mio_tok_is(tok, tl, "binary_big_endian"))
                        fmt = 2;
                }
            } else if (mio_tok_is(tok, tl, "element")) {
                mio_ply_elem *e;
                const char *name;
                size_t nl;
                if (nel == MIO_PLY_MAX_ELEMS) {
                    rc = glint_err_set(err, GLINT_EFORMAT,
                                       "%s: PLY header declares more than %d elements", what,
                                       MIO_PLY_MAX_ELEMS);
                    goto done;
                }
                e = &el[nel++];
                if (!mio_token(&q, eol, &name, &nl) || !mio_token(&q, eol, &tok, &tl) ||
                    !mio_count(tok, tl, &e->count)) {
                    understood = 0; /* malformed: assimp will say so */
                    break;
                }
                snprintf(e->name, sizeof e->name, "%.*s", (int)(nl < 31 ? nl : 31), name);
                if (e->count > (unsigned long long)MESH_MAX_VERTS ||
                    (strcmp(e->name, "face") == 0 && e->count > (unsigned long long)MESH_MAX_TRIS)) {
                    rc = glint_err_set(err, GLINT_ERANGE,
                                       "%s: PLY header declares %llu \"%s\" elements, more than "
                                       "the limit of %d", what, e->count, e->name,
                                       strcmp(e->name, "face") == 0 ? MESH_MAX_TRIS
                                                                    : MESH_MAX_VERTS);
                    goto done;
                }
            } else if (mio_tok_is(tok, tl, "property")) {
                mio_ply_elem *e = nel ? &el[nel - 1] : NULL;
                mio_ply_prop *pr;
                int sgn = 0;
                if (!e || e->nprops == MIO_PLY_MAX_PROPS || !mio_token(&q, eol, &tok, &tl)) {
                    understood = 0;
                    break;
                }
                pr = &e->props[e->nprops++];
                if (mio_tok_is(tok, tl, "list")) {
                    pr->list = 1;
                    if (!mio_token(&q, eol, &tok, &tl) ||
                        !(pr->csize = mio_ply_type(tok, tl, &sgn))) {
                        understood = 0;
                        break;
                    }
                    pr->csigned = sgn;
                    if (!mio_token(&q, eol, &tok, &tl) || !(pr->size = mio_ply_type(tok, tl, NULL))) {
                        understood = 0;
                        break;
                    }
                } else if (!(pr->size = mio_ply_type(tok, tl, NULL))) {
                    understood = 0;
                    break;
                }
            }
            /* comment, obj_info and anything else: ignored */
        }
        p = eol < end ? eol + 1 : end;
    }
    if (!data) { /* the header loop may have stopped early: look again */
        for (const char *q = buf; q < end;) {
            const char *eol = memchr(q, '\n', (size_t)(end - q)), *r = q, *tok;
            size_t tl;
            if (!eol)
                eol = end;
            if (mio_token(&r, eol, &tok, &tl) && mio_tok_is(tok, tl, "end_header")) {
                data = eol < end ? eol + 1 : end;
                break;
            }
            q = eol < end ? eol + 1 : end;
        }
    }
    if (!data) {
        /* assimp 5.2 loops forever on a PLY header without end_header */
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: PLY header has no end_header line (truncated file)", what);
        goto done;
    }
    if (!understood || fmt < 0)
        goto done; /* malformed declarations: assimp reports them */

    /* data */
    p = data;
    for (int k = 0; k < nel; k++) {
        const mio_ply_elem *e = &el[k];
        int all_scalar = 1;
        size_t rec = 0;
        for (int j = 0; j < e->nprops; j++) {
            all_scalar &= !e->props[j].list;
            rec += (size_t)e->props[j].size;
        }
        if (fmt != 0 && all_scalar) {
            size_t left = (size_t)(end - p);
            if (rec && left / rec < e->count) {
                rc = mio_ply_truncated(what, e, left / rec, err);
                goto done;
            }
            p += rec * (size_t)e->count;
            continue;
        }
        for (unsigned long long i = 0; i < e->count; i++)
            for (int j = 0; j < e->nprops; j++) {
                const mio_ply_prop *pr = &e->props[j];
                if (fmt == 0) {
                    const char *tok;
                    size_t tl;
                    unsigned long long n;
                    if (!mio_token(&p, end, &tok, &tl)) {
                        rc = mio_ply_truncated(what, e, i, err);
                        goto done;
                    }
                    if (!pr->list)
                        continue;
                    if (!mio_count(tok, tl, &n) || n > MIO_PLY_MAX_LIST) {
                        rc = glint_err_set(err, GLINT_EFORMAT,
                                           "%s: PLY element \"%s\" %llu: list length \"%.*s\" is "
                                           "not a count in 0..%d", what, e->name, i,
                                           (int)(tl < 32 ? tl : 32), tok, MIO_PLY_MAX_LIST);
                        goto done;
                    }
                    for (unsigned long long t = 0; t < n; t++)
                        if (!mio_token(&p, end, &tok, &tl)) {
                            rc = mio_ply_truncated(what, e, i, err);
                            goto done;
                        }
                } else {
                    unsigned char b[8] = {0};
                    long long n = 0;
                    if (!pr->list) {
                        if ((size_t)(end - p) < (size_t)pr->size) {
                            rc = mio_ply_truncated(what, e, i, err);
                            goto done;
                        }
                        p += pr->size;
                        continue;
                    }
                    if ((size_t)(end - p) < (size_t)pr->csize) {
                        rc = mio_ply_truncated(what, e, i, err);
                        goto done;
                    }
                    for (int c = 0; c < pr->csize; c++)
                        b[c] = (unsigned char)p[fmt == 1 ? c : pr->csize - 1 - c];
                    p += pr->csize;
                    {
                        unsigned long long u = 0;
                        for (int c = pr->csize - 1; c >= 0; c--)
                            u = (u << 8) | b[c];
                        if (pr->csigned && pr->csize < 8 && (u >> (8 * pr->csize - 1)) & 1)
                            n = -1; /* negative count */
                        else
                            n = u > (unsigned long long)LLONG_MAX ? -1 : (long long)u;
                    }
                    if (n < 0 || n > MIO_PLY_MAX_LIST) {
                        rc = glint_err_set(err, GLINT_EFORMAT,
                                           "%s: PLY element \"%s\" %llu: list length %lld "
                                           "outside 0..%d", what, e->name, i, n,
                                           MIO_PLY_MAX_LIST);
                        goto done;
                    }
                    if ((size_t)(end - p) / (size_t)pr->size < (size_t)n) {
                        rc = mio_ply_truncated(what, e, i, err);
                        goto done;
                    }
                    p += (size_t)n * (size_t)pr->size;
                }
            }
    }
done:
    free(el);
    return rc;
}

/* assimp's line ends (ParsingUtils.h IsLineEnd, without NUL). */
static int mio_line_end(char c)
{
    return c == '\r' || c == '\n' || c == '\f';
}

/* OFF: the counts against the limits, the declared vertex and face lines
 * present, no line that overflows assimp's buffer.  `named_off`: the file
 * is called .off (a headerless OFF is then recognized too). */
static int mio_prescan_off(const char *buf, size_t len, int named_off, const char *what,
                           glint_err *err)
{
    const char *p = buf, *end, *tok;
    size_t tl;
    int dim = 0;
    unsigned long long nv, nf, need, got = 0;

    /* assimp reads up to the first NUL */
    end = memchr(buf, '\0', len);
    if (!end)
        end = buf + len;
    /* first token, skipping comment lines */
    for (;;) {
        while (p < end && mio_space(*p))
            p++;
        if (p < end && *p == '#') {
            while (p < end && *p != '\n' && *p != '\r')
                p++;
            continue;
        }
        break;
    }
    {
        const char *q = p, *w;
        size_t wl;
        if (!mio_token(&q, end, &w, &wl))
            return 0;
        {
            const char *s = w, *e = w + wl;
            if (e - s >= 2 && s[0] == 'S' && s[1] == 'T')
                s += 2;
            if (s < e && *s == 'C')
                s++;
            if (s < e && *s == 'N')
                s++;
            if (s < e && *s == '4')
                s++;
            if (s < e && *s == 'n') {
                s++;
                dim = 1;
            }
            if (e - s == 3 && memcmp(s, "OFF", 3) == 0)
                p = q; /* header */
            else if (named_off && w[0] >= '0' && w[0] <= '9')
                dim = 0; /* headerless: counts come first */
            else
                return 0; /* not OFF */
        }
    }
    if (dim && !mio_token(&p, end, &tok, &tl))
        return 0;
    if (!mio_token(&p, end, &tok, &tl) || !mio_count(tok, tl, &nv) ||
        !mio_token(&p, end, &tok, &tl) || !mio_count(tok, tl, &nf))
        return 0; /* malformed: assimp will say so */
    if (nv > (unsigned long long)MESH_MAX_VERTS || nf > (unsigned long long)MESH_MAX_TRIS)
        return glint_err_set(err, GLINT_ERANGE,
                             "%s: OFF header declares %llu vertices and %llu faces, more than "
                             "the limits of %d and %d", what, nv, nf, MESH_MAX_VERTS,
                             MESH_MAX_TRIS);
    (void)mio_token(&p, end, &tok, &tl); /* edge count, unused */
    /* then lines, as assimp reads them: blank lines and comment lines
     * between the counts and the first vertex are skipped, later ones not */
    for (;;) {
        while (p < end && (mio_space(*p)))
            p++;
        if (p < end && *p == '#') {
            while (p < end && !mio_line_end(*p))
                p++;
            continue;
        }
        break;
    }
    need = nv + nf;
    while (p < end && got < need) {
        const char *s = p;
        while (p < end && !mio_line_end(*p))
            p++;
        if (p - s >= MIO_OFF_MAX_LINE)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s: OFF line %llu after the header is %zu bytes long (at most "
                                 "%d accepted)", what, got + 1, (size_t)(p - s),
                                 MIO_OFF_MAX_LINE - 1);
        got++;
        while (p < end && mio_line_end(*p))
            p++;
    }
    if (got < need)
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: OFF data ends after %llu of the %llu vertex and %llu face "
                             "lines its header declares (truncated file)", what, got, nv, nf);
    return 0;
}

/* Dispatch on content (PLY magic, OFF header) or name. */
static int mio_prescan(const char *buf, size_t len, const char *fmt, const char *what,
                       glint_err *err)
{
    if (len >= 4 && (memcmp(buf, "ply", 3) == 0 || memcmp(buf, "PLY", 3) == 0) &&
        mio_space(buf[3]))
        return mio_prescan_ply(buf, len, what, err);
    return mio_prescan_off(buf, len, strcmp(fmt, "off") == 0, what, err);
}

/* ------------------------------------------------------------------------ */
/* Import through assimp                                                     */
/* ------------------------------------------------------------------------ */

/* Row-major 3 x 4 affine transform in double precision. */
typedef struct mio_xf {
    double m[3][4];
} mio_xf;

static mio_xf mio_xf_mul(const mio_xf *a, const struct aiMatrix4x4 *b)
{
    const double B[3][4] = {{b->a1, b->a2, b->a3, b->a4},
                            {b->b1, b->b2, b->b3, b->b4},
                            {b->c1, b->c2, b->c3, b->c4}};
    mio_xf r;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) {
            double s = j == 3 ? a->m[i][3] : 0.0;
            for (int k = 0; k < 3; k++)
                s += a->m[i][k] * B[k][j];
            r.m[i][j] = s;
        }
    /* the bottom row of an assimp node transform is (0 0 0 1) for affine
     * transforms; a projective one is treated as affine */
    return r;
}

/* What the walk over the node hierarchy collects. */
typedef struct mio_gather {
    const struct aiScene *sc;
    int fill;                 /* 0: count, 1: copy */
    long long nv, nt;         /* counted / copied so far */
    long long prims;          /* points, lines, polygons left out */
    int all_nrm, all_uv;      /* every instanced triangle mesh has them */
    mesh *out;
    const char *what;
} mio_gather;

static int mio_gather_mesh(mio_gather *g, const struct aiMesh *am, unsigned mi, const mio_xf *x,
                           glint_err *err)
{
    long long ntri = 0;
    double det, cof[3][3];
    const double (*M)[4] = x->m;
    uint32_t base;

    for (unsigned f = 0; f < am->mNumFaces; f++)
        if (am->mFaces[f].mNumIndices == 3)
            ntri++;
    if (!g->fill) {
        g->prims += (long long)am->mNumFaces - ntri;
        if (!ntri)
            return 0;
        g->nv += am->mNumVertices;
        g->nt += ntri;
        g->all_nrm &= am->mNormals != NULL;
        g->all_uv &= am->mTextureCoords[0] != NULL && am->mNumUVComponents[0] >= 2;
        if (g->nt > MESH_MAX_TRIS)
            return glint_err_set(err, GLINT_ERANGE,
                                 "%s: more than %d triangles (the limit) after merging its meshes",
                                 g->what, MESH_MAX_TRIS);
        if (g->nv > MESH_MAX_VERTS)
            return glint_err_set(err, GLINT_ERANGE,
                                 "%s: more than %d vertices (the limit) after merging its meshes",
                                 g->what, MESH_MAX_VERTS);
        return 0;
    }
    if (!ntri)
        return 0;
    /* cofactor matrix: transforms normals (up to the sign of det) */
    cof[0][0] = M[1][1] * M[2][2] - M[1][2] * M[2][1];
    cof[0][1] = M[1][2] * M[2][0] - M[1][0] * M[2][2];
    cof[0][2] = M[1][0] * M[2][1] - M[1][1] * M[2][0];
    cof[1][0] = M[0][2] * M[2][1] - M[0][1] * M[2][2];
    cof[1][1] = M[0][0] * M[2][2] - M[0][2] * M[2][0];
    cof[1][2] = M[0][1] * M[2][0] - M[0][0] * M[2][1];
    cof[2][0] = M[0][1] * M[1][2] - M[0][2] * M[1][1];
    cof[2][1] = M[0][2] * M[1][0] - M[0][0] * M[1][2];
    cof[2][2] = M[0][0] * M[1][1] - M[0][1] * M[1][0];
    det = M[0][0] * cof[0][0] + M[0][1] * cof[0][1] + M[0][2] * cof[0][2];
    base = (uint32_t)g->nv;
    for (unsigned v = 0; v < am->mNumVertices; v++) {
        const struct aiVector3D *p = &am->mVertices[v];
        float *o = g->out->pos + 3 * (size_t)(g->nv + v);
        for (int i = 0; i < 3; i++) {
            double y = M[i][0] * p->x + M[i][1] * p->y + M[i][2] * p->z + M[i][3];
            o[i] = (float)y;
            if (!isfinite(o[i]))
                return glint_err_set(err, GLINT_ENONFINITE,
                                     "%s: mesh %u vertex %u: coordinate not finite after its "
                                     "node transform (%g)", g->what, mi, v, y);
        }
        if (g->out->nrm) {
            const struct aiVector3D *n = &am->mNormals[v];
            float *on = g->out->nrm + 3 * (size_t)(g->nv + v);
            for (int i = 0; i < 3; i++) {
                double y = cof[i][0] * n->x + cof[i][1] * n->y + cof[i][2] * n->z;
                on[i] = (float)(det < 0 ? -y : y);
            }
        }
        if (g->out->uv) {
            const struct aiVector3D *t = &am->mTextureCoords[0][v];
            g->out->uv[2 * (size_t)(g->nv + v)] = t->x;
            g->out->uv[2 * (size_t)(g->nv + v) + 1] = t->y;
        }
    }
    for (unsigned f = 0; f < am->mNumFaces; f++) {
        const struct aiFace *fc = &am->mFaces[f];
        uint32_t *o;
        if (fc->mNumIndices != 3)
            continue;
        for (int k = 0; k < 3; k++)
            if (fc->mIndices[k] >= am->mNumVertices)
                return glint_err_set(err, GLINT_EFORMAT,
                                     "%s: mesh %u face %u: vertex index %u out of range (%u "
                                     "vertices)", g->what, mi, f, fc->mIndices[k],
                                     am->mNumVertices);
        o = g->out->tri + 3 * (size_t)g->nt;
        o[0] = base + fc->mIndices[0];
        o[1] = base + fc->mIndices[det < 0 ? 2 : 1];
        o[2] = base + fc->mIndices[det < 0 ? 1 : 2];
        g->nt++;
    }
    g->nv += am->mNumVertices;
    return 0;
}

static int mio_gather_node(mio_gather *g, const struct aiNode *nd, const mio_xf *parent,
                           int depth, glint_err *err)
{
    mio_xf x;
    int rc;
    if (depth > MIO_MAX_NODE_DEPTH)
        return glint_err_set(err, GLINT_EFORMAT, "%s: node hierarchy deeper than %d", g->what,
                             MIO_MAX_NODE_DEPTH);
    x = mio_xf_mul(parent, &nd->mTransformation);
    for (unsigned i = 0; i < nd->mNumMeshes; i++) {
        unsigned mi = nd->mMeshes[i];
        if (mi >= g->sc->mNumMeshes || !g->sc->mMeshes[mi])
            return glint_err_set(err, GLINT_EFORMAT, "%s: node refers to mesh %u of %u", g->what,
                                 mi, g->sc->mNumMeshes);
        rc = mio_gather_mesh(g, g->sc->mMeshes[mi], mi, &x, err);
        if (rc)
            return rc;
    }
    for (unsigned i = 0; i < nd->mNumChildren; i++) {
        if (!nd->mChildren[i])
            continue;
        rc = mio_gather_node(g, nd->mChildren[i], &x, depth + 1, err);
        if (rc)
            return rc;
    }
    return 0;
}

/* One pass over the scene: every node instance, or every mesh once with
 * the identity when no node refers to a triangle mesh. */
static int mio_gather_pass(mio_gather *g, int by_nodes, glint_err *err)
{
    static const mio_xf id = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};
    if (by_nodes)
        return mio_gather_node(g, g->sc->mRootNode, &id, 0, err);
    for (unsigned i = 0; i < g->sc->mNumMeshes; i++) {
        int rc;
        if (!g->sc->mMeshes[i])
            continue;
        rc = mio_gather_mesh(g, g->sc->mMeshes[i], i, &id, err);
        if (rc)
            return rc;
    }
    return 0;
}

/* Import (path, or data + hint) into the raw merged triangle soup *raw
 * (nrm / uv arrays only when every mesh has them), in this process. */
static int mio_import_direct(const char *path, const void *data, size_t len, const char *hint,
                      const char *what, mesh *raw, long long *prims, glint_err *err)
{
    const struct aiScene *sc;
    mio_gather g;
    int rc, by_nodes;

    memset(raw, 0, sizeof *raw);
    if (path)
        sc = aiImportFile(path, aiProcess_ValidateDataStructure);
    else
        sc = aiImportFileFromMemory(data, (unsigned)len, aiProcess_ValidateDataStructure, hint);
    if (!sc) {
        const char *msg = aiGetErrorString();
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: assimp could not read it: %s", what,
                           msg && *msg ? msg : "(no message)");
        return rc;
    }
    /* Before assimp's own processing: every coordinate finite (its vertex
     * joining sorts them), no empty face (what assimp's readers leave for
     * faces missing from a truncated file), and primitive-type flags that
     * match the faces (its triangulation asserts -- aborts the process --
     * when a mesh flagged as having polygons has none). */
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        struct aiMesh *am = sc->mMeshes[i];
        unsigned types = 0;
        if (!am)
            continue;
        for (unsigned f = 0; f < am->mNumFaces; f++) {
            unsigned n = am->mFaces[f].mNumIndices;
            if (n == 0 || !am->mFaces[f].mIndices) {
                rc = glint_err_set(err, GLINT_EFORMAT,
                                   "%s: mesh %u face %u has no vertex indices (truncated or "
                                   "corrupt data)", what, i, f);
                aiReleaseImport(sc);
                return rc;
            }
            types |= n == 1 ? aiPrimitiveType_POINT
                            : n == 2 ? aiPrimitiveType_LINE
                                     : n == 3 ? aiPrimitiveType_TRIANGLE : aiPrimitiveType_POLYGON;
        }
        am->mPrimitiveTypes = types;
        for (unsigned v = 0; am->mVertices && v < am->mNumVertices; v++) {
            const struct aiVector3D *p = &am->mVertices[v];
            if (!isfinite(p->x) || !isfinite(p->y) || !isfinite(p->z)) {
                rc = glint_err_set(err, GLINT_ENONFINITE,
                                   "%s: mesh %u vertex %u has a non-finite coordinate (%g, %g, %g)",
                                   what, i, v, p->x, p->y, p->z);
                aiReleaseImport(sc);
                return rc;
            }
        }
    }
    sc = aiApplyPostProcessing(sc, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                       aiProcess_SortByPType);
    if (!sc) /* assimp released the scene */
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: assimp post-processing (triangulation, vertex joining) failed",
                             what);

    memset(&g, 0, sizeof g);
    g.sc = sc;
    g.what = what;
    g.all_nrm = g.all_uv = 1;
    by_nodes = sc->mRootNode != NULL;
    rc = mio_gather_pass(&g, by_nodes, err);
    if (!rc && g.nt == 0 && by_nodes) { /* no node instances a triangle mesh */
        memset(&g, 0, sizeof g);
        g.sc = sc;
        g.what = what;
        g.all_nrm = g.all_uv = 1;
        by_nodes = 0;
        rc = mio_gather_pass(&g, 0, err);
    }
    if (rc)
        goto done;
    *prims = g.prims;
    if (g.nt == 0) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: no triangles (%u meshes, %lld other "
                           "primitives)", what, sc->mNumMeshes, g.prims);
        goto done;
    }
    rc = mio_alloc(raw, (size_t)g.nv, (size_t)g.nt, g.all_nrm, g.all_uv, err);
    if (rc)
        goto done;
    g.fill = 1;
    g.out = raw;
    g.nv = g.nt = 0;
    rc = mio_gather_pass(&g, by_nodes, err);
    if (!rc && (g.nv != raw->nverts || g.nt != raw->ntris))
        rc = glint_err_set(err, GLINT_EINTERNAL, "%s: mesh merge counted %d/%d, copied %lld/%lld",
                           what, raw->nverts, raw->ntris, g.nv, g.nt);
done:
    aiReleaseImport(sc);
    if (rc)
        mesh_free(raw);
    return rc;
}

/* ---- the import in a child process ---------------------------------------
 *
 * assimp 5.2 crashes (SIGSEGV in its COLLADA reader on a mangled attribute
 * name), aborts (ai_assert is compiled in and calls abort()) or loops on
 * some malformed files that no pre-scan can rule out.  A daemon must
 * survive every upload, so the import runs in a forked child: the child
 * imports, merges and checks (mio_import_direct) and writes the raw soup
 * to a pipe; the parent reads it, with a time limit, and maps the child's
 * death by a signal to an error.  The child has a memory limit (its
 * current address space plus 2 GiB plus 32 bytes per byte of input; not
 * in sanitizer builds, whose shadow memory needs the address space),
 * writes nothing to stdout, and its stderr (assimp's assertion text, a
 * sanitizer report) is captured into the error message.  Each import has
 * its own process, so concurrent loads need no lock around assimp's
 * process-wide error string. */

#if defined(__SANITIZE_ADDRESS__)
#define MIO_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MIO_SANITIZED 1
#endif
#endif

#ifdef MIO_SANITIZED
/* The sanitizer runtimes of GCC 12 do not make their allocator fork-safe:
 * a child forked while another thread holds an allocator lock deadlocks
 * (until the time limit).  Sanitizer builds therefore run whole loads one
 * at a time, so that at least glint's own threads are not allocating
 * during the fork.  Production builds use glibc's malloc, which is. */
static pthread_mutex_t mio_sanitizer_lock = PTHREAD_MUTEX_INITIALIZER;
#endif

#define MIO_WIRE_MAGIC 0x676c6d31u /* "glm1" */

typedef struct mio_wire {
    uint32_t magic;
    int32_t rc;
    char msg[GLINT_ERR_MSG_MAX];
    int64_t nv, nt, prims;
    int32_t has_nrm, has_uv;
} mio_wire;

static int mio_write_all(int fd, const void *p, size_t n)
{
    const char *c = p;
    while (n) {
        ssize_t w = write(fd, c, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        c += w;
        n -= (size_t)w;
    }
    return 0;
}

static void mio_child(int fd, const char *path, const void *data, size_t len, const char *hint,
                      const char *what)
{
    mio_wire w;
    mesh raw;
    long long prims = 0;
    glint_err e;
    int rc;

#ifndef MIO_SANITIZED
    {
        FILE *f = fopen("/proc/self/statm", "r");
        unsigned long long pages = 0;
        if (f) {
            if (fscanf(f, "%llu", &pages) != 1)
                pages = 0;
            fclose(f);
        }
        if (pages) {
            struct rlimit rl;
            unsigned long long lim = pages * (unsigned long long)sysconf(_SC_PAGESIZE) +
                                     (2ull << 30) + 32ull * (unsigned long long)len;
            rl.rlim_cur = rl.rlim_max = (rlim_t)lim;
            (void)setrlimit(RLIMIT_AS, &rl);
        }
    }
#endif
    memset(&w, 0, sizeof w);
    memset(&e, 0, sizeof e);
    rc = mio_import_direct(path, data, len, hint, what, &raw, &prims, &e);
    w.magic = MIO_WIRE_MAGIC;
    w.rc = rc;
    memcpy(w.msg, e.msg, sizeof w.msg);
    if (!rc) {
        w.nv = raw.nverts;
        w.nt = raw.ntris;
        w.prims = prims;
        w.has_nrm = raw.nrm != NULL;
        w.has_uv = raw.uv != NULL;
    }
    if (mio_write_all(fd, &w, sizeof w) ||
        (!rc && (mio_write_all(fd, raw.pos, 3 * sizeof(float) * (size_t)raw.nverts) ||
                 (raw.nrm && mio_write_all(fd, raw.nrm, 3 * sizeof(float) * (size_t)raw.nverts)) ||
                 (raw.uv && mio_write_all(fd, raw.uv, 2 * sizeof(float) * (size_t)raw.nverts)) ||
                 mio_write_all(fd, raw.tri, 3 * sizeof(uint32_t) * (size_t)raw.ntris))))
        _exit(3);
    _exit(0);
}

/* Where the next bytes from the child go. */
typedef struct mio_sink {
    mio_wire w;
    unsigned char *seg[5];
    size_t seglen[5];
    int nseg, cur;
    size_t off;      /* into the current segment */
    int header_done;
    mesh *raw;
    int bad;         /* the child sent something inconsistent */
} mio_sink;

static void mio_sink_plan(mio_sink *k, glint_err *err)
{
    const mio_wire *w = &k->w;
    k->header_done = 1;
    k->nseg = 0;
    if (w->magic != MIO_WIRE_MAGIC) {
        k->bad = 1;
        return;
    }
    if (w->rc)
        return;
    if (w->nv < 1 || w->nt < 1 || w->nv > MESH_MAX_VERTS || w->nt > MESH_MAX_TRIS) {
        k->bad = 1;
        return;
    }
    if (mio_alloc(k->raw, (size_t)w->nv, (size_t)w->nt, w->has_nrm, w->has_uv, err)) {
        k->bad = 2;
        return;
    }
    k->seg[k->nseg] = (unsigned char *)k->raw->pos;
    k->seglen[k->nseg++] = 3 * sizeof(float) * (size_t)w->nv;
    if (w->has_nrm) {
        k->seg[k->nseg] = (unsigned char *)k->raw->nrm;
        k->seglen[k->nseg++] = 3 * sizeof(float) * (size_t)w->nv;
    }
    if (w->has_uv) {
        k->seg[k->nseg] = (unsigned char *)k->raw->uv;
        k->seglen[k->nseg++] = 2 * sizeof(float) * (size_t)w->nv;
    }
    k->seg[k->nseg] = (unsigned char *)k->raw->tri;
    k->seglen[k->nseg++] = 3 * sizeof(uint32_t) * (size_t)w->nt;
}

/* Read what is available on the result pipe: 1 at EOF, 0 for more, -1 on
 * error or excess data. */
static int mio_sink_read(mio_sink *k, int fd, glint_err *err)
{
    unsigned char scratch[4096];
    for (;;) {
        unsigned char *dst;
        size_t room;
        ssize_t r;
        if (!k->header_done) {
            dst = (unsigned char *)&k->w + k->off;
            room = sizeof k->w - k->off;
        } else if (k->cur < k->nseg && !k->bad) {
            dst = k->seg[k->cur] + k->off;
            room = k->seglen[k->cur] - k->off;
        } else {
            dst = scratch; /* nothing more is expected: drain and flag */
            room = sizeof scratch;
        }
        r = read(fd, dst, room);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            return 0;
        if (r < 0)
            return -1;
        if (r == 0)
            return 1;
        if (dst == scratch) {
            k->bad = k->bad ? k->bad : 1;
            continue;
        }
        k->off += (size_t)r;
        if (!k->header_done && k->off == sizeof k->w) {
            k->off = 0;
            mio_sink_plan(k, err);
        } else if (k->header_done && k->off == k->seglen[k->cur]) {
            k->off = 0;
            k->cur++;
        }
    }
}

static double mio_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int mio_import(const char *path, const void *data, size_t len, const char *hint,
                      const char *what, mesh *raw, long long *prims, glint_err *err)
{
    int out[2] = {-1, -1}, errp[2] = {-1, -1}, rc, status = 0, reaped = 0, timed_out = 0;
    int open_out, open_err;
    char errtext[400];
    size_t nerr = 0;
    double deadline;
    mio_sink k;
    pid_t pid;

    memset(raw, 0, sizeof *raw);
    memset(&k, 0, sizeof k);
    k.raw = raw;
    errtext[0] = '\0';
    if (pipe(out) || pipe(errp)) {
        rc = glint_err_set(err, GLINT_EIO, "%s: cannot create a pipe for the importer: %s", what,
                           strerror(errno));
        goto done;
    }
    for (int i = 0; i < 2; i++) { /* not inherited by programs other threads exec */
        fcntl(out[i], F_SETFD, FD_CLOEXEC);
        fcntl(errp[i], F_SETFD, FD_CLOEXEC);
    }
    pid = fork();
    if (pid < 0) {
        rc = glint_err_set(err, errno == ENOMEM || errno == EAGAIN ? GLINT_ENOMEM : GLINT_EIO,
                           "%s: cannot start the importer process: %s", what, strerror(errno));
        goto done;
    }
    if (pid == 0) {
        /* fd 3 <- result pipe, 2 <- stderr pipe, 1 <- /dev/null; the pipe
         * ends are first moved out of the way of 0..3 */
        int wfd = fcntl(out[1], F_DUPFD, 10), efd = fcntl(errp[1], F_DUPFD, 10);
        int devnull = open("/dev/null", O_WRONLY);
        if (wfd < 0 || efd < 0)
            _exit(5);
        if (devnull >= 0 && devnull != 1)
            dup2(devnull, 1);
        dup2(efd, 2);
        dup2(wfd, 3);
        /* nothing of the parent's (sockets, files) stays open in the child */
#ifdef SYS_close_range
        if (syscall(SYS_close_range, 4u, ~0u, 0u) != 0)
#endif
            for (int fd = 4; fd < 4096; fd++)
                close(fd);
        /* a crash ends the child by its signal (the parent reports it) */
        signal(SIGSEGV, SIG_DFL);
        signal(SIGBUS, SIG_DFL);
        signal(SIGFPE, SIG_DFL);
        signal(SIGILL, SIG_DFL);
        signal(SIGABRT, SIG_DFL);
        signal(SIGPIPE, SIG_DFL);
        mio_child(3, path, data, len, hint, what);
        _exit(4); /* not reached */
    }
    close(out[1]);
    close(errp[1]);
    out[1] = errp[1] = -1;
    fcntl(out[0], F_SETFL, fcntl(out[0], F_GETFL) | O_NONBLOCK);
    fcntl(errp[0], F_SETFL, fcntl(errp[0], F_GETFL) | O_NONBLOCK);
    deadline = mio_now() + MESH_IMPORT_TIMEOUT_S;
    open_out = open_err = 1;
    while (open_out || open_err) {
        struct pollfd pf[2];
        int np = 0, wait_ms;
        double left = deadline - mio_now();
        if (left <= 0) {
            timed_out = 1;
            break;
        }
        wait_ms = left > 1000.0 ? 1000000 : (int)(left * 1000.0) + 1;
        if (open_out)
            pf[np++] = (struct pollfd){.fd = out[0], .events = POLLIN};
        if (open_err)
            pf[np++] = (struct pollfd){.fd = errp[0], .events = POLLIN};
        if (poll(pf, (nfds_t)np, wait_ms) < 0) {
            if (errno == EINTR)
                continue;
            break;
        }
        for (int i = 0; i < np; i++) {
            if (!(pf[i].revents & (POLLIN | POLLHUP | POLLERR)))
                continue;
            if (pf[i].fd == out[0]) {
                int r = mio_sink_read(&k, out[0], err);
                if (r != 0)
                    open_out = 0;
            } else {
                for (;;) {
                    char b[512];
                    ssize_t r = read(errp[0], b, sizeof b);
                    if (r < 0 && errno == EINTR)
                        continue;
                    if (r == 0 || (r < 0 && errno != EAGAIN && errno != EWOULDBLOCK))
                        open_err = 0;
                    if (r <= 0)
                        break;
                    for (ssize_t j = 0; j < r && nerr + 1 < sizeof errtext; j++)
                        errtext[nerr++] = b[j] == '\n' || b[j] == '\r' ? ' ' : b[j];
                    errtext[nerr] = '\0';
                }
            }
        }
    }
    if (timed_out)
        kill(pid, SIGKILL);
    for (;;) {
        pid_t w = waitpid(pid, &status, 0);
        if (w == pid) {
            reaped = 1;
            break;
        }
        if (w < 0 && errno == EINTR)
            continue;
        break; /* ECHILD: SIGCHLD ignored by the application; judge by the data */
    }
    if (timed_out) {
        rc = glint_err_set(err, GLINT_ERANGE, "%s: reading it took more than %d s (the limit)",
                           what, MESH_IMPORT_TIMEOUT_S);
        goto done;
    }
    if (reaped && WIFSIGNALED(status)) {
        int sig = WTERMSIG(status);
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: the importer (assimp) crashed on it (signal %d, %s)%s%s: the "
                           "file is malformed", what, sig, strsignal(sig), nerr ? ": " : "",
                           errtext);
        goto done;
    }
    if (k.bad == 2) { /* out of memory for the arrays: err is set */
        rc = GLINT_ENOMEM;
        goto done;
    }
    if (!k.header_done && strstr(errtext, "DEADLYSIGNAL")) {
        /* a sanitizer build reports the crash itself and exits */
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: the importer (assimp) crashed on it: %s: the file is malformed",
                           what, errtext);
        goto done;
    }
    if (!k.header_done || k.bad || (reaped && (!WIFEXITED(status) || WEXITSTATUS(status) != 0)) ||
        (k.w.rc == 0 && k.cur != k.nseg)) {
        rc = glint_err_set(err, strstr(errtext, "Sanitizer") ? GLINT_EINTERNAL : GLINT_EFORMAT,
                           "%s: the importer process failed (exit status %d)%s%s", what,
                           reaped && WIFEXITED(status) ? WEXITSTATUS(status) : -1,
                           nerr ? ": " : "", errtext);
        goto done;
    }
    if (k.w.rc) {
        k.w.msg[sizeof k.w.msg - 1] = '\0';
        rc = glint_err_set(err, k.w.rc < 0 && k.w.rc >= GLINT_EINTERNAL ? k.w.rc : GLINT_EINTERNAL,
                           "%s", k.w.msg);
        /* assimp reports exhausting the child's memory limit as bad_alloc */
        if (strstr(k.w.msg, "bad_alloc"))
            rc = glint_err_set(err, GLINT_ERANGE,
                               "%s: reading it needs more memory than the importer may use "
                               "(%s)", what, k.w.msg);
        goto done;
    }
    *prims = k.w.prims;
    rc = 0;
done:
    for (int i = 0; i < 2; i++) {
        if (out[i] >= 0)
            close(out[i]);
        if (errp[i] >= 0)
            close(errp[i]);
    }
    if (rc)
        mesh_free(raw);
    return rc;
}

/* ------------------------------------------------------------------------ */
/* Cleaning                                                                  */
/* ------------------------------------------------------------------------ */

/* Drop degenerate triangles and unused vertices (arrays compacted in
 * place); count boundary and non-manifold edges of what remains. */
static int mio_clean(mesh *m, mesh_report *rep, const char *what, glint_err *err)
{
    size_t nv = (size_t)m->nverts, nt = (size_t)m->ntris, kept = 0, nn = 0;
    uint32_t *canon = NULL, *remap = NULL;
    mio_pair *edges = NULL;
    double diag, thr;
    int rc;

    canon = malloc(nv * sizeof *canon);
    remap = malloc(nv * sizeof *remap);
    if (!canon || !remap) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory cleaning %s", what);
        goto done;
    }
    rc = mio_weld(m->pos, nv, canon, err);
    if (rc)
        goto done;
    diag = mio_bbox_diag(m->pos, nv);
    thr = MIO_DEGENERATE_REL * diag * diag;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *f = m->tri + 3 * t;
        uint32_t a = canon[f[0]], b = canon[f[1]], c = canon[f[2]];
        if (a == b || b == c || a == c || !(mio_tri_cross_len(m->pos, f, NULL) > thr))
            continue;
        memmove(m->tri + 3 * kept, f, 3 * sizeof *f);
        kept++;
    }
    rep->dropped_degenerate = (int)(nt - kept);
    if (!kept) {
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: no usable triangles (all %zu have zero area or repeated "
                           "corners)", what, nt);
        goto done;
    }
    m->ntris = (int)kept;
    /* unused vertices out */
    memset(remap, 0xff, nv * sizeof *remap);
    for (size_t i = 0; i < 3 * kept; i++)
        remap[m->tri[i]] = 0;
    for (size_t v = 0; v < nv; v++)
        if (remap[v] == 0) {
            remap[v] = (uint32_t)nn;
            if (nn != v) {
                memmove(m->pos + 3 * nn, m->pos + 3 * v, 3 * sizeof(float));
                if (m->nrm)
                    memmove(m->nrm + 3 * nn, m->nrm + 3 * v, 3 * sizeof(float));
                if (m->uv)
                    memmove(m->uv + 2 * nn, m->uv + 2 * v, 2 * sizeof(float));
            }
            nn++;
        }
    for (size_t i = 0; i < 3 * kept; i++)
        m->tri[i] = remap[m->tri[i]];
    m->nverts = (int)nn;
    /* edges on welded positions */
    rc = mio_weld(m->pos, nn, canon, err);
    if (rc)
        goto done;
    rc = mio_edges_sorted(m, canon, &edges, err);
    if (rc)
        goto done;
    mio_edge_stats(edges, 3 * kept, &rep->boundary_edges, &rep->nonmanifold_edges);
done:
    free(canon);
    free(remap);
    free(edges);
    return rc;
}

/* The file's normals, renormalized; 0 if any is unusable (then all are
 * recomputed). */
static int mio_normals_usable(mesh *m)
{
    size_t nv = (size_t)m->nverts;
    if (!m->nrm)
        return 0;
    for (size_t v = 0; v < nv; v++) {
        v3 n = v3_loadf(m->nrm + 3 * v);
        double l = v3_len(n);
        if (!isfinite(l) || !(l > 1e-30))
            return 0;
    }
    for (size_t v = 0; v < nv; v++) {
        v3 n = v3_loadf(m->nrm + 3 * v);
        v3_storef(v3_scale(n, 1.0 / v3_len(n)), m->nrm + 3 * v);
    }
    return 1;
}

/* The file's uvs: kept if finite and spanning some area, moved into
 * [0,1]^2 by one uniform scale and shift when they leave it (tiling or
 * offset layouts).  Returns 1 if kept (OUT: *rescaled). */
static int mio_uvs_usable(mesh *m, int *rescaled)
{
    size_t nv = (size_t)m->nverts, nt = (size_t)m->ntris;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY}, area = 0.0, ext;
    *rescaled = 0;
    if (!m->uv)
        return 0;
    for (size_t v = 0; v < nv; v++)
        for (int k = 0; k < 2; k++) {
            double x = m->uv[2 * v + k];
            if (!isfinite(x))
                return 0;
            lo[k] = fmin(lo[k], x);
            hi[k] = fmax(hi[k], x);
        }
    ext = fmax(hi[0] - lo[0], hi[1] - lo[1]);
    for (size_t t = 0; t < nt; t++) {
        const float *a = m->uv + 2 * (size_t)m->tri[3 * t], *b = m->uv + 2 * (size_t)m->tri[3 * t + 1],
                    *c = m->uv + 2 * (size_t)m->tri[3 * t + 2];
        area += fabs(((double)b[0] - a[0]) * ((double)c[1] - a[1]) -
                     ((double)c[0] - a[0]) * ((double)b[1] - a[1]));
    }
    if (!(ext > 0.0) || !(area > 1e-12 * ext * ext))
        return 0; /* all uvs (nearly) equal: no parameterization */
    if (lo[0] >= -1e-6 && lo[1] >= -1e-6 && hi[0] <= 1.0 + 1e-6 && hi[1] <= 1.0 + 1e-6) {
        for (size_t i = 0; i < 2 * nv; i++)
            m->uv[i] = fminf(1.0f, fmaxf(0.0f, m->uv[i]));
        return 1;
    }
    for (size_t v = 0; v < nv; v++)
        for (int k = 0; k < 2; k++)
            m->uv[2 * v + k] = (float)fmin(1.0, fmax(0.0, (m->uv[2 * v + k] - lo[k]) / ext));
    *rescaled = 1;
    return 1;
}

/* Fraction of [0,1]^2 covered by the uv triangles (overlaps counted
 * twice). */
static double mio_uv_coverage(const mesh *m)
{
    double area = 0.0;
    for (size_t t = 0; t < (size_t)m->ntris; t++) {
        const float *a = m->uv + 2 * (size_t)m->tri[3 * t], *b = m->uv + 2 * (size_t)m->tri[3 * t + 1],
                    *c = m->uv + 2 * (size_t)m->tri[3 * t + 2];
        area += 0.5 * fabs(((double)b[0] - a[0]) * ((double)c[1] - a[1]) -
                           ((double)c[0] - a[0]) * ((double)b[1] - a[1]));
    }
    return area;
}

/* ------------------------------------------------------------------------ */
/* Entry points                                                              */
/* ------------------------------------------------------------------------ */

/* Lower-case format name from a file name's extension or a hint (at most
 * 15 characters of [a-z0-9]); "" if there is none. */
static void mio_format_name(const char *name, int is_hint, char out[16])
{
    const char *dot, *slash, *ext;
    size_t n;
    out[0] = '\0';
    if (!name)
        return;
    if (is_hint) {
        ext = name[0] == '.' ? name + 1 : name;
    } else {
        slash = strrchr(name, '/');
        dot = strrchr(slash ? slash + 1 : name, '.');
        if (!dot)
            return;
        ext = dot + 1;
    }
    n = strlen(ext);
    if (n == 0 || n > 15)
        return;
    for (size_t i = 0; i < n; i++) {
        char c = ext[i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'))) {
            out[0] = '\0';
            return;
        }
        out[i] = c;
    }
    out[n] = '\0';
}

/* Everything after the bytes are known to be there: pre-scan, import,
 * merge, clean, normals, normalization, uvs. */
static int mio_load_locked(const char *path, const void *data, size_t len, const char *fmt,
                           const char *what, mesh *out, mesh_report *report, glint_err *err);

static int mio_load(const char *path, const void *data, size_t len, const char *fmt,
                    const char *what, mesh *out, mesh_report *report, glint_err *err)
{
#ifdef MIO_SANITIZED
    int rc;
    pthread_mutex_lock(&mio_sanitizer_lock);
    rc = mio_load_locked(path, data, len, fmt, what, out, report, err);
    pthread_mutex_unlock(&mio_sanitizer_lock);
    return rc;
#else
    return mio_load_locked(path, data, len, fmt, what, out, report, err);
#endif
}

static int mio_load_locked(const char *path, const void *data, size_t len, const char *fmt,
                           const char *what, mesh *out, mesh_report *report, glint_err *err)
{
    mesh_report rep;
    mesh m;
    long long prims = 0;
    int rc, rescaled = 0;

    memset(&rep, 0, sizeof rep);
    snprintf(rep.format, sizeof rep.format, "%s", *fmt ? fmt : "unknown");
    if (data) {
        rc = mio_prescan(data, len, fmt, what, err);
        if (rc)
            return rc;
    }
    rc = mio_import(path, data, len, fmt, what, &m, &prims, err);
    if (rc)
        return rc;
    rep.dropped_primitives = prims > INT_MAX ? INT_MAX : (int)prims;
    rc = mio_clean(&m, &rep, what, err);
    if (rc)
        goto fail;
    if (!mio_normals_usable(&m)) {
        rc = mesh_compute_normals(&m, err);
        if (rc)
            goto fail;
        rep.normals_generated = 1;
    }
    mesh_normalize(&m, &rep.scale, rep.center);
    if (mio_uvs_usable(&m, &rescaled)) {
        rep.uvs_rescaled = rescaled;
    } else {
        free(m.uv);
        m.uv = NULL;
        rc = mio_uv_generate(&m, &rep.uv_charts, err);
        if (rc)
            goto fail;
        rep.uvs_generated = 1;
    }
    rep.uv_coverage = mio_uv_coverage(&m);
    rc = mesh_validate(&m, err);
    if (rc) {
        glint_err_prefix(err, "%s", what);
        goto fail;
    }
    rep.nverts = m.nverts;
    rep.ntris = m.ntris;
    *out = m;
    if (report)
        *report = rep;
    return 0;

fail:
    mesh_free(&m);
    return rc;
}

int mesh_load(const char *path, mesh *out, mesh_report *report, glint_err *err)
{
    struct stat st;
    char fmt[16], head[8];
    int fd = -1, rc;
    void *map = MAP_FAILED;
    size_t len;
    ssize_t got;

    if (report)
        memset(report, 0, sizeof *report);
    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_load: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "mesh_load: empty path");
    fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return glint_err_set(err, errno == ENOENT || errno == ENOTDIR ? GLINT_ENOTFOUND : GLINT_EIO,
                             "opening mesh file %s: %s", path, strerror(errno));
    if (fstat(fd, &st) != 0) {
        rc = glint_err_set(err, GLINT_EIO, "stat of mesh file %s: %s", path, strerror(errno));
        goto done;
    }
    if (!S_ISREG(st.st_mode)) {
        rc = glint_err_set(err, GLINT_EINVAL, "mesh file %s is not a regular file", path);
        goto done;
    }
    if ((unsigned long long)st.st_size > (unsigned long long)MESH_MAX_FILE_BYTES) {
        rc = glint_err_set(err, GLINT_ERANGE, "mesh file %s is %lld bytes, more than the limit "
                           "of %zu", path, (long long)st.st_size, (size_t)MESH_MAX_FILE_BYTES);
        goto done;
    }
    if (st.st_size == 0) {
        rc = glint_err_set(err, GLINT_EFORMAT, "mesh file %s is empty", path);
        goto done;
    }
    len = (size_t)st.st_size;
    mio_format_name(path, 0, fmt);
    /* The pre-scan reads PLY and OFF data in place (mapped read-only). */
    got = pread(fd, head, sizeof head, 0);
    if (got < 0) {
        rc = glint_err_set(err, GLINT_EIO, "reading mesh file %s: %s", path, strerror(errno));
        goto done;
    }
    {
        int maybe = strcmp(fmt, "ply") == 0 || strcmp(fmt, "off") == 0 ||
                    (got >= 3 && (memcmp(head, "ply", 3) == 0 || memcmp(head, "PLY", 3) == 0));
        for (ssize_t i = 0; !maybe && i + 2 < got; i++)
            maybe = memcmp(head + i, "OFF", 3) == 0;
        if (maybe) {
            map = mmap(NULL, len, PROT_READ, MAP_PRIVATE, fd, 0);
            if (map == MAP_FAILED) {
                rc = glint_err_set(err, GLINT_EIO, "mapping mesh file %s: %s", path,
                                   strerror(errno));
                goto done;
            }
            rc = mio_prescan(map, len, fmt, path, err);
            munmap(map, len);
            if (rc)
                goto done;
        }
    }
    close(fd);
    fd = -1;
    rc = mio_load(path, NULL, len, fmt, path, out, report, err);
done:
    if (fd >= 0)
        close(fd);
    return rc;
}

int mesh_load_mem(const void *data, size_t len, const char *hint, mesh *out,
                  mesh_report *report, glint_err *err)
{
    char fmt[16], what[48];

    if (report)
        memset(report, 0, sizeof *report);
    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_load_mem: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (!data && len)
        return glint_err_set(err, GLINT_EINVAL, "mesh_load_mem: data is NULL");
    mio_format_name(hint, 1, fmt);
    if (!fmt[0])
        return glint_err_set(err, GLINT_EINVAL,
                             "mesh_load_mem: format hint \"%.32s\" is not a file extension "
                             "(1 to 15 letters or digits, e.g. \"ply\")", hint ? hint : "(null)");
    snprintf(what, sizeof what, "%s data", fmt);
    if (len == 0)
        return glint_err_set(err, GLINT_EFORMAT, "%s: empty (0 bytes)", what);
    if (len > MESH_MAX_FILE_BYTES)
        return glint_err_set(err, GLINT_ERANGE, "%s: %zu bytes, more than the limit of %zu",
                             what, len, (size_t)MESH_MAX_FILE_BYTES);
    return mio_load(NULL, data, len, fmt, what, out, report, err);
}
