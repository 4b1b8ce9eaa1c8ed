"""Run by test_extension.py, under the Python of a `bpy` wheel (Blender 4.2+ as a module), in a mount namespace where
Debian's Embree, oneTBB and OpenImageIO are hidden and with BLENDER_USER_RESOURCES pointing to an empty folder.
Three steps, one process each, as a user would go:

    install ZIP        what `blender --command extension install-file -r user_default --enable ZIP` does: the same
                       command-line handler of Blender's extension add-on (bl_pkg), which calls
                       bpy.ops.extensions.package_install_files and saves the preferences
    render BLEND TMP   a fresh Blender: load the saved preferences (which enables the extension, as Blender's start
                       does), render BLEND at 32x32 with 10k photons and a file-textured plane; Blender's own
                       libraries are loaded into the global symbol scope first (RTLD_GLOBAL), as in the blender
                       program, where its Embree 4 is linked in
    module DIR         the installed extension's package imported by plain Python, without Blender (so without
                       Blender's oneTBB either), rendering through its scripting API: its libraries must all come
                       from DIR/lib

Each step prints one line `RESULT {json}` for the test to read; failures raise (exit code 1).
"""

import json
import os
import platform
import sys
import time


def hidden_library_refused():
    """Debian's Embree must not load here: the namespace hides it (a loader error, not a missing-file one)."""
    import ctypes
    try:
        ctypes.CDLL(f"/usr/lib/{platform.machine()}-linux-gnu/libembree3.so.3")
    except OSError as error:
        return str(error)
    raise AssertionError("Debian's libembree3 is visible: the mount namespace did not hide it")


def mapped_libraries(*words):
    """Paths of the mapped files of this process whose name holds one of `words`."""
    found = set()
    with open("/proc/self/maps") as maps:
        for line in maps:
            fields = line.split()
            if len(fields) >= 6 and any(word in os.path.basename(fields[5]) for word in words):
                found.add(fields[5])
    return sorted(found)


def report(**values):
    print("RESULT " + json.dumps(values), flush=True)


def install(zip_path):
    start = time.perf_counter()
    import bpy                                               # noqa: F401  (starts Blender)
    import bl_pkg                                            # Blender's extension add-on, on by default
    code = bl_pkg.cli_extension(["install-file", "-r", "user_default", "--enable", zip_path])
    assert code == 0, f"install-file exited with {code}"
    report(step="install", seconds=time.perf_counter() - start, refused=hidden_library_refused())


def textured_plane_render(engine, folder):
    """A plane textured from a PNG file, half red, half sRGB-0.5 grey, under a white world: the extension's core
    reads no files, so this checks that Blender's pixels of a file image reach it, decoded like the file would be."""
    import bpy
    import numpy as np

    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    image = bpy.data.images.new("Halves", 8, 8)
    pixels = np.zeros((8, 8, 4), dtype=np.float32)
    pixels[:, :4, :3] = (1.0, 0.0, 0.0)
    pixels[:, 4:, :3] = 0.5
    pixels[..., 3] = 1.0
    image.pixels.foreach_set(pixels.ravel())
    image.filepath_raw = os.path.join(folder, "halves.png")
    image.file_format = 'PNG'
    image.save()
    image = bpy.data.images.load(os.path.join(folder, "halves.png"))

    bpy.ops.mesh.primitive_plane_add(size=2.0)
    material = bpy.data.materials.new("Textured")
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.clear()
    diffuse = tree.nodes.new("ShaderNodeBsdfDiffuse")
    tree.links.new(diffuse.outputs[0], tree.nodes.new("ShaderNodeOutputMaterial").inputs["Surface"])
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    tree.links.new(texture.outputs["Color"], diffuse.inputs["Color"])
    bpy.context.active_object.data.materials.append(material)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.location = (0.0, 0.0, 10.0)
    camera.data.type, camera.data.ortho_scale = 'ORTHO', 2.0
    scene.collection.objects.link(camera)
    scene.camera = camera
    world = bpy.data.worlds.new("Uniform")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scene.world = world
    result = render(scene, 16, 1000, os.path.join(folder, "textured.exr"))
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    assert not engine.last_outcome.warnings, engine.last_outcome.warnings
    left, right = result[4:12, 1:6, :3].mean(axis=(0, 1)), result[4:12, 10:15, :3].mean(axis=(0, 1))
    grey = ((0.5 + 0.055) / 1.055) ** 2.4
    assert np.allclose(left, (1.0, 0.0, 0.0), atol=0.04), left
    assert np.allclose(right, grey, rtol=0.05), right
    return [round(float(v), 4) for v in (*left, *right)]


