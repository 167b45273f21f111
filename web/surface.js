// surface.js: what a material that varies over the surface holds, shown
// in the Factors tab: per product (material) its coefficient texture
// (where it is: coefficients.exr) and its spatial factor (how its colour
// varies: spatial.exr), those its method's description in GET /methods
// lists (`surface`), as textures over (u, v) and laid over the object in a
// painted view through that view's G-buffer (GET /scenes/{id}/views/{k}/
// gbuffer.exr: each pixel's texture coordinates), read as the renderer
// reads them: the
// coefficients bilinear between texel centres, the spatial factor bilinear
// between nodes at (i, j) / (s_res - 1).

import { decodeEXR } from './exr.js';
import { isAbort } from './requests.js';
import { surfaceTextures } from './methods.js';

const $ = id => document.getElementById(id);

// The textures over the surface a material holds (a chosen material's are
// its chosen method's): { coef, spatial }, or null when it holds none.
export function surfaceKind(m) {
  const t = surfaceTextures(m);
  const k = { coef: t.includes('coefficients'), spatial: t.includes('spatial') };
  return k.coef || k.spatial ? k : null;
}

// Bilinear between texel centres of an n x n texture t (row 0 at v = 0),
// clamped at the border: how glint reads coefficient textures.
function texelRead(t, n, u, v, off) {
  const x = Math.min(Math.max(u * n - 0.5, 0), n - 1), y = Math.min(Math.max(v * n - 0.5, 0), n - 1);
  const i = Math.min(Math.floor(x), n - 1), j = Math.min(Math.floor(y), n - 1);
  const i1 = Math.min(i + 1, n - 1), j1 = Math.min(j + 1, n - 1), fx = x - i, fy = y - j;
  const at = (a, b) => t[off + b * n + a];
  return (1 - fy) * ((1 - fx) * at(i, j) + fx * at(i1, j)) + fy * ((1 - fx) * at(i, j1) + fx * at(i1, j1));
}

// Bilinear between nodes at (i, j) / (s - 1) of RGB nodes (row 0 at v = 0).
function nodeRead(t, s, u, v, off, out) {
  const x = Math.min(Math.max(u, 0), 1) * (s - 1), y = Math.min(Math.max(v, 0), 1) * (s - 1);
  const i = Math.min(Math.floor(x), s - 2), j = Math.min(Math.floor(y), s - 2), fx = x - i, fy = y - j;
  for (let c = 0; c < 3; c++) {
    const at = (a, b) => t[3 * (off + b * s + a) + c];
    out[c] = (1 - fy) * ((1 - fx) * at(i, j) + fx * at(i + 1, j)) + fy * ((1 - fx) * at(i, j + 1) + fx * at(i + 1, j + 1));
  }
  return out;
}

const q8 = v => v <= 0 ? 0 : v >= 1 ? 255 : Math.round(v * 255);
// coefficient c in [0, 1]: dark slate to warm white
const heat = c => [q8(0.10 + 0.90 * c), q8(0.11 + 0.80 * c ** 1.2), q8(0.14 + 0.62 * c ** 2)];

export class SurfacePanel {
  constructor(api, session) {
    this.api = api;
    this.session = session;
    this.mat = null;
    this.product = 0;
    this.view = null;
    this.gbuf = new Map();                  // view -> {w, h, data: uv.U, uv.V, mask}
    this.onProduct = null;                  // called with the product shown
    $('surface-product').onchange = () => { this.product = +$('surface-product').value; this.draw(); if (this.onProduct) this.onProduct(this.product); };
    $('surface-show').onchange = () => this.drawOnObject();
  }

  // A new material (and the view to lay its textures over).
  async set(mat, view) {
    this.mat = mat;
    this.product = 0;
    this.coef = null;
    this.spatial = null;
    // nothing of the previous material stays drawn while this one's load
    this.shownOn = null;
    this.draw();
    const over = $('surface-view');
    over.width = over.width;
    $('surface-caption').textContent = '';
    const kind = surfaceKind(mat);
    $('surface-wrap').classList.toggle('hidden', !kind);
    if (!kind) return;
    const K = kind.coef ? mat.components || 1 : 1;
    const sel = $('surface-product');
    sel.textContent = '';
    for (let k = 0; k < K; k++) {
      const o = document.createElement('option');
      o.value = String(k);
      o.textContent = kind.coef ? `material ${k + 1} of ${K}` : 'the material';
      sel.appendChild(o);
    }
    sel.disabled = K < 2;
    const show = $('surface-show');
    show.textContent = '';
    const opts = [];
    if (kind.coef) opts.push(['coef', 'where it is (coefficient)']);
    if (kind.spatial) opts.push(['spatial', 'its colour (spatial factor)']);
    for (const [v, t] of opts) { const o = document.createElement('option'); o.value = v; o.textContent = t; show.appendChild(o); }
    $('surface-note').textContent = !kind.coef
      ? 'One material; its colour and brightness vary over the surface by the spatial factor s(u, v).'
      : !kind.spatial
        ? `${K} materials, each weighted over the surface by its coefficient texture (white: this material, black: none of it).`
        : `${K} materials, each weighted by its coefficient texture and tinted by its own spatial factor.`;
    const get = async f => decodeEXR(await (await this.api.images.run('surface:' + f,
      (signal, h) => this.api.materialFile(mat.id, f, undefined, signal, h), { current: () => mat === this.mat })).arrayBuffer());
    const [coef, spatial] = await Promise.all([kind.coef ? get('coefficients.exr') : null,
                                               kind.spatial ? get('spatial.exr') : null]);
    if (mat !== this.mat) return;
    // coefficients: K blocks of map_res rows, one channel; spatial: s_res rows per product
    if (coef) { this.coef = { n: coef.w, k: coef.h / coef.w, t: new Float32Array(coef.w * coef.h) }; for (let i = 0; i < coef.w * coef.h; i++) this.coef.t[i] = coef.data[3 * i]; }
    if (spatial) this.spatial = { s: spatial.w, k: spatial.h / spatial.w, t: spatial.data };
    this.draw();
    await this.setView(view);
  }

