/* glintd: the glint daemon.  Serves the browser studio (web/) at "/" and the
 * REST API under /api/v1 (described in proto/openapi.yaml).
 *
 * Options override the config file (--config FILE, JSON with the same keys
 * as the long options, e.g. {"port": 8080, "data_dir": "/var/lib/glint"}).
 * SIGTERM or SIGINT: stop accepting, let in-flight requests finish, exit 0. */
#include <errno.h>
#include <getopt.h>
#include <jansson.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "admit.h"
#include "app.h"
#include "events.h"
#include "fitsvc.h"
#include "fsio.h"
#include "log.h"
#include "render.h"
#include "store.h"

static void usage(FILE *f)
{
    fputs("usage: glintd [options]\n"
          "  --address ADDR        listen address (127.0.0.1)\n"
          "  --port N              port, 0 for an ephemeral one (8080)\n"
          "  --data-dir DIR        scenes, sessions, paintings, materials, cache (./glint-data)\n"
          "  --web-dir DIR         static files served at / (./web)\n"
          "  --env-dir DIR         HDR environment maps offered to fits as data:<file>\n"
          "  --measured-dir DIR    MERL tables (*.binary) offered to paint from as merl:<file>\n"
          "  --cache-mb N          in-memory precomputation cache budget (512)\n"
          "  --threads N           background job threads (2)\n"
          "  --work-mb N           memory for expensive work in flight: previews, base\n"
          "                        renders, G-buffers, fits; beyond it 503, or 413 for one\n"
          "                        piece that can never fit (2048)\n"
          "  --work-slots N        ... pieces of such work at once (4)\n"
          "  --work-wait S         how long a request waits for room before 503 (10)\n"
          "  --timeout S           idle timeout of a kept-alive connection, seconds (30)\n"
          "  --max-connections N   connections served at once, health checks aside (256)\n"
          "  --max-connections-per-ip N\n"
          "                        ... of them for one client (IPv4 address, IPv6 /64) (64)\n"
          "  --max-waiting-per-ip N  connections of one client waiting for their request\n"
          "                        head; the oldest is dropped beyond (256)\n"
          "  --health-reserve N    extra connections for GET /healthz only (4)\n"
          "  --header-timeout S    a request head must arrive within S seconds (10)\n"
          "  --min-body-rate B     a request body must keep up B bytes/s after a grace of\n"
          "                        --header-timeout; 0 for no minimum (1024)\n"
          "  --max-body-mb N       request body limit (32)\n"
          "  --max-image-dim N     largest upload / raster side (4096)\n"
          "  --max-mesh-tris N     largest uploaded mesh (2000000)\n"
          "  --max-strokes N       strokes per request (1000)\n"
          "  --max-stroke-work N   millions of brush evaluations per stroke request (50)\n"
          "  --api-key KEY         require this key for creation and scripting\n"
          "  --allow-origin LIST   web origins besides glintd's own whose pages may call the\n"
          "                        API (comma-separated, e.g. https://tools.example.com;\n"
          "                        none by default)\n"
          "  --config FILE         JSON config file (keys as the long options, '-' as '_')\n"
          "  --port-file FILE      write the bound port there once listening\n"
          "  --quiet               no request log\n",
          f);
}

static void config_default(app_config *c)
{
    memset(c, 0, sizeof *c);
    strcpy(c->address, "127.0.0.1");
    c->port = 8080;
    strcpy(c->data_dir, "glint-data");
    strcpy(c->web_dir, "web");
    c->cache_bytes = (size_t)512 << 20;
    c->worker_threads = 2;
    c->work_bytes = (size_t)2048 << 20;
    c->work_slots = 4;
    c->work_wait_s = 10;
    c->timeout_s = 30;
    c->max_connections = 256;
    c->max_connections_per_ip = 64;
    c->max_waiting_per_ip = 256;
    c->health_reserve = 4;
    c->header_timeout_s = 10;
    c->min_body_rate = 1024;
    c->lim.max_body = (size_t)32 << 20;
    c->lim.max_image_dim = 4096;
    c->lim.max_mesh_tris = 2000000;
    c->lim.max_strokes = 1000;
    c->lim.max_stroke_points = 10000;
    c->lim.max_stroke_work = 5e7;
    c->lim.max_views = 64;
}

static int parse_long(const char *s, const char *what, long lo, long hi, long *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < lo || v > hi) {
        fprintf(stderr, "glintd: %s '%s' must be a whole number in %ld..%ld\n", what, s, lo, hi);
        return -1;
    }
    *out = v;
    return 0;
}