def render(scene, size, photons, path):
    """Render `scene` at size x size with F12's operator, written as EXR by Blender, read back by Blender."""
    import bpy
    import numpy as np

    scene.render.engine = 'PHOTONSPLAT'
    scene.render.resolution_x = scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.photonsplat.photons = photons
    scene.render.filepath = path
    scene.render.use_file_extension = False
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.color_mode = 'RGBA'
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path, check_existing=False)
    pixels = np.empty(size * size * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(size, size, 4)


def blender_library_folder():
    """Where Blender keeps its shared libraries: lib/ beside its version folder (blender.org's program and the wheel)."""
    import bpy
    return os.path.join(os.path.dirname(bpy.utils.resource_path('LOCAL')), "lib")


def render_step(blend, folder):
    start = time.perf_counter()
    refused = hidden_library_refused()
    # The blender program links its libraries (Embree 4 among them, with Embree 3's function names) into the global
    # symbol scope; Python imports a module with RTLD_LOCAL. Import bpy the program's way.
    flags = sys.getdlopenflags()
    sys.setdlopenflags(os.RTLD_GLOBAL | os.RTLD_NOW)
    import bpy
    sys.setdlopenflags(flags)
    import numpy as np

    bpy.ops.wm.read_userpref()                  # the saved preferences, as Blender's start reads them
    name = "bl_ext.user_default.photonsplat"
    enabled = [addon.module for addon in bpy.context.preferences.addons]
    assert name in enabled, f"the extension is not enabled after install: {enabled}"
    assert "photonsplat" not in sys.modules, "a legacy photonsplat add-on is visible"
    package = sys.modules[name]
    engine = sys.modules[name + ".engine"]
    assert package.CORE_IMPORT_ERROR is None, package.CORE_IMPORT_ERROR
    assert package.IMAGE_FILES is False, "the extension's module should be the one without OpenImageIO"

    bpy.ops.wm.open_mainfile(filepath=blend, load_ui=False)
    pixels = render(bpy.context.scene, 32, 10_000, os.path.join(folder, "cornell.exr"))
    assert engine.last_outcome.status == "finished", engine.last_outcome.message
    rgb = pixels[..., :3]
    assert np.isfinite(pixels).all(), "non-finite pixels"
    assert rgb.mean() > 0.05, f"black image (mean {rgb.mean()})"
    halves = textured_plane_render(engine, folder)
    report(step="render", seconds=time.perf_counter() - start, refused=refused, package=package.__file__,
           mean=float(rgb.mean()), textured=halves, bpy_lib=blender_library_folder(),
           libraries=mapped_libraries("embree", "tbb", "OpenImageIO"))


def module_step(folder):
    """The installed extension's package imported by plain Python (its scripting API needs no Blender): nothing of
    Blender's is loaded, so its oneTBB must come from lib/ too."""
    import numpy as np

    refused = hidden_library_refused()
    sys.path.insert(0, os.path.dirname(folder))
    import photonsplat as ps
    assert os.path.dirname(ps.__file__) == folder, ps.__file__
    assert ps.CORE_IMPORT_ERROR is None, ps.CORE_IMPORT_ERROR
    scene = ps.Scene()
    white = scene.add_material(name="white", kind="diffuse", color=(0.8, 0.8, 0.8))
    scene.add_mesh(name="floor", vertices=np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], np.float32),
                   triangles=np.array([[0, 1, 2], [0, 2, 3]], np.int32))
    scene.add_point_light(name="lamp", position=(0, 0, 2), intensity=(80, 80, 80))
    camera = ps.look_at_camera(eye=(0, -6, 3), target=(0, 0, 0), width=32, height=32)
    image, _ = ps.render(scene, camera, ps.RenderSettings(photons=10_000))
    assert np.isfinite(image).all() and image[..., :3].mean() > 0.05, image[..., :3].mean()
    report(step="module", refused=refused, mean=float(image[..., :3].mean()), image_files=ps.IMAGE_FILES,
           libraries=mapped_libraries("embree", "tbb", "OpenImageIO"))


def main():
    step, *arguments = sys.argv[1:]
    if step == "install":
        install(*arguments)
    elif step == "render":
        render_step(*arguments)
    elif step == "module":
        module_step(*arguments)
    else:
        raise SystemExit(f"unknown step {step!r}")


main()
