"""Materials taken elsewhere, through the real daemon: the MERL table
(GET /materials/{id}/merl.binary) read by an independent reader written
here after BRDFRead.cpp (the MERL database's own reader, numpy), against the
material's own evaluation (POST /materials/{id}/eval): exactly at bin
centres, and within the layout's nearest-bin limit at random direction
pairs; an anisotropic material reported and averaged; access and errors;
measured materials offered by --measured-dir painting as the truth their
table holds (point lights and a sky), the resolver refusing what is not
theirs (hidden, short, a link out, traversal), and a fit of such paintings
reading the truth's colour; the published fits of the directory's
merl56_fits.json offered as sgd:<name> and abc:<name> (here one material whose
fits are Lambertian, painting as the analytic Lambert does); the glTF file of a material that varies over
the surface (maps of gold stripes on red plastic) with its two PNG textures,
parsed here (the GLB's chunks, the PNGs decoded with zlib), and the USDZ and
MaterialX packages holding the same textures (export_specs.py)."""
import json
import math
import os
import random
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import zipfile
import zlib

sys.path.insert(0, os.path.dirname(__file__))
from harness import fit_material, png_unfilter, run_tests  # noqa: E402
import export_specs  # noqa: E402

try:
    import numpy as np
except ImportError:  # the table checks need Debian's python3-numpy
    np = None

SIZE = 48
S = {}
SPECS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "export_specs.py")
CT = "ct:kd=0.4/0.3/0.2,f0=0.2,rough=0.3"

# measured materials offered by the daemon: a table of CT made by the CLI,
# and files the resolver must refuse
CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(os.environ.get("GLINTD", "build/server/glintd")))),
    "core", "glint")
MDIR = tempfile.mkdtemp(prefix="glint-measured-")
subprocess.run([CLI, "export-merl", "--brdf", CT, "-o", os.path.join(MDIR, "ct.binary")],
               check=True, stdout=subprocess.DEVNULL)
shutil.copy(os.path.join(MDIR, "ct.binary"), os.path.join(MDIR, ".hidden.binary"))
with open(os.path.join(MDIR, "short.binary"), "wb") as f:
    f.write(b"\x5a\0\0\0" * 100)
# a fits file of one material whose two fits have no highlight: abc's kD/pi
# and sgd's rhoD/pi are Lambert's kd/pi
LAMBERT_FIT = {"name": "matte-test",
               "abc": {"kD": [0.4, 0.3, 0.2], "A": [0, 0, 0], "B": 100, "C": 1, "ior": 1.5},
               "sgd": dict({k: [0.1, 0.1, 0.1] for k in ("alpha", "p", "f0", "kap", "lambda")},
                           rhoD=[0.4, 0.3, 0.2], rhoS=[0, 0, 0], f1=[0, 0, 0], c=[1e-7] * 3,
                           k=[30, 30, 30], theta0=[0.1] * 3)}
with open(os.path.join(MDIR, "merl56_fits.json"), "w") as f:
    json.dump({"materials": [LAMBERT_FIT]}, f)
OUTSIDE = tempfile.mkdtemp(prefix="glint-outside-")
shutil.copy(os.path.join(MDIR, "ct.binary"), os.path.join(OUTSIDE, "far.binary"))
os.symlink(os.path.join(OUTSIDE, "far.binary"), os.path.join(MDIR, "evil.binary"))
SCALE = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)
N = 90 * 90 * 180


def tok(t):
    return {"X-Glint-Token": t}


def fitted(d, spec, body):
    """A session on a sphere painted with `spec` (the base render at scale 1:
    f cos per unit light) on every view, and the material `body` fits."""
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201).json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    for k in range(len(sc["views"])):
        img = d.get("/api/v1/scenes/%s/views/%d/base.png?format=exr&scale=1&brdf=%s"
                    % (sc["id"], k, spec), status=200).content
        d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
              headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}), data=img,
              status=200)
    return s, fit_material(d, s, body)


# ---- an independent reader, after BRDFRead.cpp ---------------------------------------------

def rotate(v, axis, angle):
    c, s = math.cos(angle), math.sin(angle)
    d = sum(a * b for a, b in zip(axis, v))
    x = (axis[1] * v[2] - axis[2] * v[1], axis[2] * v[0] - axis[0] * v[2],
         axis[0] * v[1] - axis[1] * v[0])
    return [v[e] * c + axis[e] * d * (1 - c) + x[e] * s for e in range(3)]


