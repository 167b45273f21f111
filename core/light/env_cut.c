/* env_cut.c: compressing an environment into lights (env.h): median cut,
 * the lat-long box filter, rotation and the compression error. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "env.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* A map box-filtered by solid angle (each coarse texel the mean radiance
 * over the source texels whose centres fall in it, weighted by their
 * solid angles), in double. */
typedef struct coarse {
    int W, H;
    double *L;      /* W x H x 3 */
    double *omega;  /* H: solid angle of a texel of each row */
} coarse;

static void coarse_free(coarse *c)
{
    free(c->L);
    free(c->omega);
}

static double row_omega(int W, int H, int r)
{
    return 2.0 * M_PI / W * (cos(M_PI * r / H) - cos(M_PI * (r + 1) / H));
}

static int coarse_make(const env_map *m, int W, int H, coarse *c)
{
    double *wsum;
    c->W = W;
    c->H = H;
    c->L = calloc((size_t)W * H * 3, sizeof *c->L);
    c->omega = malloc((size_t)H * sizeof *c->omega);
    wsum = calloc((size_t)W * H, sizeof *wsum);
    if (!c->L || !c->omega || !wsum) {
        free(wsum);
        coarse_free(c);
        return -1;
    }
    for (int r = 0; r < H; r++)
        c->omega[r] = row_omega(W, H, r);
    for (int r = 0; r < m->height; r++) {
        int cr = (int)((long)r * H / m->height);
        double om = row_omega(m->width, m->height, r);
        for (int col = 0; col < m->width; col++) {
            int cc = (int)((long)col * W / m->width);
            size_t k = (size_t)cr * W + cc;
            const float *v = m->rgb + ((size_t)r * m->width + col) * 3;
            wsum[k] += om;
            for (int ch = 0; ch < 3; ch++)
                c->L[3 * k + ch] += om * v[ch];
        }
    }
    for (size_t k = 0; k < (size_t)W * H; k++)
        for (int ch = 0; ch < 3; ch++)
            c->L[3 * k + ch] = wsum[k] > 0.0 ? c->L[3 * k + ch] / wsum[k] : 0.0;
    free(wsum);
    return 0;
}

static int coarse_default(const env_map *m, int maxw, coarse *c)
{
    int W = m->width, H = m->height;
    if (W > maxw) {
        W = maxw;
        H = maxw / 2;
    }
    return coarse_make(m, W, H, c);
}

static void dir_of(int W, int H, double r, double col, double d[3])
{
    double th = M_PI * (r + 0.5) / H, ph = M_PI - 2.0 * M_PI * (col + 0.5) / W;
    d[0] = sin(th) * cos(ph);
    d[1] = sin(th) * sin(ph);
    d[2] = cos(th);
}

void env_lights_rotate(env_lights *l, double psi)
{
    double c = cos(psi), s = sin(psi);
    for (int k = 0; k < l->k; k++) {
        double *d = l->dir + 3 * k, x = d[0], y = d[1];
        d[0] = c * x - s * y;
        d[1] = s * x + c * y;
    }
}

static int lights_alloc(env_lights *l, int k)
{
    memset(l, 0, sizeof *l);
    l->dir = malloc((size_t)3 * k * sizeof *l->dir);
    l->power = calloc((size_t)3 * k, sizeof *l->power);
    l->k = k;
    return l->dir && l->power ? 0 : -1;
}

/* ---- median cut ------------------------------------------------------------------------- */

enum { S_Y, S_R, S_G, S_B, S_X, S_YY, S_Z, S_N };

typedef struct region {
    int r0, r1, c0, c1;
} region;

typedef struct sat {
    int W, H;
    double *s; /* (H+1) x (W+1) x S_N */
} sat;

static double sat_sum(const sat *t, const region *g, int q)
{
    size_t W1 = (size_t)t->W + 1;
#define AT(r, c) t->s[((size_t)(r) * W1 + (c)) * S_N + q]
    return AT(g->r1, g->c1) - AT(g->r0, g->c1) - AT(g->r1, g->c0) + AT(g->r0, g->c0);
#undef AT
}

static int sat_make(const coarse *c, sat *t)
{
    size_t W1 = (size_t)c->W + 1;
    t->W = c->W;
    t->H = c->H;
    if (!(t->s = calloc(((size_t)c->H + 1) * W1 * S_N, sizeof *t->s)))
        return -1;
    for (int r = 0; r < c->H; r++)
        for (int col = 0; col < c->W; col++) {
            const double *L = c->L + 3 * ((size_t)r * c->W + col);
            double om = c->omega[r], d[3], v[S_N];
            double Y = (0.2126 * L[0] + 0.7152 * L[1] + 0.0722 * L[2]) * om;
            dir_of(c->W, c->H, r, col, d);
            v[S_Y] = Y;
            v[S_R] = L[0] * om;
            v[S_G] = L[1] * om;
            v[S_B] = L[2] * om;
            v[S_X] = Y * d[0];
            v[S_YY] = Y * d[1];
            v[S_Z] = Y * d[2];
            for (int q = 0; q < S_N; q++)
                t->s[(((size_t)r + 1) * W1 + col + 1) * S_N + q] =
                    v[q] + t->s[((size_t)r * W1 + col + 1) * S_N + q] +
                    t->s[(((size_t)r + 1) * W1 + col) * S_N + q] -
                    t->s[((size_t)r * W1 + col) * S_N + q];
        }
    return 0;
}

