/* Tests of glintd's session event streams (server/events.h), driven through
 * the transport-free core (events_stream_open / _next / _close) over a real
 * store: replay from a sequence number, live events, presence and its
 * names, what events_publish writes to the log, the ends of a stream
 * (shutdown, a client that hangs up, its token refused) and the limits on
 * open streams.  The bytes are parsed as a
 * server-sent-events client would. */
#include <pthread.h>
#include <stdatomic.h>
#include <sys/socket.h>
#include <unistd.h>

#include "check.h"
#include "clock.h"
#include "events.h"
#include "ids.h"
#include "store.h"

/* The longest wait for an event that must come: it only catches a hang (an
 * event that comes returns the wait at once), so it is generous enough for a
 * machine busy with other work, or memcheck.  Waits for what must NOT come
 * are short windows (0.3 s): a slow machine can only make them miss a
 * wrong event, never report one that is not there. */
#define MUST_S 30.0

/* ---- fixture: a store with a scene and two sessions, and the hub ------------------ */

typedef struct fixture {
    char dir[64];
    store *st;
    events *ev;
    char scene[33], session[33], other[33];
} fixture;

static int fx_session(fixture *f, char id[33])
{
    json_t *doc;
    int rc = glint_id_new(id, NULL);
    if (rc)
        return rc;
    doc = json_pack("{s:s}", "scene_id", f->scene);
    rc = store_session_put(f->st, id, doc, NULL);
    json_decref(doc);
    return rc;
}

static int fx_open(fixture *f)
{
    json_t *doc;
    int rc;
    snprintf(f->dir, sizeof f->dir, "/tmp/glint-events-XXXXXX");
    if (!mkdtemp(f->dir))
        return -1;
    if ((rc = store_open(f->dir, &f->st, NULL)) || (rc = glint_id_new(f->scene, NULL)))
        return rc;
    doc = json_pack("{s:s}", "id", f->scene);
    rc = store_scene_put(f->st, f->scene, doc, NULL);
    json_decref(doc);
    if (rc || (rc = fx_session(f, f->session)) || (rc = fx_session(f, f->other)))
        return rc;
    return events_open(f->st, &f->ev);
}

static void fx_close(fixture *f)
{
    char cmd[128];
    events_close(f->ev);
    store_close(f->st);
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", f->dir);
    if (system(cmd) != 0)
        fprintf(stderr, "  could not remove %s\n", f->dir);
}

/* n strokes on view 0 (OUT: *last, the last one's seq). */
static int add_strokes(fixture *f, const char *session, int n, int64_t *last)
{
    json_t *a = json_array();
    int64_t first;
    int rc;
    for (int i = 0; i < n; i++)
        json_array_append_new(a, json_pack("{s:i, s:f}", "i", i, "diameter", 0.5));
    rc = store_strokes_append(f->st, session, 0, a, "exr", 3, &first, last, NULL, NULL);
    json_decref(a);
    return rc;
}

/* ---- a client: the stream's bytes parsed into events ---------------------------- */

typedef struct reader {
    ev_stream *s;
    size_t chunk;              /* bytes asked for per call */
    char buf[1 << 16];
    size_t len;
    char first[64];            /* the first bytes of the stream */
    char block[4096];          /* the text of the last event */
    int retry, comments, unknown_lines;
    ssize_t end;               /* EVENTS_STREAM_END / _ERROR once seen */
} reader;

typedef struct sse {
    long long id;              /* 0: none */
    char type[32];
    json_t *data;
} sse;

static void reader_init(reader *r, ev_stream *s)
{
    memset(r, 0, sizeof *r);
    r->s = s;
    r->chunk = sizeof r->buf;
}

/* Read once more: 1 with bytes, 0 when none came before `until`, -1 at
 * the end of the stream. */
static int reader_fill(reader *r, double until)
{
    do {
        size_t room = sizeof r->buf - 1 - r->len;
        ssize_t n = events_stream_next(r->s, r->buf + r->len, room < r->chunk ? room : r->chunk);
        if (n > 0) {
            if (r->len < sizeof r->first - 1)
                memcpy(r->first + r->len, r->buf + r->len,
                       (size_t)n < sizeof r->first - 1 - r->len ? (size_t)n
                                                                : sizeof r->first - 1 - r->len);
            r->len += (size_t)n;
            r->buf[r->len] = '\0';
            return 1;
        }
        if (n < 0) {
            r->end = n;
            return -1;
        }
    } while (glint_now() < until);
    return 0;
}

