/* http.c: libmicrohttpd glue behind the connection front, routing,
 * responses, request log, stats. */
#include "http.h"

#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "http_front.h"
#include "http_head.h"
#include "http_origin.h"
#include "json_text.h"

#define HTTP_MAX_HEAD_DEFAULT (16u << 10)  /* libmicrohttpd's 32 KiB pool holds it with room */
#define HTTP_MAX_TARGET_DEFAULT (8u << 10)
#define HTTP_MAX_FIELDS 100
#define HTTP_FD_HEADROOM 256               /* descriptors kept for files, SQLite, pipes */
#define HTTP_LOG_TARGET 1024               /* bytes of a target in the request log */

const double http_latency_bounds[12] = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025,
                                        0.05,   0.1,   0.25,   0.5,   1.0,  2.5};

struct http_server {
    struct MHD_Daemon *d;
    http_front *front;
    http_config cfg;
    const http_route *routes;
    int nroutes;
    void *app;
    pthread_mutex_t lock;
    http_stats stats;
    /* Leases of connections handed to MHD_add_connection and not yet
     * started (MHD_CONNECTION_NOTIFY_STARTED), by descriptor: the
     * notification takes them from here into the connection's socket
     * context. */
    http_front_lease **parked;
    size_t nparked;
};

/* Per-request state kept between MHD's calls, made by the URI log callback
 * (uri_seen) for every request and freed by on_completed. */
typedef struct req_ctx {
    char *target;       /* the request target as sent (percent-encoded, query included) */
    char method[16];    /* for a line logged after on_request (cut short) */
    char *body;
    size_t len, cap;
    int too_large;
    int started;        /* on_request saw the headers */
    int answered;       /* a response was queued (and logged) */
    int body_paced;     /* the minimum body rate is being enforced */
    double t0;          /* the request line was read */
    double body_t0;     /* the headers were read */
    size_t received;    /* body bytes so far */
} req_ctx;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- responses ------------------------------------------------------------------ */

