/* stroke.c: the brush of seed 004 (stroke.h).
 *
 * Application walks the stroke's bounding box (points expanded by D/2,
 * clipped to the image) in tiles of STROKE_TILE x STROKE_TILE pixels; each
 * tile first keeps the segments whose own expanded box reaches it, then
 * takes, per pixel centre, the minimum squared distance over those
 * segments.  The result equals the direct minimum over every segment (the
 * culled segments are farther than D/2 from every pixel of the tile, so
 * they cannot change a pixel that gets a weight), and the cost follows the
 * area the stroke covers instead of pixels x points. */
#include "stroke.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define STROKE_TILE 32

/* ------------------------------------------------------------------------ */
/* JSON                                                                      */
/* ------------------------------------------------------------------------ */

static const char *stroke_json_kind(const json_t *j)
{
    switch (json_typeof(j)) {
    case JSON_OBJECT: return "an object";
    case JSON_ARRAY: return "an array";
    case JSON_STRING: return "a string";
    case JSON_INTEGER: return "an integer";
    case JSON_REAL: return "a number";
    case JSON_TRUE:
    case JSON_FALSE: return "a boolean";
    case JSON_NULL: return "null";
    }
    return "something else";
}

/* A finite number from a JSON number (integers included). */
static int stroke_json_num(const json_t *j, const char *where, const char *field, double *out,
                           glint_err *err)
{
    double v;
    if (!json_is_number(j))
        return glint_err_set(err, GLINT_EFORMAT, "%s.%s: expected a number, got %s", where,
                             field, stroke_json_kind(j));
    v = json_number_value(j);
    if (!isfinite(v))
        return glint_err_set(err, GLINT_ENONFINITE, "%s.%s: %g is not finite", where, field, v);
    *out = v;
    return 0;
}

static int stroke_json_color(const json_t *j, const char *where, double c[3], glint_err *err)
{
    if (!json_is_array(j) || json_array_size(j) != 3)
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s.color: expected an array of 3 numbers [r, g, b], got %s",
                             where, json_is_array(j) ? "an array of another length"
                                                     : stroke_json_kind(j));
    for (int i = 0; i < 3; i++) {
        char field[16];
        int rc;
        snprintf(field, sizeof field, "color[%d]", i);
        rc = stroke_json_num(json_array_get(j, (size_t)i), where, field, &c[i], err);
        if (rc)
            return rc;
        if (fabs(c[i]) > STROKE_MAX_VALUE)
            return glint_err_set(err, GLINT_EINVAL, "%s.color[%d]: %g outside [-%g, %g]", where,
                                 i, c[i], STROKE_MAX_VALUE, STROKE_MAX_VALUE);
    }
    return 0;
}

static int stroke_json_points(const json_t *j, const char *where, int max_points, stroke *out,
                              glint_err *err)
{
    size_t n;

    if (!json_is_array(j))
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s.points: expected an array of [x, y] pairs, got %s", where,
                             stroke_json_kind(j));
    n = json_array_size(j);
    if (n == 0)
        return glint_err_set(err, GLINT_EINVAL, "%s.points: empty (a stroke needs 1 point or more)",
                             where);
    if (n > (size_t)max_points)
        return glint_err_set(err, GLINT_ERANGE,
                             "%s.points: %zu points, more than the limit of %d points per stroke",
                             where, n, max_points);
    out->pts = malloc(2 * n * sizeof *out->pts);
    if (!out->pts)
        return glint_err_set(err, GLINT_ENOMEM, "%s.points: out of memory for %zu points", where,
                             n);
    for (size_t i = 0; i < n; i++) {
        const json_t *p = json_array_get(j, i);
        char field[48];
        int rc;
        if (!json_is_array(p) || json_array_size(p) != 2)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s.points[%zu]: expected [x, y], got %s", where, i,
                                 json_is_array(p) ? "an array of another length"
                                                  : stroke_json_kind(p));
        for (int c = 0; c < 2; c++) {
            double v;
            snprintf(field, sizeof field, "points[%zu][%d]", i, c);
            rc = stroke_json_num(json_array_get(p, (size_t)c), where, field, &v, err);
            if (rc)
                return rc;
            if (fabs(v) > STROKE_MAX_COORD)
                return glint_err_set(err, GLINT_EINVAL, "%s.%s: %g outside [-%g, %g] pixels",
                                     where, field, v, STROKE_MAX_COORD, STROKE_MAX_COORD);
            out->pts[2 * i + (size_t)c] = v;
        }
    }
    out->npoints = (int)n;
    return 0;
}

