"""Lightmap bake traps an artist hits, in background mode: the sun room of
examples/blender_scenes.py facing out, shared materials, a headless bake's log, lightmap nodes
without an image.

``blender -b --factory-startup --python-exit-code 1 --python bake_trap_checks.py --
<build python dir> <addon dir> <results json>``:
1. facing: the sun room built as the renderers have it (walls and floor facing out): its floor
   baked (Create UV Map) with the facing check's warning (in Blender's output, which
   tests/python/test_blender_bake.py reads) and the world's colour in its lightmap; the room
   built for bakes (lightmap=True, facing in): no warning, a lightmap holding the room's light;
   the room facing out baked with Bake Side "Facing the Scene": the floor's back is baked, as
   the floor of the room facing in (all three through a UV map Lightmap Pack lays out);
2. shared materials: all ten objects of the room facing in (nine share "plaster") baked with
   Show in Materials, Make Materials Single-User on: every object shows its own lightmap;
   the same with it off: only the objects with a material of their own;
3. a room that is one closed mesh (a cube, a box and a lamp inside, the camera inside): its
   normals out, the facing check names it; turned in, it does not; a box with its normals out
   seen from outside is never named; nor a facade facing the street with a room's furniture
   behind it (its back rays hit the furniture, but the camera and lamp see its front);
4. the images' nodes: a material whose lightmap image is gone, saved and opened again, has lost
   its lightmap nodes and shows its surface again (the load_post handler).
The bakes run as a farm's would (execute, background mode): their progress lines go to the same
output. Prints BAKE_TRAPS_OK.
"""

import json
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()
sys.path.insert(0, str(setup.REPO_ROOT / "examples"))
setup.enable_addon()

import bmesh  # noqa: E402
import bpy  # noqa: E402
import numpy as np  # noqa: E402
import blender_scenes  # noqa: E402
from shgi_blender.operators import facing_check  # noqa: E402

RESOLUTION, FACING_SAMPLES = 16, 64
FACING_UV_MAP = "BakeUV"
SHARED_RESOLUTION, SHARED_SAMPLES = 8, 2
LIGHTMAP_SUFFIX = "_shgi_lightmap"
TEXTURE_NODE = "SHGI Lightmap"


def select_only(*names):
    bpy.ops.object.select_all(action="DESELECT")
    for name in names:
        bpy.data.objects[name].select_set(True)
    bpy.context.view_layer.objects.active = bpy.data.objects[names[0]]


def build_room(lightmap):
    blender_scenes.build("sun_room", 0.25, lightmap=lightmap)
    setup.enable_addon()  # read_homefile keeps the add-on; make sure
    return bpy.context.scene


def bake(folder, *names, **arguments):
    select_only(*names)
    print(f"BAKE {folder}: {' '.join(names)}", flush=True)
    return sorted(bpy.ops.shgi.bake_lightmaps(output_folder=folder, **arguments))


def lightmap_mean(name):
    image = bpy.data.images[f"{name}{LIGHTMAP_SUFFIX}"]
    pixels = np.empty(len(image.pixels), np.float32)
    image.pixels.foreach_get(pixels)
    return pixels.reshape(-1, 4)[:, :3].mean(axis=0).tolist()


def facing_checks(tmpdir, results):
    world = list(blender_scenes.SKY)
    results["world_color"] = world
    for case, lightmap, side in (("outward", False, "FRONT"), ("inward", True, "FRONT"),
                                 ("outward_facing_scene", False, "FACING_SCENE")):
        build_room(lightmap)
        # A UV map that Lightmap Pack lays out alike for the floor facing either way.
        status = bake(os.path.join(tmpdir, case), "floor", uv_map=FACING_UV_MAP, create_uv=True,
                      bake_side=side, resolution=RESOLUTION, samples=FACING_SAMPLES)
        results[case] = {"status": status, "floor_mean": lightmap_mean("floor")}


