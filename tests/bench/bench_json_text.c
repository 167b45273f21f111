/* bench_json_text: a material's manifest as text, by jansson's json_dumps
 * (every real with "%.17g") and by json_text (core/base/json_text.h: the
 * shortest text of each real), indented as material.json is and compact
 * as glintd's records and responses are.  Medians over --reps rounds,
 * alternating; each text is read back and compared with the tree.
 *
 *   ./build/tests/bench/bench_json_text [--reps N] [FILE.json]
 *
 * Without FILE, a tree shaped like a three-factor material at res 64: 576
 * log-factor reals and an info object of about 50 more. */
#include <jansson.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "json_text.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static long count_reals(json_t *j)
{
    long n = json_is_real(j);
    size_t i;
    const char *k;
    json_t *v;
    if (json_is_array(j))
        json_array_foreach(j, i, v) n += count_reals(v);
    if (json_is_object(j))
        json_object_foreach(j, k, v) n += count_reals(v);
    return n;
}

static json_t *made_up(void)
{
    json_t *root = json_object(), *fac = json_array(), *info = json_object(), *sec = json_object();
    uint64_t x = 0x9e3779b97f4a7c15ULL;
    json_object_set_new(root, "format", json_string("glint-material"));
    json_object_set_new(root, "version", json_integer(1));
    json_object_set_new(root, "method", json_string("hf3"));
    for (int k = 0; k < 3 * 64; k++) {
        json_t *t = json_array();
        for (int c = 0; c < 3; c++) {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            json_array_append_new(t, json_real(((double)(x >> 11) / 9007199254740992.0 - 0.5) * 4.0));
        }
        json_array_append_new(fac, t);
    }
    json_object_set_new(root, "log_factors", fac);
    for (int i = 0; i < 50; i++) {
        char key[32];
        snprintf(key, sizeof key, "step_%d", i);
        json_object_set_new(sec, key, json_real(1e-4 * (i + 1) / 3.0));
    }
    json_object_set_new(info, "seconds", sec);
    json_object_set_new(info, "samples", json_integer(40946));
    json_object_set_new(info, "map", json_string("log"));
    json_object_set_new(root, "info", info);
    return root;
}

int main(int argc, char **argv)
{
    int reps = 200;
    const char *file = NULL;
    json_t *j;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--reps") == 0 && i + 1 < argc)
            reps = atoi(argv[++i]);
        else if (argv[i][0] != '-')
            file = argv[i];
        else {
            fprintf(stderr, "usage: %s [--reps N] [FILE.json]\n", argv[0]);
            return 2;
        }
    }
    if (reps < 1 || reps > 1000000) {
        fprintf(stderr, "--reps: 1 to 1000000\n");
        return 2;
    }
    if (file) {
        json_error_t e;
        if (!(j = json_load_file(file, 0, &e))) {
            fprintf(stderr, "%s: %s (line %d)\n", file, e.text, e.line);
            return 1;
        }
    } else {
        j = made_up();
    }
    printf("%s: %ld reals; medians of %d rounds, alternating\n", file ? file : "made-up manifest",
           count_reals(j), reps);
    printf("| text | json_dumps (ms) | json_text (ms) | ratio | bytes (dumps / text) |\n|---|---|---|---|---|\n");
    for (int form = 0; form < 2; form++) {
        double *td = malloc((size_t)reps * sizeof *td), *tt = malloc((size_t)reps * sizeof *tt);
        size_t ld = 0, lt = 0;
        if (!td || !tt)
            return 1;
        for (int r = 0; r < reps; r++) {
            double t0 = now(), t1, t2;
            char *a = json_dumps(j, (form ? JSON_INDENT(1) : JSON_COMPACT) | JSON_REAL_PRECISION(17));
            t1 = now();
            char *b = json_text(j, form ? 1 : 0);
            t2 = now();
            json_t *back = b ? json_loads(b, 0, NULL) : NULL;
            if (!a || !b || !back || !json_equal(back, j)) {
                fprintf(stderr, "the text does not read back as the tree\n");
                return 1;
            }
            json_decref(back);
            td[r] = t1 - t0;
            tt[r] = t2 - t1;
            ld = strlen(a);
            lt = strlen(b);
            free(a);
            free(b);
        }
        qsort(td, (size_t)reps, sizeof *td, cmp);
        qsort(tt, (size_t)reps, sizeof *tt, cmp);
        printf("| %s | %.3f | %.3f | %.2f | %zu / %zu |\n", form ? "indented (material.json)" : "compact",
               td[reps / 2] * 1e3, tt[reps / 2] * 1e3, td[reps / 2] / tt[reps / 2], ld, lt);
        free(td);
        free(tt);
    }
    json_decref(j);
    return 0;
}
