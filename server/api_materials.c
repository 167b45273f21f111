/* api_materials.c: materials, their files, previews and evaluation
 * (proto/openapi.yaml, section "fits, jobs, materials, methods").
 *
 *   GET  /api/v1/materials/{id}            the material object
 *   GET  /api/v1/materials/{id}/factors.png|factors.exr   (files of methods that have them)
 *   GET  /api/v1/materials/{id}/coefficients.png|.exr     (material maps' textures)
 *   GET  /api/v1/materials/{id}/spatial.png|.exr          (spatial factors: hf4, hybrid)
 *   GET  /api/v1/materials/{id}/shader     GLSL sources + binding manifest (JSON)
 *   GET  /api/v1/materials/{id}/shader/{file}
 *   GET  /api/v1/materials/{id}/package    tar of every file of the material and its shader
 *   GET  /api/v1/materials/{id}/preview.png|preview.exr   (object=ball: the material ball)
 *   POST /api/v1/materials/{id}/eval       BRDF values at direction pairs
 *   GET  /api/v1/materials/{id}/summary    base colour, highlight, albedo, polar data
 *   (exports for other tools: api_exports.c)
 *
 * A material's files are blobs "materials/<id>/": material.json and what
 * its method writes (material_save), written before its row is committed.
 * A fit writes material.json alone (material_save_deferred); the files its
 * method derives from it (hf3: factors.exr, factors.png) are written on
 * first read (files_ensure), durable before they are answered.
 * The shader export (shader/, render_export_shader) is a pure function of the
 * material and is written on first use (GET shader, shader files,
 * package).  Reading needs the token of the material's session.  A preview's
 * time is estimated before it starts (render_material_cost, refused beyond
 * glintd --work-max-seconds) and it stops when its client goes away
 * (api_cancel_init). */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "admit.h"
#include "api_common.h"
#include "app.h"
#include "buf.h"
#include "cancel.h"
#include "fitsvc.h"
#include "material.h"
#include "readable.h"
#include "prep.h"
#include "render.h"
#include "store.h"

#define EVAL_MAX_PAIRS 65536
#define PREVIEW_MAX SCENE_MAX_SIZE
#define PREVIEW_DEFAULT 512

static http_resp material_get(http_req *req)
{
    memo_doc doc;
    glint_err e;
    if (api_material(req, req->param[0], &doc, &e))
        return api_error(&e);
    return http_bytes_owned(200, "application/json", doc.text, doc.len);
}

static http_resp blob_resp(app *a, const char *mid, const char *file, const char *ctype)
{
    char name[256];
    void *data = NULL;
    size_t len = 0;
    glint_err e;
    int rc;
    snprintf(name, sizeof name, "materials/%s/%s", mid, file);
    if ((rc = store_blob_get(a->store, name, &data, &len, &e)))
        return rc == GLINT_ENOTFOUND
                   ? http_problem(404, "not-found", "material %s has no file %s", mid, file)
                   : api_error(&e);
    return http_bytes_owned(200, ctype, data, len);
}

static pthread_mutex_t files_lock = PTHREAD_MUTEX_INITIALIZER;

/* Write the material's derived files if they are not there yet: a fit
 * saves material.json alone (material_save_deferred), and its method's
 * other files follow from it.  One writer at a time, so two first reads
 * do not both encode them. */
static int files_ensure(app *a, const char *mid, glint_err *e)
{
    char name[128], dir[4096];
    int rc;
    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(a->store, name, dir, sizeof dir, e)))
        return rc;
    pthread_mutex_lock(&files_lock);
    rc = material_files_ensure(dir, NULL, e);
    pthread_mutex_unlock(&files_lock);
    if (rc == GLINT_EFORMAT)
        return glint_err_set(e, GLINT_EINTERNAL, "material %s: %.400s", mid, e->msg);
    return rc;
}

/* Whether the blob "materials/<mid>/<file>" is there (an error counts as
 * there: reading it reports the error). */
static int blob_there(app *a, const char *mid, const char *file)
{
    char name[256], path[4096];
    struct stat st;
    snprintf(name, sizeof name, "materials/%s/%s", mid, file);
    if (store_blob_path(a->store, name, path, sizeof path, NULL))
        return 1;
    return stat(path, &st) == 0 || errno != ENOENT;
}

