/* srbf.c: the SRBF basis, static terms, energy rows and albedo (srbf.h). */
#include "srbf.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Spherical variance of the density proportional to G^2 (vMF, kappa = 2 lambda). */
static double variance_of(double lambda)
{
    double x = 2.0 * lambda;
    double coth = x > 20.0 ? 1.0 : 1.0 / tanh(x);
    return 1.0 - (coth - 1.0 / x);
}

int srbf_lambda(double sigma, double *lambda, glint_err *err)
{
    double lo = log(1e-9), hi = log(1e9), target;
    if (!(sigma >= SRBF_MIN_SIGMA && sigma <= SRBF_MAX_SIGMA))
        return glint_err_set(err, GLINT_ERANGE, "sigma %g outside [%g, %g] radians", sigma,
                             SRBF_MIN_SIGMA, SRBF_MAX_SIGMA);
    target = sigma * sigma;
    /* the variance falls from 1 to 0 as lambda grows: bisect on log lambda */
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi);
        if (variance_of(exp(mid)) > target)
            lo = mid;
        else
            hi = mid;
        if (hi - lo < 1e-14)
            break;
    }
    *lambda = exp(0.5 * (lo + hi));
    return 0;
}

static void put_unit(double *out, double x, double y, double z)
{
    double l = sqrt(x * x + y * y + z * z);
    out[0] = x / l;
    out[1] = y / l;
    out[2] = z / l;
}

/* Side-face point of face f (0 +x, 1 +y, 2 -x, 3 -y) at column coordinate u
 * and height z. */
static void side_point(int f, double u, double z, double *out)
{
    switch (f) {
    case 0: put_unit(out, 1.0, u, z); break;
    case 1: put_unit(out, -u, 1.0, z); break;
    case 2: put_unit(out, -1.0, -u, z); break;
    default: put_unit(out, u, -1.0, z); break;
    }
}

int srbf_hemicube(int res, double *xi)
{
    int J = 0, r = res;
    for (int b = 0; b < r; b++)
        for (int a = 0; a < r; a++) {
            if (xi)
                put_unit(xi + 3 * J, -1.0 + (2.0 * a + 1.0) / r, -1.0 + (2.0 * b + 1.0) / r, 1.0);
            J++;
        }
    for (int f = 0; f < 4; f++)
        for (int row = 0; row < r; row++) {
            double z = -1.0 + (2.0 * row + 1.0) / r;
            if (z <= 1e-12)
                continue;
            for (int a = 0; a < r; a++) {
                if (xi)
                    side_point(f, -1.0 + (2.0 * a + 1.0) / r, z, xi + 3 * J);
                J++;
            }
        }
    if (r % 2 == 1)
        for (int ring = 0; ring < 4 * r; ring += 2) {
            if (xi)
                side_point(ring / r, -1.0 + (2.0 * (ring % r) + 1.0) / r, 0.0, xi + 3 * J);
            J++;
        }
    return J;
}

