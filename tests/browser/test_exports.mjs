// The exports an artist takes away, from the studio's Export tab: a material
// fitted in the studio, each format downloaded through its button (a real
// download with the file name the server lists), and each file opened by a
// reader of its own ecosystem: the .glb by Khronos's glTF validator
// (gltf-validator, validateBytes: no error) and by three.js in Chromium,
// rendered with the camera and the light of one of glint's views and compared
// with glint's own render of that view (GET /materials/{id}/preview.exr); the
// .mtlx, .usda and .usdz by the checks against MaterialX's and
// UsdPreviewSurface's node definitions and the USDZ package format
// (tests/integration/export_specs.py); the MERL table by its
// header and size, the .brdf and the package by their formats.  Then a pbr
// fit of the same paintings and a two-lobe pbr material made by the CLI:
// their .glb files, with the KHR extensions, by the validator.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { run, openStudio, settled, assert, assertLE, assertEq, ARTIFACTS, SRC } from './harness.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const THREE_DIR = path.join(HERE, 'node_modules', 'three');
const EXT = { glb: 'glb', mtlx: 'mtlx', usda: 'usda', usdz: 'usdz', merl: 'binary', brdf: 'brdf', package: 'tar' };
// three.js's render of the .glb against glint's of the fitted material, the
// relative mean absolute difference on the object: 1.1% measured on the
// plastic finish (view 0, 96 x 96); the bound leaves room for other finishes
// and for three.js's own light model (its diffuse is not glTF's (1 - F) one).
const REL_BOUND = 0.05;
const PY = fs.existsSync('/usr/bin/python3') ? '/usr/bin/python3' : 'python3';

// glTF validator (npm gltf-validator): the issues of a .glb
async function validateGlb(bytes) {
  const { default: validator } = await import('gltf-validator');
  return validator.validateBytes(new Uint8Array(bytes), { maxIssues: 100 });
}

// Download one export through its button in the Export tab (OUT: the file's path and name).
async function download(page, fmt, dir) {
  await page.waitForSelector(`#dl-${fmt}:not([disabled])`);
  const [dl] = await Promise.all([page.waitForEvent('download', { timeout: 120000 }), page.click(`#dl-${fmt}`)]);
  const file = path.join(dir, dl.suggestedFilename());
  await dl.saveAs(file);
  return { file, name: dl.suggestedFilename() };
}

