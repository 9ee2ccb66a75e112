"""Light propagation volumes (seed 003; the PROPAGATION method) through Python.

Agreement with the reference path tracer on the project's Cornell box, sun room and two rooms
(the same references as the photon lattice's and probe grid's tests), for the LPV (order 1) and
the HOLPV (order 2), default settings (multi-bounce VPLs, 32 cells, light carried 32 cells: 35
LPV and 23 HOLPV steps; unclamped, clamped at walls, travel re-injection, damping, both leak
corrections): the mean of DiffInd x DiffCol within 10% and the HOLPV's Combined PSNR above the
LPV's. Where the method misses a target the test stays, marked as an expected failure with the
measured figure (strict: an improvement that meets it must remove the mark). Tests of other
settings name every setting the defaults changed (SEED: the defaults before settings layout 6).
"""

import sys
import threading

import pytest

import shgi
from blender_support import REPO_ROOT
from shgi.metrics import psnr
from scene_support import committed, path_traced_reference

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/ is not a package)

SCALE = 0.25
REFERENCE_SAMPLES = 2048
# The two rooms at the probe grid's leak-test size.
REFERENCES = {"cornell_box": (SCALE, REFERENCE_SAMPLES), "sun_room": (SCALE, REFERENCE_SAMPLES),
              "two_rooms": (0.5, 512)}

_RENDERS = {}
# The defaults before settings layout 6 (the seed's method with the flux and clamp corrections:
# rescaled lobes re-injected along the face normals, 8 steps, no leak correction), which the
# tests of other settings start from (the re-injected beams unwindowed, the photons shared
# among the lamps by flux alone, as they were measured).
SEED = dict(steps=8, damping=False, occlude_first_step=False, drop_outward_vpls=False,
            travel_reinjection=False, unclamped_transfer=False, clamp_at_surfaces=False,
            windowed_reinjection=False, light_share_uniform=0.0)


def indirect_diffuse(passes):
    return float((passes["DiffInd"] * passes["DiffCol"]).mean())


def rendered(name, order):
    """(reference passes, preview passes over the volume's field) for a scene and order."""
    key = (name, order)
    if key not in _RENDERS:
        scale, samples = REFERENCES[name]
        scene, ref = path_traced_reference(getattr(scenes, name), scale, samples)
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(seed=5, order=order))
        volume.refine()
        preview, _ = shgi.render_preview(scene, volume.current_field(),
                                         shgi.PreviewSettings(seed=5))
        _RENDERS[key] = ref, preview
    return _RENDERS[key]


def missed(figure):
    return pytest.mark.xfail(strict=True, reason=f"target missed; measured {figure}")


def assert_agrees(label, ref, preview):
    """The agreement target: the DiffInd x DiffCol mean within 10% of the path tracer's; the
    ratio and the Combined PSNR printed after `label`."""
    ratio = indirect_diffuse(preview) / indirect_diffuse(ref)
    print(f"{label}: DiffInd x DiffCol {ratio:.3f} x the path tracer's, Combined PSNR "
          f"{psnr(ref['Combined'], preview['Combined']):.2f} dB")
    assert abs(ratio - 1.0) < 0.10, ratio


# The agreement scenes, each with both orders (1: LPV, 2: HOLPV).
SCENE_ORDERS = [(name, order) for name in ("cornell_box", "sun_room", "two_rooms")
                for order in (1, 2)]


@pytest.mark.reference
@pytest.mark.parametrize("name, order", SCENE_ORDERS)
def test_indirect_diffuse_agrees_with_path_tracer(name, order):
    ref, preview = rendered(name, order)
    assert_agrees(f"{name} order {order}", ref, preview)


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room", "two_rooms"])
def test_holpv_is_closer_than_lpv(name):
    """The HOLPV's image closer to the path tracer's than the LPV's at the defaults (measured
    +2.26, +0.56, +0.42 dB: Cornell box / sun room / two rooms, seed 5; seeds 5-8 in
    docs/methods.md, "A share of the photons per lamp"). Before the HOLPV was clamped per
    transfer and the photons shared among the lamps, the two rooms read 25.8 dB against the
    LPV's 26.9."""
    ref, lpv = rendered(name, 1)
    _, holpv = rendered(name, 2)
    lpv_psnr, holpv_psnr = psnr(ref["Combined"], lpv["Combined"]), psnr(ref["Combined"],
                                                                         holpv["Combined"])
    print(f"{name}: Combined PSNR LPV {lpv_psnr:.2f} dB, HOLPV {holpv_psnr:.2f} dB")
    assert holpv_psnr > lpv_psnr


def sunlit_patch_indirect(preview, ref):
    """The sun room's sunlit floor patch (more than half the floor's brightest direct light):
    DiffInd x DiffCol there over the path tracer's (bench/propagation_surface_error.py's mask)."""
    import numpy as np
    exact = ref["DiffInd"] * ref["DiffCol"]
    up = preview["Normal"][..., 2]
    direct = preview["DiffDir"][..., :3].mean(-1)
    floor = up > 0.9
    lit = floor & (direct > 0.5 * direct[floor].max())
    return float((preview["DiffInd"] * preview["DiffCol"])[lit].mean() / exact[lit].mean())


@pytest.mark.reference
def test_windowed_reinjection_takes_the_sunlit_patch_s_own_light_off_it():
    """The HOLPV's L2 beams, positive straight behind, send part of the light back onto the
    surface it left: the sun room's sunlit patch reads 2.95x the path tracer's indirect light.
    With their band 2 windowed (x 4/5: a beam lights nothing behind it; the plain beams'
    radiance scale), the default, it reads 1.14x; the LPV (no band 2) is unchanged,
    bit for bit."""
    import numpy as np
    ref, windowed = rendered("sun_room", 2)
    _, plain = rendered_with(dict(windowed_reinjection=False), "sun_room", 2)
    plain_ratio, windowed_ratio = (sunlit_patch_indirect(plain, ref),
                                   sunlit_patch_indirect(windowed, ref))
    print(f"sun room, HOLPV: sunlit patch {plain_ratio:.3f}x the path tracer's indirect light, "
          f"windowed {windowed_ratio:.3f}x")
    assert abs(np.log(windowed_ratio)) < 0.5 * abs(np.log(plain_ratio))
    _, lpv_windowed = rendered("sun_room", 1)
    _, lpv = rendered_with(dict(windowed_reinjection=False), "sun_room", 1)
    assert np.array_equal(lpv["Combined"], lpv_windowed["Combined"])


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room", "two_rooms"])
def test_windowed_holpv_agrees_and_is_closer_than_lpv(name):
    """The windowed beams (the default) within 10% and above the LPV (the two rooms measured
    1.091x, 27.22 dB against the LPV's 26.80; clamped at walls with the photons by flux they
    read 1.069x, 25.79 dB against 26.90)."""
    ref, lpv = rendered(name, 1)
    _, holpv = rendered_with(dict(windowed_reinjection=True), name, 2)
    ratio = indirect_diffuse(holpv) / indirect_diffuse(ref)
    lpv_psnr, holpv_psnr = psnr(ref["Combined"], lpv["Combined"]), psnr(ref["Combined"],
                                                                         holpv["Combined"])
    print(f"{name}: windowed HOLPV DiffInd x DiffCol {ratio:.3f}x, Combined PSNR "
          f"{holpv_psnr:.2f} dB (LPV {lpv_psnr:.2f} dB)")
    assert abs(ratio - 1.0) < 0.10, ratio
    assert holpv_psnr > lpv_psnr


@pytest.mark.parametrize("order", [1, 2])
def test_extend_to_bounds_lights_the_strip_along_a_wall(order):
    """The two rooms' floor 0.05 m from the dim room's back wall, a wall at the scene's bounds:
    the lookup (a cell above the floor) reads the cells the wall runs through, which hold no
    light (measured 0.016 (LPV) and 0.003 (HOLPV) of the floor's irradiance 0.3 m from the
    wall); extend_to_bounds gives them the light of the inside cells next to them (1.10 and
    0.89)."""
    import numpy as np
    scene = committed(scenes.two_rooms(0.5))
    points = np.float32([[1.5, 3.0 - 0.05, 0.0], [1.5, 3.0 - 0.3, 0.0]])
    normals = np.float32([[0.0, 0.0, 1.0]] * 2)
    ratios = {}
    for extend in (False, True):
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            seed=5, order=order, extend_to_bounds=extend))
        volume.refine()
        strip, beyond = volume.current_field().irradiance(points, normals)[:, 0]
        ratios[extend] = strip / beyond
    print(f"order {order}: floor 0.05 m from the wall over 0.3 m from it {ratios[False]:.3f}, "
          f"extended to the bounds {ratios[True]:.3f}")
    assert ratios[False] < 0.05
    assert 0.5 < ratios[True] < 2.0


