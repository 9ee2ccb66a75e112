"""Regenerates the manual's pictures in docs/images/ with Blender 3.4 (Debian's) and SHGI.

Two runs, both from the repository root (docs/contributing.md, "The manual's pictures"):

    # 1. viewport.png: a Blender window (Xvfb) in Rendered shading with the SHGI engine
    xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup \
        --window-geometry 0 0 1280 800 --python docs/images/make_images.py -- \
        build/python addon viewport

    # 2. shgi_vs_cycles.png (F12 renders) and lightmap_eevee.png (a bake shown in EEVEE);
    #    background Blender, under Xvfb because EEVEE needs an OpenGL context
    xvfb-run -a -s "-screen 0 1280x800x24" blender -b --factory-startup \
        --python docs/images/make_images.py -- build/python addon renders lightmap

After '--': the folder holding the built `shgi` package, the folder holding the add-on
`shgi_blender`, then the pictures to make. The scene is the project's sun room
(examples/blender_scenes.py, the same as examples/scenes.py). Resolutions and samples are kept
small so that a run takes a few minutes on 2 cores; the labels carry the measured times.
Labels are drawn by Blender's own "Burn Into Image" stamp on a blank Workbench render, so the
script needs nothing beyond Blender and numpy.
"""

import os
import sys
import tempfile
import time
import traceback

import addon_utils
import bmesh
import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
BUILD_PYTHON = os.path.abspath(ARGS[0]) if len(ARGS) > 0 else os.path.join(REPO, "build", "python")
ADDON_DIR = os.path.abspath(ARGS[1]) if len(ARGS) > 1 else os.path.join(REPO, "addon")
PARTS = ARGS[2:] or (["viewport"] if not bpy.app.background else ["renders", "lightmap"])
for path in (ADDON_DIR, BUILD_PYTHON):
    sys.path.insert(0, path)
sys.path.insert(0, os.path.join(REPO, "examples"))

import blender_scenes  # noqa: E402  (examples/blender_scenes.py)

MAX_WIDTH = 800              # pictures are at most this wide
LABEL_HEIGHT = 22            # pixels of the label strip under each panel
TMP = tempfile.mkdtemp(prefix="shgi_images_")


def enable_addon():
    if "shgi_blender" not in bpy.context.preferences.addons:
        if addon_utils.enable("shgi_blender", default_set=True, handle_error=None) is None:
            raise RuntimeError("the shgi_blender add-on did not enable")


# --- images as numpy arrays (rows top first, RGB in [0, 1], display values) -----------------

def load_png(path):
    image = bpy.data.images.load(path)
    width, height = image.size
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)[::-1, :, :3].copy()


def save_png(array, path):
    height, width = array.shape[:2]
    image = bpy.data.images.new("shgi_picture", width, height, alpha=False)
    rgba = np.ones((height, width, 4), np.float32)
    rgba[..., :3] = np.clip(array, 0.0, 1.0)
    image.pixels.foreach_set(rgba[::-1].ravel())
    image.filepath_raw = path
    image.file_format = "PNG"
    image.save()
    bpy.data.images.remove(image)
    print(f"wrote {path} ({width} x {height})")


