"""SHGI_OT_quality_preset: sets the counts of scene.shgi from a quality preset (presets.py)."""

import bpy
from bpy.props import EnumProperty

from .. import presets

PRESET_ITEMS = [(name, presets.PRESET_LABELS[name], presets.preset_description(name))
                for name in presets.QUALITY_PRESETS]


class SHGI_OT_quality_preset(bpy.types.Operator):
    """Set samples, each method's counts (photons, resolutions, rays and passes) and the
    denoiser's effort for a level of quality"""

    bl_idname = "shgi.quality_preset"
    bl_label = "SHGI Quality Preset"
    bl_options = {"REGISTER", "UNDO"}

    preset: EnumProperty(name="Preset", items=PRESET_ITEMS, default="MEDIUM")

    @classmethod
    def description(cls, _context, properties):
        return presets.preset_description(properties.preset)

    def execute(self, context):
        presets.apply_preset(context.scene.shgi, self.preset)
        return {"FINISHED"}


CLASSES = (SHGI_OT_quality_preset,)
