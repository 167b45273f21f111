// Judging a material as an artist would: the material ball under the studio
// light beside the point-light preview (turned by dragging), the painting
// against the fit in the large view (split, and a signed difference whose
// scale is printed and checked against an independent computation from the
// server's painting and render), the first-visit guide (not in the way,
// dismissed for good, brought back from the help), a measured material the
// server offers painted as a finish, and the view a new torus opens on.
// Screenshots at 1440x900 and 1280x720.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import {
  run, openStudio, drawStroke, settled, paintAllViews, assert, assertLE, assertGE, assertEq, pageArray,
} from './harness.mjs';

// a measured material for the server to offer: a MERL table of a
// Cook-Torrance truth, written by the command line
const CLI = path.join(process.env.GLINT_BUILD_DIR || path.join(path.dirname(new URL(import.meta.url).pathname), '..', '..', 'build'), 'core', 'glint');
const MDIR = fs.mkdtempSync(path.join(os.tmpdir(), 'glint-measured-'));
const haveCli = fs.existsSync(CLI);
process.on('exit', () => fs.rmSync(MDIR, { recursive: true, force: true }));
if (haveCli) execFileSync(CLI, ['export-merl', '--brdf', 'ct:kd=0.5/0.2/0.1,f0=0.3,rough=0.15', '-o', path.join(MDIR, 'red-ct.binary')], { stdio: 'ignore' });

async function setRange(page, id, v) {
  await page.evaluate(([id, v]) => { const el = document.getElementById(id); el.value = v; el.dispatchEvent(new Event('input', { bubbles: true })); }, [id, String(v)]);
}

async function fit(page) {
  const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
  await page.waitForSelector('#quality .q[data-preset]');
  await page.click('#fit-btn');
  await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: 60000 });
  return page.evaluate(() => window.glint.lastFit);
}

// RGBA statistics of a canvas: mean brightness in a centred box of half side r (pixels),
// and every pixel.
async function canvasStats(page, id, r) {
  const centre = await page.evaluate(([id, r]) => {
    const c = document.getElementById(id), g = c.getContext('2d');
    const box = g.getImageData(c.width / 2 - r, c.height / 2 - r, 2 * r, 2 * r).data;
    let m = 0;
    for (let i = 0; i < box.length; i += 4) m += (box[i] + box[i + 1] + box[i + 2]) / 3;
    return m / (box.length / 4);
  }, [id, r]);
  const all = await pageArray(page, id => { const c = document.getElementById(id); return c.getContext('2d').getImageData(0, 0, c.width, c.height).data; }, id);
  return { centre, all };
}

