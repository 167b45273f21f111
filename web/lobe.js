// lobe.js: what an environment-lit material of lobes is made of, drawn from
// its manifest (GET /materials/{id}: basis, lobes, centres, diffuse,
// errors.energy_profile): the distribution p(h) of half vectors over the
// hemisphere, a cut through it, and how close the fit came to the energy
// limit at each elevation.

const COLS = ['#ff6b6b', '#6bd66b', '#6ba4ff'];

// p(h) for a unit h in the local frame (RGB), from the manifest.
export function lobeValue(m, h) {
  const lam = m.basis.lambda, out = [0, 0, 0];
  for (let j = 0; j < m.centres.length; j++) {
    const x = m.centres[j];
    const e = lam * (h[0] * x[0] + h[1] * x[1] + h[2] * x[2] - 1);
    if (e < -40) continue;
    const w = Math.exp(e), c = m.lobes[j];
    out[0] += c[0] * w; out[1] += c[1] * w; out[2] += c[2] * w;
  }
  return out;
}

// m: a manifest (GET /materials/{id}/material.json) with its lobes.
export function isLobeMaterial(m) {
  return !!(m && m.basis && Array.isArray(m.lobes) && Array.isArray(m.centres));
}

// The hemisphere of h seen from above (orthographic: the centre is the
// normal, the rim the horizon), colour = p(h) / its maximum; with a cut
// along the plane of incidence (x) below it.
export function drawLobe(canvas, m) {
  const g = canvas.getContext('2d'), W = canvas.width, H = canvas.height;
  g.clearRect(0, 0, W, H);
  if (!isLobeMaterial(m)) return;
  const D = Math.min(W, 160), R = D / 2 - 4, cx = D / 2, cy = D / 2;
  const img = g.createImageData(D, D), vals = new Float32Array(D * D * 3);
  let mx = 1e-30;
  for (let y = 0; y < D; y++) for (let x = 0; x < D; x++) {
    const u = (x + 0.5 - cx) / R, v = (cy - y - 0.5) / R, r2 = u * u + v * v;
    if (r2 > 1) continue;
    const p = lobeValue(m, [u, v, Math.sqrt(1 - r2)]);
    for (let c = 0; c < 3; c++) { vals[3 * (y * D + x) + c] = p[c]; mx = Math.max(mx, p[c]); }
  }
  for (let i = 0; i < D * D; i++) {
    for (let c = 0; c < 3; c++) img.data[4 * i + c] = Math.round(255 * Math.pow(vals[3 * i + c] / mx, 1 / 2.2));
    img.data[4 * i + 3] = 255;
  }
  g.putImageData(img, 0, 0);
  g.strokeStyle = 'rgba(255,255,255,.35)';
  g.beginPath(); g.arc(cx, cy, R, 0, 7); g.stroke();
  g.beginPath(); g.moveTo(cx - R, cy); g.lineTo(cx + R, cy); g.stroke();
  g.fillStyle = '#8d94a3'; g.font = '10px system-ui';
  g.fillText('the highlight, from above', 4, D + 12);
  g.fillText('centre: straight on · rim: grazing', 4, D + 24);
  g.fillText(`brightest ${mx.toPrecision(3)}`, 4, D + 36);
  // the cut through the plane of incidence: p(h) against the angle of h
  const L = D + 28, T = 14, CW = W - L - 6, CH = D - 30;
  const cut = [];
  for (let i = 0; i <= 90; i++) {
    const t = (i / 90 - 0.5) * Math.PI;       // -90..90 degrees from the normal
    cut.push(lobeValue(m, [Math.sin(t), 0, Math.cos(t)]));
  }
  const top = Math.max(1e-30, ...cut.flat());
  g.strokeStyle = '#323744'; g.strokeRect(L, T, CW, CH);
  for (let c = 0; c < 3; c++) {
    g.strokeStyle = COLS[c]; g.lineWidth = 1.3; g.globalCompositeOperation = 'lighter';
    g.beginPath();
    cut.forEach((p, i) => { const x = L + CW * i / 90, y = T + CH - CH * p[c] / top; if (i) g.lineTo(x, y); else g.moveTo(x, y); });
    g.stroke(); g.globalCompositeOperation = 'source-over';
  }
  g.fillStyle = '#8d94a3';
  g.fillText('the highlight across the surface', L, T - 3);
  g.fillText('-90°', L, T + CH + 11); g.textAlign = 'center'; g.fillText('0° (straight on)', L + CW / 2, T + CH + 11);
  g.textAlign = 'right'; g.fillText('90°', L + CW, T + CH + 11); g.textAlign = 'left';
}

// The largest directional albedo the fit reached in each band of
// outgoing elevation (at its energy rows), against the limit.
export function drawEnergy(canvas, errors) {
  const g = canvas.getContext('2d'), W = canvas.width, H = canvas.height;
  g.clearRect(0, 0, W, H);
  const prof = errors && errors.energy_profile;
  if (!prof) return;
  const n = prof.elevation_deg.length, L = 34, T = 16, CW = W - L - 8, CH = H - T - 30;
  const top = 1.1;
  g.fillStyle = '#8d94a3'; g.font = '10px system-ui';
  g.fillText(`light reflected, by viewing angle (${prof.enforced ? 'kept within what it receives' : 'not held to what it receives'})`, L, T - 4);
  g.strokeStyle = '#323744'; g.strokeRect(L, T, CW, CH);
  const yOf = a => T + CH - CH * Math.min(a, top) / top;
  g.strokeStyle = '#e0b84d'; g.setLineDash([4, 3]);
  g.beginPath(); g.moveTo(L, yOf(prof.limit)); g.lineTo(L + CW, yOf(prof.limit)); g.stroke();
  g.setLineDash([]);
  g.textAlign = 'right'; g.fillText('1', L - 3, yOf(1) + 3); g.fillText('0', L - 3, T + CH); g.textAlign = 'left';
  const bw = CW / n;
  for (let b = 0; b < n; b++) {
    const a = prof.albedo_max[b], [lo, hi] = prof.elevation_deg[b];
    g.fillStyle = '#8d94a3'; g.textAlign = 'center';
    g.fillText(`${lo}–${hi}°`, L + bw * (b + 0.5), T + CH + 11);
    g.textAlign = 'left';
    if (!a) continue;
    for (let c = 0; c < 3; c++) {
      const x = L + bw * b + 3 + c * (bw - 6) / 3, y = yOf(a[c]);
      g.fillStyle = COLS[c];
      g.fillRect(x, y, (bw - 6) / 3 - 1, T + CH - y);
    }
  }
  const worst = Math.max(...prof.albedo_max.filter(Boolean).flat());
  g.fillStyle = '#c9ced8';
  g.fillText(`highest ${worst.toFixed(4)} · limit ${prof.limit}`, L, H - 4);
  canvas.dataset.worst = String(worst);
}
