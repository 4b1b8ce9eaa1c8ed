"""The add-on zip (cmake target addon_zip, build/photonsplat-<version>.zip) installs into an empty user scripts
folder with Blender's own add-on installer and renders. A separate Blender process, so that the add-on under
test comes from the zip only, not from build/blender."""

import os
import subprocess
import sys
import zipfile

import bpy
import photonsplat
from blender_helpers import BLEND_SCENES, REPO


def addon_zip():
    version = ".".join(str(v) for v in photonsplat.bl_info["version"])
    return REPO / "build" / f"photonsplat-{version}.zip"


def blender_command():
    """The command that runs a Python script in a fresh Blender like this one: the blender program, or, for
    Blender as a Python module (the bpy wheel), this Python."""
    if bpy.app.binary_path:
        return [bpy.app.binary_path, "-b", "--factory-startup", "-noaudio", "--python-exit-code", "1", "--python"]
    return [sys.executable]


def test_zip_holds_the_package_and_the_module():
    path = addon_zip()
    assert path.exists(), f"{path} is missing: build it with cmake --build build --target addon_zip"
    names = zipfile.ZipFile(path).namelist()
    assert "photonsplat/__init__.py" in names and "photonsplat/engine.py" in names
    assert any(n.startswith("photonsplat/_core.") and n.endswith(".so") for n in names)
    assert not any("__pycache__" in n for n in names)
    assert all(n.startswith("photonsplat/") for n in names)


def test_zip_installs_with_blenders_installer_and_renders(tmp_path):
    scripts = tmp_path / "user_scripts"
    scripts.mkdir()
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(scripts), TMPDIR=str(tmp_path))
    arguments = ["--", str(addon_zip()), str(BLEND_SCENES / "cornell_caustics.blend"), str(tmp_path / "out.exr")]
    run = subprocess.run(
        [*blender_command(), str(REPO / "tests/blender/install_and_render.py"), *arguments],
        env=env, capture_output=True, text=True, timeout=120)
    log = run.stdout + run.stderr
    assert run.returncode == 0 and "INSTALL_AND_RENDER_OK" in log, log[-3000:]
    assert str(scripts) in log                   # the add-on that rendered is the installed one
    assert (scripts / "addons" / "photonsplat").is_dir()
