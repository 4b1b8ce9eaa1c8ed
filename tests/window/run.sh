#!/usr/bin/env bash
# The real-window test (tests/window/viewport_window.py) under Xvfb with software OpenGL: Blender opens the
# caustic Cornell box, renders it in a Rendered viewport and checks the screenshot. Fails on a non-zero exit
# or on any Python error in Blender's log. Screenshot and log land in build/test-artifacts/.
# PHOTONSPLAT_DOC_IMAGES=docs/images also retakes the user guide's screenshots.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
artifacts="$root/build/test-artifacts"
mkdir -p "$artifacts"
log="$artifacts/viewport_window.log"
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT

status=0
BLENDER_USER_SCRIPTS="$root/build/blender" TMPDIR="$scratch" PHOTONSPLAT_ARTIFACTS="$artifacts" \
  timeout 150 xvfb-run -a -s "-screen 0 1280x800x24" \
  blender --factory-startup -noaudio --window-geometry 0 0 1280 720 --addons photonsplat \
  "$root/blend_scenes/cornell_caustics.blend" --python "$root/tests/window/viewport_window.py" \
  >"$log" 2>&1 || status=$?
grep "viewport_window:" "$log" || true
if [ "$status" -ne 0 ]; then
  echo "window test: Blender exited with status $status; log: $log"; tail -30 "$log"; exit 1
fi
if grep -nE "Traceback|Error:|Exception" "$log"; then
  echo "window test: Python error in Blender's log ($log)"; exit 1
fi
echo "window test: passed; screenshot $artifacts/viewport_caustic.png"