@pytest.mark.reference
@pytest.mark.parametrize("name, order", SCENE_ORDERS)
def test_extend_to_bounds_brings_the_image_closer(name, order):
    """Without the dark strips along the rooms' edges both orders come closer to the path tracer
    on every scene (measured: Cornell box +0.75 / +1.9 dB (LPV / HOLPV), sun room +1.9 / +1.1,
    two rooms +3.5 / +2.2); the HOLPV's two rooms then read 1.118x, out of the 10% (not asserted
    here: docs/methods.md, "Dark edges")."""
    ref, default = rendered(name, order)
    _, extended = rendered_with(dict(extend_to_bounds=True), name, order)
    default_psnr = psnr(ref["Combined"], default["Combined"])
    extended_psnr = psnr(ref["Combined"], extended["Combined"])
    ratio = indirect_diffuse(extended) / indirect_diffuse(ref)
    print(f"{name} order {order}: Combined PSNR {default_psnr:.2f} dB, extended to the bounds "
          f"{extended_psnr:.2f} dB (DiffInd x DiffCol {ratio:.3f}x)")
    assert extended_psnr > default_psnr


# The leak corrections on (occlude_first_step, drop_outward_vpls) and the light re-injected along
# its travel direction, whose propagation leaves a closed room in about as many steps as the
# room is wide: 24 steps (docs/methods.md, "Why the accumulation does not converge").
TRAVEL = dict(SEED, occlude_first_step=True, drop_outward_vpls=True, travel_reinjection=True,
              steps=24)
_VARIANT_RENDERS = {}


def rendered_with(settings, name, order):
    """(reference, preview) of scene `name` through a volume of `order` with `settings` (a dict
    of PropagationSettings fields), once per session."""
    key = (tuple(sorted(settings.items())), name, order)
    if key not in _VARIANT_RENDERS:
        scale, samples = REFERENCES[name]
        scene, ref = path_traced_reference(getattr(scenes, name), scale, samples)
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(seed=5, order=order,
                                                                        **settings))
        volume.refine()
        preview, _ = shgi.render_preview(scene, volume.current_field(),
                                         shgi.PreviewSettings(seed=5))
        _VARIANT_RENDERS[key] = ref, preview
    return _VARIANT_RENDERS[key]


def rendered_travel(name, order):
    return rendered_with(TRAVEL, name, order)


@pytest.mark.reference
@pytest.mark.parametrize("name, order", [
    ("cornell_box", 1),
    pytest.param("cornell_box", 2, marks=missed("DiffInd 1.129x")),
    pytest.param("sun_room", 1, marks=missed("DiffInd 0.787x")),
    ("sun_room", 2),
    ("two_rooms", 1),
    pytest.param("two_rooms", 2, marks=missed("DiffInd 1.148x")),
])
def test_travel_reinjection_with_the_corrections_agrees_with_path_tracer(name, order):
    """The same agreement target with the leak corrections on (no compensation left) and the
    travel-direction re-injection at 24 steps; the Combined PSNR printed beside the defaults'."""
    ref, preview = rendered_travel(name, order)
    ratio = indirect_diffuse(preview) / indirect_diffuse(ref)
    print(f"{name} order {order}, travel re-injection + corrections, 24 steps: DiffInd x DiffCol "
          f"{ratio:.3f} x the path tracer's, Combined PSNR "
          f"{psnr(ref['Combined'], preview['Combined']):.2f} dB")
    assert abs(ratio - 1.0) < 0.10, ratio


# With the lobes propagated unclamped (a linear transfer per neighbour offset) and damping on
# top of the travel re-injection and both corrections, 24 steps.
UNCLAMPED = dict(TRAVEL, unclamped_transfer=True, damping=True, clamp_at_surfaces=False)


def rendered_unclamped(name, order):
    return rendered_with(UNCLAMPED, name, order)


@pytest.mark.reference
@pytest.mark.parametrize("name, order", [
    pytest.param("cornell_box", 1, marks=missed("DiffInd 0.882x")),
    ("cornell_box", 2),
    pytest.param("sun_room", 1, marks=missed("DiffInd 0.776x")),
    ("sun_room", 2),
    # Not light through the wall (0.008 of the dim room's own light,
    # test_unclamped_transfer_keeps_the_bright_room_out): the room's own light reads 1.27x.
    pytest.param("two_rooms", 1, marks=missed("DiffInd 1.266x")),
    ("two_rooms", 2),
])
def test_unclamped_transfer_with_damping_agrees_with_path_tracer(name, order):
    """The agreement target with unclamped_transfer and damping added to the travel
    re-injection and both corrections (24 steps): the HOLPV meets it on all three scenes
    (measured 1.038, 0.990, 1.096), the LPV on none."""
    ref, preview = rendered_unclamped(name, order)
    ratio = indirect_diffuse(preview) / indirect_diffuse(ref)
    print(f"{name} order {order}, unclamped + damping + travel + corrections, 24 steps: "
          f"DiffInd x DiffCol {ratio:.3f} x the path tracer's, Combined PSNR "
          f"{psnr(ref['Combined'], preview['Combined']):.2f} dB")
    assert abs(ratio - 1.0) < 0.10, ratio


# The unclamped settings with the lobes clamped where walls stop light (clamp_at_surfaces: a
# wall stopping a lobe's negative half makes light, and one returning the back of a lobe that
# went into it keeps light in flight) and 32 steps for both orders: the defaults but for the
# steps (the defaults carry light as far for both orders: 35 LPV, 23 HOLPV steps).
AT_SURFACES = dict(UNCLAMPED, clamp_at_surfaces=True, clamp_per_transfer=False, steps=32)


@pytest.mark.reference
@pytest.mark.parametrize("name, order", SCENE_ORDERS)
def test_clamped_at_surfaces_agrees_with_path_tracer(name, order):
    """The agreement target with clamp_at_surfaces added to the unclamped settings, 32 steps:
    both orders meet it on all three scenes (measured LPV 0.923, 0.910, 1.037; HOLPV 1.096,
    1.028, 1.092). Before walls absorbed what goes into them the HOLPV read 1.157, 1.094,
    1.171 here."""
    ref, preview = rendered_with(AT_SURFACES, name, order)
    assert_agrees(f"{name} order {order}, clamped at surfaces, 32 steps", ref, preview)


@pytest.mark.reference
@pytest.mark.parametrize("order", [pytest.param(1, marks=missed("Combined 1.095x")), 2])
def test_dim_room_through_a_final_gather_with_the_unclamped_settings(order):
    """The two rooms' dim room through a final gather (one VPL bounce less, as the add-on
    solves for it) under the settings where the HOLPV meets the 10% agreement on all three
    scenes (UNCLAMPED): its Combined mean within 5% of the path tracer's (measured 1.021; the
    seed's settings give 1.089). The LPV reads 1.095 there."""
    scale, samples = REFERENCES["two_rooms"]
    scene, ref = path_traced_reference(scenes.two_rooms, scale, samples)
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        seed=5, order=order, vpl_bounces=3, **UNCLAMPED))
    volume.refine()
    preview, _ = shgi.render_preview(scene, volume.current_field(),
                                     shgi.PreviewSettings(seed=5, samples=64, final_gather=True))
    ratio = float(preview["Combined"][..., :3].mean() / ref["Combined"][..., :3].mean())
    print(f"order {order}, unclamped settings: dim room through a final gather {ratio:.3f} x "
          "the path tracer's")
    assert abs(ratio - 1.0) < 0.05


@pytest.mark.reference
def test_lpv_dim_room_through_a_final_gather_clamped_at_surfaces():
    """The LPV's dim room through a final gather under the settings where it meets the 10%
    agreement on all three scenes (AT_SURFACES, 32 steps): within 5% (measured 1.004)."""
    scale, samples = REFERENCES["two_rooms"]
    scene, ref = path_traced_reference(scenes.two_rooms, scale, samples)
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        seed=5, order=1, vpl_bounces=3, **AT_SURFACES))
    volume.refine()
    preview, _ = shgi.render_preview(scene, volume.current_field(),
                                     shgi.PreviewSettings(seed=5, samples=64, final_gather=True))
    ratio = float(preview["Combined"][..., :3].mean() / ref["Combined"][..., :3].mean())
    print(f"LPV clamped at surfaces: dim room through a final gather {ratio:.3f} x the path "
          "tracer's")
    assert abs(ratio - 1.0) < 0.05


