// session.js: one painting session kept in step with glintd.
//
// Model.  Every view has
//   conf  the image as the server has it after every event up to v.seq
//         (float RGB, bit for bit what glintd stores),
//   disp  conf with this client's strokes that are sent but not yet
//         confirmed drawn on top (what the canvas shows),
//   base  the scene's base render (erase strokes bring it back).
// The session's event stream (strokes, paintings, fits; one sequence for
// the whole session) is applied in sequence order: a stroke with the same
// brush code as the server (brush.js), a painting by reading the new image.
// This client's strokes carry a tag (client id + counter), so their echo is
// recognized whether it comes before or after the POST's answer.
//
// Consistent reads.  A painting read at an unknown moment is pinned to the
// sequence: read the image (its X-Glint-Version), then the session (its
// last_seq L and every view's version); if the versions agree, no event
// touched the view in between, so the image is exactly the view at L:
// events up to L are in it, events after L are not.  Otherwise read again.
//
// Undo (each person undoes their own actions, per view, newest first).
// glintd's log is append-only, so an undo is a new event that everyone
// sees: the studio PUTs the view's painting as it would be without the
// action, i.e. the image just before the action (kept for its pixel box)
// with every later stroke on the view replayed on top (brush.js, the same
// math as the server).  Everyone receives it as a "painting" event.  Redo
// posts the stroke again (or PUTs the upload again), on top of the view as
// it is then.  An action can no longer be undone once another participant
// replaced the whole view after it (a photo upload or their own undo): the
// studio says so instead of guessing.  Undo history lives in the page: a
// reload keeps the paintings, not the undo stack.

import { applyStroke, strokeBox, strokeJSON } from './brush.js';
import { encodeEXR } from './exr.js';
import { cloneImage, cropBox, decodeImage, pasteBox } from './image.js';
import { EventStream } from './sse.js';
import { API, ApiError } from './api.js';
import { CLASS } from './requests.js';

const UNDO_DEPTH = 64;

function randomId(n) {
  const a = new Uint8Array(n); crypto.getRandomValues(a);
  return Array.from(a, b => b.toString(16).padStart(2, '0')).join('');
}

export class Session extends EventTarget {
  constructor(api, id, token, name) {
    super();
    this.api = api;
    this.id = id;
    this.token = token;
    this.name = name;
    this.client = randomId(4);       // tags: "<client>-<n>"
    this.tagSeq = 0;
    this.views = [];
    this.appliedSeq = 0;             // last session event applied (in order)
    this.activity = [];              // recent events, newest last
    this.writeChain = Promise.resolve();
    this.stream = null;
    this.presence = [];
    this.puts = new Map();           // seq -> image of our own PUTs
    this.stats = { strokes: 0, paintings: 0, duplicates: 0, gaps: 0, reloads: 0 };
    this.closed = false;
  }

  // A closed session tells nobody anything: reads still in flight when the
  // studio closes it (a reload on new links) finish without a listener.
  emit(type, detail) { if (!this.closed) this.dispatchEvent(new CustomEvent(type, { detail })); }

  get canPaint() { return this.doc && this.doc.access === 'paint'; }

  // Load the session, its scene and view `first` (the paintable view);
  // the others follow in the background (loadRest).  The scene and the
  // first view's images are read at the same time.
  // A refusal of the session document itself (401, 403, 404: the link's
  // token or id is wrong) comes back marked e.access, for app.js to say so.
  async open(first) {
    try {
      this.doc = await this.api.session(this.id);
    } catch (e) {
      if (e instanceof ApiError && [401, 403, 404].includes(e.status)) e.access = true;
      throw e;
    }
    let k0 = Number.isInteger(first) && first >= 0 ? first : 0;
    const sceneP = this.loadScene(this.doc.scene_id);
    const readP = this.readView(k0, this.doc, null).catch(e => e);
    this.scene = await sceneP;
    const n = this.scene.views.length;
    for (let k = 0; k < n; k++)
      this.views.push({ k, conf: null, disp: null, base: null, seq: 0, version: 0, state: 'none', queue: [],
                        pending: [], history: [], undo: [], redo: [], painted: false });
    for (const p of this.doc.paintings || []) if (this.views[p.view]) this.views[p.view].painted = true;
    this.loadSeq = this.doc.last_seq;
    if (k0 >= n) { k0 = 0; await this.loadViews([0], this.doc); return k0; }
    const got = await readP;
    if (got instanceof Error) throw got;
    this.views[k0].state = 'loading';
    if (!this.install(got, this.doc)) await this.loadViews([k0], null, 1);
    return k0;
  }

