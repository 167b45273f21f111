/* brdf.c: the analytic BRDFs of brdf.h, their spec parser and formatter.
 * brdf_eval follows ../shared/reference/hf_ref.py brdf_eval term by term
 * (lambert, phong, blinn, ct with ggx_alpha="rough"). */
#include "brdf.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "vec3.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* ---- evaluation ------------------------------------------------------- */

/* The reference clamps the cosines at 1e-12 before dividing. */
static inline double clamp_cos(double c)
{
    return c > 1e-12 ? c : 1e-12;
}

/* GGX's separable Smith G1 at a clamped cosine c. */
static inline double ct_g1(double a2, double c)
{
    return 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
}

/* The ct model's specular term (OUT spec[3]) for unit N, I, O with
 * ci = N.I > 0; cop the clamped N.O and g1o its G1 (the same for every
 * light of a point: brdf_envlit_sum takes them once). */
static inline void ct_spec(const brdf *b, double a2, v3 N, v3 I, v3 O, double ci, double cop,
                           double g1o, double spec[3])
{
    v3 h = v3_normalize(v3_add(I, O));
    double ch = v3_dot(N, h), hi = v3_dot(h, I);
    ch = ch < 0.0 ? 0.0 : (ch > 1.0 ? 1.0 : ch);
    hi = hi < 0.0 ? 0.0 : (hi > 1.0 ? 1.0 : hi);
    double t = ch * ch * (a2 - 1.0) + 1.0;
    double D = a2 / (M_PI * t * t);
    double cip = clamp_cos(ci);
    double common = D * ct_g1(a2, cip) * g1o / (4.0 * cip * cop);
    double m = 1.0 - hi, s5 = m * m * m * m * m;
    for (int c = 0; c < 3; c++)
        spec[c] = common * (b->f0[c] + (1.0 - b->f0[c]) * s5);
}

void brdf_eval(const brdf *b, const double n[3], const double wi[3],
               const double wo[3], double rgb[3])
{
    v3 N = v3_load(n), I = v3_load(wi), O = v3_load(wo);
    double ci = v3_dot(N, I), co = v3_dot(N, O);
    double spec[3] = {0.0, 0.0, 0.0};

    rgb[0] = rgb[1] = rgb[2] = 0.0;
    if (!(ci > 0.0 && co > 0.0))
        return;

    switch (b->kind) {
    case BRDF_LAMBERT:
        break;
    case BRDF_PHONG: {
        v3 r = v3_sub(v3_scale(N, 2.0 * ci), I);
        double rv = v3_dot(r, O);
        double lobe = (b->exponent + 2.0) / (2.0 * M_PI) *
                      pow(rv > 0.0 ? rv : 0.0, b->exponent);
        for (int c = 0; c < 3; c++)
            spec[c] = b->ks[c] * lobe;
        break;
    }
    case BRDF_BLINN: {
        v3 h = v3_normalize(v3_add(I, O));
        double nh = v3_dot(N, h);
        double lobe = (b->exponent + 8.0) / (8.0 * M_PI) *
                      pow(nh > 0.0 ? nh : 0.0, b->exponent);
        for (int c = 0; c < 3; c++)
            spec[c] = b->ks[c] * lobe;
        break;
    }
    case BRDF_CT: {
        double a2 = b->roughness * b->roughness, cop = clamp_cos(co);
        ct_spec(b, a2, N, I, O, ci, cop, ct_g1(a2, cop), spec);
        break;
    }
    case BRDF_WARD: {
        double a2 = b->roughness * b->roughness;
        v3 h = v3_normalize(v3_add(I, O));
        double ch = v3_dot(N, h);
        if (ch > 0.0 && b->roughness_y > 0.0 && b->roughness_y != b->roughness) {
            /* anisotropic: alpha_x = rough along t, alpha_y = rough_y along b */
            v3 t, bt;
            double ax = b->roughness, ay = b->roughness_y, ht, hb, e, lobe;
            v3_frame(N, &t, &bt);
            ht = v3_dot(h, t) / ax;
            hb = v3_dot(h, bt) / ay;
            e = (ht * ht + hb * hb) / (ch * ch);
            lobe = exp(-e) / (4.0 * M_PI * ax * ay * sqrt(ci * co));
            for (int c = 0; c < 3; c++)
                spec[c] = b->ks[c] * lobe;
        } else if (ch > 0.0) {
            double c2 = ch > 1.0 ? 1.0 : ch * ch;
            double tan2 = (1.0 - c2) / c2;
            double lobe = exp(-tan2 / a2) / (4.0 * M_PI * a2 * sqrt(ci * co));
            for (int c = 0; c < 3; c++)
                spec[c] = b->ks[c] * lobe;
        }
        break;
    }
    default:
        return; /* not a model: zero, as documented for invalid input */
    }
    for (int c = 0; c < 3; c++)
        rgb[c] = b->kd[c] / M_PI + spec[c];
}

