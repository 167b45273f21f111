/* scene.c: scenes, default icosahedral views, JSON I/O and the content hash
 * (contract and conventions in scene.h; they follow
 * ../shared/reference/hf_ref.py, section 1 "Geometry"). */
#include "scene.h"
#include "fsio.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jansson.h>
#define XXH_STATIC_LINKING_ONLY /* XXH3_state_t on the stack: no allocation */
#include <xxhash.h>

#include "vec3.h"

#define SCENE_PI 3.14159265358979323846
#define SCENE_PHI 1.61803398874989484820 /* (1 + sqrt 5) / 2 */

/* JSON document limits: a scene with SCENE_MAX_VIEWS views takes about
 * 150 KiB; anything far beyond is not a scene.  The document is 4 levels
 * deep (object, views array, view object, vector). */
#define SCENE_JSON_MAX_BYTES (16u << 20)
#define SCENE_JSON_MAX_DEPTH 16
#define SCENE_FORMAT "glint-scene"
#define SCENE_VERSION 1

/* ------------------------------------------------------------------------ */
/* Parameters, icosahedron, views                                           */
/* ------------------------------------------------------------------------ */

void scene_params_default(scene_params *p)
{
    memset(p, 0, sizeof *p);
    snprintf(p->mesh_name, sizeof p->mesh_name, "%s", "sphere");
    p->width = 128;
    p->height = 128;
    p->distance = 3.5;
    p->margin = 1.1;
    p->light_lo_deg = 20.0;
    p->light_hi_deg = 70.0;
    p->light_mid = 0;
    p->view_set = SCENE_VIEWS_ICO12;
}

void scene_icosahedron(double dirs[12][3])
{
    static const double v[12][3] = {
        {-1, SCENE_PHI, 0}, {1, SCENE_PHI, 0}, {-1, -SCENE_PHI, 0}, {1, -SCENE_PHI, 0},
        {0, -1, SCENE_PHI}, {0, 1, SCENE_PHI}, {0, -1, -SCENE_PHI}, {0, 1, -SCENE_PHI},
        {SCENE_PHI, 0, -1}, {SCENE_PHI, 0, 1}, {-SCENE_PHI, 0, -1}, {-SCENE_PHI, 0, 1}};
    for (int i = 0; i < 12; i++)
        v3_store(v3_normalize(v3_load(v[i])), dirs[i]);
}

void scene_icosahedron_faces(double dirs[20][3])
{
    double v[12][3], d[12][12], edge = INFINITY;
    int nf = 0;

    scene_icosahedron(v);
    for (int i = 0; i < 12; i++)
        for (int j = 0; j < 12; j++) {
            d[i][j] = v3_len(v3_sub(v3_load(v[i]), v3_load(v[j])));
            if (d[i][j] > 1e-9 && d[i][j] < edge)
                edge = d[i][j];
        }
    /* Faces: triples whose pairwise distances all equal the edge length,
     * enumerated in lexicographic order (i < j < k), as the reference. */
    for (int i = 0; i < 12; i++)
        for (int j = i + 1; j < 12; j++)
            for (int k = j + 1; k < 12; k++) {
                if (fabs(d[i][j] - edge) < 1e-9 && fabs(d[j][k] - edge) < 1e-9 &&
                    fabs(d[i][k] - edge) < 1e-9 && nf < 20) {
                    v3 c = v3_add(v3_add(v3_load(v[i]), v3_load(v[j])), v3_load(v[k]));
                    v3_store(v3_normalize(v3_scale(c, 1.0 / 3.0)), dirs[nf]);
                    nf++;
                }
            }
    /* An icosahedron has exactly 20 faces; the loop above cannot find more
     * (capped) or fewer (the vertices are fixed). */
}

void scene_view_frame(const scene_view *v, double fwd[3], double right[3], double up[3])
{
    v3 f = v3_normalize(v3_sub(v3_load(v->target), v3_load(v->eye)));
    v3 wu = fabs(f.z) > 0.99 ? v3_make(0, 1, 0) : v3_make(0, 0, 1);
    v3 r = v3_normalize(v3_cross(f, wu));
    v3 u = v3_cross(r, f);
    v3_store(f, fwd);
    v3_store(r, right);
    v3_store(u, up);
}

void scene_view_make(const double dir[3], double distance, double margin,
                     double light_deg, scene_view *v)
{
    double fwd[3], right[3], up[3];
    v3 d = v3_normalize(v3_load(dir));
    v3 eye = v3_scale(d, distance);

    memset(v, 0, sizeof *v);
    v3_store(eye, v->eye);
    /* target stays at the origin */
    v->half_fov = atan(margin / sqrt(distance * distance - 1.0));
    scene_view_frame(v, fwd, right, up);
    v3_store(v3_rotate(eye, v3_load(up), light_deg * SCENE_PI / 180.0), v->light);
    v->light_intensity = 1.0;
    v->light_deg = light_deg;
}