  // Scenes never change: their documents are kept in the browser.
  async loadScene(id) {
    const key = 'glint.scene.' + id;
    try {
      const c = JSON.parse(localStorage.getItem(key) || 'null');
      if (c && c.id === id && Array.isArray(c.views) && c.width > 0) return c;
    } catch (_) { /* read it again */ }
    const sc = await this.api.scene(id);
    try { localStorage.setItem(key, JSON.stringify(sc)); } catch (_) { /* full: fine */ }
    return sc;
  }

  loadRest() {
    const ks = this.views.filter(v => v.state === 'none').map(v => v.k);
    return ks.length ? this.loadViews(ks, null) : Promise.resolve();
  }

  // ---- consistent view reads ----------------------------------------------------------
  //
  // A session document (its last_seq L and every view's painting version)
  // read BEFORE a view's image pins that image: if the image's version is
  // the one the document lists, no event touched the view between the two
  // reads, so the image is the view exactly as of L: events up to L are in
  // it, later ones are not.  A view the document lists as never painted is
  // its base render as of L.  On a mismatch, read again.

  async fetchImage(k) {
    // through the studio's image queue, before previews and reference renders
    const r = await this.api.images.run(null, signal => this.api.painting(this.id, k, 'exr', signal), { cls: CLASS.paint });
    const version = +(r.headers.get('X-Glint-Version') || 0);
    return { im: await decodeImage(await r.arrayBuffer()), version };
  }

  async fetchBase(k) {
    const r = await this.api.images.run(null, signal => this.api.base(this.doc.scene_id, k, 'exr', signal), { cls: CLASS.paint });
    return decodeImage(await r.arrayBuffer());
  }

  async readView(k, doc, base) {
    const listed = (doc.paintings || []).find(p => p.view === k);
    if (!listed && Array.isArray(doc.paintings)) {
      const b = base || await this.fetchBase(k);
      return { k, im: cloneImage(b), base: b, version: 0 };
    }
    const [img, b] = await Promise.all([this.fetchImage(k), base || this.fetchBase(k)]);
    return { k, im: img.im, base: b, version: img.version };
  }

  // Take a read view if the document pins it (see above); false if not.
  install(got, doc, force) {
    const v = this.views[got.k];
    const listed = (doc.paintings || []).find(p => p.view === got.k);
    v.base = got.base;
    if (!force && (listed ? listed.version : 0) !== got.version) return false;
    v.conf = got.im;
    v.seq = doc.last_seq;
    v.version = got.version;
    const painted = !v.painted && got.version > 0;
    v.painted = v.painted || got.version > 0;
    v.state = 'ready';
    const q = v.queue; v.queue = [];
    for (const ev of q) this.applyViewEvent(v, ev);
    this.rebuildDisp(v);
    this.emit('view', { k: got.k, box: null });
    if (painted) this.emit('painted', { k: got.k });
    return true;
  }

  // Read views ks (events for them wait in their queues meanwhile).
  async loadViews(ks, doc, tries) {
    tries = tries || 0;
    for (const k of ks) this.views[k].state = 'loading';
    if (!doc) doc = await this.api.session(this.id);
    const got = await Promise.all(ks.map(k => this.readView(k, doc, this.views[k].base)));
    const retry = [];
    for (const g of got) if (!this.install(g, doc, tries >= 6)) retry.push(g.k);
    if (retry.length) await this.loadViews(retry, null, tries + 1);
  }

  // ---- the event stream -------------------------------------------------------------

  connect() {
    const since = Math.max(0, (this.loadSeq || 0) - 200); // recent history for the activity list
    this.appliedSeq = since;
    this.stream = new EventStream(`${API}/sessions/${this.id}/events`, {
      headers: { 'X-Glint-Token': this.token },
      query: { name: this.name },
      since,
      onEvent: (type, data, id) => this.onStreamEvent(type, data, id),
      onState: (s, d) => this.emit('connection', { state: s, detail: d }),
    }).start();
  }

