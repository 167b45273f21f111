#!/usr/bin/env bash
# End-to-end tests of the glint command line: every subcommand on the
# built-in sphere, and the errors it must give (clear message, non-zero
# status, never a crash).  usage: test_cli.sh path/to/glint
set -u
G=${1:?usage: test_cli.sh path/to/glint}
SRC=$(cd "$(dirname "$0")/../.." && pwd)  # the source tree: the export checks of tests/integration
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
pass=0 fail=0

ok()   { pass=$((pass + 1)); echo "ok   $1"; }
bad()  { fail=$((fail + 1)); echo "FAIL $1"; }
# expect_ok NAME CMD...: command succeeds
expect_ok() { local n=$1; shift; if "$@" >"$T/out" 2>"$T/err"; then ok "$n"; else bad "$n (status $?)"; sed 's/^/    /' "$T/err"; fi; }
# expect_err NAME STATUS PATTERN CMD...: fails with STATUS and a message matching PATTERN
expect_err() {
  local n=$1 st=$2 pat=$3; shift 3
  "$@" >"$T/out" 2>"$T/err"; local got=$?
  if [ "$got" -eq "$st" ] && grep -Eq -- "$pat" "$T/err"; then ok "$n"
  else bad "$n (status $got, want $st; stderr: $(head -c 300 "$T/err"))"; fi
}

expect_ok "version" "$G" version
expect_ok "help" "$G" help
expect_err "unknown command" 1 "unknown command 'frobnicate'" "$G" frobnicate

# scene
expect_ok "scene create" "$G" scene create --size 48 -o "$T/scene.json"
expect_ok "scene show" "$G" scene show "$T/scene.json"
grep -q '"samples"' "$T/out" && ok "scene show reports samples" || bad "scene show reports samples"
expect_err "scene size too small" 1 "size '2' must be a whole number in 8..4096" "$G" scene create --size 2 -o "$T/x.json"
expect_err "scene size not a number" 1 "must be a whole number" "$G" scene create --size abc -o "$T/x.json"
expect_err "scene light angles" 1 "light-angles" "$G" scene create --light-angles 70:20 -o "$T/x.json"
expect_err "scene unknown mesh" 1 "unknown|sphere" "$G" scene create --mesh nosuch -o "$T/x.json"
printf '{"format":"glint-scene","version":1,"mesh":"sphere","width":48' > "$T/trunc.json"
expect_err "scene truncated JSON" 1 "." "$G" scene show "$T/trunc.json"
expect_err "scene missing file" 1 "No such file" "$G" scene show "$T/nope.json"

# G-buffers
expect_ok "gbuffer" "$G" gbuffer "$T/scene.json" -o "$T/gb"
[ -f "$T/gb/view_11.exr" ] && ok "gbuffer writes 12 views" || bad "gbuffer writes 12 views"
if command -v iinfo >/dev/null; then
  iinfo -v "$T/gb/view_00.exr" | grep -q "N.X" && ok "gbuffer channel names" || bad "gbuffer channel names"
fi
expect_err "gbuffer view out of range" 1 "has 12 views" "$G" gbuffer "$T/scene.json" -o "$T/gb" --view 12

# paint
expect_ok "paint ct" "$G" paint "$T/scene.json" --brdf "ct:rough=0.3,kd=0.5,f0=0.04" -o "$T/paint"
expect_ok "paint png" "$G" paint "$T/scene.json" --brdf blinn20 --format png -o "$T/paintpng"
expect_err "paint bad brdf" 1 "unknown|brdf" "$G" paint "$T/scene.json" --brdf velvet -o "$T/p"
expect_err "paint bad key" 1 "rough" "$G" paint "$T/scene.json" --brdf "ct:rough=7" -o "$T/p"
expect_ok "paint stripes" "$G" paint "$T/scene.json" --brdf "stripes:freq=4,duty=0.3|lambert:kd=0.6/0.1/0.1|ct:f0=0.9/0.7/0.3,rough=0.2" -o "$T/paintsv"
expect_err "paint bad pattern" 1 "unknown pattern" "$G" paint "$T/scene.json" --brdf "waves|lambert|ct" -o "$T/p"
expect_err "paint stripes under an environment" 1 "leave out --env" "$G" paint "$T/scene.json" --brdf "stripes|lambert|ct" --env sky -o "$T/p"

