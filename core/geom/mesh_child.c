/* mesh_child.c: the import in a child process, and the pipe protocol
 * between that child and the loading process (step 3 of loading, see
 * mesh_io.c; contract at mio_import in mesh_int.h).
 *
 * assimp 5.2 crashes (SIGSEGV in its COLLADA reader on a mangled attribute
 * name), aborts (ai_assert is compiled in and calls abort()) or loops on
 * some malformed files that no pre-scan can rule out.  A daemon must
 * survive every upload, so the import runs in a forked child: the child
 * imports, merges and checks (mio_import_direct) and writes the raw soup
 * to a pipe; the parent reads it, with a time limit, and maps the child's
 * death by a signal to an error.  The child has a memory limit (its
 * current address space plus 2 GiB plus 32 bytes per byte of input; not
 * in sanitizer builds, whose shadow memory needs the address space),
 * writes nothing to stdout, and its stderr (assimp's assertion text, a
 * sanitizer report) is captured into the error message.  Each import has
 * its own process, so concurrent loads need no lock around assimp's
 * process-wide error string.
 *
 * The protocol: one mio_wire record (the child's verdict and, on success,
 * the counts), then on success the arrays in this order: positions,
 * normals (if has_nrm), uvs (if has_uv), triangles; then end of file.
 * Anything else (a short record, a bad magic, counts out of range, bytes
 * after the last array) is the child's failure, never trusted. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "internal/mesh_int.h"

#define MIO_WIRE_MAGIC 0x676c6d31u /* "glm1" */

typedef struct mio_wire {
    uint32_t magic;
    int32_t rc;
    char msg[GLINT_ERR_MSG_MAX];
    int64_t nv, nt, prims;
    int32_t has_nrm, has_uv;
} mio_wire;

static int mio_write_all(int fd, const void *p, size_t n)
{
    const char *c = p;
    while (n) {
        ssize_t w = write(fd, c, n);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            return -1;
        c += w;
        n -= (size_t)w;
    }
    return 0;
}

static void mio_child(int fd, const char *path, const void *data, size_t len, const char *hint,
                      const char *what)
{
    mio_wire w;
    mesh raw;
    long long prims = 0;
    glint_err e;
    int rc;

#ifndef MIO_SANITIZED
    {
        FILE *f = fopen("/proc/self/statm", "r");
        unsigned long long pages = 0;
        if (f) {
            if (fscanf(f, "%llu", &pages) != 1)
                pages = 0;
            fclose(f);
        }
        if (pages) {
            struct rlimit rl;
            unsigned long long lim = pages * (unsigned long long)sysconf(_SC_PAGESIZE) +
                                     (2ull << 30) + 32ull * (unsigned long long)len;
            rl.rlim_cur = rl.rlim_max = (rlim_t)lim;
            (void)setrlimit(RLIMIT_AS, &rl);
        }
    }
#endif
    memset(&w, 0, sizeof w);
    memset(&e, 0, sizeof e);
    rc = mio_import_direct(path, data, len, hint, what, &raw, &prims, &e);
    w.magic = MIO_WIRE_MAGIC;
    w.rc = rc;
    memcpy(w.msg, e.msg, sizeof w.msg);
    if (!rc) {
        w.nv = raw.nverts;
        w.nt = raw.ntris;
        w.prims = prims;
        w.has_nrm = raw.nrm != NULL;
        w.has_uv = raw.uv != NULL;
    }
    if (mio_write_all(fd, &w, sizeof w) ||
        (!rc && (mio_write_all(fd, raw.pos, 3 * sizeof(float) * (size_t)raw.nverts) ||
                 (raw.nrm && mio_write_all(fd, raw.nrm, 3 * sizeof(float) * (size_t)raw.nverts)) ||
                 (raw.uv && mio_write_all(fd, raw.uv, 2 * sizeof(float) * (size_t)raw.nverts)) ||
                 mio_write_all(fd, raw.tri, 3 * sizeof(uint32_t) * (size_t)raw.ntris))))
        _exit(3);
    _exit(0);
}

