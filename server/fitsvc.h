/* fitsvc.h: fits as a service: the precomputation cache and fit jobs.
 *
 * Precomputations (core fit_prep: samples, design, decomposition, operator)
 * are keyed by the content hash of everything they depend on (pcache.h),
 * built lazily on first use, shared by every session that uses the same key,
 * computed once even when many requests ask at the same moment (single
 * flight), kept in memory under a byte budget (least recently used evicted)
 * and on disk (data_dir/cache, checksummed: a corrupt file is rebuilt).
 * A fit whose precomputation is cached runs at once in the request; one
 * that must build it runs as a job with progress (jobs can be polled or
 * streamed). */
#ifndef GLINTD_FITSVC_H
#define GLINTD_FITSVC_H

#include <stddef.h>

#include "err.h"

typedef struct fitsvc fitsvc;

int fitsvc_open(const char *cache_dir, size_t budget_bytes, int threads, fitsvc **out,
                glint_err *err);
void fitsvc_close(fitsvc *f);

/* Counters for /metrics. */
typedef struct fitsvc_stats {
    unsigned long long hits, misses, builds, evictions;
    size_t bytes, entries;
    int jobs_queued, jobs_running;
    unsigned long long jobs_done, jobs_failed;
} fitsvc_stats;
void fitsvc_stats_get(fitsvc *f, fitsvc_stats *out);

#endif