/* Per-view light angle: linspace(lo, hi, n) or the midpoints of n slots. */
static double scene_light_angle(const scene_params *p, int m, int n)
{
    double lo = p->light_lo_deg, hi = p->light_hi_deg;
    if (p->light_mid)
        return lo + (hi - lo) * (m + 0.5) / n;
    if (n == 1)
        return lo;
    return lo + (hi - lo) * m / (n - 1.0);
}

/* ------------------------------------------------------------------------ */
/* Validation                                                                */
/* ------------------------------------------------------------------------ */

static int scene_check_size(int width, int height, glint_err *err)
{
    if (width < SCENE_MIN_SIZE || width > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "width %d outside %d..%d", width,
                             SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    if (height < SCENE_MIN_SIZE || height > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "height %d outside %d..%d", height,
                             SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    return 0;
}

static int scene_vec_finite(const double a[3])
{
    return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]);
}

/* Check one view; `k` names it in the message. */
static int scene_check_view(const scene_view *v, int k, glint_err *err)
{
    v3 d;
    double len;

    if (!scene_vec_finite(v->eye))
        return glint_err_set(err, GLINT_ENONFINITE, "views[%d].eye is not finite", k);
    if (!scene_vec_finite(v->target))
        return glint_err_set(err, GLINT_ENONFINITE, "views[%d].target is not finite", k);
    if (!scene_vec_finite(v->light))
        return glint_err_set(err, GLINT_ENONFINITE, "views[%d].light is not finite", k);
    if (!isfinite(v->half_fov))
        return glint_err_set(err, GLINT_ENONFINITE, "views[%d].half_fov is not finite", k);
    if (!isfinite(v->light_intensity))
        return glint_err_set(err, GLINT_ENONFINITE, "views[%d].light_intensity is not finite",
                             k);
    if (!isfinite(v->light_deg))
        return glint_err_set(err, GLINT_ENONFINITE, "views[%d].light_deg is not finite", k);
    d = v3_sub(v3_load(v->target), v3_load(v->eye));
    len = v3_len(d);
    if (!isfinite(len))
        return glint_err_set(err, GLINT_ENONFINITE,
                             "views[%d]: eye - target overflows (eye and target too far apart)",
                             k);
    if (!(len > 0.0))
        return glint_err_set(err, GLINT_EINVAL,
                             "views[%d]: eye equals target (degenerate camera)", k);
    if (!(v->half_fov > 0.0 && v->half_fov < SCENE_PI / 2))
        return glint_err_set(err, GLINT_ERANGE,
                             "views[%d].half_fov %.17g outside (0, pi/2) radians", k,
                             v->half_fov);
    if (!(v->light_intensity > 0.0))
        return glint_err_set(err, GLINT_ERANGE, "views[%d].light_intensity %.17g must be > 0",
                             k, v->light_intensity);
    return 0;
}

int scene_validate(const scene *s, glint_err *err)
{
    int rc;

    if (!s)
        return glint_err_set(err, GLINT_EINVAL, "scene is NULL");
    if (!memchr(s->mesh_name, '\0', sizeof s->mesh_name))
        return glint_err_set(err, GLINT_EFORMAT, "scene mesh name is not terminated");
    if (!memchr(s->mesh_path, '\0', sizeof s->mesh_path))
        return glint_err_set(err, GLINT_EFORMAT, "scene mesh path is not terminated");
    rc = scene_check_size(s->width, s->height, err);
    if (rc)
        return rc;
    if (s->nviews < 1 || s->nviews > SCENE_MAX_VIEWS)
        return glint_err_set(err, GLINT_ERANGE, "view count %d outside 1..%d", s->nviews,
                             SCENE_MAX_VIEWS);
    if (!s->views)
        return glint_err_set(err, GLINT_EFORMAT, "scene has %d views but no view array",
                             s->nviews);
    for (int k = 0; k < s->nviews; k++) {
        rc = scene_check_view(&s->views[k], k, err);
        if (rc)
            return rc;
    }
    rc = mesh_validate(&s->mesh, err);
    if (rc)
        return glint_err_prefix(err, "scene mesh \"%s\"", s->mesh_name);
    return 0;
}

void scene_free(scene *s)
{
    if (!s)
        return;
    mesh_free(&s->mesh);
    free(s->views);
    memset(s, 0, sizeof *s);
}

