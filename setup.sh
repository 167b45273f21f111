#!/usr/bin/env bash
# glint set-up for a fresh Debian 12 machine (run as root, from the checkout).
#
#   ./setup.sh run    install what is missing, build, run the main job
#   ./setup.sh test   install what is missing, build, run every test
#   ./setup.sh test deep   the same, and what is too slow for every change
#                          (before a release: docs/testing.md)
#
# Both are idempotent: packages already present are not reinstalled, the
# build directories are reused.
set -euo pipefail

cd "$(dirname "$0")"
mode=${1:-}
depth=${2:-}

# Build and runtime dependencies (Debian 12 package names).
BUILD_PKGS=(
  gcc g++ meson ninja-build pkg-config curl
  libopenblas-dev liblapacke-dev libjansson-dev libxxhash-dev
  libopenimageio-dev libpng-dev libfmt-dev libdeflate-dev libmicrohttpd-dev libsqlite3-dev libpq-dev libassimp-dev
  libegl-dev libgles-dev libgl1-mesa-dri libegl-mesa0 libembree-dev libgsl-dev
)
# Test-only: the independent numpy reference, OpenImageIO's tools for
# inspecting outputs, gnuplot for the benchmark plot, valgrind, and the
# PostgreSQL server and nginx that the store's and the replicas' tests start
# (tests/with_postgres.sh; nothing is left running), and Open MPI with
# ScaLAPACK, with which the build adds glint-mpi (distributed
# decompositions, tests/mpi); ccache, through which meson compiles the two
# trees the tests build.
TEST_PKGS=(
  python3 python3-numpy python3-scipy python3-requests python3-jsonschema python3-yaml python3-cvxopt python3-openimageio python3-matplotlib
  openimageio-tools gnuplot-nox wrk chromium jq valgrind postgresql nginx
  openmpi-bin libopenmpi-dev libscalapack-openmpi-dev ccache
)

missing_packages() {
  local p
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || echo "$p"
  done
}

install_packages() {
  local missing
  missing=$(missing_packages "$@")
  if [ -n "$missing" ]; then
    if [ "$(id -u)" -ne 0 ]; then
      echo "setup.sh: missing packages ($missing); run as root to install them" >&2
      exit 1
    fi
    echo "== installing: $missing"
    apt-get update -qq
    # Services the packages bring (PostgreSQL's default cluster, nginx on
    # port 80) are not started: the tests start their own on loopback ports.
    # (Debian's policy-rc.d convention, only while installing, and only when
    # the machine has no policy of its own.)
    local policy=""
    if [ ! -e /usr/sbin/policy-rc.d ]; then
      policy=/usr/sbin/policy-rc.d
      printf '#!/bin/sh\nexit 101\n' > "$policy"
      chmod 755 "$policy"
    fi
    # shellcheck disable=SC2086
    local ok=0
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $missing || ok=$?
    if [ -n "$policy" ]; then rm -f "$policy"; fi
    if [ "$ok" -ne 0 ]; then exit "$ok"; fi
  fi
}

build() {
  local dir=$1; shift
  if [ ! -f "$dir/build.ninja" ]; then
    meson setup "$dir" "$@"
  fi
  ninja -C "$dir"
}

# stage TITLE CMD...: run CMD, then print how long it took (a blank TITLE
# continues the previous stage)
stage() {
  local title=$1 t0=$SECONDS rc=0; shift
  [ -n "$title" ] && echo "== $title"
  "$@" || rc=$?
  echo "-- $((SECONDS - t0)) s (at $((SECONDS / 60)) min $((SECONDS % 60)) s)"
  return $rc
}

# The main job: glintd serving the studio on localhost, with a demo scene
# (the built-in teapot, 12 views) and a painting session created through the
# API on first start and reused afterwards; glintd answers it as its demo
# session (--demo-session: GET /api/v1/demo), which the studio lists first
# among the recent sessions.  Stops on Ctrl-C.
json_field() {  # json_field NAME < json: the first string value of "NAME"
  grep -o "\"$1\": *\"[^\"]*\"" | head -n1 | sed 's/.*: *"\(.*\)"/\1/'
}