/* The next event (preamble, comments and keep-alives are counted, not
 * returned): 1, 0 when none came within timeout_s, -1 at the end. */
static int next_event(reader *r, sse *out, double timeout_s)
{
    double until = glint_now() + timeout_s;
    memset(out, 0, sizeof *out);
    for (;;) {
        char *end = strstr(r->buf, "\n\n");
        if (end) {
            size_t n = (size_t)(end - r->buf) + 2;
            int has_event = 0;
            *end = '\0';
            snprintf(r->block, sizeof r->block, "%.4000s\n\n", r->buf);
            for (char *line = r->buf, *nl; line && *line; line = nl) {
                nl = strchr(line, '\n');
                if (nl)
                    *nl++ = '\0';
                if (strncmp(line, "id: ", 4) == 0)
                    out->id = strtoll(line + 4, NULL, 10);
                else if (strncmp(line, "event: ", 7) == 0) {
                    snprintf(out->type, sizeof out->type, "%s", line + 7);
                    has_event = 1;
                } else if (strncmp(line, "data: ", 6) == 0)
                    out->data = json_loads(line + 6, 0, NULL);
                else if (strncmp(line, "retry: ", 7) == 0)
                    r->retry = atoi(line + 7);
                else if (line[0] == ':')
                    r->comments++;
                else
                    r->unknown_lines++;
            }
            memmove(r->buf, r->buf + n, r->len - n + 1);
            r->len -= n;
            if (has_event)
                return 1;
            json_decref(out->data);
            memset(out, 0, sizeof *out);
            continue;
        }
        int rc = reader_fill(r, until);
        if (rc <= 0)
            return rc;
    }
}

/* The next event that is not presence (presence events are skipped). */
static int next_log_event(reader *r, sse *out, double timeout_s)
{
    double until = glint_now() + timeout_s;
    int rc;
    while ((rc = next_event(r, out, until - glint_now())) == 1 &&
           strcmp(out->type, "presence") == 0)
        json_decref(out->data);
    return rc;
}

/* Read presence events until one lists `count` clients (OUT: *out's data
 * kept; the caller decrefs).  1, or 0 / -1 as next_event. */
static int until_presence(reader *r, int count, sse *out, double timeout_s)
{
    double until = glint_now() + timeout_s;
    int rc;
    while ((rc = next_event(r, out, until - glint_now())) == 1) {
        if (strcmp(out->type, "presence") == 0 &&
            json_integer_value(json_object_get(out->data, "count")) == count)
            return 1;
        json_decref(out->data);
    }
    return rc;
}

static int has_client(const json_t *presence, const char *name)
{
    size_t i;
    json_t *c;
    json_array_foreach(json_object_get(presence, "clients"), i, c)
        if (strcmp(json_string_value(json_object_get(c, "name")), name) == 0)
            return 1;
    return 0;
}

/* ---- replay -------------------------------------------------------------------------- */

