"""The methods' parameter tables drive proto/ and the API (core/pipeline/method.h):
the JSON Schema of each method's parameters in proto/schemas is exactly
what `glint methods --schema NAME` generates from the table, FitRequest.json
lists exactly the registered methods, and GET /api/v1/methods describes
them exactly as the table does (`glint methods --json`); the material of each
method lit by lamps, fitted through the API, is what Material.json describes
(glintd offers four measured materials' fits, written here, for the methods
that learn from them)."""
import atexit
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from harness import GLINTD, SRC, fit_material, run_tests  # noqa: E402

CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(GLINTD))), "core", "glint")
SCHEMAS = os.path.join(SRC, "proto", "schemas")

# a fits file of four materials (sgd: a diffuse part and a highlight of
# several widths; abc alike) for tab_prior to learn from
MDIR = tempfile.mkdtemp(prefix="glint-measured-")
atexit.register(shutil.rmtree, MDIR, True)
with open(os.path.join(MDIR, "merl56_fits.json"), "w") as f:
    json.dump({"materials": [
        {"name": "fit-%d" % i,
         "abc": {"kD": [kd] * 3, "A": [1, 1, 1], "B": 10.0, "C": 1.0, "ior": 1.5},
         "sgd": dict({k: [v] * 3 for k, v in (("p", 0.5), ("f0", 0.04), ("f1", 0.0),
                                              ("kap", 0.3), ("lambda", 0.0), ("c", 1.0),
                                              ("k", 1.0), ("theta0", 0.0))},
                     rhoD=[kd, 0.8 * kd, 0.6 * kd], rhoS=[ks] * 3, alpha=[a] * 3)}
        for i, (kd, ks, a) in enumerate(((0.1, 0.5, 0.02), (0.3, 0.2, 0.05),
                                         (0.5, 0.1, 0.1), (0.2, 0.8, 0.03)))]}, f)


_cli_out = {}


def cli_json(*args):
    """The CLI's JSON answer to args (each asked once: the answers depend on
    the binary and the measured fits alone, and each run costs the CLI's
    start).  The CLI is given the daemon's measured fits: what a method
    needs of its host (GET /methods' available) is then the same."""
    if args not in _cli_out:
        env = dict(os.environ, GLINT_MEASURED_DIR=MDIR)
        _cli_out[args] = subprocess.run([CLI] + list(args), check=True, capture_output=True,
                                        text=True, env=env).stdout
    return json.loads(_cli_out[args])


def table():
    return cli_json("methods", "--json")["methods"]


def test_schema_files_are_generated_from_the_tables(d):
    methods = table()
    assert methods and methods[0]["name"] == "hf3"
    for m in methods:
        generated = cli_json("methods", "--schema", m["name"])
        path = os.path.join(SCHEMAS, generated["$id"])
        assert os.path.exists(path), "proto/schemas/%s is missing: run glint methods --schema " \
                                     "%s > %s" % (generated["$id"], m["name"], path)
        with open(path) as f:
            kept = json.load(f)
        assert kept == generated, "proto/schemas/%s differs from the table of %s: regenerate " \
                                  "it with glint methods --schema %s" % (
                                      generated["$id"], m["name"], m["name"])
        # every parameter of the table is in the schema, with its bounds
        props = generated["properties"]
        assert sorted(props) == sorted(p["name"] for p in m["params"])
        for p in m["params"]:
            for bound in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"):
                assert props[p["name"]].get(bound) == p.get(bound), (p["name"], bound)
            if "enum" in p:
                assert props[p["name"]]["enum"] == p["enum"]


def test_fit_request_lists_the_registered_methods(d):
    with open(os.path.join(SCHEMAS, "FitRequest.json")) as f:
        req = json.load(f)
    names = [m["name"] for m in table()]
    assert req["properties"]["method"]["enum"] == names
    refs = {c["if"]["properties"]["method"]["const"]: c["then"]["properties"]["params"]["$ref"]
            for c in req["allOf"]}
    assert refs == {n: cli_json("methods", "--schema", n)["$id"] for n in names}


def test_methods_endpoint_is_the_table(d):
    api = d.get("/api/v1/methods", status=200, schema="Methods.json").json()["methods"]
    assert api == table()
    # defaults are valid values of their own schema
    for m in api:
        generated = cli_json("methods", "--schema", m["name"])
        for p in m["params"]:
            s = generated["properties"][p["name"]]
            v = p["default"]
            if "minimum" in s:
                assert v >= s["minimum"], p
            if "maximum" in s:
                assert v <= s["maximum"], p
            if "exclusiveMaximum" in s:
                assert v < s["exclusiveMaximum"], p
            if "enum" in s:
                assert v in s["enum"], p


