#!/usr/bin/python3
"""Image identity: do two builds of Photon Splat render the same bits?

A refactor that only moves code must leave every image of every exact splatting method unchanged at the same
seed. This tool renders every scene of blend_scenes/ through the PHOTONSPLAT engine of a tree's build and
compares two such sets of renders file by file and pass by pass. Run it with Debian's /usr/bin/python3; it
drives `blender -b` (Debian's Blender 3.4) in subprocesses.

Commands (run from anywhere; paths may be relative):

  /usr/bin/python3 tools/image_identity.py render --tree DIR --out OUTDIR [--width 96] [--scenes DIR]
          [--methods brute,tiled,cluster,cluster_cone,gather | --methods auto] [--seed 1] [--photons 20000]
          [--threads 2]
      Renders each scenes-folder *.blend with the add-on of DIR/build/blender (build DIR first, see below) into
      OUTDIR/<scene>__<render>.exr, 32-bit float multilayer OpenEXR with every render pass the engine offers
      turned on (Combined, Depth, Normal, Emit, Direct, Indirect, Caustics). The renders of each scene:
        <method>            one progressive iteration, for each exact method (--methods; `auto` takes every
                            method of the add-on's enum but directional);
        cluster_cone_x3     three progressive iterations with cluster_cone;
        directional         one iteration of the approximate method (compared, but never a failure).
      The scenes come from --scenes (default: blend_scenes/ of the repository holding this script), so both
      trees render the same .blend files. Width 96 keeps each scene's aspect; seed, photon count and threads
      are fixed. Only settings that exist in old and new trees are set: method, seed, photons, the progressive
      count (`iterations` where the add-on has it, else `passes`) and threads (only if the property exists).
      OUTDIR/renders.json records each render's seconds, status, passes and the core's work counters;
      OUTDIR/logs/ keeps Blender's output. The render fails if two methods of a scene did the same work (same
      counters): exact methods give the same bits here, so only the counters show the method was switched.
      Caution, seen at 7af71cd: two runs of one build are not always identical. In 1 to 4 renders of a full
      run a few pixels differ (1e-8 to 3e-6, the Normal pass too, so the camera rays' hits differ), with 1 or
      2 threads, with address randomisation off, and not always in the same scene or method. Compare two
      renders of the base with each other (the noise floor) before reading a failure.

  /usr/bin/python3 tools/image_identity.py compare A B
      Compares the .exr files of folders A and B: a table of scene, render, identical, max abs difference,
      differing pixels and the passes that differ. Exits 1 if any exact-method image differs or is missing on
      one side; directional's differences are printed only. Then lists the renders whose work counters
      (renders.json) differ, for information only. Uses numpy through OpenImageIO's Python module when
      it is installed (bitwise comparison), else idiff and oiiotool (a difference of exactly 0 counts as equal).

  /usr/bin/python3 tools/image_identity.py check --base REV [--workdir DIR] [render options]
      The whole check in one command: `git worktree add` REV into a temporary folder, build it and this tree
      with the build command below, render both (this tree's scenes), compare, remove the worktree.

Build command (in a tree's root; CCACHE_BASEDIR lets trees at different paths share ccache's cache):
  CCACHE_BASEDIR=/work cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release \\
      -DPython_EXECUTABLE=/usr/bin/python3 -DCMAKE_CXX_COMPILER_LAUNCHER=ccache && \\
  CCACHE_BASEDIR=/work cmake --build build

Example, the baseline before a refactor and the check after it:
  /usr/bin/python3 tools/image_identity.py render --tree /work/base --out /work/identity/base
  /usr/bin/python3 tools/image_identity.py render --tree . --out /work/identity/wt
  /usr/bin/python3 tools/image_identity.py compare /work/identity/base /work/identity/wt

The same file also runs inside Blender (`blender -b FILE.blend --python image_identity.py -- blender-render
JSON`), where it sets up and renders one scene; that part is the function blender_render().
"""

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPOSITORY = Path(__file__).resolve().parent.parent
DEFAULT_METHODS = ("brute", "tiled", "cluster", "cluster_cone", "gather")
APPROXIMATE_METHODS = ("directional",)
PROGRESSIVE_METHOD = "cluster_cone"
PROGRESSIVE_ITERATIONS = 3
# Separates the scene's name from the render's in an output file name: atrium__cluster_cone_x3.exr.
NAME_SEPARATOR = "__"
BUILD_CONFIGURE = ["cmake", "-S", ".", "-B", "build", "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                   "-DPython_EXECUTABLE=/usr/bin/python3", "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"]
BUILD_COMPILE = ["cmake", "--build", "build"]


# --- inside Blender ----------------------------------------------------------------------------------------

def blender_render(job):
    """Renders the open .blend once per entry of job["renders"] and writes one multilayer EXR each.
    Runs inside Blender; returns the records written to the caller as JSON lines on stdout."""
    import bpy
    import photonsplat.engine as engine

    scene = bpy.context.scene
    scene.render.engine = "PHOTONSPLAT"
    props = scene.photonsplat
    method_items = props.bl_rna.properties["method"].enum_items.keys()

    # Small image of the scene's own aspect, nothing after the render that could change the pixels.
    render = scene.render
    aspect = (render.resolution_y * render.pixel_aspect_y) / (render.resolution_x * render.pixel_aspect_x)
    render.resolution_x = job["width"]
    render.resolution_y = max(1, round(job["width"] * aspect))
    render.pixel_aspect_x = render.pixel_aspect_y = 1.0
    render.resolution_percentage = 100
    render.use_border = False
    render.use_compositing = False
    render.use_sequencer = False
    render.use_file_extension = True
    image_settings = render.image_settings
    image_settings.file_format = "OPEN_EXR_MULTILAYER"
    image_settings.color_depth = "32"
    image_settings.exr_codec = "ZIP"          # lossless
    scene.frame_set(scene.frame_start)

    # Every pass: Blender's own toggles for the passes Cycles also has, every use_pass_* of the add-on's.
    for layer in scene.view_layers:
        layer.use_pass_combined = True
        layer.use_pass_z = True
        layer.use_pass_normal = True
        layer.use_pass_emit = True
        for name in layer.photonsplat.bl_rna.properties.keys():
            if name.startswith("use_pass_"):
                setattr(layer.photonsplat, name, True)
        layer.update_render_passes()

    props.seed = job["seed"]
    props.photons = job["photons"]
    props.time_limit = 0.0
    if "threads" in props.bl_rna.properties:
        props.threads = job["threads"]
    # The progressive count is `passes` in older trees and `iterations` (with `passes` an alias) in newer ones.
    count_property = "iterations" if "iterations" in props.bl_rna.properties else "passes"

    records = []
    for entry in job["renders"]:
        method = entry["method"]
        if method not in method_items:
            raise SystemExit(f"image_identity: the add-on has no method '{method}' (it has {list(method_items)})")
        props.method = method
        setattr(props, count_property, entry["iterations"])
        path = Path(job["out"]) / f"{job['scene']}{NAME_SEPARATOR}{entry['name']}.exr"
        render.filepath = str(path)
        started = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        outcome = engine.last_outcome
        records.append(dict(scene=job["scene"], render=entry["name"], method=method,
                            iterations=entry["iterations"], file=path.name,
                            seconds=round(time.perf_counter() - started, 3), status=outcome.status,
                            message=outcome.message, passes=list(outcome.passes),
                            counters=dict(outcome.stats.get("counters", {})),
                            size=[render.resolution_x, render.resolution_y], count_property=count_property))
        if outcome.status != "finished" or not path.exists():
            break
    return records


def addon_methods():
    """Inside Blender: the add-on's exact methods, in the enum's order."""
    import bpy
    items = bpy.context.scene.photonsplat.bl_rna.properties["method"].enum_items.keys()
    return [m for m in items if m not in APPROXIMATE_METHODS]


# --- render ------------------------------------------------------------------------------------------------

def blender_command(tree, blend, arguments):
    """The command line and environment that run this file inside Blender with the add-on of tree's build."""
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(Path(tree) / "build" / "blender"))
    command = ["blender", "-b", "--factory-startup", "-noaudio", "--addons", "photonsplat"]
    if blend is not None:
        command.append(str(blend))
    # --python-exit-code: an exception in this script makes Blender exit 1 instead of 0.
    command += ["--python-exit-code", "1", "--python", str(Path(__file__).resolve()), "--", *arguments]
    return command, env


