"""Painting above the fit's raster (a scene's paint_scale), through the real
daemon: the scene document gives the painting's size; base renders come at
it (or at the raster with size=raster); strokes work in its pixels; uploads
of either size are accepted and any other refused naming both; a fit of a
painting at 2x is the fit of that painting read at the raster's pixel
centres (the mean of the 2 x 2 pixels around each, img_to_raster) to the
last bit; erasing a painting uploaded at the raster uses the raster's base;
and creation refuses scales out of range."""
import json
import os
import struct
import sys

sys.path.insert(0, os.path.dirname(__file__))
from harness import fit_material, png_size, run_tests  # noqa: E402
from test_sessions import exr_encode, png_decode  # noqa: E402

W = 32
CT = "ct:kd=0.4/0.3/0.2,f0=0.2,rough=0.3"
S = {}


def tok(t):
    return {"X-Glint-Token": t}


def session(d):
    s = d.post("/api/v1/sessions", json={"scene_id": S["scene"]["id"]}, status=201).json()
    return s


def put(d, s, k, body, status=200):
    return d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
                 headers=dict(tok(s["paint_token"]), **{"Content-Type": "image/x-exr"}),
                 data=body, status=status)


def fit(d, s):
    mid = fit_material(d, s, {"method": "hf3", "params": {"res": 16}})
    return d.get("/api/v1/materials/" + mid, headers=tok(s["view_token"]), status=200).json()


def test_01_the_scene_gives_the_paintings_size(d):
    sc = d.post("/api/v1/scenes", json={"width": W, "height": W, "paint_scale": 2},
                status=201).json()
    S["scene"] = sc
    assert (sc["paint_scale"], sc["paint_width"], sc["paint_height"]) == (2, 2 * W, 2 * W), sc
    base = "/api/v1/scenes/%s/views/0/base.png" % sc["id"]
    assert png_size(d.get(base, status=200).content) == (2 * W, 2 * W)
    assert png_size(d.get(base + "?size=paint", status=200).content) == (2 * W, 2 * W)
    assert png_size(d.get(base + "?size=raster", status=200).content) == (W, W)
    assert png_size(d.get(base + "?brdf=" + CT, status=200).content) == (2 * W, 2 * W)
    assert png_size(d.get(base + "?brdf=%s&size=raster" % CT, status=200).content) == (W, W)
    d.get(base + "?size=huge", status=422)
    # a scene made before paint_scale, or without it: the raster
    plain = d.post("/api/v1/scenes", json={"width": W, "height": W}, status=201).json()
    assert (plain["paint_scale"], plain["paint_width"]) == (1, W)
    assert png_size(d.get("/api/v1/scenes/%s/views/0/base.png" % plain["id"],
                          status=200).content) == (W, W)


def test_02_creation_refuses_scales_out_of_range(d):
    for bad in (0, 5, "2", 1.5, None):
        r = d.post("/api/v1/scenes", json={"width": W, "height": W, "paint_scale": bad},
                   status=422)
        assert "paint_scale" in r.json()["detail"], r.text
    r = d.post("/api/v1/scenes", json={"width": 2048, "height": 64, "paint_scale": 4}, status=422)
    assert "8192x256" in r.json()["detail"] and "max_image_dim" in r.json()["detail"], r.text


def test_03_strokes_work_in_the_paintings_pixels(d):
    s = session(d)
    S["strokes_session"] = s
    path = "/api/v1/sessions/%s/views/0" % s["id"]
    # an unpainted view reads as the base at the painting's size
    assert png_size(d.get(path + "/painting", headers=tok(s["view_token"]),
                          status=200).content) == (2 * W, 2 * W)
    # a dab at (50.5, 10.5): beyond the raster's 32 pixels, inside the painting's 64
    stroke = {"mode": "paint", "color": [1.0, 0.0, 1.0], "diameter": 2.5, "kappa": 0.0,
              "opacity": 1.0, "points": [[50.5, 10.5]]}
    d.post(path + "/strokes", headers=dict(tok(s["paint_token"]), **{"Content-Type": "application/json"}),
           data=json.dumps({"strokes": [stroke]}), status=200)
    w, h, rows = png_decode(d.get(path + "/painting", headers=tok(s["view_token"]),
                                  status=200).content)
    assert (w, h) == (2 * W, 2 * W)
    assert rows[10][50] == [255, 0, 255], rows[10][50]
    assert rows[10][53] != [255, 0, 255] and rows[13][50] != [255, 0, 255]


