"""A method added by one core file and one registration line, through the
real daemon: the test build glintd-test (tests/methods) registers
"lambert-test", a constant-colour Lambert fit, next to hf3.  Nothing in
server/ knows it: it is fitted (cold as a job, warm at once), rendered,
evaluated, exported and measured through the same endpoints as hf3."""
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
KD = (0.3, 0.5, 0.7)
S = {}


def tok(t):
    return {"X-Glint-Token": t}


def fit(d, body, expect=(201, 202)):
    r = d.post("/api/v1/sessions/%s/fits" % S["session"],
               headers=dict(tok(S["paint"]), **{"Content-Type": "application/json"}),
               data=json.dumps(body))
    assert r.status_code in expect, r.text
    if r.status_code == 201:
        return "material", r.json()
    return "job", r.json()["job"]


def wait_job(d, jid):
    deadline = time.time() + 120
    while time.time() < deadline:
        j = d.get("/api/v1/jobs/" + jid, headers=tok(S["paint"]), status=200,
                  schema="JobResponse.json").json()["job"]
        if j["state"] in ("done", "failed"):
            return j
        time.sleep(0.1)
    raise AssertionError("job %s did not finish" % jid)


def test_00_methods_lists_the_added_method(d):
    m = d.get("/api/v1/methods", status=200, schema="Methods.json").json()["methods"]
    # the build's own methods (the CLI has no test methods), then the added one
    builtin = json.loads(subprocess.run([CLI, "methods", "--json"], check=True,
                                        capture_output=True, text=True).stdout)["methods"]
    names = [x["name"] for x in builtin]
    assert names[0] == "hf3" and "lambert-test" not in names, names
    assert [x["name"] for x in m] == names + ["lambert-test"], [x["name"] for x in m]
    lam = m[-1]
    assert [p["name"] for p in lam["params"]] == ["albedo_max"]
    # what a person reads of it, from its table alone
    assert lam["label"] == "Flat colour (test build)", lam
    assert lam["lighting"] == "point" and lam["shows"] == "none" and lam["surface"] == [], lam
    assert lam["varies"] is False and lam["chooses"] is False, lam
    assert "Lambert" in lam["summary"] and lam["when"], lam
    assert lam["params"][0]["label"] == "brightest colour allowed", lam["params"]
    assert lam["params"][0]["group"] == "basic", lam["params"]
    assert lam["params"][0]["default"] == 1.0


def test_01_setup(d):
    tmp = tempfile.mkdtemp(prefix="glint-plugin-")
    scene = os.path.join(tmp, "scene.json")
    subprocess.run([CLI, "scene", "create", "--size", str(SIZE), "-o", scene], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([CLI, "paint", scene, "--brdf", "lambert:kd=%g/%g/%g" % KD, "--scale", "1",
                    "--format", "exr", "-o", os.path.join(tmp, "paint")], check=True,
                   stdout=subprocess.DEVNULL)
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201,
                schema="Scene.json").json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201,
               schema="Session.json").json()
    S.update(scene=sc["id"], session=s["id"], paint=s["paint_token"], view=s["view_token"])
    for k in range(12):
        with open(os.path.join(tmp, "paint", "view_%02d.exr" % k), "rb") as f:
            d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                  headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}),
                  data=f.read(), status=200)


def test_02_cold_fit_is_a_job_then_warm_fits_answer_at_once(d):
    kind, job = fit(d, {"method": "lambert-test"}, expect=(202,))
    j = wait_job(d, job["id"])
    assert j["state"] == "done", j
    m = d.get("/api/v1/materials/" + j["material_id"], headers=tok(S["view"]), status=200,
              schema="Material.json").json()
    assert m["method"] == "lambert-test" and m["params"] == {"albedo_max": 1.0}
    levels = m["precomputation"]["cache"]["levels"]
    assert sorted(levels) == ["lambert-gram", "pattern"], levels
    assert levels["lambert-gram"]["memory"] == "built"
    assert m["errors"]["rms_painted"] < 1e-4, m["errors"]
    S["material"] = m
    kind, m2 = fit(d, {"method": "lambert-test"}, expect=(201,))
    assert m2["precomputation"]["cache"]["memory"] == "hit"
    # the hf3 levels were not touched: a fit with another method shares only the pattern
    kind, x = fit(d, {"method": "hf3", "params": {"res": 16}}, expect=(202,))
    wait_job(d, x["id"])