int stroke_from_json(const json_t *j, const char *where, int max_points, stroke *out,
                     glint_err *err)
{
    static const char *const keys[] = {"mode", "color", "diameter", "kappa", "scale",
                                       "opacity", "points", "tag", NULL};
    const char *k;
    json_t *v;
    int rc;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "stroke_from_json: output stroke is NULL");
    memset(out, 0, sizeof *out);
    if (!where)
        where = "stroke";
    if (max_points < 1)
        return glint_err_set(err, GLINT_EINVAL, "stroke_from_json: max_points %d is not >= 1",
                             max_points);
    if (!json_is_object(j))
        return glint_err_set(err, GLINT_EFORMAT, "%s: expected an object, got %s", where,
                             j ? stroke_json_kind(j) : "nothing");
    json_object_foreach((json_t *)j, k, v) {
        int known = 0;
        for (int i = 0; keys[i]; i++)
            if (strcmp(k, keys[i]) == 0)
                known = 1;
        if (!known)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s: unknown key \"%.64s\" (known: mode, color, diameter, kappa, "
                                 "scale, opacity, points, tag)",
                                 where, k);
    }

    out->mode = STROKE_PAINT;
    v = json_object_get(j, "mode");
    if (v) {
        const char *m = json_string_value(v);
        if (!m)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s.mode: expected \"paint\", \"scale\" or \"erase\", got %s",
                                 where, stroke_json_kind(v));
        if (strcmp(m, "paint") == 0)
            out->mode = STROKE_PAINT;
        else if (strcmp(m, "scale") == 0)
            out->mode = STROKE_SCALE;
        else if (strcmp(m, "erase") == 0)
            out->mode = STROKE_ERASE;
        else
            return glint_err_set(err, GLINT_EINVAL,
                                 "%s.mode: \"%.32s\" is not \"paint\", \"scale\" or \"erase\"",
                                 where, m);
    }

    v = json_object_get(j, "diameter");
    if (!v)
        return glint_err_set(err, GLINT_EFORMAT, "%s.diameter: missing (pixels, > 0)", where);
    if ((rc = stroke_json_num(v, where, "diameter", &out->diameter, err)))
        return rc;
    if (!(out->diameter > 0.0) || out->diameter > STROKE_MAX_DIAMETER)
        return glint_err_set(err, GLINT_EINVAL, "%s.diameter: %g outside (0, %g] pixels", where,
                             out->diameter, STROKE_MAX_DIAMETER);

    out->kappa = 0.0;
    v = json_object_get(j, "kappa");
    if (v) {
        if ((rc = stroke_json_num(v, where, "kappa", &out->kappa, err)))
            return rc;
        if (!(out->kappa >= 0.0) || out->kappa > STROKE_MAX_VALUE)
            return glint_err_set(err, GLINT_EINVAL, "%s.kappa: %g outside [0, %g]", where,
                                 out->kappa, STROKE_MAX_VALUE);
    }

    out->opacity = 1.0;
    v = json_object_get(j, "opacity");
    if (v) {
        if ((rc = stroke_json_num(v, where, "opacity", &out->opacity, err)))
            return rc;
        if (!(out->opacity >= 0.0 && out->opacity <= 1.0))
            return glint_err_set(err, GLINT_EINVAL, "%s.opacity: %g outside [0, 1]", where,
                                 out->opacity);
    }

    v = json_object_get(j, "color");
    if (out->mode == STROKE_PAINT) {
        if (!v)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s.color: missing (a paint stroke needs [r, g, b])", where);
        if ((rc = stroke_json_color(v, where, out->color, err)))
            return rc;
    }

    v = json_object_get(j, "scale");
    if (out->mode == STROKE_SCALE) {
        if (!v)
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s.scale: missing (a scale stroke needs S >= 0)", where);
        if ((rc = stroke_json_num(v, where, "scale", &out->scale, err)))
            return rc;
        if (!(out->scale >= 0.0) || out->scale > STROKE_MAX_VALUE)
            return glint_err_set(err, GLINT_EINVAL, "%s.scale: %g outside [0, %g]", where,
                                 out->scale, STROKE_MAX_VALUE);
    }

    v = json_object_get(j, "tag");
    if (v) {
        if (!json_is_string(v))
            return glint_err_set(err, GLINT_EFORMAT, "%s.tag: expected a string, got %s", where,
                                 stroke_json_kind(v));
        if (json_string_length(v) > STROKE_TAG_MAX ||
            strlen(json_string_value(v)) != json_string_length(v))
            return glint_err_set(err, GLINT_EINVAL,
                                 "%s.tag: longer than %d bytes or holds a NUL byte", where,
                                 STROKE_TAG_MAX);
        memcpy(out->tag, json_string_value(v), json_string_length(v) + 1);
    }

    v = json_object_get(j, "points");
    if (!v)
        return glint_err_set(err, GLINT_EFORMAT, "%s.points: missing (an array of [x, y])", where);
    rc = stroke_json_points(v, where, max_points, out, err);
    if (rc) {
        stroke_free(out);
        return rc;
    }
    return 0;
}

