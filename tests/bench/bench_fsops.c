/* bench_fsops: what one file-system operation costs in a directory, the
 * steps of glintd's durable writes (store_blob.c, fsio.c): a directory made
 * (a material's), a file created, 2 KiB written, the file fsynced, the
 * directory fsynced, a rename, a delete.  Medians over --reps rounds, in a
 * scratch directory made under DIR (default /tmp) and removed at the end.
 *
 *   ./build/tests/bench/bench_fsops [--dir DIR] [--reps N]
 *
 * Run it on the file system of glintd's --data-dir: a round trip makes a
 * directory, creates four files and fsyncs about eight times, so these
 * figures bound what the warm path can reach there (BENCHMARKS.md). */
#define _GNU_SOURCE
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

enum { MKDIR, CREATE, WRITE, FSYNC, DIRSYNC, RENAME, UNLINK, NOPS };
static const char *names[NOPS] = {"mkdir",         "create (O_CREAT)", "write 2 KiB",
                                  "fsync the file", "fsync the dir",   "rename",
                                  "unlink"};

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

static void fail(const char *what, const char *path)
{
    fprintf(stderr, "bench_fsops: %s %s: %s\n", what, path, strerror(errno));
    exit(1);
}

int main(int argc, char **argv)
{
    const char *base = "/tmp";
    int reps = 200;
    char root[4096], dir[4200], tmp[4300], dst[4300], buf[2048];
    double *t[NOPS];

    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--dir") && i + 1 < argc)
            base = argv[++i];
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc)
            reps = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_fsops [--dir DIR] [--reps N]\n");
            return 2;
        }
    }
    if (reps < 1 || reps > 100000) {
        fprintf(stderr, "bench_fsops: --reps %d outside 1..100000\n", reps);
        return 2;
    }
    snprintf(root, sizeof root, "%s/bench_fsops.XXXXXX", base);
    if (!mkdtemp(root))
        fail("mkdtemp", root);
    memset(buf, 'g', sizeof buf);
    for (int k = 0; k < NOPS; k++)
        if (!(t[k] = calloc((size_t)reps, sizeof *t[k])))
            return 1;
    for (int r = 0; r < reps; r++) {
        double t0;
        int fd;
        snprintf(dir, sizeof dir, "%s/d%d", root, r);
        snprintf(tmp, sizeof tmp, "%s/.f.tmp", dir);
        snprintf(dst, sizeof dst, "%s/f", dir);
        t0 = now();
        if (mkdir(dir, 0755))
            fail("mkdir", dir);
        t[MKDIR][r] = now() - t0;
        t0 = now();
        if ((fd = open(tmp, O_CREAT | O_WRONLY | O_TRUNC | O_CLOEXEC, 0644)) < 0)
            fail("create", tmp);
        t[CREATE][r] = now() - t0;
        t0 = now();
        if (write(fd, buf, sizeof buf) != (ssize_t)sizeof buf)
            fail("write", tmp);
        t[WRITE][r] = now() - t0;
        t0 = now();
        if (fsync(fd))
            fail("fsync", tmp);
        t[FSYNC][r] = now() - t0;
        close(fd);
        t0 = now();
        if (rename(tmp, dst))
            fail("rename", tmp);
        t[RENAME][r] = now() - t0;
        t0 = now();
        if ((fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC)) < 0 || fsync(fd))
            fail("fsync", dir);
        close(fd);
        t[DIRSYNC][r] = now() - t0;
    }
    for (int r = 0; r < reps; r++) { /* the deletes, then the directories */
        double t0;
        snprintf(dst, sizeof dst, "%s/d%d/f", root, r);
        t0 = now();
        if (unlink(dst))
            fail("unlink", dst);
        t[UNLINK][r] = now() - t0;
        snprintf(dir, sizeof dir, "%s/d%d", root, r);
        rmdir(dir);
    }
    rmdir(root);
    printf("file-system operations under %s, %d rounds: median / p90 (ms)\n", base, reps);
    for (int k = 0; k < NOPS; k++) {
        qsort(t[k], (size_t)reps, sizeof *t[k], cmp);
        printf("  %-18s %7.3f / %7.3f\n", names[k], 1e3 * t[k][reps / 2],
               1e3 * t[k][(int)(0.9 * (reps - 1))]);
        free(t[k]);
    }
    return 0;
}
