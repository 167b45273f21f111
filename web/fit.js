// fit.js: the fit panel: method, a quality control built from the server's
// own measurements (GET /methods?session_id=: presets and the speed-accuracy
// points measured on this scene), the parameters, and the fit itself: at
// once when the precomputation is cached (201 with the material), or as a
// job whose progress streams in (202, GET /jobs/{id}/events).

import { API, ApiError } from './api.js';
import { EventStream } from './sse.js';
import { methods, setMethods, startMethod } from './methods.js';
import { envLabels, envLabel, envNth, pct, relError, sessionLevel } from './words.js';

const $ = id => document.getElementById(id);

function fmtTime(s) {
  if (s == null || !isFinite(s)) return '?';
  if (s < 1e-3) return (s * 1e6).toFixed(0) + ' µs';
  if (s < 1) return (s * 1e3).toFixed(s < 0.01 ? 2 : 0) + ' ms';
  if (s < 120) return s.toFixed(s < 10 ? 2 : 1) + ' s';
  return (s / 60).toFixed(1) + ' min';
}
function fmtErr(e) { return e == null || !isFinite(e) ? '?' : e.toFixed(4); }
export { fmtTime, fmtErr };

// A refusal that means "paint first" (glintd's problem type no-paintings:
// the session had no painted view when the fit arrived) said as such.
function explain(e) {
  if (e instanceof ApiError && e.status === 422 && /(^|\/)no-paintings$/.test(e.problem.type || '')) {
    const n = new Error('Paint or upload at least one view, then fit again: the fit learns the material from the painted views, and this session has none yet.');
    n.title = 'Nothing painted to fit yet';
    return n;
  }
  return e;
}

// The size of a configuration in words (texels per factor, or lobes).
export function sizeLabel(params) {
  if (params.res === 0) return { text: '', title: 'detail: each model at the detail a fit of its own would use' };
  if (params.res != null) return { text: String(params.res), title: `detail ${params.res} (texels per factor)` };
  if (params.basis_res != null) {
    const J = 3 * params.basis_res * params.basis_res;
    return { text: `${J}`, title: `highlight detail ${J} (lobes)${params.lights != null ? ', ' + params.lights + ' light samples' : ''}` };
  }
  return { text: '', title: '' };
}

export class FitPanel extends EventTarget {
  constructor(api, session) {
    super();
    this.api = api;
    this.session = session;
    this.method = null;
    this.points = [];
    this.preset = null;
    this.job = null;
    this.inputs = {};
    $('fit-btn').onclick = () => this.fit();
    // a view painted (here or by someone else, live) or a stroke of ours
    // on its way: the fit may have become possible
    session.addEventListener('painted', () => { this.updateButton(); this.renderQuality(); });
    session.addEventListener('history', () => this.updateButton());
  }

  // Why a fit cannot be made now ('' when it can).
  blocker() {
    if (!this.method) return 'loading the fit methods…';
    if (!this.session.canPaint) return 'view-only link: fitting needs the paint link';
    if (!this.session.hasPainting()) return 'Paint or upload at least one view first: the fit learns the material from the painted views.';
    return '';
  }

  // The Fit button and the hint under it follow blocker().
  updateButton() {
    const why = this.blocker();
    const btn = $('fit-btn'), hint = $('fit-hint');
    btn.disabled = this.busy || !!why;
    btn.title = why || 'Fit the painted views (F)';
    hint.textContent = why;
    hint.classList.toggle('hidden', !why || !this.method);
  }

  emit(type, detail) { this.dispatchEvent(new CustomEvent(type, { detail })); }

