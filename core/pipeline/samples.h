/* samples.h: the sample set of a scene, i.e. its fixed sampling pattern.
 *
 * A sample is a pixel of a used view that the surface covers, lit and seen:
 * mask = 1, n.wi > 0 and n.wo > 0 (pixels facing away from the light are
 * not samples: a factor of the tangent projection cannot tell a light below
 * the horizon from its mirror image).  Samples are ordered by view, then
 * row-major within a view; this is the row order of every constraint
 * matrix.  The set of views used and the raster size (through the scene
 * hash) define the pattern, and its hash keys every precomputation.
 *
 * Ownership: samples_* allocate the arrays; samples_free() releases them
 * and accepts NULL or a half-built set.  Thread-safety: no global state; a
 * sample set is read-only once built and may be shared by any number of
 * threads (the precomputation cache shares it between fits). */
#ifndef GLINT_SAMPLES_H
#define GLINT_SAMPLES_H

#include <stdint.h>

#include "err.h"
#include "gbuf.h"
#include "img.h"
#include "scene.h"

#define SAMPLES_MAX (1 << 26)
/* Which pixels are samples.  SAMPLES_LIT: mask, n.wi > 0 and n.wo > 0 (the
 * point-light methods).  SAMPLES_SEEN: mask and n.wo > 0, lit by the view's
 * light or not (methods lit by an environment); wi and cos_i are still the
 * view's light's.  The rule is part of the pattern hash. */
enum { SAMPLES_LIT = 0, SAMPLES_SEEN = 1 };

typedef struct samples {
    int n;                 /* number of samples */
    int nviews;            /* views of the scene (used or not) */
    int width, height;     /* raster size */
    unsigned char *used;   /* nviews flags: 1 if the view contributes */
    int *view;             /* n: view index */
    int *pixel;            /* n: row * width + col in that view */
    float *nrm, *wi, *wo;  /* 3n each: geometry at the sample */
    double *cos_i;         /* n: n.wi (> 0) */
    double *intensity;     /* n: the radiance scale of the sample's view: pi I
                              (scene.h's view_light_scale; a painted value is
                              intensity * f * cos_i) */
    float *pos;            /* 3n: world position (0 for imported samples: has_pos = 0) */
    float *uv;             /* 2n: the surface's texture coordinates in [0,1]^2 (the mesh's,
                              or its automatic atlas'); 0 for imported samples */
    int has_pos;           /* 1 when pos and uv hold the surface's points and coordinates */
    int rule;              /* SAMPLES_LIT (default) or SAMPLES_SEEN */
    char hash[33];         /* pattern hash: scene hash + used views + rule */
    size_t cap;            /* samples the arrays hold room for (while building) */
    void *map;             /* non-NULL: the arrays (not used) lie in this mapping of a
                              cache file (pattern_load), map_size bytes; read-only by
                              contract, unmapped by samples_free */
    size_t map_size;
} samples;

/* Were the arrays of a pattern loaded from its cache file (map) cut short
 * under the process since (cfile_map_torn)?  What was read from them may
 * be zeros then. */
int samples_torn(const samples *s);

/* Collect the samples of `nviews` gbufs.  `use` (nviews flags) selects the
 * views that take part, or NULL for all.  `scene_hash` is the scene's
 * content hash (scene_hash()).  GLINT_EINVAL if no sample results. */
int samples_build(const gbuf *g, const scene_view *views, int nviews,
                  const unsigned char *use, const char scene_hash[33],
                  samples *out, glint_err *err);

/* Building a pattern view by view, in bands of rows of a view if need be
 * (so that no more than a band of G-buffer is ever held): samples_begin,
 * then samples_add for the used views in order, each view's bands top to
 * bottom (row0: the band's first row in the view), then samples_end, which
 * marks the views flagged in `use` as used (views added are used already),
 * checks that there is a sample and computes the pattern hash.  The result
 * is exactly samples_build's.  On failure the caller samples_free()s. */
int samples_begin(samples *s, int nviews, int width, int height, glint_err *err);
/* The rule of a pattern being built (after samples_begin, before any
 * samples_add; SAMPLES_LIT unless set). */
void samples_set_rule(samples *s, int rule);
int samples_add(samples *s, int view, const gbuf *band, int row0, double intensity,
                glint_err *err);
int samples_end(samples *s, const unsigned char *use, const char scene_hash[33],
                glint_err *err);
