"""SH probe grids (seed 002) through Python.

Agreement with the reference path tracer on the project's Cornell box and sun room for L1, L2
and L4 probes (fixed seeds; 0.3 m probe spacing, 6 update passes of 256 paths per probe): the
mean of DiffInd x DiffCol within 10% and Combined PSNR >= 30 dB (auto-exposure, sRGB), as for
the photon lattice. The leak test renders the dim one of two rooms split by a wall thinner than
the probe spacing.
"""

import json
import os
import sys
import threading

import numpy as np
import pytest

import shgi
from blender_support import REPO_ROOT
from shgi.metrics import psnr
from scene_support import committed, finishes_in_a_thread, path_traced_reference

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/ is not a package)

SCALE = 0.25
REFERENCE_SAMPLES = 2048
AGREEMENT_PASSES = 6


def reference(name, scale=SCALE, samples=REFERENCE_SAMPLES):
    return path_traced_reference(getattr(scenes, name), scale, samples)


def indirect_diffuse(passes):
    return float((passes["DiffInd"] * passes["DiffCol"]).mean())


def solved_grid(scene, updates, **settings):
    grid = shgi.ProbeGrid(scene, shgi.ProbeGridSettings(seed=5, **settings))
    for _ in range(updates):
        grid.update()
    return grid


@pytest.mark.reference
@pytest.mark.parametrize("order", [1, 2, 4])
@pytest.mark.parametrize("name", ["cornell_box", "sun_room"])
def test_agrees_with_path_tracer(name, order):
    scene, ref = reference(name)
    grid = solved_grid(scene, AGREEMENT_PASSES, order=order, spacing=0.3)
    preview, _ = shgi.render_preview(scene, grid.field(), shgi.PreviewSettings(seed=5))
    ratio = indirect_diffuse(preview) / indirect_diffuse(ref)
    quality = psnr(ref["Combined"], preview["Combined"])
    print(f"{name} L{order}: {grid.probe_count} probes, update {grid.timings['update']:.2f} s/pass, "
          f"DiffInd {100 * (ratio - 1):+.1f}%, PSNR {quality:.2f} dB")
    assert abs(ratio - 1.0) < 0.10, ratio
    assert quality >= 30.0


@pytest.mark.reference
def test_dim_room_does_not_leak():
    """The dim room's indirect light against the path tracer: within 15% with visibility; plain
    trilinear interpolation, reported beside it, lets the bright room's probes through the wall."""
    scene, ref = reference("two_rooms", scale=0.5, samples=512)
    expected = indirect_diffuse(ref)
    measured = {}
    for visibility in (True, False):
        grid = solved_grid(scene, 6, visibility=visibility)
        preview, _ = shgi.render_preview(scene, grid.field(), shgi.PreviewSettings(seed=5))
        measured[visibility] = indirect_diffuse(preview) / expected
    print(f"dim room indirect / reference: visibility {measured[True]:.3f}, "
          f"plain trilinear {measured[False]:.3f}")
    assert abs(measured[True] - 1.0) < 0.15
    assert measured[False] > 2.0, "the fixture should leak without visibility"


@pytest.mark.reference
def test_dim_room_through_a_final_gather_is_within_five_percent():
    """Read through a final gather, with one bounce less in the probes (the add-on's accounting:
    Light Paths > Diffuse 4 gives 2 probe bounces behind the gather), the dim room's light is
    within 5% of the path tracer's, the issue's leak target; with the probes' own 3 bounces the
    gather adds a bounce and reads brighter (reported beside it)."""
    scene, ref = reference("two_rooms", scale=0.5, samples=512)
    measured = {}
    for bounces in (2, 3):
        grid = solved_grid(scene, 8, bounces=bounces)
        preview, _ = shgi.render_preview(scene, grid.field(),
                                         shgi.PreviewSettings(seed=5, samples=64,
                                                              final_gather=True))
        measured[bounces] = (
            float(preview["Combined"][..., :3].mean() / ref["Combined"][..., :3].mean()),
            indirect_diffuse(preview) / indirect_diffuse(ref))
    print(f"dim room through a final gather (Combined, indirect) / reference: {measured}")
    assert all(abs(ratio - 1.0) < 0.05 for ratio in measured[2])
    assert measured[3][1] > measured[2][1]


