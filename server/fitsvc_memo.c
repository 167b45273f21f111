/* fitsvc_memo.c: what a session's fits keep from one to the next
 * (method_memo, prep_fit_reusing): a few memos, one per session and fit
 * point, the least recently used making room.  A fit takes its memo out of
 * the table for its run and puts it back after, so no two fits use one at
 * once (a second fit of the same point meanwhile starts from an empty
 * one, and the later of the two to finish is kept).  Memory, for at most
 * FITSVC_MEMOS points: an hf3 memo's sums are 9 res doubles per chunk of
 * samples (at most 32 chunks: 147 KB at res 64); every memo keeps the
 * pattern's painted values, 12 bytes a sample up to 16 MiB (prep.c; 4.7
 * MB for 12 views of 256x256), its fit's buffer kept rather than freed. */
#include <stdio.h>
#include <string.h>

#include "fitsvc_int.h"

static fit_memo_slot *slot_of(fitsvc *f, const char *session, const char *key)
{
    for (lru_node *x = f->memo_lru.head; x; x = x->next) {
        fit_memo_slot *sl = lru_entry(x, fit_memo_slot, node);
        if (strcmp(sl->session, session) == 0 && strcmp(sl->key, key) == 0)
            return sl;
    }
    return NULL;
}

void fitsvc_memo_take(fitsvc *f, const char *session, const char *key, method_memo *mm)
{
    fit_memo_slot *sl;
    memset(mm, 0, sizeof *mm);
    pthread_mutex_lock(&f->lock);
    if ((sl = slot_of(f, session, key))) {
        *mm = sl->mm;
        lru_remove(&f->memo_lru, &sl->node);
        memset(sl, 0, sizeof *sl);
    }
    pthread_mutex_unlock(&f->lock);
}

void fitsvc_memo_put(fitsvc *f, const char *session, const char *key, method_memo *mm,
                     int reused, int chunks)
{
    method_memo old;
    fit_memo_slot *sl;

    memset(&old, 0, sizeof old);
    if (strlen(session) >= sizeof f->memos[0].session || strlen(key) >= sizeof f->memos[0].key) {
        method_memo_clear(mm);
        return;
    }
    pthread_mutex_lock(&f->lock);
    f->memo_chunks += (unsigned long long)(chunks > 0 ? chunks : 0);
    f->memo_reused += (unsigned long long)(reused > 0 ? reused : 0);
    if ((sl = slot_of(f, session, key))) { /* one put back meanwhile: this one replaces it */
        lru_touch(&f->memo_lru, &sl->node);
    } else if (f->memo_lru.n < FITSVC_MEMOS) { /* a free slot */
        for (int i = 0; i < FITSVC_MEMOS && !sl; i++)
            if (!f->memos[i].held)
                sl = &f->memos[i];
        sl->held = 1;
        lru_push(&f->memo_lru, &sl->node);
    } else { /* the least recently put back makes room */
        sl = lru_entry(lru_oldest(&f->memo_lru), fit_memo_slot, node);
        lru_touch(&f->memo_lru, &sl->node);
    }
    old = sl->mm;
    snprintf(sl->session, sizeof sl->session, "%s", session);
    snprintf(sl->key, sizeof sl->key, "%s", key);
    sl->mm = *mm;
    pthread_mutex_unlock(&f->lock);
    memset(mm, 0, sizeof *mm);
    method_memo_clear(&old);
}

void fitsvc_memo_close(fitsvc *f)
{
    for (int i = 0; i < FITSVC_MEMOS; i++)
        method_memo_clear(&f->memos[i].mm);
    memset(f->memos, 0, sizeof f->memos);
    memset(&f->memo_lru, 0, sizeof f->memo_lru);
}

void fitsvc_memo_metrics(fitsvc *f, FILE *o)
{
    unsigned long long chunks, reused;
    int held;
    unsigned long long values = 0;
    pthread_mutex_lock(&f->lock);
    chunks = f->memo_chunks;
    reused = f->memo_reused;
    held = (int)f->memo_lru.n;
    for (lru_node *x = f->memo_lru.head; x; x = x->next) {
        const fit_memo_slot *sl = lru_entry(x, fit_memo_slot, node);
        if (sl->mm.values)
            values += (unsigned long long)sl->mm.values_n * 3 * sizeof(float);
    }
    pthread_mutex_unlock(&f->lock);
    fprintf(o, "# HELP glintd_fit_stream_chunks_total Chunks of samples of the fits' passes, "
               "by whether a session's earlier fit served their sums (views not repainted) or "
               "they were summed.\n# TYPE glintd_fit_stream_chunks_total counter\n");
    fprintf(o, "glintd_fit_stream_chunks_total{from=\"memo\"} %llu\n", reused);
    fprintf(o, "glintd_fit_stream_chunks_total{from=\"summed\"} %llu\n", chunks - reused);
    fprintf(o, "# HELP glintd_fit_memos Sessions' fit memos held.\n"
               "# TYPE glintd_fit_memos gauge\nglintd_fit_memos %d\n", held);
    fprintf(o, "# HELP glintd_fit_memo_values_bytes Painted values the memos keep, so that "
               "a fit reads again only the views repainted since.\n"
               "# TYPE glintd_fit_memo_values_bytes gauge\nglintd_fit_memo_values_bytes %llu\n",
            values);
}
