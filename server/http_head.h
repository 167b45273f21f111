/* http_head.h: a strict reader of an HTTP/1.x request head (request line and
 * header fields, up to the blank line), and the form a request target takes
 * in the request log.
 *
 * http_head_parse() is given the bytes received so far and says whether they
 * are a complete, acceptable head, the beginning of one (more bytes needed),
 * or already wrong (and with which status the connection is to be answered).
 * It reads, it never consumes: the connection front (http_front.h) peeks at
 * a socket with it and hands the untouched bytes to libmicrohttpd, which then
 * parses the same head again.  What it accepts is therefore a subset of what
 * libmicrohttpd 0.9.75 reads the same way:
 *
 *   request line   method SP request-target SP HTTP-version, ended by CRLF
 *                  or a bare LF (RFC 9112 2.2); empty lines before it are
 *                  skipped.  method: 1..32 token characters.  target: origin
 *                  form ("/..."), absolute form ("http://...") or "*", only
 *                  visible ASCII (0x21..0x7e), at most max_target bytes
 *                  (414 beyond, answered as soon as the limit is passed), no
 *                  "%00" anywhere (400: a decoded NUL would cut the path or a
 *                  query value short).  version: "HTTP/1.x" (x a digit; 1.2
 *                  and later are read as 1.1, RFC 9110 2.5); another well
 *                  formed "HTTP/d.d" is 505, anything else 400.
 *   header fields  token ":" OWS value OWS; no whitespace before the colon,
 *                  no obsolete line folding, no control character but HTAB
 *                  in a value, no bare CR anywhere (libmicrohttpd and other
 *                  parsers disagree on it): 400.  At most max_fields fields
 *                  and max_head bytes for the whole head: 431.
 *   framing        exactly one Host in HTTP/1.1; at most one Content-Length,
 *                  digits only; Transfer-Encoding together with
 *                  Content-Length is 400 (RFC 9112 6.3: the classic request
 *                  smuggling ambiguity); Transfer-Encoding alone is 411
 *                  (glintd takes request bodies with a Content-Length only);
 *                  a Content-Length over max_body is 413 as soon as the head
 *                  is read, whether the client waits for 100 Continue or
 *                  sends its body at once.
 *
 * Errors are found as early as the bytes allow: a request line that does not
 * begin with a method token is refused at its first wrong byte. */
#ifndef GLINTD_HTTP_HEAD_H
#define GLINTD_HTTP_HEAD_H

#include <stddef.h>
#include <stdint.h>

typedef struct http_head_limits {
    size_t max_head;      /* bytes of the head, leading empty lines and the blank line included */
    size_t max_target;    /* bytes of the request target */
    unsigned max_fields;  /* header fields */
    uint64_t max_body;    /* a larger Content-Length is refused with the head */
} http_head_limits;

typedef struct http_head {
    size_t len;              /* bytes of the head, blank line included */
    size_t method_off, method_len; /* the method in the buffer (len 0: not read yet) */
    size_t target_off, target_len; /* the request target, as sent (len 0: not read yet) */
    int minor;               /* HTTP/1.<minor> */
    int64_t content_length;  /* -1: no Content-Length (INT64_MAX when it does not fit) */
    int expect_continue;     /* "Expect: 100-continue" */
} http_head;

typedef struct http_head_error {
    int status;              /* 400, 411, 413, 414, 431 or 505 */
    const char *slug;        /* problem type slug, e.g. "bad-request-line" */
    char detail[192];        /* for the problem's detail; never quotes the client's bytes */
} http_head_error;

enum {
    HTTP_HEAD_OK = 0,        /* a complete, acceptable head: *out is filled */
    HTTP_HEAD_MORE = 1,      /* acceptable so far, more bytes needed */
    HTTP_HEAD_BAD = -1,      /* refused: *err says how to answer; the method and target
                                fields of *out are set when they were read */
};

/* Read the head at the start of buf[0..n).  OUT: *out (see the return
 * codes), *err on HTTP_HEAD_BAD.  n may go past the head (a body or a
 * pipelined request follows it); nothing after out->len is looked at. */
int http_head_parse(const char *buf, size_t n, const http_head_limits *lim, http_head *out,
                    http_head_error *err);

/* The request target `t` (n bytes, as sent) as the request log writes it:
 * the path percent-decoded; every run of 32 or more hex digits (ids and
 * tokens) written "{id}"; query values written "*" (their names kept, decoded
 * and redacted like the path; the query is never logged verbatim); then every
 * byte outside 0x21..0x7e, and the backslash, written \xHH, so that a log
 * line is one request whatever the target holds.  Cut to cap - 1 bytes
 * (ending in "...") when longer.  OUT: out, NUL-terminated (cap >= 8). */
void http_head_log_target(const char *t, size_t n, char *out, size_t cap);

#endif
