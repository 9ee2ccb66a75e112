"""Instant GI with the discontinuity-aware screen-space SH filter (seed 004; the INSTANT_GI
method) through Python.

Settings and refusals, the registry row, determinism (thread count, tile size), cancel keeping
the sets; the issue's Show list: the SH filter against the irradiance filter on the diffuse
Cornell box (section 4.2), the normal-mapped floor against brute force (Figs. 2 and 4: the SH
filter keeps the normal map's detail that the irradiance filter blurs, without the interleave
pattern the strict filter leaves; images under docs/images/), agreement with the path tracer on
the Cornell box and the sun room with >= 1024 VPLs, and the two rooms' dim room (exact
visibility: no leak). Read through a final gather (each gather ray's hit reads one set): the
same agreement on the Cornell box and the sun room and the dim room, determinism. A missed
target stays as a strict xfail carrying the measured figure.
"""

import math
import sys
import threading

import numpy as np
import pytest

import shgi
from blender_support import REPO_ROOT
from shgi.metrics import psnr
from scene_support import finishes_in_a_thread, path_traced_reference

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/ is not a package)

IMAGES = REPO_ROOT / "docs" / "images"
SCALE = 0.25
REFERENCE_SAMPLES = 2048
REFERENCES = {"cornell_box": (SCALE, REFERENCE_SAMPLES), "sun_room": (SCALE, REFERENCE_SAMPLES),
              "two_rooms": (0.5, 512)}
# Passes of the agreement renders: 4 passes of 16 sets x 16 light paths leave >= 1024 VPLs.
PASSES = 4


def missed(figure):
    return pytest.mark.xfail(strict=True, reason=f"target missed; measured {figure}")


def indirect_diffuse(passes):
    return float((passes["DiffInd"] * passes["DiffCol"]).mean())


def solved(scene, passes=PASSES, seed=5, **fields):
    solver = shgi.InstantGi(scene, shgi.InstantGiSettings(seed=seed, **fields))
    for _ in range(passes):
        solver.refine()
    return solver


def preview(scene, field, samples=16, **fields):
    image, _ = shgi.render_preview(scene, field,
                                   shgi.PreviewSettings(seed=5, samples=samples, **fields))
    return image


def small_cornell():
    builder = scenes.cornell_box(0.1)
    builder.scene.commit()
    return builder.scene


# --- settings, registry, determinism, cancel ------------------------------------------------

def test_settings_defaults_and_refusals():
    s = shgi.InstantGiSettings()
    assert (s.sets_x, s.sets_y, s.photons_per_set, s.vpl_bounces) == (4, 4, 16, 4)
    assert s.glossy_bounces == 4  # Cycles' Light Paths > Glossy
    assert s.passes_per_sample == 4  # the add-on's Render Passes: F12 frames as before
    assert s.filter_mode == shgi.InstantGiFilter.SH
    assert s.clamp_distance == pytest.approx(0.05)
    assert s.near_field_reach == 4.0
    assert s.gather_near_radius == pytest.approx(0.25)
    s.validate()
    for field, value in (("sets_x", 0), ("sets_y", 17), ("vpl_bounces", 0),
                         ("glossy_bounces", -1), ("glossy_bounces", 65),
                         ("passes_per_sample", 0), ("passes_per_sample", 65537),
                         ("clamp_distance", -1.0), ("depth_threshold", float("nan")),
                         ("normal_threshold", 1.5), ("near_field_reach", -1.0),
                         ("near_field_reach", 65.0), ("gather_near_radius", -0.1),
                         ("gather_near_radius", float("inf"))):
        bad = shgi.InstantGiSettings(**{field: value})
        with pytest.raises(ValueError, match=field):
            bad.validate()
        with pytest.raises(ValueError, match=field):
            shgi.InstantGi(small_cornell(), bad)


def test_registry_row():
    row = shgi.method("INSTANT_GI")
    assert row.number == 5 and row.settings_type is shgi.InstantGiSettings
    assert row.final_passes == 4 and row.solves_field
    assert "INSTANT_GI" not in dict(shgi.reserved_method_numbers())
    solver = shgi.make_solver("INSTANT_GI", small_cornell(), shgi.InstantGiSettings(seed=1))
    assert isinstance(solver, shgi.InstantGi)


def test_sets_grow_by_a_pass_each_and_hold_every_vpl():
    solver = shgi.InstantGi(small_cornell(), shgi.InstantGiSettings(seed=2, sets_x=3, sets_y=2))
    assert solver.passes == 0 and solver.current_field().vpl_count == 0
    solver.refine()
    first = solver.current_field()
    assert len(first.set_sizes) == 6 and sum(first.set_sizes) == first.vpl_count > 0
    assert max(first.set_sizes) - min(first.set_sizes) <= 1  # dealt in turn
    solver.refine()
    second = solver.current_field()
    assert second.vpl_count > first.vpl_count and solver.passes == 2
    assert [name for name, _ in solver.stage_seconds] == ["vpl_trace", "vpl_sets"]
    assert solver.memory_bytes > 0


def frames_by_threads_and_tiles(scene, field, samples, runs=((1, 16), (2, 4)), **fields):
    """The preview of `field` rendered once per (threads, tile size) of `runs` (PreviewSettings
    `fields` besides)."""
    images = []
    try:
        for threads, tile in runs:
            shgi.set_max_threads(threads)
            images.append(preview(scene, field, samples=samples, tile_size=tile, **fields))
    finally:
        shgi.set_max_threads(0)
    return images


def test_frames_do_not_depend_on_threads_or_tiles():
    """The gather, the filter and the shading are frame-wide over the G-buffer: no tile seams,
    the same bits for 1 and 2 threads and for tile sizes 2 and 16."""
    scene = small_cornell()
    field = solved(scene, passes=1).current_field()
    images = frames_by_threads_and_tiles(scene, field, 2, runs=((1, 16), (2, 16), (2, 2)))
    assert images[0]["DiffInd"].max() > 0.0
    for other in images[1:]:
        for name in ("Combined", "DiffInd", "GlossInd"):
            np.testing.assert_array_equal(images[0][name], other[name], err_msg=name)


def test_a_final_gather_reads_one_set_where_each_gather_ray_lands():
    """With PreviewSettings.final_gather the first surfaces are shaded as any field's
    (next-event estimation and one gather ray per sample, no screen-space stage), and where a
    gather ray lands the field is read through one set of the sample's passes
    (IndirectField.gather_lookup): a lookup reads one set's VPLs, not every set's. Without a
    final gather the Cornell box (no mirrors) makes no lookup beyond the first surfaces.
    (gather_near_radius 0: one set whole; its near VPLs from every set below.)"""
    scene = small_cornell()
    field = solved(scene, passes=2, gather_near_radius=0.0).current_field()
    renderer = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=2))
    renderer.render(field, 1)
    assert field.lookup_counts["lookups"] == 0
    direct = renderer.passes()
    renderer = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=2,
                                                                final_gather=True))
    renderer.render(field, 1)
    counts = field.lookup_counts
    sizes = field.set_sizes  # every pass of each set (passes_per_sample 4 >= the 2 passes)
    assert counts["lookups"] > 0
    per_lookup = counts["vpls"] / counts["lookups"]
    assert min(sizes) <= per_lookup <= max(sizes), (per_lookup, sizes)
    assert per_lookup < field.vpl_count / 8
    gathered = renderer.passes()
    assert gathered["DiffInd"].max() > 0.0
    assert not np.array_equal(direct["DiffInd"], gathered["DiffInd"])


def test_a_final_gather_reads_every_set_s_vpls_near_where_a_gather_ray_lands():
    """gather_near_radius: a gather lookup reads its set's VPLs beyond the radius and every
    set's within it, so it reads more VPLs than one set (the small Cornell box: 60.1 per lookup
    without, 67.6 with the default 0.25 m) and far fewer than every set; the frame keeps its
    mean (each VPL's expected weight is the same) and differs from one-set lookups."""
    scene = small_cornell()
    frames, per_lookup = [], []
    for radius in (0.0, 0.25):
        field = solved(scene, passes=8, gather_near_radius=radius).current_field()
        renderer = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=16,
                                                                    final_gather=True))
        renderer.render(field, 1)
        counts = field.lookup_counts
        per_lookup.append(counts["vpls"] / counts["lookups"])
        renderer.render(field, 15)
        frames.append(renderer.passes())
    assert per_lookup[0] * 1.05 < per_lookup[1] < per_lookup[0] * 4, per_lookup
    one_set, near = (frame["DiffInd"].mean() for frame in frames)
    assert not np.array_equal(frames[0]["DiffInd"], frames[1]["DiffInd"])
    assert near == pytest.approx(one_set, rel=0.05), (one_set, near)


def test_final_gather_frames_do_not_depend_on_threads_or_tiles():
    """The set each gather ray reads comes from its pixel and sample alone (a stratified number
    per pixel), so frames through a final gather are the same bits for any thread count and
    tile size, with more passes than a sample reads (each sample's view)."""
    scene = mirrored_cornell()
    field = solved(scene, passes=8, passes_per_sample=4).current_field()
    images = frames_by_threads_and_tiles(scene, field, 3, final_gather=True)
    assert images[0]["DiffInd"].max() > 0.0
    for name in ("Combined", "DiffInd", "GlossInd", "DiffDir"):
        np.testing.assert_array_equal(images[0][name], images[1][name], err_msg=name)


