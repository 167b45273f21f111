"""A session's share links over time, through the real daemon: links that
expire (refused after, renewed by the scene's owner key), tokens revoked
and replaced (the old ones refused, an open event stream of an old token
ended, the new ones working), who may do it, what is refused, and the
revocation surviving a restart (it is stored before the answer).

Event streams last as long as the token they were opened with: one whose
links expire ends, one whose token is replaced ends and carries nothing
posted after, one whose token is kept (the other link replaced) goes on.
Streams end by themselves: the tests wait for that with generous timeouts
that only catch a stream that never ends."""
import os
import sys
import threading
import time

import requests

sys.path.insert(0, os.path.dirname(__file__))
from harness import run_tests  # noqa: E402
from test_sessions_live import SSE  # noqa: E402

API = "/api/v1"
OWNER = {"X-Glint-Owner": "share-links-owner-0123456789"}


def problem(r, status, kind):
    assert r.status_code == status, "status %d, want %d: %s" % (r.status_code, status, r.text[:300])
    assert r.json()["type"].endswith(kind), r.json()
    return r.json()


def new_session(d, **extra):
    sc = d.post(API + "/scenes", status=201, schema="Scene.json", headers=OWNER,
                json={"width": 32, "height": 32}).json()
    body = dict({"scene_id": sc["id"]}, **extra)
    return d.post(API + "/sessions", status=201, schema="Session.json", json=body).json()


def get(d, s, token):
    return d.get("%s/sessions/%s" % (API, s["id"]), headers={"X-Glint-Token": token})


def tokens(d, s, headers, status=200, **body):
    return d.post("%s/sessions/%s/tokens" % (API, s["id"]), status=status, headers=headers,
                  json=body, schema="Session.json" if status == 200 else None)


def test_links_expire_and_the_owner_renews_them(d):
    s = new_session(d, expires_in=3)
    assert "expires" in s, s
    get(d, s, s["paint_token"]).raise_for_status()
    get(d, s, s["view_token"]).raise_for_status()
    # until the link has expired (the wait only catches one that never does)
    deadline = time.time() + 60
    while get(d, s, s["view_token"]).status_code == 200 and time.time() < deadline:
        time.sleep(0.1)
    for t in (s["paint_token"], s["view_token"]):
        p = problem(get(d, s, t), 403, "link-expired")
    print("  expired: %s" % p["detail"])
    # the paint token cannot renew its own expired link; the scene's owner can
    problem(d.post("%s/sessions/%s/tokens" % (API, s["id"]),
                   headers={"X-Glint-Token": s["paint_token"]}, json={"expires_in": None}),
            403, "link-expired")
    n = tokens(d, s, OWNER, expires_in=None).json()
    assert "expires" not in n and n["paint_token"] != s["paint_token"]
    get(d, n, n["paint_token"]).raise_for_status()
    problem(get(d, n, s["paint_token"]), 403, "wrong-token")


def test_revoked_tokens_are_refused_and_their_streams_end(d):
    s = new_session(d)
    url = "%s%s/sessions/%s/events?token=%s" % (d.base, API, s["id"], s["view_token"])
    r = requests.get(url, stream=True, timeout=(5, 30))
    assert r.status_code == 200
    ended = threading.Event()

    def read():
        try:
            for _ in r.iter_lines(chunk_size=1):
                pass
        except Exception:
            pass
        ended.set()

    threading.Thread(target=read, daemon=True).start()
    time.sleep(0.3)
    assert not ended.is_set()
    n = tokens(d, s, {"X-Glint-Token": s["paint_token"]}).json()
    assert ended.wait(60), "the old token's event stream did not end"
    for t in (s["paint_token"], s["view_token"]):
        problem(get(d, s, t), 403, "wrong-token")
    assert get(d, n, n["paint_token"]).json()["access"] == "paint"
    assert get(d, n, n["view_token"]).json()["access"] == "view"
    assert n["links"]["paint"].endswith(n["paint_token"])
    # revoking the view link only keeps the paint token
    m = tokens(d, n, {"X-Glint-Token": n["paint_token"]}, revoke="view").json()
    assert m["paint_token"] == n["paint_token"] and m["view_token"] != n["view_token"]
    problem(get(d, n, n["view_token"]), 403, "wrong-token")


def stream(d, s, token):
    sse = SSE("%s%s/sessions/%s/events?token=%s" % (d.base, API, s["id"], token))
    assert sse.status == 200, sse.status
    sse.until(lambda e: e[1] == "presence")
    return sse


