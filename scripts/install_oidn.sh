#!/usr/bin/env bash
# Installs Intel Open Image Denoise 2.5.1 for the denoiser's comparison test (tests/denoise.rs)
# and `penumbra bench denoise`: the pinned PyPI wheel pyoidn==2.5.1.0, which ships
# libOpenImageDenoise.so.2.5.1 (CPU and CUDA devices) and a Python binding, with numpy and
# cffi. Needs python3 and pip; idempotent.
set -euo pipefail

installed() {
    python3 -c 'import importlib.metadata as m, pyoidn, sys; sys.exit(m.version("pyoidn") != "2.5.1.0")' 2>/dev/null
}
if installed; then
    echo "install_oidn: pyoidn 2.5.1.0 is installed"
    exit 0
fi
if ! python3 -m pip --version >/dev/null 2>&1; then
    apt-get install -y -qq --no-install-recommends python3-pip >/dev/null
fi
# Debian 12 marks its Python as externally managed; this machine is CI's or the user's own.
python3 -m pip install --quiet --break-system-packages pyoidn==2.5.1.0 2>/dev/null \
    || python3 -m pip install --quiet pyoidn==2.5.1.0
installed || { echo "install_oidn: pyoidn 2.5.1.0 did not install" >&2; exit 1; }
echo "install_oidn: installed pyoidn 2.5.1.0"
