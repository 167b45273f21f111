#!/usr/bin/env python3
"""glintd benchmark (run by hand; not part of the test suite).

Starts its own daemon (quiet, fresh data directory) on an ephemeral loopback
port and prints a markdown table of:

  1. the warm round trip "upload a 256x256 PNG painting for one view, fit at
     64 texels, fetch the material JSON", median (and p90) over --runs runs,
     for a session with only that view painted and for one with all 12
     views painted (the fit then reads the other 11 paintings too);
  2. a cold fit of the same scene (empty cache): the job's wall time and the
     precomputation time it reports, and the same after a restart (the
     decomposition comes from the disk cache);
  3. wrk -t2 -c32 -d10s --latency on /healthz and on a cached material GET:
     requests/s and p99 latency.

  The client is a thin keep-alive one over the standard library's
  http.client (class Http below): `requests` adds 0.3-0.7 ms of its own to
  every request on loopback, more than some of the steps measured.
  --client requests runs the same with requests.Session, for comparison
  with figures taken that way.

  The warm round trip with one view is also timed while a held-out
  measurement (background work a fit schedules) runs.

  4. with --against OTHER_GLINTD (e.g. a build of an earlier commit): the warm
     round trip with 1 view painted, against both daemons in alternating
     rounds of 25 (8 rounds), so that both see the same load; the medians
     and their ratio.

usage: tests/bench/bench_daemon.py [--build DIR] [--glintd PATH] [--cli PATH]
                                   [--runs N] [--wrk-seconds S] [--threads N]
                                   [--against GLINTD]
"""
import argparse
import http.client
import json
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.parse


class Resp:
    """What the benchmark reads of an answer (the names requests uses)."""

    def __init__(self, method, url, status, headers, body):
        self.status_code, self.headers, self.content = status, headers, body
        self.request = type("Req", (), {"method": method, "url": url})

    @property
    def text(self):
        return self.content.decode("utf-8", "replace")

    def json(self):
        return json.loads(self.content)


class Http:
    """A keep-alive HTTP/1.1 client over http.client, one connection per
    host and port (the benchmark is sequential)."""

    def __init__(self):
        self.conns = {}

    def request(self, method, url, headers=None, data=None, json_body=None):
        u = urllib.parse.urlsplit(url)
        h = dict(headers or {})
        if json_body is not None:
            data = json.dumps(json_body)
            h.setdefault("Content-Type", "application/json")
        if isinstance(data, str):
            data = data.encode()
        path = u.path + ("?" + u.query if u.query else "")
        for attempt in (0, 1):
            c = self.conns.get(u.netloc)
            if c is None:
                c = self.conns[u.netloc] = http.client.HTTPConnection(u.hostname, u.port)
            try:
                c.request(method, path, body=data, headers=h)
                r = c.getresponse()
                body = r.read()
                break
            except (http.client.HTTPException, ConnectionError):
                c.close()  # the server closed a kept-alive connection: once more
                del self.conns[u.netloc]
                if attempt:
                    raise
        hdrs = {k.lower(): v for k, v in r.getheaders()}
        return Resp(method, url, r.status, Caseless(hdrs), body)

    def get(self, url, headers=None):
        return self.request("GET", url, headers)

    def post(self, url, headers=None, data=None, json=None):
        return self.request("POST", url, headers, data, json)

    def put(self, url, headers=None, data=None):
        return self.request("PUT", url, headers, data)


class Caseless(dict):
    def get(self, k, default=None):
        return dict.get(self, k.lower(), default)

    def __getitem__(self, k):
        return dict.__getitem__(self, k.lower())

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.dirname(os.path.dirname(HERE))


class Daemon:
    def __init__(self, glintd, data_dir, threads, extra=()):
        self.glintd, self.data_dir, self.threads = glintd, data_dir, threads
        self.extra = list(extra)
        self.proc = None

    def start(self):
        port_file = os.path.join(self.data_dir + ".port")
        if os.path.exists(port_file):
            os.unlink(port_file)
        self.log = open(self.data_dir + ".log", "ab")
        self.proc = subprocess.Popen(
            [self.glintd, "--port", "0", "--port-file", port_file, "--data-dir", self.data_dir,
             "--threads", str(self.threads), "--quiet", "--web-dir", os.path.join(SRC, "web")]
            + self.extra,
            stdout=self.log, stderr=self.log)
        t0 = time.time()
        while time.time() - t0 < 20:
            if self.proc.poll() is not None:
                raise RuntimeError("glintd exited; see %s.log" % self.data_dir)
            if os.path.exists(port_file) and open(port_file).read().strip():
                self.base = "http://127.0.0.1:%s" % open(port_file).read().strip()
                return
            time.sleep(0.02)
        raise RuntimeError("glintd did not start")

    def stop(self):
        if self.proc and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            self.proc.wait(timeout=30)
        self.log.close()


