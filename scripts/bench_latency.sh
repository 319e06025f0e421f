#!/usr/bin/env bash
# Input latency of the viewer's real window: key press to the first image rendered after it
# on screen. Starts a private Xvfb, opens SCENE (the bundled Cornell box when "-"), waits for
# the first image, then taps D (0.2 s) COUNT times, 2 s apart (the image rests in between and
# climbs back to full quality), and reads the viewer's own measurement (`--stats-file`: from
# the key's X event to the present of the first image after it). Prints the latencies and their
# median and maximum, with the image rate while the key is held.
#
#   scripts/bench_latency.sh [SCENE|-] [COUNT] [extra viewer options…]
set -euo pipefail
scene=${1:--}
count=${2:-8}
shift $(( $# > 2 ? 2 : $# ))
bin=${PENUMBRA:-target/release/penumbra}
dir=$(mktemp -d)
display=:$(( 600 + $$ % 300 ))
Xvfb "$display" -screen 0 1280x800x24 -nolisten tcp >/dev/null 2>&1 &
xvfb=$!
viewer=""
trap 'kill $viewer $xvfb 2>/dev/null || true; rm -rf "$dir"' EXIT
export DISPLAY=$display
sleep 1
args=(view)
[ "$scene" != "-" ] && args+=("$scene")
"$bin" "${args[@]}" --device "${PENUMBRA_DEVICE:-cpu}" --stats-file "$dir/stats.jsonl" "$@" \
    >"$dir/out.txt" 2>&1 &
viewer=$!
# The first image, then a few seconds of rest.
for _ in $(seq 600); do
    [ -s "$dir/stats.jsonl" ] && break
    sleep 0.2
done
[ -s "$dir/stats.jsonl" ] || { echo "no image after 120 s"; cat "$dir/out.txt"; exit 1; }
sleep 4
wid=$(xdotool search --name '^penumbra' | head -1)
xdotool windowfocus --sync "$wid"
for _ in $(seq "$count"); do
    xdotool keydown d
    sleep 0.2
    xdotool keyup d
    sleep 2
done
python3 - "$dir/stats.jsonl" "$(nproc)" <<'PY'
import json, statistics, sys
lines = [json.loads(l) for l in open(sys.argv[1])]
lat = [l["latency_ms"] for l in lines if l.get("latency_ms") is not None][1:]
print("latency ms (key press to the first new image on screen):",
      " ".join(f"{x:.0f}" for x in lat))
if lat:
    print(f"median {statistics.median(lat):.0f} ms, max {max(lat):.0f} ms over {len(lat)} presses")
first = lines[0]
print(f"first image: {first['width']}x{first['height']} at {first['t']:.2f} s")
PY
