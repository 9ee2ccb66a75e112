"""``scene.shgi``: the render settings of the SHGI engine (PropertyGroups, one per concern).

``scene.shgi`` holds what every method shares (samples, seed, Light Paths) and the viewport's
overlays; each field method has its own group named after it, mirroring its native settings
struct by field name, with its pass counts (``passes`` of a final solve, ``viewport_passes`` of
the Rendered viewport): ``scene.shgi.photon_lattice`` (shgi.PhotonLatticeSettings) and
``scene.shgi.probe_grid`` (shgi.ProbeGridSettings), ``scene.shgi.radiance_field``
(shgi.RadianceFieldSettings). settings.py holds the tables, the defaults
(the native ones) and the mapping to the native structs; bake_settings.py those of the lightmap
bake in ``scene.shgi.bake``, whose properties the bake operators carry too: bake_properties().
Files saved before the groups existed are brought up to date when they open (versioning.py).
Enum tables are module-level so Blender keeps them alive.
"""

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, IntProperty, PointerProperty,
                       StringProperty)

from . import bake_settings, native, settings, settings_upgrade

D = settings.PROPERTY_DEFAULTS
L = settings.PHOTON_LATTICE_DEFAULTS
P = settings.PROBE_GRID_DEFAULTS
R = settings.RADIANCE_FIELD_DEFAULTS
LP = settings.PROPAGATION_DEFAULTS
IG = settings.INSTANT_GI_DEFAULTS
V = settings.VIEWPORT_PROPERTY_DEFAULTS
VP = settings.VIEWPORT_PASSES_DEFAULTS
DN = settings.DENOISING_DEFAULTS
T = settings.TIME_LIMIT_DEFAULTS

METHOD_ITEMS = [(m.identifier, m.label, m.description, m.number) for m in settings.METHODS]
WORLD_SAMPLING_ITEMS = list(settings.ENUM_ITEMS["world_sampling"])
PIXEL_FILTER_ITEMS = list(settings.ENUM_ITEMS["pixel_filter"])
CAUSTICS_ITEMS = list(settings.ENUM_ITEMS["caustics"])
INTERPOLATION_ITEMS = list(settings.ENUM_ITEMS["interpolation"])
FACE_ESTIMATOR_ITEMS = list(settings.ENUM_ITEMS["face_estimator"])
INSTANT_FILTER_ITEMS = list(settings.ENUM_ITEMS["filter_mode"])
B = bake_settings.BAKE_PROPERTY_DEFAULTS
BAKE_SOURCE_ITEMS = list(bake_settings.SOURCE_ITEMS)
BAKE_CONTENT_ITEMS = list(bake_settings.CONTENT_ITEMS)
DENOISING_ITEMS = {name: list(items) for name, items in settings.DENOISING_ITEMS.items()}


def denoising_properties(prefix, where):
    """The denoiser's choices of F12 (prefix "") or of the viewport (prefix "viewport_")."""
    return {
        f"use_{prefix}denoising": BoolProperty(
            name="Denoise", default=DN[f"use_{prefix}denoising"],
            description=f"Denoise {where} with OpenImageDenoise (needs the pyoidn module)"),
        f"{prefix}denoising_guides": EnumProperty(
            name="Passes", items=DENOISING_ITEMS["guides"],
            default=DN[f"{prefix}denoising_guides"],
            description="Render passes that guide the denoiser"),
        f"{prefix}denoising_prefilter": EnumProperty(
            name="Prefilter", items=DENOISING_ITEMS["prefilter"],
            default=DN[f"{prefix}denoising_prefilter"],
            description="What is done about the noise of the guiding passes"),
        f"{prefix}denoising_quality": EnumProperty(
            name="Quality", items=DENOISING_ITEMS["quality"],
            default=DN[f"{prefix}denoising_quality"],
            description="Quality of the denoiser against its time"),
    }


