/* render_env.c: previews and base renders under an environment (render.h):
 * the cache of lights and vertex visibility, vertex shading drawn through
 * EGL, and the per-pixel CPU reference. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "brdf.h"
#include "env.h"
#include "envlit.h"
#include "measured.h"
#include "merl.h"
#include "raster.h"
#include "internal/render_int.h"
#include "vis.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

typedef struct env_entry {
    char key[256];
    env_map map;
    env_lights lights;
    envlit_vis vis;          /* of the keyed mesh's vertices (EGL); empty for CPU-only use */
    int has_vis;
    double prepare_s;
    lru_node lru;
} env_entry;

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void render_env_init(render_env *e)
{
    memset(e, 0, sizeof *e);
    snprintf(e->spec, sizeof e->spec, "studio");
    e->intensity = 1.0;
    e->lights = 256;
    e->shadows = 1;
    e->background = 1;
}

int render_env_check(const render_env *e, glint_err *err)
{
    int rc;
    if (!e || !e->spec[0])
        return glint_err_set(err, GLINT_EINVAL, "an environment render needs an environment");
    if ((rc = env_spec_check(e->spec, err)))
        return rc;
    if (!(fabs(e->rotation_deg) <= 360.0))
        return glint_err_set(err, GLINT_EINVAL, "env_rotation must be degrees in [-360, 360]");
    if (!(e->intensity > 0.0 && e->intensity <= 1e6))
        return glint_err_set(err, GLINT_EINVAL, "env_intensity must be in (0, 1e6]");
    if (e->lights < 1 || e->lights > RENDER_ENV_MAX_LIGHTS)
        return glint_err_set(err, GLINT_EINVAL, "lights must be an integer in 1..%d",
                             RENDER_ENV_MAX_LIGHTS);
    return 0;
}

static void entry_free(env_entry *x)
{
    env_map_free(&x->map);
    env_lights_free(&x->lights);
    envlit_vis_free(&x->vis);
    free(x);
}

void render_env_drop_all(render *r)
{
    while (r->envs.head) {
        env_entry *x = lru_entry(r->envs.head, env_entry, lru);
        lru_remove(&r->envs, &x->lru);
        entry_free(x);
    }
}

/* The entry's key of (mesh_key, env) (OUT: key[256]); 0 when it fits. */
static int entry_key(const char *mesh_key, const render_env *e, char key[256])
{
    int n = snprintf(key, 256, "%s|%s|%.17g|%.17g|%d|%d", mesh_key ? mesh_key : "", e->spec,
                     e->rotation_deg, e->intensity, e->lights, e->shadows);
    return n > 0 && n < 256 ? 0 : -1;
}

int render_env_vis_cached(render *r, const char *mesh_key, const render_env *e)
{
    char key[256];
    int found = 0;
    if (!r || !mesh_key || entry_key(mesh_key, e, key))
        return 0;
    pthread_mutex_lock(&r->env_lock);
    for (lru_node *p = r->envs.head; p && !found; p = p->next) {
        env_entry *y = lru_entry(p, env_entry, lru);
        found = strcmp(y->key, key) == 0 && y->has_vis;
    }
    pthread_mutex_unlock(&r->env_lock);
    return found;
}

/* The entry of (mesh_key, env) with its lights and, for `need_vis`, the
 * visibility of m's vertices (r->env_lock held).  Uncached entries (no
 * key, or r NULL) are returned in *tmp for the caller to free. */
static int entry_get(render *r, const char *mesh_key, const mesh *m, const render_env *e,
                     int need_vis, env_entry **out, env_entry **tmp, render_env_info *info,
                     const glint_cancel *cancel, glint_err *err)
{
    char key[256];
    env_entry *x = NULL;
    double t0 = now_s();
    int rc, keyed;

    *tmp = NULL;
    keyed = entry_key(mesh_key, e, key) == 0;
    if (r && mesh_key && keyed)
        for (lru_node *p = r->envs.head; p; p = p->next) {
            env_entry *y = lru_entry(p, env_entry, lru);
            if (strcmp(y->key, key) == 0) {
                lru_touch(&r->envs, p);
                x = y;
                break;
            }
        }
    if (x && (!need_vis || x->has_vis)) {
        info->cached = 1;
        info->convex = x->vis.convex;
        *out = x;
        return 0;
    }
    if (glint_cancelled(cancel))
        return glint_cancel_err(err, "the render");
    if (!x) {
        if (!(x = calloc(1, sizeof *x)))
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        snprintf(x->key, sizeof x->key, "%s", key);
        if ((rc = env_prepare(e->spec, ENV_CUT_MEDIAN, e->lights, e->rotation_deg * M_PI / 180.0,
                              e->intensity, &x->map, &x->lights, err))) {
            entry_free(x);
            return rc;
        }
        if (r && mesh_key && keyed) {
            lru_push(&r->envs, &x->lru);
            while ((int)r->envs.n > RENDER_ENV_CACHE) {
                env_entry *old = lru_entry(lru_oldest(&r->envs), env_entry, lru);
                lru_remove(&r->envs, &old->lru);
                entry_free(old);
            }
        } else {
            *tmp = x;
        }
    }
    if (need_vis && !x->has_vis) {
        if ((rc = envlit_vis_vertices(m, &x->lights, e->shadows, &x->vis, cancel, err)))
            return rc; /* the entry stays, without visibility */
        x->has_vis = 1;
        info->rays = x->vis.rays;
    }
    info->convex = x->vis.convex;
    info->prepare_s = now_s() - t0;
    *out = x;
    return 0;
}

