/* render.c: base renders and previews through EGL or on the CPU
 * (render.h). */
#include "render.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf.h"
#include "glr.h"
#include "lru.h"
#include "measured.h"
#include "merl.h"
#include "paint.h"
#include "raster.h"
#include "internal/render_int.h"

int render_engine_parse(const char *text, render_engine *out, glint_err *err)
{
    if (text && strcmp(text, "auto") == 0)
        *out = RENDER_AUTO;
    else if (text && strcmp(text, "egl") == 0)
        *out = RENDER_EGL;
    else if (text && strcmp(text, "cpu") == 0)
        *out = RENDER_CPU;
    else
        return glint_err_set(err, GLINT_EINVAL, "engine '%.32s': auto, egl or cpu",
                             text ? text : "");
    return 0;
}

int render_open(int gl_meshes, int quiet, render **out, glint_err *err)
{
    render *r = calloc(1, sizeof *r);
    *out = NULL;
    if (!r)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    pthread_mutex_init(&r->lock, NULL);
    pthread_mutex_init(&r->env_lock, NULL);
    r->quiet = quiet;
    r->max_meshes = gl_meshes > 0 ? gl_meshes : 1;
    *out = r;
    return 0;
}

static void drop_mesh(render *r, gl_mesh *g)
{
    lru_remove(&r->meshes, &g->lru);
    glr_mesh_free(r->gl, g->m);
    free(g);
}

void render_close(render *r)
{
    if (!r)
        return;
    while (r->meshes.head)
        drop_mesh(r, lru_entry(r->meshes.head, gl_mesh, lru));
    render_env_drop_all(r);
    glr_close(r->gl);
    pthread_mutex_destroy(&r->lock);
    pthread_mutex_destroy(&r->env_lock);
    free(r);
}

/* The EGL context (lock held), opened on first use: NULL with *err set
 * (GLINT_EUNSUPPORTED) when no platform works. */
glr *render_gl_get(render *r, glint_err *err)
{
    if (!r->gl_tried) {
        glint_err e;
        r->gl_tried = 1;
        if (glr_open(&r->gl, &e)) {
            r->gl = NULL;
            snprintf(r->gl_error, sizeof r->gl_error, "%s", e.msg);
            if (!r->quiet)
                fprintf(stderr, "glint: EGL unavailable, rendering on the CPU: %s\n", e.msg);
        } else if (!r->quiet) {
            fprintf(stderr, "glint: rendering through %s\n", glr_describe(r->gl));
        }
    }
    if (!r->gl)
        glint_err_set(err, GLINT_EUNSUPPORTED, "EGL rendering is unavailable: %s", r->gl_error);
    return r->gl;
}

/* The uploaded mesh for key (lock held); uncached when key is NULL (the
 * caller frees *tmp). */
int render_gl_mesh_get(render *r, const char *key, const mesh *m, glr_mesh **out,
                       glr_mesh **tmp, glint_err *err)
{
    gl_mesh *g;
    int rc;

    *tmp = NULL;
    if (!key || strlen(key) >= sizeof g->key) {
        rc = glr_mesh_upload(r->gl, m, tmp, err);
        *out = *tmp;
        return rc;
    }
    for (lru_node *n = r->meshes.head; n; n = n->next) {
        g = lru_entry(n, gl_mesh, lru);
        if (strcmp(g->key, key) == 0) {
            lru_touch(&r->meshes, n);
            *out = g->m;
            return 0;
        }
    }
    g = calloc(1, sizeof *g);
    if (!g)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if ((rc = glr_mesh_upload(r->gl, m, &g->m, err))) {
        free(g);
        return rc;
    }
    snprintf(g->key, sizeof g->key, "%s", key);
    lru_push(&r->meshes, &g->lru);
    while ((int)r->meshes.n > r->max_meshes)
        drop_mesh(r, lru_entry(lru_oldest(&r->meshes), gl_mesh, lru));
    *out = g->m;
    return 0;
}

typedef struct draw {
    const brdf *b;          /* base render, or */
    double scale;
    const material *mat;    /* a preview, or */
    /* a base render of a measured material (the CPU only): a MERL table or
     * a published fit (measured.h) as a truth function and its context */
    paint_fn fn;
    const void *fn_ctx;
    const glint_cancel *cancel;
} draw;

