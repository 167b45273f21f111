"""The environment-lit method (srbf) through the real daemon: paintings
made under a built-in sky by the CLI, uploaded to a session, fitted as a
job with method srbf, then the warm fit, the material's manifest (lobes,
diffuse, energy report), its evaluation, shader and previews, and the
parameter checks of the method's table (an unknown environment, refused
before the fit is queued, an impossible diffuse albedo, a spec with
characters the table refuses)."""
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
import exr_named  # noqa: E402
from harness import GLINTD, run_tests  # noqa: E402

CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(GLINTD))), "core", "glint")
SIZE = 48
S = {}
OWNER = "srbf-test-owner-key-0001"
PARAMS = {"env": "sky", "lights": 64, "basis_res": 5, "static": "smith"}


def write_hdr(path, w, h, fn):
    """A flat (uncompressed) Radiance RGBE file."""
    import math
    rows = []
    for r in range(h):
        row = bytearray()
        for c in range(w):
            rgb = fn(r, c)
            m = max(rgb)
            if m < 1e-32:
                row += bytes(4)
                continue
            mant, e = math.frexp(m)
            scale = mant * 256.0 / m
            row += bytes([int(v * scale) for v in rgb] + [e + 128])
        rows.append(bytes(row))
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w))
        for row in rows:
            f.write(row)


ENV_DIR = tempfile.mkdtemp(prefix="glint-envs-")
write_hdr(os.path.join(ENV_DIR, "bright.hdr"), 64, 32,
          lambda r, c: (4.0, 3.0, 2.0) if r < 8 and 20 < c < 30 else (0.3, 0.4, 0.6) if r < 16
          else (0.1, 0.1, 0.1))
write_hdr(os.path.join(ENV_DIR, ".hidden.hdr"), 64, 32, lambda r, c: (1.0, 1.0, 1.0))
os.symlink("/etc/passwd", os.path.join(ENV_DIR, "evil.hdr"))


def tok(t):
    return {"X-Glint-Token": t}


def fit(d, body, expect=(201, 202)):
    r = d.post("/api/v1/sessions/%s/fits" % S["session"],
               headers=dict(tok(S["paint"]), **{"Content-Type": "application/json"}),
               data=json.dumps(body))
    assert r.status_code in expect, r.text
    return ("material", r.json()) if r.status_code == 201 else ("job", r.json()["job"])


def wait_job(d, jid):
    deadline = time.time() + 300
    while time.time() < deadline:
        j = d.get("/api/v1/jobs/" + jid, headers=tok(S["paint"]), status=200,
                  schema="JobResponse.json").json()["job"]
        if j["state"] in ("done", "failed"):
            return j
        time.sleep(0.2)
    raise AssertionError("job %s did not finish" % jid)


def test_01_setup(d):
    tmp = tempfile.mkdtemp(prefix="glint-srbf-")
    scene = os.path.join(tmp, "scene.json")
    subprocess.run([CLI, "scene", "create", "--size", str(SIZE), "-o", scene], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([CLI, "paint", scene, "--brdf", "ct:rough=0.3,kd=0.4/0.3/0.2,f0=0.25",
                    "--env", "sky", "--lights", "64", "-o", os.path.join(tmp, "paint")],
                   check=True, stdout=subprocess.DEVNULL)
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201,
                schema="Scene.json").json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201,
               schema="Session.json").json()
    S.update(scene=sc["id"], session=s["id"], paint=s["paint_token"], view=s["view_token"])
    for k in (0, 5):
        with open(os.path.join(tmp, "paint", "view_%02d.exr" % k), "rb") as f:
            d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                  headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}),
                  data=f.read(), status=200)


