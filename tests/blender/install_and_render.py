"""Run by test_install.py in a fresh Blender whose user scripts folder is empty: installs the add-on zip as
Preferences > Add-ons > Install does, enables it, renders the caustic Cornell box and checks the image.
Arguments after `--`: the zip, the .blend, an output EXR path."""

import sys

import bpy
import numpy as np

zip_path, blend, output = sys.argv[sys.argv.index("--") + 1:]
bpy.ops.preferences.addon_install(filepath=zip_path)
bpy.ops.preferences.addon_enable(module="photonsplat")
import photonsplat                                          # noqa: E402  (installed just now)
from photonsplat import engine                              # noqa: E402

assert photonsplat.CORE_IMPORT_ERROR is None, photonsplat.CORE_IMPORT_ERROR
print("installed at", photonsplat.__file__)
bpy.ops.wm.open_mainfile(filepath=blend, load_ui=False)
scene = bpy.context.scene
scene.render.engine = 'PHOTONSPLAT'
scene.render.resolution_x = scene.render.resolution_y = 32
scene.render.resolution_percentage = 100
scene.photonsplat.photons = 10_000
scene.render.filepath = output
scene.render.use_file_extension = False
scene.render.image_settings.file_format = 'OPEN_EXR'
bpy.ops.render.render(write_still=True)
assert engine.last_outcome.status == "finished", engine.last_outcome.message
image = bpy.data.images.load(output)
pixels = np.empty(32 * 32 * 4, dtype=np.float32)
image.pixels.foreach_get(pixels)
assert np.isfinite(pixels).all() and pixels.reshape(-1, 4)[:, :3].mean() > 0.05
print("INSTALL_AND_RENDER_OK")
