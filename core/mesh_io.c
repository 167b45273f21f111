/* mesh_io.c: meshes from files (assimp), cleaning, smooth normals, glint's
 * automatic parameterization and unit-ball normalization (contract in
 * mesh.h).
 *
 * Loading runs in these steps; each reports what it decided in mesh_report:
 *  1. size checks: the file is stat'ed (missing -> GLINT_ENOTFOUND, larger
 *     than MESH_MAX_FILE_BYTES -> GLINT_ERANGE, empty -> GLINT_EFORMAT);
 *  2. a structural pre-scan of PLY and OFF data (the two formats whose
 *     headers declare element counts): a count over the limits is
 *     GLINT_ERANGE before assimp allocates for it, and data that ends before
 *     the declared elements is GLINT_EFORMAT (assimp 5.2 silently repeats
 *     the last face of a truncated ASCII PLY, zero-fills a truncated OFF and
 *     loops forever on a PLY header without end_header); OFF lines of 4096
 *     bytes or more are refused (assimp 5.2's OFF reader copies lines into a
 *     4096-byte stack buffer and writes one byte past it);
 *  3. assimp imports, in a child process (see "the import in a child
 *     process" below: assimp crashes, aborts or exhausts memory on some
 *     malformed files), with only its structure validation; every
 *     coordinate is checked to be finite (NaN or Inf -> GLINT_ENONFINITE
 *     naming the mesh and vertex), empty faces are refused, then assimp
 *     triangulates, joins identical vertices and sorts primitives by type;
 *  4. every node instance of every mesh is merged with its node transform
 *     (normals by the cofactor matrix, winding flipped under reflections);
 *     points and lines are dropped (counted);
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
#include <float.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "mesh_int.h"
#include "vec3.h"

/* Maximum depth of an assimp node hierarchy we walk. */
#define MIO_MAX_NODE_DEPTH 1024
/* Longest list in a PLY element we accept in the pre-scan. */
#define MIO_PLY_MAX_LIST 65536
/* assimp 5.2's line buffer (ParsingUtils.h BufferSize). */
#define MIO_OFF_MAX_LINE 4096

/* ------------------------------------------------------------------------ */
/* Pre-scan of PLY and OFF data                                              */
/* ------------------------------------------------------------------------ */

static int mio_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

/* A decimal count (digits only, optional '+'); saturates at ULLONG_MAX.
 * Returns 0 if the token is not a count. */
static int mio_count(const char *s, size_t n, unsigned long long *out)
{
    unsigned long long v = 0;
    size_t i = 0;
    if (n && s[0] == '+')
        i = 1;
    if (i >= n)
        return 0;
    for (; i < n; i++) {
        unsigned d;
        if (s[i] < '0' || s[i] > '9')
            return 0;
        d = (unsigned)(s[i] - '0');
        v = v > (ULLONG_MAX - d) / 10 ? ULLONG_MAX : 10 * v + d;
    }
    *out = v;
    return 1;
}

/* Next whitespace-separated token in [*p, end) (OUT: start, length);
 * 0 at the end. */
static int mio_token(const char **p, const char *end, const char **tok, size_t *len)
{
    const char *s = *p;
    while (s < end && mio_space(*s))
        s++;
    if (s >= end) {
        *p = s;
        return 0;
    }
    *tok = s;
    while (s < end && !mio_space(*s))
        s++;
    *len = (size_t)(s - *tok);
    *p = s;
    return 1;
}

static int mio_tok_is(const char *tok, size_t len, const char *word)
{
    return strlen(word) == len && memcmp(tok, word, len) == 0;
}

#define MIO_PLY_MAX_ELEMS 64
#define MIO_PLY_MAX_PROPS 64

typedef struct mio_ply_prop {
    int list;
    int size;       /* scalar or list item size in bytes */
    int csize;      /* list count size */
    int csigned;    /* list count is a signed type */
} mio_ply_prop;

typedef struct mio_ply_elem {
    char name[32];
    unsigned long long count;
    int nprops;
    mio_ply_prop props[MIO_PLY_MAX_PROPS];
} mio_ply_elem;

/* Size of a PLY scalar type name (0 if unknown), and whether it is signed. */
static int mio_ply_type(const char *tok, size_t len, int *is_signed)
{
    static const struct { const char *name; int size, sgn; } types[] = {
        {"char", 1, 1},   {"int8", 1, 1},    {"uchar", 1, 0},   {"uint8", 1, 0},
        {"short", 2, 1},  {"int16", 2, 1},   {"ushort", 2, 0},  {"uint16", 2, 0},
        {"int", 4, 1},    {"int32", 4, 1},   {"uint", 4, 0},    {"uint32", 4, 0},
        {"float", 4, 1},  {"float32", 4, 1}, {"double", 8, 1},  {"float64", 8, 1}};
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
        if (mio_tok_is(tok, len, types[i].name)) {
            if (is_signed)
                *is_signed = types[i].sgn;
            return types[i].size;
        }
    return 0;
}

static int mio_ply_truncated(const char *what, const mio_ply_elem *e, unsigned long long i,
                             glint_err *err)
{
    return glint_err_set(err, GLINT_EFORMAT,
                         "%s: PLY data ends inside element \"%s\" %llu of %llu (truncated file)",
                         what, e->name, i, e->count);
}

/* PLY: header counts against the limits, then a walk over the data that
 * checks every declared element is present.  Headers this scan does not
 * understand are left to assimp. */
