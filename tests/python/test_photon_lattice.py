"""The PhotonLattice solver and the preview renderer through Python.

Agreement with the reference path tracer on the project's Cornell box and sun room (fixed seeds,
default solver and preview settings): the mean of DiffInd x DiffCol within 10%, and Combined
PSNR >= 30 dB after auto-exposure (mean luminance of the reference mapped to 0.18) and sRGB.
The references are rendered in the test at a small size with Cycles' default bounce limits.
"""

import pathlib
import resource
import sys

import numpy as np
import pytest

import shgi
from blender_support import REPO_ROOT
from shgi.metrics import psnr  # the figure the Blender tests use too
from scene_support import committed, field_agreement, path_traced_reference

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/ is not a package)

SCALE = 0.25            # 64 x 64 (Cornell box) and 64 x 48 (sun room) pixels
REFERENCE_SAMPLES = 2048


def solved(scene):
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(seed=5))
    lattice.solve()
    return lattice


def agreement(name):
    """(reference passes, preview passes) for a project scene, computed once per session."""
    reference, (preview, timings) = field_agreement("PHOTON_LATTICE", getattr(scenes, name),
                                                    SCALE, REFERENCE_SAMPLES, solved)
    assert set(timings) == {"primary", "direct", "indirect", "frame_stages", "total"}
    return reference, preview


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room"])
def test_indirect_diffuse_agrees_with_path_tracer(name):
    reference, preview = agreement(name)
    expected = float((reference["DiffInd"] * reference["DiffCol"]).mean())
    measured = float((preview["DiffInd"] * preview["DiffCol"]).mean())
    assert abs(measured / expected - 1.0) < 0.10, (measured, expected)


@pytest.mark.reference
@pytest.mark.parametrize("name", ["cornell_box", "sun_room"])
def test_combined_psnr_against_path_tracer(name):
    reference, preview = agreement(name)
    assert psnr(reference["Combined"], preview["Combined"]) >= 30.0


def test_settings_mirror_cpp_defaults():
    settings = shgi.PhotonLatticeSettings()
    assert settings.photons == 200000 and settings.seed == 0
    assert (settings.max_bounces, settings.resolution, settings.order) == (4, 16, 2)
    assert settings.caustics == shgi.CausticMode.LATTICE
    assert settings.interpolation == shgi.LatticeInterpolation.CUBIC
    assert not settings.world_in_field
    assert shgi.PreviewSettings().samples == 16
    with pytest.raises(TypeError, match="no field 'photon'"):
        shgi.PhotonLatticeSettings(photon=3)


def test_bad_settings_name_the_field():
    scene = committed(scenes.cornell_box(0.05))
    with pytest.raises(ValueError, match="PhotonLatticeSettings.order is 3"):
        shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(order=3))
    with pytest.raises(ValueError, match="PreviewSettings.max_specular_bounces is -1"):
        shgi.render_preview(scene, None, shgi.PreviewSettings(max_specular_bounces=-1))


def test_empty_scene_is_refused():
    scene = shgi.Scene()
    scene.commit()
    with pytest.raises(ValueError, match="no geometry"):
        shgi.PhotonLattice(scene)


def test_interactive_passes_refine_and_are_deterministic():
    scene = committed(scenes.cornell_box(0.05))
    settings = shgi.PhotonLatticeSettings(photons=20000, seed=3)
    points = np.array([[0.0, 1.0, 0.001], [-0.999, 1.0, 1.0], [0.0, 1.999, 1.0]])
    normals = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    first = shgi.PhotonLattice(scene, settings)
    first.solve()
    one_pass = first.irradiance(points, normals)
    first.solve()
    assert first.passes == 2
    two_passes = first.irradiance(points, normals)
    assert np.all(one_pass > 0.0) and not np.array_equal(one_pass, two_passes)
    np.testing.assert_allclose(two_passes, one_pass, rtol=0.25)  # same field, less noise
    assert first.timings["photons_emitted"] == 20000
    assert first.timings["bounces"] >= first.timings["photons_stored"] > 0

    threads = shgi.max_threads()
    try:
        shgi.set_max_threads(1)
        single = shgi.PhotonLattice(scene, settings)
        single.solve()
        single.solve()
    finally:
        shgi.set_max_threads(threads)
    np.testing.assert_array_equal(single.irradiance(points, normals), two_passes)
    first.reset()
    assert first.passes == 0
    np.testing.assert_array_equal(first.irradiance(points, normals), 0.0)


