/* config.c: glintd's settings (contract in config.h). */
#include <errno.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "config.h"
#include "events.h"
#include "fitsvc.h"
#include "fsio.h"

void config_default(app_config *c)
{
    memset(c, 0, sizeof *c);
    strcpy(c->address, "127.0.0.1");
    c->port = 8080;
    strcpy(c->data_dir, "glint-data");
    strcpy(c->web_dir, "web");
    c->cache_bytes = (size_t)512 << 20;
    c->worker_threads = 2;
    c->background_priority = FITSVC_BG_IDLE;
    c->work_bytes = (size_t)2048 << 20;
    c->work_slots = 4;
    c->work_wait_s = 10;
    c->work_max_seconds = 600;
    c->work_interactive = -1; /* admit.h's defaults */
    c->work_per_client = -1;
    c->timeout_s = 30;
    c->max_connections = 256;
    c->max_connections_per_ip = 64;
    c->max_waiting_per_ip = 256;
    c->health_reserve = 4;
    c->header_timeout_s = 10;
    c->min_body_rate = 1024;
    c->max_streams_per_session = EVENTS_MAX_PER_SESSION_DEFAULT;
    c->max_streams_per_client = EVENTS_MAX_PER_CLIENT_DEFAULT;
    c->lim.max_body = (size_t)32 << 20;
    c->lim.max_image_dim = 4096;
    c->lim.max_mesh_tris = 2000000;
    c->lim.max_strokes = 1000;
    c->lim.max_stroke_points = 10000;
    c->lim.max_stroke_work = 5e7;
    c->lim.max_views = 64;
}

static int parse_long(const char *s, const char *what, long lo, long hi, long *out,
                      glint_err *err)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < lo || v > hi)
        return glint_err_set(err, GLINT_EINVAL, "--%s '%.64s' must be a whole number in %ld..%ld",
                             what, s, lo, hi);
    *out = v;
    return 0;
}

static int copy_str(char *dst, size_t cap, const char *src, const char *what, glint_err *err)
{
    if (strlen(src) >= cap)
        return glint_err_set(err, GLINT_EINVAL, "--%s is too long (%zu bytes, at most %zu)", what,
                             strlen(src), cap - 1);
    strcpy(dst, src);
    return 0;
}

/* The string options: name, field, capacity. */
#define STR_OPT(n, f) {n, offsetof(app_config, f), sizeof(((app_config *)0)->f)}
static const struct {
    const char *name;
    size_t off, cap;
} str_opts[] = {
    STR_OPT("address", address),   STR_OPT("data-dir", data_dir),
    STR_OPT("database", database), STR_OPT("replica-name", replica_name),
    STR_OPT("web-dir", web_dir),   STR_OPT("env-dir", env_dir),
    STR_OPT("measured-dir", measured_dir), STR_OPT("api-key", api_key),
    STR_OPT("allow-origin", allow_origin), STR_OPT("allow-host", allow_host),
    STR_OPT("demo-session", demo_session),
};

/* The numeric options: name, range, and where the value goes. */
enum { K_INT, K_UNSIGNED, K_MB, K_MILLION };
#define NUM_OPT(n, lo, hi, k, f) {n, lo, hi, k, offsetof(app_config, f)}
static const struct {
    const char *name;
    long lo, hi;
    int kind;
    size_t off;
} num_opts[] = {
    NUM_OPT("port", 0, 65535, K_INT, port),
    NUM_OPT("cache-mb", 1, 1L << 20, K_MB, cache_bytes),
    NUM_OPT("threads", 1, 64, K_INT, worker_threads),
    NUM_OPT("work-mb", 64, 1L << 22, K_MB, work_bytes),
    NUM_OPT("work-slots", 1, 1024, K_INT, work_slots),
    NUM_OPT("work-wait", 0, 3600, K_INT, work_wait_s),
    NUM_OPT("work-max-seconds", 0, 1000000, K_INT, work_max_seconds),
    NUM_OPT("work-interactive", 0, 1023, K_INT, work_interactive),
    NUM_OPT("work-per-client", 1, 1024, K_INT, work_per_client),
    NUM_OPT("timeout", 1, 3600, K_UNSIGNED, timeout_s),
    NUM_OPT("max-connections", 1, 100000, K_UNSIGNED, max_connections),
    NUM_OPT("max-connections-per-ip", 1, 100000, K_UNSIGNED, max_connections_per_ip),
    NUM_OPT("max-waiting-per-ip", 1, 1000000, K_UNSIGNED, max_waiting_per_ip),
    NUM_OPT("health-reserve", 0, 1000, K_UNSIGNED, health_reserve),
    NUM_OPT("header-timeout", 1, 3600, K_UNSIGNED, header_timeout_s),
    NUM_OPT("min-body-rate", 0, 1L << 30, K_UNSIGNED, min_body_rate),
    NUM_OPT("max-streams-per-session", 1, 100000, K_UNSIGNED, max_streams_per_session),
    NUM_OPT("max-streams-per-client", 1, 100000, K_UNSIGNED, max_streams_per_client),
    NUM_OPT("max-body-mb", 1, 4096, K_MB, lim.max_body),
    NUM_OPT("max-image-dim", 8, 16384, K_INT, lim.max_image_dim),
    NUM_OPT("max-mesh-tris", 1, 1L << 24, K_INT, lim.max_mesh_tris),
    NUM_OPT("max-strokes", 1, 1000000, K_INT, lim.max_strokes),
    NUM_OPT("max-stroke-work", 1, 100000, K_MILLION, lim.max_stroke_work),
};

