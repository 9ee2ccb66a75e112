"""Lightmap bakes in Blender: shgi.bake_lightmaps against Cycles' bake.

Background mode (``blender -b --factory-startup --python-exit-code 1 --python bake_checks.py --
<build python dir> <addon dir> <results json>``):
1. builds a closed room (floor, four walls and ceiling facing into it, a red wall, a box on the
   floor off centre, an area light off centre under the ceiling, a black world); every quad has
   a UV map "LightmapUV" spanning the unit square (the box gets one from Create UV Map later);
   records which quads face into the room and saves the file;
2. bakes the floor with Cycles (DIFFUSE, pass_filter {DIRECT, INDIRECT}, CYCLES_SAMPLES, no
   denoising) into a RESOLUTION^2 float image, timed, and once more without margin for its mask;
3. bakes the floor with shgi.bake_lightmaps for each source (PATH_TRACE, PHOTON_LATTICE,
   PROBE_GRID), timed, and compares the Blender image with Cycles' over the covered texels
   (Cycles' mask and the EXR's Coverage layer): relative mean difference, mean absolute texel
   difference and PSNR (shgi.metrics.psnr), over every covered texel and over the visible ones
   (without the texels under the box); checks the image against the EXR's Lightmap layer;
4. the refusals: nothing selected, a missing UV map, no light, an object hidden for render, the
   floor with a NaN UV and scaled to 0 (the export leaves it out and the refusal says why),
   Create UV Map on a mesh without faces, a relative output folder in an unsaved file (the room
   was saved as a copy);
5. Create UV Map (Lightmap Pack) on the box with Show in Materials, a shared material left
   alone (Make Materials Single-User off) or copied for the object (on), and Remove Lightmap
   Nodes;
6. shards: two shard bakes of the floor and the box and Merge Shards against a whole bake;
7. Export Volume of a probe grid and of a photon lattice (solving first), and its refusals
   for a scene without geometry (the solve's) and for the path tracer; the Bake panel draws; scene.shgi.bake and the operators hold the defaults
   of bake_settings.BAKE_PROPERTY_DEFAULTS.
Window mode (``-- <build> <addon> <results json> window``, under Xvfb with
--enable-event-simulate): a modal bake of two objects cancelled by Esc after the first one
finished (its files written; no image yet: the images come at the bake's end, in its one undo
step), then a modal bake to its end.
The pytest side (tests/python/test_blender_bake.py) asserts the figures; it also runs the saved
file headless with ``--python-expr``. Prints BAKE_CHECKS_OK (BAKE_WINDOW_OK in window mode).
"""

import json
import math
import os
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()
# Enabled before anything imports shgi_blender's modules (see engine_common.py).
setup.enable_addon()

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
from shgi.metrics import psnr  # noqa: E402
from latency_clock import LatencyClock  # noqa: E402
from recording_layout import draw_panel  # noqa: E402
from shgi_blender import bake_settings  # noqa: E402
from shgi_blender.engine import solution_cache  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402

RESOLUTION = 64              # texels per side of the floor's lightmap
CYCLES_SAMPLES = 1024        # the reference
THREADS = 2
SEED = 1
# shgi samples per texel of each source. The field sources bake only direct light per sample
# (next-event estimation); their indirect light comes from the field, so fewer samples do.
SHGI_SAMPLES = {"PATH_TRACE": 256, "PHOTON_LATTICE": 64, "PROBE_GRID": 64}
SOURCES = tuple(SHGI_SAMPLES)
# Cycles' Light Paths limits, used by both bakers (scene.shgi has the same names).
BOUNCES = {"max_bounces": 12, "diffuse_bounces": 4, "glossy_bounces": 4,
           "transmission_bounces": 12}
