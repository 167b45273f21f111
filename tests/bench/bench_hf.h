/* bench_hf.h: what the parts of bench_hf share. */
#ifndef GLINT_BENCH_HF_H
#define GLINT_BENCH_HF_H

#include <stdio.h>

#include "err.h"
#include "fit.h"
#include "img.h"

double now(void);
double median(double *v, int n); /* sorts v */
void die(const char *what, const glint_err *e);

/* The fit after a brush stroke, through a memo (bench_hf_stroke.c): medians
 * over the strokes. */
typedef struct stroke_row {
    int res, n, chunks;
    double again;       /* chunks summed again */
    double gather;      /* the stroked view read again and compared, seconds */
    double stream, factor, diag; /* the stroke's fit, seconds */
    double full;        /* the same fit without the memo, interleaved, seconds */
    double bytes;       /* what the stroke's factorization reads */
    /* every view read, seconds: not compared; compared, no value changed;
     * compared, every value changed */
    double read_all, same_all, diff_all;
} stroke_row;

/* reps strokes on view 0 of paint (fp's views), each fitted through a
 * memo and from nothing (the same bits, or the program stops). */
void stroke_fits(const fit_prep *fp, const img *paint, int reps, stroke_row *out);

/* A row under the warm table's, and the markdown table of n rows (bwp:
 * the bandwidth the bounds are taken at, bytes/s). */
void stroke_print(const stroke_row *w, double bwp);
void stroke_table(FILE *md, const stroke_row *rows, int n, double bwp);

#endif
