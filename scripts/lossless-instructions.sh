#!/usr/bin/env bash
# Instructions per state of the lossless night, counted by valgrind's callgrind inside
# LosslessHistory::Update (docs/performance.md, "The lossless night"): a figure that, unlike the
# milliseconds of fremen_update_bench, does not move with whatever else the machine runs.
# fremen_update_bench --parts 4 runs under callgrind twice per mix, with FEW and MANY states; the
# difference of the two counts, divided by the difference in states, is one state's update without
# what both runs share (the bench's setup updates, FFTW's planning of each length once).
#   dynamic: every cell dynamic (a daily rhythm, 1 slot in 50 flipped);
#   office:  1 cell in 20 dynamic, the rest constant (walls): the figure is per state of the mix.
# Prints both, then each mix's top functions by self cost per state.
#   scripts/lossless-instructions.sh [BUILD_DIR]
# Environment: TOP (15), KEEP=1 keeps the work directory. Needs valgrind. Takes a few minutes.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
top=${TOP:-15}
work=$(mktemp -d /tmp/fremen-lossless-callgrind.XXXXXX)
cleanup() { [[ ${KEEP:-0} == 1 ]] && echo "kept $work" >&2 || rm -rf "$work"; }
trap cleanup EXIT

# count MIX STATES: one callgrind run; its output file is $work/MIX.STATES.out.
count() {
  valgrind --tool=callgrind --callgrind-out-file="$work/$1.$2.out" \
    --toggle-collect='fremen::model::LosslessHistory::Update*' \
    "$build/bin/fremen_update_bench" --parts 4 --runs 1 --lossless-mix "$1" --lossless-states "$2" \
    >"$work/$1.$2.log" 2>&1 || { cat "$work/$1.$2.log" >&2; exit 1; }
}
# Self cost per function, "instructions<TAB>name", for one output file.
self_costs() {
  callgrind_annotate --inclusive=no --threshold=100 "$1" 2>/dev/null | grep -E '^ *[0-9,]+ ' |
    sed -E 's/^ *([0-9,]+) +(\( *[0-9.]+%\) +)?/\1\t/; s/\t\?\?\?:/\t/; s/ \[[^]]*\]$//; s/\(anonymous namespace\)/(anon)/g' |
    awk -F'\t' '{ ir = $1; gsub(",", "", ir); print ir "\t" $2 }'
}

declare -A few=([dynamic]=2 [office]=20) many=([dynamic]=6 [office]=60)
for mix in dynamic office; do
  count "$mix" "${few[$mix]}"
  count "$mix" "${many[$mix]}"
done
echo "instructions per state inside LosslessHistory::Update, 31 days of 5-s slots (535,680), callgrind:"
for mix in dynamic office; do
  a="$work/$mix.${few[$mix]}.out" b="$work/$mix.${many[$mix]}.out"
  states=$((${many[$mix]} - ${few[$mix]}))
  awk -F'\t' -v mix="$mix" -v n="$states" -v top="$top" '
    FNR == 1 { file++ }
    $2 == "PROGRAM TOTALS" { total[file] = $1; next }
    { cost[$2] += (file == 1 ? -$1 : $1) }
    END {
      printf "  %s: %.1fM per state\n", mix, (total[2] - total[1]) / n / 1e6
      fflush()
      for (f in cost) printf "%.3f\t%s\n", cost[f] / n / 1e6, f | "sort -t\"\t\" -k1,1gr | head -" top " | sed \"s/^/      /\""
    }' <(self_costs "$a") <(self_costs "$b")
done