def test_final_gather_leaves_filter_direct_to_next_event_estimation():
    """Through a final gather the field is read without filter_direct's light: next-event
    estimation gives the lamps' and the sky's direct light at the first surface and where the
    gather ray lands, so the frame is the one of the field solved without filter_direct."""
    scene = small_cornell()
    with_direct = solved(scene, passes=1, filter_direct=True).current_field()
    without = solved(scene, passes=1).current_field()
    # At the first surfaces the two fields light the frame differently ...
    assert not np.array_equal(preview(scene, with_direct, samples=2)["DiffDir"],
                              preview(scene, without, samples=2)["DiffDir"])
    # ... through a final gather alike.
    a = preview(scene, with_direct, samples=2, final_gather=True)
    b = preview(scene, without, samples=2, final_gather=True)
    assert a["DiffDir"].max() > 0.0
    for name in ("Combined", "DiffDir", "DiffInd"):
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)


def test_each_sample_gathers_the_passes_after_the_previous_samples():
    """passes_per_sample k: preview sample i gathers passes i k .. i k + k - 1 around the
    field's passes, so a frame's samples average new VPLs; with no more passes than k every
    sample gathers all of them."""
    scene = small_cornell()
    field = solved(scene, passes=6, passes_per_sample=4).current_field()
    assert field.passes == 6
    assert [field.sample_passes(i) for i in range(4)] == [
        [0, 1, 2, 3], [4, 5, 0, 1], [2, 3, 4, 5], [0, 1, 2, 3]]
    assert solved(scene, passes=3, passes_per_sample=4).current_field().sample_passes(7) == [
        0, 1, 2]
    assert solved(scene, passes=3, passes_per_sample=1).current_field().sample_passes(7) == [1]


def test_a_sample_of_one_pass_equals_that_pass_alone():
    """With passes_per_sample 1, sample 0 of a two-pass field is the one-pass field's sample 0
    bit for bit (pass 0's VPLs, scaled as one pass), and sample 1 gathers pass 1's other VPLs;
    with passes_per_sample at least the passes, frames are those of gathering every pass."""
    scene = small_cornell()
    one = preview(scene, solved(scene, passes=1).current_field(), samples=1)
    split = solved(scene, passes=2, passes_per_sample=1).current_field()
    first = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=2))
    first.render(split, 1)
    np.testing.assert_array_equal(first.passes()["DiffInd"], one["DiffInd"])
    two = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=2))
    two.render(split, 1)
    two.render(split, 1)
    both = preview(scene, solved(scene, passes=2, passes_per_sample=2).current_field(),
                   samples=2)
    # The second sample's pass differs from the first's, so the frames differ ...
    assert not np.array_equal(two.passes()["DiffInd"], both["DiffInd"])
    # ... and gathering every pass does not depend on passes_per_sample beyond the passes.
    many = preview(scene, solved(scene, passes=2, passes_per_sample=64).current_field(),
                   samples=2)
    for name in ("Combined", "DiffInd", "GlossInd"):
        np.testing.assert_array_equal(many[name], both[name], err_msg=name)


def test_frames_of_passes_per_sample_do_not_depend_on_threads_or_tiles():
    scene = small_cornell()
    field = solved(scene, passes=3, passes_per_sample=1).current_field()
    images = frames_by_threads_and_tiles(scene, field, 3)
    assert images[0]["DiffInd"].max() > 0.0
    for name in ("Combined", "DiffInd", "GlossInd"):
        np.testing.assert_array_equal(images[0][name], images[1][name], err_msg=name)


# Through a final gather, over a field whose samples read passes of their own.
@pytest.mark.parametrize("final_gather, solve", [(False, {"passes": 1}),
                                                  (True, {"passes": 8, "passes_per_sample": 4})])
def test_samples_at_once_equal_samples_one_by_one(final_gather, solve):
    scene = small_cornell()
    field = solved(scene, **solve).current_field()
    at_once = preview(scene, field, samples=3, final_gather=final_gather)
    renderer = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=3,
                                                                final_gather=final_gather))
    for _ in range(3):
        renderer.render(field, 1)
    one_by_one = renderer.passes()
    for name in ("Combined", "DiffInd"):
        np.testing.assert_array_equal(at_once[name], one_by_one[name], err_msg=name)


def test_glossy_from_vpls_changes_only_the_glossy_light():
    """glossy_from_vpls (off by default): glossy lobes of roughness 0.3 and above weigh each VPL
    by the lobe itself instead of reading the L2 SH. The diffuse light is bit for bit the same
    and the glossy light per pixel is not; frames do not depend on threads or tiles. (Both read
    the lobe clipped at the horizon, normalised above it; how close each comes to the path
    tracer's glossy light is test_indirect_glossy_converges_to_the_path_tracers'.)"""
    assert shgi.InstantGiSettings().glossy_from_vpls is False
    scene = small_cornell()
    sh = preview(scene, solved(scene).current_field(), samples=2)
    field = solved(scene, glossy_from_vpls=True).current_field()
    images = frames_by_threads_and_tiles(scene, field, 2)
    for name in ("Combined", "DiffInd", "GlossInd"):
        np.testing.assert_array_equal(images[0][name], images[1][name], err_msg=name)
    np.testing.assert_array_equal(images[0]["DiffInd"], sh["DiffInd"])
    assert not np.array_equal(images[0]["GlossInd"], sh["GlossInd"])


def test_light_paths_clamp_limits_the_screen_space_indirect_light():
    """Light Paths > Clamp (PreviewSettings.clamp_indirect) clamps each pixel's DiffInd and
    GlossInd per sample, as the path tracer clamps an indirect contribution (Cycles' clamp: the
    mean of the three components); direct light is not clamped."""
    scene = small_cornell()
    field = solved(scene, passes=1).current_field()

    def light(image, lobe):  # Cycles' passes hold light / colour: the light itself
        return np.abs(image[f"{lobe}Ind"] * image[f"{lobe}Col"])[..., :3].mean(axis=-1)

    free = preview(scene, field, samples=1)
    limit = 0.5 * float(np.percentile(light(free, "Diff"), 90))
    clamped = preview(scene, field, samples=1, clamp_indirect=limit)
    for lobe in ("Diff", "Gloss"):
        assert light(clamped, lobe).max() <= limit * (1 + 1e-5), lobe
        below = light(free, lobe) <= limit
        np.testing.assert_array_equal(clamped[f"{lobe}Ind"][below], free[f"{lobe}Ind"][below])
    assert (light(free, "Diff") > limit).mean() > 0.1  # the check has teeth
    np.testing.assert_array_equal(clamped["DiffDir"], free["DiffDir"])


def test_cancel_keeps_the_sets():
    scene = small_cornell()
    solver = solved(scene, passes=1)
    before = solver.current_field().set_sizes
    progress = shgi.Progress()
    progress.cancel()
    with pytest.raises(shgi.Cancelled):
        finishes_in_a_thread(lambda: solver.refine(progress))
    assert solver.passes == 1 and solver.current_field().set_sizes == before


def test_field_lookups_elsewhere_gather_every_set():
    """Off the camera's first surfaces (specular chains, bakes) the field is every VPL with
    exact shadows: on the Cornell box floor it holds light from above, none from below."""
    scene = small_cornell()
    field = solved(scene, passes=1).current_field()
    sh = np.asarray(field.radiance_sh((0.0, 1.0, 0.01), (0.0, 0.0, 1.0)))
    assert sh[0].min() > 0.0  # the DC term of every channel
    up = np.asarray(field.irradiance([(0.0, 1.0, 0.01)], [(0.0, 0.0, 1.0)]))
    assert up.min() > 0.0


def mirrored_cornell():
    """The small Cornell box with a mirror on its left wall: every sample's paths reflected
    there look the field up beyond the first surfaces."""
    builder = scenes.cornell_box(0.1)
    builder.material("mirror", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.0)
    builder.part("mirror", scenes.quad((-0.98, 0.2, 0.2), (0, 1.6, 0), (0, 0, 1.6)), "mirror",
                 (0.9, 0.9, 0.9))
    builder.scene.commit()
    return builder.scene


def test_lookups_through_a_mirror_read_the_sample_s_passes_alone():
    """A preview sample's lookups beyond the first surfaces (the mirror's reflections) gather
    every set's VPLs of that sample's passes, as its first surfaces do: a sample reads as many
    VPLs at 16 passes as at 4 (it read every pass at each lookup: 4x as many, and the caustics
    scene's sample took 10x the CPU at 64 passes). Lookups elsewhere (bakes, radiance_sh)
    still read every pass."""
    scene = mirrored_cornell()
    solver = shgi.InstantGi(scene, shgi.InstantGiSettings(seed=5, passes_per_sample=4))
    totals = [0]  # VPLs after each pass: pass k holds totals[k + 1] - totals[k]
    read = {}
    for passes in (4, 16):
        while solver.passes < passes:
            solver.refine()
            totals.append(solver.current_field().vpl_count)
        field = solver.current_field()
        renderer = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=2))
        for sample in range(2):
            renderer.render(field, 1)
            counts = field.lookup_counts
            per_lookup = sum(totals[k + 1] - totals[k] for k in field.sample_passes(sample))
            assert counts["lookups"] > 0
            assert counts["vpls"] == counts["lookups"] * per_lookup, (passes, sample)
            read[passes, sample] = counts
        field.radiance_sh((0.0, 1.0, 0.01), (0.0, 0.0, 1.0))
        assert field.lookup_counts["vpls"] == counts["vpls"] + field.vpl_count
    for sample in range(2):
        # The same paths whatever the field: the same lookups, and about as many VPLs each.
        assert read[16, sample]["lookups"] == read[4, sample]["lookups"]
        ratio = read[16, sample]["vpls"] / read[4, sample]["vpls"]
        print(f"sample {sample}: {read[4, sample]} at 4 passes, {read[16, sample]} at 16")
        assert 0.75 < ratio < 1.33, ratio


