// photo.js: an image dropped on the canvas, staged in the photo bar before
// it becomes a painting: either this view's painting (fitted to the raster:
// contain, cover or stretch), or a texture over the surface that paints
// every view through its texture coordinates (texmap.js).  The staged photo
// lives in the studio's state.photo; the caller passes the studio's state,
// API client and message functions once (bindPhoto).

import { blit, bitmapToImage, decodeImage, resizeImage } from './image.js';
import { isEXR } from './exr.js';
import { paintThrough, viewUV } from './texmap.js';

const $ = id => document.getElementById(id);
let state, api, toast, showError;

export async function stagePhoto(file) {
  const S = state.session;
  if (!S.canPaint) { toast('View only', 'This link cannot change paintings.', 'error'); return; }
  const buf = await file.arrayBuffer();
  let source;
  if (isEXR(buf)) source = { exr: await decodeImage(buf) };
  else {
    try { source = { bmp: await createImageBitmap(new Blob([buf]), { colorSpaceConversion: 'none', premultiplyAlpha: 'none' }) }; }
    catch (_) { toast('Not an image', `"${file.name}" cannot be read as PNG, JPEG, WebP or OpenEXR.`, 'error'); return; }
  }
  state.photo = { source, name: file.name };
  $('photo-bar').classList.remove('hidden');
  renderPhoto();
}

function photoImage() {
  const S = state.session, w = S.scene.paint_width || S.scene.width, h = S.scene.paint_height || S.scene.height;
  const src = state.photo.source;
  if (src.exr) return resizeImage(src.exr, w, h);
  return bitmapToImage(src.bmp, w, h, $('photo-fit').value);
}

// The photo as a texture over (u, v), at its own size (at most 2048 a side).
function photoTexture() {
  const src = state.photo.source;
  if (src.exr) return src.exr;
  const s = Math.min(1, 2048 / Math.max(src.bmp.width, src.bmp.height));
  return bitmapToImage(src.bmp, Math.max(1, Math.round(src.bmp.width * s)), Math.max(1, Math.round(src.bmp.height * s)), 'stretch');
}

export const onSurface = () => $('photo-place').value === 'surface';

// View k painted with the photo as a texture over the surface.
async function photoThrough(k) {
  const S = state.session, v = S.views[k];
  if (!state.photo.texture) state.photo.texture = photoTexture();
  const [uv, base] = await Promise.all([viewUV(api, S.scene.id, k), v.base || S.fetchBase(k)]);
  return paintThrough(base, uv, state.photo.texture, $('photo-flip').checked);
}

export async function renderPhoto() {
  if (!state.photo) return;
  const surf = onSurface();
  $('photo-fit-wrap').classList.toggle('hidden', surf);
  $('photo-flip-wrap').classList.toggle('hidden', !surf);
  const photo = state.photo, flip = $('photo-flip').checked, k = state.k;
  const gen = photo.gen = (photo.gen || 0) + 1;
  let img;
  try { img = surf ? await photoThrough(k) : photoImage(); } catch (e) { showError(e); return; }
  // only the newest render lands: one for an earlier placement may end later
  if (state.photo !== photo || photo.gen !== gen) return;
  photo.image = img;
  photo.imageView = k;
  photo.imageFor = surf ? `surface:${flip}` : 'flat';
  const c = $('overlay-photo');
  blit(c.getContext('2d'), img, null, state.painter.exposure);
  c.classList.remove('hidden');
  c.style.opacity = $('photo-opacity').value;
  // under the photo: the base render, to line the two up
  $('overlay-base').style.opacity = 1;
}

export function cancelPhoto() {
  state.photo = null;
  $('photo-bar').classList.add('hidden');
  $('overlay-photo').classList.add('hidden');
  $('overlay-base').style.opacity = $('base-mix').value;
  state.painter.redraw();
}

async function applyPhoto() {
  const S = state.session, k = state.k, name = state.photo.name;
  $('photo-apply').disabled = true;
  try {
    if (onSurface()) {
      // every view, one after another (each its own undo step)
      let n = 0;
      for (const v of S.views) {
        // the preview's image only if it was made for this view, over the
        // surface, with this flip (a click can come before its render ends)
        const ready = state.photo.image && v.k === state.photo.imageView &&
          state.photo.imageFor === `surface:${$('photo-flip').checked}`;
        const img = ready ? state.photo.image : await photoThrough(v.k);
        await S.uploadImage(v.k, img);
        n++;
        $('photo-apply').textContent = `Painting ${n} of ${S.views.length}…`;
      }
      cancelPhoto();
      toast('Paintings replaced', `${n} views now show ${name} over the surface`);
    } else {
      const img = state.photo.image && state.photo.imageFor === 'flat' ? state.photo.image : photoImage();
      await S.uploadImage(k, img);
      cancelPhoto();
      toast('Painting replaced', `view ${k} now shows ${name || 'the image'}`);
    }
  } catch (e) { showError(e); } finally { $('photo-apply').disabled = false; $('photo-apply').textContent = 'Use as painting'; }
}

// Wire the photo bar to the studio (once).
export function bindPhoto(ctx) {
  ({ state, api, toast, showError } = ctx);
  $('photo-opacity').oninput = () => { $('overlay-photo').style.opacity = $('photo-opacity').value; };
  $('photo-fit').onchange = renderPhoto;
  $('photo-place').onchange = renderPhoto;
  $('photo-flip').onchange = renderPhoto;
  $('photo-apply').onclick = applyPhoto;
  $('photo-cancel').onclick = cancelPhoto;
}
