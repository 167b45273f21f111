/* envlit.c: radiance under an environment's lights (envlit.h). */
#include "envlit.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "par.h"
#include "scene.h"
#include "vis.h"

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int lights_ok(const env_lights *l, glint_err *err)
{
    if (!l || l->k < 1 || !l->dir || !l->power)
        return glint_err_set(err, GLINT_EINVAL, "no lights to shade with");
    return 0;
}

void envlit_vis_free(envlit_vis *v)
{
    if (!v)
        return;
    free(v->bits);
    memset(v, 0, sizeof *v);
}

int envlit_vis_vertices(const mesh *m, const env_lights *l, int shadows, envlit_vis *out,
                        const glint_cancel *cancel, glint_err *err)
{
    vis_scene *vs = NULL;
    double t0 = now_s();
    int rc;

    memset(out, 0, sizeof *out);
    if ((rc = lights_ok(l, err)) || (rc = mesh_validate(m, err)))
        return rc;
    out->nverts = m->nverts;
    out->k = l->k;
    out->words = VIS_WORDS(l->k);
    if (!shadows)
        return 0;
    if (vis_mesh_convex(m, ENVLIT_CONVEX_TOL)) {
        out->convex = 1;
        return 0;
    }
    out->bits = malloc((size_t)m->nverts * (size_t)out->words * sizeof *out->bits);
    if (!out->bits)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the visibility of %d vertices",
                             m->nverts);
    if ((rc = vis_open(m, &vs, err)) ||
        (rc = vis_compute(vs, m->nverts, m->pos, m->nrm, l->k, l->dir, out->bits, 0, &out->rays,
                          cancel, err))) {
        vis_close(vs);
        envlit_vis_free(out);
        return rc;
    }
    vis_close(vs);
    out->seconds = now_s() - t0;
    return 0;
}

/* B for one shading point: n unit, wo unit; bits the point's visibility
 * words or NULL. */
static void shade_point(const env_lights *l, const uint64_t *bits, envlit_fn fn,
                        const void *ctx, const double *uv, const double n[3],
                        const double wo[3], double acc[3])
{
    acc[0] = acc[1] = acc[2] = 0.0;
    for (int k = 0; k < l->k; k++) {
        const double *d = l->dir + 3 * k;
        double r[3];
        if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] <= 0.0 ||
            (bits && !((bits[k >> 6] >> (k & 63)) & 1)))
            continue;
        fn(ctx, uv, n, d, wo, r);
        for (int e = 0; e < 3; e++)
            acc[e] += l->power[3 * k + e] * r[e];
    }
}

typedef struct vjob {
    const uint8_t *need;       /* vertices of triangles that may face the eye (NULL: all) */
    const mesh *m;
    const env_lights *l;
    const envlit_vis *vis;
    envlit_fn fn;
    const void *ctx;
    double eye[3], scale;
    float *rgb;
    int lo, hi;
    const glint_cancel *cancel;
    int *stopped;              /* shared: set once a thread was told to stop */
} vjob;

