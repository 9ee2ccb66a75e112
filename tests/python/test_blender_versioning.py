"""Files saved with the add-on's first settings layout (photon-lattice settings flat on
scene.shgi, the probe grid with its own bounces and clamp) open with the values they were saved
with: settings_upgrade's table outside Blender, then tests/blender/fixtures/settings_v1.blend
opened in each Blender (tests/blender/settings_versioning.py)."""

import json
import sys

import pytest

import shgi
import shgi.bake
from blender_support import BLENDER_SCRIPTS, REPO_ROOT, run_script_once

sys.path.insert(0, str(REPO_ROOT / "addon"))

from shgi_blender import settings, settings_upgrade  # noqa: E402

FIXTURE_VALUES = BLENDER_SCRIPTS / "fixtures" / "settings_v1.json"


def test_first_layout_values_move_into_the_method_groups():
    stored = {"photons": 123, "caustics": 2, "viewport_photon_passes": 5,
              "viewport_probe_passes": 40, "samples": 9, "probe_grid": {"order": 3}}
    upgrade = settings_upgrade.upgrade(stored)
    assert upgrade.values == {
        ("photon_lattice", "photons"): 123, ("photon_lattice", "caustics"): 2,
        ("photon_lattice", "viewport_passes"): 5, ("probe_grid", "viewport_passes"): 40,
        # left at the first layout's default, 6, which the scene rendered with
        ("probe_grid", "passes"): 6,
        # the field read at the first surface, as before Final Gather existed
        ("photon_lattice", "final_gather"): False, ("probe_grid", "final_gather"): False,
        # Clamp Indirect left at that layout's default, 0 (off), not today's Cycles default;
        # Filter Glossy, which it did not have, off as it rendered
        ("", "clamp_indirect"): 0.0, ("", "filter_glossy"): 0.0, **BEFORE_9, **BEFORE_10}
    assert sorted(upgrade.removed) == [("", "caustics"), ("", "photons"),
                                       ("", "viewport_photon_passes"),
                                       ("", "viewport_probe_passes")]
    # Bounces 3 and Clamp 0 are what Light Paths' defaults give the probe grid: nothing lost.
    assert upgrade.notes == []


def test_probe_grid_values_light_paths_took_over_are_dropped_with_a_note():
    upgrade = settings_upgrade.upgrade({"diffuse_bounces": 6, "clamp_indirect": 7.5,
                                        "probe_grid": {"bounces": 2, "clamp": 12.0}})
    assert ("probe_grid", "bounces") in upgrade.removed
    assert ("probe_grid", "clamp") in upgrade.removed
    assert upgrade.notes == [
        "Probe Grid > Bounces 2 is now set by Light Paths > Diffuse (6), which gives the probe "
        "grid 5",
        "Probe Grid > Clamp 12.0 is now set by Light Paths > Clamp (7.5), which gives the probe "
        "grid 7.5"]


def test_a_second_layout_scene_keeps_reading_its_field_directly():
    upgrade = settings_upgrade.upgrade({"settings_version": 2, "probe_grid": {"order": 1}})
    assert upgrade.values == {("photon_lattice", "final_gather"): False,
                              ("probe_grid", "final_gather"): False, ("", "clamp_indirect"): 0.0,
                              ("", "filter_glossy"): 0.0, **BEFORE_9, **BEFORE_10}
    assert (upgrade.removed, upgrade.notes) == ([], [])
    # One set by hand in that file (it cannot be, but a script may have) is kept.
    stored = {"settings_version": 2, "probe_grid": {"final_gather": True}, "clamp_indirect": 3.0,
              "filter_glossy": 0.5, "denoising_prefilter": 2}
    assert settings_upgrade.upgrade(stored).values == {("photon_lattice", "final_gather"): False,
                                                       **BEFORE_10}


def test_a_third_layout_scene_keeps_clamp_indirect_off():
    """Layout 4 gave Clamp Indirect Cycles' default, 10; a scene saved before, which left it at
    0, keeps 0 (it stored nothing); one that set it keeps its own value (nothing to write)."""
    assert settings.PROPERTY_DEFAULTS["clamp_indirect"] == 10.0
    assert shgi.PathTracerSettings().clamp_indirect == 0.0  # scripts keep the native 0
    assert settings_upgrade.upgrade({"settings_version": 3, "samples": 5}).values == {
        ("", "clamp_indirect"): 0.0, ("", "filter_glossy"): 0.0, **PROPAGATION_BEFORE_6,
        **INSTANT_GI_BEFORE_7, **BEFORE_9, **BEFORE_10, **INSTANT_GI_BEFORE_11}
    assert settings_upgrade.upgrade({"settings_version": 3, "clamp_indirect": 4.0}).values == {
        ("", "filter_glossy"): 0.0, **PROPAGATION_BEFORE_6, **INSTANT_GI_BEFORE_7, **BEFORE_9,
        **BEFORE_10, **INSTANT_GI_BEFORE_11}


