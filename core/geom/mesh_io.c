/* mesh_io.c: meshes from files (assimp), cleaning, smooth normals, glint's
 * automatic parameterization and unit-ball normalization (contract in
 * mesh.h).  This file holds the entry points and the steps after the
 * import; the other steps live in their own files.
 *
 * Loading runs in these steps; each reports what it decided in mesh_report:
 *  1. size checks: the file is stat'ed (missing -> GLINT_ENOTFOUND, larger
 *     than MESH_MAX_FILE_BYTES -> GLINT_ERANGE, empty -> GLINT_EFORMAT);
 *  2. a structural pre-scan of PLY and OFF data (mesh_prescan.c: counts
 *     over the limits, truncated data and lines assimp 5.2 mishandles are
 *     refused before assimp sees them);
 *  3. assimp imports, in a child process (mesh_child.c: assimp crashes,
 *     aborts or exhausts memory on some malformed files), with only its
 *     structure validation, through glint's file system (mesh_fileio.c):
 *     from memory it reads nothing but the given bytes, from disk nothing
 *     outside the file's directory; every coordinate is checked to be
 *     finite (NaN or Inf -> GLINT_ENONFINITE naming the mesh and vertex),
 *     empty faces are refused, then assimp triangulates, joins identical
 *     vertices and sorts primitives by type (mesh_assimp.c);
 *  4. every node instance of every mesh is merged with its node transform
 *     (normals by the cofactor matrix, winding flipped under reflections);
 *     points and lines are dropped (counted) (mesh_assimp.c);
 *  5. cleaning on positions welded bit-exactly (so uv or normal seams do not
 *     count as holes): triangles with two corners at the same position or an
 *     area below 5e-13 of the squared bounding-box diagonal are dropped
 *     (counted), unused vertices removed; boundary and non-manifold edges
 *     are counted (usable, reported);
 *  6. normals: the file's, renormalized, unless any is zero or non-finite;
 *     otherwise smooth area-weighted normals (mesh_compute_normals);
 *  7. centred and scaled into the unit ball (mesh_normalize);
 *  8. uvs: the file's when every vertex has finite ones spanning a non-zero
 *     area (moved uniformly into [0,1]^2 when they leave it); otherwise
 *     glint's parameterization (mesh_generate_uvs, method at its definition).
 *
 * No assimp logger is attached, and the import child's stdout goes to
 * /dev/null and its stderr into the error message: assimp prints nothing.
 * Helpers, normals and normalization live in mesh_geom.c, the
 * parameterization in mesh_uv.c. */
#include "mesh.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "internal/mesh_int.h"
#include "vec3.h"

#ifdef MIO_SANITIZED
/* The sanitizer runtimes of GCC 12 do not make their allocator fork-safe:
 * a child forked while another thread holds an allocator lock deadlocks
 * (until the time limit).  Sanitizer builds therefore run whole loads one
 * at a time, so that at least glint's own threads are not allocating
 * during the fork.  Production builds use glibc's malloc, which is. */
static pthread_mutex_t mio_sanitizer_lock = PTHREAD_MUTEX_INITIALIZER;
#endif

/* ------------------------------------------------------------------------ */
/* Cleaning                                                                  */
/* ------------------------------------------------------------------------ */

/* Drop degenerate triangles and unused vertices (arrays compacted in
 * place); count boundary and non-manifold edges of what remains. */
