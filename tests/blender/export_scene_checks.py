"""Blender → shgi.Scene export of a scene built from scratch, checked field by field.

Run by tests/python/test_blender_export.py. The export runs inside a minimal RenderEngine's
render() on F12's render depsgraph (as the SHGI engine will), and once more on the viewport
depsgraph. Prints EXPORT_SCENE_OK when every check passed.
"""

import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402

TOLERANCE = 1e-5           # float32 round trips of Blender's float properties
TEXEL_TOLERANCE = 1e-4     # sRGB decode of byte texels, float32
# shgi.Material fields in Blender 3.4's units (setup.set_principled_inputs sets any version's).
PRINCIPLED = {"base_color": (0.2, 0.4, 0.6), "metallic": 0.3, "specular": 0.7,
              "roughness": 0.25, "transmission": 0.1, "ior": 1.33,
              "emission_color": (0.5, 0.25, 0.125), "emission_strength": 2.0}
EMISSION_COLOR, EMISSION_STRENGTH = (1.0, 0.5, 0.25), 3.0
DIFFUSE_COLOR = (0.7, 0.6, 0.5, 1.0)
WORLD_COLOR, WORLD_STRENGTH = (0.1, 0.2, 0.3), 2.0
DUPLICATE_X = (10.0, 14.0, 18.0)
RESULTS = []


def add_mesh_object(name, mesh, location=(0.0, 0.0, 0.0), materials=()):
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    for material in materials:
        obj.data.materials.append(material)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def plane_mesh(name, half_size=1.0):
    mesh = bpy.data.meshes.new(name)
    h = half_size
    mesh.from_pydata([(-h, -h, 0), (h, -h, 0), (h, h, 0), (-h, h, 0)], [], [(0, 1, 2, 3)])
    mesh.uv_layers.new(name="UVMap")
    return mesh


def cube_mesh(name):
    bpy.ops.mesh.primitive_cube_add(size=2.0)
    obj = bpy.context.active_object
    obj.data.name = name
    mesh = obj.data
    bpy.data.objects.remove(obj, do_unlink=True)
    return mesh


def node_material(name, shader_idname, inputs):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    for node in [n for n in nodes if n.bl_idname != "ShaderNodeOutputMaterial"]:
        nodes.remove(node)
    shader = nodes.new(shader_idname)
    for socket, value in inputs.items():
        shader.inputs[socket].default_value = value
    output = nodes["Material Output"]
    links.new(shader.outputs[0], output.inputs["Surface"])
    return material, shader


def principled_material(name, **fields):
    """A Principled BSDF material with shgi.Material `fields` (Blender 3.4's units)."""
    material, shader = node_material(name, "ShaderNodeBsdfPrincipled", {})
    setup.set_principled_inputs(shader, **fields)
    return material, shader


def textured_material():
    """Principled whose Base Color is an Image Texture of a 2 x 2 sRGB byte image."""
    material, principled = principled_material("Textured", base_color=(0.3, 0.3, 0.3))
    image = bpy.data.images.new("Checker", 2, 2)
    image.pixels[:] = [0.0, 0.2, 0.5, 1.0, 1.0, 0.8, 0.6, 1.0,
                       0.1, 0.3, 0.9, 1.0, 0.7, 0.0, 0.4, 1.0]
    texture = material.node_tree.nodes.new("ShaderNodeTexImage")
    texture.image = image
    material.node_tree.links.new(texture.outputs["Color"], principled.inputs["Base Color"])
    return material, image


def add_light(name, light_type, location, **properties):
    light = bpy.data.lights.new(name, light_type)
    for key, value in properties.items():
        setattr(light, key, value)
    obj = bpy.data.objects.new(name, light)
    obj.location = location
    obj.rotation_euler = (0.3, 0.2, 0.1)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def nan_object():
    mesh = plane_mesh("BrokenMesh")
    mesh.vertices[0].co = (float("nan"), 0.0, 0.0)
    return add_mesh_object("Broken", mesh, (0, 0, -20))


def inf_object():
    """A vertex an artist typed inf into (Blender stores its largest float, 3.4e+38)."""
    mesh = plane_mesh("InfMesh")
    mesh.vertices[2].co = (0.0, float("inf"), 0.0)
    return add_mesh_object("Infinite", mesh, (0, 0, -30))


