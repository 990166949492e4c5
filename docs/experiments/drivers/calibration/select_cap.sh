#!/usr/bin/env bash
# Chooses the adaptive read-out cap's constants (docs/experiments/cap_selection.md) from scratch: generates the
# training sequences (SYNTHETIC: four scene families, network behaviours and evidence scales),
# maps them and the bundled scans (learned and derived one-hot evidence) with the CLI, reads the
# fused log-evidence of every GT query back, and selects leave-one-family-out.
#   bash docs/experiments/drivers/calibration/select_cap.sh [OUT_DIR]      (default out/select_cap; ~30 min)
# Needs the CLI (build/core) and the Python package (build/python-venv, scripts/test.sh makes both).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../../.." && pwd)"
out="${1:-${root}/out/select_cap}"
cli="${CLI:-${root}/build/core/src/tools/evidential_octomap}"
python="${PYTHON:-${root}/build/python-venv/bin/python}"
scans="${SCANS:-30}"
training=(
  "farm_poor --scene farm --sensor os1-32 --seed 18 --network poor"
  "farm_under --scene farm --sensor os1-64 --seed 14 --network underconfident"
  "forest_good --scene forest --sensor os1-64 --seed 11 --network good"
  "forest_s02 --scene forest --sensor os1-32 --seed 15 --network good --evidence-scale 0.2"
  "grass_hdl --scene grassland --sensor hdl-64 --seed 17 --network good --columns 1024"
  "grass_poor --scene grassland --sensor os1-64 --seed 12 --network poor"
  "rocky_over --scene rocky --sensor os1-128 --seed 13 --network overconfident"
  "rocky_s5 --scene rocky --sensor os1-64 --seed 16 --network good --evidence-scale 5"
)
mkdir -p "${out}/maps"
: > "${out}/manifest.tsv"

# Maps a dataset for both protocols with read-out cap 80 (the stored evidence does not depend
# on the cap; 80 only keeps it readable) and adds it to the manifest.
map_both() {
  local name="$1" data="$2" classes="$3" evidence="$4" protocol
  for protocol in reconstruction held-out; do
    [ -f "${out}/maps/${name}_${protocol}/map.ot" ] ||
      "${cli}" map --data "${data}" --classes "${classes}" --evidence "${evidence}" \
        --evidence-cap 80 --protocol "${protocol}" --out "${out}/maps/${name}_${protocol}" -q \
        > /dev/null
  done
  printf '%s\t%s\t%s\n' "${name}" "${data}" "${classes}" >> "${out}/manifest.tsv"
}

for spec in "${training[@]}"; do
  read -r name args <<<"${spec}"
  data="${out}/data/${name}"
  [ -f "${data}/README.md" ] || "${cli}" generate --scans "${scans}" --out "${data}" -q ${args}
  map_both "${name}" "${data}" "${data}/classes.yaml" file
done
kitti="${root}/data/semantickitti_08_first10"
map_both kitti_learned "${kitti}" "${root}/config/classes_semantickitti.yaml" learned
map_both kitti_onehot "${kitti}" "${root}/config/classes_semantickitti.yaml" onehot
"${python}" "${root}/docs/experiments/drivers/calibration/collect_log_evidence.py" "${out}"
"${python}" "${root}/docs/experiments/drivers/calibration/select_cap.py" "${out}" | tee "${out}/selection.md"
# Into docs/experiments/cap_selection.md, between its selection markers, stamped.
/usr/bin/python3 - "${root}/docs/experiments/cap_selection.md" "${out}/selection.md" \
  "commit $(git -C "${root}" rev-parse --short HEAD), $(date -u +%Y-%m-%d)" <<'EOF'
import sys
page_path, table_path, stamp = sys.argv[1:]
begin, end = "<!-- selection: begin -->", "<!-- selection: end -->"
page = open(page_path).read()
if begin not in page or end not in page:
    sys.exit("%s: no %s ... %s block" % (page_path, begin, end))
head, rest = page.split(begin, 1)
text = ("Output of `bash docs/experiments/drivers/calibration/select_cap.sh` (%s), verbatim:\n" % stamp +
        open(table_path).read())
open(page_path, "w").write(head + begin + "\n" + text + end + rest.split(end, 1)[1])
EOF
