/* mesh.c: indexed triangle meshes and the built-in shapes (contract in mesh.h).
 *
 * Sphere layout (nlat rings of cells between the poles, nlon segments):
 *   - row r = 1 .. nlat-1 (theta = pi r / nlat) holds nlon + 1 vertices,
 *     phi = 2 pi k / nlon for k = 0 .. nlon: the seam (k = 0 and k = nlon)
 *     is duplicated so that u runs 0 .. 1 without wrapping;
 *   - each pole holds nlon copies of the pole point, one per segment, with
 *     u at the segment's middle (k + .5) / nlon, so the cap triangles carry
 *     sensible texture coordinates;
 *   - cap cells are single triangles (pole copy, two ring vertices) and
 *     band cells are two triangles: no zero-area triangles anywhere.
 * Positions: (sin theta cos phi, sin theta sin phi, cos theta), so +z is
 * the theta = 0 pole; normals equal positions. */
#include "mesh.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "vec3.h"

#define MESH_PI 3.14159265358979323846

/* Default tessellation of the built-in sphere (see mesh.h). */
#define MESH_SPHERE_DEFAULT_LAT 256
#define MESH_SPHERE_DEFAULT_LON 512

/* Allocate the arrays of a mesh with the given counts (zeroed on failure). */
static int mesh_alloc(mesh *m, long long nverts, long long ntris, glint_err *err)
{
    memset(m, 0, sizeof *m);
    /* 3 * n must fit an int (indices are uint32, counts int) and a size_t
     * byte count must not overflow. */
    if (nverts < 1 || ntris < 1 || nverts > INT_MAX / 3 || ntris > INT_MAX / 3 ||
        (unsigned long long)nverts > SIZE_MAX / (3 * sizeof(float)) ||
        (unsigned long long)ntris > SIZE_MAX / (3 * sizeof(uint32_t)))
        return glint_err_set(err, GLINT_ERANGE,
                             "mesh with %lld vertices and %lld triangles is too large "
                             "(at most %d of each)", nverts, ntris, INT_MAX / 3);
    m->pos = malloc((size_t)nverts * 3 * sizeof(float));
    m->nrm = malloc((size_t)nverts * 3 * sizeof(float));
    m->uv = malloc((size_t)nverts * 2 * sizeof(float));
    m->tri = malloc((size_t)ntris * 3 * sizeof(uint32_t));
    if (!m->pos || !m->nrm || !m->uv || !m->tri) {
        mesh_free(m);
        return glint_err_set(err, GLINT_ENOMEM,
                             "out of memory for a mesh of %lld vertices and %lld triangles",
                             nverts, ntris);
    }
    m->nverts = (int)nverts;
    m->ntris = (int)ntris;
    return 0;
}

int mesh_sphere(mesh *out, int nlat, int nlon, glint_err *err)
{
    long long nverts, ntris;
    double *cphi = NULL, *sphi = NULL;
    uint32_t *t;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_sphere: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (nlat < 2 || nlat > MESH_SPHERE_MAX_SEG)
        return glint_err_set(err, GLINT_ERANGE, "sphere rings %d outside 2..%d", nlat,
                             MESH_SPHERE_MAX_SEG);
    if (nlon < MESH_SPHERE_MIN_SEG || nlon > MESH_SPHERE_MAX_SEG)
        return glint_err_set(err, GLINT_ERANGE, "sphere segments %d outside %d..%d", nlon,
                             MESH_SPHERE_MIN_SEG, MESH_SPHERE_MAX_SEG);

    nverts = 2LL * nlon + (long long)(nlat - 1) * (nlon + 1);
    ntris = 2LL * nlon + 2LL * nlon * (nlat - 2);
    rc = mesh_alloc(out, nverts, ntris, err);
    if (rc)
        return rc;

    cphi = malloc((size_t)(nlon + 1) * sizeof(double));
    sphi = malloc((size_t)(nlon + 1) * sizeof(double));
    if (!cphi || !sphi) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory building a sphere");
        goto fail;
    }
    for (int k = 0; k <= nlon; k++) {
        double phi = 2.0 * MESH_PI * k / nlon;
        cphi[k] = cos(phi);
        sphi[k] = sin(phi);
    }
    /* Exact seam: the last column repeats the first bit for bit. */
    cphi[nlon] = cphi[0];
    sphi[nlon] = sphi[0];

    /* Vertices: north pole copies [0, nlon), rings, south pole copies. */
    {
        size_t v = 0;
        for (int k = 0; k < nlon; k++, v++) {
            float *p = out->pos + 3 * v, *uv = out->uv + 2 * v;
            p[0] = 0.0f; p[1] = 0.0f; p[2] = 1.0f;
            uv[0] = (float)((k + 0.5) / nlon);
            uv[1] = 0.0f;
        }
        for (int r = 1; r < nlat; r++) {
            double theta = MESH_PI * r / nlat;
            double st = sin(theta), ct = cos(theta);
            for (int k = 0; k <= nlon; k++, v++) {
                float *p = out->pos + 3 * v, *uv = out->uv + 2 * v;
                p[0] = (float)(st * cphi[k]);
                p[1] = (float)(st * sphi[k]);
                p[2] = (float)ct;
                uv[0] = (float)((double)k / nlon);
                uv[1] = (float)((double)r / nlat);
            }
        }
        for (int k = 0; k < nlon; k++, v++) {
            float *p = out->pos + 3 * v, *uv = out->uv + 2 * v;
            p[0] = 0.0f; p[1] = 0.0f; p[2] = -1.0f;
            uv[0] = (float)((k + 0.5) / nlon);
            uv[1] = 1.0f;
        }
        if ((long long)v != nverts) {
            rc = glint_err_set(err, GLINT_EINTERNAL, "sphere vertex count %zu != %lld", v,
                               nverts);
            goto fail;
        }
    }
    memcpy(out->nrm, out->pos, (size_t)nverts * 3 * sizeof(float));

    /* Triangles, counter-clockwise seen from outside: for a cell with
     * corners a = (r, k), b = (r+1, k), c = (r, k+1), d = (r+1, k+1)
     * (theta grows with r, phi with k), (a, b, c) and (c, b, d) face out. */
    {
        const uint32_t ring0 = (uint32_t)nlon;     /* first vertex of row 1 */
        const uint32_t stride = (uint32_t)nlon + 1;
        const uint32_t south = ring0 + (uint32_t)(nlat - 1) * stride;
#define RV(r, k) (ring0 + (uint32_t)((r) - 1) * stride + (uint32_t)(k))
        t = out->tri;
        for (int k = 0; k < nlon; k++) { /* north cap: (pole, b, d) */
            *t++ = (uint32_t)k;
            *t++ = RV(1, k);
            *t++ = RV(1, k + 1);
        }
        for (int r = 1; r < nlat - 1; r++) {
            for (int k = 0; k < nlon; k++) {
                uint32_t a = RV(r, k), c = RV(r, k + 1);
                uint32_t b = RV(r + 1, k), d = RV(r + 1, k + 1);
                *t++ = a; *t++ = b; *t++ = c;
                *t++ = c; *t++ = b; *t++ = d;
            }
        }
        for (int k = 0; k < nlon; k++) { /* south cap: (a, pole, c) */
            *t++ = RV(nlat - 1, k);
            *t++ = south + (uint32_t)k;
            *t++ = RV(nlat - 1, k + 1);
        }
#undef RV
        if (t != out->tri + 3 * (size_t)ntris) {
            rc = glint_err_set(err, GLINT_EINTERNAL, "sphere triangle count mismatch");
            goto fail;
        }
    }
    free(cphi);
    free(sphi);
    return 0;