def test_mirror_frames_of_many_passes_do_not_depend_on_threads_or_tiles():
    scene = mirrored_cornell()
    field = solved(scene, passes=12, passes_per_sample=4).current_field()
    images = frames_by_threads_and_tiles(scene, field, 3)
    assert images[0]["DiffInd"].max() > 0.0
    for name in ("Combined", "DiffInd", "GlossInd"):
        np.testing.assert_array_equal(images[0][name], images[1][name], err_msg=name)


# --- filter_direct: the sky's direct light through the SH filter ------------------------------

def sky_over_a_floor():
    """A 4 m white floor under a uniform blue sky, no lamps, seen from 1.5 m above: all its
    direct light is the sky's, whose hemisphere L2 SH reproduces exactly in irradiance."""
    b = scenes.SceneBuilder()
    b.part("floor", scenes.quad((-2, -2, 0), (4, 0, 0), (0, 4, 0)), "plaster", scenes.WHITE)
    return seen_from_above(b, shgi.World(color=(0.35, 0.5, 0.8), strength=1.0))


def seen_from_above(b, world):
    """Commits builder `b`'s scene under `world`, with the floor scenes' camera (1.5 m above,
    looking down at a slant, 48 x 36 px)."""
    b.scene.set_world(world)
    b.camera(eye=(0.0, -1.0, 1.5), target=(0.0, 0.5, 0.0), lens=24.0, width=48, height=36,
             scale=1.0)
    b.scene.commit()
    return b.scene


def direct_diffuse(image):
    return float((image["DiffDir"] * image["DiffCol"])[..., :3].mean())


def test_filter_direct_defaults_off_and_moves_only_direct_light():
    """Off by default. On the Cornell box (black world, one area light) turning it on puts the
    lamp's direct light through the SH (DiffDir changes, within 5% of next-event estimation's
    mean: counted twice it would read 2x, left out 0x) and leaves the indirect light, another
    plane, bit for bit."""
    assert shgi.InstantGiSettings().filter_direct is False
    scene = small_cornell()
    off = preview(scene, solved(scene, passes=1).current_field(), samples=2)
    field = solved(scene, passes=1, filter_direct=True).current_field()
    on = preview(scene, field, samples=2)
    for name in ("DiffInd", "GlossInd"):
        np.testing.assert_array_equal(on[name], off[name], err_msg=name)
    assert not np.array_equal(on["DiffDir"], off["DiffDir"])
    ratio = direct_diffuse(on) / direct_diffuse(off)
    print(f"Cornell box, filter_direct: DiffDir x DiffCol {ratio:.4f} x next-event estimation's")
    assert abs(ratio - 1.0) < 0.05, ratio


# --- filter_direct for lamps: a point light over a Lambert floor -----------------------------

LAMP_HEIGHT = 0.5
LAMP_POWER = 100.0
LAMBERT_ALBEDO = 0.8


def lambert_floor():
    """A SceneBuilder holding a 4 m floor of the "lambert" material (albedo LAMBERT_ALBEDO, no
    specular layer)."""
    b = scenes.SceneBuilder()
    b.materials["lambert"] = b.scene.add_material(shgi.Material(
        name="lambert", base_color=(LAMBERT_ALBEDO,) * 3, specular=0.0,
        diffuse_model=shgi.DiffuseModel.LAMBERT))
    b.part("floor", scenes.quad((-2, -2, 0), (4, 0, 0), (0, 4, 0)), "lambert",
           (LAMBERT_ALBEDO,) * 3)
    return b


def lamp_over_a_floor(height=LAMP_HEIGHT, light=None):
    """A 4 m Lambert floor (albedo 0.8, no specular layer) under one light (by default a point
    light of 100 W at `height` above its centre), black world, seen from 1.5 m above at a slant:
    its pixels see the light from overhead (mu = 1) down to near the horizon."""
    b = lambert_floor()
    if light is None:
        light = shgi.Light(name="lamp", type=shgi.LightType.POINT, power=LAMP_POWER)
        light.world_from_light = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, height],
                                           [0, 0, 0, 1]], np.float32)
    b.scene.add_light(light)
    return seen_from_above(b, shgi.World(color=(0.0, 0.0, 0.0), strength=0.0))


def test_filter_direct_point_light_follows_the_l2_law():
    """A point light through L2 SH (the issue's figures, analytically): a delta of irradiance
    E0 = I / d^2 from the direction at cosine mu to the normal comes back from the clamped-cosine
    convolution as E0 (3/32 + mu/2 + 15 mu^2 / 32) instead of E0 mu: +6.25% overhead (mu = 1),
    and 3/32 of E0 at the horizon (mu = 0), where the exact light is 0. With each pixel's own set
    (filter NONE: every set holds the same light sample) every pixel's DiffDir x DiffCol follows
    that law within 1e-5 of the exact next-event estimation at the same G-buffer position, whose
    own value E0 mu^3-law (albedo / pi I mu^3 / h^2) gives mu."""
    scene = lamp_over_a_floor(height=0.2)
    exact = preview(scene, solved(scene, passes=1).current_field(), samples=1)
    field = solved(scene, passes=1, filter_direct=True,
                   filter_mode=shgi.InstantGiFilter.NONE).current_field()
    image = preview(scene, field, samples=1)
    ex = (exact["DiffDir"] * exact["DiffCol"])[..., 0]
    l2 = (image["DiffDir"] * image["DiffCol"])[..., 0]
    lit = ex > 0
    assert lit.sum() > 1000
    intensity = LAMP_POWER / (4 * math.pi)
    mu = np.cbrt(ex[lit] * math.pi * 0.2 ** 2 / (LAMBERT_ALBEDO * intensity))
    e0 = LAMBERT_ALBEDO / math.pi * intensity * (mu / 0.2) ** 2  # as pixel light, I / d^2
    law = e0 * (3 / 32 + mu / 2 + 15 * mu ** 2 / 32)
    np.testing.assert_allclose(l2[lit], law, rtol=1e-5)
    # The exact light is E0 mu (the next-event estimate agrees with mu from its own law).
    np.testing.assert_allclose(ex[lit], e0 * mu, rtol=1e-5)
    overhead = int(np.argmax(mu))
    low = int(np.argmin(mu))
    peak = l2[lit][overhead] / ex[lit][overhead]
    leak = (l2[lit][low] - ex[lit][low]) / e0[low]
    print(f"point light through L2: mu {mu.max():.4f} reads {peak:.4f} x exact; at mu "
          f"{mu.min():.3f} the L2 light exceeds the exact by {leak:.3f} E0 (3/32 = 0.094 at "
          f"mu = 0)")
    # The pixel nearest overhead (mu 0.993) reads within 0.3% of the law's +6.25% at mu = 1.
    assert mu.max() > 0.99 and 1.059 < peak <= 1.0625 + 1e-5, peak
    assert mu.min() < 0.1 and leak > 0.05, leak


@pytest.mark.parametrize("height", [
    1.0, pytest.param(0.5, marks=missed("DiffDir x DiffCol 0.978 x, Combined 0.978 x: the L2 "
                                        "law over the frame gives 0.976 x"))])
def test_filter_direct_lamp_frame_agrees_with_path_tracer(height):
    """The point light over the floor with filter_direct and the paper's SH filter: the frame's
    DiffDir x DiffCol and Combined means within 2% of the path tracer's (1024 spp; the tolerance
    of the sky test above), the lamp counted once (twice would read 2x). Whether the L2 law's
    +6% overhead and its deficit at mid angles (down to 0.92 x at mu 0.45) average out depends
    on what the frame sees: with the lamp 1 m up they do (1.003 x); 0.5 m up, the mid angles
    fill more of the frame and it reads 0.978 x, past the 2% (a strict xfail)."""
    scene = lamp_over_a_floor(height=height)
    reference = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=1024, seed=11))
    field = solved(scene, passes=1, filter_direct=True).current_field()
    image = preview(scene, field, samples=1)
    direct = direct_diffuse(image) / direct_diffuse(reference)
    combined = float(image["Combined"][..., :3].mean()) / float(
        reference["Combined"][..., :3].mean())
    overhead = (image["DiffDir"] / np.maximum(reference["DiffDir"], 1e-9))[..., 0].max()
    print(f"point light {height} m over a floor, filter_direct: DiffDir x DiffCol {direct:.4f} x, "
          f"Combined {combined:.4f} x the path tracer's; largest pixel ratio {overhead:.3f}")
    assert abs(direct - 1.0) < 0.02, direct
    assert abs(combined - 1.0) < 0.02, combined


