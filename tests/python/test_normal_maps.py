"""Normal and bump maps through the Python API and the add-on's bpy-free mesh code, plus the
Blender round trip of a glTF normalTexture (tests/blender/gltf_normal_map_checks.py) and the
export of Blender's Bump node (tests/blender/bump_export_checks.py).

The Cycles calibration of normal maps is in test_cycles_calibration.py
(tests/blender/calibration_normal_maps.py); the closed forms in tests/cpp/render/
normal_map_test.cpp.
"""

import math
import sys

import numpy as np
import pytest
import shgi

from blender_support import ADDON_DIR, BLENDER_SCRIPTS, REPO_ROOT, run_blender

sys.path.insert(0, str(REPO_ROOT / "addon"))

from shgi_blender.export.mesh_split import split_corners  # noqa: E402

PLANE = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
QUADS = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
UVS = 0.5 * PLANE[:, :2] + 0.5
TILT = 0.4  # radians, along +U


def tilted_texture():
    """A 1x1 normal map whose texel encodes a normal tilted by TILT towards +U."""
    n = np.array([math.sin(TILT), 0.0, math.cos(TILT)], np.float32)
    return shgi.Texture(np.array([[[*(0.5 * n + 0.5), 1.0]]], np.float32), name="tilt")


def normal_mapped_plane(tangents, uvs=UVS):
    """A scene of the plane with the tilted normal map, a sun straight above and a camera
    looking down; committed."""
    scene = shgi.Scene()
    texture = scene.add_texture(tilted_texture())
    scene.add_material(shgi.Material(name="bumpy", base_color=(0.5, 0.5, 0.5), specular=0.0,
                                     diffuse_model=shgi.DiffuseModel.LAMBERT,
                                     normal_texture=texture))
    mesh = scene.add_mesh(positions=PLANE * 50, triangles=QUADS, uvs=uvs, tangents=tangents)
    scene.add_instance(mesh, np.eye(4))
    scene.add_light(shgi.Light(type=shgi.LightType.SUN, strength=3.0))
    scene.set_world(shgi.World(strength=0.0))  # only the sun: a closed form
    camera = np.eye(4)
    camera[2, 3] = 0.5
    scene.set_camera(shgi.Camera(type=shgi.CameraType.ORTHOGRAPHIC, ortho_scale=0.01,
                                 resolution_x=4, resolution_y=4, world_from_camera=camera))
    scene.commit()
    return scene


def render(scene):
    return shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=16, seed=1))


def test_the_normal_pass_holds_the_mapped_normal_and_light_follows_it():
    tangents = np.tile(np.array([1, 0, 0, 1], np.float32), (4, 1))
    passes = render(normal_mapped_plane(tangents))
    normal = passes["Normal"][..., :3].reshape(-1, 3).mean(axis=0)
    np.testing.assert_allclose(normal, [math.sin(TILT), 0.0, math.cos(TILT)], atol=1e-5)
    # Lambert under a sun from the zenith: rho / pi x S cos(tilt).
    expected = 0.5 / math.pi * 3.0 * math.cos(TILT)
    assert passes["Combined"][..., 0].mean() == pytest.approx(expected, rel=2e-3)


def test_a_lightmap_bake_shades_the_mapped_normal(tmp_path):
    """The bake's texels see the sun at the tilt: Lambert DIRECT = S cos(tilt) / pi exactly
    (a delta light and one Lambert lobe: every sample is the expectation)."""
    from shgi import bake

    tangents = np.tile(np.array([1, 0, 0, 1], np.float32), (4, 1))
    scene = normal_mapped_plane(tangents, uvs={"UVMap": UVS, "LightmapUV": UVS})
    settings = shgi.LightmapSettings(samples=8, seed=3, content="DIRECT")
    job = bake.BakeJob(instance=0, name="plane", width=8, height=8)
    [lightmap] = bake.bake_scene(scene, [job], bake.BakeOptions(settings=settings),
                                 str(tmp_path))
    color = lightmap.color.reshape(-1, 3)
    covered = color[color[:, 0] > 0]
    assert len(covered) > 32
    np.testing.assert_allclose(covered, 3.0 * math.cos(TILT) / math.pi, rtol=1e-4)


def test_material_fields_round_trip_and_are_checked():
    material = shgi.Material(normal_texture=2, normal_uv_set="Detail", normal_strength=0.5,
                             normal_space=shgi.NormalMapSpace.OBJECT)
    assert (material.normal_texture, material.normal_uv_set, material.normal_strength,
            material.normal_space) == (2, "Detail", 0.5, shgi.NormalMapSpace.OBJECT)
    scene = shgi.Scene()
    with pytest.raises(ValueError, match="normal_strength"):
        scene.add_material(shgi.Material(name="M", normal_strength=float("nan")))
    with pytest.raises(ValueError, match="normal_texture = -3 is negative"):
        scene.add_material(shgi.Material(name="M", normal_texture=-3))


