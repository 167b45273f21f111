/* merl.c: tabulated isotropic BRDFs in the MERL layout (merl.h). */
#include "merl.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "fsio.h"
#include "vec3.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define MERL_MAX_THREADS 64

const double merl_scale[3] = {1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0};

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void merl_free(merl_table *t)
{
    if (!t)
        return;
    free(t->f);
    t->f = NULL;
}

/* ---- the bins ---------------------------------------------------------------------- */

/* v rotated by angle about the unit axis (Rodrigues), as BRDFRead.cpp does */
static void rotate(const double v[3], const double a[3], double angle, double out[3])
{
    double c = cos(angle), s = sin(angle), d = v[0] * a[0] + v[1] * a[1] + v[2] * a[2];
    double x[3] = {a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2],
                   a[0] * v[1] - a[1] * v[0]};
    for (int e = 0; e < 3; e++)
        out[e] = v[e] * c + a[e] * d * (1.0 - c) + x[e] * s;
}

static const double Z_AXIS[3] = {0.0, 0.0, 1.0}, Y_AXIS[3] = {0.0, 1.0, 0.0};

long merl_index(const double wi[3], const double wo[3])
{
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]}, t[3], d[3];
    double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]), th, ph, td, pd, x;
    long i, j, k;
    if (!(hl > 0.0))
        return 0;
    for (int e = 0; e < 3; e++)
        h[e] /= hl;
    th = acos(h[2] > 1.0 ? 1.0 : h[2] < -1.0 ? -1.0 : h[2]);
    ph = atan2(h[1], h[0]);
    rotate(wi, Z_AXIS, -ph, t);
    rotate(t, Y_AXIS, -th, d);
    td = acos(d[2] > 1.0 ? 1.0 : d[2] < -1.0 ? -1.0 : d[2]);
    pd = atan2(d[1], d[0]);
    /* theta_half_index */
    if (th <= 0.0) {
        i = 0;
    } else {
        x = sqrt(th / (M_PI / 2.0) * MERL_TH * MERL_TH);
        i = (long)x;
        i = i < 0 ? 0 : i >= MERL_TH ? MERL_TH - 1 : i;
    }
    j = (long)(td / (M_PI * 0.5) * MERL_TD);
    j = j < 0 ? 0 : j >= MERL_TD ? MERL_TD - 1 : j;
    if (pd < 0.0)
        pd += M_PI;
    k = (long)(pd / M_PI * MERL_PD);
    k = k < 0 ? 0 : k >= MERL_PD ? MERL_PD - 1 : k;
    return k + MERL_PD * (j + MERL_TD * i);
}

/* The direction pair at the centre of bin (i, j, k) with the half vector at
 * azimuth ph (n = +Z). */
static void bin_dirs(int i, int j, int k, double ph, double wi[3], double wo[3])
{
    double u = (i + 0.5) / MERL_TH, th = u * u * (M_PI / 2.0);
    double td = (j + 0.5) * (M_PI / 2.0) / MERL_TD, pd = (k + 0.5) * M_PI / MERL_PD;
    double d[3] = {sin(td) * cos(pd), sin(td) * sin(pd), cos(td)}, t[3];
    double h[3] = {sin(th) * cos(ph), sin(th) * sin(ph), cos(th)}, c;
    rotate(d, Y_AXIS, th, t);
    rotate(t, Z_AXIS, ph, wi);
    c = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
    for (int e = 0; e < 3; e++)
        wo[e] = 2.0 * c * h[e] - wi[e];
}

/* f at (wi, wo) in the local frame; 0 (and *below set) under the horizon */
typedef struct source {
    merl_fn fn;
    const void *ctx;
} source;

static void eval_f(const source *src, const double wi[3], const double wo[3], double f[3],
                   int *below)
{
    *below = !(wi[2] > 1e-12 && wo[2] > 1e-12);
    if (*below) {
        f[0] = f[1] = f[2] = 0.0;
        return;
    }
    src->fn(src->ctx, Z_AXIS, wi, wo, f);
}

void merl_truth(const void *ctx, const double n[3], const double wi[3], const double wo[3],
                double f[3])
{
    merl_eval(ctx, n, wi, wo, f);
}

/* ---- tabulating ---------------------------------------------------------------------- */

typedef struct job {
    const source *m;
    double *f;
    int i0, i1, azimuths;
    long below, nonfinite, negative;
    double max_f;
} job;

