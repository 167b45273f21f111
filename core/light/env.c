/* env.c: environment maps: reading, cube crosses, built-in skies, the
 * resolver and radiance lookup (env.h).  Compression is in env_cut.c. */
#include "env.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "img.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static env_resolver resolver;

void env_map_free(env_map *m)
{
    if (!m)
        return;
    free(m->rgb);
    memset(m, 0, sizeof *m);
}

void env_lights_free(env_lights *l)
{
    if (!l)
        return;
    free(l->dir);
    free(l->power);
    memset(l, 0, sizeof *l);
}

/* Direction of the centre of texel (r, c) of a W x H lat-long map. */
static void texel_dir(int W, int H, double r, double c, double d[3])
{
    double th = M_PI * (r + 0.5) / H, ph = M_PI - 2.0 * M_PI * (c + 0.5) / W;
    d[0] = sin(th) * cos(ph);
    d[1] = sin(th) * sin(ph);
    d[2] = cos(th);
}

/* Clamp negatives and non-finite values to 0, counting them. */
static void sanitize(env_map *m)
{
    size_t n = (size_t)m->width * m->height * 3;
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(m->rgb[i])) {
            m->rgb[i] = 0.0f;
            m->nonfinite++;
        } else if (m->rgb[i] < 0.0f) {
            m->rgb[i] = 0.0f;
            m->clamped++;
        }
    }
}

/* ---- cube crosses ------------------------------------------------------------------ */

/* Faces in the OpenGL cube-map convention (+X, -X, +Y, -Y, +Z, -Z with
 * +Y up in the map's own frame), mapped to glint's world by (x, y, z)_map
 * = (x, z, -y)_world... stated plainly: the cross's up face (+Y) is the
 * world's +z (the sky), its front face (+Z) looks along the world's -y. */
static void world_to_map(const double d[3], double m[3])
{
    m[0] = d[0];
    m[1] = d[2];
    m[2] = -d[1];
}

/* Cross layout cell (column, row) of each face, horizontal 4 x 3:
 *        +Y
 *   -X   +Z   +X   -Z
 *        -Y
 * vertical 3 x 4: the same with -Z below -Y, rotated by 180 degrees. */
static void face_uv(const double m[3], int *face, double *u, double *v)
{
    double ax = fabs(m[0]), ay = fabs(m[1]), az = fabs(m[2]), sc, tc, ma;
    if (ax >= ay && ax >= az) {
        ma = ax;
        *face = m[0] > 0 ? 0 : 1;
        sc = m[0] > 0 ? -m[2] : m[2];
        tc = -m[1];
    } else if (ay >= az) {
        ma = ay;
        *face = m[1] > 0 ? 2 : 3;
        sc = m[0];
        tc = m[1] > 0 ? m[2] : -m[2];
    } else {
        ma = az;
        *face = m[2] > 0 ? 4 : 5;
        sc = m[2] > 0 ? m[0] : -m[0];
        tc = -m[1];
    }
    *u = 0.5 * (sc / ma + 1.0);
    *v = 0.5 * (tc / ma + 1.0);
}

