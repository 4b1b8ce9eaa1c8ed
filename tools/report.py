"""Report: how much time buys how much quality, for every scene, method and (photons, radius), and for progressive
splatting over time, against a converged reference; and how long Cycles needs for the same quality.

Two modes, both run by tools/run_report.sh (the one documented command):

  measure (inside Blender, one scene per run; the add-on's own export, so it measures what the engine renders):
    BLENDER_USER_SCRIPTS=build/blender blender -b --factory-startup -noaudio --python-exit-code 1 \\
        --addons photonsplat blend_scenes/cornell_caustics.blend --python tools/report.py -- measure \\
        --width 192 --out build/report

    1. reference: photonsplat.render_reference (path tracing + progressive photon mapping of caustics) of the same
       exported scene, cached as build/report/reference/<scene>_<W>x<H>_<samples>spp.npy keyed by the .blend's
       content, so reruns skip it (--reference-only stops here: references can be rendered ahead under any load,
       as their quality is a sample count, and the timed steps below run later on a quiet machine);
    2. the paper's tables (HPG 2016 talk): methods cluster_cone (the paper's cluster-trivial), directional and
       tiled at 10k / 50k / 200k / 1M photons with the engine's automatic radius for each count; one-shot renders;
    3. progressive splatting of every method (brute excepted) for a time budget, the mean measured after every
       pass against its elapsed render time (Progressive.elapsed: the passes' own time and the choice of the first
       radius);
    4. caustic scenes only: Cycles through the same Blender (CPU, BOX filter, no denoising, no adaptive sampling,
       fixed seed) at 1, 2, 4, ... samples per pixel, until it reaches the quality that progressive splatting
       reached in 30 s or a render exceeds --cycles-max-seconds; the time is the wall time of
       bpy.ops.render.render (scene sync included; our times include building the BVH, not the export).
    Every metric: SSIM and PSNR on the display luma (linear -> clamp -> sRGB), relMSE on linear radiance.

  write (plain /usr/bin/python3, matplotlib from Debian): reads build/report/*/measure.json and writes into
  docs/results/: report.csv, report.md (tables shaped like the paper's, progressive quality at fixed times, the
  Cycles comparison and the headline figures), report_<scene>.png (error against time, one line per method, log
  axes) and report_crops_<scene>.png (side-by-side crops).

This is a measurement program, not a test: the machine is shared and noisy; each run states its load.
"""
import argparse
import csv
import hashlib
import json
import math
import os
import pathlib
import platform
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
TABLE_METHODS = ["cluster_cone", "directional", "tiled"]
TABLE_PHOTONS = [10_000, 50_000, 200_000, 1_000_000]
PROGRESSIVE_METHODS = ["cluster_cone", "cluster", "tiled", "gather", "directional"]
SNAPSHOT_SECONDS = [1.0, 5.0, 30.0]
SSIM_GOAL = 0.9


# ---- metrics: the core's when it has them, else the same definitions through scikit-image ---------------------

def display_luma(image):
    rgb = np.clip(np.asarray(image, np.float64)[..., :3], 0.0, 1.0)
    encoded = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(rgb, 1.0 / 2.4) - 0.055)
    return encoded @ np.array([0.2126, 0.7152, 0.0722])


def metrics(core, image, reference):
    """SSIM and PSNR of the display luma, relMSE (ε = 1e-2) and RMSE of linear radiance."""
    image = np.ascontiguousarray(image, np.float32)
    reference = np.ascontiguousarray(reference, np.float32)
    if core is not None and hasattr(core, "ssim"):
        return {"ssim": float(core.ssim(image, reference)), "psnr": float(core.psnr(image, reference)),
                "relmse": float(core.relmse(image, reference)), "rmse": float(core.rmse(image, reference))}
    from skimage.metrics import peak_signal_noise_ratio, structural_similarity

    a, b = display_luma(image), display_luma(reference)
    x, y = image[..., :3].astype(np.float64), reference[..., :3].astype(np.float64)
    return {"ssim": float(structural_similarity(a, b, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                                                data_range=1.0)),
            "psnr": float(peak_signal_noise_ratio(b, a, data_range=1.0)),
            "relmse": float(np.mean((x - y) ** 2 / (y ** 2 + 1e-2))), "rmse": float(np.sqrt(np.mean((x - y) ** 2)))}


