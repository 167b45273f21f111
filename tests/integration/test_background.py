"""Integration tests of the held-out measurement's CPU priority (glintd
--background-priority, server/fitsvc.h FITSVC_BG_*) on the real daemon.

A fit of two views or more schedules a held-out measurement of its point
(fitsvc_holdout.c), which runs on a thread named glintd-holdout.  While it
runs, the test reads that thread's scheduling policy and nice value from
/proc/<pid>/task/<tid>/stat: SCHED_IDLE by default, nice 19 with "low", the
requests' own with "normal"; no other thread of the daemon is demoted.  A
measurement that ends before the test sees its thread is tried again on a
new point (another resolution).  Linux only (skipped elsewhere).
"""
import json
import os
import subprocess
import sys
import tempfile
import time
import traceback

sys.path.insert(0, os.path.dirname(__file__))
import harness  # noqa: E402
from harness import GLINTD, Daemon, remove_dirs  # noqa: E402

CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(GLINTD))), "core", "glint")
SIZE = 64
SCHED_OTHER, SCHED_IDLE = 0, 5
THREAD = "glintd-holdout"


def threads(pid):
    """{tid: (comm, nice, policy)} of a process's live threads."""
    out = {}
    base = "/proc/%d/task" % pid
    try:
        tids = os.listdir(base)
    except OSError:
        return out
    for tid in tids:
        try:
            with open("%s/%s/stat" % (base, tid)) as f:
                st = f.read()
        except OSError:  # the thread ended meanwhile
            continue
        comm = st[st.index("(") + 1:st.rindex(")")]
        rest = st[st.rindex(")") + 2:].split()
        # fields 3.. of proc(5): nice is field 19, policy field 41
        out[int(tid)] = (comm, int(rest[16]), int(rest[38]))
    return out


def held_out(d, scene, res):
    m = d.get("/api/v1/methods?scene_id=" + scene, status=200).json()
    for p in m["scene"]["points"]:
        if p["params"].get("res") == res and len(p["views"]) >= 2:
            return p["held_out_rms"]
    return None


def painted_session(d, paint_dir, nviews):
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201).json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    for k in range(nviews):
        with open(os.path.join(paint_dir, "view_%02d.exr" % k), "rb") as f:
            d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                  headers={"Content-Type": "image/x-exr", "X-Glint-Token": s["paint_token"]},
                  data=f.read(), status=200)
    return sc["id"], s


def observe(d, scene, s, res, deadline_s=300.0):
    """Fit at `res` and watch the daemon's threads until the point's held-out
    error is there.  Returns ({(nice, policy)} of the measurement's thread,
    {(comm, nice, policy)} of every other thread seen)."""
    seen, others = set(), set()
    r = d.post("/api/v1/sessions/%s/fits" % s["id"],
               headers={"X-Glint-Token": s["paint_token"], "Content-Type": "application/json"},
               data=json.dumps({"params": {"res": res}}))
    assert r.status_code in (201, 202), r.text
    t0, last_check = time.time(), 0.0
    while time.time() - t0 < deadline_s:
        for comm, nice, policy in threads(d.proc.pid).values():
            if comm == THREAD:
                seen.add((nice, policy))
            else:
                others.add((comm, nice, policy))
        if time.time() - last_check > 0.05:
            last_check = time.time()
            if held_out(d, scene, res) is not None:
                break
        time.sleep(0.001)
    assert held_out(d, scene, res) is not None, "no held-out error after %.0f s" % deadline_s
    return seen, others


def check_mode(paint_dir, args, want):
    d = Daemon(*args)
    try:
        scene, s = painted_session(d, paint_dir, 12)
        for res in (24, 28, 20, 36, 16, 40, 44, 48):
            seen, others = observe(d, scene, s, res)
            # no thread but the measurement's is idle, whatever the setting
            # no other thread is demoted, the job workers that ran the fits
            # included (the pixels' writer runs at nice 10 by design)
            assert all(p == SCHED_OTHER and n != 19 for _, n, p in others), sorted(others)
            if seen:
                assert seen == {want}, (args, seen, want)
                print("  %s: the measurement ran at nice %d, policy %d" % (
                    " ".join(args) or "default", want[0], want[1]))
                return
        raise AssertionError("the measurement's thread was never seen (%s)" % (args,))
    finally:
        d.stop()


def held_out_point(d, scene, res):
    m = d.get("/api/v1/methods?scene_id=" + scene, status=200).json()
    for p in m["scene"]["points"]:
        if p["params"].get("res") == res and len(p["views"]) >= 2:
            return p
    return None


