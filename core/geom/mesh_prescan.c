/* mesh_prescan.c: structural pre-scan of PLY, OFF and OBJ data, before
 * assimp sees it (step 2 of loading, see mesh_io.c).
 *
 * PLY and OFF are the two formats whose headers declare element counts.  A
 * count over the limits (the caller's triangle limit for faces) is
 * GLINT_ERANGE before assimp allocates for it, and data that ends before
 * the declared elements is GLINT_EFORMAT: assimp 5.2 silently repeats the
 * last face of a truncated ASCII PLY, zero-fills a truncated OFF and loops
 * forever on a PLY header without end_header.  A PLY element of more than
 * MIO_PLY_MAX_PROPS properties, and a header of more than
 * MIO_PLY_MAX_HEADER_LINES lines, are GLINT_ERANGE (assimp 5.2 took 17 s
 * over 100,000 properties, 57 s over 100,000 comment lines).  OFF lines of
 * MIO_OFF_MAX_LINE bytes or more are refused (assimp 5.2's OFF reader copies
 * lines into a 4096-byte stack buffer and writes one byte past it).  OBJ
 * declares nothing: its face
 * lines are counted, each of k corners making k - 2 triangles (assimp's
 * triangulation), and a file over the triangle limit is GLINT_ERANGE
 * before assimp reads it (2.1 million triangles took assimp and the steps
 * after it minutes and a gigabyte).  Headers the scan does not understand
 * are left to assimp, which reports them. */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "internal/mesh_int.h"

/* Longest list in a PLY element we accept in the pre-scan. */
#define MIO_PLY_MAX_LIST 65536
/* assimp 5.2's line buffer (ParsingUtils.h BufferSize). */
#define MIO_OFF_MAX_LINE 4096

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
/* Lines of a PLY header, end_header included: assimp 5.2 reads a header in
 * time growing with the square of its lines (1 s for 10,000 comment lines,
 * 57 s for 100,000); the declarations allowed take at most 4,161. */
#define MIO_PLY_MAX_HEADER_LINES 4096

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

static int mio_ply_too_many(const char *what, unsigned long long n, unsigned long long max,
                            glint_err *err)
{
    return glint_err_set(err, GLINT_ERANGE,
                         "%s: PLY data makes %llu or more triangles, more than the limit of "
                         "%llu", what, n, max);
}

/* What the PLY scan has learnt so far. */
typedef struct mio_ply_scan {
    const char *what;
    long max_tris;
    mio_ply_elem *el;         /* MIO_PLY_MAX_ELEMS of them, nel declared */
    int nel;
    int fmt;                  /* -1 not declared, 0 ascii, 1 little endian, 2 big endian */
    int understood;           /* 0: a declaration the scan cannot read (assimp will say) */
    const char *data;         /* just after the end_header line; NULL before it is found */
    unsigned long long tris;  /* triangles the face lists make so far */
} mio_ply_scan;

/* Results of a header line besides an error: go on to the next line, or
 * stop reading the header (end_header found, or a declaration not
 * understood). */
#define MIO_PLY_NEXT 0
#define MIO_PLY_STOP 1

/* "element NAME COUNT" (the rest of the line at *q): the count against the
 * limits, a face being one triangle at least. */
static int mio_ply_decl_element(mio_ply_scan *s, const char **q, const char *eol,
                                glint_err *err)
{
    mio_ply_elem *e;
    const char *name, *tok;
    size_t nl, tl;
    if (s->nel == MIO_PLY_MAX_ELEMS)
        return glint_err_set(err, GLINT_EFORMAT, "%s: PLY header declares more than %d elements",
                             s->what, MIO_PLY_MAX_ELEMS);
    e = &s->el[s->nel++];
    if (!mio_token(q, eol, &name, &nl) || !mio_token(q, eol, &tok, &tl) ||
        !mio_count(tok, tl, &e->count)) {
        s->understood = 0; /* malformed: assimp will say so */
        return MIO_PLY_STOP;
    }
    snprintf(e->name, sizeof e->name, "%.*s", (int)(nl < 31 ? nl : 31), name);
    if (e->count > (unsigned long long)MESH_MAX_VERTS ||
        (strcmp(e->name, "face") == 0 && e->count > (unsigned long long)s->max_tris))
        return glint_err_set(err, GLINT_ERANGE,
                             "%s: PLY header declares %llu \"%s\" elements, more than the limit "
                             "of %ld", s->what, e->count, e->name,
                             strcmp(e->name, "face") == 0 ? s->max_tris : (long)MESH_MAX_VERTS);
    return MIO_PLY_NEXT;
}

