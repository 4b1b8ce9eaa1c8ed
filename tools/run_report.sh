#!/usr/bin/env bash
# Regenerates docs/results/report.md, report.csv and the report_*.png plots and crops (issue 4: speed against
# error): every scene of blend_scenes/ at 128 pixels wide (height from the scene's aspect), one Blender run per
# scene measuring the paper's tables, progressive splatting over time and, on the caustic scenes, Cycles; then
# plain Python writes the tables and plots. References are cached under build/report/reference/ (keyed by each
# .blend's content), so a rerun skips them; then the caustic Cornell box again at 256x256. Measured: 12 + 9
# minutes on the project's 2-core machine the first time, about 7 + 4 once the references are cached.
# Run after scripts/build.sh. Extra arguments go to every measure run
# (e.g. --width 128 --seconds 3 --no-cycles; see tools/report.py --help).
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
# The caustic Cornell box once more at 256x256 (a 300 s reference): how the comparison with Cycles moves with
# resolution (Cycles' cost grows with the pixels, a pass's photons do not).
BLENDER_USER_SCRIPTS="$root/build/blender" blender -b --factory-startup -noaudio --python-exit-code 1 \
  --addons photonsplat "$root/blend_scenes/cornell_caustics.blend" --python "$root/tools/report.py" -- \
  measure --out "$root/build/report_256" --width 256 --reference-seconds 300 --cycles-max-seconds 60 "$@"
/usr/bin/python3 "$root/tools/report.py" write --out "$root/build/report_256" \
  --docs "$root/docs/results/cornell_caustics_256"
echo "report written to $root/docs/results/report.md and $root/docs/results/cornell_caustics_256/report.md"
