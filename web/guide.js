// guide.js: the first-visit guide: what to paint, what each kind of method
// can represent, how to judge the result.  It is docked above the painting
// area, in the page's flow (never over the canvas, at any window size: the
// painting area shrinks to make room and the view is fitted again), goes
// away for good with "Got it" (remembered in this browser), for this visit
// with "Later", and comes back from the help dialog.

const $ = id => document.getElementById(id);
const KEY = 'glint.guide';

// canPaint: the guide is for those who paint.
export function bindGuide(canPaint) {
  const g = $('guide');
  const seen = () => { try { return localStorage.getItem(KEY) === 'seen'; } catch (_) { return false; } };
  const show = on => g.classList.toggle('hidden', !on);
  g.classList.toggle('hidden', !canPaint || seen());
  $('guide-ok').onclick = () => {
    show(false);
    try { localStorage.setItem(KEY, 'seen'); } catch (_) { /* private mode: shown again next time */ }
  };
  $('guide-later').onclick = () => show(false);
  $('guide-show').onclick = () => { $('help-dlg').classList.add('hidden'); show(true); };
}
