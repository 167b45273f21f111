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
#include "method_pbr.h"
#include "method_pbr_detail.h"
#include "method_pbr_maps.h"
#include "method_pbr_tab.h"
#include "method_tab.h"
#include "method_tab_prior.h"
#include "scene.h"

static const char *const learn_exclude_examples[] = {"", "every/4", NULL};

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
                    "hybrid, pbr_maps); 0: their own (5, 4 and 3)",
     .offset = offsetof(auto_params, components), .min = 0, .max = MATMAP_MAX},
    {.name = "threshold", .label = "how much better a richer model must be", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "a richer model is taken only when it lowers the held-out RMS by more "
                    "than this fraction of the current choice's",
     .offset = offsetof(auto_params, threshold), .min = 0.0, .max = 1.0},
    {.name = "floor", .label = "smallest gain that counts", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_NUMBER, .affects = "fit",
     .description = "nor by less than this fraction of the painting's RMS: a smaller gain is "
                    "noise, whatever the painting's brightness",
     .offset = offsetof(auto_params, floor), .min = 0.0, .max = 1.0},
    {.name = "every", .label = "views held out (one in)", .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_INT, .affects = "precomputation",
     .description = "one painted view in this many (one pixel, when one view is painted) is "
                    "held out to judge the candidates, which are fitted to the rest",
     .offset = offsetof(auto_params, every), .min = 2, .max = 64},
    {.name = "learn_exclude", .label = "measured materials not learned from",
     .group = METHOD_GROUP_ADVANCED, .type = METHOD_PARAM_TEXT, .affects = "precomputation",
     .description = "measured materials the learned-prior candidate does not learn from: "
                    "names joined by '+', or every/N for materials 0, N, 2N, ... of the fits "
                    "file (the ones a benchmark run with --every N judges); empty: none",
     .offset = offsetof(auto_params, learn_exclude),
     .syntax = "\"\" | every/N | NAME[+NAME...]", .examples = learn_exclude_examples,
     .parse = tab_prior_exclude_parse, .format = tab_prior_exclude_format},
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
    p->floor = 1e-3;
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
    pbr_params bp;
    pbr_detail_params xp;
    tab_params tp;
    tab_prior_params rp;
    pbr_tab_params gp;
    pbr_maps_params qp;
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
    method_pbr.params_default(&c->bp);
    method_tab.params_default(&c->tp);
    method_tab_prior.params_default(&c->rp);
    c->rp.tab = c->tp; /* tab's levels, shared */
    snprintf(c->rp.exclude, sizeof c->rp.exclude, "%s", p->learn_exclude);
    method_pbr_tab.params_default(&c->gp); /* pbr's level and tab's design, shared */
    method_pbr_maps.params_default(&c->qp); /* pbr's level, shared */
    if (p->components)
        c->qp.components = p->components;
    method_pbr_detail.params_default(&c->xp); /* hf3's levels and pbr's, shared */
    if (p->res)
        c->xp.hf.res = p->res;
}

/* ---- levels: the split, each candidate's precomputation on the kept pixels, then on all -- */

/* auto's levels: the split; hf3's two and hf4's one on the kept pixels;
 * hf3's two and hf4's one on every sample; hf2d's one on the kept pixels
 * and on every sample */
enum { LV_SPLIT, LV_HF3, LV_HF4 = 3, LV_FULL_HF3, LV_FULL_HF4 = 6, LV_HF2D, LV_FULL_HF2D,
       LV_PBR, LV_FULL_PBR, LV_TAB, LV_FULL_TAB = LV_TAB + 2, LV_PRIOR = LV_FULL_TAB + 2,
       LV_N };

/* What a held-out sample measures. */
enum { HELD_NO, HELD_NEW, HELD_BEYOND };

