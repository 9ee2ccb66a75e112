"""The SHGI engine's live viewport: bpy-free parts here, Blender runs below.

Outside Blender (/usr/bin/python3): the viewport camera read back from Blender's projection
matrices, the frame schedule, the sync plan of depsgraph updates, scene snapshots (build,
compare), the worker thread (its last frame equals one native render of the same view; a moved
object reuses the scene; a view change never cancels a photon pass; a scene change cancels
promptly; a probe grid refines in the background and starts afresh when its irradiance volume
moves) and the lattice overlay's geometry.
Inside Blender: tests/blender/viewport_sync_checks.py (background: which edits read geometry
again, and an incremental export equal to a full one) and tests/blender/viewport_window.py (a
real window under Xvfb: Rendered shading, screenshots, F12, a moved light, the overlay, the
probe grid refining with its probes drawn and restarting when its Irradiance Volume moves).
"""

import importlib.util
import json
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest

import shgi
from shgi.frame_denoise import denoise_frame
from blender_support import (ADDON_DIR, BLENDER_SCRIPTS, REPO_ROOT, needs_window,
                             run_blender, run_in_window)
from latency_clock import LatencyClock

sys.path.insert(0, str(REPO_ROOT / "addon"))
sys.path.insert(0, str(REPO_ROOT / "examples"))

import scenes  # noqa: E402
from shgi_blender import settings  # noqa: E402
from shgi_blender.engine import (  # noqa: E402
    field_spheres, lattice_samples, sync_plan, viewport_camera)
from shgi_blender.engine.viewport_worker import Step, ViewportWorker, frame_schedule  # noqa
from shgi_blender.export import conversions  # noqa: E402
from shgi_blender.export.light_probe import ProbeVolumeRecord  # noqa: E402
from shgi_blender.export.scene_snapshot import (  # noqa: E402
    DIFFERENT, EDITABLE, SAME, InstanceRecord, MaterialTable, SceneSnapshot)


# Projections agree to float32 rounding of pixel coordinates.
PROJECTION_TOLERANCE_PX = 1e-3
# docs/architecture.md: cancel returns within 0.2 s; the worker polls nothing, the native call raises.
CANCEL_LATENCY = 0.5
WORKER_TIMEOUT = 60.0


# --- the viewport camera -----------------------------------------------------------------------

def blender_window_matrix(camera_type, lens, sensor, shift_x, shift_y, near, far, width, height,
                          ortho_scale=1.0):
    """Blender's projection for a horizontal sensor fit: BKE_camera_params_compute_viewplane,
    then perspective_m4 / orthographic_m4 (row-major, as mathutils shows it)."""
    extent = ortho_scale if camera_type == "ORTHO" else sensor * near / lens
    pixel = extent / width
    dx, dy = shift_x * width, shift_y * width
    left, right = (-0.5 * width + dx) * pixel, (0.5 * width + dx) * pixel
    bottom, top = (-0.5 * height + dy) * pixel, (0.5 * height + dy) * pixel
    m = np.zeros((4, 4))
    if camera_type == "ORTHO":
        m[0, 0], m[1, 1], m[2, 2] = 2 / (right - left), 2 / (top - bottom), -2 / (far - near)
        m[0, 3] = -(right + left) / (right - left)
        m[1, 3] = -(top + bottom) / (top - bottom)
        m[2, 3], m[3, 3] = -(far + near) / (far - near), 1.0
    else:
        m[0, 0], m[1, 1] = 2 * near / (right - left), 2 * near / (top - bottom)
        m[0, 2], m[1, 2] = (right + left) / (right - left), (top + bottom) / (top - bottom)
        m[2, 2], m[2, 3], m[3, 2] = -(far + near) / (far - near), -2 * far * near / (far - near), -1
    return m


def region_pixel(window, view, point, width, height):
    """Where Blender draws world point `point` in a width x height region, film convention
    (x right, y down from the top, in pixels)."""
    clip = window @ view @ np.append(point, 1.0)
    ndc = clip[:3] / clip[3]
    return (ndc[0] + 1) / 2 * width, (1 - ndc[1]) / 2 * height


