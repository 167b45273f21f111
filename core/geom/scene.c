/* scene.c: scenes: parameters, the icosahedral view sets, views,
 * validation and creation (contract and conventions in scene.h; they follow
 * ../shared/reference/hf_ref.py, section 1 "Geometry").  The JSON document
 * is in scene_json.c, the content hash in scene_hash.c. */
#include "scene.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "internal/scene_int.h"
#include "vec3.h"

#define SCENE_PI 3.14159265358979323846
#define SCENE_PHI 1.61803398874989484820 /* (1 + sqrt 5) / 2 */

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
int scene_check_view(const scene_view *v, int k, glint_err *err)
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

/* Absolute form of a mesh file path (contract in scene_int.h). */
int scene_abs_path(const char *base, const char *path, char out[SCENE_PATH_MAX],
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
int scene_load_mesh(scene *out, glint_err *err)
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
