"""The data directory's disk full, then read-only, under a real glintd.

Disk full: glintd runs with a file-size limit (RLIMIT_FSIZE, SIGXFSZ
ignored), so every write past it fails with EFBIG as on a full disk.
Read-only: glintd runs as another user (nobody) when the test is root, or
with the directory's write permissions removed otherwise.  In both:
  - reads still answer 200 (scenes, sessions, paintings, materials);
  - every write answers a problem naming the storage (507 storage-full or
    503 storage-read-only) and says what failed, never 500 or a crash;
  - glintd stays up (healthz);
and after a restart without the fault: everything acknowledged before is
there, the writes work again, and no temporary or orphan file is left
(test_crash_writes.orphans).
"""
import os
import random
import resource
import shutil
import signal
import sys
import time

sys.path.insert(0, os.path.dirname(__file__))
from harness import GLINTD, run_tests  # noqa: E402
from test_crash_writes import OWNER, orphans  # noqa: E402
from test_sessions import API, png_encode, tok  # noqa: E402

SIZE = 128


def noise(seed):
    """Pixels no compression shrinks much: a painting's file is then about
    its raw size (128 x 128 x 3 bytes as PNG: 48 KiB)."""
    rng = random.Random(seed)
    px = [[(rng.randrange(256), rng.randrange(256), rng.randrange(256)) for _ in range(SIZE)]
          for _ in range(SIZE)]
    return lambda x, y: px[y][x]


def setup_data(d):
    """A scene, a session with a painting and strokes, and a material."""
    sc = d.post(API + "/scenes", status=201, headers=OWNER,
                json={"width": SIZE, "height": SIZE}).json()
    s = d.post(API + "/sessions", status=201, json={"scene_id": sc["id"]}).json()
    h = tok(s["paint_token"])
    body = png_encode(SIZE, SIZE, noise(1))
    d.put("%s/sessions/%s/views/0/painting" % (API, s["id"]), status=200, data=body,
          headers=dict(h, **{"Content-Type": "image/png"}))
    d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), status=200, headers=h,
           json={"strokes": [{"color": [1, 0, 0], "diameter": 9, "points": [[40, 40]]}]})
    r = d.post("%s/sessions/%s/fits" % (API, s["id"]), headers=h, json={"params": {"res": 16}})
    assert r.status_code in (201, 202), r.text
    if r.status_code == 202:
        import time
        while True:
            j = d.get(r.json()["job"]["links"]["self"], status=200, headers=h).json()["job"]
            if j["state"] in ("done", "failed"):
                assert j["state"] == "done", j
                mid = j["material_id"]
                break
            time.sleep(0.05)
    else:
        mid = r.json()["id"]
    return sc, s, mid


def reads_work(d, sc, s, mid):
    h = tok(s["paint_token"])
    d.get("/healthz", status=200)
    d.get(API + "/scenes/" + sc["id"], status=200)
    d.get(API + "/sessions/" + s["id"], status=200, headers=h)
    r = d.get("%s/sessions/%s/views/0/painting" % (API, s["id"]), status=200, headers=h)
    assert r.headers["X-Glint-Painted"] == "1"
    d.get(API + "/materials/" + mid, status=200, headers=h)


def writes_fail(d, sc, s, kind, status):
    """Writes that need new space on the disk answer the storage's problem;
    small ones may still succeed (a row in the database's pages), but none
    answers anything else."""
    h = tok(s["paint_token"])
    big = [  # each writes a painting's file
        d.put("%s/sessions/%s/views/1/painting" % (API, s["id"]),
              data=png_encode(SIZE, SIZE, noise(2)),
              headers=dict(h, **{"Content-Type": "image/png"})),
        d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), headers=h,
               json={"strokes": [{"color": [0, 1, 0], "diameter": 30, "points": [[60, 60]]}]}),
    ]
    small = [d.post(API + "/scenes", json={"width": SIZE, "height": SIZE}),
             d.post(API + "/sessions", json={"scene_id": sc["id"]})]
    for r in big + small:
        if r in small and r.status_code == 201:
            continue
        assert r.status_code == status, (r.request.method, r.request.url, r.status_code, r.text)
        p = r.json()
        assert p["type"].endswith(kind), p
        assert "/tmp/" not in p["detail"], p  # the data directory is not shown
    d.get("/healthz", status=200)
    return sum(r.status_code == status for r in big + small)


