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
# with the default Ω (24 periods of a week); then, with the default Ω and the data fed day by day
# (`fremenctl eval --replay`), the test err (mse) of the order chosen by the paper's rule (exact
# minimum), by the margin rule (0.001, what maps made before the rule was a setting read back as),
# by the default rule of new maps (today the margin rule too), by the weighted rule (a map
# setting), and the best order in hindsight; the last row is the means.
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

# `fremenctl eval` on a dataset.
eval_on() {
  local name=$1; shift
  "$fremenctl" eval --train "$data_dir/derived/$name/train.txt" --test "$data_dir/derived/$name/test.txt" \
    --max-order 5 "$@"
}

# The err column of `fremenctl eval` on a dataset, orders 0..5 on one line.
our_err() { eval_on "$@" | grep -E '^[0-9]' | cut -f2 | paste -sd' '; }

echo "| dataset | original err o0..o5 | ours err o0..o5 (100 floor periods) | max \|Δ\| | ours err o0..o5 (default Ω) | paper rule | margin rule | default rule | weighted rule | hindsight |"
echo "|---|---|---|---|---|---|---|---|---|---|"
sums="0 0 0 0 0 0 0 0 0 0"
worst=0
for name in "${datasets[@]}"; do
  original=$(original_err "$name")
  [ -n "$original" ] || { echo "accuracy-table: $name is not in $data_dir/README.md" >&2; exit 1; }
  ours=$(our_err "$name" --periods 100 --longest 604800 --floor-periods)
  replay=$(eval_on "$name" --replay)
  default=$(echo "$replay" | grep -E '^[0-9]' | cut -f2 | paste -sd' ')
  # "err (mse) o<order>" of each rule, then the hindsight best err and the mse beside it.
  rules=$(echo "$replay" | awk -F'\t' '/^[0-9]/ { if (best == "" || $2 < best) { best = $2; bmse = $3 } }
    /^(paper|margin|default|weighted)\t/ { r[$1] = $3 " (" $4 ") o" $2; e[$1] = $3; m[$1] = $4 }
    END { printf "%s | %s | %s | %s | %s (%s)\t%s %s %s %s %s %s %s %s %s %s\n", r["paper"], r["margin"], r["default"],
          r["weighted"], best, bmse, e["paper"], m["paper"], e["margin"], m["margin"], e["default"], m["default"],
          e["weighted"], m["weighted"], best, bmse }')
  sums=$(awk -v a="$sums" -v b="${rules#*$'\t'}" 'BEGIN { n = split(a, x, " "); split(b, y, " ");
    for (i = 1; i <= n; ++i) printf "%s%.6f", (i > 1 ? " " : ""), x[i] + y[i] }')
  delta=$(awk -v a="$original" -v b="$ours" -v tol="$tolerance" 'BEGIN {
    n = split(a, x, " "); split(b, y, " "); m = 0
    for (i = 1; i <= n; ++i) { d = x[i] - y[i]; if (d < 0) d = -d; if (d > m) m = d }
    printf "%.4f%s", m, (m > tol ? " ✗" : "") }')
  echo "| $name | $original | $ours | $delta | $default | ${rules%%$'\t'*} |"
done
awk -v s="$sums" -v n="${#datasets[@]}" 'BEGIN { split(s, x, " ");
  printf "| mean | | | | | %.4f (%.4f) | %.4f (%.4f) | %.4f (%.4f) | %.4f (%.4f) | %.4f (%.4f) |\n",
    x[1] / n, x[2] / n, x[3] / n, x[4] / n, x[5] / n, x[6] / n, x[7] / n, x[8] / n, x[9] / n, x[10] / n }'
