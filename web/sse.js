// sse.js: a server-sent events client on fetch(), so the stream can carry
// headers, report why it failed, and resume exactly where it stopped.
//
// The stream keeps the last event id it saw and sends it as Last-Event-ID
// (and ?since=) whenever it connects again: glintd then replays exactly the
// events after it (events.h: no duplicates, no gaps).  It reconnects after
// a network error, an end of stream or a 5xx, waiting `retry` ms (the
// server's "retry:" field, else 2 s; the first retry is quick).  A 4xx is
// final: the token or the session is wrong and retrying cannot help.
//
// The handler.  onEvent(type, data, id) is called once per event, in the
// order received, and synchronously: the stream reads on as soon as it
// returns.  It returns 'stop' to close the stream for good (after a job's
// last event: nothing follows it, so connecting again has nothing to
// deliver), anything else to go on.  It must not be an
// async function: its promise would come back before its work is done,
// so the decision to stop would be lost and the stream would reconnect
// forever.  Work that needs to wait (reading what the event names) is
// started from the handler, which still returns 'stop' or not at once; a
// handler that returns a promise anyway is a bug, and the stream stops
// with state 'failed' saying so rather than run on unchecked.  A handler
// that throws keeps the event unconsumed: the stream reconnects from the
// last event handled (session.js relies on this after a gap).
// opts.final lists event types after which the stream is closed whatever
// the handler returns (a job's "done" and "failed").
//
// States (onState): connecting, open, reconnecting (detail: ms to wait),
// failed (detail: why; final), closed (stopped; final).

export class EventStream {
  // url: without since/token; opts: {headers, since, onEvent(type, data, id),
  // onState(state, detail), query, final: [event types]}
  constructor(url, opts) {
    this.url = url;
    this.opts = opts;
    this.lastId = opts.since != null ? String(opts.since) : '';
    this.retry = 2000;
    this.stopped = false;
    this.ctrl = null;
    this.failures = 0;
    this.state = 'idle';
    this.connects = 0;
  }

  setState(s, detail) {
    this.state = s;
    if (this.opts.onState) this.opts.onState(s, detail);
  }

  start() { this.stopped = false; this.loop(); return this; }

  // Close for good: no reconnection after this (state 'closed', or
  // 'failed' with the reason when called as fail()).
  stop() { this.halt('closed'); }

  fail(detail) { this.halt('failed', detail); }

  halt(state, detail) {
    if (this.stopped && (this.state === 'closed' || this.state === 'failed')) return;
    this.stopped = true;
    if (this.ctrl) this.ctrl.abort();
    if (this.timer) clearTimeout(this.timer);
    this.setState(state, detail);
  }

  // Drop the connection as a network failure would (used by tests and by
  // gap recovery); the stream comes back from lastId.
  drop(since) {
    if (since != null) this.lastId = String(since);
    if (this.ctrl) this.ctrl.abort('drop');
  }

  async loop() {
    while (!this.stopped) {
      const ok = await this.once();
      if (this.stopped || ok === 'final') return;
      this.failures++;
      const wait = this.failures === 1 ? 250 : Math.min(this.retry, 500 * this.failures);
      this.setState('reconnecting', wait);
      await new Promise(res => { this.timer = setTimeout(res, wait); });
    }
  }

  async once() {
    this.ctrl = new AbortController();
    const q = new URLSearchParams(this.opts.query || {});
    if (this.lastId !== '') q.set('since', this.lastId);
    const headers = Object.assign({ Accept: 'text/event-stream' }, this.opts.headers || {});
    if (this.lastId !== '') headers['Last-Event-ID'] = this.lastId;
    let r;
    this.setState('connecting');
    try {
      r = await fetch(this.url + (q.toString() ? '?' + q : ''), { headers, signal: this.ctrl.signal, cache: 'no-store' });
    } catch (e) {
      return 'retry';
    }
    if (!r.ok) {
      let detail = r.statusText;
      try { const p = await r.json(); detail = p.detail || p.title || detail; } catch (_) { /* not JSON */ }
      if (r.status >= 400 && r.status < 500) { this.fail(detail); return 'final'; }
      return 'retry';
    }
    this.connects++;
    this.setState('open');
    const reader = r.body.getReader();
    const dec = new TextDecoder();
    let buf = '', ev = { type: '', data: [], id: null };
    try {
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        this.failures = 0;
        buf += dec.decode(value, { stream: true });
        let nl;
        while ((nl = buf.search(/\r\n|\n|\r/)) >= 0) {
          const line = buf.slice(0, nl);
          buf = buf.slice(nl + (buf[nl] === '\r' && buf[nl + 1] === '\n' ? 2 : 1));
          if (line === '') {
            if (ev.data.length) this.dispatch(ev);
            if (this.stopped) return 'final';
            ev = { type: '', data: [], id: null };
            continue;
          }
          if (line[0] === ':') continue;
          const c = line.indexOf(':');
          const field = c < 0 ? line : line.slice(0, c);
          let val = c < 0 ? '' : line.slice(c + 1);
          if (val[0] === ' ') val = val.slice(1);
          if (field === 'data') ev.data.push(val);
          else if (field === 'event') ev.type = val;
          else if (field === 'id') ev.id = val;
          else if (field === 'retry' && /^\d+$/.test(val)) this.retry = +val;
        }
      }
    } catch (e) {
      /* aborted or the connection broke */
    }
    return 'retry';
  }

  dispatch(ev) {
    let data = ev.data.join('\n');
    try { data = JSON.parse(data); } catch (_) { /* keep text */ }
    const type = ev.type || 'message';
    const ret = this.opts.onEvent(type, data, ev.id);
    // The id moves only after the event was handled, so a handler that
    // throws does not lose it.
    if (ev.id !== null) this.lastId = ev.id;
    if (ret && typeof ret.then === 'function') {
      this.fail(`the handler of "${type}" events returned a promise; it must answer at once (see sse.js)`);
    } else if (ret === 'stop' || (this.opts.final && this.opts.final.includes(type))) {
      this.stop();
    }
  }
}
