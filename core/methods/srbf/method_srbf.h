/* method_srbf.h: the srbf method: BRDF modeling under environment light
 * (Iwasaki, Dobashi, Yoshimoto and Nishita 2009), inside glint's method
 * interface (method.h).
 *
 * The painted views are lit by an environment map, compressed into lights
 * (env.h); each painted pixel is a row of the transfer matrices of eq. 6
 * (srbf.h), with the visibility of each light from each pixel cast with
 * Embree (vis.h) unless the mesh is convex; every painted view adds rows
 * to one system (the paper's footnote 1).  A fit solves eq. 17 per colour
 * channel on the Gram form with c >= 0 and energy conservation (lsq.h):
 *
 *   minimize ||T c - (b - rho_d E)||^2 + mu ||L c||^2
 *   subject to c >= 0, rho_d + g c <= 1 - SRBF_ENERGY_MARGIN at every energy
 *   direction
 *
 * where b is the painted radiance divided by the environment's intensity,
 * L the graph Laplacian of the lobe centres (a smoothness prior on p(h):
 * mu = smooth x trace(H) / J), and, with a fitted diffuse, rho_d one more
 * non-negative unknown per channel (its column E, its energy coefficient
 * 1).
 *
 * Levels (each in the cache under its own key):
 *   energy      basis, energy directions, rows g (no scene: shared by all)
 *   lights      the environment compressed (no scene: shared by all)
 *   rows        the fit's rows (pixels on the grid of `raster`), whether
 *               the mesh is convex and so whether shadows are cast
 *   transfer    visibility of each light from each row (Embree), then T
 *               (float), E, H = T'T, T'E, E'E per channel, lobes reached
 *               (kept on disk: a restart reads it instead of casting rays)
 * A repaint costs T'b over the rows and three small solves.
 *
 * Thread-safety: as method.h. */
#ifndef GLINT_METHOD_SRBF_H
#define GLINT_METHOD_SRBF_H

#include <pthread.h>
#include <stdint.h>

#include "env.h"
#include "lsq.h"
#include "material.h"
#include "method.h"
#include "srbf.h"

extern const method method_srbf;

typedef struct srbf_raster {
    int w, h;                  /* fit grid per view; 0 x 0: every sample */
} srbf_raster;

typedef struct srbf_diffuse {
    int fit;                   /* 1: fitted jointly; 0: rgb given */
    double rgb[3];
} srbf_diffuse;

typedef struct srbf_params {
    char env[ENV_NAME_MAX];
    double env_rotation;       /* degrees about +z */
    double env_intensity;
    int lights;
    int basis_res;             /* J = 3 r^2 */
    double sigma;              /* radians */
    int static_term;           /* srbf_static_kind */
    double f0;
    double alpha;
    int constraints;           /* lsq_mode */
    int visibility;            /* SRBF_VIS_* */
    srbf_raster raster;
    srbf_diffuse diffuse;
    double smooth;
    int grazing;               /* rings of energy rows near the horizon */
    int start;                 /* SRBF_START_*: where the solver starts */
} srbf_params;

enum { SRBF_VIS_AUTO = 0, SRBF_VIS_ON = 1, SRBF_VIS_OFF = 2 };

/* env_intensity: the painting is divided by it, so its range bounds what
 * the fit's values are scaled by (1e-300 made weights of 1e300, whose
 * squares overflow) */
#define SRBF_MIN_ENV_INTENSITY 1e-6
#define SRBF_MAX_ENV_INTENSITY 1e6
/* The largest weight or diffuse albedo a material holds (in either sign:
 * constraints none lets them go negative).  A fit beyond it is refused
 * (GLINT_ENUMERIC); a material file beyond it is malformed. */
#define SRBF_MAX_WEIGHT 1e30
enum { SRBF_START_WARM = 0, SRBF_START_COLD = 1 };

/* The energy rows hold the albedo to 1 - SRBF_ENERGY_MARGIN: between rows
 * (measured on a dense grid down to 0.5 degrees elevation) it rises by up
 * to 4e-4 above the rows' value, so the margin keeps it below 1
 * everywhere. */
#define SRBF_ENERGY_MARGIN 1e-3

/* The environment's and the raster's text parameters, for other methods
 * lit by the same environments (method.h's method_param.parse and format),
 * with their examples, and the visibility's values ("auto", "on", "off"). */
int srbf_env_parse(const char *text, void *field, glint_err *err);
void srbf_env_format(const void *field, char *buf, size_t len);
int srbf_raster_parse(const char *text, void *field, glint_err *err);
void srbf_raster_format(const void *field, char *buf, size_t len);
extern const char *const srbf_env_examples[];
extern const char *const srbf_raster_examples[];
extern const char *const srbf_vis_values[];

/* The parameter-table entries of the light the views were painted under
 * (env, env_rotation, env_intensity) and of self-shadowing (visibility),
 * for methods that keep srbf's environment in a member of their params:
 * OFF(m) is the offset of srbf_params' member m there (pbr_env, auto_env;
 * needs stddef.h). */
