// app.js: the glint studio.  Start page (new scene and session, join by
// link, scenes on the server), then the studio of one session: views,
// paint canvas and brush, fit, judge, export, presence and activity.
// Everything it knows comes from glintd's API (api.js).

import { Api, ApiError, parseRoute, sessionHash } from './api.js';
import { Session } from './session.js';
import { Painter } from './painter.js';
import { blit } from './image.js';
import { bindPhoto, cancelPhoto, onSurface, renderPhoto, stagePhoto } from './photo.js';
import { bindPresets } from './presets.js';
import { bindGuide } from './guide.js';
import { methodNamed, methodOf, sizeText } from './methods.js';
import { envLabels, errorMeaning, pct, relError, sessionLevel } from './words.js';

const $ = id => document.getElementById(id);
const api = new Api();
const state = { session: null, painter: null, fit: null, judge: null, k: 0, tool: 'paint', photo: null };
window.glint = { state, api, closeStudio };     // for the tests and the curious

// ---- toasts ---------------------------------------------------------------------------

function toast(title, detail, kind, ms) {
  const t = document.createElement('div');
  t.className = 'toast' + (kind ? ' ' + kind : '');
  const x = document.createElement('button'); x.className = 'x'; x.textContent = '×'; x.title = 'Dismiss';
  x.onclick = () => t.remove();
  const a = document.createElement('div'); a.className = 't'; a.textContent = title;
  const b = document.createElement('div'); b.className = 'd'; b.textContent = detail || '';
  t.append(x, a, b);
  $('toasts').appendChild(t);
  setTimeout(() => t.remove(), ms || (kind === 'error' ? 12000 : 4000));
  return t;
}

function showError(e) {
  if (e && e.name === 'AbortError') return;
  if (e instanceof ApiError) {
    const p = e.problem || {};
    toast((e.what ? e.what + ' — ' : '') + (p.title || 'Error') + (e.status ? ' (' + e.status + ')' : ''), p.detail || e.message, 'error');
  } else {
    // an Error may carry a title of its own (fit.js says "nothing painted yet" so)
    toast(e && e.title ? e.title : 'Error', e && e.message ? e.message : String(e), 'error');
  }
  // kept for the tests: what the person was told
  (window.glint.errors = window.glint.errors || []).push(e instanceof ApiError ? { status: e.status, ...e.problem } : { detail: String(e && e.message) });
}
window.addEventListener('unhandledrejection', ev => { showError(ev.reason); ev.preventDefault(); });

// ---- names and recent sessions -------------------------------------------------------------

function myName() {
  let n = localStorage.getItem('glint.name');
  if (!n) {
    const a = ['amber', 'cobalt', 'coral', 'jade', 'ochre', 'slate', 'teal', 'umber', 'violet', 'sienna'];
    n = a[Math.floor(Math.random() * a.length)] + '-' + Math.floor(100 + Math.random() * 900);
    localStorage.setItem('glint.name', n);
  }
  return n;
}
function hue(s) { let h = 0; for (const c of s) h = (h * 31 + c.charCodeAt(0)) % 360; return h; }

function remember(doc, scene, token) {
  const list = JSON.parse(localStorage.getItem('glint.recent') || '[]').filter(r => r.id !== doc.id);
  list.unshift({ id: doc.id, token, mesh: scene.mesh, size: scene.width + '×' + scene.height, access: doc.access, at: Date.now() });
  localStorage.setItem('glint.recent', JSON.stringify(list.slice(0, 12)));
}

// ---- start page ------------------------------------------------------------------------------

let startBound = false;
async function showStart() {
  $('studio').classList.add('hidden');
  $('denied').classList.add('hidden');
  document.title = 'glint studio';
  $('start').classList.remove('hidden');
  $('share-btn').classList.add('hidden');
  $('crumbs').textContent = 'material design by painting';
  $('presence').textContent = '';
  $('conn').className = 'conn hidden';
  if (!startBound) bindStart();
  renderRecent();
  loadScenes();
}

// The sessions this browser remembers, and the daemon's demo session first
// (GET /demo: one every visitor may paint) once it has answered.
function renderRecent() {
  renderRecentList(null);
  demoEntry().then(d => { if (d) renderRecentList(d); });
}

// The demo session as an entry of the list, or null where the daemon has
// none (or cannot say: the remembered sessions stay listed).
async function demoEntry() {
  try {
    const s = await api.demo();
    if (!s) return null;
    const sc = await api.scene(s.scene_id);
    return { id: s.id, token: s.paint_token, mesh: sc.mesh, size: sc.width + '×' + sc.height, demo: true };
  } catch (_) {
    return null;
  }
}

function renderRecentList(demo) {
  const ul = $('recent');
  ul.textContent = '';
  const mine = JSON.parse(localStorage.getItem('glint.recent') || '[]');
  const list = demo ? [demo, ...mine.filter(r => r.id !== demo.id)] : mine;
  if (!list.length) { ul.innerHTML = '<li class="muted">none yet</li>'; return; }
  for (const r of list) {
    const li = document.createElement('li');
    const s = document.createElement('span');
    if (r.demo) {
      li.className = 'demo';
      s.textContent = `Demo: ${r.mesh} ${r.size}`;
      s.title = 'This server\'s demo session: everyone who opens the studio here can paint it';
    } else s.textContent = `${r.mesh} ${r.size} · ${r.access === 'view' ? 'view only · ' : ''}${new Date(r.at).toLocaleString()}`;
    const b = document.createElement('a'); b.className = 'button'; b.textContent = 'Open'; b.href = sessionHash(r.id, r.token);
    li.append(s, b); ul.appendChild(li);
  }
}

