/* scenes.h: the core scenes behind the stored scene documents, and their
 * base renders (what a view shows before anyone paints it, and what erase
 * strokes bring back).
 *
 * Thread-safety: every function may be called from any thread. */
#ifndef GLINTD_SCENES_H
#define GLINTD_SCENES_H

#include "app.h"
#include "err.h"
#include "img.h"
#include "scene.h"

/* Load the core scene of a stored scene (uncached: fitsvc_scene keeps
 * loaded scenes): doc["scene"] (the glint scene JSON) with its mesh built
 * (a built-in) or loaded from the uploaded file (doc["mesh_id"]).  OUT: *out
 * (free with scenes_unload). */
int scenes_load(struct store *st, const char *id, const scene **out, glint_err *err);
void scenes_unload(const scene *sc);

/* The base render of view `view` at `scale` times the raster a side (1, or
 * the scene's paint_scale: the image its sessions paint over): rendered
 * on the CPU (the reference, so it never changes for a scene) with the
 * BRDF and scale of the scene's doc["base"], cached as the blob
 * "scenes/<id>/base<view>.exr" ("base<view>x<scale>.exr" above 1).
 * GLINT_ENOTFOUND for an unknown scene or view.  OUT: *out, float RGB
 * (img_free). */
int scenes_base(app *a, const char *id, int view, int scale, img *out, glint_err *err);

/* The memory bound of a base render (what scenes_base admits against the
 * work budget): width x height at `scale` times a side, lit by the view's
 * light (env_lights 0) or by an environment compressed into env_lights
 * lights (the scene's base.env). */
size_t scenes_base_bytes(int width, int height, int scale, int env_lights);

/* The painting's scale of a scene document: its "paint_scale" (scenes made
 * before it existed: 1). */
int scenes_paint_scale(const json_t *doc);

#endif