def test_cancel_keeps_the_previous_solution():
    scene = committed(scenes.cornell_box(0.05))
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(photons=20000))
    lattice.solve()
    before = lattice.irradiance([[0.0, 1.0, 0.001]], [[0.0, 0.0, 1.0]])
    progress = shgi.Progress()
    progress.cancel()
    with pytest.raises(shgi.Cancelled):
        lattice.solve(progress)
    assert lattice.passes == 1
    np.testing.assert_array_equal(lattice.irradiance([[0.0, 1.0, 0.001]], [[0.0, 0.0, 1.0]]),
                                  before)


def test_a_huge_photon_count_traces_in_blocks_and_cancels_without_a_memory_spike():
    """photons = 2**38 once allocated 3.6 GB of per-chunk records before tracing one photon;
    the pass now runs in blocks of chunks, and progress counts the whole pass. (Left alone, the
    pass is refused after its pilot block: test_memory_budget.py; the cancel comes first.)"""
    scene = committed(scenes.cornell_box(0.1))
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(resolution=8, photons=2**38))
    fractions = []

    def cancel_once_moving(fraction, stage):
        fractions.append(fraction)
        if fraction > 0.0:
            progress.cancel()

    progress = shgi.Progress(cancel_once_moving)
    peak_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB
    with pytest.raises(shgi.Cancelled):
        lattice.solve(progress=progress)
    grown_mib = (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - peak_before) / 1024
    assert grown_mib < 1024, f"the cancelled solve grew the peak memory by {grown_mib:.0f} MiB"
    assert 0.0 < max(fractions) < 0.01  # a second's photons are a sliver of 2**38
    assert lattice.passes == 0


def test_preview_renders_any_camera_and_refines_progressively():
    builder = scenes.cornell_box(0.05)
    scene = committed(builder)
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(photons=20000))
    lattice.solve()
    camera = scene.camera
    camera.resolution_x, camera.resolution_y = 20, 10
    renderer = shgi.PreviewRenderer(scene, shgi.PreviewSettings(seed=2), camera=camera)
    renderer.render(lattice, 2)
    renderer.render(lattice, 2)
    passes = renderer.passes()
    assert passes["Combined"].shape == (10, 20, 4)
    one_shot, _ = shgi.render_preview(scene, lattice, shgi.PreviewSettings(samples=4, seed=2),
                                      camera=camera)
    np.testing.assert_allclose(passes["Combined"], one_shot["Combined"], rtol=1e-5, atol=1e-6)
    assert (passes["DiffInd"] > 0.0).any()
    direct_only, _ = shgi.render_preview(scene, None, shgi.PreviewSettings(samples=4, seed=2),
                                         camera=camera)
    np.testing.assert_array_equal(direct_only["DiffInd"], 0.0)
    np.testing.assert_array_equal(direct_only["DiffDir"], one_shot["DiffDir"])


def test_lattice_export_writes_every_coefficient_and_documents_the_layout(tmp_path):
    import json

    from shgi.volume_export import export_lattice

    scene = committed(scenes.cornell_box(0.1))
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(photons=20000, seed=3))
    with pytest.raises(ValueError, match="solve"):
        export_lattice(lattice, tmp_path / "unsolved.json")
    lattice.solve()
    paths = export_lattice(lattice, tmp_path / "cornell.json")
    doc = json.loads(pathlib.Path(paths[0]).read_text())
    assert doc["format"] == "shgi-sh-lattice" and doc["version"] == 1
    assert "Condon-Shortley" in doc["sh"]["basis"] and "W m^-2 sr^-1" in doc["sh"]["unit"]
    solved = lattice.lattices
    for entry in doc["lattices"]:
        data = solved[entry["name"]]
        nx, ny, nz = entry["dims"]
        assert tuple(entry["dims"]) == tuple(data["dims"])
        image = shgi.read_exr(tmp_path / entry["sh_file"])
        assert len(image) == entry["coefficients"] == (data["order"] + 1) ** 2
        for c in range(entry["coefficients"]):
            pixels = image[f"sh{c:02d}"]
            assert pixels.shape == (ny * nz, nx, 3)
            # Cell (i, j, k) at column i, row j + ny * k.
            np.testing.assert_array_equal(pixels.reshape(nz, ny, nx, 3), data["sh"][..., c, :])
    assert np.abs(solved["global"]["sh"]).max() > 0.0
    with pytest.raises(ValueError, match=".json"):
        export_lattice(lattice, tmp_path / "cornell.exr")


