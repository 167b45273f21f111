// Painting in the studio: the start page, strokes with the mouse in every
// brush mode and their agreement with the server (within 1/255 on screen,
// to the float in memory), undo and redo, reload, page-load time, the
// eyedropper, keyboard, zoom and pan, a dropped photo (in a view, or over
// the surface through every view's texture coordinates), readable errors.
import {
  run, openStudio, drawStroke, settled, canvasPixels, serverPixels, floatDiff, maxDiff, pageArray, MUST_MS,
  assert, assertLE, assertGE, assertEq, waitFor, sleep, paintAllViews,
} from './harness.mjs';

async function setRange(page, id, v) {
  await page.evaluate(([id, v]) => {
    const el = document.getElementById(id);
    el.value = v;
    el.dispatchEvent(new Event('input', { bubbles: true }));
  }, [id, String(v)]);
}
async function setChecked(page, id, on) {
  if ((await page.isChecked('#' + id)) !== on) await page.click('#' + id);
}
async function setColor(page, hex) {
  await page.evaluate(hex => { const c = document.getElementById('color'); c.value = hex; c.dispatchEvent(new Event('input', { bubbles: true })); }, hex);
}
async function agree(t, page, k, what) {
  await settled(page, k);
  const local = await canvasPixels(page), server = await serverPixels(page, k);
  const d8 = maxDiff(local, server), df = await floatDiff(page, k);
  t.log(`${what}: canvas vs server ${d8}/255 per channel, floats differ by ${df.toExponential(2)}`);
  assertLE(d8, 1, what + ': canvas vs GET painting (1/255 units)');
  assertLE(df, 1e-5, what + ': float image vs the server\'s EXR');
  return local;
}