@pytest.mark.reference
@pytest.mark.parametrize("order", [1, 2])
def test_unclamped_transfer_keeps_the_bright_room_out(order):
    """Under the unclamped settings the LPV reads the two rooms 1.27x: not light through the
    wall (with only the bright lamp on, whose exact light in the dim room is 0, the volume puts
    there 0.008 (LPV) and 0.018 (HOLPV) x the dim room's own indirect light) but the dim room's
    own light, with only its lamp on 1.273 (LPV) and 1.111 (HOLPV) x the path tracer's."""
    dim_scene = committed(scenes.two_rooms(0.5, bright_power=0.0))
    dim = shgi.render_path_traced(dim_scene, shgi.PathTracerSettings(samples=128, seed=11))
    bright_scene = committed(scenes.two_rooms(0.5, dim_power=0.0))
    ratios = {}
    for name, scene in (("through the wall", bright_scene), ("own", dim_scene)):
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            seed=5, order=order, **UNCLAMPED))
        volume.refine()
        preview, _ = shgi.render_preview(scene, volume.current_field(),
                                         shgi.PreviewSettings(seed=5))
        ratios[name] = indirect_diffuse(preview) / indirect_diffuse(dim)
    print(f"order {order}, unclamped: x the dim room's own indirect light: "
          f"{ratios['through the wall']:.3f} through the wall, {ratios['own']:.3f} its own")
    assert ratios["through the wall"] < 0.05


def indirect_light_off_and_on(scene, reference, order, settings, flag):
    """{False, True}: the indirect diffuse light of a one-pass, seed-5 propagation preview of
    `scene` with `settings` and PropagationSettings `flag` off / on, x `reference`'s."""
    light = {}
    for value in (False, True):
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            seed=5, order=order, **dict(settings, **{flag: value})))
        volume.refine()
        preview, _ = shgi.render_preview(scene, volume.current_field(),
                                         shgi.PreviewSettings(seed=5))
        light[value] = indirect_diffuse(preview) / indirect_diffuse(reference)
    return light


@pytest.mark.reference
@pytest.mark.parametrize("order", [1, 2])
def test_clamp_at_walls_does_not_brighten_the_closed_room(order):
    """The dim room's own light (only its lamp on) under the unclamped settings, clamped at walls
    or not: walls that absorb what goes into them add no light to the closed room (measured
    clamped / unclamped 1.111 / 1.273 LPV, 1.116 / 1.111 HOLPV x the path tracer's). Clamped and
    rescaled to the cell's total, walls returned the back of the L2 lobes going into them:
    the HOLPV read 1.187 (docs/methods.md, "Walls absorb what goes into them")."""
    dim_scene = committed(scenes.two_rooms(0.5, bright_power=0.0))
    dim = shgi.render_path_traced(dim_scene, shgi.PathTracerSettings(samples=128, seed=11))
    own = indirect_light_off_and_on(dim_scene, dim, order, UNCLAMPED, "clamp_at_surfaces")
    print(f"order {order}: the dim room's own light, x the path tracer's: {own[True]:.3f} "
          f"clamped at walls, {own[False]:.3f} unclamped")
    assert own[True] < 1.03 * own[False]


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room", "two_rooms"])
def test_unclamped_holpv_is_closer_than_lpv(name):
    """Under the same unclamped settings the HOLPV's Combined PSNR is above the LPV's on all
    three scenes (measured 28.5 / 24.9, 21.7 / 21.1, 26.3 / 24.2 dB)."""
    ref, lpv = rendered_unclamped(name, 1)
    _, holpv = rendered_unclamped(name, 2)
    lpv_psnr, holpv_psnr = psnr(ref["Combined"], lpv["Combined"]), psnr(ref["Combined"],
                                                                         holpv["Combined"])
    print(f"{name}, unclamped: Combined PSNR LPV {lpv_psnr:.2f} dB, HOLPV {holpv_psnr:.2f} dB")
    assert holpv_psnr > lpv_psnr


def test_settings_mirror_cpp_defaults_and_validate():
    s = shgi.PropagationSettings()
    assert (s.photons, s.seed, s.vpl_bounces, s.resolution, s.steps, s.order) == (
        100000, 0, 4, 32, 0, 2)
    assert s.distance == pytest.approx(32.0) and shgi.propagation_steps(s) == 23
    assert s.occlusion and s.normal_offset == pytest.approx(1.0)
    assert s.damping and s.occlude_first_step and s.drop_outward_vpls
    assert s.travel_reinjection and s.unclamped_transfer and s.clamp_at_surfaces
    assert s.windowed_reinjection and s.clamp_per_transfer
    assert s.light_share_uniform == pytest.approx(0.5)
    assert s.cascades == 1 and s.cascade_center == (0.0, 0.0, 0.0) and s.cascade_follow_camera
    assert shgi.settings_from_dict(shgi.PropagationSettings,
                                   shgi.settings_to_dict(s)).distance == pytest.approx(32.0)
    with pytest.raises(TypeError, match="no field 'step'"):
        shgi.PropagationSettings(step=3)
    with pytest.raises(ValueError, match=r"photons: must be in \[1, "):
        shgi.PropagationSettings(photons=0)
    scene = committed(scenes.cornell_box(0.05))
    for field, value in [("order", 3), ("steps", -1), ("resolution", 1), ("vpl_bounces", 0),
                         ("normal_offset", float("nan"))]:
        with pytest.raises(ValueError, match=f"PropagationSettings.{field} is"):
            shgi.PropagationVolume(scene, shgi.PropagationSettings(**{field: value}))


def test_distance_gives_each_order_the_steps_that_carry_light_as_far():
    """With steps 0 the steps come from distance (cells of travel) over the stencil's cells per
    step (LPV 0.9146, HOLPV 1.4154: tests/cpp/propagation, LightMovesTheStencilsSpeedPerStep);
    steps above 0 win; the volume propagates that many steps (its stage timings)."""
    assert shgi.propagation_steps(shgi.PropagationSettings(order=1, steps=0, distance=30.0)) == 33
    assert shgi.propagation_steps(shgi.PropagationSettings(order=2, steps=0, distance=30.0)) == 21
    assert shgi.propagation_steps(shgi.PropagationSettings(order=2, steps=0, distance=0.0)) == 0
    assert shgi.propagation_steps(shgi.PropagationSettings(order=1, steps=5, distance=30.0)) == 5
    scene = committed(scenes.cornell_box(0.05))
    for order, steps in ((1, 7), (2, 4)):
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            order=order, steps=0, distance=6.0, photons=2000, resolution=8))
        volume.refine()
        names = [name for name, _ in volume.stage_seconds]
        assert f"propagation_step_{steps}" in names and f"propagation_step_{steps + 1}" not in names
    for value in (-1.0, float("nan"), 513.0):
        with pytest.raises(ValueError, match=r"PropagationSettings.distance is .*; it must be in "
                                             r"\[0, 512\] cells"):
            shgi.propagation_steps(shgi.PropagationSettings(steps=0, distance=value))


def cornell_box_irradiance():
    """irradiance(**fields): a small Cornell box volume's irradiance at 400 fixed random points
    and normals, solved with PropagationSettings(**fields) over a fixed seed and size."""
    import numpy as np
    scene = committed(scenes.cornell_box(0.05))
    rng = np.random.default_rng(7)
    lower, upper = (np.array(corner) for corner in scene.bounds())
    points = rng.uniform(lower, upper, (400, 3)).astype(np.float32)
    normals = rng.normal(size=(400, 3)).astype(np.float32)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)

    def irradiance(**fields):
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            seed=2, photons=20000, resolution=16, steps=6, **fields))
        volume.refine()
        return volume.current_field().irradiance(points, normals)
    return irradiance


def on_one_and_two_threads(irradiance, **fields):
    """irradiance(**fields) with 1 thread and with 2."""
    try:
        shgi.set_max_threads(1)
        one = irradiance(**fields)
        shgi.set_max_threads(2)
        two = irradiance(**fields)
    finally:
        shgi.set_max_threads(0)
    return one, two


def test_clamp_at_surfaces_is_deterministic_and_needs_the_unclamped_transfer():
    """clamp_at_surfaces gives the same field for 1 and 2 threads; without unclamped_transfer
    it changes nothing (the transfer is clamped and rescaled everywhere then)."""
    import numpy as np
    irradiance = cornell_box_irradiance()
    at_walls = dict(unclamped_transfer=True, clamp_at_surfaces=True, order=1)
    rescaled = dict(unclamped_transfer=False, order=1)
    one, two = on_one_and_two_threads(irradiance, **at_walls)
    np.testing.assert_array_equal(one, two)
    assert not np.array_equal(one, irradiance(**dict(at_walls, clamp_at_surfaces=False)))
    np.testing.assert_array_equal(irradiance(**dict(rescaled, clamp_at_surfaces=True)),
                                  irradiance(**dict(rescaled, clamp_at_surfaces=False)))


