// api.js: glintd's HTTP API (proto/openapi.yaml), nothing else.
//
// Every call goes through request(): the session token travels as
// X-Glint-Token (or ?token= where a URL must stand alone: links, SSE,
// downloads), the optional daemon API key as Authorization: Bearer, this
// browser's owner key as X-Glint-Owner on scene and environment calls (it
// owns the scenes and environment maps uploaded here: only they are listed,
// only they may be deleted; on material renders it names this browser, so
// glintd counts its work against one client's share), and a
// refusal comes back as an ApiError carrying the problem+json body
// (RFC 9457: type, title, status, detail) so the studio can show it.

import { Requests } from './requests.js';

export class ApiError extends Error {
  constructor(status, problem, what) {
    const p = problem || {};
    super((what ? what + ': ' : '') + (p.detail || p.title || 'HTTP ' + status));
    this.status = status;
    this.problem = p;
    this.what = what || '';
  }
}

export const API = '/api/v1';

export class Api {
  constructor() {
    this.token = '';
    this.apiKey = localStorage.getItem('glint.apiKey') || '';
    this.owner = localStorage.getItem('glint.owner') || '';
    if (!/^[A-Za-z0-9_-]{16,128}$/.test(this.owner)) {
      const b = crypto.getRandomValues(new Uint8Array(16));
      this.owner = Array.from(b, x => x.toString(16).padStart(2, '0')).join('');
      localStorage.setItem('glint.owner', this.owner);
    }
    this.images = new Requests();   // every image request of the studio (requests.js)
  }

  headers(extra) {
    const h = Object.assign({}, extra || {});
    if (this.token) h['X-Glint-Token'] = this.token;
    if (this.apiKey) h['Authorization'] = 'Bearer ' + this.apiKey;
    return h;
  }

  // A URL that carries the token itself (img src, downloads, SSE).
  url(path, query) {
    const q = new URLSearchParams(query || {});
    if (this.token) q.set('token', this.token);
    const s = q.toString();
    return API + path + (s ? (path.includes('?') ? '&' : '?') + s : '');
  }

  async request(method, path, { body, type, query, what, signal, raw, headers } = {}) {
    const h = this.headers(headers);
    if (/^\/(scenes|environments|materials)(\/|$)/.test(path)) h['X-Glint-Owner'] = this.owner;
    let payload = body;
    if (body !== undefined && !(body instanceof Uint8Array) && !(body instanceof Blob) && !(body instanceof ArrayBuffer)) {
      payload = JSON.stringify(body);
      h['Content-Type'] = 'application/json';
    } else if (type) h['Content-Type'] = type;
    const q = query ? '?' + new URLSearchParams(query).toString() : '';
    let r;
    try {
      r = await fetch(API + path + q, { method, headers: h, body: payload, signal, cache: 'no-store' });
    } catch (e) {
      if (e.name === 'AbortError') throw e;
      throw new ApiError(0, { title: 'Network error', detail: 'glintd cannot be reached (' + e.message + ')' }, what);
    }
    if (!r.ok) {
      let problem = null;
      const ct = r.headers.get('Content-Type') || '';
      try {
        problem = ct.includes('json') ? await r.json() : { title: r.statusText, detail: (await r.text()).slice(0, 300) };
      } catch (_) { problem = { title: r.statusText }; }
      const e = new ApiError(r.status, problem, what);
      e.retryAfter = r.headers.get('Retry-After');
      throw e;
    }
    if (raw) return r;
    if (r.status === 204) return null;
    return r.json();
  }

  get(path, opt) { return this.request('GET', path, opt); }
  post(path, body, opt) { return this.request('POST', path, Object.assign({ body }, opt)); }
  put(path, body, opt) { return this.request('PUT', path, Object.assign({ body }, opt)); }