class ShgiPhotonLatticeSettings(bpy.types.PropertyGroup):
    """PhotonLatticeSettings of the PHOTON_LATTICE method (``scene.shgi.photon_lattice``); its
    photon bounce limit is Light Paths > Diffuse."""

    photons: IntProperty(
        name="Photons", default=L["photons"], min=1, soft_max=50_000_000,
        description="Photons shot from the lights per pass: more give smoother indirect light "
                    "and take longer")
    resolution: IntProperty(
        name="Resolution", default=L["resolution"], min=1, max=settings.MAX_LATTICE_RESOLUTION,
        soft_max=256,
        description="Cells along the longest side of the scene's lattice: more follow the "
                    "light's changes more closely and need more photons")
    order: IntProperty(
        name="SH Order", default=L["order"], min=1, max=2,
        description="How much of the light's direction each lattice cell keeps: 1 only soft, "
                    "broad light; 2 sharper shading near walls and lights, with more memory")
    caustics: EnumProperty(
        name="Caustics", items=CAUSTICS_ITEMS, default=L["caustics"],
        description="How light focused by glass and mirrors onto surfaces is kept")
    caustic_resolution: IntProperty(
        name="Caustic Resolution", default=L["caustic_resolution"], min=1,
        max=settings.MAX_LATTICE_RESOLUTION, soft_max=512,
        description="Cells along the longest side of the caustic lattice: more give sharper "
                    "caustics")
    interpolation: EnumProperty(
        name="Interpolation", items=INTERPOLATION_ITEMS, default=L["interpolation"],
        description="How the lattice is blended between cells")
    blur_passes: IntProperty(
        name="Blur Passes", default=L["blur_passes"], min=0, max=16,
        description="Times the lattice is blurred: smoother light, darker corners")
    world_in_field: BoolProperty(
        name="World in Lattice", default=L["world_in_field"],
        description="The lattice also carries the sky's direct light: less noise, softer "
                    "sky shadows")
    passes: IntProperty(
        name="Render Passes", default=settings.final_passes("PHOTON_LATTICE", native.module()),
        min=1, soft_max=64,
        description="Photon passes of an F12 render, a Solve or a bake, each shooting Photons: "
                    "more give smoother light")
    viewport_passes: IntProperty(
        name="Viewport Passes", default=VP["PHOTON_LATTICE"], min=1, soft_max=64,
        description="Photon passes the Rendered viewport solves, each shooting Photons (as many "
                    "as Render Passes give the lattice of a final render; more give a smoother "
                    "viewport)")
    final_gather: BoolProperty(
        name="Final Gather", default=settings.FINAL_GATHER_DEFAULTS["PHOTON_LATTICE"],
        description="Read the lattice one bounce away from what the camera sees (a ray per "
                    "sample): smoother and truer light with fewer blocks, slower per sample")


class ShgiRadianceFieldSettings(bpy.types.PropertyGroup):
    """RadianceFieldSettings of the RADIANCE_FIELD method (``scene.shgi.radiance_field``); its
    photon bounce limit is Light Paths > Diffuse."""

    photons: IntProperty(
        name="Photons", default=R["photons"], min=1, soft_max=50_000_000,
        description="Photons shot from the lights per pass: more give smoother indirect light "
                    "and take longer")
    resolution: IntProperty(
        name="Resolution", default=R["resolution"], min=1, max=settings.MAX_RADIANCE_RESOLUTION,
        soft_max=96,
        description="Cells along the longest side of the scene's grid: more follow the light's "
                    "changes more closely and cost more gather rays")
    gather_rays: IntProperty(
        name="Gather Rays", default=R["gather_rays"], min=1, max=settings.MAX_GATHER_RAYS,
        soft_max=4096,
        description="Rays each grid point near a surface traces per pass to gather the light "
                    "around it: more give smoother light")
    face_estimator: EnumProperty(
        name="Face Estimator", items=FACE_ESTIMATOR_ITEMS, default=R["face_estimator"],
        description="How photons become the light leaving each cell's surfaces")
    use_mips: BoolProperty(
        name="Mip Filtering", default=R["use_mips"],
        description="Distant surfaces are read from coarser, averaged cells: less noise")
    mip_levels: IntProperty(
        name="Levels", default=R["mip_levels"], min=1, max=settings.MAX_MIP_LEVELS,
        description="Coarser levels of the surface light grid, the finest included")
    side_test: BoolProperty(
        name="Side Test", default=R["side_test"],
        description="Ignore grid points behind the shaded surface (less light through thin "
                    "walls)")
    visibility_test: BoolProperty(
        name="Visibility Test", default=R["visibility_test"],
        description="Ignore grid points that see a surface between them and the shaded point")
    occlusion_test: BoolProperty(
        name="Occlusion Test", default=R["occlusion_test"],
        description="Ignore grid points a wall separates from the shaded point (stops light "
                    "through walls; one shadow ray per shaded point)")
    monte_carlo_gathers: BoolProperty(
        name="Monte Carlo Gathers", default=R["monte_carlo_gathers"],
        description="Shade with the paper's random gathers of the grid's light instead of the "
                    "exact integrals (noisier; for comparison with the paper)")
    diffuse_gather_rays: IntProperty(
        name="Diffuse Rays", default=R["diffuse_gather_rays"], min=1,
        max=settings.MAX_SHADING_GATHER_RAYS,
        description="Directions of the diffuse gather per shaded point")
    glossy_gather_rays: IntProperty(
        name="Glossy Rays", default=R["glossy_gather_rays"], min=1,
        max=settings.MAX_SHADING_GATHER_RAYS,
        description="Directions of the glossy gather per shaded point")
    obscurance: BoolProperty(
        name="Obscurance", default=R["obscurance"],
        description="Darken indirect light in creases (an ambient-occlusion look, not "
                    "physically based)")
    world_in_field: BoolProperty(
        name="World in Field", default=R["world_in_field"],
        description="The field also carries the sky's direct light: less noise, softer sky "
                    "shadows")
    passes: IntProperty(
        name="Render Passes", default=settings.final_passes("RADIANCE_FIELD", native.module()),
        min=1, soft_max=64,
        description="Passes of an F12 render, a Solve or a bake, each shooting Photons and "
                    "gathering again: more give smoother light")
    viewport_passes: IntProperty(
        name="Viewport Passes", default=VP["RADIANCE_FIELD"], min=1, soft_max=64,
        description="Passes the Rendered viewport solves, each shooting Photons and gathering "
                    "again")
    final_gather: BoolProperty(
        name="Final Gather", default=settings.FINAL_GATHER_DEFAULTS["RADIANCE_FIELD"],
        description="Read the field one bounce away from what the camera sees (a ray per "
                    "sample): truer light in corners, slower per sample")