static void *vertex_range(void *arg)
{
    const vjob *j = arg;
    long every = glint_cancel_every(j->l->k);
    for (int i = j->lo; i < j->hi; i++) {
        const float *p = j->m->pos + 3 * (size_t)i, *q = j->m->nrm + 3 * (size_t)i;
        if (j->cancel && (i - j->lo) % every == 0) {
            if (__atomic_load_n(j->stopped, __ATOMIC_RELAXED))
                break;
            if (glint_cancelled(j->cancel)) {
                __atomic_store_n(j->stopped, 1, __ATOMIC_RELAXED);
                break;
            }
        }
        if (j->need && !j->need[i]) {
            memset(j->rgb + 3 * (size_t)i, 0, 3 * sizeof *j->rgb);
            continue;
        }
        double n[3] = {q[0], q[1], q[2]}, wo[3], acc[3], ln, lo, c, uv[2] = {0.0, 0.0};
        for (int e = 0; e < 3; e++)
            wo[e] = j->eye[e] - p[e];
        ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        lo = sqrt(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
        if (!(ln > 0.0) || !(lo > 0.0)) {
            memset(j->rgb + 3 * (size_t)i, 0, 3 * sizeof *j->rgb);
            continue;
        }
        for (int e = 0; e < 3; e++) {
            n[e] /= ln;
            wo[e] /= lo;
        }
        c = n[0] * wo[0] + n[1] * wo[1] + n[2] * wo[2];
        if (c < ENVLIT_GRAZE) { /* bend towards the surface (envlit.h) */
            double t[3], lt;
            for (int e = 0; e < 3; e++)
                t[e] = wo[e] - c * n[e];
            lt = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
            if (lt > 0.0) {
                double s = sqrt(1.0 - ENVLIT_GRAZE * ENVLIT_GRAZE) / lt;
                for (int e = 0; e < 3; e++)
                    wo[e] = t[e] * s + ENVLIT_GRAZE * n[e];
            } else {
                memcpy(wo, n, sizeof wo);
            }
        }
        if (j->m->uv) {
            uv[0] = j->m->uv[2 * (size_t)i];
            uv[1] = j->m->uv[2 * (size_t)i + 1];
        }
        shade_point(j->l, j->vis->bits ? j->vis->bits + (size_t)i * j->vis->words : NULL, j->fn,
                    j->ctx, j->m->uv ? uv : NULL, n, wo, acc);
        for (int e = 0; e < 3; e++)
            j->rgb[3 * (size_t)i + e] = (float)(j->scale * acc[e]);
    }
    return NULL;
}

#define ENVLIT_MAX_THREADS 64

int envlit_vertices(const mesh *m, const env_lights *l, const envlit_vis *vis, envlit_fn fn,
                    const void *ctx, const double eye[3], double scale, int nthreads,
                    float *rgb, const glint_cancel *cancel, glint_err *err)
{
    vjob jobs[ENVLIT_MAX_THREADS];
    pthread_t th[ENVLIT_MAX_THREADS];
    uint8_t *need;
    int nt, started = 0, rc, stopped = 0;

    if ((rc = lights_ok(l, err)))
        return rc;
    if (!vis || vis->nverts != m->nverts || vis->k != l->k)
        return glint_err_set(err, GLINT_EINVAL, "the visibility belongs to another mesh or lights");
    if (!(scale >= 0.0) || !isfinite(scale))
        return glint_err_set(err, GLINT_EINVAL, "scale %g must be finite and >= 0", scale);
    for (int e = 0; e < 3; e++)
        if (!isfinite(eye[e]))
            return glint_err_set(err, GLINT_ENONFINITE, "the eye is not finite");
    /* Only vertices of triangles that may face the eye are shaded: a
     * triangle all of whose vertex normals turn away by more than
     * ENVLIT_CULL from the eye is not seen (closed meshes hide it; on open
     * ones, drawn from both sides, its pixels face away and shade to 0).
     * Skipped vertices get 0.  Without memory for the flags, all are shaded. */
    need = calloc((size_t)m->nverts, 1);
    if (need) {
        uint8_t *front = malloc((size_t)m->nverts);
        if (!front) {
            free(need);
            need = NULL;
        } else {
            for (int i = 0; i < m->nverts; i++) {
                const float *p = m->pos + 3 * (size_t)i, *q = m->nrm + 3 * (size_t)i;
                double d[3] = {eye[0] - p[0], eye[1] - p[1], eye[2] - p[2]};
                double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                double nl = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2]);
                front[i] = !(q[0] * d[0] + q[1] * d[1] + q[2] * d[2] < -ENVLIT_CULL * dl * nl);
            }
            for (size_t t = 0; t < (size_t)m->ntris; t++) {
                const uint32_t *v = m->tri + 3 * t;
                if (front[v[0]] || front[v[1]] || front[v[2]])
                    need[v[0]] = need[v[1]] = need[v[2]] = 1;
            }
            free(front);
        }
    }
    nt = nthreads > 0 ? nthreads : (int)sysconf(_SC_NPROCESSORS_ONLN);
    nt = nt < 1 ? 1 : nt > ENVLIT_MAX_THREADS ? ENVLIT_MAX_THREADS : nt;
    if (nt > m->nverts / 256 + 1) /* not worth a thread below a few hundred vertices */
        nt = m->nverts / 256 + 1;
    for (int t = 0; t < nt; t++) {
        vjob *j = &jobs[t];
        j->need = need;
        j->m = m;
        j->l = l;
        j->vis = vis;
        j->fn = fn;
        j->ctx = ctx;
        memcpy(j->eye, eye, sizeof j->eye);
        j->scale = scale;
        j->rgb = rgb;
        j->lo = (int)((long)m->nverts * t / nt);
        j->hi = (int)((long)m->nverts * (t + 1) / nt);
        j->cancel = cancel;
        j->stopped = &stopped;
    }
    for (int t = 1; t < nt; t++) {
        if (pthread_create(&th[t], NULL, vertex_range, &jobs[t]))
            break;
        started = t;
    }
    vertex_range(&jobs[0]);
    for (int t = started + 1; t < nt; t++) /* threads that could not start: here */
        vertex_range(&jobs[t]);
    for (int t = 1; t <= started; t++)
        pthread_join(th[t], NULL);
    free(need);
    if (stopped)
        return glint_cancel_err(err, "shading the vertices");
    return 0;
}

