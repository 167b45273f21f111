/* method.h: fitting methods, the one way paintings become a material.
 *
 * A method is one constant table (struct method) holding everything the
 * rest of glint needs to know about it:
 *   - its parameters (name, type, default, range, description, what a
 *     change costs), defined once and used by the daemon's API, the command
 *     line, GET /methods and the JSON Schemas in proto/ (method_param_*);
 *   - the precomputation levels it needs after the sampling pattern, each
 *     with its cache key and how to build it (and optionally keep it on
 *     disk): the cache (cache.h) and the pipeline (prep.h) run them;
 *   - the fit of one set of painted samples;
 *   - the operations on the material it produces (material_ops): CPU
 *     evaluation, GLSL for previews and exports, its files and manifest.
 * The daemon, the command line and the benchmarks reach methods only
 * through this table; adding a method is one core file defining a struct
 * method and one line in method_registry.c.
 *
 * Parameters live in a method-specific struct (params_size bytes).  Every
 * value enters through the table: method_params_from_json() (the API's
 * "params" object) and method_param_set_text() (a command-line option)
 * apply the same checks and bounds; method_params_to_json() is the one
 * canonical spelling (materials, reports, cache keys of measured points).
 *
 * Thread-safety: methods are immutable; their functions may be called from
 * any thread at once on different data.  The registry is filled once, on
 * first use, from method_registry.c (and a test build's method_extra), and
 * is read-only afterwards. */
#ifndef GLINT_METHOD_H
#define GLINT_METHOD_H

#include <jansson.h>
#include <stddef.h>
#include <stdint.h>

#include "cache.h"
#include "cancel.h"
#include "err.h"
#include "samples.h"

struct material;

/* ---- parameters ------------------------------------------------------------------ */

typedef enum {
    METHOD_PARAM_INT,    /* an int field; bounds min..max */
    METHOD_PARAM_NUMBER, /* a double field; bounds min..max (finite) */
    METHOD_PARAM_ENUM,   /* an int field holding the index of one of `values` */
    METHOD_PARAM_TEXT    /* a string with a syntax, parsed into the field by `parse` */
} method_param_type;

/* Where a parameter is offered to people: with the method (basic), or among
 * the ones most people leave alone (advanced). */
typedef enum { METHOD_GROUP_BASIC, METHOD_GROUP_ADVANCED } method_param_group;

typedef struct method_param {
    const char *name;
    const char *label;            /* its plain name for people ("texels per factor") */
    method_param_group group;
    const char *option;           /* command-line spelling when not --<name> ("reg"), or NULL */
    method_param_type type;
    const char *affects;          /* "precomputation", "operator" or "fit": what a change costs */
    const char *description;
    size_t offset;                /* of the field in the params struct */
    double min, max;              /* INT, NUMBER */
    int min_exclusive, max_exclusive;
    const char *const *values;    /* ENUM: names, NULL-terminated */
    const char *syntax;           /* TEXT: the grammar, for people */
    const char *const *examples;  /* TEXT: NULL-terminated */
    /* TEXT: parse `text` into the field (0, or a code with a message that
     * names the problem, not the parameter: callers add that), and the
     * canonical spelling of a field. */
    int (*parse)(const char *text, void *field, glint_err *err);
    void (*format)(const void *field, char *buf, size_t len);
} method_param;

/* A named set of parameters offered to users ("draft", "fine"). */
typedef struct method_preset {
    const char *name;
    const char *params;           /* JSON object text, e.g. "{\"res\": 32}" */
} method_preset;

/* ---- precomputation levels --------------------------------------------------------- */

/* What a level's key, build and disk functions see. */
typedef struct method_build_in {
    const void *params;
    const samples *s;             /* the sampling pattern */
    const struct scene *sc;       /* the scene it came from; NULL for samples made
                                     elsewhere (e.g. imported from a file) */
    const void *const *prev;      /* data of the method's levels before this one */
    int level;                    /* index of the level being made */
    /* progress of the whole preparation (stage name, fraction); may be NULL */
    void (*progress)(void *cls, const char *stage, double fraction);
    void *progress_cls;
    /* asked by long builds in their loops (cancel.h; NULL: never): a build
     * told to stop returns GLINT_ECANCELLED and leaves nothing behind */
    const glint_cancel *cancel;
} method_build_in;

