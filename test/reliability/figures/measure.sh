#!/usr/bin/env bash
# The before/after figures of docs/experiments/reliability.md:
# builds the core library of a commit (git archive, plain CMake, Release) and the small programs
# here against it, then runs them. OLD=1 (-DOLD_WRITERS) selects the code paths that commit had
# before the fixes (export writing in place, clearBox in src/ros, payload += float(increment)).
# Run from the repository root:
#   bash test/reliability/figures/measure.sh 66817db OLD=1    # before (main when #16 was filed)
#   bash test/reliability/figures/measure.sh HEAD              # after
set -euo pipefail
commit="$1"
old="${2:-}"
root="$(pwd)"
out="${root}/build/figures_$(git rev-parse --short "${commit}")"
mkdir -p "${out}/src" "${out}/run"
git archive "${commit}" | tar -x -C "${out}/src"
cmake -S "${out}/src" -B "${out}/build" -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF \
  -DEVIDENTIAL_OCTOMAP_TOOLS=OFF >/dev/null
cmake --build "${out}/build" --target evidential_octomap -j2 >/dev/null
here="${root}/test/reliability/figures"
cxx=(g++ -O2 -std=c++17 -fopenmp -I"${out}/src/include" -L"${out}/build" -Wl,-rpath,"${out}/build")
libs=(-levidential_octomap -loctomap -loctomath -lyaml-cpp)
defs=()
clear_sources=("${here}/clear_nan.cpp")
if [[ "${old}" == OLD=1 ]]; then
  defs=(-DOLD_WRITERS)
  clear_sources+=(-I"${out}/src/src/ros" "${out}/src/src/ros/map_editing.cpp")
fi
"${cxx[@]}" "${defs[@]}" "${clear_sources[@]}" "${libs[@]}" -o "${out}/clear_nan"
"${cxx[@]}" "${defs[@]}" "${here}/writer_trials.cpp" "${libs[@]}" -o "${out}/writer_trials"
"${cxx[@]}" "${here}/load_path.cpp" "${libs[@]}" -o "${out}/load_path"
for program in huge_evidence sensor_grid kernel_cost absorption; do
  "${cxx[@]}" "${defs[@]}" "${here}/${program}.cpp" "${libs[@]}" -o "${out}/${program}"
done
# The mutation outcomes need that commit's seed writer and fuzz targets (formats differ).
reseal=()
grep -q resealOtChecksum "${out}/src/fuzz/fuzz_targets.h" || reseal=(-DEVIDENTIAL_NO_RESEAL)
"${cxx[@]}" "${reseal[@]}" -I"${out}/src/fuzz" -I"${root}/fuzz" "${root}/fuzz/mutation_stats.cpp" \
  "${out}/src/fuzz/fuzz_targets.cpp" "${libs[@]}" -o "${out}/mutation_stats"
"${cxx[@]}" "${out}/src/fuzz/make_seeds.cpp" "${libs[@]}" -o "${out}/make_seeds"

cd "${out}/run"
echo "== ${commit} ${old} (load $(cut -d' ' -f1-3 /proc/loadavg))"
"${out}/huge_evidence" 2>/dev/null
"${out}/sensor_grid" 2>/dev/null
# Before the bound this setting ran for minutes and took gigabytes: stop it at 30 s and 4 GB.
(ulimit -v 4000000; /usr/bin/time -f "  wall %e s, CPU %U s, max RSS %M KB" timeout 30 \
  "${out}/kernel_cost") || echo "  (kernel: not finished after 30 s, or over 4 GB)"
"${out}/absorption"
"${out}/clear_nan"
rm -rf w && mkdir w && "${out}/writer_trials" threads w
rm -rf w && mkdir w && "${out}/writer_trials" export w 50
rm -rf w && mkdir w && "${out}/writer_trials" temps w 30
rm -f fifo && mkfifo fifo
/usr/bin/time -f "  wall %e s, max RSS %M KB" timeout 60 "${out}/load_path" /dev/zero || true
/usr/bin/time -f "  wall %e s" timeout 10 "${out}/load_path" fifo || echo "  (fifo: still blocked after 10 s)"
OMP_NUM_THREADS=1 "${out}/make_seeds" seeds "${out}/src" >/dev/null
OMP_NUM_THREADS=1 "${out}/mutation_stats" seeds/ot --mutations 6000
[[ ${#reseal[@]} -eq 0 ]] && OMP_NUM_THREADS=1 "${out}/mutation_stats" seeds/ot --mutations 6000 --reseal
exit 0
