"""Differential testing against Cycles (issue 18) on a fixed sample of the generated scenes, at 64 x 64.

tools/differential.py renders the whole set (docs/results/differential.md); this sample keeps what it found fixed.
Each scene is drawn by blend_scenes/make_random_scenes.py in the run (a fresh clone has no cache), rendered by Cycles
(the oracle as tools/differential.py runs it: 16 bounces, no denoising, at scale 1 around the origin) and by Photon
Splat progressive for a fixed number of iterations with 16 bounces, and the image means are compared. The
tolerances hold Cycles' noise at these samples and Photon Splat's at these iterations; each scene says what it
guards. Under Debian's Blender 3.4 only: the sample was measured against Cycles 3.4, and it costs about a minute
and a half (the clearcoat tests half a minute of it).
"""

import json
import subprocess
import sys

import bpy
import numpy as np
import pytest

from blender_helpers import REPO

sys.path.insert(0, str(REPO / "tools"))
sys.path.insert(0, str(REPO / "blend_scenes"))

pytestmark = pytest.mark.skipif(bpy.app.version >= (4, 0, 0), reason="measured against Cycles 3.4 (Debian's Blender)")

CYCLES_SAMPLES = 256
ITERATIONS = 24
# Scenes whose lit blocks hold a sliver of a light seen in a mirror, narrower than a pixel (seed 152: two pixels
# of a block with 1.5 % of their area on the light, all of that block's light; seed 156 likewise at an ellipse
# light's edge). Whether 24 passes land on it is chance, with random positions as with the pixels' stratified
# sequence (152's block was 0 or 1.5 of Cycles' by the seed); 96 passes place 1.26 of its 1.21.
ITERATIONS_OF = {152: 96, 156: 96}

