// judge.js: judging a material: a preview that follows the mouse (the
// light or the camera orbit the object; glintd renders each frame:
// GET /materials/{id}/preview.png?eye=&light=&size=), the error per view
// (painted versus fitted, computed here from the painting and a render of
// the material for that view, with a difference image), the three factor
// curves (factors.exr) and the exports (each a download with its file
// name and how close it comes to the fitted material).

import { decodeImage, resizeImage } from './image.js';
import { fmtErr, fmtTime } from './fit.js';
import { drawEnergy, drawLobe, isLobeMaterial } from './lobe.js';
import { methodNamed, shows, sizeText, underEnv } from './methods.js';
import { SurfacePanel } from './surface.js';
import { envLabels, errorMeaning, Level, pct, relError, sessionLevel } from './words.js';
import { loadSummary, renderSummary } from './summary.js';
import { Ball } from './ball.js';
import { CLASS, isAbort } from './requests.js';

const $ = id => document.getElementById(id);
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
const len = a => Math.hypot(a[0], a[1], a[2]);
const mul = (a, s) => [a[0] * s, a[1] * s, a[2] * s];

// Spherical coordinates about +z (the scene's world up).
function toSph(v) { const r = len(v); return { r, az: Math.atan2(v[1], v[0]), el: Math.asin(Math.max(-1, Math.min(1, v[2] / r))) }; }
function fromSph(s) { const c = Math.cos(s.el); return [s.r * c * Math.cos(s.az), s.r * c * Math.sin(s.az), s.r * Math.sin(s.el)]; }

// The export formats by the names artists know them by.
const EXPORT_NAMES = {
  glb: 'glTF (.glb)', mtlx: 'MaterialX (.mtlx)', mtlx_zip: 'MaterialX with textures (.zip)',
  usda: 'USD (.usda)', usdz: 'USD with textures (.usdz)',
  merl: 'MERL table (.binary)',
  brdf: 'BRDF Explorer (.brdf)', package: 'glint package (.tar)',
};

// How close an export comes to the fitted material, in a few words.
function howClose(c) {
  if (c.exact) return 'Exactly the fitted material.';
  if (c.rel_rms == null) return c.note;
  const p = 100 * c.rel_rms;
  return (p < 0.1 ? 'Under 0.1%' : p.toFixed(p < 10 ? 1 : 0) + '%') + ' off the fitted material.';
}

function exportNote(text) {
  const li = document.createElement('li');
  li.className = 'small muted';
  li.textContent = text;
  return li;
}

export class Judge extends EventTarget {
  constructor(api, session) {
    super();
    this.api = api;
    this.session = session;
    this.mat = null;
    this.cam = null;           // {eye, light, target}
    this.inflight = false;
    this.want = 0;             // number of the newest request wanted
    this.shown = 0;            // number of the frame on screen
    this.frames = 0;
    this.errView = null;
    this.bindPreview();
    this.bindTabs();
    $('diff-gain').onchange = () => this.showDiff(this.errView);
    $('factors-log').onchange = () => this.drawFactors();
    this.surface = new SurfacePanel(api, session);
    this.surface.onProduct = () => this.drawFactors();
    this.ball = new Ball(api);
    this.ball.addEventListener('error', e => this.emit('error', e.detail));
    this.bindEnv();
  }

  // ---- the light of the preview: the point light or an environment -------------------

  bindEnv() {
    const sel = $('preview-light');
    this.api.environments().then(r => {
      const names = envLabels(r.environments);
      for (const e of r.environments) {
        const o = document.createElement('option'), l = names.get(e.spec);
        o.value = e.spec; o.textContent = l.text; o.title = l.title;
        sel.appendChild(o);
        this.ball.addEnv({ spec: e.spec, name: o.textContent, title: l.title });
      }
      if (this.mat) this.envDefault(this.mat);
    }).catch(e => this.emit('error', e));
    sel.onchange = () => { this.showEnvBar(); this.request(); };
    $('env-rot').oninput = () => { this.showEnvBar(); this.request(); };
  }

  // An environment uploaded in this studio: offered to the previews too.
  addEnv(e) {
    const o = document.createElement('option');
    o.value = e.spec; o.textContent = e.name;
    if (e.title) o.title = e.title;
    $('preview-light').appendChild(o);
    this.ball.addEnv(e);
  }

  // The environment of the preview ('' for the point light).
  envSpec() { return $('preview-light').value; }

  showEnvBar() {
    const on = !!this.envSpec();
    $('env-rot-l').classList.toggle('hidden', !on);
    $('env-rot-v').textContent = $('env-rot').value + '°';
    $('preview-hint').textContent = on ? 'drag: turn the environment · shift-drag: camera · wheel: zoom · dbl-click: reset'
                                       : 'drag: light · shift-drag: camera · wheel: zoom · dbl-click: reset';
  }