@pytest.mark.parametrize("camera_type, near", [("PERSP", 0.1), ("ORTHO", 0.5), ("ORTHO", -40.0)])
def test_viewport_camera_projects_where_blender_draws(camera_type, near):
    width, height = 161, 97
    world_from_camera = scenes.look_at((1.0, -4.0, 2.0), (0.2, 0.5, 0.8))
    view = np.linalg.inv(world_from_camera)
    window = blender_window_matrix(camera_type, 35.0, 72.0, 0.1, -0.05, near, 60.0, width,
                                   height, ortho_scale=5.0)
    fields = viewport_camera.camera_fields_from_view(view, window, width, height)
    assert fields["type"] == camera_type
    camera = viewport_camera.shgi_camera(shgi, fields)
    rng = np.random.default_rng(3)
    for point in rng.uniform(-1.0, 1.5, size=(20, 3)):
        film = camera.project(tuple(point))
        expected = region_pixel(window, view, point, width, height)
        assert film is not None
        np.testing.assert_allclose(film, expected, atol=PROJECTION_TOLERANCE_PX)
    if camera_type == "ORTHO":  # the eye moved back so that nothing in the clip range is lost
        assert fields["clip_start"] >= 0.0
        assert fields["clip_end"] - fields["clip_start"] == pytest.approx(60.0 - near)


def test_a_clip_range_deeper_than_float32_keeps_a_finite_far_clip():
    """Camera view of a 10 m lens clipping 1e-6 .. 1e6 m: in Blender's float32 projection the
    far clip is lost (W[2][2] rounds to -1, the formula gives -inf); the view clips at
    MAX_CLIP_END instead and still projects where Blender draws."""
    width, height = 64, 48
    world_from_camera = scenes.look_at((1.0, -4.0, 2.0), (0.2, 0.5, 0.8))
    view = np.linalg.inv(world_from_camera).astype(np.float32)
    window = blender_window_matrix("PERSP", 1e4, 36.0, 0.0, 0.0, 1e-6, 1e6, width,
                                   height).astype(np.float32)
    assert window[2, 2] == -1.0  # the depth range is gone
    fields = viewport_camera.camera_fields_from_view(view, window, width, height)
    assert fields["clip_end"] == viewport_camera.MAX_CLIP_END
    assert 0.0 < fields["clip_start"] < fields["clip_end"]
    assert fields["lens"] == pytest.approx(1e4, rel=1e-6)
    camera = viewport_camera.shgi_camera(shgi, fields)  # the native checks accept it
    target = np.array([0.2, 0.5, 0.8])
    film = camera.project(tuple(target))
    np.testing.assert_allclose(film, region_pixel(window.astype(np.float64), view, target,
                                                  width, height), atol=PROJECTION_TOLERANCE_PX)


def test_camera_view_of_a_scene_camera_is_that_camera():
    """A viewport showing exactly the camera frame renders what F12 renders."""
    fields = conversions.camera_fields(
        "PERSP", scenes.look_at((0, -3.6, 1), (0, 1, 1)), lens=50.0, sensor_width=36.0,
        sensor_height=24.0, sensor_fit="AUTO", ortho_scale=7.0, shift_x=0.05, shift_y=0.02,
        clip_start=0.1, clip_end=100.0, resolution_x=120, resolution_y=90,
        resolution_percentage=100)
    f12 = shgi.Camera(**fields)
    window = blender_window_matrix("PERSP", 50.0, 36.0, 0.05, 0.02, 0.1, 100.0, 120, 90)
    view = np.linalg.inv(fields["world_from_camera"])
    viewport = viewport_camera.shgi_camera(
        shgi, viewport_camera.camera_fields_from_view(view, window, 120, 90))
    for x, y in ((0.5, 0.5), (60.0, 45.0), (119.5, 3.25)):
        origin, direction, _, _ = f12.generate_ray(x, y)
        origin_v, direction_v, _, _ = viewport.generate_ray(x, y)
        np.testing.assert_allclose(origin_v, origin, atol=1e-5)
        np.testing.assert_allclose(direction_v, direction, atol=1e-5)


def test_reduced_views_keep_the_horizontal_extent():
    fields = {"resolution_x": 530, "resolution_y": 301, "lens": 20.0}
    quarter = viewport_camera.scaled_fields(fields, 4)
    assert (quarter["resolution_x"], quarter["resolution_y"]) == (132, 75)
    assert quarter["lens"] == 20.0 and fields["resolution_x"] == 530
    assert viewport_camera.scaled_fields({"resolution_x": 3, "resolution_y": 2}, 4)[
        "resolution_y"] == 1


# --- the frame schedule and the sync plan ------------------------------------------------------

def test_frame_schedule_low_resolution_first():
    lattice = frame_schedule(True, 64, 1, passes_done=0)
    assert lattice == [Step("direct", 4), Step("solve"), Step("frame", 4), Step("frame", 2),
                       Step("samples", 1, 64)]
    # A view change keeps the solved lattice: no direct-only frame, no solve.
    assert frame_schedule(True, 64, 1, passes_done=1) == lattice[2:]
    more_passes = frame_schedule(True, 8, 3, passes_done=0)
    assert [s.kind for s in more_passes].count("solve") == 3
    assert frame_schedule(False, 8, 3, passes_done=0) == [
        Step("frame", 4), Step("frame", 2), Step("samples", 1, 8)]


