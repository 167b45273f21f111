#!/usr/bin/env python3
"""What a shared database and a proxy cost a painter (run by hand, through
tests/with_postgres.sh, which starts the PostgreSQL server it needs).

For each setup, a painter posts one stroke at a time (one 3-point stroke of
diameter 6 on a 64x64 view) and the round trip is timed on the client:
  - sqlite:        one glintd, metadata in SQLite (the default);
  - postgresql:    one glintd, metadata in PostgreSQL (--database);
  - nginx+3:       three replicas on that database behind nginx
                   (deploy/nginx-replicas.conf), the stroke through nginx;
and, across replicas, how long a stroke posted to one replica takes to reach
an event stream open on another (the NOTIFY path), against the same on one
replica.  Every figure is a median and a p99 over --strokes strokes,
printed as a markdown table.

usage: tests/with_postgres.sh tests/bench/bench_replicas.py [--build DIR] [--strokes N]
"""
import argparse
import json
import os
import statistics
import sys
import threading
import time

import requests

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(SRC, "tests", "integration"))


def pct(xs, q):
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))]


def stroke(i):
    return {"color": [0.8, 0.3, 0.1], "diameter": 6,
            "points": [[8 + i % 48, 10], [12 + i % 48, 30], [20, 40 + i % 20]]}


def strokes_timed(base, sess, n):
    http = requests.Session()
    url = "%s/api/v1/sessions/%s/views/0/strokes" % (base, sess["id"])
    hdr = {"X-Glint-Token": sess["paint_token"]}
    out = []
    for i in range(n):
        t = time.perf_counter()
        r = http.post(url, json={"strokes": [stroke(i)]}, headers=hdr, timeout=30)
        out.append(time.perf_counter() - t)
        assert r.status_code == 200, r.text
    return out


def event_lag(poster, listener, sess, n):
    """Seconds from posting a stroke to `poster` until the event arrives on
    a stream open on `listener`."""
    got, ready = {}, threading.Event()
    since = requests.get("%s/api/v1/sessions/%s" % (listener, sess["id"]),
                         headers={"X-Glint-Token": sess["view_token"]},
                         timeout=30).json()["last_seq"]

    def read():
        r = requests.get("%s/api/v1/sessions/%s/events?since=%d" % (listener, sess["id"], since),
                         headers={"X-Glint-Token": sess["view_token"]}, stream=True, timeout=60)
        ready.set()
        ev = None
        for line in r.iter_lines(decode_unicode=True):
            if line.startswith("event: "):
                ev = line[7:]
            elif line.startswith("data: ") and ev == "stroke":
                got[json.loads(line[6:])["seq"]] = time.perf_counter()
                if len(got) >= n:
                    break
        r.close()

    th = threading.Thread(target=read, daemon=True)
    th.start()
    ready.wait(10)
    time.sleep(0.2)
    http = requests.Session()
    sent = {}
    for i in range(n):
        t = time.perf_counter()
        r = http.post("%s/api/v1/sessions/%s/views/1/strokes" % (poster, sess["id"]),
                      json={"strokes": [stroke(i)]},
                      headers={"X-Glint-Token": sess["paint_token"]}, timeout=30)
        sent[r.json()["first_seq"]] = t
        time.sleep(0.02)
    th.join(30)
    return [got[s] - sent[s] for s in sent if s in got]


def session(base):
    scene = requests.post(base + "/api/v1/scenes", json={"width": 64, "height": 64},
                          timeout=60).json()
    return requests.post(base + "/api/v1/sessions", json={"scene_id": scene["id"]},
                         timeout=60).json()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(SRC, "build"))
    ap.add_argument("--strokes", type=int, default=300)
    a = ap.parse_args()
    os.environ.setdefault("GLINTD", os.path.join(a.build, "server", "glintd"))
    os.environ.setdefault("GLINT_SOURCE_DIR", SRC)
    import harness
    from test_replicas import Cluster
    if not harness.PG:
        sys.exit("bench_replicas: run it through tests/with_postgres.sh")
    rows = []

    # one glintd on SQLite: the harness adds --database only when PG is set
    pg = harness.PG
    harness.PG = ""
    d = harness.Daemon("--quiet")
    harness.PG = pg
    s = session(d.base)
    strokes_timed(d.base, s, 20)
    rows.append(("sqlite, 1 glintd", strokes_timed(d.base, s, a.strokes),
                 event_lag(d.base, d.base, s, 50)))
    d.stop()

    d = harness.Daemon("--quiet")
    s = session(d.base)
    strokes_timed(d.base, s, 20)
    rows.append(("postgresql, 1 glintd", strokes_timed(d.base, s, a.strokes),
                 event_lag(d.base, d.base, s, 50)))
    d.stop()

    c = Cluster()
    try:
        s = session(c.front.base)
        strokes_timed(c.front.base, s, 20)
        times = strokes_timed(c.front.base, s, a.strokes)
        r0, r1 = c.replicas[0].base, c.replicas[1].base
        rows.append(("postgresql, 3 replicas behind nginx", times, event_lag(r1, r0, s, 50)))
    finally:
        c.stop()

    print("| setup | stroke round trip p50 (ms) | p99 (ms) | stroke to another stream "
          "p50 (ms) | p99 (ms) |")
    print("|---|---|---|---|---|")
    for name, t, lag in rows:
        print("| %s | %.2f | %.2f | %.1f | %.1f |" % (
            name, 1e3 * statistics.median(t), 1e3 * pct(t, 0.99),
            1e3 * statistics.median(lag), 1e3 * pct(lag, 0.99)))
    print("(%d strokes each; the last column of the replicas is a stroke posted to replica 1 "
          "reaching a stream on replica 0)" % a.strokes)


if __name__ == "__main__":
    main()
