/* gbfit.c: G-buffers and paintings made elsewhere into samples and values
 * (gbfit.h). */
#include "gbfit.h"

#include <stdlib.h>
#include <string.h>

#include "scene.h"

int gbfit_needs_wi(const method *m)
{
    return m->pattern_rule != SAMPLES_SEEN;
}

int gbfit_gbuf_file(const method *m, const char *path, gbuf *g, int *has_uv, int *has_wi,
                    glint_err *err)
{
    img_named im;
    int rc;

    memset(g, 0, sizeof *g);
    if ((rc = img_read_named(path, &im, err)))
        return rc;
    rc = gbuf_from_named_ex(&im, path, gbfit_needs_wi(m), g, has_uv, has_wi, err);
    img_named_free(&im);
    return rc;
}

int gbfit_gbuf_mem(const method *m, const void *data, size_t len, int max_dim,
                   int max_channels, img_header_check check, void *cls, const char *what,
                   gbuf *g, int *has_uv, int *has_wi, glint_err *err)
{
    img_named im;
    int rc;

    memset(g, 0, sizeof *g);
    if ((rc = img_read_named_mem_checked(data, len, max_dim, max_channels, check, cls, &im,
                                         err))) {
        glint_err_prefix(err, "%s", what);
        return rc;
    }
    rc = gbuf_from_named_ex(&im, what, m && gbfit_needs_wi(m), g, has_uv, has_wi, err);
    img_named_free(&im);
    return rc;
}

int gbfit_samples(const method *m, const gbuf *g, const img *paintings,
                  const unsigned char *use, int n, int has_uv, samples *s, float **rgb,
                  glint_err *err)
{
    char hash[33];
    int rc, painted = 0, first = -1;

    memset(s, 0, sizeof *s);
    *rgb = NULL;
    if (n < 1 || n > SCENE_MAX_VIEWS)
        return glint_err_set(err, GLINT_ERANGE, "%d G-buffers: a set holds 1..%d views", n,
                             SCENE_MAX_VIEWS);
    for (int v = 0; v < n; v++) {
        if (!use[v])
            continue;
        if (first < 0)
            first = v;
        if (g[v].width != g[first].width || g[v].height != g[first].height)
            return glint_err_set(err, GLINT_EINVAL,
                                 "the G-buffer of view %d is %dx%d but view %d's is %dx%d", v,
                                 g[v].width, g[v].height, first, g[first].width,
                                 g[first].height);
        if (paintings[v].width != g[v].width || paintings[v].height != g[v].height)
            return glint_err_set(err, GLINT_EINVAL,
                                 "the painting of view %d is %dx%d but its G-buffer is %dx%d",
                                 v, paintings[v].width, paintings[v].height, g[v].width,
                                 g[v].height);
        painted++;
    }
    if (!painted)
        return glint_err_set(err, GLINT_EINVAL,
                             "none of the %d views has a painting: give at least one", n);
    /* auto compares candidates that vary over the surface (hf4, maps) */
    if (!has_uv && ((m->mat && m->mat->spatial) || !strcmp(m->name, "auto")))
        return glint_err_set(err, GLINT_EINVAL,
                             "method %s fits materials that vary over the surface: it needs "
                             "texture coordinates, channels uv.U uv.V, in every painted view's "
                             "G-buffer (a view has none; hf3, hf2d and srbf do without)",
                             m->name);
    if ((rc = samples_begin(s, n, g[first].width, g[first].height, err)))
        return rc;
    samples_set_rule(s, m->pattern_rule);
    gbuf_hash(g, n, hash);
    for (int v = 0; v < n && !rc; v++)
        if (use[v]) /* lit by a light of intensity 1 (scene.h: pi f cos_i) */
            rc = samples_add(s, v, &g[v], 0, GLINT_LIGHT_UNIT, err);
    if (!rc && (rc = samples_end(s, use, hash, err)) == GLINT_EINVAL)
        glint_err_set(err, GLINT_EINVAL,
                      "the painted views' G-buffers hold no sample for method %s (a pixel is "
                      "one where the mask covers it, n.wo > 0%s)",
                      m->name, m->pattern_rule == SAMPLES_SEEN ? "" : " and n.wi > 0");
    if (rc)
        goto fail;
    s->has_pos = has_uv; /* the surface's coordinates came with every G-buffer */
    if (!(*rgb = malloc(3 * (size_t)s->n * sizeof **rgb))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for %d samples", s->n);
        goto fail;
    }
    if ((rc = samples_gather(s, paintings, *rgb, err)))
        goto fail;
    return 0;
fail:
    free(*rgb);
    *rgb = NULL;
    samples_free(s);
    return rc;
}
