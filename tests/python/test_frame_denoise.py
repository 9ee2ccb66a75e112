"""Tests of shgi.frame_denoise: OpenImageDenoise on rendered frames with albedo and normal guides.

The subject is a low-sample frame of examples/scenes.py's Cornell box (path traced, and the probe
grid's preview), scored against a high-sample render of the same scene. What must hold: the light
is kept (mean within 1% of the noisy frame's), the frame gets much closer to the reference, the
world seen directly is left as it was, nothing non-finite comes out, the same input gives the same
output, and a cancel or a Ctrl-C stops the network.
"""

import importlib.util
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import shgi
from conftest import BUILD_PYTHON, REPO_ROOT
from scene_support import committed
from shgi import metrics
from shgi import frame_denoise
from shgi.frame_denoise import (ALBEDO_PASS, CLEAN_GUIDE_SAMPLES, NOISY_PASS, NORMAL_PASS,
                                PREFILTERS, SPECULAR_CLEAN_GUIDE_SAMPLES, SPECULAR_GUIDE_SHARE,
                                FrameDenoiser, denoise_frame, direct_share, guide_images,
                                prefilter_for, specular_guide_share)

sys.path.insert(0, str(REPO_ROOT / "examples"))
import scenes  # noqa: E402  (examples/scenes.py)

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("pyoidn") is None,
    reason="pyoidn (OpenImageDenoise) is not installed for this Python: run `make deps`")

NOISY_SAMPLES = 4
REFERENCE_SAMPLES = 512
# What denoising a 4-spp Cornell box must gain at least, in PSNR against the reference (measured:
# 16-17 dB for every prefilter).
MIN_GAIN_DB = 10.0
# The light a denoiser may add or remove, as a share of the frame's mean (the 1%).
MEAN_TOLERANCE = 0.01


@pytest.fixture(scope="module")
def cornell():
    return committed(scenes.cornell_box(scale=0.5))


@pytest.fixture(scope="module")
def reference(cornell):
    return shgi.render_path_traced(
        cornell, shgi.PathTracerSettings(samples=REFERENCE_SAMPLES, seed=7))["Combined"]


@pytest.fixture(scope="module")
def noisy(cornell):
    return shgi.render_path_traced(cornell, shgi.PathTracerSettings(samples=NOISY_SAMPLES,
                                                                    seed=1))


def mean_ratio(denoised, noisy):
    return float(denoised[..., :3].mean() / noisy[..., :3].mean())


@pytest.mark.parametrize("prefilter", PREFILTERS)
def test_a_denoised_path_traced_frame_keeps_its_light_and_nears_the_reference(
        noisy, reference, prefilter):
    out = denoise_frame(noisy, prefilter=prefilter)
    assert abs(mean_ratio(out["Combined"], noisy["Combined"]) - 1.0) < MEAN_TOLERANCE
    gain = (metrics.psnr(reference, out["Combined"])
            - metrics.psnr(reference, noisy["Combined"]))
    assert gain > MIN_GAIN_DB, f"{prefilter}: {gain:.1f} dB"
    assert np.isfinite(out["Combined"]).all()
    # Alpha is the noisy frame's; the passes Cycles writes beside a denoised Combined are there.
    np.testing.assert_array_equal(out["Combined"][..., 3], noisy["Combined"][..., 3])
    np.testing.assert_array_equal(out[NOISY_PASS], noisy["Combined"])
    assert out[ALBEDO_PASS].shape == out[NORMAL_PASS].shape == noisy["Combined"].shape[:2] + (3,)


def test_a_denoised_probe_grid_preview_keeps_its_light(cornell, reference):
    grid = shgi.ProbeGrid(cornell, shgi.ProbeGridSettings(rays_per_probe=64))
    grid.update()
    passes, _ = shgi.render_preview(cornell, grid.field(),
                                    shgi.PreviewSettings(samples=NOISY_SAMPLES, seed=1))
    out = denoise_frame(passes)
    assert abs(mean_ratio(out["Combined"], passes["Combined"]) - 1.0) < MEAN_TOLERANCE
    assert metrics.psnr(reference, out["Combined"]) > metrics.psnr(reference, passes["Combined"])


def pixel_filtered(cornell, pixel_filter, width, samples, seed):
    settings = shgi.PathTracerSettings(samples=samples, seed=seed)
    settings.pixel_filter = getattr(shgi.PixelFilter, pixel_filter)
    settings.filter_width = width
    return shgi.render_path_traced(cornell, settings)


