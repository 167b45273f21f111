/* mesh_int.h: internals shared by the mesh modules and their tests.  Not
 * part of core's contract.
 *
 *   mesh_geom.c     helpers, normals, normalization
 *   mesh_uv.c       the automatic parameterization
 *   mesh_io.c       loading files: entry points, cleaning (steps in its header)
 *   mesh_prescan.c  structural pre-scan of PLY and OFF data
 *   mesh_assimp.c   the assimp import and the merge of its meshes
 *   mesh_fileio.c   the file system assimp reads through (what it may open)
 *   mesh_refs.c     the references an upload's text makes (mesh_refs_check)
 *   mesh_child.c    the import in a child process, and its pipe protocol */
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

/* ---- loading files ------------------------------------------------------ */

/* Built with AddressSanitizer: whole loads run one at a time (mesh_io.c
 * says why). */
#if defined(__SANITIZE_ADDRESS__)
#define MIO_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MIO_SANITIZED 1
#endif
#endif

/* Structural pre-scan of PLY, OFF or OBJ data in buf[0..len)
 * (mesh_prescan.c): dispatches on content (PLY magic, OFF header) or on
 * `fmt` ("off" also recognizes a headerless OFF, "obj" counts face lines);
 * other data passes.  Returns 0, or GLINT_ERANGE (a count over
 * MESH_MAX_VERTS, triangles over max_tris (<= 0 or above MESH_MAX_TRIS:
 * MESH_MAX_TRIS), a PLY element of too many properties) or GLINT_EFORMAT
 * (truncated data, a missing end_header, an overlong OFF line), the message
 * starting with `what`. */
int mio_prescan(const char *buf, size_t len, const char *fmt, const char *what, long max_tris,
                glint_err *err);

/* What a reference to another file is (mio_ref_check). */
enum {
    MIO_REF_OK = 0,   /* a relative path that stays in its directory */
    MIO_REF_DATA,     /* a data: URI: part of the file itself */
    MIO_REF_ABSOLUTE, /* starts with '/' or '\\' */
    MIO_REF_ESCAPE,   /* leaves its directory through ".." ('\\' counted as '/') */
    MIO_REF_SCHEME    /* a URI with another scheme: file:, http:, ... or "C:" */
};

/* Classify a reference as a mesh file writes it, relative to the file's
 * directory (mesh_fileio.c).  Purely lexical: touches no file. */
int mio_ref_check(const char *ref);

/* The refusal of an upload's reference `ref` (GLINT_EINVAL, "external
 * references are not allowed in uploads", naming it printable and cut to
 * a few dozen characters; `what` starts the message): the same words
 * whether the import or mesh_refs_check finds it. */
int mio_upload_refuse(const char *ref, const char *what, glint_err *err);

/* The file system one import reads through (mesh_fileio.c, where the rules
 * are): from memory (path NULL) only the `len` bytes at `data` exist, under
 * the name mio_fs_name(); from disk, the file at `path` and regular files
 * in its directory or below.  `fmt` is the format's extension.  OUT: *out,
 * owned by the caller, released with mio_fs_close after the scene it was
 * used for (data and path must outlive it).  Returns 0 or GLINT_ENOMEM. */
typedef struct mio_fs mio_fs;
struct aiFileIO;
struct aiScene;
int mio_fs_open(mio_fs **out, const char *path, const void *data, size_t len, const char *fmt,
                glint_err *err);
/* The name to give assimp (aiImportFileEx), and the file system itself. */
const char *mio_fs_name(const mio_fs *fs);
struct aiFileIO *mio_fs_io(mio_fs *fs);
/* After aiImportFileEx returned `sc` (NULL if it failed): GLINT_EINVAL if
 * the file referred to another file the rules refuse (while importing, or
 * as a texture path in sc), with `what` and the reference (truncated,
 * printable) in the message; else 0 (then a NULL sc is assimp's own
 * failure). */
int mio_fs_verdict(const mio_fs *fs, const struct aiScene *sc, const char *what,
                   glint_err *err);
/* Release.  Accepts NULL. */
void mio_fs_close(mio_fs *fs);

/* Import a file through assimp, in this process (mesh_assimp.c): the file
 * at `path`, or (path NULL) `len` bytes at `data` in format `hint` (a file
 * extension).  OUT: *raw, the merged triangle soup of every node instance
 * (nrm and uv only when every mesh has them; zeroed first, owned by the
 * caller, freed on failure), *prims, the points, lines and polygons left
 * out.  Returns 0 or a GLINT_E* code with `what` in the message.  assimp
 * may crash or abort on malformed input: call it in a child process. */
int mio_import_direct(const char *path, const void *data, size_t len, const char *hint,
                      const char *what, mesh *raw, long long *prims, glint_err *err);

/* mio_import_direct in a forked child process (mesh_child.c), with a time
 * limit (MESH_IMPORT_TIMEOUT_S) and a memory limit; the same arguments and
 * results.  A child that crashes, hangs or sends inconsistent data is an
 * error (GLINT_EFORMAT, GLINT_ERANGE for the limits, GLINT_EINTERNAL for a
 * sanitizer report), never the caller's crash.  Safe to call from several
 * threads (but see MIO_SANITIZED in mesh_io.c). */
int mio_import(const char *path, const void *data, size_t len, const char *hint,
               const char *what, mesh *raw, long long *prims, glint_err *err);

#endif
