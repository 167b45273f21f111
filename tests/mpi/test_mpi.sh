#!/usr/bin/env bash
# glint-mpi against the single-process route, on loopback:
#   - `glint fit` builds and caches hf3's decomposition (the single-process
#     eig route) in one cache directory; `mpirun -np 2 glint-mpi decompose`
#     writes it for the same views and parameters into another;
#   - both files are found under the same key, and mpi_compare checks the
#     same decisions (rank, null and barely reached directions) and the
#     same operator to the perturbation bound it states;
#   - `glint fit` on glint-mpi's directory loads the decomposition from
#     disk (a cache hit, not a rebuild) and gives the same fit errors;
#   - settings: res 32 with lambda 0.1 (the default) on 2 ranks and on 4
#     (a 2 x 2 process grid); one painted view at
#     res 96 with lambda 0 on 3 ranks (a 1 x 3 grid; two ranks get no
#     view, hence no rows; 4 null and 1 barely reached directions: the
#     keep rules cut both on the gathered result as on one process);
#   - hf4 (--method hf4, hfx's normal form): 2 ranks at s_res 24, 3 ranks
#     at s_res 16 without smoothing of s; hf2d (the same normal form): 2
#     ranks with q 2D at res_2d 16, 3 ranks with all three 2D at 12; the
#     fit from glint-mpi's file against the single-process fit, factor by
#     factor;
#   - wrong input gives a clear message and status, never a hang.
# usage: test_mpi.sh path/to/glint path/to/glint-mpi path/to/mpi_compare
# Skips (77) when mpirun is absent.  Every mpirun runs under a timeout.
set -u
G=${1:?usage: test_mpi.sh glint glint-mpi mpi_compare}
GM=${2:?}
CMP=${3:?}
command -v mpirun >/dev/null 2>&1 || { echo "SKIP: mpirun not found"; exit 77; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
pass=0 fail=0
ok()  { pass=$((pass + 1)); echo "ok   $1"; }
bad() { fail=$((fail + 1)); echo "FAIL $1"; }

# Open MPI in a container: root allowed, more ranks than cores allowed,
# TCP over loopback only (no shared-memory transport, no other interface).
# (the same settings through the environment reach a program started
# without mpirun too: a singleton MPI job, as the error cases below run)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,tcp
export OMPI_MCA_btl_tcp_if_include=lo OMPI_MCA_oob_tcp_if_include=lo OPENBLAS_NUM_THREADS=1
MPIRUN=(timeout 60 mpirun --oversubscribe -x OPENBLAS_NUM_THREADS)
# field FILE NAME: a top-level field of a JSON report
field() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])' "$1" "$2"; }

"$G" scene create --size 96 -o "$T/scene.json" >/dev/null || { echo "FAIL scene create"; exit 1; }
"$G" paint "$T/scene.json" --brdf 'ct:rough=0.3' -o "$T/paint" >/dev/null ||
    { echo "FAIL paint"; exit 1; }

mkdir -p "$T/paint1" && cp "$T/paint/view_00".* "$T/paint1/"

# compare NAME NP PAINTINGS FIT-OPTIONS...: one setting end to end
compare() {
  local name=$1 np=$2 pdir=$3; shift 3
  local c0="$T/c0-$name" c1="$T/c1-$name"
  if ! "$G" fit "$T/scene.json" --paintings "$pdir" -o "$T/m0-$name" --cache-dir "$c0" "$@" \
       > "$T/f0-$name.json" 2>"$T/err"; then
    bad "$name: single-process fit"; sed 's/^/    /' "$T/err"; return
  fi
  if ! "${MPIRUN[@]}" -np "$np" "$GM" decompose "$T/scene.json" --paintings "$pdir" \
       --cache-dir "$c1" "$@" > "$T/d-$name.json" 2>"$T/err"; then
    bad "$name: mpirun -np $np glint-mpi decompose"; sed 's/^/    /' "$T/err"; return
  fi
  ok "$name: mpirun -np $np glint-mpi decompose"
  local key
  key=$(field "$T/d-$name.json" key)
  [ -f "$c0/$key.hfd" ] && ok "$name: same key as glint fit ($key)" ||
      bad "$name: glint fit wrote no $key.hfd ($(ls "$c0"))"
  if "$CMP" "$c0" "$c1" "$key" > "$T/cmp" 2>&1; then ok "$name: same operator: $(cat "$T/cmp")"
  else bad "$name: operators differ: $(cat "$T/cmp")"; fi
  if "$G" fit "$T/scene.json" --paintings "$pdir" -o "$T/m1-$name" --cache-dir "$c1" "$@" \
       > "$T/f1-$name.json" 2>"$T/err" &&
     python3 - "$T/f0-$name.json" "$T/f1-$name.json" <<'EOF'
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:3])
lv = b["precomputation"]["cache"]["levels"]["decomposition"]
assert lv["disk"] == "loaded", "decomposition was %s, not loaded" % lv["disk"]
ea, eb = a["errors"]["rms_painted"], b["errors"]["rms_painted"]
# the fits differ by the operators' difference (checked above) applied to
# the painting: far below the fit's own error
assert abs(ea - eb) <= 1e-6 * ea, "fit rms %g vs %g" % (ea, eb)
print("rms_painted %.6g vs %.6g" % (ea, eb))
EOF
  then ok "$name: glint fit loads glint-mpi's decomposition (cache hit), same fit"
  else bad "$name: glint fit after glint-mpi"; sed 's/^/    /' "$T/err"; fi
}