def test_a_fourth_layout_scene_keeps_filter_glossy_off():
    """Layout 5 added Filter Glossy with Cycles' default, 1; a scene saved before rendered
    without the blur and keeps 0 (it stored nothing); one that set it (a script may have) keeps
    its own value. Its Clamp Indirect, layout 4's, is left alone."""
    assert settings.PROPERTY_DEFAULTS["filter_glossy"] == 1.0
    assert shgi.PathTracerSettings().filter_glossy == 0.0  # scripts keep the native 0
    assert shgi.PreviewSettings().filter_glossy == 0.0
    assert shgi.LightmapSettings().filter_glossy == 0.0
    assert settings_upgrade.upgrade({"settings_version": 4, "samples": 5}).values == {
        ("", "filter_glossy"): 0.0, **PROPAGATION_BEFORE_6, **INSTANT_GI_BEFORE_7, **BEFORE_9,
        **BEFORE_10, **INSTANT_GI_BEFORE_11}
    assert settings_upgrade.upgrade({"settings_version": 4, "filter_glossy": 0.25}).values == {
        **PROPAGATION_BEFORE_6, **INSTANT_GI_BEFORE_7, **BEFORE_9, **BEFORE_10,
        **INSTANT_GI_BEFORE_11}


# Light Propagation's defaults before layout 6, as an upgrade writes them into the group.
PROPAGATION_BEFORE_6 = {("propagation", "steps"): 8, ("propagation", "damping"): False,
                        ("propagation", "occlude_first_step"): False,
                        ("propagation", "drop_outward_vpls"): False,
                        ("propagation", "travel_reinjection"): False,
                        ("propagation", "unclamped_transfer"): False,
                        ("propagation", "clamp_at_surfaces"): False}


def test_a_fifth_layout_scene_keeps_the_light_propagation_defaults_of_then():
    """Layout 6 turned the light propagation volume's corrections on and takes its steps from
    Distance (Steps 0); a scene saved before keeps 8 steps and the corrections off, except what
    it set (kept as stored). Layouts 1 and 2 had no Light Propagation group: today's defaults."""
    assert (settings.PROPAGATION_DEFAULTS["steps"], settings.PROPAGATION_DEFAULTS["distance"]) == (
        0, 32.0)
    assert settings_upgrade.upgrade({"settings_version": 5, "samples": 5}).values == {
        **PROPAGATION_BEFORE_6, **INSTANT_GI_BEFORE_7, **BEFORE_9, **BEFORE_10,
        **INSTANT_GI_BEFORE_11}
    stored = {"settings_version": 5, "propagation": {"steps": 16, "unclamped_transfer": True}}
    assert settings_upgrade.upgrade(stored).values == {
        **{key: value for key, value in PROPAGATION_BEFORE_6.items()
           if key[1] not in ("steps", "unclamped_transfer")}, **INSTANT_GI_BEFORE_7, **BEFORE_9,
        **BEFORE_10, **INSTANT_GI_BEFORE_11}
    assert not any(group == "propagation" for group, _ in settings_upgrade.upgrade(
        {"settings_version": 2, "samples": 5}).values)


# Instant GI's Render Passes before layout 7, as an upgrade writes them into the group.
INSTANT_GI_BEFORE_7 = {("instant_gi", "passes"): 4}


def test_a_sixth_layout_scene_keeps_instant_gi_passes_for_renders_and_bakes():
    """Layout 7 gave Instant GI 64 Render Passes and bakes their own Bake Passes (4): a scene
    saved before keeps 4 Render Passes unless it set them, and bakes with the passes it set
    (it baked with its Render Passes). Layouts 1 and 2 had no Instant GI group: today's
    defaults."""
    assert settings.RENDER_PASSES_DEFAULTS["INSTANT_GI"] == 64
    defaults = settings.default_properties(shgi).instant_gi
    assert (defaults.passes, defaults.bake_passes) == (64, shgi.method("INSTANT_GI").final_passes)
    assert settings_upgrade.upgrade({"settings_version": 6, "samples": 5}).values == {
        **INSTANT_GI_BEFORE_7, **BEFORE_9, **BEFORE_10, **INSTANT_GI_BEFORE_11}
    stored = {"settings_version": 6, "instant_gi": {"passes": 12, "sets_x": 2}}
    assert settings_upgrade.upgrade(stored).values == {("instant_gi", "bake_passes"): 12,
                                                       **BEFORE_9, **BEFORE_10,
                                                       **INSTANT_GI_BEFORE_11}
    assert not any(group == "instant_gi" for group, _ in settings_upgrade.upgrade(
        {"settings_version": 2, "samples": 5}).values)