static http_resp make(int status, struct MHD_Response *r, const char *ctype)
{
    http_resp out = {status, r};
    if (r && ctype)
        MHD_add_response_header(r, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    return out;
}

http_resp http_bytes(int status, const char *content_type, const void *data, size_t len)
{
    return make(status,
                MHD_create_response_from_buffer(len, (void *)data, MHD_RESPMEM_MUST_COPY),
                content_type);
}

http_resp http_bytes_owned(int status, const char *content_type, void *data, size_t len)
{
    struct MHD_Response *r =
        MHD_create_response_from_buffer_with_free_callback(len, data, free);
    if (!r)
        free(data);
    return make(status, r, content_type);
}

http_resp http_text(int status, const char *content_type, const char *text)
{
    return http_bytes(status, content_type, text, strlen(text));
}

http_resp http_json(int status, json_t *j)
{
    char *text = j ? json_text(j, 0) : NULL;
    json_decref(j);
    if (!text)
        return http_text(500, "application/problem+json",
                         "{\"type\":\"about:blank\",\"title\":\"Internal Server Error\","
                         "\"status\":500,\"detail\":\"cannot serialize the response\"}");
    return http_bytes_owned(status, "application/json", text, strlen(text));
}

const char *http_status_title(int status)
{
    switch (status) {
    case 400: return "Bad Request";
    case 401: return "Unauthorized";
    case 403: return "Forbidden";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 408: return "Request Timeout";
    case 409: return "Conflict";
    case 411: return "Length Required";
    case 412: return "Precondition Failed";
    case 413: return "Content Too Large";
    case 414: return "URI Too Long";
    case 415: return "Unsupported Media Type";
    case 421: return "Misdirected Request";
    case 422: return "Unprocessable Content";
    case 429: return "Too Many Requests";
    case 431: return "Request Header Fields Too Large";
    case 500: return "Internal Server Error";
    case 503: return "Service Unavailable";
    case 505: return "HTTP Version Not Supported";
    default: return "Error";
    }
}

size_t http_utf8_seq(const unsigned char *s, size_t n)
{
    size_t len;
    unsigned lo = 0x80, hi = 0xbf;
    if (n == 0)
        return 0;
    if (s[0] < 0x80)
        return 1;
    if (s[0] >= 0xc2 && s[0] <= 0xdf)
        len = 2;
    else if (s[0] >= 0xe0 && s[0] <= 0xef)
        len = 3;
    else if (s[0] >= 0xf0 && s[0] <= 0xf4)
        len = 4;
    else
        return 0;
    if (s[0] == 0xe0)
        lo = 0xa0; /* overlong */
    else if (s[0] == 0xed)
        hi = 0x9f; /* surrogates */
    else if (s[0] == 0xf0)
        lo = 0x90; /* overlong */
    else if (s[0] == 0xf4)
        hi = 0x8f; /* above U+10FFFF */
    if (n < len || s[1] < lo || s[1] > hi)
        return 0;
    for (size_t i = 2; i < len; i++)
        if (s[i] < 0x80 || s[i] > 0xbf)
            return 0;
    return len;
}

int http_utf8_valid(const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    size_t n = strlen(s), k;
    for (size_t i = 0; i < n; i += k)
        if (!(k = http_utf8_seq(p + i, n - i)))
            return 0;
    return 1;
}

/* Bytes of s that are not valid UTF-8 become '?' (a message may quote what
 * a request sent, or be cut inside a character). */
static void utf8_scrub(char *s)
{
    unsigned char *p = (unsigned char *)s;
    size_t n = strlen(s), k;
    for (size_t i = 0; i < n; i += k)
        if (!(k = http_utf8_seq(p + i, n - i))) {
            p[i] = '?';
            k = 1;
        }
}

static char *problem_vjson(int status, const char *slug, const char *fmt, va_list ap)
{
    char detail[1024], type[128];
    json_t *j;
    char *text;

    vsnprintf(detail, sizeof detail, fmt, ap);
    utf8_scrub(detail);
    if (slug)
        snprintf(type, sizeof type, "/problems/%s", slug);
    else
        snprintf(type, sizeof type, "about:blank");
    j = json_pack("{s:s, s:s, s:i, s:s}", "type", type, "title", http_status_title(status),
                  "status", status, "detail", detail);
    text = j ? json_dumps(j, JSON_COMPACT) : NULL;
    json_decref(j);
    return text;
}

char *http_problem_json(int status, const char *slug, const char *fmt, ...)
{
    va_list ap;
    char *text;
    va_start(ap, fmt);
    text = problem_vjson(status, slug, fmt, ap);
    va_end(ap);
    return text;
}

http_resp http_problem(int status, const char *slug, const char *fmt, ...)
{
    va_list ap;
    char *text;

    va_start(ap, fmt);
    text = problem_vjson(status, slug, fmt, ap);
    va_end(ap);
    if (!text)
        return http_text(status, "application/problem+json", "{\"type\":\"about:blank\"}");
    return http_bytes_owned(status, "application/problem+json", text, strlen(text));
}

http_resp http_stream(int status, const char *content_type, MHD_ContentReaderCallback cb,
                      void *cls, MHD_ContentReaderFreeCallback free_cls)
{
    struct MHD_Response *r =
        MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 4096, cb, cls, free_cls);
    http_resp out = make(status, r, content_type);
    if (r)
        MHD_add_response_header(r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    return out;
}

void http_header(http_resp *r, const char *name, const char *value)
{
    if (r->r)
        MHD_add_response_header(r->r, name, value);
}

/* ---- request helpers --------------------------------------------------------------- */

int http_req_gone(http_req *req)
{
    const union MHD_ConnectionInfo *ci;
    char c;
    ssize_t n;
    if (__atomic_load_n(&req->gone, __ATOMIC_RELAXED))
        return 1;
    ci = req->conn ? MHD_get_connection_info(req->conn, MHD_CONNECTION_INFO_CONNECTION_FD) : NULL;
    if (!ci || ci->connect_fd < 0)
        return 0;
    /* the body has been read: what is left is the next pipelined request,
     * the end of the stream (0) or an error (a reset) */
    n = recv(ci->connect_fd, &c, 1, MSG_PEEK | MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
        __atomic_store_n(&req->gone, 1, __ATOMIC_RELAXED);
        return 1;
    }
    return 0;
}

const char *http_query(const http_req *req, const char *name)
{
    return MHD_lookup_connection_value(req->conn, MHD_GET_ARGUMENT_KIND, name);
}

const char *http_header_in(const http_req *req, const char *name)
{
    return MHD_lookup_connection_value(req->conn, MHD_HEADER_KIND, name);
}

void http_client_key(const http_req *req, char *out, size_t len)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(req->conn, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
    const struct sockaddr *sa = ci ? ci->client_addr : NULL;

    out[0] = '\0';
    if (sa && sa->sa_family == AF_INET) {
        inet_ntop(AF_INET, &((const struct sockaddr_in *)sa)->sin_addr, out, (socklen_t)len);
    } else if (sa && sa->sa_family == AF_INET6) {
        struct in6_addr a = ((const struct sockaddr_in6 *)sa)->sin6_addr;
        size_t n;
        if (IN6_IS_ADDR_V4MAPPED(&a)) {
            inet_ntop(AF_INET, a.s6_addr + 12, out, (socklen_t)len);
            return;
        }
        memset(a.s6_addr + 8, 0, 8); /* the /64, as the front counts */
        if (inet_ntop(AF_INET6, &a, out, (socklen_t)len) && (n = strlen(out)) + 4 < len)
            memcpy(out + n, "/64", 4);
    }
}

/* ---- routing ------------------------------------------------------------------------ */

/* Match `path` against `pattern`; placeholders capture one segment each into
 * the request (copied into `buf`). */
static int match(const char *pattern, const char *path, http_req *req, char *buf, size_t buflen)
{
    const char *p = pattern, *u = path;
    size_t used = 0;

    req->nparam = 0;
    while (*p && *u) {
        if (*p == '{') {
            const char *pe = strchr(p, '}');
            size_t n = strcspn(u, "/");
            if (!pe || n == 0 || req->nparam >= HTTP_MAX_PARAMS || used + n + 1 > buflen)
                return 0;
            memcpy(buf + used, u, n);
            buf[used + n] = '\0';
            req->param[req->nparam++] = buf + used;
            used += n + 1;
            p = pe + 1;
            u += n;
        } else if (*p == *u) {
            p++;
            u++;
        } else {
            return 0;
        }
    }
    return *p == '\0' && *u == '\0';
}

static void timing_header(const srv_timing *t, http_resp *r)
{
    char buf[SRV_TIMING_MAX * 48];
    srv_timing_format(t, buf, sizeof buf);
    if (buf[0])
        http_header(r, "Server-Timing", buf);
}

/* ---- MHD callbacks ----------------------------------------------------------------------- */

static void record(http_server *s, int status, double dt)
{
    pthread_mutex_lock(&s->lock);
    s->stats.requests++;
    if (status >= 100 && status < 600)
        s->stats.by_class[status / 100]++;
    for (int i = 0; i < 12; i++)
        if (dt <= http_latency_bounds[i])
            s->stats.latency_bucket[i]++;
    s->stats.latency_sum += dt;
    pthread_mutex_unlock(&s->lock);
}

void http_stats_get(http_server *s, http_stats *out)
{
    pthread_mutex_lock(&s->lock);
    *out = s->stats;
    pthread_mutex_unlock(&s->lock);
}

/* One request log line, "METHOD TARGET STATUS TIMEms" (the target as
 * http_head_log_target writes it), and the counters. */
static void log_request(http_server *s, const char *method, size_t mlen, const char *target,
                        size_t tlen, int status, double dt)
{
    char m[4 * 32 + 1], t[HTTP_LOG_TARGET];
    size_t k = 0;

    record(s, status, dt);
    if (s->cfg.quiet)
        return;
    if (!method || !mlen)
        m[k++] = '-';
    for (size_t i = 0; method && i < mlen && i < 32; i++) {
        unsigned char c = (unsigned char)method[i];
        if (c < 0x21 || c > 0x7e || c == '\\')
            k += (size_t)snprintf(m + k, sizeof m - k, "\\x%02x", c);
        else
            m[k++] = (char)c;
    }
    m[k] = '\0';
    if (target && tlen)
        http_head_log_target(target, tlen, t, sizeof t);
    else
        snprintf(t, sizeof t, "-");
    fprintf(stderr, "%s %s %d %.3fms\n", m, t, status, 1e3 * dt);
    fflush(stderr);
}

/* The front answered a request itself (http_front_config.answered). */
static void front_answered(void *cls, const char *method, size_t method_len, const char *target,
                           size_t target_len, int status, double seconds)
{
    log_request(cls, method, method_len, target, target_len, status, seconds);
}

/* The lease of the connection (NULL if it has none). */
static http_front_lease *conn_lease(struct MHD_Connection *conn)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return ci ? ci->socket_context : NULL;
}