def add_cube(name, size, location, inward=False):
    mesh = bpy.data.meshes.new(name)
    shape = bmesh.new()
    bmesh.ops.create_cube(shape, size=size)
    if inward:
        bmesh.ops.reverse_faces(shape, faces=shape.faces)
    shape.to_mesh(mesh)
    shape.free()
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_wall(name, width, height, location):
    """A one-quad wall facing -Y (towards the street) at `location`."""
    mesh = bpy.data.meshes.new(name)
    w, h = width / 2, height / 2
    mesh.from_pydata([(-w, 0, -h), (w, 0, -h), (w, 0, h), (-w, 0, h)], [], [(0, 1, 2, 3)])
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def closed_room_checks(results):
    """What facing_away() names in a 4 m closed cube room with a box and a point lamp inside,
    the camera inside too: the room's normals out, then in; and a box outside every viewer."""
    for case, inward, inside in (("closed_room_out", False, True),
                                 ("closed_room_in", True, True),
                                 ("box_seen_from_outside", False, False),
                                 ("facade", False, False)):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        setup.enable_addon()
        scene = bpy.context.scene
        objects = [add_cube("box", 0.5, (0.5, -0.5, -1.75))]
        if inside:
            objects.append(add_cube("room", 4.0, (0.0, 0.0, 0.0), inward=inward))
        if case == "facade":  # a 4 x 3 m facade with a wardrobe 0.5 m behind it
            objects = [add_wall("facade", 4.0, 3.0, (0.0, 0.0, 0.0)),
                       add_cube("wardrobe", 3.5, (0.0, 2.25, 0.0))]
        lamp = bpy.data.objects.new("lamp", bpy.data.lights.new("lamp", "POINT"))
        lamp.location = (0.0, 0.0, 1.5) if inside else (3.0, -4.0, 2.0)
        camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
        camera.location = (1.2, 1.2, 0.5) if inside else (1.0, -6.0, 1.0)
        for obj in (lamp, camera):
            scene.collection.objects.link(obj)
        scene.camera = camera
        bpy.context.view_layer.update()
        results[case] = facing_check.facing_away(scene, bpy.context.evaluated_depsgraph_get(),
                                                 objects)


def material_view(obj):
    """The object's material and what its lightmap nodes show (None without them)."""
    material = obj.material_slots[0].material
    texture = material.node_tree.nodes.get(TEXTURE_NODE)
    return {"material": material.name,
            "image": None if texture is None else getattr(texture.image, "name", "")}


def shared_material_checks(tmpdir, results):
    names = sorted(obj.name for obj in bpy.data.objects if obj.type == "MESH")
    for case, single_user in (("single_user", True), ("left_shared", False)):
        build_room(True)
        status = bake(os.path.join(tmpdir, case), *names, create_uv=True, hook_up_material=True,
                      single_user_materials=single_user, resolution=SHARED_RESOLUTION,
                      samples=SHARED_SAMPLES)
        results[case] = {"status": status, "objects": {
            name: material_view(bpy.data.objects[name]) for name in names}}


def imageless_node_checks(tmpdir, results):
    """After the single-user bake: the floor's material loses its image, is saved and opened."""
    build_room(True)
    bake(os.path.join(tmpdir, "imageless"), "floor", hook_up_material=True,
         resolution=SHARED_RESOLUTION, samples=SHARED_SAMPLES)
    material = bpy.data.objects["floor"].material_slots[0].material.name
    bpy.data.images.remove(bpy.data.images[f"floor{LIGHTMAP_SUFFIX}"])
    path = os.path.join(tmpdir, "imageless.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    tree = bpy.data.materials[material].node_tree
    results["imageless"] = {
        "material": material,
        "nodes": sorted(node.name for node in tree.nodes if node.name.startswith("SHGI")),
        "surface_from": tree.get_output_node("ALL").inputs["Surface"].links[0].from_node.name}


def main():
    tmpdir = tempfile.mkdtemp(prefix="shgi_bake_traps_")
    results = {"names": None}
    facing_checks(tmpdir, results)
    shared_material_checks(tmpdir, results)
    closed_room_checks(results)
    imageless_node_checks(tmpdir, results)
    with open(setup.results_path("bake_traps.json"), "w") as out:
        json.dump(results, out, indent=1)
    print("BAKE_TRAPS_OK")


main()
