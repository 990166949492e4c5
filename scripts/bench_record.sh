# Sourced by scripts/bench_sequences.sh and scripts/bench_local_map.sh: their record OUT/meta.txt
# (commit, date, load average, every command) and the long SYNTHETIC sequence both measure
# (520 scans at 2 m a scan, 1.04 km; generated into OUT/long_forest when absent).
# Needs: root, out, sequence_bench (the evidential_sequence_bench executable).
cli="${EVIDENTIAL_OCTOMAP_CLI:-${root}/build/core/src/tools/evidential_octomap}"
long="${out}/long_forest"
generate=(generate --scene forest --sensor os1-64 --scans 520 --seed 7 --route line
          --route-length 1100 --speed 20 --quiet --out "${long}")
long_args=(--data "${long}" --classes "${long}/classes.yaml" --order forward)
export OMP_NUM_THREADS=2 OMP_WAIT_POLICY=passive

meta() { echo "$*" >>"${out}/meta.txt"; }
load() { cut -d' ' -f1-3 /proc/loadavg; }
run() {  # name, then the arguments of evidential_sequence_bench
  local name="$1"
  shift
  meta "${name}: evidential_sequence_bench $* --csv ${name}.csv"
  meta "${name}: start $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
  nice -n 10 "${sequence_bench}" "$@" --csv "${out}/${name}.csv"
  meta "${name}: end $(date -u '+%Y-%m-%d %H:%M UTC'), load $(load)"
}
start_record() {  # a new OUT/meta.txt
  mkdir -p "${out}"
  : >"${out}/meta.txt"
  meta "commit: $(git -C "${root}" rev-parse --short HEAD)$(git -C "${root}" diff --quiet HEAD -- include src/core bench || echo ' (+ uncommitted changes)')"
}
make_long() {  # the long sequence, unless OUT holds it
  if [[ ! -f "${long}/poses.txt" ]]; then
    meta "long: evidential_octomap ${generate[*]}"
    nice -n 10 "${cli}" "${generate[@]}"
  fi
  meta "long: trajectory $(awk '{x=$4; y=$8; z=$12; if (NR > 1) d += sqrt((x-px)^2 + (y-py)^2 + (z-pz)^2);
    px=x; py=y; pz=z} END {printf "%.0f m over %d scans", d, NR}' "${long}/poses.txt")"
}
