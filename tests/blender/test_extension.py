"""The Blender extension (CMake target extension_zip, build/photonsplat-<version>-linux_x64.zip): what it holds, that
its module has no OpenImageIO, and that it installs from the command line into an empty Blender user folder and
renders on a machine without Debian's Embree, oneTBB and OpenImageIO.

Blender 4.2+ only (extensions do not exist before), so these run under the `bpy` wheels (run_pytest.py), not under
Debian's Blender 3.4. "Without Debian's libraries" is a mount namespace (unshare) in which every file of libembree3,
libtbb* and libOpenImageIO* is covered by /dev/null: a library there then fails to load, as on a machine that never
had the -dev packages. Where unshare cannot make one, the test fails and says so: it is the acceptance test of the
extension, a skip would hide that it did not run.
"""

import json
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import time
import tomllib
import zipfile
from pathlib import Path

import bpy
import pytest
from blender_helpers import BLEND_SCENES, REPO

pytestmark = pytest.mark.skipif(bpy.app.version < (4, 2, 0),
                                reason="extensions (blender_manifest.toml) exist from Blender 4.2 on")

PLATFORMS = {"x86_64": "linux_x64", "aarch64": "linux_arm64"}
# What the namespace hides: Debian's copies of what the extension must bring or do without.
HIDDEN = ("libembree3*", "libtbb*", "libOpenImageIO*")
LIBRARY_FOLDER = Path(f"/usr/lib/{platform.machine()}-linux-gnu")      # Debian's multiarch folder
# Libraries the extension may leave to the system (the manylinux policy's, as cmake/extension_zip.py).
SYSTEM = {"libc.so.6", "libm.so.6", "libdl.so.2", "librt.so.1", "libpthread.so.0", "libstdc++.so.6",
          "libgcc_s.so.1", "ld-linux-x86-64.so.2", "linux-vdso.so.1"}


def project_version():
    text = (REPO / "CMakeLists.txt").read_text()
    return re.search(r"project\(photonsplat VERSION (\S+)", text).group(1)


def extension_zip():
    path = REPO / "build" / f"photonsplat-{project_version()}-{PLATFORMS[platform.machine()]}.zip"
    assert path.exists(), f"{path} is missing: build it with cmake --build build --target extension_zip"
    return path


@pytest.fixture(scope="module")
def unpacked(tmp_path_factory):
    """The zip's files, unpacked as Blender unpacks them."""
    folder = tmp_path_factory.mktemp("extension") / "photonsplat"
    with zipfile.ZipFile(extension_zip()) as archive:
        archive.extractall(folder)
    return folder


def module_of(folder):
    (module,) = folder.glob("_core.*.so")
    return module


def test_zip_holds_the_manifest_the_package_the_module_and_its_libraries():
    names = set(zipfile.ZipFile(extension_zip()).namelist())
    # The package at the zip's root, as `blender --command extension build` lays it out.
    assert {"blender_manifest.toml", "__init__.py", "engine.py", "export/textures.py"} <= names
    assert any(re.fullmatch(r"_core\.cpython-311-[^/]+\.so", n) for n in names)
    assert {"lib/libembree3.so.3", "lib/libtbb.so.12"} <= names
    assert not any("__pycache__" in n or "OpenImageIO" in n for n in names)
    manifest = tomllib.loads(zipfile.ZipFile(extension_zip()).read("blender_manifest.toml").decode())
    assert manifest["id"] == "photonsplat" and manifest["type"] == "add-on"
    assert manifest["version"] == project_version()
    assert manifest["blender_version_min"] == "4.2.0"
    # The module is CPython 3.11's: Blender 5.1 (Python 3.13) must refuse the package rather than fail to load it.
    assert manifest["blender_version_max"] == "5.1.0"
    assert manifest["platforms"] == [PLATFORMS[platform.machine()].replace("_", "-")]


def test_blender_accepts_the_zip():
    """Blender's own validation of a package file (what Install from Disk runs first), strict as for a build."""
    from bl_pkg.cli import blender_ext

    manifest = blender_ext.pkg_manifest_from_archive_and_validate(str(extension_zip()), strict=True)
    assert not isinstance(manifest, str), manifest
    assert manifest.id == "photonsplat" and manifest.version == project_version()


def test_the_extension_module_needs_no_openimageio(unpacked):
    module = module_of(unpacked)
    dynamic = subprocess.run(["readelf", "-d", str(module)], capture_output=True, text=True, check=True).stdout
    needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", dynamic))
    assert needed - SYSTEM == {"libtbb.so.12"}, needed
    # DT_RPATH (not RUNPATH): also searched for the dependencies of lib/'s libraries (CMakeLists.txt says why).
    assert re.search(r"\(RPATH\)\s+Library rpath: \[\$ORIGIN/lib\]", dynamic), dynamic
    # Unpacked beside its lib/, everything it needs resolves there or to the system.
    resolved = subprocess.run(["ldd", str(module)], capture_output=True, text=True, check=True).stdout
    assert "OpenImageIO" not in resolved and "not found" not in resolved, resolved
    assert f"libtbb.so.12 => {unpacked}/lib/libtbb.so.12" in resolved, resolved
    for library in (unpacked / "lib").glob("*.so*"):
        assert not library.is_symlink()


