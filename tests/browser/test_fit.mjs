// Fitting and judging in the studio: a cold fit with job progress, a cached
// refit answered at once (no job), the preview changing where the painting changed,
// the preview following the mouse, the error per view with its difference
// image, the factor curves, the quality control's measured figures, and
// the package download.
import fs from 'node:fs';
import path from 'node:path';
import {
  run, openStudio, drawStroke, settled, assert, assertLE, assertGE, assertEq, waitFor, pageArray, ARTIFACTS,
} from './harness.mjs';

async function setRange(page, id, v) {
  await page.evaluate(([id, v]) => { const el = document.getElementById(id); el.value = v; el.dispatchEvent(new Event('input', { bubbles: true })); }, [id, String(v)]);
}

// Click Fit and wait for the material it makes; returns {id, ms, cached}.
async function fit(page) {
  const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
  await page.waitForSelector('#quality .q[data-preset]');      // the methods are loaded
  await page.click('#fit-btn');
  await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: 60000 });
  return page.evaluate(() => window.glint.lastFit);
}

// Mean of the preview's RGB over a box of image pixels of the painting
// (the preview of a view's camera is the same picture at 256 pixels).
async function previewMean(page, box, raster) {
  return page.evaluate(([b, raster]) => {
    const s = 256 / raster;
    const d = document.getElementById('preview').getContext('2d').getImageData(Math.round(b[0] * s), Math.round(b[1] * s), Math.round((b[2] - b[0]) * s), Math.round((b[3] - b[1]) * s)).data;
    let m = 0;
    for (let i = 0; i < d.length; i += 4) m += (d[i] + d[i + 1] + d[i + 2]) / 3;
    return m / (d.length / 4);
  }, [box, raster]);
}

async function framesShown(page) { return page.evaluate(() => window.glint.state.judge.frames); }

