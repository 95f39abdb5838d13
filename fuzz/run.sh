#!/usr/bin/env bash
# Builds the fuzz targets with clang in BUILD_DIR and runs each for SECONDS, JOBS at a time, then
# prints a table: executions, executions per second and the inputs that crashed, per target.
#   fuzz/run.sh BUILD_DIR SECONDS JOBS [TARGET...]     (default: every target of fuzz/CMakeLists.txt)
# With FUZZ_RUNS=N in the environment a target stops after N executions instead, SECONDS then being
# only its upper bound: `FUZZ_RUNS=10000000 fuzz/run.sh build-fuzz 3600 2` runs each to 10^7.
# Each target starts from its seeds (fuzz/corpus/<target>/) and the corpus earlier runs grew
# (BUILD_DIR/corpus/<target>/, kept between runs). A crashing input is saved as
# BUILD_DIR/crashes/<target>/crash-<sha1> (or leak-, timeout-, oom-); reproduce it with
# BUILD_DIR/bin/fuzz_<target> FILE. Exit status 1 when any target found something.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=$1 seconds=$2 jobs=$3
shift 3

cxx=${FUZZ_CXX:-clang++-14}
cc=${FUZZ_CC:-clang-14}
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFREMEN_FUZZ=ON -DCMAKE_CXX_COMPILER="$cxx" \
  -DCMAKE_C_COMPILER="$cc" >/dev/null
cmake --build "$build_dir" -j"$jobs" --target fuzz_targets

if [ $# -gt 0 ]; then
  targets=("$@")
else
  mapfile -t targets < <(sed -n 's/^fremen_fuzz_target(\([a-z_0-9]*\) .*/\1/p' fuzz/CMakeLists.txt)
fi

results=$(mktemp -d)
trap 'rm -rf "$results"' EXIT
touch "$results/.start"  # crash files newer than this are this run's

# One target: libFuzzer for `seconds`, its figures into $results/<target>.
run_one() {
  local target=$1
  local corpus="$build_dir/corpus/$target" crashes="$build_dir/crashes/$target"
  mkdir -p "$corpus" "$crashes"
  local log="$results/$target.log" status=0
  # -rss_limit_mb/-malloc_limit_mb: a small input that makes the code under test allocate over
  # 1 GiB is a finding (an unchecked length), not a machine problem. -timeout: 10 s for one input.
  local runs=()
  [ -z "${FUZZ_RUNS:-}" ] || runs=(-runs="$FUZZ_RUNS")
  "$build_dir/bin/fuzz_$target" -max_total_time="$seconds" "${runs[@]}" -print_final_stats=1 -rss_limit_mb=2048 \
    -malloc_limit_mb=1024 -timeout=10 -artifact_prefix="$crashes/" "$corpus" "fuzz/corpus/$target" \
    >"$log" 2>&1 || status=$?
  local execs secs
  execs=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\)/\1/p' "$log" | tail -1)
  secs=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$log" | tail -1)
  echo "$target ${execs:-0} ${secs:-$seconds} $status" >"$results/$target"
}

running=0
for target in "${targets[@]}"; do
  run_one "$target" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
done
wait

failed=0
printf '%-16s %8s %12s %10s  %s\n' target seconds executions exec/s findings
for target in "${targets[@]}"; do
  read -r name execs secs status <"$results/$target"
  [ "$secs" -gt 0 ] || secs=1
  findings=$(find "$build_dir/crashes/$target" -type f -newer "$results/.start" -printf '%f ' 2>/dev/null || true)
  if [ "$status" -ne 0 ] || [ -n "$findings" ]; then
    failed=1
    [ -n "$findings" ] || findings="exit status $status"
    echo "---- fuzz_$target:" >&2
    grep -E -A30 '^==[0-9]+==ERROR|runtime error|FUZZ_CHECK|^SUMMARY' "$results/$target.log" | head -60 >&2 || true
  fi
  printf '%-16s %8s %12s %10s  %s\n' "$name" "$secs" "$execs" "$((execs / secs))" "${findings:-0}"
done
exit "$failed"