def merl_lookup(table, wi, wo):
    h = [a + b for a, b in zip(wi, wo)]
    hl = math.sqrt(sum(x * x for x in h))
    h = [x / hl for x in h]
    th, ph = math.acos(max(-1.0, min(1.0, h[2]))), math.atan2(h[1], h[0])
    dvec = rotate(rotate(wi, (0, 0, 1), -ph), (0, 1, 0), -th)
    td, pd = math.acos(max(-1.0, min(1.0, dvec[2]))), math.atan2(dvec[1], dvec[0])
    i = 0 if th <= 0 else min(89, max(0, int(math.sqrt(th / (math.pi / 2) * 90 * 90))))
    j = min(89, max(0, int(td / (math.pi * 0.5) * 90)))
    if pd < 0:
        pd += math.pi
    k = min(179, max(0, int(pd / math.pi * 180)))
    ind = k + 180 * (j + 90 * i)
    return [float(table[c * N + ind]) * SCALE[c] for c in range(3)]


def bin_centre(i, j, k, ph):
    th = ((i + 0.5) / 90) ** 2 * math.pi / 2
    td, pd = (j + 0.5) * math.pi / 180, (k + 0.5) * math.pi / 180
    dvec = [math.sin(td) * math.cos(pd), math.sin(td) * math.sin(pd), math.cos(td)]
    wi = rotate(rotate(dvec, (0, 1, 0), th), (0, 0, 1), ph)
    h = [math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)]
    c = sum(a * b for a, b in zip(wi, h))
    return wi, [2 * c * h[e] - wi[e] for e in range(3)]


def evaluate(d, mid, token, pairs):
    body = {"pairs": [{"n": [0, 0, 1], "wi": wi, "wo": wo} for wi, wo in pairs]}
    vals = d.post("/api/v1/materials/%s/eval" % mid,
                  headers=dict(tok(token), **{"Content-Type": "application/json"}),
                  data=json.dumps(body), status=200, schema="EvalResponse.json").json()["values"]
    return [[v / wi[2] for v in val] for val, (wi, wo) in zip(vals, pairs)]


