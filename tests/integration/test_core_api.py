"""glintd basics over real HTTP: health, metrics, errors, static files."""
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
from harness import run_tests  # noqa: E402


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


if __name__ == "__main__":
    run_tests(globals())
