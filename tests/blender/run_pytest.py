"""Runs pytest inside Blender, so the tests can use bpy and the registered add-on.

Two ways, one per kind of Blender (scripts/blender_suite.sh runs both):
- Blender as a program (Debian's 3.4), from the repository root, after a build:
      BLENDER_USER_SCRIPTS=$PWD/build/blender TMPDIR=<scratch> blender -b --factory-startup -noaudio \
          --python-exit-code 1 --addons photonsplat --python tests/blender/run_pytest.py -- -q tests/blender
- Blender as a Python module (the `bpy` wheel of 4.5 or 5.x in a virtual environment, scripts/bpy_venv.sh):
      BLENDER_USER_SCRIPTS=$PWD/build/blender build/bpy-4.5.15/bin/python tests/blender/run_pytest.py -- \
          -q tests/blender
  The module has no command line, so this script does what `--factory-startup --addons photonsplat` does.

Everything after `--` goes to pytest. The exit code is pytest's; "no tests collected" (5) is kept as a failure,
since a test run that ran nothing proves nothing.
"""

import sys
from pathlib import Path

import bpy
import pytest


def start_module_blender():
    """Blender as a module: factory settings, then the add-on enabled from BLENDER_USER_SCRIPTS."""
    import addon_utils

    bpy.ops.wm.read_factory_settings(use_empty=False)
    if addon_utils.enable("photonsplat", default_set=True, handle_error=None) is None:
        print("run_pytest.py: the add-on photonsplat could not be enabled (is BLENDER_USER_SCRIPTS set?)",
              file=sys.stderr)
        sys.exit(1)


def main():
    if not bpy.app.binary_path:          # imported as a module, not run by the blender program
        start_module_blender()
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [str(Path(__file__).resolve().parent)]
    # The cache provider would write .pytest_cache into the source tree; it is of no use here.
    code = int(pytest.main(["-p", "no:cacheprovider", *args]))
    if code == int(pytest.ExitCode.NO_TESTS_COLLECTED):
        print("run_pytest.py: no tests were collected, which counts as a failure", file=sys.stderr)
    sys.stdout.flush()
    sys.exit(code)


main()
