"""Tests of shgi.bake (lightmaps to files, shards, merging) and of ``python -m shgi bake``.

Ground truth first: a Lambert plane under a uniform world bakes to the world's radiance exactly
(native/bake/lightmap_baker.h: the texel holds E / pi), also through a UV map that xatlas lays out
for a mesh without one (BakeOptions.lightmap_uvs, the CLI's --uv xatlas). The file layout is
checked against the in-memory lightmap (rows flipped to top-first), shard bakes against the single
bake byte for byte (docs/architecture.md, determinism), and every error against the message a user would read.
Sizes and sample counts are small: the whole file runs in well under a minute on two cores.
"""

import base64
import dataclasses
import importlib.util
import json
import math
import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import time

import numpy as np
import pytest

import shgi
from shgi import bake
from blender_support import REPO_ROOT
from test_io import decode_png

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/scenes.py, the project's test scenes)

# Radiance of the uniform world in the physical checks (W m^-2 sr^-1): colour x strength.
WORLD_COLOR, WORLD_STRENGTH = (0.2, 0.4, 0.8), 2.0
WORLD_RADIANCE = np.array(WORLD_COLOR) * WORLD_STRENGTH
ALBEDO = (0.5, 0.6, 0.7)
# With a Lambert lobe and cosine-distributed hemisphere rays, next-event estimation of a uniform
# world and the hemisphere ray both return L for every sample (f cos / pdf = 1): the bake is
# exact up to float32 round-off in the sums. (The Principled BSDF's Burley diffuse is not: its
# retro-reflection gives an albedo of about 1.006 at roughness 0.5, as in Cycles.)
ROUND_OFF = 1e-5
# A statistical check passes when the estimate lies within this many standard errors of the
# truth: an unbiased estimator fails it about once in 1.7 million seeds.
STANDARD_ERRORS = 5.0
# Real SH basis constants (shgi.sh conventions): Y00 and the factor of the l = 1 functions.
Y00, Y1 = 0.282095, 0.488603
# Lightmap half-float layers hold about 3 significant digits.
HALF = np.float16

SMALL_SETTINGS = dict(samples=8, seed=3)


def plane_scene(uvs=None, world=(WORLD_COLOR, WORLD_STRENGTH), lights=(), lightmap_uv=True,
                placements=(("plane", np.eye(4)),)):
    """A 2 x 2 m Lambert plane at z = 0 facing +Z whose LightmapUV maps (x, y) to
    ((x+1)/2, (y+1)/2) (or `uvs`; no UV map at all without `lightmap_uv`), under a uniform
    world, committed; one object per (name, world_from_object) of `placements`."""
    scene = shgi.Scene()
    material = scene.add_material(shgi.Material(name="paint", base_color=ALBEDO,
                                                diffuse_model=shgi.DiffuseModel.LAMBERT))
    positions = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    if uvs is None:
        uvs = (positions[:, :2] + 1.0) / 2.0
    mesh = scene.add_mesh(positions=positions, triangles=np.array([[0, 1, 2], [0, 2, 3]]),
                          name="plane",
                          uvs={"LightmapUV": np.asarray(uvs, np.float32)} if lightmap_uv else None,
                          material_indices=np.full(2, material))
    for name, world_from_object in placements:
        scene.add_instance(mesh, world_from_object, name)
    color, strength = world
    scene.set_world(shgi.World(color=color, strength=strength))
    for light in lights:
        scene.add_light(light)
    scene.commit()
    return scene


def point_light(x, y, z, power):
    light = shgi.Light(name="lamp", type=shgi.LightType.POINT, power=power, radius=0.0)
    light.world_from_light = np.array([[1, 0, 0, x], [0, 1, 0, y], [0, 0, 1, z], [0, 0, 0, 1]],
                                      np.float32)
    return light


def options(**settings):
    return bake.BakeOptions(settings=shgi.LightmapSettings(**{**SMALL_SETTINGS, **settings}))


def plane_job(size=8):
    return bake.BakeJob(instance=0, name="plane", width=size, height=size)


def written_files(folder):
    """{file name: bytes} of the lightmaps (EXR, PNG) in a folder."""
    return {name: (folder / name).read_bytes() for name in sorted(os.listdir(folder))
            if name.endswith((".exr", ".png"))}


# --- the physics: a plane under a uniform world ---------------------------------------------------

@pytest.mark.parametrize("content, expected", [
    ("DIRECT_INDIRECT", WORLD_RADIANCE),
    ("DIRECT", WORLD_RADIANCE),
    ("INDIRECT", np.zeros(3)),  # nothing for the world's light to scatter from
    ("FULL", np.array(ALBEDO) * WORLD_RADIANCE),  # Cycles' COLOR times the light
])
def test_plane_under_a_uniform_world_bakes_to_its_radiance(tmp_path, content, expected):
    scene = plane_scene()
    [lightmap] = bake.bake_scene(scene, [plane_job()], options(content=content), str(tmp_path))
    color = lightmap.color.reshape(-1, 3)
    np.testing.assert_allclose(color, np.broadcast_to(expected, color.shape), rtol=ROUND_OFF,
                               atol=ROUND_OFF)
    # What the file holds is the same light, to half precision.
    stored = shgi.read_exr(tmp_path / "plane.exr")["Lightmap"].reshape(-1, 3)
    np.testing.assert_array_equal(stored, color.astype(HALF).astype(np.float32))


def test_directional_sh_of_a_uniform_world_over_the_upper_hemisphere():
    """The L1 SH of radiance L over the hemisphere z > 0: c0 = L Y00 2 pi, c2 (z) = L Y1 pi,
    c1 (y) = c3 (x) = 0. Directional bakes sample the hemisphere uniformly, so the texels scatter
    around these values; their mean must lie within STANDARD_ERRORS of them."""
    scene = plane_scene()
    _, texels = bake.bake_object(scene, plane_job(), options(samples=256, directional=True))
    sh = texels.sh.reshape(-1, 4, 3) / WORLD_RADIANCE  # per unit radiance
    expected = [Y00 * 2 * math.pi, 0.0, Y1 * math.pi, 0.0]
    for coefficient, truth in enumerate(expected):
        values = sh[:, coefficient, :]
        standard_error = values.std(axis=0) / math.sqrt(len(values))
        error = np.abs(values.mean(axis=0) - truth)
        assert np.all(error <= STANDARD_ERRORS * standard_error + ROUND_OFF), (
            f"SH c{coefficient}: mean {values.mean(axis=0)}, expected {truth} "
            f"+- {STANDARD_ERRORS} x {standard_error}")


# --- L2 directional lightmaps (LightmapSettings.sh_order = 2) --------------------------------

SUN_STRENGTH = 3.0
SUN_TO = (0.3, -0.5, 0.812404)  # towards the sun, unit; 35.7 degrees from the zenith


def sun_over_a_plane(angle=0.0):
    """The Lambert plane under a black world and one sun of strength 3 W/m^2 and angular
    diameter `angle` shining from SUN_TO: with angle 0 the radiance arriving at every texel is
    a delta of weight 3 in that direction, whose SH (any order) is 3 Y_lm(SUN_TO)."""
    sun = shgi.Light(name="sun", type=shgi.LightType.SUN, strength=SUN_STRENGTH,
                     angle=angle)
    to_sun = np.array(SUN_TO) / np.linalg.norm(SUN_TO)
    # A sun's light travels along its local -Z, so its local +Z points at the sun.
    x = np.cross((0.0, 0.0, 1.0), to_sun)
    x /= np.linalg.norm(x)
    y = np.cross(to_sun, x)
    place = np.eye(4, dtype=np.float32)
    place[:3, 0], place[:3, 1], place[:3, 2] = x, y, to_sun
    sun.world_from_light = place
    return plane_scene(world=((0.0, 0.0, 0.0), 0.0), lights=[sun]), to_sun


def test_l2_bake_of_a_sun_reproduces_its_sh():
    """A known radiance field: a sun of angle 0 (a delta, S Y_lm(w) in every band) over a plane,
    baked DIRECT at L2 by the path tracer: every texel's 9 coefficients per channel equal
    S Y_lm(w) within float round-off, and the L1 bake's 4 equal the L2 bake's first 4 bit for
    bit (the order changes what is stored, not how the texel is sampled)."""
    scene, to_sun = sun_over_a_plane()
    expected = SUN_STRENGTH * shgi.sh.eval(to_sun[None, :], 2)[0]
    assert abs(expected[6]) > 0.1 and abs(expected[4]) > 0.05  # band 2 is not zero here
    _, l2 = bake.bake_object(scene, plane_job(), options(content="DIRECT", directional=True,
                                                          sh_order=2))
    assert l2.sh_order == 2 and l2.sh.shape == (8, 8, 9, 3)
    sh = l2.sh.reshape(-1, 9, 3)
    np.testing.assert_allclose(sh, np.broadcast_to(expected[None, :, None], sh.shape),
                               rtol=1e-5, atol=1e-6)
    _, l1 = bake.bake_object(scene, plane_job(), options(content="DIRECT", directional=True))
    assert l1.sh_order == 1 and l1.sh.shape == (8, 8, 4, 3)
    np.testing.assert_array_equal(l1.sh, l2.sh[:, :, :4, :])
    np.testing.assert_array_equal(l1.color, l2.color)


