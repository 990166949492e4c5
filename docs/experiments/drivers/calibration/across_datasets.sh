#!/usr/bin/env bash
# Candidate settings of the default scored on every dataset of the cross-dataset table (the same
# datasets, generated as docs/experiments/drivers/calibration/datasets.sh says, and the same queries), with the
# leave-one-dataset-out choice among them; writes docs/experiments/PAGE.
#   bash docs/experiments/drivers/calibration/across_datasets.sh VARIANTS PAGE TITLE [OUT_DIR]   (SCANS=24)
#   e.g. VARIANTS=dempster,dempster:vertical_support=0.75,dempster:vertical_support=0.5
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../../.." && pwd)"
variants="$1"
page="$2"
title="$3"
out="${4:-${root}/out/across_datasets}"
cli="${CLI:-${root}/build/core/src/tools/evidential_octomap}"
scans="${SCANS:-24}"
mkdir -p "${out}"
source "${root}/docs/experiments/drivers/calibration/datasets.sh"
generated_datasets "${cli}" "${out}" "${scans}"
compare_every_dataset "${cli}" "${out}" "${variants}" "${root}"
/usr/bin/python3 "${root}/docs/experiments/drivers/calibration/across_datasets.py" "${out}" "${root}/docs/experiments/${page}" \
  "${title}" "SCANS=${scans} bash docs/experiments/drivers/calibration/across_datasets.sh ${variants} ${page} ..."
