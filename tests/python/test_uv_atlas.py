"""Tests of shgi.uv_atlas: xatlas lightmap UV maps for meshes that have none.

The layout is checked by SHGI's own texel rasterizer, not by xatlas's word: no texel whose
triangles' areas sum past 1 (overlapping charts), the rasterizer's coverage (clamped to 1 per
texel) adding up to the exact UV area (an overlap would lose area to the clamp), every chart
at least 2 x padding empty texels from the next (room for each chart's dilation). A bake through
the new UVs is checked against an exact answer: a convex Lambert box under a uniform world
reflects exactly the world's radiance at every texel. Then the sun room's table, a box without
UVs, gets a layout and bakes in the room.
"""

import importlib.util
import sys

import numpy as np
import pytest

import shgi
from shgi.uv_atlas import add_lightmap_uvs, lightmap_uvs
from blender_support import REPO_ROOT

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/scenes.py, the project's test scenes)

needs_xatlas = pytest.mark.skipif(
    importlib.util.find_spec("xatlas") is None,
    reason="xatlas is not installed for this Python: run `make deps` or "
           "`python3 -m pip install xatlas`")

PADDING = 2
TEXELS_PER_METRE = 64.0
# The table of examples/scenes.py: 1 x 0.7 x 0.75 m, turned 10 degrees.
TABLE = ((0.6, 2.2, 0.0), 1.0, 0.7, 0.75, np.radians(10))
WORLD_COLOR, WORLD_STRENGTH = (0.2, 0.4, 0.8), 2.0
# As in test_bake.py: a Lambert surface under a uniform world bakes exactly, up to float32
# round-off in the sums.
ROUND_OFF = 1e-5
# Flat charts keep their world area: UV area in texels = world area x density^2, up to xatlas
# rounding each chart's scale to its texel grid (0.9 % measured on the table).
DENSITY_TOLERANCE = 0.03


def table_mesh():
    positions, triangles = scenes.box(*TABLE)
    return shgi.Mesh(positions=positions, triangles=triangles, name="table")


def raster(mesh, width, height):
    """The texel map of `mesh` alone (identity transform) at width x height."""
    scene = shgi.Scene()
    scene.add_instance(scene.add_mesh(mesh), np.eye(4), mesh.name)
    return shgi.rasterize_texels(scene, 0, shgi.TexelRasterSettings(width=width, height=height))


def texel_area(layout):
    """Area (texels) of the layout's UV triangles."""
    return layout.report["uv_coverage"] * layout.width * layout.height


def chart_gap(chart, limit):
    """Smallest Chebyshev distance (texels) between texels of two different charts, or `limit`
    when none are closer than that."""
    h, w = chart.shape
    for distance in range(1, limit):
        for dy in range(-distance, distance + 1):
            for dx in range(-distance, distance + 1):
                if max(abs(dy), abs(dx)) != distance:
                    continue
                a = chart[max(0, -dy):h - max(0, dy), max(0, -dx):w - max(0, dx)]
                b = chart[max(0, dy):h + min(0, dy), max(0, dx):w + min(0, dx)]
                if ((a >= 0) & (b >= 0) & (a != b)).any():
                    return distance
    return limit


@pytest.fixture(scope="module")
def table():
    """(new mesh, layout, texel map) of the table at TEXELS_PER_METRE."""
    mesh, layout = add_lightmap_uvs(table_mesh(), texels_per_metre=TEXELS_PER_METRE,
                                    padding=PADDING)
    return mesh, layout, raster(mesh, layout.width, layout.height)


@needs_xatlas
def test_layout_has_no_overlapping_charts(table):
    _, layout, texel_map = table
    report = texel_map.report
    print(f"\ntable: {layout.report}")
    assert report["overlapping_texels"] == 0
    assert report["degenerate_uv"] == 0 and report["clipped_triangles"] == 0
    # Clamping each texel's coverage to 1 would lose area wherever charts overlapped.
    assert texel_map.coverage.sum() == pytest.approx(texel_area(layout), rel=1e-4)
    assert texel_map.coverage.max() <= 1.0
    assert chart_gap(texel_map.chart, 2 * PADDING + 2) >= 2 * PADDING + 1


