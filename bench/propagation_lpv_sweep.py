#!/usr/bin/env python3
"""The light propagation volume against the path tracer for named settings (issue 51's
agreement target: DiffInd x DiffCol mean within 10% of the path tracer's on the Cornell box, the
sun room and the two rooms). Per configuration, order and scene: that ratio and the Combined
PSNR (16-spp preview). The references are test_propagation.py's (the Cornell box and the sun room
at scale 0.25, 2048 spp; the two rooms at 0.5, 512 spp), cached in --cache between runs.

    PYTHONPATH=build/python python3 bench/propagation_lpv_sweep.py [--orders 1 2]
        [--configs NAME ...]   (default: all of CONFIGS) [--cost] [--seeds 5 6 7 8]
"""

import argparse
import pathlib
import sys
import time

import numpy as np

import shgi
from shgi.metrics import psnr

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)

SCENES = {"cornell_box": (0.25, 2048), "sun_room": (0.25, 2048), "two_rooms": (0.5, 512)}
# PropagationSettings' defaults before settings layout 6 (the seed's method: rescaled lobes along
# the face normals, 8 steps, no leak correction); the configurations below start from them. The
# other propagation benches import it to measure what their tables say.
SEED = dict(steps=8, damping=False, occlude_first_step=False, drop_outward_vpls=False,
            travel_reinjection=False, unclamped_transfer=False, clamp_at_surfaces=False,
            windowed_reinjection=False, light_share_uniform=0.0)