typedef struct method_level {
    const char *name;             /* cache level, report and progress stage */
    double progress;              /* fraction of the preparation done when it starts */
    /* The key, from the parameters that affect this level and the key of
     * the level before (prev_key: the pattern's hash for the first level).
     * Keys are at most CACHE_KEY_MAX - 1 bytes. */
    void (*key)(const void *params, const samples *s, const char *prev_key, char *key,
                size_t len);
    int (*build)(const method_build_in *in, cache_value *out, glint_err *err);
    /* optional disk layer (see cache_level) */
    int (*load)(const method_build_in *in, const char *dir, const char *key, cache_value *out,
                glint_err *err);
    int (*save)(const method_build_in *in, const char *dir, const char *key,
                const cache_value *v, glint_err *err);
} method_level;

#define METHOD_MAX_LEVELS 16

/* ---- fit ------------------------------------------------------------------------------ */

/* What a method may keep from one fit to the next of one caller (a
 * painter's session), to spend less on views whose paintings did not
 * change (prep_fit_reusing): the method's own data, freed by its own
 * function.  A fit that finds another method's data there clears it first.
 * One fit at a time per memo. */
typedef struct method_memo {
    const struct method *owner;
    void *data;
    void (*free)(void *data);
    /* The painted values of the last fit's samples, kept by
     * prep_fit_reusing (methods leave them alone): 3 values_n floats of the
     * pattern named values_key, view v's samples holding the values of the
     * painting tagged values_tags[v] where values_ok[v]; a fit reads again
     * only the views whose tags changed.  values_gen, values_epoch and
     * values_id record where the values changed from one read to the next
     * (samples_change: values_gen per span of SAMPLES_SPAN samples). */
    float *values;
    uint64_t *values_tags;
    unsigned char *values_ok;
    char *values_key;
    int values_n, values_nviews;
    uint64_t *values_gen;
    uint64_t values_epoch, values_id;
} method_memo;

/* Free everything and zero *mm (accepts NULL and a zeroed memo). */
void method_memo_clear(method_memo *mm);

/* Free the method's data alone (owner, data, free), keeping the values:
 * what a method does when it finds another method's data there. */
void method_memo_drop_data(method_memo *mm);

/* Free the values alone and zero their fields. */
void method_memo_drop_values(method_memo *mm);

/* What a fit sees: the prepared levels and the painted values. */
typedef struct method_fit_in {
    const void *params;
    const samples *s;             /* the sampling pattern */
    const float *rgb;             /* 3 s->n painted values over their sample's
                                     intensity (sample-major): f cos_i */
    const void *const *levels;    /* data of each level */
    const char *const *keys;      /* key of each level */
    const cache_how *how;         /* how this fit's preparation got each level */
    const double *spent;          /* seconds it spent on each (building or waiting) */
    const cache_disk *disk;       /* what the disk layer answered when each was made */
    double pattern_seconds;       /* seconds it spent on the pattern (0 when in memory) */
    /* Optional (NULL: none): the caller's memo, and per view (s->nviews) a
     * tag naming its painting: equal tags in two fits promise equal
     * paintings of that view, so equal rgb over its samples (a method may
     * then reuse what it kept).  A method that fits another on samples or
     * values of its own making (maps, auto) passes it neither. */
    method_memo *memo;
    const uint64_t *view_tags;
    /* Optional, with memo: where the painted values changed since earlier
     * fits through this memo, span by span (samples.h), so that a method
     * may reuse what it kept for samples whose values did not change even
     * in a repainted view (a brush stroke changes a few spans). */
    const samples_change *values_change;
    /* Optional (NULL: none), for methods with method.fits_held: per sample
     * of s, 1 where the fit leaves the sample's value out (it is held out
     * to judge the material on); its value is then never read, and the
     * errors the fit reports are over the others.  The levels are those of
     * every sample, so predict gives the held-out ones their values. */
    const unsigned char *held;
} method_fit_in;

