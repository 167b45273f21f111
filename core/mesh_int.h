/* mesh_int.h: internals shared by the mesh modules (mesh_geom.c: helpers,
 * normals, normalization; mesh_uv.c: the automatic parameterization;
 * mesh_io.c: loading files) and their tests.  Not part of core's contract. */
#ifndef GLINT_MESH_INT_H
#define GLINT_MESH_INT_H

#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "vec3.h"

/* Triangles with |cross| below this fraction of the squared bounding-box
 * diagonal are "zero-area" (twice the area threshold in mesh.h's docs):
 * dropped when loading, skipped when parameterizing. */
#define MIO_DEGENERATE_REL 1e-12

/* (key, value) pairs for radix sorting. */
typedef struct mio_pair {
    uint64_t key;
    uint32_t val;
} mio_pair;

int mio_alloc(mesh *m, size_t nverts, size_t ntris, int with_nrm, int with_uv,
              glint_err *err);
double mio_tri_cross_len(const float *pos, const uint32_t *f, v3 *n);
double mio_bbox_diag(const float *pos, size_t n);
int mio_weld(const float *pos, size_t n, uint32_t *canon, glint_err *err);
int mio_edges_sorted(const mesh *m, const uint32_t *canon, mio_pair **edges,
                     glint_err *err);
void mio_edge_stats(const mio_pair *e, size_t ne, int *boundary, int *nonmanifold);
void mio_radix_sort(mio_pair *a, mio_pair *tmp, size_t n);
uint32_t mio_fbits(float x);
int mio_uv_generate(mesh *m, int *ncharts, glint_err *err);
int mio_check_mesh(const mesh *m, const char *who, glint_err *err);

#endif
