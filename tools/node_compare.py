"""Shader node programs, pixel by pixel: every case of blend_scenes/make_node_planes.py (a node driving an Emission
shader on a plane that fills an orthographic camera) rendered by Cycles and by Photon Splat, compared per pixel.
Writes docs/results/node_programs.md.

    /usr/bin/python3 tools/node_compare.py                       # every case (Cycles cached after the first run)
    /usr/bin/python3 tools/node_compare.py --only noise_3d_fac --only math_sqrt
    /usr/bin/python3 tools/node_compare.py --match voronoi       # cases whose name contains "voronoi"
    /usr/bin/python3 tools/node_compare.py --cycles-only         # fill the Cycles cache; needs no build

Run with /usr/bin/python3 it starts Debian's Blender (3.4) in the background with the add-on of `--build`
(default build/, i.e. BLENDER_USER_SCRIPTS=build/blender) and runs itself inside it. --cycles-only needs no add-on.

Cycles: CPU, 1 sample, box pixel filter of width 0.01 pixel (its one sample lies within 0.005 pixel of the
centre), no denoising, no adaptive sampling, 0 bounces (the emission is seen directly), EXR float. Cached in
build/node_compare/cycles/<case>-<hash>.npz, the hash over the case's nodes (every property, ramp and curve
points, image pixels), the scene (objects, meshes, camera, view settings) and these settings.
Photon Splat: the add-on's export (export_frame) and core.render with one iteration, whose camera rays go through
the pixel centres (view_samples.h: only progressive iterations after the first jitter), and few photons (the
planes show emission alone).

Measure, per case (acceptance (a) of the node programs issue): rel = mean over pixels and RGB of |ours - Cycles|
divided by the mean of |Cycles| (floored at 1e-3, so that a black case compares absolutely); pass: rel <= 1e-3
for deterministic nodes, <= 1e-2 for the noise-based ones (noise, voronoi, musgrave, wave with distortion, magic,
white noise; the case's class comes from the generator). Also the largest pixel difference and the number of
"edge" pixels (difference above 10 % of the mean): a handful of those on an otherwise exact case is a pixel whose
Cycles sample fell on the other side of a discontinuity (Cycles' sample is up to 0.005 pixel from the centre).
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
OUT_DIR = REPO / "build" / "node_compare"
RESULTS_MD = REPO / "docs" / "results" / "node_programs.md"
THRESHOLD = {"deterministic": 1e-3, "noise": 1e-2}
EDGE = 0.1                 # a pixel differing by more than this fraction of the mean is an "edge" pixel
MEAN_FLOOR = 1e-3

# What was found by looking at a failing case (name -> text), 25 Nov 2026 at the merge of "programs: end to end"
# (9275481). main's eb5cb96, later, addresses the sRGB order, float alpha, signed emission and bump reflection.
_SRGB_ORDER = (
    "Cycles interpolates an 8-bit sRGB image's encoded values and decodes the result (NODE_IMAGE_COMPRESS_AS_SRGB); "
    "Photon Splat decodes the texels first and then interpolates. Checked against both orders computed from the "
    "image: Cycles matches interpolate-then-decode to 3.6e-5 (mean |diff|), ours decode-then-interpolate to 2.8e-7. "
    "Closest interpolation, where the order does not matter, passes (`image_grid_byte_closest`).")
DIAGNOSED = {
    "image_grid_byte_linear": _SRGB_ORDER, "image_grid_byte_cubic": _SRGB_ORDER,
    "image_grid_byte_smart": _SRGB_ORDER, "image_grid_byte_extend": _SRGB_ORDER,
    "image_grid_byte_clip": _SRGB_ORDER,
    "image_grid_float_alpha_color": (
        "A float image with alpha below 1 (Blender's default alpha mode, Straight): Cycles' Color output is the "
        "stored colour (equal to the same image made opaque), ours is the colour multiplied by alpha (the "
        "image_texture op's alpha param 1), so 0.654 of it on average (the image's mean alpha is 0.65). The Alpha "
        "output agrees (`image_grid_float_alpha`)."),
    "math_subtract_signed": (
        "Kept signed on purpose: Cycles renders negative emission as it is, the core at 9275481 clamps a program's "
        "emission at 0 (materials.cpp); ours equals max(Cycles, 0) to 9.3e-6, so the node agrees."),
    "bump_wave_height": (
        "Bump of a height with an 11-pixel period (a scale-1.5 wave) on the dome: ours tilts the normal 2 degrees "
        "more on average (39.4 against 37.4 degrees from +Z) while smooth heights agree to 5e-6 (`bump_checker_height`, "
        "`bump_invert_noise`): a different finite-difference step (the ray differential on the inclined surface) "
        "is the likely cause."),
    "fresnel_of_bumped_normal": "Fresnel of the normal of `bump_wave_height`: the Bump's difference (Fresnel alone passes).",
    "sky_hosek": (
        "Approximated on purpose: the Hosek / Wilkie model's dataset is not reproduced, the sky_texture op evaluates "
        "Preetham's sky for the same sun direction and turbidity (the compiler notes it). Preetham itself passes "
        "(`sky_preetham`)."),
}


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", action="append", default=[], help="a case name; repeatable")
    parser.add_argument("--match", action="append", default=[], help="cases whose name contains this; repeatable")
    parser.add_argument("--size", type=int, default=64, help="pixels per side (default 64)")
    parser.add_argument("--cycles-only", action="store_true", help="render and cache Cycles only (no build needed)")
    parser.add_argument("--build", default="build", help="the build folder whose blender/ add-on renders")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--report-only", action="store_true", help="rewrite the markdown from results.json")
    parser.add_argument("--markdown", default=str(RESULTS_MD))
    parser.add_argument("--blender", default="blender")
    return parser.parse_args(argv)


# ---- host side ------------------------------------------------------------------------------------------------

def run_in_blender(argv):
    args = parse_args(argv)
    if args.report_only:
        results = json.loads((OUT_DIR / "results.json").read_text())
        write_markdown(results, Path(args.markdown))
        return
    sys.path.insert(0, str(REPO / "tools"))
    from closure_gallery import run_blender_script
    run_blender_script("node_compare", __file__, argv, args.blender, None if args.cycles_only else args.build,
                       hint="--build, or --cycles-only")


# ---- inside Blender: shared with tests/blender/test_node_pixels.py -------------------------------------------

def describe_tree(tree):
    """A node tree as JSON-able data: every node's properties, colour ramp stops, curve points, image pixels
    (hashed), node groups (recursively), input values and links."""
    import bpy
    import numpy as np

    def value(v):
        if isinstance(v, float):
            return round(v, 7)
        if isinstance(v, (int, bool, str)) or v is None:
            return v
        if isinstance(v, bpy.types.ID):
            return v.name
        try:
            return [value(x) for x in v]
        except TypeError:
            return str(v)

    def props(struct):
        out = {}
        for p in struct.bl_rna.properties:
            if p.identifier in ("rna_type", "name", "label", "location", "width", "height", "width_hidden",
                                "dimensions", "select", "show_options", "show_preview", "show_texture", "hide",
                                "mute", "parent", "use_custom_color", "color", "bl_idname", "bl_label",
                                "bl_description", "bl_icon", "bl_static_type", "bl_width_default",
                                "bl_width_min", "bl_width_max", "bl_height_default", "bl_height_min",
                                "bl_height_max", "type", "inputs", "outputs", "internal_links", "texture_mapping",
                                "color_mapping", "image_user", "interface"):
                continue
            if p.type in ('POINTER', 'COLLECTION') and p.identifier not in ("image", "node_tree", "object"):
                continue
            try:
                out[p.identifier] = value(getattr(struct, p.identifier))
            except (AttributeError, TypeError):
                pass
        return out

    def tree_desc(tree):
        nodes = []
        for node in sorted(tree.nodes, key=lambda n: n.name):
            entry = {"name": node.name, "type": node.bl_idname, "props": props(node)}
            if getattr(node, "color_ramp", None) is not None:
                r = node.color_ramp
                entry["ramp"] = [r.interpolation, r.color_mode, r.hue_interpolation,
                                 [[round(e.position, 6), value(e.color)] for e in r.elements]]
            if getattr(node, "mapping", None) is not None:
                m = node.mapping
                entry["curves"] = [[[value(p.location), p.handle_type] for p in c.points] for c in m.curves]
                entry["curve_range"] = [m.clip_min_x, m.clip_max_x, m.use_clip, value(m.black_level),
                                        value(m.white_level)]
            image = getattr(node, "image", None)
            if image is not None:
                px = np.empty(len(image.pixels), dtype=np.float32)
                image.pixels.foreach_get(px)
                entry["image"] = [image.name, list(image.size), image.colorspace_settings.name, image.is_float,
                                  image.alpha_mode, hashlib.sha256(px.tobytes()).hexdigest()]
            if getattr(node, "node_tree", None) is not None:
                entry["group"] = tree_desc(node.node_tree)
            entry["inputs"] = [[s.identifier, value(getattr(s, "default_value", None)), s.is_linked]
                               for s in node.inputs]
            nodes.append(entry)
        links = sorted([l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier]
                       for l in tree.links)
        return {"nodes": nodes, "links": links}

    return tree_desc(tree)


def describe_case(material_name):
    """What a case's Cycles image depends on, as JSON-able data: its node tree (every property), the objects,
    meshes, images and camera of the scene, and the view settings."""
    import bpy
    import numpy as np

    scene = bpy.context.scene
    bpy.context.view_layer.update()        # matrix_world of new objects is set by the depsgraph
    desc = {"blender": bpy.app.version_string, "material": describe_tree(bpy.data.materials[material_name].node_tree),
            "resolution": [scene.render.resolution_x, scene.render.resolution_y,
                           scene.render.resolution_percentage],
            "view": [scene.view_settings.view_transform, scene.view_settings.look, scene.view_settings.exposure,
                     scene.view_settings.gamma], "objects": {}}
    for obj in scene.objects:
        entry = {"type": obj.type, "matrix": [round(v, 6) for row in obj.matrix_world for v in row],
                 "hide_render": obj.hide_render, "pass_index": obj.pass_index,
                 "color": [round(c, 6) for c in obj.color]}
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
            smooth = np.empty(len(mesh.polygons), dtype=bool)
            mesh.polygons.foreach_get("use_smooth", smooth)
            h.update(smooth.tobytes())
            entry["mesh"] = h.hexdigest()
            entry["materials"] = [m.name if m else None for m in mesh.materials]
        elif obj.type == 'CAMERA':
            cam = obj.data
            entry["camera"] = [cam.type, cam.ortho_scale, cam.lens, cam.sensor_fit, cam.clip_start, cam.clip_end]
        desc["objects"][obj.name] = entry
    return desc


def cycles_plane_settings(scene, threads=2):
    """Cycles as the node comparison needs it; returns the settings that enter the cache key."""
    scene.render.engine = 'CYCLES'
    c = scene.cycles
    c.device = 'CPU'
    c.samples = 1
    c.seed = 0
    c.use_animated_seed = False
    c.use_denoising = False
    c.use_adaptive_sampling = False
    c.pixel_filter_type = 'BOX'
    c.filter_width = 0.01
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.max_bounces = 0
    c.use_auto_tile = False
    scene.render.threads_mode = 'FIXED'
    scene.render.threads = threads
    scene.render.film_transparent = False
    return {"samples": 1, "filter": ["BOX", 0.01], "max_bounces": 0, "seed": 0}


def render_cycles(path):
    """Render the current scene with bpy.ops into the OpenEXR `path`; float32 (h, w, 4), row 0 at the top."""
    import bpy
    sys.path.insert(0, str(REPO / "tools"))
    from closure_gallery import render_exr
    return render_exr(bpy.context.scene, path)


def cycles_case(name, cache_dir, threads=2):
    """Cycles' image of case `name` (already put on its object by use_case), cached by hash under cache_dir.
    Returns (image, seconds, cached)."""
    import bpy
    import numpy as np
    scene = bpy.context.scene
    settings = cycles_plane_settings(scene, threads)
    key_data = {"case": describe_case(name), "cycles": settings}
    key = hashlib.sha256(json.dumps(key_data, sort_keys=True, default=str).encode()).hexdigest()[:16]
    cache_dir = Path(cache_dir)
    cache_dir.mkdir(parents=True, exist_ok=True)
    path = cache_dir / f"{name}-{key}.npz"
    if path.exists():
        data = np.load(path)
        return data["image"], float(data["seconds"]), True
    t0 = time.perf_counter()
    image = render_cycles(cache_dir / f"tmp-{os.getpid()}.exr")
    seconds = time.perf_counter() - t0
    np.savez_compressed(path, image=image, seconds=seconds)
    path.with_suffix(".json").write_text(json.dumps(key_data, sort_keys=True, default=str, indent=0))
    return image, seconds, False


def photonsplat_case(core, threads=2):
    """Photon Splat's image of the scene as it is: one iteration (pixel-centred camera rays), few photons.
    Returns (image (h, w, 4) top-down, export notes, seconds)."""
    import bpy
    import numpy as np
    from photonsplat import export
    scene = bpy.context.scene
    ps = scene.photonsplat
    ps.photons = 1000
    ps.iterations = 1
    ps.time_limit = 0.0
    ps.radius = 0.0
    ps.seed = 1
    ps.threads = threads
    scene.render.engine = 'PHOTONSPLAT'
    t0 = time.perf_counter()
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())
    image, _stats = core.render(frame.scene, frame.camera, frame.settings)
    return np.asarray(image, dtype=np.float32), list(frame.warnings), time.perf_counter() - t0


def compare(cycles, ours, cls):
    """The per-case measure of acceptance (a)."""
    import numpy as np
    c = cycles[..., :3].astype(np.float64)
    o = ours[..., :3].astype(np.float64)
    diff = np.abs(o - c)
    mean = float(np.abs(c).mean())
    denom = max(mean, MEAN_FLOOR)
    rel = float(diff.mean() / denom)
    pixel = diff.max(axis=-1)
    edge = int((pixel > EDGE * denom).sum())
    # the measure without the edge pixels: a case that is exact but for a few pixels on discontinuities
    keep = pixel <= EDGE * denom
    rel_inner = float(diff[keep].mean() / denom) if keep.any() else rel
    return {"cycles_mean": mean, "ours_mean": float(np.abs(o).mean()), "rel": rel, "rel_inner": rel_inner,
            "max": float(diff.max()), "edge_pixels": edge, "pixels": int(pixel.size),
            "ratio": float(o.mean() / c.mean()) if abs(c.mean()) > 1e-12 else float("nan"),
            "ours_constant": bool(np.ptp(o) < 1e-7), "cycles_constant": bool(np.ptp(c) < 1e-7),
            "finite": bool(np.isfinite(o).all()),
            "pass": bool(np.isfinite(o).all() and rel <= THRESHOLD[cls])}


def likely_cause(row):
    """A first guess at why a case fails, from its numbers and the export's notes."""
    if row.get("error"):
        return f"render failed: {row['error']}"
    notes = "; ".join(row.get("warnings", []))
    if not row["finite"]:
        return "non-finite pixels in Photon Splat's image"
    if row["ours_constant"] and not row["cycles_constant"]:
        guess = "Photon Splat's image is constant: the node (or its input) is not evaluated per point"
    elif row["edge_pixels"] and row["rel_inner"] <= THRESHOLD[row["class"]]:
        guess = (f"exact but for {row['edge_pixels']} pixels on discontinuities (Cycles' sample up to 0.005 px "
                 "off the centre, or a float rounding at a step)")
    elif abs(row["ratio"] - 1.0) > 0.05 and row["rel"] < 2 * abs(row["ratio"] - 1.0) + 0.01:
        guess = f"overall level off (mean ratio {row['ratio']:.3f}): a scale, colour space or conversion"
    else:
        guess = "values differ across the image: the node's evaluation differs (see the images in build/node_compare/images/)"
    if notes:
        guess = f"export notes: {notes}. {guess}"
    return DIAGNOSED.get(row["name"], guess)


