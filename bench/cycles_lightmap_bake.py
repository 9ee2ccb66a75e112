"""Cycles' side of bench/lightmap_bench.py --cycles: bakes the sun room's floor with Cycles at
increasing sample counts. Runs inside Debian's Blender (pyenv's folders off PATH):

    blender -b --factory-startup --python-exit-code 1 --python bench/cycles_lightmap_bake.py \
        -- request.json

request.json: {"resolution": texels per side, "samples": [counts, ascending], "seed": int,
"light_paths": {Cycles Light Paths limit: value}, "out": folder, "reference": .npy path or null,
"target_error": relative RMS error or null, "repo": repository root, "build_python": the
folder holding the shgi package}. For each count: a Cycles
DIFFUSE {DIRECT, INDIRECT} bake of the floor through LightmapUV, saved as <out>/cycles_<n>.npy
((H, W, 3) float32, row 0 at v = 0, as shgi keeps lightmaps in memory) with its wall time
(bpy.ops.object.bake: Cycles' scene sync, BVH build and the bake); with a reference, its
relative RMS error, stopping after the first count at or below target_error. One untimed
1-sample bake comes first (Cycles loads its kernels on the first bake of a session). Writes
<out>/cycles.json: {"bakes": [{"samples", "seconds", "path", "error"}]}.

The scene: examples/blender_scenes.py's sun room (the same vertices, materials, sun, window
portal and sky as examples/scenes.py) in its lightmap variant (lightmap=True), as
examples/scenes.py's sun_room(lightmap=True) builds it: every quad (the walls, floor, ceiling)
faces into the room and gets the UV map LightmapUV = the unit square over its corners in
vertex order. The table (a closed box) is left as it is, as there.
"""

import json
import os
import sys
import time

import bpy
import numpy as np

ARGS = sys.argv[sys.argv.index("--") + 1:]
REQUEST = json.loads(open(ARGS[0]).read())
sys.path[:0] = [os.path.join(REQUEST["repo"], "examples"), os.path.join(REQUEST["repo"], "bench"),
                REQUEST["build_python"]]
import blender_scenes  # noqa: E402  (examples/blender_scenes.py)
from lightmap_bench import relative_rms  # noqa: E402  (one error metric for both bakers)

def set_up_cycles(scene):
    """CPU, no denoising, adaptive sampling or clamping, light paths as SHGI's bake."""
    scene.render.engine = "CYCLES"
    cycles = scene.cycles
    cycles.device = "CPU"
    cycles.use_denoising = False
    cycles.use_adaptive_sampling = False
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    cycles.blur_glossy = 0.0
    cycles.light_sampling_threshold = 0.0
    cycles.caustics_reflective = cycles.caustics_refractive = True
    for name, value in REQUEST["light_paths"].items():
        setattr(cycles, name, value)
    cycles.seed = REQUEST["seed"]
    scene.render.threads_mode = "AUTO"


def bake_floor(samples, resolution):
    """((H, W, 3) float32 Cycles DIFFUSE {DIRECT, INDIRECT} bake of the floor, seconds)."""
    bpy.context.scene.cycles.samples = samples
    obj = bpy.data.objects["floor"]
    image = bpy.data.images.new("floor_cycles", resolution, resolution, float_buffer=True)
    tree = obj.active_material.node_tree
    node = tree.nodes.new("ShaderNodeTexImage")  # the bake target; not linked, shades nothing
    node.image = image
    tree.nodes.active = node
    bpy.ops.object.select_all(action="DESELECT")
    obj.select_set(True)
    bpy.context.view_layer.objects.active = obj
    start = time.perf_counter()
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=0,
                        use_clear=True, target="IMAGE_TEXTURES")
    seconds = time.perf_counter() - start
    tree.nodes.remove(node)
    pixels = np.empty(resolution * resolution * 4, np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(resolution, resolution, 4)[..., :3].copy(), seconds


def main():
    scene = blender_scenes.build("sun_room", 1.0, lightmap=True)
    set_up_cycles(scene)
    reference = np.load(REQUEST["reference"]) if REQUEST["reference"] else None
    # Untimed: the first bake of a Blender session also loads Cycles' kernels.
    bake_floor(1, REQUEST["resolution"])
    bakes = []
    for samples in REQUEST["samples"]:
        texels, seconds = bake_floor(samples, REQUEST["resolution"])
        path = os.path.join(REQUEST["out"], f"cycles_{samples}.npy")
        np.save(path, texels)
        error = None if reference is None else relative_rms(texels, reference)
        bakes.append({"samples": samples, "seconds": seconds, "path": path, "error": error})
        print(f"cycles bake: {samples} samples, {seconds:.2f} s, error {error}", flush=True)
        if error is not None and REQUEST["target_error"] is not None:
            if error <= REQUEST["target_error"]:
                break
    with open(os.path.join(REQUEST["out"], "cycles.json"), "w") as file:
        json.dump({"bakes": bakes}, file, indent=1)


main()