def test_filter_direct_lamp_half_a_metre_up_reads_the_l2_law():
    """The 0.5 m lamp's frame mean (0.978 x, the strict xfail above) is the L2 law itself, not
    the filter or the sampling: the law E0 (3/32 + mu/2 + 15 mu^2/32) summed over the frame's
    lit pixels (each mu from the exact next-event estimate, as in the law test) gives 0.976 x
    the exact sum, as each pixel's own set (filter NONE) does to 1e-4, and the SH filter's
    frame reads within 0.5% of it. With the lamp 1 m up the same sum gives 1.001 x: the law's
    +6% overhead and its deficit at mid angles (0.92 x at mu 0.45) average out over that
    frame's angles and not over this one's. No filter can take it back: L2 SH holds only the
    clamped-cosine convolution's first three bands."""
    scene = lamp_over_a_floor(height=LAMP_HEIGHT)
    exact = preview(scene, solved(scene, passes=1).current_field(), samples=1)
    ex = (exact["DiffDir"] * exact["DiffCol"])[..., 0]
    lit = ex > 0
    intensity = LAMP_POWER / (4 * math.pi)
    mu = np.cbrt(ex[lit] * math.pi * LAMP_HEIGHT ** 2 / (LAMBERT_ALBEDO * intensity))
    e0 = LAMBERT_ALBEDO / math.pi * intensity * (mu / LAMP_HEIGHT) ** 2
    law = float((e0 * (3 / 32 + mu / 2 + 15 * mu ** 2 / 32)).sum() / ex[lit].sum())
    own = direct_diffuse(preview(scene, solved(
        scene, passes=1, filter_direct=True,
        filter_mode=shgi.InstantGiFilter.NONE).current_field(), samples=1))
    filtered = direct_diffuse(preview(scene, solved(scene, passes=1, filter_direct=True)
                                      .current_field(), samples=1))
    own /= direct_diffuse(exact)
    filtered /= direct_diffuse(exact)
    print(f"lamp {LAMP_HEIGHT} m: the L2 law over the frame {law:.4f} x, each pixel's own set "
          f"{own:.4f} x, the SH filter {filtered:.4f} x the exact direct light")
    assert abs(law - 1.0) > 0.02  # the law alone misses the 2%
    assert own == pytest.approx(law, abs=1e-4)
    assert filtered == pytest.approx(law, abs=0.005)


@pytest.mark.parametrize("kind", ["spot", "area", "sun", "sphere"])
def test_filter_direct_lights_with_extent_and_suns(kind):
    """Every light type goes through the SH with filter_direct (a spot, a 0.5 m area light, a
    sun of 5 degrees at 30 degrees from the zenith, a point light of radius 0.1 m): the frame's
    DiffDir x DiffCol mean within 7% of the path tracer's (1024 spp) — the L2 law's bias for a
    light of one direction is up to +6.25% (a sun overhead) — and not the 2x of a light counted
    twice; lights with extent are sampled per set (photons_per_set per pass)."""
    light = shgi.Light(name=kind, type=getattr(shgi.LightType, "POINT" if kind == "sphere"
                                               else kind.upper()))
    place = np.eye(4, dtype=np.float32)
    place[2, 3] = 0.8
    if kind == "spot":
        light.power, light.spot_size = 100.0, math.radians(100.0)
    elif kind == "area":
        light.power, light.size_x, light.size_y = 100.0, 0.5, 0.5
    elif kind == "sphere":
        light.power, light.radius = 100.0, 0.1
    else:
        light.strength, light.angle = 3.0, math.radians(5.0)
        c, s = math.cos(math.radians(30.0)), math.sin(math.radians(30.0))
        place[:3, :3] = np.array([[1, 0, 0], [0, c, -s], [0, s, c]], np.float32)
    light.world_from_light = place
    scene = lamp_over_a_floor(light=light)
    reference = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=1024, seed=11))
    field = solved(scene, passes=2, filter_direct=True).current_field()
    image = preview(scene, field, samples=1)
    direct = direct_diffuse(image) / direct_diffuse(reference)
    print(f"{kind} over a floor, filter_direct: DiffDir x DiffCol {direct:.4f} x the path "
          f"tracer's")
    assert abs(direct - 1.0) < 0.07, direct


def glowing_panel_over_a_floor(strength=20.0):
    """The 4 m Lambert floor of lamp_over_a_floor under a 0.6 m emissive panel (two emissive
    triangles, no scene lights) 0.8 m up and off to one side, black world."""
    b = lambert_floor()
    b.materials["glow"] = b.scene.add_material(shgi.Material(
        name="glow", base_color=(0.0, 0.0, 0.0), specular=0.0, emission_color=(1.0, 0.9, 0.7),
        emission_strength=strength))
    b.part("panel", scenes.quad((0.2, 0.2, 0.8), (0, 0.6, 0), (0.6, 0, 0)), "glow",
           (0.0, 0.0, 0.0))
    return seen_from_above(b, shgi.World(color=(0.0, 0.0, 0.0), strength=0.0))


def test_filter_direct_carries_emissive_triangles_direct_light():
    """With filter_direct the emissive triangles' direct light goes through the SH too (photons_
    per_set samples per set and pass, each triangle by its power): next-event estimation leaves
    them out, so the frame's DiffDir x DiffCol is within 7% of the path tracer's (the lights'
    tolerance above), not 2x (counted twice) or 0x (left out); the panel itself still shows
    in Combined as the camera sees it. The direct light is the filter's: each pixel's own set
    (filter NONE) gives another DiffDir (next-event estimation's would not depend on the
    filter)."""
    scene = glowing_panel_over_a_floor()
    assert len(scene.emissive_triangles()["area"]) == 2
    reference = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=1024, seed=11))
    field = solved(scene, passes=2, filter_direct=True).current_field()
    image = preview(scene, field, samples=1)
    nee = preview(scene, solved(scene, passes=2).current_field(), samples=16)
    direct = direct_diffuse(image) / direct_diffuse(reference)
    combined = float(image["Combined"][..., :3].mean()) / float(
        reference["Combined"][..., :3].mean())
    print(f"emissive panel over a floor, filter_direct: DiffDir x DiffCol {direct:.4f} x, "
          f"Combined {combined:.4f} x the path tracer's; next-event estimation "
          f"{direct_diffuse(nee) / direct_diffuse(reference):.4f} x")
    assert abs(direct - 1.0) < 0.07, direct
    assert abs(combined - 1.0) < 0.07, combined
    own = preview(scene, solved(scene, passes=2, filter_direct=True,
                                filter_mode=shgi.InstantGiFilter.NONE).current_field(), samples=1)
    assert not np.array_equal(image["DiffDir"], own["DiffDir"])
    # The control: without filter_direct DiffDir is next-event estimation's, filter or not.
    plain = preview(scene, solved(scene, passes=2, filter_mode=shgi.InstantGiFilter.NONE)
                    .current_field(), samples=1)
    np.testing.assert_array_equal(
        preview(scene, solved(scene, passes=2).current_field(), samples=1)["DiffDir"],
        plain["DiffDir"])


def test_filter_direct_carries_the_skys_direct_light():
    """With filter_direct the sky's direct light on the floor comes from the directional VPLs
    through the SH filter (the renderer's next-event estimation leaves the world out: counted
    twice it would read 2x): DiffDir x DiffCol and Combined means within 2% of the path
    tracer's (1024 spp), per channel."""
    scene = sky_over_a_floor()
    reference = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=1024, seed=11))
    field = solved(scene, passes=4, photons_per_set=256, filter_direct=True).current_field()
    image = preview(scene, field, samples=1)
    direct = direct_diffuse(image) / direct_diffuse(reference)
    combined = float(image["Combined"][..., :3].mean()) / float(
        reference["Combined"][..., :3].mean())
    print(f"sky over a floor, filter_direct: DiffDir x DiffCol {direct:.4f} x, "
          f"Combined {combined:.4f} x the path tracer's")
    assert abs(direct - 1.0) < 0.02, direct
    assert abs(combined - 1.0) < 0.02, combined
    # Per channel: the sky's colour survives the SH.
    ratio = (image["DiffDir"] * image["DiffCol"])[..., :3].mean(axis=(0, 1)) / (
        reference["DiffDir"] * reference["DiffCol"])[..., :3].mean(axis=(0, 1))
    np.testing.assert_allclose(ratio, 1.0, atol=0.02)


@pytest.mark.parametrize("make_scene",
                         [sky_over_a_floor, lamp_over_a_floor, glowing_panel_over_a_floor])
def test_filter_direct_frames_do_not_depend_on_threads_or_tiles(make_scene):
    scene = make_scene()
    field = solved(scene, passes=1, filter_direct=True).current_field()
    images = frames_by_threads_and_tiles(scene, field, 1)
    assert images[0]["DiffDir"].max() > 0.0
    for name in ("Combined", "DiffDir", "GlossDir", "DiffInd"):
        np.testing.assert_array_equal(images[0][name], images[1][name], err_msg=name)


