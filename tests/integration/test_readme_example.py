"""The README's curl example (tests/integration/readme_example.sh) runs
verbatim against a fresh daemon and leaves valid files behind.  When
docs/api.md holds the script (a ```sh block right after the line
"<!-- tests/integration/readme_example.sh -->"), the block must equal the file,
so the two never drift apart."""
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from harness import GLINTD, SRC, run_tests, validate  # noqa: E402

SCRIPT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "readme_example.sh")
CLI = os.environ.get("GLINT_CLI") or os.path.join(
    os.path.dirname(os.path.dirname(os.path.abspath(GLINTD))), "core", "glint")
MARKER = "<!-- tests/integration/readme_example.sh -->"


def test_readme_matches_the_script(d):
    readme = os.path.join(SRC, "docs", "api.md")
    text = open(readme).read() if os.path.exists(readme) else ""
    if MARKER not in text:
        print("     (README.md has no %s block yet: nothing to compare)" % MARKER)
        return
    m = re.search(re.escape(MARKER) + r"\s*```(?:sh|bash)\n(.*?)```", text, re.S)
    assert m, "the README marker is not followed by a ```sh block"
    assert m.group(1) == open(SCRIPT).read(), "README.md and readme_example.sh differ"


def test_the_script_runs(d):
    for tool in ("bash", "curl", "jq"):
        assert shutil.which(tool), "%s is needed by the README example" % tool
    assert os.access(CLI, os.X_OK), "glint CLI not found at %s (set GLINT_CLI)" % CLI
    out = tempfile.mkdtemp(prefix="glint-readme-")
    env = dict(os.environ, GLINT_URL=d.base, GLINT=CLI, OUT=out)
    p = subprocess.run(["bash", SCRIPT], env=env, capture_output=True, text=True, timeout=300)
    print("\n".join("     | " + line for line in p.stdout.splitlines()))
    assert p.returncode == 0, "exit %d\nstdout:\n%s\nstderr:\n%s" % (p.returncode, p.stdout,
                                                                       p.stderr)
    lines = p.stdout.splitlines()
    assert lines[0].startswith("scene ") and "(12 views)" in lines[0], lines
    assert any(line.startswith("painted  12 views") for line in lines), lines
    # a fresh daemon: the fit is a job that ends done
    assert any(line.startswith("job ") and ": done," in line for line in lines), lines
    m = json.load(open(os.path.join(out, "material.json")))
    validate(m, "Material.json")
    assert m["params"]["res"] == 64 and m["views_used"] == list(range(12))
    assert m["errors"]["rms_painted"] < 0.05
    with open(os.path.join(out, "factors.png"), "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    with open(os.path.join(out, "factors.exr"), "rb") as f:
        assert f.read(4) == b"\x76\x2f\x31\x01"
    with open(os.path.join(out, "preview.png"), "rb") as f:
        head = f.read(24)
        assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[16:24] == bytes.fromhex(
            "0000010000000100"), "preview is not a 256x256 PNG"
    with tarfile.open(os.path.join(out, "material.tar")) as t:
        assert any(n.endswith("/material.json") for n in t.getnames())
    # the material the script fetched is the daemon's
    token = re.search(r"paint token ([0-9a-f]{32})", p.stdout).group(1)
    r = d.get("/api/v1/materials/" + m["id"], headers={"X-Glint-Token": token}, status=200,
              schema="Material.json")
    assert r.json()["id"] == m["id"]
    shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    run_tests(globals())