def test_settings_mirror_cpp_defaults_and_validate():
    s = shgi.ProbeGridSettings()
    assert (s.order, s.rays_per_probe, s.seed, s.bounces) == (2, 256, 0, 3)
    assert s.volumes == [] and s.spacing == 0.0 and s.visibility and s.relocate
    assert s.hysteresis == pytest.approx(0.95) and s.normal_bias == pytest.approx(0.25)
    with pytest.raises(TypeError, match="no field 'rays'"):
        shgi.ProbeGridSettings(rays=3)
    # Unsigned fields take any int (numpy's too) and name the field when it does not fit,
    # rather than pybind's TypeError about incompatible arguments.
    assert shgi.ProbeGridSettings(seed=np.uint64(2**64 - 1)).seed == 2**64 - 1
    with pytest.raises(ValueError, match=r"rays_per_probe: must be in \[0, 4294967295\], got -1"):
        shgi.ProbeGridSettings(rays_per_probe=-1)
    with pytest.raises(ValueError, match=r"seed: must be in \[0, 18446744073709551615\]"):
        shgi.ProbeGridSettings(seed=2**64)
    with pytest.raises(TypeError):
        shgi.ProbeGridSettings(placement_rays=1.5)
    scene = committed(scenes.cornell_box(0.05))
    with pytest.raises(ValueError, match="ProbeGridSettings.order is 5"):
        shgi.ProbeGrid(scene, shgi.ProbeGridSettings(order=5))
    with pytest.raises(ValueError, match=r"volumes\[0\].resolution\[2\] is 0"):
        volume = shgi.ProbeVolume(resolution=(2, 2, 0))
        shgi.ProbeGrid(scene, shgi.ProbeGridSettings(volumes=[volume]))
    with pytest.raises(ValueError, match="world_from_volume"):
        shgi.ProbeVolume(world_from_volume=np.full((4, 4), np.nan))
    empty = shgi.Scene()
    empty.commit()
    with pytest.raises(ValueError, match="no geometry"):
        shgi.ProbeGrid(empty)


def test_volumes_updates_and_determinism():
    scene = committed(scenes.cornell_box(0.05))
    volume = shgi.ProbeVolume(resolution=(3, 3, 2))
    volume.world_from_volume = np.array([[0.9, 0, 0, 0], [0, 0.9, 0, 1.0], [0, 0, 0.9, 1.0],
                                         [0, 0, 0, 1]], np.float32)
    settings = shgi.ProbeGridSettings(volumes=[volume], rays_per_probe=64, seed=2)
    grid = shgi.ProbeGrid(scene, settings)
    assert grid.probe_count == 18 and grid.positions.shape == (18, 3)
    assert grid.sh.shape == (18, 9, 3) and not grid.sh.any()
    assert np.isinf(grid.relative_error()).all()
    grid.update()
    grid.update()
    assert grid.passes == 2 and grid.timings["paths"] == 64 * grid.active_count
    assert (grid.sh[grid.active, 0] > 0).all()
    assert (grid.relative_error()[grid.active] < 1.0).all()
    threads = shgi.max_threads()
    try:
        shgi.set_max_threads(1)
        single = shgi.ProbeGrid(scene, settings)
        single.update()
        single.update()
    finally:
        shgi.set_max_threads(threads)
    np.testing.assert_array_equal(single.sh, grid.sh)
    grid.reset()
    assert grid.passes == 0 and not grid.sh.any()


def test_snapshot_renders_while_the_grid_updates():
    """seed 002 Fig. 4.1: the update runs beside the renderer, which draws the latest snapshot."""
    scene = committed(scenes.cornell_box(0.1))
    grid = solved_grid(scene, 1, rays_per_probe=32)
    snapshot = grid.field()
    before = snapshot.sh.copy()
    errors = []

    def refine():
        try:
            for _ in range(3):
                grid.update()
        except Exception as error:  # pragma: no cover - reported below
            errors.append(error)

    worker = threading.Thread(target=refine)
    worker.start()
    frames = [shgi.render_preview(scene, snapshot, shgi.PreviewSettings(samples=1))[0]
              for _ in range(3)]
    worker.join()
    assert not errors
    assert grid.passes == 4 and snapshot.passes == 1
    np.testing.assert_array_equal(snapshot.sh, before)
    assert all((frame["DiffInd"] > 0).any() for frame in frames)
    assert not np.array_equal(grid.field().sh, before)


