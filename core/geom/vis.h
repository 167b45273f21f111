/* vis.h: visibility of directions from surface points by ray casting
 * (Embree 3), and whether a mesh can shadow itself at all.
 *
 * A point p with normal n sees direction d when n.d > 0 and the ray
 * p + eps n + t d (t > 0) hits no triangle of the mesh; eps is
 * VIS_EPS x the mesh's bounding radius (self-intersection guard).  Bits
 * are packed per point: word w of point i holds directions 64 w .. 64 w + 63,
 * bit b set when direction 64 w + b is seen.
 *
 * Thread-safety: a vis_scene is read-only once built; vis_compute may be
 * called from several threads on one scene and uses `nthreads` threads of
 * its own. */
#ifndef GLINT_VIS_H
#define GLINT_VIS_H

#include <stdint.h>

#include "cancel.h"
#include "err.h"
#include "mesh.h"

#define VIS_EPS 1e-4

typedef struct vis_scene vis_scene;

/* Build the ray-casting structure of a mesh (OUT: *out). */
int vis_open(const mesh *m, vis_scene **out, glint_err *err);
void vis_close(vis_scene *v);  /* accepts NULL */

/* Words per point for k directions. */
#define VIS_WORDS(k) (((k) + 63) / 64)

/* OUT: bits[npoints * VIS_WORDS(k)].  pos and nrm: 3 floats per point;
 * dirs: 3 doubles per direction (unit).  nthreads <= 0: the machine's
 * cores.  Also counts the rays cast (OUT: *rays, may be NULL).  cancel
 * (may be NULL) is asked by each thread about every GLINT_CANCEL_WORK rays:
 * GLINT_ECANCELLED once it says to stop (bits then undefined). */
int vis_compute(const vis_scene *v, int npoints, const float *pos, const float *nrm, int k,
                const double *dirs, uint64_t *bits, int nthreads, long *rays,
                const glint_cancel *cancel, glint_err *err);

/* 1 when the mesh is closed, consistently oriented and convex (no point of
 * it can shadow another: every edge's dihedral angle is convex within
 * `tol` radians and the surface is one closed piece); 0 otherwise.
 * Vertices are welded by position first (within 1e-6 of the bounding
 * radius), so seams of duplicated vertices and degenerate triangles at
 * poles do not open the surface.  Open meshes count as not convex. */
int vis_mesh_convex(const mesh *m, double tol);

#endif