  onStreamEvent(type, data, id) {
    if (type === 'presence') {
      this.presence = data.clients || [];
      this.emit('presence', this.presence);
      return;
    }
    if (typeof data !== 'object' || data === null || typeof data.seq !== 'number') return;
    const ev = data;
    if (ev.seq <= this.appliedSeq) { this.stats.duplicates++; return; }  // replayed: already applied
    if (ev.seq !== this.appliedSeq + 1) {
      // a gap: should never happen (glintd replays from Last-Event-ID), but
      // if it does, read again from the last event applied
      this.stats.gaps++;
      this.stream.drop(this.appliedSeq);
      throw new Error('gap');
    }
    this.appliedSeq = ev.seq;
    this.activity.push(ev);
    if (this.activity.length > 300) this.activity.splice(0, this.activity.length - 300);
    let painted = false;
    if (ev.type === 'stroke' || ev.type === 'painting') {
      const v = this.views[ev.view];
      if (v) {
        painted = !v.painted;
        v.painted = true;
        if (v.state === 'loading' || v.state === 'putting') v.queue.push(ev);
        else if (v.state === 'ready') this.applyViewEvent(v, ev);
      }
    }
    if (painted) this.emit('painted', { k: ev.view });
    this.emit('event', ev);
  }

  // Whether a fit has something to work with: a view glintd has as painted,
  // or one with this client's stroke on its way there (a fit is sent after
  // the writes before it, see FitPanel.run).
  hasPainting() { return this.views.some(v => v.painted || v.pending.length > 0); }

  // Apply one event to a ready view.
  applyViewEvent(v, ev) {
    const mineTag = ev.type === 'stroke' && ev.data && typeof ev.data.tag === 'string' && ev.data.tag.startsWith(this.client + '-');
    if (ev.seq <= v.seq) {               // already in the image we read
      if (mineTag) this.confirmPending(v, ev, null);
      return;
    }
    if (v.state !== 'ready') { v.queue.push(ev); return; }
    if (ev.type === 'stroke') {
      const s = ev.data;
      const box = strokeBox(s, v.conf.w, v.conf.h);
      const before = box && mineTag ? cropBox(v.conf, box) : null;
      applyStroke(s, v.conf, v.base);
      this.stats.strokes++;
      v.seq = ev.seq;
      v.history.push({ seq: ev.seq, kind: 'stroke', stroke: s, mine: mineTag, tag: s.tag });
      if (mineTag) this.confirmPending(v, ev, before ? { box, data: before } : null);
      this.rebuildDisp(v, box);
    } else if (ev.type === 'painting') {
      const own = this.puts.get(ev.seq);
      if (own) {
        this.puts.delete(ev.seq);
        v.conf = cloneImage(own.image);
        v.seq = ev.seq;
        v.version = ev.data.version;
        v.history.push({ seq: ev.seq, kind: 'painting', mine: true, undoPut: own.undo, image: own.undo ? null : own.image });
        this.rebuildDisp(v);
      } else {
        v.history.push({ seq: ev.seq, kind: 'painting', mine: false });
        this.stats.reloads++;
        v.conf = null;
        this.loadViews([v.k]).catch(e => this.emit('error', e));
      }
    }
    if (v.history.length > 2000) v.history.splice(0, v.history.length - 2000);
  }

  confirmPending(v, ev, before) {
    const i = v.pending.findIndex(p => p.tag === ev.data.tag);
    const p = i >= 0 ? v.pending.splice(i, 1)[0] : null;
    const entry = v.undo.find(u => u.tag === ev.data.tag) || (p && p.entry);
    if (entry) {
      entry.seq = ev.seq;
      entry.before = before;           // null when the stroke came in a read image: cannot undo exactly
    }
    if (!v.pending.length) this.emit('settled', { k: v.k });
  }