def drain(sse, timeout=30):
    """The events a stream carries until it ends (None if it did not end
    within `timeout`, which only a stream that never ends reaches)."""
    got, end = [], time.time() + timeout
    while time.time() < end:
        try:
            e = sse.next(timeout=max(0.01, end - time.time()))
        except Exception:
            break
        if e is None:
            return got
        got.append(e)
    sse.close()
    return None


def stroke(x):
    return {"color": [1, 0, 0], "diameter": 3, "points": [[x, 5]], "tag": "after-%d" % x}


def test_a_stream_ends_when_its_links_expire(d):
    s = new_session(d, expires_in=2)
    sse = stream(d, s, s["view_token"])
    assert drain(sse) is not None, "the stream of an expired link was still open 30 s later"
    problem(get(d, s, s["view_token"]), 403, "link-expired")
    # links renewed by the owner: a stream of the new token goes on
    n = tokens(d, s, OWNER, expires_in=None).json()
    sse = stream(d, n, n["view_token"])
    d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), status=200,
           headers={"X-Glint-Token": n["paint_token"]}, json={"strokes": [stroke(1)]})
    assert sse.until(lambda e: e[1] == "stroke")[2]["data"]["tag"] == "after-1"
    sse.close()


def test_a_replaced_token_ends_its_streams_and_they_carry_nothing_after(d):
    s = new_session(d)
    paint, view = stream(d, s, s["paint_token"]), stream(d, s, s["view_token"])
    # only the paint link is replaced: the view token's stream goes on
    n = tokens(d, s, {"X-Glint-Token": s["paint_token"]}, revoke="paint").json()
    assert n["view_token"] == s["view_token"]
    d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), status=200,
           headers={"X-Glint-Token": n["paint_token"]}, json={"strokes": [stroke(2)]})
    after = drain(paint)
    assert after is not None, "the replaced paint token's stream was still open 30 s later"
    assert not [e for e in after if e[1] == "stroke"], after
    assert view.until(lambda e: e[1] == "stroke")[2]["data"]["tag"] == "after-2"
    # now the view link too: its stream ends, and the stroke after is not on it
    tokens(d, n, {"X-Glint-Token": n["paint_token"]}, revoke="view")
    d.post("%s/sessions/%s/views/0/strokes" % (API, s["id"]), status=200,
           headers={"X-Glint-Token": n["paint_token"]}, json={"strokes": [stroke(3)]})
    after = drain(view)
    assert after is not None, "the replaced view token's stream was still open 30 s later"
    assert not [e for e in after if e[1] == "stroke"], after


def test_who_may_and_what_is_refused(d):
    s = new_session(d)
    problem(d.post("%s/sessions/%s/tokens" % (API, s["id"]), json={}), 401, "token-required")
    problem(d.post("%s/sessions/%s/tokens" % (API, s["id"]),
                   headers={"X-Glint-Token": s["view_token"]}, json={}), 403, "read-only-token")
    problem(d.post("%s/sessions/%s/tokens" % (API, s["id"]),
                   headers={"X-Glint-Owner": "somebody-else-0123456789"}, json={}),
            403, "not-owner")
    h = {"X-Glint-Token": s["paint_token"]}
    for body, word in (({"revoke": "all"}, "revoke"), ({"expires_in": 0}, "expires_in"),
                       ({"expires_in": 1.5}, "expires_in"), ({"lifetime": 3}, "unknown key")):
        p = problem(d.post("%s/sessions/%s/tokens" % (API, s["id"]), headers=h, json=body),
                    422, "invalid-input")
        assert word in p["detail"], (body, p)
    problem(d.post(API + "/sessions", json={"scene_id": s["scene_id"], "expires_in": -5}),
            422, "invalid-input")
    d.post("%s/sessions/%s/tokens" % (API, "0" * 32), status=404, json={})
    get(d, s, s["paint_token"]).raise_for_status()   # nothing changed


def test_a_revocation_survives_a_restart(d):
    s = new_session(d)
    n = tokens(d, s, {"X-Glint-Token": s["paint_token"]}, expires_in=3600).json()
    d.kill9()
    d.start()
    problem(get(d, s, s["paint_token"]), 403, "wrong-token")
    g = get(d, n, n["paint_token"]).json()
    assert g["expires"] == n["expires"]


run_tests(globals())
