/* glintd: the glint daemon.  Serves the browser studio (web/) at "/" and the
 * REST API under /api/v1 (described in proto/openapi.yaml).
 *
 * Options override the config file (--config FILE, JSON with the same keys
 * as the long options, e.g. {"port": 8080, "data_dir": "/var/lib/glint"}).
 * SIGTERM or SIGINT: stop accepting, cancel the work in flight (renders and
 * jobs stop within moments, cancel.h), let the requests answer, exit 0. */
#include <errno.h>
#include <getopt.h>
#include <jansson.h>
#include <limits.h>
#include <malloc.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "admit.h"
#include "api_common.h"
#include "app.h"
#include "cache.h"
#include "config.h"
#include "events.h"
#include "fitsvc.h"
#include "fsio.h"
#include "ids.h"
#include "jobs.h"
#include "log.h"
#include "memo.h"
#include "par.h"
#include "points.h"
#include "render.h"
#include "store.h"

#define GLINTD_ARENAS_MAX 4 /* malloc arenas, at most (fewer on fewer cores) */

/* The jobs' idle moments write the speed-accuracy record (points.h). */
static void idle_flush(void *cls)
{
    points_flush(cls, 1);
}

static void usage(FILE *f)
{
    fputs("usage: glintd [options]\n"
          "  --address ADDR        listen address (127.0.0.1)\n"
          "  --port N              port, 0 for an ephemeral one (8080)\n"
          "  --data-dir DIR        scenes, sessions, paintings, materials, cache (./glint-data)\n"
          "  --database CONNINFO   keep the metadata in PostgreSQL (a libpq connection\n"
          "                        string, e.g. \"host=/run/postgresql dbname=glint\");\n"
          "                        blobs stay in --data-dir, shared by the replicas that\n"
          "                        share the database (default: SQLite in --data-dir)\n"
          "  --replica-name NAME   name this process on every response (X-Glint-Replica),\n"
          "                        among replicas behind one proxy ([A-Za-z0-9._-], 1-64)\n"
          "  --web-dir DIR         static files served at / (./web)\n"
          "  --env-dir DIR         HDR environment maps offered to fits as data:<file>\n"
          "  --measured-dir DIR    MERL tables (*.binary) offered to paint from as merl:<file>,\n"
          "                        and the fits of its merl56_fits.json as sgd:<name>, abc:<name>\n"
          "  --cache-mb N          in-memory precomputation cache budget (512)\n"
          "  --threads N           background job threads (2)\n"
          "  --background-priority idle|low|normal\n"
          "                        CPU priority of the held-out measurements run after\n"
          "                        fits: idle only takes cores nothing else wants, low a\n"
          "                        small share of busy ones (nice 19), normal the same as\n"
          "                        requests (idle)\n"
          "  --work-mb N           memory for expensive work in flight: previews, base\n"
          "                        renders, G-buffers, fits; beyond it 503, or 413 for one\n"
          "                        piece that can never fit (2048)\n"
          "  --work-slots N        ... pieces of such work at once (4)\n"
          "  --work-wait S         how long a request waits for room before 503 (10)\n"
          "  --work-max-seconds S  the largest estimate of one piece of such work, in\n"
          "                        seconds of one core (a preview, a base render, a cold\n"
          "                        fit); beyond it 413 before it starts; 0 for no limit (600)\n"
          "  --work-interactive N  of --work-slots, kept for what people wait on (fits,\n"
          "                        previews, base renders): reference renders a client asks\n"
          "                        for at low priority and exports never take them, and wait\n"
          "                        while such work waits (1; 0 with one slot)\n"
          "  --work-per-client N   ... pieces of such work one client (its owner key, else its\n"
          "                        address) holds at once (half of --work-slots, at least 1)\n"
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
          "  --max-streams-per-session N\n"
          "                        session event streams open at once on one session;\n"
          "                        429 beyond (32)\n"
          "  --max-streams-per-client N\n"
          "                        ... for one client (IPv4 address, IPv6 /64; behind a\n"
          "                        proxy, every user) (16)\n"
          "  --max-body-mb N       request body limit (32)\n"
          "  --max-image-dim N     largest upload / raster side (4096)\n"
          "  --max-mesh-tris N     largest uploaded mesh (2000000)\n"
          "  --max-strokes N       strokes per request (1000)\n"
          "  --max-stroke-work N   millions of brush evaluations per stroke request (50)\n",
          f);
    /* in two pieces: C99 promises string literals of 4095 characters */
    fputs("  --api-key KEY         require this key for creation and scripting\n"
          "  --allow-origin LIST   web origins besides glintd's own whose pages may call the\n"
          "                        API (comma-separated, e.g. https://tools.example.com;\n"
          "                        none by default)\n"
          "  --allow-host LIST     host names the daemon answers besides IP addresses and\n"
          "                        localhost (comma-separated, e.g. glint.example.com; \"*\"\n"
          "                        for any): a request naming another Host is refused\n"
          "                        (421), so that a web page on a name that resolves to\n"
          "                        this machine cannot use it; checked without --api-key,\n"
          "                        and with it when this is given (none by default)\n"
          "  --demo-session FILE   the session every visitor of the studio may open and\n"
          "                        paint: FILE holds the answer of POST /api/v1/sessions\n"
          "                        (read at each GET /api/v1/demo, so it may be written\n"
          "                        after the daemon starts; none by default)\n"
          "  --config FILE         JSON config file (keys as the long options, '-' as '_')\n"
          "  --port-file FILE      write the bound port there once listening\n"
          "  --quiet               no request log\n",
          f);
}