/* Pixels shaded per task of envlit_gbuf's par_run: each writes its own. */
#define ENVLIT_CHUNK 1024

typedef struct pjob {
    const gbuf *g;
    const env_lights *l;
    const int *pix;            /* the covered pixels */
    const uint64_t *bits;      /* their visibility words, or NULL */
    int words;
    envlit_fn fn;              /* a light at a time, or */
    envlit_sum_fn sum;         /* every light at once */
    const void *ctx;
    double scale;
    img *out;
    size_t n;
    const glint_cancel *cancel;
    int stopped;               /* set once a task was told to stop */
} pjob;

static void pixel_chunk(void *arg, int task)
{
    pjob *x = arg;
    const gbuf *g = x->g;
    size_t lo = (size_t)task * ENVLIT_CHUNK, hi = lo + ENVLIT_CHUNK;
    size_t every = (size_t)glint_cancel_every(x->l->k);
    if (hi > x->n)
        hi = x->n;
    for (size_t i = lo; i < hi; i++) {
        size_t p = (size_t)x->pix[i];
        if ((i - lo) % every == 0) {
            if (__atomic_load_n(&x->stopped, __ATOMIC_RELAXED))
                return;
            if (glint_cancelled(x->cancel)) {
                __atomic_store_n(&x->stopped, 1, __ATOMIC_RELAXED);
                return;
            }
        }
        double nn[3], wo[3], acc[3], uv[2] = {0.0, 0.0};
        for (int e = 0; e < 3; e++) {
            nn[e] = g->nrm[3 * p + e];
            wo[e] = g->wo[3 * p + e];
        }
        if (g->uv) {
            uv[0] = g->uv[2 * p];
            uv[1] = g->uv[2 * p + 1];
        }
        if (x->sum)
            x->sum(x->ctx, x->l, x->bits ? x->bits + i * (size_t)x->words : NULL,
                   g->uv ? uv : NULL, nn, wo, acc);
        else
            shade_point(x->l, x->bits ? x->bits + i * (size_t)x->words : NULL, x->fn, x->ctx,
                        g->uv ? uv : NULL, nn, wo, acc);
        for (int e = 0; e < 3; e++)
            x->out->px[3 * p + e] = (float)(x->scale * acc[e]);
    }
}

