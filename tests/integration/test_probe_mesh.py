"""Uploaded meshes cannot read the daemon's files.

An outside probe posted glTF documents whose buffer URI named a file on the
server (/etc/shadow, ../ paths, file:// URIs): the upload answered 201 and
the file's bytes came back through the mesh report, and a missing file
answered differently from a present one.  Here the same requests go to the
real daemon: each must be refused with a 4xx problem+json answer
(Problem.json is checked by the harness), carry no bytes of the file it
names, and read the same, status and detail, whether that file exists or
not.  The same for glTF images, OBJ material libraries and COLLADA images,
whether or not anything uses them, and for relative names as well: an
upload is the whole mesh (422 invalid-mesh, naming the reference).  A glTF
that carries its data in data: URIs, and a .glb, still upload.

Counts are checked before any work: an OBJ of 2.1 million copies of one
triangle (16 MB, over the default --max-mesh-tris of 2,000,000; the import
took minutes and a gigabyte) and PLY headers of 100,000 properties or
comment lines are refused from what the bytes say, before the importer runs: 413 naming the
count and the limit, and the daemon's peak memory grows by little more than
the request body.
"""
import base64
import json
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(__file__))
from harness import run_tests  # noqa: E402

API = "/api/v1"

# Files that exist on every machine this runs on, and names that do not.
PRESENT = ["/etc/passwd", "/etc/shadow", "/etc/hostname"]
MISSING = ["/etc/glint-probe-no-such-file", "/nonexistent-glint-probe/secret"]
# The same targets spelled other ways.
SPELLINGS = ["../../../../../../../../etc/passwd", "file:///etc/passwd",
             "../../../../../../../../etc/glint-probe-no-such-file",
             "file:///etc/glint-probe-no-such-file"]

# One triangle, 3 float VEC3 positions: 36 bytes.
TRIANGLE = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)


def gltf(buffer_uri, image_uri=None):
    """The probe's document: one buffer of 36 bytes read as 3 positions."""
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 4}]}],
        "buffers": [{"uri": buffer_uri, "byteLength": 36}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
    }
    if image_uri is not None:
        doc["meshes"][0]["primitives"][0]["material"] = 0
        doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
        doc["textures"] = [{"source": 0}]
        doc["images"] = [{"uri": image_uri}]
    return json.dumps(doc).encode()


def data_uri(raw):
    return "data:application/octet-stream;base64," + base64.b64encode(raw).decode()


OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def obj(mtllib):
    return b"mtllib " + mtllib.encode() + b"\nusemtl m\n" + OBJ


def dae(image):
    return ("""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
 <library_images><image id="img"><init_from>%s</init_from></image></library_images>
 <library_effects><effect id="fx"><profile_COMMON><technique sid="t"><lambert><diffuse>
  <texture texture="img" texcoord="uv0"/></diffuse></lambert></technique></profile_COMMON>
 </effect></library_effects>
 <library_materials><material id="mat"><instance_effect url="#fx"/></material></library_materials>
 <library_geometries><geometry id="tet"><mesh>
  <source id="p"><float_array id="pa" count="12">0 0 0 1 0 0 0 1 0 0 0 1</float_array>
   <technique_common><accessor source="#pa" count="4" stride="3"><param name="X" type="float"/>
   <param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common>
  </source>
  <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
  <triangles material="m" count="4"><input semantic="VERTEX" source="#v" offset="0"/>
   <p>0 2 1 0 1 3 0 3 2 1 2 3</p></triangles>
 </mesh></geometry></library_geometries>
 <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#tet">
  <bind_material><technique_common><instance_material symbol="m" target="#mat"/>
  </technique_common></bind_material></instance_geometry></node></visual_scene>
 </library_visual_scenes>
 <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
""" % image).encode()


def dae_unused(image):
    """The COLLADA document with an image that no effect uses."""
    return dae(image).replace(b'<texture texture="img" texcoord="uv0"/>',
                              b"<color>0.8 0.8 0.8 1</color>")


def glb(image_uri=None):
    """The triangle as a .glb (JSON chunk, then the 36-byte binary chunk),
    with an image by `image_uri` that nothing uses when given."""
    doc = json.loads(gltf("unused"))
    del doc["buffers"][0]["uri"]
    if image_uri is not None:
        doc["images"] = [{"uri": image_uri}]
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    chunks = (struct.pack("<I", len(text)) + b"JSON" + text +
              struct.pack("<I", len(TRIANGLE)) + b"BIN\0" + TRIANGLE)
    return b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks


