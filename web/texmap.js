// texmap.js: a texture laid over the surface through each view's G-buffer
// (GET /scenes/{id}/views/{k}/gbuffer.exr: each pixel's texture
// coordinates and mask), so that one image (a photo of wood, a drawn
// pattern) paints every view at once, where the surface is.
//
// Conventions: the texture's top row is v = 1 and its bottom row v = 0
// (Blender's, and an OpenGL texture uploaded from an image file flipped);
// `flip` reads it the other way (row 0 at v = 0, as glint writes its own
// coefficient and spatial textures). Lookups are bilinear between texel
// centres, clamped at the edges; values are linear, as the studio's 8-bit
// mapping is (q / 255). A painted pixel is the view's base render times the
// texture colour; pixels off the surface keep the base render.

import { decodeEXR } from './exr.js';
import { newImage } from './image.js';
import { CLASS } from './requests.js';

const uvCache = new Map();   // `${sceneId}/${k}` -> Promise of {w, h, data: U, V, mask}

// The texture coordinates and mask of view k (cached per scene and view).
export function viewUV(api, sceneId, k) {
  const key = `${sceneId}/${k}`;
  if (!uvCache.has(key)) {
    const p = (async () => {
      const r = await api.images.run(null, signal => api.request('GET', `/scenes/${sceneId}/views/${k}/gbuffer.exr`, { raw: true, signal, what: 'Reading the G-buffer of view ' + k }), { cls: CLASS.paint });
      return decodeEXR(await r.arrayBuffer(), ['uv.U', 'uv.V', 'mask']);
    })();
    p.catch(() => uvCache.delete(key));
    uvCache.set(key, p);
  }
  return uvCache.get(key);
}

// The texture's RGB at (u, v) (OUT: out[3]).
export function texLookup(tex, u, v, flip, out) {
  const W = tex.w, H = tex.h, yv = flip ? v : 1 - v;
  const x = Math.min(Math.max(u * W - 0.5, 0), W - 1), y = Math.min(Math.max(yv * H - 0.5, 0), H - 1);
  const i = Math.min(Math.floor(x), W - 1), j = Math.min(Math.floor(y), H - 1);
  const i1 = Math.min(i + 1, W - 1), j1 = Math.min(j + 1, H - 1), fx = x - i, fy = y - j;
  for (let c = 0; c < 3; c++) {
    const at = (a, b) => tex.data[3 * (b * W + a) + c];
    out[c] = (1 - fy) * ((1 - fx) * at(i, j) + fx * at(i1, j)) + fy * ((1 - fx) * at(i, j1) + fx * at(i1, j1));
  }
  return out;
}

// The painting of one view: base times the texture where the mask is set.
// The base may be s times the G-buffer's size a side (a scene painted above
// its raster): each painted pixel then reads (u, v) interpolated bilinearly
// between the G-buffer's pixel centres where all four are on the surface
// and on one side of any seam of the (u, v) layout, the nearest G-buffer
// pixel elsewhere.
export function paintThrough(base, uv, tex, flip) {
  const out = newImage(base.w, base.h), rgb = [0, 0, 0];
  out.data.set(base.data);
  const s = base.w / uv.w;
  if (!(s >= 1 && Number.isInteger(s) && base.h === s * uv.h)) throw new Error(`the G-buffer is ${uv.w}x${uv.h}, the view ${base.w}x${base.h}`);
  const on = i => uv.data[3 * i + 2] > 0.5;
  for (let y = 0; y < base.h; y++) for (let x = 0; x < base.w; x++) {
    const p = y * base.w + x, near = Math.floor(y / s) * uv.w + Math.floor(x / s);
    if (!on(near)) continue;
    let u = uv.data[3 * near], v = uv.data[3 * near + 1];
    if (s > 1) {
      const fx = Math.min(Math.max((x + 0.5) / s - 0.5, 0), uv.w - 1), fy = Math.min(Math.max((y + 0.5) / s - 0.5, 0), uv.h - 1);
      const i = Math.min(Math.floor(fx), uv.w - 2), j = Math.min(Math.floor(fy), uv.h - 2), tx = fx - i, ty = fy - j;
      const q = [j * uv.w + i, j * uv.w + i + 1, (j + 1) * uv.w + i, (j + 1) * uv.w + i + 1];
      const span = c => Math.max(...q.map(a => uv.data[3 * a + c])) - Math.min(...q.map(a => uv.data[3 * a + c]));
      if (q.every(on) && span(0) < 0.25 && span(1) < 0.25) {   // not across a seam of the (u, v) layout
        const w4 = [(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty];
        u = 0; v = 0;
        for (let a = 0; a < 4; a++) { u += w4[a] * uv.data[3 * q[a]]; v += w4[a] * uv.data[3 * q[a] + 1]; }
      }
    }
    texLookup(tex, u, v, flip, rgb);
    for (let c = 0; c < 3; c++) out.data[3 * p + c] = base.data[3 * p + c] * rgb[c];
  }
  return out;
}