# fit
expect_ok "fit" "$G" fit "$T/scene.json" --paintings "$T/paint" -o "$T/mat" --cache-dir "$T/cache" -q
for f in material.json factors.exr factors.png; do
  [ -s "$T/mat/$f" ] && ok "fit writes $f" || bad "fit writes $f"
done
expect_ok "fit png paintings, single precision, brdf model" "$G" fit "$T/scene.json" --paintings "$T/paintpng" -o "$T/mat2" --precision single --model brdf --map log --reg tikhonov:rel1e-3 --no-cache -q
expect_ok "fit cached" "$G" fit "$T/scene.json" --paintings "$T/paint" -o "$T/mat3" --cache-dir "$T/cache"
grep -q '"cache_hit": 1' "$T/out" && ok "second fit reuses the cached precomputation" || bad "second fit reuses the cached precomputation"
expect_err "fit res out of range" 1 "--res '3'" "$G" fit "$T/scene.json" --paintings "$T/paint" -o "$T/m" --res 3
expect_err "fit lambda nan" 1 "--lambda 'nan'" "$G" fit "$T/scene.json" --paintings "$T/paint" -o "$T/m" --lambda nan
expect_err "fit bad regularization" 1 "unknown regularization" "$G" fit "$T/scene.json" --paintings "$T/paint" -o "$T/m" --reg magic
expect_err "fit bad mapping" 1 "unknown mapping" "$G" fit "$T/scene.json" --paintings "$T/paint" -o "$T/m" --map exp
expect_err "fit no paintings" 1 "no painting found" "$G" fit "$T/scene.json" --paintings "$T/gb/none" -o "$T/m"
expect_err "fit wrong file count" 1 "expected 12 painting files" "$G" fit "$T/scene.json" "$T/paint/view_00.exr" -o "$T/m"
mkdir -p "$T/small"
"$G" scene create --size 32 -o "$T/scene32.json" >/dev/null && "$G" paint "$T/scene32.json" --brdf lambert -o "$T/small" >/dev/null
expect_err "fit painting of the wrong size" 1 "32x32 but the scene renders 48x48" "$G" fit "$T/scene.json" --paintings "$T/small" -o "$T/m"
printf 'not an image' > "$T/small/view_00.png"; rm -f "$T/small/view_00.exr"
expect_err "fit corrupt painting" 1 "view 0" "$G" fit "$T/scene32.json" --paintings "$T/small" -o "$T/m"
if command -v oiiotool >/dev/null; then
  mkdir -p "$T/nan"; cp "$T/paint"/view_*.exr "$T/nan/"
  oiiotool "$T/paint/view_03.exr" --mulc 1e39 -d float -o "$T/nan/view_03.exr" 2>/dev/null
  expect_err "fit non-finite painting" 1 "not finite|non-finite|NaN|Inf" "$G" fit "$T/scene.json" --paintings "$T/nan" -o "$T/m"
fi