fail:
    free(cphi);
    free(sphi);
    mesh_free(out);
    return rc;
}

int mesh_sphere_default(mesh *out, glint_err *err)
{
    return mesh_sphere(out, MESH_SPHERE_DEFAULT_LAT, MESH_SPHERE_DEFAULT_LON, err);
}

/* ------------------------------------------------------------------------ */
/* Torus                                                                     */
/* ------------------------------------------------------------------------ */

/* Layout: (nu + 1) x (nv + 1) vertices, vertex (i, j) at index
 * i (nv + 1) + j with theta = 2 pi i / nu around the z axis and
 * phi = 2 pi j / nv around the tube; both seams are duplicated (the last
 * column and row repeat the first bit for bit), uv = (i / nu, j / nv).
 * Position ((R + r cos phi) cos theta, (R + r cos phi) sin theta, r sin phi)
 * / (R + r), normal (cos phi cos theta, cos phi sin theta, sin phi).
 * dP/dtheta x dP/dphi points outwards, so the cell (a, b, c, d) =
 * ((i, j), (i+1, j), (i, j+1), (i+1, j+1)) gives (a, b, d) and (a, d, c). */
int mesh_torus(mesh *out, double R, double r, int nu, int nv, glint_err *err)
{
    double *ct = NULL, *st = NULL, *cp = NULL, *sp = NULL;
    long long nverts, ntris;
    double s;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_torus: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (!isfinite(R) || !isfinite(r))
        return glint_err_set(err, GLINT_ENONFINITE, "torus radii %g, %g are not finite", R, r);
    if (!(r > 0.0) || !(R > r) || R > 1e30)
        return glint_err_set(err, GLINT_ERANGE,
                             "torus radii R = %g, r = %g: need R > r > 0 (and R <= 1e30)", R, r);
    if (nu < MESH_SPHERE_MIN_SEG || nu > MESH_SPHERE_MAX_SEG || nv < MESH_SPHERE_MIN_SEG ||
        nv > MESH_SPHERE_MAX_SEG)
        return glint_err_set(err, GLINT_ERANGE, "torus segments %d x %d outside %d..%d", nu, nv,
                             MESH_SPHERE_MIN_SEG, MESH_SPHERE_MAX_SEG);
    nverts = (long long)(nu + 1) * (nv + 1);
    ntris = 2LL * nu * nv;
    rc = mesh_alloc(out, nverts, ntris, err);
    if (rc)
        return rc;
    ct = malloc((size_t)(nu + 1) * sizeof *ct);
    st = malloc((size_t)(nu + 1) * sizeof *st);
    cp = malloc((size_t)(nv + 1) * sizeof *cp);
    sp = malloc((size_t)(nv + 1) * sizeof *sp);
    if (!ct || !st || !cp || !sp) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory building a torus");
        goto fail;
    }
    for (int i = 0; i <= nu; i++) {
        ct[i] = cos(2.0 * MESH_PI * i / nu);
        st[i] = sin(2.0 * MESH_PI * i / nu);
    }
    for (int j = 0; j <= nv; j++) {
        cp[j] = cos(2.0 * MESH_PI * j / nv);
        sp[j] = sin(2.0 * MESH_PI * j / nv);
    }
    ct[nu] = ct[0];
    st[nu] = st[0];
    cp[nv] = cp[0];
    sp[nv] = sp[0];
    s = 1.0 / (R + r);
    for (int i = 0; i <= nu; i++)
        for (int j = 0; j <= nv; j++) {
            size_t v = (size_t)i * (size_t)(nv + 1) + (size_t)j;
            double ring = R + r * cp[j];
            float *p = out->pos + 3 * v, *n = out->nrm + 3 * v, *uv = out->uv + 2 * v;
            p[0] = (float)(ring * ct[i] * s);
            p[1] = (float)(ring * st[i] * s);
            p[2] = (float)(r * sp[j] * s);
            n[0] = (float)(cp[j] * ct[i]);
            n[1] = (float)(cp[j] * st[i]);
            n[2] = (float)sp[j];
            uv[0] = (float)((double)i / nu);
            uv[1] = (float)((double)j / nv);
        }
    {
        uint32_t *t = out->tri;
        const uint32_t stride = (uint32_t)nv + 1;
        for (int i = 0; i < nu; i++)
            for (int j = 0; j < nv; j++) {
                uint32_t a = (uint32_t)i * stride + (uint32_t)j, b = a + stride, c = a + 1,
                         d = b + 1;
                *t++ = a; *t++ = b; *t++ = d;
                *t++ = a; *t++ = d; *t++ = c;
            }
    }
    free(ct);
    free(st);
    free(cp);
    free(sp);
    return 0;

