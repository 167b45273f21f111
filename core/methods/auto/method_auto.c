/* method_auto.c: "auto", the model a painting requires (method_auto.h). */
#include "method_auto.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "method_hf2d.h"
#include "method_hf3.h"
#include "method_hf4.h"
#include "method_hybrid.h"
#include "method_maps.h"
#include "scene.h"

static const method_param auto_params_table[] = {
    {.name = "res", .label = "detail", .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "texels per 1D factor of every candidate; 0: each at the settings a fit "
                    "of its own would have (hf3 and maps 128, hf4, hybrid and hf2d 32)",
     .offset = offsetof(auto_params, res), .min = 0, .max = HF_RES_MAX},
    {.name = "s_res", .label = "colour texture size", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes per side of the spatial factor of the four-factor candidates "
                    "(hf4, hybrid); 0: hf4's own (32)",
     .offset = offsetof(auto_params, sres), .min = 0, .max = HF4_SRES_MAX},
    {.name = "res_2d", .label = "detail of a 2D factor", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "nodes per side of the 2D q of the anisotropic candidate (hf2d); 0: its "
                    "own (32)",
     .offset = offsetof(auto_params, res_2d), .min = 0, .max = HF2D_SRES_MAX},
    {.name = "components", .label = "materials, at most", .type = METHOD_PARAM_INT, .affects = "fit",
     .description = "at most this many products in the material-maps candidates (maps, "
                    "hybrid); 0: their own (5 and 4)",
     .offset = offsetof(auto_params, components), .min = 0, .max = MATMAP_MAX},
    {.name = "threshold", .label = "how much better a richer model must be", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "a richer model is taken only when it lowers the held-out RMS by more "
                    "than this fraction of the current choice's",
     .offset = offsetof(auto_params, threshold), .min = 0.0, .max = 1.0},
    {.name = "floor", .label = "smallest gain that counts", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "nor by less than this (held-out RMS, per unit light): below it a gain is "
                    "within an 8-bit painting's quantization",
     .offset = offsetof(auto_params, floor), .min = 0.0, .max = 1.0},
    {.name = "every", .label = "views held out (one in)", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "one painted view in this many (one pixel, when one view is painted) is "
                    "held out to judge the candidates, which are fitted to the rest",
     .offset = offsetof(auto_params, every), .min = 2, .max = 64},
};

static const method_preset auto_presets[] = {
    {"draft", "{\"res\": 32, \"s_res\": 16, \"res_2d\": 16, \"components\": 3}"},
    {"default", "{}"},
};

static void auto_params_default(void *params)
{
    auto_params *p = params;
    memset(p, 0, sizeof *p);
    /* 0: every candidate at the settings a fit of its own would have, so the
     * choice is never a cheaper model than the one it is compared with
     * (maps shares hf3's decomposition and hybrid hf4's, so those two run
     * at their partner's resolution, which is at least their own) */
    p->res = 0;
    p->sres = 0;
    p->res_2d = 0;
    p->components = 0;
    p->threshold = 0.1;
    p->floor = 1.0 / 255.0 / 4.0;
    p->every = 4;
}

/* A resolution given (not 0) must be one its candidates take. */
static int auto_params_check(const void *params, glint_err *err)
{
    const auto_params *p = params;
    if (p->res && p->res < HF_RES_MIN)
        return glint_err_set(err, GLINT_EINVAL, "params.res must be 0 or in %d..%d", HF_RES_MIN,
                             HF_RES_MAX);
    if (p->sres && p->sres < HF4_SRES_MIN)
        return glint_err_set(err, GLINT_EINVAL, "params.s_res must be 0 or in %d..%d",
                             HF4_SRES_MIN, HF4_SRES_MAX);
    if (p->res_2d && p->res_2d < HF2D_SRES_MIN)
        return glint_err_set(err, GLINT_EINVAL, "params.res_2d must be 0 or in %d..%d",
                             HF2D_SRES_MIN, HF2D_SRES_MAX);
    return 0;
}

