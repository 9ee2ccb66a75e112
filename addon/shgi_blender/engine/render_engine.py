"""The SHGI render engine class: a thin RenderEngine that delegates (bpy side).

F12 goes to final_render.render; pass registration mirrors Cycles' (passes.py). The live
viewport (view_update / view_draw) is not implemented yet: Rendered shading shows nothing and
Material Preview uses EEVEE (bl_use_eevee_viewport).
"""

import bpy

from . import final_render, passes, solution_cache


class ShgiRenderEngine(bpy.types.RenderEngine):
    bl_idname = "SHGI"
    bl_label = "SHGI"
    bl_use_preview = False            # material previews would re-solve per thumbnail
    bl_use_eevee_viewport = True      # Material Preview shading uses EEVEE
    bl_use_shading_nodes_custom = False  # materials are Cycles/EEVEE shader node trees
    bl_use_postprocess = True

    def render(self, depsgraph):
        final_render.render(self, depsgraph)

    def update_render_passes(self, scene=None, renderlayer=None):
        for info in passes.enabled_passes(renderlayer):
            self.register_pass(scene, renderlayer, info.name, info.channels, info.channel_ids,
                               info.channel_type)


@bpy.app.handlers.persistent
def clear_solutions_on_load(_file_path):
    """Frozen solutions belong to the scenes of the file they were solved in."""
    solution_cache.clear_all()


def register():
    bpy.utils.register_class(ShgiRenderEngine)
    bpy.app.handlers.load_pre.append(clear_solutions_on_load)


def unregister():
    if clear_solutions_on_load in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(clear_solutions_on_load)
    solution_cache.clear_all()
    bpy.utils.unregister_class(ShgiRenderEngine)
