"""A client for glintd's REST API (proto/openapi.yaml), standard library only.

    from glint_client import GlintClient, GlintError

    c = GlintClient("http://127.0.0.1:8080", api_key=None)
    scene = c.create_scene(mesh="sphere", width=64, height=64)
    session = c.create_session(scene["id"])
    c.token = session["paint_token"]
    exr = c.base_render(scene["id"], 0, format="exr", brdf="ct:rough=0.3,kd=0.5")
    c.put_painting(session["id"], 0, exr)
    material = c.fit_and_wait(session["id"], "hf3", {"res": 32})
    c.preview(material["id"], view=0).save("preview.png")

JSON answers are returned as decoded dicts, exactly as the schemas in
proto/schemas describe them; files (images, archives, shader sources) are
returned as Blob, a bytes object that also carries the response's headers.

Credentials (openapi.yaml securitySchemes):
  api_key    sent as "Authorization: Bearer KEY" (glintd --api-key);
  token      a session's paint or view token, sent as X-Glint-Token;
  owner_key  the secret that owns scenes, uploaded environments and G-buffer
             sets, sent as X-Glint-Owner.
Each is set on the client and may be overridden per call (token=,
owner_key=).

Every answer outside 2xx raises GlintError with the HTTP status and, for
application/problem+json bodies (RFC 9457), the problem's type, title and
detail; a failed connection or a timeout raises GlintConnectionError (a
GlintError whose status is None).
"""
import http.client
import json
import os
import time
import urllib.parse

__all__ = ["GlintClient", "GlintError", "GlintConnectionError", "GlintTimeout",
           "JobFailed", "Blob", "Event", "EventStream", "UNCHANGED"]

from glint_base import (  # noqa: E402,F401  (re-exported: the public names)
    SHADER_FILES, MESH_FORMATS, IMAGE_FORMATS, UNCHANGED, GlintError,
    GlintConnectionError, GlintTimeout, JobFailed, Blob, Event,
    EventStream, _segment, _index, _choice, _vec3,
    _read, _image_type, _env_query)