int srbf_basis_make(int res, double sigma, srbf_basis *b, glint_err *err)
{
    int rc;
    memset(b, 0, sizeof *b);
    if (res < SRBF_MIN_RES || res > SRBF_MAX_RES)
        return glint_err_set(err, GLINT_ERANGE, "basis resolution %d outside %d..%d", res,
                             SRBF_MIN_RES, SRBF_MAX_RES);
    if ((rc = srbf_lambda(sigma, &b->lambda, err)))
        return rc;
    b->res = res;
    b->sigma = sigma;
    b->J = srbf_hemicube(res, NULL);
    if (!(b->xi = malloc((size_t)3 * b->J * sizeof *b->xi)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    srbf_hemicube(res, b->xi);
    return 0;
}

void srbf_basis_free(srbf_basis *b)
{
    if (!b)
        return;
    free(b->xi);
    memset(b, 0, sizeof *b);
}

void srbf_frame(const double n[3], double t[3], double b[3])
{
    /* t = +z x n = (-n.y, n.x, 0) */
    double tx = -n[1], ty = n[0], tz = 0.0, l = sqrt(tx * tx + ty * ty);
    if (l < 1e-9) { /* +x x n = (0, -n.z, n.y) */
        tx = 0.0;
        ty = -n[2];
        tz = n[1];
        l = sqrt(ty * ty + tz * tz);
    }
    t[0] = tx / l;
    t[1] = ty / l;
    t[2] = tz / l;
    b[0] = n[1] * t[2] - n[2] * t[1];
    b[1] = n[2] * t[0] - n[0] * t[2];
    b[2] = n[0] * t[1] - n[1] * t[0];
}

double srbf_static_eval(const srbf_static *s, const double wi[3], const double wo[3])
{
    double a = wi[2], b = wo[2], h[3], hl, x, F;
    if (!(a > 0.0) || !(b > 0.0))
        return 0.0;
    for (int e = 0; e < 3; e++)
        h[e] = wi[e] + wo[e];
    hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    x = hl > 0.0 ? (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl : 1.0;
    x = 1.0 - (x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x);
    F = s->f0 + (1.0 - s->f0) * x * x * x * x * x;
    if (s->kind == SRBF_STATIC_PAPER)
        return F / (a + b - a * b);
    {
        /* height-correlated Smith-GGX: G2 / (4ab) = 0.5 / (b L(a) + a L(b)) */
        double a2 = s->alpha * s->alpha;
        double la = sqrt(a2 + (1.0 - a2) * a * a), lb = sqrt(a2 + (1.0 - a2) * b * b);
        return F * 0.5 / (b * la + a * lb);
    }
}

void srbf_p(const srbf_basis *b, const double *c, const double h[3], double rgb[3])
{
    int J = b->J;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    for (int j = 0; j < J; j++) {
        const double *x = b->xi + 3 * j;
        double e = b->lambda * (h[0] * x[0] + h[1] * x[1] + h[2] * x[2] - 1.0);
        if (e < -40.0)
            continue;
        e = exp(e);
        rgb[0] += c[j] * e;
        rgb[1] += c[J + j] * e;
        rgb[2] += c[2 * J + j] * e;
    }
}

int srbf_energy_dirs(int grazing, double *wo)
{
    int n = srbf_hemicube(8, wo);
    /* a Fibonacci spiral over the hemisphere, uniform in solid angle, so the
     * rows are dense everywhere (the hemicube's top face leaves 14 degrees
     * between rows, over which the albedo of 9-degree lobes moves by 1%) */
    for (int i = 0; i < SRBF_ENERGY_FIB; i++) {
        double z = 1.0 - (i + 0.5) / SRBF_ENERGY_FIB, r = sqrt(1.0 - z * z);
        double ph = i * M_PI * (3.0 - sqrt(5.0));
        if (wo) {
            wo[3 * n] = r * cos(ph);
            wo[3 * n + 1] = r * sin(ph);
            wo[3 * n + 2] = z;
        }
        n++;
    }
    for (int g = 0; g < grazing; g++) {
        double el = (0.5 + 2.0 * g) * M_PI / 180.0;
        for (int k = 0; k < 64; k++) {
            double az = 2.0 * M_PI * (k + 0.5) / 64.0;
            if (wo) {
                wo[3 * n] = cos(el) * cos(az);
                wo[3 * n + 1] = cos(el) * sin(az);
                wo[3 * n + 2] = sin(el);
            }
            n++;
        }
    }
    return n;
}

/* Gauss-Legendre nodes and weights on (0, 1) (OUT: x[n], w[n]). */
static void gauss01(int n, double *x, double *w)
{
    for (int i = 0; i < n; i++) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), pp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p1 = 1.0, p2 = 0.0, dz;
            for (int k = 1; k <= n; k++) {
                double p3 = p2;
                p2 = p1;
                p1 = ((2.0 * k - 1.0) * z * p2 - (k - 1.0) * p3) / k;
            }
            pp = n * (z * p1 - p2) / (z * z - 1.0);
            dz = p1 / pp;
            z -= dz;
            if (fabs(dz) < 1e-15)
                break;
        }
        x[i] = 0.5 * (1.0 - z);
        w[i] = 1.0 / ((1.0 - z * z) * pp * pp);
    }
}