static int mio_prescan_ply(const char *buf, size_t len, const char *what, glint_err *err)
{
    mio_ply_elem *el = NULL;
    int nel = 0, fmt = -1, understood = 1, rc = 0; /* fmt: 0 ascii, 1 LE, 2 BE */
    const char *p = buf, *end = buf + len, *data = NULL;

    el = calloc(MIO_PLY_MAX_ELEMS, sizeof *el);
    if (!el)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory scanning %s", what);
    /* header: one declaration per line, up to end_header */
    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p)), *q = p, *tok;
        size_t tl;
        if (!eol)
            eol = end;
        if (mio_token(&q, eol, &tok, &tl)) {
            if (mio_tok_is(tok, tl, "end_header")) {
                data = eol < end ? eol + 1 : end;
                break;
            } else if (mio_tok_is(tok, tl, "format")) {
                if (mio_token(&q, eol, &tok, &tl)) {
                    if (mio_tok_is(tok, tl, "ascii"))
                        fmt = 0;
                    else if (mio_tok_is(tok, tl, "binary_little_endian"))
                        fmt = 1;
                    else if (mio_tok_is(tok, tl, "binary_big_endian"))
                        fmt = 2;
                }
            } else if (mio_tok_is(tok, tl, "element")) {
                mio_ply_elem *e;
                const char *name;
                size_t nl;
                if (nel == MIO_PLY_MAX_ELEMS) {
                    rc = glint_err_set(err, GLINT_EFORMAT,
                                       "%s: PLY header declares more than %d elements", what,
                                       MIO_PLY_MAX_ELEMS);
                    goto done;
                }
                e = &el[nel++];
                if (!mio_token(&q, eol, &name, &nl) || !mio_token(&q, eol, &tok, &tl) ||
                    !mio_count(tok, tl, &e->count)) {
                    understood = 0; /* malformed: assimp will say so */
                    break;
                }
                snprintf(e->name, sizeof e->name, "%.*s", (int)(nl < 31 ? nl : 31), name);
                if (e->count > (unsigned long long)MESH_MAX_VERTS ||
                    (strcmp(e->name, "face") == 0 && e->count > (unsigned long long)MESH_MAX_TRIS)) {
                    rc = glint_err_set(err, GLINT_ERANGE,
                                       "%s: PLY header declares %llu \"%s\" elements, more than "
                                       "the limit of %d", what, e->count, e->name,
                                       strcmp(e->name, "face") == 0 ? MESH_MAX_TRIS
                                                                    : MESH_MAX_VERTS);
                    goto done;
                }
            } else if (mio_tok_is(tok, tl, "property")) {
                mio_ply_elem *e = nel ? &el[nel - 1] : NULL;
                mio_ply_prop *pr;
                int sgn = 0;
                if (!e || e->nprops == MIO_PLY_MAX_PROPS || !mio_token(&q, eol, &tok, &tl)) {
                    understood = 0;
                    break;
                }
                pr = &e->props[e->nprops++];
                if (mio_tok_is(tok, tl, "list")) {
                    pr->list = 1;
                    if (!mio_token(&q, eol, &tok, &tl) ||
                        !(pr->csize = mio_ply_type(tok, tl, &sgn))) {
                        understood = 0;
                        break;
                    }
                    pr->csigned = sgn;
                    if (!mio_token(&q, eol, &tok, &tl) || !(pr->size = mio_ply_type(tok, tl, NULL))) {
                        understood = 0;
                        break;
                    }
                } else if (!(pr->size = mio_ply_type(tok, tl, NULL))) {
                    understood = 0;
                    break;
                }
            }
            /* comment, obj_info and anything else: ignored */
        }
        p = eol < end ? eol + 1 : end;
    }
    if (!data) { /* the header loop may have stopped early: look again */
        for (const char *q = buf; q < end;) {
            const char *eol = memchr(q, '\n', (size_t)(end - q)), *r = q, *tok;
            size_t tl;
            if (!eol)
                eol = end;
            if (mio_token(&r, eol, &tok, &tl) && mio_tok_is(tok, tl, "end_header")) {
                data = eol < end ? eol + 1 : end;
                break;
            }
            q = eol < end ? eol + 1 : end;
        }
    }
    if (!data) {
        /* assimp 5.2 loops forever on a PLY header without end_header */
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: PLY header has no end_header line (truncated file)", what);
        goto done;
    }
    if (!understood || fmt < 0)
        goto done; /* malformed declarations: assimp reports them */

    /* data */
    p = data;
    for (int k = 0; k < nel; k++) {
        const mio_ply_elem *e = &el[k];
        int all_scalar = 1;
        size_t rec = 0;
        for (int j = 0; j < e->nprops; j++) {
            all_scalar &= !e->props[j].list;
            rec += (size_t)e->props[j].size;
        }
        if (fmt != 0 && all_scalar) {
            size_t left = (size_t)(end - p);
            if (rec && left / rec < e->count) {
                rc = mio_ply_truncated(what, e, left / rec, err);
                goto done;
            }
            p += rec * (size_t)e->count;
            continue;
        }
        for (unsigned long long i = 0; i < e->count; i++)
            for (int j = 0; j < e->nprops; j++) {
                const mio_ply_prop *pr = &e->props[j];
                if (fmt == 0) {
                    const char *tok;
                    size_t tl;
                    unsigned long long n;
                    if (!mio_token(&p, end, &tok, &tl)) {
                        rc = mio_ply_truncated(what, e, i, err);
                        goto done;
                    }
                    if (!pr->list)
                        continue;
                    if (!mio_count(tok, tl, &n) || n > MIO_PLY_MAX_LIST) {
                        rc = glint_err_set(err, GLINT_EFORMAT,
                                           "%s: PLY element \"%s\" %llu: list length \"%.*s\" is "
                                           "not a count in 0..%d", what, e->name, i,
                                           (int)(tl < 32 ? tl : 32), tok, MIO_PLY_MAX_LIST);
                        goto done;
                    }
                    for (unsigned long long t = 0; t < n; t++)
                        if (!mio_token(&p, end, &tok, &tl)) {
                            rc = mio_ply_truncated(what, e, i, err);
                            goto done;
                        }
                } else {
                    unsigned char b[8] = {0};
                    long long n = 0;
                    if (!pr->list) {
                        if ((size_t)(end - p) < (size_t)pr->size) {
                            rc = mio_ply_truncated(what, e, i, err);
                            goto done;
                        }
                        p += pr->size;
                        continue;
                    }
                    if ((size_t)(end - p) < (size_t)pr->csize) {
                        rc = mio_ply_truncated(what, e, i, err);
                        goto done;
                    }
                    for (int c = 0; c < pr->csize; c++)
                        b[c] = (unsigned char)p[fmt == 1 ? c : pr->csize - 1 - c];
                    p += pr->csize;
                    {
                        unsigned long long u = 0;
                        for (int c = pr->csize - 1; c >= 0; c--)
                            u = (u << 8) | b[c];
                        if (pr->csigned && pr->csize < 8 && (u >> (8 * pr->csize - 1)) & 1)
                            n = -1; /* negative count */
                        else
                            n = u > (unsigned long long)LLONG_MAX ? -1 : (long long)u;
                    }
                    if (n < 0 || n > MIO_PLY_MAX_LIST) {
                        rc = glint_err_set(err, GLINT_EFORMAT,
                                           "%s: PLY element \"%s\" %llu: list length %lld "
                                           "outside 0..%d", what, e->name, i, n,
                                           MIO_PLY_MAX_LIST);
                        goto done;
                    }
                    if ((size_t)(end - p) / (size_t)pr->size < (size_t)n) {
                        rc = mio_ply_truncated(what, e, i, err);
                        goto done;
                    }
                    p += (size_t)n * (size_t)pr->size;
                }
            }
    }
