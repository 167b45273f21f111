/* auto_split.h: what the automatic choices (method_auto.c, method_auto_env.c)
 * share to hold samples out.  Private to core/methods/auto. */
#ifndef GLINT_AUTO_SPLIT_H
#define GLINT_AUTO_SPLIT_H

/* Held out by pixel (one view painted): tiles of 8 x 8 pixels, one in
 * `every` by a hash of the tile, so the split is the same for every
 * painting of a pattern and a spatial model cannot fill a held pixel from
 * painted neighbours a pixel away.  1 when pixel (row * width + col) of
 * view is held. */
int auto_pixel_held(int view, int pixel, int width, int every);

#endif
