/* scene_int.h: internals shared by the files of the scene module.  Not
 * part of core's contract (that is scene.h); only scene*.c and tests
 * include it.
 *
 * The module, one concern per file:
 *   scene.c       parameters, the icosahedral view sets, views, validation
 *                 and creation from parameters
 *   scene_json.c  the scene document: JSON reading and writing, files
 *   scene_hash.c  the content hash */
#ifndef GLINT_SCENE_INT_H
#define GLINT_SCENE_INT_H

#include "err.h"
#include "scene.h"

/* Check one view (finite, non-degenerate camera, field of view, light);
 * `k` names it in the message ("views[k]..."). */
int scene_check_view(const scene_view *v, int k, glint_err *err);

/* Absolute form of a mesh file path (OUT: out[SCENE_PATH_MAX]): an absolute
 * path is kept as written; a relative one is joined to `base` (a directory;
 * NULL or "" for the working directory), and to the working directory if
 * `base` is itself relative.  No symbolic links are resolved and "." / ".."
 * stay as written. */
int scene_abs_path(const char *base, const char *path, char out[SCENE_PATH_MAX],
                   glint_err *err);

/* Load the scene's mesh: the file at out->mesh_path (absolute) or the
 * built-in out->mesh_name; fills out->mesh and out->mesh_info. */
int scene_load_mesh(scene *out, glint_err *err);

#endif