#define SRBF_ENV_LIGHT_PARAMS(OFF)                                                            \
    {.name = "env", .label = "environment", .type = METHOD_PARAM_TEXT,                        \
     .affects = "precomputation",                                                             \
     .description = "the environment lighting the painted views: a built-in (studio, sky, "   \
                    "sunset, overcast, white), data:FILE of glintd's --env-dir or upload:ID " \
                    "of POST /api/v1/environments; the command line reads a map by its path " \
                    "instead (file:PATH)",                                                    \
     .offset = OFF(env), .syntax = "NAME | builtin:NAME | data:FILE | upload:ID",             \
     .examples = srbf_env_examples, .parse = srbf_env_parse, .format = srbf_env_format},      \
    {.name = "env_rotation", .label = "environment turned (degrees)",                         \
     .type = METHOD_PARAM_NUMBER, .affects = "precomputation",                                \
     .description = "rotation of the environment about the up (+z) axis, degrees",            \
     .offset = OFF(env_rotation), .min = -360.0, .max = 360.0},                               \
    {.name = "env_intensity", .label = "environment brightness", .type = METHOD_PARAM_NUMBER, \
     .affects = "fit",                                                                        \
     .description = "scale of the environment's radiance (the painting is divided by it)",    \
     .offset = OFF(env_intensity), .min = SRBF_MIN_ENV_INTENSITY,                             \
     .max = SRBF_MAX_ENV_INTENSITY}
#define SRBF_VIS_PARAM(OFF)                                                                   \
    {.name = "visibility", .label = "self-shadowing", .group = METHOD_GROUP_ADVANCED,         \
     .type = METHOD_PARAM_ENUM, .affects = "precomputation",                                  \
     .description = "shadows of the object on itself: auto casts rays unless the mesh is "   \
                    "convex",                                                                 \
     .offset = OFF(visibility), .values = srbf_vis_values}

/* ---- level data ---------------------------------------------------------------------- */

typedef struct srbf_energy {
    srbf_basis b;
    srbf_static st;
    int nl;
    double *wo;                /* 3 nl local directions */
    double *g;                 /* nl x J */
    double seconds;
} srbf_energy;

typedef struct srbf_lightset {
    env_lights l;
    env_cut_error e;
    char name[ENV_NAME_MAX];
    long clamped, nonfinite;
    int map_w, map_h;
    double seconds;
} srbf_lightset;

typedef struct srbf_visdata {
    int nrows;
    int *rows;                 /* sample index of each row */
    int convex;                /* -1: unknown (no mesh) */
    int on;                    /* the transfer level casts shadow rays */
    double seconds;
} srbf_visdata;

#define SRBF_KEPT_MAX 4

typedef struct srbf_transfer_data {
    int nrows, J;
    float *T;                  /* 3 x nrows x J */
    double *E;                 /* nrows x 3 */
    double *H;                 /* 3 x J x J */
    double *TE;                /* 3 x J */
    double EE[3];
    unsigned char *reach;      /* J */
    int nreach;
    int *idx;                  /* nreach: the reached lobes, increasing */
    double *LtL;               /* nreach x nreach: L'L of the centres' graph Laplacian */
    /* the energy rows on the unknowns, made with idx (not stored on disk):
     * [0] the reached lobes (nl x nreach), [1] with the diffuse albedo's
     * column of ones after them (nl x (nreach + 1)); their row maxima and
     * block maxima (lsq_rows_blocks); G[1] transposed, whose first nreach
     * rows are G[0] transposed */
    double *G[2], *gmax[2], *gblk[2], *Gt;
    int nl_rows;
    /* each channel's factor of the fit's H (lsq_factor) by (smooth, diffuse
     * fitted), made by the first fit that needs it and kept with the level:
     * a repaint starts from it (srbf_kept_factor), with the H it factors
     * (a repaint reads it in place of gathering it again); and each
     * channel's last answer, where a warm repaint starts (srbf_kept_start) */
    pthread_mutex_t kept_lock;
    int kept_init, nkept;
    struct {
        double smooth;
        int fitd;
        double *R[3];
        double *H[3];
        double *c[3];
    } kept[SRBF_KEPT_MAX];
    /* each channel's last painted radiance b (nrows) and T'b on the reached
     * lobes (nreach), so that a repaint passes over the rows it changed only
     * (srbf_painted_tb); one lock per channel, taken with kept_init */
    pthread_mutex_t tb_lock[3];
    double *tb_b[3], *tb_q[3];
    int tb_updates[3];         /* incremental updates since the last full pass */
    long terms;
    long rays;                 /* shadow rays cast (0: visibility off) */
    double vis_seconds, seconds, gram_seconds;
} srbf_transfer_data;

/* ---- the material ----------------------------------------------------------------- */

typedef struct srbf_material {
    srbf_basis b;
    srbf_static st;
    double *c;                 /* 3 x J */
    double rho[3];
    float *ptab;               /* p(h) table for previews, built on first use (NULL before) */
    int ptab_n;
} srbf_material;

