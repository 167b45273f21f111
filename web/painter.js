// painter.js: the paint canvas of one view: zoom and pan, the brush cursor,
// strokes drawn as the pointer moves (brush.js LiveStroke on the view's
// displayed image, the same math the server will apply), the eyedropper and
// the overlays (base render, a dropped photo).
//
// The canvas holds the image at its own raster size (1 canvas pixel = 1
// image pixel) and is scaled by a CSS transform, so its pixels are exactly
// the 8-bit view of the floats (image.js) at any zoom.

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
    this.emit('zoom', this.zoom);
    this.drawCursor();
  }

  fitToWindow() {
    const vp = this.el.viewport.getBoundingClientRect();
    const w = this.el.paint.width, h = this.el.paint.height;
    let z = Math.min((vp.width - 24) / w, (vp.height - 24) / h);
    z = z >= 1 ? Math.floor(z * 4) / 4 : z;          // crisp steps when enlarging
    this.zoom = Math.max(0.1, z);
    this.panX = Math.round((vp.width - w * this.zoom) / 2);
    this.panY = Math.round((vp.height - h * this.zoom) / 2);
    this.applyTransform();
  }

  zoomAt(factor, cx, cy) {
    const vp = this.el.viewport.getBoundingClientRect();
    if (cx == null) { cx = vp.width / 2; cy = vp.height / 2; }
    const z = Math.min(32, Math.max(0.1, this.zoom * factor));
    const ix = (cx - this.panX) / this.zoom, iy = (cy - this.panY) / this.zoom;
    this.zoom = z;
    this.panX = cx - ix * z; this.panY = cy - iy * z;
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
    new ResizeObserver(() => this.resizeCursor()).observe(vp);
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
    const r = this.el.viewport.getBoundingClientRect();
    this.el.cursor.width = Math.max(1, Math.round(r.width));
    this.el.cursor.height = Math.max(1, Math.round(r.height));
    this.drawCursor();
  }

  drawCursor() {
    const c = this.el.cursor, g = c.getContext('2d');
    g.clearRect(0, 0, c.width, c.height);
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
