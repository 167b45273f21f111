/* bench_img_exr: a painting encoded as OpenEXR (what a stroke stores), by
 * OpenImageIO and OpenEXR (zip at deflate level 1, one thread) and by
 * img_exr_encode (core/img/img_exr.h: libdeflate at level 1, the blocks on
 * the worker pool), and by img_exr_encode on the calling thread alone;
 * then a stroke's file made again whole and from the last one
 * (img_exr_encode_reusing), for bands of lines painted over.
 * Medians over --reps rounds, alternating; every file is read back and
 * compared with the painting, bit for bit.
 *
 *   ./build/tests/bench/bench_img_exr [--reps N] [FILE]
 *
 * FILE: an image to encode (a stroke's stored .exr, say); without it, two
 * 256x256 RGB paintings: a shaded ball in 8-bit levels (an uploaded PNG's
 * values) with a painted disc, and the same with noise in every value's
 * low 16 bits (what deflate cannot shrink). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "img.h"
#include "img_exr.h"
#include "img_oiio.h"
#include "par.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static void die(const char *what, const glint_err *e)
{
    fprintf(stderr, "bench_img_exr: %s: %s\n", what, e ? e->msg : "failed");
    exit(1);
}

static void painting(img *im, int noise)
{
    glint_err e;
    uint32_t r = 12345;
    if (img_alloc(im, 256, 256, 3, &e))
        die("img_alloc", &e);
    for (int y = 0; y < 256; y++)
        for (int x = 0; x < 256; x++)
            for (int c = 0; c < 3; c++) {
                double dx = x - 128.0, dy = y - 128.0, d = sqrt(dx * dx + dy * dy) / 110.0;
                /* a shaded ball in 8-bit levels (an uploaded PNG's values) */
                int q = d < 1.0 ? (int)lround(255.0 * (0.2 + 0.3 * c) * sqrt(1.0 - d * d)) : 0;
                float v = (float)q / 255.0f;
                if ((x - 90) * (x - 90) + (y - 100) * (y - 100) < 144) /* a stroke's disc */
                    v = 0.8f;
                if (noise) {
                    uint32_t u;
                    r = r * 1664525u + 1013904223u;
                    memcpy(&u, &v, sizeof u);
                    u ^= r >> 16;
                    memcpy(&v, &u, sizeof v);
                }
                im->px[((size_t)y * 256 + x) * 3 + c] = v;
            }
}

static void check(const img *im, const void *data, size_t len, const char *who)
{
    img back;
    glint_err e;
    if (img_read_mem(data, len, &back, &e))
        die(who, &e);
    if (back.width != im->width || back.height != im->height ||
        back.channels != im->channels ||
        memcmp(back.px, im->px, (size_t)im->width * im->height * im->channels * 4)) {
        fprintf(stderr, "bench_img_exr: %s: the file does not read back as the painting\n", who);
        exit(1);
    }
    img_free(&back);
}

static void bench(const char *name, const img *im, int reps)
{
    double *t[3];
    size_t len[3] = {0, 0, 0};
    glint_err e;
    for (int k = 0; k < 3; k++)
        t[k] = malloc((size_t)reps * sizeof *t[k]);
    for (int r = 0; r < reps; r++)
        for (int k = 0; k < 3; k++) {
            void *data = NULL;
            double t0 = now();
            int rc;
            if (k == 0)
                rc = img_oiio_write("openexr", NULL, &data, &len[k], "<memory>", im->width,
                                    im->height, im->channels, NULL, 0, im->px, &e);
            else {
                par_background(k == 2); /* k 2: every block on this thread */
                rc = img_exr_encode(im, &data, &len[k], &e);
                par_background(0);
            }
            t[k][r] = now() - t0;
            if (rc)
                die("encode", &e);
            if (r == 0)
                check(im, data, len[k], k ? "img_exr_encode" : "OpenImageIO");
            free(data);
        }
    for (int k = 0; k < 3; k++)
        qsort(t[k], (size_t)reps, sizeof *t[k], cmp);
    printf("| %s | %dx%dx%d | %.3f ms, %zu B | %.3f ms, %zu B | %.3f ms | %.2f |\n", name,
           im->width, im->height, im->channels, 1e3 * t[0][reps / 2], len[0],
           1e3 * t[1][reps / 2], len[1], 1e3 * t[2][reps / 2], t[0][reps / 2] / t[1][reps / 2]);
    for (int k = 0; k < 3; k++)
        free(t[k]);
}

/* A stroke's file: lines y0..y1 of im painted over, then the file made
 * again, whole (img_exr_encode) and from the last one
 * (img_exr_encode_reusing), alternating; both must be the same bytes. */