static int gbuf_shade(const gbuf *g, const mesh *m, const env_lights *l, int shadows,
                      envlit_fn fn, envlit_sum_fn sum, const void *ctx, double scale, img *out,
                      const glint_cancel *cancel, glint_err *err)
{
    size_t np = (size_t)g->width * g->height, n = 0;
    int *pix = NULL, words = l ? VIS_WORDS(l->k) : 1, rc;
    uint64_t *bits = NULL;
    float *pos = NULL, *nrm = NULL;
    vis_scene *vs = NULL;

    memset(out, 0, sizeof *out);
    if ((rc = lights_ok(l, err)))
        return rc;
    if (!(scale >= 0.0) || !isfinite(scale))
        return glint_err_set(err, GLINT_EINVAL, "scale %g must be finite and >= 0", scale);
    if ((rc = img_alloc(out, g->width, g->height, 3, err)))
        return rc;
    if (!(pix = malloc((np ? np : 1) * sizeof *pix))) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory");
        goto done;
    }
    for (size_t p = 0; p < np; p++)
        if (g->mask[p])
            pix[n++] = (int)p;
    if (shadows && n && !vis_mesh_convex(m, ENVLIT_CONVEX_TOL)) {
        pos = malloc(3 * n * sizeof *pos);
        nrm = malloc(3 * n * sizeof *nrm);
        bits = malloc(n * (size_t)words * sizeof *bits);
        if (!pos || !nrm || !bits) {
            rc = glint_err_set(err, GLINT_ENOMEM, "out of memory for shadow rays");
            goto done;
        }
        for (size_t i = 0; i < n; i++) {
            memcpy(pos + 3 * i, g->pos + 3 * (size_t)pix[i], 3 * sizeof *pos);
            memcpy(nrm + 3 * i, g->nrm + 3 * (size_t)pix[i], 3 * sizeof *nrm);
        }
        if ((rc = vis_open(m, &vs, err)) ||
            (rc = vis_compute(vs, (int)n, pos, nrm, l->k, l->dir, bits, 0, NULL, cancel, err)))
            goto done;
    }
    {
        pjob x = {g, l, pix, bits, words, fn, sum, ctx, scale, out, n, cancel, 0};
        par_run((int)((n + ENVLIT_CHUNK - 1) / ENVLIT_CHUNK), pixel_chunk, &x);
        if (x.stopped)
            rc = glint_cancel_err(err, "shading the pixels");
    }
done:
    vis_close(vs);
    free(pix);
    free(pos);
    free(nrm);
    free(bits);
    if (rc)
        img_free(out);
    return rc;
}

int envlit_gbuf(const gbuf *g, const mesh *m, const env_lights *l, int shadows, envlit_fn fn,
                const void *ctx, double scale, img *out, const glint_cancel *cancel,
                glint_err *err)
{
    if (!fn) {
        memset(out, 0, sizeof *out);
        return glint_err_set(err, GLINT_EINVAL, "no shader");
    }
    return gbuf_shade(g, m, l, shadows, fn, NULL, ctx, scale, out, cancel, err);
}

int envlit_gbuf_summed(const gbuf *g, const mesh *m, const env_lights *l, int shadows,
                       envlit_sum_fn sum, const void *ctx, double scale, img *out,
                       const glint_cancel *cancel, glint_err *err)
{
    if (!sum) {
        memset(out, 0, sizeof *out);
        return glint_err_set(err, GLINT_EINVAL, "no shader");
    }
    return gbuf_shade(g, m, l, shadows, NULL, sum, ctx, scale, out, cancel, err);
}

void envlit_background(const env_map *map, double psi, double intensity,
                       const scene_view *v, const uint8_t *mask, img *out)
{
    double fwd[3], right[3], up[3], t = tan(v->half_fov);
    int w = out->width, h = out->height;
    scene_view_frame(v, fwd, right, up);
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++) {
            size_t p = (size_t)j * w + i;
            double sx = (2.0 * (i + 0.5) / w - 1.0) * w / h, sy = 1.0 - 2.0 * (j + 0.5) / h;
            double d[3], l = 0.0, rgb[3];
            if (mask && mask[p])
                continue;
            for (int e = 0; e < 3; e++) {
                d[e] = fwd[e] + t * (sx * right[e] + sy * up[e]);
                l += d[e] * d[e];
            }
            l = sqrt(l);
            for (int e = 0; e < 3; e++)
                d[e] /= l;
            env_radiance(map, d, psi, intensity, rgb);
            for (int e = 0; e < 3; e++)
                out->px[3 * p + e] = (float)rgb[e];
        }
}