/* "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME" (the
 * rest of the line at *q), for the last element declared. */
static int mio_ply_decl_property(mio_ply_scan *s, const char **q, const char *eol,
                                 glint_err *err)
{
    mio_ply_elem *e = s->nel ? &s->el[s->nel - 1] : NULL;
    mio_ply_prop *pr;
    const char *tok;
    size_t tl;
    int sgn = 0;
    if (e && e->nprops == MIO_PLY_MAX_PROPS)
        return glint_err_set(err, GLINT_ERANGE,
                             "%s: PLY element \"%s\" declares more than %d properties (the "
                             "limit)", s->what, e->name, MIO_PLY_MAX_PROPS);
    if (!e || !mio_token(q, eol, &tok, &tl)) {
        s->understood = 0;
        return MIO_PLY_STOP;
    }
    pr = &e->props[e->nprops++];
    if (mio_tok_is(tok, tl, "list")) {
        pr->list = 1;
        if (!mio_token(q, eol, &tok, &tl) || !(pr->csize = mio_ply_type(tok, tl, &sgn))) {
            s->understood = 0;
            return MIO_PLY_STOP;
        }
        pr->csigned = sgn;
        if (!mio_token(q, eol, &tok, &tl) || !(pr->size = mio_ply_type(tok, tl, NULL))) {
            s->understood = 0;
            return MIO_PLY_STOP;
        }
    } else if (!(pr->size = mio_ply_type(tok, tl, NULL))) {
        s->understood = 0;
        return MIO_PLY_STOP;
    }
    return MIO_PLY_NEXT;
}

/* One header line [p, eol): end_header, format, element and property are
 * read; comment, obj_info and anything else are ignored. */
static int mio_ply_header_line(mio_ply_scan *s, const char *p, const char *eol,
                               const char *end, glint_err *err)
{
    const char *q = p, *tok;
    size_t tl;
    if (!mio_token(&q, eol, &tok, &tl))
        return MIO_PLY_NEXT;
    if (mio_tok_is(tok, tl, "end_header")) {
        s->data = eol < end ? eol + 1 : end;
        return MIO_PLY_STOP;
    }
    if (mio_tok_is(tok, tl, "format")) {
        if (mio_token(&q, eol, &tok, &tl)) {
            if (mio_tok_is(tok, tl, "ascii"))
                s->fmt = 0;
            else if (mio_tok_is(tok, tl, "binary_little_endian"))
                s->fmt = 1;
            else if (mio_tok_is(tok, tl, "binary_big_endian"))
                s->fmt = 2;
        }
        return MIO_PLY_NEXT;
    }
    if (mio_tok_is(tok, tl, "element"))
        return mio_ply_decl_element(s, &q, eol, err);
    if (mio_tok_is(tok, tl, "property"))
        return mio_ply_decl_property(s, &q, eol, err);
    return MIO_PLY_NEXT;
}

/* The header, one declaration per line up to end_header (or to the first
 * declaration not understood), within MIO_PLY_MAX_HEADER_LINES lines. */
static int mio_ply_header(mio_ply_scan *s, const char *buf, const char *end, glint_err *err)
{
    const char *p = buf;
    long lines = 0;
    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        int rc;
        if (!eol)
            eol = end;
        if (++lines > MIO_PLY_MAX_HEADER_LINES)
            return glint_err_set(err, GLINT_ERANGE,
                                 "%s: PLY header has more than %d lines (the limit)", s->what,
                                 MIO_PLY_MAX_HEADER_LINES);
        rc = mio_ply_header_line(s, p, eol, end, err);
        if (rc < 0)
            return rc;
        if (rc == MIO_PLY_STOP)
            break;
        p = eol < end ? eol + 1 : end;
    }
    return 0;
}

/* Just after the first end_header line of [buf, end), or NULL. */
static const char *mio_ply_find_end_header(const char *buf, const char *end)
{
    for (const char *q = buf; q < end;) {
        const char *eol = memchr(q, '\n', (size_t)(end - q)), *r = q, *tok;
        size_t tl;
        if (!eol)
            eol = end;
        if (mio_token(&r, eol, &tok, &tl) && mio_tok_is(tok, tl, "end_header"))
            return eol < end ? eol + 1 : end;
        q = eol < end ? eol + 1 : end;
    }
    return NULL;
}

/* A list of n items in property j: if it is the face's first list
 * (`corners`), its n - 2 triangles count against the limit. */