int stroke_list_from_json(const json_t *arr, const stroke_limits *lim, stroke **list, int *n,
                          glint_err *err)
{
    stroke *out = NULL;
    size_t count;
    int rc = 0;

    if (!list || !n || !lim)
        return glint_err_set(err, GLINT_EINVAL, "stroke_list_from_json: NULL argument");
    *list = NULL;
    *n = 0;
    if (lim->max_strokes < 1 || lim->max_points < 1)
        return glint_err_set(err, GLINT_EINVAL,
                             "stroke_list_from_json: limits %d strokes, %d points are not >= 1",
                             lim->max_strokes, lim->max_points);
    if (!json_is_array(arr))
        return glint_err_set(err, GLINT_EFORMAT, "strokes: expected an array, got %s",
                             arr ? stroke_json_kind(arr) : "nothing");
    count = json_array_size(arr);
    if (count == 0)
        return glint_err_set(err, GLINT_EINVAL, "strokes: empty (send 1 stroke or more)");
    if (count > (size_t)lim->max_strokes)
        return glint_err_set(err, GLINT_ERANGE,
                             "strokes: %zu strokes, more than the limit of %d strokes per request",
                             count, lim->max_strokes);
    out = calloc(count, sizeof *out);
    if (!out)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for %zu strokes", count);
    for (size_t i = 0; i < count; i++) {
        char where[32];
        snprintf(where, sizeof where, "strokes[%zu]", i);
        rc = stroke_from_json(json_array_get(arr, i), where, lim->max_points, &out[i], err);
        if (rc) {
            stroke_list_free(out, (int)i);
            return rc;
        }
    }
    *list = out;
    *n = (int)count;
    return 0;
}

static int stroke_set(json_t *obj, const char *key, json_t *val)
{
    return val && json_object_set_new(obj, key, val) == 0 ? 0 : -1;
}

json_t *stroke_to_json(const stroke *s)
{
    static const char *const modes[] = {"paint", "scale", "erase"};
    json_t *o, *pts;

    if (!s || s->mode < STROKE_PAINT || s->mode > STROKE_ERASE || s->npoints < 1 || !s->pts)
        return NULL;
    o = json_object();
    pts = json_array();
    if (!o || !pts)
        goto fail;
    if (stroke_set(o, "mode", json_string(modes[s->mode])))
        goto fail;
    if (s->mode == STROKE_PAINT &&
        stroke_set(o, "color", json_pack("[fff]", s->color[0], s->color[1], s->color[2])))
        goto fail;
    if (stroke_set(o, "diameter", json_real(s->diameter)) ||
        stroke_set(o, "kappa", json_real(s->kappa)))
        goto fail;
    if (s->mode == STROKE_SCALE && stroke_set(o, "scale", json_real(s->scale)))
        goto fail;
    if (stroke_set(o, "opacity", json_real(s->opacity)))
        goto fail;
    for (int i = 0; i < s->npoints; i++)
        if (json_array_append_new(pts, json_pack("[ff]", s->pts[2 * i], s->pts[2 * i + 1])))
            goto fail;
    if (stroke_set(o, "points", pts)) {
        pts = NULL; /* stolen */
        goto fail;
    }
    pts = NULL;
    if (s->tag[0] && stroke_set(o, "tag", json_string(s->tag)))
        goto fail;
    return o;
fail:
    json_decref(pts);
    json_decref(o);
    return NULL;
}

void stroke_free(stroke *s)
{
    if (!s)
        return;
    free(s->pts);
    memset(s, 0, sizeof *s);
}

void stroke_list_free(stroke *list, int n)
{
    if (!list)
        return;
    for (int i = 0; i < n; i++)
        stroke_free(&list[i]);
    free(list);
}

/* ------------------------------------------------------------------------ */
/* Geometry                                                                  */
/* ------------------------------------------------------------------------ */

