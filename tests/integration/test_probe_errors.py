"""Errors answered at once, never late and never as 500s, through the real
daemon:

- a fit request's parameters and references are checked before anything
  is queued, for sessions and G-buffer sets alike: an environment that does
  not resolve (file:PATH, an unknown data:FILE or upload:ID), env_intensity
  outside its range, visibility on where the samples have no mesh (a
  G-buffer set), a painted view without its G-buffer: 422 at once, naming
  the parameter, and no job is started;
- GET /methods offers only the environments the daemon resolves;
- an srbf material fitted with constraints none (negative lobes and
  diffuse allowed) answers every endpoint: its summary, previews, shader,
  package, glb, MERL table and evaluation;
- an upload's label of invalid UTF-8 is refused with 422, not 503;
- a scene whose base render at its paint size exceeds the work budget is
  refused at creation (413), not made to answer 413 for every view."""
import math
import os
import re
import struct
import sys
import time
import zlib

sys.path.insert(0, os.path.dirname(__file__))
import exr_named  # noqa: E402
from harness import Daemon, run_tests  # noqa: E402

API = "/api/v1"
KEY = "errors-test-key-0123456789"
SIZE = 32
S = {}


def key(extra=None):
    h = {"X-Api-Key": KEY}
    h.update(extra or {})
    return h


def png_encode(w, h, pixel):
    raw = b"".join(b"\x00" + bytes(v for x in range(w) for v in pixel(x, y)) for y in range(h))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(
            ">I", zlib.crc32(kind + body) & 0xffffffff)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def problem(r, status, kind=None):
    assert r.status_code == status, (status, r.status_code, r.text[:600])
    p = r.json()
    if kind:
        assert p["type"].endswith("/" + kind), (kind, p)
    return p


def jobs_started(d):
    m = d.get("/metrics", status=200).text
    return sum(int(v) for v in re.findall(r'^glintd_jobs(?:_finished_total)?\{state="\w+"\} (\d+)',
                                          m, re.M))


def wait_job(d, jid, headers):
    deadline = time.time() + 300
    while time.time() < deadline:
        j = d.get(API + "/jobs/" + jid, headers=headers, status=200).json()["job"]
        if j["state"] in ("done", "failed"):
            return j
        time.sleep(0.1)
    raise AssertionError("job %s did not finish" % jid)


def fitted(d, r, headers):
    assert r.status_code in (201, 202), r.text
    if r.status_code == 201:
        return r.json()["id"]
    j = wait_job(d, r.json()["job"]["id"], headers)
    assert j["state"] == "done", j
    return j["material_id"]


def test_00_setup(d):
    sc = d.post(API + "/scenes", json={"width": SIZE, "height": SIZE}, headers=key(),
                status=201).json()
    s = d.post(API + "/sessions", json={"scene_id": sc["id"]}, headers=key(), status=201).json()
    h = {"X-Glint-Token": s["paint_token"]}
    for k in (0, 5):
        d.put("%s/sessions/%s/views/%d/painting" % (API, s["id"], k),
              headers=dict(h, **{"Content-Type": "image/png"}), status=200,
              data=png_encode(SIZE, SIZE, lambda x, y: (120 + x, 90 + y, 60)))
    S.update(scene=sc["id"], session=s["id"], h=h)
    # a G-buffer set: view 0 complete, view 1 painted without its G-buffer
    st = d.post(API + "/gbuffer-sets", headers=key(),
                json={"views": 2, "width": SIZE, "height": SIZE}, status=201).json()
    gb = d.get("%s/scenes/%s/views/0/gbuffer.exr" % (API, sc["id"]), status=200,
               headers=key()).content
    exr = {"Content-Type": "image/x-exr"}
    d.put("%s/gbuffer-sets/%s/views/0/gbuffer.exr" % (API, st["id"]), headers=key(exr),
          data=gb, status=200)
    for k in (0, 1):
        d.put("%s/gbuffer-sets/%s/views/%d/painting" % (API, st["id"], k), headers=key(),
              data=png_encode(SIZE, SIZE, lambda x, y: (120, 90, 60)), status=200)
    S["set"] = st["id"]