CORRECTIONS = dict(SEED, occlude_first_step=True, drop_outward_vpls=True)
TRAVEL = dict(CORRECTIONS, travel_reinjection=True, damping=True)
UNCLAMPED = dict(TRAVEL, unclamped_transfer=True)
AT_SURFACES = dict(UNCLAMPED, clamp_at_surfaces=True, clamp_per_transfer=False)
CONFIGS = {
    # PropagationSettings' defaults, and those before settings layout 6.
    "defaults": {},
    "seed": SEED,
    # The HOLPV's re-injected beams with band 2 windowed (x 4/5; the LPV is unchanged): the
    # default; "plain" without the window (the default until 2026-11-29).
    "windowed": dict(windowed_reinjection=True),
    "plain": dict(windowed_reinjection=False),
    "plain_extended": dict(windowed_reinjection=False, extend_to_bounds=True),
    # The cells outside the scene's bounds given the light of the inside cells next to them.
    "extended": dict(extend_to_bounds=True),
    "windowed_extended": dict(windowed_reinjection=True, extend_to_bounds=True),
    # Finer volumes, light carried as many cells (the same distance in metres), plain and windowed.
    **{f"r{r}": dict(windowed_reinjection=False, resolution=r, distance=float(r))
       for r in (48, 64)},
    **{f"windowed_r{r}": dict(windowed_reinjection=True, resolution=r, distance=float(r))
       for r in (48, 64)},
    # The three changes for closed rooms (docs/methods.md, "The furnace's scale"), alone
    # and together: the furnace's radiance scale, propagation until the light settles (at most
    # 96 cells, stopping once 1% of the light is in flight), glossy VPLs (with their own glossy
    # budget); "fix" is all three with the strip along the bounds filled.
    "furnace": dict(furnace_scale=True),
    "settled": dict(distance=96.0, settle_fraction=0.01),
    "glossy": dict(glossy_vpls=True, glossy_bounces=4),
    "glossy_shared": dict(glossy_vpls=True),
    "fix": dict(furnace_scale=True, distance=96.0, settle_fraction=0.01, glossy_vpls=True,
                glossy_bounces=4, extend_to_bounds=True),
    "fix_unextended": dict(furnace_scale=True, distance=96.0, settle_fraction=0.01,
                           glossy_vpls=True, glossy_bounces=4),
    "fix_linear": dict(furnace_scale=True, distance=96.0, settle_fraction=0.01,
                       glossy_vpls=True, glossy_bounces=4, extend_to_bounds=True,
                       clamp_at_surfaces=False),
    "fix_linear_plain": dict(furnace_scale=True, distance=96.0, settle_fraction=0.01,
                             glossy_vpls=True, glossy_bounces=4, extend_to_bounds=True,
                             clamp_at_surfaces=False, windowed_reinjection=False),
    # The fix with clamp_per_transfer: only the transfers a wall stops in part clamped (the
    # HOLPV's light stays at the rooms' edges; docs/methods.md, "Clamped per transfer").
    "fix_per_transfer": dict(furnace_scale=True, distance=96.0, settle_fraction=0.01,
                             glossy_vpls=True, glossy_bounces=4, extend_to_bounds=True,
                             clamp_per_transfer=True),
    # The defaults before 2026-11-30: the HOLPV clamped at walls (clamp_per_transfer off) and
    # the photons shared among the lamps by flux alone (light_share_uniform 0); "per_transfer"
    # is the HOLPV clamped per transfer with the photons still by flux.
    "by_flux_at_walls": dict(clamp_per_transfer=False, light_share_uniform=0.0),
    "per_transfer": dict(clamp_per_transfer=True, light_share_uniform=0.0),
    # Both with 4x the photons: the two rooms' dim room, all the camera sees, gets 1% of them
    # by flux (its lamp's share), and its VPLs' noise is most of the orders' difference there
    # (docs/methods.md, "The two rooms' VPLs").
    "photons_400k": dict(clamp_per_transfer=False, light_share_uniform=0.0, photons=400000),
    "per_transfer_400k": dict(clamp_per_transfer=True, light_share_uniform=0.0,
                              photons=400000),
    "photons_1600k": dict(clamp_per_transfer=False, light_share_uniform=0.0, photons=1600000),
    "per_transfer_1600k": dict(clamp_per_transfer=True, light_share_uniform=0.0,
                               photons=1600000),
    # The photons' lamp share (docs/methods.md, "A share of the photons per lamp"): the default
    # 0.5, and others; "share_at_walls" the HOLPV clamped at walls with the default share.
    **{f"share_{u}": dict(light_share_uniform=u) for u in (0.25, 0.5, 0.75, 1.0)},
    "share_at_walls": dict(clamp_per_transfer=False),
    "defaults_400k": dict(photons=400000),
    # The fix with every transfer clamped then rescaled (LobeClamp::Rescaled, the seed's; the
    # linear transfers carry the windowed beams' negative lobes, which darken the sun room's
    # floor around its sun patch; docs/methods.md, "The sun room's floor").
    "fix_rescaled": dict(furnace_scale=True, distance=96.0, settle_fraction=0.01,
                         glossy_vpls=True, glossy_bounces=4, extend_to_bounds=True,
                         unclamped_transfer=False),
    "fix_rescaled_undamped": dict(furnace_scale=True, distance=96.0, settle_fraction=0.01,
                                  glossy_vpls=True, glossy_bounces=4, extend_to_bounds=True,
                                  unclamped_transfer=False, damping=False),
    "rescaled": dict(unclamped_transfer=False),
    "fix_settle_0.001": dict(furnace_scale=True, distance=192.0, settle_fraction=0.001,
                             glossy_vpls=True, glossy_bounces=4, extend_to_bounds=True),
    "fix_linear_settle_0.001": dict(furnace_scale=True, distance=192.0, settle_fraction=0.001,
                                    glossy_vpls=True, glossy_bounces=4, extend_to_bounds=True,
                                    clamp_at_surfaces=False),
    # Clamped at walls, the steps from a distance in cells (distance / the stencil's cells per
    # step: 30 cells are 33 LPV and 21 HOLPV steps).
    **{f"at_surfaces_d{d}": dict(AT_SURFACES, resolution=32, steps=0, distance=float(d))
       for d in (24, 26, 28, 30, 32, 34, 36)},
    "at_surfaces_r32_s24": dict(AT_SURFACES, resolution=32, steps=24),
    "at_surfaces_r32_s28": dict(AT_SURFACES, resolution=32, steps=28),
    "at_surfaces_r32_s32": dict(AT_SURFACES, resolution=32, steps=32),
    "at_surfaces_r32_s36": dict(AT_SURFACES, resolution=32, steps=36),
    "at_surfaces_r32_s40": dict(AT_SURFACES, resolution=32, steps=40),
    "unclamped_r32_s24": dict(UNCLAMPED, resolution=32, steps=24),
    "unclamped_r32_s28": dict(UNCLAMPED, resolution=32, steps=28),
    "unclamped_r32_s32": dict(UNCLAMPED, resolution=32, steps=32),
    "unclamped_r24_s18": dict(UNCLAMPED, resolution=24, steps=18),
    "unclamped_r16_s12": dict(UNCLAMPED, resolution=16, steps=12),
    "travel_r32_s32": dict(TRAVEL, resolution=32, steps=32),
    "travel_r24_s24": dict(TRAVEL, resolution=24, steps=24),
    "travel_r16_s16": dict(TRAVEL, resolution=16, steps=16),
    "travel_r16_s12": dict(TRAVEL, resolution=16, steps=12),
}
# The configurations measured before 2026-11-30 keep the defaults of then, so that the figures
# docs/methods.md quotes for them stay reproducible: the HOLPV clamped at walls and the photons
# shared among the lamps by flux alone (unless they set these themselves).
CURRENT = {"defaults", "share_at_walls", "defaults_400k"} | {n for n in CONFIGS
                                                             if n.startswith("share_")}