# The room: x, y in [-HALF, HALF], z in [0, HEIGHT] (m).
HALF, HEIGHT = 1.5, 2.4
WHITE, RED, GREY = (0.8, 0.8, 0.8), (0.7, 0.1, 0.08), (0.55, 0.55, 0.55)
BOX_CENTRE, BOX_SIZE, BOX_TURN = (0.45, -0.35), 0.7, math.radians(20.0)
LIGHT_POSITION, LIGHT_SIZE, LIGHT_POWER = (-0.4, 0.3, HEIGHT - 0.02), 0.6, 150.0
UV_MAP = "LightmapUV"
UNIT_SQUARE_UV = ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0))
# Texels fully inside the UV layout are compared; Coverage is a fraction of the texel.
FULL_COVERAGE = 1.0 - 1e-6
# Floor texels under the box lie inside it: no one sees them, and bakers disagree there by
# design (shgi moves samples out of geometry, Cycles does not). The "visible" figures leave out
# texels whose centre is within this many texels of the box's footprint (unocclude's reach).
BOX_FOOTPRINT_MARGIN_TEXELS = 1.5
# Shards: a quick bake of the floor and the box.
SHARD_RESOLUTION, SHARD_SAMPLES, SHARD_COUNT = 32, 8, 2
# Quick field solves for the export and refusal checks.
QUICK_PHOTONS, QUICK_RAYS_PER_PROBE, QUICK_PROBE_PASSES = 20_000, 32, 2
# Window mode: two objects whose bakes take a few seconds each, then a small one.
MODAL_RESOLUTION, MODAL_SAMPLES = 96, 256
MODAL_SMALL_RESOLUTION, MODAL_SMALL_SAMPLES = 16, 4
MODAL_TIMEOUT_SECONDS = 120.0
POLL_SECONDS = 0.02
WATCH_SECONDS = 0.001
WORKER_THREAD = "shgi-bake"


# --- the room ------------------------------------------------------------------------------------

def principled(name, color):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*color, 1)
    return material


def quad_object(scene, name, corner, edge_u, edge_v, material):
    """A one-face quad corner + [0,1]u + [0,1]v facing u x v, with LightmapUV = unit square."""
    c = np.asarray(corner, float)
    u, v = np.asarray(edge_u, float), np.asarray(edge_v, float)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(c), tuple(c + u), tuple(c + u + v), tuple(c + v)], [],
                     [(0, 1, 2, 3)])
    layer = mesh.uv_layers.new(name=UV_MAP)
    for loop, uv in zip(mesh.polygons[0].loop_indices, UNIT_SQUARE_UV):
        layer.data[loop].uv = uv
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj


def build_room(scene):
    """The closed room of the comparison in `scene` (an empty one)."""
    white, red = principled("white", WHITE), principled("red", RED)
    h, z = HALF, HEIGHT
    quad_object(scene, "floor", (-h, -h, 0), (2 * h, 0, 0), (0, 2 * h, 0),
                principled("floor", GREY))
    quad_object(scene, "ceiling", (-h, -h, z), (0, 2 * h, 0), (2 * h, 0, 0), white)
    quad_object(scene, "wall_north", (-h, h, 0), (2 * h, 0, 0), (0, 0, z), white)
    quad_object(scene, "wall_south", (-h, -h, 0), (0, 0, z), (2 * h, 0, 0), white)
    quad_object(scene, "wall_east", (h, -h, 0), (0, 0, z), (0, 2 * h, 0), white)
    quad_object(scene, "wall_west", (-h, -h, 0), (0, 2 * h, 0), (0, 0, z), red)
    # The cube keeps its "UVMap" and has no LightmapUV: Create UV Map adds it.
    bpy.ops.mesh.primitive_cube_add(size=BOX_SIZE, location=(*BOX_CENTRE, BOX_SIZE / 2))
    box = bpy.context.active_object
    box.name = box.data.name = "box"
    box.rotation_euler.z = BOX_TURN
    box.data.materials.append(principled("box", WHITE))
    light = bpy.data.lights.new("ceiling_light", "AREA")
    light.energy, light.shape, light.size = LIGHT_POWER, "SQUARE", LIGHT_SIZE
    light_object = bpy.data.objects.new("ceiling_light", light)
    light_object.location = LIGHT_POSITION  # an area light emits down its local -Z
    scene.collection.objects.link(light_object)
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    for field, value in BOUNCES.items():
        setattr(scene.shgi, field, value)
        setattr(scene.cycles, field, value)
    scene.shgi.seed = SEED
    scene.render.threads_mode = "FIXED"
    scene.render.threads = THREADS
    return scene


def inward_facing_quads():
    """Names of the room's quads whose normal points to the room's centre."""
    centre = np.array([0.0, 0.0, HEIGHT / 2])
    inward = []
    for obj in bpy.data.objects:
        if obj.type != "MESH" or obj.name == "box":
            continue
        polygon = obj.data.polygons[0]
        to_centre = centre - np.asarray(obj.matrix_world @ polygon.center)
        if float(np.dot(np.asarray(polygon.normal), to_centre)) > 0.0:
            inward.append(obj.name)
    return sorted(inward)


