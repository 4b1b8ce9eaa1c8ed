"""The world as a node program and a light (world.h): escaped rays see the program, direct light importance-samples
its map against analytic irradiance, photons and the reference agree, portals change noise but not the image, and
bad worlds are refused with the field named.

Every scene is tiny; the file runs in about 20 s on 2 shared cores."""
import numpy as np
import pytest

import photonsplat as ps
from photonsplat import _core
import scenes

OPS = {o["name"]: o for o in _core.shader_ops()}
CLOSEST = 1  # environment_texture's interpolation param: Cycles' Closest


def env_program(texture, interpolation=CLOSEST):
    """emission = Environment Texture(texture) along the direction (Texture Coordinate's Generated, which the
    world sets to the direction)."""
    code = [OPS["texture_coordinate"]["id"], 3, 0, 7, 0, -1, 0x3F800000, 0, 3, 6, 9, 12, 15, 18,   # width 1.0's bits
            OPS["environment_texture"]["id"], 3, 1, 2, texture, interpolation, 0, 0, 21, 24]
    return {"code": code, "registers": [0.0] * 25, "tables": [],
            "outputs": [{"target": "emission", "index": 0, "register": 21}]}


def floor_scene(env, albedo=0.8, half=50.0, program=True):
    scene = ps.Scene()
    scene.add_material(name="floor", color=(albedo,) * 3)
    v = np.array([[-half, -half, 0], [half, -half, 0], [half, half, 0], [-half, half, 0]], np.float32)
    scene.add_mesh(name="floor", vertices=v, triangles=np.array([[0, 1, 2], [0, 2, 3]], np.int32))
    if program:
        texture = scene.add_texture(name="env", pixels=env.astype(np.float32), color_space="linear")
        scene.set_world_program(env_program(texture), 0)
    else:
        scene.set_background(radiance=tuple(float(c) for c in env[0, 0, :3]))
    return scene


def top_down_camera(half_size=1.0, size=24, height=5.0):
    to_world = np.identity(4)
    to_world[2, 3] = height
    near, far = 0.1, 100.0
    projection = np.array([[1 / half_size, 0, 0, 0], [0, 1 / half_size, 0, 0],
                           [0, 0, -2 / (far - near), -(far + near) / (far - near)], [0, 0, 0, 1]])
    return ps.Camera(to_world=to_world, projection=projection, width=size, height=size)


def sun_env(width=64, height=32, rows=(26, 28), columns=(10, 12), value=500.0):
    env = np.zeros((height, width, 3), np.float32)
    env[rows[0]:rows[1], columns[0]:columns[1]] = value
    return env


def irradiance_from_above(env):
    """∫ L cos θ dω over the upper hemisphere of a piecewise-constant equirectangular map (row 0 at the nadir)."""
    height, width = env.shape[:2]
    e = 0.0
    for y in range(height):
        theta_low, theta_high = np.pi * (1 - y / height), np.pi * (1 - (y + 1) / height)
        if theta_low > np.pi / 2 + 1e-9:
            continue
        band = (2 * np.pi / width) * 0.5 * (np.cos(theta_high) ** 2 - np.cos(theta_low) ** 2)
        e += env[y, :, 0].sum() * band
    return e


def test_a_uniform_map_lights_as_the_constant_world_it_equals():
    env = np.ones((32, 64, 3), np.float32)
    camera = top_down_camera()
    settings = ps.RenderSettings(photons=0, direct_samples=16)
    programmed, _ = ps.render(floor_scene(env), camera, settings)
    constant, _ = ps.render(floor_scene(env, program=False), camera, settings)
    assert constant[..., :3].mean() == pytest.approx(0.8, rel=1e-4)
    assert programmed[..., :3].mean() == pytest.approx(0.8, rel=0.01)


def test_an_hdri_sun_gives_the_analytic_irradiance_with_little_noise():
    """A bright 2 x 2 texel 'sun' above a Lambert floor: L = albedo / π · ∫ L cos dω, whichever renderer."""
    env = sun_env()
    scene = floor_scene(env)
    expected = 0.8 / np.pi * irradiance_from_above(env)
    camera = top_down_camera()
    image, _ = ps.render(scene, camera, ps.RenderSettings(photons=0, direct_samples=16))
    red = image[..., 0]
    print(f"\nsun: {red.mean():.4f} expected {expected:.4f}, relative std {red.std() / red.mean():.4f}")
    assert red.mean() == pytest.approx(expected, rel=0.01)
    assert red.std() / red.mean() < 0.05      # importance sampling: a sun is not a firefly
    reference, _ = ps.render_reference(scene, camera, samples=16)
    assert reference[..., 0].mean() == pytest.approx(expected, rel=0.02)