def pixels_idle(d, timeout=30.0):
    """Wait until glintd keeps no painting's pixels in its queue or its hands."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        text = d.get("/metrics", status=200).text
        if ('glintd_painting_pixels_queue{state="queued"} 0' in text and
                'glintd_painting_pixels_queue{state="writing"} 0' in text):
            return
        time.sleep(0.02)
    raise AssertionError("the pixel writer did not go idle in %g s" % timeout)


def afterwards(d, sc, s, mid):
    reads_work(d, sc, s, mid)
    h = tok(s["paint_token"])
    d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), status=200, headers=h,
           json={"strokes": [{"color": [0, 0, 1], "diameter": 5, "points": [[20, 20]]}]})
    d.post(API + "/sessions", status=201, json={"scene_id": sc["id"]})
    pixels_idle(d)  # the stroke's pixels are written behind: a temporary file meanwhile
    bad = orphans(d.data_dir)
    assert not bad, bad
    leftovers = [f for _, _, fs in os.walk(d.data_dir) for f in fs if ".tmp-" in f]
    assert not leftovers, leftovers


def test_disk_full(d):
    sc, s, mid = setup_data(d)
    d.stop()
    limit = 40 << 10  # past the database's shared memory (32 KiB), short of a painting (48 KiB as PNG)

    def full():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    d.preexec = full
    d.start()
    try:
        reads_work(d, sc, s, mid)
        writes_fail(d, sc, s, "storage-full", 507)
    finally:
        d.stop()
        d.preexec = None
        d.start()
    afterwards(d, sc, s, mid)


def chown_tree(top, uid):
    for root, dirs, files in os.walk(top):
        for n in [root] + [os.path.join(root, f) for f in files]:
            os.chown(n, uid, uid)


def test_read_only_data_directory(d):
    """The directory turns read-only under a running glintd (a file system
    remounted read-only after an error): glintd runs as nobody on a
    directory it owns, which then passes to root (or, when the test is not
    root, loses its write permission)."""
    sc, s, mid = setup_data(d)
    d.stop()
    root = os.geteuid() == 0
    if root:
        os.chmod(d.tmp, 0o1777)  # the port file
        chown_tree(d.data_dir, 65534)
        # a copy nobody may run: the build may sit in a directory only root
        # enters (a checkout under a private temporary directory)
        d.glintd = os.path.join(d.tmp, "glintd")
        shutil.copy(GLINTD, d.glintd)
        os.chmod(d.glintd, 0o755)

        def nobody():
            os.setgroups([])
            os.setgid(65534)
            os.setuid(65534)
        d.preexec = nobody
    dirs = [r for r, _, _ in os.walk(d.data_dir)]
    d.start()
    try:
        h = tok(s["paint_token"])
        d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), status=200, headers=h,
               json={"strokes": [{"color": [0, 1, 1], "diameter": 4, "points": [[9, 9]]}]})
        if root:
            chown_tree(d.data_dir, 0)
        else:
            for n in dirs:
                os.chmod(n, 0o555)
        reads_work(d, sc, s, mid)
        assert writes_fail(d, sc, s, "storage-read-only", 503) >= 2
        d.stop()
        # started on it, glintd says why it cannot run
        try:
            d.start()
            started = True
        except RuntimeError:
            started = False
        if started:  # it may serve reads; writes are refused as above
            reads_work(d, sc, s, mid)
            writes_fail(d, sc, s, "storage-read-only", 503)
            d.stop()
        else:
            log = open(os.path.join(d.tmp, "glintd.log")).read()
            assert "readonly" in log or "read-only" in log or "Permission denied" in log, log[-500:]
    finally:
        if d.proc.poll() is None:
            d.stop()
        if not root:
            for n in dirs:
                os.chmod(n, 0o755)
        d.preexec = None
        d.glintd = GLINTD
        d.start()
    afterwards(d, sc, s, mid)


if __name__ == "__main__":
    run_tests(globals(), daemon_args=("--quiet",))
