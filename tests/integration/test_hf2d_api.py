"""Anisotropic paint (method hf2d) through the real daemon: a brushed
highlight (anisotropic Ward, painted by the CLI) uploaded to a session and
fitted with a 2D q; against a fit with every factor 1D on the same
paintings; the material's manifest (dimensions, log nodes, frame), factor
textures, evaluation, summary, preview, shader and package; the precomputation warm
on a second fit and read from disk by a restarted daemon; the kernel form
reported for fine 2D factors over few samples; the parameter checks."""
import io
import json
import math
import os
import subprocess
import sys
import tarfile
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
from harness import GLINTD, run_tests  # noqa: E402

CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(GLINTD))), "core", "glint")
SIZE = 48
SPEC = "ward:kd=0.3/0.25/0.2,ks=0.5,rough=0.1,rough_y=0.35"
S = {}


def tok(t):
    return {"X-Glint-Token": t}


def material(d, body, session=None):
    """Fit body in the session (default: the test's, else a Session.json
    object) and return the material, waiting for its job if need be."""
    sid = session["id"] if session else S["session"]
    paint = session["paint_token"] if session else S["paint"]
    view = session["view_token"] if session else S["view"]
    r = d.post("/api/v1/sessions/%s/fits" % sid,
               headers=dict(tok(paint), **{"Content-Type": "application/json"}),
               data=json.dumps(body))
    assert r.status_code in (201, 202), r.text
    if r.status_code == 201:
        mid = r.json()["id"]
    else:
        jid, deadline = r.json()["job"]["id"], time.time() + 300
        while True:
            j = d.get("/api/v1/jobs/" + jid, headers=tok(paint), status=200,
                      schema="JobResponse.json").json()["job"]
            if j["state"] in ("done", "failed"):
                break
            assert time.time() < deadline, "job %s did not finish" % jid
            time.sleep(0.2)
        assert j["state"] == "done", j
        mid = j["material_id"]
    return d.get("/api/v1/materials/" + mid, headers=tok(view), status=200,
                 schema="Material.json").json()


def test_01_setup(d):
    tmp = tempfile.mkdtemp(prefix="glint-hf2d-")
    scene = os.path.join(tmp, "scene.json")
    subprocess.run([CLI, "scene", "create", "--size", str(SIZE), "-o", scene], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([CLI, "paint", scene, "--brdf", SPEC, "-o", os.path.join(tmp, "paint")],
                   check=True, stdout=subprocess.DEVNULL)
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201,
                schema="Scene.json").json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201,
               schema="Session.json").json()
    S.update(scene=sc["id"], session=s["id"], paint=s["paint_token"], view=s["view_token"],
             nviews=len(sc["views"]))
    for k in range(len(sc["views"])):
        with open(os.path.join(tmp, "paint", "view_%02d.exr" % k), "rb") as f:
            d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                  headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}),
                  data=f.read(), status=200)


def test_02_a_2d_q_holds_the_brushed_highlight(d):
    two = material(d, {"method": "hf2d", "params": {"res": 32, "res_2d": 32}})
    one = material(d, {"method": "hf2d", "params": {"res": 32, "q": "1d"}})
    assert two["method"] == "hf2d" and two["res_2d"] == 32 and two["dims"] == [1, 2, 1]
    assert one["dims"] == [1, 1, 1]
    assert two["precomputation"]["gauge_dims"] == 2
    assert two["precomputation"]["unknowns"] == 32 + 32 * 32 + 32
    e2, e1 = two["errors"]["rms_painted"], one["errors"]["rms_painted"]
    print("  rms painted: all 1D %.4f, q 2D %.4f (%s form, %d unknowns)"
          % (e1, e2, two["precomputation"]["form"], two["precomputation"]["unknowns"]))
    assert e2 < 0.6 * e1
    S["two"] = two
    # warm: the same parameters again take the cached decomposition
    again = material(d, {"method": "hf2d", "params": {"res": 32, "res_2d": 32}})
    assert again["precomputation"]["cache"]["memory"] == "hit", again["precomputation"]


