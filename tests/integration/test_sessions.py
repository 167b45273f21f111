"""Scenes, meshes, sessions, paintings, limits, the API key and restarts
over real HTTP.

Every endpoint of api_scenes.c and api_sessions.c is driven against the
real daemon; every JSON answer is validated against its schema in
proto/schemas (problem bodies against Problem.json, by the harness),
including errors: malformed JSON, wrong types, unknown ids, oversize
uploads, numbers JSON cannot carry (1e999), strings for numbers.  Strokes
and the event stream are in test_sessions_live.py, which uses the helpers
below, among them an independent Python implementation of the brush of
core/truth/stroke.h (test_crash.py uses it too).
Pure Python (no numpy): small PNG and OpenEXR codecs are below.
"""
import json
import math
import os
import struct
import sys
import time
import zlib

sys.path.insert(0, os.path.dirname(__file__))
from harness import Daemon, png_unfilter, run_tests  # noqa: E402
import exr_named  # noqa: E402

API = "/api/v1"
JSON = {"Content-Type": "application/json"}
W = H = 48  # raster of the test scenes (small: the Python brush is slow)

# ---------------------------------------------------------------------------
# PNG and OpenEXR in pure Python
# ---------------------------------------------------------------------------


def png_decode(data):
    """8-bit PNG (grey, RGB, RGBA; not interlaced) -> (w, h, rows of [r,g,b])."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and interlace == 0 and ctype in (0, 2, 6), (depth, ctype)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    bpp = {0: 1, 2: 3, 6: 4}[ctype]
    rows = [[[line[x * bpp + (0 if bpp == 1 else ch)] for ch in range(3)] for x in range(w)]
            for line in png_unfilter(zlib.decompress(idat), w, h, bpp)]
    return w, h, rows


def png_encode(w, h, pixel):
    """RGB 8-bit PNG of pixel(x, y) -> (r, g, b) in 0..255."""
    raw = b"".join(b"\x00" + bytes(v for x in range(w) for v in pixel(x, y)) for y in range(h))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(
            ">I", zlib.crc32(kind + body) & 0xffffffff)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def exr_encode(w, h, pixel):
    """Uncompressed scanline OpenEXR, float channels B, G, R, of
    pixel(x, y) -> (r, g, b) floats (NaN and infinities allowed)."""
    px = [pixel(x, y) for y in range(h) for x in range(w)]
    return exr_named.write(w, h, {n: [p[c] for p in px] for n, c in (("R", 0), ("G", 1), ("B", 2))})


# ---------------------------------------------------------------------------
# The brush of core/truth/stroke.h, reimplemented independently (used by
# test_sessions_live.py and test_crash.py)
# ---------------------------------------------------------------------------


def stroke_distance(pts, px, py):
    best = math.inf
    segs = [(pts[i], pts[i + 1]) for i in range(len(pts) - 1)] if len(pts) > 1 else [(pts[0], pts[0])]
    for (ax, ay), (bx, by) in segs:
        vx, vy = bx - ax, by - ay
        l2 = vx * vx + vy * vy
        t = 0.0
        if l2 > 0:
            t = min(1.0, max(0.0, ((px - ax) * vx + (py - ay) * vy) / l2))
        dx, dy = px - (ax + t * vx), py - (ay + t * vy)
        best = min(best, dx * dx + dy * dy)
    return math.sqrt(best)


def brush_apply(img, base, s):
    """Apply stroke dict s to img (rows of [r,g,b] floats) in place."""
    h, w = len(img), len(img[0])
    r = s["diameter"] / 2
    mode = s.get("mode", "paint")
    op, kappa = s.get("opacity", 1.0), s.get("kappa", 0.0)
    xs = [p[0] for p in s["points"]]
    ys = [p[1] for p in s["points"]]
    x0, x1 = max(0, math.ceil(min(xs) - r - 0.5)), min(w - 1, math.floor(max(xs) + r - 0.5))
    y0, y1 = max(0, math.ceil(min(ys) - r - 0.5)), min(h - 1, math.floor(max(ys) + r - 0.5))
    for y in range(y0, y1 + 1):
        for x in range(x0, x1 + 1):
            d = stroke_distance(s["points"], x + 0.5, y + 0.5)
            if not d <= r:
                continue
            wt = op * math.exp(-kappa * d)
            for c in range(3):
                old = img[y][x][c]
                if mode == "paint":
                    img[y][x][c] = wt * s["color"][c] + (1 - wt) * old
                elif mode == "scale":
                    img[y][x][c] = wt * s["scale"] * old + (1 - wt) * old
                else:
                    img[y][x][c] = wt * base[y][x][c] + (1 - wt) * old


def to_float(rows):
    return [[[v / 255.0 for v in p] for p in row] for row in rows]


def max_diff(a, b):
    """Largest difference between float rows a and 8-bit-as-float rows b,
    with a clamped to [0, 1] like a PNG."""
    return max(abs(min(1.0, max(0.0, a[y][x][c])) - b[y][x][c])
               for y in range(len(a)) for x in range(len(a[0])) for c in range(3))


# ---------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------

_cache = {}


def new_scene(d, **body):
    body.setdefault("width", W)
    body.setdefault("height", H)
    r = d.post(API + "/scenes", status=201, schema="Scene.json", json=body)
    return r.json()


def shared(d):
    """One scene and session shared by the tests that only read."""
    if "scene" not in _cache:
        _cache["scene"] = new_scene(d)
        _cache["session"] = new_session(d, _cache["scene"]["id"])
    return _cache["scene"], _cache["session"]


def new_session(d, scene_id, headers=None):
    r = d.post(API + "/sessions", status=201, schema="Session.json", json={"scene_id": scene_id},
               headers=headers)
    return r.json()


def tok(t):
    return {"X-Glint-Token": t}


def post_strokes(d, sess, view, strokes, status=200, token=None, **kw):
    return d.post("%s/sessions/%s/views/%d/strokes" % (API, sess["id"], view), status=status,
                  schema="StrokesPosted.json" if status == 200 else None,
                  json={"strokes": strokes}, headers=tok(token or sess["paint_token"]), **kw)


def get_png(d, path, headers=None):
    r = d.get(path, status=200, headers=headers)
    assert r.headers["Content-Type"] == "image/png", r.headers
    return r, png_decode(r.content)


def detail(r):
    return r.json()["detail"]


# ---------------------------------------------------------------------------
# scenes
# ---------------------------------------------------------------------------


def test_scene_create_defaults(d):
    s = new_scene(d)
    assert s["mesh"] == "sphere" and s["view_set"] == "ico12" and len(s["views"]) == 12
    assert s["width"] == W and s["height"] == H
    assert s["samples"] == sum(v["samples"] for v in s["views"]) > 0
    assert all(v["samples"] > 0 for v in s["views"])
    assert "scene" not in s  # internal document not exposed
    r = d.get(API + "/scenes/" + s["id"], status=200, schema="Scene.json")
    owner = s.pop("owner_key")  # only the creation answer carries it
    assert r.json() == s and "owner" not in r.text
    lst = d.get(API + "/scenes", status=200, schema="SceneList.json",
                headers={"X-Glint-Owner": owner}).json()
    assert [x["id"] for x in lst["scenes"]] == [s["id"]] and lst["count"] == 1
    # same geometry, same hash (the key of every precomputation)
    assert new_scene(d)["hash"] == s["hash"]


def test_scene_variants(d):
    t = new_scene(d, mesh="torus", views="ico20", light_angles=[30, 60], width=32, height=24)
    assert t["mesh"] == "torus" and len(t["views"]) == 20 and t["width"] == 32 and t["height"] == 24
    assert abs(t["views"][0]["light_deg"] - 30) < 1e-9 and abs(t["views"][19]["light_deg"] - 60) < 1e-9
    tp = new_scene(d, mesh="teapot", width=16, height=16)
    assert tp["mesh"] == "teapot" and tp["hash"] != t["hash"]
    e = new_scene(d, views=[{"eye": [0, -3, 1], "light": [2, -2, 2]},
                            {"eye": [3, 0, 0], "target": [0, 0, 0.1], "light": [3, 1, 1],
                             "half_fov": 0.4, "light_intensity": 2}])
    assert e["view_set"] == "explicit" and len(e["views"]) == 2
    v0, v1 = e["views"]
    assert v0["target"] == [0, 0, 0] and abs(math.tan(v0["half_fov"]) - 1.1 / math.sqrt(10 - 1)) < 1e-12
    assert v1["half_fov"] == 0.4 and v1["light_intensity"] == 2
    b = new_scene(d, base={"brdf": "ct:rough=0.3,kd=0.4", "scale": 2})
    assert b["base"] == {"brdf": "ct:rough=0.3,kd=0.4", "scale": 2}


def test_scene_create_errors(d):
    p = API + "/scenes"
    r = d.post(p, status=400, data=b'{"width": 64,', headers=JSON)
    assert "malformed JSON" in detail(r)
    d.post(p, status=400, data=b'{"width": 1e999}', headers=JSON)  # jansson: overflow
    d.post(p, status=415, data=b'{}', headers={"Content-Type": "text/plain"})
    d.post(p, status=422, data=b'[1, 2]', headers=JSON)
    r = d.post(p, status=422, json={"width": "64"})
    assert "width: expected an integer, got a string" in detail(r)
    r = d.post(p, status=422, json={"width": 64.5})
    assert "width" in detail(r)
    r = d.post(p, status=422, json={"width": 5000})
    assert "max_image_dim" in detail(r) and "4096" in detail(r)
    r = d.post(p, status=422, json={"height": 4})
    assert "minimum of 8" in detail(r)
    r = d.post(p, status=422, json={"mesh": "bunny"})
    assert "bunny" in detail(r)
    r = d.post(p, status=422, json={"mesh": 3})
    assert "mesh: expected a string" in detail(r)
    r = d.post(p, status=422, json={"mesh_id": "0" * 32})
    assert r.json()["type"] == "/problems/unknown-mesh"
    d.post(p, status=422, json={"mesh": "sphere", "mesh_id": "0" * 32})
    r = d.post(p, status=422, json={"colour": 1})
    assert "unknown key \"colour\"" in detail(r)
    r = d.post(p, status=422, json={"views": "ico6"})
    assert "ico6" in detail(r)
    r = d.post(p, status=422, json={"views": [{"eye": [0, 0, 3]}]})
    assert "views[0].light" in detail(r)
    r = d.post(p, status=422, json={"views": [{"eye": [0, 0, 3], "light": [1, 1, "x"]}]})
    assert "views[0].light" in detail(r)
    r = d.post(p, status=422, json={"views": [{"eye": [0, 0, 0], "light": [1, 1, 1]}]})
    assert "views[0]" in detail(r)  # degenerate camera: eye at the target
    r = d.post(p, status=422, json={"views": [{"eye": [0, 0, 3], "light": [0, 0, 3]}] * 65})
    assert "max_views" in detail(r)
    r = d.post(p, status=422, json={"views": [{"eye": [0, 0, 30], "target": [0, 0, 40],
                                               "light": [0, 0, 50], "half_fov": 0.1}]})
    assert r.json()["type"] == "/problems/no-samples"
    r = d.post(p, status=422, json={"views": [{"eye": [0, 0, 3], "light": [1, 1, 1]}],
                                    "light_angles": [10, 20]})
    r = d.post(p, status=422, json={"light_angles": [10]})
    r = d.post(p, status=422, json={"base": {"brdf": "chrome"}})
    assert "base.brdf" in detail(r)


def test_scene_get_delete_unknown(d):
    d.get(API + "/scenes/" + "0" * 32, status=404)
    r = d.get(API + "/scenes/not-an-id", status=404)
    assert "scene" in detail(r)
    d.delete(API + "/scenes/" + "0" * 32, status=404)
    s = new_scene(d, width=16, height=16)
    sess = new_session(d, s["id"])
    post_strokes(d, sess, 0, [{"color": [1, 1, 1], "diameter": 3, "points": [[8, 8]]}])
    r = d.delete(API + "/scenes/" + s["id"], status=204, headers={"X-Glint-Owner": s["owner_key"]})
    assert r.content == b""
    d.get(API + "/scenes/" + s["id"], status=404)
    d.get(API + "/sessions/" + sess["id"], status=404, headers=tok(sess["paint_token"]))
    d.delete(API + "/scenes/" + s["id"], status=404)


def test_scene_delete_takes_its_materials(d):
    """Deleting a scene deletes the materials fitted in its sessions, their
    records and files, as the API says: none is left on disk that nobody,
    not even the API key, can read."""
    k = Daemon("--api-key", "s3cret-key", "--quiet")
    key = {"X-Api-Key": "s3cret-key"}
    try:
        s = k.post(API + "/scenes", status=201, json={"width": 16, "height": 16},
                   headers=key).json()
        sess = k.post(API + "/sessions", status=201, json={"scene_id": s["id"]},
                      headers=key).json()
        h = tok(sess["paint_token"])
        for view in (0, 1):
            post_strokes(k, sess, view, [{"color": [0.8, 0.2, 0.1], "diameter": 6,
                                          "points": [[8, 8]]}])
        f = k.post("%s/sessions/%s/fits" % (API, sess["id"]), json={"params": {"res": 16}},
                   headers=h)
        assert f.status_code in (201, 202), f.text
        mid = f.json()["id"] if f.status_code == 201 else None
        if mid is None:
            job = f.json()["job"]["links"]["self"]
            for _ in range(1200):
                j = k.get(job, status=200, headers=h).json()["job"]
                if j["state"] in ("done", "failed"):
                    break
                time.sleep(0.05)
            assert j["state"] == "done", j
            mid = j["material_id"]
        k.get(API + "/materials/" + mid, status=200, headers=h, schema="Material.json")
        k.get(API + "/materials/%s/package" % mid, status=200, headers=key)
        mdir = os.path.join(k.data_dir, "blobs", "materials", mid)
        assert os.path.exists(os.path.join(mdir, "material.json")), mdir
        k.delete(API + "/scenes/" + s["id"], status=204, headers={"X-Glint-Owner": s["owner_key"]})
        for hd in (key, h):
            k.get(API + "/materials/" + mid, status=404, headers=hd)
        assert not os.path.exists(mdir), os.listdir(mdir)
        k.stop()
        k.start()  # nothing comes back
        k.get(API + "/materials/" + mid, status=404, headers=key)
        assert not os.path.exists(mdir)
    finally:
        k.stop()


def test_scene_images(d):
    s, _ = shared(d)
    base = "%s/scenes/%s/views/" % (API, s["id"])
    r, (w, h, rows) = get_png(d, base + "0/base.png")
    assert (w, h) == (W, H)
    lit = sum(1 for row in rows for p in row if p[0] > 0)
    assert lit > 0.2 * W * H  # the sphere fills a good part of the frame
    assert rows[0][0] == [0, 0, 0]  # background
    r = d.get(base + "0/base.png?format=exr", status=200)
    assert r.headers["Content-Type"] == "image/x-exr" and r.content[:4] == b"\x76\x2f\x31\x01"
    # a custom BRDF, scale and intensity: brighter than the default base
    _, (_, _, bright) = get_png(d, base + "0/base.png?brdf=lambert:kd=0.9&scale=3.14159&intensity=1.5")
    assert sum(p[0] for row in bright for p in row) > sum(p[0] for row in rows for p in row)
    d.get(base + "0/base.png?brdf=chrome", status=422)
    d.get(base + "0/base.png?scale=-1", status=422)
    d.get(base + "0/base.png?scale=abc", status=422)
    d.get(base + "0/base.png?format=tiff", status=422)
    d.get(base + "12/base.png", status=404)
    d.get(base + "x/base.png", status=404)
    d.get("%s/scenes/%s/views/0/base.png" % (API, "0" * 32), status=404)
    r = d.get(base + "3/gbuffer.exr", status=200)
    assert r.headers["Content-Type"] == "image/x-exr" and r.content[:4] == b"\x76\x2f\x31\x01"
    assert b"cos_i" in r.content[:2000] and b"wi.X" in r.content[:2000]
    d.get(base + "99/gbuffer.exr", status=404)


# ---------------------------------------------------------------------------
# meshes
# ---------------------------------------------------------------------------

# an octahedron
OBJ = b"""v 1 0 0
v -1 0 0
v 0 1 0
v 0 -1 0
v 0 0 1
v 0 0 -1
f 1 3 5
f 3 2 5
f 2 4 5
f 4 1 5
f 3 1 6
f 2 3 6
f 4 2 6
f 1 4 6
"""


def test_mesh_upload_and_scene(d):
    r = d.post(API + "/meshes?format=obj", status=201, schema="Mesh.json", data=OBJ)
    m = r.json()
    assert m["triangles"] == 8 and m["format"] == "obj" and m["bytes"] == len(OBJ)
    assert r.headers["Location"] == API + "/meshes/" + m["id"]
    assert d.get(API + "/meshes/" + m["id"], status=200, schema="Mesh.json").json() == m
    s = new_scene(d, mesh_id=m["id"], width=24, height=24)
    assert s["mesh"] == "upload" and s["mesh_id"] == m["id"] and s["samples"] > 0
    _, (w, h, rows) = get_png(d, "%s/scenes/%s/views/0/base.png" % (API, s["id"]))
    assert (w, h) == (24, 24) and any(p[0] > 0 for row in rows for p in row)
    # a session on it paints like any other
    sess = new_session(d, s["id"])
    post_strokes(d, sess, 1, [{"color": [1, 0, 0], "diameter": 6, "points": [[12, 12]]}])


def test_mesh_errors(d):
    d.post(API + "/meshes", status=400, data=OBJ)  # format missing
    r = d.post(API + "/meshes?format=stl", status=422, data=OBJ)
    assert "stl" in detail(r)
    d.post(API + "/meshes?format=obj", status=400, data=b"")
    r = d.post(API + "/meshes?format=ply", status=422, data=b"this is not a mesh at all\n")
    assert r.json()["type"] == "/problems/invalid-mesh"
    d.post(API + "/meshes?format=obj", status=422, data=b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")
    d.get(API + "/meshes/" + "0" * 32, status=404)


# ---------------------------------------------------------------------------
# sessions and access
# ---------------------------------------------------------------------------


def test_session_create_and_get(d):
    s, _ = shared(d)
    sess = new_session(d, s["id"])
    assert sess["access"] == "paint" and sess["scene_id"] == s["id"] and sess["last_seq"] == 0
    assert sess["links"]["paint"] == "/#/session/%s?token=%s" % (sess["id"], sess["paint_token"])
    assert sess["links"]["view"] == "/#/session/%s?token=%s" % (sess["id"], sess["view_token"])
    assert sess["paint_token"] != sess["view_token"]
    p = API + "/sessions/" + sess["id"]
    g = d.get(p, status=200, schema="Session.json", headers=tok(sess["paint_token"])).json()
    assert g["paint_token"] == sess["paint_token"] and g["access"] == "paint"
    v = d.get(p + "?token=" + sess["view_token"], status=200, schema="Session.json").json()
    assert v["access"] == "view" and "paint_token" not in v and "paint" not in v["links"]
    assert sess["paint_token"] not in json.dumps(v)


def test_session_create_errors(d):
    p = API + "/sessions"
    d.post(p, status=400, data=b"{", headers=JSON)
    r = d.post(p, status=422, json={})
    assert "scene_id: missing" in detail(r)
    r = d.post(p, status=422, json={"scene_id": 7})
    assert "scene_id" in detail(r)
    r = d.post(p, status=422, json={"scene_id": "0" * 32})
    assert r.json()["type"] == "/problems/unknown-scene"
    r = d.post(p, status=422, json={"scene_id": "x", "name": "y"})
    assert "unknown key" in detail(r)


def test_session_access_control(d):
    """Without the right token nothing of a session is readable or writable;
    the view token reads but cannot write."""
    s, _ = shared(d)
    sess = new_session(d, s["id"])
    sid, pt, vt = sess["id"], sess["paint_token"], sess["view_token"]
    other = new_session(d, s["id"])
    png = png_encode(W, H, lambda x, y: (10, 20, 30))
    stroke = {"strokes": [{"color": [1, 1, 1], "diameter": 4, "points": [[5, 5]]}]}
    reads = ["/sessions/%s" % sid, "/sessions/%s/views/0/painting" % sid,
             "/sessions/%s/strokes" % sid, "/sessions/%s/events" % sid]
    writes = [("PUT", "/sessions/%s/views/0/painting" % sid, {"data": png}),
              ("POST", "/sessions/%s/views/0/strokes" % sid, {"json": stroke})]
    for path in reads:
        r = d.get(API + path, status=401)
        assert "token" in detail(r)
        d.get(API + path, status=403, headers=tok(other["paint_token"]))
        d.get(API + path + "?token=" + "f" * 32, status=403)
    for method, path, kw in writes:
        d.request(method, API + path, status=401, **kw)
        d.request(method, API + path, status=403, headers=tok(other["paint_token"]), **kw)
        r = d.request(method, API + path, status=403, headers=tok(vt), **kw)
        assert "view token grants reading only" in detail(r)
    # nothing was written by the refused requests
    lst = d.get(API + "/sessions/%s/strokes" % sid, status=200, schema="StrokeList.json",
                headers=tok(vt)).json()
    assert lst["strokes"] == [] and lst["last_seq"] == 0
    r = d.get(API + "/sessions/%s/views/0/painting" % sid, status=200, headers=tok(vt))
    assert r.headers["X-Glint-Painted"] == "0"
    # unknown sessions are 404 whatever the token
    d.get(API + "/sessions/" + "0" * 32, status=404, headers=tok(pt))
    d.get(API + "/sessions/nope/strokes", status=404, headers=tok(pt))


# ---------------------------------------------------------------------------
# paintings
# ---------------------------------------------------------------------------


def test_painting_upload_and_read(d):
    s, _ = shared(d)
    sess = new_session(d, s["id"])
    p = "%s/sessions/%s/views/2/painting" % (API, sess["id"])
    h = tok(sess["paint_token"])
    # never painted: the base render, marked as such
    r, img = get_png(d, p, headers=h)
    assert r.headers["X-Glint-Painted"] == "0" and r.headers["X-Glint-Version"] == "0"
    _, base = get_png(d, "%s/scenes/%s/views/2/base.png" % (API, s["id"]))
    assert img == base
    # a PNG of the right size
    pix = lambda x, y: ((x * 5) % 256, (y * 5) % 256, 128)  # noqa: E731
    r = d.put(p, status=200, schema="PaintingVersion.json", data=png_encode(W, H, pix), headers=h)
    assert r.json()["version"] == 1 and r.json()["view"] == 2 and r.json()["seq"] >= 1
    r, (w, hh, rows) = get_png(d, p, headers=h)
    assert r.headers["X-Glint-Painted"] == "1" and r.headers["X-Glint-Version"] == "1"
    assert all(rows[y][x] == list(pix(x, y)) for y in range(H) for x in range(W))
    # an HDR EXR: stored as floats (read back as EXR; PNG clamps)
    r = d.put(p, status=200, schema="PaintingVersion.json", headers=h,
              data=exr_encode(W, H, lambda x, y: (2.5, -0.5, x / W)))
    assert r.json()["version"] == 2
    r = d.get(p + "?format=exr", status=200, headers=h)
    assert r.headers["Content-Type"] == "image/x-exr" and r.content[:4] == b"\x76\x2f\x31\x01"
    # glint's own OpenEXR writer (core/img/img_exr.h), read by this independent
    # reader: the floats uploaded, bit for bit
    chans, ew, eh = exr_named.read(r.content)
    f32 = lambda v: struct.unpack("<f", struct.pack("<f", v))[0]  # noqa: E731
    assert (ew, eh) == (W, H) and sorted(chans) == ["B", "G", "R"], (ew, eh, sorted(chans))
    assert all(chans["R"][y * W + x] == 2.5 and chans["G"][y * W + x] == -0.5
               and chans["B"][y * W + x] == f32(x / W) for y in range(H) for x in range(W))
    _, (_, _, rows) = get_png(d, p, headers=h)
    assert rows[3][3][0] == 255 and rows[3][3][1] == 0
    # the view token reads it too
    d.get(p + "?token=" + sess["view_token"], status=200)
    d.get(p + "?format=gif", status=422, headers=h)


def test_painting_conditional_replace(d):
    """If-Match names the version a client built its image from: a replace
    over a version that has moved on is refused (412), nothing is stored."""
    s, _ = shared(d)
    sess = new_session(d, s["id"])
    p = "%s/sessions/%s/views/1/painting" % (API, sess["id"])
    h = tok(sess["paint_token"])
    img = png_encode(W, H, lambda x, y: (10, 20, 30))
    d.put(p, status=200, data=img, headers=dict(h, **{"If-Match": "0"}))
    r = d.put(p, status=412, data=img, headers=dict(h, **{"If-Match": "0"}))
    assert "version 1" in detail(r)
    post_strokes(d, sess, 1, [{"mode": "paint", "color": [1, 1, 1], "diameter": 6, "kappa": 0.1,
                               "points": [[5, 5]]}])
    r = d.put(p, status=412, data=img, headers=dict(h, **{"If-Match": '"1"'}))
    assert "version 2" in detail(r)
    r = d.put(p, status=200, data=img, headers=dict(h, **{"If-Match": '"2"'}))
    assert r.json()["version"] == 3
    d.put(p, status=400, data=img, headers=dict(h, **{"If-Match": "abc"}))
    d.put(p, status=412, data=img, headers=dict(h, **{"If-Match": '"1"'}))
    # the refused uploads left no blob: the view's one image is all there is
    # (the replaced versions' files go off the requests' path: soon after)
    top = os.path.join(d.data_dir, "blobs", "sessions", sess["id"])
    deadline = time.time() + 60
    while True:
        names = [f for f in os.listdir(top) if not f.endswith(".px")]
        if len(names) == 1 or time.time() > deadline:
            break
        time.sleep(0.01)
    assert len(names) == 1 and names[0].startswith("view1-"), names


def test_painting_errors(d):
    s, _ = shared(d)
    sess = new_session(d, s["id"])
    p = "%s/sessions/%s/views/0/painting" % (API, sess["id"])
    h = tok(sess["paint_token"])
    r = d.put(p, status=422, data=png_encode(W + 1, H, lambda x, y: (0, 0, 0)), headers=h)
    assert r.json()["type"] == "/problems/wrong-size"
    assert "%dx%d" % (W + 1, H) in detail(r) and "expects exactly %dx%d" % (W, H) in detail(r)
    r = d.put(p, status=422, data=b"GIF89a not really", headers=h)
    assert r.json()["type"] == "/problems/invalid-image"
    d.put(p, status=400, data=b"", headers=h)
    r = d.put(p, status=422, headers=h,
              data=exr_encode(W, H, lambda x, y: (float("nan") if (x, y) == (4, 7) else 0.5, 0, 0)))
    assert r.json()["type"] == "/problems/non-finite"
    d.put(p, status=422, headers=h, data=exr_encode(W, H, lambda x, y: (0, float("inf"), 0)))
    d.put("%s/sessions/%s/views/12/painting" % (API, sess["id"]), status=404, headers=h,
          data=png_encode(W, H, lambda x, y: (0, 0, 0)))
    d.put("%s/sessions/%s/views/-1/painting" % (API, sess["id"]), status=404, headers=h,
          data=png_encode(W, H, lambda x, y: (0, 0, 0)))
    # none of this changed the view, nor left a file: an upload's blob is
    # written while it is decoded, and removed when the image is refused
    r = d.get(p, status=200, headers=h)
    assert r.headers["X-Glint-Painted"] == "0"
    top = os.path.join(d.data_dir, "blobs", "sessions", sess["id"])
    assert not os.path.isdir(top) or os.listdir(top) == [], os.listdir(top)


def test_oversize_uploads(d):
    """Body limits give 413 naming the limit (a daemon with a 1 MiB limit)."""
    small = Daemon("--max-body-mb", "1", "--max-image-dim", "40", "--max-mesh-tris", "4",
                   "--max-strokes", "3", "--quiet")
    try:
        s = small.post(API + "/scenes", status=201, schema="Scene.json",
                       json={"width": 40, "height": 40}).json()
        r = small.post(API + "/scenes", status=422, json={"width": 41, "height": 40})
        assert "limit of 40" in detail(r) and "max_image_dim" in detail(r)
        sess = small.post(API + "/sessions", status=201, json={"scene_id": s["id"]}).json()
        h = tok(sess["paint_token"])
        big = b"\0" * (1024 * 1024 + 10)
        r = small.put("%s/sessions/%s/views/0/painting" % (API, sess["id"]), status=413, data=big,
                      headers=h)
        assert "1048576 bytes" in detail(r) and "max-body-mb" in detail(r)
        r = small.put("%s/sessions/%s/views/0/painting" % (API, sess["id"]), status=413,
                      data=png_encode(64, 64, lambda x, y: (0, 0, 0)), headers=h)
        assert "limit of 40 pixels" in detail(r)
        r = small.post(API + "/meshes?format=obj", status=413, data=big)
        assert "1048576" in detail(r)
        r = small.post(API + "/meshes?format=obj", status=413, data=OBJ)
        assert "8 triangles" in detail(r) and "limit of 4" in detail(r)
        pts = [[i % 40, 5.125] for i in range(120000)]  # about 1.3 MB of JSON
        r = small.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=413, headers=h,
                       json={"strokes": [{"color": [1, 1, 1], "diameter": 2, "points": pts}]})
        assert "1048576 bytes" in detail(r), detail(r)
        r = small.post(API + "/scenes", status=413, data=b" " * (1 << 20) + b"{}", headers=JSON)
        assert "1048576 bytes" in detail(r), detail(r)
        pts = [[i % 40, 5] for i in range(60000)]
        r = small.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=413, headers=h,
                       json={"strokes": [{"color": [1, 1, 1], "diameter": 2, "points": pts}]})
        assert "limit" in detail(r)
        one = {"color": [1, 1, 1], "diameter": 2, "points": [[1, 1]]}
        r = small.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=413, headers=h,
                       json={"strokes": [one] * 4})
        assert "limit of 3 strokes" in detail(r) and "max-strokes" in detail(r)
        small.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=200, headers=h,
                   json={"strokes": [one] * 3}, schema="StrokesPosted.json")
    finally:
        small.stop()


# ---------------------------------------------------------------------------
# the API key
# ---------------------------------------------------------------------------


def test_api_key_guards_creation(d):
    k = Daemon("--api-key", "s3cret-key", "--quiet")
    try:
        r = k.post(API + "/scenes", status=401, json={"width": 16, "height": 16})
        assert "API key" in detail(r) and r.headers.get("WWW-Authenticate", "").startswith("Bearer")
        k.post(API + "/scenes", status=401, json={}, headers={"Authorization": "Bearer wrong"})
        s = k.post(API + "/scenes", status=201, schema="Scene.json", json={"width": 16, "height": 16},
                   headers={"Authorization": "Bearer s3cret-key"}).json()
        k.post(API + "/scenes", status=201, json={"width": 16, "height": 16},
               headers={"X-Api-Key": "s3cret-key"})
        k.get(API + "/scenes", status=401)
        k.get(API + "/scenes", status=200, schema="SceneList.json", headers={"X-Api-Key": "s3cret-key"})
        k.get(API + "/scenes/" + s["id"], status=200, schema="Scene.json")  # by id: no key needed
        k.get(API + "/scenes/%s/views/0/base.png" % s["id"], status=200)
        k.delete(API + "/scenes/" + s["id"], status=401)
        k.delete(API + "/scenes/" + s["id"], status=403, headers={"X-Glint-Owner": "x" * 32})
        k.post(API + "/meshes?format=obj", status=401, data=OBJ)
        k.post(API + "/sessions", status=401, json={"scene_id": s["id"]})
        sess = k.post(API + "/sessions", status=201, json={"scene_id": s["id"]},
                      headers={"X-Api-Key": "s3cret-key"}).json()
        # the session's own tokens work without the key; the key grants everything
        k.get(API + "/sessions/" + sess["id"], status=200, headers=tok(sess["view_token"]))
        k.get(API + "/sessions/" + sess["id"], status=401)
        g = k.get(API + "/sessions/" + sess["id"], status=200, schema="Session.json",
                  headers={"Authorization": "Bearer s3cret-key"}).json()
        assert g["access"] == "paint"
        k.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=200,
               json={"strokes": [{"color": [1, 1, 1], "diameter": 2, "points": [[3, 3]]}]},
               headers={"X-Api-Key": "s3cret-key"})
        k.delete(API + "/scenes/" + s["id"], status=204, headers={"X-Api-Key": "s3cret-key"})
    finally:
        k.stop()


def test_restart_keeps_everything(d):
    """A stopped and restarted daemon (same data directory) serves the same
    scenes, sessions, strokes and paintings."""
    r = Daemon("--quiet")
    try:
        s = r.post(API + "/scenes", status=201, json={"width": 16, "height": 16}).json()
        sess = r.post(API + "/sessions", status=201, json={"scene_id": s["id"]}).json()
        h = tok(sess["paint_token"])
        r.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=200, headers=h,
               json={"strokes": [{"color": [1, 0, 1], "diameter": 5, "points": [[8, 8]]}]})
        img1 = r.get("%s/sessions/%s/views/0/painting" % (API, sess["id"]), status=200, headers=h).content
        r.stop()
        r.start()
        assert r.get(API + "/scenes/" + s["id"], status=200).json()["hash"] == s["hash"]
        lst = r.get("%s/sessions/%s/strokes" % (API, sess["id"]), status=200, headers=h).json()
        assert [x["seq"] for x in lst["strokes"]] == [1]
        img2 = r.get("%s/sessions/%s/views/0/painting" % (API, sess["id"]), status=200, headers=h).content
        assert img1 == img2
        assert r.post("%s/sessions/%s/views/0/strokes" % (API, sess["id"]), status=200, headers=h,
                      json={"strokes": [{"color": [1, 0, 1], "diameter": 5, "points": [[2, 2]]}]}
                      ).json()["first_seq"] == 2
    finally:
        r.stop()


def server_timing(r):
    """The Server-Timing steps of a response: {name: ms}."""
    out = {}
    for part in r.headers.get("Server-Timing", "").split(","):
        if ";dur=" in part:
            name, dur = part.strip().split(";dur=")
            out[name] = float(dur)
    return out


def test_uploads_kept_as_sent_and_timed(d):
    """An upload is stored as it came (PNG stays PNG, no re-encoding) and
    reads back the same after a restart, through every path that reads it:
    GET as PNG and as EXR, strokes on top of it (which read the memo's
    decoded copy, or the store after a restart) and a fit.  Uploads,
    strokes and fits say what their steps took (Server-Timing)."""
    r = Daemon("--quiet")
    try:
        s = r.post(API + "/scenes", status=201, json={"width": W, "height": H}).json()
        sess = r.post(API + "/sessions", status=201, json={"scene_id": s["id"]}).json()
        h = tok(sess["paint_token"])
        p = "%s/sessions/%s/views/1/painting" % (API, sess["id"])
        pix = lambda x, y: ((x * 7) % 256, (y * 3) % 256, 200)  # noqa: E731
        body = png_encode(W, H, pix)
        up = r.put(p, status=200, data=body, headers=dict(h, **{"Content-Type": "image/png"}))
        st = server_timing(up)
        assert {"session", "decode", "validate", "write", "store", "notify"} <= set(st), st
        assert all(v >= 0 for v in st.values()) and "encode" not in st, st
        stored = os.listdir(os.path.join(r.data_dir, "blobs", "sessions", sess["id"]))
        assert [f.rsplit(".", 1)[1] for f in stored] == ["png"], stored
        with open(os.path.join(r.data_dir, "blobs", "sessions", sess["id"], stored[0]),
                  "rb") as f:
            assert f.read() == body, "the upload was not stored as sent"
        exr = r.get(p + "?format=exr", status=200, headers=h)
        assert exr.headers["Content-Type"] == "image/x-exr"
        assert exr.content[:4] == b"\x76\x2f\x31\x01"
        # a stroke on top of it: read from the memo, timed step by step
        st = post_strokes(r, sess, 1, [{"color": [1, 0, 0], "diameter": 3, "points": [[5, 5]]}])
        steps = server_timing(st)
        assert {"session", "parse", "lock", "read", "apply", "encode", "store"} <= set(steps)
        _, (_, _, rows) = get_png(r, p, headers=h)
        assert rows[5][5] == [255, 0, 0] and rows[40][40] == list(pix(40, 40))
        # view 2: a PNG left as uploaded, for after the restart
        p2 = "%s/sessions/%s/views/2/painting" % (API, sess["id"])
        r.put(p2, status=200, data=body, headers=dict(h, **{"Content-Type": "image/png"}))
        f = r.post("%s/sessions/%s/fits" % (API, sess["id"]), json={"params": {"res": 16}},
                   headers=h)
        assert f.status_code in (201, 202), f.text
        r.stop()
        r.start()
        _, (_, _, rows) = get_png(r, p2, headers=h)
        assert all(rows[y][x] == list(pix(x, y)) for y in range(H) for x in range(W))
        # strokes after the restart read the stored PNG (the memo is empty)
        post_strokes(r, sess, 2, [{"color": [0, 0, 1], "diameter": 3, "points": [[9, 9]]}])
        _, (_, _, rows) = get_png(r, p2, headers=h)
        assert rows[9][9] == [0, 0, 255] and rows[30][20] == list(pix(20, 30))
        # a fit reads both views; answered at once (201) it is timed too
        for _ in range(2):
            f = r.post("%s/sessions/%s/fits" % (API, sess["id"]), json={"params": {"res": 16}},
                       headers=h)
            if f.status_code == 202:
                job = f.json()["job"]["links"]["self"]
                for _ in range(600):
                    j = r.get(job, status=200, headers=h).json()["job"]
                    if j["state"] in ("done", "failed"):
                        break
                    time.sleep(0.05)
                assert j["state"] == "done", j
        assert f.status_code == 201, f.text
        steps = server_timing(f)
        assert {"scene", "paintings", "fit", "save", "record", "publish"} <= set(steps), steps
        m = f.json()
        assert m["errors"]["diagnostic_samples"] >= 1
        assert m["views_used"] == [1, 2]
    finally:
        r.stop()


if __name__ == "__main__":
    run_tests(globals())
