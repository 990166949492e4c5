#!/usr/bin/env bash
# Memory of a long mission, and save/load/query of its map: the long SYNTHETIC sequence of
# scripts/bench_record.sh mapped by plain OctoMap, the exact insert with the whole map in
# memory, and the same insert in a LocalMap (radius 60 m, tiles on disk), each alone in its
# process (its own RSS after every scan); then evidential_map_io_bench on the whole map after a
# third, two thirds and all of the sequence, and on the local map's global map (leaf by leaf
# against the whole map). bench/local_map_report.py turns OUT into docs/experiments/local_map.md.
#
#   scripts/bench_local_map.sh BIN_DIR OUT   # BIN_DIR: build/core/bench (Release)
#
# About an hour on 2 cores; nothing here runs in CI.
set -euo pipefail

bin="$(realpath "$1")"
out="$(mkdir -p "$2" && cd "$2" && pwd)"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
sequence_bench="${bin}/evidential_sequence_bench"
source "${root}/scripts/bench_record.sh"
cd "${root}"

start_record
make_long
rm -rf "${out}/tiles"
mkdir -p "${out}/tiles"
# Plain OctoMap (single-threaded) runs beside the other two: RSS is per process, and no CPU
# time of these runs is compared with another's.
run plain "${long_args[@]}" --only plain &
plain_pid=$!
run local "${long_args[@]}" --only local --radius 60 --tile-dir "${out}/tiles" --save "${out}/local_global.ot"
meta "local: tiles on disk at the end: $(find "${out}/tiles" -name 'tile_*.ot' | wc -l), $(du -sm "${out}/tiles" | cut -f1) MB"
run exact "${long_args[@]}" --only exact --save "${out}/exact_whole.ot"
wait "${plain_pid}"
meta "io: evidential_map_io_bench, start $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
"${bin}/evidential_map_io_bench" "${out}/exact_whole.ot" >"${out}/io_exact.json"
"${bin}/evidential_map_io_bench" "${out}/local_global.ot" --same-as "${out}/exact_whole.ot" \
  --repeats 1 >"${out}/io_local.json"
# Save, load and query against map size: the same insert stopped after a third and two thirds.
for scans in 173 346; do
  run "exact_${scans}" "${long_args[@]}" --only exact --scans "${scans}" --save "${out}/exact_${scans}.ot"
  "${bin}/evidential_map_io_bench" "${out}/exact_${scans}.ot" >"${out}/io_exact_${scans}.json"
  rm -f "${out}/exact_${scans}.ot"
done
meta "io: end $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
