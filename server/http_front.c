/* http_front.c: the connection front (http_front.h). */
#define _GNU_SOURCE
#include "http_front.h"

#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/uio.h>
#include <time.h>
#include <unistd.h>

#include "http.h"

#define FRONT_LINGER_S 2.0            /* reading and discarding after an answer */
#define FRONT_LINGER_BYTES (1u << 20) /* ... at most this much */
#define FRONT_ACCEPT_PAUSE_S 0.1      /* when accept() runs out of descriptors */
#define FRONT_IP_BUCKETS 4096
#define FRONT_EVENTS 64

typedef struct front_conn front_conn;

/* One client: an IPv4 address or an IPv6 /64. */
typedef struct front_ip {
    unsigned char key[16];
    unsigned waiting;            /* its connections in the front (lingering ones included) */
    unsigned served;             /* its leases */
    front_conn *oldest, *newest; /* its connections in the front, by accept time */
    struct front_ip *next;       /* hash chain */
} front_ip;

/* A connection in the front: waiting for its head, or lingering after an
 * answer. */
struct front_conn {
    int fd;
    int lingering;
    double t0, deadline;
    size_t drained, drain_max;     /* read and discarded while lingering, and the most */
    struct sockaddr_storage addr;
    socklen_t addrlen;
    front_ip *ip;
    front_conn *prev, *next;       /* in f->waiting or f->linger, by deadline */
    front_conn *ip_prev, *ip_next; /* in ip's list, by accept time */
};

typedef struct front_list {
    front_conn *head, *tail;
} front_list;

struct http_front_lease {
    front_ip *ip;
    int reserve;
};

struct http_front {
    http_front_config cfg;
    int listen_fd, ep, wake;
    int listening;               /* listen_fd is in the epoll set */
    pthread_t thread;
    int started;
    int stopping;                /* set before waking the thread to stop it */
    pthread_mutex_t lock;        /* the client table, leases and their counts */
    front_ip *bucket[FRONT_IP_BUCKETS];
    unsigned served, reserved;   /* ordinary and reserve leases out */
    front_list waiting, linger;  /* both by deadline: every entry of one has the same delay */
    unsigned nconns;             /* connections in the front */
    front_conn *dead;            /* closed in this round of events, freed after it: a later
                                    event of the same round may still name them */
    double accept_resume;        /* > 0: accepting paused until then */
    char *buf;                   /* cfg.head.max_head bytes: peeks and discarded reads */
};

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- clients ------------------------------------------------------------------------------- */

static void client_key(const struct sockaddr_storage *ss, unsigned char key[16])
{
    memset(key, 0, 16);
    if (ss->ss_family == AF_INET) {
        const struct sockaddr_in *a = (const struct sockaddr_in *)ss;
        key[10] = key[11] = 0xff;
        memcpy(key + 12, &a->sin_addr, 4);
    } else if (ss->ss_family == AF_INET6) {
        const struct sockaddr_in6 *a = (const struct sockaddr_in6 *)ss;
        if (IN6_IS_ADDR_V4MAPPED(&a->sin6_addr))
            memcpy(key, &a->sin6_addr, 16);
        else
            memcpy(key, &a->sin6_addr, 8); /* the /64 */
    }
}

static unsigned client_hash(const unsigned char key[16])
{
    uint32_t h = 2166136261u;
    for (int i = 0; i < 16; i++)
        h = (h ^ key[i]) * 16777619u;
    return h % FRONT_IP_BUCKETS;
}

/* The client's entry, made if new (NULL: out of memory).  Under f->lock. */
static front_ip *client_get(http_front *f, const unsigned char key[16])
{
    unsigned b = client_hash(key);
    front_ip *ip;
    for (ip = f->bucket[b]; ip; ip = ip->next)
        if (memcmp(ip->key, key, 16) == 0)
            return ip;
    ip = calloc(1, sizeof *ip);
    if (!ip)
        return NULL;
    memcpy(ip->key, key, 16);
    ip->next = f->bucket[b];
    f->bucket[b] = ip;
    return ip;
}

