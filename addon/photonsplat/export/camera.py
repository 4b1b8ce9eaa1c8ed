"""The render camera: position/orientation, projection and resolution, exactly as Cycles frames the image.

Blender's own Object.calc_matrix_camera() builds the projection with the sensor fit, shift, pixel aspect and
clipping Cycles uses, so we hand that matrix to the core instead of re-deriving the field of view.
"""

import numpy as np


class CameraError(Exception):
    """The scene cannot be rendered from its camera (none set, or an unsupported kind)."""


def resolution(scene):
    """Final image size in pixels, with the resolution percentage applied (Blender's integer arithmetic)."""
    render = scene.render
    percentage = render.resolution_percentage
    return (max(1, render.resolution_x * percentage // 100),
            max(1, render.resolution_y * percentage // 100))


def export_camera(core, depsgraph, camera_object, width, height, notes):
    """Build a core Camera for `camera_object` (the scene camera or the engine's camera_override)."""
    if camera_object is None:
        raise CameraError("The scene has no active camera: add one, or set Scene > Camera")
    cam = camera_object.evaluated_get(depsgraph)
    if cam.type != 'CAMERA':
        raise CameraError(f"The active camera '{cam.name}' is a {cam.type.lower()} object, not a camera")
    data = cam.data
    if data.type == 'PANO':
        raise CameraError(f"Camera '{cam.name}': panoramic cameras are not supported, use perspective "
                          "or orthographic")
    if data.dof.use_dof:
        notes.append(f"Camera '{cam.name}': depth of field ignored (rendered as a pinhole)")

    render = depsgraph.scene.render
    projection = cam.calc_matrix_camera(depsgraph, x=width, y=height,
                                        scale_x=render.pixel_aspect_x, scale_y=render.pixel_aspect_y)
    # Cycles drops the object scale of the camera; normalized() makes the rotation columns unit length.
    to_world = cam.matrix_world.normalized()
    return core.Camera(to_world=matrix_to_numpy(to_world), projection=matrix_to_numpy(projection),
                       width=width, height=height)


def matrix_to_numpy(matrix):
    """mathutils.Matrix -> (4, 4) row-major numpy array (a Matrix iterates over its rows)."""
    return np.array([tuple(row) for row in matrix], dtype=np.float64)
