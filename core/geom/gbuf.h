/* gbuf.h: per-view geometry buffers (G-buffers).
 *
 * One gbuf per view, width x height pixels, row-major with row 0 at the
 * top.  For pixels with mask == 0 every other channel is zero.  Directions
 * are unit vectors pointing away from the surface: wi towards the light,
 * wo towards the camera.  A gbuf owns its arrays; gbuf_free() accepts NULL
 * and half-built buffers. */
#ifndef GLINT_GBUF_H
#define GLINT_GBUF_H

#include <stddef.h>
#include <stdint.h>

#include "err.h"

typedef struct gbuf {
    int width, height;
    uint8_t *mask; /* 1 where the surface covers the pixel centre */
    float *pos;    /* 3 per pixel: world position */
    float *nrm;    /* 3 per pixel: unit shading normal */
    float *uv;     /* 2 per pixel: texture coordinates */
    float *wi;     /* 3 per pixel: unit direction to the light */
    float *wo;     /* 3 per pixel: unit direction to the camera */
} gbuf;

/* Allocate a zeroed gbuf of the given size (OUT: *g). */
int gbuf_alloc(gbuf *g, int width, int height, glint_err *err);
void gbuf_free(gbuf *g);

/* Number of pixels with mask set. */
long gbuf_count(const gbuf *g);

/* Write the gbuf to an OpenEXR file with named float channels:
 *   mask, P.X P.Y P.Z, N.X N.Y N.Z, uv.U uv.V, wi.X wi.Y wi.Z, wo.X wo.Y wo.Z,
 *   cos_i (n.wi) and cos_o (n.wo).
 * These are exactly the values glint reads when it samples a painting of
 * this view: a pixel is a sample when mask = 1, cos_i > 0 and cos_o > 0. */
int gbuf_write_exr(const gbuf *g, const char *path, glint_err *err);

/* The same file's bytes (OUT: *out malloc'ed, *len). */
int gbuf_exr_mem(const gbuf *g, void **out, size_t *len, glint_err *err);

/* A G-buffer made elsewhere (a renderer's AOVs), or by gbuf_write_exr: an
 * image with named float channels N.X N.Y N.Z, wi.X wi.Y wi.Z and wo.X
 * wo.Y wo.Z (required; names case-insensitive, "N.x" and "Nx" too), mask
 * (optional: where absent, a pixel is covered when its three vectors are
 * non-zero), P.X P.Y P.Z and uv.U uv.V (optional; uv clamped to [0,1]).
 * Vectors are normalized; a covered pixel with a zero or non-finite vector
 * is an error naming it.  OUT: *g, *has_uv (1 when uv channels were read:
 * what methods that vary over the surface need). */
struct img_named;
int gbuf_from_named(const struct img_named *im, const char *what, gbuf *g, int *has_uv,
                    glint_err *err);
int gbuf_read_exr(const char *path, gbuf *g, int *has_uv, glint_err *err);
/* The same with the light's direction optional (need_wi 0: methods lit by
 * an environment, which read N and wo only): where wi.X wi.Y wi.Z are
 * absent, wi is left zero (so n.wi = 0) and *has_wi is 0; with need_wi 1
 * their absence is an error naming them and what needs them. */
int gbuf_from_named_ex(const struct img_named *im, const char *what, int need_wi, gbuf *g,
                       int *has_uv, int *has_wi, glint_err *err);

/* A content hash of n G-buffers (OUT: hex, 32 digits): what keys the
 * precomputations of samples made from them. */
void gbuf_hash(const gbuf *g, int n, char hex[33]);

#endif