static void *tabulate_rows(void *arg)
{
    job *jb = arg;
    for (int i = jb->i0; i < jb->i1; i++)
        for (int j = 0; j < MERL_TD; j++)
            for (int k = 0; k < MERL_PD; k++) {
                long idx = k + (long)MERL_PD * (j + (long)MERL_TD * i);
                double acc[3] = {0.0, 0.0, 0.0}, wi[3], wo[3], f[3];
                int below = 0, bad = 0;
                for (int a = 0; a < jb->azimuths; a++) {
                    bin_dirs(i, j, k, 2.0 * M_PI * a / jb->azimuths, wi, wo);
                    eval_f(jb->m, wi, wo, f, &below);
                    for (int c = 0; c < 3; c++) {
                        if (!isfinite(f[c]))
                            bad = 1;
                        acc[c] += f[c] / jb->azimuths;
                    }
                }
                jb->below += below;
                if (bad) {
                    jb->nonfinite++;
                    acc[0] = acc[1] = acc[2] = 0.0;
                }
                if (acc[0] < 0.0 || acc[1] < 0.0 || acc[2] < 0.0) {
                    jb->negative++;
                    for (int c = 0; c < 3; c++)
                        acc[c] = acc[c] < 0.0 ? 0.0 : acc[c];
                }
                for (int c = 0; c < 3; c++) {
                    jb->f[(size_t)c * MERL_N + idx] = acc[c];
                    if (acc[c] > jb->max_f)
                        jb->max_f = acc[c];
                }
            }
    return NULL;
}

/* Does m's value change with the azimuth of the half vector?  Compared at
 * 97 bins spread over the table, each at two azimuths. */
static int anisotropic(const source *m)
{
    unsigned s = 2463534242u;
    for (int t = 0; t < 97; t++) {
        double wa[3], oa[3], wb[3], ob[3], fa[3], fb[3];
        int i, j, k, below;
        s ^= s << 13, s ^= s >> 17, s ^= s << 5;
        i = (int)(s % MERL_TH);
        s ^= s << 13, s ^= s >> 17, s ^= s << 5;
        j = (int)(s % (MERL_TD * 3 / 4));
        s ^= s << 13, s ^= s >> 17, s ^= s << 5;
        k = (int)(s % MERL_PD);
        bin_dirs(i, j, k, 0.0, wa, oa);
        bin_dirs(i, j, k, 1.3, wb, ob);
        eval_f(m, wa, oa, fa, &below);
        eval_f(m, wb, ob, fb, &below);
        for (int c = 0; c < 3; c++)
            if (fabs(fa[c] - fb[c]) > 1e-7 * (fabs(fa[c]) + fabs(fb[c])) + 1e-12)
                return 1;
    }
    return 0;
}