  // A material fitted under an environment is previewed under it.
  envDefault(m) {
    const sel = $('preview-light');
    if (underEnv(m) && [...sel.options].some(o => o.value === m.params.env)) {
      sel.value = m.params.env;
      $('env-rot').value = String(Math.round(m.params.env_rotation || 0));
    }
    this.showEnvBar();
  }

  envQuery() {
    const spec = this.envSpec();
    if (!spec) return {};
    const m = this.mat, lights = m && underEnv(m) ? m.params.lights : 256;
    return { env: spec, env_rotation: $('env-rot').value, lights: String(Math.min(1024, lights || 256)) };
  }

  // A superseded request's AbortError is no error to show.
  emit(type, detail) {
    if (type === 'error' && isAbort(detail)) return;
    this.dispatchEvent(new CustomEvent(type, { detail }));
  }

  bindTabs() {
    for (const b of document.querySelectorAll('.tabs button')) {
      b.onclick = () => {
        for (const o of document.querySelectorAll('.tabs button')) o.classList.toggle('on', o === b);
        for (const t of ['errors', 'factors', 'summary', 'export']) $('tab-' + t).classList.toggle('hidden', t !== b.dataset.tab);
        if (b.dataset.tab === 'factors' && this.mat) { const w = shows(this.mat); if (w === 'lobes') this.drawLobe(); else if (w === 'factors') this.drawFactors(); }
        if (b.dataset.tab === 'export' && this.mat) this.showExports(this.mat);
      };
    }
  }

  // ---- the material ------------------------------------------------------------------

  async setMaterial(m, k) {
    if (this.mat && this.mat.id !== m.id) this.api.images.abortPrefix('reference:', 'another material is shown');
    this.mat = m;
    this.envDefault(m);
    this.markStale();
    const what = shows(m), lobe = what === 'lobes', factors = what === 'factors';
    $('factors-wrap').classList.toggle('hidden', !factors);
    $('lobe-wrap').classList.toggle('hidden', !lobe);
    $('factors-none').classList.toggle('hidden', what !== 'none');
    $('factors-tab-btn').textContent = lobe ? 'Lobe' : 'Factors';
    $('dl-factors').classList.toggle('hidden', !factors);
    $('preview-empty').textContent = 'rendering…';
    $('preview-empty').classList.toggle('hidden', this.frames > 0);
    this.resetCamera(k);
    this.ball.setMaterial(m);
    const q = t => this.api.url(`/materials/${m.id}/${t}`);
    $('dl-factors-png').href = q('factors.png');
    $('dl-factors-exr').href = q('factors.exr');
    this.exportsOf = null;
    if (!$('tab-export').classList.contains('hidden')) this.showExports(m);
    this.factors = null;
    this.manifest = null;
    if (lobe) this.loadManifest().catch(e => this.emit('error', e));
    else if (factors) this.loadFactors().catch(e => this.emit('error', e));
    this.surface.set(m, k != null ? k : (m.views_used || [])[0]).catch(e => this.emit('error', e));
    this.summary = null;
    loadSummary(this.api, m).then(sm => { if (m === this.mat) { this.summary = sm; renderSummary(sm); } })
      .catch(e => this.emit('error', e));
    this.computeErrors(k).catch(e => this.emit('error', e));
  }

  // ---- export ------------------------------------------------------------------------
  // The files the material exports to (GET /materials/{id}/exports: its
  // name, what it is for, how close it comes), listed when the Export tab
  // is first shown for a material (the list fits the material's glTF
  // numbers: a second or so), each a button that downloads it with the
  // session's token, fetched into a Blob and saved under the list's name.

  showExports(m) {
    if (this.exportsOf === m) return;
    this.exportsOf = m;
    const ul = $('exports');
    ul.replaceChildren(exportNote('Listing the formats…'));
    this.api.get(`/materials/${m.id}/exports`, { what: 'Listing the exports' }).then(lst => {
      if (m !== this.mat) return;
      ul.replaceChildren(...lst.exports.map(x => this.exportRow(m, x)));
      if (lst.fit && lst.fit.anisotropic_fit) {
        ul.appendChild(exportNote('This finish is brushed (its highlight turns with the surface): the glTF file ' +
          'carries the brushing (KHR_materials_anisotropy); MaterialX and USD carry its closest unbrushed look; ' +
          'the .brdf file and the glint package keep it exactly.'));
      } else if (lst.fit && lst.fit.anisotropy > 0.02) {
        ul.appendChild(exportNote('This finish is brushed (its highlight turns with the surface): glTF, ' +
          'MaterialX and USD carry its closest unbrushed look; the .brdf file and the glint package keep it.'));
      }
    }).catch(e => {
      if (m !== this.mat) return;
      this.exportsOf = null;
      ul.replaceChildren(exportNote('The formats could not be listed: ' + e.message));
      this.emit('error', e);
    });
  }

