/* buf.h: a growable byte buffer (request bodies, event streams, archives,
 * file reads).
 *
 * A zeroed glint_buf is empty and valid.  The data is always followed by a
 * NUL byte once anything was appended, so text can be used as a C string.
 * Growth is geometric.  Appending fails only when memory runs out
 * (GLINT_ENOMEM; the buffer keeps what it held) or when the result would
 * exceed `limit` bytes where a limit is given (GLINT_ERANGE).  Not
 * thread-safe: one owner at a time. */
#ifndef GLINT_BUF_H
#define GLINT_BUF_H

#include <stddef.h>

#include "err.h"

typedef struct glint_buf {
    char *data;   /* malloc'ed; NULL while nothing was appended */
    size_t len;   /* bytes held (the NUL after them not counted) */
    size_t cap;   /* bytes allocated */
} glint_buf;

/* Make room for `extra` more bytes (and the NUL). */
int glint_buf_reserve(glint_buf *b, size_t extra);

int glint_buf_append(glint_buf *b, const void *data, size_t len);

/* Append formatted text. */
int glint_buf_printf(glint_buf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Empty the buffer, keeping its allocation. */
void glint_buf_clear(glint_buf *b);

/* Hand the data over to the caller (free() it; never NULL on success: an
 * empty buffer gives an empty string) and reset the buffer.  OUT: *len
 * (may be NULL).  NULL only when out of memory. */
char *glint_buf_steal(glint_buf *b, size_t *len);

/* Release the data.  Accepts NULL. */
void glint_buf_free(glint_buf *b);

#endif
