/* store.h: glintd's durable state in the data directory.
 *
 * Metadata lives in SQLite (data_dir/glint.db, WAL journal, synchronous=FULL
 * so a committed transaction survives a crash or kill -9) or in PostgreSQL
 * (store_open_db; the same tables, commits durable: db.h); large blobs
 * (meshes, paintings, material files) live as files under data_dir/blobs/,
 * written atomically (fsio.h) BEFORE the row that names them is committed.
 * A call returns only after its data is durable: an answered request's
 * strokes, paintings and materials survive a crash.
 *
 * Schema (version STORE_SCHEMA_VERSION, recorded in table schema_version;
 * a database from a newer glintd is refused, never rewritten):
 *   meshes(id, info, created)             uploaded mesh files, blob "meshes/<id>.<format>"
 *   scenes(id, doc, created)              the API's scene objects
 *   sessions(id, scene_id, doc, created, last_seq)
 *   paintings(session, view, version, blob, updated)
 *                                         current image of a view, blob
 *                                         "sessions/<id>/view<k>-<random>.exr"
 *   events(session, seq, type, view, data, created)
 *                                         the session's durable event log:
 *                                         "stroke", "painting", "fit", ...
 *   materials(id, session, doc, created)
 * Every session has ONE sequence (sessions.last_seq): strokes, painting
 * uploads and published fits each take the next number, in commit order,
 * so a reader that has seen everything up to N asks for "seq > N" and gets
 * exactly what it missed.  A painting's blob gets a new name on every
 * version; the previous file is removed after the commit, and files left by
 * a crash between the two (or temporary files of an interrupted atomic
 * write) are swept when the store opens.
 *
 * Ids are 128 random bits as 32 lowercase hex digits (ids.h); times are
 * RFC 3339 UTC with milliseconds (clock.h).  The store keeps documents and
 * bytes: it never renders, fits or decodes images.
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

struct img; /* img.h */

#define STORE_SCHEMA_VERSION 1

/* A scene document's "radiance": the units of its base renders and
 * paintings (scene.h).  Documents without it are read as older ones
 * (store.c: their base scale pi becomes 1). */
#define STORE_SCENE_RADIANCE "pi I f cos_i: a white Lambertian facing a light of intensity I reads I"

typedef struct store store;

int store_open(const char *data_dir, store **out, glint_err *err);
/* The same with the metadata in PostgreSQL: `database` is a libpq
 * connection string (NULL or "": SQLite in data_dir, as store_open).  The
 * tables are created on first use, once, however many glintd processes
 * start together; blobs stay under data_dir/blobs, which processes sharing
 * the database must share too (one directory every replica mounts).  The
 * sweep at open then removes only files older than a write in progress
 * could be (STORE_SHARED_SWEEP_GRACE). */
int store_open_db(const char *data_dir, const char *database, store **out, glint_err *err);
/* Hear of other processes' changes (PostgreSQL): after any process on the
 * same database commits a stroke, painting or event to a session's log,
 * fn(ctx, session, "log") runs on a thread of the store's own (PostgreSQL
 * LISTEN/NOTIFY, on a connection of its own; this process's own commits
 * are heard too); after another process announced something of a session
 * (store_announce), fn(ctx, session, what).  When the connection was lost
 * and made again, notifications may have been missed: fn(ctx, NULL, NULL)
 * then means "any session may have changed".  The connection is retried
 * every second while the server is away.  SQLite: 0 and nothing (no other
 * process writes).  At most one listener per store; store_close stops it. */
int store_listen(store *s, void (*fn)(void *ctx, const char *session, const char *what),
                 void *ctx, glint_err *err);
/* Tell the other processes' listeners `what` ([a-z]{1,16}, e.g. "revoke":
 * the session's tokens were replaced) of a session, not this process's.
 * SQLite: 0 and nothing. */
int store_announce(store *s, const char *session, const char *what, glint_err *err);
/* Stop the listener (fn is not called after this returns; none: nothing). */
void store_listen_stop(store *s);

