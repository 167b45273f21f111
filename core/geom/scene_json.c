/* scene_json.c: the scene document (scene.h): JSON reading with every
 * field checked and named in errors, writing, and scene files. */
#include "scene.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "fsio.h"
#include "internal/scene_int.h"

/* JSON document limits: a scene with SCENE_MAX_VIEWS views takes about
 * 150 KiB; anything far beyond is not a scene.  The document is 4 levels
 * deep (object, views array, view object, vector). */
#define SCENE_JSON_MAX_BYTES (16u << 20)
#define SCENE_JSON_MAX_DEPTH 16
#define SCENE_FORMAT "glint-scene"
#define SCENE_VERSION 1

/* ------------------------------------------------------------------------ */
/* Reading                                                                   */
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

/* The text within the size and depth limits, parsed (OUT: *root, a new
 * reference). */
static int scene_json_parse(const char *text, json_t **root, glint_err *err)
{
    json_error_t jerr;
    size_t len = strnlen(text, (size_t)SCENE_JSON_MAX_BYTES + 1);

    if (len > SCENE_JSON_MAX_BYTES)
        return glint_err_set(err, GLINT_ERANGE, "scene JSON larger than %u bytes",
                             SCENE_JSON_MAX_BYTES);
    if (!scene_json_depth_ok(text, SCENE_JSON_MAX_DEPTH))
        return glint_err_set(err, GLINT_EFORMAT, "scene JSON nested deeper than %d levels",
                             SCENE_JSON_MAX_DEPTH);
    *root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    if (!*root)
        return glint_err_set(err, GLINT_EFORMAT, "scene JSON: %s (line %d, column %d)",
                             jerr.text, jerr.line, jerr.column);
    return 0;
}

/* The document is an object of known fields, of this format and version. */
static int scene_json_header(const json_t *root, glint_err *err)
{
    static const char *const keys[] = {"format", "version", "mesh", "mesh_file", "width",
                                       "height", "views", NULL};
    const json_t *j;
    long long version;
    int rc;

    if (!json_is_object(root))
        return glint_err_set(err, GLINT_EFORMAT, "scene JSON: expected an object, got %s",
                             scene_json_kind(root));
    if ((rc = scene_json_keys(root, keys, "scene", err)))
        return rc;
    j = json_object_get(root, "format");
    if (!j)
        return glint_err_set(err, GLINT_EFORMAT, "scene.format: missing (expected \"%s\")",
                             SCENE_FORMAT);
    if (!json_is_string(j) || strcmp(json_string_value(j), SCENE_FORMAT) != 0)
        return glint_err_set(err, GLINT_EFORMAT, "scene.format: expected \"%s\"", SCENE_FORMAT);
    if ((rc = scene_json_int(root, "version", &version, err)))
        return rc;
    if (version != SCENE_VERSION)
        return glint_err_set(err, GLINT_EUNSUPPORTED,
                             "scene.version %lld unsupported (this build reads version %d)",
                             version, SCENE_VERSION);
    return 0;
}

/* "mesh" (the name) and the optional "mesh_file", made absolute against
 * `base_dir`. */
static int scene_json_mesh(const json_t *root, const char *base_dir, scene *out,
                           glint_err *err)
{
    const json_t *j = json_object_get(root, "mesh");
    int rc;

    if (!j)
        return glint_err_set(err, GLINT_EFORMAT, "scene.mesh: missing");
    if (!json_is_string(j))
        return glint_err_set(err, GLINT_EFORMAT, "scene.mesh: expected a string, got %s",
                             scene_json_kind(j));
    if (json_string_length(j) >= SCENE_NAME_MAX)
        return glint_err_set(err, GLINT_ERANGE, "scene.mesh: name longer than %d bytes",
                             SCENE_NAME_MAX - 1);
    snprintf(out->mesh_name, sizeof out->mesh_name, "%s", json_string_value(j));

    j = json_object_get(root, "mesh_file");
    if (!j)
        return 0;
    if (!json_is_string(j))
        return glint_err_set(err, GLINT_EFORMAT, "scene.mesh_file: expected a string, got %s",
                             scene_json_kind(j));
    if (json_string_length(j) == 0 || json_string_length(j) >= SCENE_PATH_MAX ||
        strlen(json_string_value(j)) != json_string_length(j))
        return glint_err_set(err, GLINT_EFORMAT,
                             "scene.mesh_file: expected a path of 1..%d bytes without NUL",
                             SCENE_PATH_MAX - 1);
    rc = scene_abs_path(base_dir, json_string_value(j), out->mesh_path, err);
    if (rc)
        glint_err_prefix(err, "scene.mesh_file");
    return rc;
}

/* "width" and "height", within the limits. */
static int scene_json_size(const json_t *root, scene *out, glint_err *err)
{
    long long width, height;
    int rc;

    if ((rc = scene_json_int(root, "width", &width, err)) ||
        (rc = scene_json_int(root, "height", &height, err)))
        return rc;
    if (width < SCENE_MIN_SIZE || width > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "scene.width %lld outside %d..%d", width,
                             SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    if (height < SCENE_MIN_SIZE || height > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE, "scene.height %lld outside %d..%d", height,
                             SCENE_MIN_SIZE, SCENE_MAX_SIZE);
    out->width = (int)width;
    out->height = (int)height;
    return 0;
}

/* "views": 1..SCENE_MAX_VIEWS of them, each read and checked
 * (scene_json_view). */
static int scene_json_views(const json_t *root, scene *out, glint_err *err)
{
    const json_t *jviews = json_object_get(root, "views");
    size_t nviews;

    if (!jviews)
        return glint_err_set(err, GLINT_EFORMAT, "scene.views: missing");
    if (!json_is_array(jviews))
        return glint_err_set(err, GLINT_EFORMAT, "scene.views: expected an array, got %s",
                             scene_json_kind(jviews));
    nviews = json_array_size(jviews);
    if (nviews < 1 || nviews > SCENE_MAX_VIEWS)
        return glint_err_set(err, GLINT_ERANGE, "scene.views: %zu views, expected 1..%d",
                             nviews, SCENE_MAX_VIEWS);
    out->views = calloc(nviews, sizeof *out->views);
    if (!out->views)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu views", nviews);
    out->nviews = (int)nviews;
    for (size_t k = 0; k < nviews; k++) {
        int rc = scene_json_view(json_array_get(jviews, k), (int)k, &out->views[k], err);
        if (rc)
            return rc;
    }
    return 0;
}

/* scene_from_json with relative mesh files resolved against `base_dir`
 * (NULL: the working directory). */
static int scene_from_json_at(const char *text, const char *base_dir, scene *out,
                              glint_err *err)
{
    json_t *root = NULL;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "scene_from_json: output scene is NULL");
    memset(out, 0, sizeof *out);
    if (!text)
        return glint_err_set(err, GLINT_EINVAL, "scene_from_json: text is NULL");
    if ((rc = scene_json_parse(text, &root, err)))
        return rc;
    if ((rc = scene_json_header(root, err)) ||
        (rc = scene_json_mesh(root, base_dir, out, err)) ||
        (rc = scene_json_size(root, out, err)) ||
        (rc = scene_json_views(root, out, err)))
        goto fail;
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

/* ------------------------------------------------------------------------ */
/* Writing                                                                   */
/* ------------------------------------------------------------------------ */

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

/* ------------------------------------------------------------------------ */
/* Files                                                                     */
/* ------------------------------------------------------------------------ */

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
