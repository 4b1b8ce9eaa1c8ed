"""The world as a light (issue 17's acceptance): blend_scenes/world_hdri.blend, world_sky.blend and world_portal.blend
rendered by Cycles 3.4 and by Photon Splat, compared. Writes docs/results/worlds.md and docs/results/worlds.png.

    /usr/bin/python3 tools/world_compare.py                 # everything (long: the Cycles references)
    /usr/bin/python3 tools/world_compare.py --quick         # a smoke run: half size, few samples, 1/2/4 s
    /usr/bin/python3 tools/world_compare.py --scene hdri    # one scene (hdri, sky, portal); repeatable
    /usr/bin/python3 tools/world_compare.py --cycles-only   # fill the Cycles cache (needs no build)

Run with /usr/bin/python3 it starts Debian's Blender (3.4) in the background with the add-on of `--build` (default
build/) and runs itself inside it.

What is measured, per scene (all in linear radiance, RGB):
  * Cycles' converged image: CPU, no denoising, no adaptive sampling, no clamping, light threshold 0, Filter Glossy
    0, box filter 1 px, 16 bounces, world MIS as the file says (automatic: the map at the HDRI's resolution). It is
    the mean of two renders with seeds 1 and 2 of --cycles-samples / 2 each, cached in build/world_compare/cycles/
    by a hash of the .blend file's bytes, the resolution and the Cycles settings. Cycles' own noise is given next
    to every figure: for a mean, |m1 - m2| / (m1 + m2) (the standard error of the two-seed mean, relative); for a
    block error, relMSE(seed 1, seed 2) / 4 (the error of the two-seed mean itself, which floors every error
    measured against it).
  * mean ratio: Photon Splat's whole-image mean / Cycles'; the acceptance is |ratio - 1| <= 3 % at the longest time.
  * time to quality: Photon Splat progressive (--photons per iteration), snapshots of its running mean at
    --times seconds of wall time (from the start of the export), and Cycles at 1, 2, 4, ... samples (seeds 101...,
    independent of the reference), each timed from the start of bpy.ops.render.render (sync, BVH, the world's
    importance map included) to its end. Error = 8x8-block relMSE: both images averaged over 8x8-pixel blocks, then
    mean over blocks and channels of (a - r)^2 / (r^2 + 0.01), r the converged Cycles image (also given without
    the worst 1 % of the blocks: fireflies). Cycles' error at Photon Splat's times: the samples it reaches then,
    from a line fitted through its (samples, seconds), and its error there, interpolated log-log.
  * direct light (the HDRI scene; all scenes are reported): the light arriving at the first diffuse or glossy surface
    the camera sees straight from the world (shadow rays / BSDF samples to the environment, MIS). Cycles:
    DiffDir x DiffCol + GlossDir x GlossCol; Photon Splat: its Direct pass. Over the 8x8 blocks all of whose pixels
    see an opaque surface directly (not the background, not the glass: Cycles' Depth and TransCol passes), error as
    above against the converged Cycles direct image, at equal wall time. Acceptance: Photon Splat's error no worse
    than Cycles' at the same time.
  * caustic (the HDRI scene): Cycles' converged image with refractive caustics off (caustics_refractive False,
    same seeds and samples) subtracted from the one with them on gives the glass sphere's caustic; its region is the
    8x8 blocks (opaque, not glass) where rays parallel to the HDRI's sun direction (the scene's `sun_direction`),
    refracted in and out of the sphere, land on the floor in view, grown by one block. Energy = the sum over
    the region of the mean of R, G, B. Photon Splat's is its Caustics pass summed over the same region (and its
    combined image's excess over Cycles' caustics-off image, for comparison). Acceptance: the ratio within 20 %.
"""
import argparse
import datetime
import hashlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))
sys.path.insert(0, str(REPO / "tests" / "blender"))     # scene_geometry: the glass sphere's caustic
from closure_gallery import (commit_of_repo, display, run_blender_script, use_cycles_oracle,  # noqa: E402
                             write_png)