static http_resp material_file(http_req *req, const char *file, const char *ctype)
{
    memo_doc doc;
    glint_err e;
    if (api_material(req, req->param[0], &doc, &e))
        return api_error(&e);
    free(doc.text);
    /* not written yet (or not a file of this method: still 404 after) */
    if (!blob_there(req->app, req->param[0], file) && files_ensure(req->app, req->param[0], &e))
        return api_error(&e);
    return blob_resp(req->app, req->param[0], file, ctype);
}

static http_resp factors_png(http_req *req)
{
    return material_file(req, "factors.png", "image/png");
}

static http_resp factors_exr(http_req *req)
{
    return material_file(req, "factors.exr", "image/x-exr");
}

/* the coefficient textures of a material map (method maps) */
static http_resp coefficients_png(http_req *req)
{
    return material_file(req, "coefficients.png", "image/png");
}

static http_resp spatial_png(http_req *req)
{
    return material_file(req, "spatial.png", "image/png");
}

static http_resp spatial_exr(http_req *req)
{
    return material_file(req, "spatial.exr", "image/x-exr");
}

static http_resp coefficients_exr(http_req *req)
{
    return material_file(req, "coefficients.exr", "image/x-exr");
}

static http_resp manifest_get(http_req *req)
{
    return material_file(req, "material.json", "application/json");
}

static const char *ctype_of(const char *name)
{
    const char *dot = strrchr(name, '.');
    if (!dot)
        return "application/octet-stream";
    if (!strcmp(dot, ".json"))
        return "application/json";
    if (!strcmp(dot, ".vert") || !strcmp(dot, ".frag"))
        return "text/plain; charset=utf-8";
    if (!strcmp(dot, ".exr"))
        return "image/x-exr";
    if (!strcmp(dot, ".png"))
        return "image/png";
    return "application/octet-stream";
}

/* ---- shader export -------------------------------------------------------------------- */

static pthread_mutex_t export_lock = PTHREAD_MUTEX_INITIALIZER;

int api_material_read(http_req *req, const char *mid, material *m, glint_err *e)
{
    memo_doc doc;
    int rc;
    memset(m, 0, sizeof *m);
    if ((rc = api_material(req, mid, &doc, e)))
        return rc;
    free(doc.text);
    return api_material_load(req->app, mid, m, e);
}

/* Load a stored material (OUT: *m, material_free). */
int api_material_load(app *a, const char *mid, material *m, glint_err *e)
{
    char name[128], dir[4096];
    int rc;
    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(a->store, name, dir, sizeof dir, e)) ||
        (rc = material_load(dir, m, e)))
        return rc == GLINT_EFORMAT ? glint_err_set(e, GLINT_EINTERNAL, "material %s: %.400s",
                                                   mid, e->msg)
                                   : rc;
    return 0;
}

/* Write the material's shader export if it is not there yet (shader.json
 * is written last, so its presence means the export is complete). */
static int shader_ensure(app *a, const char *mid, glint_err *e)
{
    char name[128], dir[4096], path[4200];
    material m;
    FILE *f;
    int rc;

    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(a->store, name, dir, sizeof dir, e)))
        return rc;
    snprintf(path, sizeof path, "%s/shader/shader.json", dir);
    pthread_mutex_lock(&export_lock);
    if ((f = fopen(path, "rb"))) {
        fclose(f);
        pthread_mutex_unlock(&export_lock);
        return 0;
    }
    if ((rc = api_material_load(a, mid, &m, e)) == 0) {
        snprintf(path, sizeof path, "%s/shader", dir);
        rc = render_export_shader(&m, path, e);
        material_free(&m);
    }
    pthread_mutex_unlock(&export_lock);
    return rc;
}

static int blob_text(app *a, const char *mid, const char *file, char **text, glint_err *e)
{
    char name[256];
    void *data = NULL;
    size_t len = 0;
    int rc;
    snprintf(name, sizeof name, "materials/%s/%s", mid, file);
    *text = NULL;
    if ((rc = store_blob_get(a->store, name, &data, &len, e)))
        return rc;
    *text = data; /* NUL-terminated by store_blob_get */
    return 0;
}