RECORD_PREFIX = "IMAGE_IDENTITY "


def run_blender(tree, blend, arguments, log_path):
    """Runs Blender, keeps its output in log_path, returns the JSON records it printed."""
    command, env = blender_command(tree, blend, arguments)
    result = subprocess.run(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    Path(log_path).write_text(result.stdout)
    records = [json.loads(line[len(RECORD_PREFIX):]) for line in result.stdout.splitlines()
               if line.startswith(RECORD_PREFIX)]
    if result.returncode != 0:
        raise SystemExit(f"image_identity: Blender failed (exit {result.returncode}), see {log_path}")
    return records


def render_plan(methods):
    """(name, method, iterations) of every render of a scene."""
    plan = [dict(name=m, method=m, iterations=1) for m in methods]
    plan.append(dict(name=f"{PROGRESSIVE_METHOD}_x{PROGRESSIVE_ITERATIONS}", method=PROGRESSIVE_METHOD,
                     iterations=PROGRESSIVE_ITERATIONS))
    plan += [dict(name=m, method=m, iterations=1) for m in APPROXIMATE_METHODS]
    return plan


def render_tree(tree, out, scenes, width, methods, seed, photons, threads):
    tree, out = Path(tree).resolve(), Path(out).resolve()
    addon = tree / "build" / "blender" / "addons" / "photonsplat"
    if not addon.is_dir():
        raise SystemExit(f"image_identity: {addon} is missing: build {tree} first (see --help)")
    blends = sorted(Path(scenes).resolve().glob("*.blend"))
    if not blends:
        raise SystemExit(f"image_identity: no .blend files in {scenes}")
    out.mkdir(parents=True, exist_ok=True)
    (out / "logs").mkdir(exist_ok=True)
    for old in out.glob(f"*{NAME_SEPARATOR}*.exr"):
        old.unlink()

    if methods == ["auto"]:
        records = run_blender(tree, None, ["addon-methods"], out / "logs" / "addon-methods.txt")
        methods = records[0]["methods"]
    plan = render_plan(methods)
    print(f"rendering {len(blends)} scenes x {len(plan)} renders with {tree} (width {width}, seed {seed}, "
          f"{photons} photons) into {out}", flush=True)

    started = time.perf_counter()
    all_records, failed = [], []
    for blend in blends:
        job = dict(scene=blend.stem, out=str(out), width=width, seed=seed, photons=photons, threads=threads,
                   renders=plan)
        scene_started = time.perf_counter()
        records = run_blender(tree, blend, ["blender-render", json.dumps(job)], out / "logs" / f"{blend.stem}.txt")
        all_records += records
        summary = ", ".join(f"{r['render']} {r['seconds']:.2f}s" for r in records)
        print(f"  {blend.stem} ({time.perf_counter() - scene_started:.1f} s in Blender): {summary}", flush=True)
        failed += [r for r in records if r["status"] != "finished"]
        if len(records) != len(plan):
            failed.append(dict(scene=blend.stem, render="(the rest)", message="not rendered"))

    total = time.perf_counter() - started
    failed += same_work(all_records)
    revision = subprocess.run(["git", "-C", str(tree), "rev-parse", "HEAD"], capture_output=True, text=True)
    manifest = dict(tree=str(tree), revision=revision.stdout.strip(), scenes=str(Path(scenes).resolve()),
                    width=width, seed=seed, photons=photons, threads=threads, methods=methods,
                    seconds=round(total, 1), renders=all_records)
    (out / "renders.json").write_text(json.dumps(manifest, indent=1) + "\n")
    print(f"{len(all_records)} renders in {total:.1f} s", flush=True)
    for r in failed:
        print(f"FAILED {r['scene']} {r['render']}: {r.get('message', '')}", file=sys.stderr)
    return 1 if failed else 0


def same_work(records):
    """Exact methods give the same bits on these scenes, so the images alone cannot show that the method
    setting reached the core; their work counters (photon-sample tests, node visits...) differ. Returns a
    failure record for each pair of methods of a scene whose counters are all equal."""
    failures = []
    for i, a in enumerate(records):
        for b in records[i + 1:]:
            if a["scene"] == b["scene"] and a["method"] != b["method"] and a["iterations"] == b["iterations"] \
                    and a["counters"] and a["counters"] == b["counters"]:
                failures.append(dict(scene=a["scene"], render=f"{a['render']} and {b['render']}",
                                     message="the same work counters: did the method setting reach the core?"))
    return failures


def counter_notes(folder_a, folder_b):
    """Renders whose work counters (renders.json) differ between A and B, counter by counter."""
    manifests = [Path(folder) / "renders.json" for folder in (folder_a, folder_b)]
    if not all(m.exists() for m in manifests):
        return ["(no renders.json on both sides: counters not compared)"]
    a, b = ({(r["scene"], r["render"]): r.get("counters", {}) for r in json.loads(m.read_text())["renders"]}
            for m in manifests)
    notes = []
    for key in sorted(set(a) & set(b)):
        changed = [f"{name} {a[key][name]:g} -> {b[key][name]:g}" for name in sorted(set(a[key]) & set(b[key]))
                   if a[key][name] != b[key][name]]
        changed += [f"{name} only in A" for name in sorted(set(a[key]) - set(b[key]))]
        changed += [f"{name} only in B" for name in sorted(set(b[key]) - set(a[key]))]
        if changed:
            notes.append(f"{key[0]} {key[1]}: " + ", ".join(changed))
    return notes


# --- compare -----------------------------------------------------------------------------------------------

def pass_of(channel):
    """'ViewLayer.Combined.R' -> 'ViewLayer.Combined': a channel's pass in Blender's multilayer naming."""
    return channel.rsplit(".", 1)[0] if "." in channel else channel


def passes_of(channels):
    grouped = {}
    for channel in channels:
        grouped.setdefault(pass_of(channel), []).append(channel)
    return grouped


class Image:
    """An EXR as a backend read it: its size, channel names and whatever the backend compares with."""

    def __init__(self, path, size, channels, data):
        self.path, self.size, self.channels, self.data = path, size, channels, data


class NumpyImages:
    """Reads EXRs with OpenImageIO's Python module and compares float bits with numpy."""
    name = "numpy (OpenImageIO's Python module), bitwise"

    def __init__(self, oiio):
        self.oiio = oiio

    def read(self, path):
        import numpy as np
        source = self.oiio.ImageInput.open(str(path))
        if source is None:
            raise SystemExit(f"image_identity: cannot read {path}")
        spec = source.spec()
        pixels = np.asarray(source.read_image(format=self.oiio.FLOAT), dtype=np.float32)
        source.close()
        return Image(path, (spec.width, spec.height), list(spec.channelnames),
                     pixels.reshape(spec.height, spec.width, spec.nchannels))

    def difference(self, a, b, channels_a, channels_b):
        """(max abs difference, pixels differing in any of these channels) of two images of one size."""
        import numpy as np
        x = a.data[..., [a.channels.index(c) for c in channels_a]]
        y = b.data[..., [b.channels.index(c) for c in channels_b]]
        differs = (x.view(np.uint32) != y.view(np.uint32)).any(axis=-1)
        with np.errstate(invalid="ignore"):
            gap = np.abs(x.astype(np.float64) - y.astype(np.float64))
        gap = np.where(np.isnan(gap), np.inf, gap)      # NaN on one side only: as different as can be
        gap[~differs] = 0.0
        return float(gap.max()) if gap.size else 0.0, int(differs.sum())


class IdiffImages:
    """Compares with OpenImageIO's command-line tools: idiff for a whole file, oiiotool --diff for some channels.
    Both compare values, with fail and warn thresholds 0: any nonzero difference counts."""
    name = "idiff / oiiotool --diff (thresholds 0)"

    def read(self, path):
        info = subprocess.run(["oiiotool", "--info", "-v", str(path)], capture_output=True, text=True, check=True)
        size = re.search(r":\s*(\d+)\s*x\s*(\d+)", info.stdout)
        channels = re.search(r"channel list:\s*(.*)", info.stdout)
        if size is None or channels is None:
            raise SystemExit(f"image_identity: cannot read oiiotool's report on {path}:\n{info.stdout}")
        return Image(path, (int(size.group(1)), int(size.group(2))),
                     [c.strip() for c in channels.group(1).split(",") if c.strip()], None)

    def difference(self, a, b, channels_a, channels_b):
        if channels_a == a.channels and channels_b == b.channels and a.channels == b.channels:
            command = ["idiff", "-fail", "0", "-warn", "0", str(a.path), str(b.path)]
        else:
            command = ["oiiotool", str(a.path), "--ch", ",".join(channels_a), str(b.path), "--ch",
                       ",".join(channels_b), "--fail", "0", "--warn", "0", "--diff"]
        result = subprocess.run(command, capture_output=True, text=True)
        report = result.stdout + result.stderr
        biggest = re.search(r"Max error\s*=\s*(\S+)", report)
        over = re.search(r"(\d+) pixels \([^)]*\) over", report)
        if biggest and over:
            return float(biggest.group(1)), int(over.group(1))
        if result.returncode == 0 and "PASS" in report:
            return 0.0, 0
        raise SystemExit(f"image_identity: cannot read the comparison of {a.path} and {b.path} "
                         f"(exit {result.returncode}):\n{report}")


def image_backend():
    try:
        import OpenImageIO
        import numpy  # noqa: F401  (NumpyImages needs it)
        return NumpyImages(OpenImageIO)
    except ImportError:
        return IdiffImages()


def render_name(file_name):
    """'atrium__cluster_cone_x3.exr' -> ('atrium', 'cluster_cone_x3')."""
    scene, _, render = Path(file_name).stem.rpartition(NAME_SEPARATOR)
    return scene, render


def is_exact(render):
    method = re.sub(r"_x\d+$", "", render)
    return method not in APPROXIMATE_METHODS


def compare_file(images, path_a, path_b):
    """(max abs difference, differing pixels, notes: the passes that differ or exist on one side only).
    The two images are the same when the pixel count is 0 and there are no notes."""
    a, b = images.read(path_a), images.read(path_b)
    if a.size != b.size:
        return float("inf"), 0, [f"size {a.size[0]}x{a.size[1]} vs {b.size[0]}x{b.size[1]}"]
    passes_a, passes_b = passes_of(a.channels), passes_of(b.channels)
    notes = [f"{name} only in A" for name in passes_a if name not in passes_b]
    notes += [f"{name} only in B" for name in passes_b if name not in passes_a]
    common = [name for name in passes_a if name in passes_b]
    notes += [f"{name} has channels {passes_a[name]} vs {passes_b[name]}" for name in common
              if passes_a[name] != passes_b[name]]
    common = [name for name in common if passes_a[name] == passes_b[name]]
    # One comparison over every shared channel; pass by pass only where that finds a difference.
    shared = [c for name in common for c in passes_a[name]]
    largest, pixels = images.difference(a, b, shared, shared)
    if pixels:
        for name in common:
            gap, count = images.difference(a, b, passes_a[name], passes_b[name])
            if count:
                notes.append(f"{name.rsplit('.', 1)[-1]}: {count} px, max {gap:.3g}")
    return largest, pixels, notes


def compare(folder_a, folder_b):
    folder_a, folder_b = Path(folder_a).resolve(), Path(folder_b).resolve()
    names = sorted({p.name for p in folder_a.glob("*.exr")} | {p.name for p in folder_b.glob("*.exr")})
    if not names:
        raise SystemExit(f"image_identity: no .exr files in {folder_a} or {folder_b}")
    images = image_backend()
    print(f"A = {folder_a}\nB = {folder_b}\ncompared with {images.name}\n")
    header = ("scene", "render", "identical", "max abs diff", "differing px", "passes that differ")
    rows, failures = [], 0
    for name in names:
        scene, render = render_name(name)
        exact = is_exact(render)
        path_a, path_b = folder_a / name, folder_b / name
        if not path_a.exists() or not path_b.exists():
            rows.append((scene, render, "MISSING", "-", "-", "only in " + ("B" if path_b.exists() else "A")))
            failures += exact
            continue
        largest, pixels, notes = compare_file(images, path_a, path_b)
        same = pixels == 0 and not notes
        verdict = "yes" if same else ("NO" if exact else "no (approximate: not a failure)")
        rows.append((scene, render, verdict, f"{largest:.6g}", str(pixels), "; ".join(notes) or "-"))
        failures += exact and not same
    widths = [max(len(str(row[i])) for row in (header, *rows)) for i in range(len(header))]
    for row in (header, tuple("-" * w for w in widths), *rows):
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths)).rstrip())
    exact_count = sum(is_exact(render_name(n)[1]) for n in names)
    print(f"\n{exact_count - failures} of {exact_count} exact-method images identical"
          + (f"; {failures} DIFFER OR ARE MISSING" if failures else ""))
    # The core's work counters tell whether the same work was done (informational: a refactor may rename one).
    notes = counter_notes(folder_a, folder_b)
    print("work counters (renders.json, not a failure): " + ("all the same" if not notes else ""))
    for note in notes:
        print("  " + note)
    return 1 if failures else 0