# F12's denoising prefilter before layout 9, as an upgrade writes it.
BEFORE_9 = {("", "denoising_prefilter"): "FAST"}


def test_an_eighth_layout_scene_keeps_the_fast_prefilter():
    """Layout 8 gave F12's denoiser the Automatic prefilter and layout 9 made it the default: a
    scene saved before, which left Fast, keeps Fast; one that chose a prefilter keeps it
    (nothing to write). Film > Pixel Filter came with layout 8, with the box of one pixel every
    scene had rendered with (still the default: nothing to write)."""
    assert settings.DENOISING_DEFAULTS["denoising_prefilter"] == "AUTO"
    assert (settings.PROPERTY_DEFAULTS["pixel_filter"],
            settings.PROPERTY_DEFAULTS["filter_width"]) == ("BOX", 1.0)
    for layout in (7, 8):
        assert settings_upgrade.upgrade({"settings_version": layout, "samples": 5}).values == {
            **BEFORE_9, **BEFORE_10, **INSTANT_GI_BEFORE_11}
        assert settings_upgrade.upgrade({"settings_version": layout,
                                         "denoising_prefilter": 2}).values == {
            **BEFORE_10, **INSTANT_GI_BEFORE_11}


# The probe grid's Visibility > Blur before layout 10, as an upgrade writes it into the group.
BEFORE_10 = {("probe_grid", "visibility_blur"): 0.15}


def test_a_ninth_layout_scene_keeps_the_probe_grids_wider_visibility_blur():
    """Layout 10 narrowed the probe grid's distance filter (Visibility > Blur 0.15 -> 0.10 rad):
    a scene saved before, which left 0.15, keeps it; one that set a blur keeps its own. Native
    scripts get the new default as well."""
    assert settings.PROBE_GRID_DEFAULTS["visibility_blur"] == pytest.approx(
        shgi.ProbeGridSettings().visibility_blur) == pytest.approx(0.10)
    assert settings_upgrade.upgrade({"settings_version": 9, "samples": 5}).values == {
        **BEFORE_10, **INSTANT_GI_BEFORE_11}
    assert settings_upgrade.upgrade({"settings_version": 9,
                                     "probe_grid": {"visibility_blur": 0.4}}).values == \
        INSTANT_GI_BEFORE_11


# Instant GI's Final Gather before layout 11 (never made), as an upgrade writes it.
INSTANT_GI_BEFORE_11 = {("instant_gi", "final_gather"): False}


def test_a_tenth_layout_scene_keeps_instant_gi_without_a_final_gather():
    """Layout 11's renderer makes Instant GI's Final Gather, on for a new scene; before, it lit
    the first surfaces in screen space whatever Final Gather said. A scene saved before renders
    as it did, without a gather, whether it stored the setting or not; layouts 1 and 2 had no
    Instant GI group: today's defaults."""
    assert settings.FINAL_GATHER_DEFAULTS["INSTANT_GI"]
    assert settings.default_properties(shgi).instant_gi.final_gather
    for instant_gi in ({}, {"final_gather": True}, {"final_gather": 1}):
        stored = {"settings_version": 10, "instant_gi": instant_gi}
        assert settings_upgrade.upgrade(stored).values == INSTANT_GI_BEFORE_11
    stored = {"settings_version": 10, "instant_gi": {"final_gather": 0}}
    assert settings_upgrade.upgrade(stored).values == {}
    assert not any(group == "instant_gi" for group, _ in settings_upgrade.upgrade(
        {"settings_version": 2, "samples": 5}).values)


def test_settings_of_today_layout_are_left_alone():
    stored = {"settings_version": settings_upgrade.SETTINGS_VERSION, "samples": 3,
              "probe_grid": {"order": 1}}
    upgrade = settings_upgrade.upgrade(stored)
    assert (upgrade.values, upgrade.removed, upgrade.notes) == ({}, [], [])


def test_every_first_layout_property_has_a_place():
    """Each property of the fixture's first layout is today's (same name), moved, or taken over
    by Light Paths."""
    saved = json.loads(FIXTURE_VALUES.read_text())
    today = set(settings.PROPERTY_DEFAULTS) | set(settings.VIEWPORT_PROPERTY_DEFAULTS) | {"method"}
    # Properties added since (Light Paths > Light Splits) were not in the first layout.
    assert set(saved["shgi"]) <= today | set(settings_upgrade.MOVED_FROM_1)
    assert set(settings_upgrade.MOVED_FROM_1) <= set(saved["shgi"])
    assert set(saved["shgi.probe_grid"]) == (set(settings.PROBE_GRID_DEFAULTS)
                                             | set(settings_upgrade.DROPPED_FROM_1))


