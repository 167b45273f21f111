/* mesh.h: indexed triangle meshes and glint's built-in shapes.
 *
 * A mesh owns its arrays (allocated with malloc); mesh_free() releases them
 * and accepts NULL or a zeroed / half-built mesh.  Positions, normals and
 * texture coordinates are per vertex; triangles are counter-clockwise seen
 * from outside.  Built-in shapes are centred at the origin and fit in the
 * unit ball, so the default views frame them.  Loading meshes from files
 * plugs in here later (mesh_load): the rest of core only sees `mesh`. */
#ifndef GLINT_MESH_H
#define GLINT_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "err.h"

typedef struct mesh {
    int nverts;
    int ntris;
    float *pos;    /* 3 * nverts: x y z */
    float *nrm;    /* 3 * nverts: unit normals */
    float *uv;     /* 2 * nverts: texture coordinates in [0,1] */
    uint32_t *tri; /* 3 * ntris: vertex indices */
} mesh;

/* Limits on built-in tessellation parameters. */
#define MESH_SPHERE_MIN_SEG 3
#define MESH_SPHERE_MAX_SEG 4096

/* Unit sphere at the origin as a latitude-longitude grid: `nlat` rings of
 * quads between the poles (>= 2) and `nlon` segments around (>= 3).
 * Normals are the exact sphere normals (= positions); uv = (phi / 2pi,
 * theta / pi) with the seam duplicated.  Returns 0 or GLINT_ERANGE /
 * GLINT_ENOMEM; *out is zeroed first and owned by the caller. */
int mesh_sphere(mesh *out, int nlat, int nlon, glint_err *err);

/* The default built-in sphere used by scenes named "sphere": fine enough
 * that its facets are far below a pixel at 1024x1024 (256 x 512). */
int mesh_sphere_default(mesh *out, glint_err *err);

/* Build a built-in shape by name ("sphere").  GLINT_ENOTFOUND for an
 * unknown name, with the list of known names in the message. */
int mesh_builtin(const char *name, mesh *out, glint_err *err);

/* Check a mesh for use: counts in range, indices in range, coordinates
 * and normals finite.  Returns 0 or GLINT_EFORMAT / GLINT_ENONFINITE. */
int mesh_validate(const mesh *m, glint_err *err);

/* Release the arrays and zero *m.  Accepts NULL. */
void mesh_free(mesh *m);

#endif