typedef struct split {
    samples train;
    unsigned char *held;   /* per sample of the pattern: HELD_* */
    int nheld;
    int by_views;          /* 1: whole views held out; 0: pixels */
    unsigned char held_view[SCENE_MAX_VIEWS];  /* HELD_* per view */
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

/* The views held out, when two or more views hold samples (a painted
 * view whose pixels are all unlit or hidden is no measure): one in
 * `every` of them inside the painted range (at least one), and, when four
 * or more are painted, also the view whose light lies farthest from its
 * eye (the smallest mean wi.wo over its samples): lights beyond the range
 * the others paint, where a model that only interpolates fails.  At least
 * two views are kept.  Marks held[v] HELD_NEW or HELD_BEYOND; 1 when views
 * are held out, 0 when fewer than two are painted (pixels are then). */
static int held_views(const samples *s, int every, unsigned char held[SCENE_MAX_VIEWS])
{
    int used[SCENE_MAX_VIEWS], nu = 0, nh = 0, far = -1;
    double dot[SCENE_MAX_VIEWS] = {0}, cnt[SCENE_MAX_VIEWS] = {0};
    for (int i = 0; i < s->n; i++) {
        int v = s->view[i];
        const float *wi = s->wi + 3 * (size_t)i, *wo = s->wo + 3 * (size_t)i;
        if (v < 0 || v >= SCENE_MAX_VIEWS)
            continue;
        dot[v] += (double)wi[0] * wo[0] + (double)wi[1] * wo[1] + (double)wi[2] * wo[2];
        cnt[v] += 1.0;
    }
    for (int v = 0; v < s->nviews && v < SCENE_MAX_VIEWS; v++)
        if (s->used[v] && cnt[v] > 0.0)
            used[nu++] = v;
    if (nu < 2)
        return 0;
    for (int k = 0; k < nu; k++)
        if (k % every == every / 2 || (nh == 0 && k == nu - 1)) {
            held[used[k]] = HELD_NEW;
            nh++;
        }
    if (nu - nh < 3)
        return 1;
    for (int k = 0; k < nu; k++) {
        int v = used[k];
        if (!held[v] && (far < 0 || dot[v] / cnt[v] < dot[far] / cnt[far]))
            far = v;
    }
    held[far] = HELD_BEYOND;
    return 1;
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
    snprintf(key, len, "auto-split:%s:%d:far", s->hash, ((const auto_params *)params)->every);
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
    x->by_views = held_views(s, p->every, x->held_view);
    for (int i = 0; i < s->n; i++) {
        x->held[i] = x->by_views ? x->held_view[s->view[i]]
                                 : (unsigned char)(pixel_held(s->view[i], s->pixel[i], s->width,
                                                              p->every) ? HELD_NEW : HELD_NO);
        keep[i] = !x->held[i];
        x->nheld += !!x->held[i];
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

/* A candidate's build reports its own stages over its own preparation
 * ("design", 0.3 of hf3's); auto's caller hears them as the auto level
 * being built, its fraction mapped between that level's start and the
 * next's, so the stage names and the bar move as auto's. */
typedef struct relay {
    const method_build_in *in;
    double from, to;
} relay;

static void relay_progress(void *cls, const char *stage, double fraction)
{
    const relay *r = cls;
    (void)stage;
    fraction = fraction < 0.0 ? 0.0 : fraction > 1.0 ? 1.0 : fraction;
    r->in->progress(r->in->progress_cls, method_auto.levels[r->in->level].name,
                    r->from + (r->to - r->from) * fraction);
}

static int relayed_build(const method_build_in *in, const method *m, int k, method_build_in *c,
                         cache_value *out, glint_err *err)
{
    const method_level *lv = method_auto.levels;
    relay r = {in, lv[in->level].progress,
               in->level + 1 < method_auto.nlevels ? lv[in->level + 1].progress : 0.9};
    if (in->progress) {
        c->progress = relay_progress;
        c->progress_cls = &r;
    }
    return m->levels[k].build(c, out, err);
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
    return relayed_build(in, m, k, &c, out, err);
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
    return relayed_build(in, m, k, &c, out, err);
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

/* pbr's one level (its per-sample angles) on the kept pixels, keyed from
 * the split, and on every sample, keyed as a direct pbr fit keys it (from
 * the pattern's hash). */
static void pbrg_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    cands cs;
    char own[CACHE_KEY_MAX], sk[CACHE_KEY_MAX];
    candidates(params, &cs);
    split_key(params, s, prev_key, sk, sizeof sk);
    method_pbr.levels[0].key(&cs.bp, s, sk, own, sizeof own);
    snprintf(key, len, "%s", own);
}

static int pbrg_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return candidate_build(in, &method_pbr, 0, NULL, &cs.bp, out, err);
}

static void fpbrg_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    cands cs;
    (void)prev_key;
    candidates(params, &cs);
    method_pbr.levels[0].key(&cs.bp, s, s->hash, key, len);
}

static int fpbrg_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_build(in, &method_pbr, 0, NULL, &cs.bp, out, err);
}