/* Where the next bytes from the child go. */
typedef struct mio_sink {
    mio_wire w;
    unsigned char *seg[5];
    size_t seglen[5];
    int nseg, cur;
    size_t off;      /* into the current segment */
    int header_done;
    mesh *raw;
    int bad;         /* the child sent something inconsistent */
} mio_sink;

static void mio_sink_plan(mio_sink *k, glint_err *err)
{
    const mio_wire *w = &k->w;
    k->header_done = 1;
    k->nseg = 0;
    if (w->magic != MIO_WIRE_MAGIC) {
        k->bad = 1;
        return;
    }
    if (w->rc)
        return;
    if (w->nv < 1 || w->nt < 1 || w->nv > MESH_MAX_VERTS || w->nt > MESH_MAX_TRIS) {
        k->bad = 1;
        return;
    }
    if (mio_alloc(k->raw, (size_t)w->nv, (size_t)w->nt, w->has_nrm, w->has_uv, err)) {
        k->bad = 2;
        return;
    }
    k->seg[k->nseg] = (unsigned char *)k->raw->pos;
    k->seglen[k->nseg++] = 3 * sizeof(float) * (size_t)w->nv;
    if (w->has_nrm) {
        k->seg[k->nseg] = (unsigned char *)k->raw->nrm;
        k->seglen[k->nseg++] = 3 * sizeof(float) * (size_t)w->nv;
    }
    if (w->has_uv) {
        k->seg[k->nseg] = (unsigned char *)k->raw->uv;
        k->seglen[k->nseg++] = 2 * sizeof(float) * (size_t)w->nv;
    }
    k->seg[k->nseg] = (unsigned char *)k->raw->tri;
    k->seglen[k->nseg++] = 3 * sizeof(uint32_t) * (size_t)w->nt;
}

/* Read what is available on the result pipe: 1 at EOF, 0 for more, -1 on
 * error or excess data. */
static int mio_sink_read(mio_sink *k, int fd, glint_err *err)
{
    unsigned char scratch[4096];
    for (;;) {
        unsigned char *dst;
        size_t room;
        ssize_t r;
        if (!k->header_done) {
            dst = (unsigned char *)&k->w + k->off;
            room = sizeof k->w - k->off;
        } else if (k->cur < k->nseg && !k->bad) {
            dst = k->seg[k->cur] + k->off;
            room = k->seglen[k->cur] - k->off;
        } else {
            dst = scratch; /* nothing more is expected: drain and flag */
            room = sizeof scratch;
        }
        r = read(fd, dst, room);
        if (r < 0 && errno == EINTR)
            continue;
        if (r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            return 0;
        if (r < 0)
            return -1;
        if (r == 0)
            return 1;
        if (dst == scratch) {
            k->bad = k->bad ? k->bad : 1;
            continue;
        }
        k->off += (size_t)r;
        if (!k->header_done && k->off == sizeof k->w) {
            k->off = 0;
            mio_sink_plan(k, err);
        } else if (k->header_done && k->off == k->seglen[k->cur]) {
            k->off = 0;
            k->cur++;
        }
    }
}

static double mio_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* mesh_import_in_process (mesh.h): for fuzzing and memcheck only. */
static int mio_in_process;

void mesh_import_in_process(int on)
{
    mio_in_process = on;
}

/* What the loading process gathers from one importer child. */
typedef struct mio_run {
    mio_sink k;           /* the result pipe's bytes */
    char errtext[400];    /* the child's stderr, line ends turned to spaces */
    size_t nerr;
    int status, reaped;   /* waitpid's status, if the child was reaped */
    int timed_out;        /* the child outlived MESH_IMPORT_TIMEOUT_S (and was killed) */
} mio_run;

/* In the child, after fork: fd 3 <- result pipe, 2 <- stderr pipe,
 * 1 <- /dev/null (the pipe ends are first moved out of the way of 0..3),
 * every other descriptor closed and crashes left to their signals; then
 * the import.  Never returns. */
static void mio_child_start(const int out[2], const int errp[2], const char *path,
                            const void *data, size_t len, const char *hint, const char *what)
{
    int wfd = fcntl(out[1], F_DUPFD, 10), efd = fcntl(errp[1], F_DUPFD, 10);
    int devnull = open("/dev/null", O_WRONLY);
    if (wfd < 0 || efd < 0)
        _exit(5);
    if (devnull >= 0 && devnull != 1)
        dup2(devnull, 1);
    dup2(efd, 2);
    dup2(wfd, 3);
    /* nothing of the parent's (sockets, files) stays open in the child */
#ifdef SYS_close_range
    if (syscall(SYS_close_range, 4u, ~0u, 0u) != 0)
#endif
        for (int fd = 4; fd < 4096; fd++)
            close(fd);
    /* a crash ends the child by its signal (the parent reports it) */
    signal(SIGSEGV, SIG_DFL);
    signal(SIGBUS, SIG_DFL);
    signal(SIGFPE, SIG_DFL);
    signal(SIGILL, SIG_DFL);
    signal(SIGABRT, SIG_DFL);
    signal(SIGPIPE, SIG_DFL);
    mio_child(3, path, data, len, hint, what);
    _exit(4); /* not reached */
}

/* Whatever the stderr pipe holds now, appended to r->errtext (truncated
 * to fit); 0 once the pipe is closed or fails. */
static int mio_read_stderr(mio_run *r, int fd)
{
    int open_err = 1;
    for (;;) {
        char b[512];
        ssize_t n = read(fd, b, sizeof b);
        if (n < 0 && errno == EINTR)
            continue;
        if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK))
            open_err = 0;
        if (n <= 0)
            break;
        for (ssize_t j = 0; j < n && r->nerr + 1 < sizeof r->errtext; j++)
            r->errtext[r->nerr++] = b[j] == '\n' || b[j] == '\r' ? ' ' : b[j];
        r->errtext[r->nerr] = '\0';
    }
    return open_err;
}