static int copy_str(char *dst, size_t cap, const char *src, const char *what)
{
    if (strlen(src) >= cap) {
        fprintf(stderr, "glintd: %s too long\n", what);
        return -1;
    }
    strcpy(dst, src);
    return 0;
}

/* Apply one option (from the command line or the config file). */
static int apply_opt(app_config *c, const char *name, const char *val)
{
    long v;
    if (!strcmp(name, "address"))
        return copy_str(c->address, sizeof c->address, val, "--address");
    if (!strcmp(name, "data-dir"))
        return copy_str(c->data_dir, sizeof c->data_dir, val, "--data-dir");
    if (!strcmp(name, "web-dir"))
        return copy_str(c->web_dir, sizeof c->web_dir, val, "--web-dir");
    if (!strcmp(name, "env-dir"))
        return copy_str(c->env_dir, sizeof c->env_dir, val, "--env-dir");
    if (!strcmp(name, "measured-dir"))
        return copy_str(c->measured_dir, sizeof c->measured_dir, val, "--measured-dir");
    if (!strcmp(name, "api-key"))
        return copy_str(c->api_key, sizeof c->api_key, val, "--api-key");
    if (!strcmp(name, "allow-origin"))
        return copy_str(c->allow_origin, sizeof c->allow_origin, val, "--allow-origin");
    if (!strcmp(name, "port")) {
        if (parse_long(val, "--port", 0, 65535, &v)) return -1;
        c->port = (int)v;
    } else if (!strcmp(name, "cache-mb")) {
        if (parse_long(val, "--cache-mb", 1, 1 << 20, &v)) return -1;
        c->cache_bytes = (size_t)v << 20;
    } else if (!strcmp(name, "threads")) {
        if (parse_long(val, "--threads", 1, 64, &v)) return -1;
        c->worker_threads = (int)v;
    } else if (!strcmp(name, "work-mb")) {
        if (parse_long(val, "--work-mb", 64, 1 << 22, &v)) return -1;
        c->work_bytes = (size_t)v << 20;
    } else if (!strcmp(name, "work-slots")) {
        if (parse_long(val, "--work-slots", 1, 1024, &v)) return -1;
        c->work_slots = (int)v;
    } else if (!strcmp(name, "work-wait")) {
        if (parse_long(val, "--work-wait", 0, 3600, &v)) return -1;
        c->work_wait_s = (int)v;
    } else if (!strcmp(name, "timeout")) {
        if (parse_long(val, "--timeout", 1, 3600, &v)) return -1;
        c->timeout_s = (unsigned)v;
    } else if (!strcmp(name, "max-connections")) {
        if (parse_long(val, "--max-connections", 1, 100000, &v)) return -1;
        c->max_connections = (unsigned)v;
    } else if (!strcmp(name, "max-connections-per-ip")) {
        if (parse_long(val, "--max-connections-per-ip", 1, 100000, &v)) return -1;
        c->max_connections_per_ip = (unsigned)v;
    } else if (!strcmp(name, "max-waiting-per-ip")) {
        if (parse_long(val, "--max-waiting-per-ip", 1, 1000000, &v)) return -1;
        c->max_waiting_per_ip = (unsigned)v;
    } else if (!strcmp(name, "health-reserve")) {
        if (parse_long(val, "--health-reserve", 0, 1000, &v)) return -1;
        c->health_reserve = (unsigned)v;
    } else if (!strcmp(name, "header-timeout")) {
        if (parse_long(val, "--header-timeout", 1, 3600, &v)) return -1;
        c->header_timeout_s = (unsigned)v;
    } else if (!strcmp(name, "min-body-rate")) {
        if (parse_long(val, "--min-body-rate", 0, 1L << 30, &v)) return -1;
        c->min_body_rate = (unsigned)v;
    } else if (!strcmp(name, "max-body-mb")) {
        if (parse_long(val, "--max-body-mb", 1, 4096, &v)) return -1;
        c->lim.max_body = (size_t)v << 20;
    } else if (!strcmp(name, "max-image-dim")) {
        if (parse_long(val, "--max-image-dim", 8, 16384, &v)) return -1;
        c->lim.max_image_dim = (int)v;
    } else if (!strcmp(name, "max-mesh-tris")) {
        if (parse_long(val, "--max-mesh-tris", 1, 1 << 24, &v)) return -1;
        c->lim.max_mesh_tris = (int)v;
    } else if (!strcmp(name, "max-strokes")) {
        if (parse_long(val, "--max-strokes", 1, 1000000, &v)) return -1;
        c->lim.max_strokes = (int)v;
    } else if (!strcmp(name, "max-stroke-work")) {
        if (parse_long(val, "--max-stroke-work", 1, 100000, &v)) return -1;
        c->lim.max_stroke_work = (double)v * 1e6;
    } else {
        fprintf(stderr, "glintd: unknown option '%s'\n", name);
        return -1;
    }
    return 0;
}

