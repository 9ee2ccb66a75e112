"""The add-on's bpy-free export code: socket names, units, vertex splitting, matrices.

Runs without Blender: shgi_blender.export.conversions and mesh_split import only numpy and shgi.
"""

import math
import pathlib
import sys

import numpy as np
import pytest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "addon"))

import shgi  # noqa: E402
from shgi_blender.export import conversions  # noqa: E402
from shgi_blender.export.mesh_split import distinct_rows, split_corners  # noqa: E402

BLENDER_3_4 = (3, 4, 1)
BLENDER_4_2 = (4, 2, 0)
TOLERANCE = 1e-6
IDENTITY = np.eye(4)


def principled_values(names, **overrides):
    """Input values of a Principled BSDF keyed by the given socket names."""
    values = {"base_color": (0.2, 0.4, 0.6, 1.0), "metallic": 0.3, "roughness": 0.25,
              "ior": 1.5, "specular": 0.5, "transmission": 0.1,
              "emission_color": (1.0, 0.5, 0.25, 1.0), "emission_strength": 2.0}
    values.update(overrides)
    return {names[field]: value for field, value in values.items()}


def test_socket_names_differ_between_3_4_and_4_x():
    old = conversions.principled_socket_names(BLENDER_3_4)
    new = conversions.principled_socket_names(BLENDER_4_2)
    assert (old["specular"], old["transmission"], old["emission_color"]) == (
        "Specular", "Transmission", "Emission")
    assert (new["specular"], new["transmission"], new["emission_color"]) == (
        "Specular IOR Level", "Transmission Weight", "Emission Color")
    assert old["base_color"] == new["base_color"] == "Base Color"
    assert conversions.principled_socket_names((4, 0, 0)) == new


def test_principled_3_4_values_are_copied():
    names = conversions.principled_socket_names(BLENDER_3_4)
    fields = conversions.material_fields_from_principled(
        principled_values(names, specular=0.7), BLENDER_3_4)
    assert fields["base_color"] == pytest.approx((0.2, 0.4, 0.6))
    assert fields["specular"] == pytest.approx(0.7)
    assert fields["emission_color"] == pytest.approx((1.0, 0.5, 0.25))
    assert (fields["metallic"], fields["transmission"], fields["emission_strength"]) == (
        0.3, 0.1, 2.0)
    material = shgi.Material(**fields)
    assert material.is_emissive()


@pytest.mark.parametrize("ior", [1.33, 1.45, 1.5, 2.4])
def test_specular_ior_level_half_gives_the_fresnel_of_the_ior(ior):
    f0 = ((ior - 1) / (ior + 1)) ** 2
    assert conversions.specular_from_ior_level(0.5, ior) == pytest.approx(
        f0 / conversions.SPECULAR_F0_SCALE)
    # 0 removes the reflection, 1 doubles F0 (Blender 4's manual).
    assert conversions.specular_from_ior_level(0.0, ior) == 0.0
    assert conversions.specular_from_ior_level(1.0, ior) == pytest.approx(
        2 * f0 / conversions.SPECULAR_F0_SCALE)


def test_principled_4_x_level_at_ior_1_5_is_specular_0_5():
    # IOR 1.5 has F0 = 0.04 = 0.08 * 0.5: Blender 3.4's default look.
    names = conversions.principled_socket_names(BLENDER_4_2)
    fields = conversions.material_fields_from_principled(principled_values(names), BLENDER_4_2)
    assert fields["specular"] == pytest.approx(0.5)
    assert fields["transmission"] == pytest.approx(0.1)


