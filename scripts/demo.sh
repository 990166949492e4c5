#!/usr/bin/env bash
# The README's first command. Builds the offline CLI (Release, build/core: the same build tree as
# scripts/test.sh, so after test.sh nothing is rebuilt), maps the bundled SemanticKITTI scans with
# the evidential (Dempster-Shafer) map, prints the metrics and shows the pictures.
#
#   bash scripts/demo.sh            map + metrics + top-down pictures (about a minute after the build)
#   bash scripts/demo.sh compare    the full comparison: every rule and ablation, two protocols,
#                                   three evidence derivations and RELLIS-3D (several minutes)
#
# Writes out/demo/{map.ot, metrics.md, metrics.json, semantic.png, uncertainty.png, error.png}
# (compare: out/compare/{compare.md, compare.json}). Knobs (environment):
#   JOBS=N          build parallelism (default 2)
#   DEMO_SCANS=N    map only the first N scans (default: all 10)
#   DEMO_OUT=dir    output directory (default out)
#   DEMO_VIEW=0     never open the pictures (default: open them when there is a display)
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "${root}"
export PATH="/usr/bin:/bin:${PATH}"
jobs="${JOBS:-2}"
scans="${DEMO_SCANS:-0}"
out="${DEMO_OUT:-out}"
started=${SECONDS}

core_dir="build/core"
cli="${core_dir}/src/tools/evidential_octomap"
data="data/semantickitti_08_first10"
classes="config/classes_semantickitti.yaml"

note() { printf '\n==== %s\n' "$*"; }

usage() {
  sed -n '2,17p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
}

mode="${1:-map}"
case "${mode}" in
  map | compare) ;;
  -h | --help)
    usage
    exit 0
    ;;
  *)
    echo "demo.sh: unknown command '${mode}'" >&2
    usage >&2
    exit 2
    ;;
esac

build_cli() {
  note "dependencies"
  bash scripts/install_deps.sh
  note "build: the offline CLI (${core_dir}, Release, -j${jobs})"
  local t0=${SECONDS} targets
  cmake -S . -B "${core_dir}" -DCMAKE_BUILD_TYPE=Release -DEVIDENTIAL_OCTOMAP_ROS=OFF >/dev/null
  # Only the CLI and what it links (scripts/test.sh builds the rest in the same tree). The target
  # list is read into a variable first: `cmake ... | grep -q` fails under pipefail when grep
  # stops reading early, which used to build every test and fuzz target here.
  targets="$(cmake --build "${core_dir}" --target help)"
  if grep -q 'evidential_octomap_cli' <<<"${targets}"; then
    cmake --build "${core_dir}" -j"${jobs}" --target evidential_octomap_cli
  else
    cmake --build "${core_dir}" -j"${jobs}"
  fi
  if [[ ! -x "${cli}" ]]; then
    echo "demo.sh: error: the offline CLI was not built: ${cli} does not exist." >&2
    echo "demo.sh: it comes from src/tools (CMake option EVIDENTIAL_OCTOMAP_TOOLS=ON, needs" \
      "OpenCV, CLI11 and nlohmann-json)." >&2
    exit 1
  fi
  echo "demo.sh: built in $((SECONDS - t0)) s"
}

# Opens the pictures in the desktop's viewer when there is a display (and DEMO_VIEW is not 0).
show_pictures() {
  if [[ "${DEMO_VIEW:-1}" != "0" && -n "${DISPLAY:-}" ]] && command -v xdg-open >/dev/null; then
    for f in "$@"; do xdg-open "${f}" >/dev/null 2>&1 & done
    echo "(opened in your image viewer; DEMO_VIEW=0 turns this off)"
  fi
}

run_map() {
  local dir="${out}/demo"
  rm -rf "${dir}"
  note "map: ${cli} map --data ${data} --classes ${classes} --evidence learned --out ${dir}"
  # It prints the metrics (the content of metrics.md) when it is done.
  # CPU beside wall time, and the load average: on a shared machine the wall time alone misleads.
  local TIMEFORMAT="demo.sh: mapped and evaluated in %0R s (CPU %1U s user + %1S s system)"
  time "${cli}" map --data "${data}" --classes "${classes}" --evidence learned --out "${dir}" \
    --scans "${scans}"
  echo "demo.sh: load average $(cut -d' ' -f1-3 /proc/loadavg)"

  local missing=0
  for f in map.ot metrics.md metrics.json semantic.png uncertainty.png error.png; do
    [[ -s "${dir}/${f}" ]] || { echo "demo.sh: MISSING ${dir}/${f}" >&2; missing=1; }
  done
  ((missing == 0)) || exit 1

  note "pictures"
  echo "  ${dir}/semantic.png     top-down, class colours"
  echo "  ${dir}/uncertainty.png  top-down, uncertainty (blue certain ... red uncertain)"
  echo "  ${dir}/error.png        top-down, voxels whose class disagrees with the ground truth"
  echo "  ${dir}/map.ot           the map: octomap::AbstractOcTree::read with this library"
  show_pictures "${dir}/semantic.png" "${dir}/uncertainty.png"
  cat <<EOF

==== next
  bash scripts/demo.sh compare      every rule and ablation on the same queries (several minutes)
  live in rviz (ROS 1): build the catkin workspace once (scripts/test.sh does it), then
    source build/.catkin_ws/devel/setup.bash
    roslaunch evidential_octomap demo.launch
EOF
}

run_compare() {
  local dir="${out}/compare" t0=${SECONDS}
  rm -rf "${dir}"
  note "compare: ${cli} compare --data ${data} --classes ${classes} --out ${dir}"
  echo "(one progress line per run on stderr; the tables follow when every run is done)"
  "${cli}" compare --data "${data}" --classes "${classes}" --out "${dir}" --scans "${scans}" \
    >/dev/null
  echo "demo.sh: compared in $((SECONDS - t0)) s"
  [[ -s "${dir}/compare.md" ]] || { echo "demo.sh: MISSING ${dir}/compare.md" >&2; exit 1; }
  note "${dir}/compare.md"
  cat "${dir}/compare.md"
}

build_cli
if [[ "${mode}" == compare ]]; then run_compare; else run_map; fi
echo
echo "demo.sh: done in $((SECONDS - started)) s"
