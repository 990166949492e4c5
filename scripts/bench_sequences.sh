#!/usr/bin/env bash
# Measures the steady-state and long-sequence benchmarks with evidential_sequence_bench into OUT
# (CSV files and meta.txt: commit, date, load average, commands). scripts/bench.sh calls it and
# turns the files into docs/experiments/benchmarks.md with bench/sequence_report.py.
#
#   scripts/bench_sequences.sh BIN OUT    # BIN: the evidential_sequence_bench executable
#
# 1. revisit: the bundled scans driven forth and back at their real poses, 60 inserts, plain,
#    exact and live interleaved in one process (the ratios);
# 2. long: the SYNTHETIC off-road sequence of scripts/bench_record.sh (EVIDENTIAL_OCTOMAP_CLI:
#    the CLI that generates it), each method alone in its process: its cost as the map grows and
#    its own RSS after every scan.
# Each takes 10 minutes to hours on 2 shared cores; nothing here runs in CI.
set -euo pipefail

bin="$(realpath "$1")"
out="$(mkdir -p "$2" && cd "$2" && pwd)"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
sequence_bench="${bin}"
source "${root}/scripts/bench_record.sh"
cd "${root}"

start_record
kitti=(--data data/semantickitti_08_first10 --classes config/classes_semantickitti.yaml)
run revisit "${kitti[@]}" --order revisit --scans 10 --steps 60
make_long
for method in exact live plain; do
  run "long_${method}" "${long_args[@]}" --only "${method}"
done
meta "profile: scripts/bench_profile.sh (perf), start $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
bash "${root}/scripts/bench_profile.sh" "${bin}" "${out}"
