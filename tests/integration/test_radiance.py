"""One radiance scale on the studio's path, through the real daemon
(scene.h: a point light of intensity I makes a white Lambertian facing it
read I; under an environment a pixel is the integral of L f cos).

A finish applied as the studio applies it (GET base.png?brdf=SPEC&format=exr
with the scene's own base settings, uploaded as every view's painting) and
fitted reads back its base colour in the material's summary within 2%, and
the material's preview of a painted view matches the finish's render of
that view; the same under an environment with srbf.  A scene stored before
the scene documents named their radiance (base scale pi) is read in
today's units: its base renders keep their brightness."""
import json
import math
import os
import sqlite3
import sys

sys.path.insert(0, os.path.dirname(__file__))
from harness import PG, fit_material, run_tests  # noqa: E402

import numpy as np  # noqa: E402
import OpenImageIO as oiio  # noqa: E402

SIZE = 32
VIEW = 3
TOL = 0.02
PREVIEW_TOL = 0.05
S = {}


def tok(t):
    return {"X-Glint-Token": t}


def exr_pixels(data):
    """RGB of an OpenEXR held in memory (OpenImageIO reads it from a file)."""
    path = os.path.join(S["tmp"], "px.exr")
    with open(path, "wb") as f:
        f.write(data)
    inp = oiio.ImageInput.open(path)
    px = np.asarray(inp.read_image("float"))[..., :3].astype(np.float64)
    inp.close()
    return px


def painted_session(d, scene, spec):
    """A session whose every view is the finish `spec`, as the studio's
    finishes paint it (the scene's base settings, no scale of its own)."""
    s = d.post("/api/v1/sessions", json={"scene_id": scene["id"]}, status=201).json()
    env = (scene["base"].get("env") or {})
    q = "format=exr&brdf=" + spec + ("&env=" + env["spec"] if env else "")
    for k in range(len(scene["views"])):
        img = d.get("/api/v1/scenes/%s/views/%d/base.png?%s" % (scene["id"], k, q),
                    status=200).content
        d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
              headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}), data=img,
              status=200)
    return s


def check_round_trip(d, scene, spec, want, body):
    s = painted_session(d, scene, spec)
    mid = fit_material(d, s, body)
    summ = d.get("/api/v1/materials/%s/summary" % mid, headers=tok(s["view_token"]),
                 status=200).json()
    got = np.array(summ["base_colour"])
    err = float(np.linalg.norm(got - want) / np.linalg.norm(want))
    print("  %s %s: base colour %s (finish %s), %.2f%% off" % (
        body["method"], spec, np.round(got, 4), np.round(want, 4), 100 * err))
    assert err <= TOL, "base colour %s, the finish's %s" % (got, want)
    if scene["base"].get("env"):
        return
    prev = exr_pixels(d.get("/api/v1/materials/%s/preview.exr?view=%d&renderer=cpu"
                            % (mid, VIEW), headers=tok(s["view_token"]), status=200).content)
    ref = exr_pixels(d.get("/api/v1/scenes/%s/views/%d/base.png?format=exr&size=raster&brdf=%s"
                           % (scene["id"], VIEW, spec), status=200).content)
    rel = float(np.sqrt(np.mean((prev - ref) ** 2)) / np.sqrt(np.mean(ref ** 2)))
    print("  preview of view %d against the finish's render: %.2f%% relative RMS" % (VIEW, 100 * rel))
    assert rel <= PREVIEW_TOL, rel


def ct_base(kd, f0, rough):
    """pi f at light and eye 45 degrees on the same side (brdf.h's ct)."""
    c = math.cos(math.pi / 4)
    a2 = rough * rough
    D = a2 / (math.pi * (c * c * (a2 - 1) + 1) ** 2)
    G1 = 2 * c / (c + math.sqrt(a2 + (1 - a2) * c * c))
    return np.array(kd) + math.pi * D * G1 * G1 * np.array(f0) / (4 * c * c)


def test_01_point_lights(d):
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201).json()
    assert sc["base"]["scale"] == 1, sc["base"]
    assert "white Lambertian" in sc["radiance"], sc.get("radiance")
    S["scene"] = sc
    check_round_trip(d, sc, "lambert:kd=0.5", np.full(3, 0.5),
                     {"method": "hf3", "params": {"res": 32}})
    check_round_trip(d, sc, "ct:kd=0.8/0.45/0.1,f0=0.04,rough=0.25",
                     ct_base([0.8, 0.45, 0.1], [0.04] * 3, 0.25),
                     {"method": "hf3", "params": {"res": 32}})


def test_02_environment(d):
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE,
                                        "base": {"env": {"spec": "sky"}}}, status=201).json()
    assert sc["base"]["scale"] == 1, sc["base"]
    check_round_trip(d, sc, "lambert:kd=0.5", np.full(3, 0.5),
                     {"method": "srbf", "params": {"env": "sky", "lights": 64,
                                                    "basis_res": 5}})
    # a method lit by point lights is refused on it, naming those lit by one
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    for m in ("hf3", "auto"):
        r = d.post("/api/v1/sessions/%s/fits" % s["id"], headers=tok(s["paint_token"]),
                   json={"method": m}, status=422)
        assert "lighting-mismatch" in r.text and "srbf" in r.text and "sky" in r.text, r.text


def test_03_older_scene_documents(d):
    if PG:
        print("  (the metadata is in PostgreSQL: the SQLite document edit does not apply)")
        return
    sc = S["scene"]
    url = "/api/v1/scenes/%s/views/%d/base.png?format=exr&size=raster" % (sc["id"], VIEW)
    before = d.get(url, status=200).content
    d.stop()
    db = sqlite3.connect(os.path.join(d.data_dir, "glint.db"))
    doc = json.loads(db.execute("SELECT doc FROM scenes WHERE id = ?", (sc["id"],)).fetchone()[0])
    del doc["radiance"]
    doc["base"]["scale"] = math.pi
    db.execute("UPDATE scenes SET doc = ? WHERE id = ?", (json.dumps(doc), sc["id"]))
    db.commit()
    db.close()
    d.start()
    again = d.get("/api/v1/scenes/" + sc["id"], status=200).json()
    assert abs(again["base"]["scale"] - 1.0) < 1e-15, again["base"]
    assert again["radiance"] == sc["radiance"]
    after = d.get(url, status=200).content
    a, b = exr_pixels(before), exr_pixels(after)
    assert np.max(np.abs(a - b)) <= 1e-6 * np.max(np.abs(a)), np.max(np.abs(a - b))


if __name__ == "__main__":
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        S["tmp"] = tmp
        run_tests(globals())
