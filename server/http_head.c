/* http_head.c: strict request-head reader and the logged form of a target
 * (http_head.h). */
#include "http_head.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define METHOD_MAX 32

static int is_tchar(unsigned char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           (c != '\0' && strchr("!#$%&'*+-.^_`|~", c) != NULL);
}

static int is_digit(unsigned char c)
{
    return c >= '0' && c <= '9';
}

static int refuse(http_head_error *err, int status, const char *slug, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static int refuse(http_head_error *err, int status, const char *slug, const char *fmt, ...)
{
    va_list ap;
    err->status = status;
    err->slug = slug;
    va_start(ap, fmt);
    vsnprintf(err->detail, sizeof err->detail, fmt, ap);
    va_end(ap);
    return HTTP_HEAD_BAD;
}

/* The head is not complete within buf[0..n): more bytes are needed, unless
 * the limit on its size is already reached. */
static int need_more(size_t n, const http_head_limits *lim, http_head_error *err)
{
    if (n >= lim->max_head)
        return refuse(err, 431, "header-too-large",
                      "the request head (request line and header fields) exceeds %zu bytes",
                      lim->max_head);
    return HTTP_HEAD_MORE;
}

/* Case-insensitive comparison of buf[0..n) with the NUL-terminated `s`. */
static int eq_nocase(const char *buf, size_t n, const char *s)
{
    return strlen(s) == n && strncasecmp(buf, s, n) == 0;
}

/* The request line at buf[p..n).  OUT: *line_end (index just past its LF). */
static int parse_request_line(const char *buf, size_t n, size_t p, const http_head_limits *lim,
                              http_head *out, size_t *line_end, http_head_error *err)
{
    size_t i = p, t, v, eol;

    while (i < n && i - p <= METHOD_MAX && is_tchar((unsigned char)buf[i]))
        i++;
    if (i - p > METHOD_MAX)
        return refuse(err, 400, "bad-request-line", "the method is longer than %d bytes",
                      METHOD_MAX);
    if (i == n)
        return need_more(n, lim, err);
    if (buf[i] != ' ' || i == p)
        return refuse(err, 400, "bad-request-line",
                      "the request line does not start with a method token and a space");
    out->method_off = p;
    out->method_len = i - p;

    t = i + 1;
    for (i = t; i < n && buf[i] != ' '; i++) {
        unsigned char c = (unsigned char)buf[i];
        if (c == '\r' || c == '\n')
            return refuse(err, 400, "bad-request-line",
                          "the request line has no HTTP version (HTTP/0.9 is not served)");
        if (c < 0x21 || c > 0x7e)
            return refuse(err, 400, "bad-request-target",
                          "the request target holds a control character or a byte outside "
                          "ASCII (0x%02x at offset %zu); percent-encode it",
                          c, i - t);
        if (i - t >= lim->max_target)
            return refuse(err, 414, "uri-too-long",
                          "the request target is longer than %zu bytes", lim->max_target);
    }
    if (i == n)
        return need_more(n, lim, err);
    if (i == t)
        return refuse(err, 400, "bad-request-line", "the request target is empty");
    out->target_off = t;
    out->target_len = i - t;
    if (!(buf[t] == '/' || (i - t == 1 && buf[t] == '*') ||
          (i - t > 7 && strncasecmp(buf + t, "http://", 7) == 0) ||
          (i - t > 8 && strncasecmp(buf + t, "https://", 8) == 0)))
        return refuse(err, 400, "bad-request-target",
                      "the request target must be a path starting with '/', an absolute URI "
                      "or '*'");
    for (size_t k = t; k + 2 < i; k++)
        if (buf[k] == '%' && buf[k + 1] == '0' && buf[k + 2] == '0')
            return refuse(err, 400, "bad-request-target",
                          "the request target holds %%00 (a NUL byte) at offset %zu", k - t);

    /* "HTTP/d.d" then CRLF or LF; compared as far as the bytes go */
    v = i + 1;
    for (eol = v; eol < n && buf[eol] != '\n'; eol++) {
        static const char pat[] = "HTTP/#.#\r";
        size_t k = eol - v;
        unsigned char c = (unsigned char)buf[eol];
        int ok = k < sizeof pat - 1 &&
                 (pat[k] == '#' ? is_digit(c) : (unsigned char)pat[k] == c);
        if (!ok)
            return refuse(err, 400, "bad-request-line",
                          "the request line must end with \"HTTP/1.1\" or \"HTTP/1.0\"");
    }
    if (eol == n)
        return need_more(n, lim, err);
    if (eol - v != (buf[eol - 1] == '\r' ? 9u : 8u))
        return refuse(err, 400, "bad-request-line",
                      "the request line must end with \"HTTP/1.1\" or \"HTTP/1.0\"");
    if (buf[v + 5] != '1')
        return refuse(err, 505, "http-version-not-supported",
                      "HTTP/%c.%c is not supported: glintd speaks HTTP/1.1 and HTTP/1.0",
                      buf[v + 5], buf[v + 7]);
    out->minor = buf[v + 7] - '0';
    *line_end = eol + 1;
    return HTTP_HEAD_OK;
}

/* Content-Length: 1*DIGIT, saturating at INT64_MAX. */
static int parse_length(const char *v, size_t n, int64_t *out)
{
    int64_t x = 0;
    if (n == 0)
        return -1;
    for (size_t i = 0; i < n; i++) {
        if (!is_digit((unsigned char)v[i]))
            return -1;
        if (x > (INT64_MAX - 9) / 10)
            x = INT64_MAX;
        else
            x = x * 10 + (v[i] - '0');
    }
    *out = x;
    return 0;
}

int http_head_parse(const char *buf, size_t n, const http_head_limits *lim, http_head *out,
                    http_head_error *err)
{
    size_t p = 0, fields = 0;
    int hosts = 0, te = 0, rc;

    memset(out, 0, sizeof *out);
    out->content_length = -1;

    /* empty lines before the request line are skipped (RFC 9112 2.2) */
    while (p < n && (buf[p] == '\r' || buf[p] == '\n')) {
        if (buf[p] == '\r' && p + 1 < n && buf[p + 1] != '\n')
            return refuse(err, 400, "bad-request-line", "a CR not followed by LF");
        if (buf[p] == '\r' && p + 1 == n)
            return need_more(n, lim, err);
        p += buf[p] == '\r' ? 2 : 1;
    }
    if (p >= n)
        return need_more(n, lim, err);
    rc = parse_request_line(buf, n, p, lim, out, &p, err);
    if (rc != HTTP_HEAD_OK)
        return rc;

    for (;;) {
        size_t name, colon, v, ve, eol;

        if (p == n)
            return need_more(n, lim, err);
        if (buf[p] == '\n' || buf[p] == '\r') {
            if (buf[p] == '\r') {
                if (p + 1 == n)
                    return need_more(n, lim, err);
                if (buf[p + 1] != '\n')
                    return refuse(err, 400, "bad-header", "a CR not followed by LF");
                p++;
            }
            out->len = p + 1;
            break;
        }
        if (buf[p] == ' ' || buf[p] == '\t')
            return refuse(err, 400, "bad-header",
                          "a header line starts with whitespace (obsolete line folding is "
                          "not accepted)");
        name = p;
        while (p < n && is_tchar((unsigned char)buf[p]))
            p++;
        if (p == n)
            return need_more(n, lim, err);
        if (buf[p] != ':' || p == name)
            return refuse(err, 400, "bad-header",
                          "header field %zu is not a token followed by ':' (no whitespace "
                          "before the colon)",
                          fields + 1);
        colon = p;
        for (eol = colon + 1; eol < n && buf[eol] != '\n'; eol++) {
            unsigned char c = (unsigned char)buf[eol];
            if (c == '\r' && eol + 1 < n && buf[eol + 1] != '\n')
                return refuse(err, 400, "bad-header", "a CR not followed by LF");
            if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f)
                return refuse(err, 400, "bad-header",
                              "header field %zu holds the control character 0x%02x",
                              fields + 1, c);
        }
        if (eol == n)
            return need_more(n, lim, err);
        if (++fields > lim->max_fields)
            return refuse(err, 431, "header-too-large", "more than %u header fields",
                          lim->max_fields);
        v = colon + 1;
        ve = eol;
        if (ve > v && buf[ve - 1] == '\r')
            ve--;
        while (v < ve && (buf[v] == ' ' || buf[v] == '\t'))
            v++;
        while (ve > v && (buf[ve - 1] == ' ' || buf[ve - 1] == '\t'))
            ve--;

        if (eq_nocase(buf + name, colon - name, "Content-Length")) {
            if (out->content_length >= 0)
                return refuse(err, 400, "bad-content-length",
                              "more than one Content-Length header");
            if (parse_length(buf + v, ve - v, &out->content_length))
                return refuse(err, 400, "bad-content-length",
                              "Content-Length must be a decimal number of bytes");
        } else if (eq_nocase(buf + name, colon - name, "Transfer-Encoding")) {
            te = 1;
        } else if (eq_nocase(buf + name, colon - name, "Host")) {
            hosts++;
        } else if (eq_nocase(buf + name, colon - name, "Expect")) {
            if (eq_nocase(buf + v, ve - v, "100-continue"))
                out->expect_continue = 1;
        }
        p = eol + 1;
    }
    if (out->len > lim->max_head)
        return refuse(err, 431, "header-too-large",
                      "the request head (request line and header fields) exceeds %zu bytes",
                      lim->max_head);
    if (hosts > 1 || (hosts == 0 && out->minor >= 1))
        return refuse(err, 400, "bad-host",
                      "an HTTP/1.1 request needs exactly one Host header (it has %d)", hosts);
    if (te && out->content_length >= 0)
        return refuse(err, 400, "bad-framing",
                      "Content-Length and Transfer-Encoding together: the body's length is "
                      "ambiguous");
    if (te)
        return refuse(err, 411, "length-required",
                      "request bodies must come with a Content-Length (Transfer-Encoding, "
                      "e.g. chunked, is not accepted)");
    /* with or without "Expect: 100-continue": a client that sends its body
     * at once is answered while it sends, not after it (the front lingers) */
    if (out->content_length >= 0 && (uint64_t)out->content_length > lim->max_body)
        return refuse(err, 413, "body-too-large",
                      "Content-Length %lld exceeds the request body limit of %llu bytes "
                      "(max_body, glintd --max-body-mb %llu)",
                      (long long)out->content_length, (unsigned long long)lim->max_body,
                      (unsigned long long)(lim->max_body >> 20));
    return HTTP_HEAD_OK;
}

