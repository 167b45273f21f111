// The studio at its edges: a finished fit job's event stream is closed for
// good (done or failed: no reconnecting to it), the fit control waits for a
// painted view (and wakes up when anyone paints one), a "nothing painted"
// refusal reads as a sentence, and a session link with a wrong, cut-short
// or missing token (or an unknown session) gives a page that says so, with
// the way back to the start page, instead of a half-working studio.
import {
  run, openStudio, drawStroke, settled, assert, assertEq, assertLE, waitFor, sleep,
} from './harness.mjs';

const JOB_EVENTS = /\/api\/v1\/jobs\/[^/]+\/events/;

// Requests whose URL matches re, from now on.
function countRequests(page, re) {
  const seen = [];
  page.on('request', r => { if (re.test(r.url())) seen.push({ url: r.url() }); });
  return seen;
}

const fitState = page => page.evaluate(() => {
  const b = document.getElementById('fit-btn'), h = document.getElementById('fit-hint');
  return { disabled: b.disabled, title: b.title, hint: h && !h.classList.contains('hidden') ? h.textContent : '' };
});

const toasts = page => page.evaluate(() => [...document.querySelectorAll('#toasts .toast')].map(t => ({
  title: t.querySelector('.t').textContent, detail: t.querySelector('.d').textContent, error: t.classList.contains('error'),
})));