@pytest.fixture(scope="module")
def saved():
    return json.loads(FIXTURE_VALUES.read_text())


def test_first_layout_file_opens_with_its_values(blender, build_python_dir, tmp_path_factory,
                                                  saved):
    results = run_script_once("settings_versioning.py", "SETTINGS_VERSIONING_OK",
                              build_python_dir, tmp_path_factory, blender=blender)
    expected = results["expected"]
    # Every value the file was saved with, none left out of the check.
    assert len(expected) == (len(saved["shgi"]) + len(saved["shgi.probe_grid"])
                             - len(settings_upgrade.DROPPED_FROM_1))
    assert expected["photon_lattice.photons"] == saved["shgi"]["photons"]
    assert expected["probe_grid.passes"] == saved["shgi"]["probe_passes"]
    for read in (results["values"], results["reopened"]):
        assert set(read) == set(expected)
        for path, value in expected.items():
            assert read[path] == pytest.approx(value, abs=1e-6), path
    assert results["settings_version"] == settings_upgrade.SETTINGS_VERSION
    # The file's Light Paths reach both methods: Diffuse 6 is 5 probe bounces after the
    # renderer's own surface, and 6 photon bounces; Clamp 7.5 clamps the probes' samples.
    light_paths = saved["shgi"]
    assert results["native"] == {
        "probe_grid.bounces": light_paths["diffuse_bounces"] - 1,
        "probe_grid.clamp": light_paths["clamp_indirect"],
        "photon_lattice.max_bounces": light_paths["diffuse_bounces"]}


def test_a_new_scene_solves_as_many_probe_passes_as_the_cli(blender, build_python_dir,
                                                            tmp_path_factory):
    results = run_script_once("settings_versioning.py", "SETTINGS_VERSIONING_OK",
                              build_python_dir, tmp_path_factory, blender=blender)
    assert results["new_scene_passes"] == results["bake_probe_grid_passes"] == \
        shgi.bake.PROBE_GRID_PASSES
    # Saved with today's layout: the default is kept, not read as the first layout's 6.
    # Layout 3 left Clamp Indirect at 0: it stays 0; a new scene clamps at Cycles' 10.
    assert results["new_scene_clamp"] == 10.0
    version = settings_upgrade.SETTINGS_VERSION
    kept = {"settings_version": version, "denoising_prefilter": "FAST"}
    assert results["layout_3_clamp"] == {
        "left": {"clamp_indirect": 0.0, "filter_glossy": 0.0, **kept},
        "set": {"clamp_indirect": 7.5, "filter_glossy": 0.0, **kept}}
    # Layout 4 had no Filter Glossy: it stays off; a new scene filters at Cycles' 1.
    assert results["new_scene_filter_glossy"] == 1.0
    assert results["layout_4_filter_glossy"] == {
        "left": {"clamp_indirect": 10.0, "filter_glossy": 0.0, **kept},
        "set": {"clamp_indirect": 10.0, "filter_glossy": 0.5, **kept}}
    # Layout 8 denoised F12 with the Fast prefilter: kept when left; a new scene has Automatic.
    assert results["new_scene_prefilter"] == "AUTO"
    assert results["layout_8_prefilter"] == {"left": "FAST", "set": "NONE"}
    # Layout 5's Light Propagation: 8 steps and the corrections off, left or set; a new scene
    # takes its steps from Distance with them on.
    old = {"distance": 32.0, "damping": False, "occlude_first_step": False,
           "drop_outward_vpls": False, "travel_reinjection": False, "unclamped_transfer": False,
           "clamp_at_surfaces": False}
    assert results["layout_5_propagation"] == {"left": dict(old, steps=8),
                                               "set": dict(old, steps=16)}
    assert results["new_scene_propagation"] == {
        "steps": 0, "distance": 32.0, "damping": True, "occlude_first_step": True,
        "drop_outward_vpls": True, "travel_reinjection": True, "unclamped_transfer": True,
        "clamp_at_surfaces": True}
    assert results["today_reopened"] == {"samples": 33,
                                         "probe_grid.passes": shgi.bake.PROBE_GRID_PASSES,
                                         "settings_version": settings_upgrade.SETTINGS_VERSION}


def test_final_passes_fallback_matches_the_cli():
    """The add-on's defaults when shgi does not import are what `python -m shgi bake` runs."""
    assert settings.FINAL_PASSES_FALLBACK["PROBE_GRID"] == shgi.bake.PROBE_GRID_PASSES
    for solver, passes in settings.FINAL_PASSES_FALLBACK.items():
        assert passes == shgi.method(solver).final_passes
        assert settings.final_passes(solver, shgi) == passes
        assert settings.final_passes(solver, None) == passes