/* ---- parsing ---------------------------------------------------------- */

#define BRDF_SPEC_MAX 512

enum { K_KD = 1, K_KS = 2, K_F0 = 4, K_E = 8, K_ROUGH = 16, K_ROUGH_Y = 32 };

typedef struct brdf_model {
    const char *name;
    brdf_kind kind;
    int keys; /* keys that apply to this model */
} brdf_model;

static const brdf_model brdf_models[] = {
    {"lambert", BRDF_LAMBERT, K_KD},
    {"phong", BRDF_PHONG, K_KD | K_KS | K_E},
    {"blinn", BRDF_BLINN, K_KD | K_KS | K_E},
    {"ct", BRDF_CT, K_KD | K_F0 | K_ROUGH},
    {"ward", BRDF_WARD, K_KD | K_KS | K_ROUGH | K_ROUGH_Y},
};

static const brdf_model *brdf_model_of(brdf_kind k)
{
    for (size_t i = 0; i < sizeof brdf_models / sizeof brdf_models[0]; i++)
        if (brdf_models[i].kind == k)
            return &brdf_models[i];
    return NULL;
}

static void brdf_set3(double v[3], double x) { v[0] = v[1] = v[2] = x; }

/* Defaults of a model (the reference truths). */
static void brdf_defaults(brdf_kind k, brdf *b)
{
    memset(b, 0, sizeof *b);
    b->kind = k;
    switch (k) {
    case BRDF_LAMBERT:
        brdf_set3(b->kd, 0.8);
        break;
    case BRDF_PHONG:
        brdf_set3(b->kd, 0.7);
        brdf_set3(b->ks, 0.3);
        b->exponent = 32.0;
        break;
    case BRDF_BLINN:
        brdf_set3(b->kd, 0.7);
        brdf_set3(b->ks, 0.3);
        b->exponent = 20.0;
        break;
    case BRDF_CT:
        brdf_set3(b->kd, 0.5);
        brdf_set3(b->f0, 0.3);
        b->roughness = 0.2;
        break;
    case BRDF_WARD:
        brdf_set3(b->kd, 0.5);
        brdf_set3(b->ks, 0.3);
        b->roughness = 0.2;
        break;
    }
}

/* Resolve a model or preset name (OUT: *b with its values). */
static int brdf_name(const char *name, brdf *b)
{
    for (size_t i = 0; i < sizeof brdf_models / sizeof brdf_models[0]; i++) {
        if (strcmp(name, brdf_models[i].name) == 0) {
            brdf_defaults(brdf_models[i].kind, b);
            return 1;
        }
    }
    if (strcmp(name, "phong32") == 0) {
        brdf_defaults(BRDF_PHONG, b);
    } else if (strcmp(name, "blinn20") == 0) {
        brdf_defaults(BRDF_BLINN, b);
    } else if (strcmp(name, "blinn100") == 0) {
        brdf_defaults(BRDF_BLINN, b);
        b->exponent = 100.0;
    } else if (strcmp(name, "ct0.2") == 0) {
        brdf_defaults(BRDF_CT, b);
    } else if (strcmp(name, "ct0.5") == 0) {
        brdf_defaults(BRDF_CT, b);
        b->roughness = 0.5;
    } else {
        return 0;
    }
    return 1;
}

