// painter.js: the paint canvas of one view: zoom and pan, the brush cursor,
// strokes drawn as the pointer moves (brush.js LiveStroke on the view's
// displayed image, the same math the server will apply), the eyedropper and
// the overlays (base render, a dropped photo).
//
// The canvas holds the image at its own raster size (1 canvas pixel = 1
// image pixel) and is scaled by a CSS transform, so its pixels are exactly
// the 8-bit view of the floats (image.js) at any zoom.  On the screen an
// image pixel covers zoom x devicePixelRatio device pixels: fitting to the
// window picks a zoom that makes this a whole number (and puts the image's
// corner on a device pixel), so every pixel is drawn the same size; at a
// zoom where it is not (a browser zoom of 225-275%, or the wheel), the
// canvas is smoothed instead of drawn as blocks of uneven widths, which
// made stair-stepped edges.  The brush cursor's canvas is sized in device
// pixels.

import { LiveStroke } from './brush.js';
import { blit, cloneImage } from './image.js';

export class Painter extends EventTarget {
  constructor(els, session, getBrush) {
    super();
    this.el = els;                 // {viewport, stage, paint, base, photo, cursor}
    this.session = session;
    this.getBrush = getBrush;
    this.k = -1;
    this.zoom = 1; this.panX = 0; this.panY = 0;
    this.tool = 'paint';
    this.exposure = 1;
    this.live = null;
    this.spaceHeld = false;
    this.mouse = null;             // last pointer position in image coordinates
    this.ctx = els.paint.getContext('2d', { willReadFrequently: true });
    this.bind();
  }

  emit(type, detail) { this.dispatchEvent(new CustomEvent(type, { detail })); }

  get view() { return this.session.views[this.k]; }

  // ---- showing a view -----------------------------------------------------------------

  show(k, keepZoom) {
    const v = this.session.views[k];
    const first = this.k < 0;
    this.cancelLive();
    this.k = k;
    // the canvas is the view's image: the painting's size (the scene's
    // paint_scale times its raster), or the raster's for a painting uploaded so
    const sc = this.session.scene;
    const { w, h } = v.disp ? { w: v.disp.w, h: v.disp.h } : { w: sc.paint_width || sc.width, h: sc.paint_height || sc.height };
    for (const c of [this.el.paint, this.el.base, this.el.photo]) { c.width = w; c.height = h; }
    this.el.stage.style.width = w + 'px'; this.el.stage.style.height = h + 'px';
    this.redraw();
    if (first || !keepZoom) this.fitToWindow();
  }

  redraw(box) {
    const v = this.view;
    if (!v || !v.disp) return;
    blit(this.ctx, v.disp, box, this.exposure);
    if (!box && v.base) blit(this.el.base.getContext('2d'), v.base, null, this.exposure);
  }

  setExposure(e) { this.exposure = e; this.redraw(); }
  setBaseMix(a) { this.el.base.style.opacity = a; }

  // ---- zoom and pan -------------------------------------------------------------------

  applyTransform() {
    this.el.stage.style.transform = `translate(${this.panX}px, ${this.panY}px) scale(${this.zoom})`;
    this.applyRendering();
    this.emit('zoom', this.zoom);
    this.drawCursor();
  }

  fitToWindow() {
    const vp = this.el.viewport.getBoundingClientRect();
    const w = this.el.paint.width, h = this.el.paint.height, dpr = devicePixelRatio || 1;
    let z = Math.min((vp.width - 24) / w, (vp.height - 24) / h);
    if (z * dpr >= 1) z = Math.floor(z * dpr + 1e-9) / dpr;     // whole device pixels per image pixel
    this.zoom = Math.max(0.1, z);
    // the image's corner on a device pixel (the viewport may not start on one)
    const snap = (o, x) => Math.round((o + x) * dpr) / dpr - o;
    this.panX = snap(vp.left, (vp.width - w * this.zoom) / 2);
    this.panY = snap(vp.top, (vp.height - h * this.zoom) / 2);
    this.fitted = true;
    this.applyTransform();
  }

  // Device pixels per image pixel; blocks of one size (pixelated) when it
  // is a whole number or large (8 and up, where one device pixel more or
  // less does not show), else smoothed.
  applyRendering() {
    const k = this.zoom * (devicePixelRatio || 1);
    const whole = k >= 1 && Math.abs(k - Math.round(k)) < 1e-3;
    const mode = whole || k >= 8 ? 'pixelated' : 'auto';
    if (this.el.stage.dataset.rendering !== mode) {
      this.el.stage.dataset.rendering = mode;
      for (const c of this.el.stage.querySelectorAll('canvas')) c.style.imageRendering = mode;
    }
  }