def target_path(ref):
    """The server file a reference would reach (the daemon's working
    directory is below / at most 8 levels deep)."""
    if ref.startswith("file://"):
        return ref[len("file://"):]
    return os.path.normpath(os.path.join("/", ref))


def file_bytes(path):
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError:
        return b""


def assert_no_bytes_of(body, content, what):
    """No 8-byte run of the file, and none of the floats the probe's 36-byte
    buffer would have become, appears in the answer."""
    for i in range(0, max(0, len(content) - 7)):
        run = content[i:i + 8]
        assert run not in body, "%s: the answer holds bytes of the file: %r" % (what, run)
    if len(content) >= 36:
        for x in struct.unpack("<9f", content[:36]):
            for text in ("%g" % x, repr(x)):
                if len(text) >= 6:
                    assert text.encode() not in body, "%s: the answer holds %s" % (what, text)


def refused(d, fmt, body, ref):
    """Post an upload that refers to `ref`; check the refusal; return
    (status, detail with the reference replaced by <ref>)."""
    r = d.post(API + "/meshes?format=" + fmt, data=body)
    assert 400 <= r.status_code < 500, "%s %s: status %d: %s" % (fmt, ref, r.status_code,
                                                                 r.text[:300])
    assert r.headers.get("Content-Type", "").startswith("application/problem+json"), \
        "%s %s: %s" % (fmt, ref, r.headers.get("Content-Type"))
    p = r.json()
    assert "report" not in p and "id" not in p
    detail = p["detail"]
    assert "external references are not allowed in uploads" in detail, detail
    # the reference as the file writes it
    shown = ref
    assert shown[:40] in detail, "%s: the detail does not name the reference: %s" % (ref, detail)
    # (the reference itself is in the detail: look at everything else)
    assert_no_bytes_of(r.content.replace(shown.encode(), b""), file_bytes(target_path(ref)),
                       "%s %s" % (fmt, ref))
    return r.status_code, p["type"], p["title"], detail.replace(shown, "<ref>")


def same_answers(d, fmt, make, refs):
    answers = {ref: refused(d, fmt, make(ref), ref) for ref in refs}
    first = answers[refs[0]]
    for ref, a in answers.items():
        assert a == first, "%s: %s answers %r, %s answers %r" % (fmt, refs[0], first, ref, a)
    return first


def test_probe_gltf_buffer(d):
    # the probe's own request, for files that exist and files that do not
    assert all(os.path.exists(p) for p in PRESENT)
    assert not any(os.path.exists(p) for p in MISSING)
    same_answers(d, "gltf", gltf, PRESENT + MISSING + SPELLINGS)
    # the same document with its data inline uploads, and reports its own triangle
    r = d.post(API + "/meshes?format=gltf", status=201, schema="Mesh.json",
               data=gltf(data_uri(TRIANGLE)))
    m = r.json()
    assert m["triangles"] == 1 and m["format"] == "gltf"
    assert [round(c, 6) for c in m["report"]["center"]] == [0.5, 0.5, 0.0]


def test_probe_gltf_image(d):
    inline = data_uri(TRIANGLE)
    same_answers(d, "gltf", lambda ref: gltf(inline, ref), PRESENT + MISSING + SPELLINGS)


def test_probe_obj_mtllib(d):
    same_answers(d, "obj", obj, PRESENT + MISSING + SPELLINGS[:1] + SPELLINGS[2:3])


def test_probe_dae_image(d):
    same_answers(d, "dae", dae, PRESENT + MISSING + SPELLINGS)


def test_probe_buffer_and_image_alike(d):
    a = refused(d, "gltf", gltf("/etc/passwd"), "/etc/passwd")
    b = refused(d, "gltf", gltf(data_uri(TRIANGLE), "/etc/passwd"), "/etc/passwd")
    assert a == b, (a, b)


