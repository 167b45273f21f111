"""Memory outside the work budget: uploads whose header declares more than
their target holds, long stroke histories read at once, and event streams
that never read.

Each memory case runs on a daemon of its own, started with --work-mb 256
--cache-mb 64 as the probe's was, so that its peak resident set (VmHWM in
/proc/PID/status) is that of the case, and asserts the safe answer and

    VmHWM <= work budget + FIXED_MB

where FIXED_MB is docs/security.md's fixed part ("Security and limits", Memory:
about 160 MB of libraries).  The cache budget is left out of the bound:
these scenes are 32 x 32 and keep next to nothing in it.  Under
AddressSanitizer (its shadow and quarantine hold memory glintd freed) the
bound is not asserted, only the answers: the plain build's run asserts it.

An image's size, channels and the memory of its decode are checked from
its header before a pixel is decoded (server/upload_gate.h); a page of the
stroke history holds at most 1 MiB of strokes; a request's parsed JSON is
held against the work budget.
"""
import concurrent.futures as cf
import json
import os
import socket
import sys

sys.path.insert(0, os.path.dirname(__file__))
from harness import Daemon, run_tests, validate  # noqa: E402
from probe_files import exr_declaring, far_stroke, png_declaring  # noqa: E402
from test_sessions import H, W, new_session, post_strokes  # noqa: E402

API = "/api/v1"
WORK_MB = 256
CACHE_MB = 64
FIXED_MB = 160
PAGE_BYTES = 1 << 20


def problem(r, status, kind):
    assert r.status_code == status, "status %d, want %d: %s" % (r.status_code, status, r.text[:400])
    assert r.headers.get("Content-Type", "").startswith("application/problem+json"), r.headers
    body = r.json()
    assert body["type"].endswith(kind), "type %s, want %s" % (body["type"], kind)
    return body


def rss_kb(d, field):
    with open("/proc/%d/status" % d.proc.pid) as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1])
    raise AssertionError("no %s" % field)


class Budgeted:
    """A daemon with the probe's budgets; check_peak() holds its high-water mark
    to the bound."""

    def __init__(self, data_dir=None):
        self.d = Daemon("--work-mb", str(WORK_MB), "--cache-mb", str(CACHE_MB), "--quiet",
                        data_dir=data_dir)
        self.before_kb = rss_kb(self.d, "VmRSS")

    def check_peak(self, what):
        peak = rss_kb(self.d, "VmHWM")
        if self.d.sanitized():
            print("  %s: peak RSS %d MiB, not bounded under the sanitizers (the plain build's "
                  "run bounds it)" % (what, peak >> 10))
            return
        assert peak <= (WORK_MB + FIXED_MB) * 1024, \
            "%s: peak RSS %d MiB, beyond the work budget %d MiB + %d MiB fixed" % (
                what, peak >> 10, WORK_MB, FIXED_MB)
        print("  %s: peak RSS %d MiB (bound %d MiB)" % (what, peak >> 10, WORK_MB + FIXED_MB))


def session(d, size=32):
    sc = d.post(API + "/scenes", status=201, json={"width": size, "height": size}).json()
    s = d.post(API + "/sessions", status=201, json={"scene_id": sc["id"]}).json()
    return sc, s


def tok(s, which="paint_token"):
    return {"X-Glint-Token": s[which]}


# ---- item 1: an upload's header against its target, before decoding -------------------


