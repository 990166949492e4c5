#!/usr/bin/env bash
# Where the exact insert spends its CPU at steady state: `perf record` over 30 inserts of the
# bundled scans forth and back (the exact insert alone, library defaults, 50 m, 2 threads), the
# functions' shares of the samples (self time) as a markdown table in OUT/profile.md.
#
#   scripts/bench_profile.sh BIN OUT   # BIN: evidential_sequence_bench (Release)
# Needs perf (Debian linux-perf); outside CI.
set -euo pipefail

bin="$1"
out="$2"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mkdir -p "${out}"
cd "${root}"
args=(--data data/semantickitti_08_first10 --classes config/classes_semantickitti.yaml
      --order revisit --scans 10 --steps 30 --only exact)
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
OMP_NUM_THREADS=2 OMP_WAIT_POLICY=passive nice -n 10 \
  perf record -q -F 499 -o "${out}/perf.data" "${bin}" "${args[@]}" --csv "${out}/profile_steps.csv" \
  2>/dev/null
{
  echo "\`perf record -F 499 evidential_sequence_bench ${args[*]}\` ($(date -u '+%Y-%m-%d %H:%M UTC'),"
  echo "commit $(git rev-parse --short HEAD), load average ${load_before} before, all 30 inserts:"
  echo "first pass and steady state). Self time of each function, share of all samples:"
  echo
  echo "| share | function |"
  echo "|---|---|"
  perf report -i "${out}/perf.data" --no-children --sort symbol --stdio 2>/dev/null |
    awk '/^ +[0-9.]+%/ && n < 20 {share = $1; $1 = ""; $2 = "";
         sub(/^ +/, ""); sub(/ +- +- *$/, ""); gsub(/\|/, "\\|"); print "| " share " | `" $0 "` |"; n++}'
} >"${out}/profile.md"
