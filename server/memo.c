/* memo.c: decoded paintings and material documents (memo.h). */
#include "memo.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "lru.h"

typedef struct pentry {
    char session[33];
    int view;
    long long version;
    img im;
    int refs;          /* the list's own (while listed) + pins */
    int listed;
    lru_node lru;
} pentry;

struct memo_painting {
    pentry e;          /* a handle is the entry itself */
};

typedef struct dentry {
    char id[33];
    memo_doc d;
    lru_node lru;
} dentry;

struct memo {
    pthread_mutex_t lock;
    lru_list paintings;
    size_t im_bytes, im_budget;
    unsigned long long im_hits, im_misses;
    lru_list docs;
    size_t doc_bytes, doc_budget;
    unsigned long long doc_hits, doc_misses;
};

static size_t img_bytes(const img *im)
{
    return (size_t)im->width * im->height * im->channels * sizeof(float);
}

int memo_open(size_t painting_budget, size_t doc_budget, memo **out, glint_err *err)
{
    memo *m = calloc(1, sizeof *m);
    *out = NULL;
    if (!m)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    pthread_mutex_init(&m->lock, NULL);
    m->im_budget = painting_budget;
    m->doc_budget = doc_budget;
    *out = m;
    return 0;
}

/* Drop one reference (lock held). */
static void punref(pentry *e)
{
    if (--e->refs == 0) {
        img_free(&e->im);
        free(e);
    }
}

static void punlist(memo *m, pentry *e)
{
    lru_remove(&m->paintings, &e->lru);
    e->listed = 0;
    m->im_bytes -= img_bytes(&e->im);
    punref(e);
}

/* List e (one reference for the list), replacing the same view's older
 * image, then keep the budget (lock held).  0, or -1 when a newer version
 * is listed already. */
static int pinsert(memo *m, pentry *e)
{
    for (lru_node *n = m->paintings.head; n;) {
        pentry *q = lru_entry(n, pentry, lru);
        n = n->next;
        if (q->view == e->view && strcmp(q->session, e->session) == 0) {
            if (q->version >= e->version)
                return -1;
            punlist(m, q);
        }
    }
    lru_push(&m->paintings, &e->lru);
    e->listed = 1;
    e->refs++;
    m->im_bytes += img_bytes(&e->im);
    while (m->im_bytes > m->im_budget && m->paintings.n > 1)
        punlist(m, lru_entry(lru_oldest(&m->paintings), pentry, lru));
    return 0;
}

int memo_painting_put(memo *m, const char *session, int view, long long version, img *im,
                      memo_painting **out)
{
    pentry *e;
    *out = NULL;
    if (!im->px || img_bytes(im) > m->im_budget)
        return GLINT_ETOOBIG;
    e = calloc(1, sizeof(memo_painting));
    if (!e)
        return GLINT_ENOMEM;
    snprintf(e->session, sizeof e->session, "%s", session);
    e->view = view;
    e->version = version;
    e->im = *im;
    e->refs = 1; /* the caller's pin */
    memset(im, 0, sizeof *im);
    pthread_mutex_lock(&m->lock);
    pinsert(m, e); /* when a newer one is listed, the caller's pin is all */
    pthread_mutex_unlock(&m->lock);
    *out = (memo_painting *)e;
    return 0;
}

void memo_painting_offer(memo *m, const char *session, int view, long long version,
                         const img *im)
{
    img copy;
    memo_painting *h;
    if (!m || !session || !im || !im->px || img_bytes(im) > m->im_budget ||
        img_alloc(&copy, im->width, im->height, im->channels, NULL))
        return;
    memcpy(copy.px, im->px, img_bytes(im));
    if (memo_painting_put(m, session, view, version, &copy, &h) == 0)
        memo_painting_release(m, h);
    img_free(&copy);
}

int memo_painting_get(memo *m, const char *session, int view, long long version,
                      memo_painting **out)
{
    int rc = GLINT_ENOTFOUND;
    *out = NULL;
    pthread_mutex_lock(&m->lock);
    for (lru_node *n = m->paintings.head; n; n = n->next) {
        pentry *q = lru_entry(n, pentry, lru);
        if (q->view == view && q->version == version && strcmp(q->session, session) == 0) {
            q->refs++;
            lru_touch(&m->paintings, n);
            *out = (memo_painting *)q;
            rc = 0;
            break;
        }
    }
    if (rc == 0)
        m->im_hits++;
    else
        m->im_misses++;
    pthread_mutex_unlock(&m->lock);
    return rc;
}

