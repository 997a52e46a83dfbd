#!/usr/bin/env bash
# Creates the project's virtual environment and installs the core (with its test and
# `new` extras), every plugin under plugins/ (embodichain-viewer included: the viewers of
# `headless: false`), and torch. Idempotent. The test fixture
# plugins (tests/fixture_plugins/) are not installed: the tests expose them themselves.
#
# Environment variables:
#   PYTHON           interpreter that creates .venv (default: python3)
#   TORCH_VERSION    torch version (default below), TORCHVISION_VERSION likewise
#   TORCH_INDEX_URL  install torch and torchvision from this package index instead of the
#                    default one, e.g. the CPU-only wheels, which leave out about 4 GB of
#                    CUDA libraries a CPU machine never uses:
#                      TORCH_INDEX_URL=https://download.pytorch.org/whl/cpu make setup
#                    Unset (the default), they come from the configured registry (pip's
#                    index), whose Linux build bundles the CUDA libraries.
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

# FFmpeg shared libraries: lerobot's default video backend (torchcodec) decodes the
# recorded mp4 files with them (PyAV bundles its own, under other names, which
# torchcodec cannot use). Debian 12 ships FFmpeg 5.1 (~165 MB). Only when libavcodec
# is missing, and only when we may install packages (root with apt).
FFMPEG_PKGS="libavutil57 libavcodec59 libavformat59 libavdevice59 libavfilter8 libswscale6 libswresample4"
if ! grep -q "libavcodec\.so\." <<<"$GL_LIBS"; then
  if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = "0" ]; then
    echo "[setup] installing FFmpeg shared libraries (torchcodec decodes the dataset videos with them)"
    # shellcheck disable=SC2086
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        $FFMPEG_PKGS >/dev/null) \
      || echo "[setup] warning: could not install FFmpeg's libraries; LeRobotDataset(...) then needs" \
              "video_backend='pyav' (apt-get install --no-install-recommends $FFMPEG_PKGS)"
  else
    echo "[setup] warning: no FFmpeg shared libraries found; LeRobotDataset(...) with the default video" \
         "backend (torchcodec) cannot decode videos; install them (apt-get install --no-install-recommends" \
         "$FFMPEG_PKGS, or your system's FFmpeg 4-8 libraries) or pass video_backend='pyav'"
  fi
fi

# Xvfb and Chromium: the viewer tests photograph MuJoCo's native window on a virtual X
# display and the browser viewer's page in headless Chromium (plugins/embodichain-viewer).
# Only when missing, and only when we may install packages (root with apt).
VIEWER_TEST_PKGS="xvfb chromium"
if ! command -v Xvfb >/dev/null 2>&1 || ! command -v chromium >/dev/null 2>&1; then
  if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = "0" ]; then
    echo "[setup] installing Xvfb and Chromium (the viewer tests' screenshots)"
    # shellcheck disable=SC2086
    (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        $VIEWER_TEST_PKGS >/dev/null) \
      || echo "[setup] warning: could not install $VIEWER_TEST_PKGS; the viewer screenshot tests will skip"
  else
    echo "[setup] note: no Xvfb/Chromium; the viewer screenshot tests will skip (apt-get install $VIEWER_TEST_PKGS)"
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
# docs/getting_started.md and the other pages cite this version (tests/test_docs.py checks).
TORCH_VERSION=${TORCH_VERSION:-2.10.0}
TORCHVISION_VERSION=${TORCHVISION_VERSION:-0.25.0}
TORCH_INDEX_URL=${TORCH_INDEX_URL:-}
torch_index=()
if [ -n "$TORCH_INDEX_URL" ]; then
  echo "[setup] torch $TORCH_VERSION and torchvision $TORCHVISION_VERSION from $TORCH_INDEX_URL"
  torch_index=(--index-url "$TORCH_INDEX_URL")
fi
$PIP install -q ${torch_index[@]+"${torch_index[@]}"} "torch==$TORCH_VERSION" "torchvision==$TORCHVISION_VERSION"
# The core with its test extra (pytest, pytest-xdist for `make test`'s workers, sybil, ruff, mypy,
# mkdocs) and the `new` extra (cookiecutter, for `embodichain new`).
args=(-e ".[test,new]")
for p in plugins/*/; do
  [ -f "$p/pyproject.toml" ] && args+=(-e "$p")
done
$PIP install -q "${args[@]}"
# An older set-up installed the test fixture plugin, which put FixtureReach-v0 into every
# `embodichain list tasks`: remove it (the tests expose it themselves).
if $PIP show -q embodichain-fixture >/dev/null 2>&1; then
  echo "[setup] removing the test fixture plugin an older set-up installed"
  $PIP uninstall -q -y embodichain-fixture
fi
echo "[setup] environment ready in .venv"
