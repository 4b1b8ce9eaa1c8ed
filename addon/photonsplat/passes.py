"""Render passes of Photon Splat: which exist, when a view layer asks for them, and writing them into Blender's
render result.

Names, channels and types follow Cycles where Cycles has the pass (Combined, Depth, Normal, Emit), so
compositor setups made for Cycles work unchanged; Direct, Indirect and Caustics are Photon Splat's own split of
the light: Combined = Emit + Direct + Indirect, and Caustics is the part of Indirect that Cycles' Caustics
toggles (Light Paths, reflective and refractive) would remove: light that met a glossy, mirror or refracting
surface right after a scatter Cycles labels diffuse (by the closure its camera path picks there).
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RenderPass:
    name: str          # the pass name in the render result and on the compositor's Render Layers node
    channel_ids: str   # one letter per channel, as Blender names them
    kind: str          # 'COLOR' | 'VECTOR' | 'VALUE'
    source: str        # the core's film output (photonsplat.FILM_OUTPUTS) it shows; "" for Combined itself

    def enabled(self, view_layer):
        return _ENABLED[self.name](view_layer)


PASSES = (
    RenderPass("Combined", "RGBA", 'COLOR', ""),
    RenderPass("Depth", "Z", 'VALUE', "depth"),
    RenderPass("Normal", "XYZ", 'VECTOR', "normal"),
    RenderPass("Emit", "RGB", 'COLOR', "emission"),
    RenderPass("Direct", "RGB", 'COLOR', "direct"),
    RenderPass("Indirect", "RGB", 'COLOR', "indirect"),
    RenderPass("Caustics", "RGB", 'COLOR', "caustics"),
)

# Blender's own toggles where they exist (the ones Cycles uses), our view-layer settings for the others.
_ENABLED = {
    "Combined": lambda layer: True,
    "Depth": lambda layer: layer.use_pass_z,
    "Normal": lambda layer: layer.use_pass_normal,
    "Emit": lambda layer: layer.use_pass_emit,
    "Direct": lambda layer: layer.photonsplat.use_pass_direct,
    "Indirect": lambda layer: layer.photonsplat.use_pass_indirect,
    "Caustics": lambda layer: layer.photonsplat.use_pass_caustics,
}


def enabled_passes(view_layer):
    return [p for p in PASSES if p.enabled(view_layer)]


def film_outputs(view_layer):
    """The core film outputs (RenderSettings.outputs) a render of this view layer needs: only the enabled passes
    are made, and held while a progressive render averages them."""
    return ("combined", *(p.source for p in enabled_passes(view_layer) if p.source))


def register_passes(engine, scene, view_layer):
    """What RenderEngine.update_render_passes does: declare the passes this layer will get."""
    for render_pass in enabled_passes(view_layer):
        engine.register_pass(scene, view_layer, render_pass.name, len(render_pass.channel_ids),
                             render_pass.channel_ids, render_pass.kind)


def needs_components(view_layer):
    """Whether the core must return its per-pass images (anything beyond Combined is on)."""
    return any(p.source for p in enabled_passes(view_layer))


def write_passes(layer, components, width, height):
    """Writes every pass beyond Combined that the result layer has (the engine writes Combined as it goes).
    Core images have row 0 at the top; Blender's at the bottom. Returns the names written."""
    from . import compat     # imports bpy: only here, so the pass table loads without Blender (tests/python)
    written = []
    for render_pass in PASSES:
        if not render_pass.source:
            continue
        target = layer.passes.get(render_pass.name)
        if target is None:
            continue
        data = (components or {}).get(render_pass.source)
        if data is None:
            raise RuntimeError(f"the core returned no '{render_pass.source}' image for the {render_pass.name} pass")
        channels = len(render_pass.channel_ids)
        data = np.asarray(data, dtype=np.float32)
        if data.shape != (height, width, channels):
            raise RuntimeError(f"the core's {render_pass.name} pass has shape {data.shape}, "
                               f"expected {(height, width, channels)}")
        compat.write_pass_pixels(target, np.ascontiguousarray(data[::-1].reshape(-1, channels)))
        written.append(render_pass.name)
    return written