/* Free the entry once it holds nothing.  Under f->lock. */
static void client_put(http_front *f, front_ip *ip)
{
    front_ip **pp;
    if (ip->waiting || ip->served)
        return;
    for (pp = &f->bucket[client_hash(ip->key)]; *pp; pp = &(*pp)->next)
        if (*pp == ip) {
            *pp = ip->next;
            free(ip);
            return;
        }
}

/* ---- lists --------------------------------------------------------------------------------- */

static void list_push(front_list *l, front_conn *c)
{
    c->next = NULL;
    c->prev = l->tail;
    if (l->tail)
        l->tail->next = c;
    else
        l->head = c;
    l->tail = c;
}

static void list_remove(front_list *l, front_conn *c)
{
    if (c->prev)
        c->prev->next = c->next;
    else
        l->head = c->next;
    if (c->next)
        c->next->prev = c->prev;
    else
        l->tail = c->prev;
    c->prev = c->next = NULL;
}

/* Take c out of the front (lists, client count); the caller then closes or
 * hands on c->fd and buries c. */
static void conn_detach(http_front *f, front_conn *c)
{
    front_ip *ip = c->ip;
    list_remove(c->lingering ? &f->linger : &f->waiting, c);
    if (c->ip_prev)
        c->ip_prev->ip_next = c->ip_next;
    else
        ip->oldest = c->ip_next;
    if (c->ip_next)
        c->ip_next->ip_prev = c->ip_prev;
    else
        ip->newest = c->ip_prev;
    f->nconns--;
    pthread_mutex_lock(&f->lock);
    ip->waiting--;
    client_put(f, ip);
    pthread_mutex_unlock(&f->lock);
}

/* Keep c's record until the round of events ends (conn_reap). */
static void conn_bury(http_front *f, front_conn *c)
{
    c->fd = -1;
    c->next = f->dead;
    f->dead = c;
}

static void conn_close(http_front *f, front_conn *c)
{
    conn_detach(f, c);
    close(c->fd);
    conn_bury(f, c);
}

static void conn_reap(http_front *f)
{
    while (f->dead) {
        front_conn *c = f->dead;
        f->dead = c->next;
        free(c);
    }
}

/* ---- answers ------------------------------------------------------------------------------- */

/* Write a problem+json answer with "Connection: close" (best effort: it is
 * small and the socket's buffer empty, so one non-blocking send does). */
static void send_problem(int fd, int status, const char *slug, const char *detail,
                         int head_only, int retry_after)
{
    char *body = http_problem_json(status, slug, "%s", detail);
    char head[512], date[64];
    size_t blen = body ? strlen(body) : 0;
    struct iovec iov[2];
    struct msghdr msg;
    struct tm tm;
    time_t t = time(NULL);
    int n;

    gmtime_r(&t, &tm);
    strftime(date, sizeof date, "%a, %d %b %Y %H:%M:%S GMT", &tm);
    n = snprintf(head, sizeof head,
                 "HTTP/1.1 %d %s\r\nDate: %s\r\nContent-Type: application/problem+json\r\n"
                 "Content-Length: %zu\r\n%sConnection: close\r\n\r\n",
                 status, http_status_title(status), date, blen,
                 retry_after ? "Retry-After: 1\r\n" : "");
    memset(&msg, 0, sizeof msg);
    iov[0].iov_base = head;
    iov[0].iov_len = (size_t)n;
    iov[1].iov_base = body;
    iov[1].iov_len = head_only ? 0 : blen;
    msg.msg_iov = iov;
    msg.msg_iovlen = 2;
    (void)sendmsg(fd, &msg, MSG_NOSIGNAL | MSG_DONTWAIT);
    free(body);
}

/* Read and discard what the client sends while lingering; close at its end,
 * on an error or past c->drain_max bytes. */
static void linger_drain(http_front *f, front_conn *c)
{
    for (;;) {
        ssize_t k = recv(c->fd, f->buf, f->cfg.head.max_head, MSG_DONTWAIT);
        if (k > 0) {
            c->drained += (size_t)k;
            if (c->drained > c->drain_max)
                break;
            continue;
        }
        if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
            return;
        if (k < 0 && errno == EINTR)
            continue;
        break; /* end of stream or error */
    }
    conn_close(f, c);
}

/* Peek again at what the client sent so far: the method and target read
 * from it (for the log) go to *h, the byte count to *have. */
