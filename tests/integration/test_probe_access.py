"""Who may do what, and how much one request may cost: the owner model of
scenes, admission of expensive work against a memory budget, the bound on
brush work per request, the media type of a painting, and error details
that never show where the server keeps its data.

Each test reproduces a request of an outside probe and asserts the safe
answer: its status, an RFC 9457 problem+json body (validated against
proto/schemas/Problem.json by the harness) and, where it matters, the
daemon's memory or time.
"""
import concurrent.futures as cf
import json
import os
import re
import struct
import sys
import time
import zlib

sys.path.insert(0, os.path.dirname(__file__))
from harness import Daemon, run_tests  # noqa: E402

API = "/api/v1"
SIZE = 48


def problem(r, status, kind=None):
    assert r.status_code == status, "status %d, want %d: %s" % (r.status_code, status, r.text[:400])
    assert r.headers.get("Content-Type", "").startswith("application/problem+json"), r.headers
    body = r.json()
    if kind:
        assert body["type"].endswith(kind), "type %s, want %s" % (body["type"], kind)
    return body


def owner(name):
    return {"X-Glint-Owner": ("owner-%s-" % name).ljust(24, "x")}


def scene(d, headers=None, **body):
    body.setdefault("width", SIZE)
    body.setdefault("height", SIZE)
    return d.post(API + "/scenes", status=201, schema="Scene.json", json=body,
                  headers=headers or {}).json()


def session(d, sc):
    return d.post(API + "/sessions", status=201, schema="Session.json",
                  json={"scene_id": sc["id"]}).json()


def tok(s):
    return {"X-Glint-Token": s["paint_token"]}


def paint(d, s, k=0, diameter=30):
    c = SIZE // 2
    return d.post("%s/sessions/%s/views/%d/strokes" % (API, s["id"], k), status=200,
                  headers=tok(s),
                  json={"strokes": [{"color": [0.8, 0.5, 0.3], "diameter": diameter,
                                     "points": [[c, c], [c + 4, c + 2]]}]})


def rss_kb(d, field="VmRSS"):
    with open("/proc/%d/status" % d.proc.pid) as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise AssertionError("no %s" % field)


def work_counts(d):
    """glintd's admission counters (/metrics): admitted, over_budget, busy
    (pieces of work) and peak (bytes held at most)."""
    m = d.get("/metrics", status=200).text
    out = {k: int(re.search(r'glintd_work_total\{outcome="%s"\} (\d+)' % k, m).group(1))
           for k in ("admitted", "over_budget", "busy")}
    out["peak"] = int(re.search(r"glintd_work_peak_bytes (\d+)", m).group(1))
    return out