def test_escaped_camera_rays_see_the_map():
    """Looking straight up at a map whose upper half is one colour and lower half another."""
    env = np.zeros((32, 64, 3), np.float32)
    env[16:] = (0.2, 0.4, 0.8)
    env[:16] = (1.0, 0.5, 0.0)
    scene = ps.Scene()
    scene.add_material(name="m", color=(0.5,) * 3)
    v = np.array([[100, 100, 0], [101, 100, 0], [101, 101, 0]], np.float32)   # out of view
    scene.add_mesh(name="speck", vertices=v, triangles=np.array([[0, 1, 2]], np.int32))
    texture = scene.add_texture(name="env", pixels=env, color_space="linear")
    scene.set_world_program(env_program(texture), 0)
    up = ps.look_at_camera(eye=(0, 0, 0), target=(0, 0.01, 1), width=8, height=8, fov_y_degrees=30)
    down = ps.look_at_camera(eye=(0, 0, 0), target=(0, 0.01, -1), width=8, height=8, fov_y_degrees=30)
    image, _ = ps.render(scene, up, ps.RenderSettings(photons=0))
    np.testing.assert_allclose(image[..., :3].reshape(-1, 3).mean(0), (0.2, 0.4, 0.8), rtol=1e-5)
    image, _ = ps.render(scene, down, ps.RenderSettings(photons=0))
    np.testing.assert_allclose(image[..., :3].reshape(-1, 3).mean(0), (1.0, 0.5, 0.0), rtol=1e-5)
    assert scene.world_radiance((0, 0.01, 1)) == pytest.approx((0.2, 0.4, 0.8))


def wall_scene(env):
    scene = ps.Scene()
    scene.add_material(name="white", color=(0.8, 0.8, 0.8))
    h = 4.0
    floor = np.array([[-h, -h, 0], [h, -h, 0], [h, h, 0], [-h, h, 0]], np.float32)
    wall = np.array([[-h, 1, 0], [h, 1, 0], [h, 1, 3], [-h, 1, 3]], np.float32)
    quad = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    scene.add_mesh(name="floor", vertices=floor, triangles=quad)
    scene.add_mesh(name="wall", vertices=wall, triangles=quad)
    texture = scene.add_texture(name="env", pixels=env, color_space="linear")
    scene.set_world_program(env_program(texture), 0)
    return scene


def test_photons_from_the_map_agree_with_the_reference():
    """Indirect light between a floor and a wall under a sky with a sun: the photons (drawn from the map) and the
    path-traced reference (light-sampling the map with MIS) agree."""
    env = np.zeros((64, 128, 3), np.float32)
    env[32:] = (0.2, 0.3, 0.5)
    env[50:52, 20:22] = 2000.0
    scene = wall_scene(env)
    camera = ps.look_at_camera(eye=(0, -6, 3), target=(0, 0, 0.8), width=40, height=30, fov_y_degrees=50)
    image, _ = ps.render(scene, camera, ps.RenderSettings(photons=100000, iterations=4))
    reference, _ = ps.render_reference(scene, camera, samples=128)
    print(f"\nphotons {image[..., :3].mean():.4f}, reference {reference[..., :3].mean():.4f}")
    assert image[..., :3].mean() == pytest.approx(reference[..., :3].mean(), rel=0.02)