# ---- measure (inside Blender) --------------------------------------------------------------------------------

def load_average():
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


def file_digest(path):
    h = hashlib.sha1()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:12]


def has_specular(bpy):
    """Whether the scene has glass or mirror surfaces: light through them makes caustics."""
    from photonsplat.export import materials

    for mat in bpy.data.materials:
        if mat.users == 0:
            continue
        kind = materials.convert_material(mat).core_arguments().get("kind")
        if kind in ("glass", "mirror"):
            return True
    return False


def measure_scene(args):
    import bpy

    from photonsplat import _core as core
    from photonsplat import export

    blend = pathlib.Path(bpy.data.filepath)
    name = blend.stem
    scene = bpy.context.scene
    aspect = scene.render.resolution_y / scene.render.resolution_x
    width = args.width
    height = max(16, int(round(width * aspect)))
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    out = pathlib.Path(args.out) / name
    out.mkdir(parents=True, exist_ok=True)
    caustic = has_specular(bpy)
    record = {"scene": name, "width": width, "height": height, "caustic": caustic, "cores": os.cpu_count(),
              "machine": platform.machine(), "load_at_start": load_average(), "version": core.__version__,
              "tables": [], "progressive": [], "cycles": []}
    print(f"report: {name} {width}x{height} caustic={caustic} load {record['load_at_start']:.1f}", flush=True)

    scene.photonsplat.seed = args.seed
    scene.photonsplat.radius = 0.0
    scene.photonsplat.passes = 1
    scene.photonsplat.time_limit = 0.0
    frame = export.export_frame(core, bpy.context.evaluated_depsgraph_get())

    # 1. the reference
    reference, record["reference"] = reference_image(core, frame, name, blend, caustic, args)
    np.save(out / "reference.npy", reference)
    if args.reference_only:
        return

    # 2. one-shot renders shaped like the paper's tables
    snapshots = {}
    for photons in TABLE_PHOTONS:
        for method in TABLE_METHODS:
            settings = frame.settings
            settings.photons, settings.method, settings.radius, settings.iterations = photons, method, 0.0, 1
            started = time.perf_counter()
            image, stats = core.render(frame.scene, frame.camera, settings)
            wall = time.perf_counter() - started
            row = {"photons": photons, "method": method, "radius": stats["values"]["radius"], "seconds": wall,
                   **metrics(core, image, reference)}
            record["tables"].append(row)
            print(f"report: table {photons} {method}: {row['seconds']:.2f} s SSIM {row['ssim']:.3f}", flush=True)
            if photons == 200_000 and method in ("cluster_cone", "directional"):
                snapshots[f"one-shot {method}, 200k photons"] = (image, wall)

    # 3. progressive splatting over time
    for method in PROGRESSIVE_METHODS:
        budget = args.long_seconds if method == "cluster_cone" and caustic else args.seconds
        if method == "cluster_cone" and not caustic:
            budget = max(args.seconds, 2 * args.seconds)
        settings = frame.settings
        settings.photons, settings.method, settings.radius = args.progressive_photons, method, 0.0
        settings.iterations, settings.time_limit = 0, budget
        progressive = core.Progressive(frame.scene, frame.camera, settings)
        curve, taken = [], set()
        while not progressive.finished:
            progressive.step()
            image = progressive.image()
            point = {"method": method, "pass": progressive.iterations_done, "seconds": progressive.elapsed,
                     "radius": progressive.radius, **metrics(core, image, reference)}
            curve.append(point)
            if method == "cluster_cone":
                for t in SNAPSHOT_SECONDS:  # the last mean before t seconds
                    if progressive.elapsed <= t:
                        snapshots[f"progressive {t:g} s"] = (image, progressive.elapsed)
        last = curve[-1]
        print(f"report: progressive {method}: {last['pass']} passes in {last['seconds']:.1f} s, SSIM "
              f"{last['ssim']:.3f}", flush=True)
        record["progressive"] += curve

    # 4. Cycles on the caustic scenes
    if caustic and not args.no_cycles:
        record["cycles"], cycles_images = cycles_curve(bpy, core, reference, record, out, args)
        snapshots.update(cycles_images)

    record["load_at_end"] = load_average()
    names = sorted(snapshots)
    np.savez_compressed(out / "snapshots.npz", **{f"img{i}": snapshots[n][0] for i, n in enumerate(names)})
    record["snapshots"] = [{"label": n, "seconds": snapshots[n][1], "key": f"img{i}"} for i, n in enumerate(names)]
    with open(out / "measure.json", "w") as f:
        json.dump(record, f, indent=1)
    print(f"report: {name} written to {out}", flush=True)


