#!/usr/bin/env bash
# Memory of a long mission, and save/load/query of its map: the long SYNTHETIC sequence of
# scripts/bench_sequences.sh mapped by plain OctoMap, the exact insert with the whole map in
# memory, and the same insert in a LocalMap (radius 60 m, tiles on disk), each alone in its
# process (its own RSS after every scan); then evidential_map_io_bench on the whole map and on
# the local map's global map (leaf by leaf against the whole map). bench/local_map_report.py
# turns OUT into the section of docs/long_missions.md.
#
#   scripts/bench_local_map.sh BIN_DIR OUT   # BIN_DIR: build/core/bench (Release)
#
# About an hour on 2 cores; nothing here runs in CI.
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
  "${bin}/evidential_sequence_bench" "$@" --csv "${out}/${name}.csv"
  meta "${name}: end $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
}

: >"${out}/meta.txt"
meta "commit: $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- include src/core bench || echo ' (+ uncommitted changes)')"
if [[ ! -f "${long}/poses.txt" ]]; then
  meta "long: evidential_octomap ${generate[*]}"
  "${cli}" "${generate[@]}"
fi
meta "long: trajectory $(awk '{x=$4; y=$8; z=$12; if (NR > 1) d += sqrt((x-px)^2 + (y-py)^2 + (z-pz)^2);
  px=x; py=y; pz=z} END {printf "%.0f m over %d scans", d, NR}' "${long}/poses.txt")"
long_args=(--data "${long}" --classes "${long}/classes.yaml" --order forward)
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
