"""Pickled scenes and settings (shgi.pickling): what a farm's workers receive is the scene the
client built, so it renders and bakes to the same bits; every settings field travels."""

import pickle
import sys

import numpy as np
import pytest

import shgi
from shgi import bake
from blender_support import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402


def round_trip(value):
    return pickle.loads(pickle.dumps(value))


def textured_scene():
    """A plane with a base colour texture and a normal map (UVs and tangents), a box of another
    material, one light of every type, a world and a camera."""
    scene = shgi.Scene()
    pixels = np.random.default_rng(3).random((4, 5, 4)).astype(np.float32)
    colour = scene.add_texture(shgi.Texture(pixels, name="colour"))
    normal = scene.add_texture(shgi.Texture(
        np.array([[[0.6, 0.5, 0.9, 1.0]]], np.float32), name="bumps"))
    scene.add_material(shgi.Material(name="floor", base_color_texture=colour,
                                     normal_texture=normal, normal_strength=0.7, roughness=0.3))
    scene.add_material(shgi.Material(name="box", base_color=(0.2, 0.6, 0.3), metallic=0.5,
                                     emission_color=(1.0, 0.5, 0.2), emission_strength=0.1))
    plane = np.array([[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]], np.float32)
    quads = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    uvs = {"UVMap": 0.25 * plane[:, :2] + 0.5, "LightmapUV": 0.2 * plane[:, :2] + 0.45}
    tangents = np.tile(np.array([1, 0, 0, -1], np.float32), (4, 1))
    floor = scene.add_mesh(positions=plane, triangles=quads, uvs=uvs, tangents=tangents,
                           name="floor")
    box = scenes.box((0.5, 0.3, 0.4), 0.8, 0.6, 0.8, 0.3)
    cube = scene.add_mesh(positions=box[0], triangles=box[1],
                          material_indices=np.ones(len(box[1]), np.uint32), name="cube")
    scene.add_instance(floor, np.eye(4), "floor")
    moved = np.eye(4)
    moved[:3, 3] = (-0.7, 0.4, 0.0)
    scene.add_instance(cube, moved, "cube")
    scene.add_instance(cube, np.eye(4), "cube.001")
    for light in (shgi.Light(type=shgi.LightType.POINT, power=200.0, radius=0.1),
                  shgi.Light(type=shgi.LightType.SPOT, power=300.0, spot_size=0.9,
                             spot_blend=0.3),
                  shgi.Light(type=shgi.LightType.SUN, strength=2.0, angle=0.05),
                  shgi.Light(type=shgi.LightType.AREA, power=100.0, size_x=0.5, size_y=0.3,
                             shape=shgi.AreaShape.RECTANGLE)):
        light.world_from_light = np.array([[1, 0, 0, 0.3], [0, 1, 0, -0.2], [0, 0, 1, 2.5],
                                           [0, 0, 0, 1]], np.float32)
        scene.add_light(light)
    scene.set_world(shgi.World(color=(0.4, 0.5, 0.7), strength=0.5))
    scene.set_camera(shgi.Camera(resolution_x=24, resolution_y=16, lens=30.0,
                                 world_from_camera=scenes.look_at((0, -5, 3), (0, 0, 0.3))))
    return scene


def plain(scene):
    """Everything a Scene holds as comparable data."""
    fields = shgi.settings_to_dict
    return {
        "meshes": [(m.name, m.positions.tobytes(), m.triangles.tobytes(), m.normals.tobytes(),
                    {k: v.tobytes() for k, v in m.uv_sets.items()},
                    m.material_indices.tobytes(), m.tangents.tobytes()) for m in scene.meshes],
        "instances": [(i.mesh_id, i.world_from_object.tobytes(), i.name)
                      for i in scene.instances],
        "materials": [fields(m) for m in scene.materials],
        "textures": [(t.name, t.pixels.tobytes()) for t in scene.textures],
        "lights": [fields(light) for light in scene.lights],
        "world": fields(scene.world), "camera": fields(scene.camera)}


def test_a_pickled_scene_holds_the_same_data_and_renders_the_same_bits():
    scene = textured_scene()
    copy = round_trip(scene)
    assert plain(copy) == plain(scene)
    assert len(copy.lights) == 4 and len(copy.textures) == 2 and not copy.committed
    assert pickle.dumps(copy) == pickle.dumps(scene)  # the farm's content hash is stable
    scene.commit()
    copy.commit()
    settings = shgi.PathTracerSettings(samples=4, seed=5)
    original, again = shgi.render_path_traced(scene, settings), \
        shgi.render_path_traced(copy, settings)
    assert original.keys() == again.keys()
    for name in original:
        np.testing.assert_array_equal(again[name], original[name], err_msg=name)
    assert original["Combined"].mean() > 0  # lit: the comparison means something


def test_a_pickled_scene_bakes_the_same_bits(tmp_path):
    scene = scenes.sun_room(0.25, lightmap=True).scene
    copy = round_trip(scene)
    scene.commit()
    copy.commit()
    options = bake.BakeOptions(settings=shgi.LightmapSettings(samples=4, seed=2, directional=True))
    results = []
    for name, which in (("original", scene), ("copy", copy)):
        jobs = bake.jobs_for_scene(which, "LightmapUV", 8, names=["floor", "back"])
        results.append(bake.bake_scene(which, jobs, options, str(tmp_path / name)))
    for first, second in zip(*results):
        np.testing.assert_array_equal(first.color, second.color)
        np.testing.assert_array_equal(first.sh, second.sh)
    assert results[0][0].color.max() > 0


@pytest.mark.parametrize("name", [row.identifier for row in shgi.methods()
                                  if row.settings_type.__module__.startswith("shgi")])
def test_every_native_method_settings_pickle_every_field(name):
    settings = shgi.default_settings(name, seed=11)
    for field, value in shgi.settings_to_dict(settings).items():  # a field off its default
        if isinstance(value, bool):
            setattr(settings, field, not value)
        elif isinstance(value, int) and field != "seed" and value > 1:
            setattr(settings, field, value - 1)
    if name == "PROBE_GRID":
        settings.volumes = [shgi.ProbeVolume(world_from_volume=np.diag([2, 3, 1, 1]),
                                             resolution=(3, 2, 4))]
    copy = round_trip(settings)
    assert type(copy) is type(settings)
    assert shgi.settings_to_dict(copy) == shgi.settings_to_dict(settings)


def test_bake_settings_and_options_pickle():
    options = bake.BakeOptions(settings=shgi.LightmapSettings(samples=9, content="INDIRECT",
                                                              directional=True, seed=4),
                               uv_set="Bake", filter=True, padding=2)
    options.filter_settings.normal_power = 32.0
    copy = round_trip(options)
    assert shgi.settings_to_dict(copy.settings) == shgi.settings_to_dict(options.settings)
    assert shgi.settings_to_dict(copy.filter_settings) == \
        shgi.settings_to_dict(options.filter_settings)
    assert (copy.uv_set, copy.filter, copy.padding) == ("Bake", True, 2)