static int mio_clean(mesh *m, mesh_report *rep, const char *what, glint_err *err)
{
    size_t nv = (size_t)m->nverts, nt = (size_t)m->ntris, kept = 0, nn = 0;
    uint32_t *canon = NULL, *remap = NULL;
    mio_pair *edges = NULL;
    double diag, thr;
    int rc;

    canon = malloc(nv * sizeof *canon);
    remap = malloc(nv * sizeof *remap);
    if (!canon || !remap) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory cleaning %s", what);
        goto done;
    }
    rc = mio_weld(m->pos, nv, canon, err);
    if (rc)
        goto done;
    diag = mio_bbox_diag(m->pos, nv);
    thr = MIO_DEGENERATE_REL * diag * diag;
    for (size_t t = 0; t < nt; t++) {
        const uint32_t *f = m->tri + 3 * t;
        uint32_t a = canon[f[0]], b = canon[f[1]], c = canon[f[2]];
        if (a == b || b == c || a == c || !(mio_tri_cross_len(m->pos, f, NULL) > thr))
            continue;
        memmove(m->tri + 3 * kept, f, 3 * sizeof *f);
        kept++;
    }
    rep->dropped_degenerate = (int)(nt - kept);
    if (!kept) {
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: no usable triangles (all %zu have zero area or repeated "
                           "corners)", what, nt);
        goto done;
    }
    m->ntris = (int)kept;
    /* unused vertices out */
    memset(remap, 0xff, nv * sizeof *remap);
    for (size_t i = 0; i < 3 * kept; i++)
        remap[m->tri[i]] = 0;
    for (size_t v = 0; v < nv; v++)
        if (remap[v] == 0) {
            remap[v] = (uint32_t)nn;
            if (nn != v) {
                memmove(m->pos + 3 * nn, m->pos + 3 * v, 3 * sizeof(float));
                if (m->nrm)
                    memmove(m->nrm + 3 * nn, m->nrm + 3 * v, 3 * sizeof(float));
                if (m->uv)
                    memmove(m->uv + 2 * nn, m->uv + 2 * v, 2 * sizeof(float));
            }
            nn++;
        }
    for (size_t i = 0; i < 3 * kept; i++)
        m->tri[i] = remap[m->tri[i]];
    m->nverts = (int)nn;
    /* edges on welded positions */
    rc = mio_weld(m->pos, nn, canon, err);
    if (rc)
        goto done;
    rc = mio_edges_sorted(m, canon, &edges, err);
    if (rc)
        goto done;
    mio_edge_stats(edges, 3 * kept, &rep->boundary_edges, &rep->nonmanifold_edges);
done:
    free(canon);
    free(remap);
    free(edges);
    return rc;
}

/* The file's normals, renormalized; 0 if any is unusable (then all are
 * recomputed). */
static int mio_normals_usable(mesh *m)
{
    size_t nv = (size_t)m->nverts;
    if (!m->nrm)
        return 0;
    for (size_t v = 0; v < nv; v++) {
        v3 n = v3_loadf(m->nrm + 3 * v);
        double l = v3_len(n);
        if (!isfinite(l) || !(l > 1e-30))
            return 0;
    }
    for (size_t v = 0; v < nv; v++) {
        v3 n = v3_loadf(m->nrm + 3 * v);
        v3_storef(v3_scale(n, 1.0 / v3_len(n)), m->nrm + 3 * v);
    }
    return 1;
}

/* The file's uvs: kept if finite and spanning some area, moved into
 * [0,1]^2 by one uniform scale and shift when they leave it (tiling or
 * offset layouts).  Returns 1 if kept (OUT: *rescaled). */
static int mio_uvs_usable(mesh *m, int *rescaled)
{
    size_t nv = (size_t)m->nverts, nt = (size_t)m->ntris;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY}, area = 0.0, ext;
    *rescaled = 0;
    if (!m->uv)
        return 0;
    for (size_t v = 0; v < nv; v++)
        for (int k = 0; k < 2; k++) {
            double x = m->uv[2 * v + k];
            if (!isfinite(x))
                return 0;
            lo[k] = fmin(lo[k], x);
            hi[k] = fmax(hi[k], x);
        }
    ext = fmax(hi[0] - lo[0], hi[1] - lo[1]);
    for (size_t t = 0; t < nt; t++) {
        const float *a = m->uv + 2 * (size_t)m->tri[3 * t], *b = m->uv + 2 * (size_t)m->tri[3 * t + 1],
                    *c = m->uv + 2 * (size_t)m->tri[3 * t + 2];
        area += fabs(((double)b[0] - a[0]) * ((double)c[1] - a[1]) -
                     ((double)c[0] - a[0]) * ((double)b[1] - a[1]));
    }
    if (!(ext > 0.0) || !(area > 1e-12 * ext * ext))
        return 0; /* all uvs (nearly) equal: no parameterization */
    if (lo[0] >= -1e-6 && lo[1] >= -1e-6 && hi[0] <= 1.0 + 1e-6 && hi[1] <= 1.0 + 1e-6) {
        for (size_t i = 0; i < 2 * nv; i++)
            m->uv[i] = fminf(1.0f, fmaxf(0.0f, m->uv[i]));
        return 1;
    }
    for (size_t v = 0; v < nv; v++)
        for (int k = 0; k < 2; k++)
            m->uv[2 * v + k] = (float)fmin(1.0, fmax(0.0, (m->uv[2 * v + k] - lo[k]) / ext));
    *rescaled = 1;
    return 1;
}