  exportRow(m, x) {
    const li = document.createElement('li');
    const b = document.createElement('button');
    b.id = 'dl-' + x.format;
    b.className = x.format === 'glb' ? 'primary' : '';
    b.textContent = (EXPORT_NAMES[x.format] || x.format);
    b.title = 'Download ' + x.file_name + ': ' + x.carries;
    b.disabled = !x.available;
    b.onclick = () => this.download(m, x, b);
    const what = document.createElement('span');
    what.className = 'small';
    what.textContent = x.use_in + '. ' + (x.available ? howClose(x.how_close) : x.reason || 'not available for this material');
    li.append(b, what);
    return li;
  }

  async download(m, x, b) {
    const label = b.textContent;
    b.disabled = true;
    b.textContent = x.expensive ? 'preparing (a few seconds)…' : 'preparing…';
    try {
      const r = await this.api.materialFile(m.id, x.url.slice(x.url.lastIndexOf('/') + 1));
      const u = URL.createObjectURL(await r.blob());
      const a = document.createElement('a');
      a.href = u; a.download = x.file_name;
      document.body.appendChild(a); a.click(); a.remove();
      setTimeout(() => URL.revokeObjectURL(u), 60000);
    } catch (e) { this.emit('error', e); } finally { b.textContent = label; b.disabled = false; }
  }

  // ---- preview -----------------------------------------------------------------------

  resetCamera(k) {
    const v = this.session.scene.views[k != null ? k : 0];
    this.cam = { eye: v.eye.slice(), light: v.light.slice(), target: (v.target || [0, 0, 0]).slice(), view: k };
    this.request();
  }

  bindPreview() {
    const g = $('preview-gizmo');
    g.addEventListener('contextmenu', e => e.preventDefault());
    g.addEventListener('pointerdown', e => {
      if (!this.cam) return;
      g.setPointerCapture(e.pointerId);
      this.drag = { x: e.clientX, y: e.clientY, what: e.shiftKey || e.button === 2 ? 'eye' : 'light' };
    });
    g.addEventListener('pointermove', e => {
      if (!this.drag) return;
      const dx = e.clientX - this.drag.x, dy = e.clientY - this.drag.y;
      this.drag.x = e.clientX; this.drag.y = e.clientY;
      this.orbit(this.drag.what, dx, dy);
    });
    const end = () => { this.drag = null; };
    g.addEventListener('pointerup', end);
    g.addEventListener('pointercancel', end);
    g.addEventListener('wheel', e => {
      if (!this.cam) return;
      e.preventDefault();
      const d = sub(this.cam.eye, this.cam.target);
      const r = Math.min(20, Math.max(1.3, len(d) * Math.exp(e.deltaY * 0.001)));
      this.cam.eye = add(this.cam.target, mul(d, r / len(d)));
      this.cam.view = null;
      this.request();
    }, { passive: false });
    g.addEventListener('dblclick', () => this.emit('reset'));
  }

  // Orbit the light or the eye about the target: horizontal drags turn
  // about the world up (+z), vertical ones tilt.
  orbit(what, dx, dy) {
    if (what === 'light' && this.envSpec()) {          // turn the environment instead
      const r = $('env-rot');
      let v = +r.value + dx * 0.6;
      v = ((v + 180) % 360 + 360) % 360 - 180;
      r.value = String(Math.round(v / 5) * 5);
      this.showEnvBar();
      this.request();
      return;
    }
    const rel = sub(this.cam[what], this.cam.target);
    const s = toSph(rel);
    const sign = what === 'eye' ? -1 : 1;
    s.az -= sign * dx * 0.012;
    s.el = Math.max(-1.5, Math.min(1.5, s.el + sign * dy * 0.012 * (what === 'eye' ? -1 : -1)));
    this.cam[what] = add(this.cam.target, fromSph(s));
    this.cam.view = null;
    this.request();
  }

  // What a preview is for: the material and the light (a new one of either
  // aborts the frame in flight; camera and light moves wait for it).
  frameKey() { return this.mat ? this.mat.id + '|' + this.envSpec() : ''; }

  // The preview shows another material than the current one (or none yet):
  // dimmed until the current one's frame is drawn.
  markStale() {
    const c = $('preview'), stale = c.dataset.material !== (this.mat ? this.mat.id : '');
    c.style.opacity = stale && this.frames ? '0.35' : '';
  }

  // One request in flight for the same material and light; while it runs,
  // later moves only update what is wanted, and the newest wanted frame is
  // asked for when it returns.  A request for another material or light
  // aborts it (requests.js: the daemon frees its slot).
  request() {
    if (!this.mat || !this.cam) return;
    this.want++;
    this.drawGizmo();
    if (this.inflight && this.inflight.key !== this.frameKey()) {
      this.api.images.abort('preview', 'another material or light');
      this.inflight = null;
    }
    if (!this.inflight) this.fetchFrame();
  }

