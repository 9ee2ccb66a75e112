"""Undo after a lightmap bake with Show in Materials, then Material Preview, in a real window.

Runs Blender with a window under Xvfb (Debian's Blender program; the bpy module has none):

    xvfb-run -a blender --factory-startup --enable-event-simulate \
        --window-geometry 0 0 <W> <H> --python tests/blender/bake_undo_window.py -- \
        <build python dir> <addon dir> <results json>

The steps run from a timer on Blender's main thread while the window draws. In the startup
file's scene it builds the sun room facing in (examples/blender_scenes.py, lightmap=True),
pushes an undo step, selects the ten objects and pushes another, then:
1. bakes its ten objects from the 3D view (INVOKE_DEFAULT: modal, as the Bake button does) with
   Show in Materials and Create UV Map (the table has no LightmapUV); the bake is not among the
   registered operators that Adjust Last Operation and Repeat Last would run again;
2. undoes once (ed.undo in the window): UV maps, images, material copies and nodes must all go
   back to the state before the bake;
3. switches the 3D view to Material Preview and draws it (EEVEE compiles the materials);
4. redoes (ed.redo) and draws again: the bake's state comes back whole;
5. adds two rugs (no lightmap UV map yet), bakes them with Create UV Map and cancels with Esc
   (simulated) once the first one's files are written: the first rug's image is kept and both
   got the UV map, in one undo step, which one undo takes back whole.
After each step it records the data's state (lightmap images, the lightmap nodes per material
and their images, each object's materials and UV maps) and what is inconsistent in it (a
lightmap node without its image, an object showing a lightmap through a UV map its mesh lacks).
tests/python/test_blender_bake.py asserts them. Prints BAKE_UNDO_WINDOW_OK; a failed step
writes its error and exits with 1; a crash leaves no results.
"""

import os
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()
sys.path.insert(0, str(setup.REPO_ROOT / "examples"))

import bpy  # noqa: E402

RESOLUTION, SAMPLES = 16, 16
# The cancelled bake: each rug takes seconds, so Esc lands while the second one bakes.
CANCEL_RESOLUTION, CANCEL_SAMPLES = 96, 256
RUGS = ("rug_a", "rug_b")
BAKE_TIMEOUT_SECONDS = 120.0
POLL_SECONDS = 0.1
# Material Preview: redraws, a pause between them for EEVEE's shader compiles.
PREVIEW_DRAWS, PREVIEW_PAUSE_SECONDS = 6, 0.5
WORKER_THREAD = "shgi-bake"
LIGHTMAP_SUFFIX = "_shgi_lightmap"
TEXTURE_NODE, UV_NODE = "SHGI Lightmap", "SHGI Lightmap UV"
RESULTS_PATH = setup.results_path("bake_undo_window.json")
RESULTS = {}


def view3d():
    """(window, area, region, space) of the 3D view."""
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, area, region, area.spaces.active


def in_view(operator, *args, **kwargs):
    """Runs bpy.ops `operator` with the 3D view's window, area and region as its context."""
    window, area, region, _space = view3d()
    with bpy.context.temp_override(window=window, area=area, region=region):
        return sorted(operator(*args, **kwargs))


def draw(times=1):
    for _ in range(times):
        in_view(bpy.ops.wm.redraw_timer, type="DRAW_WIN_SWAP", iterations=1)


def data_state():
    """What the bake touches: lightmap images, lightmap nodes per material (their image), each
    mesh object's materials and UV maps; and `problems`, what is inconsistent among them."""
    images = sorted(image.name for image in bpy.data.images
                    if image.name.endswith(LIGHTMAP_SUFFIX))
    nodes, uv_nodes = {}, {}
    for material in bpy.data.materials:
        tree = material.node_tree
        texture = tree.nodes.get(TEXTURE_NODE) if tree is not None else None
        if texture is not None:
            nodes[material.name] = texture.image.name if texture.image is not None else None
            uv = tree.nodes.get(UV_NODE)
            uv_nodes[material.name] = uv.uv_map if uv is not None else None
    objects = {obj.name: {"materials": [slot.material.name for slot in obj.material_slots
                                        if slot.material is not None],
                          "uv_maps": [layer.name for layer in obj.data.uv_layers]}
               for obj in bpy.data.objects if obj.type == "MESH"}
    problems = [f"material {name!r}: lightmap node without an image"
                for name, image in nodes.items() if image is None]
    problems += [f"material {name!r}: image {image!r} is not among {images}"
                 for name, image in nodes.items() if image is not None and image not in images]
    for name, row in objects.items():
        problems += [f"object {name!r}: material {material!r} reads UV map "
                     f"{uv_nodes[material]!r}, which the mesh lacks"
                     for material in row["materials"]
                     if material in uv_nodes and uv_nodes[material] not in row["uv_maps"]]
    return {"images": images, "nodes": nodes, "objects": objects, "problems": problems}


def worker_running():
    return any(thread.name == WORKER_THREAD for thread in threading.enumerate())


def select(names):
    bpy.ops.object.select_all(action="DESELECT")
    for name in names:
        bpy.data.objects[name].select_set(True)
    bpy.context.view_layer.objects.active = bpy.data.objects[names[0]]


