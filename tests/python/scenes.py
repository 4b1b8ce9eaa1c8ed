"""Small scenes built from numpy arrays, as a script author would build them."""
import numpy as np

import photonsplat as ps


def quad(a, b, c, d):
    return np.array([a, b, c, d], np.float32), np.array([[0, 1, 2], [0, 2, 3]], np.int32)


def plane_scene(albedo=0.8, light_height=2.0, power=1000.0):
    """A 40 m Lambertian plane at z = 0 under a point light of `power` watts (Blender's convention)."""
    scene = ps.Scene()
    scene.add_material(name="plane", kind="diffuse", color=(albedo,) * 3)
    v, t = quad((-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0))
    scene.add_mesh(name="plane", vertices=v, triangles=t)
    scene.add_point_light(name="lamp", position=(0, 0, light_height), intensity=(power / (4 * np.pi),) * 3)
    return scene


def cornell_box():
    scene = ps.Scene()
    white = scene.add_material(name="white", color=(0.75, 0.75, 0.75))
    red = scene.add_material(name="red", color=(0.75, 0.1, 0.1))
    green = scene.add_material(name="green", color=(0.1, 0.75, 0.1))
    glass = scene.add_material(name="glass", kind="glass", color=(1, 1, 1), ior=1.5)
    walls = [
        ("floor", ((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)), white),
        ("ceiling", ((-1, -1, 2), (-1, 1, 2), (1, 1, 2), (1, -1, 2)), white),
        ("back", ((-1, 1, 0), (1, 1, 0), (1, 1, 2), (-1, 1, 2)), white),
        ("left", ((-1, -1, 0), (-1, 1, 0), (-1, 1, 2), (-1, -1, 2)), red),
        ("right", ((1, -1, 0), (1, -1, 2), (1, 1, 2), (1, 1, 0)), green),
    ]
    for name, corners, material in walls:
        v, t = quad(*corners)
        scene.add_mesh(name=name, vertices=v, triangles=t, material_ids=np.full(2, material, np.int32))
    v, t, n = uv_sphere(0.35)
    transform = np.identity(4)
    transform[:3, 3] = (0.0, 0.0, 1.0)
    scene.add_mesh(name="ball", vertices=v, triangles=t, normals=n,
                   material_ids=np.full(len(t), glass, np.int32), transform=transform)
    scene.add_point_light(name="lamp", position=(0, 0, 1.8), intensity=(100 / (4 * np.pi),) * 3, radius=0.02)
    return scene


def uv_sphere(radius, rings=16, segments=32):
    theta = np.linspace(0, np.pi, rings + 1)
    phi = np.linspace(0, 2 * np.pi, segments + 1)
    th, ph = np.meshgrid(theta, phi, indexing="ij")
    n = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1).reshape(-1, 3)
    tris = []
    for i in range(rings):
        for j in range(segments):
            a = i * (segments + 1) + j
            b = a + segments + 1
            tris += [(a, b, a + 1), (a + 1, b, b + 1)]
    return (radius * n).astype(np.float32), np.array(tris, np.int32), n.astype(np.float32)


def cornell_camera(width=48, height=48):
    return ps.look_at_camera(eye=(0, -3.9, 1), target=(0, 0, 1), width=width, height=height, fov_y_degrees=40)