/* tab's two levels (its design and operator) on the kept pixels, keyed
 * from the split, and on every sample, keyed as a direct tab fit keys
 * them. */
static void tabd_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    cands cs;
    char sk[CACHE_KEY_MAX];
    candidates(params, &cs);
    split_key(params, s, prev_key, sk, sizeof sk);
    method_tab.levels[0].key(&cs.tp, s, sk, key, len);
}

static int tabd_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return candidate_build(in, &method_tab, 0, NULL, &cs.tp, out, err);
}

static void tabo_key(const void *params, const samples *s, const char *prev_key, char *key,
                     size_t len)
{
    cands cs;
    candidates(params, &cs);
    method_tab.levels[1].key(&cs.tp, s, prev_key, key, len);
}

static int tabo_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return candidate_build(in, &method_tab, 1, in->prev + LV_TAB, &cs.tp, out, err);
}

static void ftabd_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    cands cs;
    (void)prev_key;
    candidates(params, &cs);
    method_tab.levels[0].key(&cs.tp, s, s->hash, key, len);
}

static int ftabd_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_build(in, &method_tab, 0, NULL, &cs.tp, out, err);
}

static int ftabo_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    candidates(in->params, &cs);
    return full_build(in, &method_tab, 1, in->prev + LV_FULL_TAB, &cs.tp, out, err);
}

/* tab_prior's learned prior, or why there is none (no fits file on this
 * host, or a broken one): the candidate is then skipped, not the choice. */
typedef struct auto_prior {
    tab_prior *p;
    char why[GLINT_ERR_MSG_MAX];
} auto_prior;

static void prior_key(const void *params, const samples *s, const char *prev_key, char *key,
                      size_t len)
{
    cands cs;
    (void)prev_key;
    candidates(params, &cs);
    tab_prior_level_key(&cs.rp, s, "measured", key, len);
}

static void prior_free(void *data)
{
    auto_prior *a = data;
    if (a && a->p) {
        tab_prior_free(a->p);
        free(a->p);
    }
    free(a);
}

static int prior_build(const method_build_in *in, cache_value *out, glint_err *err)
{
    cands cs;
    method_build_in c = *in;
    cache_value v = {0};
    auto_prior *a = calloc(1, sizeof *a);
    int rc;
    if (!a)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    candidates(in->params, &cs);
    c.params = &cs.rp;
    c.prev = NULL;
    if ((rc = tab_prior_level_build(&c, &v, err))) {
        if (rc == GLINT_ENOMEM || rc == GLINT_ECANCELLED) {
            free(a);
            return rc;
        }
        snprintf(a->why, sizeof a->why, "%s", err->msg);
    } else {
        a->p = v.data;
    }
    out->data = a;
    out->bytes = sizeof *a + v.bytes;
    out->free = prior_free;
    return 0;
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
    {.name = "physical angles", .progress = 0.88, .key = pbrg_key, .build = pbrg_build},
    {.name = "full physical angles", .progress = 0.9, .key = fpbrg_key, .build = fpbrg_build},
    {.name = "table design", .progress = 0.91, .key = tabd_key, .build = tabd_build},
    {.name = "table operator", .progress = 0.92, .key = tabo_key, .build = tabo_build},
    {.name = "full table design", .progress = 0.93, .key = ftabd_key, .build = ftabd_build},
    {.name = "full table operator", .progress = 0.94, .key = tabo_key, .build = ftabo_build},
    {.name = "learned prior", .progress = 0.95, .key = prior_key, .build = prior_build},
};

