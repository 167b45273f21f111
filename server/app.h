/* app.h: glintd's shared state, handed to every handler as req->app.
 *
 * Modules: http (transport), store (SQLite metadata + blob files in the data
 * directory), the api_* handlers.  Numerics stay in core/: handlers call
 * core's stages (scene, raster, fit, material, glr) and never compute
 * themselves. */
#ifndef GLINTD_APP_H
#define GLINTD_APP_H

#include <pthread.h>
#include <stddef.h>
#include <time.h>

#include "http.h"

typedef struct app_limits {
    size_t max_body;          /* bytes of one request body (uploads included) */
    int max_image_dim;        /* width or height of an uploaded image or raster */
    int max_mesh_tris;        /* triangles of an uploaded mesh */
    int max_strokes;          /* strokes in one request */
    int max_stroke_points;    /* points in one stroke */
    int max_views;            /* views of a scene */
} app_limits;

typedef struct app_config {
    char address[64];
    int port;
    char data_dir[4096];
    char web_dir[4096];
    size_t cache_bytes;       /* in-memory budget for precomputations */
    int worker_threads;       /* background jobs */
    unsigned timeout_s;       /* idle connection timeout */
    unsigned max_connections;
    char api_key[256];        /* "" = none */
    int quiet;
    app_limits lim;
} app_config;

struct store;
struct events;
struct fitsvc;
struct glr;

typedef struct app {
    app_config cfg;
    time_t started;
    http_server *http;
    struct store *store;      /* store.h: SQLite + blobs */
    struct events *events;    /* events.h: per-session SSE streams */
    struct fitsvc *fits;      /* fitsvc.h: precomputation cache, jobs */
    struct glr *gl;           /* glr.h: EGL renderer, opened lazily; */
    pthread_mutex_t gl_lock;  /* one thread at a time uses it */
    int gl_failed;            /* 1 after glr_open failed (previews then use the CPU) */
} app;

/* Routes of each api module (defined in api_*.c). */
extern const http_route api_core_routes[];
extern const int api_core_nroutes;
extern const http_route api_scenes_routes[];     /* scenes, meshes */
extern const int api_scenes_nroutes;
extern const http_route api_sessions_routes[];   /* sessions, paintings, strokes, events */
extern const int api_sessions_nroutes;
extern const http_route api_fits_routes[];       /* fits, jobs, materials, methods */
extern const int api_fits_nroutes;

#endif
