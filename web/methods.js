// methods.js: what the studio knows of the fit methods, all of it from
// GET /methods (each method's own table in core): a plain-language label,
// what it models and when to use it, the lighting its painted views need,
// and what its materials hold (textures over the surface, factors or lobes
// to draw).  No module of the studio names a method: a method added to
// core reaches the method choice, its notes and the views of its materials
// from this answer alone.

let list = [];

// The catalogue, as GET /methods lists it (the first is the default).
export function setMethods(ms) { list = Array.isArray(ms) ? ms : []; }
export function methods() { return list; }
export function methodNamed(name) { return list.find(x => x.name === name) || null; }

// The method that describes a material: a material of a method that
// chooses among the others is the chosen method's (choice.chosen).
export function methodOf(m) {
  if (!m) return null;
  const chosen = m.choice && m.choice.chosen;
  return (chosen && methodNamed(chosen)) || methodNamed(m.method);
}

// Whether a material was fitted under an environment (its params name it).
export function underEnv(m) {
  const d = methodOf(m);
  return d ? d.lighting === 'environment' && !!(m.params && m.params.env) : !!(m && m.params && m.params.env);
}

// What of a material can be drawn beside its renders: 'factors', 'lobes' or 'none'.
export function shows(m) {
  const d = methodOf(m);
  return d ? d.shows : 'factors';
}

// The textures over the surface a material holds ('coefficients', 'spatial').
export function surfaceTextures(m) {
  const d = methodOf(m);
  return d && Array.isArray(d.surface) ? d.surface : [];
}

// The method a scene starts on, among those the server can fit: under an
// environment the first method lit by one; else the first that chooses the
// model the painting needs; else the default.
export function startMethod(env) {
  const can = list.filter(x => x.available !== false);
  if (!can.length) return list[0] || null;
  const env1 = env && can.find(x => x.lighting === 'environment');
  return env1 || can.find(x => x.chooses) || can[0];
}

// A material's size in words, from the members its summary carries
// (products, texels, a spatial grid, 2D factors, lobes), else its label.
export function sizeText(m) {
  const parts = [];
  if (m.components != null) parts.push(`${m.components} materials`);
  if (m.res != null) parts.push(`${m.res} texels`);
  if (m.s_res != null) parts.push(`${m.s_res}² spatial`);
  if (m.res_2d != null && Array.isArray(m.dims))
    parts.push(`${m.res_2d}² 2D (${m.dims.map((d, j) => d === 2 ? 'pqr'[j] : '').join('') || 'none'})`);
  if (typeof m.lobes === 'number') parts.push(`${m.lobes} lobes`);
  if (underEnv(m)) parts.push(String(m.params.env));
  if (parts.length) return parts.join(' · ');
  const d = methodOf(m);
  return d ? d.label : (m.method || '');
}