  async setView(k) {
    if (k == null || !this.mat || !surfaceKind(this.mat)) return;
    this.view = k;
    const sc = this.session.scene;
    if (!this.gbuf.has(k)) {
      try {
        const r = await this.api.images.run('gbuffer:' + k,
          signal => this.api.request('GET', `/scenes/${sc.id}/views/${k}/gbuffer.exr`, { raw: true, signal, what: 'Reading the G-buffer of view ' + k }));
        this.gbuf.set(k, await decodeEXR(await r.arrayBuffer(), ['uv.U', 'uv.V', 'mask']));
      } catch (e) {
        if (isAbort(e)) return;
        $('surface-caption').textContent = 'the object view needs the G-buffer: ' + e.message;
        return;
      }
    }
    if (k === this.view) this.drawOnObject();
  }

  // The product's textures over (u, v), v up.
  draw() {
    const p = this.product;
    const put = (id, n, fn) => {
      const c = $(id);
      c.classList.toggle('hidden', !n);
      if (!n) return;
      c.width = c.height = n;
      const g = c.getContext('2d'), im = g.createImageData(n, n);
      for (let y = 0; y < n; y++) for (let x = 0; x < n; x++) {
        const o = 4 * (y * n + x), [r, gg, b] = fn(x, n - 1 - y);
        im.data[o] = r; im.data[o + 1] = gg; im.data[o + 2] = b; im.data[o + 3] = 255;
      }
      g.putImageData(im, 0, 0);
    };
    const C = this.coef, S = this.spatial;
    put('surface-coef', C && p < C.k ? C.n : 0, (i, j) => heat(C.t[(p * C.n + j) * C.n + i]));
    let mx = 1e-12;
    if (S && p < S.k) for (let i = 0; i < S.s * S.s * 3; i++) mx = Math.max(mx, S.t[3 * p * S.s * S.s + i]);
    put('surface-spatial', S && p < S.k ? S.s : 0, (i, j) => [0, 1, 2].map(c => q8(S.t[3 * ((p * S.s + j) * S.s + i) + c] / mx)));
    this.scaleSpatial = mx;
    $('surface-coef-label').classList.toggle('hidden', !(C && p < C.k));
    $('surface-spatial-label').classList.toggle('hidden', !(S && p < S.k));
    this.drawOnObject();
  }

  // The chosen texture of the product laid over the object in the view.
  drawOnObject() {
    const G = this.gbuf.get(this.view), c = $('surface-view');
    if (!G || !this.mat) return;
    const what = $('surface-show').value, p = this.product, C = this.coef, S = this.spatial;
    if ((what === 'coef' && !(C && p < C.k)) || (what === 'spatial' && !(S && p < S.k))) return;
    c.width = G.w; c.height = G.h;
    const g = c.getContext('2d'), im = g.createImageData(G.w, G.h), rgb = [0, 0, 0];
    let covered = 0, sum = 0;
    for (let i = 0; i < G.w * G.h; i++) {
      const u = G.data[3 * i], v = G.data[3 * i + 1], on = G.data[3 * i + 2] > 0.5;
      let col = [20, 22, 28];
      if (on && what === 'coef') {
        const x = texelRead(C.t, C.n, u, v, p * C.n * C.n);
        col = heat(x); sum += x; covered++;
      } else if (on) {
        nodeRead(S.t, S.s, u, v, p * S.s * S.s, rgb);
        col = rgb.map(x => q8(x / this.scaleSpatial)); covered++;
      }
      im.data[4 * i] = col[0]; im.data[4 * i + 1] = col[1]; im.data[4 * i + 2] = col[2]; im.data[4 * i + 3] = 255;
    }
    g.putImageData(im, 0, 0);
    this.shownOn = { material: this.mat.id, view: this.view, what, product: p, covered, mean: covered ? sum / covered : 0 };
    $('surface-caption').textContent = `view ${this.view}: ` + (what === 'coef'
      ? `material ${p + 1}'s weight over the object (mean ${(covered ? sum / covered : 0).toFixed(2)} over ${covered} pixels)`
      : `material ${p + 1}'s spatial factor over the object (each channel over its maximum, ${this.scaleSpatial.toPrecision(3)})`);
  }
}
