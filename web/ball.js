// ball.js: the material ball: the current material on a sphere under an
// environment (the neutral studio light by default, any built-in sky or
// captured map), beside the point-light preview of the object.  Dragging
// turns the environment; glintd renders each frame
// (GET /materials/{id}/preview.png?object=ball&env=&env_rotation=).

import { CLASS, isAbort } from './requests.js';

const $ = id => document.getElementById(id);

// The ball's camera: a little above the equator, looking at the origin
// from the distance the scenes' views use (they frame the unit ball).
const EYE = [0, -3.5, 1.1];
const SIZE = 256;

export class Ball extends EventTarget {
  constructor(api) {
    super();
    this.api = api;
    this.mat = null;
    this.want = 0;
    this.shown = 0;
    this.inflight = false;
    this.frames = 0;
    this.last = null;          // {ms, renderer, env} of the newest frame shown
    const sel = $('ball-env');
    sel.onchange = () => this.request();
    $('ball-rot').oninput = () => this.request();
    this.bindDrag();
  }

  // Offer an environment (GET /environments, or one uploaded here).
  addEnv(e) {
    const o = document.createElement('option');
    o.value = e.spec; o.textContent = e.name;
    $('ball-env').appendChild(o);
    if (e.spec === 'studio') $('ball-env').value = 'studio';
  }

  setMaterial(m) {
    this.mat = m;
    const c = $('ball');
    c.style.opacity = this.frames && c.dataset.material !== m.id ? '0.35' : '';
    $('ball-empty').classList.toggle('hidden', this.frames > 0);
    this.request();
  }

  bindDrag() {
    const c = $('ball');
    c.addEventListener('pointerdown', e => { c.setPointerCapture(e.pointerId); this.drag = e.clientX; });
    c.addEventListener('pointermove', e => {
      if (this.drag == null) return;
      const dx = e.clientX - this.drag;
      if (Math.abs(dx) < 2) return;
      this.drag = e.clientX;
      const r = $('ball-rot');
      let v = +r.value + dx * 1.2;
      v = ((v + 180) % 360 + 360) % 360 - 180;
      r.value = String(Math.round(v / 5) * 5);
      this.request();
    });
    const end = () => { this.drag = null; };
    c.addEventListener('pointerup', end);
    c.addEventListener('pointercancel', end);
    c.addEventListener('dblclick', () => { $('ball-rot').value = '0'; this.request(); });
  }

  query() {
    return { object: 'ball', eye: EYE.join(','), size: String(SIZE), env: $('ball-env').value || 'studio',
             env_rotation: $('ball-rot').value };
  }

  // What a frame is for: the material and the environment (turning it
  // waits for the frame in flight; another material or environment aborts it).
  frameKey() { return this.mat ? this.mat.id + '|' + ($('ball-env').value || 'studio') : ''; }

  // One request in flight per material and environment; the newest wanted
  // frame follows when it returns.
  request() {
    $('ball-rot-v').textContent = $('ball-rot').value + '°';
    if (!this.mat) return;
    this.want++;
    if (this.inflight && this.inflight.key !== this.frameKey()) {
      this.api.images.abort('ball', 'another material or environment');
      this.inflight = null;
    }
    if (!this.inflight) this.fetchFrame();
  }

  async fetchFrame() {
    const n = this.want, mat = this.mat, q = this.query(), key = this.frameKey();
    const job = this.inflight = { key, n };
    const current = () => this.mat === mat && this.frameKey() === key;
    const t0 = performance.now();
    try {
      const r = await this.api.images.run('ball', (signal, h) => this.api.materialFile(mat.id, 'preview.png', q, signal, h),
        { cls: CLASS.interactive, current });
      const bmp = await createImageBitmap(await r.blob(), { colorSpaceConversion: 'none' });
      if (current() && n > this.shown) {
        const c = $('ball');
        c.getContext('2d').drawImage(bmp, 0, 0, SIZE, SIZE);
        c.dataset.material = mat.id;
        c.style.opacity = '';
        this.shown = n;
        this.frames++;
        this.last = { ms: performance.now() - t0, renderer: r.headers.get('X-Glint-Renderer') || '',
                      env: r.headers.get('X-Glint-Env') || '', query: q, material: mat.id };
        $('ball-empty').classList.add('hidden');
        $('ball').title = `the material on a ball under ${q.env}, turned ${q.env_rotation}° ` +
          `(${Math.round(this.last.ms)} ms) · drag: turn the light · double-click: reset`;
        this.dispatchEvent(new CustomEvent('frame', { detail: this.last }));
      }
    } catch (e) {
      if (!isAbort(e)) this.dispatchEvent(new CustomEvent('error', { detail: e }));
    } finally {
      if (this.inflight === job) {
        this.inflight = null;
        if (this.want > n && this.mat) this.fetchFrame();
      }
    }
  }
}
