#!/usr/bin/env python3
"""Memory of glintd's expensive requests against the bounds it admits them
by (run by hand; not part of the test suite).

For each case a fresh daemon (quiet, fresh data directory, --work-mb large
enough for the case) gets a scene ready, then one request (or N at once);
the table prints the growth of the daemon's peak resident set (VmHWM) over
its resident set just before the request, that growth per pixel, and the
memory bound the daemon held for the request (glintd_work_peak_bytes in
/metrics), so bound / measured says how much margin admission keeps.
Cases: material previews at 1024, 2048 and 4096 on the CPU and through EGL
(skipped where EGL does not work; the context is opened by a small
preview first), a base render with other settings and a
G-buffer at 2048 x 2048, a cold fit of 12 painted views.

usage: tests/bench/bench_memory.py [--build DIR] [--glintd PATH]
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time

import requests

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.dirname(os.path.dirname(HERE))
API = "/api/v1"


class Daemon:
    def __init__(self, glintd, *args):
        self.tmp = tempfile.mkdtemp(prefix="glint-bench-mem-")
        port_file = os.path.join(self.tmp, "port")
        self.proc = subprocess.Popen(
            [glintd, "--port", "0", "--port-file", port_file, "--data-dir",
             os.path.join(self.tmp, "data"), "--quiet", "--web-dir", os.path.join(SRC, "web")] +
            list(args), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for _ in range(1000):
            if os.path.exists(port_file) and open(port_file).read().strip():
                self.base = "http://127.0.0.1:%s" % open(port_file).read().strip()
                return
            time.sleep(0.02)
        raise RuntimeError("glintd did not start")

    def kb(self, field):
        with open("/proc/%d/status" % self.proc.pid) as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
        return 0

    def req(self, method, path, **kw):
        r = requests.request(method, self.base + path, timeout=600, **kw)
        if r.status_code >= 400:
            raise RuntimeError("%s %s: %d %s" % (method, path, r.status_code, r.text[:300]))
        return r

    def held_peak(self):
        for line in self.req("GET", "/metrics").text.splitlines():
            if line.startswith("glintd_work_peak_bytes "):
                return int(line.split()[1])
        return 0

    def stop(self):
        self.proc.terminate()
        self.proc.wait()
        shutil.rmtree(self.tmp, ignore_errors=True)


def material(d, size=64, views=1):
    sc = d.req("POST", API + "/scenes", json={"width": size, "height": size}).json()
    s = d.req("POST", API + "/sessions", json={"scene_id": sc["id"]}).json()
    h = {"X-Glint-Token": s["paint_token"]}
    for k in range(views):
        d.req("POST", "%s/sessions/%s/views/%d/strokes" % (API, s["id"], k), headers=h,
              json={"strokes": [{"color": [0.8, 0.5, 0.3], "diameter": size / 2,
                                 "points": [[size / 2, size / 2]]}]})
    r = d.req("POST", "%s/sessions/%s/fits" % (API, s["id"]), headers=h,
              json={"params": {"res": 32}})
    if r.status_code == 201:
        return sc, s, r.json()["id"]
    job = r.json()["job"]["id"]
    while True:
        j = d.req("GET", API + "/jobs/" + job, headers=h).json()["job"]
        if j["state"] == "done":
            return sc, s, j["material_id"]
        if j["state"] == "failed":
            raise RuntimeError(j)
        time.sleep(0.05)


def measure(glintd, name, pixels, prepare, run, parallel=1):
    d = Daemon(glintd, "--work-mb", "65536", "--work-slots", "64")
    try:
        ctx = prepare(d)
        before = d.kb("VmRSS")
        t0 = time.time()
        errs = []

        def one():
            try:
                run(d, ctx)
            except Exception as e:  # noqa: BLE001
                errs.append(str(e))
        ts = [threading.Thread(target=one) for _ in range(parallel)]
        for t in ts:
            t.start()
        for t in ts:
            t.join()
        dt = time.time() - t0
        if errs:
            print("| %s | skipped: %s | | | | |" % (name, errs[0][:80]))
            return
        grown = (d.kb("VmHWM") - before) * 1024
        bound = d.held_peak()
        print("| %s | %.2f | %.0f | %.1f | %.0f | %.2f |" % (
            name, dt, grown / 2**20, grown / pixels if pixels else 0, bound / 2**20,
            bound / grown if grown > 0 else float("inf")))
        sys.stdout.flush()
    finally:
        d.stop()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default=os.path.join(SRC, "build"))
    ap.add_argument("--glintd")
    a = ap.parse_args()
    glintd = a.glintd or os.path.join(a.build, "server", "glintd")
    print("| request | seconds | peak RSS growth (MiB) | bytes per pixel | bound held (MiB) | bound / growth |")
    print("|---|---|---|---|---|---|")
    for eng in ("cpu", "egl"):
        for size in (1024, 2048, 4096):
            def run(d, ctx, size=size, eng=eng):
                sc, s, mid = ctx
                d.req("GET", "%s/materials/%s/preview.png?view=0&size=%d&renderer=%s"
                      % (API, mid, size, eng), headers={"X-Glint-Token": s["paint_token"]})
            def prep(d, eng=eng):
                ctx = material(d)
                if eng == "egl":  # open the EGL context first: it is not the render's
                    d.req("GET", "%s/materials/%s/preview.png?view=0&size=8&renderer=egl"
                          % (API, ctx[2]), headers={"X-Glint-Token": ctx[1]["paint_token"]})
                return ctx
            measure(glintd, "preview %s %d^2" % (eng, size), size * size, prep, run)
    def run4(d, ctx):
        sc, s, mid = ctx
        d.req("GET", "%s/materials/%s/preview.png?view=0&size=4096&renderer=cpu"
              % (API, mid), headers={"X-Glint-Token": s["paint_token"]})
    measure(glintd, "4 previews cpu 4096^2 at once", 4 * 4096 * 4096, material, run4, parallel=4)

    def big_scene(d):
        return d.req("POST", API + "/scenes", json={
            "width": 2048, "height": 2048,
            "views": [{"eye": [0, -3, 1], "light": [2, -2, 2]}]}).json()
    measure(glintd, "base render (other BRDF) cpu 2048^2", 2048 * 2048, big_scene,
            lambda d, sc: d.req("GET", "%s/scenes/%s/views/0/base.png?brdf=lambert:kd=0.5"
                                % (API, sc["id"])))
    measure(glintd, "G-buffer 2048^2", 2048 * 2048, big_scene,
            lambda d, sc: d.req("GET", "%s/scenes/%s/views/0/gbuffer.exr" % (API, sc["id"])))

    def painted(d):
        sc = d.req("POST", API + "/scenes", json={"width": 512, "height": 512}).json()
        s = d.req("POST", API + "/sessions", json={"scene_id": sc["id"]}).json()
        h = {"X-Glint-Token": s["paint_token"]}
        for k in range(12):
            d.req("POST", "%s/sessions/%s/views/%d/strokes" % (API, s["id"], k), headers=h,
                  json={"strokes": [{"color": [0.8, 0.5, 0.3], "diameter": 400,
                                     "points": [[256, 256]]}]})
        return s

    def fit(d, s):
        h = {"X-Glint-Token": s["paint_token"]}
        r = d.req("POST", "%s/sessions/%s/fits" % (API, s["id"]), headers=h,
                  json={"params": {"res": 128}})
        job = r.json()["job"]["id"]
        while d.req("GET", API + "/jobs/" + job, headers=h).json()["job"]["state"] not in (
                "done", "failed"):
            time.sleep(0.05)
    measure(glintd, "cold fit, 12 views of 512^2 (1.57 M samples), res 128", 0, painted, fit)


if __name__ == "__main__":
    main()