/* The quadrature over wi on the local hemisphere: directions and weights
 * (cos theta Gauss-Legendre x phi midpoint). */
typedef struct quad {
    int n;
    double *d, *w;
} quad;

/* Gauss-Legendre panels in cos theta, graded toward the horizon: near a
 * grazing outgoing direction the static term changes on the scale of
 * wo.n (0.009 at 0.5 degrees), which one panel resolves only slowly.
 * Panels [0, 0.02], [0.02, 0.2], [0.2, 1] with nq/4, nq/4 and nq/2 nodes;
 * phi by the midpoint rule with 3 nq steps. */
static int quad_make(int nq, quad *q)
{
    static const double edge[4] = {0.0, 0.02, 0.2, 1.0};
    int nphi = 3 * nq, k = 0, per[3] = {nq / 4, nq / 4, nq - 2 * (nq / 4)};
    double *x = malloc((size_t)nq * sizeof *x), *wx = malloc((size_t)nq * sizeof *wx);
    q->n = nq * nphi;
    q->d = malloc((size_t)3 * q->n * sizeof *q->d);
    q->w = malloc((size_t)q->n * sizeof *q->w);
    if (!x || !wx || !q->d || !q->w) {
        free(x);
        free(wx);
        free(q->d);
        free(q->w);
        return -1;
    }
    for (int pnl = 0, at = 0; pnl < 3; pnl++) {
        double a = edge[pnl], len = edge[pnl + 1] - edge[pnl];
        gauss01(per[pnl], x + at, wx + at);
        for (int i = at; i < at + per[pnl]; i++) {
            x[i] = a + len * x[i];
            wx[i] *= len;
        }
        at += per[pnl];
    }
    for (int i = 0; i < nq; i++) {
        double ct = x[i], st = sqrt(1.0 - ct * ct);
        for (int j = 0; j < nphi; j++) {
            double ph = 2.0 * M_PI * (j + 0.5) / nphi;
            q->d[3 * k] = st * cos(ph);
            q->d[3 * k + 1] = st * sin(ph);
            q->d[3 * k + 2] = ct;
            q->w[k] = wx[i] * 2.0 * M_PI / nphi;
            k++;
        }
    }
    free(x);
    free(wx);
    return 0;
}

/* The quadrature node k as an incident direction for outgoing wo: OUT wi,
 * h and the weight of G(h.xi) (w s cos and the Jacobian).  Above
 * SRBF_HSPACE_Z the nodes are incident directions; below, where a grazing
 * wo makes h swing across the hemisphere as wi passes its mirror
 * direction, they are half vectors: wi = 2 (wo.h) h - wo, dwi = 4 (wo.h) dh. */
#define SRBF_HSPACE_Z 0.1
static double node(const srbf_static *s, const quad *q, int k, const double wo[3], double wi[3],
                   double h[3])
{
    const double *d = q->d + 3 * k;
    double hl, wt;
    if (wo[2] > SRBF_HSPACE_Z) {
        for (int e = 0; e < 3; e++) {
            wi[e] = d[e];
            h[e] = d[e] + wo[e];
        }
        hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
        if (!(hl > 0.0))
            return 0.0;
        for (int e = 0; e < 3; e++)
            h[e] /= hl;
        return q->w[k] * srbf_static_eval(s, wi, wo) * wi[2];
    }
    {
        double oh = wo[0] * d[0] + wo[1] * d[1] + wo[2] * d[2];
        if (oh <= 0.0)
            return 0.0;
        for (int e = 0; e < 3; e++) {
            h[e] = d[e];
            wi[e] = 2.0 * oh * d[e] - wo[e];
        }
        if (wi[2] <= 0.0)
            return 0.0;
        wt = q->w[k] * 4.0 * oh;
        return wt * srbf_static_eval(s, wi, wo) * wi[2];
    }
}

