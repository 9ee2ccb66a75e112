"""The light panel and the view layer's passes under SHGI, laid out as Cycles' are."""

import bpy

from ..engine import passes
from .compat import ShgiPanel

# (heading, [(view layer toggle, label)]): the toggles of passes.PASSES, grouped as in Cycles'
# Data and Light pass panels.
PASS_GROUPS = (
    ("Data", [("use_pass_combined", "Combined"), ("use_pass_z", "Z"),
              ("use_pass_normal", "Normal")]),
    ("Diffuse", [("use_pass_diffuse_direct", "Direct"), ("use_pass_diffuse_indirect", "Indirect"),
                 ("use_pass_diffuse_color", "Color")]),
    ("Glossy", [("use_pass_glossy_direct", "Direct"), ("use_pass_glossy_indirect", "Indirect"),
                ("use_pass_glossy_color", "Color")]),
    ("Transmission", [("use_pass_transmission_direct", "Direct"),
                      ("use_pass_transmission_indirect", "Indirect"),
                      ("use_pass_transmission_color", "Color")]),
    ("Other", [("use_pass_emit", "Emission"), ("use_pass_environment", "Environment")]),
)


class SHGI_LIGHT_PT_light(ShgiPanel, bpy.types.Panel):
    """Cycles' light panel without its Cycles-only options; Portal is Cycles' own property."""

    bl_label = "Light"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return context.light is not None and super().poll(context)

    def draw(self, context):
        layout = self.layout
        light = context.light
        layout.row().prop(light, "type", expand=True)
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column()
        column.prop(light, "color")
        column.prop(light, "energy")
        column.separator()
        if light.type in {"POINT", "SPOT"}:
            column.prop(light, "shadow_soft_size", text="Radius")
        elif light.type == "SUN":
            column.prop(light, "angle")
        elif light.type == "AREA":
            column.prop(light, "shape")
            sub = column.column(align=True)
            if light.shape in {"SQUARE", "DISK"}:
                sub.prop(light, "size")
            else:
                sub.prop(light, "size", text="Size X")
                sub.prop(light, "size_y", text="Y")
            cycles = getattr(light, "cycles", None)  # Cycles' add-on defines the Portal flag
            if cycles is not None:
                column.prop(cycles, "is_portal", text="Portal")
        if context.object is not None and context.object.data == light:
            column.prop(context.object, "visible_camera", text="Visible to Camera")


class SHGI_VIEWLAYER_PT_passes(ShgiPanel, bpy.types.Panel):
    """The view-layer pass toggles of the passes SHGI fills (passes.PASSES)."""

    bl_label = "Passes"
    bl_context = "view_layer"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        view_layer = context.view_layer
        for heading, toggles in PASS_GROUPS:
            column = layout.column(heading=heading, align=True)
            for flag, label in toggles:
                column.prop(view_layer, flag, text=label)
        unsupported = passes.unsupported_enabled_passes(view_layer)
        if unsupported:
            layout.label(text="Not computed by SHGI: " + ", ".join(unsupported), icon="INFO")


CLASSES = (SHGI_LIGHT_PT_light, SHGI_VIEWLAYER_PT_passes)
