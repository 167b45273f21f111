#!/usr/bin/env python3
"""From paintings to a material with glint_client, against a running glintd.

    python3 example.py http://127.0.0.1:8080 [--api-key KEY] [--out DIR]

Creates a scene (the built-in sphere at a small raster) and a painting
session; paints a few views with the daemon's own render of an analytic BRDF
(each view's base render with brdf=..., fetched as float OpenEXR and
uploaded as that view's painting); fits them with method hf3, waiting for
the job when the precomputation is not in memory yet; reads the material's
summary; saves a preview (preview.png) and the material's package
(glint-material-<id8>.tar) in the output directory; and prints a short
report. Exits with status 1 on any failure.
"""
import argparse
import os
import sys
import tarfile
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from glint_client import GlintClient, GlintError  # noqa: E402

DEFAULT_BRDF = "ct:rough=0.3,kd=0.5/0.35/0.2,f0=0.04"


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("url", help="glintd's base URL, e.g. http://127.0.0.1:8080")
    ap.add_argument("--api-key", help="the daemon's API key (glintd --api-key)")
    ap.add_argument("--out", help="directory for preview.png and the package "
                                  "(default: a new temporary directory)")
    ap.add_argument("--brdf", default=DEFAULT_BRDF,
                    help="the BRDF the views are painted with (default %(default)s)")
    ap.add_argument("--views", default="0,4,7",
                    help="comma-separated views to paint (default %(default)s)")
    ap.add_argument("--size", type=int, default=64, help="raster side (default %(default)s)")
    ap.add_argument("--res", type=int, default=32,
                    help="hf3 texels per factor (default %(default)s)")
    args = ap.parse_args(argv)
    try:
        args.views = [int(v) for v in args.views.split(",")]
    except ValueError:
        ap.error("--views must be comma-separated view indices")
    return args


def run(args):
    c = GlintClient(args.url, api_key=args.api_key)
    out = args.out or tempfile.mkdtemp(prefix="glint-example-")
    os.makedirs(out, exist_ok=True)
    t0 = time.monotonic()

    health = c.health()
    print("glintd   %s, up %d s" % (args.url, health["uptime_s"]))

    scene = c.create_scene(mesh="sphere", width=args.size, height=args.size)
    if max(args.views) >= len(scene["views"]):
        raise SystemExit("the scene has views 0..%d only" % (len(scene["views"]) - 1))
    print("scene    %s (%s, %dx%d, %d views)" % (scene["id"], scene["mesh"], scene["width"],
                                                   scene["height"], len(scene["views"])))
    session = c.create_session(scene["id"])
    c.token = session["paint_token"]  # every session call below uses it
    print("session  %s" % session["id"])

    for k in args.views:
        image = c.base_render(scene["id"], k, format="exr", brdf=args.brdf)
        v = c.put_painting(session["id"], k, image, content_type="image/x-exr")
        print("painted  view %d with %s (version %d, %d bytes of EXR)" % (
            k, args.brdf, v["version"], len(image)))

    r = c.fit(session["id"], "hf3", {"res": args.res})
    if "job" in r:
        job = r["job"]
        print("fit      job %s (precomputation not in memory): waiting" % job["id"])
        job = c.wait_job(job["id"], timeout=600)
        print("job      %s: %s in %.2f s" % (job["id"], job["state"], job.get("seconds", 0)))
        material = c.get_material(job["material_id"])
    else:
        material = r
        print("fit      at once (precomputation in memory)")
    print("material %s: method %s, res %d, views %s, rms on the painted pixels %.4f" % (
        material["id"], material["method"], material["params"]["res"],
        material["views_used"], material["errors"]["rms_painted"]))

    s = c.summary(material["id"])
    h = s["highlight"]
    width = "none" if h["half_width_deg"] is None else "%.1f deg" % h["half_width_deg"]
    print("summary  base colour %s, highlight strength %.2f, half width %s" % (
        "/".join("%.3f" % x for x in s["base_colour"]), h["strength"], width))
    print("         albedo %s" % ", ".join(
        "%g deg: %.3f" % (a["theta_deg"], sum(a["rgb"]) / 3) for a in s["albedo"]))

    preview = c.preview(material["id"], view=args.views[0], size=128)
    preview_path = preview.save(os.path.join(out, "preview.png"))
    package = c.package(material["id"])
    tar_path = package.save(os.path.join(out, "glint-material-%s.tar" % material["id"][:8]))
    with tarfile.open(tar_path) as tf:
        names = tf.getnames()
    if not any(n.endswith("/material.json") for n in names):
        raise RuntimeError("the package has no material.json: %s" % names)
    print("saved    %s (%d bytes, renderer %s)" % (preview_path, len(preview),
                                                    preview.header("X-Glint-Renderer", "?")))
    print("saved    %s (%d files)" % (tar_path, len(names)))
    link = session["links"].get("paint")
    if link:
        print("studio   %s%s" % (args.url.rstrip("/"), link))
    print("done     in %.1f s" % (time.monotonic() - t0))


def main(argv=None):
    args = parse_args(argv)
    try:
        run(args)
    except GlintError as e:
        print("example.py: %s" % e, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
