// bench_studio.mjs: how long the studio (web/) takes, in headless Chromium
// against a real glintd, with the browser tests' harness
// (tests/browser/harness.mjs: `npm ci --prefix tests/browser` once).  The
// browser tests check that these things happen; this prints how soon:
//
//   - page load to the first paintable view (window.glint.paintableMs: from
//     the navigation's start), cold (a fresh browser context, nothing
//     cached) and warm (reloads: the studio's files revalidated, 304);
//   - a stroke from one browser to another: mouse up in one page to the
//     stroke applied in the other (both pages' Date.now(), one machine),
//     p50 and p99 over the strokes, alternating who paints;
//   - a fit: the click on Fit to the preview shown (a frame of the judge),
//     cold (the precomputation built by a job) and cached (answered in the
//     request);
//   - "choose for me" (the method that chooses among the lamp-lit models)
//     on a finish painted over every view: the click on Fit to the first
//     look shown (the quickest model, fitted beside the choice) and to the
//     chosen material shown, cold and repeated (its levels cached).
//
// usage: node tests/bench/bench_studio.mjs [--loads N] [--strokes N] [--fits N]
//   [--choices N] (defaults 5, 30, 3, 2; GLINTD, GLINT_SOURCE_DIR as for the browser tests),
//   or `meson test -C build --benchmark --verbose studio`.
// Exits 77 (skipped) without Chromium or playwright-core, as the tests do.
import { run, openStudio, drawStroke, settled, assert } from '../browser/harness.mjs';

const argv = process.argv.slice(2);
const opt = (name, dflt) => { const i = argv.indexOf('--' + name); return i >= 0 ? +argv[i + 1] : dflt; };
const LOADS = opt('loads', 5), STROKES = opt('strokes', 30), FITS = opt('fits', 3);
const CHOICES = opt('choices', 2);

// nearest-rank percentile of a list of numbers
function pct(xs, p) {
  const s = xs.slice().sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.max(0, Math.ceil(p / 100 * s.length) - 1))];
}
const fmt = xs => `median ${pct(xs, 50).toFixed(0)} ms (min ${Math.min(...xs).toFixed(0)}, max ${Math.max(...xs).toFixed(0)}, n=${xs.length})`;
const say = s => console.log('      ' + s);

// Record, in a page, when each session event was applied (Date.now() by
// seq) and when the mouse last went up.
async function instrument(page) {
  await page.evaluate(() => {
    window.__appliedAt = {};
    window.glint.state.session.addEventListener('event', e => { window.__appliedAt[e.detail.seq] = Date.now(); });
    document.addEventListener('pointerup', () => { window.__upAt = Date.now(); }, true);
  });
}

async function clickFitUntilPreview(page) {
  const before = await page.evaluate(() => [window.glint.lastFit && window.glint.lastFit.id, window.glint.state.judge.frames]);
  await page.waitForFunction(() => !document.getElementById('fit-btn').disabled);
  const t0 = Date.now();
  await page.click('#fit-btn');
  await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b[0] &&
    window.glint.state.judge.mat && window.glint.state.judge.mat.id === window.glint.lastFit.id &&
    window.glint.state.judge.frames > b[1], before, { polling: 'raf' });
  const ms = Date.now() - t0;
  return { ms, fit: await page.evaluate(() => window.glint.lastFit) };
}

