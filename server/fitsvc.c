/* fitsvc.c: fits as a service (fitsvc.h): its life cycle, the scenes
 * through the cache, the material documents and the metrics.  A session's
 * fits are fitsvc_session.c (their tasks fitsvc_task.c), a G-buffer set's
 * fitsvc_gbuf.c; both record their material through fitsvc_record.c. */
#include "fitsvc.h"
#include "fitsvc_int.h"

#include <malloc.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ids.h"
#include "json_text.h"
#include "scenes.h"
#include "store.h"


/* ---- scenes ----------------------------------------------------------------------- */

static int src_load(void *cls, const char *id, const scene **out, glint_err *err)
{
    return scenes_load(cls, id, out, err);
}

static void src_unload(void *cls, const scene *sc)
{
    (void)cls;
    scenes_unload(sc);
}

int fitsvc_scene(fitsvc *f, const char *scene_id, cache_entry **out, glint_err *err)
{
    prep_scene_source src = {src_load, src_unload, f->st};
    *out = NULL;
    if (scene_id && !scene_id[0]) { /* a material fitted from a G-buffer set */
        glint_err_set(err, GLINT_EUNSUPPORTED,
                      "this material was fitted from uploaded G-buffers (a G-buffer set): it "
                      "has no scene or mesh, which this needs; use a material fitted through a "
                      "session on a scene");
        return glint_err_kind(err, "no-scene");
    }
    if (!glint_id_valid(scene_id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no scene %.40s", scene_id ? scene_id : "");
    return prep_scene_acquire(f->cache, scene_id, &src, out, err);
}

/* ---- materials ------------------------------------------------------------------------ */

int fitsvc_material_doc(fitsvc *f, const char *id, memo_doc *out, glint_err *err)
{
    json_t *j = NULL;
    const char *sid, *scid, *set = "";
    int rc;

    memset(out, 0, sizeof *out);
    if (!glint_id_valid(id))
        return glint_err_set(err, GLINT_ENOTFOUND, "no material %.40s", id ? id : "");
    if (memo_doc_get(f->memo, id, out) == 0)
        return 0;
    if ((rc = store_material_get(f->st, id, &j, err)))
        return rc == GLINT_ENOTFOUND ? glint_err_set(err, rc, "no material %s", id) : rc;
    sid = json_string_value(json_object_get(j, "session_id"));
    scid = json_string_value(json_object_get(j, "scene_id"));
    if (!sid && !scid && json_is_string(json_object_get(j, "gbuffer_set_id"))) {
        sid = scid = ""; /* fitted from a G-buffer set (fitsvc_gbuf.c): no session, no scene */
        set = json_string_value(json_object_get(j, "gbuffer_set_id"));
    }
    if (!sid || !scid) {
        json_decref(j);
        return glint_err_set(err, GLINT_EINTERNAL, "material %s names no session or scene", id);
    }
    if (f->links) /* the links of today, whatever the record was stored with */
        json_object_set_new(j, "links", f->links(id, sid, scid, set));
    snprintf(out->session, sizeof out->session, "%s", sid);
    snprintf(out->scene, sizeof out->scene, "%s", scid);
    out->text = json_text(j, 0);
    json_decref(j);
    if (!out->text)
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    out->len = strlen(out->text);
    memo_doc_put(f->memo, id, out->session, out->scene, out->text, out->len);
    return 0;
}

/* ---- life cycle ----------------------------------------------------------------------- */

int fitsvc_open(const fitsvc_config *cfg, store *st, events *ev, fitsvc **out, glint_err *err)
{
    fitsvc *f;
    int rc;

    *out = NULL;
    /* A fit allocates a few arrays of 0.1 to 30 MiB (samples, log values,
     * diagnostics) and frees them at once.  With glibc's defaults these go
     * to fresh mmaps or trimmed heap tops, and every fit pays the page
     * faults again (measured: 38 -> 22 ms for a warm fit of 393,512
     * samples).  Keep them in the heap.  Process-wide: startup only. */
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
    mallopt(M_TRIM_THRESHOLD, 64 << 20);
    if (!(f = calloc(1, sizeof *f)))
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    f->cache = cfg->cache;
    f->jobs = cfg->jobs;
    f->memo = cfg->memo;
    f->points = cfg->points;
    f->st = st;
    f->ev = ev;
    f->work = cfg->work;
    f->background = cfg->background;
    f->links = cfg->links;
    pthread_mutex_init(&f->lock, NULL);
    if (!(f->holdouts = json_object())) {
        free(f);
        return glint_err_set(err, GLINT_ENOMEM, "out of memory");
    }
    if (st && (rc = fitsvc_pixels_start(f, err))) {
        fitsvc_close(f);
        return rc;
    }
    /* every level of every method shows in /metrics from the start */
    cache_declare_level(f->cache, "scene");
    cache_declare_level(f->cache, "pattern");
    for (int i = 0; i < method_count(); i++)
        for (int l = 0; l < method_at(i)->nlevels; l++)
            cache_declare_level(f->cache, method_at(i)->levels[l].name);
    *out = f;
    return 0;
}

void fitsvc_close(fitsvc *f)
{
    if (!f)
        return;
    fitsvc_pixels_stop(f); /* holds the memo's paintings while it writes */
    fitsvc_memo_close(f);
    json_decref(f->holdouts);
    pthread_mutex_destroy(&f->lock);
    free(f);
}

void fitsvc_metrics(fitsvc *f, FILE *o)
{
    cache_stats s;
    unsigned long long hits, misses;

    pthread_mutex_lock(&f->lock);
    hits = f->hits;
    misses = f->misses;
    pthread_mutex_unlock(&f->lock);
    cache_stats_get(f->cache, &s);
    fprintf(o, "# HELP glintd_fit_requests_total Fit requests by whether the whole "
               "precomputation was in memory.\n# TYPE glintd_fit_requests_total counter\n");
    fprintf(o, "glintd_fit_requests_total{cache=\"hit\"} %llu\n", hits);
    fprintf(o, "glintd_fit_requests_total{cache=\"miss\"} %llu\n", misses);
    fprintf(o, "# HELP glintd_fitcache_lookups_total Precomputation cache lookups by level and "
               "outcome (hit: in memory; joined: waited for another request's build; built).\n"
               "# TYPE glintd_fitcache_lookups_total counter\n");
    for (int l = 0; l < s.nlevels; l++) {
        const cache_level_stats *ls = &s.level[l];
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"hit\"} %llu\n",
                ls->name, ls->hits);
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"joined\"} %llu\n",
                ls->name, ls->joins);
        fprintf(o, "glintd_fitcache_lookups_total{level=\"%s\",outcome=\"built\"} %llu\n",
                ls->name, ls->builds);
    }
    fprintf(o, "# HELP glintd_fitcache_build_failures_total Builds that failed, by level.\n"
               "# TYPE glintd_fitcache_build_failures_total counter\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_build_failures_total{level=\"%s\"} %llu\n",
                s.level[l].name, s.level[l].failures);
    fprintf(o, "# HELP glintd_fitcache_build_seconds_total Time spent building, by level.\n"
               "# TYPE glintd_fitcache_build_seconds_total counter\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_build_seconds_total{level=\"%s\"} %.6f\n", s.level[l].name,
                s.level[l].build_seconds);
    fprintf(o, "# HELP glintd_fitcache_evictions_total Entries evicted (least recently used) to "
               "keep the byte budget.\n# TYPE glintd_fitcache_evictions_total counter\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_evictions_total{level=\"%s\"} %llu\n", s.level[l].name,
                s.level[l].evictions);
    fprintf(o, "# HELP glintd_fitcache_bytes Bytes held in memory, by level.\n"
               "# TYPE glintd_fitcache_bytes gauge\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_bytes{level=\"%s\"} %zu\n", s.level[l].name,
                s.level[l].bytes);
    fprintf(o, "# HELP glintd_fitcache_entries Entries in memory, by level.\n"
               "# TYPE glintd_fitcache_entries gauge\n");
    for (int l = 0; l < s.nlevels; l++)
        fprintf(o, "glintd_fitcache_entries{level=\"%s\"} %zu\n", s.level[l].name,
                s.level[l].entries);
    fprintf(o, "# HELP glintd_fitcache_budget_bytes The in-memory budget.\n"
               "# TYPE glintd_fitcache_budget_bytes gauge\nglintd_fitcache_budget_bytes %zu\n",
            s.budget);
    {
        unsigned long long loads = 0, builds = 0, rebuilds = 0;
        for (int l = 0; l < s.nlevels; l++) {
            loads += s.level[l].disk_loads;
            builds += s.level[l].disk_builds;
            rebuilds += s.level[l].disk_rebuilds;
        }
        fprintf(o, "# HELP glintd_fitcache_disk_total Disk-backed levels by what the disk "
                   "cache answered.\n# TYPE glintd_fitcache_disk_total counter\n");
        fprintf(o, "glintd_fitcache_disk_total{outcome=\"loaded\"} %llu\n", loads);
        fprintf(o, "glintd_fitcache_disk_total{outcome=\"built\"} %llu\n", builds);
        fprintf(o, "glintd_fitcache_disk_total{outcome=\"rebuilt\"} %llu\n", rebuilds);
    }
    memo_metrics(f->memo, o);
    fitsvc_pixels_metrics(f, o);
    fitsvc_memo_metrics(f, o);
    jobs_metrics(f->jobs, o);
}
