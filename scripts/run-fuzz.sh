#!/usr/bin/env bash
# Runs every libFuzzer target of a LAZYBOE_FUZZ build (make fuzz) one after the other, each for
# SECONDS or until RUNS executions, and prints executions, coverage and corpus per target.
#   usage: scripts/run-fuzz.sh BUILD_DIR SECONDS [RUNS] [TARGET...]
# The committed seeds (tests/fuzz/corpus/<target>) are read, never written: what libFuzzer adds
# goes to BUILD_DIR/fuzz-corpus/<target>; crashes, leaks, timeouts and out-of-memory inputs to
# BUILD_DIR/fuzz-artifacts/<target>/ (then the script exits 1); logs to BUILD_DIR/fuzz-logs/.
set -uo pipefail
build=${1:?usage: run-fuzz.sh BUILD_DIR SECONDS [RUNS] [TARGET...]}
seconds=${2:?seconds}
runs=${3:-0}
shift $(( $# < 3 ? $# : 3 ))
src=$(cd "$(dirname "$0")/.." && pwd)
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(robot_config urdf environment query_line problems csv trajectory_csv bundle runs_csv edge_index)

# Inputs a little larger than the largest seed (the Panda URDF is 12 kB, a bundle 16 to 20 kB).
max_len() {
  case $1 in
    urdf) echo 16384 ;;
    bundle) echo 24576 ;;
    edge_index) echo 8192 ;;
    robot_config) echo 8192 ;;
    *) echo 4096 ;;
  esac
}

status=0
summary=()
for t in "${targets[@]}"; do
  bin=$build/bin/fuzz_$t
  [[ -x $bin ]] || { echo "run-fuzz: $bin missing (cmake --build $build --target fuzz_targets)" >&2; exit 2; }
  work=$build/fuzz-corpus/$t art=$build/fuzz-artifacts/$t log=$build/fuzz-logs/$t.log
  mkdir -p "$work" "$art" "$(dirname "$log")"
  dict=()
  [[ -f $src/tests/fuzz/$t.dict ]] && dict=(-dict="$src/tests/fuzz/$t.dict")
  limit=()
  [[ $runs -gt 0 ]] && limit=(-runs="$runs")
  export LSAN_OPTIONS="suppressions=$src/tests/fuzz/lsan.supp:print_suppressions=0"
  start=$(date +%s)
  "$bin" -max_total_time="$seconds" "${limit[@]}" -max_len="$(max_len "$t")" -timeout=10 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$art/" "${dict[@]}" \
    "$work" "$src/tests/fuzz/corpus/$t" > "$log" 2>&1
  rc=$?
  elapsed=$(( $(date +%s) - start ))
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  last=$(grep -E '^#[0-9]+' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]*' <<< "$last" | grep -o '[0-9]*')
  ft=$(grep -o 'ft: [0-9]*' <<< "$last" | grep -o '[0-9]*')
  corp=$(grep -o 'corp: [0-9]*/[0-9A-Za-z]*' <<< "$last" | cut -d' ' -f2)
  found=$(find "$art" -type f | wc -l)
  line=$(printf '%-15s %10s execs %6s s  cov %5s  ft %6s  corpus %-10s findings %s' "$t" "${execs:-?}" \
    "$elapsed" "${cov:-?}" "${ft:-?}" "${corp:-?}" "$found")
  echo "$line"
  summary+=("$line")
  if [[ $rc -ne 0 || $found -ne 0 ]]; then
    status=1
    echo "run-fuzz: $t: finding (exit $rc), see $log and $art" >&2
    grep -E 'ERROR|SUMMARY|runtime error|what\(\)' "$log" | head -5 >&2
  fi
done
limit_text=""; [[ $runs -gt 0 ]] && limit_text=", at most $runs executions"
echo "--- fuzzing summary (at most ${seconds} s per target${limit_text}) ---"
printf '%s\n' "${summary[@]}"
exit $status
