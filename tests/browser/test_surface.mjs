// Materials that vary over the surface in the studio: the automatic choice
// is the default method and says what it weighed; a material map's
// coefficient textures and a hybrid's spatial factors are shown as textures
// and laid over the object through the view's G-buffer, per product, with
// the factor curves following the product chosen.  The paintings are gold
// stripes on red plastic over the texture coordinates, painted by the
// glint CLI on the scene glintd makes from the same size (the same scene
// hash), uploaded as a script would.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { run, openStudio, assert, assertEq, assertGE, SRC } from './harness.mjs';

const CLI = path.join(process.env.GLINT_BUILD_DIR || path.join(SRC, 'build'), 'core', 'glint');
const SIZE = 64;
const SPEC = 'stripes:freq=3,duty=0.5|lambert:kd=0.7/0.15/0.1|ct:kd=0.05,f0=0.9/0.7/0.3,rough=0.25';

// A session whose 12 views are painted with the stripes.
async function stripedSession(t) {
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'glint-surface-'));
  execFileSync(CLI, ['scene', 'create', '--size', String(SIZE), '-o', path.join(tmp, 'scene.json')], { stdio: 'ignore' });
  execFileSync(CLI, ['paint', path.join(tmp, 'scene.json'), '--brdf', SPEC, '-o', path.join(tmp, 'paint')], { stdio: 'ignore' });
  const s = await t.daemon.newSession({ width: SIZE, height: SIZE });
  for (let k = 0; k < s.scene.views.length; k++) {
    const bytes = fs.readFileSync(path.join(tmp, 'paint', `view_${String(k).padStart(2, '0')}.exr`));
    await t.daemon.api('PUT', `/sessions/${s.session.id}/views/${k}/painting`, bytes,
      { 'X-Glint-Token': s.session.paint_token, 'Content-Type': 'image/x-exr' });
  }
  fs.rmSync(tmp, { recursive: true, force: true });
  return s;
}

async function setValue(page, id, v) {
  await page.evaluate(([id, v]) => { const el = document.getElementById(id); el.value = v; el.dispatchEvent(new Event('change', { bubbles: true })); }, [id, String(v)]);
}

async function setParam(page, name, v) {
  await page.evaluate(([n, v]) => { const el = document.getElementById('param-' + n); el.value = v; el.dispatchEvent(new Event('input', { bubbles: true })); el.dispatchEvent(new Event('change', { bubbles: true })); }, [name, String(v)]);
}

async function fit(page) {
  const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
  await page.click('#fit-btn');
  await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: 120000 });
  const id = await page.evaluate(() => window.glint.lastFit.id);
  await page.waitForFunction(id => { const j = window.glint.state.judge; return j.mat && j.mat.id === id; }, id);
  return page.evaluate(() => window.glint.state.judge.mat);
}

// Distinct 8-bit values and the spread of a canvas's covered pixels.
function canvasStats(page, id) {
  return page.evaluate(id => {
    const c = document.getElementById(id), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    const seen = new Set(); let lo = 255, hi = 0;
    for (let i = 0; i < d.length; i += 4) { seen.add(d[i] << 16 | d[i + 1] << 8 | d[i + 2]); lo = Math.min(lo, d[i]); hi = Math.max(hi, d[i]); }
    return { w: c.width, h: c.height, distinct: seen.size, lo, hi };
  }, id);
}