  async load() {
    const m = await this.api.methods(this.session.id);
    setMethods(m.methods);
    this.methods = methods();
    this.points = (m.scene && m.scene.points) || [];
    try { this.envs = (await this.api.environments()).environments; } catch (_) { this.envs = null; }
    const sel = $('fit-method');
    const env = this.sceneEnv();
    sel.textContent = '';
    for (const x of this.methods) {
      const o = document.createElement('option');
      o.value = x.name;
      o.textContent = x.label || x.name;
      o.title = x.summary || x.label || '';
      // the daemon refuses a point-light method on a scene painted under an
      // environment (lighting-mismatch), and an environment's method on a
      // scene painted under lamps would assume a light the paintings never
      // had: offered, but not choosable
      if (x.available === false) {
        // this host cannot fit it (tab_prior without the measured fits)
        o.disabled = true;
        o.title += ' — not on this server: ' + (x.unavailable || 'it cannot fit it');
      } else if (env && x.lighting === 'point') {
        o.disabled = true;
        o.title += ' — needs the views\' point lights; this scene is painted under an environment';
      } else if (!env && x.lighting === 'environment') {
        o.disabled = true;
        o.title += ' — needs paintings made under an environment; this scene is painted under lamps';
      }
      sel.appendChild(o);
    }
    sel.onchange = () => this.setMethod(sel.value);
    this.guide();
    // a scene painted under an environment is fitted under it by default;
    // else the method that chooses the model the painting needs, when offered
    this.setMethod(startMethod(!!this.sceneEnv()).name);
  }

  // The first-visit guide's line on the methods: their labels, as offered.
  guide() {
    const el = $('guide-methods');
    if (!el || !this.methods.length) return;
    el.textContent = '';
    const lower = t => t.charAt(0).toLowerCase() + t.slice(1);
    this.methods.forEach((x, i) => {
      if (i) el.append(i === this.methods.length - 1 ? ' or ' : ', ');
      const it = document.createElement('i');
      it.textContent = lower(x.label || x.name);
      it.title = x.summary || '';
      el.appendChild(it);
    });
    el.append('.');
  }

  // Switch the method: its parameters, presets and measured points.
  setMethod(name) {
    this.method = this.methods.find(x => x.name === name) || this.methods[0];
    const sel = $('fit-method');
    sel.value = this.method.name;
    sel.title = this.method.summary || this.method.label || '';
    this.methodAdvanced();
    $('method-note').textContent = [this.method.summary || this.method.title, this.method.when].filter(Boolean).join(' ');
    this.inputs = {};
    this.preset = null;                  // a method without presets: its own parameters
    this.buildParams();
    const def = this.method.presets.find(p => p.name === 'default') || this.method.presets[0];
    const d0 = this.defaults();
    for (const [k, { inp }] of Object.entries(this.inputs)) inp.value = d0[k];
    const env = this.sceneEnv();
    if (env && this.inputs.env) {                       // the light the views were painted under
      const inp = this.inputs.env.inp;
      if (inp.tagName === 'SELECT' && ![...inp.options].some(o => o.value === env.spec)) {
        const o = document.createElement('option'); o.value = o.textContent = env.spec; inp.appendChild(o);
      }
      inp.value = env.spec;
      if (this.inputs.env_rotation) this.inputs.env_rotation.inp.value = env.rotation || 0;
      if (this.inputs.env_intensity && env.intensity) this.inputs.env_intensity.inp.value = env.intensity;
    }
    this.choose(def ? def.name : null);
    this.renderQuality();
    this.updateButton();
    this.emit('method', this.method);
  }

  // Refresh the measured points (after a fit, or when views get painted).
  async refresh() {
    try {
      const m = await this.api.methods(this.session.id);
      this.points = (m.scene && m.scene.points) || [];
    } catch (_) { /* keep the old figures */ }
    this.renderQuality();
  }

  // The environment the scene's base renders are lit by (null: point lights).
  sceneEnv() {
    const sc = this.session && this.session.scene;
    return (sc && sc.base && sc.base.env) || null;
  }

  defaults() {
    const d = {};
    for (const p of this.method.params) d[p.name] = p.default;
    return d;
  }

