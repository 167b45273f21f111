"""The formats artists take a material into, through the real daemon: the
MaterialX (.mtlx) and USD (.usda) files of a fitted material checked against
their specifications' node definitions (export_specs.py) and against the
.glb's own metallic-roughness numbers; every download (glb, mtlx, usda,
MERL, .brdf, package) an attachment with a file name; the list of exports
(GET /materials/{id}/exports) with how close each comes, the same figure
the files and their headers state; access and errors."""
import json
import math
import os
import re
import struct
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from harness import fit_material, run_tests  # noqa: E402
import export_specs  # noqa: E402

SIZE = 48
S = {}
CT = "ct:kd=0.4/0.3/0.2,f0=0.2,rough=0.3"
CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(os.environ.get("GLINTD", "build/server/glintd")))),
    "core", "glint")
# red plastic with gold stripes (test_exports.py's): a material of maps varies over the surface
STRIPES = ("stripes:freq=3,duty=0.5|ct:kd=0.6/0.1/0.08,f0=0.04,rough=0.3|"
           "ct:kd=0,f0=0.9/0.7/0.3,rough=0.25")
EXTS = {"glb": "glb", "mtlx": "mtlx", "mtlx_zip": "mtlx.zip", "usda": "usda", "usdz": "usdz",
        "merl": "binary", "brdf": "brdf", "package": "tar"}


def tok(t):
    return {"X-Glint-Token": t}


def setup(d):
    if S:
        return
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201).json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    for k in range(len(sc["views"])):
        img = d.get("/api/v1/scenes/%s/views/%d/base.png?format=exr&scale=1&brdf=%s"
                    % (sc["id"], k, CT), status=200).content
        d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
              headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}), data=img,
              status=200)
    mid = fit_material(d, s, {"method": "hf3", "params": {"res": 32}})
    S.update(session=s, material=mid, scene=sc)


def get(d, what, **kw):
    return d.get("/api/v1/materials/%s/%s" % (S["material"], what),
                 headers=tok(S["session"]["view_token"]), **kw)


def header_fields(h):
    return dict(kv.split("=", 1) for kv in h.split("; "))


def glb_material(content):
    jl = struct.unpack("<I", content[12:16])[0]
    doc = json.loads(content[20:20 + jl])
    return doc, doc["materials"][0]["pbrMetallicRoughness"]


def saved(content, name):
    path = os.path.join(tempfile.mkdtemp(prefix="glint-fmt-"), name)
    with open(path, "wb") as f:
        f.write(content)
    return path


def test_01_the_list_says_how_close_each_comes(d):
    setup(d)
    lst = get(d, "exports", status=200, schema="ExportList.json").json()
    print("exports:", json.dumps(lst)[:1500])
    assert [e["format"] for e in lst["exports"]] == list(EXTS), lst
    fit = lst["fit"]
    # the figure is the fit's, the same for the three files that carry it
    for e in lst["exports"]:
        assert e["available"], e
        assert re.fullmatch(r"sphere-%s\.%s" % (S["material"][:8], EXTS[e["format"]]), e["file_name"]), e
        assert e["url"].startswith("/api/v1/materials/%s/" % S["material"]), e
        if e["format"] in ("glb", "mtlx", "mtlx_zip", "usda", "usdz"):
            assert e["how_close"]["rel_rms"] == fit["rel_rms"] and not e["how_close"]["exact"], e
        else:
            assert e["how_close"]["exact"] and e["how_close"]["rel_rms"] is None, e
    assert [e["expensive"] for e in lst["exports"]] == [False, False, False, False, False, True,
                                                        False, False]
    # ct rough 0.3 is glTF roughness sqrt(0.3); the fit is close on the painted views
    assert abs(fit["roughness"] - math.sqrt(0.3)) < 0.1 and 0 < fit["rel_rms"] < 0.1, fit
    S["fit"] = fit
    r = get(d, "material.glb", status=200)
    g = header_fields(r.headers["X-Glint-Gltf"])
    assert abs(float(g["fit_rel_rms"]) - fit["rel_rms"]) < 1e-4, (g, fit)
    S["glb"] = r.content


def test_02_mtlx_as_the_standard_surface_nodedef_has_it(d):
    setup(d)
    r = get(d, "material.mtlx", status=200)
    assert r.headers["Content-Type"].startswith("application/xml")
    path = saved(r.content, "m.mtlx")
    vals = export_specs.check_mtlx(r.text, path)
    _, pbr = glb_material(S["glb"])
    for a, b in zip(vals["base_color"], pbr["baseColorFactor"][:3]):
        assert abs(a - b) < 1e-4, (vals, pbr)
    assert abs(vals["metalness"] - pbr["metallicFactor"]) < 1e-4
    assert abs(vals["specular_roughness"] - pbr["roughnessFactor"]) < 1e-4
    assert vals["specular_IOR"] == 1.5
    f = header_fields(r.headers["X-Glint-Fit"])
    assert abs(float(f["fit_rel_rms"]) - S["fit"]["rel_rms"]) < 1e-4, f
    m = re.search(r"fit_rel_rms ([0-9.]+)", r.text)
    assert m and abs(float(m.group(1)) - S["fit"]["rel_rms"]) < 1e-4, r.text[:600]
    # a broken document fails the check: the check can fail
    bad = r.text.replace('name="metalness" type="float"', 'name="metalness" type="color3"')
    try:
        export_specs.check_mtlx(bad)
        raise AssertionError("a metalness of type color3 passed")
    except export_specs.Bad:
        pass


