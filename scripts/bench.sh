#!/usr/bin/env bash
# Builds the core and the benchmarks in Release, runs evidential_bench on the bundled
# SemanticKITTI scans (30 inserts forth and back: first pass and steady state), then the revisit
# and long-sequence benchmarks (scripts/bench_sequences.sh), and regenerates docs/experiments/benchmarks.md,
# docs/images/bench_cpu_per_scan.png and bench/results/benchmarks.json. Prints the key ratios,
# and compares them with the previous bench/results/benchmarks.json.
#
#   scripts/bench.sh                  # full run: 1-3 hours on 2 shared cores (outside CI)
#   scripts/bench.sh --quick          # 4 scans, exact and fast against plain: < 3 min (not for the docs)
#   scripts/bench.sh --repeats 3      # the interleaved sequence 3 times (medians over all)
#   scripts/bench.sh --no-docs        # measure and compare only; write nothing in the tree
#   scripts/bench.sh --sequences DIR  # take the sequence figures scripts/bench_sequences.sh wrote
#                                     # into DIR (stamped there) instead of measuring them again
#   scripts/bench.sh --docs-only --sequences DIR  # rewrite the docs from the last run's results
#                                     # (its stamps kept), e.g. once longer sequences are measured
#   BUILD_DIR=/tmp/b scripts/bench.sh # build elsewhere (default: build/bench-release)
# Any other argument is passed to evidential_bench (see evidential_bench --help).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${BUILD_DIR:-${root}/build/bench-release}"
jobs="${JOBS:-$(nproc)}"
given=("$@")
write_docs=1
quick=0
docs_only=0
sequences=""
bench_args=()
while (($#)); do
  case "$1" in
    --no-docs) write_docs=0 ;;
    --quick) write_docs=0; quick=1; bench_args+=("$1") ;;
    --sequences) sequences="$(cd "$2" && pwd)"; shift ;;
    --docs-only) docs_only=1 ;;
    *) bench_args+=("$1") ;;
  esac
  shift
done
# First pass (inserts 0-9) and steady state (10-29) of the scans driven forth and back.
((quick)) || bench_args=(--steps 30 ${bench_args[@]+"${bench_args[@]}"})

log() { echo "bench.sh: $*" >&2; }
# The code measured: stamped now, before the build, since the tree may change during a long run.
commit="$(git -C "${root}" rev-parse --short HEAD 2>/dev/null || echo unknown)"
dirty=""
git -C "${root}" diff --quiet HEAD -- include src/core CMakeLists.txt 2>/dev/null || dirty=" (+ uncommitted core changes)"

out_json="${build}/benchmarks.json"
out_md="${build}/benchmarks.tables.md"
stamp="${build}/benchmarks.stamp"
if ((docs_only)); then
  # The last run's stamps (date, commit, load, command), written when it measured.
  [[ -f "${stamp}" ]] || { log "no ${stamp}: run scripts/bench.sh first"; exit 1; }
  # shellcheck disable=SC1090
  source "${stamp}"
else
# --- build (Release) ----------------------------------------------------------------------------
if grep -q 'add_subdirectory(bench)' "${root}/CMakeLists.txt"; then
  mkdir -p "${build}"
  log "configuring ${build}/core (Release, EVIDENTIAL_OCTOMAP_BENCH=ON)"
  cmake -S "${root}" -B "${build}/core" -DCMAKE_BUILD_TYPE=Release -DEVIDENTIAL_OCTOMAP_BENCH=ON \
    -DEVIDENTIAL_OCTOMAP_TOOLS=OFF -DBUILD_TESTING=OFF >"${build}/core.configure.log" 2>&1 ||
    { cat "${build}/core.configure.log" >&2; exit 1; }
  cmake --build "${build}/core" -j"${jobs}" --target evidential_bench evidential_sequence_bench
  bin="${build}/core/bench/evidential_bench"
else
  # bench/ is not in the top-level project yet: build the core, install it into a private
  # prefix and build bench/ as its own project against it (find_package(evidential_octomap)).
  mkdir -p "${build}"
  log "configuring ${build}/core (Release)"
  cmake -S "${root}" -B "${build}/core" -DCMAKE_BUILD_TYPE=Release \
    -DEVIDENTIAL_OCTOMAP_TOOLS=OFF -DBUILD_TESTING=OFF >"${build}/core.configure.log" 2>&1 ||
    { cat "${build}/core.configure.log" >&2; exit 1; }
  cmake --build "${build}/core" -j"${jobs}"
  cmake --install "${build}/core" --prefix "${build}/prefix" >/dev/null
  cmake -S "${root}/bench" -B "${build}/bench" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="${build}/prefix" >"${build}/bench.configure.log" 2>&1 ||
    { cat "${build}/bench.configure.log" >&2; exit 1; }
  cmake --build "${build}/bench" -j"${jobs}"
  bin="${build}/bench/evidential_bench"
fi

# --- run ----------------------------------------------------------------------------------------
cd "${root}"
baseline="${root}/bench/results/benchmarks.json"
previous=""
if [[ -f "${baseline}" ]]; then
  previous="${build}/benchmarks.previous.json"
  cp "${baseline}" "${previous}"
fi
# Passive OpenMP waiting, as launch/mapping.launch sets it: spinning idle threads would count
# as CPU time of the insert (about 15 % of it, bench/README.md).
command=(env OMP_NUM_THREADS=2 OMP_WAIT_POLICY=passive "${bin}" --data data/semantickitti_08_first10
         --classes config/classes_semantickitti.yaml --json "${out_json}" --md "${out_md}"
         ${bench_args[@]+"${bench_args[@]}"})
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
started="$(date -u '+%Y-%m-%d %H:%M UTC')"
log "running: ${command[*]}"
"${command[@]}"
load_after="$(cut -d' ' -f1-3 /proc/loadavg)"
declare -p commit dirty started load_before load_after given bench_args >"${stamp}"