TEST(replay_after_a_sequence_number)
{
    fixture f;
    ev_stream *s;
    reader r;
    sse e;
    int64_t last;
    json_t *data = json_pack("{s:s}", "material_id", "m1");
    static const char *const types[] = {"stroke", "stroke", "stroke", "fit", "painting"};
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(add_strokes(&f, f.session, 3, &last));
    ASSERT_OK(store_event_append(f.st, f.session, "fit", -1, data, NULL, NULL));
    ASSERT_OK(store_painting_put(f.st, f.session, 1, "exr", 3, NULL, &last, NULL));
    ASSERT_EQ(last, 5);

    ASSERT_OK(events_stream_open(f.ev, f.session, 2, "ann", -1, NULL, &s, NULL));
    reader_init(&r, s);
    for (int seq = 3; seq <= 5; seq++) {
        ASSERT_EQ(next_event(&r, &e, MUST_S), 1);
        ASSERT_EQ(e.id, seq);
        ASSERT_MSG(strcmp(e.type, types[seq - 1]) == 0, "event %d is %s", seq, e.type);
        ASSERT_EQ(json_integer_value(json_object_get(e.data, "seq")), seq);
        ASSERT(strcmp(json_string_value(json_object_get(e.data, "type")), e.type) == 0);
        if (seq == 4)
            ASSERT(json_equal(json_object_get(e.data, "data"), data));
        json_decref(e.data);
    }
    /* the wire: the preamble first, one event as three lines */
    ASSERT(strncmp(r.first, "retry: 2000\n", 12) == 0);
    ASSERT_EQ(r.retry, 2000);
    {
        static const char head[] = "id: 5\nevent: painting\ndata: {";
        ASSERT_MSG(strncmp(r.block, head, strlen(head)) == 0, "block: %s", r.block);
        ASSERT(strchr(r.block + strlen(head), '\n') == r.block + strlen(r.block) - 2);
    }
    /* then who is here, without an id */
    ASSERT_EQ(next_event(&r, &e, MUST_S), 1);
    ASSERT(strcmp(e.type, "presence") == 0);
    ASSERT_EQ(e.id, 0);
    ASSERT_EQ(json_integer_value(json_object_get(e.data, "count")), 1);
    json_decref(e.data);
    /* and nothing else */
    ASSERT_EQ(next_event(&r, &e, 0.3), 0);
    ASSERT_EQ(r.unknown_lines, 0);
    events_stream_close(s);

    /* from the start, in small pieces; beyond the end: nothing */
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, NULL, -1, NULL, &s, NULL));
    reader_init(&r, s);
    r.chunk = 7;
    for (int seq = 1; seq <= 5; seq++) {
        ASSERT_EQ(next_log_event(&r, &e, MUST_S), 1);
        ASSERT_EQ(e.id, seq);
        json_decref(e.data);
    }
    events_stream_close(s);
    ASSERT_OK(events_stream_open(f.ev, f.session, 99, NULL, -1, NULL, &s, NULL));
    reader_init(&r, s);
    ASSERT_EQ(next_log_event(&r, &e, 0.3), 0);
    events_stream_close(s);
    json_decref(data);
    fx_close(&f);
}

TEST(replay_longer_than_one_batch)
{
    fixture f;
    ev_stream *s;
    reader r;
    sse e;
    int64_t last;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(add_strokes(&f, f.session, 150, &last));
    ASSERT_OK(add_strokes(&f, f.session, 50, &last));
    ASSERT_EQ(last, 200);
    ASSERT_OK(events_stream_open(f.ev, f.session, 10, NULL, -1, NULL, &s, NULL));
    reader_init(&r, s);
    for (int seq = 11; seq <= 200; seq++) {
        ASSERT_EQ(next_log_event(&r, &e, MUST_S), 1);
        ASSERT_EQ(e.id, seq);
        ASSERT_EQ(json_integer_value(json_object_get(json_object_get(e.data, "data"), "i")),
                  seq <= 150 ? seq - 1 : seq - 151);
        json_decref(e.data);
    }
    ASSERT_EQ(next_log_event(&r, &e, 0.3), 0);
    events_stream_close(s);
    fx_close(&f);
}

/* ---- live ---------------------------------------------------------------------------- */

typedef struct live {
    reader r;
    int want;                  /* events to read */
    long long ids[8];
    atomic_int got;
} live;

static void *live_main(void *arg)
{
    live *l = arg;
    sse e;
    int got = 0;
    while (got < l->want && next_log_event(&l->r, &e, MUST_S) == 1) {
        l->ids[got] = e.id;
        atomic_store(&l->got, ++got);
        json_decref(e.data);
    }
    return NULL;
}

/* 0 once both readers have n events, -1 after MUST_S. */
static int live_wait(live *a, live *b, int n)
{
    for (double end = glint_now() + MUST_S; glint_now() < end; usleep(1000))
        if (atomic_load(&a->got) >= n && atomic_load(&b->got) >= n)
            return 0;
    return -1;
}

/* Each event reaches both streams of the session, in order, while they wait
 * live (each is published once both have read the one before), through
 * either call (events_publish, events_notify); the other session's stream
 * sees none of it.  (How soon it arrives, woken rather than found by the
 * next EVENTS_POLL_MS poll, is a matter of delay only: a poll also finds
 * it.  The delay is measured end to end, a stroke from one browser to
 * another, by tests/bench/bench_studio.mjs.) */
