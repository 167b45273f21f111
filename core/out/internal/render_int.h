/* render_int.h: internals shared by render.c and render_env.c (not part
 * of core's contract, which is render.h). */
#ifndef GLINT_RENDER_INT_H
#define GLINT_RENDER_INT_H

#include <pthread.h>

#include "glr.h"
#include "lru.h"
#include "render.h"

typedef struct gl_mesh {
    char key[128];
    glr_mesh *m;
    lru_node lru;
} gl_mesh;

struct render {
    pthread_mutex_t lock;      /* the EGL context: one draw at a time */
    glr *gl;
    int gl_tried;              /* glr_open was attempted */
    char gl_error[GLINT_ERR_MSG_MAX];
    int quiet;
    int max_meshes;
    lru_list meshes;
    pthread_mutex_t env_lock;  /* the environment cache (render_env.c) */
    lru_list envs;
};

/* The EGL context (r->lock held), opened on first use: NULL with *err set
 * (GLINT_EUNSUPPORTED) when no platform works. */
glr *render_gl_get(render *r, glint_err *err);

/* The uploaded mesh for key (r->lock held); uncached when key is NULL
 * (the caller frees *tmp). */
int render_gl_mesh_get(render *r, const char *key, const mesh *m, glr_mesh **out,
                       glr_mesh **tmp, glint_err *err);

/* Drop every cached environment (render_close). */
void render_env_drop_all(render *r);

/* Whether the environment cache holds the visibility of mesh_key's
 * vertices under e (a render of it casts no rays); 0 for a NULL r or key. */
int render_env_vis_cached(render *r, const char *mesh_key, const render_env *e);

#endif