  // disp = conf + pending strokes.
  rebuildDisp(v, box) {
    if (!v.conf) return;
    if (!v.disp || v.disp.w !== v.conf.w || !box) v.disp = cloneImage(v.conf);
    else {
      // only the box changed in conf; pending strokes may cover more
      v.disp.data.set(v.conf.data);
    }
    for (const p of v.pending) applyStroke(p.stroke, v.disp, v.base);
    // a stroke being drawn is redrawn over the new image
    if (this.liveHook && this.liveHook.k === v.k) this.liveHook.rebase(v.disp);
    this.emit('view', { k: v.k, box: box && !v.pending.length && !this.liveHook ? box : null });
  }

  // ---- writing ------------------------------------------------------------------------

  // Writes of this client go out one after the other, in the order made.
  chain(fn) {
    const p = this.writeChain.then(fn);
    this.writeChain = p.catch(() => {});
    return p;
  }

  // "<client>-<n>~<name>": the client part recognizes our own echoes, the
  // name tells the others who painted (glintd keeps up to 64 bytes).
  newTag() {
    let t = this.client + '-' + (++this.tagSeq) + '~' + String(this.name || '').replace(/[\u0000-\u001f~]/g, '');
    while (new TextEncoder().encode(t).length > 64) t = t.slice(0, -1);
    return t;
  }

  // A stroke finished on the canvas: it is already in v.disp (drawn live);
  // record it as pending and send it.
  commitStroke(k, s, { isRedo } = {}) {
    const v = this.views[k];
    const tag = this.newTag();
    const json = strokeJSON(s, tag);
    const entry = { kind: 'stroke', tag, stroke: strokeJSON(s), seq: null, before: null };
    v.pending.push({ tag, stroke: json, entry });
    v.undo.push(entry);
    if (v.undo.length > UNDO_DEPTH) v.undo.shift();
    if (!isRedo) v.redo = [];
    this.emit('history', { k });
    return this.chain(async () => {
      try {
        const r = await this.api.postStrokes(this.id, k, [json]);
        entry.seq = entry.seq || r.first_seq;
        return r;
      } catch (e) {
        // refused: take it off the canvas and the undo stack
        const i = v.pending.findIndex(p => p.tag === tag);
        if (i >= 0) v.pending.splice(i, 1);
        const j = v.undo.indexOf(entry);
        if (j >= 0) v.undo.splice(j, 1);
        this.rebuildDisp(v);
        this.emit('history', { k });
        throw e;
      }
    });
  }

  // Draw a stroke on disp right away and send it (for strokes not drawn
  // live, e.g. redo).
  sendStroke(k, s, opt) {
    const v = this.views[k];
    const box = applyStroke(s, v.disp, v.base);
    this.emit('view', { k, box });
    return this.commitStroke(k, s, opt);
  }

  // Wait until this client's writes on view k are answered and echoed.
  async settle(k, timeoutMs) {
    await this.writeChain;
    const v = this.views[k];
    const t0 = performance.now();
    while ((v.pending.length || v.state !== 'ready' || this.puts.size) && performance.now() - t0 < (timeoutMs || 5000))
      await new Promise(r => setTimeout(r, 20));
    if (v.pending.length || v.state !== 'ready') throw new Error('the server has not confirmed the last stroke yet; try again');
  }

  // PUT an image as view k's painting; the echo is recognized by its seq.
  // (encoded: the image's OpenEXR file when the caller has it already)
  async putImage(k, image, undo, encoded) {
    const v = this.views[k];
    const bytes = encoded || encodeEXR(image);
    return this.chain(async () => {
      v.state = 'putting';              // events for the view wait until we know our seq
      try {
        const r = await this.api.putPainting(this.id, k, bytes);
        this.puts.set(r.seq, { image, undo });
        return r;
      } finally {
        v.state = v.conf ? 'ready' : 'loading';
        const q = v.queue; v.queue = [];
        if (v.state === 'ready') for (const ev of q) this.applyViewEvent(v, ev);
        else v.queue = q;
      }
    });
  }

  // A dropped photo (already at the raster size) becomes the painting;
  // encoded: its OpenEXR file, sent as it is (a finish glintd rendered).
  async uploadImage(k, image, encoded) {
    const v = this.views[k];
    await this.settle(k);
    const entry = { kind: 'painting', image, before: cloneImage(v.conf), seq: null };
    const r = await this.putImage(k, image, false, encoded);
    entry.seq = r.seq;
    v.undo.push(entry);
    if (v.undo.length > UNDO_DEPTH) v.undo.shift();
    v.redo = [];
    this.emit('history', { k });
    return r;
  }