def test_probe_unused_and_relative_references(d):
    """A reference nothing uses, or a relative one, is still a reference to
    a file the upload does not carry: refused with 422 invalid-mesh naming
    it (a glTF image no material samples, relative glTF images, an OBJ
    material library beside the file, a COLLADA image no effect uses, the
    JSON of a .glb); the same files without it upload."""
    inline = data_uri(TRIANGLE)
    unused = json.loads(gltf(inline))
    unused["images"] = [{"uri": "/etc/passwd"}]
    cases = [("gltf", json.dumps(unused).encode(), "/etc/passwd"),
             ("gltf", gltf(inline, "tex.png"), "tex.png"),
             ("gltf", gltf(inline, "textures/tex.png"), "textures/tex.png"),
             ("obj", obj("model.mtl"), "model.mtl"),
             ("dae", dae_unused("file:///etc/passwd"), "file:///etc/passwd"),
             ("dae", dae_unused("../textures/wood.png"), "../textures/wood.png"),
             ("dae", dae("tex.png"), "tex.png"),
             ("glb", glb("tex.png"), "tex.png")]
    for fmt, body, ref in cases:
        r = d.post(API + "/meshes?format=" + fmt, data=body)
        assert r.status_code == 422, "%s %s: %d %s" % (fmt, ref, r.status_code, r.text[:300])
        p = r.json()
        assert p["type"] == "/problems/invalid-mesh", p
        assert "external references are not allowed in uploads" in p["detail"], p["detail"]
        assert '"%s"' % ref in p["detail"], "%s: not named: %s" % (ref, p["detail"])
        assert_no_bytes_of(r.content.replace(ref.encode(), b""),
                           file_bytes(target_path(ref)) if ref.startswith(("/", "file:"))
                           else b"", "%s %s" % (fmt, ref))
    # without the reference the same documents upload
    for fmt, body in (("gltf", gltf(inline)), ("glb", glb()), ("obj", OBJ),
                      ("dae", dae_unused("x").replace(
                          b'<library_images><image id="img"><init_from>x</init_from></image>'
                          b'</library_images>', b""))):
        r = d.post(API + "/meshes?format=" + fmt, data=body, schema="Mesh.json")
        assert r.status_code == 201, "%s: %d %s" % (fmt, r.status_code, r.text[:300])


def peak_kb(d):
    with open("/proc/%d/status" % d.proc.pid) as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    raise AssertionError("no VmHWM")


def test_counts_are_checked_before_the_import(d):
    many = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n" + b"f 1 2 3\n" * 2100000
    before = peak_kb(d)
    r = d.post(API + "/meshes?format=obj", data=many, timeout=600)
    assert r.status_code == 413, (r.status_code, r.text[:300])
    p = r.json()
    assert p["type"].endswith("/mesh-too-large"), p
    assert "2100000 triangles" in p["detail"] and "limit of 2000000" in p["detail"], p
    assert "--max-mesh-tris" in p["detail"], p
    # the body (16.8 MB, in a buffer of up to twice that while it arrives)
    # and little else: no import, no cleaning of 2.1 million triangles
    grown = peak_kb(d) - before
    assert grown < 64 * 1024, "peak memory grew by %d kB" % grown
    ply = (b"ply\nformat ascii 1.0\nelement vertex 3\n" + b"property float x\n" * 100000 +
           b"element face 1\nproperty list uchar int vertex_indices\nend_header\n"
           b"0\n1\n2\n3 0 1 2\n")
    r = d.post(API + "/meshes?format=ply", data=ply, timeout=600)
    assert r.status_code == 413, (r.status_code, r.text[:300])
    p = r.json()
    assert "more than 64 properties" in p["detail"], p
    ply = (b"ply\nformat ascii 1.0\n" + b"comment hello\n" * 100000 +
           b"element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           b"end_header\n0 0 0\n1 0 0\n0 1 0\n")
    r = d.post(API + "/meshes?format=ply", data=ply, timeout=600)
    assert r.status_code == 413 and "more than 4096 lines" in r.text, (r.status_code, r.text)
    # within the limits, the same kinds of file upload
    d.post(API + "/meshes?format=obj", data=OBJ, status=201, schema="Mesh.json")
    ok = (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
          b"property float z\nelement face 2\nproperty list uchar int vertex_indices\n"
          b"end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 3 1\n")
    d.post(API + "/meshes?format=ply", data=ok, status=201, schema="Mesh.json")


if __name__ == "__main__":
    run_tests(globals())