/* Squared distance from (px, py) to the segment [a, b] (a dab when a = b),
 * computed exactly as documented in stroke.h. */
static double stroke_seg_d2(double px, double py, const double *a, const double *b)
{
    double vx = b[0] - a[0], vy = b[1] - a[1];
    double l2 = vx * vx + vy * vy;
    double t = 0.0, dx, dy;

    if (l2 > 0.0) {
        t = ((px - a[0]) * vx + (py - a[1]) * vy) / l2;
        if (t < 0.0)
            t = 0.0;
        else if (t > 1.0)
            t = 1.0;
    }
    dx = px - (a[0] + t * vx);
    dy = py - (a[1] + t * vy);
    return dx * dx + dy * dy;
}

/* Segment i of a stroke: points i and i + 1, or the single point of a dab. */
static int stroke_nseg(const stroke *s)
{
    return s->npoints > 1 ? s->npoints - 1 : 1;
}

static const double *stroke_seg_b(const stroke *s, int i)
{
    return s->npoints > 1 ? s->pts + 2 * (i + 1) : s->pts;
}

double stroke_distance(const stroke *s, double x, double y)
{
    double best = INFINITY;
    if (!s || s->npoints < 1 || !s->pts)
        return INFINITY;
    for (int i = 0; i < stroke_nseg(s); i++) {
        double d2 = stroke_seg_d2(x, y, s->pts + 2 * i, stroke_seg_b(s, i));
        if (d2 < best)
            best = d2;
    }
    return sqrt(best);
}

/* w from the distance, as documented. */
static double stroke_w(const stroke *s, double d)
{
    if (!(d <= 0.5 * s->diameter))
        return 0.0;
    return s->opacity * exp(-s->kappa * d);
}

double stroke_weight(const stroke *s, double x, double y)
{
    if (!s || s->npoints < 1 || !s->pts)
        return 0.0;
    return stroke_w(s, stroke_distance(s, x, y));
}

/* ------------------------------------------------------------------------ */
/* Application                                                               */
/* ------------------------------------------------------------------------ */

/* Pixel index range [lo, hi] whose centres c = i + 0.5 satisfy
 * a <= c <= b, clipped to [0, n - 1] (hi < lo when empty). */
static void stroke_range(double a, double b, int n, int *lo, int *hi)
{
    double l = ceil(a - 0.5), h = floor(b - 0.5);
    if (l < 0.0)
        l = 0.0;
    if (h > (double)(n - 1))
        h = (double)(n - 1);
    if (h < l) {
        *lo = 0;
        *hi = -1;
        return;
    }
    *lo = (int)l;
    *hi = (int)h;
}

static int stroke_check_img(const img *im, const char *what, glint_err *err)
{
    if (!im || !im->px || im->width < 1 || im->height < 1)
        return glint_err_set(err, GLINT_EINVAL, "stroke: %s image is empty", what);
    if (im->channels != 3)
        return glint_err_set(err, GLINT_EINVAL, "stroke: %s image has %d channels, expected 3 (RGB)",
                             what, im->channels);
    return 0;
}

static int stroke_check(const stroke *s, glint_err *err)
{
    if (!s || s->npoints < 1 || !s->pts)
        return glint_err_set(err, GLINT_EINVAL, "stroke: no points");
    if (s->mode < STROKE_PAINT || s->mode > STROKE_ERASE)
        return glint_err_set(err, GLINT_EINVAL, "stroke: unknown mode %d", (int)s->mode);
    if (!(s->diameter > 0.0) || s->diameter > STROKE_MAX_DIAMETER || !(s->kappa >= 0.0) ||
        s->kappa > STROKE_MAX_VALUE || !(s->opacity >= 0.0 && s->opacity <= 1.0) ||
        !(s->scale >= 0.0) || s->scale > STROKE_MAX_VALUE)
        return glint_err_set(err, GLINT_EINVAL,
                             "stroke: diameter %g, kappa %g, opacity %g or scale %g out of range",
                             s->diameter, s->kappa, s->opacity, s->scale);
    for (int c = 0; c < 3; c++)
        if (!isfinite(s->color[c]) || fabs(s->color[c]) > STROKE_MAX_VALUE)
            return glint_err_set(err, GLINT_EINVAL, "stroke: color[%d] %g out of range", c,
                                 s->color[c]);
    for (int i = 0; i < 2 * s->npoints; i++)
        if (!isfinite(s->pts[i]) || fabs(s->pts[i]) > STROKE_MAX_COORD)
            return glint_err_set(err, GLINT_EINVAL, "stroke: point %d coordinate %g out of range",
                                 i / 2, s->pts[i]);
    return 0;
}

