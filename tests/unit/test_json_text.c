/* test_json_text.c: json_text (core/base/json_text.h) against jansson's own
 * json_dumps: the same bytes for trees without reals (compact and
 * indented), the same tree when read back for trees with them, every real
 * back as the same double (sign of zero included, as a real), and the
 * shortest text's own properties. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "json_text.h"

static uint64_t rng = 0x9e3779b97f4a7c15ULL;
static uint64_t next(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

/* a finite double of random bits, or one of the extremes */
static double some_real(void)
{
    static const double odd[] = {0.0, -0.0, 1.0, -1.0, 0.1, 1e21, 1e-7, 1e-6, 123456.0, 1e20,
                                 9007199254740993.0, DBL_MAX, -DBL_MAX, DBL_MIN, 4.9e-324,
                                 -4.9e-324, 2.2250738585072009e-308, 0.30000000000000004,
                                 5e-324, 1.7976931348623157e308, 100.0, 1e15, 1e16, 1e17};
    uint64_t u = next();
    double d;
    if (u % 4 == 0)
        return odd[(u >> 8) % (sizeof odd / sizeof odd[0])];
    if (u % 4 == 1) /* a value of the size a fit writes */
        return ((double)(next() >> 11) * (1.0 / 9007199254740992.0) - 0.5) * 20.0;
    do {
        u = next();
        memcpy(&d, &u, sizeof d);
    } while (!isfinite(d));
    return d;
}

/* a string of random bytes: ASCII with every control character, quotes
 * and backslashes, and valid UTF-8 of 2, 3 and 4 bytes */
static json_t *some_string(void)
{
    char s[64];
    size_t n = 0, len = next() % 20;
    for (size_t i = 0; i < len && n + 4 < sizeof s; i++) {
        uint64_t u = next();
        switch (u % 5) {
        case 0: s[n++] = (char)(1 + (u >> 8) % 0x7f); break; /* 0x01..0x7f */
        case 1: s[n++] = "\"\\/\b\f\n\r\t\x01\x1f"[(u >> 8) % 10]; break;
        case 2: s[n++] = (char)0xc3; s[n++] = (char)0xa9; break;               /* e acute */
        case 3: s[n++] = (char)0xe2; s[n++] = (char)0x82; s[n++] = (char)0xac; break; /* euro */
        default: s[n++] = (char)0xf0; s[n++] = (char)0x9f; s[n++] = (char)0x8e; s[n++] = (char)0xa8;
        }
    }
    return json_stringn(s, n);
}

static json_t *some_tree(int depth, int reals)
{
    uint64_t u = next() % (depth > 4 ? 6 : 9);
    switch (u) {
    case 0: return some_string();
    case 1: return json_integer((json_int_t)next());
    case 2: return reals ? json_real(some_real()) : json_integer(-7);
    case 3: return json_true();
    case 4: return json_false();
    case 5: return json_null();
    case 6:
    case 7: {
        json_t *a = json_array();
        int n = (int)(next() % 6);
        for (int i = 0; i < n; i++)
            json_array_append_new(a, some_tree(depth + 1, reals));
        return a;
    }
    default: {
        json_t *o = json_object();
        int n = (int)(next() % 6);
        for (int i = 0; i < n; i++) {
            char key[16];
            snprintf(key, sizeof key, "k%d\t\"%d", (int)(next() % 1000), i);
            if (!reals && next() % 16 == 0) /* a NUL in a key: jansson writes it, never reads it */
                json_object_setn_new(o, "nul\0key", 7, some_tree(depth + 1, reals));
            else
                json_object_set_new(o, key, some_tree(depth + 1, reals));
        }
        return o;
    }
    }
}

/* a and b the same tree, every real the same bits and still a real */
static int same_bits(const json_t *a, const json_t *b)
{
    if (json_typeof(a) != json_typeof(b))
        return 0;
    if (json_is_real(a)) {
        double x = json_real_value(a), y = json_real_value(b);
        return memcmp(&x, &y, sizeof x) == 0;
    }
    if (json_is_array(a)) {
        if (json_array_size(a) != json_array_size(b))
            return 0;
        for (size_t i = 0; i < json_array_size(a); i++)
            if (!same_bits(json_array_get(a, i), json_array_get(b, i)))
                return 0;
        return 1;
    }
    if (json_is_object(a)) {
        const char *k;
        json_t *v;
        if (json_object_size(a) != json_object_size(b))
            return 0;
        json_object_foreach((json_t *)a, k, v) {
            json_t *w = json_object_get(b, k);
            if (!w || !same_bits(v, w))
                return 0;
        }
        return 1;
    }
    return json_equal((json_t *)a, (json_t *)b);
}