/* ---- the material ------------------------------------------------------------------------ */

#define MATERIAL_GPU_MAX_UNIFORMS 12

typedef struct material_gpu_uniform {
    const char *name;             /* "u_res" */
    const char *type;             /* "int", "float" or "vec3" */
    double v[3];                  /* the value (an int in v[0]) */
    const char *meaning;
} material_gpu_uniform;

/* How the GPU evaluates a material: a fragment stage that defines
 * `vec3 glint_material(vec3 n, vec3 wi, vec3 wo)` and shades with it (the
 * renderer sets u_eye, u_light, u_light_intensity and feeds v_pos, v_nrm,
 * v_uv from the shared vertex stage), at most one float texture, and
 * constant uniforms.  Filled by material_ops.gpu; release with
 * material_gpu_free(). */
typedef struct material_gpu {
    const char *program;          /* one compiled program per name ("hf3") */
    const char *frag_src;         /* static text of the method */
    const char *tex_uniform;      /* sampler name; NULL when there is no texture */
    int tex_w, tex_h;
    float *tex;                   /* RGB float, row-major, row 0 first (malloc'ed) */
    int nuniforms;
    material_gpu_uniform uniform[MATERIAL_GPU_MAX_UNIFORMS];
    json_t *manifest;             /* method members of shader.json (owned) */
} material_gpu;

void material_gpu_free(material_gpu *g);

typedef struct material_ops {
    /* The material at the surface point with texture coordinates uv (NULL:
     * its average over the surface; ignored by materials that do not vary)
     * and unit vectors (OUT rgb[3], per unit light): 0 unless n.wi > 0 and
     * n.wo > 0. */
    void (*eval)(const void *data, const double uv[2], const double n[3], const double wi[3],
                 const double wo[3], double rgb[3]);
    /* Optional: the same for previews, faster and approximate (the method
     * states its error); NULL: eval.  May build caches inside data on
     * first use, safely from several threads. */
    void (*eval_preview)(const void *data, const double uv[2], const double n[3],
                         const double wi[3], const double wo[3], double rgb[3]);
    /* 1 when the material varies over the surface (reads uv). */
    int spatial;
    void (*free)(void *data);
    /* Write the method's members of material.json into `manifest`. */
    int (*to_json)(const void *data, json_t *manifest, glint_err *err);
    /* Read them back (validated; `file` names the source in messages). */
    int (*from_json)(const json_t *manifest, const char *file, void **data, glint_err *err);
    /* Files beside material.json (may add members to `manifest`).  With
     * derived_files set, dir may be NULL: add the manifest's members only. */
    int (*save_files)(const void *data, const char *dir, json_t *manifest, glint_err *err);
    /* Optional: the names of the files save_files writes, NULL-terminated,
     * when each is a pure function of material.json (what from_json reads
     * back).  material_save_deferred then leaves them to be written on first
     * use (material_files_ensure).  NULL: written with the manifest. */
    const char *const *derived_files;
    int (*gpu)(const void *data, material_gpu *out, glint_err *err);
    /* A few members for the API's material object (e.g. {"res": 64}). */
    json_t *(*summary)(const void *data);
    /* Optional: the material as BRDF Explorer's analytic .brdf text, exact
     * (OUT: *text, free()); NULL: not offered (the MERL table is). */
    int (*brdf_explorer)(const void *data, char **text, glint_err *err);
} material_ops;

/* ---- the method ------------------------------------------------------------------------- */

/* Where a fit's samples come from, for the checks of its parameters made
 * before any work (method_params_usable). */
typedef struct method_source {
    int has_mesh;                 /* a scene's mesh and the samples' positions are there (not
                                     so for samples made elsewhere: a G-buffer set) */
} method_source;

/* The light the painted views are seen under, as a fit reads them. */
typedef enum {
    METHOD_LIGHT_POINT,           /* each view's point light */
    METHOD_LIGHT_ENV              /* an environment (the `env` parameter) */
} method_lighting;