def select_only(*names):
    bpy.ops.object.select_all(action="DESELECT")
    for name in names:
        bpy.data.objects[name].select_set(True)
    bpy.context.view_layer.objects.active = bpy.data.objects[names[0]] if names else None


def under_box(resolution):
    """(H, W) bool: floor texels whose centre lies within BOX_FOOTPRINT_MARGIN_TEXELS of the
    box's footprint (the floor's LightmapUV maps u to x and v to y over [-HALF, HALF])."""
    centres = -HALF + 2.0 * HALF * (np.arange(resolution) + 0.5) / resolution
    x, y = np.meshgrid(centres - BOX_CENTRE[0], centres - BOX_CENTRE[1])  # rows: v (y)
    c, s = math.cos(BOX_TURN), math.sin(BOX_TURN)
    local_x, local_y = c * x + s * y, -s * x + c * y
    reach = BOX_SIZE / 2 + BOX_FOOTPRINT_MARGIN_TEXELS * 2.0 * HALF / resolution
    return (np.abs(local_x) <= reach) & (np.abs(local_y) <= reach)


# --- the two bakers ------------------------------------------------------------------------------

def set_up_cycles(scene):
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.samples = CYCLES_SAMPLES
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    scene.shgi.clamp_indirect = 0.0  # SHGI's bakes unclamped too
    cycles.blur_glossy = scene.shgi.filter_glossy = 0.0  # and unfiltered, both
    cycles.light_sampling_threshold = 0.0
    cycles.seed = SEED


