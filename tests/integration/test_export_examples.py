"""An example of every export format for every method, written by the test
run into the build directory's examples/ (GLINT_EXAMPLES_DIR), each checked
here as the tool that reads it would read it.

Every built-in method fits a painting of the default sphere (gold stripes
on red plastic for the methods that vary over the surface, one
Cook-Torrance material for the others, under the sky for srbf) through the
real daemon, and its material is downloaded as
  package/       the manifest, factor textures (EXR, PNG 8/16-bit) and GLSL
                 (ES 3.00 and 3.30 core), unpacked from GET .../package
  material.brdf  BRDF Explorer's analytic file
  material.glb   the mesh with a glTF 2.0 metallic-roughness material
  material.mtlx  that material as MaterialX standard_surface
  material.usda  that material as a UsdPreviewSurface on the mesh (hf3's; the
                 others' without the mesh: 19 MB each otherwise)
(the two checked against their node definitions, export_specs.py) and hf3's as a MERL table (material.binary: 35 MB, one is enough to show
the layout).  examples/README.txt lists what was written and what opens it."""
import io
import json
import os
import shutil
import struct
import subprocess
import sys
import tarfile
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from harness import fit_material, run_tests  # noqa: E402
import export_specs  # noqa: E402

SIZE = 48
CT = "ct:kd=0.4/0.3/0.2,f0=0.2,rough=0.3"
STRIPES = ("stripes:freq=3,duty=0.5,soft=0.3|ct:kd=0.6/0.3/0.2,f0=0.04,rough=0.3|"
           "ct:kd=0.05,f0=0.9/0.7/0.3,rough=0.25")
# name, params (small: the formats are the same at any size), painted truth
METHODS = [
    ("hf3", {"res": 32}, CT),
    ("hf2d", {"res": 16, "res_2d": 8}, CT),
    ("hf4", {"res": 16, "s_res": 8}, STRIPES),
    ("maps", {"res": 16, "components": 2, "map_res": 32}, STRIPES),
    ("srbf", {"env": "sky", "lights": 64, "basis_res": 3}, CT),
]
OUT = os.environ.get("GLINT_EXAMPLES_DIR") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(os.environ.get("GLINTD",
                                                                   "build/server/glintd")))),
    "examples")
CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(os.environ.get("GLINTD", "build/server/glintd")))),
    "core", "glint")
WRITTEN = []


def tok(t):
    return {"X-Glint-Token": t}


def fit(d, method, params, spec):
    """A session on the sphere painted with spec on every view (under the
    sky for srbf) and the material the method fits: (session, material id)."""
    sc = d.post("/api/v1/scenes", json={"width": SIZE, "height": SIZE}, status=201).json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    light = "&env=sky&lights=64" if method == "srbf" else ""
    painted = None
    if "|" in spec:  # a truth that varies over the surface: the CLI paints it
        tmp = tempfile.mkdtemp(prefix="glint-examples-")
        scene = os.path.join(tmp, "scene.json")
        subprocess.run([CLI, "scene", "create", "--size", str(SIZE), "-o", scene], check=True,
                       stdout=subprocess.DEVNULL)
        subprocess.run([CLI, "paint", scene, "--brdf", spec, "-o", os.path.join(tmp, "paint")],
                       check=True, stdout=subprocess.DEVNULL)
        painted = os.path.join(tmp, "paint")
    for k in range(len(sc["views"])):
        if painted:
            with open(os.path.join(painted, "view_%02d.exr" % k), "rb") as f:
                img = f.read()
        else:
            img = d.get("/api/v1/scenes/%s/views/%d/base.png?format=exr&scale=1&brdf=%s%s"
                        % (sc["id"], k, spec, light), status=200).content
        d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
              headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}), data=img,
              status=200)
    return s, fit_material(d, s, {"method": method, "params": params})


def write(rel, data):
    path = os.path.join(OUT, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)
    WRITTEN.append((rel, len(data)))


def unpack(method, tar_bytes):
    """The package's regular files under <method>/package/ (names checked:
    relative, no '..'); returns the names."""
    names = []
    with tarfile.open(fileobj=io.BytesIO(tar_bytes), mode="r:") as tf:
        for m in tf.getmembers():
            if m.isdir():
                continue
            parts = m.name.split("/")
            assert m.isfile() and not m.name.startswith("/") and ".." not in parts, m.name
            rel = "/".join(parts[1:])  # below glint-material-<id8>/
            write(os.path.join(method, "package", rel), tf.extractfile(m).read())
            names.append(rel)
    return names