// The .glb in three.js with the camera and light of view v of the scene,
// into a float render target (linear, as glint's EXR), against glint's
// preview.exr of the same view; both read in a page of the daemon's origin
// (three's module build served from node_modules through page.route).
async function threeVersusGlint(t, base, session, mid, v, k, glbBytes) {
  const page = await t.page();
  await page.route(`${base}/three-test/**`, route => {
    const rel = new URL(route.request().url()).pathname.replace(/^\/three-test\//, '');
    if (rel === 'model.glb') return route.fulfill({ body: glbBytes, contentType: 'model/gltf-binary' });
    if (rel === 'index.html') {
      return route.fulfill({ contentType: 'text/html', body: '<!doctype html><script type="importmap">' +
        '{"imports": {"three": "/three-test/build/three.module.js"}}</script><body></body>' });
    }
    const f = path.join(THREE_DIR, rel);
    if (!f.startsWith(THREE_DIR + path.sep) || !fs.existsSync(f)) return route.fulfill({ status: 404, body: 'no ' + rel });
    return route.fulfill({ body: fs.readFileSync(f), contentType: 'text/javascript' });
  });
  await page.goto(`${base}/three-test/index.html`);
  return page.evaluate(async ([v, k, mid, token]) => {
    const THREE = await import('three');
    const { GLTFLoader } = await import('/three-test/examples/jsm/loaders/GLTFLoader.js');
    const { decodeEXR } = await import('/exr.js');
    const r = await fetch(`/api/v1/materials/${mid}/preview.exr?view=${k}`, { headers: { 'X-Glint-Token': token } });
    if (!r.ok) throw new Error('preview.exr: ' + r.status);
    const ref = await decodeEXR(await r.arrayBuffer());
    const W = ref.w, H = ref.h;
    const gltf = await new GLTFLoader().loadAsync('/three-test/model.glb');
    const scene = new THREE.Scene();
    scene.add(gltf.scene);
    // glint's camera: eye, target, vertical half field of view, up +z (+y looking along z)
    const cam = new THREE.PerspectiveCamera(2 * v.half_fov * 180 / Math.PI, W / H, 0.05, 100);
    const f = new THREE.Vector3(...v.target).sub(new THREE.Vector3(...v.eye)).normalize();
    cam.up.set(0, Math.abs(f.z) > 0.99 ? 1 : 0, Math.abs(f.z) > 0.99 ? 0 : 1);
    cam.position.set(...v.eye);
    cam.lookAt(...v.target);
    // glint's point light: no fall-off, a white Lambertian facing it reads I
    // (f cos times pi I); three's light of intensity L gives f cos L with decay 0
    const light = new THREE.PointLight(0xffffff, Math.PI * v.light_intensity, 0, 0);
    light.position.set(...v.light);
    scene.add(light);
    const gl = new THREE.WebGLRenderer({ antialias: false });
    gl.setSize(W, H);
    const rt = new THREE.WebGLRenderTarget(W, H, { type: THREE.FloatType });
    gl.setRenderTarget(rt);
    gl.setClearColor(0x000000, 0);
    gl.render(scene, cam);
    const px = new Float32Array(4 * W * H);
    gl.readRenderTargetPixels(rt, 0, 0, W, H, px);
    // compare where both show the object (three's alpha; glint's non-zero), rows flipped
    let n = 0, sumAbs = 0, sumRef = 0, onlyOne = 0, meanThree = 0, meanGlint = 0;
    for (let y = 0; y < H; y++) for (let x = 0; x < W; x++) {
      const o = 4 * ((H - 1 - y) * W + x), g = 3 * (y * W + x);
      const a = px[o + 3] > 0.5, dark = px[o] + px[o + 1] + px[o + 2] < 1e-4;
      const b = ref.data[g] + ref.data[g + 1] + ref.data[g + 2] > 0 || (a && dark); // unlit: black in both
      if (a !== b) { onlyOne++; continue; }
      if (!a) continue;
      n++;
      for (let c = 0; c < 3; c++) {
        sumAbs += Math.abs(px[o + c] - ref.data[g + c]);
        sumRef += Math.abs(ref.data[g + c]);
        meanThree += px[o + c]; meanGlint += ref.data[g + c];
      }
    }
    return { W, H, pixels: n, onlyOne, mae: sumAbs / (3 * n), rel: sumAbs / sumRef,
             meanThree: meanThree / (3 * n), meanGlint: meanGlint / (3 * n) };
  }, [v, k, mid, session.view_token]);
}

run({
  async 'every export downloaded from the Export tab and opened by its reader'(t) {
    let haveValidator = true;
    try { await import('gltf-validator'); } catch (_) { haveValidator = false; }
    assert(haveValidator && fs.existsSync(path.join(THREE_DIR, 'build', 'three.module.js')),
           'gltf-validator and three are installed (npm ci --prefix tests/browser)');
    const { url, session, scene } = await t.daemon.newSession({ mesh: 'sphere', width: 96, height: 96 });
    const page = await t.page();
    await openStudio(page, url);
    await page.selectOption('#preset-sel', 'plastic');
    await page.click('#preset-apply');
    await page.waitForFunction(() => document.getElementById('preset-apply').textContent === 'Paint all views' &&
                               !document.getElementById('preset-apply').disabled, null, { timeout: 60000 });
    await settled(page, 0);
    await page.waitForSelector('#quality .q[data-preset]');
    await page.click('#fit-btn');
    await page.waitForFunction(() => window.glint.lastFit && window.glint.lastFit.id, null, { timeout: 120000 });
    const mid = await page.evaluate(() => window.glint.lastFit.id);
    await page.click('.tabs button[data-tab="export"]');
    await page.waitForSelector('#dl-glb:not([disabled])', { timeout: 120000 });
    const rows = await page.locator('#exports li').allInnerTexts();
    t.log('Export tab: ' + rows.map(r => r.replace(/\s+/g, ' ')).join(' | '));
    await t.shot(page, '30-export-tab.png');
    assertEq(rows.length, 7, 'seven formats');
    assert(rows.every(r => /%|[Ee]xactly/.test(r)), 'each says how close it comes');
    const lst = await t.daemon.api('GET', `/materials/${mid}/exports`, undefined, { 'X-Glint-Token': session.view_token });
    const dir = fs.mkdtempSync(path.join(ARTIFACTS, 'exports-'));
    const files = {};
    for (const x of lst.exports) {
      const { file, name } = await download(page, x.format, dir);
      assertEq(name, x.file_name, `the ${x.format} download's file name`);
      assert(new RegExp(`^sphere-${mid.slice(0, 8)}\\.${EXT[x.format]}$`).test(name), 'named after the mesh and the material: ' + name);
      files[x.format] = file;
      t.log(`${x.format}: ${name}, ${fs.statSync(file).size} bytes, ` +
            (x.how_close.exact ? 'exact' : `rel RMS ${x.how_close.rel_rms.toFixed(4)}`));
    }
    // the .glb: Khronos's validator finds no error
    const glb = fs.readFileSync(files.glb);
    const rep = await validateGlb(glb);
    t.log(`gltf-validator ${rep.validatorVersion}: ${rep.issues.numErrors} errors, ${rep.issues.numWarnings} warnings, ` +
          `${rep.issues.numInfos} infos; ${rep.info.totalVertexCount} vertices`);
    if (rep.issues.numErrors) t.log(JSON.stringify(rep.issues.messages.slice(0, 5)));
    assertEq(rep.issues.numErrors, 0, 'the glTF validator\'s errors');
    assert(rep.info.materialCount === 1 && rep.info.totalVertexCount > 1000, 'one material on the mesh');
    // the .mtlx, .usda and .usdz against their node definitions (and the package's format)
    for (const f of ['mtlx', 'usda', 'usdz']) {
      const out = execFileSync(PY, [path.join(SRC, 'tests', 'integration', 'export_specs.py'), f, files[f]], { encoding: 'utf8' });
      t.log(`${f} conforms: ${out.trim().slice(0, 200)}`);
    }
    // MERL: three int32 dimensions 90 90 180, then 3 x 90 x 90 x 180 doubles
    const merl = fs.readFileSync(files.merl);
    assertEq([merl.readInt32LE(0), merl.readInt32LE(4), merl.readInt32LE(8)].join(','), '90,90,180', 'the MERL table\'s dimensions');
    assertEq(merl.length, 12 + 8 * 3 * 90 * 90 * 180, 'the MERL table\'s size');
    assert(fs.readFileSync(files.brdf, 'utf8').startsWith('analytic\n'), 'a BRDF Explorer analytic file');
    assertEq(fs.readFileSync(files.package).subarray(257, 262).toString(), 'ustar', 'the package is a tar file');
    // three.js renders the .glb as glint renders the material, view by view
    const k = scene.views.findIndex(v => {
      const f = v.target.map((x, i) => x - v.eye[i]), l = Math.hypot(...f);
      return Math.abs(f[2] / l) < 0.9;
    });
    const cmp = await threeVersusGlint(t, t.daemon.base, session, mid, scene.views[k], k, glb);
    t.log(`three.js ${JSON.parse(fs.readFileSync(path.join(THREE_DIR, 'package.json'), 'utf8')).version} vs glint, view ${k} ` +
          `(${cmp.W}x${cmp.H}, ${cmp.pixels} pixels on the object in both, ${cmp.onlyOne} on one only): ` +
          `mean absolute difference ${cmp.mae.toFixed(4)}, relative ${(100 * cmp.rel).toFixed(1)}% ` +
          `(mean ${cmp.meanThree.toFixed(4)} three.js, ${cmp.meanGlint.toFixed(4)} glint); ` +
          `the glTF fit's own rel RMS ${lst.fit.rel_rms.toFixed(4)}`);
    assert(cmp.pixels > 0.3 * cmp.W * cmp.H, 'the object fills the view in both renders');
    assertLE(cmp.onlyOne, 0.03 * cmp.pixels, 'the silhouettes agree');
    assertLE(cmp.rel, REL_BOUND, 'three.js\'s render of the .glb against glint\'s render of the material');

    // The same paintings fitted by the pbr method: its .glb carries the
    // material's own parameters with the KHR extensions (or the fit, when
    // that is closer) and the validator, which knows the extensions, finds
    // no error.  Then a two-lobe pbr material made by the CLI, whose
    // sharper lobe becomes KHR_materials_clearcoat.
    const H = { 'X-Glint-Token': session.paint_token };
    let fit = await t.daemon.api('POST', `/sessions/${session.id}/fits`, { method: 'pbr' }, H);
    let pmid = fit.id;
    for (let i = 0; !pmid && i < 600; i++) {
      const j = (await t.daemon.api('GET', `/jobs/${fit.job.id}`, undefined, H)).job;
      assert(j.state !== 'failed' && j.state !== 'cancelled', 'the pbr fit ran: ' + JSON.stringify(j));
      if (j.state === 'done') pmid = j.material_id;
      else await new Promise(r => setTimeout(r, 200));
    }
    assert(pmid, 'the pbr fit finished');
    const plst = await t.daemon.api('GET', `/materials/${pmid}/exports`, undefined, H);
    const pf = plst.fit;
    t.log(`pbr material: export ${pf.export}, rel RMS ${pf.rel_rms.toFixed(4)} (mapped ${pf.rel_rms_exact.toFixed(4)}, ` +
          `fitted ${pf.rel_rms_fitted.toFixed(4)}, ${pf.smith} G), extensions ${pf.extensions.join(', ') || 'none'}` +
          (pf.note ? `; ${pf.note}` : ''));
    assert(pf.export === 'exact parameters' || pf.export === 'fitted', 'the path is named');
    assertEq(pf.export === 'exact parameters', pf.rel_rms_exact <= pf.rel_rms_fitted, 'the closer path is kept');
    const r = await fetch(`${t.daemon.base}/api/v1/materials/${pmid}/material.glb`, { headers: H });
    assertEq(r.status, 200, 'the pbr material\'s .glb');
    assert(/export=(exact|fitted)/.test(r.headers.get('x-glint-gltf')), 'X-Glint-Gltf names the path');
    const pglb = Buffer.from(await r.arrayBuffer());
    const prep = await validateGlb(pglb);
    t.log(`gltf-validator on the pbr .glb: ${prep.issues.numErrors} errors, ${prep.issues.numWarnings} warnings, ` +
          `extensions used ${JSON.stringify(prep.info.extensionsUsed || [])}`);
    if (prep.issues.numErrors) t.log(JSON.stringify(prep.issues.messages.slice(0, 5)));
    assertEq(prep.issues.numErrors, 0, 'the glTF validator\'s errors on the pbr material\'s .glb');
    assertEq(JSON.stringify(prep.info.extensionsUsed || []), JSON.stringify(pf.extensions), 'the extensions the exports list names');

    const glint = path.join(process.env.GLINT_BUILD_DIR || path.join(SRC, 'build'), 'core', 'glint');
    const cdir = fs.mkdtempSync(path.join(ARTIFACTS, 'coat-'));
    fs.mkdirSync(path.join(cdir, 'mat'));
    fs.writeFileSync(path.join(cdir, 'mat', 'material.json'), JSON.stringify({
      format: 'glint-material', version: 1, method: 'pbr', fresnel: 'dielectric', diffuse: [0.3, 0.1, 0.05],
      lobes: [{ alpha: 0.2, ks: [1, 1, 1], ior: 1.5 }, { alpha: 0.02, ks: [0.5, 0.5, 0.5], ior: 1.5 }], info: {} }));
    execFileSync(glint, ['scene', 'create', '--size', '48', '-o', path.join(cdir, 'scene.json')]);
    const out = JSON.parse(execFileSync(glint, ['export-gltf', path.join(cdir, 'mat'), '--scene', path.join(cdir, 'scene.json'),
                                                '-o', path.join(cdir, 'coat.glb')], { encoding: 'utf8' }));
    t.log(`two-lobe pbr material by the CLI: export ${out.export}, mapped ${out.rel_rms_exact}, fitted ${out.rel_rms_fitted}, ` +
          `extensions ${out.extensions.join(', ')}`);
    assert(out.extensions.includes('KHR_materials_clearcoat'), 'the sharper lobe is the clearcoat (closer than the fit)');
    const crep = await validateGlb(fs.readFileSync(path.join(cdir, 'coat.glb')));
    if (crep.issues.numErrors) t.log(JSON.stringify(crep.issues.messages.slice(0, 5)));
    assertEq(crep.issues.numErrors, 0, 'the glTF validator\'s errors on the clearcoat .glb');
    assertEq((crep.info.extensionsUsed || []).length, 3, 'ior, specular and clearcoat declared');
  },
});
