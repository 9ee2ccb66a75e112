"""The render passes SHGI fills, with Cycles' names, channels and view-layer toggles (no bpy).

The renderers return {pass name: float32 (H, W, C)} with row 0 at the top; Blender's render
result stores rows bottom-up, flattened to (H * W, C) (``blender_rect``). The engine registers
the enabled passes exactly as Cycles does (``RenderEngine.register_pass`` from
``update_render_passes``, same names, channel ids and types) so that the view layer's pass
toggles, the compositor's Render Layers node and multilayer EXR files see the same layers under
both engines.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PassInfo:
    """A render pass: Cycles' name, channel ids, channel type and the ViewLayer toggle."""

    name: str
    channel_ids: str
    channel_type: str    # 'COLOR', 'VECTOR' or 'VALUE', as RenderEngine.register_pass wants
    view_layer_flag: str  # the ViewLayer boolean that enables it ("" = always on)

    @property
    def channels(self):
        return len(self.channel_ids)


# Cycles' order (intern/cycles/blender/addon/engine.py, list_render_passes).
PASSES = (
    PassInfo("Combined", "RGBA", "COLOR", ""),
    PassInfo("Depth", "Z", "VALUE", "use_pass_z"),
    PassInfo("Normal", "XYZ", "VECTOR", "use_pass_normal"),
    PassInfo("DiffDir", "RGB", "COLOR", "use_pass_diffuse_direct"),
    PassInfo("DiffInd", "RGB", "COLOR", "use_pass_diffuse_indirect"),
    PassInfo("DiffCol", "RGB", "COLOR", "use_pass_diffuse_color"),
    PassInfo("GlossDir", "RGB", "COLOR", "use_pass_glossy_direct"),
    PassInfo("GlossInd", "RGB", "COLOR", "use_pass_glossy_indirect"),
    PassInfo("GlossCol", "RGB", "COLOR", "use_pass_glossy_color"),
    PassInfo("TransDir", "RGB", "COLOR", "use_pass_transmission_direct"),
    PassInfo("TransInd", "RGB", "COLOR", "use_pass_transmission_indirect"),
    PassInfo("TransCol", "RGB", "COLOR", "use_pass_transmission_color"),
    PassInfo("Emit", "RGB", "COLOR", "use_pass_emit"),
    PassInfo("Env", "RGB", "COLOR", "use_pass_environment"),
)

# View-layer passes Blender offers that SHGI does not compute: {toggle: Cycles' pass name}.
# An enabled one is reported once per render and left out of the result.
UNSUPPORTED_PASSES = {
    "use_pass_mist": "Mist",
    "use_pass_position": "Position",
    "use_pass_vector": "Vector",
    "use_pass_uv": "UV",
    "use_pass_object_index": "IndexOB",
    "use_pass_material_index": "IndexMA",
    "use_pass_shadow": "Shadow",
    "use_pass_ambient_occlusion": "AO",
}


def enabled_passes(view_layer):
    """The PassInfo of every pass the view layer enables that SHGI fills, Combined first."""
    return [info for info in PASSES
            if not info.view_layer_flag or getattr(view_layer, info.view_layer_flag, False)]


def unsupported_enabled_passes(view_layer):
    """Names of the enabled view-layer passes SHGI leaves out."""
    return [name for flag, name in UNSUPPORTED_PASSES.items() if getattr(view_layer, flag, False)]


def blender_rect(pixels, channels):
    """(H * W, channels) float32, bottom row first: a pass as RenderPass.rect stores it.

    pixels: (H, W, C) or (H, W) with row 0 at the top. Missing channels are zero, extra ones
    dropped (a 4-channel pass from 3-channel pixels gets alpha 0).
    """
    pixels = np.asarray(pixels, dtype=np.float32)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    if pixels.ndim != 3:
        raise ValueError(f"pixels: shape {pixels.shape} is not (H, W) or (H, W, C)")
    height, width, have = pixels.shape
    rect = np.zeros((height, width, channels), dtype=np.float32)
    rect[:, :, :min(have, channels)] = pixels[:, :, :channels]
    return np.ascontiguousarray(rect[::-1].reshape(height * width, channels))


def top_down(rect, width, height):
    """Inverse of blender_rect: (H * W, C) bottom-up -> (H, W, C) with row 0 at the top."""
    rect = np.asarray(rect, dtype=np.float32)
    return rect.reshape(height, width, -1)[::-1]
