#!/usr/bin/env bash
# Installs, from Debian 12's own packages, whatever the build, the demo and the tests need and the machine lacks.
# Idempotent: packages already present are not touched; nothing is downloaded from anywhere but apt.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libembree-dev libtbb-dev libglm-dev
  libopenimageio-dev openimageio-tools
  pybind11-dev python3-dev python3-numpy python3-pytest python3-skimage python3-matplotlib python3-venv
  libgtest-dev
  clang libclang-rt-14-dev llvm
  blender
  xvfb xauth x11-utils imagemagick mesa-vulkan-drivers libgl1-mesa-dri
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
