/* stroke.h: the brush of seed 004 (section 4.3, equation 23): strokes that
 * paint a view's image, parsed from and written to JSON, applied in order.
 *
 * A stroke is a polyline of points in pixel coordinates of the view's
 * image: x to the right, y down, origin at the top-left corner of the
 * image, so pixel (column i, row j) has its centre at (i + 0.5, j + 0.5).
 * One point is a dab.  Points may lie outside the image (only the pixels
 * inside are changed).
 *
 * The brush, exactly (the browser studio reimplements it and must agree
 * within 1/255; everything below is evaluated in IEEE double precision and
 * the result stored as float):
 *
 *   d(p)  = distance from the pixel centre p to the polyline: the minimum
 *           over its segments [a, b] of |p - q| with
 *             v = b - a,  t = clamp(((p - a) . v) / (v . v), 0, 1),  q = a + t v
 *           (t = 0 when v . v = 0, i.e. a repeated point or a dab),
 *           and d = sqrt(dx*dx + dy*dy) of the closest q;
 *   w(p)  = opacity * exp(-kappa * d)   if d <= D / 2,
 *           0                           otherwise            (D: diameter);
 *   paint: B = w C + (1 - w) B'
 *   scale: B = w S B' + (1 - w) B'
 *   erase: B = w Base + (1 - w) B'
 * per channel, where B' is the pixel before the stroke and Base the view's
 * base render.  A stroke is one coverage: w is taken at the minimum
 * distance to the whole polyline (the largest weight along it), never
 * accumulated over its points or segments, so a slow stroke with many
 * points is the same as a fast one along the same path.  Strokes of a list
 * apply one after the other, each to the result of the previous one.
 *
 * Seed 004 writes the cut-off as d <= D; glint's D is the brush's diameter,
 * so the cut-off is its radius D / 2.  Colors may be negative (a negative
 * color pulls a highlight down: it removes highlights) or above 1 (HDR).
 *
 * Ownership: a stroke owns its point array; stroke_free() and
 * stroke_list_free() accept NULL and half-built strokes.
 * Thread-safety: no global state; strokes are values once parsed, and
 * applying them writes only the caller's image. */
#ifndef GLINT_STROKE_H
#define GLINT_STROKE_H

#include <jansson.h>

#include "err.h"
#include "img.h"

#define STROKE_MAX_COORD 1e6      /* |x|, |y| of a point, pixels */
#define STROKE_MAX_DIAMETER 65536.0
#define STROKE_MAX_VALUE 1e6      /* |color|, kappa, scale */
#define STROKE_TAG_MAX 64         /* bytes of the optional client tag */

typedef enum stroke_mode {
    STROKE_PAINT = 0,  /* B = w C + (1 - w) B' */
    STROKE_SCALE = 1,  /* B = w S B' + (1 - w) B' */
    STROKE_ERASE = 2   /* B = w Base + (1 - w) B' */
} stroke_mode;

typedef struct stroke {
    stroke_mode mode;
    double color[3];   /* C (paint): finite, |c| <= STROKE_MAX_VALUE */
    double diameter;   /* D, pixels: 0 < D <= STROKE_MAX_DIAMETER */
    double kappa;      /* gaussian parameter per pixel: 0 <= kappa <= STROKE_MAX_VALUE */
    double scale;      /* S (scale): 0 <= S <= STROKE_MAX_VALUE */
    double opacity;    /* in [0, 1] */
    int npoints;       /* >= 1 */
    double *pts;       /* 2 * npoints: x0 y0 x1 y1 ... (owned) */
    char tag[STROKE_TAG_MAX + 1]; /* client's tag, echoed back; "" if none */
} stroke;

/* Limits applied by the list parser. */
typedef struct stroke_limits {
    int max_strokes;   /* strokes in one list, >= 1 */
    int max_points;    /* points in one stroke, >= 1 */
} stroke_limits;