def sky_and_lamps_over_a_floor():
    """The glowing panel over a floor (emissive triangles) under the blue sky of
    sky_over_a_floor, with a point light (a delta light: one sample per set, made at the first
    pass) and a 0.5 m area light (a light with extent): every kind of filter_direct sample."""
    scene = glowing_panel_over_a_floor()
    scene.set_world(shgi.World(color=(0.35, 0.5, 0.8), strength=1.0))
    for kind, x in (("POINT", -0.6), ("AREA", 0.6)):
        light = shgi.Light(name=kind.lower(), type=getattr(shgi.LightType, kind), power=60.0)
        light.size_x = light.size_y = 0.5
        light.world_from_light = np.array([[1, 0, 0, x], [0, 1, 0, 0.5], [0, 0, 1, 0.7],
                                           [0, 0, 0, 1]], np.float32)
        scene.add_light(light)
    scene.commit()
    return scene


def test_filter_direct_samples_gather_the_sky_and_lamps_of_their_passes():
    """With filter_direct a preview sample gathers the sky directions and the samples of lights
    with extent and emissive triangles of its passes only, as its VPLs (passes_per_sample), so
    more passes cost a sample no more: sample 0 of an 8-pass field at 4 passes per sample is
    the 4-pass field's sample 0 bit for bit; the delta light's one sample (made at the first
    pass) is in every sample: over a point light alone the direct light of two samples is the
    same whether they gather passes 0-3 and 4-7 or all 8; and with every kind of sample the
    two samples' direct light is within 5% of gathering all 8 passes (a sample's share of a
    light read once per pass too few or too many would be off by 2x)."""
    scene = sky_and_lamps_over_a_floor()
    eight = solved(scene, passes=8, filter_direct=True).current_field()
    four = solved(scene, passes=4, filter_direct=True).current_field()
    assert eight.sample_passes(1) == [4, 5, 6, 7]
    first = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=2))
    first.render(eight, 1)
    alone = preview(scene, four, samples=1)
    for name in ("Combined", "DiffDir", "GlossDir", "DiffInd"):
        np.testing.assert_array_equal(first.passes()[name], alone[name], err_msg=name)
    # So a renderer may solve passes as its samples need them (F12 does): sample 0 from the
    # 4-pass field, sample 1 from the 8-pass one, is the 8-pass field's frame.
    split = preview(scene, eight, samples=2)
    lazy = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=5, samples=2))
    lazy.render(four, 1)
    lazy.render(eight, 1)
    for name in ("Combined", "DiffDir", "GlossDir", "DiffInd"):
        np.testing.assert_array_equal(lazy.passes()[name], split[name], err_msg=name)
    every = preview(scene, solved(scene, passes=8, passes_per_sample=8, filter_direct=True)
                    .current_field(), samples=2)
    ratio = direct_diffuse(split) / direct_diffuse(every)
    print(f"sky, lamps and panel, 8 passes: DiffDir x DiffCol of 4 per sample {ratio:.4f} x "
          f"that of all 8")
    assert abs(ratio - 1.0) < 0.05, ratio
    lamp = lamp_over_a_floor()
    split = preview(lamp, solved(lamp, passes=8, filter_direct=True).current_field(),
                    samples=2)
    every = preview(lamp, solved(lamp, passes=8, passes_per_sample=8, filter_direct=True)
                    .current_field(), samples=2)
    assert direct_diffuse(split) > 0.0
    np.testing.assert_array_equal(split["DiffDir"], every["DiffDir"])


def test_filter_direct_frames_of_passes_per_sample_do_not_depend_on_threads_or_tiles():
    scene = sky_and_lamps_over_a_floor()
    field = solved(scene, passes=8, passes_per_sample=2, filter_direct=True).current_field()
    images = frames_by_threads_and_tiles(scene, field, 3)
    assert images[0]["DiffDir"].max() > 0.0
    for name in ("Combined", "DiffDir", "GlossDir", "DiffInd"):
        np.testing.assert_array_equal(images[0][name], images[1][name], err_msg=name)


def test_a_bake_with_filter_direct_counts_the_sky_once():
    """A bake over a filter_direct field: the field includes the world's direct light, so the
    baker's next-event estimation leaves the world out. A Lambert plane under a uniform world
    bakes DIRECT_INDIRECT to the world's radiance (E / pi), as without the field, within 2%
    per channel (counted twice it would read 2x, left out 0x)."""
    from test_bake import WORLD_RADIANCE, options, plane_job, plane_scene
    from shgi import bake
    scene = plane_scene()
    field = solved(scene, passes=4, photons_per_set=256, filter_direct=True).current_field()
    _, texels = bake.bake_object(scene, plane_job(), options(content="DIRECT_INDIRECT"), field)
    mean = texels.color.reshape(-1, 3).mean(axis=0)
    print(f"plane under a uniform world, filter_direct bake: {mean / WORLD_RADIANCE} x L")
    np.testing.assert_allclose(mean / WORLD_RADIANCE, 1.0, atol=0.02)


def test_a_bake_with_filter_direct_counts_a_lamp_once():
    """A bake over a filter_direct field with a point light 1 m over a 2 m Lambert plane: the
    baker leaves the lamp out of next-event estimation (includes_lights_direct), so the 32 x 32
    lightmap's mean is within 2% of the bake without a field (counted twice: 2x). With each
    texel's own set (filter NONE) the mean is the L2 law's over the plane (1.004 x); the filter
    within the chart adds its blur (at 8 x 8 texels, a window of 1.25 m: 1.17 x)."""
    from test_bake import options, plane_job, plane_scene
    from shgi import bake
    light = shgi.Light(name="lamp", type=shgi.LightType.POINT, power=100.0)
    light.world_from_light = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1.0],
                                       [0, 0, 0, 1]], np.float32)
    scene = plane_scene(world=((0.0, 0.0, 0.0), 0.0), lights=[light])
    job, content = plane_job(32), options(content="DIRECT_INDIRECT")
    exact = bake.bake_object(scene, job, content, None)[1].color.reshape(-1, 3).mean(axis=0)
    for mode, tolerance in ((shgi.InstantGiFilter.SH, 0.02), (shgi.InstantGiFilter.NONE, 0.01)):
        field = solved(scene, passes=1, filter_direct=True, filter_mode=mode).current_field()
        mean = bake.bake_object(scene, job, content, field)[1].color.reshape(-1, 3).mean(axis=0)
        print(f"point light over a plane, filter_direct bake ({mode.name}): {mean / exact} x")
        np.testing.assert_allclose(mean / exact, 1.0, atol=tolerance)



def test_a_bake_with_filter_direct_counts_emissive_triangles_once():
    """A bake over a filter_direct field with a 0.6 m emissive panel (two triangles) 1 m over
    the 2 m Lambert plane, black world: the baker leaves the triangles out of next-event
    estimation, the field carries them, so the 32 x 32 lightmap's mean is within 2% of the
    bake without a field (counted twice: 2x), as the lamp's above (each texel's own set within
    1%; measured 1.019 x and 1.009 x, the chart filter's blur of the panel's bright centre and
    L2's law); and it is the field's light: the SH filter and each texel's own set bake different
    texels (next-event estimation's would not depend on the filter)."""
    from shgi import bake
    from test_bake import options, plane_job
    scene = shgi.Scene()
    paint = scene.add_material(shgi.Material(name="paint", base_color=(0.8, 0.8, 0.8),
                                             specular=0.0,
                                             diffuse_model=shgi.DiffuseModel.LAMBERT))
    glow = scene.add_material(shgi.Material(name="glow", base_color=(0.0, 0.0, 0.0),
                                            specular=0.0, emission_color=(1.0, 0.9, 0.7),
                                            emission_strength=20.0))
    square = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    scene.add_instance(scene.add_mesh(positions=square, triangles=tris, name="plane",
                                      uvs={"LightmapUV": (square[:, :2] + 1.0) / 2.0},
                                      material_indices=np.full(2, paint)), np.eye(4), "plane")
    panel = 0.3 * square + np.array([0, 0, 1], np.float32)
    scene.add_instance(scene.add_mesh(positions=panel, triangles=tris, name="panel",
                                      material_indices=np.full(2, glow)), np.eye(4), "panel")
    scene.set_world(shgi.World(color=(0.0, 0.0, 0.0), strength=0.0))
    scene.commit()
    job, content = plane_job(32), options(content="DIRECT_INDIRECT")
    # The bake without a field at 256 samples (8 read 0.15% low): the reference's own noise
    # out of the comparison.
    exact = bake.bake_object(scene, job, options(content="DIRECT_INDIRECT", samples=256),
                             None)[1].color.reshape(-1, 3).mean(axis=0)
    texels = {}
    for mode, tolerance in ((shgi.InstantGiFilter.SH, 0.02), (shgi.InstantGiFilter.NONE, 0.01)):
        field = solved(scene, passes=1, filter_direct=True, filter_mode=mode).current_field()
        texels[mode] = bake.bake_object(scene, job, content, field)[1].color
        mean = texels[mode].reshape(-1, 3).mean(axis=0)
        print(f"emissive panel over a plane, filter_direct bake ({mode.name}): {mean / exact} x")
        np.testing.assert_allclose(mean / exact, 1.0, atol=tolerance)
    assert not np.array_equal(texels[shgi.InstantGiFilter.SH], texels[shgi.InstantGiFilter.NONE])