run({
  async 'fit: progress while precomputing, cached refit at once, the preview changes where painted'(t) {
    // (how long a fit takes from the click to the preview: tests/bench/bench_studio.mjs)
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 128, height: 128 });
    const page = await t.page();
    await openStudio(page, url);
    await page.waitForSelector('#quality .q');
    // a first, neutral painting: an erase stroke leaves the base render but marks the view painted
    await page.keyboard.press('e');
    await drawStroke(page, [[10, 10], [20, 10]]);
    await settled(page, 0);
    await page.keyboard.press('b');
    // record what the progress bar shows during the cold fit
    await page.evaluate(() => {
      window.__progress = [];
      new MutationObserver(() => {
        const el = document.getElementById('fit-progress');
        if (!el.classList.contains('hidden')) window.__progress.push(el.querySelector('span').textContent);
      }).observe(document.getElementById('fit-progress'), { attributes: true, subtree: true, childList: true, characterData: true });
    });
    const f1 = await fit(page);
    const stages = await page.evaluate(() => window.__progress);
    t.log(`cold fit: ${f1.ms.toFixed(0)} ms, progress shown: ${[...new Set(stages)].slice(0, 6).join(' | ')}`);
    assertEq(f1.cached, false, 'the first fit builds its precomputation (a job)');
    assert(stages.some(s => /%/.test(s)), 'progress was shown');
    await page.waitForFunction(id => window.glint.state.judge.mat && window.glint.state.judge.mat.id === id && window.glint.state.judge.frames > 0, f1.id);
    const region = [58, 30, 86, 52];                  // where the highlight goes (image pixels)
    const m1 = await previewMean(page, region, 128);
    // paint a bright highlight there and fit again: same views, same parameters: cached
    await setRange(page, 'diameter', 26); await setRange(page, 'kappa', 0.02);
    await drawStroke(page, [[62, 41], [82, 41]]);
    await settled(page, 0);
    const n0 = await framesShown(page);
    const jobRequests = [];
    page.on('request', r => { if (/\/api\/v1\/jobs\//.test(r.url())) jobRequests.push(r.url()); });
    const f2 = await fit(page);
    assertEq(f2.cached, true, 'the refit finds its precomputation cached');
    assertEq(jobRequests.length, 0, 'requests about a job for the cached refit (answered in the request)');
    await page.waitForFunction(n => window.glint.state.judge.frames > n, n0);
    const m2 = await previewMean(page, region, 128);
    const mOut = [await previewMean(page, [100, 90, 120, 110], 128)];
    t.log(`preview mean in the painted region: ${m1.toFixed(1)} -> ${m2.toFixed(1)} (of 255)`);
    assertGE(m2 - m1, 25, 'the preview brightened in the painted region');
    void mOut;
    await t.shot(page, '10-fit-preview.png');
  },

  async 'the preview follows the mouse: drag moves the light, shift-drag the camera'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'teapot', width: 128, height: 128 });
    const page = await t.page();
    await openStudio(page, url);
    await drawStroke(page, [[40, 50], [90, 60]]);
    await settled(page, 0);
    await fit(page);
    await page.waitForFunction(() => window.glint.state.judge.frames > 0);
    const img = () => pageArray(page, () => document.getElementById('preview').getContext('2d').getImageData(0, 0, 256, 256).data);
    const a = await img();
    const g = await page.locator('#preview-gizmo').boundingBox();
    const light0 = await page.evaluate(() => window.glint.state.judge.cam.light.slice());
    const f0 = await framesShown(page);
    await page.mouse.move(g.x + 128, g.y + 128);
    await page.mouse.down();
    for (let i = 1; i <= 12; i++) await page.mouse.move(g.x + 128 + 8 * i, g.y + 128 - 3 * i);
    await page.mouse.up();
    await page.waitForFunction(() => { const j = window.glint.state.judge; return !j.inflight && j.shown === j.want; }, null, { timeout: 60000 });
    const light1 = await page.evaluate(() => window.glint.state.judge.cam.light.slice());
    const f1 = await framesShown(page);
    const b = await img();
    let diff = 0; for (let i = 0; i < a.length; i++) diff += Math.abs(a[i] - b[i]);
    t.log(`light drag: ${f1 - f0} frames for 12 moves (one request in flight, the newest wins), mean |change| ${(diff / a.length).toFixed(2)}`);
    assert(light1.some((x, i) => Math.abs(x - light0[i]) > 0.3), 'the light moved');
    assertGE(f1 - f0, 1, 'frames shown while dragging');
    assertLE(f1 - f0, 12, 'no more frames than moves');
    assertGE(diff / a.length, 0.5, 'the picture changed');
    const eye0 = await page.evaluate(() => window.glint.state.judge.cam.eye.slice());
    await page.keyboard.down('Shift');
    await page.mouse.move(g.x + 100, g.y + 100);
    await page.mouse.down();
    await page.mouse.move(g.x + 160, g.y + 120, { steps: 5 });
    await page.mouse.up();
    await page.keyboard.up('Shift');
    const eye1 = await page.evaluate(() => window.glint.state.judge.cam.eye.slice());
    assert(eye1.some((x, i) => Math.abs(x - eye0[i]) > 0.3), 'the camera orbited');
    await page.waitForFunction(() => { const j = window.glint.state.judge; return !j.inflight && j.shown === j.want; });
    await t.shot(page, '11-preview-orbit.png');
  },

  async 'error per view: numbers, difference image, factor curves, quality figures, package download'(t) {
    const { url, session } = await t.daemon.newSession({ mesh: 'sphere', width: 128, height: 128 });
    const page = await t.page();
    await openStudio(page, url);
    // paint two views
    await setRange(page, 'diameter', 30); await setRange(page, 'kappa', 0.05);
    await drawStroke(page, [[50, 40], [80, 45]]);
    await settled(page, 0);
    await page.keyboard.press('3');
    await page.waitForFunction(() => window.glint.state.k === 2 && window.glint.state.session.views[2].state === 'ready');
    await drawStroke(page, [[40, 70], [70, 60]]);
    await settled(page, 2);
    // the three-factor model, whose factor curves are checked below (the
    // automatic choice may take a model without factors)
    await page.selectOption('#fit-method', 'hf3');
    const f = await fit(page);
    await page.waitForFunction(() => window.glint.state.judge.rows && window.glint.state.judge.rows.size === 2, null, { timeout: 60000 });
    const rows = await page.evaluate(() => [...window.glint.state.judge.rows].map(([k, r]) => ({ k, rms: r.rms, n: r.n })));
    const mat = await t.daemon.api('GET', `/materials/${f.id}`, undefined, { 'X-Glint-Token': session.paint_token });
    // pooled over the views, the client's per-view errors give the server's RMS
    const pooled = Math.sqrt(rows.reduce((a, r) => a + r.rms * r.rms * r.n, 0) / rows.reduce((a, r) => a + r.n, 0));
    t.log(`per view: ${rows.map(r => `view ${r.k} RMS ${r.rms.toFixed(4)} over ${r.n} px`).join(', ')}; pooled ${pooled.toFixed(4)}, server rms_painted ${mat.errors.rms_painted.toFixed(4)}`);
    assertEq(rows.reduce((a, r) => a + r.n, 0), mat.precomputation.samples, 'pixels compared = the fit\'s samples');
    assertLE(Math.abs(pooled - mat.errors.rms_painted), 2e-3, 'client-side errors agree with the server');
    assertEq(await page.locator('#err-table tbody tr').count(), 2, 'error table rows');
    const diffLit = await page.evaluate(() => {
      const c = document.getElementById('diff-img'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let n = 0; for (let i = 0; i < d.length; i += 4) if (d[i] > 60) n++; return n;
    });
    assertGE(diffLit, 20, 'the difference image shows where the fit misses');
    await page.click('#err-table tbody tr[data-view="2"]');
    await page.waitForFunction(() => window.glint.state.k === 2 && window.glint.state.judge.errView === 2 && window.glint.state.judge.frames > 0);
    await t.shot(page, '12-errors.png');
    // factor curves
    await page.click('.tabs button[data-tab="factors"]');
    await page.waitForFunction(() => window.glint.state.judge.factors);
    // curves are drawn in R, G, B with additive blending (grey paint: one white curve)
    const ink = await page.evaluate(() => {
      const c = document.getElementById('factors'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let n = 0; for (let i = 0; i < d.length; i += 4) if (Math.max(d[i], d[i + 1], d[i + 2]) > 180) n++; return n;
    });
    t.log(`factor plot: ${ink} curve pixels`);
    assertGE(ink, 300, 'three factor curves drawn');
    const res = await page.evaluate(() => window.glint.state.judge.factors.w);
    assertEq(res, mat.res, 'factor texels');
    await t.shot(page, '13-factors.png');
    // the material in numbers: the server's summary, shown as words and a polar plot
    await page.click('.tabs button[data-tab="summary"]');
    await page.waitForFunction(() => window.glint.state.judge.summary, null, { timeout: 60000 });
    const sm = await t.daemon.api('GET', `/materials/${f.id}/summary`, undefined, { 'X-Glint-Token': session.paint_token });
    const words = await page.textContent('#tab-summary');
    t.log('in numbers: ' + words.replace(/\s+/g, ' ').trim());
    assert(words.includes(sm.base_colour[0].toFixed(3)), 'the base colour shown is the server\'s');
    assert(/highlight|matte|sheen/.test(words), 'the highlight is put in words');
    const polarInk = await page.evaluate(() => {
      const c = document.getElementById('sum-polar'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let n = 0; for (let i = 0; i < d.length; i += 4) if (d[i + 3] > 0 && Math.max(d[i], d[i + 1], d[i + 2]) > 90) n++; return n;
    });
    assertGE(polarInk, 200, 'the polar plot is drawn');
    await t.shot(page, '13b-in-numbers.png');
    // the quality control now shows measured figures for the default preset
    await page.waitForFunction(() => {
      const cells = [...document.querySelectorAll('#quality .q[data-preset="default"] .v')].map(c => c.textContent);
      return cells.length === 3 && /\d/.test(cells[0]) && /\d/.test(cells[1]) && /^[\d.]+%/.test(cells[2]);   // the error as a percentage
    });
    t.log('quality row: ' + (await page.locator('#quality .q[data-preset="default"]').innerText()).replace(/\s+/g, ' '));
    // export
    await page.click('.tabs button[data-tab="export"]');
    const [dl] = await Promise.all([page.waitForEvent('download'), page.click('#dl-package')]);
    const file = path.join(ARTIFACTS, 'material-package.tar');
    await dl.saveAs(file);
    const tar = fs.readFileSync(file);
    assertEq(tar.subarray(257, 262).toString(), 'ustar', 'a tar file');
    const names = [];
    for (let off = 0; off + 512 <= tar.length;) {
      const name = tar.subarray(off, off + 100).toString().replace(/\0.*$/s, '');
      if (!name) break;
      names.push(name);
      const size = parseInt(tar.subarray(off + 124, off + 136).toString().replace(/\0.*$/s, '').trim() || '0', 8);
      off += 512 + Math.ceil(size / 512) * 512;
    }
    t.log('package: ' + names.join(', '));
    assert(names.some(n => n.endsWith('material.json')), 'the package holds the manifest');
    assert(names.some(n => /factors\.(exr|png)$/.test(n)), 'the package holds the factors');
    await t.shot(page, '14-export.png');
  },
});