def test_03_parameters_come_from_the_table(d):
    r = d.post("/api/v1/sessions/%s/fits" % S["session"], headers=tok(S["paint"]),
               json={"method": "lambert-test", "params": {"albedo_max": 0}}, status=422)
    assert "params.albedo_max" in r.json()["detail"]
    r = d.post("/api/v1/sessions/%s/fits" % S["session"], headers=tok(S["paint"]),
               json={"method": "lambert-test", "params": {"res": 32}}, status=422)
    assert "params.res" in r.json()["detail"] and "lambert-test takes albedo_max" in \
        r.json()["detail"]
    kind, m = fit(d, {"method": "lambert-test", "params": {"albedo_max": 0.4}})
    if kind == "job":
        m = d.get("/api/v1/materials/" + wait_job(d, m["id"])["material_id"],
                  headers=tok(S["view"]), status=200).json()
    assert m["params"] == {"albedo_max": 0.4}


def test_04_the_material_evaluates_renders_and_exports(d):
    mid, h = S["material"]["id"], tok(S["view"])
    pkg = d.get("/api/v1/materials/%s/package" % mid, headers=h, status=200)
    with tarfile.open(fileobj=io.BytesIO(pkg.content)) as t:
        names = sorted(n.split("/", 1)[1] for n in t.getnames())
        top = t.getnames()[0].split("/")[0]
        manifest = json.load(t.extractfile(top + "/material.json"))
    assert names == ["material.json", "shader/glint_material.frag",
                     "shader/glint_material.vert", "shader/glint_material_330.frag",
                     "shader/glint_material_330.vert", "shader/shader.json"], names
    assert manifest["method"] == "lambert-test"
    for c in range(3):
        assert abs(manifest["albedo"][c] - KD[c]) < 1e-4, manifest["albedo"]
    r = d.post("/api/v1/materials/%s/eval" % mid, headers=dict(h, **{"Content-Type": "application/json"}),
               data=json.dumps({"pairs": [{"n": [0, 0, 1], "wi": [0, 0.6, 0.8], "wo": [0, 0, 1]}]}),
               status=200, schema="EvalResponse.json").json()["values"][0]
    for c in range(3):
        assert abs(r[c] - manifest["albedo"][c] / math.pi * 0.8) < 1e-6, r
    sh = d.get("/api/v1/materials/%s/shader" % mid, headers=h, status=200,
               schema="Shader.json").json()
    assert "u_albedo" in sh["fragment"] and sorted(sh["files"]) == [
        "glint_material.frag", "glint_material.vert", "glint_material_330.frag",
        "glint_material_330.vert", "shader.json"]
    assert sh["manifest"]["method"] == "lambert-test"
    d.get("/api/v1/materials/%s/factors.png" % mid, headers=h, status=404)
    # previews: the method's shader on EGL and its evaluation on the CPU agree
    gl = d.get("/api/v1/materials/%s/preview.exr?view=0" % mid, headers=h, status=200)
    cpu = d.get("/api/v1/materials/%s/preview.exr?view=0&renderer=cpu" % mid, headers=h,
                status=200)
    assert cpu.headers["X-Glint-Renderer"] == "cpu"
    assert gl.content[:4] == b"\x76\x2f\x31\x01" and cpu.content[:4] == b"\x76\x2f\x31\x01"
    png = d.get("/api/v1/materials/%s/preview.png?eye=0,3,1&light=2,2,2&size=64" % mid,
                headers=h, status=200)
    assert png.headers["Content-Type"] == "image/png" and len(png.content) > 100


def test_05_points_record_the_method(d):
    pts = d.get("/api/v1/methods?scene_id=" + S["scene"], status=200,
                schema="Methods.json").json()["scene"]["points"]
    methods = sorted({p["method"] for p in pts})
    assert methods == ["hf3", "lambert-test"], methods


run_tests(globals())
