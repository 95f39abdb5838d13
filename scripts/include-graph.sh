#!/usr/bin/env bash
# The include graph between the project's layers: for each layer, how many #include lines of its
# files (tests included) name each other layer's headers. docs/layout.md shows it; run it after
# moving code to see what a layer still reaches into.
#   scripts/include-graph.sh [--private] [REV]     (default: the work tree; REV: that commit)
# --private counts only the includes of storage/'s private headers (those not in
# storage/include/storage/, its public API) from outside storage/.
set -euo pipefail
cd "$(dirname "$0")/.."
private=0
if [ "${1:-}" = --private ]; then private=1; shift; fi
rev=${1:-}
# Longest prefix first, so that storage/model/ is not counted as storage/.
layers=(storage/model storage server client/lib client/formats client/fremenctl client/bench client/examples
        base testing tests fuzz)
layer_of() {
  local path=$1 layer
  for layer in "${layers[@]}"; do
    case $path in "$layer"/*) echo "$layer"; return ;; esac
  done
  echo other
}
if [ -n "$rev" ]; then
  all_files=$(git ls-tree -r --name-only "$rev")
  show() { git show "$rev:$1"; }
else
  all_files=$(git ls-files)
  show() { cat "$1"; }
fi
files=$(grep -E '\.(h|cc)$' <<<"$all_files")
declare -A public
while read -r header; do public["storage/${header#storage/include/storage/}"]=1; done \
  < <(grep '^storage/include/storage/' <<<"$all_files" || true)
declare -A count
for file in $files; do
  from=$(layer_of "$file")
  [ "$from" != other ] || continue
  while read -r included; do
    to=$(layer_of "$included")
    [ "$to" != other ] && [ "$to" != "$from" ] || continue
    if [ "$private" = 1 ] && { [ "$to" != storage ] || [ -n "${public[$included]:-}" ]; }; then continue; fi
    count["$from -> $to"]=$(( ${count["$from -> $to"]:-0} + 1 ))
  done < <(show "$file" | sed -n 's/^#include "\([^"]*\)".*/\1/p')
done
for edge in "${!count[@]}"; do printf '%-36s %4d\n' "$edge" "${count[$edge]}"; done | sort