static void peek_request(http_front *f, front_conn *c, http_head *h, size_t *have)
{
    http_head_error e;
    ssize_t k = recv(c->fd, f->buf, f->cfg.head.max_head, MSG_PEEK | MSG_DONTWAIT);
    *have = k > 0 ? (size_t)k : 0;
    (void)http_head_parse(f->buf, *have, &f->cfg.head, h, &e);
}

/* Answer c, log it, and let it linger.  h: what was read of its head (for
 * the log; f->buf holds the bytes). */
static void conn_answer(http_front *f, front_conn *c, const http_head *h, int status,
                        const char *slug, const char *detail, int retry_after, double now)
{
    const char *m = h && h->method_len ? f->buf + h->method_off : NULL;
    const char *t = h && h->target_len ? f->buf + h->target_off : NULL;
    int head_only = m && h->method_len == 4 && memcmp(m, "HEAD", 4) == 0;

    send_problem(c->fd, status, slug, detail, head_only, retry_after);
    /* a body refused with its head (413) may be on its way, up to the limit:
     * read it too, so that the client's stack does not reset the connection
     * before the answer is read */
    c->drain_max = FRONT_LINGER_BYTES;
    if (status == 413 && h && h->len && h->content_length > 0)
        c->drain_max += h->len + ((uint64_t)h->content_length < f->cfg.head.max_body
                                      ? (size_t)h->content_length
                                      : (size_t)f->cfg.head.max_body);
    if (f->cfg.answered)
        f->cfg.answered(f->cfg.cls, m, m ? h->method_len : 0, t, t ? h->target_len : 0, status,
                        now - c->t0);
    shutdown(c->fd, SHUT_WR);
    list_remove(&f->waiting, c);
    c->lingering = 1;
    c->deadline = now + FRONT_LINGER_S;
    list_push(&f->linger, c);
    linger_drain(f, c);
}

static void conn_admit(http_front *f, front_conn *c, const http_head *h, double now);

/* Drop c to make room: a connection that had begun its request is told
 * (503), one that sent nothing, or one lingering, is just closed.  One
 * whose whole head has arrived (its readiness not yet handled: the front
 * was accepting a flood) is admitted instead, as it would have been a
 * moment later: a health check from a flooded address is answered. */
static void conn_evict(http_front *f, front_conn *c, double now)
{
    if (!c->lingering) {
        http_head h;
        http_head_error e;
        size_t have;
        peek_request(f, c, &h, &have);
        if (have && http_head_parse(f->buf, have, &f->cfg.head, &h, &e) == HTTP_HEAD_OK) {
            conn_admit(f, c, &h, now);
            return;
        }
        if (have) {
            const char *m = h.method_len ? f->buf + h.method_off : NULL;
            const char *t = h.target_len ? f->buf + h.target_off : NULL;
            send_problem(c->fd, 503, "too-many-connections",
                         "too many connections are waiting for their request; try again", 0,
                         1);
            if (f->cfg.answered)
                f->cfg.answered(f->cfg.cls, m, m ? h.method_len : 0, t, t ? h.target_len : 0,
                                503, now - c->t0);
        }
    }
    conn_close(f, c);
}

/* The oldest connection in the front (lingering ones first), or NULL. */
static front_conn *oldest(http_front *f)
{
    return f->linger.head ? f->linger.head : f->waiting.head;
}

/* ---- admission ----------------------------------------------------------------------------- */

static int is_health(const char *buf, const http_head *h)
{
    const char *m = buf + h->method_off, *t = buf + h->target_off;
    size_t plen = h->target_len;
    const char *q = memchr(t, '?', plen);
    if (q)
        plen = (size_t)(q - t);
    if (!((h->method_len == 3 && memcmp(m, "GET", 3) == 0) ||
          (h->method_len == 4 && memcmp(m, "HEAD", 4) == 0)))
        return 0;
    return (plen == 8 && memcmp(t, "/healthz", 8) == 0) ||
           (plen == 15 && memcmp(t, "/api/v1/healthz", 15) == 0);
}

