#!/usr/bin/env bash
# Does a `calibrate` fit on a user's validation split carry over to their other data? For each
# generated dataset of the cross-dataset table, a validation sequence of the same scene, sensor,
# network and evidence scale but another seed (SCANS_VALIDATION scans) is calibrated, and the
# cap of the file `calibrate` writes (the fit, or -1 when the fit is not better than the adaptive
# cap beyond its interval) is scored on the table's sequence (both protocols) against the
# adaptive cap. The bundled scans are calibrated on their first half, the held-out protocol's
# mapped scans, and scored on the held-out queries (the second half). Writes docs/experiments/PAGE (default
# results_calibrate.md).
#   bash docs/experiments/drivers/calibration/calibrate_transfer.sh [OUT_DIR] [PAGE]
#   (SCANS=24, SCANS_VALIDATION=8)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../../.." && pwd)"
out="${1:-${root}/out/across_datasets}"
page="${2:-results_calibrate.md}"
cli="${CLI:-${root}/build/core/src/tools/evidential_octomap}"
scans="${SCANS:-24}"
validation_scans="${SCANS_VALIDATION:-8}"
mkdir -p "${out}/calibrate"
source "${root}/docs/experiments/drivers/calibration/datasets.sh"
generated_datasets "${cli}" "${out}" "${scans}"

# The variants scored: the adaptive cap, the cap `calibrate` wrote into FILE and, when that is
# the adaptive one, the fit it did not keep (what --keep-fit writes).
variants_of() {
  local written fit
  written="$(sed -n 's/^evidence_cap: //p' "$1")"
  fit="$(sed -n 's/^# Fitted cap \([^:]*\):.*/\1/p' "$1")"
  echo "dempster,dempster:evidence_cap=${written}$([ "${written}" = -1 ] &&
    echo ",dempster:evidence_cap=${fit}")"
}

for spec in "${GENERATED_SPECS[@]}"; do
  read -r name args <<<"${spec}"
  seed="$(sed -n 's/.*--seed \([0-9]*\).*/\1/p' <<<"${args}")"
  validation="${out}/calibrate/validation_${name}"
  [ -f "${validation}/README.md" ] || "${cli}" generate --scans "${validation_scans}" \
    --out "${validation}" -q ${args/--seed ${seed}/--seed $((seed + 100))}
  "${cli}" calibrate --data "${validation}" --classes "${validation}/classes.yaml" \
    --evidence file --out "${out}/calibrate/${name}.yaml" -q > /dev/null
  "${cli}" compare --data "${out}/${name}" --classes "${out}/${name}/classes.yaml" --no-rellis \
    --sources file --variants "$(variants_of "${out}/calibrate/${name}.yaml")" \
    --protocols reconstruction,held-out \
    --out "${out}/calibrate/compare_${name}" --quiet > /dev/null
done

kitti=(--data "${root}/data/semantickitti_08_first10"
  --classes "${root}/config/classes_semantickitti.yaml")
for evidence in learned onehot; do
  "${cli}" calibrate "${kitti[@]}" --scans 5 --evidence "${evidence}" \
    --out "${out}/calibrate/bundled_${evidence}.yaml" -q > /dev/null
  "${cli}" compare "${kitti[@]}" --no-rellis --sources "${evidence}" --protocols held-out \
    --variants "$(variants_of "${out}/calibrate/bundled_${evidence}.yaml")" \
    --out "${out}/calibrate/compare_bundled_${evidence}" --quiet > /dev/null
done

/usr/bin/python3 "${root}/docs/experiments/drivers/calibration/calibrate_transfer.py" "${out}/calibrate" \
  "${root}/docs/experiments/${page}" \
  "SCANS=${scans} SCANS_VALIDATION=${validation_scans} bash \
docs/experiments/drivers/calibration/calibrate_transfer.sh"