# --- check -------------------------------------------------------------------------------------------------

def build(tree, ccache_basedir):
    env = dict(os.environ, CCACHE_BASEDIR=ccache_basedir)
    print(f"building {tree} (CCACHE_BASEDIR={ccache_basedir})", flush=True)
    for command in (BUILD_CONFIGURE, BUILD_COMPILE):
        subprocess.run(command, cwd=tree, env=env, check=True, stdout=subprocess.DEVNULL)


def check(args):
    here = Path(subprocess.run(["git", "-C", str(REPOSITORY), "rev-parse", "--show-toplevel"],
                               capture_output=True, text=True, check=True).stdout.strip())
    # Beside this tree by default, so that CCACHE_BASEDIR (their common parent) covers both and ccache hits.
    workdir = Path(tempfile.mkdtemp(prefix="image-identity-", dir=args.workdir or here.parent))
    base_tree = workdir / "base"
    basedir = os.environ.get("CCACHE_BASEDIR") or os.path.commonpath([here, workdir])
    if basedir == "/":
        basedir = str(here.parent)
    subprocess.run(["git", "-C", str(here), "worktree", "add", "--detach", str(base_tree), args.base], check=True)
    try:
        build(base_tree, basedir)
        build(here, basedir)
        options = (args.scenes, args.width, args.methods, args.seed, args.photons, args.threads)
        status = render_tree(base_tree, workdir / "renders-base", *options)
        status |= render_tree(here, workdir / "renders-here", *options)
        status |= compare(workdir / "renders-base", workdir / "renders-here")
    finally:
        subprocess.run(["git", "-C", str(here), "worktree", "remove", "--force", str(base_tree)])
        if not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)
        else:
            print(f"renders kept in {workdir}")
    return status