# render and eval
expect_ok "render view" "$G" render "$T/mat" --scene "$T/scene.json" --view 3 -o "$T/r3.png"
expect_ok "render free camera exr" "$G" render "$T/mat" --scene "$T/scene.json" --eye 0,3,1 --light 2,2,2 --size 64x40 -o "$T/rf.exr"
expect_err "render needs a camera" 1 "needs --view" "$G" render "$T/mat" --scene "$T/scene.json" -o "$T/r.png"
expect_err "render bad vector" 1 "three" "$G" render "$T/mat" --scene "$T/scene.json" --eye 1,2 --light 1,1,1 -o "$T/r.png"
expect_err "render eye at target" 1 "coincide" "$G" render "$T/mat" --scene "$T/scene.json" --eye 0,0,0 --light 1,1,1 -o "$T/r.png"
expect_err "render unsupported format" 1 "." "$G" render "$T/mat" --scene "$T/scene.json" --view 0 -o "$T/r.bmpx"
printf '0 0 1  0.6 0 0.8  0 0 1\n0.3 0 0.95 -0.3 0 0.95\n' > "$T/dirs.txt"
expect_ok "eval" "$G" eval "$T/mat" --dirs "$T/dirs.txt"
[ "$(wc -l < "$T/out")" -eq 2 ] && ok "eval prints one line per pair" || bad "eval prints one line per pair"
printf '0 0 1 nan 0 0.8 0 0 1\n' > "$T/dirsnan.txt"
expect_err "eval non-finite direction" 1 "not finite" "$G" eval "$T/mat" --dirs "$T/dirsnan.txt"
printf '0 0 1 1 2\n' > "$T/dirsshort.txt"
expect_err "eval malformed line" 1 "expected 6, 9 or 11 numbers" "$G" eval "$T/mat" --dirs "$T/dirsshort.txt"
# several materials over the texture coordinates: maps, and eval at u v
expect_ok "fit maps" "$G" fit "$T/scene.json" --paintings "$T/paintsv" --method maps --res 16 --map_res 16 --components 2 --rounds 1 -o "$T/matsv" --cache-dir "$T/cache" -q
[ -f "$T/matsv/coefficients.exr" ] && ok "maps writes its coefficient textures" || bad "maps writes its coefficient textures"
printf '0 0 1  0.3 0 1  -0.2 0.1 1  0.05 0.5\n0 0 1  0.3 0 1  -0.2 0.1 1  0.17 0.5\n0 0 1  0.3 0 1  -0.2 0.1 1\n' > "$T/dirsuv.txt"
expect_ok "eval at texture coordinates" "$G" eval "$T/matsv" --dirs "$T/dirsuv.txt"
[ "$(sed -n 1p "$T/out")" != "$(sed -n 2p "$T/out")" ] && ok "a map varies over the surface" || bad "a map varies over the surface"
printf '0 0 1  0.3 0 1  -0.2 0.1 1  1.5 0.5\n' > "$T/dirsbaduv.txt"
expect_err "eval texture coordinates out of range" 1 "u v must be in" "$G" eval "$T/matsv" --dirs "$T/dirsbaduv.txt"
expect_err "maps rounds without refine" 1 "needs refine" "$G" fit "$T/scene.json" --paintings "$T/paintsv" --method maps --rounds 2 --refine 0 -o "$T/x" -q
printf '{"format":"glint-material","version":1,"method":"hf3","res":64' > "$T/mat3/material.json"
expect_err "corrupt material" 1 "material.json" "$G" eval "$T/mat3" --dirs "$T/dirs.txt"

