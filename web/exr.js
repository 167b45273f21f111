// exr.js: just enough OpenEXR to move float paintings between the studio
// and glintd without losing HDR values or precision.
//
// encodeEXR: single-part scanline file, channels B G R as 32-bit float,
//            no compression (every reader accepts it; loopback makes size moot).
// decodeEXR: single-part scanline files with NONE, ZIPS or ZIP compression
//            (what OpenImageIO writes for glintd), HALF / FLOAT / UINT channels;
//            returns {w, h, data: Float32Array RGB} (Y-only files are grey);
//            with pick = [three channel names] those channels instead of
//            R, G, B (a G-buffer's uv.U, uv.V, mask).
// Zip blocks are inflated with the browser's DecompressionStream('deflate').

const MAGIC = 20000630;
const LE = new Uint8Array(new Uint32Array([1]).buffer)[0] === 1;

function te(s) { return new TextEncoder().encode(s); }

export function encodeEXR(im) {
  const { w, h, data } = im;
  const parts = [];
  const attr = (name, type, bytes) => { parts.push(te(name + '\0' + type + '\0')); const n = new Uint8Array(4); new DataView(n.buffer).setInt32(0, bytes.length, true); parts.push(n, bytes); };
  const i32 = (...v) => { const b = new Uint8Array(4 * v.length); const d = new DataView(b.buffer); v.forEach((x, i) => d.setInt32(4 * i, x, true)); return b; };
  const f32 = (...v) => { const b = new Uint8Array(4 * v.length); const d = new DataView(b.buffer); v.forEach((x, i) => d.setFloat32(4 * i, x, true)); return b; };
  // chlist: name\0, pixel type (2 = FLOAT), pLinear, 3 reserved, xSampling, ySampling; then \0
  const ch = [];
  for (const c of ['B', 'G', 'R']) { ch.push(te(c + '\0'), i32(2), new Uint8Array(4), i32(1, 1)); }
  ch.push(new Uint8Array(1));
  attr('channels', 'chlist', concat(ch));
  attr('compression', 'compression', new Uint8Array([0]));
  attr('dataWindow', 'box2i', i32(0, 0, w - 1, h - 1));
  attr('displayWindow', 'box2i', i32(0, 0, w - 1, h - 1));
  attr('lineOrder', 'lineOrder', new Uint8Array([0]));
  attr('pixelAspectRatio', 'float', f32(1));
  attr('screenWindowCenter', 'v2f', f32(0, 0));
  attr('screenWindowWidth', 'float', f32(1));
  parts.push(new Uint8Array(1));
  const header = concat([i32(MAGIC, 2), ...parts]);
  const lineBytes = 3 * 4 * w, chunk = 8 + lineBytes;
  const out = new Uint8Array(header.length + 8 * h + chunk * h);
  out.set(header, 0);
  const dv = new DataView(out.buffer);
  let table = header.length, pos = header.length + 8 * h;
  for (let y = 0; y < h; y++) {
    dv.setBigUint64(table + 8 * y, BigInt(pos), true);
    dv.setInt32(pos, y, true); dv.setInt32(pos + 4, lineBytes, true);
    let p = pos + 8;
    for (const c of [2, 1, 0]) // B, G, R
      for (let x = 0; x < w; x++, p += 4) dv.setFloat32(p, data[3 * (y * w + x) + c], true);
    pos += chunk;
  }
  return out;
}

function concat(arrs) {
  let n = 0; for (const a of arrs) n += a.length;
  const o = new Uint8Array(n); let p = 0;
  for (const a of arrs) { o.set(a, p); p += a.length; }
  return o;
}

export function isEXR(buf) {
  return buf.byteLength >= 4 && new DataView(buf).getInt32(0, true) === MAGIC;
}

// (a stream made from the bytes directly: a Blob and a Response a block
// cost Chromium a round trip to its browser process each, 40 ms an image)
async function inflate(bytes, want) {
  const ds = new DecompressionStream('deflate');
  const w = ds.writable.getWriter();
  w.write(bytes).catch(() => {});
  w.close().catch(() => {});
  const r = ds.readable.getReader(), out = new Uint8Array(want);
  let n = 0;
  for (;;) {
    const { done, value } = await r.read();
    if (done) break;
    if (n + value.length > want) throw new Error('an EXR block inflates to more than its lines');
    out.set(value, n); n += value.length;
  }
  return n === want ? out : out.subarray(0, n);
}

// Undo OpenEXR's zip predictor and byte interleaving (in place into a new array).
function unpredict(t) {
  for (let i = 1; i < t.length; i++) t[i] = (t[i - 1] + t[i] - 128) & 255;
  const out = new Uint8Array(t.length), half = (t.length + 1) >> 1;
  for (let i = 0, a = 0, b = half; i < t.length; ) {
    out[i++] = t[a++];
    if (i < t.length) out[i++] = t[b++];
  }
  return out;
}