static http_resp shader_get(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0];
    json_t *manifest = NULL, *files = NULL, *names = NULL, *nm;
    char *man = NULL, *vert = NULL, *frag = NULL, name[128], href[200];
    memo_doc doc;
    http_resp r;
    glint_err e;
    size_t i;
    int rc;

    if ((rc = api_material(req, mid, &doc, &e)))
        return api_error(&e);
    free(doc.text);
    snprintf(name, sizeof name, "materials/%s/shader", mid);
    if ((rc = shader_ensure(a, mid, &e)) ||
        (rc = blob_text(a, mid, "shader/shader.json", &man, &e)) ||
        (rc = blob_text(a, mid, "shader/glint_material.vert", &vert, &e)) ||
        (rc = blob_text(a, mid, "shader/glint_material.frag", &frag, &e)) ||
        (rc = store_blob_list(a->store, name, &names, &e)))
        goto done;
    if (!(manifest = json_loads(man, 0, NULL))) {
        rc = glint_err_set(&e, GLINT_EINTERNAL, "material %s: unreadable shader manifest", mid);
        goto done;
    }
    files = json_object();
    json_array_foreach(names, i, nm) {
        snprintf(href, sizeof href, "/api/v1/materials/%s/shader/%s", mid,
                 json_string_value(nm));
        json_object_set_new(files, json_string_value(nm), json_string(href));
    }
    r = http_json(200, json_pack("{s:s, s:s, s:s, s:o, s:o}", "language", "GLSL ES 3.00",
                                 "vertex", vert, "fragment", frag, "manifest", manifest, "files",
                                 files));
done:
    if (rc)
        r = api_error(&e);
    json_decref(names);
    free(man);
    free(vert);
    free(frag);
    return r;
}

static http_resp shader_file(http_req *req)
{
    const char *file = req->param[1];
    char path[160];
    memo_doc doc;
    glint_err e;

    if (!*file || strlen(file) > 64 || strchr(file, '/') || file[0] == '.')
        return http_problem(404, "not-found", "a shader export has no file %.64s", file);
    if (api_material(req, req->param[0], &doc, &e))
        return api_error(&e);
    free(doc.text);
    if (shader_ensure(req->app, req->param[0], &e))
        return api_error(&e);
    snprintf(path, sizeof path, "shader/%s", file);
    return blob_resp(req->app, req->param[0], path, ctype_of(file));
}

/* ---- package: an uncompressed POSIX ustar archive --------------------------------------- */

/* Append one regular file to a tar image in memory. */
static int tar_add(glint_buf *t, const char *name, const void *data, size_t len, time_t mtime)
{
    unsigned char h[512];
    unsigned sum = 0;
    static const unsigned char zero[512];

    memset(h, 0, sizeof h);
    memcpy(h, name, strnlen(name, 99)); /* callers keep names under 100 bytes */
    snprintf((char *)h + 100, 8, "%07o", 0644);
    snprintf((char *)h + 108, 8, "%07o", 0);
    snprintf((char *)h + 116, 8, "%07o", 0);
    snprintf((char *)h + 124, 12, "%011llo", (unsigned long long)len);
    snprintf((char *)h + 136, 12, "%011llo", (unsigned long long)mtime);
    memset(h + 148, ' ', 8); /* the checksum counts its own field as spaces */
    h[156] = '0';
    memcpy(h + 257, "ustar", 6);
    memcpy(h + 263, "00", 2);
    snprintf((char *)h + 265, 32, "glint");
    snprintf((char *)h + 297, 32, "glint");
    for (int i = 0; i < 512; i++)
        sum += h[i];
    snprintf((char *)h + 148, 8, "%06o", sum);
    h[155] = ' ';
    if (glint_buf_append(t, h, 512) || glint_buf_append(t, data, len) ||
        (len % 512 && glint_buf_append(t, zero, 512 - len % 512)))
        return GLINT_ENOMEM;
    return 0;
}

/* Add every file of the blob directory "materials/<mid>/<sub>" (sub "" or
 * "shader"); material.json first. */