# seed: (what the scene guards, tolerance on |mean ratio - 1|, bounds on the ratio of 8 x 8 blocks holding a tenth of
# the mean or more). The first ten are regression scenes of biases the full set found; the others were within 2 %
# of Cycles there and cover rooms and open scenes, scales 0.01 and 100, and most material kinds (no sharp Glass BSDF:
# its caustics are where Cycles is least converged).
SAMPLE = {
    39: ("rough glass seen from outside: a photon's power takes 1/eta^2 where it refracts (its glass was 2.7x "
         "Cycles)",
         0.03, (0.5, 2.2)),
    9: ("a clearcoat floor's highlight of a small point light: the clearcoat is sampled as Cycles samples it "
        "(that block was 0.71 of Cycles)", 0.03, (0.85, 1.3)),
    152: ("a rough glass wall seen from its back face reflects an area light by a mirror floor: a photon's power "
          "follows the refractions it made, not the face it lands on (the highlight was 1/ior^2 of Cycles, the "
          "image 0.875; 0.986 at 16 s, 0.989 at its 96 passes, where the highlight's photons are still spread "
          "wide, its blocks 0.75 to 1.33)", 0.05, (0.4, 3.5)),
    156: ("an ellipse light in view is seen as an ellipse, not as its rectangle (the image was 4/pi of Cycles, "
          "1.256)", 0.03, (0.45, 1.6)),
    150: ("a closed cylinder of translucent mixed with diffuse in a room under two soft point lights: the boundary "
          "correction stops at a surface that transmits and reflects (its outside was 2-2.6x Cycles, the image "
          "1.20), and photons of a light's disc facing its receiver take d^2/(d^2 + R^2) at their first hit, as its "
          "direct light does (the room alone was 5 % bright)", 0.03, (0.8, 1.25)),
    138: ("a floor's caustic behind a clearcoated Principled glass cylinder, under a spot: photons aimed at the "
          "glass go on through it after storing a caustic photon on its inside (the image was 0.90 of Cycles; 1.015 "
          "at 16 s, 1.019 at these iterations, where the caustic's blocks are still 0.57 to 1.75)", 0.05, (0.4, 2.5)),
    55: ("a rough Multiscatter GGX Glossy floor (roughness 0.76) under a sun and an area light: the add-on passes "
         "the Glossy's colour on as the tint of the lobe's extra bounces (without it the lobe scattered once only, "
         "the image 0.84 of Cycles), and direct light takes Cycles' evaluation towards a light sample, which tints "
         "each extra bounce twice (1.14 with the walk's tint)", 0.03, (0.77, 1.3)),
    14: ("a Glossy floor of Multiscatter GGX at roughness 0.02 under a point light: Cycles 3.x's clamped D makes "
         "its BSDF rays keep almost none of the lights they meet (a mirror to the export, which once showed the "
         "lights' reflections and caustics in full: the image 2.2 of Cycles)", 0.03, (0.77, 1.3)),
    22: ("a rough Glass of Multiscatter GGX (a cylinder, roughness 0.45): Cycles 3.x's random walk on its "
         "microsurface, each microfacet reflecting by its own Fresnel, where the export once split single-scatter "
         "GGX by the shading normal's (the image 0.940 of Cycles at these iterations; 0.993 with the walk's, 0.976 "
         "with Cycles' own value of its light samples blended in as Cycles blends it, where the lower half of the "
         "cylinder, seen through it, is darker: Cycles runs a path's walks on numbers shifted from one vertex to "
         "the next, which photons cannot share; the reference does, test_the_reference_runs_multiscatter_glass_"
         "on_cycles_numbers)",
         0.03, (0.77, 1.3)),
    30: ("a Multiscatter GGX Glass ball (roughness 0.35) under three area lights: Cycles 3.x values its light samples "
         "by an evaluation walk of its own, which its sampling walk does not agree with, and weighs the two by the "
         "power heuristic with the density the glass reports (the ball's top was 1.4 of Cycles with the walk's value "
         "alone, the image 1.018)", 0.03, (0.77, 1.3)),
    8: ("a room at scale 0.01: metal, transparency", 0.03, (0.77, 1.3)),
    12: ("an open scene under a spot: Principled dielectric and glass", 0.03, (0.77, 1.3)),
    18: ("an open scene under an area light: emission, Principled glass", 0.03, (0.77, 1.3)),
    44: ("a room at scale 100: rough glass, translucency, transparency", 0.03, (0.77, 1.3)),
    47: ("a room with an emitting wall under a spot and an ellipse", 0.03, (0.77, 1.3)),
    50: ("an open scene: glossy, Mix, Principled metal and glass", 0.03, (0.77, 1.3)),
}
# The scenes whose caustic energy is compared: the engine's Caustics pass against Cycles' Caustics on minus off.
# seed: (what the scene guards, Cycles' samples, Photon Splat's iterations). 108's excess is a third of its image
# and smooth: 64 samples and 8 passes pin it (1.017; the test's share of the suite matters).
CAUSTIC_SEEDS = {
    30: ("Principled glass, and Multiscatter GGX glass whose light samples Cycles values by its own evaluation (the "
         "pass was 1.10 of Cycles' excess with the walk's value)", CYCLES_SAMPLES, ITERATIONS),
    3: ("a Multiscatter GGX Glass ball (roughness 0.12) under a spot, an area light and a sun: a photon straight from "
        "its light takes Cycles' blend of its light-sample evaluation and its walk (the pass was 1.21 of Cycles' "
        "excess)", CYCLES_SAMPLES, ITERATIONS),
    108: ("a room of red Principled walls (roughness 0.84), a glossy cylinder and an emitting Suzanne: Cycles labels "
          "each scatter by the closure it picked, one weight per closure, and its toggles drop the glossy part after "
          "a diffuse label, per channel (the pass was 1.51 of Cycles' excess with every photon that met a glossy "
          "part in it, 1.18 with Cycles' labels in one luminance share)", 64, 8),
}
CAUSTIC_TOLERANCE = 0.10
# The scene whose floor carries a clearcoat under a spot light (test_a_clearcoat_follows_cycles_light_pick).
CLEARCOAT_SEED = 153
# The room whose point light of radius 0.86 hangs 0.38 under its ceiling (test_a_soft_light_lights_what_lies_within_
# its_radius_as_cycles_disc).
SOFT_LIGHT_SEED = 15
# The room whose Principled wall (metallic 0.67) is seen through a translucent ball (test_the_caustics_pass_takes_
# what_a_surface_seen_through_translucency_reflects_by_its_glossy_parts).
THROUGH_TRANSLUCENCY_SEED = 132


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    """The sample's .blend files, drawn by the generator in a Blender of its own (it starts from factory settings)."""
    folder = tmp_path_factory.mktemp("random_scenes")
    seeds = ",".join(str(s) for s in set(SAMPLE) | set(CAUSTIC_SEEDS) |
                     {CLEARCOAT_SEED, SOFT_LIGHT_SEED, THROUGH_TRANSLUCENCY_SEED})
    subprocess.run([bpy.app.binary_path, "-b", "--factory-startup", "-noaudio", "--python",
                    str(REPO / "blend_scenes" / "make_random_scenes.py"), "--", str(folder), "--seeds", seeds,
                    "--size", "64x64"], check=True, stdout=subprocess.DEVNULL)
    return folder