int config_apply(app_config *c, const char *name, const char *val, glint_err *err)
{
    size_t i;
    long v = 0;
    if (!strcmp(name, "background-priority")) {
        /* in the order of FITSVC_BG_* */
        static const char *const names[] = {"idle", "low", "normal", NULL};
        _Static_assert(FITSVC_BG_IDLE == 0 && FITSVC_BG_LOW == 1 && FITSVC_BG_NORMAL == 2,
                       "names[] is in the order of FITSVC_BG_*");
        for (i = 0; names[i]; i++)
            if (!strcmp(val, names[i])) {
                c->background_priority = (int)i;
                return 0;
            }
        return glint_err_set(err, GLINT_EINVAL,
                             "--background-priority '%.64s' must be idle, low or normal", val);
    }
    for (i = 0; i < sizeof str_opts / sizeof *str_opts; i++)
        if (!strcmp(name, str_opts[i].name))
            return copy_str((char *)c + str_opts[i].off, str_opts[i].cap, val, name, err);
    for (i = 0; i < sizeof num_opts / sizeof *num_opts; i++) {
        void *f = (char *)c + num_opts[i].off;
        if (strcmp(name, num_opts[i].name))
            continue;
        if (parse_long(val, name, num_opts[i].lo, num_opts[i].hi, &v, err))
            return GLINT_EINVAL;
        switch (num_opts[i].kind) {
        case K_INT: *(int *)f = (int)v; break;
        case K_UNSIGNED: *(unsigned *)f = (unsigned)v; break;
        case K_MB: *(size_t *)f = (size_t)v << 20; break;
        default: *(double *)f = (double)v * 1e6; break;
        }
        return 0;
    }
    return glint_err_set(err, GLINT_EINVAL, "unknown option '%.64s'", name);
}

int config_load_text(app_config *c, const char *text, size_t len, const char *origin,
                     glint_err *err)
{
    json_error_t e;
    json_t *root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &e), *v;
    const char *k;
    int rc = 0;

    if (!root)
        return glint_err_set(err, GLINT_EFORMAT, "config %s: line %d: %s", origin, e.line, e.text);
    if (!json_is_object(root)) {
        json_decref(root);
        return glint_err_set(err, GLINT_EFORMAT, "config %s: expected a JSON object", origin);
    }
    json_object_foreach(root, k, v) {
        char name[64], val[32];
        const char *s = val;
        size_t i;
        if (strlen(k) >= sizeof name) {
            rc = glint_err_set(err, GLINT_EINVAL, "config %s: unknown key '%.64s...'", origin, k);
            break;
        }
        for (i = 0; k[i]; i++)
            name[i] = k[i] == '_' ? '-' : k[i];
        name[i] = '\0';
        if (!strcmp(name, "quiet")) {
            if (!json_is_boolean(v)) {
                rc = glint_err_set(err, GLINT_EINVAL, "config %s: '%s' must be true or false",
                                   origin, k);
                break;
            }
            c->quiet = json_is_true(v);
            continue;
        }
        if (json_is_string(v))
            s = json_string_value(v);
        else if (json_is_integer(v))
            snprintf(val, sizeof val, "%lld", (long long)json_integer_value(v));
        else {
            rc = glint_err_set(err, GLINT_EINVAL, "config %s: '%s' must be a string or an integer",
                               origin, k);
            break;
        }
        if ((rc = config_apply(c, name, s, err))) {
            glint_err_prefix(err, "config %s", origin);
            break;
        }
    }
    json_decref(root);
    return rc;
}

int config_load_file(app_config *c, const char *path, glint_err *err)
{
    char *text = NULL;
    size_t len = 0;
    int rc = fsio_read_all(path, CONFIG_MAX_FILE, &text, &len, err);
    if (rc)
        return glint_err_prefix(err, "config");
    rc = config_load_text(c, text, len, path, err);
    free(text);
    return rc;
}