def check_waits_for_the_painters(paint_dir, busy_s=3.0):
    """A measurement scheduled while a painter keeps uploading does none of
    its views until the uploads pause for a second; then it ends, and says
    how long it waited."""
    d = Daemon()
    try:
        scene, s = painted_session(d, paint_dir, 12)
        with open(os.path.join(paint_dir, "view_00.exr"), "rb") as f:
            body = f.read()
        r = d.post("/api/v1/sessions/%s/fits" % s["id"],
                   headers={"X-Glint-Token": s["paint_token"],
                            "Content-Type": "application/json"},
                   data=json.dumps({"params": {"res": 24}}))
        assert r.status_code in (201, 202), r.text
        if r.status_code == 202:  # the cold fit's job; the measurement comes after it
            jid = r.json()["job"]["id"]
            while d.get("/api/v1/jobs/" + jid, headers={"X-Glint-Token": s["paint_token"]},
                        status=200).json()["job"]["state"] not in ("done", "failed"):
                time.sleep(0.01)
        t0, puts, gap = time.time(), 0, 0.0
        while time.time() - t0 < busy_s:
            t1 = time.time()
            d.put("/api/v1/sessions/%s/views/1/painting" % s["id"],
                  headers={"Content-Type": "image/x-exr", "X-Glint-Token": s["paint_token"]},
                  data=body, status=200)
            puts += 1
            p = held_out_point(d, scene, 24)
            assert p is not None and p["held_out_rms"] is None, \
                "measured while the painter was at work: %s" % p
            gap = max(gap, time.time() - t1)
            time.sleep(0.05)
        deadline = time.time() + 300
        while time.time() < deadline:
            p = held_out_point(d, scene, 24)
            if p["held_out_rms"] is not None:
                break
            time.sleep(0.05)
        h = p["held_out"]
        assert h is not None, "no held-out error 300 s after the uploads stopped"
        # it waited (the uploads above saw it unmeasured after each one), and
        # says so (how long depends on when its idle thread first ran)
        assert h["paused_seconds"] > 0, h
        assert h["seconds"] >= 0, h
        print("  %d uploads in %.1f s (longest step %.2f s); the measurement waited %.2f s, "
              "then took %.2f s" % (puts, busy_s, gap, h["paused_seconds"], h["seconds"]))
    finally:
        d.stop()


def wait_job(d, s, jid, deadline_s=300.0):
    t0 = time.time()
    while time.time() - t0 < deadline_s:
        j = d.get("/api/v1/jobs/" + jid, headers={"X-Glint-Token": s["paint_token"]},
                  status=200).json()["job"]
        if j["state"] in ("done", "failed"):
            return j
        time.sleep(0.01)
    raise AssertionError("job %s not done after %.0f s" % (jid, deadline_s))


def check_a_queued_fit_is_not_held_back(paint_dir, busy_s=300.0):
    """With one job worker, a measurement waiting for the painters holds it:
    a painter's cold fit queued meanwhile must not wait for the painter to
    stop.  The measurement goes on when a fit is queued, and the fit runs
    after it while the uploads go on (they go on until it is done: busy_s
    only catches a fit held back for good)."""
    d = Daemon("--threads", "1")
    try:
        scene, s = painted_session(d, paint_dir, 12)
        with open(os.path.join(paint_dir, "view_00.exr"), "rb") as f:
            body = f.read()
        hdr = {"X-Glint-Token": s["paint_token"], "Content-Type": "application/json"}
        r = d.post("/api/v1/sessions/%s/fits" % s["id"], headers=hdr,
                   data=json.dumps({"params": {"res": 24}}), status=202)
        assert wait_job(d, s, r.json()["job"]["id"])["state"] == "done"
        # the measurement of res 24 now holds the worker, waiting for a pause
        r = d.post("/api/v1/sessions/%s/fits" % s["id"], headers=hdr,
                   data=json.dumps({"params": {"res": 28}}), status=202)
        jid, t0, state = r.json()["job"]["id"], time.time(), None
        while time.time() - t0 < busy_s:
            d.put("/api/v1/sessions/%s/views/1/painting" % s["id"],
                  headers={"Content-Type": "image/x-exr", "X-Glint-Token": s["paint_token"]},
                  data=body, status=200)
            state = d.get("/api/v1/jobs/" + jid, headers={"X-Glint-Token": s["paint_token"]},
                          status=200).json()["job"]["state"]
            if state in ("done", "failed"):
                break
            time.sleep(0.05)
        assert state == "done", "the queued fit was %s after %.0f s of uploads" % (state, busy_s)
        print("  the queued fit was done after %.2f s of uploads" % (time.time() - t0))
    finally:
        d.stop()


def main():
    if not os.path.isdir("/proc/self/task"):
        print("skipped: no /proc/<pid>/task here")
        sys.exit(77)
    tmp = tempfile.mkdtemp(prefix="glint-bg-")
    subprocess.run([CLI, "scene", "create", "--size", str(SIZE), "-o",
                    os.path.join(tmp, "scene.json")], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([CLI, "paint", os.path.join(tmp, "scene.json"), "--brdf",
                    "ct:rough=0.3,kd=0.5,f0=0.3", "-o", os.path.join(tmp, "paint")],
                   check=True, stdout=subprocess.DEVNULL)
    paint = os.path.join(tmp, "paint")
    checks = [(name, lambda a=args, w=want: check_mode(paint, a, w)) for name, args, want in (
        ("default", (), (0, SCHED_IDLE)),
        ("idle", ("--background-priority", "idle"), (0, SCHED_IDLE)),
        ("low", ("--background-priority", "low"), (19, SCHED_OTHER)),
        ("normal", ("--background-priority", "normal"), (0, SCHED_OTHER)))]
    checks += [("waits_for_the_painters", lambda: check_waits_for_the_painters(paint)),
               ("a_queued_fit_is_not_held_back",
                lambda: check_a_queued_fit_is_not_held_back(paint))]
    passed = failed = 0
    for name, fn in checks:
        try:
            fn()
            print("ok   " + name)
            passed += 1
        except Exception:  # noqa: BLE001
            print("FAIL " + name)
            traceback.print_exc(file=sys.stdout)
            failed += 1
        sys.stdout.flush()
    for path, excerpt in sorted(harness.sanitizer_findings.items()):
        print("FAIL sanitizer report in %s:\n%s" % (path, excerpt))
        failed += 1
    print("%d passed, %d failed" % (passed, failed))
    remove_dirs(failed, [tmp])
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