def cycles_mean(blend, caustics=True, samples=CYCLES_SAMPLES, edit=None):
    """Cycles' image of the scene (`edit`, if given, changes the opened scene first)."""
    import make_random_scenes
    from closure_gallery import render_exr, use_cycles_oracle
    bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    scene = bpy.context.scene
    make_random_scenes.canonical(scene, json.loads(scene["differential"]))
    if edit:
        edit()
    cycles = use_cycles_oracle(scene, samples, 1, 2)
    cycles.caustics_reflective = cycles.caustics_refractive = caustics
    return render_exr(scene, blend.with_suffix(".exr"))[..., :3]


def photonsplat_image(blend, core, iterations=ITERATIONS, caustics_pass=False, edit=None):
    """The image, and the Caustics pass where asked for (it costs two more splats of most photons); `edit` as in
    cycles_mean."""
    from photonsplat import export
    bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    scene = bpy.context.scene
    if edit:
        edit()
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    settings = frame.settings
    settings.iterations, settings.max_bounces, settings.threads, settings.seed = iterations, 16, 2, 1
    settings.caustics_pass = caustics_pass
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    for _ in range(iterations):
        progressive.step()
    image = np.asarray(progressive.image())[..., :3]
    return (image, np.asarray(progressive.passes()["caustics"])) if caustics_pass else image


@pytest.mark.parametrize("seed", list(SAMPLE))
def test_generated_scene_matches_cycles(seed, scenes, core):
    from differential import block_means
    guards, tolerance, (low, high) = SAMPLE[seed]
    blend = scenes / f"random_{seed}.blend"
    cycles = cycles_mean(blend)
    ours = photonsplat_image(blend, core, ITERATIONS_OF.get(seed, ITERATIONS))
    ratio = ours.mean() / cycles.mean()
    print(f"\nseed {seed} ({guards}): mean ratio {ratio:.4f}")
    assert abs(ratio - 1.0) <= tolerance, guards
    # No part of the image far off: blocks of 8 x 8 pixels holding a tenth of the mean or more within the bounds.
    c, p = block_means(cycles).mean(-1), block_means(ours).mean(-1)
    lit = c >= 0.1 * c.mean()
    ratios = p[lit] / c[lit]
    print(f"blocks {ratios.min():.3f} to {ratios.max():.3f}")
    assert low < ratios.min() and ratios.max() < high, guards


@pytest.mark.parametrize("seed", list(CAUSTIC_SEEDS))
def test_caustics_pass_carries_what_cycles_caustic_toggles_remove(seed, scenes, core):
    guards, samples, iterations = CAUSTIC_SEEDS[seed]
    blend = scenes / f"random_{seed}.blend"
    excess = cycles_mean(blend, True, samples).mean() - cycles_mean(blend, False, samples).mean()
    _, caustics = photonsplat_image(blend, core, iterations, caustics_pass=True)
    ratio = caustics.mean() / excess
    print(f"\nseed {seed} ({guards}): caustic energy ratio {ratio:.3f} (Cycles' excess {excess:.4f})")
    assert abs(ratio - 1.0) <= CAUSTIC_TOLERANCE, guards


def test_the_caustics_pass_takes_what_a_surface_seen_through_translucency_reflects_by_its_glossy_parts(scenes, core):
    """Cycles labels a translucent scatter diffuse, and its Caustics toggles then drop every part of the next surface
    but the diffuse-labelled ones: what a Principled wall's specular layer reflects towards a translucent ball in
    front of the camera is caustic light, its direct light included. Seed 132, its glass wall and glossy cube hidden:
    the ball's pixels (rows 40-63, columns 16-47) held 0.50 of Cycles' excess in the Caustics pass, the image 0.87,
    where only a surface without a diffuse part gave all its light to the pass; 0.998 and 0.993 at 40 passes against
    128 Cycles samples, 1.036 and 1.006 here (64 samples, 8 passes)."""
    blend = scenes / f"random_{THROUGH_TRANSLUCENCY_SEED}.blend"

    def hide_the_others():
        scene = bpy.context.scene
        for name in ('Object2_wall', 'Object3_cube'):
            scene.objects[name].hide_render = scene.objects[name].hide_viewport = True  # the export reads the viewport

    images = {}
    for caustics in (True, False):
        images[caustics] = cycles_mean(blend, caustics, 64, edit=hide_the_others)
    _, ours = photonsplat_image(blend, core, 8, caustics_pass=True, edit=hide_the_others)
    excess = images[True] - images[False]
    ball = (slice(40, 64), slice(16, 48))
    ball_ratio = ours[ball].mean() / excess[ball].mean()
    ratio = ours.mean() / excess.mean()
    print(f"\nseed {THROUGH_TRANSLUCENCY_SEED}: caustic energy ratio {ratio:.3f}, in the ball {ball_ratio:.3f}")
    assert abs(ball_ratio - 1.0) < 0.1
    assert abs(ratio - 1.0) < 0.05