  // ---- the calls the studio makes ------------------------------------------------
  createScene(spec) { return this.post('/scenes', spec, { what: 'Creating the scene' }); }
  listScenes() { return this.get('/scenes', { what: 'Listing scenes' }); }
  deleteScene(id) { return this.request('DELETE', '/scenes/' + id, { what: 'Deleting the scene' }); }
  scene(id) { return this.get('/scenes/' + id, { what: 'Reading the scene' }); }
  uploadMesh(bytes, format) {
    return this.request('POST', '/meshes', { body: bytes, type: 'application/octet-stream', query: { format }, what: 'Uploading the mesh' });
  }
  // the daemon's demo session with its paint token; null where it has none (204)
  demo() { return this.get('/demo', { what: 'Reading the demo session' }); }
  createSession(sceneId) { return this.post('/sessions', { scene_id: sceneId }, { what: 'Creating the session' }); }
  session(id) { return this.get('/sessions/' + id, { what: 'Reading the session' }); }
  replaceTokens(sid, body) { return this.post(`/sessions/${sid}/tokens`, body, { what: 'Replacing the links' }); }
  postStrokes(sid, k, strokes) {
    return this.post(`/sessions/${sid}/views/${k}/strokes`, { strokes }, { what: 'Sending the stroke' });
  }
  putPainting(sid, k, bytes) {
    return this.request('PUT', `/sessions/${sid}/views/${k}/painting`, { body: bytes, type: 'image/x-exr', what: 'Uploading the painting' });
  }
  painting(sid, k, format, signal) {
    return this.request('GET', `/sessions/${sid}/views/${k}/painting`, { query: { format: format || 'exr' }, raw: true, signal, what: 'Reading the painting of view ' + k });
  }
  base(sceneId, k, format, signal) {
    return this.request('GET', `/scenes/${sceneId}/views/${k}/base.png`, { query: format ? { format } : undefined, raw: true, signal, what: 'Reading the base render of view ' + k });
  }
  strokes(sid, since, limit) { return this.get(`/sessions/${sid}/strokes`, { query: { since, limit: limit || 1000 }, what: 'Reading strokes' }); }
  environments() { return this.get('/environments', { what: 'Reading the environments' }); }
  measured() { return this.get('/measured', { what: 'Reading the measured materials' }); }
  uploadEnvironment(bytes, name) {
    return this.request('POST', '/environments', { body: bytes, type: 'application/octet-stream', query: { name }, what: 'Uploading the environment' });
  }
  methods(sid) { return this.get('/methods', { query: { session_id: sid }, what: 'Reading the fit methods' }); }
  fit(sid, body) { return this.request('POST', `/sessions/${sid}/fits`, { body, raw: true, what: 'Fitting' }); }
  job(id) { return this.get('/jobs/' + id, { what: 'Reading the job' }); }
  material(id) { return this.get('/materials/' + id, { what: 'Reading the material' }); }
  materials(sid) { return this.get(`/sessions/${sid}/materials`, { what: 'Listing materials' }); }
  // headers: e.g. { Priority: 'u=6' } for a render glintd may run after
  // interactive work (requests.js).
  materialFile(id, file, query, signal, headers) {
    return this.request('GET', `/materials/${id}/${file}`, { query, raw: true, signal, headers, what: 'Reading ' + file });
  }
}

// Parse the studio's hash route: "#/session/ID?token=T&view=K" (the form
// of the links glintd hands out) or "#/" (start).
export function parseRoute(hash) {
  const h = (hash || '').replace(/^#/, '');
  const [path, qs] = h.split('?');
  const q = new URLSearchParams(qs || '');
  const m = /^\/session\/([0-9a-f]{32})\/?$/.exec(path || '');
  if (m) return { name: 'session', id: m[1], token: q.get('token') || '', view: q.has('view') ? +q.get('view') : null };
  return { name: 'start' };
}

export function sessionHash(id, token, view) {
  return '#/session/' + id + '?token=' + encodeURIComponent(token) + (view != null ? '&view=' + view : '');
}
