"""The texture gallery: every material of blend_scenes/texture_gallery.blend (image and procedural textures, node
groups, ramps, mixes, bump and normal maps on Principled and other BSDFs) rendered by Cycles and Photon Splat,
compared per material on the probe sphere. Writes docs/results/texture_gallery.md and
docs/results/texture_gallery.png.

    /usr/bin/python3 tools/texture_gallery.py                  # everything
    /usr/bin/python3 tools/texture_gallery.py --only bump_noise --only diffuse_brick
    /usr/bin/python3 tools/texture_gallery.py --cycles-only    # fill the Cycles cache (needs no build)
    /usr/bin/python3 tools/texture_gallery.py --quick          # fewer samples and iterations: a smoke run

Modelled on tools/closure_gallery.py: run with /usr/bin/python3 it starts Debian's Blender (3.4) in the background
with the add-on of `--build` (default build/) and runs itself inside it. Cycles renders are cached in
build/texture_gallery/cycles/, one .npz per material, keyed by a hash of the material's nodes (every property,
ramp stops, curve points, image pixels, groups), the scene and the Cycles settings.

What is measured (acceptance (b) of the shader node programs issue): the mean linear radiance (mean of R, G, B)
over the probe sphere's pixels (all four pixel corners inside its analytic silhouette). `ratio` = Photon Splat /
Cycles; `chroma` = the largest difference of a component of (r, g, b) / (r + g + b) of the two means. A material
passes with |ratio - 1| <= 10 % and chroma <= 0.05; at least 90 % of them must.
Cycles' own noise: the Cycles image is the mean of renders with seeds 1, 2, ... (4 at a time, a quarter of
--cycles-samples each); the standard error of their means, relative, is its noise on the probe mean; while above
--cycles-noise (0.5 %) 4 more seeds are added, up to --cycles-max-samples. Cycles as in closure_gallery.py: CPU, no
denoising, adaptive sampling or clamping, light threshold 0, Filter Glossy 0, box filter 1 px, 16 bounces.
"""
import argparse
import datetime
import hashlib
import json
import os
import platform
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tools"))
from closure_gallery import (commit_of_repo, display, render_exr, run_blender_script, use_cycles_oracle,  # noqa: E402
                             write_png)

OUT_DIR = REPO / "build" / "texture_gallery"
RESULTS_MD = REPO / "docs" / "results" / "texture_gallery.md"
RESULTS_PNG = REPO / "docs" / "results" / "texture_gallery.png"
GALLERY_BLEND = REPO / "blend_scenes" / "texture_gallery.blend"

PS_RATIO, PS_CHROMA, PS_SHARE = 0.10, 0.05, 0.90
BOUNCES = 16
SEEDS = 4

# What was found by looking at a failing material (filled in after a run; name -> text).
DIAGNOSED = {}


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", action="append", default=[], help="a material name; repeatable")
    parser.add_argument("--blend", default=str(GALLERY_BLEND),
                        help="another gallery: a copy of texture_gallery.blend whose scene property 'gallery' "
                             "names other materials (e.g. an artist's, appended into it)")
    parser.add_argument("--quick", action="store_true", help="a smoke run: few samples and iterations")
    parser.add_argument("--cycles-only", action="store_true", help="render and cache Cycles only (no build needed)")
    parser.add_argument("--build", default="build", help="the build folder whose blender/ add-on renders")
    parser.add_argument("--cycles-samples", type=int, help="Cycles samples per pixel, over 4 seeds (default 512, "
                        "quick 64)")
    parser.add_argument("--cycles-noise", type=float, default=0.005,
                        help="Cycles' relative noise on the probe mean to reach (default 0.5 %%)")
    parser.add_argument("--cycles-max-samples", type=int, help="Cycles' sample cap (default 2048, quick 256)")
    parser.add_argument("--photons", type=int, help="Photon Splat photons per iteration (default 1000000, quick 50000)")
    parser.add_argument("--iterations", type=int, help="Photon Splat iterations (default 64, quick 4)")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--report-only", action="store_true",
                        help="rewrite the markdown and the contact sheet from build/texture_gallery/ (no rendering)")
    parser.add_argument("--markdown", default=str(RESULTS_MD))
    parser.add_argument("--png", default=str(RESULTS_PNG))
    parser.add_argument("--blender", default="blender")
    args = parser.parse_args(argv)
    quick = args.quick
    args.cycles_samples = args.cycles_samples or (64 if quick else 512)
    args.cycles_max_samples = args.cycles_max_samples or (256 if quick else 2048)
    args.photons = args.photons or (50000 if quick else 1000000)
    args.iterations = args.iterations or (4 if quick else 64)
    return args