/* What the front refuses in a head, refused again for the requests that
 * reach libmicrohttpd without it (the later ones of a kept-alive
 * connection).  resp.r is NULL when the request is acceptable. */
static http_resp check_request(const http_server *s, const req_ctx *ctx,
                               struct MHD_Connection *conn)
{
    const char *te = MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                                 MHD_HTTP_HEADER_TRANSFER_ENCODING);
    const char *cl = MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                                 MHD_HTTP_HEADER_CONTENT_LENGTH);
    http_resp none = {0, NULL};

    if (ctx->target && strstr(ctx->target, "%00"))
        return http_problem(400, "bad-request-target",
                            "the request target holds %%00 (a NUL byte)");
    if (te && cl)
        return http_problem(400, "bad-framing",
                            "Content-Length and Transfer-Encoding together: the body's length "
                            "is ambiguous");
    if (te)
        return http_problem(411, "length-required",
                            "request bodies must come with a Content-Length (Transfer-Encoding, "
                            "e.g. chunked, is not accepted)");
    if (cl) { /* digits only: libmicrohttpd refused anything else */
        char *end;
        unsigned long long n;
        errno = 0;
        n = strtoull(cl, &end, 10);
        if (errno == ERANGE || n > s->cfg.max_body)
            return http_problem(413, "body-too-large",
                                "Content-Length %.32s exceeds the request body limit of %zu bytes "
                                "(max_body, glintd --max-body-mb %zu)",
                                cl, s->cfg.max_body, s->cfg.max_body >> 20);
    }
    return none;
}

