// The environment-lit method in the studio: choosing it, its environment
// from those glintd offers, a fit, the preview under the fit's environment
// (turned by a slider or a drag), the lobe p(h) and the energy profile, the
// error per view against a render under the environment, and the point
// light still available for any material; pbr_tab_env chosen, fitted,
// previewed and shown on the ball.
import {
  run, openStudio, drawStroke, settled, assert, assertLE, assertEq, waitFor, pageArray,
} from './harness.mjs';

async function setValue(page, id, v, ev) {
  await page.evaluate(([id, v, ev]) => {
    const el = document.getElementById(id); el.value = v; el.dispatchEvent(new Event(ev, { bubbles: true }));
  }, [id, String(v), ev || 'input']);
}

function previewBytes(page) {
  return pageArray(page, () => document.getElementById('preview').getContext('2d').getImageData(0, 0, 256, 256).data);
}

run({
  async 'a scene painted under an environment: chosen on the start page, fitted under it'(t) {
    const page = await t.page();
    await page.goto(t.daemon.base + '/#/');
    await page.waitForFunction(() => [...document.getElementById('base-light-sel').options].some(o => o.value === 'sky'), null, { timeout: 60000 });
    const { scene, url } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64, base: { env: { spec: 'sky', rotation: 30, lights: 32 } } });
    assertEq(scene.base.env.spec, 'sky', 'the scene keeps its environment');
    await openStudio(page, url);
    await page.waitForSelector('#param-env', { state: 'attached' });
    assertEq(await page.inputValue('#fit-method'), 'pbr_env', 'the first environment method (physically based) is chosen');
    assert(await page.evaluate(() => document.querySelector('#fit-method option[value="hf3"]').disabled),
      'a method lit by point lights is offered but not choosable (the daemon refuses it: lighting-mismatch)');
    assertEq(await page.inputValue('#param-env'), 'sky', 'under the scene environment');
    // the display exposure opens where the environment-lit view is not blown
    // out: the 99th percentile of the shown base render's brightness at most 1
    // at the largest step that allows it
    const ex = await page.evaluate(() => {
      const S = window.glint.state.session, v = S.views.find(x => x.base);
      const d = v.base.data, lum = [];
      for (let i = 0; i < d.length; i += 3) {
        const y = 0.2126 * d[i] + 0.7152 * d[i + 1] + 0.0722 * d[i + 2];
        if (y > 0) lum.push(y);
      }
      lum.sort((a, b) => a - b);
      return { p99: lum[Math.floor(0.99 * (lum.length - 1))], e: +document.getElementById('exposure').value,
               painter: window.glint.state.painter.exposure };
    });
    t.log(`environment-lit base: 99th percentile ${ex.p99.toFixed(3)}, exposure ${ex.e}x`);
    assertEq(ex.painter, ex.e, 'the canvas shows the exposure the control says');
    assert(ex.p99 * ex.e <= 1.0001 || ex.e === 0.25, 'not blown out: ' + JSON.stringify(ex));
    assert(ex.e === 4 || ex.p99 * ex.e * 2 > 1, 'the largest step that is not: ' + JSON.stringify(ex));
    assertEq(await page.inputValue('#param-env_rotation'), '30', 'turned as the scene is');
    // the base the artist paints on is lit by the sky, not by the view's point light
    const lit = await page.evaluate(async id => {
      const a = await fetch(`/api/v1/scenes/${id}/views/0/base.png?format=exr`).then(r => r.arrayBuffer());
      const b = await fetch(`/api/v1/scenes/${id}/views/0/base.png?format=exr&env=sky&env_rotation=30&lights=32`).then(r => r.arrayBuffer());
      // the same pixels; the writer's capDate stamp may differ by a second
      const undated = buf => {
        const x = new Uint8Array(buf), key = new TextEncoder().encode('capDate\0string\0');
        for (let i = 0; i + key.length + 4 <= x.length; i++) {
          if (key.every((c, k) => x[i + k] === c)) {
            const j = i + key.length + 4, n = x[j - 4] | (x[j - 3] << 8);
            x.fill(0, j, j + n);
            break;
          }
        }
        return x;
      };
      const x = undated(a), y = undated(b);
      return x.length === y.length && x.every((v, i) => v === y[i]);
    }, scene.id);
    assert(lit, 'the base render is the render under the environment');
  },
  async 'srbf in the studio: environment, fit, lobe, energy, preview under the environment'(t) {
    // a scene painted under lamps offers the environment's method but not to choose
    const lamps = await t.daemon.newSession({ mesh: 'torus', width: 96, height: 96 });
    const p0 = await t.page();
    await openStudio(p0, lamps.url);
    await p0.waitForSelector('#fit-method option[value="srbf"]', { state: 'attached' });
    assert(await p0.evaluate(() => document.querySelector('#fit-method option[value="srbf"]').disabled),
           'an environment\'s method is not choosable on a scene painted under lamps');
    await p0.close();
    const { url } = await t.daemon.newSession({ mesh: 'torus', width: 96, height: 96,
                                                base: { env: { spec: 'sky', lights: 32 } } });
    const page = await t.page();
    const refs = [];   // the reference renders the studio asks for (the error table's)
    page.on('request', r => {
      const u = new URL(r.url());
      if (u.pathname.endsWith('/preview.exr') && u.searchParams.get('renderer') === 'cpu')
        refs.push({ view: +u.searchParams.get('view'), size: +u.searchParams.get('size') });
    });
    await openStudio(page, url);
    await page.waitForSelector('#quality .q[data-preset]');
    const methods = await page.evaluate(() => [...document.getElementById('fit-method').options].map(o => o.value));
    assert(methods.includes('hf3') && methods.includes('srbf'), 'both methods offered: ' + methods);
    await setValue(page, 'fit-method', 'srbf', 'change');
    const note = await page.textContent('#method-note');
    assert(/environment/.test(note), 'the method says what it represents: ' + note);
    // the environment parameter lists what glintd offers
    const envs = await page.evaluate(() => [...document.getElementById('param-env').options].map(o => o.value));
    assert(envs.includes('sky') && envs.includes('studio'), 'environments offered: ' + envs);
    // an HDR file of the artist's, uploaded from the studio: chosen, and offered to the previews
    const w = 32, h = 16, px = Buffer.alloc(4 * w * h);
    for (let i = 0; i < w * h; i++) px.set(i < w * 4 ? [128, 128, 128, 130] : [128, 128, 160, 128], 4 * i);
    const hdr = Buffer.concat([Buffer.from(`#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y ${h} +X ${w}\n`), px]);
    await page.setInputFiles('#env-file', { name: 'my sky.hdr', mimeType: 'application/octet-stream', buffer: hdr });
    await page.waitForFunction(() => /^upload:[0-9a-f]{32}$/.test(document.getElementById('param-env').value), null, { timeout: 60000 });
    const upl = await page.evaluate(() => {
      const sel = document.getElementById('param-env');
      return { spec: sel.value, name: sel.selectedOptions[0].textContent,
               preview: [...document.getElementById('preview-light').options].map(o => o.value) };
    });
    assertEq(upl.name, 'my sky.hdr', 'the upload is listed by its file name');
    assert(upl.preview.includes(upl.spec), 'the previews offer the upload: ' + upl.preview);
    // the upload is this browser's (its owner key): listed to it, not to anyone else
    const mine = await page.evaluate(async () => (await window.glint.api.environments()).environments.map(e => e.spec));
    assert(mine.includes(upl.spec), 'listed again to the studio that uploaded it: ' + mine);
    const anyone = (await (await fetch(t.daemon.base + '/api/v1/environments')).json()).environments.map(e => e.spec);
    assert(!anyone.includes(upl.spec) && anyone.includes('sky'), 'not listed to a caller without its owner key: ' + anyone);
    // a file that is not a map: a clear error, nothing added
    t.allowConsole(/environments\?name=notes\.hdr/);
    const nEnv = await page.evaluate(() => document.getElementById('param-env').options.length);
    await page.setInputFiles('#env-file', { name: 'notes.hdr', mimeType: 'text/plain', buffer: Buffer.from('not a map') });
    await waitFor(() => page.evaluate(() => /OpenEXR nor Radiance/.test(document.body.textContent)), 60000, 'the upload error is shown');
    assertEq(await page.evaluate(() => document.getElementById('param-env').options.length), nEnv, 'nothing added');
    await setValue(page, 'param-env', 'sky', 'change');
    await page.click('#quality .q[data-preset="draft"] input');
    assertEq(await page.inputValue('#param-lights'), '64', 'the draft preset sets 64 lights');
    // a highlight painted on the top of the torus
    await drawStroke(page, [[40, 30], [56, 30]]);
    await settled(page, 0);
    const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
    await page.click('#fit-btn');
    await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: 120000 });
    const mat = await page.evaluate(() => window.glint.state.judge.mat);
    assertEq(mat.method, 'srbf', 'an srbf material');
    assertEq(mat.params.env, 'sky', 'fitted under the chosen environment');
    // the preview is lit by the fit's environment
    assertEq(await page.inputValue('#preview-light'), 'sky', 'the preview uses the fit environment');
    await page.waitForFunction(() => window.glint.state.judge.frames > 0 && /lights=64/.test(window.glint.state.judge.lastEnv || ''), null, { timeout: 60000 });
    const env = await page.evaluate(() => window.glint.state.judge.lastEnv);
    t.log('preview: ' + env);
    const a = await previewBytes(page);
    // turning the environment renders again, differently
    const n0 = await page.evaluate(() => window.glint.state.judge.frames);
    await setValue(page, 'env-rot', 90);
    await page.waitForFunction(n => window.glint.state.judge.frames > n, n0, { timeout: 60000 });
    const b = await previewBytes(page);
    let diff = 0;
    for (let i = 0; i < a.length; i++) diff += Math.abs(a[i] - b[i]);
    assert(diff / a.length > 0.5, 'turning the environment changes the preview: ' + (diff / a.length).toFixed(2));
    // the lobe and the energy profile
    await page.click('#factors-tab-btn');
    assertEq(await page.textContent('#factors-tab-btn'), 'Lobe', 'the tab names the lobe');
    assert(await page.isVisible('#lobe'), 'p(h) is drawn');
    const worst = await page.evaluate(() => +document.getElementById('energy').dataset.worst);
    t.log(`highest directional albedo at the energy rows: ${worst}`);
    assert(worst > 0, 'the energy profile has values');
    assertLE(worst, 1, 'energy is conserved at every band');
    const lobePx = await page.evaluate(() => {
      const d = document.getElementById('lobe').getContext('2d').getImageData(0, 0, 160, 160).data;
      let s = 0; for (let i = 0; i < d.length; i += 4) s += d[i] + d[i + 1] + d[i + 2];
      return s;
    });
    assert(lobePx > 0, 'the lobe image is not black');
    // the error per view, against a render under the environment: a coarse
    // render of each view first (a quarter of the size, shown with "≈"), then
    // the full one, which replaces it
    await page.click('.tabs button[data-tab="errors"]');
    await waitFor(() => page.evaluate(() => {
      const rows = [...document.querySelectorAll('#err-table tbody tr')];
      return rows.length && rows.every(tr => /\d/.test(tr.querySelector('td:nth-child(2)').textContent) &&
                                         !tr.classList.contains('coarse'));
    }), 120000, 'per-view errors from the full renders');
    const full = await page.evaluate(() => window.glint.state.session.scene.paint_width || window.glint.state.session.scene.width);
    t.log('reference renders requested (view:size): ' + refs.map(r => `${r.view}:${r.size}`).join(' '));
    for (const v of new Set(refs.map(r => r.view))) {
      const sizes = refs.filter(r => r.view === v).map(r => r.size);
      assertEq(sizes.join(','), `${Math.max(16, Math.round(full / 4))},${full}`, `view ${v}: a coarse render, then the full one`);
    }
    assert(refs.length >= 2, 'reference renders were requested');
    assert(await page.evaluate(() => [...window.glint.state.judge.rows.values()].every(r => !r.coarse)),
      'every row is the full render\'s');
    // shown as a percentage of the painting's brightness; the RMS behind it
    const { rms, level, shown } = await page.evaluate(() => {
      const tr = document.querySelector('#err-table tbody tr'), r = window.glint.state.judge.rows.get(+tr.dataset.view);
      return { rms: r.rms, level: r.level.level(), shown: tr.querySelector('td:nth-child(2)').textContent };
    });
    t.log(`view 0 against the render under the environment: "${shown}", RMS ${rms} over the painting's ${level}`);
    assert(isFinite(rms) && rms < 0.5, 'a finite per-view error');
    assert(/%$/.test(shown) && Math.abs(parseFloat(shown) - 100 * rms / level) <= Math.max(0.05, 0.051 * 100 * rms / level), 'shown as its percentage: ' + shown);
    // the point light is still there, for any material
    const n1 = await page.evaluate(() => window.glint.state.judge.frames);
    await setValue(page, 'preview-light', '', 'change');
    await page.waitForFunction(n => window.glint.state.judge.frames > n, n1, { timeout: 60000 });
    assertEq(await page.evaluate(() => window.glint.state.judge.lastEnv), '', 'point-light preview');
    assert(await page.isHidden('#env-rot-l'), 'no turn slider for the point light');
    await t.shot(page, 'envlit.png');
  },
  async 'a physical fit with a painted correction under an environment: chosen, fitted, shown'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64,
                                                base: { env: { spec: 'sky', lights: 32 } } });
    const page = await t.page();
    await openStudio(page, url);
    await page.waitForSelector('#fit-method option[value="pbr_tab_env"]', { state: 'attached' });
    assert(!(await page.evaluate(() => document.querySelector('#fit-method option[value="pbr_tab_env"]').disabled)),
      'offered on a scene painted under an environment');
    await setValue(page, 'fit-method', 'pbr_tab_env', 'change');
    const note = await page.textContent('#method-note');
    assert(/environment/.test(note) && /correction/.test(note), 'the method says what it represents: ' + note);
    assertEq(await page.inputValue('#param-env'), 'sky', 'under the scene environment');
    await setValue(page, 'param-lights', 32, 'change');
    await drawStroke(page, [[24, 18], [40, 18]]);
    await settled(page, 0);
    const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
    await page.click('#fit-btn');
    await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: 120000 });
    const mat = await page.evaluate(() => window.glint.state.judge.mat);
    assertEq(mat.method, 'pbr_tab_env', 'a pbr_tab_env material');
    assertEq(mat.params.env, 'sky', 'fitted under the scene environment');
    // previewed under the fit's environment, and the ball drawn
    await page.waitForFunction(() => window.glint.state.judge.frames > 0 && /lights=/.test(window.glint.state.judge.lastEnv || ''),
      null, { timeout: 60000 });
    const px = await previewBytes(page);
    let centre = 0;   // the object's middle: 16 x 16 pixels about the preview's centre
    for (let y = 120; y < 136; y++)
      for (let x = 120; x < 136; x++) centre += (px[4 * (256 * y + x)] + px[4 * (256 * y + x) + 1] + px[4 * (256 * y + x) + 2]) / 3;
    centre /= 256;
    t.log(`preview under ${await page.evaluate(() => window.glint.state.judge.lastEnv)}: centre ${centre.toFixed(1)} of 255`);
    assert(centre > 8, 'the preview shows the material lit');
    await page.waitForFunction(id => window.glint.state.judge.ball.frames > 0 &&
      (window.glint.state.judge.ball.last.query || {}).object === 'ball', mat.id, { timeout: 60000 });
    t.log('ball: ' + JSON.stringify(await page.evaluate(() => window.glint.state.judge.ball.last.env)));
    await t.shot(page, 'envlit-pbr-tab-env.png');
  },
  async 'choose for me under an environment: a first look under the scene light, then the choice'(t) {
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 48, height: 48,
                                                base: { env: { spec: 'sky', rotation: 30, lights: 32 } } });
    const page = await t.page();
    await openStudio(page, url);
    await page.waitForSelector('#quality .q[data-preset]');
    const opts = await page.evaluate(() => [...document.getElementById('fit-method').options]
      .map(o => ({ v: o.value, off: o.disabled })));
    const mine = (await t.daemon.api('GET', '/methods')).methods.filter(m => m.chooses);
    const envChooser = mine.find(m => m.lighting === 'environment').name;
    const lampChooser = mine.find(m => m.lighting === 'point').name;
    assert(opts.some(o => o.v === envChooser && !o.off), 'the choice under an environment is offered: ' + JSON.stringify(opts));
    assert(opts.some(o => o.v === lampChooser && o.off), 'the choice among lamp-lit models is not');
    await setValue(page, 'fit-method', envChooser, 'change');
    assertEq(await page.inputValue('#param-env'), 'sky', 'under the scene environment');
    assertEq(await page.inputValue('#param-env_rotation'), '30', 'turned as the scene is');
    await page.click('#quality .q[data-preset="draft"] input');
    await drawStroke(page, [[18, 14], [30, 14]]);
    await settled(page, 0);
    const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
    await page.click('#fit-btn');
    await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: 240000 });
    const mat = await page.evaluate(() => window.glint.state.judge.mat);
    const first = await page.evaluate(() => window.glint.firstLook);
    t.log(`first look ${JSON.stringify(first)}; chose ${mat.choice && mat.choice.chosen_label}`);
    assert(mat.choice && mat.choice.candidates.length >= 2, 'the choice reports its candidates');
    assertEq(mat.params.env, 'sky', 'the choice was made under the scene environment');
    // the first look, shown while it chose, was fitted under the same light
    assert(first && first.id, 'a first look was shown');
    const fm = await page.evaluate(id => window.glint.api.material(id), first.id);
    assertEq(fm.params.env, 'sky', 'the first look is fitted under the scene environment');
    assertEq(fm.params.env_rotation, 30, 'turned as the scene is');
    // the words name each candidate by its own label
    await waitFor(() => page.evaluate(() => !!document.getElementById('auto-choice')), 60000, 'the choice is explained');
    const said = await page.textContent('#auto-choice');
    t.log('said: ' + said);
    for (const c of mat.choice.candidates) assert(said.includes(c.label), 'names ' + c.label + ': ' + said);
    // judged on two hold-outs (auto_env's default), and it says so
    assertEq(mat.choice.held_out_folds.length, 2, 'two hold-outs');
    assert(said.includes('over 2 hold-outs'), 'says how many hold-outs: ' + said);
    // where it started: from the correction only with one view painted, and then it says so
    const c0 = mat.choice.candidates[0].label;
    assert(mat.choice.started_from === c0 || mat.choice.held_out === 'pixels', 'several views start from the simplest: ' + mat.choice.started_from);
    if (mat.choice.started_from !== c0)
      assert(said.includes('started from ' + mat.choice.started_from), 'says where it started: ' + said);
    else
      assert(said.includes('a richer model is kept only when'), 'says a richer model must win: ' + said);
    t.log(`started from ${mat.choice.started_from} (held out: ${mat.choice.held_out})`);
  },
});