def test_a_saved_lattice_loads_back_and_renders_the_same_pixels(tmp_path):
    """save() then load(): the loaded lattice renders the solved one's image bit for bit (the
    same float32 lattices and cell surfaces), keeps its settings, passes and timings, and
    cannot solve again (it has no scene); a truncated file is refused by name."""
    scene = committed(scenes.cornell_box(0.05))
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(photons=20000, seed=4))
    lattice.solve()
    lattice.solve()
    path = tmp_path / "cornell.shlattice"
    lattice.save(path)
    loaded = shgi.PhotonLattice.load(path)
    assert (loaded.passes, loaded.timings, loaded.settings.seed) == (2, lattice.timings, 4)
    preview = shgi.PreviewSettings(samples=2, seed=3)
    solved_image, _ = shgi.render_preview(scene, lattice, preview)
    loaded_image, _ = shgi.render_preview(scene, loaded, preview)
    assert (solved_image["DiffInd"] > 0.0).any()
    for name, pixels in solved_image.items():
        np.testing.assert_array_equal(loaded_image[name], pixels, err_msg=name)
    with pytest.raises(ValueError, match=rf"read from \"{path}\" and has no scene"):
        loaded.refine()
    truncated = tmp_path / "truncated.shlattice"
    truncated.write_bytes(path.read_bytes()[:1000])
    with pytest.raises(OSError, match=rf"^cannot read lattice file \"{truncated}\": the lattice "
                                      r"coefficients \(110592 of 4 bytes\) is longer than"):
        shgi.PhotonLattice.load(truncated)


# The add-on's quality presets (addon/shgi_blender/presets.py), read without bpy.
sys.path.insert(0, str(REPO_ROOT / "addon"))
from shgi_blender.presets import QUALITY_PRESETS  # noqa: E402


def two_rooms(bright_lamp_power):
    """The two rooms (scale 0.5) with the lamp beyond the wall at `bright_lamp_power` W."""
    builder = scenes.two_rooms(0.5)
    lights = list(builder.scene.lights)
    for light in lights:
        if light.name == "bright_lamp":
            light.power = bright_lamp_power
    builder.scene.set_lights(lights)
    return committed(builder)


def dim_room_means(scene, preset, final_gather=True):
    """(Combined, DiffInd x DiffCol) means of the dim room (all the camera sees) with the lattice
    solved at `preset`'s counts as the add-on solves it for Light Paths > Diffuse 4 (one photon
    scattering less through a final gather, settings.light_path_fields)."""
    values = QUALITY_PRESETS[preset]
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(
        seed=5, photons=values["photon_lattice.photons"],
        resolution=values["photon_lattice.resolution"],
        caustic_resolution=values["photon_lattice.caustic_resolution"],
        max_bounces=4 - int(final_gather)))
    lattice.solve()
    preview, _ = shgi.render_preview(scene, lattice.current_field(), shgi.PreviewSettings(
        seed=5, samples=64, final_gather=final_gather))
    return (float(preview["Combined"][..., :3].mean()),
            float((preview["DiffInd"] * preview["DiffCol"]).mean()))


@pytest.mark.reference
@pytest.mark.parametrize("preset", list(QUALITY_PRESETS))
def test_no_light_crosses_the_two_rooms_wall(preset):
    """The leak itself: a 2000 W lamp beyond a 0.1 m wall, thinner than every preset's cells
    (0.125-0.375 m), adds nothing to the dim room in the path tracer, and (through the lattice's
    visibility masks) at most 1.5% to the lattice's dim room, Combined and indirect diffuse,
    direct lookup and final gather. Before the masks it added (direct lookup, Combined /
    indirect) 66% / 95% at Default and 8% / 11% at Production: the bright room's cells were
    blended into the dim room's lookups through the wall. The lamps
    share the photons by power, so with the bright lamp on the dim room holds 1% of them and its
    mean moves by their noise (measured -2.4% at Medium, direct lookup): bounded at 5% below."""
    dark = two_rooms(0.0)
    lit = two_rooms(2000.0)
    for gather in (False, True):
        ratios = [with_lamp / without for with_lamp, without in
                  zip(dim_room_means(lit, preset, gather), dim_room_means(dark, preset, gather))]
        print(f"{preset}, final gather {gather}: dim room with / without the bright lamp "
              f"(Combined, indirect): {ratios[0]:.3f}, {ratios[1]:.3f}")
        assert all(0.95 < ratio < 1.015 for ratio in ratios), (gather, ratios)