/* The Host rule (http_config.allow_host): resp.r is NULL when the request
 * names a host this daemon serves, or is a health check. */
static http_resp check_host(const http_server *s, struct MHD_Connection *conn,
                            const char *method, const char *url)
{
    const char *host = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
    http_resp none = {0, NULL};

    /* no Host (HTTP/1.0): not a browser, which always sends one */
    if (!host || http_host_served(host, s->cfg.allow_host))
        return none;
    if ((strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0) &&
        (strcmp(url, "/healthz") == 0 || strcmp(url, "/api/v1/healthz") == 0))
        return none;
    return http_problem(421, "host-not-served",
                        "glintd does not serve the host name in \"Host: %.200s\": it answers "
                        "IP addresses, localhost and the names given with --allow-host (a page "
                        "on another name that resolves to this machine is refused)", host);
}

/* Seconds left before the body falls behind min_body_rate (after its grace
 * of header_timeout_s); <= 0 when it has. */
static double body_slack(const http_server *s, const req_ctx *ctx, double now)
{
    return ctx->body_t0 + (double)s->cfg.header_timeout_s +
           (double)ctx->received / (double)s->cfg.min_body_rate - now;
}

/* libmicrohttpd's timeout is an idle one: set to the slack after each piece
 * of body, it closes the connection once the body falls behind even when
 * nothing more arrives. */
static void body_pace(struct MHD_Connection *conn, double slack)
{
    unsigned t = slack < 1.0 ? 1u : (unsigned)(slack + 0.999);
    MHD_set_connection_option(conn, MHD_CONNECTION_OPTION_TIMEOUT, t);
}

static void *uri_seen(void *cls, const char *uri, struct MHD_Connection *conn)
{
    req_ctx *ctx = calloc(1, sizeof *ctx);
    (void)cls;
    (void)conn;
    if (!ctx)
        return NULL;
    ctx->t0 = now_s();
    ctx->target = strdup(uri ? uri : "");
    return ctx;
}

/* The request state when uri_seen could not allocate it: made again on
 * the first on_request call (and kept in *con_cls); NULL if that fails
 * too. */
static req_ctx *req_ctx_late(void **con_cls)
{
    req_ctx *ctx = calloc(1, sizeof *ctx);
    if (!ctx)
        return NULL;
    ctx->t0 = now_s();
    *con_cls = ctx;
    return ctx;
}

/* The request log's line for an answer: the target as sent when uri_seen
 * kept it, else the decoded path. */
static void log_answer(http_server *s, const req_ctx *ctx, const char *method, const char *url,
                       int status, double seconds)
{
    log_request(s, method, strlen(method), ctx->target ? ctx->target : url,
                strlen(ctx->target ? ctx->target : url), status, seconds);
}

/* Queue `resp` (which is destroyed), mark the request answered and log
 * it. */
static enum MHD_Result answer(http_server *s, req_ctx *ctx, struct MHD_Connection *conn,
                              const char *method, const char *url, http_resp resp)
{
    enum MHD_Result ret = MHD_queue_response(conn, (unsigned)resp.status, resp.r);
    MHD_destroy_response(resp.r);
    ctx->answered = 1;
    log_answer(s, ctx, method, url, resp.status, now_s() - ctx->t0);
    return ret;
}

/* First call: headers only.  Queue nothing now unless refusing (this
 * libmicrohttpd answers "Connection: close" to responses queued on the
 * first call, which a refusal wants).  A body to come is paced from here
 * (min_body_rate). */