/* The candidates' parameters. */
typedef struct cands {
    fit_params fp;
    hf2d_params_t dp;
    hf4_params_t hp;
    maps_params mp;
    hybrid_params yp;
} cands;

static void candidates(const auto_params *p, cands *c)
{
    fit_params_default(&c->fp);
    if (p->res)
        c->fp.res = p->res;
    method_hf2d.params_default(&c->dp); /* q 2D, p and r 1D */
    if (p->res)
        c->dp.res = p->res;
    if (p->res_2d)
        c->dp.sres = p->res_2d;
    method_hf4.params_default(&c->hp);
    if (p->res)
        c->hp.res = p->res;
    if (p->sres)
        c->hp.sres = p->sres;
    method_maps.params_default(&c->mp);
    c->mp.hf = c->fp; /* hf3's decomposition serves the maps' products */
    if (p->components)
        c->mp.components = p->components;
    method_hybrid.params_default(&c->yp);
    c->yp.h = c->hp; /* hf4's decomposition serves the hybrid's products */
    if (p->components)
        c->yp.components = p->components;
}

/* ---- levels: the split, each candidate's precomputation on the kept pixels, then on all -- */

/* auto's levels: the split; hf3's two and hf4's one on the kept pixels;
 * hf3's two and hf4's one on every sample; hf2d's one on the kept pixels
 * and on every sample */
enum { LV_SPLIT, LV_HF3, LV_HF4 = 3, LV_FULL_HF3, LV_FULL_HF4 = 6, LV_HF2D, LV_FULL_HF2D,
       LV_N };

typedef struct split {
    samples train;
    unsigned char *held;   /* per sample of the pattern: 1 held out */
    int nheld;
    int by_views;          /* 1: whole views held out; 0: pixels */
    unsigned char held_view[SCENE_MAX_VIEWS];
} split;

/* Held out by pixel (one view painted): tiles of HELD_TILE x HELD_TILE
 * pixels, one in `every` by a hash of the tile, so the split is the same
 * for every painting of a pattern and a spatial model cannot fill a held
 * pixel from painted neighbours a pixel away. */
#define HELD_TILE 8
static int pixel_held(int view, int pixel, int width, int every)
{
    unsigned h = (unsigned)view << 24 ^ (unsigned)(pixel / width / HELD_TILE) << 12 ^
                 (unsigned)(pixel % width / HELD_TILE);
    h ^= h >> 16; /* murmur3's finalizer */
    h *= 0x85ebca6bu;
    h ^= h >> 13;
    h *= 0xc2b2ae35u;
    h ^= h >> 16;
    return h % (unsigned)every == 0;
}

static void split_free(void *data)
{
    split *x = data;
    samples_free(&x->train);
    free(x->held);
    free(x);
}

static void split_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    (void)prev_key;
    snprintf(key, len, "auto-split:%s:%d", s->hash, ((const auto_params *)params)->every);
}