def test_the_direct_light_around_the_network_follows_the_pixel_filter_and_the_samples():
    counts = (1, 2, 4, 16, 128, 4096)
    # A filter that keeps each sample in its pixel: more goes around as the edge's noise falls.
    box = [direct_share(n) for n in counts]
    assert box == sorted(box) and box[0] >= 0.75 and box[-1] > 0.999
    # One that spreads it: less, as the network rebuilds the emitter's soft fringe.
    spread = [direct_share(n, "BLACKMAN_HARRIS", 1.5) for n in counts]
    assert spread == sorted(spread, reverse=True) and spread[0] >= 0.75 and spread[-1] < 0.01
    assert direct_share(None) == direct_share(1)
    # What matters is whether a sample can land outside its pixel.
    assert direct_share(16, "BOX", 2.0) == direct_share(16, "GAUSSIAN", 1.5) == spread[3]
    assert direct_share(16, "GAUSSIAN", 0.3) == direct_share(16, "BOX", 0.5) == box[3]
    for kwargs, setting in (({"pixel_filter": "TENT"}, "pixel_filter"),
                            ({"filter_width": 0.0}, "filter_width"),
                            ({"filter_width": float("nan")}, "filter_width"),
                            ({"samples": 0}, "samples"), ({"samples": 2.5}, "samples")):
        with pytest.raises(ValueError, match=setting):
            direct_share(**kwargs)
    with pytest.raises(ValueError, match="filter_width"):
        FrameDenoiser(filter_width=11.0)


@pytest.mark.parametrize("pixel_filter, width", (("BOX", 1.0), ("BLACKMAN_HARRIS", 1.5)))
@pytest.mark.parametrize("samples", (1, 4, 16))
def test_either_pixel_filter_keeps_the_light_at_every_sample_count(cornell, pixel_filter, width,
                                                                    samples):
    """The network's halo around the lamp, which the direct light's split holds down, is
    largest at 1 spp (unsplit: 3-4% more light)."""
    frame = pixel_filtered(cornell, pixel_filter, width, samples, seed=1)
    out = denoise_frame(frame, prefilter="AUTO", samples=samples, pixel_filter=pixel_filter,
                        filter_width=width)["Combined"]
    assert np.isfinite(out).all()
    assert abs(mean_ratio(out, frame["Combined"]) - 1.0) < MEAN_TOLERANCE


# With Blackman-Harris 1.5 at 16 spp, taking all the direct light around the network (the rule
# before the split followed the pixel filter) scored 36.26 dB, none of it 38.63, the share 38.31
# (docs/equal-time.md, "The direct light's split").
SPREAD_SPLIT_GAIN_DB = 1.0


def test_a_spreading_pixel_filter_leaves_the_emitters_fringe_to_the_network(cornell,
                                                                           monkeypatch):
    reference = pixel_filtered(cornell, "BLACKMAN_HARRIS", 1.5, REFERENCE_SAMPLES,
                               seed=7)["Combined"]
    frame = pixel_filtered(cornell, "BLACKMAN_HARRIS", 1.5, 16, seed=1)

    def score():
        return metrics.psnr(reference, denoise_frame(
            frame, prefilter="AUTO", samples=16, pixel_filter="BLACKMAN_HARRIS",
            filter_width=1.5)["Combined"])

    share = score()
    monkeypatch.setattr(frame_denoise, "direct_share", lambda *args: 1.0)
    assert share > score() + SPREAD_SPLIT_GAIN_DB


def test_the_guides_are_the_renderers_guide_passes(noisy):
    albedo, normal, background = guide_images(noisy)
    np.testing.assert_array_equal(albedo, np.clip(noisy[ALBEDO_PASS], 0.0, 1.0))
    np.testing.assert_array_equal(normal, noisy[NORMAL_PASS])
    # No surface of the Cornell box is specular, so the guides are the first hit's: its closure
    # weights and its normal (render/film.h).
    summed = noisy["DiffCol"] + noisy["GlossCol"] + noisy["TransCol"]
    np.testing.assert_allclose(noisy[ALBEDO_PASS], summed, rtol=0, atol=1e-5)
    np.testing.assert_array_equal(noisy[NORMAL_PASS], noisy["Normal"])
    # The camera sees the open box's front edge and the black world around it: those pixels,
    # and only they, hold no surface.
    assert 0 < background.sum() < background.size
    assert (albedo[background] == 0).all() and (normal[background] == 0).all()
    assert (noisy["Depth"][~background] < 1e9).all()


