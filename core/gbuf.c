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