def zero_scale_collection_instancer():
    """An Empty scaled to 0 instancing a collection whose object is in no scene."""
    collection = bpy.data.collections.new("Instanced")
    collection.objects.link(bpy.data.objects.new("InstancedSource", plane_mesh("SourceMesh")))
    instancer = bpy.data.objects.new("FlatInstancer", None)
    instancer.instance_type = "COLLECTION"
    instancer.instance_collection = collection
    instancer.location, instancer.scale = (0, -40, 0), (0.0, 0.0, 0.0)
    bpy.context.scene.collection.objects.link(instancer)


def build_scene():
    """Every case of the issue in one scene; returns what the checks need."""
    setup.clear_scene()
    principled, _ = principled_material("Principled", **PRINCIPLED)
    cube = add_mesh_object("ModCube", cube_mesh("CubeMesh"), materials=[principled])
    array = cube.modifiers.new("Array", "ARRAY")
    array.count, array.relative_offset_displace = 2, (1.0, 0.0, 0.0)
    textured, image = textured_material()
    shared = plane_mesh("SharedPlane")
    shared.materials.append(textured)
    for index, x in enumerate(DUPLICATE_X):
        add_mesh_object(f"Dup.{index}", shared, (x, 0.0, 0.0))
    emission, _ = node_material("Glow", "ShaderNodeEmission",
                                {"Color": (*EMISSION_COLOR, 1.0), "Strength": EMISSION_STRENGTH})
    add_mesh_object("Emitter", plane_mesh("EmitterMesh"), (0, 10, 3), [emission])
    glossy, _ = node_material("Glossy", "ShaderNodeBsdfGlossy", {})
    add_mesh_object("Shiny", plane_mesh("ShinyMesh"), (0, -10, 0), [glossy])
    add_mesh_object("Bare", plane_mesh("BareMesh"), (0, 20, 0))
    add_mesh_object("HiddenCube", cube_mesh("HiddenMesh"), (0, 0, 30)).hide_render = True
    diffuse, _ = node_material("Matte", "ShaderNodeBsdfDiffuse", {"Color": DIFFUSE_COLOR})
    add_mesh_object("ViewportHidden", plane_mesh("ViewportHiddenMesh"), (0, 30, 0),
                    [diffuse]).hide_viewport = True
    add_mesh_object("Flat", plane_mesh("FlatMesh"), (0, 40, 0)).scale = (1.0, 1.0, 0.0)
    nan_object()
    inf_object()
    zero_scale_collection_instancer()
    text = bpy.data.objects.new("Label", bpy.data.curves.new("LabelText", "FONT"))
    text.location = (30, 0, 0)
    bpy.context.scene.collection.objects.link(text)
    blob = bpy.data.objects.new("Blob", bpy.data.metaballs.new("BlobData"))
    blob.data.elements.new().radius = 1.0
    blob.location = (40, 0, 0)
    bpy.context.scene.collection.objects.link(blob)
    add_light("PointLight", "POINT", (1, 2, 3), energy=100.0, shadow_soft_size=0.3,
              color=(1.0, 0.9, 0.8))
    add_light("SpotLight", "SPOT", (2, 2, 3), energy=50.0, spot_size=0.8, spot_blend=0.3,
              shadow_soft_size=0.1)
    add_light("SunLight", "SUN", (0, 0, 9), energy=3.0, angle=0.1)
    add_light("RectLight", "AREA", (3, 2, 3), energy=20.0, shape="RECTANGLE", size=2.0,
              size_y=0.5)
    add_light("DiskLight", "AREA", (4, 2, 3), energy=30.0, shape="DISK", size=1.5)
    add_light("WindowPortal", "AREA", (5, 2, 3), energy=10.0, size=1.0).data.cycles.is_portal = True
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("CameraData"))
    camera.location = (0.0, -30.0, 10.0)
    bpy.context.scene.collection.objects.link(camera)
    bpy.context.scene.camera = camera
    world = bpy.context.scene.world
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*WORLD_COLOR, 1.0)
    background.inputs["Strength"].default_value = WORLD_STRENGTH
    return image


class ExportProbeEngine(bpy.types.RenderEngine):
    """Exports F12's render depsgraph, as the SHGI render engine will."""

    bl_idname = "SHGI_EXPORT_PROBE"
    bl_label = "SHGI export probe"

    def render(self, depsgraph):
        try:
            RESULTS.append(export_scene(depsgraph, report=self.report))
        except Exception:  # reported by the checks: a failed render would hide it
            RESULTS.append(traceback.format_exc())