def record(kind, name, **flags):
    return sync_plan.UpdateRecord(kind=kind, name=name, **flags)


def test_sync_plan_drops_only_what_changed():
    moved = sync_plan.plan_updates([record("OBJECT", "Cube", transform=True,
                                           object_type="MESH", data_name="CubeMesh")])
    assert not moved.geometry and not moved.material_names and not moved.world
    edited = sync_plan.plan_updates([
        record("OBJECT", "Cube", geometry=True, shading=True, object_type="MESH",
               data_name="CubeMesh"),
        record("MESH", "CubeMesh", geometry=True, transform=True, shading=True)])
    assert edited.geometry_names == {"Cube", "CubeMesh"}
    light = sync_plan.plan_updates([record("OBJECT", "Light", geometry=True,
                                           object_type="LIGHT", data_name="Light"),
                                    record("LIGHT", "Light", geometry=True)])
    assert not light.geometry and not light.all_materials
    material = sync_plan.plan_updates([record("MATERIAL", "white", shading=True),
                                       record("NODETREE", "Shader Nodetree", embedded=True)])
    assert material.material_names == {"white"} and not material.all_materials
    group = sync_plan.plan_updates([record("NODETREE", "NodeGroup")])
    assert group.all_materials and group.world and not group.geometry
    world = sync_plan.plan_updates([record("WORLD", "World", shading=True)])
    assert world.world and not world.all_materials
    assert sync_plan.full_plan().geometry


# --- snapshots and the worker ------------------------------------------------------------------

def snapshot_of(scene):
    """A SceneSnapshot of a scripted shgi.Scene (what the viewport's export records)."""
    table = MaterialTable()
    for material in scene.materials:
        table.add_material(material)
    snapshot = SceneSnapshot(table)
    for mesh in scene.meshes:
        snapshot.add_mesh(mesh)
    for instance in scene.instances:
        snapshot.add_instance(instance.mesh_id, instance.world_from_object, instance.name)
    for light in scene.lights:
        snapshot.add_light(light)
    snapshot.set_world(scene.world)
    return snapshot.freeze()


def moved(snapshot, index, offset):
    """A copy of `snapshot` (same meshes and materials) with instance `index` translated."""
    table = MaterialTable()
    table.materials, table.textures = list(snapshot.materials), list(snapshot.textures)
    copy = SceneSnapshot(table)
    copy.meshes, copy.lights, copy.world = snapshot.meshes, snapshot.lights, snapshot.world
    copy.instances = list(snapshot.instances)
    instance = snapshot.instances[index]
    matrix = instance.world_from_object.copy()
    matrix[:3, 3] += offset
    copy.instances[index] = InstanceRecord(instance.mesh_id, matrix, instance.name)
    return copy.freeze()


def view_of(scene, width, height):
    camera = scene.camera
    return {"type": "PERSP", "lens": camera.lens, "sensor_width": camera.sensor_width,
            "sensor_fit": "HORIZONTAL", "shift_x": 0.0, "shift_y": 0.0,
            "clip_start": camera.clip_start, "clip_end": camera.clip_end,
            "resolution_x": width, "resolution_y": height,
            "world_from_camera": np.asarray(camera.world_from_camera, np.float64)}


def properties(photon_lattice=None, probe_grid=None, **overrides):
    """render_property_values of scene.shgi's defaults (method PHOTON_LATTICE, frames not
    denoised unless asked), `overrides` set and the method groups' values overridden from the
    dicts of their names."""
    props = settings.default_properties(shgi, **dict(
        {"method": "PHOTON_LATTICE", "use_viewport_denoising": False}, **overrides))
    for group, values in (("photon_lattice", photon_lattice), ("probe_grid", probe_grid)):
        for name, value in (values or {}).items():
            setattr(getattr(props, group), name, value)
    return settings.render_property_values(props)


def wait_for(predicate, timeout=WORKER_TIMEOUT):
    deadline = time.perf_counter() + timeout
    while not predicate():
        assert time.perf_counter() < deadline, "timed out"
        time.sleep(0.005)


def final_frame(worker, samples, after=0):
    wait_for(lambda: (worker.latest_frame() is not None and worker.latest_frame().frame_id > after
                      and worker.latest_frame().divisor == 1
                      and worker.latest_frame().samples == samples) or worker.error)
    assert worker.error is None, worker.error
    return worker.latest_frame()