/* ------------------------------------------------------------------------ */
/* Creation from parameters                                                  */
/* ------------------------------------------------------------------------ */

/* Absolute form of a mesh file path (OUT: out[SCENE_PATH_MAX]): an absolute
 * path is kept as written; a relative one is joined to `base` (a directory;
 * NULL or "" for the working directory), and to the working directory if
 * `base` is itself relative.  No symbolic links are resolved and "." / ".."
 * stay as written. */
static int scene_abs_path(const char *base, const char *path, char out[SCENE_PATH_MAX],
                          glint_err *err)
{
    char cwd[SCENE_PATH_MAX];
    int n;

    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "empty mesh file path");
    if (path[0] == '/') {
        n = snprintf(out, SCENE_PATH_MAX, "%s", path);
    } else if (base && base[0] == '/') {
        n = snprintf(out, SCENE_PATH_MAX, "%s/%s", base, path);
    } else {
        if (!getcwd(cwd, sizeof cwd))
            return glint_err_set(err, errno == ERANGE ? GLINT_ERANGE : GLINT_EIO,
                                 "resolving mesh file %.200s: working directory: %s", path,
                                 strerror(errno));
        if (base && *base)
            n = snprintf(out, SCENE_PATH_MAX, "%s/%s/%s", cwd, base, path);
        else
            n = snprintf(out, SCENE_PATH_MAX, "%s/%s", cwd, path);
    }
    if (n < 0 || n >= SCENE_PATH_MAX)
        return glint_err_set(err, GLINT_ERANGE,
                             "mesh file path %.200s is longer than %d bytes once made absolute",
                             path, SCENE_PATH_MAX - 1);
    return 0;
}

/* Load the scene's mesh: the file at out->mesh_path (absolute) or the
 * built-in out->mesh_name. */
static int scene_load_mesh(scene *out, glint_err *err)
{
    memset(&out->mesh_info, 0, sizeof out->mesh_info);
    if (out->mesh_path[0])
        return mesh_load(out->mesh_path, &out->mesh, &out->mesh_info, err);
    return mesh_builtin(out->mesh_name, &out->mesh, err);
}

int scene_create(const scene_params *p, scene *out, glint_err *err)
{
    double dirs[20][3];
    int n, rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "scene_create: output scene is NULL");
    memset(out, 0, sizeof *out);
    if (!p)
        return glint_err_set(err, GLINT_EINVAL, "scene_create: parameters are NULL");
    if (!memchr(p->mesh_name, '\0', sizeof p->mesh_name))
        return glint_err_set(err, GLINT_EINVAL, "mesh name is not terminated within %d bytes",
                             SCENE_NAME_MAX);
    if (!memchr(p->mesh_path, '\0', sizeof p->mesh_path))
        return glint_err_set(err, GLINT_EINVAL, "mesh path is not terminated within %d bytes",
                             SCENE_PATH_MAX);
    rc = scene_check_size(p->width, p->height, err);
    if (rc)
        return rc;
    if (!isfinite(p->distance) || !(p->distance > 1.0) || p->distance > 1e6)
        return glint_err_set(err, GLINT_ERANGE,
                             "camera distance %.17g outside (1, 1e6] (the views frame the unit "
                             "ball from outside)", p->distance);
    if (!isfinite(p->margin) || !(p->margin > 0.0) || p->margin > 1e6)
        return glint_err_set(err, GLINT_ERANGE, "margin %.17g outside (0, 1e6]", p->margin);
    if (!isfinite(p->light_lo_deg) || !isfinite(p->light_hi_deg))
        return glint_err_set(err, GLINT_ENONFINITE, "light angles %g:%g are not finite",
                             p->light_lo_deg, p->light_hi_deg);
    if (fabs(p->light_lo_deg) > 360.0 || fabs(p->light_hi_deg) > 360.0)
        return glint_err_set(err, GLINT_ERANGE, "light angles %g:%g outside [-360, 360] degrees",
                             p->light_lo_deg, p->light_hi_deg);
    if (p->view_set == SCENE_VIEWS_ICO12) {
        n = 12;
        scene_icosahedron(dirs);
    } else if (p->view_set == SCENE_VIEWS_ICO20) {
        n = 20;
        scene_icosahedron_faces(dirs);
    } else {
        return glint_err_set(err, GLINT_EINVAL,
                             "view set %d unknown (SCENE_VIEWS_ICO12 = 0, SCENE_VIEWS_ICO20 = 1)",
                             p->view_set);
    }

    if (p->mesh_path[0]) {
        const char *slash = strrchr(p->mesh_path, '/');
        const char *base = slash ? slash + 1 : p->mesh_path;
        rc = scene_abs_path(NULL, p->mesh_path, out->mesh_path, err);
        if (rc)
            goto fail;
        /* the label: the file's base name, cut to fit */
        snprintf(out->mesh_name, sizeof out->mesh_name, "%.*s", SCENE_NAME_MAX - 1,
                 *base ? base : "mesh");
    } else {
        snprintf(out->mesh_name, sizeof out->mesh_name, "%s", p->mesh_name);
    }
    out->width = p->width;
    out->height = p->height;
    rc = scene_load_mesh(out, err);
    if (rc)
        goto fail;
    out->views = calloc((size_t)n, sizeof *out->views);
    if (!out->views) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for %d views", n);
        goto fail;
    }
    out->nviews = n;
    for (int m = 0; m < n; m++)
        scene_view_make(dirs[m], p->distance, p->margin, scene_light_angle(p, m, n),
                        &out->views[m]);
    rc = scene_validate(out, err);
    if (rc)
        goto fail;
    return 0;

