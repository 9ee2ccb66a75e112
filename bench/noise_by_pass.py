"""Where the per-sample noise of SHGI's path tracer and of Cycles is, pass by pass and bounce
limit by bounce limit, on one of bench/equal_time.py's scenes (default: the sun room).

    PYTHONPATH=build/python /opt/shgi/bpy-5.0.1/bin/python bench/noise_by_pass.py
        [--scene sun_room] [--samples 64] [--max-bounces 1,2,3,8] [--lights all|sun|world]
        [--no-specular] [--shgi-set field=value,...] [--no-cycles]
        [--cache build/equal_time_cache]

A benchmark, not a test: nothing is asserted. Each renderer renders the scene twice (seeds
equal_time.SEED and SEED + 1) at the same samples, with the same Light Paths limits (but
max_bounces, one row group per --max-bounces value), both undenoised; SHGI through
shgi.PathTracer with the add-on's F12 settings (as bench/caustics_noise.py), Cycles through F12
with its light passes on. Per pass, the noise is estimated without a reference as half the
squared difference of the two renders, times spp (constant under 1/N variance), averaged over
pixels and RGB:
- "lin": of the pass's contribution to Combined (DiffDir x DiffCol, ..., Emit, Env) scaled by
  the display exposure: linear variance per sample;
- "disp": the same, each pixel weighted by the squared slope of the display transform (sRGB,
  clipped at 1) at the reference's pixel: the pass's share of the bench's display-space "pair x
  spp" (bench/caustics_noise.py) to first order. The passes' "disp" add up to Combined's where
  the passes are uncorrelated.
"Combined pair" is bench/caustics_noise.py's pair x spp (display space, exact). The exposure and
the slope come from the SHGI reference cached by bench/equal_time.py (or, without it, from the
mean of both SHGI renders). "mean" is the pass's mean contribution (exposure-scaled), to check
the renderers agree on where the light is. The slope is the full scene's: with fewer bounces
or lights the image is darker than the reference and "disp" only ranks the passes. --shgi-set
sets PathTracerSettings fields on SHGI's renders (hypothesis tests: e.g.
russian_roulette_depth=100; an enum by its value, roulette_survival=1); --lights and
--no-specular change the scene in both renderers.
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

# Light passes and the colour pass each is multiplied by in Combined (None: added as is).
LIGHT_PASSES = (("DiffDir", "DiffCol"), ("DiffInd", "DiffCol"), ("GlossDir", "GlossCol"),
                ("GlossInd", "GlossCol"), ("TransDir", "TransCol"), ("TransInd", "TransCol"),
                ("Emit", None), ("Env", None))
# View-layer toggles of those passes (Cycles writes only what the view layer enables).
VIEW_LAYER_FLAGS = ("use_pass_diffuse_direct", "use_pass_diffuse_indirect",
                    "use_pass_diffuse_color", "use_pass_glossy_direct",
                    "use_pass_glossy_indirect", "use_pass_glossy_color",
                    "use_pass_transmission_direct", "use_pass_transmission_indirect",
                    "use_pass_transmission_color", "use_pass_emit", "use_pass_environment")
# sRGB's linear segment ends here (IEC 61966-2-1).
SRGB_LINEAR_END = 0.0031308


def parse_args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scene", default="sun_room")
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--max-bounces", default=str(equal_time.BOUNCES["max_bounces"]),
                        help="comma-separated Light Paths > Max Bounces, one row group each")
    parser.add_argument("--resolution", default="200x150", help="WxH pixels")
    parser.add_argument("--cache", default=os.path.join(REPO_ROOT, "build", "equal_time_cache"))
    parser.add_argument("--shgi-set", default="",
                        help="comma-separated field=value of shgi.PathTracerSettings for SHGI's "
                             "renders (numbers)")
    parser.add_argument("--no-specular", action="store_true",
                        help="every Principled BSDF's Specular IOR Level 0 (no glossy lobe on "
                             "dielectrics) in both renderers")
    parser.add_argument("--no-cycles", action="store_true", help="SHGI's rows only")
    parser.add_argument("--lights", default="all", choices=("all", "sun", "world"),
                        help="which emitters stay on (the others get strength 0): the noise of "
                             "the sun's light alone, or of the world's (sky) alone; the exposure "
                             "stays the whole scene's")
    args = parser.parse_args(argv)
    args.max_bounces = [int(n) for n in args.max_bounces.split(",")]
    args.width, args.height = (int(x) for x in args.resolution.lower().split("x"))
    args.shgi_set = dict(item.split("=") for item in args.shgi_set.split(",") if item)
    return args


def srgb_slope(linear):
    """d sRGB / d linear at `linear` (>= 0), 0 where the display clips (above 1)."""
    x = np.maximum(linear, SRGB_LINEAR_END)
    slope = np.where(linear <= SRGB_LINEAR_END, 12.92, 1.055 / 2.4 * x ** (1.0 / 2.4 - 1.0))
    return np.where(linear > 1.0, 0.0, slope)


def contributions(passes):
    """{pass: (H, W, 3) its contribution to Combined} and Combined itself."""
    out = {}
    for name, color in LIGHT_PASSES:
        if name not in passes:
            continue
        light = passes[name][..., :3]
        out[name] = light * passes[color][..., :3] if color else light
    out["Combined"] = passes["Combined"][..., :3]
    return out


def noise_rows(first, second, exposure, weight, samples):
    """{pass: (lin, disp, mean)} of two renders' contributions (see the module docstring)."""
    from shgi import metrics

    rows = {}
    for name in first:
        half_square = 0.5 * ((first[name] - second[name]) * exposure) ** 2
        mean = 0.5 * float((first[name] + second[name]).mean()) * exposure
        rows[name] = (float(half_square.mean()) * samples,
                      float((half_square * weight).mean()) * samples, mean)
    pair = metrics.display(first["Combined"], exposure) - metrics.display(second["Combined"],
                                                                          exposure)
    rows["Combined pair"] = (float("nan"), 0.5 * float((pair ** 2).mean()) * samples,
                             float("nan"))
    return rows