/* Whether segment a-b, widened by r, may reach the tile of pixel centres
 * [cx0, cx1] x [cy0, cy1] (its bounding box does): stroke_apply's test, and
 * stroke_cost's count of it. */
static int stroke_seg_near(const double *a, const double *b, double r, double cx0, double cx1,
                           double cy0, double cy1)
{
    return !(fmax(a[0], b[0]) + r < cx0 || fmin(a[0], b[0]) - r > cx1 ||
             fmax(a[1], b[1]) + r < cy0 || fmin(a[1], b[1]) - r > cy1);
}

int stroke_apply(const stroke *s, img *im, const img *base, stroke_report *rep, glint_err *err)
{
    double r, xmin, xmax, ymin, ymax;
    int nseg, ix0, ix1, iy0, iy1, rc;
    int *cand = NULL;
    stroke_report local = {0, 0, 0, -1, -1};

    if (rep)
        *rep = local;
    if ((rc = stroke_check(s, err)) || (rc = stroke_check_img(im, "target", err)))
        return rc;
    if (s->mode == STROKE_ERASE) {
        if (!base)
            return glint_err_set(err, GLINT_EINVAL, "stroke: an erase stroke needs the base image");
        if ((rc = stroke_check_img(base, "base", err)))
            return rc;
        if (base->width != im->width || base->height != im->height)
            return glint_err_set(err, GLINT_EINVAL, "stroke: base image %dx%d, target %dx%d",
                                 base->width, base->height, im->width, im->height);
    }

    r = 0.5 * s->diameter;
    xmin = xmax = s->pts[0];
    ymin = ymax = s->pts[1];
    for (int i = 1; i < s->npoints; i++) {
        xmin = fmin(xmin, s->pts[2 * i]);
        xmax = fmax(xmax, s->pts[2 * i]);
        ymin = fmin(ymin, s->pts[2 * i + 1]);
        ymax = fmax(ymax, s->pts[2 * i + 1]);
    }
    stroke_range(xmin - r, xmax + r, im->width, &ix0, &ix1);
    stroke_range(ymin - r, ymax + r, im->height, &iy0, &iy1);
    if (ix1 < ix0 || iy1 < iy0)
        return 0; /* entirely outside the image */

    nseg = stroke_nseg(s);
    cand = malloc((size_t)nseg * sizeof *cand);
    if (!cand)
        return glint_err_set(err, GLINT_ENOMEM, "stroke: out of memory for %d segments", nseg);
    local.x0 = im->width;
    local.y0 = im->height;

    for (int ty = iy0; ty <= iy1; ty += STROKE_TILE) {
        int ty1 = ty + STROKE_TILE - 1 < iy1 ? ty + STROKE_TILE - 1 : iy1;
        for (int tx = ix0; tx <= ix1; tx += STROKE_TILE) {
            int tx1 = tx + STROKE_TILE - 1 < ix1 ? tx + STROKE_TILE - 1 : ix1;
            /* pixel centres of the tile span [tx + .5, tx1 + .5] x [ty + .5, ty1 + .5] */
            double cx0 = tx + 0.5, cx1 = tx1 + 0.5, cy0 = ty + 0.5, cy1 = ty1 + 0.5;
            int nc = 0;
            for (int i = 0; i < nseg; i++) {
                const double *a = s->pts + 2 * i, *b = stroke_seg_b(s, i);
                if (stroke_seg_near(a, b, r, cx0, cx1, cy0, cy1))
                    cand[nc++] = i;
            }
            if (nc == 0)
                continue;
            for (int y = ty; y <= ty1; y++) {
                double py = y + 0.5;
                for (int x = tx; x <= tx1; x++) {
                    double px = x + 0.5, best = INFINITY, w;
                    size_t o = 3 * ((size_t)y * (size_t)im->width + (size_t)x);
                    for (int c = 0; c < nc && best > 0.0; c++) {
                        double d2 = stroke_seg_d2(px, py, s->pts + 2 * cand[c],
                                                  stroke_seg_b(s, cand[c]));
                        if (d2 < best)
                            best = d2;
                    }
                    w = stroke_w(s, sqrt(best));
                    if (!(w > 0.0))
                        continue;
                    for (int ch = 0; ch < 3; ch++) {
                        double old = im->px[o + (size_t)ch], v;
                        if (s->mode == STROKE_PAINT)
                            v = w * s->color[ch] + (1.0 - w) * old;
                        else if (s->mode == STROKE_SCALE)
                            v = w * s->scale * old + (1.0 - w) * old;
                        else
                            v = w * (double)base->px[o + (size_t)ch] + (1.0 - w) * old;
                        if (!(fabs(v) <= FLT_MAX)) {
                            free(cand);
                            return glint_err_set(err, GLINT_ENONFINITE,
                                                 "stroke: pixel (x %d, y %d) channel %d becomes "
                                                 "%g, beyond the float range",
                                                 x, y, ch, v);
                        }
                        im->px[o + (size_t)ch] = (float)v;
                    }
                    local.pixels++;
                    if (x < local.x0) local.x0 = x;
                    if (x > local.x1) local.x1 = x;
                    if (y < local.y0) local.y0 = y;
                    if (y > local.y1) local.y1 = y;
                }
            }
        }
    }
    free(cand);
    if (local.pixels == 0) {
        local.x0 = local.y0 = 0;
        local.x1 = local.y1 = -1;
    }
    if (rep)
        *rep = local;
    return 0;
}

