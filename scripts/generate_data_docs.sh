#!/usr/bin/env bash
# Pictures of docs/data.md and numbers of docs/experiments/data.md, from datasets the generator writes here (all SYNTHETIC):
#   docs/images/data_topdown_<family>.png  top-down view of each scene family (GT classes)
#   docs/images/data_reliability.png       per-point reliability diagrams of the network presets
#   build/data_docs/metrics.md             per-point metrics of each preset (pasted into docs/experiments/data.md)
#   build/data_docs/families.md            the same of the good preset in each family
# Needs the CLI (built here if missing) and /usr/bin/python3 with numpy, matplotlib, yaml
# (scripts/packages.txt). Usage: bash scripts/generate_data_docs.sh   (JOBS=N, default 2)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "${root}"
export PATH="/usr/bin:/bin:${PATH}"
cli="build/core/src/tools/evidential_octomap"
work="build/data_docs"
if [[ ! -x "${cli}" ]]; then
  cmake -S . -B build/core -DCMAKE_BUILD_TYPE=Release -DEVIDENTIAL_OCTOMAP_ROS=OFF
  cmake --build build/core -j"${JOBS:-2}" --target evidential_octomap_cli
fi
mkdir -p "${work}" docs/images
stamp="SYNTHETIC data - evidential_octomap generate - commit $(git rev-parse --short HEAD) - $(date -u +%Y-%m-%d)"

# Per-point metrics of network_metrics.json as a table row: name, then the columns below.
row() {
  python3 - "$1" "$2" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
print("| %s | %d | %.3f | %.3f | %.3f | %.3f | %.3f | %.3f |" % (
    sys.argv[2], m["points"], m["accuracy"], m["auroc_vacuity"],
    m["auroc_one_minus_max_softmax"], m["ece_softmax"], m["ece_dirichlet_mean"],
    m["wrong_cell_accuracy"]))
PY
}
header() {
  echo "| $1 | points | accuracy | AUROC u = C/S | AUROC 1 - max softmax | ECE softmax | ECE Dirichlet mean | accuracy in wrong cells |"
  echo "|---|---|---|---|---|---|---|---|"
}

# One dataset per scene family: 200 scans (40 m of a 400 m loop), os1-64; every 4th scan drawn.
header "family (good preset)" >"${work}/families.md"
for family in forest grassland rocky farm; do
  "${cli}" generate --scene "${family}" --sensor os1-64 --scans 200 --seed 1 -q \
    --out "${work}/${family}"
  row "${work}/${family}/network_metrics.json" "${family}" >>"${work}/families.md"
  python3 scripts/data_docs.py topdown "${work}/${family}" "docs/images/data_topdown_${family}.png" \
    --every 4 --extent 70 --title "${family} (SYNTHETIC, os1-64, seed 1, 200 scans)" --stamp "${stamp}"
done

# The network presets on one forest sequence (the same scene and scans; only the network differs).
header "preset (forest, seed 3)" >"${work}/metrics.md"
specs=()
for preset in good poor overconfident underconfident; do
  "${cli}" generate --scene forest --sensor os1-64 --scans 200 --seed 3 --network "${preset}" -q \
    --out "${work}/forest_${preset}"
  row "${work}/forest_${preset}/network_metrics.json" "${preset}" >>"${work}/metrics.md"
  specs+=("${preset}=${work}/forest_${preset}")
done
python3 scripts/data_docs.py reliability docs/images/data_reliability.png "${specs[@]}" \
  --stamp "${stamp} - forest, os1-64, seed 3, 200 scans"
cat "${work}/metrics.md" "${work}/families.md"
echo "wrote docs/images/data_topdown_{forest,grassland,rocky,farm}.png, data_reliability.png"