/* ---- the fit ------------------------------------------------------------------------ */

/* The candidates, cheapest first, each with its levels on the kept pixels
 * and on every sample (maps reuses hf3's, hybrid hf4's). */
typedef struct cand_def {
    const method *m;
    size_t params;                /* offset of its parameters in cands */
    int nlv;
    int train_lv[3], full_lv[3];
} cand_def;

static const cand_def CANDS[] = {
    {&method_hf3, offsetof(cands, fp), 2, {LV_HF3, LV_HF3 + 1}, {LV_FULL_HF3, LV_FULL_HF3 + 1}},
    {&method_pbr, offsetof(cands, bp), 1, {LV_PBR}, {LV_FULL_PBR}},
    {&method_pbr_detail, offsetof(cands, xp), 3, {LV_PBR, LV_HF3, LV_HF3 + 1},
     {LV_FULL_PBR, LV_FULL_HF3, LV_FULL_HF3 + 1}},
    {&method_tab, offsetof(cands, tp), 2, {LV_TAB, LV_TAB + 1}, {LV_FULL_TAB, LV_FULL_TAB + 1}},
    {&method_tab_prior, offsetof(cands, rp), 3, {LV_TAB, LV_TAB + 1, LV_PRIOR},
     {LV_FULL_TAB, LV_FULL_TAB + 1, LV_PRIOR}},
    {&method_pbr_tab, offsetof(cands, gp), 2, {LV_PBR, LV_TAB}, {LV_FULL_PBR, LV_FULL_TAB}},
    {&method_hf2d, offsetof(cands, dp), 1, {LV_HF2D}, {LV_FULL_HF2D}},
    {&method_hf4, offsetof(cands, hp), 1, {LV_HF4}, {LV_FULL_HF4}},
    {&method_maps, offsetof(cands, mp), 2, {LV_HF3, LV_HF3 + 1}, {LV_FULL_HF3, LV_FULL_HF3 + 1}},
    {&method_hybrid, offsetof(cands, yp), 1, {LV_HF4}, {LV_FULL_HF4}},
    {&method_pbr_maps, offsetof(cands, qp), 1, {LV_PBR}, {LV_FULL_PBR}},
};
#define NCAND ((int)(sizeof CANDS / sizeof CANDS[0]))

static const void *cand_params(const cands *cs, int c)
{
    return (const char *)cs + CANDS[c].params;
}

/* A candidate's error on the held-out samples: per unit light, RGB, the
 * material evaluated at each sample's texture coordinates; RMS over those
 * held as `which` (HELD_NEW, HELD_BEYOND; 0: every held one).  -1 when
 * none is held so. */