def test_l2_bake_of_a_uniform_world_has_no_band_two():
    """Radiance L over the hemisphere z > 0 at L2: c0 = L Y00 2 pi, c2 = L Y1 pi, and every
    other coefficient 0 — band 2 too (the integral of P2 over a hemisphere vanishes) — within
    STANDARD_ERRORS of the texels' mean, as the L1 test above."""
    scene = plane_scene()
    _, texels = bake.bake_object(scene, plane_job(), options(samples=256, directional=True,
                                                             sh_order=2))
    sh = texels.sh.reshape(-1, 9, 3) / WORLD_RADIANCE
    expected = [Y00 * 2 * math.pi, 0.0, Y1 * math.pi] + [0.0] * 6
    for coefficient, truth in enumerate(expected):
        values = sh[:, coefficient, :]
        standard_error = values.std(axis=0) / math.sqrt(len(values))
        error = np.abs(values.mean(axis=0) - truth)
        assert np.all(error <= STANDARD_ERRORS * standard_error + ROUND_OFF), (
            f"SH c{coefficient}: mean {values.mean(axis=0)}, expected {truth}")


@pytest.mark.parametrize("method", ["PHOTON_LATTICE", "INSTANT_GI"])
def test_l2_bakes_from_fields(method):
    """Every bake source writes L2: a field's bake of the sun over the plane (the sun's direct
    light by next-event estimation, the field's indirect light nil on a lone plane; INSTANT_GI
    with filter_direct carries the sun itself, as one delta per set through its interleaved
    sets and window) reproduces the sun's 9 coefficients."""
    scene, to_sun = sun_over_a_plane()
    expected = SUN_STRENGTH * shgi.sh.eval(to_sun[None, :], 2)[0]
    if method == "INSTANT_GI":
        solver = shgi.InstantGi(scene, shgi.InstantGiSettings(seed=1, filter_direct=True))
    else:
        solver = shgi.make_solver(method, scene, shgi.method(method).settings_type(seed=1))
    solver.refine()
    _, texels = bake.bake_object(scene, plane_job(), options(content="DIRECT_INDIRECT",
                                                             directional=True, sh_order=2),
                                 solver.current_field())
    sh = texels.sh.reshape(-1, 9, 3)
    np.testing.assert_allclose(sh, np.broadcast_to(expected[None, :, None], sh.shape),
                               rtol=1e-4, atol=1e-5)


def test_l2_exr_layers_and_refusals(tmp_path):
    """An L2 bake writes SH.c0 .. SH.c8 (float), the L1 layers first; sh_order outside 1..2 is
    refused naming the field; shards of another order do not merge; OIDN refuses L2."""
    scene, _ = sun_over_a_plane()
    [lightmap] = bake.bake_scene(scene, [plane_job(8)],
                                 options(directional=True, sh_order=2), str(tmp_path))
    info = shgi.read_exr_info(tmp_path / "plane.exr")
    assert info["channels"][5:] == [(f"SH.c{i}.{c}", "float") for i in range(9) for c in "RGB"]
    layers = shgi.read_exr(tmp_path / "plane.exr")
    for i in range(9):
        np.testing.assert_array_equal(layers[f"SH.c{i}"], lightmap.sh[::-1, :, i, :])
    for bad in (0, 3):
        with pytest.raises(ValueError, match="sh_order"):
            shgi.LightmapSettings(sh_order=bad).validate()
    l1 = shgi.bake_lightmap(scene, shgi.rasterize_texels(scene, 0, shgi.TexelRasterSettings(
        width=8, height=8, uv_set="LightmapUV")), shgi.LightmapSettings(samples=4,
                                                                          directional=True))
    l2 = shgi.LightmapTexels(l1.color, l1.variance, np.zeros_like(l1.baked),
                             np.zeros((8, 8, 9, 3), np.float32))
    assert l2.sh_order == 2
    with pytest.raises(ValueError, match="L2 directional"):
        shgi.merge_lightmap(l2, l1)
    with pytest.raises(ValueError, match="sh"):
        shgi.LightmapTexels(l1.color, l1.variance, l1.baked, np.zeros((8, 8, 5, 3)))
    with pytest.raises(ValueError, match="L1 directional lightmaps only"):
        bake.denoise_method(dataclasses.replace(
            options(directional=True, sh_order=2), denoise="OIDN"))


# --- the file layout ------------------------------------------------------------------------------

def test_exr_layers_pixel_types_row_order_and_png(tmp_path):
    # A lamp just above the plane's v = 0 edge (y = -1): the bottom rows of the lightmap (row 0
    # in memory) are far brighter than the top ones. The UV square is inset by 2 texels so the
    # border is padding (coverage 0, light from dilation).
    size, border_texels = 16, 2
    inset = border_texels / size
    uvs = np.array([[inset, inset], [1 - inset, inset], [1 - inset, 1 - inset],
                    [inset, 1 - inset]])
    scene = plane_scene(uvs=uvs, world=((0.0, 0.0, 0.0), 0.0),
                        lights=[point_light(0.0, -0.9, 0.3, 50.0)])
    [lightmap] = bake.bake_scene(scene, [plane_job(size)], options(directional=True),
                                 str(tmp_path))
    exr, png = tmp_path / "plane.exr", tmp_path / "plane.png"
    assert lightmap.paths == [str(exr), str(png)]

    info = shgi.read_exr_info(exr)
    assert (info["width"], info["height"]) == (size, size)
    expected_channels = ([(f"Lightmap.{c}", "half") for c in "RGB"]
                         + [("Variance.V", "float"), ("Coverage.V", "float")]
                         + [(f"SH.c{i}.{c}", "float") for i in range(4) for c in "RGB"])
    assert info["channels"] == expected_channels

    # In memory row 0 is v = 0: the lit edge comes first.
    luminance = lightmap.color.mean(axis=2)
    first, last = border_texels, size - border_texels - 1  # covered rows
    assert luminance[first].mean() > 4 * luminance[last].mean()
    layers = shgi.read_exr(exr)
    # In the file the top row comes first: every layer is the in-memory one upside down.
    np.testing.assert_array_equal(layers["Lightmap"],
                                  lightmap.color[::-1].astype(HALF).astype(np.float32))
    np.testing.assert_array_equal(layers["Variance"][:, :, 0], lightmap.variance[::-1])
    np.testing.assert_array_equal(layers["Coverage"][:, :, 0], lightmap.coverage[::-1])
    for i in range(4):
        np.testing.assert_array_equal(layers[f"SH.c{i}"], lightmap.sh[::-1, :, i, :])
    assert layers["Lightmap"][last].mean() > 4 * layers["Lightmap"][first].mean()  # lit edge last
    # The padding: no coverage, but dilated light, so bilinear lookups never read black.
    border = np.ones((size, size), bool)
    border[first:last + 1, first:last + 1] = False
    assert np.all(lightmap.coverage[border] == 0.0) and np.all(lightmap.coverage[~border] > 0.0)
    assert np.all(lightmap.color[border].max(axis=1) > 0.0)

    pixels, _ = decode_png(png)
    assert pixels.shape == (size, size, 3)
    expected = np.round(255 * shgi.srgb_from_linear(lightmap.color[::-1].copy()))
    assert np.abs(pixels.astype(int) - expected).max() <= 1


def test_no_png_when_not_asked(tmp_path):
    scene = plane_scene()
    bake.bake_scene(scene, [plane_job()], dataclasses.replace(options(), png=False), str(tmp_path))
    assert sorted(os.listdir(tmp_path)) == ["plane.exr"]


def test_denoise_option_runs_the_chosen_denoiser_before_dilation(tmp_path):
    scene = plane_scene(lights=[point_light(0.3, -0.2, 0.8, 40.0)])
    raw = bake.bake_scene(scene, [plane_job(16)], options(), str(tmp_path / "raw"))[0]
    shgi_filter = bake.bake_scene(scene, [plane_job(16)],
                                  dataclasses.replace(options(), denoise="SHGI"),
                                  str(tmp_path / "shgi"))[0]
    assert not np.array_equal(raw.color, shgi_filter.color)
    with pytest.raises(ValueError, match="NONE, SHGI, OIDN"):
        bake.bake_scene(scene, [plane_job()], dataclasses.replace(options(), denoise="BLUR"),
                        str(tmp_path / "bad"))
    pytest.importorskip("pyoidn", reason="pyoidn is not installed (make deps installs it)")
    oidn = bake.bake_scene(scene, [plane_job(16)], dataclasses.replace(options(), denoise="OIDN"),
                           str(tmp_path / "oidn"))[0]
    assert np.isfinite(oidn.color).all() and not np.array_equal(raw.color, oidn.color)
    # The denoised light keeps the raw bake's level.
    assert abs(oidn.color.mean() / raw.color.mean() - 1.0) < 0.05


