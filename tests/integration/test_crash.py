"""Crash test: strokes are posted continuously while the daemon is killed
with SIGKILL at random moments and restarted, six rounds.  After every
restart:
  - every stroke whose POST was answered 200 is stored, with the number it
    was given and the same content;
  - the numbering has no gaps (1..last_seq), and anything stored beyond the
    acknowledged strokes comes from requests that were sent but never
    answered (committed just before the kill);
  - each view's painting is exactly its strokes applied in order to the base
    render (within 1/255, checked with the Python brush of test_sessions);
  - the session can still be read and painted.
Finally the session is fitted (the fits API), which must succeed.

GLINT_CRASH_SEED fixes the random moments; the seed used is printed.
"""
import os
import random
import sys
import threading
import time

import requests

sys.path.insert(0, os.path.dirname(__file__))
from harness import PG, SCHEMAS, run_tests, validate  # noqa: E402
from test_crash_writes import age_blobs  # noqa: E402
from test_sessions import (API, brush_apply, get_png, max_diff, to_float,  # noqa: E402
                           tok)

SIZE = 40
ROUNDS = 6
VIEWS = (0, 7)


def random_stroke(rng, n):
    pts = [[rng.uniform(-3, SIZE + 3), rng.uniform(-3, SIZE + 3)]]
    for _ in range(rng.randint(0, 3)):
        pts.append([pts[-1][0] + rng.uniform(-6, 6), pts[-1][1] + rng.uniform(-6, 6)])
    s = {"diameter": rng.uniform(1.5, 8), "kappa": rng.uniform(0, 0.3),
         "opacity": rng.uniform(0.3, 1), "points": pts, "tag": "s%d" % n}
    if rng.random() < 0.15:
        s["mode"] = "erase"
    else:
        s["color"] = [rng.uniform(-0.5, 1.5) for _ in range(3)]
    return s


def poster(d, sess, rng, stop, acked, sent, errors):
    """Post batches of 1..3 strokes until the daemon goes away."""
    http = requests.Session()
    url = "%s%s/sessions/%s/views/%%d/strokes" % (d.base, API, sess["id"])
    n = len(sent)
    while not stop.is_set():
        view = rng.choice(VIEWS)
        batch = []
        for _ in range(rng.randint(1, 3)):
            batch.append(random_stroke(rng, n))
            n += 1
        for s in batch:
            sent[s["tag"]] = (view, s)
        try:
            r = http.post(url % view, json={"strokes": batch}, headers=tok(sess["paint_token"]),
                          timeout=10)
        except requests.RequestException:
            break  # killed
        if r.status_code != 200:
            errors.append("%d %s" % (r.status_code, r.text[:300]))
            break
        a = r.json()
        validate(a, "StrokesPosted.json")
        assert a["last_seq"] - a["first_seq"] + 1 == len(batch)
        for i, s in enumerate(batch):
            acked[a["first_seq"] + i] = (view, s)


def stored_strokes(d, sess):
    out, since = {}, 0
    while True:
        page = d.get("%s/sessions/%s/strokes?since=%d&limit=10000" % (API, sess["id"], since),
                     status=200, schema="StrokeList.json", headers=tok(sess["view_token"])).json()
        for x in page["strokes"]:
            out[x["seq"]] = (x["view"], x["stroke"])
        since = page["last_seq"]
        if not page["more"]:
            return out, page["last_seq"]


def same_stroke(a, b):
    """The stored canonical stroke b is the sent stroke a."""
    keys = ("diameter", "kappa", "opacity", "points", "tag", "color")
    return all(a.get(k) == b.get(k) for k in keys) and a.get("mode", "paint") == b["mode"]