  async fetchFrame() {
    const n = this.want;
    const c = this.cam, f = a => a.map(x => x.toFixed(4)).join(',');
    const q = Object.assign({ eye: f(c.eye), light: f(c.light), target: f(c.target), size: '256' }, this.envQuery());
    const mat = this.mat, key = this.frameKey(), job = this.inflight = { key, n };
    const current = () => this.mat === mat && this.frameKey() === key;
    try {
      const r = await this.api.images.run('preview', (signal, h) => this.api.materialFile(mat.id, 'preview.png', q, signal, h),
        { cls: CLASS.interactive, current, busy: e => this.showBusy(e) });
      const bmp = await createImageBitmap(await r.blob(), { colorSpaceConversion: 'none' });
      if (current() && n > this.shown) this.drawFrame(bmp, mat, n, r);
    } catch (e) {
      this.emit('error', e);
    } finally {
      if (this.inflight === job) {
        this.inflight = null;
        if (this.want > n && this.mat) this.fetchFrame();
      }
    }
  }

  // Draw a frame of mat (the current material: checked by the caller).
  drawFrame(bmp, mat, n, r) {
    const cv = $('preview');
    cv.getContext('2d').drawImage(bmp, 0, 0, 256, 256);
    cv.dataset.material = mat.id;
    cv.dataset.frame = String(n);
    this.shown = n;
    this.frames++;
    this.markStale();
    $('preview-empty').classList.add('hidden');
    this.lastRenderer = r.headers.get('X-Glint-Renderer') || '';
    this.lastEnv = r.headers.get('X-Glint-Env') || '';
    this.emit('frame', { n, renderer: this.lastRenderer, material: mat.id });
  }

  // The daemon is busy: its words (what it does, that the preview will
  // follow) under the preview while the request waits to be asked again.
  showBusy(e) {
    const el = $('preview-empty');
    el.textContent = (e.problem && e.problem.detail) || 'the server is busy; the preview will follow';
    el.classList.remove('hidden');
  }

  // The light's direction as seen from the camera, drawn over the preview.
  drawGizmo() {
    const g = $('preview-gizmo').getContext('2d');
    g.clearRect(0, 0, 256, 256);
    if (!this.cam) return;
    const fwd = sub(this.cam.target, this.cam.eye), fl = len(fwd);
    const f = mul(fwd, 1 / fl);
    let right = [f[1] * 1 - 0, -f[0] * 1, 0];      // f x z
    if (len(right) < 1e-6) right = [1, 0, 0];
    right = mul(right, 1 / len(right));
    const up = [right[1] * f[2] - right[2] * f[1], right[2] * f[0] - right[0] * f[2], right[0] * f[1] - right[1] * f[0]];
    const l = sub(this.cam.light, this.cam.target), ll = len(l);
    const lx = (l[0] * right[0] + l[1] * right[1] + l[2] * right[2]) / ll;
    const ly = (l[0] * up[0] + l[1] * up[1] + l[2] * up[2]) / ll;
    const lz = -(l[0] * f[0] + l[1] * f[1] + l[2] * f[2]) / ll;   // > 0: light on the camera's side
    const cx = 226, cy = 30, R = 20;
    g.strokeStyle = 'rgba(255,255,255,.5)'; g.lineWidth = 1;
    g.beginPath(); g.arc(cx, cy, R, 0, 7); g.stroke();
    g.fillStyle = lz >= 0 ? '#ffd34d' : 'rgba(255,211,77,.35)';
    g.beginPath(); g.arc(cx + lx * R, cy - ly * R, 4, 0, 7); g.fill();
    g.fillStyle = 'rgba(255,255,255,.8)'; g.font = '10px system-ui';
    g.fillText(this.cam.view != null ? 'view ' + this.cam.view : 'free', 6, 250);
  }

  // ---- an environment-lit material: its lobe and its energy ----------------------------

  async loadManifest() {
    const mat = this.mat;
    const r = await this.api.images.run('manifest', (signal, h) => this.api.materialFile(mat.id, 'material.json', undefined, signal, h),
      { current: () => mat === this.mat });
    const man = await r.json();
    if (mat !== this.mat) return;
    this.manifest = man;
    this.drawLobe();
  }

  drawLobe() {
    const m = this.mat, man = this.manifest;
    drawEnergy($('energy'), m && m.errors);
    if (!isLobeMaterial(man)) return;
    drawLobe($('lobe'), man);
    const d = man.diffuse || [0, 0, 0], used = m.weights_nonzero;
    $('lobe-note').textContent = `base colour ${d.map(x => (+x).toFixed(3)).join(' / ')}`;
    $('lobe-tech').querySelector('.body').textContent = `diffuse albedo ${d.map(x => (+x).toFixed(3)).join(' / ')} · ${man.centres.length} lobes, ` +
      `σ = ${(man.basis.sigma * 180 / Math.PI).toFixed(1)}°` + (used != null ? ` · ${used} lobe weights non-zero` : '') +
      ` · static term ${man.static ? man.static.term : '?'} · p(h): the distribution of half vectors`;
  }