def cycles_bake(name):
    """Cycles' DIFFUSE {DIRECT, INDIRECT} bake of object `name` through LightmapUV, without a
    margin: ((H, W, 4) float64 RGBA, seconds); alpha is 1 where Cycles baked (the image starts at
    0). The comparisons read only those texels, so the one bake is the reference and the mask."""
    obj = bpy.data.objects[name]
    image = bpy.data.images.new(f"{name}_cycles", RESOLUTION, RESOLUTION, alpha=True,
                                float_buffer=True)
    image.generated_color = (0.0, 0.0, 0.0, 0.0)
    tree = obj.active_material.node_tree
    node = tree.nodes.new("ShaderNodeTexImage")
    node.image = image
    tree.nodes.active = node
    obj.data.uv_layers.active = obj.data.uv_layers[UV_MAP]
    select_only(name)
    start = time.perf_counter()
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=0,
                        use_clear=True, target="IMAGE_TEXTURES")
    seconds = time.perf_counter() - start
    tree.nodes.remove(node)
    pixels = np.empty(RESOLUTION * RESOLUTION * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(RESOLUTION, RESOLUTION, 4).astype(np.float64), seconds


def image_texels(name):
    """(H, W, 3) float64 texels of Blender image `name` (rows from v = 0)."""
    image = bpy.data.images[name]
    width, height = image.size
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(height, width, 4)[..., :3].astype(np.float64)


def exr_layers(path):
    """{layer: (H, W, C) float64} of a lightmap EXR, rows flipped to v = 0 first."""
    return {name: np.asarray(pixels, np.float64)[::-1]
            for name, pixels in shgi.read_exr(path).items()}


def bake(*names, **arguments):
    """shgi.bake_lightmaps of the objects `names` (selected); its seconds."""
    select_only(*names)
    start = time.perf_counter()
    status = bpy.ops.shgi.bake_lightmaps(**arguments)
    if status != {"FINISHED"}:
        raise AssertionError(f"shgi.bake_lightmaps({arguments}) returned {status}")
    return time.perf_counter() - start


def figures(reference, texels, mask):
    """A bake against the Cycles reference over the texels of `mask`."""
    ref, img = reference[mask], texels[mask]
    ref_mean = float(ref.mean())
    return {"mean_difference": float((img - ref).mean()) / ref_mean,
            "mean_absolute_difference": float(np.abs(img - ref).mean()) / ref_mean,
            "psnr": psnr(ref, img), "texels": int(mask.sum())}


def bake_comparison(scene, tmpdir, results):
    set_up_cycles(scene)
    reference, seconds = cycles_bake("floor")
    mask = reference[..., 3] > 0.5
    results["cycles"] = {"seconds": seconds, "samples": CYCLES_SAMPLES,
                         "mask_texels": int(mask.sum())}
    print(f"Cycles bake of the floor: {RESOLUTION}x{RESOLUTION} texels, {CYCLES_SAMPLES} "
          f"samples, {seconds:.2f} s")
    visible = ~under_box(RESOLUTION)
    for source in SOURCES:
        out_dir = os.path.join(tmpdir, f"bake_{source.lower()}")
        seconds = bake("floor", source=source, samples=SHGI_SAMPLES[source],
                       resolution=RESOLUTION, output_folder=out_dir)
        texels = image_texels("floor_shgi_lightmap")
        layers = exr_layers(os.path.join(out_dir, "floor.exr"))
        covered = mask & (layers["Coverage"][..., 0] >= FULL_COVERAGE)
        row = {"seconds": seconds, "samples": SHGI_SAMPLES[source],
               "covered": figures(reference[..., :3], texels, covered),
               "visible": figures(reference[..., :3], texels, covered & visible),
               "files": sorted(os.listdir(out_dir)),
               # Row order and UV orientation: the baked texels against Cycles' as they are
               # and mirrored in v (rows) and in u (columns).
               "orientation_psnr": {
                   "as_baked": psnr(reference[covered, :3], texels[covered]),
                   "v_mirrored": psnr(reference[covered, :3], texels[::-1][covered]),
                   "u_mirrored": psnr(reference[covered, :3], texels[:, ::-1][covered])},
               # The EXR holds half floats: relative rounding 2^-11.
               "exr_vs_image": float(np.max(np.abs(layers["Lightmap"] - texels)
                                            / np.maximum(np.abs(texels), 1e-3)))}
        results["sources"][source] = row
        print(f"shgi {source} ({row['samples']} samples, {seconds:.2f} s): covered texels "
              f"mean {100 * row['covered']['mean_difference']:+.2f}%, PSNR "
              f"{row['covered']['psnr']:.2f} dB; visible texels mean "
              f"{100 * row['visible']['mean_difference']:+.2f}%, mean |difference| "
              f"{100 * row['visible']['mean_absolute_difference']:.2f}%, PSNR "
              f"{row['visible']['psnr']:.2f} dB")
    image = bpy.data.images["floor_shgi_lightmap"]
    results["image"] = {"size": list(image.size), "is_float": image.is_float,
                        "packed": image.packed_file is not None}
    # The image was baked into five times; what it packed is the last bake.
    image.reload()  # from the packed data
    texels = image_texels(image.name)
    exr = exr_layers(os.path.join(out_dir, "floor.exr"))["Lightmap"]
    results["image"]["packed_vs_last_exr"] = float(np.max(np.abs(exr - texels)
                                                          / np.maximum(np.abs(texels), 1e-3)))


# --- refusals ------------------------------------------------------------------------------------

def refusal(*names, **arguments):
    """The error message of a bake of `names` that must fail (RuntimeError in background)."""
    select_only(*names)
    try:
        bpy.ops.shgi.bake_lightmaps(**arguments)
    except RuntimeError as error:
        return str(error)
    raise AssertionError(f"a bake of {names} with {arguments} did not fail")


def refusal_checks(tmpdir, results):
    out = os.path.join(tmpdir, "refused")
    errors = results["errors"]
    errors["nothing_selected"] = refusal(output_folder=out)
    errors["only_a_light"] = refusal("ceiling_light", output_folder=out)
    errors["missing_uv_map"] = refusal("box", "floor", output_folder=out)
    light = bpy.data.objects["ceiling_light"]
    light.hide_render = True
    errors["no_light"] = refusal("floor", output_folder=out, resolution=16, samples=1)
    light.hide_render = False
    wall = bpy.data.objects["wall_north"]
    wall.hide_render = True
    errors["hidden_for_render"] = refusal("wall_north", output_folder=out)
    wall.hide_render = False
    left_out_refusals(out, errors)
    results["faceless_uv_maps"] = faceless_refusal(out, errors)
    # The room was saved as a copy: this file has no path yet.
    results["file_path_while_refused"] = bpy.data.filepath
    errors["unsaved_relative_folder"] = refusal("floor", output_folder="//lightmaps")
    results["refused_files"] = os.path.exists(out)


def left_out_refusals(out, errors):
    """The floor with a NaN in its lightmap UV map, then scaled to 0: the export leaves it out,
    and the refusal says why."""
    floor = bpy.data.objects["floor"]
    corner = floor.data.uv_layers[UV_MAP].data[0]
    uv = tuple(corner.uv)
    corner.uv = (math.nan, uv[1])
    errors["nan_uv"] = refusal("floor", output_folder=out)
    corner.uv = uv
    floor.scale = (0.0, 1.0, 1.0)
    errors["zero_scale"] = refusal("floor", output_folder=out)
    floor.scale = (1.0, 1.0, 1.0)


def faceless_refusal(out, errors):
    """Create UV Map on a mesh of two vertices and no faces is refused; the UV maps the mesh
    is left with."""
    mesh = bpy.data.meshes.new("points")
    mesh.from_pydata([(0.0, 0.0, 0.5), (0.2, 0.2, 0.6)], [], [])
    obj = bpy.data.objects.new("points", mesh)
    bpy.context.scene.collection.objects.link(obj)
    errors["faceless_create_uv"] = refusal("points", create_uv=True, output_folder=out)
    uv_maps = [layer.name for layer in mesh.uv_layers]
    bpy.data.objects.remove(obj, do_unlink=True)
    bpy.data.meshes.remove(mesh)
    return uv_maps


# --- UV maps, materials, shards, volumes ---------------------------------------------------------

def overlapping_samples(uv, corners, grid):
    """Sample points of a grid x grid lattice over the unit square inside more than one of the
    UV triangles `corners` (T, 3 loop indices into `uv`)."""
    centres = (np.stack(np.meshgrid(np.arange(grid), np.arange(grid)), -1).reshape(-1, 2)
               + 0.5) / grid
    inside = np.zeros(len(centres), np.int32)
    for a, b, c in uv[corners]:
        d = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1])
        if abs(d) < 1e-12:
            continue
        l1 = ((b[1] - c[1]) * (centres[:, 0] - c[0]) + (c[0] - b[0]) * (centres[:, 1] - c[1])) / d
        l2 = ((c[1] - a[1]) * (centres[:, 0] - c[0]) + (a[0] - c[0]) * (centres[:, 1] - c[1])) / d
        inside += (l1 > 0) & (l2 > 0) & (1 - l1 - l2 > 0)
    return int(np.count_nonzero(inside > 1)), float(np.count_nonzero(inside) / len(centres))