def view0_pngs(cli, tmp):
    """Two paintings of view 0 of the daemon's default scene at 256x256, made
    by the CLI (PNG bytes); the scene is left in tmp/scene.json and every
    view's PNGs in tmp/png0, tmp/png1."""
    subprocess.run([cli, "scene", "create", "--size", "256", "-o", tmp + "/scene.json"],
                   check=True, stdout=subprocess.DEVNULL)
    pngs = []
    for i, brdf in enumerate(["ct:rough=0.3,kd=0.5,f0=0.3", "ct:rough=0.2,kd=0.4,f0=0.2"]):
        subprocess.run([cli, "paint", tmp + "/scene.json", "--brdf", brdf, "--format", "png",
                        "-o", "%s/png%d" % (tmp, i)], check=True, stdout=subprocess.DEVNULL)
        with open("%s/png%d/view_00.png" % (tmp, i), "rb") as f:
            pngs.append(f.read())
    return pngs


def check(r, status):
    if r.status_code != status:
        raise RuntimeError("%s %s: %d %s" % (r.request.method, r.request.url, r.status_code,
                                             r.text[:300]))
    return r


def wait_job(http, base, job, token):
    while True:
        j = check(http.get(base + job["links"]["self"], headers={"X-Glint-Token": token}),
                  200).json()["job"]
        if j["state"] == "done":
            return j
        if j["state"] == "failed":
            raise RuntimeError("job failed: %s" % j["error"])
        time.sleep(0.002)  # polls are cheap; a coarser step would add to the times measured


def fit(http, base, sid, token, res, post_steps=None):
    """Fit; follow the job if there is one.  Returns (material, job or None, seconds).
    post_steps: dict receiving the POST's own Server-Timing steps."""
    t0 = time.perf_counter()
    r = http.post(base + "/api/v1/sessions/%s/fits" % sid,
                  headers={"X-Glint-Token": token, "Content-Type": "application/json"},
                  data=json.dumps({"params": {"res": res}}))
    if post_steps is not None:
        server_timing(r, post_steps)
    if r.status_code == 201:
        return r.json(), None, time.perf_counter() - t0
    check(r, 202)
    j = wait_job(http, base, r.json()["job"], token)
    dt = time.perf_counter() - t0
    m = check(http.get(base + "/api/v1/materials/" + j["material_id"],
                       headers={"X-Glint-Token": token}), 200).json()
    return m, j, dt


def new_session(http, base, scene_id, paint_dir, views, ext):
    s = check(http.post(base + "/api/v1/sessions", json={"scene_id": scene_id}), 201).json()
    ctype = {"png": "image/png", "exr": "image/x-exr"}[ext]
    for k in views:
        with open(os.path.join(paint_dir, "view_%02d.%s" % (k, ext)), "rb") as f:
            check(http.put(base + "/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                           headers={"X-Glint-Token": s["paint_token"], "Content-Type": ctype},
                           data=f.read()), 200)
    return s


def server_timing(r, into):
    """Collect the Server-Timing steps of a response (name -> list of ms)."""
    for part in r.headers.get("Server-Timing", "").split(","):
        m = re.match(r"\s*([\w-]+);dur=([\d.]+)", part)
        if m:
            into.setdefault(m.group(1), []).append(float(m.group(2)))