static int split_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    const auto_params *p = in->params;
    const samples *s = in->s;
    split *x = calloc(1, sizeof *x);
    unsigned char *keep = NULL;
    char tag[32];
    int rc;
    if (!x || !(x->held = malloc((size_t)s->n)) || !(keep = malloc((size_t)s->n))) {
        free(keep);
        if (x)
            free(x->held);
        free(x);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    {
        /* whole views when two or more are painted: one in `every` of them,
         * at least one, at most all but one; else one pixel in `every` */
        /* views that hold samples: a painted view whose pixels are all
         * unlit or hidden is no measure */
        int used[SCENE_MAX_VIEWS], nu = 0, nh = 0;
        unsigned char has[SCENE_MAX_VIEWS] = {0};
        for (int i = 0; i < s->n; i++)
            if (s->view[i] >= 0 && s->view[i] < SCENE_MAX_VIEWS)
                has[s->view[i]] = 1;
        for (int v = 0; v < s->nviews && v < SCENE_MAX_VIEWS; v++)
            if (s->used[v] && has[v])
                used[nu++] = v;
        x->by_views = nu >= 2;
        for (int k = 0; k < nu && x->by_views; k++)
            if (k % p->every == p->every / 2 || (nh == 0 && k == nu - 1)) {
                x->held_view[used[k]] = 1;
                nh++;
            }
        for (int i = 0; i < s->n; i++) {
            x->held[i] = (unsigned char)(x->by_views ? x->held_view[s->view[i]]
                                                     : pixel_held(s->view[i], s->pixel[i],
                                                                  s->width, p->every));
            keep[i] = !x->held[i];
            x->nheld += x->held[i];
        }
    }
    snprintf(tag, sizeof tag, "auto-train-%d", p->every);
    if (x->nheld < 1 || x->nheld == s->n)
        rc = glint_err_set(err, GLINT_EINVAL,
                           "%d painted samples are too few to hold one in %d out: paint more "
                           "views or use a method directly", s->n, p->every);
    else
        rc = samples_pick(s, keep, tag, &x->train, err);
    free(keep);
    if (rc) {
        free(x->held);
        free(x);
        return rc;
    }
    out->data = x;
    out->bytes = sizeof *x + (size_t)s->n + (size_t)x->train.n * 80;
    out->free = split_free;
    return 0;
}

/* A candidate level: its method's level k, built on the kept pixels. */
static int candidate_build(const method_build_in *in, const method *m, int k,
                           const void *const *prev, const void *params, cache_value *out,
                           glint_err *err)
{
    method_build_in c = *in;
    c.params = params;
    c.s = &((const split *)in->prev[0])->train;
    c.prev = prev;
    c.level = k;
    return m->levels[k].build(&c, out, err);
}

static void hf3d_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    const auto_params *p = params;
    cands cs;
    candidates(p, &cs);
    snprintf(key, len, "%s/hf3:%d:%.17g:%d:%.17g", prev_key, cs.fp.res, cs.fp.lambda,
             (int)cs.fp.route, cs.fp.rcond);
    (void)s;
}

static int hf3d_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return candidate_build(in, &method_hf3, 0, NULL, &cs.fp, out, err);
}

static void hf3o_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    (void)params;
    (void)s;
    snprintf(key, len, "%s/operator", prev_key);
}

static int hf3o_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return candidate_build(in, &method_hf3, 1, in->prev + 1, &cs.fp, out, err);
}

static void hf4d_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    const auto_params *p = params;
    cands cs;
    const char *split_key_end = strchr(prev_key, '/');
    candidates(p, &cs);
    /* keyed from the split, not from hf3's levels before it */
    snprintf(key, len, "%.*s/hf4:%d:%d:%.17g:%.17g:%.17g",
             split_key_end ? (int)(split_key_end - prev_key) : (int)strlen(prev_key), prev_key,
             cs.hp.res, cs.hp.sres, cs.hp.lambda, cs.hp.lambda_s, cs.hp.rcond);
    (void)s;
}

static int hf4d_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return candidate_build(in, &method_hf4, 0, NULL, &cs.hp, out, err);
}

/* The full pattern's levels: the chosen candidate is refitted to every
 * painted sample.  Keyed and built exactly as hf3 and hf4 key and build
 * their own (the disk layer too), so they are the same cache entries as a
 * direct hf3 or hf4 fit of these views. */
static int full_build(const method_build_in *in, const method *m, int k, const void *const *prev,
                      const void *params, cache_value *out, glint_err *err)
{
    method_build_in c = *in;
    c.params = params;
    c.prev = prev;
    c.level = k;
    return m->levels[k].build(&c, out, err);
}

static void fhf3d_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    cands cs;
    candidates(params, &cs);
    method_hf3.levels[0].key(&cs.fp, s, prev_key, key, len);
}