run({
  async 'a finished fit job: its event stream is not opened again'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const page = await t.page();
    await openStudio(page, url);
    await page.waitForSelector('#quality .q[data-preset]');
    await drawStroke(page, [[30, 30], [60, 40]]);
    await settled(page, 0);
    const seen = countRequests(page, JOB_EVENTS);
    await page.waitForFunction(() => !document.getElementById('fit-btn').disabled);
    await page.click('#fit-btn');
    await page.waitForFunction(() => window.glint.lastFit, null, { timeout: 60000 });
    const fit = await page.evaluate(() => window.glint.lastFit);
    assertEq(fit.cached, false, 'the first fit of a fresh scene is a job');
    await page.waitForFunction(() => window.glint.state.fit.jobStream.state === 'closed');
    const atDone = seen.length;
    await sleep(10000);
    const after = seen.length - atDone;
    t.log(`job event stream requests: ${seen.length} in all, ${after} in the 10 s after the fit finished`);
    assertEq(after, 0, 'requests for the job\'s events after it finished');
    assertLE(seen.length, 1, 'job event requests (the one that delivered the final event)');
    assertEq(await page.evaluate(() => window.glint.state.fit.jobStream.state), 'closed', 'the job stream is closed');
  },

  async 'a failed fit job: the failure is said and its stream is not opened again'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const page = await t.page();
    await openStudio(page, url);
    await page.waitForSelector('#quality .q[data-preset]');
    await drawStroke(page, [[30, 30], [60, 40]]);
    await settled(page, 0);
    // one fit, one job (a method that chooses sends a quick first look beside it)
    await page.selectOption('#fit-method', 'hf3');
    // glintd answers with a job that fails while building its precomputation
    const id = 'f00d'.repeat(8);
    const job = (seq, o) => Object.assign({ id, kind: 'fit', state: 'running', progress: 0.2, stage: 'precomputation', created: new Date().toISOString() }, o);
    await page.route('**/api/v1/sessions/*/fits', r => r.fulfill({
      status: 202, contentType: 'application/json', headers: { Location: `/api/v1/jobs/${id}` },
      body: JSON.stringify({ job: job(0, { state: 'queued', progress: 0, stage: 'queued' }) }),
    }));
    let streams = 0;
    await page.route(`**/api/v1/jobs/${id}/events*`, r => {
      streams++;
      const since = +(r.request().headers()['last-event-id'] || 0);
      const evs = [[1, 'progress', job(1)], [2, 'failed', job(2, { state: 'failed', error: 'the operator did not fit in memory' })]];
      r.fulfill({ status: 200, contentType: 'text/event-stream',
        body: evs.filter(e => e[0] > since).map(([n, type, j]) => `id: ${n}\nevent: ${type}\ndata: ${JSON.stringify(j)}\n\n`).join('') });
    });
    await page.click('#fit-btn');
    await page.waitForFunction(() => [...document.querySelectorAll('#toasts .toast.error')].some(t => /did not fit in memory/.test(t.textContent)), null, { timeout: 60000 });
    await sleep(5000);
    t.log(`job event stream requests for the failed job: ${streams}`);
    assertEq(streams, 1, 'job event requests');
    assertEq(await page.evaluate(() => window.glint.state.fit.jobStream.state), 'closed', 'the job stream is closed');
    assertEq((await fitState(page)).disabled, false, 'the fit can be tried again');
  },

  async 'sse.js: a handler\'s "stop" and the final events end a stream for good; an async handler is refused'(t) {
    const page = await t.page();
    await page.goto(t.daemon.base + '/#/');
    const hits = {};
    await page.route('**/sse-probe/*', r => {
      const name = new URL(r.request().url()).pathname.split('/').pop();
      hits[name] = (hits[name] || 0) + 1;
      r.fulfill({ status: 200, contentType: 'text/event-stream',
        body: 'id: 1\nevent: progress\ndata: {"n":1}\n\nid: 2\nevent: done\ndata: {"n":2}\n\n' });
    });
    const got = await page.evaluate(async () => {
      const { EventStream } = await import('/sse.js');
      const follow = (name, onEvent, opts) => new Promise(res => {
        const seen = [];
        const es = new EventStream('/sse-probe/' + name, Object.assign({
          onEvent: (type, d) => { seen.push(type); return onEvent(type, d); },
        }, opts)).start();
        setTimeout(() => { const r = { state: es.state, seen: seen.join(' ') }; es.stop(); res(r); }, 3000);
      });
      return {
        stop: await follow('stop', type => (type === 'done' ? 'stop' : undefined)),
        final: await follow('final', () => undefined, { final: ['done', 'failed'] }),
        async: await follow('async', async type => (type === 'done' ? 'stop' : undefined)),
      };
    });
    t.log(`requests: ${JSON.stringify(hits)}; ${Object.entries(got).map(([k, v]) => `${k}: ${v.state} after "${v.seen}"`).join('; ')}`);
    assertEq(hits.stop, 1, 'requests of the stream stopped by its handler');
    assertEq(got.stop.state, 'closed', 'that stream is closed');
    assertEq(got.stop.seen, 'progress done', 'and saw every event once');
    assertEq(hits.final, 1, 'requests of the stream that ended with a final event');
    assertEq(got.final.state, 'closed', 'that stream is closed');
    assertEq(hits.async, 1, 'requests of the stream with an async handler');
    assertEq(got.async.state, 'failed', 'that stream says its handler is wrong');
  },

  async 'fit waits for a painted view and wakes up when anyone paints one'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const ana = await t.page(), bo = await t.page();
    await openStudio(ana, url);
    await openStudio(bo, url);
    for (const p of [ana, bo]) await p.waitForSelector('#quality .q[data-preset]');
    const fits = countRequests(bo, /\/fits$/);
    for (const p of [ana, bo]) {
      const s = await fitState(p);
      assert(s.disabled, 'fit is disabled while nothing is painted');
      assert(/paint or upload at least one view/i.test(s.hint), 'a hint says what to do: ' + JSON.stringify(s.hint));
      assert(/paint or upload at least one view/i.test(s.title), 'and so does the button: ' + JSON.stringify(s.title));
    }
    await t.shot(bo, '30-fit-needs-a-painting.png');
    await bo.keyboard.press('f');                    // the keyboard does not get around it
    await sleep(300);
    assertEq(fits.length, 0, 'fit requests sent with nothing painted');
    // Ana paints: her fit control and Bo's (live) come on
    await drawStroke(ana, [[30, 30], [60, 40]]);
    await settled(ana, 0);
    for (const p of [ana, bo]) {
      await p.waitForFunction(() => !document.getElementById('fit-btn').disabled, null, { timeout: 60000 });
      const s = await fitState(p);
      assertEq(s.hint, '', 'the hint is gone');
      assert(!/paint or upload/i.test(s.title), 'the button no longer asks for a painting');
    }
    await bo.click('#fit-btn');
    await bo.waitForFunction(() => window.glint.lastFit, null, { timeout: 60000 });
  },

  async 'a "nothing painted" refusal reads as a sentence'(t) {
    // glintd's own answer to a fit of a session with nothing painted
    const empty = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const r = await fetch(`${t.daemon.base}/api/v1/sessions/${empty.session.id}/fits`, {
      method: 'POST', headers: { 'X-Glint-Token': empty.session.paint_token, 'Content-Type': 'application/json' }, body: '{}' });
    assertEq(r.status, 422, 'glintd refuses the fit');
    const problem = await r.text();
    assert(/no-paintings/.test(problem), 'as "no-paintings": ' + problem);
    // the studio sees a painted view but glintd (say, a moment behind) still answers so
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const page = await t.page();
    t.allowConsole(/status of 422/);
    await openStudio(page, url);
    await page.waitForSelector('#quality .q[data-preset]');
    await drawStroke(page, [[30, 30], [60, 40]]);
    await settled(page, 0);
    await page.route('**/api/v1/sessions/*/fits', rt => rt.fulfill({ status: 422, contentType: 'application/problem+json', body: problem }));
    await page.waitForFunction(() => !document.getElementById('fit-btn').disabled);
    await page.click('#fit-btn');
    await page.waitForSelector('#toasts .toast.error');
    const [msg] = await toasts(page);
    t.log(`shown: "${msg.title}" — ${msg.detail}`);
    assert(!/422|Unprocessable|problem|no-paintings/i.test(msg.title + ' ' + msg.detail), 'no raw problem text');
    assert(/paint/i.test(msg.title + ' ' + msg.detail), 'says to paint first');
    assertEq((await fitState(page)).disabled, false, 'the fit can be tried again');
  },

  async 'a wrong, cut-short or missing token, or an unknown session: a page that says so'(t) {
    const { session } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const base = t.daemon.base;
    const cases = [
      ['wrong token', `${base}/#/session/${session.id}?token=${'0'.repeat(32)}`, 403],
      ['cut-short token', `${base}/#/session/${session.id}?token=${session.paint_token.slice(0, 11)}`, 403],
      ['no token', `${base}/#/session/${session.id}?token=`, 401],
      ['unknown session', `${base}/#/session/${'ab'.repeat(16)}?token=${session.paint_token}`, 404],
    ];
    t.allowConsole(/status of 40[134]/);
    for (const [what, link, status] of cases) {
      const page = await t.page();
      const api = [];
      page.on('response', r => { if (r.url().includes('/api/v1/')) api.push(r.status() + ' ' + new URL(r.url()).pathname); });
      await page.goto(link);
      await page.waitForSelector('#denied:not(.hidden)', { timeout: 60000 });
      const shown = await page.evaluate(() => ({
        studio: !document.getElementById('studio').classList.contains('hidden'),
        start: !document.getElementById('start').classList.contains('hidden'),
        text: document.getElementById('denied').innerText,
        back: !!document.querySelector('#denied a[href="#/"]'),
      }));
      t.log(`${what}: ${shown.text.replace(/\s+/g, ' ').slice(0, 160)}`);
      assert(!shown.studio && !shown.start, 'only the message is shown');
      assert(/link/i.test(shown.text), 'it talks about the link');
      assert(status === 404 ? /(no longer|not) exist|unknown|deleted/i.test(shown.text) : /wrong|expired|cut short|incomplete|token/i.test(shown.text), 'it says what happened');
      assert(shown.back, 'a way back to the start page');
      assertEq(api.filter(a => !a.startsWith('2')).join(', '), `${status} /api/v1/sessions/${link.match(/session\/(\w+)/)[1]}`, 'one refused request, nothing more');
      assert(!api.some(a => /events/.test(a)), 'no event stream opened');
      assertEq((await toasts(page)).length, 0, 'no error toasts');
      if (status === 403) await t.shot(page, '31-link-refused.png');
      await page.click('#denied a[href="#/"]');
      await page.waitForSelector('#start:not(.hidden)', { timeout: 60000 });
      assert(await page.evaluate(() => document.getElementById('denied').classList.contains('hidden')), 'the message is gone on the start page');
      await page.close();
    }
  },
});
