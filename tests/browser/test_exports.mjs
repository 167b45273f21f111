// The exports an artist takes away, from the studio's Export tab: a material
// fitted in the studio, each format downloaded through its button (a real
// download with the file name the server lists), and each file opened by a
// reader of its own ecosystem: the .glb by Khronos's glTF validator
// (gltf-validator, validateBytes: no error) and by three.js in Chromium,
// rendered with the camera and the light of one of glint's views and compared
// with glint's own render of that view (GET /materials/{id}/preview.exr); the
// .mtlx, .mtlx.zip, .usda and .usdz by the checks against MaterialX's and
// UsdPreviewSurface's node definitions and the USDZ package format
// (tests/integration/export_specs.py); the MERL table by its
// header and size, the .brdf and the package by their formats.  Then a pbr
// fit of the same paintings and a two-lobe pbr material made by the CLI:
// their .glb files, with the KHR extensions, by the validator.  Last, a
// material that varies over the surface (maps of a checker of gold and red
// plastic): its MaterialX package read by three.js's own MaterialX reader
// (MaterialXLoader: the document and its textures from the .mtlx.zip) and
// rendered beside the .glb, both against glint's render.  And a brushed
// finish fitted as brushed: its .glb carries KHR_materials_anisotropy (the
// validator; three.js's render against glint's, with the anisotropy and
// without), and the Export tab says what each format holds.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { run, openStudio, settled, paintAllViews, assert, assertLE, assertEq, ARTIFACTS, SRC } from './harness.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const THREE_DIR = path.join(HERE, 'node_modules', 'three');
const EXT = { glb: 'glb', mtlx: 'mtlx', mtlx_zip: 'mtlx\\.zip', usda: 'usda', usdz: 'usdz', merl: 'binary', brdf: 'brdf', package: 'tar' };
// three.js's render of the .glb against glint's of the fitted material, the
// relative mean absolute difference on the object: 1.1% measured on the
// plastic finish (view 0, 96 x 96); the bound leaves room for other finishes
// and for three.js's own light model (its diffuse is not glTF's (1 - F) one).
const REL_BOUND = 0.05;
const PY = fs.existsSync('/usr/bin/python3') ? '/usr/bin/python3' : 'python3';
// red plastic and gold in a checker of two squares across u and across v: a
// material of maps that varies over the surface both ways (a texture read
// upside down puts the gold where the plastic is)
const CHECKER = 'checker:freq=1,duty=0.5|ct:kd=0.6/0.1/0.08,f0=0.04,rough=0.3|ct:kd=0,f0=0.9/0.7/0.3,rough=0.25';
// three.js's render of the MaterialX package against its render of the .glb
// (the same textures through two readers and two material models): 1.9%
// measured on the checker at 96 x 96 (0.5-0.9% on stripes across u, bake_res
// 32 to 128); the .glb's textures turned upside down differ from it by 28%.
// Against glint's render of the material: 23.8%, as the .glb's own render
// (and the WebGL renderer's of it): three.js widens a highlight by its
// normals' change across a pixel (its specular antialiasing), so the figure
// falls with the size (a uniform gold: 20.9% at 64 x 64, 13.5% at 160 x 160;
// a plastic 1.9%), and the bake's texels straddle the squares' edges.
const MTLX_GLB_BOUND = 0.05;
const MTLX_GLINT_BOUND = 0.30;

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