def test_snapshot_builds_the_scene_and_tells_transforms_apart():
    scene = scenes.cornell_box(0.1).scene
    snapshot = snapshot_of(scene)
    built, warnings = snapshot.build()
    built.commit()
    assert warnings == [] and built.stats()["triangles"] == scene.stats()["triangles"]
    assert snapshot.compare(snapshot_of(scene)) == DIFFERENT  # other meshes (copies)
    assert snapshot.compare(snapshot) == SAME
    assert moved(snapshot, 5, (0.1, 0, 0)).compare(snapshot) == EDITABLE
    assert moved(snapshot, 5, (0.1, 0, 0)).moved_instances(snapshot) == [5]
    dusk = moved(snapshot, 5, (0, 0, 0))
    dusk.world = shgi.World(color=(0.2, 0.1, 0.05), strength=0.5)
    assert dusk.compare(snapshot) == EDITABLE and dusk.moved_instances(snapshot) == []
    brighter = moved(snapshot, 5, (0, 0, 0))
    light = shgi.Light(**{name: getattr(scene.lights[0], name) for name in (
        "type", "shape", "size_x", "size_y", "color", "world_from_light")}, power=120.0)
    brighter.lights = [light]
    assert brighter.compare(snapshot) == EDITABLE and brighter.lights_differ(snapshot)
    assert not brighter.moved_instances(snapshot)


def test_snapshot_build_skips_what_native_checks_refuse():
    snapshot = snapshot_of(scenes.cornell_box(0.1).scene)
    singular = np.diag([1.0, 0.0, 1.0, 1.0])
    snapshot.add_instance(0, singular, "flat")
    scene, warnings = snapshot.build()
    assert len(scene.instances) == len(snapshot.instances) - 1
    assert len(warnings) == 1 and "'flat'" in warnings[0] and "singular" in warnings[0]


@pytest.mark.parametrize("method", ["PHOTON_LATTICE", "PATH_TRACE"])
def test_worker_ends_with_the_image_of_one_native_render(method):
    scene = scenes.cornell_box(0.1).scene
    view = view_of(scene, 40, 30)
    props = properties(method=method, viewport_samples=6, seed=2,
                       photon_lattice={"photons": 20000})
    worker = ViewportWorker(shgi)
    try:
        assert worker.request(snapshot_of(scene), view, props)
        frame = final_frame(worker, 6)
    finally:
        worker.stop()
    assert not worker.running
    if method == "PHOTON_LATTICE":  # read through a final gather, the lattice's default
        assert settings.preview_settings(settings.properties_from_values(props),
                                         shgi).final_gather
    expected = script_frame(scene, view, props, 6)
    np.testing.assert_array_equal(frame.pixels, expected["Combined"][::-1])


def script_frame(scene, view, props, samples):
    """The passes a script renders of `view` with the viewport's render properties `props`
    (render_property_values) at `samples` per pixel: the path tracer, or a solved lattice."""
    scene.set_camera(viewport_camera.shgi_camera(shgi, view))
    scene.commit()
    values = SimpleNamespace(**dict(settings.properties_from_values(props).__dict__,
                                    samples=samples))
    if values.method == "PATH_TRACE":
        return shgi.render_path_traced(scene, settings.path_tracer_settings(values, shgi))
    lattice = shgi.PhotonLattice(scene, settings.photon_lattice_settings(values, shgi))
    lattice.solve()
    passes, _ = shgi.render_preview(scene, lattice, settings.preview_settings(values, shgi))
    return passes


@pytest.mark.skipif(importlib.util.find_spec("pyoidn") is None, reason="needs pyoidn")
@pytest.mark.parametrize("method", ["PHOTON_LATTICE", "PATH_TRACE"])
def test_worker_denoises_its_frames_as_a_script_would(method):
    """With viewport denoising on, each frame from the start sample on is the renderer's frame
    denoised by shgi.frame_denoise with the viewport's choices (the renderer then also sums the
    guides); before the start sample frames stay noisy."""
    scene = scenes.cornell_box(0.1).scene
    view = view_of(scene, 40, 30)
    props = properties(method=method, viewport_samples=6, seed=2, use_viewport_denoising=True,
                       viewport_denoising_start_sample=2, photon_lattice={"photons": 20000})
    values = settings.properties_from_values(props)
    denoising = settings.denoising(values, viewport=True)
    assert (denoising.guides, denoising.prefilter, denoising.quality) == (
        "ALBEDO", "FAST", "BALANCED")  # Cycles' viewport defaults
    worker = ViewportWorker(shgi)
    try:
        assert worker.request(snapshot_of(scene), view, props)
        frame = final_frame(worker, 6)
        status = worker.status
    finally:
        worker.stop()
    assert "not denoised" not in status
    noisy = script_frame(scene, view, props, 6)
    expected = denoise_frame(noisy, denoising.quality, denoising.prefilter, denoising.guides,
                             samples=6, pixel_filter=denoising.pixel_filter,
                             filter_width=denoising.filter_width)
    assert not np.array_equal(expected["Combined"], noisy["Combined"])
    np.testing.assert_array_equal(frame.pixels, expected["Combined"][::-1])