static char *brdf_trim(char *s)
{
    char *e;
    while (*s == ' ' || *s == '\t')
        s++;
    e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || e[-1] == '\t'))
        *--e = '\0';
    return s;
}

/* One finite number filling the whole of `s`. */
static int brdf_number(const char *s, double *x)
{
    char *end;
    if (!*s)
        return 0;
    errno = 0;
    *x = strtod(s, &end);
    return end != s && *end == '\0' && errno != ERANGE && isfinite(*x);
}

/* Value of key `key`: one number, or (rgb != 0) "r/g/b". (OUT: v[3]) */
static int brdf_value(const char *key, char *val, int rgb, double v[3],
                      glint_err *err)
{
    char *parts[3];
    int np = 0;
    char *p = val;

    for (;;) {
        char *slash = strchr(p, '/');
        if (np == 3)
            return glint_err_set(err, GLINT_EINVAL,
                                 "brdf key '%s': too many components in '%s' "
                                 "(one number or r/g/b)",
                                 key, val);
        parts[np++] = p;
        if (!slash)
            break;
        *slash = '\0';
        p = slash + 1;
    }
    if (np == 2 || (np == 3 && !rgb))
        return glint_err_set(err, GLINT_EINVAL, "brdf key '%s' takes %s, got %d components",
                             key, rgb ? "one number or r/g/b" : "one number", np);
    for (int i = 0; i < np; i++) {
        char *t = brdf_trim(parts[i]);
        if (!brdf_number(t, &v[i]))
            return glint_err_set(err, GLINT_EINVAL,
                                 "brdf key '%s': '%s' is not a finite number", key, t);
    }
    if (np == 1)
        v[1] = v[2] = v[0];
    return 0;
}

static int brdf_range3(const char *key, const double v[3], glint_err *err)
{
    for (int c = 0; c < 3; c++)
        if (!(v[c] >= 0.0 && v[c] <= 1.0))
            return glint_err_set(err, GLINT_ERANGE,
                                 "brdf key '%s': component %d = %g outside [0, 1]", key, c,
                                 v[c]);
    return 0;
}