OUT_DIR = REPO / "build" / "world_compare"
RESULTS_MD = REPO / "docs" / "results" / "worlds.md"
RESULTS_PNG = REPO / "docs" / "results" / "worlds.png"
SCENES = {"hdri": "world_hdri", "sky": "world_sky", "portal": "world_portal"}
BOUNCES = 16
BLOCK = 8
EPSILON = 0.01
MEAN_TOLERANCE = 0.03
CAUSTIC_TOLERANCE = 0.20
TRIM = 0.01            # the time-to-quality table also gives the error without the worst 1 % of the blocks


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scene", action="append", default=[], choices=sorted(SCENES),
                        help="a scene: hdri, sky or portal; repeatable (default all)")
    parser.add_argument("--quick", action="store_true",
                        help="a smoke run: half resolution, 64 Cycles samples, 50k photons, 1/2/4 s")
    parser.add_argument("--cycles-only", action="store_true", help="render and cache the Cycles references only")
    parser.add_argument("--build", default="build", help="the build folder whose blender/ add-on renders")
    parser.add_argument("--scale", type=int, help="resolution percentage of the files' 480x270 (default 100, "
                        "quick 50)")
    parser.add_argument("--cycles-samples", type=int, help="samples of the converged Cycles image, over two seeds "
                        "(default 2048, quick 64)")
    parser.add_argument("--times", type=float, nargs="+", help="Photon Splat's snapshot times in seconds "
                        "(default 1 4 16, quick 1 2 4)")
    parser.add_argument("--photons", type=int, help="Photon Splat photons per iteration (default 200000, quick "
                        "50000)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the markdown and the contact sheet from build/world_compare/ (no rendering)")
    parser.add_argument("--markdown", default=str(RESULTS_MD))
    parser.add_argument("--png", default=str(RESULTS_PNG))
    parser.add_argument("--blender", default="blender")
    args = parser.parse_args(argv)
    quick = args.quick
    args.scale = args.scale or (50 if quick else 100)
    args.cycles_samples = args.cycles_samples or (64 if quick else 2048)
    args.times = sorted(args.times or ([1.0, 2.0, 4.0] if quick else [1.0, 4.0, 16.0]))
    args.photons = args.photons or (50000 if quick else 200000)
    args.scenes = args.scene or list(SCENES)
    return args


def command_line(argv):
    return "/usr/bin/python3 tools/world_compare.py" + "".join(f" {a}" for a in argv)


# ---- host side ------------------------------------------------------------------------------------------------

def run_in_blender(argv):
    args = parse_args(argv)
    if args.report_only:
        report_only(args)
        return
    run_blender_script("world_compare", __file__, argv, args.blender, None if args.cycles_only else args.build,
                       hint="--build, or --cycles-only")


# ---- measures (numpy only) ------------------------------------------------------------------------------------

def blocks(image, np):
    """(H/8, W/8, 3) block means of the RGB of `image` (rows and columns past a multiple of 8 dropped)."""
    h, w = image.shape[0] // BLOCK * BLOCK, image.shape[1] // BLOCK * BLOCK
    rgb = image[:h, :w, :3].astype(np.float64)
    return rgb.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, 3).mean(axis=(1, 3))


def block_mask(mask, np):
    """(H/8, W/8) bool: blocks all of whose pixels are in `mask`."""
    h, w = mask.shape[0] // BLOCK * BLOCK, mask.shape[1] // BLOCK * BLOCK
    return mask[:h, :w].reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK).all(axis=(1, 3))


def block_relmse(image, reference, np, mask=None, trim=0.0):
    """8x8-block relMSE; `trim` > 0 leaves out that fraction of the blocks with the largest error (a firefly
    in one block can make the plain mean jump by orders of magnitude)."""
    a, r = blocks(image, np), blocks(reference, np)
    err = ((a - r) ** 2 / (r ** 2 + EPSILON)).mean(axis=-1)
    if mask is not None:
        err = err[mask]
    if not err.size:
        return float("nan")
    if trim > 0.0:
        err = np.sort(err.ravel())[:max(1, int(round(err.size * (1.0 - trim))))]
    return float(err.mean())


def mean_rgb(image, np):
    return float(image[..., :3].astype(np.float64).mean())


def cycles_at_time(series, key, t, np):
    """Cycles' `key` at wall time t: the samples Cycles reaches in t seconds from a least-squares line
    seconds = a + b * samples through its series (timings on a shared machine are noisy; the line is monotone),
    and the error there, interpolated log-log between the series' sample counts. (None, samples) when t is below
    the time of one sample or past the series."""
    samples = np.array([s["samples"] for s in series], float)
    seconds = np.array([s["seconds"] for s in series], float)
    values = np.array([s[key] for s in series], float)
    if len(series) < 2:
        return None, None
    b, a = np.polyfit(samples, seconds, 1)
    if b <= 0:
        return None, None
    reached = (t - a) / b
    if reached < samples.min() or reached > samples.max():
        return None, reached
    value = float(np.exp(np.interp(np.log(reached), np.log(samples), np.log(np.maximum(values, 1e-30)))))
    return value, reached


# ---- inside Blender -------------------------------------------------------------------------------------------