def test_a_png_declaring_16384_squared_is_refused_from_its_header(_d):
    body = png_declaring(16384, 16384)
    assert len(body) < 1 << 20, len(body)  # under a MiB on the wire: 3 GiB decoded
    b = Budgeted()
    try:
        sc, s = session(b.d)
        url = "%s/sessions/%s/views/0/painting" % (API, s["id"])
        # (the timeouts: where a daemon decodes it first, that takes a while)
        p = problem(b.d.put(url, data=body, headers=tok(s), timeout=300), 413, "image-too-large")
        b.check_peak("PNG of 16384^2 on a 32x32 view")
        assert "16384x16384" in p["detail"] and "max-image-dim" in p["detail"], p
        assert "expects exactly 32x32" in p["detail"], p
        # two at once, as the probe sent them
        with cf.ThreadPoolExecutor(2) as ex:
            rs = list(ex.map(lambda _: b.d.put(url, data=body, headers=tok(s), timeout=300),
                             range(2)))
        for r in rs:
            problem(r, 413, "image-too-large")
        b.check_peak("PNG of 16384^2 on a 32x32 view, two at once")
        # one within --max-image-dim but not the view's size: 422 from the header
        p = problem(b.d.put(url, data=png_declaring(4096, 4096), headers=tok(s)), 422,
                    "wrong-size")
        assert "4096x4096" in p["detail"], p
        b.check_peak("PNG of 4096^2 on a 32x32 view")
        # nothing was kept; the view's own size still goes in
        r = b.d.get(url, status=200, headers=tok(s))
        assert r.headers["X-Glint-Painted"] == "0"
        problem(b.d.put(url, data=png_declaring(32, 64), headers=tok(s)), 422, "wrong-size")
        b.d.put(url, data=png_declaring(32, 32), headers=tok(s), status=200)
    finally:
        b.d.stop()


def test_an_exr_declaring_16384_squared_is_refused_from_its_header(_d):
    body = exr_declaring(16384, 16384, ["R", "G", "B"])
    assert len(body) < 8 << 20, len(body)
    b = Budgeted()
    try:
        sc, s = session(b.d)
        url = "%s/sessions/%s/views/0/painting" % (API, s["id"])
        p = problem(b.d.put(url, data=body, headers=tok(s), timeout=300), 413, "image-too-large")
        b.check_peak("ZIP OpenEXR of 16384^2 on a 32x32 view")
        assert "16384x16384" in p["detail"], p
        # the same through a G-buffer set's painting
        st = b.d.post(API + "/gbuffer-sets", status=201,
                      json={"views": 1, "width": 32, "height": 32}).json()
        p = problem(b.d.put("%s/gbuffer-sets/%s/views/0/painting" % (API, st["id"]), data=body,
                            headers={"X-Glint-Owner": st["owner_key"]},
                            timeout=300), 413, "image-too-large")
        b.check_peak("ZIP OpenEXR of 16384^2 as a G-buffer set's painting")
    finally:
        b.d.stop()


def test_a_32_channel_exr_beyond_the_sets_size_is_refused_from_its_header(_d):
    names = ["c%02d" % i for i in range(32)]
    body = exr_declaring(4096, 4096, names)
    b = Budgeted()
    try:
        st = b.d.post(API + "/gbuffer-sets", status=201,
                      json={"views": 1, "width": 4096, "height": 8}).json()
        url = "%s/gbuffer-sets/%s/views/0/gbuffer.exr" % (API, st["id"])
        owner = {"X-Glint-Owner": st["owner_key"], "Content-Type": "image/x-exr"}
        r = b.d.put(url, data=body, headers=owner, timeout=300)
        assert r.status_code == 422, r.status_code
        b.check_peak("32-channel OpenEXR of 4096^2 into a 4096x8 set")
        p = problem(r, 422, "wrong-size")
        assert "4096x4096" in p["detail"] and "4096x8" in p["detail"], p
        # the set's size with more channels than a G-buffer has: refused too
        more = exr_declaring(4096, 8, ["c%02d" % i for i in range(40)])
        p = problem(b.d.put(url, data=more, headers=owner), 422,
                    "invalid-gbuffer")
        assert "40 channels" in p["detail"], p
    finally:
        b.d.stop()