static int load_config(app_config *c, const char *path)
{
    json_error_t e;
    json_t *root = json_load_file(path, JSON_REJECT_DUPLICATES, &e), *v;
    const char *k;
    int rc = 0;

    if (!root) {
        fprintf(stderr, "glintd: config %s: line %d: %s\n", path, e.line, e.text);
        return -1;
    }
    if (!json_is_object(root)) {
        fprintf(stderr, "glintd: config %s: expected a JSON object\n", path);
        json_decref(root);
        return -1;
    }
    json_object_foreach(root, k, v) {
        char name[64], val[4096];
        size_t i;
        if (strlen(k) >= sizeof name) {
            fprintf(stderr, "glintd: config %s: key too long\n", path);
            rc = -1;
            break;
        }
        for (i = 0; k[i]; i++)
            name[i] = k[i] == '_' ? '-' : k[i];
        name[i] = '\0';
        if (json_is_string(v))
            snprintf(val, sizeof val, "%s", json_string_value(v));
        else if (json_is_integer(v))
            snprintf(val, sizeof val, "%lld", (long long)json_integer_value(v));
        else if (json_is_boolean(v) && !strcmp(name, "quiet")) {
            c->quiet = json_is_true(v);
            continue;
        } else {
            fprintf(stderr, "glintd: config %s: '%s' must be a string or an integer\n", path, k);
            rc = -1;
            break;
        }
        if (apply_opt(c, name, val)) {
            fprintf(stderr, "glintd: (in config %s)\n", path);
            rc = -1;
            break;
        }
    }
    json_decref(root);
    return rc;
}