def blender_main(argv):
    import bpy
    import numpy as np

    args = parse_args(argv)
    for sub in ("cycles", "images", "tmp"):
        (OUT_DIR / sub).mkdir(parents=True, exist_ok=True)
    core = None
    export = None
    if not args.cycles_only:
        from photonsplat import export
        from photonsplat.engine import load_core
        core = load_core()

    def cycles_settings(scene, samples, seed, refractive_caustics=True):
        c = use_cycles_oracle(scene, samples, seed, args.threads, BOUNCES)
        c.caustics_reflective = True
        c.caustics_refractive = refractive_caustics
        scene.render.film_transparent = False
        layer = bpy.context.view_layer
        layer.use_pass_z = True
        layer.use_pass_diffuse_direct = layer.use_pass_diffuse_color = True
        layer.use_pass_glossy_direct = layer.use_pass_glossy_color = True
        layer.use_pass_transmission_color = True
        world = scene.world
        return {"samples": samples, "refractive_caustics": refractive_caustics, "bounces": BOUNCES,
                "threads": args.threads, "scale": args.scale,
                "world_sampling": [world.cycles.sampling_method, world.cycles.sample_map_resolution]
                if world is not None else None}

    cycles_passes = {"Combined": "RGBA", "Depth": "Z", "DiffDir": "RGB", "DiffCol": "RGB", "GlossDir": "RGB",
                     "GlossCol": "RGB", "TransCol": "RGB"}

    def render_cycles(scene):
        """One render with bpy.ops into a multilayer EXR; returns ({pass: float32 (H, W, 4) top row first},
        seconds of the render call)."""
        path = OUT_DIR / "tmp" / "cycles.exr"
        scene.render.filepath = str(path)
        scene.render.use_file_extension = False
        settings = scene.render.image_settings
        settings.file_format = 'OPEN_EXR_MULTILAYER'
        settings.color_depth = '32'
        t0 = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        seconds = time.perf_counter() - t0
        layer = bpy.context.view_layer.name
        out = {}
        for name, channels in cycles_passes.items():
            mapping = [f"{target}={layer}.{name}.{channel}" for target, channel in zip("RGBA", channels)]
            mapping += [f"{target}=0.0" for target in "RGBA"[len(channels):]]
            single = OUT_DIR / "tmp" / f"{name}.exr"
            subprocess.run(["oiiotool", str(path), "--ch", ",".join(mapping), "-d", "float", "-o", str(single)],
                           check=True, capture_output=True)
            image = bpy.data.images.load(str(single), check_existing=False)
            try:
                width, height = image.size
                pixels = np.empty(width * height * 4, dtype=np.float32)
                image.pixels.foreach_get(pixels)
                out[name] = np.flipud(pixels.reshape(height, width, 4)).copy()
            finally:
                bpy.data.images.remove(image)
                os.remove(single)
        os.remove(path)
        return out, seconds

    def cycles_direct(p):
        return np.concatenate([p["DiffDir"][..., :3] * p["DiffCol"][..., :3]
                               + p["GlossDir"][..., :3] * p["GlossCol"][..., :3], p["Combined"][..., 3:]], axis=-1)

    def cycles_reference(label, scene, blend_bytes, refractive_caustics=True):
        """The converged Cycles image: seeds 1 and 2 of cycles_samples / 2 each, cached. Returns
        {"seeds": [passes of seed 1, of seed 2], "seconds": total}."""
        per_seed = max(1, args.cycles_samples // 2)
        settings = cycles_settings(scene, per_seed, 1, refractive_caustics)
        key_data = {"blend": hashlib.sha256(blend_bytes).hexdigest(), "cycles": settings,
                    "blender": bpy.app.version_string, "passes": sorted(cycles_passes)}
        key = hashlib.sha256(json.dumps(key_data, sort_keys=True).encode()).hexdigest()[:16]
        tag = "" if refractive_caustics else "-nocaustics"
        path = OUT_DIR / "cycles" / f"{label}{tag}-{key}.npz"
        if path.exists():
            data = np.load(path)
            seeds = [{name: data[f"s{i}_{name}"] for name in cycles_passes} for i in range(2)]
            return {"seeds": seeds, "seconds": float(data["seconds"]), "samples": per_seed * 2, "cached": True}
        seeds, total = [], 0.0
        for seed in (1, 2):
            cycles_settings(scene, per_seed, seed, refractive_caustics)
            print(f"world_compare:   Cycles {label}{tag} seed {seed}: {per_seed} samples", flush=True)
            passes, seconds = render_cycles(scene)
            seeds.append(passes)
            total += seconds
        np.savez_compressed(path, seconds=total,
                            **{f"s{i}_{name}": seeds[i][name] for i in range(2) for name in cycles_passes})
        path.with_suffix(".json").write_text(json.dumps(key_data, sort_keys=True, indent=0))
        return {"seeds": seeds, "seconds": total, "samples": per_seed * 2, "cached": False}

    def caustic_blocks(scene, shape):
        """The 8x8 blocks where the sun's light refracted through the glass sphere lands on the floor and is seen
        by the camera (rays parallel to the scene's `sun_direction` through the sphere, in and out, to z = 0;
        tests/blender/scene_geometry.py), grown by one block: the caustic's region, found without noise."""
        from bpy_extras.object_utils import world_to_camera_view
        from mathutils import Vector
        from scene_geometry import caustic_floor_points, visible_from
        sun = np.asarray(scene["sun_direction"], float)
        center, radius = np.asarray(scene["glass_center"], float), float(scene["glass_radius"])
        ior = bpy.data.materials["Glass"].node_tree.nodes["Glass BSDF"].inputs["IOR"].default_value
        landing = caustic_floor_points(center + 1.0e5 * sun, center, radius, ior, count=20000)
        eye = np.asarray(scene.camera.matrix_world.translation, float)
        landing = landing[visible_from(landing, eye, [(center, radius)])]
        width = scene.render.resolution_x * scene.render.resolution_percentage // 100
        height = scene.render.resolution_y * scene.render.resolution_percentage // 100
        hits = np.zeros(shape, int)
        for point in landing:
            x, y, depth = world_to_camera_view(scene, scene.camera, Vector(point))
            row, col = int((1.0 - y) * height) // BLOCK, int(x * width) // BLOCK      # row 0 at the top
            if depth > 0 and 0 <= row < shape[0] and 0 <= col < shape[1]:
                hits[row, col] += 1
        core_blocks = hits >= max(1, int(0.002 * len(landing)))
        grown = core_blocks.copy()
        grown[1:] |= core_blocks[:-1]
        grown[:-1] |= core_blocks[1:]
        grown[:, 1:] |= grown[:, :-1].copy()
        grown[:, :-1] |= grown[:, 1:].copy()
        return grown

    def mean_of(ref, name):
        return 0.5 * (ref["seeds"][0][name] + ref["seeds"][1][name])

    def noise_of_mean(a, b):
        ma, mb = mean_rgb(a, np), mean_rgb(b, np)
        return abs(ma - mb) / max(ma + mb, 1e-12)

    def photonsplat_snapshots(scene):
        """Photon Splat progressive: snapshots (wall seconds, image, passes) at args.times."""
        ps = scene.photonsplat
        ps.photons = args.photons
        ps.iterations = 0
        ps.time_limit = max(args.times) * 1.05 + 1.0
        ps.radius = 0.0
        ps.seed = 1
        ps.threads = args.threads
        ps.max_bounces = BOUNCES
        scene.render.engine = 'PHOTONSPLAT'
        t0 = time.perf_counter()
        frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
        frame.settings.caustics_pass = True
        frame.settings.outputs = ("combined", "emission", "direct", "indirect", "caustics")
        export_seconds = time.perf_counter() - t0
        progressive = core.Progressive(frame.scene, frame.camera, frame.settings)
        snapshots = []
        pending = list(args.times)
        while pending and not progressive.finished:
            progressive.step()
            wall = time.perf_counter() - t0
            if wall >= pending[0] or progressive.finished:
                while pending and wall >= pending[0]:
                    pending.pop(0)
                snapshots.append({"seconds": wall, "iterations": progressive.iterations_done,
                                  "image": np.asarray(progressive.image(), dtype=np.float32),
                                  "passes": {k: np.asarray(v, dtype=np.float32)
                                             for k, v in progressive.passes().items()}})
                # the snapshot's copies are not Photon Splat's time: leave them out of the clock
                t0 += time.perf_counter() - t0 - wall
        return snapshots, list(frame.warnings), export_seconds, progressive.stats()

    def cycles_series(scene, max_seconds):
        """Cycles at 1, 2, 4, ... samples (seeds 101, 102, ...) until a render takes max_seconds: [(seconds,
        samples, passes)]. Not cached: these are timings."""
        series, samples = [], 1
        while True:
            cycles_settings(scene, samples, 100 + len(series) + 1)
            passes, seconds = render_cycles(scene)
            series.append({"seconds": seconds, "samples": samples, "passes": passes})
            print(f"world_compare:   Cycles {samples} spp: {seconds:.1f} s", flush=True)
            if seconds >= max_seconds or samples >= 65536:
                return series
            samples *= 2

    results = {"scenes": {}, "args": {k: v for k, v in vars(args).items()}, "command": command_line(argv),
               "load_start": os.getloadavg()[0]}
    sheet = []
    started = time.time()
    for label in args.scenes:
        blend = REPO / "blend_scenes" / f"{SCENES[label]}.blend"
        print(f"world_compare: {label}: {blend.name}", flush=True)
        bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
        scene = bpy.context.scene
        scene.render.resolution_percentage = args.scale
        blend_bytes = blend.read_bytes()
        world = scene.world
        row = {"blend": blend.name, "resolution": [scene.render.resolution_x * args.scale // 100,
                                                   scene.render.resolution_y * args.scale // 100],
               "world_sampling": [world.cycles.sampling_method, world.cycles.sample_map_resolution]}
        ref = cycles_reference(label, scene, blend_bytes)
        cyc = mean_of(ref, "Combined")
        s1, s2 = ref["seeds"][0]["Combined"], ref["seeds"][1]["Combined"]
        row["cycles"] = {"samples": ref["samples"], "seconds": ref["seconds"], "mean": mean_rgb(cyc, np),
                         "mean_noise": noise_of_mean(s1, s2), "block_floor": block_relmse(s1, s2, np) / 4.0,
                         "block_floor_trimmed": block_relmse(s1, s2, np, trim=TRIM) / 4.0}
        depth = ref["seeds"][0]["Depth"][..., 0]
        glass = (ref["seeds"][0]["TransCol"][..., :3].sum(axis=-1) + ref["seeds"][1]["TransCol"][..., :3].sum(
            axis=-1)) > 1e-6
        # Grown by 2 pixels: at the glass's rim Cycles' transmission weight falls to nothing (Fresnel) while the
        # pixel still holds what is seen through the glass, which the Direct pass of Photon Splat counts (its view
        # samples behind glass) and Cycles' DiffDir / GlossDir do not.
        grown = glass.copy()
        for axis in (0, 1):
            for step in (-2, -1, 1, 2):
                grown |= np.roll(glass, step, axis=axis)
        opaque = (depth < 1e9) & ~grown
        opaque_blocks = block_mask(opaque, np)
        direct_ref = 0.5 * (cycles_direct(ref["seeds"][0]) + cycles_direct(ref["seeds"][1]))
        row["direct_floor"] = block_relmse(cycles_direct(ref["seeds"][0]), cycles_direct(ref["seeds"][1]), np,
                                           opaque_blocks) / 4.0
        row["direct_blocks"] = int(opaque_blocks.sum())
        caustic = None
        if label == "hdri":
            off = cycles_reference(label, scene, blend_bytes, refractive_caustics=False)
            off_img = mean_of(off, "Combined")
            region_blocks = caustic_blocks(scene, opaque_blocks.shape) & opaque_blocks
            px = np.kron(region_blocks, np.ones((BLOCK, BLOCK), bool))
            region = np.zeros(cyc.shape[:2], bool)
            region[:px.shape[0], :px.shape[1]] = px

            def energy(image):
                return float(image[..., :3][region].astype(np.float64).mean(axis=-1).sum())

            e_seeds = [energy(ref["seeds"][i]["Combined"]) - energy(off["seeds"][i]["Combined"]) for i in range(2)]
            caustic = {"region_blocks": int(region_blocks.sum()), "region_pixels": int(region.sum()),
                       "cycles_energy": energy(cyc) - energy(off_img),
                       "cycles_energy_noise": abs(e_seeds[0] - e_seeds[1]) / max(abs(sum(e_seeds)), 1e-12),
                       "cycles_on_region": energy(cyc), "cycles_off_region": energy(off_img),
                       "off_seconds": off["seconds"]}
            row["caustic"] = caustic
        if args.cycles_only:
            results["scenes"][label] = row
            continue

        snapshots, warnings, export_seconds, stats = photonsplat_snapshots(scene)
        row["warnings"] = warnings
        row["export_seconds"] = export_seconds
        row["photonsplat"] = []
        for snap in snapshots:
            img, passes = snap["image"], snap["passes"]
            entry = {"seconds": snap["seconds"], "iterations": snap["iterations"],
                     "mean": mean_rgb(img, np), "ratio": mean_rgb(img, np) / max(row["cycles"]["mean"], 1e-12),
                     "block_relmse": block_relmse(img, cyc, np),
                     "trimmed_relmse": block_relmse(img, cyc, np, trim=TRIM),
                     "direct_relmse": block_relmse(passes["direct"], direct_ref, np, opaque_blocks)
                     if "direct" in passes else None}
            if caustic is not None and "caustics" in passes:
                entry["caustic_energy"] = energy(passes["caustics"])
                entry["caustic_ratio"] = entry["caustic_energy"] / max(caustic["cycles_energy"], 1e-12)
                entry["excess_energy"] = energy(img) - caustic["cycles_off_region"]
            row["photonsplat"].append(entry)
            print(f"world_compare:   Photon Splat {snap['seconds']:.1f} s ({snap['iterations']} it): ratio "
                  f"{entry['ratio']:.3f}, block relMSE {entry['block_relmse']:.4f}", flush=True)
        last = snapshots[-1]

        series = cycles_series(scene, max(s["seconds"] for s in snapshots) * 1.25)
        row["cycles_series"] = [{"seconds": s["seconds"], "samples": s["samples"],
                                 "mean": mean_rgb(s["passes"]["Combined"], np),
                                 "block_relmse": block_relmse(s["passes"]["Combined"], cyc, np),
                                 "trimmed_relmse": block_relmse(s["passes"]["Combined"], cyc, np, trim=TRIM),
                                 "direct_relmse": block_relmse(cycles_direct(s["passes"]), direct_ref, np,
                                                               opaque_blocks)} for s in series]
        for entry in row["photonsplat"]:
            entry["cycles_at_time"], entry["cycles_samples_at_time"] = cycles_at_time(
                row["cycles_series"], "block_relmse", entry["seconds"], np)
            entry["cycles_direct_at_time"], _ = cycles_at_time(row["cycles_series"], "direct_relmse",
                                                               entry["seconds"], np)
            entry["cycles_trimmed_at_time"], _ = cycles_at_time(row["cycles_series"], "trimmed_relmse",
                                                                entry["seconds"], np)
        results["scenes"][label] = row
        np.savez_compressed(OUT_DIR / "images" / f"{label}.npz", cycles=cyc, ours=last["image"],
                            direct_cycles=direct_ref, direct_ours=last["passes"].get("direct", last["image"]),
                            caustics_ours=last["passes"].get("caustics", np.zeros_like(cyc)))
        # the contact sheet: Cycles | Photon Splat | Cycles direct | Photon Splat direct (display: exposure of file)
        gain = 2.0 ** scene.view_settings.exposure
        row["display_gain"] = gain
        sheet.append([display(im * gain) for im in (cyc, last["image"], direct_ref,
                                                    last["passes"].get("direct", last["image"]))])

    results["load_end"] = os.getloadavg()[0]
    results["seconds"] = time.time() - started
    results["commit"] = commit_of_repo()
    results["date"] = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    results["blender"] = bpy.app.version_string
    (OUT_DIR / "results.json").write_text(json.dumps(results, indent=1, default=str))
    if args.cycles_only:
        print(f"world_compare: Cycles cached ({OUT_DIR / 'cycles'})")
        return
    write_markdown(results, args, Path(args.markdown))
    if sheet:
        write_sheet(sheet, Path(args.png), np)
    print(f"world_compare: wrote {args.markdown} and {args.png} ({results['seconds']:.0f} s)")


def report_only(args):
    """The markdown and the contact sheet again, from the last run's results.json and images (numpy only)."""
    import numpy as np
    results = json.loads((OUT_DIR / "results.json").read_text())
    saved = argparse.Namespace(**results["args"])
    if saved.cycles_only:
        sys.exit(f"world_compare: {OUT_DIR / 'results.json'} is from a --cycles-only run: nothing to report")
    write_markdown(results, saved, Path(args.markdown))
    sheet = []
    for label, row in results["scenes"].items():
        path = OUT_DIR / "images" / f"{label}.npz"
        if path.exists():
            data = np.load(path)
            gain = row.get("display_gain", 1.0)
            sheet.append([display(data[k] * gain) for k in ("cycles", "ours", "direct_cycles", "direct_ours")])
    if sheet:
        write_sheet(sheet, Path(args.png), np)
    print(f"world_compare: wrote {args.markdown} and {args.png} from {OUT_DIR / 'results.json'}")


def write_sheet(rows, path, np):
    gap = 4
    h, w = rows[0][0].shape[:2]
    height = len(rows) * h + (len(rows) - 1) * gap
    width = 4 * w + 3 * gap
    canvas = np.full((height, width, 3), 255, np.uint8)
    for r, images in enumerate(rows):
        for c, im in enumerate(images):
            y, x = r * (h + gap), c * (w + gap)
            canvas[y:y + im.shape[0], x:x + im.shape[1]] = im
    path.parent.mkdir(parents=True, exist_ok=True)
    write_png(path, canvas)


def fmt(value, spec, none="–"):
    return none if value is None else format(value, spec)


def err(value):
    """An error figure: 4 decimals, or 2 significant digits when that would show zeros."""
    if value is None:
        return "–"
    return f"{value:.4f}" if abs(value) >= 1e-3 or value == 0 else f"{value:.1e}"


def at_time(value, row, reached=None):
    """A Cycles error interpolated at a Photon Splat time, or why there is none."""
    if value is not None:
        return err(value)
    series = row["cycles_series"]
    if series and reached is not None and reached > series[-1]["samples"]:
        return "past Cycles' series"
    if series:
        return f"under 1 sample by the line through its times (1 spp took {series[0]['seconds']:.1f} s)"
    return "–"


def write_markdown(results, args, path):
    lines = []
    add = lines.append
    quick = " (quick smoke run: half size, few samples; not the acceptance figures)" if args.quick else ""
    add("# The world as a light: HDRI, sky and portal scenes against Cycles")
    add("")
    load = ""
    if "load_start" in results:
        load = f" (load average {results['load_start']:.1f} at the start, {results['load_end']:.1f} at the end)"
    add(f"Issue 17's acceptance. Measured {results['date']} at {results['commit']} with Blender "
        f"{results['blender']} on a {os.cpu_count()}-core machine{load}, {args.threads} threads for both renderers"
        f"{quick}:")
    add("")
    add("    " + results["command"])
    add("")
    add("Scenes (blend_scenes/make_world_scenes.py): `world_hdri.blend` (glass sphere, gold torus, white block on a "
        "floor; Blender's studio-light HDRI city.exr, packed), `world_sky.blend` (the same under a Nishita Sky "
        "Texture with its sun disc, and a wall), `world_portal.blend` (a room lit through a window by the same "
        "HDRI, an area light with Portal on filling the window). How each figure is made: the docstring of "
        "tools/world_compare.py; in short: Cycles' converged image is the mean of seeds 1 and 2, its own noise is "
        "given beside each figure (mean: |m1 − m2| / (m1 + m2); block error: relMSE(seed 1, seed 2) / 4); errors "
        "are 8×8-block relMSE against it; times are wall seconds of the whole render (export / sync included).")
    add("")
    if args.quick:
        add(f"In a quick run Cycles' converged image has only {args.cycles_samples} samples: errors against it, "
            "Cycles' own above all, say little; the run shows that the tool works.")
        add("")
    add("Results images: `docs/results/worlds.png`, a row per scene: Cycles converged | Photon Splat at the longest "
        "time | Cycles direct light | Photon Splat's Direct pass (display at each file's exposure).")
    add("")
    add("## Mean against Cycles (acceptance: within 3 % at the longest time)")
    add("")
    add("| scene | size | Cycles mean (noise) | Cycles samples, s | Photon Splat | ratio | pass |")
    add("|---|---|---|---|---|---|---|")
    for label, row in results["scenes"].items():
        c = row["cycles"]
        last = row["photonsplat"][-1]
        ok = abs(last["ratio"] - 1.0) <= MEAN_TOLERANCE
        add(f"| {label} | {row['resolution'][0]}×{row['resolution'][1]} | {c['mean']:.4f} (±{c['mean_noise']:.2%}) "
            f"| {c['samples']}, {c['seconds']:.0f} s | {last['mean']:.4f} ({last['seconds']:.1f} s, "
            f"{last['iterations']} it) | {last['ratio']:.3f} | {'yes' if ok else '**no**'} |")
    add("")
    add("## Time to quality (8×8-block relMSE against converged Cycles, equal wall time)")
    add("")
    add(f"Beside each error, in brackets, the same without the worst {TRIM:.0%} of the blocks: Cycles' fireflies "
        "(the sun seen through glass or off the gold torus by a diffuse bounce) make single blocks, and so the "
        "plain mean, jump by orders of magnitude from one sample count to the next.")
    add("")
    add("| scene | time | Photon Splat (iterations) | mean ratio | Cycles at that time (≈ samples) | "
        "Cycles reference's own error |")
    add("|---|---|---|---|---|---|")
    for label, row in results["scenes"].items():
        for e in row["photonsplat"]:
            cycles = at_time(e["cycles_at_time"], row, e["cycles_samples_at_time"])
            if e["cycles_at_time"] is not None:
                cycles += (f" [{err(e.get('cycles_trimmed_at_time'))}] "
                           f"({e['cycles_samples_at_time']:.0f})")
            add(f"| {label} | {e['seconds']:.1f} s | {err(e['block_relmse'])} [{err(e.get('trimmed_relmse'))}] "
                f"({e['iterations']}) | {e['ratio']:.3f} | {cycles} | {err(row['cycles']['block_floor'])} "
                f"[{err(row['cycles'].get('block_floor_trimmed'))}] |")
    add("")
    add("Cycles' series (seeds 101, 102, ...; each render timed from the call to its end):")
    add("")
    add("| scene | samples | seconds | mean ratio to converged | block relMSE [without the worst 1 %] | "
        "direct relMSE |")
    add("|---|---|---|---|---|---|")
    for label, row in results["scenes"].items():
        for s in row["cycles_series"]:
            add(f"| {label} | {s['samples']} | {s['seconds']:.1f} | {s['mean'] / row['cycles']['mean']:.3f} | "
                f"{err(s['block_relmse'])} [{err(s.get('trimmed_relmse'))}] | {err(s['direct_relmse'])} |")
    add("")
    add("## Direct light at equal time (acceptance: the HDRI scene's Photon Splat error no worse than Cycles')")
    add("")
    add("Direct light = light from the world at the first opaque surface the camera sees (Cycles: DiffDir × DiffCol "
        "+ GlossDir × GlossCol; Photon Splat: its Direct pass), over the 8×8 blocks that see only opaque surfaces "
        "(not background, not glass, nor within 2 pixels of glass: at its rim Cycles' transmission weight fades "
        "while the pixel still shows what lies behind it), 8×8-block relMSE against Cycles' converged direct "
        "image.")
    add("")
    add("| scene | blocks | time | Photon Splat direct | Cycles direct at that time | Cycles reference's own "
        "error | pass |")
    add("|---|---|---|---|---|---|---|")
    for label, row in results["scenes"].items():
        for e in row["photonsplat"]:
            ok = (e["direct_relmse"] is not None and e["cycles_direct_at_time"] is not None
                  and e["direct_relmse"] <= e["cycles_direct_at_time"])
            add(f"| {label} | {row['direct_blocks']} | {e['seconds']:.1f} s | {err(e['direct_relmse'])} | "
                f"{at_time(e['cycles_direct_at_time'], row, e['cycles_samples_at_time'])} | "
                f"{err(row['direct_floor'])} | {'yes' if ok else '**no**'} |")
    add("")
    if "hdri" in results["scenes"] and "caustic" in results["scenes"]["hdri"]:
        row = results["scenes"]["hdri"]
        c = row["caustic"]
        add("## The HDRI sun's caustic (acceptance: energy within 20 % of Cycles')")
        add("")
        add(f"Region: {c['region_blocks']} blocks of 8×8 ({c['region_pixels']} pixels) where rays parallel to the "
            f"HDRI's sun direction, refracted through the glass sphere, land on the floor in view, grown by one "
            f"block (opaque blocks only). Cycles' caustic there: its image with refractive caustics minus without. "
            f"Energy: sum over the region of the mean of R, G, B. Cycles: on {c['cycles_on_region']:.2f}, off "
            f"{c['cycles_off_region']:.2f}, caustic **{c['cycles_energy']:.2f}** "
            f"(noise ±{c['cycles_energy_noise']:.1%}, from the two seeds).")
        add("")
        add("| time | Photon Splat Caustics pass | ratio | Photon Splat combined − Cycles off | pass |")
        add("|---|---|---|---|---|")
        for e in row["photonsplat"]:
            ratio = e.get("caustic_ratio")
            ok = ratio is not None and abs(ratio - 1.0) <= CAUSTIC_TOLERANCE
            add(f"| {e['seconds']:.1f} s | {fmt(e.get('caustic_energy'), '.2f')} | {fmt(ratio, '.3f')} | "
                f"{fmt(e.get('excess_energy'), '.2f')} | {'yes' if ok else '**no**'} |")
        add("")
    add("## Notes from the export")
    add("")
    for label, row in results["scenes"].items():
        notes = row.get("warnings") or []
        add(f"- {label}: " + ("; ".join(notes) if notes else "none"))
    add("")
    add("## How Cycles 3.4 treats these worlds (what the engine must match)")
    add("")
    add("- World MIS (`world.cycles.sampling_method`, default Automatic): the importance map's resolution is the "
        "Environment Texture's image size (here 1024×512); a Nishita sky with its sun disc adds direct sampling of "
        "the sun's cone (Cycles' empirical `sun_weight` 4 beside the map), as long as its Vector input is unlinked "
        "or Texture Coordinate Generated (else a 4096×2048 map); Manual uses `sample_map_resolution`. "
        "Recorded per scene in results.json (`world_sampling`).")
    add("- Blender 3.4's Cycles has no light tree (3.5 brought it): the world is one light among the others, "
        "picked by power, with MIS against BSDF sampling.")
    add("- Portals (`light.cycles.is_portal`): the area light gives no light of its own and is invisible; the world "
        "is sampled through it from points that see it, mixed (MIS) with map sampling.")
    add("- Caustics: Cycles' `caustics_refractive` / `caustics_reflective` (both on here) decide whether a path that "
        "has bounced diffusely may go on through glass / off glossy; the caustic figure above switches the "
        "refractive one off.")
    add("")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    try:
        import bpy  # noqa: F401
    except ImportError:
        run_in_blender(argv)
    else:
        try:
            blender_main(argv)
        except Exception:
            import traceback
            traceback.print_exc()
            sys.exit(1)