function halfToFloat(hh) {
  const s = hh & 0x8000 ? -1 : 1, e = (hh >> 10) & 31, f = hh & 1023;
  if (e === 0) return s * f * 2 ** -24;
  if (e === 31) return f ? NaN : s * Infinity;
  return s * (1 + f / 1024) * 2 ** (e - 15);
}

export async function decodeEXR(buf, pick) {
  const dv = new DataView(buf), u8 = new Uint8Array(buf);
  if (dv.getInt32(0, true) !== MAGIC) throw new Error('not an OpenEXR file');
  const flags = dv.getUint32(4, true);
  if (flags & 0x200) throw new Error('tiled OpenEXR files are not supported');
  if (flags & 0x1800) throw new Error('multi-part or deep OpenEXR files are not supported');
  let p = 8;
  const str = () => { let e = p; while (u8[e] !== 0) e++; const s = new TextDecoder().decode(u8.subarray(p, e)); p = e + 1; return s; };
  let channels = null, comp = 0, dw = null;
  for (;;) {
    const name = str();
    if (!name) break;
    const type = str(), size = dv.getInt32(p, true); p += 4;
    const end = p + size;
    if (name === 'channels' && type === 'chlist') {
      channels = [];
      while (u8[p] !== 0) {
        const cn = str(); const pt = dv.getInt32(p, true);
        const xs = dv.getInt32(p + 8, true), ys = dv.getInt32(p + 12, true); p += 16;
        if (xs !== 1 || ys !== 1) throw new Error('subsampled EXR channels are not supported');
        channels.push({ name: cn, type: pt, size: pt === 1 ? 2 : 4 });
      }
    } else if (name === 'compression') comp = u8[p];
    else if (name === 'dataWindow') dw = [0, 1, 2, 3].map(i => dv.getInt32(p + 4 * i, true));
    p = end;
  }
  if (!channels || !dw) throw new Error('EXR header lacks channels or dataWindow');
  const lpb = { 0: 1, 2: 1, 3: 16 }[comp];
  if (!lpb) throw new Error('EXR compression ' + comp + ' is not supported (none, zips and zip are)');
  const w = dw[2] - dw[0] + 1, h = dw[3] - dw[1] + 1;
  const data = new Float32Array(w * h * 3);
  const lineBytes = channels.reduce((a, c) => a + c.size * w, 0);
  const idx = { R: -1, G: -1, B: -1, Y: -1 };
  channels.forEach((c, i) => { const k = c.name.split('.').pop(); if (k in idx && idx[k] < 0) idx[k] = i; });
  const src = pick ? pick.map(n => channels.findIndex(c => c.name === n))
    : idx.R >= 0 ? [idx.R, idx.G, idx.B] : [idx.Y, idx.Y, idx.Y];
  if (src.some(i => i < 0)) throw new Error(pick ? 'EXR lacks one of the channels ' + pick.join(', ') : 'EXR has no R, G, B (or Y) channels');
  const nblocks = Math.ceil(h / lpb);
  // where each channel's samples start within a line, and which of R, G, B it feeds
  const chOff = [];
  let acc = 0;
  for (const c of channels) { chOff.push(acc); acc += c.size * w; }
  const feeds = channels.map((c, ci) => [0, 1, 2].filter(k => src[k] === ci));
  const jobs = [];
  for (let b = 0; b < nblocks; b++) {
    const off = Number(dv.getBigUint64(p + 8 * b, true));
    const y = dv.getInt32(off, true) - dw[1], n = dv.getInt32(off + 4, true);
    const lines = Math.min(lpb, h - y);
    const raw = u8.subarray(off + 8, off + 8 + n);
    const want = lines * lineBytes;
    jobs.push((async () => {
      let block = (comp === 0 || n === want) ? raw : unpredict(await inflate(raw, want));
      if (block.byteOffset & 3) block = block.slice();          // aligned for typed views
      const bd = new DataView(block.buffer, block.byteOffset, block.byteLength);
      for (let l = 0; l < lines; l++) {
        const row = (y + l) * w, lo = l * lineBytes;
        for (let ci = 0; ci < channels.length; ci++) {
          const c = channels[ci], ks = feeds[ci];
          if (!ks.length) continue;
          const at = block.byteOffset + lo + chOff[ci];
          let vals;
          if (c.type === 2 && LE) vals = new Float32Array(block.buffer, at, w);
          else if (c.type === 1) { const hv = new Uint16Array(block.buffer.slice(at, at + 2 * w)); vals = new Float32Array(w); for (let x = 0; x < w; x++) vals[x] = halfToFloat(hv[x]); }
          else { vals = new Float32Array(w); for (let x = 0; x < w; x++) vals[x] = c.type === 2 ? bd.getFloat32(lo + chOff[ci] + 4 * x, true) : bd.getUint32(lo + chOff[ci] + 4 * x, true); }
          for (const k of ks) for (let x = 0, o = 3 * row + k; x < w; x++, o += 3) data[o] = vals[x];
        }
      }
    })());
  }
  await Promise.all(jobs);
  return { w, h, data };
}
