"""Image Texture nodes -> core textures (base colours looked up at the hit's UV, or read by node programs).

Cycles' Image Texture defaults are what the core does: UV coordinates from the render UV map, Linear
(bilinear) interpolation, Repeat extension, flat projection, the image's straight colour. The image reaches the
core either as a file path, read there with OpenImageIO, or, for packed, generated or otherwise file-less images,
as Blender's own pixels. A core without OpenImageIO (IMAGE_FILES False: the Blender extension's module) gets
Blender's pixels for every image. Colour spaces: 'sRGB' images are decoded with the sRGB curve, linear and
non-colour data are used as stored; Blender's float buffers are already linear.

Anything else (another coordinate source, Closest or Cubic interpolation, Clip/Extend, box or sphere
projection, image sequences, UDIM tiles, colour spaces other than sRGB/linear) is rendered the default way
and a note names what was approximated.
"""

import os
from dataclasses import dataclass

import bpy
import numpy as np

# Cycles renders an Image Texture node without an image (or with an unreadable one) in this colour.
MISSING_IMAGE_COLOR = (1.0, 0.0, 1.0)

# Blender colour spaces whose data is used unchanged (scene-linear or non-colour data).
# Blender 3.x calls scene-linear Rec.709 "Linear", 4.x "Linear Rec.709".
_LINEAR_SPACES = {"Linear", "Linear Rec.709", "Non-Color", "Raw", "Linear ACES", "Linear ACEScg", "XYZ",
                  "scene_linear"}


@dataclass
class TextureRef:
    image: object          # bpy.types.Image
    key: str               # one core texture per key
    color_space: str       # "sRGB" | "linear", as the core takes it
    path: str = None       # file to read with OpenImageIO; None: use the image's pixels


def core_reads_image_files():
    """Whether the compiled core reads image files itself: True for the build against Debian's libraries, False for
    the Blender extension's module (no OpenImageIO), which then gets Blender's pixels for every image."""
    try:
        from .._core import IMAGE_FILES
    except ImportError:            # no core at all: nothing will be rendered, pixels are the safe answer
        return False
    return bool(IMAGE_FILES)


def texture_reference(node, notes, program=False):
    """(TextureRef or None, colour to use when there is no texture) for an Image Texture node (or an Environment
    Texture node in a program). With `program` the node is compiled to a node program (export/shader_program.py),
    which renders its coordinates, interpolation, extension and projection: only the image itself is noted."""
    image = node.image
    if image is None:
        notes.append(f"{node.bl_label} node without an image: rendered magenta, as Cycles does")
        return None, MISSING_IMAGE_COLOR
    if not program:
        if node.inputs["Vector"].is_linked:
            notes.append(f"image '{image.name}': texture coordinates from other nodes ignored, the UV map used")
        if node.interpolation != 'Linear':
            notes.append(f"image '{image.name}': {node.interpolation} interpolation rendered as Linear")
        if node.extension != 'REPEAT':
            notes.append(f"image '{image.name}': extension {node.extension} rendered as Repeat")
        if node.projection != 'FLAT':
            notes.append(f"image '{image.name}': {node.projection.lower()} projection rendered as flat (UV)")
    if image.source in ('SEQUENCE', 'MOVIE', 'TILED'):
        notes.append(f"image '{image.name}': {image.source.lower()} image rendered with its first frame or tile")

    space_name = image.colorspace_settings.name
    if space_name in _LINEAR_SPACES:
        file_space = "linear"
    else:
        file_space = "sRGB"
        if space_name != "sRGB":
            notes.append(f"image '{image.name}': colour space {space_name} decoded as sRGB")

    path = None
    if image.source in ('FILE', 'SEQUENCE') and image.packed_file is None and core_reads_image_files():
        candidate = bpy.path.abspath(image.filepath, library=image.library)
        if os.path.isfile(candidate):
            path = candidate
    if path is not None:
        color_space = file_space       # the file's values, as its colour space says
    else:
        # Blender's float buffers are already scene-linear; byte buffers hold the encoded values.
        color_space = "linear" if image.is_float else file_space
    key = f"{image.name_full}|{color_space}|{path}"
    return TextureRef(image=image, key=key, color_space=color_space, path=path), (0.8, 0.8, 0.8)


def add_texture(core_scene, reference):
    """Add the image of `reference` to the core scene; returns its texture index. Raises ValueError when the
    image cannot be read (the caller turns it into a note)."""
    image = reference.image
    if reference.path is not None:
        return core_scene.add_texture(name=image.name, path=reference.path, color_space=reference.color_space)
    count = len(image.pixels)          # reading the pixels loads the image if it was not yet
    width, height = image.size
    channels = image.channels
    if count == 0 or width * height * channels != count:
        raise ValueError("the image has no pixels")
    pixels = np.empty(count, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    # Blender keeps float buffers associated with alpha (premultiplied), byte buffers straight.
    return core_scene.add_texture(name=image.name, pixels=pixels.reshape(height, width, channels),
                                  color_space=reference.color_space,
                                  alpha="premultiplied" if image.is_float else "straight")