# With glossy scatterings counted apart (PhotonLatticeSettings.glossy_bounces, as Light Paths >
# Glossy) and a spent diffuse budget leaving the glossy lobe on, as the path tracer's does, every
# preset comes within 5% (0.951-0.956 indirect at Default-Medium, 2026-11-29); with a glossy
# gather ray no longer spending the diffuse bounce (render/path_integrator.h), 0.961-0.980.
@pytest.mark.reference
@pytest.mark.parametrize("preset", list(QUALITY_PRESETS))
def test_dim_room_through_a_final_gather_is_within_five_percent(preset):
    """The issue's target: the dim room read through a final gather within 5% of the path
    tracer's (Combined and indirect diffuse) at every preset. Before the visibility masks it read
    1.58x (Preview) to 1.01x (Production) too bright; since, 0.94x; with glossy_bounces 0.96x
    (indirect 0.943 at Default); with glossy reflection after the last diffuse one 0.951."""
    scene, reference = path_traced_reference(scenes.two_rooms, 0.5, 512)
    measured = dim_room_means(scene, preset)
    ratios = (measured[0] / float(reference["Combined"][..., :3].mean()),
              measured[1] / float((reference["DiffInd"] * reference["DiffCol"]).mean()))
    print(f"{preset}: dim room through a final gather (Combined, indirect) / path tracer: "
          f"{ratios[0]:.3f}, {ratios[1]:.3f}")
    assert all(abs(ratio - 1.0) < 0.05 for ratio in ratios), ratios


def plaster_room(camera):
    """The dim room of the two rooms alone (3 x 3 x 2.5 m, Principled plaster: Roughness 0.5,
    Specular 0.5; the 100 W lamp 0.5 m under the ceiling), seen by `camera(builder)`."""
    plaster = shgi.Material(name="plaster", base_color=scenes.WHITE)
    builder = scenes.closed_room((3.0, 3.0, 2.5), plaster, lamp_at=(1.5, 1.5, 2.0))
    camera(builder)
    return committed(builder)


def glossy_ratio(scene, reference_samples=1024, surface_normal=None):
    """The lattice's glossy indirect light (GlossInd x GlossCol, read at the first surface) over
    the path tracer's: the image's mean, or that of the pixels whose normal is surface_normal."""
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(
        seed=5, photons=400000, resolution=32, max_bounces=4))
    lattice.solve()
    reference = shgi.render_path_traced(scene, shgi.PathTracerSettings(
        samples=reference_samples, seed=11))
    preview, _ = shgi.render_preview(scene, lattice.current_field(),
                                     shgi.PreviewSettings(seed=5, samples=16))
    means = []
    for passes in (reference, preview):
        glossy = (passes["GlossInd"] * passes["GlossCol"])[..., :3]
        if surface_normal is not None:
            glossy = glossy[passes["Normal"][..., :3] @ np.asarray(surface_normal) > 0.99]
        means.append(float(glossy.mean()))
    return means[1] / means[0]


@pytest.mark.reference
def test_glossy_indirect_light_of_a_plaster_room_is_within_five_percent():
    """A cell's SH holds what its surfaces receive, nothing from below their horizon, and L2
    rounds that step off: a glossy lobe read it as about half at grazing views and 1.15x along
    the normal. The lookup divides by what the lobe reads of the upper hemisphere
    (FieldLookup.horizon): the room's glossy indirect light read 0.80 of the path tracer's (the
    two rooms' camera, 2026-11-29), now within 5%, as the probe grid's (0.985)."""
    def camera(builder):
        builder.camera(eye=(2.9, 0.2, 1.4), target=(0.0, 2.2, 1.0), lens=18.0, width=128,
                       height=96, scale=0.25)
    ratio = glossy_ratio(plaster_room(camera))
    print(f"plaster room: lattice glossy indirect / path tracer {ratio:.3f}")
    assert abs(ratio - 1.0) < 0.05, ratio