class ShgiProbeGridSettings(bpy.types.PropertyGroup):
    """ProbeGridSettings of the PROBE_GRID method (``scene.shgi.probe_grid``); its paths' bounce
    limit and clamp come from Light Paths (settings.LIGHT_PATH_VALUES)."""

    order: IntProperty(
        name="SH Order", default=P["order"], min=1, max=4,
        description="How much of the light's direction each probe keeps: 1 only soft, broad "
                    "light; 2 and up sharper shading from nearby lights, with more memory and "
                    "time")
    spacing: FloatProperty(
        name="Spacing", default=P["spacing"], min=0.0, max=settings.MAX_PROBE_SPACING,
        soft_max=10.0, unit="LENGTH",
        description="Probe spacing of the volume fitted to the scene when it has no Irradiance "
                    "Volume; 0 puts 8 probes along its longest side")
    rays_per_probe: IntProperty(
        name="Rays per Probe", default=P["rays_per_probe"], min=1,
        max=settings.MAX_RAYS_PER_PROBE, soft_max=4096,
        description="Paths traced per probe and update pass")
    hysteresis: FloatProperty(
        name="History", default=P["hysteresis"], min=0.0, max=0.999,
        description="How much of the earlier passes each update keeps: higher gives a calmer, "
                    "less noisy result that follows scene edits more slowly")
    visibility: BoolProperty(
        name="Visibility", default=P["visibility"],
        description="Keep light from leaking through walls: each probe lights only the "
                    "surfaces it can see")
    visibility_resolution: IntProperty(
        name="Visibility Resolution", default=P["visibility_resolution"], min=2, max=64,
        description="How finely each probe records what it can see, against leaks: higher "
                    "follows thin walls better and takes more memory")
    visibility_blur: FloatProperty(
        name="Blur", default=P["visibility_blur"], min=settings.MIN_VISIBILITY_BLUR, max=1.5,
        subtype="ANGLE",
        description="Angular radius of the distance filter (EEVEE's Visibility Blur)")
    normal_bias: FloatProperty(
        name="Bias", default=P["normal_bias"], min=0.0, max=1.0,
        description="Probe spacings a shading point moves along its normal before it reads "
                    "the probes (EEVEE's Visibility Bias)")
    view_bias: FloatProperty(
        name="View Bias", default=P["view_bias"], min=0.0, max=1.0,
        description="Probe spacings a shading point moves towards the camera before it reads "
                    "the probes; raise it when blotches or leaks show near walls")
    bleed_bias: FloatProperty(
        name="Bleed Bias", default=P["bleed_bias"], min=0.0, max=settings.MAX_BLEED_BIAS,
        description="Visibility weights below it become 0, against light bleeding (EEVEE's "
                    "Bleed Bias)")
    relocate: BoolProperty(
        name="Relocate", default=P["relocate"],
        description="Move probes inside geometry out of it before disabling them")
    max_offset: FloatProperty(
        name="Max Offset", default=P["max_offset"], min=0.0, max=0.5,
        description="Largest relocation, in probe spacings per axis")
    backface_threshold: FloatProperty(
        name="Back-face Threshold", default=P["backface_threshold"],
        min=settings.MIN_BACKFACE_THRESHOLD, max=1.0,
        description="Share of back-face hits that marks a probe as inside geometry")
    placement_rays: IntProperty(
        name="Placement Rays", default=P["placement_rays"], min=settings.MIN_PLACEMENT_RAYS,
        max=settings.MAX_RAYS_PER_PROBE, soft_max=4096,
        description="Rays per probe that find probes inside geometry")
    passes: IntProperty(
        name="Render Passes", default=settings.final_passes("PROBE_GRID", native.module()),
        min=1, soft_max=256,
        description="Probe update passes of an F12 render, a Solve or a bake: more give "
                    "calmer light and take longer")
    viewport_passes: IntProperty(
        name="Viewport Passes", default=VP["PROBE_GRID"], min=1, soft_max=1024,
        description="Probe update passes the Rendered viewport runs in the background, a new "
                    "frame after each, before it stops refining")
    final_gather: BoolProperty(
        name="Final Gather", default=settings.FINAL_GATHER_DEFAULTS["PROBE_GRID"],
        description="Read the probes one bounce away from what the camera sees (a ray per "
                    "sample): smoother and truer light with fewer blocks, slower per sample")