static enum MHD_Result on_head(http_server *s, req_ctx *ctx, struct MHD_Connection *conn,
                               const char *method, const char *url)
{
    http_resp resp;
    const char *cl;

    ctx->started = 1;
    snprintf(ctx->method, sizeof ctx->method, "%s", method);
    resp = check_request(s, ctx, conn);
    if (!resp.r && s->cfg.check_host)
        resp = check_host(s, conn, method, url);
    if (resp.r)
        return answer(s, ctx, conn, method, url, resp);
    cl = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_LENGTH);
    if (s->cfg.min_body_rate && cl && strcmp(cl, "0") != 0) {
        ctx->body_paced = 1;
        ctx->body_t0 = now_s();
        body_pace(conn, body_slack(s, ctx, ctx->body_t0));
    }
    return MHD_YES;
}

/* Append n bytes to the body, NUL-terminated; once it would pass max_body
 * it is dropped and only flagged (the route answers 413).  -1 when out of
 * memory. */
static int body_keep(const http_server *s, req_ctx *ctx, const char *data, size_t n)
{
    if (ctx->len + n > s->cfg.max_body) {
        ctx->too_large = 1;
        free(ctx->body);
        ctx->body = NULL;
        ctx->len = ctx->cap = 0;
        return 0;
    }
    if (ctx->len + n + 1 > ctx->cap) {
        size_t ncap = ctx->cap ? ctx->cap : 8192;
        char *nb;
        while (ncap < ctx->len + n + 1)
            ncap *= 2;
        nb = realloc(ctx->body, ncap);
        if (!nb)
            return -1;
        ctx->body = nb;
        ctx->cap = ncap;
    }
    memcpy(ctx->body + ctx->len, data, n);
    ctx->len += n;
    ctx->body[ctx->len] = '\0';
    return 0;
}

/* A piece of the body (*size bytes, consumed): a body that has fallen
 * behind min_body_rate closes the connection (logged as 408), else the
 * piece is kept. */
static enum MHD_Result on_body(http_server *s, req_ctx *ctx, struct MHD_Connection *conn,
                               const char *method, const char *url, const char *data,
                               size_t *size)
{
    if (ctx->body_paced) {
        double now = now_s(), slack;
        ctx->received += *size;
        slack = body_slack(s, ctx, now);
        if (slack <= 0) {
            ctx->answered = 1;
            log_answer(s, ctx, method, url, 408, now - ctx->t0);
            return MHD_NO; /* libmicrohttpd cannot answer in the middle of a body: close */
        }
        body_pace(conn, slack);
    }
    if (!ctx->too_large && body_keep(s, ctx, data, *size))
        return MHD_NO;
    *size = 0;
    return MHD_YES;
}

/* A request from another web origin (Origin unlike Host): admitted with
 * CORS headers when --allow-origin names it (OUT: *cors), else only GET
 * and HEAD go on and anything else is refused (403).  resp.r is NULL when
 * the request goes on. */
static http_resp check_origin(const http_server *s, struct MHD_Connection *conn,
                              const char *method, const char *origin, int *cors)
{
    http_resp resp = {0, NULL};
    if (origin && !http_same_origin(origin, MHD_lookup_connection_value(conn, MHD_HEADER_KIND,
                                                                   MHD_HTTP_HEADER_HOST))) {
        int safe = strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0;
        if (http_origin_allowed(s->cfg.allow_origin, origin))
            *cors = 1;
        else if (!safe)
            resp = http_problem(403, "cross-origin",
                                "requests from the web origin %.200s are not admitted: glintd "
                                "answers its own studio's pages (glintd --allow-origin admits "
                                "others)", origin);
    }
    return resp;
}

/* The route whose pattern and method match answers (its path parameters
 * are kept in pbuf); a path matched with another method is 405; a GET or
 * HEAD outside /api/ is a static file; anything else 404.  resp.r is NULL
 * only when building the response failed. */
static http_resp dispatch(const http_server *s, http_req *req, struct MHD_Connection *conn,
                          const char *method, const char *url, char *pbuf, size_t pbuflen)
{
    http_resp resp = {0, NULL};
    int matched_path = 0;

    for (int i = 0; i < s->nroutes && !resp.r; i++) {
        if (!match(s->routes[i].pattern, url, req, pbuf, pbuflen))
            continue;
        matched_path = 1;
        if (strcmp(s->routes[i].method, method) != 0)
            continue;
        resp = s->routes[i].fn(req);
        if (req->release)
            req->release(req);
        break;
    }
    if (!resp.r) {
        if (matched_path)
            resp = http_problem(405, "method-not-allowed", "%s is not allowed on %s", method, url);
        else if ((strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0) &&
                 strncmp(url, "/api/", 5) != 0)
            resp = http_static_serve(s->cfg.static_dir, url, MHD_lookup_connection_value(
                                           conn, MHD_HEADER_KIND,
                                           MHD_HTTP_HEADER_IF_MODIFIED_SINCE));
        else
            resp = http_problem(404, "not-found", "no such resource: %s %s", method, url);
    }
    return resp;
}

