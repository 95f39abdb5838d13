#!/usr/bin/env bash
# Instructions per cell-observation of the ingest path, counted by valgrind's callgrind: a figure
# that, unlike a rate, does not move with whatever else the machine runs (docs/performance.md,
# "Instructions per cell-observation"). A fremend and fremen_ingest_load --batches (a fixed
# workload: one stream of BATCHES scans of CELLS cells, acknowledged once durable) both run under
# callgrind; the daemon's counters are zeroed after a warm-up batch (which creates the map) and
# dumped once the workload is acknowledged, so its start, map creation and shutdown are left out.
# The client's whole run is counted (its start is a small share at the default workload).
# With LOAD=office the workload is fremen_office_load's instead: one robot scanning the whole
# ~213k-cell office floor every 5 s for DAYS simulated days (mostly static cells, a few percent
# dynamic), after a warm-up scan that creates the map.
# Prints instructions per cell-observation for the client (encode), the daemon (decode, log,
# apply) and both, then the daemon's and the client's top functions (callgrind_annotate, inclusive
# of nothing: self cost).
#   scripts/ingest-instructions.sh [BUILD_DIR] [-- load flags...]
# Environment: BATCHES (100), CELLS (10000), LOAD (scans or office), DAYS (0.01: 173 scans),
# TOP (25), KEEP=1 keeps the work directory, FREMEND: the daemon binary (default
# BUILD_DIR/bin/fremend).
# Needs valgrind (callgrind_annotate, callgrind_control). Takes a few minutes.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
[[ $# -gt 0 ]] && shift
[[ ${1:-} == -- ]] && shift
extra=("$@")
batches=${BATCHES:-100}
cells=${CELLS:-10000}
top=${TOP:-25}
work=$(mktemp -d /tmp/fremen-callgrind.XXXXXX)
daemon_pid=
cleanup() {
  if [[ -n $daemon_pid ]] && kill -0 "$daemon_pid" 2>/dev/null; then
    kill "$daemon_pid" 2>/dev/null || true
    wait "$daemon_pid" 2>/dev/null || true
  fi
  [[ ${KEEP:-0} == 1 ]] && echo "kept $work" >&2 || rm -rf "$work"
}
trap cleanup EXIT

port=$((20000 + RANDOM % 20000))
valgrind --tool=callgrind --callgrind-out-file="$work/daemon.%p" \
  "${FREMEND:-$build/bin/fremend}" --listen "127.0.0.1:$port" --http-listen "" --data-dir "$work/data" --shards 2 \
  --update-schedule "" --log-level warn >"$work/daemon.log" 2>&1 &
daemon_pid=$!

if [[ ${LOAD:-scans} == office ]]; then
  load=("$build/bin/fremen_office_load" --address "127.0.0.1:$port" --streams 1 --window 4 --no-ceilings
        "${extra[@]}")
  warmup=(--days "$(awk 'BEGIN { print 1 / 17280 }')")  # one scan
  workload=(--days "${DAYS:-0.01}")
  what="1 robot, the office floor for ${DAYS:-0.01} days"
else
  load=("$build/bin/fremen_ingest_load" --address "127.0.0.1:$port" --grid 100 --cells "$cells" --streams 1
        --window 8 --predict-calls 0 "${extra[@]}")
  warmup=(--batches 1)
  workload=(--batches "$batches")
  what="1 stream, $batches batches of $cells cells"
fi
# The daemon starts slowly under valgrind: retry the warm-up batch until it answers.
for attempt in $(seq 1 120); do
  if "${load[@]}" "${warmup[@]}" >"$work/warmup.log" 2>&1; then break; fi
  kill -0 "$daemon_pid" 2>/dev/null || { cat "$work/daemon.log" >&2; exit 1; }
  sleep 1
done
grep -q "cell-observations acknowledged" "$work/warmup.log" || { cat "$work/warmup.log" >&2; exit 1; }

callgrind_control --zero "$daemon_pid" >/dev/null
valgrind --tool=callgrind --callgrind-out-file="$work/client.out" "${load[@]}" "${workload[@]}" \
  >"$work/client.log" 2>"$work/client.err" || { cat "$work/client.log" "$work/client.err" >&2; exit 1; }
callgrind_control --dump=workload "$daemon_pid" >/dev/null
# The dump is written asynchronously, by the daemon's next scheduled thread.
for attempt in $(seq 1 60); do
  daemon_out=$(ls "$work"/daemon.$daemon_pid.* 2>/dev/null | head -1 || true)
  [[ -n $daemon_out ]] && break
  sleep 1
done
[[ -n $daemon_out ]] || { echo "no callgrind dump of the daemon" >&2; exit 1; }
sleep 2  # let the dump finish writing

observations=$(sed -n 's/.* \([0-9]*\) cell-observations acknowledged.*/\1/p' "$work/client.log")
[[ $observations -gt 0 ]] || { cat "$work/client.log" >&2; exit 1; }
total_ir() { callgrind_annotate "$1" 2>/dev/null | sed -n 's/^ *\([0-9,]*\) .*PROGRAM TOTALS.*/\1/p' | tr -d ,; }
client_ir=$(total_ir "$work/client.out")
daemon_ir=$(total_ir "$daemon_out")
echo "workload: $observations cell-observations ($what${extra:+ ${extra[*]}})"
awk -v c="$client_ir" -v d="$daemon_ir" -v n="$observations" 'BEGIN {
  printf "instructions per cell-observation: client %.1f, daemon %.1f, total %.1f\n", c / n, d / n, (c + d) / n }'
echo
# Self cost per function, in instructions per cell-observation (sed, not head: no SIGPIPE).
top_functions() {
  callgrind_annotate --inclusive=no --threshold=100 "$1" 2>/dev/null | grep -E '^ *[0-9,]+ ' |
    grep -v 'PROGRAM TOTALS' | sed -n "1,${top}p" |
    sed -E 's/^ *([0-9,]+) +\( *[0-9.]+%\) +/\1 /' |
    awk -v n="$observations" '{ ir = $1; gsub(",", "", ir); $1 = ""; printf "%8.2f/obs %s\n", ir / n, $0 }' |
    sed -E 's/ \[[^]]*\]$//; s/\(anonymous namespace\)/(anon)/g; s/std::__cxx11::basic_string<char, std::char_traits<char>, std::allocator<char> >/std::string/g'
}
echo "daemon, top $top functions by instructions (self):"
top_functions "$daemon_out"
echo
echo "client, top $top functions by instructions (self):"
top_functions "$work/client.out"