static int draw_gl(render *r, const char *key, const mesh *m, const draw *d,
                   const scene_view *v, int w, int h, img *out, render_used *used,
                   glint_err *err)
{
    glr_mesh *gm = NULL, *tmp = NULL;
    int rc;

    if (d->fn) /* a table of 1458000 bins per channel, or a fit: the CPU shades it */
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "measured materials (merl:, sgd:, abc:) render on the CPU");
    pthread_mutex_lock(&r->lock);
    if (glint_cancelled(d->cancel)) { /* after waiting for the context */
        pthread_mutex_unlock(&r->lock);
        return glint_cancel_err(err, "the render");
    }
    if (!render_gl_get(r, err)) {
        pthread_mutex_unlock(&r->lock);
        return GLINT_EUNSUPPORTED;
    }
    rc = render_gl_mesh_get(r, key, m, &gm, &tmp, err);
    if (!rc)
        rc = d->mat ? glr_preview(r->gl, gm, d->mat, v, w, h, 0.0f, out, err)
                    : glr_base_render(r->gl, gm, v, w, h, d->b, d->scale, 0.0f, out, err);
    if (!rc && used)
        snprintf(used->engine, sizeof used->engine, "egl; %s", glr_describe(r->gl));
    glr_mesh_free(r->gl, tmp);
    glr_trim_targets(r->gl, RENDER_GL_KEEP_PIXELS);
    pthread_mutex_unlock(&r->lock);
    return rc;
}

static int draw_cpu(const mesh *m, const draw *d, const scene_view *v, int w, int h, img *out,
                    render_used *used, glint_err *err)
{
    int rc;
    if (d->mat) {
        rc = material_render(d->mat, m, v, w, h, out, d->cancel, err);
    } else {
        /* a base render shades a few tens of ns a pixel (render_cost_seconds):
         * asked before and after rasterizing */
        gbuf g;
        if (glint_cancelled(d->cancel))
            return glint_cancel_err(err, "the render");
        if ((rc = raster_view(m, v, w, h, &g, err)))
            return rc;
        if (glint_cancelled(d->cancel))
            rc = glint_cancel_err(err, "the render");
        else
            rc = d->fn
                     ? paint_views_fn(d->fn, d->fn_ctx, &g, v, 1, d->scale, out, NULL, err)
                     : paint_views(d->b, &g, v, 1, d->scale, out, NULL, err);
        gbuf_free(&g);
    }
    if (!rc && used)
        snprintf(used->engine, sizeof used->engine, "cpu");
    return rc;
}

static int draw_any(render *r, render_engine eng, const char *key, const mesh *m,
                    const draw *d, const scene_view *v, int w, int h, img *out,
                    render_used *used, glint_err *err)
{
    int rc;
    memset(out, 0, sizeof *out);
    if (eng == RENDER_CPU || !r)
        return eng == RENDER_EGL ? glint_err_set(err, GLINT_EUNSUPPORTED,
                                                 "EGL rendering needs a renderer")
                                 : draw_cpu(m, d, v, w, h, out, used, err);
    rc = draw_gl(r, key, m, d, v, w, h, out, used, err);
    if (rc == 0 || eng == RENDER_EGL || rc == GLINT_ECANCELLED)
        return rc;
    if (rc != GLINT_EUNSUPPORTED && !r->quiet)
        fprintf(stderr, "glint: EGL rendering failed, using the CPU: %s\n",
                err ? err->msg : glint_strerror(rc));
    img_free(out);
    glint_err_clear(err);
    return draw_cpu(m, d, v, w, h, out, used, err);
}

size_t render_peak_bytes(render_engine eng, int base, int width, int height)
{
    size_t px = (size_t)(width > 0 ? width : 0) * (size_t)(height > 0 ? height : 0);
    size_t cpu = base ? 72 : 20, egl = 40;
    return RENDER_FIXED_BYTES + px * (eng == RENDER_CPU ? cpu : cpu > egl ? cpu : egl);
}

size_t render_gbuffer_peak_bytes(int width, int height)
{
    return RENDER_FIXED_BYTES +
           (size_t)(width > 0 ? width : 0) * (size_t)(height > 0 ? height : 0) * 224;
}

int render_brdf_check(const char *brdf_spec, glint_err *err)
{
    brdf b;
    char path[4096];
    measured_truth t;
    if (brdf_spec && !strncmp(brdf_spec, "merl:", 5))
        return merl_resolve(brdf_spec + 5, path, sizeof path, err);
    if (measured_spec_is(brdf_spec))
        return measured_truth_parse(brdf_spec, &t, err);
    return brdf_parse(brdf_spec, &b, err);
}

