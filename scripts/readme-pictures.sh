#!/bin/bash
# Regenerates the README's pictures (docs/*.png) from `fremenctl demo` against a throwaway fremend:
# the week plot of the demo door's p(t), and the predicted demo office at noon on the Monday after
# the simulated week, scaled up 12× (the map is 40 × 20 cells).
# Usage: scripts/readme-pictures.sh [BUILD_DIR]
set -euo pipefail
BIN=${1:-build}/bin
OUT=$(cd "$(dirname "$0")/.." && pwd)/docs
WORK=$(mktemp -d)
trap 'kill $(cat "$WORK/pid") 2>/dev/null || true; rm -rf "$WORK"' EXIT
"$BIN/fremend" --data-dir "$WORK/data" --listen 127.0.0.1:0 --http-listen 127.0.0.1:0 --log-level info > "$WORK/log" 2>&1 &
echo $! > "$WORK/pid"
for _ in $(seq 100); do grep -q "listening on" "$WORK/log" && break; sleep 0.1; done
export FREMEN_ADDRESS=$(grep -o "listening on [^ ]*" "$WORK/log" | head -1 | cut -d' ' -f3)
"$BIN/fremenctl" demo > /dev/null
"$BIN/fremenctl" model --map demo-states --name door --plot "$OUT/door-week.png" > /dev/null
"$BIN/fremenctl" region --map demo-office --time 2023-11-27T13:00:00Z --mode scale --out "$WORK/noon" > /dev/null
/usr/bin/python3 - "$WORK/noon.pgm" "$OUT/office-noon.png" <<'PY'
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
magic, w, h, _, pixels = data.split(maxsplit=4)
w, h, scale = int(w), int(h), 12
rows = []
for y in range(h):
    row = b"".join(bytes([pixels[y * w + x]]) * scale for x in range(w))
    rows += [b"\0" + row] * scale
def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w * scale, h * scale, 8, 0, 0, 0, 0))
png += chunk(b"IDAT", zlib.compress(b"".join(rows), 9)) + chunk(b"IEND", b"")
open(sys.argv[2], "wb").write(png)
PY
echo "wrote $OUT/door-week.png and $OUT/office-noon.png"