def png_bytes(w, h):
    raw = b"".join(b"\x00" + b"\x80\x40\x20" * w for _ in range(h))

    def chunk(t, data):
        return struct.pack(">I", len(data)) + t + data + struct.pack(">I", zlib.crc32(t + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


# ---------------------------------------------------------------------------
# item 3: the owner model (listing, deleting)
# ---------------------------------------------------------------------------


def test_list_needs_an_owner_key_and_shows_only_the_owners(d):
    a = scene(d, owner("alice"))
    b = scene(d, owner("bob"))
    anon = scene(d)  # no key sent: the daemon makes one and answers it once
    assert a["owner_key"] == owner("alice")["X-Glint-Owner"]
    assert re.fullmatch(r"[0-9a-f]{32}", anon["owner_key"])
    # the probe's request: a stranger lists every scene id
    r = d.get(API + "/scenes")
    p = problem(r, 401, "owner-key-required")
    assert "X-Glint-Owner" in p["detail"]
    assert a["id"] not in r.text and b["id"] not in r.text
    la = d.get(API + "/scenes", status=200, schema="SceneList.json", headers=owner("alice")).json()
    assert [x["id"] for x in la["scenes"]] == [a["id"]] and la["count"] == 1
    lb = d.get(API + "/scenes", status=200, headers=owner("bob")).json()
    assert [x["id"] for x in lb["scenes"]] == [b["id"]]
    ln = d.get(API + "/scenes", status=200, headers={"X-Glint-Owner": anon["owner_key"]}).json()
    assert [x["id"] for x in ln["scenes"]] == [anon["id"]]
    # an owner nobody used sees nothing; keys are never shown again
    assert d.get(API + "/scenes", status=200, headers=owner("carol")).json()["count"] == 0
    for sc in (a, b, anon):
        g = d.get(API + "/scenes/" + sc["id"], status=200, schema="Scene.json").json()
        assert "owner_key" not in g and "owner" not in g and sc["owner_key"] not in json.dumps(g)


def test_malformed_owner_keys_are_refused(d):
    for bad in ("short", "x" * 129, "has space in it ok", "semi;colon-and-more", "ünïcode-key-long"):
        h = {"X-Glint-Owner": bad.encode("utf-8").decode("latin-1")}
        problem(d.get(API + "/scenes", headers=h), 422, "invalid-owner-key")
        problem(d.post(API + "/scenes", json={"width": SIZE, "height": SIZE}, headers=h), 422,
                "invalid-owner-key")


def test_delete_needs_the_owner_key(d):
    a = scene(d, owner("dana"))
    s = session(d, a)
    paint(d, s)
    # the probe's request: DELETE without credentials destroyed the scene
    p = problem(d.delete(API + "/scenes/" + a["id"]), 401, "owner-key-required")
    assert "owner key" in p["detail"]
    problem(d.delete(API + "/scenes/" + a["id"], headers=owner("eve")), 403, "not-owner")
    # a paint token of one of its sessions does not own the scene
    problem(d.delete(API + "/scenes/" + a["id"], headers=tok(s)), 401, "owner-key-required")
    # nothing was lost
    d.get(API + "/scenes/" + a["id"], status=200)
    d.get("%s/sessions/%s/strokes" % (API, s["id"]), status=200, headers=tok(s))
    d.delete(API + "/scenes/" + a["id"], status=204, headers=owner("dana"))
    d.get(API + "/scenes/" + a["id"], status=404)
    d.get("%s/sessions/%s" % (API, s["id"]), status=404, headers=tok(s))


def test_api_key_lists_and_deletes_everything(d):
    k = Daemon("--api-key", "probe-api-key-0123", "--quiet")
    try:
        key = {"X-Api-Key": "probe-api-key-0123"}
        a = scene(k, dict(key, **owner("fay")))
        b = scene(k, dict(key, **owner("gus")))
        problem(k.get(API + "/scenes"), 401, "owner-key-required")
        mine = k.get(API + "/scenes", status=200, headers=owner("fay")).json()
        assert [x["id"] for x in mine["scenes"]] == [a["id"]]
        every = k.get(API + "/scenes", status=200, schema="SceneList.json", headers=key).json()
        assert {x["id"] for x in every["scenes"]} == {a["id"], b["id"]}
        problem(k.delete(API + "/scenes/" + b["id"], headers=owner("fay")), 403, "not-owner")
        k.delete(API + "/scenes/" + b["id"], status=204, headers=key)
        k.delete(API + "/scenes/" + a["id"], status=204, headers=owner("fay"))
    finally:
        k.stop()


# ---------------------------------------------------------------------------
# item 4: expensive work against a memory budget
# ---------------------------------------------------------------------------


def fitted_material(d):
    sc = scene(d)
    s = session(d, sc)
    paint(d, s)
    r = d.post("%s/sessions/%s/fits" % (API, s["id"]), headers=tok(s), json={"params": {"res": 16}})
    assert r.status_code in (201, 202), r.text
    if r.status_code == 201:
        return sc, s, r.json()["id"]
    job = r.json()["job"]["id"]
    for _ in range(600):
        j = d.get("%s/jobs/%s" % (API, job), status=200, headers=tok(s)).json()["job"]
        if j["state"] == "done":
            return sc, s, j["material_id"]
        assert j["state"] != "failed", j
        time.sleep(0.05)
    raise AssertionError("fit job did not finish")


def test_previews_beyond_the_budget_get_503_and_memory_stays_bounded(d):
    budget_mb = 400
    w = Daemon("--work-mb", str(budget_mb), "--work-slots", "4", "--work-wait", "0", "--quiet")
    try:
        sc, s, mid = fitted_material(w)
        url = "%s/materials/%s/preview.png?view=0&size=%d&renderer=cpu"
        # one piece that can never fit: 413 at once, naming the budget
        m0 = work_counts(w)
        problem(w.get(url % (API, mid, 4608), headers=tok(s)), 422)  # size beyond the max
        # (an EGL preview is bounded by 40 B/pixel: 640 MiB at 4096^2, admitted
        # or refused before any rendering, so whether EGL works here or not)
        r = w.get(API + "/materials/%s/preview.exr?view=0&size=4096&renderer=egl" % mid,
                  headers=tok(s))
        p = problem(r, 413, "over-budget")
        assert "--work-mb" in p["detail"] and "400 MiB" in p["detail"], p
        # at once: refused before any work was admitted or memory held
        m1 = work_counts(w)
        assert m1["over_budget"] == m0["over_budget"] + 1, (m0, m1)
        assert (m1["admitted"], m1["peak"]) == (m0["admitted"], m0["peak"]), (m0, m1)
        base = rss_kb(w)
        # the probe's request: four 4096^2 previews at once (335 MB bound each on
        # the CPU): one runs, the others are refused with Retry-After
        with cf.ThreadPoolExecutor(4) as ex:
            rs = list(ex.map(lambda _: w.get(url % (API, mid, 4096), headers=tok(s)), range(4)))
        codes = sorted(r.status_code for r in rs)
        assert codes.count(200) >= 1 and codes.count(503) >= 1, codes
        assert set(codes) <= {200, 503}, codes
        for r in rs:
            if r.status_code == 503:
                p = problem(r, 503, "busy")
                assert r.headers.get("Retry-After", "").isdigit(), r.headers
                assert "MiB" in p["detail"] and "try again" in p["detail"], p
        peak = rss_kb(w, "VmHWM")
        # the stated bound: the work budget plus 200 MB (heap kept by the
        # allocator, the encoder's buffers) over the resident set before
        assert peak - base < (budget_mb + 200) * 1024, (base, peak)
        m = w.get("/metrics", status=200).text
        assert re.search(r'glintd_work_total\{outcome="busy"\} [1-9]', m), m
        assert "glintd_work_budget_bytes %d" % (budget_mb << 20) in m
        # once the work is done, the budget is free again
        held = re.search(r"glintd_work_held_bytes (\d+)", m).group(1)
        assert held == "0", held
        w.get(url % (API, mid, 1024), status=200, headers=tok(s))
    finally:
        w.stop()


def test_requests_wait_for_room_within_work_wait(d):
    # the studio asks for every view's base render at once: with one slot they
    # take turns instead of failing
    w = Daemon("--work-slots", "1", "--work-wait", "20", "--quiet")
    try:
        sc = scene(w, width=96, height=96)
        urls = ["%s/scenes/%s/views/%d/base.png?format=exr" % (API, sc["id"], k) for k in range(12)]
        with cf.ThreadPoolExecutor(12) as ex:
            codes = list(ex.map(lambda u: w.get(u).status_code, urls))
        assert codes == [200] * 12, codes
        m = w.get("/metrics").text
        assert re.search(r"glintd_work_waited_total [1-9]", m), m
        assert re.search(r'glintd_work_total\{outcome="busy"\} 0', m), m
    finally:
        w.stop()


def test_gbuffer_and_base_renders_are_admitted(d):
    w = Daemon("--work-mb", "64", "--quiet")
    try:
        one = [{"eye": [0, -3, 1], "light": [2, -2, 2]}]
        # (a scene whose own base render, 16 MiB + 72 B x 1024^2 = 88 MiB, could
        # never be admitted is refused when it is made: test_probe_errors.py)
        big = scene(w, width=640, height=640, views=one)
        # G-buffer bound: 16 MiB + 224 B x 640^2 = 104 MiB
        p = problem(w.get("%s/scenes/%s/views/0/gbuffer.exr" % (API, big["id"])), 413,
                    "over-budget")
        assert "G-buffer" in p["detail"] and "64 MiB" in p["detail"]
        # a base render with other settings: 16 MiB + 72 B x 640^2 = 44 MiB, and
        # 8 B x 16 groups of lights x 640^2 = 50 MiB more under an environment
        w.get("%s/scenes/%s/views/0/base.png" % (API, big["id"]), status=200)
        problem(w.get("%s/scenes/%s/views/0/base.png?brdf=lambert:kd=0.5&env=sky&lights=1024"
                      % (API, big["id"])), 413, "over-budget")
        small = scene(w, width=64, height=64)
        w.get("%s/scenes/%s/views/0/gbuffer.exr" % (API, small["id"]), status=200)
        w.get("%s/scenes/%s/views/0/base.png?brdf=lambert:kd=0.5" % (API, small["id"]), status=200)
    finally:
        w.stop()


def test_fits_beyond_the_budget_are_refused_up_front(d):
    w = Daemon("--work-mb", "64", "--quiet")
    try:
        sc = scene(w, width=64, height=64)
        s = session(w, sc)
        for k in range(12):
            paint(w, s, k)
        # the svd route's dense matrix: 48 bytes per sample and texel, about
        # 8,000 samples x 768 texels here
        r = w.post("%s/sessions/%s/fits" % (API, s["id"]), headers=tok(s),
                   json={"params": {"route": "svd", "res": 256}})
        p = problem(r, 413, "over-budget")
        assert "fit" in p["detail"] and "--work-mb" in p["detail"]
        m = w.get("/metrics").text  # no job was started for it
        assert re.search(r'glintd_jobs(_finished_total)?\{state="\w+"\} [1-9]', m) is None, m
        # the same paintings within the budget fit
        r = w.post("%s/sessions/%s/fits" % (API, s["id"]), headers=tok(s),
                   json={"params": {"res": 16}})
        assert r.status_code in (201, 202), r.text
    finally:
        w.stop()


# ---------------------------------------------------------------------------
# item 5: brush work per request
# ---------------------------------------------------------------------------


def test_a_huge_stroke_is_refused_quickly_and_blocks_nothing(d):
    sc = scene(d, width=256, height=256)
    s = session(d, sc)
    pts = [[(i * 37) % 256, (i * 91) % 256] for i in range(10000)]
    r = d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), headers=tok(s),
               json={"strokes": [{"color": [1, 0, 0], "diameter": 65536, "points": pts}]})
    p = problem(r, 413, "too-much-brush-work")
    assert "max-stroke-work" in p["detail"], p
    # refused up front: the request's steps (Server-Timing) end with the
    # parse, before the session's lock, the painting's read and any brush
    # work (a wall-clock bound here failed under ASAN on a slow machine)
    steps = [x.split(";")[0].strip() for x in r.headers.get("Server-Timing", "").split(",")]
    assert steps == ["session", "parse"], r.headers.get("Server-Timing")
    # nothing was applied, and the session's next stroke goes through
    assert d.get("%s/sessions/%s/strokes" % (API, s["id"]), headers=tok(s),
                 status=200).json()["strokes"] == []
    r = paint(d, s, 0, diameter=8)
    steps = [x.split(";")[0].strip() for x in r.headers.get("Server-Timing", "").split(",")]
    assert "apply" in steps and "store" in steps, r.headers.get("Server-Timing")
    # the same stroke with a brush the raster can hold is fine
    d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), headers=tok(s), status=200,
           json={"strokes": [{"color": [1, 0, 0], "diameter": 4, "points": pts[:2000]}]})


