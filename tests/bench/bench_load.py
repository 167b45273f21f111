#!/usr/bin/env python3
"""glintd under load (run by hand; not part of the test suite).

Starts its own daemon on an ephemeral loopback port and, for --seconds each
(60 by default), runs two phases:

  1. 32 painters (threads, each with its own keep-alive connection) posting
     strokes to 8 sessions of one scene (4 painters a session, each on a view
     of its own), a stroke every --think ms, while 4 scripts fit at once:
     each script has a session of its own and loops upload a painting (PUT
     PNG), fit (POST, following the job when there is one), GET the material,
     GET a 256x256 preview;
  2. the same with 1,000 more connections held open and idle (each sends a
     GET /healthz and then waits, sending another every 10 s so that the
     daemon's idle timeout of 30 s does not close it).

Prints, per phase and per endpoint: requests, errors (any answer but the
expected status, or a failed connection), p50, p99 and max latency; the
strokes and fits per second achieved; glintd's resident memory (VmRSS) at
the start and its peak, sampled every 0.25 s.  Exits 1 if any request
failed.

usage: tests/bench/bench_load.py [--build DIR] [--seconds S] [--painters N]
                                 [--scripts N] [--idle N] [--think MS]
"""
import argparse
import os
import random
import socket
import sys
import tempfile
import threading
import time

import requests

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from bench_daemon import SRC, Daemon, check, new_session, view0_pngs  # noqa: E402

API = "/api/v1"


class Book:
    """Latencies and errors per endpoint, shared by the threads."""

    def __init__(self):
        self.lock = threading.Lock()
        self.t = {}
        self.err = {}
        self.first_error = None

    def add(self, name, dt, ok, why=""):
        with self.lock:
            self.t.setdefault(name, []).append(dt)
            if not ok:
                self.err[name] = self.err.get(name, 0) + 1
                if self.first_error is None:
                    self.first_error = "%s: %s" % (name, why)

    def rows(self):
        out = []
        for name in sorted(self.t):
            v = sorted(self.t[name])
            p = lambda q: v[min(len(v) - 1, int(q * len(v)))] * 1e3  # noqa: E731
            out.append((name, len(v), self.err.get(name, 0), p(0.5), p(0.99), v[-1] * 1e3))
        return out


def timed(book, name, fn, status):
    t0 = time.perf_counter()
    try:
        r = fn()
        ok = r.status_code == status
        why = "" if ok else "%d %s" % (r.status_code, r.text[:200])
    except requests.RequestException as e:
        r, ok, why = None, False, str(e)
    book.add(name, time.perf_counter() - t0, ok, why)
    return r if ok else None


def painter(base, s, view, stop, book, think, seed):
    rng = random.Random(seed)
    http = requests.Session()
    h = {"X-Glint-Token": s["paint_token"]}
    url = base + API + "/sessions/%s/views/%d/strokes" % (s["id"], view)
    while not stop.is_set():
        x, y = rng.uniform(20, 230), rng.uniform(20, 230)
        pts = [[x + 4 * k, y + 2 * k] for k in range(rng.randint(1, 20))]
        body = {"strokes": [{"color": [rng.random(), rng.random(), rng.random()],
                             "diameter": rng.uniform(4, 24), "kappa": 0.5, "points": pts}]}
        timed(book, "POST strokes", lambda: http.post(url, headers=h, json=body), 200)
        stop.wait(think)


def script(base, s, pngs, stop, book, res):
    http = requests.Session()
    h = {"X-Glint-Token": s["paint_token"]}
    i = 0
    while not stop.is_set():
        body = pngs[i % len(pngs)]
        i += 1
        timed(book, "PUT painting", lambda: http.put(
            base + API + "/sessions/%s/views/0/painting" % s["id"],
            headers=dict(h, **{"Content-Type": "image/png"}), data=body), 200)
        t0 = time.perf_counter()
        try:
            r = http.post(base + API + "/sessions/%s/fits" % s["id"], headers=h,
                          json={"params": {"res": res}})
            mid = None
            if r.status_code == 201:
                mid = r.json()["id"]
            elif r.status_code == 202:
                url = base + r.json()["job"]["links"]["self"]
                while True:
                    j = http.get(url, headers=h).json()["job"]
                    if j["state"] in ("done", "failed"):
                        mid = j.get("material_id")
                        break
                    time.sleep(0.01)
            book.add("POST fit (to its material)", time.perf_counter() - t0, mid is not None,
                     "" if mid else "%d %s" % (r.status_code, r.text[:200]))
        except requests.RequestException as e:
            book.add("POST fit (to its material)", time.perf_counter() - t0, False, str(e))
            continue
        if mid:
            timed(book, "GET material", lambda: http.get(
                base + API + "/materials/" + mid, headers=h), 200)
            timed(book, "GET preview.png", lambda: http.get(
                base + API + "/materials/%s/preview.png?view=3&size=256" % mid,
                headers=h), 200)


