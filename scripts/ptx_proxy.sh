#!/usr/bin/env bash
# A proxy for "does this kernel change alter the GPU's arithmetic?" without a GPU: compiles the
# program source penumbra gives an NVIDIA GPU, at two revisions, with clang for NVIDIA's PTX,
# and compares each kernel's floating-point instructions:
#
#   scripts/ptx_proxy.sh OLD_REV NEW_REV [OUT_DIR]
#
# The program's source is the same for every scene and its options are the host's: the current
# binary writes both as it builds the wavefront program on the CPU (PENUMBRA_DUMP_PROGRAMS,
# src/cl/program.rs), the options once per scene (the wavefront's features are the scene's own,
# as on a GPU: render/strategy.rs adds nothing for it; the CPU's -cl-denorms-are-zero becomes
# the GPU's -DPERMUTE_BY_SELECT), the source once per revision, its kernels/ folder exported
# and read through PENUMBRA_KERNEL_DIR. The constants header is the binary's: a revision whose
# src/cl/types.rs differs is warned of.
#
# Each source is compiled by clang (CLANG, default clang-15) for nvptx64-nvidia-nvcl, with
# libclc's built-ins (LIBCLC, default Debian's libclc-15 nvptx64--nvidiacl.bc) linked in so that
# dot, normalize, mix and the like are instructions rather than calls, every function inlined
# into its kernels (inline made always_inline, so each kernel holds all its arithmetic), at -O3 with
# -ffp-contract=fast (a mul and an add fused wherever they meet, across statements and past
# `#pragma OPENCL FP_CONTRACT OFF`, as ptxas fuses PTX's unrounded mul/add) and with clang's
# default (fused within an expression, honouring the pragma; PTX ops then carry .rn). Each
# kernel's sequence of f32 arithmetic instructions, register names dropped, is compared
# (comparisons and selects are left out: a select picks a value exactly, and a select for a
# ternary swaps its operands under the opposite comparison): "same" (identical sequence), "reordered" (the same instructions in another order)
# or "DIFFERS" (with the counts that changed). Only kernels whose sequence differs are listed.
#
# Environment: PENUMBRA (binary, default target/release/penumbra; its host code decides the
# features and options), PENUMBRA_SCENES (default ../shared/scenes), SCENES (default the five
# shared scenes the GPU images were compared on, and the bundled box), CONTRACT (default
# "fast on"), CLANG, LIBCLC. Needs clang with the NVPTX target and libclc (Debian: apt-get
# install clang-15 libclc-15).
set -euo pipefail

old=${1:?usage: ptx_proxy.sh OLD_REV NEW_REV [OUT_DIR]}
new=${2:?usage: ptx_proxy.sh OLD_REV NEW_REV [OUT_DIR]}
out=${3:-$(mktemp -d /tmp/ptx_proxy.XXXXXX)}
P=$(realpath "${PENUMBRA:-target/release/penumbra}")
S=${PENUMBRA_SCENES:-../shared/scenes}
CLANG=${CLANG:-clang-15}
LIBCLC=${LIBCLC:-/usr/lib/clc/nvptx64--nvidiacl.bc}
SCENES=${SCENES:-"assets/cornell-box.glb $S/CornellBox/CornellBox.glb $S/FlightHelmet/FlightHelmet.gltf $S/DreamApartment/dream-apartment.glb $S/HotelRoom/hotel-room.glb $S/StanfordBunny/bunny.glb"}
mkdir -p "$out"

