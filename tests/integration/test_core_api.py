"""glintd basics over real HTTP: health, metrics, errors, static files."""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(__file__))
from harness import Daemon, run_tests  # noqa: E402


def test_healthz(d):
    r = d.get("/healthz", status=200, schema="Health.json")
    assert r.headers["Content-Type"] == "application/json"


def test_metrics_text(d):
    d.get("/healthz", status=200)
    r = d.get("/metrics", status=200)
    assert r.headers["Content-Type"].startswith("text/plain")
    assert "glintd_requests_total" in r.text
    assert "glintd_request_duration_seconds_bucket" in r.text


def test_unknown_path_is_problem(d):
    r = d.get("/api/v1/does-not-exist", status=404)
    assert r.json()["status"] == 404


def test_wrong_method_is_problem(d):
    r = d.post("/healthz", status=405)
    assert "POST" in r.json()["detail"]


def test_static_files_revalidate(d):
    r = d.get("/", status=200)
    assert r.headers["Content-Type"].startswith("text/html")
    assert r.headers["Cache-Control"] == "no-cache"
    lm = r.headers["Last-Modified"]
    r = d.get("/", status=304, headers={"If-Modified-Since": lm})
    assert r.content == b""
    d.request("HEAD", "/", status=200)


def test_static_traversal_refused(d):
    d.get("/../../etc/passwd", status=404)


def test_static_links_lead_nowhere_outside(d):
    """Symbolic links in the web directory are not followed: a link to
    /etc/passwd, to /etc, a directory link on the way, a link to a file
    inside the tree; nor are FIFOs or directories served.  The web
    directory itself may be a link (the operator chose it)."""
    top = tempfile.mkdtemp(prefix="glint-web-")
    web = os.path.join(top, "web")
    os.makedirs(os.path.join(web, "sub"))
    with open(os.path.join(web, "index.html"), "w") as f:
        f.write("<!doctype html><title>studio</title>")
    with open(os.path.join(web, "sub", "app.js"), "w") as f:
        f.write("export const ok = 1;\n")
    with open(os.path.join(top, "secret.txt"), "w") as f:
        f.write("outside the web directory\n")
    os.symlink("/etc/passwd", os.path.join(web, "link-passwd.txt"))
    os.symlink("/etc", os.path.join(web, "link-etc"))
    os.symlink(top, os.path.join(web, "link-up"))
    os.symlink("../../secret.txt", os.path.join(web, "sub", "secret.txt"))
    os.symlink("sub/app.js", os.path.join(web, "alias.js"))
    os.mkfifo(os.path.join(web, "pipe.txt"))
    os.symlink(web, os.path.join(top, "web-link"))
    w = Daemon("--web-dir", os.path.join(top, "web-link"), "--quiet")
    try:
        assert w.get("/", status=200).text.startswith("<!doctype html>")
        assert w.get("/sub/app.js", status=200).text.startswith("export")
        assert w.get("/sub//app.js", status=200).text.startswith("export")
        for path in ("/link-passwd.txt", "/link-etc/passwd", "/link-etc/hostname",
                     "/link-up/secret.txt", "/sub/secret.txt", "/alias.js", "/pipe.txt",
                     "/sub", "/sub/"):
            r = w.get(path)
            assert r.status_code == 404, "%s: %d %r" % (path, r.status_code, r.text[:80])
            assert "root:" not in r.text and "outside" not in r.text, path
    finally:
        w.stop()


if __name__ == "__main__":
    run_tests(globals())