/* Split g in two where its luminance power is halved (OUT: a, b); 0 if
 * it is a single texel. */
static int split(const sat *t, const region *g, region *a, region *b)
{
    int w = g->c1 - g->c0, h = g->r1 - g->r0, along_cols;
    double thc = M_PI * (0.5 * (g->r0 + g->r1)) / t->H;
    double aw = sin(thc) * w * 2.0 * M_PI / t->W, ah = h * M_PI / t->H, total, best = INFINITY;
    int cut = -1;
    if (w == 1 && h == 1)
        return 0;
    along_cols = (aw >= ah && w > 1) || h == 1;
    total = sat_sum(t, g, S_Y);
    *a = *b = *g;
    if (along_cols) {
        for (int c = g->c0 + 1; c < g->c1; c++) {
            region part = *g;
            double dv;
            part.c1 = c;
            dv = fabs(sat_sum(t, &part, S_Y) - 0.5 * total);
            if (dv < best) {
                best = dv;
                cut = c;
            }
        }
        a->c1 = cut;
        b->c0 = cut;
    } else {
        for (int r = g->r0 + 1; r < g->r1; r++) {
            region part = *g;
            double dv;
            part.r1 = r;
            dv = fabs(sat_sum(t, &part, S_Y) - 0.5 * total);
            if (dv < best) {
                best = dv;
                cut = r;
            }
        }
        a->r1 = cut;
        b->r0 = cut;
    }
    return 1;
}

