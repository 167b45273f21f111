/* mesh_refs.c: the references to other files an upload's bytes make,
 * found in the text itself (contract at mesh_refs_check in mesh.h).
 *
 * The import (mesh_fileio.c) refuses every file an upload asks it to open
 * and every unsafe texture path it records, but an importer never sees a
 * reference it has no use for: a glTF image no material samples, a
 * COLLADA image no effect uses, an OBJ material library it could not
 * open.  An upload is meant to carry all its data itself, so every
 * reference it writes is refused, used or not, before the import:
 *  - glTF (.gltf text, and the JSON chunk of a .glb): every "uri" member
 *    with a string value, at any depth (buffers, images, extensions);
 *  - COLLADA: the text of <init_from> (an image's file; not the image id
 *    that a <surface>'s <init_from> names) and of <ref> (COLLADA 1.5),
 *    CDATA included, and every url= or source= attribute that does not
 *    point into the document ('#'), and the literal a DOCTYPE or ENTITY
 *    declaration names after SYSTEM or PUBLIC;
 *  - OBJ: the mtllib, maplib, call, shadow_obj and trace_obj statements;
 *  - PLY: a header's "comment TextureFile NAME" (or obj_info).
 * data: URIs are part of the file and pass.  The scan keeps no more than
 * a reference's first MREF_KEEP bytes, whatever the upload's size: memory
 * is constant, time linear.  glTF and COLLADA are also recognized by their
 * content, whatever the format given, so that a file named as another
 * format is scanned for what it is. */
#include <ctype.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "internal/mesh_int.h"

/* Bytes of a reference kept (to check its scheme and to show it). */
#define MREF_KEEP 256

/* A reference's text, cut to MREF_KEEP bytes. */
typedef struct mref {
    char s[MREF_KEEP + 1];
    size_t n;      /* bytes kept */
    size_t total;  /* bytes the reference has */
} mref;

static void mref_put(mref *r, char c)
{
    if (r->n < MREF_KEEP)
        r->s[r->n++] = c;
    r->s[r->n] = '\0';
    r->total++;
}

/* n bytes at s (kept as far as there is room). */
static void mref_append(mref *r, const char *s, size_t n)
{
    size_t room = MREF_KEEP - r->n, k = n < room ? n : room;
    memcpy(r->s + r->n, s, k);
    r->n += k;
    r->s[r->n] = '\0';
    r->total += n;
}

/* Leading and trailing whitespace removed (of what was kept). */
static void mref_trim(mref *r)
{
    size_t a = 0;
    while (r->n && isspace((unsigned char)r->s[r->n - 1]))
        r->s[--r->n] = '\0';
    while (a < r->n && isspace((unsigned char)r->s[a]))
        a++;
    memmove(r->s, r->s + a, r->n - a + 1);
    r->n -= a;
    r->total = r->n;
}

/* 0 when the reference is part of the file (a data: URI); else the refusal. */
static int mref_judge(const mref *r, const char *what, glint_err *err)
{
    if (strncasecmp(r->s, "data:", 5) == 0)
        return 0;
    return mio_upload_refuse(r->s, what, err);
}

/* ---- glTF ------------------------------------------------------------------ */

static int hexval(char c)
{
    return c >= '0' && c <= '9' ? c - '0' : (tolower((unsigned char)c) - 'a' + 10);
}

/* The JSON string whose opening quote is just before *p, decoded into r
 * (\uXXXX of ASCII as the character, others as '?'); *p moves past its
 * closing quote.  -1 when it does not end before `end`. */