double stroke_cost(const stroke *s, int width, int height)
{
    double r = 0.5 * s->diameter, xmin, xmax, ymin, ymax, cost = 0.0;
    int ix0, ix1, iy0, iy1, nseg = stroke_nseg(s);

    xmin = xmax = s->pts[0];
    ymin = ymax = s->pts[1];
    for (int i = 1; i < s->npoints; i++) {
        xmin = fmin(xmin, s->pts[2 * i]);
        xmax = fmax(xmax, s->pts[2 * i]);
        ymin = fmin(ymin, s->pts[2 * i + 1]);
        ymax = fmax(ymax, s->pts[2 * i + 1]);
    }
    stroke_range(xmin - r, xmax + r, width, &ix0, &ix1);
    stroke_range(ymin - r, ymax + r, height, &iy0, &iy1);
    /* the loops of stroke_apply, counting instead of evaluating */
    for (int ty = iy0; ty <= iy1; ty += STROKE_TILE) {
        int ty1 = ty + STROKE_TILE - 1 < iy1 ? ty + STROKE_TILE - 1 : iy1;
        for (int tx = ix0; tx <= ix1; tx += STROKE_TILE) {
            int tx1 = tx + STROKE_TILE - 1 < ix1 ? tx + STROKE_TILE - 1 : ix1;
            double cx0 = tx + 0.5, cx1 = tx1 + 0.5, cy0 = ty + 0.5, cy1 = ty1 + 0.5;
            long nc = 0;
            for (int i = 0; i < nseg; i++) {
                const double *a = s->pts + 2 * i, *b = stroke_seg_b(s, i);
                nc += stroke_seg_near(a, b, r, cx0, cx1, cy0, cy1);
            }
            cost += (double)nc * (tx1 - tx + 1) * (ty1 - ty + 1);
        }
    }
    return cost;
}

double stroke_list_cost(const stroke *list, int n, int width, int height)
{
    double cost = 0.0;
    for (int i = 0; i < n; i++)
        cost += stroke_cost(&list[i], width, height);
    return cost;
}

int stroke_apply_list(const stroke *list, int n, img *im, const img *base, stroke_report *total,
                      glint_err *err)
{
    stroke_report all = {0, 0, 0, -1, -1};
    if (total)
        *total = all;
    if (n < 0 || (n > 0 && !list))
        return glint_err_set(err, GLINT_EINVAL, "stroke_apply_list: %d strokes but no list", n);
    for (int i = 0; i < n; i++) {
        stroke_report rep;
        int rc = stroke_apply(&list[i], im, base, &rep, err);
        if (rc) {
            if (err)
                glint_err_prefix(err, "strokes[%d]", i);
            return rc;
        }
        if (rep.pixels == 0)
            continue;
        if (all.pixels == 0) {
            all.x0 = rep.x0;
            all.y0 = rep.y0;
            all.x1 = rep.x1;
            all.y1 = rep.y1;
        } else {
            all.x0 = rep.x0 < all.x0 ? rep.x0 : all.x0;
            all.y0 = rep.y0 < all.y0 ? rep.y0 : all.y0;
            all.x1 = rep.x1 > all.x1 ? rep.x1 : all.x1;
            all.y1 = rep.y1 > all.y1 ? rep.y1 : all.y1;
        }
        all.pixels += rep.pixels;
    }
    if (total)
        *total = all;
    return 0;
}
