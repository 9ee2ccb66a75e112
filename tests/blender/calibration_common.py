"""Shared code of the Cycles calibration scripts (tests/blender/calibration_*.py).

Each case builds a small scene with bpy, renders it with Cycles (CPU, no denoising, no adaptive
sampling, no clamping, no filter glossy, 1 px box filter, Standard view, every lighting pass) and
with shgi.render_path_traced on the exported depsgraph, at the same size and bounce limits, and
compares image means of Combined and of the lighting passes.

Noise: each renderer renders BATCHES independent images (different seeds) of SAMPLES / BATCHES
samples; a pass mean is the mean over batches and its standard error the standard deviation of
the batch means over sqrt(BATCHES). A case is only meaningful when both standard errors are
below a quarter of the tolerance (relative), which the pytest side checks along with the errors.

Scripts run as ``blender -b --factory-startup --python-exit-code 1 --python <script> --
<build python dir> <addon dir> <results json> [case ...]``.
"""

import json
import math
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import blender_test_setup as setup  # noqa: E402

setup.add_import_paths()

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import shgi  # noqa: E402
from mathutils import Euler, Vector  # noqa: E402
from shgi_blender.export import export_scene  # noqa: E402

COMBINED_TOLERANCE = 0.02
PASS_TOLERANCE = 0.03
RESOLUTION = 48
BATCHES = 8
THREADS = 2
# Cycles' Light Paths limits, used by both renderers (PathTracerSettings has the same names).
BOUNCES = {"max_bounces": 8, "diffuse_bounces": 4, "glossy_bounces": 4,
           "transmission_bounces": 8}
# Passes compared as they are stored (lighting divided by colour) and, for the lighting passes,
# as products with their colour pass (what the passes contribute to Combined).
COLOR_OF = {"DiffDir": "DiffCol", "DiffInd": "DiffCol", "GlossDir": "GlossCol",
            "GlossInd": "GlossCol", "TransDir": "TransCol", "TransInd": "TransCol"}


# --- scene building -------------------------------------------------------------------------

def reset_scene(world_color=(0.0, 0.0, 0.0), world_strength=0.0):
    """An empty factory scene set up for a calibration render."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False
    # SHGI's pixel filter is a 1-px box (uniform jitter over the pixel); Cycles' Box filter of
    # width 1 samples exactly that. (A 0.01 px Blackman-Harris point-samples pixel centres, which
    # changes the mean of every pixel crossed by an edge: 3% of DiffCol in the room scene.)
    cycles.pixel_filter_type = "BOX"
    cycles.filter_width = 1.0
    cycles.sample_clamp_direct = 0.0
    cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.caustics_reflective = True
    cycles.caustics_refractive = True
    cycles.light_sampling_threshold = 0.0
    cycles.max_bounces = BOUNCES["max_bounces"]
    cycles.diffuse_bounces = BOUNCES["diffuse_bounces"]
    cycles.glossy_bounces = BOUNCES["glossy_bounces"]
    cycles.transmission_bounces = BOUNCES["transmission_bounces"]
    cycles.transparent_max_bounces = 8
    cycles.volume_bounces = 0
    scene.render.threads_mode = "FIXED"
    scene.render.threads = THREADS
    scene.render.resolution_x = RESOLUTION
    scene.render.resolution_y = RESOLUTION
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    setup.use_multilayer_exr(scene.render.image_settings)
    layer = scene.view_layers[0]
    for name in ("diffuse_direct", "diffuse_indirect", "diffuse_color", "glossy_direct",
                 "glossy_indirect", "glossy_color", "transmission_direct",
                 "transmission_indirect", "transmission_color", "emit", "environment"):
        setattr(layer, "use_pass_" + name, True)
    world = bpy.data.worlds.new("World")
    world.use_nodes = True
    background = world.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*world_color, 1.0)
    background.inputs["Strength"].default_value = world_strength
    scene.world = world
    return scene


def principled(name, base_color, roughness=0.5, specular=0.0, metallic=0.0, transmission=0.0,
               ior=1.45, emission=(0.0, 0.0, 0.0), emission_strength=0.0):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    setup.set_principled_inputs(
        material.node_tree.nodes["Principled BSDF"], base_color=base_color, roughness=roughness,
        ior=ior, specular=specular, metallic=metallic, transmission=transmission,
        emission_color=emission, emission_strength=emission_strength)
    return material


def diffuse_bsdf(name, color, roughness=0.0):
    """A Diffuse BSDF material (Lambert at roughness 0, Oren-Nayar above)."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    tree = material.node_tree
    tree.nodes.remove(tree.nodes["Principled BSDF"])
    node = tree.nodes.new("ShaderNodeBsdfDiffuse")
    node.inputs["Color"].default_value = (*color, 1.0)
    node.inputs["Roughness"].default_value = roughness
    tree.links.new(node.outputs["BSDF"], tree.nodes["Material Output"].inputs["Surface"])
    return material


