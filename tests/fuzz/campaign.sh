#!/usr/bin/env bash
# A fuzzing campaign: each target under libFuzzer for a while, its corpus
# grown from tests/fuzz/corpus, minimized and written back there.
#
#   tests/fuzz/campaign.sh [-t SECONDS] [-j JOBS] [TARGET...]
#
# -t: seconds per target (default 600); -j: targets at once (default 1);
# targets: json image mesh cache config http_head stroke_file
# (default: all).
# Builds build-fuzz (clang, -Dfuzzing=true, AddressSanitizer and
# UndefinedBehaviorSanitizer) if it is not there.  Writes, per target,
# build-fuzz/fuzz-work/NAME.log (libFuzzer's output), NAME-crash-* (inputs
# that crashed, if any) and one line of build-fuzz/fuzz-work/report.txt:
# executions, coverage (edges), features, corpus before and after, crashes.
# Inputs that crashed go to tests/fuzz/crashes/NAME once fixed (by hand:
# the test command replays them).
set -euo pipefail
cd "$(dirname "$0")/../.."
secs=600 jobs=1
while getopts "t:j:" o; do
  case $o in t) secs=$OPTARG ;; j) jobs=$OPTARG ;; *) exit 2 ;; esac
done
shift $((OPTIND - 1))
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(json image mesh cache config http_head stroke_file)
B=${GLINT_FUZZ_BUILD:-build-fuzz}
if [ ! -f "$B/build.ninja" ]; then
  CC=clang CXX=clang++ meson setup "$B" -Dfuzzing=true -Db_sanitize=address,undefined \
    -Db_lundef=false -Dbuildtype=debugoptimized
fi
ninja -C "$B" $(printf "tests/fuzz/fuzz_%s " "${targets[@]}")
W=$B/fuzz-work
mkdir -p "$W"
export ASAN_OPTIONS=fast_unwind_on_malloc=0:detect_leaks=1:allocator_may_return_null=1
export LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp:print_suppressions=0
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1

one() {
  local t=$1 exe=$B/tests/fuzz/fuzz_$1 work=$W/$1 extra=()
  rm -rf "$work" "$work.min" && mkdir -p "$work" "$work.min"
  cp tests/fuzz/corpus/"$t"/* "$work"/
  local before
  before=$(ls "$work" | wc -l)
  # assimp crashes and loops on some malformed files (mesh_child.c); the
  # campaign goes on past them, as glintd does (its import runs in a child)
  [ "$t" = mesh ] && extra=(-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
  "$exe" "$work" -max_total_time="$secs" -timeout=20 -rss_limit_mb=4096 -max_len=1048576 \
    -print_final_stats=1 -artifact_prefix="$W/$t-" "${extra[@]}" > "$W/$t.log" 2>&1 || true
  "$exe" -merge=1 -timeout=20 -rss_limit_mb=4096 -max_len=1048576 "${extra[@]:0:0}" "$work.min" "$work" > "$W/$t.merge.log" 2>&1 || true
  local after execs cov ft crashes
  after=$(ls "$work.min" | wc -l)
  execs=$( (grep -o 'stat::number_of_executed_units: *[0-9]*' "$W/$t.log" || true) \
           | grep -o '[0-9]*$' | tail -1 || true)
  if [ -z "$execs" ]; then   # -fork: the last status line's count
    execs=$( (grep -o '^#[0-9]*' "$W/$t.log" || true) | tail -1 | tr -d '#')
  fi
  cov=$( (grep -o 'cov: [0-9]*' "$W/$t.log" || true) | tail -1 | grep -o '[0-9]*' || true)
  ft=$( (grep -o 'ft: [0-9]*' "$W/$t.log" || true) | tail -1 | grep -o '[0-9]*' || true)
  crashes=$(ls "$W" | grep -c "^$t-\(crash\|leak\|timeout\|oom\)-" || true)
  if [ "$after" -gt 0 ]; then
    rm -rf tests/fuzz/corpus/"$t" && mkdir -p tests/fuzz/corpus/"$t"
    cp "$work.min"/* tests/fuzz/corpus/"$t"/
  fi
  printf '%-10s %5ss  executions %10s  edges %6s  features %7s  corpus %4s -> %4s  crashes %s\n' \
    "$t" "$secs" "${execs:-?}" "${cov:-?}" "${ft:-?}" "$before" "$after" "$crashes" \
    | tee -a "$W/report.txt"
}

running=0
for t in "${targets[@]}"; do
  one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then wait -n; running=$((running - 1)); fi
done
wait
