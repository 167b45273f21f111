"""Replicas: three glintd processes on one PostgreSQL database and one
shared data directory, behind nginx routing each scene to one replica by
consistent hashing (deploy/nginx-replicas.conf), all on loopback and all
started here (PostgreSQL by tests/with_postgres.sh, which runs this file).

  - a scene's requests (its sessions, strokes, paintings, fits, materials,
    jobs) all reach one replica: their ids share the scene's routing digits;
  - painters on different replicas see each other live: a stream open on
    one replica receives strokes posted to the other two (PostgreSQL
    LISTEN/NOTIFY), and strokes posted at once to one view through two
    replicas all end up in its painting, in their numbered order;
  - killing the replica that holds a scene (SIGKILL, strokes in flight)
    loses no acknowledged stroke: nginx moves the scene to another replica,
    which reads its log from the database and its precomputation from the
    shared cache files instead of building it again.

Skipped (77) without GLINT_TEST_PG or without nginx (Debian: nginx)."""
import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

import requests

sys.path.insert(0, os.path.dirname(__file__))
from harness import PG, SRC, Daemon, fit_material, remove_dirs, validate  # noqa: E402
from test_crash import random_stroke, same_stroke, stored_strokes  # noqa: E402
from test_sessions import API, brush_apply, get_png, max_diff, to_float, tok  # noqa: E402

NGINX = shutil.which("nginx") or "/usr/sbin/nginx"
SIZE = 40
REPLICAS = 3


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Front:
    """nginx, spoken to like a Daemon (the harness's request helpers)."""
    request, get, post, put = Daemon.request, Daemon.get, Daemon.post, Daemon.put

    def __init__(self, upstreams):
        self.tmp = tempfile.mkdtemp(prefix="glint-nginx-")
        self.port = free_port()
        self.base = "http://127.0.0.1:%d" % self.port
        with open(os.path.join(SRC, "deploy", "nginx-replicas.conf")) as f:
            conf = f.read()
        lines = "\n        ".join("server 127.0.0.1:%d max_fails=1 fail_timeout=5s;" % p
                                 for p in upstreams)
        conf = (conf.replace("@PREFIX@", self.tmp).replace("@LISTEN@", "127.0.0.1:%d" % self.port)
                .replace("@UPSTREAMS@", lines))
        if os.geteuid() == 0:  # workers would drop to nobody, who cannot write tmp
            conf = "user root;\n" + conf
        with open(os.path.join(self.tmp, "nginx.conf"), "w") as f:
            f.write(conf)
        self.out = open(os.path.join(self.tmp, "nginx.out"), "wb")
        self.proc = subprocess.Popen([NGINX, "-p", self.tmp, "-c",
                                      os.path.join(self.tmp, "nginx.conf"), "-g", "daemon off;"],
                                     stdout=self.out, stderr=subprocess.STDOUT)
        deadline = time.time() + 20
        while True:
            try:
                requests.get(self.base + API + "/healthz", timeout=2)
                return
            except requests.RequestException:
                if self.proc.poll() is not None or time.time() > deadline:
                    with open(os.path.join(self.tmp, "nginx.out"), "rb") as f:
                        raise RuntimeError("nginx did not start: %r" % f.read()[-2000:])
                time.sleep(0.05)

    def stop(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGQUIT)
            try:
                self.proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
        self.out.close()
        shutil.rmtree(self.tmp, ignore_errors=True)


class Cluster:
    def __init__(self):
        self.tmp = tempfile.mkdtemp(prefix="glint-replicas-")
        self.data = os.path.join(self.tmp, "data")  # every replica's --data-dir
        self.replicas = [Daemon("--replica-name", "r%d" % i, "--quiet", data_dir=self.data)
                         for i in range(REPLICAS)]
        self.front = Front([r.port for r in self.replicas])

    def served(self, path, token):
        """The replica that answers a GET of `path` through nginx (its
        X-Glint-Replica), as an index."""
        r = self.front.get(path, status=200, headers=tok(token))
        return int(r.headers["X-Glint-Replica"][1:])

    def stop(self):
        self.front.stop()
        for r in self.replicas:
            r.stop()


def new_painting(c, d):
    scene = d.post(API + "/scenes", status=201, json={"width": SIZE, "height": SIZE}).json()
    sess = d.post(API + "/sessions", status=201, json={"scene_id": scene["id"]}).json()
    return scene, sess


def stream_events(d, sess, got, ready, stop):
    """Collect a session's stroke events from one replica's stream, until
    `stop` is set (checked at each line: the stream's keep-alives)."""
    r = requests.get("%s%s/sessions/%s/events" % (d.base, API, sess["id"]),
                     headers=tok(sess["view_token"]), stream=True, timeout=30)
    assert r.status_code == 200, r.text
    ready.set()
    ev = None
    try:
        for line in r.iter_lines(decode_unicode=True):
            if stop.is_set():
                break
            if line.startswith("event: "):
                ev = line[7:]
            elif line.startswith("data: ") and ev == "stroke":
                data = json.loads(line[6:])
                validate(data, "SessionEvent.json")
                got.append((time.time(), data))
    except requests.RequestException:
        pass  # the replica went away (the last test kills one)
    finally:
        r.close()