# --- progress -------------------------------------------------------------------------------------

def test_progress_only_moves_forward_and_ends_at_one(tmp_path):
    scene = plane_scene()
    reports = []
    progress = bake.BakeProgress(lambda fraction, stage: reports.append((fraction, stage)))
    jobs = [plane_job(16)]
    bake.bake_scene(scene, jobs, dataclasses.replace(options(), filter=True), str(tmp_path),
                    progress=progress)
    fractions = [fraction for fraction, _ in reports]
    assert all(b >= a for a, b in zip(fractions, fractions[1:])), fractions
    assert reports[-1] == (1.0, "done") and progress.fraction == 1.0
    assert any("baking" in stage for _, stage in reports)


# --- shards ---------------------------------------------------------------------------------------

SUN_ROOM_JOBS = [("floor", 48, 32), ("back", 32, 32), ("left_wall_2", 16, 16)]
SHARDS = 4


@pytest.fixture(scope="module")
def sun_room():
    """The sun room with inward walls and LightmapUV, and three objects of different sizes:
    6 + 4 + 1 tiles of 16 texels, so some shards hold nothing of the small wall."""
    scene = scenes.sun_room(0.25, lightmap=True).scene
    scene.commit()
    index = {inst.name: i for i, inst in enumerate(scene.instances)}
    jobs = [bake.BakeJob(index[name], name, w, h) for name, w, h in SUN_ROOM_JOBS]
    return scene, jobs


def sun_room_options(**settings):
    """Directional and filtered: the merge must reproduce every layer and the filter's input."""
    return dataclasses.replace(options(directional=True, tile_size=16, **settings), filter=True)


@pytest.fixture(scope="module")
def sharded_bake(sun_room, tmp_path_factory):
    """A single bake and a 4-shard bake + merge of the sun room: (single dir, farm dir)."""
    scene, jobs = sun_room
    single = tmp_path_factory.mktemp("single")
    farm = tmp_path_factory.mktemp("farm")
    bake.bake_scene(scene, jobs, sun_room_options(), str(single))
    for shard in range(SHARDS):
        paths = bake.bake_scene(scene, jobs, sun_room_options(), str(farm), shard=(shard, SHARDS))
        assert paths == [bake.shard_path(str(farm), job.name, shard, SHARDS) for job in jobs]
    bake.merge_shards(scene, jobs, sun_room_options(), str(farm), SHARDS)
    return single, farm


def test_merged_shards_are_byte_identical_to_a_single_bake(sharded_bake):
    single, farm = sharded_bake
    expected = written_files(single)
    assert sorted(expected) == sorted(f"{name}.{ext}" for name, _, _ in SUN_ROOM_JOBS
                                      for ext in ("exr", "png"))
    merged = written_files(farm)
    assert sorted(merged) == sorted(expected)
    for name in expected:
        assert merged[name] == expected[name], f"{name} differs between the merge and the bake"
    # The bake is not trivially black: the sun lights the floor through the window.
    floor = shgi.read_exr(single / "floor.exr")["Lightmap"]
    assert floor.max() > 10 * np.median(floor) > 0.0


def copy_farm(farm, tmp_path):
    """A copy of the shard files (tests below damage them)."""
    copy = tmp_path / "farm"
    shutil.copytree(farm / "shards", copy / "shards")
    return copy


def test_merge_with_a_missing_shard_file_names_it(sun_room, sharded_bake, tmp_path):
    scene, jobs = sun_room
    farm = copy_farm(sharded_bake[1], tmp_path)
    missing = bake.shard_path(str(farm), "back", 2, SHARDS)
    os.remove(missing)
    with pytest.raises(OSError) as info:
        bake.merge_shards(scene, jobs, sun_room_options(), str(farm), SHARDS)
    assert missing in str(info.value) and "bake that shard again" in str(info.value)


def test_merge_with_a_damaged_shard_file_names_it(sun_room, sharded_bake, tmp_path):
    scene, jobs = sun_room
    farm = copy_farm(sharded_bake[1], tmp_path)
    damaged = bake.shard_path(str(farm), "floor", 1, SHARDS)
    with open(damaged, "r+b") as file:
        file.truncate(100)
    with pytest.raises(OSError, match="damaged") as info:
        bake.merge_shards(scene, jobs, sun_room_options(), str(farm), SHARDS)
    assert damaged in str(info.value)


def test_merge_refuses_a_duplicated_shard(sun_room, sharded_bake, tmp_path):
    """Shard 0's file copied over shard 1's: its texels would overlap shard 0's and shard 1's
    would be missing."""
    scene, jobs = sun_room
    farm = copy_farm(sharded_bake[1], tmp_path)
    duplicate = bake.shard_path(str(farm), "floor", 1, SHARDS)
    shutil.copyfile(bake.shard_path(str(farm), "floor", 0, SHARDS), duplicate)
    with pytest.raises(ValueError) as info:
        bake.merge_shards(scene, jobs, sun_room_options(), str(farm), SHARDS)
    assert duplicate in str(info.value) and "shard 0 (merge: 1)" in str(info.value)


def test_merging_overlapping_texels_is_refused(sun_room):
    """The native merge itself: the same shard merged twice overlaps itself."""
    scene, jobs = sun_room
    tiles = shgi.lightmap_shard_tiles(jobs[0].width, jobs[0].height, 16, 0, SHARDS)
    _, part = bake.bake_object(scene, jobs[0], sun_room_options(samples=1), tiles=tiles)
    h, w = part.height, part.width
    merged = shgi.LightmapTexels(np.zeros((h, w, 3)), np.zeros((h, w)), np.zeros((h, w), bool),
                                 np.zeros((h, w, 4, 3)))
    shgi.merge_lightmap(merged, part)
    with pytest.raises(ValueError, match="baked twice; shards must not overlap"):
        shgi.merge_lightmap(merged, part)


def test_merge_refuses_shards_baked_with_other_settings(sun_room, sharded_bake, tmp_path):
    scene, jobs = sun_room
    farm = copy_farm(sharded_bake[1], tmp_path)
    # Shard 3 baked again with more samples: its texels would not match the other shards'.
    bake.bake_scene(scene, jobs, sun_room_options(samples=16), str(farm), shard=(3, SHARDS))
    with pytest.raises(ValueError) as info:
        bake.merge_shards(scene, jobs, sun_room_options(), str(farm), SHARDS)
    message = str(info.value)
    assert bake.shard_path(str(farm), "floor", 3, SHARDS) in message
    assert "samples 16 (merge: 8)" in message
    # A shard baked with fewer objects deals the tiles out differently: refused too.
    bake.bake_scene(scene, jobs[:2], sun_room_options(), str(farm), shard=(3, SHARDS))
    with pytest.raises(ValueError, match=r"objects \[\['floor', 48, 32\], \['back', 32, 32\]\]"):
        bake.merge_shards(scene, jobs, sun_room_options(), str(farm), SHARDS)
    # Merging with another resolution than the shards were baked at is refused the same way.
    bigger = [bake.BakeJob(job.instance, job.name, 2 * job.width, job.height) for job in jobs]
    with pytest.raises(ValueError, match=r"width 48 \(merge: 96\)"):
        bake.merge_shards(scene, bigger, sun_room_options(), str(sharded_bake[1]), SHARDS)


# Final gather against the path tracer on the sun room's floor and back wall (lightmap means,
# PATH_TRACE 512 samples, the field 64), as the project's agreement tests ask: within 5%. The
# photon lattice at its defaults reads the back wall 5% dark with or without a gather (its own
# bias; docs/baking.md), so only the probe grid is held to it here.
GATHER_AGREEMENT = 0.05


@pytest.mark.parametrize("method", ["PROBE_GRID"])
def test_final_gather_bake_agrees_with_the_path_tracer(sun_room, method, tmp_path):
    """A bake with final_gather reads the field where each sample's gather ray lands; the
    field, solved one bounce shallower for it, gives lightmaps whose means agree with the path
    tracer's; final_gather is part of the settings every shard must share."""
    scene, _jobs = sun_room
    index = {inst.name: i for i, inst in enumerate(scene.instances)}
    jobs = [bake.BakeJob(index[name], name, 16, 16) for name in ("floor", "back")]

    def means(field, samples, gather):
        baked = bake.bake_scene(scene, jobs, options(samples=samples, final_gather=gather),
                                str(tmp_path / f"{method}-{gather}-{field is None}"), field)
        return np.array([lm.color[lm.coverage > 0].mean(axis=0) for lm in baked])

    reference = means(None, 512, False)
    field = bake.solve_field(scene, method, gather=True)
    np.testing.assert_allclose(means(field, 64, True), reference, rtol=GATHER_AGREEMENT)
    assert "final_gather" in bake._SHARD_SETTINGS