# G-buffers and paintings as another tool would hand them over (the views
# `glint gbuffer` wrote above): the same fit
expect_ok "fit-gbuffers" "$G" fit-gbuffers "$T/gb" --paintings "$T/paint" -o "$T/matgb" --no-cache
rms_of() { grep -o '"rms_painted": *[0-9.e-]*' "$1" | head -1 | sed 's/.*: *//'; }
a=$(rms_of "$T/matgb/material.json"); b=$(rms_of "$T/mat/material.json")
awk -v a="$a" -v b="$b" 'BEGIN { exit !(a > 0 && (a - b < 1e-6) && (b - a < 1e-6)) }' && ok "fit-gbuffers fits as fit does ($a, $b)" || bad "fit-gbuffers fits as fit does ($a, $b)"
expect_ok "fit-gbuffers, colour varying over uv" "$G" fit-gbuffers "$T/gb" --paintings "$T/paintsv" --method hf4 --res 16 -o "$T/matgb4" --no-cache
expect_err "fit-gbuffers: srbf's shadows need a mesh" 1 "visibility needs the scene's mesh" "$G" fit-gbuffers "$T/gb" --paintings "$T/paint" --method srbf --visibility on --lights 16 --basis_res 3 -o "$T/x"
mkdir -p "$T/nopaint"
expect_err "fit-gbuffers without paintings" 1 "no painting" "$G" fit-gbuffers "$T/gb" --paintings "$T/nopaint" -o "$T/x"
expect_err "fit-gbuffers without G-buffers" 1 "no G-buffer" "$G" fit-gbuffers "$T/nopaint" --paintings "$T/paint" -o "$T/x"
if command -v oiiotool >/dev/null; then
  mkdir -p "$T/gbhalf"
  oiiotool --create 48x48 3 --chnames N.X,N.Y,N.Z -d float -o "$T/gbhalf/view_00.exr" >/dev/null 2>&1
  expect_err "fit-gbuffers names a missing channel" 1 "no channel wi.X" "$G" fit-gbuffers "$T/gbhalf" --paintings "$T/paint" -o "$T/x"
fi

# samples round trip: fitting exported samples gives the same factors
expect_ok "export-samples" "$G" export-samples "$T/scene.json" --paintings "$T/paint" --channel 1 -o "$T/s.txt"
expect_ok "fit-samples" "$G" fit-samples "$T/s.txt" -o "$T/mats" --no-cache --eval "$T/s.txt"
grep -q '"rms"' "$T/out" && ok "fit-samples reports eval error" || bad "fit-samples reports eval error"
printf '0 1 2 0 0 1 nan 0 1 0 0 1 0.5\n' > "$T/sbad.txt"
expect_err "fit-samples non-finite" 1 "not finite" "$G" fit-samples "$T/sbad.txt" -o "$T/m"

# meshes from files and built-in shapes; base renders; EGL rendering; shader export
printf 'v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\nf 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n' > "$T/cube.obj"
expect_ok "scene from an OBJ file" "$G" scene create --mesh "$T/cube.obj" --size 32 -o "$T/cube.json"
expect_ok "scene with the built-in teapot" "$G" scene create --mesh teapot --size 32 -o "$T/teapot.json"
expect_ok "scene with the built-in torus" "$G" scene create --mesh torus --size 32 -o "$T/torus.json"
printf 'v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n' > "$T/nan.obj"
expect_err "scene from an OBJ with NaN" 1 "finite|NaN|nan" "$G" scene create --mesh "$T/nan.obj" -o "$T/x.json"
printf 'ply\nformat ascii 1.0\nelement vertex 3\n' > "$T/trunc.ply"
expect_err "scene from a truncated PLY" 1 "." "$G" scene create --mesh "$T/trunc.ply" -o "$T/x.json"
expect_err "scene from a missing mesh file" 1 "." "$G" scene create --mesh "$T/none.obj" -o "$T/x.json"
expect_ok "base-render (auto engine)" "$G" base-render "$T/teapot.json" -o "$T/base"
[ -f "$T/base/view_11.png" ] && ok "base-render writes 12 views" || bad "base-render writes 12 views"
expect_ok "base-render on the CPU" "$G" base-render "$T/teapot.json" -o "$T/basecpu" --engine cpu --format exr
expect_err "base-render bad engine" 1 "auto, egl or cpu" "$G" base-render "$T/teapot.json" -o "$T/b" --engine vulkan
expect_ok "render with EGL" "$G" render "$T/mat" --scene "$T/scene.json" --view 1 --engine egl -o "$T/egl.png"
expect_ok "render on the CPU" "$G" render "$T/mat" --scene "$T/scene.json" --view 1 --engine cpu -o "$T/cpu.png"
if command -v oiiotool >/dev/null; then
  oiiotool "$T/egl.png" "$T/cpu.png" --diff >/dev/null 2>&1 && ok "EGL and CPU renders agree" || bad "EGL and CPU renders agree"
