/* check.h: the unit-test harness shared by every tests/unit/test_*.c.
 *
 * Each test file defines its tests with TEST(name) { ... } and lists them in
 * a TEST_LIST at the bottom; the runner executes every test (or the ones
 * named on the command line), prints one line per test and a closing
 * "N passed, N failed" line, and exits non-zero if any failed.  A failing
 * ASSERT prints file, line, the expression and the values, then returns from
 * the test (later tests still run). */
#ifndef GLINT_CHECK_H
#define GLINT_CHECK_H

#include "test_paths.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int check_failed_;

#define CHECK_FAIL_(...)                                                   \
    do {                                                                   \
        fprintf(stderr, "  %s:%d: ", __FILE__, __LINE__);                  \
        fprintf(stderr, __VA_ARGS__);                                      \
        fputc('\n', stderr);                                               \
        check_failed_ = 1;                                                 \
        return;                                                            \
    } while (0)

#define ASSERT(c)                                                          \
    do { if (!(c)) CHECK_FAIL_("ASSERT(%s) failed", #c); } while (0)
#define ASSERT_MSG(c, ...)                                                 \
    do { if (!(c)) CHECK_FAIL_(__VA_ARGS__); } while (0)
#define ASSERT_EQ(a, b)                                                    \
    do { long long a_ = (long long)(a), b_ = (long long)(b);               \
         if (a_ != b_) CHECK_FAIL_("%s == %s failed: %lld vs %lld", #a, #b, a_, b_); } while (0)
#define ASSERT_OK(call)                                                    \
    do { int rc_ = (call);                                                 \
         if (rc_ != 0) CHECK_FAIL_("%s returned %d", #call, rc_); } while (0)
/* |a - b| <= tol, both finite */
#define ASSERT_NEAR(a, b, tol)                                             \
    do { double a_ = (double)(a), b_ = (double)(b), t_ = (double)(tol);    \
         if (!isfinite(a_) || !isfinite(b_) || fabs(a_ - b_) > t_)         \
             CHECK_FAIL_("|%s - %s| <= %s failed: %.17g vs %.17g (diff %.3g, tol %.3g)", \
                         #a, #b, #tol, a_, b_, fabs(a_ - b_), t_); } while (0)
#define ASSERT_LE(a, b)                                                    \
    do { double a_ = (double)(a), b_ = (double)(b);                        \
         if (!(a_ <= b_)) CHECK_FAIL_("%s <= %s failed: %.6g vs %.6g", #a, #b, a_, b_); } while (0)
#define ASSERT_LT(a, b)                                                    \
    do { double a_ = (double)(a), b_ = (double)(b);                        \
         if (!(a_ < b_)) CHECK_FAIL_("%s < %s failed: %.6g vs %.6g", #a, #b, a_, b_); } while (0)
#define ASSERT_FINITE(a)                                                   \
    do { double a_ = (double)(a);                                          \
         if (!isfinite(a_)) CHECK_FAIL_("%s is not finite (%g)", #a, a_); } while (0)

typedef struct check_case { const char *name; void (*fn)(void); } check_case;

#define TEST(name) static void test_##name(void)
#define TEST_ENTRY(name) { #name, test_##name }
#define TEST_LIST static const check_case check_cases_[] =
#define TEST_MAIN()                                                        \
    int main(int argc, char **argv)                                        \
    {                                                                      \
        int npass = 0, nfail = 0;                                          \
        size_t n = sizeof check_cases_ / sizeof check_cases_[0];           \
        for (size_t i = 0; i < n; i++) {                                   \
            int want = argc < 2;                                           \
            for (int a = 1; a < argc; a++)                                 \
                if (strcmp(argv[a], check_cases_[i].name) == 0) want = 1;  \
            if (!want) continue;                                           \
            check_failed_ = 0;                                             \
            check_cases_[i].fn();                                          \
            printf("%s %s\n", check_failed_ ? "FAIL" : "ok  ",            \
                   check_cases_[i].name);                                  \
            fflush(stdout);                                                \
            if (check_failed_) nfail++; else npass++;                      \
        }                                                                  \
        printf("%d passed, %d failed\n", npass, nfail);                    \
        return nfail ? 1 : 0;                                              \
    }

/* Directory of the shared test data (meshes, environment maps), or NULL
 * when it is absent: $GLINT_DATA_DIR, else ../shared/data relative to the
 * source tree (test_paths.h). */
static inline const char *check_data_dir(void)
{
    static char buf[4096];
    const char *env = getenv("GLINT_DATA_DIR");
    if (env && *env) return env;
    snprintf(buf, sizeof buf, "%s/../shared/data", glint_test_source_dir);
    FILE *f = fopen(buf, "r");
    if (f) { fclose(f); return buf; }
    return NULL;
}

#endif
