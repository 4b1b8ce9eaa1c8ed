"""Scene.bump_shadowing and add_material(bump_map_correction=...): which bump shadowing term diffuse closures under a
bumped normal take (native/include/photonsplat/bump_shadowing.h). The terms themselves are checked in
tests/native/test_bump_shadowing.cpp and against Cycles in tests/blender/test_bump_shadowing.py."""
import pytest

import photonsplat as ps


def test_the_term_follows_the_blender_version_and_refuses_others():
    scene = ps.Scene()
    assert scene.bump_shadowing == "cycles3"
    scene.bump_shadowing = "cycles4"
    assert scene.bump_shadowing == "cycles4"
    with pytest.raises(ValueError, match="bump_shadowing"):
        scene.bump_shadowing = "cycles5"
    assert scene.bump_shadowing == "cycles4"


def test_a_material_takes_its_bump_map_correction():
    scene = ps.Scene()
    assert scene.add_material(name="corrected", kind="diffuse") == 0
    assert scene.add_material(name="uncorrected", kind="diffuse", bump_map_correction=False) == 1
    with pytest.raises(TypeError):
        scene.add_material(name="bad", kind="diffuse", bump_map_correction="no")