static const struct option glintd_options[] = {
    {"address", required_argument, 0, 1}, {"port", required_argument, 0, 1},
    {"data-dir", required_argument, 0, 1}, {"web-dir", required_argument, 0, 1},
    {"database", required_argument, 0, 1}, {"replica-name", required_argument, 0, 1},
    {"env-dir", required_argument, 0, 1}, {"measured-dir", required_argument, 0, 1},
    {"cache-mb", required_argument, 0, 1}, {"threads", required_argument, 0, 1},
    {"timeout", required_argument, 0, 1}, {"max-connections", required_argument, 0, 1},
    {"max-connections-per-ip", required_argument, 0, 1},
    {"max-waiting-per-ip", required_argument, 0, 1}, {"health-reserve", required_argument, 0, 1},
    {"header-timeout", required_argument, 0, 1}, {"min-body-rate", required_argument, 0, 1},
    {"max-streams-per-session", required_argument, 0, 1},
    {"max-streams-per-client", required_argument, 0, 1},
    {"max-body-mb", required_argument, 0, 1}, {"max-image-dim", required_argument, 0, 1},
    {"max-mesh-tris", required_argument, 0, 1}, {"max-strokes", required_argument, 0, 1},
    {"max-stroke-work", required_argument, 0, 1}, {"work-mb", required_argument, 0, 1},
    {"work-slots", required_argument, 0, 1}, {"work-wait", required_argument, 0, 1},
    {"work-max-seconds", required_argument, 0, 1},
    {"background-priority", required_argument, 0, 1},
    {"api-key", required_argument, 0, 1}, {"allow-origin", required_argument, 0, 1},
    {"allow-host", required_argument, 0, 1}, {"demo-session", required_argument, 0, 1},
    {"config", required_argument, 0, 2},
    {"port-file", required_argument, 0, 3}, {"quiet", no_argument, 0, 4},
    {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};

/* glintd_parse_options's answer when the daemon is to start (else it is
 * the exit status). */
#define GLINTD_START (-1)

/* Every connection has a thread of its own, and glibc gives threads up to
 * 8 malloc arenas per core, each keeping the peak its threads reached:
 * with a few hundred connections open (event streams), every large
 * request landed in an arena of its own and stayed there (measured: 30
 * open streams, then 16 stroke requests of 320 KB: +136 MB resident with
 * 16 arenas, +20 MB with 2).  A few arenas serve the threads that actually
 * run at once. */
static void glintd_limit_arenas(void)
{
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    mallopt(M_ARENA_MAX, cpus < 2 ? 2 : cpus > GLINTD_ARENAS_MAX ? GLINTD_ARENAS_MAX
                                                                 : (int)cpus);
}

/* --replica-name goes on every response: letters, digits, '.', '_', '-'. */
static int glintd_replica_name_ok(const char *name)
{
    for (const char *ch = name; *ch; ch++)
        if (!((*ch >= 'A' && *ch <= 'Z') || (*ch >= 'a' && *ch <= 'z') ||
              (*ch >= '0' && *ch <= '9') || *ch == '.' || *ch == '_' || *ch == '-'))
            return 0;
    return 1;
}

/* The configuration: defaults, then the config file, then the options
 * over it (OUT: *port_file).  GLINTD_START, or the status to exit with
 * (--help, a bad option or value: the message is printed). */
static int glintd_parse_options(int argc, char **argv, app_config *cfg, const char **port_file)
{
    const struct option *lo = glintd_options;
    glint_err ge;
    int c, idx;

    config_default(cfg);
    /* the config file first, so that options override it: a first pass of
     * getopt finds --config (either form), the second applies the rest */
    opterr = 0;
    while ((c = getopt_long(argc, argv, "h", lo, &idx)) != -1)
        if (c == 2 && config_load_file(cfg, optarg, &ge)) {
            fprintf(stderr, "glintd: %s\n", ge.msg);
            return 1;
        }
    opterr = 1;
    optind = 1;
    while ((c = getopt_long(argc, argv, "h", lo, &idx)) != -1) {
        if (c == 1) {
            if (config_apply(cfg, lo[idx].name, optarg, &ge)) {
                fprintf(stderr, "glintd: %s\n", ge.msg);
                return 1;
            }
        } else if (c == 2) {
            /* read in the first pass */
        } else if (c == 3) {
            *port_file = optarg;
        } else if (c == 4) {
            cfg->quiet = 1;
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
    if (!glintd_replica_name_ok(cfg->replica_name)) {
        fprintf(stderr, "glintd: --replica-name: only letters, digits, '.', '_' and '-' "
                        "(got '%s')\n", cfg->replica_name);
        return 1;
    }
    return GLINTD_START;
}

/* The data directory, and the environment maps and measured tables on
 * offer. */
static int glintd_prepare_data(const app_config *cfg, glint_err *ge)
{
    int rc = fsio_mkdirs(cfg->data_dir, ge);
    if (!rc)
        rc = api_envs_init(cfg->env_dir, ge);
    if (!rc)
        rc = api_measured_init(cfg->measured_dir, ge);
    return rc;
}

/* Block the stop signals in every thread (the threads started after this
 * inherit the mask); the main thread waits for them (OUT: *set). */
static void glintd_block_stop_signals(sigset_t *set)
{
    sigemptyset(set);
    sigaddset(set, SIGTERM);
    sigaddset(set, SIGINT);
    pthread_sigmask(SIG_BLOCK, set, NULL);
    signal(SIGPIPE, SIG_IGN);
}

/* The services behind the API, in the order they depend on each other:
 * the work admission, the store and its event streams, the caches, the
 * speed-accuracy record, the job threads, the fits and the renderer. */
static int glintd_open_services(app *a, glint_err *ge)
{
    char cache_dir[4200], points_dir[4300];
    fitsvc_config fc = {NULL, NULL, NULL, NULL, NULL, a->cfg.background_priority,
                        api_material_links};
    size_t budget = a->cfg.cache_bytes; /* precomputations; decoded paintings get an
                                           eighth of it more, material documents a
                                           thirty-second */
    int rc;

    snprintf(cache_dir, sizeof cache_dir, "%s/cache", a->cfg.data_dir);
    snprintf(points_dir, sizeof points_dir, "%s/points", cache_dir);
    if ((rc = admit_open(a->cfg.work_bytes, a->cfg.work_slots, a->cfg.work_wait_s, &a->work,
                         ge)))
        return rc;
    admit_limit_seconds(a->work, a->cfg.work_max_seconds);
    {
        admit_stats st;
        admit_get_stats(a->work, &st);
        admit_limit_classes(a->work,
                            a->cfg.work_interactive >= 0 ? a->cfg.work_interactive : st.reserve,
                            a->cfg.work_per_client > 0 ? a->cfg.work_per_client : st.per_client);
    }
    fc.work = a->work;
    if ((rc = store_open_db(a->cfg.data_dir, a->cfg.database, &a->store, ge)) ||
        (rc = api_envs_store(a->store, ge)) ||
        (rc = events_open(a->store, &a->events)) ||
        /* replicas on one database: their strokes reach this one's streams */
        (rc = store_listen(a->store, events_on_store_change, a->events, ge)) ||
        (rc = cache_open(cache_dir, budget, &a->cache, ge)) ||
        (rc = memo_open(budget / 8, budget / 32, &a->memo, ge)) ||
        (rc = points_open(points_dir, &a->points, ge)) ||
        (rc = jobs_open(a->cfg.worker_threads, idle_flush, a->points, POINTS_SAVE_PERIOD_S,
                        &a->jobs, ge)))
        return rc;
    fc.cache = a->cache;
    fc.jobs = a->jobs;
    fc.memo = a->memo;
    fc.points = a->points;
    if ((rc = fitsvc_open(&fc, a->store, a->events, &a->fits, ge)) ||
        (rc = render_open(8, 0, &a->render, ge)))
        return rc;
    return 0;
}

/* Error details never show where the data lives: the data and web
 * directories, as given and resolved, are private paths of the log. */
static void glintd_hide_paths(const app_config *cfg)
{
    char real[PATH_MAX];
    log_private_path(cfg->data_dir);
    if (realpath(cfg->data_dir, real))
        log_private_path(real);
    if (realpath(cfg->web_dir, real))
        log_private_path(real);
    log_private_path(cfg->demo_session); /* after the data directory it may lie in */
}

/* Every API module's routes in one table (OUT: *nroutes); NULL when out
 * of memory. */
static http_route *glintd_routes(int *nroutes)
{
    const http_route *tables[] = {api_core_routes, api_scenes_routes, api_sessions_routes,
                                  api_tokens_routes, api_fits_routes, api_materials_routes,
                                  api_methods_routes, api_envs_routes,
                                  api_measured_routes, api_exports_routes,
                                  api_gbuffers_routes, api_views_routes, api_demo_routes};
    const int counts[] = {api_core_nroutes, api_scenes_nroutes, api_sessions_nroutes,
                          api_tokens_nroutes, api_fits_nroutes, api_materials_nroutes,
                          api_methods_nroutes, api_envs_nroutes,
                          api_measured_nroutes, api_exports_nroutes,
                          api_gbuffers_nroutes, api_views_nroutes, api_demo_nroutes};
    const int ntables = (int)(sizeof counts / sizeof counts[0]);
    int total = 0;
    http_route *routes;

    for (int i = 0; i < ntables; i++)
        total += counts[i];
    routes = calloc((size_t)total, sizeof *routes);
    if (!routes)
        return NULL;
    *nroutes = 0;
    for (int i = 0; i < ntables; i++) {
        memcpy(routes + *nroutes, tables[i], (size_t)counts[i] * sizeof *routes);
        *nroutes += counts[i];
    }
    return routes;
}

/* The HTTP front's settings from the configuration (OUT: *hc). */
static void glintd_http_config(const app_config *cfg, http_config *hc)
{
    memset(hc, 0, sizeof *hc);
    hc->address = cfg->address;
    hc->port = cfg->port;
    hc->max_body = cfg->lim.max_body;
    hc->timeout_s = cfg->timeout_s;
    hc->max_connections = cfg->max_connections;
    hc->max_connections_per_ip = cfg->max_connections_per_ip;
    hc->max_waiting_per_ip = cfg->max_waiting_per_ip;
    hc->health_reserve = cfg->health_reserve;
    hc->header_timeout_s = cfg->header_timeout_s;
    hc->min_body_rate = cfg->min_body_rate;
    hc->static_dir = cfg->web_dir;
    hc->allow_origin = cfg->allow_origin[0] ? cfg->allow_origin : NULL;
    hc->allow_host = cfg->allow_host[0] ? cfg->allow_host : NULL;
    hc->check_host = !cfg->api_key[0] || cfg->allow_host[0];
    hc->quiet = cfg->quiet;
    hc->replica = cfg->replica_name[0] ? cfg->replica_name : NULL;
}

/* The demo session's file, when one is named: what GET /api/v1/demo will
 * answer, on stderr.  Not fatal: the file may be written (or replaced by
 * a valid one) after the start. */
static void glintd_announce_demo(const app_config *cfg)
{
    char id[GLINT_ID_LEN];
    glint_err ge;
    if (!cfg->demo_session[0])
        return;
    if (api_demo_read(cfg->demo_session, id, &ge) == 0)
        fprintf(stderr, "glintd: demo session %s (from %s)\n", id, cfg->demo_session);
    else if (ge.code == GLINT_ENOTFOUND)
        fprintf(stderr, "glintd: --demo-session: no %s yet: GET /api/v1/demo answers 204 "
                        "until it is written\n", cfg->demo_session);
    else
        fprintf(stderr, "glintd: warning: --demo-session: %s\n", ge.msg);
}

/* Where the daemon serves and which Host names it answers, on stderr;
 * the bound port written to `port_file` if one was asked for. */
static void glintd_announce(const app *a, const http_config *hc, int port, const char *port_file)
{
    glint_err ge;
    fprintf(stderr, "glintd: serving http://%s:%d/ (data %s, metadata in %s)\n", a->cfg.address,
            port, a->cfg.data_dir, store_backend(a->store));
    if (!hc->check_host || strcmp(a->cfg.allow_host, "*") == 0)
        fprintf(stderr, "glintd: answering any Host name (%s)\n",
                hc->check_host ? "--allow-host *" : "the API key guards the API");
    else
        fprintf(stderr, "glintd: answering the Host names localhost, IP addresses%s%s\n",
                a->cfg.allow_host[0] ? " and " : " (--allow-host adds others)",
                a->cfg.allow_host);
    glintd_announce_demo(&a->cfg);
    if (port_file) {
        char buf[32];
        int n = snprintf(buf, sizeof buf, "%d\n", port);
        if (fsio_write_atomic(port_file, buf, (size_t)n, &ge))
            fprintf(stderr, "glintd: %s\n", ge.msg);
    }
}

/* After SIGTERM or SIGINT: the renders in flight ask a->stopping and stop;
 * nothing new is admitted; the jobs stop (their builds ask) and no new one
 * starts; the streams end, then the connections; then everything closes,
 * each service after those that use it. */
static void glintd_shutdown(app *a, http_route *routes)
{
    __atomic_store_n(&a->stopping, 1, __ATOMIC_RELAXED);
    admit_stop(a->work);
    jobs_stop(a->jobs);
    events_shutdown(a->events); /* end the event streams, then the connections */
    jobs_shutdown(a->jobs);     /* and the job streams */
    http_server_stop(a->http);
    free(routes);
    jobs_close(a->jobs); /* running jobs finish first: they hold cache entries */
    fitsvc_close(a->fits);
    points_close(a->points);
    memo_close(a->memo);
    cache_close(a->cache);
    render_close(a->render);
    store_listen_stop(a->store); /* it wakes the streams: stop it first */
    events_close(a->events);
    store_close(a->store);
    admit_close(a->work);
}

int main(int argc, char **argv)
{
    app a;
    const char *port_file = NULL;
    int port = 0, sig, nroutes = 0, rc;
    char err[256];
    sigset_t set;
    glint_err ge;
    http_config hc;
    http_route *routes;

    memset(&a, 0, sizeof a);
    par_blas_single(); /* glint's loops are parallel; BLAS's idle threads would spin */
    glintd_limit_arenas();
    if ((rc = glintd_parse_options(argc, argv, &a.cfg, &port_file)) != GLINTD_START)
        return rc;
    if (glintd_prepare_data(&a.cfg, &ge)) {
        fprintf(stderr, "glintd: %s\n", ge.msg);
        return 1;
    }
    glintd_block_stop_signals(&set);
    if (glintd_open_services(&a, &ge)) {
        fprintf(stderr, "glintd: %s\n", ge.msg);
        return 1;
    }
    events_set_limits(a.events, a.cfg.max_streams_per_session, a.cfg.max_streams_per_client);
    glintd_hide_paths(&a.cfg);
    routes = glintd_routes(&nroutes);
    if (!routes)
        return 1;
    glintd_http_config(&a.cfg, &hc);
    a.started = time(NULL);
    if (http_server_start(&hc, routes, nroutes, &a, &a.http, &port, err, sizeof err)) {
        fprintf(stderr, "glintd: %s\n", err);
        free(routes);
        return 1;
    }
    glintd_announce(&a, &hc, port, port_file);
    if (sigwait(&set, &sig) == 0)
        fprintf(stderr, "glintd: %s: cancelling the work in flight, finishing requests\n",
                sig == SIGTERM ? "SIGTERM" : "SIGINT");
    glintd_shutdown(&a, routes);
    fprintf(stderr, "glintd: stopped\n");
    return 0;
}