# Runs the binary on a scene with PENUMBRA_DUMP_PROGRAMS (and the environment given before it)
# and copies the path tracer's program it wrote to DEST.cl and DEST.options; the render itself
# may fail once the program is written (kernels of another revision than the host).
dump() {
    local scene=$1 dest=$2 tmp
    tmp=$(mktemp -d)
    PENUMBRA_DUMP_PROGRAMS=$tmp "$P" render "$scene" --device cpu --kernel wavefront \
        --width 8 --height 8 --spp 1 -o "$tmp/image.exr" >/dev/null 2>"$tmp/err" || true
    local cl
    cl=$(grep -l 'kernel void extend' "$tmp"/*.cl 2>/dev/null | head -1) ||
        { echo "no program written for $scene: $(tail -1 "$tmp/err")" >&2; exit 1; }
    cp "$cl" "$dest.cl"
    cp "${cl%.cl}.options" "$dest.options"
    rm -rf "$tmp"
}

# The program's source is the same for every scene, and the options are the host's: the source
# of each revision is dumped once (the bundled box, its kernels read from the revision's), the
# options of each scene once (GPU options: -DPERMUTE_BY_SELECT for -cl-denorms-are-zero).
mkdir -p "$out/options"
for scene in $SCENES; do
    name=$(basename "${scene%.*}")
    dump "$scene" "$out/options/$name"
    sed -i -e 's/-cl-denorms-are-zero/-DPERMUTE_BY_SELECT/' -e 's/-cl-nv-[^ ]*//g' \
        "$out/options/$name.options"
done
for rev in "$old" "$new"; do
    rm -rf "${out:?}/$rev" && mkdir -p "$out/$rev/tree"
    git archive "$rev" kernels | tar -x -C "$out/$rev/tree"
    git diff --quiet "$rev" HEAD -- src/cl/types.rs ||
        echo "warning: src/cl/types.rs differs between $rev and HEAD: the constants are HEAD's" >&2
    PENUMBRA_KERNEL_DIR=$out/$rev/tree dump assets/cornell-box.glb "$out/$rev/program"
done

# Each kernel's f32 instruction mnemonics, one line per kernel: "NAME op op op ...".
ops() {
    awk '
        /^\.(visible |weak )?(entry|func)/ {
            if (name != "") print name, seq
            line = $0; sub(/\(\)?[ \t]*$/, "", line); n = split(line, w, /[ \t(]+/); name = w[n]; seq = ""
            if ($1 != ".entry") name = ""
            next
        }
        {
            line = $0; sub(/^[ \t]+(@!?%p[0-9]+[ \t]+)?/, "", line); split(line, w, /[ \t]/); op = w[1]
            if (op ~ /^(fma|mul|add|sub|div|sqrt|rsqrt|rcp|neg|abs|min|max|ex2|lg2|sin|cos|cvt|copysign)\..*f32/) seq = seq " " op
        }
        END { if (name != "") print name, seq }
    ' "$1"
}

compile() {
    local rev=$1 name=$2 contract=$3 dir=$out/$1
    # shellcheck disable=SC2046
    "$CLANG" -x cl -cl-std=CL1.2 -target nvptx64-nvidia-nvcl -O3 -ffp-contract="$contract" \
        -Xclang -finclude-default-header -cl-fp32-correctly-rounded-divide-sqrt \
        -Xclang -mlink-builtin-bitcode -Xclang "$LIBCLC" -Wno-linker-warnings \
        '-Dinline=inline __attribute__((always_inline))' $(sed 's/-cl-fp32-correctly-rounded-divide-sqrt//' "$out/options/$name.options") \
        -S -o "$dir/$name.$contract.ptx" "$dir/program.cl" 2>"$dir/$name.$contract.clang.err" ||
        { echo "clang failed on $name at $rev: $(head -3 "$dir/$name.$contract.clang.err")" >&2; exit 1; }
    ops "$dir/$name.$contract.ptx" >"$dir/$name.$contract.ops"
}

status=0
for scene in $SCENES; do
    name=$(basename "${scene%.*}")
    for contract in ${CONTRACT:-fast on}; do
        compile "$old" "$name" "$contract" & a=$!
        compile "$new" "$name" "$contract" & b=$!
        wait $a && wait $b || exit 1
        report=$(python3 - "$out/$old/$name.$contract.ops" "$out/$new/$name.$contract.ops" <<'PY'
import collections, sys
def read(p):
    return {l.split()[0]: l.split()[1:] for l in open(p) if l.strip()}
a, b = read(sys.argv[1]), read(sys.argv[2])
same = reordered = 0
for f in sorted(set(a) | set(b)):
    if f not in a or f not in b:
        print(f"  {f}: only at {'new' if f in b else 'old'}")
    elif a[f] == b[f]:
        same += 1
    elif collections.Counter(a[f]) == collections.Counter(b[f]):
        reordered += 1
        print(f"  {f}: reordered ({len(a[f])} ops)")
    else:
        ca, cb = collections.Counter(a[f]), collections.Counter(b[f])
        delta = ", ".join(f"{k} {cb[k] - ca[k]:+d}" for k in sorted(set(ca) | set(cb)) if ca[k] != cb[k])
        print(f"  {f}: DIFFERS ({len(a[f])} -> {len(b[f])} ops: {delta})")
print(f"  {same} kernels the same")
PY
)
        echo "$name, -ffp-contract=$contract:"
        echo "$report"
        grep -q 'DIFFERS\|reordered\|only at' <<<"$report" && status=1
    done
done
echo "PTX and op lists in $out"
exit $status
