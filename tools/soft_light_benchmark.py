"""The photon stage's cost for soft lights near surfaces, where first_hit_falloff does the most work: a closed
room, a spot of radius 0.25 at 0.3 over the floor (its photons' first hits within two radii, where the spot's
cone takes a quadrature) and a point light of radius 0.25 at 0.3 under the ceiling (its disc crossing the
ceiling's horizon, a clipped polygon), 400,000 photons at 320 x 240. Prints the median stage times of --repeats
renders as JSON. To compare two builds, alternate them in one session on an otherwise idle machine:

    /usr/bin/python3 tools/soft_light_benchmark.py --build build [--repeats 5]
"""
import argparse
import json
import statistics
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def main(argv):
    p = argparse.ArgumentParser(prog="soft_light_benchmark.py")
    p.add_argument("--build", default=str(REPO / "build"), help="a build folder holding python/photonsplat")
    p.add_argument("--repeats", type=int, default=5)
    args = p.parse_args(argv)
    sys.path.insert(0, str(Path(args.build) / "python"))
    sys.path.insert(0, str(REPO / "tests" / "python"))
    import numpy as np
    import photonsplat as ps
    import scenes

    scene = ps.Scene()
    scene.add_material(name="white", color=(0.8, 0.8, 0.8))
    walls = [((-3, -3, 0), (3, -3, 0), (3, 3, 0), (-3, 3, 0)), ((-3, -3, 2.5), (-3, 3, 2.5), (3, 3, 2.5), (3, -3, 2.5)),
             ((-3, -3, 0), (-3, 3, 0), (-3, 3, 2.5), (-3, -3, 2.5)), ((3, -3, 0), (3, -3, 2.5), (3, 3, 2.5), (3, 3, 0)),
             ((-3, -3, 0), (-3, -3, 2.5), (3, -3, 2.5), (3, -3, 0)), ((-3, 3, 0), (3, 3, 0), (3, 3, 2.5), (-3, 3, 2.5))]
    for k, quad in enumerate(walls):
        v, t = scenes.quad(*quad)
        scene.add_mesh(name=f"wall{k}", vertices=v, triangles=t)
    scene.add_spot_light("spot", position=(0, 0, 0.3), direction=(0, 0, -1), intensity=(50, 50, 50), radius=0.25,
                         spot_size=1.2, spot_blend=0.15)
    scene.add_point_light("lamp", position=(1, 1, 2.2), intensity=(50, 50, 50), radius=0.25)
    to_world = np.eye(4)
    to_world[:3, :3] = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]], float)
    to_world[:3, 3] = (0, -2.9, 1.2)
    projection = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1.0001, -0.02], [0, 0, -1, 0]], float)
    camera = ps.Camera(to_world=to_world, projection=projection, width=320, height=240)
    settings = ps.RenderSettings(photons=400000, seed=1)
    times = {}
    for _ in range(args.repeats):
        _, stats = ps.render(scene, camera, settings)
        for stage, seconds in stats["seconds"].items():
            times.setdefault(stage, []).append(seconds)
    print(json.dumps({stage: round(statistics.median(v), 4) for stage, v in sorted(times.items())}))


if __name__ == "__main__":
    main(sys.argv[1:])
