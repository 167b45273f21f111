/* mesh_geom.c: mesh helpers shared by the mesh modules (argument checks,
 * welding, edges, sorting), smooth normals and unit-ball normalization (contract in mesh.h). */
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
/* Small helpers                                                             */
/* ------------------------------------------------------------------------ */

/* Arrays of a mesh; nrm / uv only when asked for.  *m zeroed on failure. */
int mio_alloc(mesh *m, size_t nverts, size_t ntris, int with_nrm, int with_uv,
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

double mio_tri_cross_len(const float *pos, const uint32_t *f, v3 *n)
{
    v3 a = v3_loadf(pos + 3 * (size_t)f[0]), b = v3_loadf(pos + 3 * (size_t)f[1]),
       c = v3_loadf(pos + 3 * (size_t)f[2]);
    v3 x = v3_cross(v3_sub(b, a), v3_sub(c, a));
    if (n)
        *n = x;
    return v3_len(x);
}

double mio_bbox_diag(const float *pos, size_t n)
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

void mio_radix_sort(mio_pair *a, mio_pair *tmp, size_t n)
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
uint32_t mio_fbits(float x)
{
    uint32_t u;
    if (x == 0.0f)
        x = 0.0f;
    memcpy(&u, &x, sizeof u);
    return u;
}

int mio_weld(const float *pos, size_t n, uint32_t *canon, glint_err *err)
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
int mio_edges_sorted(const mesh *m, const uint32_t *canon, mio_pair **edges,
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
void mio_edge_stats(const mio_pair *e, size_t ne, int *boundary, int *nonmanifold)
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

/* Arguments every public mesh operation requires. */
int mio_check_mesh(const mesh *m, const char *who, glint_err *err)
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

/* The public entry of the automatic parameterization (mesh_uv.c). */
int mesh_generate_uvs(mesh *m, glint_err *err)
{
    int rc = mio_check_mesh(m, "mesh_generate_uvs", err);
    if (rc)
        return rc;
    return mio_uv_generate(m, NULL, err);
}