fail:
    free(ct);
    free(st);
    free(cp);
    free(sp);
    mesh_free(out);
    return rc;
}

/* ------------------------------------------------------------------------ */
/* Utah teapot                                                               */
/* ------------------------------------------------------------------------ */

/* Martin Newell's teapot (1975, public domain) as published with 32
 * bicubic Bezier patches on 306 control points (rim 0-3, upper body 4-7,
 * lower body 8-11, handle 12-15, spout 16-19, lid knob 20-23, lid 24-27,
 * bottom 28-31), z up, spout towards +x.  Indices are zero-based; each
 * patch lists its 4 x 4 control points row by row (row = u, column = v).
 * Points 204, 205, 215 and 222 are part of the published set but unused. */
static const double mesh_teapot_pts[306][3] = {
    {1.4, 0, 2.4}, {1.4, -0.784, 2.4}, {0.784, -1.4, 2.4}, {0, -1.4, 2.4},
    {1.3375, 0, 2.53125}, {1.3375, -0.749, 2.53125}, {0.749, -1.3375, 2.53125}, {0, -1.3375, 2.53125},
    {1.4375, 0, 2.53125}, {1.4375, -0.805, 2.53125}, {0.805, -1.4375, 2.53125}, {0, -1.4375, 2.53125},
    {1.5, 0, 2.4}, {1.5, -0.84, 2.4}, {0.84, -1.5, 2.4}, {0, -1.5, 2.4},
    {-0.784, -1.4, 2.4}, {-1.4, -0.784, 2.4}, {-1.4, 0, 2.4}, {-0.749, -1.3375, 2.53125},
    {-1.3375, -0.749, 2.53125}, {-1.3375, 0, 2.53125}, {-0.805, -1.4375, 2.53125}, {-1.4375, -0.805, 2.53125},
    {-1.4375, 0, 2.53125}, {-0.84, -1.5, 2.4}, {-1.5, -0.84, 2.4}, {-1.5, 0, 2.4},
    {-1.4, 0.784, 2.4}, {-0.784, 1.4, 2.4}, {0, 1.4, 2.4}, {-1.3375, 0.749, 2.53125},
    {-0.749, 1.3375, 2.53125}, {0, 1.3375, 2.53125}, {-1.4375, 0.805, 2.53125}, {-0.805, 1.4375, 2.53125},
    {0, 1.4375, 2.53125}, {-1.5, 0.84, 2.4}, {-0.84, 1.5, 2.4}, {0, 1.5, 2.4},
    {0.784, 1.4, 2.4}, {1.4, 0.784, 2.4}, {0.749, 1.3375, 2.53125}, {1.3375, 0.749, 2.53125},
    {0.805, 1.4375, 2.53125}, {1.4375, 0.805, 2.53125}, {0.84, 1.5, 2.4}, {1.5, 0.84, 2.4},
    {1.75, 0, 1.875}, {1.75, -0.98, 1.875}, {0.98, -1.75, 1.875}, {0, -1.75, 1.875},
    {2, 0, 1.35}, {2, -1.12, 1.35}, {1.12, -2, 1.35}, {0, -2, 1.35},
    {2, 0, 0.9}, {2, -1.12, 0.9}, {1.12, -2, 0.9}, {0, -2, 0.9},
    {-0.98, -1.75, 1.875}, {-1.75, -0.98, 1.875}, {-1.75, 0, 1.875}, {-1.12, -2, 1.35},
    {-2, -1.12, 1.35}, {-2, 0, 1.35}, {-1.12, -2, 0.9}, {-2, -1.12, 0.9},
    {-2, 0, 0.9}, {-1.75, 0.98, 1.875}, {-0.98, 1.75, 1.875}, {0, 1.75, 1.875},
    {-2, 1.12, 1.35}, {-1.12, 2, 1.35}, {0, 2, 1.35}, {-2, 1.12, 0.9},
    {-1.12, 2, 0.9}, {0, 2, 0.9}, {0.98, 1.75, 1.875}, {1.75, 0.98, 1.875},
    {1.12, 2, 1.35}, {2, 1.12, 1.35}, {1.12, 2, 0.9}, {2, 1.12, 0.9},
    {2, 0, 0.45}, {2, -1.12, 0.45}, {1.12, -2, 0.45}, {0, -2, 0.45},
    {1.5, 0, 0.225}, {1.5, -0.84, 0.225}, {0.84, -1.5, 0.225}, {0, -1.5, 0.225},
    {1.5, 0, 0.15}, {1.5, -0.84, 0.15}, {0.84, -1.5, 0.15}, {0, -1.5, 0.15},
    {-1.12, -2, 0.45}, {-2, -1.12, 0.45}, {-2, 0, 0.45}, {-0.84, -1.5, 0.225},
    {-1.5, -0.84, 0.225}, {-1.5, 0, 0.225}, {-0.84, -1.5, 0.15}, {-1.5, -0.84, 0.15},
    {-1.5, 0, 0.15}, {-2, 1.12, 0.45}, {-1.12, 2, 0.45}, {0, 2, 0.45},
    {-1.5, 0.84, 0.225}, {-0.84, 1.5, 0.225}, {0, 1.5, 0.225}, {-1.5, 0.84, 0.15},
    {-0.84, 1.5, 0.15}, {0, 1.5, 0.15}, {1.12, 2, 0.45}, {2, 1.12, 0.45},
    {0.84, 1.5, 0.225}, {1.5, 0.84, 0.225}, {0.84, 1.5, 0.15}, {1.5, 0.84, 0.15},
    {-1.6, 0, 2.025}, {-1.6, -0.3, 2.025}, {-1.5, -0.3, 2.25}, {-1.5, 0, 2.25},
    {-2.3, 0, 2.025}, {-2.3, -0.3, 2.025}, {-2.5, -0.3, 2.25}, {-2.5, 0, 2.25},
    {-2.7, 0, 2.025}, {-2.7, -0.3, 2.025}, {-3, -0.3, 2.25}, {-3, 0, 2.25},
    {-2.7, 0, 1.8}, {-2.7, -0.3, 1.8}, {-3, -0.3, 1.8}, {-3, 0, 1.8},
    {-1.5, 0.3, 2.25}, {-1.6, 0.3, 2.025}, {-2.5, 0.3, 2.25}, {-2.3, 0.3, 2.025},
    {-3, 0.3, 2.25}, {-2.7, 0.3, 2.025}, {-3, 0.3, 1.8}, {-2.7, 0.3, 1.8},
    {-2.7, 0, 1.575}, {-2.7, -0.3, 1.575}, {-3, -0.3, 1.35}, {-3, 0, 1.35},
    {-2.5, 0, 1.125}, {-2.5, -0.3, 1.125}, {-2.65, -0.3, 0.9375}, {-2.65, 0, 0.9375},
    {-2, -0.3, 0.9}, {-1.9, -0.3, 0.6}, {-1.9, 0, 0.6}, {-3, 0.3, 1.35},
    {-2.7, 0.3, 1.575}, {-2.65, 0.3, 0.9375}, {-2.5, 0.3, 1.125}, {-1.9, 0.3, 0.6},
    {-2, 0.3, 0.9}, {1.7, 0, 1.425}, {1.7, -0.66, 1.425}, {1.7, -0.66, 0.6},
    {1.7, 0, 0.6}, {2.6, 0, 1.425}, {2.6, -0.66, 1.425}, {3.1, -0.66, 0.825},
    {3.1, 0, 0.825}, {2.3, 0, 2.1}, {2.3, -0.25, 2.1}, {2.4, -0.25, 2.025},
    {2.4, 0, 2.025}, {2.7, 0, 2.4}, {2.7, -0.25, 2.4}, {3.3, -0.25, 2.4},
    {3.3, 0, 2.4}, {1.7, 0.66, 0.6}, {1.7, 0.66, 1.425}, {3.1, 0.66, 0.825},
    {2.6, 0.66, 1.425}, {2.4, 0.25, 2.025}, {2.3, 0.25, 2.1}, {3.3, 0.25, 2.4},
    {2.7, 0.25, 2.4}, {2.8, 0, 2.475}, {2.8, -0.25, 2.475}, {3.525, -0.25, 2.49375},
    {3.525, 0, 2.49375}, {2.9, 0, 2.475}, {2.9, -0.15, 2.475}, {3.45, -0.15, 2.5125},
    {3.45, 0, 2.5125}, {2.8, 0, 2.4}, {2.8, -0.15, 2.4}, {3.2, -0.15, 2.4},
    {3.2, 0, 2.4}, {3.525, 0.25, 2.49375}, {2.8, 0.25, 2.475}, {3.45, 0.15, 2.5125},
    {2.9, 0.15, 2.475}, {3.2, 0.15, 2.4}, {2.8, 0.15, 2.4}, {0, 0, 3.15},
    {0, -0.002, 3.15}, {0.002, 0, 3.15}, {0.8, 0, 3.15}, {0.8, -0.45, 3.15},
    {0.45, -0.8, 3.15}, {0, -0.8, 3.15}, {0, 0, 2.85}, {0.2, 0, 2.7},
    {0.2, -0.112, 2.7}, {0.112, -0.2, 2.7}, {0, -0.2, 2.7}, {-0.002, 0, 3.15},
    {-0.45, -0.8, 3.15}, {-0.8, -0.45, 3.15}, {-0.8, 0, 3.15}, {-0.112, -0.2, 2.7},
    {-0.2, -0.112, 2.7}, {-0.2, 0, 2.7}, {0, 0.002, 3.15}, {-0.8, 0.45, 3.15},
    {-0.45, 0.8, 3.15}, {0, 0.8, 3.15}, {-0.2, 0.112, 2.7}, {-0.112, 0.2, 2.7},
    {0, 0.2, 2.7}, {0.45, 0.8, 3.15}, {0.8, 0.45, 3.15}, {0.112, 0.2, 2.7},
    {0.2, 0.112, 2.7}, {0.4, 0, 2.55}, {0.4, -0.224, 2.55}, {0.224, -0.4, 2.55},
    {0, -0.4, 2.55}, {1.3, 0, 2.55}, {1.3, -0.728, 2.55}, {0.728, -1.3, 2.55},
    {0, -1.3, 2.55}, {1.3, 0, 2.4}, {1.3, -0.728, 2.4}, {0.728, -1.3, 2.4},
    {0, -1.3, 2.4}, {-0.224, -0.4, 2.55}, {-0.4, -0.224, 2.55}, {-0.4, 0, 2.55},
    {-0.728, -1.3, 2.55}, {-1.3, -0.728, 2.55}, {-1.3, 0, 2.55}, {-0.728, -1.3, 2.4},
    {-1.3, -0.728, 2.4}, {-1.3, 0, 2.4}, {-0.4, 0.224, 2.55}, {-0.224, 0.4, 2.55},
    {0, 0.4, 2.55}, {-1.3, 0.728, 2.55}, {-0.728, 1.3, 2.55}, {0, 1.3, 2.55},
    {-1.3, 0.728, 2.4}, {-0.728, 1.3, 2.4}, {0, 1.3, 2.4}, {0.224, 0.4, 2.55},
    {0.4, 0.224, 2.55}, {0.728, 1.3, 2.55}, {1.3, 0.728, 2.55}, {0.728, 1.3, 2.4},
    {1.3, 0.728, 2.4}, {0, 0, 0}, {1.5, 0, 0.15}, {1.5, 0.84, 0.15},
    {0.84, 1.5, 0.15}, {0, 1.5, 0.15}, {1.5, 0, 0.075}, {1.5, 0.84, 0.075},
    {0.84, 1.5, 0.075}, {0, 1.5, 0.075}, {1.425, 0, 0}, {1.425, 0.798, 0},
    {0.798, 1.425, 0}, {0, 1.425, 0}, {-0.84, 1.5, 0.15}, {-1.5, 0.84, 0.15},
    {-1.5, 0, 0.15}, {-0.84, 1.5, 0.075}, {-1.5, 0.84, 0.075}, {-1.5, 0, 0.075},
    {-0.798, 1.425, 0}, {-1.425, 0.798, 0}, {-1.425, 0, 0}, {-1.5, -0.84, 0.15},
    {-0.84, -1.5, 0.15}, {0, -1.5, 0.15}, {-1.5, -0.84, 0.075}, {-0.84, -1.5, 0.075},
    {0, -1.5, 0.075}, {-1.425, -0.798, 0}, {-0.798, -1.425, 0}, {0, -1.425, 0},
    {0.84, -1.5, 0.15}, {1.5, -0.84, 0.15}, {0.84, -1.5, 0.075}, {1.5, -0.84, 0.075},
    {0.798, -1.425, 0}, {1.425, -0.798, 0},
};