def test_02_the_fit_is_a_job_then_warm(d):
    # the scene's base renders are lit by its point lights: the fit runs (these
    # paintings were made under the sky) and the answer says what it assumes
    r = d.post("/api/v1/sessions/%s/fits" % S["session"],
               headers=dict(tok(S["paint"]), **{"Content-Type": "application/json"}),
               data=json.dumps({"method": "srbf", "params": PARAMS}), status=202,
               schema="JobResponse.json").json()
    assert len(r["warnings"]) == 1 and "point lights" in r["warnings"][0], r
    job = r["job"]
    j = wait_job(d, job["id"])
    assert j["state"] == "done", j
    m = d.get("/api/v1/materials/" + j["material_id"], headers=tok(S["view"]), status=200,
              schema="Material.json").json()
    assert m["method"] == "srbf"
    levels = m["precomputation"]["cache"]["levels"]
    assert sorted(levels) == ["energy", "lights", "pattern", "rows", "transfer"], levels
    assert m["errors"]["rel_rms_painted"] < 0.1, m["errors"]
    assert m["errors"]["albedo_max_rows"] <= 1.0
    assert m["precomputation"]["mesh_convex"] is True and m["precomputation"]["visibility"] == 0
    S["material"] = m
    kind, m2 = fit(d, {"method": "srbf", "params": dict(PARAMS, diffuse="0.3")}, expect=(201,))
    assert m2["precomputation"]["cache"]["memory"] == "hit"   # diffuse changes the fit only
    assert m2["params"]["diffuse"] == "0.3" and m2["diffuse"] == [0.3, 0.3, 0.3], m2["diffuse"]


def test_03_the_material_evaluates_and_renders(d):
    mid, h = S["material"]["id"], tok(S["view"])
    pkg = d.get("/api/v1/materials/%s/package" % mid, headers=h, status=200)
    assert len(pkg.content) > 1000
    r = d.post("/api/v1/materials/%s/eval" % mid,
               headers=dict(h, **{"Content-Type": "application/json"}),
               data=json.dumps({"pairs": [{"n": [0, 0, 1], "wi": [0, 0.6, 0.8],
                                           "wo": [0, -0.6, 0.8]}]}),
               status=200, schema="EvalResponse.json").json()["values"][0]
    assert all(v > 0 for v in r), r
    sh = d.get("/api/v1/materials/%s/shader" % mid, headers=h, status=200,
               schema="Shader.json").json()
    assert "u_lobes" in sh["fragment"]
    gl = d.get("/api/v1/materials/%s/preview.exr?view=0" % mid, headers=h, status=200)
    cpu = d.get("/api/v1/materials/%s/preview.exr?view=0&renderer=cpu" % mid, headers=h,
                status=200)
    assert gl.content[:4] == b"\x76\x2f\x31\x01" and cpu.content[:4] == b"\x76\x2f\x31\x01"


def test_05_environments_of_the_env_dir(d):
    env = d.get("/api/v1/environments", status=200).json()["environments"]
    specs = [e["spec"] for e in env]
    assert specs[:5] == ["studio", "sky", "sunset", "overcast", "white"], specs
    assert "data:bright.hdr" in specs and not any("hidden" in x or "evil" in x for x in specs)
    kind, job = fit(d, {"method": "srbf", "params": dict(PARAMS, env="data:bright.hdr")})
    if kind == "job":
        j = wait_job(d, job["id"])
        assert j["state"] == "done", j
    # refused before anything is queued, naming the parameter
    for bad in ("data:evil.hdr", "data:.hidden.hdr", "data:../bright.hdr", "data:nosuch.hdr"):
        r = d.post("/api/v1/sessions/%s/fits" % S["session"], headers=tok(S["paint"]),
                   json={"method": "srbf", "params": dict(PARAMS, env=bad)}, status=422)
        assert "params.env" in r.json()["detail"] and "no environment" in r.json()["detail"], \
            (bad, r.text)