async function loadScenes() {
  const ul = $('scenes');
  try {
    const r = await api.listScenes();
    ul.textContent = '';
    if (!r.scenes.length) { ul.innerHTML = '<li class="muted">none yet</li>'; return; }
    for (const sc of r.scenes.slice().reverse()) {
      const li = document.createElement('li');
      const s = document.createElement('span');
      s.textContent = `${sc.mesh} ${sc.width}×${sc.height} · ${sc.views.length} views · ${sc.id.slice(0, 8)}`;
      s.title = sc.id;
      const b = document.createElement('button'); b.textContent = 'New session';
      b.onclick = () => startSession(sc).catch(showError);
      const del = document.createElement('button'); del.textContent = 'Delete'; del.className = 'danger';
      del.title = 'Delete this scene with its sessions (materials stay)';
      del.onclick = async () => {
        if (!confirm('Delete this scene and every session painted on it? Materials stay.')) return;
        try { await api.deleteScene(sc.id); loadScenes(); } catch (e) { showError(e); }
      };
      li.append(s, b, del); ul.appendChild(li);
    }
  } catch (e) {
    ul.innerHTML = '';
    const li = document.createElement('li'); li.className = 'muted';
    li.textContent = e.message;
    ul.appendChild(li);
  }
}

function bindStart() {
  startBound = true;
  let mesh = 'sphere', meshId = null;
  for (const b of $('shape-seg').querySelectorAll('button')) {
    b.onclick = () => {
      for (const o of $('shape-seg').querySelectorAll('button')) o.classList.toggle('on', o === b);
      mesh = b.dataset.mesh;
      $('mesh-drop').classList.toggle('hidden', mesh !== 'upload');
    };
  }
  const upload = async file => {
    const ext = (file.name.split('.').pop() || '').toLowerCase();
    if (!['ply', 'obj', 'off', 'gltf', 'glb', 'dae'].includes(ext)) { toast('Not a mesh file', `"${file.name}": use PLY, OBJ, OFF, glTF, GLB or DAE`, 'error'); return; }
    $('mesh-info').textContent = 'uploading ' + file.name + '…';
    try {
      const m = await api.uploadMesh(new Uint8Array(await file.arrayBuffer()), ext);
      meshId = m.id;
      $('mesh-info').textContent = `${file.name}: ${m.triangles} triangles, ${m.vertices} vertices` + (m.report && m.report.normals_generated ? ', normals generated' : '');
    } catch (e) { meshId = null; $('mesh-info').textContent = ''; showError(e); }
  };
  $('mesh-file').onchange = e => e.target.files[0] && upload(e.target.files[0]);
  const dz = $('mesh-drop');
  dz.ondragover = e => { e.preventDefault(); dz.classList.add('over'); };
  dz.ondragleave = () => dz.classList.remove('over');
  dz.ondrop = e => { e.preventDefault(); dz.classList.remove('over'); if (e.dataTransfer.files[0]) upload(e.dataTransfer.files[0]); };
  api.environments().then(r => {
    const names = envLabels(r.environments);
    for (const e of r.environments) {
      const o = document.createElement('option'), l = names.get(e.spec);
      o.value = e.spec; o.textContent = l.text; o.title = l.title;
      $('base-light-sel').appendChild(o);
    }
  }).catch(() => { /* the point lights stay available */ });
  $('create-btn').onclick = async () => {
    const size = +$('size-sel').value;
    // paint at a multiple of the raster (the fit still samples the raster):
    // the painted image up to 512 a side, at most 4x
    const spec = { width: size, height: size, views: $('viewset-sel').value,
                   paint_scale: Math.max(1, Math.min(4, Math.floor(512 / size))) };
    if ($('base-light-sel').value) spec.base = { env: { spec: $('base-light-sel').value } };
    if (mesh === 'upload') {
      if (!meshId) { toast('No mesh yet', 'Upload a mesh file first, or pick a built-in shape.', 'error'); return; }
      spec.mesh_id = meshId;
    } else spec.mesh = mesh;
    $('create-btn').disabled = true;
    $('create-status').textContent = 'rendering the views…';
    try {
      const sc = await api.createScene(spec);
      await startSession(sc);
    } catch (e) { showError(e); } finally { $('create-btn').disabled = false; $('create-status').textContent = ''; }
  };
  $('join-btn').onclick = () => {
    const v = $('join-link').value.trim();
    const i = v.indexOf('#');
    const r = parseRoute(i >= 0 ? v.slice(i) : v);
    if (r.name !== 'session') { toast('Not a session link', 'A link looks like …/#/session/<id>?token=<token>', 'error'); return; }
    location.hash = sessionHash(r.id, r.token);
  };
  $('apikey').value = api.apiKey;
  $('apikey-save').onclick = () => { api.apiKey = $('apikey').value.trim(); localStorage.setItem('glint.apiKey', api.apiKey); loadScenes(); };
}

async function startSession(scene) {
  const s = await api.createSession(scene.id);
  location.hash = sessionHash(s.id, s.paint_token, firstView(scene));
}

