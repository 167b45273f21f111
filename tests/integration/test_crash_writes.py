"""Crash test over every kind of write: rounds, each starting one write
(a scene made or deleted, a session, a painting uploaded, strokes, a fit and
its material, a mesh, an environment uploaded or deleted) and killing glintd
with SIGKILL at a random moment, before, during or after it.  The rounds
cover every kind of write with a kill in each of three windows (0-30 ms,
30-300 ms, 0.3-1.5 s after it starts: before it got far, in the middle of
a longer one, after a short one), in an order drawn at random: 27 rounds
(GLINT_CRASH_ROUNDS=N: N rounds, the same cover repeated, each repetition
in an order of its own; 100 or more for a long run).  The writes have what
they need from the start (a painted session, spare scenes and environments
to delete), so no round is spent on nothing.  After every restart:
  - every write answered 2xx is there, as answered: scenes, sessions, meshes,
    environments and materials readable (a material's files too), paintings
    at least at the acknowledged version, strokes at least to the
    acknowledged number; every acknowledged deletion stays deleted (one sent
    but unanswered may have happened or not, and then stays as it is found);
  - no orphan: each directory or file under blobs/ belongs to a row of the
    database (materials, scenes, meshes, paintings) or, for an uploaded
    environment, to its record; no temporary file of an interrupted atomic
    write is left.
Then the data is used once more (a fit of an acknowledged session).

GLINT_CRASH_SEED fixes the random choices; the seed used is printed.
"""
import os
import random
import sqlite3
import sys
import threading
import time

import requests

sys.path.insert(0, os.path.dirname(__file__))
from harness import PG, pg_query, run_tests  # noqa: E402
from test_sessions import API, png_encode, tok  # noqa: E402

KINDS = ["scene", "delete_scene", "session", "painting", "strokes", "fit", "mesh", "env",
         "delete_env"]
# when the kill lands after the write started (seconds): a write takes from a
# millisecond (a stroke) to a second (a cold fit)
WINDOWS = [(0, 0.03), (0.03, 0.3), (0.3, 1.5)]
ROUNDS = int(os.environ.get("GLINT_CRASH_ROUNDS", str(len(KINDS) * len(WINDOWS))))
SIZE = 32
OWNER = {"X-Glint-Owner": "crash-test-owner-key"}
OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def hdr(w, h):
    """A small Radiance HDR lat-long map (flat, uncompressed)."""
    return (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w)
            + bytes([128, 100, 64, 129]) * (w * h))


class State:
    """What the daemon acknowledged."""

    def __init__(self):
        self.scenes, self.deleted_scenes = [], []
        self.sessions = []          # dicts with id, paint_token, scene_id
        self.paint_version = {}     # (sid, view) -> acknowledged version
        self.last_seq = {}          # sid -> highest acknowledged stroke number
        self.materials = []         # (id, token)
        self.meshes = []
        self.envs, self.deleted_envs = [], []
        # deletions sent but not answered: done or not, as the kill fell
        self.maybe_deleted = set()


def live_sessions(st):
    return [s for s in st.sessions if s["scene_id"] not in st.deleted_scenes]


