/* store.h: glintd's durable state in the data directory.
 *
 * Metadata lives in SQLite (data_dir/glint.db, WAL journal, synchronous=FULL
 * so a committed transaction survives a crash or kill -9); large blobs
 * (meshes, paintings, material files) live as files under data_dir/blobs/,
 * written atomically (fsio.h) BEFORE the row that names them is committed.
 * A call returns only after its data is durable: an answered request's
 * strokes, paintings and materials survive a crash.
 *
 * Ids are 128 random bits as 32 lowercase hex digits (getrandom).
 * Thread-safety: every function may be called from any thread; the store
 * serializes access internally.  Strings returned through char** and json_t**
 * are owned by the caller (free / json_decref).  Every function returns 0 or
 * a negative GLINT_E* code with a message (GLINT_ENOTFOUND for unknown ids). */
#ifndef GLINTD_STORE_H
#define GLINTD_STORE_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>

#include "err.h"

typedef struct store store;

int store_open(const char *data_dir, store **out, glint_err *err);
void store_close(store *s);

/* 128 random bits as 32 hex digits + NUL (OUT: id[33]). */
int store_new_id(char id[33], glint_err *err);

/* ---- blobs (files under data_dir/blobs) ------------------------------------ */
int store_blob_put(store *s, const char *name, const void *data, size_t len, glint_err *err);
int store_blob_get(store *s, const char *name, void **data, size_t *len, glint_err *err);
/* Absolute path of a blob (OUT: buf). */
int store_blob_path(store *s, const char *name, char *buf, size_t len, glint_err *err);
int store_blob_delete(store *s, const char *name, glint_err *err);

/* ---- meshes (uploaded files) -------------------------------------------------- */
/* info: {"format": "ply", "triangles": n, "bytes": n, ...}; the file is a blob. */
int store_mesh_put(store *s, const char *id, const json_t *info, const void *data, size_t len,
                   glint_err *err);
int store_mesh_get(store *s, const char *id, json_t **info, glint_err *err);

/* ---- scenes -------------------------------------------------------------------------- */
/* doc: the API's scene object (includes the glint scene JSON under "scene"). */
int store_scene_put(store *s, const char *id, const json_t *doc, glint_err *err);
int store_scene_get(store *s, const char *id, json_t **doc, glint_err *err);
int store_scene_list(store *s, json_t **array, glint_err *err);
int store_scene_delete(store *s, const char *id, glint_err *err);

/* ---- sessions ------------------------------------------------------------------------- */
/* doc holds scene_id, created, and the two tokens (paint_token, view_token). */
int store_session_put(store *s, const char *id, const json_t *doc, glint_err *err);
int store_session_get(store *s, const char *id, json_t **doc, glint_err *err);

/* Paintings: the current image of view `view` of a session, as OpenEXR
 * bytes (float RGB, the raster's size).  version increments on each put. */
int store_painting_put(store *s, const char *session, int view, const void *exr, size_t len,
                       int64_t *version, glint_err *err);
int store_painting_get(store *s, const char *session, int view, void **exr, size_t *len,
                       int64_t *version, glint_err *err);

/* Strokes: appended in one transaction with the painting they produced, so
 * the numbered history and the image never disagree.  OUT: *first_seq,
 * *last_seq (session-wide numbering from 1). */
int store_strokes_append(store *s, const char *session, int view, const json_t *strokes,
                         const void *exr, size_t len, int64_t *first_seq, int64_t *last_seq,
                         glint_err *err);
/* Strokes with seq > since, in order, as a JSON array of
 * {"seq", "view", "stroke", "created"}. */
int store_strokes_since(store *s, const char *session, int64_t since, json_t **array,
                        glint_err *err);

/* ---- materials ----------------------------------------------------------------------- */
/* doc: the API's material object; files (material.json, factors.*, shader
 * export) are blobs named "materials/<id>/<file>". */
int store_material_put(store *s, const char *id, const char *session, const json_t *doc,
                       glint_err *err);
int store_material_get(store *s, const char *id, json_t **doc, glint_err *err);
int store_material_list(store *s, const char *session, json_t **array, glint_err *err);

#endif
