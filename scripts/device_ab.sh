#!/usr/bin/env bash
# A change meant to keep behaviour, checked on the GPU machine in one run: the images of two
# builds compared bit for bit (scripts/same_images.sh on the device), then `bench frame` and
# `bench trace` of both, alternated A B A B A B so that drift of the card affects both alike.
#
#   A=.device/penumbra-base B=.device/penumbra SCENES=.device/scenes OUT=/dir scripts/device_ab.sh
#
# Writes $OUT/log.txt (the comparison, every benchmark line, medians) and $OUT/ab.jsonl.
set -uo pipefail
: "${A:?old binary}" "${B:?new binary}" "${OUT:?output folder}"
S=${SCENES:-.device/scenes}
DEVICE=${DEVICE:-gpu}
REPEAT=${REPEAT:-3}
mkdir -p "$OUT"
LOG=$OUT/log.txt
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
log() { echo "$*" | tee -a "$LOG" >&2; }

log "== $(date -u +%Y-%m-%dT%H:%M:%SZ) A=$A B=$B device=$DEVICE"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader >>"$LOG"
"$B" devices >>"$LOG" 2>&1

log "== images (same_images.sh on $DEVICE)"
for side in A B; do
    bin=${!side}
    # The lanes are a CPU path: on a GPU each kernel once.
    PENUMBRA=$bin PENUMBRA_SCENES=$S DEVICE=$DEVICE SIZE=${SIZE:-192x128} \
        RUNS=${IMAGE_RUNS:-wavefront:- megakernel:-} \
        scripts/same_images.sh "$TMP/$side" >>"$LOG" 2>&1
done
scripts/same_images.sh --compare "$TMP/A" "$TMP/B" 2>&1 | tee -a "$LOG" >&2

log "== benchmarks"
"$B" bench generate --from "$S/StanfordBunny/bunny.glb" --triangles 1000000 \
    -o "$TMP/bunnies.glb" >>"$LOG" 2>&1
for i in $(seq "$REPEAT"); do
    for side in A B; do
        bin=${!side}
        for scene in "$TMP/bunnies.glb" "$S/DreamApartment/dream-apartment.glb"; do
            echo "{\"side\":\"$side\",\"bench\":\"frame\",\"scene\":\"$(basename "$scene")\",\"out\":$(
                timeout 120 "$bin" bench frame "$scene" --device "$DEVICE" --spp 64 --json 2>>"$LOG" | tail -1)}" >>"$OUT/ab.jsonl"
            echo "{\"side\":\"$side\",\"bench\":\"trace\",\"scene\":\"$(basename "$scene")\",\"out\":$(
                timeout 120 "$bin" bench trace "$scene" --device "$DEVICE" --runs 10 --warmup 3 --json 2>>"$LOG" | tail -1)}" >>"$OUT/ab.jsonl"
        done
        echo "{\"side\":\"$side\",\"bench\":\"frame\",\"scene\":\"box-1024\",\"out\":$(
            timeout 120 "$bin" bench frame --device "$DEVICE" --width 1024 --height 1024 --bounces 8 \
                --hard-shadows --spp 64 --json 2>>"$LOG" | tail -1)}" >>"$OUT/ab.jsonl"
    done
done
log "== done"
