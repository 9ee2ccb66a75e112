"""Properties > Render panels of the SHGI engine: method and samples (with the native module's
import error when it fails), light paths, the photon lattice with its frozen solution, and the
last render's figures."""

import textwrap
import time

import bpy

from .. import native, presets, settings
from ..engine import final_render, solution_cache
from .compat import ShgiPanel

WRAP_COLUMNS = 56  # characters per line of long messages in a panel of default width


def draw_wrapped(layout, text, icon="NONE"):
    """Draws `text` as several labels (Blender's labels do not wrap)."""
    column = layout.column(align=True)
    for index, line in enumerate(textwrap.wrap(text, WRAP_COLUMNS)):
        column.label(text=line, icon=icon if index == 0 else "BLANK1")


class SHGI_RENDER_PT_method(ShgiPanel, bpy.types.Panel):
    bl_label = "SHGI"
    bl_context = "render"

    def draw(self, context):
        layout = self.layout
        error = native.error()
        if error is not None:
            draw_wrapped(layout.box(), error, icon="ERROR")
        props = context.scene.shgi
        layout.prop(props, "method")
        row = layout.row(align=True)
        current = presets.matching_preset(props)
        for name, label in presets.PRESET_LABELS.items():
            row.operator("shgi.quality_preset", text=label,
                         depress=(name == current)).preset = name
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column(align=True)
        column.prop(props, "viewport_samples", text="Viewport Samples")
        column.prop(props, "samples", text="Render Samples")
        column.prop(props, "seed")


class SHGI_RENDER_PT_light_paths(ShgiPanel, bpy.types.Panel):
    bl_label = "Light Paths"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        props = context.scene.shgi
        column = layout.column(align=True, heading="Max Bounces")
        for name in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces"):
            column.prop(props, name)
        column = layout.column(align=True)
        column.prop(props, "clamp_indirect")
        column.prop(props, "world_sampling")
        if settings.METHODS_BY_ID[props.method].uses_lattice:
            column.prop(props, "max_specular_bounces")


class SHGI_RENDER_PT_photon_lattice(ShgiPanel, bpy.types.Panel):
    bl_label = "Photon Lattice"
    bl_context = "render"

    @classmethod
    def poll(cls, context):
        return (super().poll(context)
                and settings.METHODS_BY_ID[context.scene.shgi.method].uses_lattice)

    def draw(self, context):
        layout = self.layout
        props = context.scene.shgi
        row = layout.row(align=True)
        row.operator("shgi.lattice_solve", icon="LIGHT_SUN")
        row.operator("shgi.lattice_clear", icon="X")
        solution = solution_cache.get(context.scene.name_full)
        if solution is not None:
            self._draw_solution(layout.box(), props, solution)
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column(align=True)
        for name in ("photons", "resolution", "order", "interpolation", "blur_passes"):
            column.prop(props, name)
        column = layout.column(align=True)
        column.prop(props, "caustics")
        sub = column.column(align=True)
        sub.active = props.caustics != "OFF"
        sub.prop(props, "caustic_resolution")
        layout.prop(props, "world_in_field")
        column = layout.column(align=True)
        column.prop(props, "viewport_photon_passes", text="Viewport Passes")
        column.prop(props, "show_lattice_samples", text="Show Lattice Samples")

    @staticmethod
    def _draw_solution(layout, props, solution):
        solved_at = time.strftime("%H:%M:%S", time.localtime(solution.solved_at))
        layout.label(text=f"Frozen solution ({solved_at}): F12 renders it from any camera",
                     icon="FREEZE")
        layout.label(text="Scene edits made since are not seen: Solve again or Clear")
        if solution.signature != settings.lattice_signature(props):
            layout.label(text="Settings changed since the solve: Solve again to apply them",
                         icon="ERROR")
        grid = layout.grid_flow(columns=2, even_columns=True, align=True)
        for key, label in solution_cache.TIMING_LABELS.items():
            if key in solution.timings:
                grid.label(text=label)
                grid.label(text=f"{1000.0 * solution.timings[key]:.1f} ms")
        grid.label(text="Photons emitted / stored")
        grid.label(text=f"{solution.photons_emitted:,} / "
                        f"{int(solution.timings.get('photons_stored', 0)):,}")
        grid.label(text="Memory")
        grid.label(text=f"{solution.memory_bytes / solution_cache.BYTES_PER_MIB:.2f} MiB")


class SHGI_RENDER_PT_last_render(ShgiPanel, bpy.types.Panel):
    bl_label = "Last Render"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, _context):
        layout = self.layout
        record = final_render.last_render()
        if not record:
            layout.label(text="No render in this session yet")
            return
        width, height = record["size"]
        state = " (cancelled)" if record["cancelled"] else ""
        layout.label(text=f"{record['method']}: {width}x{height} px, {record['samples']} "
                          f"samples{state}")
        grid = layout.grid_flow(columns=2, even_columns=True, align=True)
        for name, seconds in record["timings"].items():
            grid.label(text=name.capitalize())
            grid.label(text=f"{seconds:.2f} s")
        for message in record["errors"] + record["warnings"]:
            draw_wrapped(layout, message, icon="ERROR" if message in record["errors"]
                         else "INFO")


CLASSES = (SHGI_RENDER_PT_method, SHGI_RENDER_PT_light_paths, SHGI_RENDER_PT_photon_lattice,
           SHGI_RENDER_PT_last_render)