def round_trips(http, base, s, pngs, runs, res, server=None):
    """Upload a PNG for view 0 (alternating contents), fit (201), GET the material.
    server: dict {"put": {}, "fit": {}} receiving the Server-Timing steps."""
    times, steps, hits = [], {"put": [], "fit": [], "get": []}, 0
    h = {"X-Glint-Token": s["paint_token"]}
    for i in range(runs):
        body = pngs[i % len(pngs)]
        t0 = time.perf_counter()
        rp = check(http.put(base + "/api/v1/sessions/%s/views/0/painting" % s["id"],
                            headers=dict(h, **{"Content-Type": "image/png"}), data=body), 200)
        t1 = time.perf_counter()
        r = http.post(base + "/api/v1/sessions/%s/fits" % s["id"],
                      headers=dict(h, **{"Content-Type": "application/json"}),
                      data=json.dumps({"params": {"res": res}}))
        check(r, 201)
        t2 = time.perf_counter()
        check(http.get(base + r.headers["Location"], headers=h), 200)
        t3 = time.perf_counter()
        if server is not None:
            server_timing(rp, server.setdefault("put", {}))
            server_timing(r, server.setdefault("fit", {}))
            inner = server.setdefault("inner", {})
            for k, v in r.json().get("seconds", {}).items():
                inner.setdefault(k, []).append(1e3 * v)
        times.append(t3 - t0)
        steps["put"].append(t1 - t0)
        steps["fit"].append(t2 - t1)
        steps["get"].append(t3 - t2)
        hits += r.json()["precomputation"]["cache"]["memory"] == "hit"
    return times, steps, hits


def strokes(http, base, s, runs, server):
    """POST one stroke (20 points, diameter 12) to view 1 of a session, runs
    times: the painter's brush.  Returns the times; server receives the
    Server-Timing steps."""
    h = {"X-Glint-Token": s["paint_token"]}
    times = []
    for i in range(runs):
        pts = [[20 + 10 * k, 40 + (i * 7) % 160] for k in range(20)]
        body = {"strokes": [{"color": [0.2 + 0.6 * (i % 2), 0.3, 0.5], "diameter": 12,
                             "points": pts}]}
        t0 = time.perf_counter()
        r = check(http.post(base + "/api/v1/sessions/%s/views/1/strokes" % s["id"], headers=h,
                            json=body), 200)
        times.append(time.perf_counter() - t0)
        server_timing(r, server)
    return times


def stroke_round_trips(http, base, s, view, runs, res, server):
    """A painter's loop: POST one stroke (as strokes()) to a painted view, POST
    a fit (201), GET the material, runs times.  Returns the times, the
    fits' chunks summed again and of how many; server receives the steps'
    Server-Timing ("stroke", "fit") and the fits' own seconds ("inner")."""
    h = {"X-Glint-Token": s["paint_token"]}
    times, again, chunks = [], [], 0
    for i in range(runs):
        pts = [[20 + 10 * k, 40 + (i * 7) % 160] for k in range(20)]
        body = {"strokes": [{"color": [0.2 + 0.6 * (i % 2), 0.3, 0.5], "diameter": 12,
                             "points": pts}]}
        t0 = time.perf_counter()
        rs = check(http.post(base + "/api/v1/sessions/%s/views/%d/strokes" % (s["id"], view),
                             headers=h, json=body), 200)
        r = check(http.post(base + "/api/v1/sessions/%s/fits" % s["id"],
                            headers=dict(h, **{"Content-Type": "application/json"}),
                            data=json.dumps({"params": {"res": res}})), 201)
        check(http.get(base + r.headers["Location"], headers=h), 200)
        times.append(time.perf_counter() - t0)
        server_timing(rs, server.setdefault("stroke", {}))
        server_timing(r, server.setdefault("fit", {}))
        m = r.json()
        inner = server.setdefault("inner", {})
        for k, v in m.get("seconds", {}).items():
            inner.setdefault(k, []).append(1e3 * v)
        pre = m["precomputation"]
        chunks = pre.get("stream_chunks", 0)
        again.append(chunks - pre.get("stream_chunks_reused", 0))
    return times, again, chunks


def against(d, http, pngs, tmp, a):
    """Warm round trips (1 view painted) against this daemon and another one,
    alternating rounds so that both see the same load."""
    other = Daemon(a.against, tmp + "/data-against", a.threads)
    other.start()
    try:
        sessions = []
        for dd in (d, other):
            sc = check(http.post(dd.base + "/api/v1/scenes", json={"width": 256, "height": 256}),
                       201).json()
            if a.against_views == 12:
                s = new_session(http, dd.base, sc["id"], tmp + "/exr", range(12), "exr")
            else:
                s = new_session(http, dd.base, sc["id"], tmp + "/png0", [0], "png")
            fit(http, dd.base, s["id"], s["paint_token"], 64)
            round_trips(http, dd.base, s, pngs, 3, 64)
            sessions.append(s)
        times = [[], []]
        for _ in range(8):
            for i, dd in enumerate((d, other)):
                times[i] += round_trips(http, dd.base, sessions[i], pngs, 25, 64)[0]
    finally:
        other.stop()
    m = [statistics.median(t) for t in times]
    return [("warm round trip, %d view%s painted, alternating rounds (8 x 25): this build / "
             "--against" % (a.against_views, "s" if a.against_views > 1 else ""),
             "%s / %s" % (ms(m[0]), ms(m[1])), "ms"),
            ("... ratio this / --against", "%.3f" % (m[0] / m[1]), "")]