int brdf_parse(const char *spec, brdf *out, glint_err *err)
{
    char buf[BRDF_SPEC_MAX];
    char *name, *rest, *item;
    const brdf_model *m;
    brdf b;
    int seen = 0;

    if (!out)
        return glint_err_set(err, GLINT_EINVAL, "brdf_parse: NULL output");
    if (!spec)
        return glint_err_set(err, GLINT_EINVAL, "brdf spec is NULL");
    if (strlen(spec) >= sizeof buf)
        return glint_err_set(err, GLINT_EINVAL, "brdf spec longer than %d characters",
                             (int)sizeof buf - 1);
    strcpy(buf, spec);

    rest = strchr(buf, ':');
    if (rest)
        *rest++ = '\0';
    name = brdf_trim(buf);
    if (!*name)
        return glint_err_set(err, GLINT_EINVAL, "brdf spec '%s' has no model name", spec);
    if (!brdf_name(name, &b))
        return glint_err_set(err, GLINT_ENOTFOUND,
                             "unknown brdf '%s' (models lambert, phong, blinn, ct, ward; "
                             "presets phong32, blinn20, blinn100, ct0.2, ct0.5)",
                             name);
    m = brdf_model_of(b.kind);

    for (item = rest; item;) {
        char *next = strchr(item, ',');
        char *eq, *key, *val;
        double v[3];
        int bit;
        int rc;

        if (next)
            *next++ = '\0';
        eq = strchr(item, '=');
        if (!eq) {
            char *t = brdf_trim(item);
            return glint_err_set(err, GLINT_EINVAL,
                                 "brdf spec item '%s' is not key=value", t);
        }
        *eq = '\0';
        key = brdf_trim(item);
        val = brdf_trim(eq + 1);

        if (strcmp(key, "kd") == 0)
            bit = K_KD;
        else if (strcmp(key, "ks") == 0)
            bit = K_KS;
        else if (strcmp(key, "f0") == 0)
            bit = K_F0;
        else if (strcmp(key, "e") == 0)
            bit = K_E;
        else if (strcmp(key, "rough") == 0)
            bit = K_ROUGH;
        else if (strcmp(key, "rough_y") == 0)
            bit = K_ROUGH_Y;
        else
            return glint_err_set(err, GLINT_EINVAL,
                                 "unknown brdf key '%s' (kd, ks, f0, e, rough, rough_y)", key);
        if (!(m->keys & bit))
            return glint_err_set(err, GLINT_EINVAL, "brdf key '%s' does not apply to %s",
                                 key, m->name);
        if (seen & bit)
            return glint_err_set(err, GLINT_EINVAL, "brdf key '%s' given twice", key);
        seen |= bit;

        rc = brdf_value(key, val, bit == K_KD || bit == K_KS || bit == K_F0, v, err);
        if (rc)
            return rc;
        switch (bit) {
        case K_KD:
        case K_KS:
        case K_F0:
            rc = brdf_range3(key, v, err);
            if (rc)
                return rc;
            memcpy(bit == K_KD ? b.kd : bit == K_KS ? b.ks : b.f0, v, sizeof v);
            break;
        case K_E:
            if (!(v[0] > 0.0 && v[0] <= 10000.0))
                return glint_err_set(err, GLINT_ERANGE,
                                     "brdf key 'e' = %g outside (0, 10000]", v[0]);
            b.exponent = v[0];
            break;
        case K_ROUGH:
            if (!(v[0] >= 0.01 && v[0] <= 1.0))
                return glint_err_set(err, GLINT_ERANGE,
                                     "brdf key 'rough' = %g outside [0.01, 1]", v[0]);
            b.roughness = v[0];
            break;
        case K_ROUGH_Y:
            if (!(v[0] >= 0.01 && v[0] <= 1.0))
                return glint_err_set(err, GLINT_ERANGE,
                                     "brdf key 'rough_y' = %g outside [0.01, 1]", v[0]);
            b.roughness_y = v[0];
            break;
        }
        item = next;
    }
    *out = b;
    return 0;
}

/* ---- formatting ------------------------------------------------------- */

/* Shortest %g text that reads back to exactly x. */
static void brdf_fmt_num(char *s, size_t n, double x)
{
    for (int prec = 6; prec <= 17; prec++) {
        snprintf(s, n, "%.*g", prec, x);
        if (strtod(s, NULL) == x)
            return;
    }
}

static size_t brdf_fmt_rgb(char *s, size_t n, const double v[3])
{
    char a[32], b[32], c[32];
    brdf_fmt_num(a, sizeof a, v[0]);
    if (v[0] == v[1] && v[1] == v[2])
        return (size_t)snprintf(s, n, "%s", a);
    brdf_fmt_num(b, sizeof b, v[1]);
    brdf_fmt_num(c, sizeof c, v[2]);
    return (size_t)snprintf(s, n, "%s/%s/%s", a, b, c);
}

void brdf_format(const brdf *b, char *buf, int len)
{
    char tmp[512], num[96];
    const brdf_model *m;
    size_t pos;

    if (!buf || len <= 0)
        return;
    m = b ? brdf_model_of(b->kind) : NULL;
    if (!m) {
        snprintf(buf, (size_t)len, "invalid");
        return;
    }
    pos = (size_t)snprintf(tmp, sizeof tmp, "%s", m->name);
    if (m->keys & K_KD) {
        brdf_fmt_rgb(num, sizeof num, b->kd);
        pos += (size_t)snprintf(tmp + pos, sizeof tmp - pos, ":kd=%s", num);
    }
    if (m->keys & K_KS) {
        brdf_fmt_rgb(num, sizeof num, b->ks);
        pos += (size_t)snprintf(tmp + pos, sizeof tmp - pos, ",ks=%s", num);
    }
    if (m->keys & K_F0) {
        brdf_fmt_rgb(num, sizeof num, b->f0);
        pos += (size_t)snprintf(tmp + pos, sizeof tmp - pos, ",f0=%s", num);
    }
    if (m->keys & K_E) {
        brdf_fmt_num(num, sizeof num, b->exponent);
        pos += (size_t)snprintf(tmp + pos, sizeof tmp - pos, ",e=%s", num);
    }
    if (m->keys & K_ROUGH) {
        brdf_fmt_num(num, sizeof num, b->roughness);
        pos += (size_t)snprintf(tmp + pos, sizeof tmp - pos, ",rough=%s", num);
    }
    if ((m->keys & K_ROUGH_Y) && b->roughness_y > 0.0 && b->roughness_y != b->roughness) {
        brdf_fmt_num(num, sizeof num, b->roughness_y);
        snprintf(tmp + pos, sizeof tmp - pos, ",rough_y=%s", num);
    }
    snprintf(buf, (size_t)len, "%s", tmp);
}