fi
expect_ok "export-shader" "$G" export-shader "$T/mat" -o "$T/shader"
for f in glint_material.frag glint_material.vert glint_factors.exr shader.json; do
  [ -s "$T/shader/$f" ] && ok "export-shader writes $f" || bad "export-shader writes $f"
done

# MERL tables: a material and a truth out, a measured material painted back in
expect_ok "export-merl of a material" "$G" export-merl "$T/mat" -o "$T/mat.binary"
grep -q '"anisotropic": false' "$T/out" && ok "export-merl reports isotropy" || bad "export-merl reports isotropy"
[ "$(stat -c %s "$T/mat.binary")" = 34992012 ] && ok "a MERL file is 34992012 bytes" || bad "a MERL file is 34992012 bytes"
expect_ok "export-merl of a truth" "$G" export-merl --brdf ct:rough=0.3,kd=0.4,f0=0.2 -o "$T/ct.binary"
expect_ok "paint from a MERL table" "$G" paint "$T/scene.json" --brdf "merl:$T/ct.binary" -o "$T/merlpaint"
[ -f "$T/merlpaint/view_11.exr" ] && ok "paint from a MERL table writes 12 views" || bad "paint from a MERL table writes 12 views"
head -c 1000 "$T/ct.binary" > "$T/short.binary"
expect_err "paint from a truncated MERL table" 1 "not a MERL|truncated" "$G" paint "$T/scene.json" --brdf "merl:$T/short.binary" -o "$T/x"
expect_err "paint from a missing MERL table" 1 "No such file|nosuch" "$G" paint "$T/scene.json" --brdf "merl:$T/nosuch.binary" -o "$T/x"
expect_err "export-merl usage" 1 "usage" "$G" export-merl "$T/mat"
expect_ok "export-brdf" "$G" export-brdf "$T/mat" -o "$T/mat.brdf"
expect_ok "export-gltf" "$G" export-gltf "$T/mat" --scene "$T/scene.json" --paintings "$T/paint" -o "$T/mat.glb"
[ "$(head -c 4 "$T/mat.glb")" = glTF ] && grep -q '"roughness"' "$T/out" && ok "export-gltf writes binary glTF and its fit" || bad "export-gltf writes binary glTF and its fit"
expect_err "export-gltf usage" 1 "usage" "$G" export-gltf "$T/mat" -o "$T/x.glb"
expect_ok "export-mtlx" "$G" export-mtlx "$T/mat" --scene "$T/scene.json" --paintings "$T/paint" -o "$T/mat.mtlx"
grep -q '"fit_rel_rms"' "$T/out" && python3 "$SRC/tests/integration/export_specs.py" mtlx "$T/mat.mtlx" && ok "export-mtlx: standard_surface inputs as the node definition has them" || bad "export-mtlx: standard_surface inputs as the node definition has them"
# (the layer with the sphere's mesh, 19 MB, is checked whole by the integration tests)
expect_ok "export-usda" "$G" export-usda "$T/mat" --scene "$T/scene.json" --paintings "$T/paint" -o "$T/mat.usda"
grep -q 'def Mesh "mesh"' "$T/mat.usda" && grep -q 'rel material:binding = </glint/material>' "$T/mat.usda" && ok "export-usda: the mesh bound to the material" || bad "export-usda: the mesh bound to the material"
expect_ok "export-usda --no-mesh" "$G" export-usda "$T/mat" --scene "$T/scene.json" --paintings "$T/paint" --no-mesh -o "$T/nomesh.usda"
! grep -q 'def Mesh' "$T/nomesh.usda" && python3 "$SRC/tests/integration/export_specs.py" usda "$T/nomesh.usda" && ok "export-usda --no-mesh: the UsdPreviewSurface alone, as the specification has it" || bad "export-usda --no-mesh: the UsdPreviewSurface alone, as the specification has it"
# a pbr material: its own parameters with KHR extensions where closer than the fit
expect_ok "paint phong32" "$G" paint "$T/scene.json" --brdf phong32 -o "$T/paintph"
expect_ok "fit pbr" "$G" fit "$T/scene.json" --paintings "$T/paintph" --method pbr -o "$T/matpbr" --no-cache -q
expect_ok "export-gltf of a pbr material" "$G" export-gltf "$T/matpbr" --scene "$T/scene.json" --paintings "$T/paintph" -o "$T/pbr.glb"
python3 - "$T/out" "$T/pbr.glb" <<'PY' && ok "export-gltf of a pbr material: the closer path, its extensions declared" || bad "export-gltf of a pbr material: the closer path, its extensions declared ($(cat "$T/out"))"
import json, struct, sys
o = json.load(open(sys.argv[1]))
b = open(sys.argv[2], "rb").read()
d = json.loads(b[20:20 + struct.unpack("<I", b[12:16])[0]])
assert o["export"] in ("exact parameters", "fitted"), o
assert (o["export"] == "exact parameters") == (o["rel_rms_exact"] <= o["rel_rms_fitted"]), o
assert abs(o["fit_rel_rms"] - min(o["rel_rms_exact"], o["rel_rms_fitted"])) < 1e-4, o
assert d.get("extensionsUsed", []) == o["extensions"], (d.get("extensionsUsed"), o)
assert sorted(d["materials"][0].get("extensions", {})) == sorted(o["extensions"])
assert d["materials"][0]["extras"]["glint"]["export"] == o["export"]
PY
expect_ok "export-usda of a pbr material" "$G" export-usda "$T/matpbr" --scene "$T/scene.json" --paintings "$T/paintph" --no-mesh -o "$T/pbr.usda"
python3 "$SRC/tests/integration/export_specs.py" usda "$T/pbr.usda" >/dev/null && ok "export-usda of a pbr material conforms" || bad "export-usda of a pbr material conforms"
expect_ok "export-mtlx of a pbr material" "$G" export-mtlx "$T/matpbr" --scene "$T/scene.json" --paintings "$T/paintph" -o "$T/pbr.mtlx"
python3 "$SRC/tests/integration/export_specs.py" mtlx "$T/pbr.mtlx" >/dev/null && ok "export-mtlx of a pbr material conforms" || bad "export-mtlx of a pbr material conforms"
expect_err "export-mtlx usage" 1 "usage" "$G" export-mtlx "$T/mat" -o "$T/x.mtlx"
expect_ok "export-mtlx-zip of maps" "$G" export-mtlx-zip "$T/matsv" --scene "$T/scene.json" --paintings "$T/paintsv" --bake-res 8 -o "$T/sv.mtlx.zip"
grep -q '"res": 8' "$T/out" && python3 "$SRC/tests/integration/export_specs.py" mtlx.zip "$T/sv.mtlx.zip" >/dev/null && [ "$(python3 -c 'import sys, zipfile; print(len(zipfile.ZipFile(sys.argv[1]).namelist()))' "$T/sv.mtlx.zip")" = 3 ] && ok "export-mtlx-zip: the document and the two textures it reads" || bad "export-mtlx-zip: the document and the two textures it reads"
expect_ok "export-mtlx-zip of a uniform material" "$G" export-mtlx-zip "$T/mat" --scene "$T/scene.json" --paintings "$T/paint" -o "$T/u.mtlx.zip"
python3 "$SRC/tests/integration/export_specs.py" mtlx.zip "$T/u.mtlx.zip" >/dev/null && ok "export-mtlx-zip of a uniform material conforms" || bad "export-mtlx-zip of a uniform material conforms"
expect_err "export-mtlx-zip --bake-res range" 1 "bake-res" "$G" export-mtlx-zip "$T/mat" --scene "$T/scene.json" --bake-res 5000 -o "$T/x.zip"
expect_err "export-mtlx-zip usage" 1 "usage" "$G" export-mtlx-zip "$T/mat" -o "$T/x.zip"
expect_err "export-mtlx --no-mesh is usda's" 1 "usage" "$G" export-mtlx "$T/mat" --scene "$T/scene.json" --no-mesh -o "$T/x.mtlx"
head -1 "$T/mat.brdf" | grep -q '^analytic$' && grep -q 'vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)' "$T/mat.brdf" && ok "export-brdf writes BRDF Explorer's format" || bad "export-brdf writes BRDF Explorer's format"