  // ---- factor curves -----------------------------------------------------------------

  async loadFactors() {
    const mat = this.mat;
    const r = await this.api.images.run('factors', (signal, h) => this.api.materialFile(mat.id, 'factors.exr', undefined, signal, h),
      { current: () => mat === this.mat });
    const im = await decodeImage(await r.arrayBuffer());
    if (mat !== this.mat) return;
    this.factors = im;             // 3 rows (p, q, r) per product x res texels, RGB, linear
    this.drawFactors();
  }

  drawFactors() {
    const c = $('factors'), g = c.getContext('2d');
    g.clearRect(0, 0, c.width, c.height);
    const im = this.factors;
    if (!im) return;
    if (this.mat && Array.isArray(this.mat.dims)) return this.drawFactors2d(g, c, im);
    const log = $('factors-log').checked;
    // each curve in words on the plot; its symbol under "advanced" below it
    const names = [['how the light\'s direction changes the colour'], ['the highlight: how the colour changes near the mirror direction'], ['how the viewing direction changes the colour']];
    const H = c.height / 3, L = 34, Rm = 6, W = c.width - L - Rm;
    // a material map's product k: rows 3k .. 3k + 2
    const k = Math.min(this.surface.product || 0, Math.floor(im.h / 3) - 1), row0 = 3 * Math.max(0, k);
    for (let j = 0; j < 3; j++) {
      const r = row0 + j;
      const y0 = j * H + 14, h = H - 30;
      const vals = [];
      for (let x = 0; x < im.w; x++) for (let ch = 0; ch < 3; ch++) vals.push(im.data[3 * (r * im.w + x) + ch]);
      const tf = v => log ? Math.log10(Math.max(v, 1e-6)) : v;
      let lo = Math.min(...vals.map(tf)), hi = Math.max(...vals.map(tf));
      if (!log) lo = Math.min(0, lo);
      if (hi - lo < 1e-9) { hi += 0.5; lo -= 0.5; }
      g.fillStyle = '#8d94a3'; g.font = '11px system-ui';
      g.fillText(names[j][0], L, y0 - 3);
      g.strokeStyle = '#323744'; g.strokeRect(L, y0, W, h);
      g.fillStyle = '#8d94a3'; g.font = '9px system-ui'; g.textAlign = 'right';
      g.fillText(log ? '1e' + hi.toFixed(1) : hi.toPrecision(3), L - 3, y0 + 8);
      g.fillText(log ? '1e' + lo.toFixed(1) : lo.toPrecision(3), L - 3, y0 + h);
      g.textAlign = 'left';
      if (j === 2) { g.fillText('straight on', L, y0 + h + 10); g.textAlign = 'right'; g.fillText('grazing', L + W, y0 + h + 10); g.textAlign = 'left'; }
      const cols = ['#ff6b6b', '#6bd66b', '#6ba4ff'];
      for (let ch = 0; ch < 3; ch++) {
        g.strokeStyle = cols[ch]; g.lineWidth = 1.3; g.globalCompositeOperation = 'lighter';
        g.beginPath();
        for (let x = 0; x < im.w; x++) {
          const v = tf(im.data[3 * (r * im.w + x) + ch]);
          const px = L + W * x / Math.max(1, im.w - 1), py = y0 + h - h * (v - lo) / (hi - lo);
          if (x) g.lineTo(px, py); else g.moveTo(px, py);
        }
        g.stroke();
        g.globalCompositeOperation = 'source-over';
      }
    }
  }

