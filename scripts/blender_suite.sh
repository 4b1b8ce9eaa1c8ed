#!/usr/bin/env bash
# Runs the Blender test suite (tests/blender, pytest inside Blender) under every supported Blender, or under the
# versions named: 3.4 is Debian's blender program (`blender -b`); 4.5 LTS and 5.0 are the `bpy` modules of
# scripts/bpy_venv.sh. Needs a build (scripts/build.sh). Extra arguments after `--` go to pytest (default: the
# whole tests/blender folder).
#   bash scripts/blender_suite.sh                 # 3.4, 4.5.15 and 5.0.1
#   bash scripts/blender_suite.sh 5.0.1 -- -q tests/blender/test_light_units.py
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# The supported versions. 5.0.1 is the newest 5.x with a wheel for Python 3.11 (5.1 moved to Python 3.13).
SUPPORTED=(3.4 4.5.15 5.0.1)

versions=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do versions+=("$1"); shift; done
[ $# -gt 0 ] && shift
[ ${#versions[@]} -eq 0 ] && versions=("${SUPPORTED[@]}")
pytest_args=("$@")
[ ${#pytest_args[@]} -eq 0 ] && pytest_args=(-q -p no:cacheprovider tests/blender)

run_version() {  # the suite under one version, to stdout; its status
  local version="$1" scratch started status=0 python
  scratch="$(mktemp -d)"
  started=$SECONDS
  echo "== Blender $version: tests/blender"
  if [ "$version" = "3.4" ]; then
    (cd "$root" && BLENDER_USER_SCRIPTS="$root/build/blender" TMPDIR="$scratch" \
      blender -b --factory-startup -noaudio --python-exit-code 1 --addons photonsplat \
      --python tests/blender/run_pytest.py -- "${pytest_args[@]}") || status=1
  else
    python="$(bash "$root/scripts/bpy_venv.sh" "$version")"
    # The module reads its user folders from the environment: keep them out of the user's own.
    (cd "$root" && BLENDER_USER_SCRIPTS="$root/build/blender" BLENDER_USER_CONFIG="$scratch/config" \
      BLENDER_USER_DATAFILES="$scratch/datafiles" TMPDIR="$scratch" \
      "$python" tests/blender/run_pytest.py -- "${pytest_args[@]}") || status=1
  fi
  echo "== Blender $version: $((SECONDS - started)) s"
  rm -rf "$scratch"
  return $status
}

# Blender 3.4 runs alone (its renders take both cores). The bpy modules' suites run side by side, each into a log
# printed when it ends: each keeps about 1.3 of 2 cores busy, and the two took 98 s together against 142 s one
# after the other. Their virtual environments are made first, one at a time (pip's cache is shared).
status=0
pids=()
logs=()
for version in "${versions[@]}"; do
  if [ "$version" = "3.4" ] || [ ${#versions[@]} -eq 1 ]; then
    run_version "$version" || status=1
  else
    bash "$root/scripts/bpy_venv.sh" "$version" >/dev/null
    log="$(mktemp)"
    run_version "$version" >"$log" 2>&1 &
    pids+=("$!")
    logs+=("$log")
  fi
done
for i in "${!pids[@]}"; do
  wait "${pids[$i]}" || status=1
  cat "${logs[$i]}"
  rm -f "${logs[$i]}"
done
exit $status