def invoke_bake(folder, **arguments):
    """shgi.bake_lightmaps('INVOKE_DEFAULT') of the selected objects into `folder` (absolute),
    as the Bake button runs it."""
    return in_view(bpy.ops.shgi.bake_lightmaps, "INVOKE_DEFAULT", output_folder=folder,
                   **arguments)


def add_rugs():
    """Two 2 x 2 m quads just above the floor, without a UV map."""
    for index, name in enumerate(RUGS):
        z = 0.01 * (index + 1)
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata([(-1, 1, z), (1, 1, z), (1, 3, z), (-1, 3, z)], [], [(0, 1, 2, 3)])
        bpy.context.scene.collection.objects.link(bpy.data.objects.new(name, mesh))


def cancelled_bake():
    """Generator: the rugs' bake, cancelled by Esc once the first rug's files are written."""
    select(RUGS)
    folder = os.path.join(tempfile.mkdtemp(prefix="shgi_undo_"), "rugs")
    RESULTS["cancel_invoke_status"] = invoke_bake(
        folder, create_uv=True, resolution=CANCEL_RESOLUTION, samples=CANCEL_SAMPLES)
    start = time.perf_counter()
    while not os.path.exists(os.path.join(folder, f"{RUGS[0]}.png")):
        if time.perf_counter() - start > BAKE_TIMEOUT_SECONDS or not worker_running():
            raise AssertionError("the first rug's lightmap never arrived")
        yield POLL_SECONDS
    RESULTS["worker_running_at_esc"] = worker_running()
    view3d()[0].event_simulate(type="ESC", value="PRESS")
    start = time.perf_counter()
    while worker_running():
        if time.perf_counter() - start > BAKE_TIMEOUT_SECONDS:
            raise AssertionError("Esc did not stop the rugs' bake")
        yield POLL_SECONDS
    yield 0.5  # the operator's timer notices the end and keeps what finished


def baked_room():
    """Generator: the room's ten objects baked to the end with Show in Materials."""
    names = sorted(obj.name for obj in bpy.data.objects if obj.type == "MESH")
    select(names)
    in_view(bpy.ops.ed.undo_push, message="select")  # as selecting in the view pushes one
    RESULTS["invoke_status"] = invoke_bake(
        os.path.join(tempfile.mkdtemp(prefix="shgi_undo_"), "lightmaps"),
        hook_up_material=True, create_uv=True, resolution=RESOLUTION, samples=SAMPLES)
    start = time.perf_counter()
    while worker_running() or not all(f"{name}{LIGHTMAP_SUFFIX}" in bpy.data.images
                                      for name in names):
        if time.perf_counter() - start > BAKE_TIMEOUT_SECONDS:
            raise AssertionError(f"the modal bake did not finish: {data_state()}")
        yield POLL_SECONDS
    yield 0.5  # the operator's timer notices the end and makes the images


def material_preview(draws=PREVIEW_DRAWS):
    """Generator: the 3D view in Material Preview, drawn `draws` times (EEVEE compiles)."""
    space = view3d()[3]
    space.shading.type = "MATERIAL"
    for _ in range(draws):
        draw()
        yield PREVIEW_PAUSE_SECONDS
    RESULTS["shading"] = space.shading.type


def steps():
    """Generator of the steps; yields the seconds to wait before going on."""
    bpy.context.preferences.view.show_splash = False
    setup.enable_addon()
    setup.clear_scene()
    import blender_scenes

    blender_scenes.sun_room(0.25, lightmap=True)
    in_view(bpy.ops.ed.undo_push, message="sun room")
    yield 0.5
    RESULTS["before_bake"] = data_state()
    yield from baked_room()
    RESULTS["after_bake"] = data_state()
    # What Adjust Last Operation and Repeat Last may run again (synchronously, the UI waiting):
    # the operators Blender keeps whose type has REGISTER (UNDO alone keeps them listed only).
    RESULTS["registered_after_bake"] = [op.bl_idname for op in bpy.context.window_manager.operators
                                        if "REGISTER" in op.bl_options]
    RESULTS["undo_status"] = in_view(bpy.ops.ed.undo)
    RESULTS["after_undo"] = data_state()
    yield from material_preview()
    RESULTS["after_material_preview"] = data_state()
    RESULTS["redo_status"] = in_view(bpy.ops.ed.redo)
    yield from material_preview()
    RESULTS["after_redo"] = data_state()
    add_rugs()
    in_view(bpy.ops.ed.undo_push, message="rugs")
    RESULTS["before_cancelled_bake"] = data_state()
    yield from cancelled_bake()
    RESULTS["after_cancelled_bake"] = data_state()
    RESULTS["cancelled_undo_status"] = in_view(bpy.ops.ed.undo)
    draw()
    RESULTS["after_cancelled_undo"] = data_state()


# The factory settings open the splash (Quick Setup) over the 3D view after this script runs.
bpy.context.preferences.view.show_splash = False
setup.run_steps_in_window(steps(), RESULTS, RESULTS_PATH, "BAKE_UNDO_WINDOW_OK")
