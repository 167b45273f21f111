"""The material ball (GET /materials/{id}/preview.png?object=ball) through
the real daemon: a material fitted on a torus shown on a unit sphere whose
silhouette covers the disc that geometry predicts (the torus's own render
does not); under an environment, the ball's vertex shading drawn through EGL
against the CPU's per-pixel reference; a furnace check (a white environment
of radiance 1 returns the material's directional albedo at the ball's
centre); the parameter checks."""
import json
import math
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
from harness import run_tests  # noqa: E402

SIZE = 48
SPEC = "ct:rough=0.3,kd=0.5/0.35/0.2,f0=0.2"
S = {}

try:
    import numpy as np
    import OpenImageIO as oiio
except ImportError:  # the image checks need Debian's python3-numpy and python3-openimageio
    np = None


def tok(t):
    return {"X-Glint-Token": t}


def exr(content):
    path = os.path.join(tempfile.mkdtemp(prefix="glint-ball-"), "p.exr")
    with open(path, "wb") as f:
        f.write(content)
    return np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT))[:, :, :3]


def test_01_a_torus_painted_and_fitted(d):
    sc = d.post("/api/v1/scenes", json={"mesh": "torus", "width": SIZE, "height": SIZE},
                status=201, schema="Scene.json").json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201,
               schema="Session.json").json()
    S.update(scene=sc, session=s)
    for k in (0, 4, 7):
        img = d.get("/api/v1/scenes/%s/views/%d/base.png?format=exr&brdf=%s" % (sc["id"], k, SPEC),
                    status=200).content
        d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
              headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}), data=img,
              status=200)
    r = d.post("/api/v1/sessions/%s/fits" % s["id"],
               headers=dict(tok(s["paint_token"]), **{"Content-Type": "application/json"}),
               data=json.dumps({"method": "hf3", "params": {"res": 32}}))
    assert r.status_code in (201, 202), r.text
    if r.status_code == 202:
        jid, deadline = r.json()["job"]["id"], time.time() + 300
        while True:
            j = d.get("/api/v1/jobs/" + jid, headers=tok(s["paint_token"]), status=200).json()["job"]
            if j["state"] in ("done", "failed"):
                break
            assert time.time() < deadline
            time.sleep(0.2)
        assert j["state"] == "done", j
        S["material"] = j["material_id"]
    else:
        S["material"] = r.json()["id"]


def test_02_the_ball_is_a_unit_sphere_framed_like_the_object(d):
    url = "/api/v1/materials/%s/preview.exr" % S["material"]
    h = tok(S["session"]["view_token"])
    # lit from everywhere (a white environment), every pixel the object covers is > 0
    q = "?view=0&size=256&env=white&lights=32&background=0"
    ball = d.get(url + q + "&object=ball", headers=h, status=200)
    torus = d.get(url + q, headers=h, status=200)
    d.get(url + "?view=0&object=scene&size=64", headers=h, status=200)
    d.get(url + "?view=0&object=ball&size=64", headers=h, status=200)
    if np is None:
        return
    v = S["scene"]["views"][0]
    dist = math.dist(v["eye"], v.get("target", [0, 0, 0]))
    # a unit sphere seen from dist under half field of view h: a disc of
    # radius tan(asin(1 / dist)) / tan(h) in normalized device coordinates
    rad = math.tan(math.asin(1.0 / dist)) / math.tan(v["half_fov"])
    want = math.pi * rad * rad / 4.0
    b, t = exr(ball.content), exr(torus.content)
    cover_b = float((b.max(axis=2) > 0).mean())
    cover_t = float((t.max(axis=2) > 0).mean())
    print("ball covers %.4f of the image (a unit sphere: %.4f), the torus %.4f"
          % (cover_b, want, cover_t))
    assert abs(cover_b - want) < 0.01, (cover_b, want)
    assert abs(cover_t - want) > 0.05, (cover_t, want)


def test_03_under_an_environment_vertex_against_pixel_shading(d):
    url = "/api/v1/materials/%s/preview.exr" % S["material"]
    h = tok(S["session"]["view_token"])
    q = "?object=ball&eye=0,-3.5,1.2&env=studio&lights=64&background=0&size=128"
    gl = d.get(url + q, headers=h, status=200)
    info = gl.headers["X-Glint-Env"]
    assert "convex=1" in info and "rays=0" in info, info
    cpu = d.get(url + q + "&renderer=cpu", headers=h, status=200)
    assert cpu.headers["X-Glint-Renderer"].startswith("cpu")
    if np is None or "vertex shading" not in gl.headers["X-Glint-Renderer"]:
        return
    a, b = exr(gl.content), exr(cpu.content)
    both = (a.max(axis=2) > 0) & (b.max(axis=2) > 0)
    rel = float(np.sqrt(((a - b)[both] ** 2).sum() / (b[both] ** 2).sum()))
    print("ball under the studio: vertex shading %.4f from pixel shading" % rel)
    assert both.sum() > 0.3 * both.size and rel < 0.03, (int(both.sum()), rel)


def test_04_furnace(d):
    """Under the white environment (radiance 1 everywhere) the pixel at the
    ball's centre, seen head on, is the integral of f cos over the
    hemisphere: the directional albedo the summary reports at 0 degrees."""
    if np is None:
        return
    mid, h = S["material"], tok(S["session"]["view_token"])
    img = exr(d.get("/api/v1/materials/%s/preview.exr?object=ball&eye=0,-3.5,0&env=white"
                    "&lights=1024&renderer=cpu&background=0&size=65" % mid, headers=h,
                    status=200).content)
    centre = img[32, 32]
    summ = d.get("/api/v1/materials/%s/summary" % mid, headers=h, status=200,
                 schema="MaterialSummary.json").json()
    alb = [a for a in summ["albedo"] if a["theta_deg"] == 0][0]["rgb"]
    print("furnace: ball centre", [round(float(x), 4) for x in centre], "albedo at 0 deg",
          [round(x, 4) for x in alb])
    for c in range(3):
        assert abs(centre[c] - alb[c]) < 0.03 * max(alb[c], 0.05), (c, centre, alb)


def test_05_checks(d):
    url = "/api/v1/materials/%s/preview.png" % S["material"]
    h = tok(S["session"]["view_token"])
    for q in ("view=0&object=cube", "view=0&object=", "view=0&object=ball&size=5",
              "object=ball&eye=0,0,0&target=0,0,0&light=1,1,1"):
        r = d.get(url + "?" + q, headers=h)
        assert r.status_code == 422, (q, r.status_code, r.text)
        assert r.headers["Content-Type"].startswith("application/problem+json")
    assert "object must be scene or ball" in d.get(url + "?view=0&object=cube", headers=h).text
    d.get(url + "?view=0&object=ball", status=401)


run_tests(globals())