def test_worker_without_pyoidn_shows_noisy_frames_and_says_why(monkeypatch):
    monkeypatch.setitem(sys.modules, "pyoidn", None)  # `import pyoidn` raises ImportError
    scene = scenes.cornell_box(0.1).scene
    view = view_of(scene, 24, 24)
    props = properties(method="PATH_TRACE", viewport_samples=2, use_viewport_denoising=True)
    worker = ViewportWorker(shgi)
    try:
        worker.request(snapshot_of(scene), view, props)
        frame = final_frame(worker, 2)
        status = worker.status
    finally:
        worker.stop()
    assert "not denoised" in status and "pyoidn" in status, status
    assert np.isfinite(frame.pixels).all() and frame.pixels[..., :3].mean() > 0.0


def test_worker_stops_refining_at_its_time_limit():
    """Asked for 10^6 samples with a Viewport Time Limit, the worker stops its rounds once the
    limit passed and says so; the last frame it published holds the samples done."""
    scene = scenes.cornell_box(0.1).scene
    props = properties(method="PATH_TRACE", viewport_samples=10 ** 6, viewport_time_limit=0.3)
    worker = ViewportWorker(shgi)
    try:
        worker.request(snapshot_of(scene), view_of(scene, 24, 24), props)
        wait_for(lambda: worker.status.startswith("Done") or worker.error)
        assert worker.error is None, worker.error
        status, frame = worker.status, worker.latest_frame()
    finally:
        worker.stop()
    assert status == f"Done, time limit at {frame.samples} samples", status
    assert frame.divisor == 1 and 1 <= frame.samples < 10 ** 6


def test_worker_edits_the_scene_in_place_and_ignores_equal_requests():
    scene = scenes.cornell_box(0.1).scene
    view, props = view_of(scene, 24, 24), properties(viewport_samples=2,
                                                    photon_lattice={"photons": 10000})
    snapshot = snapshot_of(scene)
    worker = ViewportWorker(shgi)
    try:
        worker.request(snapshot, view, props)
        first = final_frame(worker, 2)
        # The same scene exported again (new snapshot, same content): nothing restarts.
        again = moved(snapshot, 0, (0, 0, 0))
        assert not worker.request(again, dict(view), props)
        shifted = moved(snapshot, 6, (0.15, 0.0, 0.0))
        assert worker.request(shifted, view, props)
        second = final_frame(worker, 2, after=first.frame_id)
        sky = moved(shifted, 6, (0.0, 0.0, 0.0))
        sky.world = shgi.World(color=(0.3, 0.4, 0.6), strength=1.0)
        assert worker.request(sky, view, props)
        third = final_frame(worker, 2, after=second.frame_id)
        counters = dict(worker.counters)
    finally:
        worker.stop()
    assert counters["scene_builds"] == 1 and counters["in_place_updates"] == 2
    assert counters["solves"] == 3  # a moved block or another world changes the lattice
    assert not np.array_equal(first.pixels, second.pixels)
    assert third.pixels[..., :3].mean() > second.pixels[..., :3].mean()  # the sky lights it


def with_volume(snapshot, centre_z):
    """A copy of `snapshot` (same scene content) whose one irradiance volume, 3 x 3 x 3 probes
    in a 1.6 m cube, is centred at (0, 1, centre_z)."""
    copy = moved(snapshot, 0, (0, 0, 0))
    matrix = np.array([[0.8, 0, 0, 0], [0, 0.8, 0, 1.0], [0, 0, 0.8, centre_z], [0, 0, 0, 1]],
                      np.float32)
    copy.probe_volumes = (ProbeVolumeRecord(matrix, (3, 3, 3), "volume"),)
    return copy