def test_concurrent_calls_on_one_grid_are_serialised():
    """update() and reset() from two threads, and lookups beside them, neither crash the host nor
    lose passes: the calls run one at a time and readers hold their own snapshot."""
    scene = committed(scenes.cornell_box(0.1))
    grid = solved_grid(scene, 0, rays_per_probe=4, placement_rays=8)
    points = np.tile(np.array([[0.0, 0.0, 0.5]], np.float32), (2000, 1))
    normals = np.tile(np.array([[0.0, 0.0, 1.0]], np.float32), (2000, 1))
    errors = []

    def repeat(call, times):
        try:
            for _ in range(times):
                call()
        except Exception as error:  # pragma: no cover - reported below
            errors.append(error)

    workers = [threading.Thread(target=repeat, args=(grid.update, 20)),
               threading.Thread(target=repeat, args=(grid.update, 20)),
               threading.Thread(target=repeat, args=(lambda: grid.irradiance(points, normals), 20)),
               threading.Thread(target=repeat, args=(lambda: grid.sh, 20))]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()
    assert not errors
    assert grid.passes == 40
    worker = threading.Thread(target=repeat, args=(grid.reset, 10))
    worker.start()
    repeat(grid.update, 10)
    worker.join()
    assert not errors
    assert 0 <= grid.passes <= 10
    assert np.isfinite(grid.irradiance(points, normals)).all()


def test_update_or_reset_from_the_grids_own_progress_callback_is_refused_not_a_deadlock():
    """update() waited for its own lock when its progress callback called update() or reset();
    the callback runs on whichever thread reports, so the call it waits for never ends."""
    scene = committed(scenes.cornell_box(0.1))
    grid = solved_grid(scene, 0, rays_per_probe=4, placement_rays=8)
    refusals = []

    def callback(fraction, stage):
        for call in (grid.update, grid.reset):
            try:
                call()
            except RuntimeError as error:
                refusals.append(str(error))

    finishes_in_a_thread(lambda: grid.update(progress=shgi.Progress(callback, min_interval=0.0)),
                         timeout=60.0)
    assert grid.passes == 1
    assert refusals and all("called from inside this grid's running update() or reset()" in
                            message for message in refusals)
    grid.update()  # the grid works on afterwards
    assert grid.passes == 2


def test_lookups_reject_normals_without_direction_and_far_points():
    """A zero normal once made NaN probe indices (a crash); far points overflowed distances."""
    scene = committed(scenes.cornell_box(0.1))
    grid = solved_grid(scene, 1, rays_per_probe=8)
    for field in (grid, grid.field()):
        with pytest.raises(ValueError, match=r"normals\[1\]: \(0, 0, 0\) has no direction"):
            field.irradiance(np.array([[0, 0, 0.5], [0, 0, 0.5]]), np.array([[0, 0, 1.0], [0, 0, 0]]))
        with pytest.raises(ValueError, match="normal: .* has no direction"):
            field.radiance_sh(np.array([0, 0, 0.5]), np.array([1e-30, 0, 0]))
        with pytest.raises(ValueError, match=r"points\[0\]: .* is beyond 1e\+12 m"):
            field.irradiance(np.array([[1e20, 0, 0.5]]), np.array([[0, 0, 1.0]]))


def test_files_round_trip_and_continue(tmp_path):
    scene = committed(scenes.cornell_box(0.05))
    grid = solved_grid(scene, 2, rays_per_probe=32)
    points = np.array([[0.0, 1.0, 0.01], [-0.99, 1.0, 1.0]])
    normals = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
    expected = grid.irradiance(points, normals)

    grid.field().export(str(tmp_path / "grid.json"))
    imported = shgi.ProbeField.import_exr(str(tmp_path / "grid.json"))
    np.testing.assert_array_equal(imported.sh, grid.sh)
    np.testing.assert_array_equal(imported.irradiance(points, normals), expected)
    assert {p.name for p in tmp_path.iterdir()} == {
        "grid.json", "grid_volume0.exr", "grid_volume0_visibility.exr"}
    channels = {c[0] for c in shgi.read_exr_info(str(tmp_path / "grid_volume0.exr"))["channels"]}
    assert {"sh00.R", "sh08.B", "Position.X", "Active.V", "Variance.V"} <= channels

    grid.save(str(tmp_path / "grid.shprobes"))
    assert (tmp_path / "grid.shprobes").stat().st_size < grid.probe_count * (56 + 12 + 1 + 4 + 8 * 64) + 256
    loaded = shgi.ProbeField.load(str(tmp_path / "grid.shprobes"))
    np.testing.assert_allclose(loaded.sh, grid.sh, rtol=2.0 ** -11, atol=2.0 ** -24)
    resumed = shgi.ProbeGrid.from_field(scene, shgi.ProbeGridSettings(rays_per_probe=32), loaded)
    assert resumed.passes == 2
    resumed.update()
    assert resumed.passes == 3
    with pytest.raises(OSError, match="grid.missing"):
        shgi.ProbeField.load(str(tmp_path / "grid.missing"))


