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


def border_region(scene, width, height):
    """The pixels a render covers, (x0, y0, x1, y1) with rows counted from the BOTTOM as Blender does: the
    render border when it is on (Blender truncates border * size to whole pixels), else the whole frame."""
    render = scene.render
    if not render.use_border:
        return (0, 0, width, height)
    x0, x1 = int(render.border_min_x * width), int(render.border_max_x * width)
    y0, y1 = int(render.border_min_y * height), int(render.border_max_y * height)
    return (x0, y0, max(x1, x0 + 1), max(y1, y0 + 1))


def crop_projection(projection, region, width, height):
    """The projection that maps the pixels `region` of a width x height frame onto the whole image: a render
    border then costs only its own pixels, with exactly the rays the full frame would have traced there."""
    x0, y0, x1, y1 = region
    # The region in normalised device coordinates ([-1, 1], y up), then its centre and half extent.
    left, right = 2.0 * x0 / width - 1.0, 2.0 * x1 / width - 1.0
    bottom, top = 2.0 * y0 / height - 1.0, 2.0 * y1 / height - 1.0
    cx, cy, sx, sy = (left + right) / 2, (bottom + top) / 2, (right - left) / 2, (top - bottom) / 2
    # Clip-space x' = (x - cx * w) / sx (and the same for y): NDC x' = (x/w - cx) / sx.
    crop = np.array([[1 / sx, 0, 0, -cx / sx],
                     [0, 1 / sy, 0, -cy / sy],
                     [0, 0, 1, 0],
                     [0, 0, 0, 1]], dtype=np.float64)
    return crop @ np.asarray(projection, dtype=np.float64)


def export_camera(core, depsgraph, camera_object, width, height, notes, region=None):
    """Build a core Camera for `camera_object` (the scene camera or the engine's camera_override).

    `region` (x0, y0, x1, y1), rows from the bottom, renders only those pixels of the frame (render border)."""
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
    projection = matrix_to_numpy(projection)
    if region is not None and tuple(region) != (0, 0, width, height):
        projection = crop_projection(projection, region, width, height)
        width, height = region[2] - region[0], region[3] - region[1]
    return core.Camera(to_world=matrix_to_numpy(to_world), projection=projection, width=width, height=height)


def matrix_to_numpy(matrix):
    """mathutils.Matrix -> (4, 4) row-major numpy array (a Matrix iterates over its rows)."""
    return np.array([tuple(row) for row in matrix], dtype=np.float64)
