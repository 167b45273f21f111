// requests.js: the studio's image requests (previews, the ball, reference
// renders for the error table, paintings, base renders, textures) through
// one queue, so that
//  - a request names its purpose ("preview", "ball", "reference:view3"): a
//    new request of the same purpose aborts the one before (AbortController:
//    the browser closes its connection, and glintd frees its work slot),
//    queued or running;
//  - at most MAX renders (previews, the ball, reference renders) run at
//    once, and at most MAX reads of what painting needs (paintings, base
//    renders: only when the studio loads or resynchronises a view, so they
//    never wait behind a render that takes minutes): the browser opens six
//    connections to a host, and the rest stay free for strokes, fits and
//    the event stream;
//  - they start by class: paint reads, then what follows the mouse
//    (preview, ball), then reference renders, of which at most one runs at
//    once, sent with the HTTP Priority header u=6 (RFC 9218) so that glintd
//    runs them after interactive work;
//  - a request whose `current()` says it is no longer wanted is dropped
//    before it starts, and its answer is refused when it arrives (the
//    caller checks again before drawing: a request is for a material, a
//    view, an environment, and only an answer for the current ones is
//    drawn);
//  - a busy answer (503) is asked again after its Retry-After while it is
//    still wanted, the slot given to others meanwhile.
//
// run(purpose, fn, opt) returns fn's result; fn(signal, headers) does the
// fetch; opt.cls is one of CLASS, opt.current() says whether the answer is
// still wanted, opt.busy(error) hears of a busy answer that will be asked
// again.  A superseded or unwanted request rejects with an AbortError
// (isAbort), which callers drop silently.

export const MAX = 2;
const LOW_MAX = 1;
const RETRIES = 6;

export const CLASS = { paint: 0, interactive: 1, reference: 2 };

export function abortError(why) {
  return new DOMException(why || 'superseded', 'AbortError');
}

export function isAbort(e) {
  return !!e && (e.name === 'AbortError' || e.aborted === true);
}

export class Requests {
  constructor(max) {
    this.max = max || MAX;
    this.queue = [];             // waiting, in arrival order
    this.running = new Set();
    this.byPurpose = new Map();  // purpose -> its newest request
    this.stats = { started: 0, superseded: 0, dropped: 0, retried: 0, peak: 0 };
  }

  // Run fn for `purpose` (null: never superseded).  opt.cls: CLASS.*
  // (interactive); opt.current(): still wanted? (always).
  run(purpose, fn, opt = {}) {
    if (purpose != null) this.abort(purpose);
    const ctrl = new AbortController();
    const job = { purpose, fn, ctrl, cls: opt.cls != null ? opt.cls : CLASS.interactive,
                  current: opt.current || (() => true), busy: opt.busy, tries: 0, seq: this.seq = (this.seq || 0) + 1 };
    const p = new Promise((resolve, reject) => { job.resolve = resolve; job.reject = reject; });
    if (purpose != null) this.byPurpose.set(purpose, job);
    this.queue.push(job);
    this.pump();
    return p;
  }

  // Abort the request of `purpose`, queued or running.
  abort(purpose, why) {
    const job = this.byPurpose.get(purpose);
    if (job) this.cancel(job, why || 'superseded');
  }

  // Abort every request whose purpose starts with prefix ("reference:").
  abortPrefix(prefix, why) {
    for (const [p, job] of [...this.byPurpose]) if (p.startsWith(prefix)) this.cancel(job, why || 'superseded');
  }

  // How many run now, by class (for tests).
  counts() {
    const c = { running: this.running.size, queued: this.queue.length, paint: 0, interactive: 0, reference: 0 };
    for (const j of this.running) c[Object.keys(CLASS).find(k => CLASS[k] === j.cls)]++;
    return c;
  }

  cancel(job, why) {
    if (job.done) return;
    this.stats.superseded++;
    this.finish(job, null, abortError(why));
    job.ctrl.abort();
  }

  finish(job, value, err) {
    if (job.done) return;
    job.done = true;
    clearTimeout(job.timer);
    const i = this.queue.indexOf(job);
    if (i >= 0) this.queue.splice(i, 1);
    this.running.delete(job);
    if (job.purpose != null && this.byPurpose.get(job.purpose) === job) this.byPurpose.delete(job.purpose);
    if (err) job.reject(err); else job.resolve(value);
    this.pump();
  }

  // The next job to start: the best class first, arrival order within one.
  next() {
    let low = 0, paint = 0;
    for (const j of this.running) {
      if (j.cls === CLASS.reference) low++;
      if (j.cls === CLASS.paint) paint++;
    }
    const renders = this.running.size - paint;
    let best = null;
    for (const j of this.queue) {
      if (j.waiting) continue;                         // a busy answer's pause
      if (j.cls === CLASS.paint ? paint >= this.max : renders >= this.max) continue;
      if (j.cls === CLASS.reference && low >= LOW_MAX) continue;
      if (!best || j.cls < best.cls) best = j;
    }
    return best;
  }

  pump() {
    for (;;) {
      const job = this.next();
      if (!job) return;
      this.queue.splice(this.queue.indexOf(job), 1);
      if (!job.current()) { this.stats.dropped++; this.finish(job, null, abortError('no longer wanted')); continue; }
      this.start(job);
    }
  }

  async start(job) {
    this.running.add(job);
    this.stats.started++;
    this.stats.peak = Math.max(this.stats.peak, this.running.size - this.counts().paint);
    const headers = job.cls === CLASS.reference ? { Priority: 'u=6' } : {};
    let value, err = null;
    try { value = await job.fn(job.ctrl.signal, headers); } catch (e) { err = e; }
    if (job.done) return;                              // superseded meanwhile
    if (err && err.status === 503 && job.tries < RETRIES && job.current()) return this.later(job, err);
    if (!err && !job.current()) err = abortError('answer for what is no longer shown');
    this.finish(job, value, err);
  }

  // A busy answer: the slot goes to others, and the request is asked again
  // after the daemon's Retry-After while it is still wanted.
  later(job, err) {
    job.tries++;
    this.stats.retried++;
    if (job.busy) job.busy(err);
    this.running.delete(job);
    job.waiting = true;
    this.queue.push(job);
    const s = Math.min(10, Math.max(1, +(err.retryAfter || 2)));
    job.timer = setTimeout(() => { job.waiting = false; this.pump(); }, 1000 * s);
    this.pump();
  }
}