def test_filter_direct_bakes_of_direct_or_indirect_light_alone():
    """Content DIRECT over a filter_direct field samples every emitter (the field, which is not
    read, does not stand in for them): the lamp and the sky within 2% of the bake without a
    field. Content INDIRECT reads the field without its direct light (without_direct): a lone
    plane has no indirect light, exactly 0 (before, the field's lamp and sky showed up there and
    a DIRECT bake came out black)."""
    from test_bake import options, plane_job, plane_scene
    from shgi import bake
    light = shgi.Light(name="lamp", type=shgi.LightType.POINT, power=100.0)
    light.world_from_light = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 1.0],
                                       [0, 0, 0, 1]], np.float32)
    scene = plane_scene(lights=[light])  # and the uniform world of test_bake
    field = solved(scene, passes=1, filter_direct=True).current_field()
    job = plane_job(16)
    exact = bake.bake_object(scene, job, options(content="DIRECT", samples=64), None)[1]
    direct = bake.bake_object(scene, job, options(content="DIRECT", samples=64), field)[1]
    ratio = direct.color.reshape(-1, 3).mean(axis=0) / exact.color.reshape(-1, 3).mean(axis=0)
    print(f"filter_direct field, DIRECT bake: {ratio} x the bake without a field")
    np.testing.assert_allclose(ratio, 1.0, atol=0.02)
    indirect = bake.bake_object(scene, job, options(content="INDIRECT"), field)[1]
    assert indirect.color.max() == 0.0


# --- the Show list: agreement with the path tracer -------------------------------------------

_RENDERS = {}


def rendered(name, seed=5, final_gather=False, **fields):
    """(reference, preview, field) of scene `name` solved with InstantGiSettings `fields`;
    final_gather: read through a final gather, the field one diffuse bounce shallower (the
    add-on's accounting: Light Paths > Diffuse 4 gives 3 VPL bounces)."""
    key = (name, seed, final_gather, tuple(sorted(fields.items())))
    if key not in _RENDERS:
        scale, samples = REFERENCES[name]
        scene, ref = path_traced_reference(getattr(scenes, name), scale, samples)
        if final_gather:
            fields = {"vpl_bounces": 3, **fields}
        solver = solved(scene, seed=seed, **fields)
        field = solver.current_field()
        _RENDERS[key] = ref, preview(scene, field, final_gather=final_gather), field
    return _RENDERS[key]


# Seeds of the DiffInd agreement: one solve's DiffInd mean with the default 4 passes (~2000
# VPLs) scatters from seed to seed by 2.2% (sun room) and 4.5% (Cornell box) (one standard
# deviation over seeds 5..12), so the test holds the mean over four solves to the 5%.
AGREEMENT_SEEDS = (5, 6, 7, 8)


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room"])
def test_indirect_diffuse_agrees_with_path_tracer(name):
    """DiffInd x DiffCol within 5% of the path tracer's with >= 1024 VPLs per solve: the mean
    over AGREEMENT_SEEDS' solves (one solve reads the VPLs' noise as much as the method's
    bias)."""
    ratios = []
    for seed in AGREEMENT_SEEDS:
        ref, image, field = rendered(name, seed=seed)
        assert field.vpl_count >= 1024
        ratios.append(indirect_diffuse(image) / indirect_diffuse(ref))
    ratio = float(np.mean(ratios))
    print(f"{name}: DiffInd x DiffCol {ratio:.3f} x the path tracer's over seeds "
          f"{AGREEMENT_SEEDS} (each: {', '.join(f'{r:.3f}' for r in ratios)})")
    assert abs(ratio - 1.0) < 0.05, ratio


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room"])
def test_indirect_diffuse_converges_to_the_path_tracers(name):
    """With 16 x more VPLs (256 light paths per set, ~37000 VPLs) the noise is gone and what
    is left is the method's bias: DiffInd x DiffCol within 2% of the path tracer's. The light
    paths' glossy scatterings have a budget of their own (glossy_bounces, Light Paths >
    Glossy) as the path tracer's: counted against vpl_bounces they cut the paths that bounce
    off the plaster's specular layer short, and the sun room converged to 0.962 x (Cornell box
    0.993 x); now 1.005 x (1.009 x)."""
    scale, samples = REFERENCES[name]
    scene, ref = path_traced_reference(getattr(scenes, name), scale, samples)
    field = solved(scene, photons_per_set=256).current_field()
    ratio = indirect_diffuse(preview(scene, field, samples=4)) / indirect_diffuse(ref)
    print(f"{name}: {field.vpl_count} VPLs, DiffInd x DiffCol {ratio:.4f} x the path tracer's")
    assert abs(ratio - 1.0) < 0.02, ratio


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room"])
@pytest.mark.parametrize("glossy_from_vpls", [False, True])
def test_indirect_glossy_converges_to_the_path_tracers(name, glossy_from_vpls):
    """The glossy light with the VPLs' noise gone (as the diffuse convergence test): GlossInd x
    GlossCol within 7% of the path tracer's, read from the L2 SH and from the VPLs
    (glossy_from_vpls). A pixel's SH holds light from above its surface only, and a lobe about
    the reflected direction read the zero below the horizon: the SH's 0.72 x the path tracer's on
    the Cornell box (sun room 0.90 x; a default solve, bench/instant_gi_glossy_horizon.py) before
    both read the lobe clipped at the horizon about its
    dominant direction, normalised above it (FieldLookup::horizon; glossy_from_vpls' lobe
    normalised over the upper hemisphere). Now SH 1.057 x / 0.991 x, VPLs 0.974 x / 0.949 x."""
    scale, samples = REFERENCES[name]
    scene, ref = path_traced_reference(getattr(scenes, name), scale, samples)
    field = solved(scene, photons_per_set=256, glossy_from_vpls=glossy_from_vpls).current_field()
    image = preview(scene, field, samples=4)
    ratio = float((image["GlossInd"] * image["GlossCol"]).mean()) / float(
        (ref["GlossInd"] * ref["GlossCol"]).mean())
    print(f"{name}, glossy_from_vpls={glossy_from_vpls}: GlossInd x GlossCol {ratio:.4f} x the "
          f"path tracer's")
    assert abs(ratio - 1.0) < 0.07, ratio


@pytest.mark.reference
def test_sun_room_with_filter_direct_agrees_with_path_tracer():
    """filter_direct on the sun room (its sky enters through the window as directional VPLs,
    its sun as one delta per set): the Combined mean within 5% of the path tracer's."""
    ref, image, field = rendered("sun_room", filter_direct=True)
    combined = float(image["Combined"][..., :3].mean()) / float(ref["Combined"][..., :3].mean())
    direct = direct_diffuse(image) / direct_diffuse(ref)
    quality = psnr(ref["Combined"], image["Combined"])
    print(f"sun room, filter_direct: Combined {combined:.3f} x, DiffDir x DiffCol {direct:.3f} x "
          f"the path tracer's, DiffInd x DiffCol "
          f"{indirect_diffuse(image) / indirect_diffuse(ref):.3f} x, PSNR {quality:.2f} dB")
    assert abs(combined - 1.0) < 0.05, combined


@pytest.mark.reference
@missed("DiffDir x DiffCol 0.927 x: the sun at mu 0.51 on the floor through L2 reads "
        "(3/32 + mu/2 + 15 mu^2/32) / mu = 0.923 x")
def test_sun_room_with_filter_direct_direct_light_within_five_percent():
    """The sun room's DiffDir x DiffCol mean within 5% of the path tracer's with filter_direct.
    It held (0.994 x) while only the sky went through the SH; with the sun too, the floor's
    sunlit patch follows the L2 law for a delta at mu = 0.51 (0.923 x)."""
    ref, image, _ = rendered("sun_room", filter_direct=True)
    direct = direct_diffuse(image) / direct_diffuse(ref)
    assert abs(direct - 1.0) < 0.05, direct


# Passes of the PSNR renders that take new VPLs per sample: 64 passes, 4 per sample (the
# default passes_per_sample), so each of the 16 samples gathers as many VPLs as a 4-pass solve's
# sample does (the same shadow rays per frame) and the frame averages 16 x as many.
SAMPLE_PASSES = 64


@pytest.mark.reference
@pytest.mark.parametrize("name, passes", [
    ("cornell_box", PASSES),
    pytest.param("sun_room", PASSES, marks=missed("PSNR 30.85 dB (seeds 5..12: 29.65 to "
                                                  "31.22): every sample shares the VPLs")),
    ("cornell_box", SAMPLE_PASSES),
    ("sun_room", SAMPLE_PASSES),
])
def test_psnr_against_path_tracer(name, passes):
    """Combined PSNR >= 32 dB with >= 1024 VPLs and 16 samples. With 4 passes every sample
    gathers them all and shares their noise (the sun room misses: a strict xfail); with 64
    passes, 4 per sample, each sample gathers new ones at the same cost per sample (seeds
    5..12: sun room 32.57 to 32.84 dB)."""
    ref, image, field = rendered(name) if passes == PASSES else rendered(name, passes=passes)
    quality = psnr(ref["Combined"], image["Combined"])
    print(f"{name}, {passes} passes: Combined PSNR {quality:.2f} dB with {field.vpl_count} "
          f"VPLs, {len(field.sample_passes(0))} passes per sample")
    assert field.vpl_count >= 1024
    assert quality >= 32.0