def test_probe_grid_refines_in_the_background_and_restarts_when_its_volume_moves():
    """The viewport's probe grid runs probe_grid.viewport_passes updates, a frame after each, and
    ends with the image of that grid; moving the volume keeps the scene but places new probes."""
    scene = scenes.cornell_box(0.1).scene
    view = view_of(scene, 24, 24)
    snapshot = with_volume(snapshot_of(scene), 1.0)
    props = properties(method="PROBE_GRID", viewport_samples=2, seed=2,
                       probe_grid={"rays_per_probe": 16, "viewport_passes": 3})
    worker = ViewportWorker(shgi)
    try:
        worker.request(snapshot, view, props)
        first = final_frame(worker, 2)
        after_first = dict(worker.counters)
        raised = with_volume(snapshot, 1.1)
        assert worker.request(raised, view, props)
        second = final_frame(worker, 2, after=first.frame_id)
        counters = dict(worker.counters)
    finally:
        worker.stop()
    assert after_first["solves"] == 3 and after_first["frames"] >= 3 + 2
    assert counters["solves"] == 6 and counters["scene_builds"] == 1
    scene.set_camera(viewport_camera.shgi_camera(shgi, view))
    scene.commit()
    volume = shgi.ProbeVolume(world_from_volume=raised.probe_volumes[0].world_from_volume,
                              resolution=(3, 3, 3))
    grid = shgi.ProbeGrid(scene, settings.probe_grid_settings(
        settings.properties_from_values(props), shgi, [volume]))
    for _ in range(3):
        grid.update()
    values = settings.properties_from_values(props)
    expected, _ = shgi.render_preview(scene, grid.field(), settings.preview_settings(
        SimpleNamespace(**dict(values.__dict__, samples=2)), shgi))
    np.testing.assert_array_equal(second.pixels, expected["Combined"][::-1])
    assert not np.array_equal(first.pixels, second.pixels)


def test_propagation_cascades_follow_the_view_without_a_new_solve():
    """With cascades the light propagation volume's finer level follows the view as the artist
    navigates: a view 14 m along the hall moves that level (PropagationVolume.recenter) without
    a new solve, and the frame is the one of a volume built around that view from the start."""
    scene = scenes.hall(0.25).scene
    view, snapshot = view_of(scene, 24, 16), snapshot_of(scene)
    props = settings.default_properties(shgi, method="PROPAGATION", use_viewport_denoising=False,
                                        viewport_samples=2)
    for name, value in (("cascades", 2), ("resolution", 16), ("photons", 20000), ("steps", 4)):
        setattr(props.propagation, name, value)
    props = settings.render_property_values(props)
    worker = ViewportWorker(shgi)
    try:
        worker.request(snapshot, view, props)
        first = final_frame(worker, 2)
        assert worker.counters["recentres"] == 0
        along = dict(view, world_from_camera=scenes.look_at((10.0, -3.5, 1.5), (10.0, 4.0, 1.0)))
        assert worker.request(snapshot, along, props)
        second = final_frame(worker, 2, after=first.frame_id)
        counters = dict(worker.counters)
    finally:
        worker.stop()
    assert counters["solves"] == 1 and counters["recentres"] == 1
    assert counters["scene_builds"] == 1
    built, _ = snapshot.build()
    built.set_camera(viewport_camera.shgi_camera(shgi, along))
    built.commit()
    values = settings.properties_from_values(props)
    volume = shgi.PropagationVolume(built, settings.propagation_settings(values, shgi))
    volume.refine()
    expected, _ = shgi.render_preview(built, volume.current_field(), settings.preview_settings(
        SimpleNamespace(**dict(values.__dict__, samples=2)), shgi))
    np.testing.assert_array_equal(second.pixels, expected["Combined"][::-1])


def test_a_view_change_keeps_the_photon_pass_and_a_scene_change_cancels_it():
    scene = scenes.cornell_box(0.25).scene
    view, snapshot = view_of(scene, 24, 24), snapshot_of(scene)
    slow = properties(viewport_samples=1, photon_lattice={"photons": 3_000_000})
    worker = ViewportWorker(shgi)
    try:
        worker.request(snapshot, view, slow)
        wait_for(lambda: worker.status.startswith("Tracing photons"))
        turned = dict(view, world_from_camera=scenes.look_at((0.3, -3.6, 1.0), (0, 1, 1)))
        worker.request(snapshot, turned, slow)
        final_frame(worker, 1)
        assert worker.counters["solves"] == 1  # the pass in flight was not thrown away
        endless = properties(viewport_samples=1, photon_lattice={"photons": 200_000_000})
        worker.request(moved(snapshot, 6, (0.1, 0, 0)), turned, endless)
        wait_for(lambda: worker.status.startswith("Tracing photons"))
        time.sleep(0.2)  # well inside the pass
        assert worker.status.startswith("Tracing photons")
        clock = LatencyClock()
        worker.request(moved(snapshot, 6, (0.2, 0, 0)), turned, slow)
        wait_for(lambda: not worker.status.startswith("Tracing photons"), timeout=5.0)
        latency = clock.read()
    finally:
        worker.stop()
    assert latency.seconds < CANCEL_LATENCY, str(latency)