def test_passes_without_the_guide_passes_give_the_first_hits_guides(noisy):
    first_hit = {name: image for name, image in noisy.items()
                 if name not in (ALBEDO_PASS, NORMAL_PASS)}
    albedo, normal, _ = guide_images(first_hit)
    summed = noisy["DiffCol"] + noisy["GlossCol"] + noisy["TransCol"]
    np.testing.assert_array_equal(albedo, np.clip(summed, 0.0, 1.0))
    np.testing.assert_array_equal(normal, noisy["Normal"])


def test_the_world_seen_directly_is_left_as_it_was():
    builder = scenes.SceneBuilder()
    # A grey floor under a bright blue sky, seen from above at a slant: half the frame is sky.
    builder.part("floor", scenes.quad((-2, -2, 0), (4, 0, 0), (0, 4, 0)), "grey", (0.5,) * 3)
    builder.scene.set_world(shgi.World(color=(0.2, 0.4, 1.0), strength=2.0))
    builder.camera((0, -5, 1.2), (0, 0, 0.6), 35.0, 96, 64, 1.0)
    scene = committed(builder)
    passes = shgi.render_path_traced(scene, shgi.PathTracerSettings(samples=2, seed=3))
    _, _, background = guide_images(passes)
    assert 0 < background.sum() < background.size
    out = denoise_frame(passes)
    np.testing.assert_array_equal(out["Combined"][background], passes["Combined"][background])


def test_non_finite_input_gives_finite_output(noisy):
    broken = dict(noisy, Combined=noisy["Combined"].copy())
    broken["Combined"][3, 5, 0] = np.nan
    broken["Combined"][7, 2, 1] = np.inf
    out = denoise_frame(broken, prefilter="FAST")
    assert np.isfinite(out["Combined"]).all()


def test_the_same_frame_denoises_to_the_same_bits(noisy):
    with FrameDenoiser("BALANCED", "FAST") as denoiser:
        first = denoiser.denoise(noisy)["Combined"]
        again = denoiser.denoise(noisy)["Combined"]
    np.testing.assert_array_equal(first, again)
    np.testing.assert_array_equal(first, denoise_frame(noisy, "BALANCED", "FAST")["Combined"])


def test_a_frame_without_its_guides_is_refused_naming_them(noisy):
    with pytest.raises(ValueError, match="Normal.*combined_only"):
        denoise_frame({"Combined": noisy["Combined"], "DiffCol": noisy["DiffCol"],
                       "GlossCol": noisy["GlossCol"], "TransCol": noisy["TransCol"]})
    only_colour = denoise_frame({"Combined": noisy["Combined"]}, guides="NONE")
    assert ALBEDO_PASS not in only_colour and NORMAL_PASS not in only_colour


@pytest.mark.parametrize("name, value", [("quality", "BEST"), ("prefilter", "SLOW"),
                                         ("guides", "DEPTH")])
def test_bad_choices_are_refused_naming_them(name, value):
    with pytest.raises(ValueError, match=f"{name} '{value}': use one of"):
        FrameDenoiser(**{name: value})


def test_a_cancelled_progress_stops_the_network(noisy):
    progress = shgi.Progress()
    progress.cancel()
    with FrameDenoiser() as denoiser, pytest.raises(shgi.Cancelled, match="denoising"):
        denoiser.denoise(noisy, progress)


def test_automatic_prefilter_is_fast_for_noisy_guides_and_none_for_clean_ones(noisy):
    assert [prefilter_for("AUTO", samples) for samples in (None, 1, CLEAN_GUIDE_SAMPLES - 1,
                                                           CLEAN_GUIDE_SAMPLES, 4096)] == [
        "FAST", "FAST", "FAST", "NONE", "NONE"]
    assert all(prefilter_for(name, 1) == name for name in PREFILTERS if name != "AUTO")
    with FrameDenoiser("BALANCED", "AUTO") as auto:
        for samples, same_as in ((None, "FAST"), (NOISY_SAMPLES, "FAST"),
                                 (CLEAN_GUIDE_SAMPLES, "NONE")):
            np.testing.assert_array_equal(
                auto.denoise(noisy, samples=samples)["Combined"],
                denoise_frame(noisy, "BALANCED", same_as, samples=samples)["Combined"])
        # Before it knows where a render stops, a time limit plans for the longer of the two.
        assert auto.estimate_seconds(640, 360) == max(
            FrameDenoiser("BALANCED", name).estimate_seconds(640, 360) for name in ("FAST", "NONE"))


