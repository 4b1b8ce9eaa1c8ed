"""The glint: a smooth glass sphere under a small sphere light (blend_scenes/glints_point.blend) shows the light
as a bright highlight where it mirrors it, as Cycles does.

The light is a 100 W point light of radius 5 cm, hidden from camera rays; the glass sphere (IOR 1.5) reflects it
at the point whose normal halves the directions to the camera and to the light (computed here from the
geometry, not hard-coded). At 128 x 128 that highlight covers about a quarter of a pixel, so the pixels holding
it average the light's radiance (about 1000 W/(sr·m²)) times Fresnel (about 0.04) over the part they cover:
the 3 x 3 pixels around the mirror point sum to 9.8 in Cycles (1024 samples; 12.0 in the reference renderer,
both noisy: few samples land on so small a spot), against 0.02 a pixel for the glass around it. The test asks
for a quarter of Cycles' sum, which a renderer that never shows lights in smooth reflections cannot reach (the
engine before the closures work: 0.17). A camera ray finds the spot with a chance of about a fifth per
iteration (at the glass, Photon Splat follows both the reflected and the refracted ray, docs/architecture.md),
hence 128 jittered iterations, which put the expected sum about 4.5 standard deviations above the bound (few
photons: only the camera rays matter here). A path tracer choosing one branch at random finds it with a chance of
F x a fifth per sample: the reference renderer at 64 samples misses it for two seeds of three.
"""

import time

import bpy
import numpy as np

from blender_helpers import open_scene, pixel_of, render_pixels, use_photonsplat

SIZE = 128
CYCLES_GLINT = 9.8           # Cycles' sum over the 3 x 3 pixels around the glint (tools/closure_gallery.py --glints)


def mirror_point(center, radius, eye, light):
    """The point of the sphere where a ray from `eye` is mirrored to `light` (the one facing both)."""
    # Normals over the hemisphere facing the eye; pick the one whose reflection of the view ray hits the light.
    theta, phi = np.meshgrid(np.linspace(0.0, np.pi, 721), np.linspace(-np.pi, np.pi, 1441), indexing="ij")
    normals = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    points = center + radius * normals
    to_eye = eye - points
    to_eye /= np.linalg.norm(to_eye, axis=-1, keepdims=True)
    to_light = light - points
    to_light /= np.linalg.norm(to_light, axis=-1, keepdims=True)
    half = to_eye + to_light
    half /= np.linalg.norm(half, axis=-1, keepdims=True)
    alignment = np.einsum("...i,...i->...", half, normals)
    alignment[np.einsum("...i,...i->...", to_eye, normals) <= 0.0] = -1.0
    return points.reshape(-1, 3)[np.argmax(alignment)]


def test_glass_sphere_shows_the_small_sphere_light_as_a_glint(tmp_path, core):
    started = time.perf_counter()
    scene = open_scene("glints_point")
    use_photonsplat(scene, SIZE, 10000, iterations=128)
    glass, light, camera = bpy.data.objects["GlassSphere"], bpy.data.objects["Light"], scene.camera
    center = np.array(glass.matrix_world.translation)
    point = mirror_point(center, glass.dimensions.x / 2.0, np.array(camera.matrix_world.translation),
                         np.array(light.matrix_world.translation))
    row, column = pixel_of(scene, camera, point)                 # rows from the bottom, as render_pixels gives
    pixels = render_pixels(tmp_path / "glints.exr")
    luminance = pixels[..., :3].mean(axis=-1)
    around = luminance[max(row - 1, 0):row + 2, max(column - 1, 0):column + 2]
    glass_row, glass_column = pixel_of(scene, camera, center)
    seconds = time.perf_counter() - started
    print(f"\nglint at pixel (row {row} from the bottom, column {column}): sum of the 3x3 {around.sum():.2f} "
          f"(Cycles {CYCLES_GLINT}); glass at its centre {luminance[glass_row, glass_column]:.2f}; {seconds:.1f} s")
    assert np.isfinite(pixels).all()
    assert around.sum() >= 0.25 * CYCLES_GLINT