def test_06_previews_under_an_environment(d):
    mid, h = S["material"]["id"], tok(S["view"])
    url = "/api/v1/materials/%s/preview.exr" % mid
    a = d.get(url + "?view=0&env=sky&lights=64", headers=h, status=200)
    info = a.headers["X-Glint-Env"]
    assert "lights=64" in info and "cached=0" in info and "convex=1" in info, info
    assert a.content[:4] == b"\x76\x2f\x31\x01"
    b = d.get(url + "?view=0&env=sky&lights=64", headers=h, status=200)
    assert "cached=1" in b.headers["X-Glint-Env"], b.headers["X-Glint-Env"]
    cpu = d.get(url + "?view=0&env=sky&lights=64&renderer=cpu", headers=h, status=200)
    assert cpu.headers["X-Glint-Renderer"].startswith("cpu")
    try:
        import numpy as np
        import OpenImageIO as oiio
    except ImportError:
        np = None
    if np is not None and "vertex shading" in a.headers["X-Glint-Renderer"]:
        imgs = []
        for r in (a, cpu, b):
            # a file of its own for each: OpenImageIO caches images by name, and
            # a rewritten file of the same size within a second reads as the old one
            path = os.path.join(ENV_DIR, "p%d.exr" % len(imgs))
            with open(path, "wb") as f:
                f.write(r.content)
            imgs.append(np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT)))
        # background: the same sky on both; the object: vertex against pixel shading
        rel = np.sqrt(((imgs[0] - imgs[1]) ** 2).sum() / (imgs[1] ** 2).sum())
        assert rel < 0.1, rel
        # the cached lights and visibility: the same image
        same = imgs[0] == imgs[2]
        assert same.all(), ("pixels differ", int((~same).sum()),
                            float(np.abs(imgs[0] - imgs[2]).max()), b.headers["X-Glint-Renderer"],
                            b.headers["X-Glint-Env"], a.headers["X-Glint-Env"])
    # a free camera needs no light under an environment; a map of the env dir, rotated
    # (its lights are sampled from a new map: over a minute under ASAN on a
    # slow machine, so this request waits longer than the harness's 60 s)
    d.get(url + "?eye=0,-3,1&env=data:bright.hdr&env_rotation=90&shadows=0&background=0",
          headers=h, status=200, timeout=600)
    d.get(url + "?eye=0,-3,1", headers=h, status=422)
    for q, code in (("env=data:evil.hdr", 404), ("env=data:../x.hdr", 404),
                    ("env=a%20b", 422), ("view=0&env_rotation=10", 422),
                    ("view=0&env=sky&lights=0", 422), ("view=0&env=sky&lights=5000", 422),
                    ("view=0&env=sky&shadows=2", 422), ("view=0&env=sky&env_intensity=-1", 422),
                    ("view=0&env=sky&env_rotation=nan", 422)):
        if not q.startswith("view"):
            q = "view=0&" + q
        r = d.get(url + "?" + q, headers=h)
        assert r.status_code == code, (q, r.status_code, r.text)
    # the base render to paint on, under the same sky
    base = d.get("/api/v1/scenes/%s/views/0/base.png?env=sky&lights=64&brdf=lambert:kd=0.5"
                 % S["scene"], status=200)
    assert base.content[:4] == b"\x89PNG"
    d.get("/api/v1/scenes/%s/views/0/base.png?env=nosuch" % S["scene"], status=404)