run({
  async 'start page: create a scene and a session, see the views'(t) {
    const page = await t.page();
    await page.goto(t.daemon.base + '/');
    await page.waitForSelector('#start:not(.hidden)');
    await t.shot(page, '01-start.png');
    await page.click('#shape-seg button[data-mesh="torus"]');
    await page.selectOption('#size-sel', '128');
    await page.click('#create-btn');
    await page.waitForSelector('body[data-ready="1"]', { timeout: 60000 });
    assert(/#\/session\/[0-9a-f]{32}\?token=/.test(page.url()), 'the URL is the session link: ' + page.url());
    assertEq(await page.locator('#thumbs .thumb').count(), 12, 'thumbnails');
    assertEq(await page.evaluate(() => window.glint.state.session.scene.mesh), 'torus', 'mesh');
    // painted above the raster where the scene allows: 128 -> 512
    assertEq(await page.evaluate(() => window.glint.state.session.scene.paint_scale), 4, 'paint_scale of a 128 scene');
    await page.waitForFunction(() => window.glint.state.session.views.every(v => v.state === 'ready'));
    await t.shot(page, '02-studio-empty.png');
  },

  async 'upload a mesh, make a scene of it and paint on it'(t) {
    const page = await t.page();
    await page.goto(t.daemon.base + '/');
    await page.click('#shape-seg button[data-mesh="upload"]');
    const obj = 'v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n' +
      'f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n';
    await page.setInputFiles('#mesh-file', { name: 'octahedron.obj', mimeType: 'text/plain', buffer: Buffer.from(obj) });
    await page.waitForFunction(() => /8 triangles/.test(document.getElementById('mesh-info').textContent));
    await page.selectOption('#size-sel', '128');
    await page.click('#create-btn');
    await page.waitForSelector('body[data-ready="1"]', { timeout: 60000 });
    assertEq(await page.evaluate(() => window.glint.state.session.scene.mesh), 'upload', 'a scene of the uploaded mesh');
    await drawStroke(page, [[40, 40], [90, 80]]);
    await agree(t, page, 0, 'stroke on the uploaded mesh');
  },

  async 'mouse strokes in every mode agree with the server within 1/255'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 128, height: 128 });
    const page = await t.page();
    await openStudio(page, url);
    // paint: white, soft
    await setRange(page, 'diameter', 30); await setRange(page, 'kappa', 0.08);
    await drawStroke(page, [[30, 40], [60, 50], [90, 45]]);
    await agree(t, page, 0, 'paint');
    // HDR: a red highlight above 1
    await setChecked(page, 'hdr', true);
    await page.fill('#intensity', '3.5'); await page.dispatchEvent('#intensity', 'input');
    await setColor(page, '#ff4020');
    await setRange(page, 'opacity', 0.7);
    await drawStroke(page, [[40, 80], [70, 90]]);
    await agree(t, page, 0, 'paint HDR 3.5');
    const hdrMax = await page.evaluate(() => Math.max(...window.glint.state.session.views[0].conf.data));
    assertGE(hdrMax, 2, 'the painting holds values above 1');
    // negative: removes the highlight
    await setChecked(page, 'hdr', false);
    await page.keyboard.press('n');
    await setColor(page, '#ffffff'); await setRange(page, 'opacity', 0.5);
    await drawStroke(page, [[55, 40], [58, 100]]);
    await agree(t, page, 0, 'negative color');
    await page.keyboard.press('n');
    // scale: darken by half
    await page.keyboard.press('s');
    await setRange(page, 'scale', 0.5); await setRange(page, 'opacity', 1); await setRange(page, 'kappa', 0);
    await drawStroke(page, [[20, 20], [100, 100]]);
    await agree(t, page, 0, 'scale S=0.5');
    // erase: back to the base render
    await page.keyboard.press('e');
    await setRange(page, 'diameter', 16);
    await drawStroke(page, [[30, 100], [100, 30]]);
    await agree(t, page, 0, 'erase');
    await page.keyboard.press('b');
    // a dab (a click)
    const [x, y] = [64, 64];
    const box = await page.locator('#paint').boundingBox();
    await page.mouse.click(box.x + x * box.width / 128, box.y + y * box.height / 128);
    await agree(t, page, 0, 'dab');
    await t.shot(page, '03-strokes.png');
  },

  async 'a scene painted at twice its raster: canvas, strokes, erase and a photo over the surface'(t) {
    const { url, scene } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64, paint_scale: 2 });
    assertEq(scene.paint_width, 128, 'the scene gives the painting\'s size');
    const page = await t.page();
    await openStudio(page, url);
    const size = await page.evaluate(() => [document.getElementById('paint').width, document.getElementById('paint').height]);
    assertEq(size.join('x'), '128x128', 'the canvas is the painting, not the raster');
    // strokes beyond the raster's 64 pixels, in every mode, agree with the server
    await setRange(page, 'diameter', 9); await setRange(page, 'kappa', 0.1);
    await drawStroke(page, [[70, 40], [110, 52], [118, 90]]);
    await agree(t, page, 0, '2x paint');
    await page.keyboard.press('e');
    await setRange(page, 'diameter', 6);
    await drawStroke(page, [[100, 45], [112, 70]]);
    await agree(t, page, 0, '2x erase');
    await page.keyboard.press('b');
    // a photo over the surface: every pixel of the painting is the base times the texture at its (u, v)
    await page.evaluate(async () => {
      const c = new OffscreenCanvas(64, 32), g = c.getContext('2d');
      g.fillStyle = 'rgb(255,128,64)'; g.fillRect(0, 0, 32, 32);
      g.fillStyle = 'rgb(64,128,255)'; g.fillRect(32, 0, 32, 32);
      const dt = new DataTransfer();
      dt.items.add(new File([await c.convertToBlob({ type: 'image/png' })], 'texture.png', { type: 'image/png' }));
      document.getElementById('viewport').dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
    });
    await page.waitForSelector('#photo-bar:not(.hidden)');
    await page.selectOption('#photo-place', 'surface');
    await page.waitForFunction(() => window.glint.state.photo && window.glint.state.photo.texture);
    await page.click('#photo-apply');
    await page.waitForSelector('#photo-bar.hidden', { state: 'attached', timeout: 60000 });
    await settled(page, 2);
    const res = await page.evaluate(async () => {
      const S = window.glint.state.session;
      const { decodeEXR } = await import('/exr.js');
      const get = async path => (await fetch(path, { headers: { 'X-Glint-Token': S.token } })).arrayBuffer();
      const G = await decodeEXR(await get(`/api/v1/scenes/${S.scene.id}/views/2/gbuffer.exr`), ['uv.U', 'uv.V', 'mask']);
      const B = await decodeEXR(await get(`/api/v1/scenes/${S.scene.id}/views/2/base.png?format=exr`));
      const P = await decodeEXR(await get(`/api/v1/sessions/${S.id}/views/2/painting?format=exr`));
      const A = [1, 128 / 255, 64 / 255], Bc = [64 / 255, 128 / 255, 1];
      let n = 0, worst = 0;
      // painting pixels whose raster pixel and its neighbours lie well inside one colour
      for (let y = 0; y < P.h; y++) for (let x = 0; x < P.w; x++) {
        const r = Math.floor(y / 2) * G.w + Math.floor(x / 2);
        if (!(G.data[3 * r + 2] > 0.5) || Math.abs(G.data[3 * r] - 0.5) < 0.1 || G.data[3 * r] < 0.05 || G.data[3 * r] > 0.95) continue;
        const p = y * P.w + x, col = G.data[3 * r] < 0.5 ? A : Bc;
        for (let c = 0; c < 3; c++) worst = Math.max(worst, Math.abs(P.data[3 * p + c] - B.data[3 * p + c] * col[c]));
        n++;
      }
      return { n, worst, w: P.w, bw: B.w };
    });
    t.log(`photo over the surface at 2x: ${res.n} painting pixels checked, worst ${res.worst.toExponential(2)}`);
    assertEq(res.w + 'x' + res.bw, '128x128', 'the painting and the base at the painting\'s size');
    assertGE(res.n, 500, 'pixels checked');
    assertLE(res.worst, 1e-5, 'base x texture colour');
    await t.shot(page, '03b-paint-2x.png');
  },

  async 'undo restores the canvas, redo brings the stroke back'(t) {
    const { url, session } = await t.daemon.newSession({ mesh: 'sphere', width: 128, height: 128 });
    const page = await t.page();
    await openStudio(page, url);
    await page.keyboard.press('2');           // view 1
    await page.waitForFunction(() => window.glint.state.k === 1 && window.glint.state.session.views[1].state === 'ready');
    const before = await canvasPixels(page);
    await setRange(page, 'diameter', 40);
    await drawStroke(page, [[20, 60], [110, 70]]);
    await settled(page, 1);
    const after = await canvasPixels(page);
    assertGE(maxDiff(before, after), 50, 'the stroke shows');
    await page.keyboard.press('Control+z');
    await waitFor(async () => maxDiff(await canvasPixels(page), before) === 0, 60000, 'undo on the canvas');
    await settled(page, 1);
    assertLE(maxDiff(await serverPixels(page, 1), before), 1, 'undo on the server');
    await page.keyboard.press('Control+Shift+z');
    await waitFor(async () => maxDiff(await canvasPixels(page), after) <= 1, 60000, 'redo on the canvas');
    await settled(page, 1);
    assertLE(maxDiff(await serverPixels(page, 1), after), 1, 'redo on the server');
    // two strokes, undone in reverse order
    await drawStroke(page, [[60, 10], [60, 120]]);
    await settled(page, 1);
    await page.keyboard.press('Control+z');
    await waitFor(async () => maxDiff(await canvasPixels(page), after) <= 1, 60000, 'undo the 2nd stroke');
    await page.keyboard.press('Control+z');
    await waitFor(async () => maxDiff(await canvasPixels(page), before) <= 1, 60000, 'undo the 1st stroke');
    await settled(page, 1);
    assertLE(maxDiff(await serverPixels(page, 1), before), 1, 'both undone on the server');
    // two presses at once take back two strokes (each waits for the one before)
    await drawStroke(page, [[20, 20], [100, 40]]);
    await settled(page, 1);
    await drawStroke(page, [[20, 90], [100, 110]]);
    await settled(page, 1);
    await page.keyboard.press('Control+z');
    await page.keyboard.press('Control+z');
    await waitFor(async () => maxDiff(await canvasPixels(page), before) <= 1, 60000, 'two quick undos');
    await settled(page, 1);
    assertLE(maxDiff(await serverPixels(page, 1), before), 1, 'two quick undos on the server');
    // undo of my stroke keeps someone else's later stroke on top
    await drawStroke(page, [[30, 30], [100, 100]]);
    await settled(page, 1);
    const other = { mode: 'paint', color: [0.9, 0.1, 0.1], diameter: 24, kappa: 0.02, opacity: 1, points: [[20, 100], [100, 20]] };
    await t.daemon.api('POST', `/sessions/${session.id}/views/1/strokes`, { strokes: [other] }, { 'X-Glint-Token': session.paint_token });
    await page.waitForFunction(() => window.glint.state.session.views[1].seq >= 12);
    await page.click('#undo');
    await settled(page, 1);
    // expected: the base render with only the other person's stroke
    const expected = await pageArray(page, async other => {
      const { applyStroke } = await import('/brush.js');
      const { cloneImage, to8 } = await import('/image.js');
      const v = window.glint.state.session.views[1];
      const im = cloneImage(v.base);
      applyStroke(other, im, v.base);
      const out = [];
      for (let i = 0; i < im.w * im.h; i++) out.push(to8(im.data[3 * i]), to8(im.data[3 * i + 1]), to8(im.data[3 * i + 2]), 255);
      return new Float64Array(out);
    }, other);
    await waitFor(async () => maxDiff(await canvasPixels(page), expected) <= 1, 60000, 'undo under a later stroke');
    assertLE(maxDiff(await serverPixels(page, 1), expected), 1, 'the server agrees');
    await t.shot(page, '04-undo.png');
  },

  async 'reload keeps the paintings and the view'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'torus', width: 128, height: 128 });
    const page = await t.page();
    await openStudio(page, url);
    await page.keyboard.press('4');
    await page.waitForFunction(() => window.glint.state.k === 3 && window.glint.state.session.views[3].state === 'ready');
    await drawStroke(page, [[20, 20], [100, 40], [60, 110]]);
    await settled(page, 3);
    await page.keyboard.press('ArrowLeft');
    await page.waitForFunction(() => window.glint.state.k === 2 && window.glint.state.session.views[2].state === 'ready');
    await drawStroke(page, [[30, 60], [90, 60]]);
    await settled(page, 2);
    const v2 = await canvasPixels(page);
    await page.reload();
    await page.waitForSelector('body[data-ready="1"]');
    assertEq(await page.evaluate(() => window.glint.state.k), 2, 'the view after reload');
    assertEq(maxDiff(await canvasPixels(page), v2), 0, 'view 2 after reload');
    await page.keyboard.press('ArrowRight');
    await page.waitForFunction(() => window.glint.state.k === 3 && window.glint.state.session.views[3].state === 'ready');
    assertLE(maxDiff(await canvasPixels(page), await serverPixels(page, 3)), 1, 'view 3 after reload');
    await page.waitForFunction(() => document.querySelectorAll('#thumbs .thumb.painted').length === 2);
  },

  async 'a warm reload takes the studio\'s files from the cache and opens paintable'(t) {
    // (how long a cold and a warm load take: tests/bench/bench_studio.mjs)
    const { url } = await t.daemon.newSession({ mesh: 'teapot', width: 256, height: 256 });
    const page = await t.page();
    const cdp = await page.context().newCDPSession(page);
    await cdp.send('Network.enable');
    // the studio's own files (not the API) that the page loaded, and those
    // the browser's cache answered without asking glintd
    let loaded = [];
    const fromCache = new Set();
    cdp.on('Network.requestServedFromCache', e => fromCache.add(e.requestId));
    // the studio's files still on their way: a module imported after the
    // page is ready (summary.js, ball.js) must be in the cache before a
    // reload can find it there
    const pending = new Set();
    cdp.on('Network.requestWillBeSent', e => {
      const u = new URL(e.request.url);
      if (u.origin === t.daemon.base && !u.pathname.startsWith('/api/')) pending.add(e.requestId);
    });
    cdp.on('Network.loadingFinished', e => pending.delete(e.requestId));
    cdp.on('Network.loadingFailed', e => pending.delete(e.requestId));
    const filesLoaded = () => waitFor(() => pending.size === 0, MUST_MS, 'the studio\'s files loaded');
    cdp.on('Network.responseReceived', e => {
      const u = new URL(e.response.url);
      if (u.origin === t.daemon.base && !u.pathname.startsWith('/api/')) loaded.push({ id: e.requestId, path: u.pathname });
    });
    // how glintd answered each of them (its log: "GET /app.js 304 0.05ms"),
    // once every one asked is there
    const answers = async from => {
      const asked = loaded.filter(f => !fromCache.has(f.id)).map(f => f.path);
      let got;
      await waitFor(() => {
        got = new Map();
        for (const m of t.daemon.log().slice(from).matchAll(/^GET (\/[^ ?]*)\S* (\d{3}) /gm)) if (!m[1].startsWith('/api/')) got.set(m[1], +m[2]);
        return asked.every(p => got.has(p));
      }, MUST_MS, 'glintd\'s log lines of the files');
      return { cached: loaded.length - asked.length, asked: asked.map(p => [p, got.get(p)]) };
    };
    let from = t.daemon.log().length;
    await openStudio(page, url);
    const cold = await answers(from);
    await filesLoaded();
    assert(cold.asked.length >= 10 && cold.asked.every(f => f[1] === 200), 'a cold load downloads the files: ' + JSON.stringify(cold));
    for (let i = 0; i < 2; i++) {
      loaded = [];
      from = t.daemon.log().length;
      await page.reload();
      await page.waitForSelector('body[data-ready="1"]');
      const warm = await answers(from);
      await filesLoaded();
      assert(warm.cached + warm.asked.length >= 10, 'the files before the first paintable view: ' + JSON.stringify(warm));
      const again = warm.asked.filter(f => f[1] !== 304);
      assertEq(again.length, 0, 'files sent again on a warm reload (not 304, not from the cache): ' + JSON.stringify(again));
    }
    // and it is paintable: a stroke goes through
    await drawStroke(page, [[100, 100], [150, 120]]);
    await settled(page, 0);
  },

  async 'eyedropper, brush-size keys, view keys, zoom and pan'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const page = await t.page();
    await openStudio(page, url);
    // eyedropper on an HDR dab
    await setChecked(page, 'hdr', true);
    await page.fill('#intensity', '2'); await page.dispatchEvent('#intensity', 'input');
    await setColor(page, '#80ff40'); await setRange(page, 'kappa', 0); await setRange(page, 'diameter', 20);
    await drawStroke(page, [[48, 48], [50, 48]]);
    await settled(page, 0);
    await setChecked(page, 'hdr', false); await setColor(page, '#000000');
    await page.keyboard.press('i');
    const box = await page.locator('#paint').boundingBox();
    await page.mouse.click(box.x + 49 * box.width / 96, box.y + 48.5 * box.height / 96);
    assertEq(await page.inputValue('#color'), '#80ff40', 'picked color');
    assert(await page.isChecked('#hdr'), 'picked HDR value turns HDR on');
    assertLE(Math.abs(+await page.inputValue('#intensity') - 2), 1e-3, 'picked intensity');
    assertEq(await page.evaluate(() => window.glint.state.tool), 'paint', 'back to paint after picking');
    // [ and ]
    const d0 = +await page.inputValue('#diameter');
    await page.keyboard.press(']'); await page.keyboard.press(']');
    const d1 = +await page.inputValue('#diameter');
    await page.keyboard.press('[');
    const d2 = +await page.inputValue('#diameter');
    assert(d1 > d0 && d2 < d1, `diameter keys: ${d0} -> ${d1} -> ${d2}`);
    // views
    await page.keyboard.press('7');
    await page.waitForFunction(() => window.glint.state.k === 6);
    await page.keyboard.press('ArrowRight');
    await page.waitForFunction(() => window.glint.state.k === 7);
    // zoom and pan
    const z0 = await page.evaluate(() => window.glint.state.painter.zoom);
    await page.keyboard.press('+');
    const z1 = await page.evaluate(() => window.glint.state.painter.zoom);
    assertGE(z1, z0 * 1.2, 'zoom in');
    await page.mouse.move(box.x + 10, box.y + 10);
    await page.mouse.wheel(0, 300);
    const z2 = await page.evaluate(() => window.glint.state.painter.zoom);
    assert(z2 < z1, 'wheel zooms out');
    const p0 = await page.evaluate(() => [window.glint.state.painter.panX, window.glint.state.painter.panY]);
    await page.keyboard.down(' ');
    await page.mouse.move(box.x + 50, box.y + 50);
    await page.mouse.down(); await page.mouse.move(box.x + 120, box.y + 90, { steps: 4 }); await page.mouse.up();
    await page.keyboard.up(' ');
    const p1 = await page.evaluate(() => [window.glint.state.painter.panX, window.glint.state.painter.panY]);
    assertLE(Math.abs(p1[0] - p0[0] - 70) + Math.abs(p1[1] - p0[1] - 40), 2, 'space-drag pans by the drag');
    const seq = await page.evaluate(() => window.glint.state.session.appliedSeq);
    assertEq(seq, 1, 'panning painted nothing');
    await page.keyboard.press('0');
    await page.keyboard.press('?');
    await page.waitForSelector('#help-dlg:not(.hidden)');
    await t.shot(page, '05-keyboard-help.png');
    await page.keyboard.press('Escape');
  },

  async 'a dropped photo becomes the painting, compared with the base first'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 128, height: 128 });
    const page = await t.page();
    await openStudio(page, url);
    // a 200x150 "photo": a gradient with a bright spot
    await page.evaluate(async () => {
      const c = new OffscreenCanvas(200, 150), g = c.getContext('2d');
      const gr = g.createLinearGradient(0, 0, 200, 0); gr.addColorStop(0, '#203040'); gr.addColorStop(1, '#c0a080');
      g.fillStyle = gr; g.fillRect(0, 0, 200, 150);
      g.fillStyle = '#fff'; g.beginPath(); g.arc(120, 60, 20, 0, 7); g.fill();
      const blob = await c.convertToBlob({ type: 'image/png' });
      const dt = new DataTransfer();
      dt.items.add(new File([blob], 'photo.png', { type: 'image/png' }));
      const vp = document.getElementById('viewport');
      vp.dispatchEvent(new DragEvent('dragover', { dataTransfer: dt, bubbles: true, cancelable: true }));
      vp.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
    });
    await page.waitForSelector('#photo-bar:not(.hidden)');
    await setRange(page, 'photo-opacity', 0.6);
    await page.selectOption('#photo-fit', 'cover');
    await t.shot(page, '06-photo-compare.png');
    const staged = await pageArray(page, () => {
      const im = window.glint.state.photo.image, out = [];
      for (let i = 0; i < im.w * im.h; i++) out.push(...[0, 1, 2].map(c => Math.round(im.data[3 * i + c] * 255)), 255);
      return new Float64Array(out);
    });
    await page.click('#photo-apply');
    await page.waitForSelector('#photo-bar.hidden', { state: 'attached' });
    await settled(page, 0);
    assertLE(maxDiff(await serverPixels(page, 0), staged), 1, 'the server has the photo');
    assertLE(maxDiff(await canvasPixels(page), staged), 1, 'the canvas shows the photo');
    // undo brings the base render back
    await page.keyboard.press('Control+z');
    await settled(page, 0);
    const base = await page.evaluate(() => { const v = window.glint.state.session.views[0]; return Array.from(v.conf.data.slice(0, 300)).map((x, i) => x - v.base.data[i]); });
    assertLE(Math.max(...base.map(Math.abs)), 0, 'undo of the photo');
  },

  async 'a photo placed over the surface paints every view through its texture coordinates'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const page = await t.page();
    await openStudio(page, url);
    // a 64x32 texture: u < 1/2 orange, u >= 1/2 blue (8-bit values, read linearly)
    await page.evaluate(async () => {
      const c = new OffscreenCanvas(64, 32), g = c.getContext('2d');
      g.fillStyle = 'rgb(255,128,64)'; g.fillRect(0, 0, 32, 32);
      g.fillStyle = 'rgb(64,128,255)'; g.fillRect(32, 0, 32, 32);
      const blob = await c.convertToBlob({ type: 'image/png' });
      const dt = new DataTransfer();
      dt.items.add(new File([blob], 'texture.png', { type: 'image/png' }));
      const vp = document.getElementById('viewport');
      vp.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
    });
    await page.waitForSelector('#photo-bar:not(.hidden)');
    // "over the surface", and "Use as painting" in the same task, while the
    // preview over the surface is still being rendered: view 0 must not
    // take the flat photo's preview
    await page.evaluate(() => {
      const place = document.getElementById('photo-place');
      place.value = 'surface';
      place.dispatchEvent(new Event('change'));
      document.getElementById('photo-apply').click();
    });
    await page.waitForSelector('#photo-bar.hidden', { state: 'attached', timeout: 60000 });
    await t.shot(page, '06b-texture-over-surface.png');
    const nviews = await page.evaluate(() => window.glint.state.session.views.length);
    let checked = 0;
    for (const k of [0, 5, nviews - 1]) {
      await settled(page, k);
      // expected, from the view's G-buffer and base render read here: base x colour(u)
      const res = await page.evaluate(async k => {
        const S = window.glint.state.session;
        const { decodeEXR } = await import('/exr.js');
        const get = async path => (await fetch(path, { headers: { 'X-Glint-Token': S.token } })).arrayBuffer();
        const G = await decodeEXR(await get(`/api/v1/scenes/${S.scene.id}/views/${k}/gbuffer.exr`), ['uv.U', 'uv.V', 'mask']);
        const B = await decodeEXR(await get(`/api/v1/scenes/${S.scene.id}/views/${k}/base.png?format=exr`));
        const P = await decodeEXR(await get(`/api/v1/sessions/${S.id}/views/${k}/painting?format=exr`));
        const A = [255 / 255, 128 / 255, 64 / 255], Bc = [64 / 255, 128 / 255, 255 / 255];
        let n = 0, worst = 0, off = 0;
        for (let p = 0; p < G.w * G.h; p++) {
          const on = G.data[3 * p + 2] > 0.5, u = G.data[3 * p];
          for (let c = 0; c < 3; c++) {
            if (!on) { off = Math.max(off, Math.abs(P.data[3 * p + c] - B.data[3 * p + c])); continue; }
            if (Math.abs(u - 0.5) < 0.05) continue;          // the blend across the edge
            const want = B.data[3 * p + c] * (u < 0.5 ? A : Bc)[c];
            worst = Math.max(worst, Math.abs(P.data[3 * p + c] - want));
          }
          if (on && Math.abs(u - 0.5) >= 0.05) n++;
        }
        return { n, worst, off };
      }, k);
      t.log(`view ${k}: ${res.n} surface pixels, |painting - base x texture| <= ${res.worst.toExponential(2)}, off the surface <= ${res.off}`);
      assertGE(res.n, 100, 'the surface covers the view');
      assertLE(res.worst, 1e-5, `view ${k} is its base render tinted by the texture`);
      assertLE(res.off, 0, `view ${k} keeps the base render off the surface`);
      checked++;
    }
    assertEq(checked, 3, 'three views checked');
    // each view is one undo step of its own
    await page.evaluate(() => window.glint.selectView ? window.glint.selectView(0) : null);
    assert(await page.evaluate(() => window.glint.state.session.canUndo(0)), 'view 0 can undo the texture');
  },

  async 'a finish to start from paints every view with the server\'s render of it'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const page = await t.page();
    await openStudio(page, url);
    await page.selectOption('#preset-sel', 'satin');
    await page.evaluate(() => { const c = document.getElementById('preset-colour'); c.value = '#336699'; c.dispatchEvent(new Event('input', { bubbles: true })); });
    const note = await page.textContent('#preset-note');
    assert(/stretched/.test(note), 'the finish is described: ' + note);
    await paintAllViews(page);
    await t.shot(page, '06c-finish-satin.png');
    const nviews = await page.evaluate(() => window.glint.state.session.views.length);
    for (const k of [0, nviews - 1]) {
      await settled(page, k);
      // the painting is the server's render of the satin spec with kd from the colour
      const d = await page.evaluate(async k => {
        const S = window.glint.state.session;
        const { decodeEXR } = await import('/exr.js');
        const get = async path => (await fetch(path, { headers: { 'X-Glint-Token': S.token } })).arrayBuffer();
        // the scene's lighting and scale, as the studio asks for them
        const { presetQuery } = await import('/presets.js');
        const q = new URLSearchParams(presetQuery(S.scene, 'ward:kd=0.2/0.4/0.6,ks=0.4,rough=0.08,rough_y=0.3'));
        const want = await decodeEXR(await get(`/api/v1/scenes/${S.scene.id}/views/${k}/base.png?${q}`));
        const got = await decodeEXR(await get(`/api/v1/sessions/${S.id}/views/${k}/painting?format=exr`));
        const base = await decodeEXR(await get(`/api/v1/scenes/${S.scene.id}/views/${k}/base.png?format=exr`));
        let mx = 0, changed = 0;
        for (let i = 0; i < got.data.length; i++) {
          mx = Math.max(mx, Math.abs(got.data[i] - want.data[i]));
          changed = Math.max(changed, Math.abs(got.data[i] - base.data[i]));
        }
        return { mx, changed };
      }, k);
      t.log(`view ${k}: |painting - render of the finish| <= ${d.mx}, differs from the base render by up to ${d.changed.toFixed(3)}`);
      assertLE(d.mx, 0, `view ${k} is the server's render of the finish`);
      assertGE(d.changed, 0.05, `view ${k} is not the base render`);
    }
    assert(await page.evaluate(() => window.glint.state.session.canUndo(0)), 'each view can undo the finish');
  },

  async 'the toolbar keeps one row and the Fit button shows at 1280x720 and 1440x900'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const page = await t.page();
    for (const [w, h] of [[1280, 720], [1440, 900]]) {
      await page.setViewportSize({ width: w, height: h });
      await openStudio(page, url);
      for (const tool of ['paint', 'hdr', 'scale']) {
        if (tool === 'hdr') {
          await setChecked(page, 'hdr', true);  // its intensity field appears
        } else {
          if (tool === 'scale') await setChecked(page, 'hdr', false);
          await page.click(`#tools button[data-tool="${tool}"]`);
        }
        const rows = await page.evaluate(() => {
          const tops = new Set();
          for (const el of document.getElementById('toolbar').children) {
            const r = el.getBoundingClientRect();
            if (r.width > 0 && r.height > 0) tops.add(Math.round(r.top + r.height / 2));
          }
          return [...tops];
        });
        const widths = await page.evaluate(() => [...document.getElementById('toolbar').children].map(el => `${el.id || el.className}:${Math.round(el.getBoundingClientRect().width)}`).join(' ') + ' of ' + Math.round(document.getElementById('toolbar').getBoundingClientRect().width));
        t.log(`${w}x${h}, ${tool}: toolbar item centres at ${rows.join(', ')} px (${widths})`);
        assertLE(Math.max(...rows) - Math.min(...rows), 4, `${w}x${h} ${tool}: one toolbar row`);
      }
      await page.click('#tools button[data-tool="paint"]');
      const fitBox = await page.locator('#fit-btn').boundingBox();
      assert(fitBox && fitBox.y + fitBox.height <= h, `${w}x${h}: the Fit button is above the fold`);
      await t.shot(page, `00-layout-${w}x${h}.png`);
    }
  },

  async 'server refusals are shown with their problem detail'(t) {
    t.allowConsole(/status of 422/);
    const page = await t.page();
    await page.goto(t.daemon.base + '/');
    await page.click('#shape-seg button[data-mesh="upload"]');
    await page.setInputFiles('#mesh-file', { name: 'broken.ply', mimeType: 'application/octet-stream', buffer: Buffer.from('ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n') });
    const toast = page.locator('.toast.error').first();
    await toast.waitFor({ timeout: 60000 });
    const text = await toast.innerText();
    t.log('toast: ' + text.replace(/\s+/g, ' ').slice(0, 160));
    assert(/422/.test(text) && /Uploading the mesh/.test(text), 'the toast names the action and the status');
    const err = await page.evaluate(() => window.glint.errors[window.glint.errors.length - 1]);
    assert(err.detail && text.includes(err.detail.slice(0, 40)), 'the toast shows the server\'s detail: ' + err.detail);
    await t.shot(page, '07-error.png');
  },
});