# ---- host side ------------------------------------------------------------------------------------------------

def run_in_blender(argv):
    args = parse_args(argv)
    if args.report_only:
        report_only(args)
        return
    run_blender_script("texture_gallery", __file__, argv, args.blender, None if args.cycles_only else args.build,
                       args.blend, hint="--build, or --cycles-only")


# ---- inside Blender -------------------------------------------------------------------------------------------

def blender_main(argv):
    import bpy
    import numpy as np
    from node_compare import describe_tree

    args = parse_args(argv)
    only = set(args.only)
    for sub in ("cycles", "images"):
        (OUT_DIR / sub).mkdir(parents=True, exist_ok=True)
    core = None
    core_note = None
    if not args.cycles_only:
        from photonsplat import export
        from photonsplat.engine import load_core
        core = load_core()
        if not hasattr(core, "shader_ops"):
            core_note = ("the core has no shader_ops (node programs not built in): Photon Splat renders the "
                         "textures the way the add-on did before them")
    started = time.time()
    timings = {"cycles": 0.0, "photonsplat": 0.0, "cycles_cached": 0}

    def cycles_settings(scene, samples, seed):
        c = use_cycles_oracle(scene, samples, seed, args.threads)
        scene.render.film_transparent = False
        return {k: getattr(c, k) for k in ("samples", "light_sampling_threshold", "filter_width", "max_bounces",
                                           "caustics_reflective", "caustics_refractive", "blur_glossy")}

    def describe_scene(scene):
        bpy.context.view_layer.update()
        desc = {"blender": bpy.app.version_string,
                "resolution": [scene.render.resolution_x, scene.render.resolution_y,
                               scene.render.resolution_percentage],
                "view": [scene.view_settings.view_transform, scene.view_settings.look,
                         scene.view_settings.exposure, scene.view_settings.gamma], "objects": {}}
        if scene.world is not None:
            desc["world"] = describe_tree(scene.world.node_tree) if scene.world.use_nodes else list(scene.world.color)
        for obj in scene.objects:
            entry = {"type": obj.type, "matrix": [round(v, 6) for row in obj.matrix_world for v in row],
                     "visible_camera": obj.visible_camera, "hide_render": obj.hide_render,
                     "materials": [s.material.name if s.material else None for s in obj.material_slots]}
            if obj.type == 'MESH':
                mesh = obj.data
                co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
                mesh.vertices.foreach_get("co", co)
                h = hashlib.sha256(co.tobytes())
                for layer in mesh.uv_layers:
                    uv = np.empty(len(layer.data) * 2, dtype=np.float32)
                    layer.data.foreach_get("uv", uv)
                    h.update(uv.tobytes())
                for attr in mesh.color_attributes:
                    c = np.empty(len(attr.data) * 4, dtype=np.float32)
                    attr.data.foreach_get("color", c)
                    h.update(c.tobytes())
                entry["mesh"] = h.hexdigest()
            elif obj.type == 'LIGHT':
                light = obj.data
                entry["light"] = {k: (list(getattr(light, k)) if k == "color" else getattr(light, k))
                                  for k in ("type", "energy", "color", "shadow_soft_size", "angle", "size")
                                  if hasattr(light, k)}
            elif obj.type == 'CAMERA':
                cam = obj.data
                entry["camera"] = [cam.type, cam.lens, cam.sensor_width, cam.sensor_fit, cam.clip_start,
                                   cam.clip_end]
            desc["objects"][obj.name] = entry
        return desc

    def relative_noise(images, mask):
        means = np.array([im[..., :3][mask].mean() for im in images])
        return float(means.std(ddof=1) / np.sqrt(len(means)) / max(abs(means.mean()), 1e-12))

    def cycles_image(name, scene, mask):
        per_seed = max(1, args.cycles_samples // SEEDS)
        settings = cycles_settings(scene, per_seed, 1)
        policy = {"per_seed": per_seed, "seeds": SEEDS, "noise": args.cycles_noise,
                  "max_samples": max(args.cycles_max_samples, args.cycles_samples)}
        materials = sorted({s.material.name for o in scene.objects for s in o.material_slots if s.material})
        key_data = {"scene": describe_scene(scene), "cycles": settings, "policy": policy, "mask": int(mask.sum()),
                    "materials": {n: describe_tree(bpy.data.materials[n].node_tree) for n in materials}}
        key = hashlib.sha256(json.dumps(key_data, sort_keys=True, default=str).encode()).hexdigest()[:16]
        path = OUT_DIR / "cycles" / f"{name}-{key}.npz"
        if path.exists():
            timings["cycles_cached"] += 1
            data = np.load(path)
            images, seconds = data["images"], float(data["seconds"])
        else:
            t0 = time.perf_counter()
            images = []
            while True:
                for _ in range(SEEDS):
                    cycles_settings(scene, per_seed, len(images) + 1)
                    images.append(render_exr(scene, OUT_DIR / f"cycles_tmp_{os.getpid()}.exr"))
                noise = relative_noise(images, mask)
                if noise <= args.cycles_noise or (len(images) + SEEDS) * per_seed > policy["max_samples"]:
                    break
                print(f"texture_gallery:   Cycles noise {noise:.2%} at {len(images) * per_seed} samples: "
                      f"{SEEDS} more seeds", flush=True)
            images = np.stack(images)
            seconds = time.perf_counter() - t0
            timings["cycles"] += seconds
            np.savez_compressed(path, images=images, seconds=seconds)
            path.with_suffix(".json").write_text(json.dumps(key_data, sort_keys=True, default=str, indent=0))
        return images.mean(axis=0), relative_noise(images, mask), len(images) * per_seed, seconds

    def photonsplat_image(scene):
        ps = scene.photonsplat
        ps.photons = args.photons
        ps.iterations = args.iterations
        ps.time_limit = 0.0
        ps.radius = 0.0
        ps.seed = 1
        ps.threads = args.threads
        if hasattr(ps, "max_bounces"):
            ps.max_bounces = BOUNCES
        scene.render.engine = 'PHOTONSPLAT'
        t0 = time.perf_counter()
        frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
        image, stats = core.render(frame.scene, frame.camera, frame.settings)
        seconds = time.perf_counter() - t0
        timings["photonsplat"] += seconds
        return np.asarray(image, dtype=np.float32), list(frame.warnings), seconds

    def sphere_mask(scene, center, radius):
        """Pixels (top-down) whose four corners all see the sphere (the closure gallery's analytic mask)."""
        cam_obj = scene.camera
        cam = cam_obj.data
        width, height = scene.render.resolution_x, scene.render.resolution_y
        half_w = 0.5 * cam.sensor_width / cam.lens
        sx, sy = (half_w, half_w * height / width) if width >= height else (half_w * width / height, half_w)
        gx, gy = np.meshgrid(np.linspace(-sx, sx, width + 1), np.linspace(sy, -sy, height + 1))
        local = np.stack([gx, gy, -np.ones_like(gx)], axis=-1)
        m = np.array(cam_obj.matrix_world)
        dirs = local @ m[:3, :3].T
        dirs /= np.linalg.norm(dirs, axis=-1, keepdims=True)
        oc = m[:3, 3] - np.asarray(center)
        b = dirs @ oc
        hit = (b * b - (oc @ oc - radius * radius)) > 0.0
        return hit[:-1, :-1] & hit[1:, :-1] & hit[:-1, 1:] & hit[1:, 1:]

    def mean_rgb(image, mask):
        return image[..., :3][mask].astype(np.float64).mean(axis=0)

    def chroma(rgb):
        return rgb / max(rgb.sum(), 1e-12)

    scene = bpy.context.scene
    names = list(scene["gallery"])
    if only:
        names = [n for n in names if n in only]
    probe = bpy.data.objects["Probe"]
    bpy.context.view_layer.update()
    mask = sphere_mask(scene, tuple(scene["probe_center"]), float(scene["probe_radius"]))
    rows, sheet = [], []
    for index, name in enumerate(names):
        probe.material_slots[0].material = bpy.data.materials[name]
        print(f"texture_gallery: [{index + 1}/{len(names)}] {name}", flush=True)
        cyc, noise, spp, cycles_seconds = cycles_image(name, scene, mask)
        mc = mean_rgb(cyc, mask)
        row = {"name": name, "cycles_mean": float(mc.mean()), "cycles_rgb": mc.tolist(), "cycles_noise": noise,
               "cycles_samples": spp, "seconds": {"cycles": cycles_seconds}}
        if core is None:
            rows.append(row)
            sheet.append((cyc,))
            np.savez_compressed(OUT_DIR / "images" / f"{name}.npz", cycles=cyc)
            print(f"texture_gallery:   Cycles {row['cycles_mean']:.4f} (noise {noise:.2%}, {spp} spp, "
                  f"{cycles_seconds:.1f} s)", flush=True)
            continue
        try:
            ours, warnings, ps_seconds = photonsplat_image(scene)
        except Exception as error:
            row.update({"error": f"{type(error).__name__}: {error}", "ps_pass": False, "warnings": []})
            rows.append(row)
            sheet.append((cyc, np.zeros_like(cyc)))
            print(f"texture_gallery:   ERROR {row['error']}", flush=True)
            continue
        mp = mean_rgb(ours, mask)
        row.update({"ps_ratio": float(mp.mean() / max(mc.mean(), 1e-12)),
                    "ps_chroma": float(np.abs(chroma(mp) - chroma(mc)).max()),
                    "ps_image_ratio": float(ours[..., :3].mean() / max(cyc[..., :3].mean(), 1e-12)),
                    "warnings": warnings})
        row["seconds"]["photonsplat"] = ps_seconds
        row["ps_pass"] = abs(row["ps_ratio"] - 1.0) <= PS_RATIO and row["ps_chroma"] <= PS_CHROMA
        rows.append(row)
        sheet.append((cyc, ours))
        np.savez_compressed(OUT_DIR / "images" / f"{name}.npz", cycles=cyc, ours=ours)
        print(f"texture_gallery:   Cycles {row['cycles_mean']:.4f} (noise {noise:.2%}, {cycles_seconds:.1f} s)  PS "
              f"ratio {row['ps_ratio']:.3f} chroma {row['ps_chroma']:.3f} ({ps_seconds:.1f} s)  "
              f"{'pass' if row['ps_pass'] else 'FAIL'}", flush=True)

    results = {"gallery": rows, "timings": timings, "wall_seconds": time.time() - started,
               "args": dict(vars(args)), "core_note": core_note,
               "photonsplat_version": getattr(core, "__version__", "?") if core is not None else None,
               "blender": bpy.app.version_string, "commit": commit_of_repo(),
               "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}
    (OUT_DIR / "results.json").write_text(json.dumps(results, indent=1))
    if only:
        print("texture_gallery: --only: the markdown and the contact sheet are left as they are "
              f"(results in {OUT_DIR / 'results.json'})")
        return
    write_markdown(results, Path(args.markdown))
    write_sheet(sheet, Path(args.png), np)


def report_only(args):
    import numpy as np
    results = json.loads((OUT_DIR / "results.json").read_text())
    sheet = []
    for r in results["gallery"]:
        data = np.load(OUT_DIR / "images" / f"{r['name']}.npz")
        sheet.append(tuple(data[k] for k in ("cycles", "ours") if k in data))
    write_markdown(results, Path(args.markdown))
    write_sheet(sheet, Path(args.png), np)


def write_markdown(results, path):
    rows = results["gallery"]
    a = argparse.Namespace(**results["args"])
    t = results["timings"]
    cpu = ""
    try:
        cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    cycles_only = results["args"].get("cycles_only")
    command = "/usr/bin/python3 tools/texture_gallery.py" + (" --quick" if a.quick else "") + (
        " --cycles-only" if cycles_only else "")
    lines = ["# Texture gallery: Photon Splat against Cycles", "",
             f"Generated by `{command}` on {results['date']}, commit {results['commit']}"
             + (f", Photon Splat {results['photonsplat_version']} (add-on of `{a.build}/blender`)"
                if results.get("photonsplat_version") else "")
             + f", Blender {results['blender']} (Debian) for Cycles; {platform.machine()} {cpu}, {os.cpu_count()} "
             f"cores, {a.threads} render threads. Wall time {results['wall_seconds'] / 60:.1f} min (Cycles "
             f"{t['cycles']:.0f} s for the renders not in the cache, {t['cycles_cached']} taken from it; Photon "
             f"Splat {t['photonsplat']:.0f} s).",
             "",
             "Scene: `blend_scenes/texture_gallery.blend` (`make_texture_gallery.py`): the closure gallery's probe "
             "sphere (UV map, a vertex colour attribute) over a grey floor, sun (3 W/m², 2°), 0.2 m point light and "
             "grey world, seen through a 70 mm lens at 96×96; the materials use image textures (packed 16×16 float "
             "and sRGB images, a 32×32 normal map), procedural textures, node groups, colour ramps, Mix RGB, Bump, "
             "Normal Map, converters, on Principled, Diffuse, Glossy, Anisotropic, Velvet, Emission and Mix / Add "
             f"shaders. Cycles {a.cycles_samples} samples per pixel over four seeds (4 more at a time, up to "
             f"{a.cycles_max_samples}, while the noise of the probe mean is above {a.cycles_noise:.1%}), CPU, no "
             f"denoising, adaptive sampling or clamping, box filter 1 px, {BOUNCES} bounces, cached in "
             "`build/texture_gallery/cycles/`"
             + ("." if cycles_only else f"; Photon Splat progressive, {a.iterations} iterations of "
                f"{a.photons:,} photons, automatic radius."),
             "",
             "Measure: mean linear radiance over the probe's pixels (all four corners inside its analytic "
             "silhouette). *ratio* = Photon Splat / Cycles; *chroma* = largest component difference of (r, g, b)/"
             "(r+g+b) of the means; *image* = whole-image ratio (for information). Pass (acceptance (b)): "
             f"|ratio − 1| ≤ {PS_RATIO:.0%} and chroma ≤ {PS_CHROMA}, required for ≥ {PS_SHARE:.0%} of the "
             "materials. *Cycles noise* = relative standard error of Cycles' probe mean from the seeds' spread.",
             ""]
    if results.get("core_note"):
        lines += [f"**Note:** {results['core_note']}.", ""]
    noise = [r["cycles_noise"] for r in rows]
    rms = (sum(n * n for n in noise) / max(len(noise), 1)) ** 0.5
    if cycles_only:
        lines += ["**Cycles only**: Photon Splat was not run (`--cycles-only`).", "",
                  f"- Cycles' own noise on the probe mean: RMS {rms:.2%}, largest {max(noise):.2%}.", "",
                  "| # | material | Cycles mean | Cycles rgb | Cycles noise | spp |", "|---|---|---|---|---|---|"]
        for i, r in enumerate(rows, 1):
            lines.append(f"| {i} | `{r['name']}` | {r['cycles_mean']:.4f} | "
                         f"{', '.join(f'{c:.3f}' for c in r['cycles_rgb'])} | {r['cycles_noise']:.2%} | "
                         f"{r['cycles_samples']} |")
    else:
        passed = sum(bool(r.get("ps_pass")) for r in rows)
        lines += ["## Summary", "",
                  f"- Photon Splat: **{passed} / {len(rows)}** materials pass ({passed / max(len(rows), 1):.0%}; "
                  f"required ≥ {PS_SHARE:.0%}): **{'met' if passed >= PS_SHARE * len(rows) else 'not met'}**.",
                  f"- Cycles' own noise on the probe mean: RMS {rms:.2%}, largest {max(noise):.2%}."]
        measured = [r for r in rows if "ps_ratio" in r]
        if measured:
            lo, hi = min(measured, key=lambda r: r["ps_ratio"]), max(measured, key=lambda r: r["ps_ratio"])
            ch = max(measured, key=lambda r: r["ps_chroma"])
            lines.append(f"- Ratios from {lo['ps_ratio']:.3f} (`{lo['name']}`) to {hi['ps_ratio']:.3f} "
                         f"(`{hi['name']}`); largest chroma {ch['ps_chroma']:.3f} (`{ch['name']}`).")
        lines += ["", "## Per material", "",
                  "| # | material | Cycles mean | Cycles noise | spp | PS ratio | PS chroma | PS image | PS | "
                  "Photon Splat's export notes |", "|---|---|---|---|---|---|---|---|---|---|"]
        for i, r in enumerate(rows, 1):
            if r.get("error"):
                lines.append(f"| {i} | `{r['name']}` | {r['cycles_mean']:.4f} | {r['cycles_noise']:.2%} | "
                             f"{r['cycles_samples']} | – | – | – | **ERROR** | {r['error']} |")
                continue
            notes = "; ".join(r["warnings"]).replace("|", "\\|") or "–"
            lines.append(f"| {i} | `{r['name']}` | {r['cycles_mean']:.4f} | {r['cycles_noise']:.2%} | "
                         f"{r['cycles_samples']} | {r['ps_ratio']:.3f} | {r['ps_chroma']:.3f} | "
                         f"{r['ps_image_ratio']:.3f} | {'pass' if r['ps_pass'] else '**FAIL**'} | {notes} |")
        failing = [r for r in rows if not r.get("ps_pass")]
        if failing:
            lines += ["", "### Failures", "",
                      "The cause printed is the exporter's own note (what it approximated) or what was diagnosed; "
                      "the images are in `build/texture_gallery/images/`.", ""]
            for r in failing:
                if r.get("error"):
                    lines.append(f"- `{r['name']}`: {r['error']}")
                    continue
                why = DIAGNOSED.get(r["name"]) or "; ".join(r["warnings"]) or "no export note"
                lines.append(f"- `{r['name']}`: ratio {r['ps_ratio']:.3f}, chroma {r['ps_chroma']:.3f}: {why}")
    lines += ["", "## Contact sheet", "",
              "`texture_gallery.png`: four materials per row, in the table's order, each as "
              + ("Cycles alone" if cycles_only else "Cycles | Photon Splat") + ", display sRGB clipped to [0, 1].",
              ""]
    path.write_text("\n".join(lines) + "\n")
    print(f"texture_gallery: wrote {path}")


def write_sheet(rows, path, np):
    if not rows:
        return
    tile, columns = 64, 4
    tiles = []
    for group in rows:
        shrunk = []
        for image in group:
            h, w = image.shape[:2]
            ys = (np.arange(tile) * h / tile).astype(int)
            xs = (np.arange(tile) * w / tile).astype(int)
            shrunk.append(display(image[ys][:, xs]))
        gap = np.full((tile, 2, 3), 255, np.uint8)
        parts = []
        for s in shrunk:
            parts += [s, gap]
        tiles.append(np.concatenate(parts[:-1], axis=1))
    blank = np.zeros_like(tiles[0])
    while len(tiles) % columns:
        tiles.append(blank)
    sep = np.full((tile, 8, 3), 255, np.uint8)
    lines = []
    for k in range(0, len(tiles), columns):
        parts = []
        for t in tiles[k:k + columns]:
            parts += [t, sep]
        lines.append(np.concatenate(parts[:-1], axis=1))
        lines.append(np.full((6, lines[-1].shape[1], 3), 255, np.uint8))
    write_png(path, np.concatenate(lines[:-1], axis=0))
    print(f"texture_gallery: wrote {path}")


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
