#!/usr/bin/env bash
# Every benchmark of docs/benchmarks.md on the GPU machine, in one run of well under 10 minutes.
#
# Run from the repository root, with
#   .device/penumbra                      a release build (cargo build --release; the binary
#                                         runs unchanged on the GPU machine)
#   .device/scenes/StanfordBunny/bunny.glb
#   .device/scenes/DreamApartment/dream-apartment.glb
#   .device/scenes/CornellBox/CornellBox.glb
#   tests/references/cornell-box-mitsuba-128.exr   (tracked in the repository)
# and OUT set to an empty folder:
#   OUT=/some/dir scripts/device_bench.sh
#
# Environment: DEVICE (default gpu; `cpu` measures PoCL), PENUMBRA (binary), SCENES (folder).
# Writes 6 files to $OUT:
#   log.txt                       devices, every table as printed, timings of each step
#   trace.jsonl                   bench trace, one JSON line per scene (+ PoCL on the host CPU)
#   frame.jsonl                   bench frame at 1920x1080, one JSON line per scene
#   converge.jsonl                bench converge, one JSON line per run
#   converge-cornell-mitsuba.png  bundled Cornell box against the Mitsuba reference
#   converge-cornellbox.png       shared CornellBox (emissive only) against a penumbra reference
set -uo pipefail

P=${PENUMBRA:-.device/penumbra}
S=${SCENES:-.device/scenes}
DEVICE=${DEVICE:-gpu}
: "${OUT:?set OUT to the output folder}"
mkdir -p "$OUT"
LOG=$OUT/log.txt
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
BUNNY=$S/StanfordBunny/bunny.glb
APARTMENT=$S/DreamApartment/dream-apartment.glb
CORNELL=$S/CornellBox/CornellBox.glb
BUNNIES=$TMP/bunnies.glb
START=$SECONDS

log() { echo "$*" | tee -a "$LOG" >&2; }

# step LIMIT_S FILE_OR_- CMD...: runs CMD with a time limit; stdout appended to FILE (or the
# log), stderr to the log; records the exit status and duration.
step() {
    local limit=$1 dest=$2
    shift 2
    local t0=$SECONDS
    log "+ $*"
    if [ "$dest" = "-" ]; then
        timeout "$limit" "$@" >>"$LOG" 2>>"$LOG"
    else
        timeout "$limit" "$@" >>"$dest" 2>>"$LOG"
    fi
    local rc=$?
    log "  exit $rc after $((SECONDS - t0)) s (total $((SECONDS - START)) s)"
    return 0
}

log "== penumbra device benchmarks, $(date -u +%Y-%m-%dT%H:%M:%SZ)"
log "commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm \
    --format=csv >>"$LOG" 2>&1
nproc >>"$LOG"
step 60 - "$P" devices

log "== generated scene: StanfordBunny copies, >= 1M triangles, in a closed room"
step 120 - "$P" bench generate --from "$BUNNY" --triangles 1000000 -o "$BUNNIES"

log "== bench trace (1280x720 rays per set; median of 10 after 3 warm-up)"
for scene in "$BUNNY" "$APARTMENT" "$BUNNIES"; do
    step 240 "$OUT/trace.jsonl" "$P" bench trace "$scene" --device "$DEVICE" --runs 10 \
        --warmup 3 --json
    step 240 - "$P" bench trace "$scene" --device "$DEVICE" --runs 10 --warmup 3 \
        --validate 65536
done
log "== bench trace on the host CPU through PoCL, for scale"
step 240 "$OUT/trace.jsonl" "$P" bench trace "$BUNNIES" --device cpu --runs 3 --warmup 1 \
    --validate 65536 --json

log "== bench frame (1920x1080, 64 frames of 1 spp, 4 bounces, MIS, Russian roulette)"
for scene in "$BUNNY" "$APARTMENT" "$BUNNIES"; do
    step 240 "$OUT/frame.jsonl" "$P" bench frame "$scene" --device "$DEVICE" --spp 64 --json
    step 240 - "$P" bench frame "$scene" --device "$DEVICE" --spp 16
done
log "== bench frame, the settings of GPU.md's Mitsuba figures"
# Lambertian Cornell box at 1024x1024 with long paths; 1M triangles with up to 7 bounces
# (Mitsuba max_depth 8 = penumbra --bounces 6).
step 240 "$OUT/frame.jsonl" "$P" bench frame --device "$DEVICE" --width 1024 --height 1024 \
    --bounces 8 --hard-shadows --spp 64 --json
step 240 "$OUT/frame.jsonl" "$P" bench frame "$BUNNIES" --device "$DEVICE" --bounces 6 \
    --spp 64 --json

log "== bench converge: bundled Cornell box against the Mitsuba reference (128x128, 8 bounces)"
step 300 "$OUT/converge.jsonl" "$P" bench converge \
    --reference tests/references/cornell-box-mitsuba-128.exr --bounces 8 --hard-shadows \
    --device "$DEVICE" --spp 8192 --max-seconds 30 --json \
    --plot "$OUT/converge-cornell-mitsuba.png" \
    --title "bundled Cornell box vs Mitsuba 3 reference: 128×128, 8 bounces"

log "== bench converge: shared CornellBox (emissive ceiling only) against a penumbra reference"
step 300 - "$P" render "$CORNELL" -o "$TMP/cornellbox-ref.exr" --device "$DEVICE" \
    --width 128 --height 128 --bounces 8 --spp 1048576 --seed 4242
step 300 "$OUT/converge.jsonl" "$P" bench converge "$CORNELL" \
    --reference "$TMP/cornellbox-ref.exr" --bounces 8 --device "$DEVICE" --spp 65536 \
    --max-seconds 30 --json --plot "$OUT/converge-cornellbox.png" \
    --title "CornellBox.glb vs penumbra 1048576 spp: 128×128, 8 bounces"

log "== done in $((SECONDS - START)) s"