def test_a_scene_stays_on_one_replica(c):
    f = c.front
    scene, sess = new_painting(c, f)
    assert sess["id"][:8] == scene["id"][:8]
    for view in (0, 3):
        f.post("%s/sessions/%s/views/%d/strokes" % (API, sess["id"], view), status=200,
               json={"strokes": [{"color": [1, 0.5, 0.2], "diameter": 6,
                                  "points": [[10, 10], [30, 20]]}]},
               headers=tok(sess["paint_token"]))
    f.get("%s/sessions/%s/views/0/painting" % (API, sess["id"]), status=200,
          headers=tok(sess["view_token"]))
    mid = fit_material(f, sess, {"params": {"res": 8}})
    assert mid[:8] == scene["id"][:8]
    f.get(API + "/materials/" + mid, status=200, headers=tok(sess["view_token"]))
    paths = ["%s/scenes/%s/views/1/base.png" % (API, scene["id"]),
             "%s/sessions/%s" % (API, sess["id"]),
             "%s/sessions/%s/views/0/painting" % (API, sess["id"]),
             "%s/sessions/%s/strokes" % (API, sess["id"]),
             "%s/materials/%s" % (API, mid), "%s/materials/%s/factors.png" % (API, mid)]
    owners = [c.served(p, sess["view_token"]) for _ in range(3) for p in paths]
    print("scene %s...: %d requests, all answered by replica %s"
          % (scene["id"][:8], len(owners), sorted(set(owners))))
    assert len(set(owners)) == 1, owners
    # another scene's things may live elsewhere: the ring spreads scenes
    spread = set()
    for _ in range(12):
        s2, ss2 = new_painting(c, f)
        spread.add(c.served("%s/sessions/%s" % (API, ss2["id"]), ss2["view_token"]))
    assert len(spread) >= 2, spread


def test_painters_on_different_replicas_see_each_other_live(c):
    a, b, z = c.replicas
    scene, sess = new_painting(c, a)
    got, ready, stop = [], threading.Event(), threading.Event()
    th = threading.Thread(target=stream_events, args=(a, sess, got, ready, stop), daemon=True)
    th.start()
    assert ready.wait(60)
    sent = {}
    for i, d in enumerate((b, z, b, z)):
        t = time.time()
        r = d.post("%s/sessions/%s/views/2/strokes" % (API, sess["id"]), status=200,
                   json={"strokes": [{"color": [0.2, 0.9, 0.1], "diameter": 5, "tag": "r%d" % i,
                                      "points": [[5 + 8 * i, 20]]}]},
                   headers=tok(sess["paint_token"])).json()
        sent[r["first_seq"]] = t
    deadline = time.time() + 60  # (only catches a hang: they come at once)
    while len(got) < len(sent) and time.time() < deadline:
        time.sleep(0.02)
    stop.set()
    seqs = [e["seq"] for _, e in got]
    assert seqs == sorted(sent), "stream on replica 0 got %s, posted %s" % (seqs, sorted(sent))
    lag = [t - sent[e["seq"]] for t, e in got]
    print("strokes posted to replicas 1 and 2 reached a stream on replica 0 after %.0f ms "
          "at most" % (1000 * max(lag)))


def test_revoking_on_one_replica_ends_streams_on_another(c):
    a, b, _ = c.replicas
    scene, sess = new_painting(c, a)
    r = requests.get("%s%s/sessions/%s/events" % (a.base, API, sess["id"]),
                     headers=tok(sess["view_token"]), stream=True, timeout=30)
    assert r.status_code == 200
    ended = threading.Event()

    def drain():
        try:
            for _ in r.iter_lines():
                pass
        except requests.RequestException:
            pass
        ended.set()

    threading.Thread(target=drain, daemon=True).start()
    time.sleep(0.3)
    assert not ended.is_set()
    t0 = time.time()
    new = b.post("%s/sessions/%s/tokens" % (API, sess["id"]), status=200,
                 json={"revoke": "both"}, headers=tok(sess["paint_token"])).json()
    assert ended.wait(60), "the stream on replica 0 outlived the revocation on replica 1"
    print("tokens revoked on replica 1: the stream on replica 0 ended after %.0f ms"
          % (1000 * (time.time() - t0)))
    r.close()
    # the old token is refused everywhere, the new one works everywhere
    for d in (a, b):
        d.get("%s/sessions/%s" % (API, sess["id"]), status=403,
              headers=tok(sess["view_token"]))
        d.get("%s/sessions/%s" % (API, sess["id"]), status=200, headers=tok(new["view_token"]))