SMALL = {"lights": 16, "basis_res": 3}


def test_01_environments_are_checked_before_queuing(d):
    """An environment that does not resolve is refused at once (422, naming
    params.env), not accepted and failed by the job."""
    url = "%s/sessions/%s/fits" % (API, S["session"])
    before = jobs_started(d)
    for env in ("file:/etc/passwd", "data:nonexistent.exr", "upload:" + "0" * 32,
                "upload:nosuch", "nosuch"):
        body = {"method": "srbf", "params": dict(SMALL, env=env)}
        p = problem(d.post(url, headers=S["h"], json=body), 422, "invalid-parameter")
        assert "params.env" in p["detail"] and env in p["detail"], p
        p = problem(d.post("%s/gbuffer-sets/%s/fits" % (API, S["set"]), headers=key(),
                           json=body), 422, "invalid-parameter")
        assert "params.env" in p["detail"], p
    assert jobs_started(d) == before


def test_02_env_intensity_is_checked_before_queuing(d):
    url = "%s/sessions/%s/fits" % (API, S["session"])
    for v in (1e-300, 1e-30, 0, -1, 1e7):
        body = {"method": "srbf", "params": dict(SMALL, env="sky", env_intensity=v)}
        p = problem(d.post(url, headers=S["h"], json=body), 422, "invalid-parameter")
        assert "params.env_intensity" in p["detail"], p


def test_03_gbuffer_set_fits_are_checked_before_queuing(d):
    """A G-buffer set's fit: a painted view without its G-buffer, and srbf's
    visibility on (G-buffers carry no mesh to cast shadows with), are 422
    at once."""
    url = "%s/gbuffer-sets/%s/fits" % (API, S["set"])
    before = jobs_started(d)
    p = problem(d.post(url, headers=key(), json={"method": "srbf",
                                                 "params": dict(SMALL, env="sky")}),
                422, "missing-gbuffer")
    assert "view 1" in p["detail"], p
    p = problem(d.post(url, headers=key(), json={"method": "hf3", "params": {"res": 8}}),
                422, "missing-gbuffer")
    # the view painted alone: visibility on needs a mesh the set does not have
    st = d.post(API + "/gbuffer-sets", headers=key(),
                json={"views": 2, "width": SIZE, "height": SIZE}, status=201).json()
    gb = d.get("%s/scenes/%s/views/0/gbuffer.exr" % (API, S["scene"]), status=200,
               headers=key()).content
    d.put("%s/gbuffer-sets/%s/views/0/gbuffer.exr" % (API, st["id"]),
          headers=key({"Content-Type": "image/x-exr"}), data=gb, status=200)
    d.put("%s/gbuffer-sets/%s/views/0/painting" % (API, st["id"]), headers=key(),
          data=png_encode(SIZE, SIZE, lambda x, y: (120, 90, 60)), status=200)
    p = problem(d.post("%s/gbuffer-sets/%s/fits" % (API, st["id"]), headers=key(),
                       json={"method": "srbf",
                             "params": dict(SMALL, env="sky", visibility="on")}),
                422, "invalid-parameter")
    assert "params.visibility" in p["detail"], p
    assert jobs_started(d) == before
    S["set1"] = st["id"]


def test_04_methods_offer_what_the_daemon_resolves(d):
    ms = d.get(API + "/methods", status=200).json()["methods"]
    env = [p for m in ms if m["name"] == "srbf" for p in m["params"] if p["name"] == "env"][0]
    assert "file:" not in env["syntax"] and not any(
        x.startswith("file:") for x in env.get("examples", [])), env
    assert "data:" in env["syntax"] and "upload:" in env["syntax"], env


