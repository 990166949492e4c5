#!/usr/bin/env bash
# The cross-dataset tables (docs/experiments/calibration_tables.md, docs/images/reliability_cross_dataset.png):
# every rule on the bundled SemanticKITTI scans
# (learned and derived evidence), the RELLIS-3D scan (synthetic predictions) and generated
# off-road sequences (SYNTHETIC: four scene families, four network behaviours, evidence scales
# the map is not told), both protocols, the same queries for every row. The adaptive cap's
# constants were chosen on other generated sequences (new seeds here) and, leave-one-family-out,
# the bundled scans (docs/experiments/drivers/calibration/select_cap.sh).
#   bash docs/experiments/drivers/calibration/cross_dataset.sh [OUT_DIR]     (default out/cross_dataset; SCANS=24)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../../.." && pwd)"
out="${1:-${root}/out/cross_dataset}"
cli="${CLI:-${root}/build/core/src/tools/evidential_octomap}"
scans="${SCANS:-24}"
mkdir -p "${out}"
git -C "${root}" rev-parse --short HEAD > "${out}/commit.txt"
variants="dempster,sbki,ebs,reference_compat"
source "${root}/docs/experiments/drivers/calibration/datasets.sh"
generated_datasets "${cli}" "${out}" "${scans}"
compare_every_dataset "${cli}" "${out}" "${variants}" "${root}"
/usr/bin/python3 "${root}/docs/experiments/drivers/calibration/summarize.py" "${out}" \
  "${root}/docs/experiments/calibration_tables.md" "${root}/docs/images/reliability_cross_dataset.png" \
  "${root}/docs/experiments/results.md"
echo "wrote docs/experiments/calibration_tables.md and its block of docs/experiments/results.md (per-dataset tables in ${out}/compare_*/compare.md)"