static int median_cut(const coarse *c, int k, env_lights *out, glint_err *err)
{
    sat t;
    region *cur = malloc((size_t)k * sizeof *cur), *nxt = malloc((size_t)k * sizeof *nxt);
    int n = 1;
    if (!cur || !nxt || sat_make(c, &t)) {
        free(cur);
        free(nxt);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory for the median cut");
    }
    cur[0] = (region){0, c->H, 0, c->W};
    while (n < k) {
        int m = 0, grew = 0, count = n;
        for (int i = 0; i < n; i++) {
            region a, b;
            if (count < k && split(&t, &cur[i], &a, &b)) {
                nxt[m++] = a;
                nxt[m++] = b;
                count++;
                grew = 1;
            } else {
                nxt[m++] = cur[i];
            }
        }
        region *sw = cur;
        cur = nxt;
        nxt = sw;
        n = m;
        if (!grew)
            break;
    }
    if (lights_alloc(out, n)) {
        free(cur);
        free(nxt);
        free(t.s);
        env_lights_free(out);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    for (int i = 0; i < n; i++) {
        double dx = sat_sum(&t, &cur[i], S_X), dy = sat_sum(&t, &cur[i], S_YY),
               dz = sat_sum(&t, &cur[i], S_Z), l = sqrt(dx * dx + dy * dy + dz * dz);
        if (l > 0.0) {
            out->dir[3 * i] = dx / l;
            out->dir[3 * i + 1] = dy / l;
            out->dir[3 * i + 2] = dz / l;
        } else {
            dir_of(c->W, c->H, 0.5 * (cur[i].r0 + cur[i].r1) - 0.5,
                   0.5 * (cur[i].c0 + cur[i].c1) - 0.5, out->dir + 3 * i);
        }
        out->power[3 * i] = sat_sum(&t, &cur[i], S_R);
        out->power[3 * i + 1] = sat_sum(&t, &cur[i], S_G);
        out->power[3 * i + 2] = sat_sum(&t, &cur[i], S_B);
    }
    free(cur);
    free(nxt);
    free(t.s);
    return 0;
}

int env_compress(const env_map *m, env_cut how, int k, double psi, double intensity,
                 env_lights *out, glint_err *err)
{
    coarse c;
    int rc = 0;
    memset(out, 0, sizeof *out);
    if (k < 1 || k > ENV_MAX_LIGHTS)
        return glint_err_set(err, GLINT_ERANGE, "lights %d outside 1..%d", k, ENV_MAX_LIGHTS);
    if (!isfinite(psi) || !isfinite(intensity) || intensity < 0.0)
        return glint_err_set(err, GLINT_EINVAL, "rotation and intensity must be finite, "
                                                "intensity >= 0");
    if (how == ENV_CUT_LATLONG) {
        int w = (int)lround(sqrt(2.0 * k));
        if (w % 2 || w * w / 2 != k || w > m->width)
            return glint_err_set(err, GLINT_EINVAL,
                                 "a lat-long compression takes k = w^2/2 lights for an even w "
                                 "up to the map's width (%d): %d is not one", m->width, k);
        if (coarse_make(m, w, w / 2, &c))
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        if (lights_alloc(out, k)) {
            coarse_free(&c);
            env_lights_free(out);
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        }
        for (int r = 0; r < c.H; r++)
            for (int col = 0; col < c.W; col++) {
                size_t i = (size_t)r * c.W + col;
                dir_of(c.W, c.H, r, col, out->dir + 3 * i);
                for (int ch = 0; ch < 3; ch++)
                    out->power[3 * i + ch] = c.L[3 * i + ch] * c.omega[r];
            }
    } else {
        if (coarse_default(m, 512, &c))
            return glint_err_set(err, GLINT_ENOMEM, "out of memory");
        rc = median_cut(&c, k, out, err);
    }
    coarse_free(&c);
    if (rc)
        return rc;
    env_lights_rotate(out, psi);
    out->total[0] = out->total[1] = out->total[2] = 0.0;
    for (int i = 0; i < out->k; i++)
        for (int ch = 0; ch < 3; ch++) {
            out->power[3 * i + ch] *= intensity;
            out->total[ch] += out->power[3 * i + ch];
        }
    return 0;
}

/* ---- compression error ------------------------------------------------------------- */

int env_compress_error(const env_map *m, const env_lights *l, double psi, double intensity,
                       env_cut_error *out, glint_err *err)
{
    enum { NN = 256 };
    const double lambda = 81.0, cutg = 1.0 - 40.0 / lambda;
    double num_i = 0, den_i = 0, num_g = 0, den_g = 0, cs = cos(psi), sn = sin(psi);
    coarse c;
    double *dirs;

    memset(out, 0, sizeof *out);
    if (coarse_default(m, 256, &c))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    if (!(dirs = malloc((size_t)c.W * c.H * 3 * sizeof *dirs))) {
        coarse_free(&c);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    for (int r = 0; r < c.H; r++)
        for (int col = 0; col < c.W; col++) {
            double d[3], *o = dirs + 3 * ((size_t)r * c.W + col);
            dir_of(c.W, c.H, r, col, d);
            o[0] = cs * d[0] - sn * d[1];
            o[1] = sn * d[0] + cs * d[1];
            o[2] = d[2];
        }
    for (int i = 0; i < NN; i++) {
        double z = 1.0 - (2.0 * i + 1.0) / NN, rr = sqrt(1.0 - z * z);
        double ph = i * M_PI * (3.0 - sqrt(5.0)), n[3] = {rr * cos(ph), rr * sin(ph), z};
        double fi[3] = {0, 0, 0}, fg[3] = {0, 0, 0}, li[3] = {0, 0, 0}, lg[3] = {0, 0, 0};
        for (size_t t = 0; t < (size_t)c.W * c.H; t++) {
            const double *d = dirs + 3 * t, *L = c.L + 3 * t;
            double cd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2], om = c.omega[t / c.W];
            if (cd > 0.0)
                for (int ch = 0; ch < 3; ch++)
                    fi[ch] += L[ch] * om * cd;
            if (cd > cutg) {
                double g = exp(lambda * (cd - 1.0));
                for (int ch = 0; ch < 3; ch++)
                    fg[ch] += L[ch] * om * g;
            }
        }
        for (int k = 0; k < l->k; k++) {
            const double *d = l->dir + 3 * k, *P = l->power + 3 * k;
            double cd = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
            if (cd > 0.0)
                for (int ch = 0; ch < 3; ch++)
                    li[ch] += P[ch] * cd;
            if (cd > cutg) {
                double g = exp(lambda * (cd - 1.0));
                for (int ch = 0; ch < 3; ch++)
                    lg[ch] += P[ch] * g;
            }
        }
        for (int ch = 0; ch < 3; ch++) {
            fi[ch] *= intensity;
            fg[ch] *= intensity;
            num_i += (li[ch] - fi[ch]) * (li[ch] - fi[ch]);
            den_i += fi[ch] * fi[ch];
            num_g += (lg[ch] - fg[ch]) * (lg[ch] - fg[ch]);
            den_g += fg[ch] * fg[ch];
        }
    }
    out->irradiance_rel_rms = den_i > 0 ? sqrt(num_i / den_i) : 0.0;
    out->glossy_rel_rms = den_g > 0 ? sqrt(num_g / den_g) : 0.0;
    free(dirs);
    coarse_free(&c);
    return 0;
}