def blender_main(argv):
    import bpy
    import numpy as np

    args = parse_args(argv)
    sys.path.insert(0, str(REPO / "blend_scenes"))
    import make_node_planes as planes

    names = [c[0] for c in planes.CASES]
    if args.only:
        names = [n for n in names if n in args.only]
    if args.match:
        names = [n for n in names if any(m in n for m in args.match)]
    cases = planes.build(args.size, names)
    core = None
    core_note = None
    if not args.cycles_only:
        from photonsplat.engine import load_core
        core = load_core()
        if not hasattr(core, "shader_ops"):
            core_note = ("the core has no shader_ops (node programs not built in): Photon Splat renders the "
                         "nodes the way the add-on did before them")
    (OUT_DIR / "images").mkdir(parents=True, exist_ok=True)
    started = time.time()
    rows = []
    t_cycles = t_ps = 0.0
    cached = 0
    for index, (name, cls, obj, node) in enumerate(cases):
        planes.use_case(name)
        cyc, seconds, was_cached = cycles_case(name, OUT_DIR / "cycles", args.threads)
        cached += was_cached
        t_cycles += 0.0 if was_cached else seconds
        row = {"name": name, "class": cls, "object": obj, "node": node}
        if core is None:
            row.update({"cycles_mean": float(np.abs(cyc[..., :3]).mean())})
            print(f"node_compare: [{index + 1}/{len(cases)}] {name}: Cycles mean {row['cycles_mean']:.4f}"
                  f"{' (cached)' if was_cached else f' ({seconds:.1f} s)'}", flush=True)
            rows.append(row)
            continue
        try:
            ours, warnings, ps_seconds = photonsplat_case(core, args.threads)
        except Exception as error:           # a case the export or core refuses: recorded, the run goes on
            row.update({"error": f"{type(error).__name__}: {error}", "pass": False, "warnings": [],
                        "cycles_mean": float(np.abs(cyc[..., :3]).mean())})
            rows.append(row)
            print(f"node_compare: [{index + 1}/{len(cases)}] {name}: ERROR {row['error']}", flush=True)
            continue
        t_ps += ps_seconds
        row.update(compare(cyc, ours, cls))
        row["warnings"] = warnings
        np.savez_compressed(OUT_DIR / "images" / f"{name}.npz", cycles=cyc, ours=ours)
        rows.append(row)
        print(f"node_compare: [{index + 1}/{len(cases)}] {name}: rel {row['rel']:.2e} max {row['max']:.3g} "
              f"edge {row['edge_pixels']} {'pass' if row['pass'] else 'FAIL'}", flush=True)
    for row in rows:
        if "pass" in row and not row["pass"]:
            row["cause"] = likely_cause(row)
    results = {"rows": rows, "size": args.size, "cycles_only": args.cycles_only, "core_note": core_note,
               "blender": bpy.app.version_string, "cycles_seconds": t_cycles, "cycles_cached": cached,
               "photonsplat_seconds": t_ps, "wall_seconds": time.time() - started,
               "command": "/usr/bin/python3 tools/node_compare.py " + " ".join(argv),
               "commit": commit_of_repo(),
               "photonsplat_version": getattr(core, "__version__", "?") if core is not None else None,
               "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}
    OUT_DIR.mkdir(parents=True, exist_ok=True)
    (OUT_DIR / "results.json").write_text(json.dumps(results, indent=1))
    if core is not None:
        write_failure_sheet([r["name"] for r in rows if not r.get("pass") and not r.get("error")],
                            OUT_DIR / "failures.png")
    if args.only or args.match:
        print(f"node_compare: --only/--match: the markdown is left as it is (results in {OUT_DIR / 'results.json'})")
        return
    write_markdown(results, Path(args.markdown))


def write_failure_sheet(names, path):
    """Cycles | Photon Splat | 10 x |difference| for each failing case, four per row (display sRGB, clipped)."""
    import numpy as np
    sys.path.insert(0, str(REPO / "tools"))
    from closure_gallery import display, write_png
    if not names:
        return
    tiles = []
    for name in names:
        data = np.load(OUT_DIR / "images" / f"{name}.npz")
        c, o = data["cycles"], data["ours"]
        d = np.abs(o - c) * 10.0
        gap = np.full((c.shape[0], 2, 3), 255, np.uint8)
        tiles.append(np.concatenate([display(c), gap, display(o), gap, display(d)], axis=1))
    blank = np.zeros_like(tiles[0])
    while len(tiles) % 4:
        tiles.append(blank)
    rows = [np.concatenate(sum(([t, np.full((t.shape[0], 8, 3), 255, np.uint8)] for t in tiles[k:k + 4]), [])[:-1],
                           axis=1) for k in range(0, len(tiles), 4)]
    sheet = np.concatenate(sum(([r, np.full((6, r.shape[1], 3), 255, np.uint8)] for r in rows), [])[:-1], axis=0)
    write_png(path, sheet)
    (path.with_suffix(".txt")).write_text("\n".join(names) + "\n")
    print(f"node_compare: wrote {path} (failing cases, in the order of {path.with_suffix('.txt')})")


def commit_of_repo():
    try:
        head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(REPO), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True).stdout.strip()
        return head + (" (with uncommitted changes)" if dirty else "")
    except OSError:
        return "?"