def clearcoat_floor(scenes, core, metal=False, extra_lamp=False, world_only=False, world_strength=None):
    """Seed 153's floor alone, its Principled reduced to a clearcoat (over a grey metal with `metal`), under its spot
    (Light0) and world, with a 0.001 W lamp added 50 m away (`extra_lamp`), or under its world alone
    (`world_only`); `world_strength` replaces the world's. Returns the image means of Cycles (512 samples), the
    reference (256 passes) and Photon Splat (64 passes)."""
    from closure_gallery import render_exr, use_cycles_oracle
    from photonsplat import export
    bpy.ops.wm.open_mainfile(filepath=str(scenes / f"random_{CLEARCOAT_SEED}.blend"), load_ui=False)
    scene = bpy.context.scene
    keep = ('Floor',) if world_only else ('Floor', 'Light0')
    for ob in scene.objects:
        if ob.type in ('MESH', 'LIGHT') and ob.name not in keep:
            ob.hide_render = ob.hide_viewport = True  # the export reads the viewport's depsgraph
    floor = next(n for n in bpy.data.materials['Floor'].node_tree.nodes if n.bl_idname == 'ShaderNodeBsdfPrincipled')
    floor.inputs['Base Color'].default_value = (0.7, 0.7, 0.7, 1.0) if metal else (0.0, 0.0, 0.0, 1.0)
    floor.inputs['Metallic'].default_value = 1.0 if metal else 0.0
    floor.inputs['Specular'].default_value = 0.5613 if metal else 0.0
    if world_strength is not None:
        scene.world.node_tree.nodes['Background'].inputs['Strength'].default_value = world_strength
    if extra_lamp:
        lamp = bpy.data.lights.new('Extra', 'POINT')
        lamp.energy, lamp.shadow_soft_size = 0.001, 0.05
        ob = bpy.data.objects.new('Extra', lamp)
        ob.location = (30.0, 30.0, 30.0)
        scene.collection.objects.link(ob)
    use_cycles_oracle(scene, 512, 1, 2)
    cycles = render_exr(scene, scenes / f"clearcoat_{metal}_{extra_lamp}_{world_only}.exr")[..., :3]
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    reference = np.asarray(core.render_reference(frame.scene, frame.camera, samples=256, seed=1, threads=2,
                                                 max_bounces=16)[0])[..., :3]
    settings = frame.settings
    settings.iterations, settings.max_bounces, settings.threads, settings.seed = 64, 16, 2, 1
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    for _ in range(64):
        progressive.step()
    return cycles.mean(), reference.mean(), np.asarray(progressive.image())[..., :3].mean()


def test_a_clearcoat_follows_cycles_light_pick(scenes, core):
    """Cycles samples its clearcoat by GGX's visible normals but weighs those directions with GTR1's density, so
    what it converges to depends on its MIS weights, and they hold the probability of picking the light among all
    lights: a 0.001 W lamp added 50 m away takes about 3 % off a clearcoat's highlight of a spot. Seed 153's floor,
    clearcoat only, under its spot alone and with that lamp: the reference and the engine follow Cycles both ways
    (issue 18: 10 of the 13 scenes whose reference was off without a known cause held a clearcoat, all under
    several lights; before, both renderers gave the same image with and without the lamp)."""
    alone, with_lamp = clearcoat_floor(scenes, core), clearcoat_floor(scenes, core, extra_lamp=True)
    for name, k in (("Cycles", 0), ("reference", 1), ("Photon Splat", 2)):
        print(f"\n{name}: {alone[k]:.5f} alone, {with_lamp[k]:.5f} with the far lamp ({with_lamp[k] / alone[k]:.4f})")
    cycles_change = with_lamp[0] / alone[0]
    assert cycles_change < 0.985          # measured 0.971 at 2 x 1024 samples: the effect this test is about
    for k in (1, 2):
        assert alone[k] / alone[0] == pytest.approx(1.0, abs=0.01)
        assert with_lamp[k] / with_lamp[0] == pytest.approx(1.0, abs=0.01)