def test_instant_gi_bake_interleaves_its_sets_and_shards_merge_exactly(sun_room, tmp_path):
    """An INSTANT_GI bake reads one VPL set per texel (the interleave pattern over the texels)
    and filters within UV charts (issue 50, item 7; the closed-form checks are C++
    InterleavedBake.*): its means agree with the same VPLs gathered whole at every texel (one
    set holding them all), and its shards, whose filter windows reach into each other's tiles,
    merge byte-identically to a single bake."""
    scene, jobs = sun_room
    interleaved = shgi.default_settings("INSTANT_GI")
    interleaved.sets_x = interleaved.sets_y = 4
    interleaved.photons_per_set = 64
    whole = shgi.default_settings("INSTANT_GI")
    whole.sets_x = whole.sets_y = 1
    whole.photons_per_set = 16 * 64
    run = options(content="INDIRECT", tile_size=16)

    def bake_with(settings, folder, shard=None):
        field = bake.solve_field(scene, "INSTANT_GI", settings=settings)
        return bake.bake_scene(scene, jobs, run, str(tmp_path / folder), field, shard=shard)

    means = [np.array([lm.color[lm.coverage > 0].mean(axis=0) for lm in bake_with(s, name)])
             for s, name in ((interleaved, "interleaved"), (whole, "whole"))]
    assert means[1].min() > 0.0
    np.testing.assert_allclose(means[0], means[1], rtol=0.03)
    for shard in range(SHARDS):
        bake_with(interleaved, "farm", shard=(shard, SHARDS))
    bake.merge_shards(scene, jobs, run, str(tmp_path / "farm"), SHARDS)
    single, merged = written_files(tmp_path / "interleaved"), written_files(tmp_path / "farm")
    assert sorted(merged) == sorted(single)
    for name in single:
        assert merged[name] == single[name], f"{name} differs between the merge and the bake"


def test_solve_field_for_a_gather_is_one_bounce_shallower():
    """GATHER_DEPTH_FIELDS: for every built-in field method (INSTANT_GI was once left out, and a
    gathered bake from it carried a bounce too many), the settings solve_field(gather=True) uses
    hold one diffuse bounce less than the method's, never below the least the method solves."""
    native = [row for row in shgi.methods()
              if row.solves_field and getattr(shgi, row.settings_type.__name__, None)
              is row.settings_type]
    assert len(native) >= 5
    for row in native:
        method = row.identifier
        name, least = bake.GATHER_DEPTH_FIELDS[row.settings_type.__name__]
        settings = shgi.default_settings(method)
        assert getattr(settings, name) - 1 >= least
        shallow = bake._gather_settings(settings)
        assert getattr(shallow, name) == getattr(settings, name) - 1
        setattr(settings, name, least)
        assert getattr(bake._gather_settings(settings), name) == least


def test_bad_shard_numbers_are_refused(sun_room, tmp_path):
    scene, jobs = sun_room
    for shard in [(4, 4), (-1, 4), (0, 0)]:
        with pytest.raises(ValueError, match="use i/N"):
            bake.bake_scene(scene, jobs, sun_room_options(), str(tmp_path), shard=shard)
    with pytest.raises(ValueError, match="shards must be a whole number >= 1, got 0"):
        bake.merge_shards(scene, jobs, sun_room_options(), str(tmp_path), 0)


def test_shards_split_tiles_over_all_objects():
    """Tiles are counted over the objects in order and dealt out i mod N: every tile lands in
    exactly one shard."""
    jobs = [bake.BakeJob(0, name, w, h) for name, w, h in SUN_ROOM_JOBS]
    opts = options(tile_size=16)
    split = [bake._shard_tiles(jobs, opts, shard, SHARDS) for shard in range(SHARDS)]
    for k, job in enumerate(jobs):
        count = shgi.lightmap_tile_count(job.width, job.height, 16)
        dealt = sorted(tile for shard in split for tile in shard[k])
        assert dealt == list(range(count))
    assert [len(split[s][2]) for s in range(SHARDS)] == [0, 0, 1, 0]  # global tile 10


# --- lightmap UVs laid out by xatlas --------------------------------------------------------------

needs_xatlas = pytest.mark.skipif(
    importlib.util.find_spec("xatlas") is None,
    reason="xatlas is not installed for this Python: run `make deps` or "
           "`python3 -m pip install xatlas`")
# Texels per metre for the 2 x 2 m plane: resolution_for_density gives sqrt(2 x 4 m^2) x 8 = 22.6,
# rounded up to 24 texels a side.
XATLAS_DENSITY, XATLAS_SIDE = 8.0, 24
# A plane scaled by 2 (16 m^2): sqrt(32) x 8 = 45.3, rounded up to 48.
LARGE_SIDE = 48
SCALE_2_AT_X_5 = np.array([[2, 0, 0, 5], [0, 2, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1]], np.float32)


def test_resolution_for_density_counts_world_metres():
    """sqrt(2 x area) x density, rounded up to a multiple of 4, clamped; the same from the
    area alone (resolution_for_area: for surfaces not in a Scene yet, like the add-on's)."""
    scene = plane_scene(placements=(("plane", np.eye(4)), ("large", SCALE_2_AT_X_5)))
    assert bake.resolution_for_density(scene, 0, XATLAS_DENSITY) == XATLAS_SIDE
    assert bake.resolution_for_density(scene, 1, XATLAS_DENSITY) == LARGE_SIDE
    square = np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], np.float32)
    assert bake.surface_area(square, [[0, 1, 2], [0, 2, 3]]) == pytest.approx(4.0)
    assert bake.resolution_for_area(4.0, XATLAS_DENSITY) == XATLAS_SIDE
    assert bake.resolution_for_area(16.0, XATLAS_DENSITY) == LARGE_SIDE
    assert bake.resolution_for_area(16.0, XATLAS_DENSITY, 64, 128) == 64
    assert bake.resolution_for_area(1e6, XATLAS_DENSITY, 16, 128) == 128
    with pytest.raises(ValueError, match="texels_per_metre must be positive"):
        bake.resolution_for_area(4.0, 0.0)


def xatlas_options(**settings):
    return dataclasses.replace(options(**settings), lightmap_uvs="XATLAS")


def assert_world_radiance_on_the_charts(lightmap):
    """Every texel the UV map covers holds the uniform world's radiance (E / pi, exact)."""
    color = lightmap.color[lightmap.coverage > 0]
    assert len(color) > 0
    np.testing.assert_allclose(color, np.broadcast_to(WORLD_RADIANCE, color.shape),
                               rtol=ROUND_OFF, atol=ROUND_OFF)


def assert_coverage_is_the_reported_layout(lightmap):
    """The rasterizer's coverage of the baked UV map adds up to the reported layout's UV area,
    without overlaps: the lightmap was baked through that layout."""
    layout = lightmap.report["uv_layout"]
    height, width = lightmap.coverage.shape
    assert lightmap.report["overlapping_texels"] == 0
    assert lightmap.coverage.sum() == pytest.approx(layout["uv_coverage"] * width * height,
                                                    rel=1e-4)


def test_a_mesh_without_the_uv_map_is_refused_unless_xatlas_is_asked_for(tmp_path):
    scene = plane_scene(lightmap_uv=False)
    assert bake.jobs_for_scene(scene, "LightmapUV", texels_per_metre=XATLAS_DENSITY) == []
    with pytest.raises(ValueError, match=r"no UV map 'LightmapUV' on 'plane' \(has \[\]\): .*"
                                         "lightmap_uvs='XATLAS'"):
        bake.jobs_for_scene(scene, "LightmapUV", names=["plane"])
    with pytest.raises(ValueError, match="no UV map 'LightmapUV' on 'plane': add one, choose "
                                         "another UV map, or let xatlas lay one out"):
        bake.bake_scene(scene, [plane_job()], options(), str(tmp_path))
    with pytest.raises(ValueError, match="lightmap_uvs 'BLENDER': use one of EXISTING, XATLAS"):
        bake.bake_scene(scene, [plane_job()], dataclasses.replace(options(),
                                                                  lightmap_uvs="BLENDER"),
                        str(tmp_path))
    assert os.listdir(tmp_path) == [] and scene.meshes[0].uv_sets == {}