def test_a_decode_beyond_the_work_budget_is_refused_before_it_starts(_d):
    # a 2048 x 2048 G-buffer set takes 2048^2 paintings; with the budget at
    # 64 MiB a painting's decode bound (6 bytes a sample for an 8-bit PNG, 12
    # a pixel for the RGB copy, 8 MiB: 128 MiB) can never fit: 413 naming
    # the budget.  (A session's scene that large is refused at creation:
    # its base renders need more than its paintings.)
    w = Daemon("--work-mb", "64", "--quiet")
    try:
        st = w.post(API + "/gbuffer-sets", status=201,
                    json={"views": 1, "width": 2048, "height": 2048}).json()
        url = "%s/gbuffer-sets/%s/views/0/painting" % (API, st["id"])
        p = problem(w.put(url, data=png_declaring(2048, 2048),
                          headers={"X-Glint-Owner": st["owner_key"]}), 413, "over-budget")
        assert "--work-mb" in p["detail"] and "64 MiB" in p["detail"], p
        assert "2048x2048" in p["detail"], p
        assert rss_kb(w, "VmHWM") <= (64 + FIXED_MB) * 1024 or w.sanitized()
    finally:
        w.stop()


# ---- item 1: long stroke histories --------------------------------------------------------


def test_a_long_stroke_history_is_read_in_bounded_pages(_d):
    # 60 strokes of 10,000 points: a 13 MB history (the probe's was 1,000
    # strokes; this shows the same and takes seconds to write)
    strokes = 60
    b = Budgeted()
    data_dir = b.d.data_dir
    try:
        sc, s = session(b.d)
        url = "%s/sessions/%s/views/0/strokes" % (API, s["id"])
        text = json.dumps({"strokes": [far_stroke(10000)] * strokes}).encode()
        b.d.post(url, data=text, headers={**tok(s), "Content-Type": "application/json"},
                 status=200, timeout=300)
    finally:
        b.d.stop()
    # a fresh daemon on that data: its high-water mark is the readers'
    b = Budgeted(data_dir=data_dir)
    try:
        view = tok(s, "view_token")
        page = "%s/sessions/%s/strokes?limit=10000" % (API, s["id"])
        b.d.get(page.replace("10000", "1"), status=200, headers=view, schema="StrokeList.json")
        r = b.d.get(page, status=200, headers=view)
        b.check_peak("%d strokes of 10,000 points asked for in one page" % strokes)
        # four readers at once, each asking for the whole history in one page
        with cf.ThreadPoolExecutor(4) as ex:
            rs = list(ex.map(lambda _: b.d.get(page, headers=view), range(4)))
        b.check_peak("the same by four readers at once")
        for x in [r] + rs:
            assert x.status_code == 200 and len(x.content) <= PAGE_BYTES + 4096, (
                x.status_code, len(x.content))
        # a page: at most 1 MiB, never empty, and last_seq the cursor to the
        # next, which follows it without a gap
        got = r.json()
        assert got["more"] is True and 1 <= len(got["strokes"]) < strokes, (
            got["more"], len(got["strokes"]))
        seen = 0
        for _ in range(3):
            for x in got["strokes"]:
                assert x["seq"] == seen + 1, (x["seq"], seen)
                seen = x["seq"]
            assert got["last_seq"] == seen and got["more"] is True
            got = b.d.get(page + "&since=%d" % got["last_seq"], status=200, headers=view).json()
        b.check_peak("the history read page after page")
    finally:
        b.d.stop()


def test_a_stroke_request_holds_its_parsed_size_against_the_budget(_d):
    # a JSON body of small numbers grows about 30 times when parsed: 150
    # strokes of 10,000 points (about 33 MB of text, 4.5 million values)
    # would take the budget's double; refused before parsing, naming it.
    # Half of it (a tree of about 200 MiB) fits and is written.
    b = Budgeted()
    try:
        sc, s = session(b.d)
        url = "%s/sessions/%s/views/0/strokes" % (API, s["id"])
        hdr = {**tok(s), "Content-Type": "application/json"}
        big = json.dumps({"strokes": [far_stroke(10000)] * 150}).encode()
        p = problem(b.d.post(url, data=big, headers=hdr, timeout=300), 413, "over-budget")
        assert "parsing a JSON body" in p["detail"] and "--work-mb" in p["detail"], p
        b.check_peak("a stroke request of %.0f MB whose tree passes the budget" % (len(big) / 1e6))
        half = json.dumps({"strokes": [far_stroke(10000)] * 70}).encode()
        b.d.post(url, data=half, headers=hdr, status=200, timeout=300)
        b.check_peak("a stroke request of %.0f MB within the budget" % (len(half) / 1e6))
    finally:
        b.d.stop()


