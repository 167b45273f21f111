/* fuzz_stroke_file.c: the stored file a stroke replaces.
 *
 * A stroke stores its view again as OpenEXR, copying from the view's
 * stored file the blocks of lines it did not touch
 * (img_write_exr_mem_reusing, server/api_sessions.c).  That file is what
 * an upload stored, whatever bytes glintd decoded, or glint's own
 * OpenEXR.  Input:
 *   byte 0: the file.  Even: the rest of the input is the file.  Odd: the
 *     file is img_exr_encode's of a small image that bytes 3-7 describe
 *     (width, height, 3 or 4 channels, values), with bytes 8-... XORed
 *     into it, three at a time (an offset in two bytes, a mask), so that
 *     the table and the blocks are reached;
 *   bytes 1-2: the lines the stroke changed (first, count; lines outside
 *     the image too).
 * The file must decode, as glintd decoded it before the stroke (an image
 * refused there never reaches a stroke).  Its RGB image, with those lines
 * changed, is encoded from the file.  Checked: the result decodes to that
 * image bit for bit; with no block copied it is img_exr_encode's bytes;
 * from glint's own file unchanged it is img_exr_encode's bytes too. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "img.h"
#include "img_exr.h"

#define MAX_DIM 96

/* img_exr_encode's file of a w x h image of nch channels whose values
 * come from seed (smooth, so that blocks compress; some exact zeros). */
static int glint_file(int w, int h, int nch, unsigned seed, void **file, size_t *len)
{
    img im = {0};
    glint_err e;
    int rc;
    if (img_alloc(&im, w, h, nch, &e))
        return -1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < nch; c++) {
                unsigned v = (unsigned)(x * (int)(seed & 7) + y * (int)((seed >> 3) & 7) +
                                        c * (int)(seed >> 6)) %
                             23u;
                im.px[((size_t)y * w + x) * nch + c] = v == 0 ? 0.0f : (float)v / 16.0f;
            }
    rc = img_exr_encode(&im, file, len, &e);
    img_free(&im);
    return rc ? -1 : 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    glint_err e;
    img im = {0}, back = {0};
    void *file = NULL, *out = NULL, *whole = NULL;
    size_t len = 0, out_len = 0, whole_len = 0;
    int reused = 0, pristine = 0, y0, y1;

    if (size < 3 || size > (size_t)4 << 20)
        return 0;
    if (data[0] & 1) {
        if (size < 8)
            return 0;
        if (glint_file(1 + data[3] % MAX_DIM, 1 + data[4] % MAX_DIM, data[5] & 1 ? 4 : 3,
                       (unsigned)data[6] | (unsigned)data[7] << 8, &file, &len))
            return 0;
        pristine = 1;
        for (size_t i = 8; i + 2 < size; i += 3) {
            size_t at = ((size_t)data[i] | (size_t)data[i + 1] << 8) % len;
            ((unsigned char *)file)[at] ^= data[i + 2];
            pristine &= data[i + 2] == 0;
        }
    } else {
        if (!(file = malloc(size - 3)) && size > 3)
            return 0;
        if (size > 3)
            memcpy(file, data + 3, size - 3);
        len = size - 3;
    }
    /* glintd's decode of the stored file (api_sessions.c, view_current) */
    if (img_read_mem_max(file, len, MAX_DIM, &im, &e) || img_to_rgb(&im, &e)) {
        FUZZ_CHECK(e.msg[0] != '\0');
        fuzz_note("stroke_file", e.msg);
        goto done;
    }
    for (size_t i = 0; i < (size_t)im.width * im.height * 3; i++)
        if (!isfinite(im.px[i])) /* refused at upload (img_validate) */
            goto done;
    /* the stroke: lines y0..y1 changed (none when y1 < y0) */
    y0 = (int)(data[1] % (im.height + 2)) - 1;
    y1 = y0 + data[2] % (im.height + 2) - 1;
    for (int y = y0 < 0 ? 0 : y0; y <= y1 && y < im.height; y++)
        for (int x = 0; x < im.width; x++)
            for (int c = 0; c < 3; c++)
                im.px[((size_t)y * im.width + x) * 3 + c] = 0.25f * (float)((x + y + c) % 7);
    if (img_write_exr_mem_reusing(&im, file, len, y0, y1, &out, &out_len, &reused, &e)) {
        FUZZ_CHECK(e.code == GLINT_ENOMEM);
        goto done;
    }
    FUZZ_CHECK(reused >= 0 && reused <= (im.height + 15) / 16);
    if (reused) {
        char note[64];
        snprintf(note, sizeof note, "%d of %d blocks copied", reused, (im.height + 15) / 16);
        fuzz_note("stroke_file", note);
    }
    FUZZ_CHECK(img_read_mem(out, out_len, &back, &e) == 0);
    FUZZ_CHECK(back.width == im.width && back.height == im.height && back.channels == 3);
    FUZZ_CHECK(memcmp(back.px, im.px, (size_t)im.width * im.height * 3 * sizeof(float)) == 0);
    if (reused == 0 || pristine) {
        FUZZ_CHECK(img_exr_encode(&im, &whole, &whole_len, &e) == 0);
        FUZZ_CHECK(whole_len == out_len && memcmp(whole, out, out_len) == 0);
    }
done:
    img_free(&im);
    img_free(&back);
    free(file);
    free(out);
    free(whole);
    return 0;
}