// The view a new scene opens on: the one that shows the most of the object
// lit (its samples), seen from above or level, so that a torus does not
// open edge-on; view 0 unless another shows at least 10% more.
function firstView(scene) {
  const vs = (scene.views || []).map((v, k) => ({ k, n: v.samples || 0, up: (v.eye[2] - ((v.target || [0, 0, 0])[2])) >= -1e-9 }));
  const pool = vs.some(v => v.up) ? vs.filter(v => v.up) : vs;
  const best = pool.reduce((a, b) => (b.n > a.n ? b : a), pool[0] || { k: 0, n: 0 });
  return vs.length && vs[0].up && vs[0].n >= 0.9 * best.n ? 0 : best.k;
}

// ---- studio ------------------------------------------------------------------------------

async function openStudio(route) {
  performance.mark('glint-open');
  $('start').classList.add('hidden');
  $('denied').classList.add('hidden');
  $('studio').classList.remove('hidden');
  api.token = route.token;
  const S = new Session(api, route.id, route.token, myName());
  state.session = S;
  let k0;
  try {
    k0 = await S.open(route.view);
  } catch (e) {
    $('crumbs').textContent = 'cannot open this session';
    if (e instanceof ApiError && e.access) {
      state.session = null;                // nothing of it is open: no stream, no panels
      showDenied(e);
    } else showError(e);
    return;
  }
  remember(S.doc, S.scene, route.token);
  setupStudioUI(S);
  autoExpose(S, k0);
  selectView(k0, true);
  performance.mark('glint-paintable');
  window.glint.paintableMs = performance.now();
  document.body.dataset.ready = '1';
  // everything else follows
  S.connect();
  S.loadRest().then(() => { if (!S.closed) for (const v of S.views) drawThumb(v.k); }).catch(e => { if (!S.closed) showError(e); });
  loadFitAndMaterials(S).catch(showError);
}

// A scene painted under an environment reads in the environment's own
// radiance, often far above 1 (a sky at noon): the display exposure starts
// at the largest of the offered steps that keeps the first view's base
// render's 99th percentile of brightness at most 1, so its thumbnails and
// canvas do not open pure white.  Point-lit scenes keep 1x: there a white
// matte surface facing the lamp reads 1.
function autoExpose(S, k) {
  const v = S.views[k], env = S.scene && S.scene.base && S.scene.base.env;
  if (!env || !v || !v.base) return;
  const d = v.base.data, lum = [];
  for (let i = 0; i < d.length; i += 3) {
    const y = 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
    if (y > 0) lum.push(y);
  }
  if (!lum.length) return;
  lum.sort((a, b) => a - b);
  const p99 = lum[Math.min(lum.length - 1, Math.floor(0.99 * lum.length))];
  const sel = $('exposure');
  const steps = [...sel.options].map(o => +o.value).sort((a, b) => b - a);
  const e = steps.find(x => p99 * x <= 1) || steps[steps.length - 1];
  sel.value = String(e);
  state.painter.setExposure(e);
  sel.title = `Display exposure (does not change the painting); set to ${sel.selectedOptions[0].textContent} ` +
    'so the environment-lit view is not blown out';
}

// The session link does not open the session (glintd refused the session
// document: 401 no token, 403 a token that is not this session's, 404 no
// such session): say so on a page of its own, not in a studio that cannot
// work.
function showDenied(e) {
  let why = {
    401: ['This link has no token',
      'A session link ends in "?token=…", the key to the session. This one has none: it was probably cut short when it was copied. Ask for the link again and paste it whole.'],
    403: ['This link\'s token does not open the session',
      'The link may be wrong, cut short or expired: its token is not one of this session\'s. Ask whoever shared it for the link again and paste it whole.'],
    404: ['This session does not exist',
      'The link may be wrong or expired: there is no such session on this server (it may have been deleted). Check the link, or start a new session.'],
  }[e.status];
  if (e.status === 403 && /(^|\/)link-expired$/.test((e.problem || {}).type || ''))
    why = ['This link has expired',
      'The session\'s links were set to stop working after a while, and this one has. Ask whoever shared it for new links: the scene\'s owner can issue them.'];
  $('studio').classList.add('hidden');
  $('start').classList.add('hidden');
  $('share-btn').classList.add('hidden');
  $('conn').className = 'conn hidden';
  $('denied-title').textContent = why[0];
  $('denied-text').textContent = why[1];
  const p = e.problem || {};
  $('denied-detail').textContent = `glintd answered ${e.status}${p.detail ? ': ' + p.detail : p.title ? ': ' + p.title : ''}.`;
  $('denied').classList.remove('hidden');
  document.title = why[0] + ' · glint studio';
}