/* The head of c is complete and acceptable: hand it on, or refuse it. */
static void conn_admit(http_front *f, front_conn *c, const http_head *h, double now)
{
    front_ip *ip = c->ip;
    http_front_lease *lease = malloc(sizeof *lease);
    int refusal = 0, reserve = 0, fd;
    char detail[160];

    if (!lease) {
        conn_answer(f, c, h, 503, "out-of-memory", "the server is out of memory", 1, now);
        return;
    }
    pthread_mutex_lock(&f->lock);
    if (ip->served < f->cfg.max_per_ip && f->served < f->cfg.max_connections)
        reserve = 0;
    else if (is_health(f->buf, h) && f->reserved < f->cfg.health_reserve)
        reserve = 1;
    else
        refusal = ip->served >= f->cfg.max_per_ip ? 429 : 503;
    if (!refusal) {
        ip->served++;
        if (reserve)
            f->reserved++;
        else
            f->served++;
    }
    pthread_mutex_unlock(&f->lock);

    if (refusal) {
        free(lease);
        if (refusal == 429)
            snprintf(detail, sizeof detail,
                     "this client already has %u connections being served (the limit per "
                     "client); reuse one or try again",
                     f->cfg.max_per_ip);
        else
            snprintf(detail, sizeof detail,
                     "the server is serving its limit of %u connections; try again",
                     f->cfg.max_connections);
        conn_answer(f, c, h, refusal,
                    refusal == 429 ? "too-many-connections-per-client" : "too-many-connections",
                    detail, 1, now);
        return;
    }
    lease->ip = ip;
    lease->reserve = reserve;
    epoll_ctl(f->ep, EPOLL_CTL_DEL, c->fd, NULL);
    conn_detach(f, c); /* ip stays: the lease counts in ip->served */
    fd = c->fd;
    f->cfg.deliver(f->cfg.cls, fd, (const struct sockaddr *)&c->addr, c->addrlen, lease);
    conn_bury(f, c);
}

/* Bytes arrived on a waiting connection (or it was closed). */
static void conn_readable(http_front *f, front_conn *c, uint32_t events, double now)
{
    http_head h;
    http_head_error e;
    ssize_t k;
    int rc;

    if (c->fd < 0) /* closed earlier in this round */
        return;
    if (c->lingering) {
        linger_drain(f, c);
        return;
    }
    k = recv(c->fd, f->buf, f->cfg.head.max_head, MSG_PEEK | MSG_DONTWAIT);
    if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR))
        return;
    if (k <= 0) { /* closed (or failed) before a request came */
        conn_close(f, c);
        return;
    }
    rc = http_head_parse(f->buf, (size_t)k, &f->cfg.head, &h, &e);
    if (rc == HTTP_HEAD_MORE) {
        if (events & (EPOLLRDHUP | EPOLLHUP | EPOLLERR))
            conn_close(f, c); /* the client stopped sending half-way through its head */
        return;
    }
    if (rc == HTTP_HEAD_BAD)
        conn_answer(f, c, &h, e.status, e.slug, e.detail, 0, now);
    else
        conn_admit(f, c, &h, now);
}

/* The header deadline of c passed. */
static void conn_expire(http_front *f, front_conn *c, double now)
{
    http_head h;
    size_t have;
    char detail[128];

    peek_request(f, c, &h, &have);
    if (!have) { /* an idle connection: nothing to answer */
        conn_close(f, c);
        return;
    }
    snprintf(detail, sizeof detail, "the request head did not arrive within %u s",
             f->cfg.header_timeout_s);
    conn_answer(f, c, &h, 408, "request-timeout", detail, 0, now);
}

/* ---- the loop ------------------------------------------------------------------------------ */

static void accept_pause(http_front *f, double now)
{
    if (f->listening) {
        epoll_ctl(f->ep, EPOLL_CTL_DEL, f->listen_fd, NULL);
        f->listening = 0;
    }
    f->accept_resume = now + FRONT_ACCEPT_PAUSE_S;
}

static void accept_resume(http_front *f)
{
    struct epoll_event ev = {.events = EPOLLIN, .data.ptr = &f->listen_fd};
    if (epoll_ctl(f->ep, EPOLL_CTL_ADD, f->listen_fd, &ev) == 0)
        f->listening = 1;
    f->accept_resume = 0;
}

