#!/usr/bin/env bash
# README command (2): install what is missing, build, and run every test: the native GoogleTest suite (ctest),
# the Python API tests (pytest on /usr/bin/python3), the Blender tests under Blender 3.4, 4.5 LTS and 5.0
# (scripts/blender_suite.sh: pytest inside blender -b, and in the pip bpy modules of build/bpy-*), the
# real-window viewport test (Blender under Xvfb; its screenshot stays in build/test-artifacts/), and the
# sanitizer and fuzzing runs of scripts/sanitize.sh (ASan+UBSan suite, TSan on cross-thread control, 30 s of
# libFuzzer; PHOTONSPLAT_SANITIZE_STEPS="" skips them, e.g. for a quick local run).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/install-deps.sh"
bash "$root/scripts/build.sh"

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
status=0

echo "== native tests (ctest)"
ctest --test-dir "$root/build" --output-on-failure --timeout 300 --parallel "$(nproc)" || status=1

echo "== Python API tests (pytest)"
(cd "$root" && /usr/bin/python3 -m pytest -q -p no:cacheprovider tests/python) || status=1

echo "== Blender tests under every supported Blender: 3.4 (blender -b), 4.5 LTS and 5.0 (bpy modules)"
bash "$root/scripts/blender_suite.sh" || status=1

echo "== real-window test (Blender under Xvfb: Rendered viewport screenshot)"
bash "$root/tests/window/run.sh" || status=1

echo "== sanitizers and fuzzing (scripts/sanitize.sh)"
bash "$root/scripts/sanitize.sh" || status=1

exit $status
