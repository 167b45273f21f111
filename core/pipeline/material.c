/* material.c: materials of any method: evaluation, CPU rendering, errors,
 * files (material.h).  Method-specific work goes through material_ops. */
#include "material.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fsio.h"
#include "json_text.h"
#include "raster.h"

#define MATERIAL_JSON_MAX (64u << 20)

void material_init(material *m, const method *meth, void *data, json_t *info)
{
    memset(m, 0, sizeof *m);
    m->method = meth;
    m->data = data;
    m->info = info ? info : json_object();
}

void material_free(material *m)
{
    if (!m)
        return;
    if (m->method && m->data)
        m->method->mat->free(m->data);
    json_decref(m->info);
    memset(m, 0, sizeof *m);
}

const char *material_method_name(const material *m)
{
    return m && m->method ? m->method->name : "";
}

void material_eval(const material *m, const double n[3], const double wi[3],
                   const double wo[3], double rgb[3])
{
    m->method->mat->eval(m->data, NULL, n, wi, wo, rgb);
}

void material_eval_at(const material *m, const double uv[2], const double n[3],
                      const double wi[3], const double wo[3], double rgb[3])
{
    m->method->mat->eval(m->data, uv, n, wi, wo, rgb);
}

void material_eval_preview(const material *m, const double n[3], const double wi[3],
                           const double wo[3], double rgb[3])
{
    material_eval_preview_at(m, NULL, n, wi, wo, rgb);
}

void material_eval_preview_at(const material *m, const double uv[2], const double n[3],
                              const double wi[3], const double wo[3], double rgb[3])
{
    const material_ops *o = m->method->mat;
    (o->eval_preview ? o->eval_preview : o->eval)(m->data, uv, n, wi, wo, rgb);
}

int material_spatial(const material *m)
{
    return m && m->method && m->method->mat->spatial;
}

json_t *material_summary(const material *m)
{
    return m->method->mat->summary ? m->method->mat->summary(m->data) : json_object();
}

int material_gpu_get(const material *m, material_gpu *out, glint_err *err)
{
    memset(out, 0, sizeof *out);
    if (!m->method || !m->data)
        return glint_err_set(err, GLINT_EINVAL, "empty material");
    if (!m->method->mat->gpu)
        return glint_err_set(err, GLINT_EUNSUPPORTED, "method %s has no GPU evaluation",
                             m->method->name);
    return m->method->mat->gpu(m->data, out, err);
}

/* Shade one G-buffer pixel range [p0, p1) into out (RGB) under a light of
 * intensity INTENSITY: pi I f cos_i (scene.h's radiance). */
static void shade_pixels(const material *m, const gbuf *g, size_t p0, size_t p1,
                         double intensity, float background, float *out)
{
    double gain = GLINT_LIGHT_UNIT * intensity;
    void (*eval)(const void *, const double *, const double *, const double *,
                 const double *, double *) = m->method->mat->eval;
    for (size_t p = p0; p < p1; p++) {
        float *o = out + 3 * (p - p0);
        double n[3], wi[3], wo[3], rgb[3], uv[2] = {0.0, 0.0};
        if (!g->mask[p]) {
            o[0] = o[1] = o[2] = background;
            continue;
        }
        for (int c = 0; c < 3; c++) {
            n[c] = g->nrm[3 * p + c];
            wi[c] = g->wi[3 * p + c];
            wo[c] = g->wo[3 * p + c];
        }
        if (g->uv) {
            uv[0] = g->uv[2 * p];
            uv[1] = g->uv[2 * p + 1];
        }
        eval(m->data, g->uv ? uv : NULL, n, wi, wo, rgb);
        for (int c = 0; c < 3; c++)
            o[c] = (float)(rgb[c] * gain);
    }
}

static int check_intensity(double intensity, glint_err *err)
{
    if (!isfinite(intensity) || intensity < 0.0)
        return glint_err_set(err, GLINT_EINVAL, "light intensity %g must be finite and >= 0",
                             intensity);
    return 0;
}

int material_shade(const material *m, const gbuf *g, double intensity, float background,
                   img *out, glint_err *err)
{
    int rc;

    memset(out, 0, sizeof *out);
    if ((rc = check_intensity(intensity, err)))
        return rc;
    if (!m->method)
        return glint_err_set(err, GLINT_EINVAL, "empty material");
    if ((rc = img_alloc(out, g->width, g->height, 3, err)))
        return rc;
    shade_pixels(m, g, 0, (size_t)g->width * g->height, intensity, background, out->px);
    return 0;
}