@needs_xatlas
def test_report_counts_charts_and_utilisation(table):
    _, layout, texel_map = table
    report = layout.report
    # Six faces at right angles: six planar charts, as the rasterizer finds them too.
    assert report["chart_count"] == 6 == texel_map.chart_count
    assert 0.0 < report["uv_coverage"] <= report["utilization"] <= 1.0
    assert (report["width"], report["height"]) == (layout.width, layout.height)
    assert report["texels_per_metre"] == TEXELS_PER_METRE


@needs_xatlas
def test_charts_keep_the_texel_density(table):
    mesh, layout, _ = table
    positions, triangles = np.asarray(mesh.positions, np.float64), layout.triangles
    a, b, c = (positions[triangles[:, k]] for k in range(3))
    world_area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
    assert texel_area(layout) == pytest.approx(world_area * TEXELS_PER_METRE ** 2,
                                               rel=DENSITY_TOLERANCE)


@needs_xatlas
def test_vertex_map_carries_every_attribute():
    positions, triangles = scenes.box(*TABLE)
    normals = positions - positions.mean(axis=0)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    texture_uvs = positions[:, :2] * 0.5
    mesh = shgi.Mesh(positions=positions, triangles=triangles, normals=normals,
                     uvs={"UVMap": texture_uvs}, material_indices=np.arange(12) % 3, name="t")
    new, layout = add_lightmap_uvs(mesh, resolution=64, padding=PADDING)
    split = layout.vertex_map
    # The same triangles in the same order, corner by corner.
    np.testing.assert_array_equal(np.asarray(new.positions)[new.triangles],
                                  positions[triangles])
    np.testing.assert_allclose(np.asarray(new.normals), normals[split], rtol=1e-6)
    np.testing.assert_allclose(new.uv_sets["UVMap"], texture_uvs[split], rtol=1e-6)
    np.testing.assert_array_equal(new.material_indices, np.arange(12) % 3)
    assert list(new.uv_sets) == ["UVMap", "LightmapUV"]
    # Vertices are split only where charts meet: each corner of the box is on three faces.
    assert len(split) == 24


@needs_xatlas
def test_world_from_object_makes_the_density_count_world_metres():
    positions, triangles = scenes.box(*TABLE)
    normals = positions - positions.mean(axis=0)
    mesh = shgi.Mesh(positions=positions, triangles=triangles, name="t",
                     normals=normals / np.linalg.norm(normals, axis=1, keepdims=True))
    scale = np.diag([2.0, 2.0, 2.0, 1.0])
    _, plain = add_lightmap_uvs(mesh, texels_per_metre=32.0)
    _, scaled = add_lightmap_uvs(mesh, texels_per_metre=32.0, world_from_object=scale)
    # Twice the size in the world: four times the texels at the same density.
    assert texel_area(scaled) == pytest.approx(4.0 * texel_area(plain), rel=DENSITY_TOLERANCE)


@needs_xatlas
def test_resolution_packs_one_square_atlas():
    mesh, layout = add_lightmap_uvs(table_mesh(), resolution=64, padding=PADDING)
    assert (layout.width, layout.height) == (64, 64)
    assert layout.uvs.min() >= 0.0 and layout.uvs.max() <= 1.0
    texel_map = raster(mesh, 64, 64)
    assert texel_map.report["overlapping_texels"] == 0
    assert texel_map.report["clipped_triangles"] == 0
    assert chart_gap(texel_map.chart, 2 * PADDING + 2) >= 2 * PADDING + 1


@needs_xatlas
def test_same_input_same_layout():
    first = lightmap_uvs(*scenes.box(*TABLE), texels_per_metre=TEXELS_PER_METRE)
    second = lightmap_uvs(*scenes.box(*TABLE), texels_per_metre=TEXELS_PER_METRE)
    np.testing.assert_array_equal(first.uvs, second.uvs)
    np.testing.assert_array_equal(first.triangles, second.triangles)