def verify(d, scene, sess, acked, sent, bases, swept_all=False):
    stored, last = stored_strokes(d, sess)
    assert sorted(stored) == list(range(1, last + 1)), "gaps in the numbering: %s" % sorted(stored)
    for seq, (view, s) in acked.items():
        assert seq in stored, "acknowledged stroke %d (%s) lost" % (seq, s["tag"])
        assert stored[seq][0] == view and same_stroke(s, stored[seq][1]), \
            "stroke %d changed: sent %s, stored %s" % (seq, s, stored[seq])
    extra = [seq for seq in stored if seq not in acked]
    for seq in extra:
        tag = stored[seq][1]["tag"]
        assert tag in sent and same_stroke(sent[tag][1], stored[seq][1]), \
            "stored stroke %d was never sent" % seq
    g = d.get(API + "/sessions/" + sess["id"], status=200, schema="Session.json",
              headers=tok(sess["paint_token"])).json()
    assert g["last_seq"] == last
    # the store swept what the kill left behind: one file per painted view,
    # no orphaned painting versions, no temporary files
    sdir = os.path.join(d.data_dir, "blobs", "sessions", sess["id"])
    # (none yet when the kill came before the first stroke was stored)
    files = sorted(os.listdir(sdir)) if os.path.isdir(sdir) else []
    # a painting's decoded pixels ("<blob>.px") go with their blob: none
    # without it
    pixels = [f for f in files if f.endswith(".px")]
    files = [f for f in files if not f.endswith(".px")]
    assert all(p[:-3] in files for p in pixels), (pixels, files)
    painted = sorted(p["view"] for p in g["paintings"])
    if PG and swept_all is False:
        # blobs shared by replicas: the sweep leaves files younger than its
        # grace (another replica's write in progress); what rows name is there
        assert set("view%d" % v for v in painted) <= set(f.split("-")[0] for f in files), files
    else:
        assert [f.split("-")[0] for f in files] == ["view%d" % v for v in painted], files
    for view in VIEWS:
        want = [[list(p) for p in row] for row in bases[view]]
        for seq in sorted(stored):
            if stored[seq][0] == view:
                brush_apply(want, bases[view], stored[seq][1])
        r, (_, _, got) = get_png(d, "%s/sessions/%s/views/%d/painting" % (API, sess["id"], view),
                                 headers=tok(sess["view_token"]))
        diff = max_diff(want, to_float(got))
        assert diff <= 1.0 / 255 + 1e-9, "view %d painting differs from its strokes by %g" % (
            view, diff)
    return len(stored), len(extra)


def fit_after(d, sess):
    """Fit the session (the fits developer's API); the fit must succeed."""
    r = d.post("%s/sessions/%s/fits" % (API, sess["id"]), json={"params": {"res": 16}},
               headers=tok(sess["paint_token"]))
    if r.status_code in (404, 405, 501) and "no such resource" in r.text or r.status_code == 501:
        # TODO(fits): POST /sessions/{id}/fits is not served by this build yet;
        # once it is, this test checks that the session fits after the crashes.
        print("TODO: POST /sessions/{id}/fits not available (%d): fit after crash not checked"
              % r.status_code)
        return "not available"
    assert r.status_code in (201, 202), "fit: %d %s" % (r.status_code, r.text[:500])
    if r.status_code == 201:
        if "Material.json" in SCHEMAS:
            validate(r.json(), "Material.json")
        return "material at once"
    job = r.json()["job"]
    deadline = time.time() + 300
    while job["state"] not in ("done", "failed") and time.time() < deadline:
        time.sleep(0.2)
        job = d.get("%s/jobs/%s" % (API, job["id"]), status=200,
                    headers=tok(sess["paint_token"])).json()["job"]
    assert job["state"] == "done", "fit job: %s" % job
    return "job done in %.1f s" % job.get("seconds", 0)


def test_crash_rounds(d):
    seed = int(os.environ.get("GLINT_CRASH_SEED", str(int(time.time()))))
    rng = random.Random(seed)
    print("seed %d" % seed)
    scene = d.post(API + "/scenes", status=201, json={"width": SIZE, "height": SIZE}).json()
    sess = d.post(API + "/sessions", status=201, json={"scene_id": scene["id"]}).json()
    bases = {}
    for v in VIEWS:
        _, (_, _, rows) = get_png(d, "%s/scenes/%s/views/%d/base.png" % (API, scene["id"], v))
        bases[v] = to_float(rows)
    acked, sent = {}, {}
    t0 = time.time()
    rounds = 0
    while rounds < ROUNDS:
        stop, errors = threading.Event(), []
        th = threading.Thread(target=poster, args=(d, sess, random.Random(rng.random()), stop,
                                                   acked, sent, errors))
        th.start()
        time.sleep(rng.uniform(0.3, 2.0))
        d.kill9()
        stop.set()
        th.join(30)
        assert not errors, "stroke requests failed before the kill: %s" % errors
        rounds += 1
        d.start()
        nstored, nextra = verify(d, scene, sess, acked, sent, bases)
        print("round %d: %d strokes acknowledged, %d stored (%d committed but unanswered), "
              "all acknowledged present" % (rounds, len(acked), nstored, nextra))
    assert len(acked) > 0
    if PG:
        # past the sweep's grace every orphan goes, as on SQLite at once
        d.stop()
        age_blobs(d.data_dir)
        d.start()
        verify(d, scene, sess, acked, sent, bases, swept_all=True)
    # still usable: one more batch continues the numbering
    _, last = stored_strokes(d, sess)
    r = d.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=200,
               json={"strokes": [{"color": [1, 1, 1], "diameter": 3, "points": [[20, 20]]}]},
               headers=tok(sess["paint_token"]))
    assert r.json()["first_seq"] == last + 1
    print("fit after the crashes: %s" % fit_after(d, sess))
    print("crash test: %d rounds in %.1f s, %d strokes acknowledged, all present"
          % (rounds, time.time() - t0, len(acked)))


if __name__ == "__main__":
    run_tests(globals(), daemon_args=("--quiet",))
