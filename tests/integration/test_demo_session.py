"""The daemon's demo session (glintd --demo-session FILE, GET /api/v1/demo),
through the real daemon: none without the option or before the file is
written (204); the session named by the file with its current paint token
once it is (as setup.sh's main job writes it, after the start); a bad file
(not JSON, not an object, no id, too large, a directory) answered with a
clear 500 that names the problem and hides the path, the daemon serving on;
a session of another data directory 404; replaced tokens followed; expired
links 403; an option value too long refused at the start."""
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(__file__))
from harness import GLINTD, SRC, Daemon, run_tests  # noqa: E402

API = "/api/v1"
OWNER = {"X-Glint-Owner": "demo-session-owner-0123456789"}


def problem(r, status, kind):
    assert r.status_code == status, "status %d, want %d: %s" % (r.status_code, status, r.text[:300])
    assert r.json()["type"].endswith("/" + kind), r.json()
    return r.json()


def write(path, text):
    """Whole or not at all, as setup.sh writes it."""
    with open(path + ".tmp", "w") as f:
        f.write(text)
    os.replace(path + ".tmp", path)


def new_session(d, **extra):
    sc = d.post(API + "/scenes", status=201, schema="Scene.json", headers=OWNER,
                json={"mesh": "sphere", "width": 32, "height": 32}).json()
    return d.post(API + "/sessions", status=201, schema="Session.json",
                  json=dict({"scene_id": sc["id"]}, **extra))


def demo_daemon():
    """A daemon given --demo-session with a file not written yet."""
    path = os.path.join(tempfile.mkdtemp(), "demo-session.json")
    return Daemon("--demo-session", path), path


def test_no_option_no_demo(d):
    r = d.get(API + "/demo", status=204)
    assert r.content == b"", r.content


def test_the_file_written_after_the_start_names_the_demo(d):
    dd, path = demo_daemon()
    try:
        assert "no %s yet" % path in open(os.path.join(dd.tmp, "glintd.log")).read()
        dd.get(API + "/demo", status=204)
        created = new_session(dd)
        write(path, created.text)
        r = dd.get(API + "/demo", status=200, schema="Session.json")
        s, c = r.json(), created.json()
        assert r.headers.get("Cache-Control") == "no-store", r.headers
        assert s["id"] == c["id"] and s["access"] == "paint", s
        assert s["paint_token"] == c["paint_token"], (s, c)
        assert s["links"]["paint"] == "/#/session/%s?token=%s" % (c["id"], c["paint_token"]), s
        # the token answered opens the session for painting
        got = dd.get("%s/sessions/%s" % (API, s["id"]), status=200,
                     headers={"X-Glint-Token": s["paint_token"]}).json()
        assert got["access"] == "paint", got
        # replaced tokens: the store's current ones, not the file's
        n = dd.post("%s/sessions/%s/tokens" % (API, s["id"]), status=200, json={},
                    headers={"X-Glint-Token": s["paint_token"]}).json()
        assert n["paint_token"] != c["paint_token"]
        assert dd.get(API + "/demo", status=200).json()["paint_token"] == n["paint_token"]
        # a session of another data directory
        other = dict(c, id="0123456789abcdef0123456789abcdef")
        write(path, json.dumps(other))
        p = problem(dd.get(API + "/demo"), 404, "not-found")
        assert other["id"] in p["detail"], p
    finally:
        dd.stop()


def test_a_bad_file_is_a_clear_error_and_the_daemon_serves_on(d):
    dd, path = demo_daemon()
    bad = [
        ("garbage", "line 1"),
        ("[1, 2]", "expected a session"),
        ('{"scene_id": "0123456789abcdef0123456789abcdef"}', "expected a session"),
        ('{"id": "ABC"}', "expected a session"),
        ('{"id": 12}', "expected a session"),
        ('{"id": "0123456789abcdef0123456789abcdef", "id": "x"}', "duplicate"),
        ('{"id": "%s"}' % ("0" * 70000), "larger than"),
    ]
    try:
        for text, says in bad:
            write(path, text)
            p = problem(dd.get(API + "/demo"), 500, "demo-file-invalid")
            assert says in p["detail"], (text[:40], p)
            assert os.path.dirname(path) not in p["detail"], p  # a private path
            dd.get("/healthz", status=200)
        os.unlink(path)
        os.mkdir(path)
        p = problem(dd.get(API + "/demo"), 500, "demo-file-invalid")
        print("  a directory: %s" % p["detail"])
        dd.get("/healthz", status=200)
    finally:
        dd.stop()
    log = open(os.path.join(dd.tmp, "glintd.log")).read()
    assert "the demo session file %s: line 1" % path in log, "the operator's log names the file"


def test_a_bad_file_at_the_start_is_a_warning(d):
    path = os.path.join(tempfile.mkdtemp(), "demo-session.json")
    write(path, "{")
    dd = Daemon("--demo-session", path)
    try:
        dd.get("/healthz", status=200)
        assert "warning: --demo-session: the demo session file" in \
            open(os.path.join(dd.tmp, "glintd.log")).read()
        problem(dd.get(API + "/demo"), 500, "demo-file-invalid")
    finally:
        dd.stop()


def test_expired_links_are_refused(d):
    dd, path = demo_daemon()
    try:
        write(path, new_session(dd, expires_in=1).text)
        deadline = time.time() + 60  # only catches links that never expire
        while dd.get(API + "/demo").status_code == 200 and time.time() < deadline:
            time.sleep(0.1)
        problem(dd.get(API + "/demo"), 403, "link-expired")
    finally:
        dd.stop()


def test_an_option_too_long_is_refused_at_the_start(d):
    r = subprocess.run([GLINTD, "--port", "0", "--web-dir", os.path.join(SRC, "web"),
                        "--data-dir", tempfile.mkdtemp(), "--demo-session", "x" * 5000],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert "--demo-session is too long" in r.stderr, r.stderr


run_tests(globals())