TEST(the_layout_is_json_dumps_s)
{
    static const int indents[] = {0, 1, 2, 4, 31};
    for (int t = 0; t < 400; t++) {
        json_t *j = some_tree(0, 0);
        for (size_t k = 0; k < sizeof indents / sizeof indents[0]; k++) {
            size_t flags = indents[k] ? JSON_INDENT(indents[k]) : JSON_COMPACT;
            char *want = json_dumps(j, flags | JSON_ENCODE_ANY), *got = json_text(j, indents[k]);
            ASSERT(want && got);
            ASSERT_MSG(strcmp(want, got) == 0, "indent %d:\n%s\nagainst\n%s", indents[k], got,
                       want);
            free(want);
            free(got);
        }
        json_decref(j);
    }
}

TEST(every_real_reads_back_the_same)
{
    long reals = 0, shorter = 0;
    for (int t = 0; t < 2000; t++) {
        json_t *j = some_tree(0, 1), *back;
        json_error_t e;
        char *got = json_text(j, t % 3), *want = json_dumps(j, JSON_ENCODE_ANY | JSON_COMPACT | JSON_REAL_PRECISION(17));
        ASSERT(got && want);
        back = json_loads(got, JSON_DECODE_ANY, &e);
        ASSERT_MSG(back, "%s: %s", e.text, got);
        ASSERT_MSG(same_bits(j, back), "not the same tree: %s", got);
        reals += strchr(want, '.') || strchr(want, 'e');
        shorter += strlen(got) < strlen(want);
        json_decref(back);
        free(got);
        free(want);
        json_decref(j);
    }
    ASSERT(reals > 500);
    ASSERT(shorter > 0);
}

TEST(the_shortest_text_of_a_real)
{
    static const struct { double v; const char *text; } cases[] = {
        {1.0, "1.0"},       {-0.0, "-0.0"},       {0.0, "0.0"},
        {0.1, "0.1"},       {1e21, "1e+21"},      {1e-7, "1e-07"},
        {1e-6, "1e-06"},    {123456.0, "123456.0"}, {5e-324, "5e-324"},
        {1e16, "1e+16"},    {1e15, "1000000000000000.0"},
        {DBL_MAX, "1.7976931348623157e+308"},    {0.30000000000000004, "0.30000000000000004"},
        {-2.2250738585072014e-308, "-2.2250738585072014e-308"},
    };
    char buf[32];
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        int n = glint_dtoa_shortest(cases[i].v, buf, (int)sizeof buf);
        ASSERT_MSG(n == (int)strlen(cases[i].text) && strcmp(buf, cases[i].text) == 0,
                   "%.17g: %s, not %s", cases[i].v, buf, cases[i].text);
    }
    ASSERT(glint_dtoa_shortest(NAN, buf, (int)sizeof buf) < 0); /* jansson holds none */
    ASSERT(glint_dtoa_shortest(-INFINITY, buf, (int)sizeof buf) < 0);
    ASSERT(glint_dtoa_shortest(0.1, buf, 3) < 0); /* "0.1" and its NUL do not fit in 3 */
    /* random doubles: at most 17 significant digits, and strtod gives them back */
    for (int t = 0; t < 200000; t++) {
        double v = some_real(), r;
        int n = glint_dtoa_shortest(v, buf, (int)sizeof buf), digits = 0;
        ASSERT(n > 0 && n < (int)sizeof buf);
        r = strtod(buf, NULL);
        ASSERT_MSG(memcmp(&r, &v, sizeof v) == 0, "%.17g printed %s", v, buf);
        for (const char *p = buf, *first = NULL; *p && *p != 'e'; p++) {
            if (!first && *p >= '1' && *p <= '9')
                first = p;
            digits += first && *p >= '0' && *p <= '9';
        }
        /* 17 significant digits at most, or 16 and ".0" */
        ASSERT_MSG(digits <= 17 + 1, "%s", buf);
    }
}

TEST(bad_calls_and_deep_trees)
{
    json_t *deep = json_array(), *a = deep;
    char *t;
    ASSERT(json_text(NULL, 0) == NULL);
    ASSERT(json_text(deep, -1) == NULL);
    ASSERT(json_text(deep, 32) == NULL);
    for (int i = 0; i < JSON_TEXT_MAX_DEPTH + 5; i++) {
        json_t *b = json_array();
        json_array_append_new(a, b);
        a = b;
    }
    ASSERT(json_text(deep, 0) == NULL); /* beyond the depth: refused, not a crash */
    json_decref(deep);
    a = json_object();
    t = json_text(a, 1);
    ASSERT(t && strcmp(t, "{}") == 0);
    free(t);
    json_decref(a);
}

TEST_LIST {
    TEST_ENTRY(the_layout_is_json_dumps_s),
    TEST_ENTRY(every_real_reads_back_the_same),
    TEST_ENTRY(the_shortest_text_of_a_real),
    TEST_ENTRY(bad_calls_and_deep_trees),
};
TEST_MAIN()
