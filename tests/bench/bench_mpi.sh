#!/usr/bin/env bash
# bench_mpi: glint-mpi decompose on 1 and 2 ranks against the single-process
# route (bench_mpi_ref: pattern_raster + hf_design_build + hf_decomp_build,
# eig), at a few sizes of the built-in sphere: raster size, views, texels;
# then hf4's decomposition (--method hf4) at three sizes of its spatial
# factor, against `glint fit`.
#
# usage: tests/bench/bench_mpi.sh [BUILD_DIR] [OUT_DIR] [--quick]
#   BUILD_DIR: a build with glint-mpi (default build); OUT_DIR: where the
#   JSON reports go (default a new directory under /tmp).
# For each size it prints one row per run: ranks x threads per rank, wall
# seconds of the whole command (mpirun's start included), the steps'
# seconds (rank 0's, the slowest rank's for pattern/design/gram), samples
# per rank, peak resident memory per rank (largest), and the difference
# from the single-process route (mpi_compare: operator M = V diag(1/s^2)
# V^T, relative Frobenius norm).  OpenBLAS runs one thread per rank
# (OPENBLAS_NUM_THREADS=1) so that ranks do not oversubscribe the cores.
set -u
B=${1:-build}
OUT=${2:-$(mktemp -d /tmp/bench_mpi.XXXXXX)}
QUICK=${3:-}
G=$B/core/glint GM=$B/core/glint-mpi REF=$B/tests/bench/bench_mpi_ref CMP=$B/tests/mpi/mpi_compare
for x in "$G" "$GM" "$REF" "$CMP"; do
  [ -x "$x" ] || { echo "bench_mpi: $x not built (MPI and ScaLAPACK found?)" >&2; exit 1; }
done
command -v mpirun >/dev/null || { echo "bench_mpi: mpirun not found" >&2; exit 1; }
mkdir -p "$OUT"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1
MPIRUN=(mpirun -x OPENBLAS_NUM_THREADS --oversubscribe --mca btl self,tcp
        --mca btl_tcp_if_include lo --mca oob_tcp_if_include lo)
now() { date +%s.%N; }

# size: raster pixels, view set, texels per factor
SIZES=("256 ico12 128" "512 ico12 256" "512 ico20 512" "1024 ico20 512")
[ "$QUICK" = --quick ] && SIZES=("256 ico12 128" "512 ico12 256")

echo "machine: $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p'); $(mpirun --version | head -1)"
printf '| %-22s | %-9s | %7s | %7s | %6s | %6s | %6s | %6s | %6s | %10s | %8s | %9s |\n' \
  size run wall pattern design gram reduce eig gather samples/rank "RSS MB" "op diff"
printf '|%s|\n' "------------------------|-----------|---------|---------|--------|--------|--------|--------|--------|------------|----------|-----------"
for sz in "${SIZES[@]}"; do
  set -- $sz
  px=$1 vs=$2 res=$3 tag="${1}px-${2}-res${3}"
  "$G" scene create --size "$px" --views "$vs" -o "$OUT/$tag.json" >/dev/null || exit 1
  # the single-process route, on the machine's cores
  t0=$(now)
  "$REF" "$OUT/$tag.json" "$OUT/ref-$tag" "$res" 0.1 0 > "$OUT/ref-$tag.out" || exit 1
  t1=$(now)
  python3 - "$OUT/ref-$tag.out" "$tag" "$t0" "$t1" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1])); s = r["seconds"]
print("| %-22s | %-9s | %7.2f | %7.2f | %6.2f | %6s | %6s | %6.2f | %6s | %10d | %8.0f | %9s |" % (
    sys.argv[2], "1 process", float(sys.argv[4]) - float(sys.argv[3]), s["pattern"], s["design"],
    "", "", s["decomposition"], "", r["samples"], r["peak_rss_mb"], "(ref)"))
EOF
  key=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["key"])' "$OUT/ref-$tag.out")
  for run in "1 1" "1 0" "2 1"; do
    set -- $run
    np=$1 th=$2 name="np$1-t$2-$tag"
    targs=(); [ "$th" != 0 ] && targs=(--threads "$th")
    t0=$(now)
    "${MPIRUN[@]}" -np "$np" "$GM" decompose "$OUT/$tag.json" --cache-dir "$OUT/$name" \
        --res "$res" "${targs[@]}" > "$OUT/$name.out" 2> "$OUT/$name.err" ||
        { echo "bench_mpi: $name failed:"; cat "$OUT/$name.err"; exit 1; }
    t1=$(now)
    "$CMP" "$OUT/ref-$tag" "$OUT/$name" "$key" > "$OUT/$name.cmp" 2>&1
    python3 - "$OUT/$name.out" "$OUT/$name.cmp" "$tag" "$np" "$th" "$t0" "$t1" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1])); s = r["seconds"]
