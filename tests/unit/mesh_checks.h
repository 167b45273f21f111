/* mesh_checks.h: geometric checks of meshes for the tests of core/mesh_io
 * and the built-in shapes (test_mesh_io.c, test_mesh_refs.c,
 * test_mesh_gen.c): bounding box, areas, what every loaded mesh must
 * satisfy, uv overlaps and area distortion, edge counts on welded
 * positions, and outward orientation by ray parity. */
#ifndef GLINT_MESH_CHECKS_H
#define GLINT_MESH_CHECKS_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "vec3.h"

/* ---- geometric checks ----------------------------------------------------------- */

static inline void bbox(const mesh *m, double lo[3], double hi[3])
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

static inline double max_norm(const mesh *m)
{
    double r = 0.0;
    for (int v = 0; v < m->nverts; v++)
        r = fmax(r, v3_len(v3_loadf(m->pos + 3 * v)));
    return r;
}

static inline double tri_area3(const mesh *m, int t)
{
    const uint32_t *f = m->tri + 3 * t;
    v3 a = v3_loadf(m->pos + 3 * f[0]), b = v3_loadf(m->pos + 3 * f[1]),
       c = v3_loadf(m->pos + 3 * f[2]);
    return 0.5 * v3_len(v3_cross(v3_sub(b, a), v3_sub(c, a)));
}

static inline double tri_area_uv(const mesh *m, int t) /* signed */
{
    const uint32_t *f = m->tri + 3 * t;
    const float *a = m->uv + 2 * f[0], *b = m->uv + 2 * f[1], *c = m->uv + 2 * f[2];
    return 0.5 * (((double)b[0] - a[0]) * ((double)c[1] - a[1]) -
                  ((double)c[0] - a[0]) * ((double)b[1] - a[1]));
}

/* Everything a loaded mesh must satisfy: valid, unit normals, uv in
 * [0,1], normalized into the unit ball with max |v| = 1. */
static inline int check_loaded(const mesh *m, char *why, size_t whylen)
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
static inline double edge_fn(const float *a, const float *b, double px, double py)
{
    int swap = a[0] > b[0] || (a[0] == b[0] && a[1] > b[1]);
    const float *lo = swap ? b : a, *hi = swap ? a : b;
    double e = ((double)hi[0] - lo[0]) * (py - lo[1]) - ((double)hi[1] - lo[1]) * (px - lo[0]);
    return swap ? -e : e;
}

/* Samples of a G x G grid over [0,1]^2 strictly inside two or more uv
 * triangles (OUT: *covered, samples inside at least one). */
static inline long uv_overlaps(const mesh *m, int G, long *covered)
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
static inline double uv_within(const mesh *m, double f, double *neg)
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

static inline int pos_cmp(const float *a, const float *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

static inline int ekey_cmp(const void *x, const void *y)
{
    const ekey *p = x, *q = y;
    int c = pos_cmp(p->a, q->a);
    return c ? c : pos_cmp(p->b, q->b);
}

static inline void edge_counts(const mesh *m, long *boundary, long *nonmanifold)
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
static inline int ray_hits(const mesh *m, int t, v3 o, v3 d)
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
static inline double outward_share(const mesh *m, int nsamples)
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

#endif
