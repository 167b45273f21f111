"""Integration tests of fits, jobs, materials and methods (server/api_fits.c,
server/fitsvc.c) on the real daemon over HTTP.

Paintings are made by the glint CLI (GLINT_CLI, or core/glint next to the
daemon's build directory) for a scene with the daemon's default parameters
at 64x64: `glint scene create` gives the same content hash as the daemon's
scene (checked), `glint paint` a Cook-Torrance painting of every view.
Every JSON body is validated against proto/schemas (problem bodies by the
harness).  Tests run in name order and share the state below.
"""
import io
import json
import os
import re
import subprocess
import sys
import tarfile
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(__file__))
from harness import GLINTD, png_pixels, png_size, run_tests, sse_events, validate  # noqa: E402

import requests  # noqa: E402

CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(GLINTD))), "core", "glint")
SIZE = 64
BRDF = "ct:rough=0.3,kd=0.5,f0=0.3"
S = {}  # shared state: scene, sessions, tokens, materials


def tok(t):
    return {"X-Glint-Token": t}


def paint_headers(t=None):
    h = {"Content-Type": "application/json"}
    h.update(tok(t or S["paint"]))
    return h


def wait_job(d, job_id, token, timeout=120):
    t0 = time.time()
    while time.time() - t0 < timeout:
        j = d.get("/api/v1/jobs/%s" % job_id, headers=tok(token), status=200,
                  schema="JobResponse.json").json()["job"]
        if j["state"] in ("done", "failed"):
            return j
        time.sleep(0.05)
    raise AssertionError("job %s did not finish" % job_id)


def fit(d, params, token=None, session=None, expect=None):
    """POST a fit; return ("material", doc) or ("job", job)."""
    r = d.post("/api/v1/sessions/%s/fits" % (session or S["session"]),
               headers=paint_headers(token), data=json.dumps({"method": "hf3", "params": params}))
    if expect is not None:
        assert r.status_code == expect, (r.status_code, r.text[:400])
    if r.status_code == 201:
        validate(r.json(), "Material.json")
        assert r.headers["Location"] == "/api/v1/materials/" + r.json()["id"]
        return "material", r.json()
    assert r.status_code == 202, (r.status_code, r.text[:400])
    validate(r.json(), "JobResponse.json")
    job = r.json()["job"]
    assert r.headers["Location"] == "/api/v1/jobs/" + job["id"]
    assert job["state"] in ("queued", "running", "done")
    return "job", job


def fit_material(d, params, session=None, token=None):
    """Fit and return the material (following the job when there is one)."""
    kind, x = fit(d, params, session=session, token=token)
    if kind == "material":
        return x
    j = wait_job(d, x["id"], token or S["paint"])
    assert j["state"] == "done", j
    return get_material(d, j["material_id"], token or S["paint"])


def get_material(d, mid, token=None):
    return d.get("/api/v1/materials/" + mid, headers=tok(token or S["view"]), status=200,
                 schema="Material.json").json()


def make_session(d, views):
    s = d.post("/api/v1/sessions", json={"scene_id": S["scene"]}, status=201,
               schema="Session.json").json()
    for k in views:
        with open(os.path.join(S["paint_dir"], "view_%02d.exr" % k), "rb") as f:
            d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                  headers={"Content-Type": "image/x-exr", "X-Glint-Token": s["paint_token"]},
                  data=f.read(), status=200, schema="PaintingVersion.json")
    return s


def metric(d, name, labels):
    """Value of a Prometheus sample, or None when the metric is not exposed."""
    text = d.get("/metrics", status=200).text
    want = name + "{" + ",".join('%s="%s"' % kv for kv in labels.items()) + "}"
    for line in text.splitlines():
        if line.startswith(want + " "):
            return float(line.split()[-1])
    return None


# ---- setup -----------------------------------------------------------------------

def test_00_setup(d):
    assert os.access(CLI, os.X_OK), "glint CLI not found at %s (set GLINT_CLI)" % CLI
    tmp = tempfile.mkdtemp(prefix="glint-fits-")
    subprocess.run([CLI, "scene", "create", "--size", str(SIZE), "-o",
                    os.path.join(tmp, "scene.json")], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([CLI, "paint", os.path.join(tmp, "scene.json"), "--brdf", BRDF, "-o",
                    os.path.join(tmp, "paint")], check=True, stdout=subprocess.DEVNULL)
    shown = subprocess.run([CLI, "scene", "show", os.path.join(tmp, "scene.json")],
                           check=True, capture_output=True, text=True).stdout
    cli_hash = json.loads(shown[shown.index("{"):])["hash"]
    subprocess.run([CLI, "paint", os.path.join(tmp, "scene.json"), "--brdf",
                    "ct:rough=0.15,kd=0.3,f0=0.5", "-o", os.path.join(tmp, "paint2")],
                   check=True, stdout=subprocess.DEVNULL)
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201,
                schema="Scene.json").json()
    assert sc["hash"] == cli_hash, "the CLI's scene is not the daemon's: %s %s" % (
        sc["hash"], cli_hash)
    S.update(scene=sc["id"], nviews=len(sc["views"]), paint_dir=os.path.join(tmp, "paint"),
             paint2_dir=os.path.join(tmp, "paint2"))
    s = make_session(d, range(S["nviews"]))
    S.update(session=s["id"], paint=s["paint_token"], view=s["view_token"])


