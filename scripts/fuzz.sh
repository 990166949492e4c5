#!/usr/bin/env bash
# libFuzzer run of the .ot reader (or the class-table loader), bounded in time, one job.
#   scripts/fuzz.sh [ot|class_table|services|pointcloud2|service_requests] [seconds] [flags...]
#   e.g. scripts/fuzz.sh ot 600        scripts/fuzz.sh class_table 120
# Needs clang (Debian: clang, libclang-rt-14-dev). Builds fuzz/ (ASan + UBSan + libFuzzer, core
# sources compiled in) in build/fuzz, writes fresh seeds with the library itself (make_seeds),
# replays fuzz/regressions first, then fuzzes. Crashes land in build/fuzz/artifacts/; copy each
# (minimised: add -minimize_crash=1 -runs=10000 and the crash file) to fuzz/regressions/<target>/.
# Environment: CORE_DIR fuzzes another checkout's include/ and src/core/ (e.g. a patched copy).
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
target="${1:-ot}"
seconds="${2:-300}"
shift $(( $# >= 2 ? 2 : $# ))
build="${BUILD_DIR:-$repo/build/fuzz}"
case "$target" in ot|class_table|services|pointcloud2|service_requests) ;;
  *) echo "target: ot, class_table, services, pointcloud2 or service_requests"; exit 2;; esac
command -v clang++ >/dev/null || { echo "fuzz.sh needs clang++ (apt-get install clang)"; exit 1; }

cmake -S "$repo/fuzz" -B "$build" -DCMAKE_CXX_COMPILER=clang++ \
  -DEVIDENTIAL_CORE_DIR="${CORE_DIR:-$repo}" >"$build.configure.log" 2>&1 ||
  { tail -n 20 "$build.configure.log"; exit 1; }
cmake --build "$build" -j2 >"$build/build.log" 2>&1 ||
  { grep -E "error" "$build/build.log" | head -n 20; exit 1; }

# Seeds: written by the library (so they follow the file format), built with the same clang.
seeds="$build/seeds"
OMP_NUM_THREADS=1 "$build/make_seeds" "$seeds" "$repo" >/dev/null
corpus="$build/corpus_$target"
mkdir -p "$corpus" "$build/artifacts"
cp -n "$seeds/$target"/* "$corpus/" 2>/dev/null || true
# Kept inputs (findings and coverage) start every run.
cp -n "$repo/fuzz/regressions/$target"/* "$corpus/" 2>/dev/null || true

export OMP_NUM_THREADS=1                 # one fuzz job = one core
export ASAN_OPTIONS="${ASAN_OPTIONS:-malloc_context_size=4:detect_leaks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

ros_target=0
[[ "$target" == pointcloud2 || "$target" == service_requests ]] && ros_target=1
if ((!ros_target)); then  # the replay harness has no ROS code in it
  echo "fuzz.sh: replaying fuzz/regressions/$target and 3000 fixed-seed mutations (ASan + UBSan)"
  mkdir -p "$repo/fuzz/regressions/$target"
  "$build/fuzz_replay" --target "$target" --corpus "$seeds/$target" \
    --regressions "$repo/fuzz/regressions/$target" --mutations 3000 \
    --save-current "$build/artifacts/replay_current.bin" | tail -n 1
elif [[ ! -x "$build/fuzz_$target" ]]; then
  echo "fuzz.sh: fuzz_$target was not built: configure with -DEVIDENTIAL_FUZZ_ROS=ON" \
    "-DEVIDENTIAL_ROS_INCLUDE=<catkin devel/include> (BUILD_DIR=$build)"; exit 1
fi

echo "fuzz.sh: libFuzzer $target for $seconds s (corpus $corpus)"
set +e
binary="$build/fuzz_$target"
[[ "$target" == ot ]] && binary="$build/fuzz_ot_reader"
[[ "$target" == services ]] && binary="$build/fuzz_map_services"
"$binary" -max_total_time="$seconds" -max_len=32768 -timeout=20 -rss_limit_mb=2048 \
  -close_fd_mask=2 -print_final_stats=1 -artifact_prefix="$build/artifacts/" "$@" "$corpus" \
  >"$build/fuzz_$target.log" 2>&1
rc=$?
set -e
grep -E "^#[0-9]+.*(DONE|pulse)|stat::number_of_executed_units|stat::peak_rss|SUMMARY|INVARIANT|Test unit written" \
  "$build/fuzz_$target.log" | tail -n 8
echo "fuzz.sh: exit $rc; artifacts: $(ls "$build/artifacts" | grep -v replay_current | wc -l) in $build/artifacts"
exit $rc