/* Parse one stroke object (`where` names it in messages, e.g.
 * "strokes[3]"):
 *   {"mode": "paint" | "scale" | "erase"   (default "paint"),
 *    "color": [r, g, b]     (required for paint; ignored otherwise),
 *    "diameter": D          (required),
 *    "kappa": k             (default 0: a hard-edged disc),
 *    "scale": S             (required for scale; ignored otherwise),
 *    "opacity": o           (default 1),
 *    "points": [[x, y], ...] (required, 1..max_points),
 *    "tag": "..."           (optional, at most STROKE_TAG_MAX bytes)}
 * Unknown keys are refused (a misspelt "opacty" must not pass silently).
 * Returns 0, or: GLINT_ERANGE only when `max_points` is exceeded (the
 * caller's limit; a server answers 413), GLINT_EFORMAT for a wrong type or
 * a missing or unknown key, GLINT_ENONFINITE for NaN or infinity,
 * GLINT_EINVAL for a value outside its range; the message names the field
 * and the value.  *out is zeroed first; on failure it holds nothing. */
int stroke_from_json(const json_t *j, const char *where, int max_points, stroke *out,
                     glint_err *err);

/* Parse an array of 1..lim->max_strokes strokes (messages name
 * "strokes[i]...").  GLINT_ERANGE when a limit is exceeded, otherwise as
 * stroke_from_json.  OUT: *list (malloc'ed, free with stroke_list_free) and
 * *n. */
int stroke_list_from_json(const json_t *arr, const stroke_limits *lim, stroke **list, int *n,
                          glint_err *err);

/* The canonical JSON of a stroke (defaults filled in, ignored fields left
 * out): stroke_from_json reads it back to the same stroke, bit for bit when
 * dumped with JSON_REAL_PRECISION(17).  New reference (caller decrefs), or
 * NULL when out of memory. */
json_t *stroke_to_json(const stroke *s);

void stroke_free(stroke *s);
void stroke_list_free(stroke *list, int n);

/* The distance d from (x, y) to the stroke's polyline, as defined above. */
double stroke_distance(const stroke *s, double x, double y);

/* The weight w at (x, y), as defined above. */
double stroke_weight(const stroke *s, double x, double y);

/* What one application did. */
typedef struct stroke_report {
    long pixels;          /* pixels with w > 0 */
    int x0, y0, x1, y1;   /* their bounding box, inclusive (x1 < x0 when none) */
} stroke_report;

/* Apply one stroke to `im` (RGB, 3 channels) in place.  `base` (same size,
 * 3 channels) is required for erase strokes and may be NULL otherwise.
 * Returns 0, GLINT_EINVAL for a bad image or a missing base, or
 * GLINT_ENONFINITE when a result overflows float (e.g. a scale stroke
 * repeated until the value exceeds FLT_MAX); the message names the pixel.
 * On failure `im` may hold a partial result: apply to a copy when that
 * matters.  rep may be NULL. */
int stroke_apply(const stroke *s, img *im, const img *base, stroke_report *rep, glint_err *err);

/* The work stroke_apply does for s on a width x height image, in distance
 * evaluations (pixels times the segments near them): at most this many,
 * computed without evaluating anything (a few operations per segment and
 * tile), so a server can refuse a request before doing it.  A one-point
 * dab of diameter D costs about D^2; a long stroke with a huge diameter
 * costs its points times the image. */
double stroke_cost(const stroke *s, int width, int height);
double stroke_list_cost(const stroke *list, int n, int width, int height);

/* Apply n strokes in order.  On failure the message names the stroke
 * ("strokes[i]: ...").  OUT: *total (may be NULL): the pixels changed,
 * summed over the strokes, and the bounding box of all of them (x1 < x0
 * and y1 < y0 when none). */
int stroke_apply_list(const stroke *list, int n, img *im, const img *base, stroke_report *total,
                      glint_err *err);

#endif