static double held_rms(const material *m, const samples *s, const split *x, const float *rgb,
                       int which)
{
    double ss = 0.0;
    long cnt = 0;
    for (int i = 0; i < s->n; i++) {
        double n[3], wi[3], wo[3], uv[2], v[3];
        if (!x->held[i] || (which && x->held[i] != which))
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
    return cnt ? sqrt(ss / (3.0 * cnt)) : -1.0;
}

/* Fit candidate c (parameters from cs) to samples s, values rgb, with
 * auto's levels lv (its own levels in order). */
static int fit_on(const method_fit_in *in, int c, const cands *cs, const samples *s,
                  const float *rgb, const int *lvi, material *out, glint_err *err)
{
    method_fit_in ci = *in;
    const void *lv[3];
    const char *ky[3];
    cache_how how[3];
    double spent[3];
    cache_disk disk[3];
    for (int l = 0; l < CANDS[c].nlv; l++) {
        lv[l] = lvi[l] == LV_PRIOR ? ((const auto_prior *)in->levels[LV_PRIOR])->p
                                   : in->levels[lvi[l]];
        ky[l] = in->keys[lvi[l]];
        how[l] = in->how[lvi[l]];
        spent[l] = in->spent[lvi[l]];
        disk[l] = in->disk[lvi[l]];
    }
    ci.params = cand_params(cs, c);
    ci.s = s;
    ci.rgb = rgb;
    ci.memo = NULL; /* samples and values of auto's own choosing */
    ci.view_tags = NULL;
    ci.values_change = NULL;
    ci.levels = lv;
    ci.keys = ky;
    ci.how = how;
    ci.spent = spent;
    ci.disk = disk;
    return CANDS[c].m->fit(&ci, out, err);
}

/* What each candidate scored. */
typedef struct scores {
    double held[NCAND], held_new[NCAND], held_beyond[NCAND], secs[NCAND];
    const char *skipped[NCAND];   /* why a candidate was not fitted, or NULL */
} scores;

/* Fit every candidate to the kept samples and measure it on the held-out
 * ones. */
static int fit_candidates(const method_fit_in *in, const cands *cs, material *cand, scores *sc,
                          glint_err *err)
{
    const split *x = in->levels[0];
    const samples *s = in->s, *tr = &x->train;
    float *trgb = malloc(3 * (size_t)tr->n * sizeof *trgb);
    int rc = 0;
    if (!trgb)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    for (int i = 0, k = 0; i < s->n; i++)
        if (!x->held[i]) {
            memcpy(trgb + 3 * (size_t)k, in->rgb + 3 * (size_t)i, 3 * sizeof *trgb);
            k++;
        }
    for (int c = 0; c < NCAND && !rc; c++) {
        double t = glint_now();
        const auto_prior *ap = in->levels[LV_PRIOR];
        if (CANDS[c].m == &method_tab_prior && !ap->p) {
            sc->skipped[c] = ap->why;
            continue;
        }
        if ((rc = fit_on(in, c, cs, tr, trgb, CANDS[c].train_lv, &cand[c], err))) {
            glint_err_prefix(err, "auto, candidate %s", CANDS[c].m->name);
            break;
        }
        sc->secs[c] = glint_now() - t;
        sc->held[c] = held_rms(&cand[c], s, x, in->rgb, 0);
        sc->held_new[c] = held_rms(&cand[c], s, x, in->rgb, HELD_NEW);
        sc->held_beyond[c] = held_rms(&cand[c], s, x, in->rgb, HELD_BEYOND);
    }
    free(trgb);
    return rc;
}

/* What a candidate is judged by: with new views and a view beyond the
 * painted range both held out, the geometric mean of its held-out RMS on
 * each (the beyond view's error is the larger, and in a pooled RMS it hid
 * a model that halves the error on new views: white-marble's pbr_detail,
 * docs/methods.md); else the pooled held-out RMS. */
static double judged(const scores *sc, int c)
{
    if (sc->held_new[c] >= 0.0 && sc->held_beyond[c] >= 0.0)
        return sqrt(sc->held_new[c] * sc->held_beyond[c]);
    return sc->held[c];
}

/* The floor in the painting's units: p->floor times the RMS of the
 * painted values.  It was a quarter of an 8-bit step per unit light, which
 * held every dark material at hf3: on fruitwood-241 (painted RMS about
 * 0.01) pbr_tab's judged held-out RMS was 0.0002 against hf3's 0.0007, a
 * gain below 0.001, and the 20 new views then showed 3.5% against 0.2%. */
static double floor_value(const auto_params *p, const method_fit_in *in)
{
    double ss = 0.0;
    for (long i = 0; i < 3L * in->s->n; i++)
        ss += (double)in->rgb[i] * in->rgb[i];
    return in->s->n ? p->floor * sqrt(ss / (3.0 * (double)in->s->n)) : 0.0;
}

/* The rule: cheapest first; a later candidate is taken when its judged
 * held-out RMS is below the current choice's by more than the threshold
 * (a fraction) and the floor (fl, in the painting's units).  Each take
 * lowers it, so the choice is never worse on the held-out samples, so
 * judged, than the first, the simplest.  Writes each candidate's figures
 * into `list`; the chosen index. */
static int choose(const auto_params *p, double fl, const material *cand, const scores *sc,
                  json_t *list)
{
    int chosen = 0;
    for (int c = 0; c < NCAND; c++) {
        double jc = judged(sc, c), jk = judged(sc, chosen);
        int take = c > 0 && jc < jk * (1.0 - p->threshold) && jk - jc > fl;
        json_t *e;
        if (sc->skipped[c]) {
            json_array_append_new(list, json_pack("{s:s, s:s, s:s, s:b}", "method",
                                                  CANDS[c].m->name, "label", CANDS[c].m->label,
                                                  "skipped", sc->skipped[c], "taken", 0));
            continue;
        }
        e = json_pack(
            "{s:s, s:s, s:f, s:f, s:f, s:b}", "method", CANDS[c].m->name, "label",
            CANDS[c].m->label, "held_out_rms", sc->held[c], "rms_painted",
            json_number_value(json_object_get(json_object_get(cand[c].info, "errors"),
                                              "rms_painted")),
            "fit_seconds", sc->secs[c], "taken", c == 0 || take);
        if (sc->held_new[c] >= 0.0)
            json_object_set_new(e, "held_out_rms_new_views", json_real(sc->held_new[c]));
        if (sc->held_beyond[c] >= 0.0)
            json_object_set_new(e, "held_out_rms_beyond", json_real(sc->held_beyond[c]));
        json_object_set_new(e, "judged_rms", json_real(jc));
        json_array_append_new(list, e);
        if (take)
            chosen = c;
    }
    return chosen;
}

static json_t *choice_report(const auto_params *p, double fl, const split *x, int chosen,
                             json_t *list)
{
    json_t *choice = json_pack(
        "{s:s, s:o, s:f, s:f, s:f, s:s, s:i, s:i, s:i, s:s}", "chosen", CANDS[chosen].m->name,
        "candidates", list, "threshold", p->threshold, "floor", p->floor, "floor_value", fl,
        "held_out",
        x->by_views ? "views" : "pixels", "held_out_every", p->every, "held_out_samples",
        x->nheld, "candidate_samples", x->train.n, "rule",
        "cheapest first (hf3, pbr, pbr_detail, tab, tab_prior, pbr_tab, hf2d, hf4, maps, "
        "hybrid, pbr_maps; one the host cannot fit is skipped, with the reason); a later "
        "one is "
        "taken when its judged RMS (the geometric mean of its held-out RMS on the new views "
        "and on the view beyond the painted range when both are held out, else its held-out "
        "RMS) is below the current choice's by more than the threshold (a fraction) and "
        "floor_value (the floor times the painting's RMS), so the choice is never worse so "
        "judged than hf3; the material is the chosen "
        "method refitted to every painted sample");
    if (x->by_views) {
        json_t *hv = json_array(), *hb = json_array();
        for (int v = 0; v < SCENE_MAX_VIEWS; v++)
            if (x->held_view[v])
                json_array_append_new(x->held_view[v] == HELD_BEYOND ? hb : hv,
                                      json_integer(v));
        json_object_set_new(choice, "held_out_views", hv);
        json_object_set_new(choice, "held_out_views_beyond", hb);
    }
    return choice;
}

static int auto_fit(const method_fit_in *in, material *out, glint_err *err)
{
    const auto_params *p = in->params;
    const split *x = in->levels[0];
    cands cs;
    material cand[NCAND];
    scores sc;
    double t0 = glint_now(), tf;
    int chosen, rc;
    json_t *choice;

    memset(out, 0, sizeof *out);
    memset(cand, 0, sizeof cand);
    memset(&sc, 0, sizeof sc);
    candidates(p, &cs);
    /* coefficient texels no more than a sixteenth of the samples: finer
     * textures hold texels that few samples reach, fitted to the painted
     * views' own residuals (tests/unit/test_auto.c) */
    cs.mp.map_res = (int)floor(sqrt(x->train.n / 16.0));
    cs.mp.map_res = cs.mp.map_res < 8 ? 8 : cs.mp.map_res > 128 ? 128 : cs.mp.map_res;
    cs.yp.map_res = cs.mp.map_res;
    if ((rc = fit_candidates(in, &cs, cand, &sc, err)))
        goto done;
    {
        json_t *list = json_array();
        double fl = floor_value(p, in);
        chosen = choose(p, fl, cand, &sc, list);
        choice = choice_report(p, fl, x, chosen, list);
    }
    /* the chosen model refitted to every painted sample: the candidates saw
     * all but the held-out ones */
    tf = glint_now();
    if ((rc = fit_on(in, chosen, &cs, in->s, in->rgb, CANDS[chosen].full_lv, out, err))) {
        json_decref(choice);
        glint_err_prefix(err, "auto, %s refitted to every sample", CANDS[chosen].m->name);
        goto done;
    }
    json_object_set_new(choice, "refit_seconds", json_real(glint_now() - tf));
    if (!out->info)
        out->info = json_object();
    json_object_set(out->info, "chosen_params", json_object_get(out->info, "params"));
    json_object_set_new(out->info, "params", method_params_to_json(&method_auto, p));
    json_object_set_new(out->info, "choice", choice);
    json_object_set_new(json_object_get(out->info, "seconds"), "auto", json_real(glint_now() - t0));
done:
    for (int c = 0; c < NCAND; c++)
        material_free(&cand[c]);
    return rc;
}

static size_t auto_fit_bytes(const void *params, long nsamples)
{
    cands cs;
    size_t b = 0;
    candidates(params, &cs);
    for (int c = 0; c < NCAND; c++)
        b += method_fit_bytes(CANDS[c].m, cand_params(&cs, c), nsamples);
    return b;
}

/* Every candidate is fitted. */
static double auto_fit_seconds(const void *params, long nsamples)
{
    cands cs;
    double t = 0.0;
    candidates(params, &cs);
    for (int c = 0; c < NCAND; c++)
        t += method_fit_seconds(CANDS[c].m, cand_params(&cs, c), nsamples);
    return t;
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
        "Fits one material (hf3), one physically based material (pbr: Lambert + GGX), the "
        "same times a three-factor detail of what it leaves (pbr_detail), one isotropic BRDF "
        "tabulated over the half and difference angles (tab), that table continued as "
        "measured materials go on (tab_prior, where the host has their fits; learn_exclude "
        "leaves some out of its learning), pbr corrected by such a table (pbr_tab), one "
        "anisotropic material (hf2d: a 2D q), one material with a colour texture (hf4), "
        "material maps (maps), maps of textured materials (hybrid) and maps of physically "
        "based materials (pbr_maps), each at its own "
        "settings, to the painted views but those held out (one in `every`, and the one whose "
        "light is farthest from its eye: a light beyond the painted range; one pixel tile in "
        "`every` when one view is painted), and keeps the cheapest whose error on the "
        "held-out samples (the geometric mean of the new views' and the beyond view's) is not "
        "beaten by a later one by more than `threshold`: never worse there than hf3. The material is the chosen method's, refitted to every painted "
        "sample; info.choice lists every candidate's held-out RMS (pooled, on new views and "
        "beyond the range) and painted RMS and why it was or was not taken.",
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