  // A browser zoom changes devicePixelRatio: the rendering follows it, and
  // so does the cursor's canvas.
  watchRatio() {
    const mq = matchMedia(`(resolution: ${devicePixelRatio || 1}dppx)`);
    mq.addEventListener('change', () => { this.applyRendering(); this.resizeCursor(); this.watchRatio(); }, { once: true });
  }

  zoomAt(factor, cx, cy) {
    const vp = this.el.viewport.getBoundingClientRect();
    if (cx == null) { cx = vp.width / 2; cy = vp.height / 2; }
    const z = Math.min(32, Math.max(0.1, this.zoom * factor));
    const ix = (cx - this.panX) / this.zoom, iy = (cy - this.panY) / this.zoom;
    this.zoom = z;
    this.panX = cx - ix * z; this.panY = cy - iy * z;
    this.fitted = false;
    this.applyTransform();
  }

  // viewport coordinates -> image coordinates (pixel centres at i + 0.5)
  toImage(e) {
    const r = this.el.viewport.getBoundingClientRect();
    const cx = e.clientX - r.left, cy = e.clientY - r.top;
    return { x: (cx - this.panX) / this.zoom, y: (cy - this.panY) / this.zoom, cx, cy };
  }

  // ---- pointer ------------------------------------------------------------------------

  bind() {
    const vp = this.el.viewport;
    vp.addEventListener('pointerdown', e => this.down(e));
    vp.addEventListener('pointermove', e => this.move(e));
    vp.addEventListener('pointerup', e => this.up(e));
    vp.addEventListener('pointercancel', e => this.up(e, true));
    vp.addEventListener('pointerleave', () => { this.mouse = null; this.drawCursor(); this.emit('hover', null); });
    vp.addEventListener('contextmenu', e => e.preventDefault());
    vp.addEventListener('wheel', e => {
      e.preventDefault();
      const p = this.toImage(e);
      this.zoomAt(Math.exp(-e.deltaY * (e.deltaMode ? 0.05 : 0.0015)), p.cx, p.cy);
    }, { passive: false });
    // the painting area changed size (the window, the guide above it, a
    // wrapped toolbar): a view still fitted to the window is fitted again
    new ResizeObserver(() => { this.resizeCursor(); if (this.fitted && this.k >= 0) this.fitToWindow(); }).observe(vp);
    this.watchRatio();
  }

  panning(e) { return this.tool === 'pan' || this.spaceHeld || e.button === 1 || !this.session.canPaint && this.tool !== 'pick'; }

  down(e) {
    if (this.k < 0 || !this.view.disp) return;
    this.el.viewport.focus({ preventScroll: true });
    const p = this.toImage(e);
    if (e.button === 2) return;
    this.el.viewport.setPointerCapture(e.pointerId);
    if (this.panning(e)) {
      this.drag = { x: e.clientX, y: e.clientY, px: this.panX, py: this.panY };
      this.el.viewport.classList.add('pan');
      return;
    }
    if (this.tool === 'pick') { this.pick(p); return; }
    if (!this.session.canPaint || this.view.state === 'none') return;
    const b = this.getBrush();
    const s = { mode: b.mode, color: b.color, diameter: b.diameter, kappa: b.kappa, scale: b.scale, opacity: b.opacity, points: [] };
    const v = this.view;
    this.live = new LiveStroke(s, cloneImage(v.disp), v.base);
    this.live.k = this.k;
    this.session.liveHook = {
      k: this.k,
      rebase: disp => {       // the view changed under the stroke (another person's stroke)
        const pts = this.live.s.points.slice();
        const s2 = Object.assign({}, this.live.s, { points: [] });
        const l2 = new LiveStroke(s2, cloneImage(disp), this.view.base);
        l2.k = this.k;
        for (const q of pts) l2.add(q[0], q[1], disp);
        this.live = l2;
      },
    };
    this.addPoint(p.x, p.y);
  }

  addPoint(x, y) {
    const pts = this.live.s.points;
    // a point per half pixel is all the brush can show; fewer points, same stroke
    x = Math.round(x * 100) / 100; y = Math.round(y * 100) / 100;
    if (pts.length) {
      const l = pts[pts.length - 1];
      if ((l[0] - x) ** 2 + (l[1] - y) ** 2 < 0.25) return;
    }
    const box = this.live.add(x, y, this.view.disp);
    if (box) { this.redraw(box); this.emit('painting', this.k); }
    if (pts.length >= 4000) { this.finishLive(); }
  }

