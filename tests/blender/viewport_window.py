"""The live viewport in a real window: Rendered shading with the SHGI engine.

Runs Blender with a window under Xvfb (Mesa's software OpenGL), not in background mode:

    xvfb-run -a -s "-screen 0 800x600x24" blender --factory-startup \
        --window-geometry 0 0 <W> <H> --python tests/blender/viewport_window.py -- \
        <build python dir> <addon dir> <results json>

The script only registers a timer; the steps run from it on Blender's main thread while the
event loop draws the window. It builds the project's Cornell box (its ceiling light moved to the
left), turns the 3D view into the camera view in Rendered shading with the SHGI engine and
PHOTON_LATTICE, and then:
1. checks that the viewport's camera projects world points where Blender's own matrices do
   (free perspective, orthographic and camera views);
2. waits until the viewport has accumulated every sample, takes a screenshot and checks it is
   not black and that the frames came low resolution first;
3. renders the same camera with F12 (same settings and seed) and compares the screenshot inside
   the camera border with it, in 8 x 8 blocks after the same view transform (Standard, sRGB);
4. moves the light to the right: the sync must read no geometry, and the new screenshot must
   be darker on the left and brighter on the right;
5. turns the lattice overlay on and checks that it drew spheres into the screenshot;
6. switches to PATH_TRACE (a few samples: the image is not black);
7. switches to PROBE_GRID with the probe overlay on: the grid refines in the background (a
   frame per update pass), the overlay draws its probes; then an Irradiance Volume object is
   added and moved, and each time the worker starts a new grid with the object's probes;
8. leaves Rendered shading and checks that the viewport session ended with its engine.
Results go to the JSON file; tests/python/test_blender_viewport.py asserts the figures. A
failed step writes its error there and exits Blender with 1 (exceptions in timers do not).
"""

import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()
sys.path.insert(0, str(setup.REPO_ROOT / "examples"))

import bpy  # noqa: E402
import numpy as np  # noqa: E402
from bpy_extras import view3d_utils  # noqa: E402
from mathutils import Matrix, Vector  # noqa: E402

STEP_SECONDS = 0.25
CONVERGE_TIMEOUT_SECONDS = 120.0
SCALE = 0.5                    # F12 at 128 x 128 pixels
SAMPLES = 16                   # viewport and F12 samples per pixel
PHOTONS = 100_000
SEED = 1
LIGHT_X = (-0.6, 0.6)          # the ceiling light, before and after the move
BLOCKS = 8                     # comparison blocks per side of the camera frame
BORDER_INSET = 2               # pixels left out along the camera border (its anti-aliased edge)
PATH_TRACE_SAMPLES = 4
PROBE_SAMPLES = 4              # viewport samples of the probe grid step
PROBE_PASSES = 3               # its background update passes
PROBE_VOLUME_RESOLUTION = (4, 3, 3)
BLOCK_NUDGE = 0.1              # m the short block moves along X
# Everything the viewport's overlays draw besides draw handlers (the grid, axes, texts...).
OTHER_OVERLAYS = ("show_floor", "show_axis_x", "show_axis_y", "show_axis_z", "show_text",
                  "show_cursor", "show_extras", "show_object_origins", "show_outline_selected",
                  "show_relationship_lines", "show_bones", "show_stats", "show_annotation")
OVERLAY_CHANGE = 0.05          # display-value change that counts as a drawn overlay pixel
OVERLAY_TIMEOUT_SECONDS = 30.0
SESSION_END_TIMEOUT_SECONDS = 10.0
RESULTS_PATH = setup.results_path("shgi_viewport_window.json")  # screenshots go beside it

RESULTS = {}


# --- the scene and the view -------------------------------------------------------------------

def build_scene():
    """The Cornell box in the startup file's scene, light on the left, SHGI at SAMPLES."""
    import blender_scenes

    setup.clear_scene()
    scene = bpy.context.scene
    blender_scenes.cornell_box(SCALE)
    light = bpy.data.objects["ceiling_light"]
    light.location.x = LIGHT_X[0]
    scene.render.engine = "SHGI"
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    setup.use_multilayer_exr(scene.render.image_settings)
    props = scene.shgi
    props.method = "PHOTON_LATTICE"
    props.samples = props.viewport_samples = SAMPLES
    props.photon_lattice.photons = PHOTONS
    props.seed = SEED
    return scene


def view3d():
    """(window, area, region, space) of the 3D view."""
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, area, region, area.spaces.active


def set_up_view():
    """Camera view of the whole camera frame, nothing drawn over the render."""
    window, area, region, space = view3d()
    for name in ("show_region_toolbar", "show_region_ui", "show_region_header",
                 "show_region_tool_header", "show_gizmo"):
        if hasattr(space, name):
            setattr(space, name, False)
    space.overlay.show_overlays = False
    space.region_3d.view_perspective = "CAMERA"
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.view3d.view_center_camera()