/* Fraction of [0,1]^2 covered by the uv triangles (overlaps counted
 * twice). */
static double mio_uv_coverage(const mesh *m)
{
    double area = 0.0;
    for (size_t t = 0; t < (size_t)m->ntris; t++) {
        const float *a = m->uv + 2 * (size_t)m->tri[3 * t], *b = m->uv + 2 * (size_t)m->tri[3 * t + 1],
                    *c = m->uv + 2 * (size_t)m->tri[3 * t + 2];
        area += 0.5 * fabs(((double)b[0] - a[0]) * ((double)c[1] - a[1]) -
                           ((double)c[0] - a[0]) * ((double)b[1] - a[1]));
    }
    return area;
}

/* ------------------------------------------------------------------------ */
/* Entry points                                                              */
/* ------------------------------------------------------------------------ */

/* Lower-case format name from a file name's extension or a hint (at most
 * 15 characters of [a-z0-9]); "" if there is none. */
static void mio_format_name(const char *name, int is_hint, char out[16])
{
    const char *dot, *slash, *ext;
    size_t n;
    out[0] = '\0';
    if (!name)
        return;
    if (is_hint) {
        ext = name[0] == '.' ? name + 1 : name;
    } else {
        slash = strrchr(name, '/');
        dot = strrchr(slash ? slash + 1 : name, '.');
        if (!dot)
            return;
        ext = dot + 1;
    }
    n = strlen(ext);
    if (n == 0 || n > 15)
        return;
    for (size_t i = 0; i < n; i++) {
        char c = ext[i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9'))) {
            out[0] = '\0';
            return;
        }
        out[i] = c;
    }
    out[n] = '\0';
}

/* Everything after the bytes are known to be there: pre-scan, import,
 * merge, clean, normals, normalization, uvs. */
static int mio_load_locked(const char *path, const void *data, size_t len, const char *fmt,
                           const char *what, long max_tris, mesh *out, mesh_report *report,
                           glint_err *err);

static int mio_load(const char *path, const void *data, size_t len, const char *fmt,
                    const char *what, long max_tris, mesh *out, mesh_report *report,
                    glint_err *err)
{
#ifdef MIO_SANITIZED
    int rc;
    pthread_mutex_lock(&mio_sanitizer_lock);
    rc = mio_load_locked(path, data, len, fmt, what, max_tris, out, report, err);
    pthread_mutex_unlock(&mio_sanitizer_lock);
    return rc;
#else
    return mio_load_locked(path, data, len, fmt, what, max_tris, out, report, err);
#endif
}

static int mio_load_locked(const char *path, const void *data, size_t len, const char *fmt,
                           const char *what, long max_tris, mesh *out, mesh_report *report,
                           glint_err *err)
{
    mesh_report rep;
    mesh m;
    long long prims = 0;
    int rc, rescaled = 0;

    memset(&rep, 0, sizeof rep);
    snprintf(rep.format, sizeof rep.format, "%s", *fmt ? fmt : "unknown");
    if (data) {
        rc = mio_prescan(data, len, fmt, what, max_tris, err);
        if (rc)
            return rc;
    }
    rc = mio_import(path, data, len, fmt, what, &m, &prims, err);
    if (rc)
        return rc;
    rep.dropped_primitives = prims > INT_MAX ? INT_MAX : (int)prims;
    rc = mio_clean(&m, &rep, what, err);
    if (rc)
        goto fail;
    if (!mio_normals_usable(&m)) {
        rc = mesh_compute_normals(&m, err);
        if (rc)
            goto fail;
        rep.normals_generated = 1;
    }
    mesh_normalize(&m, &rep.scale, rep.center);
    if (mio_uvs_usable(&m, &rescaled)) {
        rep.uvs_rescaled = rescaled;
    } else {
        free(m.uv);
        m.uv = NULL;
        rc = mio_uv_generate(&m, &rep.uv_charts, err);
        if (rc)
            goto fail;
        rep.uvs_generated = 1;
    }
    rep.uv_coverage = mio_uv_coverage(&m);
    rc = mesh_validate(&m, err);
    if (rc) {
        glint_err_prefix(err, "%s", what);
        goto fail;
    }
    rep.nverts = m.nverts;
    rep.ntris = m.ntris;
    *out = m;
    if (report)
        *report = rep;
    return 0;

fail:
    mesh_free(&m);
    return rc;
}