class Idle:
    """n keep-alive connections, each refreshed with a GET /healthz every
    `every` seconds (one thread: the requests of a round are all sent, then
    all answers read, so that a round takes one round trip, not n)."""

    def __init__(self, port, n, every=10.0):
        self.port, self.n, self.every = port, n, every
        self.socks, self.errors, self.stop = [], 0, threading.Event()
        self.lock = threading.Lock()

    @staticmethod
    def _send(s):
        s.sendall(b"GET /healthz HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")

    @staticmethod
    def _read(s):
        data = b""
        while b"\r\n\r\n" not in data:
            chunk = s.recv(4096)
            if not chunk:
                raise OSError("closed")
            data += chunk
        head, _, rest = data.partition(b"\r\n\r\n")
        length = 0
        for line in head.split(b"\r\n"):
            if line.lower().startswith(b"content-length:"):
                length = int(line.split(b":")[1])
        while len(rest) < length:
            chunk = s.recv(4096)
            if not chunk:
                raise OSError("closed")
            rest += chunk
        if not head.startswith(b"HTTP/1.1 200"):
            raise OSError(head.split(b"\r\n")[0].decode())

    def _round(self):
        """Ping every open socket; drop and count the ones that fail."""
        with self.lock:
            alive = []
            for s in self.socks:
                try:
                    self._send(s)
                    alive.append(s)
                except OSError:
                    self.errors += 1
            kept = []
            for s in alive:
                try:
                    self._read(s)
                    kept.append(s)
                except OSError:
                    self.errors += 1
                    s.close()
            self.socks = kept
            return len(kept)

    def open(self):
        for _ in range(self.n):
            s = socket.create_connection(("127.0.0.1", self.port))
            s.settimeout(30)
            self.socks.append(s)
        self._round()
        self.th = threading.Thread(target=self._keep, daemon=True)
        self.th.start()

    def _keep(self):
        while not self.stop.wait(self.every):
            self._round()

    def held(self):
        return self._round()

    def close(self):
        self.stop.set()
        for s in self.socks:
            s.close()


def rss_kb(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def phase(label, base, pid, sessions, scripts, pngs, a):
    book, stop = Book(), threading.Event()
    peak = [rss_kb(pid)]
    start_rss = peak[0]
    th = []
    for i in range(a.painters):
        s = sessions[i % len(sessions)]
        th.append(threading.Thread(target=painter, args=(
            base, s, (i // len(sessions)) % 12, stop, book, a.think / 1e3, i)))
    for i, s in enumerate(scripts):
        th.append(threading.Thread(target=script, args=(base, s, pngs, stop, book, a.res)))
    t0 = time.time()
    for t in th:
        t.start()
    while time.time() - t0 < a.seconds:
        time.sleep(0.25)
        peak.append(rss_kb(pid))
    stop.set()
    for t in th:
        t.join()
    wall = time.time() - t0
    rows = book.rows()
    print("\n### %s (%.0f s, %d painters, %d scripts)\n" % (label, wall, a.painters,
                                                            len(scripts)))
    print("| endpoint | requests | errors | p50 ms | p99 ms | max ms |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, n, err, p50, p99, mx in rows:
        print("| %s | %d | %d | %.1f | %.1f | %.1f |" % (name, n, err, p50, p99, mx))
    counts = {r[0]: r[1] for r in rows}
    print("\nstrokes/s %.0f, fits/s %.1f; glintd VmRSS %.0f MiB at the start, peak %.0f MiB"
          % (counts.get("POST strokes", 0) / wall,
             counts.get("POST fit (to its material)", 0) / wall, start_rss / 1024,
             max(peak) / 1024))
    if book.first_error:
        print("first error: " + book.first_error)
    return sum(r[2] for r in rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(SRC, "build"))
    ap.add_argument("--seconds", type=float, default=60)
    ap.add_argument("--painters", type=int, default=32)
    ap.add_argument("--scripts", type=int, default=4)
    ap.add_argument("--idle", type=int, default=1000)
    ap.add_argument("--think", type=float, default=50, help="ms between a painter's strokes")
    ap.add_argument("--res", type=int, default=64, help="the scripts' fit resolution")
    a = ap.parse_args()
    glintd = os.path.join(a.build, "server", "glintd")
    cli = os.path.join(a.build, "core", "glint")
    tmp = tempfile.mkdtemp(prefix="glint-load-")
    pngs = view0_pngs(cli, tmp)
    # twice what is held: at 3/4 of its limits glintd stops keeping
    # connections alive (http_front.h), which would close the idle ones
    conns = 2 * (a.idle + a.painters + 4 * a.scripts + 64)
    d = Daemon(glintd, tmp + "/data", 2, [
        "--max-connections", str(conns), "--max-connections-per-ip", str(conns),
        "--max-waiting-per-ip", str(conns)])
    d.start()
    bad = 0
    try:
        http = requests.Session()
        sc = check(http.post(d.base + API + "/scenes", json={"width": 256, "height": 256}),
                   201).json()
        sessions = [check(http.post(d.base + API + "/sessions", json={"scene_id": sc["id"]}),
                          201).json() for _ in range(8)]
        scripts = [new_session(http, d.base, sc["id"], tmp + "/png0", [0], "png")
                   for _ in range(a.scripts)]
        print("glintd load benchmark: %s; loadavg before %s" % (
            glintd, " ".join("%.2f" % x for x in os.getloadavg())))
        bad += phase("painters and scripts", d.base, d.proc.pid, sessions, scripts, pngs, a)
        idle = Idle(int(d.base.rsplit(":", 1)[1]), a.idle)
        t0 = time.time()
        idle.open()
        print("\n%d idle connections opened in %.1f s; glintd VmRSS %.0f MiB" % (
            a.idle, time.time() - t0, rss_kb(d.proc.pid) / 1024))
        bad += phase("the same with %d idle connections held" % a.idle, d.base, d.proc.pid,
                     sessions, scripts, pngs, a)
        held = idle.held()
        print("\nidle connections still open at the end: %d of %d (%d failed pings)" % (
            held, a.idle, idle.errors))
        bad += a.idle - held
        idle.close()
    finally:
        d.stop()
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