static void bench_reuse(const char *name, const img *orig, int y0, int y1, int reps)
{
    double *t[2];
    img im;
    glint_err e;
    void *prev = NULL, *a = NULL, *b = NULL;
    size_t plen = 0, la = 0, lb = 0;
    int reused = 0;
    if (img_alloc(&im, orig->width, orig->height, orig->channels, &e))
        die("img_alloc", &e);
    memcpy(im.px, orig->px, (size_t)im.width * im.height * im.channels * sizeof(float));
    if (img_exr_encode(&im, &prev, &plen, &e))
        die("encode", &e);
    for (int y = y0; y <= y1 && y < im.height; y++) /* a band of paint across the image */
        for (int x = im.width / 4; x < 3 * im.width / 4; x++)
            for (int c = 0; c < im.channels; c++)
                im.px[((size_t)y * im.width + x) * im.channels + c] = 0.3f + 0.1f * (float)c;
    for (int k = 0; k < 2; k++)
        t[k] = malloc((size_t)reps * sizeof *t[k]);
    for (int r = 0; r < reps; r++)
        for (int k = 0; k < 2; k++) {
            void *data = NULL;
            size_t len = 0;
            double t0 = now();
            int rc = k ? img_exr_encode_reusing(&im, prev, plen, y0, y1, &data, &len, &reused, &e)
                       : img_exr_encode(&im, &data, &len, &e);
            t[k][r] = now() - t0;
            if (rc)
                die("encode", &e);
            if (r == 0) {
                if (k)
                    b = data, lb = len;
                else
                    a = data, la = len;
            } else {
                free(data);
            }
        }
    if (la != lb || memcmp(a, b, la)) {
        fprintf(stderr, "bench_img_exr: %s: the file made from the last one differs\n", name);
        exit(1);
    }
    check(&im, b, lb, "img_exr_encode_reusing");
    for (int k = 0; k < 2; k++)
        qsort(t[k], (size_t)reps, sizeof *t[k], cmp);
    printf("| %s | %d..%d | %d of %d | %.3f ms | %.3f ms | %.2f |\n", name, y0, y1, reused,
           (im.height + 15) / 16, 1e3 * t[0][reps / 2], 1e3 * t[1][reps / 2],
           t[0][reps / 2] / t[1][reps / 2]);
    for (int k = 0; k < 2; k++)
        free(t[k]);
    free(prev);
    free(a);
    free(b);
    img_free(&im);
}

int main(int argc, char **argv)
{
    int reps = 41;
    const char *file = NULL;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc)
            reps = atoi(argv[++i]);
        else if (argv[i][0] != '-')
            file = argv[i];
        else {
            fprintf(stderr, "usage: bench_img_exr [--reps N] [FILE]\n");
            return 2;
        }
    }
    if (reps < 1)
        reps = 1;
    glint_err e0;
    printf("threads %d; medians of %d, alternating\n\n", par_threads(), reps);
    printf("| image | size | OpenImageIO + OpenEXR | img_exr_encode | img_exr_encode, one "
           "thread | ratio |\n|---|---|---|---|---|---|\n");
    if (file) {
        img im;
        glint_err e;
        if (img_read(file, &im, &e))
            die(file, &e);
        if (im.channels != 3 && im.channels != 4)
            die("the image is not RGB or RGBA", NULL);
        bench(file, &im, reps);
        img_free(&im);
    } else {
        for (int noise = 0; noise < 2; noise++) {
            img im;
            painting(&im, noise);
            bench(noise ? "painting, noisy low bits" : "painting", &im, reps);
            img_free(&im);
        }
    }
    /* a stroke's lines: a dab of diameter 12 within a block and across
     * two, a stroke 40 lines high, every line */
    printf("\nA stroke's file, made again whole and from the last file (the blocks of 16 lines "
           "it missed copied):\n\n| image | lines changed | blocks copied | whole | from the "
           "last file | ratio |\n|---|---|---|---|---|---|\n");
    for (int noise = 0; noise < 2; noise++) {
        static const int band[4][2] = {{98, 109}, {90, 101}, {80, 119}, {0, 255}};
        img im;
        if (file) {
            if (noise)
                break;
            if (img_read(file, &im, &e0))
                die(file, &e0);
        } else {
            painting(&im, noise);
        }
        for (int k = 0; k < 4; k++)
            bench_reuse(file ? file : noise ? "painting, noisy low bits" : "painting", &im,
                        band[k][0] * im.height / 256, band[k][1] * im.height / 256, reps);
        img_free(&im);
    }
    return 0;
}
