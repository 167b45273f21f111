/* test_brdf.c: the analytic BRDFs (brdf.h) and painting (paint.h).
 *
 * Normalization and energy checks integrate brdf_eval over the hemisphere
 * with the midpoint rule; values at one configuration are computed by hand
 * from the header's formulas and cross-checked against the reference
 * implementation (../shared/reference/hf_ref.py brdf_eval).  The summed
 * shading under an environment (brdf_envlit_sum) is checked against the
 * sum of brdf_envlit a light at a time, digit for digit. */
#include <float.h>
#include <stdint.h>

#include "brdf.h"
#include "check.h"
#include "gbuf.h"
#include "img.h"
#include "paint.h"
#include "scene.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static const double Z[3] = {0.0, 0.0, 1.0};

static uint64_t rng_state = 0x2545f4914f6cdd1dull;
static double rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

/* Uniform random unit vector (rejection from the cube). */
static void rnd_dir(double v[3])
{
    for (;;) {
        double l2;
        for (int c = 0; c < 3; c++)
            v[c] = 2.0 * rnd() - 1.0;
        l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        if (l2 > 1e-4 && l2 <= 1.0) {
            double l = sqrt(l2);
            for (int c = 0; c < 3; c++)
                v[c] /= l;
            return;
        }
    }
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void dir_polar(double theta, double phi, double v[3])
{
    v[0] = sin(theta) * cos(phi);
    v[1] = sin(theta) * sin(phi);
    v[2] = cos(theta);
}

static brdf parse_or_die(const char *spec)
{
    brdf b;
    glint_err e;
    if (brdf_parse(spec, &b, &e) != 0) {
        fprintf(stderr, "brdf_parse(%s): %s\n", spec, e.msg);
        exit(2);
    }
    return b;
}

/* Directional albedo of channel 0 seen from wo: int f(wi, wo) cos_i dwi
 * over the upper hemisphere of n = z (midpoint rule, nt x np cells). */
static double albedo(const brdf *b, const double wo[3], int nt, int np)
{
    double sum = 0.0, dt = 0.5 * M_PI / nt, dp = 2.0 * M_PI / np;
    for (int i = 0; i < nt; i++) {
        double t = (i + 0.5) * dt, w = cos(t) * sin(t) * dt * dp;
        for (int j = 0; j < np; j++) {
            double wi[3], f[3];
            dir_polar(t, (j + 0.5) * dp, wi);
            brdf_eval(b, Z, wi, wo, f);
            sum += f[0] * w;
        }
    }
    return sum;
}

static const char *const all_specs[] = {
    "lambert", "phong", "blinn", "ct", "ward",
    "phong32", "blinn20", "blinn100", "ct0.2", "ct0.5",
    "phong:kd=0.1/0.2/0.3,ks=0.9/0.5/0.2,e=3",
    "ct:kd=0.2,f0=0.9/0.5/0.04,rough=1",
    "ward:ks=0.7,rough=0.05",
};
#define NSPECS ((int)(sizeof all_specs / sizeof all_specs[0]))

/* ---- model properties -------------------------------------------------- */

TEST(reciprocity)
{
    double worst = 0.0;
    for (int s = 0; s < NSPECS; s++) {
        brdf b = parse_or_die(all_specs[s]);
        for (int k = 0; k < 2000; k++) {
            double n[3], wi[3], wo[3], f1[3], f2[3];
            rnd_dir(n);
            rnd_dir(wi);
            rnd_dir(wo);
            if (dot3(n, wi) < 0)
                for (int c = 0; c < 3; c++) wi[c] = -wi[c];
            if (dot3(n, wo) < 0)
                for (int c = 0; c < 3; c++) wo[c] = -wo[c];
            brdf_eval(&b, n, wi, wo, f1);
            brdf_eval(&b, n, wo, wi, f2);
            for (int c = 0; c < 3; c++) {
                double d = fabs(f1[c] - f2[c]) / fmax(1.0, fabs(f1[c]));
                ASSERT_FINITE(f1[c]);
                ASSERT_MSG(f1[c] >= 0.0, "%s: negative f %g", all_specs[s], f1[c]);
                if (d > worst) worst = d;
            }
        }
    }
    ASSERT_LE(worst, 1e-12);
}

TEST(zero_below_horizon)
{
    for (int s = 0; s < NSPECS; s++) {
        brdf b = parse_or_die(all_specs[s]);
        for (int k = 0; k < 2000; k++) {
            double n[3], wi[3], wo[3], f[3];
            rnd_dir(n);
            rnd_dir(wi);
            rnd_dir(wo);
            /* at least one below: flip whichever is above, at random */
            if (dot3(n, wi) > 0 && dot3(n, wo) > 0) {
                double *v = (k & 1) ? wi : wo;
                for (int c = 0; c < 3; c++) v[c] = -v[c];
            }
            brdf_eval(&b, n, wi, wo, f);
            ASSERT_MSG(f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0,
                       "%s: f = %g at cos_i %g cos_o %g", all_specs[s], f[0],
                       dot3(n, wi), dot3(n, wo));
        }
        /* exactly on the horizon counts as below */
        {
            double wi[3] = {1.0, 0.0, 0.0}, wo[3] = {0.0, 0.6, 0.8}, f[3] = {1, 1, 1};
            brdf_eval(&b, Z, wi, wo, f);
            ASSERT(f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0);
            brdf_eval(&b, Z, wo, wi, f);
            ASSERT(f[0] == 0.0 && f[1] == 0.0 && f[2] == 0.0);
        }
    }
}

/* GGX: int D(h) (n.h) dw_h = 1.  D is read back from brdf_eval at
 * wi = wo = h, where F = f0 = 1, kd = 0 and f = D G1(c)^2 / (4 c^2). */
TEST(ggx_normalization)
{
    static const double alphas[] = {0.05, 0.2, 0.5, 1.0};
    for (int k = 0; k < 4; k++) {
        char spec[64];
        double a = alphas[k], a2 = a * a, sum = 0.0;
        const int nt = 20000;
        const double dt = 0.5 * M_PI / nt;
        brdf b;
        snprintf(spec, sizeof spec, "ct:kd=0,f0=1,rough=%g", a);
        b = parse_or_die(spec);
        for (int i = 0; i < nt; i++) {
            double t = (i + 0.5) * dt, h[3], f[3];
            double c = cos(t);
            double g1 = 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
            dir_polar(t, 0.3, h);
            brdf_eval(&b, Z, h, h, f);
            double D = f[0] * 4.0 * c * c / (g1 * g1);
            sum += 2.0 * M_PI * D * c * sin(t) * dt;
        }
        ASSERT_MSG(fabs(sum - 1.0) < 1e-3, "alpha %g: integral %.6f", a, sum);
    }
}

/* Modified Phong: at normal incidence the lobe reflects exactly ks. */
TEST(phong_normalization)
{
    static const double es[] = {1.0, 32.0, 200.0};
    for (int k = 0; k < 3; k++) {
        char spec[64];
        snprintf(spec, sizeof spec, "phong:kd=0,ks=1,e=%g", es[k]);
        brdf b = parse_or_die(spec);
        double r = albedo(&b, Z, 2000, 8);
        ASSERT_MSG(fabs(r - 1.0) < 1e-3, "e %g: albedo %.6f", es[k], r);
    }
}

/* Normalized Blinn-Phong (e+8)/(8 pi): NOT exactly energy conserving.  At
 * normal incidence (h at theta/2) the lobe's albedo is, with u = cos(theta/2),
 *   (e+8) int_{1/sqrt2}^1 u^(e+1) (2u^2 - 1) du
 *   = (e+8) [2 (1 - 2^-((e+4)/2)) / (e+4) - (1 - 2^-((e+2)/2)) / (e+2)],
 * 1.0607 for e = 20, 1.0181 for e = 100, -> 1 as e grows. */
TEST(blinn_normalization)
{
    static const double es[] = {5.0, 20.0, 100.0};
    for (int k = 0; k < 3; k++) {
        double e = es[k];
        char spec[64];
        snprintf(spec, sizeof spec, "blinn:kd=0,ks=1,e=%g", e);
        brdf b = parse_or_die(spec);
        double want = (e + 8.0) * (2.0 * (1.0 - pow(2.0, -(e + 4.0) / 2.0)) / (e + 4.0) -
                                   (1.0 - pow(2.0, -(e + 2.0) / 2.0)) / (e + 2.0));
        double r = albedo(&b, Z, 2000, 8);
        ASSERT_MSG(fabs(r - want) < 1e-3, "e %g: albedo %.6f, closed form %.6f", e, r, want);
        ASSERT_LT(want, 1.07); /* the overshoot stays small */
    }
}

TEST(energy)
{
    static const double degs[] = {0.0, 30.0, 60.0, 80.0};
    static const struct { const char *spec; double max_albedo; } cases[] = {
        {"lambert", 1.0},
        {"lambert:kd=1", 1.0},
        {"phong", 1.0},
        {"phong:kd=0.5,ks=0.5,e=5", 1.0},
        /* blinn: kd + ks X(e), X(20) = 1.0607 at normal incidence */
        {"blinn", 0.7 + 0.3 * 1.0607},
        {"blinn:kd=0.6,ks=0.3,e=20", 1.0}, /* kd + 1.0607 ks <= 1 */
        {"blinn100", 0.7 + 0.3 * 1.0181},
        {"ct", 1.0},
        {"ct0.5", 1.0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        brdf b = parse_or_die(cases[k].spec);
        for (int d = 0; d < 4; d++) {
            double wo[3], r;
            dir_polar(degs[d] * M_PI / 180.0, 0.0, wo);
            r = albedo(&b, wo, 600, 1200);
            ASSERT_MSG(r <= cases[k].max_albedo + 1e-3, "%s at %g deg: albedo %.5f > %.5f",
                       cases[k].spec, degs[d], r, cases[k].max_albedo);
            if (b.kind == BRDF_LAMBERT)
                ASSERT_NEAR(r, b.kd[0], 1e-3);
            if (b.kind == BRDF_PHONG && d == 0) /* kd + ks exactly */
                ASSERT_NEAR(r, b.kd[0] + b.ks[0], 1e-3);
        }
        /* blinn defaults really do exceed 1 at normal incidence */
        if (strcmp(cases[k].spec, "blinn") == 0)
            ASSERT_LT(1.0, albedo(&b, Z, 600, 1200));
    }
}

/* n = z, wi = (0.6, 0, 0.8), wo = (0, 0.6, 0.8): cos_i = cos_o = 0.8,
 * wi + wo = (0.6, 0.6, 1.6), |.|^2 = 3.28, n.h = 1.6/sqrt(3.28),
 * h.wi = 1.64/sqrt(3.28), r = (-0.6, 0, 0.8), r.wo = 0.64. */
TEST(hand_values)
{
    const double wi[3] = {0.6, 0.0, 0.8}, wo[3] = {0.0, 0.6, 0.8};
    const double nh = 1.6 / sqrt(3.28), hi = 1.64 / sqrt(3.28);
    double f[3], want;
    brdf b;

    /* lambert kd 0.8 */
    b = parse_or_die("lambert");
    brdf_eval(&b, Z, wi, wo, f);
    ASSERT_NEAR(f[0], 0.8 / M_PI, 1e-15);
    ASSERT_NEAR(f[0], 0.25464790894703254, 1e-15); /* hf_ref.py */

    /* phong32 kd 0.7 ks 0.3 */
    b = parse_or_die("phong32");
    brdf_eval(&b, Z, wi, wo, f);
    want = 0.7 / M_PI + 0.3 * 34.0 / (2.0 * M_PI) * pow(0.64, 32.0);
    ASSERT_NEAR(f[0], want, 1e-15);
    ASSERT_NEAR(f[0], 0.22281793934105834, 1e-15);

    /* blinn20 and blinn100 */
    b = parse_or_die("blinn20");
    brdf_eval(&b, Z, wi, wo, f);
    want = 0.7 / M_PI + 0.3 * 28.0 / (8.0 * M_PI) * pow(nh, 20.0);
    ASSERT_NEAR(f[0], want, 1e-14);
    ASSERT_NEAR(f[0], 0.250851925618318, 1e-14);
    b = parse_or_die("blinn100");
    brdf_eval(&b, Z, wi, wo, f);
    ASSERT_NEAR(f[0], 0.22282227350105813, 1e-14);

    /* ct0.2: D = a^2 / (pi (nh^2 (a^2 - 1) + 1)^2), G1(0.8), Schlick */
    {
        double a2 = 0.04, t = nh * nh * (a2 - 1.0) + 1.0;
        double D = a2 / (M_PI * t * t);
        double g1 = 1.6 / (0.8 + sqrt(a2 + (1.0 - a2) * 0.64));
        double F = 0.3 + 0.7 * pow(1.0 - hi, 5.0);
        b = parse_or_die("ct0.2");
        brdf_eval(&b, Z, wi, wo, f);
        want = 0.5 / M_PI + D * g1 * g1 * F / (4.0 * 0.64);
        ASSERT_NEAR(f[0], want, 1e-14);
        ASSERT_NEAR(f[0], 0.18262614972283278, 1e-14);
        b = parse_or_die("ct0.5");
        brdf_eval(&b, Z, wi, wo, f);
        ASSERT_NEAR(f[0], 0.20988994058529525, 1e-14);
    }

    /* ward kd 0.5 ks 0.3 a 0.2: tan^2(th_h) = (1 - nh^2)/nh^2 = 0.72/2.56 */
    b = parse_or_die("ward");
    brdf_eval(&b, Z, wi, wo, f);
    want = 0.5 / M_PI + 0.3 * exp(-0.28125 / 0.04) / (4.0 * M_PI * 0.04 * 0.8);
    ASSERT_NEAR(f[0], want, 1e-14);

    /* RGB weights act per channel */
    b = parse_or_die("phong:kd=0.1/0.2/0.3,ks=0.4/0.5/0.6,e=2");
    brdf_eval(&b, Z, wi, wo, f);
    for (int c = 0; c < 3; c++)
        ASSERT_NEAR(f[c], (0.1 + 0.1 * c) / M_PI + (0.4 + 0.1 * c) * 4.0 / (2.0 * M_PI) *
                              0.64 * 0.64, 1e-15);
}

/* ---- parsing ----------------------------------------------------------- */

static int brdf_same(const brdf *a, const brdf *b)
{
    if (a->kind != b->kind || a->exponent != b->exponent || a->roughness != b->roughness)
        return 0;
    for (int c = 0; c < 3; c++)
        if (a->kd[c] != b->kd[c] || a->ks[c] != b->ks[c] || a->f0[c] != b->f0[c])
            return 0;
    return 1;
}

TEST(parse_presets)
{
    brdf b;
    glint_err e;
    ASSERT_OK(brdf_parse("lambert", &b, &e));
    ASSERT(b.kind == BRDF_LAMBERT && b.kd[0] == 0.8 && b.kd[2] == 0.8 && b.ks[0] == 0.0);
    ASSERT_OK(brdf_parse("phong", &b, &e));
    ASSERT(b.kind == BRDF_PHONG && b.kd[1] == 0.7 && b.ks[1] == 0.3 && b.exponent == 32.0);
    ASSERT_OK(brdf_parse("phong32", &b, &e));
    ASSERT(b.kind == BRDF_PHONG && b.exponent == 32.0);
    ASSERT_OK(brdf_parse("blinn", &b, &e));
    ASSERT(b.kind == BRDF_BLINN && b.kd[0] == 0.7 && b.ks[0] == 0.3 && b.exponent == 20.0);
    ASSERT_OK(brdf_parse("blinn20", &b, &e));
    ASSERT(b.kind == BRDF_BLINN && b.exponent == 20.0);
    ASSERT_OK(brdf_parse("blinn100", &b, &e));
    ASSERT(b.kind == BRDF_BLINN && b.exponent == 100.0 && b.kd[0] == 0.7);
    ASSERT_OK(brdf_parse("ct", &b, &e));
    ASSERT(b.kind == BRDF_CT && b.kd[0] == 0.5 && b.f0[2] == 0.3 && b.roughness == 0.2);
    ASSERT_OK(brdf_parse("ct0.2", &b, &e));
    ASSERT(b.kind == BRDF_CT && b.roughness == 0.2);
    ASSERT_OK(brdf_parse("ct0.5", &b, &e));
    ASSERT(b.kind == BRDF_CT && b.roughness == 0.5 && b.f0[0] == 0.3);
    ASSERT_OK(brdf_parse("ward", &b, &e));
    ASSERT(b.kind == BRDF_WARD && b.kd[0] == 0.5 && b.ks[0] == 0.3 && b.roughness == 0.2);
}

TEST(parse_keys)
{
    brdf b;
    glint_err e;
    ASSERT_OK(brdf_parse("phong:kd=0.5,ks=0.2/0.3/0.4,e=64", &b, &e));
    ASSERT(b.kind == BRDF_PHONG && b.kd[0] == 0.5 && b.kd[1] == 0.5 && b.kd[2] == 0.5);
    ASSERT(b.ks[0] == 0.2 && b.ks[1] == 0.3 && b.ks[2] == 0.4 && b.exponent == 64.0);
    ASSERT_OK(brdf_parse("blinn100:kd=0.1", &b, &e)); /* preset + override */
    ASSERT(b.exponent == 100.0 && b.kd[0] == 0.1 && b.ks[0] == 0.3);
    ASSERT_OK(brdf_parse(" blinn : e = 10 , kd= 0 ", &b, &e));
    ASSERT(b.exponent == 10.0 && b.kd[0] == 0.0);
    ASSERT_OK(brdf_parse("ct:f0=0.04/0.05/1,rough=0.01", &b, &e));
    ASSERT(b.f0[0] == 0.04 && b.f0[2] == 1.0 && b.roughness == 0.01);
    ASSERT_OK(brdf_parse("ward:rough=1,ks=1,kd=0", &b, &e));
    ASSERT_OK(brdf_parse("phong:e=10000", &b, &e));
    ASSERT_OK(brdf_parse("phong:e=1e-3", &b, &e));
}

TEST(parse_errors)
{
    static const struct { const char *spec; int code; const char *needle; } bad[] = {
        {"", GLINT_EINVAL, "no model"},
        {"velvet", GLINT_ENOTFOUND, "'velvet'"},
        {"Phong", GLINT_ENOTFOUND, "'Phong'"},
        {"phong:q=1", GLINT_EINVAL, "'q'"},
        {"phong:kd=0.5,shine=3", GLINT_EINVAL, "'shine'"},
        {"lambert:e=3", GLINT_EINVAL, "'e'"},
        {"ct:ks=0.3", GLINT_EINVAL, "'ks'"},
        {"phong:kd=nan", GLINT_EINVAL, "nan"},
        {"phong:kd=NaN/0/0", GLINT_EINVAL, "NaN"},
        {"phong:ks=inf", GLINT_EINVAL, "inf"},
        {"phong:e=1e999", GLINT_EINVAL, "1e999"},
        {"phong:kd=1.5", GLINT_ERANGE, "1.5"},
        {"phong:kd=0.5/-0.1/0.5", GLINT_ERANGE, "component 1"},
        {"phong:e=0", GLINT_ERANGE, "'e'"},
        {"phong:e=-3", GLINT_ERANGE, "'e'"},
        {"phong:e=10001", GLINT_ERANGE, "10001"},
        {"ct:rough=0.005", GLINT_ERANGE, "'rough'"},
        {"ct:rough=1.5", GLINT_ERANGE, "'rough'"},
        {"ct:f0=2", GLINT_ERANGE, "'f0'"},
        {"phong:kd", GLINT_EINVAL, "kd"},
        {"phong:kd=", GLINT_EINVAL, "kd"},
        {"phong:kd=0.5x", GLINT_EINVAL, "0.5x"},
        {"phong:kd=0.5/0.5", GLINT_EINVAL, "kd"},
        {"phong:kd=0.1/0.2/0.3/0.4", GLINT_EINVAL, "kd"},
        {"phong:e=1/2/3", GLINT_EINVAL, "'e'"},
        {"phong:kd=0.5,kd=0.6", GLINT_EINVAL, "twice"},
        {"phong:kd=0.5,", GLINT_EINVAL, "key=value"},
        {"phong:", GLINT_EINVAL, "key=value"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        brdf b;
        glint_err e = {0};
        int rc;
        memset(&b, 0xab, sizeof b);
        rc = brdf_parse(bad[k].spec, &b, &e);
        ASSERT_MSG(rc == bad[k].code, "'%s': rc %d, want %d (%s)", bad[k].spec, rc,
                   bad[k].code, e.msg);
        ASSERT_MSG(strstr(e.msg, bad[k].needle) != NULL, "'%s': message '%s' lacks '%s'",
                   bad[k].spec, e.msg, bad[k].needle);
        ASSERT(((unsigned char *)&b)[0] == 0xab); /* output untouched on error */
    }
    ASSERT_EQ(brdf_parse(NULL, NULL, NULL), GLINT_EINVAL);
    {
        brdf b;
        ASSERT_EQ(brdf_parse(NULL, &b, NULL), GLINT_EINVAL);
        char longspec[600];
        memset(longspec, 'a', sizeof longspec - 1);
        longspec[sizeof longspec - 1] = '\0';
        ASSERT_EQ(brdf_parse(longspec, &b, NULL), GLINT_EINVAL);
    }
}

TEST(format_roundtrip)
{
    char buf[256];
    brdf b, c;
    glint_err e;

    b = parse_or_die("phong");
    brdf_format(&b, buf, sizeof buf);
    ASSERT_MSG(strcmp(buf, "phong:kd=0.7,ks=0.3,e=32") == 0, "got '%s'", buf);
    b = parse_or_die("ct0.5");
    brdf_format(&b, buf, sizeof buf);
    ASSERT_MSG(strcmp(buf, "ct:kd=0.5,f0=0.3,rough=0.5") == 0, "got '%s'", buf);
    b = parse_or_die("lambert");
    brdf_format(&b, buf, sizeof buf);
    ASSERT_MSG(strcmp(buf, "lambert:kd=0.8") == 0, "got '%s'", buf);

    for (int s = 0; s < NSPECS; s++) {
        b = parse_or_die(all_specs[s]);
        brdf_format(&b, buf, sizeof buf);
        ASSERT_MSG(brdf_parse(buf, &c, &e) == 0, "'%s' -> '%s': %s", all_specs[s], buf,
                   e.msg);
        ASSERT_MSG(brdf_same(&b, &c), "'%s' -> '%s' differs", all_specs[s], buf);
    }
    /* values that need 17 digits still round trip */
    b = parse_or_die("blinn");
    b.kd[1] = 0.1 + 0.2;
    b.exponent = 1.0 / 3.0;
    brdf_format(&b, buf, sizeof buf);
    ASSERT_OK(brdf_parse(buf, &c, &e));
    ASSERT_MSG(brdf_same(&b, &c), "'%s' differs", buf);
    /* short buffers are truncated, NUL-terminated */
    brdf_format(&b, buf, 6);
    ASSERT(strcmp(buf, "blinn") == 0);
    brdf_format(&b, buf, 0);
}

/* ---- painting ---------------------------------------------------------- */

static void set3(float *p, double x, double y, double z)
{
    p[0] = (float)x;
    p[1] = (float)y;
    p[2] = (float)z;
}

/* A 3x2 view: pixel 0 uncovered; 1 lit; 2 light below the horizon; 3 camera
 * below; 4 lit with a tilted normal; 5 light exactly on the horizon. */
static int tiny_gbuf(gbuf *g, double shift)
{
    int rc = gbuf_alloc(g, 3, 2, NULL);
    if (rc)
        return rc;
    for (int p = 1; p < 6; p++)
        g->mask[p] = 1;
    set3(g->nrm + 3, 0, 0, 1);
    set3(g->wi + 3, 0.6, 0, 0.8);
    set3(g->wo + 3, 0, 0.6, 0.8);
    set3(g->nrm + 6, 0, 0, 1);
    set3(g->wi + 6, 0.6, 0, -0.8);
    set3(g->wo + 6, 0, 0.6, 0.8);
    set3(g->nrm + 9, 0, 0, 1);
    set3(g->wi + 9, 0.6, 0, 0.8);
    set3(g->wo + 9, 0, -0.6, -0.8);
    set3(g->nrm + 12, 0, 0.6, 0.8);
    {
        double y = 0.6 * cos(shift), l = sqrt(y * y + 0.64);
        set3(g->wi + 12, 0, y / l, 0.8 / l);
    }
    set3(g->wo + 12, 0, 0, 1);
    set3(g->nrm + 15, 0, 0, 1);
    set3(g->wi + 15, 1, 0, 0);
    set3(g->wo + 15, 0, 0, 1);
    return 0;
}

/* What paint must produce at pixel p, before scaling (I: pi times the
 * view's light intensity, scene.h). */
static void expect_raw(const brdf *b, const gbuf *g, double I, int p, double out[3])
{
    double n[3], wi[3], wo[3];
    out[0] = out[1] = out[2] = 0.0;
    if (!g->mask[p])
        return;
    for (int c = 0; c < 3; c++) {
        n[c] = g->nrm[3 * p + c];
        wi[c] = g->wi[3 * p + c];
        wo[c] = g->wo[3 * p + c];
    }
    if (!(dot3(n, wi) > 0 && dot3(n, wo) > 0))
        return;
    brdf_eval(b, n, wi, wo, out);
    for (int c = 0; c < 3; c++)
        out[c] *= I * dot3(n, wi);
}

static void views_init(scene_view *v, int n)
{
    memset(v, 0, sizeof *v * (size_t)n);
    for (int k = 0; k < n; k++) {
        v[k].light_intensity = 1.0 + 1.5 * k;
        v[k].half_fov = 0.3;
        v[k].eye[2] = 3.5;
        v[k].light_deg = -1;
    }
}

TEST(paint_fixed_scale)
{
    gbuf g[2];
    scene_view v[2];
    img out[2];
    glint_err e;
    double used = 0.0;
    brdf b = parse_or_die("ct:kd=0.3/0.5/0.7,f0=0.04,rough=0.3");

    ASSERT_OK(tiny_gbuf(&g[0], 0.0));
    ASSERT_OK(tiny_gbuf(&g[1], 0.5));
    views_init(v, 2);
    memset(out, 0, sizeof out);
    ASSERT_MSG(paint_views(&b, g, v, 2, 3.0, out, &used, &e) == 0, "%s", e.msg);
    ASSERT(used == 3.0);
    for (int k = 0; k < 2; k++) {
        ASSERT(out[k].width == 3 && out[k].height == 2 && out[k].channels == 3);
        for (int p = 0; p < 6; p++) {
            double raw[3];
            expect_raw(&b, &g[k], M_PI * v[k].light_intensity, p, raw);
            for (int c = 0; c < 3; c++) {
                float got = out[k].px[3 * p + c];
                float want = (float)(3.0 * raw[c]);
                ASSERT_MSG(fabsf(got - want) <= 2.0f * FLT_EPSILON * fabsf(want),
                           "view %d px %d ch %d: %.9g vs %.9g", k, p, c, got, want);
                if (p == 0 || p == 2 || p == 3 || p == 5)
                    ASSERT(got == 0.0f);
                else
                    ASSERT(got > 0.0f);
            }
        }
    }
    /* the hand value: view 0 pixel 1 is 3 * pi 1 * f * 0.8 (scene.h: pi I f cos_i) */
    {
        double f[3];
        const double wi[3] = {0.6, 0.0, 0.8}, wo[3] = {0.0, 0.6, 0.8};
        brdf_eval(&b, Z, wi, wo, f);
        ASSERT_NEAR(out[0].px[3], 3.0 * M_PI * f[0] * 0.8, 1e-6 * f[0]);
        /* view 1 has intensity 2.5 */
        ASSERT_NEAR(out[1].px[3], 2.5 * 3.0 * M_PI * f[0] * 0.8, 1e-6 * f[0]);
    }
    img_free(&out[0]);
    img_free(&out[1]);
    gbuf_free(&g[0]);
    gbuf_free(&g[1]);
}

TEST(paint_auto_scale)
{
    gbuf g[2];
    scene_view v[2];
    img out[2];
    glint_err e;
    double used = 0.0, vmax = 0.0;
    brdf b = parse_or_die("blinn100");

    ASSERT_OK(tiny_gbuf(&g[0], 0.0));
    ASSERT_OK(tiny_gbuf(&g[1], 0.9));
    views_init(v, 2);
    for (int k = 0; k < 2; k++)
        for (int p = 0; p < 6; p++) {
            double raw[3];
            expect_raw(&b, &g[k], M_PI * v[k].light_intensity, p, raw);
            for (int c = 0; c < 3; c++)
                vmax = fmax(vmax, raw[c]);
        }
    memset(out, 0, sizeof out);
    ASSERT_MSG(paint_views(&b, g, v, 2, 0.0, out, &used, &e) == 0, "%s", e.msg);
    ASSERT_NEAR(used, 1.0 / vmax, 1e-12 / vmax);
    {
        float m = 0.0f;
        for (int k = 0; k < 2; k++)
            for (int i = 0; i < 18; i++) {
                double raw[3];
                expect_raw(&b, &g[k], M_PI * v[k].light_intensity, i / 3, raw);
                ASSERT(out[k].px[i] <= 1.0f);
                ASSERT_NEAR(out[k].px[i], raw[i % 3] / vmax, 1e-6);
                m = fmaxf(m, out[k].px[i]);
            }
        ASSERT(m == 1.0f);
    }
    img_free(&out[0]);
    img_free(&out[1]);

    /* a negative scale also means automatic */
    ASSERT_OK(paint_views(&b, g, v, 1, -1.0, out, NULL, &e));
    img_free(&out[0]);

    /* nothing lit: scale 1, all zero, no division by zero */
    memset(g[0].mask, 0, 6);
    used = 0.0;
    ASSERT_OK(paint_views(&b, g, v, 1, 0.0, out, &used, &e));
    ASSERT(used == 1.0);
    for (int i = 0; i < 18; i++)
        ASSERT(out[0].px[i] == 0.0f);
    img_free(&out[0]);
    gbuf_free(&g[0]);
    gbuf_free(&g[1]);
}

TEST(paint_errors)
{
    gbuf g[1];
    scene_view v[1];
    img out[1];
    glint_err e;
    brdf b = parse_or_die("lambert");

    ASSERT_OK(tiny_gbuf(&g[0], 0.0));
    views_init(v, 1);
    memset(out, 0, sizeof out);
    ASSERT_EQ(paint_views(&b, g, v, 1, NAN, out, NULL, &e), GLINT_ENONFINITE);
    ASSERT_EQ(paint_views(&b, g, v, 0, 1.0, out, NULL, &e), GLINT_ERANGE);
    ASSERT_EQ(paint_views(NULL, g, v, 1, 1.0, out, NULL, &e), GLINT_EINVAL);
    v[0].light_intensity = 0.0;
    ASSERT_EQ(paint_views(&b, g, v, 1, 1.0, out, NULL, &e), GLINT_EINVAL);
    ASSERT(strstr(e.msg, "intensity") != NULL);
    v[0].light_intensity = 1.0;
    b.kd[1] = NAN;
    ASSERT_EQ(paint_views(&b, g, v, 1, 1.0, out, NULL, &e), GLINT_ENONFINITE);
    b.kd[1] = 0.8;
    /* a NaN normal on a covered pixel: reported, nothing left allocated */
    g[0].nrm[3 * 4 + 1] = NAN;
    ASSERT_EQ(paint_views(&b, g, v, 1, 1.0, out, NULL, &e), GLINT_ENONFINITE);
    ASSERT_MSG(strstr(e.msg, "x 1, y 1") != NULL, "msg: %s", e.msg);
    ASSERT(out[0].px == NULL);
    ASSERT_EQ(paint_views(&b, g, v, 1, 0.0, out, NULL, &e), GLINT_ENONFINITE);
    ASSERT(out[0].px == NULL);
    gbuf_free(&g[0]);
}

/* brdf_envlit_sum against the per-light sum envlit.h describes (lights
 * above the horizon, visible by their bit, power times brdf_envlit), for
 * every model: equal to the last digit, with and without visibility bits,
 * views above and below the horizon and at grazing. */
TEST(envlit_sum_is_the_per_light_sum)
{
    static const char *const specs[] = {
        "lambert:kd=0.6/0.3/0.1", "ct:kd=0.2,f0=0.9/0.6/0.3,rough=0.2", "ct:kd=0.5,rough=0.01",
        "ct:kd=0,f0=0.04,rough=1", "phong:e=40", "blinn", "ward:rough=0.1,rough_y=0.35"};
    enum { K = 100 };
    double dir[3 * K], power[3 * K];
    uint64_t bits[2];
    env_lights l = {K, dir, power, {0.0, 0.0, 0.0}};
    long compared = 0, nonzero = 0;
    for (int k = 0; k < K; k++) {
        rnd_dir(dir + 3 * k);
        for (int c = 0; c < 3; c++)
            power[3 * k + c] = 0.05 * rnd();
    }
    for (size_t si = 0; si < sizeof specs / sizeof specs[0]; si++) {
        brdf b;
        glint_err e;
        ASSERT_OK(brdf_parse(specs[si], &b, &e));
        for (int trial = 0; trial < 200; trial++) {
            double n[3], wo[3], want[3] = {0.0, 0.0, 0.0}, got[3];
            const uint64_t *vis = trial % 2 ? bits : NULL;
            rnd_dir(n);
            rnd_dir(wo);
            if (trial % 10 == 3) { /* grazing: wo on n's horizon */
                double d = dot3(n, wo);
                for (int c = 0; c < 3; c++)
                    wo[c] -= d * n[c];
            }
            bits[0] = (uint64_t)(rnd() * 4294967296.0) << 32 | (uint64_t)(rnd() * 4294967296.0);
            bits[1] = (uint64_t)(rnd() * 4294967296.0);
            for (int k = 0; k < K; k++) {
                double r[3];
                if (dot3(n, dir + 3 * k) <= 0.0 || (vis && !((vis[k >> 6] >> (k & 63)) & 1)))
                    continue;
                brdf_envlit(&b, NULL, n, dir + 3 * k, wo, r);
                for (int c = 0; c < 3; c++)
                    want[c] += power[3 * k + c] * r[c];
            }
            brdf_envlit_sum(&b, &l, vis, NULL, n, wo, got);
            for (int c = 0; c < 3; c++) {
                ASSERT_MSG(got[c] == want[c], "%s, trial %d, channel %d: %.17g against %.17g",
                           specs[si], trial, c, got[c], want[c]);
                compared++;
                nonzero += want[c] != 0.0;
            }
        }
    }
    printf("  %ld sums compared (%ld not zero): equal to the last digit\n", compared, nonzero);
    ASSERT(nonzero > compared / 4);
}

TEST_LIST {
    TEST_ENTRY(reciprocity),
    TEST_ENTRY(zero_below_horizon),
    TEST_ENTRY(ggx_normalization),
    TEST_ENTRY(phong_normalization),
    TEST_ENTRY(blinn_normalization),
    TEST_ENTRY(energy),
    TEST_ENTRY(hand_values),
    TEST_ENTRY(parse_presets),
    TEST_ENTRY(parse_keys),
    TEST_ENTRY(parse_errors),
    TEST_ENTRY(format_roundtrip),
    TEST_ENTRY(paint_fixed_scale),
    TEST_ENTRY(paint_auto_scale),
    TEST_ENTRY(paint_errors),
    TEST_ENTRY(envlit_sum_is_the_per_light_sum),
};

TEST_MAIN()
