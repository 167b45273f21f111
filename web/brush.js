// brush.js: the brush of seed 004 (section 4.3, eq. 23), exactly as
// core/truth/stroke.c applies it, so that what the canvas shows is what the
// server will fit (they agree within 1/255; in practice to the float).
//
// An image is {w, h, data: Float32Array(w*h*3)} of linear RGB, the same
// values the server keeps (8-bit files map v = q/255).  Pixel (i, j) has
// its centre at (i + 0.5, j + 0.5).  For a stroke:
//   d(p) = min over the polyline's segments of |p - q| (t clamped to [0,1]),
//   w(p) = opacity * exp(-kappa * d)  if d <= D/2, else 0,
//   paint: B = w C + (1-w) B';  scale: B = w S B' + (1-w) B';
//   erase: B = w Base + (1-w) B'.
// Everything is computed in double precision and stored as float32, as the
// C code does ((float)v).  One coverage per stroke: the minimum distance
// over the whole polyline, never accumulated over its points.

export const MODES = ['paint', 'scale', 'erase'];

// Squared distance from (px, py) to the segment a-b (a dab when a = b).
function segD2(px, py, ax, ay, bx, by) {
  const vx = bx - ax, vy = by - ay;
  const l2 = vx * vx + vy * vy;
  let t = 0;
  if (l2 > 0) {
    t = ((px - ax) * vx + (py - ay) * vy) / l2;
    if (t < 0) t = 0; else if (t > 1) t = 1;
  }
  const dx = px - (ax + t * vx), dy = py - (ay + t * vy);
  return dx * dx + dy * dy;
}

// Pixel index range [lo, hi] whose centres lie in [a, b], clipped to [0, n-1].
function pixRange(a, b, n) {
  let lo = Math.ceil(a - 0.5), hi = Math.floor(b - 0.5);
  if (lo < 0) lo = 0;
  if (hi > n - 1) hi = n - 1;
  return hi < lo ? null : [lo, hi];
}

// Segments of a stroke as flat [ax, ay, bx, by] quadruples.
function segments(pts) {
  const out = [];
  if (pts.length === 1) out.push([pts[0][0], pts[0][1], pts[0][0], pts[0][1]]);
  for (let i = 0; i + 1 < pts.length; i++)
    out.push([pts[i][0], pts[i][1], pts[i + 1][0], pts[i + 1][1]]);
  return out;
}

export function weightOf(s, d) {
  if (!(d <= 0.5 * s.diameter)) return 0;
  const op = s.opacity === undefined ? 1 : s.opacity;
  return op * Math.exp(-(s.kappa || 0) * d);
}

// The pixel box a stroke can touch, clipped to w x h: [x0, y0, x1, y1]
// inclusive, or null.
export function strokeBox(s, w, h) {
  const r = 0.5 * s.diameter;
  let xmin = Infinity, xmax = -Infinity, ymin = Infinity, ymax = -Infinity;
  for (const [x, y] of s.points) {
    if (x < xmin) xmin = x; if (x > xmax) xmax = x;
    if (y < ymin) ymin = y; if (y > ymax) ymax = y;
  }
  const rx = pixRange(xmin - r, xmax + r, w), ry = pixRange(ymin - r, ymax + r, h);
  return rx && ry ? [rx[0], ry[0], rx[1], ry[1]] : null;
}

// New value of one channel.
function blend(mode, w, c, S, old, base) {
  if (mode === 'scale') return w * S * old + (1 - w) * old;
  if (mode === 'erase') return w * base + (1 - w) * old;
  return w * c + (1 - w) * old;
}

