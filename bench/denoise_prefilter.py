"""The denoiser's Prefilter and Quality at equal samples: the same noisy F12 frames denoised with
every choice of shgi.frame_denoise, scored against the renderer's own reference.

    PYTHONPATH=build/python /opt/shgi/bpy-5.0.1/bin/python bench/denoise_prefilter.py
        [--scenes sun_room,textured] [--samples 1,2,4,8,16,64] [--cycles]
        [--cache build/equal_time_cache] [--pixel-filter BLACKMAN_HARRIS --filter-width 1.5]
        [--split]

With --split, each frame is instead denoised with the Automatic prefilter and three shares of
the direct light (Emit + Env) taken around the network: all of it (the rule before the share
followed the pixel filter), none of it, and frame_denoise.direct_share's for the frame's
samples and pixel filter (what F12 does).

A benchmark, not a test: nothing is asserted. Scenes are bench/equal_time.py's (same
resolution, Light Paths and seed), plus "textured": the Cornell box with a 256 x 256 colour grid
on its floor and back wall, whose guides are noisy at few samples (textures and antialiased
edges are what make a guide noisy; the other scenes are untextured). Each frame is an F12 of
SHGI's PATH_TRACE (with --cycles, also of Cycles) at the given samples with denoising on, so
that its Noisy Image, Denoising Albedo and Denoising Normal are the renderer's own; the noisy
frame is then denoised offline by a FrameDenoiser of each (prefilter, quality), the second run
of each timed in CPU seconds (process time: OIDN's threads count, other jobs do not).

References: bench/equal_time.py's cached ones (the most samples cached, of REFERENCE_SEED); the
textured scene's is rendered here once with SHGI (REFERENCE_SAMPLES, REFERENCE_SEED) and cached.
"""

import argparse
import os
import sys
import time

import bpy

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [os.path.join(REPO_ROOT, "bench")]

import equal_time  # noqa: E402  (sets sys.path for the add-on, shgi and the scenes)
import numpy as np  # noqa: E402

DEFAULT_SAMPLES = (1, 2, 4, 8, 16, 64)
TEXTURED = "textured"
# The textured scene's reference samples (its noise is far below every score here).
TEXTURED_REFERENCE_SAMPLES = 1024
GRID_PIXELS = 256
TEXTURED_PARTS = ("floor", "back")
PASSES_USED = ("use_pass_emit", "use_pass_environment", "use_pass_z", "use_pass_normal",
               "use_pass_diffuse_color", "use_pass_glossy_color", "use_pass_transmission_color")


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenes", default=f"sun_room,{TEXTURED}")
    parser.add_argument("--samples", default=",".join(str(n) for n in DEFAULT_SAMPLES))
    parser.add_argument("--resolution", default="200x150", help="WxH pixels")
    parser.add_argument("--cycles", action="store_true", help="Cycles' frames too")
    parser.add_argument("--cache", default=os.path.join(REPO_ROOT, "build", "equal_time_cache"))
    parser.add_argument("--pixel-filter", default=None,
                        help="SHGI's Film > Pixel Filter (BOX, GAUSSIAN, BLACKMAN_HARRIS); "
                             "default the add-on's")
    parser.add_argument("--filter-width", type=float, default=None)
    parser.add_argument("--split", action="store_true",
                        help="compare shares of the direct light taken around the network")
    args = parser.parse_args(argv)
    args.scenes = args.scenes.split(",")
    args.samples = [int(n) for n in args.samples.split(",")]
    args.width, args.height = (int(x) for x in args.resolution.lower().split("x"))
    return args


