# The generated datasets of the cross-dataset tables (SYNTHETIC, docs/data.md): scene, sensor,
# seed, network behaviour and an evidence scale the map is not told. Sourced by
# cross_dataset.sh and across_datasets.sh, so both score the same data.
#   generated_datasets CLI OUT SCANS   generates each into OUT/<name> unless it is there
#   compare_every_dataset CLI OUT VARIANTS ROOT
#                                      compare VARIANTS on each (OUT/compare_<name>) and on the
#                                      bundled scans with the RELLIS-3D scan (OUT/compare_bundled)
#   GENERATED_NAMES                    their names, in table order
GENERATED_SPECS=(
  "forest_good --scene forest --sensor os1-64 --seed 21 --network good"
  "grassland_poor --scene grassland --sensor os1-64 --seed 22 --network poor"
  "rocky_overconfident_x5 --scene rocky --sensor os1-128 --seed 23 --network overconfident --evidence-scale 5"
  "farm_underconfident_x0.3 --scene farm --sensor os1-32 --seed 24 --network underconfident --evidence-scale 0.3"
)
GENERATED_NAMES=()
for spec in "${GENERATED_SPECS[@]}"; do GENERATED_NAMES+=("${spec%% *}"); done

generated_datasets() {
  local cli="$1" out="$2" scans="$3" name args
  for spec in "${GENERATED_SPECS[@]}"; do
    read -r name args <<<"${spec}"
    [ -f "${out}/${name}/README.md" ] || "${cli}" generate --scans "${scans}" --out "${out}/${name}" -q ${args}
  done
}

compare_every_dataset() {
  local cli="$1" out="$2" variants="$3" root="$4" name
  for name in "${GENERATED_NAMES[@]}"; do
    "${cli}" compare --data "${out}/${name}" --classes "${out}/${name}/classes.yaml" --no-rellis \
      --sources file --variants "${variants}" --protocols reconstruction,held-out \
      --out "${out}/compare_${name}" --quiet > /dev/null
  done
  "${cli}" compare --data "${root}/data/semantickitti_08_first10" \
    --classes "${root}/config/classes_semantickitti.yaml" --sources learned,onehot \
    --variants "${variants}" --protocols reconstruction,held-out --out "${out}/compare_bundled" \
    --quiet > /dev/null
}