def wrk(url, seconds, headers=()):
    cmd = ["wrk", "-t2", "-c32", "-d%ds" % seconds, "--latency"]
    for h in headers:
        cmd += ["-H", h]
    out = subprocess.run(cmd + [url], check=True, capture_output=True, text=True).stdout
    rps = float(re.search(r"Requests/sec:\s+([\d.]+)", out).group(1))
    p99 = re.search(r"^\s+99%\s+([\d.]+)(us|ms|s)\s*$", out, re.M)
    scale = {"us": 1e-3, "ms": 1.0, "s": 1e3}[p99.group(2)]
    errors = re.search(r"Non-2xx or 3xx responses:\s+(\d+)", out)
    return rps, float(p99.group(1)) * scale, int(errors.group(1)) if errors else 0


def settle(http, base, timeout=60.0):
    """Wait until glintd runs no job (the held-out measurement a cold fit
    schedules runs in the background); returns the seconds waited."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        m = http.get(base + "/metrics").text
        if ('glintd_jobs{state="running"} 0' in m and 'glintd_jobs{state="queued"} 0' in m):
            break
        time.sleep(0.05)
    return time.time() - t0


def cpu_ms(pid):
    """CPU time of a process's live threads (Linux schedstat), ms."""
    tot = 0
    try:
        tids = os.listdir("/proc/%d/task" % pid)
    except OSError:
        return float("nan")
    for tid in tids:
        try:
            with open("/proc/%d/task/%s/schedstat" % (pid, tid)) as f:
                tot += int(f.read().split()[0])
        except (OSError, ValueError, IndexError):
            pass
    return tot * 1e-6


