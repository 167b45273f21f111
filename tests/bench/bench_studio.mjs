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
//     chosen material shown, cold and repeated (its levels cached);
//   - under an environment, on a new scene as the studio makes it (sphere,
//     160 px raster painted at 480, lit by the built-in sky): "Paint all
//     views" with a gold metal finish, click to every view painted, and the
//     first fit (the first environment method, pbr_env), click to the
//     preview shown;
//   - with two artists in one session and a reference render running all
//     the while (the studio's own reference queue, a big CPU render under
//     an environment, one after another): strokes between them (p50, p95),
//     fits (click to preview, and how long the fit's request waited in the
//     browser before it was sent and in glintd: Resource Timing and
//     Server-Timing), and "choose for me" on the plastic finish.
//
// usage: node tests/bench/bench_studio.mjs [--loads N] [--strokes N] [--fits N]
//   [--choices N] [--envs N] [--busy-strokes N] (defaults 5, 30, 3, 2, 2, 30; GLINTD, GLINT_SOURCE_DIR as for the browser tests),
//   or `meson test -C build --benchmark --verbose studio`.
// Exits 77 (skipped) without Chromium or playwright-core, as the tests do.
import { run, Daemon, openStudio, drawStroke, settled, assert, waitFor } from '../browser/harness.mjs';

const argv = process.argv.slice(2);
const opt = (name, dflt) => { const i = argv.indexOf('--' + name); return i >= 0 ? +argv[i + 1] : dflt; };
const LOADS = opt('loads', 5), STROKES = opt('strokes', 30), FITS = opt('fits', 3);
const CHOICES = opt('choices', 2), ENVS = opt('envs', 2), BUSY_STROKES = opt('busy-strokes', 30);

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

// The studio's scene as "Create scene and session" makes it by default: a
// 160 px raster painted at 480 (paint_scale 3), 12 views.
const STUDIO_SCENE = { mesh: 'sphere', width: 160, height: 160, paint_scale: 3 };

async function metric(d, name, labels) {
  const txt = await (await fetch(d.base + '/metrics')).text();
  const line = txt.split('\n').find(l => l.startsWith(name + (labels || '') + ' '));
  return line ? +line.split(' ').pop() : NaN;
}

// "Paint all views" with finish id in colour (#rrggbb): the click to every
// view painted (its upload stored).  Clicked once the studio has every
// view's base render (as an artist who has looked at the views and picked
// a finish): not measured against the studio's own first loads.
async function paintAllViews(page, finish, colour) {
  await page.waitForFunction(() => window.glint.state.session.views.every(v => v.state === 'ready'), null, { timeout: 600000 });
  await page.selectOption('#preset-sel', finish);
  if (colour) await page.evaluate(c => { const el = document.getElementById('preset-colour'); el.value = c; el.dispatchEvent(new Event('input')); }, colour);
  const t0 = Date.now();
  await page.click('#preset-apply');
  await page.waitForFunction(() => !document.getElementById('preset-apply').disabled, null, { timeout: 600000 });
  await page.waitForFunction(() => { const S = window.glint.state.session; return S.views.every(v => v.state === 'ready' && v.pending.length === 0) && S.puts.size === 0; }, null, { timeout: 600000 });
  return Date.now() - t0;
}

// The Resource Timing of the page's last request to /fits: how long it
// waited in the browser before it was sent (for a free connection) and
// from sent to the first byte of the answer (glintd), and glintd's own
// Server-Timing steps.
function lastFitTiming(page) {
  return page.evaluate(() => {
    const e = performance.getEntriesByType('resource').filter(x => /\/fits(\?|$)/.test(x.name)).pop();
    return e && { stalled: e.requestStart - e.startTime, server: e.responseStart - e.requestStart,
                  steps: e.serverTiming.map(s => `${s.name} ${s.duration.toFixed(0)}`).join(', ') };
  });
}

// n strokes between pages a and b, alternating who paints (stroke i along
// line(i)): each one's lag from mouse up in one to applied in the other.
// after(): called once each stroke has arrived.
async function strokeLags(a, b, n, line, after) {
  await instrument(a);
  await instrument(b);
  const lag = [];
  for (let i = 0; i < n; i++) {
    const [from, to] = i % 2 ? [b, a] : [a, b];
    const s0 = await to.evaluate(() => window.glint.state.session.appliedSeq);
    await drawStroke(from, line(i), 4);
    await to.waitForFunction(s => window.__appliedAt[s + 1] !== undefined, s0);
    const up = await from.evaluate(() => window.__upAt), at = await to.evaluate(s => window.__appliedAt[s + 1], s0);
    lag.push(at - up);
    if (after) await after();
    await settled(from, 0);
  }
  return lag;
}

