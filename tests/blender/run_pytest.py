"""Runs pytest inside Blender, so the tests can use bpy and the registered add-on.

From the repository root, after a build:
    BLENDER_USER_SCRIPTS=$PWD/build/blender TMPDIR=<scratch> blender -b --factory-startup -noaudio \
        --python-exit-code 1 --addons photonsplat --python tests/blender/run_pytest.py -- -q tests/blender

Everything after `--` goes to pytest. Blender exits with pytest's exit code; "no tests collected" (5) is kept
as a failure, since a test run that ran nothing proves nothing.
"""

import sys
from pathlib import Path

import pytest


def main():
    args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [str(Path(__file__).resolve().parent)]
    # The cache provider would write .pytest_cache into the source tree; it is of no use here.
    code = int(pytest.main(["-p", "no:cacheprovider", *args]))
    if code == int(pytest.ExitCode.NO_TESTS_COLLECTED):
        print("run_pytest.py: no tests were collected, which counts as a failure", file=sys.stderr)
    sys.stdout.flush()
    sys.exit(code)


main()