static void accept_all(http_front *f, double now)
{
    for (;;) {
        struct sockaddr_storage ss;
        socklen_t sl = sizeof ss;
        unsigned char key[16];
        struct epoll_event ev;
        front_conn *c;
        front_ip *ip;
        int fd = accept4(f->listen_fd, (struct sockaddr *)&ss, &sl, SOCK_NONBLOCK | SOCK_CLOEXEC);

        if (fd < 0) {
            if (errno == EINTR || errno == ECONNABORTED || errno == EPROTO)
                continue;
            if (errno == EMFILE || errno == ENFILE || errno == ENOBUFS || errno == ENOMEM) {
                if (oldest(f)) {
                    conn_evict(f, oldest(f), now);
                    continue;
                }
                accept_pause(f, now);
            }
            return; /* EAGAIN: all accepted */
        }
        client_key(&ss, key);
        pthread_mutex_lock(&f->lock);
        ip = client_get(f, key);
        if (ip)
            ip->waiting++; /* counted now, so that evictions below cannot free ip */
        pthread_mutex_unlock(&f->lock);
        c = ip ? calloc(1, sizeof *c) : NULL;
        if (!c) {
            close(fd);
            if (ip) {
                pthread_mutex_lock(&f->lock);
                ip->waiting--;
                client_put(f, ip);
                pthread_mutex_unlock(&f->lock);
            }
            continue;
        }
        while (ip->waiting > f->cfg.max_waiting_per_ip && ip->oldest)
            conn_evict(f, ip->oldest, now);
        while (f->nconns >= f->cfg.max_waiting && oldest(f))
            conn_evict(f, oldest(f), now);
        c->fd = fd;
        c->ip = ip;
        c->t0 = now;
        c->deadline = now + f->cfg.header_timeout_s;
        memcpy(&c->addr, &ss, sizeof ss);
        c->addrlen = sl;
        list_push(&f->waiting, c);
        c->ip_prev = ip->newest;
        if (ip->newest)
            ip->newest->ip_next = c;
        else
            ip->oldest = c;
        ip->newest = c;
        f->nconns++;
        /* edge-triggered: peeking leaves the bytes queued, so a level-triggered
         * set would report them again and again; bytes already there when the
         * socket is added are reported once */
        ev.events = EPOLLIN | EPOLLRDHUP | EPOLLET;
        ev.data.ptr = c;
        if (epoll_ctl(f->ep, EPOLL_CTL_ADD, fd, &ev) != 0)
            conn_close(f, c);
    }
}

/* Expire what is due; returns the next deadline (0: none). */
static double expire(http_front *f, double now)
{
    double next = 0;
    while (f->linger.head && f->linger.head->deadline <= now)
        conn_close(f, f->linger.head);
    while (f->waiting.head && f->waiting.head->deadline <= now)
        conn_expire(f, f->waiting.head, now);
    if (f->accept_resume > 0 && f->accept_resume <= now)
        accept_resume(f);
    if (f->linger.head)
        next = f->linger.head->deadline;
    if (f->waiting.head && (!next || f->waiting.head->deadline < next))
        next = f->waiting.head->deadline;
    if (f->accept_resume > 0 && (!next || f->accept_resume < next))
        next = f->accept_resume;
    return next;
}

static void *front_main(void *arg)
{
    http_front *f = arg;
    struct epoll_event ev[FRONT_EVENTS];
    double next = 0;

    for (;;) {
        int timeout = -1, n;
        double now;
        if (next > 0) {
            double dt = next - now_s();
            timeout = dt <= 0 ? 0 : (int)(dt * 1000.0) + 1;
        }
        n = epoll_wait(f->ep, ev, FRONT_EVENTS, timeout);
        if (n < 0 && errno != EINTR)
            break;
        now = now_s();
        for (int i = 0; i < n; i++) {
            void *p = ev[i].data.ptr;
            if (p == &f->wake) {
                if (__atomic_load_n(&f->stopping, __ATOMIC_ACQUIRE))
                    goto out;
            } else if (p == &f->listen_fd) {
                accept_all(f, now);
            } else {
                conn_readable(f, p, ev[i].events, now);
            }
        }
        next = expire(f, now_s());
        conn_reap(f);
    }
out:
    return NULL;
}