done:
    free(el);
    return rc;
}

/* assimp's line ends (ParsingUtils.h IsLineEnd, without NUL). */
static int mio_line_end(char c)
{
    return c == '\r' || c == '\n' || c == '\f';
}

/* OFF: the counts against the limits, the declared vertex and face lines
 * present, no line that overflows assimp's buffer.  `named_off`: the file
 * is called .off (a headerless OFF is then recognized too). */
static int mio_prescan_off(const char *buf, size_t len, int named_off, const char *what,
                           glint_err *err)
{
    const char *p = buf, *end, *tok;
    size_t tl;
    int dim = 0;
    unsigned long long nv, nf, need, got = 0;

    /* assimp reads up to the first NUL */
    end = memchr(buf, '\0', len);
    if (!end)
        end = buf + len;
    /* first token, skipping comment lines */
    for (;;) {
        while (p < end && mio_space(*p))
            p++;
        if (p < end && *p == '#') {
            while (p < end && *p != '\n' && *p != '\r')
                p++;
            continue;
        }
        break;
    }
    {
        const char *q = p, *w;
        size_t wl;
        if (!mio_token(&q, end, &w, &wl))
            return 0;
        {
            const char *s = w, *e = w + wl;
            if (e - s >= 2 && s[0] == 'S' && s[1] == 'T')
                s += 2;
            if (s < e && *s == 'C')
                s++;
            if (s < e && *s == 'N')
                s++;
            if (s < e && *s == '4')
                s++;
            if (s < e && *s == 'n') {
                s++;
                dim = 1;
            }
            if (e - s == 3 && memcmp(s, "OFF", 3) == 0)
                p = q; /* header */
            else if (named_off && w[0] >= '0' && w[0] <= '9')
                dim = 0; /* headerless: counts come first */
            else
                return 0; /* not OFF */
        }
    }
    if (dim && !mio_token(&p, end, &tok, &tl))
        return 0;
    if (!mio_token(&p, end, &tok, &tl) || !mio_count(tok, tl, &nv) ||
        !mio_token(&p, end, &tok, &tl) || !mio_count(tok, tl, &nf))
        return 0; /* malformed: assimp will say so */
    if (nv > (unsigned long long)MESH_MAX_VERTS || nf > (unsigned long long)MESH_MAX_TRIS)
        return glint_err_set(err, GLINT_ERANGE,
                             "%s: OFF header declares %llu vertices and %llu faces, more than "
                             "the limits of %d and %d", what, nv, nf, MESH_MAX_VERTS,
                             MESH_MAX_TRIS);
    (void)mio_token(&p, end, &tok, &tl); /* edge count, unused */
    /* then lines, as assimp reads them: blank lines and comment lines
     * between the counts and the first vertex are skipped, later ones not */
    for (;;) {
        while (p < end && (mio_space(*p)))
            p++;
        if (p < end && *p == '#') {
            while (p < end && !mio_line_end(*p))
                p++;
            continue;
        }
        break;
    }
    need = nv + nf;
    while (p < end && got < need) {
        const char *s = p;
        while (p < end && !mio_line_end(*p))
            p++;
        if (p - s >= MIO_OFF_MAX_LINE)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s: OFF line %llu after the header is %zu bytes long (at most "
                                 "%d accepted)", what, got + 1, (size_t)(p - s),
                                 MIO_OFF_MAX_LINE - 1);
        got++;
        while (p < end && mio_line_end(*p))
            p++;
    }
    if (got < need)
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: OFF data ends after %llu of the %llu vertex and %llu face "
                             "lines its header declares (truncated file)", what, got, nv, nf);
    return 0;
}