static int json_str(const char **p, const char *end, mref *r)
{
    const char *q = *p, *quote = NULL, *bs;
    memset(r, 0, sizeof *r);
    for (;;) {
        char c;
        /* runs without escapes (a data: URI's megabytes) by memchr: the
         * next quote, found again only once an escape passed it */
        if ((!quote || quote < q) && !(quote = memchr(q, '"', (size_t)(end - q))))
            return -1;
        bs = memchr(q, '\\', (size_t)(quote - q));
        mref_append(r, q, (size_t)((bs ? bs : quote) - q));
        q = bs ? bs : quote;
        if (!bs)
            break;
        if (++q >= end) /* past the backslash */
            return -1;
        c = *q++;
        if (c == 'u') {
            unsigned v = 0;
            int k;
            for (k = 0; k < 4 && q < end && isxdigit((unsigned char)*q); k++, q++)
                v = 16 * v + (unsigned)hexval(*q);
            if (k < 4)
                return -1;
            c = v < 0x80 ? (char)v : '?';
        } else if (c == 'n' || c == 't' || c == 'r' || c == 'b' || c == 'f') {
            c = ' ';
        }
        mref_put(r, c);
    }
    *p = q + 1;
    return 0;
}

static const char *json_ws(const char *p, const char *end)
{
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r'))
        p++;
    return p;
}

/* Every "uri": "..." member in the JSON text [p, end).  Text that is not
 * JSON ends the scan: the import refuses it. */
static int scan_json(const char *p, const char *end, const char *what, glint_err *err)
{
    mref key, val;
    while (p < end) {
        const char *q;
        if (*p++ != '"')
            continue;
        if (json_str(&p, end, &key))
            return 0;
        q = json_ws(p, end);
        if (q >= end || *q != ':' || key.total != 3 || memcmp(key.s, "uri", 3) != 0)
            continue; /* a value, or another member: go on after it */
        q = json_ws(q + 1, end);
        if (q >= end || *q != '"')
            continue; /* not a string: no reference */
        q++;
        if (json_str(&q, end, &val))
            return 0;
        p = q;
        if (mref_judge(&val, what, err))
            return GLINT_EINVAL;
    }
    return 0;
}

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* A .glb: its first chunk, the JSON. */
static int scan_glb(const unsigned char *b, size_t len, const char *what, glint_err *err)
{
    size_t n;
    if (len < 20 || le32(b + 16) != 0x4E4F534Au) /* "JSON" */
        return 0;
    n = le32(b + 12);
    if (n > len - 20)
        n = len - 20;
    return scan_json((const char *)b + 20, (const char *)b + 20 + n, what, err);
}

/* ---- COLLADA ------------------------------------------------------------------ */

static int xml_name_char(char c)
{
    return isalnum((unsigned char)c) || c == '_' || c == '-' || c == ':' || c == '.';
}

static const char *find(const char *p, const char *end, const char *s)
{
    size_t n = strlen(s);
    for (; p + n <= end; p++) {
        if (!(p = memchr(p, s[0], (size_t)(end - p))) || p + n > end)
            return NULL;
        if (memcmp(p, s, n) == 0)
            return p;
    }
    return NULL;
}

/* The text of an element from p (just after its start tag) to its first
 * child element or end tag, CDATA sections included and comments left
 * out, trimmed (OUT: r). */
static void xml_text(const char *p, const char *end, mref *r)
{
    memset(r, 0, sizeof *r);
    while (p < end) {
        if (*p == '<') {
            const char *c;
            if (end - p >= 4 && !memcmp(p, "<!--", 4)) {
                c = find(p + 4, end, "-->");
                p = c ? c + 3 : end;
                continue;
            }
            if (end - p < 9 || memcmp(p, "<![CDATA[", 9) != 0)
                break;
            c = find(p + 9, end, "]]>");
            for (p += 9; p < (c ? c : end); p++)
                mref_put(r, *p);
            p = c ? c + 3 : end;
            continue;
        }
        mref_put(r, *p++);
    }
    mref_trim(r);
}

/* A DOCTYPE or ENTITY declaration from p (after "<!"): the quoted literal
 * after SYSTEM or PUBLIC, if any, judged.  *next: where the scan goes on. */
