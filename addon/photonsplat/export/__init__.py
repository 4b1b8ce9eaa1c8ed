"""Evaluated Blender depsgraph -> what the native core renders: a Scene, a Camera and RenderSettings.

One module per concept does the conversion (mesh, materials, textures, lights, camera, world; instancing for
how objects become core meshes and instances); sync.py walks the depsgraph and ties them together, for the
final render (export_frame) and the viewport (BlenderSync) alike. The core module is passed in as `core` (the
compiled photonsplat._core), which keeps this code free of import-time dependencies on the native library.
"""

from . import camera  # noqa: F401  (export.camera.resolution: the engine's result size)
from .sync import (  # noqa: F401  (the package's interface)
    BlenderSync,
    ExportError,
    ExportedFrame,
    export_frame,
    render_settings,
    render_settings_kwargs,
    warning_lines,
)