def test_01_the_merl_table_reads_as_the_material(d):
    s, mid = fitted(d, CT, {"method": "hf3", "params": {"res": 64}})
    S.update(session=s, material=mid)
    r = d.get("/api/v1/materials/%s/merl.binary" % mid, headers=tok(s["view_token"]), status=200)
    info = r.headers["X-Glint-Merl"]
    print("X-Glint-Merl:", info)
    assert "anisotropic=0" in info and "azimuths=1" in info and "nonfinite=0" in info, info
    assert len(r.content) == 12 + 3 * N * 8 == 34992012, len(r.content)
    if np is None:
        return
    dims = np.frombuffer(r.content[:12], dtype="<i4")
    assert list(dims) == [90, 90, 180], dims
    table = np.frombuffer(r.content[12:], dtype="<f8")
    assert np.isfinite(table).all() and (table >= 0).all()
    rng = random.Random(5)
    # bin centres (above the horizon), the half vector at any azimuth: exact
    pairs = []
    while len(pairs) < 300:
        wi, wo = bin_centre(rng.randrange(90), rng.randrange(80), rng.randrange(180),
                            rng.uniform(0, 2 * math.pi))
        if wi[2] > 0.02 and wo[2] > 0.02:
            pairs.append((wi, wo))
    want = evaluate(d, mid, s["view_token"], pairs)
    worst = max(abs(a - b) / (abs(b) + 1e-9)
                for (wi, wo), w in zip(pairs, want) for a, b in zip(merl_lookup(table, wi, wo), w))
    print("bin centres, the independent reader against /eval: worst relative %.2e" % worst)
    assert worst < 1e-6, worst
    # random pairs: the nearest bin, as every MERL reader looks it up
    pairs = []
    for _ in range(400):
        ti, to = math.acos(rng.uniform(0.05, 1)), math.acos(rng.uniform(0.05, 1))
        pi_, po = rng.uniform(0, 2 * math.pi), rng.uniform(0, 2 * math.pi)
        pairs.append(([math.sin(ti) * math.cos(pi_), math.sin(ti) * math.sin(pi_), math.cos(ti)],
                      [math.sin(to) * math.cos(po), math.sin(to) * math.sin(po), math.cos(to)]))
    want = evaluate(d, mid, s["view_token"], pairs)
    lum = lambda c: 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]  # noqa: E731
    errs = sorted(abs(lum(merl_lookup(table, wi, wo)) - lum(w)) / (lum(w) + 1e-6)
                  for (wi, wo), w in zip(pairs, want))
    print("random pairs, nearest bin: median %.4f, 90th percentile %.4f relative"
          % (errs[len(errs) // 2], errs[len(errs) * 9 // 10]))
    assert errs[len(errs) // 2] < 0.03, errs[len(errs) // 2]


def test_02_an_anisotropic_material_is_averaged(d):
    s, mid = fitted(d, "ward:kd=0.3,ks=0.5,rough=0.1,rough_y=0.35",
                    {"method": "hf2d", "params": {"res": 32, "res_2d": 16}})
    r = d.get("/api/v1/materials/%s/merl.binary" % mid, headers=tok(s["view_token"]), status=200)
    info = r.headers["X-Glint-Merl"]
    print("X-Glint-Merl:", info)
    assert "anisotropic=1" in info and "azimuths=8" in info, info
    assert len(r.content) == 34992012
    # the fit measures how much the material turns with the surface; the .glb carries
    # an anisotropic fit (KHR_materials_anisotropy, with the mesh's TANGENT) where it is
    # the closer, MaterialX and USD the isotropic one, and the note says so
    lst = d.get("/api/v1/materials/%s/exports" % mid, headers=tok(s["view_token"]), status=200,
                schema="ExportList.json").json()
    fit = lst["fit"]
    print("anisotropy:", fit["anisotropy"], fit.get("anisotropic_fit"), fit.get("note"))
    assert fit["anisotropy"] > 0.1, fit
    af = fit["anisotropic_fit"]
    assert af["rel_rms"] < fit["rel_rms"] and 0 < af["strength"] <= 1, fit
    assert "KHR_materials_anisotropy" in fit["extensions"], fit
    assert "KHR_materials_anisotropy" in fit["note"] and "MaterialX and USD hold the isotropic" \
        in fit["note"], fit
    glb = [e for e in lst["exports"] if e["format"] == "glb"][0]
    assert glb["how_close"]["rel_rms"] == af["rel_rms"], glb
    r = d.get("/api/v1/materials/%s/material.glb" % mid, headers=tok(s["view_token"]), status=200)
    doc, binary = glb_chunks(r.content)
    ext = doc["materials"][0]["extensions"]["KHR_materials_anisotropy"]
    assert abs(ext["anisotropyStrength"] - af["strength"]) < 1e-6, (ext, af)
    assert doc["extensionsUsed"] == ["KHR_materials_anisotropy"], doc["extensionsUsed"]
    prim = doc["meshes"][0]["primitives"][0]
    tan = doc["accessors"][prim["attributes"]["TANGENT"]]
    assert tan["type"] == "VEC4" and tan["count"] == doc["accessors"][prim["attributes"]["NORMAL"]]["count"]
    bv = doc["bufferViews"][tan["bufferView"]]
    t = struct.unpack_from("<%df" % (4 * tan["count"]), binary, bv["byteOffset"])
    nv = doc["bufferViews"][doc["accessors"][prim["attributes"]["NORMAL"]]["bufferView"]]
    nrm = struct.unpack_from("<%df" % (3 * tan["count"]), binary, nv["byteOffset"])
    for i in range(0, tan["count"], 97):  # unit, w 1, at right angles to the normal
        tx, ty, tz, tw = t[4 * i:4 * i + 4]
        nx, ny, nz = nrm[3 * i:3 * i + 3]
        assert abs(tx * tx + ty * ty + tz * tz - 1) < 1e-5 and tw == 1.0, (i, t[4 * i:4 * i + 4])
        assert abs(tx * nx + ty * ny + tz * nz) < 1e-5, i
    mtlx = d.get("/api/v1/materials/%s/material.mtlx" % mid, headers=tok(s["view_token"]),
                 status=200).text
    assert "specular_anisotropy" not in mtlx
    # BRDF Explorer's file for hf2d: its 2D factors embedded, no texture bound
    r = d.get("/api/v1/materials/%s/material.brdf" % mid, headers=tok(s["view_token"]), status=200)
    text = r.text
    assert text.startswith("analytic\n") and "method hf2d" in text, text[:300]
    assert "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)" in text
    assert "sampler2D" not in text and "texelFetch" not in text
    assert text.count("    vec3(") >= 16 * 16, "a 2D factor is embedded"


def test_03_access_and_errors(d):
    mid = S["material"]
    # the material on its mesh as binary glTF, with the fitted metallic-roughness material
    r = d.get("/api/v1/materials/%s/material.glb" % mid, headers=tok(S["session"]["view_token"]),
              status=200)
    glb = r.content
    magic, version, total = struct.unpack("<III", glb[:12])
    jl, jt = struct.unpack("<II", glb[12:20])
    assert (magic, version, total, jt) == (0x46546C67, 2, len(glb), 0x4E4F534A)
    doc = json.loads(glb[20:20 + jl])
    bl, bt = struct.unpack("<II", glb[20 + jl:28 + jl])
    assert bt == 0x004E4942 and 28 + jl + bl == len(glb)
    acc = doc["accessors"]
    nv, ni = acc[0]["count"], acc[3]["count"]
    assert acc[1]["count"] == acc[2]["count"] == nv and ni % 3 == 0 and ni > 0
    assert all(abs(v) <= 1.0 + 1e-6 for v in acc[0]["min"] + acc[0]["max"])  # the unit ball
    views = doc["bufferViews"]
    assert views[0]["byteLength"] == 12 * nv and views[3]["byteLength"] == 4 * ni
    pbr = doc["materials"][0]["pbrMetallicRoughness"]
    extras = doc["materials"][0]["extras"]["glint"]
    print("glTF:", r.headers["X-Glint-Gltf"], "| extras:", extras)
    # ct kd 0.4/0.3/0.2, f0 0.2, alpha 0.3: glTF roughness sqrt(0.3) = 0.548
    assert abs(pbr["roughnessFactor"] - math.sqrt(0.3)) < 0.1, pbr
    assert extras["fit_rel_rms"] < 0.1 and extras["method"] == "hf3", extras
    assert "alpha = roughness^2" in extras["model"]
    d.get("/api/v1/materials/%s/material.glb" % mid, status=401)
    # the hf3 material as BRDF Explorer's analytic file
    r = d.get("/api/v1/materials/%s/material.brdf" % mid, headers=tok(S["session"]["view_token"]),
              status=200)
    text = r.text
    assert text.startswith("analytic\n") and "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)" in text
    assert text.index("::begin parameters") < text.index("::begin shader") < text.index("::end shader")
    assert text.count("vec3(") > 3 * 64, "the factors are embedded"
    d.get("/api/v1/materials/%s/material.brdf" % mid, status=401)
    d.get("/api/v1/materials/%s/merl.binary" % mid, status=401)
    d.get("/api/v1/materials/%s/merl.binary" % ("0" * 32), headers=tok(S["session"]["view_token"]),
          status=404)
    d.get("/api/v1/materials/%s/merl.binary" % mid, headers=tok("x" * 40), status=403)


def exr(content):
    import OpenImageIO as oiio
    path = os.path.join(tempfile.mkdtemp(prefix="glint-exp-"), "x.exr")
    with open(path, "wb") as f:
        f.write(content)
    return np.asarray(oiio.ImageBuf(path).get_pixels(oiio.FLOAT))[:, :, :3]


def test_04_measured_materials_paint_as_their_truth(d):
    lst = d.get("/api/v1/measured", status=200, schema="MeasuredList.json").json()["materials"]
    assert [m["spec"] for m in lst] == ["merl:ct.binary", "sgd:matte-test", "abc:matte-test"], lst
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201).json()
    url = "/api/v1/scenes/%s/views/%%d/base.png?format=exr&scale=1&brdf=%%s" % sc["id"]
    for q in ("", "&env=sky&lights=32"):
        a = d.get(url % (2, "merl:ct.binary") + q, status=200)
        b = d.get(url % (2, CT) + q, status=200)
        if np is not None:
            x, y = exr(a.content), exr(b.content)
            rel = float(np.sqrt(((x - y) ** 2).sum() / (y ** 2).sum()))
            print("base render from the measured table against its truth%s: %.4f relative RMS"
                  % (" under the sky" if q else "", rel))
            assert rel < 0.02, rel
    for fit in ("sgd:matte-test", "abc:matte-test"):
        a = d.get(url % (2, fit), status=200)
        b = d.get(url % (2, "lambert:kd=0.4/0.3/0.2"), status=200)
        if np is not None:
            x, y = exr(a.content), exr(b.content)
            rel = float(np.sqrt(((x - y) ** 2).sum() / (y ** 2).sum()))
            assert rel < 1e-6, (fit, rel)
    for bad in ("merl:.hidden.binary", "merl:short.binary", "merl:evil.binary",
                "merl:../ct.binary", "merl:nosuch.binary", "merl:", "sgd:nosuch", "abc:",
                "sgd:../merl56_fits.json"):
        r = d.get(url % (0, bad), status=422)
        assert "no measured material" in r.text or "needs a name" in r.text, (bad, r.text)
    # a session painted from the measured material, fitted: the truth's colour
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    for k in range(len(sc["views"])):
        d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
              headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}),
              data=d.get(url % (k, "merl:ct.binary"), status=200).content, status=200)
    mid = fit_material(d, s, {"method": "hf3", "params": {"res": 64}})
    summ = d.get("/api/v1/materials/%s/summary" % mid, headers=tok(s["view_token"]),
                 status=200, schema="MaterialSummary.json").json()
    print("fitted to the measured paintings: base colour", summ["base_colour"])
    for c, kd in enumerate((0.4, 0.3, 0.2)):
        assert abs(summ["base_colour"][c] - kd) < 0.15 * kd + 0.02, summ["base_colour"]


