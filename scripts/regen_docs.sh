#!/usr/bin/env bash
# Regenerates the tables and pictures of README.md and docs/ from the scripts that produce them,
# each stamped with the commit and the date:
#
#   bash scripts/regen_docs.sh            README's pictures and results table (scripts/demo.sh),
#                                         docs/ros.md's launch-parameter table and rviz pictures
#   bash scripts/regen_docs.sh readme     only the README's pictures and table (no ROS needed)
#   bash scripts/regen_docs.sh rviz       only the rviz pictures (needs the catkin workspace)
#   bash scripts/regen_docs.sh all        also docs/data.md (scripts/generate_data_docs.sh), the
#                                         records of docs/experiments/ (scripts/results.sh,
#                                         scripts/bench.sh): hours on 2 cores
# Every run ends with the experiments index and the guides' figure blocks (scripts/docs/).
#
# The rviz pictures need a built catkin workspace (bash scripts/test.sh builds build/.catkin_ws),
# xvfb and imagemagick. Look at the pictures before committing them.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "${root}"
export PATH="/usr/bin:/bin:${PATH}"
what="${1:-default}"
out="build/regen_docs"
stamp="commit $(git rev-parse --short HEAD), $(date -u +%Y-%m-%d)"
note() { printf '\n==== regen_docs: %s\n' "$*"; }

# Replaces the line after `<!-- stamp:KEY -->` in FILE by TEXT.
stamp_line() {
  /usr/bin/python3 - "$1" "$2" "$3" <<'PY'
import sys
path, key, text = sys.argv[1:]
lines = open(path).read().split("\n")
marker = "<!-- stamp:%s -->" % key
i = lines.index(marker)  # a missing marker is an error: the docs and this script disagree
lines[i + 1] = text
open(path, "w").write("\n".join(lines))
PY
}

readme() {
  note "README: bash scripts/demo.sh (pictures, metrics)"
  DEMO_OUT="${out}" DEMO_VIEW=0 bash scripts/demo.sh
  cp "${out}/demo/semantic.png" docs/images/demo_semantic.png
  cp "${out}/demo/uncertainty.png" docs/images/demo_uncertainty.png
  /usr/bin/python3 scripts/docs/readme_results.py "${out}/demo/metrics.json" README.md
  stamp_line README.md pictures "*Pictures: \`bash scripts/regen_docs.sh\` (\`scripts/demo.sh\`), ${stamp}.*"
}

ros_tables() {
  note "docs/ros.md: which launch file sets which parameter"
  /usr/bin/python3 scripts/docs/launch_params.py docs/ros.md
}

rviz() {
  note "docs/ros.md: rviz pictures of demo.launch (the live profile), headless"
  local view
  for view in semantic uncertainty conflict cost; do
    local name="rviz_demo_${view}.png"
    [[ "${view}" == semantic ]] && name="rviz_demo.png"
    VIEW="${view}" RATE="${RATE:-0.25}" WAIT="${WAIT:-20}" \
      bash src/ros/scripts/rviz_screenshot.sh "docs/images/${name}"
  done
  stamp_line docs/ros.md pictures "*Pictures: \`bash scripts/regen_docs.sh rviz\` (\`demo.launch\`, live profile), ${stamp}.*"
}

others() {
  note "docs/data.md: scripts/generate_data_docs.sh"
  bash scripts/generate_data_docs.sh
  note "docs/experiments/results*.md, calibration_tables.md: scripts/results.sh"
  bash scripts/results.sh "${out}/results"
  note "docs/experiments/benchmarks.md: scripts/bench.sh"
  bash scripts/bench.sh
}

case "${what}" in
  default) readme; ros_tables; rviz ;;
  readme) readme ;;
  rviz) ros_tables; rviz ;;
  all) readme; ros_tables; rviz; others ;;
  *) sed -n '2,15p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//' >&2; exit 2 ;;
esac
note "docs/experiments/README.md and the guides' figure blocks: scripts/docs/"
/usr/bin/python3 scripts/docs/experiments_index.py
/usr/bin/python3 scripts/docs/figures.py
note "done (${stamp}); git diff --stat shows what changed"
