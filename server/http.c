/* http.c: libmicrohttpd glue, routing, responses, request log, stats. */
#include "http.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <pthread.h>
#include <sys/socket.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define JSON_MAX_DEPTH 32

const double http_latency_bounds[12] = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025,
                                        0.05,   0.1,   0.25,   0.5,   1.0,  2.5};

struct http_server {
    struct MHD_Daemon *d;
    http_config cfg;
    const http_route *routes;
    int nroutes;
    void *app;
    pthread_mutex_t lock;
    http_stats stats;
};

/* Per-request state kept between MHD's calls. */
typedef struct req_ctx {
    char *body;
    size_t len, cap;
    int too_large;
    double t0;
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
    char *text = j ? json_dumps(j, JSON_COMPACT | JSON_REAL_PRECISION(17)) : NULL;
    json_decref(j);
    if (!text)
        return http_text(500, "application/problem+json",
                         "{\"type\":\"about:blank\",\"title\":\"Internal Server Error\","
                         "\"status\":500,\"detail\":\"cannot serialize the response\"}");
    return http_bytes_owned(status, "application/json", text, strlen(text));
}

static const char *status_title(int status)
{
    switch (status) {
    case 400: return "Bad Request";
    case 401: return "Unauthorized";
    case 403: return "Forbidden";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 409: return "Conflict";
    case 412: return "Precondition Failed";
    case 413: return "Content Too Large";
    case 415: return "Unsupported Media Type";
    case 422: return "Unprocessable Content";
    case 429: return "Too Many Requests";
    case 500: return "Internal Server Error";
    case 503: return "Service Unavailable";
    default: return "Error";
    }
}

http_resp http_problem(int status, const char *slug, const char *fmt, ...)
{
    char detail[1024], type[128];
    va_list ap;
    json_t *j;
    char *text;

    va_start(ap, fmt);
    vsnprintf(detail, sizeof detail, fmt, ap);
    va_end(ap);
    if (slug)
        snprintf(type, sizeof type, "/problems/%s", slug);
    else
        snprintf(type, sizeof type, "about:blank");
    j = json_pack("{s:s, s:s, s:i, s:s}", "type", type, "title", status_title(status),
                  "status", status, "detail", detail);
    text = j ? json_dumps(j, JSON_COMPACT) : NULL;
    json_decref(j);
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

const char *http_query(const http_req *req, const char *name)
{
    return MHD_lookup_connection_value(req->conn, MHD_GET_ARGUMENT_KIND, name);
}

const char *http_header_in(const http_req *req, const char *name)
{
    return MHD_lookup_connection_value(req->conn, MHD_HEADER_KIND, name);
}

static int json_depth(const json_t *j)
{
    int best = 0;
    if (json_is_object(j)) {
        const char *k;
        json_t *v;
        json_object_foreach((json_t *)j, k, v) {
            int d = json_depth(v);
            if (d > best)
                best = d;
        }
        return best + 1;
    }
    if (json_is_array(j)) {
        size_t i;
        json_t *v;
        json_array_foreach(j, i, v) {
            int d = json_depth(v);
            if (d > best)
                best = d;
        }
        return best + 1;
    }
    return 0;
}

/* Nesting depth of JSON text, counted before parsing (so a hostile document
 * cannot make the parser recurse deeply). */
static int text_depth(const char *s, size_t n)
{
    int depth = 0, best = 0, in_str = 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (in_str) {
            if (c == '\\')
                i++;
            else if (c == '"')
                in_str = 0;
        } else if (c == '"') {
            in_str = 1;
        } else if (c == '{' || c == '[') {
            if (++depth > best)
                best = depth;
        } else if (c == '}' || c == ']') {
            depth--;
        }
    }
    return best;
}

json_t *http_body_json(http_req *req, http_resp *problem)
{
    json_error_t e;
    json_t *j;
    const char *ct = http_header_in(req, MHD_HTTP_HEADER_CONTENT_TYPE);

    if (req->body_too_large) {
        *problem = http_problem(413, "body-too-large", "request body exceeds the limit");
        return NULL;
    }
    if (ct && strncmp(ct, "application/json", 16) != 0) {
        *problem = http_problem(415, "unsupported-media-type",
                                "expected Content-Type application/json, got %s", ct);
        return NULL;
    }
    if (req->body_len == 0) {
        *problem = http_problem(400, "invalid-json", "empty body: a JSON object is required");
        return NULL;
    }
    if (text_depth(req->body, req->body_len) > JSON_MAX_DEPTH) {
        *problem = http_problem(413, "json-too-deep", "JSON nesting deeper than the limit of %d",
                                JSON_MAX_DEPTH);
        return NULL;
    }
    j = json_loadb(req->body, req->body_len, JSON_REJECT_DUPLICATES, &e);
    if (!j) {
        *problem = http_problem(400, "invalid-json", "malformed JSON at line %d column %d: %s",
                                e.line, e.column, e.text);
        return NULL;
    }
    if (!json_is_object(j) || json_depth(j) > JSON_MAX_DEPTH) {
        json_decref(j);
        *problem = http_problem(422, "invalid-json", "the body must be a JSON object");
        return NULL;
    }
    return j;
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

/* ---- static files --------------------------------------------------------------------- */

static const char *mime_of(const char *path)
{
    const char *dot = strrchr(path, '.');
    static const struct { const char *ext, *type; } t[] = {
        {".html", "text/html; charset=utf-8"}, {".js", "text/javascript; charset=utf-8"},
        {".mjs", "text/javascript; charset=utf-8"}, {".css", "text/css; charset=utf-8"},
        {".json", "application/json"}, {".png", "image/png"}, {".svg", "image/svg+xml"},
        {".ico", "image/x-icon"}, {".yaml", "application/yaml"}, {".txt", "text/plain"}};
    if (dot)
        for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++)
            if (strcmp(dot, t[i].ext) == 0)
                return t[i].type;
    return "application/octet-stream";
}

