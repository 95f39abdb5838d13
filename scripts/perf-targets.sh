#!/usr/bin/env bash
# Every figure of the ingest and query targets (docs/performance.md, "Targets"), one benchmark
# after another, each against a fresh fremend on a fresh data directory, on the machine as it is:
# the rows of the table "The ingest and query targets, one night". Prints each benchmark's own
# summary lines. Speed is never asserted here: read the figures next to their ceilings.
#
#   scripts/perf-targets.sh [BUILD_DIR]      (default: build; takes about ten minutes)
set -euo pipefail

build=${1:-build}
bin=$(cd "$build/bin" && pwd)
work=$(mktemp -d)
daemon=
cleanup() {
  if [[ -n "$daemon" ]]; then kill "$daemon" 2>/dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT

port=50099
address=127.0.0.1:$port

# A fresh fremend on a fresh directory, ready once its port accepts connections (there is nothing
# to recover).
start_daemon() {
  rm -rf "$work/data" && mkdir -p "$work/data"
  "$bin/fremend" --data-dir "$work/data" --listen "$address" --http-listen "" --update-schedule "" \
    --log-level warn >"$work/fremend.log" 2>&1 &
  daemon=$!
  for _ in $(seq 100); do
    (echo >"/dev/tcp/127.0.0.1/$port") 2>/dev/null && return 0
    sleep 0.1
  done
  echo "fremend did not start:" >&2
  cat "$work/fremend.log" >&2
  exit 1
}

stop_daemon() {
  kill "$daemon"
  wait "$daemon" 2>/dev/null || true
  daemon=
}

section() { printf '\n=== %s (%s)\n' "$1" "$(date -u +%H:%M:%S)"; }

section "the paper's office, a simulated week (fremen_office_load)"
start_daemon
"$bin/fremen_office_load" --address "$address"
stop_daemon

section "sparse 10k-cell scans, compact encoding (fremen_ingest_load --encoding compact)"
start_daemon
"$bin/fremen_ingest_load" --address "$address" --encoding compact --predict-calls 0
stop_daemon

section "small scans, 1000 cells (fremen_ingest_load --cells 1000)"
start_daemon
"$bin/fremen_ingest_load" --address "$address" --cells 1000 --predict-calls 0
stop_daemon

section "one state's history in batches (fremen_ingest_load --history-states 1)"
start_daemon
"$bin/fremen_ingest_load" --address "$address" --history-states 1 --predict-calls 0
stop_daemon

section "regions, series and batched Predict (fremen_query_load --create)"
start_daemon
"$bin/fremen_query_load" --address="$address" --create --region-reps=30
stop_daemon

section "publication + checkpoint, lossless nights (fremen_update_bench)"
"$bin/fremen_update_bench" --parts 24 --lossless-mix both

section "recovery from 100 MB of log (fremen_store_bench --only recovery)"
"$bin/fremen_store_bench" --only recovery
