/* gbfit.h: fitting G-buffers and paintings made elsewhere (a renderer's
 * AOVs): what `glint fit-gbuffers` and glintd's G-buffer sets share.
 *
 * A G-buffer set is n views of one raster size, each a G-buffer with named
 * channels (gbuf.h: gbuf_from_named_ex) and, optionally, its RGB painting
 * under a light of intensity 1 (scene.h: pi f cos_i).  The painted views form the sampling pattern by the
 * method's rule (samples.h: SAMPLES_LIT for point-light methods, which need
 * wi; SAMPLES_SEEN for methods lit by an environment, which read N and wo
 * only), keyed by the G-buffers' content (gbuf_hash); the values are the
 * paintings at the samples.  The result goes to prep_acquire_samples and
 * prep_fit like any pattern.  Without a scene there is no mesh: methods
 * that cast shadows (srbf's visibility) run without them, and those that
 * vary over the surface need uv channels in every G-buffer.
 *
 * Ownership: outputs are the caller's (gbuf_free, samples_free, free).
 * Thread-safety: no global state. */
#ifndef GLINT_GBFIT_H
#define GLINT_GBFIT_H

#include <stddef.h>

#include "err.h"
#include "gbuf.h"
#include "img.h"
#include "method.h"
#include "samples.h"

/* Whether method m needs the light's direction (wi channels): 1 for
 * point-light methods. */
int gbfit_needs_wi(const method *m);

/* One view's G-buffer for method m, from an image file or from memory (an
 * upload; sides at most max_dim and channels at most max_channels, checked
 * before decoding, and the header seen by check(cls, header) first when
 * check is not NULL: img_read_named_mem_checked).  m NULL: wi optional
 * (checking an upload before any method is chosen).  `what` names it
 * in messages.  OUT: *g, *has_uv (uv channels were read), *has_wi. */
int gbfit_gbuf_file(const method *m, const char *path, gbuf *g, int *has_uv, int *has_wi,
                    glint_err *err);
int gbfit_gbuf_mem(const method *m, const void *data, size_t len, int max_dim,
                   int max_channels, img_header_check check, void *cls, const char *what,
                   gbuf *g, int *has_uv, int *has_wi, glint_err *err);

/* The samples and painted values of n views (1..SCENE_MAX_VIEWS) for method
 * m: g[n] and paintings[n], read where use[v] is set (G-buffers of one
 * size, each painting its G-buffer's size, 1, 3 or 4 channels; unused
 * entries may be zeroed: they only enter the hash); has_uv: every
 * G-buffer had uv channels.  Checks sizes (naming the view), that a view is
 * painted, that methods whose material varies over the surface
 * (material_ops.spatial, and auto, whose candidates do) have uv, and that the painted views hold a
 * sample.  OUT: *s (has_pos =
 * has_uv), *rgb (3 s->n values, malloc'ed). */
int gbfit_samples(const method *m, const gbuf *g, const img *paintings,
                  const unsigned char *use, int n, int has_uv, samples *s, float **rgb,
                  glint_err *err);

#endif
