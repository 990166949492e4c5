#!/usr/bin/env bash
# Renders the demo in rviz headless and saves a screenshot, so anyone can check what a user sees:
#   bash src/ros/scripts/rviz_screenshot.sh [out.png]      (default docs/images/rviz_demo.png)
#   VIEW=uncertainty bash src/ros/scripts/rviz_screenshot.sh docs/images/rviz_demo_uncertainty.png
#   VIEW=conflict bash src/ros/scripts/rviz_screenshot.sh docs/images/rviz_demo_conflict.png
# VIEW picks which map display of rviz_cfg/demo_semantickitti.rviz is ticked: semantic (default),
# uncertainty, conflict or cost (the 2-D projected cost map alone); the legend is
# always shown. Needs a built catkin workspace (WS, default build/.catkin_ws), xvfb and
# imagemagick. Runs demo.launch under Xvfb with software GL, waits until the map has been
# published after the last scan (SCANS, default 10), waits WAIT seconds more for rviz to draw,
# grabs the root window, stops everything. RATE sets the player's scans per second (default 0.4).
set -eo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
out="${1:-${root}/docs/images/rviz_demo.png}"
ws="${WS:-${root}/build/.catkin_ws}"
wait_draw="${WAIT:-15}"
view="${VIEW:-semantic}"
export PATH="/usr/bin:/bin:${PATH}"
mkdir -p "$(dirname "${out}")"
set +u
# shellcheck disable=SC1091
source "${ws}/devel/setup.bash"
export LIBGL_ALWAYS_SOFTWARE=1
tmp="$(mktemp -d)"
log="${tmp}/demo.log"

# The one config with the chosen display ticked instead of the semantic map.
config="${tmp}/view.rviz"
case "${view}" in
  semantic) cp "${root}/rviz_cfg/demo_semantickitti.rviz" "${config}" ;;
  uncertainty | conflict | cost)
    topic="/${view}_cells_vis_array"
    [[ "${view}" == cost ]] && topic="/projected_cost_map"
    /usr/bin/python3 - "${root}/rviz_cfg/demo_semantickitti.rviz" "${config}" "${topic}" <<'PY'
import sys, yaml
src, dst, topic = sys.argv[1:]
config = yaml.safe_load(open(src))
for d in config["Visualization Manager"]["Displays"]:
    shown = d.get("Marker Topic", d.get("Topic")) == topic
    if "Marker Topic" in d or d.get("Class") == "rviz/Map":
        d["Enabled"] = d["Value"] = shown
yaml.safe_dump(config, open(dst, "w"), sort_keys=False)
PY
    ;;
  *) echo "rviz_screenshot: VIEW must be semantic, uncertainty, conflict or cost" >&2; exit 2 ;;
esac

display=":$((90 + RANDOM % 9))"
Xvfb "${display}" -screen 0 1280x800x24 -nolisten tcp &
xvfb_pid=$!
cleanup() {
  [[ -n "${launch_pid:-}" ]] && kill -INT "${launch_pid}" 2>/dev/null && wait "${launch_pid}" 2>/dev/null
  kill "${xvfb_pid}" 2>/dev/null || true
}
trap cleanup EXIT
sleep 2
export DISPLAY="${display}"
port=$((11400 + RANDOM % 500))
export ROS_MASTER_URI="http://localhost:${port}"
# The launch file by path: `roslaunch evidential_octomap demo.launch` walks the package tree and
# fails with "multiple files named" when a workspace inside the repository links back to it.
roslaunch --port "${port}" "${root}/launch/demo.launch" rviz:=true rate:="${RATE:-0.4}" \
  rviz_config:="${config}" >"${log}" 2>&1 &
launch_pid=$!
echo "rviz_screenshot: demo running (log ${log}); waiting for the last scan's map"
published=0
for _ in $(seq 1 400); do
  grep -q "published .*over ${SCANS:-10} scans" "${log}" && { published=1; break; }
  if ! kill -0 "${launch_pid}" 2>/dev/null; then echo "demo died, see ${log}" >&2; exit 1; fi
  # rviz is not a required node: the launch outlives it, and a picture now would show nothing.
  if grep -q "\[rviz-[0-9]*\] process has died" "${log}"; then
    echo "rviz died (software GL under Xvfb), see ${log}; run again" >&2
    exit 1
  fi
  sleep 1
done
((published)) || { echo "no map after the last scan within 400 s, see ${log}" >&2; exit 1; }
sleep "${wait_draw}"
import -window root "${out}"
echo "rviz_screenshot: wrote ${out}"