  // A material with 2D factors (its dims): a 2D factor drawn as its parabolic map (the disc is the
  // hemisphere, the normal at its centre, t to the right, b up), a 1D one
  // as a curve; each panel scaled to its own range.
  drawFactors2d(g, c, im) {
    const m = this.mat, S = m.res_2d, log = $('factors-log').checked;
    const names = [['light', 'direction'], ['highlight', ''], ['view', 'direction']];
    const Wp = c.width / 3, tf = v => log ? Math.log10(Math.max(v, 1e-6)) : v;
    let row = 0;
    for (let j = 0; j < 3; j++) {
      const two = m.dims[j] === 2, rows = two ? S : 1, x0 = j * Wp + 6, size = Math.min(Wp - 12, c.height - 34);
      const vals = [];
      for (let y = 0; y < rows; y++) for (let x = 0; x < (two ? S : m.res); x++) {
        const k = 3 * ((row + y) * im.w + x);
        vals.push(tf((im.data[k] + im.data[k + 1] + im.data[k + 2]) / 3));
      }
      let lo = Math.min(...vals), hi = Math.max(...vals);
      if (hi - lo < 1e-9) { hi += 0.5; lo -= 0.5; }
      g.fillStyle = '#8d94a3'; g.font = '11px system-ui'; g.textAlign = 'left';
      g.fillText(`${names[j][0]} ${two ? 'map' : 'curve'}`, x0, 12);
      if (two) {
        const cell = size / S, y0 = 18;
        for (let y = 0; y < S; y++) for (let x = 0; x < S; x++) {
          const k = 3 * ((row + y) * im.w + x);
          const rgb = [0, 1, 2].map(ch => tf(im.data[k + ch]));
          const sc = v => Math.round(255 * Math.min(1, Math.max(0, (v - lo) / (hi - lo))));
          g.fillStyle = `rgb(${sc(rgb[0])},${sc(rgb[1])},${sc(rgb[2])})`;
          g.fillRect(x0 + x * cell, y0 + (S - 1 - y) * cell, Math.ceil(cell), Math.ceil(cell));
        }
        g.strokeStyle = '#8d94a3'; g.beginPath();
        g.arc(x0 + size / 2, y0 + size / 2, size / 2, 0, 2 * Math.PI); g.stroke();
        g.fillStyle = '#5d6473'; g.font = '9px system-ui';
        g.fillText('centre: straight on · rim: grazing', x0, y0 + size + 11);
      } else {
        const y0 = 18, h = size, cols = ['#ff6b6b', '#6bd66b', '#6ba4ff'];
        g.strokeStyle = '#323744'; g.strokeRect(x0, y0, size, h);
        for (let ch = 0; ch < 3; ch++) {
          g.strokeStyle = cols[ch]; g.lineWidth = 1.3; g.beginPath();
          for (let x = 0; x < m.res; x++) {
            const v = tf(im.data[3 * (row * im.w + x) + ch]);
            const px = x0 + size * x / Math.max(1, m.res - 1), py = y0 + h - h * (v - lo) / (hi - lo);
            if (x) g.lineTo(px, py); else g.moveTo(px, py);
          }
          g.stroke();
        }
        g.fillStyle = '#5d6473'; g.font = '9px system-ui';
        g.fillText('straight on … grazing', x0, y0 + h + 11);
      }
      row += rows;
    }
  }

  // ---- error per view ---------------------------------------------------------------

  // For every view the fit used: the RMS over the object's lit pixels of
  // (fitted - painted), from a render of the material for that view (CPU
  // renderer: the same rasterizer that defines the fit's samples) and the
  // view's current painting.
  async computeErrors(prefer) {
    const mat = this.mat;
    const S = this.session, sc = S.scene;
    const tb = $('err-table').querySelector('tbody');
    tb.textContent = '';
    const env = underEnv(mat);
    this.renderErrSummary(mat, sessionLevel(S, mat.views_used || []));
    this.rows = new Map();
    const square = sc.width === sc.height;
    const used = mat.views_used || [];
    const snap = new Map((mat.paintings || []).map(p => [p.view, p.version]));
    let now = new Map();
    try { now = new Map(((await this.api.session(S.id)).paintings || []).map(p => [p.view, p.version])); } catch (_) { /* no staleness marks */ }
    for (const k of used) {
      const tr = document.createElement('tr');
      tr.dataset.view = k;
      tr.innerHTML = `<td>${k}</td><td>…</td><td></td><td></td>`;
      tr.onclick = () => { this.showDiff(k); this.emit('select-view', k); };
      tb.appendChild(tr);
    }
    if (!square) return;
    // one view's row from a render of the material (full, or coarse: a
    // quarter of the size, upsampled, shown at once under an environment,
    // where a full reference render takes seconds to minutes)
    const measure = async (k, fitted, coarse) => {
      if (mat !== this.mat) return;
      const v = S.views[k];
      if (!v.conf) await S.loadViews([k]);
      const painted = v.conf, base = resizeImage(v.base, painted.w, painted.h);
      if (fitted.w !== painted.w || fitted.h !== painted.h) fitted = resizeImage(fitted, painted.w, painted.h);
      let s2 = 0, n = 0, mx = 0;
      const lv = new Level();
      const diff = new Float32Array(painted.w * painted.h);
      for (let i = 0; i < painted.w * painted.h; i++) {
        const lit = env ? fitted.data[3 * i] > 0 || fitted.data[3 * i + 1] > 0 || fitted.data[3 * i + 2] > 0
                         : base.data[3 * i] > 0 || base.data[3 * i + 1] > 0 || base.data[3 * i + 2] > 0;
        if (!lit) { diff[i] = -1; continue; }
        let dm = 0;
        for (let c = 0; c < 3; c++) {
          const d = fitted.data[3 * i + c] - painted.data[3 * i + c];
          s2 += d * d; mx = Math.max(mx, Math.abs(d)); dm += Math.abs(d) / 3;
          lv.add(painted.data[3 * i + c]);
        }
        diff[i] = dm; n++;
      }
      const rms = n ? Math.sqrt(s2 / (3 * n)) : 0;
      const stale = snap.has(k) && now.has(k) && snap.get(k) !== now.get(k);
      if (coarse && this.rows.has(k)) return;   // the full render came first
      this.rows.set(k, { rms, max: mx, n, fitted, painted, diff, stale, level: lv, coarse });
      const tr = tb.querySelector(`tr[data-view="${k}"]`);
      if (tr) {
        const L = lv.level(), about = coarse ? '≈ ' : '';
        tr.classList.toggle('coarse', coarse);
        tr.title = coarse ? 'from a quick, coarse render; the full one follows' : '';
        tr.innerHTML = `<td>${k}${stale ? ' <span title="painted again since this fit">*</span>' : ''}</td><td title="${errorMeaning(relError(rms, L))} (advanced: RMS ${fmtErr(rms)})"><span class="meter"></span>${about}${pct(relError(rms, L))}</td>` +
          `<td title="advanced: ${fmtErr(mx)} in the painting's units">${about}${pct(relError(mx, L))}</td><td>${n}</td>`;
      }
      if (coarse && this.errView === k) this.showDiff(k);
    };
    // every view's coarse render queued before any full one: the reference
    // renders run one at a time, so each view shows a figure in a second
    const coarse = env ? used.map(k => this.fittedFor(k, mat, 4).then(f => measure(k, f, true), () => {})) : [];
    await Promise.all(used.map(async k => measure(k, await this.fittedFor(k, mat), false)));
    await Promise.all(coarse);
    if (mat !== this.mat) return;
    this.level = [...this.rows.values()].reduce((a, r) => a.merge(r.level), new Level()).level();
    this.renderErrSummary(mat, this.level);
    // bars relative to the worst view
    const worst = Math.max(1e-12, ...[...this.rows.values()].map(r => r.rms));
    for (const [k, r] of this.rows) {
      const m = tb.querySelector(`tr[data-view="${k}"] .meter`);
      if (m) m.style.width = Math.max(2, Math.round(50 * r.rms / worst)) + 'px';
    }
    this.emit('errors', this.rows);
    const k = used.includes(prefer) ? prefer : used[0];
    if (k != null) this.showDiff(k);
  }