def build(name, args):
    """The scene `name` at the bench's size with every pass the denoiser reads."""
    if name != TEXTURED:
        scene = equal_time.build_scene(name, args.width, args.height)
    else:
        scene = equal_time.build_scene("cornell_box", args.width, args.height)
        grid = bpy.data.images.new("grid", GRID_PIXELS, GRID_PIXELS)
        grid.generated_type = "COLOR_GRID"
        material = bpy.data.materials.new("grid")
        material.use_nodes = True
        nodes, links = material.node_tree.nodes, material.node_tree.links
        texture = nodes.new("ShaderNodeTexImage")
        texture.image = grid
        links.new(texture.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
        for part in TEXTURED_PARTS:
            mesh = bpy.data.objects[part].data
            layer = mesh.uv_layers.new(name="UVMap")
            for loop in mesh.loops:  # the quad's corners onto the unit square
                layer.data[loop.index].uv = ((0, 0), (1, 0), (1, 1), (0, 1))[loop.vertex_index]
            mesh.materials[0] = material
    if args.pixel_filter is not None:
        scene.shgi.pixel_filter = args.pixel_filter
    if args.filter_width is not None:
        scene.shgi.filter_width = args.filter_width
    layer = scene.view_layers[0]
    layer.cycles.denoising_store_passes = True
    for name_of_pass in PASSES_USED:
        setattr(layer, name_of_pass, True)
    return scene


def render(scene, engine, samples, path, seed=equal_time.SEED, denoise=True):
    """{pass: float32 (H, W, C)} of an F12 of `samples` samples."""
    from shgi_blender.engine import passes as pass_names

    if engine == "CYCLES":
        equal_time.use_cycles(scene, samples, denoise)
        scene.cycles.seed = seed
    else:
        equal_time.use_shgi(scene, "PATH_TRACE", samples, denoise=denoise)
        scene.shgi.seed = seed
    try:
        equal_time.render_f12(scene, engine, path)
    finally:
        scene.cycles.seed = scene.shgi.seed = equal_time.SEED
    names = pass_names.names_from_blender_names(bpy.app.version)
    import shgi
    return {names.get(layer.split(".")[-1], layer.split(".")[-1]): np.asarray(pixels, np.float32)
            for layer, pixels in shgi.read_exr(path).items()}


def reference(name, scene, renderer, args):
    if name != TEXTURED:
        key = f"{name}_{args.width}x{args.height}_{renderer}_{equal_time.REFERENCE_SAMPLES}spp"
        if renderer == "shgi":
            key = key.replace("_shgi_", f"_shgi_clamp10{equal_time.shgi_reference_tag(scene.shgi)}_")
        else:
            key = key.replace("_cycles_", "_cycles_clamp10_")
        return equal_time.reference(scene, key, None, None, args)[0]
    path = os.path.join(args.cache, f"{TEXTURED}_{args.width}x{args.height}_shgi"
                                    f"{equal_time.pixel_filter_tag(scene.shgi)}_seed"
                                    f"{equal_time.REFERENCE_SEED}_{TEXTURED_REFERENCE_SAMPLES}spp.npy")
    if not os.path.exists(path):
        frame = render(scene, "SHGI", TEXTURED_REFERENCE_SAMPLES,
                       os.path.join(args.cache, "render.exr"), seed=equal_time.REFERENCE_SEED,
                       denoise=False)
        np.save(path, frame["Combined"][..., :3].astype(np.float64))
    return np.load(path)


def split_study(args):
    """PSNR of each frame denoised (Automatic prefilter) with all, none and direct_share's share
    of the direct light around the network."""
    from shgi import frame_denoise, metrics

    rule = frame_denoise.direct_share
    exr = os.path.join(args.cache, "prefilter.exr")
    for name in args.scenes:
        scene = build(name, args)
        props = scene.shgi
        ref = reference(name, scene, "shgi", args)
        print(f"\n{name}, SHGI, {props.pixel_filter} {props.filter_width:g}: PSNR dB of the "
              "frame denoised with a share of the direct light around the network")
        print(f"{'spp':>5s} {'noisy':>6s} {'all':>6s} {'none':>6s} {'rule':>6s} {'share':>6s}")
        for samples in args.samples:
            frame = render(scene, "SHGI", samples, exr)
            noisy = dict(frame, Combined=frame["Noisy Image"])
            cells = []
            for share in (lambda *_: 1.0, lambda *_: 0.0, rule):
                frame_denoise.direct_share = share
                try:
                    with frame_denoise.FrameDenoiser("HIGH", "AUTO", "ALBEDO_NORMAL",
                                                     props.pixel_filter,
                                                     props.filter_width) as denoiser:
                        out = denoiser.denoise(noisy, samples=samples)["Combined"]
                finally:
                    frame_denoise.direct_share = rule
                cells.append(f"{metrics.psnr(ref, out):6.2f}")
            share = rule(samples, props.pixel_filter, props.filter_width)
            print(f"{samples:5d} {metrics.psnr(ref, frame['Noisy Image']):6.2f} "
                  + " ".join(cells) + f" {share:6.3f}", flush=True)


def main():
    args = parse_args()
    if args.split:
        split_study(args)
        return
    from shgi import frame_denoise, metrics

    choices = [(prefilter, quality) for prefilter in ("FAST", "NONE", "ACCURATE")
               for quality in ("HIGH", "BALANCED")]
    exr = os.path.join(args.cache, "prefilter.exr")
    header = " ".join(f"{p[:4] + '/' + q[:4]:>12s}" for p, q in choices)
    for name in args.scenes:
        scene = build(name, args)
        # The share of the direct light around the network follows the scene's pixel filter.
        denoisers = {choice: frame_denoise.FrameDenoiser(
            choice[1], choice[0], "ALBEDO_NORMAL", scene.shgi.pixel_filter,
            scene.shgi.filter_width) for choice in choices}
        renderers = ["SHGI"] + (["CYCLES"] if args.cycles and name != TEXTURED else [])
        for engine in renderers:
            ref = reference(name, scene, "shgi" if engine == "SHGI" else "cycles", args)
            print(f"\n{name}, {engine}: PSNR dB of the denoised frame (CPU s of a denoise)")
            print(f"{'spp':>5s} {'noisy':>6s} {header}")
            for samples in args.samples:
                frame = render(scene, engine, samples, exr)
                noisy = dict(frame, Combined=frame["Noisy Image"])
                cells = []
                for choice, denoiser in denoisers.items():
                    denoiser.denoise(noisy, samples=samples)  # the first run sets it up
                    start = time.process_time()
                    out = denoiser.denoise(noisy, samples=samples)["Combined"]
                    seconds = time.process_time() - start
                    cells.append(f"{metrics.psnr(ref, out):5.2f} ({seconds:.2f})")
                print(f"{samples:5d} {metrics.psnr(ref, frame['Noisy Image']):6.2f} "
                      + " ".join(cells), flush=True)
        for denoiser in denoisers.values():
            denoiser.close()


if __name__ == "__main__":
    main()
