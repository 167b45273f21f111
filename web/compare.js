// compare.js: the painting against the fitted material, large, in the view
// being painted.  "split": the fit right of a line the slider moves, the
// painting left of it, at the painting's zoom and exposure.  "difference":
// the fit minus the painting in luminance, red where the fit is brighter,
// blue where it is darker, scaled so that full colour is the 99th
// percentile of |difference| over the object (the scale is printed, so a
// faint difference does not read as a large one).  The fitted image is the
// judge's render of the material for that view (the CPU renderer, the
// rasterizer that defines the fit's samples).

import { blit, resizeImage, to8 } from './image.js';
import { errorMeaning, pct } from './words.js';

const $ = id => document.getElementById(id);
const lum = (d, i) => 0.2126 * d[3 * i] + 0.7152 * d[3 * i + 1] + 0.0722 * d[3 * i + 2];

// The signed luminance difference over the object and its scale: d[i] =
// Y(fitted) - Y(painted) (NaN off the object), scale = the 99th percentile
// of |d| (at least 1e-4), rms over the object; level = the RMS of the
// painting's luminance there (the brightness the percentages are of).
export function signedDiff(painted, fitted, base) {
  const n = painted.w * painted.h, d = new Float32Array(n), mags = [];
  let s2 = 0, p2 = 0;
  for (let i = 0; i < n; i++) {
    const on = lum(base.data, i) > 0 || lum(fitted.data, i) > 0;
    if (!on) { d[i] = NaN; continue; }
    d[i] = lum(fitted.data, i) - lum(painted.data, i);
    mags.push(Math.abs(d[i]));
    s2 += d[i] * d[i];
    p2 += lum(painted.data, i) ** 2;
  }
  mags.sort((a, b) => a - b);
  const p99 = mags.length ? mags[Math.min(mags.length - 1, Math.floor(0.99 * mags.length))] : 0;
  const level = mags.length ? Math.sqrt(p2 / mags.length) : 0;
  return { d, scale: Math.max(1e-4, p99), rms: mags.length ? Math.sqrt(s2 / mags.length) : 0, pixels: mags.length, level };
}

// Diverging colours: 0 dark grey, +1 red, -1 blue.
export function diffColour(t) {
  if (Number.isNaN(t)) return [20, 22, 28];
  const a = Math.min(1, Math.abs(t));
  return t >= 0 ? [Math.round(45 + 210 * a), Math.round(45 + 20 * a), Math.round(45 - 10 * a)]
                : [Math.round(45 - 10 * a), Math.round(45 + 95 * a), Math.round(45 + 210 * a)];
}

export class Compare {
  constructor(session, judge, painter) {
    this.session = session;
    this.judge = judge;
    this.painter = painter;
    this.k = -1;
    this.cache = new Map();    // `${material id}/${view}` -> Promise of the fitted image
    this.last = null;          // what is shown: {mode, k, mat, scale, rms}
    $('compare-mode').onchange = () => this.update();
    $('compare-split').oninput = () => this.draw();
  }

  get mode() { return $('compare-mode').value; }

  // The view shown, the material or the painting changed.
  setView(k) { this.k = k; this.update(); }

  async update() {
    const mode = this.mode, c = $('overlay-fit');
    $('compare-split').classList.toggle('hidden', mode !== 'split');
    const mat = this.judge.mat, k = this.k;
    if (!mode || !mat || k < 0) {
      c.classList.add('hidden');
      $('compare-legend').textContent = mode && !mat ? 'fit first to compare' : '';
      this.fitted = null; this.last = null;
      return;
    }
    const key = mat.id + '/' + k;
    if (!this.cache.has(key)) this.cache.set(key, this.judge.fittedFor(k));
    let fitted;
    try { fitted = await this.cache.get(key); } catch (e) { this.cache.delete(key); $('compare-legend').textContent = 'no render: ' + e.message; return; }
    if (mat !== this.judge.mat || k !== this.k || mode !== this.mode) return;
    this.fitted = fitted;
    this.draw();
  }

  draw() {
    const c = $('overlay-fit'), S = this.session, v = S.views[this.k];
    if (!this.fitted || !v || !v.conf || !this.mode) return;
    const { w, h } = v.conf;
    const f = resizeImage(this.fitted, w, h);   // a painting uploaded at the raster's size
    if (c.width !== w || c.height !== h) { c.width = w; c.height = h; }
    const g = c.getContext('2d');
    c.classList.remove('hidden');
    if (this.mode === 'split') {
      const x = Math.round(w * +$('compare-split').value / 100);
      blit(g, f, null, this.painter.exposure);
      g.clearRect(0, 0, x, h);
      g.fillStyle = 'rgba(255,255,255,.85)';
      g.fillRect(Math.min(w - 1, x), 0, 1, h);
      // the view's error from the judge's table, when it has this view
      const row = this.judge.rows && this.judge.rows.get(this.k), lv = row && row.level.level();
      $('compare-legend').textContent = 'painted | fitted' + (lv ? ` · ${pct(row.rms / lv)} off` : '');
      $('compare-legend').title = lv ? `In this view: ${errorMeaning(row.rms / lv)} (advanced: RMS ${row.rms.toPrecision(3)})` : '';
      this.last = { mode: 'split', k: this.k, mat: this.judge.mat.id, split: x };
      return;
    }
    const sd = signedDiff(v.conf, f, v.base);
    const im = g.createImageData(w, h);
    for (let i = 0; i < w * h; i++) {
      const [r, gg, b] = diffColour(sd.d[i] / sd.scale);
      im.data[4 * i] = r; im.data[4 * i + 1] = gg; im.data[4 * i + 2] = b; im.data[4 * i + 3] = 255;
    }
    g.putImageData(im, 0, 0);
    const L = $('compare-legend');
    const of = x => sd.level > 0 ? pct(x / sd.level) : x.toPrecision(2);
    L.innerHTML = '<span class="sw" style="background:rgb(255,65,35)"></span>brighter <span class="sw" style="background:rgb(35,140,255)"></span>darker' +
      ` ±${of(sd.scale)}`;
    L.title = `Red: the fit is brighter than the painting; blue: darker. In this view: ${errorMeaning(sd.level > 0 ? sd.rms / sd.level : null)}. Full colour is ±${of(sd.scale)} of the painting's brightness ` +
      `(99% of the object's pixels differ by less). Advanced: luminance of the fit minus the painting over ${sd.pixels} pixels of the object, ` +
      `full colour ±${sd.scale.toPrecision(3)} (${to8(sd.scale, 1)}/255 of display white), RMS ${sd.rms.toPrecision(3)}, painting's RMS ${sd.level.toPrecision(3)}.`;
    this.last = { mode: 'diff', k: this.k, mat: this.judge.mat.id, scale: sd.scale, rms: sd.rms, pixels: sd.pixels, level: sd.level };
  }
}
