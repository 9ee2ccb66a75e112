"""Properties > Render panels of the SHGI engine: method, quality preset and samples (with the
native module's import error when it fails), light paths (with Cycles' Max Bounces sub-panel,
which says what the scene's field method cannot follow), the photon lattice or the probe grid
(with its Visibility sub-panel, laid out as EEVEE's irradiance volume settings) with the frozen
solution (out of date after a scene edit: Re-solve), lightmap bakes and the volume export (scene.shgi.bake; its Farm sub-panel), and the
last render's figures.

Labels beside values stay short: the label column of a Properties editor of the default width
holds about 11 characters (tests/python/test_blender_engine.py measures them)."""


import bpy

from .. import bake_settings, native, presets, settings
from ..engine import final_render, solution_cache, solution_files
from . import field_overlay, figure_rows
from .compat import ShgiPanel
from .wrapped_text import draw_wrapped

class SHGI_RENDER_PT_method(ShgiPanel, bpy.types.Panel):
    bl_label = "SHGI"
    bl_context = "render"

    def draw(self, context):
        layout = self.layout
        error = native.error()
        if error is not None:
            draw_wrapped(layout.box(), error, icon="ERROR")
        props = context.scene.shgi
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(props, "method")
        # A menu naming the preset the counts match: a row of buttons cut their labels.
        split = layout.split(factor=0.4)
        split.alignment = "RIGHT"
        split.label(text="Quality")
        split.operator_menu_enum("shgi.quality_preset", "preset",
                                 text=presets.preset_label(props))
        column = layout.column(align=True)
        column.label(text="Samples")
        column.prop(props, "viewport_samples", text="Viewport")
        column.prop(props, "samples", text="Render")
        column = layout.column(align=True)
        column.label(text="Time Limit")
        column.prop(props, "viewport_time_limit", text="Viewport")
        column.prop(props, "time_limit", text="Render")
        layout.prop(props, "seed")


class SHGI_RENDER_PT_denoise(ShgiPanel, bpy.types.Panel):
    bl_label = "Denoise"
    bl_context = "render"
    bl_parent_id = "SHGI_RENDER_PT_method"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        props = context.scene.shgi
        error = native.denoiser_error()
        if error is not None:
            draw_wrapped(layout.box(), error, icon="INFO")
        for prefix, heading in (("viewport_", "Viewport"), ("", "Render")):
            column = layout.column(align=True)
            column.label(text=heading)
            column.prop(props, f"use_{prefix}denoising", text="Denoise")
            sub = column.column(align=True)
            sub.active = getattr(props, f"use_{prefix}denoising") and error is None
            if prefix:
                sub.prop(props, "viewport_denoising_start_sample", text="Start")
            sub.prop(props, f"{prefix}denoising_guides", text="Passes")
            sub.prop(props, f"{prefix}denoising_prefilter", text="Prefilter")
            sub.prop(props, f"{prefix}denoising_quality", text="Quality")


class SHGI_RENDER_PT_film(ShgiPanel, bpy.types.Panel):
    """Cycles' Film > Pixel Filter: its type and width."""

    bl_label = "Film"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        draw_props_column(self.layout, context.scene.shgi,
                          (("pixel_filter", "Pixel Filter"), ("filter_width", "Width")))


class SHGI_RENDER_PT_light_paths(ShgiPanel, bpy.types.Panel):
    bl_label = "Light Paths"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        draw_props_column(self.layout, context.scene.shgi,
                          (("clamp_indirect", "Clamp"), ("filter_glossy", "Filter Glossy"),
                           ("world_sampling", "World"), ("light_splits", "Light Splits")))


class SHGI_RENDER_PT_light_paths_max_bounces(ShgiPanel, bpy.types.Panel):
    """Cycles' Light Paths > Max Bounces sub-panel: Total and the limit per kind of bounce."""

    bl_label = "Max Bounces"
    bl_context = "render"
    bl_parent_id = "SHGI_RENDER_PT_light_paths"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        props = context.scene.shgi
        column = layout.column(align=True)
        for name in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces"):
            column.prop(props, name)
        solver = settings.METHODS_BY_ID[props.method].solver
        if solver:
            column.prop(props, "max_specular_bounces", text="Specular")
            draw_wrapped(layout, settings.light_path_limits(solver), icon="INFO")


def draw_props_column(layout, props, fields):
    """`fields` ((property, label), ...) of `props` in one aligned column, labels split off as
    Cycles' panels draw them."""
    layout.use_property_split = True
    layout.use_property_decorate = False
    column = layout.column(align=True)
    for name, text in fields:
        column.prop(props, name, text=text)
    return column


