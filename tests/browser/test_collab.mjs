// Studio sessions with several people: strokes appear live on the others'
// canvases, presence, fits announced to everyone, a late joiner sees the
// whole history, a view-only link cannot paint, and a dropped connection
// (or a restarted daemon) catches up without duplicates or gaps.
import {
  run, openStudio, drawStroke, settled, canvasPixels, serverPixels, maxDiff, pageArray, recordToasts,
  assert, assertLE, assertGE, assertEq, waitFor, sleep,
} from './harness.mjs';

async function named(t, name) {
  const ctx = await t.context();
  await ctx.addInitScript(n => { if (location.protocol.startsWith('http')) localStorage.setItem('glint.name', n); }, name);
  return ctx.newPage();
}
const seqOf = page => page.evaluate(() => window.glint.state.session.appliedSeq);
const statsOf = page => page.evaluate(() => Object.assign({}, window.glint.state.session.stats));
// Wait until the page has applied the session's events up to #n, view 0
// ready; then it must have applied #n and nothing after it (the caller
// knows there is no later event: one more would be a stroke counted twice
// or one nobody drew).
async function appliedUpTo(page, n) {
  await page.waitForFunction(n => {
    const S = window.glint.state.session;
    return S.appliedSeq >= n && S.views[0].state === 'ready';
  }, n, { timeout: 60000 });
  assertEq(await seqOf(page), n, 'the events applied');
}