compare res32 2 "$T/paint" --res 32
compare view0-res96-lambda0-3ranks 3 "$T/paint1" --res 96 --lambda 0
compare res32-4ranks 4 "$T/paint" --res 32

# compare_hfx METHOD NAME NP PAINTINGS FIT-OPTIONS...: hf4's or hf2d's
# normal form end to end.  No operator tool here: the fits are compared,
# every log value of material.json (hf4: p, q, r and the spatial s; hf2d:
# its 1D and 2D factors' nodes; at full precision) within the operator's
# perturbation bound 64 n eps (s_max / s_min)^2 max |y|.
compare_hfx() {
  local method=$1 name=$2 np=$3 pdir=$4; shift 4
  local c0="$T/c0-$name" c1="$T/c1-$name"
  if ! "$G" fit "$T/scene.json" --paintings "$pdir" -o "$T/m0-$name" --cache-dir "$c0" \
       --method "$method" "$@" > "$T/f0-$name.json" 2>"$T/err"; then
    bad "$name: single-process fit"; sed 's/^/    /' "$T/err"; return
  fi
  if ! "${MPIRUN[@]}" -np "$np" "$GM" decompose "$T/scene.json" --paintings "$pdir" \
       --cache-dir "$c1" --method "$method" "$@" > "$T/d-$name.json" 2>"$T/err"; then
    bad "$name: mpirun -np $np glint-mpi decompose --method $method"; sed 's/^/    /' "$T/err"
    return
  fi
  ok "$name: mpirun -np $np glint-mpi decompose --method $method"
  local file
  file=$(basename "$(field "$T/d-$name.json" file)")
  [ -f "$c0/$file" ] && ok "$name: same file as glint fit ($file)" ||
      bad "$name: glint fit wrote no $file ($(ls "$c0"))"
  if "$G" fit "$T/scene.json" --paintings "$pdir" -o "$T/m1-$name" --cache-dir "$c1" \
       --method "$method" "$@" > "$T/f1-$name.json" 2>"$T/err" &&
     python3 - "$T/d-$name.json" "$T/f1-$name.json" "$T/m0-$name/material.json" \
       "$T/m1-$name/material.json" > "$T/cmp" 2>&1 <<'EOF'
import json, sys
rep, fit = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
lv = fit["precomputation"]["cache"]["levels"]["decomposition"]
assert lv["disk"] == "loaded", "decomposition was %s, not loaded" % lv["disk"]
def flat(x):
    if isinstance(x, dict):
        x = [x[k] for k in sorted(x)]
    if isinstance(x, list):
        return [v for e in x for v in flat(e)]
    return [x] if isinstance(x, (int, float)) else []
a, b = (json.load(open(p)) for p in sys.argv[3:5])
keys = ["log_factors", "log_s", "log_nodes"]
ya = [v for k in keys if k in a for v in flat(a[k])]
yb = [v for k in keys if k in b for v in flat(b[k])]
assert len(ya) == len(yb) > 0
diff = max(abs(x - y) for x, y in zip(ya, yb))
tol = 64 * rep["n"] * 2.220446049250313e-16 * (rep["s_max"] / rep["s_min"]) ** 2 * \
    max(abs(x) for x in ya)
print("log-factor diff %.3g, tolerance %.3g, rank %d, form %s" % (diff, tol, rep["rank"],
                                                                 rep["form"]))
assert diff <= tol
EOF
  then ok "$name: glint fit loads it (cache hit), same factors: $(cat "$T/cmp")"
  else bad "$name: glint fit after glint-mpi: $(cat "$T/cmp")"; sed 's/^/    /' "$T/err"; fi
}