# --- command line ------------------------------------------------------------------------------------------

def add_render_options(parser):
    parser.add_argument("--scenes", default=str(REPOSITORY / "blend_scenes"),
                        help="folder of the .blend files to render (default: this repository's blend_scenes)")
    parser.add_argument("--width", type=int, default=96, help="image width in pixels; height keeps the aspect")
    parser.add_argument("--methods", default=",".join(DEFAULT_METHODS),
                        help="comma-separated exact methods, or 'auto' for the add-on's enum minus directional")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--photons", type=int, default=20_000)
    parser.add_argument("--threads", type=int, default=2, help="set only where the add-on has the property")


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    render = commands.add_parser("render", help="render every scene of --scenes with a tree's build")
    render.add_argument("--tree", required=True, help="the tree whose build/blender add-on renders")
    render.add_argument("--out", required=True, help="folder for the EXRs (its old EXRs are removed)")
    add_render_options(render)
    comparison = commands.add_parser("compare", help="compare two render folders")
    comparison.add_argument("a")
    comparison.add_argument("b")
    checking = commands.add_parser("check", help="build, render and compare REV against this tree")
    checking.add_argument("--base", required=True, help="git revision to compare against")
    checking.add_argument("--workdir", default=None, help="where the temporary folder goes (default: this tree's parent folder)")
    checking.add_argument("--keep", action="store_true", help="keep the renders (the worktree is always removed)")
    add_render_options(checking)
    args = parser.parse_args(argv)
    if args.command in ("render", "check"):
        args.methods = [m for m in args.methods.split(",") if m]
    if args.command == "render":
        return render_tree(args.tree, args.out, args.scenes, args.width, args.methods, args.seed, args.photons,
                           args.threads)
    if args.command == "compare":
        return compare(args.a, args.b)
    return check(args)


def main_in_blender(argv):
    """Entry point under `blender --python`: the records go to stdout, one JSON per line."""
    if argv[0] == "addon-methods":
        records = [dict(methods=addon_methods())]
    else:
        records = blender_render(json.loads(argv[1]))
    for record in records:
        print(RECORD_PREFIX + json.dumps(record), flush=True)


if __name__ == "__main__":
    if "bpy" in sys.modules:      # run by Blender (blender_command)
        main_in_blender(sys.argv[sys.argv.index("--") + 1:])
    else:
        sys.exit(main(sys.argv[1:]))