def test_light_share_uniform_is_deterministic_and_validated():
    """The photons' lamp share gives the same two-room field for 1 and 2 threads; it changes the
    field of a scene with two lamps (the two rooms) and not that of a scene with one (the
    Cornell box's single area light: the same photons, bit for bit); NaN or a share outside
    [0, 1] is a ValueError naming the setting."""
    import numpy as np
    scene = committed(scenes.two_rooms(0.5))
    points = np.float32([[1.5, 1.5, 0.0], [1.5, 2.9, 1.2], [4.5, 1.5, 2.9]])
    normals = np.float32([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])

    def two_rooms(**fields):
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            seed=2, photons=20000, resolution=16, steps=6, **fields))
        volume.refine()
        return volume.current_field().irradiance(points, normals)
    one, two = on_one_and_two_threads(two_rooms, light_share_uniform=0.5)
    np.testing.assert_array_equal(one, two)
    assert not np.array_equal(one, two_rooms(light_share_uniform=0.0))
    irradiance = cornell_box_irradiance()
    np.testing.assert_array_equal(irradiance(light_share_uniform=0.5),
                                  irradiance(light_share_uniform=0.0))
    for value in (float("nan"), -0.1, 1.5):
        with pytest.raises(ValueError, match=r"PropagationSettings.light_share_uniform is .*; "
                                             r"it must be in \[0, 1\]"):
            shgi.PropagationVolume(scene, shgi.PropagationSettings(light_share_uniform=value))


def test_clamp_per_transfer_is_deterministic_and_needs_the_clamp_at_walls():
    """clamp_per_transfer (the default) gives the same HOLPV field for 1 and 2 threads and
    changes the clamp at walls' field; without clamp_at_surfaces (linear) it changes nothing.
    The LPV ignores it (its clamp at walls, bit for bit)."""
    import numpy as np
    irradiance = cornell_box_irradiance()
    assert shgi.PropagationSettings().clamp_per_transfer
    one, two = on_one_and_two_threads(irradiance, order=2, clamp_per_transfer=True)
    np.testing.assert_array_equal(one, two)
    assert not np.array_equal(one, irradiance(order=2, clamp_per_transfer=False))
    np.testing.assert_array_equal(
        irradiance(order=2, clamp_at_surfaces=False, clamp_per_transfer=True),
        irradiance(order=2, clamp_at_surfaces=False, clamp_per_transfer=False))
    np.testing.assert_array_equal(irradiance(order=1, clamp_per_transfer=True),
                                  irradiance(order=1, clamp_per_transfer=False))


def test_an_empty_or_uncommitted_scene_is_refused():
    with pytest.raises(ValueError, match="not committed"):
        shgi.PropagationVolume(scenes.cornell_box(0.05).scene)
    empty = shgi.Scene()
    empty.commit()
    with pytest.raises(ValueError, match="no geometry"):
        shgi.PropagationVolume(empty)


def field_irradiance(volume):
    import numpy as np
    points = np.array([[0.0, 0.0, 0.1], [0.5, -0.5, 1.0], [-0.7, 0.3, 1.8]], np.float32)
    normals = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]], np.float32)
    return volume.current_field().irradiance(points, normals)


def test_passes_are_deterministic_and_report_their_stages():
    scene = committed(scenes.cornell_box(0.05))
    settings = shgi.PropagationSettings(seed=3, photons=20000, resolution=16, steps=4)
    volumes = [shgi.PropagationVolume(scene, settings) for _ in range(2)]
    for volume in volumes:
        assert volume.passes == 0 and field_irradiance(volume).max() == 0.0
        volume.refine()
    assert volumes[0].passes == 1 and volumes[0].vpl_count > 0
    assert (field_irradiance(volumes[0]) == field_irradiance(volumes[1])).all()
    assert field_irradiance(volumes[0]).max() > 0.0
    stages = [name for name, _ in volumes[0].stage_seconds]
    assert stages == ["vpl_trace", "vpl_reflect", "injection", "geometry_volume",
                      "propagation_step_1", "propagation_step_2", "propagation_step_3",
                      "propagation_step_4"]
    assert all(seconds >= 0.0 for _, seconds in volumes[0].stage_seconds)


def test_cancel_keeps_the_previous_field():
    scene = committed(scenes.cornell_box(0.05))
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(photons=20000, steps=4))
    volume.refine()
    before = field_irradiance(volume)
    progress = shgi.Progress(lambda fraction, stage: progress.cancel())
    with pytest.raises(shgi.Cancelled):
        volume.refine(progress)
    assert volume.passes == 1
    assert (field_irradiance(volume) == before).all()


def test_a_field_stays_valid_while_the_next_pass_runs():
    scene = committed(scenes.cornell_box(0.05))
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(photons=20000, steps=4))
    volume.refine()
    field = volume.current_field()
    before = field.irradiance([[0.0, 0.0, 0.1]], [[0.0, 0.0, 1.0]])
    worker = threading.Thread(target=volume.refine)
    worker.start()
    during = field.irradiance([[0.0, 0.0, 0.1]], [[0.0, 0.0, 1.0]])
    worker.join()
    assert (during == before).all()
    assert volume.passes == 2


@pytest.mark.reference
def test_cornell_floor_holpv_closer_than_lpv_and_self_lighting_reported():
    """Seed 003 §5.7: on the Cornell box's floor the HOLPV's mean indirect light is closer to
    the path tracer's than the LPV's; the ceiling-to-floor ratio of indirect light (against the
    reference's) is the self-lighting measure (a lit floor's own VPLs light it again)."""
    ref, _ = rendered("cornell_box", 1)
    normal_z = ref["Normal"][..., 2]
    floor, ceiling = normal_z > 0.9, normal_z < -0.9
    assert floor.any() and ceiling.any()

    def means(passes):
        return float(passes["DiffInd"][floor].mean()), float(passes["DiffInd"][ceiling].mean())

    ref_floor, ref_ceiling = means(ref)
    errors = {}
    for order in (1, 2):
        floor_mean, ceiling_mean = means(rendered("cornell_box", order)[1])
        errors[order] = abs(floor_mean / ref_floor - 1.0)
        print(f"order {order}: floor {floor_mean / ref_floor:.3f}x the reference, "
              f"ceiling/floor {ceiling_mean / floor_mean:.3f} "
              f"(reference {ref_ceiling / ref_floor:.3f})")
    assert errors[2] < errors[1]


@pytest.mark.reference
@pytest.mark.parametrize("order, windowed", [
    (1, False), (2, False), (2, True),
])
def test_dim_room_through_a_final_gather_is_within_five_percent(order, windowed):
    """The two rooms' dim room read through a final gather, with one VPL bounce less (the
    add-on's accounting: Light Paths > Diffuse 4 gives 3 behind the gather): its Combined mean
    within 5% of the path tracer's, the leak target the probe grid meets too (measured 1.027
    LPV, 1.042 HOLPV with plain beams, 1.030 with windowed ones (the default); 0.997, 1.011 and
    1.004 with the HOLPV clamped at walls and the photons by flux alone; the seed's settings
    0.978, 1.089)."""
    scale, samples = REFERENCES["two_rooms"]
    scene, ref = path_traced_reference(scenes.two_rooms, scale, samples)
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        seed=5, order=order, vpl_bounces=3, windowed_reinjection=windowed))
    volume.refine()
    preview, _ = shgi.render_preview(scene, volume.current_field(),
                                     shgi.PreviewSettings(seed=5, samples=64, final_gather=True))
    ratio = float(preview["Combined"][..., :3].mean() / ref["Combined"][..., :3].mean())
    print(f"order {order}{' windowed' if windowed else ''}: dim room through a final gather "
          f"{ratio:.3f} x the path tracer's")
    assert abs(ratio - 1.0) < 0.05


@pytest.mark.reference
@pytest.mark.parametrize("order", [1, 2])
def test_first_step_occlusion_keeps_the_bright_room_out(order):
    """The two rooms' leak taken apart: with only the bright lamp on, the dim room's exact
    indirect light is 0, so whatever the volume puts there crossed the wall; it is compared with
    the dim room's own indirect light (only the dim lamp on, path traced). With the first step
    unoccluded (the seed, §3.2.3), VPLs within half a cell of the wall are injected into the
    cell the wall runs through and their first step crosses it: measured +20% (LPV) and +36%
    (HOLPV) of the dim room's own light (the seed's settings). occlude_first_step keeps it under
    5%."""
    dim_scene = committed(scenes.two_rooms(0.5, bright_power=0.0))
    dim = shgi.render_path_traced(dim_scene, shgi.PathTracerSettings(samples=128, seed=11))
    bright_scene = committed(scenes.two_rooms(0.5, dim_power=0.0))
    leaks = indirect_light_off_and_on(bright_scene, dim, order, SEED, "occlude_first_step")
    print(f"order {order}: light through the wall, x the dim room's own indirect light: "
          f"{leaks[False]:.3f} (first step unoccluded), {leaks[True]:.3f} (occluded)")
    assert leaks[True] < 0.05
    assert leaks[True] < leaks[False]


