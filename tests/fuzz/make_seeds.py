#!/usr/bin/env python3
"""Write the fuzz targets' starting corpora (tests/fuzz/corpus/NAME/seed-*).

    make_seeds.py BUILD_DIR

Small, valid inputs of every kind each target reads: the campaigns
(campaign.sh) grow the corpora from them, and the minimized result is what
tests/fuzz/corpus keeps.  Images, patterns and decompositions are made by
glint itself (BUILD_DIR/core/glint, BUILD_DIR/tests/fuzz/fuzz_cache).
Standard library only."""
import base64
import glob
import json
import os
import struct
import subprocess
import sys
import tempfile
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def put(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


def json_seeds():
    stroke = {"mode": "paint", "color": [0.8, 0.2, 0.1], "diameter": 12, "kappa": 0.5,
              "opacity": 0.7, "points": [[10, 10], [20, 15.5], [30, 40]], "tag": "t1"}
    put("json", "strokes", b"\x00\x00" + json.dumps([stroke]).encode())
    put("json", "strokes-modes", b"\x00\x00" + json.dumps([
        {"mode": "scale", "scale": 1.5, "diameter": 4, "points": [[1, 2]]},
        {"mode": "erase", "diameter": 3e2, "points": [[0, 0], [255, 255]]}]).encode())
    # one set per method, in the registry's order (the second byte picks it)
    params = [{"res": 32, "lambda": 0.05, "mapping": "log", "model": "brdf", "route": "svd",
               "regularization": "trunc:full", "precision": "single", "rcond": 1e-8},
              {"env": "sky", "lights": 16, "basis_res": 3, "sigma": 0.1, "static": "smith",
               "constraints": "nonneg", "diffuse": "0.2,0.3,0.4", "raster": "full",
               "smooth": 0, "grazing": 0, "start": "warm", "env_rotation": 90.5},
              {"res": 16, "s_res": 8, "lambda_s": 0.2, "mapping": "add:0.5,eps=0.01"},
              {"res": 16, "res_2d": 8, "p": "2d", "q": "1d", "lambda_2d": 0.1},
              {"components": 3, "merge": "lsq", "map_res": 64, "tolerance": 0.1, "rounds": 2},
              {"components": 2, "s_res": 8, "refine": 5, "smooth": 0.5},
              {"threshold": 0.2, "every": 2, "floor": 0.01}]
    for i, p in enumerate(params):
        put("json", "params-%d" % i, bytes([1, i]) + json.dumps(p).encode())
    scene = {"format": "glint-scene", "version": 1, "mesh": "sphere", "width": 16,
             "height": 16, "views": [
                 {"eye": [0, 0, 3.5], "target": [0, 0, 0], "half_fov": 0.3,
                  "light": [1, 1, 3], "light_intensity": 1, "light_deg": 20},
                 {"eye": [0, 3.5, 0.1], "target": [0, 0, 0.1], "half_fov": 0.5,
                  "light": [0, 3, 1], "light_intensity": 2.5, "light_deg": 40}]}
    put("json", "scene", b"\x02\x00" + json.dumps(scene).encode())
    # every control character but NUL (jansson refuses it), in a value and
    # a key, and reals at the edges, for json_text's escapes and shortest
    # reals (every document is written back; a first byte of 3 picks
    # indent 1)
    ctl = "".join(chr(c) for c in range(1, 32)) + "\"\\/\x7f\u00e9\u2028"
    put("json", "control-chars", b"\x03\x00" + json.dumps(
        [{"tag": ctl, ctl: [1, -0.0, 5e-324, 1e-310, 1.7976931348623157e308, 0.1, 1e21,
                           -9007199254740993, 123456789012345678]}]).encode())
    put("json", "control-chars-no-reals", b"\x00\x00" + json.dumps(
        [{"tag": ctl, ctl: [1, -9007199254740993, {"": [[], {}]}]}]).encode())


def image_seeds(glint, tmp):
    scene = os.path.join(tmp, "s.json")
    subprocess.run([glint, "scene", "create", "--size", "8", "-o", scene], check=True,
                   stdout=subprocess.DEVNULL)
    for fmt in ("png", "exr", "hdr"):
        out = os.path.join(tmp, "p-" + fmt)
        subprocess.run([glint, "paint", scene, "--brdf", "lambert", "--format", fmt, "-o", out],
                       check=True, stdout=subprocess.DEVNULL)
        first = sorted(glob.glob(os.path.join(out, "*." + fmt)))[0]
        data = open(first, "rb").read()
        put("image", "painting." + fmt, b"\x00" + data)
        if fmt != "hdr":  # a stored upload, under a stroke on lines 2..3
            put("stroke_file", "upload." + fmt, bytes([0, 3, 2]) + data)
    # an 8 x 4 lat-long map and a 4 x 3 cross (faces 1 x 1), as Radiance HDR (flat RLE-less)
    def hdr(w, h):
        head = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w)
        return head + bytes([128, 100, 64, 129]) * (w * h)
    put("image", "env-latlong.hdr", b"\x01" + hdr(8, 4))
    put("image", "env-cross.hdr", b"\x01" + hdr(4, 3))
    # PNGs the target builds (byte 0 of 3: png_build in fuzz_image.c):
    # width, height, colour type and depth, flags, then scanline bytes
    rows = bytes((i * 29 + 7) % 256 for i in range(97))
    for name, head in (("rgb8", [15, 11, 0, 0]), ("rgba8", [20, 5, 1, 0]),
                       ("rgb8-gamma", [7, 7, 0, 2]), ("rgb8-text-offs", [9, 4, 0, 96]),
                       ("rgb8-interlaced", [12, 13, 0, 1]), ("rgb8-trns", [6, 6, 0, 8]),
                       ("palette8", [10, 10, 13, 0]), ("grey16", [5, 9, 8, 0]),
                       ("rgb16-srgb-chrm", [4, 4, 9, 20])):
        put("image", "built-" + name, bytes([3] + head) + rows)
    # a MERL header (90 x 90 x 180) with too few entries
    put("image", "merl-short", b"\x02" + struct.pack("<3i", 90, 90, 180) + b"\x00" * 64)