/* ---- life cycle ---------------------------------------------------------------------------- */

int http_front_start(const http_front_config *cfg, http_front **out, char *err, size_t errlen)
{
    http_front *f = calloc(1, sizeof *f);
    struct epoll_event ev;
    int fl;

    *out = NULL;
    if (!f || !(f->buf = malloc(cfg->head.max_head ? cfg->head.max_head : 1))) {
        snprintf(err, errlen, "out of memory");
        goto fail_alloc;
    }
    f->cfg = *cfg;
    f->listen_fd = cfg->listen_fd;
    f->wake = -1;
    pthread_mutex_init(&f->lock, NULL);
    fl = fcntl(f->listen_fd, F_GETFL);
    if (fl < 0 || fcntl(f->listen_fd, F_SETFL, fl | O_NONBLOCK) < 0) {
        snprintf(err, errlen, "cannot make the listening socket non-blocking: %s",
                 strerror(errno));
        goto fail_epoll;
    }
    f->ep = epoll_create1(EPOLL_CLOEXEC);
    if (f->ep < 0) {
        snprintf(err, errlen, "epoll_create1: %s", strerror(errno));
        goto fail_epoll;
    }
    f->wake = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    ev.events = EPOLLIN;
    ev.data.ptr = &f->wake;
    if (f->wake < 0 || epoll_ctl(f->ep, EPOLL_CTL_ADD, f->wake, &ev) != 0) {
        snprintf(err, errlen, "eventfd: %s", strerror(errno));
        goto fail_wake;
    }
    accept_resume(f);
    if (!f->listening) {
        snprintf(err, errlen, "epoll_ctl on the listening socket: %s", strerror(errno));
        goto fail_wake;
    }
    *out = f; /* before the thread runs: deliver() may look it up at once */
    if (pthread_create(&f->thread, NULL, front_main, f) != 0) {
        *out = NULL;
        snprintf(err, errlen, "cannot start the connection thread");
        goto fail_wake;
    }
    f->started = 1;
    return 0;

fail_wake:
    if (f->wake >= 0)
        close(f->wake);
    close(f->ep);
fail_epoll:
    pthread_mutex_destroy(&f->lock);
fail_alloc:
    close(cfg->listen_fd);
    if (f)
        free(f->buf);
    free(f);
    return -1;
}

void http_front_stop(http_front *f)
{
    uint64_t one = 1;
    if (!f || !f->started)
        return;
    __atomic_store_n(&f->stopping, 1, __ATOMIC_RELEASE);
    if (write(f->wake, &one, sizeof one) != (ssize_t)sizeof one)
        perror("glintd: waking the connection thread");
    pthread_join(f->thread, NULL);
    f->started = 0;
    while (oldest(f))
        conn_close(f, oldest(f));
    conn_reap(f);
    close(f->listen_fd);
    close(f->wake);
    close(f->ep);
}

void http_front_release(http_front *f, http_front_lease *lease)
{
    if (!lease)
        return;
    pthread_mutex_lock(&f->lock);
    if (lease->reserve)
        f->reserved--;
    else
        f->served--;
    lease->ip->served--;
    client_put(f, lease->ip);
    pthread_mutex_unlock(&f->lock);
    free(lease);
}

int http_front_lease_is_reserve(const http_front_lease *lease)
{
    return lease && lease->reserve;
}

int http_front_busy(http_front *f, const http_front_lease *lease)
{
    int busy;
    pthread_mutex_lock(&f->lock);
    busy = 4 * (unsigned long)f->served >= 3 * (unsigned long)f->cfg.max_connections ||
           (lease && 4 * (unsigned long)lease->ip->served >= 3 * (unsigned long)f->cfg.max_per_ip);
    pthread_mutex_unlock(&f->lock);
    return busy;
}

void http_front_free(http_front *f)
{
    if (!f)
        return;
    for (int b = 0; b < FRONT_IP_BUCKETS; b++)
        while (f->bucket[b]) {
            front_ip *ip = f->bucket[b];
            f->bucket[b] = ip->next;
            free(ip);
        }
    pthread_mutex_destroy(&f->lock);
    free(f->buf);
    free(f);
}
