#!/usr/bin/env bash
# Issue 19's frame benchmark (tools/frame_benchmark.py) on the Cornell box with caustics and the atrium at
# 1920x1080: stage times, rays per second beside Embree's floor, and F12 against one Cycles sample. Writes
# docs/results/frame_benchmark.md (and the JSON records into build/frame_benchmark/). Run after scripts/build.sh,
# on a quiet machine; about 3 minutes on 2 cores.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$root/build/frame_benchmark"
mkdir -p "$out"
for scene in cornell_caustics atrium; do
  BLENDER_USER_SCRIPTS="$root/build/blender" blender -b --factory-startup -noaudio --python-exit-code 1 \
    --addons photonsplat "$root/blend_scenes/$scene.blend" --python "$root/tools/frame_benchmark.py" -- \
    --json "$out/$scene.json" "$@" | grep -v "^frame_benchmark:" || true
  test -s "$out/$scene.json"
done
/usr/bin/python3 "$root/tools/frame_benchmark.py" --report "$root/docs/results/frame_benchmark.md" \
  "$out/cornell_caustics.json" "$out/atrium.json"
