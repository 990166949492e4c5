#!/usr/bin/env bash
# Builds the core and its tests with AddressSanitizer + UndefinedBehaviorSanitizer
# (-DEVIDENTIAL_OCTOMAP_SANITIZE=ON) in build/sanitize and runs ctest there.
#   scripts/sanitize.sh [-j N] [ctest arguments...]    e.g. scripts/sanitize.sh -j 2 -R reliability
# Environment: BUILD_DIR (default build/sanitize), CXX (compiler), SANITIZE_TOOLS (ON: the CLI
# and its tests too, the whole ctest suite; OFF: core only); EVIDENTIAL_SOAK_SCANS (100),
# EVIDENTIAL_FUZZ_MUTATIONS (1000), EVIDENTIAL_KILL_TRIALS (20) shorten the reliability tests.
# The reliability tests (test/reliability) are part of the run when test/CMakeLists.txt adds
# them; until then they are built and run standalone in $BUILD_DIR/reliability.
# Prints one summary line: "sanitize: N tests, F failed" and exits non-zero on any failure.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs=2
if [[ "${1:-}" == "-j" ]]; then jobs="$2"; shift 2; fi
build="${BUILD_DIR:-$repo/build/sanitize}"

# Leaks are errors; stop at the first report; readable stacks. UBSan aborts on every finding
# (-fno-sanitize-recover=all in the CMake option).
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# OpenMP runtimes keep thread pools alive at exit; that is not a leak of ours.
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$repo/test/reliability/lsan.supp}"
export OMP_NUM_THREADS="${OMP_NUM_THREADS:-2}"
# The reliability tests, shortened for the ~3x slower sanitized build (full sizes: plain ctest).
export EVIDENTIAL_SOAK_SCANS="${EVIDENTIAL_SOAK_SCANS:-100}"
export EVIDENTIAL_FUZZ_MUTATIONS="${EVIDENTIAL_FUZZ_MUTATIONS:-1000}"
export EVIDENTIAL_KILL_TRIALS="${EVIDENTIAL_KILL_TRIALS:-20}"

configure() {  # <source> <build>
  cmake -S "$1" -B "$2" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DEVIDENTIAL_OCTOMAP_SANITIZE=ON \
    -DEVIDENTIAL_OCTOMAP_TOOLS="${SANITIZE_TOOLS:-ON}" -DBUILD_TESTING=ON >"$2.configure.log" 2>&1 || {
      tail -n 30 "$2.configure.log"; echo "sanitize: configure of $1 failed"; exit 1; }
}

status=0
total=0
failed=0
run_ctest() {  # <build> <label>
  local log="$1/ctest.log"
  set +e
  (cd "$1" && ctest --output-on-failure --timeout 1800 "${@:3}") >"$log" 2>&1
  local rc=$?
  set -e
  grep -E "tests passed|tests failed|Failed|\*\*\*|Total Test time" "$log" | tail -n 40 || true
  local line n f
  line="$(grep -E "tests passed, [0-9]+ tests failed out of [0-9]+" "$log" | tail -n 1 || true)"
  n="$(sed -E 's/.* out of ([0-9]+).*/\1/' <<<"$line")"
  f="$(sed -E 's/.*passed, ([0-9]+) tests failed.*/\1/' <<<"$line")"
  [[ "$n" =~ ^[0-9]+$ ]] || n=0
  [[ "$f" =~ ^[0-9]+$ ]] || f=0
  echo "sanitize [$2]: $n tests, $f failed (log: $log)"
  total=$((total + n)); failed=$((failed + f))
  if [[ $rc -ne 0 ]]; then status=1; fi
}

mkdir -p "$build"
echo "sanitize: configuring and building in $build (ASan + UBSan, -j$jobs)"
configure "$repo" "$build"
if ! cmake --build "$build" -j"$jobs" >"$build/build.log" 2>&1; then
  grep -E "error|Error" "$build/build.log" | head -n 30
  echo "sanitize: build failed (log: $build/build.log)"
  exit 1
fi
run_ctest "$build" core "$@"

# The reliability tests, standalone while test/CMakeLists.txt does not include them.
if ! grep -qs "add_subdirectory(reliability)" "$repo/test/CMakeLists.txt"; then
  rel="$build/reliability"
  mkdir -p "$rel"
  configure "$repo/test/reliability" "$rel"
  if ! cmake --build "$rel" -j"$jobs" >"$rel/build.log" 2>&1; then
    grep -E "error|Error" "$rel/build.log" | head -n 30
    echo "sanitize: reliability build failed (log: $rel/build.log)"
    exit 1
  fi
  run_ctest "$rel" reliability "$@"
fi

echo "sanitize: $total tests, $failed failed"
exit $status
