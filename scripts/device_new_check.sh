#!/usr/bin/env bash
# On the GPU machine: renders every scene under SCENES with a build's two kernels into OUT
# (PNGs to look at, EXRs compared between the kernels), so that new kernel code is checked to
# compile and to agree across kernels on the card.
#
#   P=.device/penumbra SCENES=.device/scenes OUT=/dir scripts/device_new_check.sh
set -uo pipefail
: "${P:?binary}" "${OUT:?output folder}"
S=${SCENES:-.device/scenes}
mkdir -p "$OUT"
mapfile -t scenes < <(find "$S" \( -name '*.glb' -o -name '*.gltf' \) | sort)
for scene in "${scenes[@]}"; do
    name=$(basename "${scene%.*}")
    for k in wavefront megakernel; do
        "$P" render "$scene" --device gpu --kernel "$k" --width 320 --height 240 --spp 64 \
            -o "$OUT/$name-$k.exr" >"$OUT/$name-$k.json" 2>"$OUT/$name-$k.err" ||
            echo "FAILED: $name $k: $(tail -1 "$OUT/$name-$k.err")"
    done
    "$P" render "$scene" --device gpu --width 320 --height 240 --spp 64 -o "$OUT/$name.png" \
        >/dev/null 2>&1
    cmp -s "$OUT/$name-wavefront.exr" "$OUT/$name-megakernel.exr" && same=identical || same=differ
    echo "$name: kernels $same"
done