@needs_xatlas
def test_xatlas_lays_out_a_plane_without_uvs_that_bakes_to_its_radiance(tmp_path):
    scene = plane_scene(lightmap_uv=False)
    jobs = bake.jobs_for_scene(scene, "LightmapUV", texels_per_metre=XATLAS_DENSITY,
                               lightmap_uvs="XATLAS")
    assert jobs == [bake.BakeJob(0, "plane", XATLAS_SIDE, XATLAS_SIDE)]
    stages = []
    progress = bake.BakeProgress(lambda fraction, stage: stages.append(stage))
    [lightmap] = bake.bake_scene(scene, jobs, xatlas_options(), str(tmp_path), progress=progress)

    assert_world_radiance_on_the_charts(lightmap)
    assert_coverage_is_the_reported_layout(lightmap)
    layout = lightmap.report["uv_layout"]
    # One flat quad: one chart, as the rasterizer counts it too.
    assert layout["chart_count"] == 1 == lightmap.report["charts"]
    assert 0.0 < layout["uv_coverage"] <= layout["utilization"] <= 1.0
    assert (layout["width"], layout["height"]) == (XATLAS_SIDE, XATLAS_SIDE)
    assert layout["padding"] == bake.BakeOptions().uv_padding and layout["objects"] == ["plane"]
    # Packed as densely as the lightmap allows: at least the density asked for.
    assert layout["texels_per_metre"] >= XATLAS_DENSITY
    assert (f"plane: lightmap UVs by xatlas: 1 charts, utilization "
            f"{layout['utilization']:.2f} (24 x 24)") in stages
    # The mesh in the scene now has the UV map; a second bake lays out nothing again.
    assert list(scene.meshes[0].uv_sets) == ["LightmapUV"]
    assert bake.generate_lightmap_uvs(scene, jobs, xatlas_options()) == jobs
    stored = shgi.read_exr(tmp_path / "plane.exr")["Lightmap"]
    np.testing.assert_array_equal(stored, lightmap.color[::-1].astype(HALF).astype(np.float32))


@needs_xatlas
def test_a_mesh_two_objects_share_gets_one_layout_packed_for_the_smaller_lightmap(tmp_path):
    """The plane's mesh placed twice, once scaled by 2 (side by side, coplanar: neither shades
    the other): one layout, packed at the small object's 24 texels, serves both lightmaps."""
    scene = plane_scene(lightmap_uv=False,
                        placements=[("small", np.eye(4)), ("large", SCALE_2_AT_X_5)])
    jobs = bake.jobs_for_scene(scene, "LightmapUV", texels_per_metre=XATLAS_DENSITY,
                               lightmap_uvs="XATLAS")
    assert [(job.name, job.width) for job in jobs] == [("small", XATLAS_SIDE),
                                                        ("large", LARGE_SIDE)]
    small, large = bake.bake_scene(scene, jobs, xatlas_options(), str(tmp_path))
    assert small.report["uv_layout"] == large.report["uv_layout"]
    layout = small.report["uv_layout"]
    assert layout["width"] == XATLAS_SIDE and layout["objects"] == ["small", "large"]
    assert scene.stats()["meshes"] == 1
    for lightmap in (small, large):
        assert_world_radiance_on_the_charts(lightmap)
        assert_coverage_is_the_reported_layout(lightmap)
    assert large.coverage.shape == (LARGE_SIDE, LARGE_SIDE)


@needs_xatlas
def test_xatlas_shards_merge_like_a_single_bake_and_refuse_other_uv_options(tmp_path):
    """Every shard and the merge lay the mesh out again (here on fresh scenes): the layout is
    deterministic, so the merge is byte-identical to a single bake; shard files record the UV
    option and padding, so a merge with others is refused."""
    def fresh_jobs():
        scene = plane_scene(lightmap_uv=False)
        return scene, bake.jobs_for_scene(scene, "LightmapUV", texels_per_metre=XATLAS_DENSITY,
                                          lightmap_uvs="XATLAS")

    tiled = xatlas_options(tile_size=16)  # 4 tiles of the 24 x 24 lightmap
    bake.bake_scene(*fresh_jobs(), tiled, str(tmp_path / "single"))
    for shard in range(2):
        bake.bake_scene(*fresh_jobs(), tiled, str(tmp_path / "farm"), shard=(shard, 2))
    scene, jobs = fresh_jobs()
    with pytest.raises(ValueError, match="no UV map 'LightmapUV' on 'plane'"):
        bake.merge_shards(scene, jobs, options(tile_size=16), str(tmp_path / "farm"), 2)
    [merged] = bake.merge_shards(scene, jobs, tiled, str(tmp_path / "farm"), 2)
    assert merged.report["uv_layout"]["chart_count"] == 1
    assert written_files(tmp_path / "farm") == written_files(tmp_path / "single")
    # The scene now has the UV map, so only the shard files' record tells the bakes apart.
    with pytest.raises(ValueError, match=r"lightmap_uvs 'XATLAS' \(merge: 'EXISTING'\)"):
        bake.merge_shards(scene, jobs, options(tile_size=16), str(tmp_path / "farm"), 2)
    with pytest.raises(ValueError, match=r"uv_padding 2 \(merge: 3\)"):
        bake.merge_shards(scene, jobs, dataclasses.replace(tiled, uv_padding=3),
                          str(tmp_path / "farm"), 2)


@needs_xatlas
def test_uv_layouts_come_before_solving_an_indirect_light_field(tmp_path):
    """A field belongs to the scene it was solved for: laying out UVs after solving it is
    refused; laid out first, the bake through the field is exact as well."""
    scene = plane_scene(lightmap_uv=False)
    jobs = bake.jobs_for_scene(scene, "LightmapUV", resolution=16, lightmap_uvs="XATLAS")
    stale = bake.solve_field(scene, "PHOTON_LATTICE")
    with pytest.raises(ValueError, match="call generate_lightmap_uvs\\(scene, jobs, options\\) "
                                         "before solve_field"):
        bake.bake_scene(scene, jobs, xatlas_options(), str(tmp_path), stale)
    assert scene.meshes[0].uv_sets == {}
    jobs = bake.generate_lightmap_uvs(scene, jobs, xatlas_options())
    field = bake.solve_field(scene, "PHOTON_LATTICE")
    [lightmap] = bake.bake_scene(scene, jobs, xatlas_options(), str(tmp_path), field)
    assert_world_radiance_on_the_charts(lightmap)
    assert lightmap.report["uv_layout"]["width"] == 16


def test_xatlas_option_without_xatlas_raises_naming_the_pip_command(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "xatlas", None)  # makes `import xatlas` fail
    scene = plane_scene(lightmap_uv=False)
    with pytest.raises(ImportError, match=r"-m pip install( --break-system-packages)? xatlas"):
        bake.bake_scene(scene, [plane_job()], xatlas_options(), str(tmp_path))
    assert scene.meshes[0].uv_sets == {} and scene.committed
    assert os.listdir(tmp_path) == []


# --- errors from bake_scene -----------------------------------------------------------------------

def test_nothing_to_bake(tmp_path):
    with pytest.raises(ValueError, match="nothing to bake"):
        bake.bake_scene(plane_scene(), [], options(), str(tmp_path))


def test_a_scene_without_light_is_refused(tmp_path):
    dark = plane_scene(world=((0.0, 0.0, 0.0), 0.0))
    with pytest.raises(ValueError, match="the scene has no light"):
        bake.bake_scene(dark, [plane_job()], options(), str(tmp_path))
    # A portal only guides world sampling; with a black world it lights nothing.
    portal = shgi.Light(name="portal", type=shgi.LightType.AREA, portal=True, size_x=1.0)
    dark_with_portal = plane_scene(world=((0.0, 0.0, 0.0), 0.0), lights=[portal])
    with pytest.raises(ValueError, match="the scene has no light"):
        bake.bake_scene(dark_with_portal, [plane_job()], options(), str(tmp_path))
    assert os.listdir(tmp_path) == []


def test_an_object_whose_uv_map_covers_nothing(tmp_path):
    outside = np.array([[2.0, 2.0], [3.0, 2.0], [3.0, 3.0], [2.0, 3.0]])  # all beyond [0, 1]
    with pytest.raises(ValueError, match="object 'plane': its UV map 'LightmapUV' covers no "
                                         "texel of the 8 x 8 lightmap"):
        bake.bake_scene(plane_scene(uvs=outside), [plane_job()], options(), str(tmp_path))


def test_bad_padding_and_settings_are_value_errors(tmp_path):
    scene = plane_scene()
    with pytest.raises(ValueError, match="padding"):
        bake.bake_scene(scene, [plane_job()], dataclasses.replace(options(), padding=-1),
                        str(tmp_path))
    with pytest.raises(ValueError, match="samples"):
        bake.bake_scene(scene, [plane_job()], options(samples=0), str(tmp_path))


# --- the command line -----------------------------------------------------------------------------

# glTF constants (glTF 2.0 spec, 3.6.2): component types and the point light's units.
FLOAT, UNSIGNED_SHORT = 5126, 5123
PBR_WATTS_TO_LUMENS = 683.0  # Blender's glTF importer: lm per W
LAMP_POWER = 300.0  # W


def face(center, normal, tangent, half):
    """4 corners (glTF coordinates) of a square facing `normal` (CCW seen from the front)."""
    c, n, u = (np.asarray(v, np.float64) for v in (center, normal, tangent))
    v = np.cross(n, u)  # u x v = n
    return [c + half * (-u - v), c + half * (u - v), c + half * (u + v), c + half * (-u + v)]