def roughness(texels):
    """Mean absolute difference of horizontally neighbouring texels (noise, plus edges)."""
    return float(np.abs(np.diff(texels, axis=1)).mean())


def denoised_bake(tmpdir, results):
    """The floor at 4 samples per texel, raw and denoised by OpenImageDenoise inside this
    Blender (pyoidn's library beside Blender's own copy): same light, far less noise."""
    layers = {}
    for name, arguments in (("raw", {"filter": False}),
                            ("oidn", {"filter": True, "denoiser": "OIDN"})):
        folder = os.path.join(tmpdir, f"oidn_{name}")
        bake("floor", resolution=SHARD_RESOLUTION, samples=4, output_folder=folder, **arguments)
        exr = shgi.read_exr(os.path.join(folder, "floor.exr"))
        covered = np.asarray(exr["Coverage"])[..., 0] > 0
        layers[name] = np.where(covered[..., None], np.asarray(exr["Lightmap"], np.float64), 0)
    results["oidn"] = {name: {"mean": float(texels.mean()), "roughness": roughness(texels)}
                       for name, texels in layers.items()}


def xatlas_layout(tmpdir, results):
    """Create UV Map with the xatlas layout on a copy of the box without the UV map: a
    lightmap UV map inside the unit square whose triangles do not overlap, then the bake."""
    box = bpy.data.objects["box"]
    copy = box.copy()
    copy.data = box.data.copy()
    copy.name = "box_xatlas"
    copy.data.uv_layers.remove(copy.data.uv_layers[UV_MAP])
    copy.location.x += 0.01  # beside the box, in the same light
    bpy.context.scene.collection.objects.link(copy)
    folder = os.path.join(tmpdir, "xatlas")
    bake("box_xatlas", create_uv=True, uv_layout="XATLAS", resolution=SHARD_RESOLUTION,
         samples=SHARD_SAMPLES, output_folder=folder)
    mesh = copy.data
    uv = np.empty(len(mesh.loops) * 2, np.float32)
    mesh.uv_layers[UV_MAP].data.foreach_get("uv", uv)
    mesh.calc_loop_triangles()
    corners = np.empty(len(mesh.loop_triangles) * 3, np.int32)
    mesh.loop_triangles.foreach_get("loops", corners)
    overlapping, covered = overlapping_samples(uv.reshape(-1, 2), corners.reshape(-1, 3), 256)
    a, b, c = (uv.reshape(-1, 2)[corners.reshape(-1, 3)[:, k]].astype(np.float64)
               for k in range(3))
    uv_area = 0.5 * float(np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                                 - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])).sum())
    lightmap = shgi.read_exr(os.path.join(folder, "box_xatlas.exr"))
    results["xatlas"] = {
        "uv_maps": [layer.name for layer in mesh.uv_layers],
        "uv_range": [float(uv.min()), float(uv.max())],
        "overlapping_samples": overlapping, "covered_share": covered, "uv_area": uv_area,
        "files": sorted(os.listdir(folder)),
        "lightmap_mean": float(np.asarray(lightmap["Lightmap"]).mean())}
    bpy.data.objects.remove(copy, do_unlink=True)


