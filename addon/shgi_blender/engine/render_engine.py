"""The SHGI render engine class: a thin RenderEngine that delegates (bpy side).

F12 goes to final_render.render; pass registration mirrors Cycles' (passes.py). Rendered
shading goes to a viewport.ViewportSession, made on the first view_update and stopped when
Blender frees the engine; Material Preview uses EEVEE (bl_use_eevee_viewport).
"""

import bpy

from .. import native
from . import final_render, passes, solution_cache, solution_files, viewport


class ShgiRenderEngine(bpy.types.RenderEngine):
    bl_idname = "SHGI"
    bl_label = "SHGI"
    bl_use_preview = False            # material previews would re-solve per thumbnail
    bl_use_eevee_viewport = True      # Material Preview shading uses EEVEE
    bl_use_shading_nodes_custom = False  # materials are Cycles/EEVEE shader node trees
    bl_use_postprocess = True

    def render(self, depsgraph):
        final_render.render(self, depsgraph)

    # The viewport session is an attribute set on first use (no __init__: its signature
    # differs between Blender versions).
    def view_update(self, context, depsgraph):
        if getattr(self, "viewport", None) is None:
            if not native.available():
                self.update_stats("", native.error())
                return
            self.viewport = viewport.ViewportSession()
        self.viewport.view_update(self, context, depsgraph)

    def view_draw(self, context, depsgraph):
        session = getattr(self, "viewport", None)
        if session is not None:
            session.view_draw(self, context, depsgraph)

    def __del__(self):
        try:
            session = self.viewport
        except (AttributeError, ReferenceError):  # no viewport, or already invalidated
            return
        session.stop()

    def update_render_passes(self, scene=None, renderlayer=None):
        denoising = scene is not None and scene.shgi.use_denoising
        for info in passes.enabled_passes(renderlayer, denoising):
            self.register_pass(scene, renderlayer, info.blender_name(bpy.app.version),
                               info.channels, info.channel_ids, info.channel_type)


@bpy.app.handlers.persistent
def clear_solutions_on_load(_file_path):
    """Frozen solutions and viewport sessions belong to the file they were made in."""
    solution_cache.clear_all()
    viewport.stop_all()


def register():
    bpy.utils.register_class(ShgiRenderEngine)
    bpy.app.handlers.load_pre.append(clear_solutions_on_load)
    solution_files.register()


def unregister():
    solution_files.unregister()
    if clear_solutions_on_load in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(clear_solutions_on_load)
    solution_cache.clear_all()
    viewport.stop_all()
    bpy.utils.unregister_class(ShgiRenderEngine)