def test_principled_4_x_is_layered_with_the_node_distribution():
    names = conversions.principled_socket_names(BLENDER_4_2)
    default = shgi.Material(**conversions.material_fields_from_principled(
        principled_values(names), BLENDER_4_2))
    assert default.principled_model == shgi.PrincipledModel.V2
    assert default.distribution == shgi.MicrofacetDistribution.MULTISCATTER_GGX
    ggx = conversions.material_fields_from_principled(principled_values(names), BLENDER_4_2,
                                                      "GGX")
    assert ggx["distribution"] == shgi.MicrofacetDistribution.GGX
    with pytest.raises(ValueError, match="BECKMANN"):
        conversions.material_fields_from_principled(principled_values(names), BLENDER_4_2,
                                                    "BECKMANN")
    # Blender 3.4 keeps the added (v1) closures, whatever its node's distribution.
    old = shgi.Material(**conversions.material_fields_from_principled(
        principled_values(conversions.principled_socket_names(BLENDER_3_4)), BLENDER_3_4,
        "MULTI_GGX"))
    assert (old.principled_model, old.distribution) == (
        shgi.PrincipledModel.V1, shgi.MicrofacetDistribution.GGX)


def test_emission_and_diffuse_shaders():
    emission = conversions.material_fields_from_emission((2.0, 1.0, 0.5, 1.0), 4.0)
    assert emission["base_color"] == (0, 0, 0) and emission["specular"] == 0
    assert shgi.Material(**emission).is_emissive()
    diffuse = conversions.material_fields_from_diffuse((0.5, 0.6, 0.7, 1.0))
    assert diffuse["base_color"] == pytest.approx((0.5, 0.6, 0.7)) and diffuse["specular"] == 0


def test_fallback_is_blender_default_grey():
    material = shgi.Material(**conversions.fallback_material_fields())
    assert material.base_color == pytest.approx((0.8, 0.8, 0.8))
    assert material.roughness == pytest.approx(0.5)


def test_clamping_reports_what_changed():
    fields = {"metallic": 1.5, "roughness": 0.5, "specular": -0.1, "ior": 0.9,
              "base_color": (1.2, -0.1, 0.5), "emission_strength": -1.0}
    clamped, changed = conversions.clamp_material_fields(fields)
    assert clamped["metallic"] == 1.0 and clamped["specular"] == 0.0 and clamped["ior"] == 1.0
    assert clamped["base_color"] == (1.2, 0.0, 0.5) and clamped["emission_strength"] == 0.0
    assert sorted(changed) == ["base_color", "emission_strength", "ior", "metallic", "specular"]
    shgi.Material(**clamped)  # accepted by SHGI's validation


def test_ignored_principled_inputs():
    assert conversions.ignored_principled_inputs({"Subsurface": 0.0, "Alpha": 1.0}) == []
    assert conversions.ignored_principled_inputs({"Clearcoat": 0.2, "Alpha": 0.5}) == [
        "Clearcoat", "Alpha"]


@pytest.mark.parametrize("colorspace, is_float, decode", [
    ("sRGB", False, True), ("sRGB", True, False), ("Non-Color", False, False),
    ("Linear", True, False)])
def test_texture_decoding_rule(colorspace, is_float, decode):
    assert conversions.texture_needs_srgb_decode(colorspace, is_float) == decode
    assert conversions.texture_colorspace_is_known(colorspace)


def test_point_spot_sun_light_units():
    point = shgi.Light(**conversions.light_fields("POINT", 100.0, (1, 0.5, 0.25), IDENTITY,
                                                  shadow_soft_size=0.3, name="Lamp"))
    assert (point.type, point.power, point.radius, point.name) == (
        shgi.LightType.POINT, 100.0, pytest.approx(0.3), "Lamp")
    spot = shgi.Light(**conversions.light_fields("SPOT", 50.0, (1, 1, 1), IDENTITY,
                                                 spot_size=0.8, spot_blend=0.3))
    assert (spot.spot_size, spot.spot_blend) == (pytest.approx(0.8), pytest.approx(0.3))
    # Blender 3.4's spot falloff includes the cone cosine; 4.0's does not.
    assert spot.spot_cone_cosine
    spot_4 = shgi.Light(**conversions.light_fields("SPOT", 50.0, (1, 1, 1), IDENTITY,
                                                   blender_version=BLENDER_4_2))
    assert not spot_4.spot_cone_cosine
    sun = shgi.Light(**conversions.light_fields("SUN", 3.0, (1, 1, 1), IDENTITY, angle=0.1))
    # The sun's energy is its strength in W/m^2, not a power.
    assert (sun.type, sun.strength) == (shgi.LightType.SUN, 3.0)
    assert sun.angle == pytest.approx(0.1)