def reference_image(core, frame, name, blend, caustic, args):
    """The converged reference, from the cache when the same scene, size and settings were rendered before."""
    cache = pathlib.Path(args.out) / "reference"
    cache.mkdir(parents=True, exist_ok=True)
    key = (f"{name}_{frame.width}x{frame.height}_{args.reference_samples}spp_{args.reference_seconds:g}s_"
           f"{args.reference_photons}ph_{file_digest(blend)}")
    path = cache / f"{key}.npy"
    info_path = cache / f"{key}.json"
    if path.exists() and info_path.exists():
        print(f"report: reference from the cache {path}", flush=True)
        return np.load(path), json.loads(info_path.read_text())
    started = time.perf_counter()
    if hasattr(core, "render_reference"):
        # Caustic photons only where glass or mirrors can make caustics; elsewhere pure path tracing.
        photons = args.reference_photons if caustic else 0
        image, stats = core.render_reference(frame.scene, frame.camera, samples=args.reference_samples,
                                             seed=1234, caustic_photons=photons,
                                             time_limit=args.reference_seconds)
        info = {"kind": "render_reference (path tracing + progressive photon mapping of caustics)",
                "samples": stats["values"].get("samples", args.reference_samples), "caustic_photons": photons}
    else:
        # Without the reference renderer: a long progressive exact splat, which converges to the same answer but
        # is not independent of the methods measured; the report says so.
        settings = frame.settings
        settings.method, settings.photons, settings.radius = "cluster_cone", 200_000, 0.0
        settings.iterations, settings.time_limit = 0, args.reference_seconds
        image, stats = core.render(frame.scene, frame.camera, settings)
        info = {"kind": "progressive cluster_cone (render_reference unavailable: not independent)",
                "samples": stats["values"]["iterations"]}
    info["seconds"] = time.perf_counter() - started
    np.save(path, image)
    core.write_image(str(cache / f"{key}.exr"), image)
    info_path.write_text(json.dumps(info))
    print(f"report: reference {info}", flush=True)
    return image, info


def read_exr(bpy, path):
    img = bpy.data.images.load(str(path), check_existing=False)
    try:
        w, h = img.size
        pixels = np.empty(w * h * 4, np.float32)
        img.pixels.foreach_get(pixels)
        return pixels.reshape(h, w, 4)[::-1].copy()  # Blender's rows go bottom-up
    finally:
        bpy.data.images.remove(img)


def cycles_curve(bpy, core, reference, record, out, args):
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    cycles = scene.cycles
    cycles.device = 'CPU'
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False
    cycles.seed = args.seed
    cycles.pixel_filter_type = 'BOX'
    cycles.filter_width = 1.0
    scene.render.threads_mode = 'AUTO'
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.color_depth = '32'
    scene.render.use_persistent_data = False
    progressive = [p for p in record["progressive"] if p["method"] == "cluster_cone"]
    target = max([p["ssim"] for p in progressive] + [SSIM_GOAL])
    curve, images = [], {}
    samples = 1
    while samples <= args.cycles_max_samples:
        cycles.samples = samples
        scene.render.filepath = str(out / f"cycles_{samples:05d}.exr")
        started = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        wall = time.perf_counter() - started
        image = read_exr(bpy, scene.render.filepath)
        point = {"samples": samples, "seconds": wall, **metrics(core, image, reference)}
        curve.append(point)
        print(f"report: cycles {samples} spp: {wall:.1f} s SSIM {point['ssim']:.3f}", flush=True)
        for t in SNAPSHOT_SECONDS:
            if wall <= t:
                images[f"Cycles {t:g} s"] = (image, wall)
        images["Cycles (last)"] = (image, wall)
        if point["ssim"] >= target or wall > args.cycles_max_seconds:
            break
        samples *= 2
    scene.render.engine = 'PHOTONSPLAT'
    return curve, images


