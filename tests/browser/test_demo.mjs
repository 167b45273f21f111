// The daemon's demo session in the studio's "Recent sessions": glintd
// started as setup.sh's main job starts it (--demo-session FILE, the file
// written through the API once the daemon listens: a teapot scene and a
// session on it), a browser that has never been here sees "Demo: teapot
// ..." first in the list, and its Open link opens the session for painting
// with the paint token the daemon answers.  Before the file is written the
// list has no demo (and the start page no console error); a browser's own
// sessions stay listed after the demo, which is listed once even after it
// was opened (and so remembered) in that browser.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { run, assert, assertEq, MUST_MS } from './harness.mjs';

const DIR = fs.mkdtempSync(path.join(os.tmpdir(), 'glint-demo-'));
const DEMO = path.join(DIR, 'demo-session.json');
process.on('exit', () => fs.rmSync(DIR, { recursive: true, force: true }));

// The start page's recent sessions once its GET /api/v1/demo (and the
// demo's scene, when there is one) has been answered and drawn.
async function recentAfterDemo(page, base) {
  const asked = page.waitForResponse(r => r.url().endsWith('/api/v1/demo'), { timeout: MUST_MS });
  await page.goto(base + '/');
  const r = await asked;
  if (r.status() === 200) await page.waitForSelector('#recent li.demo', { timeout: MUST_MS });
  else await page.waitForSelector('#recent li', { timeout: MUST_MS });
  return page.$$eval('#recent li', lis => lis.map(li => {
    const a = li.querySelector('a');
    return { text: li.textContent, demo: li.classList.contains('demo'), href: a ? a.getAttribute('href') : null };
  }));
}

// What setup.sh's main job does once glintd listens: a teapot scene, a
// session on it, the answer written whole to the demo file.
async function makeDemo(daemon) {
  const sc = await daemon.api('POST', '/scenes', { mesh: 'teapot', width: 96, height: 96 });
  const s = await daemon.api('POST', '/sessions', { scene_id: sc.id });
  fs.writeFileSync(DEMO + '.tmp', JSON.stringify(s));
  fs.renameSync(DEMO + '.tmp', DEMO);
  return s;
}

run({
  async 'no demo before the file is written: the list says none yet'(t) {
    const page = await t.page();
    const list = await recentAfterDemo(page, t.daemon.base);
    t.log(JSON.stringify(list));
    assertEq(list.filter(r => r.demo).length, 0, 'demo entries');
    assertEq(list.length, 1, 'entries');
    assert(/none yet/.test(list[0].text), 'the empty list says so: ' + list[0].text);
  },

  async 'the demo session is first in Recent sessions and opens for painting'(t) {
    const s = await makeDemo(t.daemon);
    const page = await t.page();
    const list = await recentAfterDemo(page, t.daemon.base);
    t.log(JSON.stringify(list));
    assertEq(list.length, 1, 'entries in a new browser');
    assert(list[0].demo && /^Demo: teapot 96×96/.test(list[0].text), 'the demo entry: ' + list[0].text);
    assertEq(list[0].href, `#/session/${s.id}?token=${s.paint_token}`, 'its link');
    await t.shot(page, '60-demo-recent.png');
    const cut = await page.$eval('#recent li.demo span', e => e.scrollWidth - e.clientWidth);
    assertEq(cut, 0, 'pixels of the demo label cut off');

    await page.click('#recent li.demo a');
    await page.waitForSelector('body[data-ready="1"]', { timeout: MUST_MS });
    const opened = await page.evaluate(() => {
      const S = window.glint.state.session;
      return { id: S.id, canPaint: S.canPaint, views: S.views.length };
    });
    t.log(JSON.stringify(opened));
    assertEq(opened.id, s.id, 'the session opened');
    assertEq(opened.canPaint, true, 'opened for painting');
    assertEq(opened.views, 12, 'its views');

    // back on the start page: remembered now, still listed once, first
    const again = await recentAfterDemo(page, t.daemon.base);
    assertEq(again.filter(r => r.href && r.href.includes(s.id)).length, 1, 'entries of the demo session');
    assert(again[0].demo, 'the demo first: ' + JSON.stringify(again));
  },

  async "a browser's own sessions stay listed after the demo"(t) {
    const mine = await t.daemon.newSession({ mesh: 'sphere', width: 48, height: 48 });
    const page = await t.page();
    await page.goto(mine.url);
    await page.waitForSelector('body[data-ready="1"]', { timeout: MUST_MS });
    const list = await recentAfterDemo(page, t.daemon.base);
    t.log(JSON.stringify(list));
    assertEq(list.length, 2, 'entries');
    assert(list[0].demo, 'the demo first');
    assert(!list[1].demo && list[1].href.includes(mine.session.id) && /^sphere 48×48/.test(list[1].text),
      "this browser's session second: " + list[1].text);
  },
}, { daemonArgs: ['--demo-session', DEMO] });
