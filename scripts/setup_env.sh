#!/usr/bin/env bash
# Creates the project's virtual environment and installs the core, every plugin
# under plugins/, and the test fixture plugins. Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}

# System library for headless rendering (Mesa EGL / OSMesa; embodichain_core/rendering.py
# picks MUJOCO_GL=egl when libEGL is found, else osmesa). Only when no EGL vendor
# library (Mesa or NVIDIA) and no OSMesa is present, and only when we may install
# packages (root with apt). Both Mesa backends render on the CPU (llvmpipe).
# (ldconfig's output is captured first: with pipefail, 'ldconfig | grep -q' can fail on SIGPIPE.)
GL_LIBS=$(ldconfig -p 2>/dev/null || true)
if ! grep -q -E "libOSMesa|libEGL_mesa|libEGL_nvidia" <<<"$GL_LIBS"; then
  if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = "0" ]; then
    echo "[setup] installing Mesa (EGL/OSMesa) for headless rendering"
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
        libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6 >/dev/null) \
      || echo "[setup] warning: could not install Mesa; rendering needs libEGL or libOSMesa" \
              "(apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6)"
  else
    echo "[setup] warning: no EGL/OSMesa library found; camera sensors need one" \
         "(apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6)"
  fi
fi

if [ ! -x .venv/bin/python ]; then
  "$PYTHON" -m venv .venv
fi
PIP=".venv/bin/python -m pip"
$PIP install -q --upgrade pip >/dev/null 2>&1 || true
# torch: the version lerobot 0.4.x allows (plugins/embodichain-lerobot needs torch<2.11,
# torchvision<0.26). Pinned first so no later requirement pulls another build. The
# registry's Linux build bundles CUDA libraries (about 4 GB of wheels); it runs on the CPU.
TORCH_VERSION=${TORCH_VERSION:-2.10.0}
TORCHVISION_VERSION=${TORCHVISION_VERSION:-0.25.0}
$PIP install -q "torch==$TORCH_VERSION" "torchvision==$TORCHVISION_VERSION"
args=(-e ".[test]")
for p in plugins/*/ tests/fixture_plugins/*/; do
  [ -f "$p/pyproject.toml" ] && args+=(-e "$p")
done
$PIP install -q "${args[@]}"
echo "[setup] environment ready in .venv"
