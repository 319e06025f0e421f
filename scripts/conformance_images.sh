#!/usr/bin/env bash
# Renders every Khronos sample model under PENUMBRA_SCENES/khronos with no options (but the
# size and samples) beside its Khronos screenshot, for docs/gltf-conformance.md:
# docs/images/conformance/MODEL.png (penumbra) and MODEL-reference.png (the screenshot, scaled).
#
#   PENUMBRA_SCENES=../shared/scenes scripts/conformance_images.sh
#
# Environment: PENUMBRA (binary, default target/release/penumbra), SIZE (default 320x240),
# SPP (default 128).
set -euo pipefail
P=${PENUMBRA:-target/release/penumbra}
S=${PENUMBRA_SCENES:-../shared/scenes}/khronos
SIZE=${SIZE:-320x240}
SPP=${SPP:-128}
OUT=docs/images/conformance
mkdir -p "$OUT"
for dir in "$S"/*/; do
    name=$(basename "$dir")
    scene=$(find "$dir" \( -name '*.glb' -o -name '*.gltf' \) | sort | head -1)
    [[ -n $scene ]] || continue
    rm -f "$OUT/$name.png"
    "$P" render "$scene" -o "$OUT/$name.png" --width "${SIZE%x*}" --height "${SIZE#*x}" \
        --spp "$SPP" >/dev/null
    # The model's own screenshot.*; of an animated GIF, its first frame.
    shot=$(find "$dir/screenshot" -name 'screenshot.*' | sort | head -1)
    [[ -n $shot ]] && convert "$shot[0]" -resize "${SIZE}" -strip "$OUT/$name-reference.png"
done