int render_base(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                const scene_view *v, int width, int height, const char *brdf_spec,
                double scale, img *out, render_used *used, const glint_cancel *cancel,
                glint_err *err)
{
    brdf b;
    draw d = {&b, scale, NULL, NULL, NULL, cancel};
    measured_truth t;
    const merl_table *mt;
    int rc;
    memset(out, 0, sizeof *out);
    if (!(scale > 0.0) || !isfinite(scale))
        return glint_err_set(err, GLINT_EINVAL, "base render scale %g must be > 0", scale);
    if (brdf_spec && !strncmp(brdf_spec, "merl:", 5)) {
        if ((rc = merl_acquire(brdf_spec + 5, &mt, err)))
            return rc;
        d.fn = merl_truth;
        d.fn_ctx = mt;
        rc = draw_any(r, eng, mesh_key, m, &d, v, width, height, out, used, err);
        merl_release(mt);
        return rc;
    }
    if (measured_spec_is(brdf_spec)) {
        if ((rc = measured_truth_parse(brdf_spec, &t, err)))
            return rc;
        d.fn = measured_truth_fn;
        d.fn_ctx = &t;
        return draw_any(r, eng, mesh_key, m, &d, v, width, height, out, used, err);
    }
    if ((rc = brdf_parse(brdf_spec, &b, err)))
        return rc;
    return draw_any(r, eng, mesh_key, m, &d, v, width, height, out, used, err);
}

int render_material(render *r, render_engine eng, const char *mesh_key, const mesh *m,
                    const material *mat, const scene_view *v, int width, int height, img *out,
                    render_used *used, const glint_cancel *cancel, glint_err *err)
{
    draw d = {NULL, 0.0, mat, NULL, NULL, cancel};
    return draw_any(r, eng, mesh_key, m, &d, v, width, height, out, used, err);
}

int render_gbuffer_exr(const mesh *m, const scene_view *v, int width, int height, void **data,
                       size_t *len, glint_err *err)
{
    gbuf g;
    int rc;
    *data = NULL;
    *len = 0;
    if ((rc = raster_view(m, v, width, height, &g, err)))
        return rc;
    rc = gbuf_exr_mem(&g, data, len, err);
    gbuf_free(&g);
    return rc;
}

int render_export_shader(const material *m, const char *dir, glint_err *err)
{
    return glr_shader_export(m, dir, err);
}

/* ---- cameras ---------------------------------------------------------------------- */

void render_camera_init(render_camera *c)
{
    memset(c, 0, sizeof *c);
    c->view = -1;
    c->intensity = -1.0;
}

int render_parse_vec3(const char *s, double v[3])
{
    char *end;
    if (!s)
        return GLINT_EINVAL;
    for (int i = 0; i < 3; i++) {
        v[i] = strtod(s, &end);
        if (end == s || !isfinite(v[i]) || fabs(v[i]) > 1e6)
            return GLINT_EINVAL;
        s = end;
        if (i < 2) {
            if (*s != ',')
                return GLINT_EINVAL;
            s++;
        }
    }
    return *s ? GLINT_EINVAL : 0;
}

int render_camera_view(const scene *sc, const render_camera *c, scene_view *v, glint_err *err)
{
    double d[3];
    if (c->view >= sc->nviews)
        return glint_err_set(err, GLINT_EINVAL,
                             "view must be an integer in 0..%d (the scene has %d views)",
                             sc->nviews - 1, sc->nviews);
    if (c->view < 0 && !(c->has_eye && c->has_light))
        return glint_err_set(err, GLINT_EINVAL,
                             "a camera needs a view of the scene, or an eye and a light");
    if (c->view >= 0) {
        *v = sc->views[c->view];
    } else {
        memset(v, 0, sizeof *v);
        v->half_fov = sc->views[0].half_fov;
        v->light_intensity = 1.0;
        v->light_deg = -1.0;
    }
    if (c->has_eye) {
        memcpy(v->eye, c->eye, sizeof v->eye);
        if (!c->has_target)
            v->target[0] = v->target[1] = v->target[2] = 0.0;
    }
    if (c->has_target)
        memcpy(v->target, c->target, sizeof v->target);
    if (c->has_light)
        memcpy(v->light, c->light, sizeof v->light);
    if (c->fov_deg != 0.0) {
        if (!(c->fov_deg >= 1.0 && c->fov_deg <= 170.0))
            return glint_err_set(err, GLINT_EINVAL,
                                 "fov must be a vertical field of view in degrees, 1..170");
        v->half_fov = 0.5 * c->fov_deg * M_PI / 180.0;
    }
    if (c->intensity >= 0.0) {
        if (!(c->intensity <= 1e6))
            return glint_err_set(err, GLINT_EINVAL, "intensity must be in [0, 1e6]");
        v->light_intensity = c->intensity;
    }
    for (int i = 0; i < 3; i++)
        d[i] = v->target[i] - v->eye[i];
    if (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < 1e-12)
        return glint_err_set(err, GLINT_EINVAL, "eye and target coincide");
    return 0;
}