async function clickFitUntilPreview(page) {
  const before = await page.evaluate(() => [window.glint.lastFit && window.glint.lastFit.id, window.glint.state.judge.frames]);
  await page.waitForFunction(() => !document.getElementById('fit-btn').disabled);
  const t0 = Date.now();
  await page.click('#fit-btn');
  await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b[0] &&
    window.glint.state.judge.mat && window.glint.state.judge.mat.id === window.glint.lastFit.id &&
    window.glint.state.judge.frames > b[1], before, { polling: 'raf', timeout: 600000 });
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
    const lag = await strokeLags(ana, bo, STROKES, i => { const y = 10 + (i * 97) % 108; return [[15, y], [110, 128 - y]]; });
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
      await paintAllViews(page, 'plastic');
      for (const out of [null, again]) {
        const c = await chooseForMe(page);
        if (out) { out.push(c.ms); continue; }
        chosen.push(c.ms);
        if (c.first) first.push(c.first);
        picks.push(c.pick);
      }
      await page.context().close();
    }
    say(`choose for me on the plastic finish (96-104 px sphere, 12 views): first look shown ${first.length ? fmt(first) : 'never (the choice came first)'}`);
    say(`choose for me on the plastic finish: the choice shown, cold ${fmt(chosen)} (chose ${picks.join(', ')})`);
    say(`choose for me on the plastic finish: the choice shown, repeated ${fmt(again)}`);
  },

  async 'under an environment: a finish on every view, the first fit'(t) {
    const painted = [], fitted = [], methods = [];
    for (let i = 0; i < ENVS; i++) {
      // a scene of its own each time: nothing of the environment's prepared by an earlier one but the environment itself
      const { url } = await t.daemon.newSession(Object.assign({}, STUDIO_SCENE, { base: { env: { spec: 'sky' } } }));
      const page = await t.page();
      await openStudio(page, url);
      await page.waitForSelector('#quality .q[data-preset]');
      painted.push(await paintAllViews(page, 'metal', '#d4a017'));
      const c = await clickFitUntilPreview(page);
      fitted.push(c.ms);
      methods.push(c.fit.method || await page.evaluate(() => window.glint.state.judge.mat.method));
      await page.context().close();
    }
    say(`under the sky, 160 px sphere painted at 480: "Paint all views" (gold metal, 12 views), click to every view painted: ${fmt(painted)}`);
    say(`under the sky: the first fit on the new scene (${[...new Set(methods)].join(', ')}), click to the preview shown: ${fmt(fitted)}`);
  },

  async 'two artists while a reference render runs'(t) {
    // a daemon of its own: no other case's background work; renders not cut off by a time limit
    const d = await new Daemon(['--work-max-seconds', '0', '--quiet']).start();
    try {
      await busyStudio(t, d);
    } finally {
      await d.stop();
    }
  },
});

// "Choose for me" (the method that chooses among the lamp-lit models) on
// what page shows: the click to the chosen material shown, and to the first
// look (when one came first), and what it chose.
async function chooseForMe(page) {
  const chooser = await page.evaluate(() => {
    const m = window.glint.state.fit.methods.find(x => x.chooses && x.lighting === 'point');
    return m && m.name;
  });
  assert(chooser, 'a method that chooses among the lamp-lit models is offered');
  await page.selectOption('#fit-method', chooser);
  await page.evaluate(() => { window.glint.firstLook = null; });
  const c = await clickFitUntilPreview(page);
  const fl = await page.evaluate(() => window.glint.firstLook);
  return { ms: c.ms, first: fl && fl.ms, pick: await page.evaluate(() => (window.glint.state.judge.mat.choice || {}).chosen) };
}

