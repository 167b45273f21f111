#include "gbuf.h"

#include <stdlib.h>
#include <string.h>

#include "img.h"
#include "scene.h"

int gbuf_alloc(gbuf *g, int width, int height, glint_err *err)
{
    size_t n;

    memset(g, 0, sizeof *g);
    if (width < 1 || height < 1 || width > SCENE_MAX_SIZE || height > SCENE_MAX_SIZE)
        return glint_err_set(err, GLINT_ERANGE,
                             "G-buffer size %dx%d outside 1..%d", width, height,
                             SCENE_MAX_SIZE);
    n = (size_t)width * (size_t)height;
    g->width = width;
    g->height = height;
    g->mask = calloc(n, 1);
    g->pos = calloc(3 * n, sizeof(float));
    g->nrm = calloc(3 * n, sizeof(float));
    g->uv = calloc(2 * n, sizeof(float));
    g->wi = calloc(3 * n, sizeof(float));
    g->wo = calloc(3 * n, sizeof(float));
    if (!g->mask || !g->pos || !g->nrm || !g->uv || !g->wi || !g->wo) {
        gbuf_free(g);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a %dx%d G-buffer",
                             width, height);
    }
    return 0;
}

void gbuf_free(gbuf *g)
{
    if (!g)
        return;
    free(g->mask);
    free(g->pos);
    free(g->nrm);
    free(g->uv);
    free(g->wi);
    free(g->wo);
    memset(g, 0, sizeof *g);
}

long gbuf_count(const gbuf *g)
{
    long c = 0;
    size_t n = (size_t)g->width * (size_t)g->height;
    for (size_t i = 0; i < n; i++)
        c += g->mask[i] != 0;
    return c;
}

#define NCH 17
static const char *const gbuf_names[NCH] = {
    "mask", "P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "uv.U", "uv.V",
    "wi.X", "wi.Y", "wi.Z", "wo.X", "wo.Y", "wo.Z", "cos_i", "cos_o"};

/* The NCH channels of gbuf_write_exr, interleaved (malloc'ed). */
static float *gbuf_channels(const gbuf *g)
{
    size_t n = (size_t)g->width * (size_t)g->height;
    float *data = malloc(n * NCH * sizeof(float));

    if (!data)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        float *d = data + i * NCH;
        const float *nr = g->nrm + 3 * i, *wi = g->wi + 3 * i, *wo = g->wo + 3 * i;
        d[0] = g->mask[i] ? 1.0f : 0.0f;
        memcpy(d + 1, g->pos + 3 * i, 3 * sizeof(float));
        memcpy(d + 4, nr, 3 * sizeof(float));
        memcpy(d + 7, g->uv + 2 * i, 2 * sizeof(float));
        memcpy(d + 9, wi, 3 * sizeof(float));
        memcpy(d + 12, wo, 3 * sizeof(float));
        d[15] = nr[0] * wi[0] + nr[1] * wi[1] + nr[2] * wi[2];
        d[16] = nr[0] * wo[0] + nr[1] * wo[1] + nr[2] * wo[2];
    }
    return data;
}

int gbuf_write_exr(const gbuf *g, const char *path, glint_err *err)
{
    float *data = gbuf_channels(g);
    int rc;
    if (!data)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory exporting a G-buffer");
    rc = img_write_exr_named(path, g->width, g->height, NCH, gbuf_names, data, err);
    free(data);
    return rc;
}

int gbuf_exr_mem(const gbuf *g, void **out, size_t *len, glint_err *err)
{
    float *data = gbuf_channels(g);
    int rc;
    *out = NULL;
    *len = 0;
    if (!data)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory exporting a G-buffer");
    rc = img_write_exr_named_mem(g->width, g->height, NCH, gbuf_names, data, out, len, err);
    free(data);
    return rc;
}

/* ---- reading G-buffers made elsewhere -------------------------------------------------- */

#include <math.h>
#include <stdio.h>
#include <strings.h>
#include <xxhash.h>

/* The index of channel `name` (case-insensitive; "N.X" also matches "N.x"
 * and "Nx"), or -1. */
static int channel_of(const img_named *im, const char *name)
{
    char alt[16];
    size_t n = strlen(name);
    snprintf(alt, sizeof alt, "%s", name);
    if (n >= 3 && name[n - 2] == '.') { /* "N.X" -> "NX" */
        alt[n - 2] = name[n - 1];
        alt[n - 1] = '\0';
    }
    for (int c = 0; c < im->channels; c++)
        if (!strcasecmp(im->names[c], name) || !strcasecmp(im->names[c], alt))
            return c;
    return -1;
}

static int vec_channels(const img_named *im, const char *base, const char *const comp[],
                        int ncomp, int ch[3], const char *what, int need_wi, glint_err *err)
{
    for (int k = 0; k < ncomp; k++) {
        char name[16];
        snprintf(name, sizeof name, "%s.%s", base, comp[k]);
        if ((ch[k] = channel_of(im, name)) < 0) {
            if (!err)
                return -1;
            if (!strcmp(base, "wi"))
                return glint_err_set(err, GLINT_EFORMAT,
                                     "%s: no channel %s (point-light methods need the direction "
                                     "to the light, wi.X wi.Y wi.Z; methods lit by an "
                                     "environment, such as srbf, do not)",
                                     what, name);
            return glint_err_set(err, GLINT_EFORMAT,
                                 "%s: no channel %s (a G-buffer needs N.X N.Y N.Z, %swo.X wo.Y "
                                 "wo.Z; mask, P.X P.Y P.Z and uv.U uv.V are optional)",
                                 what, name, need_wi ? "wi.X wi.Y wi.Z, " : "");
        }
    }
    return 0;
}

