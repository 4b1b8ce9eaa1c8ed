"""Splatting against the independent reference where the atrium loses light (docs/results/README.md, "Atrium:
where splatting's missing light is"): a room lit by a sun through a skylight, whose photons go through the
sun's emission guide. With a small radius splatting agrees with the reference; with a radius that is a good
part of the room the kernel overlaps the walls, where photons on the walls are rejected by the normal test
and the disc's area beyond the surface holds none, so the estimate is low near every edge: the boundary bias,
which shrinks with the radius. The boundary correction (kernel_coverage.h, on by default) divides each view
sample's estimate by the part of its kernel that lies on a like-facing surface, which removes that bias.
Deterministic per seed; about 3 s on 2 shared cores."""
import numpy as np
import pytest

import photonsplat as ps
from scenes import quad


def skylit_room(oren_nayar=False):
    """A closed 2 x 2 x 2 m room with a 1 x 1 m skylight in its roof and a sun high above; its walls Lambert, or
    Oren–Nayar (roughness 0.8) with `oren_nayar`."""
    scene = ps.Scene()
    if oren_nayar:
        scene.add_material(name="white", kind="closures",
                           closures=[dict(kind="diffuse", color=(0.7, 0.7, 0.7), roughness=0.8)])
    else:
        scene.add_material(name="white", color=(0.7, 0.7, 0.7))
    h, top = 0.5, 2.0
    walls = [((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)),
             ((-1, -1, 0), (-1, 1, 0), (-1, 1, top), (-1, -1, top)),
             ((1, -1, 0), (1, -1, top), (1, 1, top), (1, 1, 0)),
             ((-1, 1, 0), (1, 1, 0), (1, 1, top), (-1, 1, top)),
             ((-1, -1, 0), (-1, -1, top), (1, -1, top), (1, -1, 0)),
             ((-1, -1, top), (1, -1, top), (1, -h, top), (-1, -h, top)),      # the roof around the skylight
             ((-1, h, top), (1, h, top), (1, 1, top), (-1, 1, top)),
             ((-1, -h, top), (-h, -h, top), (-h, h, top), (-1, h, top)),
             ((h, -h, top), (1, -h, top), (1, h, top), (h, h, top))]
    for i, corners in enumerate(walls):
        v, t = quad(*corners)
        scene.add_mesh(name=f"wall{i}", vertices=v, triangles=t)
    scene.add_sun_light(name="sun", direction=(0.15, 0.1, -1.0), irradiance=(5.0, 5.0, 5.0), angle=0.02)
    return scene


@pytest.fixture(scope="module")
def room():
    scene = skylit_room()
    camera = ps.look_at_camera(eye=(0.0, -0.9, 1.0), target=(0.2, 1.0, 0.6), width=24, height=24)
    # Direct light and one bounce, as splatting's max_bounces = 1 (photons stored at their second hit).
    reference, _ = ps.render_reference(scene, camera, samples=1024, max_bounces=1, seed=1)
    return scene, camera, float(np.mean(reference[..., :3]))


def splat(scene, camera, radius, correction=False):
    # Jittered passes at a fixed radius (alpha 1): a box filter like the reference's, and the bias of `radius`.
    # 16 passes, so that the sunlit patch's pixels (the direct light) have converged too: at 4 passes the image
    # mean was still 1 % low at every radius, and the figures below depended on where those passes fell.
    settings = ps.RenderSettings(photons=50_000, radius=radius, max_bounces=1, iterations=16, alpha=1.0,
                                 direct_samples=16, seed=1, boundary_correction=correction)
    image, _, passes = ps.render(scene, camera, settings, passes=True)
    return float(np.mean(image[..., :3])), float(np.mean(passes["indirect"]))


def test_small_radius_agrees_with_the_reference(room):
    scene, camera, reference = room
    mean, _ = splat(scene, camera, 0.02)
    assert mean / reference == pytest.approx(1.0, abs=0.03)   # measured 0.996


def test_without_the_correction_a_large_radius_loses_light_at_the_walls(room):
    scene, camera, reference = room
    mean_small, indirect_small = splat(scene, camera, 0.02)
    mean_large, indirect_large = splat(scene, camera, 0.3)
    # The same photons (same seed) at both radii: only the kernel differs.
    assert indirect_large < 0.96 * indirect_small                     # measured 0.933
    assert mean_large / reference < mean_small / reference - 0.03     # measured 0.936 against 0.996


# A kernel of radius 0.5 is a quarter of the room: besides the walls it crosses, it spreads the bright floor
# around the sunlit patch over darker parts, a blur the correction does not undo (it only rescales by the part of
# the kernel on the surface). Its image is 2.3 % low; this test once stated 0.994 for it, measured at 4 passes of
# independent pixel positions whose direct light had not converged.
@pytest.mark.parametrize("radius, tolerance", [(0.3, 0.015), (0.5, 0.03)])
def test_the_boundary_correction_keeps_a_large_radius_s_light(room, radius, tolerance):
    scene, camera, reference = room
    _, indirect_small = splat(scene, camera, 0.02, correction=True)
    mean_large, indirect_large = splat(scene, camera, radius, correction=True)
    # Measured: indirect 0.998 (0.3) and 0.980 (0.5) of the small radius's; without the correction 0.933, 0.849.
    assert indirect_large == pytest.approx(indirect_small, rel=0.025)
    # Measured 0.994, 0.977 (uncorrected 0.936, 0.861).
    assert mean_large / reference == pytest.approx(1.0, abs=tolerance)


def test_the_boundary_correction_takes_in_diffuse_like_lobes():
    """An Oren–Nayar wall's view samples carry a lobe (their BRDF depends on the directions), and glossy samples
    keep their estimate uncorrected (kernel_coverage.cpp); a diffuse-like lobe's light changes over the kernel as
    Lambert's does, so it takes the correction too (issue 18: rooms of Oren–Nayar or Principled walls were 0.35-0.5 %
    darker than Cycles at 64 x 64; differential seed 184's walls alone 0.9965, 1.0006 since)."""
    scene = skylit_room(oren_nayar=True)
    camera = ps.look_at_camera(eye=(0.0, -0.9, 1.0), target=(0.2, 1.0, 0.6), width=24, height=24)
    _, indirect_small = splat(scene, camera, 0.02, correction=True)
    _, indirect_large = splat(scene, camera, 0.3, correction=True)
    print(f"indirect at radius 0.3: {indirect_large / indirect_small:.3f} of radius 0.02's")
    # Measured 1.008; 0.944 before (a Lambert room without the correction: 0.933).
    assert indirect_large == pytest.approx(indirect_small, rel=0.025)
