#!/usr/bin/env bash
# Makes build/bpy-<VERSION>/, a virtual environment of Debian's /usr/bin/python3 (3.11) holding Blender <VERSION>
# as a Python module (the `bpy` wheel from the Python package index) and pytest: current Blender releases,
# headless, for the Blender test suite (scripts/blender_suite.sh). Test tooling only: the product's own
# dependencies stay Debian packages. Idempotent: an environment that already imports that bpy is kept.
# Prints the environment's python.
#   bash scripts/bpy_venv.sh 4.5.15
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
version="${1:?usage: bpy_venv.sh VERSION (e.g. 4.5.15)}"
venv="$root/build/bpy-$version"
python="$venv/bin/python"

if [ -x "$python" ] && "$python" -c "import sys, bpy; sys.exit(bpy.app.version_string.split()[0] != '$version')" \
     >/dev/null 2>&1; then
  echo "$python"
  exit 0
fi
rm -rf "$venv"
mkdir -p "$root/build"
/usr/bin/python3 -m venv "$venv" >&2
# bpy pins numpy below 2; the module is built against Debian's numpy 1.24, whose C API numpy 1.26 keeps.
# pip's own chatter goes to a log, shown when the install fails.
if ! "$python" -m pip install --quiet --disable-pip-version-check "bpy==$version" pytest >"$venv/pip.log" 2>&1; then
  cat "$venv/pip.log" >&2
  echo "bpy_venv.sh: could not install bpy==$version into $venv" >&2
  exit 1
fi
echo "$python"