run_daemon() {
  local port=${GLINT_PORT:-8080} data=${GLINT_RUN_DATA:-out/glint-data}
  local base="http://127.0.0.1:$port" demo sid tok scene
  mkdir -p "$data"
  envs=()
  # the CC0 environment maps beside the checkout, offered as data:<file>
  [ -d ../shared/data/envmaps ] && envs=(--env-dir ../shared/data/envmaps)
  # the measured materials' published fits: finishes to paint with, and what
  # the learned-prior method learns from
  [ -f ../shared/data/measured/merl56_fits.json ] && envs+=(--measured-dir ../shared/data/measured)
  demo="$data/demo-session.json"
  ./build/server/glintd --port "$port" --data-dir "$data" --web-dir web "${envs[@]}" \
    --demo-session "$demo" &
  local pid=$!
  trap 'kill -TERM $pid 2>/dev/null; wait $pid; exit 0' INT TERM
  for _ in $(seq 100); do curl -fs "$base/healthz" >/dev/null && break; sleep 0.1; done
  sid=$(json_field id 2>/dev/null < "$demo" || true)
  tok=$(json_field paint_token 2>/dev/null < "$demo" || true)
  if [ -z "$sid" ] || ! curl -fs "$base/api/v1/sessions/$sid?token=$tok" >/dev/null; then
    scene=$(curl -fsS -X POST "$base/api/v1/scenes" -H 'Content-Type: application/json' \
              -d '{"mesh": "teapot", "width": 256, "height": 256}' | json_field id)
    # whole or not at all: glintd reads the file at each GET /api/v1/demo
    curl -fsS -X POST "$base/api/v1/sessions" -H 'Content-Type: application/json' \
         -d "{\"scene_id\": \"$scene\"}" > "$demo.tmp"
    mv "$demo.tmp" "$demo"
    sid=$(json_field id < "$demo")
    tok=$(json_field paint_token < "$demo")
  fi
  echo
  echo "== glint studio: open $base/#/session/$sid?token=$tok"
  echo "   (the REST API is under $base/api/v1, see docs/api.md; Ctrl-C stops glintd)"
  wait $pid
}

