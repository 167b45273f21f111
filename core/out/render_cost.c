/* render_cost.c: estimates of a render's time (render.h, "Cost"). */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "brdf.h"
#include "envlit.h"
#include "measured.h"
#include "merl.h"
#include "internal/render_int.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Evaluations per round of eval_seconds. */
#define COST_EVALS 32

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Seconds of one evaluation of fn here: the least of three rounds of
 * COST_EVALS evaluations at fixed direction pairs above the surface (the
 * least: other work on the machine makes a round slower, never faster;
 * the first round also builds what a preview evaluation caches). */
static double eval_seconds(envlit_fn fn, const void *ctx)
{
    static const double n[3] = {0.0, 0.0, 1.0};
    double best = INFINITY, uv[2] = {0.5, 0.5}, rgb[3];
    for (int round = 0; round < 3; round++) {
        double t0 = now_s(), dt;
        for (int k = 0; k < COST_EVALS; k++) {
            double a = 2.0 * M_PI * k / COST_EVALS, ti = 0.1 + 1.3 * k / COST_EVALS,
                   to = 0.7 * ti;
            double wi[3] = {sin(ti) * cos(a), sin(ti) * sin(a), cos(ti)};
            double wo[3] = {sin(to) * cos(a + 2.0), sin(to) * sin(a + 2.0), cos(to)};
            fn(ctx, uv, n, wi, wo, rgb);
        }
        dt = (now_s() - t0) / COST_EVALS;
        if (dt < best)
            best = dt;
    }
    return best;
}

/* Whether r draws through EGL: its context opened (here, when not tried
 * yet: the render would open it next). */
static int gl_works(render *r)
{
    int ok;
    if (!r)
        return 0;
    pthread_mutex_lock(&r->lock);
    ok = render_gl_get(r, NULL) != NULL;
    pthread_mutex_unlock(&r->lock);
    return ok;
}

/* The estimate (render.h) from the evaluations' seconds; cpu_only: EGL
 * cannot draw it (a measured material). */
static double cost(render *r, render_engine eng, const char *key, const mesh *m,
                   const render_env *env, double eval_s, double eval_preview_s, int cpu_only,
                   int w, int h)
{
    double px = (double)(w > 0 ? w : 0) * (double)(h > 0 ? h : 0), half, ray;
    int gl = !cpu_only && (eng == RENDER_EGL || (eng == RENDER_AUTO && gl_works(r)));
    if (!env)
        return px * (RENDER_COST_PIXEL_S + eval_s);
    half = 0.5 * env->lights;
    if (!gl) {
        ray = env->shadows ? RENDER_COST_RAY_S : 0.0;
        return px * (RENDER_COST_PIXEL_S + half * (eval_s + ray));
    }
    ray = env->shadows && !render_env_vis_cached(r, key, env) ? RENDER_COST_RAY_S : 0.0;
    return px * RENDER_COST_PIXEL_S + (double)(m ? m->nverts : 0) * half * (eval_preview_s + ray);
}

double render_cost_seconds(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                           const render_env *env, double eval_s, double eval_preview_s,
                           int width, int height)
{
    return cost(r, eng, mesh_key, m, env, eval_s, eval_preview_s, 0, width, height);
}

double render_material_cost(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                            const material *mat, const render_env *env, int width, int height)
{
    double e, ep;
    if (!mat || !mat->method)
        return 0.0;
    e = eval_seconds(material_envlit, mat);
    ep = env ? eval_seconds(material_envlit_preview, mat) : e;
    return cost(r, eng, mesh_key, m, env, e, ep, 0, width, height);
}

int render_base_cost(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                     const char *brdf_spec, const render_env *env, int width, int height,
                     double *seconds, glint_err *err)
{
    brdf b;
    double e;
    int rc;
    *seconds = 0.0;
    if (brdf_spec && !strncmp(brdf_spec, "merl:", 5)) { /* the CPU shades a measured material */
        const merl_table *t;
        if ((rc = merl_acquire(brdf_spec + 5, &t, err)))
            return rc;
        e = eval_seconds(merl_envlit, t);
        merl_release(t);
        *seconds = cost(r, eng, mesh_key, m, env, e, e, 1, width, height);
        return 0;
    }
    if (measured_spec_is(brdf_spec)) { /* the CPU shades a published fit too */
        measured_truth t;
        if ((rc = measured_truth_parse(brdf_spec, &t, err)))
            return rc;
        e = eval_seconds(measured_envlit, &t);
        *seconds = cost(r, eng, mesh_key, m, env, e, e, 1, width, height);
        return 0;
    }
    if ((rc = brdf_parse(brdf_spec, &b, err)))
        return rc;
    e = eval_seconds(brdf_envlit, &b);
    *seconds = cost(r, eng, mesh_key, m, env, e, e, 0, width, height);
    return 0;
}