// Two artists in one session on d, the studio's default scene; one's
// studio keeps a big reference render running (its reference queue, one
// at a time) while both paint, one fits and then chooses.
async function busyStudio(t, d) {
  t.allowConsole(/status of 503/);
  const { url } = await d.newSession(STUDIO_SCENE);
  const ana = await t.page(), bo = await t.page();
  await openStudio(ana, url);
  await openStudio(bo, url);
  for (const p of [ana, bo]) await p.waitForFunction(() => window.glint.state.session.presence.length === 2);
  await drawStroke(ana, [[100, 100], [300, 200]]);
  await settled(ana, 0);
  const { fit } = await clickFitUntilPreview(ana);
  await waitFor(async () => (await metric(d, 'glintd_work_running_by_class', '{class="background"}')) === 0, 600000, 'background work of the fit ends');
  await ana.evaluate(async mid => {
    const { CLASS } = await import('/requests.js');
    const api = window.glint.api;
    window.__refs = 0;
    window.__refLoop = (async () => {
      for (let k = 0; !window.__refStop; k++) {
        await api.images.run('reference:bench' + k,
          (s, h) => api.materialFile(mid, 'preview.exr', { view: String(k % 12), size: '2048', renderer: 'cpu', env: 'sky', lights: '256' }, s, h),
          { cls: CLASS.reference }).then(() => { window.__refs++; }, () => {});
      }
    })();
  }, fit.id);
  await waitFor(async () => (await metric(d, 'glintd_work_running_by_class', '{class="background"}')) === 1, 60000, 'a reference render running');
  // (the second artist's studio asks for its own reference renders after its fits: at times two run)
  const busy = async () => (await metric(d, 'glintd_work_running_by_class', '{class="background"}')) >= 1;
  let whileBusy = 0, measured = 0;
  const note = async () => { measured++; if (await busy()) whileBusy++; };
  const lag = await strokeLags(ana, bo, BUSY_STROKES, i => { const y = 40 + (i * 131) % 400; return [[60, y], [420, 480 - y]]; }, note);
  // fits by the other artist (cached: the scene's precomputation is built)
  const fits = [], stalled = [], server = [];
  let steps = '';
  for (let i = 0; i < FITS; i++) {
    await drawStroke(bo, [[150 + 20 * i, 150], [250, 260]]);
    await settled(bo, 0);
    const c = await clickFitUntilPreview(bo);
    await note();
    fits.push(c.ms);
    const rt = await lastFitTiming(bo);
    stalled.push(rt.stalled);
    server.push(rt.server);
    steps = rt.steps;
  }
  // a finish on every view and "choose for me", still beside the render
  const paint = await paintAllViews(bo, 'plastic');
  await note();
  const ch = await chooseForMe(bo);
  await note();
  // the choice's own account: each candidate's fit seconds, the refit
  const chSteps = await bo.evaluate(() => {
    const c = window.glint.state.judge.mat.choice || {};
    return (c.candidates || []).map(x => `${x.method} ${(+x.fit_seconds).toFixed(2)} s`).join(', ') +
      (c.refit_seconds != null ? `, refit ${(+c.refit_seconds).toFixed(2)} s` : '');
  });
  const done = await ana.evaluate(() => { window.__refStop = true; window.glint.api.images.abortPrefix('reference:'); return window.__refs; });
  await ana.evaluate(() => window.__refLoop);
  // closed before their daemon stops: nothing of theirs asks it again
  for (const p of [ana, bo]) await p.context().close();
  const ms = x => `${x.toFixed(0)} ms`;
  say(`with a reference render running (${done} finished meanwhile; reference work running at ${whileBusy} of ${measured} measurements): 160 px sphere painted at 480, two artists`);
  say(`  stroke, mouse up in one browser to applied in the other: p50 ${pct(lag, 50)} ms, p95 ${pct(lag, 95)} ms (min ${Math.min(...lag)}, max ${Math.max(...lag)}, n=${lag.length})`);
  say(`  fit, click to the preview shown (cached): ${fmt(fits)}`);
  say(`  the fit request, waiting in the browser before it was sent: max ${ms(Math.max(...stalled))}; sent to the answer's first byte: ${fmt(server)} (glintd's steps, the last: ${steps})`);
  say(`  "Paint all views" (satin plastic): ${ms(paint)}; choose for me: first look ${ch.first ? ms(ch.first) : 'never (the choice came first)'}, the choice (${ch.pick}) shown ${ms(ch.ms)} (its candidates: ${chSteps})`);
}