def export_with_render_depsgraph():
    bpy.utils.register_class(ExportProbeEngine)
    scene = bpy.context.scene
    scene.render.engine = ExportProbeEngine.bl_idname
    scene.render.resolution_x, scene.render.resolution_y = 32, 24
    bpy.ops.render.render()
    bpy.utils.unregister_class(ExportProbeEngine)
    if len(RESULTS) != 1 or isinstance(RESULTS[0], str):
        raise AssertionError(f"export in render() failed: {RESULTS}")
    return RESULTS[0]


def instances_by_name(scene):
    return {instance.name: instance for instance in scene.instances}


def check_geometry(result):
    scene = result.scene
    instances = instances_by_name(scene)
    expected = {"ModCube", "Dup.0", "Dup.1", "Dup.2", "Emitter", "Shiny", "Bare",
                "ViewportHidden", "Label", "Blob"}
    if set(instances) != expected:
        raise AssertionError(f"instances {sorted(instances)} != {sorted(expected)}")
    meshes = scene.meshes
    cube = meshes[instances["ModCube"].mesh_id]
    # Two flat-shaded cubes (Array modifier): 6 faces x 4 split vertices, 12 triangles each.
    if (len(cube.positions), len(cube.triangles)) != (48, 24):
        raise AssertionError(f"array cube: {len(cube.positions)} vertices, "
                             f"{len(cube.triangles)} triangles; expected 48, 24")
    setup.check_close("array cube x extent", (cube.positions[:, 0].min(),
                                              cube.positions[:, 0].max()), (-1.0, 3.0), TOLERANCE)
    duplicate_meshes = {instances[f"Dup.{i}"].mesh_id for i in range(3)}
    if len(duplicate_meshes) != 1 or meshes[duplicate_meshes.pop()].name != "SharedPlane":
        raise AssertionError("linked duplicates must share one mesh named SharedPlane")
    # 9 meshes: FlatMesh is converted, but its instance (scale 0: singular) is skipped.
    if len(meshes) != 9 or result.stats.meshes != 9 or result.stats.instances != 10:
        raise AssertionError(f"{len(meshes)} meshes {[m.name for m in meshes]}, instances "
                             f"{[i.name for i in scene.instances]}, stats {result.stats}")
    for name in ("Label", "Blob"):
        if len(meshes[instances[name].mesh_id].triangles) == 0:
            raise AssertionError(f"the non-mesh object {name} exported no triangles")
    setup.check_close("Dup.1 translation", instances["Dup.1"].world_from_object[:3, 3],
                      (DUPLICATE_X[1], 0.0, 0.0), TOLERANCE)


def check_materials(result, image):
    scene = result.scene
    materials = {material.name: material for material in scene.materials}
    p = materials["Principled"]
    for field, expected in PRINCIPLED.items():
        setup.check_close(f"Principled {field}", getattr(p, field), expected, TOLERANCE)
    glow = materials["Glow"]
    setup.check_close("Glow emission", (*glow.emission_color, glow.emission_strength),
                      (*EMISSION_COLOR, EMISSION_STRENGTH), TOLERANCE)
    setup.check_close("Glow base_color", glow.base_color, (0, 0, 0), 0.0)
    matte = materials["Matte"]
    setup.check_close("Matte", (*matte.base_color, matte.specular), (*DIFFUSE_COLOR[:3], 0.0),
                      TOLERANCE)
    fallback = materials["SHGI fallback"]
    setup.check_close("fallback", (*fallback.base_color, fallback.roughness),
                      (0.8, 0.8, 0.8, 0.5), TOLERANCE)
    instances = instances_by_name(scene)
    fallback_id = [m.name for m in scene.materials].index(fallback.name)
    for name in ("Shiny", "Bare"):
        used = set(scene.meshes[instances[name].mesh_id].material_indices.tolist())
        if used != {fallback_id}:
            raise AssertionError(f"{name} uses materials {used}, not the fallback {fallback_id}")
    check_texture(scene, materials["Textured"], image)


def check_texture(scene, material, image):
    setup.check_close("Textured base_color", material.base_color, (1, 1, 1), 0.0)
    texture = scene.textures[material.base_color_texture]
    encoded = np.array(image.pixels[:], np.float32).reshape(2, 2, 4)
    expected = encoded.copy()
    expected[:, :, :3] = shgi.linear_from_srgb(encoded[:, :, :3])
    setup.check_close("texels", texture.pixels.ravel(), expected.ravel(), TEXEL_TOLERANCE)


