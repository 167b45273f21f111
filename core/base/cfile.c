/* cfile.c: checksummed cache files (cfile.h). */
#include "cfile.h"

#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include "fsio.h"

void cfile_put(cfile_w *b, const void *src, size_t n)
{
    if (b->oom)
        return;
    if (b->len + n > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        unsigned char *q;
        while (cap < b->len + n)
            cap *= 2;
        if (!(q = realloc(b->p, cap))) {
            b->oom = 1;
            return;
        }
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->len, src, n);
    b->len += n;
}

void cfile_reserve(cfile_w *b, size_t total)
{
    unsigned char *q;
    if (b->oom || total <= b->cap)
        return;
    if (!(q = realloc(b->p, total)))
        return; /* cfile_put will try again, and remember a failure */
    b->p = q;
    b->cap = total;
}

void cfile_put_u32(cfile_w *b, uint32_t v)
{
    cfile_put(b, &v, sizeof v);
}

void cfile_begin(cfile_w *b, const char magic[8], uint32_t kind)
{
    memset(b, 0, sizeof *b);
    cfile_put(b, magic, 8);
    cfile_put_u32(b, kind);
}

int cfile_write(cfile_w *b, const char *dir, const char *name, glint_err *err)
{
    char path[4096];
    uint64_t h;
    int rc;
    if (!b->oom) {
        h = XXH64(b->p, b->len, 0);
        cfile_put(b, &h, sizeof h);
    }
    if (b->oom) {
        free(b->p);
        memset(b, 0, sizeof *b);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory writing %s", name);
    }
    if (!(rc = fsio_mkdirs(dir, err)) && !(rc = fsio_join(path, sizeof path, dir, name, err)))
        rc = fsio_write_rebuildable(path, b->p, b->len, err);
    free(b->p);
    memset(b, 0, sizeof *b);
    return rc;
}

int cfile_open(const char *dir, const char *name, const char magic[8], uint32_t kind,
               size_t max_bytes, cfile_r *r, glint_err *err)
{
    char path[4096];
    size_t len;
    uint64_t h;
    uint32_t k;
    int rc;

    memset(r, 0, sizeof *r);
    if ((rc = fsio_join(path, sizeof path, dir, name, err)))
        return rc;
    if ((rc = fsio_read_all(path, max_bytes, &r->data, &len, err)))
        return rc;
    if (len < 8 + 4 + 8 || memcmp(r->data, magic, 8)) {
        cfile_close(r);
        return glint_err_set(err, GLINT_EFORMAT, "%s is not a glint %.8s cache file", name,
                             magic);
    }
    memcpy(&h, r->data + len - 8, 8);
    if (XXH64(r->data, len - 8, 0) != h) {
        cfile_close(r);
        return glint_err_set(err, GLINT_EFORMAT, "%s: checksum mismatch (damaged file)", name);
    }
    r->len = len - 8;
    r->at = 8;
    if (cfile_get(r, &k, 4) || k != kind) {
        cfile_close(r);
        return glint_err_set(err, GLINT_EFORMAT, "%s holds another kind of level", name);
    }
    return 0;
}

int cfile_get(cfile_r *r, void *dst, size_t n)
{
    if (r->len - r->at < n)
        return GLINT_EFORMAT;
    memcpy(dst, r->data + r->at, n);
    r->at += n;
    return 0;
}

int cfile_done(const cfile_r *r)
{
    return r->at == r->len;
}

void cfile_close(cfile_r *r)
{
    free(r->data);
    memset(r, 0, sizeof *r);
}

/* Read n bytes at the file's position (0, or -1 when it ends first or
 * fails). */
static int read_full(int fd, void *dst, size_t n)
{
    char *p = dst;
    while (n) {
        ssize_t got = read(fd, p, n > ((size_t)1 << 30) ? ((size_t)1 << 30) : n);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            return -1;
        p += got;
        n -= (size_t)got;
    }
    return 0;
}

int cfile_stream_open(const char *dir, const char *name, const char magic[8], uint32_t kind,
                      size_t max_bytes, cfile_s *r, glint_err *err)
{
    char path[4096], head[12];
    struct stat st;
    uint32_t k;
    int rc;

    memset(r, 0, sizeof *r);
    if ((rc = fsio_join(path, sizeof path, dir, name, err)))
        return rc;
    if ((r->fd = open(path, O_RDONLY | O_CLOEXEC)) < 0)
        return glint_err_set(err, errno == ENOENT ? GLINT_ENOTFOUND : GLINT_EIO,
                             "cannot read %s: %s", path, strerror(errno));
    if (fstat(r->fd, &st) != 0) {
        rc = glint_err_set(err, GLINT_EIO, "cannot read %s: %s", path, strerror(errno));
        goto fail;
    }
    if (!S_ISREG(st.st_mode) || (size_t)st.st_size > max_bytes ||
        (size_t)st.st_size < 8 + 4 + 8 || read_full(r->fd, head, sizeof head) ||
        memcmp(head, magic, 8)) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s is not a glint %.8s cache file", name,
                           magic);
        goto fail;
    }
    memcpy(&k, head + 8, 4);
    if (k != kind) {
        rc = glint_err_set(err, GLINT_EFORMAT, "%s holds another kind of level", name);
        goto fail;
    }
    if (!(r->hash = XXH64_createState())) {
        rc = glint_err_set(err, GLINT_ENOMEM, "out of memory reading %s", name);
        goto fail;
    }
    XXH64_reset(r->hash, 0);
    XXH64_update(r->hash, head, sizeof head);
    r->len = (size_t)st.st_size - 8;
    r->at = sizeof head;
    return 0;