/* The headers every answer carries besides its own: Server-Timing, Allow
 * on a 405, CORS for an admitted origin, Vary when there is an Origin,
 * the replica's name, and Connection: close where the connection should
 * not be kept. */
static void common_headers(http_server *s, struct MHD_Connection *conn, http_resp *resp,
                           const srv_timing *timing, int cors, const char *origin)
{
    http_front_lease *lease;

    timing_header(timing, resp);
    if (resp->status == 405)
        MHD_add_response_header(resp->r, MHD_HTTP_HEADER_ALLOW, "GET, POST, PUT, DELETE");
    if (cors) {
        MHD_add_response_header(resp->r, "Access-Control-Allow-Origin", origin);
        MHD_add_response_header(resp->r, "Access-Control-Expose-Headers",
                                "Location, ETag, Content-Disposition, X-Glint-Env, Server-Timing, "
                                "X-Glint-Replica");
    }
    if (origin)
        MHD_add_response_header(resp->r, MHD_HTTP_HEADER_VARY, "Origin");
    if (s->cfg.replica)
        MHD_add_response_header(resp->r, "X-Glint-Replica", s->cfg.replica);
    /* a health check's reserve connection, and any connection while the
     * limits are nearly reached, is not kept alive */
    lease = conn_lease(conn);
    if (lease && (http_front_lease_is_reserve(lease) || http_front_busy(s->front, lease)))
        MHD_add_response_header(resp->r, MHD_HTTP_HEADER_CONNECTION, "close");
}

/* libmicrohttpd's access handler, called with the head (on_head), with
 * each piece of body (on_body), then once more to answer: origin checks,
 * a preflight, the route (dispatch), the common headers. */
static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    http_server *s = cls;
    req_ctx *ctx = *con_cls;
    http_req req;
    http_resp resp;
    char pbuf[1024];
    int cors = 0;
    const char *origin;

    (void)version;
    if (!ctx && !(ctx = req_ctx_late(con_cls))) /* uri_seen could not allocate */
        return MHD_NO;
    if (!ctx->started)
        return on_head(s, ctx, conn, method, url);
    if (*upload_data_size)
        return on_body(s, ctx, conn, method, url, upload_data, upload_data_size);
    if (ctx->body_paced) { /* the body is in: back to the idle timeout */
        MHD_set_connection_option(conn, MHD_CONNECTION_OPTION_TIMEOUT, s->cfg.timeout_s);
        ctx->body_paced = 0;
    }

    origin = MHD_lookup_connection_value(conn, MHD_HEADER_KIND, "Origin");
    resp = check_origin(s, conn, method, origin, &cors);
    if (!resp.r && strcmp(method, "OPTIONS") == 0) /* a preflight, or a probe of the methods */
        resp = http_preflight(cors);
    memset(&req, 0, sizeof req);
    req.method = method;
    req.path = url;
    req.conn = conn;
    req.body = ctx->body ? ctx->body : "";
    req.body_len = ctx->len;
    req.body_too_large = ctx->too_large;
    req.app = s->app;
    if (!resp.r)
        resp = dispatch(s, &req, conn, method, url, pbuf, sizeof pbuf);
    if (!resp.r)
        resp = http_problem(500, NULL, "internal error building the response");
    if (!resp.r)
        return MHD_NO;
    common_headers(s, conn, &resp, &req.timing, cors, origin);
    return answer(s, ctx, conn, method, url, resp);
}

static void on_completed(void *cls, struct MHD_Connection *conn, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    http_server *s = cls;
    req_ctx *ctx = *con_cls;
    (void)conn;
    if (ctx) {
        if (!ctx->answered && ctx->body_paced && toe == MHD_REQUEST_TERMINATED_TIMEOUT_REACHED)
            log_request(s, ctx->method, strlen(ctx->method), ctx->target,
                        ctx->target ? strlen(ctx->target) : 0, 408, now_s() - ctx->t0);
        free(ctx->target);
        free(ctx->body);
        free(ctx);
        *con_cls = NULL;
    }
}

/* MHD_OPTION_NOTIFY_CONNECTION: a started connection takes its lease from
 * s->parked; a closed one gives it back to the front. */