int material_render(const material *m, const mesh *msh, const scene_view *v, int width,
                    int height, img *out, const glint_cancel *cancel, glint_err *err)
{
    int rc, band;

    memset(out, 0, sizeof *out);
    if (!m->method)
        return glint_err_set(err, GLINT_EINVAL, "empty material");
    if ((rc = check_intensity(v->light_intensity, err)))
        return rc;
    if (width < SCENE_MIN_SIZE || width > SCENE_MAX_SIZE || height < SCENE_MIN_SIZE ||
        height > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "render size %dx%d outside %d..%d", width,
                             height, SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    if ((rc = img_alloc(out, width, height, 3, err)))
        return rc;
    band = MATERIAL_RENDER_BAND_PIXELS / width;
    if (band < 1)
        band = 1;
    for (int row0 = 0; row0 < height; row0 += band) {
        int nrows = height - row0 < band ? height - row0 : band;
        gbuf g;
        rc = raster_view_rows(msh, v, width, height, row0, nrows, &g, err);
        if (rc) {
            img_free(out);
            return rc;
        }
        /* shaded in pieces of GLINT_CANCEL_WORK pixels, asking cancel between */
        for (size_t p0 = 0, np = (size_t)width * nrows; p0 < np && !rc; p0 += GLINT_CANCEL_WORK) {
            size_t p1 = np - p0 < (size_t)GLINT_CANCEL_WORK ? np : p0 + GLINT_CANCEL_WORK;
            if (glint_cancelled(cancel))
                rc = glint_cancel_err(err, "the render");
            else
                shade_pixels(m, &g, p0, p1, v->light_intensity, 0.0f,
                             out->px + (size_t)3 * width * row0 + 3 * p0);
        }
        gbuf_free(&g);
        if (rc) {
            img_free(out);
            return rc;
        }
    }
    return 0;
}

int material_error_views(const material *m, const gbuf *g, const scene_view *views,
                         int nviews, const img *truth, double *rms, double *max_abs,
                         long *count, glint_err *err)
{
    double ss = 0.0, mx = 0.0;
    long cnt = 0;

    for (int v = 0; v < nviews; v++) {
        const gbuf *gb = &g[v];
        const img *t = &truth[v];
        size_t np = (size_t)gb->width * gb->height;
        double I = GLINT_LIGHT_UNIT * (views ? views[v].light_intensity : 1.0);
        if (!t->px || t->width != gb->width || t->height != gb->height || t->channels < 1 ||
            t->channels == 2 || t->channels > 4)
            return glint_err_set(err, GLINT_EINVAL, "reference image %d does not match its view",
                                 v);
        for (size_t p = 0; p < np; p++) {
            double n[3], wi[3], wo[3], rgb[3], ci, co, uv[2] = {0.0, 0.0};
            if (!gb->mask[p])
                continue;
            if (gb->uv) {
                uv[0] = gb->uv[2 * p];
                uv[1] = gb->uv[2 * p + 1];
            }
            for (int c = 0; c < 3; c++) {
                n[c] = gb->nrm[3 * p + c];
                wi[c] = gb->wi[3 * p + c];
                wo[c] = gb->wo[3 * p + c];
            }
            ci = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
            co = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
            if (!(ci > 0.0 && co > 0.0))
                continue;
            material_eval_at(m, gb->uv ? uv : NULL, n, wi, wo, rgb);
            for (int c = 0; c < 3; c++) {
                double ref = t->px[p * t->channels + (t->channels == 1 ? 0 : c)];
                double d = rgb[c] * I - ref;
                ss += d * d;
                if (fabs(d) > mx)
                    mx = fabs(d);
            }
            cnt++;
        }
    }
    if (rms)
        *rms = cnt ? sqrt(ss / (3.0 * cnt)) : 0.0;
    if (max_abs)
        *max_abs = mx;
    if (count)
        *count = cnt;
    return 0;
}

/* The manifest without what save_files adds (NULL when out of memory or
 * the method refuses, with *err set). */
static json_t *manifest_of(const material *m, glint_err *err)
{
    json_t *root = json_object();
    if (!root) {
        glint_err_set(err, GLINT_ENOMEM, "out of memory for the material manifest");
        return NULL;
    }
    json_object_set_new(root, "format", json_string("glint-material"));
    json_object_set_new(root, "version", json_integer(1));
    json_object_set_new(root, "method", json_string(m->method->name));
    if (m->method->mat->to_json(m->data, root, err)) {
        json_decref(root);
        return NULL;
    }
    json_object_set_new(root, "info", json_deep_copy(m->info ? m->info : json_object()));
    return root;
}

/* material_save, material_save_deferred: `defer` leaves the method's
 * derived files unwritten. */
static int save(const material *m, const char *dir, int defer, glint_err *err)
{
    char path[4096];
    json_t *root = NULL;
    char *text = NULL;
    fsio_group grp;
    int rc;

    if (!m->method)
        return glint_err_set(err, GLINT_EINVAL, "empty material");
    if ((rc = fsio_mkdirs(dir, err)))
        return rc;
    if (!(root = manifest_of(m, err)))
        return err && err->code ? err->code : GLINT_ENOMEM;
    defer = defer && m->method->mat->derived_files;
    /* the files are made durable together, at the end (fsio.h) */
    fsio_group_begin(&grp);
    if (m->method->mat->save_files &&
        (rc = m->method->mat->save_files(m->data, defer ? NULL : dir, root, err)))
        goto done;
    text = json_text(root, 1);
    if (!text) {
        rc = glint_err_set(err, GLINT_ENOMEM, "cannot serialize the material manifest");
        goto done;
    }
    if ((rc = fsio_join(path, sizeof path, dir, "material.json", err)))
        goto done;
    rc = fsio_write_atomic(path, text, strlen(text), err);
done:
    {
        glint_err gerr;
        int grc = fsio_group_end(&grp, &gerr);
        if (!rc && grc) {
            rc = grc;
            if (err)
                *err = gerr;
        }
    }
    free(text);
    json_decref(root);
    return rc;
}

int material_save(const material *m, const char *dir, glint_err *err)
{
    return save(m, dir, 0, err);
}

int material_save_deferred(const material *m, const char *dir, glint_err *err)
{
    return save(m, dir, 1, err);
}

/* 1 when dir/name is there (a regular file), 0 when it is not, minus an
 * errno value when it cannot be told or is something else. */
static int file_there(const char *dir, const char *name)
{
    char path[4096];
    struct stat st;
    if (fsio_join(path, sizeof path, dir, name, NULL))
        return -ENAMETOOLONG;
    if (stat(path, &st) == 0)
        return S_ISREG(st.st_mode) ? 1 : -EISDIR;
    return errno == ENOENT ? 0 : -errno;
}

int material_files_ensure(const char *dir, int *written, glint_err *err)
{
    material m;
    json_t *root = NULL;
    fsio_group grp;
    int rc, missing = 0;

    if (written)
        *written = 0;
    if ((rc = material_load(dir, &m, err)))
        return rc;
    if (!m.method->mat->derived_files || !m.method->mat->save_files) {
        material_free(&m);
        return 0;
    }
    for (const char *const *f = m.method->mat->derived_files; *f; f++) {
        int there = file_there(dir, *f);
        if (there < 0) {
            material_free(&m);
            return glint_err_set(err, GLINT_EIO, "%s/%s: %s", dir, *f,
                                 there == -EISDIR ? "not a regular file" : strerror(-there));
        }
        missing += !there;
    }
    if (!missing) {
        material_free(&m);
        return 0;
    }
    /* written again in full: the manifest made here is thrown away (the one
     * on disk already holds what save_files adds) */
    if (!(root = manifest_of(&m, err))) {
        material_free(&m);
        return err && err->code ? err->code : GLINT_ENOMEM;
    }
    fsio_group_begin(&grp);
    rc = m.method->mat->save_files(m.data, dir, root, err);
    {
        glint_err gerr;
        int grc = fsio_group_end(&grp, &gerr);
        if (!rc && grc) {
            rc = grc;
            if (err)
                *err = gerr;
        }
    }
    if (!rc && written)
        *written = missing;
    json_decref(root);
    material_free(&m);
    return rc;
}

int material_load(const char *path, material *out, glint_err *err)
{
    char file[4096], *text = NULL;
    size_t len, plen = strlen(path);
    json_t *root = NULL, *v;
    json_error_t jerr;
    const method *meth;
    void *data = NULL;
    int rc;

    memset(out, 0, sizeof *out);
    if (plen > 5 && strcmp(path + plen - 5, ".json") == 0)
        snprintf(file, sizeof file, "%s", path);
    else if ((rc = fsio_join(file, sizeof file, path, "material.json", err)))
        return rc;
    rc = fsio_read_all(file, MATERIAL_JSON_MAX, &text, &len, err);
    if (rc)
        return rc;
    root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    free(text);
    if (!root)
        return glint_err_set(err, GLINT_EFORMAT, "%s: line %d: %s", file, jerr.line, jerr.text);
    rc = GLINT_EFORMAT;
    if (!json_is_object(root) || !json_is_string(json_object_get(root, "format")) ||
        strcmp(json_string_value(json_object_get(root, "format")), "glint-material") != 0) {
        glint_err_set(err, rc, "%s is not a glint material (format != glint-material)", file);
        goto fail;
    }
    v = json_object_get(root, "version");
    if (!json_is_integer(v) || json_integer_value(v) != 1) {
        glint_err_set(err, rc, "%s: unsupported material version", file);
        goto fail;
    }
    v = json_object_get(root, "method");
    meth = json_is_string(v) ? method_find(json_string_value(v)) : NULL;
    if (!meth) {
        char names[256];
        method_names(names, sizeof names);
        glint_err_set(err, rc, "%s: unsupported method (this glint knows %s)", file, names);
        goto fail;
    }
    if (!meth->mat) {
        glint_err_set(err, rc, "%s: method %s makes no materials of its own", file, meth->name);
        goto fail;
    }
    if ((rc = meth->mat->from_json(root, file, &data, err)))
        goto fail;
    v = json_object_get(root, "info");
    material_init(out, meth, data, json_is_object(v) ? json_incref(v) : NULL);
    json_decref(root);
    return 0;
fail:
    json_decref(root);
    return rc;
}

void material_envlit(const void *ctx, const double uv[2], const double n[3],
                     const double wi[3], const double wo[3], double rgb[3])
{
    material_eval_at(ctx, uv, n, wi, wo, rgb);
}

void material_envlit_preview(const void *ctx, const double uv[2], const double n[3],
                             const double wi[3], const double wo[3], double rgb[3])
{
    material_eval_preview_at(ctx, uv, n, wi, wo, rgb);
}