def test_methods_say_what_they_are_for(d):
    """What a person and the studio read of every method: a label, a
    one-line summary, when to use it, its lighting and capabilities, and
    each parameter's plain name and group; the studio names no method."""
    api = d.get("/api/v1/methods", status=200, schema="Methods.json").json()["methods"]
    labels = [m["label"] for m in api]
    assert len(set(labels)) == len(labels), labels
    for m in api:
        assert m["label"] != m["name"] and m["summary"] and m["when"], m["name"]
        assert "\n" not in m["summary"] and "\n" not in m["when"], m["name"]
        names = [p["name"] for p in m["params"]]
        # a method lit by an environment names it; a point-light one has no env
        assert (m["lighting"] == "environment") == ("env" in names), m["name"]
        # materials that vary over the surface hold a texture over it
        assert not m["varies"] or m["surface"], m["name"]
        assert any(p["group"] == "basic" for p in m["params"]), m["name"]
        for p in m["params"]:
            assert p["label"] and p["label"] != p["name"], (m["name"], p["name"])
    # what the studio shows of a method is in the artist's words: no
    # method's name (hf3, srbf, ...) in a label, summary or when-to-use
    named = re.compile(r"(?<![A-Za-z0-9_])(%s)(?![A-Za-z0-9_])" % "|".join(re.escape(m["name"]) for m in api))
    for m in api:
        for field in ("label", "summary", "when"):
            assert not named.search(m[field]), (m["name"], field, m[field])
        for p in m["params"]:
            if p["group"] == "basic":
                assert not named.search(p["label"]), (m["name"], p["name"], p["label"])
    by = {m["name"]: m for m in api}
    # one method that chooses for each lighting
    assert [(m["name"], m["lighting"]) for m in api if m["chooses"]] == [
        ("auto", "point"), ("auto_env", "environment")]
    assert by["srbf"]["lighting"] == "environment" and by["srbf"]["shows"] == "lobes"
    assert by["hf3"]["lighting"] == "point" and by["hf3"]["shows"] == "factors"
    assert by["maps"]["surface"] == ["coefficients"] and by["hf4"]["surface"] == ["spatial"]
    assert by["hybrid"]["surface"] == ["coefficients", "spatial"]
    assert by["hf3"]["surface"] == [] and not by["hf3"]["varies"]
    # this daemon has measured fits (--measured-dir): every method can fit here
    assert all(x["available"] and "unavailable" not in x for x in by.values()), \
        [n for n, x in by.items() if not x["available"]]


# small parameters of each method lit by lamps (tests/unit/method_small.h's)
SMALL = {"hf3": {"res": 8}, "pbr": {"starts": 1, "max_iter": 20},
         "pbr_detail": {"res": 8, "starts": 1, "max_iter": 20},
         "tab": {"res_h": 8, "res_d": 4}, "pbr_tab": {"res_h": 8, "res_d": 4, "starts": 1},
         "tab_prior": {"res_h": 8, "res_d": 4, "components": 2},
         "pbr_maps": {"starts": 1, "components": 2, "map_res": 16, "rounds": 2},
         "hf4": {"res": 8, "s_res": 4}, "hf2d": {"res": 8, "res_2d": 8},
         "maps": {"res": 8, "components": 2, "map_res": 16, "rounds": 2},
         "hybrid": {"res": 8, "s_res": 4, "components": 2, "map_res": 16, "rounds": 2}}


def test_every_lamp_lit_methods_material_is_described_by_material_json(d):
    """Each method lit by lamps fitted through the API to one painting: the
    material glintd answers is what Material.json describes (its report's
    precomputation names the cache key, whatever the method's levels)."""
    methods = [m["name"] for m in table() if m["lighting"] == "point" and not m["chooses"]]
    assert sorted(methods) == sorted(SMALL), methods
    sc = d.post("/api/v1/scenes", json={"width": 32, "height": 32}, status=201).json()
    s = d.post("/api/v1/sessions", json={"scene_id": sc["id"]}, status=201).json()
    for k in range(len(sc["views"])):
        img = d.get("/api/v1/scenes/%s/views/%d/base.png?format=exr&scale=1&brdf=%s"
                    % (sc["id"], k, "ct:kd=0.4/0.3/0.2,f0=0.2,rough=0.3"), status=200).content
        d.put("/api/v1/sessions/%s/views/%d/painting" % (s["id"], k),
              headers={"X-Glint-Token": s["paint_token"], "Content-Type": "image/x-exr"},
              data=img, status=200)
    for name in methods:
        mid = fit_material(d, s, {"method": name, "params": SMALL[name]})
        m = d.get("/api/v1/materials/" + mid, headers={"X-Glint-Token": s["view_token"]},
                  status=200, schema="Material.json").json()
        assert m["method"] == name, (name, m["method"])
        print("  %-10s precomputation key %s" % (name, m["precomputation"]["cache_key"][:40]))


run_tests(globals(), daemon_args=("--measured-dir", MDIR))
