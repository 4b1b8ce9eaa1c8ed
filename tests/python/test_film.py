"""The film: a render makes, holds and returns only the outputs its settings ask for, with the same bits for the
outputs it does make, and the add-on's render passes name the core's outputs. Under 10 s."""
import importlib.util
import pathlib

import numpy as np

import photonsplat as ps
from scenes import cornell_box, cornell_camera, plane_scene

ADDON = pathlib.Path(__file__).resolve().parents[2] / "addon" / "photonsplat"


def test_only_the_requested_outputs_are_returned_with_the_same_bits():
    scene, camera = cornell_box(), cornell_camera(24, 24)
    everything = ps.RenderSettings(photons=5000, seed=3, caustics_pass=True)
    image, _, passes = ps.render(scene, camera, everything, passes=True)
    assert set(passes) == set(ps.FILM_OUTPUTS) - {"combined"}
    some = ps.RenderSettings(photons=5000, seed=3, outputs=("direct", "depth"))
    image_some, _, passes_some = ps.render(scene, camera, some, passes=True)
    assert set(passes_some) == {"direct", "depth"}
    assert np.array_equal(image_some, image)
    for name in passes_some:
        assert np.array_equal(passes_some[name], passes[name]), name


def test_a_progressive_render_of_combined_alone_holds_32_bytes_a_pixel_of_sums():
    # The viewport's case: a 1280x720 view that shows only Combined holds the running mean of RGBA in double,
    # 32 bytes a pixel; every output held 144.
    scene = plane_scene()
    camera = ps.look_at_camera(eye=(0, -4, 3), target=(0, 0, 0), width=1280, height=720)
    pixels = 1280 * 720
    fields = dict(photons=500, direct_samples=1, iterations=2, boundary_correction=False)
    combined = ps.Progressive(scene, camera, ps.RenderSettings(outputs=("combined",), **fields))
    combined.step()
    assert combined.stats()["bytes"]["progressive_sums"] <= 32 * pixels
    every = ps.RenderSettings(outputs=ps.FILM_OUTPUTS, **fields)
    full = ps.Progressive(scene, camera, every)
    full.step()
    assert full.stats()["bytes"]["progressive_sums"] == (4 + 4 * 3) * 8 * pixels + (3 + 1) * 4 * pixels  # 144 bytes
    assert np.array_equal(full.image(), combined.image())


def test_the_addon_render_passes_name_the_core_outputs():
    spec = importlib.util.spec_from_file_location("passes_table", ADDON / "passes.py")
    passes = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(passes)
    sources = [p.source for p in passes.PASSES if p.source]
    assert sorted(sources) == sorted(set(ps.FILM_OUTPUTS) - {"combined"})
