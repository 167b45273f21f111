/* replay.c: the fuzz targets' main() outside libFuzzer.
 *
 *   fuzz_NAME [--allow-empty] PATH...
 *
 * Runs the target once on every file named or found (not recursively) in
 * a directory named, each read into a buffer of its exact size (so that a
 * sanitizer sees a read past the end).  Prints how many ran; exits 1 when
 * a path cannot be read, or when no input ran at all and --allow-empty was
 * not given for that path (a missing corpus must not pass as a clean run).
 * A crash or a failed property aborts, which fails the test. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fuzz.h"

/* LLVMFuzzerInitialize is optional in a target: weak here. */
__attribute__((weak)) int LLVMFuzzerInitialize(int *argc, char ***argv);

static int run_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    long n;
    uint8_t *buf;
    if (!f) {
        fprintf(stderr, "replay: cannot open %s\n", path);
        return -1;
    }
    if (fseek(f, 0, SEEK_END) || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET)) {
        fclose(f);
        fprintf(stderr, "replay: cannot size %s\n", path);
        return -1;
    }
    buf = malloc(n ? (size_t)n : 1);
    if (!buf || (n && fread(buf, 1, (size_t)n, f) != (size_t)n)) {
        free(buf);
        fclose(f);
        fprintf(stderr, "replay: cannot read %s\n", path);
        return -1;
    }
    fclose(f);
    LLVMFuzzerTestOneInput(buf, (size_t)n);
    free(buf);
    return 0;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Every regular file in dir, in name order; the count run, or -1. */
static long run_dir(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    char **names = NULL, path[4096];
    size_t n = 0, cap = 0, i;
    long ran = 0;
    if (!d)
        return -1;
    while ((e = readdir(d))) {
        struct stat st;
        if (e->d_name[0] == '.')
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (stat(path, &st) || !S_ISREG(st.st_mode))
            continue;
        if (n == cap) {
            char **t = realloc(names, (cap = cap ? 2 * cap : 64) * sizeof *names);
            if (!t)
                break;
            names = t;
        }
        names[n++] = strdup(path);
    }
    closedir(d);
    qsort(names, n, sizeof *names, by_name);
    for (i = 0; i < n; i++) {
        if (names[i] && run_file(names[i]) == 0)
            ran++;
        else
            ran = -1 - (long)n; /* stays negative */
        free(names[i]);
    }
    free(names);
    return ran < 0 ? -1 : ran;
}

int main(int argc, char **argv)
{
    int allow_empty = 0, bad = 0;
    long total = 0;
    if (LLVMFuzzerInitialize)
        LLVMFuzzerInitialize(&argc, &argv);
    for (int i = 1; i < argc; i++) {
        struct stat st;
        long ran;
        if (!strcmp(argv[i], "--allow-empty")) {
            allow_empty = 1;
            continue;
        }
        if (stat(argv[i], &st)) {
            if (allow_empty) { /* an optional directory (crashes/) may be absent */
                allow_empty = 0;
                continue;
            }
            fprintf(stderr, "replay: %s does not exist\n", argv[i]);
            bad = 1;
            continue;
        }
        ran = S_ISDIR(st.st_mode) ? run_dir(argv[i]) : (run_file(argv[i]) ? -1 : 1);
        if (ran < 0 || (ran == 0 && !allow_empty)) {
            fprintf(stderr, "replay: %s: %s\n", argv[i], ran < 0 ? "unreadable" : "no inputs");
            bad = 1;
        } else {
            printf("%s: %ld inputs\n", argv[i], ran);
        }
        total += ran > 0 ? ran : 0;
        allow_empty = 0;
    }
    printf("%ld inputs replayed without a crash\n", total);
    return bad;
}
