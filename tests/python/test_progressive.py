"""Progressive, consistent splatting: convergence to an analytic answer at the Knaus–Zwicker rate, exact methods
agreeing pass after pass, directional falling back to exact, time limits, cancel, determinism, bad settings.

The analytic scene is the inside of a closed sphere whose wall emits Le and reflects with albedo a: the radiance
is then Le/(1 − a) everywhere, whatever the shape (L = Le + a·E/π with E = π·L solves the rendering equation for
a closed enclosure). On a sphere the area within chord distance r of a point is exactly π r² (Archimedes), so the
density estimate has no kernel bias there and the error is the noise the passes average away. About 15 s in all.
"""
import math

import numpy as np
import pytest

import photonsplat as ps
from scenes import cornell_box, cornell_camera, quad, uv_sphere

LE, ALBEDO = 1.0, 0.5
EXACT_RADIANCE = LE / (1.0 - ALBEDO)


def glowing_sphere():
    scene = ps.Scene()
    wall = scene.add_material(name="wall", kind="diffuse", color=(ALBEDO,) * 3, emission=(LE,) * 3)
    v, t, n = uv_sphere(1.0, rings=24, segments=48)
    scene.add_mesh(name="sphere", vertices=v, triangles=t, material_ids=np.full(len(t), wall, np.int32))
    return scene


def sphere_camera(size=32):
    return ps.look_at_camera(eye=(0, 0, 0.2), target=(0, 1, 0), width=size, height=size, fov_y_degrees=60)


def sphere_settings(**kwargs):
    base = dict(photons=4000, radius=0.3, max_bounces=64, seed=5, direct_samples=1, method="cluster_cone")
    base.update(kwargs)
    return ps.RenderSettings(**base)


def test_error_falls_at_the_knaus_zwicker_rate():
    progressive = ps.Progressive(glowing_sphere(), sphere_camera(), sphere_settings(iterations=0, time_limit=1e6))
    passes, mse = [], []
    for n in range(1, 129):
        progressive.step()
        if n & (n - 1) == 0 or n in (3, 6, 12, 24, 48, 96):
            image = progressive.image()[..., :3].astype(np.float64)
            passes.append(n)
            mse.append(float(np.mean((image - EXACT_RADIANCE) ** 2)))
    slope = np.polyfit(np.log(passes), np.log(mse), 1)[0]
    print(f"\nMSE against Le/(1-a) by passes: {dict(zip(passes, (f'{m:.2e}' for m in mse)))}; log-log slope {slope:.3f}")
    assert -0.9 <= slope <= -0.4, slope
    assert mse[-1] < mse[0] / 8
    assert abs(progressive.image()[..., :3].mean() / EXACT_RADIANCE - 1.0) < 0.01
    assert progressive.radius < 0.3 * 128 ** (-1 / 6) * 1.2


@pytest.fixture(scope="module")
def cornell():
    return cornell_box()


def test_one_pass_is_the_one_shot_render_bit_for_bit(cornell):
    camera = cornell_camera(40, 32)
    settings = ps.RenderSettings(photons=5000, seed=2)
    one_shot, stats = ps.render(cornell, camera, settings)
    assert stats["values"]["iterations"] == 1
    progressive = ps.Progressive(cornell, camera, settings)
    assert progressive.iterations_done == 0 and not progressive.image().any()
    progressive.step()
    assert np.array_equal(progressive.image(), one_shot)
    # A time budget smaller than one pass still renders that one pass, and nothing else: with the boundary
    # correction (the default) a progressive render starts at the one-pass radius.
    timed, stats = ps.render(cornell, camera, ps.RenderSettings(photons=5000, seed=2, iterations=0, time_limit=1e-6))
    assert stats["values"]["iterations"] == 1
    assert np.array_equal(timed, one_shot)
    # Without the correction it starts at the automatic radius, which weighs the boundary bias.
    _, stats = ps.render(cornell, camera, ps.RenderSettings(photons=5000, seed=2, iterations=0, time_limit=1e-6,
                                                            boundary_correction=False))
    assert stats["values"]["radius"] == pytest.approx(ps.automatic_radius(cornell, camera, 5000), rel=1e-6)


def test_exact_methods_converge_to_the_same_answer():
    scene, camera = glowing_sphere(), sphere_camera(24)
    images = {}
    for method in ("brute", "tiled", "cluster", "cluster_cone", "gather"):
        image, stats = ps.render(scene, camera, sphere_settings(method=method, iterations=6))
        assert stats["values"]["iterations"] == 6
        images[method] = image
    for method, image in images.items():
        np.testing.assert_allclose(image, images["brute"], rtol=1e-4, atol=1e-6, err_msg=method)
    assert abs(images["brute"][..., :3].mean() / EXACT_RADIANCE - 1.0) < 0.03


def test_directional_falls_back_to_exact_as_the_radius_shrinks(cornell):
    camera = cornell_camera(32, 32)
    settings = ps.RenderSettings(photons=3000, seed=4, radius=0.25, method="directional", directional_level=1,
                                 iterations=0, time_limit=1e6, alpha=0.3)
    progressive = ps.Progressive(cornell, camera, settings)
    while progressive.stats()["values"].get("exact_iterations", 0) < 2 and progressive.iterations_done < 40:
        progressive.step()
    values = progressive.stats()["values"]
    first = values["exact_from_iteration"]
    print(f"\ndirectional: exact from pass {first:.0f}, radius then {progressive.radius:.4f}")
    assert first > 1, "the first pass is the directional one-shot image"
    assert values["exact_iterations"] == progressive.iterations_done - first + 1  # and exact from then on


