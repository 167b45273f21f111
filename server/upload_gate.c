/* upload_gate.c: the check of an uploaded image's header (upload_gate.h). */
#include "upload_gate.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "admit.h"
#include "api_common.h"

void upload_gate_init(upload_gate *g, app *a, const char *what)
{
    memset(g, 0, sizeof *g);
    g->a = a;
    g->what = what;
    g->max_dim = a->cfg.lim.max_image_dim;
    g->max_dim_name = "max_image_dim, glintd --max-image-dim";
    g->too_large_code = GLINT_ETOOBIG;
    g->too_large_kind = "image-too-large";
    g->max_channels = 4;
    g->invalid_kind = "invalid-image";
}

void upload_gate_size(upload_gate *g, int w, int h)
{
    if (g->nsizes < 2) {
        g->w[g->nsizes] = w;
        g->h[g->nsizes] = h;
        g->nsizes++;
    }
}

/* The header's size is one the target takes. */
static int size_taken(const upload_gate *g, const img_header *hd)
{
    if (g->nsizes == 0)
        return 1;
    for (int i = 0; i < g->nsizes; i++)
        if (hd->width == g->w[i] && hd->height == g->h[i])
            return 1;
    return 0;
}

int upload_gate_check(void *cls, const img_header *hd, glint_err *err)
{
    upload_gate *g = cls;
    const char *sep = g->expect[0] ? "; " : "";
    size_t bytes, px = (size_t)hd->width * (size_t)hd->height;
    char what[96];
    int rc;

    g->seen = 1;
    g->hd = *hd;
    g->refused = 1;
    if (hd->width > g->max_dim || hd->height > g->max_dim)
        return api_reject(err, g->too_large_code, g->too_large_kind,
                          "%s is %dx%d, beyond the limit of %d pixels a side (%s)%s%s", g->what,
                          hd->width, hd->height, g->max_dim, g->max_dim_name, sep, g->expect);
    if (!size_taken(g, hd))
        return api_reject(err, GLINT_EINVAL, "wrong-size", "%s is %dx%d%s%s", g->what,
                          hd->width, hd->height, sep, g->expect);
    if (hd->channels > g->max_channels)
        return api_reject(err, GLINT_EINVAL, g->invalid_kind,
                          "%s has %d channels, more than the %d it may have", g->what,
                          hd->channels, g->max_channels);
    /* sides within max_dim (at most IMG_MAX_DIM): no overflow below */
    bytes = hd->decode_bytes;
    bytes = px && g->per_pixel > (SIZE_MAX - bytes) / px ? SIZE_MAX : bytes + px * g->per_pixel;
    snprintf(what, sizeof what, "decoding %s (%s, %dx%d, %d channels)", g->what, hd->format,
             hd->width, hd->height, hd->channels);
    if ((rc = admit_enter(g->a->work, bytes, what, err)))
        return rc;
    g->held = bytes;
    g->refused = 0;
    return 0;
}

void upload_gate_leave(upload_gate *g)
{
    if (g->held)
        admit_leave(g->a->work, g->held);
    g->held = 0;
}
