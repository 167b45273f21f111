/* http.h: glintd's HTTP layer on libmicrohttpd: a connection front with
 * per-client limits and deadlines, request bodies with a size limit and a
 * minimum rate, a routing table with path parameters, response helpers
 * (JSON, RFC 9457 problem+json, bytes, files, server-sent events), one log
 * line per request, and request metrics.
 *
 * Connections.  glintd owns the listening socket: its connection front
 * (http_front.h) accepts every connection and keeps it, without a thread,
 * until the request head has arrived in full (within header_timeout_s),
 * reads that head strictly (http_head.h), answers anything wrong itself
 * with problem+json (400, 408, 411, 413, 414, 431, 505) and hands the
 * rest to libmicrohttpd (MHD_USE_NO_LISTEN_SOCKET + MHD_add_connection,
 * thread per connection, poll() so that descriptors above FD_SETSIZE
 * work), at most max_connections at once and max_connections_per_ip per
 * client (429 / 503 beyond), plus health_reserve connections for
 * "GET /healthz" and "GET /api/v1/healthz" only.  Idle and slow clients
 * thus wait in the front's epoll set and cannot take libmicrohttpd's
 * threads.  Not covered by the front: a kept-alive connection's later
 * requests go to libmicrohttpd directly.  This layer refuses %00 in their
 * target and Transfer-Encoding in them as the front does, but their heads
 * have only libmicrohttpd's idle timeout (timeout_s) and its own limits and
 * HTML error pages; to keep such connections few, answers carry
 * "Connection: close" once three quarters of a limit is in use, and always
 * on a health-reserve connection.  A request body must keep up an average
 * of min_body_rate bytes/s after a grace of header_timeout_s, or the
 * connection is closed (logged as 408).  The process's open-files limit is
 * raised to its hard limit at start.
 *
 * The request log (stderr, one line per request, "METHOD TARGET STATUS
 * TIMEms") writes the target as http_head_log_target() does: control
 * characters escaped, ids and tokens (32 hex digits) and every query value
 * redacted.
 *
 * A handler receives an http_req and returns an http_resp made by one of
 * the http_* constructors below; the layer queues it, logs it and destroys
 * it.  Handlers run on the connection's own thread (thread per connection),
 * so they may block; long work belongs in a job (jobs.h).  Ownership:
 * constructors take ownership of what they are given where the comment says
 * "steals". */
#ifndef GLINTD_HTTP_H
#define GLINTD_HTTP_H

#include <jansson.h>
#include <microhttpd.h>
#include <stddef.h>
#include <stdint.h>

#include "timing.h"

#define HTTP_MAX_PARAMS 4

typedef struct http_req {
    const char *method;     /* "GET", "POST", ... */
    const char *path;       /* URL path without the query */
    struct MHD_Connection *conn;
    const char *param[HTTP_MAX_PARAMS]; /* {placeholders} of the route, in order */
    int nparam;
    const char *body;       /* request body (NUL-terminated), or "" */
    size_t body_len;
    int body_too_large;     /* the body exceeded the limit (handler answers 413) */
    void *app;              /* the application (http_server_start's `app`) */
    srv_timing timing;      /* steps the handler timed: sent as Server-Timing (timing.h) */
    int gone;               /* http_req_gone said so (read and set atomically) */
    /* What the handler holds until it returns (e.g. of a work budget), and
     * how to give it back: the layer calls release(req), when set, right
     * after the handler, whatever it answered. */
    size_t held;
    void (*release)(struct http_req *req);
} http_req;

typedef struct http_resp {
    int status;
    struct MHD_Response *r; /* owned until queued */
} http_resp;

typedef http_resp (*http_handler)(http_req *req);

typedef struct http_route {
    const char *method;     /* "GET", "POST", "PUT", "DELETE" */
    const char *pattern;    /* "/api/v1/scenes/{id}/views/{k}/base.png" */
    http_handler fn;
} http_route;

typedef struct http_server http_server;

typedef struct http_config {
    const char *address;    /* "127.0.0.1" (default), "0.0.0.0", "::1" */
    int port;               /* 0 = ephemeral */
    size_t max_body;        /* request body limit in bytes */
    unsigned timeout_s;     /* idle timeout of a connection libmicrohttpd serves */
    unsigned max_connections;        /* served at once, health reserve aside (0: 256) */
    unsigned max_connections_per_ip; /* ... per client, IPv4 address or IPv6 /64 (0: all) */
    unsigned max_waiting_per_ip;     /* of one client waiting for their head (0: 256) */
    unsigned health_reserve;         /* extra connections for health checks */
    unsigned header_timeout_s;       /* the request head must arrive within this (0: 10 s) */
    unsigned min_body_rate;          /* bytes/s a request body keeps up (0: no minimum) */
    size_t max_head;        /* request line + header fields, bytes (0: 16 KiB) */
    size_t max_target;      /* request target, bytes (0: 8 KiB) */
    const char *static_dir; /* served at "/" (NULL: none) */
    /* Web origins besides the daemon's own (comma-separated, "scheme://host
     * [:port]"; NULL: none).  A request whose Origin header names another
     * origin (a page elsewhere calling the API) is refused (403,
     * "cross-origin") unless it is a GET or HEAD, which is answered without
     * CORS headers, so the browser keeps the answer from that page; an
     * admitted origin gets Access-Control-Allow-Origin and its preflights
     * (OPTIONS) are answered.  The daemon's own origin is the request's
     * Host under http or https. */
    const char *allow_origin;
    /* Host names served besides IP address literals and "localhost"
     * (comma-separated, a name or name:port; "*": any; NULL: none), and
     * whether to check (check_host 1).  A request whose Host names
     * anything else is refused, whatever its method (421,
     * "host-not-served"), except GET and HEAD of the health checks: a page
     * on some name that its DNS points at this machine (DNS rebinding) is
     * then the browser's own origin for that name, and its Origin the
     * same, so the Origin rule above cannot tell it from the studio; the
     * Host can.  An address literal is always served: no name was
     * resolved to reach it, so no page elsewhere can send it. */
    const char *allow_host;
    int check_host;
    int quiet;              /* no request log lines */
    /* This process's name among replicas behind one proxy, sent on every
     * response as X-Glint-Replica (NULL: no header). */
    const char *replica;
} http_config;

