"""Which web pages may call the API, through the real daemon (started with
--allow-origin https://tools.example.com): a page of glintd's own origin
may do anything its tokens allow; a page elsewhere is refused every write
(403 cross-origin, nothing done) and its reads come back without CORS
headers (the browser keeps them from the page); an admitted origin gets
Access-Control-Allow-Origin and its preflights answered; requests with no
Origin (scripts, curl) are unaffected."""
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
from harness import run_tests  # noqa: E402

API = "/api/v1"
TOOLS = "https://tools.example.com"
OWNER = {"X-Glint-Owner": "origins-owner-0123456789ab"}


def scenes(d):
    return d.get(API + "/scenes", status=200, headers=OWNER).json()["scenes"]


def test_own_origin_and_scripts_may_write(d):
    r = d.post(API + "/scenes", status=201, json={"width": 16, "height": 16},
               headers=dict(OWNER, Origin=d.base))
    assert "Access-Control-Allow-Origin" not in r.headers
    d.post(API + "/scenes", status=201, json={"width": 16, "height": 16}, headers=OWNER)


def test_another_origin_may_not_write_nor_read_across(d):
    before = len(scenes(d))
    for method, path, body in (("POST", "/scenes", {"width": 16, "height": 16}),
                               ("POST", "/sessions", {"scene_id": "0" * 32}),
                               ("DELETE", "/scenes/" + "0" * 32, None)):
        r = d.request(method, API + path, json=body,
                      headers=dict(OWNER, Origin="https://evil.example"))
        assert r.status_code == 403 and r.json()["type"].endswith("cross-origin"), r.text
    print("  %s" % r.json()["detail"])
    assert len(scenes(d)) == before, "nothing was created"
    r = d.get(API + "/scenes", headers=dict(OWNER, Origin="https://evil.example"))
    assert r.status_code == 200 and "Access-Control-Allow-Origin" not in r.headers
    assert "Origin" in r.headers.get("Vary", "")
    r = d.request("OPTIONS", API + "/scenes",
                  headers={"Origin": "https://evil.example",
                           "Access-Control-Request-Method": "POST"})
    assert r.status_code == 403, r.status_code
    # a page served by some other port of the same host is another origin too
    other = d.base.rsplit(":", 1)[0] + ":1"
    r = d.post(API + "/scenes", json={"width": 16, "height": 16},
               headers=dict(OWNER, Origin=other))
    assert r.status_code == 403


def test_an_admitted_origin_is_answered_with_cors(d):
    r = d.request("OPTIONS", API + "/scenes",
                  headers={"Origin": TOOLS, "Access-Control-Request-Method": "POST",
                           "Access-Control-Request-Headers": "content-type, x-glint-owner"})
    assert r.status_code == 204, r.status_code
    assert r.headers["Access-Control-Allow-Origin"] == TOOLS
    assert "POST" in r.headers["Access-Control-Allow-Methods"]
    assert "X-Glint-Token" in r.headers["Access-Control-Allow-Headers"]
    r = d.post(API + "/scenes", status=201, json={"width": 16, "height": 16},
               headers=dict(OWNER, Origin=TOOLS))
    assert r.headers["Access-Control-Allow-Origin"] == TOOLS
    assert "Location" in r.headers["Access-Control-Expose-Headers"]


run_tests(globals(), daemon_args=("--allow-origin", TOOLS + ", https://other.example.com"))