/* What the studio's Factors tab can draw of a material, besides its files. */
typedef enum {
    METHOD_SHOWS_NONE,            /* nothing beyond the renders */
    METHOD_SHOWS_FACTORS,         /* factors.png: three rows (p, q, r) per product */
    METHOD_SHOWS_LOBES            /* the manifest's lobes over the half vector */
} method_shows;

typedef struct method {
    const char *name;             /* "hf3": [a-z0-9_-], at most 15 bytes */
    const char *title;
    /* For people who do not know the methods' names: */
    const char *label;            /* a plain-language name ("one material, point light") */
    const char *summary;          /* one line: what it models */
    const char *when;             /* one line: when to use it */
    method_lighting lighting;     /* what the painted views must be lit by */
    method_shows shows;           /* what of a material can be drawn */
    /* The textures over the surface a material holds (NULL-terminated;
     * NULL: none): "coefficients" (where each of several materials is,
     * coefficients.exr) and "spatial" (how a material's colour varies,
     * spatial.exr). */
    const char *const *surface;
    int fits_held;                /* 1: fit honours method_fit_in.held */
    int chooses;                  /* 1: fits other methods and keeps the one the painting
                                     needs (the studio starts on it) */
    const char *reference;        /* the paper, or NULL */
    const char *description;
    const char *held_out;         /* how the held-out error is measured, for people */
    const char *schema;           /* file in proto/schemas of its params ("FitParams.json") */
    size_t params_size;
    const method_param *params;
    int nparams;
    const method_preset *presets;
    int npresets;
    void (*params_default)(void *params);
    /* Checks across parameters after they were set (may be NULL). */
    int (*params_check)(const void *params, glint_err *err);
    /* Checks of the parameters against what lies outside them, cheap and
     * made before a fit is queued (may be NULL): what they name exists (an
     * environment the host resolves) and the samples' source offers what
     * they need (a mesh to cast shadows with).  0, or a code with a message
     * that names the problem, not the parameter: OUT *param names that. */
    int (*params_usable)(const void *params, const method_source *src, const char **param,
                         glint_err *err);
    /* Optional (NULL: always): 0 when this host can fit the method at all,
     * else a code with a message saying what the host lacks (tab_prior
     * without the measured materials' fits).  Cheap; GET /methods says it
     * (method_describe), and the API refuses a fit of such a method before
     * any work (422 method-unavailable). */
    int (*available)(glint_err *why);
    /* Which pixels are samples (samples.h: SAMPLES_LIT, the default 0, or
     * SAMPLES_SEEN for methods lit by an environment). */
    int pattern_rule;
    const method_level *levels;
    int nlevels;
    int (*fit)(const method_fit_in *in, struct material *out, glint_err *err);
    /* Optional: the painted values the method's own model gives the
     * pattern's samples with material m (fitted by this method), from the
     * levels of a preparation of those samples (in->rgb unused): OUT
     * rgb[3 n], NaN where the method models no value.  What a held-out
     * error compares with the painting (NULL: the material evaluated under
     * each sample's point light, times its intensity). */
    int (*predict)(const method_fit_in *in, const struct material *m, float *rgb,
                   glint_err *err);
    const material_ops *mat;
    /* Whether a held-out measurement (one precomputation per painted view,
     * or one of every view with fits_held; in the background) is affordable
     * with these parameters (NULL: yes). */
    int (*holdout_ok)(const void *params);
    /* An upper bound of the memory a fit with these parameters takes for
     * nsamples samples, every level built (pattern included), in bytes: what
     * a service admits a cold fit by (NULL: METHOD_FIT_BYTES_PER_SAMPLE per
     * sample). */
    size_t (*fit_bytes)(const void *params, long nsamples);
    /* An estimate of the time a cold fit with these parameters takes for
     * nsamples samples, every level built (pattern included), in seconds of
     * one core at the rates below: what a service refuses a fit by before
     * it starts (NULL: METHOD_SECONDS_PER_SAMPLE per sample).  An estimate
     * from the parameters, not a bound: it is right within a small factor
     * (the method's comment says how it was checked). */
    double (*fit_seconds)(const void *params, long nsamples);
} method;

