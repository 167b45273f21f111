// words.js: the studio's numbers and names as an artist reads them.
//
// An error is said as a percentage of the painting's own brightness: the
// RMS of (fitted - painted) over the object's pixels and RGB, divided by
// the RMS of the painted values over the same pixels (both in the
// painting's units, so the ratio holds for 8-bit paintings and for HDR
// ones painted under an environment alike).  The RMS itself, the sample
// counts and the method's name are kept for the "advanced" disclosures.
//
// Environments that share a file name (three uploads of my_loft.exr) are
// told apart by a number in the order glintd lists them, their size and
// upload time going into the tooltip.

// The error relative to the painting's brightness (a fraction), or null
// when either figure is missing or the painting is black.
export function relError(rms, level) {
  if (rms == null || !isFinite(rms) || !(level > 0) || !isFinite(level)) return null;
  return rms / level;
}

// A fraction as a percentage with two significant figures ("3.2%", "0.41%",
// "12%"); '?' when unknown.
export function pct(frac) {
  if (frac == null || !isFinite(frac)) return '?';
  const p = 100 * frac;
  if (p >= 10) return p.toFixed(0) + '%';
  if (p >= 1) return p.toFixed(1) + '%';
  return p.toPrecision(2) + '%';
}

// The one-line meaning of an error: "3.2% — the fitted material differs
// from your painting by about 3% of its brightness".
export function errorMeaning(frac) {
  if (frac == null || !isFinite(frac)) return 'error not known yet';
  const p = 100 * frac, about = p >= 1 ? Math.round(p) + '%' : p >= 0.1 ? 'less than 1%' : 'almost nothing';
  return `${pct(frac)} — the fitted material differs from your painting by about ${about}${p >= 0.1 ? ' of its brightness' : ''}`;
}

// Sums for the painting's brightness over a set of pixels: add each
// painted RGB value's square; level() is their RMS.
export class Level {
  constructor() { this.s2 = 0; this.n = 0; }
  add(v) { this.s2 += v * v; this.n++; }
  merge(o) { this.s2 += o.s2; this.n += o.n; return this; }
  level() { return this.n ? Math.sqrt(this.s2 / this.n) : null; }
}

// Labels for a list of environments ({spec, name, kind, width, height,
// bytes, created}): spec -> {text, title}.  A name that repeats gets
// " (2)", " (3)", ... from its second appearance on; the title carries the
// size and the upload time.
export function envLabels(envs) {
  const seen = new Map(), out = new Map();
  for (const e of envs || []) {
    const n = (seen.get(e.name) || 0) + 1;
    seen.set(e.name, n);
    out.set(e.spec, envLabel(e, n));
  }
  return out;
}

// The label of one environment, the n-th of its name.
export function envLabel(e, n) {
  const text = e.name + (e.kind === 'builtin' ? ' (built-in)' : '') + (n > 1 ? ` (${n})` : '');
  const bits = [];
  if (e.width && e.height) bits.push(`${e.width}×${e.height}`);
  if (e.bytes != null) bits.push(e.bytes >= 1048576 ? (e.bytes / 1048576).toFixed(1) + ' MB' : Math.max(1, Math.round(e.bytes / 1024)) + ' kB');
  if (e.created) bits.push('uploaded ' + new Date(e.created).toLocaleString());
  return { text, title: [text, ...bits].join(' · ') };
}

// The next number for a name among labels already given (an upload made
// in this studio joins the list glintd gave).
export function envNth(envs, name) {
  return (envs || []).filter(e => e.name === name).length;
}

// The painting's brightness sums of one view of the session (its
// confirmed painting over the pixels its base render lights: the pixels
// that give the fit its samples), cached until the view changes (its seq
// or version).  null while the view is not loaded.
const levels = new WeakMap();
export function viewLevel(v) {
  if (!v || !v.conf || !v.base || v.base.w !== v.conf.w || v.base.h !== v.conf.h) return null;
  const key = `${v.seq}/${v.version}/${v.conf.w}`;
  const c = levels.get(v);
  if (c && c.key === key && c.im === v.conf) return c.sums;
  const sums = new Level(), p = v.conf.data, b = v.base.data;
  for (let i = 0; i < p.length; i += 3) {
    if (!(b[i] > 0 || b[i + 1] > 0 || b[i + 2] > 0)) continue;
    sums.add(p[i]); sums.add(p[i + 1]); sums.add(p[i + 2]);
  }
  levels.set(v, { key, im: v.conf, sums });
  return sums;
}

// The painting's brightness (RMS of its values) over the views listed
// (those loaded), or null when none is.
export function sessionLevel(session, views) {
  const all = new Level();
  for (const k of views || []) {
    const s = viewLevel(session.views[k]);
    if (s) all.merge(s);
  }
  return all.level();
}
