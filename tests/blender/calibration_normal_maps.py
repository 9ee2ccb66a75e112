"""Cycles calibration of normal maps: a tangent-space Normal Map node (an Image Texture of
bumps, Non-Color) on a UV-mapped plane under a sun (also at Strength 0.5, and as a Blender
Object Space map on the plane turned and tilted), a point and an area light, and on the floor
and walls of the open-topped room lit by an area light (indirect light between normal-mapped
surfaces); and a Bump node fed by an Image Texture of heights on the plane, under the sun and,
inverted at Strength 0.6, under the point light.

Each case also reports, as information, SHGI's Combined and DiffInd with the normal maps taken
(and bump maps) taken out of the exported scene: how far from Cycles a renderer that ignores
them is.

Run by tests/python/test_cycles_calibration.py; prints CALIBRATION_NORMAL_MAPS_DONE and writes
the per-case results as JSON (see calibration_common.py).
"""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import calibration_common as cal  # noqa: E402

import bpy  # noqa: E402
import numpy as np  # noqa: E402

SAMPLES = 512
# The bump image: BUMPS x BUMPS sine bumps over the UV square, slopes up to MAX_SLOPE.
IMAGE_SIZE = 128
BUMPS = 4
MAX_SLOPE = 0.8
# Texture repeats per metre of the surfaces.
UV_SCALE = 0.5