/* Read both pipes (non-blocking) until the child has closed them, or
 * until the time limit (r->timed_out). */
static void mio_collect(mio_run *r, int outfd, int errfd, glint_err *err)
{
    double deadline = mio_now() + MESH_IMPORT_TIMEOUT_S;
    int open_out = 1, open_err = 1;
    while (open_out || open_err) {
        struct pollfd pf[2];
        int np = 0, wait_ms;
        double left = deadline - mio_now();
        if (left <= 0) {
            r->timed_out = 1;
            break;
        }
        wait_ms = left > 1000.0 ? 1000000 : (int)(left * 1000.0) + 1;
        if (open_out)
            pf[np++] = (struct pollfd){.fd = outfd, .events = POLLIN};
        if (open_err)
            pf[np++] = (struct pollfd){.fd = errfd, .events = POLLIN};
        if (poll(pf, (nfds_t)np, wait_ms) < 0) {
            if (errno == EINTR)
                continue;
            break;
        }
        for (int i = 0; i < np; i++) {
            if (!(pf[i].revents & (POLLIN | POLLHUP | POLLERR)))
                continue;
            if (pf[i].fd == outfd) {
                if (mio_sink_read(&r->k, outfd, err) != 0)
                    open_out = 0;
            } else {
                open_err = mio_read_stderr(r, errfd);
            }
        }
    }
}

/* The child killed if it ran out of time, then waited for. */
static void mio_reap(mio_run *r, pid_t pid)
{
    if (r->timed_out)
        kill(pid, SIGKILL);
    for (;;) {
        pid_t w = waitpid(pid, &r->status, 0);
        if (w == pid) {
            r->reaped = 1;
            break;
        }
        if (w < 0 && errno == EINTR)
            continue;
        break; /* ECHILD: SIGCHLD ignored by the application; judge by the data */
    }
}

/* The import's outcome from what the child did and sent: the time limit,
 * a crash, no memory for the arrays, a sanitizer's report, anything
 * inconsistent, the child's own error (bad_alloc being the memory limit),
 * or success (OUT: *prims). */