/* Start serving `routes` (n entries, matched in order).  OUT: *out, and the
 * bound port in *port_out. */
int http_server_start(const http_config *cfg, const http_route *routes, int n, void *app,
                      http_server **out, int *port_out, char *err, size_t errlen);

/* Stop accepting, let in-flight requests finish, stop. */
void http_server_stop(http_server *s);

/* ---- responses ---------------------------------------------------------------- */

/* JSON body (steals a reference to j). */
http_resp http_json(int status, json_t *j);

/* RFC 9457 problem: {"type", "title", "status", "detail"} as
 * application/problem+json; `type` is a short slug ("invalid-json"), made
 * into "https://glint.invalid/problems/<slug>" is NOT done: type is
 * "about:blank" unless slug given, then "/problems/<slug>". */
http_resp http_problem(int status, const char *slug, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* The title of a status ("Not Found"), "Error" for one without. */
const char *http_status_title(int status);

/* The problem+json text of http_problem(), NUL-terminated, to free() (NULL
 * when out of memory). */
char *http_problem_json(int status, const char *slug, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* The length of the valid UTF-8 sequence at s[0..n) (RFC 3629: no
 * overlong forms, no surrogates, nothing above U+10FFFF), 0 if none is.
 * http_utf8_valid: whether all of s is valid UTF-8.  What a request sends
 * (a query value, a path) is bytes: check it before it goes into JSON,
 * which only holds UTF-8 (jansson refuses the rest). */
size_t http_utf8_seq(const unsigned char *s, size_t n);
int http_utf8_valid(const char *s);

/* Bytes copied into the response. */
http_resp http_bytes(int status, const char *content_type, const void *data, size_t len);

/* Bytes handed over (steals `data`, freed with free()). */
http_resp http_bytes_owned(int status, const char *content_type, void *data, size_t len);

/* A plain-text body. */
http_resp http_text(int status, const char *content_type, const char *text);

/* A streamed response (server-sent events): `cb` is MHD's content reader
 * callback, `cls` its closure freed with `free_cls`. */
http_resp http_stream(int status, const char *content_type, MHD_ContentReaderCallback cb,
                      void *cls, MHD_ContentReaderFreeCallback free_cls);

/* Add a header to a response before it is returned. */
void http_header(http_resp *r, const char *name, const char *value);

/* A file of the static directory `dir` (NULL: none) for GET `path`
 * ("/" is /index.html), revalidated on every load (Cache-Control:
 * no-cache, Last-Modified / If-Modified-Since `ims`).  Only regular files
 * reached from `dir` without a symbolic link, "." or ".." on the way are
 * served (404 otherwise), so a link in the tree leads nowhere outside it. */
http_resp http_static_serve(const char *dir, const char *path, const char *ims);

/* ---- request helpers ------------------------------------------------------------ */

/* Query argument or NULL. */
const char *http_query(const http_req *req, const char *name);

/* Request header or NULL. */
const char *http_header_in(const http_req *req, const char *name);

/* The client a request came from, as the connection front counts them:
 * its IPv4 address, or its IPv6 address's /64 ("2001:db8:1:2::/64"),
 * into out[0..len) (at least HTTP_CLIENT_KEY_MAX bytes); "" when unknown.
 * Behind a proxy this is the proxy. */
#define HTTP_CLIENT_KEY_MAX 64
void http_client_key(const http_req *req, char *out, size_t len);
/* 1 once the request's client has gone: it closed or reset its connection
 * (or shut down its sending side, which an HTTP/1.1 client waiting for an
 * answer does not do).  With a thread per connection, libmicrohttpd learns
 * of a close only after the handler returns, so a long handler (a render)
 * asks this between pieces of its work and gives up.  A non-blocking peek
 * at the socket (a few microseconds); safe from any thread while the
 * handler runs; once 1, always 1. */
int http_req_gone(http_req *req);

/* Request counters for /metrics (api_core.c). */
typedef struct http_stats {
    uint64_t requests;
    uint64_t by_class[6];   /* 1xx..5xx by status / 100 */
    uint64_t latency_bucket[12];
    double latency_sum;
} http_stats;

void http_stats_get(http_server *s, http_stats *out);
extern const double http_latency_bounds[12];

#endif
