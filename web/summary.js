// summary.js: the material in numbers an artist reads (GET
// /materials/{id}/summary, core/out/readable.h): its base colour, how strong
// and how wide its highlight is, how much light it reflects at a few
// angles, and BRDF Explorer's polar plot (f in the plane of incidence for
// lights at 15, 45 and 75 degrees).

const $ = id => document.getElementById(id);
const lum = v => 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2];
const q8 = v => Math.round(255 * Math.min(1, Math.max(0, v)));

export async function loadSummary(api, mat) {
  const r = await api.materialFile(mat.id, 'summary');
  return r.json();
}

// Words for the highlight.
function highlightWords(h) {
  if (!(h.strength > 0.05) || h.half_width_deg == null)
    return h.strength > 0.05 ? `a highlight ${h.strength.toFixed(1)}× the base, wider than the hemisphere reads` : 'no highlight: matte';
  const w = h.half_width_deg;
  if (h.strength < 0.25) return `a faint sheen: ${h.strength.toFixed(2)}× the base at the mirror direction, half width ${w.toFixed(1)}°`;
  const kind = w < 4 ? 'mirror-like' : w < 10 ? 'sharp' : w < 20 ? 'glossy' : w < 35 ? 'soft' : 'broad';
  return `${kind} highlight: ${h.strength.toFixed(1)}× brighter than the base, half width ${w.toFixed(1)}°`;
}

export function renderSummary(sm) {
  const b = sm.base_colour;
  $('sum-swatch').style.background = `rgb(${q8(b[0])},${q8(b[1])},${q8(b[2])})`;
  $('sum-base').textContent = `base colour ${b.map(x => x.toFixed(3)).join(' / ')}` + (Math.max(...b) > 1 ? ' (brighter than white: the painting\'s scale)' : '');
  $('sum-highlight').textContent = highlightWords(sm.highlight);
  const alb = sm.albedo.map(a => `${a.theta_deg}°: ${lum(a.rgb).toFixed(3)}`).join(' · ');
  const over = sm.albedo.some(a => Math.max(...a.rgb) > 1);
  $('sum-albedo').textContent = `share of the light it reflects, by the light's angle: ${alb}` + (over ? ' — above 1: more than it receives' : '');
  $('sum-albedo').title = 'advanced: the directional albedo (luminance) at each angle of incidence';
  drawPolar($('sum-polar'), sm);
}

// f in the plane of incidence, one curve per light angle, as a polar plot:
// the normal up, the light's side to the left; the viewing angle marked at
// 0, 30, 60 and 90 degrees each side, the radius read as brightness.
export const POLAR_TICKS = [-90, -60, -30, 0, 30, 60, 90];

// The plot's geometry on a W x H canvas: the centre (the point on the
// surface), the outer ring's radius, and where each angle's label goes.
export function polarLayout(W, H) {
  const cx = W / 2, cy = H - 18, R = Math.min(W / 2 - 26, H - 42);
  const ticks = POLAR_TICKS.map(t => {
    const a = t * Math.PI / 180;
    return { deg: t, text: `${Math.abs(t)}°`, x: cx + (R + 11) * Math.sin(a), y: cy - (R + 9) * Math.cos(a) };
  });
  return { cx, cy, R, ticks };
}

export function drawPolar(c, sm) {
  const g = c.getContext('2d'), W = c.width, H = c.height, { cx, cy, R, ticks } = polarLayout(W, H);
  g.clearRect(0, 0, W, H);
  let mx = 1e-9;
  for (const p of sm.polar) for (const f of p.f) mx = Math.max(mx, lum(f));
  g.strokeStyle = '#323744';
  for (const k of [0.25, 0.5, 0.75, 1]) { g.beginPath(); g.arc(cx, cy, R * k, Math.PI, 2 * Math.PI); g.stroke(); }
  g.beginPath(); g.moveTo(cx - R, cy); g.lineTo(cx + R, cy); g.moveTo(cx, cy); g.lineTo(cx, cy - R); g.stroke();
  drawPolarTicks(g, cx, cy, R, ticks);
  const cols = ['#ffb45e', '#6bd66b', '#6ba4ff'];
  sm.polar.forEach((p, j) => {
    g.strokeStyle = cols[j % 3]; g.lineWidth = 1.5; g.beginPath();
    p.theta_o_deg.forEach((t, i) => {
      const r = R * lum(p.f[i]) / mx, a = t * Math.PI / 180;
      const x = cx + r * Math.sin(a), y = cy - r * Math.cos(a);
      if (i) g.lineTo(x, y); else g.moveTo(x, y);
    });
    g.stroke();
    // the light's direction
    const a = -p.theta_i_deg * Math.PI / 180;
    g.setLineDash([3, 3]); g.beginPath(); g.moveTo(cx, cy); g.lineTo(cx + R * Math.sin(a), cy - R * Math.cos(a)); g.stroke(); g.setLineDash([]);
    g.fillStyle = cols[j % 3]; g.font = '10px system-ui';
    g.fillText(`light ${p.theta_i_deg}°`, 6, 12 + 12 * j);
  });
  g.fillStyle = '#8d94a3'; g.font = '9px system-ui'; g.textAlign = 'right';
  g.fillText(`brightness · outer ring ${mx.toPrecision(3)}`, W - 4, 12);
  g.textAlign = 'center';
  g.fillText('viewing angle from straight on', cx, H - 3);
  g.textAlign = 'left';
}

// Spokes and labels at the viewing angles of POLAR_TICKS, just outside
// the outer ring (angle a from the normal: x = sin a, y = cos a).
function drawPolarTicks(g, cx, cy, R, ticks) {
  g.save();
  g.strokeStyle = '#2a2e38'; g.fillStyle = '#8d94a3'; g.font = '9px system-ui';
  g.textAlign = 'center'; g.textBaseline = 'middle';
  for (const t of ticks) {
    const a = t.deg * Math.PI / 180;
    if (t.deg % 90) { g.beginPath(); g.moveTo(cx, cy); g.lineTo(cx + R * Math.sin(a), cy - R * Math.cos(a)); g.stroke(); }
    g.fillText(t.text, t.x, t.y);
  }
  g.restore();
}