  move(e) {
    const p = this.toImage(e);
    this.mouse = p;
    if (this.drag) {
      this.panX = this.drag.px + e.clientX - this.drag.x;
      this.fitted = false;
      this.panY = this.drag.py + e.clientY - this.drag.y;
      this.applyTransform();
      return;
    }
    if (this.live) {
      const evs = e.getCoalescedEvents ? e.getCoalescedEvents() : [e];
      for (const ce of evs.length ? evs : [e]) { const q = this.toImage(ce); this.addPoint(q.x, q.y); }
    }
    this.drawCursor();
    this.hover(p);
  }

  up(e, cancel) {
    if (this.drag) { this.drag = null; this.el.viewport.classList.remove('pan'); return; }
    if (this.live) {
      if (cancel) this.cancelLive(); else this.finishLive();
    }
  }

  finishLive() {
    const live = this.live;
    this.live = null;
    this.session.liveHook = null;
    if (!live || !live.s.points.length) return;
    this.session.commitStroke(live.k, live.s).catch(err => this.emit('error', err));
  }

  cancelLive() {
    if (!this.live) return;
    const v = this.session.views[this.live.k];
    this.live = null;
    this.session.liveHook = null;
    this.session.rebuildDisp(v);
  }

  hover(p) {
    const v = this.view;
    if (!v || !v.disp) return;
    const x = Math.floor(p.x), y = Math.floor(p.y);
    if (x < 0 || y < 0 || x >= v.disp.w || y >= v.disp.h) { this.emit('hover', null); return; }
    const o = 3 * (y * v.disp.w + x);
    this.emit('hover', { x, y, rgb: [v.disp.data[o], v.disp.data[o + 1], v.disp.data[o + 2]] });
  }

  pick(p) {
    const v = this.view;
    const x = Math.floor(p.x), y = Math.floor(p.y);
    if (x < 0 || y < 0 || x >= v.disp.w || y >= v.disp.h) return;
    const o = 3 * (y * v.disp.w + x);
    this.emit('pick', [v.disp.data[o], v.disp.data[o + 1], v.disp.data[o + 2]]);
  }

  // ---- brush cursor -------------------------------------------------------------------

  resizeCursor() {
    const r = this.el.viewport.getBoundingClientRect(), dpr = devicePixelRatio || 1;
    this.el.cursor.width = Math.max(1, Math.round(r.width * dpr));
    this.el.cursor.height = Math.max(1, Math.round(r.height * dpr));
    this.el.cursor.style.width = r.width + 'px';
    this.el.cursor.style.height = r.height + 'px';
    this.drawCursor();
  }

  drawCursor() {
    const c = this.el.cursor, g = c.getContext('2d'), dpr = c.width / Math.max(1, parseFloat(c.style.width) || c.width);
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.clearRect(0, 0, c.width, c.height);
    g.setTransform(dpr, 0, 0, dpr, 0, 0);          // drawn in CSS pixels
    const m = this.mouse;
    if (!m || this.drag || this.tool === 'pan' || this.spaceHeld || !this.session.canPaint && this.tool !== 'pick') return;
    const sx = this.panX + m.x * this.zoom, sy = this.panY + m.y * this.zoom;
    g.lineWidth = 1;
    if (this.tool === 'pick') {
      g.strokeStyle = '#fff';
      g.beginPath(); g.arc(sx, sy, 6, 0, 7); g.moveTo(sx - 10, sy); g.lineTo(sx + 10, sy); g.moveTo(sx, sy - 10); g.lineTo(sx, sy + 10); g.stroke();
      return;
    }
    const b = this.getBrush();
    const r = Math.max(1, b.diameter / 2 * this.zoom);
    g.strokeStyle = 'rgba(0,0,0,.8)'; g.beginPath(); g.arc(sx, sy, r + 1, 0, 7); g.stroke();
    g.strokeStyle = 'rgba(255,255,255,.95)'; g.beginPath(); g.arc(sx, sy, r, 0, 7); g.stroke();
    // where the weight has fallen to half of the opacity: the gaussian's feel
    if (b.kappa > 0) {
      const dh = Math.log(2) / b.kappa;
      if (dh < b.diameter / 2) {
        g.setLineDash([3, 3]); g.strokeStyle = 'rgba(255,255,255,.5)';
        g.beginPath(); g.arc(sx, sy, dh * this.zoom, 0, 7); g.stroke(); g.setLineDash([]);
      }
    }
    g.fillStyle = '#fff'; g.fillRect(sx - 0.5, sy - 0.5, 1, 1);
  }
}