/* The default of method.fit_bytes, per sample. */
#define METHOD_FIT_BYTES_PER_SAMPLE 512

/* m->fit_bytes, or the default. */
size_t method_fit_bytes(const method *m, const void *params, long nsamples);

/* Rates of the fit estimates, in seconds of one core, measured through
 * glintd on the 2-vCPU development machine (cold fits of a 128 x 128 torus,
 * 3 views, 18,476 samples; the levels' build_seconds):
 *   METHOD_SECONDS_PER_SAMPLE  the passes over the samples: rasterizing the
 *                              pattern (5.4 us a sample), designs, gathers;
 *   METHOD_SECONDS_PER_FLOP    a dense factorization of n unknowns counted as
 *                              n^3 (hf3 res 512, 1536 unknowns: decomposition
 *                              and operator 6.7 s, 1.8 ns per n^3). */
#define METHOD_SECONDS_PER_SAMPLE 1e-5
#define METHOD_SECONDS_PER_FLOP 2e-9

/* m->fit_seconds, or the default. */
double method_fit_seconds(const method *m, const void *params, long nsamples);

/* The estimate of factorizing n unknowns densely (n^3 at
 * METHOD_SECONDS_PER_FLOP), for methods' fit_seconds. */
double method_dense_seconds(double n);

/* ---- the registry ------------------------------------------------------------------------ */

/* The i-th method (0: the default), NULL past the end. */
const method *method_at(int i);
int method_count(void);
/* By name; NULL when unknown. */
const method *method_find(const char *name);
/* The names, comma-separated, for messages (OUT: buf). */
void method_names(char *buf, size_t len);

/* ---- parameters through the table --------------------------------------------------------- */

/* A params struct with the method's defaults (malloc'ed; free()). NULL when
 * out of memory. */
void *method_params_new(const method *m);

const method_param *method_param_find(const method *m, const char *name);

/* Set one parameter from JSON (the API).  Messages name it
 * "params.<name>".  Unknown names give GLINT_EINVAL naming the known ones. */
int method_param_set_json(const method *m, void *params, const char *name, const json_t *v,
                          glint_err *err);

/* Set every member of a JSON object, then run the cross checks.  A non-object
 * gives GLINT_EINVAL ("params must be an object"). */
int method_params_from_json(const method *m, void *params, const json_t *obj, glint_err *err);

/* m->params_usable (0 when the method has none): GLINT_EINVAL with a
 * message naming the parameter "params.<name>", as the API spells it. */
int method_params_usable(const method *m, const void *params, const method_source *src,
                         glint_err *err);

/* m->available (0 when the method has none): 0, or the code and message
 * saying why this host cannot fit m. */
int method_available(const method *m, glint_err *why);

/* Set one parameter from text (the command line: messages name it
 * "--<name> '<text>'"). */
int method_param_set_text(const method *m, void *params, const char *name, const char *text,
                          glint_err *err);

/* Every parameter with its canonical value (a new object). */
json_t *method_params_to_json(const method *m, const void *params);

/* A method's errors by painted view: the "rms_by_view" member of its
 * "errors" object, [{"view": k, "rms": x, "samples": n}, ...] for the views
 * with samples, ascending k.  se[k]: the sum of squared residuals of view
 * k's samples over their three channels, n[k]: its samples (nviews each);
 * rms = sqrt(se / (3 n)), as rms_painted is of the sums over every view.
 * A new array, NULL when out of memory. */
json_t *method_rms_by_view(const double *se, const long *n, int nviews);

/* The canonical text of one parameter (OUT: buf). */
void method_param_format(const method_param *p, const void *params, char *buf, size_t len);

/* The method described for GET /methods: name, title, label, summary,
 * when, lighting ("point" or "environment"), varies (over the surface),
 * surface, shows, chooses, reference, description, params (with plain
 * names, groups, defaults and ranges), presets, held_out, available (and
 * unavailable: why not, when this host cannot fit it) (a new object). */
json_t *method_describe(const method *m);

/* A JSON Schema (draft 2020-12) of the method's params object, as proto/
 * keeps it (a new object). */
json_t *method_params_schema(const method *m);

#endif