def session():
    from shgi_blender.engine import viewport
    sessions = viewport.sessions()
    return sessions[0] if sessions else None


def wait_for_samples(samples, timeout, since=0):
    """Yields until the session's newest frame (id > since) holds `samples` at full resolution;
    returns the frames seen as (divisor, samples) in order."""
    seen, start = [], time.perf_counter()
    while True:
        current = session()
        frame = current.worker.latest_frame() if current is not None else None
        if frame is not None and frame.frame_id > since:
            if not seen or seen[-1][2] != frame.frame_id:
                seen.append((frame.divisor, frame.samples, frame.frame_id))
            if frame.divisor == 1 and frame.samples >= samples \
                    and current.drawn_frame_id == frame.frame_id:
                return seen, time.perf_counter() - start
        if time.perf_counter() - start > timeout:
            raise AssertionError(f"the viewport did not reach {samples} samples in {timeout} s: "
                                 f"frames {seen}, status {current and current.worker.status!r}, "
                                 f"error {current and current.worker.error}")
        yield STEP_SECONDS


# --- screenshots -------------------------------------------------------------------------------

def screenshot(name):
    """The 3D view's region as float RGB (H, W, 3) display values, row 0 at the bottom."""
    window, _area, region, _space = view3d()
    path = os.path.join(os.path.dirname(RESULTS_PATH), f"viewport_{name}.png")
    with bpy.context.temp_override(window=window):
        bpy.ops.screen.screenshot(filepath=path)
    image = bpy.data.images.load(path)
    try:
        width, height = image.size
        pixels = np.empty(width * height * 4, np.float32)
        image.pixels.foreach_get(pixels)
    finally:
        bpy.data.images.remove(image)
    pixels = pixels.reshape(height, width, 4)[..., :3]
    RESULTS.setdefault("screenshots", {})[name] = path
    return pixels[region.y:region.y + region.height, region.x:region.x + region.width]


def camera_border(scene):
    """(x0, y0, x1, y1) region pixels of the camera frame (y from the bottom)."""
    _window, _area, region, space = view3d()
    camera = scene.camera
    corners = [camera.matrix_world @ corner for corner in camera.data.view_frame(scene=scene)]
    points = [view3d_utils.location_3d_to_region_2d(region, space.region_3d, corner)
              for corner in corners]
    xs, ys = [p.x for p in points], [p.y for p in points]
    return min(xs), min(ys), max(xs), max(ys)


def crop_blocks(image, box, blocks):
    """(blocks, blocks, 3) means of `image` inside box (x0, y0, x1, y1), inset by BORDER_INSET."""
    x0, y0 = (int(math.ceil(v)) + BORDER_INSET for v in box[:2])
    x1, y1 = (int(math.floor(v)) - BORDER_INSET for v in box[2:])
    return block_means(image[y0:y1, x0:x1], blocks)


def block_means(image, blocks):
    height, width = image.shape[:2]
    rows = np.linspace(0, height, blocks + 1).astype(int)
    cols = np.linspace(0, width, blocks + 1).astype(int)
    return np.array([[image[rows[i]:rows[i + 1], cols[j]:cols[j + 1]].reshape(-1, 3).mean(0)
                      for j in range(blocks)] for i in range(blocks)])


# --- the steps ---------------------------------------------------------------------------------

def check_camera_alignment():
    """Max pixel distance between Blender's projection and the shgi camera's, per view kind."""
    import shgi
    from shgi_blender.engine import viewport_camera

    window, area, region, space = view3d()
    rv3d = space.region_3d
    points = [Vector((x, y, z)) for x in (-0.8, 0.0, 0.7) for y in (0.3, 1.0, 1.8)
              for z in (0.2, 1.0, 1.9)]
    errors = {}
    for kind in ("PERSP", "ORTHO", "CAMERA"):
        rv3d.view_perspective = kind
        if kind != "CAMERA":
            rv3d.view_location = (0.0, 1.0, 1.0)
            rv3d.view_distance = 6.0
            rv3d.view_rotation = Matrix.Rotation(math.radians(70), 4, "X").to_quaternion()
        with bpy.context.temp_override(window=window, area=area, region=region):
            bpy.ops.wm.redraw_timer(type="DRAW", iterations=1)  # updates the region's matrices
        fields = viewport_camera.camera_fields_from_view(
            rv3d.view_matrix, rv3d.window_matrix, region.width, region.height)
        camera = viewport_camera.shgi_camera(shgi, fields)
        worst = 0.0
        for point in points:
            expected = view3d_utils.location_3d_to_region_2d(region, rv3d, point)
            film = camera.project(tuple(point))
            if expected is None or film is None:
                continue
            # Film y runs down from the top; region y up from the bottom.
            worst = max(worst, math.hypot(film[0] - expected.x,
                                          (region.height - film[1]) - expected.y))
        errors[kind] = worst
    RESULTS["alignment_px"] = errors


