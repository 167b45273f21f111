"""Work that is too expensive, abandoned or unfair, through the real daemon
(server/admit.h, server/jobs.h, core/base/cancel.h):

- an estimate beyond glintd --work-max-seconds is refused before it starts
  (413, kind too-expensive, naming the estimate and the limit): a CPU
  preview at 2048 under an environment of many lights, an srbf fit at its
  largest parameters;
- a preview whose client closed its connection is cancelled and frees its
  work slot (glintd_work_running back to 0, glintd_work_total{outcome=
  "cancelled"} counted), and the next request is served;
- SIGTERM while a render and a cold fit run: the daemon exits (0) promptly;
- one painter's flood of fits supersedes its own queued fits instead of
  filling the queue, another painter's fit is queued (not 503), jobs are
  cancelled with DELETE (paint rights; view rights are refused).

The expensive work is chosen to take minutes if nothing stops it, and the
tests wait for what must happen with generous timeouts that only catch a
hang: they assert what happened, never how long it took.
"""
import json
import os
import re
import signal
import socket
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(__file__))
import harness  # noqa: E402
from harness import Daemon, remove_dirs  # noqa: E402

SPEC = "ct:rough=0.3,kd=0.5/0.35/0.2,f0=0.2"
HANG_S = 60  # longest wait for something that must happen
# The tests of cancelling lift the time limit (when the daemon has one): their
# slow work is what they are about, not its estimate.
NO_LIMIT = (["--work-max-seconds", "0"]
            if b"--work-max-seconds" in subprocess.run([harness.GLINTD, "--help"],
                                                        capture_output=True).stdout else [])


def tok(t):
    return {"X-Glint-Token": t}


def metric(d, name, labels=""):
    text = d.get("/metrics", status=200).text
    m = re.search(r"^%s%s (\S+)$" % (re.escape(name), re.escape(labels)), text, re.M)
    assert m, "no metric %s%s" % (name, labels)
    return float(m.group(1))


def wait_for(what, fn, timeout=HANG_S):
    deadline = time.time() + timeout
    while True:
        v = fn()
        if v:
            return v
        assert time.time() < deadline, "%s did not happen within %d s" % (what, timeout)
        time.sleep(0.05)


def painted_session(d, size=64, mesh="torus", scene=None, views=(0, 4, 7)):
    """A session on a (new) scene with views painted from base renders (one
    view: its fits schedule no held-out measurement, which would take a
    work slot in the background)."""
    if scene is None:
        scene = d.post("/api/v1/scenes", json={"mesh": mesh, "width": size, "height": size},
                       status=201).json()["id"]
    s = d.post("/api/v1/sessions", json={"scene_id": scene}, status=201).json()
    for k in views:
        img = d.get("/api/v1/scenes/%s/views/%d/base.png?format=exr&brdf=%s" % (scene, k, SPEC),
                    status=200).content
        d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
              headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}), data=img,
              status=200)
    return scene, s


def post_fit(d, s, body, **kw):
    return d.post("/api/v1/sessions/%s/fits" % s["id"],
                  headers=dict(tok(s["paint_token"]), **{"Content-Type": "application/json"}),
                  data=json.dumps(body), **kw)


def fitted_material(d, s):
    r = post_fit(d, s, {"method": "hf3", "params": {"res": 32}})
    assert r.status_code in (201, 202), r.text
    if r.status_code == 201:
        return r.json()["id"]
    j = wait_job(d, s, r.json()["job"]["id"], ("done", "failed"))
    assert j["state"] == "done", j
    return j["material_id"]


def job(d, s, jid):
    return d.get("/api/v1/jobs/" + jid, headers=tok(s["view_token"]), status=200,
                 schema="JobResponse.json").json()["job"]


def wait_job(d, s, jid, states, timeout=HANG_S):
    return wait_for("job %s reaching %s" % (jid, states),
                    lambda: (lambda j: j if j["state"] in states else None)(job(d, s, jid)),
                    timeout)


# A CPU preview of the torus under the sky with shadows: about 100,000
# covered pixels x 500 lights x an evaluation and a shadow ray each, minutes
# of work.
SLOW = "view=0&size=512&renderer=cpu&env=sky&lights=1024"
# 2048 x 2048 on the CPU under many lights: well beyond the default limit.
HUGE = "view=0&size=2048&renderer=cpu&env=sky&lights=1024"


def start_abandoned_preview(d, mid, token):
    """Send a slow preview request on a raw connection and return it once the
    render holds its work slot."""
    before = metric(d, "glintd_work_total", '{outcome="admitted"}')
    c = socket.create_connection(("127.0.0.1", d.port))
    c.sendall(("GET /api/v1/materials/%s/preview.png?%s HTTP/1.1\r\nHost: localhost\r\n"
               "X-Glint-Token: %s\r\n\r\n" % (mid, SLOW, token)).encode())
    wait_for("the slow preview taking its slot",
             lambda: metric(d, "glintd_work_total", '{outcome="admitted"}') > before and
             metric(d, "glintd_work_running") >= 1)
    return c