typedef struct shader {
    envlit_fn fn;          /* exact (pixels) */
    envlit_fn fn_vertex;   /* at vertices: the method's preview evaluation */
    const void *ctx;
    double scale;
    const glint_cancel *cancel;
    envlit_sum_fn sum;     /* fn summed over the lights in one call, or NULL */
} shader;

static int env_draw_gl(render *r, const char *key, const mesh *m, const shader *s,
                       const env_entry *x, const render_env *e, const scene_view *v, int w,
                       int h, img *out, render_env_info *info, render_used *used,
                       glint_err *err)
{
    float *rgb = malloc(3 * (size_t)m->nverts * sizeof *rgb);
    uint8_t *mask = e->background ? malloc((size_t)w * h) : NULL;
    glr_mesh *gm = NULL, *tmp = NULL;
    double t0 = now_s();
    int rc;

    if (!rgb || (e->background && !mask)) {
        free(rgb);
        free(mask);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for vertex colours");
    }
    rc = envlit_vertices(m, &x->lights, &x->vis, s->fn_vertex, s->ctx, v->eye, s->scale, 0, rgb,
                         s->cancel, err);
    info->shade_s = now_s() - t0;
    if (!rc) {
        t0 = now_s();
        pthread_mutex_lock(&r->lock);
        if (!render_gl_get(r, err))
            rc = GLINT_EUNSUPPORTED;
        else if (!(rc = render_gl_mesh_get(r, key, m, &gm, &tmp, err)))
            rc = glr_vertex_colors(r->gl, gm, v, w, h, rgb, m->nverts, 0.0f, out, mask, err);
        if (!rc && used)
            snprintf(used->engine, sizeof used->engine, "egl; %s; vertex shading",
                     glr_describe(r->gl));
        if (r->gl) {
            glr_mesh_free(r->gl, tmp);
            glr_trim_targets(r->gl, RENDER_GL_KEEP_PIXELS);
        }
        pthread_mutex_unlock(&r->lock);
        info->draw_s = now_s() - t0;
    }
    if (!rc && e->background)
        envlit_background(&x->map, e->rotation_deg * M_PI / 180.0, e->intensity, v, mask, out);
    free(rgb);
    free(mask);
    return rc;
}

static int env_draw_cpu(const mesh *m, const shader *s, const env_entry *x, const render_env *e,
                        const scene_view *v, int w, int h, img *out, render_env_info *info,
                        render_used *used, glint_err *err)
{
    gbuf g;
    double t0 = now_s();
    int rc;
    if ((rc = raster_view(m, v, w, h, &g, err)))
        return rc;
    /* (a convex mesh casts no shadows: envlit_gbuf is told so, not asked to find it again) */
    info->convex = e->shadows && vis_mesh_convex(m, ENVLIT_CONVEX_TOL);
    rc = s->sum ? envlit_gbuf_summed(&g, m, &x->lights, e->shadows && !info->convex, s->sum,
                                     s->ctx, s->scale, out, s->cancel, err)
                : envlit_gbuf(&g, m, &x->lights, e->shadows && !info->convex, s->fn, s->ctx,
                              s->scale, out, s->cancel, err);
    if (!rc && e->background)
        envlit_background(&x->map, e->rotation_deg * M_PI / 180.0, e->intensity, v, g.mask, out);
    gbuf_free(&g);
    info->shade_s = now_s() - t0;
    if (!rc && used)
        snprintf(used->engine, sizeof used->engine, "cpu; pixel shading");
    return rc;
}