static int tar_dir(app *a, glint_buf *t, const char *mid, const char *sub, time_t now,
                   glint_err *e)
{
    char dir[160], name[300], path[200];
    json_t *names = NULL, *nm;
    size_t i;
    int rc;

    snprintf(dir, sizeof dir, "materials/%s%s%s", mid, *sub ? "/" : "", sub);
    if ((rc = store_blob_list(a->store, dir, &names, e)))
        return rc;
    for (int pass = 0; pass < 2 && !rc; pass++)
        json_array_foreach(names, i, nm) {
            const char *f = json_string_value(nm);
            void *data = NULL;
            size_t len = 0;
            if ((pass == 0) != (strcmp(f, "material.json") == 0))
                continue;
            snprintf(path, sizeof path, "%s%s%s", sub, *sub ? "/" : "", f);
            snprintf(name, sizeof name, "materials/%s/%s", mid, path);
            if ((rc = store_blob_get(a->store, name, &data, &len, e)))
                break;
            snprintf(name, sizeof name, "glint-material-%.8s/%s", mid, path);
            rc = tar_add(t, name, data, len, now);
            free(data);
            if (rc) {
                glint_err_set(e, rc, "out of memory for the package");
                break;
            }
        }
    json_decref(names);
    return rc;
}

static http_resp package_get(http_req *req)
{
    app *a = req->app;
    const char *mid = req->param[0];
    static const unsigned char zero[1024];
    glint_buf t = {0};
    char disp[128], scene_id[33], *mem;
    size_t len;
    time_t now = time(NULL);
    memo_doc doc;
    http_resp r;
    glint_err e;

    if (api_material(req, mid, &doc, &e))
        return api_error(&e);
    free(doc.text);
    memcpy(scene_id, doc.scene, sizeof scene_id);
    if (files_ensure(a, mid, &e) || shader_ensure(a, mid, &e) ||
        tar_dir(a, &t, mid, "", now, &e) ||
        tar_dir(a, &t, mid, "shader", now, &e)) {
        glint_buf_free(&t);
        return api_error(&e);
    }
    if (glint_buf_append(&t, zero, sizeof zero) || !(mem = glint_buf_steal(&t, &len))) {
        glint_buf_free(&t);
        return http_problem(503, "out-of-memory", "out of memory");
    }
    r = http_bytes_owned(200, "application/x-tar", mem, len);
    api_export_filename(a, mid, scene_id, "tar", disp, sizeof disp);
    api_attachment(&r, disp);
    return r;
}

/* ---- preview ------------------------------------------------------------------------------- */