static void on_connection(void *cls, struct MHD_Connection *conn, void **socket_context,
                          enum MHD_ConnectionNotificationCode code)
{
    http_server *s = cls;
    if (code == MHD_CONNECTION_NOTIFY_STARTED) {
        const union MHD_ConnectionInfo *ci =
            MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);
        int fd = ci ? ci->connect_fd : -1;
        *socket_context = fd >= 0 && (size_t)fd < s->nparked
                              ? __atomic_exchange_n(&s->parked[fd], NULL, __ATOMIC_ACQ_REL)
                              : NULL;
    } else if (*socket_context) {
        http_front_release(s->front, *socket_context);
        *socket_context = NULL;
    }
}

/* http_front_config.deliver: park the lease under the descriptor and hand
 * the socket to libmicrohttpd, whose thread starts the connection. */
static void deliver(void *cls, int fd, const struct sockaddr *addr, socklen_t addrlen,
                    http_front_lease *lease)
{
    http_server *s = cls;
    http_front_lease *stale;

    if (fd < 0 || (size_t)fd >= s->nparked) {
        close(fd);
        http_front_release(s->front, lease);
        return;
    }
    /* a lease still parked under this descriptor is one libmicrohttpd
     * dropped (and closed) before starting its connection */
    stale = __atomic_exchange_n(&s->parked[fd], lease, __ATOMIC_ACQ_REL);
    http_front_release(s->front, stale);
    if (MHD_add_connection(s->d, fd, addr, addrlen) != MHD_YES)
        http_front_release(s->front,
                           __atomic_exchange_n(&s->parked[fd], NULL, __ATOMIC_ACQ_REL));
}

/* Raise the soft open-files limit to the hard one (waiting connections
 * cost a descriptor each).  Returns the limit now in force. */
static unsigned long raise_nofile(void)
{
    struct rlimit rl;
    if (getrlimit(RLIMIT_NOFILE, &rl) != 0)
        return 1024;
    if (rl.rlim_cur != rl.rlim_max) {
        struct rlimit want = rl;
        want.rlim_cur = rl.rlim_max == RLIM_INFINITY ? (rlim_t)1 << 20 : rl.rlim_max;
        if (setrlimit(RLIMIT_NOFILE, &want) == 0)
            rl = want;
    }
    return rl.rlim_cur == RLIM_INFINITY ? 1ul << 20 : (unsigned long)rl.rlim_cur;
}

/* A bound, listening TCP socket for addr:port.  OUT: *port_out. */
static int listen_on(const char *addr, int port, int *port_out, char *err, size_t errlen)
{
    struct sockaddr_storage ss;
    socklen_t sl;
    int fd, one = 1;

    memset(&ss, 0, sizeof ss);
    if (strchr(addr, ':')) {
        struct sockaddr_in6 *a6 = (struct sockaddr_in6 *)&ss;
        a6->sin6_family = AF_INET6;
        a6->sin6_port = htons((uint16_t)port);
        if (inet_pton(AF_INET6, addr, &a6->sin6_addr) != 1) {
            snprintf(err, errlen, "invalid IPv6 address '%s'", addr);
            return -1;
        }
        sl = sizeof *a6;
    } else {
        struct sockaddr_in *a4 = (struct sockaddr_in *)&ss;
        a4->sin_family = AF_INET;
        a4->sin_port = htons((uint16_t)port);
        if (inet_pton(AF_INET, addr, &a4->sin_addr) != 1) {
            snprintf(err, errlen, "invalid IPv4 address '%s'", addr);
            return -1;
        }
        sl = sizeof *a4;
    }
    fd = socket(ss.ss_family, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) {
        snprintf(err, errlen, "socket: %s", strerror(errno));
        return -1;
    }
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (ss.ss_family == AF_INET6)
        setsockopt(fd, IPPROTO_IPV6, IPV6_V6ONLY, &one, sizeof one);
    if (bind(fd, (struct sockaddr *)&ss, sl) != 0 || listen(fd, SOMAXCONN) != 0) {
        snprintf(err, errlen, "cannot listen on %s port %d: %s", addr, port, strerror(errno));
        close(fd);
        return -1;
    }
    sl = sizeof ss;
    if (getsockname(fd, (struct sockaddr *)&ss, &sl) != 0) {
        snprintf(err, errlen, "getsockname: %s", strerror(errno));
        close(fd);
        return -1;
    }
    *port_out = ntohs(ss.ss_family == AF_INET6 ? ((struct sockaddr_in6 *)&ss)->sin6_port
                                               : ((struct sockaddr_in *)&ss)->sin_port);
    return fd;
}