// What the pages below share, installed before each loads:
//   glintViewRig(THREE, object, v, W, H): the object in a scene with glint's
//     camera of view v (eye, target, vertical half field of view, up +z; +y
//     looking along z) and its point light (no fall-off: a white Lambertian
//     facing it reads I, f cos times pi I; three's light of intensity L gives
//     f cos L with decay 0); THREE is either build;
//   glintReference(mid, k, token): glint's render of view k (preview.exr, linear);
//   glintThree(px, W, H): a three.js render read back (RGBA floats, rows
//     bottom-first) as a sampler (x, y, c) -> value, null off the object;
//   glintImage(ref, px, W, H): glint's render as a sampler, on the object where
//     lit or where the render px shows it black (unlit in both);
//   glintCompare(a, b, W, H): where both samplers show the object, the mean
//     absolute difference (mae), relative to b's (rel), and each one's mean;
//     pixels on one only (onlyOne).
function installThreeHelpers(page) {
  return page.addInitScript(() => {
    window.glintViewRig = (THREE, object, v, W, H) => {
      const scene = new THREE.Scene();
      scene.add(object);
      const cam = new THREE.PerspectiveCamera(2 * v.half_fov * 180 / Math.PI, W / H, 0.05, 100);
      const f = new THREE.Vector3(...v.target).sub(new THREE.Vector3(...v.eye)).normalize();
      cam.up.set(0, Math.abs(f.z) > 0.99 ? 1 : 0, Math.abs(f.z) > 0.99 ? 0 : 1);
      cam.position.set(...v.eye);
      cam.lookAt(...v.target);
      const light = new THREE.PointLight(0xffffff, Math.PI * v.light_intensity, 0, 0);
      light.position.set(...v.light);
      scene.add(light);
      return { scene, cam };
    };
    window.glintReference = async (mid, k, token) => {
      const { decodeEXR } = await import('/exr.js');
      const r = await fetch(`/api/v1/materials/${mid}/preview.exr?view=${k}`, { headers: { 'X-Glint-Token': token } });
      if (!r.ok) throw new Error('preview.exr: ' + r.status);
      return decodeEXR(await r.arrayBuffer());
    };
    window.glintThree = (px, W, H) => (x, y, c) => {
      const o = 4 * ((H - 1 - y) * W + x);
      return px[o + 3] > 0.5 ? px[o + c] : null;
    };
    window.glintImage = (ref, px, W, H) => (x, y, c) => {
      const g = 3 * (y * W + x), o = 4 * ((H - 1 - y) * W + x);
      const on = ref.data[g] + ref.data[g + 1] + ref.data[g + 2] > 0 ||
                 (px[o + 3] > 0.5 && px[o] + px[o + 1] + px[o + 2] < 1e-4);
      return on ? ref.data[g + c] : null;
    };
    window.glintCompare = (a, b, W, H) => {
      let n = 0, sumAbs = 0, sumRef = 0, onlyOne = 0, meanA = 0, meanB = 0;
      for (let y = 0; y < H; y++) for (let x = 0; x < W; x++) {
        const va = a(x, y, 0), vb = b(x, y, 0);
        if ((va === null) !== (vb === null)) { onlyOne++; continue; }
        if (va === null) continue;
        n++;
        for (let c = 0; c < 3; c++) {
          const p = a(x, y, c), q = b(x, y, c);
          sumAbs += Math.abs(p - q); sumRef += Math.abs(q); meanA += p; meanB += q;
        }
      }
      return { W, H, pixels: n, onlyOne, mae: sumAbs / (3 * n), rel: sumAbs / sumRef,
               meanA: meanA / (3 * n), meanB: meanB / (3 * n) };
    };
  });
}