def draw_frozen_solution(layout, context):
    """The Solve and Clear buttons, and the figures of the scene's frozen solution."""
    props = context.scene.shgi
    key = context.scene.name_full
    row = layout.row(align=True)
    row.operator("shgi.solve", icon="LIGHT_SUN")
    if props.method == "PROBE_GRID":
        row.operator("shgi.load_solution", icon="FILE_FOLDER")
    row.operator("shgi.clear_solution", icon="X")
    solution = solution_cache.get(key)
    if solution is None:
        problem = solution_files.load_problem(key)
        if problem is not None:
            draw_wrapped(layout.box(), problem, icon="ERROR")
        return
    box = layout.box()
    solved_at = solution_cache.solved_at_text(solution)
    if solution.method != props.method:
        draw_wrapped(box, f"Frozen {settings.METHODS_BY_ID[solution.method].label} solution "
                          f"({solved_at}): not used by this method", icon="INFO")
        return
    changed = solution_cache.changed_since(key, solution)
    if changed is not None:
        draw_wrapped(box, f"Using the solution of {solved_at}; the scene changed since "
                          f"({changed})", icon="ERROR")
        box.operator("shgi.solve", text="Re-solve", icon="FILE_REFRESH")
    else:
        draw_wrapped(box, f"Frozen solution ({solved_at}): F12 renders it from any camera",
                     icon="FREEZE")
    if solution.signature is not None and solution.signature != settings.solver_signature(props):
        draw_wrapped(box, "Settings changed since the solve: Re-solve to apply them",
                     icon="ERROR")
    if solution.method not in solution_cache.FIELD_FILES:
        draw_wrapped(box, "Not saved with the file (this method's field cannot be read back)",
                     icon="INFO")
    figure_rows.draw_rows(box, figure_rows.solution_rows(solution))


class _FieldPanel(ShgiPanel):
    """A panel shown when the scene's method solves with the solver SOLVER."""

    bl_context = "render"
    SOLVER = ""

    @classmethod
    def poll(cls, context):
        return (super().poll(context)
                and settings.METHODS_BY_ID[context.scene.shgi.method].solver == cls.SOLVER)


def draw_passes_and_final_gather(layout, group, label="Passes"):
    """A field method's refinement passes for F12 and the viewport, and its Final Gather: every
    field settings group has the three properties by these names."""
    column = layout.column(align=True)
    column.label(text=label)
    column.prop(group, "passes", text="Render")
    column.prop(group, "viewport_passes", text="Viewport")
    layout.prop(group, "final_gather")


class SHGI_RENDER_PT_photon_lattice(_FieldPanel, bpy.types.Panel):
    bl_label = "Photon Lattice"
    SOLVER = "PHOTON_LATTICE"

    def draw(self, context):
        layout = self.layout
        props = context.scene.shgi
        lattice = props.photon_lattice
        draw_frozen_solution(layout, context)
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column(align=True)
        for name in ("photons", "resolution", "order", "interpolation", "blur_passes"):
            column.prop(lattice, name)
        column = layout.column(align=True)
        column.prop(lattice, "caustics")
        sub = column.column(align=True)
        sub.active = lattice.caustics != "OFF"
        sub.prop(lattice, "caustic_resolution", text="Resolution")
        layout.prop(lattice, "world_in_field")
        draw_passes_and_final_gather(layout, lattice, "Photon Passes")
        field_overlay.draw_overlay_settings(layout, props, "show_lattice_samples")


class SHGI_RENDER_PT_radiance_field(_FieldPanel, bpy.types.Panel):
    bl_label = "Radiance Field"
    SOLVER = "RADIANCE_FIELD"

    def draw(self, context):
        layout = self.layout
        props = context.scene.shgi
        field = props.radiance_field
        draw_frozen_solution(layout, context)
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column(align=True)
        for name in ("photons", "resolution", "gather_rays", "face_estimator"):
            column.prop(field, name)
        column = layout.column(align=True)
        column.prop(field, "use_mips")
        sub = column.column(align=True)
        sub.active = field.use_mips
        sub.prop(field, "mip_levels")
        column = layout.column(align=True)
        column.prop(field, "monte_carlo_gathers")
        sub = column.column(align=True)
        sub.active = field.monte_carlo_gathers
        sub.prop(field, "diffuse_gather_rays")
        sub.prop(field, "glossy_gather_rays")
        column = layout.column(align=True)
        for name in ("side_test", "visibility_test", "occlusion_test", "obscurance",
                     "world_in_field"):
            column.prop(field, name)
        draw_passes_and_final_gather(layout, field)


