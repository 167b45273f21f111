// ball.js: the material ball: the current material on a sphere under an
// environment (the neutral studio light by default, any built-in sky or
// captured map), beside the point-light preview of the object.  Dragging
// turns the environment; glintd renders each frame
// (GET /materials/{id}/preview.png?object=ball&env=&env_rotation=).

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

  // One request in flight; the newest wanted frame follows when it returns.
  request() {
    $('ball-rot-v').textContent = $('ball-rot').value + '°';
    if (!this.mat) return;
    this.want++;
    if (!this.inflight) this.fetchFrame();
  }

  async fetchFrame() {
    const n = this.want, mat = this.mat, q = this.query();
    this.inflight = true;
    const t0 = performance.now();
    try {
      const r = await this.api.materialFile(mat.id, 'preview.png', q);
      const bmp = await createImageBitmap(await r.blob(), { colorSpaceConversion: 'none' });
      if (mat === this.mat && n > this.shown) {
        $('ball').getContext('2d').drawImage(bmp, 0, 0, SIZE, SIZE);
        this.shown = n;
        this.frames++;
        this.last = { ms: performance.now() - t0, renderer: r.headers.get('X-Glint-Renderer') || '',
                      env: r.headers.get('X-Glint-Env') || '', query: q };
        $('ball-empty').classList.add('hidden');
        $('ball').title = `the material on a ball under ${q.env}, turned ${q.env_rotation}° ` +
          `(${Math.round(this.last.ms)} ms) · drag: turn the light · double-click: reset`;
        this.dispatchEvent(new CustomEvent('frame', { detail: this.last }));
      }
    } catch (e) {
      this.dispatchEvent(new CustomEvent('error', { detail: e }));
    } finally {
      this.inflight = false;
      if (this.want > n && mat === this.mat) this.fetchFrame();
    }
  }
}