def test_over_the_limit_is_refused_up_front():
    d = Daemon("--quiet")  # the default --work-max-seconds, 600
    try:
        scene, s = painted_session(d, views=(0,))
        mid = fitted_material(d, s)
        r = d.get("/api/v1/materials/%s/preview.png?%s" % (mid, HUGE),
                  headers=tok(s["view_token"]), status=413, timeout=HANG_S)
        p = r.json()
        assert p["type"] == "/problems/too-expensive", p
        assert "2048x2048 preview" in p["detail"] and "600 s" in p["detail"], p
        est = float(re.search(r"estimated at (\d+) s", p["detail"]).group(1))
        assert est > 600, p
        assert metric(d, "glintd_work_running") == 0  # it never took a slot
        # srbf at its largest parameters: refused, not queued
        r = post_fit(d, s, {"method": "srbf", "params": {"lights": 4096, "basis_res": 16,
                                                         "raster": "full", "grazing": 8}})
        assert r.status_code == 413, r.text
        p = r.json()
        assert p["type"] == "/problems/too-expensive", p
        assert "cold srbf fit" in p["detail"] and "600 s" in p["detail"], p
        assert metric(d, "glintd_jobs_queued", '{queue="people"}') == 0
        # what is within the limit is served
        d.get("/api/v1/materials/%s/preview.png?view=0&size=64" % mid,
              headers=tok(s["view_token"]), status=200)
        assert metric(d, "glintd_work_total", '{outcome="too_expensive"}') == 2
        assert metric(d, "glintd_work_max_seconds") == 600
    finally:
        d.stop()


def test_an_abandoned_preview_frees_its_slot():
    d = Daemon("--work-slots", "1", "--work-wait", "0", "--quiet", *NO_LIMIT)
    try:
        scene, s = painted_session(d, views=(0,))
        mid = fitted_material(d, s)
        c = start_abandoned_preview(d, mid, s["view_token"])
        c.close()  # the client goes away
        wait_for("the abandoned preview's slot freed",
                 lambda: metric(d, "glintd_work_running") == 0)
        assert metric(d, "glintd_work_total", '{outcome="cancelled"}') >= 1
        # the only slot serves the next request (with --work-wait 0, 503 if still taken)
        d.get("/api/v1/materials/%s/preview.png?view=0&size=64" % mid,
              headers=tok(s["view_token"]), status=200)
    finally:
        d.stop()


def test_sigterm_with_work_running_exits():
    d = Daemon("--quiet", *NO_LIMIT)
    scene, s = painted_session(d, views=(0,))
    mid = fitted_material(d, s)
    c = start_abandoned_preview(d, mid, s["view_token"])
    # and a cold fit building its precomputation (an srbf energy level of minutes)
    r = post_fit(d, s, {"method": "srbf", "params": {"basis_res": 16, "grazing": 8}})
    assert r.status_code == 202, r.text
    wait_job(d, s, r.json()["job"]["id"], ("running",))
    d.proc.send_signal(signal.SIGTERM)
    try:
        rc = d.proc.wait(timeout=HANG_S)
    except subprocess.TimeoutExpired:
        d.proc.kill()
        raise AssertionError("glintd did not exit within %d s of SIGTERM" % HANG_S)
    finally:
        c.close()
        d.stop()
    assert rc == 0, rc
    with open(os.path.join(d.tmp, "glintd.log"), "rb") as f:
        assert b"glintd: stopped" in f.read()


def test_one_painters_flood_does_not_shut_out_another():
    d = Daemon("--threads", "2", "--quiet")
    try:
        scene, a = painted_session(d)
        _, b = painted_session(d, scene=scene)
        # two long cold fits of two other painters hold both workers
        holders = []
        for _ in range(2):
            _, c = painted_session(d, scene=scene)
            r = post_fit(d, c, {"method": "srbf", "params": {"basis_res": 12}})
            assert r.status_code == 202, r.text
            holders.append((c, r.json()["job"]["id"]))
        for c, jid in holders:
            wait_job(d, c, jid, ("running",))
        # painter a posts 300 distinct fits: each replaces a's queued one
        ids = []
        for res in range(4, 304):
            r = post_fit(d, a, {"method": "hf3", "params": {"res": res}})
            assert r.status_code == 202, r.text
            ids.append(r.json()["job"]["id"])
        assert metric(d, "glintd_jobs_queued", '{queue="people"}') == 1
        first = job(d, a, ids[0])
        assert first["state"] == "failed" and first["cancelled"] == "superseded", first
        assert ids[1] in first["error"], first
        # painter b is queued, not refused
        r = post_fit(d, b, {"method": "hf3", "params": {"res": 24}})
        assert r.status_code == 202, r.text
        bid = r.json()["job"]["id"]
        # a job is cancelled with paint rights only; the holders stop
        c, jid = holders[0]
        d.delete("/api/v1/jobs/" + jid, headers=tok(c["view_token"]), status=403)
        d.delete("/api/v1/jobs/" + jid, headers=tok(a["paint_token"]), status=403)
        for c, jid in holders:
            r = d.delete("/api/v1/jobs/" + jid, headers=tok(c["paint_token"]),
                         schema="JobResponse.json")
            assert r.status_code in (200, 202), r.text
            assert r.json()["job"]["cancelled"] == "deleted", r.text
        for c, jid in holders:
            j = wait_job(d, c, jid, ("done", "failed"))
            assert j["state"] == "failed" and j["cancelled"] == "deleted", j
        assert wait_job(d, b, bid, ("done", "failed"))["state"] == "done"
        assert wait_job(d, a, ids[-1], ("done", "failed"))["state"] == "done"
        d.delete("/api/v1/jobs/" + bid, headers=tok(b["paint_token"]), status=409)
    finally:
        d.stop()


def main():
    failed = 0
    for name, fn in sorted(globals().items()):
        if name.startswith("test_") and callable(fn):
            try:
                fn()
                print("ok   " + name)
            except Exception:
                import traceback
                print("FAIL " + name)
                traceback.print_exc(file=sys.stdout)
                failed += 1
            sys.stdout.flush()
    for path, excerpt in sorted(harness.sanitizer_findings.items()):
        print("FAIL sanitizer report in %s:\n%s" % (path, excerpt))
        failed += 1
    print("%d failed" % failed)
    remove_dirs(failed)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