def test_03_usda_as_the_preview_surface_spec_has_it(d):
    setup(d)
    r = get(d, "material.usda", status=200)
    path = saved(r.content, "m.usda")
    vals, meshes = export_specs.check_usda(r.text, path)
    assert meshes == 1
    doc, pbr = glb_material(S["glb"])
    for a, b in zip(vals["diffuseColor"], pbr["baseColorFactor"][:3]):
        assert abs(a - b) < 1e-4, (vals, pbr)
    assert abs(vals["metallic"] - pbr["metallicFactor"]) < 1e-4
    assert abs(vals["roughness"] - pbr["roughnessFactor"]) < 1e-4
    # the mesh the .glb holds: as many points and triangles
    counts = re.search(r"int\[\] faceVertexCounts = \[([^]]*)\]", r.text).group(1).count("3")
    assert counts == doc["accessors"][3]["count"] // 3, counts
    f = header_fields(r.headers["X-Glint-Fit"])
    assert abs(float(f["fit_rel_rms"]) - S["fit"]["rel_rms"]) < 1e-4, f
    assert re.search(r"fit_rel_rms %.4f" % S["fit"]["rel_rms"], r.text)
    alone = get(d, "material.usda?mesh=0", status=200).text
    assert export_specs.check_usda(alone)[1] == 0 and len(alone) < 4000
    bad = r.text.replace("float inputs:roughness", "double inputs:roughness")
    try:
        export_specs.check_usda(bad)
        raise AssertionError("a roughness of type double passed")
    except export_specs.Bad:
        pass


def test_04_every_download_is_an_attachment_with_a_name(d):
    setup(d)
    paths = {"glb": "material.glb", "mtlx": "material.mtlx", "mtlx_zip": "material.mtlx.zip",
             "usda": "material.usda",
             "usdz": "material.usdz", "merl": "merl.binary", "brdf": "material.brdf",
             "package": "package"}
    for fmt, p in paths.items():
        r = get(d, p, status=200)
        want = 'attachment; filename="sphere-%s.%s"' % (S["material"][:8], EXTS[fmt])
        assert r.headers.get("Content-Disposition") == want, (fmt, r.headers.get("Content-Disposition"))


def test_05_access_and_errors(d):
    setup(d)
    mid = S["material"]
    for p in ("material.mtlx", "material.mtlx.zip", "material.usda", "material.usdz", "exports"):
        d.get("/api/v1/materials/%s/%s" % (mid, p), status=401)
        d.get("/api/v1/materials/%s/%s" % (mid, p), headers=tok("x" * 40), status=403)
        d.get("/api/v1/materials/%s/%s" % ("0" * 32, p), headers=tok(S["session"]["view_token"]),
              status=404)
    get(d, "material.usda?mesh=2", status=400)


def test_06_a_material_that_varies_exports_its_average_and_says_so(d):
    tmp = tempfile.mkdtemp(prefix="glint-fmt-sv-")
    scene = os.path.join(tmp, "scene.json")
    subprocess.run([CLI, "scene", "create", "--size", str(SIZE), "-o", scene], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([CLI, "paint", scene, "--brdf", STRIPES, "-o", os.path.join(tmp, "paint")],
                   check=True, stdout=subprocess.DEVNULL)
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201).json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    for k in range(len(sc["views"])):
        with open(os.path.join(tmp, "paint", "view_%02d.exr" % k), "rb") as f:
            d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                  headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}),
                  data=f.read(), status=200)
    mid = fit_material(d, s, {"method": "maps", "params": {"res": 32, "map_res": 16, "components": 3}})
    h = tok(s["view_token"])
    lst = d.get("/api/v1/materials/%s/exports" % mid, headers=h, status=200,
                schema="ExportList.json").json()
    print("maps:", json.dumps(lst["fit"]), [(e["format"], e["how_close"]["rel_rms"], e["expensive"])
                                            for e in lst["exports"]])
    assert lst["fit"]["spatial"], lst["fit"]
    for fmt in ("glb", "mtlx_zip", "usdz"):
        x = [e for e in lst["exports"] if e["format"] == fmt][0]
        assert x["expensive"] and "textures come closer" in x["how_close"]["note"], x
    # the average of gold and red plastic is further from either than a plain plastic's fit
    assert lst["fit"]["rel_rms"] > 0.05, lst["fit"]
    mtlx = d.get("/api/v1/materials/%s/material.mtlx" % mid, headers=h, status=200).text
    assert "this is its average" in mtlx and "spatial=1" in \
        d.get("/api/v1/materials/%s/material.mtlx" % mid, headers=h, status=200).headers["X-Glint-Fit"]
    export_specs.check_mtlx(mtlx)
    usda = d.get("/api/v1/materials/%s/material.usda?mesh=0" % mid, headers=h, status=200).text
    assert "this is its average" in usda
    export_specs.check_usda(usda)


if __name__ == "__main__":
    run_tests(globals())
