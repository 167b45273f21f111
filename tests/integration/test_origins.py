"""Which web pages may call the API, through the real daemon (started with
--allow-origin https://tools.example.com): a page of glintd's own origin
may do anything its tokens allow; a page elsewhere is refused every write
(403 cross-origin, nothing done) and its reads come back without CORS
headers (the browser keeps them from the page); an admitted origin gets
Access-Control-Allow-Origin and its preflights answered; requests with no
Origin (scripts, curl) are unaffected.

The Host rule (DNS rebinding): a page on a name that its DNS points at
127.0.0.1 is, to the browser, its own origin, and its requests carry that
name as Host and Origin alike.  Without an API key glintd answers only IP
addresses, localhost and the names of --allow-host (here
studio.example.test): anything else is refused whatever the method (421
host-not-served, nothing done), health checks aside; with an API key and
no --allow-host every Host is answered."""
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
from harness import Daemon, run_tests  # noqa: E402

API = "/api/v1"
TOOLS = "https://tools.example.com"
OWNER = {"X-Glint-Owner": "origins-owner-0123456789ab"}
SERVED = "studio.example.test"


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


def as_host(d, name):
    """Host and Origin of a page on `name` that resolves to the daemon."""
    host = "%s:%d" % (name, d.port)
    return {"Host": host, "Origin": "http://" + host}


def test_a_rebound_name_is_refused_whatever_the_method(d):
    before = len(scenes(d))
    evil = as_host(d, "attacker.example")
    for method, path, body in (("POST", "/scenes", {"width": 16, "height": 16}),
                               ("GET", "/environments", None),
                               ("GET", "/scenes", None)):
        r = d.request(method, API + path, json=body, headers=dict(OWNER, **evil))
        assert r.status_code == 421 and r.json()["type"].endswith("host-not-served"), r.text[:300]
        assert "attacker.example" in r.json()["detail"] and "--allow-host" in r.json()["detail"]
    print("  %s" % r.json()["detail"])
    assert len(scenes(d)) == before, "nothing was created"
    # what the page could have learned the id of is not deleted either
    sc = d.post(API + "/scenes", status=201, json={"width": 16, "height": 16},
                headers=OWNER).json()
    r = d.delete(API + "/scenes/" + sc["id"], headers=dict(OWNER, **evil))
    assert r.status_code == 421, r.text
    d.get(API + "/scenes/" + sc["id"], status=200)
    # the studio's files are not served under that name, the health checks are
    assert d.get("/", headers={"Host": evil["Host"]}).status_code == 421
    for path in ("/healthz", API + "/healthz"):
        d.get(path, status=200, headers={"Host": evil["Host"]})
    # a Host with no name to rebind, or a malformed one
    for host in ("localhost:%d" % d.port, "LOCALHOST", "127.0.0.1:%d" % d.port, "[::1]:1",
                 "192.0.2.7"):
        d.get(API + "/scenes", status=200, headers=dict(OWNER, Host=host))
    for host in ("localhost.attacker.example", "127.0.0.1.attacker.example", "127.1",
                 "[::1", "localhost:80x", ":80"):
        assert d.get(API + "/scenes", headers=dict(OWNER, Host=host)).status_code == 421, host


def test_the_studio_on_its_own_names_works(d):
    """The studio served by glintd on localhost, 127.0.0.1 or a name given
    with --allow-host: its files, and its writes from its own origin."""
    for name in ("localhost", "127.0.0.1", SERVED, SERVED.upper()):
        page = as_host(d, name)
        assert d.get("/", headers={"Host": page["Host"]}).status_code == 200, name
        d.post(API + "/scenes", status=201, json={"width": 16, "height": 16},
               headers=dict(OWNER, **page))
    # a served Host does not make another origin's page one of glintd's own
    r = d.post(API + "/scenes", json={"width": 16, "height": 16},
               headers=dict(OWNER, Host="%s:%d" % (SERVED, d.port), Origin="http://evil.example"))
    assert r.status_code == 403 and r.json()["type"].endswith("cross-origin"), r.text


def test_with_an_api_key_any_host_is_answered(d):
    k = Daemon("--api-key", "origins-api-key-0123", "--quiet")
    try:
        key = {"X-Api-Key": "origins-api-key-0123"}
        evil = as_host(k, "attacker.example")
        k.post(API + "/scenes", status=201, json={"width": 16, "height": 16},
               headers=dict(key, **evil))
        r = k.post(API + "/scenes", json={"width": 16, "height": 16}, headers=evil)
        assert r.status_code == 401, r.text    # the key is what guards it
    finally:
        k.stop()


run_tests(globals(), daemon_args=("--allow-origin", TOOLS + ", https://other.example.com",
                                  "--allow-host", SERVED))