def room_gltf(lightmap_uv=True, lamp=True):
    """A glTF (Y up) of a 4 x 4 m floor and a 0.8 m box on it, each with TEXCOORD_0 (every face
    on the whole unit square: overlapping, useless for a lightmap) and TEXCOORD_1 (a lightmap
    layout without overlaps), lit by a KHR_lights_punctual point light 2.5 m up (without
    `lamp`, its node is left out, as an exporter drops the lights it cannot write)."""
    floor = face((0, 0, 0), (0, 1, 0), (1, 0, 0), 2.0)
    box = []
    for axis in range(3):
        for sign in (1.0, -1.0):
            normal = np.zeros(3)
            normal[axis] = sign
            tangent = np.zeros(3)
            tangent[(axis + 1) % 3] = 1.0
            box += face(np.array((0.5, 0.4, 0.3)) + 0.4 * normal, normal, tangent, 0.4)
    unit = [(0, 0), (1, 0), (1, 1), (0, 1)]
    # The box's faces in a 3 x 2 grid of cells, each face inset by a tenth of its cell.
    atlas = [((k % 3 + 0.1 + 0.8 * u) / 3, (k // 3 + 0.1 + 0.8 * v) / 2)
             for k in range(6) for u, v in unit]
    meshes = [("Floor", floor, unit, unit), ("Box", box, unit * 6, atlas)]
    data, views, accessors, gltf_meshes = b"", [], [], []

    def add(values, fmt, kind, count, component, bounds=False):
        nonlocal data
        blob = struct.pack(f"<{len(values)}{fmt}", *values)
        blob += b"\0" * (-len(blob) % 4)
        views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(blob)})
        accessor = {"bufferView": len(views) - 1, "componentType": component, "count": count,
                    "type": kind}
        if bounds:
            points = np.reshape(values, (count, 3))
            accessor["min"], accessor["max"] = points.min(0).tolist(), points.max(0).tolist()
        accessors.append(accessor)
        data += blob
        return len(accessors) - 1

    for name, corners, uv0, uv1 in meshes:
        attributes = {
            "POSITION": add(np.ravel(corners).tolist(), "f", "VEC3", len(corners), FLOAT, True),
            "TEXCOORD_0": add(np.ravel(uv0).tolist(), "f", "VEC2", len(uv0), FLOAT),
        }
        if lightmap_uv:
            attributes["TEXCOORD_1"] = add(np.ravel(uv1).tolist(), "f", "VEC2", len(uv1), FLOAT)
        indices = [q + i for q in range(0, len(corners), 4) for i in (0, 1, 2, 0, 2, 3)]
        gltf_meshes.append({"name": name, "primitives": [{
            "attributes": attributes, "material": 0,
            "indices": add(indices, "H", "SCALAR", len(indices), UNSIGNED_SHORT)}]})
    return {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2] if lamp else [0, 1]}],
        "nodes": [{"name": "Floor", "mesh": 0}, {"name": "Box", "mesh": 1},
                  {"name": "Lamp", "translation": [0.8, 2.5, -0.6],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{
            "name": "Lamp", "type": "point",
            "intensity": LAMP_POWER * PBR_WATTS_TO_LUMENS / (4 * math.pi)}]}},
        "materials": [{"name": "Plaster", "pbrMetallicRoughness": {
            "baseColorFactor": [0.7, 0.7, 0.7, 1.0], "metallicFactor": 0.0}}],
        "meshes": gltf_meshes,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(data).decode()}],
    }


@pytest.fixture(scope="module")
def room_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("gltf") / "room.gltf"
    path.write_text(json.dumps(room_gltf()))
    return path


def run_cli(build_python_dir, *args, progress=False):
    """`python -m shgi bake ...` with this interpreter, as a farm would run it (not a tty)."""
    env = dict(os.environ, PYTHONPATH=str(build_python_dir))
    env.pop("SHGI_PROGRESS", None)
    if progress:
        env["SHGI_PROGRESS"] = "1"
    command = [sys.executable, "-m", "shgi", "bake", *map(str, args)]
    return subprocess.run(command, capture_output=True, text=True, env=env, timeout=120)


CLI_BAKE = ["--resolution", "32", "--samples", "8", "--seed", "5"]
# docs/architecture.md: a cancelled call returns within 0.2 s; the process also has to exit. Generous, as
# the machine may be loaded.
CANCEL_SECONDS = 10.0


def test_cli_bake_writes_the_lightmaps_with_a_progress_bar(build_python_dir, room_file, tmp_path):
    out = tmp_path / "out"
    result = run_cli(build_python_dir, room_file, "--out", out, *CLI_BAKE, progress=True)
    assert result.returncode == 0, result.stderr
    assert sorted(os.listdir(out)) == ["Box.exr", "Box.png", "Floor.exr", "Floor.png"]
    assert f"Floor: {out / 'Floor.exr'} {out / 'Floor.png'}" in result.stdout
    # The bar on stderr, finishing at 100% (text mode reads its carriage returns as newlines).
    bars = re.findall(r"\[(#*)(\.*)\] +(\d+\.\d)% ", result.stderr)
    assert bars and all(len(done) + len(left) == 30 for done, left, _ in bars)
    assert bars[-1][2] == "100.0" and "100.0% done" in result.stderr
    # TEXCOORD_1 ('UVMap.001') was baked, not the overlapping TEXCOORD_0: the box's cells.
    coverage = shgi.read_exr(out / "Box.exr")["Coverage"][:, :, 0]
    assert 0.4 < (coverage > 0).mean() < 0.8
    # The floor is lit but for the box's footprint (0.64 of its 16 m^2, no light gets under).
    dark = (shgi.read_exr(out / "Floor.exr")["Lightmap"].max(axis=2) == 0.0).mean()
    assert 0.0 < dark < 0.64 / 16


def test_cli_shards_then_merge_equal_a_plain_bake(build_python_dir, room_file, tmp_path):
    plain, farm = tmp_path / "plain", tmp_path / "farm"
    result = run_cli(build_python_dir, room_file, "--out", plain, *CLI_BAKE)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""  # no bar when stderr is not a terminal and none was asked for
    for shard in ("0/2", "1/2"):
        result = run_cli(build_python_dir, room_file, "--out", farm, *CLI_BAKE, "--shard", shard)
        assert result.returncode == 0, result.stderr
        assert os.listdir(farm) == ["shards"]  # a shard writes no lightmap
    result = run_cli(build_python_dir, room_file, "--out", farm, *CLI_BAKE, "--merge", "2")
    assert result.returncode == 0, result.stderr
    expected = written_files(plain)
    assert len(expected) == 4 and written_files(farm) == expected


def test_cli_refuses_a_scene_without_lamps_unless_asked(build_python_dir, tmp_path):
    """The room without its lamp (an exporter dropped it): refused, naming the file, the cause
    and the flag; with --world-light-only it bakes, lit by the loader's default world alone
    (on average no brighter than that world's radiance, the box shading part of the floor)."""
    path = tmp_path / "no_lamp.gltf"
    path.write_text(json.dumps(room_gltf(lamp=False)))
    out = tmp_path / "out"
    result = run_cli(build_python_dir, path, "--out", out, *CLI_BAKE)
    assert result.returncode == 1, result.stderr
    for words in (f"shgi bake: error: {path}: no lamp and no emissive material",
                  "left out by the exporter", "--world-light-only"):
        assert words in result.stderr, result.stderr
    assert "Traceback" not in result.stderr and not out.exists()
    result = run_cli(build_python_dir, path, "--out", out, *CLI_BAKE, "--world-light-only")
    assert result.returncode == 0, result.stderr
    world = shgi.load_gltf(str(path)).world
    radiance = world.strength * np.asarray(world.color)
    floor = shgi.read_exr(out / "Floor.exr")["Lightmap"].mean(axis=(0, 1))
    assert (0.5 * radiance < floor).all() and (floor <= radiance).all(), (floor, radiance)
    help_text = run_cli(build_python_dir, "--help").stdout
    assert "--world-light-only" in help_text