def check_lights(result):
    lights = {light.name: light for light in result.scene.lights}
    point, spot, sun = lights["PointLight"], lights["SpotLight"], lights["SunLight"]
    rect, disk = lights["RectLight"], lights["DiskLight"]
    setup.check_close("point", (point.power, point.radius, *point.color),
                      (100.0, 0.3, 1.0, 0.9, 0.8), TOLERANCE)
    setup.check_close("spot", (spot.power, spot.spot_size, spot.spot_blend, spot.radius),
                      (50.0, 0.8, 0.3, 0.1), TOLERANCE)
    setup.check_close("sun", (sun.strength, sun.angle), (3.0, 0.1), TOLERANCE)
    setup.check_close("rect", (rect.power, rect.size_x, rect.size_y),
                      (setup.native_area_power(20.0), 2.0, 0.5), TOLERANCE)
    setup.check_close("disk", (disk.power, disk.size_x, disk.size_y),
                      (setup.native_area_power(30.0), 1.5, 1.5), TOLERANCE)
    if (rect.shape, disk.shape, sun.type) != (shgi.AreaShape.RECTANGLE, shgi.AreaShape.DISK,
                                              shgi.LightType.SUN):
        raise AssertionError(f"light enums: {rect.shape}, {disk.shape}, {sun.type}")
    if not lights["WindowPortal"].portal or rect.portal:
        raise AssertionError("cycles.is_portal was not exported as Light.portal")
    matrix = np.array(bpy.data.objects["PointLight"].matrix_world)
    setup.check_close("point world_from_light", point.world_from_light.ravel(), matrix.ravel(),
                      TOLERANCE)
    if not result.scene.has_camera or result.scene.camera.resolution_x != 32:
        raise AssertionError("the scene camera was not exported at the render size")
    world = result.scene.world
    setup.check_close("world", (*world.color, world.strength), (*WORLD_COLOR, WORLD_STRENGTH),
                      TOLERANCE)


def check_warnings(result):
    expected = {"'Bare' has no material", "'Glossy'", "'Broken'", "'Flat'"}
    for fragment in expected:
        if not any(fragment in message for message in result.warnings):
            raise AssertionError(f"no warning mentions {fragment!r}: {result.warnings}")
    if result.stats.skipped_objects != 4:
        raise AssertionError(f"skipped_objects = {result.stats.skipped_objects}, expected 4")
    check_named_refusals(result)


def check_named_refusals(result):
    """The inf vertex names its object, vertex, coordinate and fix; the instancer scaled to 0
    is named (not the object it instances) with its scale."""
    expected = {
        "Infinite": "object 'Infinite': mesh 'InfMesh': vertex 2 has y = inf; SHGI places "
                    "coordinates within ±1e+12 m: move the vertex back (Edit Mode, Sidebar > "
                    "Item > Vertex) or fix the modifier or geometry nodes that put it there",
        "FlatInstancer": "object 'FlatInstancer': its scale is 0 (world scale (0.0, 0.0, 0.0)), "
                         "which flattens every instance it makes; give every axis a non-zero "
                         "scale (Object Properties > Transform > Scale, of it or of its parents)",
    }
    for name, message in expected.items():
        if f"{message}; skipped" not in result.warnings:
            raise AssertionError(f"no warning {message!r}: {result.warnings}")
        if name not in result.skipped:
            raise AssertionError(f"{name} is not among the skipped objects {result.skipped}")
    if any("InstancedSource" in message for message in result.warnings) or (
            "InstancedSource" in result.skipped):
        raise AssertionError(f"the instanced object was blamed: {result.warnings}")


def check_ray_hits(result):
    scene = result.scene
    scene.commit()
    origins = np.array([[DUPLICATE_X[1] + 0.3, 0.2, 5.0], [0.0, 10.0, 5.0]], np.float32)
    hits = scene.intersect(origins, np.array([[0, 0, -1.0], [0, 0, -1.0]], np.float32))
    setup.check_close("ray t", hits["t"], (5.0, 2.0), TOLERANCE)
    names = [scene.instances[i].name for i in hits["instance_id"]]
    if names != ["Dup.1", "Emitter"]:
        raise AssertionError(f"rays hit {names}")
    emissive = scene.emissive_triangles()
    emitter_rows = emissive["instance_id"] == hits["instance_id"][1]
    if emitter_rows.sum() != 2:
        raise AssertionError(f"{emitter_rows.sum()} emissive triangles on Emitter, expected 2")
    setup.check_close("emitter radiance", emissive["radiance"][emitter_rows].ravel(),
                      np.tile(np.array(EMISSION_COLOR) * EMISSION_STRENGTH, 2), TOLERANCE)


