"""The RadianceField solver (seed 001) through Python: settings, validation, passes, cancel, and
agreement with the reference path tracer on the project's scenes.

Agreement (fixed seeds, default solver settings, one pass as a final solve runs): the Cornell
box at 64 x 64 pixels against a 2048-sample path-traced reference, Combined PSNR after
auto-exposure and sRGB (shgi.metrics.psnr) and the mean of DiffInd x DiffCol; the sun room
the same way (the photon lattice's reference), and the dim room of two_rooms (all the camera
sees) at 128 x 96 x 0.5 pixels against 512 samples. docs/methods.md, "Radiance field", has the
figures and the command that measures them.
"""

import sys

import numpy as np
import pytest

import shgi
from blender_support import REPO_ROOT
from scene_support import committed, field_agreement
from shgi.metrics import psnr

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/ is not a package)

SCALE = 0.25
REFERENCE_SAMPLES = 2048


def indirect_diffuse(passes):
    return float((passes["DiffInd"] * passes["DiffCol"]).mean())


def solved(scene):
    field = shgi.RadianceField(scene, shgi.RadianceFieldSettings(seed=5))
    field.refine()
    return field


def agreement(name, scale=SCALE, samples=REFERENCE_SAMPLES):
    """(reference passes, preview passes) of a project scene, once per session."""
    reference, (preview, _) = field_agreement("RADIANCE_FIELD", getattr(scenes, name), scale,
                                              samples, solved)
    return reference, preview


def test_settings_mirror_cpp_defaults():
    s = shgi.RadianceFieldSettings()
    assert (s.photons, s.seed, s.max_bounces, s.glossy_bounces, s.resolution, s.gather_rays) == (
        200000, 0, 4, 4, 32, 400)
    assert s.face_estimator == shgi.FaceEstimator.PROJECTED_AREA
    assert s.use_mips and s.mip_levels == 4 and s.side_test
    assert not (s.visibility_test or s.obscurance or s.world_in_field or s.use_bounds)
    assert s.face_sigma == pytest.approx(0.5) and s.backface_threshold == pytest.approx(0.25)
    assert s.obscurance_rays == 32 and s.obscurance_weight == pytest.approx(1.0)
    assert not s.monte_carlo_gathers
    assert (s.diffuse_gather_rays, s.glossy_gather_rays) == (32, 64)


@pytest.mark.parametrize("field, value", [("resolution", 0), ("gather_rays", 0),
                                          ("glossy_bounces", -1), ("glossy_bounces", 65),
                                          ("diffuse_gather_rays", 0), ("glossy_gather_rays", 0),
                                          ("face_sigma", float("nan")), ("mip_levels", 0),
                                          ("obscurance_distance", float("inf"))])
def test_bad_settings_name_the_field(field, value):
    with pytest.raises(ValueError, match=f"RadianceFieldSettings.{field}"):
        shgi.RadianceFieldSettings(**{field: value}).validate()


def test_registry_row_and_solver():
    row = shgi.method("RADIANCE_FIELD")
    assert (row.number, row.settings_type, row.final_passes) == (4, shgi.RadianceFieldSettings, 1)
    scene = committed(scenes.cornell_box(0.125))
    solver = shgi.make_solver("RADIANCE_FIELD", scene,
                              shgi.RadianceFieldSettings(photons=20000, resolution=8,
                                                         gather_rays=64))
    assert isinstance(solver, shgi.RadianceField) and solver.passes == 0
    solver.refine()
    assert solver.passes == 1
    assert [stage for stage, _ in solver.stage_seconds] == [
        "voxelise", "photons", "radiance_grid", "sh_field"]
    assert solver.timings["sample_points"] > 0 and solver.memory_bytes > 0


def test_passes_refine_deterministically_and_cancel_keeps_the_solution():
    scene = committed(scenes.cornell_box(0.125))
    settings = shgi.RadianceFieldSettings(photons=20000, resolution=8, gather_rays=64, seed=3)
    fields = [shgi.RadianceField(scene, settings) for _ in range(2)]
    for field in fields:
        field.refine()
    points = [[0.0, 0.5, 0.3], [0.5, 0.5, 1.0]]
    normals = [[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]]
    first = fields[0].irradiance(points, normals)
    assert np.array_equal(first, fields[1].irradiance(points, normals))
    assert (first > 0.0).all()

    def cancel_in_the_gather(fraction, stage):
        if stage == "sh_field":  # after the photons and the grid of the pass
            progress.cancel()

    progress = shgi.Progress(cancel_in_the_gather)
    with pytest.raises(shgi.Cancelled):
        fields[0].refine(progress)
    assert fields[0].passes == 1
    np.testing.assert_array_equal(fields[0].irradiance(points, normals), first)


@pytest.mark.reference
def test_cornell_box_combined_psnr_against_path_tracer():
    reference, preview = agreement("cornell_box")
    quality = psnr(reference["Combined"], preview["Combined"])
    print(f"cornell_box: Combined PSNR {quality:.2f} dB")
    assert quality >= 36.0


@pytest.mark.reference
def test_cornell_box_indirect_diffuse_agrees_with_path_tracer():
    reference, preview = agreement("cornell_box")
    ratio = indirect_diffuse(preview) / indirect_diffuse(reference)
    print(f"cornell_box: DiffInd x DiffCol / reference {ratio:.3f}")
    assert abs(ratio - 1.0) < 0.05


@pytest.mark.reference
@pytest.mark.parametrize("name, scale, samples", [("sun_room", SCALE, REFERENCE_SAMPLES),
                                                  ("two_rooms", 0.5, 512)])
def test_rooms_agree_with_path_tracer(name, scale, samples):
    """The issue's targets: the sun room Combined PSNR >= 32 dB and its indirect diffuse within
    5%; two_rooms' dim room (all the camera sees) within 5%. Before a gather hit read only the
    faces of the side it sees, the sun room read 23.6 dB / +15% (its creases read the sunlit
    outside walls) and the dim room -6.4%; before glossy scatterings had their own budget,
    -5.7% and -4.0%."""
    reference, preview = agreement(name, scale, samples)
    quality = psnr(reference["Combined"], preview["Combined"])
    ratio = indirect_diffuse(preview) / indirect_diffuse(reference)
    print(f"{name}: Combined PSNR {quality:.2f} dB, DiffInd x DiffCol / reference {ratio:.3f}")
    if name == "sun_room":
        assert quality >= 32.0
    assert abs(ratio - 1.0) < 0.05