def test_cli_sizes_lightmaps_by_the_addon_texel_density(build_python_dir, room_file, tmp_path):
    """Without a size the CLI sizes each lightmap as the Blender add-on does by default: from
    its Texel Density (the same default); --resolution still fixes the size; --help says so."""
    sys.path.insert(0, str(REPO_ROOT / "addon"))
    from shgi_blender import bake_settings

    density = bake.DEFAULT_TEXELS_PER_METRE
    assert bake_settings.BAKE_PROPERTY_DEFAULTS["texel_density"] == density
    assert bake_settings.BAKE_PROPERTY_DEFAULTS["resolution"] == 0  # the density decides
    scene = shgi.load_gltf(str(room_file))
    expected = {inst.name: bake.resolution_for_density(scene, index, density)
                for index, inst in enumerate(scene.instances)}
    assert len(set(expected.values())) == 2  # the floor and the box differ in size
    out = tmp_path / "density"
    result = run_cli(build_python_dir, room_file, "--out", out, "--samples", "2")
    assert result.returncode == 0, result.stderr
    for name, side in expected.items():
        assert shgi.read_exr(out / f"{name}.exr")["Lightmap"].shape == (side, side, 3), name
    out = tmp_path / "fixed"
    result = run_cli(build_python_dir, room_file, "--out", out, "--samples", "2",
                     "--resolution", "20")
    assert result.returncode == 0, result.stderr
    for name in expected:
        assert shgi.read_exr(out / f"{name}.exr")["Lightmap"].shape == (20, 20, 3), name
    help_text = " ".join(run_cli(build_python_dir, "--help").stdout.split())
    assert f"texel density of {density:g} texels per metre" in help_text, help_text
    assert "--resolution N makes every lightmap N x N" in help_text


def test_cli_bakes_a_mesh_of_two_materials_into_one_lightmap(build_python_dir, tmp_path):
    """Blender exports a mesh with two material slots as one glTF mesh of two primitives: the
    node is one object, baked into one lightmap (the CLI refused it as two objects of one name)."""
    document = room_gltf()
    floor = document["meshes"][0]["primitives"][0]
    halves = []
    for first in (0, 3):  # the floor quad's two triangles, as views into its index accessor
        accessor = dict(document["accessors"][floor["indices"]], count=3, byteOffset=2 * first)
        document["accessors"].append(accessor)
        halves.append(dict(floor, indices=len(document["accessors"]) - 1))
    document["materials"].append({"name": "Tiles", "pbrMetallicRoughness": {
        "baseColorFactor": [0.5, 0.5, 0.7, 1.0], "metallicFactor": 0.0}})
    halves[1]["material"] = 1
    document["meshes"][0]["primitives"] = halves
    path = tmp_path / "two_materials.gltf"
    path.write_text(json.dumps(document))
    out = tmp_path / "out"
    result = run_cli(build_python_dir, path, "--out", out, *CLI_BAKE)
    assert result.returncode == 0, result.stderr
    assert sorted(os.listdir(out)) == ["Box.exr", "Box.png", "Floor.exr", "Floor.png"]
    # Both triangles are in the one lightmap: it covers the whole floor.
    coverage = shgi.read_exr(out / "Floor.exr")["Coverage"][:, :, 0]
    assert (coverage > 0).mean() > 0.95


def test_cli_missing_file(build_python_dir, tmp_path):
    missing = tmp_path / "nowhere.gltf"
    result = run_cli(build_python_dir, missing, "--out", tmp_path / "out")
    assert result.returncode == 1
    assert "shgi bake: error:" in result.stderr and str(missing) in result.stderr
    assert "Traceback" not in result.stderr


def test_cli_scene_without_the_lightmap_uv_map(build_python_dir, tmp_path):
    path = tmp_path / "no_lightmap_uv.gltf"
    path.write_text(json.dumps(room_gltf(lightmap_uv=False)))
    result = run_cli(build_python_dir, path, "--out", tmp_path / "out")
    assert result.returncode == 1
    assert "no mesh has a lightmap UV map" in result.stderr
    assert "TEXCOORD_1" in result.stderr and "['UVMap']" in result.stderr
    result = run_cli(build_python_dir, path, "--out", tmp_path / "out", "--uv-set", "Bake")
    assert result.returncode == 1 and "no mesh has the UV map 'Bake'" in result.stderr
    assert not (tmp_path / "out").exists()


def test_cli_uv_xatlas_lays_out_objects_without_lightmap_uvs(build_python_dir, tmp_path):
    """The room without TEXCOORD_1: --uv xatlas lays out the floor (one chart) and the box (a
    chart per face, its faces share no vertices), prints each layout, bakes both; shards and a
    merge lay them out alike and give the same files."""
    path = tmp_path / "no_lightmap_uv.gltf"
    path.write_text(json.dumps(room_gltf(lightmap_uv=False)))
    plain, farm = tmp_path / "plain", tmp_path / "farm"
    result = run_cli(build_python_dir, path, "--out", plain, *CLI_BAKE, "--uv", "xatlas")
    assert result.returncode == 0, result.stderr
    layouts = dict(re.findall(r"^(\w+): lightmap UVs by xatlas: (\d+) charts, utilization "
                              r"(?:0\.\d\d|1\.00) \(32 x 32\)$", result.stdout, re.MULTILINE))
    assert layouts == {"Floor": "1", "Box": "6"}, result.stdout
    assert f"Box: {plain / 'Box.exr'} {plain / 'Box.png'}" in result.stdout
    assert sorted(os.listdir(plain)) == ["Box.exr", "Box.png", "Floor.exr", "Floor.png"]
    # The floor is lit but for the box's footprint (0.64 of its 16 m^2).
    dark = (shgi.read_exr(plain / "Floor.exr")["Lightmap"].max(axis=2) == 0.0).mean()
    assert 0.0 < dark < 0.64 / 16
    assert shgi.read_exr(plain / "Box.exr")["Coverage"].max() <= 1.0

    for shard in ("0/2", "1/2"):
        result = run_cli(build_python_dir, path, "--out", farm, *CLI_BAKE, "--uv", "XATLAS",
                         "--shard", shard)
        assert result.returncode == 0, result.stderr
    result = run_cli(build_python_dir, path, "--out", farm, *CLI_BAKE, "--merge", "2")
    assert result.returncode == 1 and "--uv xatlas to lay one out" in result.stderr
    result = run_cli(build_python_dir, path, "--out", farm, *CLI_BAKE, "--uv", "xatlas",
                     "--merge", "2")
    assert result.returncode == 0, result.stderr
    assert written_files(farm) == written_files(plain)


@pytest.mark.parametrize("arguments, message", [
    (["--shard", "2/2"], "argument --shard: '2/2': need N >= 1 and 0 <= i < N"),
    (["--shard", "one/2"], "argument --shard: 'one/2': use i/N"),
    (["--shard", "0/2", "--merge", "2"], "not allowed with argument"),
    (["--merge", "0"], "argument --merge: 0 is less than 1"),
    (["--padding", "-1"], "argument --padding: -1 is less than 0"),
    (["--density", "0"], "argument --density: 0 is not a positive number"),
    (["--uv", "blender"], "argument --uv: invalid choice: 'BLENDER'"),
])
def test_cli_bad_arguments(build_python_dir, room_file, tmp_path, arguments, message):
    result = run_cli(build_python_dir, room_file, "--out", tmp_path / "out", *arguments)
    assert result.returncode == 2
    assert message in result.stderr
    assert not (tmp_path / "out").exists()


def test_cli_ctrl_c_cancels_the_bake(build_python_dir, room_file, tmp_path):
    """SIGINT while a long bake runs: exit 130 with "cancelled" within a moment, no crash (the
    bake runs on a worker thread that the main thread cancels)."""
    env = dict(os.environ, PYTHONPATH=str(build_python_dir), SHGI_PROGRESS="1")
    command = [sys.executable, "-m", "shgi", "bake", str(room_file), "--out", str(tmp_path),
               "--resolution", "512", "--samples", "2048"]  # minutes of work in short tiles
    # The child gets the default SIGINT action even in a run started with it ignored (conftest).
    process = subprocess.Popen(command, env=env, stderr=subprocess.PIPE, text=True)
    try:
        for line in process.stderr:  # bar redraws end in "\r": a line each in text mode
            if "baking lightmap" in line:
                break
        process.send_signal(signal.SIGINT)
        sent = time.monotonic()
        _, rest = process.communicate(timeout=CANCEL_SECONDS)
        waited = time.monotonic() - sent
    finally:
        process.kill()
        process.wait()
    assert process.returncode == 130, rest
    assert rest.rstrip().endswith("cancelled") and "terminate" not in rest
    assert waited < CANCEL_SECONDS
    assert not (tmp_path / "Floor.exr").exists()


def test_cli_bakes_l2_directional_lightmaps(build_python_dir, room_file, tmp_path):
    """`--directional --sh-order 2` writes SH.c0 .. SH.c8, whose first four are the L1 bake's
    (`--directional` alone) bit for bit; `--help` names the flag; a third order is refused."""
    help_text = run_cli(build_python_dir, "--help").stdout
    assert "--sh-order" in help_text and "SH.c0 .. SH.c8" in help_text
    outs = {}
    for order in (1, 2):
        outs[order] = tmp_path / f"l{order}"
        result = run_cli(build_python_dir, room_file, "--out", outs[order], *CLI_BAKE,
                         "--directional", "--sh-order", order)
        assert result.returncode == 0, result.stderr
    l1, l2 = (shgi.read_exr(outs[order] / "Floor.exr") for order in (1, 2))
    assert sorted(name for name in l2 if name.startswith("SH.")) == [f"SH.c{i}" for i in range(9)]
    assert sorted(name for name in l1 if name.startswith("SH.")) == [f"SH.c{i}" for i in range(4)]
    for name in ("Lightmap", "SH.c0", "SH.c1", "SH.c2", "SH.c3"):
        np.testing.assert_array_equal(l1[name], l2[name], err_msg=name)
    assert np.abs(l2["SH.c6"]).max() > 0.0
    refused = run_cli(build_python_dir, room_file, "--out", tmp_path / "l3", *CLI_BAKE,
                      "--directional", "--sh-order", "3")
    assert refused.returncode != 0 and "--sh-order" in refused.stderr