# ---- write (plain Python) ------------------------------------------------------------------------------------

def first_time_reaching(curve, ssim):
    for p in curve:
        if p["ssim"] >= ssim:
            return p["seconds"]
    return None


def interpolated_time_reaching(curve, ssim):
    """Where a curve measured on a grid (Cycles: samples ×2) crosses `ssim`: log-time interpolated linearly in SSIM
    between the last point below and the first at or above it. The grid's own time is an upper bound within 2×;
    this is the fairer estimate. None when the curve never reaches it; the first point's time when it starts there."""
    for i, p in enumerate(curve):
        if p["ssim"] >= ssim:
            if i == 0:
                return p["seconds"]
            q = curve[i - 1]
            f = (ssim - q["ssim"]) / (p["ssim"] - q["ssim"]) if p["ssim"] > q["ssim"] else 1.0
            return math.exp(math.log(q["seconds"]) + f * (math.log(p["seconds"]) - math.log(q["seconds"])))
    return None


def ssim_at(curve, seconds):
    """SSIM of the last mean done by `seconds`; None when the run's budget ended well before (a time-limited run
    stops a pass short of its budget: within 25 % counts as having reached it)."""
    reached = [p for p in curve if p["seconds"] <= seconds]
    if not reached or curve[-1]["seconds"] < 0.75 * seconds:
        return None
    return reached[-1]["ssim"]


def ratio_text(r):
    """A speed ratio: whole numbers from 10 up, two significant digits below (0.14× is Cycles being faster)."""
    return f"{r:.0f}×" if r >= 10 else f"{r:.2g}×"


def fmt_time(t, cap=None):
    if t is None:
        return f"> {fmt_time(cap)} (not reached)" if cap is not None else "not reached"
    return f"{t:.2f} s" if t < 10 else f"{t:.0f} s"