def test_bad_paths_and_loose_json_are_refused_by_name(tmp_path):
    """Found by fuzzing: a folder raised a bare RuntimeError, a NUL byte cut the path short
    (naming another file), JSON integers such as version 1.5 or true read as 1, and a save
    renamed its file over a device or FIFO."""
    scene = committed(scenes.cornell_box(0.05))
    field = solved_grid(scene, 1, rays_per_probe=8).field()
    with pytest.raises(OSError, match="is a folder"):
        shgi.ProbeField.import_exr(str(tmp_path))
    with pytest.raises(OSError, match="is a folder"):
        shgi.ProbeField.load(str(tmp_path))
    field.save(str(tmp_path / "grid.shprobes"))
    with pytest.raises(ValueError, match="NUL byte"):
        shgi.ProbeField.load(str(tmp_path / "grid.shprobes") + "\0.other")
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with pytest.raises(OSError, match="not a regular file"):
        field.save(str(fifo))
    with pytest.raises(OSError, match="not a regular file"):
        shgi.ProbeField.load(str(fifo))
    assert fifo.is_fifo()

    field.export(str(tmp_path / "grid.json"))
    original = json.loads((tmp_path / "grid.json").read_text())
    for key, value in [("version", 1.5), ("version", True), ("passes", -1), ("passes", 1.0)]:
        doc = dict(original, **{key: value})
        (tmp_path / "grid.json").write_text(json.dumps(doc))
        with pytest.raises(OSError, match=f"{key} is {json.dumps(value)}; it must be"):
            shgi.ProbeField.import_exr(str(tmp_path / "grid.json"))


def test_an_export_listing_too_many_volumes_is_refused_before_reading_them(tmp_path):
    """Found by fuzzing: a 4 MB JSON listing one small volume 20,000 times made import_exr read
    its EXRs 20,000 times and ask for ~9 GB, where the binary format caps volumes at 4096."""
    scene = committed(scenes.cornell_box(0.05))
    solved_grid(scene, 1, rays_per_probe=8).field().export(str(tmp_path / "grid.json"))
    doc = json.loads((tmp_path / "grid.json").read_text())
    doc["volumes"] = doc["volumes"] * 20000
    (tmp_path / "grid.json").write_text(json.dumps(doc))
    with pytest.raises(OSError, match="volumes holds 20000 volumes; a probe grid has 1..4096"):
        shgi.ProbeField.import_exr(str(tmp_path / "grid.json"))
    with pytest.raises(ValueError, match="ProbeGridSettings.volumes holds 4097 volumes; "
                                         "a probe grid has 1..4096"):
        shgi.ProbeGrid(scene, shgi.ProbeGridSettings(
            volumes=[shgi.ProbeVolume(resolution=(1, 1, 1))] * 4097))


def test_grid_memory_is_capped_before_allocation():
    """Fine visibility maps on many probes asked for ~9 GB and raised a bare MemoryError."""
    scene = committed(scenes.cornell_box(0.05))
    volume = shgi.ProbeVolume(resolution=(128, 128, 64))
    with pytest.raises(ValueError, match="1048576 probes with visibility_resolution 64 need "
                                         ".* GB; the limit is .* lower visibility_resolution"):
        shgi.ProbeGrid(scene, shgi.ProbeGridSettings(volumes=[volume], visibility_resolution=64))


def test_cancel_keeps_the_previous_probes():
    scene = committed(scenes.cornell_box(0.05))
    grid = solved_grid(scene, 1, rays_per_probe=16)
    before = grid.sh.copy()
    progress = shgi.Progress()
    progress.cancel()
    with pytest.raises(shgi.Cancelled):
        grid.update(progress)
    assert grid.passes == 1
    np.testing.assert_array_equal(grid.sh, before)