TEST(live_events_wake_every_stream_of_the_session)
{
    fixture f;
    ev_stream *a, *b, *o;
    static live la, lb;
    reader ro;
    pthread_t ta, tb;
    int64_t last;
    sse e;
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "a", -1, NULL, &a, NULL));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "b", -1, NULL, &b, NULL));
    ASSERT_OK(events_stream_open(f.ev, f.other, 0, "o", -1, NULL, &o, NULL));
    memset(&la, 0, sizeof la);
    memset(&lb, 0, sizeof lb);
    reader_init(&la.r, a);
    reader_init(&lb.r, b);
    reader_init(&ro, o);
    la.want = lb.want = 5;
    ASSERT_EQ(pthread_create(&ta, NULL, live_main, &la), 0);
    ASSERT_EQ(pthread_create(&tb, NULL, live_main, &lb), 0);
    for (int i = 0; i < 5; i++) {
        ASSERT_OK(live_wait(&la, &lb, i));
        ASSERT_OK(add_strokes(&f, f.session, 1, &last));
        ASSERT_EQ(last, i + 1);
        if (i % 2)
            events_notify(f.ev, f.session); /* what the strokes handler does */
        else
            events_publish(f.ev, f.session, "stroke", json_object());
    }
    pthread_join(ta, NULL);
    pthread_join(tb, NULL);
    ASSERT_EQ(atomic_load(&la.got), 5);
    ASSERT_EQ(atomic_load(&lb.got), 5);
    for (int i = 0; i < 5; i++) {
        ASSERT_EQ(la.ids[i], i + 1);
        ASSERT_EQ(lb.ids[i], i + 1);
    }
    /* the other session's stream saw none of it */
    ASSERT_EQ(next_log_event(&ro, &e, 0.3), 0);
    events_stream_close(a);
    events_stream_close(b);
    events_stream_close(o);
    fx_close(&f);
}

/* ---- presence ------------------------------------------------------------------------ */

TEST(presence_when_listeners_come_and_go)
{
    fixture f;
    ev_stream *a, *b, *c, *d, *x, *o;
    reader ra, rb, ro;
    sse e;
    char longname[101], utf8[70], expect[70];
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "Ann\x01\tie\x7f", -1, NULL, &a, NULL));
    ASSERT_OK(events_stream_open(f.ev, f.other, 0, "elsewhere", -1, NULL, &o, NULL));
    reader_init(&ra, a);
    reader_init(&ro, o);
    ASSERT_EQ(until_presence(&ra, 1, &e, MUST_S), 1);
    {
        json_t *c0 = json_array_get(json_object_get(e.data, "clients"), 0);
        ASSERT(strcmp(json_string_value(json_object_get(c0, "name")), "Annie") == 0);
        ASSERT_EQ(strlen(json_string_value(json_object_get(c0, "id"))), 16);
        ASSERT(strcmp(json_string_value(json_object_get(e.data, "type")), "presence") == 0);
    }
    json_decref(e.data);
    /* joining: everyone hears of it, the newcomer sees everyone */
    memset(longname, 'x', 100);
    longname[100] = '\0';
    memset(utf8, 'a', 63);
    strcpy(utf8 + 63, "\xc3\xa9"); /* 65 bytes: the cut falls inside the last character */
    memcpy(expect, utf8, 63);
    expect[63] = '\0';
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, NULL, -1, NULL, &b, NULL));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, longname, -1, NULL, &c, NULL));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, utf8, -1, NULL, &d, NULL));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "\x01\x02\x1b", -1, NULL, &x, NULL));
    ASSERT_EQ(until_presence(&ra, 5, &e, MUST_S), 1);
    ASSERT(has_client(e.data, "Annie"));
    ASSERT(has_client(e.data, "anonymous")); /* no name */
    longname[EVENTS_NAME_MAX] = '\0';
    ASSERT(has_client(e.data, longname));  /* 64 bytes of it */
    ASSERT(has_client(e.data, expect));    /* no broken character */
    {
        size_t i, anonymous = 0;
        json_t *cl;
        json_array_foreach(json_object_get(e.data, "clients"), i, cl) {
            anonymous += strcmp(json_string_value(json_object_get(cl, "name")), "anonymous") == 0;
            ASSERT(strlen(json_string_value(json_object_get(cl, "name"))) <= EVENTS_NAME_MAX);
        }
        ASSERT_EQ(anonymous, 2); /* only control characters: anonymous too */
    }
    json_decref(e.data);
    reader_init(&rb, b);
    ASSERT_EQ(until_presence(&rb, 5, &e, MUST_S), 1);
    ASSERT(has_client(e.data, "Annie"));
    json_decref(e.data);
    /* leaving */
    events_stream_close(c);
    events_stream_close(d);
    events_stream_close(x);
    ASSERT_EQ(until_presence(&ra, 2, &e, MUST_S), 1);
    ASSERT(has_client(e.data, "Annie") && has_client(e.data, "anonymous"));
    json_decref(e.data);
    ASSERT_EQ(until_presence(&rb, 2, &e, MUST_S), 1);
    json_decref(e.data);
    events_stream_close(b);
    ASSERT_EQ(until_presence(&ra, 1, &e, MUST_S), 1);
    ASSERT(!has_client(e.data, "anonymous"));
    json_decref(e.data);
    /* the other session's stream only ever saw itself */
    while (next_event(&ro, &e, 0.3) == 1) {
        ASSERT(strcmp(e.type, "presence") == 0);
        ASSERT_EQ(json_integer_value(json_object_get(e.data, "count")), 1);
        ASSERT(has_client(e.data, "elsewhere"));
        json_decref(e.data);
    }
    events_stream_close(a);
    events_stream_close(o);
    events_stream_close(NULL);
    fx_close(&f);
}