let uiBound = false;
function setupStudioUI(S) {
  const sc = S.scene;
  $('crumbs').innerHTML = '';
  const b = document.createElement('b'); b.textContent = sc.mesh;
  $('crumbs').append(b, document.createTextNode(` ${sc.width}×${sc.height}${sc.paint_scale > 1 ? ` (painted at ${sc.paint_width})` : ''} · ${sc.views.length} views · session ${S.id.slice(0, 8)}` + (S.canPaint ? '' : ' · view only')));
  $('share-btn').classList.remove('hidden');
  $('readonly-badge').classList.toggle('hidden', S.canPaint);
  bindGuide(S.canPaint);
  $('viewport').classList.toggle('readonly', !S.canPaint);
  for (const id of ['undo', 'redo']) $(id).disabled = true;
  for (const el of $('toolbar').querySelectorAll('input, button')) if (!S.canPaint && !['pick', 'pan'].includes(el.dataset.tool)) el.disabled = true;
  if (!S.canPaint) state.tool = 'pan';     // a view-only link drags to look around
  $('fit-btn').disabled = true;            // the fit panel enables it (fit.js)
  $('fit-btn').title = 'loading the fit methods…';

  // thumbnails
  const th = $('thumbs');
  th.textContent = '';
  for (const v of S.views) {
    const bt = document.createElement('button');
    bt.className = 'thumb'; bt.dataset.k = v.k;
    bt.title = `view ${v.k} (${v.k < 9 ? 'key ' + (v.k + 1) : 'arrows'}) · ${sc.views[v.k].samples} pixels of the object`;
    const c = document.createElement('canvas'); c.width = sc.paint_width || sc.width; c.height = sc.paint_height || sc.height;
    const lab = document.createElement('span'); lab.className = 'k'; lab.textContent = v.k;
    const dot = document.createElement('span'); dot.className = 'dot'; dot.title = 'painted';
    bt.append(c, lab, dot);
    bt.onclick = () => selectView(v.k);
    th.appendChild(bt);
  }

  const painter = new Painter({
    viewport: $('viewport'), stage: $('stage'), paint: $('paint'), base: $('overlay-base'), photo: $('overlay-photo'), cursor: $('cursor'),
  }, S, brush);
  state.painter = painter;
  painter.addEventListener('error', e => showError(e.detail));
  painter.addEventListener('zoom', e => { $('zoom-v').textContent = Math.round(e.detail * 100) + '%'; });
  painter.addEventListener('hover', e => {
    const d = e.detail;
    $('st-px').textContent = d ? `x ${d.x} y ${d.y} · ${d.rgb.map(x => x.toFixed(3)).join(' ')}` : '';
  });
  painter.addEventListener('pick', e => setColorFrom(e.detail));
  painter.addEventListener('painting', () => {});

  S.addEventListener('view', e => {
    const { k, box } = e.detail;
    if (k === state.k && !state.photo) painter.redraw(box);
    if (k === state.k && state.compare && state.compare.mode === 'diff') state.compare.draw();
    scheduleThumb(k);
  });
  S.addEventListener('event', e => onSessionEvent(e.detail));
  S.addEventListener('painted', e => scheduleThumb(e.detail.k));
  S.addEventListener('presence', e => renderPresence(e.detail));
  S.addEventListener('connection', e => {
    const c = $('conn');
    c.className = 'conn ' + e.detail.state;
    c.textContent = { open: 'live', connecting: 'connecting…', reconnecting: 'reconnecting…', failed: 'disconnected', closed: 'closed' }[e.detail.state] || e.detail.state;
    c.title = e.detail.state === 'failed' ? 'The event stream was refused: ' + e.detail.detail : 'Live updates from the other people in this session';
    if (e.detail.state === 'failed') toast('Live updates stopped', e.detail.detail, 'error');
  });
  S.addEventListener('history', () => updateUndo());
  S.addEventListener('settled', () => updateUndo());
  S.addEventListener('error', e => showError(e.detail));

  for (const v of S.views) if (v.disp) scheduleThumb(v.k);
  if (!uiBound) bindStudioControls();
  uiBound = true;
  updateBrushUI();
  updateUndo();
}

function selectView(k, first) {
  const S = state.session;
  if (!S || k < 0 || k >= S.views.length) return;
  // a photo placed in a view belongs to it; one over the surface follows
  const keepPhoto = state.photo && onSurface();
  if (state.photo && !keepPhoto) cancelPhoto();
  state.k = k;
  if (keepPhoto) renderPhoto();
  for (const t of $('thumbs').children) t.classList.toggle('on', +t.dataset.k === k);
  const v = S.views[k];
  const go = () => {
    state.painter.show(k, !first);
    const sv = S.scene.views[k];
    $('st-view').textContent = `view ${k}` + (sv.light_deg != null ? ` · light ${sv.light_deg.toFixed(0)}°` : '');
    $('st-view').title = `view ${k} · ${sv.samples} pixels of the object this view gives the fit` + (sv.light_deg != null ? ` · light ${sv.light_deg.toFixed(0)}°` : '');
    updateUndo();
    history.replaceState(null, '', sessionHash(S.id, S.token, k));
  };
  if (v.state === 'none') {
    S.loadViews([k]).then(go).catch(showError);
  } else go();
  if (state.judge && state.judge.mat && !state.judge.drag) state.judge.showDiff(k);
  if (state.compare) state.compare.setView(k);
}

// thumbnails: at most one redraw per view per frame
const thumbDirty = new Set();
function scheduleThumb(k) {
  if (!thumbDirty.size) requestAnimationFrame(() => { for (const j of thumbDirty) drawThumb(j); thumbDirty.clear(); });
  thumbDirty.add(k);
}
function drawThumb(k) {
  const S = state.session;
  if (!S) return;                    // closed meanwhile (a redraw was due)
  const v = S.views[k];
  const bt = $('thumbs').children[k];
  if (!bt || !v.disp) return;
  blit(bt.querySelector('canvas').getContext('2d'), v.disp, null, state.painter ? state.painter.exposure : 1);
  bt.classList.toggle('painted', !!v.painted);
}

