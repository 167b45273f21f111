"""The Python client (clients/python/glint_client.py) and its worked example
against the real daemon, run with an API key: the example end to end (its
preview and package checked as files); every group of the API through the
client (health, metrics, methods, environments, meshes, scenes, base
renders, G-buffers, sessions, share links, paintings, strokes, the session's
event stream, fits as a job and at once, jobs and their event streams,
materials and all their files), each JSON answer checked against its schema;
errors raised as GlintError with the server's status and problem details."""
import io
import json
import os
import struct
import subprocess
import sys
import tarfile
import tempfile
import zlib

sys.path.insert(0, os.path.dirname(__file__))
from harness import SRC, run_tests, validate  # noqa: E402

CLIENT_DIR = os.path.join(SRC, "clients", "python")
sys.path.insert(0, CLIENT_DIR)
from glint_client import (GlintClient, GlintConnectionError, GlintError,  # noqa: E402
                          UNCHANGED)

KEY = "python-client-key-0123"
OWNER = "python-client-owner-0123456789"
SIZE = 32
VIEWS = (0, 3, 5)
SPEC = "ct:rough=0.25,kd=0.45/0.3/0.2,f0=0.05"
PNG_SIG = b"\x89PNG\r\n\x1a\n"
EXR_SIG = b"\x76\x2f\x31\x01"
S = {}


def png_size(data):
    """(width, height) of a PNG whose chunks' CRCs hold and whose image data
    inflates to exactly the rows its header announces."""
    assert data[:8] == PNG_SIG, data[:16]
    pos, idat, hdr = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        crc, = struct.unpack(">I", data[pos + 8 + n:pos + 12 + n])
        assert zlib.crc32(kind + body) == crc, "bad CRC in chunk %r" % kind
        if kind == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
        if kind == b"IEND":
            break
    w, h, depth, ctype = hdr[:4]
    channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}[ctype]
    assert len(zlib.decompress(idat)) == h * (1 + (w * channels * depth + 7) // 8)
    return w, h


def hdr_map(width, height, rgbe=(128, 128, 128, 128)):
    """A flat Radiance HDR lat-long map (constant 0.5 by default)."""
    head = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width)
    return head + bytes(rgbe) * (width * height)


def raises(fn, status, kind=None):
    """The GlintError fn raises, checked for status and problem type."""
    try:
        fn()
    except GlintError as e:
        assert e.status == status, "status %r, want %d: %s" % (e.status, status, e)
        assert e.type and e.title and e.detail, "no problem details: %s" % e
        validate({"type": e.type, "title": e.title, "status": e.status, "detail": e.detail},
                 "Problem.json")
        if kind:
            assert e.kind == kind, "type %s, want %s" % (e.type, kind)
        return e
    raise AssertionError("no GlintError (want %d %s)" % (status, kind or ""))