  // The fit's error in words (a percentage of the painting's brightness,
  // level: the RMS of the painted values over the views' object pixels;
  // null until the views are read), what the automatic choice weighed, and
  // the figures behind them (RMS, samples, size, method) behind an
  // "advanced" disclosure.
  renderErrSummary(mat, level) {
    const e = mat.errors || {}, box = $('err-summary');
    const frac = relError(e.rms_painted, level);
    const samples = e.diagnostic_samples != null && mat.precomputation && e.diagnostic_samples < mat.precomputation.samples
      ? `over ${e.diagnostic_samples} of ${mat.precomputation.samples} samples (an evenly spaced subsample${e.diagnostic_runs > 1 ? `: ${e.diagnostic_runs} runs of ${Math.round(e.diagnostic_samples / e.diagnostic_runs)} consecutive samples` : ''})`
      : `over ${mat.precomputation ? mat.precomputation.samples : '?'} samples`;
    const d = methodNamed((mat.choice && mat.choice.chosen) || mat.method);
    const tech = [`RMS ${fmtErr(e.rms_painted)}` + (e.max_abs_painted != null ? `, max ${fmtErr(e.max_abs_painted)}` : '') + ' ' + samples,
      sizeText(mat), `method ${d ? d.name : mat.method}`, `fit ${fmtTime(mat.seconds && mat.seconds.fit)}`]
      .concat(e.albedo_max_rows != null ? [`highest albedo ${e.albedo_max_rows.toFixed(4)}`] : []);
    box.textContent = '';
    const line = document.createElement('div');
    line.id = 'err-meaning';
    line.textContent = level != null ? errorMeaning(frac) : 'measuring the error against your painting…';
    box.appendChild(line);
    if (mat.choice && mat.choice.candidates) box.appendChild(this.choiceWords(mat.choice, level));
    const adv = document.createElement('details');
    adv.className = 'adv'; adv.id = 'err-advanced';
    const sm = document.createElement('summary'); sm.textContent = 'advanced';
    const body = document.createElement('div'); body.textContent = tech.join(' · ');
    if (mat.choice && mat.choice.candidates)
      body.textContent += ' · candidates (held-out RMS): ' + mat.choice.candidates.map(x => `${x.label || x.method} (${x.method}) ${x.skipped ? 'not tried: ' + x.skipped : fmtErr(x.held_out_rms)}`).join(', ');
    adv.append(sm, body);
    box.appendChild(adv);
    if (!(this.session.scene.width === this.session.scene.height)) box.append('per-view errors need a square raster (previews are square)');
  }