def bake_properties():
    """{name: property definition} of the lightmap bake, made anew on each call: the
    ShgiBakeSettings group and each bake operator hold their own (bake_settings.py)."""
    return {
        "uv_map": StringProperty(
            name="UV Map", default=B["uv_map"],
            description="The UV map the lightmap is laid out in (one per object, inside the "
                        "unit square, without overlaps)"),
        "create_uv": BoolProperty(
            name="Create UV Map", default=B["create_uv"],
            description="Give objects without the UV map one, laid out by the Layout"),
        "uv_layout": EnumProperty(
            name="Layout", items=list(bake_settings.UV_LAYOUT_ITEMS), default=B["uv_layout"],
            description="How Create UV Map lays out the new UV map"),
        "resolution": IntProperty(
            name="Resolution", default=B["resolution"], min=0,
            **bake_settings.resolution_range(native.module()),
            description="Texels per side of each object's lightmap; 0 sizes each lightmap "
                        "from the texel density"),
        "texel_density": FloatProperty(
            name="Texel Density", default=B["texel_density"], min=0.0, soft_max=1024.0,
            description="Texels per metre of surface, used when the resolution is 0"),
        "samples": IntProperty(
            name="Samples", default=B["samples"], min=1, max=bake_settings.MAX_SAMPLES,
            soft_max=4096,
            description="Samples per texel"),
        "content": EnumProperty(
            name="Content", items=BAKE_CONTENT_ITEMS, default=B["content"],
            description="What the texels hold, in the units of Cycles' Diffuse bake"),
        "source": EnumProperty(
            name="Indirect Light", items=BAKE_SOURCE_ITEMS, default=B["source"],
            description="Where the indirect light comes from"),
        "final_gather": BoolProperty(
            name="Final Gather", default=B["final_gather"],
            description="With a solved Indirect Light (not Path Trace): each sample traces one "
                        "ray and reads the solution where it lands, with that point's direct "
                        "light, instead of reading it at the texel. Slower (like path tracing "
                        "one bounce); blocks and light leaking through thin walls are one "
                        "bounce further away"),
        "directional": BoolProperty(
            name="Directional", default=B["directional"],
            description="Also store the direction light arrives from at each texel (EXR "
                        "layers SH.c0..c3, or SH.c0..c8 at SH Order 2), so that normal-mapped "
                        "surfaces can be shaded"),
        "sh_order": IntProperty(
            name="SH Order", default=B["sh_order"], min=1, max=2,
            description="With Directional: 1 stores 4 direction coefficients per channel "
                        "(SH.c0..c3); 2 stores 9 (SH.c0..c8), which keeps "
                        "sharper changes of direction (a lamp's falloff over a normal map) at "
                        "2.25 times the memory"),
        "filter": BoolProperty(
            name="Denoise", default=B["filter"],
            description="Denoise the baked texels (never across UV charts) with the Denoiser"),
        "denoiser": EnumProperty(
            name="Denoiser", items=list(bake_settings.DENOISER_ITEMS), default=B["denoiser"],
            description="What Denoise uses"),
        "padding": IntProperty(
            name="Padding", default=B["padding"], min=0, max=64,
            description="Texels the lightmap is extended beyond the UV charts, against seams "
                        "when it is filtered"),
        "tile_size": IntProperty(
            name="Tile Size", default=B["tile_size"], min=4, max=1024,
            description="Texels per side of the tiles a lightmap is baked in: the unit of work "
                        "of threads and of shards"),
        "output_folder": StringProperty(
            name="Output Folder", default=B["output_folder"], subtype="DIR_PATH",
            description="Where <object>.exr and <object>.png are written (// is the .blend "
                        "file's folder)"),
        "shard_index": IntProperty(
            name="Shard", default=B["shard_index"], min=0,
            description="Which shard this bake writes, 0 .. Shards - 1"),
        "shard_count": IntProperty(
            name="Shards", default=B["shard_count"], min=1, soft_max=1024,
            description="Split the bake into this many shards for a render farm. This "
                        "Computer: each bake writes one shard's raw files, Merge Shards writes "
                        "the lightmaps (1 bakes whole lightmaps); Dask: the tasks of the bake "
                        "(1: four per worker); Flamenco: the job's shard tasks"),
        "farm": EnumProperty(
            name="Farm", items=list(bake_settings.FARM_ITEMS), default=B["farm"],
            description="Where the bake runs"),
        "scheduler": StringProperty(
            name="Scheduler", default=B["scheduler"],
            description="Address of the Dask scheduler (tcp://HOST:PORT, what `dask scheduler` "
                        "prints); empty: start Workers Dask worker processes on this computer "
                        "for the bake"),
        "workers": IntProperty(
            name="Workers", default=B["workers"], min=1, max=bake_settings.MAX_FARM_WORKERS,
            soft_max=64,
            description="Dask worker processes the bake starts on this computer when Scheduler "
                        "is empty (one native thread each)"),
        "hook_up_material": BoolProperty(
            name="Show in Materials", default=B["hook_up_material"],
            description="Add the lightmap to each object's materials (nodes named SHGI "
                        "Lightmap) so that EEVEE and Workbench show it"),
        "bake_side": EnumProperty(
            name="Bake Side", items=list(bake_settings.BAKE_SIDE_ITEMS),
            default=B["bake_side"],
            description="Which side of a surface the lightmap holds"),
        "single_user_materials": BoolProperty(
            name="Make Materials Single-User", default=B["single_user_materials"],
            description="With Show in Materials: give an object whose material other objects "
                        "use too a copy of it to show its own lightmap in (off: such materials "
                        "are left alone)"),
    }


