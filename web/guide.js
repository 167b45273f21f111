// guide.js: the first-visit guide: what to paint, what each kind of method
// can represent, how to judge the result.  It stands in a corner of the
// painting area without blocking it (only its buttons take the pointer),
// goes away for good with "Got it" (remembered in this browser), and comes
// back from the help dialog.

const $ = id => document.getElementById(id);
const KEY = 'glint.guide';

export function bindGuide(canPaint) {
  const g = $('guide');
  const seen = () => { try { return localStorage.getItem(KEY) === 'seen'; } catch (_) { return false; } };
  g.classList.toggle('hidden', !canPaint || seen());
  // a press on its buttons is not a stroke on the painting below
  g.onpointerdown = e => e.stopPropagation();
  $('guide-ok').onclick = () => {
    g.classList.add('hidden');
    try { localStorage.setItem(KEY, 'seen'); } catch (_) { /* private mode: shown again next time */ }
  };
  $('guide-later').onclick = () => g.classList.add('hidden');
  $('guide-show').onclick = () => { $('help-dlg').classList.add('hidden'); g.classList.remove('hidden'); };
}
