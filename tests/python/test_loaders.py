"""Tests of shgi.load_gltf and shgi.load_obj: small files written into tmp_path, loaded, committed
and traced; expected values follow the conventions in native/io/gltf_loader.h and obj_loader.h
(Y-up -> Z-up as (x, y, z) -> (x, -z, y), glTF v -> 1 - v, glTF light units / 683 lm/W).
"""

import base64
import json
import math
import struct
import threading

import numpy as np
import pytest

import shgi

# Blender's glTF importer: PBR_WATTS_TO_LUMENS
# (io_scene_gltf2/blender/com/gltf2_blender_conversion.py).
PBR_WATTS_TO_LUMENS = 683.0


def gltf_document(indices=(0, 1, 2, 0, 2, 3)):
    """A floor quad at glTF height y = 2 (Blender z = 2) facing up, a point light, a camera."""
    positions = [-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1]
    uvs = [0, 0, 1, 0, 1, 1, 0, 1]
    data = (struct.pack("<12f", *positions) + struct.pack("<8f", *uvs)
            + struct.pack("<6H", *indices))
    return {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "Floor", "mesh": 0, "translation": [0, 2, 0]},
            {"name": "Lamp", "translation": [0, 5, 0],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "Cam", "camera": 0, "translation": [0, 3, 6]},
        ],
        "cameras": [{"type": "perspective",
                     "perspective": {"yfov": 0.6, "aspectRatio": 2.0, "znear": 0.05}}],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"name": "Lamp", "type": "point", "intensity": PBR_WATTS_TO_LUMENS}]}},
        "materials": [{"name": "Green",
                       "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.7, 0.2, 1.0],
                                                "metallicFactor": 0.0, "roughnessFactor": 0.4}}],
        "meshes": [{"name": "Quad", "primitives": [
            {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
        ],
        "buffers": [{"byteLength": len(data),
                     "uri": "data:application/octet-stream;base64,"
                            + base64.b64encode(data).decode()}],
    }


def write_gltf(path, document):
    path.write_text(json.dumps(document))
    return path


def trace_down(scene, x, y):
    """Distance from (x, y, 10) straight down to the first hit, or None."""
    hits = scene.intersect(np.array([[x, y, 10.0]], np.float32),
                           np.array([[0.0, 0.0, -1.0]], np.float32))
    if not hits["hit"][0]:
        return None
    return float(hits["t"][0])


# --- glTF ---------------------------------------------------------------------------------------

def test_load_gltf_counts_materials_lights_and_a_ray_hit(tmp_path):
    scene = shgi.load_gltf(write_gltf(tmp_path / "scene.gltf", gltf_document()))
    assert len(scene.meshes) == 1 and len(scene.instances) == 1
    assert len(scene.materials) == 1 and len(scene.lights) == 1

    green = scene.materials[0]
    assert green.name == "Green"
    np.testing.assert_allclose(np.asarray(green.base_color), [0.1, 0.7, 0.2], rtol=1e-6)
    assert green.roughness == pytest.approx(0.4)

    lamp = scene.lights[0]
    assert lamp.name == "Lamp"
    assert lamp.power == pytest.approx(4 * math.pi)  # 683 cd -> 4 pi W
    np.testing.assert_allclose(np.asarray(lamp.world_from_light)[:3, 3], [0, 0, 5], atol=1e-6)

    scene.commit()
    assert trace_down(scene, 0.5, 0.5) == pytest.approx(8.0)  # floor at Blender z = 2
    assert trace_down(scene, 3.0, 0.0) is None


def two_material_document(second_has_normals):
    """gltf_document's floor as one mesh of two primitives (as Blender exports a mesh with two
    material slots): the first triangle Green with normals and UVs, the second Red with no UVs
    and, unless `second_has_normals`, no normals."""
    document = gltf_document()
    positions = [-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1]
    data = (struct.pack("<12f", *positions) + struct.pack("<12f", *[0, 1, 0] * 4)
            + struct.pack("<8f", 0, 0, 1, 0, 1, 1, 0, 1) + struct.pack("<6H", 0, 1, 2, 0, 2, 3))
    document["buffers"] = [{"byteLength": len(data), "uri": "data:application/octet-stream;"
                            "base64," + base64.b64encode(data).decode()}]
    document["bufferViews"] = [{"buffer": 0, "byteOffset": o, "byteLength": n}
                               for o, n in ((0, 48), (48, 48), (96, 32), (128, 6), (134, 6))]
    document["accessors"] = [
        {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5123, "count": 3, "type": "SCALAR"},
        {"bufferView": 4, "componentType": 5123, "count": 3, "type": "SCALAR"}]
    document["materials"].append({"name": "Red", "pbrMetallicRoughness": {
        "baseColorFactor": [0.8, 0.1, 0.1, 1.0], "metallicFactor": 0.0}})
    second = {"POSITION": 0, "NORMAL": 1} if second_has_normals else {"POSITION": 0}
    document["meshes"] = [{"name": "Floor", "primitives": [
        {"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3,
         "material": 0},
        {"attributes": second, "indices": 4, "material": 1}]}]
    return document


@pytest.mark.parametrize("second_has_normals", [True, False])
def test_load_gltf_merges_a_meshs_primitives_with_a_material_per_triangle(tmp_path,
                                                                         second_has_normals):
    scene = shgi.load_gltf(write_gltf(tmp_path / "two.gltf",
                                      two_material_document(second_has_normals)))
    [mesh] = scene.meshes
    [floor] = [i for i in scene.instances if i.mesh_id == 0]
    assert floor.name == "Floor" and mesh.name == "Floor"
    names = [m.name for m in scene.materials]
    assert [names[i] for i in mesh.material_indices] == ["Green", "Red"]
    # Four vertices from each primitive; without normals the second gets three flat corners.
    assert len(mesh.positions) == (8 if second_has_normals else 7)
    assert len(mesh.normals) == len(mesh.positions)
    np.testing.assert_allclose(mesh.normals, np.tile([0, 0, 1], (len(mesh.normals), 1)),
                               atol=1e-6)  # glTF +Y is Blender +Z, and the flat normal agrees
    uvs = mesh.uv_sets["UVMap"]
    assert uvs.shape == (len(mesh.positions), 2)
    np.testing.assert_array_equal(uvs[4:], 0.0)  # the second primitive had no UVs
    scene.commit()
    assert trace_down(scene, 0.5, -0.5) == pytest.approx(8.0)  # both triangles are there
    assert trace_down(scene, -0.5, 0.5) == pytest.approx(8.0)


def test_load_gltf_flips_v_and_converts_the_camera(tmp_path):
    scene = shgi.load_gltf(str(write_gltf(tmp_path / "scene.gltf", gltf_document())))
    mesh = scene.meshes[0]
    positions = np.asarray(mesh.positions)
    np.testing.assert_allclose(positions[0], [-1, -1, 0])  # glTF (-1, 0, 1)
    uv = mesh.uv_sets["UVMap"]
    np.testing.assert_allclose(uv[0], [0, 1])  # glTF (0, 0) is the top-left corner

    camera = scene.camera
    world_from_camera = np.asarray(camera.world_from_camera)
    np.testing.assert_allclose(world_from_camera[:3, 3], [0, -6, 3], atol=1e-6)
    forward = world_from_camera[:3, :3] @ np.array([0, 0, -1])
    np.testing.assert_allclose(forward, [0, 1, 0], atol=1e-6)  # glTF -Z is Blender +Y
    assert camera.resolution_x == 2 * camera.resolution_y


def test_load_gltf_options_and_bad_lighting_mode(tmp_path):
    path = write_gltf(tmp_path / "scene.gltf", gltf_document())
    unitless = shgi.load_gltf(path, lighting_mode="COMPAT")
    assert unitless.lights[0].power == pytest.approx(4 * math.pi * PBR_WATTS_TO_LUMENS, rel=1e-6)
    bare = shgi.load_gltf(path, import_lights=False, import_camera=False)
    assert len(bare.lights) == 0
    with pytest.raises(ValueError, match="lighting_mode"):
        shgi.load_gltf(path, lighting_mode="WATTS")


def test_load_gltf_missing_file_is_oserror(tmp_path):
    missing = tmp_path / "missing.gltf"
    with pytest.raises(OSError, match="missing.gltf"):
        shgi.load_gltf(missing)


def test_load_gltf_malformed_names_the_path(tmp_path):
    path = tmp_path / "broken.gltf"
    path.write_text('{"asset": {"version": "2.0"}, "nodes": [')
    with pytest.raises(OSError) as info:
        shgi.load_gltf(path)
    assert str(path) in str(info.value)


def test_load_gltf_buffer_uri_naming_a_folder_or_device_is_oserror(tmp_path):
    """A buffer URI naming a folder made tinygltf allocate its bogus size (MemoryError:
    std::bad_alloc); one naming a device read without end."""
    (tmp_path / "folder.bin").mkdir()
    for uri in ("folder.bin", "../" * 32 + "dev/zero"):
        document = gltf_document()
        document["buffers"][0]["uri"] = uri
        path = tmp_path / "scene.gltf"
        path.write_text(json.dumps(document))
        with pytest.raises(OSError, match=r"is not a regular file \(a folder, device"):
            shgi.load_gltf(path)


def test_load_gltf_index_out_of_range_is_oserror(tmp_path):
    path = write_gltf(tmp_path / "bad_index.gltf", gltf_document(indices=(0, 1, 2, 0, 2, 40)))
    with pytest.raises(OSError, match=r"indices\[5\] = 40, but the primitive has only 4"):
        shgi.load_gltf(path)


def test_load_gltf_from_two_threads(tmp_path):
    """Loading releases the GIL and logs through a sink that takes it: two concurrent loads must
    neither deadlock nor interfere."""
    path = write_gltf(tmp_path / "scene.gltf", gltf_document())
    results = []
    threads = [threading.Thread(target=lambda: results.append(shgi.load_gltf(path)))
               for _ in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=60)
    assert [len(scene.meshes) for scene in results] == [1, 1]


# --- OBJ ----------------------------------------------------------------------------------------

OBJ_TEXT = """mtllib two.mtl
v -1 1 1
v 1 1 1
v 1 1 -1
v -1 1 -1
v 3 0 0
v 4 0 0
v 3 2 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
o Floor
usemtl Red
f 1/1 2/2 3/3 4/4
o Glow
usemtl Glow
f 5 6 7
"""

MTL_TEXT = """newmtl Red
Kd 0.8 0.1 0.1
Ns 250
illum 2
newmtl Glow
Kd 0 0 0
Ke 3 3 3
"""


def write_obj(tmp_path, obj_text=OBJ_TEXT):
    (tmp_path / "two.mtl").write_text(MTL_TEXT)
    path = tmp_path / "two.obj"
    path.write_text(obj_text)
    return path


def test_load_obj_counts_materials_and_a_ray_hit(tmp_path):
    scene = shgi.load_obj(write_obj(tmp_path))
    assert len(scene.meshes) == 2 and len(scene.instances) == 2
    assert [m.name for m in scene.materials] == ["Red", "Glow"]
    red, glow = scene.materials
    np.testing.assert_allclose(np.asarray(red.base_color), [0.8, 0.1, 0.1], rtol=1e-6)
    assert red.roughness == pytest.approx(1 - math.sqrt(0.25))
    np.testing.assert_allclose(np.asarray(glow.emission_color) * glow.emission_strength, [3, 3, 3])
    np.testing.assert_allclose(scene.meshes[0].uv_sets["UVMap"][2], [1, 1])  # not flipped

    scene.commit()
    assert trace_down(scene, 0.0, 0.0) == pytest.approx(9.0)  # OBJ y = 1 is Blender z = 1


def test_load_obj_names_that_are_not_utf8_come_back_escaped(tmp_path, caplog):
    """A Latin-1 material or shape name reached Python as bytes no str could hold: reading
    scene.materials raised UnicodeDecodeError. The loader now keeps such bytes as \\xNN
    escapes, as Python's backslashreplace writes them, and warns naming the name."""
    (tmp_path / "latin.mtl").write_bytes(b"newmtl caf\xe9\nKd 0.5 0.5 0.5\n")
    path = tmp_path / "latin.obj"
    path.write_bytes(b"mtllib latin.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl caf\xe9\n"
                     b"o Stra\xdfe\nf 1 2 3\n")
    with caplog.at_level("WARNING", logger="shgi"):
        scene = shgi.load_obj(path)
    assert [m.name for m in scene.materials] == [b"caf\xe9".decode("utf-8", "backslashreplace")]
    assert scene.instances[0].name == scene.meshes[0].name == "Stra\\xdfe"
    assert "material name 'caf\\xe9' is not UTF-8" in caplog.text
    assert "shape name 'Stra\\xdfe' is not UTF-8" in caplog.text


def test_load_obj_missing_file_is_oserror(tmp_path):
    with pytest.raises(OSError, match="nothing.obj"):
        shgi.load_obj(tmp_path / "nothing.obj")


def test_load_obj_malformed_names_the_path(tmp_path):
    path = write_obj(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 12\n")
    with pytest.raises(OSError) as info:
        shgi.load_obj(path)
    assert str(path) in str(info.value)
    assert "vertex (v) 12" in str(info.value)


def test_load_obj_bad_up_axis_is_valueerror(tmp_path):
    with pytest.raises(ValueError, match="up_axis"):
        shgi.load_obj(write_obj(tmp_path), up_axis="X")


def test_a_relative_obj_index_before_the_first_vertex_is_named_as_such(tmp_path):
    path = write_obj(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -7\n")
    with pytest.raises(OSError, match="points before the first vertex .* the file has 3 "
                                      "vertices"):
        shgi.load_obj(path)


def many_nodes_document(nodes):
    """gltf_document's floor quad used by `nodes` nodes (a heavily instanced scene)."""
    document = gltf_document()
    document["nodes"] = [{"name": f"Floor.{i}", "mesh": 0, "translation": [0, 2 + i, 0]}
                         for i in range(nodes)]
    document["scenes"] = [{"nodes": list(range(nodes))}]
    return document


@pytest.mark.parametrize("loader", ["gltf", "obj"])
def test_loading_reports_its_stages_and_is_cancelled_by_its_progress(tmp_path, loader):
    if loader == "gltf":
        path = write_gltf(tmp_path / "many.gltf", many_nodes_document(200))
        load = shgi.load_gltf
    else:
        text = "".join(f"o Quad.{i}\nv 0 0 {i}\nv 1 0 {i}\nv 0 1 {i}\nf -3 -2 -1\n"
                       for i in range(200))
        path = write_obj(tmp_path, text)
        load = shgi.load_obj
    seen = []
    progress = shgi.Progress(lambda fraction, stage: seen.append((stage, fraction)),
                             min_interval=0.0)
    scene = load(path, progress=progress)
    assert len(scene.instances) == 200
    assert [stage for stage, _ in seen if stage == "reading"] and \
        [stage for stage, _ in seen if stage == "importing"]
    fractions = [fraction for _, fraction in seen]
    assert fractions == sorted(fractions) and fractions[-1] == pytest.approx(1.0)

    def cancel_while_importing(fraction, stage):
        if stage == "importing" and fraction > 0.6:
            cancelling.cancel()

    cancelling = shgi.Progress(cancel_while_importing, min_interval=0.0)
    with pytest.raises(shgi.Cancelled):
        load(path, progress=cancelling)