def steps():
    """Every step in order (generators yield the seconds to wait before going on)."""
    start = time.perf_counter()
    setup.enable_addon()
    scene = build_scene()
    set_up_view()
    yield STEP_SECONDS
    check_camera_alignment()
    set_up_view()
    before, box = yield from converge(scene)
    compare_with_f12(scene, before, box)
    yield STEP_SECONDS
    yield from move_light(before, box)
    after = yield from move_block()
    yield from show_overlay(scene, after, box)
    yield from path_trace(scene, box)
    yield from probe_grid(scene, box)
    yield from leave_rendered_shading()
    RESULTS["total_seconds"] = time.perf_counter() - start


def converge(scene):
    """Rendered shading until every sample is in: (screenshot, camera border)."""
    _window, _area, region, space = view3d()
    RESULTS["region"] = (region.width, region.height)
    space.shading.type = "RENDERED"
    frames, seconds = yield from wait_for_samples(SAMPLES, CONVERGE_TIMEOUT_SECONDS)
    RESULTS["frames_before_move"] = frames
    RESULTS["converge_seconds"] = seconds
    RESULTS["first_sync"] = sync_report()
    before = screenshot("before_move")
    box = camera_border(scene)
    RESULTS["camera_border"] = box
    return before, box


def compare_with_f12(scene, before, box):
    """F12 of the same camera, displayed as the viewport displays it (Standard view, sRGB)."""
    import shgi
    import shgi.metrics

    start = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    RESULTS["f12_seconds"] = time.perf_counter() - start
    path = os.path.join(os.path.dirname(RESULTS_PATH), "viewport_f12.exr")
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    layers = shgi.read_exr(path)
    combined = next(pixels for name, pixels in layers.items() if name.endswith("Combined"))
    # Bottom row first, as the screenshot; Standard view: sRGB, no exposure.
    f12 = shgi.metrics.display(combined[::-1], 1.0)
    viewport_blocks = crop_blocks(before, box, BLOCKS)
    f12_blocks = block_means(f12, BLOCKS)
    RESULTS["f12_mean"] = float(f12_blocks.mean())
    RESULTS["viewport_mean"] = float(viewport_blocks.mean())
    RESULTS["block_max_abs_diff"] = float(np.abs(viewport_blocks - f12_blocks).max())
    RESULTS["block_mean_abs_diff"] = float(np.abs(viewport_blocks - f12_blocks).mean())


def move_light(before, box):
    """Moves the ceiling light to the right; luminance of the frame's thirds before/after."""
    from shgi.metrics import LUMINANCE

    last_frame = session().worker.latest_frame().frame_id
    bpy.data.objects["ceiling_light"].location.x = LIGHT_X[1]
    frames, seconds = yield from wait_for_samples(SAMPLES, CONVERGE_TIMEOUT_SECONDS,
                                                  since=last_frame)
    RESULTS["move_sync"] = sync_report()
    RESULTS["move_seconds"] = seconds
    RESULTS["frames_after_move"] = frames
    after = screenshot("after_move")
    thirds = [[float((blocks[:, column] @ LUMINANCE).mean()) for column in range(3)]
              for blocks in (crop_blocks(before, box, 3), crop_blocks(after, box, 3))]
    RESULTS["thirds_before"], RESULTS["thirds_after"] = thirds


def move_block():
    """A transform-only edit: the short block moves. Returns the screenshot after it."""
    last_frame = session().worker.latest_frame().frame_id
    bpy.data.objects["short_block"].location.x += BLOCK_NUDGE
    yield from wait_for_samples(SAMPLES, CONVERGE_TIMEOUT_SECONDS, since=last_frame)
    RESULTS["block_move_sync"] = sync_report()
    return screenshot("after_block_move")