static int mio_ply_count_tris(mio_ply_scan *s, int j, int corners, unsigned long long n,
                              glint_err *err)
{
    if (j == corners && n >= 3 && (s->tris += n - 2) > (unsigned long long)s->max_tris)
        return mio_ply_too_many(s->what, s->tris, (unsigned long long)s->max_tris, err);
    return 0;
}

/* ASCII property j of element e's record i at *p: its tokens present, and
 * a list's length a count in range. */
static int mio_ply_ascii_prop(mio_ply_scan *s, const mio_ply_elem *e, unsigned long long i,
                              int j, int corners, const char **p, const char *end,
                              glint_err *err)
{
    const char *tok;
    size_t tl;
    unsigned long long n;
    int rc;
    if (!mio_token(p, end, &tok, &tl))
        return mio_ply_truncated(s->what, e, i, err);
    if (!e->props[j].list)
        return 0;
    if (!mio_count(tok, tl, &n) || n > MIO_PLY_MAX_LIST)
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: PLY element \"%s\" %llu: list length \"%.*s\" is not a count "
                             "in 0..%d", s->what, e->name, i, (int)(tl < 32 ? tl : 32), tok,
                             MIO_PLY_MAX_LIST);
    if ((rc = mio_ply_count_tris(s, j, corners, n, err)))
        return rc;
    for (unsigned long long t = 0; t < n; t++)
        if (!mio_token(p, end, &tok, &tl))
            return mio_ply_truncated(s->what, e, i, err);
    return 0;
}

/* A binary list count of pr->csize bytes at p, in the file's byte order;
 * -1 for a negative one or one beyond LLONG_MAX. */
static long long mio_ply_binary_count(const mio_ply_prop *pr, const char *p, int fmt)
{
    unsigned char b[8] = {0};
    unsigned long long u = 0;
    for (int c = 0; c < pr->csize; c++)
        b[c] = (unsigned char)p[fmt == 1 ? c : pr->csize - 1 - c];
    for (int c = pr->csize - 1; c >= 0; c--)
        u = (u << 8) | b[c];
    if (pr->csigned && pr->csize < 8 && (u >> (8 * pr->csize - 1)) & 1)
        return -1; /* negative count */
    return u > (unsigned long long)LLONG_MAX ? -1 : (long long)u;
}

/* Binary property j of element e's record i at *p: its bytes present, and
 * a list's count in range. */
static int mio_ply_binary_prop(mio_ply_scan *s, const mio_ply_elem *e, unsigned long long i,
                               int j, int corners, const char **p, const char *end,
                               glint_err *err)
{
    const mio_ply_prop *pr = &e->props[j];
    long long n;
    int rc;
    if (!pr->list) {
        if ((size_t)(end - *p) < (size_t)pr->size)
            return mio_ply_truncated(s->what, e, i, err);
        *p += pr->size;
        return 0;
    }
    if ((size_t)(end - *p) < (size_t)pr->csize)
        return mio_ply_truncated(s->what, e, i, err);
    n = mio_ply_binary_count(pr, *p, s->fmt);
    *p += pr->csize;
    if (n < 0 || n > MIO_PLY_MAX_LIST)
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: PLY element \"%s\" %llu: list length %lld outside 0..%d",
                             s->what, e->name, i, n, MIO_PLY_MAX_LIST);
    if ((rc = mio_ply_count_tris(s, j, corners, (unsigned long long)n, err)))
        return rc;
    if ((size_t)(end - *p) / (size_t)pr->size < (size_t)n)
        return mio_ply_truncated(s->what, e, i, err);
    *p += (size_t)n * (size_t)pr->size;
    return 0;
}

/* Element e's records from *p: a binary element of scalars is skipped as
 * one block; otherwise property by property. */
static int mio_ply_walk_elem(mio_ply_scan *s, const mio_ply_elem *e, const char **p,
                             const char *end, glint_err *err)
{
    int all_scalar = 1, corners = -1; /* the face's first list: its corners */
    size_t rec = 0;
    for (int j = 0; j < e->nprops; j++) {
        all_scalar &= !e->props[j].list;
        rec += (size_t)e->props[j].size;
        if (e->props[j].list && corners < 0 && strcmp(e->name, "face") == 0)
            corners = j;
    }
    if (s->fmt != 0 && all_scalar) {
        size_t left = (size_t)(end - *p);
        if (rec && left / rec < e->count)
            return mio_ply_truncated(s->what, e, left / rec, err);
        *p += rec * (size_t)e->count;
        return 0;
    }
    for (unsigned long long i = 0; i < e->count; i++)
        for (int j = 0; j < e->nprops; j++) {
            int rc = s->fmt == 0 ? mio_ply_ascii_prop(s, e, i, j, corners, p, end, err)
                                 : mio_ply_binary_prop(s, e, i, j, corners, p, end, err);
            if (rc)
                return rc;
        }
    return 0;
}