def check_viewport_depsgraph():
    result = export_scene(bpy.context.evaluated_depsgraph_get(), for_render=True)
    names = set(instances_by_name(result.scene))
    if "HiddenCube" in names or "ViewportHidden" in names or "ModCube" not in names:
        raise AssertionError(f"viewport export instances: {sorted(names)}")


def check_tiny_scale_instancer():
    """A collection instance scaled by 1e-17 on x (not 0): the commit refuses the copy it makes, and
    its message names the instancer; the instanced object, also in the scene, keeps its name
    (the instance a bake of it picks)."""
    setup.clear_scene()
    source = add_mesh_object("InstancedSource", plane_mesh("SourceMesh"))
    collection = bpy.data.collections.new("Instanced")
    collection.objects.link(source)
    instancer = bpy.data.objects.new("TinyInstancer", None)
    instancer.instance_type = "COLLECTION"
    instancer.instance_collection = collection
    instancer.location, instancer.scale = (0, -40, 0), (1e-17, 1.0, 1.0)
    bpy.context.scene.collection.objects.link(instancer)
    result = export_scene(bpy.context.evaluated_depsgraph_get(), for_render=True)
    names = sorted(instance.name for instance in result.scene.instances)
    if names != ["InstancedSource", "InstancedSource (instanced by TinyInstancer)"]:
        raise AssertionError(f"instances {names}")
    try:
        result.scene.commit()
    except ValueError as error:
        if "'InstancedSource (instanced by TinyInstancer)'" not in str(error):
            raise AssertionError(f"the commit's refusal does not name the instancer: {error}")
    else:
        raise AssertionError("a copy shrunk by 1e17 was committed")


def check_triangle_arrays():
    """The triangles' vertices and material indices read from Blender's stored arrays (4.x/5.x)
    equal the loop triangles' own, on quads, an n-gon and triangles with mixed material slots,
    and on a mesh that never had a material index set (no material_index attribute)."""
    from shgi_blender.export import mesh as mesh_export

    mixed = bpy.data.meshes.new("MixedFaces")
    mixed.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0), (2, 1, 0),
                       (3, 0.5, 0), (2.5, 2, 0), (1.5, 2.5, 0)],
                      [], [(0, 1, 2, 3), (1, 4, 5, 2), (4, 6, 5), (2, 5, 7, 8, 3)])
    mixed.polygons.foreach_set("material_index", np.array([2, 0, 1, 2], dtype=np.int32))
    plain = plane_mesh("NoMaterialIndex")
    for mesh in (mixed, plain):
        mesh.calc_loop_triangles()
        triangles = mesh.loop_triangles
        loops = np.empty(len(triangles) * 3, np.int32)
        triangles.foreach_get("loops", loops)
        vertices, materials = mesh_export._triangle_vertices_and_materials(mesh, loops)
        expected_vertices = np.empty(len(triangles) * 3, np.int32)
        triangles.foreach_get("vertices", expected_vertices)
        expected_materials = np.empty(len(triangles), np.int32)
        triangles.foreach_get("material_index", expected_materials)
        if (vertices.dtype != np.int32 or materials.dtype != np.int32
                or not np.array_equal(vertices, expected_vertices)
                or not np.array_equal(materials, expected_materials)):
            raise AssertionError(f"{mesh.name}: vertices {vertices.tolist()} materials "
                                 f"{materials.tolist()}; the loop triangles' "
                                 f"{expected_vertices.tolist()} {expected_materials.tolist()}")
        if mesh is mixed and sorted(set(materials.tolist())) != [0, 1, 2]:
            raise AssertionError(f"MixedFaces: slots {materials.tolist()}, expected 0, 1 and 2")


def main():
    check_triangle_arrays()
    image = build_scene()
    result = export_with_render_depsgraph()
    check_geometry(result)
    check_materials(result, image)
    check_lights(result)
    check_warnings(result)
    check_ray_hits(result)
    check_viewport_depsgraph()
    check_tiny_scale_instancer()
    print("stats:", result.stats)
    print("EXPORT_SCENE_OK")


main()