def write_markdown(results, path):
    rows = results["rows"]
    lines = ["# Shader node programs: Photon Splat against Cycles, pixel by pixel", ""]
    lines += [
        f"Generated by `{results['command'].strip()}` on {results['date']}, commit {results['commit']}; Cycles of "
        f"Blender {results['blender']} (Debian's `/usr/bin/blender`)"
        + (f", Photon Splat {results['photonsplat_version']}" if results.get("photonsplat_version") else "")
        + f". {len(rows)} cases at {results['size']}×{results['size']} pixels; wall time "
        f"{results['wall_seconds'] / 60:.1f} min (Cycles {results['cycles_seconds']:.0f} s for the renders not in "
        f"the cache, {results['cycles_cached']} taken from it; Photon Splat {results['photonsplat_seconds']:.0f} s).",
        "",
        "Scenes: `blend_scenes/make_node_planes.py`: per case a material, Emission (strength 1) driven by the node "
        "under test, on a 16×16 grid plane (scaled 2.5, turned 20° about Z, with a vertex colour attribute) or on "
        "the same grid raised into a smooth dome (for the nodes that read normals and incoming directions), filling "
        "an orthographic camera; black world; Standard view, look None, exposure 0.",
        "",
        "Cycles: CPU, 1 sample, box filter of width 0.01 px (its sample within 0.005 px of the pixel centre), no "
        "denoising, 0 bounces, EXR float; cached in `build/node_compare/cycles/`. Photon Splat: the add-on's export "
        "and one iteration of the core, whose camera rays go through the pixel centres (progressive iterations "
        "after the first jitter them; there is no separate anti-aliasing setting).",
        "",
        "Measure: *rel* = mean over pixels and RGB of |Photon Splat − Cycles| / mean |Cycles| (the mean floored at "
        f"{MEAN_FLOOR:g}); pass (acceptance (a)): rel ≤ 1e-3 for deterministic nodes, ≤ 1 % for the noise-based "
        "ones (noise, voronoi, musgrave, wave with distortion, magic, white noise). *max* = the largest pixel "
        f"difference; *edge* = pixels differing by more than {EDGE:.0%} of the mean (a few on an otherwise exact "
        "case are pixels whose Cycles sample fell across a discontinuity); *inner* = rel without them.",
        "",
    ]
    if results.get("core_note"):
        lines += [f"**Note:** {results['core_note']}.", ""]
    if results.get("cycles_only"):
        lines += ["**Cycles only**: Photon Splat was not run (`--cycles-only`); the table lists Cycles' means, the "
                  "comparison awaits a build with node programs.", "",
                  "| # | case | node | class | object | Cycles mean |", "|---|---|---|---|---|---|"]
        for i, r in enumerate(rows, 1):
            lines.append(f"| {i} | `{r['name']}` | {r['node']} | {r['class']} | {r['object']} | "
                         f"{r['cycles_mean']:.4f} |")
        path.write_text("\n".join(lines) + "\n")
        print(f"node_compare: wrote {path}")
        return
    passed = sum(bool(r.get("pass")) for r in rows)
    by_class = {}
    for r in rows:
        by_class.setdefault(r["class"], [0, 0])
        by_class[r["class"]][0] += bool(r.get("pass"))
        by_class[r["class"]][1] += 1
    by_node = {}
    for r in rows:
        by_node.setdefault(r["node"], [0, 0])
        by_node[r["node"]][0] += bool(r.get("pass"))
        by_node[r["node"]][1] += 1
    lines += ["## Summary", "",
              f"- **{passed} / {len(rows)}** cases pass: "
              + ", ".join(f"{cls} {p} / {n}" for cls, (p, n) in sorted(by_class.items())) + ".",
              "- Per node: " + ", ".join(f"{node} {p}/{n}" for node, (p, n) in sorted(by_node.items())) + "."]
    for cls in sorted(by_class):
        ok = [r for r in rows if r["class"] == cls and r.get("pass")]
        if ok:
            worst = max(ok, key=lambda r: r["rel"])
            median = sorted(r["rel"] for r in ok)[len(ok) // 2]
            lines.append(f"- Passing {cls} cases: median rel {median:.1e}, largest {worst['rel']:.1e} "
                         f"(`{worst['name']}`; threshold {THRESHOLD[cls]:g}).")
    edged = [r for r in rows if r.get("pass") and r.get("edge_pixels")]
    if edged:
        lines.append(f"- {len(edged)} passing cases have an edge pixel or a few (a Cycles sample across a step): "
                     + ", ".join(f"`{r['name']}` {r['edge_pixels']}" for r in edged) + ".")
    lines += ["", "## Per case", "",
              "| # | case | node | class | Cycles mean | rel | inner | max | edge | result |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for i, r in enumerate(rows, 1):
        if r.get("error"):
            lines.append(f"| {i} | `{r['name']}` | {r['node']} | {r['class']} | {r['cycles_mean']:.4f} | – | – | – "
                         f"| – | **ERROR** |")
            continue
        lines.append(f"| {i} | `{r['name']}` | {r['node']} | {r['class']} | {r['cycles_mean']:.4f} | "
                     f"{r['rel']:.2e} | {r['rel_inner']:.2e} | {r['max']:.3g} | {r['edge_pixels']} | "
                     f"{'pass' if r['pass'] else '**FAIL**'} |")
    failing = [r for r in rows if not r.get("pass")]
    if failing:
        lines += ["", "## Failures and their likely causes", "",
                  "Guessed from the numbers and the export's notes; `build/node_compare/images/<case>.npz` holds "
                  "both images.", ""]
        for r in failing:
            rel = f"rel {r['rel']:.2e}" if "rel" in r else "no image"
            lines.append(f"- `{r['name']}` ({rel}): {DIAGNOSED.get(r['name']) or r.get('cause') or likely_cause(r)}")
    path.write_text("\n".join(lines) + "\n")
    print(f"node_compare: wrote {path}")


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