int merl_tabulate(merl_fn fn, const void *ctx, int nthreads, merl_table *out, merl_stats *st,
                  glint_err *err)
{
    source src = {fn, ctx}, *m = &src;
    job jobs[MERL_MAX_THREADS];
    pthread_t th[MERL_MAX_THREADS];
    unsigned char started[MERL_MAX_THREADS] = {0};
    merl_stats dummy;
    double t0 = now_s();
    int nt;

    memset(out, 0, sizeof *out);
    if (!st)
        st = &dummy;
    memset(st, 0, sizeof *st);
    if (!fn)
        return glint_err_set(err, GLINT_EINVAL, "nothing to tabulate");
    if (!(out->f = malloc((size_t)3 * MERL_N * sizeof *out->f)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a MERL table (%zu MB)",
                             (size_t)3 * MERL_N * sizeof *out->f >> 20);
    st->anisotropic = anisotropic(m);
    st->azimuths = st->anisotropic ? MERL_AZIMUTHS : 1;
    nt = nthreads > 0 ? nthreads : (int)sysconf(_SC_NPROCESSORS_ONLN);
    nt = nt < 1 ? 1 : nt > MERL_MAX_THREADS ? MERL_MAX_THREADS : nt > MERL_TH ? MERL_TH : nt;
    for (int t = 0; t < nt; t++) {
        jobs[t] = (job){m, out->f, MERL_TH * t / nt, MERL_TH * (t + 1) / nt, st->azimuths, 0, 0,
                        0, 0.0};
        if (t > 0)
            started[t] = pthread_create(&th[t], NULL, tabulate_rows, &jobs[t]) == 0;
    }
    tabulate_rows(&jobs[0]);
    for (int t = 1; t < nt; t++) {
        if (started[t])
            pthread_join(th[t], NULL);
        else
            tabulate_rows(&jobs[t]); /* no thread: done here */
    }
    for (int t = 0; t < nt; t++) {
        st->below_horizon += jobs[t].below;
        st->nonfinite += jobs[t].nonfinite;
        st->negative += jobs[t].negative;
        if (jobs[t].max_f > st->max_f)
            st->max_f = jobs[t].max_f;
    }
    st->seconds = now_s() - t0;
    return 0;
}

/* ---- the file ------------------------------------------------------------------------- */

int merl_write_mem(const merl_table *t, void **data, size_t *len, glint_err *err)
{
    unsigned char *p;
    int32_t dims[3] = {MERL_TH, MERL_TD, MERL_PD};
    *data = NULL;
    *len = 0;
    if (!t || !t->f)
        return glint_err_set(err, GLINT_EINVAL, "no MERL table to write");
    if (!(p = malloc(MERL_FILE_BYTES)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a MERL file");
    memcpy(p, dims, sizeof dims);
    for (int c = 0; c < 3; c++)
        for (size_t i = 0; i < MERL_N; i++) {
            double v = t->f[(size_t)c * MERL_N + i] / merl_scale[c];
            memcpy(p + 12 + 8 * ((size_t)c * MERL_N + i), &v, 8);
        }
    *data = p;
    *len = MERL_FILE_BYTES;
    return 0;
}

int merl_write(const merl_table *t, const char *path, glint_err *err)
{
    void *data;
    size_t len;
    int rc = merl_write_mem(t, &data, &len, err);
    if (!rc)
        rc = fsio_write_atomic(path, data, len, err);
    free(data);
    return rc;
}

int merl_read_mem(const void *data, size_t len, merl_table *out, glint_err *err)
{
    const unsigned char *p = data;
    int32_t dims[3];
    memset(out, 0, sizeof *out);
    if (len < 12)
        return glint_err_set(err, GLINT_EFORMAT, "not a MERL BRDF file: %zu bytes", len);
    memcpy(dims, p, sizeof dims);
    if (dims[0] != MERL_TH || dims[1] != MERL_TD || dims[2] != MERL_PD)
        return glint_err_set(err, GLINT_EFORMAT,
                             "not a MERL BRDF file: dimensions %d x %d x %d, expected 90 x 90 x "
                             "180 (theta_h, theta_d, phi_d)",
                             (int)dims[0], (int)dims[1], (int)dims[2]);
    if (len != MERL_FILE_BYTES)
        return glint_err_set(err, GLINT_EFORMAT,
                             "MERL BRDF file of %zu bytes, expected %zu (3 x 1458000 doubles "
                             "after the dimensions): truncated or padded",
                             len, MERL_FILE_BYTES);
    if (!(out->f = malloc((size_t)3 * MERL_N * sizeof *out->f)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for a MERL table");
    for (int c = 0; c < 3; c++)
        for (size_t i = 0; i < MERL_N; i++) {
            double v;
            memcpy(&v, p + 12 + 8 * ((size_t)c * MERL_N + i), 8);
            if (!isfinite(v) || fabs(v) > 1e12) {
                merl_free(out);
                return glint_err_set(err, GLINT_EFORMAT,
                                     "MERL BRDF file: entry %zu of the %s channel is %g (not a "
                                     "finite BRDF value)",
                                     i, c == 0 ? "red" : c == 1 ? "green" : "blue", v);
            }
            out->f[(size_t)c * MERL_N + i] = v * merl_scale[c];
        }
    return 0;
}

int merl_read(const char *path, merl_table *out, glint_err *err)
{
    char *data = NULL;
    size_t len = 0;
    int rc;
    memset(out, 0, sizeof *out);
    if ((rc = fsio_read_all(path, MERL_FILE_BYTES + 1, &data, &len, err)))
        return rc;
    rc = merl_read_mem(data, len, out, err);
    free(data);
    return rc;
}

void merl_eval(const merl_table *t, const double n[3], const double wi[3], const double wo[3],
               double rgb[3])
{
    double tt[3], bb[3], li[3], lo[3];
    long idx;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!t || !t->f)
        return;
    {
        v3 nn = {n[0], n[1], n[2]}, T, B;
        v3_frame(nn, &T, &B);
        tt[0] = T.x, tt[1] = T.y, tt[2] = T.z;
        bb[0] = B.x, bb[1] = B.y, bb[2] = B.z;
    }
    li[0] = wi[0] * tt[0] + wi[1] * tt[1] + wi[2] * tt[2];
    li[1] = wi[0] * bb[0] + wi[1] * bb[1] + wi[2] * bb[2];
    li[2] = wi[0] * n[0] + wi[1] * n[1] + wi[2] * n[2];
    lo[0] = wo[0] * tt[0] + wo[1] * tt[1] + wo[2] * tt[2];
    lo[1] = wo[0] * bb[0] + wo[1] * bb[1] + wo[2] * bb[2];
    lo[2] = wo[0] * n[0] + wo[1] * n[1] + wo[2] * n[2];
    if (!(li[2] > 0.0) || !(lo[2] > 0.0))
        return;
    idx = merl_index(li, lo);
    for (int c = 0; c < 3; c++) {
        double v = t->f[(size_t)c * MERL_N + idx];
        rgb[c] = v > 0.0 ? v : 0.0;
    }
}

void merl_envlit(const void *ctx, const double uv[2], const double n[3], const double wi[3],
                 const double wo[3], double rgb[3])
{
    double c = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    (void)uv;
    merl_eval(ctx, n, wi, wo, rgb);
    for (int e = 0; e < 3; e++)
        rgb[e] *= c > 0.0 ? c : 0.0;
}

/* ---- measured materials by name ------------------------------------------------------ */

typedef struct held {
    char path[4096];
    merl_table t;
    int refs;
    unsigned long used;      /* a clock: larger is more recent */
} held;

static pthread_mutex_t held_lock = PTHREAD_MUTEX_INITIALIZER;
static held cache_[MERL_CACHE];
static unsigned long clock_;
static merl_resolver resolver_;

void merl_set_resolver(merl_resolver fn)
{
    resolver_ = fn;
}

int merl_resolve(const char *name, char *path, size_t len, glint_err *err)
{
    if (!name || !name[0])
        return glint_err_set(err, GLINT_EINVAL, "merl: a measured material needs a name");
    if (!resolver_)
        return glint_err_set(err, GLINT_ENOTFOUND, "no measured material '%.200s' here", name);
    return resolver_(name, path, len, err);
}

int merl_acquire(const char *name, const merl_table **out, glint_err *err)
{
    char path[4096];
    merl_table t;
    int rc, slot = -1;

    *out = NULL;
    if ((rc = merl_resolve(name, path, sizeof path, err)))
        return rc;
    pthread_mutex_lock(&held_lock);
    for (int i = 0; i < MERL_CACHE; i++)
        if (cache_[i].t.f && !strcmp(cache_[i].path, path)) {
            cache_[i].refs++;
            cache_[i].used = ++clock_;
            *out = &cache_[i].t;
            pthread_mutex_unlock(&held_lock);
            return 0;
        }
    pthread_mutex_unlock(&held_lock);
    if ((rc = merl_read(path, &t, err)))
        return rc;
    pthread_mutex_lock(&held_lock);
    for (int i = 0; i < MERL_CACHE; i++) /* an empty slot, else the oldest unused one */
        if (!cache_[i].refs && (slot < 0 || !cache_[i].t.f ||
                                (cache_[slot].t.f && cache_[i].used < cache_[slot].used)))
            slot = i;
    if (slot < 0) { /* every table in use: this one is the caller's alone */
        pthread_mutex_unlock(&held_lock);
        merl_free(&t);
        return glint_err_set(err, GLINT_EBUSY, "measured materials: %d in use, try again",
                             MERL_CACHE);
    }
    merl_free(&cache_[slot].t);
    snprintf(cache_[slot].path, sizeof cache_[slot].path, "%s", path);
    cache_[slot].t = t;
    cache_[slot].refs = 1;
    cache_[slot].used = ++clock_;
    *out = &cache_[slot].t;
    pthread_mutex_unlock(&held_lock);
    return 0;
}

void merl_release(const merl_table *t)
{
    if (!t)
        return;
    pthread_mutex_lock(&held_lock);
    for (int i = 0; i < MERL_CACHE; i++)
        if (&cache_[i].t == t && cache_[i].refs > 0)
            cache_[i].refs--;
    pthread_mutex_unlock(&held_lock);
}