static const uint16_t mesh_teapot_patches[32][16] = {
    {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15},
    {3, 16, 17, 18, 7, 19, 20, 21, 11, 22, 23, 24, 15, 25, 26, 27},
    {18, 28, 29, 30, 21, 31, 32, 33, 24, 34, 35, 36, 27, 37, 38, 39},
    {30, 40, 41, 0, 33, 42, 43, 4, 36, 44, 45, 8, 39, 46, 47, 12},
    {12, 13, 14, 15, 48, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59},
    {15, 25, 26, 27, 51, 60, 61, 62, 55, 63, 64, 65, 59, 66, 67, 68},
    {27, 37, 38, 39, 62, 69, 70, 71, 65, 72, 73, 74, 68, 75, 76, 77},
    {39, 46, 47, 12, 71, 78, 79, 48, 74, 80, 81, 52, 77, 82, 83, 56},
    {56, 57, 58, 59, 84, 85, 86, 87, 88, 89, 90, 91, 92, 93, 94, 95},
    {59, 66, 67, 68, 87, 96, 97, 98, 91, 99, 100, 101, 95, 102, 103, 104},
    {68, 75, 76, 77, 98, 105, 106, 107, 101, 108, 109, 110, 104, 111, 112, 113},
    {77, 82, 83, 56, 107, 114, 115, 84, 110, 116, 117, 88, 113, 118, 119, 92},
    {120, 121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132, 133, 134, 135},
    {123, 136, 137, 120, 127, 138, 139, 124, 131, 140, 141, 128, 135, 142, 143, 132},
    {132, 133, 134, 135, 144, 145, 146, 147, 148, 149, 150, 151, 68, 152, 153, 154},
    {135, 142, 143, 132, 147, 155, 156, 144, 151, 157, 158, 148, 154, 159, 160, 68},
    {161, 162, 163, 164, 165, 166, 167, 168, 169, 170, 171, 172, 173, 174, 175, 176},
    {164, 177, 178, 161, 168, 179, 180, 165, 172, 181, 182, 169, 176, 183, 184, 173},
    {173, 174, 175, 176, 185, 186, 187, 188, 189, 190, 191, 192, 193, 194, 195, 196},
    {176, 183, 184, 173, 188, 197, 198, 185, 192, 199, 200, 189, 196, 201, 202, 193},
    {203, 203, 203, 203, 206, 207, 208, 209, 210, 210, 210, 210, 211, 212, 213, 214},
    {203, 203, 203, 203, 209, 216, 217, 218, 210, 210, 210, 210, 214, 219, 220, 221},
    {203, 203, 203, 203, 218, 223, 224, 225, 210, 210, 210, 210, 221, 226, 227, 228},
    {203, 203, 203, 203, 225, 229, 230, 206, 210, 210, 210, 210, 228, 231, 232, 211},
    {211, 212, 213, 214, 233, 234, 235, 236, 237, 238, 239, 240, 241, 242, 243, 244},
    {214, 219, 220, 221, 236, 245, 246, 247, 240, 248, 249, 250, 244, 251, 252, 253},
    {221, 226, 227, 228, 247, 254, 255, 256, 250, 257, 258, 259, 253, 260, 261, 262},
    {228, 231, 232, 211, 256, 263, 264, 233, 259, 265, 266, 237, 262, 267, 268, 241},
    {269, 269, 269, 269, 278, 279, 280, 281, 274, 275, 276, 277, 270, 271, 272, 273},
    {269, 269, 269, 269, 281, 288, 289, 290, 277, 285, 286, 287, 273, 282, 283, 284},
    {269, 269, 269, 269, 290, 297, 298, 299, 287, 294, 295, 296, 284, 291, 292, 293},
    {269, 269, 269, 269, 299, 304, 305, 278, 296, 302, 303, 274, 293, 300, 301, 270},
};