/* With a shared database (PostgreSQL), other glintd processes may share
 * the blob directory too: the sweep at open leaves files younger than this
 * (seconds), which a write in progress elsewhere may still be naming. */
#define STORE_SHARED_SWEEP_GRACE 600

/* "sqlite" or "postgresql". */
const char *store_backend(const store *s);
void store_close(store *s);

/* ---- blobs (files under data_dir/blobs) ------------------------------------ */
/* Names are relative paths of [A-Za-z0-9._-] segments separated by '/'
 * (no "..", no leading '/'); parent directories are created.  put writes
 * atomically and durably; get reads the whole file (OUT: *data malloc'ed,
 * NUL appended, *len); GLINT_ENOTFOUND when absent. */
int store_blob_put(store *s, const char *name, const void *data, size_t len, glint_err *err);
int store_blob_get(store *s, const char *name, void **data, size_t *len, glint_err *err);
/* Absolute path of a blob (OUT: buf). */
int store_blob_path(store *s, const char *name, char *buf, size_t len, glint_err *err);
int store_blob_delete(store *s, const char *name, glint_err *err);
/* Wait until the files of replaced paintings queued for removal are gone
 * (a painting's commit removes the version it replaces off its request's
 * path; store_close waits as well). */
void store_reap_wait(store *s);
/* Remove the blob directory tree `name` (best effort: what cannot be
 * removed stays, for the sweep when the store opens). */
void store_blob_rmtree(store *s, const char *name);
/* The regular files directly in the blob directory `name`, sorted (OUT:
 * *names, an array of strings; empty when the directory does not exist). */
int store_blob_list(store *s, const char *name, json_t **names, glint_err *err);

/* ---- meshes (uploaded files) -------------------------------------------------- */
/* info: {"format": "ply", "triangles": n, "bytes": n, ...}; the file is the
 * blob "meshes/<id>.<format>" (store_mesh_data reads it back). */
int store_mesh_put(store *s, const char *id, const json_t *info, const void *data, size_t len,
                   glint_err *err);
int store_mesh_get(store *s, const char *id, json_t **info, glint_err *err);
/* The uploaded file's bytes and its format (OUT: *data malloc'ed, *len,
 * format[16]). */
int store_mesh_data(store *s, const char *id, void **data, size_t *len, char format[16],
                    glint_err *err);

/* ---- scenes -------------------------------------------------------------------------- */
/* doc: the API's scene object (includes the glint scene JSON under "scene"). */
int store_scene_put(store *s, const char *id, const json_t *doc, glint_err *err);
int store_scene_get(store *s, const char *id, json_t **doc, glint_err *err);
/* Every scene's doc, oldest first. */
int store_scene_list(store *s, json_t **array, glint_err *err);
/* How many scenes' docs hold `text` (the stored JSON text, e.g.
 * "\"upload:<id>\"" for the scenes whose base renders an environment
 * lights); text must hold no '%', '_' or '\\' (GLINT_EINVAL).  OUT: *n. */
int store_scene_count_naming(store *s, const char *text, long long *n, glint_err *err);
/* Deletes the scene, its sessions with their events and paintings, the
 * materials fitted in them, and the blobs under "scenes/<id>/",
 * "sessions/<session>/" and "materials/<material>/". */
int store_scene_delete(store *s, const char *id, glint_err *err);

/* ---- sessions ------------------------------------------------------------------------- */
/* doc holds scene_id, created, the two tokens (paint_token, view_token)
 * and, for links that expire, expires (ISO time) and expires_unix.
 * put: GLINT_ENOTFOUND if the scene does not exist.  get: the stored doc
 * with "last_seq" (the session's last sequence number, 0 if none) added. */
int store_session_put(store *s, const char *id, const json_t *doc, glint_err *err);
int store_session_get(store *s, const char *id, json_t **doc, glint_err *err);
/* Replace a session's doc (its tokens, its expiry), durably; "last_seq" is
 * not stored.  GLINT_ENOTFOUND if there is no such session. */