def show_overlay(scene, without, box):
    """The lattice overlay draws spheres inside the camera frame. Draw handlers draw with the
    viewport's overlays, so those are on with everything else they would draw off."""
    from shgi_blender.ui import field_overlay

    _window, _area, region, space = view3d()
    for name in OTHER_OVERLAYS:
        setattr(space.overlay, name, False)
    space.overlay.show_overlays = True
    scene.shgi.show_lattice_samples = True
    deadline = time.perf_counter() + OVERLAY_TIMEOUT_SECONDS
    draws = field_overlay.stats()["draws"]
    while field_overlay.stats()["draws"] < draws + 2:
        if time.perf_counter() > deadline:
            raise AssertionError(f"the overlay did not draw: {field_overlay.stats()}")
        region.tag_redraw()
        yield STEP_SECONDS
    changed = np.abs(screenshot("overlay") - without).max(axis=2) > OVERLAY_CHANGE
    x0, y0, x1, y1 = (int(v) for v in box)
    inside = changed[y0:y1, x0:x1]
    RESULTS["overlay"] = dict(field_overlay.stats(), changed_inside=float(inside.mean()),
                              changed_outside=float(changed.sum() - inside.sum()) / changed.size)
    scene.shgi.show_lattice_samples = False
    space.overlay.show_overlays = False


def path_trace(scene, box):
    """The path tracer in the viewport: a few samples, not black."""
    scene.shgi.method = "PATH_TRACE"
    scene.shgi.viewport_samples = PATH_TRACE_SAMPLES
    last_frame = session().worker.latest_frame().frame_id
    yield from wait_for_samples(PATH_TRACE_SAMPLES, CONVERGE_TIMEOUT_SECONDS, since=last_frame)
    RESULTS["path_trace_mean"] = float(crop_blocks(screenshot("path_trace"), box, BLOCKS).mean())


def probe_grid(scene, box):
    """PROBE_GRID refines in the background with its overlay on; an added, then moved,
    Irradiance Volume object restarts the grid with the object's probes."""
    from shgi_blender.ui import field_overlay

    _window, _area, region, space = view3d()
    for name in OTHER_OVERLAYS:
        setattr(space.overlay, name, False)
    space.overlay.show_overlays = True
    props = scene.shgi
    props.method = "PROBE_GRID"
    props.viewport_samples = PROBE_SAMPLES
    props.probe_grid.viewport_passes = PROBE_PASSES
    props.show_probes = True
    last_frame = session().worker.latest_frame().frame_id
    frames, _ = yield from wait_for_samples(PROBE_SAMPLES, CONVERGE_TIMEOUT_SECONDS,
                                            since=last_frame)
    worker = session().worker
    RESULTS["probe_grid"] = {"frames": frames, "passes": worker._solver.passes,
                             "probes": worker._solver.grid.probe_count,
                             "mean": float(crop_blocks(screenshot("probe_grid"), box,
                                                       BLOCKS).mean())}
    draws = field_overlay.stats()["draws"]
    while field_overlay.stats()["draws"] < draws + 2:
        region.tag_redraw()
        yield STEP_SECONDS
    RESULTS["probe_grid"]["overlay_spheres"] = field_overlay.stats()["spheres"]
    RESULTS["probe_grid"]["active"] = worker._solver.grid.active_count
    volume = setup.add_irradiance_volume(scene, "probe_volume", PROBE_VOLUME_RESOLUTION)
    volume.location, volume.scale = (0.0, 1.0, 1.0), (0.9, 0.9, 0.9)
    grids = []
    for step in ("added", "moved"):
        if step == "moved":
            volume.location.z += 0.1
        last_frame = worker.latest_frame().frame_id
        yield from wait_for_samples(PROBE_SAMPLES, CONVERGE_TIMEOUT_SECONDS, since=last_frame)
        grid = worker._solver.grid
        grids.append(grid)
        RESULTS["probe_grid"][step] = {
            "probes": grid.probe_count, "passes": grid.passes,
            "volume_z": float(np.asarray(grid.volumes[0].world_from_volume)[2, 3]),
            "new_grid": len(grids) == 1 or grids[-1] is not grids[-2]}
    bpy.data.objects.remove(volume)
    props.show_probes = False
    space.overlay.show_overlays = False


def leave_rendered_shading():
    """Solid shading frees the viewport's engine, whose session must stop."""
    _window, _area, region, space = view3d()
    space.shading.type = "SOLID"
    deadline = time.perf_counter() + SESSION_END_TIMEOUT_SECONDS
    while session() is not None and time.perf_counter() < deadline:
        region.tag_redraw()
        yield STEP_SECONDS
    RESULTS["sessions_after_solid"] = 0 if session() is None else 1


def sync_report():
    report = session().sync.last_report
    counters = dict(session().worker.counters)
    return {"change": report.change, "meshes_read": report.meshes_read,
            "materials_converted": report.materials_converted, "seconds": report.seconds,
            "worker": counters}


# --- the timer driving the steps ---------------------------------------------------------------

# The factory settings open the splash (Quick Setup) over the 3D view after this script runs.
bpy.context.preferences.view.show_splash = False
setup.run_steps_in_window(steps(), RESULTS, RESULTS_PATH, "VIEWPORT_WINDOW_OK", echo_results=True)