def ms(x):
    return "%.1f" % (1e3 * x)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(SRC, "build"))
    ap.add_argument("--glintd")
    ap.add_argument("--cli")
    ap.add_argument("--runs", type=int, default=50)
    ap.add_argument("--wrk-seconds", type=int, default=10)
    ap.add_argument("--threads", type=int, default=2, help="glintd --threads (job workers)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary directory")
    ap.add_argument("--against", help="another glintd to compare warm round trips with")
    ap.add_argument("--against-views", type=int, choices=(1, 12), default=1,
                    help="views painted in the --against comparison")
    ap.add_argument("--settle", action="store_true",
                    help="let background jobs finish before the warm round trips")
    ap.add_argument("--restarts", type=int, default=5,
                    help="restarts timed, each followed by the first fit (median shown)")
    ap.add_argument("--client", choices=("http.client", "requests"), default="http.client",
                    help="the HTTP client timed (default: a thin one over http.client)")
    a = ap.parse_args()
    glintd = a.glintd or os.path.join(a.build, "server", "glintd")
    cli = a.cli or os.path.join(a.build, "core", "glint")
    tmp = tempfile.mkdtemp(prefix="glint-bench-")
    rows = []
    load0 = " ".join("%.2f" % x for x in os.getloadavg())
    try:
        pngs = view0_pngs(cli, tmp)
        subprocess.run([cli, "paint", tmp + "/scene.json", "--brdf", "ct:rough=0.3,kd=0.5,f0=0.3",
                        "-o", tmp + "/exr"], check=True, stdout=subprocess.DEVNULL)

        d = Daemon(glintd, tmp + "/data", a.threads)
        d.start()
        if a.client == "requests":
            import requests
            http = requests.Session()
        else:
            http = Http()
        sc = check(http.post(d.base + "/api/v1/scenes", json={"width": 256, "height": 256}),
                   201).json()

        # cold: empty memory and disk caches, one view painted, then all 12
        s1 = new_session(http, d.base, sc["id"], tmp + "/png0", [0], "png")
        m, job, dt = fit(http, d.base, s1["id"], s1["paint_token"], 64)
        assert job is not None, "the first fit of a fresh daemon should be a job"
        c = m["precomputation"]["cache"]
        rows.append(("cold fit, 1 view (%d samples), res 64: job wall time" %
                     m["precomputation"]["samples"], ms(dt), "ms"))
        rows.append(("... its precomputation (raster + samples + design + decomposition + "
                     "operator, disk %s)" % c["disk"], ms(c["cold_seconds"]), "ms"))
        s12 = new_session(http, d.base, sc["id"], tmp + "/exr", range(12), "exr")
        m12, job, dt = fit(http, d.base, s12["id"], s12["paint_token"], 64)
        c = m12["precomputation"]["cache"]
        rows.append(("cold fit, 12 views (%d samples), res 64: job wall time" %
                     m12["precomputation"]["samples"], ms(dt), "ms"))
        rows.append(("... its precomputation (disk %s)" % c["disk"], ms(c["cold_seconds"]),
                     "ms"))
        for name, lv in c["levels"].items():
            rows.append(("...... %s level" % name, ms(lv["build_seconds"]), "ms"))

        # warm round trips
        if a.settle:
            settle(http, d.base)
        for label, s in (("1 view painted", s1), ("12 views painted", s12)):
            round_trips(http, d.base, s, pngs, 3, 64)  # warm the connection and the caches
            server = {}
            t, steps, hits = round_trips(http, d.base, s, pngs, a.runs, 64, server)
            t.sort()
            rows.append(("warm round trip (PUT 256x256 PNG + POST fit res 64 + GET material), "
                         "%s: median of %d (cache hits %d/%d)" % (label, a.runs, hits, a.runs),
                         ms(statistics.median(t)), "ms"))
            rows.append(("... p90 / min / max", "%s / %s / %s" % (
                ms(t[int(0.9 * (len(t) - 1))]), ms(t[0]), ms(t[-1])), "ms"))
            rows.append(("... medians of the steps: PUT painting / POST fit (201) / GET material",
                         " / ".join(ms(statistics.median(steps[k])) for k in ("put", "fit", "get")),
                         "ms"))
            for k, what in (("put", "PUT"), ("fit", "POST fit")):
                st = server.get(k, {})
                rows.append(("... %s inside glintd (Server-Timing medians): %s" % (
                    what, " / ".join(st)), " / ".join(
                        "%.2f" % statistics.median(v) for v in st.values()), "ms"))
            # the fit step's own parts, as the material reports them
            st = {k: v for k, v in server.get("inner", {}).items()
                  if k in ("gather", "map", "stream", "apply_operator", "apply",
                           "factorization", "diagnostics", "fit")}
            rows.append(("...... its fit step (the material's seconds, medians): %s" % (
                " / ".join(st)), " / ".join("%.2f" % statistics.median(v) for v in st.values()),
                "ms"))
        # beside a held-out measurement: a fit of the 12-view session at a
        # new resolution schedules one (background work of 0.5-1 s, which
        # waits for a second without fits or uploads before each view); the
        # one-view round trips run while it is scheduled
        settle(http, d.base)
        fit(http, d.base, s12["id"], s12["paint_token"], 48)
        t, _, _ = round_trips(http, d.base, s1, pngs, 50, 64)
        busy = 'glintd_jobs{state="running"} 0' not in http.get(d.base + "/metrics").text
        rows.append(("warm round trip, 1 view, while a 12-view held-out measurement is "
                     "scheduled: median of 50 (still scheduled after them: %s)" % (
                         "yes" if busy else "no"), ms(statistics.median(t)), "ms"))
        rows.append(("... the measurement done after them (settled)", "%.2f" % settle(
            http, d.base), "s"))
        # strokes on a painted view (the memo holds its image)
        server = {}
        strokes(http, d.base, s12, 3, {})
        t = strokes(http, d.base, s12, a.runs, server)
        rows.append(("stroke (20 points, diameter 12) on a painted 256x256 view: median of %d"
                     % a.runs, ms(statistics.median(t)), "ms"))
        rows.append(("... inside glintd (Server-Timing medians): %s" % " / ".join(server),
                     " / ".join("%.2f" % statistics.median(v) for v in server.values()), "ms"))
        # the painter's loop: a stroke, a fit, the material
        for label, s in (("1 view painted", s1), ("12 views painted", s12)):
            server = {}
            stroke_round_trips(http, d.base, s, 0, 3, 64, {})
            t, again, chunks = stroke_round_trips(http, d.base, s, 0, a.runs, 64, server)
            t.sort()
            rows.append(("stroke round trip (POST stroke on view 0 + POST fit res 64 + GET "
                         "material), %s: median of %d" % (label, a.runs),
                         ms(statistics.median(t)), "ms"))
            rows.append(("... p90 / min / max", "%s / %s / %s" % (
                ms(t[int(0.9 * (len(t) - 1))]), ms(t[0]), ms(t[-1])), "ms"))
            rows.append(("... chunks of the fit's pass summed again (median, of %d)" % chunks,
                         "%g" % statistics.median(again), ""))
            for k, what in (("stroke", "POST stroke"), ("fit", "POST fit")):
                st = server.get(k, {})
                rows.append(("... %s inside glintd (Server-Timing medians): %s" % (
                    what, " / ".join(st)), " / ".join(
                        "%.2f" % statistics.median(v) for v in st.values()), "ms"))
            st = {k: v for k, v in server.get("inner", {}).items()
                  if k in ("gather", "stream", "apply", "factorization", "diagnostics", "fit")}
            rows.append(("...... its fit step (the material's seconds, medians): %s" % (
                " / ".join(st)), " / ".join("%.2f" % statistics.median(v) for v in st.values()),
                "ms"))
        warm = check(http.get(d.base + "/api/v1/materials/" + m12["id"],
                              headers={"X-Glint-Token": s12["paint_token"]}), 200)
        rows.append(("material JSON size", str(len(warm.content)), "bytes"))

        # wrk
        if shutil.which("wrk"):
            for label, url, hdr in (
                    ("/healthz", d.base + "/healthz", ()),
                    ("GET /api/v1/materials/{id} (cached material)",
                     d.base + "/api/v1/materials/" + m12["id"],
                     ("X-Glint-Token: " + s12["paint_token"],))):
                rps, p99, bad = wrk(url, a.wrk_seconds, hdr)
                rows.append(("wrk -t2 -c32 -d%ds %s: requests/s" % (a.wrk_seconds, label),
                             "%.0f" % rps, "req/s"))
                rows.append(("... p99 latency%s" % (" (%d non-2xx!)" % bad if bad else ""),
                             "%.2f" % p99, "ms"))
        else:
            rows.append(("wrk", "not installed", ""))

        if a.against:
            rows += against(d, http, pngs, tmp, a)

        # restart: the decomposition from the disk cache, the paintings
        # from their kept pixels; `--restarts` of them, the median's
        # breakdown shown
        runs = []
        for _ in range(a.restarts):
            d.stop()
            d.start()
            cpu0, steps = cpu_ms(d.proc.pid), {}
            m, job, dt = fit(http, d.base, s12["id"], s12["paint_token"], 64, steps)
            cpu = cpu_ms(d.proc.pid) - cpu0
            runs.append((dt, steps, m["precomputation"]["cache"], cpu))
        runs.sort(key=lambda r: r[0])
        dt, steps, c, cpu = runs[(len(runs) - 1) // 2]
        rows.append(("after a restart, 12 views, res 64: job wall time (disk %s), median of %d "
                     "restarts" % (c["disk"], len(runs)), ms(dt), "ms"))
        rows.append(("... min / max", "%s / %s" % (ms(runs[0][0]), ms(runs[-1][0])), "ms"))
        rows.append(("... the POST before the job (Server-Timing): %s" % " / ".join(steps),
                     " / ".join("%.1f" % v[0] for v in steps.values()), "ms"))
        rows.append(("... its precomputation: %s" % " / ".join(c["levels"]), " / ".join(
            ms(lv["build_seconds"]) for lv in c["levels"].values()), "ms"))
        rows.append(("... CPU time of glintd's threads over it (both cores: wall %s ms)"
                     % ms(dt), "%.0f" % cpu, "ms"))
        d.stop()
    finally:
        if not a.keep:
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            print("kept", tmp, file=sys.stderr)

    print("client: %s" % a.client)
    print("load average before / after: %s / %s" % (load0, " ".join(
        "%.2f" % x for x in os.getloadavg())))
    print()
    print("| measurement | value | unit |")
    print("|---|---|---|")
    for r in rows:
        print("| %s | %s | %s |" % r)


if __name__ == "__main__":
    main()