const img *memo_painting_img(const memo_painting *p)
{
    return &p->e.im;
}

void memo_painting_release(memo *m, memo_painting *p)
{
    if (!p)
        return;
    pthread_mutex_lock(&m->lock);
    punref(&p->e);
    pthread_mutex_unlock(&m->lock);
}

static void dfree(dentry *e)
{
    free(e->d.text);
    free(e);
}

void memo_doc_put(memo *m, const char *id, const char *session, const char *scene,
                  const char *text, size_t len)
{
    dentry *e;
    if (!m || !id || !text || len + sizeof *e > m->doc_budget)
        return;
    e = calloc(1, sizeof *e);
    if (!e || !(e->d.text = malloc(len + 1))) {
        free(e);
        return;
    }
    memcpy(e->d.text, text, len);
    e->d.text[len] = '\0';
    e->d.len = len;
    snprintf(e->id, sizeof e->id, "%s", id);
    snprintf(e->d.session, sizeof e->d.session, "%s", session ? session : "");
    snprintf(e->d.scene, sizeof e->d.scene, "%s", scene ? scene : "");
    pthread_mutex_lock(&m->lock);
    for (lru_node *n = m->docs.head; n; n = n->next)
        if (strcmp(lru_entry(n, dentry, lru)->id, id) == 0) {
            pthread_mutex_unlock(&m->lock);
            dfree(e);
            return;
        }
    lru_push(&m->docs, &e->lru);
    m->doc_bytes += len + sizeof *e;
    while (m->doc_bytes > m->doc_budget) {
        dentry *old = lru_entry(lru_oldest(&m->docs), dentry, lru);
        lru_remove(&m->docs, &old->lru);
        m->doc_bytes -= old->d.len + sizeof *old;
        dfree(old);
    }
    pthread_mutex_unlock(&m->lock);
}

int memo_doc_get(memo *m, const char *id, memo_doc *out)
{
    int rc = GLINT_ENOTFOUND;
    memset(out, 0, sizeof *out);
    pthread_mutex_lock(&m->lock);
    for (lru_node *n = m->docs.head; n; n = n->next) {
        dentry *q = lru_entry(n, dentry, lru);
        if (strcmp(q->id, id) != 0)
            continue;
        *out = q->d;
        out->text = malloc(q->d.len + 1);
        if (!out->text) {
            rc = GLINT_ENOMEM;
            break;
        }
        memcpy(out->text, q->d.text, q->d.len + 1);
        lru_touch(&m->docs, n);
        rc = 0;
        break;
    }
    if (rc == 0)
        m->doc_hits++;
    else
        m->doc_misses++;
    pthread_mutex_unlock(&m->lock);
    return rc;
}

void memo_close(memo *m)
{
    if (!m)
        return;
    while (m->paintings.head) {
        pentry *e = lru_entry(m->paintings.head, pentry, lru);
        lru_remove(&m->paintings, &e->lru);
        img_free(&e->im);
        free(e);
    }
    while (m->docs.head) {
        dentry *e = lru_entry(m->docs.head, dentry, lru);
        lru_remove(&m->docs, &e->lru);
        dfree(e);
    }
    pthread_mutex_destroy(&m->lock);
    free(m);
}

void memo_metrics(memo *m, FILE *o)
{
    unsigned long long ih, im, dh, dm;
    size_t ib;
    pthread_mutex_lock(&m->lock);
    ih = m->im_hits;
    im = m->im_misses;
    ib = m->im_bytes;
    dh = m->doc_hits;
    dm = m->doc_misses;
    pthread_mutex_unlock(&m->lock);
    fprintf(o, "# HELP glintd_painting_cache_total Decoded paintings found in memory or not.\n"
               "# TYPE glintd_painting_cache_total counter\n");
    fprintf(o, "glintd_painting_cache_total{outcome=\"hit\"} %llu\n", ih);
    fprintf(o, "glintd_painting_cache_total{outcome=\"miss\"} %llu\n", im);
    fprintf(o, "# HELP glintd_painting_cache_bytes Bytes of decoded paintings held.\n"
               "# TYPE glintd_painting_cache_bytes gauge\nglintd_painting_cache_bytes %zu\n",
            ib);
    fprintf(o, "# HELP glintd_material_doc_cache_total Material documents served from memory "
               "or read from the store.\n# TYPE glintd_material_doc_cache_total counter\n");
    fprintf(o, "glintd_material_doc_cache_total{outcome=\"hit\"} %llu\n", dh);
    fprintf(o, "glintd_material_doc_cache_total{outcome=\"miss\"} %llu\n", dm);
}
