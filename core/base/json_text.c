/* json_text.c: json_dumps's layout with the reals in their shortest form
 * (json_text.h). */
#include "json_text.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "buf.h"

typedef struct jbuf {
    glint_buf out;
    int indent, fail;
} jbuf;

static void put(jbuf *b, const char *s, size_t n)
{
    if (!b->fail && glint_buf_append(&b->out, s, n))
        b->fail = 1;
}

/* jansson's dump_indent: a newline and depth x indent spaces, or nothing
 * in compact text */
static void newline(jbuf *b, int depth)
{
    static const char spaces[] = "                                                                ";
    const size_t width = sizeof spaces - 1; /* 64 */
    size_t n;
    if (!b->indent)
        return;
    put(b, "\n", 1);
    for (n = (size_t)depth * (size_t)b->indent; n > 0;) {
        size_t k = n < width ? n : width;
        put(b, spaces, k);
        n -= k;
    }
}

/* jansson's dump_string without flags: ", \, the control characters
 * escaped, the rest (UTF-8, validated by jansson) as it is */
static void put_string(jbuf *b, const char *s, size_t n)
{
    size_t run = 0;
    put(b, "\"", 1);
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        char esc[8];
        const char *e = NULL;
        if (c >= 0x20 && c != '"' && c != '\\')
            continue;
        switch (c) {
        case '"': e = "\\\""; break;
        case '\\': e = "\\\\"; break;
        case '\b': e = "\\b"; break;
        case '\f': e = "\\f"; break;
        case '\n': e = "\\n"; break;
        case '\r': e = "\\r"; break;
        case '\t': e = "\\t"; break;
        default:
            snprintf(esc, sizeof esc, "\\u%04X", c);
            e = esc;
        }
        put(b, s + run, i - run);
        put(b, e, strlen(e));
        run = i + 1;
    }
    put(b, s + run, n - run);
    put(b, "\"", 1);
}

static void dump(jbuf *b, const json_t *j, int depth)
{
    char num[48];
    int n;

    if (b->fail)
        return;
    if (depth > JSON_TEXT_MAX_DEPTH) {
        b->fail = 1;
        return;
    }
    switch (json_typeof(j)) {
    case JSON_OBJECT: {
        const char *key;
        json_t *v;
        size_t i = 0, klen, count = json_object_size(j);
        if (!count) {
            put(b, "{}", 2);
            return;
        }
        put(b, "{", 1);
        newline(b, depth + 1);
        json_object_keylen_foreach((json_t *)j, key, klen, v) {
            put_string(b, key, klen); /* a key may hold a NUL (json_object_setn) */
            put(b, b->indent ? ": " : ":", b->indent ? 2 : 1);
            dump(b, v, depth + 1);
            if (++i < count) {
                put(b, ",", 1);
                newline(b, depth + 1);
            } else {
                newline(b, depth);
            }
        }
        put(b, "}", 1);
        return;
    }
    case JSON_ARRAY: {
        size_t count = json_array_size(j);
        if (!count) {
            put(b, "[]", 2);
            return;
        }
        put(b, "[", 1);
        newline(b, depth + 1);
        for (size_t i = 0; i < count; i++) {
            dump(b, json_array_get(j, i), depth + 1);
            if (i + 1 < count) {
                put(b, ",", 1);
                newline(b, depth + 1);
            } else {
                newline(b, depth);
            }
        }
        put(b, "]", 1);
        return;
    }
    case JSON_STRING:
        put_string(b, json_string_value(j), json_string_length(j));
        return;
    case JSON_INTEGER:
        n = snprintf(num, sizeof num, "%" JSON_INTEGER_FORMAT, json_integer_value(j));
        put(b, num, (size_t)n);
        return;
    case JSON_REAL:
        n = glint_dtoa_shortest(json_real_value(j), num, (int)sizeof num);
        if (n < 0) { /* jansson holds no inf or NaN */
            b->fail = 1;
            return;
        }
        put(b, num, (size_t)n);
        return;
    case JSON_TRUE:
        put(b, "true", 4);
        return;
    case JSON_FALSE:
        put(b, "false", 5);
        return;
    case JSON_NULL:
        put(b, "null", 4);
        return;
    }
    b->fail = 1;
}

char *json_text(const json_t *j, int indent)
{
    jbuf b = {{NULL, 0, 0}, indent, 0};
    char *text;
    if (!j || indent < 0 || indent > 31)
        return NULL;
    dump(&b, j, 0);
    if (b.fail) {
        glint_buf_free(&b.out);
        return NULL;
    }
    text = glint_buf_steal(&b.out, NULL);
    glint_buf_free(&b.out);
    return text;
}