def test_05_unconstrained_materials_answer_every_endpoint(d):
    """constraints none lets lobes and the diffuse albedo go negative: the
    material's summary and exports still answer (never 500)."""
    h = S["h"]
    # dark where the sphere faces the camera, bright towards its rim: the
    # unconstrained fit answers with a negative diffuse albedo
    rim = png_encode(SIZE, SIZE, lambda x, y: (min(255, int(255 * (math.hypot(
        x - 15.5, y - 15.5) / 12) ** 4)),) * 3)
    for k in (0, 5):
        d.put("%s/sessions/%s/views/%d/painting" % (API, S["session"], k), data=rim,
              headers=dict(h, **{"Content-Type": "image/png"}), status=200)
    body = {"method": "srbf", "params": {"env": "sky", "lights": 16, "basis_res": 5,
                                         "smooth": 0, "constraints": "none"}}
    mid = fitted(d, d.post("%s/sessions/%s/fits" % (API, S["session"]), headers=h,
                           json=body), h)
    m = d.get(API + "/materials/" + mid, headers=h, status=200, schema="Material.json").json()
    assert min(m["diffuse"]) < 0, m["diffuse"]  # a negative diffuse albedo
    for path in ("/preview.png?view=0", "/preview.png?view=0&renderer=cpu",
                 "/preview.exr?view=0", "/shader", "/package", "/material.glb",
                 "/merl.binary", "/material.brdf"):
        # (a MERL table of 75 lobes at 8 azimuths takes seconds: the timeout
        # only catches a hang)
        r = d.get(API + "/materials/" + mid + path, headers=h, timeout=600)
        assert r.status_code in (200, 422), (path, r.status_code, r.text[:400])
        if r.status_code == 422:
            assert r.json()["detail"], (path, r.text)
        if path == "/merl.binary":  # clamped to 0 where negative, and said so
            neg = re.search(r"negative=(\d+)", r.headers["X-Glint-Merl"])
            assert neg and int(neg.group(1)) > 0, r.headers["X-Glint-Merl"]
    r = d.post(API + "/materials/%s/eval" % mid, headers=h, status=200,
               json={"pairs": [{"n": [0, 0, 1], "wi": [0, 0.6, 0.8], "wo": [0, -0.6, 0.8]}]})
    assert len(r.json()["values"]) == 1
    lst = d.get("%s/sessions/%s/materials" % (API, S["session"]), headers=h, status=200).json()
    assert mid in [x["id"] for x in lst["materials"]]
    assert m["weights_negative"] > 0, m  # the summary says what is unphysical
    S["unconstrained"] = m


def test_06_labels_of_invalid_utf8_are_refused(d):
    hdr = (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 8 +X 16\n" + bytes([128, 128, 128, 129])
           * (16 * 8))
    oct_ = {"Content-Type": "application/octet-stream"}
    for q in ("name=%ff%fe", "name=a%c3", "name=%ed%a0%80"):
        p = problem(d.post(API + "/environments?" + q, headers=key(oct_), data=hdr), 422,
                    "invalid-parameter")
        assert "UTF-8" in p["detail"], p
    r = d.post(API + "/environments?name=caf%c3%a9", headers=key(oct_), data=hdr, status=201)
    assert r.json()["name"] == "caf\u00e9"


def test_07_scenes_beyond_the_work_budget_are_refused_at_creation(d):
    """A base render at the paint size that can never be admitted: 413 when
    the scene is made, naming the budget; within it, made."""
    w = Daemon("--work-mb", "64", "--quiet")
    try:
        r = w.post(API + "/scenes", json={"width": 256, "height": 256, "paint_scale": 4})
        p = problem(r, 413, "over-budget")
        assert "paint_scale 4" in p["detail"] and "--work-mb" in p["detail"], p
        assert "64 MiB" in p["detail"], p
        sc = w.post(API + "/scenes", json={"width": 256, "height": 256, "paint_scale": 2},
                    status=201).json()
        w.get("%s/scenes/%s/views/0/base.png" % (API, sc["id"]), status=200)
    finally:
        w.stop()


if __name__ == "__main__":
    run_tests(globals(), daemon_args=("--api-key", KEY))
