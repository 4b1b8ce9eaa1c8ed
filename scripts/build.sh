#!/usr/bin/env bash
# Configures and builds everything into build/: the core, the Python module laid out as
# build/python/photonsplat and build/blender/addons/photonsplat, the native tests, the legacy add-on zip
# (build/photonsplat-<version>.zip, Blender 3.4) and the Blender 4.2+ extension
# (build/photonsplat-<version>-linux_x64.zip).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cmake -S "$root" -B "$root/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPython_EXECUTABLE=/usr/bin/python3
cmake --build "$root/build" --parallel "$(nproc)"