class SHGI_RENDER_PT_probe_grid(_FieldPanel, bpy.types.Panel):
    """The probe grid's settings; its volumes are the scene's Irradiance Volume objects."""

    bl_label = "Probe Grid"
    SOLVER = "PROBE_GRID"

    def draw(self, context):
        layout = self.layout
        props = context.scene.shgi
        grid = props.probe_grid
        draw_frozen_solution(layout, context)
        volumes = irradiance_volume_count(context.scene)
        layout.label(icon="OUTLINER_OB_LIGHTPROBE", text=(
            f"{volumes} Irradiance Volume{'s' if volumes != 1 else ''} place the probes"
            if volumes else "No Irradiance Volume: probes fill the scene"))
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column(align=True)
        sub = column.column(align=True)
        sub.active = volumes == 0
        sub.prop(grid, "spacing")
        column.prop(grid, "order")
        column.prop(grid, "rays_per_probe", text="Rays")
        column.prop(grid, "hysteresis")
        # The probes' bounce limit and clamp are Light Paths' (settings.LIGHT_PATH_VALUES).
        draw_wrapped(layout, "Bounces and Clamp follow Light Paths", icon="INFO")
        draw_passes_and_final_gather(layout, grid, "Update Passes")
        column = layout.column(align=True, heading="Relocation")
        column.prop(grid, "relocate", text="Move Out of Geometry")
        sub = column.column(align=True)
        sub.active = grid.relocate
        sub.prop(grid, "max_offset")
        column.prop(grid, "backface_threshold", text="Back Faces")
        field_overlay.draw_overlay_settings(layout, props, "show_probes")


class SHGI_RENDER_PT_probe_grid_visibility(_FieldPanel, bpy.types.Panel):
    """EEVEE's irradiance volume Visibility panel: Bias, Bleed Bias, Blur."""

    bl_label = "Visibility"
    bl_parent_id = "SHGI_RENDER_PT_probe_grid"
    SOLVER = "PROBE_GRID"

    def draw_header(self, context):
        self.layout.prop(context.scene.shgi.probe_grid, "visibility", text="")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        grid = context.scene.shgi.probe_grid
        column = layout.column(align=True)
        column.active = grid.visibility
        column.prop(grid, "normal_bias", text="Bias")
        column.prop(grid, "view_bias", text="View Bias")
        column.prop(grid, "bleed_bias", text="Bleed Bias")
        column.prop(grid, "visibility_blur", text="Blur")
        column.prop(grid, "visibility_resolution", text="Resolution")


class SHGI_RENDER_PT_propagation(_FieldPanel, bpy.types.Panel):
    bl_label = "Light Propagation"
    SOLVER = "PROPAGATION"

    def draw(self, context):
        layout = self.layout
        volume = context.scene.shgi.propagation
        draw_frozen_solution(layout, context)
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column(align=True)
        for name in ("photons", "resolution", "steps"):
            column.prop(volume, name)
        sub = column.column(align=True)
        sub.active = volume.steps == 0  # Distance counts only with Steps 0
        sub.prop(volume, "distance")
        for name in ("order", "normal_offset", "cascades"):
            column.prop(volume, name)
        column = layout.column(align=True)
        for name in ("occlusion", "occlude_first_step", "drop_outward_vpls", "travel_reinjection",
                     "unclamped_transfer", "clamp_at_surfaces", "damping"):
            column.prop(volume, name)
        draw_passes_and_final_gather(layout, volume)


class SHGI_RENDER_PT_instant_gi(_FieldPanel, bpy.types.Panel):
    bl_label = "Instant GI"
    SOLVER = "INSTANT_GI"

    def draw(self, context):
        layout = self.layout
        instant = context.scene.shgi.instant_gi
        draw_frozen_solution(layout, context)
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column(align=True)
        for name in ("sets_x", "sets_y", "photons_per_set", "clamp_distance"):
            column.prop(instant, name)
        column = layout.column(align=True)
        for name in ("filter_mode", "depth_threshold", "normal_threshold", "filter_direct"):
            column.prop(instant, name)
        column = layout.column(align=True)
        column.label(text="Passes")
        column.prop(instant, "passes", text="Render")
        column.prop(instant, "viewport_passes", text="Viewport")
        column.prop(instant, "bake_passes", text="Bake")
        column.prop(instant, "passes_per_sample", text="Per Sample")
        layout.prop(instant, "final_gather")


def irradiance_volume_count(scene):
    """Irradiance Volume objects of the scene that render."""
    from ..export.light_probe import is_irradiance_volume

    return sum(1 for obj in scene.objects if is_irradiance_volume(obj) and not obj.hide_render)