/* One energy row: g[j] = sum_nodes w s cos G(h.xi_j). */
static void energy_row(const srbf_basis *b, const srbf_static *s, const quad *q,
                       const double wo[3], double *g)
{
    int J = b->J;
    double cut = 1.0 - 40.0 / b->lambda;
    memset(g, 0, (size_t)J * sizeof *g);
    for (int k = 0; k < q->n; k++) {
        double wi[3], h[3], wt = node(s, q, k, wo, wi, h);
        if (wt == 0.0)
            continue;
        for (int j = 0; j < J; j++) {
            const double *x = b->xi + 3 * j;
            double d = h[0] * x[0] + h[1] * x[1] + h[2] * x[2];
            if (d > cut)
                g[j] += wt * exp(b->lambda * (d - 1.0));
        }
    }
}

typedef struct erows_job {
    const srbf_basis *b;
    const srbf_static *s;
    const quad *q;
    const double *wo;
    double *g;
    int l0, l1;
    const glint_cancel *cancel;
    int *stopped;  /* shared: set once a thread was told to stop */
} erows_job;

static void *erows_run(void *arg)
{
    erows_job *j = arg;
    for (int l = j->l0; l < j->l1; l++) {
        if (j->cancel) { /* a row is q->n x J terms: asked every row */
            if (__atomic_load_n(j->stopped, __ATOMIC_RELAXED))
                break;
            if (glint_cancelled(j->cancel)) {
                __atomic_store_n(j->stopped, 1, __ATOMIC_RELAXED);
                break;
            }
        }
        energy_row(j->b, j->s, j->q, j->wo + 3 * l, j->g + (size_t)l * j->b->J);
    }
    return NULL;
}

static int cores(int nthreads)
{
    long n = nthreads > 0 ? nthreads : sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > 64 ? 64 : (int)n;
}

int srbf_energy_rows(const srbf_basis *b, const srbf_static *s, int nl, const double *wo,
                     int nq, double *g, int nthreads, const glint_cancel *cancel,
                     glint_err *err)
{
    quad q;
    int nt = cores(nthreads), stopped = 0;
    pthread_t th[64];
    erows_job jobs[64];
    if (nq <= 0)
        nq = 96;
    if (nq < 8 || nq > 1024 || nl < 1)
        return glint_err_set(err, GLINT_ERANGE, "quadrature %d or rows %d out of range", nq, nl);
    if (quad_make(nq, &q))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the quadrature");
    if (nt > nl)
        nt = nl;
    for (int t = 0; t < nt; t++) {
        jobs[t] = (erows_job){b, s, &q, wo, g, (int)((long)nl * t / nt),
                              (int)((long)nl * (t + 1) / nt), cancel, &stopped};
        if (t && pthread_create(&th[t], NULL, erows_run, &jobs[t]))
            erows_run(&jobs[t]), th[t] = 0;
    }
    erows_run(&jobs[0]);
    for (int t = 1; t < nt; t++)
        if (th[t])
            pthread_join(th[t], NULL);
    free(q.d);
    free(q.w);
    if (stopped)
        return glint_cancel_err(err, "the energy rows");
    return 0;
}

void srbf_albedo(const srbf_basis *b, const srbf_static *s, const double *c, const double wo[3],
                 int nq, double rgb[3])
{
    quad q;
    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (quad_make(nq > 0 ? nq : 96, &q))
        return;
    for (int k = 0; k < q.n; k++) {
        double wi[3], h[3], p[3], wt = node(s, &q, k, wo, wi, h);
        if (wt == 0.0)
            continue;
        srbf_p(b, c, h, p);
        for (int ch = 0; ch < 3; ch++)
            rgb[ch] += wt * p[ch];
    }
    free(q.d);
    free(q.w);
}
