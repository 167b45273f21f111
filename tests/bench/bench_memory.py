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
G-buffer at 2048 x 2048, a cold fit of 12 painted views, and uploads of a
2048 x 2048 painting in each format (the decode's bound from the header,
core/img/img.h) and of a 2048 x 2048 G-buffer of 32 channels.

A second table replays the memory probes of the project's issue 49, each
on a fresh daemon with the probe's budgets (--work-mb 256 --cache-mb 64):
images whose header declares more than their target holds, and readers
of a long stroke history.  It prints each answer and the daemon's peak
resident set (VmHWM) against the work budget plus the fixed 160 MB of
docs/security.md's Memory paragraph.

usage: tests/bench/bench_memory.py [--build DIR] [--glintd PATH]
                                   [--strokes N] [--only uploads|probes]
"""
import argparse
import json
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
sys.path.insert(0, os.path.join(SRC, "tests", "integration"))
import probe_files  # noqa: E402


class Daemon:
    def __init__(self, glintd, *args, data_dir=None):
        self.tmp = tempfile.mkdtemp(prefix="glint-bench-mem-")
        self.data_dir = data_dir or os.path.join(self.tmp, "data")
        port_file = os.path.join(self.tmp, "port")
        self.proc = subprocess.Popen(
            [glintd, "--port", "0", "--port-file", port_file, "--data-dir",
             self.data_dir, "--quiet", "--web-dir", os.path.join(SRC, "web")] +
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

    def call(self, method, path, **kw):
        """The answer, whatever its status."""
        return requests.request(method, self.base + path, timeout=600, **kw)

    def req(self, method, path, **kw):
        r = self.call(method, path, **kw)
        if r.status_code >= 400:
            raise RuntimeError("%s %s: %d %s" % (method, path, r.status_code, r.text[:300]))
        return r

    def held_peak(self):
        for line in self.req("GET", "/metrics").text.splitlines():
            if line.startswith("glintd_work_peak_bytes "):
                return int(line.split()[1])
        return 0

    def stop(self, keep_data=False):
        """keep_data: leave the directory (its data directory) to the caller."""
        self.proc.terminate()
        self.proc.wait()
        if not keep_data:
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
    ap.add_argument("--strokes", type=int, default=1000,
                    help="strokes of 10,000 points in the history probe (the probe's: 1000)")
    ap.add_argument("--only", choices=("uploads", "probes"),
                    help="only the uploads' rows of the first table (and the probes), or only "
                         "the probes")
    a = ap.parse_args()
    glintd = a.glintd or os.path.join(a.build, "server", "glintd")
    if a.only != "probes":
        print("| request | seconds | peak RSS growth (MiB) | bytes per pixel | bound held (MiB) "
              "| bound / growth |")
        print("|---|---|---|---|---|---|")
        if a.only != "uploads":
            renders_and_fits(glintd)
        uploads(glintd)
        print()
    probes(glintd, a.strokes)


def renders_and_fits(glintd):
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


def oiiotool_file(args, ext):
    """A file oiiotool makes (None when there is no oiiotool)."""
    fd, path = tempfile.mkstemp(suffix=ext)
    os.close(fd)
    try:
        subprocess.run(["oiiotool"] + args + ["-o", path], check=True, capture_output=True)
        with open(path, "rb") as f:
            return f.read()
    except (OSError, subprocess.CalledProcessError):
        return None
    finally:
        os.unlink(path)


def uploads(glintd):
    """A 2048^2 painting in each format, and a 32-channel G-buffer: the
    decode's bound held (from the header) against the growth measured."""
    n = 2048
    files = [
        ("PNG 8-bit (direct path)", probe_files.png_declaring(n, n)),
        ("PNG 16-bit (OpenImageIO)", probe_files.png_declaring(n, n, depth=16)),
        ("JPEG progressive 4:4:4", oiiotool_file(
            ["--create", "%dx%d" % (n, n), "3", "--attrib", "jpeg:progressive", "1",
             "--attrib", "jpeg:subsampling", "4:4:4"], ".jpg")),
        ("OpenEXR half, ZIP", probe_files.exr_declaring(n, n, ["R", "G", "B"], half=True)),
        ("OpenEXR float, ZIP", probe_files.exr_declaring(n, n, ["R", "G", "B"])),
    ]

    def view(d):
        sc = d.req("POST", API + "/scenes", json={"width": n, "height": n}).json()
        return d.req("POST", API + "/sessions", json={"scene_id": sc["id"]}).json()
    for name, body in files:
        if body is None:
            print("| upload %s %d^2 | skipped: no oiiotool | | | | |" % (name, n))
            continue
        measure(glintd, "upload %s %d^2" % (name, n), n * n, view,
                lambda d, s, body=body: d.req(
                    "PUT", "%s/sessions/%s/views/0/painting" % (API, s["id"]), data=body,
                    headers={"X-Glint-Token": s["paint_token"]}))

    def gbuffer_set(d):
        return d.req("POST", API + "/gbuffer-sets",
                     json={"views": 1, "width": n, "height": n}).json()
    names = ["mask", "P.X", "P.Y", "P.Z", "N.X", "N.Y", "N.Z", "wo.X", "wo.Y", "wo.Z", "wi.X",
             "wi.Y", "wi.Z", "uv.U", "uv.V"]
    gb = probe_files.exr_declaring(n, n, names + ["extra%02d" % i for i in range(32 - len(names))])
    measure(glintd, "upload G-buffer of 32 float channels %d^2" % n, n * n, gbuffer_set,
            lambda d, st: d.req("PUT", "%s/gbuffer-sets/%s/views/0/gbuffer.exr"
                                % (API, st["id"]), data=gb,
                                headers={"X-Glint-Owner": st["owner_key"]}))
    hdr = probe_files.hdr_flat(n, n // 2)
    measure(glintd, "upload environment, Radiance HDR %dx%d" % (n, n // 2), n * n // 2,
            lambda d: None, lambda d, _: d.req("POST", API + "/environments", data=hdr))


PROBE_WORK_MB, PROBE_CACHE_MB, FIXED_MB = 256, 64, 160


def probe(glintd, name, run, data_dir=None, keep_data=False):
    """run(d) on a fresh daemon with the probe's budgets -> its answers, as
    text; the row: the answers, the peak resident set, the bound."""
    d = Daemon(glintd, "--work-mb", str(PROBE_WORK_MB), "--cache-mb", str(PROBE_CACHE_MB),
               data_dir=data_dir)
    try:
        answer = run(d)
        peak = d.kb("VmHWM") / 1024.0
        bound = PROBE_WORK_MB + FIXED_MB
        print("| %s | %s | %.0f | %d | %s |" % (name, answer, peak, bound,
                                              "yes" if peak <= bound else "NO"))
        sys.stdout.flush()
        return d.data_dir
    finally:
        d.stop(keep_data=keep_data)


def answers(rs):
    """'413 image-too-large' for each answer (x N when the same)."""
    texts = []
    for r in rs:
        kind = ""
        if r.headers.get("Content-Type", "").startswith("application/problem+json"):
            kind = " " + r.json()["type"].rsplit("/", 1)[-1]
        texts.append("%d%s" % (r.status_code, kind))
    return ", ".join(sorted(set(texts))) + (" (x%d)" % len(rs) if len(rs) > 1 else "")


def at_once(n, fn):
    out = [None] * n

    def one(i):
        out[i] = fn()
    ts = [threading.Thread(target=one, args=(i,)) for i in range(n)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    return out


def probes(glintd, nstrokes):
    print("| probe (--work-mb %d --cache-mb %d) | answer | peak RSS (MiB) | work budget + fixed "
          "(MiB) | within |" % (PROBE_WORK_MB, PROBE_CACHE_MB))
    print("|---|---|---|---|---|")

    def session(d):
        sc = d.req("POST", API + "/scenes", json={"width": 32, "height": 32}).json()
        return d.req("POST", API + "/sessions", json={"scene_id": sc["id"]}).json()

    def painting(d, body, n=1):
        s = session(d)
        url = "%s/sessions/%s/views/0/painting" % (API, s["id"])
        return answers(at_once(n, lambda: d.call(
            "PUT", url, data=body, headers={"X-Glint-Token": s["paint_token"]})))
    png = probe_files.png_declaring(16384, 16384)
    probe(glintd, "PNG of %d KB declaring 16384^2, as a 32x32 view's painting" % (len(png) >> 10),
          lambda d: painting(d, png))
    probe(glintd, "the same, two at once", lambda d: painting(d, png, 2))
    exr = probe_files.exr_declaring(16384, 16384, ["R", "G", "B"])
    probe(glintd, "ZIP OpenEXR of %.1f MB declaring 16384^2, as a painting" % (len(exr) / 1e6),
          lambda d: painting(d, exr))

    def gbuffer(d):
        st = d.req("POST", API + "/gbuffer-sets",
                   json={"views": 1, "width": 4096, "height": 8}).json()
        body = probe_files.exr_declaring(4096, 4096, ["c%02d" % i for i in range(32)])
        return answers([d.call("PUT", "%s/gbuffer-sets/%s/views/0/gbuffer.exr"
                               % (API, st["id"]), data=body,
                               headers={"X-Glint-Owner": st["owner_key"]})])
    probe(glintd, "32-channel OpenEXR of 4096^2 into a G-buffer set of 4096x8", gbuffer)

    # the history: written by one daemon, read by a fresh one (its peak is
    # the readers')
    ids = {}

    def write(d):
        s = session(d)
        ids.update(s)
        url = "%s/sessions/%s/views/0/strokes" % (API, s["id"])
        # 60 strokes a request: a tree of about 170 MiB, within the budget
        per = 60
        text = json.dumps({"strokes": [probe_files.far_stroke(10000)] * per}).encode()
        left, rs = nstrokes, []
        while left > 0:
            if left < per:
                text = json.dumps({"strokes": [probe_files.far_stroke(10000)] * left}).encode()
            rs.append(d.call("POST", url, data=text, headers={
                "X-Glint-Token": s["paint_token"], "Content-Type": "application/json"}))
            left -= per
        return answers(rs)
    def write_at_once(d):
        s = session(d)
        url = "%s/sessions/%s/views/0/strokes" % (API, s["id"])
        text = json.dumps({"strokes": [probe_files.far_stroke(10000)] * 150}).encode()
        return answers([d.call("POST", url, data=text, headers={
            "X-Glint-Token": s["paint_token"], "Content-Type": "application/json"})])
    probe(glintd, "one request of 150 strokes of 10,000 points (a tree of twice the budget)",
          write_at_once)
    data = probe(glintd, "writing %d strokes of 10,000 points (1 inside the image)" % nstrokes,
                 write, keep_data=True)

    def read(d, n):
        url = "%s/sessions/%s/strokes?limit=10000" % (API, ids["id"])
        rs = at_once(n, lambda: d.call("GET", url, headers={"X-Glint-Token": ids["view_token"]}))
        return "%s, %.1f MB each" % (answers(rs), len(rs[0].content) / 1e6)
    probe(glintd, "GET .../strokes?limit=10000 with a view token, one reader",
          lambda d: read(d, 1), data_dir=data)
    probe(glintd, "the same, four readers at once", lambda d: read(d, 4), data_dir=data)
    shutil.rmtree(os.path.dirname(data), ignore_errors=True)


if __name__ == "__main__":
    main()