def stroke_file_seeds():
    # (the files an upload stored, byte 0 even, come from image_seeds) glint's own files (byte 0 odd): width, height, channels, values; a
    # stroke within a block, across a block edge, none, every line; then
    # the same file with one byte of a table entry and of a block flipped
    put("stroke_file", "glint-1block", bytes([1, 4, 3, 39, 11, 0, 0x5b, 0x01]))
    put("stroke_file", "glint-edge", bytes([1, 15, 4, 63, 47, 0, 0x2d, 0x00]))
    put("stroke_file", "glint-none", bytes([1, 0, 0, 20, 70, 0, 0x13, 0x02]))
    put("stroke_file", "glint-all", bytes([1, 0, 80, 20, 70, 0, 0x13, 0x02]))
    put("stroke_file", "glint-rgba", bytes([1, 2, 5, 30, 33, 1, 0x7f, 0x00]))
    put("stroke_file", "glint-flipped",
        bytes([1, 40, 3, 31, 63, 0, 0x66, 0x01]) + struct.pack("<HB", 0x160, 0x01)
        + struct.pack("<HB", 0x1a0, 0x80))


def mesh_seeds():
    obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\n" \
          b"vn 0 0 1\nf 1/1/1 3/3/1 2/2/1\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    put("mesh", "tet.obj", b"\x01" + obj)
    ply = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n" \
          b"property float z\nelement face 4\nproperty list uchar int vertex_indices\n" \
          b"end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"
    put("mesh", "tet.ply", b"\x00" + ply)
    verts = struct.pack("<12f", 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1)
    faces = b"".join(struct.pack("<B3i", 3, *f) for f in ((0, 2, 1), (0, 1, 3), (0, 3, 2),
                                                          (1, 2, 3)))
    plyb = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\n" \
           b"property float y\nproperty float z\nelement face 4\n" \
           b"property list uchar int vertex_indices\nend_header\n" + verts + faces
    put("mesh", "tet-binary.ply", b"\x00" + plyb)
    off = b"OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"
    put("mesh", "tet.off", b"\x02" + off)
    tri = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 4}]}],
           "buffers": [{"uri": "data:application/octet-stream;base64," +
                        base64.b64encode(tri).decode(), "byteLength": 36}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3,
                          "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}]}
    put("mesh", "tri.gltf", b"\x03" + json.dumps(doc).encode())
    del doc["buffers"][0]["uri"]
    js = json.dumps(doc).encode()
    js += b" " * (-len(js) % 4)
    glb = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(js) + 8 + len(tri)) + \
        struct.pack("<I4s", len(js), b"JSON") + js + struct.pack("<I4s", len(tri), b"BIN\0") + tri
    put("mesh", "tri.glb", b"\x04" + glb)
    dae = b"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
 <library_geometries><geometry id="tet"><mesh>
  <source id="p"><float_array id="pa" count="12">0 0 0 1 0 0 0 1 0 0 0 1</float_array>
   <technique_common><accessor source="#pa" count="4" stride="3"><param name="X" type="float"/>
   <param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common>
  </source>
  <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
  <triangles count="4"><input semantic="VERTEX" source="#v" offset="0"/>
   <p>0 2 1 0 1 3 0 3 2 1 2 3</p></triangles>
 </mesh></geometry></library_geometries>
 <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#tet"/>
 </node></visual_scene></library_visual_scenes>
 <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""
    put("mesh", "tet.dae", b"\x05" + dae)