def test_light_exposure_scales_the_energy_and_unrendered_settings_are_named():
    # Blender 5.0's Light.exposure: energy x 2^exposure, for powers and the sun's strength.
    point = conversions.light_fields("POINT", 100.0, (1, 1, 1), IDENTITY, exposure=1.5)
    assert point["power"] == pytest.approx(100.0 * 2 ** 1.5)
    sun = conversions.light_fields("SUN", 3.0, (1, 1, 1), IDENTITY, exposure=-1.0)
    assert sun["strength"] == pytest.approx(1.5)
    assert conversions.ignored_light_settings({"use_temperature": False, "normalize": True}) == []
    assert conversions.ignored_light_settings({"use_temperature": True, "normalize": False}) == [
        "use_temperature", "normalize"]


@pytest.mark.parametrize("shape, size_y", [("SQUARE", 2.0), ("RECTANGLE", 0.5), ("DISK", 2.0),
                                           ("ELLIPSE", 0.5)])
def test_area_light_sizes(shape, size_y):
    light = shgi.Light(**conversions.light_fields("AREA", 20.0, (1, 1, 1), IDENTITY,
                                                  shape=shape, size=2.0, size_y=0.5))
    assert light.shape == conversions.AREA_SHAPES[shape]
    assert (light.power, light.size_x, light.size_y) == (20.0, 2.0, size_y)


def test_portal_is_kept_for_area_lights_only():
    portal = shgi.Light(**conversions.light_fields("AREA", 0.0, (1, 1, 1), IDENTITY, portal=True))
    assert portal.portal
    # Blender keeps cycles.is_portal on every light but uses it only for area lights.
    point = shgi.Light(**conversions.light_fields("POINT", 10.0, (1, 1, 1), IDENTITY,
                                                  portal=True))
    assert not point.portal


def test_unknown_light_type_names_it():
    with pytest.raises(ValueError, match="'PROBE'"):
        conversions.light_fields("PROBE", 1.0, (1, 1, 1), IDENTITY)


def camera_kwargs(**overrides):
    kwargs = dict(lens=50.0, sensor_width=36.0, sensor_height=24.0, sensor_fit="AUTO",
                  ortho_scale=7.0, shift_x=0.1, shift_y=-0.2, clip_start=0.1, clip_end=100.0,
                  resolution_x=1920, resolution_y=1080, resolution_percentage=50)
    kwargs.update(overrides)
    return kwargs


def test_camera_fields_and_resolution_percentage():
    matrix = np.eye(4)
    matrix[:3, 3] = (1.0, 2.0, 3.0)
    camera = shgi.Camera(**conversions.camera_fields("ORTHO", matrix,
                                                     **camera_kwargs(sensor_fit="VERTICAL")))
    assert (camera.resolution_x, camera.resolution_y) == (960, 540)
    assert camera.type == shgi.CameraType.ORTHOGRAPHIC
    assert camera.sensor_fit == shgi.SensorFit.VERTICAL
    assert (camera.shift_x, camera.shift_y) == (pytest.approx(0.1), pytest.approx(-0.2))
    np.testing.assert_allclose(camera.world_from_camera[:3, 3], (1.0, 2.0, 3.0))


def test_render_resolution_rounds_down_like_blender():
    assert conversions.render_resolution(1001, 501, 50) == (500, 250)
    assert conversions.render_resolution(1, 1, 1) == (1, 1)


def test_panoramic_camera_is_refused():
    with pytest.raises(ValueError, match="'PANO'"):
        conversions.camera_fields("PANO", IDENTITY, **camera_kwargs())


