#!/usr/bin/env bash
# Measures the steady-state and long-sequence benchmarks with evidential_sequence_bench into OUT
# (CSV files and meta.txt: commit, date, load average, commands). scripts/bench.sh calls it and
# turns the files into docs/benchmarks.md with bench/sequence_report.py.
#
#   scripts/bench_sequences.sh BIN OUT    # BIN: the evidential_sequence_bench executable
#
# 1. revisit: the bundled scans driven forth and back at their real poses, 60 inserts, plain,
#    exact and live interleaved in one process (the ratios);
# 2. long: a SYNTHETIC generated off-road sequence (520 scans at 2 m a scan, 1.04 km), generated
#    into OUT/long_forest when absent (EVIDENTIAL_OCTOMAP_CLI: the CLI that generates it), each
#    method alone in its process: its cost as the map grows and its own RSS after every scan.
# Each takes 10 minutes to hours on 2 shared cores; nothing here runs in CI.
set -euo pipefail

bin="$1"
out="$2"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cli="${EVIDENTIAL_OCTOMAP_CLI:-${root}/build/core/src/tools/evidential_octomap}"
long="${out}/long_forest"
generate=(generate --scene forest --sensor os1-64 --scans 520 --seed 7 --route line
          --route-length 1100 --speed 20 --quiet --out "${long}")
mkdir -p "${out}"
cd "${root}"
export OMP_NUM_THREADS=2 OMP_WAIT_POLICY=passive

meta() { echo "$*" >>"${out}/meta.txt"; }
load() { cut -d' ' -f1-3 /proc/loadavg; }
run() {  # name, then the arguments of evidential_sequence_bench
  local name="$1"
  shift
  meta "${name}: evidential_sequence_bench $* --csv ${name}.csv"
  meta "${name}: start $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
  nice -n 10 "${bin}" "$@" --csv "${out}/${name}.csv"
  meta "${name}: end $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
}

: >"${out}/meta.txt"
meta "commit: $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- include src/core bench || echo ' (+ uncommitted changes)')"
kitti=(--data data/semantickitti_08_first10 --classes config/classes_semantickitti.yaml)
run revisit "${kitti[@]}" --order revisit --scans 10 --steps 60
if [[ ! -f "${long}/poses.txt" ]]; then
  meta "long: evidential_octomap ${generate[*]}"
  nice -n 10 "${cli}" "${generate[@]}"
fi
meta "long: trajectory $(awk '{x=$4; y=$8; z=$12; if (NR > 1) d += sqrt((x-px)^2 + (y-py)^2 + (z-pz)^2);
  px=x; py=y; pz=z} END {printf "%.0f m over %d scans", d, NR}' "${long}/poses.txt")"
long_args=(--data "${long}" --classes "${long}/classes.yaml" --order forward)
for method in exact live plain; do
  run "long_${method}" "${long_args[@]}" --only "${method}"
done
meta "profile: scripts/bench_profile.sh (perf), start $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
bash "${root}/scripts/bench_profile.sh" "${bin}" "${out}"