def add_mesh(name, vertices, faces, material, smooth=False):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    if smooth:
        for polygon in mesh.polygons:
            polygon.use_smooth = True
    mesh.materials.append(material)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def add_quad(name, corner, edge_u, edge_v, material):
    """A quad corner, +u, +u+v, +v; its front (counter-clockwise) faces along u x v."""
    c, u, v = Vector(corner), Vector(edge_u), Vector(edge_v)
    return add_mesh(name, [c, c + u, c + u + v, c + v], [(0, 1, 2, 3)], material)


def add_box(name, center, half, material):
    cx, cy, cz = center
    hx, hy, hz = half
    vertices = [(cx + sx * hx, cy + sy * hy, cz + sz * hz)
                for sz in (-1, 1) for sy in (-1, 1) for sx in (-1, 1)]
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return add_mesh(name, vertices, faces, material)


def add_sphere(name, center, radius, material, segments=32, rings=16):
    vertices, faces = [], []
    for ring in range(1, rings):
        theta = math.pi * ring / rings
        for seg in range(segments):
            phi = 2 * math.pi * seg / segments
            vertices.append((center[0] + radius * math.sin(theta) * math.cos(phi),
                             center[1] + radius * math.sin(theta) * math.sin(phi),
                             center[2] + radius * math.cos(theta)))
    top, bottom = len(vertices), len(vertices) + 1
    vertices += [(center[0], center[1], center[2] + radius), (center[0], center[1],
                                                            center[2] - radius)]
    for seg in range(segments):
        nxt = (seg + 1) % segments
        faces.append((top, seg, nxt))
        for ring in range(rings - 2):
            a, b = ring * segments, (ring + 1) * segments
            faces.append((a + seg, b + seg, b + nxt, a + nxt))
        last = (rings - 2) * segments
        faces.append((last + nxt, last + seg, bottom))
    return add_mesh(name, vertices, faces, material, smooth=True)


def add_room(colors=None, material=principled):
    """An open-topped room: floor, back, left and right walls (Principled, specular 0, or
    `material`(name, colour)), 4 m x 4 m x 2.5 m, open towards the camera (-Y) and the sky."""
    colors = colors or {"floor": (0.8, 0.8, 0.8), "back": (0.7, 0.7, 0.7),
                        "left": (0.7, 0.2, 0.2), "right": (0.2, 0.6, 0.2)}
    mats = {k: material(k, c) for k, c in colors.items()}
    add_quad("floor", (-2, -2, 0), (4, 0, 0), (0, 4, 0), mats["floor"])
    add_quad("back", (-2, 2, 0), (4, 0, 0), (0, 0, 2.5), mats["back"])
    add_quad("left", (-2, -2, 0), (0, 4, 0), (0, 0, 2.5), mats["left"])
    add_quad("right", (2, -2, 0), (0, 0, 2.5), (0, 4, 0), mats["right"])


def add_camera(location=(0.0, -5.5, 1.3), target=(0.0, 0.0, 0.9), lens=35.0):
    data = bpy.data.cameras.new("Camera")
    data.lens = lens
    obj = bpy.data.objects.new("Camera", data)
    obj.location = location
    direction = Vector(target) - Vector(location)
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.scene.camera = obj
    return obj


def add_light(kind, location, rotation=(0.0, 0.0, 0.0), **props):
    data = bpy.data.lights.new(kind.lower(), kind)
    for key, value in props.items():
        setattr(data, key, value)
    obj = bpy.data.objects.new(kind.lower(), data)
    obj.location = location
    obj.rotation_euler = Euler(rotation)
    bpy.context.scene.collection.objects.link(obj)
    return obj


# --- rendering -------------------------------------------------------------------------------

def render_cycles(samples, tmpdir):
    """[{pass: (H, W, C)}] of BATCHES Cycles renders with seeds 0..BATCHES-1."""
    scene = bpy.context.scene
    scene.cycles.samples = samples // BATCHES
    batches = []
    for batch in range(BATCHES):
        scene.cycles.seed = batch
        path = os.path.join(tmpdir, f"cycles_{batch}.exr")
        scene.render.filepath = path
        bpy.ops.render.render(write_still=True)
        batches.append(setup.read_render_exr(path))
    return batches


def render_shgi(samples, **settings_fields):
    """(export warnings, [{pass: (H, W, C)}] of BATCHES SHGI renders with seeds 0..BATCHES-1)."""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    result = export_scene(depsgraph, bpy.context.scene)
    scene = result.scene
    scene.commit()
    batches = []
    for batch in range(BATCHES):
        settings = shgi.PathTracerSettings(samples=samples // BATCHES, seed=batch, **BOUNCES,
                                           **settings_fields)
        passes = shgi.render_path_traced(scene, settings)
        batches.append({name: np.asarray(px, np.float64) for name, px in passes.items()})
    return list(result.warnings), batches


def pass_mean(batches, name):
    """(mean, standard error) over batches of the mean of a pass's RGB channels.
    'X*Y' is the per-pixel product of two passes (lighting times colour)."""
    means = []
    for passes in batches:
        if "*" in name:
            a, b = name.split("*")
            values = passes[a][..., :3] * passes[b][..., :3]
        else:
            values = passes[name][..., :3]
        means.append(float(values.mean()))
    means = np.array(means)
    return float(means.mean()), float(means.std(ddof=1) / math.sqrt(len(means)))