for _name, _config in CONFIGS.items():
    if _name not in CURRENT:
        _config.setdefault("clamp_per_transfer", False)
        _config.setdefault("light_share_uniform", 0.0)


def indirect(passes):
    return float((np.asarray(passes["DiffInd"]) * np.asarray(passes["DiffCol"])).mean())


def reference(name, cache):
    scale, spp = SCENES[name]
    scene = getattr(scenes, name)(scale).scene
    scene.commit()
    path = cache / f"{name}_{scale}_{spp}.npz"
    if path.exists():
        return scene, dict(np.load(path))
    ref = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=spp, seed=11))
    passes = {key: np.asarray(ref[key]) for key in ("Combined", "DiffInd", "DiffCol")}
    cache.mkdir(parents=True, exist_ok=True)
    np.savez(path, **passes)
    return scene, passes


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--orders", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--configs", nargs="+", default=list(CONFIGS))
    parser.add_argument("--cost", action="store_true",
                        help="also the steps taken and the pass's CPU seconds (all threads)")
    parser.add_argument("--cache", type=pathlib.Path, default=pathlib.Path("/tmp/shgi_lpv_refs"))
    parser.add_argument("--seeds", type=int, nargs="+", default=[5],
                        help="the volume's and the preview's seeds, a row each")
    args = parser.parse_args()
    refs = {name: reference(name, args.cache) for name in SCENES}
    for config in args.configs:
        for order, seed in ((o, s) for o in args.orders for s in args.seeds):
            row = f"{config:<20} order {order}:"
            if args.seeds != [5]:
                row += f" seed {seed}"
            for name, (scene, ref) in refs.items():
                volume = shgi.PropagationVolume(scene, shgi.PropagationSettings(
                    seed=seed, order=order, **CONFIGS[config]))
                cpu = time.process_time()
                volume.refine()
                cpu = time.process_time() - cpu
                steps = sum(stage.startswith("propagation_step_")
                            for stage, _ in volume.stage_seconds)
                preview, _ = shgi.render_preview(scene, volume.current_field(),
                                                 shgi.PreviewSettings(seed=seed))
                row += (f"  {name} {indirect(preview) / indirect(ref):.3f}"
                        f" {psnr(ref['Combined'], preview['Combined']):5.2f} dB")
                if args.cost:
                    row += f" ({steps} steps, {cpu:.1f} s CPU)"

            print(row, flush=True)


if __name__ == "__main__":
    main()