def test_03_manifest_files_eval_preview_shader_package(d):
    mid, h = S["two"]["id"], tok(S["view"])
    man = d.get("/api/v1/materials/%s/material.json" % mid, headers=h, status=200).json()
    assert man["method"] == "hf2d" and man["dims"] == [1, 2, 1] and man["res_2d"] == 32
    assert len(man["log_nodes"]["p"]) == 32 and len(man["log_nodes"]["q"]) == 32 * 32
    assert "Z x n" in man["frame"]
    lay = man["factors_layout"]
    assert lay["width"] == 32 and lay["height"] == 1 + 32 + 1 and lay["first_row"] == [0, 1, 33]
    exr = d.get("/api/v1/materials/%s/factors.exr" % mid, headers=h, status=200)
    assert exr.content[:4] == b"\x76\x2f\x31\x01", "not OpenEXR"
    # evaluation: the highlight is narrow along t and wide along b.  At n = +X
    # (t = +Y, b = +Z), wo = n: the light tilted by 0.35 rad towards b is
    # brighter than towards t.
    c, s_ = math.cos(0.35), math.sin(0.35)
    body = {"pairs": [{"n": [1, 0, 0], "wi": [c, s_, 0], "wo": [1, 0, 0]},
                      {"n": [1, 0, 0], "wi": [c, 0, s_], "wo": [1, 0, 0]}]}
    vals = d.post("/api/v1/materials/%s/eval" % mid,
                  headers=dict(h, **{"Content-Type": "application/json"}),
                  data=json.dumps(body), status=200, schema="EvalResponse.json").json()["values"]
    print("  eval: tilted along t %s, along b %s" % (vals[0], vals[1]))
    assert vals[1][0] > 1.5 * vals[0][0], vals
    # the summary: schema-valid, a highlight with a width, albedo below 1
    sm = d.get("/api/v1/materials/%s/summary" % mid, headers=h, status=200,
               schema="MaterialSummary.json").json()
    print("  summary: base %s, highlight strength %.2f, half width %s deg" % (
        [round(x, 3) for x in sm["base_colour"]], sm["highlight"]["strength"],
        sm["highlight"]["half_width_deg"]))
    assert sm["highlight"]["strength"] > 0.5 and sm["highlight"]["half_width_deg"] > 0
    assert all(0 < x < 1.0 for a in sm["albedo"] for x in a["rgb"]), sm["albedo"]
    d.get("/api/v1/materials/%s/summary" % ("0" * 32), headers=h, status=404)
    r = d.get("/api/v1/materials/%s/preview.png?view=2" % mid, headers=h, status=200)
    assert r.content[:8] == b"\x89PNG\r\n\x1a\n"
    pkg = d.get("/api/v1/materials/%s/package" % mid, headers=h, status=200)
    with tarfile.open(fileobj=io.BytesIO(pkg.content)) as t:
        names = {n.split("/", 1)[1] for n in t.getnames() if "/" in n}
        assert {"material.json", "factors.exr", "factors.png",
                "shader/glint_material.frag"} <= names, names
        frag = t.extractfile(t.getnames()[0].split("/")[0] +
                             "/shader/glint_material.frag").read().decode()
        assert "glint_parabolic" in frag and "u_dims" in frag
    # an hf2d material has no spatial factor
    d.get("/api/v1/materials/%s/spatial.png" % mid, headers=h, status=404)


def test_04_fine_factors_over_one_view_take_the_kernel_form(d):
    # one painted view of a fresh session: few samples, three 2D factors
    s = d.post("/api/v1/sessions", json={"scene_id": S["scene"]}, status=201,
               schema="Session.json").json()
    img = d.get("/api/v1/sessions/%s/views/0/painting?format=exr" % S["session"],
                headers=tok(S["view"]), status=200).content
    d.put("/api/v1/sessions/%s/views/0/painting" % s["id"],
          headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}),
          data=img, status=200)
    m = material(d, {"method": "hf2d", "params": {"p": "2d", "q": "2d", "r": "2d",
                                                   "res_2d": 32}}, session=s)
    pre = m["precomputation"]
    print("  one view: %d samples, %d unknowns, %s form" % (pre["samples"], pre["unknowns"],
                                                           pre["form"]))
    assert pre["samples"] < pre["unknowns"] and pre["form"] == "kernel"
    assert m["errors"]["log_clamped"] == 0


def test_05_parameters_are_checked(d):
    for params, word in (({"res_2d": 2}, "res_2d"), ({"res_2d": 65}, "res_2d"),
                         ({"q": "3d"}, "q"), ({"lambda_2d": -1}, "lambda_2d"),
                         ({"p": 2}, "p")):
        r = d.post("/api/v1/sessions/%s/fits" % S["session"],
                   headers=dict(tok(S["paint"]), **{"Content-Type": "application/json"}),
                   data=json.dumps({"method": "hf2d", "params": params}))
        assert r.status_code == 422, (params, r.status_code, r.text)
        assert word in r.json()["detail"], (params, r.json())


def test_06_a_restart_reads_the_decomposition_from_disk(d):
    d.stop()
    d.start()
    m = material(d, {"method": "hf2d", "params": {"res": 32, "res_2d": 32}})
    cache = m["precomputation"]["cache"]
    assert cache["memory"] == "built" and cache["disk"] == "loaded", cache
    assert cache["levels"]["decomposition"]["disk"] == "loaded", cache
    assert m["errors"]["rms_painted"] == S["two"]["errors"]["rms_painted"]


if __name__ == "__main__":
    run_tests(globals())
