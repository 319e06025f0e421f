#!/usr/bin/env bash
# Writes optimized versions of glTF scenes with the real tools, as users' pipelines do:
#   NAME.pack.glb   gltfpack (KHR_mesh_quantization)
#   NAME.cc.glb     gltfpack -cc (EXT_meshopt_compression + quantization)
#   NAME.draco.glb  gltf-transform draco (KHR_draco_mesh_compression)
#   NAME.webp.glb   gltf-transform webp --lossless (EXT_texture_webp; only for scenes with textures;
#                   lossless, so the comparison checks the decoder, not the codec's loss)
# Usage: scripts/optimized_scenes.sh OUT_DIR SCENE.glb|SCENE.gltf...
# The tools come from tools/node_modules (scripts/install_gltf_tools.sh).
set -euo pipefail
bin="$(cd "$(dirname "$0")/.." && pwd)/tools/node_modules/.bin"
out="$1"
shift
mkdir -p "$out"
for scene in "$@"; do
    name="$(basename "${scene%.*}")"
    "$bin/gltfpack" -i "$scene" -o "$out/$name.pack.glb" >/dev/null
    "$bin/gltfpack" -cc -i "$scene" -o "$out/$name.cc.glb" >/dev/null
    "$bin/gltf-transform" draco "$scene" "$out/$name.draco.glb" >/dev/null
    if grep -aq "\"images\"" "$scene"; then
        "$bin/gltf-transform" webp --lossless true "$scene" "$out/$name.webp.glb" >/dev/null
    fi
done
