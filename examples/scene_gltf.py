"""Writes a shgi.Scene of examples/scenes.py as a glTF file, for what needs a scene *file*: farm
bakes (shgi.farm sends the file to its workers), ``python -m shgi bake``.

What glTF holds of it: the meshes (one UV map, written as TEXCOORD_0, so that shgi.load_gltf
names it "UVMap"), the instances, each material's base colour and roughness, sun and point
lights (KHR_lights_punctual, in the units shgi.load_gltf's default "SPEC" mode reads back). Not
written: area lights and portals (glTF has none) and the world (glTF has none; the loader's
default world lights the file instead).

Axes: shgi scenes are Blender's Z up, glTF is Y up. shgi.load_gltf turns a glTF point p into
C p and a node's matrix M into C M C^T (meshes) or C M (lights), C = blender_from_gltf; this
writer applies the inverses, C^T p, C^T W C and C^T L.
"""

import base64
import json
import math
import struct

import numpy as np

import shgi

# shgi.load_gltf's blender_from_gltf: glTF +X -> +X, +Y -> +Z, +Z -> -Y.
BLENDER_FROM_GLTF = np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], float)
# glTF's luminous efficacy of its physically based light units (lm/W), as the loader reads them.
PBR_WATTS_TO_LUMENS = 683.0
FLOAT, UNSIGNED_INT = 5126, 5125


def write_gltf(scene, path, uv_set="LightmapUV"):
    """Writes `scene` (a shgi.Scene) to `path` (.gltf, buffers embedded); `uv_set`, the UV map
    written as TEXCOORD_0 where a mesh has it. Returns `path`."""
    c_t = BLENDER_FROM_GLTF.T
    blob = bytearray()
    views, accessors, meshes, nodes, lights = [], [], [], [], []

    def add(array, kind, component):
        array = np.ascontiguousarray(array)
        offset = len(blob)
        blob.extend(array.tobytes())
        blob.extend(b"\0" * (-len(blob) % 4))
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": array.nbytes})
        accessor = {"bufferView": len(views) - 1, "componentType": component,
                    "count": len(array), "type": kind}
        if kind == "VEC3":
            accessor["min"], accessor["max"] = array.min(0).tolist(), array.max(0).tolist()
        accessors.append(accessor)
        return len(accessors) - 1

    for mesh in scene.meshes:
        positions = np.asarray(mesh.positions, np.float64) @ c_t[:3, :3].T
        attributes = {"POSITION": add(positions.astype(np.float32), "VEC3", FLOAT)}
        if uv_set in mesh.uv_sets:
            uv = np.array(mesh.uv_sets[uv_set], np.float32)
            uv[:, 1] = 1.0 - uv[:, 1]  # glTF's v runs down the image
            attributes["TEXCOORD_0"] = add(uv, "VEC2", FLOAT)
        materials = np.asarray(mesh.material_indices)
        primitives = []
        for material in np.unique(materials):
            triangles = np.asarray(mesh.triangles, np.uint32)[materials == material]
            primitives.append({"attributes": attributes, "material": int(material),
                               "indices": add(triangles.ravel(), "SCALAR", UNSIGNED_INT)})
        meshes.append({"name": mesh.name, "primitives": primitives})
    for inst in scene.instances:
        world = c_t @ np.asarray(inst.world_from_object, float) @ BLENDER_FROM_GLTF
        nodes.append({"name": inst.name, "mesh": int(inst.mesh_id),
                      "matrix": world.T.ravel().tolist()})
    for light in scene.lights:
        source = _gltf_light(light)
        if source is None:
            continue
        lights.append(source)
        world = c_t @ np.asarray(light.world_from_light, float)
        nodes.append({"name": light.name, "matrix": world.T.ravel().tolist(),
                      "extensions": {"KHR_lights_punctual": {"light": len(lights) - 1}}})
    document = {
        "asset": {"version": "2.0", "generator": "SHGI examples/scene_gltf.py"},
        "scene": 0,
        "scenes": [{"nodes": list(range(len(nodes)))}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": [_gltf_material(material) for material in scene.materials],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(bytes(blob)).decode()}],
    }
    if lights:
        document["extensionsUsed"] = ["KHR_lights_punctual"]
        document["extensions"] = {"KHR_lights_punctual": {"lights": lights}}
    with open(path, "w", encoding="utf-8") as file:
        json.dump(document, file)
    return path


def _gltf_material(material):
    return {"name": material.name, "pbrMetallicRoughness": {
        "baseColorFactor": [*map(float, material.base_color), 1.0],
        "metallicFactor": 0.0, "roughnessFactor": float(material.roughness)}}


def _gltf_light(light):
    """The KHR_lights_punctual light of a sun or point light; None for the others."""
    color = [float(v) for v in light.color]
    if light.type == shgi.LightType.SUN:
        return {"name": light.name, "type": "directional", "color": color,
                "intensity": float(light.strength) * PBR_WATTS_TO_LUMENS}
    if light.type == shgi.LightType.POINT:
        return {"name": light.name, "type": "point", "color": color,
                "intensity": float(light.power) * PBR_WATTS_TO_LUMENS / (4.0 * math.pi)}
    return None
