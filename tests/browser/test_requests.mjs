// The studio's image requests under load: what is drawn is what was asked
// for last (a delayed answer for the material shown before is never drawn,
// whether the request was aborted or its answer arrives anyway), a render
// abandoned by its page frees its work slot in glintd (running or still
// waiting for one), and strokes reach the other artist while a reference
// render runs.  Assertions are on state (what is drawn, /metrics), never on
// how long anything took.
import {
  run, Daemon, openStudio, drawStroke, settled, canvasPixels, pageArray, maxDiff,
  assert, assertEq, assertGE, waitFor,
} from './harness.mjs';

async function fit(page) {
  const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
  await page.waitForSelector('#quality .q[data-preset]');
  await page.click('#fit-btn');
  await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: 60000 });
  return page.evaluate(() => window.glint.lastFit.id);
}

// Every view painted with a finish of the studio's, then fitted.
async function paintAndFit(page, finish, colour) {
  await page.selectOption('#preset-sel', finish);
  await page.evaluate(c => { const el = document.getElementById('preset-colour'); el.value = c; el.dispatchEvent(new Event('input')); }, colour);
  await page.click('#preset-apply');
  await page.waitForFunction(() => !document.getElementById('preset-apply').disabled);
  await page.waitForFunction(() => { const S = window.glint.state.session; return S.views.every(v => v.state === 'ready' && v.pending.length === 0) && S.puts.size === 0; });
  return fit(page);
}

// Show material id (the material list, as an artist picks it).
const pick = (page, id) => page.selectOption('#mat-sel', id);

// A canvas's pixels and the pixels of the PNG at url drawn the way the
// studio draws it (createImageBitmap, drawImage at the canvas's size).
async function drawnAndOwn(page, id, url) {
  const drawn = await canvasPixels(page, id);
  const own = await pageArray(page, async ([id, url]) => {
    const c = document.getElementById(id), S = window.glint.state.session;
    const r = await fetch(url, { headers: { 'X-Glint-Token': S.token } });
    const bmp = await createImageBitmap(await r.blob(), { colorSpaceConversion: 'none' });
    const o = new OffscreenCanvas(c.width, c.height), g = o.getContext('2d');
    g.drawImage(bmp, 0, 0, c.width, c.height);
    return g.getImageData(0, 0, c.width, c.height).data;
  }, [id, url]);
  return { drawn, own };
}

async function metric(d, name, labels) {
  const r = await fetch(d.base + '/metrics');
  const txt = await r.text();
  const line = txt.split('\n').find(l => l.startsWith(name + (labels || '') + ' '));
  return line ? +line.split(' ').pop() : NaN;
}

// The newest request URL the page made for material id's preview.png of a
// kind (object=ball or not).
function lastUrls(page) {
  const seen = [];
  page.on('request', r => { if (/\/preview\.png\?/.test(r.url())) seen.push(r.url()); });
  return (id, ball) => {
    const u = seen.filter(x => x.includes('/materials/' + id + '/') && x.includes('object=ball') === ball).pop();
    return u && u.replace(/^https?:\/\/[^/]+/, '');
  };
}