def test_automatic_prefilter_waits_longer_for_guides_seen_through_glass(noisy):
    """Guides followed through clear glass stay noisy longer (docs/equal-time.md): a frame of
    which more than SPECULAR_GUIDE_SHARE sees its guides so runs Fast up to
    SPECULAR_CLEAN_GUIDE_SAMPLES."""
    builder = scenes.cornell_box(scale=0.25)
    builder.material("glass", (1.0, 1.0, 1.0), transmission=1.0, roughness=0.0, ior=1.45)
    builder.part("glass_block", scenes.box((-0.45, 0.1, 0.0), 0.5, 0.3, 0.9, np.radians(25)),
                 "glass", (1.0, 1.0, 1.0))
    frame = shgi.render_path_traced(committed(builder),
                                    shgi.PathTracerSettings(samples=2, seed=1))
    share = specular_guide_share(frame)
    assert SPECULAR_GUIDE_SHARE < share < 0.5, share  # measured 0.13
    assert specular_guide_share(noisy) == 0.0  # no specular surface in the plain box
    # Without the first hit's passes (the viewport's) nothing is known: the plain threshold.
    assert specular_guide_share({name: image for name, image in frame.items()
                                 if name != "DiffCol"}) == 0.0
    assert [prefilter_for("AUTO", samples, share) for samples in (
        CLEAN_GUIDE_SAMPLES, SPECULAR_CLEAN_GUIDE_SAMPLES - 1, SPECULAR_CLEAN_GUIDE_SAMPLES)] == [
        "FAST", "FAST", "NONE"]
    with FrameDenoiser("BALANCED", "AUTO") as auto:
        for samples, same_as in ((CLEAN_GUIDE_SAMPLES, "FAST"),
                                 (SPECULAR_CLEAN_GUIDE_SAMPLES, "NONE")):
            np.testing.assert_array_equal(
                auto.denoise(frame, samples=samples)["Combined"],
                denoise_frame(frame, "BALANCED", same_as, samples=samples)["Combined"])


# Clean enough guides (16 samples of the Cornell box) let the High network run: measured 40.04 dB
# (Automatic, i.e. None) against Fast's 39.53 and Accurate's 40.05 (4, 8, 32 samples: the same
# order, Accurate above the others only at 4).
CLEAN_GUIDES_SAMPLES_TESTED = 16
MIN_HIGH_NETWORK_GAIN_DB = 0.25
ACCURATE_TOLERANCE_DB = 0.1


def test_automatic_prefilter_with_clean_guides_matches_accurate_and_beats_fast(cornell,
                                                                               reference):
    frame = shgi.render_path_traced(cornell, shgi.PathTracerSettings(
        samples=CLEAN_GUIDES_SAMPLES_TESTED, seed=1))
    score = {name: metrics.psnr(reference, denoise_frame(
        frame, prefilter=name, samples=CLEAN_GUIDES_SAMPLES_TESTED)["Combined"])
        for name in ("FAST", "AUTO", "ACCURATE")}
    assert score["AUTO"] > score["FAST"] + MIN_HIGH_NETWORK_GAIN_DB, score
    assert score["AUTO"] > score["ACCURATE"] - ACCURATE_TOLERANCE_DB, score