def create_uv_and_materials(tmpdir, results):
    """Create UV Map on the box with Show in Materials; a shared material is left alone, or
    copied for the object with Make Materials Single-User; Remove Lightmap Nodes gives the
    material back."""
    box = bpy.data.objects["box"]
    bake("box", create_uv=True, hook_up_material=True, resolution=SHARD_RESOLUTION,
         samples=SHARD_SAMPLES, output_folder=os.path.join(tmpdir, "box"))
    uv = np.empty(len(box.data.loops) * 2, np.float32)
    box.data.uv_layers[UV_MAP].data.foreach_get("uv", uv)
    tree = box.active_material.node_tree
    texture = tree.nodes.get("SHGI Lightmap")
    output = tree.get_output_node("ALL")
    results["create_uv"] = {
        "uv_maps": [layer.name for layer in box.data.uv_layers],
        "active_uv_map": box.data.uv_layers.active.name,
        "uv_range": [float(uv.min()), float(uv.max())]}
    results["materials"] = {
        "nodes": sorted(node.name for node in tree.nodes if node.name.startswith("SHGI")),
        "image": texture.image.name if texture else None,
        "uv_node_map": tree.nodes["SHGI Lightmap UV"].uv_map,
        "surface_from": output.inputs["Surface"].links[0].from_node.name,
        "active_node": tree.nodes.active.name,
        # SHGI's export looks through the preview nodes: the box keeps its own material.
        "exported_materials": sorted(material.name for material in export_scene(
            bpy.context.evaluated_depsgraph_get(), with_camera=False).scene.materials)}
    bake("ceiling", hook_up_material=True, single_user_materials=False, resolution=16,
         samples=1, output_folder=os.path.join(tmpdir, "ceiling"))
    results["materials"]["shared_material_nodes"] = [
        node.name for node in bpy.data.materials["white"].node_tree.nodes
        if node.name.startswith("SHGI")]
    bake("ceiling", hook_up_material=True, resolution=16, samples=1,
         output_folder=os.path.join(tmpdir, "ceiling"))
    ceiling = bpy.data.objects["ceiling"].active_material
    results["materials"]["single_user"] = {
        "ceiling_material": ceiling.name,
        "ceiling_image": ceiling.node_tree.nodes["SHGI Lightmap"].image.name,
        "white_users": sorted(obj.name for obj in bpy.data.objects
                              if obj.active_material == bpy.data.materials["white"]),
        "white_nodes": [node.name for node in bpy.data.materials["white"].node_tree.nodes
                        if node.name.startswith("SHGI")]}
    bpy.data.objects["ceiling"].active_material = bpy.data.materials["white"]  # as built
    select_only("box")
    bpy.ops.shgi.remove_lightmap_nodes()
    results["materials"]["after_removal"] = {
        "nodes": [node.name for node in tree.nodes if node.name.startswith("SHGI")],
        "surface_from": output.inputs["Surface"].links[0].from_node.name}


def shard_checks(tmpdir, results):
    """Two shards and Merge Shards against a whole bake of the floor and the box."""
    common = dict(resolution=SHARD_RESOLUTION, samples=SHARD_SAMPLES, source="PATH_TRACE")
    whole, sharded = os.path.join(tmpdir, "whole"), os.path.join(tmpdir, "sharded")
    bake("box", "floor", output_folder=whole, **common)
    for index in range(SHARD_COUNT):
        bake("box", "floor", output_folder=sharded, shard_index=index, shard_count=SHARD_COUNT,
             **common)
    shard_files = sorted(os.listdir(os.path.join(sharded, "shards")))
    select_only("box", "floor")
    status = bpy.ops.shgi.merge_lightmap_shards(output_folder=sharded, shard_count=SHARD_COUNT,
                                                **common)
    identical = {}
    for name in sorted(os.listdir(whole)):
        with open(os.path.join(whole, name), "rb") as a, open(os.path.join(sharded, name),
                                                              "rb") as b:
            identical[name] = a.read() == b.read()
    results["shards"] = {"shard_files": shard_files, "merge_status": sorted(status),
                         "identical": identical}


