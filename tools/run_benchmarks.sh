#!/usr/bin/env bash
# Regenerates the tables behind docs/benchmarks.md (the paper's method set, measured like the paper):
# the atrium fly-through and the Cornell box at 1920x1080, photon counts 10k / 50k / 200k / 1M, every method,
# written as markdown and JSON into docs/results/. docs/benchmarks.md says how long it takes.
# Run after scripts/build.sh (or either README command).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$root/docs/results"
mkdir -p "$out"
bench() {  # scene, name, extra arguments...
  local scene="$1" name="$2"
  shift 2
  BLENDER_USER_SCRIPTS="$root/build/blender" blender -b --factory-startup -noaudio --python-exit-code 1 \
    --addons photonsplat "$root/blend_scenes/$scene" --python "$root/tools/benchmark.py" -- \
    --resolution 1920x1080 --json "$out/$name.json" --markdown "$out/$name.md" "$@"
}
methods=tiled,cluster,cluster_cone,directional,gather
# Every method, photon count and fly-through position once.
bench atrium.blend bench_atrium --frames 1-8 --photons 10000,50000,200000,1000000 --methods "$methods" --repeats 1
# The acceptance ratios at 200k photons with medians of 3 runs.
bench atrium.blend bench_atrium_200k --frames 1-8 --photons 200000 --methods tiled,cluster_cone,directional --repeats 3
# The Cornell box with glass and mirror spheres.
bench cornell_caustics.blend bench_cornell --photons 10000,50000,200000,1000000 --methods "$methods" --repeats 3
echo "tables written to $out"