def write(kind, base, st, rng, acks):
    """Perform one write of `kind`; append what was acknowledged to acks
    (applied to the state only after the restart, by the main thread)."""
    http = requests.Session()
    url = base + API
    if kind == "scene":
        r = http.post(url + "/scenes", json={"width": SIZE, "height": SIZE,
                                             "mesh": rng.choice(["sphere", "torus"])},
                      headers=OWNER, timeout=30)
        if r.status_code == 201:
            acks.append(("scene", r.json()["id"]))
    elif kind == "delete_scene":
        # only scenes made for deleting: the sessions' scenes stay
        spare = [s for s in st.scenes if s not in st.deleted_scenes
                 and all(x["scene_id"] != s for x in st.sessions)]
        if spare:
            sid = rng.choice(spare)
            acks.append(("maybe_delete", sid))
            r = http.delete(url + "/scenes/" + sid, headers=OWNER, timeout=30)
            if r.status_code == 204:
                acks.append(("delete_scene", sid))
    elif kind == "session":
        scenes = [s for s in st.scenes if s not in st.deleted_scenes]
        if scenes:
            r = http.post(url + "/sessions", json={"scene_id": rng.choice(scenes)}, timeout=30)
            if r.status_code == 201:
                acks.append(("session", r.json()))
    elif kind == "painting":
        ss = live_sessions(st)
        if ss:
            s, view = rng.choice(ss), rng.randint(0, 11)
            shade = rng.randint(0, 255)
            body = png_encode(SIZE, SIZE, lambda x, y: (shade, (x * 7) % 256, (y * 7) % 256))
            r = http.put(url + "/sessions/%s/views/%d/painting" % (s["id"], view), data=body,
                         headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/png"}),
                         timeout=30)
            if r.status_code == 200:
                acks.append(("painting", (s["id"], view, r.json()["version"])))
    elif kind == "strokes":
        ss = live_sessions(st)
        if ss:
            s = rng.choice(ss)
            strokes = [{"color": [rng.random(), 0.5, 0.2], "diameter": rng.uniform(2, 9),
                        "points": [[rng.uniform(0, SIZE), rng.uniform(0, SIZE)]]}
                       for _ in range(rng.randint(1, 4))]
            r = http.post(url + "/sessions/%s/views/%d/strokes" % (s["id"], rng.randint(0, 11)),
                          json={"strokes": strokes}, headers=tok(s["paint_token"]), timeout=30)
            if r.status_code == 200:
                acks.append(("strokes", (s["id"], r.json()["last_seq"])))
    elif kind == "fit":
        ss = [s for s in live_sessions(st)
              if any(k[0] == s["id"] for k in st.paint_version)]
        if ss:
            s = rng.choice(ss)
            r = http.post(url + "/sessions/%s/fits" % s["id"], headers=tok(s["paint_token"]),
                          json={"params": {"res": 8}}, timeout=60)
            mid = None
            if r.status_code == 201:
                mid = r.json()["id"]
            elif r.status_code == 202:
                link = base + r.json()["job"]["links"]["self"]
                while True:
                    j = http.get(link, headers=tok(s["paint_token"]), timeout=30).json()["job"]
                    if j["state"] in ("done", "failed"):
                        mid = j.get("material_id")
                        break
                    time.sleep(0.005)
            if mid:
                acks.append(("material", (mid, s["paint_token"])))
    elif kind == "mesh":
        r = http.post(url + "/meshes?format=obj", data=OBJ, timeout=30)
        if r.status_code == 201:
            acks.append(("mesh", r.json()["id"]))
    elif kind == "env":
        r = http.post(url + "/environments", data=hdr(16, 8), headers=OWNER, timeout=30)
        if r.status_code == 201:
            acks.append(("env", r.json()["id"]))
    elif kind == "delete_env":
        live = [e for e in st.envs if e not in st.deleted_envs]
        if live:
            eid = rng.choice(live)
            acks.append(("maybe_delete", eid))
            r = http.delete(url + "/environments/" + eid, headers=OWNER, timeout=30)
            if r.status_code == 204:
                acks.append(("delete_env", eid))


def apply(st, acks):
    for kind, v in acks:
        if kind == "scene":
            st.scenes.append(v)
        elif kind == "delete_scene":
            st.deleted_scenes.append(v)
        elif kind == "session":
            st.sessions.append(v)
        elif kind == "painting":
            sid, view, ver = v
            st.paint_version[(sid, view)] = max(ver, st.paint_version.get((sid, view), 0))
        elif kind == "strokes":
            st.last_seq[v[0]] = max(v[1], st.last_seq.get(v[0], 0))
        elif kind == "material":
            st.materials.append(v)
        elif kind == "mesh":
            st.meshes.append(v)
        elif kind == "env":
            st.envs.append(v)
        elif kind == "delete_env":
            st.deleted_envs.append(v)
        elif kind == "maybe_delete":
            st.maybe_deleted.add(v)