@pytest.mark.reference
def test_glossy_indirect_light_at_a_grazing_view_is_not_halved():
    """The floor seen 80 degrees from its normal by an orthographic camera: every pixel's lobe
    lies near the horizon, where the rounded step read 0.51 of the path tracer's glossy light;
    now 0.91, as the probe grid's L2 lobe reads (0.90: bench/lattice_glossy_angles.py), whose
    limit the 15% here allows for."""
    def camera(builder):
        angle = np.radians(80.0)
        eye = np.array([1.5, 1.5, 0.0]) + 0.9 * np.array([np.sin(angle), 0.0, np.cos(angle)])
        view = shgi.Camera(type=shgi.CameraType.ORTHOGRAPHIC, ortho_scale=0.8, resolution_x=24,
                           resolution_y=24, clip_start=0.01)
        view.world_from_camera = scenes.look_at(eye, (1.5, 1.5, 0.0), (0, 1, 0))
        builder.scene.set_camera(view)
    ratio = glossy_ratio(plaster_room(camera), surface_normal=(0.0, 0.0, 1.0))
    print(f"plaster room's floor at 80 degrees: lattice glossy indirect / path tracer {ratio:.3f}")
    assert abs(ratio - 1.0) < 0.15, ratio


def test_a_lattice_saved_before_the_visibility_masks_opens_and_samples_as_it_did():
    """Lattice file version 1 (no visibility masks; solutions saved with a .blend by the earlier
    add-on) still loads, and its lookups are those of the build that saved it, bit for bit."""
    import json
    folder = pathlib.Path(__file__).parent / "lattice_files"
    expected = json.loads((folder / "cornell_box_v1.json").read_text())
    lattice = shgi.PhotonLattice.load(str(folder / "cornell_box_v1.shlattice"))
    # Saved before glossy_bounces: its photons counted glossy scatterings against max_bounces.
    assert lattice.settings.glossy_bounces == -1
    for (point, normal), values in zip(expected["points"], expected["radiance_sh"]):
        np.testing.assert_array_equal(np.asarray(lattice.radiance_sh(point, normal)),
                                      np.asarray(values, np.float32))


@pytest.mark.xfail(strict=True, reason=(
    "not built: per-cell storage by side of the surface. Both floors lie in one 0.25 m cell (and "
    "the floor's lookup offset reaches past the shelf), so the unlit floor reads the shelf's "
    "light: ratio 1.000 measured 2026-11-28, with and without the visibility masks"))
def test_an_unlit_floor_one_centimetre_under_a_lit_shelf_reads_zero():
    """The minimal thin-gap scene: a 2 x 2 m shelf whose top is lit by the light a ceiling
    reflects, and a 1 x 1 m floor 1 cm under its middle, both facing up. No light reaches the
    floor (the path tracer's answer is 0 up to the light through the 1 cm slit, 0.5 m away):
    the lattice's lookup there should read (nearly) nothing."""
    from scenes import SceneBuilder, WHITE, quad
    builder = SceneBuilder()
    builder.part("ceiling", quad((-2, -2, 2.5), (0, 4, 0), (4, 0, 0)), "plaster", WHITE)
    builder.part("shelf", quad((-1, -1, 0.51), (2, 0, 0), (0, 2, 0)), "plaster", WHITE)
    builder.part("floor", quad((-0.5, -0.5, 0.50), (1, 0, 0), (0, 1, 0)), "plaster", WHITE)
    lamp = shgi.Light(name="lamp", type=shgi.LightType.POINT, power=100.0, radius=0.05)
    lamp.world_from_light = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 2.0], [0, 0, 0, 1]],
                                     np.float32)
    builder.scene.add_light(lamp)
    builder.scene.set_world(shgi.World(color=(0.0, 0.0, 0.0), strength=0.0))
    scene = committed(builder)
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(
        seed=5, photons=200000, resolution=16, max_bounces=2))
    lattice.solve()
    shelf = np.asarray(lattice.radiance_sh((0.1, 0.1, 0.51), (0, 0, 1)))[0]
    floor = np.asarray(lattice.radiance_sh((0.1, 0.1, 0.50), (0, 0, 1)))[0]
    print(f"L00 on the shelf {shelf}, on the floor under it {floor}")
    assert shelf.min() > 0.1
    assert floor.max() < 0.01 * shelf.min(), (floor, shelf)


def test_reset_reports_progress_through_the_visibility_rays():
    """A reset measures the cells' surfaces (clipping the triangles: the first half of its
    progress), then traces the visibility rays between neighbouring cells (the second half, which
    reported nothing before and looked stuck at 100% in the status bar while it ran)."""
    scene = committed(scenes.cornell_box(0.1))
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(
        resolution=24, caustics=shgi.CausticMode.OFF))
    fractions = []  # every report: no minimum interval between callbacks
    lattice.reset(shgi.Progress(lambda fraction, stage: fractions.append(fraction), 0.0))
    assert fractions == sorted(fractions) and fractions[-1] == pytest.approx(1.0)
    assert len({f for f in fractions if 0.5 < f < 1.0}) >= 3, fractions