@pytest.mark.reference
def test_dim_room_is_within_five_percent():
    """The two rooms' dim room: every VPL reaches a pixel only through an exact shadow ray, so
    the bright room's light does not come through the wall. The dim lamp has 1% of the power,
    so 1% of the light paths: 128 per set (8x the default; with 16 per set, seeds 5 and 6 read
    Combined 1.20x and 0.84x: too few VPLs in the dim room, not leaks). Even at 128 one solve
    scatters by ~5% from seed to seed (seeds 5..8: DiffInd 1.058, 0.923, 0.949, 0.978 x), so
    the means over AGREEMENT_SEEDS' solves are held to the 5%."""
    combined, indirect = [], []
    for seed in AGREEMENT_SEEDS:
        ref, image, _ = rendered("two_rooms", seed=seed, photons_per_set=128)
        combined.append(float(image["Combined"][..., :3].mean() /
                              ref["Combined"][..., :3].mean()))
        indirect.append(indirect_diffuse(image) / indirect_diffuse(ref))
    print(f"dim room over seeds {AGREEMENT_SEEDS}: Combined {np.mean(combined):.3f}, DiffInd x "
          f"DiffCol {np.mean(indirect):.3f} x the path tracer's (each: "
          f"{', '.join(f'{r:.3f}' for r in indirect)})")
    assert abs(np.mean(combined) - 1.0) < 0.05
    assert abs(np.mean(indirect) - 1.0) < 0.05


def gathered_ratios(name, **fields):
    """Per seed of AGREEMENT_SEEDS, (Combined, DiffInd x DiffCol) means of scene `name` read
    through a final gather over the path tracer's."""
    ratios = []
    for seed in AGREEMENT_SEEDS:
        ref, image, _ = rendered(name, seed=seed, final_gather=True, **fields)
        ratios.append((float(image["Combined"][..., :3].mean() / ref["Combined"][..., :3].mean()),
                       indirect_diffuse(image) / indirect_diffuse(ref)))
    return np.array(ratios)


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room"])
def test_final_gather_agrees_with_path_tracer(name):
    """Through a final gather (a gather ray per sample reading one set where it lands, the
    field one bounce shallower) Combined and DiffInd x DiffCol within 5% of the path tracer's,
    the tolerance of the other methods' final-gather tests, over AGREEMENT_SEEDS' solves as
    test_indirect_diffuse_agrees_with_path_tracer holds the first surfaces."""
    ratios = gathered_ratios(name)
    mean = ratios.mean(axis=0)
    print(f"{name} through a final gather: Combined {mean[0]:.3f}, DiffInd x DiffCol "
          f"{mean[1]:.3f} x the path tracer's over seeds {AGREEMENT_SEEDS} (each: "
          f"{', '.join(f'{c:.3f}/{d:.3f}' for c, d in ratios)})")
    assert np.all(np.abs(mean - 1.0) < 0.05), mean


@pytest.mark.reference
def test_dim_room_through_a_final_gather_is_within_five_percent():
    """The two rooms' dim room read through a final gather, as test_dim_room_is_within_five_
    percent reads it at the first surfaces (128 light paths per set, the means over
    AGREEMENT_SEEDS' solves): the gather rays' hits see the bright room's light only through
    exact shadow rays, so nothing leaks through the wall."""
    ratios = gathered_ratios("two_rooms", photons_per_set=128)
    mean = ratios.mean(axis=0)
    print(f"dim room through a final gather: Combined {mean[0]:.3f}, DiffInd x DiffCol "
          f"{mean[1]:.3f} x the path tracer's over seeds {AGREEMENT_SEEDS} (each: "
          f"{', '.join(f'{c:.3f}/{d:.3f}' for c, d in ratios)})")
    assert np.all(np.abs(mean - 1.0) < 0.05), mean


@pytest.mark.reference
def test_sh_filter_matches_irradiance_filter_on_a_diffuse_box():
    """Section 4.2: without normal maps, filtering SH and filtering irradiance agree."""
    scale, samples = REFERENCES["cornell_box"]
    scene, _ = path_traced_reference(scenes.cornell_box, scale, samples)
    field_sh = solved(scene).current_field()
    field_e = solved(scene, filter_mode=shgi.InstantGiFilter.IRRADIANCE).current_field()
    sh_image, e_image = preview(scene, field_sh, samples=4), preview(scene, field_e, samples=4)
    ratio = indirect_diffuse(sh_image) / indirect_diffuse(e_image)
    sh_ind, e_ind = sh_image["DiffInd"][..., :3], e_image["DiffInd"][..., :3]
    relative_rmse = float(np.sqrt(((sh_ind - e_ind) ** 2).mean()) / e_ind.mean())
    print(f"Cornell box: SH filter / irradiance filter {ratio:.4f}, relative RMSE "
          f"{relative_rmse:.4f}")
    assert abs(ratio - 1.0) < 0.02
    assert relative_rmse < 0.02


# --- the Show list: the normal-mapped floor (Figs. 2 and 4) ---------------------------------

STRIPES = 12      # normal-map stripes across the floor
TILT = 0.6        # radians: the stripes' normals lean this far towards -x and +x in turn


def look_at(eye, target, up=(0.0, 0.0, 1.0)):
    eye, target, up = (np.asarray(v, np.float64) for v in (eye, target, up))
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross(up, back)
    right /= np.linalg.norm(right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, np.cross(back, right), back, eye
    return m


def striped_normal_texture(size=96):
    u = (np.arange(size) + 0.5) / size
    angle = TILT * np.sign(np.sin(2.0 * math.pi * STRIPES * u))
    n = np.stack([np.sin(angle), np.zeros(size), np.cos(angle)], axis=-1)
    texels = np.concatenate([0.5 * n + 0.5, np.ones((size, 1))], axis=-1)
    return shgi.Texture(np.ascontiguousarray(np.tile(texels[None], (8, 1, 1)), np.float32),
                        name="stripes")


def normal_mapped_floor():
    """A 2 m floor with a striped tangent-space normal map and a white wall at x = +1, a point
    light 0.4 m from the wall: the floor's indirect light comes mostly from the wall, and the
    stripes lean towards it and away from it in turn."""
    scene = shgi.Scene()
    texture = scene.add_texture(striped_normal_texture())
    bumpy = scene.add_material(shgi.Material(name="bumpy", base_color=(0.7, 0.7, 0.7),
                                             specular=0.0,
                                             diffuse_model=shgi.DiffuseModel.LAMBERT,
                                             normal_texture=texture))
    white = scene.add_material(shgi.Material(name="white", base_color=(0.8, 0.8, 0.8),
                                             specular=0.0,
                                             diffuse_model=shgi.DiffuseModel.LAMBERT))
    tris = np.array([[0, 1, 2], [0, 2, 3]], np.int32)
    floor = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    uvs = 0.5 * floor[:, :2] + 0.5
    tangents = np.tile(np.array([1, 0, 0, 1], np.float32), (4, 1))
    scene.add_instance(scene.add_mesh(positions=floor, triangles=tris, uvs=uvs,
                                      tangents=tangents, material_indices=[bumpy, bumpy]),
                       np.eye(4))
    wall = np.array([[1, -1, 0], [1, 1, 0], [1, 1, 2], [1, -1, 2]], np.float32)
    scene.add_instance(scene.add_mesh(positions=wall, triangles=tris,
                                      material_indices=[white, white]), np.eye(4))
    lamp = np.eye(4)
    lamp[:3, 3] = (0.6, 0.0, 0.8)
    scene.add_light(shgi.Light(type=shgi.LightType.POINT, power=100.0, world_from_light=lamp))
    scene.set_world(shgi.World(strength=0.0))
    camera = shgi.Camera(lens=30.0, resolution_x=96, resolution_y=72)
    camera.world_from_camera = look_at((-0.6, 0.0, 1.3), (0.2, 0.0, 0.0))
    scene.set_camera(camera)
    scene.commit()
    return scene


_FLOOR = {}


def floor_images():
    """DiffInd of the floor scene for each filter (4 x 4 sets) and of brute force (the same
    VPLs in one set, every pixel gathering all of them), 4 samples each."""
    if not _FLOOR:
        scene = normal_mapped_floor()
        images = {}
        for mode in ("SH", "IRRADIANCE", "STRICT", "NONE"):
            field = solved(scene, passes=2, photons_per_set=32,
                           filter_mode=getattr(shgi.InstantGiFilter, mode)).current_field()
            images[mode] = preview(scene, field, samples=4)["DiffInd"][..., :3]
        field = solved(scene, passes=2, photons_per_set=16 * 32, sets_x=1, sets_y=1,
                       filter_mode=shgi.InstantGiFilter.NONE).current_field()
        images["BRUTE_FORCE"] = preview(scene, field, samples=4)["DiffInd"][..., :3]
        _FLOOR.update(images)
    return _FLOOR


def save_floor_images(images):
    IMAGES.mkdir(parents=True, exist_ok=True)
    scale = np.percentile(images["BRUTE_FORCE"], 99)
    for mode, pixels in images.items():
        rgb = np.clip(pixels / scale, 0.0, 1.0)  # write_png encodes sRGB
        rgba = np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,))], axis=-1)
        shgi.write_png(str(IMAGES / f"instant_gi_floor_{mode.lower()}.png"),
                       np.ascontiguousarray(rgba, np.float32))


