"""Fixtures of the tests that run inside Blender (run_pytest.py starts them there).

Outside Blender (plain python3 -m pytest) there is no bpy: this folder is then ignored, not failed.
"""

import pytest

try:
    import bpy
except ImportError:
    bpy = None

if bpy is None:
    collect_ignore_glob = ["*.py"]


@pytest.fixture
def caustics_scene():
    from blender_helpers import open_scene
    return open_scene("cornell_caustics")


@pytest.fixture
def diffuse_scene():
    from blender_helpers import open_scene
    return open_scene("cornell_diffuse")


@pytest.fixture
def empty_scene():
    bpy.ops.wm.read_homefile(use_empty=True)
    return bpy.context.scene


@pytest.fixture(scope="session")
def core():
    """The compiled module. Render tests fail (not skip) without it: a build that cannot render is broken."""
    from photonsplat import engine
    return engine.load_core()