run({
  async 'two people in one session see each other\'s strokes live'(t) {
    // (how soon: tests/bench/bench_studio.mjs measures it)
    const { url } = await t.daemon.newSession({ mesh: 'torus', width: 128, height: 128 });
    const ana = await named(t, 'ana'), bo = await named(t, 'bo');
    await openStudio(ana, url);
    await openStudio(bo, url);
    for (const p of [ana, bo]) await p.waitForFunction(() => window.glint.state.session.presence.length === 2, null, { timeout: 60000 });
    const who = await ana.evaluate(() => [...document.querySelectorAll('#presence .who')].map(e => e.textContent).sort());
    assertEq(who.join(','), 'ana,bo', 'presence');
    const connects = p => p.evaluate(() => window.glint.state.session.stream.connects);
    const c0 = [await connects(ana), await connects(bo)];
    // One stroke at a time.  Before each, both screens hold every stroke so
    // far (the painter's own echo included: it may come after the other
    // screen has shown the stroke, and a count read before it would be one
    // short), so the new stroke is the session's event #n and nothing else
    // can come; the other screen must apply it as #n, drawn by the painter,
    // once.  (An exact wait for "last count + 1" could be overshot: on a
    // busy machine the echo and the next stroke may be applied in one task,
    // and the count never shows the value in between.)
    let n = 0;
    for (const [from, to, pts] of [[ana, bo, [[20, 30], [100, 50]]], [bo, ana, [[30, 100], [90, 20]]], [ana, bo, [[64, 10], [64, 118]]]]) {
      for (const p of [from, to]) await appliedUpTo(p, n);
      await drawStroke(from, pts, 4);
      n++;
      await appliedUpTo(to, n);
      const painter = await from.evaluate(() => window.glint.state.session.client);
      const got = await to.evaluate(n => {
        const S = window.glint.state.session, h = S.views[0].history.find(e => e.seq === n);
        const tag = h && h.tag;
        return { tag, times: S.views[0].history.filter(e => e.tag === tag).length, strokes: S.stats.strokes };
      }, n);
      assert(typeof got.tag === 'string' && got.tag.startsWith(painter + '-'), `stroke #${n} on view 0 is the painter's: ${JSON.stringify(got.tag)}`);
      assertEq(got.times, 1, `stroke #${n} applied once`);
      assertEq(got.strokes, n, 'strokes applied on the receiving screen');
    }
    // over the streams that were open: none of it came by reconnecting
    assertEq(JSON.stringify([await connects(ana), await connects(bo)]), JSON.stringify(c0), 'stream connections while painting');
    for (const p of [ana, bo]) {
      const st = await statsOf(p);
      assertEq(st.duplicates + st.gaps, 0, 'no duplicates or gaps');
    }
    // both at once, overlapping, on the same view
    await Promise.all([
      (async () => { for (let i = 0; i < 4; i++) await drawStroke(ana, [[10 + 20 * i, 10], [40 + 20 * i, 110]], 3); })(),
      (async () => { for (let i = 0; i < 4; i++) await drawStroke(bo, [[10, 20 + 25 * i], [118, 30 + 25 * i]], 3); })(),
    ]);
    await settled(ana, 0); await settled(bo, 0);
    await waitFor(async () => (await seqOf(ana)) === 11 && (await seqOf(bo)) === 11, 60000, 'all 11 strokes on both screens');
    const a = await canvasPixels(ana), b = await canvasPixels(bo);
    assertEq(maxDiff(a, b), 0, 'both canvases are the same');
    assertLE(maxDiff(a, await serverPixels(ana, 0)), 1, 'and the server agrees');
    await t.shot(ana, '20-collab-ana.png');
    await t.shot(bo, '21-collab-bo.png');
  },

  async 'a fit by one person appears for the other; a late joiner sees the whole history'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const ana = await named(t, 'ana'), bo = await named(t, 'bo');
    await openStudio(ana, url);
    await openStudio(bo, url);
    const boToasts = await recordToasts(bo);
    await drawStroke(ana, [[30, 30], [60, 40]]);
    await settled(ana, 0);
    await ana.keyboard.press('5');
    await ana.waitForFunction(() => window.glint.state.session.views[4].state === 'ready');
    await drawStroke(ana, [[20, 60], [70, 50]]);
    await settled(ana, 4);
    await ana.waitForSelector('#quality .q[data-preset]');
    await ana.click('#fit-btn');
    await ana.waitForFunction(() => window.glint.lastFit, null, { timeout: 60000 });
    const mid = await ana.evaluate(() => window.glint.lastFit.id);
    await bo.waitForFunction(id => window.glint.state.material && window.glint.state.material.id === id, mid, { timeout: 60000 });
    await bo.waitForFunction(() => window.glint.state.judge.frames > 0, null, { timeout: 60000 });
    assert((await boToasts()).some(x => x.title === 'New fit'), 'bo is told of the new fit');
    await t.shot(bo, '22-collab-fit-arrives.png');
    // a late joiner
    const cy = await named(t, 'cy');
    await openStudio(cy, url);
    await cy.waitForFunction(() => window.glint.state.session.views.every(v => v.state === 'ready'));
    await cy.waitForFunction(() => document.querySelectorAll('#activity li').length >= 3);
    const acts = await cy.evaluate(() => [...document.querySelectorAll('#activity li')].map(li => li.textContent));
    t.log('late joiner\'s activity: ' + acts.join(' | '));
    assert(acts.some(a => /fit/.test(a)) && acts.filter(a => /paint/.test(a)).length === 2, 'history: two strokes and a fit');
    for (const k of [0, 4]) {
      const img = await pageArray(cy, k => window.glint.state.session.views[k].disp.data, k);
      const ref = await pageArray(ana, k => window.glint.state.session.views[k].conf.data, k);
      let m = 0; for (let i = 0; i < img.length; i++) m = Math.max(m, Math.abs(img[i] - ref[i]));
      assertEq(m, 0, `late joiner's view ${k} equals the painter's`);
    }
    assertEq(await cy.evaluate(() => window.glint.state.material && window.glint.state.material.id), mid, 'the late joiner sees the latest material');
    assertEq(await cy.evaluate(() => document.querySelectorAll('#thumbs .thumb.painted').length), 2, 'painted views marked');
  },

  async 'a view-only link watches but cannot paint or fit'(t) {
    const { url, viewUrl, session } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const ana = await named(t, 'ana'), viewer = await named(t, 'viewer');
    await openStudio(ana, url);
    await openStudio(viewer, viewUrl);
    assertEq(await viewer.evaluate(() => window.glint.state.session.doc.access), 'view', 'access');
    assert(await viewer.isVisible('#readonly-badge'), 'view-only badge');
    assert(await viewer.isDisabled('#fit-btn'), 'fit disabled');
    const before = await canvasPixels(viewer);
    await drawStroke(viewer, [[10, 10], [80, 80]]);
    await sleep(300);
    assertEq(maxDiff(await canvasPixels(viewer), before), 0, 'a drag does not paint');
    const strokes = await t.daemon.api('GET', `/sessions/${session.id}/strokes?since=0`, undefined, { 'X-Glint-Token': session.paint_token });
    assertEq(strokes.strokes.length, 0, 'nothing was sent');
    await drawStroke(ana, [[20, 50], [70, 50]]);
    await viewer.waitForFunction(() => window.glint.state.session.appliedSeq >= 1);
    await settled(ana, 0);
    assertEq(maxDiff(await canvasPixels(viewer), await canvasPixels(ana)), 0, 'the viewer sees the painter\'s stroke');
    await viewer.keyboard.press('0');
    await t.shot(viewer, '23-view-only.png');
    await ana.click('#share-btn');
    const links = [await ana.inputValue('#link-paint'), await ana.inputValue('#link-view')];
    assert(links[0].includes(session.paint_token) && links[1].includes(session.view_token), 'share dialog shows both links');
    await t.shot(ana, '24-share.png');
  },

  async 'someone else\'s upload replaces the view live; undo then says why it cannot'(t) {
    const { url, session } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const page = await named(t, 'ana');
    await openStudio(page, url);
    await drawStroke(page, [[20, 20], [70, 60]]);
    await settled(page, 0);
    // another person uploads an image (a PNG made in the page, sent from node like a script would)
    const png = Buffer.from(await page.evaluate(async () => {
      const c = new OffscreenCanvas(96, 96), g = c.getContext('2d');
      g.fillStyle = '#405060'; g.fillRect(0, 0, 96, 96); g.fillStyle = '#f0c000'; g.fillRect(30, 30, 36, 36);
      return Array.from(new Uint8Array(await (await c.convertToBlob({ type: 'image/png' })).arrayBuffer()));
    }));
    await fetch(`${t.daemon.base}/api/v1/sessions/${session.id}/views/0/painting`, { method: 'PUT', headers: { 'X-Glint-Token': session.paint_token, 'Content-Type': 'image/png' }, body: png });
    await page.waitForFunction(() => window.glint.state.session.appliedSeq === 2 && window.glint.state.session.views[0].state === 'ready');
    await settled(page, 0);
    assertLE(maxDiff(await canvasPixels(page), await serverPixels(page, 0)), 1, 'the upload shows');
    await page.keyboard.press('Control+z');
    const toast = page.locator('.toast.error', { hasText: 'no longer be undone' });
    await toast.waitFor({ timeout: 60000 });
    assertLE(maxDiff(await canvasPixels(page), await serverPixels(page, 0)), 1, 'nothing was undone');
    assertEq(await seqOf(page), 2, 'no undo was sent');
  },

  async 'a dropped connection catches up without duplicates or gaps'(t) {
    // while the stream is cut, the browser's reconnection attempts fail on purpose
    t.allowConsole(/\/events/);
    const { url, session } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const H = { 'X-Glint-Token': session.paint_token };
    const page = await named(t, 'ana');
    await openStudio(page, url);
    await drawStroke(page, [[20, 20], [40, 30]]);
    await settled(page, 0);
    // cut the stream and refuse reconnections for a while
    await page.route('**/events**', r => r.abort());
    await page.evaluate(() => window.glint.state.session.stream.drop());
    await page.waitForFunction(() => window.glint.state.session.stream.state !== 'open');
    const stroke = (y, c) => ({ mode: 'paint', color: c, diameter: 10, kappa: 0.05, opacity: 1, points: [[10, y], [86, y]] });
    for (let i = 0; i < 6; i++) {
      await t.daemon.api('POST', `/sessions/${session.id}/views/${i % 2 ? 3 : 0}/strokes`, { strokes: [stroke(15 + 12 * i, [0.2 * i, 0.5, 1 - 0.1 * i])] }, H);
    }
    await t.daemon.api('POST', `/sessions/${session.id}/views/0/strokes`, { strokes: [stroke(90, [1, 0, 0]), stroke(5, [0, 1, 0])] }, H);
    await sleep(600);
    assertEq(await seqOf(page), 1, 'nothing arrives while cut');
    await t.shot(page, '25-reconnecting.png');
    await page.unroute('**/events**');
    await page.waitForFunction(() => window.glint.state.session.appliedSeq === 9, null, { timeout: 60000 });
    const st = await statsOf(page);
    t.log(`after reconnecting: applied up to #9, stats ${JSON.stringify(st)}`);
    assertEq(st.duplicates, 0, 'no duplicates');
    assertEq(st.gaps, 0, 'no gaps');
    assertEq(st.strokes, 1 + 8, 'each stroke applied once (1 own + 8 missed)');
    await settled(page, 0);
    assertLE(maxDiff(await canvasPixels(page), await serverPixels(page, 0)), 1, 'view 0 caught up');
    await page.keyboard.press('4');
    await page.waitForFunction(() => window.glint.state.k === 3 && window.glint.state.session.views[3].state === 'ready');
    assertLE(maxDiff(await canvasPixels(page), await serverPixels(page, 3)), 1, 'view 3 caught up');
  },

  async 'a restarted daemon: the studio reconnects and catches up'(t) {
    t.allowConsole(/\/events|ERR_CONNECTION_REFUSED|ERR_EMPTY_RESPONSE|ERR_CONNECTION_RESET/);
    const { url, session } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const H = { 'X-Glint-Token': session.paint_token };
    const page = await named(t, 'ana');
    await openStudio(page, url);
    await drawStroke(page, [[20, 20], [60, 30]]);
    await settled(page, 0);
    // every view loaded first: a base render still running when glintd stops
    // is cancelled (503), which is not what this test is about
    await page.waitForFunction(() => window.glint.state.session.views.every(v => v.state === 'ready'), null, { timeout: 60000 });
    await t.daemon.restart();
    await t.daemon.api('POST', `/sessions/${session.id}/views/0/strokes`, { strokes: [{ color: [0, 0, 1], diameter: 20, points: [[10, 70], [80, 70]] }] }, H);
    await page.waitForFunction(() => window.glint.state.session.appliedSeq === 2 && window.glint.state.session.stream.state === 'open', null, { timeout: 60000 });
    const st = await statsOf(page);
    assertEq(st.duplicates + st.gaps, 0, 'no duplicates or gaps after the restart');
    await drawStroke(page, [[20, 80], [80, 10]]);
    await settled(page, 0);
    assertLE(maxDiff(await canvasPixels(page), await serverPixels(page, 0)), 1, 'in step with the restarted server');
    t.log(`reconnected after the restart (${await page.evaluate(() => window.glint.state.session.stream.connects)} connections in all)`);
  },

  // The studio reopens on new links by closing the session and reloading the
  // page; until the new page commits, the old one runs what it had in
  // flight.  Views still loading then (a busy machine) used to finish into a
  // studio with no session and throw "Cannot read properties of null".
  // Here the other views' base renders are held, the studio closes as it
  // does before that reload, and then they arrive.
  async 'views that arrive after the studio closed its session change nothing and throw nothing'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const ana = await named(t, 'ana');
    const held = [];
    let bases = 0, served = 0;
    let hold = true;
    await ana.route('**/base.png*', r => { if (bases++ === 0 || !hold) r.continue(); else held.push(r); });
    await openStudio(ana, url);
    await waitFor(() => held.length > 0, null, 'the other views are loading');
    const before = await ana.evaluate(() => window.glint.state.session.views.filter(v => v.state === 'ready').length);
    await ana.evaluate(() => { window.__closed = window.glint.state.session; window.glint.closeStudio(); });
    hold = false;
    for (const r of held.splice(0)) { await r.continue(); served++; }
    // they are read and installed in the closed session, and go no further
    await ana.waitForFunction(n => window.__closed.views.filter(v => v.state === 'ready').length > n, before, { timeout: 60000 });
    await sleep(500);                    // a frame's thumbnail redraws, had any been scheduled
    t.log(`${served} held reads arrived after closing; the studio stayed quiet`);
    assertEq(await ana.evaluate(() => window.glint.state.session), null, 'no session open');
  },

  async 'replacing the share links: the old view link stops, the studio reopens on the new one'(t) {
    const { url, viewUrl, session } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const ana = await named(t, 'ana'), viewer = await named(t, 'viewer');
    t.allowConsole(/403|Forbidden/);
    await openStudio(ana, url);
    await openStudio(viewer, viewUrl);
    await viewer.waitForFunction(() => document.getElementById('conn').textContent === 'live');
    await ana.click('#share-btn');
    assert(await ana.isVisible('#links-replace'), 'the paint link may replace the links');
    await ana.selectOption('#links-expires-in', '86400');
    await ana.click('#links-replace');
    await ana.waitForFunction(t0 => window.glint && window.glint.state.session && window.glint.state.session.token !== t0 && window.glint.paintableMs != null, session.paint_token, { timeout: 60000 });
    const doc = await ana.evaluate(() => window.glint.state.session.doc);
    assert(doc.paint_token !== session.paint_token && doc.expires, 'new tokens, expiring');
    t.log(`new links expire ${doc.expires}`);
    // the viewer's live stream ended and was refused on reconnecting
    await viewer.waitForFunction(() => document.getElementById('conn').textContent === 'disconnected', null, { timeout: 60000 });
    const old = await fetch(`${t.daemon.base}/api/v1/sessions/${session.id}`, { headers: { 'X-Glint-Token': session.view_token } });
    assertEq(old.status, 403, 'the old view link is refused');
    // the new paint link paints
    await drawStroke(ana, [[20, 30], [44, 30]]);
    await settled(ana, 0);
    await ana.click('#share-btn');
    assert((await ana.textContent('#links-expiry')).includes('expire'), 'the dialog says when the links expire');
    await t.shot(ana, '25-links-replaced.png');
  },
});