# --- the lattice overlay -----------------------------------------------------------------------

def test_lattice_grid_and_surface_cells():
    origin, cell, dims = lattice_samples.lattice_grid((0, 0, 0), (4, 1, 1), 8)
    assert cell == 0.5 and tuple(dims) == (8, 2, 2)
    np.testing.assert_allclose(origin, (0, 0, 0))
    # One big floor quad of 2 x 2 m at resolution 4 (cells of 0.5 m) over bounds 2 x 2 x 1:
    # every cell of the bottom layer holds surface, none above.
    table = MaterialTable()
    snapshot = SceneSnapshot(table)
    quad = shgi.Mesh(positions=np.array([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0]], np.float32),
                     triangles=np.array([[0, 1, 2], [0, 2, 3]]))
    snapshot.add_instance(snapshot.add_mesh(quad), np.eye(4), "floor")
    centres, cell = lattice_samples.surface_cell_centres(snapshot, ((0, 0, 0), (2, 2, 1)), 4)
    assert cell == 0.5 and len(centres) == 16
    np.testing.assert_allclose(centres[:, 2], 0.25)


def test_icosphere_faces_outwards_and_ambient_cube_weights_sum_to_one():
    vertices, faces = field_spheres.icosphere(1)
    assert vertices.shape == (42, 3) and faces.shape == (80, 3)
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    assert (np.einsum("ij,ij->i", np.cross(b - a, c - a), a + b + c) > 0).all()
    weights = field_spheres.ambient_cube_weights(vertices)
    np.testing.assert_allclose(weights.sum(axis=1), 1.0, rtol=1e-5)


def test_lattice_overlay_shades_spheres_by_irradiance():
    scene = scenes.cornell_box(0.1).scene
    scene.commit()
    lattice = shgi.PhotonLattice(scene, shgi.PhotonLatticeSettings(photons=20000, seed=1))
    lattice.solve()
    overlay = lattice_samples.lattice_overlay(lattice, snapshot_of(scene), scene, 8)
    spheres = len(overlay.centres)
    assert spheres > 0 and overlay.positions.shape == (spheres * 42, 3)
    assert overlay.indices.max() == len(overlay.positions) - 1
    # The six irradiances are the lattice's, towards the six axes.
    expected = lattice.irradiance(overlay.centres[:1].repeat(6, 0), field_spheres.AXES)
    np.testing.assert_allclose(overlay.irradiance[0], expected, rtol=1e-6)
    assert 0.0 < overlay.colors[:, :3].mean() < 1.0 and (overlay.colors[:, 3] == 1).all()


# --- inside Blender ----------------------------------------------------------------------------

def test_viewport_sync_in_blender(blender, build_python_dir, tmp_path):
    out = tmp_path / "viewport_sync.json"
    result = run_blender(BLENDER_SCRIPTS / "viewport_sync_checks.py", build_python_dir,
                         ADDON_DIR, out, blender=blender, timeout=300)
    log = result.stdout[-6000:] + result.stderr[-3000:]
    assert result.returncode == 0 and "VIEWPORT_SYNC_OK" in result.stdout, log
    results = json.loads(out.read_text())
    for edit in ("move object", "move light", "light power", "material colour", "world colour",
                 "select"):
        assert results[edit]["meshes_read"] == 0, (edit, results[edit])
    # Blender flags the mesh's geometry when a slot gets another material.
    for edit in ("edit mesh", "add modifier", "assign material"):
        assert results[edit]["meshes_read"] == 1, (edit, results[edit])
    assert results["move object"]["change"] == EDITABLE
    assert results["world colour"]["change"] == EDITABLE
    assert results["select"]["change"] == SAME
    assert results["material colour"]["materials_converted"] == 1


# Viewport against F12 inside the camera border (8 x 8 blocks, sRGB display values). Both
# render the same photon lattice (same seed and photons, one pass: the same solution bit for bit)
# with 16 samples, so they differ only by pixel noise and resampling (the viewport's frame is
# ~3.4x F12's 128 pixels): a block averages >= 4096 F12 samples (~1% noise) and a one-pixel
# shift of an edge inside a 16-pixel block moves its mean by ~2% of the edge's contrast.
# Measured on this machine: mean -1.2%, largest block difference 0.023.
VIEWPORT_MEAN_TOLERANCE = 0.05
VIEWPORT_BLOCK_TOLERANCE = 0.05
# The light moves from the left third to the right third: each third changes by ~30-50%.
LIGHT_MOVE_CHANGE = 0.15
WINDOW = (640, 520)