def cache_seeds(build, glint, tmp):
    seeds = os.path.join(tmp, "cache")
    os.makedirs(seeds)
    env = dict(os.environ, GLINT_FUZZ_SEEDS=seeds)
    subprocess.run([os.path.join(build, "tests", "fuzz", "fuzz_cache"), "--allow-empty",
                    os.path.join(tmp, "none")], check=True, env=env, stdout=subprocess.DEVNULL)
    # srbf's levels, from a small fit through the CLI
    scene = os.path.join(tmp, "s8.json")
    subprocess.run([glint, "scene", "create", "--size", "8", "-o", scene], check=True,
                   stdout=subprocess.DEVNULL)
    subprocess.run([glint, "paint", scene, "--brdf", "ct:rough=0.2", "--env", "sky", "-o",
                    os.path.join(tmp, "pe")], check=True, stdout=subprocess.DEVNULL)
    subprocess.run([glint, "fit", scene, "--paintings", os.path.join(tmp, "pe"), "--method",
                    "srbf", "--env", "sky", "--lights", "4", "--basis_res", "2", "--grazing",
                    "0", "--raster", "full", "--cache-dir", seeds, "-o",
                    os.path.join(tmp, "m")], check=True, stdout=subprocess.DEVNULL)
    for path in sorted(os.listdir(seeds)):
        data = open(os.path.join(seeds, path), "rb").read()
        if path.endswith(".hfd"):
            sel, head = 0, 8
        elif path.endswith(".pattern"):
            rule = struct.unpack_from("<I", data, 12 + 16)[0]
            sel, head = 1 | (rule << 2), 12
        elif path.startswith("srbf-energy"):
            sel, head = 2, 12
        elif path.startswith("srbf-transfer"):
            sel, head = 3, 12
        else:
            continue
        tag = path.split(".")[-1] + "-" + path[:8]
        put("cache", tag, bytes([sel]) + data)
        put("cache", tag + "-sealed", bytes([sel | 0x80]) + data[head:-8])


def config_seeds():
    put("config", "full", json.dumps({
        "address": "127.0.0.1", "port": 8080, "data_dir": "/var/lib/glint", "web_dir": "web",
        "cache_mb": 512, "threads": 2, "work_mb": 2048, "work_slots": 4, "work_wait": 10,
        "timeout": 30, "max_connections": 256, "max-connections-per-ip": 64,
        "max_waiting_per_ip": 256, "health_reserve": 4, "header_timeout": 10,
        "min_body_rate": 1024, "max_body_mb": 32, "max_image_dim": 4096,
        "max_mesh_tris": 2000000, "max_strokes": 1000, "max_stroke_work": 50,
        "api_key": "k", "allow_origin": "https://a.example", "quiet": True}).encode())
    put("config", "strings", b'{"port": "8081", "env_dir": "envs", "measured_dir": "m"}')


def http_seeds():
    put("http_head", "get", b"GET /api/v1/scenes/0123456789abcdef0123456789abcdef?token=x HTTP/1.1"
        b"\r\nHost: 127.0.0.1:8080\r\nAccept: */*\r\n\r\n")
    put("http_head", "put", b"PUT /api/v1/sessions/a/paintings/0 HTTP/1.1\r\nHost: h\r\n"
        b"Content-Type: image/png\r\nContent-Length: 1234\r\nExpect: 100-continue\r\n\r\nbody")
    put("http_head", "chunked", b"POST /api/v1/fits HTTP/1.1\r\nHost: h\r\n"
        b"Transfer-Encoding: chunked\r\n\r\n5\r\nhello\r\n0\r\n\r\n")
    put("http_head", "http10", b"\r\nGET / HTTP/1.0\r\n\r\n")


def main():
    build = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "build")
    glint = os.path.join(build, "core", "glint")
    with tempfile.TemporaryDirectory() as tmp:
        json_seeds()
        image_seeds(glint, tmp)
        stroke_file_seeds()
        mesh_seeds()
        cache_seeds(build, glint, tmp)
        config_seeds()
        http_seeds()


if __name__ == "__main__":
    main()
