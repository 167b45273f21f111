/* merl.h: a tabulated isotropic BRDF in the layout of the MERL BRDF
 * database (Matusik, Pfister, Brand and McMillan 2003, "A Data-Driven
 * Reflectance Model"; its reader BRDFRead.cpp), which BRDF Explorer, ALTA
 * and dj_brdf read: a material made in glint, taken elsewhere, and measured
 * materials brought in as truths to paint from.
 *
 * The file
 *   3 int32 (little-endian): the dimensions 90, 90, 180 (theta_h, theta_d,
 *   phi_d), then 3 x MERL_N doubles (little-endian): all of red, then
 *   green, then blue.  Entry (i, j, k) is at k + 180 (j + 90 i); the BRDF
 *   is the stored value times the channel's scale, 1/1500, 1.15/1500 and
 *   1.66/1500 for red, green and blue.  Negative entries mark bins no
 *   measurement reached (readers skip or clamp them).
 *
 * The bins, in Rusinkiewicz's half/difference angles (n = +Z; h the half
 * vector, at theta_h from n and azimuth phi_h; the difference vector d is
 * wi in the frame where h is the pole: wi rotated by -phi_h about n, then
 * by -theta_h about +Y):
 *   theta_h: i = floor(90 sqrt(theta_h / (pi/2))), finer near the normal
 *            where highlights are;
 *   theta_d: j = floor(90 theta_d / (pi/2));
 *   phi_d:   k = floor(180 phi_d / pi), phi_d taken modulo pi (reciprocity
 *            and isotropy make phi_d and phi_d + pi the same).
 * Lookups are nearest-bin, exactly as BRDFRead.cpp does them, so a table
 * reads the same here as in the tools that share that reader.
 *
 * Tabulating a material (merl_from_material, merl_material.h) evaluates it at each bin's
 * centre, theta_h = ((i + 1/2) / 90)^2 pi/2, theta_d = (j + 1/2) pi/180,
 * phi_d = (k + 1/2) pi/180: f = the material's value per unit light
 * divided by n.wi (readable.h's convention), 0 where wi or wo falls under
 * the horizon.  The table holds isotropic BRDFs only: a material whose
 * value depends on the azimuth of the half vector (anisotropic, e.g. hf2d
 * with 2D factors) is averaged over MERL_AZIMUTHS azimuths, and one that
 * varies over the surface is taken at its average over the surface
 * (material_eval with no uv); merl_stats says which happened.
 *
 * Thread-safety: tables are read-only once made; merl_tabulate uses its
 * own threads and reads its source only. */
#ifndef GLINT_MERL_H
#define GLINT_MERL_H

#include <stddef.h>

#include "err.h"

#define MERL_TH 90
#define MERL_TD 90
#define MERL_PD 180
#define MERL_N (MERL_TH * MERL_TD * MERL_PD) /* 1458000 bins */
#define MERL_FILE_BYTES (12 + (size_t)3 * MERL_N * 8)
#define MERL_AZIMUTHS 8

extern const double merl_scale[3];

typedef struct merl_table {
    double *f; /* 3 x MERL_N: the BRDF (scale applied), channel-major; < 0: no data */
} merl_table;

/* What tabulating did. */
typedef struct merl_stats {
    int anisotropic;     /* the material's value changed with the half vector's azimuth */
    int azimuths;        /* half-vector azimuths averaged per bin (1 or MERL_AZIMUTHS) */
    int spatial;         /* the material varies over the surface: its average was taken */
    long below_horizon;  /* bins whose centre has wi or wo under the horizon (written 0) */
    long nonfinite;      /* bins where the material gave a non-finite value (written 0) */
    long negative;       /* bins where its value was negative (written 0: a table reads
                            < 0 as no data; an unconstrained fit can be negative in places) */
    double max_f;        /* largest f written */
    double seconds;
} merl_stats;


/* Tabulate any BRDF given as a function: f at unit (n, wi, wo), per
 * steradian, no cosine (brdf_eval's and merl_truth's shape; paint.h's
 * paint_fn).  Called with n = +Z, wi and wo above the horizon. */
typedef void (*merl_fn)(const void *ctx, const double n[3], const double wi[3],
                        const double wo[3], double f[3]);
int merl_tabulate(merl_fn fn, const void *ctx, int nthreads, merl_table *out, merl_stats *st,
                  glint_err *err);

/* The file's bytes (OUT: *data, MERL_FILE_BYTES long, free()). */
int merl_write_mem(const merl_table *t, void **data, size_t *len, glint_err *err);
/* Written atomically (fsio.h). */
int merl_write(const merl_table *t, const char *path, glint_err *err);

/* Parse a file's bytes: GLINT_EFORMAT naming what is wrong (size,
 * dimensions, non-finite entries) otherwise.  OUT: *out. */
int merl_read_mem(const void *data, size_t len, merl_table *out, glint_err *err);
int merl_read(const char *path, merl_table *out, glint_err *err);

/* f at unit n, wi, wo (OUT: rgb[3], per steradian, no cosine): the nearest
 * bin, negative entries read as 0; 0 below either horizon.  The frame
 * around n is vec3.h's v3_frame (an isotropic table does not depend on it). */
void merl_eval(const merl_table *t, const double n[3], const double wi[3], const double wo[3],
               double rgb[3]);

/* merl_eval as a truth function (ctx: const merl_table *), for paint.h's
 * paint_views_fn: painting from a measured material. */
void merl_truth(const void *ctx, const double n[3], const double wi[3], const double wo[3],
                double f[3]);

/* merl_eval times n.wi, as envlit.h's envlit_fn (ctx: const merl_table *):
 * a measured material under an environment. */
void merl_envlit(const void *ctx, const double uv[2], const double n[3], const double wi[3],
                 const double wo[3], double rgb[3]);

/* ---- measured materials by name ("merl:NAME" truths) ------------------------------
 * The host says where a name's file is (merl_set_resolver; the command
 * line: a path; glintd: a file of its --measured-dir, never outside it);
 * merl_acquire reads it once and keeps the MERL_CACHE most recently used
 * tables (35 MB each), shared read-only by any number of threads. */
#define MERL_CACHE 2
typedef int (*merl_resolver)(const char *name, char *path, size_t len, glint_err *err);
void merl_set_resolver(merl_resolver fn);
/* The file of NAME (GLINT_ENOTFOUND saying why not). */
int merl_resolve(const char *name, char *path, size_t len, glint_err *err);
/* The table of NAME (OUT: *out, held until merl_release). */
int merl_acquire(const char *name, const merl_table **out, glint_err *err);
void merl_release(const merl_table *t);

/* The bin of a direction pair in the local frame (n = +Z): the index
 * k + 180 (j + 90 i), as BRDFRead.cpp computes it. */
long merl_index(const double wi[3], const double wo[3]);

void merl_free(merl_table *t);

#endif