@needs_xatlas
def test_bake_through_the_layout_is_exact_under_a_uniform_world():
    """Every texel of a convex Lambert box under a uniform world sees the world over its whole
    hemisphere and holds exactly the world's radiance: the UVs put every texel on the box."""
    mesh, layout = add_lightmap_uvs(table_mesh(), texels_per_metre=32.0, padding=PADDING)
    scene = shgi.Scene()
    material = scene.add_material(shgi.Material(name="paint", base_color=(0.5, 0.6, 0.7),
                                                diffuse_model=shgi.DiffuseModel.LAMBERT))
    mesh.material_indices = np.full(len(layout.triangles), material)
    scene.add_instance(scene.add_mesh(mesh), np.eye(4), "table")
    scene.set_world(shgi.World(color=WORLD_COLOR, strength=WORLD_STRENGTH))
    scene.commit()
    texel_map = shgi.rasterize_texels(scene, 0, shgi.TexelRasterSettings(
        width=layout.width, height=layout.height))
    texels = shgi.bake_lightmap(scene, texel_map, shgi.LightmapSettings(samples=8, seed=2))
    np.testing.assert_array_equal(texels.baked, texel_map.coverage > 0)
    color = texels.color[texels.baked]
    expected = np.array(WORLD_COLOR) * WORLD_STRENGTH
    np.testing.assert_allclose(color, np.broadcast_to(expected, color.shape), rtol=ROUND_OFF,
                               atol=ROUND_OFF)


@needs_xatlas
def test_sun_room_table_bakes_through_xatlas_uvs():
    """The sun room's table has no UV map (only the room's quads get one); with xatlas's it
    bakes in the room: every covered texel is baked and lit, and lies on the table, on one of
    its six faces (texel positions inside the table's box, normals along a face's normal)."""
    room = scenes.sun_room(lightmap=True).scene
    index = [inst.name for inst in room.instances].index("table")
    inst = room.instances[index]
    original = room.meshes[inst.mesh_id]
    assert "LightmapUV" not in original.uv_sets
    mesh, layout = add_lightmap_uvs(original, texels_per_metre=32.0,
                                    world_from_object=inst.world_from_object, padding=PADDING)
    room.set_mesh(inst.mesh_id, mesh)  # the table, with its UV map, back into the room
    room.commit()
    scene = room
    texel_map = shgi.rasterize_texels(scene, index, shgi.TexelRasterSettings(
        width=layout.width, height=layout.height))
    shgi.unocclude(scene, texel_map)
    texels = shgi.bake_lightmap(scene, texel_map, shgi.LightmapSettings(samples=16, seed=1))
    assert texel_map.report["overlapping_texels"] == 0
    np.testing.assert_array_equal(texels.baked, texel_map.coverage > 0)
    baked = texels.baked
    assert np.isfinite(texels.color).all() and (texels.color >= 0.0).all()
    charts = texel_map.chart
    assert sorted(np.unique(charts[baked])) == list(range(6))
    assert all(texels.color[charts == c].mean() > 0.0 for c in range(6))
    # Where the texels lie: on the table (positions are texel means: inside its box) ...
    corners = np.asarray(original.positions)
    positions = texel_map.positions[baked]
    assert (positions >= corners.min(axis=0) - 1e-4).all()
    assert (positions <= corners.max(axis=0) + 1e-4).all()
    # ... and on its faces: each chart's normal is one of the six face normals.
    p, t = corners, np.asarray(original.triangles)
    faces = np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]])
    faces /= np.linalg.norm(faces, axis=1, keepdims=True)
    best = np.abs(texel_map.normals[baked] @ faces.T).max(axis=1)
    assert best.min() > 0.999


@needs_xatlas
def test_bad_input_names_the_fix():
    positions, triangles = scenes.box(*TABLE)
    with pytest.raises(ValueError, match="give texels_per_metre > 0 or resolution > 0"):
        lightmap_uvs(positions, triangles)
    with pytest.raises(ValueError, match="triangles index vertices 0..8, but there are 8"):
        lightmap_uvs(positions, np.vstack([triangles, [[0, 1, 8]]]), resolution=32)
    with pytest.raises(ValueError, match="positions must be finite"):
        lightmap_uvs(positions[:, :2], triangles, resolution=32)


def test_without_xatlas_it_raises_naming_the_pip_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "xatlas", None)  # makes `import xatlas` fail
    with pytest.raises(ImportError, match=r"-m pip install( --break-system-packages)? xatlas"):
        lightmap_uvs(*scenes.box(*TABLE), resolution=32)