# --- the revisit and the long sequence -----------------------------------------------------------
if ((!quick)) && [[ -z "${sequences}" ]]; then
  sequences="${build}/sequences"
  log "measuring the sequences into ${sequences} (scripts/bench_sequences.sh)"
  bash "${root}/scripts/bench_sequences.sh" "$(dirname "${bin}")/evidential_sequence_bench" \
    "${sequences}"
fi

if [[ -n "${previous}" ]]; then
  echo
  echo "==== compared with the committed bench/results/benchmarks.json ===="
  python3 "${root}/bench/compare_summary.py" "${previous}" "${out_json}" || true
fi

fi  # docs_only
cd "${root}"

# --- docs ---------------------------------------------------------------------------------------
if ((write_docs)); then
  cpu="$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  mkdir -p "${root}/bench/results" "${root}/docs"
  cp "${out_json}" "${root}/bench/results/benchmarks.json"
  {
    echo "# Benchmarks"
    echo
    echo "Generated by \`scripts/bench.sh\` (do not edit by hand; the analysis is in"
    echo "[\`bench/README.md\`](../../bench/README.md): profile, the fast free-space mode's map quality,"
    echo "each target with its measured value). JSON: \`bench/results/benchmarks.json\`."
    echo "The node's throughput with drops (insertion thread, bounded queue) is in"
    echo "[live_profile.md](live_profile.md)."
    echo
    echo "| | |"
    echo "|---|---|"
    echo "| machine | $(nproc) cores (\`nproc\`), ${cpu}, $(awk '/MemTotal/ {printf "%.1f GB", $2/1048576}' /proc/meminfo) RAM |"
    echo "| date | ${started} |"
    echo "| code | commit ${commit}${dirty}, Release |"
    echo "| load average (1/5/15 min) before / after | ${load_before} / ${load_after} |"
    echo "| command | \`scripts/bench.sh${given[*]:+ ${given[*]}}\`, which ran \`OMP_NUM_THREADS=2 OMP_WAIT_POLICY=passive evidential_bench --data data/semantickitti_08_first10 --classes config/classes_semantickitti.yaml${bench_args[*]:+ ${bench_args[*]}}\` |"
    echo "| data | SemanticKITTI 08 scans 0–9 (123k points each) in the world frame, resolution 0.2 m, evidence **derived** from the predictions: one-hot × 20 over C = 20 classes; rows marked *learned (cross-fitted)*: the bundled model's evidence (\`config/learned/semantickitti.model\`, each scan from the fold not trained on it), computed before timing |"
    echo
    echo "The methods take turns scan by scan (each keeps its own map), so a change of the shared"
    echo "machine's load hits them alike. With a load average above the core count wall times are"
    echo "inflated and the 1-vs-2-thread comparison is unreliable; CPU time (process CPU, all"
    echo "threads) is the trustworthy figure and the ratios are of CPU times in this one run."
    echo
    cat "${out_md}"
    if [[ -n "${sequences}" ]]; then
      echo
      echo "## Steady state and a long sequence"
      echo
      echo "Measured by \`scripts/bench_sequences.sh\`: plain OctoMap, the exact insert with the"
      echo "library defaults and the live launch settings, max range 50 m, 0.2 m, 2 threads, one-hot"
      echo "evidence × 20 **derived** from the predictions; on the revisit interleaved scan by scan in"
      echo "one process (the ratios), on the long sequence each alone in its own process (its cost"
      echo "as the map grows, its RSS). Its record of the runs:"
      echo
      echo '```'
      cat "${sequences}/meta.txt"
      echo '```'
      echo
      report=()
      for m in plain exact live; do
        [[ -f "${sequences}/long_${m}.csv" ]] && report+=(--long "${m}=${sequences}/long_${m}.csv")
      done
      [[ -f "${sequences}/occupied_only.csv" ]] && report+=(--fewer-rows "${sequences}/occupied_only.csv")
      /usr/bin/python3 "${root}/bench/sequence_report.py" --revisit "${sequences}/revisit.csv" \
        --long-label "Long sequence: SYNTHETIC generated forest trail (2 m a scan)" \
        ${report[@]+"${report[@]}"} --png "${root}/docs/images/bench_cpu_per_scan.png" \
        --png-link ../images/bench_cpu_per_scan.png
      if [[ -f "${sequences}/live_rate/summary.json" ]]; then
        echo
        echo "### The live node fed by the player (bench/live_rate.py)"
        echo
        echo "\`mapping.launch\` (live profile, max range 50 m) and \`play_semantickitti.py\` looping the bundled scans, on the same 2 cores;"
        echo "figures after the first minute (\`~status\`), from \`${sequences##*/}/live_rate/summary.json\`:"
        echo
        /usr/bin/python3 -c 'import json, sys
s = json.load(open(sys.argv[1]))
print("| figure | value |\n|---|---|")
for k, v in s.items():
    print("| %s | %s |" % (k, " ".join(v) if isinstance(v, list) else (round(v, 2) if isinstance(v, float) else v)))' \
          "${sequences}/live_rate/summary.json"
      fi
      if [[ -f "${sequences}/profile.md" ]]; then
        echo
        echo "### Profile of the exact insert (scripts/bench_profile.sh)"
        echo
        cat "${sequences}/profile.md"
      fi
    fi
  } >"${root}/docs/experiments/benchmarks.md"
  log "wrote docs/experiments/benchmarks.md and bench/results/benchmarks.json"
fi
