"""Blender's stock panels shown under SHGI as under Cycles, and the mixin of SHGI's own panels.

Cycles adds itself to every panel that lists the internal 'BLENDER_RENDER' engine (output,
dimensions, colour management, object, mesh, camera, ... panels), except those it replaces; SHGI
does the same with the same exceptions (but keeps the spot-shape panel, which Cycles draws in its
own light panels), plus EEVEE's material and world surface panels (the node trees SHGI exports).
Cycles' own panels are not reused: they share one COMPAT_ENGINES set, so adding SHGI to one
would show all of Cycles' settings. Only the panels SHGI was added to are restored on
unregister. SHGI's own Properties panels take ShgiPanel: shown only while SHGI renders.
"""

import bpy

from ..engine.render_engine import ShgiRenderEngine

ENGINE = ShgiRenderEngine.bl_idname
# Panels listing BLENDER_RENDER that SHGI leaves out: Cycles' exclusions (its ui.get_panels)
# but DATA_PT_spot; SHGI replaces them with its own light and pass panels or does not support them.
EXCLUDED_PANELS = {
    "DATA_PT_area", "DATA_PT_camera_dof", "DATA_PT_falloff_curve", "DATA_PT_light",
    "DATA_PT_preview", "MATERIAL_PT_context_material", "MATERIAL_PT_preview",
    "NODE_DATA_PT_light", "NODE_DATA_PT_spot", "OBJECT_PT_visibility", "VIEWLAYER_PT_filter",
    "VIEWLAYER_PT_layer_passes", "RENDER_PT_post_processing", "RENDER_PT_simplify",
}
# Panels of other engines that show what SHGI exports.
EXTRA_PANELS = (
    "EEVEE_MATERIAL_PT_context_material", "EEVEE_MATERIAL_PT_surface", "EEVEE_WORLD_PT_surface",
)

_added = []


class ShgiPanel:
    """Mixin of SHGI's Properties editor panels (each sets bl_context): shown under SHGI only."""

    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES


def stock_panels():
    """The stock panel classes SHGI should appear in."""
    panels = [panel for panel in bpy.types.Panel.__subclasses__()
              if "BLENDER_RENDER" in getattr(panel, "COMPAT_ENGINES", ())
              and panel.__name__ not in EXCLUDED_PANELS]
    panels += [getattr(bpy.types, name) for name in EXTRA_PANELS if hasattr(bpy.types, name)]
    return panels


def add_engine_to_stock_panels():
    for panel in stock_panels():
        if ENGINE not in panel.COMPAT_ENGINES:
            panel.COMPAT_ENGINES.add(ENGINE)
            _added.append(panel)


def remove_engine_from_stock_panels():
    for panel in _added:
        panel.COMPAT_ENGINES.discard(ENGINE)
    _added.clear()