void brdf_envlit(const void *ctx, const double uv[2], const double n[3], const double wi[3],
                 const double wo[3], double rgb[3])
{
    (void)uv;
    double c = n[0] * wi[0] + n[1] * wi[1] + n[2] * wi[2];
    brdf_eval(ctx, n, wi, wo, rgb);
    for (int e = 0; e < 3; e++)
        rgb[e] *= c > 0.0 ? c : 0.0;
}

/* Light k of l above n's horizon and not shadowed (bits). */
static int lit(const env_lights *l, const uint64_t *bits, const double n[3], int k)
{
    const double *d = l->dir + 3 * k;
    return n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0.0 &&
           (!bits || ((bits[k >> 6] >> (k & 63)) & 1));
}

/* brdf_eval's ct and lambert cases times n.wi, summed with the lights'
 * powers: its expressions, in its order.  The lights above the horizon and
 * seen are gathered in order into blocks; each light's term is computed
 * across a block with vector instructions (elementwise, so each term is
 * what the scalar expressions give: no fused multiply-add, C11's
 * -ffp-contract=off) and the terms are then added one by one in the
 * lights' order, so the sums keep their digits. */
#define CT_BLOCK 64

typedef struct ct_block {
    int n;
    double x[CT_BLOCK], y[CT_BLOCK], z[CT_BLOCK], ci[CT_BLOCK];
    double pw[3][CT_BLOCK];
    double term[3][CT_BLOCK];
} ct_block;

/* The point's constants: normal, view, the view's clamped cosine and G1,
 * kd / pi, and the model's a2 and f0. */
typedef struct ct_point {
    double nx, ny, nz, ox, oy, oz, cop, g1o, a2;
    double kdpi[3], f0[3];
} ct_point;

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
/* no-trapping-math: the clamps become selects (the values are the same) */
#define CT_CLONES                                                                          \
    __attribute__((target_clones("avx512f", "avx2", "default"), optimize("no-trapping-math")))
#else
#define CT_CLONES
#endif

/* term[c][j] = pw[c][j] ((kd[c] / pi + spec[c]) ci) across block b: ct_spec's
 * expressions (v3_normalize of I + O, whose length is positive when both
 * cosines are), lambert when spec is 0. */