static int fhf3d_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_build(in, &method_hf3, 0, NULL, &cs.fp, out, err);
}

/* A candidate method's disk layer under auto's params: its own params. */
static int full_load(const method_build_in *in, const method *m, const void *params,
                     const char *dir, const char *key, cache_value *out, glint_err *err)
{
    method_build_in c = *in;
    c.params = params;
    c.prev = NULL;
    return m->levels[0].load(&c, dir, key, out, err);
}

static int full_save(const method_build_in *in, const method *m, const void *params,
                     const char *dir, const char *key, const cache_value *v, glint_err *err)
{
    method_build_in c = *in;
    c.params = params;
    c.prev = NULL;
    return m->levels[0].save(&c, dir, key, v, err);
}

static int fhf3d_load(const method_build_in *in, const char *dir, const char *key,
                      cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_load(in, &method_hf3, &cs.fp, dir, key, out, err);
}

static int fhf3d_save(const method_build_in *in, const char *dir, const char *key,
                      const cache_value *v, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_save(in, &method_hf3, &cs.fp, dir, key, v, err);
}

static int fhf4d_load(const method_build_in *in, const char *dir, const char *key,
                      cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_load(in, &method_hf4, &cs.hp, dir, key, out, err);
}

static int fhf4d_save(const method_build_in *in, const char *dir, const char *key,
                      const cache_value *v, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_save(in, &method_hf4, &cs.hp, dir, key, v, err);
}

static void fhf3o_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    cands cs;
    candidates(params, &cs);
    method_hf3.levels[1].key(&cs.fp, s, prev_key, key, len); /* prev: the full decomposition */
}

static int fhf3o_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_build(in, &method_hf3, 1, in->prev + LV_FULL_HF3, &cs.fp, out, err);
}

static void fhf4d_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    cands cs;
    candidates(params, &cs);
    method_hf4.levels[0].key(&cs.hp, s, prev_key, key, len);
}

static int fhf4d_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_build(in, &method_hf4, 0, NULL, &cs.hp, out, err);
}

static void hf2dd_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    cands cs;
    char own[CACHE_KEY_MAX], sk[CACHE_KEY_MAX];
    candidates(params, &cs);
    /* keyed from the split (the level before is the full hf4 decomposition,
     * whose key does not name it): the split's key, then hf2d's own */
    split_key(params, s, prev_key, sk, sizeof sk);
    method_hf2d.levels[0].key(&cs.dp, s, prev_key, own, sizeof own);
    snprintf(key, len, "%s/%s", sk, own);
}

static int hf2dd_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return candidate_build(in, &method_hf2d, 0, NULL, &cs.dp, out, err);
}

static void fhf2dd_key(const void *params, const samples *s, const char *prev_key, char *key,
                       size_t len)
{
    cands cs;
    candidates(params, &cs);
    method_hf2d.levels[0].key(&cs.dp, s, prev_key, key, len);
}

static int fhf2dd_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_build(in, &method_hf2d, 0, NULL, &cs.dp, out, err);
}

static int fhf2dd_load(const method_build_in *in, const char *dir, const char *key,
                       cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_load(in, &method_hf2d, &cs.dp, dir, key, out, err);
}

static int fhf2dd_save(const method_build_in *in, const char *dir, const char *key,
                       const cache_value *v, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_save(in, &method_hf2d, &cs.dp, dir, key, v, err);
}