int http_server_start(const http_config *cfg, const http_route *routes, int n, void *app,
                      http_server **out, int *port_out, char *err, size_t errlen)
{
    http_server *s = calloc(1, sizeof *s);
    http_front_config fc;
    const unsigned flags = MHD_USE_THREAD_PER_CONNECTION | MHD_USE_INTERNAL_POLLING_THREAD |
                           MHD_USE_POLL | MHD_USE_NO_LISTEN_SOCKET | MHD_USE_ITC |
                           MHD_USE_ERROR_LOG;
    const char *addr = cfg->address ? cfg->address : "127.0.0.1";
    unsigned long nofile;
    unsigned reserved_fds;
    int lfd, port = 0;

    *out = NULL;
    if (!s) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    s->cfg = *cfg;
    if (!s->cfg.max_connections)
        s->cfg.max_connections = 256;
    if (!s->cfg.max_connections_per_ip)
        s->cfg.max_connections_per_ip = s->cfg.max_connections;
    if (!s->cfg.max_waiting_per_ip)
        s->cfg.max_waiting_per_ip = 256;
    if (!s->cfg.header_timeout_s)
        s->cfg.header_timeout_s = 10;
    if (!s->cfg.max_head)
        s->cfg.max_head = HTTP_MAX_HEAD_DEFAULT;
    if (!s->cfg.max_target)
        s->cfg.max_target = HTTP_MAX_TARGET_DEFAULT;
    s->routes = routes;
    s->nroutes = n;
    s->app = app;
    pthread_mutex_init(&s->lock, NULL);

    nofile = raise_nofile();
    s->nparked = nofile;
    s->parked = calloc(s->nparked, sizeof *s->parked);
    if (!s->parked) {
        snprintf(err, errlen, "out of memory");
        goto fail_parked;
    }
    lfd = listen_on(addr, cfg->port, &port, err, errlen);
    if (lfd < 0)
        goto fail_listen;
    s->d = MHD_start_daemon(flags, 0, NULL, NULL, on_request, s,
                            MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)s->cfg.timeout_s,
                            /* the front enforces the limits; this one only backs them */
                            MHD_OPTION_CONNECTION_LIMIT,
                            s->cfg.max_connections + s->cfg.health_reserve + 16u,
                            MHD_OPTION_NOTIFY_COMPLETED, on_completed, s,
                            MHD_OPTION_NOTIFY_CONNECTION, on_connection, s,
                            MHD_OPTION_URI_LOG_CALLBACK, uri_seen, s,
                            MHD_OPTION_END);
    if (!s->d) {
        snprintf(err, errlen, "cannot start libmicrohttpd");
        close(lfd);
        goto fail_listen;
    }
    reserved_fds = s->cfg.max_connections + s->cfg.health_reserve + HTTP_FD_HEADROOM;
    memset(&fc, 0, sizeof fc);
    fc.listen_fd = lfd;
    fc.head.max_head = s->cfg.max_head;
    fc.head.max_target = s->cfg.max_target;
    fc.head.max_fields = HTTP_MAX_FIELDS;
    fc.head.max_body = s->cfg.max_body;
    fc.header_timeout_s = s->cfg.header_timeout_s;
    fc.max_connections = s->cfg.max_connections;
    fc.max_per_ip = s->cfg.max_connections_per_ip;
    fc.health_reserve = s->cfg.health_reserve;
    fc.max_waiting_per_ip = s->cfg.max_waiting_per_ip;
    fc.max_waiting = nofile > reserved_fds + 16 ? (unsigned)(nofile - reserved_fds) : 16;
    fc.deliver = deliver;
    fc.answered = front_answered;
    fc.cls = s;
    if (http_front_start(&fc, &s->front, err, errlen))
        goto fail_front;
    fprintf(stderr,
            "glintd: open files limit %lu; connections: %u (+%u for health checks), %u per "
            "client, %u waiting; request heads within %u s\n",
            nofile, fc.max_connections, fc.health_reserve, fc.max_per_ip, fc.max_waiting,
            fc.header_timeout_s);
    if (port_out)
        *port_out = port;
    *out = s;
    return 0;

fail_front:
    MHD_stop_daemon(s->d);
fail_listen:
    free(s->parked);
fail_parked:
    pthread_mutex_destroy(&s->lock);
    free(s);
    return -1;
}

void http_server_stop(http_server *s)
{
    if (!s)
        return;
    /* The front stops accepting and closes the connections still waiting
     * for their head; MHD_stop_daemon then waits for the connection
     * threads (in-flight requests finish), which give their leases back. */
    http_front_stop(s->front);
    MHD_stop_daemon(s->d);
    for (size_t i = 0; i < s->nparked; i++)
        if (s->parked[i])
            http_front_release(s->front, s->parked[i]);
    http_front_free(s->front);
    free(s->parked);
    pthread_mutex_destroy(&s->lock);
    free(s);
}
