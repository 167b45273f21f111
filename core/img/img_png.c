/* img_png.c: the direct PNG decoder (img_png.h). */
#include "internal/img_png.h"

#include <png.h>
#include <setjmp.h>
#include <stdlib.h>
#include <string.h>

typedef struct png_mem {
    const unsigned char *p;
    size_t len, at;
} png_mem;

static void mem_read(png_structp png, png_bytep out, size_t n)
{
    png_mem *m = png_get_io_ptr(png);
    if (n > m->len - m->at)
        png_error(png, "truncated");
    memcpy(out, m->p + m->at, n);
    m->at += n;
}

/* libpng's warnings (a bad CRC in an ancillary chunk, say) are not ours
 * to print, nor its errors: OpenImageIO decodes the image again and says
 * what is wrong with it. */
static void quiet(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg;
}

static void stop(png_structp png, png_const_charp msg)
{
    (void)msg;
    png_longjmp(png, 1);
}

int img_png_read(const void *mem, size_t len, int max_dim, int max_channels,
                 img_oiio_pixels *out)
{
    png_mem src = {mem, len, 0};
    png_structp png;
    png_infop info = NULL;
    unsigned char *volatile row = NULL;
    float *volatile px = NULL;
    png_uint_32 w, h;
    int depth, ctype, interlace, nch;
    float level[256]; /* q / 255.0f, as img_oiio.cpp divides */

    memset(out, 0, sizeof *out);
    if (!mem || len < 8 || png_sig_cmp(mem, 0, 8) != 0)
        return 1;
    if (!(png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, stop, quiet)))
        return 1;
    if (!(info = png_create_info_struct(png))) {
        png_destroy_read_struct(&png, NULL, NULL);
        return 1;
    }
    if (setjmp(png_jmpbuf(png))) {
        free(row);
        free(px);
        png_destroy_read_struct(&png, &info, NULL);
        return 1;
    }
    /* strict: a bad CRC in any chunk, or what libpng calls a benign error,
     * stops this path, and OpenImageIO decides about the file */
    png_set_crc_action(png, PNG_CRC_ERROR_QUIT, PNG_CRC_ERROR_QUIT);
    png_set_benign_errors(png, 0);
    png_set_read_fn(png, &src, mem_read);
    png_read_info(png, info);
    png_get_IHDR(png, info, &w, &h, &depth, &ctype, &interlace, NULL, NULL);
    nch = ctype == PNG_COLOR_TYPE_RGB ? 3 : ctype == PNG_COLOR_TYPE_RGB_ALPHA ? 4 : 0;
    if (depth != 8 || !nch || nch > max_channels || interlace != PNG_INTERLACE_NONE ||
        w < 1 || h < 1 || w > (png_uint_32)max_dim || h > (png_uint_32)max_dim ||
        png_get_valid(png, info,
                      PNG_INFO_tRNS | PNG_INFO_gAMA | PNG_INFO_sRGB | PNG_INFO_iCCP |
                          PNG_INFO_cHRM) ||
        png_get_rowbytes(png, info) != (size_t)w * nch)
        png_error(png, "not for this path");
    if (!(row = malloc((size_t)w * nch)) || !(px = malloc((size_t)w * h * nch * sizeof *px)))
        png_error(png, "out of memory");
    for (int q = 0; q < 256; q++)
        level[q] = (float)q / 255.0f;
    for (png_uint_32 y = 0; y < h; y++) {
        float *o = px + (size_t)y * w * nch;
        png_read_row(png, row, NULL);
        for (size_t i = 0; i < (size_t)w * nch; i++)
            o[i] = level[row[i]];
    }
    png_read_end(png, NULL); /* the chunks after the pixels, checked as OpenImageIO's are */
    png_destroy_read_struct(&png, &info, NULL);
    free(row);
    out->width = (int)w;
    out->height = (int)h;
    out->channels = nch;
    out->px = px;
    return 0;
}