def test_cli_merge_without_shards_names_the_missing_file(build_python_dir, room_file, tmp_path):
    result = run_cli(build_python_dir, room_file, "--out", tmp_path, *CLI_BAKE, "--merge", "3")
    assert result.returncode == 1
    assert str(tmp_path / "shards" / "Floor.shard-0-of-3.npz") in result.stderr


def test_settings_edited_by_a_progress_callback_do_not_reach_a_running_bake():
    # The bake functions read their settings again after checking them, with the GIL released:
    # a callback (or another thread) shrinking the raster or switching to directional mid-run
    # corrupted the heap or crashed. They now work on a copy taken before the GIL is released.
    scene = plane_scene()
    raster = shgi.TexelRasterSettings(width=16, height=16)

    def shrink(fraction, stage):
        raster.width = raster.height = 1

    texel_map = shgi.rasterize_texels(scene, 0, raster, progress=shgi.Progress(shrink, 0.0))
    assert (texel_map.width, texel_map.height) == (16, 16) and raster.width == 1
    settings = shgi.LightmapSettings(samples=1, tile_size=8)

    def go_directional(fraction, stage):
        settings.directional = True

    texels = shgi.bake_lightmap(scene, texel_map, settings,
                                progress=shgi.Progress(go_directional, 0.0))
    assert not texels.directional and texels.sh is None  # baked as the call was made
    assert settings.directional
    filtering = shgi.LightmapFilterSettings(iterations=2)

    def huge_filter(fraction, stage):
        filtering.iterations = 2**31 - 1  # ran "forever" (and 1 << 31 overflowed)

    shgi.filter_lightmap(texel_map, texels, filtering, progress=shgi.Progress(huge_filter, 0.0))
    unocclude = shgi.UnoccludeSettings(ray_count=4)

    def many_rays(fraction, stage):
        unocclude.ray_count = 2**31 - 1

    assert shgi.unocclude(scene, texel_map, unocclude,
                          progress=shgi.Progress(many_rays, 0.0))["samples"] > 0


def test_an_array_too_big_to_copy_is_a_memory_error_naming_it():
    # A broadcast view of 12 bytes stands for a (2^32, 3) array: numpy cannot allocate its
    # contiguous copy, and the binding read through the null array it got back (SIGSEGV).
    positions = np.broadcast_to(np.zeros(3, np.float32), (2**32, 3))
    with pytest.raises(MemoryError, match="positions: a contiguous float32 copy of the "
                                          r"\(4294967296, 3\) array does not fit in memory"):
        shgi.Scene().add_mesh(positions=positions, triangles=np.array([[0, 1, 2]]))
    pixels = np.broadcast_to(np.zeros(1, np.float16), (2**20, 2**20, 4))
    with pytest.raises(MemoryError, match="pixels: a contiguous float32 copy"):
        shgi.write_png("unused.png", pixels)


def test_cli_output_folder_that_is_a_file_is_named(build_python_dir, room_file, tmp_path):
    blocker = tmp_path / "lightmaps"
    blocker.write_text("not a folder")
    for out in (blocker, blocker / "inner"):
        result = run_cli(build_python_dir, room_file, "--out", out, *CLI_BAKE)
        assert result.returncode == 1, result.stderr
        assert f"output folder '{out}': '{blocker}' is a file, not a folder" in result.stderr
        assert "Errno" not in result.stderr.splitlines()[-1]


def test_a_texel_map_is_refused_by_another_scene_or_after_its_instance_changed():
    """A TexelMap made for one scene baked against another without an error, unocclude ran on a
    map whose instance had moved, and a map whose mesh was replaced failed with "hit.triangle_id
    = 1 but its mesh has 1 triangles". The map records the scene, mesh and transform it was
    made for."""
    scene = plane_scene()
    texel_map = shgi.rasterize_texels(scene, 0, shgi.TexelRasterSettings(width=8, height=8))
    settings = shgi.LightmapSettings(samples=1, tile_size=8)
    assert shgi.bake_lightmap(scene, texel_map, settings).width == 8
    again = "call rasterize_texels(scene, instance_id, settings) again"

    other = plane_scene()
    with pytest.raises(ValueError) as caught:
        shgi.bake_lightmap(other, texel_map, settings)
    assert str(caught.value).startswith("bake_lightmap: the texel map was made for another scene")
    assert again in str(caught.value)

    moved = np.eye(4)
    moved[2, 3] = 1.0
    scene.set_instance_transform(0, moved)
    scene.commit()
    with pytest.raises(ValueError) as caught:
        shgi.unocclude(scene, texel_map, shgi.UnoccludeSettings())
    assert str(caught.value).startswith(
        "unocclude: the texel map was made before instance 0 'plane' moved")
    assert again in str(caught.value)
    texel_map = shgi.rasterize_texels(scene, 0, shgi.TexelRasterSettings(width=8, height=8))
    assert shgi.unocclude(scene, texel_map, shgi.UnoccludeSettings())["samples"] > 0

    positions = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0]], np.float32)
    scene.set_mesh(0, shgi.Mesh(positions=positions, triangles=np.array([[0, 1, 2]]),
                                name="plane", uvs={"LightmapUV": (positions[:, :2] + 1.0) / 2.0}))
    scene.commit()
    with pytest.raises(ValueError) as caught:
        shgi.bake_lightmap(scene, texel_map, settings)
    assert str(caught.value).startswith(
        "bake_lightmap: the texel map was made before the mesh of instance 0 'plane' changed")
    assert "triangle_id" not in str(caught.value)


def test_light_splits_cut_the_bake_error_where_a_bright_light_is_hidden():
    """The plane lit by a 20 W lamp above it, with a 2000 W lamp 4 m away behind a wall: the
    light tree alone sends most shadow rays to the hidden lamp; with LightmapSettings.light_splits
    (default 4) every texel samples both, so the direct bake's error at equal samples drops by
    more than SPLIT_FACTOR, and both stay unbiased (means within the reference's noise)."""
    wall = np.array([[0, 0, 4, 1.5], [0, 4, 0, 0], [-4, 0, 0, 0], [0, 0, 0, 1]], np.float32)
    lamps = [shgi.Light(name=name, type=shgi.LightType.POINT, power=power, radius=0.1,
                        world_from_light=np.array([[1, 0, 0, x], [0, 1, 0, 0], [0, 0, 1, 1],
                                                   [0, 0, 0, 1]], np.float32))
             for name, power, x in (("dim", 20.0, 0.0), ("bright", 2000.0, 4.0))]
    scene = plane_scene(world=((0.0, 0.0, 0.0), 0.0), lights=lamps,
                        placements=(("plane", np.eye(4)), ("wall", wall)))
    texel_map = shgi.rasterize_texels(scene, 0, shgi.TexelRasterSettings(width=16, height=16))

    def baked(samples, splits, seed):
        settings = shgi.LightmapSettings(samples=samples, seed=seed, content="DIRECT",
                                         light_splits=splits)
        return np.asarray(shgi.bake_lightmap(scene, texel_map, settings).color, np.float64)

    covered = np.asarray(texel_map.covered, bool) if hasattr(texel_map, "covered") else None
    reference = baked(1024, 4, seed=99)
    mask = (reference[..., :3].sum(axis=-1) > 0) if covered is None else covered
    ref = reference[mask][..., :3]
    errors, means = {}, {}
    for splits in (1, 4):
        image = baked(4, splits, seed=7)[mask][..., :3]
        errors[splits] = np.sqrt(np.mean((image - ref) ** 2)) / ref.mean()
        means[splits] = image.mean() / ref.mean()
    print(f"hidden bright lamp, 4 samples: relative RMSE {errors[1]:.3f} (1 split), "
          f"{errors[4]:.3f} (4); means {means[1]:.4f}, {means[4]:.4f}")
    assert errors[1] > SPLIT_FACTOR * errors[4]
    for splits in (1, 4):  # unbiased: the mean of len(ref) texels within its standard error
        assert abs(means[splits] - 1.0) < STANDARD_ERRORS * errors[splits] / np.sqrt(len(ref))


# The bake's error ratio above measured 110x (1 split against 4, seed 7): asserted with margin.
SPLIT_FACTOR = 10.0