def test_tangents_of_the_wrong_shape_name_the_argument():
    with pytest.raises(ValueError, match="tangents"):
        shgi.Mesh(positions=PLANE, triangles=QUADS, tangents=np.zeros((4, 3), np.float32))
    with pytest.raises(ValueError, match="tangents has 3 elements but positions has 4"):
        shgi.Scene().add_mesh(positions=PLANE, triangles=QUADS,
                              tangents=np.zeros((3, 4), np.float32))


def test_nan_tangents_and_missing_uvs_fall_back_to_the_flat_normal_with_a_warning():
    received = []
    shgi.set_log_sink(lambda level, message: received.append(message))
    try:
        tangents = np.full((4, 4), np.nan, np.float32)
        nan_passes = render(normal_mapped_plane(tangents))
        no_uv_passes = render(normal_mapped_plane(None, uvs=None))
    finally:
        shgi.set_log_sink(shgi._forward_to_logging)
    assert any("4 of 4 tangents are NaN, infinite or zero" in m for m in received), received
    assert any("has a tangent-space normal map but the mesh has no UV map" in m
               for m in received), received
    for passes in (nan_passes, no_uv_passes):
        normal = passes["Normal"][..., :3].reshape(-1, 3).mean(axis=0)
        np.testing.assert_allclose(normal, [0.0, 0.0, 1.0], atol=1e-6)
        assert passes["Combined"][..., 0].mean() == pytest.approx(0.5 / math.pi * 3.0,
                                                                  rel=2e-3)


def test_split_corners_keeps_tangents_and_splits_where_they_differ():
    positions = PLANE
    corners = QUADS.ravel()
    tangents = np.tile(np.array([1, 0, 0, 1], np.float32), (6, 1))
    tangents[3] = [0, 1, 0, -1]  # corner 3 (vertex 0 of the second triangle) differs
    split = split_corners(positions, corners, corner_tangents=tangents)
    assert len(split.positions) == 5 and split.tangents.shape == (5, 4)
    np.testing.assert_array_equal(split.tangents[split.triangles[1, 0]], [0, 1, 0, -1])
    tangents[3] = np.nan  # NaN compared as 0 (shgi drops it), not a split per corner
    split = split_corners(positions, corners, corner_tangents=tangents)
    np.testing.assert_array_equal(split.tangents[split.triangles[1, 0]], [0, 0, 0, 0])


@pytest.mark.blender
def test_a_gltf_normal_texture_renders_as_the_blend(blender, build_python_dir):
    result = run_blender(BLENDER_SCRIPTS / "gltf_normal_map_checks.py", build_python_dir,
                         ADDON_DIR, blender=blender, timeout=300)
    output = result.stdout[-4000:] + result.stderr[-4000:]
    assert result.returncode == 0, output
    assert "GLTF_NORMAL_MAP_OK" in result.stdout, output


@pytest.mark.blender
def test_the_bump_node_exports_with_its_settings_and_refuses_what_it_cannot_read(
        blender, build_python_dir):
    result = run_blender(BLENDER_SCRIPTS / "bump_export_checks.py", build_python_dir,
                         ADDON_DIR, blender=blender, timeout=300)
    output = result.stdout[-4000:] + result.stderr[-4000:]
    assert result.returncode == 0, output
    assert "BUMP_EXPORT_OK" in result.stdout, output


def test_a_bumped_plane_under_the_sun_matches_the_closed_form():
    """A height ramp h = u across a plane 100 m wide (UV 0..1): grad h = 1/100 per m, so at
    Distance 20 every normal tilts by atan(0.2) towards -x, and a Lambert plane under a sun
    overhead reads rho / pi S cos(tilt); the Normal pass holds the tilted normal."""
    scene = shgi.Scene()
    texels = np.ones((2, 64, 4), np.float32)  # h = u at the texel centres: exact in between
    texels[..., :3] = ((np.arange(64) + 0.5) / 64).astype(np.float32)[None, :, None]
    height = scene.add_texture(shgi.Texture(texels, name="ramp"))
    scene.add_material(shgi.Material(name="bumpy", base_color=(0.5, 0.5, 0.5), specular=0.0,
                                     diffuse_model=shgi.DiffuseModel.LAMBERT,
                                     bump_texture=height, bump_distance=20.0))
    mesh = scene.add_mesh(positions=PLANE * 50, triangles=QUADS, uvs=UVS)
    scene.add_instance(mesh, np.eye(4))
    scene.add_light(shgi.Light(type=shgi.LightType.SUN, strength=3.0))
    scene.set_world(shgi.World(strength=0.0))
    camera = np.eye(4)
    camera[2, 3] = 0.5
    scene.set_camera(shgi.Camera(type=shgi.CameraType.ORTHOGRAPHIC, ortho_scale=0.01,
                                 resolution_x=4, resolution_y=4, world_from_camera=camera))
    scene.commit()
    passes = render(scene)
    tilt = math.atan(20.0 / 100.0)
    combined = np.asarray(passes["Combined"])[..., :3].mean()
    assert combined == pytest.approx(0.5 / math.pi * 3.0 * math.cos(tilt), rel=2e-3)
    normal = np.asarray(passes["Normal"])[..., :3].reshape(-1, 3).mean(axis=0)
    np.testing.assert_allclose(normal, [-math.sin(tilt), 0.0, math.cos(tilt)], atol=1e-4)