# ---- fits: cold (job), warm (201), operator level ------------------------------------

def test_01_cold_fit_is_a_job_with_progress(d):
    kind, job = fit(d, {"res": 32}, expect=202)
    assert kind == "job"
    events = sse_events(d, "/api/v1/jobs/%s/events" % job["id"], tok(S["view"]))
    for _, _, data in events:
        validate(data, "Job.json")
    types = [t for _, t, _ in events]
    assert types[-1] == "done", types
    assert all(t == "progress" for t in types[:-1]), types
    ids = [int(i) for i, _, _ in events]
    assert ids == sorted(ids) and len(set(ids)) == len(ids), ids
    stages = []
    for _, _, data in events:
        if not stages or stages[-1] != data["stage"]:
            stages.append(data["stage"])
    for st in ("samples", "design", "decomposition", "operator", "fit", "done"):
        assert st in stages, (st, stages)
    assert stages.index("samples") < stages.index("decomposition") < stages.index("fit")
    progress = [data["progress"] for _, _, data in events]
    assert progress == sorted(progress) and progress[-1] == 1.0, progress
    j = wait_job(d, job["id"], S["paint"])
    assert j["state"] == "done" and j["links"]["material"].endswith(j["material_id"])
    m = get_material(d, j["material_id"])
    assert m["session_id"] == S["session"] and m["scene_id"] == S["scene"]
    assert m["params"]["res"] == 32 and m["res"] == 32
    assert m["views_used"] == list(range(S["nviews"]))
    cache = m["precomputation"]["cache"]
    assert cache["memory"] == "built", cache
    assert cache["levels"]["decomposition"]["memory"] == "built"
    assert cache["disk"] in ("built", "rebuilt"), cache
    assert cache["levels"]["pattern"]["disk"] in ("built", "rebuilt"), cache
    assert cache["cold_seconds"] > 0
    assert m["seconds"]["decomposition"] > 0
    assert 0 < m["errors"]["rms_painted"] < 0.05, m["errors"]
    S["m32"] = m


def test_02_warm_fit_answers_at_once(d):
    # at once: in the request (201, no job), every level of the precomputation
    # a hit in memory and no time spent building one
    kind, m = fit(d, {"res": 32}, expect=201)
    cache = m["precomputation"]["cache"]
    assert cache["memory"] == "hit", cache
    assert all(lv["memory"] == "hit" for lv in cache["levels"].values()), cache
    assert cache["key"] == S["m32"]["precomputation"]["cache"]["key"]
    for st in ("samples", "design", "decomposition", "operator"):
        assert m["seconds"][st] == 0, m["seconds"]
    assert m["id"] != S["m32"]["id"]
    # the same paintings and parameters: the same factors
    assert abs(m["errors"]["rms_painted"] - S["m32"]["errors"]["rms_painted"]) < 1e-12
    # the mapping and the model do not enter the precomputation
    kind, m2 = fit(d, {"res": 32, "mapping": "log", "model": "brdf"}, expect=201)
    assert m2["params"]["mapping"].startswith("log") and m2["params"]["model"] == "brdf"
    assert m2["precomputation"]["cache"]["memory"] == "hit"


def test_03_operator_level_is_shared_with_the_decomposition(d):
    m = fit_material(d, {"res": 32, "regularization": "tikhonov:rel1e-2"})
    lv = m["precomputation"]["cache"]["levels"]
    assert lv["pattern"]["memory"] == "hit", lv
    assert lv["decomposition"]["memory"] == "hit", lv
    assert lv["operator"]["memory"] == "built", lv
    assert m["params"]["regularization"] == "tikhonov:rel0.01"
    kind, m2 = fit(d, {"res": 32, "regularization": "tikhonov:rel1e-2"}, expect=201)
    assert m2["precomputation"]["cache"]["memory"] == "hit"
    m3 = fit_material(d, {"res": 32, "precision": "single"})
    assert m3["precomputation"]["cache"]["levels"]["operator"]["memory"] == "built"
    assert m3["params"]["precision"] == "single"


# ---- materials ------------------------------------------------------------------------

def test_04_material_files(d):
    m = S["m32"]
    mid, h = m["id"], tok(S["view"])
    png = d.get("/api/v1/materials/%s/factors.png" % mid, headers=h, status=200)
    assert png.headers["Content-Type"] == "image/png"
    assert png_size(png.content) == (32, 3)
    exr = d.get("/api/v1/materials/%s/factors.exr" % mid, headers=h, status=200)
    assert exr.content[:4] == b"\x76\x2f\x31\x01", "not OpenEXR"
    sh = d.get("/api/v1/materials/%s/shader" % mid, headers=h, status=200,
               schema="Shader.json").json()
    assert sh["vertex"].startswith("#version 300 es")
    assert sh["fragment"].startswith("#version 300 es")
    for name, href in sh["files"].items():
        r = d.get(href, headers=h, status=200)
        assert len(r.content) > 0, name
    d.get("/api/v1/materials/%s/shader/passwd" % mid, headers=h, status=404)
    d.get("/api/v1/materials/%s/shader/..%%2f..%%2fglint.db" % mid, headers=h, status=404)
    pkg = d.get("/api/v1/materials/%s/package" % mid, headers=h, status=200)
    assert pkg.headers["Content-Type"] == "application/x-tar"
    assert pkg.headers["Content-Disposition"] == 'attachment; filename="sphere-%s.tar"' % mid[:8]
    with tarfile.open(fileobj=io.BytesIO(pkg.content)) as t:
        names = sorted(n.split("/", 1)[1] for n in t.getnames())
        assert names == sorted(["material.json", "factors.png", "factors.exr",
                                "shader/shader.json", "shader/glint_material.vert",
                                "shader/glint_material.frag", "shader/glint_factors.exr",
                                "shader/glint_factors_rgba16f.bin", "shader/glint_factors16.png",
                                "shader/glint_material_330.vert",
                                "shader/glint_material_330.frag"]), names
        top = t.getnames()[0].split("/")[0]
        manifest = json.load(t.extractfile(top + "/material.json"))
        assert manifest["format"] == "glint-material" and manifest["res"] == 32
        assert len(manifest["log_factors"]["p"]) == 32
        assert manifest["info"]["errors"] == m["errors"]
        assert t.extractfile(top + "/factors.png").read() == png.content