void mesh_teapot_data(const double (**points)[3], int *npoints,
                      const uint16_t (**patches)[16], int *npatches)
{
    if (points)
        *points = mesh_teapot_pts;
    if (npoints)
        *npoints = 306;
    if (patches)
        *patches = mesh_teapot_patches;
    if (npatches)
        *npatches = 32;
}

/* Cubic Bernstein weights and their derivatives at (t, s = 1 - t), with s
 * passed in exactly (s = (seg - k) / seg) so that b_j(t) and b_{3-j}(s)
 * are the same expressions. */
static void mesh_bernstein(double t, double s, double b[4], double d[4])
{
    b[0] = s * s * s;
    b[1] = 3.0 * (s * s) * t;
    b[2] = 3.0 * (t * t) * s;
    b[3] = t * t * t;
    d[0] = -3.0 * (s * s);
    d[1] = 3.0 * s * (s - 2.0 * t);
    d[2] = 3.0 * t * (2.0 * s - t);
    d[3] = 3.0 * (t * t);
}

/* Position and partial derivatives of patch k at (u, v). */
static void mesh_teapot_eval(int k, double u, double su, double v, double sv, v3 *p, v3 *pu,
                             v3 *pv)
{
    double bu[4], du[4], bv[4], dv[4];
    v3 P = v3_make(0, 0, 0), Pu = P, Pv = P;
    mesh_bernstein(u, su, bu, du);
    mesh_bernstein(v, sv, bv, dv);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            v3 c = v3_load(mesh_teapot_pts[mesh_teapot_patches[k][4 * i + j]]);
            P = v3_add(P, v3_scale(c, bu[i] * bv[j]));
            Pu = v3_add(Pu, v3_scale(c, du[i] * bv[j]));
            Pv = v3_add(Pv, v3_scale(c, bu[i] * dv[j]));
        }
    *p = P;
    *pu = Pu;
    *pv = Pv;
}

