// image.js: float RGB images {w, h, data: Float32Array(w*h*3)} and their
// way to and from the screen and the wire.
//
// On screen a value v shows as round(clamp(v * exposure, 0, 1) * 255): the
// same linear 8-bit mapping glintd uses for PNG (q/255 reads back as q), so
// at exposure 1 the canvas shows what GET .../painting?format=png returns.

import { decodeEXR, isEXR } from './exr.js';

export function newImage(w, h) { return { w, h, data: new Float32Array(w * h * 3) }; }
export function cloneImage(im) { return { w: im.w, h: im.h, data: new Float32Array(im.data) }; }

export function to8(v, exposure) {
  const x = v * (exposure || 1);
  return x <= 0 ? 0 : x >= 1 ? 255 : Math.round(x * 255);
}

// Write a box [x0, y0, x1, y1] (inclusive; whole image when omitted) of a
// float image into a 2D context at 1:1.
export function blit(ctx, im, box, exposure) {
  const b = box || [0, 0, im.w - 1, im.h - 1];
  const bw = b[2] - b[0] + 1, bh = b[3] - b[1] + 1;
  if (bw <= 0 || bh <= 0) return;
  const id = ctx.createImageData(bw, bh), o = id.data, d = im.data;
  for (let y = 0; y < bh; y++) {
    let s = 3 * ((b[1] + y) * im.w + b[0]), t = 4 * y * bw;
    for (let x = 0; x < bw; x++, s += 3, t += 4) {
      o[t] = to8(d[s], exposure); o[t + 1] = to8(d[s + 1], exposure); o[t + 2] = to8(d[s + 2], exposure); o[t + 3] = 255;
    }
  }
  ctx.putImageData(id, b[0], b[1]);
}

// Copy a box out of an image (for undo) and back in.
export function cropBox(im, b) {
  const bw = b[2] - b[0] + 1, bh = b[3] - b[1] + 1, out = new Float32Array(bw * bh * 3);
  for (let y = 0; y < bh; y++)
    out.set(im.data.subarray(3 * ((b[1] + y) * im.w + b[0]), 3 * ((b[1] + y) * im.w + b[2] + 1)), 3 * y * bw);
  return out;
}

export function pasteBox(im, b, data) {
  const bw = b[2] - b[0] + 1, bh = b[3] - b[1] + 1;
  for (let y = 0; y < bh; y++)
    im.data.set(data.subarray(3 * y * bw, 3 * (y + 1) * bw), 3 * ((b[1] + y) * im.w + b[0]));
}

export function unionBox(a, b) {
  if (!a) return b; if (!b) return a;
  return [Math.min(a[0], b[0]), Math.min(a[1], b[1]), Math.max(a[2], b[2]), Math.max(a[3], b[3])];
}

// Decode any image body glintd sends (EXR as float; PNG/JPEG through the
// browser, 8-bit q -> q/255) into a float RGB image.
export async function decodeImage(buf) {
  if (isEXR(buf)) return decodeEXR(buf);
  const bmp = await createImageBitmap(new Blob([buf]), { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
  return bitmapToImage(bmp, bmp.width, bmp.height);
}

// Draw a bitmap (optionally fitted into w x h) and read it as floats.
export function bitmapToImage(bmp, w, h, fit) {
  const c = new OffscreenCanvas(w, h), g = c.getContext('2d', { willReadFrequently: true, colorSpace: 'srgb' });
  g.fillStyle = '#000'; g.fillRect(0, 0, w, h);
  if (fit === 'stretch' || !fit) g.drawImage(bmp, 0, 0, w, h);
  else {
    const s = fit === 'cover' ? Math.max(w / bmp.width, h / bmp.height) : Math.min(w / bmp.width, h / bmp.height);
    const dw = bmp.width * s, dh = bmp.height * s;
    g.drawImage(bmp, (w - dw) / 2, (h - dh) / 2, dw, dh);
  }
  const px = g.getImageData(0, 0, w, h).data, im = newImage(w, h);
  for (let i = 0, j = 0; i < w * h; i++, j += 4) {
    im.data[3 * i] = px[j] / 255; im.data[3 * i + 1] = px[j + 1] / 255; im.data[3 * i + 2] = px[j + 2] / 255;
  }
  return im;
}

// Resample a float image to w x h (nearest texel; used when a dropped EXR
// has another size).
export function resizeImage(im, w, h) {
  if (im.w === w && im.h === h) return im;
  const out = newImage(w, h);
  for (let y = 0; y < h; y++)
    for (let x = 0; x < w; x++) {
      const sx = Math.min(im.w - 1, Math.floor((x + 0.5) * im.w / w)), sy = Math.min(im.h - 1, Math.floor((y + 0.5) * im.h / h));
      out.data.set(im.data.subarray(3 * (sy * im.w + sx), 3 * (sy * im.w + sx) + 3), 3 * (y * w + x));
    }
  return out;
}

export function imageToCanvas(im, exposure) {
  const c = document.createElement('canvas');
  c.width = im.w; c.height = im.h;
  blit(c.getContext('2d'), im, null, exposure);
  return c;
}