// ---- brush ---------------------------------------------------------------------------------

function hexToRgb(h) { return [1, 3, 5].map(i => parseInt(h.slice(i, i + 2), 16) / 255); }
function rgbToHex(c) { return '#' + c.map(v => Math.round(Math.min(1, Math.max(0, v)) * 255).toString(16).padStart(2, '0')).join(''); }

// The brush as the server takes it.
function brush() {
  const hdr = $('hdr').checked;
  const inten = hdr ? Math.max(0, +$('intensity').value || 0) : 1;
  const sign = $('neg').checked ? -1 : 1;
  const c = hexToRgb($('color').value).map(v => +(sign * v * inten).toFixed(6));
  return {
    mode: state.tool === 'scale' ? 'scale' : state.tool === 'erase' ? 'erase' : 'paint',
    color: c, diameter: +$('diameter').value, kappa: +$('kappa').value,
    scale: +$('scale').value, opacity: +$('opacity').value,
  };
}

function updateBrushUI() {
  const b = brush();
  $('diameter-v').textContent = b.diameter;
  $('kappa-v').textContent = b.kappa.toFixed(3);
  $('opacity-v').textContent = b.opacity.toFixed(2);
  $('scale-v').textContent = b.scale.toFixed(2);
  $('cval').textContent = '(' + b.color.map(v => v.toFixed(2)).join(', ') + ')';
  $('color').title = 'Brush colour ' + $('cval').textContent;
  for (const [id, v] of [['diameter', b.diameter], ['kappa', b.kappa.toFixed(3)], ['opacity', b.opacity.toFixed(2)], ['scale', b.scale.toFixed(2)]])
    $(id).title = String(v);
  $('intensity').classList.toggle('hidden', !$('hdr').checked);
  $('scale-tb').classList.toggle('hidden', state.tool !== 'scale');
  // the colour matters to painting and picking only (Scale multiplies what is there)
  for (const el of document.querySelectorAll('#toolbar .colour-only'))
    el.classList.toggle('hidden', !(state.tool === 'paint' || state.tool === 'pick'));
  for (const t of $('tools').children) t.classList.toggle('on', t.dataset.tool === state.tool);
  if (state.painter) {
    state.painter.tool = state.tool;
    $('viewport').classList.toggle('pick', state.tool === 'pick');
    $('viewport').classList.toggle('pan', state.tool === 'pan');
    state.painter.drawCursor();
  }
}

function setTool(t) { state.tool = t; updateBrushUI(); }

function setColorFrom(rgb) {
  const mx = Math.max(...rgb.map(Math.abs));
  const neg = rgb.every(v => v <= 0) && mx > 0;
  const c = rgb.map(v => Math.abs(v));
  if (mx > 1) { $('hdr').checked = true; $('intensity').value = mx.toFixed(3); $('color').value = rgbToHex(c.map(v => v / mx)); }
  else { $('hdr').checked = false; $('intensity').value = 1; $('color').value = rgbToHex(c); }
  $('neg').checked = neg;
  if (state.tool === 'pick') state.tool = 'paint';
  updateBrushUI();
  toast('Colour picked', `red ${rgb[0].toFixed(2)}, green ${rgb[1].toFixed(2)}, blue ${rgb[2].toFixed(2)}`);
}

function updateUndo() {
  const S = state.session;
  if (!S) return;
  $('undo').disabled = !S.canUndo(state.k);
  $('redo').disabled = !S.canRedo(state.k);
}

async function doUndo() {
  const S = state.session;
  if (!S.canUndo(state.k)) return;
  try { await S.undo(state.k); } catch (e) { showError(e); }
  updateUndo();
}
async function doRedo() {
  const S = state.session;
  if (!S.canRedo(state.k)) return;
  try { await S.redo(state.k); } catch (e) { showError(e); }
  updateUndo();
}

// ---- session events: activity, presence, fits ------------------------------------------------

function onSessionEvent(ev) {
  const S = state.session;
  if ((ev.type === 'stroke' || ev.type === 'painting') && S.views[ev.view]) {
    const mine = ev.type === 'stroke' && ev.data && String(ev.data.tag || '').startsWith(S.client + '-');
    if (!mine && ev.seq > S.loadSeq) {
      const bt = $('thumbs').children[ev.view];
      if (bt) { bt.classList.remove('flash'); void bt.offsetWidth; bt.classList.add('flash'); }
    }
  }
  if (ev.type === 'fit') onFitEvent(ev);
  addActivity(ev);
}