@pytest.mark.reference
@pytest.mark.parametrize("order", [1, 2])
def test_outward_vpls_dropped_keep_the_outside_out(order):
    """The sun room with its window shut and the sky off: no light enters (the path tracer
    finds none inside), yet the sunlit roof and outer walls' VPLs, injected into the cells those
    surfaces run through, showed inside (measured with the seed's settings 0.139 LPV, 0.127
    HOLPV x the open room's indirect light). drop_outward_vpls leaves out the VPLs that can light nothing (on the
    scene's bounds, facing out): nothing is left inside."""
    _, open_reference = path_traced_reference(scenes.sun_room, *REFERENCES["sun_room"])
    shut = committed(scenes.sun_room(SCALE, window_shut=True))
    inside = indirect_light_off_and_on(shut, open_reference, order, SEED, "drop_outward_vpls")
    print(f"order {order}: light inside the shut sun room, x the open room's indirect light: "
          f"{inside[False]:.3f} (all VPLs), {inside[True]:.4f} (outward ones dropped)")
    assert inside[True] < 0.001


# --- closed rooms with an exact answer ---------------------------------------------------------

# The furnace (scenes.closed_room(): every wall emits radiance 1 and reflects half, Lambert): the
# indirect light the VPLs carry gives every wall point the same irradiance, pi (a + ... + a^n).
FURNACE_ALBEDO = 0.5
# Cells of the furnace's longest side: the two rooms' dim room at their default resolution.
FURNACE_RESOLUTION = 16
# How even a method's furnace light must be: the light within 0.5-1 cell of a wall's nearest
# edge against the light 4 or more cells from it (1 exactly).
FURNACE_EVENNESS = 0.10


def furnace_light(order, **settings):
    """The field's irradiance over the furnace's exact, area-weighted over all six walls: within
    0.5-1 cell of a wall's nearest edge, 4 or more cells from it, and over the walls less the
    half cell along their edges (the dark strip of docs/methods.md, "Dark edges")."""
    import numpy as np
    scene = committed(scenes.closed_room())
    points, normals, areas, edges = scenes.room_wall_points()
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        seed=5, order=order, resolution=FURNACE_RESOLUTION, photons=200000, **settings))
    volume.refine()
    bounces = volume.settings.vpl_bounces
    exact = np.pi * sum(FURNACE_ALBEDO ** k for k in range(1, bounces + 1))
    ratio = volume.current_field().irradiance(points, normals).mean(-1) / exact
    lower, upper = scene.bounds()
    cells = edges / (max(np.subtract(upper, lower)) / FURNACE_RESOLUTION)

    def mean(mask):
        return float((ratio * areas)[mask].sum() / areas[mask].sum())

    return mean((cells >= 0.5) & (cells < 1.0)), mean(cells >= 4.0), mean(cells >= 0.5)


@pytest.mark.parametrize("order, settings", [
    (1, {}),
    # Clamped where walls stop light, the HOLPV's light falls towards every edge of the room:
    # the clamp sends light from the cells along the walls into the room (docs/methods.md,
    # "Closed rooms: the furnace").
    pytest.param(2, {"windowed_reinjection": False, "clamp_per_transfer": False},
                 marks=missed("0.5-1 cell from an edge 1.10x, 4+ cells 1.35x the exact")),
    pytest.param(2, {"clamp_per_transfer": False},
                 marks=missed("0.5-1 cell from an edge 1.05x, 4+ cells 1.36x the exact")),
    (2, {"windowed_reinjection": False, "clamp_at_surfaces": False}),
    # Clamped per transfer (only the transfers a wall stops in part; the HOLPV's default): its
    # light stays at the edges (docs/methods.md, "Clamped per transfer"). The LPV's ramped the
    # other way per transfer (1.41x near an edge, 1.15x beyond), so it ignores the setting.
    (2, {}),
])
def test_furnace_light_is_even_from_the_edges_in(order, settings):
    """In the furnace every wall point's exact indirect light is the same: the field's light
    near the edges of the walls over its light in their middle must be 1 within
    FURNACE_EVENNESS (measured 1.27 / 1.25 LPV; HOLPV 1.10 / 1.35, linear 1.26 / 1.28, its
    windowed beams (the default) 1.05 / 1.36)."""
    near, far, _ = furnace_light(order, **settings)
    print(f"order {order} {settings}: furnace light 0.5-1 cell from an edge {near:.3f}x the "
          f"exact, 4+ cells {far:.3f}x")
    assert abs(near / far - 1.0) < FURNACE_EVENNESS


@pytest.mark.parametrize("order, settings", [
    # The light carried until it settles (96 cells: the defaults' 32 settle this 16-cell room
    # too, within 2%), the strip along the bounds filled, each order with the transfer whose
    # furnace light is even (above).
    pytest.param(1, {"distance": 96.0, "extend_to_bounds": True},
                 marks=missed("1.285x the exact (the radiance scale)")),
    pytest.param(2, {"distance": 96.0, "extend_to_bounds": True, "clamp_at_surfaces": False,
                     "windowed_reinjection": False},
                 marks=missed("1.285x the exact (the radiance scale)")),
    # furnace_scale: the accumulation over settled_room_excess() of its transfer, the furnace's
    # own reading, so this is its calibration (other resolutions: docs/methods.md, "The
    # furnace's scale"); the HOLPV with its default transfer (windowed, clamped at walls) too.
    (1, {"distance": 96.0, "extend_to_bounds": True, "furnace_scale": True}),
    (2, {"distance": 96.0, "extend_to_bounds": True, "furnace_scale": True}),
    (2, {"distance": 96.0, "extend_to_bounds": True, "furnace_scale": True,
         "clamp_at_surfaces": False}),
    (2, {"distance": 96.0, "extend_to_bounds": True, "furnace_scale": True,
         "clamp_per_transfer": False}),
])
def test_furnace_closed_room_reads_the_closed_form(order, settings):
    """A closed room's light once it has settled, against the closed form: within 10%. At the
    radiance scales fitted to a single VPL's near field both orders read 1.285x: too large for a
    room whose light has settled; the test scenes' means hide it (docs/methods.md, "Closed
    rooms: the furnace"). furnace_scale takes that excess off."""
    _, _, mean = furnace_light(order, **settings)
    print(f"order {order} {settings}: furnace light {mean:.3f}x the exact")
    assert abs(mean - 1.0) < 0.10


@pytest.mark.reference
@pytest.mark.parametrize("order, glossy_vpls", [
    pytest.param(1, False,
                 marks=missed("Specular 0.5 adds 22% to the path tracer's, 7% to the LPV's")),
    pytest.param(2, False,
                 marks=missed("Specular 0.5 adds 22% to the path tracer's, 7% to the HOLPV's")),
    (1, True),
    (2, True),
])
def test_light_reflected_by_a_glossy_layer_reaches_the_volume(order, glossy_vpls):
    """The dim room alone (scenes.closed_room() lit by a lamp 0.5 m under its ceiling), walls
    Lambert 0.73 with and without the Principled BSDF's default Specular 0.5 on top: the glossy
    layer reflects more light onto the other walls, and the volume's indirect light must grow
    with it as the path tracer's does (within 5%). Its VPLs carry only what surfaces reflect
    diffusely: the light a wall reflects glossily lights the others in the path tracer, not in
    the volume. glossy_vpls (with their own glossy budget) adds the rough glossy lobes' light to
    the VPLs (measured: the path tracer's x 1.222, the volume's x 1.203 for both orders)."""
    growth = {}
    for specular in (0.0, 0.5):
        builder = scenes.closed_room(
            material=shgi.Material(name="walls", base_color=(0.73, 0.73, 0.73),
                                   diffuse_model=shgi.DiffuseModel.LAMBERT, specular=specular),
            lamp_at=(1.5, 1.5, 2.0))
        builder.camera(eye=(2.9, 0.2, 1.4), target=(0.0, 2.2, 1.0), lens=18.0, width=128,
                       height=96, scale=0.5)
        scene = committed(builder)
        ref = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=256, seed=11))
        glossy = dict(glossy_vpls=True, glossy_bounces=4) if glossy_vpls else {}
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            seed=5, order=order, resolution=FURNACE_RESOLUTION, **glossy))
        volume.refine()
        preview, _ = shgi.render_preview(scene, volume.current_field(),
                                         shgi.PreviewSettings(seed=5))
        growth[specular] = (indirect_diffuse(ref), indirect_diffuse(preview))
    exact = growth[0.5][0] / growth[0.0][0]
    volume_growth = growth[0.5][1] / growth[0.0][1]
    print(f"order {order}, glossy_vpls {glossy_vpls}: Specular 0.5 multiplies the path "
          f"tracer's indirect light by {exact:.3f}, the volume's by {volume_growth:.3f}")
    assert abs(volume_growth / exact - 1.0) < 0.05