def test_time_limit_and_cancel_stop_it(cornell):
    camera = cornell_camera(32, 32)
    settings = ps.RenderSettings(photons=3000, seed=1, iterations=0, time_limit=0.4)
    image, stats = ps.render(cornell, camera, settings)
    values = stats["values"]
    per_pass = values["elapsed"] / values["iterations"]
    assert values["iterations"] >= 1
    # No pass is started once the budget is used up: the last one began before the limit.
    assert values["iterations"] == 1 or values["elapsed"] - per_pass < settings.time_limit * 1.5

    stages = []

    def cancel_in_iteration_three(stage, fraction):  # progress is polled ~10x a second: cancel from iteration 3 on
        stages.append(stage)
        return stage.startswith("iteration ") and int(stage.split()[1].split("/")[0]) >= 3

    settings = ps.RenderSettings(photons=3000, seed=1, iterations=1000)
    image, stats = ps.render(cornell, camera, settings, progress=cancel_in_iteration_three)
    assert stats["values"]["cancelled"] == 1 and stats["values"]["iterations"] >= 2
    assert np.isfinite(image).all() and image[..., :3].max() > 0
    # Cancelled inside the first pass (5M photons: the first poll, after 0.1 s, finds it tracing): nothing to show.
    settings = ps.RenderSettings(photons=5_000_000, seed=1, iterations=1000)
    with pytest.raises(ps.Cancelled):
        ps.render(cornell, camera, settings, progress=lambda stage, fraction: True)
    progressive = ps.Progressive(cornell, camera, settings)
    with pytest.raises(ps.Cancelled):
        progressive.step(progress=lambda stage, fraction: True)
    assert progressive.iterations_done == 0 and not progressive.finished and not progressive.image().any()


def test_a_pixel_partly_covered_converges_as_cycles_samples_it():
    """An emitting rectangle over a black world seen from above (orthographic), its edges across pixels: each
    pixel's value is the part of it the rectangle covers. Passes after the first fall in the pixel along its own
    low-discrepancy sequence, as Cycles places a pixel's samples, so 65 passes find that part within 0.02 (the
    first pass, through the centre, is the most of it). At independent random positions the error was 0.10-0.11
    (issue 18, seed 85 of the random scenes: a small light seen in a mirror torus, one block of the image 1.5, 1.04
    and 0.67 of Cycles at 1, 4 and 16 s)."""
    scene = ps.Scene()
    lamp = scene.add_material(name="lamp", color=(0.0, 0.0, 0.0), emission=(1.0, 1.0, 1.0))
    x0, x1, y0, y1 = -0.31, 0.43, -0.27, 0.52
    v, t = quad((x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0))
    scene.add_mesh(name="lamp", vertices=v, triangles=t, material_ids=np.full(2, lamp, np.int32))
    size, near, far = 16, 0.1, 100.0
    to_world = np.identity(4)
    to_world[2, 3] = 5.0
    projection = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, -2 / (far - near), -(far + near) / (far - near)],
                           [0, 0, 0, 1]])
    camera = ps.Camera(to_world=to_world, projection=projection, width=size, height=size)  # sees [-1, 1]^2
    edges = np.linspace(-1.0, 1.0, size + 1)
    cover_x = np.clip(np.minimum(edges[1:], x1) - np.maximum(edges[:-1], x0), 0, None) * size / 2
    cover_y = np.clip(np.minimum(edges[1:], y1) - np.maximum(edges[:-1], y0), 0, None) * size / 2
    covered = np.outer(cover_y[::-1], cover_x)          # row 0 is the top of the image: +y
    for seed in (1, 2):
        progressive = ps.Progressive(scene, camera, ps.RenderSettings(photons=1000, iterations=65, seed=seed,
                                                                      direct_samples=1))
        for _ in range(65):
            progressive.step()
        error = np.abs(np.asarray(progressive.image())[..., 0] - covered)
        print(f"\nseed {seed}: largest error {error.max():.4f} over {(covered % 1 > 0).sum()} partly covered pixels")
        assert error.max() < 0.03


def test_bit_identical_for_any_thread_count(cornell):
    camera = cornell_camera(40, 40)
    images = [ps.render(cornell, camera, ps.RenderSettings(photons=4000, seed=9, iterations=4, threads=t))[0]
              for t in (1, 2, 8)]
    assert np.array_equal(images[0], images[1]) and np.array_equal(images[0], images[2])


@pytest.mark.parametrize("field, value", [("iterations", -1), ("time_limit", -1.0), ("time_limit", math.inf),
                                          ("alpha", 0.0), ("alpha", 1.5), ("aimed_photons", -0.5),
                                          ("aimed_photons", math.nan)])
def test_bad_progressive_settings_name_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        ps.RenderSettings(**{field: value})
    with pytest.raises(ValueError, match="iterations"):
        ps.RenderSettings(iterations=0)