def check_glb(glb, spatial):
    magic, version, total = struct.unpack("<III", glb[:12])
    jl, jt = struct.unpack("<II", glb[12:20])
    assert (magic, version, total, jt) == (0x46546C67, 2, len(glb), 0x4E4F534A)
    doc = json.loads(glb[20:20 + jl])
    bl, bt = struct.unpack("<II", glb[20 + jl:28 + jl])
    assert bt == 0x004E4942 and 28 + jl + bl == len(glb)
    mat = doc["materials"][0]
    pbr = mat["pbrMetallicRoughness"]
    assert 0 <= pbr.get("roughnessFactor", 1) <= 1 and 0 <= pbr.get("metallicFactor", 1) <= 1
    assert "alpha = roughness^2" in mat["extras"]["glint"]["model"]
    if spatial:
        assert "baseColorTexture" in pbr and "metallicRoughnessTexture" in pbr, pbr
        for im in doc["images"]:
            v = doc["bufferViews"][im["bufferView"]]
            start = 28 + jl + v.get("byteOffset", 0)
            assert glb[start:start + 8] == b"\x89PNG\r\n\x1a\n", "an embedded PNG"
    return doc


def test_01_every_method_in_every_format(d):
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    for method, params, spec in METHODS:
        s, mid = fit(d, method, params, spec)
        h = tok(s["view_token"])
        mat = d.get("/api/v1/materials/" + mid, headers=h, status=200).json()
        spatial = spec == STRIPES
        # the package: manifest, textures, shaders
        names = unpack(method, d.get("/api/v1/materials/%s/package" % mid, headers=h,
                                     status=200).content)
        manifest = json.loads(open(os.path.join(OUT, method, "package", "material.json")).read())
        assert manifest["method"] == method, manifest.get("method")
        for want in ("shader/glint_material.frag", "shader/glint_material_330.frag",
                     "shader/shader.json"):
            assert want in names, (method, want, names)
        # BRDF Explorer
        brdf = d.get("/api/v1/materials/%s/material.brdf" % mid, headers=h, status=200).text
        assert brdf.startswith("analytic\n") and "::end shader" in brdf
        assert "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)" in brdf
        assert ("float surface_u 0 1 0.5" in brdf) == spatial, method
        write(os.path.join(method, "material.brdf"), brdf.encode())
        # glTF
        glb = d.get("/api/v1/materials/%s/material.glb" % mid, headers=h, status=200).content
        check_glb(glb, spatial)
        write(os.path.join(method, "material.glb"), glb)
        # MaterialX and USD
        mtlx = d.get("/api/v1/materials/%s/material.mtlx" % mid, headers=h, status=200).text
        export_specs.check_mtlx(mtlx)
        write(os.path.join(method, "material.mtlx"), mtlx.encode())
        usda = d.get("/api/v1/materials/%s/material.usda%s" % (mid, "" if method == "hf3" else "?mesh=0"),
                     headers=h, status=200).text
        assert export_specs.check_usda(usda)[1] == (1 if method == "hf3" else 0)
        write(os.path.join(method, "material.usda"), usda.encode())
        print("%-5s %-28s package %2d files, .brdf %7d bytes, .glb %7d bytes, .mtlx %5d, .usda %8d"
              % (method, mat.get("method", method) + " " + mid[:8], len(names), len(brdf),
                 len(glb), len(mtlx), len(usda)))
        if method == "hf3":
            merl = d.get("/api/v1/materials/%s/merl.binary" % mid, headers=h, status=200).content
            assert len(merl) == 12 + 8 * 3 * 90 * 90 * 180
            assert struct.unpack("<iii", merl[:12]) == (90, 90, 180)
            write(os.path.join(method, "material.binary"), merl)
    lines = ["Examples of glint's exports, written by tests/integration/test_export_examples.py",
             "(each method fitted to a painting of the default sphere; see docs/exports.md,",
             "'Using a glint material elsewhere').", "",
             "  METHOD/package/        material.json, factor textures (EXR, PNG), shader/ (GLSL",
             "                         ES 3.00 and 3.30 core, shader.json: the bindings)",
             "  METHOD/material.brdf   BRDF Explorer (File > Open BRDF)",
             "  METHOD/material.glb    glTF 2.0: Blender (File > Import > glTF), three.js, any viewer",
             "  METHOD/material.mtlx   MaterialX standard_surface: Houdini, Maya, Substance, MaterialXView",
             "  METHOD/material.usda   USD UsdPreviewSurface (hf3's with the mesh): Omniverse, Houdini, Blender 4+, usdview",
             "  hf3/material.binary    the MERL layout: BRDF Explorer, ALTA, dj_brdf", "",
             "Files:"] + ["  %-60s %10d bytes" % (rel, n) for rel, n in WRITTEN]
    with open(os.path.join(OUT, "README.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("examples written to", OUT)


if __name__ == "__main__":
    run_tests(globals())
