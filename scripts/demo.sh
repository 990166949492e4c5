#!/usr/bin/env bash
# The README's `bash scripts/demo.sh`: builds the core and the offline CLI (Release, build/core,
# the same build tree as scripts/test.sh), maps the bundled SemanticKITTI sequence with the
# evidential (Dempster-Shafer) map, compares it with the baselines, and says where the results are.
#
#   out/demo/map.ot        the semantic map (open with octomap::AbstractOcTree::read + our library)
#   out/demo/metrics.md    map and input-prediction metrics (metrics.json: the same, for scripts)
#   out/demo/*.png         top-down renders: semantic classes and uncertainty
#   out/compare/           dempster vs sbki vs ebs on the same queries (markdown table)
#
# JOBS=N sets build parallelism (default 2).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "${root}"
export PATH="/usr/bin:/bin:${PATH}"
jobs="${JOBS:-2}"
started=${SECONDS}

core_dir="build/core"
cli="${core_dir}/src/tools/evidential_octomap"
data="data/semantickitti_08_first10"
classes="config/classes_semantickitti.yaml"

note() { printf '\n==== %s\n' "$*"; }

note "dependencies"
bash scripts/install_deps.sh

note "build: core + offline CLI (${core_dir}, Release, -j${jobs})"
t0=${SECONDS}
cmake -S . -B "${core_dir}" -DCMAKE_BUILD_TYPE=Release -DEVIDENTIAL_OCTOMAP_ROS=OFF
# Only the CLI and what it links (scripts/test.sh builds the rest in the same tree).
target=()
if cmake --build "${core_dir}" --target help 2>/dev/null | grep -q 'evidential_octomap_cli'; then
  target=(--target evidential_octomap_cli)
fi
cmake --build "${core_dir}" -j"${jobs}" "${target[@]}"
echo "demo.sh: built in $((SECONDS - t0)) s"

if [[ ! -x "${cli}" ]]; then
  echo "demo.sh: error: the offline CLI was not built: ${cli} does not exist." >&2
  echo "demo.sh: it comes from src/tools (CMake option EVIDENTIAL_OCTOMAP_TOOLS=ON, needs OpenCV," \
    "CLI11 and nlohmann-json)." >&2
  exit 1
fi

rm -rf out/demo out/compare
mkdir -p out

note "map: ${cli} map --data ${data} --classes ${classes} --out out/demo"
t0=${SECONDS}
"${cli}" map --data "${data}" --classes "${classes}" --out out/demo
echo "demo.sh: mapped in $((SECONDS - t0)) s"

note "compare: ${cli} compare --data ${data} --classes ${classes} --out out/compare"
t0=${SECONDS}
"${cli}" compare --data "${data}" --classes "${classes}" --out out/compare
echo "demo.sh: compared in $((SECONDS - t0)) s"

note "results"
missing=0
for f in out/demo/map.ot out/demo/metrics.json out/demo/metrics.md; do
  if [[ -f "${f}" ]]; then
    echo "  ${f}  ($(du -h "${f}" | cut -f1))"
  else
    echo "  ${f}  MISSING" >&2
    missing=1
  fi
done
shopt -s nullglob
pngs=(out/demo/*.png)
compare_md=(out/compare/*.md)
shopt -u nullglob
if ((${#pngs[@]} == 0)); then
  echo "  out/demo/*.png  MISSING (no renders)" >&2
  missing=1
fi
for f in "${pngs[@]}" "${compare_md[@]}"; do echo "  ${f}"; done
if ((${#compare_md[@]} == 0)); then
  echo "  out/compare/*.md  MISSING (no comparison table)" >&2
  missing=1
fi

if [[ -f out/demo/metrics.md ]]; then
  note "out/demo/metrics.md"
  cat out/demo/metrics.md
fi
for f in "${compare_md[@]}"; do
  note "${f}"
  cat "${f}"
done

cat <<EOF

==== live in rviz (ROS 1)
Build the catkin workspace once (scripts/test.sh does the same, so if you ran it this is done):

  mkdir -p build/.catkin_ws/src && ln -sfn "\$PWD" build/.catkin_ws/src/evidential_octomap
  PATH=/usr/bin:\$PATH catkin_make -C build/.catkin_ws -DPYTHON_EXECUTABLE=/usr/bin/python3 \\
      -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF -DEVIDENTIAL_OCTOMAP_TOOLS=OFF -j${jobs}

then, in a shell at ${root}:

  source build/.catkin_ws/devel/setup.bash
  roslaunch evidential_octomap demo.launch

which plays ${data} as a live PointCloud2 stream with evidence into evidential_mapping_node and
opens rviz with the semantic and uncertainty maps.

demo.sh: done in $((SECONDS - started)) s
EOF
exit "${missing}"