def test_perspective_camera_centre_projects_to_the_shifted_film_centre():
    # A point on the view axis lands shift * (fitted width) pixels off the centre.
    camera = shgi.Camera(**conversions.camera_fields("PERSP", IDENTITY, **camera_kwargs()))
    x, y = camera.project((0.0, 0.0, -5.0))
    assert x == pytest.approx(480 - 0.1 * 960, abs=1e-3)
    assert y == pytest.approx(270 - 0.2 * 960, abs=1e-3)


def test_row_major_keeps_translation_in_the_last_column():
    # mathutils.Matrix iterates rows; a nested list of rows stands in for it here.
    rows = [[1, 0, 0, 5], [0, 1, 0, 6], [0, 0, 1, 7], [0, 0, 0, 1]]
    matrix = conversions.row_major(rows)
    assert matrix.dtype == np.float64 and matrix.shape == (4, 4)
    np.testing.assert_array_equal(matrix[:3, 3], (5, 6, 7))
    scene = shgi.Scene()
    mesh = scene.add_mesh(positions=np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32),
                          triangles=np.array([[0, 1, 2]]))
    scene.add_material(shgi.Material())
    scene.add_instance(mesh, matrix)
    assert scene.bounds()[0] == pytest.approx((5, 6, 7))
    with pytest.raises(ValueError, match="shape"):
        conversions.row_major([[1, 0, 0]])


def test_world_fields_and_equirect_average():
    assert conversions.world_fields((0.1, 0.2, 0.3, 1.0), 2.0) == {
        "color": (0.1, 0.2, 0.3), "strength": 2.0}
    uniform = np.full((8, 16, 4), 0.5, np.float32)
    assert conversions.equirect_average(uniform) == pytest.approx((0.5, 0.5, 0.5))
    # Bright poles (first and last rows) weigh little: cos(latitude) of their rows is small.
    image = np.zeros((64, 8, 3))
    image[[0, -1]] = 1.0
    expected = 2 * math.cos(math.pi * (0.5 - 0.5 / 64)) / sum(
        math.cos(math.pi * ((i + 0.5) / 64 - 0.5)) for i in range(64))
    assert conversions.equirect_average(image)[0] == pytest.approx(expected)


def quad_corners():
    """Two triangles over 4 vertices sharing the edge 0-2: (3T,) corner vertices."""
    positions = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    return positions, np.array([0, 1, 2, 0, 2, 3])


def test_split_shares_vertices_with_equal_corner_data():
    positions, corners = quad_corners()
    normals = np.tile([0.0, 0.0, 1.0], (6, 1))
    uvs = positions[corners][:, :2]
    split = split_corners(positions, corners, normals, {"UVMap": uvs})
    assert len(split.positions) == 4 and split.triangles.shape == (2, 3)
    # Every triangle corner keeps its position, normal and UV.
    np.testing.assert_array_equal(split.positions[split.triangles.ravel()], positions[corners])
    np.testing.assert_array_equal(split.uvs["UVMap"][split.triangles.ravel()], uvs)
    assert split.triangles.dtype == np.int32 and split.normals.dtype == np.float32


def test_split_duplicates_vertices_at_normal_and_uv_seams():
    positions, corners = quad_corners()
    normals = np.array([[0, 0, 1]] * 3 + [[0, 1, 0]] * 3, np.float64)  # a crease along 0-2
    split = split_corners(positions, corners, normals)
    assert len(split.positions) == 6
    np.testing.assert_array_equal(split.normals[split.triangles.ravel()], normals)
    uvs = {"A": np.zeros((6, 2)), "B": np.array([[0, 0]] * 3 + [[1, 0]] * 3, np.float64)}
    assert len(split_corners(positions, corners, None, uvs).positions) == 6
    assert split_corners(positions, corners, None, uvs).normals is None