def write_outputs(args):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    measured = pathlib.Path(args.out)
    records = [json.loads(p.read_text()) for p in sorted(measured.glob("*/measure.json"))]
    if not records:
        sys.exit(f"no measurements under {measured}: run the measure mode first")
    docs = pathlib.Path(args.docs)
    docs.mkdir(parents=True, exist_ok=True)

    with open(docs / "report.csv", "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["scene", "kind", "method", "photons", "radius", "pass_or_samples", "seconds", "ssim", "psnr",
                      "relmse", "rmse"])
        for r in records:
            for t in r["tables"]:
                out.writerow([r["scene"], "one-shot", t["method"], t["photons"], f"{t['radius']:.6g}", 1,
                              f"{t['seconds']:.4f}", f"{t['ssim']:.5f}", f"{t['psnr']:.3f}", f"{t['relmse']:.6g}",
                              f"{t['rmse']:.6g}"])
            for p in r["progressive"]:
                out.writerow([r["scene"], "progressive", p["method"], "", f"{p['radius']:.6g}", p["pass"],
                              f"{p['seconds']:.4f}", f"{p['ssim']:.5f}", f"{p['psnr']:.3f}", f"{p['relmse']:.6g}",
                              f"{p['rmse']:.6g}"])
            for c in r["cycles"]:
                out.writerow([r["scene"], "cycles", "cycles", "", "", c["samples"], f"{c['seconds']:.4f}",
                              f"{c['ssim']:.5f}", f"{c['psnr']:.3f}", f"{c['relmse']:.6g}", f"{c['rmse']:.6g}"])

    lines = ["# Speed against error: report", "",
             "Regenerate with `bash tools/run_report.sh` (see its header for how long it takes). Every figure "
             "is measured against a converged reference of the same exported scene at the same resolution. SSIM "
             "and PSNR are on the display luma (linear → clamp [0, 1] → sRGB), relMSE on linear radiance "
             "(ε = 1e-2). Times are wall-clock seconds on this machine, shared with other jobs: the load average "
             "is given per scene, and figures taken under load are slower than the machine can do.", ""]
    headline = ["## Headline: progressive splatting against Cycles on the caustic scenes", "",
                "| scene | progressive SSIM at 1 s / 5 s / 30 s | Cycles time to the same SSIM | "
                f"progressive time to SSIM {SSIM_GOAL} | Cycles time to SSIM {SSIM_GOAL} (grid; interpolated) | ratio |",
                "|---|---|---|---|---|---|"]
    body = []
    for r in records:
        name = r["scene"]
        body += [f"## `{name}.blend` at {r['width']}×{r['height']}", "",
                 f"Reference: {r['reference']['kind']}, {r['reference']['samples']:.0f} samples per pixel "
                 f"({r['reference'].get('seconds', float('nan')):.0f} s when rendered). Load average "
                 f"{r['load_at_start']:.1f} at the start, {r.get('load_at_end', float('nan')):.1f} at the end, "
                 f"{r['cores']} cores.", ""]
        brightness = relative_brightness(r, measured / name)
        if brightness:
            body += ["Mean linear radiance relative to the reference (a systematic offset caps SSIM below 1 however "
                     "long a renderer runs): " + "; ".join(f"{k} {v:.3f}" for k, v in brightness.items()) + ".",
                     ""]
        body += ["One-shot renders, shaped like the paper's tables (SSIM %, PSNR dB; the engine's automatic radius "
                 "for each photon count; `cluster_cone` is the paper's cluster-trivial):", "",
                 "| photons, radius | " + " | ".join(f"{m} SSIM | PSNR | relMSE | s" for m in TABLE_METHODS) + " |",
                 "|---" * (1 + 4 * len(TABLE_METHODS)) + "|"]
        for photons in TABLE_PHOTONS:
            rows = {t["method"]: t for t in r["tables"] if t["photons"] == photons}
            if not rows:
                continue
            radius = next(iter(rows.values()))["radius"]
            cells = []
            for m in TABLE_METHODS:
                t = rows.get(m)
                cells += ([f"{100 * t['ssim']:.0f}", f"{t['psnr']:.0f}", f"{t['relmse']:.3g}", f"{t['seconds']:.2f}"]
                          if t else ["–"] * 4)
            body.append(f"| {photons // 1000}k, {radius:.3g} | " + " | ".join(cells) + " |")
        body += ["", "Progressive splatting (every pass: new photons, jittered pixels, r² shrinking by "
                 "(i−1+α)/i, α = 2/3), the running mean measured after each pass:", "",
                 "| method | passes | time (s) | SSIM at 1 s | SSIM at 5 s | final SSIM | final PSNR | final relMSE |"
                 f" time to SSIM {SSIM_GOAL} |", "|---|---|---|---|---|---|---|---|---|"]
        curves = {}
        for p in r["progressive"]:
            curves.setdefault(p["method"], []).append(p)
        for method, curve in curves.items():
            last = curve[-1]
            s1, s5 = ssim_at(curve, 1.0), ssim_at(curve, 5.0)
            body.append(f"| {method} | {last['pass']} | {last['seconds']:.1f} | "
                        f"{'–' if s1 is None else f'{s1:.3f}'} | {'–' if s5 is None else f'{s5:.3f}'} | "
                        f"{last['ssim']:.3f} | {last['psnr']:.1f} | {last['relmse']:.3g} | "
                        f"{fmt_time(first_time_reaching(curve, SSIM_GOAL))} |")
        if r["cycles"]:
            cyc = r["cycles"]
            cap = cyc[-1]["seconds"]
            body += ["", "Cycles (CPU, BOX filter 1 px, no denoising, no adaptive sampling; wall time of the render "
                     "call, scene sync included):", "", "| samples | time (s) | SSIM | PSNR | relMSE |",
                     "|---|---|---|---|---|"]
            body += [f"| {c['samples']} | {c['seconds']:.2f} | {c['ssim']:.3f} | {c['psnr']:.1f} | {c['relmse']:.3g} |"
                     for c in cyc]
            prog = curves.get("cluster_cone", [])
            cells = []
            matches = []
            for t in SNAPSHOT_SECONDS:
                s = ssim_at(prog, t)
                if s is None:
                    continue
                ct = first_time_reaching(cyc, s)
                cells.append(f"{s:.3f}")
                matches.append(f"{t:g} s → {fmt_time(ct, cap)}")
            tp, tc = first_time_reaching(prog, SSIM_GOAL), first_time_reaching(cyc, SSIM_GOAL)
            ti = interpolated_time_reaching(cyc, SSIM_GOAL)
            if tp is not None and tc is not None:
                ratio = f"{ratio_text(tc / tp)} ({ratio_text(ti / tp)} interpolated)"
            elif tp is not None:
                ratio = f"> {ratio_text(cap / tp)} (Cycles did not reach it)"
            else:
                ratio = "progressive did not reach it"
            body += ["", f"Cycles needs, for the SSIM progressive `cluster_cone` reaches in "
                     + "; ".join(matches) + f" (grid: samples ×2, so Cycles' times are upper bounds within a "
                     "factor of about 2).", ""]
            interpolated = f"; {fmt_time(ti)}" if ti is not None else ""
            headline.append(f"| `{name}` | {' / '.join(cells)} | {'; '.join(matches)} | {fmt_time(tp)} | "
                            f"{fmt_time(tc, cap)}{interpolated} | {ratio} |")
        plot_path = docs / f"report_{name}.png"
        plot_scene(plt, r, curves, plot_path)
        crops_path = docs / f"report_crops_{name}.png"
        crop_figure(plt, r, measured / name, crops_path)
        body += ["", f"![error against time]({plot_path.name})", "", f"![crops]({crops_path.name})", ""]
    text = "\n".join(lines + headline + [""] + body) + "\n"
    (docs / "report.md").write_text(text)
    print(text)


