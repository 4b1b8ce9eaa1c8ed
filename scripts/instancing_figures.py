"""Memory and update cost of instancing, for docs/translation.md (a measurement, not a test).

    PYTHONPATH=build/python /usr/bin/python3 scripts/instancing_figures.py

1000 copies of a 5120-triangle sphere, once as 1000 instances of one mesh, once as 1000 separate meshes; then
the cost of moving one instance (set_instance_transform + the next BVH update) against rebuilding the scene.
"""
import math
import resource
import time

import numpy as np

import photonsplat as ps


def icosphere(subdivisions):
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
         (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2), (10, 7, 6),
         (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10),
         (8, 6, 7), (9, 8, 1)]
    v = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(subdivisions):
        cache, faces = {}, []
        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                cache[key] = len(v) - 1
            return cache[key]
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            faces += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = faces
    return np.array(v, np.float32) * 0.4, np.array(f, np.int32)


def transforms(count):
    for i in range(count):
        m = np.eye(4)
        m[:3, 3] = (i % 40, i // 40, 0.0)
        yield m


def build(instanced, vertices, triangles, count=1000):
    scene = ps.Scene()
    scene.add_material(name="white")
    if instanced:
        mesh = scene.add_mesh_data("sphere", vertices, triangles)
        for m in transforms(count):
            scene.add_instance(mesh, m)
    else:
        for i, m in enumerate(transforms(count)):
            scene.add_mesh(name=f"sphere{i}", vertices=vertices, triangles=triangles, transform=m)
    return scene


def camera():
    return ps.look_at_camera(eye=(20, -30, 30), target=(20, 12, 0), width=64, height=64)


def main():
    vertices, triangles = icosphere(4)
    settings = ps.RenderSettings(photons=1000, direct_samples=1)
    print(f"mesh: {len(triangles)} triangles; 1000 copies")
    for instanced in (True, False):
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        started = time.perf_counter()
        scene = build(instanced, vertices, triangles)
        scene.set_background((1, 1, 1))
        _, stats = ps.render(scene, camera(), settings)
        seconds = time.perf_counter() - started
        grown = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - rss
        print(f"{'instances of one mesh' if instanced else '1000 separate meshes '}: scene {scene.scene_bytes / 1e6:7.2f} MB, "
              f"Embree buffers {stats['bytes']['embree_scene'] / 1e6:7.2f} MB, peak RSS +{grown / 1e3:7.1f} MB, "
              f"build + render {seconds:5.2f} s (scene_build stage {stats['seconds']['scene_build']:.3f} s)")
        if instanced:
            started = time.perf_counter()
            scene.set_instance_transform(0, np.eye(4))
            _, moved = ps.render(scene, camera(), settings)
            print(f"  move one instance + render: scene_build stage {moved['seconds']['scene_build']:.4f} s "
                  f"(top-level refit only), total {time.perf_counter() - started:.2f} s")


if __name__ == "__main__":
    main()
