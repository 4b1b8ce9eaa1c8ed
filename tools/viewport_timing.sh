#!/usr/bin/env bash
# Measures the viewport's response to a light move in a 1280x720 Blender window under Xvfb (see
# tools/viewport_timing.py). A program, not a test: run it on a quiet machine after `bash scripts/build.sh`.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
BLENDER_USER_SCRIPTS="$root/build/blender" TMPDIR="$scratch" \
  xvfb-run -a -s "-screen 0 1280x800x24" \
  blender --factory-startup -noaudio --window-geometry 0 0 1280 720 --addons photonsplat \
  "$root/blend_scenes/cornell_caustics.blend" --python "$root/tools/viewport_timing.py" 2>&1 | grep "viewport_timing" 