def test_05_previews(d):
    mid, h = S["m32"]["id"], tok(S["view"])
    r = d.get("/api/v1/materials/%s/preview.png?view=0" % mid, headers=h, status=200)
    assert r.headers["Content-Type"] == "image/png"
    assert png_size(r.content) == (SIZE, SIZE)
    renderer = r.headers["X-Glint-Renderer"]
    assert renderer == "cpu" or renderer.startswith("egl"), renderer
    w, hh, ch, px = png_pixels(r.content)
    assert max(px) > 100, "the preview is black"
    c = d.get("/api/v1/materials/%s/preview.png?view=0&renderer=cpu" % mid, headers=h,
              status=200)
    assert c.headers["X-Glint-Renderer"] == "cpu"
    w2, h2, ch2, px2 = png_pixels(c.content)
    if renderer.startswith("egl"):
        # EGL and the CPU reference agree on almost every pixel
        diff = sum(1 for i in range(0, len(px), ch) if abs(px[i] - px2[i // ch * ch2]) > 8)
        assert diff < 0.02 * w * hh, (diff, renderer)
    r = d.get("/api/v1/materials/%s/preview.exr?eye=0,3,1&light=2,2,2&size=48&fov=30" % mid,
              headers=h, status=200)
    assert r.headers["Content-Type"] == "image/x-exr"
    assert r.content[:4] == b"\x76\x2f\x31\x01"
    r = d.get("/api/v1/materials/%s/preview.png?view=2&light=3,0,0&size=40" % mid, headers=h,
              status=200)
    assert png_size(r.content) == (40, 40)
    # renderer=cpu is honoured at any size (the CPU renders in bands of rows),
    # never answered with a claim that EGL is missing
    r = d.get("/api/v1/materials/%s/preview.png?view=0&size=2048&renderer=cpu" % mid,
              headers=h, status=200)
    assert r.headers["X-Glint-Renderer"] == "cpu" and png_size(r.content) == (2048, 2048)
    for q, word in [("", "view"), ("?view=99", "view"), ("?view=-1", "view"),
                    ("?view=0&size=5000", "size"), ("?view=0&size=abc", "size"),
                    ("?eye=0,3,1", "view"), ("?eye=0,3&light=1,1,1", "eye"),
                    ("?eye=0,3,nan&light=1,1,1", "eye"), ("?eye=1,1,1&light=1,1,1&target=1,1,1", "coincide"),
                    ("?view=0&fov=0", "fov"), ("?view=0&renderer=gpu", "renderer"),
                    ("?view=0&intensity=-1", "intensity")]:
        r = d.get("/api/v1/materials/%s/preview.png%s" % (mid, q), headers=h, status=422)
        assert word in r.json()["detail"], (q, r.json()["detail"])


def test_06_eval(d):
    mid, h = S["m32"]["id"], paint_headers(S["view"])
    pairs = [{"n": [0, 0, 1], "wi": [0.6, 0, 0.8], "wo": [0, 0, 1]},
             {"n": [0, 0, 2], "wi": [0, 0, 5], "wo": [0, 0, 1]},   # lengths do not matter
             {"n": [0, 0, 1], "wi": [0, 0, -1], "wo": [0, 0, 1]}]  # light below: 0
    r = d.post("/api/v1/materials/%s/eval" % mid, headers=h, data=json.dumps({"pairs": pairs}),
               status=200, schema="EvalResponse.json").json()
    assert len(r["values"]) == 3
    assert all(v > 0 for v in r["values"][0]) and all(v > 0 for v in r["values"][1])
    assert r["values"][2] == [0, 0, 0]
    # the mirror configuration is brighter than an oblique one (a highlight was painted)
    assert r["values"][1][0] > r["values"][0][0]
    # huge and tiny lengths are directions like any other
    big = [{"n": [0, 0, 1e308], "wi": [1e308, 1e308, 1e308], "wo": [0, 0, 5e-324]}]
    r2 = d.post("/api/v1/materials/%s/eval" % mid, headers=h, data=json.dumps({"pairs": big}),
                status=200, schema="EvalResponse.json").json()
    assert all(v > 0 for v in r2["values"][0]), r2
    url = "/api/v1/materials/%s/eval" % mid
    bad = [
        ('{"pairs": [{"n": [0, 0, 0], "wi": [0, 0, 1], "wo": [0, 0, 1]}]}', 422, "pairs[0].n"),
        ('{"pairs": [{"n": [0, 0, 1], "wi": [0, 1], "wo": [0, 0, 1]}]}', 422, "pairs[0].wi"),
        ('{"pairs": [{"n": [0, 0, 1], "wi": [0, 0, 1], "wo": ["a", 0, 1]}]}', 422, "pairs[0].wo"),
        ('{"pairs": [{"n": [0, 0, 1], "wi": [0, 0, 1]}]}', 422, "pairs[0]"),
        ('{"pairs": [{"n": [0, 0, 1], "wi": [0, 0, 1], "wo": [0, 0, 1], "x": 1}]}', 422, "pairs[0]"),
        ('{"pairs": []}', 422, "pairs"),
        ('{"pairs": [], "extra": 1}', 422, "extra"),
        ('{"pairs": [{"n": [0, 0, 1e999], "wi": [0, 0, 1], "wo": [0, 0, 1]}]}', 400, ""),
        ('{"pairs": [{"n": [0, 0, NaN], "wi": [0, 0, 1], "wo": [0, 0, 1]}]}', 400, ""),
        ('{"pairs": [{"n": [0, 0, 1], "wi": [0, 0, 1], "wo": [0, 0, Infinity]}]}', 400, ""),
        ('{"pairs": [{"n": [0, 0, 5e-324], "wi": [0, 0, 1], "wo": [0, 0, -0.0]}]}', 422, "pairs[0].wo"),
        ('{"pairs": ', 400, ""),
    ]
    for body, status, word in bad:
        r = d.post(url, headers=h, data=body, status=status)
        assert word in r.json()["detail"], (body, r.json()["detail"])
    many = {"pairs": [{"n": [0, 0, 1], "wi": [0, 0, 1], "wo": [0, 0, 1]}] * 65537}
    r = d.post(url, headers=h, data=json.dumps(many), status=413)
    assert "65536" in r.json()["detail"]


# ---- validation and access --------------------------------------------------------------

def test_07_fit_parameters_are_validated(d):
    url = "/api/v1/sessions/%s/fits" % S["session"]
    h = paint_headers()
    cases = [
        ({"params": {"res": 3}}, "params.res"),
        ({"params": {"res": 513}}, "params.res"),
        ({"params": {"res": 64.5}}, "params.res"),
        ({"params": {"res": "64"}}, "params.res"),
        ({"params": {"lambda": -1}}, "params.lambda"),
        ({"params": {"lambda": "0.1"}}, "params.lambda"),
        ({"params": {"lambda": 1e9}}, "params.lambda"),
        ({"params": {"regularization": "foo"}}, "params.regularization"),
        ({"params": {"regularization": "trunc:150%"}}, "params.regularization"),
        ({"params": {"regularization": 3}}, "params.regularization"),
        ({"params": {"mapping": "bogus"}}, "params.mapping"),
        ({"params": {"model": "phong"}}, "params.model"),
        ({"params": {"precision": "half"}}, "params.precision"),
        ({"params": {"route": "qr"}}, "params.route"),
        ({"params": {"rcond": 0}}, "params.rcond"),
        ({"params": {"rcond": 1}}, "params.rcond"),
        ({"params": {"resolution": 64}}, "params.resolution"),
        ({"params": [64]}, "params"),
        ({"method": "hf9"}, "hf9"),
        ({"method": 3}, "method"),
        ({"params": {}, "views": [1]}, "views"),
    ]
    for body, word in cases:
        r = d.post(url, headers=h, data=json.dumps(body), status=422)
        assert word in r.json()["detail"], (body, r.json()["detail"])
    d.post(url, headers=h, data="{", status=400)
    d.post(url, headers=h, data="[1]", status=422)
    d.post(url, headers=h, data="", status=400)
    d.post(url, headers={"X-Glint-Token": S["paint"], "Content-Type": "text/plain"},
           data="{}", status=415)
    d.post(url, headers=h, data='{"params": {"res": 1e999}}', status=400)
    # a session with nothing painted
    s = make_session(d, [])
    r = d.post("/api/v1/sessions/%s/fits" % s["id"], headers=paint_headers(s["paint_token"]),
               data="{}", status=422)
    assert "painting" in r.json()["detail"]


def test_08_access(d):
    mid = S["m32"]["id"]
    url = "/api/v1/sessions/%s/fits" % S["session"]
    body = json.dumps({"params": {"res": 32}})
    d.post(url, headers={"Content-Type": "application/json"}, data=body, status=401)
    d.post(url, headers=paint_headers(S["view"]), data=body, status=403)
    d.post(url, headers=paint_headers("0" * 32), data=body, status=403)
    other = make_session(d, [0])
    d.post(url, headers=paint_headers(other["paint_token"]), data=body, status=403)
    for suffix in ("", "/factors.png", "/factors.exr", "/shader", "/shader/shader.json",
                   "/package", "/preview.png?view=0"):
        d.get("/api/v1/materials/%s%s" % (mid, suffix), status=401)
        d.get("/api/v1/materials/%s%s" % (mid, suffix), headers=tok(other["view_token"]),
              status=403)
    d.post("/api/v1/materials/%s/eval" % mid, data='{"pairs": []}',
           headers={"Content-Type": "application/json"}, status=401)
    # the token in the query works too (EventSource and <img> cannot set headers)
    d.get("/api/v1/materials/%s?token=%s" % (mid, S["view"]), status=200, schema="Material.json")
    d.get("/api/v1/materials/%s/factors.png?token=%s" % (mid, S["view"]), status=200)
    d.get("/api/v1/sessions/%s/materials" % S["session"], status=401)
    # unknown ids
    nobody = "0123456789abcdef0123456789abcdef"
    for path in ("/api/v1/materials/" + nobody, "/api/v1/materials/%s/factors.png" % nobody,
                 "/api/v1/materials/%s/preview.png?view=0" % nobody, "/api/v1/jobs/" + nobody,
                 "/api/v1/jobs/%s/events" % nobody, "/api/v1/materials/not-an-id",
                 "/api/v1/jobs/..%2f..", "/api/v1/sessions/%s/materials" % nobody):
        d.get(path, headers=tok(S["paint"]), status=404)
    d.post("/api/v1/sessions/%s/fits" % nobody, headers=paint_headers(), data="{}", status=404)
    d.post("/api/v1/materials/%s/eval" % nobody, headers=paint_headers(), data='{"pairs":[]}',
           status=404)
    # jobs belong to their session too
    kind, x = fit(d, {"res": 20})
    if kind == "job":
        d.get("/api/v1/jobs/%s" % x["id"], status=401)
        d.get("/api/v1/jobs/%s" % x["id"], headers=tok(other["paint_token"]), status=403)
        wait_job(d, x["id"], S["view"])


# ---- single flight ----------------------------------------------------------------------

def test_09_concurrent_cold_fits_build_once(d):
    """Four sessions painting the same six views ask for the same new
    precomputation at once: one build, the others wait for it."""
    sessions = [make_session(d, range(6)) for _ in range(4)]
    builds0 = metric(d, "glintd_fitcache_lookups_total",
                     {"level": "decomposition", "outcome": "built"})
    answers, errors = [None] * 4, []
    barrier = threading.Barrier(4)

    def go(i):
        try:
            barrier.wait()
            r = requests.post(d.base + "/api/v1/sessions/%s/fits" % sessions[i]["id"],
                              headers=paint_headers(sessions[i]["paint_token"]),
                              data=json.dumps({"params": {"res": 40}}), timeout=60)
            answers[i] = r
        except Exception as e:  # noqa: BLE001
            errors.append(e)

    threads = [threading.Thread(target=go, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    materials = []
    for s, r in zip(sessions, answers):
        assert r.status_code in (201, 202), r.text
        if r.status_code == 202:
            validate(r.json(), "JobResponse.json")
            j = wait_job(d, r.json()["job"]["id"], s["paint_token"])
            assert j["state"] == "done", j
            materials.append(get_material(d, j["material_id"], s["view_token"]))
        else:
            validate(r.json(), "Material.json")
            materials.append(r.json())
    keys = {m["precomputation"]["cache"]["key"] for m in materials}
    assert len(keys) == 1, keys
    for level in ("pattern", "decomposition", "operator"):
        how = sorted(m["precomputation"]["cache"]["levels"][level]["memory"] for m in materials)
        assert how.count("built") == 1, (level, how)
        assert set(how) <= {"built", "joined", "hit"}, (level, how)
    assert sum(r.status_code == 202 for r in answers) >= 1
    builds1 = metric(d, "glintd_fitcache_lookups_total",
                     {"level": "decomposition", "outcome": "built"})
    if builds0 is not None:  # /metrics exposes the cache
        assert builds1 - builds0 == 1, (builds0, builds1)
    for m, s in zip(materials, sessions):
        assert m["session_id"] == s["id"] and m["views_used"] == list(range(6))


# ---- methods, session listing, session events -------------------------------------------

def test_10_methods(d):
    m = d.get("/api/v1/methods", status=200, schema="Methods.json").json()
    hf3 = m["methods"][0]
    assert hf3["name"] == "hf3" and "scene" not in m
    res = [p for p in hf3["params"] if p["name"] == "res"][0]
    assert (res["default"], res["minimum"], res["maximum"]) == (128, 4, 512)
    names = {p["name"] for p in hf3["params"]}
    assert {"res", "lambda", "regularization", "mapping", "model", "precision",
            "route"} <= names
    # this daemon has no --measured-dir: the one method that learns from the
    # measured materials is listed as one it cannot fit, with the reason, and
    # a fit of it is refused before any work
    by = {x["name"]: x for x in m["methods"]}
    assert all(x["available"] for n, x in by.items() if n != "tab_prior"), \
        [n for n, x in by.items() if not x["available"]]
    tp = by["tab_prior"]
    assert tp["available"] is False and "--measured-dir" in tp["unavailable"], tp
    assert all("unavailable" not in x for n, x in by.items() if n != "tab_prior")
    r = d.post("/api/v1/sessions/%s/fits" % S["session"], headers=paint_headers(None),
               data=json.dumps({"method": "tab_prior"}))
    assert r.status_code == 422, (r.status_code, r.text[:400])
    prob = r.json()
    assert prob["type"].endswith("method-unavailable"), prob
    assert "tab_prior cannot fit on this host" in prob["detail"] and "--measured-dir" in prob["detail"], prob
    # the points measured on the scene, held-out error included (measured in
    # the background, below every request's priority and in the daemon's
    # pauses: wait for it; the deadline only guards a hang)
    deadline = time.time() + 300
    while True:
        m = d.get("/api/v1/methods?scene_id=" + S["scene"], status=200,
                  schema="Methods.json").json()
        pts = [p for p in m["scene"]["points"]
               if p["params"] == S["m32"]["params"] and p["views"] == list(range(12))]
        assert len(pts) == 1, m["scene"]["points"]
        p = pts[0]
        if p["held_out_rms"] is not None or time.time() > deadline:
            break
        time.sleep(0.2)
    assert p["fits"] >= 2 and p["fit_seconds"] > 0, p
    assert p["cold_seconds"] is not None and p["cold_seconds"] > 0, p
    assert abs(p["rms_painted"] - S["m32"]["errors"]["rms_painted"]) < 1e-9
    assert p["held_out_rms"] is not None, "no held-out error after 300 s"
    assert p["held_out"]["method"] == "leave-one-view-out" and p["held_out"]["views"] == 12
    assert p["held_out_rms"] >= p["rms_painted"] * 0.5
    assert "material_id" not in p
    m2 = d.get("/api/v1/methods?session_id=" + S["session"], headers=tok(S["view"]), status=200,
               schema="Methods.json").json()
    assert m2["scene"]["id"] == S["scene"]
    d.get("/api/v1/methods?session_id=" + S["session"], status=401)
    d.get("/api/v1/methods?scene_id=0123456789abcdef0123456789abcdef", status=404)
    d.get("/api/v1/methods?scene_id=%s&session_id=%s" % (S["scene"], S["session"]), status=422)


def test_11_session_materials_and_fit_events(d):
    lst = d.get("/api/v1/sessions/%s/materials" % S["session"], headers=tok(S["view"]),
                status=200, schema="MaterialList.json").json()["materials"]
    ids = [m["id"] for m in lst]
    assert S["m32"]["id"] in ids and len(ids) >= 5
    # listed with the links a material is answered with, the MERL table's too
    listed = lst[ids.index(S["m32"]["id"])]["links"]
    assert listed == S["m32"]["links"] and "merl" in listed and "session" in listed, listed
    events = sse_events(d, "/api/v1/sessions/%s/events?since=0" % S["session"], tok(S["view"]),
                        timeout=30, stop_types=("fit",))
    fits = [e for e in events if e[1] == "fit"]
    assert fits, [e[1] for e in events]
    data = fits[0][2]
    payload = data.get("data", data)
    assert payload["material_id"] == S["m32"]["id"], data
    assert payload["summary"]["res"] == 32


def test_12_job_stream_resumes_after_last_event_id(d):
    kind, job = fit(d, {"res": 24}, expect=202)
    events = sse_events(d, "/api/v1/jobs/%s/events" % job["id"], tok(S["view"]))
    last = events[-1]
    assert last[1] == "done"
    again = sse_events(d, "/api/v1/jobs/%s/events" % job["id"],
                       dict(tok(S["view"]), **{"Last-Event-ID": str(int(last[0]) - 1)}))
    assert [e[1] for e in again] == ["done"], again
    again = sse_events(d, "/api/v1/jobs/%s/events?since=%s" % (job["id"], last[0]),
                       tok(S["view"]), timeout=20, stop_types=("done", "failed", "progress"))
    assert again == [], again
    d.get("/api/v1/jobs/%s/events?since=x" % job["id"], headers=tok(S["view"]), status=400)


def test_12b_a_new_painting_is_fitted_not_a_cached_one(d):
    """Paintings are read when the fit is requested: a repainted view is in
    the next fit (decoded paintings are cached by version)."""
    s = make_session(d, range(S["nviews"]))
    kind, m1 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    assert m1["paintings"][0] == {"view": 0, "version": 1}
    with open(os.path.join(S["paint2_dir"], "view_00.exr"), "rb") as f:
        d.put("/api/v1/sessions/%s/views/0/painting" % s["id"],
              headers={"Content-Type": "image/x-exr", "X-Glint-Token": s["paint_token"]},
              data=f.read(), status=200, schema="PaintingVersion.json")
    kind, m2 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    assert m2["paintings"][0] == {"view": 0, "version": 2}, m2["paintings"][:2]
    assert m2["paintings"][1] == {"view": 1, "version": 1}
    assert abs(m2["errors"]["rms_painted"] - m1["errors"]["rms_painted"]) > 1e-6
    kind, m3 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    assert m3["errors"] == m2["errors"]


def test_12c_a_repainted_view_leaves_the_others_sums_to_the_memo(d):
    """A session's next fit sums again only the chunks of samples of the
    views repainted since its last fit; the others' sums come from its
    memo, and the material is the same bits as a fit of the same paintings
    in a session that has no memo."""
    memo0 = metric(d, "glintd_fit_stream_chunks_total", {"from": "memo"})
    s = make_session(d, range(S["nviews"]))
    kind, m1 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    chunks = m1["precomputation"]["stream_chunks"]
    assert chunks > 4 and m1["precomputation"]["stream_chunks_reused"] == 0, m1["precomputation"]
    nused = len(m1["views_used"])
    assert nused > 1 and m1["precomputation"]["values_views_read"] == nused
    kind, m1b = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    assert m1b["precomputation"]["stream_chunks_reused"] == chunks
    assert m1b["precomputation"]["values_views_read"] == 0
    assert m1b["errors"] == m1["errors"]
    with open(os.path.join(S["paint2_dir"], "view_05.exr"), "rb") as f:
        body = f.read()
    d.put("/api/v1/sessions/%s/views/5/painting" % s["id"],
          headers={"Content-Type": "image/x-exr", "X-Glint-Token": s["paint_token"]},
          data=body, status=200, schema="PaintingVersion.json")
    kind, m2 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    reused = m2["precomputation"]["stream_chunks_reused"]
    assert 0 < reused < chunks, m2["precomputation"]
    assert m2["precomputation"]["values_views_read"] == 1
    assert m2["errors"] != m1["errors"]
    # the same paintings, fitted from nothing
    s2 = make_session(d, range(S["nviews"]))
    d.put("/api/v1/sessions/%s/views/5/painting" % s2["id"],
          headers={"Content-Type": "image/x-exr", "X-Glint-Token": s2["paint_token"]},
          data=body, status=200, schema="PaintingVersion.json")
    kind, m3 = fit(d, {"res": 32}, token=s2["paint_token"], session=s2["id"], expect=201)
    assert m3["precomputation"]["stream_chunks_reused"] == 0
    assert m3["precomputation"]["values_views_read"] == nused
    assert m3["errors"] == m2["errors"], (m3["errors"], m2["errors"])
    f2 = d.get("/api/v1/materials/%s/factors.exr" % m2["id"], headers=tok(s["view_token"]),
               status=200)
    f3 = d.get("/api/v1/materials/%s/factors.exr" % m3["id"], headers=tok(s2["view_token"]),
               status=200)
    # the same file but for the time it was written (the header's DateTime)
    stamp = re.compile(rb"\d{4}:\d\d:\d\d \d\d:\d\d:\d\d")
    assert stamp.sub(b"", f2.content) == stamp.sub(b"", f3.content)
    # another point of the same session keeps its own memo
    kind, m4 = fit(d, {"res": 16}, token=s["paint_token"], session=s["id"])
    if kind == "job":
        m4 = get_material(d, wait_job(d, m4["id"], s["paint_token"])["material_id"],
                          s["paint_token"])
    assert m4["precomputation"]["stream_chunks_reused"] == 0
    kind, m5 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    assert m5["precomputation"]["stream_chunks_reused"] == chunks
    assert m5["precomputation"]["values_views_read"] == 0
    assert m5["errors"] == m2["errors"]
    held = [float(line.split()[-1]) for line in d.get("/metrics", status=200).text.splitlines()
            if line.startswith("glintd_fit_memo_values_bytes ")]
    assert held and held[0] >= 12 * m5["precomputation"]["samples"], held
    assert metric(d, "glintd_fit_stream_chunks_total", {"from": "memo"}) >= \
        (memo0 or 0) + chunks + reused + chunks


def test_12d_a_stroke_leaves_the_sums_of_the_samples_it_did_not_change(d):
    """After a brush stroke a session's next fit compares the view's values
    with those it kept and sums again only the chunks of samples whose
    values changed: the same figures as a fit of the stroked painting from
    nothing.  The same stroke again changes no value: nothing is summed
    again."""
    s = make_session(d, range(S["nviews"]))
    kind, m1 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    chunks = m1["precomputation"]["stream_chunks"]
    assert chunks > 4, m1["precomputation"]
    stroke = {"strokes": [{"color": [0.9, 0.2, 0.1], "diameter": 3,
                           "points": [[SIZE // 2, SIZE // 2]]}]}
    url = "/api/v1/sessions/%s/views/0/strokes" % s["id"]
    d.post(url, json=stroke, headers=tok(s["paint_token"]), status=200)
    kind, m2 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    pre = m2["precomputation"]
    assert pre["values_views_read"] == 1, pre
    assert 1 <= chunks - pre["stream_chunks_reused"] <= 2, pre
    assert m2["errors"] != m1["errors"]
    # the stroked painting, fitted from nothing
    body = d.get("/api/v1/sessions/%s/views/0/painting?format=exr" % s["id"],
                 headers=tok(s["view_token"]), status=200).content
    s2 = make_session(d, range(1, S["nviews"]))
    d.put("/api/v1/sessions/%s/views/0/painting" % s2["id"],
          headers={"Content-Type": "image/x-exr", "X-Glint-Token": s2["paint_token"]},
          data=body, status=200, schema="PaintingVersion.json")
    kind, m3 = fit(d, {"res": 32}, token=s2["paint_token"], session=s2["id"], expect=201)
    assert m3["precomputation"]["stream_chunks_reused"] == 0
    assert m3["errors"] == m2["errors"], (m3["errors"], m2["errors"])
    # the same stroke again: a new version of the view, the same values
    d.post(url, json=stroke, headers=tok(s["paint_token"]), status=200)
    kind, m4 = fit(d, {"res": 32}, token=s["paint_token"], session=s["id"], expect=201)
    assert m4["paintings"][0]["version"] == m2["paintings"][0]["version"] + 1
    assert m4["precomputation"]["values_views_read"] == 1
    assert m4["precomputation"]["stream_chunks_reused"] == chunks, m4["precomputation"]
    assert m4["errors"] == m2["errors"]


# ---- the disk layer: restart and corruption ---------------------------------------------

def test_13_restart_reuses_the_disk_cache_and_rebuilds_corrupt_files(d):
    d.stop()
    d.start()
    m = get_material(d, S["m32"]["id"])  # materials survive
    assert m["id"] == S["m32"]["id"]
    kind, job = fit(d, {"res": 32}, expect=202)  # memory is empty after a restart
    j = wait_job(d, job["id"], S["paint"])
    m = get_material(d, j["material_id"])
    cache = m["precomputation"]["cache"]
    assert cache["memory"] == "built" and cache["disk"] == "loaded", cache
    assert cache["levels"]["pattern"]["disk"] == "loaded", cache  # not rasterized again
    assert cache["levels"]["decomposition"]["disk"] == "loaded", cache
    assert m["precomputation"]["cache_hit"] == 1
    assert m["precomputation"]["cache_key"] == S["m32"]["precomputation"]["cache_key"]
    assert abs(m["errors"]["rms_painted"] - S["m32"]["errors"]["rms_painted"]) < 1e-9
    # corrupt the decomposition's file: it is rebuilt, never trusted
    path = os.path.join(d.data_dir, "cache", m["precomputation"]["cache_key"] + ".hfd")
    assert os.path.exists(path), path
    with open(path, "r+b") as f:
        f.seek(200)
        f.write(b"\xff" * 16)
    # and the sampling patterns' files: cut short
    patterns = [os.path.join(d.data_dir, "cache", n)
                for n in os.listdir(os.path.join(d.data_dir, "cache")) if n.endswith(".pattern")]
    assert patterns
    for p in patterns:
        os.truncate(p, os.path.getsize(p) // 2)
    d.stop()
    d.start()
    kind, job = fit(d, {"res": 32}, expect=202)
    j = wait_job(d, job["id"], S["paint"])
    m = get_material(d, j["material_id"])
    cache = m["precomputation"]["cache"]
    assert cache["disk"] == "rebuilt", cache
    assert cache["levels"]["pattern"]["disk"] == "rebuilt", cache
    assert abs(m["errors"]["rms_painted"] - S["m32"]["errors"]["rms_painted"]) < 1e-9
    # the points were kept across the restarts
    pts = d.get("/api/v1/methods?scene_id=" + S["scene"], status=200,
                schema="Methods.json").json()["scene"]["points"]
    p = [p for p in pts if p["params"] == S["m32"]["params"] and p["views"] == list(range(12))]
    assert p and p[0]["disk_seconds"] is not None, p


def pixels_idle(d, timeout=30.0):
    """Wait until glintd has no painting's pixels queued or being written."""
    t0 = time.time()
    while time.time() - t0 < timeout:
        if (metric(d, "glintd_painting_pixels_queue", {"state": "queued"}) == 0 and
                metric(d, "glintd_painting_pixels_queue", {"state": "writing"}) == 0):
            return
        time.sleep(0.02)
    raise AssertionError("the pixel writer did not go idle in %g s" % timeout)


def reads(d):
    return {k: metric(d, "glintd_painting_reads_total", {"from": k})
            for k in ("pixels", "decoded")}


def test_14_a_restart_reads_paintings_as_pixels_kept_beside_them(d):
    """Each painting's decoded pixels are written beside its upload; after a
    restart a fit reads them instead of decoding the OpenEXR again, and a
    damaged or missing pixels file is decoded from the upload and kept
    again: the material is the same either way."""
    pixels_idle(d)
    sdir = os.path.join(d.data_dir, "blobs", "sessions", S["session"])
    deadline = time.time() + 10  # replaced versions' files go soon after their requests
    while True:
        names = sorted(os.listdir(sdir))
        pixels = [n for n in names if n.endswith(".px")]
        if len(pixels) == S["nviews"] or time.time() > deadline:
            break
        time.sleep(0.01)
    assert len(pixels) == S["nviews"] and all(p[:-3] in names for p in pixels), names
    d.stop()
    d.start()
    m = fit_material(d, {"res": 32})
    assert reads(d) == {"pixels": S["nviews"], "decoded": 0}, reads(d)
    assert abs(m["errors"]["rms_painted"] - S["m32"]["errors"]["rms_painted"]) < 1e-9
    # one damaged (a flipped byte), one gone
    with open(os.path.join(sdir, pixels[0]), "r+b") as f:
        f.seek(1000)
        b = f.read(1)
        f.seek(1000)
        f.write(bytes([b[0] ^ 0x20]))
    os.unlink(os.path.join(sdir, pixels[1]))
    d.stop()
    d.start()
    m = fit_material(d, {"res": 32})
    assert reads(d) == {"pixels": S["nviews"] - 2, "decoded": 2}, reads(d)
    assert abs(m["errors"]["rms_painted"] - S["m32"]["errors"]["rms_painted"]) < 1e-9
    pixels_idle(d)  # both kept again
    assert sorted(n for n in os.listdir(sdir) if n.endswith(".px")) == pixels
    d.stop()
    d.start()
    fit_material(d, {"res": 32})
    assert reads(d) == {"pixels": S["nviews"], "decoded": 0}, reads(d)


if __name__ == "__main__":
    run_tests(globals())