static const method_level auto_levels[] = {
    {.name = "split", .progress = 0.05, .key = split_key, .build = split_build},
    {.name = "decomposition", .progress = 0.1, .key = hf3d_key, .build = hf3d_build},
    {.name = "operator", .progress = 0.2, .key = hf3o_key, .build = hf3o_build},
    {.name = "spatial decomposition", .progress = 0.3, .key = hf4d_key, .build = hf4d_build},
    {.name = "full decomposition", .progress = 0.5, .key = fhf3d_key, .build = fhf3d_build,
     .load = fhf3d_load, .save = fhf3d_save},
    {.name = "full operator", .progress = 0.6, .key = fhf3o_key, .build = fhf3o_build},
    {.name = "full spatial decomposition", .progress = 0.7, .key = fhf4d_key,
     .build = fhf4d_build, .load = fhf4d_load, .save = fhf4d_save},
    {.name = "anisotropic decomposition", .progress = 0.75, .key = hf2dd_key,
     .build = hf2dd_build},
    {.name = "full anisotropic decomposition", .progress = 0.85, .key = fhf2dd_key,
     .build = fhf2dd_build, .load = fhf2dd_load, .save = fhf2dd_save},
};

/* ---- the fit ------------------------------------------------------------------------ */

#define NCAND 5 /* hf3, hf2d, hf4, maps, hybrid: cheapest first */

/* The held-out RMS of material m: per unit light, RGB, over the held
 * samples. */
static double held_rms(const material *m, const samples *s, const split *x, const float *rgb)
{
    double ss = 0.0;
    long cnt = 0;
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], uv[2], v[3];
        if (!x->held[i])
            continue;
        for (int c = 0; c < 3; c++) {
            n[c] = s->nrm[3 * (size_t)i + c];
            wi[c] = s->wi[3 * (size_t)i + c];
            wo[c] = s->wo[3 * (size_t)i + c];
        }
        uv[0] = s->uv ? s->uv[2 * (size_t)i] : 0.0;
        uv[1] = s->uv ? s->uv[2 * (size_t)i + 1] : 0.0;
        material_eval_at(m, s->uv ? uv : NULL, n, wi, wo, v);
        for (int c = 0; c < 3; c++) {
            double d = v[c] - rgb[3 * (size_t)i + c];
            ss += d * d;
        }
        cnt++;
    }
    return cnt ? sqrt(ss / (3.0 * cnt)) : 0.0;
}

/* Fit method m (params mp) to samples s, values rgb, with auto's levels
 * from `base` (hf3's two, or hf4's one). */
static int fit_on(const method_fit_in *in, const method *m, const void *mp, const samples *s,
                  const float *rgb, int base, material *out, glint_err *err)
{
    method_fit_in ci = *in;
    const void *lv[2];
    const char *ky[2];
    cache_how how[2];
    double spent[2];
    cache_disk disk[2];
    int nl = m->nlevels < 2 ? m->nlevels : 2;
    for (int l = 0; l < nl; l++) {
        lv[l] = in->levels[base + l];
        ky[l] = in->keys[base + l];
        how[l] = in->how[base + l];
        spent[l] = in->spent[base + l];
        disk[l] = in->disk[base + l];
    }
    ci.params = mp;
    ci.s = s;
    ci.rgb = rgb;
    ci.memo = NULL; /* samples and values of auto's own choosing */
    ci.view_tags = NULL;
    ci.levels = lv;
    ci.keys = ky;
    ci.how = how;
    ci.spent = spent;
    ci.disk = disk;
    return m->fit(&ci, out, err);
}