def test_04_a_painting_at_2x_fits_as_its_raster_reading(d):
    sc = S["scene"]
    a, b = session(d), session(d)
    # a painting with detail inside each raster pixel: a smooth field plus a
    # checker of the painting's pixels
    def hi(x, y):
        base = 0.02 + 0.3 * (x + 0.5) / (2 * W) + 0.2 * (y + 0.5) / (2 * W)
        e = 0.05 if (x + y) % 2 else -0.03
        return (base + e, 0.7 * base + 0.5 * e, 0.4 * base - 0.2 * e)

    def f32(v):
        return struct.unpack("<f", struct.pack("<f", v))[0]

    def lo(x, y):  # the mean of the 2 x 2 painting pixels around the raster pixel's centre
        px = [[f32(c) for c in hi(2 * x + dx, 2 * y + dy)] for dy in (0, 1) for dx in (0, 1)]
        return tuple(0.25 * sum(p[c] for p in px) for c in range(3))

    for k in range(len(sc["views"])):
        put(d, a, k, exr_encode(2 * W, 2 * W, hi))
        put(d, b, k, exr_encode(W, W, lo))
    # any other size is refused, naming both
    r = put(d, a, 0, exr_encode(48, 48, hi), status=422)
    detail = r.json()["detail"]
    assert "48x48" in detail and "64x64" in detail and "32x32" in detail, detail
    ma, mb = fit(d, a), fit(d, b)
    ea, eb = ma["errors"]["rms_painted"], mb["errors"]["rms_painted"]
    print("rms painted: 2x painting %.12g, its raster reading %.12g" % (ea, eb))
    assert ea == eb, (ea, eb)
    pa = d.post("/api/v1/materials/%s/eval" % ma["id"], headers=tok(a["view_token"]),
                json={"pairs": [{"n": [0, 0, 1], "wi": [0.3, 0.1, 0.95], "wo": [-0.2, 0.4, 0.9]}]},
                status=200).json()
    pb = d.post("/api/v1/materials/%s/eval" % mb["id"], headers=tok(b["view_token"]),
                json={"pairs": [{"n": [0, 0, 1], "wi": [0.3, 0.1, 0.95], "wo": [-0.2, 0.4, 0.9]}]},
                status=200).json()
    assert pa["values"] == pb["values"], (pa, pb)
    S["raster_session"] = b


def test_05_erasing_a_raster_sized_painting(d):
    b = S["raster_session"]
    path = "/api/v1/sessions/%s/views/1" % b["id"]
    erase = {"mode": "erase", "diameter": 6, "kappa": 0.0, "opacity": 1.0,
             "points": [[16.5, 16.5], [20.5, 16.5]]}
    d.post(path + "/strokes", headers=dict(tok(b["paint_token"]), **{"Content-Type": "application/json"}),
           data=json.dumps({"strokes": [erase]}), status=200)
    w, h, rows = png_decode(d.get(path + "/painting", headers=tok(b["view_token"]),
                                  status=200).content)
    assert (w, h) == (W, W)
    base = png_decode(d.get("/api/v1/scenes/%s/views/1/base.png?size=raster" % S["scene"]["id"],
                            status=200).content)[2]
    assert rows[16][18] == base[16][18], (rows[16][18], base[16][18])


if __name__ == "__main__":
    run_tests(globals())
