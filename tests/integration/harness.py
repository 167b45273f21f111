"""Test harness for glintd integration tests: starts the real daemon on an
ephemeral loopback port with a fresh data directory, talks HTTP to it, and
validates every JSON body against the schemas in proto/schemas.

usage in a test file:
    from harness import Daemon, run_tests
    def test_x(d): d.get("/healthz", schema="Health.json")
    run_tests(globals())
"""
import json
import os
import shutil
import signal
import subprocess
import struct
import sys
import tempfile
import time
import traceback
import zlib

import jsonschema
import requests

# Every temporary directory of a run (the Daemons', and those the tests make
# through tempfile) lies under one, removed with the Daemons' when every test
# passed (remove_dirs).
RUN_TMP = tempfile.mkdtemp(prefix="glint-itest-")
os.chmod(RUN_TMP, 0o755)  # a test runs glintd as another user from a directory in it
tempfile.tempdir = RUN_TMP

SRC = os.environ.get("GLINT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
GLINTD = os.environ.get("GLINTD", os.path.join(SRC, "build", "server", "glintd"))
SCHEMA_DIR = os.path.join(SRC, "proto", "schemas")


def _schemas():
    store = {}
    for name in os.listdir(SCHEMA_DIR):
        if name.endswith(".json"):
            with open(os.path.join(SCHEMA_DIR, name)) as f:
                store[name] = json.load(f)
    return store


SCHEMAS = _schemas()


def validate(body, schema_name):
    """Validate a decoded JSON body against proto/schemas/<schema_name>
    (cross-file $refs such as {"$ref": "Scene.json"} resolve by file name).
    Debian 12's jsonschema 4.10 resolves them through RefResolver."""
    schema = SCHEMAS[schema_name]
    resolver = jsonschema.RefResolver(base_uri="", referrer=schema, store=SCHEMAS)
    jsonschema.Draft202012Validator(schema, resolver=resolver).validate(body)


# Waits only catch hangs; a loaded machine or a sanitizer build (setup.sh
# sets GLINT_TEST_TIMEOUT_SCALE=3 there, as meson's --timeout-multiplier)
# makes them longer, never shorter.
TIMEOUT_SCALE = max(1.0, float(os.environ.get("GLINT_TEST_TIMEOUT_SCALE") or 1))

# What a sanitizer build of glintd reported (AddressSanitizer, LeakSanitizer,
# UndefinedBehaviorSanitizer write to its stderr, which is the log): each
# finding fails the run (run_tests).
SANITIZER_MARKS = ("ERROR: AddressSanitizer", "ERROR: LeakSanitizer", "runtime error:")
sanitizer_findings = {}


def sanitizer_check(log_path):
    try:
        with open(log_path, "rb") as f:
            text = f.read().decode("utf-8", "replace")
    except OSError:
        return
    for mark in SANITIZER_MARKS:
        at = text.find(mark)
        if at >= 0:
            sanitizer_findings[log_path] = text[max(0, at - 200):at + 3000]
            return


# With GLINT_TEST_PG set (tests/with_postgres.sh started a PostgreSQL
# server), every data directory gets a database of its own on that server
# and glintd keeps its metadata there (--database): the same tests, the
# other store engine.  A data directory reused by a later Daemon keeps its
# database.
PG = os.environ.get("GLINT_TEST_PG", "")
_pg_databases = {}


def pg_database(data_dir):
    """The connection string of data_dir's database, created on first use."""
    if data_dir not in _pg_databases:
        name = "it_" + os.urandom(8).hex()
        subprocess.run(["psql", "-q", "-X", "-v", "ON_ERROR_STOP=1", PG, "-c",
                        "CREATE DATABASE %s" % name], check=True)
        _pg_databases[data_dir] = "%s dbname=%s" % (PG, name)
    return _pg_databases[data_dir]


def pg_query(data_dir, sql):
    """Rows of a query on data_dir's database, as lists of strings."""
    out = subprocess.run(["psql", "-q", "-X", "-A", "-t", "-F", "\t", "-v", "ON_ERROR_STOP=1",
                          pg_database(data_dir), "-c", sql],
                         check=True, capture_output=True, text=True).stdout
    return [line.split("\t") for line in out.splitlines() if line]


# Every Daemon this process made: run_tests removes their directories when
# every test passed (and keeps them, named, for a look when one failed).
daemons = []


class Daemon:
    """A running glintd; stop() sends SIGTERM and waits."""

    def __init__(self, *args, data_dir=None):
        self.tmp = tempfile.mkdtemp(prefix="glintd-test-")
        daemons.append(self)
        self.data_dir = data_dir or os.path.join(self.tmp, "data")
        self.args = list(args)
        if PG and "--database" not in self.args:
            self.args += ["--database", pg_database(os.path.realpath(self.data_dir))]
        self.proc = None
        self.preexec = None  # run in the child before glintd (limits, another user)
        self.glintd = GLINTD
        self.port_dir = self.tmp
        self.start()

    def start(self):
        port_file = os.path.join(self.port_dir, "port")
        if os.path.exists(port_file):
            os.unlink(port_file)
        self.log = open(os.path.join(self.tmp, "glintd.log"), "ab")
        self.proc = subprocess.Popen(
            [self.glintd, "--port", "0", "--port-file", port_file, "--data-dir", self.data_dir,
             "--web-dir", os.path.join(SRC, "web")] + self.args,
            stdout=self.log, stderr=self.log, preexec_fn=self.preexec)
        deadline = time.time() + 20
        while time.time() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError("glintd exited with %d; log: %s" % (self.proc.returncode, self.tmp))
            if os.path.exists(port_file):
                with open(port_file) as f:
                    txt = f.read().strip()
                if txt:
                    # on PostgreSQL no SQLite file is made
                    assert not (PG and os.path.exists(os.path.join(self.data_dir, "glint.db")))
                    self.port = int(txt)
                    self.base = "http://127.0.0.1:%d" % self.port
                    return
            time.sleep(0.02)
        raise RuntimeError("glintd did not start")

    def stop(self, sig=signal.SIGTERM):
        if self.proc and self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.log.close()
        sanitizer_check(os.path.join(self.tmp, "glintd.log"))

    def kill9(self):
        self.stop(signal.SIGKILL)

    def sanitized(self):
        """Whether this glintd runs under AddressSanitizer: its allocator
        holds freed memory in a quarantine (256 MB) and its shadow grows with
        every byte touched, so a resident-memory bound measures the sanitizer,
        not glintd.  Tests of memory bounds assert them on the plain build
        (the first tier) and only the answers here."""
        with open("/proc/%d/maps" % self.proc.pid) as f:
            return "libasan" in f.read()

    def request(self, method, path, status=None, schema=None, **kw):
        """HTTP request; checks the status, validates JSON (problem bodies
        against Problem.json, others against `schema`) and returns the response."""
        kw.setdefault("timeout", 60 * TIMEOUT_SCALE)
        r = requests.request(method, self.base + path, **kw)
        if status is not None:
            assert r.status_code == status, "%s %s: status %d, want %d: %s" % (
                method, path, r.status_code, status, r.text[:500])
        ctype = r.headers.get("Content-Type", "")
        if ctype.startswith("application/problem+json"):
            validate(r.json(), "Problem.json")
            assert r.status_code >= 400
        elif schema is not None:
            validate(r.json(), schema)
        return r

    def get(self, path, **kw):
        return self.request("GET", path, **kw)

    def post(self, path, **kw):
        return self.request("POST", path, **kw)

    def put(self, path, **kw):
        return self.request("PUT", path, **kw)

    def delete(self, path, **kw):
        return self.request("DELETE", path, **kw)


def png_size(data):
    """(width, height) of PNG bytes (IHDR), after checking the signature."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    w, h = struct.unpack(">II", data[16:24])
    return w, h


def png_unfilter(raw, w, h, bpp):
    """The rows (bytearrays of w * bpp bytes) of 8-bit PNG image data, once
    inflated (`raw`): each row's filter byte undone (PNG specification,
    filter types 0-4)."""
    stride, rows = w * bpp, []
    assert len(raw) == h * (stride + 1), (len(raw), w, h, bpp)
    prev = bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        assert f <= 4, "filter type %d" % f
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b = prev[x]
            c = prev[x - bpp] if x >= bpp else 0
            if f == 1:
                line[x] = (line[x] + a) & 255
            elif f == 2:
                line[x] = (line[x] + b) & 255
            elif f == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pr = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                line[x] = (line[x] + pr) & 255
        rows.append(line)
        prev = line
    return rows


def png_pixels(data):
    """8-bit RGB(A) PNG (no interlace) -> (w, h, channels, bytes), filters undone."""
    w, h = png_size(data)
    depth, ctype = data[24], data[25]
    assert depth == 8 and ctype in (2, 6), (depth, ctype)
    ch = 3 if ctype == 2 else 4
    pos, idat = 8, b""
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        if kind == b"IDAT":
            idat += data[pos + 8:pos + 8 + n]
        pos += 12 + n
    return w, h, ch, b"".join(png_unfilter(zlib.decompress(idat), w, h, ch))


def sse_events(d, path, headers, timeout=120, stop_types=("done", "failed")):
    """Read a server-sent event stream; return [(id, type, data)] up to and
    including the first event whose type is in stop_types."""
    r = requests.get(d.base + path, headers=headers, stream=True, timeout=timeout * TIMEOUT_SCALE)
    assert r.status_code == 200, r.text
    assert r.headers["Content-Type"].startswith("text/event-stream")
    events, cur = [], {}
    try:
        for raw in r.iter_lines(decode_unicode=True):
            if raw is None:
                continue
            if raw == "":
                if "event" in cur or "data" in cur:
                    events.append((cur.get("id"), cur.get("event", "message"),
                                   json.loads(cur["data"]) if "data" in cur else None))
                    if events[-1][1] in stop_types:
                        break
                cur = {}
                continue
            if raw.startswith(":"):
                continue
            k, _, v = raw.partition(":")
            cur[k] = v[1:] if v.startswith(" ") else v
    finally:
        r.close()
    return events


def fit_material(d, session, body, timeout=300):
    """POST a fit of `body` ({"method", "params"}) to a session and wait for
    its material: its id (201 at once, or the job's when it is done)."""
    tok = {"X-Glint-Token": session["paint_token"]}
    r = d.post("/api/v1/sessions/%s/fits" % session["id"],
               headers=dict(tok, **{"Content-Type": "application/json"}), data=json.dumps(body))
    assert r.status_code in (201, 202), r.text
    if r.status_code == 201:
        return r.json()["id"]
    jid, deadline = r.json()["job"]["id"], time.time() + timeout * TIMEOUT_SCALE
    while True:
        j = d.get("/api/v1/jobs/" + jid, headers=tok, status=200).json()["job"]
        if j["state"] in ("done", "failed"):
            break
        assert time.time() < deadline, "the fit's job did not finish in %d s" % timeout
        time.sleep(0.1)
    assert j["state"] == "done", j
    return j["material_id"]


def run_tests(namespace, daemon_args=()):
    """Run every test_* function of a module, each given a shared Daemon;
    print one line per test and 'N passed, N failed'; exit non-zero on failure."""
    d = Daemon(*daemon_args)
    passed = failed = 0
    try:
        for name, fn in sorted(namespace.items()):
            if not name.startswith("test_") or not callable(fn):
                continue
            try:
                fn(d)
                print("ok   " + name)
                passed += 1
            except Exception:
                print("FAIL " + name)
                traceback.print_exc(file=sys.stdout)
                failed += 1
            sys.stdout.flush()
    finally:
        d.stop()
    for path, excerpt in sorted(sanitizer_findings.items()):
        print("FAIL sanitizer report in %s:\n%s" % (path, excerpt))
        failed += 1
    print("%d passed, %d failed" % (passed, failed))
    remove_dirs(failed)
    sys.exit(1 if failed else 0)


def remove_dirs(failed, more=()):
    """The directories of every Daemon made (and `more`): removed when no
    test failed, else named and kept for a look."""
    for path in [x.tmp for x in daemons] + list(more):
        if failed:
            print("kept: %s" % path)
        else:
            shutil.rmtree(path, ignore_errors=True)
    for x in daemons:
        if not failed and x.proc and x.proc.poll() is None:
            x.proc.kill()
            x.proc.wait()
    if failed:
        print("kept: %s" % RUN_TMP)
    else:
        shutil.rmtree(RUN_TMP, ignore_errors=True)