def test_07_uploaded_environments(d):
    """POST /api/v1/environments: decoded before it is kept, listed, named by
    fits and previews as upload:<id>, refused with a reason when it cannot
    be used, deleted."""
    with open(os.path.join(ENV_DIR, "bright.hdr"), "rb") as f:
        hdr = f.read()
    oct_ = {"Content-Type": "application/octet-stream", "X-Glint-Owner": OWNER}
    r = d.post("/api/v1/environments?name=bright%20upload", headers=oct_, data=hdr, status=201,
               schema="Environment.json")
    up = r.json()
    assert up.pop("owner_key") == OWNER, up
    assert up["spec"] == "upload:" + up["id"] and up["kind"] == "upload", up
    assert (up["width"], up["height"], up["layout"], up["format"]) == (64, 32, "latlong", "hdr")
    assert up["name"] == "bright upload" and up["bytes"] == len(hdr)
    assert r.headers["Location"] == "/api/v1/environments/" + up["id"]
    listed = d.get("/api/v1/environments", headers={"X-Glint-Owner": OWNER},
                   status=200).json()["environments"]
    assert [e for e in listed if e["spec"] == up["spec"]] == [up], listed
    # a fit and a preview under it
    kind, job = fit(d, {"method": "srbf", "params": dict(PARAMS, env=up["spec"])})
    if kind == "job":
        j = wait_job(d, job["id"])
        assert j["state"] == "done", j
        lit = j["material_id"]
    else:
        lit = job["id"]
    mid, h = S["material"]["id"], tok(S["view"])
    p = d.get("/api/v1/materials/%s/preview.exr?view=0&lights=32&env=%s" % (mid, up["spec"]),
              headers=h, status=200)
    assert ("env=" + up["spec"]) in p.headers["X-Glint-Env"], p.headers["X-Glint-Env"]
    # shared data: an EXR from the CC0 maps when present
    exr = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data", "envmaps",
                       "courtyard.exr")
    if os.path.exists(exr) and os.path.getsize(exr) < 48 << 20:
        with open(exr, "rb") as f:
            r = d.post("/api/v1/environments", headers=oct_, data=f.read())
        assert r.status_code in (201, 422), r.text  # 422 only when its sides pass 4096
        if r.status_code == 201:
            e = r.json()
            assert e["format"] == "exr" and e["width"] == 2 * e["height"], e
            d.delete("/api/v1/environments/" + e["id"], headers={"X-Glint-Owner": OWNER},
                     status=204)
    # refused, each with its reason
    flat = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n"
    cases = [
        (b"", 400, "empty-body"),
        (b"hello, not a map", 422, "neither OpenEXR nor Radiance"),
        (b"\x76\x2f\x31\x01" + bytes(200), 422, "cannot be used"),
        (flat % (40, 64) + bytes(4 * 40 * 64), 422, "cannot be used"),     # 8:5, no layout
        (flat % (2049, 4098) + bytes(4096), 422, "4096"),  # sides above 4096: from the header
        (hdr[:len(hdr) // 2], 422, "cannot be used"),                       # truncated
    ]
    for body, code, words in cases:
        r = d.post("/api/v1/environments", headers=oct_, data=body)
        assert r.status_code == code and words in r.text, (body[:20], r.status_code, r.text)
    for q in ("name=", "name=a%22b", "name=" + "x" * 61):
        r = d.post("/api/v1/environments?" + q, headers=oct_, data=hdr)
        assert r.status_code == 422, (q, r.status_code, r.text)
    for bad in ("upload:" + "0" * 32, "upload:../bright.hdr", "upload:" + up["id"] + ".hdr"):
        r = d.get("/api/v1/materials/%s/preview.exr?view=0&env=%s" % (mid, bad), headers=h)
        assert r.status_code == 404, (bad, r.status_code, r.text)
    # deleted by its owner: no longer listed or read; a second delete is 404
    d.delete("/api/v1/environments/" + up["id"], headers={"X-Glint-Owner": OWNER}, status=204)
    listed = d.get("/api/v1/environments", headers={"X-Glint-Owner": OWNER},
                   status=200).json()["environments"]
    assert up["spec"] not in [e["spec"] for e in listed]
    d.get("/api/v1/materials/%s/preview.exr?view=0&env=%s" % (mid, up["spec"]), headers=h,
          status=404)
    d.delete("/api/v1/environments/" + up["id"], headers={"X-Glint-Owner": OWNER}, status=404)
    d.delete("/api/v1/environments/nosuch", status=404)
    # the material fitted under it is its own BRDF: it still reads, renders and exports
    m = d.get("/api/v1/materials/" + lit, headers=h, status=200, schema="Material.json").json()
    assert m["params"]["env"] == up["spec"], m["params"]
    assert d.get("/api/v1/materials/%s/preview.exr?view=0" % lit, headers=h,
                 status=200).content[:4] == b"\x76\x2f\x31\x01"
    assert d.get("/api/v1/materials/%s/preview.exr?view=0&env=sky&lights=32" % lit, headers=h,
                 status=200).content[:4] == b"\x76\x2f\x31\x01"
    assert len(d.get("/api/v1/materials/%s/package" % lit, headers=h, status=200).content) > 1000
    d.get("/api/v1/materials/%s/shader" % lit, headers=h, status=200, schema="Shader.json")


def test_07b_uploads_belong_to_their_owner(d):
    """An uploaded environment is listed to the owner key it was made with
    and deleted by it (or the API key); the built-ins and data: maps are
    everyone's and never deleted; a scene whose base renders it lights
    keeps it until the scene is deleted."""
    with open(os.path.join(ENV_DIR, "bright.hdr"), "rb") as f:
        hdr = f.read()
    oct_ = {"Content-Type": "application/octet-stream"}
    mine, other = {"X-Glint-Owner": OWNER}, {"X-Glint-Owner": "another-owner-key-0000"}
    up = d.post("/api/v1/environments?name=mine", headers=dict(oct_, **mine), data=hdr,
                status=201, schema="Environment.json").json()
    url = "/api/v1/environments/" + up["id"]
    # what a caller without credentials sees and may do: not listed, not deleted
    envs = d.get("/api/v1/environments", status=200).json()["environments"]
    assert up["spec"] not in [e["spec"] for e in envs], envs
    r = d.delete(url, status=401)
    assert r.json()["type"].endswith("/owner-key-required"), r.text
    assert up["owner_key"] == OWNER
    # no owner key sent: the daemon makes one, answered this once
    made = d.post("/api/v1/environments", headers=oct_, data=hdr, status=201,
                  schema="Environment.json").json()
    assert len(made["owner_key"]) == 32 and made["owner_key"] != OWNER, made
    d.post("/api/v1/environments", headers=dict(oct_, **{"X-Glint-Owner": "short"}), data=hdr,
           status=422)

    def listed(headers):
        envs = d.get("/api/v1/environments", headers=headers, status=200).json()["environments"]
        for e in envs:
            assert "owner" not in e and "owner_key" not in e, e
        return [e["spec"] for e in envs]
    anyone, others = listed({}), listed(other)
    for specs in (anyone, others):
        assert "sky" in specs and "data:bright.hdr" in specs, specs
        assert up["spec"] not in specs and made["spec"] not in specs, specs
    assert up["spec"] in listed(mine) and made["spec"] not in listed(mine)
    assert made["spec"] in listed({"X-Glint-Owner": made["owner_key"]})
    # deleting: 403 with another owner key, never a built-in or data: map
    r = d.delete(url, headers=other, status=403)
    assert r.json()["type"].endswith("/not-owner"), r.text
    for name in ("sky", "builtin:studio", "data:bright.hdr"):
        r = d.delete("/api/v1/environments/" + name, headers=mine, status=403)
        assert r.json()["type"].endswith("/not-deletable"), r.text
    assert "sky" in listed({}) and "data:bright.hdr" in listed({})
    # a scene lit by it: the upload stays while the scene does
    body = {"width": 32, "height": 32, "base": {"env": {"spec": up["spec"], "lights": 16}}}
    sc = d.post("/api/v1/scenes", json=body, headers=other, status=201,
                schema="Scene.json").json()
    r = d.delete(url, headers=mine, status=409)
    assert r.json()["type"].endswith("/environment-in-use") and "1 scene" in r.text, r.text
    d.get("/api/v1/scenes/%s/views/1/base.png" % sc["id"], status=200)
    d.delete("/api/v1/scenes/" + sc["id"], headers=other, status=204)
    d.delete(url, headers=mine, status=204)
    assert up["spec"] not in listed(mine)
    d.delete("/api/v1/environments/" + made["id"],
             headers={"X-Glint-Owner": made["owner_key"]}, status=204)


def test_07c_nonfinite_texels_read_as_zero(d):
    """An OpenEXR map with NaN and infinite texels is kept, those texels
    read as 0 and counted, as the API says."""
    import math
    w, h = 16, 8
    chans = {c: [0.5] * (w * h) for c in "RGB"}
    chans["R"][3], chans["G"][17], chans["B"][40] = math.nan, math.inf, -math.inf
    oct_ = {"Content-Type": "application/octet-stream", "X-Glint-Owner": OWNER}
    r = d.post("/api/v1/environments?name=holes", headers=oct_, data=exr_named.write(w, h, chans),
               status=201, schema="Environment.json")
    e = r.json()
    assert e["nonfinite"] == 3 and e["format"] == "exr" and e["width"] == w, e
    # usable: a base render under it
    sc = d.post("/api/v1/scenes", headers={"X-Glint-Owner": OWNER},
                json={"width": 16, "height": 16, "base": {"env": {"spec": e["spec"], "lights": 8}}},
                status=201).json()
    d.get("/api/v1/scenes/%s/views/0/base.png" % sc["id"], status=200)
    d.delete("/api/v1/scenes/" + sc["id"], headers={"X-Glint-Owner": OWNER}, status=204)
    d.delete("/api/v1/environments/" + e["id"], headers={"X-Glint-Owner": OWNER}, status=204)


def undated(exr):
    """OpenEXR bytes less the value of the capDate attribute the writer
    stamps (two renders of the same pixels a second apart differ there)."""
    key = b"capDate\x00string\x00"
    i = exr.find(key)
    if i < 0:
        return exr
    j = i + len(key) + 4
    n = int.from_bytes(exr[i + len(key):j], "little")
    return exr[:j] + bytes(n) + exr[j + n:]


def test_08_a_scene_to_paint_under_an_environment(d):
    """base.env at creation: the scene's base renders (what an artist paints
    on, and what an unpainted view is) are lit by the environment."""
    body = {"width": SIZE, "height": SIZE, "base": {"env": {"spec": "sky", "lights": 64}}}
    sc = d.post("/api/v1/scenes", json=body, status=201, schema="Scene.json").json()
    assert sc["base"]["env"] == {"spec": "sky", "rotation": 0, "intensity": 1, "lights": 64,
                                 "shadows": True, "background": True}, sc["base"]
    got = d.get("/api/v1/scenes/%s/views/0/base.png?format=exr" % sc["id"], status=200).content
    same = d.get("/api/v1/scenes/%s/views/0/base.png?format=exr&env=sky&lights=64" % sc["id"],
                 status=200).content
    lamp = d.get("/api/v1/scenes/%s/views/0/base.png?format=exr" % S["scene"],
                 status=200).content
    assert got[:4] == b"\x76\x2f\x31\x01"
    assert undated(got) == undated(same) and undated(got) != undated(lamp)
    for env, code in (({"spec": "nosuch"}, 404), ({"spec": "sky", "lights": 0}, 422),
                      ({"spec": "sky", "rotation": "x"}, 422), ({"spec": "sky", "up": 1}, 422),
                      ({"spec": "a b"}, 422), ({"lights": 8}, 422), ("sky", 422),
                      ({"spec": "sky", "intensity": -1}, 422), ({"spec": "sky", "shadows": 1}, 422)):
        r = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE, "base": {"env": env}})
        assert r.status_code == code and "base.env" in r.text, (env, r.status_code, r.text)


