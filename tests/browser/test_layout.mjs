// The studio's layout and words at 1280x720, as a newcomer first sees it:
// the first-visit guide open beside the painting (never over the paint
// canvas: boxes compared and elementFromPoint checked over the canvas), the
// method choice by labels with no method name in its visible text and
// inside its panel, the brush sliders labelled in words, the technical
// parameters behind an "advanced" disclosure, uploads of the same file name
// told apart, errors as percentages, and the polar plot's angle labels;
// then at a device pixel ratio of 2.5 (a browser zoom of 250%), the paint
// canvas drawn with whole device pixels per image pixel (the fix for
// stair-stepped edges) and smoothed where that cannot be.
import {
  run, openStudio, drawStroke, settled, assert, assertLE, assertEq, MUST_MS,
} from './harness.mjs';

async function setValue(page, id, v) {
  await page.evaluate(([id, v]) => { const el = document.getElementById(id); el.value = v; el.dispatchEvent(new Event('change', { bubbles: true })); }, [id, String(v)]);
}

async function fit(page) {
  const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
  await page.waitForSelector('#quality .q[data-preset]');
  await page.click('#fit-btn');
  await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: MUST_MS });
  return page.evaluate(() => window.glint.lastFit);
}

// Whether text names a method: its name as a word ("hf3", "(srbf)").
function namesMethod(text, names) {
  return names.filter(n => new RegExp(`(^|[^A-Za-z0-9_])${n}([^A-Za-z0-9_]|$)`).test(text));
}