int store_session_update(store *s, const char *id, const json_t *doc, glint_err *err);

/* Paintings: the current image of view `view` of a session, as the bytes
 * of an image file of the raster's size: the PNG, JPEG or OpenEXR a client
 * uploaded, as it came (validated before), or the float RGB OpenEXR of a
 * view painted by strokes; the blob's name ends in the format's extension,
 * told by its first bytes.  version increments on each put
 * (strokes included), from 1.  put also appends a "painting" event
 * ({"view", "version"}) to the session's log in the same transaction
 * (OUT: *seq, may be NULL).  get: GLINT_ENOTFOUND when the view was never
 * painted (the caller then uses the base render). */
int store_painting_put(store *s, const char *session, int view, const void *exr, size_t len,
                       int64_t *version, int64_t *seq, glint_err *err);
/* The same, only if the view is still at painting version `base` (0: never
 * painted; -1: no check): GLINT_ECONFLICT otherwise (store_strokes_append_at). */
int store_painting_put_at(store *s, const char *session, int view, int64_t base,
                          const void *exr, size_t len, int64_t *version, int64_t *seq,
                          glint_err *err);
/* store_painting_put_at in two steps, so that a caller may write the blob
 * while it checks the image: blob_put writes the bytes durably as a new
 * blob of the view (OUT: its name, namelen >= 160), which nothing names
 * yet; commit_at then does what put_at does after writing, or removes the
 * blob if the commit fails.  A blob never committed: the caller removes it
 * (store_blob_delete), or store_sweep does after a crash. */
int store_painting_blob_put(store *s, const char *session, int view, const void *data,
                            size_t len, char *name, size_t namelen, glint_err *err);
int store_painting_commit_at(store *s, const char *session, int view, int64_t base,
                             const char *blob, int64_t *version, int64_t *seq, glint_err *err);
int store_painting_get(store *s, const char *session, int view, void **exr, size_t *len,
                       int64_t *version, glint_err *err);
/* Decoded paintings (store_pixels.c): a painting's pixels as decoded, kept
 * beside its blob so that a restart reads them rather than decoding the
 * image again (img_raw.h: checksummed, not fsynced, rebuildable).  They go
 * with their blob.  put: GLINT_ECONFLICT when the view is no longer at
 * `version` (nothing is left behind then).  get: the pixels of the
 * view's current painting and its version; GLINT_ENOTFOUND when there are
 * none (never painted, never kept, or replaced meanwhile), GLINT_EFORMAT
 * when the file is torn or not one (the caller decodes the blob). */
int store_painting_pixels_put(store *s, const char *session, int view, int64_t version,
                              const struct img *im, glint_err *err);
int store_painting_pixels_get(store *s, const char *session, int view, int max_dim,
                              struct img *out, int64_t *version, glint_err *err);
/* The painted views of a session: [{"view", "version", "updated"}] by view. */
int store_paintings_list(store *s, const char *session, json_t **array, glint_err *err);

/* Strokes: appended in one transaction with the painting they produced, so
 * the numbered history and the image never disagree.  `strokes` is a JSON
 * array of stroke objects (stored as given, one event each).  OUT:
 * *first_seq, *last_seq (session-wide numbering from 1), *version (the
 * painting's new version; may be NULL). */
int store_strokes_append(store *s, const char *session, int view, const json_t *strokes,
                         const void *exr, size_t len, int64_t *first_seq, int64_t *last_seq,
                         int64_t *version, glint_err *err);
/* The same, committed only if the view is still at painting version
 * `base` (0: never painted), the version the image was made from:
 * GLINT_ECONFLICT when another writer (another glintd on the same
 * database) changed the view meanwhile; nothing is stored then and the
 * caller applies its strokes again to the new image.  base -1: no check. */
