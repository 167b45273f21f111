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

const uvCache = new Map();   // `${sceneId}/${k}` -> Promise of {w, h, data: U, V, mask}

// The texture coordinates and mask of view k (cached per scene and view).
export function viewUV(api, sceneId, k) {
  const key = `${sceneId}/${k}`;
  if (!uvCache.has(key)) {
    const p = (async () => {
      const r = await api.request('GET', `/scenes/${sceneId}/views/${k}/gbuffer.exr`, { raw: true, what: 'Reading the G-buffer of view ' + k });
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
export function paintThrough(base, uv, tex, flip) {
  const out = newImage(base.w, base.h), rgb = [0, 0, 0];
  out.data.set(base.data);
  if (uv.w !== base.w || uv.h !== base.h) throw new Error(`the G-buffer is ${uv.w}x${uv.h}, the view ${base.w}x${base.h}`);
  for (let p = 0; p < base.w * base.h; p++) {
    if (!(uv.data[3 * p + 2] > 0.5)) continue;
    texLookup(tex, uv.data[3 * p], uv.data[3 * p + 1], flip, rgb);
    for (let c = 0; c < 3; c++) out.data[3 * p + c] = base.data[3 * p + c] * rgb[c];
  }
  return out;
}