run({
  async '1280x720 with the guide open: canvas uncovered, plain words, method choice inside its panel, labelled brush'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const page = await t.page({ viewport: { width: 1280, height: 720 } });
    await openStudio(page, url);
    assert(await page.isVisible('#guide'), 'the guide is open on a first visit');
    await page.waitForFunction(() => document.getElementById('guide-methods').textContent.length > 0);
    await page.waitForSelector('#quality .q[data-preset]');
    await t.shot(page, '50-layout-1280x720-guide.png');

    // the guide and the paint canvas: disjoint boxes, and every point of the
    // canvas that the painting area shows is the canvas itself
    const g = await page.locator('#guide').boundingBox(), c = await page.locator('#paint').boundingBox();
    const ox = Math.max(0, Math.min(g.x + g.width, c.x + c.width) - Math.max(g.x, c.x));
    const oy = Math.max(0, Math.min(g.y + g.height, c.y + c.height) - Math.max(g.y, c.y));
    t.log(`guide ${JSON.stringify(g)}; canvas ${JSON.stringify(c)}`);
    assertEq(ox * oy, 0, 'the guide and the canvas overlap (px²)');
    const hits = await page.evaluate(() => {
      const c = document.getElementById('paint').getBoundingClientRect(), v = document.getElementById('viewport').getBoundingClientRect();
      const x0 = Math.max(c.left, v.left) + 1, x1 = Math.min(c.right, v.right) - 1, y0 = Math.max(c.top, v.top) + 1, y1 = Math.min(c.bottom, v.bottom) - 1;
      const out = { n: 0, other: [], area: (x1 - x0) * (y1 - y0) / (c.width * c.height) };
      for (let i = 0; i <= 12; i++) for (let j = 0; j <= 12; j++) {
        const el = document.elementFromPoint(x0 + (x1 - x0) * i / 12, y0 + (y1 - y0) * j / 12);
        out.n++;
        if (!el || el.id !== 'paint') out.other.push(el ? el.id || el.tagName : 'nothing');
      }
      return out;
    });
    assertEq(hits.other.join(','), '', `points over the canvas that are not the canvas (of ${hits.n})`);
    assert(hits.area > 0.95, 'the painting area shows the whole canvas: ' + hits.area);
    // strokes reach the canvas with the guide open
    await drawStroke(page, [[10, 30], [50, 36]]);
    await settled(page, 0);

    // the method choice: labels only, no method name in what is shown
    const api = (await t.daemon.api('GET', '/methods')).methods;
    const names = api.map(m => m.name);
    const shown = await page.evaluate(() => {
      const sel = document.getElementById('fit-method');
      return { options: [...sel.options].map(o => o.textContent), note: document.getElementById('method-note').innerText,
               guide: document.getElementById('guide-methods').innerText, panel: document.getElementById('fit-panel').innerText };
    });
    for (const o of shown.options) assertEq(namesMethod(o, names).join(','), '', `method names in the option "${o}"`);
    assertEq(namesMethod(shown.guide, names).join(','), '', 'method names in the guide: ' + shown.guide);
    assertEq(namesMethod(shown.panel, names).join(','), '', 'method names in the fit panel\'s visible text: ' + shown.panel);
    assertEq(shown.options.join(' | '), api.map(m => m.label).join(' | '), 'every method by its label');
    // its technical names wait behind the advanced disclosure
    await page.click('#advanced > summary');
    await page.click('#method-tech > summary');
    const tech = await page.textContent('#method-tech');
    assert(namesMethod(tech, names).length === 1, 'the advanced part names the method: ' + tech);

    // the method dropdown inside its panel, with the longest label chosen
    const longest = api.filter(m => m.lighting === 'point').sort((a, b) => b.label.length - a.label.length)[0];
    await setValue(page, 'fit-method', longest.name);
    const edge = await page.evaluate(() => {
      const s = document.getElementById('fit-method').getBoundingClientRect(), p = document.getElementById('right');
      const pr = p.getBoundingClientRect();
      return { right: s.right, left: s.left, panelRight: pr.left + p.clientLeft + p.clientWidth, panelLeft: pr.left };
    });
    t.log(`method dropdown ${edge.left.toFixed(1)}..${edge.right.toFixed(1)}, panel ${edge.panelLeft.toFixed(1)}..${edge.panelRight.toFixed(1)}`);
    assertLE(edge.right, edge.panelRight, 'the method dropdown\'s right edge');

    // parameters: basic ones by plain names, advanced ones behind their own disclosure
    await setValue(page, 'fit-method', 'hf3');
    const params = await page.evaluate(() => {
      const box = document.getElementById('params'), adv = document.getElementById('params-advanced');
      const basic = [...box.querySelectorAll(':scope > label')].map(l => l.textContent);
      const inAdv = adv ? [...adv.querySelectorAll('label')].map(l => l.htmlFor.replace(/^param-/, '')) : [];
      return { basic, inAdv, advOpen: adv ? adv.open : null };
    });
    const hf3 = api.find(m => m.name === 'hf3');
    const advNames = hf3.params.filter(p => p.group === 'advanced').map(p => p.name);
    assertEq(params.inAdv.join(','), advNames.join(','), 'the advanced parameters are behind the disclosure');
    assertEq(params.advOpen, false, 'the advanced disclosure starts closed');
    assertEq(params.basic.join(','), hf3.params.filter(p => p.group !== 'advanced').map(p => p.label).join(','), 'basic parameters by their labels');
    for (const l of params.basic) assert(!/[_(]|texel|factor|lobe|sigma/.test(l), 'a basic parameter in plain words: ' + l);

    // the brush sliders in words, with tooltips
    const brush = await page.evaluate(() => ['diameter', 'kappa', 'opacity', 'scale'].map(id => {
      const l = document.getElementById(id).closest('label');
      return { id, text: l.querySelector('span').textContent, title: l.title };
    }));
    assertEq(brush.map(b => b.text).join(','), 'size,softness,opacity,strength', 'the brush sliders\' labels');
    for (const b of brush) assert(b.title.length > 30, `${b.id} has a tooltip`);
    const tb = await page.evaluate(() => {
      const tops = new Set();
      for (const el of document.getElementById('toolbar').children) {
        const r = el.getBoundingClientRect();
        if (r.width > 0 && r.height > 0) tops.add(Math.round(r.top + r.height / 2));
      }
      return Math.max(...tops) - Math.min(...tops);
    });
    assertLE(tb, 4, 'the toolbar keeps one row with the sliders labelled');

    // three uploads of one file name: three entries told apart
    await setValue(page, 'fit-method', 'srbf');
    const w = 32, h = 16, px = Buffer.alloc(4 * w * h);
    for (let i = 0; i < w * h; i++) px.set([128, 128, 140, 128], 4 * i);
    const hdr = Buffer.concat([Buffer.from(`#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y ${h} +X ${w}\n`), px]);
    for (let i = 0; i < 3; i++) {
      const before = await page.evaluate(() => document.getElementById('param-env').options.length);
      await page.setInputFiles('#env-file', { name: 'my_loft.hdr', mimeType: 'application/octet-stream', buffer: hdr });
      await page.waitForFunction(b => document.getElementById('param-env').options.length > b, before, { timeout: MUST_MS });
    }
    const lofts = await page.evaluate(() => [...document.getElementById('param-env').options].filter(o => o.textContent.startsWith('my_loft')).map(o => o.textContent));
    assertEq(lofts.join(' | '), 'my_loft.hdr | my_loft.hdr (2) | my_loft.hdr (3)', 'uploads of one name told apart');
    const previewLofts = await page.evaluate(() => [...document.getElementById('preview-light').options].filter(o => o.textContent.startsWith('my_loft')).map(o => o.textContent));
    assertEq(new Set(previewLofts).size, 3, 'the previews tell them apart too: ' + previewLofts);

    // a fit: its error as a percentage with its meaning, RMS behind "advanced"
    await setValue(page, 'fit-method', 'hf3');
    const f = await fit(page);
    await page.waitForFunction(() => /%/.test(document.getElementById('err-meaning') ? document.getElementById('err-meaning').textContent : '')
      && document.querySelector('#err-table tbody td:nth-child(2)') && /%/.test(document.querySelector('#err-table tbody td:nth-child(2)').textContent), null, { timeout: MUST_MS });
    const words = await page.evaluate(() => ({
      result: document.getElementById('fit-result').innerText, meaning: document.getElementById('err-meaning').textContent,
      summary: document.getElementById('err-summary').innerText, head: document.querySelector('#err-table thead').innerText,
    }));
    t.log(`fit ${f.id.slice(0, 8)}: "${words.result}"; "${words.meaning}"`);
    assert(/\d%/.test(words.result), 'the fit result gives the error as a percentage: ' + words.result);
    assert(/^[\d.]+% — the fitted material differs from your painting by about/.test(words.meaning), 'the error\'s meaning: ' + words.meaning);
    assert(!/RMS|samples/.test(words.summary) && !/RMS/.test(words.head), 'no RMS or sample counts in sight: ' + words.summary + ' / ' + words.head);
    assert(/RMS/.test(await page.textContent('#err-advanced')), 'the RMS is behind the advanced disclosure');
    // the percentage is the RMS over the painting's brightness (from the view's pixels, computed here)
    const check = await page.evaluate(() => {
      const J = window.glint.state.judge, [k, r] = [...J.rows.entries()][0];
      const p = r.painted.data, b = window.glint.state.session.views[k].base;
      let s2 = 0, n = 0;
      for (let i = 0; i < p.length; i += 3) if (b.data[i] > 0 || b.data[i + 1] > 0 || b.data[i + 2] > 0) { s2 += p[i] ** 2 + p[i + 1] ** 2 + p[i + 2] ** 2; n += 3; }
      return { shown: document.querySelector(`#err-table tr[data-view="${k}"] td:nth-child(2)`).textContent, rms: r.rms, level: Math.sqrt(s2 / n) };
    });
    const want = 100 * check.rms / check.level;
    t.log(`view error shown "${check.shown}", RMS ${check.rms.toFixed(4)} / brightness ${check.level.toFixed(4)} = ${want.toFixed(3)}%`);
    assertLE(Math.abs(parseFloat(check.shown) - want), Math.max(0.05, 0.051 * want), 'the view\'s percentage');

    // the polar plot: angle labels drawn at 0, 30, 60, 90 degrees each side, and none between
    await page.click('.tabs button[data-tab="summary"]');
    await page.waitForFunction(() => window.glint.state.judge.summary, null, { timeout: MUST_MS });
    const polar = await page.evaluate(async () => {
      const { polarLayout } = await import('/summary.js');
      const c = document.getElementById('sum-polar'), g = c.getContext('2d'), L = polarLayout(c.width, c.height);
      const ink = (x, y) => {          // pixels of the label colour in a 14x10 box
        const d = g.getImageData(Math.round(x - 7), Math.round(y - 5), 14, 10).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) if (d[i + 3] > 60) n++;
        return n;
      };
      const between = L.ticks.filter(t => t.deg > 0 && t.deg < 90).map(t => {
        const a = (t.deg + 15) * Math.PI / 180;
        return ink(L.cx + (L.R + 11) * Math.sin(a), L.cy - (L.R + 9) * Math.cos(a));
      });
      return { ticks: L.ticks.map(t => ({ text: t.text, x: t.x, y: t.y, n: ink(t.x, t.y) })), between, w: c.width, h: c.height, title: c.title };
    });
    t.log('polar labels: ' + polar.ticks.map(x => `${x.text} ${x.n}px`).join(', ') + `; between them ${polar.between.join(', ')}px`);
    assertEq([...new Set(polar.ticks.map(x => x.text))].join(','), '90°,60°,30°,0°', 'the angles labelled');
    for (const x of polar.ticks) {
      assert(x.x >= 4 && x.x <= polar.w - 4 && x.y >= 4 && x.y <= polar.h - 4, `${x.text} inside the plot`);
      assert(x.n >= 6, `the label ${x.text} is drawn`);
    }
    for (const n of polar.between) assertEq(n, 0, 'nothing drawn between the labels');
    assert(!/f \(luminance\)/.test(polar.title) && /bright/.test(polar.title), 'the plot explained in words');
    await t.shot(page, '51-layout-numbers.png');
  },

  async 'at a device pixel ratio of 2.5 the paint canvas is drawn in whole device pixels'(t) {
    // painted at 512 a side: the window fits it at under one CSS pixel per image pixel
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 128, height: 128, paint_scale: 4 });
    const page = await t.page({ viewport: { width: 1280, height: 720 }, deviceScaleFactor: 2.5 });
    await openStudio(page, url);
    const at = () => page.evaluate(() => {
      const c = document.getElementById('paint'), r = c.getBoundingClientRect(), cur = document.getElementById('cursor');
      const vp = document.getElementById('viewport').getBoundingClientRect();
      return { dpr: devicePixelRatio, zoom: window.glint.state.painter.zoom, w: c.width, cssW: r.width, left: r.left, top: r.top,
               rendering: getComputedStyle(c).imageRendering, cursorW: cur.width, vpW: vp.width };
    });
    const a = await at();
    const k = a.cssW * a.dpr / a.w;
    t.log(`dpr ${a.dpr}: zoom ${a.zoom}, ${a.w} image px shown ${a.cssW} CSS px = ${k} device px each, at (${a.left}, ${a.top}); ${a.rendering}`);
    assertEq(a.dpr, 2.5, 'the page\'s device pixel ratio');
    assertLE(Math.abs(k - Math.round(k)), 1e-6, 'whole device pixels per image pixel');
    assert(Math.round(k) >= 1, 'at least one device pixel per image pixel');
    for (const v of [a.left, a.top]) assertLE(Math.abs(v * a.dpr - Math.round(v * a.dpr)), 1e-3, 'the canvas starts on a device pixel');
    assertEq(a.rendering, 'pixelated', 'drawn as equal blocks');
    assertLE(Math.abs(a.cursorW - Math.round(a.vpW * a.dpr)), 1, 'the brush cursor\'s canvas is in device pixels');
    // a zoom that gives uneven blocks is smoothed instead
    await page.click('#zoom-in');
    const b = await at();
    const kb = b.cssW * b.dpr / b.w;
    t.log(`zoomed in: ${kb.toFixed(3)} device px per image px; ${b.rendering}`);
    assert(Math.abs(kb - Math.round(kb)) > 1e-3, 'the zoom step gives a fractional size');
    assertEq(b.rendering, 'auto', 'smoothed at a fractional size');
    await page.click('#zoom-fit');
    assertEq((await at()).rendering, 'pixelated', 'fitting to the window again: equal blocks');
  },
});