static int env_any(render *r, render_engine eng, const char *key, const mesh *m,
                   const shader *s, const render_env *e, const scene_view *v, int w, int h,
                   img *out, render_env_info *info, render_used *used, glint_err *err)
{
    render_env_info dummy;
    env_entry *x = NULL, *tmp = NULL;
    int rc, gl = eng != RENDER_CPU && r;

    if (!info)
        info = &dummy;
    memset(info, 0, sizeof *info);
    memset(out, 0, sizeof *out);
    if ((rc = render_env_check(e, err)) || (rc = mesh_validate(m, err)))
        return rc;
    if (eng == RENDER_EGL && !r)
        return glint_err_set(err, GLINT_EUNSUPPORTED, "EGL rendering needs a renderer");
    if (w < 1 || h < 1 || w > SCENE_MAX_SIZE || h > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "render size %dx%d outside 1..%d", w, h,
                             SCENE_MAX_SIZE);
    if (r)
        pthread_mutex_lock(&r->env_lock);
    rc = entry_get(r, key, m, e, gl, &x, &tmp, info, s->cancel, err);
    if (!rc) {
        info->lights = x->lights.k;
        snprintf(info->env, sizeof info->env, "%s", x->map.name);
        if (gl) {
            rc = env_draw_gl(r, key, m, s, x, e, v, w, h, out, info, used, err);
            if (rc && rc != GLINT_ECANCELLED && eng == RENDER_AUTO) {
                if (rc != GLINT_EUNSUPPORTED && !r->quiet)
                    fprintf(stderr, "glint: EGL rendering failed, using the CPU: %s\n",
                            err ? err->msg : glint_strerror(rc));
                img_free(out);
                glint_err_clear(err);
                rc = env_draw_cpu(m, s, x, e, v, w, h, out, info, used, err);
            }
        } else {
            rc = env_draw_cpu(m, s, x, e, v, w, h, out, info, used, err);
        }
    }
    if (tmp)
        entry_free(tmp);
    if (r)
        pthread_mutex_unlock(&r->env_lock);
    return rc;
}

int render_material_env(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                        const material *mat, const render_env *env, const scene_view *v,
                        int width, int height, img *out, render_env_info *info,
                        render_used *used, const glint_cancel *cancel, glint_err *err)
{
    shader s = {material_envlit, material_envlit_preview, mat, 1.0, cancel, NULL};
    if (!mat || !mat->method) {
        memset(out, 0, sizeof *out);
        return glint_err_set(err, GLINT_EINVAL, "no material to render");
    }
    return env_any(r, eng, mesh_key, m, &s, env, v, width, height, out, info, used, err);
}

int render_base_env(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                    const char *brdf_spec, double scale, const render_env *env,
                    const scene_view *v, int width, int height, img *out,
                    render_env_info *info, render_used *used, const glint_cancel *cancel,
                    glint_err *err)
{
    brdf b;
    shader s = {brdf_envlit, brdf_envlit, &b, scale, cancel, NULL};
    int rc;
    memset(out, 0, sizeof *out);
    if (!(scale > 0.0) || !isfinite(scale))
        return glint_err_set(err, GLINT_EINVAL, "base render scale %g must be > 0", scale);
    if (brdf_spec && !strncmp(brdf_spec, "merl:", 5)) { /* a measured material */
        const merl_table *t;
        if ((rc = merl_acquire(brdf_spec + 5, &t, err)))
            return rc;
        s.fn = s.fn_vertex = merl_envlit;
        s.ctx = t;
        rc = env_any(r, eng, mesh_key, m, &s, env, v, width, height, out, info, used, err);
        merl_release(t);
        return rc;
    }
    if (measured_spec_is(brdf_spec)) { /* a published fit of a measured material */
        measured_truth t;
        if ((rc = measured_truth_parse(brdf_spec, &t, err)))
            return rc;
        s.fn = s.fn_vertex = measured_envlit;
        s.ctx = &t;
        return env_any(r, eng, mesh_key, m, &s, env, v, width, height, out, info, used, err);
    }
    if ((rc = brdf_parse(brdf_spec, &b, err)))
        return rc;
    s.sum = brdf_envlit_sum;
    return env_any(r, eng, mesh_key, m, &s, env, v, width, height, out, info, used, err);
}

/* ---- the material ball ------------------------------------------------------------- */

static pthread_once_t ball_once = PTHREAD_ONCE_INIT;
static mesh ball_mesh;
static int ball_rc;

static void ball_init(void)
{
    ball_rc = mesh_sphere(&ball_mesh, RENDER_BALL_LAT, RENDER_BALL_LON, NULL);
}

int render_ball(const mesh **out, glint_err *err)
{
    pthread_once(&ball_once, ball_init);
    *out = ball_rc ? NULL : &ball_mesh;
    return ball_rc ? glint_err_set(err, ball_rc, "out of memory for the material ball") : 0;
}