def relative_brightness(record, folder):
    reference = np.load(folder / "reference.npy")
    snaps = np.load(folder / "snapshots.npz")
    mean = float(np.mean(reference[..., :3]))
    if not mean > 0:
        return {}
    return {s["label"]: float(np.mean(snaps[s["key"]][..., :3])) / mean for s in record["snapshots"]}


def plot_scene(plt, record, curves, path):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for method, curve in curves.items():
        t = [p["seconds"] for p in curve]
        axes[0].plot(t, [p["relmse"] for p in curve], marker=".", label=f"progressive {method}")
        axes[1].plot(t, [1 - p["ssim"] for p in curve], marker=".", label=f"progressive {method}")
    for m in TABLE_METHODS:
        rows = [x for x in record["tables"] if x["method"] == m]
        axes[0].scatter([x["seconds"] for x in rows], [x["relmse"] for x in rows], marker="x",
                        label=f"one-shot {m} (10k–1M photons)")
        axes[1].scatter([x["seconds"] for x in rows], [1 - x["ssim"] for x in rows], marker="x")
    if record["cycles"]:
        c = record["cycles"]
        axes[0].plot([p["seconds"] for p in c], [p["relmse"] for p in c], "k--o", label="Cycles")
        axes[1].plot([p["seconds"] for p in c], [1 - p["ssim"] for p in c], "k--o")
    for ax, label in zip(axes, ["relMSE (linear radiance)", "1 − SSIM (display luma)"]):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("render time (s)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle(f"{record['scene']} at {record['width']}×{record['height']}: error against time")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def to_display(image):
    rgb = np.clip(np.asarray(image, np.float64)[..., :3], 0.0, 1.0)
    return np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(rgb, 1.0 / 2.4) - 0.055)