run({
  async 'a delayed answer for the material shown before is never drawn'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const page = await t.page();
    const urlOf = lastUrls(page);
    await openStudio(page, url);
    const m1 = await paintAndFit(page, 'matte', '#20c040');
    const m2 = await paintAndFit(page, 'metal', '#d0a020');
    assert(m1 !== m2, 'two materials');
    await page.waitForFunction(m => document.getElementById('preview').dataset.material === m && document.getElementById('ball').dataset.material === m, m2);
    // m1's own frames, to answer the held requests with
    await pick(page, m1);
    await page.waitForFunction(m => document.getElementById('preview').dataset.material === m && document.getElementById('ball').dataset.material === m, m1);
    await pick(page, m2);
    await page.waitForFunction(m => document.getElementById('preview').dataset.material === m && document.getElementById('ball').dataset.material === m, m2);
    const body1 = await pageArray(page, async u => new Uint8Array(await (await fetch(u, { headers: { 'X-Glint-Token': window.glint.state.session.token } })).arrayBuffer()), urlOf(m1, false));
    // every material the preview and the ball draw from now on
    await page.evaluate(() => {
      window.__drawn = [];
      const obs = new MutationObserver(ms => { for (const m of ms) window.__drawn.push(m.target.id + ':' + m.target.dataset.material); });
      for (const id of ['preview', 'ball']) obs.observe(document.getElementById(id), { attributes: true, attributeFilter: ['data-material'] });
    });
    for (const round of ['aborted', 'answered anyway']) {
      if (round === 'answered anyway') {
        // no abort: the answers for m1 arrive, and the check on arrival alone keeps them off the canvas
        await page.evaluate(() => { const q = window.glint.api.images; q.abort = () => {}; q.abortPrefix = () => {}; });
      }
      const held = [];
      await page.route(`**/api/v1/materials/${m1}/preview.png*`, route => { held.push(route); });
      await pick(page, m1);
      await waitFor(() => held.length >= 2, 60000, 'the preview and the ball of m1 asked for and held');
      await pick(page, m2);
      // m2 is the material shown (the list's change handler reads it first)
      await page.waitForFunction(m => window.glint.state.judge.mat.id === m && window.glint.state.judge.ball.mat.id === m, m2);
      if (round === 'aborted') {
        // m2 drawn while m1's answers are still held
        await page.waitForFunction(m => document.getElementById('preview').dataset.material === m && document.getElementById('ball').dataset.material === m, m2);
      }
      for (const r of held) await r.fulfill({ status: 200, contentType: 'image/png', body: Buffer.from(body1) }).catch(() => { /* aborted by the page */ });
      await page.unroute(`**/api/v1/materials/${m1}/preview.png*`);
      await page.waitForFunction(m => document.getElementById('preview').dataset.material === m && document.getElementById('ball').dataset.material === m, m2);
      // m1's answers have come and gone: every request the queue started has ended
      await page.waitForFunction(() => window.glint.api.images.counts().running === 0 && window.glint.api.images.counts().queued === 0);
      const drawn = await page.evaluate(() => window.__drawn.splice(0));
      assert(!drawn.some(x => x.endsWith(':' + m1)), `${round}: nothing of m1 drawn after m2 was chosen: ${drawn.join(' ')}`);
      for (const [id, ball] of [['preview', false], ['ball', true]]) {
        const { drawn: px, own } = await drawnAndOwn(page, id, urlOf(m2, ball));
        assertEq(maxDiff(px, own), 0, `${round}: the ${id} shows m2's own render`);
        const { own: other } = await drawnAndOwn(page, id, urlOf(m1, ball));
        assertGE(maxDiff(px, other), 20, `${round}: and not m1's`);
      }
      assertEq(await page.evaluate(() => window.glint.state.material.id), m2, 'the material shown');
    }
    const st = await page.evaluate(() => window.glint.api.images.stats);
    assertGE(st.superseded, 2, 'the first round aborted the preview and the ball of m1');
    t.log(`image requests: ${JSON.stringify(st)}`);
  },

  async 'an abandoned render frees its work slot, running or waiting'(t) {
    const d = await new Daemon(['--work-slots', '1', '--work-wait', '600', '--work-max-seconds', '0', '--quiet']).start();
    try {
      const { url } = await d.newSession({ mesh: 'sphere', width: 96, height: 96 });
      const page = await t.page();
      await openStudio(page, url);
      await drawStroke(page, [[20, 30], [70, 50]]);
      await settled(page, 0);
      const mid = await fit(page);
      await page.waitForFunction(() => window.glint.api.images.counts().running === 0 && window.glint.state.judge.frames > 0);
      const running = () => metric(d, 'glintd_work_running');
      await waitFor(async () => (await running()) === 0, 60000, 'nothing running');
      const big = `/api/v1/materials/${mid}/preview.exr?view=0&size=4096&renderer=cpu&env=studio&lights=256`;
      const cancelled0 = await metric(d, 'glintd_work_total', '{outcome="cancelled"}');
      // 1. a render running for the page, aborted by it (AbortController)
      await page.evaluate(u => {
        window.__big = new AbortController();
        window.__bigDone = fetch(u, { headers: { 'X-Glint-Token': window.glint.state.session.token }, signal: window.__big.signal })
          .then(r => 'status ' + r.status, e => e.name);
      }, big);
      await waitFor(async () => (await running()) === 1, 60000, 'the big render running');
      // a request from someone else waits for the only slot
      const sess = await page.evaluate(() => [window.glint.state.session.id, window.glint.state.session.token]);
      const small = fetch(`${d.base}/api/v1/materials/${mid}/preview.png?view=0&size=64`, { headers: { 'X-Glint-Token': sess[1] } });
      await waitFor(async () => (await metric(d, 'glintd_work_waiting_by_class', '{class="interactive"}')) === 1, 60000, 'the small preview waiting');
      await page.evaluate(() => window.__big.abort());
      assertEq(await page.evaluate(() => window.__bigDone), 'AbortError', 'the page aborted its render');
      assertEq((await small).status, 200, 'the waiting preview was admitted once the render was abandoned');
      await waitFor(async () => (await metric(d, 'glintd_work_total', '{outcome="cancelled"}')) === cancelled0 + 1, 60000, 'the abandoned render counted as cancelled');
      await waitFor(async () => (await running()) === 0, 60000, 'the slot free');
      // 2. a request waiting for the slot, its tab closed: it never takes the slot
      const ctrl = new AbortController();
      const held = fetch(d.base + big, { headers: { 'X-Glint-Token': sess[1] }, signal: ctrl.signal }).catch(e => e.name);
      await waitFor(async () => (await running()) === 1, 60000, 'a render from elsewhere running');
      const gone0 = await metric(d, 'glintd_work_gone_waiting_total');
      await page.evaluate(u => { fetch(u, { headers: { 'X-Glint-Token': window.glint.state.session.token } }).catch(() => {}); }, `/api/v1/materials/${mid}/preview.png?view=1&size=128`);
      await waitFor(async () => (await metric(d, 'glintd_work_waiting_by_class', '{class="interactive"}')) === 1, 60000, 'the page\'s preview waiting');
      await page.close();
      await waitFor(async () => (await metric(d, 'glintd_work_gone_waiting_total')) === gone0 + 1, 60000, 'the closed tab\'s request gave up its wait');
      assertEq(await metric(d, 'glintd_work_waiting_by_class', '{class="interactive"}'), 0, 'nothing waits');
      const admitted = await metric(d, 'glintd_work_total', '{outcome="admitted"}');
      ctrl.abort();
      assertEq(await held, 'AbortError', 'the other render abandoned too');
      await waitFor(async () => (await running()) === 0, 60000, 'the slot free again');
      const r = await fetch(`${d.base}/api/v1/materials/${mid}/preview.png?view=0&size=32`, { headers: { 'X-Glint-Token': sess[1] } });
      assertEq(r.status, 200, 'a following request is admitted');
      assertEq(await metric(d, 'glintd_work_total', '{outcome="admitted"}'), admitted + 1, 'the closed tab\'s preview never ran');
    } finally {
      await d.stop();
    }
  },

  async 'strokes reach the other artist while a reference render runs'(t) {
    // on a machine busy with other tests a render may be told to wait (503), and is asked again
    t.allowConsole(/status of 503/);
    // its daemon stops under the two studios, cutting their event streams
    t.allowConsole(/\/events\?.*|ERR_INCOMPLETE_CHUNKED_ENCODING/);
    // a daemon of its own: no held-out measurement of another test's fits running (background work too)
    const d = await new Daemon(['--work-max-seconds', '0', '--background-priority', 'normal', '--quiet']).start();
    try {
      await strokesWhileRendering(t, d);
    } finally {
      await d.stop();
    }
  },
});