/* Dispatch on content (PLY magic, OFF header) or name. */
static int mio_prescan(const char *buf, size_t len, const char *fmt, const char *what,
                       glint_err *err)
{
    if (len >= 4 && (memcmp(buf, "ply", 3) == 0 || memcmp(buf, "PLY", 3) == 0) &&
        mio_space(buf[3]))
        return mio_prescan_ply(buf, len, what, err);
    return mio_prescan_off(buf, len, strcmp(fmt, "off") == 0, what, err);
}

/* ------------------------------------------------------------------------ */
/* Import through assimp                                                     */
/* ------------------------------------------------------------------------ */

/* Row-major 3 x 4 affine transform in double precision. */
typedef struct mio_xf {
    double m[3][4];
} mio_xf;

static mio_xf mio_xf_mul(const mio_xf *a, const struct aiMatrix4x4 *b)
{
    const double B[3][4] = {{b->a1, b->a2, b->a3, b->a4},
                            {b->b1, b->b2, b->b3, b->b4},
                            {b->c1, b->c2, b->c3, b->c4}};
    mio_xf r;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 4; j++) {
            double s = j == 3 ? a->m[i][3] : 0.0;
            for (int k = 0; k < 3; k++)
                s += a->m[i][k] * B[k][j];
            r.m[i][j] = s;
        }
    /* the bottom row of an assimp node transform is (0 0 0 1) for affine
     * transforms; a projective one is treated as affine */
    return r;
}

/* What the walk over the node hierarchy collects. */
typedef struct mio_gather {
    const struct aiScene *sc;
    int fill;                 /* 0: count, 1: copy */
    long long nv, nt;         /* counted / copied so far */
    long long prims;          /* points, lines, polygons left out */
    int all_nrm, all_uv;      /* every instanced triangle mesh has them */
    mesh *out;
    const char *what;
} mio_gather;

static int mio_gather_mesh(mio_gather *g, const struct aiMesh *am, unsigned mi, const mio_xf *x,
                           glint_err *err)
{
    long long ntri = 0;
    double det, cof[3][3];
    const double (*M)[4] = x->m;
    uint32_t base;

    for (unsigned f = 0; f < am->mNumFaces; f++)
        if (am->mFaces[f].mNumIndices == 3)
            ntri++;
    if (!g->fill) {
        g->prims += (long long)am->mNumFaces - ntri;
        if (!ntri)
            return 0;
        g->nv += am->mNumVertices;
        g->nt += ntri;
        g->all_nrm &= am->mNormals != NULL;
        g->all_uv &= am->mTextureCoords[0] != NULL && am->mNumUVComponents[0] >= 2;
        if (g->nt > MESH_MAX_TRIS)
            return glint_err_set(err, GLINT_ERANGE,
                                 "%s: more than %d triangles (the limit) after merging its meshes",
                                 g->what, MESH_MAX_TRIS);
        if (g->nv > MESH_MAX_VERTS)
            return glint_err_set(err, GLINT_ERANGE,
                                 "%s: more than %d vertices (the limit) after merging its meshes",
                                 g->what, MESH_MAX_VERTS);
        return 0;
    }
    if (!ntri)
        return 0;
    /* cofactor matrix: transforms normals (up to the sign of det) */
    cof[0][0] = M[1][1] * M[2][2] - M[1][2] * M[2][1];
    cof[0][1] = M[1][2] * M[2][0] - M[1][0] * M[2][2];
    cof[0][2] = M[1][0] * M[2][1] - M[1][1] * M[2][0];
    cof[1][0] = M[0][2] * M[2][1] - M[0][1] * M[2][2];
    cof[1][1] = M[0][0] * M[2][2] - M[0][2] * M[2][0];
    cof[1][2] = M[0][1] * M[2][0] - M[0][0] * M[2][1];
    cof[2][0] = M[0][1] * M[1][2] - M[0][2] * M[1][1];
    cof[2][1] = M[0][2] * M[1][0] - M[0][0] * M[1][2];
    cof[2][2] = M[0][0] * M[1][1] - M[0][1] * M[1][0];
    det = M[0][0] * cof[0][0] + M[0][1] * cof[0][1] + M[0][2] * cof[0][2];
    base = (uint32_t)g->nv;
    for (unsigned v = 0; v < am->mNumVertices; v++) {
        const struct aiVector3D *p = &am->mVertices[v];
        float *o = g->out->pos + 3 * (size_t)(g->nv + v);
        for (int i = 0; i < 3; i++) {
            double y = M[i][0] * p->x + M[i][1] * p->y + M[i][2] * p->z + M[i][3];
            o[i] = (float)y;
            if (!isfinite(o[i]))
                return glint_err_set(err, GLINT_ENONFINITE,
                                     "%s: mesh %u vertex %u: coordinate not finite after its "
                                     "node transform (%g)", g->what, mi, v, y);
        }
        if (g->out->nrm) {
            const struct aiVector3D *n = &am->mNormals[v];
            float *on = g->out->nrm + 3 * (size_t)(g->nv + v);
            for (int i = 0; i < 3; i++) {
                double y = cof[i][0] * n->x + cof[i][1] * n->y + cof[i][2] * n->z;
                on[i] = (float)(det < 0 ? -y : y);
            }
        }
        if (g->out->uv) {
            const struct aiVector3D *t = &am->mTextureCoords[0][v];
            g->out->uv[2 * (size_t)(g->nv + v)] = t->x;
            g->out->uv[2 * (size_t)(g->nv + v) + 1] = t->y;
        }
    }
    for (unsigned f = 0; f < am->mNumFaces; f++) {
        const struct aiFace *fc = &am->mFaces[f];
        uint32_t *o;
        if (fc->mNumIndices != 3)
            continue;
        for (int k = 0; k < 3; k++)
            if (fc->mIndices[k] >= am->mNumVertices)
                return glint_err_set(err, GLINT_EFORMAT,
                                     "%s: mesh %u face %u: vertex index %u out of range (%u "
                                     "vertices)", g->what, mi, f, fc->mIndices[k],
                                     am->mNumVertices);
        o = g->out->tri + 3 * (size_t)g->nt;
        o[0] = base + fc->mIndices[0];
        o[1] = base + fc->mIndices[det < 0 ? 2 : 1];
        o[2] = base + fc->mIndices[det < 0 ? 1 : 2];
        g->nt++;
    }
    g->nv += am->mNumVertices;
    return 0;
}