def test_a_soft_light_lights_what_lies_within_its_radius_as_cycles_disc(scenes, core):
    """Cycles 3.4 lights each receiver of a soft point light from the disc of its radius turned towards it, the
    receivers within the radius too, whose BSDF rays meet that disc (ray_disk_intersect). Seed 15's room under its
    point light of radius 0.86, 0.38 under the ceiling, its other light hidden: the reference refused BSDF rays from
    within the radius (0.972 of Cycles), and photons left the light's sphere, which the ceiling cuts, so that the
    ceiling within the radius got none (0.964; the whole scene 0.981). Direct light alone agreed (1.000)."""
    import make_random_scenes
    from closure_gallery import render_exr, use_cycles_oracle
    from photonsplat import export
    blend = scenes / f"random_{SOFT_LIGHT_SEED}.blend"
    bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    scene = bpy.context.scene
    make_random_scenes.canonical(scene, json.loads(scene["differential"]))
    other = bpy.data.objects["Light1"]
    other.hide_render = other.hide_viewport = True
    use_cycles_oracle(scene, CYCLES_SAMPLES, 1, 2)
    cycles = render_exr(scene, blend.with_suffix(".soft.exr"))[..., :3].mean()
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    reference = np.asarray(core.render_reference(frame.scene, frame.camera, samples=64, seed=1, threads=2,
                                                 max_bounces=16)[0])[..., :3].mean()
    settings = frame.settings
    settings.iterations, settings.max_bounces, settings.threads, settings.seed = ITERATIONS, 16, 2, 1
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    for _ in range(ITERATIONS):
        progressive.step()
    photonsplat = np.asarray(progressive.image())[..., :3].mean()
    print(f"\nreference {reference / cycles:.4f} of Cycles, Photon Splat {photonsplat / cycles:.4f}")
    assert reference / cycles == pytest.approx(1.0, abs=0.012)
    assert photonsplat / cycles == pytest.approx(1.0, abs=0.02)


@pytest.mark.parametrize("world_only", [True, False])
def test_a_clearcoat_over_metal_is_chosen_defensively_at_the_first_hit(scenes, core, world_only):
    """At the camera's first hit Cycles chooses each closure with at least 1/8 of their summed weights (defensive
    sampling), which changes what its clearcoat converges to: over a grey metal, whose weight is about 50 times the
    clearcoat's, the clearcoat is chosen about 8 times as often. Seed 153's floor as a clearcoat over metal, under
    a constant world alone (BSDF sampling only) and under its spot: the reference was 1.055 and 1.020 of Cycles
    before (issue 18: seed 24's room of clearcoated walls without its glass, 1.027)."""
    cycles, reference, photonsplat = clearcoat_floor(scenes, core, metal=True, world_only=world_only,
                                                     world_strength=1.0 if world_only else 0.0)
    print(f"\nCycles {cycles:.5f}, reference {reference / cycles:.4f} of it, Photon Splat {photonsplat / cycles:.4f}")
    assert reference / cycles == pytest.approx(1.0, abs=0.01)
    assert photonsplat / cycles == pytest.approx(1.0, abs=0.01)