@needs_window
def test_viewport_in_a_window(build_python_dir, tmp_path):
    out = tmp_path / "viewport_window.json"
    result = run_in_window("viewport_window.py", WINDOW, build_python_dir, ADDON_DIR, out)
    log = result.stdout[-6000:] + result.stderr[-3000:]
    assert result.returncode == 0 and "VIEWPORT_WINDOW_OK" in result.stdout, log
    r = json.loads(out.read_text())
    for kind, error in r["alignment_px"].items():
        assert error < 0.01, (kind, error)
    divisors = [frame[0] for frame in r["frames_before_move"]]
    assert divisors[0] > 1 and divisors[-1] == 1 and divisors == sorted(divisors, reverse=True)
    assert r["viewport_mean"] > 0.1, "the viewport is black"
    assert abs(r["viewport_mean"] / r["f12_mean"] - 1.0) < VIEWPORT_MEAN_TOLERANCE, r
    assert r["block_max_abs_diff"] < VIEWPORT_BLOCK_TOLERANCE, r
    (left0, _, right0), (left1, _, right1) = r["thirds_before"], r["thirds_after"]
    assert left1 < left0 * (1 - LIGHT_MOVE_CHANGE) and right1 > right0 * (1 + LIGHT_MOVE_CHANGE)
    assert r["move_sync"]["meshes_read"] == 0
    assert r["move_sync"]["change"] == EDITABLE  # a moved light: set_lights, no BVH build
    assert r["block_move_sync"]["change"] == EDITABLE
    assert r["block_move_sync"]["meshes_read"] == 0
    # The light's move and the block's, each edited in place on the one scene built first.
    assert r["block_move_sync"]["worker"]["in_place_updates"] == 2
    assert r["block_move_sync"]["worker"]["scene_builds"] == 1
    assert r["overlay"]["spheres"] > 100 and r["overlay"]["changed_inside"] > 0.01
    assert r["path_trace_mean"] > 0.1
    probes = r["probe_grid"]
    assert probes["passes"] == 3 and probes["mean"] > 0.1, probes
    assert probes["overlay_spheres"] == probes["active"] > 0, probes
    for step, z in (("added", 1.0), ("moved", 1.1)):  # each edit of the volume: a new grid
        assert probes[step]["probes"] == 4 * 3 * 3 and probes[step]["new_grid"], probes
        assert probes[step]["passes"] == 3 and abs(probes[step]["volume_z"] - z) < 1e-5
    assert r["sessions_after_solid"] == 0


def test_light_and_material_edits_restart_the_viewport_without_a_bvh_build():
    """A light's power and a material's colour change in the viewport: the worker edits its
    scene in place, builds no BVH, and renders the edited scene exactly as a scene built from
    the edited snapshot renders it."""
    scene = scenes.cornell_box(0.1).scene
    view, props = view_of(scene, 24, 24), properties(method="PATH_TRACE", viewport_samples=2)
    snapshot = snapshot_of(scene)
    worker = ViewportWorker(shgi)
    try:
        worker.request(snapshot, view, props)
        first = final_frame(worker, 2)
        builds = worker._scene.stats()["bvh_builds"]
        edited = moved(snapshot, 0, (0, 0, 0))
        light = scene.lights[0]
        brighter = shgi.Light(**{name: getattr(light, name) for name in (
            "type", "shape", "size_x", "size_y", "color", "world_from_light")},
            power=4.0 * light.power)
        edited.lights = [brighter]
        red = edited.materials[0]
        table = MaterialTable()
        table.materials, table.textures = list(edited.materials), list(edited.textures)
        table.set_material(0, shgi.Material(name=red.name, base_color=(0.9, 0.1, 0.1)))
        edited._table, edited._frozen = table, None
        edited.freeze()
        assert edited.compare(snapshot) == EDITABLE
        assert worker.request(edited, view, props)
        second = final_frame(worker, 2, after=first.frame_id)
        counters = dict(worker.counters)
        after_builds = worker._scene.stats()["bvh_builds"]
    finally:
        worker.stop()
    assert counters["scene_builds"] == 1 and counters["in_place_updates"] == 1
    assert after_builds == builds
    rebuilt, _ = edited.build()
    rebuilt.set_camera(viewport_camera.shgi_camera(shgi, view))
    rebuilt.commit()
    expected = shgi.render_path_traced(rebuilt, settings.path_tracer_settings(
        SimpleNamespace(**dict(SimpleNamespace(**dict(props)).__dict__, samples=2)), shgi))
    np.testing.assert_array_equal(second.pixels, expected["Combined"][::-1])
    assert second.pixels[..., :3].mean() > 1.1 * first.pixels[..., :3].mean()  # 4x the lamp