class SHGI_RENDER_PT_bake(ShgiPanel, bpy.types.Panel):
    """Lightmaps of the selected objects (scene.shgi.bake, the bake operators' settings) and
    the export of the solved field as a volume."""

    bl_label = "Bake"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        bake = context.scene.shgi.bake
        meshes = sum(1 for obj in getattr(context, "selected_objects", ()) if obj.type == "MESH")
        layout.label(text=f"{meshes} selected mesh object{'s' if meshes != 1 else ''} to bake",
                     icon="OBJECT_DATA")
        row = layout.row(align=True)
        if bake.farm == "FLAMENCO":
            row.operator("shgi.write_flamenco_job", icon="EXPORT")
        else:
            row.operator("shgi.bake_lightmaps", icon="RENDER_STILL")
        if bake.shard_count > 1 and bake.farm != "DASK":
            row.operator("shgi.merge_lightmap_shards", icon="NODE_COMPOSITING")
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column(align=True)
        for name in ("source", "content", "samples", "bake_side"):
            column.prop(bake, name)
        sub = column.column(align=True)
        sub.active = bake_settings.uses_field(bake)
        sub.prop(bake, "final_gather")
        column = layout.column(align=True)
        column.prop(bake, "uv_map")
        column.prop(bake, "create_uv")
        sub = column.column(align=True)
        sub.active = bake.create_uv
        sub.prop(bake, "uv_layout")
        column = layout.column(align=True)
        column.prop(bake, "resolution")
        sub = column.column(align=True)
        sub.active = bake.resolution == 0
        sub.prop(bake, "texel_density", text="Texels per m")
        column.prop(bake, "padding")
        column = layout.column(align=True)
        column.prop(bake, "directional")
        sub = column.column(align=True)
        sub.active = bake.directional
        sub.prop(bake, "sh_order")
        column.prop(bake, "filter")
        sub = column.column(align=True)
        sub.active = bake.filter
        sub.prop(bake, "denoiser")
        column.prop(bake, "hook_up_material")
        sub = column.column(align=True)
        sub.active = bake.hook_up_material
        sub.prop(bake, "single_user_materials")
        layout.prop(bake, "output_folder")
        layout.operator("shgi.remove_lightmap_nodes", icon="X")
        layout.separator()
        layout.prop(bake, "volume_path")
        row = layout.row()
        row.active = settings.METHODS_BY_ID[context.scene.shgi.method].uses_field
        row.operator("shgi.export_volume", icon="EXPORT")


class SHGI_RENDER_PT_bake_farm(ShgiPanel, bpy.types.Panel):
    """The Bake panel's render farm settings: where the bake runs (this computer, a Dask
    cluster, a Flamenco job), its shards and the tiles they are made of."""

    bl_label = "Farm"
    bl_context = "render"
    bl_parent_id = "SHGI_RENDER_PT_bake"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        bake = context.scene.shgi.bake
        layout.prop(bake, "farm")
        column = layout.column(align=True)
        if bake.farm == "DASK":
            column.prop(bake, "scheduler")
            sub = column.column(align=True)
            sub.active = not bake.scheduler.strip()
            sub.prop(bake, "workers")
        column.prop(bake, "shard_count")
        if bake.farm == "LOCAL":
            sub = column.column(align=True)
            sub.active = bake.shard_count > 1
            sub.prop(bake, "shard_index")
        column.prop(bake, "tile_size")
        if bake.farm == "DASK" and bake.shard_count <= 1:
            layout.label(text=f"{bake_settings.SHARDS_PER_WORKER} shards per worker",
                         icon="INFO")


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
        method = settings.METHODS_BY_ID.get(record["method"])
        region = " Render Region" if "region" in record else ""
        denoised = ", denoised" if record.get("denoised") else ""
        draw_wrapped(layout, f"{method.label if method else record['method']}: {width}x{height} "
                             f"px{region}, {record['samples']} samples{denoised}{state}")
        figure_rows.draw_rows(layout, figure_rows.render_timing_rows(record["timings"]))
        for message in record["errors"] + record["warnings"]:
            draw_wrapped(layout, message, icon="ERROR" if message in record["errors"]
                         else "INFO")


# Parents before their sub-panels.
CLASSES = (SHGI_RENDER_PT_method, SHGI_RENDER_PT_denoise, SHGI_RENDER_PT_film,
           SHGI_RENDER_PT_light_paths,
           SHGI_RENDER_PT_light_paths_max_bounces, SHGI_RENDER_PT_photon_lattice,
           SHGI_RENDER_PT_radiance_field,
           SHGI_RENDER_PT_probe_grid, SHGI_RENDER_PT_probe_grid_visibility,
           SHGI_RENDER_PT_propagation, SHGI_RENDER_PT_instant_gi,
           SHGI_RENDER_PT_bake, SHGI_RENDER_PT_bake_farm, SHGI_RENDER_PT_last_render)
