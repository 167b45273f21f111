/* mesh.h: indexed triangle meshes and glint's built-in shapes.
 *
 * A mesh owns its arrays (allocated with malloc); mesh_free() releases them
 * and accepts NULL or a zeroed / half-built mesh.  Positions, normals and
 * texture coordinates are per vertex; triangles are counter-clockwise seen
 * from outside.  Built-in shapes are centred at the origin and fit in the
 * unit ball, so the default views frame them.  Meshes from files come in
 * through mesh_load (mesh_io.c), normalized the same way: the rest of core
 * only sees `mesh`. */
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
 * `seg` x `seg` (1..MESH_TEAPOT_MAX_SEG); normals from the patch
 * derivatives (degenerate points handled), uv per patch in a documented
 * atlas.  Fits the unit ball. */
int mesh_teapot(mesh *out, int seg, glint_err *err);

#define MESH_TEAPOT_MAX_SEG 512

/* Parameters of the built-in "torus" and "teapot" (mesh_builtin). */
#define MESH_TORUS_DEFAULT_R 0.7
#define MESH_TORUS_DEFAULT_MINOR 0.3
#define MESH_TORUS_DEFAULT_NU 512   /* segments around the axis */
#define MESH_TORUS_DEFAULT_NV 256   /* segments around the tube */
#define MESH_TEAPOT_DEFAULT_SEG 16

/* The teapot's Bezier control data, for tests and tools (OUT, each may be
 * NULL): 306 control points and 32 patches of 16 zero-based indices, row
 * by row.  Static storage, never freed. */
void mesh_teapot_data(const double (**points)[3], int *npoints,
                      const uint16_t (**patches)[16], int *npatches);

/* ---- meshes from files ---------------------------------------------------- */

#define MESH_MAX_TRIS (1 << 24)    /* 16.7M triangles */
#define MESH_MAX_VERTS (3 * MESH_MAX_TRIS) /* vertices, and any PLY element count */
#define MESH_MAX_FILE_BYTES ((size_t)1 << 30)
/* Time limit of one import (assimp runs in a child process, see mesh_load). */
#define MESH_IMPORT_TIMEOUT_S 300

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
    int dropped_primitives;    /* points, lines (and faces assimp could not triangulate) ignored */
    int uvs_rescaled;          /* 1 if the file's uvs left [0,1]^2 and were moved into it */
    int uv_charts;             /* charts of the generated parameterization (0 if none) */
    double uv_coverage;        /* fraction of [0,1]^2 covered by uv triangles */
} mesh_report;

/* Load a mesh file through assimp (OBJ, PLY, OFF, glTF 2.0, COLLADA and
 * whatever else assimp reads), merge all its meshes, triangulate, then
 * clean and normalize: missing file -> GLINT_ENOTFOUND; non-finite
 * coordinates -> GLINT_ENONFINITE (naming the vertex); empty, truncated,
 * unreadable or without triangles -> GLINT_EFORMAT (with assimp's message
 * where it has one); over MESH_MAX_TRIS, MESH_MAX_FILE_BYTES or a PLY/OFF
 * header claiming more, or an import needing more memory or time than
 * allowed -> GLINT_ERANGE; zero-area triangles dropped (counted); normals
 * from the file or smooth area-weighted ones; uvs from the file or
 * generated (mesh_generate_uvs); centred and scaled into the unit ball
 * (mesh_normalize).  assimp runs in a forked child process (time limit
 * MESH_IMPORT_TIMEOUT_S, a memory limit), so a file that crashes or hangs
 * it is an error, never the caller's crash; safe to call from several
 * threads at once.  report may be NULL (it is zeroed on failure).  *out is
 * zeroed first and owned by the caller.  Steps and limits in mesh_io.c.
 *
 * References to other files (glTF buffers and images, OBJ material
 * libraries, COLLADA images) may name files in the mesh file's directory
 * or below it, and nothing else is ever read: an absolute path, a ".."
 * that leaves the directory, or a URI with a scheme other than data: ->
 * GLINT_EINVAL naming the reference (rules in mesh_fileio.c). */
int mesh_load(const char *path, mesh *out, mesh_report *report, glint_err *err);

/* The same from a buffer in memory (an upload); `hint` is the format's file
 * extension ("ply", "obj", "glb", ...).  The buffer is read on its own: no
 * file is opened, whatever the data names.  data: URIs and a .glb's binary
 * chunk are part of the data.  A reference to a file the import needs (a
 * glTF buffer), or one mesh_load would refuse (also as a texture path), ->
 * GLINT_EINVAL "external references are not allowed in uploads", naming
 * the reference (truncated), the same whether such a file exists or not.
 * A plain relative name the import can do without (an OBJ mtllib, a glTF
 * image) is ignored: glint uses only the geometry. */
int mesh_load_mem(const void *data, size_t len, const char *hint, mesh *out,
                  mesh_report *report, glint_err *err);

/* The references to other files that an upload's bytes make, found in
 * their text whether or not anything uses them: glTF "uri" members at any
 * depth (buffers, images, extensions; also in a .glb's JSON chunk);
 * COLLADA <init_from> of an image and <ref> text, url= and source=
 * attributes that do not point into the document ('#'), DOCTYPE or
 * ENTITY literals after SYSTEM or PUBLIC; OBJ mtllib, maplib, call,
 * shadow_obj and trace_obj statements; PLY "comment TextureFile NAME".
 * data: URIs are part of the file.  0 when there is none; else
 * GLINT_EINVAL naming the first, in mesh_load_mem's words ("external
 * references are not allowed in uploads").  `fmt` is the upload's format
 * (ply, obj, off, gltf, glb, dae); glTF and COLLADA are also recognized by
 * their content.  Reads only `data`, in constant memory; a server calls it
 * on an upload before mesh_load_mem (which, for files it stored earlier,
 * still loads the geometry of an upload that names a plain relative file
 * it never reads). */
int mesh_refs_check(const void *data, size_t len, const char *fmt, glint_err *err);
/* mesh_load_mem with the host's triangle limit (max_tris, at most
 * MESH_MAX_TRIS): what the data's counts say before it is imported (PLY and
 * OFF headers, OBJ face lines; mesh_prescan.c) is held to it, GLINT_ERANGE
 * naming the count and the limit.  Formats without a count to read first
 * (glTF, COLLADA) are imported, and the caller checks the mesh it gets. */
int mesh_load_mem_max(const void *data, size_t len, const char *hint, long max_tris, mesh *out,
                      mesh_report *report, glint_err *err);

/* Import in the calling process instead of a child (on != 0).  Only for a
 * fuzzer, which must see the importer's coverage and wants its crashes, and
 * for a test under memcheck, which must see the import's memory: a malformed
 * file may then crash or hang the caller.  Set it before any import (it is
 * not synchronised with imports in flight). */
void mesh_import_in_process(int on);

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
