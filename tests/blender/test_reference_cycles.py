"""The reference renderer against Cycles on the diffuse Cornell box: mean linear radiance within 2 %, SSIM >= 0.98
on the display luma.

Both are converged enough for that at 32 x 32 pixels with 1024 samples per pixel each (with fewer samples the
noise of the two alone lowers the SSIM below the bound). Cycles runs with what makes it an
unbiased box-filtered estimate comparable to ours: no denoising (Debian's Cycles has no OpenImageDenoise), no
adaptive sampling, no clamping, light sampling threshold 0, BOX pixel filter of width 1, and 16 bounces, the
reference's default.
"""

import time

import bpy
import numpy as np

import photonsplat
from blender_helpers import render_pixels, use_cycles

SIZE = 32
SAMPLES = 1024
BOUNCES = 16


def render_cycles(scene, path):
    use_cycles(scene, SIZE, BOUNCES, samples=SAMPLES)
    cycles = scene.cycles
    cycles.light_sampling_threshold = 0.0
    cycles.pixel_filter_type = 'BOX'
    cycles.filter_width = 1.0
    return np.flipud(render_pixels(path))         # Blender's rows are bottom-up; the core's top-down


def test_reference_matches_cycles_on_the_diffuse_cornell_box(diffuse_scene, tmp_path, core):
    started = time.perf_counter()
    cycles = render_cycles(diffuse_scene, tmp_path / "cycles.exr")
    cycles_seconds = time.perf_counter() - started
    started = time.perf_counter()
    ours, stats = photonsplat.reference.render_reference(bpy.context.evaluated_depsgraph_get(), samples=SAMPLES,
                                                         max_bounces=BOUNCES)
    ours_seconds = time.perf_counter() - started
    assert ours.shape == (SIZE, SIZE, 4) and stats["values"]["samples"] == SAMPLES
    assert stats["warnings"] == []
    ratio = ours[..., :3].mean() / cycles[..., :3].mean()
    per_channel = ours[..., :3].reshape(-1, 3).mean(axis=0) / cycles[..., :3].reshape(-1, 3).mean(axis=0)
    ssim, psnr = photonsplat.ssim(ours, cycles), photonsplat.psnr(ours, cycles)
    print(f"\nreference vs Cycles, {SIZE}x{SIZE}, {SAMPLES} spp each: Cycles {cycles_seconds:.1f} s, reference "
          f"{ours_seconds:.1f} s; mean ratio {ratio:.4f} (per channel {np.round(per_channel, 4)}), SSIM {ssim:.4f}, "
          f"PSNR {psnr:.1f} dB")
    assert abs(ratio - 1.0) < 0.02
    assert np.all(np.abs(per_channel - 1.0) < 0.02)
    assert ssim >= 0.98


def test_reference_helper_reports_export_problems(empty_scene, core):
    """No camera: the exporter's error, not a crash or a black image."""
    import pytest
    from photonsplat import export
    with pytest.raises(export.ExportError):
        photonsplat.reference.render_reference(bpy.context.evaluated_depsgraph_get(), samples=1)