  // What the automatic choice weighed, in words: the chosen model's label,
  // each candidate's label and its error on what it did not fit.
  choiceWords(c, level) {
    const div = document.createElement('div');
    div.id = 'auto-choice'; div.className = 'small';
    const name = x => (methodNamed(x) || { label: x }).label;
    // a candidate's own label first: one method may be tried in several forms
    const b = document.createElement('b'); b.textContent = c.chosen_label || name(c.chosen);
    const on = c.held_out === 'views' ? 'views' : 'parts of the painting';
    // a choice judged on several hold-outs (auto_env's folds) says how many
    const folds = (c.held_out_folds || []).length;
    const over = folds > 1 ? `, over ${folds} hold-outs` : '';
    div.append('Chose ', b, `: the error of each on ${on} it did not see${over} — `,
      c.candidates.filter(x => !x.skipped).map(x => `${x.label || name(x.method)} ${level != null ? pct(relError(x.held_out_rms, level)) : fmtErr(x.held_out_rms)}`).join(' · ') + '. ');
    // a candidate this host cannot fit (a method that learns from data it
    // lacks): named, the reason on hover
    for (const x of c.candidates.filter(x => x.skipped)) {
      const sk = document.createElement('span');
      sk.className = 'muted'; sk.title = x.skipped;
      sk.textContent = `${x.label || name(x.method)}: not tried here. `;
      div.appendChild(sk);
    }
    const why = document.createElement('span');
    why.className = 'muted'; why.title = c.rule || '';
    // where the choice started from another than the first candidate (auto_env
    // from one painted view starts from the correction), it says which
    const first = c.candidates.find(x => !x.skipped);
    const start = c.started_from && first && c.started_from !== (first.label || name(first.method)) ? c.started_from : null;
    const pc = Math.round(100 * c.threshold);
    why.textContent = start
      ? `(started from ${start}, the best from one painted view on measured materials; another is kept only when it is more than ${pc}% better)`
      : `(a richer model is kept only when it is more than ${pc}% better)`;
    div.appendChild(why);
    return div;
  }

  // The material rendered for view k as the fit saw it: the CPU renderer at
  // the painting's size (over `div`: a coarse render), under the fit's
  // environment for a material fitted under one (linear RGB).
  async fittedFor(k, mat = this.mat, div = 1) {
    const sc = this.session.scene, full = sc.paint_width || sc.width;
    const q = { view: String(k), renderer: 'cpu', size: String(div > 1 ? Math.max(16, Math.round(full / div)) : full) };
    if (underEnv(mat)) Object.assign(q, { env: mat.params.env, env_rotation: String(mat.params.env_rotation), env_intensity: String(mat.params.env_intensity),
                                          lights: String(Math.min(1024, mat.params.lights)), shadows: mat.params.visibility === 'off' ? '0' : '1', background: '0' });
    // a reference render: after the studio's other requests, and in the
    // daemon after interactive work; dropped once another material is shown
    const r = await this.api.images.run(`reference:view${k}${div > 1 ? ':coarse' : ''}`, (signal, h) => this.api.materialFile(mat.id, 'preview.exr', q, signal, h),
      { cls: CLASS.reference, current: () => this.mat === mat });
    return decodeImage(await r.arrayBuffer());
  }

  showDiff(k) {
    const row = this.rows && this.rows.get(k);
    if (!row) return;
    this.errView = k;
    if (k !== this.surface.view) this.surface.setView(k).catch(e => this.emit('error', e));
    for (const tr of $('err-table').querySelectorAll('tr')) tr.classList.toggle('on', +tr.dataset.view === k);
    $('diff-wrap').classList.remove('hidden');
    const { painted, fitted, diff } = row;
    let gain = +$('diff-gain').value;
    if ($('diff-gain').value === 'p99') {     // white = the 99th percentile of |difference|
      const m = [...diff].filter(x => x >= 0).sort((a, b) => a - b);
      const p99 = m.length ? m[Math.min(m.length - 1, Math.floor(0.99 * m.length))] : 0;
      gain = 1 / Math.max(1e-4, p99);
      $('diff-gain').options[0].textContent = `auto (white = ${(1 / gain).toPrecision(2)})`;
    }
    const draw = (id, fn) => {
      const c = $(id); c.width = painted.w; c.height = painted.h;
      const g = c.getContext('2d'), img = g.createImageData(painted.w, painted.h);
      for (let i = 0; i < painted.w * painted.h; i++) { const [r, gg, b] = fn(i); img.data[4 * i] = r; img.data[4 * i + 1] = gg; img.data[4 * i + 2] = b; img.data[4 * i + 3] = 255; }
      g.putImageData(img, 0, 0);
    };
    const q = v => v <= 0 ? 0 : v >= 1 ? 255 : Math.round(v * 255);
    draw('diff-painted', i => [q(painted.data[3 * i]), q(painted.data[3 * i + 1]), q(painted.data[3 * i + 2])]);
    draw('diff-fitted', i => [q(fitted.data[3 * i]), q(fitted.data[3 * i + 1]), q(fitted.data[3 * i + 2])]);
    // heat: black -> red -> yellow -> white as |difference| x gain grows
    draw('diff-img', i => {
      if (diff[i] < 0) return [20, 22, 28];
      const t = Math.min(1, diff[i] * gain);
      return [q(t * 3), q(t * 3 - 1), q(t * 3 - 2)];
    });
  }
}
