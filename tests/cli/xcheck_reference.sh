#!/usr/bin/env bash
# Cross-check glint's factors against the independent numpy implementation
# in ../shared/reference on identical samples (Cook-Torrance GGX 0.5, 12
# views at 64x64, R = 64, lambda = 0.1, log(0.1 + f)).  Skips (status 77)
# when the reference or numpy is absent.  usage: xcheck_reference.sh glint SRCDIR
set -u
G=${1:?}; SRC=${2:?}
REF=${GLINT_REFERENCE_DIR:-$SRC/../shared/reference}
PY=/usr/bin/python3
if [ ! -f "$REF/hf_ref.py" ] || ! $PY -c 'import numpy, scipy' 2>/dev/null; then
  echo "skipped: no reference at $REF or no numpy/scipy for $PY"
  exit 77
fi
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
set -e
"$G" scene create --size 64 -o "$T/scene.json" >/dev/null
"$G" paint "$T/scene.json" --brdf ct0.5 -o "$T/paint" >/dev/null
"$G" export-samples "$T/scene.json" --paintings "$T/paint" -o "$T/s.txt" >/dev/null
"$G" fit-samples "$T/s.txt" -o "$T/mat" --res 64 --lambda 0.1 --map add:0.1 --no-cache \
    --eval "$T/s.txt" --eval-out "$T/glint.txt" >/dev/null
$PY "$REF/hf_ref.py" fit-samples "$T/s.txt" --R 64 --lam 0.1 --mapping add --json "$T/ref.json" \
    --eval "$T/s.txt" --eval-out "$T/ref.txt" >/dev/null
set +e
$PY - "$T" <<'PY'
import json, sys
import numpy as np
t = sys.argv[1]
ref = json.load(open(f"{t}/ref.json"))["factors_log_canonical_gauge"]
mine = json.load(open(f"{t}/mat/material.json"))["log_factors"]
worst = 0.0
for k in "pqr":
    a = np.array(mine[k])[:, 0]
    b = np.array(ref["log_" + k])
    worst = max(worst, float(np.abs(a - b).max()))
va, vb = np.loadtxt(f"{t}/glint.txt"), np.loadtxt(f"{t}/ref.txt")
dv = float(np.abs(va - vb).max())
# Both read the same 9-digit sample text; glint stores the geometry in
# float, so projections differ by ~1e-8 and log-factors by ~1e-7.
print(f"max |log-factor difference| {worst:.2e} (tol 1e-5), max |value difference| {dv:.2e} (tol 1e-5)")
ok = worst <= 1e-5 and dv <= 1e-5
print("1 passed, 0 failed" if ok else "0 passed, 1 failed")
sys.exit(0 if ok else 1)
PY