def hidden_files():
    """Every file of Debian's Embree 3, oneTBB and OpenImageIO (symbolic links lead to them)."""
    files = set()
    for pattern in HIDDEN:
        for path in LIBRARY_FOLDER.glob(pattern):
            if path.is_file():
                files.add(path.resolve())
    return sorted(files)


def namespace_command():
    """`unshare` making a private mount namespace (as root, or mapped to root where user namespaces are allowed)."""
    if shutil.which("unshare") is None:
        pytest.fail("unshare (util-linux) is not installed: the extension's acceptance test needs it to hide "
                    "Debian's Embree, oneTBB and OpenImageIO")
    command = ["unshare", "--mount", "--propagation", "private"]
    if os.geteuid() != 0:
        command.append("--map-root-user")
    probe = subprocess.run([*command, "true"], capture_output=True, text=True)
    if probe.returncode != 0:
        pytest.fail(f"cannot make a mount namespace with {' '.join(command)} ({probe.stderr.strip()}): the "
                    "extension's acceptance test must run as root or where unprivileged user namespaces are allowed")
    return command


def results(log):
    return {r["step"]: r for r in (json.loads(line[len("RESULT "):]) for line in log.splitlines()
                                   if line.startswith("RESULT "))}


def test_extension_installs_from_the_command_line_and_renders_without_debians_libraries(tmp_path):
    hidden = hidden_files()
    assert any("libembree3" in p.name for p in hidden) and any("libtbb" in p.name for p in hidden)
    resources = tmp_path / "user_resources"
    resources.mkdir()
    # An empty Blender user folder: BLENDER_USER_RESOURCES holds config/, scripts/ and extensions/; no other
    # BLENDER_* variable (the suite runs with BLENDER_USER_SCRIPTS=build/blender, the legacy add-on's folder).
    env = {k: v for k, v in os.environ.items() if not k.startswith("BLENDER_") and k != "PYTHONPATH"}
    env.update(BLENDER_USER_RESOURCES=str(resources), TMPDIR=str(tmp_path))
    installed = resources / "extensions" / "user_default" / "photonsplat"
    child = [sys.executable, str(REPO / "tests/blender/extension_install_and_render.py")]
    steps = [
        [*child, "install", str(extension_zip())],
        [*child, "render", str(BLEND_SCENES / "cornell_caustics.blend"), str(tmp_path)],
        [*child, "module", str(installed)],
    ]
    script = " && ".join([*(f"mount --bind /dev/null {shlex.quote(str(p))}" for p in hidden),
                          *(shlex.join(step) for step in steps)])
    start = time.perf_counter()
    run = subprocess.run([*namespace_command(), "sh", "-c", script], env=env, cwd=tmp_path,
                         capture_output=True, text=True, timeout=300)
    seconds = time.perf_counter() - start
    log = run.stdout + run.stderr
    assert run.returncode == 0, log[-4000:]
    steps = results(log)
    assert set(steps) == {"install", "render", "module"}, log[-4000:]
    install, render, module = steps["install"], steps["render"], steps["module"]
    print(f"\nextension: {extension_zip().stat().st_size / 2**20:.1f} MiB; install {install['seconds']:.1f} s, "
          f"render {render['seconds']:.1f} s (both with Blender's start), all three steps {seconds:.1f} s")
    print("hidden:", len(hidden), "files; a hidden library fails to load with:", render["refused"])
    print(f"textured plane, left and right halves: {render['textured']}")
    for step in (render, module):
        print(f"{step['step']}: mean {step['mean']:.3f}", *step["libraries"], sep="\n  ")

    assert (installed / "blender_manifest.toml").exists()
    assert render["package"] == str(installed / "__init__.py")        # bl_ext.user_default.photonsplat
    assert render["mean"] > 0.05
    lib = str(installed / "lib") + "/"
    bpy_lib = render["bpy_lib"] + "/"
    for step in (render, module):
        libraries = step["libraries"]
        assert not any(p.startswith(str(LIBRARY_FOLDER)) for p in libraries), libraries
        # Blender's own OpenImageIO (it reads the scene's images) may be there; no other.
        assert all(p.startswith(bpy_lib) for p in libraries if "OpenImageIO" in p), libraries
        embree3 = [p for p in libraries if "libembree3" in p]
        assert embree3 and all(p.startswith(lib) for p in embree3), libraries
    # Inside Blender, oneTBB is Blender's own when it ships one (4.2+ does: a library of the same soname is shared);
    # otherwise, and in plain Python, the extension's.
    assert all(p.startswith((lib, bpy_lib)) for p in render["libraries"] if "libtbb" in p), render["libraries"]
    assert any("libembree4" in p for p in render["libraries"])     # Blender's Embree 4 was there all along
    assert [p for p in module["libraries"] if "libtbb.so" in p] == [lib + "libtbb.so.12"], module["libraries"]
    assert module["image_files"] is False
    assert not any("OpenImageIO" in p for p in module["libraries"]), module["libraries"]