def vm_hwm_kb(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    raise AssertionError("no VmHWM")


# ---- item 1: event streams that never read --------------------------------------------


def open_stream_raw(d, sess, source):
    """A stream requested from loopback address `source` by a client that
    reads its answer's first line and nothing more."""
    so = socket.socket()
    so.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    so.bind((source, 0))
    so.connect(("127.0.0.1", d.port))
    so.sendall(b"GET %s/sessions/%s/events?token=%s HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
               % (API.encode(), sess["id"].encode(), sess["view_token"].encode()))
    return so


def test_streams_that_never_read_are_bounded(d):
    """240 event streams requested on one session by clients that never
    read (12 loopback addresses, 20 each), then 16 stroke requests of
    320 KB whose events those streams would carry: the daemon's peak
    resident memory grows by less than 128 MB, at most 32 streams are open
    on the session and 16 per client, and the others are refused at once
    (429 too-many-streams, naming the limit, the connection closed)."""
    w = Daemon("--quiet")
    socks = []
    try:
        sc = w.post(API + "/scenes", status=201, json={"width": W, "height": H}).json()
        sess = new_session(w, sc["id"])
        hwm0 = vm_hwm_kb(w.proc.pid)
        status, refusals = [], []
        for i in range(240):  # one after the other: which limit refuses is known
            so = open_stream_raw(w, sess, "127.0.0.%d" % (2 + i // 20))
            socks.append(so)
            so.settimeout(30)
            head = b""
            while b"\r\n" not in head:
                chunk = so.recv(1024)
                if not chunk:
                    break
                head += chunk
            status.append(head.split(b" ")[1] if head.startswith(b"HTTP/1.1 ") else head[:40])
            if status[-1] == b"429":
                while True:                           # the refusal closes the connection
                    chunk = so.recv(65536)
                    if not chunk:
                        break
                    head += chunk
                refusals.append(head.decode("utf-8", "replace"))
        pts = [[0.5 + (k % 30), 0.5 + (k // 30) % 30] for k in range(8000)]
        for _ in range(16):
            post_strokes(w, sess, 0, [{"color": [1, 0, 0], "diameter": 1, "points": pts}] * 3)
        grown = (vm_hwm_kb(w.proc.pid) - hwm0) / 1024.0
        print("  peak resident memory grew by %.0f MB; %d streams open, %d refused" % (
            grown, status.count(b"200"), status.count(b"429")))
        assert grown < 128 or w.sanitized(), "peak resident memory grew by %.0f MB" % grown
        assert status.count(b"200") == 32 and status.count(b"429") == 208, status
        details = []
        for text in refusals:
            body = json.loads(text.split("\r\n\r\n", 1)[1])
            validate(body, "Problem.json")
            assert body["type"].endswith("too-many-streams"), body
            assert "connection: close" in text.lower().split("\r\n\r\n")[0]
            details.append(body["detail"])
        # the first address: 16 streams, then its own limit; the second
        # fills the session's; every later one meets the session's
        assert all("--max-streams-per-client 16" in x for x in details[:4]), details[:5]
        assert all("--max-streams-per-session 32" in x for x in details[4:]), details[4:6]
        print("  %s\n  %s" % (details[0], details[-1]))
    finally:
        for so in socks:
            so.close()
        w.stop()


if __name__ == "__main__":
    run_tests(globals(), daemon_args=("--quiet",))
