#!/usr/bin/env bash
# The kernel's cost before and after a change: plain OctoMap, the exact insert (library
# defaults) and the live launch's settings, interleaved in one process, for two builds of
# evidential_sequence_bench run one after the other, on the bundled scans forth and back
# (revisit, 30 inserts: first pass 0-9, steady state 10-29; each also with the movable clearing
# off) and on a SYNTHETIC generated
# off-road sequence (os1-64 forest, 40 scans, each once: first 10, then 10-39), how the two
# builds' maps differ (evidential_map_diff), the perf profile of each (scripts/bench_profile.sh);
# CSV files and meta.txt (commits, load average, commands) into OUT, then the record
# docs/experiments/RECORD.md (default kernel_one_hot, titled TITLE) with bench/kernel_ab_report.py.
#
#   scripts/bench_kernel_ab.sh BEFORE_BIN AFTER_BIN OUT [RECORD [TITLE [NOTE]]]   # ~30 min
# Outside CI; CLI (for generating the sequence): EVIDENTIAL_OCTOMAP_CLI or build/core's.
set -euo pipefail

before="$(realpath "$1")"
after="$(realpath "$2")"
out="$(mkdir -p "$3" && cd "$3" && pwd)"
record="${4:-kernel_one_hot}"
title="${5:-}"
note="${6:-}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cli="${EVIDENTIAL_OCTOMAP_CLI:-${root}/build/core/src/tools/evidential_octomap}"
offroad="${out}/forest40"
export OMP_NUM_THREADS=2 OMP_WAIT_POLICY=passive
cd "${root}"

meta() { echo "$*" >>"${out}/meta.txt"; }
load() { cut -d' ' -f1-3 /proc/loadavg; }
run() {  # name, binary, then the arguments of evidential_sequence_bench
  local name="$1" bin="$2"
  shift 2
  meta "${name}: $(basename "${bin}") $* --csv ${name}.csv"
  meta "${name}: start $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
  "${bin}" "$@" --csv "${out}/${name}.csv" >/dev/null
  meta "${name}: end $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
}

: >"${out}/meta.txt"
meta "before: ${BEFORE_COMMIT:-unknown}; after: commit $(git rev-parse --short HEAD)"
if [[ ! -f "${offroad}/poses.txt" ]]; then
  generate=(generate --scene forest --sensor os1-64 --scans 40 --seed 7 --route line
            --route-length 1100 --speed 20 --quiet --out "${offroad}")
  meta "offroad: evidential_octomap ${generate[*]}"
  "${cli}" "${generate[@]}"
fi
kitti=(--data data/semantickitti_08_first10 --classes config/classes_semantickitti.yaml
       --order revisit --scans 10 --steps 30)
forest=(--data "${offroad}" --classes "${offroad}/classes.yaml" --order forward)
# What the default clearing of movable classes costs, in the same runs (both builds have them).
methods=(--methods plain,exact,exact_no_clearing,live,live_no_clearing)
for which in before after; do
  bin="${before}"
  [[ "${which}" == after ]] && bin="${after}"
  run "revisit_${which}" "${bin}" "${kitti[@]}" "${methods[@]}"
  run "offroad_${which}" "${bin}" "${forest[@]}" "${methods[@]}"
done
# The maps of both builds after the 30 inserts, leaf by leaf (evidential_map_diff beside AFTER).
for method in exact live; do
  for which in before after; do
    bin="${before}"
    [[ "${which}" == after ]] && bin="${after}"
    run "save_${method}_${which}" "${bin}" "${kitti[@]}" --only "${method}" \
      --save "${out}/${method}_${which}.ot"
  done
  meta "map_diff_${method}: evidential_map_diff ${method}_before.ot ${method}_after.ot"
  "$(dirname "${after}")/evidential_map_diff" "${out}/${method}_before.ot" \
    "${out}/${method}_after.ot" >"${out}/map_diff_${method}.txt"
done
for which in before after; do
  bin="${before}"
  [[ "${which}" == after ]] && bin="${after}"
  meta "profile_${which}: scripts/bench_profile.sh, start $(date -u '+%Y-%m-%d %H:%M UTC')," \
    "load $(load)"
  bash "${root}/scripts/bench_profile.sh" "${bin}" "${out}/prof_${which}" >/dev/null
done
command="scripts/bench_kernel_ab.sh BEFORE_BIN AFTER_BIN OUT"
[[ $# -ge 4 ]] && command+=" ${record}"
[[ -n "${title}" ]] && command+=" '${title}'"
[[ -n "${note}" ]] && command+=" NOTE"
python3 "${root}/bench/kernel_ab_report.py" "${out}" --command "${command}" \
  ${title:+--title "${title}"} ${note:+--note "${note}"} >"${root}/docs/experiments/${record}.md"