/* Unit normal of patch k at (u, v).  Where the derivatives are degenerate
 * (the collapsed first rows of the knob and bottom patches, whose four
 * control points coincide: dP/dv = 0 there), the normal is taken at a
 * point moved towards the patch centre by 1e-4, then 1e-3, 1e-2 in
 * parameter space, which is within that distance of the limit normal. */
static v3 mesh_teapot_normal(int k, double u, double su, double v, double sv)
{
    static const double steps[] = {1e-4, 1e-3, 1e-2};
    v3 p, pu, pv, n;

    mesh_teapot_eval(k, u, su, v, sv, &p, &pu, &pv);
    n = v3_cross(pu, pv);
    /* The derivatives are O(1) for this data (control points span ~6
     * units): a partial derivative below 1e-7 is rounding noise around a
     * collapsed edge, and so is the cross product then. */
    for (size_t a = 0; a < sizeof steps / sizeof steps[0] &&
                       (v3_len(pu) < 1e-7 || v3_len(pv) < 1e-7 || v3_len(n) < 1e-12);
         a++) {
        double uu = u < 0.5 ? u + steps[a] : u - steps[a];
        double vv = v < 0.5 ? v + steps[a] : v - steps[a];
        mesh_teapot_eval(k, uu, 1.0 - uu, vv, 1.0 - vv, &p, &pu, &pv);
        n = v3_cross(pu, pv);
    }
    /* In this data dP/du x dP/dv points into the teapot on every patch
     * (rows run top to bottom, columns counter-clockwise seen from +z):
     * the outward normal is the opposite. */
    return v3_scale(v3_normalize(n), -1.0);
}