c = json.load(open(sys.argv[2]))
th = "cores" if sys.argv[5] == "0" else sys.argv[5]
per = max(p["samples"] for p in r["per_rank"])
print("| %-22s | %-9s | %7.2f | %7.2f | %6.2f | %6.2f | %6.3f | %6.2f | %6.3f | %10d | %8.0f | %9.1e |" % (
    sys.argv[3], "%s x %s" % (sys.argv[4], th), float(sys.argv[7]) - float(sys.argv[6]),
    s["pattern"], s["design"], s["gram"], s["reduce"], s["eig"], s["gather"], per,
    r["peak_rss_mb_max"], c.get("op_rel_diff", float("nan"))))
EOF
  done
done
# hf4 (--method hf4): the eigensolver's share grows as n^3 with the spatial
# factor (n = 3 res + s_res^2).  The single process is `glint fit` (its
# decomposition level's build seconds; peak RSS from /usr/bin/time);
# glint-mpi's file is checked by fitting from it: the largest difference of
# any log-factor from the single-process fit.
HF4=("32 24" "32 48" "32 64")
[ "$QUICK" = --quick ] && HF4=("32 24")
"$G" scene create --size 48 -o "$OUT/hf4.json" >/dev/null || exit 1
"$G" paint "$OUT/hf4.json" -o "$OUT/hf4-paint" \
    --brdf 'stripes:freq=3,duty=0.5|lambert:kd=0.7/0.15/0.1|ct:kd=0.05,f0=0.9/0.7/0.3,rough=0.25' \
    >/dev/null || exit 1
echo
printf '| %-16s | %-9s | %7s | %6s | %6s | %6s | %7s | %6s | %8s | %10s |\n' \
  "hf4 (48px, 12 v)" run wall gram reduce eig decomp gather "RSS MB" "factor diff"
printf '|%s|\n' "------------------|-----------|---------|--------|--------|--------|---------|--------|----------|------------"
for hs in "${HF4[@]}"; do
  set -- $hs
  res=$1 sres=$2 tag="hf4-res$1-s$2"
  opts=(--method hf4 --res "$res" --s_res "$sres")
  t0=$(now)
  /usr/bin/time -f %M -o "$OUT/$tag-ref.rss" "$G" fit "$OUT/hf4.json" --paintings "$OUT/hf4-paint" \
      --cache-dir "$OUT/$tag-ref" -o "$OUT/$tag-ref-mat" "${opts[@]}" > "$OUT/$tag-ref.json" || exit 1
  t1=$(now)
  python3 - "$OUT/$tag-ref.json" "$OUT/$tag-ref.rss" "$res/$sres" "$t0" "$t1" <<'EOF'
import json, sys
f = json.load(open(sys.argv[1]))["precomputation"]
lv = f["cache"]["levels"]["decomposition"]
print("| %-16s | %-9s | %7.2f | %6s | %6s | %6s | %7.2f | %6s | %8.0f | %10s |" % (
    "res/s_res " + sys.argv[3] + " n=%d" % f["unknowns"], "1 process",
    float(sys.argv[5]) - float(sys.argv[4]), "", "", "", lv["build_seconds"], "",
    int(open(sys.argv[2]).read().split()[-1]) / 1024.0, "(ref)"))
EOF
  for np in 1 2; do
    name="np$np-$tag"
    t0=$(now)
    "${MPIRUN[@]}" -np "$np" "$GM" decompose "$OUT/hf4.json" --paintings "$OUT/hf4-paint" \
        --cache-dir "$OUT/$name" "${opts[@]}" > "$OUT/$name.out" 2> "$OUT/$name.err" ||
        { echo "bench_mpi: $name failed:"; cat "$OUT/$name.err"; exit 1; }
    t1=$(now)
    "$G" fit "$OUT/hf4.json" --paintings "$OUT/hf4-paint" --cache-dir "$OUT/$name" \
        -o "$OUT/$name-mat" "${opts[@]}" > "$OUT/$name-fit.json" || exit 1
    python3 - "$OUT/$name.out" "$OUT/$name-fit.json" "$OUT/$tag-ref-mat/material.json" \
        "$OUT/$name-mat/material.json" "$np" "$t0" "$t1" "$res/$sres" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1])); s = r["seconds"]
fit = json.load(open(sys.argv[2]))
assert fit["precomputation"]["cache"]["levels"]["decomposition"]["disk"] == "loaded"
def flat(x):
    if isinstance(x, dict):
        x = [x[k] for k in sorted(x)]
    if isinstance(x, list):
        return [v for e in x for v in flat(e)]
    return [x] if isinstance(x, (int, float)) else []
a, b = (json.load(open(p)) for p in sys.argv[3:5])
d = max(abs(x - y) for x, y in zip(flat(a["log_factors"]) + flat(a["log_s"]),
                                   flat(b["log_factors"]) + flat(b["log_s"])))
print("| %-16s | %-9s | %7.2f | %6.3f | %6.3f | %6.2f | %7.2f | %6.3f | %8.0f | %10.1e |" % (
    "res/s_res " + sys.argv[8] + " n=%d" % r["n"], "%s x 1" % sys.argv[5],
    float(sys.argv[7]) - float(sys.argv[6]), s["gram"], s["reduce"], s["eig"],
    s["gram"] + s["wait"] + s["reduce"] + s["eig"] + s["gather"] + s["keep"], s["gather"],
    r["peak_rss_mb_max"], d))
EOF
  done
done
echo "reports: $OUT"