static int mio_gather_node(mio_gather *g, const struct aiNode *nd, const mio_xf *parent,
                           int depth, glint_err *err)
{
    mio_xf x;
    int rc;
    if (depth > MIO_MAX_NODE_DEPTH)
        return glint_err_set(err, GLINT_EFORMAT, "%s: node hierarchy deeper than %d", g->what,
                             MIO_MAX_NODE_DEPTH);
    x = mio_xf_mul(parent, &nd->mTransformation);
    for (unsigned i = 0; i < nd->mNumMeshes; i++) {
        unsigned mi = nd->mMeshes[i];
        if (mi >= g->sc->mNumMeshes || !g->sc->mMeshes[mi])
            return glint_err_set(err, GLINT_EFORMAT, "%s: node refers to mesh %u of %u", g->what,
                                 mi, g->sc->mNumMeshes);
        rc = mio_gather_mesh(g, g->sc->mMeshes[mi], mi, &x, err);
        if (rc)
            return rc;
    }
    for (unsigned i = 0; i < nd->mNumChildren; i++) {
        if (!nd->mChildren[i])
            continue;
        rc = mio_gather_node(g, nd->mChildren[i], &x, depth + 1, err);
        if (rc)
            return rc;
    }
    return 0;
}

/* One pass over the scene: every node instance, or every mesh once with
 * the identity when no node refers to a triangle mesh. */
static int mio_gather_pass(mio_gather *g, int by_nodes, glint_err *err)
{
    static const mio_xf id = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}}};
    if (by_nodes)
        return mio_gather_node(g, g->sc->mRootNode, &id, 0, err);
    for (unsigned i = 0; i < g->sc->mNumMeshes; i++) {
        int rc;
        if (!g->sc->mMeshes[i])
            continue;
        rc = mio_gather_mesh(g, g->sc->mMeshes[i], i, &id, err);
        if (rc)
            return rc;
    }
    return 0;
}

/* Import (path, or data + hint) into the raw merged triangle soup *raw
 * (nrm / uv arrays only when every mesh has them), in this process. */
static int mio_import_direct(const char *path, const void *data, size_t len, const char *hint,
                      const char *what, mesh *raw, long long *prims, glint_err *err)
{
    const struct aiScene *sc;
    mio_gather g;
    int rc, by_nodes;

    memset(raw, 0, sizeof *raw);
    if (path)
        sc = aiImportFile(path, aiProcess_ValidateDataStructure);
    else
        sc = aiImportFileFromMemory(data, (unsigned)len, aiProcess_ValidateDataStructure, hint);
    if (!sc) {
        const char *msg = aiGetErrorString();
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: assimp could not read it: %s", what,
                           msg && *msg ? msg : "(no message)");
        return rc;
    }
    /* Before assimp's own processing: every coordinate finite (its vertex
     * joining sorts them), no empty face (what assimp's readers leave for
     * faces missing from a truncated file), and primitive-type flags that
     * match the faces (its triangulation asserts -- aborts the process --
     * when a mesh flagged as having polygons has none). */
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        struct aiMesh *am = sc->mMeshes[i];
        unsigned types = 0;
        if (!am)
            continue;
        for (unsigned f = 0; f < am->mNumFaces; f++) {
            unsigned n = am->mFaces[f].mNumIndices;
            if (n == 0 || !am->mFaces[f].mIndices) {
                rc = glint_err_set(err, GLINT_EFORMAT,
                                   "%s: mesh %u face %u has no vertex indices (truncated or "
                                   "corrupt data)", what, i, f);
                aiReleaseImport(sc);
                return rc;
            }
            types |= n == 1 ? aiPrimitiveType_POINT
                            : n == 2 ? aiPrimitiveType_LINE
                                     : n == 3 ? aiPrimitiveType_TRIANGLE : aiPrimitiveType_POLYGON;
        }
        am->mPrimitiveTypes = types;
        for (unsigned v = 0; am->mVertices && v < am->mNumVertices; v++) {
            const struct aiVector3D *p = &am->mVertices[v];
            if (!isfinite(p->x) || !isfinite(p->y) || !isfinite(p->z)) {
                rc = glint_err_set(err, GLINT_ENONFINITE,
                                   "%s: mesh %u vertex %u has a non-finite coordinate (%g, %g, %g)",
                                   what, i, v, p->x, p->y, p->z);
                aiReleaseImport(sc);
                return rc;
            }
        }
    }
    sc = aiApplyPostProcessing(sc, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                       aiProcess_SortByPType);
    if (!sc) /* assimp released the scene */
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: assimp post-processing (triangulation, vertex joining) failed",
                             what);

    memset(&g, 0, sizeof g);
    g.sc = sc;
    g.what = what;
    g.all_nrm = g.all_uv = 1;
    by_nodes = sc->mRootNode != NULL;
    rc = mio_gather_pass(&g, by_nodes, err);
    if (!rc && g.nt == 0 && by_nodes) { /* no node instances a triangle mesh */
        memset(&g, 0, sizeof g);
        g.sc = sc;
        g.what = what;
        g.all_nrm = g.all_uv = 1;
        by_nodes = 0;
        rc = mio_gather_pass(&g, 0, err);
    }
    if (rc)
        goto done;
    *prims = g.prims;
    if (g.nt == 0) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: no triangles (%u meshes, %lld other "
                           "primitives)", what, sc->mNumMeshes, g.prims);
        goto done;
    }
    rc = mio_alloc(raw, (size_t)g.nv, (size_t)g.nt, g.all_nrm, g.all_uv, err);
    if (rc)
        goto done;
    g.fill = 1;
    g.out = raw;
    g.nv = g.nt = 0;
    rc = mio_gather_pass(&g, by_nodes, err);
    if (!rc && (g.nv != raw->nverts || g.nt != raw->ntris))
        rc = glint_err_set(err, GLINT_EINTERNAL, "%s: mesh merge counted %d/%d, copied %lld/%lld",
                           what, raw->nverts, raw->ntris, g.nv, g.nt);