static int from_cross(const img *im, env_map *out, glint_err *err)
{
    int horiz = im->width * 3 == im->height * 4, F = horiz ? im->width / 4 : im->width / 3;
    /* cell of each face: +X, -X, +Y, -Y, +Z, -Z */
    static const int hc[6][2] = {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {3, 1}};
    static const int vc[6][2] = {{2, 1}, {0, 1}, {1, 0}, {1, 2}, {1, 1}, {1, 3}};
    int W = 4 * F, H = 2 * F;
    if (F < 2)
        return glint_err_set(err, GLINT_EINVAL, "cube cross faces of %d pixels are too small", F);
    out->width = W;
    out->height = H;
    if (!(out->rgb = malloc((size_t)W * H * 3 * sizeof *out->rgb)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int r = 0; r < H; r++)
        for (int c = 0; c < W; c++) {
            double d[3], m[3], u, v;
            int f, cx, cy, px, py;
            texel_dir(W, H, r, c, d);
            world_to_map(d, m);
            face_uv(m, &f, &u, &v);
            cx = horiz ? hc[f][0] : vc[f][0];
            cy = horiz ? hc[f][1] : vc[f][1];
            if (!horiz && f == 5) { /* the vertical cross stores -Z upside down */
                u = 1.0 - u;
                v = 1.0 - v;
            }
            px = cx * F + (int)fmin(F - 1, floor(u * F));
            py = cy * F + (int)fmin(F - 1, floor(v * F));
            for (int ch = 0; ch < 3; ch++)
                out->rgb[((size_t)r * W + c) * 3 + ch] =
                    im->px[((size_t)py * im->width + px) * im->channels +
                           (im->channels >= 3 ? ch : 0)];
        }
    snprintf(out->layout, sizeof out->layout, "cross");
    return 0;
}

static int from_img(const img *im, const char *name, env_map *out, glint_err *err)
{
    int rc = 0;
    memset(out, 0, sizeof *out);
    snprintf(out->name, sizeof out->name, "%s", name);
    if (im->width == 2 * im->height) {
        if (im->width > ENV_MAX_DIM)
            return glint_err_set(err, GLINT_ERANGE, "environment %dx%d above %d wide",
                                 im->width, im->height, ENV_MAX_DIM);
        out->width = im->width;
        out->height = im->height;
        if (!(out->rgb = malloc((size_t)im->width * im->height * 3 * sizeof *out->rgb)))
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        for (size_t p = 0; p < (size_t)im->width * im->height; p++)
            for (int ch = 0; ch < 3; ch++)
                out->rgb[3 * p + ch] = im->px[p * im->channels + (im->channels >= 3 ? ch : 0)];
        snprintf(out->layout, sizeof out->layout, "latlong");
    } else if (im->width * 3 == im->height * 4 || im->width * 4 == im->height * 3) {
        rc = from_cross(im, out, err);
    } else {
        return glint_err_set(err, GLINT_EINVAL,
                             "environment %dx%d: expected a lat-long map (2:1) or a cube "
                             "cross (4:3 or 3:4)",
                             im->width, im->height);
    }
    if (!rc)
        sanitize(out);
    else
        env_map_free(out);
    return rc;
}

static const char *base_name(const char *path)
{
    const char *s = strrchr(path, '/');
    return s ? s + 1 : path;
}

int env_load(const char *path, env_map *out, glint_err *err)
{
    img im;
    int rc;
    memset(out, 0, sizeof *out);
    if ((rc = img_read_keep_nonfinite(path, &im, err)))
        return rc;
    rc = from_img(&im, base_name(path), out, err);
    img_free(&im);
    return rc;
}

int env_load_mem(const void *data, size_t len, const char *name, int max_dim,
                 img_header_check check, void *cls, env_map *out, glint_err *err)
{
    img im;
    int rc;
    memset(out, 0, sizeof *out);
    if ((rc = img_read_mem_keep_nonfinite(data, len, max_dim, check, cls, &im, err)))
        return rc;
    rc = from_img(&im, name ? name : "upload", out, err);
    img_free(&im);
    return rc;
}

/* ---- built-in skies --------------------------------------------------------------- */

static const char *const builtins[] = {"sky", "studio", "sunset", "white", "overcast", NULL};

const char *env_builtin_names(void)
{
    return "sky, studio, sunset, white, overcast";
}

/* Radiance of a sun of angular radius `rad` (radians) around s. */
static double sun(const double d[3], const double s[3], double rad)
{
    double c = d[0] * s[0] + d[1] * s[1] + d[2] * s[2];
    return c >= cos(rad) ? 1.0 : 0.0;
}

static void sky_texel(int kind, const double d[3], double rgb[3])
{
    double z = d[2];
    if (kind == 3) { /* white */
        rgb[0] = rgb[1] = rgb[2] = 1.0;
        return;
    }
    if (kind == 1) { /* studio: grey dome, dark floor, two soft boxes */
        static const double b1[3] = {0.6, -0.5, 0.62}, b2[3] = {-0.7, 0.4, 0.59};
        double g = z > 0 ? 0.35 + 0.25 * z : 0.12 + 0.05 * (1 + z);
        double l1 = sqrt(b1[0] * b1[0] + b1[1] * b1[1] + b1[2] * b1[2]);
        double l2 = sqrt(b2[0] * b2[0] + b2[1] * b2[1] + b2[2] * b2[2]);
        double c1 = (d[0] * b1[0] + d[1] * b1[1] + d[2] * b1[2]) / l1;
        double c2 = (d[0] * b2[0] + d[1] * b2[1] + d[2] * b2[2]) / l2;
        g += (c1 > cos(0.25) ? 6.0 : 0.0) + (c2 > cos(0.3) ? 3.0 : 0.0);
        rgb[0] = rgb[1] = rgb[2] = g;
        return;
    }
    if (kind == 4) { /* overcast: CIE-like, brighter at the zenith */
        double g = z > 0 ? (1.0 + 2.0 * z) / 3.0 : 0.1;
        rgb[0] = rgb[1] = rgb[2] = g;
        return;
    }
    if (kind == 2) { /* sunset: low warm sun, orange horizon, dark blue zenith */
        static const double s[3] = {0.9950, 0.0, 0.0998};
        double hz = z > 0 ? exp(-6.0 * z) : 0.0;
        if (z > 0) {
            rgb[0] = 0.08 + 1.2 * hz;
            rgb[1] = 0.09 + 0.5 * hz;
            rgb[2] = 0.25 + 0.1 * hz;
        } else {
            rgb[0] = 0.05;
            rgb[1] = 0.04;
            rgb[2] = 0.04;
        }
        if (sun(d, s, 0.02)) {
            rgb[0] += 800.0;
            rgb[1] += 450.0;
            rgb[2] += 150.0;
        }
        return;
    }
    { /* sky: blue gradient, sun at 50 degrees elevation, green-grey ground */
        static const double s[3] = {0.3830, 0.4564, 0.8030};
        if (z > 0) {
            rgb[0] = 0.35 + 0.3 * (1 - z);
            rgb[1] = 0.55 + 0.25 * (1 - z);
            rgb[2] = 1.0 + 0.1 * (1 - z);
        } else {
            rgb[0] = 0.15;
            rgb[1] = 0.17;
            rgb[2] = 0.12;
        }
        if (sun(d, s, 0.02)) {
            rgb[0] += 2000.0;
            rgb[1] += 1900.0;
            rgb[2] += 1700.0;
        }
    }
}

int env_builtin(const char *name, int width, int height, env_map *out, glint_err *err)
{
    int kind = -1;
    memset(out, 0, sizeof *out);
    for (int i = 0; builtins[i]; i++)
        if (!strcmp(name, builtins[i]))
            kind = i;
    if (kind < 0)
        return glint_err_set(err, GLINT_ENOTFOUND, "no built-in environment '%s' (built-ins: %s)",
                             name, env_builtin_names());
    if (height < 8 || width != 2 * height || width > ENV_MAX_DIM)
        return glint_err_set(err, GLINT_ERANGE, "built-in size %dx%d (need W = 2H, H >= 8)",
                             width, height);
    out->width = width;
    out->height = height;
    if (!(out->rgb = malloc((size_t)width * height * 3 * sizeof *out->rgb)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    /* each texel: the mean over a 4 x 4 grid inside it (the sun is small) */
    for (int r = 0; r < height; r++)
        for (int c = 0; c < width; c++) {
            double acc[3] = {0, 0, 0};
            for (int a = 0; a < 4; a++)
                for (int b = 0; b < 4; b++) {
                    double d[3], v[3];
                    texel_dir(width, height, r - 0.5 + (a + 0.5) / 4.0, c - 0.5 + (b + 0.5) / 4.0,
                              d);
                    sky_texel(kind, d, v);
                    for (int ch = 0; ch < 3; ch++)
                        acc[ch] += v[ch] / 16.0;
                }
            for (int ch = 0; ch < 3; ch++)
                out->rgb[((size_t)r * width + c) * 3 + ch] = (float)acc[ch];
        }
    snprintf(out->name, sizeof out->name, "%s", name);
    snprintf(out->layout, sizeof out->layout, "builtin");
    return 0;
}

/* ---- specs ---------------------------------------------------------------------------- */

void env_set_resolver(env_resolver fn)
{
    resolver = fn;
}

int env_spec_check(const char *spec, glint_err *err)
{
    size_t n = spec ? strlen(spec) : 0;
    if (n == 0 || n >= ENV_NAME_MAX)
        return glint_err_set(err, GLINT_EINVAL, "an environment name has 1 to %d characters",
                             ENV_NAME_MAX - 1);
    for (size_t i = 0; i < n; i++) {
        char c = spec[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              c == '.' || c == '_' || c == ':' || c == '-' || c == '/'))
            return glint_err_set(err, GLINT_EINVAL,
                                 "environment name '%s': only letters, digits and . _ : - / "
                                 "are allowed", spec);
    }
    return 0;
}

/* Whether spec names a built-in ("NAME" or "builtin:NAME"); OUT *name:
 * spec without its "builtin:" (spec itself when it has none). */
static int is_builtin(const char *spec, const char **name)
{
    *name = strncmp(spec, "builtin:", 8) ? spec : spec + 8;
    for (int i = 0; builtins[i]; i++)
        if (!strcmp(*name, builtins[i]))
            return 1;
    return 0;
}

int env_spec_lookup(const char *spec, glint_err *err)
{
    char path[4096];
    const char *name;
    int rc;
    if ((rc = env_spec_check(spec, err)))
        return rc;
    if (is_builtin(spec, &name))
        return 0;
    if (name != spec)
        return glint_err_set(err, GLINT_ENOTFOUND, "no built-in environment '%s' (built-ins: %s)",
                             name, env_builtin_names());
    if (!resolver)
        return glint_err_set(err, GLINT_ENOTFOUND, "unknown environment '%s' (built-ins: %s)",
                             spec, env_builtin_names());
    return resolver(spec, path, sizeof path, err);
}

int env_resolve(const char *spec, env_map *out, glint_err *err)
{
    char path[4096];
    const char *name;
    int rc;
    memset(out, 0, sizeof *out);
    if ((rc = env_spec_check(spec, err)))
        return rc;
    if (is_builtin(spec, &name) || name != spec) /* (an unknown one: the error names them) */
        return env_builtin(name, 512, 256, out, err);
    if (!resolver)
        return glint_err_set(err, GLINT_ENOTFOUND, "unknown environment '%s' (built-ins: %s)",
                             spec, env_builtin_names());
    if ((rc = resolver(spec, path, sizeof path, err)))
        return rc;
    if ((rc = env_load(path, out, err)))
        return rc;
    snprintf(out->name, sizeof out->name, "%s", spec);
    return 0;
}

int env_identity(const char *spec, char *out, size_t len, glint_err *err)
{
    char path[4096];
    const char *name;
    struct stat st;
    int rc;
    if ((rc = env_spec_check(spec, err)))
        return rc;
    if (is_builtin(spec, &name)) {
        snprintf(out, len, "builtin:%s", name);
        return 0;
    }
    if (name != spec || !resolver)
        return env_spec_lookup(spec, err); /* its error */
    if ((rc = resolver(spec, path, sizeof path, err)))
        return rc;
    if (stat(path, &st))
        return glint_err_set(err, GLINT_ENOTFOUND, "environment '%s': %s", spec, strerror(errno));
    if (snprintf(out, len, "file:%llu:%llu:%lld:%lld.%09ld:%s", (unsigned long long)st.st_dev,
                 (unsigned long long)st.st_ino, (long long)st.st_size,
                 (long long)st.st_mtim.tv_sec, (long)st.st_mtim.tv_nsec, path) >= (int)len)
        return glint_err_set(err, GLINT_ERANGE, "environment '%s': its path is too long", spec);
    return 0;
}

/* ---- lookup ---------------------------------------------------------------------------- */

void env_radiance(const env_map *m, const double d[3], double psi, double intensity,
                  double rgb[3])
{
    /* the rotated map at d is the map at Rz(-psi) d */
    double c = cos(psi), s = sin(psi), x = c * d[0] + s * d[1], y = -s * d[0] + c * d[1];
    double z = d[2], th = acos(z < -1 ? -1 : z > 1 ? 1 : z), ph = atan2(y, x);
    double fr = th / M_PI * m->height - 0.5, fc = (M_PI - ph) / (2.0 * M_PI) * m->width - 0.5;
    int r0 = (int)floor(fr), c0 = (int)floor(fc);
    double tr = fr - r0, tc = fc - c0;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            int r = r0 + a, cc = ((c0 + b) % m->width + m->width) % m->width;
            double w = (a ? tr : 1 - tr) * (b ? tc : 1 - tc);
            r = r < 0 ? 0 : r >= m->height ? m->height - 1 : r;
            for (int ch = 0; ch < 3; ch++)
                rgb[ch] += w * m->rgb[((size_t)r * m->width + cc) * 3 + ch];
        }
    for (int ch = 0; ch < 3; ch++)
        rgb[ch] *= intensity;
}

void env_total_power(const env_map *m, double rgb[3])
{
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (int r = 0; r < m->height; r++) {
        double om = 2.0 * M_PI / m->width *
                    (cos(M_PI * r / m->height) - cos(M_PI * (r + 1) / m->height));
        for (int c = 0; c < m->width; c++)
            for (int ch = 0; ch < 3; ch++)
                rgb[ch] += om * m->rgb[((size_t)r * m->width + c) * 3 + ch];
    }
}