int mesh_load(const char *path, mesh *out, mesh_report *report, glint_err *err)
{
    struct stat st;
    char fmt[16], head[8];
    int fd = -1, rc;
    void *map = MAP_FAILED;
    size_t len;
    ssize_t got;

    if (report)
        memset(report, 0, sizeof *report);
    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_load: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "mesh_load: empty path");
    fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return glint_err_set(err, errno == ENOENT || errno == ENOTDIR ? GLINT_ENOTFOUND : GLINT_EIO,
                             "opening mesh file %s: %s", path, strerror(errno));
    if (fstat(fd, &st) != 0) {
        rc = glint_err_set(err, GLINT_EIO, "stat of mesh file %s: %s", path, strerror(errno));
        goto done;
    }
    if (!S_ISREG(st.st_mode)) {
        rc = glint_err_set(err, GLINT_EINVAL, "mesh file %s is not a regular file", path);
        goto done;
    }
    if ((unsigned long long)st.st_size > (unsigned long long)MESH_MAX_FILE_BYTES) {
        rc = glint_err_set(err, GLINT_ERANGE, "mesh file %s is %lld bytes, more than the limit "
                           "of %zu", path, (long long)st.st_size, (size_t)MESH_MAX_FILE_BYTES);
        goto done;
    }
    if (st.st_size == 0) {
        rc = glint_err_set(err, GLINT_EFORMAT, "mesh file %s is empty", path);
        goto done;
    }
    len = (size_t)st.st_size;
    mio_format_name(path, 0, fmt);
    /* The pre-scan reads PLY and OFF data in place (mapped read-only). */
    got = pread(fd, head, sizeof head, 0);
    if (got < 0) {
        rc = glint_err_set(err, GLINT_EIO, "reading mesh file %s: %s", path, strerror(errno));
        goto done;
    }
    {
        int maybe = strcmp(fmt, "ply") == 0 || strcmp(fmt, "off") == 0 ||
                    (got >= 3 && (memcmp(head, "ply", 3) == 0 || memcmp(head, "PLY", 3) == 0));
        for (ssize_t i = 0; !maybe && i + 2 < got; i++)
            maybe = memcmp(head + i, "OFF", 3) == 0;
        if (maybe) {
            map = mmap(NULL, len, PROT_READ, MAP_PRIVATE, fd, 0);
            if (map == MAP_FAILED) {
                rc = glint_err_set(err, GLINT_EIO, "mapping mesh file %s: %s", path,
                                   strerror(errno));
                goto done;
            }
            rc = mio_prescan(map, len, fmt, path, MESH_MAX_TRIS, err);
            munmap(map, len);
            if (rc)
                goto done;
        }
    }
    close(fd);
    fd = -1;
    rc = mio_load(path, NULL, len, fmt, path, MESH_MAX_TRIS, out, report, err);
done:
    if (fd >= 0)
        close(fd);
    return rc;
}

int mesh_load_mem(const void *data, size_t len, const char *hint, mesh *out,
                  mesh_report *report, glint_err *err)
{
    return mesh_load_mem_max(data, len, hint, MESH_MAX_TRIS, out, report, err);
}

int mesh_load_mem_max(const void *data, size_t len, const char *hint, long max_tris, mesh *out,
                      mesh_report *report, glint_err *err)
{
    char fmt[16], what[48];

    if (report)
        memset(report, 0, sizeof *report);
    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "mesh_load_mem: output mesh is NULL");
    memset(out, 0, sizeof *out);
    if (!data && len)
        return glint_err_set(err, GLINT_EINVAL, "mesh_load_mem: data is NULL");
    mio_format_name(hint, 1, fmt);
    if (!fmt[0])
        return glint_err_set(err, GLINT_EINVAL,
                             "mesh_load_mem: format hint \"%.32s\" is not a file extension "
                             "(1 to 15 letters or digits, e.g. \"ply\")", hint ? hint : "(null)");
    snprintf(what, sizeof what, "%s data", fmt);
    if (len == 0)
        return glint_err_set(err, GLINT_EFORMAT, "%s: empty (0 bytes)", what);
    if (len > MESH_MAX_FILE_BYTES)
        return glint_err_set(err, GLINT_ERANGE, "%s: %zu bytes, more than the limit of %zu",
                             what, len, (size_t)MESH_MAX_FILE_BYTES);
    return mio_load(NULL, data, len, fmt, what, max_tris, out, report, err);
}