def export_volume_checks(scene, tmpdir, results):
    """Export Volume solves and freezes the method's field when there is none, then writes it."""
    scene.shgi.photon_lattice.photons = QUICK_PHOTONS
    scene.shgi.probe_grid.rays_per_probe = QUICK_RAYS_PER_PROBE
    scene.shgi.probe_grid.passes = QUICK_PROBE_PASSES
    volumes = {}
    for method in ("PROBE_GRID", "PHOTON_LATTICE"):
        scene.shgi.method = method
        solution_cache.clear(scene.name_full)
        path = os.path.join(tmpdir, f"volume_{method.lower()}", "volume.json")
        status = bpy.ops.shgi.export_volume(filepath=path)
        with open(path) as handle:
            document = json.load(handle)
        volumes[method] = {"status": sorted(status), "files": sorted(os.listdir(
            os.path.dirname(path))), "json_keys": sorted(document),
            "frozen": solution_cache.get(scene.name_full, method) is not None}
    volumes["no_geometry_error"] = export_without_geometry(scene, tmpdir)
    scene.shgi.method = "PATH_TRACE"
    try:
        bpy.ops.shgi.export_volume(filepath=os.path.join(tmpdir, "volume_none", "none.json"))
        volumes["PATH_TRACE_error"] = None
    except RuntimeError as error:
        volumes["PATH_TRACE_error"] = str(error)
    results["volumes"] = volumes
    scene.render.engine = "SHGI"
    results["panel"] = draw_panel("SHGI_RENDER_PT_bake")


def export_without_geometry(scene, tmpdir):
    """Export Volume of a photon lattice with every mesh hidden for render: the solve it runs
    first refuses; the error message (None when it did not fail)."""
    meshes = [obj for obj in scene.objects if obj.type == "MESH"]
    for obj in meshes:
        obj.hide_render = True
    scene.shgi.method = "PHOTON_LATTICE"
    solution_cache.clear(scene.name_full)
    try:
        bpy.ops.shgi.export_volume(filepath=os.path.join(tmpdir, "volume_empty", "empty.json"))
        return None
    except RuntimeError as error:
        return str(error)
    finally:
        for obj in meshes:
            obj.hide_render = False


def property_defaults(scene, results):
    """scene.shgi.bake's values and the bake operators' defaults, by property name."""
    results["group_defaults"] = {name: getattr(scene.shgi.bake, name)
                                 for name in bake_settings.BAKE_PROPERTY_DEFAULTS}
    for operator in ("bake_lightmaps", "merge_lightmap_shards"):
        rna = getattr(bpy.ops.shgi, operator).get_rna_type().properties
        results[f"{operator}_defaults"] = {name: rna[name].default
                                           for name in bake_settings.BAKE_PROPERTY_DEFAULTS}
    # (hard max, soft max) of Resolution in the group and in each bake operator.
    owners = {"scene.shgi.bake": scene.shgi.bake.bl_rna.properties}
    owners.update({operator: getattr(bpy.ops.shgi, operator).get_rna_type().properties
                   for operator in ("bake_lightmaps", "merge_lightmap_shards")})
    results["resolution_range"] = {owner: [rna["resolution"].hard_max,
                                           rna["resolution"].soft_max]
                                   for owner, rna in owners.items()}


# --- background mode -----------------------------------------------------------------------------