case "$mode" in
  run)
    install_packages "${BUILD_PKGS[@]}"
    build build
    echo "== glint demo (paint the built-in sphere, fit, render new views)"
    ./build/core/glint demo -o out/demo
    run_daemon
    ;;
  test)
    install_packages "${BUILD_PKGS[@]}" "${TEST_PKGS[@]}"
    # Node.js for the browser tests: the machine's own if present (>= 18),
    # else Debian's.  playwright-core comes from npm, pinned by the lock file;
    # it drives Debian's /usr/bin/chromium (no browser download).
    command -v node >/dev/null && command -v npm >/dev/null || install_packages nodejs npm
    npm ci --prefix tests/browser --no-audit --no-fund --loglevel=error
    # a build configured before Open MPI was installed (./setup.sh run)
    # learns of it: glint-mpi and its tests join
    if [ -f build/build.ninja ] && ! grep -q glint-mpi build/build.ninja; then
      meson setup --reconfigure build
    fi
    # meson compiles through ccache when it is installed; paths relative to
    # the checkout let a fresh clone elsewhere reuse what an earlier one built
    export CCACHE_BASEDIR=$PWD CCACHE_NOHASHDIR=true
    # tests run two at a time (one per core): each one's BLAS on one thread
    export OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1}
    SECONDS=0
    failed=0   # every tier runs; the command fails at the end if one did
    stage "building the plain tree and the sanitizers' tree" \
      build build
    stage "" build build-asan -Db_sanitize=address,undefined -Db_lundef=false \
      -Dbuildtype=debugoptimized -Dc_args=-fno-omit-frame-pointer
    # Each test runs once, in the build that checks the most for what it
    # costs.  The plain build: the command line, the cross-checks with the
    # numpy references, glint-mpi, the studio in Chromium, allocation
    # failure (it replaces malloc, which the sanitizers own), the numerical
    # programs of suite 'valgrind-slow' (two to three times slower under the
    # sanitizers; `test deep` runs them there) and the integration tests of
    # suite 'plain' (resident-memory bounds, the importer's address-space
    # limit).
    stage "plain build: CLI, reference cross-checks, MPI, Chromium, allocation failure, the numerical programs, memory bounds" \
      meson test -C build --suite plain --suite cli --suite ref --suite mpi --suite browser \
        --suite valgrind-slow --print-errorlogs || failed=$((failed + 1))
    stage "unit tests under valgrind (memcheck; the programs that take about a minute there)" \
      meson test -C build --setup valgrind --suite valgrind --print-errorlogs \
        || failed=$((failed + 1))
    # The other unit programs, the fuzz corpora and glintd over real HTTP
    # (with PostgreSQL, the replicas behind nginx) under AddressSanitizer +
    # UndefinedBehaviorSanitizer: a sanitizer report fails the test (the
    # daemon's log is read by tests/integration/harness.py).  Timeouts are
    # three times the plain build's.
    export ASAN_OPTIONS=fast_unwind_on_malloc=0:detect_leaks=1
    export LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0"
    export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
    stage "sanitizers: unit tests and the fuzz corpora" \
      meson test -C build-asan --suite unit --suite fuzz --no-suite valgrind-slow --print-errorlogs \
        --timeout-multiplier 3 \
        || failed=$((failed + 1))
    # the daemon's previews on the CPU (GLINT_EGL=off: llvmpipe's JIT hung
    # under ASan); two tests a core, as they spend much of their time
    # waiting on the daemon's answers and its restarts
    GLINT_EGL=off GLINT_TEST_TIMEOUT_SCALE=3 stage "sanitizers: glintd driven by the integration tests" \
      meson test -C build-asan --suite integration --no-suite plain --print-errorlogs \
        --num-processes $(( $(nproc) * 2 )) --timeout-multiplier 3 \
        --logbase testlog-integration || failed=$((failed + 1))
    logs=(build/meson-logs/testlog.json build/meson-logs/testlog-valgrind.json
          build-asan/meson-logs/testlog.json build-asan/meson-logs/testlog-integration.json)
    if [ "$depth" = deep ]; then
      # Before a release (docs/testing.md): what is too slow for every
      # change.  The numerical programs under the sanitizers and under
      # memcheck, every unit program on the plain build, and allocation
      # failure at every allocation.
      stage "deep: the numerical programs under the sanitizers" \
        meson test -C build-asan --suite valgrind-slow --print-errorlogs --timeout-multiplier 3 \
          --logbase testlog-deep || failed=$((failed + 1))
      unset ASAN_OPTIONS LSAN_OPTIONS UBSAN_OPTIONS
      stage "deep: every unit program on the plain build, allocation failure at every allocation" \
        env GLINT_ALLOC_FAIL_STRIDE=1 meson test -C build --suite unit --print-errorlogs \
          --timeout-multiplier 20 --logbase testlog-deep || failed=$((failed + 1))
      stage "deep: the programs that take minutes to hours under valgrind" \
        meson test -C build --setup valgrind --suite valgrind-deep --suite valgrind-slow \
          --print-errorlogs \
          --timeout-multiplier 12 --logbase testlog-valgrind-slow || failed=$((failed + 1))
      logs+=(build-asan/meson-logs/testlog-deep.json build/meson-logs/testlog-deep.json
             build/meson-logs/testlog-valgrind-slow.json)
    fi
    echo "== the test command took $((SECONDS / 60)) min $((SECONDS % 60)) s"
    python3 tests/summary.py "${logs[@]}"
    [ "$failed" -eq 0 ]
    ;;
  *)
    echo "usage: ./setup.sh run | ./setup.sh test [deep]" >&2
    exit 1
    ;;
esac