done:
    aiReleaseImport(sc);
    if (rc)
        mesh_free(raw);
    return rc;
}

/* ---- the import in a child process ---------------------------------------
 *
 * assimp 5.2 crashes (SIGSEGV in its COLLADA reader on a mangled attribute
 * name), aborts (ai_assert is compiled in and calls abort()) or loops on
 * some malformed files that no pre-scan can rule out.  A daemon must
 * survive every upload, so the import runs in a forked child: the child
 * imports, merges and checks (mio_import_direct) and writes the raw soup
 * to a pipe; the parent reads it, with a time limit, and maps the child's
 * death by a signal to an error.  The child has a memory limit (its
 * current address space plus 2 GiB plus 32 bytes per byte of input; not
 * in sanitizer builds, whose shadow memory needs the address space),
 * writes nothing to stdout, and its stderr (assimp's assertion text, a
 * sanitizer report) is captured into the error message.  Each import has
 * its own process, so concurrent loads need no lock around assimp's
 * process-wide error string. */

#if defined(__SANITIZE_ADDRESS__)
#define MIO_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MIO_SANITIZED 1
#endif
#endif

#ifdef MIO_SANITIZED
/* The sanitizer runtimes of GCC 12 do not make their allocator fork-safe:
 * a child forked while another thread holds an allocator lock deadlocks
 * (until the time limit).  Sanitizer builds therefore run whole loads one
 * at a time, so that at least glint's own threads are not allocating
 * during the fork.  Production builds use glibc's malloc, which is. */
static pthread_mutex_t mio_sanitizer_lock = PTHREAD_MUTEX_INITIALIZER;
#endif

#define MIO_WIRE_MAGIC 0x676c6d31u /* "glm1" */

typedef struct mio_wire {
    uint32_t magic;
    int32_t rc;
    char msg[GLINT_ERR_MSG_MAX];
    int64_t nv, nt, prims;
    int32_t has_nrm, has_uv;
} mio_wire;