static int xml_decl(const char *p, const char *end, const char **next, const char *what,
                    glint_err *err)
{
    int after_id = 0;
    *next = end;
    while (p < end && *p != '>' && *p != '[') {
        if (*p == '"' || *p == '\'') {
            const char q = *p++;
            mref r;
            memset(&r, 0, sizeof r);
            while (p < end && *p != q)
                mref_put(&r, *p++);
            if (after_id && mref_judge(&r, what, err))
                return GLINT_EINVAL;
            p++;
            continue;
        }
        if (xml_name_char(*p)) {
            const char *s = p;
            while (p < end && xml_name_char(*p))
                p++;
            after_id |= (p - s == 6 && (!memcmp(s, "SYSTEM", 6) || !memcmp(s, "PUBLIC", 6)));
            continue;
        }
        p++;
    }
    *next = p;
    return 0;
}

/* The attributes of a start tag from p (after its name) to its '>' (OUT:
 * *gt, NULL when the text ends first): url= and source= judged unless
 * they point into the document. */
static int xml_attrs(const char *p, const char *end, const char **gt, const char *what,
                     glint_err *err)
{
    *gt = NULL;
    while (p < end) {
        const char *name;
        size_t nl;
        char q;
        mref r;
        if (*p == '>') {
            *gt = p;
            return 0;
        }
        if (!xml_name_char(*p)) {
            p++;
            continue;
        }
        for (name = p; p < end && xml_name_char(*p); p++)
            ;
        nl = (size_t)(p - name);
        p = json_ws(p, end);
        if (p >= end || *p != '=')
            continue;
        p = json_ws(p + 1, end);
        if (p >= end || (*p != '"' && *p != '\''))
            continue;
        q = *p++;
        memset(&r, 0, sizeof r);
        while (p < end && *p != q)
            mref_put(&r, *p++);
        if (p < end)
            p++;
        mref_trim(&r);
        if (((nl == 3 && !memcmp(name, "url", 3)) || (nl == 6 && !memcmp(name, "source", 6))) &&
            r.n && r.s[0] != '#' && mref_judge(&r, what, err))
            return GLINT_EINVAL;
    }
    return 0;
}

static int scan_xml(const char *p, const char *end, const char *what, glint_err *err)
{
    int in_surface = 0;
    while ((p = memchr(p, '<', (size_t)(end - p)))) {
        const char *name = p + 1, *ne, *gt;
        int closing = 0;
        if (end - p >= 4 && !memcmp(p, "<!--", 4)) { /* a comment */
            const char *c = find(p + 4, end, "-->");
            p = c ? c + 3 : end;
            continue;
        }
        if (end - p >= 9 && !memcmp(p, "<![CDATA[", 9)) {
            const char *c = find(p + 9, end, "]]>");
            p = c ? c + 3 : end;
            continue;
        }
        if (name < end && *name == '!') {
            if (xml_decl(name + 1, end, &p, what, err))
                return GLINT_EINVAL;
            continue;
        }
        if (name < end && *name == '?') {
            const char *c = find(name, end, "?>");
            p = c ? c + 2 : end;
            continue;
        }
        if (name < end && *name == '/') {
            closing = 1;
            name++;
        }
        for (ne = name; ne < end && xml_name_char(*ne); ne++)
            ;
        if (closing) {
            if (ne - name == 7 && !memcmp(name, "surface", 7) && in_surface)
                in_surface--;
            p = ne;
            continue;
        }
        if (xml_attrs(ne, end, &gt, what, err))
            return GLINT_EINVAL;
        if (!gt)
            return 0;
        p = gt + 1;
        if (gt[-1] == '/')
            continue; /* empty element */
        if (ne - name == 7 && !memcmp(name, "surface", 7))
            in_surface++;
        if ((ne - name == 9 && !memcmp(name, "init_from", 9) && !in_surface) ||
            (ne - name == 3 && !memcmp(name, "ref", 3))) {
            mref r;
            xml_text(p, end, &r);
            if (r.n && mref_judge(&r, what, err))
                return GLINT_EINVAL;
        }
    }
    return 0;
}