fail:
    scene_free(out);
    return rc;
}

/* ------------------------------------------------------------------------ */
/* JSON                                                                      */
/* ------------------------------------------------------------------------ */

static const char *scene_json_kind(const json_t *j)
{
    switch (json_typeof(j)) {
    case JSON_OBJECT: return "an object";
    case JSON_ARRAY: return "an array";
    case JSON_STRING: return "a string";
    case JSON_INTEGER: return "an integer";
    case JSON_REAL: return "a real number";
    case JSON_TRUE: return "true";
    case JSON_FALSE: return "false";
    case JSON_NULL: return "null";
    }
    return "an unknown value";
}

/* Reject keys outside `allowed` (NULL-terminated): a misspelt field would
 * otherwise be silently ignored. */
static int scene_json_keys(const json_t *obj, const char *const *allowed, const char *where,
                           glint_err *err)
{
    const char *key;
    json_t *val;

    json_object_foreach((json_t *)obj, key, val) {
        int ok = 0;
        (void)val;
        for (const char *const *a = allowed; *a; a++)
            if (strcmp(key, *a) == 0)
                ok = 1;
        if (!ok)
            return glint_err_set(err, GLINT_EFORMAT, "%s: unknown field \"%.64s\"", where,
                                 key);
    }
    return 0;
}

/* A finite number (integer or real) at obj[key].  If `required` is 0 and
 * the key is absent, *out is left alone. */
static int scene_json_number(const json_t *obj, const char *key, int required,
                             const char *where, double *out, glint_err *err)
{
    const json_t *j = json_object_get(obj, key);
    double x;

    if (!j) {
        if (!required)
            return 0;
        return glint_err_set(err, GLINT_EFORMAT, "%s.%s: missing", where, key);
    }
    if (!json_is_number(j))
        return glint_err_set(err, GLINT_EFORMAT, "%s.%s: expected a number, got %s", where,
                             key, scene_json_kind(j));
    x = json_number_value(j);
    if (!isfinite(x))
        return glint_err_set(err, GLINT_ENONFINITE, "%s.%s: not finite", where, key);
    *out = x;
    return 0;
}

static int scene_json_vec3(const json_t *obj, const char *key, const char *where,
                           double out[3], glint_err *err)
{
    const json_t *j = json_object_get(obj, key);

    if (!j)
        return glint_err_set(err, GLINT_EFORMAT, "%s.%s: missing", where, key);
    if (!json_is_array(j))
        return glint_err_set(err, GLINT_EFORMAT, "%s.%s: expected an array of 3 numbers, got %s",
                             where, key, scene_json_kind(j));
    if (json_array_size(j) != 3)
        return glint_err_set(err, GLINT_EFORMAT, "%s.%s: expected 3 numbers, got %zu", where,
                             key, json_array_size(j));
    for (size_t i = 0; i < 3; i++) {
        const json_t *e = json_array_get(j, i);
        if (!json_is_number(e))
            return glint_err_set(err, GLINT_EFORMAT, "%s.%s[%zu]: expected a number, got %s",
                                 where, key, i, scene_json_kind(e));
        out[i] = json_number_value(e);
        if (!isfinite(out[i]))
            return glint_err_set(err, GLINT_ENONFINITE, "%s.%s[%zu]: not finite", where, key,
                                 i);
    }
    return 0;
}

/* An integer at obj[key], kept as long long so that huge values are
 * reported as they are, not wrapped. */
