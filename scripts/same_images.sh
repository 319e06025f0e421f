#!/usr/bin/env bash
# Renders every shared scene (and the bundled box) with both kernels into a folder of EXRs, so
# that a change meant to keep behaviour can be checked bit for bit against the build before it:
#
#   PENUMBRA=old/penumbra scripts/same_images.sh /tmp/before
#   PENUMBRA=target/release/penumbra scripts/same_images.sh /tmp/after
#   scripts/same_images.sh --compare /tmp/before /tmp/after
#
# Environment: PENUMBRA (binary, default target/release/penumbra), PENUMBRA_SCENES (default
# ../shared/scenes), DEVICE (default cpu), SIZE (default 96x64), SPP (default 2), RUNS (default
# "wavefront:- megakernel:- megakernel:0 megakernel:1": KERNEL:PENUMBRA_LANES, - for unset).
# The CPU's lanes are also forced on (PENUMBRA_LANES=1) and off (=0) for the megakernel, so the
# scalar, the lanes and the wavefront paths are each covered.
set -uo pipefail

if [[ ${1:-} == --compare ]]; then
    a=$2 b=$3 bad=0 n=0
    for f in "$a"/*.exr; do
        n=$((n + 1))
        g=$b/$(basename "$f")
        if [[ ! -f $g ]]; then echo "missing: $g"; bad=$((bad + 1)); continue; fi
        cmp -s "$f" "$g" || { echo "differs: $(basename "$f")"; bad=$((bad + 1)); }
    done
    for g in "$b"/*.exr; do [[ -f $a/$(basename "$g") ]] || { echo "extra: $g"; bad=$((bad + 1)); }; done
    echo "$n images compared, $bad differ"
    exit $((bad > 0))
fi

out=${1:?usage: same_images.sh OUT_DIR | --compare A B}
P=${PENUMBRA:-target/release/penumbra}
S=${PENUMBRA_SCENES:-../shared/scenes}
DEVICE=${DEVICE:-cpu}
SIZE=${SIZE:-96x64}
SPP=${SPP:-2}
mkdir -p "$out"
w=${SIZE%x*} h=${SIZE#*x}
mapfile -t scenes < <(find "$S" \( -name '*.glb' -o -name '*.gltf' \) | sort)
scenes=(assets/cornell-box.glb "${scenes[@]}")
for scene in "${scenes[@]}"; do
    name=$(basename "${scene%.*}")
    for run in ${RUNS:-wavefront:- megakernel:- megakernel:0 megakernel:1}; do
        kernel=${run%:*} lanes=${run#*:}
        tag=$name.$kernel
        env=()
        if [[ $lanes != - ]]; then tag=$tag.lanes$lanes; env=(PENUMBRA_LANES=$lanes); fi
        if ! env "${env[@]}" "$P" render "$scene" --device "$DEVICE" --kernel "$kernel" \
            --width "$w" --height "$h" --spp "$SPP" --seed 7 -o "$out/$tag.exr" \
            >"$out/$tag.json" 2>"$out/$tag.err"; then
            echo "failed: $tag ($(tail -1 "$out/$tag.err"))"
        fi
    done
done
echo "$(ls "$out"/*.exr | wc -l) images in $out"