run({
  async 'first paintable view, cold and warm'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'teapot', width: 256, height: 256 });
    const cold = [], warm = [];
    for (let i = 0; i < LOADS; i++) {
      const page = await t.page();            // a fresh context: nothing cached
      cold.push(await openStudio(page, url));
      if (i === 0) {
        for (let j = 0; j < LOADS; j++) {
          await page.reload();
          await page.waitForSelector('body[data-ready="1"]');
          warm.push(await page.evaluate(() => window.glint.paintableMs));
        }
      }
      await page.context().close();
    }
    say(`page load to the first paintable view (256x256 teapot): cold ${fmt(cold)}`);
    say(`page load to the first paintable view (256x256 teapot): warm ${fmt(warm)}`);
  },

  async 'stroke propagation between two browsers'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'torus', width: 128, height: 128 });
    const ana = await t.page(), bo = await t.page();
    await openStudio(ana, url);
    await openStudio(bo, url);
    for (const p of [ana, bo]) await p.waitForFunction(() => window.glint.state.session.presence.length === 2);
    await instrument(ana);
    await instrument(bo);
    const lag = [];
    for (let i = 0; i < STROKES; i++) {
      const [from, to] = i % 2 ? [bo, ana] : [ana, bo];
      const y = 10 + (i * 97) % 108;
      const s0 = await to.evaluate(() => window.glint.state.session.appliedSeq);
      await drawStroke(from, [[15, y], [110, 128 - y]], 4);
      await to.waitForFunction(s => window.__appliedAt[s + 1] !== undefined, s0);
      const up = await from.evaluate(() => window.__upAt), at = await to.evaluate(s => window.__appliedAt[s + 1], s0);
      lag.push(at - up);
      await settled(from, 0);
    }
    const st = await ana.evaluate(() => window.glint.state.session.stats);
    assert(st.duplicates + st.gaps === 0, 'no duplicates or gaps');
    say(`stroke, mouse up in one browser to applied in the other (128x128 torus): p50 ${pct(lag, 50)} ms, p99 ${pct(lag, 99)} ms (min ${Math.min(...lag)}, max ${Math.max(...lag)}, n=${lag.length})`);
  },

  async 'fit request to the preview shown'(t) {
    const cold = [], cached = [];
    for (let i = 0; i < FITS; i++) {
      // a scene of its own: the precomputation is built (a job)
      const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96 + 8 * i, height: 96 + 8 * i });
      const page = await t.page();
      await openStudio(page, url);
      await page.waitForSelector('#quality .q[data-preset]');
      await drawStroke(page, [[30, 30], [60, 40]]);
      await settled(page, 0);
      const c = await clickFitUntilPreview(page);
      assert(c.fit.cached === false, 'a fresh scene\'s fit is a job');
      cold.push(c.ms);
      // paint more and fit again: the same precomputation, cached
      await drawStroke(page, [[40, 60], [70, 55]]);
      await settled(page, 0);
      const w = await clickFitUntilPreview(page);
      assert(w.fit.cached === true, 'the refit is cached');
      cached.push(w.ms);
      await page.context().close();
    }
    say(`fit, click to the preview shown (96-112 px sphere, default quality): cold (job) ${fmt(cold)}`);
    say(`fit, click to the preview shown (96-112 px sphere, default quality): cached ${fmt(cached)}`);
  },

  async 'choose for me: the first look and the choice'(t) {
    const first = [], chosen = [], again = [], picks = [];
    for (let i = 0; i < CHOICES; i++) {
      const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96 + 8 * i, height: 96 + 8 * i });
      const page = await t.page();
      await openStudio(page, url);
      await page.waitForSelector('#quality .q[data-preset]');
      const chooser = await page.evaluate(() => {
        const m = window.glint.state.fit.methods.find(x => x.chooses && x.lighting === 'point');
        return m && m.name;
      });
      assert(chooser, 'a method that chooses among the lamp-lit models is offered');
      await page.selectOption('#fit-method', chooser);
      await page.selectOption('#preset-sel', 'plastic');
      await page.click('#preset-apply');
      await page.waitForFunction(() => !document.getElementById('preset-apply').disabled);
      await page.waitForFunction(() => { const S = window.glint.state.session; return S.views.every(v => v.state === 'ready' && v.pending.length === 0) && S.puts.size === 0; });
      for (const out of [null, again]) {
        await page.evaluate(() => { window.glint.firstLook = null; });
        const c = await clickFitUntilPreview(page);
        const fl = await page.evaluate(() => window.glint.firstLook);
        if (out) { out.push(c.ms); continue; }
        chosen.push(c.ms);
        if (fl) first.push(fl.ms);
        picks.push(await page.evaluate(() => (window.glint.state.judge.mat.choice || {}).chosen));
      }
      await page.context().close();
    }
    say(`choose for me on the plastic finish (96-104 px sphere, 12 views): first look shown ${first.length ? fmt(first) : 'never (the choice came first)'}`);
    say(`choose for me on the plastic finish: the choice shown, cold ${fmt(chosen)} (chose ${picks.join(', ')})`);
    say(`choose for me on the plastic finish: the choice shown, repeated ${fmt(again)}`);
  },
});