def background_main():
    tmpdir = tempfile.mkdtemp(prefix="shgi_bake_")
    results = {"sources": {}, "errors": {}}
    bpy.ops.wm.read_homefile(use_empty=True, use_factory_startup=True)
    setup.enable_addon()
    scene = build_room(bpy.context.scene)
    property_defaults(scene, results)
    results["inward_quads"] = inward_facing_quads()
    blend_path = os.path.join(tmpdir, "room.blend")
    select_only("floor")  # what the headless run bakes
    bpy.ops.wm.save_as_mainfile(filepath=blend_path, copy=True)
    results["blend_path"] = blend_path
    start = time.perf_counter()
    bake_comparison(scene, tmpdir, results)
    results["comparison_seconds"] = time.perf_counter() - start
    refusal_checks(tmpdir, results)
    create_uv_and_materials(tmpdir, results)
    xatlas_layout(tmpdir, results)
    denoised_bake(tmpdir, results)
    shard_checks(tmpdir, results)
    export_volume_checks(scene, tmpdir, results)
    with open(setup.results_path("bake_checks.json"), "w") as out:
        json.dump(results, out, indent=1)
    print("BAKE_CHECKS_OK")


# --- window mode: the modal bake -----------------------------------------------------------------

def worker_running():
    return any(thread.name == WORKER_THREAD for thread in threading.enumerate())


def watch_worker_end(clock):
    """{"latency": clock.read()} once the bake's worker thread has ended, timed by a thread of
    its own (the steps' timer runs only between Blender's redraws)."""
    ended = {}

    def watch():
        while worker_running():
            time.sleep(WATCH_SECONDS)
        ended["latency"] = clock.read()

    threading.Thread(target=watch, name="bake-watch", daemon=True).start()
    return ended


def invoke_bake(out_dir, *names, **arguments):
    """shgi.bake_lightmaps('INVOKE_DEFAULT') in the 3D view of the window, as a button does."""
    select_only(*names)
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=window, area=area, region=region):
        return bpy.ops.shgi.bake_lightmaps("INVOKE_DEFAULT", output_folder=out_dir, **arguments)


def modal_steps(results, out_dir):
    """Generator of the window-mode steps; yields the seconds to wait before going on."""
    bpy.context.preferences.view.show_splash = False
    setup.enable_addon()
    setup.clear_scene()
    build_room(bpy.context.scene)
    yield 0.5
    cancelled_dir = os.path.join(out_dir, "cancelled")
    status = invoke_bake(cancelled_dir, "box", "floor", create_uv=True,
                         resolution=MODAL_RESOLUTION, samples=MODAL_SAMPLES)
    results["invoke_status"] = sorted(status)
    start = time.perf_counter()
    # The first object's files (its image waits for the bake's end: one undo step).
    while not os.path.exists(os.path.join(cancelled_dir, "box.png")):
        if time.perf_counter() - start > MODAL_TIMEOUT_SECONDS or not worker_running():
            raise AssertionError("the first lightmap of the modal bake never arrived")
        yield POLL_SECONDS
    results["images_while_running"] = sorted(image.name for image in bpy.data.images
                                             if image.name.endswith("_shgi_lightmap"))
    results["first_image_seconds"] = time.perf_counter() - start
    results["worker_running_at_esc"] = worker_running()
    esc = LatencyClock()
    ended = watch_worker_end(esc)
    bpy.context.window_manager.windows[0].event_simulate(type="ESC", value="PRESS")
    while "latency" not in ended and esc.read().wall < MODAL_TIMEOUT_SECONDS:
        yield POLL_SECONDS
    results["cancel_latency"] = ended["latency"]._asdict()
    yield 0.5  # the operator's timer notices the end and finishes
    results["cancelled"] = {"images": sorted(image.name for image in bpy.data.images
                                             if image.name.endswith("_shgi_lightmap")),
                            "files": sorted(os.listdir(cancelled_dir))}
    finished_dir = os.path.join(out_dir, "finished")
    invoke_bake(finished_dir, "floor", resolution=MODAL_SMALL_RESOLUTION,
                samples=MODAL_SMALL_SAMPLES)
    start = time.perf_counter()
    while not (os.path.exists(os.path.join(finished_dir, "floor.exr"))
               and "floor_shgi_lightmap" in bpy.data.images):
        if time.perf_counter() - start > MODAL_TIMEOUT_SECONDS:
            raise AssertionError("the second modal bake did not finish")
        yield POLL_SECONDS
    results["finished"] = {"size": list(bpy.data.images["floor_shgi_lightmap"].size),
                           "files": sorted(os.listdir(finished_dir))}


def window_main():
    path = setup.results_path("bake_window.json")
    results = {}
    steps = modal_steps(results, os.path.join(os.path.dirname(path), "modal_bake"))
    setup.run_steps_in_window(steps, results, path, "BAKE_WINDOW_OK")


if setup.script_args()[3:4] == ["window"]:
    window_main()
else:
    background_main()
