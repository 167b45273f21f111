/* raster.h: deterministic CPU rasterizer producing G-buffers.
 *
 * Renders a mesh through a scene view's pinhole camera (conventions in
 * scene.h) into a gbuf: depth-tested, perspective-correct interpolation of
 * position, normal (renormalized) and uv, sampled at pixel centres with a
 * top-left fill rule so that a pixel on a shared edge belongs to exactly one
 * triangle.  The result depends only on the inputs (no threads racing, no
 * GL), so it defines glint's sampling pattern. */
#ifndef GLINT_RASTER_H
#define GLINT_RASTER_H

#include "err.h"
#include "gbuf.h"
#include "mesh.h"
#include "scene.h"

/* Rasterize `m` seen from view `v` at width x height into *out (allocated
 * here; caller frees with gbuf_free).  wi = normalize(light - P),
 * wo = normalize(eye - P).  Fails with GLINT_ERANGE on a size outside
 * [SCENE_MIN_SIZE, SCENE_MAX_SIZE], GLINT_EINVAL on a degenerate camera. */
int raster_view(const mesh *m, const scene_view *v, int width, int height,
                gbuf *out, glint_err *err);

/* Rows [row0, row0 + nrows) of the width x height view, exactly as
 * raster_view() computes them (same projection, coverage and depth order),
 * into a width x nrows gbuf (row 0 = row `row0`): for rendering large
 * images in bands with bounded memory.  GLINT_ERANGE for rows outside the
 * view. */
int raster_view_rows(const mesh *m, const scene_view *v, int width, int height, int row0,
                     int nrows, gbuf *out, glint_err *err);

/* Rasterize every view of a scene.  *out becomes a malloc'ed array of
 * s->nviews gbufs (caller frees each with gbuf_free, then free(*out)). */
int raster_scene(const scene *s, gbuf **out, glint_err *err);

/* Free an array of n gbufs as returned by raster_scene.  Accepts NULL. */
void raster_free_all(gbuf *g, int n);

#endif