// A page of the daemon's origin with three.js served from node_modules
// under /three-test/ (build 'webgl': three.module.js; 'webgpu': the WebGPU
// build, its renderer on its WebGL 2 backend), the addons at three/addons/,
// the files of `bytes` ({name: Buffer}) and the helpers above.
async function threePage(t, base, bytes, build) {
  const page = await t.page();
  const imports = build === 'webgpu'
    ? { three: '/three-test/build/three.webgpu.js', 'three/webgpu': '/three-test/build/three.webgpu.js',
        'three/tsl': '/three-test/build/three.tsl.js', 'three/addons/': '/three-test/examples/jsm/' }
    : { three: '/three-test/build/three.module.js', 'three/addons/': '/three-test/examples/jsm/' };
  await page.route(`${base}/three-test/**`, route => {
    const rel = new URL(route.request().url()).pathname.replace(/^\/three-test\//, '');
    if (bytes[rel]) return route.fulfill({ body: bytes[rel], contentType: 'application/octet-stream' });
    if (rel === 'index.html') {
      return route.fulfill({ contentType: 'text/html', body: '<!doctype html><script type="importmap">' +
        JSON.stringify({ imports }) + '</script><body></body>' });
    }
    const f = path.join(THREE_DIR, rel);
    if (!f.startsWith(THREE_DIR + path.sep) || !fs.existsSync(f)) return route.fulfill({ status: 404, body: 'no ' + rel });
    return route.fulfill({ body: fs.readFileSync(f), contentType: 'text/javascript' });
  });
  await installThreeHelpers(page);
  await page.goto(`${base}/three-test/index.html`);
  return page;
}

// The .glb in three.js with the camera and light of view v of the scene,
// into a float render target (linear, as glint's EXR), against glint's
// preview.exr of the same view.  aniso: 'as written', or a check of how the
// anisotropy is read: 'off' (set to 0) or 'turned' (its direction a quarter).
async function threeVersusGlint(t, base, session, mid, v, k, glbBytes, aniso = 'as written') {
  const page = await threePage(t, base, { 'model.glb': glbBytes }, 'webgl');
  const c = await page.evaluate(async ([v, k, mid, token, aniso]) => {
    const THREE = await import('three');
    const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
    const ref = await window.glintReference(mid, k, token);
    const W = ref.w, H = ref.h;
    const gltf = await new GLTFLoader().loadAsync('/three-test/model.glb');
    gltf.scene.traverse(o => {
      if (!o.isMesh) return;
      if (aniso === 'off') o.material.anisotropy = 0;
      if (aniso === 'turned') o.material.anisotropyRotation += Math.PI / 2;
    });
    const { scene, cam } = window.glintViewRig(THREE, gltf.scene, v, W, H);
    const gl = new THREE.WebGLRenderer({ antialias: false });
    gl.setSize(W, H);
    const rt = new THREE.WebGLRenderTarget(W, H, { type: THREE.FloatType });
    gl.setRenderTarget(rt);
    gl.setClearColor(0x000000, 0);
    gl.render(scene, cam);
    const px = new Float32Array(4 * W * H);
    gl.readRenderTargetPixels(rt, 0, 0, W, H, px);
    return window.glintCompare(window.glintThree(px, W, H), window.glintImage(ref, px, W, H), W, H);
  }, [v, k, mid, session.view_token, aniso]);
  return Object.assign(c, { meanThree: c.meanA, meanGlint: c.meanB });
}

// The .glb's mesh rendered by three.js twice (its WebGPU build), with the
// .glb's own material and with the material three's MaterialXLoader makes
// of the .mtlx.zip (its uvSpace top-left: the mesh's texture coordinates
// are glTF's), with the camera and light of view v, each against glint's
// preview.exr of that view and against each other.
async function mtlxVersusGlb(t, base, v, k, mid, token, bytes) {
  const page = await threePage(t, base, bytes, 'webgpu');
  return page.evaluate(async ([v, k, mid, token]) => {
    const THREE = await import('three');
    const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
    const { MaterialXLoader } = await import('three/addons/loaders/MaterialXLoader.js');
    const ref = await window.glintReference(mid, k, token);
    const W = ref.w, H = ref.h;
    const gltf = await new GLTFLoader().loadAsync('/three-test/model.glb');
    let mesh = null;
    gltf.scene.traverse(o => { if (o.isMesh && !mesh) mesh = o; });
    // a relative URL: the loader prefixes its textures' blob URLs with the
    // package's folder.  uvSpace top-left: the .glb's texture coordinates are
    // glTF's (three.js 0.187 applies it to texcoord values; an image node
    // samples the same either way: measured, identical renders)
    const mx = await new MaterialXLoader().loadAsync('material.mtlx.zip', { uvSpace: 'top-left' });
    const names = Object.keys(mx.materials);
    if (names.length !== 1) throw new Error('MaterialXLoader made ' + names.length + ' materials');
    const mxMat = mx.materials[names[0]];
    const { scene, cam } = window.glintViewRig(THREE, gltf.scene, v, W, H);
    const gl = new THREE.WebGPURenderer({ antialias: false, forceWebGL: true });
    await gl.init();
    gl.setSize(W, H);
    gl.setClearColor(0x000000, 0);
    const rt = new THREE.RenderTarget(W, H, { type: THREE.FloatType });
    const draw = async mat => {
      mesh.material = mat;
      gl.setRenderTarget(rt);
      gl.render(scene, cam);
      return new Float32Array(await gl.readRenderTargetPixelsAsync(rt, 0, 0, W, H));
    };
    const glbMat = mesh.material;
    const pxGlb = await draw(glbMat), pxMx = await draw(mxMat);
    const three = px => window.glintThree(px, W, H), glint = window.glintImage(ref, pxGlb, W, H);
    return { W, H, material: names[0], warnings: mx.warnings.map(w => w.message || String(w)),
             mxType: mxMat.type, glbHasMaps: !!(glbMat.map && glbMat.metalnessMap && glbMat.roughnessMap),
             glbVsGlint: window.glintCompare(three(pxGlb), glint, W, H),
             mxVsGlint: window.glintCompare(three(pxMx), glint, W, H),
             mxVsGlb: window.glintCompare(three(pxMx), three(pxGlb), W, H) };
  }, [v, k, mid, token]);
}

// A fit through the API (the paint token's), waited for when it runs as a
// job; the material's id.
async function fitMaterial(t, session, body, H) {
  const fit = await t.daemon.api('POST', `/sessions/${session.id}/fits`, body, H);
  let mid = fit.id;
  for (let i = 0; !mid && i < 600; i++) {
    const j = (await t.daemon.api('GET', `/jobs/${fit.job.id}`, undefined, H)).job;
    assert(j.state !== 'failed' && j.state !== 'cancelled', `the ${body.method} fit ran: ` + JSON.stringify(j));
    if (j.state === 'done') mid = j.material_id;
    else await new Promise(r => setTimeout(r, 200));
  }
  assert(mid, `the ${body.method} fit finished`);
  return mid;
}

// The first view of the scene that does not look along the vertical axis.
function sideView(scene) {
  return scene.views.findIndex(v => {
    const f = v.target.map((x, i) => x - v.eye[i]), l = Math.hypot(...f);
    return Math.abs(f[2] / l) < 0.9;
  });
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
    await paintAllViews(page);
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
    assertEq(rows.length, 8, 'eight formats');
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
    // the .mtlx, .mtlx.zip, .usda and .usdz against their node definitions (and the packages' formats)
    for (const f of ['mtlx', 'mtlx_zip', 'usda', 'usdz']) {
      const out = execFileSync(PY, [path.join(SRC, 'tests', 'integration', 'export_specs.py'), f.replace('_', '.'), files[f]], { encoding: 'utf8' });
      t.log(`${f} conforms: ${out.trim().slice(0, 200)}`);
    }
    // MERL: three int32 dimensions 90 90 180, then 3 x 90 x 90 x 180 doubles
    const merl = fs.readFileSync(files.merl);
    assertEq([merl.readInt32LE(0), merl.readInt32LE(4), merl.readInt32LE(8)].join(','), '90,90,180', 'the MERL table\'s dimensions');
    assertEq(merl.length, 12 + 8 * 3 * 90 * 90 * 180, 'the MERL table\'s size');
    assert(fs.readFileSync(files.brdf, 'utf8').startsWith('analytic\n'), 'a BRDF Explorer analytic file');
    assertEq(fs.readFileSync(files.package).subarray(257, 262).toString(), 'ustar', 'the package is a tar file');
    // three.js renders the .glb as glint renders the material, view by view
    const k = sideView(scene);
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
    const pmid = await fitMaterial(t, session, { method: 'pbr' }, H);
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
  async 'a material that varies: its MaterialX package rendered by three.js as its .glb is'(t) {
    // a checker of gold and red plastic painted by the CLI, fitted as maps: the
    // exports bake textures; three.js reads the .mtlx.zip with its own
    // MaterialX reader and renders it beside the .glb, both against glint
    assert(fs.existsSync(path.join(THREE_DIR, 'examples', 'jsm', 'loaders', 'MaterialXLoader.js')),
           'three.js with its MaterialXLoader is installed (npm ci --prefix tests/browser)');
    const glint = path.join(process.env.GLINT_BUILD_DIR || path.join(SRC, 'build'), 'core', 'glint');
    const dir = fs.mkdtempSync(path.join(ARTIFACTS, 'mtlx-'));
    const SIZE = 96;
    execFileSync(glint, ['scene', 'create', '--size', String(SIZE), '-o', path.join(dir, 'scene.json')]);
    execFileSync(glint, ['paint', path.join(dir, 'scene.json'), '--brdf', CHECKER, '-o', path.join(dir, 'paint')]);
    const { session, scene } = await t.daemon.newSession({ mesh: 'sphere', width: SIZE, height: SIZE });
    const H = { 'X-Glint-Token': session.paint_token };
    for (let k = 0; k < scene.views.length; k++) {
      const exr = fs.readFileSync(path.join(dir, 'paint', `view_${String(k).padStart(2, '0')}.exr`));
      await t.daemon.api('PUT', `/sessions/${session.id}/views/${k}/painting`, exr, Object.assign({ 'Content-Type': 'image/x-exr' }, H));
    }
    const mid = await fitMaterial(t, session, { method: 'maps', params: { res: 32, map_res: 32, components: 3 } }, H);
    const get = async p => {
      const r = await fetch(`${t.daemon.base}/api/v1/materials/${mid}/${p}`, { headers: H });
      assertEq(r.status, 200, p);
      return { bytes: Buffer.from(await r.arrayBuffer()), fit: r.headers.get('x-glint-fit') || r.headers.get('x-glint-gltf') };
    };
    const glb = await get('material.glb'), pkg = await get('material.mtlx.zip');
    t.log(`.glb: ${glb.fit}`);
    t.log(`.mtlx.zip: ${pkg.fit}`);
    assert(/textures=32/.test(pkg.fit), 'the package carries 32 x 32 textures');
    fs.writeFileSync(path.join(dir, 'material.mtlx.zip'), pkg.bytes);
    execFileSync(PY, [path.join(SRC, 'tests', 'integration', 'export_specs.py'), 'mtlx.zip', path.join(dir, 'material.mtlx.zip')]);
    const k = sideView(scene);
    const c = await mtlxVersusGlb(t, t.daemon.base, scene.views[k], k, mid, session.view_token,
                                  { 'model.glb': glb.bytes, 'material.mtlx.zip': pkg.bytes });
    const pct = x => (100 * x.rel).toFixed(1) + '%';
    t.log(`three.js ${JSON.parse(fs.readFileSync(path.join(THREE_DIR, 'package.json'), 'utf8')).version}, WebGPURenderer ` +
          `(WebGL 2), view ${k}, ${c.W}x${c.H}: MaterialXLoader made ${c.material} (${c.mxType}), ` +
          `${c.warnings.length} warnings${c.warnings.length ? ' (' + c.warnings.slice(0, 3).join('; ') + ')' : ''}; ` +
          `relative mean absolute difference: MaterialX vs .glb ${pct(c.mxVsGlb)} (${c.mxVsGlb.pixels} pixels, ` +
          `${c.mxVsGlb.onlyOne} on one only), .glb vs glint ${pct(c.glbVsGlint)}, MaterialX vs glint ${pct(c.mxVsGlint)}`);
    assert(c.glbHasMaps, 'the .glb carries base colour and metallic-roughness textures');
    assert(c.mxVsGlb.pixels > 0.3 * c.W * c.H, 'the object fills the view');
    assertLE(c.mxVsGlb.onlyOne, 0.01 * c.mxVsGlb.pixels, 'the silhouettes agree');
    assertLE(c.mxVsGlb.rel, MTLX_GLB_BOUND, 'three.js\'s render of the MaterialX package against its render of the .glb');
    assertLE(c.mxVsGlint.rel, MTLX_GLINT_BOUND, 'three.js\'s render of the MaterialX package against glint\'s render of the material');
  },
  async 'a brushed finish: the .glb carries its anisotropy, the Export tab says what each format holds'(t) {
    const { url, session, scene } = await t.daemon.newSession({ mesh: 'sphere', width: 64, height: 64 });
    const page = await t.page();
    await openStudio(page, url);
    await page.selectOption('#preset-sel', 'satin');
    await paintAllViews(page);
    await settled(page, 0);
    await page.selectOption('#fit-method', 'hf2d');
    await page.click('#fit-btn');
    await page.waitForFunction(() => window.glint.lastFit && window.glint.lastFit.id, null, { timeout: 120000 });
    const mid = await page.evaluate(() => window.glint.lastFit.id);
    await page.click('.tabs button[data-tab="export"]');
    await page.waitForSelector('#dl-glb:not([disabled])', { timeout: 120000 });
    const rows = await page.locator('#exports li').allInnerTexts();
    const lst = await t.daemon.api('GET', `/materials/${mid}/exports`, undefined, { 'X-Glint-Token': session.view_token });
    t.log(`hf2d on the brushed satin: anisotropy ${lst.fit.anisotropy.toFixed(3)}; the tab's last line: ${rows[rows.length - 1]}`);
    assert(lst.fit.anisotropy > 0.02, 'the fit measures the brushed look');
    assert(rows.some(r => /brushed/.test(r) && /KHR_materials_anisotropy/.test(r) && /unbrushed look/.test(r)),
           'the Export tab says what each format carries');
    const af = lst.fit.anisotropic_fit;
    assert(af, 'the .glb carries an anisotropic fit');
    const glbRow = lst.exports.find(x => x.format === 'glb');
    t.log(`anisotropic fit: strength ${af.strength.toFixed(3)}, rotation ${(af.rotation * 180 / Math.PI).toFixed(1)} degrees, ` +
          `relative RMS ${af.rel_rms.toFixed(4)} against the isotropic fit's ${lst.fit.rel_rms.toFixed(4)}; the list's glb figure ${glbRow.how_close.rel_rms.toFixed(4)}`);
    assertLE(af.rel_rms, lst.fit.rel_rms, 'the anisotropic fit is the closer');
    assertEq(glbRow.how_close.rel_rms, af.rel_rms, 'the list states the .glb\'s own figure');
    // the .glb downloaded from the tab: Khronos's validator, then three.js's
    // render (its MeshPhysicalMaterial's anisotropy) against glint's, with
    // the extension and with its anisotropy set to 0
    const dir = fs.mkdtempSync(path.join(ARTIFACTS, 'aniso-'));
    const { file } = await download(page, 'glb', dir);
    const glb = fs.readFileSync(file);
    const rep = await validateGlb(glb);
    if (rep.issues.numErrors) t.log(JSON.stringify(rep.issues.messages.slice(0, 5)));
    assertEq(rep.issues.numErrors, 0, 'the glTF validator\'s errors on the anisotropic .glb');
    assertEq(JSON.stringify(rep.info.extensionsUsed || []), '["KHR_materials_anisotropy"]', 'the extension declared');
    const k = sideView(scene);
    const withA = await threeVersusGlint(t, t.daemon.base, session, mid, scene.views[k], k, glb);
    const noA = await threeVersusGlint(t, t.daemon.base, session, mid, scene.views[k], k, glb, 'off');
    const turned = await threeVersusGlint(t, t.daemon.base, session, mid, scene.views[k], k, glb, 'turned');
    t.log(`three.js vs glint, view ${k} (${withA.W}x${withA.H}): relative mean absolute difference ${(100 * withA.rel).toFixed(1)}% ` +
          `with the extension as written, ${(100 * noA.rel).toFixed(1)}% with its anisotropy set to 0, ` +
          `${(100 * turned.rel).toFixed(1)}% with its direction turned 90 degrees`);
    assertLE(withA.onlyOne, 0.03 * withA.pixels, 'the silhouettes agree');
    assertLE(withA.rel, noA.rel, 'the anisotropy brings three.js\'s render closer to glint\'s');
    assertLE(withA.rel, turned.rel, 'three.js reads the direction as glint wrote it (tangent and rotation)');
  },
});