static int parse_num(const char *s, double lo, double hi, double *out)
{
    char *end;
    double v = strtod(s, &end);
    if (end == s || *end || !isfinite(v) || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

/* The camera, engine and size of a preview request. */
static int preview_args(http_req *req, const scene *sc, int has_env, render_engine *eng,
                        scene_view *v, int *w, int *h, glint_err *e)
{
    const char *q_view = http_query(req, "view"), *q_eye = http_query(req, "eye"),
               *q_light = http_query(req, "light"), *q_target = http_query(req, "target"),
               *q_fov = http_query(req, "fov"), *q_size = http_query(req, "size"),
               *q_int = http_query(req, "intensity"), *q_rend = http_query(req, "renderer");
    render_camera c;
    double x;
    int size = 0;

    render_camera_init(&c);
    *eng = RENDER_AUTO;
    if (q_rend && render_engine_parse(q_rend, eng, NULL))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "renderer must be auto, egl or cpu");
    if (q_size) {
        if (parse_num(q_size, SCENE_MIN_SIZE, PREVIEW_MAX, &x) || x != floor(x))
            return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                              "size must be an integer in %d..%d", SCENE_MIN_SIZE, PREVIEW_MAX);
        size = (int)x;
    }
    if (!q_view && !(q_eye && (q_light || has_env)))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          has_env ? "a preview needs view=K, or eye=x,y,z"
                                  : "a preview needs view=K, or eye=x,y,z and light=x,y,z");
    if (q_view) {
        if (parse_num(q_view, 0, sc->nviews - 1, &x) || x != floor(x))
            return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                              "view must be an integer in 0..%d (the scene has %d views)",
                              sc->nviews - 1, sc->nviews);
        c.view = (int)x;
    }
    if (q_eye && render_parse_vec3(q_eye, c.eye))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "eye must be x,y,z (finite numbers)");
    if (q_light && render_parse_vec3(q_light, c.light))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "light must be x,y,z (finite numbers)");
    if (q_target && render_parse_vec3(q_target, c.target))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "target must be x,y,z (finite numbers)");
    c.has_eye = q_eye != NULL;
    c.has_light = q_light != NULL;
    if (has_env && q_eye && !q_light) { /* the environment lights it: any light will do */
        memcpy(c.light, c.eye, sizeof c.light);
        c.has_light = 1;
    }
    c.has_target = q_target != NULL;
    if (q_fov && parse_num(q_fov, 1.0, 170.0, &c.fov_deg))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "fov must be a vertical field of view in degrees, 1..170");
    if (q_int && parse_num(q_int, 0.0, 1e6, &c.intensity))
        return api_reject(e, GLINT_EINVAL, "invalid-parameter", "intensity must be in [0, 1e6]");
    if (!q_int && !q_view)
        c.intensity = 1.0;
    if (render_camera_view(sc, &c, v, e))
        return glint_err_kind(e, "invalid-parameter");
    if (!size)
        size = q_view && !q_eye ? (sc->width > sc->height ? sc->width : sc->height)
                                : PREVIEW_DEFAULT;
    /* a view keeps the scene's aspect (size is the longer side); a free
     * camera renders a square */
    *w = *h = size;
    if (q_view && !q_eye && sc->width != sc->height) {
        if (sc->width > sc->height)
            *h = (int)lround((double)size * sc->height / sc->width);
        else
            *w = (int)lround((double)size * sc->width / sc->height);
        if (*w < SCENE_MIN_SIZE)
            *w = SCENE_MIN_SIZE;
        if (*h < SCENE_MIN_SIZE)
            *h = SCENE_MIN_SIZE;
    }
    return 0;
}

static http_resp preview(http_req *req, const char *format)
{
    app *a = req->app;
    const char *mid = req->param[0];
    cache_entry *se = NULL;
    const scene *sc;
    const mesh *msh;
    const char *mkey, *q_obj;
    render_engine eng;
    render_used used;
    render_env env;
    render_env_info info;
    int has_env = 0;
    material m = {0};
    memo_doc doc = {{0}, {0}, NULL, 0};
    scene_view v;
    img im = {0};
    void *data = NULL;
    size_t len = 0;
    http_resp r;
    glint_err e;
    int w = 0, h = 0, rc;
    size_t bytes = 0;
    char what[64];
    glint_cancel cancel;
    admit_ticket ticket = {0};

    api_cancel_init(req, &cancel);
    if ((rc = api_material(req, mid, &doc, &e)))
        goto done;
    if ((rc = fitsvc_scene(a->fits, doc.scene, &se, &e))) {
        if (rc == GLINT_ENOTFOUND)
            api_reject(&e, rc, "scene-gone", "the material's scene no longer exists");
        goto done;
    }
    sc = prep_scene_of(se)->sc;
    msh = &sc->mesh;
    mkey = doc.scene;
    if ((q_obj = http_query(req, "object")) && strcmp(q_obj, "scene")) {
        /* the material ball: the scenes' views frame the unit ball, so
         * every camera of the scene frames it too */
        if (strcmp(q_obj, "ball")) {
            rc = api_reject(&e, GLINT_EINVAL, "invalid-parameter", "object must be scene or ball");
            goto done;
        }
        if ((rc = render_ball(&msh, &e)))
            goto done;
        mkey = RENDER_BALL_KEY;
    }
    if ((rc = api_env_query(req, &env, &has_env, &e)) ||
        (rc = preview_args(req, sc, has_env, &eng, &v, &w, &h, &e)))
        goto done;
    /* under an environment the CPU reference holds a G-buffer and shadow
     * bits per pixel (VIS_WORDS(lights) words) */
    bytes = has_env ? render_peak_bytes(eng, 1, w, h) +
                          (size_t)w * h * 8 * (size_t)((env.lights + 63) / 64)
                    : render_peak_bytes(eng, 0, w, h);
    snprintf(what, sizeof what, "a %dx%d preview", w, h);
    /* its time is estimated before it takes a slot: refused up front when
     * beyond the limit, and cancelled when the client leaves */
    api_work_ticket(req, bytes, 0, &ticket);
    if ((rc = api_material_load(a, mid, &m, &e)) ||
        (rc = admit_cost(a->work,
                         render_material_cost(a->render, eng, mkey, msh, &m, has_env ? &env : NULL,
                                              w, h),
                         what, &e)) ||
        (rc = admit_take(a->work, &ticket, what, 0, &e)))
        goto done;
    rc = has_env ? render_material_env(a->render, eng, mkey, msh, &m, &env, &v, w, h, &im, &info,
                                       &used, &cancel, &e)
                 : render_material(a->render, eng, mkey, msh, &m, &v, w, h, &im, &used, &cancel,
                                   &e);
    api_work_ended(req, rc);
    if (rc) {
        if (rc == GLINT_EUNSUPPORTED && eng == RENDER_EGL)
            glint_err_kind(&e, "egl-unavailable");
        goto done;
    }
    if ((rc = img_write_mem(format, &im, &data, &len, &e)))
        goto done;
    r = http_bytes_owned(200, strcmp(format, "png") == 0 ? "image/png" : "image/x-exr", data,
                         len);
    http_header(&r, "X-Glint-Renderer", used.engine);
    if (has_env)
        api_env_header(&r, &info);
done:
    if (rc)
        r = api_error(&e);
    img_free(&im);
    admit_give(a->work, &ticket);
    material_free(&m);
    cache_release(a->cache, se);
    free(doc.text);
    return r;
}