/* Make coincident vertices bit-identical: patches sharing an edge evaluate
 * it from the same control points, possibly in opposite directions, which
 * can differ in the last bit.  Vertices within `tol` (max norm) of an
 * earlier one in x-sorted order take its position exactly. */
typedef struct mesh_snap_key { float x; uint32_t i; } mesh_snap_key;

static int mesh_snap_key_cmp(const void *a, const void *b)
{
    const mesh_snap_key *p = a, *q = b;
    if (p->x < q->x) return -1;
    if (p->x > q->x) return 1;
    return p->i < q->i ? -1 : p->i > q->i;
}

static int mesh_snap_positions(mesh *m, float tol, glint_err *err)
{
    size_t n = (size_t)m->nverts;
    mesh_snap_key *k = malloc(n * sizeof *k);
    unsigned char *done = calloc(n, 1);
    if (!k || !done) {
        free(k);
        free(done);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory welding %zu vertices", n);
    }
    for (size_t i = 0; i < n; i++) {
        k[i].x = m->pos[3 * i];
        k[i].i = (uint32_t)i;
    }
    qsort(k, n, sizeof *k, mesh_snap_key_cmp);
    for (size_t a = 0; a < n; a++) {
        const float *p;
        if (done[k[a].i])
            continue;
        p = m->pos + 3 * (size_t)k[a].i;
        for (size_t b = a + 1; b < n && k[b].x - k[a].x <= tol; b++) {
            float *q = m->pos + 3 * (size_t)k[b].i;
            if (done[k[b].i])
                continue;
            if (fabsf(q[0] - p[0]) <= tol && fabsf(q[1] - p[1]) <= tol &&
                fabsf(q[2] - p[2]) <= tol) {
                q[0] = p[0];
                q[1] = p[1];
                q[2] = p[2];
                done[k[b].i] = 1;
            }
        }
    }
    free(k);
    free(done);
    return 0;
}

static int mesh_same_pos(const float *a, const float *b)
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

/* Layout: patch k owns (seg + 1)^2 vertices, vertex (i, j) (u = i / seg,
 * v = j / seg) at k (seg + 1)^2 + i (seg + 1) + j; patches are not welded
 * (each has its own uv cell) but coincident positions are made identical,
 * so shared edges rasterize without cracks.  uv atlas: a 6 x 6 grid of
 * cells of side 1/6, patch k in column k mod 6, row k / 6, its (u, v)
 * square inset by 2% of the cell on each side: no two patches share a
 * texel.  Triangles with two coincident corners (at the collapsed knob and
 * bottom centres) are left out.  Finally centred and scaled into the unit
 * ball (mesh_normalize). */
int mesh_teapot(mesh *out, int seg, glint_err *err)
{
    const int np = 32;
    long long per, nverts, maxtris;
    uint32_t *t;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_teapot: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (seg < 1 || seg > MESH_TEAPOT_MAX_SEG)
        return glint_err_set(err, GLINT_ERANGE, "teapot segments %d outside 1..%d", seg,
                             MESH_TEAPOT_MAX_SEG);
    per = (long long)(seg + 1) * (seg + 1);
    nverts = np * per;
    maxtris = 2LL * np * seg * seg;
    rc = mesh_alloc(out, nverts, maxtris, err);
    if (rc)
        return rc;

    for (int k = 0; k < np; k++) {
        double cu = (double)(k % 6), cv = (double)(k / 6);
        for (int i = 0; i <= seg; i++) {
            double u = (double)i / seg, su = (double)(seg - i) / seg;
            for (int j = 0; j <= seg; j++) {
                double v = (double)j / seg, sv = (double)(seg - j) / seg;
                size_t vi = (size_t)(k * per + (long long)i * (seg + 1) + j);
                v3 p, pu, pv, n;
                mesh_teapot_eval(k, u, su, v, sv, &p, &pu, &pv);
                n = mesh_teapot_normal(k, u, su, v, sv);
                v3_storef(p, out->pos + 3 * vi);
                v3_storef(n, out->nrm + 3 * vi);
                out->uv[2 * vi] = (float)((cu + 0.02 + 0.96 * u) / 6.0);
                out->uv[2 * vi + 1] = (float)((cv + 0.02 + 0.96 * v) / 6.0);
            }
        }
    }
    mesh_normalize(out, NULL, NULL);
    rc = mesh_snap_positions(out, 1e-6f, err);
    if (rc)
        goto fail;

    t = out->tri;
    for (int k = 0; k < np; k++)
        for (int i = 0; i < seg; i++)
            for (int j = 0; j < seg; j++) {
                uint32_t a = (uint32_t)(k * per + (long long)i * (seg + 1) + j);
                uint32_t b = a + (uint32_t)(seg + 1), c = a + 1, d = b + 1;
                uint32_t tri2[2][3] = {{a, b, d}, {a, d, c}};
                for (int h = 0; h < 2; h++) {
                    uint32_t *f = tri2[h];
                    const float *p0 = out->pos + 3 * (size_t)f[0];
                    const float *p1 = out->pos + 3 * (size_t)f[1];
                    const float *p2 = out->pos + 3 * (size_t)f[2];
                    if (mesh_same_pos(p0, p1) || mesh_same_pos(p1, p2) || mesh_same_pos(p0, p2))
                        continue;
                    /* reversed: dP/dv x dP/du is the outward side */
                    *t++ = f[0];
                    *t++ = f[2];
                    *t++ = f[1];
                }
            }
    out->ntris = (int)((t - out->tri) / 3);
    {
        uint32_t *shrunk = realloc(out->tri, (size_t)out->ntris * 3 * sizeof *shrunk);
        if (shrunk)
            out->tri = shrunk;
    }
    return 0;

fail:
    mesh_free(out);
    return rc;
}