def verify(d, st):
    for s in st.scenes:
        if s in st.maybe_deleted and s not in st.deleted_scenes:
            if d.get(API + "/scenes/" + s).status_code == 404:
                st.deleted_scenes.append(s)  # deleted before the kill, unanswered
            st.maybe_deleted.discard(s)
        d.get(API + "/scenes/" + s, status=404 if s in st.deleted_scenes else 200)
    for s in st.sessions:
        r = d.get(API + "/sessions/" + s["id"], status=200, headers=tok(s["paint_token"]))
        assert r.json()["id"] == s["id"]
    for (sid, view), ver in st.paint_version.items():
        s = next(x for x in st.sessions if x["id"] == sid)
        if s["scene_id"] in st.deleted_scenes:
            continue
        r = d.get("%s/sessions/%s/views/%d/painting" % (API, sid, view), status=200,
                  headers=tok(s["paint_token"]))
        assert int(r.headers["X-Glint-Version"]) >= ver, (sid, view, ver, r.headers)
    for sid, seq in st.last_seq.items():
        s = next(x for x in st.sessions if x["id"] == sid)
        r = d.get("%s/sessions/%s/strokes?since=%d&limit=10" % (API, sid, seq - 1), status=200,
                  headers=tok(s["paint_token"]))
        assert any(x["seq"] == seq for x in r.json()["strokes"]), (sid, seq)
    for mid, token in st.materials:
        d.get(API + "/materials/" + mid, status=200, headers=tok(token))
        d.get(API + "/materials/%s/factors.png" % mid, status=200, headers=tok(token))
    for m in st.meshes:
        d.get(API + "/meshes/" + m, status=200)
    envs = {e.get("id") for e in d.get(API + "/environments", headers=OWNER,
                                       status=200).json()["environments"]}
    for e in st.envs:
        if e in st.maybe_deleted and e not in st.deleted_envs:
            if e not in envs:
                st.deleted_envs.append(e)  # deleted before the kill, unanswered
            st.maybe_deleted.discard(e)
        assert (e in envs) == (e not in st.deleted_envs), (e, envs)


def orphans(data):
    """Files and directories under blobs/ that nothing refers to."""
    if PG:
        rows = lambda q: {r[0] for r in pg_query(os.path.realpath(data), q)}  # noqa: E731
    else:
        db = sqlite3.connect("file:%s/glint.db?mode=ro" % data, uri=True)
        rows = lambda q: {r[0] for r in db.execute(q)}  # noqa: E731
    materials, scenes = rows("SELECT id FROM materials"), rows("SELECT id FROM scenes")
    meshes, paintings = rows("SELECT id FROM meshes"), rows("SELECT blob FROM paintings")
    if not PG:
        db.close()
    blobs, bad = os.path.join(data, "blobs"), []
    for root, dirs, files in os.walk(blobs):
        for f in files + dirs:
            if ".tmp-" in f:
                bad.append(os.path.join(root, f))
    for kind, ids in (("materials", materials), ("scenes", scenes)):
        top = os.path.join(blobs, kind)
        for name in os.listdir(top) if os.path.isdir(top) else []:
            if name not in ids:
                bad.append("%s/%s" % (kind, name))
    top = os.path.join(blobs, "meshes")
    for name in os.listdir(top) if os.path.isdir(top) else []:
        if name.split(".")[0] not in meshes and ".tmp-" not in name:
            bad.append("meshes/" + name)
    top = os.path.join(blobs, "sessions")
    for sid in os.listdir(top) if os.path.isdir(top) else []:
        for name in os.listdir(os.path.join(top, sid)):
            # a painting's decoded pixels, "<blob>.px", belong to its blob's row
            blob = name[:-3] if name.endswith(".px") else name
            if "sessions/%s/%s" % (sid, blob) not in paintings and ".tmp-" not in name:
                bad.append("sessions/%s/%s" % (sid, name))
    top = os.path.join(blobs, "environments")
    names = os.listdir(top) if os.path.isdir(top) else []
    for name in names:
        stem = name.split(".")[0]
        if ".tmp-" in name:
            continue
        pair = [n for n in names if n.split(".")[0] == stem and ".tmp-" not in n]
        if len(pair) != 2:
            bad.append("environments/" + name)
    return bad


def schedule(rng, rounds):
    """`rounds` (kind, kill window) pairs: every pair once in each cycle, each
    cycle in an order of its own."""
    out = []
    while len(out) < rounds:
        cycle = [(k, w) for k in KINDS for w in WINDOWS]
        rng.shuffle(cycle)
        out += cycle
    return out[:rounds]


