// harness.mjs: end-to-end tests of the glint studio (web/) in headless
// Chromium (Debian's /usr/bin/chromium driven by playwright-core) against a
// real glintd on an ephemeral loopback port with a fresh data directory.
//
// usage in a test file:
//   import { run } from './harness.mjs';
//   run({ async 'paints a stroke'(t) { const page = await t.page(); ... } });
// Every test gets fresh browser contexts (t.page(), t.context()); any
// console error or page error in them fails the test, unless the test
// declares it expected (t.allowConsole(re) for messages whose source URL or
// text matches).  Prints one line per test and "N passed, N failed"; exits
// 77 (skipped) when Chromium or playwright-core is missing.

import { spawn } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const HERE = path.dirname(fileURLToPath(import.meta.url));
export const SRC = process.env.GLINT_SOURCE_DIR || path.resolve(HERE, '..', '..');
export const GLINTD = process.env.GLINTD || path.join(SRC, 'build', 'server', 'glintd');
export const CHROMIUM = process.env.GLINT_CHROMIUM || '/usr/bin/chromium';
export const ARTIFACTS = process.env.GLINT_ARTIFACTS_DIR ||
  path.join(process.env.GLINT_BUILD_DIR || path.join(SRC, 'build'), 'artifacts');
const PW = path.join(HERE, 'node_modules', 'playwright-core', 'index.mjs');

export const sleep = ms => new Promise(r => setTimeout(r, ms));

// The longest wait for something that must happen (the tests' explicit
// waits use the same): it only catches a hang, since what comes ends the
// wait at once, so it is generous enough for a machine busy with other
// tests.
export const MUST_MS = 60000;

// ---- the daemon -----------------------------------------------------------------------------

export class Daemon {
  constructor(args) {
    this.tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'glint-browser-'));
    this.dataDir = path.join(this.tmp, 'data');
    this.args = args || [];
    this.port = 0;
    this.logPath = path.join(this.tmp, 'glintd.log');
  }

  // Start glintd; `port` 0 picks an ephemeral one (a restart reuses it: the
  // pages keep their origin).  Beside other tests, a port just given up can
  // be taken for a moment by another program's connection: then glintd
  // cannot listen on it, and starting is tried again until it can.
  async start(port) {
    for (let attempt = 1; ; attempt++) {
      try {
        return await this.startOnce(port);
      } catch (e) {
        const taken = port && /Address already in use/.test(this.log().slice(this.logStart));
        if (!taken || attempt >= 150) throw e;
        await sleep(200);
      }
    }
  }

  async startOnce(port) {
    const portFile = path.join(this.tmp, 'port');
    this.logStart = this.log().length;
    fs.rmSync(portFile, { force: true });
    const log = fs.openSync(this.logPath, 'a');
    this.proc = spawn(GLINTD, ['--port', String(port || 0), '--port-file', portFile, '--data-dir', this.dataDir,
      '--web-dir', path.join(SRC, 'web'), ...this.args], { stdio: ['ignore', log, log] });
    fs.closeSync(log);
    let exited = null;
    this.proc.on('exit', c => { exited = c; });
    const t0 = Date.now();
    while (Date.now() - t0 < MUST_MS) {
      if (exited !== null) throw new Error(`glintd exited with ${exited}; log: ${this.logPath}`);
      try {
        const txt = fs.readFileSync(portFile, 'utf8').trim();
        if (txt) { this.port = +txt; this.base = `http://127.0.0.1:${this.port}`; return this; }
      } catch (_) { /* not yet */ }
      await sleep(20);
    }
    throw new Error('glintd did not start');
  }

  async stop(signal) {
    if (!this.proc || this.proc.exitCode !== null) return;
    const done = new Promise(r => this.proc.once('exit', r));
    this.proc.kill(signal || 'SIGTERM');
    const t = setTimeout(() => this.proc.kill('SIGKILL'), 20000);
    await done;
    clearTimeout(t);
  }

  async restart() {
    await this.stop();
    await this.start(this.port);
  }

  // ---- the API from node (what a script or another person would do) ----
  async api(method, p, body, headers) {
    const h = Object.assign({}, headers || {});
    let payload = body;
    if (body !== undefined && !(body instanceof Uint8Array) && !Buffer.isBuffer(body)) {
      payload = JSON.stringify(body);
      h['Content-Type'] = 'application/json';
    }
    const r = await fetch(this.base + '/api/v1' + p, { method, headers: h, body: payload });
    const ct = r.headers.get('content-type') || '';
    const out = ct.includes('json') ? await r.json() : Buffer.from(await r.arrayBuffer());
    if (!r.ok) throw new Error(`${method} ${p}: ${r.status} ${JSON.stringify(out)}`);
    return out;
  }

  async newSession(spec) {
    const sc = await this.api('POST', '/scenes', spec || { mesh: 'sphere', width: 96, height: 96 });
    const s = await this.api('POST', '/sessions', { scene_id: sc.id });
    return { scene: sc, session: s, url: `${this.base}/#/session/${s.id}?token=${s.paint_token}`,
             viewUrl: `${this.base}/#/session/${s.id}?token=${s.view_token}` };
  }

  log() { try { return fs.readFileSync(this.logPath, 'utf8'); } catch (_) { return ''; } }
}

