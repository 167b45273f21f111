#!/usr/bin/env bash
# glint set-up for a fresh Debian 12 machine (run as root, from the checkout).
#
#   ./setup.sh run    install what is missing, build, run the main job
#   ./setup.sh test   install what is missing, build, run every test
#
# Both are idempotent: packages already present are not reinstalled, the
# build directories are reused.
set -euo pipefail

cd "$(dirname "$0")"
mode=${1:-}

# Build and runtime dependencies (Debian 12 package names).
BUILD_PKGS=(
  gcc g++ meson ninja-build pkg-config curl
  libopenblas-dev liblapacke-dev libjansson-dev libxxhash-dev
  libopenimageio-dev libpng-dev libfmt-dev libdeflate-dev libmicrohttpd-dev libsqlite3-dev libpq-dev libassimp-dev
  libegl-dev libgles-dev libgl1-mesa-dri libegl-mesa0 libembree-dev
)
# Test-only: the independent numpy reference, OpenImageIO's tools for
# inspecting outputs, gnuplot for the benchmark plot, valgrind, and the
# PostgreSQL server and nginx that the store's and the replicas' tests start
# (tests/with_postgres.sh; nothing is left running), and Open MPI with
# ScaLAPACK, with which the build adds glint-mpi (distributed
# decompositions, tests/mpi).
TEST_PKGS=(
  python3 python3-numpy python3-scipy python3-requests python3-jsonschema python3-yaml python3-cvxopt python3-openimageio python3-matplotlib
  openimageio-tools gnuplot-nox wrk chromium jq valgrind postgresql nginx
  openmpi-bin libopenmpi-dev libscalapack-openmpi-dev
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

# The main job: glintd serving the studio on localhost, with a demo scene
# (the built-in teapot, 12 views) and a painting session created through the
# API on first start and reused afterwards.  Stops on Ctrl-C.
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
  ./build/server/glintd --port "$port" --data-dir "$data" --web-dir web "${envs[@]}" &
  local pid=$!
  trap 'kill -TERM $pid 2>/dev/null; wait $pid; exit 0' INT TERM
  for _ in $(seq 100); do curl -fs "$base/healthz" >/dev/null && break; sleep 0.1; done
  demo="$data/demo-session.json"
  sid=$(json_field id 2>/dev/null < "$demo" || true)
  tok=$(json_field paint_token 2>/dev/null < "$demo" || true)
  if [ -z "$sid" ] || ! curl -fs "$base/api/v1/sessions/$sid?token=$tok" >/dev/null; then
    scene=$(curl -fsS -X POST "$base/api/v1/scenes" -H 'Content-Type: application/json' \
              -d '{"mesh": "teapot", "width": 256, "height": 256}' | json_field id)
    curl -fsS -X POST "$base/api/v1/sessions" -H 'Content-Type: application/json' \
         -d "{\"scene_id\": \"$scene\"}" > "$demo"
    sid=$(json_field id < "$demo")
    tok=$(json_field paint_token < "$demo")
  fi
  echo
  echo "== glint studio: open $base/#/session/$sid?token=$tok"
  echo "   (the REST API is under $base/api/v1, see README.md; Ctrl-C stops glintd)"
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
    build build
    echo "== unit, CLI and integration tests"
    meson test -C build --print-errorlogs
    echo "== unit tests under valgrind (memcheck; those that finish within minutes there)"
    meson test -C build --setup valgrind --suite valgrind --print-errorlogs
    echo "== unit tests and the fuzz corpora under AddressSanitizer + UndefinedBehaviorSanitizer"
    # the sanitizers run the numerical programs two to three times slower:
    # their timeouts are three times the plain build's (srbf_fit takes
    # 226-246 s plain here and ran past its 600 s under them once)
    build build-asan -Db_sanitize=address,undefined -Db_lundef=false -Dbuildtype=debugoptimized -Dc_args=-fno-omit-frame-pointer
    ASAN_OPTIONS=fast_unwind_on_malloc=0:detect_leaks=1 \
    LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0" \
    UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
      meson test -C build-asan --suite unit --suite fuzz --print-errorlogs --timeout-multiplier 3
    # the daemon under the sanitizers, driven by the integration tests (a
    # sanitizer report in its log fails the test: tests/integration/harness.py);
    # its previews on the CPU (GLINT_EGL=off: llvmpipe's JIT hung under ASan)
    echo "== integration tests: glintd under AddressSanitizer + UndefinedBehaviorSanitizer"
    GLINT_EGL=off ASAN_OPTIONS=fast_unwind_on_malloc=0:detect_leaks=1 \
    LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp:print_suppressions=0" \
    UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
      meson test -C build-asan --suite integration --no-suite unsanitized --print-errorlogs \
        --logbase testlog-integration
    python3 tests/summary.py build/meson-logs/testlog.json build/meson-logs/testlog-valgrind.json \
      build-asan/meson-logs/testlog.json \
      build-asan/meson-logs/testlog-integration.json
    ;;
  *)
    echo "usage: ./setup.sh run | ./setup.sh test" >&2
    exit 1
    ;;
esac