# --- three changes for closed rooms together (docs/methods.md, "The furnace's scale") ---------
# The furnace's radiance scale, propagation until the light settles (at most 96 cells, stopping
# once 1% of the light is in flight), glossy VPLs with their own glossy budget, and the strip
# along the bounds filled. Not the defaults: the HOLPV is then below the LPV on the sun room and
# the two rooms.
# Measured with the HOLPV clamped at walls and the photons shared among the lamps by flux alone.
CLOSED_ROOMS = dict(furnace_scale=True, distance=96.0, settle_fraction=0.01, glossy_vpls=True,
                    glossy_bounces=4, extend_to_bounds=True, clamp_per_transfer=False,
                    light_share_uniform=0.0)


@pytest.mark.reference
@pytest.mark.parametrize("name, order", SCENE_ORDERS)
def test_closed_room_settings_agree_with_path_tracer(name, order):
    """With the three changes together no error is left to offset another: the means within
    10% (measured LPV 1.003 / 1.032 / 0.952, HOLPV 0.982 / 0.980 / 1.010: Cornell box / sun
    room / two rooms)."""
    ref, preview = rendered_with(CLOSED_ROOMS, name, order)
    assert_agrees(f"{name} order {order}", ref, preview)


# The HOLPV clamped per transfer (docs/methods.md, "Clamped per transfer"): only the transfers
# a wall stops in part are clamped, so its light stays at the rooms' edges. The LPV keeps its
# clamp at walls (per transfer its furnace light ramps and its PSNR drops on all three scenes).
HOLPV_PER_TRANSFER = dict(CLOSED_ROOMS, clamp_per_transfer=True)


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room", "two_rooms"])
def test_closed_room_settings_per_transfer_agree_with_path_tracer(name):
    """The HOLPV clamped per transfer with the three changes: the means within 10% (measured
    0.979 / 0.973 / 0.999: Cornell box / sun room / two rooms)."""
    ref, preview = rendered_with(HOLPV_PER_TRANSFER, name, 2)
    assert_agrees(f"{name} HOLPV per transfer", ref, preview)


@pytest.mark.reference
@pytest.mark.parametrize("name, holpv", [
    ("cornell_box", "clamped at walls"),
    # The LPV gains more from the changes than the HOLPV, whose clamp at walls still moves light
    # off the rooms' edges (docs/methods.md, "The furnace's scale").
    pytest.param("sun_room", "clamped at walls",
                 marks=missed("PSNR HOLPV 26.49 dB, LPV 27.40 dB")),
    pytest.param("two_rooms", "clamped at walls",
                 marks=missed("PSNR HOLPV 29.77 dB, LPV 32.09 dB")),
    ("cornell_box", "per transfer"),
    # Per transfer the two rooms come within 0.3 dB; the sun room drops 0.4 dB.
    pytest.param("sun_room", "per transfer",
                 marks=missed("PSNR HOLPV per transfer 26.1 dB, LPV 27.4 dB")),
    pytest.param("two_rooms", "per transfer",
                 marks=missed("PSNR HOLPV per transfer 31.7 dB, LPV 32.0 dB")),
])
def test_closed_room_settings_holpv_is_closer_than_lpv(name, holpv):
    ref, lpv = rendered_with(CLOSED_ROOMS, name, 1)
    _, holpv_preview = rendered_with(
        HOLPV_PER_TRANSFER if holpv == "per transfer" else CLOSED_ROOMS, name, 2)
    lpv_psnr = psnr(ref["Combined"], lpv["Combined"])
    holpv_psnr = psnr(ref["Combined"], holpv_preview["Combined"])
    print(f"{name}: Combined PSNR LPV {lpv_psnr:.2f} dB, HOLPV {holpv} {holpv_psnr:.2f} dB")
    assert holpv_psnr > lpv_psnr


@pytest.mark.reference
@pytest.mark.parametrize("order, per_transfer", [(1, False), (2, False), (2, True)])
def test_dim_room_through_a_final_gather_with_the_closed_room_settings(order, per_transfer):
    """The leak target (test_dim_room_through_a_final_gather_is_within_five_percent) with the
    three changes: the dim room's Combined mean through a final gather within 5% (measured
    0.972 LPV, 0.986 HOLPV, 0.998 the HOLPV clamped per transfer)."""
    scale, samples = REFERENCES["two_rooms"]
    scene, ref = path_traced_reference(scenes.two_rooms, scale, samples)
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        seed=5, order=order, **dict(CLOSED_ROOMS, vpl_bounces=3,
                                    clamp_per_transfer=per_transfer)))
    volume.refine()
    preview, _ = shgi.render_preview(scene, volume.current_field(),
                                     shgi.PreviewSettings(seed=5, samples=64, final_gather=True))
    ratio = float(preview["Combined"][..., :3].mean() / ref["Combined"][..., :3].mean())
    print(f"order {order}: dim room through a final gather {ratio:.3f} x the path tracer's")
    assert abs(ratio - 1.0) < 0.05


@pytest.mark.parametrize("order", [1, 2])
def test_settle_fraction_stops_once_the_light_has_settled(order):
    """With settle_fraction the propagation stops once that fraction of the injected light is
    left in flight: fewer steps than the distance's, the same light within 2% where the full
    distance's steps are taken (at 1%); the same field whatever the thread count (the light in
    flight is summed in cell order, the glossy VPLs' flux per VPL)."""
    import numpy as np
    scene = committed(scenes.two_rooms(0.5))
    points, normals = np.float32([[1.5, 1.5, 0.0], [1.5, 2.9, 1.2], [4.5, 1.5, 2.9]]), \
        np.float32([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
    light, steps = {}, {}
    for settle in (0.0, 0.01):
        volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
            seed=5, order=order, distance=96.0, settle_fraction=settle))
        volume.refine()
        steps[settle] = sum(name.startswith("propagation_step_")
                            for name, _ in volume.stage_seconds)
        light[settle] = volume.current_field().irradiance(points, normals)
    print(f"order {order}: {steps[0.0]} steps, settled after {steps[0.01]}; light "
          f"{(light[0.01] / light[0.0]).mean(-1)}x the full run's")
    assert steps[0.01] < steps[0.0] == shgi.propagation_steps(
        shgi.PropagationSettings(order=order, distance=96.0))
    assert np.allclose(light[0.01], light[0.0], rtol=0.02)
    # With the other closed-room settings too (glossy VPLs, the furnace's scale), 1 and 2 threads.
    fields = []
    try:
        for threads in (1, 2):
            shgi.set_max_threads(threads)
            volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
                seed=5, order=order, **CLOSED_ROOMS))
            volume.refine()
            fields.append(volume.current_field().irradiance(points, normals))
    finally:
        shgi.set_max_threads(0)
    np.testing.assert_array_equal(fields[0], fields[1])


def test_closed_room_settings_are_validated():
    scene = committed(scenes.cornell_box(0.05))
    for settle in (-0.1, 1.0, float("nan")):
        with pytest.raises(ValueError, match="PropagationSettings.settle_fraction is"):
            shgi.PropagationVolume(scene, shgi.PropagationSettings(settle_fraction=settle))
    with pytest.raises(ValueError, match="PropagationSettings.glossy_bounces is"):
        shgi.PropagationVolume(scene, shgi.PropagationSettings(glossy_bounces=-2))
    with pytest.raises(ValueError, match="furnace_scale needs travel_reinjection"):
        shgi.PropagationVolume(scene, shgi.PropagationSettings(furnace_scale=True,
                                                               travel_reinjection=False))


@pytest.mark.parametrize("options", [dict(order=1), dict(order=2, damping=True,
                                                         travel_reinjection=True),
                                     dict(order=2, occlusion=False),
                                     dict(order=2, windowed_reinjection=True)])