static int scene_json_int(const json_t *obj, const char *key, long long *out,
                          glint_err *err)
{
    const json_t *j = json_object_get(obj, key);

    if (!j)
        return glint_err_set(err, GLINT_EFORMAT, "scene.%s: missing", key);
    if (!json_is_integer(j))
        return glint_err_set(err, GLINT_EFORMAT, "scene.%s: expected an integer, got %s", key,
                             scene_json_kind(j));
    *out = (long long)json_integer_value(j);
    return 0;
}

static int scene_json_view(const json_t *jv, int k, scene_view *v, glint_err *err)
{
    static const char *const keys[] = {"eye", "target", "half_fov", "light",
                                       "light_intensity", "light_deg", NULL};
    char where[32];
    int rc;

    snprintf(where, sizeof where, "views[%d]", k);
    if (!json_is_object(jv))
        return glint_err_set(err, GLINT_EFORMAT, "%s: expected an object, got %s", where,
                             scene_json_kind(jv));
    if ((rc = scene_json_keys(jv, keys, where, err)) ||
        (rc = scene_json_vec3(jv, "eye", where, v->eye, err)) ||
        (rc = scene_json_vec3(jv, "target", where, v->target, err)) ||
        (rc = scene_json_number(jv, "half_fov", 1, where, &v->half_fov, err)) ||
        (rc = scene_json_vec3(jv, "light", where, v->light, err)))
        return rc;
    v->light_intensity = 1.0;
    v->light_deg = -1.0;
    if ((rc = scene_json_number(jv, "light_intensity", 0, where, &v->light_intensity, err)) ||
        (rc = scene_json_number(jv, "light_deg", 0, where, &v->light_deg, err)))
        return rc;
    return scene_check_view(v, k, err);
}

/* Nesting depth of a JSON text (brackets outside strings), stopping as soon
 * as it exceeds `limit`: the parser recurses, so bound it before parsing. */
static int scene_json_depth_ok(const char *text, int limit)
{
    int depth = 0, in_str = 0;
    for (const char *c = text; *c; c++) {
        if (in_str) {
            if (*c == '\\' && c[1])
                c++;
            else if (*c == '"')
                in_str = 0;
        } else if (*c == '"') {
            in_str = 1;
        } else if (*c == '[' || *c == '{') {
            if (++depth > limit)
                return 0;
        } else if (*c == ']' || *c == '}') {
            depth--;
        }
    }
    return 1;
}

/* scene_from_json with relative mesh files resolved against `base_dir`
 * (NULL: the working directory). */