/* Append the samples of `part` (begun with the same views, raster size and
 * rule, e.g. one view's samples made on another thread) after those of s,
 * in order, and mark part's used views as used in s: adding the views' parts
 * in view order makes exactly the pattern samples_add would.  GLINT_ERANGE
 * past SAMPLES_MAX. */
int samples_append(samples *s, const samples *part, glint_err *err);

/* The pattern hash samples_end gives a pattern of `rule` made from the scene
 * of scene_hash (may be NULL) with used[nviews] (OUT: out, 32 hex digits). */
int samples_pattern_hash(int rule, const char scene_hash[33], const unsigned char *used,
                         int nviews, char out[33], glint_err *err);

/* The samples of one G-buffer (or band), by the LIT rule and by a rule. */
long samples_count(const gbuf *g);
long samples_count_rule(const gbuf *g, int rule);

/* The samples of the views flagged in `use` out of a pattern of every view:
 * exactly the pattern samples_build would make from those views (same
 * order, same hash for the same scene_hash). */
/* The samples flagged in keep[all->n], in order (a held-out split of a
 * pattern's pixels): a pattern of its own, hashed from all's hash and
 * `tag` (samples_derived_hash), so that its precomputations are keyed
 * apart from all's.  GLINT_EINVAL when none is kept. */
int samples_pick(const samples *all, const unsigned char *keep, const char *tag, samples *out,
                 glint_err *err);
/* A 32-hex-digit hash derived from another and a tag (OUT: out). */
void samples_derived_hash(const char hash[33], const char *tag, char out[33]);

int samples_subset(const samples *all, const unsigned char *use, const char scene_hash[33],
                   samples *out, glint_err *err);

/* Read every sample's value from the paintings: one image per view (the
 * unused views' images are ignored and may be zeroed imgs), each sized like
 * the raster, with 1 (grey), 3 (RGB) or 4 (RGBA, alpha ignored) channels.
 * OUT: rgb[3 * n] (sample-major, channel-minor), divided by the view's light
 * intensity.  Non-finite values give GLINT_ENONFINITE naming the view and
 * pixel; a size mismatch GLINT_EINVAL. */
int samples_gather(const samples *s, const img *paintings, float *rgb,
                   glint_err *err);

/* The same for the samples of the views flagged in views[nviews] alone
 * (NULL: every view); the other samples' entries of rgb are left as they
 * are, and the other views' images are not looked at.  changed (NULL:
 * not asked), one flag per span of SAMPLES_SPAN samples (sample i in span
 * i / SAMPLES_SPAN): set to 1 where a value written differs in its bits
 * from the one rgb held, left alone elsewhere.  On an error some values
 * may have been written (and flagged). */
int samples_gather_views(const samples *s, const img *paintings, const unsigned char *views,
                         float *rgb, unsigned char *changed, glint_err *err);

/* Sample values kept from one read to the next (a painter's session,
 * prep_fit_reusing) are compared in spans of SAMPLES_SPAN consecutive
 * samples. */
#define SAMPLES_SPAN 1024

/* Where kept sample values changed, for whoever keeps results made from
 * them: the reads into the buffer are numbered (epoch: this read's), and
 * gen[k] is the number of the last read that changed a value of span k.
 * Results made from the values as of read e are still those of the
 * values now over every span with gen <= e.  id names the buffer's
 * history: it is new (samples_change_id) whenever values may have changed
 * without being recorded (a new buffer, a failed read), so that numbers
 * are compared only within one history. */
typedef struct samples_change {
    uint64_t id;         /* never 0 */
    uint64_t epoch;
    const uint64_t *gen; /* (n + SAMPLES_SPAN - 1) / SAMPLES_SPAN */
} samples_change;

/* A new history id: unique in the process, never 0 (thread-safe). */
uint64_t samples_change_id(void);

/* Write the samples in the reference's text format, one line per sample:
 *   view row col nx ny nz wix wiy wiz wox woy woz value
 * (value: channel `channel` of rgb, or omitted when rgb is NULL). */
int samples_export(const samples *s, const float *rgb, int channel,
                   const char *path, glint_err *err);

/* Read samples written by samples_export or by the reference
 * (hf_ref.py export-samples): '#' lines are comments; 12 geometric columns
 * after view/row/col; an optional 13th value column.  OUT: *out (width and
 * height are inferred from the largest row/col), and, when `values` is not
 * NULL, a malloc'ed array of 3 * n values (the value replicated to RGB;
 * 0 where the column is absent).  Every number is validated. */
int samples_import(const char *path, samples *out, float **values,
                   glint_err *err);

void samples_free(samples *s);

#endif
