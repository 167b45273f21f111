/* img_raw.c: a decoded image as a checksummed cache file (img_raw.h). */
#include "img_raw.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "cfile.h"

#define MAGIC "GLIMGR01"
#define KIND 1
#define HEADER (8 + 4 + 3 * 4)

int img_raw_save(const img *im, const char *dir, const char *name, glint_err *err)
{
    uint32_t u[3];
    size_t n;
    cfile_w b;

    if (!im || !im->px || im->width < 1 || im->height < 1 || im->width > IMG_MAX_DIM ||
        im->height > IMG_MAX_DIM || im->channels < 1 || im->channels > 4)
        return glint_err_set(err, GLINT_EINVAL, "img_raw_save: not an image");
    n = (size_t)im->width * (size_t)im->height * (size_t)im->channels;
    u[0] = (uint32_t)im->width;
    u[1] = (uint32_t)im->height;
    u[2] = (uint32_t)im->channels;
    cfile_begin(&b, MAGIC, KIND);
    cfile_reserve(&b, HEADER + n * sizeof(float) + 8);
    cfile_put(&b, u, sizeof u);
    cfile_put(&b, im->px, n * sizeof(float));
    return cfile_write(&b, dir, name, err);
}

/* Any value not finite?  (An OR over the array: vectorizes.) */
static int any_nonfinite(const float *p, size_t n)
{
    int bad = 0;
    for (size_t i = 0; i < n; i++)
        bad |= !isfinite(p[i]);
    return bad;
}

int img_raw_load(const char *dir, const char *name, int max_dim, img *out, glint_err *err)
{
    uint32_t u[3];
    size_t n, max_file;
    cfile_s r;
    const char *why = NULL;
    int rc;

    memset(out, 0, sizeof *out);
    if (max_dim < 1 || max_dim > IMG_MAX_DIM)
        max_dim = IMG_MAX_DIM;
    max_file = HEADER + (size_t)max_dim * (size_t)max_dim * 4 * sizeof(float) + 8;
    memset(&r, 0, sizeof r);
    if ((rc = cfile_stream_open(dir, name, MAGIC, KIND, max_file, &r, err)))
        return rc;
    if (cfile_stream_get(&r, u, sizeof u) || u[0] < 1 || u[1] < 1 || u[0] > (uint32_t)max_dim ||
        u[1] > (uint32_t)max_dim || u[2] < 1 || u[2] > 4) {
        why = "has sizes outside the limits";
        goto done;
    }
    n = (size_t)u[0] * u[1] * u[2];
    if (cfile_stream_left(&r) != n * sizeof(float)) {
        why = "has the wrong size";
        goto done;
    }
    if ((rc = img_alloc(out, (int)u[0], (int)u[1], (int)u[2], err)))
        goto done;
    if (cfile_stream_get(&r, out->px, n * sizeof(float)))
        why = "has the wrong size";
    else if ((rc = cfile_stream_end(&r, name, err)))
        goto done;
    else if (any_nonfinite(out->px, n))
        why = "has values that are not finite";
done:
    cfile_stream_close(&r);
    if (why)
        rc = glint_err_set(err, GLINT_EFORMAT, "%s: the decoded image %s", name, why);
    if (rc)
        img_free(out);
    return rc;
}
