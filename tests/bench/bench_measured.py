#!/usr/bin/env python3
"""How fits of measured materials hold up under new views and new light.

For each measured material (the published sgd fits of the MERL materials
in ../shared/data/measured, painted with `glint paint --brdf sgd:NAME`):
paint the sphere from 12 point-lit views (lights 20..70 degrees from the
eyes), fit it with each method, and render the material where nothing was
painted: the 20 views of the icosahedron's face centres with lights in the
painted range (new views), and the same views with lights at 75..88
degrees (lights beyond the painted range).  The error of a material on a
set of views is the relative RMS over every covered pixel,
|render - truth| / |truth|.  Printed: per method, median, 90th percentile
and the worst materials, with the median fit time (wall clock of the
command, warm precomputation).

usage: bench_measured.py GLINT [--size N] [--every K | --materials a,b]
       [--methods a,b:param=value,c] [--data ../shared/data/measured]
(every K-th material of the 56; default 4: 14 materials; or those named).
A method that chooses prints what it chose.  The method `abc` fits
nothing: it is the other published fit of the same measurements (`glint
paint --brdf abc:NAME`) scored against the sgd truths, how far apart two
fits of one material are under this protocol.  GLINT is copied first, so a
rebuild while it runs does not stop it.  The radiance is
scene.h's: a point light of intensity 1 makes a white Lambertian read 1."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np
import OpenImageIO as oiio


def run(args):
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError("%s: %s" % (" ".join(args), r.stderr.strip()[-400:]))
    return r.stdout


def pixels(path):
    inp = oiio.ImageInput.open(path)
    px = np.asarray(inp.read_image("float"))[..., :3].astype(np.float64)
    inp.close()
    return px


def shown(m):
    """METHOD[:param=value...] as printed: a list of names (A+B+...) as its
    count, so that a run's lines stay one per material."""
    meth, *kv = m.split(":")
    return ":".join([meth] + [k.split("=", 1)[0] + "=<%d names>" % (k.count("+") + 1)
                              if "+" in k else k for k in kv])


def image_error(dir_a, truth_dir, n):
    """The relative RMS of the images of dir_a against truth_dir's."""
    num = den = 0.0
    for k in range(n):
        t = pixels(os.path.join(truth_dir, "view_%02d.exr" % k))
        r = pixels(os.path.join(dir_a, "view_%02d.exr" % k))
        num += float(((r - t) ** 2).sum())
        den += float((t ** 2).sum())
    return (num / den) ** 0.5 if den > 0 else float("nan")