def test_a_saved_field_loads_back_looking_up_the_same_light(options, tmp_path):
    """PropagationField.save / load (what the add-on writes beside a saved .blend): the loaded
    field answers every lookup bit for bit as the solved one, with and without the geometry's
    transmittance, damping and travel re-injection; a field before the first pass loads as no
    light."""
    import numpy as np
    scene = committed(scenes.cornell_box(0.05))
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        seed=3, photons=20000, resolution=16, steps=4, **options))
    empty_path = tmp_path / "empty.shlpv"
    volume.current_field().save(str(empty_path))
    assert shgi.PropagationField.load(str(empty_path)).irradiance(
        np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32)).max() == 0.0
    volume.refine()
    field = volume.current_field()
    path = tmp_path / "field.shlpv"
    field.save(str(path))
    loaded = shgi.PropagationField.load(str(path))
    rng = np.random.default_rng(1)
    points = rng.uniform(-0.06, 0.06, (500, 3)).astype(np.float32)
    normals = rng.normal(size=(500, 3)).astype(np.float32)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    expected = field.irradiance(points, normals)
    assert expected.max() > 0.0
    assert np.array_equal(loaded.irradiance(points, normals), expected)
    assert loaded.memory_bytes == field.memory_bytes


def test_a_damaged_field_file_is_refused_naming_it(tmp_path):
    """Hostile files: not a field, truncated, a header damaged, a cell count the file does not
    hold — an OSError naming the file, never a crash or a huge allocation."""
    scene = committed(scenes.cornell_box(0.05))
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(photons=5000, resolution=8,
                                                                    steps=2))
    volume.refine()
    path = tmp_path / "field.shlpv"
    volume.current_field().save(str(path))
    data = path.read_bytes()
    cases = {"magic.shlpv": b"NOTAFIELD" + data[9:], "short.shlpv": data[: len(data) // 2],
             "offset.shlpv": data[:12] + b"\xff\xff\xff\xff" + data[16:],
             # counts (after magic 8, version 4, offset 4, flags 2, level count 4, the
             # level's blend faces 1, origin 12, cell size 4)
             "counts.shlpv": data[:39] + b"\xff\xff\x00\x00" * 3 + data[51:],
             "tail.shlpv": data + b"\x00"}
    for name, content in cases.items():
        bad = tmp_path / name
        bad.write_bytes(content)
        with pytest.raises(OSError, match=name):
            shgi.PropagationField.load(str(bad))


# Cascades: examples/scenes.py's hall of 32 x 8 x 4 m (four lamps along it, three blocks),
# larger than a 32-cell volume resolves (1 m cells). Two levels at resolution 32: the coarsest over the hall, a finer
# one of 0.5 m cells spanning 16 m around the camera at x = -4 (the hall's whole width and
# height). Steps 8: light moves at most 8 cells, so at least 8 + 2 cells (the lookup's reach)
# inside the finer level's box nothing outside it reaches, and the finer level there holds
# what one 0.5 m volume over the whole hall (resolution 64) holds.
CASCADE_CENTER = (-4.0, 0.0, 1.5)


def hall():
    return committed(scenes.hall())


def hall_field(scene, order, **settings):
    """A pass over the hall (8 steps unless `steps` is given); a cascade_center given is used
    instead of the camera's position."""
    if "cascade_center" in settings:
        settings.setdefault("cascade_follow_camera", False)
    settings.setdefault("steps", 8)
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        seed=3, photons=100000, order=order, **settings))
    volume.refine()
    return volume


def floor_line():
    """Points along the hall's floor (y = 0.3) every 0.05 m, facing up."""
    import numpy as np
    xs = np.arange(-15.5, 15.5, 0.05)
    points = np.stack([xs, np.full_like(xs, 0.3), np.zeros_like(xs)], 1).astype(np.float32)
    return xs, points, np.tile(np.float32([0, 0, 1]), (len(xs), 1))


def line_irradiance(field, points, normals):
    return field.irradiance(points, normals)[:, :3].mean(axis=1)


@pytest.mark.parametrize("order", [1, 2])
def test_cascades_give_the_fine_answer_near_the_camera_and_light_far_away(order):
    """Near the camera the cascaded field is what one volume of the finest level's cells over
    the whole hall gives (measured within 1.5e-6); beyond the finer level it is the coarsest
    level's, which alone is the single 32-cell volume (bit for bit), and still lit."""
    import numpy as np
    scene = hall()
    cascaded = hall_field(scene, order, resolution=32, cascades=2,
                          cascade_center=CASCADE_CENTER)
    field = cascaded.current_field()
    assert field.level_count == 2 and cascaded.current_field().level_field(0).level_count == 1
    fine = hall_field(scene, order, resolution=64).current_field()
    coarse = hall_field(scene, order, resolution=32).current_field()
    xs, points, normals = floor_line()
    e_cascaded, e_fine, e_coarse = (line_irradiance(f, points, normals)
                                    for f in (field, fine, coarse))
    near = np.abs(xs - CASCADE_CENTER[0]) < 2.5
    far = np.abs(xs - CASCADE_CENTER[0]) > 9.0
    assert near.sum() > 50 and far.sum() > 100
    near_error = float(np.max(np.abs(e_cascaded[near] / e_fine[near] - 1.0)))
    print(f"order {order}: near the camera, cascades vs one fine volume: {near_error:.2e}")
    assert near_error < 1e-4
    # The 0.5 m answer differs from the 1 m one there (the finer cells are worth having).
    assert np.max(np.abs(e_coarse[near] / e_fine[near] - 1.0)) > 0.1
    np.testing.assert_array_equal(e_cascaded[far], e_coarse[far])
    assert e_cascaded[far].min() > 0.25 * e_cascaded.max()


@pytest.mark.parametrize("order", [1, 2])
def test_cascade_borders_show_no_seam(order):
    """Across the finer level's borders (its x faces; the blend band is 4 of its cells inside
    a margin of 1) the field stays continuous: the steepest change per tenth of a fine cell in
    the bands is measured 1.7% (LPV) and 1.0% (HOLPV) with the defaults' steps (35 and 23; the
    seed's settings at 8 steps: 1.6%, 1.5%), below 2%, and below the steepest change the fine
    level shows alone anywhere along the line (12% and 10%, a block's edge). At 8 steps the
    unclamped LPV leaves stretches of the floor unlit (its negative light, clamped at 0 by the
    lookup) and its seam reads 4.0%."""
    import numpy as np
    scene = hall()
    field = hall_field(scene, order, resolution=32, cascades=2, cascade_center=CASCADE_CENTER,
                       steps=0).current_field()
    fine_alone = field.level_field(0)
    xs, points, normals = floor_line()
    e = line_irradiance(field, points, normals)
    weights_known = line_irradiance(fine_alone, points, normals)
    steps = np.abs(np.diff(e)) / (0.5 * (e[1:] + e[:-1]))
    # The bands: where the cascaded field is neither level alone (the weight is inside (0, 1)).
    coarse_alone = field.level_field(1)
    e_coarse = line_irradiance(coarse_alone, points, normals)
    blended = (e != weights_known) & (e != e_coarse)
    band = blended[1:] | blended[:-1]
    assert 20 < band.sum() < 200
    seam = float(steps[band].max())
    inside = np.abs(xs - CASCADE_CENTER[0]) < 7.0
    fine_steps = np.abs(np.diff(weights_known[inside])) / (
        0.5 * (weights_known[inside][1:] + weights_known[inside][:-1]))
    print(f"order {order}: steepest change per 0.05 m in the blend bands {seam:.4f}, "
          f"the fine level's steepest inside its box {fine_steps.max():.4f}")
    assert seam < 0.02
    assert seam < fine_steps.max()


def test_cascades_are_deterministic_and_report_each_level():
    """The same seed gives the same field whatever the thread count; stages per level; the
    memory estimate (before anything is allocated) covers what the solver holds; a saved
    cascaded field loads back answering the same."""
    import numpy as np
    scene = hall()
    settings = dict(resolution=16, cascades=3, cascade_center=CASCADE_CENTER)
    xs, points, normals = floor_line()
    fields = []
    try:
        for threads in (1, 2):
            shgi.set_max_threads(threads)
            volume = hall_field(scene, 2, **settings)
            fields.append(volume.current_field())
    finally:
        shgi.set_max_threads(0)
    assert fields[0].level_count == 3
    np.testing.assert_array_equal(line_irradiance(fields[0], points, normals),
                                  line_irradiance(fields[1], points, normals))
    stages = [name for name, _ in volume.stage_seconds]
    expected = ["vpl_trace", "vpl_reflect"]
    for level in range(3):
        expected += [f"level_{level}_injection", f"level_{level}_geometry_volume"] + [
            f"level_{level}_propagation_step_{k}" for k in range(1, 9)]
    assert stages == expected
    estimate = shgi.PropagationVolume.estimate_memory_bytes(
        scene, shgi.PropagationSettings(order=2, steps=8, **settings))
    assert volume.memory_bytes <= estimate
    assert shgi.PropagationVolume.estimate_memory_bytes(
        scene, shgi.PropagationSettings(order=2, steps=8, resolution=16)) < estimate


