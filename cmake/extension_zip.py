"""Writes the Blender extension (Blender 4.2+): build/photonsplat-<version>-<platform>.zip, run by the extension_zip
target of CMakeLists.txt with Debian's /usr/bin/python3.

The zip holds, at its root (the layout `blender --command extension build` writes, and what Blender's installer
looks for first):
    blender_manifest.toml          from addon/blender_manifest.toml.in, version filled in by CMake
    __init__.py, engine.py, ...    the add-on package (addon/photonsplat), without __pycache__
    _core.cpython-311-....so       the module built without OpenImageIO (photonsplat_core_bundled), DT_RPATH $ORIGIN/lib
    lib/                           the shared libraries it needs beyond the system's, under their sonames:
                                   Embree 3 (opened by the module by path: --load), what `ldd` says the module and
                                   Embree need (oneTBB), and what oneTBB opens by itself at run time (tbbmalloc)
    lib/licenses/                  the Debian copyright files of the packages those libraries come from

"The system's" is the manylinux policy's list (PEP 600, auditwheel): glibc's libraries, libstdc++, libgcc_s and a few
X11/GL ones every desktop has; everything else is copied. OpenImageIO must not be among them: the build fails if it
is, since the extension exists to do without it.

    python3 extension_zip.py --source addon/photonsplat --manifest build/extension/blender_manifest.toml \\
        --module build/extension/module/_core....so --load /usr/lib/.../libembree3.so.3.13.5=libembree3.so.3 \\
        --stage build/extension/photonsplat --output build/photonsplat-0.1.0-linux_x64.zip
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

# The libraries every Linux system has (auditwheel's manylinux policy, plus the loader and the vDSO): never copied.
SYSTEM_LIBRARIES = {
    "linux-vdso.so.1", "ld-linux-x86-64.so.2", "ld-linux-aarch64.so.1",
    "libc.so.6", "libm.so.6", "libdl.so.2", "librt.so.1", "libpthread.so.0", "libutil.so.1", "libnsl.so.1",
    "libresolv.so.2", "libcrypt.so.1", "libstdc++.so.6", "libgcc_s.so.1",
    "libX11.so.6", "libXext.so.6", "libXrender.so.1", "libICE.so.6", "libSM.so.6", "libGL.so.1",
    "libgobject-2.0.so.0", "libgthread-2.0.so.0", "libglib-2.0.so.0",
}
# Libraries a bundled one opens with dlopen (so ldd does not list them), copied when present beside it:
# oneTBB loads its scalable allocator from its own folder and falls back to malloc without it.
RUNTIME_COMPANIONS = {"libtbb.so.12": ["libtbbmalloc.so.2"]}
# What the extension is built to do without.
FORBIDDEN = re.compile(r"OpenImageIO|libpython", re.IGNORECASE)

LDD_LINE = re.compile(r"^\s*(\S+)\s*=>\s*(\S+)")


def ldd(path):
    """{soname: resolved path} of everything `ldd` lists for `path`; fails on a library it cannot find."""
    run = subprocess.run(["ldd", str(path)], capture_output=True, text=True, check=True)
    found = {}
    for line in run.stdout.splitlines():
        match = LDD_LINE.match(line)
        if not match:
            continue
        name, target = match.groups()
        if target == "not":
            sys.exit(f"extension_zip: {path} needs {name}, which ldd cannot find")
        found[name] = Path(target)
    return found


def soname(path):
    run = subprocess.run(["readelf", "-d", str(path)], capture_output=True, text=True, check=True)
    match = re.search(r"\(SONAME\)\s+Library soname: \[([^\]]+)\]", run.stdout)
    return match.group(1) if match else None


def libraries_to_bundle(module, loaded):
    """{soname: file} to put in lib/: the libraries loaded by path (`loaded`), and the closure of what they and the
    module need, without the system's."""
    bundle = dict(loaded)
    pending = [module, *loaded.values()]
    seen = set()
    while pending:
        path = pending.pop()
        if path in seen:
            continue
        seen.add(path)
        for name, target in ldd(path).items():
            if name in SYSTEM_LIBRARIES or name in bundle:
                continue
            bundle[name] = target
            pending.append(target)
    for name in list(bundle):
        for companion in RUNTIME_COMPANIONS.get(name, []):
            candidate = bundle[name].resolve().parent / companion
            if candidate.exists() and companion not in bundle:
                bundle[companion] = candidate
    forbidden = sorted(name for name in bundle if FORBIDDEN.search(name))
    if forbidden:
        sys.exit(f"extension_zip: the extension's module must not need {', '.join(forbidden)}")
    return bundle