def test_strokes_at_once_through_two_replicas_all_reach_the_painting(c):
    a, b, z = c.replicas
    scene, sess = new_painting(c, a)
    _, (_, _, rows) = get_png(a, "%s/scenes/%s/views/1/base.png" % (API, scene["id"]))
    base = to_float(rows)
    errors = []

    def painter(d, seed):
        rng = random.Random(seed)
        http = requests.Session()
        for n in range(25):
            s = random_stroke(rng, seed * 1000 + n)
            r = http.post("%s%s/sessions/%s/views/1/strokes" % (d.base, API, sess["id"]),
                          json={"strokes": [s]}, headers=tok(sess["paint_token"]), timeout=30)
            if r.status_code != 200:
                errors.append(r.text[:300])

    ths = [threading.Thread(target=painter, args=(d, i + 1)) for i, d in enumerate((b, z))]
    for t in ths:
        t.start()
    for t in ths:
        t.join()
    assert not errors, errors
    stored, last = stored_strokes(a, sess)
    assert last == 50 and sorted(stored) == list(range(1, 51))
    want = [[list(p) for p in row] for row in base]
    for seq in sorted(stored):
        brush_apply(want, base, stored[seq][1])
    _, (_, _, got) = get_png(z, "%s/sessions/%s/views/1/painting" % (API, sess["id"]),
                             headers=tok(sess["view_token"]))
    diff = max_diff(want, to_float(got))
    assert diff <= 1.0 / 255 + 1e-9, "the painting differs from its 50 strokes by %g" % diff


def test_z_killing_a_replica_loses_no_stroke_and_moves_its_scenes(c):
    f = c.front
    scene, sess = new_painting(c, f)
    f.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=200,
           json={"strokes": [{"color": [0.9, 0.4, 0.1], "diameter": 9, "points": [[20, 20]]}]},
           headers=tok(sess["paint_token"]))
    first = fit_material(f, sess, {"params": {"res": 8}})
    owner = c.served("%s/materials/%s" % (API, first), sess["view_token"])
    victim = c.replicas[owner]
    acked, sent, stop = {}, {}, threading.Event()

    def poster():
        rng, n = random.Random(7), 0
        http = requests.Session()
        while not stop.is_set():
            s = random_stroke(rng, n)
            n += 1
            sent[s["tag"]] = s
            try:
                r = http.post("%s%s/sessions/%s/views/0/strokes" % (f.base, API, sess["id"]),
                              json={"strokes": [s]}, headers=tok(sess["paint_token"]),
                              timeout=30)
            except requests.RequestException:
                continue
            if r.status_code == 200:  # 502 while the replica dies: never acknowledged
                acked[r.json()["first_seq"]] = s

    th = threading.Thread(target=poster)
    th.start()
    time.sleep(1.0)
    before = len(acked)
    victim.kill9()
    time.sleep(2.0)
    stop.set()
    th.join(60)
    after = len(acked) - before
    stored, last = stored_strokes(f, sess)
    # one numbering for the session's log: 2 is the first fit's event
    missing = sorted(set(range(1, last + 1)) - set(stored))
    assert missing == [2], "gaps besides the fit's event: %s" % missing
    for seq, s in acked.items():
        assert seq in stored and same_stroke(s, stored[seq][1]), "acknowledged %d lost" % seq
    for seq, (_, s) in stored.items():
        assert seq == 1 or s["tag"] in sent, "stroke %d was never sent" % seq
    # the scene is served elsewhere now, from the shared cache files
    m2 = fit_material(f, sess, {"params": {"res": 8}})
    now = c.served("%s/materials/%s" % (API, m2), sess["view_token"])
    assert now != owner, (owner, now)
    m = f.get(API + "/materials/" + m2, status=200, headers=tok(sess["view_token"])).json()
    cache = m["precomputation"]["cache"]
    assert cache["memory"] == "built" and cache["disk"] == "loaded", cache
    print("replica %d killed: %d strokes acknowledged before, %d after (through replica %d); "
          "all %d stored; the next fit loaded the cache from disk"
          % (owner, before, after, now, len(stored)))


def main():
    if not PG:
        print("skipped: needs a PostgreSQL server (run through tests/with_postgres.sh)")
        sys.exit(77)
    if not os.path.exists(NGINX):
        print("skipped: nginx is not installed (apt install nginx)")
        sys.exit(77)
    c = Cluster()
    passed = failed = 0
    try:
        for name, fn in sorted(globals().items()):
            if not name.startswith("test_") or not callable(fn):
                continue
            try:
                fn(c)
                print("ok   " + name)
                passed += 1
            except Exception:
                import traceback
                print("FAIL " + name)
                traceback.print_exc(file=sys.stdout)
                failed += 1
            sys.stdout.flush()
    finally:
        c.stop()
    print("%d passed, %d failed" % (passed, failed))
    remove_dirs(failed, [c.tmp])
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