static int auto_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const auto_params *p = in->params;
    const split *x = in->levels[0];
    const samples *s = in->s, *tr = &x->train;
    cands cs;
    float *trgb = NULL;
    material cand[NCAND];
    const method *ms[NCAND] = {&method_hf3, &method_hf2d, &method_hf4, &method_maps,
                               &method_hybrid};
    const void *ps[NCAND] = {&cs.fp, &cs.dp, &cs.hp, &cs.mp, &cs.yp};
    /* each candidate's levels on the kept pixels and on every sample (maps
     * reuses hf3's, hybrid hf4's) */
    static const int train_lv[NCAND] = {LV_HF3, LV_HF2D, LV_HF4, LV_HF3, LV_HF4};
    static const int full_lv[NCAND] = {LV_FULL_HF3, LV_FULL_HF2D, LV_FULL_HF4, LV_FULL_HF3,
                                       LV_FULL_HF4};
    double held[NCAND], secs[NCAND], t0 = glint_now();
    int chosen = 0, rc = 0;
    json_t *list, *choice;

    memset(out, 0, sizeof *out);
    memset(cand, 0, sizeof cand);
    candidates(p, &cs);
    /* coefficient texels no more than a sixteenth of the samples: finer
     * textures hold texels that few samples reach, fitted to the painted
     * views' own residuals (tests/unit/test_auto.c) */
    cs.mp.map_res = (int)floor(sqrt(tr->n / 16.0));
    cs.mp.map_res = cs.mp.map_res < 8 ? 8 : cs.mp.map_res > 128 ? 128 : cs.mp.map_res;
    cs.yp.map_res = cs.mp.map_res;
    if (!(trgb = malloc(3 * (size_t)tr->n * sizeof *trgb)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int i = 0, k = 0; i < s->n; i++)
        if (!x->held[i]) {
            memcpy(trgb + 3 * (size_t)k, in->rgb + 3 * (size_t)i, 3 * sizeof *trgb);
            k++;
        }
    for (int c = 0; c < NCAND; c++) {
        secs[c] = glint_now();
        if ((rc = fit_on(in, ms[c], ps[c], tr, trgb, train_lv[c], &cand[c], err))) {
            glint_err_prefix(err, "auto, candidate %s", ms[c]->name);
            goto done;
        }
        secs[c] = glint_now() - secs[c];
        held[c] = held_rms(&cand[c], s, x, in->rgb);
    }
    /* cheapest first; a richer candidate is taken when it beats the current
     * choice by more than the threshold (hf4 and maps are alternatives:
     * each is measured against the choice so far) */
    list = json_array();
    for (int c = 0; c < NCAND; c++) {
        int take = c > 0 && held[c] < held[chosen] * (1.0 - p->threshold) &&
                   held[chosen] - held[c] > p->floor;
        json_array_append_new(
            list, json_pack("{s:s, s:f, s:f, s:f, s:b}", "method", ms[c]->name, "held_out_rms",
                            held[c], "rms_painted",
                            json_number_value(json_object_get(
                                json_object_get(cand[c].info, "errors"), "rms_painted")),
                            "fit_seconds", secs[c], "taken", c == 0 || take));
        if (take)
            chosen = c;
    }
    choice = json_pack("{s:s, s:o, s:f, s:f, s:s, s:i, s:i, s:i, s:s}", "chosen",
                       ms[chosen]->name, "candidates", list, "threshold", p->threshold, "floor",
                       p->floor, "held_out",
                       x->by_views ? "views" : "pixels", "held_out_every", p->every,
                       "held_out_samples", x->nheld, "candidate_samples", tr->n,
                       "rule",
                       "cheapest first (hf3, hf2d, hf4, maps, hybrid); a richer one is taken "
                       "when its "
                       "held-out RMS is below the current choice's by more than the "
                       "threshold (a fraction) and the floor; the material is the chosen "
                       "method refitted to every painted sample");
    if (x->by_views) {
        json_t *hv = json_array();
        for (int v = 0; v < SCENE_MAX_VIEWS; v++)
            if (x->held_view[v])
                json_array_append_new(hv, json_integer(v));
        json_object_set_new(choice, "held_out_views", hv);
    }
    /* the chosen model refitted to every painted sample: the candidates saw
     * all but the held-out ones */
    {
        double tf = glint_now();
        if ((rc = fit_on(in, ms[chosen], ps[chosen], s, in->rgb, full_lv[chosen], out, err))) {
            json_decref(choice);
            glint_err_prefix(err, "auto, %s refitted to every sample", ms[chosen]->name);
            goto done;
        }
        json_object_set_new(choice, "refit_seconds", json_real(glint_now() - tf));
    }
    if (!out->info)
        out->info = json_object();
    json_object_set(out->info, "chosen_params", json_object_get(out->info, "params"));
    json_object_set_new(out->info, "params", method_params_to_json(&method_auto, p));
    json_object_set_new(out->info, "choice", choice);
    json_object_set_new(json_object_get(out->info, "seconds"), "auto", json_real(glint_now() - t0));
done:
    for (int c = 0; c < NCAND; c++)
        material_free(&cand[c]);
    free(trgb);
    return rc;
}