int mesh_builtin(const char *name, mesh *out, glint_err *err)
{
    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_builtin: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (!name)
        return glint_err_set(err, GLINT_EINVAL, "mesh_builtin: mesh name is NULL");
    if (strcmp(name, "sphere") == 0)
        return mesh_sphere_default(out, err);
    if (strcmp(name, "torus") == 0)
        return mesh_torus(out, MESH_TORUS_DEFAULT_R, MESH_TORUS_DEFAULT_MINOR,
                          MESH_TORUS_DEFAULT_NU, MESH_TORUS_DEFAULT_NV, err);
    if (strcmp(name, "teapot") == 0)
        return mesh_teapot(out, MESH_TEAPOT_DEFAULT_SEG, err);
    return glint_err_set(err, GLINT_ENOTFOUND,
                         "unknown built-in mesh \"%.64s\" (known: sphere, torus, teapot)", name);
}

/* The checks of mesh_validate over whole arrays, without an early exit, so
 * that they vectorize (a built-in sphere of 131,839 vertices is validated
 * on every load of its scene); the loops that name the first fault run
 * only when one of these finds one. */
static int any_index_at_least(const uint32_t *a, size_t n, uint32_t lim)
{
    int bad = 0;
#pragma omp simd reduction(| : bad)
    for (size_t i = 0; i < n; i++)
        bad |= a[i] >= lim;
    return bad;
}

static int any_nonfinite_f32(const float *a, size_t n)
{
    int bad = 0;
#pragma omp simd reduction(| : bad)
    for (size_t i = 0; i < n; i++)
        bad |= !(fabsf(a[i]) <= FLT_MAX); /* NaN fails the comparison */
    return bad;
}

int mesh_validate(const mesh *m, glint_err *err)
{
    size_t nv, nt;

    if (!m)
        return glint_err_set(err, GLINT_EINVAL, "mesh is NULL");
    if (m->nverts < 3 || m->nverts > INT_MAX / 3)
        return glint_err_set(err, GLINT_EFORMAT, "mesh vertex count %d outside 3..%d",
                             m->nverts, INT_MAX / 3);
    if (m->ntris < 1 || m->ntris > INT_MAX / 3)
        return glint_err_set(err, GLINT_EFORMAT, "mesh triangle count %d outside 1..%d",
                             m->ntris, INT_MAX / 3);
    if (!m->pos || !m->nrm || !m->uv || !m->tri)
        return glint_err_set(err, GLINT_EFORMAT, "mesh has a missing array (%s%s%s%s)",
                             m->pos ? "" : " pos", m->nrm ? "" : " nrm",
                             m->uv ? "" : " uv", m->tri ? "" : " tri");
    nv = (size_t)m->nverts;
    nt = (size_t)m->ntris;
    if (!any_index_at_least(m->tri, 3 * nt, (uint32_t)m->nverts) &&
        !any_nonfinite_f32(m->pos, 3 * nv) && !any_nonfinite_f32(m->nrm, 3 * nv) &&
        !any_nonfinite_f32(m->uv, 2 * nv))
        return 0;
    /* something is wrong: find the first fault, for the message */
    for (size_t i = 0; i < 3 * nt; i++)
        if (m->tri[i] >= (uint32_t)m->nverts)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "mesh triangle %zu: vertex index %u out of range (%d vertices)",
                                 i / 3, m->tri[i], m->nverts);
    for (size_t i = 0; i < 3 * nv; i++) {
        if (!isfinite(m->pos[i]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "mesh vertex %zu: position is not finite", i / 3);
        if (!isfinite(m->nrm[i]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "mesh vertex %zu: normal is not finite", i / 3);
    }
    for (size_t i = 0; i < 2 * nv; i++)
        if (!isfinite(m->uv[i]))
            return glint_err_set(err, GLINT_ENONFINITE,
                                 "mesh vertex %zu: texture coordinate is not finite", i / 2);
    return 0;
}

void mesh_free(mesh *m)
{
    if (!m)
        return;
    free(m->pos);
    free(m->nrm);
    free(m->uv);
    free(m->tri);
    memset(m, 0, sizeof *m);
}
