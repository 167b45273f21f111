/* fitsvc_record.c: recording a fit (fitsvc_int.h: fit_record), the one
 * path of every fit, a session's or a G-buffer set's:
 *
 *   save      the material's files, blobs "materials/<id>/" (before its row:
 *             a crash leaves only files the sweep removes);
 *   document  the API's material object (proto/schemas/Material.json), its
 *             links the API's (fitsvc_config.links);
 *   store     its row, and for a session the "fit" event in the same commit;
 *   memo      its serialized document, for the reads that follow;
 *   events    the session's streams hear of it. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "fitsvc_int.h"
#include "ids.h"
#include "json_text.h"
#include "material.h"

/* The "fit" event's data: the material, its link and what the studio shows
 * of it at once. */
static json_t *fit_event(const char *mid, const json_t *d, const char *mname, double rms,
                         double fit_s, int nused, const char *memory)
{
    json_t *res = json_object_get(d, "res");
    json_t *ev = json_pack("{s:s, s:s, s:{s:s, s:f, s:f, s:i, s:s}}", "material_id", mid, "href",
                           json_string_value(json_object_get(json_object_get(d, "links"),
                                                             "self")),
                           "summary", "method", mname, "rms_painted", rms, "fit_seconds", fit_s,
                           "views", nused, "cache", memory ? memory : "?");
    if (ev && res)
        json_object_set(json_object_get(ev, "summary"), "res", res);
    return ev;
}

/* The document: where the fit came from, the method's summary of the
 * material, its parameters, views, statistics and links. */
static json_t *fit_document(fitsvc *f, const fit_record_in *in, const material *m,
                            const fit_report *r, const char *mid)
{
    const int session = in->session_id && in->session_id[0];
    char created[GLINT_TIME_LEN];
    json_t *d, *views = json_array(), *paintings = session ? json_array() : NULL, *summary;
    int bad = !views || (session && !paintings);

    for (int v = 0; !bad && v < in->nviews; v++) {
        if (!in->use[v])
            continue;
        bad |= json_array_append_new(views, json_integer(v));
        if (paintings)
            bad |= json_array_append_new(
                paintings,
                json_pack("{s:i, s:I}", "view", v, "version", (json_int_t)in->versions[v]));
    }
    glint_time_iso(time(NULL), created);
    if (session)
        d = json_pack("{s:s, s:s, s:s, s:s, s:s}", "id", mid, "session_id", in->session_id,
                      "scene_id", in->scene_id, "created", created, "method", in->method->name);
    else
        d = json_pack("{s:s, s:s, s:s, s:s}", "id", mid, "gbuffer_set_id", in->set_id,
                      "created", created, "method", in->method->name);
    if (bad || !d) {
        json_decref(views);
        json_decref(paintings);
        json_decref(d);
        return NULL;
    }
    summary = material_summary(m);
    json_object_update(d, summary);
    json_decref(summary);
    json_object_set_new(d, "views_used", views);
    if (paintings)
        json_object_set_new(d, "paintings", paintings);
    json_object_update(d, r->members); /* the method's: not read here */
    if (f->links)
        json_object_set_new(d, "links",
                            f->links(mid, session ? in->session_id : "",
                                     session ? in->scene_id : "", session ? "" : in->set_id));
    return d;
}

int fit_record(fitsvc *f, const fit_record_in *in, const material *m, const fit_report *r,
               char mid[33], json_t **doc, glint_err *err)
{
    const int session = in->session_id && in->session_id[0];
    const char *owner = session ? in->session_id : in->set_id;
    char name[128], dir[4096];
    json_t *d = NULL;
    double t0 = glint_now();
    int rc, nused = 0;

    *doc = NULL;
    if ((rc = glint_id_new_near(owner, mid, err)))
        return rc;
    snprintf(name, sizeof name, "materials/%s", mid);
    if ((rc = store_blob_path(f->st, name, dir, sizeof dir, err)) ||
        (rc = material_save_deferred(m, dir, err)))
        return rc;
    t0 = srv_timing_step(in->tm, "save", t0);
    if (!(d = fit_document(f, in, m, r, mid)))
        return glint_err_set(err, GLINT_ENOMEM, "cannot build the material object");
    if (session) { /* the record and the session's "fit" event, in one commit */
        json_t *ev;
        for (int v = 0; v < in->nviews; v++)
            nused += in->use[v] != 0;
        ev = fit_event(mid, d, in->method->name, isfinite(r->rms_painted) ? r->rms_painted : 0.0,
                       in->fit_seconds, nused, r->memory);
        if (!ev)
            rc = glint_err_set(err, GLINT_ENOMEM, "cannot build the fit's event");
        else
            rc = store_material_put_event(f->st, mid, owner, d, "fit", ev, NULL, err);
        json_decref(ev);
    } else {
        rc = store_material_put(f->st, mid, owner, d, err);
    }
    if (rc) {
        json_decref(d);
        return rc;
    }
    srv_timing_step(in->tm, "record", t0);
    {
        char *text = json_text(d, 0);
        if (text)
            memo_doc_put(f->memo, mid, session ? in->session_id : "",
                         session ? in->scene_id : "", text, strlen(text));
        free(text);
    }
    if (session) /* the studio hears of it */
        events_notify(f->ev, in->session_id);
    *doc = d;
    return 0;
}