def shgi_renders(native, scene, args, max_bounces):
    import shgi
    from shgi_blender import settings

    renders = []
    start = time.process_time()
    for seed in (equal_time.SEED, equal_time.SEED + 1):
        tracer = settings.path_tracer_settings(scene.shgi, shgi)
        tracer.samples = args.samples
        tracer.max_bounces = max_bounces
        for field, value in args.shgi_set.items():
            current = getattr(tracer, field)
            setattr(tracer, field, type(current)(int(value)) if not isinstance(current, float)
                    else float(value))
        tracer.seed = seed
        renders.append(shgi.render_path_traced(native, tracer))
    cpu = time.process_time() - start
    return renders, cpu


def cycles_renders(scene, args, max_bounces):
    import blender_test_setup as setup

    exr = os.path.join(REPO_ROOT, "build", f"noise_by_pass_{os.getpid()}.exr")
    equal_time.use_cycles(scene, args.samples, False)
    scene.cycles.max_bounces = max_bounces
    renders = []
    for seed in (equal_time.SEED, equal_time.SEED + 1):
        scene.cycles.seed = seed
        equal_time.render_f12(scene, "CYCLES", exr)
        renders.append(setup.read_render_exr(exr))
    scene.cycles.seed = equal_time.SEED
    os.remove(exr)
    return renders


def main():
    args = parse_args()
    from shgi_blender.export.scene_export import export_scene

    scene = equal_time.build_scene(args.scene, args.width, args.height)
    if args.lights == "sun":
        scene.world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    elif args.lights == "world":
        for light in bpy.data.lights:
            if light.type == "SUN":
                light.energy = 0.0
    if args.no_specular:
        for material in bpy.data.materials:
            if material.node_tree is not None:
                for node in material.node_tree.nodes:
                    if node.type == "BSDF_PRINCIPLED":
                        node.inputs["Specular IOR Level"].default_value = 0.0
    for flag in VIEW_LAYER_FLAGS:
        setattr(bpy.context.view_layer, flag, True)
    native = export_scene(bpy.context.evaluated_depsgraph_get(), scene).scene
    native.commit()
    key = (f"{args.scene}_{args.width}x{args.height}_shgi_clamp{scene.shgi.clamp_indirect:g}"
           f"{equal_time.shgi_reference_tag(scene.shgi)}_{equal_time.REFERENCE_SAMPLES}spp")
    path = equal_time.reference_path(args.cache, key)
    reference = np.load(path) if os.path.exists(path) else None
    print(f"{args.scene} {args.width}x{args.height}, {args.samples} spp, lights {args.lights}, "
          "SHGI settings "
          f"{args.shgi_set or 'as the add-on'}; exposure from "
          f"{path if reference is not None else 'the SHGI renders'}")
    from shgi import metrics

    for max_bounces in args.max_bounces:
        shgi_pair, cpu = shgi_renders(native, scene, args, max_bounces)
        if reference is None:
            reference = 0.5 * (shgi_pair[0]["Combined"][..., :3] +
                               shgi_pair[1]["Combined"][..., :3])
        exposure = metrics.auto_exposure(reference)
        weight = srgb_slope(reference[..., :3] * exposure) ** 2
        results = {"shgi": noise_rows(*(contributions(p) for p in shgi_pair), exposure, weight,
                                      args.samples)}
        if not args.no_cycles:
            results["cycles"] = noise_rows(
                *(contributions(p) for p in cycles_renders(scene, args, max_bounces)), exposure,
                weight, args.samples)
        print(f"\nmax_bounces {max_bounces}: SHGI CPU {1e3 * cpu / (2 * args.samples):.1f} "
              "ms/spp")
        print(f"{'pass':14s} " + " ".join(f"{r + ' ' + c:>15s}" for r in results
                                          for c in ("lin", "disp", "mean"))
              + ("  disp SHGI/Cycles" if len(results) == 2 else ""))
        for name in results["shgi"]:
            cells = [results[r][name] for r in results]
            line = f"{name:14s} " + " ".join(f"{v:15.5f}" for cell in cells for v in cell)
            if len(cells) == 2 and cells[1][1] > 0.0:
                line += f"  {cells[0][1] / cells[1][1]:8.3f}"
            print(line)


if __name__ == "__main__":
    main()