fail:
    close(r->fd);
    memset(r, 0, sizeof *r);
    return rc;
}

int cfile_stream_get(cfile_s *r, void *dst, size_t n)
{
    /* pieces small enough to be hashed while the cache holds them */
    const size_t piece = (size_t)256 << 10;
    char *p = dst;
    if (!r->hash)
        return GLINT_EINVAL;
    if (r->len - r->at < n)
        return GLINT_EFORMAT;
    for (size_t off = 0; off < n; off += piece) {
        size_t k = n - off < piece ? n - off : piece;
        if (read_full(r->fd, p + off, k))
            return GLINT_EIO;
        XXH64_update(r->hash, p + off, k);
    }
    r->at += n;
    return 0;
}

size_t cfile_stream_left(const cfile_s *r)
{
    return r->hash ? r->len - r->at : 0;
}

int cfile_stream_end(cfile_s *r, const char *name, glint_err *err)
{
    uint64_t h;
    char extra;
    if (!r->hash || r->at != r->len || read_full(r->fd, &h, sizeof h) ||
        read(r->fd, &extra, 1) != 0)
        return glint_err_set(err, GLINT_EFORMAT, "%s: the file has the wrong size", name);
    if (XXH64_digest(r->hash) != h)
        return glint_err_set(err, GLINT_EFORMAT, "%s: checksum mismatch (damaged file)", name);
    return 0;
}

void cfile_stream_close(cfile_s *r)
{
    if (r->hash) { /* open */
        close(r->fd);
        XXH64_freeState(r->hash);
    }
    memset(r, 0, sizeof *r);
}

void cfile_name(const char *key, const char *ext, char *name, size_t len)
{
    XXH128_hash_t h = XXH3_128bits(key, strlen(key));
    snprintf(name, len, "%016llx%016llx%s", (unsigned long long)h.high64,
             (unsigned long long)h.low64, ext);
}

/* ---- mapped --------------------------------------------------------------------------- */

/* The mappings kept (cfile_map_keep), so that a file cut short under one
 * does not kill the process: a fault (SIGBUS) at an address of a kept
 * mapping puts a zeroed page there and marks the mapping torn; its owner
 * asks cfile_map_torn and drops what it read.  Faults elsewhere go to the
 * action there was before. */
#define MAP_SLOTS 4096

static struct map_slot {
    _Atomic uintptr_t start;
    _Atomic size_t size;
    _Atomic int torn;
} map_slots[MAP_SLOTS];
static pthread_mutex_t map_lock = PTHREAD_MUTEX_INITIALIZER;
static struct sigaction bus_before, segv_before;
static uintptr_t page_size;
static int bus_installed;

/* SIGBUS is what the kernel raises; valgrind reports the same access as
 * SIGSEGV ("not within mapped region"), so both come here. */
static void on_sigbus(int sig, siginfo_t *si, void *uc)
{
    uintptr_t a = (uintptr_t)si->si_addr;
    (void)uc;
    for (int i = 0; i < MAP_SLOTS; i++) {
        uintptr_t s = atomic_load(&map_slots[i].start);
        if (s && a >= s && a - s < atomic_load(&map_slots[i].size)) {
            void *pg = (void *)(a & ~(page_size - 1));
            atomic_store(&map_slots[i].torn, 1);
            if (mmap(pg, page_size, PROT_READ | PROT_WRITE,
                     MAP_PRIVATE | MAP_ANONYMOUS | MAP_FIXED, -1, 0) != MAP_FAILED)
                return; /* the access is made again, and reads zeros */
            break;
        }
    }
    /* not a kept mapping's: the fault comes again, under the action before */
    sigaction(sig, sig == SIGBUS ? &bus_before : &segv_before, NULL);
}

/* Register a kept mapping (-1 when every slot is taken). */
static int map_register(void *base, size_t size)
{
    int slot = -1;
    pthread_mutex_lock(&map_lock);
    if (!bus_installed) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_sigaction = on_sigbus;
        sa.sa_flags = SA_SIGINFO;
        sigemptyset(&sa.sa_mask);
        page_size = (uintptr_t)sysconf(_SC_PAGESIZE);
        if (sigaction(SIGBUS, &sa, &bus_before) == 0 &&
            sigaction(SIGSEGV, &sa, &segv_before) == 0)
            bus_installed = 1;
    }
    for (int i = 0; bus_installed && i < MAP_SLOTS && slot < 0; i++)
        if (!atomic_load(&map_slots[i].start)) {
            atomic_store(&map_slots[i].torn, 0);
            atomic_store(&map_slots[i].size, size);
            atomic_store(&map_slots[i].start, (uintptr_t)base);
            slot = i;
        }
    pthread_mutex_unlock(&map_lock);
    return slot;
}