  // The parameters by their plain names, the basic ones first, then those
  // most people leave alone under a heading of their own.
  buildParams() {
    const box = $('params');
    box.textContent = '';
    const basic = this.method.params.filter(p => p.group !== 'advanced');
    const advanced = this.method.params.filter(p => p.group === 'advanced');
    for (const p of basic) this.addParam(box, p, false);
    if (!advanced.length) return;
    // the parameters most people leave alone, by their technical names too,
    // behind a disclosure of their own
    const det = document.createElement('details');
    det.id = 'params-advanced'; det.className = 'adv';
    const sum = document.createElement('summary'); sum.textContent = 'advanced';
    sum.title = 'settings most people leave alone, with their technical names';
    const grid = document.createElement('div'); grid.className = 'params-grid';
    det.append(sum, grid);
    box.appendChild(det);
    for (const p of advanced) this.addParam(grid, p, true);
  }

  // One parameter: its label, its input and what changing it costs.  In
  // the advanced part the technical name follows the plain one.
  addParam(box, p, technical) {
    const lab = document.createElement('label');
    lab.textContent = p.label || p.name;
    if (technical && p.label && p.label !== p.name) {
      const n = document.createElement('code'); n.className = 'pname'; n.textContent = p.name;
      lab.append(' ', n);
    }
    lab.title = technical ? `${p.name}: ${p.description}` : p.description;
    let inp, extra = null;
    if (p.name === 'env' && this.envs) {           // the environments glintd offers
      inp = document.createElement('select');
      const names = envLabels(this.envs);
      for (const e of this.envs) {
        const o = document.createElement('option'), l = names.get(e.spec);
        o.value = e.spec; o.textContent = l.text; o.title = l.title; inp.appendChild(o);
      }
      extra = this.envUpload(inp);
    } else if (p.enum) {
      inp = document.createElement('select');
      for (const v of p.enum) { const o = document.createElement('option'); o.value = o.textContent = v; inp.appendChild(o); }
    } else {
      inp = document.createElement('input');
      if (p.type === 'string') {
        inp.type = 'text';
        if (p.examples) {
          const dl = document.createElement('datalist'); dl.id = 'dl-' + p.name;
          for (const v of p.examples) { const o = document.createElement('option'); o.value = v; dl.appendChild(o); }
          box.appendChild(dl); inp.setAttribute('list', dl.id);
        }
      } else {
        inp.type = 'number';
        inp.step = p.type === 'integer' ? '1' : 'any';
        if (p.minimum != null) inp.min = p.minimum;
        if (p.maximum != null) inp.max = p.maximum;
      }
    }
    inp.value = p.default;
    inp.id = 'param-' + p.name;
    inp.title = p.description + (technical && p.syntax ? ' (' + p.syntax + ')' : '') +
      (p.affects === 'fit' ? ' · quick to change' : ' · changing it rebuilds the precomputation (the next fit is slower)');
    inp.addEventListener('input', () => { this.preset = this.matchPreset(); this.renderQuality(); });
    this.inputs[p.name] = { p, inp };
    lab.htmlFor = inp.id;
    box.append(lab, inp);
    if (extra) box.appendChild(extra);
    const d = document.createElement('div'); d.className = 'desc';
    d.textContent = p.affects === 'fit' ? 'quick to change' : 'changing it makes the next fit slower';
    d.title = technical ? 'changing it costs: ' + p.affects : '';
    box.appendChild(d);
  }

  // The method's technical name, model and reference, in the advanced
  // part under the method's note.
  methodAdvanced() {
    const el = $('method-tech');
    if (!el) return;
    const m = this.method;
    el.querySelector('.body').textContent = [`method ${m.name}`, m.title, m.reference].filter(Boolean).join(' · ');
  }

