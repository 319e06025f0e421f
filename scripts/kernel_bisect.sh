#!/usr/bin/env bash
# Which kernel commit changes a device's images? One binary renders the same scenes with the
# kernels of each revision (PENUMBRA_KERNEL_DIR: the host and its buffers stay the same), and each
# image is compared byte for byte with the first revision's. It tells kernel changes from host
# changes where two builds' images differ (issue 52: GPU images differ while PoCL's match).
#
#   scripts/kernel_bisect.sh prepare OUT_DIR REV...        # here: exports each REV's kernels/,
#                                                          # the release binary (xz), two scenes
#   OUT=results bash OUT_DIR/kernel_bisect.sh run OUT_DIR  # on the device machine (carry OUT_DIR)
#
# Environment for `run`: DEVICE (default gpu), SIZE (320x240), SPP (16), SCENES (default: the
# two prepared), KERNELS ("megakernel wavefront"). Writes $OUT/log.txt: scene kernel rev ref|same|DIFFERS.
set -uo pipefail

if [[ ${1:-} == prepare ]]; then
    dir=${2:?usage: kernel_bisect.sh prepare OUT_DIR REV...}; shift 2
    mkdir -p "$dir/k" "$dir/scenes"
    printf '%s\n' "$@" > "$dir/revs"
    for r in "$@"; do mkdir -p "$dir/k/$r" && git archive "$r" kernels | tar -x -C "$dir/k/$r"; done
    xz -T2 -3 -c target/release/penumbra > "$dir/penumbra.xz"
    S=${PENUMBRA_SCENES:-../shared/scenes}
    cp -r "$S/CornellBox" "$S/DreamApartment" "$dir/scenes/"
    cp "$0" "$dir/kernel_bisect.sh"
    du -sh "$dir"
    exit 0
fi

dir=${2:?usage: kernel_bisect.sh run DIR}
OUT=${OUT:-.}
P=/tmp/penumbra-bisect
xz -dc "$dir/penumbra.xz" > "$P" && chmod +x "$P"
L=$OUT/log.txt
SIZE=${SIZE:-320x240}
mkdir -p /tmp/bisect-images
"$P" devices >> "$L" 2>&1
scenes=${SCENES:-"$dir/scenes/CornellBox/CornellBox.glb $dir/scenes/DreamApartment/dream-apartment.glb"}
# Word splitting of the list is wanted here (paths without spaces).
for scene in $scenes; do
    s=$(basename "${scene%.*}")
    for k in ${KERNELS:-megakernel wavefront}; do
        ref=
        while read -r r; do
            o=/tmp/bisect-images/$s-$k-$r.exr
            t0=$SECONDS
            if ! PENUMBRA_KERNEL_DIR=$dir/k/$r "$P" render "$scene" --device "${DEVICE:-gpu}" \
                --kernel "$k" --width "${SIZE%x*}" --height "${SIZE#*x}" --spp "${SPP:-16}" \
                --seed 7 -o "$o" >/dev/null 2>/tmp/bisect-err.txt; then
                echo "$s $k $r FAILED: $(tail -1 /tmp/bisect-err.txt)" >> "$L"
                continue
            fi
            if [[ -z $ref ]]; then ref=$o res=ref
            elif cmp -s "$ref" "$o"; then res=same
            else res=DIFFERS; fi
            echo "$s $k $r $res $((SECONDS - t0)) s" >> "$L"
        done < "$dir/revs"
    done
done
cat "$L"