run({
  async 'material ball, split and difference views, guide, at 1440x900 and 1280x720'(t) {
    const { url, session } = await t.daemon.newSession({ mesh: 'torus', width: 96, height: 96 });
    const page = await t.page();
    await page.setViewportSize({ width: 1440, height: 900 });
    await openStudio(page, url);
    // the guide is there on a first visit, and strokes go through it to the painting
    assert(await page.isVisible('#guide'), 'the first-visit guide shows');
    // its line on the methods comes from GET /methods (their labels)
    await page.waitForFunction(() => document.getElementById('guide-methods').textContent.length > 0);
    const guideText = await page.textContent('#guide');
    assert(/one finish, lit by lamps/.test(guideText) && /varies over the surface/.test(guideText), 'the guide says what the methods can represent');
    // start from the plastic finish on every view, then paint a highlight on view 3
    await page.selectOption('#preset-sel', 'plastic');
    await paintAllViews(page);
    await settled(page, 0);
    await setRange(page, 'diameter', 26);
    await page.keyboard.press('4');
    await page.waitForFunction(() => window.glint.state.k === 3 && window.glint.state.session.views[3].state === 'ready');
    await drawStroke(page, [[30, 40], [60, 50]]);
    await settled(page, 3);
    const f = await fit(page);
    // the material ball: a sphere under the studio light, a frame per material
    await page.waitForFunction(() => window.glint.state.judge.ball.frames > 0, null, { timeout: 60000 });
    const b1 = await page.evaluate(() => window.glint.state.judge.ball.last);
    t.log(`material ball: ${Math.round(b1.ms)} ms in the page, ${b1.renderer.split(';')[0]}; ${b1.env}`);
    assertEq(b1.query.object, 'ball', 'the ball is asked for');
    assertEq(b1.query.env, 'studio', 'lit by the studio by default');
    const s1 = await canvasStats(page, 'ball', 30);
    assertGE(s1.centre, 8, 'the ball is lit');
    // dragging turns the environment: a new frame, another image
    const box = await page.locator('#ball').boundingBox();
    await page.mouse.move(box.x + 20, box.y + box.height / 2);
    await page.mouse.down();
    await page.mouse.move(box.x + 90, box.y + box.height / 2, { steps: 5 });
    await page.mouse.up();
    await page.waitForFunction(() => {
      const b = window.glint.state.judge.ball, l = b.last;
      return l && !b.inflight && l.query.env_rotation !== '0' && l.query.env_rotation === document.getElementById('ball-rot').value;
    }, null, { timeout: 60000 });
    const b2 = await page.evaluate(() => window.glint.state.judge.ball.last);
    const s2 = await canvasStats(page, 'ball', 30);
    let moved = 0;
    for (let i = 0; i < s1.all.length; i += 4) if (Math.abs(s1.all[i] - s2.all[i]) > 6) moved++;
    t.log(`turned to ${b2.query.env_rotation}°: ${moved} pixels changed`);
    assertGE(moved, 200, 'the turned light moves over the ball');
    // the large comparison in view 3: split
    await page.selectOption('#compare-mode', 'split');
    await page.waitForFunction(() => { const l = window.glint.state.compare.last; return l && l.mode === 'split' && l.k === 3; }, null, { timeout: 60000 });
    const split = await page.evaluate(() => {
      const c = document.getElementById('overlay-fit'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let left = 0, right = 0;
      for (let y = 0; y < c.height; y++) for (let x = 0; x < c.width; x++) {
        const a = d[4 * (y * c.width + x) + 3];
        if (x < c.width / 2 - 1 && a) left++;
        if (x > c.width / 2 + 1 && a) right++;
      }
      return { left, right, shown: !c.classList.contains('hidden'), w: c.width };
    });
    assert(split.shown && split.left === 0 && split.right > 0, 'split: the painting left of the line, the fit right of it: ' + JSON.stringify(split));
    await t.shot(page, '40-compare-split-1440x900.png');
    // the signed difference, its scale against an independent computation
    await page.selectOption('#compare-mode', 'diff');
    await page.waitForFunction(() => { const l = window.glint.state.compare.last; return l && l.mode === 'diff' && l.k === 3; }, null, { timeout: 60000 });
    const mine = await page.evaluate(() => window.glint.state.compare.last);
    const ref = await page.evaluate(async ([mid, sid, tok, n]) => {
      const { decodeImage } = await import('/image.js');
      const h = { 'X-Glint-Token': tok };
      const get = async u => decodeImage(await (await fetch(u, { headers: h })).arrayBuffer());
      const p = await get(`/api/v1/sessions/${sid}/views/3/painting?format=exr`);
      const f = await get(`/api/v1/materials/${mid}/preview.exr?view=3&renderer=cpu&size=${n}`);
      const b = await get(`/api/v1/scenes/${window.glint.state.session.scene.id}/views/3/base.png?format=exr`);
      const Y = (im, i) => 0.2126 * im.data[3 * i] + 0.7152 * im.data[3 * i + 1] + 0.0722 * im.data[3 * i + 2];
      const ds = [];
      for (let i = 0; i < n * n; i++) if (Y(b, i) > 0 || Y(f, i) > 0) ds.push(Y(f, i) - Y(p, i));
      const mags = ds.map(Math.abs).sort((a, b) => a - b);
      let p2 = 0;
      for (let i = 0; i < n * n; i++) if (Y(b, i) > 0 || Y(f, i) > 0) p2 += Y(p, i) ** 2;
      return { pixels: ds.length, p99: mags[Math.floor(0.99 * mags.length)], rms: Math.sqrt(ds.reduce((a, d) => a + d * d, 0) / ds.length),
               level: Math.sqrt(p2 / ds.length) };
    }, [f.id, session.id, session.paint_token, 96]);
    t.log(`difference: full colour ±${mine.scale.toPrecision(3)}, RMS ${mine.rms.toPrecision(3)} over ${mine.pixels} px (independently: ±${ref.p99.toPrecision(3)}, ${ref.rms.toPrecision(3)}, ${ref.pixels} px)`);
    assertEq(mine.pixels, ref.pixels, 'the object pixels compared');
    assertLE(Math.abs(mine.scale - ref.p99), 1e-5 + 1e-4 * ref.p99, 'the difference\'s scale is its 99th percentile');
    assertLE(Math.abs(mine.rms - ref.rms), 1e-5 + 1e-4 * ref.rms, 'the difference\'s RMS');
    const legend = await page.textContent('#compare-legend');
    // the scale as a percentage of the painting's brightness (its luminance's RMS over the same pixels)
    const scalePct = 100 * ref.p99 / ref.level, shownPct = parseFloat(legend.slice(legend.indexOf('±') + 1));
    t.log(`legend "${legend}": ±${scalePct.toFixed(3)}% independently`);
    assert(legend.includes('brighter') && /±[\d.]+%/.test(legend), 'the legend prints the scale as a percentage: ' + legend);
    assertLE(Math.abs(shownPct - scalePct), Math.max(0.006, 0.051 * scalePct), 'the legend\'s percentage');
    const clipped = await page.evaluate(() => { const L = document.getElementById('compare-legend'); return L.scrollWidth - L.clientWidth; });
    assertLE(clipped, 0, 'the legend shows whole (px cut off)');
    const title = await page.getAttribute('#compare-legend', 'title');
    assert(/differs from your painting by about/.test(title), 'the legend\'s title says what the figure means: ' + title);
    assert(title.includes('RMS ' + mine.rms.toPrecision(3)), 'the legend\'s title gives the RMS under advanced');
    const sat = await page.evaluate(() => {
      const c = document.getElementById('overlay-fit'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let full = 0, any = 0;
      for (let i = 0; i < d.length; i += 4) { if (d[i] >= 250 || d[i + 2] >= 250) full++; if (Math.abs(d[i] - d[i + 2]) > 30) any++; }
      return { full, any, n: d.length / 4 };
    });
    t.log(`difference image: ${sat.any} pixels coloured, ${sat.full} at full colour`);
    assertGE(sat.any, 30, 'the difference shows where the fit misses');
    assertLE(sat.full, Math.ceil(0.02 * mine.pixels) + 1, 'at most the top 1-2% of the object saturates');
    // both widths: the toolbar and the status bar keep one row, Fit above the fold
    for (const [w, h] of [[1440, 900], [1280, 720]]) {
      await page.setViewportSize({ width: w, height: h });
      await page.waitForTimeout(100);
      const rows = await page.evaluate(() => ['toolbar', 'statusbar'].map(id => {
        const tops = new Set();
        for (const el of document.getElementById(id).children) {
          const r = el.getBoundingClientRect();
          if (r.width > 0 && r.height > 0) tops.add(Math.round(r.top + r.height / 2));
        }
        return Math.max(...tops) - Math.min(...tops);
      }));
      assertLE(Math.max(...rows), 4, `${w}x${h}: toolbar and status bar in one row`);
      const fitBox = await page.locator('#fit-btn').boundingBox();
      assert(fitBox.y + fitBox.height <= h, `${w}x${h}: the Fit button is above the fold`);
      // nothing in the status bar (compare, its legend, exposure, zoom) is cut off
      const cut = await page.evaluate(() => {
        const bar = document.getElementById('statusbar').getBoundingClientRect();
        return [...document.getElementById('statusbar').children].filter(el => {
          const r = el.getBoundingClientRect();
          return r.width > 0 && el.id !== 'st-px' && r.right > bar.right - 4;
        }).map(el => el.id || el.className);
      });
      assertEq(cut.join(','), '', `${w}x${h}: status bar items cut off`);
      const legendCut = await page.evaluate(() => { const L = document.getElementById('compare-legend'); return [L.scrollWidth - L.clientWidth, L.textContent, document.getElementById('st-view').scrollWidth - document.getElementById('st-view').clientWidth]; });
      assertLE(legendCut[0], 0, `${w}x${h}: the compare legend "${legendCut[1]}" shows whole (px cut off)`);
      assertLE(legendCut[2], 0, `${w}x${h}: the view's label shows whole (px cut off)`);
      // the material ball, its controls (light, turn) and the tabs below it above the fold too
      for (const sel of ['#ball', '#ball-row select', '#ball-row input[type=range]', '.tabs button >> nth=-1']) {
        const box = await page.locator(sel).first().boundingBox();
        assert(box && box.y + box.height <= h, `${w}x${h}: ${sel} is above the fold`);
      }
      await t.shot(page, `41-judge-${w}x${h}.png`);
    }
    // the guide: dismissed for good, back from the help
    await page.click('#guide-ok');
    assert(!(await page.isVisible('#guide')), 'Got it hides the guide');
    await page.reload();
    await page.waitForSelector('body[data-ready="1"]', { timeout: 60000 });
    assert(!(await page.isVisible('#guide')), 'not shown again in this browser');
    await page.click('#help-btn');
    await page.click('#guide-show');
    assert(await page.isVisible('#guide'), 'the help brings the guide back');
  },

  async 'a measured material the server offers is a finish to start from'(t) {
    if (!haveCli) { t.log('no glint command line at ' + CLI + ': skipped'); return; }
    const { url, session } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const page = await t.page();
    await openStudio(page, url);
    await page.waitForFunction(() => [...document.getElementById('preset-sel').options].some(o => o.value === 'measured: red-ct'));
    await page.selectOption('#preset-sel', 'measured: red-ct');
    assert(/Measured/.test(await page.textContent('#preset-note')), 'the measured finish is described');
    assert(await page.isDisabled('#preset-colour'), 'its colour is what was measured');
    await paintAllViews(page);
    await settled(page, 0);
    const d = await page.evaluate(async ([sid, tok]) => {
      const { decodeImage } = await import('/image.js');
      const S = window.glint.state.session;
      const get = async u => decodeImage(await (await fetch(u, { headers: { 'X-Glint-Token': tok } })).arrayBuffer());
      const p = await get(`/api/v1/sessions/${sid}/views/0/painting?format=exr`);
      const b = await get(`/api/v1/scenes/${S.scene.id}/views/0/base.png?format=exr&brdf=merl:red-ct.binary`);
      let mx = 0, lit = 0, red = 0, blue = 0;
      for (let i = 0; i < p.data.length; i++) { mx = Math.max(mx, Math.abs(p.data[i] - b.data[i])); if (b.data[i] > 0) lit++; }
      for (let i = 0; i < p.data.length; i += 3) { red += p.data[i]; blue += p.data[i + 2]; }
      return { mx, lit, red, blue };
    }, [session.id, session.paint_token]);
    t.log(`view 0 painted from the measured table: ${d.lit} lit values, largest difference from the server's render ${d.mx.toExponential(2)}; summed red ${d.red.toFixed(1)}, blue ${d.blue.toFixed(1)}`);
    assertGE(d.lit, 1000, 'the measured finish lights the sphere');
    assertLE(d.mx, 1e-6, 'the painting is the server\'s render of the measured table');
    assertGE(d.red, 2 * d.blue, 'its colour is the measured red');
    await t.shot(page, '43-measured-finish.png');
  },

  async 'a new torus opens on a view that shows it, not edge-on'(t) {
    const page = await t.page();
    await page.goto(t.daemon.base + '/');
    await page.waitForSelector('#start:not(.hidden)');
    await page.click('#shape-seg button[data-mesh="torus"]');
    await page.selectOption('#size-sel', '128');
    await page.click('#create-btn');
    await page.waitForSelector('body[data-ready="1"]', { timeout: 60000 });
    const r = await page.evaluate(() => {
      const S = window.glint.state.session, k = window.glint.state.k;
      return { k, n: S.scene.views.map(v => v.samples), eye: S.scene.views[k].eye };
    });
    const best = Math.max(...r.n);
    t.log(`opened on view ${r.k} (${r.n[r.k]} samples; view 0 has ${r.n[0]}, the most ${best}; eye z ${r.eye[2].toFixed(2)})`);
    assertGE(r.eye[2], 0, 'seen from above or level');
    assertGE(r.n[r.k], 0.9 * r.n[0], 'at least as much of the torus as view 0 shows');
    assertGE(r.n[r.k], 1.1 * r.n[0], 'the edge-on view 0 is not the one opened');
    await t.shot(page, '42-torus-first-view.png');
  },
}, { daemonArgs: ['--measured-dir', MDIR] });