int store_strokes_append_at(store *s, const char *session, int view, int64_t base,
                            const json_t *strokes, const void *exr, size_t len,
                            int64_t *first_seq, int64_t *last_seq, int64_t *version,
                            glint_err *err);
/* Strokes with seq > since, in order, as a JSON array of
 * {"seq", "view", "stroke", "created"}. */
int store_strokes_since(store *s, const char *session, int64_t since, json_t **array,
                        glint_err *err);
/* The same, at most `limit` strokes and, when max_bytes > 0, at most
 * max_bytes of their records as compact JSON (json_dumpb, a comma each):
 * the first stroke is always taken, so a page is never empty while strokes
 * follow, and holds at most max_bytes or one stroke.  Only the page is
 * decoded.  OUT: *more = 1 when more follow; *last_seq: what the answer
 * covers, to pass as `since` next time (the session's last sequence
 * number, or the last stroke's when *more). */
int store_strokes_page(store *s, const char *session, int64_t since, int limit,
                       size_t max_bytes, json_t **array, int *more, int64_t *last_seq,
                       glint_err *err);

/* ---- the session's event log ------------------------------------------------------------- */
/* Append an event of `type` (not "stroke" or "painting", which the calls
 * above append) with `data` (a JSON object, not stolen); view -1 for
 * none.  OUT: *seq. */
int store_event_append(store *s, const char *session, const char *type, int view,
                       const json_t *data, int64_t *seq, glint_err *err);
/* Events with seq > since, in order, at most `limit`, as a JSON array of
 * {"seq", "type", "view" (absent when none), "data", "created"}.  OUT:
 * *last_seq (may be NULL): the session's last sequence number. */
int store_events_since(store *s, const char *session, int64_t since, int limit,
                       json_t **array, int64_t *last_seq, glint_err *err);
/* One row of the event log as stored: `data` is the compact JSON text of
 * the event's data (one line, as json_text writes it). */
typedef struct store_event_row {
    int64_t seq;
    const char *type;
    int64_t view;           /* -1: none */
    const char *data;
    const char *created;    /* ISO time */
} store_event_row;

/* Called for each row; the strings are valid during the call only.
 * Non-zero stops the read and is returned. */
typedef int (*store_event_fn)(void *ctx, const store_event_row *row, glint_err *err);

/* The events after `since` handed to fn in order, as text, without
 * building a JSON tree (an event stream's read costs the text it keeps):
 * at most `limit` rows (<= 0: no limit) and, after the first, no more once
 * the rows' data text reaches max_bytes (0: no limit).  fn runs with the
 * store locked: it must only copy.  OUT: *more: rows were left for the
 * next read.  GLINT_ENOTFOUND for an unknown session. */
int store_events_each(store *s, const char *session, int64_t since, int limit, size_t max_bytes,
                      store_event_fn fn, void *ctx, int *more, glint_err *err);

/* ---- materials ----------------------------------------------------------------------- */
/* doc: the API's material object; files (material.json, factors.*, shader
 * export) are blobs named "materials/<id>/<file>". */
int store_material_put(store *s, const char *id, const char *session, const json_t *doc,
                       glint_err *err);
/* The material's row and the session's event announcing it (`type`,
 * `data` as store_event_append) in one transaction: one durable commit,
 * and no material without its event or event without its material.
 * OUT: *seq (may be NULL), the event's number. */
int store_material_put_event(store *s, const char *id, const char *session, const json_t *doc,
                             const char *type, const json_t *data, int64_t *seq,
                             glint_err *err);
int store_material_get(store *s, const char *id, json_t **doc, glint_err *err);
/* Delete the materials of `session` (a session's or G-buffer set's id:
 * the owner they were stored with), rows and their blobs "materials/<id>/"
 * (files after the rows: a crash leaves only files the sweep removes).
 * None: 0. */
int store_materials_delete(store *s, const char *session, glint_err *err);
int store_material_list(store *s, const char *session, json_t **array, glint_err *err);

#endif
