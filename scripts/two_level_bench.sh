#!/usr/bin/env bash
# The flat BVH against two levels on the same rays and frames (issue 14: two levels within
# 10 % of flat), in one run of about 5 minutes on the GPU machine (DEVICE=cpu ROUNDS=1: about
# 4 minutes on the 2-core machine).
#
# Run from the repository root, with
#   .device/penumbra                          a release build (cargo build --release)
#   .device/scenes/StanfordBunny/bunny.glb
# and OUT set to an empty folder:
#   OUT=/some/dir scripts/two_level_bench.sh
#
# Environment: DEVICE (default gpu; `cpu` measures PoCL at a smaller size), PENUMBRA (binary),
# SCENES (folder), ROUNDS (default 2: flat and two-level alternate, ROUNDS times each).
# Writes to $OUT:
#   log.txt       devices and every table as printed
#   trace.jsonl   bench trace --json, one line per scene, form and round (`bvh_levels` names
#                 the form, `results[].median_ms` the three ray sets)
#   frame-flat.jsonl, frame-two-level.jsonl
#                 bench frame --json per form, likewise (`samples_per_second`)
#   summary.txt   two-level against flat per scene: rays/s and samples/s ratios (best round)
set -uo pipefail

P=${PENUMBRA:-.device/penumbra}
S=${SCENES:-.device/scenes}
DEVICE=${DEVICE:-gpu}
ROUNDS=${ROUNDS:-2}
: "${OUT:?set OUT to the output folder}"
mkdir -p "$OUT"
LOG=$OUT/log.txt
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
if [ "$DEVICE" = cpu ]; then
    TRACE_SIZE=(--width 640 --height 360 --runs 3 --warmup 1)
    FRAME_SIZE=(--width 320 --height 180 --spp 4)
else
    # The settings of the H200 figures: trace at the default 1280x720, frames at 1024x1024
    # with 6 bounces.
    TRACE_SIZE=(--width 1280 --height 720 --runs 10 --warmup 3)
    FRAME_SIZE=(--width 1024 --height 1024 --bounces 6 --spp 64)
fi

log() { echo "$*" | tee -a "$LOG" >&2; }
run() {
    local dest=$1
    shift
    log "+ $*"
    timeout 300 "$@" >>"$dest" 2>>"$LOG" || log "  exit $?"
}

log "== penumbra flat against two levels, $(date -u +%Y-%m-%dT%H:%M:%SZ)"
log "commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version \
    --format=csv >>"$LOG" 2>&1
"$P" devices >>"$LOG" 2>&1

# Two rooms: 7 bunnies (9 instances of 3 meshes) and 49 icospheres (51
# instances of 3 meshes), 1 M triangles each.
run "$LOG" "$P" bench generate --from "$S/StanfordBunny/bunny.glb" --triangles 1000000 \
    -o "$TMP/bunnies.glb"
run "$LOG" "$P" bench generate --triangles 1000000 -o "$TMP/spheres.glb"

for scene in bunnies spheres; do
    for round in $(seq "$ROUNDS"); do
        for bvh in flat two-level; do
            run "$OUT/trace.jsonl" "$P" bench trace "$TMP/$scene.glb" --device "$DEVICE" \
                --bvh "$bvh" "${TRACE_SIZE[@]}" --validate 65536 --json
            run "$OUT/frame-$bvh.jsonl" "$P" bench frame "$TMP/$scene.glb" --device "$DEVICE" \
                --bvh "$bvh" "${FRAME_SIZE[@]}" --json
        done
    done
done

python3 - "$OUT" >"$OUT/summary.txt" <<'EOF'
import json, sys, collections
out = sys.argv[1]
best = collections.defaultdict(dict)
for line in open(f"{out}/trace.jsonl"):
    j = json.loads(line)
    key = (j["scene"].rsplit("/", 1)[-1], j["bvh_levels"])
    for r in j["results"]:
        best[key][r["kind"]] = max(best[key].get(r["kind"], 0), r["rays_per_second"])
    if j.get("mismatches"):
        print(f"MISMATCHES {key}: {j['mismatches']}")
for bvh in ("flat", "two-level"):
    for line in open(f"{out}/frame-{bvh}.jsonl"):
        j = json.loads(line)
        key = (j["scene"].rsplit("/", 1)[-1], bvh)
        best[key]["frame"] = max(best[key].get("frame", 0), j["samples_per_second"])
print("scene          measure   flat (M/s)  two-level (M/s)  two-level/flat  (rays/s; frame: samples/s)")
for scene in sorted({k[0] for k in best}):
    flat, two = best[(scene, "flat")], best[(scene, "two-level")]
    for m in ("primary", "diffuse", "shadow", "frame"):
        if m in flat and m in two:
            print(f"{scene:14s} {m:8s} {flat[m] / 1e6:10.2f} {two[m] / 1e6:16.2f} {two[m] / flat[m]:15.3f}")
EOF
cat "$OUT/summary.txt" | tee -a "$LOG"