static http_resp preview_png(http_req *req)
{
    return preview(req, "png");
}

static http_resp preview_exr(http_req *req)
{
    return preview(req, "exr");
}

/* ---- eval ------------------------------------------------------------------------------------ */

/* A unit vector from a JSON array of 3 finite numbers, not all zero (any
 * length: scaled by its largest entry first, so nothing overflows). */
static int unit_vec(const json_t *a, double v[3])
{
    double n = 0.0, mx = 0.0;
    if (!json_is_array(a) || json_array_size(a) != 3)
        return -1;
    for (int i = 0; i < 3; i++) {
        json_t *x = json_array_get(a, (size_t)i);
        if (!json_is_number(x) || !isfinite(json_number_value(x)))
            return -1;
        v[i] = json_number_value(x);
        if (fabs(v[i]) > mx)
            mx = fabs(v[i]);
    }
    if (!(mx > 0.0))
        return -2;
    for (int i = 0; i < 3; i++) {
        v[i] /= mx;
        n += v[i] * v[i];
    }
    n = sqrt(n);
    for (int i = 0; i < 3; i++)
        v[i] /= n;
    return 0;
}

/* Evaluate the pairs of an eval body.  OUT: *values. */
static int eval_pairs(app *a, const char *mid, const json_t *body, json_t **values,
                      glint_err *e)
{
    static const char *const names[3] = {"n", "wi", "wo"};
    json_t *pairs, *p, *x;
    material m = {0};
    const char *k;
    size_t i;
    int rc;

    *values = NULL;
    json_object_foreach((json_t *)body, k, x) {
        if (strcmp(k, "pairs") != 0)
            return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                              "unknown member '%.64s' (eval takes \"pairs\")", k);
    }
    pairs = json_object_get(body, "pairs");
    if (!json_is_array(pairs) || json_array_size(pairs) == 0)
        return api_reject(e, GLINT_EINVAL, "invalid-parameter",
                          "pairs must be a non-empty array of {\"n\", \"wi\", \"wo\"}");
    if (json_array_size(pairs) > EVAL_MAX_PAIRS)
        return api_reject(e, GLINT_ETOOBIG, "too-many-pairs",
                          "%zu pairs exceed the limit of %d per request", json_array_size(pairs),
                          EVAL_MAX_PAIRS);
    if ((rc = api_material_load(a, mid, &m, e)))
        return rc;
    *values = json_array();
    json_array_foreach(pairs, i, p) {
        double d[3][3], rgb[3], uv[2];
        json_t *juv = json_object_get(p, "uv");
        if (!json_is_object(p) || json_object_size(p) != (juv ? 4u : 3u)) {
            rc = api_reject(e, GLINT_EINVAL, "invalid-parameter",
                            "pairs[%zu] must be an object with exactly n, wi and wo, and "
                            "optionally uv", i);
            break;
        }
        if (juv) { /* texture coordinates in [0, 1]^2 */
            for (int j = 0; j < 2; j++) {
                json_t *ux = json_array_get(juv, (size_t)j);
                uv[j] = json_is_number(ux) ? json_number_value(ux) : NAN;
            }
            if (!json_is_array(juv) || json_array_size(juv) != 2 || !(uv[0] >= 0.0) ||
                !(uv[0] <= 1.0) || !(uv[1] >= 0.0) || !(uv[1] <= 1.0)) {
                rc = api_reject(e, GLINT_EINVAL, "invalid-parameter",
                                "pairs[%zu].uv must be [u, v] with both in [0, 1]", i);
                break;
            }
        }
        for (int j = 0; j < 3 && !rc; j++) {
            int u = unit_vec(json_object_get(p, names[j]), d[j]);
            if (u == -2)
                rc = api_reject(e, GLINT_EINVAL, "invalid-parameter",
                                "pairs[%zu].%s must not be a zero vector", i, names[j]);
            else if (u)
                rc = api_reject(e, GLINT_EINVAL, "invalid-parameter",
                                "pairs[%zu].%s must be an array of 3 finite numbers", i,
                                names[j]);
        }
        if (rc)
            break;
        material_eval_at(&m, juv ? uv : NULL, d[0], d[1], d[2], rgb);
        json_array_append_new(*values, json_pack("[f, f, f]", rgb[0], rgb[1], rgb[2]));
    }
    material_free(&m);
    if (rc) {
        json_decref(*values);
        *values = NULL;
    }
    return rc;
}