class ShgiPropagationSettings(bpy.types.PropertyGroup):
    """PropagationSettings of the PROPAGATION method (``scene.shgi.propagation``); its light
    paths' bounce limit is Light Paths > Diffuse."""

    photons: IntProperty(
        name="Light Paths", default=LP["photons"], min=1, soft_max=10_000_000,
        description="Light paths traced from the lights per pass; where they land become the "
                    "little lights the grid spreads: more give smoother light")
    resolution: IntProperty(
        name="Resolution", default=LP["resolution"], min=2,
        max=settings.MAX_PROPAGATION_RESOLUTION, soft_max=128,
        description="Cells along the longest side of the scene: more keep light and shadow "
                    "sharper, and each step costs more")
    steps: IntProperty(
        name="Steps", default=LP["steps"], min=0, max=settings.MAX_PROPAGATION_STEPS,
        soft_max=64,
        description="How many times light spreads to the next cells from where it lands: more "
                    "reach farther and brighten closed rooms (0: as many as Distance needs)")
    distance: FloatProperty(
        name="Distance", default=LP["distance"], min=0.0,
        max=settings.MAX_PROPAGATION_DISTANCE, soft_max=128.0,
        description="With Steps 0, how many cells light spreads from where it lands: each "
                    "Order takes the steps that carry it this far (Order 2 reaches farther "
                    "per step)")
    order: IntProperty(
        name="Order", default=LP["order"], min=1, max=2,
        description="1: light spreads to the 6 face neighbours with broad directions (faster); "
                    "2: to all 26 neighbours with sharper directions")
    occlusion: BoolProperty(
        name="Occlusion", default=LP["occlusion"],
        description="Walls and objects block the light spreading through the grid")
    normal_offset: FloatProperty(
        name="Normal Offset", default=LP["normal_offset"], min=0.0,
        max=settings.MAX_PROPAGATION_NORMAL_OFFSET,
        description="Cells in front of a surface where its light is read: less shows finer "
                    "detail, more keeps light on the far side of thin walls out")
    damping: BoolProperty(
        name="Damping", default=LP["damping"],
        description="Dim a surface where the light arriving at it is stronger just behind it "
                    "than in front of it (its own light, or light from behind a wall)")
    occlude_first_step: BoolProperty(
        name="Occlude First Step", default=LP["occlude_first_step"],
        description="Walls block light from its first step on: keeps light next to a thin "
                    "wall from crossing it, and darkens closed rooms a little")
    drop_outward_vpls: BoolProperty(
        name="Drop Outward Lights", default=LP["drop_outward_vpls"],
        description="Leave out the light of sunlit roofs and outer walls facing away from the "
                    "scene: it lights nothing, and otherwise seeps into the rooms behind them")
    unclamped_transfer: BoolProperty(
        name="Unclamped Transfer", default=LP["unclamped_transfer"],
        description="Spread light between cells without cutting off the negative back of its "
                    "directions: light crosses open rooms without spreading out (with Clamp At "
                    "Walls, the closest to path-traced light for both orders)")
    clamp_at_surfaces: BoolProperty(
        name="Clamp At Walls", default=LP["clamp_at_surfaces"],
        description="With Unclamped Transfer, cut off the negative back of the light's "
                    "directions where walls stop part of it: walls then neither add light nor "
                    "send back light that reaches them")
    cascades: IntProperty(
        name="Cascades", default=LP["cascades"], min=1, max=settings.MAX_PROPAGATION_CASCADES,
        description="Nested grids around the camera for large scenes, each finer one with "
                    "cells half the size and Resolution cells across: detail near the camera, "
                    "light everywhere (1: one grid over the scene; more needs Resolution of "
                    f"at least {settings.MIN_CASCADE_RESOLUTION})")
    travel_reinjection: BoolProperty(
        name="Travel Re-injection", default=LP["travel_reinjection"],
        description="Light crossing a cell face keeps going the way it travelled instead of "
                    "spreading like a lit wall: it reaches far walls in fewer steps")
    passes: IntProperty(
        name="Render Passes", default=settings.final_passes("PROPAGATION", native.module()),
        min=1, soft_max=64,
        description="Passes of an F12 render, a Solve or a bake, each tracing Light Paths: "
                    "more give smoother light")
    viewport_passes: IntProperty(
        name="Viewport Passes", default=VP["PROPAGATION"], min=1, soft_max=64,
        description="Passes the Rendered viewport solves, each tracing Light Paths")
    final_gather: BoolProperty(
        name="Final Gather", default=settings.FINAL_GATHER_DEFAULTS["PROPAGATION"],
        description="Read the grid one bounce away from what the camera sees (a ray per "
                    "sample): fewer blocks and leaks, slower per sample")