# environment lighting: truths painted under a built-in sky, the srbf fit, a preview
expect_ok "paint under an environment" "$G" paint "$T/torus.json" --brdf ct:rough=0.3,kd=0.4,f0=0.25 --env sky --lights 64 -o "$T/envlit"
expect_err "paint under an unknown environment" 1 "built-in" "$G" paint "$T/torus.json" --brdf lambert --env nosuch -o "$T/x"
expect_ok "fit srbf" "$G" fit "$T/torus.json" --paintings "$T/envlit" --method srbf --env sky --lights 64 --basis_res 3 --static smith --no-cache -o "$T/srbfmat"
python3 - "$T/srbfmat/material.json" <<'PY' && ok "srbf material: fits its paintings, energy holds, shadows cast" || bad "srbf material: fits its paintings, energy holds, shadows cast"
import json, sys
m = json.load(open(sys.argv[1]))
i = m["info"]
assert m["method"] == "srbf" and len(m["lobes"]) == 27, m["method"]
assert i["errors"]["rel_rms_painted"] < 0.1, i["errors"]["rel_rms_painted"]
assert i["errors"]["albedo_max_rows"] <= 1.0, i["errors"]["albedo_max_rows"]
assert i["precomputation"]["visibility"] == 1 and i["precomputation"]["mesh_convex"] is False
PY
expect_ok "render an srbf material" "$G" render "$T/srbfmat" --scene "$T/torus.json" --view 0 -o "$T/srbf.png"
expect_ok "render an srbf material under the sky, rotated" "$G" render "$T/srbfmat" --scene "$T/torus.json" --eye 0,-3,1.5 --env sky --env-rotation 45 --lights 16 --size 96x96 -o "$T/srbf_env.exr"
grep -q "16 lights, shadows cast" "$T/out" && ok "render --env reports its lights and shadows" || bad "render --env reports its lights and shadows ($(cat "$T/out"))"
expect_ok "render --env on the CPU (the reference)" "$G" render "$T/srbfmat" --scene "$T/torus.json" --view 0 --env sky --lights 16 --no-background --engine cpu -o "$T/srbf_env_cpu.png"
expect_err "render --env with a bad spec" 1 "env" "$G" render "$T/srbfmat" --scene "$T/torus.json" --view 0 --env "a b" -o "$T/x.png"
expect_err "render --env with too many lights" 1 "lights" "$G" render "$T/srbfmat" --scene "$T/torus.json" --view 0 --env sky --lights 5000 -o "$T/x.png"
expect_err "render --env unknown environment" 1 "no environment|built-in|unknown" "$G" render "$T/srbfmat" --scene "$T/torus.json" --view 0 --env nosuch -o "$T/x.png"
expect_err "fit srbf with an impossible diffuse albedo" 1 "above 1" "$G" fit "$T/torus.json" --paintings "$T/envlit" --method srbf --diffuse 1.5 -o "$T/x"

# demo (the main job before the daemon exists)
expect_ok "demo" "$G" demo -o "$T/demo"
[ -f "$T/demo/material/material.json" ] && ok "demo writes a material" || bad "demo writes a material"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