int gbuf_from_named(const img_named *im, const char *what, gbuf *g, int *has_uv,
                    glint_err *err)
{
    int has_wi;
    return gbuf_from_named_ex(im, what, 1, g, has_uv, &has_wi, err);
}

int gbuf_from_named_ex(const img_named *im, const char *what, int need_wi, gbuf *g,
                       int *has_uv, int *has_wi, glint_err *err)
{
    static const char *const xyz[3] = {"X", "Y", "Z"}, *const uv2[2] = {"U", "V"};
    int cn[3], ci[3] = {0, 0, 0}, co[3], cp[3] = {0, 0, 0}, cu[3] = {0, 0, 0}, cm, has_p, rc;
    size_t np;

    memset(g, 0, sizeof *g);
    *has_uv = 0;
    *has_wi = 0;
    if ((rc = vec_channels(im, "N", xyz, 3, cn, what, need_wi, err)) ||
        (need_wi && (rc = vec_channels(im, "wi", xyz, 3, ci, what, need_wi, err))) ||
        (rc = vec_channels(im, "wo", xyz, 3, co, what, need_wi, err)))
        return rc;
    *has_wi = vec_channels(im, "wi", xyz, 3, ci, what, need_wi, NULL) == 0;
    has_p = vec_channels(im, "P", xyz, 3, cp, what, need_wi, NULL) == 0;
    *has_uv = vec_channels(im, "uv", uv2, 2, cu, what, need_wi, NULL) == 0;
    cm = channel_of(im, "mask");
    if ((rc = gbuf_alloc(g, im->width, im->height, err)))
        return rc;
    np = (size_t)im->width * im->height;
    for (size_t p = 0; p < np; p++) {
        const float *px = im->px + p * (size_t)im->channels;
        float v[3][3];
        int on = cm >= 0 ? px[cm] > 0.5f : 1;
        for (int k = 0; k < 3; k++) {
            v[0][k] = px[cn[k]];
            v[1][k] = *has_wi ? px[ci[k]] : 0.0f;
            v[2][k] = px[co[k]];
        }
        for (int a = 0; a < 3 && on; a++) {
            double l;
            if (a == 1 && !*has_wi)
                continue; /* no light direction: left zero */
            l = sqrt((double)v[a][0] * v[a][0] + (double)v[a][1] * v[a][1] +
                     (double)v[a][2] * v[a][2]);
            if (!isfinite(l)) {
                gbuf_free(g);
                return glint_err_set(err, GLINT_ENONFINITE,
                                     "%s: pixel (x %d, y %d) has a non-finite %s", what,
                                     (int)(p % (size_t)im->width), (int)(p / (size_t)im->width),
                                     a == 0 ? "normal" : a == 1 ? "wi" : "wo");
            }
            if (l < 1e-6) { /* no geometry here (a background pixel without a mask) */
                if (cm >= 0) {
                    gbuf_free(g);
                    return glint_err_set(err, GLINT_EFORMAT,
                                         "%s: pixel (x %d, y %d) is in the mask but its %s is "
                                         "zero",
                                         what, (int)(p % (size_t)im->width),
                                         (int)(p / (size_t)im->width),
                                         a == 0 ? "normal" : a == 1 ? "wi" : "wo");
                }
                on = 0;
                break;
            }
            for (int k = 0; k < 3; k++)
                v[a][k] = (float)(v[a][k] / l);
        }
        if (!on)
            continue;
        g->mask[p] = 1;
        memcpy(g->nrm + 3 * p, v[0], sizeof v[0]);
        memcpy(g->wi + 3 * p, v[1], sizeof v[1]);
        memcpy(g->wo + 3 * p, v[2], sizeof v[2]);
        for (int k = 0; k < 3 && has_p; k++)
            g->pos[3 * p + k] = isfinite(px[cp[k]]) ? px[cp[k]] : 0.0f;
        for (int k = 0; k < 2 && *has_uv; k++) {
            float u = px[cu[k]];
            g->uv[2 * p + k] = !(u > 0.0f) ? 0.0f : u > 1.0f ? 1.0f : u;
        }
    }
    return 0;
}

int gbuf_read_exr(const char *path, gbuf *g, int *has_uv, glint_err *err)
{
    img_named im;
    int rc;
    memset(g, 0, sizeof *g);
    if ((rc = img_read_named(path, &im, err)))
        return rc;
    rc = gbuf_from_named(&im, path, g, has_uv, err);
    img_named_free(&im);
    return rc;
}

void gbuf_hash(const gbuf *g, int n, char hex[33])
{
    XXH3_state_t *st = XXH3_createState();
    XXH128_hash_t h = {0, 0};
    if (st && XXH3_128bits_reset(st) == XXH_OK) {
        XXH3_128bits_update(st, "glint-gbuffers/1", 16);
        for (int v = 0; v < n; v++) {
            size_t np = (size_t)g[v].width * g[v].height;
            int wh[2] = {g[v].width, g[v].height};
            XXH3_128bits_update(st, wh, sizeof wh);
            XXH3_128bits_update(st, g[v].mask, np);
            XXH3_128bits_update(st, g[v].nrm, 3 * np * sizeof(float));
            XXH3_128bits_update(st, g[v].wi, 3 * np * sizeof(float));
            XXH3_128bits_update(st, g[v].wo, 3 * np * sizeof(float));
            XXH3_128bits_update(st, g[v].uv, 2 * np * sizeof(float));
            XXH3_128bits_update(st, g[v].pos, 3 * np * sizeof(float));
        }
        h = XXH3_128bits_digest(st);
    }
    XXH3_freeState(st);
    snprintf(hex, 33, "%016llx%016llx", (unsigned long long)h.high64,
             (unsigned long long)h.low64);
}