class ShgiInstantGiSettings(bpy.types.PropertyGroup):
    """InstantGiSettings of the INSTANT_GI method (``scene.shgi.instant_gi``); its light paths'
    bounce limit is Light Paths > Diffuse."""

    sets_x: IntProperty(
        name="Sets X", default=IG["sets_x"], min=1, max=settings.MAX_INSTANT_SETS,
        description="Sets of little lights across: neighbouring pixels see different sets, "
                    "blended over this many pixels")
    sets_y: IntProperty(
        name="Sets Y", default=IG["sets_y"], min=1, max=settings.MAX_INSTANT_SETS,
        description="Sets of little lights down, blended over this many pixels")
    photons_per_set: IntProperty(
        name="Light Paths per Set", default=IG["photons_per_set"], min=1,
        max=settings.MAX_INSTANT_PHOTONS_PER_SET, soft_max=1024,
        description="Light paths traced per set and pass; where they land become the little "
                    "lights each pixel sees with exact shadows: more give smoother light and "
                    "cost more per pixel")
    clamp_distance: FloatProperty(
        name="Clamp Distance", default=IG["clamp_distance"], min=0.0, soft_max=1.0,
        subtype="DISTANCE",
        description="Little lights closer than this count as this far: no bright spots in "
                    "corners, slightly darker corners")
    filter_mode: EnumProperty(
        name="Filter", items=INSTANT_FILTER_ITEMS, default=IG["filter_mode"],
        description="What is blended between neighbouring pixels")
    depth_threshold: FloatProperty(
        name="Depth Threshold", default=IG["depth_threshold"], min=0.0, soft_max=1.0,
        description="Neighbours whose depth differs by more than this fraction are not blended")
    normal_threshold: FloatProperty(
        name="Normal Threshold", default=IG["normal_threshold"], min=-1.0, max=1.0,
        description="Neighbours whose surfaces' normals have a cosine below this are not "
                    "blended (normal maps do not count)")
    filter_direct: BoolProperty(
        name="Filter Direct Light", default=IG["filter_direct"],
        description="Direct light of the world, lamps and suns goes through the SH filter, "
                    "blended like the indirect light (the world from as many sky directions "
                    "per set as Light Paths per Set; lamps with size from as many samples per "
                    "set): smoother, but L2 SH reads a lamp up to 6% brighter overhead and "
                    "lets some of it past the horizon. Emissive surfaces too, from as many "
                    "samples per set. Off: all direct light is sampled directly")
    passes: IntProperty(
        name="Render Passes", default=settings.render_passes("INSTANT_GI", native.module()),
        min=1, soft_max=256,
        description="Passes of an F12 render or a Solve, each adding Light Paths per Set to "
                    "every set: more give smoother light. A sample sees Per Sample of them, so "
                    "passes beyond that cost no more per sample")
    bake_passes: IntProperty(
        name="Bake Passes", default=settings.final_passes("INSTANT_GI", native.module()),
        min=1, soft_max=64,
        description="Passes of a bake, each adding Light Paths per Set to every set: every "
                    "texel sees all of them, so each pass adds to the bake's time")
    viewport_passes: IntProperty(
        name="Viewport Passes", default=VP["INSTANT_GI"], min=1, soft_max=64,
        description="Passes the Rendered viewport solves")
    passes_per_sample: IntProperty(
        name="Passes per Sample", default=IG["passes_per_sample"], min=1,
        max=settings.MAX_INSTANT_PASSES_PER_SAMPLE, soft_max=64,
        description="Passes of little lights each sample sees, the next ones after the "
                    "previous sample's: with more Render Passes than this, a render's samples "
                    "see different little lights and average them, for smoother light at the "
                    "same cost per sample")
    final_gather: BoolProperty(
        name="Final Gather", default=settings.FINAL_GATHER_DEFAULTS["INSTANT_GI"],
        description="Read the little lights one bounce away from what the camera sees (a ray "
                    "per sample, each reading one set) instead of filtering them on screen: "
                    "exact direct light where the rays land. Bakes filter as before")


