/* app.h: glintd's shared state, handed to every handler as req->app.
 *
 * Modules: http (transport), store (SQLite metadata + blob files in the data
 * directory), events (session streams), the precomputation cache, jobs,
 * memo and points (opened here, lent to fitsvc), fitsvc (fits), scenes (core
 * scenes and base renders), the api_* handlers, admit (expensive work
 * against a memory budget).  Numerics stay in core/: the server reaches them through the
 * method (method.h), pipeline (prep.h), material (material.h) and render
 * (render.h) interfaces only. */
#ifndef GLINTD_APP_H
#define GLINTD_APP_H

#include <pthread.h>
#include <stddef.h>
#include <time.h>

#include "err.h"
#include "http.h"

typedef struct app_limits {
    size_t max_body;          /* bytes of one request body (uploads included) */
    int max_image_dim;        /* width or height of an uploaded image or raster */
    int max_mesh_tris;        /* triangles of an uploaded mesh */
    int max_strokes;          /* strokes in one request */
    int max_stroke_points;    /* points in one stroke */
    double max_stroke_work;   /* distance evaluations of one request's strokes (stroke_cost) */
    int max_views;            /* views of a scene */
} app_limits;

typedef struct app_config {
    char address[64];
    int port;
    char data_dir[4096];
    char database[1024];      /* PostgreSQL connection string ("" = SQLite in data_dir) */
    char replica_name[65];    /* X-Glint-Replica on every response ("" = none) */
    char web_dir[4096];
    char env_dir[4096];       /* HDR maps offered as data:<file> ("" = none) */
    char measured_dir[4096];  /* MERL tables offered as merl:<file>, its fits file's
                                 materials as sgd:<name> and abc:<name> ("" = none) */
    size_t cache_bytes;       /* in-memory budget for precomputations */
    size_t work_bytes;        /* memory budget of expensive work in flight (admit.h) */
    int work_slots;           /* ... pieces of it at once */
    int work_wait_s;          /* how long a request waits for room (admit.h) */
    int work_max_seconds;     /* largest estimate of one piece of work, seconds (0: none) */
    int work_interactive;     /* slots kept for interactive work (-1: admit.h's default) */
    int work_per_client;      /* slots one client may hold (-1: admit.h's default) */
    int worker_threads;       /* background jobs */
    int background_priority;  /* fitsvc.h FITSVC_BG_*: measurements no one waits for */
    unsigned timeout_s;       /* idle timeout of a kept-alive connection */
    unsigned max_connections; /* connections served at once (health reserve aside) */
    unsigned max_connections_per_ip; /* ... per client */
    unsigned max_waiting_per_ip;     /* connections of a client waiting for their request head */
    unsigned health_reserve;  /* extra connections for health checks */
    unsigned header_timeout_s;       /* the request head must arrive within this */
    unsigned min_body_rate;   /* bytes/s a request body must keep up (0: no minimum) */
    unsigned max_streams_per_session; /* event streams open on one session (events.h) */
    unsigned max_streams_per_client;  /* ... for one client */
    char demo_session[4096];  /* the demo session's file, GET /api/v1/demo ("" = none) */
    char api_key[256];        /* "" = none */
    char allow_origin[1024];  /* other web origins admitted (http.h); "" = none */
    char allow_host[1024];    /* Host names served besides addresses and localhost (http.h) */
    int quiet;
    app_limits lim;
} app_config;

struct store;
struct events;
struct fitsvc;
struct render;
struct admit;
struct cache;
struct jobs;
struct memo;
struct points;

typedef struct app {
    app_config cfg;
    time_t started;
    int stopping;             /* SIGTERM or SIGINT came (read and set atomically): work stops */
    http_server *http;
    struct store *store;      /* store.h: SQLite + blobs */
    struct events *events;    /* events.h: per-session SSE streams */
    struct cache *cache;      /* core cache.h: precomputations (scenes, patterns, levels) */
    struct jobs *jobs;        /* jobs.h: background work (cold fits, measurements) */
    struct memo *memo;        /* memo.h: decoded paintings and material documents */
    struct points *points;    /* points.h: the scenes' speed-accuracy records */
    struct fitsvc *fits;      /* fitsvc.h: fits, with the four above */
    struct render *render;    /* core render.h: previews (EGL opened on first use) */
    struct admit *work;       /* admit.h: renders, G-buffers and fits against a budget */
} app;

/* Routes of each api module (defined in api_*.c). */
extern const http_route api_core_routes[];
extern const int api_core_nroutes;
extern const http_route api_scenes_routes[];     /* scenes, meshes */
extern const int api_scenes_nroutes;
extern const http_route api_views_routes[];      /* a scene's base renders and G-buffers */
extern const int api_views_nroutes;
extern const http_route api_sessions_routes[];   /* sessions, paintings, strokes, events */
extern const int api_sessions_nroutes;
extern const http_route api_tokens_routes[];     /* a session's links: revoke, expiry */
extern const int api_tokens_nroutes;
extern const http_route api_fits_routes[];       /* fits, jobs */
extern const int api_fits_nroutes;
extern const http_route api_materials_routes[];  /* materials, previews, exports */
extern const int api_materials_nroutes;
extern const http_route api_methods_routes[];    /* the methods catalogue */
extern const int api_methods_nroutes;
extern const http_route api_envs_routes[];       /* the environments on offer */
extern const int api_envs_nroutes;
/* The environments' resolver (api_envs.c), set before threads start. */
int api_envs_init(const char *dir, glint_err *err);
extern const http_route api_exports_routes[];    /* materials for other tools */
extern const int api_exports_nroutes;
extern const http_route api_gbuffers_routes[];   /* G-buffer sets and their fits */
extern const int api_gbuffers_nroutes;
extern const http_route api_measured_routes[];   /* measured materials on offer */
extern const int api_measured_nroutes;
/* The measured materials' resolver (api_measured.c), set before threads start. */
int api_measured_init(const char *dir, glint_err *err);
extern const http_route api_demo_routes[];       /* the demo session (--demo-session) */
extern const int api_demo_nroutes;
/* The demo session's id from its file (the answer of POST /api/v1/sessions;
 * OUT: id).  GLINT_ENOTFOUND (kind "no-demo") when the file is not there;
 * else a code of kind "demo-file-invalid" naming what is wrong.  api_demo.c. */
int api_demo_read(const char *path, char id[33], glint_err *err);
/* Uploaded environments live in the store's blobs (after store_open). */
int api_envs_store(struct store *s, glint_err *err);

#endif