def describe(data, name):
    """What an orphan is: its age, its entries, and whether a row names it
    by now (a diagnosis for the failure message)."""
    path = os.path.join(data, "blobs", name)
    try:
        st = os.lstat(path)
    except OSError:
        return "gone"
    out = "mtime %.3f s ago" % (time.time() - st.st_mtime)
    if os.path.isdir(path):
        out += ", entries %s" % sorted(os.listdir(path))
    if name.startswith("materials/"):
        q = "SELECT count(*) FROM materials WHERE id = '%s'" % name.split("/")[1][:32]
        if PG:
            n = pg_query(os.path.realpath(data), q)[0][0]
        else:
            db = sqlite3.connect("file:%s/glint.db?mode=ro" % data, uri=True)
            n = db.execute(q).fetchone()[0]
            db.close()
        out += ", rows naming it now: %s" % n
    return out


def age_blobs(data, seconds=1200):
    """Every file and directory under blobs/ made `seconds` older."""
    old = time.time() - seconds
    for root, dirs, files in os.walk(os.path.join(data, "blobs")):
        for name in dirs + files:
            os.utime(os.path.join(root, name), (old, old), follow_symlinks=False)


def test_kill_during_every_kind_of_write(d):
    seed = int(os.environ.get("GLINT_CRASH_SEED", str(int(time.time()))))
    rng = random.Random(seed)
    print("seed %d" % seed)
    st = State()
    # something for every kind of write from the first round on: a session
    # with a painting (strokes, fits), a spare scene and an environment for
    # each deletion round (deletions pick among the spare ones)
    apply(st, [("scene", d.post(API + "/scenes", status=201, headers=OWNER,
                                json={"width": SIZE, "height": SIZE}).json()["id"])])
    s = d.post(API + "/sessions", status=201, json={"scene_id": st.scenes[0]}).json()
    apply(st, [("session", s)])
    cycles = -(-ROUNDS // (len(KINDS) * len(WINDOWS)))
    # (two spare scenes a deletion: a session round may take one for its own)
    for kind in ["painting"] + ["scene", "scene", "env"] * len(WINDOWS) * cycles:
        acks = []
        write(kind, d.base, st, rng, acks)
        assert acks, "the set-up's %s write was not acknowledged" % kind
        apply(st, acks)
    counts, killed_in_flight, t0 = {}, 0, time.time()
    for rnd, (kind, (lo, hi)) in enumerate(schedule(rng, ROUNDS)):
        acks = []
        th = threading.Thread(target=lambda: _safe(write, kind, d.base, st, rng, acks))
        th.start()
        time.sleep(rng.uniform(lo, hi))
        alive = th.is_alive()
        d.kill9()
        th.join(60)
        killed_in_flight += alive and not acks
        apply(st, acks)
        counts[kind] = counts.get(kind, 0) + 1
        if PG:
            # blobs shared by replicas are swept only past a grace (a young
            # file may be another replica's write in progress): age them
            age_blobs(d.data_dir)
        d.start()
        verify(d, st)
        bad = orphans(d.data_dir)
        assert not bad, "round %d (%s): orphans after recovery: %s" % (
            rnd, kind, [(b, describe(d.data_dir, b)) for b in bad[:10]])
    # the data is still good for work
    ss = [x for x in live_sessions(st) if any(k[0] == x["id"] for k in st.paint_version)]
    if ss:
        r = d.post("%s/sessions/%s/fits" % (API, ss[0]["id"]), headers=tok(ss[0]["paint_token"]),
                   json={"params": {"res": 8}})
        assert r.status_code in (201, 202), r.text
    print("%d rounds in %.1f s (%s); %d killed with the write in flight; acknowledged and "
          "present: %d scenes (%d deleted), %d sessions, %d paintings, %d stroke batches' "
          "sessions, %d materials, %d meshes, %d environments (%d deleted); no orphans"
          % (ROUNDS, time.time() - t0, ", ".join("%s %d" % kv for kv in sorted(counts.items())),
             killed_in_flight, len(st.scenes), len(st.deleted_scenes), len(st.sessions),
             len(st.paint_version), len(st.last_seq), len(st.materials), len(st.meshes),
             len(st.envs), len(st.deleted_envs)))


def _safe(fn, *args):
    try:
        fn(*args)
    except requests.RequestException:
        pass  # killed


if __name__ == "__main__":
    run_tests(globals(), daemon_args=("--quiet",))
