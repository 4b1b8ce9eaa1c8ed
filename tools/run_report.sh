#!/usr/bin/env bash
# Regenerates docs/results/report.md, report.csv and the report_*.png plots and crops (speed against error):
# every scene of blend_scenes/ at 128 pixels wide (height from the scene's aspect), one Blender run per
# scene measuring the paper's tables, progressive splatting over time and, on the caustic scenes, Cycles; then
# plain Python writes the tables and plots. Then the caustic scenes once more at 256 pixels wide, into
# docs/results/caustic_256/. References (4096 samples per pixel, however long that takes) are cached under
# build/report*/reference/ keyed by each .blend's content, so a rerun skips them; they can be made ahead, under
# any load, with `measure --reference-only` (README.md says how long each part takes). Run the measurements on a
# quiet machine (every report states its load average). Run after scripts/build.sh. Extra arguments go to every
# measure run (e.g. --seconds 3 --no-cycles; see tools/report.py --help).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out="$root/build/report"
mkdir -p "$out"
scenes=(cornell_caustics cornell_diffuse glossy_row atrium)
for scene in "${scenes[@]}"; do
  BLENDER_USER_SCRIPTS="$root/build/blender" blender -b --factory-startup -noaudio --python-exit-code 1 \
    --addons photonsplat "$root/blend_scenes/$scene.blend" --python "$root/tools/report.py" -- \
    measure --out "$out" "$@"
done
/usr/bin/python3 "$root/tools/report.py" write --out "$out" --docs "$root/docs/results"
# The caustic scenes once more at 256 pixels wide: how the comparison with Cycles moves with resolution (Cycles'
# cost grows with the pixels, a pass's photons do not).
for scene in cornell_caustics glossy_row atrium; do
  BLENDER_USER_SCRIPTS="$root/build/blender" blender -b --factory-startup -noaudio --python-exit-code 1 \
    --addons photonsplat "$root/blend_scenes/$scene.blend" --python "$root/tools/report.py" -- \
    measure --out "$root/build/report_256" --width 256 --cycles-max-seconds 60 "$@"
done
/usr/bin/python3 "$root/tools/report.py" write --out "$root/build/report_256" --docs "$root/docs/results/caustic_256"
echo "report written to $root/docs/results/report.md and $root/docs/results/caustic_256/report.md"
