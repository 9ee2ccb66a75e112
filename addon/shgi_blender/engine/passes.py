"""The render passes SHGI fills, with Cycles' names, channels and view-layer toggles (no bpy).

The renderers return {pass name: float32 (H, W, C)} with row 0 at the top, named as Cycles
named its passes up to Blender 4.x ("DiffDir"); Blender's render result stores rows bottom-up,
flattened to (H * W, C) (``blender_rect``). The engine registers the enabled passes exactly as
Cycles does (``RenderEngine.register_pass`` from ``update_render_passes``, same names, channel
ids and types) so that the view layer's pass toggles, the compositor's Render Layers node and
multilayer EXR files see the same layers under both engines. Blender 5.0 renamed the passes
after their UI labels ("Diffuse Direct"): ``PassInfo.blender_name`` gives a version's name.
"""

from dataclasses import dataclass

import numpy as np


# Blender 5.0 names render passes by their UI labels (Cycles' engine.py, list_render_passes).
LABEL_PASS_NAMES_VERSION = (5, 0, 0)


@dataclass(frozen=True)
class PassInfo:
    """A render pass: its name in the renderers' results (Cycles' before Blender 5.0), channel
    ids, channel type, the ViewLayer toggle and, when it differs, Blender 5's name."""

    name: str
    channel_ids: str
    channel_type: str    # 'COLOR', 'VECTOR' or 'VALUE', as RenderEngine.register_pass wants
    view_layer_flag: str  # the ViewLayer boolean that enables it ("" = always on)
    label: str = ""      # the name from Blender 5.0 on ("" = `name`)

    @property
    def channels(self):
        return len(self.channel_ids)

    def blender_name(self, blender_version):
        """The pass's name in the render results of a Blender version, e.g. (5, 0, 1)."""
        if self.label and tuple(blender_version) >= LABEL_PASS_NAMES_VERSION:
            return self.label
        return self.name


# Cycles' order (intern/cycles/blender/addon/engine.py, list_render_passes).
PASSES = (
    PassInfo("Combined", "RGBA", "COLOR", ""),
    PassInfo("Depth", "Z", "VALUE", "use_pass_z"),
    PassInfo("Normal", "XYZ", "VECTOR", "use_pass_normal"),
    PassInfo("DiffDir", "RGB", "COLOR", "use_pass_diffuse_direct", "Diffuse Direct"),
    PassInfo("DiffInd", "RGB", "COLOR", "use_pass_diffuse_indirect", "Diffuse Indirect"),
    PassInfo("DiffCol", "RGB", "COLOR", "use_pass_diffuse_color", "Diffuse Color"),
    PassInfo("GlossDir", "RGB", "COLOR", "use_pass_glossy_direct", "Glossy Direct"),
    PassInfo("GlossInd", "RGB", "COLOR", "use_pass_glossy_indirect", "Glossy Indirect"),
    PassInfo("GlossCol", "RGB", "COLOR", "use_pass_glossy_color", "Glossy Color"),
    PassInfo("TransDir", "RGB", "COLOR", "use_pass_transmission_direct", "Transmission Direct"),
    PassInfo("TransInd", "RGB", "COLOR", "use_pass_transmission_indirect",
             "Transmission Indirect"),
    PassInfo("TransCol", "RGB", "COLOR", "use_pass_transmission_color", "Transmission Color"),
    PassInfo("Emit", "RGB", "COLOR", "use_pass_emit", "Emission"),
    PassInfo("Env", "RGB", "COLOR", "use_pass_environment", "Environment"),
)

# The passes a denoised render adds (shgi.frame_denoise), as Cycles writes them when it denoises
# (Noisy Image) and stores its denoising data (the guides).
DENOISING_PASSES = (
    PassInfo("Noisy Image", "RGBA", "COLOR", ""),
    PassInfo("Denoising Normal", "XYZ", "VECTOR", ""),
    PassInfo("Denoising Albedo", "RGB", "COLOR", ""),
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


def enabled_passes(view_layer, denoising=False):
    """The PassInfo of every pass the view layer enables that SHGI fills, Combined first, and
    with `denoising` (F12 denoises) the DENOISING_PASSES."""
    enabled = [info for info in PASSES
               if not info.view_layer_flag or getattr(view_layer, info.view_layer_flag, False)]
    return enabled + list(DENOISING_PASSES) if denoising else enabled


def names_from_blender_names(blender_version):
    """{pass name in a Blender version's render results: the renderers' name} for PASSES and
    DENOISING_PASSES."""
    return {info.blender_name(blender_version): info.name
            for info in PASSES + DENOISING_PASSES}


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