def clearcoated_wall_room(core, clearcoat, samples, iterations):
    """A 4 m room of Principled walls (diffuse only: Specular 0, Roughness 0.5) under a point light of radius 0.1,
    at 48 x 48, one wall (the one the camera faces) with a Clearcoat of `clearcoat` at its default roughness (0.03).
    Returns the image means of Cycles (`samples`, one seed) and Photon Splat (`iterations` passes)."""
    from closure_gallery import render_exr, use_cycles_oracle
    from photonsplat import export
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x = scene.render.resolution_y = 48
    scene.render.resolution_percentage = 100
    bpy.ops.mesh.primitive_cube_add(size=4)
    room = bpy.context.object
    import bmesh
    mesh = bmesh.new()
    mesh.from_mesh(room.data)
    bmesh.ops.reverse_faces(mesh, faces=list(mesh.faces))  # facing in
    mesh.to_mesh(room.data)
    mesh.free()
    for coat in (0.0, clearcoat):
        material = bpy.data.materials.new(f"walls_{coat}")
        material.use_nodes = True
        principled = material.node_tree.nodes['Principled BSDF']
        principled.inputs['Base Color'].default_value = (0.6, 0.48, 0.3, 1.0)
        principled.inputs['Roughness'].default_value = 0.5
        principled.inputs['Specular'].default_value = 0.0
        principled.inputs['Clearcoat'].default_value = coat
        room.data.materials.append(material)
    for polygon in room.data.polygons:
        polygon.material_index = 1 if polygon.normal.y < -0.9 else 0
    lamp = bpy.data.lights.new('Lamp', 'POINT')
    lamp.energy, lamp.shadow_soft_size = 300.0, 0.1
    lamp_object = bpy.data.objects.new('Lamp', lamp)
    lamp_object.location = (-1.0, 0.5, 1.2)
    scene.collection.objects.link(lamp_object)
    camera = bpy.data.objects.new('Camera', bpy.data.cameras.new('Camera'))
    camera.location, camera.rotation_euler = (1.6, -1.6, 0.5), (1.45, 0.0, 0.6)
    scene.collection.objects.link(camera)
    scene.camera = camera
    scene.world = bpy.data.worlds.new('Black')
    scene.world.color = (0.0, 0.0, 0.0)
    use_cycles_oracle(scene, samples, 1, 2)
    cycles = render_exr(scene, REPO / "build" / "clearcoated_wall_room.exr")[..., :3].mean()
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    settings = frame.settings
    settings.iterations, settings.max_bounces, settings.threads, settings.seed = iterations, 16, 2, 1
    progressive = core.Progressive(frame.scene, frame.camera, settings)
    for _ in range(iterations):
        progressive.step()
    return cycles, np.asarray(progressive.image())[..., :3].mean()


def test_a_clearcoated_wall_reflects_the_room_as_cycles_finds_it(core):
    """Cycles samples a clearcoat by GGX's visible normals of its alpha (0.0009 at the default roughness) and weighs
    the draw by GTR1's density, so a sharp clearcoat reflects the room as a mirror with its whole Fresnel weight, and
    GTR1's reported density takes light from the other parts near the mirror direction (docs/closures.md). Photon
    Splat splatted the clearcoat's own f: the wall came out 1.7-2.1 % brighter than Cycles, the image 1.011 (issue
    18: rooms of clearcoated walls, seeds 24, 89, 99, 102 and 184, 0.8-1.9 % brighter; without their clearcoats
    the same scenes are 0.8-1.1 % darker than Cycles, for reasons of their own). Measured since: 0.997, and 0.9996
    once the boundary correction took in the walls' diffuse lobes."""
    cycles, photonsplat = clearcoated_wall_room(core, 1.0, 256, 64)
    print(f"\nCycles {cycles:.5f}, Photon Splat {photonsplat / cycles:.4f} of it")
    assert photonsplat / cycles == pytest.approx(1.0, abs=0.006)


def test_the_reference_runs_multiscatter_glass_on_cycles_numbers(scenes, core):
    """Cycles 3.x seeds the random numbers of a shading point's multiscatter walks per path and bounce by a fixed
    step (CyclesLcg, glass_multiscatter.h), so a path's walks at successive vertices are not independent, and what
    it converges to through Multiscatter Glass depends on it. Seed 22's cylinder (roughness 0.45), seen through: the
    reference with independent walks was 0.92 and 0.88 of Cycles in the two blocks below its cap (2 x 4096 passes),
    0.98 and 1.00 on Cycles' numbers (2 x 2048), against 2 x 2048 Cycles samples; here 0.89 and 0.88 against 0.99
    and 0.99 at 1024 of each."""
    from differential import block_means
    from photonsplat import export
    blend = scenes / "random_22.blend"
    cycles = block_means(cycles_mean(blend, samples=1024)).mean(-1)
    bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    scene = bpy.context.scene
    import make_random_scenes
    make_random_scenes.canonical(scene, json.loads(scene["differential"]))
    scene.render.engine = 'PHOTONSPLAT'
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    reference = np.asarray(core.render_reference(frame.scene, frame.camera, samples=1024, seed=1, threads=2,
                                                 max_bounces=16)[0])[..., :3]
    ours = block_means(reference).mean(-1)
    below_the_cap = [ours[4, 2] / cycles[4, 2], ours[4, 3] / cycles[4, 3]]
    ratio = reference.mean() / (cycles.mean())
    print(f"\nseed 22, the reference: mean ratio {ratio:.4f}, below the cap {np.round(below_the_cap, 3)}")
    assert abs(ratio - 1.0) < 0.02
    assert all(abs(r - 1.0) < 0.05 for r in below_the_cap)