static int scene_from_json_at(const char *text, const char *base_dir, scene *out,
                              glint_err *err)
{
    static const char *const keys[] = {"format", "version", "mesh", "mesh_file", "width",
                                       "height", "views", NULL};
    json_error_t jerr;
    json_t *root = NULL;
    const json_t *j, *jviews;
    long long version, width, height;
    size_t nviews, len;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "scene_from_json: output scene is NULL");
    memset(out, 0, sizeof *out);
    if (!text)
        return glint_err_set(err, GLINT_EINVAL, "scene_from_json: text is NULL");
    len = strnlen(text, (size_t)SCENE_JSON_MAX_BYTES + 1);
    if (len > SCENE_JSON_MAX_BYTES)
        return glint_err_set(err, GLINT_ERANGE, "scene JSON larger than %u bytes",
                             SCENE_JSON_MAX_BYTES);
    if (!scene_json_depth_ok(text, SCENE_JSON_MAX_DEPTH))
        return glint_err_set(err, GLINT_EFORMAT, "scene JSON nested deeper than %d levels",
                             SCENE_JSON_MAX_DEPTH);
    root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    if (!root)
        return glint_err_set(err, GLINT_EFORMAT, "scene JSON: %s (line %d, column %d)",
                             jerr.text, jerr.line, jerr.column);
    if (!json_is_object(root)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene JSON: expected an object, got %s",
                           scene_json_kind(root));
        goto fail;
    }
    if ((rc = scene_json_keys(root, keys, "scene", err)))
        goto fail;

    j = json_object_get(root, "format");
    if (!j) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene.format: missing (expected \"%s\")",
                           SCENE_FORMAT);
        goto fail;
    }
    if (!json_is_string(j) || strcmp(json_string_value(j), SCENE_FORMAT) != 0) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene.format: expected \"%s\"", SCENE_FORMAT);
        goto fail;
    }
    if ((rc = scene_json_int(root, "version", &version, err)))
        goto fail;
    if (version != SCENE_VERSION) {
        rc = glint_err_set(err, GLINT_EUNSUPPORTED,
                           "scene.version %lld unsupported (this build reads version %d)",
                           version, SCENE_VERSION);
        goto fail;
    }

    j = json_object_get(root, "mesh");
    if (!j) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene.mesh: missing");
        goto fail;
    }
    if (!json_is_string(j)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene.mesh: expected a string, got %s",
                           scene_json_kind(j));
        goto fail;
    }
    if (json_string_length(j) >= SCENE_NAME_MAX) {
        rc = glint_err_set(err, GLINT_ERANGE, "scene.mesh: name longer than %d bytes",
                           SCENE_NAME_MAX - 1);
        goto fail;
    }
    snprintf(out->mesh_name, sizeof out->mesh_name, "%s", json_string_value(j));

    j = json_object_get(root, "mesh_file");
    if (j) {
        if (!json_is_string(j)) {
            rc = glint_err_set(err, GLINT_EFORMAT, "scene.mesh_file: expected a string, got %s",
                               scene_json_kind(j));
            goto fail;
        }
        if (json_string_length(j) == 0 || json_string_length(j) >= SCENE_PATH_MAX ||
            strlen(json_string_value(j)) != json_string_length(j)) {
            rc = glint_err_set(err, GLINT_EFORMAT,
                               "scene.mesh_file: expected a path of 1..%d bytes without NUL",
                               SCENE_PATH_MAX - 1);
            goto fail;
        }
        rc = scene_abs_path(base_dir, json_string_value(j), out->mesh_path, err);
        if (rc) {
            glint_err_prefix(err, "scene.mesh_file");
            goto fail;
        }
    }

    if ((rc = scene_json_int(root, "width", &width, err)) ||
        (rc = scene_json_int(root, "height", &height, err)))
        goto fail;
    if (width < SCENE_MIN_SIZE || width > SCENE_MAX_SIZE) {
        rc = glint_err_set(err, GLINT_ERANGE, "scene.width %lld outside %d..%d", width,
                           SCENE_MIN_SIZE, SCENE_MAX_SIZE);
        goto fail;
    }
    if (height < SCENE_MIN_SIZE || height > SCENE_MAX_SIZE) {
        rc = glint_err_set(err, GLINT_ERANGE, "scene.height %lld outside %d..%d", height,
                           SCENE_MIN_SIZE, SCENE_MAX_SIZE);
        goto fail;
    }
    out->width = (int)width;
    out->height = (int)height;

    jviews = json_object_get(root, "views");
    if (!jviews) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene.views: missing");
        goto fail;
    }
    if (!json_is_array(jviews)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene.views: expected an array, got %s",
                           scene_json_kind(jviews));
        goto fail;
    }
    nviews = json_array_size(jviews);
    if (nviews < 1 || nviews > SCENE_MAX_VIEWS) {
        rc = glint_err_set(err, GLINT_ERANGE, "scene.views: %zu views, expected 1..%d", nviews,
                           SCENE_MAX_VIEWS);
        goto fail;
    }
    out->views = calloc(nviews, sizeof *out->views);
    if (!out->views) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu views", nviews);
        goto fail;
    }
    out->nviews = (int)nviews;
    for (size_t k = 0; k < nviews; k++) {
        rc = scene_json_view(json_array_get(jviews, k), (int)k, &out->views[k], err);
        if (rc)
            goto fail;
    }

    /* The mesh last: building or loading it is the expensive step. */
    rc = scene_load_mesh(out, err);
    if (rc) {
        glint_err_prefix(err, "%s", out->mesh_path[0] ? "scene.mesh_file" : "scene.mesh");
        goto fail;
    }
    rc = scene_validate(out, err);
    if (rc)
        goto fail;
    json_decref(root);
    return 0;

fail:
    json_decref(root);
    scene_free(out);
    return rc;
}

int scene_from_json(const char *text, scene *out, glint_err *err)
{
    return scene_from_json_at(text, NULL, out, err);
}

/* json_object_set_new that reports failure (it steals `val` either way). */
static int scene_json_set(json_t *obj, const char *key, json_t *val)
{
    return val && json_object_set_new(obj, key, val) == 0 ? 0 : -1;
}

static json_t *scene_json_vec3_new(const double a[3])
{
    json_t *arr = json_array();
    if (!arr)
        return NULL;
    for (int i = 0; i < 3; i++)
        if (json_array_append_new(arr, json_real(a[i])) != 0) {
            json_decref(arr);
            return NULL;
        }
    return arr;
}

