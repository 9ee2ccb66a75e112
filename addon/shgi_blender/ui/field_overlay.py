"""The field overlay: small spheres shaded by the indirect light of the method's field.

PHOTON_LATTICE draws a sphere per lattice cell holding surface (``scene.shgi
show_lattice_samples``), PROBE_GRID one per active probe (``show_probes``; probes disabled
inside geometry are not drawn). Drawn in every 3D view (a SpaceView3D POST_VIEW draw handler)
when the method's toggle is on and the scene renders with SHGI. The spheres come from the field
the scene's Rendered viewport is solving (its worker computes them after each pass, so the
probes brighten as the grid refines), or else from the scene's frozen solution of the method
(computed once, by the Solve operator's worker thread). engine/field_spheres.py makes the
geometry and colours; this module only uploads them as one GPU batch (rebuilt when the overlay
changes) and draws it with back faces culled. The toggles also show in the viewport's Overlays
popover.
"""

import bpy
import gpu
from gpu_extras.batch import batch_for_shader

from .. import settings
from ..engine import solution_cache, viewport
from .wrapped_text import draw_wrapped
from ..engine.frame_display import builtin_shader
from .compat import ENGINE

SMOOTH_COLOR_SHADER_NAMES = ("SMOOTH_COLOR", "3D_SMOOTH_COLOR")

_state = {"handle": None, "batch": None, "overlay": None, "draws": 0, "spheres": 0}


def stats():
    """{"draws": overlay draws so far, "spheres": spheres in the last draw}."""
    return {"draws": _state["draws"], "spheres": _state["spheres"]}


def overlay_for(scene):
    """The FieldSpheres to draw for `scene`, or None."""
    for session in viewport.sessions():
        if session.scene_key == scene.name_full:
            overlay = session.worker.latest_overlay()
            if overlay is not None:
                return overlay
    solution = solution_cache.get(scene.name_full, scene.shgi.method)
    return solution.overlay if solution is not None else None


def draw_field_overlay():
    """The draw handler (POST_VIEW, world space)."""
    scene = bpy.context.scene
    if scene is None or scene.render.engine != ENGINE or not settings.overlay_wanted(scene.shgi):
        return
    overlay = overlay_for(scene)
    if overlay is None:
        return
    overlay = overlay.resized(scene.shgi.overlay_size)
    shader = builtin_shader(SMOOTH_COLOR_SHADER_NAMES)
    if _state["overlay"] is not overlay and not _same_spheres(_state["overlay"], overlay):
        _state["batch"] = batch_for_shader(shader, "TRIS", {"pos": overlay.positions,
                                                            "color": overlay.colors},
                                           indices=overlay.indices)
        _state["overlay"] = overlay
    # Back faces culled: handlers may draw without a depth buffer (Rendered shading), and the
    # spheres' triangles face outwards (counter-clockwise).
    gpu.state.face_culling_set("BACK")
    gpu.state.depth_test_set("LESS_EQUAL")
    gpu.state.depth_mask_set(True)
    try:
        _state["batch"].draw(shader)
    finally:
        gpu.state.depth_mask_set(False)
        gpu.state.depth_test_set("NONE")
        gpu.state.face_culling_set("NONE")
    _state["draws"] += 1
    _state["spheres"] = len(overlay.centres)


def _same_spheres(drawn, overlay):
    """Whether the batch of `drawn` shows `overlay` (a resized copy of the same spheres)."""
    return (drawn is not None and drawn.colors is overlay.colors
            and drawn.radius_spacings == overlay.radius_spacings)


# The legend of the spheres, drawn under their toggle.
LEGEND = ("Sphere colours: the indirect light arriving from each side, exposed so that their "
          "mean is mid grey")


def draw_overlay_settings(layout, props, toggle):
    """The overlay's toggle `toggle` of scene.shgi, its sphere size and legend when shown."""
    layout.prop(props, toggle)
    if getattr(props, toggle):
        layout.prop(props, "overlay_size", text="Size")
        draw_wrapped(layout, LEGEND, icon="INFO")


def draw_overlay_popover(self, context):
    """Appended to the viewport's Overlays popover (VIEW3D_PT_overlay)."""
    if context.engine != ENGINE:
        return
    layout = self.layout
    layout.label(text="SHGI")
    solver = settings.METHODS_BY_ID[context.scene.shgi.method].solver
    toggle = {"PHOTON_LATTICE": "show_lattice_samples", "PROBE_GRID": "show_probes"}.get(solver)
    if toggle is not None:
        draw_overlay_settings(layout, context.scene.shgi, toggle)


def register():
    if _state["handle"] is None:
        _state["handle"] = bpy.types.SpaceView3D.draw_handler_add(
            draw_field_overlay, (), "WINDOW", "POST_VIEW")
    bpy.types.VIEW3D_PT_overlay.append(draw_overlay_popover)


def unregister():
    bpy.types.VIEW3D_PT_overlay.remove(draw_overlay_popover)
    if _state["handle"] is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_state["handle"], "WINDOW")
    _state.update(handle=None, batch=None, overlay=None)
