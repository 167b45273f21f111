// presets.js: finishes to start from.  A preset is an analytic BRDF (core
// spec, brdf.h); applying it paints every view of the session with the
// server's own render of that BRDF (GET base.png?brdf=SPEC&format=exr, under
// the scene's point lights, or its environment when it has one), each view
// one undo step, for the artist to edit.  The colour replaces the diffuse
// albedo (kd) of the finishes that have one.  Measured materials the server
// offers (GET /measured: MERL tables, brdf=merl:<file>, and published fits
// of measured materials, brdf=sgd:<name> or abc:<name>) are finishes too.

import { decodeImage } from './image.js';

const $ = id => document.getElementById(id);
let state, api, toast, showError;

// Each finish by how it looks (name); id is the value the finish list
// keeps; the analytic spec and its parameters are in the tooltip.
export const PRESETS = [
  { id: 'matte', name: 'matte clay', title: 'Diffuse only, no highlight: chalk, clay, unfinished wood', spec: kd => `lambert:kd=${kd}` },
  { id: 'plastic', name: 'satin plastic', title: 'A diffuse colour under a white, fairly sharp highlight', spec: kd => `ct:kd=${kd},f0=0.04,rough=0.25` },
  { id: 'glossy', name: 'glossy paint', title: 'A sharp white highlight over the colour', spec: kd => `ct:kd=${kd},f0=0.05,rough=0.1` },
  { id: 'metal', name: 'polished metal', title: 'No diffuse colour: the colour is in the highlight (gold when the colour is)', spec: kd => `ct:kd=0,f0=${kd},rough=0.2` },
  { id: 'satin', name: 'brushed satin', title: 'A highlight stretched around the vertical axis (fit it as brushed / anisotropic)', spec: kd => `ward:kd=${kd},ks=0.4,rough=0.08,rough_y=0.3` },
  { id: 'rough', name: 'rough rubber', title: 'A wide, dim highlight: rubber, unglazed ceramic', spec: kd => `ct:kd=${kd},f0=0.04,rough=0.6` },
  // the analytic truths glint's own tests paint with (brdf.h's defaults; the colour is not used)
  { id: 'truth: phong32', name: 'white plastic, sharp highlight', title: 'Grey-white with a sharp highlight; its own colour', tech: 'Phong, exponent 32, the reference truth', spec: () => 'phong32', fixed: true },
  { id: 'truth: blinn20', name: 'white plastic, soft highlight', title: 'Grey-white with a softer highlight; its own colour', tech: 'Blinn-Phong, exponent 20, the reference truth', spec: () => 'blinn20', fixed: true },
  { id: 'truth: ct0.2', name: 'white glaze, glossy', title: 'A glossy glaze; its own colour', tech: 'Cook-Torrance GGX, roughness 0.2, the reference truth', spec: () => 'ct0.2', fixed: true },
  { id: 'truth: ct0.5', name: 'white glaze, rough', title: 'A rough glaze; its own colour', tech: 'Cook-Torrance GGX, roughness 0.5, the reference truth', spec: () => 'ct0.5', fixed: true },
  { id: 'truth: ward', name: 'white satin', title: 'A soft satin sheen; its own colour', tech: 'isotropic Ward, roughness 0.2', spec: () => 'ward', fixed: true },
];

// '#rrggbb' -> 'r/g/b' in [0, 1] (linear, as the studio reads 8-bit values).
export function kdOf(hex) {
  const v = [1, 3, 5].map(i => parseInt(hex.slice(i, i + 2), 16) / 255);
  return v.map(x => +x.toFixed(4)).join('/');
}

// The query that renders spec for view k as the scene's base is lit.
export function presetQuery(scene, spec) {
  const q = { brdf: spec, format: 'exr' };
  const b = scene.base || {};
  if (b.scale) q.scale = b.scale;
  if (b.env && b.env.spec) {
    q.env = b.env.spec;
    if (b.env.rotation != null) q.env_rotation = b.env.rotation;
    if (b.env.intensity != null) q.env_intensity = b.env.intensity;
    if (b.env.lights != null) q.lights = b.env.lights;
    if (b.env.shadows != null) q.shadows = b.env.shadows ? 1 : 0;
    if (b.env.background != null) q.background = b.env.background ? 1 : 0;
  }
  return q;
}

function presetChosen() {
  const p = PRESETS.find(x => x.id === $('preset-sel').value) || PRESETS[0];
  $('preset-colour').disabled = !!p.fixed;
  $('preset-note').textContent = p.title;
  return p;
}

// Every view painted with the server's render of the chosen finish.
async function applyPreset() {
  const S = state.session;
  if (!S.canPaint) { toast('View only', 'This link cannot change paintings.', 'error'); return; }
  const p = presetChosen(), spec = p.spec(kdOf($('preset-colour').value));
  const btn = $('preset-apply');
  btn.disabled = true;
  // The next view renders in glintd while this one is decoded and stored:
  // one render ahead, two requests at most.
  const render = v => api.request('GET', `/scenes/${S.scene.id}/views/${v.k}/base.png`, { query: presetQuery(S.scene, spec), raw: true, what: `Rendering ${p.name} for view ${v.k}` })
    .then(r => r.arrayBuffer());
  const ahead = v => { const x = render(v); x.catch(() => {}); return x; };   // its failure is read where it is awaited
  try {
    let n = 0, next = S.views.length ? ahead(S.views[0]) : null;
    for (let i = 0; i < S.views.length; i++) {
      const bytes = await next;
      next = i + 1 < S.views.length ? ahead(S.views[i + 1]) : null;
      // glintd's own file goes back as it came: decoded for the canvas, not encoded again
      await S.uploadImage(S.views[i].k, await decodeImage(bytes), new Uint8Array(bytes));
      btn.textContent = `${++n} of ${S.views.length}…`;
    }
    toast('Every view painted', `${n} views now show ${p.name}; edit them, then fit`);
  } catch (e) { showError(e); } finally { btn.disabled = false; btn.textContent = 'Paint all views'; }
}

// The finish list's entry for a finish: its look, its id as the value.
function presetOption(p) {
  const o = document.createElement('option');
  o.value = p.id; o.textContent = p.name; o.title = p.title + ' · advanced: ' + (p.tech || p.spec('kd'));
  return o;
}

// Wire the finish controls to the studio (once).
export function bindPresets(ctx) {
  ({ state, api, toast, showError } = ctx);
  const sel = $('preset-sel');
  if (sel.options.length) return;
  for (const p of PRESETS) sel.appendChild(presetOption(p));
  sel.onchange = presetChosen;
  $('preset-apply').onclick = applyPreset;
  presetChosen();
  api.measured().then(r => {
    for (const m of r.materials || []) {
      const fit = m.spec.startsWith('merl:') ? '' : ' ' + m.spec.slice(0, 3);
      const look = m.name.replace(/[-_.]+/g, ' ').trim();
      const p = { id: 'measured: ' + m.name + fit, name: `${look} (measured${fit ? ', fitted' : ''})`,
                  title: 'Measured from a real material; its own colour', tech: `${m.layout}, ${m.spec}`, spec: () => m.spec, fixed: true };
      PRESETS.push(p);
      sel.appendChild(presetOption(p));
    }
  }).catch(() => { /* the analytic finishes stay */ });
}