def rmse(image, reference):
    return float(np.sqrt(((image - reference) ** 2).mean()))


@pytest.mark.reference
def test_sh_filter_keeps_normal_map_detail():
    """Figs. 2 and 4: against brute force, the SH filter's RMSE is at most half the irradiance
    filter's (which blends across the stripes) and below the strict filter's (which stops at
    the stripes and keeps the interleave pattern)."""
    images = floor_images()
    save_floor_images(images)
    brute = images["BRUTE_FORCE"]
    assert brute.mean() > 0.0
    errors = {mode: rmse(images[mode], brute) / float(brute.mean())
              for mode in ("SH", "IRRADIANCE", "STRICT", "NONE")}
    print("relative RMSE against brute force: " +
          ", ".join(f"{mode} {error:.4f}" for mode, error in errors.items()))
    assert errors["SH"] <= 0.5 * errors["IRRADIANCE"]
    assert errors["SH"] < errors["STRICT"]


@pytest.mark.reference
def test_sh_filter_residual_per_interleave_phase_is_under_one_percent():
    """Each of the 16 interleave phases (pixels (x mod 4, y mod 4)) averages within 1% of brute
    force over the same pixels: no set shows through the filter. It held once the near field
    (near_field_reach, 4 by default) left the filter: without it, 2.1%, the window blurring the
    wall's foot."""
    images = floor_images()
    sh, brute = images["SH"].sum(-1), images["BRUTE_FORCE"].sum(-1)
    residuals = []
    for j in range(4):
        for i in range(4):
            residuals.append(sh[j::4, i::4].mean() / brute[j::4, i::4].mean() - 1.0)
    none = images["NONE"].sum(-1)
    raw = [none[j::4, i::4].mean() / brute[j::4, i::4].mean() - 1.0
           for j in range(4) for i in range(4)]
    print(f"largest residual per phase: SH filter {max(map(abs, residuals)):.4f}, "
          f"unfiltered {max(map(abs, raw)):.4f}")
    assert max(map(abs, residuals)) < 0.01



def without_normal_map(scene):
    """The same scene with its normal-mapped material flat."""
    for i, material in enumerate(scene.materials):
        if material.normal_texture >= 0:
            material.normal_texture = -1
            scene.set_material(i, material)
    scene.commit()
    return scene


@pytest.mark.reference
def test_normal_map_changes_the_floors_light_as_it_changes_the_path_tracers():
    """On the normal-mapped floor, the SH filter's indirect diffuse light (DiffInd over the
    floor's pixels, found from the flat floor's Normal pass) over the path tracer's is within 2%
    (the normal-map calibration's tolerance) of the same ratio on the flat floor, both over two
    VPL seeds. The path tracer fades each light by the diffuse lobe's bump shadowing (Cycles');
    the gather takes it in through the shadowed cosine's SH (render/bump_irradiance.h). Without
    it the normal map's change was 1.173x over four seeds; with it 1.012x (1.008-1.020 each)."""
    ratios, floor = {}, None
    for name, scene in (("flat", without_normal_map(normal_mapped_floor())),
                        ("normal map", normal_mapped_floor())):
        path = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=256, seed=11))
        if floor is None:
            floor = path["Normal"][..., 2] > 0.9
        reference = float(path["DiffInd"][..., :3][floor].mean())
        instant = [float(preview(scene, solved(scene, passes=16, seed=seed, photons_per_set=64)
                                 .current_field(), samples=16)["DiffInd"][..., :3][floor].mean())
                   for seed in (5, 6)]
        ratios[name] = np.mean(instant) / reference
    change = ratios["normal map"] / ratios["flat"]
    print(f"floor DiffInd over the path tracer's: {ratios}; the normal map's change {change:.4f}")
    assert abs(change - 1.0) < 0.02

def floor_edge_rows(image):
    """The pixels of the rows on either side of the floor's edge against the wall (from the
    Normal pass: the floor's stripes lean at most TILT from +z, the wall faces -x), away from
    the image's sides (where the wall's near end meets the floor too)."""
    floor = image["Normal"][..., 2] > 0.5
    edge = np.zeros_like(floor)
    edge[1:] |= floor[1:] != floor[:-1]
    edge[:-1] |= floor[1:] != floor[:-1]
    edge[:, :2] = edge[:, -2:] = False
    return edge


def test_near_field_is_every_sets_vpls_within_reach():
    """near_field_reach: a pixel gathers the VPLs nearer than the reach times its filter window's
    (the farthest neighbour it blends) from every set, each scaled by 1 / the sets, and keeps
    them out of the filter. At the largest reach with 8 x 8 sets (windows 9 pixels across, at
    least 6 cm on the floor, so near radii of at least 3.8 m: more than the scene's 3 m) every
    VPL is near every pixel, which is then brute force's pixel (the same VPLs in one set) up to
    the order of the sums; frames do not depend on threads or tiles."""
    scene = normal_mapped_floor()
    field = solved(scene, passes=2, photons_per_set=8, sets_x=8, sets_y=8,
                   near_field_reach=64.0).current_field()
    images = frames_by_threads_and_tiles(scene, field, 2)
    for name in ("Combined", "DiffInd", "GlossInd"):
        np.testing.assert_array_equal(images[0][name], images[1][name], err_msg=name)
    brute = preview(scene, solved(scene, passes=2, photons_per_set=64 * 8, sets_x=1, sets_y=1,
                                  filter_mode=shgi.InstantGiFilter.NONE).current_field(),
                    samples=2)["DiffInd"][..., :3]
    assert brute.mean() > 0.0
    relative = (np.abs(images[0]["DiffInd"][..., :3] - brute).max(-1) /
                np.maximum(brute.max(-1), 1e-9))
    assert relative.max() < 1e-4, relative.max()


def test_gather_cut_windows_gathers_every_set_where_an_edge_cuts_the_window():
    """gather_cut_windows (off by default): a pixel whose filter window an edge cuts gathers
    every set itself (each scaled by 1 / the sets) and skips the filter, so at the wall's foot
    it is brute force's pixel (the same VPLs in one set) up to the order of the sums, while
    pixels away from edges keep the filtered light; frames do not depend on threads or tiles."""
    assert shgi.InstantGiSettings().gather_cut_windows is False
    scene = normal_mapped_floor()
    field = solved(scene, passes=2, photons_per_set=32, gather_cut_windows=True).current_field()
    images = frames_by_threads_and_tiles(scene, field, 2)
    for name in ("Combined", "DiffInd", "GlossInd"):
        np.testing.assert_array_equal(images[0][name], images[1][name], err_msg=name)
    brute = preview(scene, solved(scene, passes=2, photons_per_set=16 * 32, sets_x=1, sets_y=1,
                                  filter_mode=shgi.InstantGiFilter.NONE).current_field(),
                    samples=2)["DiffInd"][..., :3]
    image = images[0]
    relative = (np.abs(image["DiffInd"][..., :3] - brute).max(-1) /
                np.maximum(brute.max(-1), 1e-9))
    edge = floor_edge_rows(image)
    assert edge.sum() >= 2 * image["DiffInd"].shape[1] - 8
    assert relative[edge].max() < 1e-4
    assert (relative > 1e-4).mean() > 0.5  # most pixels are still the filter's


@pytest.mark.reference
def test_gather_cut_windows_brings_the_residual_per_phase_under_one_percent():
    """Without the near field (near_field_reach 0, the paper's filter), the residual per
    interleave phase (2.1%) is the filter's blur at the wall's foot, where the window is cut to the side away from the
    wall: the rows either side of the edge read 1.58x and 1.51x brute force, and since the edge
    is horizontal in the image it lands on row phases (column phases agree within 0.2%). With
    gather_cut_windows those pixels gather every set instead: under 1%, and a lower RMSE."""
    scene = normal_mapped_floor()
    field = solved(scene, passes=2, photons_per_set=32, gather_cut_windows=True,
                   near_field_reach=0.0).current_field()
    sh = preview(scene, field, samples=4)["DiffInd"][..., :3]
    plain = preview(scene, solved(scene, passes=2, photons_per_set=32,
                                  near_field_reach=0.0).current_field(),
                    samples=4)["DiffInd"][..., :3]
    brute = floor_images()["BRUTE_FORCE"]
    residuals = [sh.sum(-1)[j::4, i::4].mean() / brute.sum(-1)[j::4, i::4].mean() - 1.0
                 for j in range(4) for i in range(4)]
    errors = {"SH": rmse(plain, brute), "cut windows gathered": rmse(sh, brute)}
    print(f"largest residual per phase {max(map(abs, residuals)):.4f}; relative RMSE " +
          ", ".join(f"{k} {v / float(brute.mean()):.4f}" for k, v in errors.items()))
    assert max(map(abs, residuals)) < 0.01
    assert errors["cut windows gathered"] < errors["SH"]