/* Static files are revalidated on every load (Cache-Control: no-cache)
 * with Last-Modified / If-Modified-Since, so an unchanged module costs a
 * 304 and no body. */
static http_resp serve_static(const http_server *s, const char *path, const char *ims)
{
    char full[4096], lm[64];
    struct stat st;
    struct tm tm;
    FILE *f;
    char *data;
    http_resp r;

    if (!s->cfg.static_dir || strstr(path, "..") || strchr(path, '\\'))
        return http_problem(404, "not-found", "no such resource: %s", path);
    if (strcmp(path, "/") == 0)
        path = "/index.html";
    if (snprintf(full, sizeof full, "%s%s", s->cfg.static_dir, path) >= (int)sizeof full ||
        stat(full, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size > (64 << 20))
        return http_problem(404, "not-found", "no such resource: %s", path);
    f = fopen(full, "rb");
    data = malloc((size_t)st.st_size + 1);
    if (!f || !data || fread(data, 1, (size_t)st.st_size, f) != (size_t)st.st_size) {
        if (f)
            fclose(f);
        free(data);
        return http_problem(500, NULL, "cannot read %s", path);
    }
    fclose(f);
    gmtime_r(&st.st_mtime, &tm);
    strftime(lm, sizeof lm, "%a, %d %b %Y %H:%M:%S GMT", &tm);
    if (ims && strcmp(ims, lm) == 0) {
        free(data);
        r = http_bytes(304, NULL, "", 0);
    } else {
        r = http_bytes_owned(200, mime_of(full), data, (size_t)st.st_size);
    }
    http_header(&r, MHD_HTTP_HEADER_LAST_MODIFIED, lm);
    http_header(&r, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache");
    return r;
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

static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn, const char *url,
                                  const char *method, const char *version,
                                  const char *upload_data, size_t *upload_data_size,
                                  void **con_cls)
{
    http_server *s = cls;
    req_ctx *ctx = *con_cls;
    http_req req;
    http_resp resp = {0, NULL};
    char pbuf[1024];
    int matched_path = 0;
    enum MHD_Result ret;

    if (!ctx) {
        /* First call: headers only.  Queue nothing now (this libmicrohttpd
         * answers "Connection: close" to responses queued on the first call). */
        ctx = calloc(1, sizeof *ctx);
        if (!ctx)
            return MHD_NO;
        ctx->t0 = now_s();
        *con_cls = ctx;
        return MHD_YES;
    }
    if (*upload_data_size) {
        if (!ctx->too_large) {
            size_t n = *upload_data_size;
            if (ctx->len + n > s->cfg.max_body) {
                ctx->too_large = 1;
                free(ctx->body);
                ctx->body = NULL;
                ctx->len = ctx->cap = 0;
            } else {
                if (ctx->len + n + 1 > ctx->cap) {
                    size_t ncap = ctx->cap ? ctx->cap : 8192;
                    char *nb;
                    while (ncap < ctx->len + n + 1)
                        ncap *= 2;
                    nb = realloc(ctx->body, ncap);
                    if (!nb)
                        return MHD_NO;
                    ctx->body = nb;
                    ctx->cap = ncap;
                }
                memcpy(ctx->body + ctx->len, upload_data, n);
                ctx->len += n;
                ctx->body[ctx->len] = '\0';
            }
        }
        *upload_data_size = 0;
        return MHD_YES;
    }

    memset(&req, 0, sizeof req);
    req.method = method;
    req.path = url;
    req.conn = conn;
    req.body = ctx->body ? ctx->body : "";
    req.body_len = ctx->len;
    req.body_too_large = ctx->too_large;
    req.app = s->app;
    for (int i = 0; i < s->nroutes; i++) {
        if (!match(s->routes[i].pattern, url, &req, pbuf, sizeof pbuf))
            continue;
        matched_path = 1;
        if (strcmp(s->routes[i].method, method) != 0)
            continue;
        resp = s->routes[i].fn(&req);
        break;
    }
    if (!resp.r) {
        if (matched_path)
            resp = http_problem(405, "method-not-allowed", "%s is not allowed on %s", method, url);
        else if ((strcmp(method, "GET") == 0 || strcmp(method, "HEAD") == 0) &&
                 strncmp(url, "/api/", 5) != 0)
            resp = serve_static(s, url, MHD_lookup_connection_value(
                                           conn, MHD_HEADER_KIND,
                                           MHD_HTTP_HEADER_IF_MODIFIED_SINCE));
        else
            resp = http_problem(404, "not-found", "no such resource: %s %s", method, url);
    }
    if (!resp.r)
        resp = http_problem(500, NULL, "internal error building the response");
    if (!resp.r)
        return MHD_NO;
    if (resp.status == 405)
        MHD_add_response_header(resp.r, MHD_HTTP_HEADER_ALLOW, "GET, POST, PUT, DELETE");
    ret = MHD_queue_response(conn, (unsigned)resp.status, resp.r);
    MHD_destroy_response(resp.r);
    {
        double dt = now_s() - ctx->t0;
        record(s, resp.status, dt);
        if (!s->cfg.quiet) {
            fprintf(stderr, "%s %s %d %.3fms\n", method, url, resp.status, 1e3 * dt);
            fflush(stderr);
        }
    }
    (void)version;
    return ret;
}

static void on_completed(void *cls, struct MHD_Connection *conn, void **con_cls,
                         enum MHD_RequestTerminationCode toe)
{
    req_ctx *ctx = *con_cls;
    (void)cls;
    (void)conn;
    (void)toe;
    if (ctx) {
        free(ctx->body);
        free(ctx);
        *con_cls = NULL;
    }
}

int http_server_start(const http_config *cfg, const http_route *routes, int n, void *app,
                      http_server **out, int *port_out, char *err, size_t errlen)
{
    http_server *s = calloc(1, sizeof *s);
    struct sockaddr_storage ss;
    socklen_t sl;
    const union MHD_DaemonInfo *info;
    unsigned flags = MHD_USE_THREAD_PER_CONNECTION | MHD_USE_INTERNAL_POLLING_THREAD |
                     MHD_USE_ERROR_LOG;
    const char *addr = cfg->address ? cfg->address : "127.0.0.1";

    *out = NULL;
    if (!s) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    memset(&ss, 0, sizeof ss);
    if (strchr(addr, ':')) {
        struct sockaddr_in6 *a6 = (struct sockaddr_in6 *)&ss;
        a6->sin6_family = AF_INET6;
        a6->sin6_port = htons((uint16_t)cfg->port);
        if (inet_pton(AF_INET6, addr, &a6->sin6_addr) != 1) {
            snprintf(err, errlen, "invalid IPv6 address '%s'", addr);
            free(s);
            return -1;
        }
        flags |= MHD_USE_IPv6;
        sl = sizeof *a6;
    } else {
        struct sockaddr_in *a4 = (struct sockaddr_in *)&ss;
        a4->sin_family = AF_INET;
        a4->sin_port = htons((uint16_t)cfg->port);
        if (inet_pton(AF_INET, addr, &a4->sin_addr) != 1) {
            snprintf(err, errlen, "invalid IPv4 address '%s'", addr);
            free(s);
            return -1;
        }
        sl = sizeof *a4;
    }
    (void)sl;
    s->cfg = *cfg;
    s->routes = routes;
    s->nroutes = n;
    s->app = app;
    pthread_mutex_init(&s->lock, NULL);
    s->d = MHD_start_daemon(flags, (uint16_t)cfg->port, NULL, NULL, on_request, s,
                            MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&ss,
                            MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)cfg->timeout_s,
                            MHD_OPTION_CONNECTION_LIMIT, (unsigned)cfg->max_connections,
                            MHD_OPTION_NOTIFY_COMPLETED, on_completed, s,
                            MHD_OPTION_END);
    if (!s->d) {
        snprintf(err, errlen, "cannot listen on %s port %d (address in use or not allowed)",
                 addr, cfg->port);
        pthread_mutex_destroy(&s->lock);
        free(s);
        return -1;
    }
    info = MHD_get_daemon_info(s->d, MHD_DAEMON_INFO_BIND_PORT);
    if (port_out)
        *port_out = info ? info->port : cfg->port;
    *out = s;
    return 0;
}

void http_server_stop(http_server *s)
{
    if (!s)
        return;
    /* MHD_stop_daemon closes the listening socket, then waits for the
     * connection threads: in-flight requests finish. */
    MHD_stop_daemon(s->d);
    pthread_mutex_destroy(&s->lock);
    free(s);
}