def test_01_the_example_runs(d):
    out = tempfile.mkdtemp(prefix="glint-pyclient-")
    p = subprocess.run([sys.executable, os.path.join(CLIENT_DIR, "example.py"), d.base,
                        "--api-key", KEY, "--out", out],
                       capture_output=True, text=True, timeout=300)
    print("\n".join("     | " + line for line in p.stdout.splitlines()))
    assert p.returncode == 0, "exit %d\n%s\n%s" % (p.returncode, p.stdout, p.stderr)
    lines = p.stdout.splitlines()
    assert lines[0].startswith("glintd ") and " up " in lines[0], lines
    assert sum(line.startswith("painted  view ") for line in lines) == 3, lines
    assert any(line.startswith("material ") and "method hf3, res 32" in line for line in lines)
    assert any(line.startswith("summary  base colour ") for line in lines), lines
    assert png_size(open(os.path.join(out, "preview.png"), "rb").read()) == (128, 128)
    tars = [f for f in os.listdir(out) if f.endswith(".tar")]
    assert len(tars) == 1, os.listdir(out)
    with tarfile.open(os.path.join(out, tars[0])) as tf:
        names = tf.getnames()
        man = [n for n in names if n.endswith("/material.json")]
        assert len(man) == 1, names
        m = json.load(tf.extractfile(man[0]))
    assert m["method"] == "hf3" and {"format", "version", "info"} <= set(m), sorted(m)
    assert any(n.endswith("/factors.png") for n in names), names
    # the material it reports is the one saved
    mid = [line.split()[1].rstrip(":") for line in lines if line.startswith("material ")][0]
    assert tars[0] == "glint-material-%s.tar" % mid[:8]
    # a failure exits non-zero, naming the problem
    p = subprocess.run([sys.executable, os.path.join(CLIENT_DIR, "example.py"), d.base,
                        "--api-key", "wrong-key", "--out", out],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 1 and "401" in p.stderr and "API key" in p.stderr, p.stderr


def test_02_health_metrics_methods_environments(d):
    c = GlintClient(d.base)
    h = c.health()
    validate(h, "Health.json")
    assert "glintd_requests_total" in c.metrics()
    ms = c.methods()
    validate(ms, "Methods.json")
    names = [m["name"] for m in ms["methods"]]
    assert "hf3" in names and "scene" not in ms, names
    hf3 = c.method("hf3")
    assert "res" in [p["name"] for p in hf3["params"]]
    try:
        c.method("no-such-method")
        raise AssertionError("KeyError expected")
    except KeyError:
        pass
    meas = c.measured()
    validate(meas, "MeasuredList.json")
    assert meas["materials"] == [], meas  # no --measured-dir: none on offer
    envs = c.list_environments()["environments"]
    for e in envs:
        validate(e, "Environment.json")
    assert {"studio", "white"} <= {e["spec"] for e in envs if e["kind"] == "builtin"}, envs


def test_03_meshes_and_scenes(d):
    c = GlintClient(d.base, api_key=KEY)
    cube = b"".join(b"v %d %d %d\n" % (x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1))
    cube += b"f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n"
    path = os.path.join(tempfile.mkdtemp(prefix="glint-pyclient-"), "cube.obj")
    with open(path, "wb") as f:
        f.write(cube)
    mesh = c.upload_mesh(path)  # the format from the extension
    validate(mesh, "Mesh.json")
    assert mesh["format"] == "obj" and mesh["triangles"] == 12 and mesh["bytes"] == len(cube)
    assert c.get_mesh(mesh["id"]) == mesh
    up = c.create_scene(mesh_id=mesh["id"], width=SIZE, height=SIZE, owner_key=OWNER)
    validate(up, "Scene.json")
    assert up["mesh"] == "upload" and up["mesh_id"] == mesh["id"] and up["owner_key"] == OWNER

    sc = c.create_scene(mesh="sphere", width=SIZE, height=SIZE, views="ico12",
                        owner_key=OWNER)
    validate(sc, "Scene.json")
    assert (sc["mesh"], sc["width"], len(sc["views"])) == ("sphere", SIZE, 12)
    assert c.get_scene(sc["id"]) == {k: v for k, v in sc.items() if k != "owner_key"}
    mine = c.list_scenes(owner_key=OWNER)  # with the key: every scene; the owner's: its own
    validate(mine, "SceneList.json")
    pub = GlintClient(d.base, owner_key=OWNER).list_scenes()
    assert [s["id"] for s in pub["scenes"]] == [up["id"], sc["id"]] and pub["count"] == 2, pub
    assert mine["count"] >= 3  # the example's scene too

    png = c.base_render(sc["id"], 2)
    assert png.content_type == "image/png" and png_size(png) == (SIZE, SIZE)
    exr = c.base_render(sc["id"], 2, format="exr", brdf=SPEC, scale=1.0, intensity=2.0)
    assert exr[:4] == EXR_SIG and exr.content_type == "image/x-exr"
    lit = c.base_render(sc["id"], 2, brdf=SPEC, env="white", env_rotation=30, env_intensity=1.5,
                        lights=16, shadows=False, background=True)
    assert png_size(lit) == (SIZE, SIZE) and bytes(lit) != bytes(png)
    g = c.gbuffer(sc["id"], 2)
    assert g[:4] == EXR_SIG and len(g) > 1000
    S.update(scene=sc, upload_scene=up)

    # deleting needs the owner key (or the API key)
    anon = GlintClient(d.base)
    raises(lambda: anon.delete_scene(up["id"]), 401, "owner-key-required")
    raises(lambda: anon.delete_scene(up["id"], owner_key="someone-else-0123456789"), 403,
           "not-owner")
    assert GlintClient(d.base, owner_key=OWNER).delete_scene(up["id"]) is None
    raises(lambda: c.get_scene(up["id"]), 404, "not-found")


def test_04_sessions_paintings_and_strokes(d):
    c = GlintClient(d.base, api_key=KEY)
    sc = S["scene"]
    s = c.create_session(sc["id"])
    validate(s, "Session.json")
    assert s["access"] == "paint" and s["last_seq"] == 0 and "expires" not in s
    p = GlintClient(d.base, token=s["paint_token"])  # what a painter holds: no API key
    v = GlintClient(d.base, token=s["view_token"])
    got = v.get_session(s["id"])
    validate(got, "Session.json")
    assert got["access"] == "view" and "paint_token" not in got
    for k in VIEWS:
        before = p.get_painting(s["id"], k)
        assert before.header("X-Glint-Painted") == "0" and before.header("X-Glint-Version") == "0"
        r = p.put_painting(s["id"], k, p.base_render(sc["id"], k, format="exr", brdf=SPEC))
        validate(r, "PaintingVersion.json")
        assert r["view"] == k and r["version"] == 1
    after = v.get_painting(s["id"], VIEWS[0], format="exr")
    assert after[:4] == EXR_SIG and after.header("X-Glint-Painted") == "1"
    assert after.header("X-Glint-Version") == "1"
    # a PNG goes back in, its type read from its bytes; If-Match guards the version
    png = p.get_painting(s["id"], 9)
    r = p.put_painting(s["id"], 9, png, if_match=0)
    assert r["version"] == 1
    raises(lambda: p.put_painting(s["id"], 9, png, if_match=0), 412)

    stroke = {"color": [1.0, 0.9, 0.8], "diameter": 6, "kappa": 0.1, "opacity": 0.5,
              "points": [[10, 10], [20, 14]], "tag": "pyclient"}
    r = p.post_strokes(s["id"], 9, [stroke, dict(stroke, mode="erase", points=[[12, 12]])])
    validate(r, "StrokesPosted.json")
    assert r["strokes"] == 2 and r["last_seq"] == r["first_seq"] + 1 and r["version"] == 2
    lst = v.list_strokes(s["id"])
    validate(lst, "StrokeList.json")
    assert [x["seq"] for x in lst["strokes"]] == [r["first_seq"], r["last_seq"]]
    assert lst["strokes"][0]["stroke"]["tag"] == "pyclient" and not lst["more"]
    page = v.list_strokes(s["id"], since=0, limit=1)
    assert len(page["strokes"]) == 1 and page["more"], page
    assert [x["seq"] for x in v.iter_strokes(s["id"])] == [r["first_seq"], r["last_seq"]]
    raises(lambda: v.post_strokes(s["id"], 9, stroke), 403, "read-only-token")
    S.update(session=s)


def test_05_the_session_event_stream(d):
    s = S["session"]
    p = GlintClient(d.base, token=s["paint_token"])
    last = p.get_session(s["id"])["last_seq"]
    with p.session_events(s["id"], since=last, name="pyclient-test", timeout=10) as st:
        first = st.next()  # presence: this client connected
        validate(first.data, "Presence.json")
        assert first.event == "presence" and first.id is None
        assert "pyclient-test" in [x["name"] for x in first.data["clients"]], first.data
        r = p.post_strokes(s["id"], 1, {"color": [0.2, 0.4, 0.9], "diameter": 4,
                                        "points": [[16, 16]], "tag": "live"})
        seen = []
        for ev in st:
            seen.append(ev)
            if ev.event == "stroke":
                break
        assert not st.timed_out, "no stroke event within 10 s: %s" % seen
    ev = seen[-1]
    validate(ev.data, "SessionEvent.json")
    assert ev.id == r["first_seq"] == ev.data["seq"] and ev.data["view"] == 1
    assert ev.data["data"]["tag"] == "live"
    # a reconnect after an event id replays what followed it, then waits
    with p.session_events(s["id"], last_event_id=r["first_seq"] - 1, timeout=1.5) as st:
        durable = [e for e in st if e.id is not None]
        assert st.timed_out
    assert [e.id for e in durable] == [r["first_seq"]], durable


def test_06_fits_jobs_and_materials(d):
    s = S["session"]
    p = GlintClient(d.base, token=s["paint_token"])
    raises(lambda: p.fit(s["id"], "hf3", {"res": 2}), 422)
    first = p.fit(s["id"], "hf3", {"res": 32})
    # a pattern never fitted: the precomputation is built by a job
    assert "job" in first, "want a job for a new precomputation: %s" % sorted(first)
    validate(first, "JobResponse.json")
    jid = first["job"]["id"]
    with p.job_events(jid, since=0, timeout=120) as st:
        events = list(st)
        assert not st.timed_out, events
    for e in events:
        validate(e.data, "Job.json")
    assert events and events[-1].event == "done", [e.event for e in events]
    job = p.wait_job(jid, timeout=120)
    validate({"job": job}, "JobResponse.json")
    assert job["state"] == "done" and job["material_id"] == events[-1].data["material_id"]
    validate(p.get_job(jid), "JobResponse.json")
    m1 = p.get_material(job["material_id"])
    validate(m1, "Material.json")
    assert m1["views_used"] == sorted(VIEWS + (1, 9)) and m1["params"]["res"] == 32, m1
    # the same pattern again: in memory now, fitted at once
    m2 = p.fit(s["id"], "hf3", {"res": 32})
    assert "job" not in m2, m2
    validate(m2, "Material.json")
    assert m2["precomputation"]["cache"]["memory"] == "hit"
    m3 = p.fit_and_wait(s["id"], "hf3", {"res": 32, "lambda": 0.2})
    validate(m3, "Material.json")
    lst = GlintClient(d.base, token=s["view_token"]).list_materials(s["id"])
    validate(lst, "MaterialList.json")
    assert [m["id"] for m in lst["materials"]] == [m1["id"], m2["id"], m3["id"]]
    S.update(material=m2)


def test_07_material_files(d):
    s, mid = S["session"], S["material"]["id"]
    v = GlintClient(d.base, token=s["view_token"])
    assert png_size(v.factors(mid)) == (32, 3)  # p, q, r of res texels
    assert v.factors(mid, format="exr")[:4] == EXR_SIG
    for fn in (v.coefficients, v.spatial):  # hf3 has neither
        for fmt in ("png", "exr"):
            raises(lambda: fn(mid, format=fmt), 404)
    man = v.manifest(mid)
    assert man["method"] == "hf3" and {"format", "version", "info"} <= set(man)
    sh = v.shader(mid)
    validate(sh, "Shader.json")
    assert "void main" in sh["fragment"]
    frag = v.shader_file(mid, "glint_material.frag")
    assert frag.decode() == sh["fragment"]
    assert v.shader_file(mid, "glint_factors.exr")[:4] == EXR_SIG
    assert len(v.shader_file(mid, "glint_factors_rgba16f.bin")) > 0
    assert v.shader_file(mid, "glint_factors16.png")[:8] == b"\x89PNG\r\n\x1a\n"
    assert v.shader_file(mid, "glint_material_330.frag").decode().startswith("#version 330 core")
    pkg = v.package(mid)
    with tarfile.open(fileobj=io.BytesIO(pkg)) as tf:
        names = tf.getnames()
    top = "glint-material-%s/" % mid[:8]
    for want in ("material.json", "factors.png", "factors.exr", "shader/glint_material.frag"):
        assert top + want in names, names

    a = v.preview(mid, view=3)
    assert png_size(a) == (SIZE, SIZE) and a.header("X-Glint-Renderer")
    b = v.preview(mid, eye=(0, 3, 1), light=[2, 2, 2], target="0,0,0", fov=40, intensity=1.5,
                  size=48, renderer="cpu")
    assert png_size(b) == (48, 48) and b.header("X-Glint-Renderer") == "cpu"
    ball = v.preview(mid, view=3, object="ball", size=40)
    assert png_size(ball) == (40, 40)
    lit = v.preview(mid, format="exr", view=3, object="ball", env="studio", env_rotation=45,
                    env_intensity=1.2, lights=16, shadows=True, background=False, size=40)
    assert lit[:4] == EXR_SIG and "env=studio" in lit.header("X-Glint-Env", ""), lit.headers
    raises(lambda: v.preview(mid, view=0, size=4), 422, "invalid-parameter")
    raises(lambda: v.preview(mid, view=99), 422, "invalid-parameter")

    summ = v.summary(mid)
    validate(summ, "MaterialSummary.json")
    glb = v.gltf(mid)
    assert glb[:4] == b"glTF" and "roughness=" in glb.header("X-Glint-Gltf", ""), glb.headers
    lst = v.exports(mid)
    validate(lst, "ExportList.json")
    assert "mtlx_zip" in [e["format"] for e in lst["exports"]], lst
    mx = v.materialx(mid)
    assert b"<standard_surface" in mx and "fit_rel_rms=" in mx.header("X-Glint-Fit", "")
    mz = v.materialx(mid, textures=True, bake_res=8)
    assert mz[:2] == b"PK" and "textures=0" in mz.header("X-Glint-Fit", ""), mz.headers
    assert b"#usda 1.0" in v.usd(mid, mesh=False)[:20]
    assert v.usd(mid, package=True, bake_res=0)[:2] == b"PK"
    for bad in (lambda: v.materialx(mid, bake_res=8), lambda: v.usd(mid, bake_res=8),
                lambda: v.usd(mid, package=True, mesh=False)):
        try:
            bad()
            raise AssertionError("a contradictory export request was sent")
        except ValueError:
            pass
    brdf = v.brdf_explorer(mid)
    assert brdf.startswith(b"analytic\n") and b"vec3 BRDF(" in brdf
    merl = v.merl(mid)
    assert len(merl) == 34992012 and merl[:12] == bytes([90, 0, 0, 0, 90, 0, 0, 0, 180, 0, 0, 0])
    assert "azimuths=" in merl.header("X-Glint-Merl", ""), merl.headers
    ev = v.eval(mid, [([0, 0, 1], [0, 1, 1], [0, -1, 1]),
                      {"n": [0, 0, 1], "wi": [0, 0, 1], "wo": [1, 0, 1]},
                      ([0, 0, 1], [0, 0, -1], [0, 0, 1])])
    validate(ev, "EvalResponse.json")
    assert len(ev["values"]) == 3 and max(ev["values"][0]) > 0 and ev["values"][2] == [0, 0, 0]
    raises(lambda: v.eval(mid, [([0, 0, 0], [0, 0, 1], [0, 0, 1])]), 422)
    pts = v.methods(session_id=s["id"])
    validate(pts, "Methods.json")
    assert pts["scene"]["id"] == S["scene"]["id"] and pts["scene"]["points"], pts.get("scene")
    validate(GlintClient(d.base).methods(scene_id=S["scene"]["id"]), "Methods.json")


def test_08_environment_upload(d):
    c = GlintClient(d.base, api_key=KEY)
    raises(lambda: GlintClient(d.base).upload_environment(hdr_map(32, 16)), 401,
           "api-key-required")
    e = c.upload_environment(hdr_map(32, 16), name="flat grey")
    validate(e, "Environment.json")
    assert (e["kind"], e["name"], e["width"], e["height"]) == ("upload", "flat grey", 32, 16)
    assert e["spec"] in [x["spec"] for x in c.list_environments()["environments"]]
    # listed to its owner key (made for it here), deleted only by it or the API key
    mine = GlintClient(d.base, owner_key=e["owner_key"])
    assert e["spec"] in [x["spec"] for x in mine.list_environments()["environments"]]
    assert e["spec"] not in [x["spec"] for x in GlintClient(d.base).list_environments(
        owner_key=OWNER)["environments"]]
    raises(lambda: GlintClient(d.base).delete_environment(e["id"]), 401, "owner-key-required")
    s = S["session"]
    img = GlintClient(d.base, token=s["view_token"]).preview(
        S["material"]["id"], view=3, env=e["spec"], lights=8, background=False)
    assert png_size(img) == (SIZE, SIZE)
    assert c.delete_environment(e["id"]) is None
    assert e["spec"] not in [x["spec"] for x in c.list_environments()["environments"]]
    raises(lambda: c.delete_environment(e["id"]), 404)
    raises(lambda: c.upload_environment(b"not an image"), 422)


def test_09_share_links(d):
    s = S["session"]
    p = GlintClient(d.base, token=s["paint_token"])
    n = p.replace_tokens(s["id"], revoke="both", expires_in=3600)
    validate(n, "Session.json")
    assert n["paint_token"] != s["paint_token"] and n["view_token"] != s["view_token"]
    assert "expires" in n
    raises(lambda: p.get_session(s["id"]), 403, "wrong-token")
    raises(lambda: p.get_session(s["id"], token=s["view_token"]), 403, "wrong-token")
    p.token = n["paint_token"]
    assert p.get_session(s["id"])["access"] == "paint"
    # the owner key renews them and clears the expiry; the view token alone stays
    o = GlintClient(d.base, owner_key=OWNER).replace_tokens(s["id"], revoke="paint",
                                                            expires_in=None)
    assert "expires" not in o and o["view_token"] == n["view_token"]
    assert o["paint_token"] != n["paint_token"]
    k = GlintClient(d.base, api_key=KEY).replace_tokens(s["id"], revoke="none")
    assert k["paint_token"] == o["paint_token"] and "expires" not in k
    k = GlintClient(d.base, api_key=KEY).replace_tokens(s["id"], revoke="none",
                                                        expires_in=UNCHANGED)
    assert k["paint_token"] == o["paint_token"]
    S["session"] = dict(s, paint_token=o["paint_token"], view_token=o["view_token"])


def test_10_errors(d):
    s = S["session"]
    anon = GlintClient(d.base)
    e = raises(lambda: anon.get_material("0" * 32, token=s["view_token"]), 404, "not-found")
    assert "0" * 32 in e.detail and "404" in str(e)
    raises(lambda: anon.get_material(S["material"]["id"]), 401, "token-required")
    raises(lambda: anon.get_session(s["id"]), 401, "token-required")
    raises(lambda: anon.create_scene(width=SIZE, height=SIZE), 401, "api-key-required")
    raises(lambda: GlintClient(d.base, api_key="wrong").create_session(S["scene"]["id"]), 401)
    raises(lambda: GlintClient(d.base, api_key=KEY).create_scene(width=3, height=SIZE), 422)
    raises(lambda: anon.base_render(S["scene"]["id"], 99), 404)
    raises(lambda: anon.get_job("f" * 32, token=s["paint_token"]), 404, "not-found")
    # arguments the client refuses before sending
    for bad in (lambda: anon.base_render(S["scene"]["id"], "0"),
                lambda: anon.base_render(S["scene"]["id"], True),
                lambda: anon.base_render(S["scene"]["id"], 0, format="jpg"),
                lambda: anon.get_scene(""),
                lambda: anon.preview("x", eye=(1, 2)),
                lambda: anon.shader_file("x", "../material.json"),
                lambda: anon.post_strokes("x", 0, [])):
        try:
            bad()
            raise AssertionError("no ValueError")
        except ValueError:
            pass
    # ids are escaped into one path segment
    e = raises(lambda: anon.get_scene("../meshes/x"), 404)
    assert e.url.endswith("/api/v1/scenes/..%2Fmeshes%2Fx"), e.url
    # no daemon there
    try:
        GlintClient("http://127.0.0.1:1", timeout=5).health()
        raise AssertionError("no error")
    except GlintConnectionError as e:
        assert e.status is None and "127.0.0.1:1" in str(e)



def test_11_gbuffer_sets(d):
    """G-buffers and paintings made elsewhere: here the scene's own
    G-buffers and base renders, uploaded to a set and fitted."""
    c = GlintClient(d.base, api_key=KEY)
    sc = S["scene"]["id"]
    st = c.create_gbuffer_set(2, SIZE, SIZE)
    validate(st, "GbufferSet.json")
    for k in (0, 1):
        v = c.put_gbuffer(st["id"], k, c.gbuffer(sc, VIEWS[k]))
        validate(v, "GbufferView.json")
        assert v["view"] == k and v["has_wi"] and v["samples_lit"] > 0, v
        c.put_gbuffer_painting(st["id"], k, c.base_render(sc, VIEWS[k], format="exr",
                                                          brdf=SPEC, scale=1.0))
    got = c.get_gbuffer_set(st["id"])
    validate(got, "GbufferSet.json")
    assert all(v["gbuffer"] and v["painting"] for v in got["view_state"]), got
    m = c.fit_gbuffers_and_wait(st["id"], "hf3", {"res": 16})
    validate(m, "Material.json")
    assert m["gbuffer_set_id"] == st["id"] and m["views_used"] == [0, 1], m
    assert m["id"] in [x["id"] for x in c.list_gbuffer_materials(st["id"])["materials"]]
    assert c.factors(m["id"]).startswith(PNG_SIG)
    raises(lambda: c.gltf(m["id"]), 422, "no-scene")
    # the set is its owner key's (made for it here) and the API key's
    raises(lambda: GlintClient(d.base).get_gbuffer_set(st["id"]), 401, "owner-key-required")
    raises(lambda: GlintClient(d.base, owner_key=OWNER).get_gbuffer_set(st["id"]), 403,
           "not-owner")
    assert GlintClient(d.base, owner_key=st["owner_key"]).get_gbuffer_set(st["id"])["id"] == \
        st["id"]
    raises(lambda: c.put_gbuffer(st["id"], 2, c.gbuffer(sc, 0)), 404)
    raises(lambda: c.put_gbuffer(st["id"], 0, b"not an exr"), 422, "invalid-gbuffer")
    assert c.delete_gbuffer_set(st["id"]) is None
    raises(lambda: c.get_gbuffer_set(st["id"]), 404)


run_tests(globals(), daemon_args=("--api-key", KEY, "--quiet"))
