// A method the studio has never heard of: glintd-test (tests/methods)
// registers the test-only Lambert method by one line beside the build's
// own, and nothing in web/ names any method.  The studio offers it by the
// label its table gives, says under the choice what it models and when to
// use it, names its parameter plainly, fits it, previews the material and
// lists it by its label, and draws no factors for it (its table says it
// has none), all from GET /api/v1/methods.
import {
  run, openStudio, drawStroke, settled, recordToasts, assert, assertEq, assertGE,
} from './harness.mjs';

const NAME = 'lambert-test';

async function setValue(page, id, v) {
  await page.evaluate(([id, v]) => { const el = document.getElementById(id); el.value = v; el.dispatchEvent(new Event('change', { bubbles: true })); }, [id, String(v)]);
}

run({
  async 'the test-only Lambert method: offered by its label, noted, fitted and previewed'(t) {
    const api = (await t.daemon.api('GET', '/methods')).methods;
    const lam = api.find(m => m.name === NAME);
    assert(lam, 'glintd-test lists the test method: ' + api.map(m => m.name));
    const { url } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const page = await t.page();
    await openStudio(page, url);
    const toasts = await recordToasts(page);
    await page.waitForSelector(`#fit-method option[value="${NAME}"]`, { state: 'attached' });
    // the method choice: every method by its label, the test one among them
    const opts = await page.evaluate(() => [...document.getElementById('fit-method').options].map(o => ({ value: o.value, text: o.textContent })));
    assertEq(opts.map(o => o.value).join(','), api.map(m => m.name).join(','), 'every method offered, in the table\'s order');
    for (const o of opts) assertEq(o.text, api.find(m => m.name === o.value).label, 'offered by its label');
    assertEq(opts.find(o => o.value === NAME).text, 'Flat colour (test build)', 'the test method\'s label');
    // the guide names it too
    await page.waitForFunction(() => document.getElementById('guide-methods').textContent.length > 0);
    assert((await page.textContent('#guide-methods')).includes('flat colour (test build)'), 'the guide lists it');
    // chosen: its notes and its parameter's plain name
    await setValue(page, 'fit-method', NAME);
    const note = await page.textContent('#method-note');
    assert(note.includes(lam.summary) && note.includes(lam.when), 'the note is its summary and when to use it: ' + note);
    assert(/Lambert/.test(note), 'it says what it models: ' + note);
    const label = await page.evaluate(() => document.querySelector('#params label[for="param-albedo_max"]').textContent);
    assertEq(label, 'brightest colour allowed', 'the parameter by its plain name');
    assertEq(await page.inputValue('#param-albedo_max'), '1', 'at its default');
    // paint a view and fit it
    await drawStroke(page, [[20, 30], [44, 30]]);
    await settled(page, 0);
    const before = await page.evaluate(() => window.glint.lastFit && window.glint.lastFit.id);
    await page.click('#fit-btn');
    await page.waitForFunction(b => window.glint.lastFit && window.glint.lastFit.id !== b, before, { timeout: 120000 });
    const mat = await page.evaluate(() => window.glint.state.judge.mat);
    assertEq(mat.method, NAME, 'a material of the test method');
    // listed by its label (it has no size of its own to show)
    const listed = await page.evaluate(() => document.getElementById('mat-sel').selectedOptions[0].textContent);
    assert(listed.includes(lam.label), 'the material list names it by its label: ' + listed);
    // previewed: the preview shows the lit sphere
    await page.waitForFunction(() => window.glint.state.judge.frames > 0, null, { timeout: 120000 });
    const lit = await page.evaluate(() => {
      const c = document.getElementById('preview'), g = c.getContext('2d');
      const d = g.getImageData(c.width / 4, c.height / 4, c.width / 2, c.height / 2).data;
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i] + d[i + 1] + d[i + 2] > 30) n++;
      return n / (d.length / 4);
    });
    assertGE(lit, 0.05, 'the preview shows the material on the object');
    // its errors per view are measured like any material's
    await page.waitForSelector('#err-table tbody tr', { state: 'attached', timeout: 120000 });
    // the Factors tab says there is nothing to draw (its table: shows none)
    await page.click('#factors-tab-btn');
    assert(await page.isVisible('#factors-none'), 'no factors to draw, said so');
    assert(!(await page.isVisible('#factors-wrap')) && !(await page.isVisible('#lobe-wrap')) && !(await page.isVisible('#surface-wrap')),
      'no factor curves, lobes or textures over the surface');
    const errs = (await toasts()).filter(x => x.error);
    assertEq(errs.length, 0, 'no error shown: ' + JSON.stringify(errs));
    await t.shot(page, 'method_plugin.png');
  },
});
