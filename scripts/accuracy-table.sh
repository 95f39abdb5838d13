#!/usr/bin/env bash
# Developer script, not a test: compares `fremenctl eval` with the original FremenServer's published
# errors on the shared datasets and prints a markdown table.
#
#   scripts/accuracy-table.sh [bin-dir] [data-dir]
#     bin-dir   where fremenctl is (default: build/bin)
#     data-dir  the shared data folder (default: ../shared/data beside the repository); the
#               original's figures are read from its README.md, the data from derived/<name>/
#
# Columns: the original's err at orders 0..5; ours with its settings (100 periods
# floor(604800/k), --floor-periods); the largest |Δ| between the two (marked ✗ above 0.01); ours
# with the default Ω (24 periods of a week).
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
bin_dir=${1:-$root/build/bin}
data_dir=${2:-$root/../shared/data}
fremenctl=$bin_dir/fremenctl
tolerance=0.01

datasets=(tom_door_min aruba_living_room aruba_master_bedroom aruba_sleeping
          kasteren_bedroom_door kasteren_toilet_door synth_square_daily synth_irregular_epoch)

[ -x "$fremenctl" ] || { echo "accuracy-table: no $fremenctl; build first (make build)" >&2; exit 1; }
[ -f "$data_dir/README.md" ] || { echo "accuracy-table: no $data_dir/README.md" >&2; exit 1; }

# The err column (orders 0..5) of a dataset's row in the README's table of the original.
original_err() {
  awk -F'|' -v name="$1" '{ gsub(/ /, "", $2) } $2 == name { sub(/^ +/, "", $3); sub(/ +$/, "", $3); print $3; exit }' \
    "$data_dir/README.md"
}

# The err column of `fremenctl eval` on a dataset, orders 0..5 on one line.
our_err() {
  local name=$1; shift
  "$fremenctl" eval --train "$data_dir/derived/$name/train.txt" --test "$data_dir/derived/$name/test.txt" \
    --max-order 5 "$@" | cut -f2 | paste -sd' '
}

echo "| dataset | original err o0..o5 | ours err o0..o5 (100 floor periods) | max \|Δ\| | ours err o0..o5 (default Ω) |"
echo "|---|---|---|---|---|"
worst=0
for name in "${datasets[@]}"; do
  original=$(original_err "$name")
  [ -n "$original" ] || { echo "accuracy-table: $name is not in $data_dir/README.md" >&2; exit 1; }
  ours=$(our_err "$name" --periods 100 --longest 604800 --floor-periods)
  default=$(our_err "$name")
  delta=$(awk -v a="$original" -v b="$ours" -v tol="$tolerance" 'BEGIN {
    n = split(a, x, " "); split(b, y, " "); m = 0
    for (i = 1; i <= n; ++i) { d = x[i] - y[i]; if (d < 0) d = -d; if (d > m) m = d }
    printf "%.4f%s", m, (m > tol ? " ✗" : "") }')
  echo "| $name | $original | $ours | $delta | $default |"
done