static int mio_write_all(int fd, const void *p, size_t n)
{
    const char *c = p;
    while (n) {
        ssize_t w = write(fd, c, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        c += w;
        n -= (size_t)w;
    }
    return 0;
}

static void mio_child(int fd, const char *path, const void *data, size_t len, const char *hint,
                      const char *what)
{
    mio_wire w;
    mesh raw;
    long long prims = 0;
    glint_err e;
    int rc;

#ifndef MIO_SANITIZED
    {
        FILE *f = fopen("/proc/self/statm", "r");
        unsigned long long pages = 0;
        if (f) {
            if (fscanf(f, "%llu", &pages) != 1)
                pages = 0;
            fclose(f);
        }
        if (pages) {
            struct rlimit rl;
            unsigned long long lim = pages * (unsigned long long)sysconf(_SC_PAGESIZE) +
                                     (2ull << 30) + 32ull * (unsigned long long)len;
            rl.rlim_cur = rl.rlim_max = (rlim_t)lim;
            (void)setrlimit(RLIMIT_AS, &rl);
        }
    }
#endif
    memset(&w, 0, sizeof w);
    memset(&e, 0, sizeof e);
    rc = mio_import_direct(path, data, len, hint, what, &raw, &prims, &e);
    w.magic = MIO_WIRE_MAGIC;
    w.rc = rc;
    memcpy(w.msg, e.msg, sizeof w.msg);
    if (!rc) {
        w.nv = raw.nverts;
        w.nt = raw.ntris;
        w.prims = prims;
        w.has_nrm = raw.nrm != NULL;
        w.has_uv = raw.uv != NULL;
    }
    if (mio_write_all(fd, &w, sizeof w) ||
        (!rc && (mio_write_all(fd, raw.pos, 3 * sizeof(float) * (size_t)raw.nverts) ||
                 (raw.nrm && mio_write_all(fd, raw.nrm, 3 * sizeof(float) * (size_t)raw.nverts)) ||
                 (raw.uv && mio_write_all(fd, raw.uv, 2 * sizeof(float) * (size_t)raw.nverts)) ||
                 mio_write_all(fd, raw.tri, 3 * sizeof(uint32_t) * (size_t)raw.ntris))))
        _exit(3);
    _exit(0);
}

/* Where the next bytes from the child go. */
typedef struct mio_sink {
    mio_wire w;
    unsigned char *seg[5];
    size_t seglen[5];
    int nseg, cur;
    size_t off;      /* into the current segment */
    int header_done;
    mesh *raw;
    int bad;         /* the child sent something inconsistent */
} mio_sink;

static void mio_sink_plan(mio_sink *k, glint_err *err)
{
    const mio_wire *w = &k->w;
    k->header_done = 1;
    k->nseg = 0;
    if (w->magic != MIO_WIRE_MAGIC) {
        k->bad = 1;
        return;
    }
    if (w->rc)
        return;
    if (w->nv < 1 || w->nt < 1 || w->nv > MESH_MAX_VERTS || w->nt > MESH_MAX_TRIS) {
        k->bad = 1;
        return;
    }
    if (mio_alloc(k->raw, (size_t)w->nv, (size_t)w->nt, w->has_nrm, w->has_uv, err)) {
        k->bad = 2;
        return;
    }
    k->seg[k->nseg] = (unsigned char *)k->raw->pos;
    k->seglen[k->nseg++] = 3 * sizeof(float) * (size_t)w->nv;
    if (w->has_nrm) {
        k->seg[k->nseg] = (unsigned char *)k->raw->nrm;
        k->seglen[k->nseg++] = 3 * sizeof(float) * (size_t)w->nv;
    }
    if (w->has_uv) {
        k->seg[k->nseg] = (unsigned char *)k->raw->uv;
        k->seglen[k->nseg++] = 2 * sizeof(float) * (size_t)w->nv;
    }
    k->seg[k->nseg] = (unsigned char *)k->raw->tri;
    k->seglen[k->nseg++] = 3 * sizeof(uint32_t) * (size_t)w->nt;
}

/* Read what is available on the result pipe: 1 at EOF, 0 for more, -1 on
 * error or excess data. */
static int mio_sink_read(mio_sink *k, int fd, glint_err *err)
{
    unsigned char scratch[4096];
    for (;;) {
        unsigned char *dst;
        size_t room;
        ssize_t r;
        if (!k->header_done) {
            dst = (unsigned char *)&k->w + k->off;
            room = sizeof k->w - k->off;
        } else if (k->cur < k->nseg && !k->bad) {
            dst = k->seg[k->cur] + k->off;
            room = k->seglen[k->cur] - k->off;
        } else {
            dst = scratch; /* nothing more is expected: drain and flag */
            room = sizeof scratch;
        }
        r = read(fd, dst, room);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            return 0;
        if (r < 0)
            return -1;
        if (r == 0)
            return 1;
        if (dst == scratch) {
            k->bad = k->bad ? k->bad : 1;
            continue;
        }
        k->off += (size_t)r;
        if (!k->header_done && k->off == sizeof k->w) {
            k->off = 0;
            mio_sink_plan(k, err);
        } else if (k->header_done && k->off == k->seglen[k->cur]) {
            k->off = 0;
            k->cur++;
        }
    }
}

static double mio_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

static int mio_import(const char *path, const void *data, size_t len, const char *hint,
                      const char *what, mesh *raw, long long *prims, glint_err *err)
{
    int out[2] = {-1, -1}, errp[2] = {-1, -1}, rc, status = 0, reaped = 0, timed_out = 0;
    int open_out, open_err;
    char errtext[400];
    size_t nerr = 0;
    double deadline;
    mio_sink k;
    pid_t pid;

    memset(raw, 0, sizeof *raw);
    memset(&k, 0, sizeof k);
    k.raw = raw;
    errtext[0] = '\0';
    if (pipe(out) || pipe(errp)) {
        rc = glint_err_set(err, GLINT_EIO, "%s: cannot create a pipe for the importer: %s", what,
                           strerror(errno));
        goto done;
    }
    for (int i = 0; i < 2; i++) { /* not inherited by programs other threads exec */
        fcntl(out[i], F_SETFD, FD_CLOEXEC);
        fcntl(errp[i], F_SETFD, FD_CLOEXEC);
    }
    pid = fork();
    if (pid < 0) {
        rc = glint_err_set(err, errno == ENOMEM || errno == EAGAIN ? GLINT_ENOMEM : GLINT_EIO,
                           "%s: cannot start the importer process: %s", what, strerror(errno));
        goto done;
    }
    if (pid == 0) {
        /* fd 3 <- result pipe, 2 <- stderr pipe, 1 <- /dev/null; the pipe
         * ends are first moved out of the way of 0..3 */
        int wfd = fcntl(out[1], F_DUPFD, 10), efd = fcntl(errp[1], F_DUPFD, 10);
        int devnull = open("/dev/null", O_WRONLY);
        if (wfd < 0 || efd < 0)
            _exit(5);
        if (devnull >= 0 && devnull != 1)
            dup2(devnull, 1);
        dup2(efd, 2);
        dup2(wfd, 3);
        /* nothing of the parent's (sockets, files) stays open in the child */
#ifdef SYS_close_range
        if (syscall(SYS_close_range, 4u, ~0u, 0u) != 0)
#endif
            for (int fd = 4; fd < 4096; fd++)
                close(fd);
        /* a crash ends the child by its signal (the parent reports it) */
        signal(SIGSEGV, SIG_DFL);
        signal(SIGBUS, SIG_DFL);
        signal(SIGFPE, SIG_DFL);
        signal(SIGILL, SIG_DFL);
        signal(SIGABRT, SIG_DFL);
        signal(SIGPIPE, SIG_DFL);
        mio_child(3, path, data, len, hint, what);
        _exit(4); /* not reached */
    }
    close(out[1]);
    close(errp[1]);
    out[1] = errp[1] = -1;
    fcntl(out[0], F_SETFL, fcntl(out[0], F_GETFL) | O_NONBLOCK);
    fcntl(errp[0], F_SETFL, fcntl(errp[0], F_GETFL) | O_NONBLOCK);
    deadline = mio_now() + MESH_IMPORT_TIMEOUT_S;
    open_out = open_err = 1;
    while (open_out || open_err) {
        struct pollfd pf[2];
        int np = 0, wait_ms;
        double left = deadline - mio_now();
        if (left <= 0) {
            timed_out = 1;
            break;
        }
        wait_ms = left > 1000.0 ? 1000000 : (int)(left * 1000.0) + 1;
        if (open_out)
            pf[np++] = (struct pollfd){.fd = out[0], .events = POLLIN};
        if (open_err)
            pf[np++] = (struct pollfd){.fd = errp[0], .events = POLLIN};
        if (poll(pf, (nfds_t)np, wait_ms) < 0) {
            if (errno == EINTR)
                continue;
            break;
        }
        for (int i = 0; i < np; i++) {
            if (!(pf[i].revents & (POLLIN | POLLHUP | POLLERR)))
                continue;
            if (pf[i].fd == out[0]) {
                int r = mio_sink_read(&k, out[0], err);
                if (r != 0)
                    open_out = 0;
            } else {
                for (;;) {
                    char b[512];
                    ssize_t r = read(errp[0], b, sizeof b);
                    if (r < 0 && errno == EINTR)
                        continue;
                    if (r == 0 || (r < 0 && errno != EAGAIN && errno != EWOULDBLOCK))
                        open_err = 0;
                    if (r <= 0)
                        break;
                    for (ssize_t j = 0; j < r && nerr + 1 < sizeof errtext; j++)
                        errtext[nerr++] = b[j] == '\n' || b[j] == '\r' ? ' ' : b[j];
                    errtext[nerr] = '\0';
                }
            }
        }
    }
    if (timed_out)
        kill(pid, SIGKILL);
    for (;;) {
        pid_t w = waitpid(pid, &status, 0);
        if (w == pid) {
            reaped = 1;
            break;
        }
        if (w < 0 && errno == EINTR)
            continue;
        break; /* ECHILD: SIGCHLD ignored by the application; judge by the data */
    }
    if (timed_out) {
        rc = glint_err_set(err, GLINT_ERANGE, "%s: reading it took more than %d s (the limit)",
                           what, MESH_IMPORT_TIMEOUT_S);
        goto done;
    }
    if (reaped && WIFSIGNALED(status)) {
        int sig = WTERMSIG(status);
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: the importer (assimp) crashed on it (signal %d, %s)%s%s: the "
                           "file is malformed", what, sig, strsignal(sig), nerr ? ": " : "",
                           errtext);
        goto done;
    }
    if (k.bad == 2) { /* out of memory for the arrays: err is set */
        rc = GLINT_ENOMEM;
        goto done;
    }
    if (!k.header_done && strstr(errtext, "DEADLYSIGNAL")) {
        /* a sanitizer build reports the crash itself and exits */
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: the importer (assimp) crashed on it: %s: the file is malformed",
                           what, errtext);
        goto done;
    }
    if (!k.header_done || k.bad || (reaped && (!WIFEXITED(status) || WEXITSTATUS(status) != 0)) ||
        (k.w.rc == 0 && k.cur != k.nseg)) {
        rc = glint_err_set(err, strstr(errtext, "Sanitizer") ? GLINT_EINTERNAL : GLINT_EFORMAT,
                           "%s: the importer process failed (exit status %d)%s%s", what,
                           reaped && WIFEXITED(status) ? WEXITSTATUS(status) : -1,
                           nerr ? ": " : "", errtext);
        goto done;
    }
    if (k.w.rc) {
        k.w.msg[sizeof k.w.msg - 1] = '\0';
        rc = glint_err_set(err, k.w.rc < 0 && k.w.rc >= GLINT_EINTERNAL ? k.w.rc : GLINT_EINTERNAL,
                           "%s", k.w.msg);
        /* assimp reports exhausting the child's memory limit as bad_alloc */
        if (strstr(k.w.msg, "bad_alloc"))
            rc = glint_err_set(err, GLINT_ERANGE,
                               "%s: reading it needs more memory than the importer may use "
                               "(%s)", what, k.w.msg);
        goto done;
    }
    *prims = k.w.prims;
    rc = 0;