# ---------------------------------------------------------------------------
# item 8: a painting's Content-Type
# ---------------------------------------------------------------------------


def test_painting_content_type_must_match_its_bytes(d):
    sc = scene(d)
    s = session(d, sc)
    url = "%s/sessions/%s/views/0/painting" % (API, s["id"])
    png = png_bytes(SIZE, SIZE)
    # the probe's request: a PNG said to be something else
    p = problem(d.put(url, data=png, headers=dict(tok(s), **{"Content-Type": "text/plain"})), 415,
                "unsupported-media-type")
    assert "text/plain" in p["detail"]
    p = problem(d.put(url, data=png, headers=dict(tok(s), **{"Content-Type": "image/x-exr"})), 415,
                "unsupported-media-type")
    assert "PNG" in p["detail"]
    problem(d.put(url, data=png, headers=dict(tok(s), **{"Content-Type": "application/json"})), 415)
    # bytes of no accepted format, whatever the type says
    problem(d.put(url, data=b"GIF89a" + b"\0" * 64, headers=tok(s)), 422, "invalid-image")
    problem(d.put(url, data=b"GIF89a" + b"\0" * 64,
                  headers=dict(tok(s), **{"Content-Type": "image/png"})), 415)
    # nothing was stored by the refusals
    assert d.get("%s/sessions/%s" % (API, s["id"]), headers=tok(s)).json()["last_seq"] == 0
    for ct in ("image/png", "IMAGE/PNG; charset=binary", "application/octet-stream", None):
        h = dict(tok(s))
        if ct:
            h["Content-Type"] = ct
        d.put(url, data=png, headers=h, status=200)
    exr = d.get(url + "?format=exr", headers=tok(s), status=200).content
    d.put(url, data=exr, headers=dict(tok(s), **{"Content-Type": "image/x-exr"}), status=200)