static struct map_slot *map_find(const void *base)
{
    for (int i = 0; base && i < MAP_SLOTS; i++)
        if (atomic_load(&map_slots[i].start) == (uintptr_t)base)
            return &map_slots[i];
    return NULL;
}

int cfile_map_torn(const void *base)
{
    struct map_slot *m = map_find(base);
    return m && atomic_load(&m->torn);
}

int cfile_map_open(const char *dir, const char *name, const char magic[8], uint32_t kind,
                   size_t max_bytes, cfile_m *m, glint_err *err)
{
    char path[4096];
    struct stat st;
    uint64_t h;
    uint32_t k;
    void *p;
    int fd, rc;

    memset(m, 0, sizeof *m);
    if ((rc = fsio_join(path, sizeof path, dir, name, err)))
        return rc;
    if ((fd = open(path, O_RDONLY | O_CLOEXEC)) < 0)
        return glint_err_set(err, errno == ENOENT ? GLINT_ENOTFOUND : GLINT_EIO,
                             "cannot read %s: %s", path, strerror(errno));
    if (fstat(fd, &st) != 0) {
        rc = glint_err_set(err, GLINT_EIO, "cannot read %s: %s", path, strerror(errno));
        close(fd);
        return rc;
    }
    if (!S_ISREG(st.st_mode) || (size_t)st.st_size > max_bytes ||
        (size_t)st.st_size < 8 + 4 + 8) {
        close(fd);
        return glint_err_set(err, GLINT_EFORMAT, "%s is not a glint %.8s cache file", name,
                             magic);
    }
    /* populated at once: one fault per page would cost more than the
     * reading.  Mapped read-only first: populating a writable private
     * mapping would copy every page (the kernel breaks copy-on-write ahead
     * of a write); made writable after, a page is copied only if written. */
    p = mmap(NULL, (size_t)st.st_size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
    close(fd);
    if (p == MAP_FAILED)
        return glint_err_set(err, errno == ENOMEM ? GLINT_ENOMEM : GLINT_EIO,
                             "cannot map %s: %s", path, strerror(errno));
    if (mprotect(p, (size_t)st.st_size, PROT_READ | PROT_WRITE) != 0) {
        rc = glint_err_set(err, GLINT_EIO, "cannot map %s: %s", path, strerror(errno));
        munmap(p, (size_t)st.st_size);
        return rc;
    }
    m->base = p;
    m->size = (size_t)st.st_size;
    m->len = m->size - 8;
    if (memcmp(m->base, magic, 8)) {
        cfile_map_close(m);
        return glint_err_set(err, GLINT_EFORMAT, "%s is not a glint %.8s cache file", name,
                             magic);
    }
    memcpy(&k, m->base + 8, 4);
    if (k != kind) {
        cfile_map_close(m);
        return glint_err_set(err, GLINT_EFORMAT, "%s holds another kind of level", name);
    }
    memcpy(&h, m->base + m->len, 8);
    if (XXH64(m->base, m->len, 0) != h) {
        cfile_map_close(m);
        return glint_err_set(err, GLINT_EFORMAT, "%s: checksum mismatch (damaged file)", name);
    }
    m->at = 12;
    return 0;
}

const void *cfile_map_take(cfile_m *m, size_t n)
{
    const void *p;
    if (!m->base || m->len - m->at < n)
        return NULL;
    p = m->base + m->at;
    m->at += n;
    return p;
}

int cfile_map_align(cfile_m *m, size_t a)
{
    size_t to = (m->at + a - 1) / a * a;
    if (!m->base)
        return GLINT_EINVAL;
    if (to > m->len)
        return GLINT_EFORMAT;
    m->at = to;
    return 0;
}

int cfile_map_keep(cfile_m *m, void **base, size_t *size)
{
    if (!m->base)
        return GLINT_EINVAL;
    if (map_register(m->base, m->size) < 0)
        return GLINT_ERANGE;
    *base = m->base;
    *size = m->size;
    memset(m, 0, sizeof *m);
    return 0;
}

void cfile_unmap(void *base, size_t size)
{
    struct map_slot *slot;
    if (!base)
        return;
    pthread_mutex_lock(&map_lock);
    if ((slot = map_find(base)))
        atomic_store(&slot->start, 0);
    pthread_mutex_unlock(&map_lock);
    munmap(base, size);
}

void cfile_map_close(cfile_m *m)
{
    cfile_unmap(m->base, m->size);
    memset(m, 0, sizeof *m);
}

void cfile_pad(cfile_w *b, size_t a)
{
    static const unsigned char zero[64];
    size_t n = (a - b->len % a) % a;
    while (n) {
        size_t k = n < sizeof zero ? n : sizeof zero;
        cfile_put(b, zero, k);
        n -= k;
    }
}