static size_t auto_fit_bytes(const void *params, long nsamples)
{
    cands cs;
    size_t b = 0;
    candidates(params, &cs);
    b += method_fit_bytes(&method_hf3, &cs.fp, nsamples);
    b += method_fit_bytes(&method_hf2d, &cs.dp, nsamples);
    b += method_fit_bytes(&method_hf4, &cs.hp, nsamples);
    b += method_fit_bytes(&method_maps, &cs.mp, nsamples);
    b += method_fit_bytes(&method_hybrid, &cs.yp, nsamples);
    return b;
}

/* Every candidate is fitted. */
static double auto_fit_seconds(const void *params, long nsamples)
{
    cands cs;
    candidates(params, &cs);
    return method_fit_seconds(&method_hf3, &cs.fp, nsamples) +
           method_fit_seconds(&method_hf2d, &cs.dp, nsamples) +
           method_fit_seconds(&method_hf4, &cs.hp, nsamples) +
           method_fit_seconds(&method_maps, &cs.mp, nsamples) +
           method_fit_seconds(&method_hybrid, &cs.yp, nsamples);
}

static int auto_holdout_ok(const void *params)
{
    return ((const auto_params *)params)->sres <= 32 &&
           ((const auto_params *)params)->res_2d <= 32;
}

const method method_auto = {
    .name = "auto",
    .label = "Choose for me",
    .summary = "Lets glint choose: one material, a brushed one, one with varying "
        "colour or several materials, whichever best predicts painted views it "
        "did not fit.",
    .when = "Use it when unsure which model the painting needs (lit by lamps): it "
        "keeps the simplest unless a richer one is clearly better, and says "
        "what it chose and why.",
    .lighting = METHOD_LIGHT_POINT,
    .shows = METHOD_SHOWS_FACTORS,
    .chooses = 1,
    .title = "Automatic: the simplest model that the painting needs",
    .reference = "Jaroszkiewicz & McCool, GI 2003 (the models); the choice is glint's",
    .description =
        "Fits one material (hf3), one anisotropic material (hf2d: a 2D q), one material with "
        "a colour texture (hf4), material maps "
        "(maps) and maps of textured materials (hybrid) to the painted pixels but one in `every`, and keeps the cheapest whose error "
        "on the held-out pixels is not beaten by a richer one by more than `threshold`. The "
        "material is the chosen method's; info.choice lists every candidate's held-out and "
        "painted RMS and why it was or was not taken.",
    .held_out = "leave-one-view-out: for each painted view, fit the others and measure the RMS "
                "error on that view's painted pixels; pooled over views",
    .schema = "FitParamsAuto.json",
    .params_size = sizeof(auto_params),
    .params = auto_params_table,
    .nparams = (int)(sizeof auto_params_table / sizeof auto_params_table[0]),
    .presets = auto_presets,
    .npresets = (int)(sizeof auto_presets / sizeof auto_presets[0]),
    .params_default = auto_params_default,
    .params_check = auto_params_check,
    .levels = auto_levels,
    .nlevels = (int)(sizeof auto_levels / sizeof auto_levels[0]),
    .fit = auto_fit,
    .mat = NULL,
    .holdout_ok = auto_holdout_ok,
    .fit_bytes = auto_fit_bytes,
    .fit_seconds = auto_fit_seconds,
};