# ---------------------------------------------------------------------------
# item 10: error details never show the server's paths
# ---------------------------------------------------------------------------


def test_errors_never_show_the_data_directory(d):
    w = Daemon("--quiet")
    try:
        sc = scene(w)
        s = session(w, sc)
        paint(w, s)
        data = os.path.realpath(w.data_dir)
        # make the materials' directory unusable (a file in its place: even
        # root cannot create files below it)
        mats = os.path.join(w.data_dir, "blobs", "materials")
        os.makedirs(os.path.dirname(mats), exist_ok=True)
        if os.path.isdir(mats):
            os.rename(mats, mats + ".away")
        with open(mats, "w") as f:
            f.write("not a directory\n")
        texts = []
        for _ in range(2):  # the first fit runs as a job, the second in the request
            r = w.post("%s/sessions/%s/fits" % (API, s["id"]), headers=tok(s),
                       json={"params": {"res": 16}})
            texts.append(r.text)
            if r.status_code == 202:
                job = r.json()["job"]["id"]
                for _ in range(600):
                    j = w.get("%s/jobs/%s" % (API, job), status=200, headers=tok(s))
                    if j.json()["job"]["state"] in ("done", "failed"):
                        break
                    time.sleep(0.05)
                texts.append(j.text)
                assert j.json()["job"]["state"] == "failed", j.text
            else:
                problem(r, r.status_code)
                assert r.status_code >= 500, r.text
        joined = "\n".join(texts)
        for path in {data, w.data_dir, w.tmp, os.path.realpath(w.tmp)}:
            assert path not in joined, (path, joined)
        assert "<data>" in joined, joined
    finally:
        w.stop()


if __name__ == "__main__":
    run_tests(globals())