function addActivity(ev) {
  const ol = $('activity');
  const li = document.createElement('li');
  const t = (ev.created || '').slice(11, 19);
  const d = ev.data || {};
  let what;
  const who = ev.type === 'stroke' && typeof d.tag === 'string' && d.tag.includes('~') ? d.tag.slice(d.tag.indexOf('~') + 1) : '';
  if (ev.type === 'stroke') what = `<b>${d.mode}</b> view ${ev.view} · size ${+(+d.diameter).toFixed(1)}` + (who ? ` <span class="by" style="color:hsl(${hue(who)} 60% 65%)"></span>` : '');
  else if (ev.type === 'painting') what = `<b>image</b> view ${ev.view}`;
  else if (ev.type === 'fit') what = `<b>fit</b> <span class="fitwhat"></span>`;
  else what = `<b>${ev.type}</b>`;
  li.innerHTML = `<span class="num">#${ev.seq}</span> ${what}`;
  const by = li.querySelector('.by');
  if (by) by.textContent = who;
  const fw = li.querySelector('.fitwhat');
  if (fw && d.summary) { const md = methodNamed(d.summary.chosen || d.summary.method); fw.textContent = md ? md.label : ''; }
  li.title = `${ev.type} #${ev.seq} at ${t}` + (ev.type === 'stroke' ? ` · ${JSON.stringify(d).slice(0, 200)}` : '');
  li.dataset.seq = ev.seq;
  if (ev.view != null) li.dataset.view = ev.view;
  const first = ol.querySelector('li');
  if (ev.seq < (first ? +first.dataset.seq || 0 : 0)) ol.insertBefore(li, $('earlier-li'));   // an older one
  else ol.prepend(li);
  const all = ol.querySelectorAll('li[data-seq]');
  for (let i = 600; i < all.length; i++) all[i].remove();
  earlierLink();
}

// "earlier": strokes before the ones the stream replayed (GET /strokes, paged)
function earlierLink() {
  const ol = $('activity');
  const items = [...ol.querySelectorAll('li[data-seq]')];
  const oldest = items.length ? Math.min(...items.map(li => +li.dataset.seq)) : 0;
  let li = $('earlier-li');
  if (oldest <= 1) { if (li) li.remove(); return; }
  if (!li) { li = document.createElement('li'); li.id = 'earlier-li'; li.innerHTML = '<a href="javascript:void 0" id="earlier">earlier…</a>'; }
  ol.appendChild(li);
}

async function loadEarlier() {
  const S = state.session;
  const items = [...$('activity').querySelectorAll('li[data-seq]')];
  const oldest = Math.min(...items.map(li => +li.dataset.seq));
  const from = Math.max(0, oldest - 1 - 300);
  const r = await api.strokes(S.id, from, 300);
  for (const s of r.strokes.filter(s => s.seq < oldest).reverse())
    addActivity({ seq: s.seq, type: 'stroke', view: s.view, data: s.stroke, created: s.created });
  earlierLink();
}

function renderPresence(clients) {
  const box = $('presence');
  box.textContent = '';
  const me = myName();
  let meShown = false;
  for (const c of clients) {
    const d = document.createElement('span');
    d.className = 'who';
    const isMe = c.name === me && !meShown;
    if (isMe) { d.classList.add('me'); meShown = true; }
    d.style.background = `hsl(${hue(c.name || c.id)} 60% 65%)`;
    d.textContent = (c.name || 'anonymous').slice(0, 14);
    d.title = (c.name || 'anonymous') + (isMe ? ' (you)' : '');
    box.appendChild(d);
  }
  box.title = clients.length + ' here';
}

// ---- fits and materials -----------------------------------------------------------------------

async function loadFitAndMaterials(S) {
  const [{ FitPanel }, { Judge }, { Compare }] = await Promise.all([import('./fit.js'), import('./judge.js'), import('./compare.js')]);
  const fit = new FitPanel(api, S);
  const judge = new Judge(api, S);
  state.fit = fit; state.judge = judge;
  state.compare = new Compare(S, judge, state.painter);
  state.compare.setView(state.k);
  fit.addEventListener('error', e => showError(e.detail));
  fit.addEventListener('envs', e => judge.addEnv(e.detail));
  judge.addEventListener('error', e => showError(e.detail));
  judge.addEventListener('reset', () => judge.resetCamera(state.k));
  judge.addEventListener('select-view', e => selectView(e.detail));
  fit.addEventListener('material', e => {
    const { material: m, ms, cached, first } = e.detail;
    addMaterialOption(m, true);
    showMaterial(m);
    showFitResult(m, ms, cached);
    // a first look, shown while a choosing method works, is not the fit
    if (first) window.glint.firstLook = { id: m.id, ms, method: m.method };
    else window.glint.lastFit = { id: m.id, ms, cached };
  });
  $('mat-sel').onchange = async () => {
    const id = $('mat-sel').value;
    if (!id) return;
    try { showMaterial(await api.material(id)); } catch (e) { showError(e); }
  };
  await fit.load().catch(showError);
  const list = await api.materials(S.id);
  const mats = (list.materials || []).slice().sort((a, b) => (a.created || '').localeCompare(b.created || ''));
  for (const m of mats) addMaterialOption(m, false);
  if (mats.length) { const m = mats[mats.length - 1]; $('mat-sel').value = m.id; showMaterial(m); }
  else { const o = document.createElement('option'); o.value = ''; o.textContent = 'no fit yet'; $('mat-sel').appendChild(o); }
}

