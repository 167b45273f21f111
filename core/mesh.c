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

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

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

int mesh_builtin(const char *name, mesh *out, glint_err *err)
{
    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_builtin: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (!name)
        return glint_err_set(err, GLINT_EINVAL, "mesh_builtin: mesh name is NULL");
    if (strcmp(name, "sphere") == 0)
        return mesh_sphere_default(out, err);
    return glint_err_set(err, GLINT_ENOTFOUND,
                         "unknown built-in mesh \"%.64s\" (known: sphere)", name);
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
