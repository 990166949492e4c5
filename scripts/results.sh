#!/usr/bin/env bash
# Writes every table and picture of docs/experiments/results.md and the pages it links: results_tables.md
# (every rule x evidence source x protocol on the bundled scans), results_ablation.md (kernel
# ablations of the default), images/quality_learned.png, and the cross-dataset block,
# calibration_tables.md and images/reliability_cross_dataset.png (docs/experiments/drivers/calibration/
# cross_dataset.sh), results_vertical_support.md, results_ground_support.md, results_sigma0.md,
# results_ds_multiplier.md, results_other_class_weight.md, results_length_scale.md and
# results_evidence_cap.md (docs/experiments/drivers/calibration/across_datasets.sh), results_calibrate.md
# (calibrate_transfer.sh).
# Each page is stamped with the commit and date.
#   bash scripts/results.sh [OUT_DIR]      (default out/results; ~1.5 h on 2 cores)
# CROSS=0 skips the cross-dataset part (docs/experiments/drivers/calibration/cross_dataset.sh).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="${1:-${root}/out/results}"
cli="${CLI:-${root}/build/core/src/tools/evidential_octomap}"
kitti=(--data "${root}/data/semantickitti_08_first10"
  --classes "${root}/config/classes_semantickitti.yaml")
stamp="commit $(git -C "${root}" rev-parse --short HEAD), $(date -u +%Y-%m-%d)"
mkdir -p "${out}"

# docs/experiments/<page>: a title, what made it, then the compare.md of <dir> verbatim.
publish() {
  local page="$1" title="$2" dir="$3" command="$4"
  { printf '# %s\n\nOutput of `%s`, verbatim (`compare.md`; %s, written by scripts/results.sh).\n\n' \
      "${title}" "${command}" "${stamp}"
    sed "s|${root}/||g" "${dir}/compare.md"; } > "${root}/docs/experiments/${page}"
}

"${cli}" compare "${kitti[@]}" --sources onehot,knn-vote,confusion,learned \
  --variants dempster,sbki,ebs,reference_compat --protocols reconstruction,held-out \
  --out "${out}/compare_all" --quiet > /dev/null
publish results_tables.md "Every rule, every evidence source, both protocols (bundled data)" \
  "${out}/compare_all" "evidential_octomap compare --sources onehot,knn-vote,confusion,learned --variants dempster,sbki,ebs,reference_compat --protocols reconstruction,held-out"

ablation="dempster,ebs,dempster:ds_multiplier=2,dempster:ds_multiplier=3,dempster:ds_multiplier=8"
ablation+=",dempster:length_scale=0.25,dempster:length_scale=0.35,dempster:sigma0=1"
ablation+=",dempster:beta=0.5,dempster:downsampling=average,dempster:other_class_weight=1"
"${cli}" compare "${kitti[@]}" --sources onehot,learned --protocols reconstruction,held-out \
  --no-rellis --variants "${ablation}" --out "${out}/ablation" --quiet > /dev/null
publish results_ablation.md "Kernel and down-sampling ablations of the default (bundled data)" \
  "${out}/ablation" "evidential_octomap compare --sources onehot,learned --protocols reconstruction,held-out --no-rellis --variants ${ablation}"

"${cli}" map "${kitti[@]}" --evidence learned --out "${out}/learned" -q > /dev/null
cp "${out}/learned/quality.png" "${root}/docs/images/quality_learned.png"

if [ "${CROSS:-1}" != 0 ]; then
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/cross_dataset.sh" "${out}/cross_dataset"
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/across_datasets.sh" \
    dempster,dempster:vertical_support=0.75,dempster:vertical_support=0.5 \
    results_vertical_support.md "The kernel support's height (vertical_support) across datasets" \
    "${out}/across_datasets"
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/across_datasets.sh" \
    dempster:ground_vertical_support=1,dempster:ground_vertical_support=0.5,dempster \
    results_ground_support.md \
    "The support height of ground classes (ground_vertical_support) across datasets" \
    "${out}/across_datasets"
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/across_datasets.sh" \
    dempster:sigma0=1,dempster:sigma0=0.85,dempster,dempster:sigma0=0.5,ebs results_sigma0.md \
    "A point's reliability discount (the kernel amplitude sigma0) across datasets" \
    "${out}/across_datasets"
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/across_datasets.sh" \
    dempster,dempster:ds_multiplier=3,dempster:ds_multiplier=8 results_ds_multiplier.md \
    "The count cap (ds_multiplier) across datasets" "${out}/across_datasets"
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/across_datasets.sh" \
    dempster:other_class_weight=1,dempster,dempster:other_class_weight=0.5,dempster:other_class_weight=0 \
    results_other_class_weight.md \
    "A point's weight in voxels that hold other classes (other_class_weight) across datasets" \
    "${out}/across_datasets"
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/across_datasets.sh" \
    dempster,dempster:length_scale=0.35,dempster:length_scale=0.4,dempster:length_scale=0.45,ebs,\
ebs:length_scale=0.35 \
    results_length_scale.md "The kernel length scale (length_scale) across datasets" \
    "${out}/across_datasets"
  caps=dempster
  for cap in 2.5 3 4 5 6 8 10; do caps+=",dempster:evidence_cap=${cap}"; done
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/across_datasets.sh" "${caps}" \
    results_evidence_cap.md "The read-out cap across datasets: adaptive against fixed" \
    "${out}/across_datasets"
  SCANS="${SCANS:-24}" bash "${root}/docs/experiments/drivers/calibration/calibrate_transfer.sh" \
    "${out}/across_datasets"
fi