// ---- assertions ---------------------------------------------------------------------------------

export function assert(cond, msg) { if (!cond) throw new Error('assertion failed: ' + msg); }
export function assertLE(a, b, msg) { if (!(a <= b)) throw new Error(`assertion failed: ${msg}: ${a} > ${b}`); }
export function assertGE(a, b, msg) { if (!(a >= b)) throw new Error(`assertion failed: ${msg}: ${a} < ${b}`); }
export function assertEq(a, b, msg) { if (a !== b) throw new Error(`assertion failed: ${msg}: ${JSON.stringify(a)} !== ${JSON.stringify(b)}`); }

export async function waitFor(fn, ms, what) {
  const t0 = Date.now();
  let last;
  while (Date.now() - t0 < (ms || MUST_MS)) {
    try { last = await fn(); if (last) return last; } catch (e) { last = e; }
    await sleep(25);
  }
  throw new Error('timed out waiting for ' + (what || 'a condition') + (last instanceof Error ? ': ' + last.message : ''));
}

// ---- page helpers ---------------------------------------------------------------------------------

// Open a session link and wait until the first view can be painted.
export async function openStudio(page, url) {
  await page.goto(url);
  await page.waitForSelector('body[data-ready="1"]', { timeout: MUST_MS });
  return page.evaluate(() => window.glint.paintableMs);
}

// Every toast the page shows from now on, kept after the toast itself has
// gone (after 4 s, an error's after 12: a busy machine may pass that before
// a test looks): returns a function that gives [{title, detail, error}].
export async function recordToasts(page) {
  await page.evaluate(() => {
    window.__toasts = [];
    new MutationObserver(ms => {
      for (const m of ms) {
        for (const n of m.addedNodes) {
          if (n.classList && n.classList.contains('toast')) {
            window.__toasts.push({ title: n.querySelector('.t').textContent, detail: n.querySelector('.d').textContent, error: n.classList.contains('error') });
          }
        }
      }
    }).observe(document.getElementById('toasts'), { childList: true });
  });
  return () => page.evaluate(() => window.__toasts.slice());
}

// Image coordinates of the view -> page coordinates of the paint canvas.
export async function canvasMapper(page) {
  const box = await page.locator('#paint').boundingBox();
  const [w, h] = await page.evaluate(() => [document.getElementById('paint').width, document.getElementById('paint').height]);
  return (x, y) => [box.x + x * box.width / w, box.y + y * box.height / h];
}

// Drag the mouse along image-space points (a stroke).
export async function drawStroke(page, pts, steps) {
  const map = await canvasMapper(page);
  const [x0, y0] = map(pts[0][0], pts[0][1]);
  await page.mouse.move(x0, y0);
  await page.mouse.down();
  for (let i = 1; i < pts.length; i++) {
    const [x, y] = map(pts[i][0], pts[i][1]);
    await page.mouse.move(x, y, { steps: steps || 6 });
  }
  await page.mouse.up();
}

// Paint the chosen finish on every view (the Finish panel's button) and wait
// until the button is back: every view painted.
export async function paintAllViews(page) {
  await page.click('#preset-apply');
  await page.waitForFunction(() => document.getElementById('preset-apply').textContent === 'Paint all views' &&
                             !document.getElementById('preset-apply').disabled, null, { timeout: 60000 });
}

// Wait until this page's strokes on view k are confirmed by the server.
export async function settled(page, k) {
  await page.waitForFunction(k => {
    const S = window.glint.state.session, v = S && S.views[k];
    return v && v.state === 'ready' && v.pending.length === 0 && S.puts.size === 0;
  }, k, { timeout: MUST_MS });
}

// What fn(arg) returns in the page, a typed array (Uint8ClampedArray,
// Float32Array, ...), as the same typed array here.  Its bytes come as one
// base64 string: page.evaluate would send an array number by number (a
// 512x512 RGBA canvas took 20-60 s that way on a busy machine).  fn is
// sent as its source text (no closures, as for page.evaluate); arg as JSON.
export async function pageArray(page, fn, arg) {
  const [type, b64] = await page.evaluate(`(async () => {
    const a = await (${fn.toString()})(${JSON.stringify(arg === undefined ? null : arg)});
    const u = new Uint8Array(a.buffer, a.byteOffset, a.byteLength);
    let s = '';
    for (let i = 0; i < u.length; i += 0x8000) s += String.fromCharCode.apply(null, u.subarray(i, i + 0x8000));
    return [a.constructor.name, btoa(s)];
  })()`);
  const T = { Uint8ClampedArray, Uint8Array, Int16Array, Float32Array, Float64Array }[type];
  if (!T) throw new Error('pageArray: not a typed array of a known type: ' + type);
  return new T(new Uint8Array(Buffer.from(b64, 'base64')).buffer);  // (a copy: aligned)
}