def bump_image(blender_space=False):
    """A tangent-space normal map of h = sin(2 pi B u) sin(2 pi B v) bumps, float, Non-Color;
    with `blender_space`, the same normals in Blender's own object-space convention (Y and Z
    negated) for a plane whose u and v run along its object's X and Y."""
    name = "bumps_blender" if blender_space else "bumps"
    image = bpy.data.images.get(name)
    if image is not None:
        return image
    image = bpy.data.images.new(name, IMAGE_SIZE, IMAGE_SIZE, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    t = (np.arange(IMAGE_SIZE) + 0.5) / IMAGE_SIZE * 2.0 * math.pi * BUMPS
    v, u = np.meshgrid(t, t, indexing="ij")  # rows are v (bottom first), columns u
    slope_u = MAX_SLOPE * np.cos(u) * np.sin(v)
    slope_v = MAX_SLOPE * np.sin(u) * np.cos(v)
    normal = np.stack([-slope_u, -slope_v, np.ones_like(u)], axis=-1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    if blender_space:
        normal[..., 1:] *= -1.0
    pixels = np.concatenate([0.5 * normal + 0.5, np.ones_like(u)[..., None]], axis=-1)
    image.pixels.foreach_set(pixels.astype(np.float32).ravel())
    image.pack()
    return image


# The height image of the Bump cases: h = 0.5 + HEIGHT_AMPLITUDE sin(2 pi B u) sin(2 pi B v) with
# HEIGHT_BUMPS periods per UV unit (one per metre at UV_SCALE 0.5: many pixels per bump, so
# Cycles' pixel-footprint differences and SHGI's texel differences see the same slope); at
# Distance 1 the surface slopes reach 2 pi B A UV_SCALE = 0.63.
HEIGHT_SIZE = 128
HEIGHT_BUMPS = 2
HEIGHT_AMPLITUDE = 0.1


def height_image():
    """The bump cases' height field as a float, Non-Color image (the same value in R, G, B)."""
    image = bpy.data.images.get("heights")
    if image is not None:
        return image
    image = bpy.data.images.new("heights", HEIGHT_SIZE, HEIGHT_SIZE, float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    t = (np.arange(HEIGHT_SIZE) + 0.5) / HEIGHT_SIZE * 2.0 * math.pi * HEIGHT_BUMPS
    v, u = np.meshgrid(t, t, indexing="ij")
    h = 0.5 + HEIGHT_AMPLITUDE * np.sin(u) * np.sin(v)
    pixels = np.stack([h, h, h, np.ones_like(h)], axis=-1)
    image.pixels.foreach_set(pixels.astype(np.float32).ravel())
    image.pack()
    return image


def bumped(name, color, strength=1.0, invert=False):
    """A Principled material (specular 0) whose Normal is a Bump node of the height image."""
    material = cal.principled(name, color)
    tree = material.node_tree
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = height_image()
    bump = tree.nodes.new("ShaderNodeBump")
    bump.invert = invert
    bump.inputs["Strength"].default_value = strength
    bump.inputs["Distance"].default_value = 1.0
    tree.links.new(texture.outputs["Color"], bump.inputs["Height"])
    tree.links.new(bump.outputs["Normal"], tree.nodes["Principled BSDF"].inputs["Normal"])
    return material


def normal_mapped(name, color, space="TANGENT"):
    """A Principled material (specular 0, as the room's) with the bump normal map, in tangent
    space or in Blender's object space."""
    material = cal.principled(name, color)
    tree = material.node_tree
    texture = tree.nodes.new("ShaderNodeTexImage")
    texture.image = bump_image(blender_space=space == "BLENDER_OBJECT")
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    normal_map.space = space
    normal_map.uv_map = "UVMap"
    tree.links.new(texture.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], tree.nodes["Principled BSDF"].inputs["Normal"])
    return material


def add_uvs(obj):
    """UVMap from the quad's own axes: u along its first edge, v along its second (metres x
    UV_SCALE)."""
    mesh = obj.data
    layer = mesh.uv_layers.new(name="UVMap")
    origin = mesh.vertices[0].co
    edge_u = (mesh.vertices[1].co - origin)
    edge_v = (mesh.vertices[3].co - origin)
    for loop in mesh.loops:
        p = mesh.vertices[loop.vertex_index].co - origin
        layer.data[loop.index].uv = (UV_SCALE * p.dot(edge_u.normalized()),
                                     UV_SCALE * p.dot(edge_v.normalized()))


def plane_scene(material=lambda: normal_mapped("plane", (0.8, 0.8, 0.8))):
    """The UV-mapped 6 m plane with the material `material()` makes (made after the reset, which
    removes materials) and the camera."""
    cal.reset_scene()
    add_uvs(cal.add_quad("plane", (-3, -3, 0), (6, 0, 0), (0, 6, 0), material()))
    cal.add_camera(location=(0.0, -3.2, 2.6), target=(0.0, 0.0, 0.0))


def add_sun():
    cal.add_light("SUN", (0.0, 0.0, 5.0), (math.radians(45), 0.0, math.radians(120)),
                  energy=3.0, angle=math.radians(2))


def plane_sun(name, tmpdir, results):
    plane_scene()
    add_sun()
    compare(name, ("DiffDir",), tmpdir, results)


def plane_half_strength(name, tmpdir, results):
    # The sun case with the Normal Map's Strength at 0.5: the blend between the normals.
    plane_scene()
    for node in bpy.data.materials["plane"].node_tree.nodes:
        if node.bl_idname == "ShaderNodeNormalMap":
            node.inputs["Strength"].default_value = 0.5
    add_sun()
    compare(name, ("DiffDir",), tmpdir, results)


def plane_blender_object_space(name, tmpdir, results):
    # The sun case with the bumps as a Blender Object Space map on the plane turned 40 degrees
    # about Z and tilted 15 degrees about X (the object's rotation turns the normals).
    cal.reset_scene()
    plane = cal.add_quad("plane", (-3, -3, 0), (6, 0, 0), (0, 6, 0),
                         normal_mapped("plane", (0.8, 0.8, 0.8), "BLENDER_OBJECT"))
    add_uvs(plane)
    plane.rotation_euler = (math.radians(15), 0.0, math.radians(40))
    cal.add_camera(location=(0.0, -3.2, 2.6), target=(0.0, 0.0, 0.0))
    add_sun()
    compare(name, ("DiffDir",), tmpdir, results)


def bump_sun(name, tmpdir, results):
    plane_scene(lambda: bumped("plane", (0.8, 0.8, 0.8)))
    add_sun()
    compare(name, ("DiffDir",), tmpdir, results)


def bump_point_inverted(name, tmpdir, results):
    plane_scene(lambda: bumped("plane", (0.8, 0.8, 0.8), strength=0.6, invert=True))
    cal.add_light("POINT", (-0.8, 0.5, 1.5), energy=300.0, shadow_soft_size=0.1)
    compare(name, ("DiffDir",), tmpdir, results)


def plane_point(name, tmpdir, results):
    plane_scene()
    cal.add_light("POINT", (-0.8, 0.5, 1.5), energy=300.0, shadow_soft_size=0.1)
    compare(name, ("DiffDir",), tmpdir, results)


def plane_area(name, tmpdir, results):
    plane_scene()
    cal.add_light("AREA", (1.0, -0.5, 1.6), (math.radians(30), 0.0, math.radians(60)),
                  shape="RECTANGLE", size=1.0, size_y=0.5, energy=300.0)
    compare(name, ("DiffDir",), tmpdir, results)


def room(name, tmpdir, results):
    cal.reset_scene(world_color=(0.5, 0.6, 0.8), world_strength=0.2)
    cal.add_room(material=normal_mapped)
    for wall in ("floor", "back", "left", "right"):
        add_uvs(bpy.data.objects[wall])
    cal.add_box("box", (0.4, 0.3, 0.45), (0.45, 0.45, 0.45),
                cal.principled("box", (0.6, 0.6, 0.8)))
    cal.add_camera(location=(0.0, -4.5, 1.4), target=(0.0, 0.0, 0.7))
    cal.add_light("AREA", (-0.4, -2.2, 3.0), (math.radians(35), 0.0, math.radians(-10)),
                  shape="RECTANGLE", size=1.2, size_y=0.6, energy=500.0)
    compare(name, ("DiffDir", "DiffInd"), tmpdir, results, samples=2 * SAMPLES)


def compare(name, passes, tmpdir, results, samples=SAMPLES):
    cal.compare(name, passes, samples, samples, tmpdir, results)
    results[name]["without_normal_maps"] = without_normal_maps(samples)
    print(f"   {name}: SHGI without normal maps: " + ", ".join(
        f"{p} {v:+.2f}% vs Cycles" for p, v in results[name]["without_normal_maps"].items()),
          flush=True)


def without_normal_maps(samples):
    """{pass: relative error vs Cycles in %} of SHGI with the exported normal maps removed
    (Cycles' means are those just stored by cal.compare)."""
    import shgi
    from shgi_blender.export import export_scene

    result = export_scene(bpy.context.evaluated_depsgraph_get(), bpy.context.scene)
    scene = result.scene
    for index, material in enumerate(scene.materials):
        material.normal_texture = -1
        material.bump_texture = -1
        scene.set_material(index, material)
    scene.commit()
    batches = []
    for batch in range(cal.BATCHES):
        settings = shgi.PathTracerSettings(samples=samples // cal.BATCHES, seed=batch,
                                           **cal.BOUNCES)
        passes = shgi.render_path_traced(scene, settings)
        batches.append({n: np.asarray(px, np.float64) for n, px in passes.items()})
    return {p: 100.0 * (cal.pass_mean(batches, p)[0] / cal.last_cycles_mean(p) - 1.0)
            for p in ("Combined", "DiffInd") if cal.last_cycles_mean(p) > 0.0}


CASES = {"normal_map_sun": plane_sun, "normal_map_half_strength": plane_half_strength,
         "normal_map_blender_object_space": plane_blender_object_space,
         "normal_map_point": plane_point,
         "normal_map_area": plane_area, "normal_map_room": room,
         "bump_map_sun": bump_sun, "bump_map_point_inverted": bump_point_inverted}

if __name__ == "__main__":
    cal.run_cases(CASES, "CALIBRATION_NORMAL_MAPS_DONE")