int main(int argc, char **argv)
{
    static const struct option lo[] = {
        {"address", required_argument, 0, 1}, {"port", required_argument, 0, 1},
        {"data-dir", required_argument, 0, 1}, {"web-dir", required_argument, 0, 1},
        {"env-dir", required_argument, 0, 1}, {"measured-dir", required_argument, 0, 1},
        {"cache-mb", required_argument, 0, 1}, {"threads", required_argument, 0, 1},
        {"timeout", required_argument, 0, 1}, {"max-connections", required_argument, 0, 1},
        {"max-connections-per-ip", required_argument, 0, 1},
        {"max-waiting-per-ip", required_argument, 0, 1}, {"health-reserve", required_argument, 0, 1},
        {"header-timeout", required_argument, 0, 1}, {"min-body-rate", required_argument, 0, 1},
        {"max-body-mb", required_argument, 0, 1}, {"max-image-dim", required_argument, 0, 1},
        {"max-mesh-tris", required_argument, 0, 1}, {"max-strokes", required_argument, 0, 1},
        {"max-stroke-work", required_argument, 0, 1}, {"work-mb", required_argument, 0, 1},
        {"work-slots", required_argument, 0, 1}, {"work-wait", required_argument, 0, 1},
        {"api-key", required_argument, 0, 1}, {"allow-origin", required_argument, 0, 1},
        {"config", required_argument, 0, 2},
        {"port-file", required_argument, 0, 3}, {"quiet", no_argument, 0, 4},
        {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    app a;
    const char *port_file = NULL;
    int c, idx, port = 0, sig;
    char err[256];
    sigset_t set;
    glint_err ge;
    http_config hc;
    http_route *routes;
    int nroutes = 0;

    memset(&a, 0, sizeof a);
    config_default(&a.cfg);
    /* the config file first, so that options override it */
    for (int i = 1; i < argc - 1; i++)
        if (!strcmp(argv[i], "--config") && load_config(&a.cfg, argv[i + 1]))
            return 1;
    while ((c = getopt_long(argc, argv, "h", lo, &idx)) != -1) {
        if (c == 1) {
            if (apply_opt(&a.cfg, lo[idx].name, optarg))
                return 1;
        } else if (c == 2) {
            /* handled above */
        } else if (c == 3) {
            port_file = optarg;
        } else if (c == 4) {
            a.cfg.quiet = 1;
        } else if (c == 'h') {
            usage(stdout);
            return 0;
        } else {
            usage(stderr);
            return 1;
        }
    }
    if (optind != argc) {
        fprintf(stderr, "glintd: unexpected argument '%s'\n", argv[optind]);
        return 1;
    }
    if (fsio_mkdirs(a.cfg.data_dir, &ge)) {
        fprintf(stderr, "glintd: %s\n", ge.msg);
        return 1;
    }

    if (api_envs_init(a.cfg.env_dir, &ge) || api_measured_init(a.cfg.measured_dir, &ge)) {
        fprintf(stderr, "glintd: %s\n", ge.msg);
        return 1;
    }
    /* Block the stop signals in every thread; the main thread waits for them. */
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGINT);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    signal(SIGPIPE, SIG_IGN);

    {
        char cache_dir[4200];
        fitsvc_config fc = {cache_dir, a.cfg.cache_bytes, a.cfg.worker_threads, NULL};
        snprintf(cache_dir, sizeof cache_dir, "%s/cache", a.cfg.data_dir);
        if (admit_open(a.cfg.work_bytes, a.cfg.work_slots, a.cfg.work_wait_s, &a.work, &ge)) {
            fprintf(stderr, "glintd: %s\n", ge.msg);
            return 1;
        }
        fc.work = a.work;
        if (store_open(a.cfg.data_dir, &a.store, &ge) || api_envs_store(a.store, &ge) ||
            events_open(a.store, &a.events) ||
            fitsvc_open(&fc, a.store, a.events, &a.fits, &ge) ||
            render_open(8, 0, &a.render, &ge)) {
            fprintf(stderr, "glintd: %s\n", ge.msg);
            return 1;
        }
    }
    /* error details never show where the data lives */
    log_private_path(a.cfg.data_dir);
    {
        char real[PATH_MAX];
        if (realpath(a.cfg.data_dir, real))
            log_private_path(real);
        if (realpath(a.cfg.web_dir, real))
            log_private_path(real);
    }

    {
        const http_route *tables[] = {api_core_routes, api_scenes_routes, api_sessions_routes,
                                      api_tokens_routes, api_fits_routes, api_materials_routes,
                                      api_methods_routes, api_envs_routes,
                                      api_measured_routes, api_exports_routes};
        const int counts[] = {api_core_nroutes, api_scenes_nroutes, api_sessions_nroutes,
                              api_tokens_nroutes, api_fits_nroutes, api_materials_nroutes,
                              api_methods_nroutes, api_envs_nroutes,
                              api_measured_nroutes, api_exports_nroutes};
        const int ntables = (int)(sizeof counts / sizeof counts[0]);
        int total = 0;
        for (int i = 0; i < ntables; i++)
            total += counts[i];
        routes = calloc((size_t)total, sizeof *routes);
        if (!routes)
            return 1;
        for (int i = 0; i < ntables; i++) {
            memcpy(routes + nroutes, tables[i], (size_t)counts[i] * sizeof *routes);
            nroutes += counts[i];
        }
    }

    memset(&hc, 0, sizeof hc);
    hc.address = a.cfg.address;
    hc.port = a.cfg.port;
    hc.max_body = a.cfg.lim.max_body;
    hc.timeout_s = a.cfg.timeout_s;
    hc.max_connections = a.cfg.max_connections;
    hc.max_connections_per_ip = a.cfg.max_connections_per_ip;
    hc.max_waiting_per_ip = a.cfg.max_waiting_per_ip;
    hc.health_reserve = a.cfg.health_reserve;
    hc.header_timeout_s = a.cfg.header_timeout_s;
    hc.min_body_rate = a.cfg.min_body_rate;
    hc.static_dir = a.cfg.web_dir;
    hc.allow_origin = a.cfg.allow_origin[0] ? a.cfg.allow_origin : NULL;
    hc.quiet = a.cfg.quiet;
    a.started = time(NULL);
    if (http_server_start(&hc, routes, nroutes, &a, &a.http, &port, err, sizeof err)) {
        fprintf(stderr, "glintd: %s\n", err);
        free(routes);
        return 1;
    }
    fprintf(stderr, "glintd: serving http://%s:%d/ (data %s)\n", a.cfg.address, port,
            a.cfg.data_dir);
    if (port_file) {
        char buf[32];
        int n = snprintf(buf, sizeof buf, "%d\n", port);
        if (fsio_write_atomic(port_file, buf, (size_t)n, &ge))
            fprintf(stderr, "glintd: %s\n", ge.msg);
    }
    if (sigwait(&set, &sig) == 0)
        fprintf(stderr, "glintd: %s: finishing in-flight requests\n",
                sig == SIGTERM ? "SIGTERM" : "SIGINT");
    events_shutdown(a.events); /* end the event streams, then the connections */
    fitsvc_shutdown(a.fits);   /* and the job streams */
    http_server_stop(a.http);
    free(routes);
    fitsvc_close(a.fits);
    render_close(a.render);
    events_close(a.events);
    store_close(a.store);
    admit_close(a.work);
    fprintf(stderr, "glintd: stopped\n");
    return 0;
}
