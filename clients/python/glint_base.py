"""What glint_client.GlintClient builds on: its errors, the Blob and event
types it returns, the constants of the API and the checks of arguments
(standard library only; import glint_client, which re-exports the public
names)."""
import http.client
import json
import os
import socket
import time
import urllib.parse

SHADER_FILES = ("shader.json", "glint_material.vert", "glint_material.frag",
                "glint_material_330.vert", "glint_material_330.frag",
                "glint_factors.exr", "glint_factors_rgba16f.bin", "glint_factors16.png")
MESH_FORMATS = ("ply", "obj", "off", "gltf", "glb", "dae")
IMAGE_FORMATS = ("png", "exr")
UNCHANGED = object()  # replace_tokens(expires_in=UNCHANGED): leave the expiry as it is

_MAGIC_TYPES = ((b"\x89PNG\r\n\x1a\n", "image/png"), (b"\xff\xd8\xff", "image/jpeg"),
                (b"\x76\x2f\x31\x01", "image/x-exr"))


class GlintError(Exception):
    """An answer outside 2xx, or a request that got no answer.

    status: the HTTP status (None when no answer came); type, title, detail:
    the problem+json members (None when the body was not a problem);
    method, url: the request; body: the raw answer; retry_after: the
    Retry-After header's seconds (503 busy), else None.
    """

    def __init__(self, message, status=None, type=None, title=None, detail=None,
                 method=None, url=None, body=b"", retry_after=None):
        super().__init__(message)
        self.status, self.type, self.title, self.detail = status, type, title, detail
        self.method, self.url, self.body, self.retry_after = method, url, body, retry_after

    @property
    def kind(self):
        """The problem type's last path segment, e.g. "not-found" for
        /problems/not-found (None without a problem body)."""
        return self.type.rsplit("/", 1)[-1] if self.type else None


class GlintConnectionError(GlintError):
    """The daemon could not be reached, or the connection failed or timed out."""


class GlintTimeout(GlintError):
    """A wait (wait_job) ran past its deadline."""


class JobFailed(GlintError):
    """A fit job ended in state failed; job holds the Job object."""

    def __init__(self, job):
        super().__init__("job %s failed: %s" % (job.get("id"), job.get("error")),
                         detail=job.get("error"))
        self.job = job


class Blob(bytes):
    """The bytes of a file answer, with headers (an http.client.HTTPMessage)
    and content_type. save(path) writes them and returns path."""

    headers = None

    @property
    def content_type(self):
        return (self.headers.get("Content-Type", "") if self.headers else "").split(";")[0].strip()

    def header(self, name, default=None):
        """One response header, or default."""
        return self.headers.get(name, default) if self.headers else default

    def save(self, path):
        with open(path, "wb") as f:
            f.write(self)
        return path


class Event:
    """One server-sent event: id (int, or the string sent, or None), event
    (the type, "message" when none was named), data (the decoded JSON, or the
    text when it is not JSON)."""

    __slots__ = ("id", "event", "data")

    def __init__(self, id, event, data):
        self.id, self.event, self.data = id, event, data

    def __repr__(self):
        return "Event(id=%r, event=%r, data=%r)" % (self.id, self.event, self.data)


class EventStream:
    """An open text/event-stream answer, iterated as Event objects.

    Iteration ends when the server ends the stream, or when no event arrives
    within timeout seconds (comments such as ": keep-alive" do not count);
    timed_out then says which. Use it as a context manager, or call close().
    """

    def __init__(self, conn, sock, resp, timeout):
        self._conn, self._sock, self._resp = conn, sock, resp
        self.timeout, self.timed_out, self.closed = timeout, False, False
        self.headers = resp.headers
        self.retry_ms = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __iter__(self):
        return self

    def __next__(self):
        ev = self.next(self.timeout)
        if ev is None:
            raise StopIteration
        return ev

    def next(self, timeout=None):
        """The next event, or None when the stream ended or timeout seconds
        (default: the stream's) passed without one."""
        if self.closed:
            return None
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        ev_id, ev_type, data = None, None, []
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return self._stop(timed_out=True)
            try:
                self._sock.settimeout(left)
                raw = self._resp.readline()
            except (socket.timeout, TimeoutError):
                return self._stop(timed_out=True)
            except (OSError, http.client.HTTPException, ValueError):
                return self._stop()
            if not raw:
                return self._stop()
            line = raw.decode("utf-8", "replace").rstrip("\r\n")
            if line == "":
                if data:
                    return Event(ev_id, ev_type or "message", _maybe_json("\n".join(data)))
                ev_id, ev_type = None, None
                continue
            if line.startswith(":"):
                continue
            field, _, value = line.partition(":")
            value = value[1:] if value.startswith(" ") else value
            if field == "data":
                data.append(value)
            elif field == "event":
                ev_type = value
            elif field == "id":
                ev_id = int(value) if value.isdigit() else value
            elif field == "retry" and value.isdigit():
                self.retry_ms = int(value)

    def _stop(self, timed_out=False):
        self.timed_out = timed_out
        self.close()
        return None

    def close(self):
        """End the stream (closes the connection)."""
        if not self.closed:
            self.closed = True
            try:
                self._resp.close()
            finally:
                self._conn.close()


def _maybe_json(text):
    try:
        return json.loads(text)
    except ValueError:
        return text


def _segment(value, what="id"):
    """A path segment from a user value, percent-encoded."""
    if not isinstance(value, str) or not value:
        raise ValueError("%s must be a non-empty string, not %r" % (what, value))
    return urllib.parse.quote(value, safe="")


def _index(value, what="view"):
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError("%s must be a non-negative int, not %r" % (what, value))
    return value


def _choice(value, allowed, what):
    if value not in allowed:
        raise ValueError("%s must be one of %s, not %r" % (what, ", ".join(allowed), value))
    return value


def _vec3(value, what):
    """'x,y,z' from a string or a sequence of three numbers."""
    if value is None or isinstance(value, str):
        return value
    v = list(value)
    if len(v) != 3 or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
        raise ValueError("%s must be three numbers, not %r" % (what, value))
    return ",".join(repr(float(x)) for x in v)


def _flag(value):
    """0/1 for a boolean query parameter (None stays None)."""
    return None if value is None else int(bool(value))


def _read(data, what):
    """Bytes from bytes-like data, or the contents of a file path."""
    if isinstance(data, (bytes, bytearray, memoryview)):
        return bytes(data)
    if isinstance(data, (str, os.PathLike)):
        with open(data, "rb") as f:
            return f.read()
    raise TypeError("%s must be bytes or a file path, not %s" % (what, type(data).__name__))


def _image_type(data):
    for magic, ctype in _MAGIC_TYPES:
        if data.startswith(magic):
            return ctype
    return "application/octet-stream"


def _env_query(env, env_rotation, env_intensity, lights, shadows, background):
    return {"env": env, "env_rotation": env_rotation, "env_intensity": env_intensity,
            "lights": lights, "shadows": _flag(shadows), "background": _flag(background)}