def test_the_time_estimate_follows_the_last_denoise(noisy):
    with FrameDenoiser("FAST", "NONE", "ALBEDO") as denoiser:
        guess = denoiser.estimate_seconds(640, 360)
        assert guess > 0.0
        denoiser.denoise(noisy)
        height, width = noisy["Combined"].shape[:2]
        measured = denoiser.estimate_seconds(width, height)
        # A frame four times larger is estimated four times longer, a smaller one no shorter.
        assert denoiser.estimate_seconds(2 * width, 2 * height) == pytest.approx(4 * measured)
        assert denoiser.estimate_seconds(width // 2, height // 2) == measured


def test_choices_not_run_yet_are_estimated_from_the_last_denoise_of_others(monkeypatch):
    """A render's first denoise with new choices (Automatic's None after its Fast ones) is
    planned from the table, or from the denoises this process ran, scaled by the table's rates,
    when that is longer (a loaded machine)."""
    from shgi import frame_denoise

    pixels = 128 * 128
    rates = {prefilter: frame_denoise.ESTIMATED_RATES[(prefilter, "HIGH")]
             for prefilter in ("FAST", "NONE")}
    table = pixels * rates["NONE"] + frame_denoise.SETUP_SECONDS
    monkeypatch.setattr(frame_denoise, "MEASURED", {})
    with FrameDenoiser("HIGH", "NONE") as denoiser:
        assert denoiser.estimate_seconds(128, 128) == pytest.approx(table)
        for fast_seconds in (0.05, 1.0):
            frame_denoise.MEASURED[("HIGH", "FAST", "ALBEDO_NORMAL")] = (pixels, fast_seconds)
            # A frame twice as wide is planned twice as long from the same measurement.
            for width in (128, 256):
                scaled = fast_seconds * rates["NONE"] / rates["FAST"] * width / 128
                assert denoiser.estimate_seconds(width, 128) == pytest.approx(
                    max(width / 128 * pixels * rates["NONE"] + frame_denoise.SETUP_SECONDS,
                        scaled))
        assert denoiser.estimate_seconds(128, 128) > table  # 1 s of Fast: a slow machine


def test_prepare_sets_up_every_network_a_denoise_may_run(noisy, monkeypatch):
    """A render with a Time Limit prepares its denoiser before it samples: with Automatic both
    networks (Fast and None) are then set up for the frame's size, the denoise that follows
    sets nothing up again and gives the same bits, and the plan no longer counts a setup."""
    from shgi import frame_denoise

    monkeypatch.setattr(frame_denoise, "MEASURED", {})
    height, width = noisy["Combined"].shape[:2]
    with FrameDenoiser("HIGH", "AUTO") as denoiser:
        unprepared = denoiser.estimate_seconds(width, height)
        denoiser.prepare(width, height)
        assert denoiser.estimate_seconds(width, height) == pytest.approx(
            unprepared - frame_denoise.SETUP_SECONDS)
        set_up = denoiser._setup

        def no_new_setup(flt, shape, slots):
            assert denoiser._buffers[id(flt)][0] == (shape, tuple(slots)), slots
            return set_up(flt, shape, slots)

        monkeypatch.setattr(denoiser, "_setup", no_new_setup)
        for samples in (NOISY_SAMPLES, CLEAN_GUIDE_SAMPLES):
            out = denoiser.denoise(noisy, samples=samples)["Combined"]
            np.testing.assert_array_equal(out, denoise_frame(
                noisy, "HIGH", prefilter_for("AUTO", samples), samples=samples)["Combined"])
    with FrameDenoiser() as denoiser:
        for size in ((0, 10), (10, -1), (10.5, 10), (10, 10 ** 6)):
            with pytest.raises(ValueError, match="whole number of pixels"):
                denoiser.prepare(*size)


def test_automatic_prefilter_runs_none_only_where_it_fits_the_time_left(noisy, monkeypatch):
    """At the end of a time-limited render Automatic runs None only when the time left covers
    its estimate; else Fast, which takes half as long. (The estimate is fixed here: a measured
    one follows each denoise, and on a loaded machine moves between calls.)"""
    with FrameDenoiser("HIGH", "AUTO") as auto:
        none_seconds = 0.5
        monkeypatch.setattr(auto, "_estimate", lambda prefilter, pixels: {
            "NONE": none_seconds, "FAST": none_seconds / 2}[prefilter])
        for seconds, runs in ((None, "NONE"), (2 * none_seconds, "NONE"),
                              (0.5 * none_seconds, "FAST"), (-0.1, "FAST")):
            np.testing.assert_array_equal(
                auto.denoise(noisy, samples=CLEAN_GUIDE_SAMPLES, seconds=seconds)["Combined"],
                denoise_frame(noisy, "HIGH", runs, samples=CLEAN_GUIDE_SAMPLES)["Combined"],
                err_msg=str(seconds))


def test_ctrl_c_stops_a_large_denoise_in_a_plain_script():
    code = textwrap.dedent(f"""
        import os, signal, sys, threading, time
        sys.path.insert(0, {str(BUILD_PYTHON)!r})
        import numpy as np
        from shgi.frame_denoise import denoise_frame
        rng = np.random.default_rng(0)
        frame = {{"Combined": rng.random((2160, 3840, 4), dtype=np.float32)}}
        sent = []

        def interrupt_soon():
            time.sleep(0.5)
            sent.append(time.perf_counter())
            os.kill(os.getpid(), signal.SIGINT)

        threading.Thread(target=interrupt_soon, daemon=True).start()
        try:
            for _ in range(20):  # ~5 s each on 2 cores: minutes when not interrupted
                denoise_frame(frame, guides="NONE")
        except KeyboardInterrupt:
            print(f"KeyboardInterrupt {{time.perf_counter() - sent[0]:.3f}} s after SIGINT")
        else:
            print("finished")
    """)
    child = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                           timeout=120)
    assert child.returncode == 0, child.stderr[-2000:]
    assert child.stdout.startswith("KeyboardInterrupt"), child.stdout + child.stderr[-2000:]
    print(child.stdout.strip())