def crop_window(reference, image=None):
    """A window of half the image's size: where `image` is furthest from the reference (display luma), or, without
    an image, where the reference has the most detail (local luma variance)."""
    luma = display_luma(reference)
    error = None if image is None else np.abs(display_luma(image) - luma)
    h, w = luma.shape
    ch, cw = max(8, h // 2), max(8, w // 2)
    best, where = -1.0, (0, 0)
    for y in range(0, h - ch + 1, max(1, ch // 4)):
        for x in range(0, w - cw + 1, max(1, cw // 4)):
            v = float(np.var(luma[y:y + ch, x:x + cw]) if error is None else np.mean(error[y:y + ch, x:x + cw]))
            if v > best:
                best, where = v, (y, x)
    y, x = where
    return slice(y, y + ch), slice(x, x + cw)


def crop_figure(plt, record, folder, path):
    reference = np.load(folder / "reference.npy")
    snaps = np.load(folder / "snapshots.npz")
    panels = [("reference", reference, None)]
    order = ["progressive 1 s", "progressive 5 s", "progressive 30 s", "Cycles 1 s", "Cycles 5 s", "Cycles 30 s",
             "Cycles (last)", "one-shot cluster_cone, 200k photons", "one-shot directional, 200k photons"]
    by_label = {s["label"]: s for s in record["snapshots"]}
    for label in order:
        if label in by_label:
            s = by_label[label]
            panels.append((label, snaps[s["key"]], s["seconds"]))
    early = by_label.get("progressive 1 s")
    ys, xs = crop_window(reference, snaps[early["key"]] if early else None)
    fig, axes = plt.subplots(1, len(panels), figsize=(2.2 * len(panels), 2.6))
    for ax, (label, image, seconds) in zip(np.atleast_1d(axes), panels):
        ax.imshow(to_display(image[ys, xs]), interpolation="nearest")
        title = label if seconds is None else f"{label}\n({seconds:.2f} s)"
        ax.set_title(title, fontsize=7)
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mode", choices=["measure", "write"])
    parser.add_argument("--out", default=str(ROOT / "build" / "report"), help="measurements and reference cache")
    parser.add_argument("--docs", default=str(ROOT / "docs" / "results"), help="where write puts its outputs")
    parser.add_argument("--width", type=int, default=128, help="image width; height keeps the scene's aspect")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--seconds", type=float, default=5.0, help="progressive budget per method")
    parser.add_argument("--long-seconds", type=float, default=30.0,
                        help="progressive budget of cluster_cone on caustic scenes (the 30 s figure)")
    parser.add_argument("--progressive-photons", type=int, default=12_500,
                        help="photons per progressive pass (fewer, cheaper passes reach SSIM 0.9 sooner: docs/results)")
    parser.add_argument("--reference-samples", type=int, default=4096, help="reference passes (1 path/pixel each)")
    parser.add_argument("--reference-photons", type=int, default=100_000, help="caustic photons per reference pass")
    parser.add_argument("--reference-seconds", type=float, default=0.0,
                        help="time cap of one reference (it stops after the pass that reaches it); 0 = none, so the "
                             "reference's quality is --reference-samples whatever the machine's load")
    parser.add_argument("--reference-only", action="store_true",
                        help="render (or find in the cache) the reference and stop: references can be made ahead, "
                             "under any load, and the timed measurements run later on a quiet machine")
    parser.add_argument("--cycles-max-samples", type=int, default=65536)
    parser.add_argument("--cycles-max-seconds", type=float, default=45.0,
                        help="stop Cycles' sample doubling after a render that took longer than this")
    parser.add_argument("--no-cycles", action="store_true")
    return parser.parse_args(argv)


def main():
    args = parse_args()
    if args.mode == "measure":
        measure_scene(args)
    else:
        write_outputs(args)


if __name__ == "__main__":
    try:
        main()
    except SystemExit:
        raise
    except Exception:  # make Blender exit non-zero with --python-exit-code
        import traceback

        traceback.print_exc()
        sys.exit(1)