// Apply stroke s to image `im` in place.  `base` (same size) is needed by
// erase strokes.  `clip` ([x0, y0, x1, y1], optional) limits the pixels
// changed (used to replay strokes over a region).  Returns the box of the
// pixels changed, or null.
export function applyStroke(s, im, base, clip) {
  const mode = s.mode || 'paint';
  if (mode === 'erase' && !base) throw new Error('an erase stroke needs the base render');
  let box = strokeBox(s, im.w, im.h);
  if (!box) return null;
  if (clip) {
    box = [Math.max(box[0], clip[0]), Math.max(box[1], clip[1]),
           Math.min(box[2], clip[2]), Math.min(box[3], clip[3])];
    if (box[2] < box[0] || box[3] < box[1]) return null;
  }
  const r = 0.5 * s.diameter, segs = segments(s.points);
  const col = s.color || [0, 0, 0], S = s.scale === undefined ? 1 : s.scale;
  const W = im.w, px = im.data, bp = base ? base.data : null;
  let cx0 = Infinity, cy0 = Infinity, cx1 = -1, cy1 = -1;
  for (let y = box[1]; y <= box[3]; y++) {
    const py = y + 0.5;
    // segments whose expanded box reaches this row
    const cand = segs.filter(g => !(Math.max(g[1], g[3]) + r < py || Math.min(g[1], g[3]) - r > py));
    if (!cand.length) continue;
    for (let x = box[0]; x <= box[2]; x++) {
      const pxc = x + 0.5;
      let best = Infinity;
      for (let c = 0; c < cand.length && best > 0; c++) {
        const g = cand[c];
        const d2 = segD2(pxc, py, g[0], g[1], g[2], g[3]);
        if (d2 < best) best = d2;
      }
      const w = weightOf(s, Math.sqrt(best));
      if (!(w > 0)) continue;
      const o = 3 * (y * W + x);
      for (let ch = 0; ch < 3; ch++)
        px[o + ch] = blend(mode, w, col[ch], S, px[o + ch], bp ? bp[o + ch] : 0);
      if (x < cx0) cx0 = x; if (x > cx1) cx1 = x;
      if (y < cy0) cy0 = y; if (y > cy1) cy1 = y;
    }
  }
  return cx1 < 0 ? null : [cx0, cy0, cx1, cy1];
}

// A stroke being drawn: keeps the minimum squared distance per pixel, so
// each new point costs only the area of its own segment, and renders
// before -> after from the image as it was when the stroke began.  The
// result equals applyStroke on the finished stroke, value for value.
export class LiveStroke {
  constructor(s, before, base) {
    this.s = s;                  // {mode, color, diameter, kappa, scale, opacity, points: []}
    this.before = before;        // image the stroke starts from (not modified)
    this.base = base;
    this.d2 = new Float64Array(before.w * before.h).fill(Infinity);
    this.box = null;             // pixels touched so far
  }

  // Add a point; updates `out` (an image equal to `before` outside the
  // stroke's pixels) and returns the box of pixels rewritten, or null.
  add(x, y, out) {
    const s = this.s, pts = s.points;
    pts.push([x, y]);
    const a = pts.length > 1 ? pts[pts.length - 2] : pts[0], b = pts[pts.length - 1];
    const seg = { mode: s.mode, diameter: s.diameter, points: [a, b] };
    const box = strokeBox(seg, out.w, out.h);
    if (!box) return null;
    const W = out.w, d2 = this.d2, src = this.before.data, dst = out.data;
    const bp = this.base ? this.base.data : null;
    const mode = s.mode || 'paint', col = s.color || [0, 0, 0];
    const S = s.scale === undefined ? 1 : s.scale;
    for (let yy = box[1]; yy <= box[3]; yy++) {
      const py = yy + 0.5;
      for (let xx = box[0]; xx <= box[2]; xx++) {
        const i = yy * W + xx;
        const dd = segD2(xx + 0.5, py, a[0], a[1], b[0], b[1]);
        if (!(dd < d2[i])) continue;
        d2[i] = dd;
        const w = weightOf(s, Math.sqrt(dd));
        if (!(w > 0)) continue;
        const o = 3 * i;
        for (let ch = 0; ch < 3; ch++)
          dst[o + ch] = blend(mode, w, col[ch], S, src[o + ch], bp ? bp[o + ch] : 0);
      }
    }
    this.box = this.box ? [Math.min(this.box[0], box[0]), Math.min(this.box[1], box[1]),
                           Math.max(this.box[2], box[2]), Math.max(this.box[3], box[3])] : box;
    return box;
  }
}

// The JSON the server takes (stroke.h): only the fields of the mode.
export function strokeJSON(s, tag) {
  const o = { mode: s.mode || 'paint' };
  if (o.mode === 'paint') o.color = s.color.slice(0, 3);
  o.diameter = s.diameter;
  o.kappa = s.kappa || 0;
  if (o.mode === 'scale') o.scale = s.scale;
  o.opacity = s.opacity === undefined ? 1 : s.opacity;
  o.points = s.points.map(p => [p[0], p[1]]);
  if (tag) o.tag = tag;
  return o;
}