/* ---- OBJ and PLY ---------------------------------------------------------------- */

/* The line [p, e) as a statement: its keyword (OUT: *kw, *kwl) and the
 * rest, trimmed (OUT: r). */
static void line_split(const char *p, const char *e, const char **kw, size_t *kwl, mref *r)
{
    while (p < e && isspace((unsigned char)*p))
        p++;
    *kw = p;
    while (p < e && !isspace((unsigned char)*p))
        p++;
    *kwl = (size_t)(p - *kw);
    memset(r, 0, sizeof *r);
    while (p < e)
        mref_put(r, *p++);
    mref_trim(r);
}

static int word_is(const char *s, size_t n, const char *w)
{
    return strlen(w) == n && memcmp(s, w, n) == 0;
}

static int scan_obj(const char *p, const char *end, const char *what, glint_err *err)
{
    static const char *const stmts[] = {"mtllib", "maplib", "call", "shadow_obj", "trace_obj",
                                        NULL};
    while (p < end) {
        const char *e = memchr(p, '\n', (size_t)(end - p)), *kw;
        size_t kwl;
        mref r;
        if (!e)
            e = end;
        line_split(p, e, &kw, &kwl, &r);
        for (int i = 0; stmts[i]; i++)
            if (word_is(kw, kwl, stmts[i]) && r.n && mref_judge(&r, what, err))
                return GLINT_EINVAL;
        p = e + (e < end);
    }
    return 0;
}

/* The header's lines, up to end_header. */
static int scan_ply(const char *p, const char *end, const char *what, glint_err *err)
{
    while (p < end) {
        const char *e = memchr(p, '\n', (size_t)(end - p)), *kw;
        size_t kwl;
        mref r;
        if (!e)
            e = end;
        line_split(p, e, &kw, &kwl, &r);
        if (word_is(kw, kwl, "end_header"))
            return 0;
        if ((word_is(kw, kwl, "comment") || word_is(kw, kwl, "obj_info")) &&
            r.n > 11 && strncasecmp(r.s, "TextureFile", 11) == 0 &&
            isspace((unsigned char)r.s[11])) {
            memmove(r.s, r.s + 12, r.n - 11);
            r.n -= 12;
            mref_trim(&r);
            if (r.n && mref_judge(&r, what, err))
                return GLINT_EINVAL;
        }
        p = e + (e < end);
    }
    return 0;
}

/* ---- the check ------------------------------------------------------------------ */

int mesh_refs_check(const void *data, size_t len, const char *fmt, glint_err *err)
{
    const char *p = data, *end = p + len, *q;
    char what[48];
    int rc = 0;

    if (!data && len)
        return glint_err_set(err, GLINT_EINVAL, "mesh_refs_check: data is NULL");
    if (!fmt)
        fmt = "";
    snprintf(what, sizeof what, "%.15s data", fmt[0] ? fmt : "mesh");
    if (!len)
        return 0;
    q = len >= 3 && !memcmp(p, "\xef\xbb\xbf", 3) ? p + 3 : p; /* a UTF-8 BOM */
    q = json_ws(q, end);
    if (len >= 20 && !memcmp(p, "glTF", 4))
        rc = scan_glb(data, len, what, err);
    else if (!strcasecmp(fmt, "gltf") || (q < end && *q == '{'))
        rc = scan_json(q, end, what, err);
    if (!rc && (!strcasecmp(fmt, "dae") || find(p, end, "<COLLADA")))
        rc = scan_xml(p, end, what, err);
    if (!rc && !strcasecmp(fmt, "obj"))
        rc = scan_obj(p, end, what, err);
    if (!rc && (!strcasecmp(fmt, "ply") || (len >= 3 && !strncasecmp(p, "ply", 3))))
        rc = scan_ply(p, end, what, err);
    return rc;
}
