"""Camera helpers for scripts: build the (to_world, projection) pair that photonsplat.Camera takes.

Blender users get both matrices from Blender itself (see export/camera.py); these helpers are for
scripts that build scenes from numpy arrays.
"""
import math

import numpy as np

from ._core import Camera


def perspective_projection(fov_y_degrees, aspect, near=0.1, far=1000.0):
    """OpenGL-style projection (camera looks down -Z), the convention of Blender's calc_matrix_camera."""
    if not (0.0 < fov_y_degrees < 180.0):
        raise ValueError(f"fov_y_degrees: must be in (0, 180), got {fov_y_degrees}")
    if not (0.0 < near < far):
        raise ValueError(f"near/far: need 0 < near < far, got near={near}, far={far}")
    f = 1.0 / math.tan(math.radians(fov_y_degrees) / 2.0)
    return np.array(
        [
            [f / aspect, 0.0, 0.0, 0.0],
            [0.0, f, 0.0, 0.0],
            [0.0, 0.0, (far + near) / (near - far), 2.0 * far * near / (near - far)],
            [0.0, 0.0, -1.0, 0.0],
        ]
    )


def look_at_camera(eye, target, width, height, up=(0.0, 0.0, 1.0), fov_y_degrees=40.0, near=0.1, far=1000.0):
    """A perspective photonsplat.Camera at `eye` looking at `target` (Blender's +Z up by default)."""
    eye = np.asarray(eye, dtype=np.float64)
    forward = np.asarray(target, dtype=np.float64) - eye
    if not np.all(np.isfinite(forward)) or np.linalg.norm(forward) == 0.0:
        raise ValueError("target: must differ from eye and be finite")
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, np.asarray(up, dtype=np.float64))
    if np.linalg.norm(right) < 1e-9:
        raise ValueError("up: must not be parallel to the viewing direction")
    right /= np.linalg.norm(right)
    true_up = np.cross(right, forward)
    to_world = np.identity(4)
    to_world[:3, 0], to_world[:3, 1], to_world[:3, 2], to_world[:3, 3] = right, true_up, -forward, eye
    projection = perspective_projection(fov_y_degrees, width / height, near, far)
    return Camera(to_world=to_world, projection=projection, width=width, height=height)