class GlintClient:
    """glintd at base_url (http:// or https://, optionally with a path prefix).

    api_key: the daemon's API key (glintd --api-key), needed to create
    scenes, sessions, meshes and environments on a daemon that has one;
    token: the default session token (paint or view) for session, job and
    material calls; owner_key: the default X-Glint-Owner for what an owner
    key owns (scenes, uploaded environments, G-buffer sets: creating,
    listing, deleting; a set's every call); timeout: seconds per request; busy_retries: how
    many times a 503 answer carrying Retry-After (the work budget is taken
    now; nothing was done) is retried after the time it names (at most
    max_retry_wait seconds each).
    """

    def __init__(self, base_url, api_key=None, token=None, owner_key=None, timeout=60.0,
                 busy_retries=3, max_retry_wait=10.0):
        u = urllib.parse.urlsplit(base_url)
        if u.scheme not in ("http", "https") or not u.hostname:
            raise ValueError("base_url must be http://HOST[:PORT][/PREFIX], not %r" % base_url)
        self.base_url = base_url.rstrip("/")
        self._scheme, self._host, self._port = u.scheme, u.hostname, u.port
        self._prefix = u.path.rstrip("/")
        self._origin = "%s://%s" % (u.scheme, u.netloc)
        self.api_key, self.token, self.owner_key = api_key, token, owner_key
        self.timeout, self.busy_retries, self.max_retry_wait = timeout, busy_retries, max_retry_wait

    # ---- transport ------------------------------------------------------

    def _connect(self, timeout):
        cls = http.client.HTTPSConnection if self._scheme == "https" else http.client.HTTPConnection
        return cls(self._host, self._port, timeout=timeout)

    def _headers(self, token, owner_key, extra):
        h = {"Accept": "application/json, application/problem+json, */*"}
        if self.api_key:
            h["Authorization"] = "Bearer " + self.api_key
        token = token if token is not None else self.token
        if token:
            h["X-Glint-Token"] = token
        owner_key = owner_key if owner_key is not None else self.owner_key
        if owner_key:
            h["X-Glint-Owner"] = owner_key
        h.update(extra or {})
        return h

    def _target(self, path, query):
        q = {k: v for k, v in (query or {}).items() if v is not None}
        return self._prefix + path + ("?" + urllib.parse.urlencode(q) if q else "")

    def _open(self, method, path, query=None, body=None, headers=None, token=None,
              owner_key=None, timeout=None):
        """Send a request; (connection, socket, response) for an answer in 2xx,
        else GlintError (after busy retries)."""
        target = self._target(path, query)
        url = self._origin + target
        hdrs = self._headers(token, owner_key, headers)
        retries = max(0, self.busy_retries)
        for attempt in range(retries + 1):
            conn = self._connect(self.timeout if timeout is None else timeout)
            try:
                conn.request(method, target, body=body, headers=hdrs)
                sock = conn.sock
                resp = conn.getresponse()
            except (OSError, http.client.HTTPException) as e:
                conn.close()
                raise GlintConnectionError("%s %s: %s" % (method, url, str(e) or type(e).__name__),
                                           method=method, url=url) from e
            if 200 <= resp.status < 300:
                return conn, sock, resp
            try:
                err = self._error(method, url, resp)
            except (OSError, http.client.HTTPException) as e:
                err = GlintConnectionError("%s %s: %d, then %s" % (method, url, resp.status, e),
                                           status=resp.status, method=method, url=url)
            finally:
                conn.close()
            if err.status != 503 or err.retry_after is None or attempt == retries:
                raise err
            time.sleep(min(err.retry_after, self.max_retry_wait))

    @staticmethod
    def _error(method, url, resp):
        body = resp.read()
        ctype = resp.headers.get("Content-Type", "")
        retry = resp.headers.get("Retry-After")
        retry = int(retry) if retry and retry.isdigit() else None
        problem = {}
        if "json" in ctype:
            try:
                problem = json.loads(body)
            except ValueError:
                problem = {}
            if not isinstance(problem, dict):
                problem = {}
        detail = problem.get("detail")
        msg = "%s %s: %d %s" % (method, url, resp.status, problem.get("title") or resp.reason)
        if detail:
            msg += ": " + detail
        elif body and not problem:
            msg += ": " + body[:200].decode("utf-8", "replace")
        return GlintError(msg, status=resp.status, type=problem.get("type"),
                          title=problem.get("title"), detail=detail, method=method, url=url,
                          body=body, retry_after=retry)

    def _call(self, method, path, query=None, json_body=None, data=None, content_type=None,
              headers=None, token=None, owner_key=None, raw=False):
        """One request read whole: the decoded JSON, a Blob when raw, or None
        for an empty answer."""
        hdrs = dict(headers or {})
        body = data
        if json_body is not None:
            body = json.dumps(json_body).encode()
            hdrs["Content-Type"] = "application/json"
        elif content_type:
            hdrs["Content-Type"] = content_type
        if body is None and method in ("POST", "PUT"):
            body = b""
        conn, _, resp = self._open(method, path, query, body, hdrs, token, owner_key)
        try:
            payload = resp.read()
        except (OSError, http.client.HTTPException) as e:
            url = self._origin + self._target(path, query)
            raise GlintConnectionError("%s %s: reading the answer: %s" % (method, url, e),
                                       status=resp.status, method=method, url=url) from e
        finally:
            conn.close()
        if raw:
            out = Blob(payload)
            out.headers = resp.headers
        elif not payload:
            out = None
        else:
            try:
                out = json.loads(payload)
            except ValueError as e:
                url = self._origin + self._target(path, query)
                raise GlintError("%s %s: %d answer is not JSON: %r" % (
                    method, url, resp.status, payload[:100]), status=resp.status,
                    method=method, url=url, body=payload) from e
        return out

    def _stream(self, path, query, headers, token, timeout):
        conn, sock, resp = self._open("GET", path, query, None,
                                      dict(headers, Accept="text/event-stream"), token, None,
                                      timeout=max(timeout, 1.0))
        return EventStream(conn, sock, resp, timeout)

    # ---- health ---------------------------------------------------------

    def health(self):
        """GET /healthz: Health {status: "ok", uptime_s}."""
        return self._call("GET", "/healthz")

    def metrics(self):
        """GET /metrics: the Prometheus exposition text (str)."""
        return self._call("GET", "/metrics", raw=True).decode("utf-8")

    # ---- meshes ---------------------------------------------------------

    def upload_mesh(self, data, format=None):
        """POST /api/v1/meshes: upload a mesh file (bytes, or a file path whose
        extension gives format when format is None). Returns Mesh (id,
        triangles, vertices, report of what loading decided)."""
        if format is None and isinstance(data, (str, os.PathLike)):
            format = os.path.splitext(os.fspath(data))[1].lstrip(".").lower()
        _choice(format, MESH_FORMATS, "format")
        return self._call("POST", "/api/v1/meshes", {"format": format},
                          data=_read(data, "mesh"), content_type="application/octet-stream")

    def get_mesh(self, mesh_id):
        """GET /api/v1/meshes/{id}: Mesh."""
        return self._call("GET", "/api/v1/meshes/" + _segment(mesh_id))

    # ---- scenes ---------------------------------------------------------

    def create_scene(self, mesh=None, mesh_id=None, width=None, height=None, views=None,
                     light_angles=None, base=None, owner_key=None, paint_scale=None):
        """POST /api/v1/scenes: a scene on a built-in mesh (sphere, torus,
        teapot; the daemon's default is sphere) or an uploaded mesh_id.
        views: "ico12", "ico20" or a list of {eye, light, ...}; base: {brdf,
        scale, env}; paint_scale: paint at 1..4 times the raster a side (the
        fit still samples the raster). Returns Scene, whose owner_key (the
        one sent, or one the daemon made) is shown only here."""
        if mesh is not None and mesh_id is not None:
            raise ValueError("give mesh or mesh_id, not both")
        for name, v in (("width", width), ("height", height), ("paint_scale", paint_scale)):
            if v is not None:
                _index(v, name)
        body = {k: v for k, v in (("mesh", mesh), ("mesh_id", mesh_id), ("width", width),
                                   ("height", height), ("views", views),
                                   ("light_angles", light_angles), ("base", base),
                                   ("paint_scale", paint_scale))
                if v is not None}
        return self._call("POST", "/api/v1/scenes", json_body=body, owner_key=owner_key)

    def list_scenes(self, owner_key=None):
        """GET /api/v1/scenes: SceneList {scenes, count}: the owner key's
        scenes (every scene with the API key), oldest first."""
        return self._call("GET", "/api/v1/scenes", owner_key=owner_key)

    def get_scene(self, scene_id):
        """GET /api/v1/scenes/{id}: Scene."""
        return self._call("GET", "/api/v1/scenes/" + _segment(scene_id))

    def delete_scene(self, scene_id, owner_key=None):
        """DELETE /api/v1/scenes/{id}: deletes the scene with its sessions and
        the materials fitted in them; needs its owner key or the API key.
        Returns None."""
        self._call("DELETE", "/api/v1/scenes/" + _segment(scene_id), owner_key=owner_key)

    def base_render(self, scene_id, view, format="png", brdf=None, scale=None, intensity=None,
                    env=None, env_rotation=None, env_intensity=None, lights=None, shadows=None,
                    background=None, size=None):
        """GET /api/v1/scenes/{id}/views/{k}/base.png: a view's base render
        (Blob, PNG or float RGB OpenEXR); with brdf (a core spec such as
        ct:rough=0.3,kd=0.5), scale or intensity a render of that BRDF; with
        env an environment lights it (env_rotation degrees, env_intensity,
        lights, shadows, background as booleans); size "paint" (the
        painting's size, the default) or "raster"."""
        q = {"format": _choice(format, IMAGE_FORMATS, "format"), "brdf": brdf, "scale": scale,
             "intensity": intensity,
             "size": None if size is None else _choice(size, ("paint", "raster"), "size")}
        q.update(_env_query(env, env_rotation, env_intensity, lights, shadows, background))
        return self._call("GET", "/api/v1/scenes/%s/views/%d/base.png" % (
            _segment(scene_id), _index(view)), q, raw=True)

    def gbuffer(self, scene_id, view):
        """GET /api/v1/scenes/{id}/views/{k}/gbuffer.exr: the view's G-buffer
        (Blob, OpenEXR with mask, P, N, uv, wi, wo, cos_i, cos_o)."""
        return self._call("GET", "/api/v1/scenes/%s/views/%d/gbuffer.exr" % (
            _segment(scene_id), _index(view)), raw=True)

    # ---- sessions -------------------------------------------------------

    def create_session(self, scene_id, expires_in=None):
        """POST /api/v1/sessions: Session with paint_token, view_token and the
        studio's share links; expires_in: seconds until the links stop working."""
        body = {"scene_id": scene_id}
        if expires_in is not None:
            body["expires_in"] = _index(expires_in, "expires_in")
        return self._call("POST", "/api/v1/sessions", json_body=body)

    def get_session(self, session_id, token=None):
        """GET /api/v1/sessions/{id}: Session (a view token's answer has no
        paint token); access says what the token grants."""
        return self._call("GET", "/api/v1/sessions/" + _segment(session_id), token=token)

    def replace_tokens(self, session_id, revoke=None, expires_in=UNCHANGED, token=None,
                       owner_key=None):
        """POST /api/v1/sessions/{id}/tokens: revoke and replace the session's
        tokens (revoke: both (default), paint, view or none) and set when the
        links expire (seconds from now; None: never; UNCHANGED: as they are).
        Allowed to the paint token, the scene's owner key and the API key.
        Returns Session with the new tokens and links."""
        body = {}
        if revoke is not None:
            body["revoke"] = _choice(revoke, ("both", "paint", "view", "none"), "revoke")
        if expires_in is not UNCHANGED:
            body["expires_in"] = None if expires_in is None else _index(expires_in, "expires_in")
        return self._call("POST", "/api/v1/sessions/%s/tokens" % _segment(session_id),
                          json_body=body, token=token, owner_key=owner_key)

    # ---- paintings and strokes ------------------------------------------

    def put_painting(self, session_id, view, image, content_type=None, if_match=None,
                     token=None):
        """PUT /api/v1/sessions/{id}/views/{k}/painting: replace a view's
        painting with image (PNG, JPEG or OpenEXR bytes, or a file path; its
        type is read from its first bytes unless content_type is given).
        if_match: only if the view is still at that painting version (412
        otherwise). Returns PaintingVersion {view, version, seq}."""
        data = _read(image, "image")
        hdrs = {} if if_match is None else {"If-Match": '"%d"' % _index(if_match, "if_match")}
        return self._call("PUT", "/api/v1/sessions/%s/views/%d/painting" % (
            _segment(session_id), _index(view)), data=data,
            content_type=content_type or _image_type(data), headers=hdrs, token=token)

    def get_painting(self, session_id, view, format="png", token=None):
        """GET /api/v1/sessions/{id}/views/{k}/painting: the view's current
        image (Blob; the base render for a view never painted). Its headers
        X-Glint-Painted ("1"/"0") and X-Glint-Version (0 for the base render)
        say which."""
        return self._call("GET", "/api/v1/sessions/%s/views/%d/painting" % (
            _segment(session_id), _index(view)),
            {"format": _choice(format, IMAGE_FORMATS, "format")}, raw=True, token=token)

    def post_strokes(self, session_id, view, strokes, token=None):
        """POST /api/v1/sessions/{id}/views/{k}/strokes: apply strokes (a
        Stroke dict or a list of them: points, diameter, color, mode, ...), in
        order, all or none. Returns StrokesPosted {first_seq, last_seq,
        version, strokes, pixels}."""
        if isinstance(strokes, dict):
            strokes = [strokes]
        if not isinstance(strokes, (list, tuple)) or not strokes or \
                not all(isinstance(s, dict) for s in strokes):
            raise ValueError("strokes must be a Stroke dict or a non-empty list of them")
        return self._call("POST", "/api/v1/sessions/%s/views/%d/strokes" % (
            _segment(session_id), _index(view)), json_body={"strokes": list(strokes)},
            token=token)

    def list_strokes(self, session_id, since=0, limit=None, token=None):
        """GET /api/v1/sessions/{id}/strokes: StrokeList {strokes, last_seq,
        more}: strokes with seq > since, in order, at most limit of them."""
        q = {"since": _index(since, "since"),
             "limit": None if limit is None else _index(limit, "limit")}
        return self._call("GET", "/api/v1/sessions/%s/strokes" % _segment(session_id), q,
                          token=token)

    def iter_strokes(self, session_id, since=0, token=None):
        """Every stroke with seq > since (items of StrokeList.strokes), paging
        through list_strokes."""
        while True:
            page = self.list_strokes(session_id, since, token=token)
            yield from page["strokes"]
            if not page["more"]:
                return
            since = page["last_seq"]

    def session_events(self, session_id, since=None, last_event_id=None, name=None,
                       token=None, timeout=30.0):
        """GET /api/v1/sessions/{id}/events: an EventStream of the session's
        events. Durable events (stroke, painting, fit; id: the sequence
        number; data: SessionEvent) replay from since or last_event_id (the
        whole history by default), then follow live; presence events (no id;
        data: Presence) list the connected clients (name: this client's).
        timeout: the longest wait for an event before iteration ends."""
        q = {"since": None if since is None else _index(since, "since"), "name": name}
        h = {} if last_event_id is None else {
            "Last-Event-ID": str(_index(last_event_id, "last_event_id"))}
        return self._stream("/api/v1/sessions/%s/events" % _segment(session_id), q, h, token,
                            timeout)

    # ---- fits and jobs --------------------------------------------------

    def fit(self, session_id, method="hf3", params=None, token=None):
        """POST /api/v1/sessions/{id}/fits: fit the painted views (the paint
        token). Returns Material when it was fitted at once (201), or
        JobResponse {job} when it runs as a job (202): pass
        result["job"]["id"] to wait_job, or use fit_and_wait."""
        if not isinstance(method, str) or not method:
            raise ValueError("method must be a method name such as hf3")
        if params is not None and not isinstance(params, dict):
            raise ValueError("params must be a dict")
        body = {"method": method}
        if params:
            body["params"] = params
        return self._call("POST", "/api/v1/sessions/%s/fits" % _segment(session_id),
                          json_body=body, token=token)

    def fit_and_wait(self, session_id, method="hf3", params=None, token=None, timeout=600.0):
        """fit, then wait_job when it became a job: the Material either way."""
        r = self.fit(session_id, method, params, token=token)
        if "job" not in r:
            return r
        job = self.wait_job(r["job"]["id"], timeout=timeout, token=token)
        return self.get_material(job["material_id"], token=token)

    def get_job(self, job_id, token=None):
        """GET /api/v1/jobs/{id}: JobResponse {job: Job (state, stage,
        progress, material_id once done, error once failed)}."""
        return self._call("GET", "/api/v1/jobs/" + _segment(job_id), token=token)

    def wait_job(self, job_id, timeout=600.0, poll=0.25, token=None):
        """Poll GET /api/v1/jobs/{id} until the job finishes: the Job when
        done; JobFailed when failed; GlintTimeout after timeout seconds."""
        deadline = time.monotonic() + timeout
        while True:
            job = self.get_job(job_id, token=token)["job"]
            if job["state"] == "done":
                return job
            if job["state"] == "failed":
                raise JobFailed(job)
            if time.monotonic() >= deadline:
                raise GlintTimeout("job %s still %s (%s, %.0f%%) after %gs" % (
                    job_id, job["state"], job.get("stage"), 100 * job.get("progress", 0), timeout))
            time.sleep(poll)

    def job_events(self, job_id, since=None, last_event_id=None, token=None, timeout=60.0):
        """GET /api/v1/jobs/{id}/events: an EventStream of "progress" events,
        then one "done" or "failed" (each event's data a Job), after which
        the stream ends."""
        q = {"since": None if since is None else _index(since, "since")}
        h = {} if last_event_id is None else {
            "Last-Event-ID": str(_index(last_event_id, "last_event_id"))}
        return self._stream("/api/v1/jobs/%s/events" % _segment(job_id), q, h, token, timeout)

    # ---- materials ------------------------------------------------------

    def _mat(self, material_id, tail=""):
        return "/api/v1/materials/" + _segment(material_id) + tail

    def list_materials(self, session_id, token=None):
        """GET /api/v1/sessions/{id}/materials: MaterialList {materials},
        oldest first."""
        return self._call("GET", "/api/v1/sessions/%s/materials" % _segment(session_id),
                          token=token)

    def get_material(self, material_id, token=None):
        """GET /api/v1/materials/{id}: Material (method, params, views_used,
        errors, seconds, precomputation, links)."""
        return self._call("GET", self._mat(material_id), token=token)

    def factors(self, material_id, format="png", token=None):
        """GET /api/v1/materials/{id}/factors.{png,exr}: the factor textures
        (Blob; PNG rows scaled per png_scale of the manifest, EXR linear)."""
        return self._call("GET", self._mat(material_id, "/factors." + _choice(
            format, IMAGE_FORMATS, "format")), raw=True, token=token)

    def coefficients(self, material_id, format="png", token=None):
        """GET /api/v1/materials/{id}/coefficients.{png,exr}: the coefficient
        textures of methods maps and hybrid (Blob; 404 for other methods)."""
        return self._call("GET", self._mat(material_id, "/coefficients." + _choice(
            format, IMAGE_FORMATS, "format")), raw=True, token=token)

    def spatial(self, material_id, format="png", token=None):
        """GET /api/v1/materials/{id}/spatial.{png,exr}: the spatial factors of
        methods hf4 and hybrid (Blob; 404 for other methods)."""
        return self._call("GET", self._mat(material_id, "/spatial." + _choice(
            format, IMAGE_FORMATS, "format")), raw=True, token=token)

    def manifest(self, material_id, token=None):
        """GET /api/v1/materials/{id}/material.json: the manifest as glint saved
        it (format, version, method, info and the method's own members)."""
        return self._call("GET", self._mat(material_id, "/material.json"), token=token)

    def shader(self, material_id, token=None):
        """GET /api/v1/materials/{id}/shader: Shader {language, vertex,
        fragment, manifest, files}."""
        return self._call("GET", self._mat(material_id, "/shader"), token=token)

    def shader_file(self, material_id, name, token=None):
        """GET /api/v1/materials/{id}/shader/{file}: one file of the shader
        export (Blob), name one of SHADER_FILES."""
        return self._call("GET", self._mat(material_id, "/shader/" + _segment(
            _choice(name, SHADER_FILES, "name"))), raw=True, token=token)

    def package(self, material_id, token=None):
        """GET /api/v1/materials/{id}/package: everything of the material as
        one uncompressed tar (Blob): glint-material-<id8>/material.json,
        factors.png, factors.exr and shader/."""
        return self._call("GET", self._mat(material_id, "/package"), raw=True, token=token)

    def merl(self, material_id, token=None):
        """GET /api/v1/materials/{id}/merl.binary: the material tabulated as
        an isotropic BRDF in the MERL layout (Blob, 34,992,012 bytes; its
        X-Glint-Merl header says whether it was averaged over azimuths or
        over the surface). BRDF Explorer, ALTA and dj_brdf read it."""
        return self._call("GET", self._mat(material_id, "/merl.binary"), raw=True, token=token)

    def brdf_explorer(self, material_id, token=None):
        """GET /api/v1/materials/{id}/material.brdf: the material as BRDF
        Explorer's analytic .brdf text (Blob), for every method; GlintError
        422 when its texture is too large to embed (use merl())."""
        return self._call("GET", self._mat(material_id, "/material.brdf"), raw=True, token=token)

    def gltf(self, material_id, bake_res=None, token=None):
        """GET /api/v1/materials/{id}/material.glb: the material on its
        scene's mesh as binary glTF 2.0 with a fitted metallic-roughness
        material (Blob; X-Glint-Gltf gives the fit and its error). A
        material that varies over the surface is baked into bake_res x
        bake_res textures (the daemon's default 32; 0: the average only)."""
        q = {"bake_res": None if bake_res is None else _index(bake_res, "bake_res")}
        return self._call("GET", self._mat(material_id, "/material.glb"), q, raw=True,
                          token=token)

    def exports(self, material_id, token=None):
        """GET /api/v1/materials/{id}/exports: ExportList, every format the
        material exports to with its file name, URL, what it carries and how
        close it comes to the material (the metallic-roughness fit)."""
        return self._call("GET", self._mat(material_id, "/exports"), token=token)

    def materialx(self, material_id, textures=False, bake_res=None, token=None):
        """GET /api/v1/materials/{id}/material.mtlx: the fit as a MaterialX
        standard_surface (Blob, text; X-Glint-Fit gives the fit and its
        error). textures=True: material.mtlx.zip, the document in a zip with
        the .glb's baked textures, which it reads, where the material varies
        over the surface (bake_res as gltf()'s)."""
        if not textures:
            if bake_res is not None:
                raise ValueError("bake_res needs textures=True")
            return self._call("GET", self._mat(material_id, "/material.mtlx"), raw=True,
                              token=token)
        q = {"bake_res": None if bake_res is None else _index(bake_res, "bake_res")}
        return self._call("GET", self._mat(material_id, "/material.mtlx.zip"), q, raw=True,
                          token=token)

    def usd(self, material_id, package=False, mesh=True, bake_res=None, token=None):
        """GET /api/v1/materials/{id}/material.usda: the fit as a
        UsdPreviewSurface bound to the scene's mesh (mesh=False: the
        material alone) (Blob, text). package=True: material.usdz, the layer
        with the .glb's baked textures where the material varies (bake_res
        as gltf()'s)."""
        if not package:
            if bake_res is not None:
                raise ValueError("bake_res needs package=True")
            return self._call("GET", self._mat(material_id, "/material.usda"),
                              {"mesh": None if mesh else 0}, raw=True, token=token)
        if not mesh:
            raise ValueError("a USDZ package always holds the mesh")
        q = {"bake_res": None if bake_res is None else _index(bake_res, "bake_res")}
        return self._call("GET", self._mat(material_id, "/material.usdz"), q, raw=True,
                          token=token)

    def preview(self, material_id, format="png", view=None, eye=None, light=None, target=None,
                fov=None, intensity=None, size=None, renderer=None, object=None, env=None,
                env_rotation=None, env_intensity=None, lights=None, shadows=None,
                background=None, token=None):
        """GET /api/v1/materials/{id}/preview.{png,exr}: the material rendered
        on its scene's mesh (object="scene") or the material ball
        (object="ball"), from view=K or eye/light/target ("x,y,z" or three
        numbers), at size x size; renderer auto, egl or cpu; env lights it
        with an environment. Returns a Blob whose X-Glint-Renderer (and,
        under env, X-Glint-Env) header says how it was drawn."""
        q = {"view": None if view is None else _index(view), "eye": _vec3(eye, "eye"),
             "light": _vec3(light, "light"), "target": _vec3(target, "target"), "fov": fov,
             "intensity": intensity, "size": None if size is None else _index(size, "size"),
             "renderer": None if renderer is None else _choice(
                 renderer, ("auto", "egl", "cpu"), "renderer"),
             "object": None if object is None else _choice(object, ("scene", "ball"), "object")}
        q.update(_env_query(env, env_rotation, env_intensity, lights, shadows, background))
        return self._call("GET", self._mat(material_id, "/preview." + _choice(
            format, IMAGE_FORMATS, "format")), q, raw=True, token=token)

    def summary(self, material_id, token=None):
        """GET /api/v1/materials/{id}/summary: MaterialSummary (base_colour,
        highlight, albedo, polar)."""
        return self._call("GET", self._mat(material_id, "/summary"), token=token)

    def eval(self, material_id, pairs, token=None):
        """POST /api/v1/materials/{id}/eval: the material at direction pairs,
        each a dict {n, wi, wo[, uv]} or a tuple (n, wi, wo[, uv]). Returns
        EvalResponse {values: one [r, g, b] per pair}."""
        out = []
        for p in pairs:
            if isinstance(p, dict):
                out.append(p)
            elif isinstance(p, (list, tuple)) and len(p) in (3, 4):
                out.append(dict(zip(("n", "wi", "wo", "uv"), (list(x) for x in p))))
            else:
                raise ValueError("a pair is {n, wi, wo[, uv]} or (n, wi, wo[, uv]), not %r" % (p,))
        if not out:
            raise ValueError("pairs must not be empty")
        return self._call("POST", self._mat(material_id, "/eval"), json_body={"pairs": out},
                          token=token)

    # ---- methods and environments ---------------------------------------

    def methods(self, scene_id=None, session_id=None, token=None):
        """GET /api/v1/methods: Methods {methods: name, title, params (each
        with type, default, bounds), presets}; with scene_id or session_id
        (its token) also scene {id, hash, points measured so far}."""
        return self._call("GET", "/api/v1/methods",
                          {"scene_id": scene_id, "session_id": session_id}, token=token)

    def method(self, name):
        """The entry of GET /api/v1/methods for one method (its parameter
        table); KeyError when the daemon has no such method."""
        for m in self.methods()["methods"]:
            if m["name"] == name:
                return m
        raise KeyError(name)

    def list_environments(self, owner_key=None):
        """GET /api/v1/environments: {environments: [Environment]}: the
        built-in skies, the daemon's --env-dir maps and the uploads of the
        owner key (every upload with the API key)."""
        return self._call("GET", "/api/v1/environments", owner_key=owner_key)

    def measured(self):
        """GET /api/v1/measured: {materials: [{spec, name, layout}]}: the
        MERL tables of the daemon's --measured-dir, each usable as a base
        render's brdf (base_render(..., brdf=spec))."""
        return self._call("GET", "/api/v1/measured")

    def upload_environment(self, data, name=None, owner_key=None):
        """POST /api/v1/environments: upload an HDR map (OpenEXR or Radiance
        HDR bytes, or a file path; lat-long or cube cross). Returns
        Environment; its spec (upload:<id>) is what env= and params.env
        take, and its owner_key (the one sent, else one made; shown only
        here) lists and deletes it."""
        return self._call("POST", "/api/v1/environments", {"name": name},
                          data=_read(data, "environment"), content_type="application/octet-stream",
                          owner_key=owner_key)

    def delete_environment(self, env_id, owner_key=None):
        """DELETE /api/v1/environments/{id}: delete an uploaded map; needs
        its owner key or the API key, and no scene lit by it (409).
        Returns None."""
        self._call("DELETE", "/api/v1/environments/" + _segment(env_id, "env_id"),
                   owner_key=owner_key)

    # ---- G-buffer sets: G-buffers and paintings made elsewhere ----------

    def create_gbuffer_set(self, views, width, height, owner_key=None):
        """POST /api/v1/gbuffer-sets (API key): a set of `views` views of
        width x height, for G-buffers and paintings another renderer made.
        Returns GbufferSet, whose owner_key (the one sent, else one made;
        shown only here) every other call on the set needs (or the API
        key)."""
        return self._call("POST", "/api/v1/gbuffer-sets", json_body={
            "views": _index(views, "views"), "width": _index(width, "width"),
            "height": _index(height, "height")}, owner_key=owner_key)

    def get_gbuffer_set(self, set_id):
        """GET /api/v1/gbuffer-sets/{id}: GbufferSet, with each view's state."""
        return self._call("GET", "/api/v1/gbuffer-sets/" + _segment(set_id, "set_id"))

    def delete_gbuffer_set(self, set_id, owner_key=None):
        """DELETE /api/v1/gbuffer-sets/{id}: the set, its uploads and the
        materials fitted from it. Returns None."""
        self._call("DELETE", "/api/v1/gbuffer-sets/" + _segment(set_id, "set_id"),
                   owner_key=owner_key)

    def put_gbuffer(self, set_id, view, exr):
        """PUT /api/v1/gbuffer-sets/{id}/views/{k}/gbuffer.exr: view k's
        G-buffer, OpenEXR bytes or a file path with named channels N.X N.Y
        N.Z, wo.X wo.Y wo.Z, wi.X wi.Y wi.Z (point-light methods), mask,
        P.X P.Y P.Z, uv.U uv.V (optional). Returns GbufferView."""
        return self._call("PUT", "/api/v1/gbuffer-sets/%s/views/%d/gbuffer.exr" % (
            _segment(set_id, "set_id"), _index(view)), data=_read(exr, "exr"),
            content_type="image/x-exr")

    def put_gbuffer_painting(self, set_id, view, image, content_type=None):
        """PUT /api/v1/gbuffer-sets/{id}/views/{k}/painting: view k's RGB
        painting per unit light (PNG, JPEG, OpenEXR or HDR bytes, or a file
        path)."""
        data = _read(image, "image")
        return self._call("PUT", "/api/v1/gbuffer-sets/%s/views/%d/painting" % (
            _segment(set_id, "set_id"), _index(view)), data=data,
            content_type=content_type or _image_type(data))

    def fit_gbuffers(self, set_id, method="hf3", params=None):
        """POST /api/v1/gbuffer-sets/{id}/fits: fit the painted views with
        any method (as fit does). Material (201) or JobResponse (202)."""
        if not isinstance(method, str) or not method:
            raise ValueError("method must be a method name such as hf3")
        if params is not None and not isinstance(params, dict):
            raise ValueError("params must be a dict")
        body = {"method": method}
        if params:
            body["params"] = params
        return self._call("POST", "/api/v1/gbuffer-sets/%s/fits" % _segment(set_id, "set_id"),
                          json_body=body)

    def fit_gbuffers_and_wait(self, set_id, method="hf3", params=None, timeout=600.0):
        """fit_gbuffers, then wait_job when it became a job: the Material."""
        r = self.fit_gbuffers(set_id, method, params)
        if "job" not in r:
            return r
        job = self.wait_job(r["job"]["id"], timeout=timeout)
        return self.get_material(job["material_id"])

    def list_gbuffer_materials(self, set_id):
        """GET /api/v1/gbuffer-sets/{id}/materials: MaterialList."""
        return self._call("GET", "/api/v1/gbuffer-sets/%s/materials" % _segment(set_id, "set_id"))