compare_hfx hf4 hf4-sres24 2 "$T/paint" --res 32 --s_res 24
compare_hfx hf4 hf4-sres16-lambdas0-3ranks 3 "$T/paint" --res 32 --s_res 16 --lambda_s 0
compare_hfx hf2d hf2d-q2d 2 "$T/paint" --res 32 --res_2d 16
compare_hfx hf2d hf2d-pqr2d-3ranks 3 "$T/paint" --res 32 --res_2d 12 --p 2d --r 2d

# a decomposition already cached is not rebuilt (unless --force)
if "${MPIRUN[@]}" -np 2 "$GM" decompose "$T/scene.json" --paintings "$T/paint" \
     --cache-dir "$T/c1-res32" --res 32 > "$T/again.json" 2>&1 &&
   grep -q '"cached": true' "$T/again.json"; then ok "cached decomposition reused"
else bad "cached decomposition reused: $(head -c 300 "$T/again.json")"; fi

# expect_err NAME STATUS PATTERN ARGS...: mpirun -np 2 glint-mpi ARGS fails so
# (every rank reaches the decision, rank 0 alone says it); expect_err1 the
# same from one process started without mpirun (a failing 2-rank job
# takes 2.5 s to tear down here, a singleton 1 s)
expect_err() {
  local n=$1 st=$2 pat=$3; shift 3
  "${MPIRUN[@]}" -np 2 "$GM" "$@" >"$T/out" 2>"$T/err"; local got=$?
  if [ "$got" -eq "$st" ] && grep -Eq -- "$pat" "$T/err" &&
     [ "$(grep -c -- "$pat" "$T/err")" -le 1 ]; then ok "$n"
  else bad "$n (status $got, want $st; stderr: $(head -c 300 "$T/err"))"; fi
}
expect_err1() {
  local n=$1 st=$2 pat=$3; shift 3
  timeout 60 "$GM" "$@" >"$T/out" 2>"$T/err"; local got=$?
  if [ "$got" -eq "$st" ] && grep -Eq -- "$pat" "$T/err"; then ok "$n"
  else bad "$n (status $got, want $st; stderr: $(head -c 300 "$T/err"))"; fi
}
S=$T/scene.json
expect_err "svd route refused" 1 "eig route only" decompose "$S" --cache-dir "$T/x" --route svd
expect_err1 "other method refused" 1 "hf3's, hf4's and hf2d's constraint matrices only" \
    decompose "$S" --cache-dir "$T/x" --method maps
"$G" scene create --size 32 -o "$T/small.json" >/dev/null
expect_err "hf4's kernel form refused" 1 "kernel form there, which is not distributed" decompose \
    "$T/small.json" --cache-dir "$T/x" --method hf4 --s_res 64 --views 0
expect_err1 "hf4's dense form refused" 1 "dense form there, which is not distributed" decompose \
    "$T/small.json" --cache-dir "$T/x" --method hf4 --s_res 64 --views 0 --lambda 0 \
    --lambda_s 0
expect_err1 "res out of range" 1 "res" decompose "$S" --cache-dir "$T/x" --res 3
expect_err "bad view list" 1 "--views '0,x'" decompose "$S" --cache-dir "$T/x" --views 0,x
expect_err1 "view out of range" 1 "in 0..11" decompose "$S" --cache-dir "$T/x" --views 40
expect_err1 "views and paintings" 1 "give one" decompose "$S" --cache-dir "$T/x" --views 0 \
    --paintings "$T/paint"
expect_err1 "no paintings" 1 "no painting in" decompose "$S" --cache-dir "$T/x" --paintings "$T"
expect_err1 "no cache" 1 "cache directory is needed" decompose "$S" --no-cache
expect_err "missing scene" 1 "nope.json" decompose "$T/nope.json" --cache-dir "$T/x"
expect_err1 "unknown command" 1 "unknown command 'frob'" frob
expect_err1 "no scene" 1 "expected one scene file" decompose --cache-dir "$T/x"
touch "$T/ro" && chmod 0444 "$T/ro"
expect_err1 "cache dir is a file" 2 "." decompose "$S" --cache-dir "$T/ro/sub"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