def test_04_parameters_are_checked_by_the_table(d):
    h = dict(tok(S["paint"]), **{"Content-Type": "application/json"})
    url = "/api/v1/sessions/%s/fits" % S["session"]
    r = d.post(url, headers=h, data=json.dumps({"method": "srbf",
                                                "params": {"diffuse": "1.5"}}), status=422)
    assert "params.diffuse" in r.json()["detail"] and "above 1" in r.json()["detail"]
    r = d.post(url, headers=h, data=json.dumps({"method": "srbf",
                                                "params": {"env": "a b"}}), status=422)
    assert "params.env" in r.json()["detail"]
    r = d.post(url, headers=h, data=json.dumps({"method": "srbf",
                                                "params": {"lights": 0}}), status=422)
    assert "params.lights" in r.json()["detail"]
    # a spec the daemon cannot resolve (it reads no file a request names):
    # refused at once, not by the job
    r = d.post(url, headers=h, data=json.dumps({"method": "srbf", "params": dict(
        PARAMS, env="file:/etc/passwd")}), status=422)
    assert "params.env" in r.json()["detail"] and "built-in" in r.json()["detail"], r.text


def test_09_held_out_error_under_the_environment(d):
    # two painted views: the fit's point gets a leave-one-view-out error,
    # each view rendered under the environment from the other's fit
    # (measured in the background, below every request's priority and in
    # the daemon's pauses: wait for it; the deadline only guards a hang)
    deadline = time.time() + 300
    while True:
        m = d.get("/api/v1/methods?scene_id=" + S["scene"], status=200,
                  schema="Methods.json").json()
        pts = [p for p in m["scene"]["points"] if p["method"] == "srbf" and
               p["params"] == S["material"]["params"]]
        assert len(pts) == 1, m["scene"]["points"]
        p = pts[0]
        if p["held_out_rms"] is not None or time.time() > deadline:
            break
        time.sleep(0.2)
    assert p["held_out_rms"] is not None, "no held-out error after 300 s"
    h = p["held_out"]
    print("  held out rms %.4g (painted %.4g) in %.2f s" % (p["held_out_rms"], p["rms_painted"],
                                                          h.get("seconds", -1)))
    assert h["method"] == "leave-one-view-out" and h["views"] == 2, h
    assert [v["view"] for v in h["per_view"]] == [0, 5], h
    assert all(v["pixels"] > 0 for v in h["per_view"]), h
    # a new view is harder than the painted one, and a Cook-Torrance target
    # is within reach of the model (seed 004: 18-25% on new views)
    assert p["rms_painted"] * 0.5 <= p["held_out_rms"] < 10 * p["rms_painted"] + 0.05, p


run_tests(globals(), daemon_args=("--env-dir", ENV_DIR))
