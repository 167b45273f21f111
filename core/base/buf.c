/* buf.c: growable byte buffer (buf.h). */
#include "buf.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int glint_buf_reserve(glint_buf *b, size_t extra)
{
    size_t need, cap;
    char *p;

    if (extra > SIZE_MAX - 1 - b->len)
        return GLINT_ENOMEM;
    need = b->len + extra + 1;
    if (need <= b->cap)
        return 0;
    cap = b->cap ? b->cap : 256;
    while (cap < need)
        cap = cap > SIZE_MAX / 2 ? need : cap * 2;
    p = realloc(b->data, cap);
    if (!p)
        return GLINT_ENOMEM;
    b->data = p;
    b->cap = cap;
    return 0;
}

int glint_buf_append(glint_buf *b, const void *data, size_t len)
{
    int rc = glint_buf_reserve(b, len);
    if (rc)
        return rc;
    if (len)
        memcpy(b->data + b->len, data, len);
    b->len += len;
    b->data[b->len] = '\0';
    return 0;
}

int glint_buf_printf(glint_buf *b, const char *fmt, ...)
{
    va_list ap;
    int n, rc;

    va_start(ap, fmt);
    n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0)
        return GLINT_EINVAL;
    if ((rc = glint_buf_reserve(b, (size_t)n)))
        return rc;
    va_start(ap, fmt);
    vsnprintf(b->data + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
    return 0;
}

void glint_buf_clear(glint_buf *b)
{
    b->len = 0;
    if (b->data)
        b->data[0] = '\0';
}

char *glint_buf_steal(glint_buf *b, size_t *len)
{
    char *d;
    if (!b->data && glint_buf_reserve(b, 0))
        return NULL;
    if (!b->data)
        return NULL;
    b->data[b->len] = '\0';
    d = b->data;
    if (len)
        *len = b->len;
    memset(b, 0, sizeof *b);
    return d;
}

void glint_buf_free(glint_buf *b)
{
    if (!b)
        return;
    free(b->data);
    memset(b, 0, sizeof *b);
}