def test_split_rejects_nan_and_bad_indices():
    positions, corners = quad_corners()
    positions[2, 1] = np.nan
    with pytest.raises(ValueError, match=r"^mesh 'quad': vertex 2 has y = nan; SHGI places "
                                         r"coordinates within ±1e\+12 m: move the vertex back"):
        split_corners(positions, corners, name="quad")
    with pytest.raises(ValueError, match=r"\[0, 4\)"):
        split_corners(quad_corners()[0], np.array([0, 1, 4]), name="quad")
    with pytest.raises(ValueError, match="corner 1"):
        split_corners(quad_corners()[0], corners, np.array([[0, 0, 1], [np.inf, 0, 0]] * 3))


def test_split_names_an_inf_vertex_as_the_artist_typed_it():
    """Blender stores an inf typed into a vertex field as its largest float (3.4e+38): finite,
    but its normals are NaN. It is refused as inf, before the normals; so is a real inf and a
    coordinate beyond shgi.MAX_COORDINATE, with its value; the limit itself passes."""
    largest = np.finfo(np.float32).max
    for value, text in ((largest, "inf"), (-np.inf, "-inf"), (2e12, "2e\\+12 m")):
        positions, corners = quad_corners()
        positions[1, 2], positions[3, 0] = value, value
        with pytest.raises(ValueError, match=rf"^mesh 'quad': vertex 1 has z = {text} \(and 1 "
                                             r"more vertices\); SHGI places coordinates within "
                                             r"±1e\+12 m"):
            split_corners(positions, corners, name="quad")
    positions, corners = quad_corners()
    positions[0] = shgi.MAX_COORDINATE
    assert split_corners(positions, corners).positions[0].tolist() == [shgi.MAX_COORDINATE] * 3


def test_split_of_an_empty_mesh():
    split = split_corners(np.zeros((0, 3)), np.zeros(0, np.int32))
    assert split.positions.shape == (0, 3) and split.triangles.shape == (0, 3)


def test_split_matches_distinct_corner_rows_on_a_random_mesh():
    """Against the definition: one vertex per distinct (Blender vertex, float32 data) row of the
    corners, ordered by Blender vertex and then by first corner, with every corner's data
    kept; 0.0 and -0.0 are the same value."""
    rng = np.random.default_rng(7)
    positions = rng.random((50, 3), dtype=np.float32)
    corners = rng.integers(0, 40, 600)  # vertices 40-49 are unused and dropped
    # Few distinct values, so that corners of one vertex often agree and sometimes do not.
    normals = rng.integers(-1, 2, (600, 3)).astype(np.float64)
    normals[normals == 0] = rng.choice([0.0, -0.0], int((normals == 0).sum()))
    uvs = {"UVMap": rng.integers(0, 2, (600, 2)).astype(np.float32)}
    split = split_corners(positions, corners, normals, uvs, name="random")
    rows = np.concatenate([corners[:, None], normals + 0.0, uvs["UVMap"]], axis=1)
    _, first = np.unique(rows, axis=0, return_index=True)
    first = first[np.lexsort((first, corners[first]))]
    assert len(split.positions) == len(first)
    np.testing.assert_array_equal(split.positions, positions[corners[first]])
    np.testing.assert_array_equal(split.normals, (normals + 0.0)[first].astype(np.float32))
    flat = split.triangles.ravel()
    np.testing.assert_array_equal(split.positions[flat], positions[corners])
    np.testing.assert_array_equal(split.normals[flat], normals.astype(np.float32))
    np.testing.assert_array_equal(split.uvs["UVMap"][flat], uvs["UVMap"])


def test_distinct_rows_is_exact_even_when_every_row_hashes_alike():
    rng = np.random.default_rng(3)
    columns = [rng.integers(0, 3, 500).astype(np.uint32) for _ in range(3)]
    rows = np.stack(columns, axis=1)
    _, expected_first = np.unique(rows, axis=0, return_index=True)
    expected_first.sort()
    for row_hash in (None, lambda cols: np.zeros(cols[0].size, np.uint64)):
        first, inverse = distinct_rows(columns, row_hash=row_hash)
        np.testing.assert_array_equal(first, expected_first)
        np.testing.assert_array_equal(rows[first][inverse], rows)