/* p(h) tabulated for previews (method_srbf_table.c): RGB over the
 * hemisphere of h in the local frame, on an N x N hemi-octahedral map
 * (s = u + v, t = u - v with (u, v) = (x, y) / (|x| + |y| + z)), bilinear.
 * N grows with lambda so that the interpolation error at a lobe's peak
 * stays near SRBF_TABLE_TOL relative; above SRBF_TABLE_MAX the preview
 * evaluates exactly.  Built once per material (about N^2 J exponentials),
 * thread-safe. */
#define SRBF_TABLE_TOL 5e-3
#define SRBF_TABLE_MAX 1024
int srbf_table_n(double lambda);
/* f (n.wi) like the method's eval, with p(h) from the table. */
void srbf_material_eval_preview(const srbf_material *sm, const double n[3], const double wi[3],
                                const double wo[3], double rgb[3]);

/* Make a material of method srbf (takes *sm's arrays). */
/* As hf3_material_init (method_hf3.h): *sm moved, info stolen; GLINT_ENOMEM
 * releases both and leaves a material with no data. */
int srbf_material_init(material *m, srbf_material *sm, json_t *info, glint_err *err);
/* The srbf material of m, or NULL. */
const srbf_material *srbf_material_of(const material *m);
/* Evaluate at world unit vectors (OUT rgb). */
void srbf_material_eval(const srbf_material *sm, const double n[3], const double wi[3],
                        const double wo[3], double rgb[3]);
/* Its directional albedo at a local outgoing direction, rho_d included
 * (OUT rgb). */
void srbf_material_albedo(const srbf_material *sm, const double wo[3], int nq, double rgb[3]);

extern const material_ops srbf_material_ops;
extern const char srbf_glsl_frag[];

/* Disk layer of the energy and transfer levels (method_srbf_disk.c). */
int srbf_energy_save(const char *dir, const char *key, const srbf_energy *x, glint_err *err);
int srbf_energy_load(const char *dir, const char *key, srbf_energy *x, glint_err *err);
int srbf_transfer_save(const char *dir, const char *key, const srbf_transfer_data *x,
                       glint_err *err);
int srbf_transfer_load(const char *dir, const char *key, srbf_transfer_data *x,
                       glint_err *err);
void srbf_energy_clear(srbf_energy *x);
/* The transfer level (method_srbf_transfer.c) and the shadow rays it casts
 * (method_srbf.c). */
int srbf_transfer_build(const method_build_in *in, cache_value *out, glint_err *err);
int srbf_transfer_level_load(const method_build_in *in, const char *dir, const char *key,
                       cache_value *out, glint_err *err);
int srbf_transfer_level_save(const method_build_in *in, const char *dir, const char *key,
                       const cache_value *v, glint_err *err);
int srbf_cast_shadows(const method_build_in *in, const srbf_visdata *vd, const env_lights *l,
                      uint64_t **bits, long *rays, glint_err *err);
/* idx, LtL and the energy rows of a transfer level from its reach flags
 * and the energy level. */
int srbf_transfer_reach(srbf_transfer_data *x, const srbf_energy *en, glint_err *err);
void srbf_transfer_clear(srbf_transfer_data *x);
/* The kept factor of channel ch's H (nu x nu) for (smooth, fitd), made from
 * H on first use (and a copy of H kept with it); NULL when no room is left
 * (the solver then factors per call) or memory runs out.  OUT *kept: 1 when
 * an earlier fit made it. */
const double *srbf_kept_factor(srbf_transfer_data *x, double smooth, int fitd, int ch,
                               const double *H, int nu, int *kept);
/* The H kept with that factor (nu x nu, read-only while the level lives),
 * or NULL when none is kept yet. */
const double *srbf_kept_gram(srbf_transfer_data *x, double smooth, int fitd, int ch);
/* The last answer (nu entries) kept for (smooth, fitd) and channel ch:
 * copied to c0 and 1 returned, or 0 when none is kept.  srbf_kept_answer
 * keeps c (where srbf_kept_factor made room; otherwise nothing). */
int srbf_kept_start(srbf_transfer_data *x, double smooth, int fitd, int ch, int nu, double *c0);
void srbf_kept_answer(srbf_transfer_data *x, double smooth, int fitd, int ch, int nu,
                      const double *c);
/* q = T'b on the reached lobes (nreach entries, in idx order) for channel
 * ch's painted radiance b (nrows).  Where the level keeps an earlier
 * painting of the channel that differs in at most a quarter of the rows,
 * q is the kept T'b plus T' of the differences on those rows (a stroke
 * reads a stroke's rows of T, not all of them); otherwise, and after
 * SRBF_TB_REFRESH such updates (rounding stays at a few ulps of the full
 * sum), a full pass.  b and q are kept for the next call.  Returns the rows
 * of T read. */
#define SRBF_TB_REFRESH 64
int srbf_painted_tb(srbf_transfer_data *x, int ch, const double *b, double *q);
size_t srbf_transfer_bytes(const srbf_transfer_data *x);

#endif