char *scene_to_json(const scene *s, glint_err *err)
{
    json_t *root = NULL, *views = NULL;
    char *text = NULL;

    if (scene_validate(s, err))
        return NULL;
    root = json_object();
    views = json_array();
    if (!root || !views)
        goto nomem;
    if (scene_json_set(root, "format", json_string(SCENE_FORMAT)) ||
        scene_json_set(root, "version", json_integer(SCENE_VERSION)) ||
        scene_json_set(root, "mesh", json_string(s->mesh_name)) ||
        (s->mesh_path[0] && scene_json_set(root, "mesh_file", json_string(s->mesh_path))) ||
        scene_json_set(root, "width", json_integer(s->width)) ||
        scene_json_set(root, "height", json_integer(s->height)))
        goto nomem;
    for (int k = 0; k < s->nviews; k++) {
        const scene_view *v = &s->views[k];
        json_t *jv = json_object();
        if (!jv || json_array_append_new(views, jv) != 0)
            goto nomem;
        if (scene_json_set(jv, "eye", scene_json_vec3_new(v->eye)) ||
            scene_json_set(jv, "target", scene_json_vec3_new(v->target)) ||
            scene_json_set(jv, "half_fov", json_real(v->half_fov)) ||
            scene_json_set(jv, "light", scene_json_vec3_new(v->light)) ||
            scene_json_set(jv, "light_intensity", json_real(v->light_intensity)) ||
            scene_json_set(jv, "light_deg", json_real(v->light_deg)))
            goto nomem;
    }
    if (scene_json_set(root, "views", views)) {
        views = NULL; /* stolen */
        goto nomem;
    }
    views = NULL;
    /* 17 significant digits: every double reads back bit for bit. */
    text = json_dumps(root, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_ENSURE_ASCII |
                                JSON_REAL_PRECISION(17));
    if (!text)
        goto nomem;
    json_decref(root);
    return text;

nomem:
    json_decref(views);
    json_decref(root);
    glint_err_set(err, GLINT_ENOMEM, "out of memory serializing a scene to JSON");
    return NULL;
}

int scene_load(const char *path, scene *out, glint_err *err)
{
    FILE *f = NULL;
    char *text = NULL;
    size_t n = 0, cap = 0;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "scene_load: output scene is NULL");
    memset(out, 0, sizeof *out);
    if (!path)
        return glint_err_set(err, GLINT_EINVAL, "scene_load: path is NULL");
    f = fopen(path, "rb");
    if (!f)
        return glint_err_set(err, errno == ENOENT ? GLINT_ENOTFOUND : GLINT_EIO,
                             "opening scene file %s: %s", path, strerror(errno));
    /* Read in growing chunks (works for pipes too), up to the size limit. */
    for (;;) {
        size_t got;
        if (n + 1 >= cap) {
            size_t ncap = cap ? 2 * cap : 65536;
            char *t;
            if (ncap > (size_t)SCENE_JSON_MAX_BYTES + 2)
                ncap = (size_t)SCENE_JSON_MAX_BYTES + 2;
            if (ncap <= cap) {
                rc = glint_err_set(err, GLINT_ERANGE, "scene file %s larger than %u bytes",
                                   path, SCENE_JSON_MAX_BYTES);
                goto done;
            }
            t = realloc(text, ncap);
            if (!t) {
                rc = glint_err_set(err, GLINT_ENOMEM, "out of memory reading %s", path);
                goto done;
            }
            text = t;
            cap = ncap;
        }
        got = fread(text + n, 1, cap - 1 - n, f);
        n += got;
        if (got == 0)
            break;
    }
    if (ferror(f)) {
        rc = glint_err_set(err, GLINT_EIO, "reading scene file %s failed", path);
        goto done;
    }
    text[n] = '\0';
    if (memchr(text, '\0', n)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "scene file %s contains a NUL byte", path);
        goto done;
    }
    {
        /* relative mesh files are relative to the scene file's directory */
        char dir[SCENE_PATH_MAX];
        const char *slash = strrchr(path, '/');
        size_t dl = slash ? (size_t)(slash - path) : 0;
        if (dl >= sizeof dir) {
            rc = glint_err_set(err, GLINT_ERANGE, "scene file path %.200s too long", path);
            goto done;
        }
        if (slash && dl == 0)
            snprintf(dir, sizeof dir, "/");
        else
            snprintf(dir, sizeof dir, "%.*s", (int)dl, path);
        rc = scene_from_json_at(text, dir, out, err);
    }
    if (rc)
        glint_err_prefix(err, "%s", path);
done:
    free(text);
    fclose(f);
    return rc;
}