def shrink(array, width):
    """Box-filtered to `width` pixels wide (integer steps, then nearest for the rest)."""
    height = int(round(array.shape[0] * width / array.shape[1]))
    rows = (np.arange(height) * array.shape[0] / height).astype(int)
    cols = (np.arange(width) * array.shape[1] / width).astype(int)
    factor = max(1, array.shape[1] // width)
    if factor > 1:  # average factor x factor blocks first, so text stays readable
        h, w = array.shape[0] // factor * factor, array.shape[1] // factor * factor
        array = array[:h, :w].reshape(h // factor, factor, w // factor, factor, 3).mean((1, 3))
        rows = np.minimum(rows // factor, array.shape[0] - 1)
        cols = np.minimum(cols // factor, array.shape[1] - 1)
    return array[rows][:, cols]


def label(text, width):
    """A strip of `width` x LABEL_HEIGHT pixels reading `text` (Blender's stamp)."""
    scene = bpy.data.scenes.get("shgi_label") or bpy.data.scenes.new("shgi_label")
    if scene.camera is None:
        camera = bpy.data.objects.new("shgi_label_camera", bpy.data.cameras.new("shgi_label"))
        scene.collection.objects.link(camera)
        scene.camera = camera
    render = scene.render
    render.engine = "BLENDER_WORKBENCH"
    render.resolution_x, render.resolution_y = width, LABEL_HEIGHT
    render.resolution_percentage = 100
    render.use_stamp = True
    for field in ("time", "date", "frame", "frame_range", "camera", "lens", "scene", "marker",
                  "filename", "sequencer_strip", "render_time", "memory", "hostname", "labels"):
        setattr(render, "use_stamp_" + field, False)
    render.use_stamp_note = True
    render.stamp_note_text = text
    render.stamp_font_size = 13
    render.stamp_background = (0.1, 0.1, 0.1, 1.0)
    render.image_settings.file_format = "PNG"
    render.filepath = os.path.join(TMP, "label.png")
    bpy.ops.render.render(write_still=True, scene=scene.name)
    strip = load_png(render.filepath)
    strip[:] = np.where(strip.mean(-1, keepdims=True) > 0.5, 1.0, 0.1)  # white on dark grey
    return strip


def panel(image, text):
    return np.concatenate([image, label(text, image.shape[1])], axis=0)


# --- the scene ----------------------------------------------------------------------------------

def sun_room(scale):
    """The sun room in a fresh file, the add-on enabled, SHGI at its defaults."""
    blender_scenes.build("sun_room", scale)
    enable_addon()
    scene = bpy.context.scene
    scene.render.engine = "SHGI"
    scene.view_settings.view_transform = "Filmic"
    return scene


def render_f12(scene, path):
    """F12 of `scene` saved as a PNG (display values); its seconds."""
    scene.render.image_settings.file_format = "PNG"
    start = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    seconds = time.perf_counter() - start
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    return seconds


# --- picture 2: SHGI beside Cycles --------------------------------------------------------------

def make_renders():
    scene = sun_room(1.0)  # 256 x 192 pixels
    panels = []
    for method, samples, name in (("PHOTON_LATTICE", 64, "Photon Lattice"),
                                  ("PROBE_GRID", 64, "Probe Grid")):
        scene.render.engine = "SHGI"
        bpy.ops.shgi.quality_preset(preset="MEDIUM")  # 64 spp, 400k photons, 24 cells
        scene.shgi.method = method
        scene.shgi.samples = samples
        path = os.path.join(TMP, f"{method}.png")
        seconds = render_f12(scene, path)
        panels.append(panel(load_png(path), f"SHGI {name}, {samples} spp: {seconds:.1f} s"))
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 256
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    path = os.path.join(TMP, "cycles.png")
    seconds = render_f12(scene, path)
    panels.append(panel(load_png(path), f"Cycles, 256 spp: {seconds:.1f} s"))
    gap = np.ones((panels[0].shape[0], 4, 3), np.float32)
    row = np.concatenate([panels[0], gap, panels[1], gap, panels[2]], axis=1)
    save_png(row, os.path.join(HERE, "shgi_vs_cycles.png"))


# --- picture 3: a baked lightmap in EEVEE -------------------------------------------------------

def make_lightmap():
    scene = sun_room(1.5)  # 384 x 288 pixels
    meshes = [obj for obj in scene.objects if obj.type == "MESH"]
    for obj in meshes:  # Show in Materials leaves shared materials alone
        obj.active_material = obj.active_material.copy()
        if obj.name != "table":
            # The room's walls face out of the room (as in examples/scenes.py); a bake sees a
            # surface's front, so turn them inwards as sun_room(lightmap=True) does.
            mesh = bmesh.new()
            mesh.from_mesh(obj.data)
            bmesh.ops.reverse_faces(mesh, faces=mesh.faces)
            mesh.to_mesh(obj.data)
            mesh.free()
    bpy.ops.object.select_all(action="DESELECT")
    for obj in meshes:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = meshes[0]
    out = os.path.join(TMP, "lightmaps")
    start = time.perf_counter()
    status = bpy.ops.shgi.bake_lightmaps(
        source="PATH_TRACE", samples=256, resolution=128, create_uv=True,
        uv_layout="LIGHTMAP_PACK", filter=True, hook_up_material=True, output_folder=out)
    bake_seconds = time.perf_counter() - start
    if status != {"FINISHED"}:
        raise RuntimeError(f"shgi.bake_lightmaps returned {status}")
    scene.render.engine = "BLENDER_EEVEE"
    scene.eevee.taa_render_samples = 16
    path = os.path.join(TMP, "eevee.png")
    seconds = render_f12(scene, path)
    view = panel(load_png(path), f"EEVEE with the baked lightmaps: {seconds:.1f} s")
    floor = load_png(os.path.join(out, "floor.png"))
    floor = np.repeat(np.repeat(floor, 2, axis=0), 2, axis=1)[:view.shape[0] - LABEL_HEIGHT]
    side = panel(floor, "floor.png (128 x 128)")
    side = np.pad(side, ((view.shape[0] - side.shape[0], 0), (0, 0), (0, 0)), constant_values=1)
    gap = np.ones((view.shape[0], 4, 3), np.float32)
    row = np.concatenate([view, gap, side], axis=1)
    save_png(row, os.path.join(HERE, "lightmap_eevee.png"))
    print(f"bake: {len(meshes)} objects, 128 x 128, 256 samples per texel, {bake_seconds:.1f} s")


# --- picture 1: the viewport in a window ---------------------------------------------------------

def view3d():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, area, region, area.spaces.active


def viewport_steps():
    """Generator run by a timer (the window must draw between steps)."""
    from shgi_blender.engine import viewport

    enable_addon()
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    blender_scenes.sun_room(1.0)
    scene = bpy.context.scene
    scene.render.engine = "SHGI"
    scene.view_settings.view_transform = "Filmic"
    bpy.ops.shgi.quality_preset(preset="PREVIEW")
    scene.shgi.method = "PHOTON_LATTICE"
    scene.shgi.viewport_samples = 16
    window, area, region, space = view3d()
    for other in window.screen.areas:
        if other.type == "PROPERTIES":
            other.spaces.active.context = "RENDER"
    space.region_3d.view_perspective = "CAMERA"
    with bpy.context.temp_override(window=window, area=area, region=region):
        bpy.ops.view3d.view_center_camera()
    yield 0.5
    space.shading.type = "RENDERED"
    start = time.perf_counter()
    while time.perf_counter() - start < 120:
        sessions = viewport.sessions()
        frame = sessions[0].worker.latest_frame() if sessions else None
        if frame is not None and frame.divisor == 1 and frame.samples >= 16 \
                and sessions[0].drawn_frame_id == frame.frame_id:
            break
        yield 0.25
    yield 1.0  # one more redraw
    path = os.path.join(TMP, "window.png")
    with bpy.context.temp_override(window=window):
        bpy.ops.screen.screenshot(filepath=path)
    image = load_png(path)
    save_png(shrink(image, min(MAX_WIDTH, image.shape[1])), os.path.join(HERE, "viewport.png"))
    space.shading.type = "SOLID"
    yield 0.5


def run_in_window():
    steps = viewport_steps()

    def drive():
        try:
            return next(steps)
        except StopIteration:
            code = 0
        except Exception:
            traceback.print_exc()
            code = 1
        sys.stdout.flush()
        os._exit(code)

    bpy.context.preferences.view.show_splash = False
    bpy.app.timers.register(drive, first_interval=1.0)


if "viewport" in PARTS:
    run_in_window()
else:
    try:
        if "renders" in PARTS:
            make_renders()
        if "lightmap" in PARTS:
            make_lightmap()
    except Exception:
        traceback.print_exc()
        sys.stdout.flush()
        os._exit(1)