// The paint canvas's RGBA bytes.
export function canvasPixels(page, id) {
  return pageArray(page, id => {
    const c = document.getElementById(id || 'paint');
    return c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  }, id);
}

// The server's painting of view k as 8-bit RGBA (GET ...?format=png), read in the page.
export function serverPixels(page, k) {
  return pageArray(page, async k => {
    const S = window.glint.state.session;
    const r = await fetch(`/api/v1/sessions/${S.id}/views/${k}/painting?format=png`, { headers: { 'X-Glint-Token': S.token } });
    const bmp = await createImageBitmap(await r.blob(), { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
    const c = new OffscreenCanvas(bmp.width, bmp.height), g = c.getContext('2d');
    g.drawImage(bmp, 0, 0);
    return g.getImageData(0, 0, bmp.width, bmp.height).data;
  }, k);
}

// Largest difference between the page's float image of view k and the
// server's float painting (EXR).
export function floatDiff(page, k, which) {
  return page.evaluate(async ([k, which]) => {
    const S = window.glint.state.session;
    const { decodeEXR } = await import('/exr.js');
    const r = await fetch(`/api/v1/sessions/${S.id}/views/${k}/painting?format=exr`, { headers: { 'X-Glint-Token': S.token } });
    const im = await decodeEXR(await r.arrayBuffer());
    const mine = S.views[k][which || 'disp'];
    let mx = 0;
    for (let i = 0; i < im.data.length; i++) mx = Math.max(mx, Math.abs(im.data[i] - mine.data[i]));
    return mx;
  }, [k, which]);
}

export function maxDiff(a, b) {
  if (a.length !== b.length) return Infinity;
  let m = 0;
  for (let i = 0; i < a.length; i++) if ((i & 3) !== 3) m = Math.max(m, Math.abs(a[i] - b[i]));
  return m;
}

// ---- the runner -------------------------------------------------------------------------------------

export async function run(tests, opts) {
  if (!fs.existsSync(CHROMIUM) || !fs.existsSync(PW)) {
    console.log(`SKIP: needs ${CHROMIUM} and tests/browser/node_modules/playwright-core (npm ci --prefix tests/browser)`);
    process.exit(77);
  }
  if (!fs.existsSync(GLINTD)) { console.log('SKIP: no glintd at ' + GLINTD); process.exit(77); }
  const { chromium } = await import(PW);
  fs.mkdirSync(ARTIFACTS, { recursive: true });
  const daemon = await new Daemon((opts && opts.daemonArgs) || []).start();
  // launch() starts Chromium on a fresh temporary profile (user-data-dir)
  // of its own, removed when the browser closes; each test's contexts are
  // fresh too (no cache, storage or cookies from another test).
  const b = await chromium.launch({
    executablePath: CHROMIUM,
    args: ['--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-component-update',
      '--disable-sync', '--no-first-run', '--disable-quic'],
  });
  let passed = 0, failed = 0;
  const only = process.env.GLINT_TEST_ONLY;
  for (const [name, fn] of Object.entries(tests)) {
    if (only && !name.includes(only)) continue;
    const contexts = [];
    const problems = [];
    const allowed = [];
    const t = {
      daemon, browser: b, name,
      allowConsole(re) { allowed.push(re); },
      async context(o) {
        const c = await b.newContext(Object.assign({ viewport: { width: 1280, height: 800 }, acceptDownloads: true }, o || {}));
        c.setDefaultTimeout(MUST_MS);
        contexts.push(c);
        c.on('page', p => watch(p));
        return c;
      },
      async page(o) { const c = await t.context(o); const p = await c.newPage(); return p; },
      async shot(page, file) { const f = path.join(ARTIFACTS, file); await page.screenshot({ path: f }); return f; },
      log: (...a) => console.log('     ', ...a),
    };
    const watch = p => {
      const tag = p.url();
      p.on('console', m => {
        if (m.type() !== 'error') return;
        const where = (m.location() && m.location().url) || '';
        const text = m.text();
        if (allowed.some(re => re.test(text) || re.test(where))) return;
        problems.push(`console error: ${text} (${where})`);
      });
      p.on('pageerror', e => problems.push(`page error: ${e.message}`));
      p.on('crash', () => problems.push('page crashed ' + tag));
    };
    const t0 = Date.now();
    try {
      await fn(t);
      if (problems.length) throw new Error(problems.join('\n'));
      console.log(`ok   ${name} (${((Date.now() - t0) / 1000).toFixed(1)} s)`);
      passed++;
    } catch (e) {
      console.log(`FAIL ${name}`);
      console.log('     ' + String(e && e.stack || e).split('\n').join('\n     '));
      if (problems.length) console.log('     also: ' + problems.join('\n     '));
      failed++;
    } finally {
      for (const c of contexts) await c.close().catch(() => {});
    }
  }
  await b.close();
  await daemon.stop();
  if (failed) console.log('glintd log: ' + daemon.logPath);
  else fs.rmSync(daemon.tmp, { recursive: true, force: true });
  console.log(`${passed} passed, ${failed} failed`);
  process.exit(failed ? 1 : 0);
}