def error(glint, mat, scene, truth_dir, n, tmp):
    num = den = 0.0
    for k in range(n):
        out = os.path.join(tmp, "r.exr")
        run([glint, "render", mat, "--scene", scene, "--view", str(k), "--engine", "cpu",
             "-o", out])
        t = pixels(os.path.join(truth_dir, "view_%02d.exr" % k))
        r = pixels(out)
        num += float(((r - t) ** 2).sum())
        den += float((t ** 2).sum())
    return (num / den) ** 0.5 if den > 0 else float("nan")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("glint")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--every", type=int, default=4)
    ap.add_argument("--materials", default="")
    ap.add_argument("--methods", default="hf3,pbr,pbr_detail,auto")
    ap.add_argument("--data", default=os.path.join(os.path.dirname(__file__), "..", "..", "..",
                                                   "shared", "data", "measured"))
    a = ap.parse_args()
    fits = os.path.join(a.data, "merl56_fits.json")
    if not os.path.exists(fits):
        print("no %s: nothing to measure" % fits)
        return 0
    names = [m["name"] for m in json.load(open(fits))["materials"]][::a.every]
    if a.materials:
        names = a.materials.split(",")
    methods = a.methods.split(",")
    env = dict(os.environ, GLINT_MEASURED_DIR=os.path.abspath(a.data))
    os.environ.update(env)
    res = {m: [] for m in methods}
    with tempfile.TemporaryDirectory() as tmp:
        shutil.copy(a.glint, os.path.join(tmp, "glint"))
        a.glint = os.path.join(tmp, "glint")
        sc = {k: os.path.join(tmp, k + ".json") for k in ("painted", "new", "beyond")}
        size = ["--size", str(a.size)]
        run([a.glint, "scene", "create", "--mesh", "sphere"] + size + ["-o", sc["painted"]])
        run([a.glint, "scene", "create", "--mesh", "sphere", "--views", "ico20",
             "--light-angles", "20:70:mid"] + size + ["-o", sc["new"]])
        run([a.glint, "scene", "create", "--mesh", "sphere", "--views", "ico20",
             "--light-angles", "75:88:mid"] + size + ["-o", sc["beyond"]])
        cache = os.path.join(tmp, "cache")
        for name in names:
            spec = "sgd:" + name
            dirs = {}
            for k, s in sc.items():
                dirs[k] = os.path.join(tmp, "t_" + k)
                run([a.glint, "paint", s, "--brdf", spec, "-o", dirs[k]])
            for m in methods:
                # METHOD[:param=value...]: a method at other settings than its defaults
                meth, *kv = m.split(":")
                extra = [x for p in kv for x in ("--" + p.split("=", 1)[0], p.split("=", 1)[1])]
                mat = os.path.join(tmp, "m_" + str(methods.index(m)))
                if meth == "abc":  # no fit: the other published fit against sgd
                    e = []
                    for k, n in (("painted", 12), ("new", 20), ("beyond", 20)):
                        other = os.path.join(tmp, "abc_" + k)
                        run([a.glint, "paint", sc[k], "--brdf", "abc:" + name, "-o", other])
                        e.append(image_error(other, dirs[k], n))
                    res[m].append((name, e[0], e[1], e[2], 0.0))
                    print("%-26s %-10s painted %6.2f%%  new views %6.2f%%  beyond %6.2f%%"
                          % (name, shown(m), 100 * e[0], 100 * e[1], 100 * e[2]), flush=True)
                    continue
                t0 = time.perf_counter()
                try:
                    run([a.glint, "fit", sc["painted"], "--paintings", dirs["painted"], "-o", mat,
                         "--method", meth, "--cache-dir", cache] + extra)
                except RuntimeError as e:
                    print("%-26s %-6s fit failed: %s" % (name, shown(m), e), flush=True)
                    continue
                secs = time.perf_counter() - t0
                e_p = error(a.glint, mat, sc["painted"], dirs["painted"], 12, tmp)
                e_n = error(a.glint, mat, sc["new"], dirs["new"], 20, tmp)
                e_b = error(a.glint, mat, sc["beyond"], dirs["beyond"], 20, tmp)
                res[m].append((name, e_p, e_n, e_b, secs))
                with open(os.path.join(mat, "material.json")) as f:
                    chose = json.load(f)["method"]
                print("%-26s %-10s painted %6.2f%%  new views %6.2f%%  beyond %6.2f%%  %.2f s%s"
                      % (name, shown(m), 100 * e_p, 100 * e_n, 100 * e_b, secs,
                         "" if chose == meth else "  chose " + chose), flush=True)
    print()
    print("| method | materials | painted median | new views median | p90 | beyond median | "
          "p90 | worst (new views) | fit s (median) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for m in methods:
        r = res[m]
        if not r:
            continue
        col = lambda i: np.array([x[i] for x in r])
        worst = sorted(r, key=lambda x: -x[2])[:3]
        print("| %s | %d | %.1f%% | %.1f%% | %.1f%% | %.1f%% | %.1f%% | %s | %.2f |" % (
            shown(m), len(r), 100 * np.median(col(1)), 100 * np.median(col(2)),
            100 * np.percentile(col(2), 90), 100 * np.median(col(3)),
            100 * np.percentile(col(3), 90),
            ", ".join("%s %.0f%%" % (w[0], 100 * w[2]) for w in worst), np.median(col(4))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
