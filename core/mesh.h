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

/* Build a built-in shape by name ("sphere", "torus", "teapot").
 * GLINT_ENOTFOUND for an unknown name, with the list of known names in the
 * message. */
int mesh_builtin(const char *name, mesh *out, glint_err *err);

/* ---- procedural built-ins (no files needed) ---------------------------- */

/* Torus around the z axis, major radius R, minor radius r (R > r > 0),
 * `nu` segments around the axis and `nv` around the tube; uv = (u, v)
 * angles / 2pi.  Scaled to fit the unit ball. */
int mesh_torus(mesh *out, double R, double r, int nu, int nv, glint_err *err);

/* The Utah teapot from its 32 bicubic Bezier patches, each tessellated
 * `seg` x `seg`; normals from the patch derivatives (degenerate points
 * handled), uv per patch in a documented atlas.  Fits the unit ball. */
int mesh_teapot(mesh *out, int seg, glint_err *err);

/* ---- meshes from files ---------------------------------------------------- */

#define MESH_MAX_TRIS (1 << 24)    /* 16.7M triangles */
#define MESH_MAX_FILE_BYTES ((size_t)1 << 30)

/* What loading decided, for reports and manifests. */
typedef struct mesh_report {
    int nverts, ntris;         /* after cleaning */
    int dropped_degenerate;    /* zero-area or repeated-index triangles removed */
    int normals_generated;     /* 1 if smooth normals were computed */
    int uvs_generated;         /* 1 if the automatic parameterization was used */
    int nonmanifold_edges;     /* edges shared by more than two triangles (usable) */
    int boundary_edges;        /* edges of a single triangle (open mesh) */
    double scale;              /* applied: unit-ball normalization factor */
    double center[3];          /* applied: subtracted before scaling */
    char format[16];           /* "ply", "obj", "off", "gltf", "dae", ... */
} mesh_report;

/* Load a mesh file through assimp (OBJ, PLY, OFF, glTF 2.0, COLLADA and
 * whatever else assimp reads), merge all its meshes, triangulate, then
 * clean and normalize: non-finite coordinates -> GLINT_ENONFINITE; empty ->
 * GLINT_EFORMAT; over MESH_MAX_TRIS or MESH_MAX_FILE_BYTES -> GLINT_ERANGE;
 * zero-area triangles dropped (counted); normals from the file or smooth
 * area-weighted ones; uvs from the file or generated (mesh_generate_uvs);
 * centred and scaled into the unit ball (mesh_normalize).  report may be
 * NULL.  *out is owned by the caller. */
int mesh_load(const char *path, mesh *out, mesh_report *report, glint_err *err);

/* The same from a buffer in memory (an upload); `hint` is the format's file
 * extension ("ply", "obj", "glb", ...). */
int mesh_load_mem(const void *data, size_t len, const char *hint, mesh *out,
                  mesh_report *report, glint_err *err);

/* Smooth per-vertex normals, area-weighted (replaces m->nrm). */
int mesh_compute_normals(mesh *m, glint_err *err);

/* glint's automatic parameterization for meshes without texture
 * coordinates (replaces m->uv, may split vertices at chart seams); the
 * method is documented at its definition. */
int mesh_generate_uvs(mesh *m, glint_err *err);

/* Translate the bounding-box centre to the origin and scale so every vertex
 * lies in the unit ball (OUT: *scale, center[3]; either may be NULL). */
void mesh_normalize(mesh *m, double *scale, double center[3]);

/* Check a mesh for use: counts in range, indices in range, coordinates
 * and normals finite.  Returns 0 or GLINT_EFORMAT / GLINT_ENONFINITE. */
int mesh_validate(const mesh *m, glint_err *err);

/* Release the arrays and zero *m.  Accepts NULL. */
void mesh_free(mesh *m);

#endif
