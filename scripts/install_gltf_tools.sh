#!/usr/bin/env bash
# Installs the glTF optimizers the compressed-scene tests (tests/compressed.rs) run, at the
# versions tools/package-lock.json pins: node and npm from Debian when missing, then
# gltfpack and @gltf-transform/cli into tools/node_modules (ignored by git).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi
cd tools
npm ci --no-audit --no-fund --loglevel=error
npm ls --depth=0