/* ---- the logged form of a target ----------------------------------------------------------- */

typedef struct log_out {
    char *p;
    size_t used, cap; /* cap excludes the room kept for "..." and the NUL */
    int cut;
} log_out;

static void put(log_out *o, const char *s, size_t n)
{
    if (o->cut)
        return;
    if (o->used + n > o->cap) {
        o->cut = 1;
        return;
    }
    memcpy(o->p + o->used, s, n);
    o->used += n;
}

static int hexval(unsigned char c)
{
    if (c >= '0' && c <= '9')
        return c - '0';
    if (c >= 'a' && c <= 'f')
        return c - 'a' + 10;
    if (c >= 'A' && c <= 'F')
        return c - 'A' + 10;
    return -1;
}

/* Percent-decode s[0..n) into d (plus_space: '+' is a space, as in a query).
 * Returns the decoded length (<= n). */
static size_t decode(const char *s, size_t n, char *d, int plus_space)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] == '%' && i + 2 < n && hexval((unsigned char)s[i + 1]) >= 0 &&
            hexval((unsigned char)s[i + 2]) >= 0) {
            d[k++] = (char)(hexval((unsigned char)s[i + 1]) * 16 +
                            hexval((unsigned char)s[i + 2]));
            i += 2;
        } else if (plus_space && s[i] == '+') {
            d[k++] = ' ';
        } else {
            d[k++] = s[i];
        }
    }
    return k;
}