run({
  async 'auto is the default and says what it weighed; maps show where each material is'(t) {
    const { url } = await stripedSession(t);
    const page = await t.page();
    await openStudio(page, url);
    await page.waitForSelector('#quality .q[data-preset]');
    assertEq(await page.inputValue('#fit-method'), 'auto', 'glint chooses the model by default');
    const a = await fit(page);
    const methods = (await t.daemon.api('GET', '/methods')).methods;
    const point = methods.filter(m => m.lighting === 'point' && !m.chooses).map(m => m.name);
    assert(a.choice && a.choice.candidates.length === point.length, 'the automatic choice reports its candidates: every method lit by lamps');
    // while it chose, the first of those was fitted and shown, and then replaced
    const first = await page.evaluate(() => window.glint.firstLook);
    t.log(`first look: ${JSON.stringify(first)}`);
    assert(first && first.method === point[0], 'a first look from the first method lit by lamps');
    assertEq(a.method, 'auto', 'then the chosen material is shown');
    // said in percentages once the views' brightness is known
    await page.waitForFunction(() => /\d%/.test((document.getElementById('auto-choice') || {}).textContent || ''), null, { timeout: 60000 });
    const said = await page.textContent('#auto-choice');
    t.log(`auto: ${said}`);
    // every candidate by its label (from GET /methods), with its error as a percentage; no method names
    const labels = new Map(methods.map(m => [m.name, m.label]));
    assert(said.includes(labels.get(a.choice.chosen)) && point.every(m => said.includes(labels.get(m))), 'every candidate by its label');
    assert(!point.some(m => new RegExp(`\\b${m}\\b`).test(said)), 'no method names: ' + said);
    // ... but one this glintd cannot fit (it lacks the measured materials'
    // fits the learned prior needs), named as not tried, the reason on hover
    const fitted = a.choice.candidates.filter(x => !x.skipped);
    assertEq((said.match(/\d%/g) || []).length >= fitted.length, true, 'each candidate\'s error as a percentage: ' + said);
    const skipped = a.choice.candidates.filter(x => x.skipped).map(x => x.method);
    assertEq(skipped.join(','), 'tab_prior', 'the learned prior is not tried without measured fits');
    assert(said.includes(`${labels.get('tab_prior')}: not tried here`), 'said so: ' + said);
    const why = await page.evaluate(() => [...document.querySelectorAll('#auto-choice span[title]')].map(e => e.title).join(' | '));
    assert(/measured/.test(why), 'the reason on hover: ' + why);
    // and in the method list it is offered but not choosable, the reason on hover
    const opt = await page.evaluate(() => { const o = document.querySelector('#fit-method option[value="tab_prior"]'); return o && { disabled: o.disabled, title: o.title }; });
    assert(opt && opt.disabled && /not on this server: .*measured/.test(opt.title), 'tab_prior offered but disabled: ' + JSON.stringify(opt));

    // material maps of 3 products
    await setValue(page, 'fit-method', 'maps');
    await setParam(page, 'res', 32);
    await setParam(page, 'components', 3);
    await setParam(page, 'map_res', 32);
    const m = await fit(page);
    assertEq(m.method, 'maps', 'a maps material');
    await page.click('.tabs button[data-tab="factors"]');
    await page.waitForFunction(() => !document.getElementById('surface-wrap').classList.contains('hidden'));
    // the maps' own textures (the automatic choice's material may have had some)
    await page.waitForFunction(id => (window.glint.state.judge.surface.shownOn || {}).material === id, m.id);
    const opts = await page.evaluate(() => [...document.getElementById('surface-product').options].map(o => o.value));
    assertEq(opts.length, m.components, 'one entry per product');
    assert(await page.evaluate(() => document.getElementById('surface-spatial-label').classList.contains('hidden')), 'maps have no spatial factor');
    const coef = await canvasStats(page, 'surface-coef');
    t.log(`coefficient texture of material 1: ${coef.w}x${coef.h}, ${coef.distinct} colours, red ${coef.lo}..${coef.hi}`);
    assertEq(coef.w, 32, 'the texture at map_res');
    assertGE(coef.hi - coef.lo, 100, 'the first material covers part of the surface, not all of it');
    const on0 = await page.evaluate(() => window.glint.state.judge.surface.shownOn);
    const view = await canvasStats(page, 'surface-view');
    t.log(`over the object (view ${on0.view}): ${on0.covered} pixels, mean weight ${on0.mean.toFixed(3)}, ${view.distinct} colours`);
    assertEq(view.w, SIZE, 'laid over the view at the raster size');
    assertGE(on0.covered, 500, 'the object covers the view');
    assertGE(view.distinct, 20, 'the weight varies over the object');
    // the second product: other weights, other factor curves
    const curves0 = await page.evaluate(() => Array.from(document.getElementById('factors').getContext('2d').getImageData(0, 0, 320, 300).data.filter((_, i) => i % 4 === 0)).reduce((a, b) => a + b, 0));
    await setValue(page, 'surface-product', 1);
    await page.waitForFunction(() => window.glint.state.judge.surface.shownOn.product === 1);
    const on1 = await page.evaluate(() => window.glint.state.judge.surface.shownOn);
    const curves1 = await page.evaluate(() => Array.from(document.getElementById('factors').getContext('2d').getImageData(0, 0, 320, 300).data.filter((_, i) => i % 4 === 0)).reduce((a, b) => a + b, 0));
    t.log(`material 2: mean weight ${on1.mean.toFixed(3)}; factor plot ink ${curves0} -> ${curves1}`);
    assert(Math.abs(on1.mean - on0.mean) > 1e-3, 'another product, other weights');
    assert(curves1 !== curves0, 'the factor curves follow the product');
    await page.locator('#surface-view').scrollIntoViewIfNeeded();
    await t.shot(page, '30-surface-maps.png');
  },

  async 'a hybrid shows each material\'s spatial factor over the object'(t) {
    const { url } = await stripedSession(t);
    const page = await t.page();
    await openStudio(page, url);
    await page.waitForSelector('#quality .q[data-preset]');
    await setValue(page, 'fit-method', 'hybrid');
    await setParam(page, 'res', 32);
    await setParam(page, 's_res', 8);
    await setParam(page, 'components', 2);
    await setParam(page, 'map_res', 32);
    const m = await fit(page);
    assertEq(m.method, 'hybrid', 'a hybrid material');
    await page.click('.tabs button[data-tab="factors"]');
    await page.waitForFunction(id => (window.glint.state.judge.surface.shownOn || {}).material === id, m.id);
    const shows = await page.evaluate(() => [...document.getElementById('surface-show').options].map(o => o.value));
    assertEq(shows.join(','), 'coef,spatial', 'both textures offered');
    await setValue(page, 'surface-show', 'spatial');
    await page.waitForFunction(() => window.glint.state.judge.surface.shownOn.what === 'spatial');
    const sp = await canvasStats(page, 'surface-spatial');
    const on = await page.evaluate(() => window.glint.state.judge.surface.shownOn);
    t.log(`spatial factor of material 1: ${sp.w}x${sp.h}, ${sp.distinct} colours; over the object ${on.covered} pixels`);
    assertEq(sp.w, 8, 'the spatial factor at s_res');
    assertGE(sp.distinct, 4, 'the spatial factor varies');
    assertGE(on.covered, 500, 'laid over the object');
    await page.locator('#surface-view').scrollIntoViewIfNeeded();
    await t.shot(page, '31-surface-hybrid.png');
  },
});
