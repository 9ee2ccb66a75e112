"""SHGI_OT_quality_preset: sets the counts of scene.shgi from a quality preset (presets.py)."""

import bpy
from bpy.props import EnumProperty

from .. import presets

PRESET_ITEMS = [(name, presets.PRESET_LABELS[name],
                 ", ".join(f"{presets.field_label(field)} {presets.value_text(value)}"
                           for field, value in values.items()))
                for name, values in presets.QUALITY_PRESETS.items()]


class SHGI_OT_quality_preset(bpy.types.Operator):
    """Set samples, photons, lattice resolutions, probe rays and passes and the denoiser's effort
    for a level of quality"""

    bl_idname = "shgi.quality_preset"
    bl_label = "SHGI Quality Preset"
    bl_options = {"REGISTER", "UNDO"}

    preset: EnumProperty(name="Preset", items=PRESET_ITEMS, default="MEDIUM")

    @classmethod
    def description(cls, _context, properties):
        values = presets.QUALITY_PRESETS[properties.preset]
        return f"{presets.PRESET_LABELS[properties.preset]}: " + ", ".join(
            f"{presets.field_label(field)} {presets.value_text(value)}"
            for field, value in values.items())

    def execute(self, context):
        presets.apply_preset(context.scene.shgi, self.preset)
        return {"FINISHED"}


CLASSES = (SHGI_OT_quality_preset,)