# ---- glTF textures of a material that varies over the surface ------------------------------

STRIPES = ("stripes:freq=3,duty=0.5|ct:kd=0.6/0.1/0.08,f0=0.04,rough=0.3|"
           "ct:kd=0,f0=0.9/0.7/0.3,rough=0.25")
SV_SIZE = 64  # at 48 a material of maps is 30 to 70% from the stripes in renders


def glb_chunks(glb):
    """The JSON document and the BIN chunk of a binary glTF file."""
    magic, version, total = struct.unpack("<III", glb[:12])
    jl, jt = struct.unpack("<II", glb[12:20])
    assert (magic, version, total, jt) == (0x46546C67, 2, len(glb), 0x4E4F534A)
    bl, bt = struct.unpack("<II", glb[20 + jl:28 + jl])
    assert bt == 0x004E4942 and 28 + jl + bl == len(glb)
    return json.loads(glb[20:20 + jl]), glb[28 + jl:28 + jl + bl]


def png_decode(png):
    """An 8-bit RGB PNG's size and rows of bytes (PNG specification: IHDR,
    zlib-compressed IDAT, one filter byte per row)."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n", png[:8]
    pos, idat, hdr = 8, b"", None
    while pos < len(png):
        n, typ = struct.unpack(">I4s", png[pos:pos + 8])
        body = png[pos + 8:pos + 8 + n]
        assert zlib.crc32(typ + body) == struct.unpack(">I", png[pos + 8 + n:pos + 12 + n])[0]
        if typ == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif typ == b"IDAT":
            idat += body
        pos += 12 + n
    w, h, depth, ctype, _, _, interlace = hdr
    assert (depth, ctype, interlace) == (8, 2, 0), hdr  # 8-bit RGB, not interlaced
    rows = png_unfilter(zlib.decompress(idat), w, h, 3)
    return w, h, rows


def test_05_a_spatial_material_bakes_textures(d):
    tmp = tempfile.mkdtemp(prefix="glint-gltf-")
    scene = os.path.join(tmp, "scene.json")
    subprocess.run([CLI, "scene", "create", "--size", str(SV_SIZE), "-o", scene], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([CLI, "paint", scene, "--brdf", STRIPES, "-o", os.path.join(tmp, "paint")],
                   check=True, stdout=subprocess.DEVNULL)
    sc = d.post("/api/v1/scenes", json={"width": SV_SIZE, "height": SV_SIZE}, status=201).json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    for k in range(len(sc["views"])):
        with open(os.path.join(tmp, "paint", "view_%02d.exr" % k), "rb") as f:
            d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                  headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}),
                  data=f.read(), status=200)
    mid = fit_material(d, s, {"method": "maps",
                              "params": {"res": 32, "map_res": 32, "components": 3}})
    h = tok(s["view_token"])
    url = "/api/v1/materials/%s/material.glb" % mid
    r = d.get(url + "?bake_res=16", headers=h, status=200)
    info = r.headers["X-Glint-Gltf"]
    doc, binary = glb_chunks(r.content)
    mat = doc["materials"][0]
    pbr, extras = mat["pbrMetallicRoughness"], mat["extras"]["glint"]
    print("glTF of maps:", info, "| textures:", extras["textures"])
    assert "spatial=1" in info and "textures=16" in info, info
    assert pbr["baseColorFactor"] == [1, 1, 1, 1] and pbr["metallicFactor"] == 1
    assert pbr["roughnessFactor"] == 1
    prim = doc["meshes"][0]["primitives"][0]
    assert doc["accessors"][prim["attributes"]["TEXCOORD_0"]]["count"] == \
        doc["accessors"][prim["attributes"]["POSITION"]]["count"]
    assert len(doc["images"]) == 2 and len(doc["textures"]) == 2
    imgs = []
    for key in ("baseColorTexture", "metallicRoughnessTexture"):
        assert pbr[key]["texCoord"] == 0
        im = doc["images"][doc["textures"][pbr[key]["index"]]["source"]]
        assert im["mimeType"] == "image/png"
        bv = doc["bufferViews"][im["bufferView"]]
        assert bv["byteOffset"] % 4 == 0 and bv["byteOffset"] + bv["byteLength"] <= len(binary)
        imgs.append(png_decode(binary[bv["byteOffset"]:bv["byteOffset"] + bv["byteLength"]]))
    assert all(w == hh == 16 for w, hh, _ in imgs), [(w, hh) for w, hh, _ in imgs]
    assert extras["textures"]["res"] == 16 and not extras["spatial_average"]
    assert extras["textures"]["texel_rel_rms_median"] < 0.3, extras["textures"]
    # metallic-roughness: R 1, and the stripes across u (bands of 1/6) in B (metallic):
    # gold on [0, 1/6), red plastic on [1/6, 1/3) (texel columns 0-1 and 3-4)
    mr = imgs[1][2]
    assert all(row[3 * x] == 255 for row in mr for x in range(16))
    metal = [sum(row[3 * x + 2] for row in mr) / (16 * 255.0) for x in range(16)]
    green = [sum(row[3 * x + 1] for row in imgs[0][2]) / (16 * 255.0) for x in range(16)]
    print("by texel column, metallic:", " ".join("%.2f" % m for m in metal))
    print("by texel column, base colour's green (sRGB):", " ".join("%.2f" % g for g in green))
    # the material of maps holds the stripes only loosely (5 to 40% from its truth at the
    # painted samples): the textures vary, and the gold columns are the more metallic
    assert max(green) - min(green) > 0.1 and max(metal) - min(metal) > 0.2, (green, metal)
    assert (metal[0] + metal[1]) / 2 > (metal[3] + metal[4]) / 2 + 0.1, metal
    # the average alone when no textures are asked for; sizes refused
    r = d.get(url + "?bake_res=0", headers=h, status=200)
    doc, _ = glb_chunks(r.content)
    assert "images" not in doc and "textures=0" in r.headers["X-Glint-Gltf"]
    assert "textures_not_baked" in doc["materials"][0]["extras"]["glint"]
    for bad in ("257", "-1", "x", "1e3"):
        d.get(url + "?bake_res=" + bad, headers=h, status=400)
    # the USDZ package: the USD layer reading the same textures, checked against
    # the node definitions and the package format (export_specs.py)
    glb_pngs = []
    r = d.get(url + "?bake_res=16", headers=h, status=200)
    doc, binary = glb_chunks(r.content)
    for im in doc["images"]:
        bv = doc["bufferViews"][im["bufferView"]]
        glb_pngs.append(binary[bv["byteOffset"]:bv["byteOffset"] + bv["byteLength"]])
    r = d.get("/api/v1/materials/%s/material.usdz?bake_res=16" % mid, headers=h, status=200)
    assert r.headers["Content-Type"].startswith("model/vnd.usdz+zip")
    assert "textures=16" in r.headers["X-Glint-Fit"], r.headers["X-Glint-Fit"]
    assert re.search(r'filename="sphere-[0-9a-f]{8}\.usdz"', r.headers["Content-Disposition"])
    pkg = os.path.join(tmp, "m.usdz")
    with open(pkg, "wb") as f:
        f.write(r.content)
    out = subprocess.run([sys.executable, SPECS, "usdz", pkg], capture_output=True, text=True)
    print("usdz:", out.stdout.strip()[:300], out.stderr.strip())
    assert out.returncode == 0, out.stderr
    z = zipfile.ZipFile(pkg)
    assert z.namelist() == ["glint.usda", "textures/base_color.png",
                            "textures/metallic_roughness.png"], z.namelist()
    # the same textures as the .glb's, byte for byte (the bake is deterministic)
    assert [z.read("textures/base_color.png"), z.read("textures/metallic_roughness.png")] == \
        glb_pngs
    # a package whose files are compressed is not a USDZ: the check says so
    bad = os.path.join(tmp, "bad.usdz")
    with zipfile.ZipFile(bad, "w", zipfile.ZIP_DEFLATED) as w:
        for n in z.namelist():
            w.writestr(n, z.read(n))
    out = subprocess.run([sys.executable, SPECS, "usdz", bad], capture_output=True, text=True)
    assert out.returncode != 0 and "compressed" in out.stderr, out.stderr
    # without textures: the layer alone, the average
    r = d.get("/api/v1/materials/%s/material.usdz?bake_res=0" % mid, headers=h, status=200)
    with open(pkg, "wb") as f:
        f.write(r.content)
    assert zipfile.ZipFile(pkg).namelist() == ["glint.usda"]
    assert subprocess.run([sys.executable, SPECS, "usdz", pkg]).returncode == 0
    d.get("/api/v1/materials/%s/material.usdz?bake_res=x" % mid, headers=h, status=400)
    # the MaterialX package: the document reading the same textures, checked against
    # the node definitions (image, extract, nodegraph outputs) with its files in it
    r = d.get("/api/v1/materials/%s/material.mtlx.zip?bake_res=16" % mid, headers=h, status=200)
    assert r.headers["Content-Type"] == "application/zip", r.headers["Content-Type"]
    assert "textures=16" in r.headers["X-Glint-Fit"], r.headers["X-Glint-Fit"]
    assert re.search(r'filename="sphere-[0-9a-f]{8}\.mtlx\.zip"', r.headers["Content-Disposition"])
    pkg = os.path.join(tmp, "m.mtlx.zip")
    with open(pkg, "wb") as f:
        f.write(r.content)
    out = subprocess.run([sys.executable, SPECS, "mtlx.zip", pkg], capture_output=True, text=True)
    print("mtlx.zip:", out.stdout.strip()[:300], out.stderr.strip())
    assert out.returncode == 0, out.stderr
    z = zipfile.ZipFile(pkg)
    assert z.namelist() == ["glint.mtlx", "textures/base_color.png",
                            "textures/metallic_roughness.png"], z.namelist()
    assert [z.read("textures/base_color.png"), z.read("textures/metallic_roughness.png")] == \
        glb_pngs
    doc = z.read("glint.mtlx").decode()
    assert 'nodegraph="NG_glint_%s" output="base_color_out"' % mid[:8] in doc, doc
    # a document naming a texture the package lacks: the check says so
    bad = os.path.join(tmp, "bad.mtlx.zip")
    with zipfile.ZipFile(bad, "w", zipfile.ZIP_STORED) as w:
        w.writestr("glint.mtlx", doc)
        w.writestr("textures/base_color.png", z.read("textures/base_color.png"))
    out = subprocess.run([sys.executable, SPECS, "mtlx.zip", bad], capture_output=True, text=True)
    assert out.returncode != 0 and "not in the package" in out.stderr, out.stderr
    # an extract index outside the nodedef's uimin..uimax: the check says so
    try:
        export_specs.check_mtlx(doc.replace('type="integer" value="2"', 'type="integer" value="3"'))
        raise AssertionError("an extract index of 3 on a vector3 passed")
    except export_specs.Bad as e:
        assert "outside 0..2" in str(e), e
    # without textures: the document alone, the average's values
    r = d.get("/api/v1/materials/%s/material.mtlx.zip?bake_res=0" % mid, headers=h, status=200)
    with open(pkg, "wb") as f:
        f.write(r.content)
    z = zipfile.ZipFile(pkg)
    assert z.namelist() == ["glint.mtlx"] and "this is its average" in z.read("glint.mtlx").decode()
    assert subprocess.run([sys.executable, SPECS, "mtlx.zip", pkg]).returncode == 0
    d.get("/api/v1/materials/%s/material.mtlx.zip?bake_res=x" % mid, headers=h, status=400)


run_tests(globals(), daemon_args=("--measured-dir", MDIR))