/* Write decoded bytes d[0..n): hex runs of 32 or more as "{id}", the rest
 * escaped. */
static void put_redacted(log_out *o, const char *d, size_t n)
{
    size_t i = 0;
    while (i < n) {
        size_t j = i;
        while (j < n && hexval((unsigned char)d[j]) >= 0)
            j++;
        if (j - i >= 32) {
            put(o, "{id}", 4);
            i = j;
            continue;
        }
        if (j == i)
            j = i + 1;
        for (; i < j; i++) {
            unsigned char c = (unsigned char)d[i];
            if (c < 0x21 || c > 0x7e || c == '\\') {
                char esc[5];
                snprintf(esc, sizeof esc, "\\x%02x", c);
                put(o, esc, 4);
            } else {
                put(o, (const char *)&d[i], 1);
            }
        }
    }
}

void http_head_log_target(const char *t, size_t n, char *out, size_t cap)
{
    log_out o = {out, 0, cap - 4, 0};
    const char *q = memchr(t, '?', n);
    size_t plen = q ? (size_t)(q - t) : n;
    char *d = malloc(n + 1);

    if (!d) {
        snprintf(out, cap, "-");
        return;
    }
    put_redacted(&o, d, decode(t, plen, d, 0));
    if (q) {
        const char *s = q + 1, *end = t + n;
        put(&o, "?", 1);
        while (s <= end) {
            const char *amp = memchr(s, '&', (size_t)(end - s));
            const char *pe = amp ? amp : end;
            const char *eq = memchr(s, '=', (size_t)(pe - s));
            put_redacted(&o, d, decode(s, (size_t)((eq ? eq : pe) - s), d, 1));
            if (eq)
                put(&o, "=*", 2);
            if (!amp)
                break;
            put(&o, "&", 1);
            s = amp + 1;
        }
    }
    free(d);
    if (o.cut)
        memcpy(out + o.used, "...", 3), o.used += 3;
    out[o.used] = '\0';
}