/* ---- publish ------------------------------------------------------------------------- */

static int64_t last_seq(fixture *f, const char *session)
{
    json_t *arr;
    int64_t last = -1;
    if (store_events_since(f->st, session, 0, 1, &arr, &last, NULL) == 0)
        json_decref(arr);
    return last;
}

TEST(publish_appends_fit_to_the_log_and_only_wakes_for_strokes)
{
    fixture f;
    ev_stream *s;
    reader r;
    sse e;
    int64_t last;
    json_t *arr;
    char unknown[33];
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(add_strokes(&f, f.session, 2, &last));
    ASSERT_OK(events_stream_open(f.ev, f.session, 2, "r", -1, NULL, &s, NULL));
    reader_init(&r, s);
    ASSERT_EQ(until_presence(&r, 1, &e, MUST_S), 1);
    json_decref(e.data);

    events_publish(f.ev, f.session, "fit", json_pack("{s:s}", "material_id", "m7"));
    ASSERT_EQ(last_seq(&f, f.session), 3);
    ASSERT_OK(store_events_since(f.st, f.session, 2, 0, &arr, NULL, NULL));
    ASSERT_EQ(json_array_size(arr), 1);
    ASSERT(strcmp(json_string_value(json_object_get(json_array_get(arr, 0), "type")), "fit") == 0);
    ASSERT(json_object_get(json_array_get(arr, 0), "view") == NULL);
    json_decref(arr);
    ASSERT_EQ(next_log_event(&r, &e, MUST_S), 1);
    ASSERT_EQ(e.id, 3);
    ASSERT(strcmp(e.type, "fit") == 0);
    ASSERT(strcmp(json_string_value(json_object_get(json_object_get(e.data, "data"),
                                                    "material_id")), "m7") == 0);
    json_decref(e.data);

    /* "stroke" and "painting" are in the log already: publishing only wakes */
    events_publish(f.ev, f.session, "stroke", json_pack("{s:i}", "i", 1));
    events_publish(f.ev, f.session, "painting", json_pack("{s:i}", "view", 0));
    ASSERT_EQ(last_seq(&f, f.session), 3);
    ASSERT_EQ(next_log_event(&r, &e, 0.3), 0);
    /* reserved, malformed, unknown session, no session: nothing is logged */
    events_publish(f.ev, f.session, "presence", json_object());
    events_publish(f.ev, f.session, "note", json_array());
    events_publish(f.ev, f.session, "note", NULL);
    ASSERT_OK(glint_id_new(unknown, NULL));
    events_publish(f.ev, unknown, "fit", json_object());
    events_publish(f.ev, NULL, "fit", json_object());
    events_publish(f.ev, f.session, NULL, json_object());
    events_publish(NULL, f.session, "fit", json_object());
    ASSERT_EQ(last_seq(&f, f.session), 3);
    ASSERT_EQ(next_log_event(&r, &e, 0.3), 0);
    /* any other type takes the next number */
    events_publish(f.ev, f.session, "note", json_pack("{s:s}", "text", "hello"));
    ASSERT_EQ(last_seq(&f, f.session), 4);
    ASSERT_EQ(next_log_event(&r, &e, MUST_S), 1);
    ASSERT_EQ(e.id, 4);
    ASSERT(strcmp(e.type, "note") == 0);
    json_decref(e.data);
    events_stream_close(s);
    fx_close(&f);
}