class ShgiBakeSettings(bpy.types.PropertyGroup):
    """Lightmap bake settings (``scene.shgi.bake``) that the Bake panel shows."""

    __annotations__ = dict(
        bake_properties(),
        volume_path=StringProperty(
            name="Volume File", default=bake_settings.VOLUME_PATH_DEFAULT, subtype="FILE_PATH",
            description="The JSON file Export Volume writes (its EXR files go beside it)"))


class ShgiSceneSettings(bpy.types.PropertyGroup):
    """SHGI render settings of a scene (``scene.shgi``)."""

    method: EnumProperty(
        name="Method", items=METHOD_ITEMS, default=settings.METHODS[0].identifier,
        description="How indirect light is computed")
    samples: IntProperty(
        name="Samples", default=D["samples"], min=1, max=settings.MAX_SAMPLES, soft_max=4096,
        description="Samples per pixel of a final render")
    seed: IntProperty(
        name="Seed", default=D["seed"], min=0,
        description="Random seed; a render is a pure function of it")
    max_bounces: IntProperty(
        name="Total", default=D["max_bounces"], min=0, max=1024,
        description="Total bounce limit of a path (Cycles' Max Bounces > Total)")
    diffuse_bounces: IntProperty(
        name="Diffuse", default=D["diffuse_bounces"], min=0, max=1024,
        description="Diffuse bounces of a path; the Photon Lattice's photons and the Probe "
                    "Grid's probes follow it too")
    glossy_bounces: IntProperty(
        name="Glossy", default=D["glossy_bounces"], min=0, max=1024,
        description="Glossy bounce limit")
    transmission_bounces: IntProperty(
        name="Transmission", default=D["transmission_bounces"], min=0, max=1024,
        description="Transmission bounce limit")
    clamp_indirect: FloatProperty(
        name="Clamp Indirect", default=D["clamp_indirect"], min=0.0, soft_max=100.0,
        description="Brightest indirect light sample (the mean of its colour), against "
                    "fireflies, as Cycles' Clamping > Indirect Light and with its default "
                    "(also the Probe Grid's probe samples); 0 disables clamping")
    filter_glossy: FloatProperty(
        name="Filter Glossy", default=D["filter_glossy"], min=0.0, soft_max=10.0,
        description="Adaptively blur glossy and glass surfaces after blurry bounces, to reduce "
                    "noise at the cost of accuracy, as Cycles' Caustics > Filter Glossy and with "
                    "its default; 0 disables the blur")
    pixel_filter: EnumProperty(
        name="Pixel Filter", items=PIXEL_FILTER_ITEMS, default=D["pixel_filter"],
        description="How each sample spreads over its pixel and its neighbours, as Cycles' Film "
                    "> Pixel Filter. Box of width 1 (the default here) keeps each sample in its "
                    "pixel; Blackman-Harris 1.5 is Cycles' default look")
    filter_width: FloatProperty(
        name="Width", default=D["filter_width"], min=0.01, max=10.0, soft_max=3.0,
        subtype="PIXEL",
        description="Pixel filter width, as Cycles' (a Blackman-Harris filter of width 1.5 "
                    "spreads a sample over three pixels)")
    world_sampling: EnumProperty(
        name="World Sampling", items=WORLD_SAMPLING_ITEMS, default=D["world_sampling"],
        description="How direct light from the world is sampled")
    light_splits: IntProperty(
        name="Light Splits", default=D["light_splits"], min=1, max=settings.MAX_LIGHT_SPLITS,
        description="Most lights one shading point sends a shadow ray to: where a group of "
                    "lights is large or near, the light tree splits it and samples each part. "
                    "1 picks one light per shadow ray; more cuts the noise of scenes with many "
                    "lights at a little more cost per sample")
    max_specular_bounces: IntProperty(
        name="Specular Bounces", default=D["max_specular_bounces"], min=0, max=64,
        description="Mirror and glass bounces followed by the lattice renderer")
    viewport_samples: IntProperty(
        name="Viewport Samples", default=V["viewport_samples"], min=1, max=settings.MAX_SAMPLES,
        soft_max=4096,
        description="Samples per pixel the Rendered viewport accumulates before it stops")
    time_limit: FloatProperty(
        name="Time Limit", default=T["time_limit"], min=0.0, soft_max=3600.0,
        subtype="TIME_ABSOLUTE",
        description="Longest a final render may take from the end of the scene export (0: no "
                    "limit); it stops with the best image so far, denoised")
    viewport_time_limit: FloatProperty(
        name="Viewport Time Limit", default=T["viewport_time_limit"], min=0.0, soft_max=3600.0,
        subtype="TIME_ABSOLUTE",
        description="Longest the Rendered viewport keeps refining an unchanged view (0: no "
                    "limit)")
    viewport_denoising_start_sample: IntProperty(
        name="Start Sample", default=DN["viewport_denoising_start_sample"], min=1,
        max=settings.MAX_SAMPLES, soft_max=64,
        description="Sample from which the viewport shows denoised frames")
    __annotations__.update(denoising_properties("", "the final render"))
    __annotations__.update(denoising_properties("viewport_", "the Rendered viewport"))
    photon_lattice: PointerProperty(type=ShgiPhotonLatticeSettings, name="Photon Lattice",
                                    description="Settings of the Photon Lattice method")
    probe_grid: PointerProperty(type=ShgiProbeGridSettings, name="Probe Grid",
                                description="Settings of the Probe Grid method")
    radiance_field: PointerProperty(type=ShgiRadianceFieldSettings, name="Radiance Field",
                                    description="Settings of the Radiance Field method")
    instant_gi: PointerProperty(type=ShgiInstantGiSettings, name="Instant GI",
                                description="Settings of the Instant GI method")
    propagation: PointerProperty(type=ShgiPropagationSettings, name="Light Propagation",
                                 description="Settings of the Light Propagation Volumes method")
    bake: PointerProperty(type=ShgiBakeSettings, name="Bake",
                          description="Lightmap bake settings")
    settings_version: IntProperty(
        name="Settings Version", default=settings_upgrade.SETTINGS_VERSION, min=1,
        options={"HIDDEN"},
        description="The layout of these settings in the file (versioning.py brings older "
                    "files up to date when they open)")
    show_probes: BoolProperty(
        name="Show Probes", default=V["show_probes"],
        description="Draw each probe as a small sphere whose colour on each side is the "
                    "indirect light arriving from that side (Rendered viewport or frozen "
                    "solution)")
    overlay_size: FloatProperty(
        name="Sphere Size", default=V["overlay_size"], min=0.02, max=0.5, subtype="FACTOR",
        description="Radius of the probe and lattice spheres in the viewport, as a share of "
                    "the distance between neighbouring probes or cells")
    show_lattice_samples: BoolProperty(
        name="Show Lattice Samples", default=V["show_lattice_samples"],
        description="Draw the photon lattice's cells that hold surface as small spheres shaded "
                    "by their indirect light (Rendered viewport or frozen solution)")


# Registered in this order: a PointerProperty's group before the group holding it.
_CLASSES = (ShgiPhotonLatticeSettings, ShgiProbeGridSettings, ShgiRadianceFieldSettings,
            ShgiPropagationSettings, ShgiInstantGiSettings, ShgiBakeSettings,
            ShgiSceneSettings)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.shgi = PointerProperty(type=ShgiSceneSettings, name="SHGI",
                                           description="SHGI render settings")


def unregister():
    del bpy.types.Scene.shgi
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