done:
    for (int i = 0; i < 2; i++) {
        if (out[i] >= 0)
            close(out[i]);
        if (errp[i] >= 0)
            close(errp[i]);
    }
    if (rc)
        mesh_free(raw);
    return rc;
}

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
                           const char *what, mesh *out, mesh_report *report, glint_err *err);

static int mio_load(const char *path, const void *data, size_t len, const char *fmt,
                    const char *what, mesh *out, mesh_report *report, glint_err *err)
{
#ifdef MIO_SANITIZED
    int rc;
    pthread_mutex_lock(&mio_sanitizer_lock);
    rc = mio_load_locked(path, data, len, fmt, what, out, report, err);
    pthread_mutex_unlock(&mio_sanitizer_lock);
    return rc;
#else
    return mio_load_locked(path, data, len, fmt, what, out, report, err);
#endif
}

static int mio_load_locked(const char *path, const void *data, size_t len, const char *fmt,
                           const char *what, mesh *out, mesh_report *report, glint_err *err)
{
    mesh_report rep;
    mesh m;
    long long prims = 0;
    int rc, rescaled = 0;

    memset(&rep, 0, sizeof rep);
    snprintf(rep.format, sizeof rep.format, "%s", *fmt ? fmt : "unknown");
    if (data) {
        rc = mio_prescan(data, len, fmt, what, err);
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
            rc = mio_prescan(map, len, fmt, path, err);
            munmap(map, len);
            if (rc)
                goto done;
        }
    }
    close(fd);
    fd = -1;
    rc = mio_load(path, NULL, len, fmt, path, out, report, err);
done:
    if (fd >= 0)
        close(fd);
    return rc;
}

int mesh_load_mem(const void *data, size_t len, const char *hint, mesh *out,
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
    return mio_load(NULL, data, len, fmt, what, out, report, err);
}