/* ---- the end of a stream ------------------------------------------------------------- */

typedef struct ender {
    reader r;
    atomic_int events;         /* read so far */
    ssize_t end;
} ender;

/* Reads until the stream ends; a wait of MUST_S without it ends with
 * x->end 0, which the test reports. */
static void *ender_main(void *arg)
{
    ender *x = arg;
    sse e;
    while (next_event(&x->r, &e, MUST_S) == 1) {
        json_decref(e.data);
        atomic_fetch_add(&x->events, 1);
    }
    x->end = x->r.end;
    return NULL;
}

TEST(shutdown_ends_streams_promptly)
{
    fixture f;
    ev_stream *a, *b, *late;
    static ender xa, xb;
    pthread_t ta, tb;
    char buf[256];
    ASSERT_OK(fx_open(&f));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "a", -1, NULL, &a, NULL));
    ASSERT_OK(events_stream_open(f.ev, f.other, 0, "b", -1, NULL, &b, NULL));
    reader_init(&xa.r, a);
    reader_init(&xb.r, b);
    ASSERT_EQ(pthread_create(&ta, NULL, ender_main, &xa), 0);
    ASSERT_EQ(pthread_create(&tb, NULL, ender_main, &xb), 0);
    /* both have read their presence and wait for more */
    for (double end = glint_now() + MUST_S;
         (atomic_load(&xa.events) < 1 || atomic_load(&xb.events) < 1) && glint_now() < end;)
        usleep(1000);
    ASSERT(atomic_load(&xa.events) >= 1 && atomic_load(&xb.events) >= 1);
    events_shutdown(f.ev);
    pthread_join(ta, NULL);
    pthread_join(tb, NULL);
    ASSERT_EQ(xa.end, EVENTS_STREAM_END);
    ASSERT_EQ(xb.end, EVENTS_STREAM_END);
    /* a stream opened afterwards ends at once: its first call says so */
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "late", -1, NULL, &late, NULL));
    ASSERT_EQ(events_stream_next(late, buf, sizeof buf), EVENTS_STREAM_END);
    events_stream_close(late);
    events_stream_close(a);
    events_stream_close(b);
    fx_close(&f);
}

TEST(stream_ends_when_the_client_hangs_up)
{
    fixture f;
    ev_stream *s;
    reader r;
    sse e;
    int sv[2];
    ASSERT_OK(fx_open(&f));
    ASSERT_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "gone", sv[0], NULL, &s, NULL));
    reader_init(&r, s);
    ASSERT_EQ(until_presence(&r, 1, &e, MUST_S), 1);
    json_decref(e.data);
    /* a client that sends something is still there */
    ASSERT_EQ(write(sv[1], "x", 1), 1);
    ASSERT_EQ(next_event(&r, &e, 0.3), 0);
    ASSERT_EQ(r.end, 0);
    close(sv[1]);
    ASSERT_EQ(next_event(&r, &e, MUST_S), -1);
    ASSERT_EQ(r.end, EVENTS_STREAM_END);
    events_stream_close(s);
    close(sv[0]);
    fx_close(&f);
}

/* ---- streams of a token, and the limits ------------------------------------------------ */

/* events_check_fn: *ctx (an atomic_int) says whether the token is refused. */
static int check_flag(void *ctx, const char *session, const char *token, time_t *expires)
{
    (void)session;
    *expires = 0;
    return strcmp(token, "the-token") != 0 || atomic_load((atomic_int *)ctx) ? GLINT_EDENIED : 0;
}