def test_cascades_follow_the_scene_camera_by_default():
    """cascade_follow_camera (on by default) centres the finer levels on the scene camera's
    position, as cascade_center there would; off, cascade_center decides."""
    import numpy as np
    scene = hall()
    eye = (-4.0, -3.5, 1.5)  # examples/scenes.py's hall camera
    xs, points, normals = floor_line()
    followed = hall_field(scene, 1, resolution=16, cascades=2, cascade_follow_camera=True,
                          cascade_center=(9.0, 0.0, 1.0)).current_field()
    placed = hall_field(scene, 1, resolution=16, cascades=2, cascade_center=eye).current_field()
    elsewhere = hall_field(scene, 1, resolution=16, cascades=2,
                           cascade_center=(9.0, 0.0, 1.0)).current_field()
    np.testing.assert_array_equal(line_irradiance(followed, points, normals),
                                  line_irradiance(placed, points, normals))
    assert not np.array_equal(line_irradiance(followed, points, normals),
                              line_irradiance(elsewhere, points, normals))


def test_a_saved_cascaded_field_loads_back(tmp_path):
    import numpy as np
    scene = hall()
    field = hall_field(scene, 1, resolution=16, cascades=2, cascade_center=(5.0, 1.0, 1.0),
                       damping=True).current_field()
    path = tmp_path / "cascaded.shlpv"
    field.save(str(path))
    loaded = shgi.PropagationField.load(str(path))
    xs, points, normals = floor_line()
    assert loaded.level_count == 2
    np.testing.assert_array_equal(loaded.irradiance(points, normals),
                                  field.irradiance(points, normals))


def test_cascade_settings_are_validated_before_allocating():
    scene = hall()
    for fields, match in [(dict(cascades=0), "cascades is 0"),
                          (dict(cascades=9), "cascades is 9"),
                          (dict(cascades=2, resolution=8), r"resolution \(with cascades\) is 8")]:
        with pytest.raises(ValueError, match=f"PropagationSettings.{match}"):
            shgi.PropagationVolume(scene, shgi.PropagationSettings(**fields))
    with pytest.raises(ValueError, match="cascade_center: element .* is nan"):
        shgi.PropagationSettings(cascade_center=(float("nan"), 0, 0))
    huge = shgi.PropagationSettings(resolution=256, cascades=8, order=2)
    assert shgi.PropagationVolume.estimate_memory_bytes(scene, huge) > 10 ** 10
    with pytest.raises(MemoryError, match="cascade levels"):
        shgi.PropagationVolume(scene, huge)


def test_cancel_with_cascades_keeps_the_previous_field():
    """A cancel in any level's injection or propagation keeps the last field."""
    import numpy as np
    scene = hall()
    volume = hall_field(scene, 1, resolution=16, cascades=3, cascade_center=CASCADE_CENTER)
    xs, points, normals = floor_line()
    before = line_irradiance(volume.current_field(), points, normals)
    for stage_to_cancel in ("injecting VPLs, level 1", "propagating, level 2"):
        progress = shgi.Progress(
            lambda fraction, stage: progress.cancel() if stage == stage_to_cancel else None)
        with pytest.raises(shgi.Cancelled):
            volume.refine(progress)
        assert volume.passes == 1
        np.testing.assert_array_equal(line_irradiance(volume.current_field(), points, normals),
                                      before)


# Cascades that follow a moving camera (PropagationVolume.recenter; the viewport's navigation).
# The hall at resolution 16 with 3 levels: cells of 2, 1 and 0.5 m; the finer boxes 16 m and
# 8 m along x around the centre (the hall's whole width and height).


def level_lines(field, points, normals):
    return [line_irradiance(field.level_field(level), points, normals)
            for level in range(field.level_count)]


@pytest.mark.parametrize("order", [1, 2])
def test_recentred_cascades_are_a_volume_reset_there(order):
    """recenter() moves only the levels whose inner region (the middle half of their box) the
    camera left, snapped to their own cells, and rebuilds those alone: the field is bit for bit
    what a volume whose levels were centred there from the start gives after as many passes,
    and the levels that did not move are kept as they were."""
    import numpy as np
    scene = hall()
    settings = dict(resolution=16, cascades=3, order=order, steps=8, seed=3, photons=30000,
                    cascade_follow_camera=False)
    start, far = (-4.0, 0.0, 1.5), (8.3, 0.7, 1.2)
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        cascade_center=start, **settings))
    for _ in range(2):
        volume.refine()
    xs, points, normals = floor_line()
    before = volume.current_field()
    before_levels = level_lines(before, points, normals)
    # 1.5 m: inside the middle half of the finest box (8 m) and of the next (16 m).
    assert volume.recenter((-2.5, 0.0, 1.5)) == []
    np.testing.assert_array_equal(line_irradiance(volume.current_field(), points, normals),
                                  line_irradiance(before, points, normals))
    # 12.3 m away both finer levels move; the coarsest (the whole hall) never does.
    assert volume.recenter(far) == [0, 1]
    assert volume.passes == 2
    moved = volume.current_field()
    fresh = shgi.PropagationVolume(scene, shgi.PropagationSettings(cascade_center=far, **settings))
    for _ in range(2):
        fresh.refine()
    np.testing.assert_array_equal(line_irradiance(moved, points, normals),
                                  line_irradiance(fresh.current_field(), points, normals))
    for a, b in zip(level_lines(moved, points, normals),
                    level_lines(fresh.current_field(), points, normals)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(level_lines(moved, points, normals)[2], before_levels[2])
    assert not np.array_equal(level_lines(moved, points, normals)[0], before_levels[0])
    # Refining goes on from there as the fresh volume does.
    volume.refine()
    fresh.refine()
    np.testing.assert_array_equal(line_irradiance(volume.current_field(), points, normals),
                                  line_irradiance(fresh.current_field(), points, normals))


def test_a_level_held_by_the_hall_end_stays_and_only_the_finest_moves():
    """Near the hall's end the 16 m level is already against its bounds and cannot move (it is
    not rebuilt); the finest level still follows."""
    scene = hall()
    volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        resolution=16, cascades=3, steps=4, photons=20000, cascade_follow_camera=False,
        cascade_center=(11.0, 0.0, 1.5)))
    volume.refine()
    # Level 1 (16 m) spans x in [0, 16] either way; level 0 (8 m) moves from [7, 15] to [8, 16].
    assert volume.recenter((15.5, 0.0, 1.5)) == [0]
    assert volume.recenter((15.5, 0.0, 1.5)) == []


def test_recenter_without_cascades_or_with_a_bad_point():
    import numpy as np
    scene = hall()
    single = shgi.PropagationVolume(scene, shgi.PropagationSettings(resolution=16, steps=2,
                                                                    photons=5000))
    single.refine()
    assert single.recenter((10.0, 0.0, 1.0)) == []
    cascaded = shgi.PropagationVolume(scene, shgi.PropagationSettings(
        resolution=16, cascades=2, steps=2, photons=5000))
    with pytest.raises(ValueError, match=r"point: element .* is nan"):
        cascaded.recenter((float("nan"), 0.0, 0.0))
    with pytest.raises(ValueError, match="point"):
        cascaded.recenter((1.0, 2.0))
    # Before the first pass the levels move and the field stays empty.
    assert cascaded.recenter((12.0, 0.0, 1.0)) == [0]
    assert cascaded.current_field().level_count == 0
    cascaded.refine()
    xs, points, normals = floor_line()
    assert np.all(np.isfinite(line_irradiance(cascaded.current_field(), points, normals)))
    scene.set_world(shgi.World(color=(0.1, 0.1, 0.1), strength=1.0))
    scene.commit()
    with pytest.raises(ValueError, match="recenter: the scene was edited"):
        cascaded.recenter((-12.0, 0.0, 1.0))


def test_a_cancelled_recenter_keeps_the_volume():
    """A cancel while the moved levels are rebuilt keeps the solver and its field as they were;
    the next recenter moves them from there."""
    import numpy as np
    scene = hall()
    settings = shgi.PropagationSettings(resolution=16, cascades=3, steps=4, photons=20000,
                                        cascade_follow_camera=False, cascade_center=CASCADE_CENTER)
    volume = shgi.PropagationVolume(scene, settings)
    volume.refine()
    volume.refine()
    xs, points, normals = floor_line()
    before = line_irradiance(volume.current_field(), points, normals)
    for stage_to_cancel in ("geometry volume, level 1", "re-injecting VPLs, pass 2",
                            "propagating, level 0"):
        progress = shgi.Progress(
            lambda fraction, stage: progress.cancel() if stage == stage_to_cancel else None)
        with pytest.raises(shgi.Cancelled):
            volume.recenter((9.0, 0.0, 1.5), progress)
        np.testing.assert_array_equal(line_irradiance(volume.current_field(), points, normals),
                                      before)
    assert volume.recenter((9.0, 0.0, 1.5)) == [0, 1]