def compare(case, compared_passes, cycles_samples, shgi_samples, tmpdir, results,
            also=None, shgi_settings=None):
    """Renders the current scene with both renderers and stores the comparison in results.

    compared_passes: passes asserted besides Combined; "A*B" is the per-pixel product of two
        passes (used where SHGI's colour passes differ from Cycles', see the report rows).
    also: {other case name: passes} compared on the same renders, stored as separate cases.
    shgi_settings: extra PathTracerSettings fields (diagnostic cases only).
    """
    start = time.perf_counter()
    cycles_batches = render_cycles(cycles_samples, tmpdir)
    _last_cycles_batches[:] = cycles_batches
    cycles_seconds = time.perf_counter() - start
    start = time.perf_counter()
    warnings, shgi_batches = render_shgi(shgi_samples, **(shgi_settings or {}))
    shgi_seconds = time.perf_counter() - start
    for name, passes in [(case, ("Combined",) + tuple(compared_passes))] + list(
            (also or {}).items()):
        rows = [_row(p, cycles_batches, shgi_batches, asserted=True) for p in passes]
        if name == case:
            informative = [f"{n}*{COLOR_OF[n]}" for n in compared_passes if n in COLOR_OF]
            informative += sorted({COLOR_OF[n.split("*")[0]] for n in compared_passes
                                   if n.split("*")[0] in COLOR_OF})
            informative += [n for n in ("Emit", "Env") if n not in compared_passes]
            rows += [_row(p, cycles_batches, shgi_batches, asserted=False)
                     for p in informative if p not in passes]
        results[name] = {"rows": rows, "cycles_samples": cycles_samples,
                         "shgi_samples": shgi_samples, "cycles_seconds": cycles_seconds,
                         "shgi_seconds": shgi_seconds, "warnings": warnings}
        print_case(name, results[name])


_last_cycles_batches = []  # the Cycles renders of the last compare(), for diagnostics


def last_cycles_mean(name):
    """The mean of a pass in the last compare()'s Cycles renders (pass_mean's naming)."""
    return pass_mean(_last_cycles_batches, name)[0]


def _row(name, cycles_batches, shgi_batches, asserted):
    c_mean, c_se = pass_mean(cycles_batches, name)
    s_mean, s_se = pass_mean(shgi_batches, name)
    rel = (s_mean - c_mean) / c_mean if c_mean != 0 else (0.0 if s_mean == 0 else math.inf)
    tol = (COMBINED_TOLERANCE if name == "Combined" else PASS_TOLERANCE) if asserted else None
    return {"pass": name, "cycles": c_mean, "shgi": s_mean, "rel_error": rel,
            "cycles_se": c_se, "shgi_se": s_se,
            "cycles_rel_se": c_se / abs(c_mean) if c_mean else math.inf,
            "shgi_rel_se": s_se / abs(s_mean) if s_mean else math.inf, "tolerance": tol}


def print_case(case, result):
    print(f"\n== {case}: Cycles {result['cycles_samples']} spp {result['cycles_seconds']:.1f} s, "
          f"SHGI {result['shgi_samples']} spp {result['shgi_seconds']:.1f} s "
          f"({BATCHES} seeds each, {RESOLUTION}x{RESOLUTION} px)", flush=True)
    if result["warnings"]:
        print("   export warnings:", result["warnings"])
    print(f"   {'case':<26}{'pass':<18}{'cycles':>11}{'(se%)':>8}{'shgi':>11}{'(se%)':>8}"
          f"{'rel.err':>9}{'tol':>7}  status")
    for row in result["rows"]:
        tol = row["tolerance"]
        if tol is None:
            status = "info"
        else:
            ok = abs(row["rel_error"]) <= tol
            noisy = max(row["cycles_rel_se"], row["shgi_rel_se"]) >= tol / 4
            status = ("ok" if ok else "FAIL") + (" NOISY" if noisy else "")
        print(f"   {case:<26}{row['pass']:<18}{row['cycles']:>11.5g}"
              f"{100 * row['cycles_rel_se']:>7.2f}%{row['shgi']:>11.5g}"
              f"{100 * row['shgi_rel_se']:>7.2f}%{100 * row['rel_error']:>8.2f}%"
              f"{'' if tol is None else f'{100 * tol:.0f}%':>7}  {status}", flush=True)


def run_cases(cases, marker):
    """Runs the selected cases {name: function(tmpdir, results)} and writes the JSON."""
    out = setup.results_path("shgi_calib.json")
    selected = setup.script_args()[3:]  # case names after the results path; none: every case
    shgi.set_max_threads(THREADS)
    results = {}
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="shgi_calib_") as tmpdir:
        for name, build in cases.items():
            if selected and name not in selected:
                continue
            build(name, tmpdir, results)
    with open(out, "w") as f:
        json.dump(results, f, indent=1)
    print(f"\n{marker} {len(results)} cases in {time.perf_counter() - start:.1f} s -> {out}",
          flush=True)