CT_CLONES static void ct_terms(const ct_point *p, int ct, ct_block *restrict b)
{
    const double a2 = p->a2, cop = p->cop, g1o = p->g1o;
    const double f0r = p->f0[0], f0g = p->f0[1], f0b = p->f0[2];
    const double kr = p->kdpi[0], kg = p->kdpi[1], kb = p->kdpi[2];
    if (!ct) {
        for (int c = 0; c < 3; c++) {
            const double kdpi = p->kdpi[c];
#pragma omp simd
            for (int j = 0; j < b->n; j++)
                b->term[c][j] = b->pw[c][j] * (kdpi * b->ci[j]);
        }
        return;
    }
#pragma omp simd
    for (int j = 0; j < b->n; j++) {
        double hx = b->x[j] + p->ox, hy = b->y[j] + p->oy, hz = b->z[j] + p->oz;
        double inv = 1.0 / sqrt(hx * hx + hy * hy + hz * hz);
        hx = hx * inv;
        hy = hy * inv;
        hz = hz * inv;
        double ch = p->nx * hx + p->ny * hy + p->nz * hz;
        double hi = hx * b->x[j] + hy * b->y[j] + hz * b->z[j];
        ch = ch < 0.0 ? 0.0 : (ch > 1.0 ? 1.0 : ch);
        hi = hi < 0.0 ? 0.0 : (hi > 1.0 ? 1.0 : hi);
        double t = ch * ch * (a2 - 1.0) + 1.0;
        double D = a2 / (M_PI * t * t);
        double ci = b->ci[j];
        double cip = ci > 1e-12 ? ci : 1e-12;
        double g1i = 2.0 * cip / (cip + sqrt(a2 + (1.0 - a2) * cip * cip));
        double common = D * g1i * g1o / (4.0 * cip * cop);
        double m = 1.0 - hi, s5 = m * m * m * m * m;
        double s0 = common * (f0r + (1.0 - f0r) * s5), s1 = common * (f0g + (1.0 - f0g) * s5),
               s2 = common * (f0b + (1.0 - f0b) * s5);
        b->term[0][j] = b->pw[0][j] * ((kr + s0) * ci);
        b->term[1][j] = b->pw[1][j] * ((kg + s1) * ci);
        b->term[2][j] = b->pw[2][j] * ((kb + s2) * ci);
    }
}

/* Block b's terms added to acc in the lights' order; the block emptied. */
static void ct_flush(const ct_point *p, int ct, ct_block *b, double acc[3])
{
    ct_terms(p, ct, b);
    for (int j = 0; j < b->n; j++)
        for (int c = 0; c < 3; c++)
            acc[c] += b->term[c][j];
    b->n = 0;
}

static void sum_ct(const brdf *b, const env_lights *l, const uint64_t *bits, const double n[3],
                   const double wo[3], double acc[3])
{
    v3 N = v3_load(n), O = v3_load(wo);
    double co = v3_dot(N, O);
    int ct = b->kind == BRDF_CT;
    ct_point p = {.nx = N.x, .ny = N.y, .nz = N.z, .ox = O.x, .oy = O.y, .oz = O.z};
    ct_block blk;
    if (!(co > 0.0))
        return;
    p.a2 = b->roughness * b->roughness;
    p.cop = clamp_cos(co);
    p.g1o = ct ? ct_g1(p.a2, p.cop) : 0.0;
    for (int c = 0; c < 3; c++) {
        p.kdpi[c] = b->kd[c] / M_PI;
        p.f0[c] = b->f0[c];
    }
    blk.n = 0;
    for (int k = 0; k < l->k; k++) {
        const double *d = l->dir + 3 * k, *pw = l->power + 3 * k;
        double ci = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
        int j = blk.n;
        if (!(ci > 0.0) || (bits && !((bits[k >> 6] >> (k & 63)) & 1)))
            continue;
        blk.x[j] = d[0];
        blk.y[j] = d[1];
        blk.z[j] = d[2];
        blk.ci[j] = ci;
        for (int c = 0; c < 3; c++)
            blk.pw[c][j] = pw[c];
        if (++blk.n == CT_BLOCK)
            ct_flush(&p, ct, &blk, acc);
    }
    if (blk.n)
        ct_flush(&p, ct, &blk, acc);
}

void brdf_envlit_sum(const void *ctx, const env_lights *l, const uint64_t *bits,
                     const double uv[2], const double n[3], const double wo[3], double acc[3])
{
    const brdf *b = ctx;
    acc[0] = acc[1] = acc[2] = 0.0;
    if (b->kind == BRDF_CT || b->kind == BRDF_LAMBERT) {
        sum_ct(b, l, bits, n, wo, acc);
        return;
    }
    for (int k = 0; k < l->k; k++) {
        double r[3];
        if (!lit(l, bits, n, k))
            continue;
        brdf_envlit(b, uv, n, l->dir + 3 * k, wo, r);
        for (int c = 0; c < 3; c++)
            acc[c] += l->power[3 * k + c] * r[c];
    }
}
