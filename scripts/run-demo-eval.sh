#!/usr/bin/env bash
# The demo of `make demo-eval`: generates a small synthetic dataset and prints
# the offline accuracy of the FreMEn model on it, per model order.
#
#   scripts/run-demo-eval.sh <bin-dir>
#
# The data: a door open on weekdays 9:00-17:00 UTC, seen once a minute, each sample flipped with
# probability 0.05; two weeks to train, the following week to test; epoch times from 1.7e9 s, so
# that the demo also exercises precise phase arithmetic on realistic timestamps. Self-contained:
# it needs nothing but fremenctl and awk.
set -euo pipefail

bin_dir=${1:?usage: run-demo-eval.sh <bin-dir>}
fremenctl=$bin_dir/fremenctl
[ -x "$fremenctl" ] || { echo "run-demo-eval: no $fremenctl; build first" >&2; exit 1; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Samples [first, last) minutes after the start; a fixed seed keeps the demo reproducible.
generate() {
  awk -v first="$1" -v last="$2" -v seed="$3" 'BEGIN {
    srand(seed); start = 1700000000
    for (m = first; m < last; ++m) {
      t = start + 60 * m
      weekday = (int(t / 86400) + 4) % 7          # 1970-01-01 was a Thursday; 0 = Sunday
      hour = (t % 86400) / 3600
      open = weekday >= 1 && weekday <= 5 && hour >= 9 && hour < 17
      if (rand() < 0.05) open = !open
      print t, open
    }
  }'
}

minutes_per_week=$((7 * 24 * 60))
generate 0 $((2 * minutes_per_week)) 1 >"$work/train.txt"
generate $((2 * minutes_per_week)) $((3 * minutes_per_week)) 2 >"$work/test.txt"

echo "FreMEn, default Ω: a door open on weekday working hours (5% noise), trained on two weeks, predicting the third"
echo "(err: share of wrongly predicted samples, 0.05 at best given the noise; mse: mean squared error)"
echo
printf 'order\terr\tmse\n'
"$fremenctl" eval --train "$work/train.txt" --test "$work/test.txt"