// The fit's result beside the Fit button: how long it took and its error
// as a percentage of the painting's brightness (the meaning and the RMS in
// the tooltip).
function showFitResult(m, ms, cached) {
  if (!state.session) return;
  const frac = relError(m.errors.rms_painted, sessionLevel(state.session, m.views_used || []));
  const el = $('fit-result');
  el.textContent = '';
  const t = document.createElement('em');
  t.textContent = ms < 1000 ? ms.toFixed(0) + ' ms' : (ms / 1000).toFixed(1) + ' s';
  const e = document.createElement('em');
  e.textContent = frac != null ? pct(frac) : (+m.errors.rms_painted).toFixed(4);
  el.append(t, frac != null ? ' · ' : ' · error ', e, frac != null ? ' off your painting' : '');
  el.title = (frac != null ? errorMeaning(frac) + '. ' : '') + (cached ? 'Quick: the precomputation was in memory.' : 'The precomputation was built first.') +
    ` Advanced: RMS ${(+m.errors.rms_painted).toFixed(4)}.`;
}

// A material's name in the list: its time and what it models; its size
// and RMS in the tooltip.
function materialText(m) {
  const d = methodOf(m), t = (m.created || '').slice(11, 19);
  return { text: `${t} · ${d ? d.label : m.method || ''}`, title: `${sizeText(m)} · RMS ${(+m.errors.rms_painted).toFixed(4)}` + (d ? ` · method ${d.name}` : '') };
}

function addMaterialOption(m, select) {
  const sel = $('mat-sel');
  for (const o of [...sel.options]) if (!o.value) o.remove();
  if (![...sel.options].some(o => o.value === m.id)) {
    const o = document.createElement('option');
    o.value = m.id;
    const l = materialText(m);
    o.textContent = l.text; o.title = l.title;
    sel.appendChild(o);
  }
  if (select) sel.value = m.id;
  const on = sel.selectedOptions[0];
  sel.title = on && on.title ? on.textContent + ' · ' + on.title : 'Materials of this session';
}

function showMaterial(m) {
  state.material = m;
  state.judge.setMaterial(m, state.k);
  if (state.compare) state.compare.update();
}

async function onFitEvent(ev) {
  const S = state.session;
  const id = ev.data && ev.data.material_id;
  if (!id || !state.judge || ev.seq <= S.loadSeq) return;
  // our own fit announces itself before its answer arrives: wait for it
  if (state.fit && state.fit.busy) await state.fit.running;
  if ([...$('mat-sel').options].some(o => o.value === id)) return;   // ours, already shown
  try {
    const m = await api.material(id);
    addMaterialOption(m, $('follow').checked);
    if ($('follow').checked) showMaterial(m);
    const d = methodOf(m), frac = relError(m.errors.rms_painted, sessionLevel(S, m.views_used || []));
    toast('New fit', `${d ? d.label : 'a material'}` + (frac != null ? `, ${pct(frac)} off the painting` : '') + ($('follow').checked ? '' : ' — pick it in the material list'));
    if (state.fit) state.fit.refresh();
  } catch (e) { showError(e); }
}

// ---- controls and keyboard ----------------------------------------------------------------------