int scene_save(const scene *s, const char *path, glint_err *err)
{
    fsio_atomic a;
    char *text;
    int rc;

    if (!path || !*path)
        return glint_err_set(err, GLINT_EINVAL, "scene_save: empty path");
    rc = scene_validate(s, err);
    if (rc)
        return rc;
    text = scene_to_json(s, err); /* after validation it can only run out of memory */
    if (!text)
        return GLINT_ENOMEM;
    rc = fsio_atomic_open(&a, path, err);
    if (rc == 0) {
        if (fputs(text, a.fp) < 0 || fputc('\n', a.fp) == EOF) {
            rc = glint_err_set(err, GLINT_EIO, "writing %s failed", path);
            fsio_atomic_abort(&a);
        } else {
            rc = fsio_atomic_commit(&a, err);
        }
    }
    free(text);
    return rc;
}

/* ------------------------------------------------------------------------ */
/* Content hash                                                              */
/* ------------------------------------------------------------------------ */

/* Canonical little-endian serialization fed to XXH3 through a small buffer,
 * independent of struct layout and host byte order. */
typedef struct scene_hasher {
    XXH3_state_t st;
    unsigned char buf[4096];
    size_t n;
} scene_hasher;

static void scene_hash_flush(scene_hasher *h)
{
    if (h->n) {
        (void)XXH3_128bits_update(&h->st, h->buf, h->n);
        h->n = 0;
    }
}

static void scene_hash_u32(scene_hasher *h, uint32_t x)
{
    if (h->n + 4 > sizeof h->buf)
        scene_hash_flush(h);
    for (int i = 0; i < 4; i++)
        h->buf[h->n++] = (unsigned char)(x >> (8 * i));
}

static void scene_hash_u64(scene_hasher *h, uint64_t x)
{
    if (h->n + 8 > sizeof h->buf)
        scene_hash_flush(h);
    for (int i = 0; i < 8; i++)
        h->buf[h->n++] = (unsigned char)(x >> (8 * i));
}

static void scene_hash_f64(scene_hasher *h, double x)
{
    uint64_t u;
    if (x == 0.0)
        x = 0.0; /* -0 and +0 describe the same geometry */
    memcpy(&u, &x, sizeof u);
    scene_hash_u64(h, u);
}

static void scene_hash_f32s(scene_hasher *h, const float *a, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        float x = a[i] == 0.0f ? 0.0f : a[i];
        uint32_t u;
        memcpy(&u, &x, sizeof u);
        scene_hash_u32(h, u);
    }
}

static void scene_hash_bytes(scene_hasher *h, const char *s, size_t n)
{
    scene_hash_u32(h, (uint32_t)n);
    for (size_t i = 0; i < n; i++) {
        if (h->n + 1 > sizeof h->buf)
            scene_hash_flush(h);
        h->buf[h->n++] = (unsigned char)s[i];
    }
}

void scene_hash(const scene *s, char hex[33])
{
    static const char tag[] = "glint-scene-hash";
    scene_hasher h;
    XXH128_hash_t d;
    const mesh *m;
    size_t nv, nt;

    memset(&h, 0, sizeof h);
    (void)XXH3_128bits_reset(&h.st);
    scene_hash_bytes(&h, tag, sizeof tag - 1);
    scene_hash_u32(&h, 1); /* serialization version */
    if (s) {
        scene_hash_u32(&h, (uint32_t)s->width);
        scene_hash_u32(&h, (uint32_t)s->height);
        scene_hash_u32(&h, (uint32_t)s->nviews);
        for (int k = 0; s->views && k < s->nviews; k++) {
            const scene_view *v = &s->views[k];
            for (int i = 0; i < 3; i++)
                scene_hash_f64(&h, v->eye[i]);
            for (int i = 0; i < 3; i++)
                scene_hash_f64(&h, v->target[i]);
            scene_hash_f64(&h, v->half_fov);
            for (int i = 0; i < 3; i++)
                scene_hash_f64(&h, v->light[i]);
            scene_hash_f64(&h, v->light_intensity);
            /* light_deg is informative only: not hashed */
        }
        m = &s->mesh;
        nv = m->nverts > 0 ? (size_t)m->nverts : 0;
        nt = m->ntris > 0 ? (size_t)m->ntris : 0;
        scene_hash_u32(&h, (uint32_t)nv);
        scene_hash_u32(&h, (uint32_t)nt);
        if (m->pos && m->nrm && m->uv && m->tri) {
            scene_hash_f32s(&h, m->pos, 3 * nv);
            scene_hash_f32s(&h, m->nrm, 3 * nv);
            scene_hash_f32s(&h, m->uv, 2 * nv);
            for (size_t i = 0; i < 3 * nt; i++)
                scene_hash_u32(&h, m->tri[i]);
        }
    }
    scene_hash_flush(&h);
    d = XXH3_128bits_digest(&h.st);
    snprintf(hex, 33, "%016llx%016llx", (unsigned long long)d.high64,
             (unsigned long long)d.low64);
}