  // An HDR file of the artist's (OpenEXR or Radiance, lat-long or a cube
  // cross): glintd decodes it before keeping it; the new environment is
  // chosen here and offered to the previews ('envs' event).
  envUpload(sel) {
    const lab = document.createElement('label');
    lab.className = 'env-upload';
    lab.textContent = 'upload HDR…';
    lab.title = 'an OpenEXR or Radiance HDR map, lat-long (2:1) or a cube cross, sides up to 4096';
    const f = document.createElement('input');
    f.type = 'file'; f.accept = '.exr,.hdr'; f.id = 'env-file'; f.hidden = true;
    f.onchange = async () => {
      const file = f.files && f.files[0];
      if (!file) return;
      try {
        const name = file.name.replace(/[^\x20-\x7e]|["\\]/g, '_').slice(0, 60) || 'upload';
        const e = await this.api.uploadEnvironment(new Uint8Array(await file.arrayBuffer()), name);
        const l = envLabel(e, envNth(this.envs, e.name) + 1);
        this.envs.push(e);
        const o = document.createElement('option'); o.value = e.spec; o.textContent = l.text; o.title = l.title;
        sel.appendChild(o); sel.value = e.spec;
        sel.dispatchEvent(new Event('input', { bubbles: true }));
        this.emit('envs', Object.assign({}, e, { name: l.text, title: l.title }));
      } catch (err) { this.emit('error', err); }
      f.value = '';
    };
    lab.appendChild(f);
    return lab;
  }

  values() {
    const o = {};
    for (const [name, { p, inp }] of Object.entries(this.inputs)) {
      if (inp.value === '') continue;
      o[name] = p.type === 'string' ? inp.value : p.type === 'integer' ? parseInt(inp.value, 10) : parseFloat(inp.value);
    }
    return o;
  }

  // The parameters the presets set (the quality knobs); the others (the
  // environment, the diffuse albedo, ...) stay as the user set them.
  presetKeys() {
    const k = new Set();
    for (const pr of this.method.presets) for (const n of Object.keys(pr.params)) k.add(n);
    return k;
  }

  choose(name) {
    const pr = this.method.presets.find(p => p.name === name);
    if (!pr) return;
    const d = this.defaults(), keys = this.presetKeys();
    for (const [k, { inp }] of Object.entries(this.inputs))
      if (keys.has(k)) inp.value = k in pr.params ? pr.params[k] : d[k];
    this.preset = name;
    this.renderQuality();
  }

  matchPreset() {
    const v = this.values(), d = this.defaults(), keys = [...this.presetKeys()];
    for (const pr of this.method.presets) {
      const want = Object.assign({}, d, pr.params);
      if (keys.every(k => String(want[k]) === String(v[k]))) return pr.name;
    }
    return null;
  }

  paintedViews() { return this.session.views.filter(v => v.painted).map(v => v.k); }

  // The measured point of a configuration: same parameters and, best, the
  // same painted views (they make the sampling pattern).
  pointFor(params) {
    const views = this.paintedViews().join(',');
    const same = p => p && p.params && (!p.method || p.method === this.method.name) && Object.keys(params).every(k => p.params[k] === undefined || String(p.params[k]) === String(params[k]));
    const cands = this.points.filter(same);
    const exact = cands.filter(p => p.views.join(',') === views);
    const pick = arr => arr.slice().sort((a, b) => (b.updated || '').localeCompare(a.updated || ''))[0];
    if (exact.length) return { point: pick(exact), exact: true };
    if (cands.length) return { point: pick(cands), exact: false };
    return null;
  }

  // Cold time of an unmeasured resolution, from the nearest measured one
  // (the precomputation grows as res^3, per the method's description).
  estimateCold(res) {
    const m = this.points.filter(p => p.cold_seconds != null && p.params && p.params.res && (!p.method || p.method === this.method.name));
    if (!m.length) return null;
    m.sort((a, b) => Math.abs(Math.log(a.params.res / res)) - Math.abs(Math.log(b.params.res / res)));
    return m[0].cold_seconds * Math.pow(res / m[0].params.res, 3);
  }

  // One row per preset: texels, then what this server measured on this
  // scene: the warm fit, the first fit (precomputation from scratch) and
  // the error (held-out when measured, else on the painted pixels).
  renderQuality() {
    if (!this.method) return;            // not loaded yet
    const box = $('quality');
    box.textContent = '';
    const head = document.createElement('div');
    head.className = 'q head';
    head.innerHTML = '<span></span><span>quality</span><span title="a fit when its precomputation is in memory">fit</span><span title="the first fit of a configuration: builds the precomputation">first</span><span title="how far the fitted material is from your painting, as a percentage of the painting\'s brightness: on views left out of the fit when measured (each painted view in turn), else on the painted views">error</span>';
    box.appendChild(head);
    const d = this.defaults();
    const level = sessionLevel(this.session, this.paintedViews());
    const cell = (html, title) => { const c = document.createElement('span'); c.className = 'v'; c.innerHTML = html; if (title) c.title = title; return c; };
    const addRow = (name, params, onpick, on) => {
      const row = document.createElement('label');
      row.className = 'q' + (on ? ' on' : '');
      row.dataset.preset = name;
      const r = document.createElement('input');
      r.type = 'radio'; r.name = 'quality'; r.checked = on;
      if (onpick) r.onchange = onpick; else r.disabled = true;
      const nm = document.createElement('span'); nm.className = 'qn';
      nm.innerHTML = '<b></b> <span class="res"></span>';
      nm.firstChild.textContent = name;
      const sz = sizeLabel(params);
      nm.lastChild.textContent = sz.text;
      nm.title = sz.title;
      row.append(r, nm);
      const found = this.pointFor(params);
      if (found) {
        const p = found.point;
        const cold = p.cold_seconds != null ? p.cold_seconds : p.disk_seconds;
        const err = p.held_out_rms != null ? p.held_out_rms : p.rms_painted;
        const other = found.exact ? '' : '<sup title="measured with another set of painted views">*</sup>';
        row.append(cell(`<em>${fmtTime(p.fit_seconds)}</em>`, `median of the last ${Math.min(16, p.fits)} fit(s), precomputation in memory`),
                   cell(cold != null ? `<em>${fmtTime(cold)}</em>` : '—', p.cold_seconds != null ? 'precomputation from scratch' : 'precomputation with the decomposition from the disk cache'),
                   cell(`<em>${level ? pct(relError(err, level)) : err.toFixed(3)}</em>${p.held_out_rms != null ? '<sup title="on views left out of the fit">°</sup>' : ''}${other}`,
                        (p.held_out_rms != null ? 'on views left out of the fit' : 'on the painted views') +
                        ` · advanced: RMS painted ${fmtErr(p.rms_painted)}, held-out ${fmtErr(p.held_out_rms)} (${p.samples} samples, views ${p.views.join(' ')})`));
      } else {
        const est = params.res != null ? this.estimateCold(params.res) : null;
        row.append(cell('—', 'not measured on this scene yet'),
                   cell(est != null ? `≈${fmtTime(est)}` : '—', est != null ? 'estimated from the measured resolutions (the precomputation grows as res³); not measured yet' : 'not measured on this scene yet'),
                   cell('—', 'not measured on this scene yet: the first fit at this quality measures it'));
      }
      box.appendChild(row);
    };
    const cur = this.values(), qd = {};
    for (const k of this.presetKeys()) qd[k] = d[k];
    for (const pr of this.method.presets) addRow(pr.name, Object.assign({}, d, cur, qd, pr.params), () => this.choose(pr.name), this.preset === pr.name);
    if (!this.preset) addRow('custom', this.values(), null, true);
  }

  setProgress(frac, text) {
    const el = $('fit-progress');
    el.classList.toggle('hidden', frac == null);
    $('fit-result').classList.toggle('hidden', frac != null);
    if (frac == null) return;
    el.querySelector('.bar-fill').style.width = (100 * frac).toFixed(1) + '%';
    el.querySelector('span').textContent = text;
  }

  fit() {
    if (this.busy) return this.running;
    if (this.blocker()) {                          // the keyboard: say it again, do not send
      const hint = $('fit-hint');
      hint.classList.remove('flash'); void hint.offsetWidth; hint.classList.add('flash');
      return Promise.resolve();
    }
    this.running = this.run();
    return this.running;
  }

  async run() {
    this.busy = true;
    $('fit-btn').disabled = true;
    const t0 = performance.now();
    this.setProgress(0, 'sending…');
    try {
      await this.session.writeChain;       // the strokes made so far are in the fit
      // a method that chooses among others takes a while: the quickest of
      // those it weighs is fitted beside it and shown first, then replaced
      // (its failure is not the fit's: caught here, before the fit's own
      // error can leave it unawaited)
      const first = this.method.chooses ? this.firstLook(t0).catch(() => {}) : null;
      const r = await this.api.fit(this.session.id, { method: this.method.name, params: this.values() });
      const body = await r.json();
      if (r.status === 201) {
        this.firstDone = true;
        this.setProgress(null);
        this.emit('material', { material: body, ms: performance.now() - t0, cached: true });
      } else {
        await this.follow(body.job, t0);
      }
      if (first) await first;
      this.refresh();
    } catch (e) {
      this.setProgress(null);
      this.emit('error', explain(e));
    } finally {
      this.busy = false;
      this.updateButton();
    }
  }

  // The first look while a choosing method works: the first method offered
  // for the same lighting that does not choose (the quickest the daemon
  // lists first), at its own settings but for the light the views were
  // painted under (the environment, its turn and brightness, as setMethod
  // fills them), shown only while the choice is still running and labelled
  // as such.  Its failure is not the fit's: nothing is shown then.
  async firstLook(t0) {
    this.firstDone = false;
    const q = this.methods.find(x => !x.chooses && x.lighting === this.method.lighting);
    if (!q) return;
    const own = new Set(q.params.map(p => p.name)), v = this.values(), light = {};
    for (const k of ['env', 'env_rotation', 'env_intensity'])
      if (own.has(k) && v[k] !== undefined) light[k] = v[k];
    const r = await this.api.fit(this.session.id, { method: q.name, params: light });
    let m = await r.json();
    if (r.status !== 201) {
      let j = m.job;
      while (j && j.state !== 'done' && j.state !== 'failed' && !this.firstDone) {
        await new Promise(ok => setTimeout(ok, 150));
        j = (await this.api.job(j.id)).job;
      }
      if (!j || j.state !== 'done' || this.firstDone) return;
      m = await this.api.material(j.material_id);
    }
    if (this.firstDone) return;
    this.emit('material', { material: m, ms: performance.now() - t0, cached: r.status === 201, first: true });
    this.firstNote = `showing ${q.label.charAt(0).toLowerCase() + q.label.slice(1)} first; `;
  }

  // Stream a job's progress until it is done (or failed).  The handler
  // answers each event at once (sse.js): the job's last event closes the
  // stream for good, and the material it names is read after that.
  follow(job, t0) {
    return new Promise((resolve, reject) => {
      this.firstNote = '';
      const show = j => this.setProgress(j.progress, (this.firstNote || '') + `${j.stage} ${(100 * j.progress).toFixed(0)}%` + (j.seconds != null ? ` · ${fmtTime(j.seconds)}` : ''));
      show(job);
      const es = new EventStream(`${API}/jobs/${job.id}/events`, {
        headers: { 'X-Glint-Token': this.session.token },
        final: ['done', 'failed'],
        onEvent: (type, j) => {
          if (typeof j !== 'object' || j === null) return undefined;
          if (type === 'done' || j.state === 'done') {
            this.firstDone = true;
            this.setProgress(null);
            this.api.material(j.material_id).then(
              m => { this.emit('material', { material: m, ms: performance.now() - t0, cached: false, job: j }); resolve(); },
              reject);
            return 'stop';
          }
          if (type === 'failed' || j.state === 'failed') {
            this.firstDone = true;
            this.setProgress(null);
            reject(new Error('The fit failed: ' + (j.error || 'no reason given')));
            return 'stop';
          }
          show(j);
          return undefined;
        },
        onState: (s, d) => { if (s === 'failed') { this.setProgress(null); reject(new Error('Following the fit job: ' + d)); } },
      });
      this.jobStream = es;
      es.start();
    });
  }
}