function bindStudioControls() {
  bindPresets({ state, api, toast, showError });
  bindPhoto({ state, api, toast, showError });
  // buttons do not keep the keyboard focus (Space would press them again)
  for (const b of document.querySelectorAll('#toolbar button, #statusbar button, #thumbs, .tabs button'))
    b.addEventListener('mousedown', e => { if (e.target.closest('button')) e.preventDefault(); });
  for (const b of $('tools').children) b.onclick = () => setTool(b.dataset.tool);
  $('activity').onclick = e => {
    const li = e.target.closest('li');
    if (li && li.dataset.view !== undefined && li.dataset.view !== '') selectView(+li.dataset.view);
    if (e.target.id === 'earlier') loadEarlier().catch(showError);
  };
  for (const id of ['color', 'neg', 'hdr', 'intensity', 'scale', 'diameter', 'kappa', 'opacity']) $(id).addEventListener('input', updateBrushUI);
  $('undo').onclick = doUndo;
  $('redo').onclick = doRedo;
  $('zoom-in').onclick = () => state.painter.zoomAt(1.25);
  $('zoom-out').onclick = () => state.painter.zoomAt(0.8);
  $('zoom-fit').onclick = () => state.painter.fitToWindow();
  $('base-mix').oninput = () => state.painter.setBaseMix(+$('base-mix').value);
  $('exposure').onchange = () => { state.painter.setExposure(+$('exposure').value); for (const v of state.session.views) drawThumb(v.k); if (state.compare) state.compare.draw(); };

  const vp = $('viewport');
  vp.addEventListener('dragover', e => { e.preventDefault(); $('drop-hint').classList.remove('hidden'); });
  vp.addEventListener('dragleave', () => $('drop-hint').classList.add('hidden'));
  vp.addEventListener('drop', e => {
    e.preventDefault();
    $('drop-hint').classList.add('hidden');
    const f = e.dataTransfer.files[0];
    if (f) stagePhoto(f).catch(showError);
  });

  $('share-btn').onclick = () => {
    const S = state.session, L = S.doc.links || {};
    const abs = p => location.origin + location.pathname + p.replace(/^\//, '');
    $('link-paint').value = L.paint ? abs(L.paint) : '(this is a view-only link)';
    $('link-view').value = L.view ? abs(L.view) : '';
    $('my-name').value = myName();
    $('links-manage').classList.toggle('hidden', !L.paint);
    $('links-expiry').textContent = S.doc.expires ? `(these expire ${new Date(S.doc.expires).toLocaleString()})` : '(these never expire)';
    $('share-dlg').classList.remove('hidden');
  };
  // new tokens for the session: the old links stop working at once (and
  // their live streams end); this studio reopens on the new paint link
  $('links-replace').onclick = async () => {
    const S = state.session, v = $('links-expires-in').value;
    try {
      const doc = await api.replaceTokens(S.id, { revoke: 'both', expires_in: v ? +v : null });
      toast('Links replaced', 'The old links no longer open this session.' + (doc.expires ? ' The new ones expire ' + new Date(doc.expires).toLocaleString() + '.' : ''));
      $('share-dlg').classList.add('hidden');
      location.hash = sessionHash(S.id, doc.paint_token, state.k);
    } catch (e) { showError(e); }
  };
  $('share-close').onclick = () => $('share-dlg').classList.add('hidden');
  for (const b of document.querySelectorAll('[data-copy]')) {
    b.onclick = async () => {
      const inp = $(b.dataset.copy);
      inp.select();
      try { await navigator.clipboard.writeText(inp.value); toast('Copied', inp.value); }
      catch (_) { document.execCommand('copy'); }
    };
  }
  $('name-save').onclick = () => {
    const n = $('my-name').value.trim().slice(0, 40);
    if (!n) return;
    localStorage.setItem('glint.name', n);
    const S = state.session;
    S.name = n;
    if (S.stream) { S.stream.opts.query.name = n; S.stream.drop(); }   // presence shows the new name
    $('share-dlg').classList.add('hidden');
  };
  $('help-btn').onclick = () => $('help-dlg').classList.toggle('hidden');
  $('help-close').onclick = () => $('help-dlg').classList.add('hidden');

  document.addEventListener('keydown', onKey);
  document.addEventListener('keyup', e => {
    if (e.code === 'Space' && state.painter) { state.painter.spaceHeld = false; $('viewport').classList.remove('pan'); state.painter.drawCursor(); }
  });
}

function onKey(e) {
  if ($('studio').classList.contains('hidden') || !state.session) return;
  const tag = (e.target.tagName || '').toLowerCase();
  const typing = (tag === 'input' && !['range', 'checkbox', 'radio', 'color'].includes(e.target.type)) || tag === 'textarea' || tag === 'select';
  if (e.key === 'Escape') {
    for (const d of ['share-dlg', 'help-dlg']) $(d).classList.add('hidden');
    if (state.photo) cancelPhoto();
    return;
  }
  if (typing) return;
  // a focused slider keeps its arrow keys
  if (e.target.type === 'range' && /^Arrow/.test(e.key)) return;
  const S = state.session, ctrl = e.ctrlKey || e.metaKey;
  if (ctrl && (e.key === 'z' || e.key === 'Z')) { e.preventDefault(); if (e.shiftKey) doRedo(); else doUndo(); return; }
  if (ctrl && (e.key === 'y' || e.key === 'Y')) { e.preventDefault(); doRedo(); return; }
  if (ctrl || e.altKey) return;
  const n = S.views.length;
  if (/^[1-9]$/.test(e.key)) { if (+e.key - 1 < n) selectView(+e.key - 1); e.preventDefault(); return; }
  switch (e.key) {
    case 'ArrowRight': case 'ArrowDown': selectView((state.k + 1) % n); e.preventDefault(); return;
    case 'ArrowLeft': case 'ArrowUp': selectView((state.k + n - 1) % n); e.preventDefault(); return;
    case '[': case ']': {
      const d = $('diameter'), v = +d.value;
      d.value = e.key === ']' ? Math.min(+d.max, Math.max(v + 1, Math.round(v * 1.2))) : Math.max(+d.min, Math.min(v - 1, Math.round(v / 1.2)));
      updateBrushUI(); return;
    }
    case 'b': case 'B': setTool('paint'); return;
    case 's': case 'S': setTool('scale'); return;
    case 'e': case 'E': setTool('erase'); return;
    case 'i': case 'I': setTool('pick'); return;
    case 'h': case 'H': setTool('pan'); return;
    case 'n': case 'N': $('neg').checked = !$('neg').checked; updateBrushUI(); return;
    case '+': case '=': state.painter.zoomAt(1.25); return;
    case '-': case '_': state.painter.zoomAt(0.8); return;
    case '0': state.painter.fitToWindow(); return;
    case 'f': case 'F': if (state.fit && S.canPaint) state.fit.fit(); return;
    case '?': $('help-dlg').classList.toggle('hidden'); return;
    case ' ':
      if (e.target === document.body || e.target === $('viewport')) {
        e.preventDefault();
        state.painter.spaceHeld = true; $('viewport').classList.add('pan'); state.painter.drawCursor();
      }
      return;
  }
}

// ---- routing ----------------------------------------------------------------------------------------

// Close the open session: its stream stops and nothing it still has in
// flight reaches the studio (the page reloads to open another; until the
// new page commits, the old one runs on).
function closeStudio() {
  if (!state.session) return;
  state.session.close();
  state.session = null;
}

let current = null;
function route() {
  const r = parseRoute(location.hash);
  const key = r.name === 'session' ? r.id + '/' + r.token : 'start';
  if (key === current) {
    if (r.name === 'session' && r.view != null && r.view !== state.k) selectView(r.view);
    return;
  }
  current = key;
  if (state.session) { closeStudio(); location.reload(); return; }
  if (r.name === 'session') openStudio(r).catch(showError);
  else showStart().catch(showError);
}
window.addEventListener('hashchange', route);
route();