static http_resp eval_post(http_req *req)
{
    json_t *body = NULL, *values = NULL;
    memo_doc doc;
    glint_err e;
    int rc;

    if ((rc = api_material(req, req->param[0], &doc, &e)))
        return api_error(&e);
    free(doc.text);
    if ((rc = api_body_json(req, &body, &e)) ||
        (rc = eval_pairs(req->app, req->param[0], body, &values, &e))) {
        json_decref(body);
        return api_error(&e);
    }
    json_decref(body);
    return http_json(200, json_pack("{s:o}", "values", values));
}

/* ---- summary -------------------------------------------------------------------------------- */

/* GET /api/v1/materials/{id}/summary: the material in numbers (readable.h). */
static http_resp summary_get(http_req *req)
{
    material m = {0};
    json_t *o = NULL;
    glint_err e;
    int rc;

    if ((rc = api_material_read(req, req->param[0], &m, &e)))
        return api_error(&e);
    rc = material_readable(&m, &o, &e);
    material_free(&m);
    if (rc)
        return api_error(&e);
    return http_json(200, o);
}

const http_route api_materials_routes[] = {
    {"GET", "/api/v1/materials/{id}", material_get},
    {"GET", "/api/v1/materials/{id}/factors.png", factors_png},
    {"GET", "/api/v1/materials/{id}/factors.exr", factors_exr},
    {"GET", "/api/v1/materials/{id}/coefficients.png", coefficients_png},
    {"GET", "/api/v1/materials/{id}/coefficients.exr", coefficients_exr},
    {"GET", "/api/v1/materials/{id}/spatial.png", spatial_png},
    {"GET", "/api/v1/materials/{id}/spatial.exr", spatial_exr},
    {"GET", "/api/v1/materials/{id}/material.json", manifest_get},
    {"GET", "/api/v1/materials/{id}/shader", shader_get},
    {"GET", "/api/v1/materials/{id}/shader/{file}", shader_file},
    {"GET", "/api/v1/materials/{id}/package", package_get},
    {"GET", "/api/v1/materials/{id}/preview.png", preview_png},
    {"GET", "/api/v1/materials/{id}/preview.exr", preview_exr},
    {"POST", "/api/v1/materials/{id}/eval", eval_post},
    {"GET", "/api/v1/materials/{id}/summary", summary_get},
};
const int api_materials_nroutes = sizeof api_materials_routes / sizeof api_materials_routes[0];