TEST(a_token_stream_sends_nothing_once_its_token_is_refused)
{
    fixture f;
    ev_stream *s, *key;
    static atomic_int refused;
    events_access acc = {"the-token", check_flag, &refused, NULL};
    reader r, rk;
    sse e;
    int64_t last;
    ASSERT_OK(fx_open(&f));
    atomic_store(&refused, 0);
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "tok", -1, &acc, &s, NULL));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "key", -1, NULL, &key, NULL));
    reader_init(&r, s);
    reader_init(&rk, key);
    ASSERT_EQ(until_presence(&r, 2, &e, MUST_S), 1);
    json_decref(e.data);
    ASSERT_EQ(until_presence(&rk, 2, &e, MUST_S), 1);
    json_decref(e.data);
    /* while the tokens change, the token's stream sends nothing, even what
     * was appended meanwhile; once refused, it ends without it */
    events_revoke_begin(f.ev, f.session);
    ASSERT_OK(add_strokes(&f, f.session, 2, &last));
    events_notify(f.ev, f.session);
    ASSERT_EQ(next_log_event(&r, &e, 0.3), 0);
    atomic_store(&refused, 1);
    events_revoke_end(f.ev, f.session);
    ASSERT_EQ(next_log_event(&r, &e, MUST_S), -1);
    ASSERT_EQ(r.end, EVENTS_STREAM_END);
    ASSERT(strstr(r.buf, "event: stroke") == NULL);
    /* a stream opened without a token goes on, and has the strokes */
    ASSERT_EQ(next_log_event(&rk, &e, MUST_S), 1);
    ASSERT(strcmp(e.type, "stroke") == 0 && e.id == last - 1);
    json_decref(e.data);
    events_stream_close(s);
    /* a token refused before its stream's first byte: nothing at all */
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "late", -1, &acc, &s, NULL));
    reader_init(&r, s);
    ASSERT_EQ(next_event(&r, &e, MUST_S), -1);
    ASSERT_EQ(r.len, 0);
    events_stream_close(s);
    events_stream_close(key);
    fx_close(&f);
}

TEST(streams_per_session_and_per_client_are_limited)
{
    fixture f;
    ev_stream *a, *b, *c, *x = NULL;
    events_access ca = {NULL, NULL, NULL, "192.0.2.1"}, cb = ca, cc = ca;
    glint_err err;
    cb.client = "192.0.2.2";
    cc.client = "192.0.2.3";
    ASSERT_OK(fx_open(&f));
    events_set_limits(f.ev, 2, 1);
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "a", -1, &ca, &a, NULL));
    ASSERT_EQ(events_stream_open(f.ev, f.other, 0, "a2", -1, &ca, &x, &err), GLINT_EBUSY);
    ASSERT(x == NULL && strcmp(err.kind, "too-many-streams") == 0);
    ASSERT(strstr(err.msg, "192.0.2.1") && strstr(err.msg, "--max-streams-per-client 1"));
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "b", -1, &cb, &b, NULL));
    ASSERT_EQ(events_stream_open(f.ev, f.session, 0, "c", -1, &cc, &x, &err), GLINT_EBUSY);
    ASSERT(strstr(err.msg, f.session) && strstr(err.msg, "--max-streams-per-session 2"));
    /* another session has room; a closed stream makes room */
    ASSERT_OK(events_stream_open(f.ev, f.other, 0, "c", -1, &cc, &c, NULL));
    events_stream_close(c);
    events_stream_close(a);
    ASSERT_OK(events_stream_open(f.ev, f.session, 0, "a", -1, &ca, &a, NULL));
    events_stream_close(a);
    events_stream_close(b);
    fx_close(&f);
}

TEST_LIST{
    TEST_ENTRY(replay_after_a_sequence_number),
    TEST_ENTRY(replay_longer_than_one_batch),
    TEST_ENTRY(live_events_wake_every_stream_of_the_session),
    TEST_ENTRY(presence_when_listeners_come_and_go),
    TEST_ENTRY(publish_appends_fit_to_the_log_and_only_wakes_for_strokes),
    TEST_ENTRY(shutdown_ends_streams_promptly),
    TEST_ENTRY(stream_ends_when_the_client_hangs_up),
    TEST_ENTRY(a_token_stream_sends_nothing_once_its_token_is_refused),
    TEST_ENTRY(streams_per_session_and_per_client_are_limited),
};

TEST_MAIN()