def room(portal):
    """A closed 2 x 2 x 2 room with a 1 x 1 window in its +Y wall, lit only through it."""
    scene = ps.Scene()
    scene.add_material(name="white", color=(0.7, 0.7, 0.7))
    quads = []
    def q(a, b, c, d):
        quads.append((a, b, c, d))
    s = 1.0
    q((-s, -s, -s), (s, -s, -s), (s, s, -s), (-s, s, -s))      # floor
    q((-s, -s, s), (-s, s, s), (s, s, s), (s, -s, s))          # ceiling
    q((-s, -s, -s), (-s, s, -s), (-s, s, s), (-s, -s, s))      # -X
    q((s, -s, -s), (s, -s, s), (s, s, s), (s, s, -s))          # +X
    q((-s, -s, -s), (-s, -s, s), (s, -s, s), (s, -s, -s))      # -Y
    # +Y wall with a window x, z in [-0.5, 0.5]
    for a, b in (((-s, -s), (s, -0.5)), ((-s, 0.5), (s, s)), ((-s, -0.5), (-0.5, 0.5)), ((0.5, -0.5), (s, 0.5))):
        q((a[0], s, a[1]), (b[0], s, a[1]), (b[0], s, b[1]), (a[0], s, b[1]))
    vertices = np.array([p for quad in quads for p in quad], np.float32)
    triangles = np.array([t for k in range(len(quads)) for t in ((4 * k, 4 * k + 1, 4 * k + 2),
                                                                   (4 * k, 4 * k + 2, 4 * k + 3))], np.int32)
    scene.add_mesh(name="room", vertices=vertices, triangles=triangles)
    env = np.zeros((32, 64, 3), np.float32)
    env[16:] = (0.5, 0.6, 0.9)
    env[:16] = (0.2, 0.15, 0.1)
    texture = scene.add_texture(name="env", pixels=env, color_space="linear")
    scene.set_world_program(env_program(texture), 0)
    if portal:
        # Light enters travelling along -Y: cross(edge_u, edge_v) = -Y.
        scene.add_portal("window", corner=(-0.5, 1.0, -0.5), edge_u=(1.0, 0.0, 0.0), edge_v=(0.0, 0.0, 1.0))
    return scene


def test_a_portal_changes_the_noise_not_the_image():
    camera = ps.look_at_camera(eye=(0, -0.9, 0), target=(0, 1, -0.3), width=24, height=24, fov_y_degrees=80)
    settings = ps.RenderSettings(photons=200000, iterations=8, direct_samples=4)
    without, _ = ps.render(room(False), camera, settings)
    with_portal, _ = ps.render(room(True), camera, settings)
    reference, _ = ps.render_reference(room(True), camera, samples=256)
    means = [x[..., :3].mean() for x in (without, with_portal, reference)]
    print(f"\nroom: without portal {means[0]:.4f}, with {means[1]:.4f}, reference {means[2]:.4f}")
    assert means[1] == pytest.approx(means[2], rel=0.03)
    assert means[0] == pytest.approx(means[2], rel=0.03)
    scene = room(True)
    assert scene.portal_count == 1
    scene.clear_lights()
    assert scene.portal_count == 0


def test_a_program_that_folds_is_the_constant_world():
    scene = floor_scene(np.ones((4, 8, 3), np.float32), program=False)
    program = {"code": [], "registers": [0.25, 0.5, 1.0], "tables": [],
               "outputs": [{"target": "emission", "index": 0, "register": 0}]}
    scene.set_world_program(program, 0)
    assert not scene.world_programmed
    assert scene.world_map_info()["constant"]
    assert scene.world_radiance((0, 0, 1)) == pytest.approx((0.25, 0.5, 1.0))
    scene.set_world_program(None)
    assert scene.world_radiance((0, 0, 1)) == pytest.approx((0.25, 0.5, 1.0))


@pytest.mark.parametrize("change, field", [
    (lambda s, p: s.set_world_program({**p, "outputs": [{"target": "closure_color", "index": 0, "register": 21}]}, 0),
     "world.program"),
    (lambda s, p: s.set_world_program(p, -1), "world.map_resolution"),
    (lambda s, p: s.add_portal("p", (0, 0, 0), (1, 0, 0), (2, 0, 0)), "portal 'p'.edges"),
    (lambda s, p: s.add_portal("p", (np.nan, 0, 0), (1, 0, 0), (0, 1, 0)), "portal 'p'.corner"),
])
def test_bad_worlds_name_the_field(change, field):
    scene = floor_scene(np.ones((4, 8, 3), np.float32))
    with pytest.raises(ValueError, match=field.replace("(", r"\(")):
        change(scene, env_program(0))


def test_a_black_or_hostile_map_renders_finite():
    for env in (np.zeros((4, 8, 3), np.float32), np.full((4, 8, 3), 3e38, np.float32)):
        scene = floor_scene(env)
        image, _ = ps.render(scene, top_down_camera(size=8), ps.RenderSettings(photons=1000, direct_samples=2))
        assert np.isfinite(image).all()