def debian_copyright(path):
    """(package, /usr/share/doc/<package>/copyright) of the Debian package that installed `path`, or None."""
    if shutil.which("dpkg-query") is None:
        return None
    run = subprocess.run(["dpkg-query", "-S", str(path.resolve())], capture_output=True, text=True)
    if run.returncode != 0:
        return None
    package = run.stdout.split(":", 1)[0].strip()
    notice = Path("/usr/share/doc") / package / "copyright"
    return (package, notice) if notice.exists() else None


def check_manifest(path):
    manifest = tomllib.loads(path.read_text())
    for key in ("schema_version", "id", "version", "name", "tagline", "maintainer", "type", "license",
                "blender_version_min", "platforms"):
        if key not in manifest:
            sys.exit(f"extension_zip: {path} lacks {key}")
    if len(manifest["tagline"]) > 64 or not manifest["tagline"][-1].isalnum():
        sys.exit(f"extension_zip: {path}: the tagline must be 64 characters at most, ending without punctuation")


def stage(args, bundle):
    """The extension's folder, as Blender will unpack it."""
    if args.stage.exists():
        shutil.rmtree(args.stage)
    shutil.copytree(args.source, args.stage, ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "*.so"))
    shutil.copy2(args.manifest, args.stage / "blender_manifest.toml")
    shutil.copy2(args.module, args.stage / args.module.name)
    lib = args.stage / "lib"
    (lib / "licenses").mkdir(parents=True)
    for name, path in sorted(bundle.items()):
        shutil.copy2(path.resolve(), lib / name)           # the file itself, under the name the loader asks for
        notice = debian_copyright(path)
        if notice is not None:
            shutil.copy2(notice[1], lib / "licenses" / f"{notice[0]}.copyright")


def write_zip(folder, output):
    """Every file of `folder`, named relative to it, deflated (as Blender's own `extension build` does)."""
    temporary = output.with_name("." + output.name)
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    with zipfile.ZipFile(temporary, "w", zipfile.ZIP_DEFLATED, compresslevel=6) as archive:
        for path in files:
            archive.write(path, path.relative_to(folder).as_posix())
    os.replace(temporary, output)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--source", type=Path, required=True, help="the add-on package folder")
    parser.add_argument("--manifest", type=Path, required=True, help="blender_manifest.toml")
    parser.add_argument("--module", type=Path, required=True, help="the compiled module for the extension")
    parser.add_argument("--load", action="append", default=[], metavar="FILE=NAME",
                        help="a library the module opens by path from lib/, and the name it opens it by")
    parser.add_argument("--stage", type=Path, required=True, help="folder to lay the extension out in")
    parser.add_argument("--output", type=Path, required=True, help="the zip to write")
    args = parser.parse_args()

    check_manifest(args.manifest)
    loaded = {}
    for item in args.load:
        path, _, name = item.partition("=")
        path = Path(path)
        if soname(path) != name:
            sys.exit(f"extension_zip: {path} has soname {soname(path)}, but the module opens it as {name}")
        loaded[name] = path
    bundle = libraries_to_bundle(args.module, loaded)
    stage(args, bundle)
    write_zip(args.stage, args.output)
    size = args.output.stat().st_size / 2**20
    print(f"extension_zip: {args.output.name}, {size:.1f} MiB; lib/: {', '.join(sorted(bundle))}")


if __name__ == "__main__":
    main()