  canUndo(k) { return this.canPaint && this.views[k] && this.views[k].undo.length > 0; }
  canRedo(k) { return this.canPaint && this.views[k] && this.views[k].redo.length > 0; }

  // Undo and redo run one after another: each takes the newest entry only
  // once the one before has put its image and left the stack, so two quick
  // presses take back two actions (taken at once, both read the same newest
  // entry: it was undone twice and the one under it dropped from the stack).
  undo(k) { return this.inTurn(() => this.undoNow(k)); }
  redo(k) { return this.inTurn(() => this.redoNow(k)); }
  inTurn(fn) {
    const p = (this.turns || Promise.resolve()).then(fn, fn);
    this.turns = p.catch(() => {});
    return p;
  }

  async undoNow(k) {
    const v = this.views[k];
    if (!v.undo.length) return null;
    await this.settle(k);
    const entry = v.undo[v.undo.length - 1];
    if (entry.seq == null || (entry.kind === 'stroke' && !entry.before)) {
      v.undo.pop(); this.emit('history', { k });
      throw new Error('this stroke reached the view through a fresh read, not step by step, so the studio cannot take it back exactly');
    }
    const later = v.history.filter(h => h.seq > entry.seq);
    if (later.some(h => h.kind === 'painting' && !h.mine)) {
      v.undo.length = 0; this.emit('history', { k });
      throw new Error('another participant replaced this view after your change (an upload or their undo), so it can no longer be undone');
    }
    const img = this.without(v, entry, later);
    const own = v.history.find(h => h.seq === entry.seq);
    if (own) own.removed = true;
    const baseSeq = v.seq;
    let r;
    try {
      r = await this.putImage(k, img, true);
    } catch (e) {
      if (own) own.removed = false;
      throw e;
    }
    await this.repairClobbered(v, baseSeq, r.seq);
    v.undo.pop();
    v.redo.push(entry);
    this.emit('history', { k });
    return r;
  }

  // The view as it would be without `entry`: its "before" pixels with every
  // later, still standing action replayed on top, inside its box.
  without(v, entry, later) {
    const img = cloneImage(v.conf);
    let box;
    if (entry.kind === 'stroke') { box = entry.before.box; pasteBox(img, box, entry.before.data); }
    else { box = [0, 0, img.w - 1, img.h - 1]; img.data.set(entry.before.data); }
    for (const h of later) {
      if (h.removed || h.undoPut) continue;
      if (h.kind === 'stroke') applyStroke(h.stroke, img, v.base, box);
      else if (h.kind === 'painting' && h.image) pasteBox(img, box, cropBox(h.image, box));
    }
    return img;
  }

  // glintd has no conditional PUT: a stroke that landed between our read
  // and our PUT was overwritten by it.  Put it back (replay it on top).
  async repairClobbered(v, baseSeq, putSeq) {
    const t0 = performance.now();
    while ((this.appliedSeq < putSeq || this.puts.has(putSeq)) && performance.now() - t0 < 3000)
      await new Promise(r => setTimeout(r, 10));
    // strokes between the image we computed from and our PUT
    const lost = this.activity.filter(e => e.view === v.k && e.type === 'stroke' && e.seq > baseSeq && e.seq < putSeq);
    if (!lost.length) return;
    const img = cloneImage(v.conf);
    for (const e of lost) applyStroke(e.data, img, v.base);
    await this.putImage(v.k, img, true);
  }

  async redoNow(k) {
    const v = this.views[k];
    const entry = v.redo.pop();
    if (!entry) return null;
    this.emit('history', { k });
    if (entry.kind === 'stroke') return this.sendStroke(k, entry.stroke, { isRedo: true });
    await this.settle(k);
    const e2 = { kind: 'painting', image: entry.image, before: cloneImage(v.conf), seq: null };
    const r = await this.putImage(k, entry.image, false);
    e2.seq = r.seq;
    v.undo.push(e2);
    this.emit('history', { k });
    return r;
  }

  close() { this.closed = true; if (this.stream) this.stream.stop(); }
}
