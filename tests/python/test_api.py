"""The scripting API from plain /usr/bin/python3: build a scene from numpy arrays, render, read the stats."""
import math
import threading
import time

import numpy as np
import pytest

import photonsplat as ps
from scenes import cornell_box, cornell_camera, plane_scene


def test_package_exposes_the_api():
    for name in ("Scene", "Camera", "RenderSettings", "render", "write_image", "Cancelled", "look_at_camera"):
        assert hasattr(ps, name), name
    assert set(ps.METHODS) >= {"brute", "cluster"}


def test_render_returns_an_image_and_stats():
    image, stats = ps.render(cornell_box(), cornell_camera(), ps.RenderSettings(photons=20000))
    assert image.shape == (48, 48, 4) and image.dtype == np.float32
    assert np.isfinite(image).all()
    assert image[..., :3].mean() > 0.01, "the lit box must not render black"
    assert np.all(image[..., 3] == 1.0)
    for stage in ("view_samples", "direct_light", "photon_trace", "hierarchy_build", "splat", "total"):
        assert stats["seconds"][stage] >= 0.0, stage
    for counter in ("photon_sample_tests", "contributing_pairs", "photons_emitted"):
        assert stats["counters"][counter] > 0, counter
    assert stats["bytes"]["hierarchy"] > 0 and stats["bytes"]["photon_map"] > 0
    assert stats["values"]["radius"] > 0


def test_stages_report_their_rays_beside_embrees_floor():
    scene, camera = cornell_box(), cornell_camera()
    _, stats = ps.render(scene, camera, ps.RenderSettings(photons=20000, direct_samples=4))
    rays = stats["counters"]
    pixels = camera.width * camera.height
    # Every pixel's camera ray at least; four shadow rays per view sample towards the one light, less those the
    # light's side turns away; eight coverage probes per probed sample; a ray per photon segment.
    assert rays["rays.view_samples"] >= pixels
    assert pixels < rays["rays.direct_light"] <= 4 * stats["counters"]["view_samples"] * 2
    assert rays["rays.kernel_coverage"] >= 8 * pixels / 2
    assert rays["rays.photon_trace"] >= 20000
    assert rays["rays.total"] >= sum(rays[f"rays.{s}"] for s in ("view_samples", "direct_light", "photon_trace"))
    floor = ps.ray_floor(scene, camera)
    assert floor["rays"] == pixels and 0 < floor["hits"] <= pixels
    assert floor["seconds"] > 0 and floor["rays_per_second"] > 0
    with pytest.raises(TypeError):
        ps.ray_floor(scene, None)


def test_passes_add_up_to_the_image():
    image, _, passes = ps.render(cornell_box(), cornell_camera(16, 16), ps.RenderSettings(photons=5000), passes=True)
    total = passes["emission"] + passes["direct"] + passes["indirect"]
    np.testing.assert_allclose(image[..., :3], total, rtol=1e-6, atol=1e-7)
    assert passes["indirect"].sum() > 0


def test_brute_and_cluster_agree_through_python():
    scene, camera = cornell_box(), cornell_camera(32, 32)
    a, sa = ps.render(scene, camera, ps.RenderSettings(photons=10000, method="brute", seed=3))
    b, sb = ps.render(scene, camera, ps.RenderSettings(photons=10000, method="cluster", seed=3))
    np.testing.assert_allclose(a, b, rtol=1e-4, atol=1e-7)
    assert sa["counters"]["contributing_pairs"] == sb["counters"]["contributing_pairs"]


def test_same_seed_same_image_other_seed_other_image():
    scene, camera = cornell_box(), cornell_camera(24, 24)
    a, _ = ps.render(scene, camera, ps.RenderSettings(photons=5000, seed=1, threads=1))
    b, _ = ps.render(scene, camera, ps.RenderSettings(photons=5000, seed=1, threads=2))
    c, _ = ps.render(scene, camera, ps.RenderSettings(photons=5000, seed=2))
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_point_light_over_plane_matches_the_cycles_convention():
    # Blender point light of P watts at height d over albedo ρ: radiance ρ·P/(4π²d²) right below it.
    scene = plane_scene(albedo=0.8, light_height=2.0, power=1000.0)
    camera = ps.look_at_camera(eye=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0), width=9, height=9, fov_y_degrees=2)
    image, _ = ps.render(scene, camera, ps.RenderSettings(photons=1000))
    expected = 0.8 * 1000 / (4 * math.pi ** 2 * 4.0)
    assert image[4, 4, 0] == pytest.approx(expected, rel=0.01)


def test_progress_callback_is_called_and_can_cancel():
    calls = []

    def progress(stage, fraction):
        calls.append((stage, fraction))
        return True  # cancel at the first report

    start = time.monotonic()
    with pytest.raises(ps.Cancelled):
        ps.render(cornell_box(), cornell_camera(256, 256),
                  ps.RenderSettings(photons=20_000_000, method="brute"), progress=progress)
    assert time.monotonic() - start < 3.0
    assert calls and isinstance(calls[0][0], str) and 0.0 <= calls[0][1] <= 1.0


def test_exception_in_progress_callback_stops_the_render_and_propagates():
    def progress(stage, fraction):
        raise KeyError("from the callback")

    with pytest.raises(KeyError):
        ps.render(cornell_box(), cornell_camera(256, 256),
                  ps.RenderSettings(photons=20_000_000, method="brute"), progress=progress)


def test_render_releases_the_gil():
    ticks = []
    stop = threading.Event()

    def ticker():
        while not stop.is_set():
            ticks.append(time.monotonic())
            time.sleep(0.01)

    t = threading.Thread(target=ticker)
    t.start()
    try:
        ps.render(cornell_box(), cornell_camera(128, 128), ps.RenderSettings(photons=200000))
    finally:
        stop.set()
        t.join()
    assert len(ticks) > 10, "another Python thread must run while the core renders"


def test_write_image(tmp_path):
    assert ps.IMAGE_FILES is True       # the build against Debian's libraries has OpenImageIO (not the extension's)
    image, _ = ps.render(cornell_box(), cornell_camera(16, 16), ps.RenderSettings(photons=2000))
    for name in ("out.exr", "out.png"):
        ps.write_image(str(tmp_path / name), image)
        assert (tmp_path / name).stat().st_size > 0
    with pytest.raises(ValueError, match="image"):
        ps.write_image(str(tmp_path / "bad.png"), np.zeros((4, 4), np.float32))
    with pytest.raises(RuntimeError):
        ps.write_image(str(tmp_path / "no_such_dir" / "x.png"), image)


def test_progress_moves_within_a_long_splat_and_never_goes_back():
    reports = []
    ps.render(cornell_box(), cornell_camera(96, 96), ps.RenderSettings(photons=100_000, method="brute"),
              progress=lambda stage, fraction: reports.append((stage, fraction)))
    fractions = [f for _, f in reports]
    assert fractions == sorted(fractions), "progress went backwards"
    inside_splat = {round(f, 3) for s, f in reports if s.startswith("splat") and 0.45 < f < 0.98}
    assert len(inside_splat) >= 2, f"the bar must move during the splat, got {reports}"