// Two artists in one session on d; one's studio runs big reference renders.
async function strokesWhileRendering(t, d) {
  const { url } = await d.newSession({ mesh: 'torus', width: 96, height: 96 });
  const ana = await t.page(), bo = await t.page();
  await openStudio(ana, url);
  await openStudio(bo, url);
  await drawStroke(ana, [[20, 30], [70, 50]]);
  await settled(ana, 0);
  const mid = await fit(ana);
  await ana.waitForFunction(() => window.glint.api.images.counts().running === 0 && window.glint.state.judge.frames > 0);
  // (the fit's held-out measurement is background work too: let it end; at
  // normal CPU priority, so that it does on a machine busy with other tests)
  await waitFor(async () => (await metric(d, 'glintd_work_running_by_class', '{class="background"}')) === 0, 60000, 'no background work yet');
  // reference renders of every view through the studio's queue (as its error table asks for them), made big
  await ana.evaluate(async mid => {
    const { CLASS } = await import('/requests.js');
    const api = window.glint.api;
    window.__refs = [0, 1, 2].map(k => api.images.run('reference:view' + k,
      (s, h) => api.materialFile(mid, 'preview.exr', { view: String(k), size: '4096', renderer: 'cpu', env: 'studio', lights: '256' }, s, h),
      { cls: CLASS.reference }).then(() => 'done', e => e.name));
  }, mid);
  // it runs in glintd as background work (the Priority header came through), one at a time
  await waitFor(async () => (await metric(d, 'glintd_work_running_by_class', '{class="background"}')) === 1, 60000, 'a reference render running');
  assertEq(await ana.evaluate(() => window.glint.api.images.counts().reference), 1, 'one reference render at once');
  for (const [from, to, pts] of [[bo, ana, [[10, 60], [90, 40]]], [ana, bo, [[50, 10], [50, 90]]]]) {
    const s0 = await to.evaluate(() => window.glint.state.session.appliedSeq);
    await drawStroke(from, pts, 4);
    await settled(from, 0);
    await to.waitForFunction(s => window.glint.state.session.appliedSeq >= s + 1 && window.glint.state.session.views[0].state === 'ready', s0, { timeout: 60000 });
    assertEq(maxDiff(await canvasPixels(from), await canvasPixels(to)), 0, 'the stroke is on the other artist\'s canvas');
  }
  // and the reference render was still running all the while
  assertEq(await metric(d, 'glintd_work_running_by_class', '{class="background"}'), 1, 'the reference render still runs');
  // a preview (interactive) is admitted beside it
  const ok = await ana.evaluate(async mid => (await window.glint.api.materialFile(mid, 'preview.png', { view: '0', size: '64' })).status, mid);
  assertEq(ok, 200, 'an interactive preview beside the reference render');
  await ana.evaluate(() => window.glint.api.images.abortPrefix('reference:'));
  assertEq((await ana.evaluate(() => Promise.all(window.__refs))).join(','), 'AbortError,AbortError,AbortError', 'the reference renders aborted');
  await waitFor(async () => (await metric(d, 'glintd_work_running')) === 0, 60000, 'their slots free');
}
