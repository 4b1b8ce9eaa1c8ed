"""Makes the freshly built package importable: <repo>/build/python (override with PHOTONSPLAT_BUILD_DIR)."""
import os
import pathlib
import sys

_build = pathlib.Path(os.environ.get("PHOTONSPLAT_BUILD_DIR", pathlib.Path(__file__).resolve().parents[2] / "build"))
sys.path.insert(0, str(_build / "python"))