/* PLY: header counts against the limits, then a walk over the data that
 * checks every declared element is present.  Headers this scan does not
 * understand are left to assimp. */
static int mio_prescan_ply(const char *buf, size_t len, const char *what, long max_tris,
                           glint_err *err)
{
    const char *end = buf + len, *p;
    mio_ply_scan s;
    int rc;

    memset(&s, 0, sizeof s);
    s.what = what;
    s.max_tris = max_tris;
    s.fmt = -1;
    s.understood = 1;
    s.el = calloc(MIO_PLY_MAX_ELEMS, sizeof *s.el);
    if (!s.el)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory scanning %s", what);
    rc = mio_ply_header(&s, buf, end, err);
    if (!rc && !s.data) /* the header loop may have stopped early: look again */
        s.data = mio_ply_find_end_header(buf, end);
    if (!rc && !s.data) /* assimp 5.2 loops forever on a PLY header without end_header */
        rc = glint_err_set(err, GLINT_EFORMAT,
                           "%s: PLY header has no end_header line (truncated file)", what);
    /* malformed declarations are left to assimp, which reports them */
    if (!rc && s.understood && s.fmt >= 0) {
        p = s.data;
        for (int k = 0; k < s.nel && !rc; k++)
            rc = mio_ply_walk_elem(&s, &s.el[k], &p, end, err);
    }
    free(s.el);
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
                           long max_tris, glint_err *err)
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
    if (nv > (unsigned long long)MESH_MAX_VERTS || nf > (unsigned long long)max_tris)
        return glint_err_set(err, GLINT_ERANGE,
                             "%s: OFF header declares %llu vertices and %llu faces, more than "
                             "the limits of %d and %ld", what, nv, nf, MESH_MAX_VERTS, max_tris);
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

/* OBJ: the triangles of its face lines ("f" and "fo", assimp's
 * ObjFileParser; k corners make k - 2 triangles) and its vertex lines,
 * against the limits.  A line's first byte and token decide, as for assimp
 * (which skips a line that begins with whitespace). */
static int mio_prescan_obj(const char *buf, size_t len, const char *what, long max_tris,
                           glint_err *err)
{
    const char *p = buf, *end = buf + len;
    unsigned long long tris = 0, verts = 0;

    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p)), *q = p, *tok;
        size_t tl;
        if (!eol)
            eol = end;
        if ((*p == 'f' || *p == 'v') && mio_token(&q, eol, &tok, &tl)) {
            if (mio_tok_is(tok, tl, "f") || mio_tok_is(tok, tl, "fo")) {
                unsigned long long k = 0;
                while (mio_token(&q, eol, &tok, &tl))
                    k++;
                if (k >= 3)
                    tris += k - 2;
            } else if (mio_tok_is(tok, tl, "v")) {
                verts++;
            }
        }
        p = eol < end ? eol + 1 : end;
    }
    if (tris > (unsigned long long)max_tris)
        return glint_err_set(err, GLINT_ERANGE,
                             "%s: its faces make %llu triangles, more than the limit of %ld",
                             what, tris, max_tris);
    if (verts > (unsigned long long)MESH_MAX_VERTS)
        return glint_err_set(err, GLINT_ERANGE,
                             "%s: it declares %llu vertices, more than the limit of %d", what,
                             verts, MESH_MAX_VERTS);
    return 0;
}

/* Dispatch on content (PLY magic, OFF header) or name. */
int mio_prescan(const char *buf, size_t len, const char *fmt, const char *what, long max_tris,
                glint_err *err)
{
    int rc;
    if (max_tris <= 0 || max_tris > MESH_MAX_TRIS)
        max_tris = MESH_MAX_TRIS;
    /* named .ply, whatever it holds: assimp's PLY reader takes "ply" in any
     * case followed by anything, and loops without end_header (found by
     * tests/fuzz: "plY", "ply)", "ply3ds" ...) */
    if (strcmp(fmt, "ply") == 0 ||
        (len >= 4 && strncasecmp(buf, "ply", 3) == 0 && mio_space(buf[3])))
        return mio_prescan_ply(buf, len, what, max_tris, err);
    if ((rc = mio_prescan_off(buf, len, strcmp(fmt, "off") == 0, what, max_tris, err)))
        return rc;
    return strcmp(fmt, "obj") == 0 ? mio_prescan_obj(buf, len, what, max_tris, err) : 0;
}