static int mio_verdict(mio_run *r, const char *what, long long *prims, glint_err *err)
{
    mio_sink *k = &r->k;
    int rc;
    if (r->timed_out)
        return glint_err_set(err, GLINT_ERANGE, "%s: reading it took more than %d s (the limit)",
                             what, MESH_IMPORT_TIMEOUT_S);
    if (r->reaped && WIFSIGNALED(r->status)) {
        int sig = WTERMSIG(r->status);
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: the importer (assimp) crashed on it (signal %d, %s)%s%s: the "
                             "file is malformed", what, sig, strsignal(sig), r->nerr ? ": " : "",
                             r->errtext);
    }
    if (k->bad == 2) /* out of memory for the arrays: err is set */
        return GLINT_ENOMEM;
    if (!k->header_done && strstr(r->errtext, "DEADLYSIGNAL"))
        /* a sanitizer build reports the crash itself and exits */
        return glint_err_set(err, GLINT_EFORMAT,
                             "%s: the importer (assimp) crashed on it: %s: the file is malformed",
                             what, r->errtext);
    if (!k->header_done || k->bad ||
        (r->reaped && (!WIFEXITED(r->status) || WEXITSTATUS(r->status) != 0)) ||
        (k->w.rc == 0 && k->cur != k->nseg))
        return glint_err_set(err,
                             strstr(r->errtext, "Sanitizer") ? GLINT_EINTERNAL : GLINT_EFORMAT,
                             "%s: the importer process failed (exit status %d)%s%s", what,
                             r->reaped && WIFEXITED(r->status) ? WEXITSTATUS(r->status) : -1,
                             r->nerr ? ": " : "", r->errtext);
    if (k->w.rc) {
        k->w.msg[sizeof k->w.msg - 1] = '\0';
        rc = glint_err_set(err, k->w.rc < 0 && k->w.rc >= GLINT_EINTERNAL ? k->w.rc
                                                                         : GLINT_EINTERNAL,
                           "%s", k->w.msg);
        /* assimp reports exhausting the child's memory limit as bad_alloc
         * (in its own message: others may quote names from the file) */
        if (k->w.rc == GLINT_EFORMAT && strstr(k->w.msg, "bad_alloc"))
            rc = glint_err_set(err, GLINT_ERANGE,
                               "%s: reading it needs more memory than the importer may use "
                               "(%s)", what, k->w.msg);
        return rc;
    }
    *prims = k->w.prims;
    return 0;
}

int mio_import(const char *path, const void *data, size_t len, const char *hint,
               const char *what, mesh *raw, long long *prims, glint_err *err)
{
    int out[2] = {-1, -1}, errp[2] = {-1, -1}, rc;
    mio_run r;
    pid_t pid;

    if (mio_in_process)
        return mio_import_direct(path, data, len, hint, what, raw, prims, err);
    memset(raw, 0, sizeof *raw);
    memset(&r, 0, sizeof r);
    r.k.raw = raw;
    if (pipe(out) || pipe(errp)) {
        rc = glint_err_set(err, GLINT_EIO, "%s: cannot create a pipe for the importer: %s", what,
                           strerror(errno));
        goto done;
    }
    for (int i = 0; i < 2; i++) { /* not inherited by programs other threads exec */
        fcntl(out[i], F_SETFD, FD_CLOEXEC);
        fcntl(errp[i], F_SETFD, FD_CLOEXEC);
    }
    pid = fork();
    if (pid < 0) {
        rc = glint_err_set(err, errno == ENOMEM || errno == EAGAIN ? GLINT_ENOMEM : GLINT_EIO,
                           "%s: cannot start the importer process: %s", what, strerror(errno));
        goto done;
    }
    if (pid == 0)
        mio_child_start(out, errp, path, data, len, hint, what);
    close(out[1]);
    close(errp[1]);
    out[1] = errp[1] = -1;
    fcntl(out[0], F_SETFL, fcntl(out[0], F_GETFL) | O_NONBLOCK);
    fcntl(errp[0], F_SETFL, fcntl(errp[0], F_GETFL) | O_NONBLOCK);
    mio_collect(&r, out[0], errp[0], err);
    mio_reap(&r, pid);
    rc = mio_verdict(&r, what, prims, err);
done:
    for (int i = 0; i < 2; i++) {
        if (out[i] >= 0)
            close(out[i]);
        if (errp[i] >= 0)
            close(errp[i]);
    }
    if (rc)
        mesh_free(raw);
    return rc;
}
