/* http_front.h: glintd's connection front, between the listening socket and
 * libmicrohttpd (used by http.c only).
 *
 * One thread owns the listening socket and an epoll set.  It accepts every
 * connection and keeps it, at the cost of a descriptor and a small record and
 * no thread, until its request head has arrived: it peeks (recv MSG_PEEK) at
 * the bytes, never consuming them, and reads them with http_head_parse()
 * (http_head.h).  Then either
 *   - the head is refused (400, 411, 413, 414, 431, 505), or it did not
 *     arrive within the header deadline (408), or the client's limit or the
 *     global one is reached (429, 503): the front answers with an RFC 9457
 *     application/problem+json body and "Connection: close", shuts its side
 *     down and reads and discards what the client still sends for up to
 *     2 s and 1 MiB (after a 413 for a Content-Length over max_body, 1 MiB
 *     more than the body it declared, up to max_body: so the client's stack
 *     does not reset the connection before the answer is read), then
 *     closes;
 *   - or it is admitted: the untouched socket and a lease are handed on
 *     (cfg.deliver, i.e. MHD_add_connection) and libmicrohttpd reads the
 *     same head again.
 *
 * Why a front, measured on libmicrohttpd 0.9.75: its connection limit and
 * per-IP limit count idle and half-sent connections (260 connections
 * dripping a header line every 10 s, or 1000 idle ones, starve everyone),
 * its only deadline is an idle timeout, and it writes HTML for 400, 414,
 * 431 and 505.  Handing accepted sockets to a daemon started with
 * MHD_USE_NO_LISTEN_SOCKET (which implies MHD_USE_ITC: added connections
 * are picked up at once) works with thread per connection; MHD_USE_POLL is
 * needed too, as with select() libmicrohttpd closes, unanswered, any
 * connection whose descriptor is FD_SETSIZE (1024) or more, which a front
 * holding 1000 waiting sockets reaches at once.
 *
 * Admission.  A connection handed on holds a lease until libmicrohttpd
 * closes it (http_front_release).  Ordinary leases: at most max_connections
 * in all and max_per_ip per client (an IPv4 address, an IPv6 /64; beyond
 * the client's limit 429, beyond the global one 503, both with Retry-After).
 * "GET" or "HEAD" of /healthz or /api/v1/healthz takes an ordinary lease
 * when one is free, else one of health_reserve reserve leases, whatever the
 * client holds: health checks answer through any flood.  Waiting
 * connections are capped per client (max_waiting_per_ip) and in all
 * (max_waiting, and whenever accept() runs out of descriptors): the oldest
 * waiting connection of that client, or of all, is dropped to make room,
 * with a 503 when it had begun its request.  A connection that sent nothing
 * is closed silently at the header deadline; a partial head gets 408.
 *
 * What the front does not cover: later requests on a kept-alive connection
 * go to libmicrohttpd directly.  http.c applies the target and framing
 * checks to those too (400 for %00 and for Content-Length with
 * Transfer-Encoding, 411 for Transfer-Encoding, 413 for a Content-Length
 * over max_body, before the body is read), but their heads have only
 * libmicrohttpd's idle timeout (--timeout) and its own limits and HTML
 * error pages (431, 414, 400, 505).  http.c closes kept-alive connections
 * after each answer when http_front_busy() says the limits are nearly
 * reached, and after every answer on a reserve lease.  Request bodies are
 * read by libmicrohttpd; http.c enforces their minimum rate. */
#ifndef GLINTD_HTTP_FRONT_H
#define GLINTD_HTTP_FRONT_H

#include <stddef.h>
#include <sys/socket.h>

#include "http_head.h"

typedef struct http_front http_front;
typedef struct http_front_lease http_front_lease;

typedef struct http_front_config {
    int listen_fd;               /* bound, listening; the front makes it non-blocking, closes it */
    http_head_limits head;       /* what a request head may be */
    unsigned header_timeout_s;   /* the whole head must arrive within this */
    unsigned max_connections;    /* ordinary leases in all */
    unsigned max_per_ip;         /* leases one client holds (reserve leases included) */
    unsigned health_reserve;     /* reserve leases, for health checks only */
    unsigned max_waiting_per_ip; /* connections of one client waiting for their head */
    unsigned max_waiting;        /* connections waiting in all */
    /* Hand an admitted connection on.  Called on the front's thread; `fd`
     * (non-blocking, its head unread) and `lease` belong to the callee from
     * then on, which passes the lease to http_front_release() once the
     * connection is closed (at once if it cannot take the connection). */
    void (*deliver)(void *cls, int fd, const struct sockaddr *addr, socklen_t addrlen,
                    http_front_lease *lease);
    /* The front answered a request itself (for the request log and the
     * counters).  method/target: as sent, NULL when not read. */
    void (*answered)(void *cls, const char *method, size_t method_len, const char *target,
                     size_t target_len, int status, double seconds);
    void *cls;
} http_front_config;

/* Start the front's thread.  On failure the listening socket is closed and
 * err says why.  OUT: *out. */
int http_front_start(const http_front_config *cfg, http_front **out, char *err, size_t errlen);

/* Stop accepting: join the thread, close the listening socket and every
 * waiting connection.  Leases handed out stay valid.  Accepts NULL. */
void http_front_stop(http_front *f);

/* Give a lease back (any thread).  The lease is freed. */
void http_front_release(http_front *f, http_front_lease *lease);

/* 1 when the lease is a health-check reserve lease. */
int http_front_lease_is_reserve(const http_front_lease *lease);

/* 1 when three quarters of the global limit, or of the lease's client's
 * limit, are in use: kept-alive connections should then be closed after
 * their answer. */
int http_front_busy(http_front *f, const http_front_lease *lease);

/* Free the front, after http_front_stop and once every lease was released.
 * Accepts NULL. */
void http_front_free(http_front *f);

#endif
