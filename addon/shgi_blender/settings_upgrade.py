"""How the settings a .blend saved with an earlier add-on map onto today's ``scene.shgi``. No bpy.

Blender stores an add-on's properties in the file by name, so a property that moved reads as
its default in the new place while its old value lies unused under the old name. Versions of
``scene.shgi``'s layout:

1. The photon lattice's settings flat on ``scene.shgi`` (photons, resolution, order, …), the
   pass counts too (viewport_photon_passes, probe_passes, viewport_probe_passes), and
   ``scene.shgi.probe_grid`` with its own ``bounces`` and ``clamp``.
2. One group per method (settings.METHOD_SETTINGS) holding its pass counts; Light Paths sets
   the probe grid's bounce limit and clamp (settings.LIGHT_PATH_VALUES).
3. Each method group's ``final_gather``, on for a new scene (settings.FINAL_GATHER_DEFAULTS). A
   scene saved before it read its field at the first surface: it keeps doing so (off), so that
   it renders, and its frozen solutions compare, as they did.
4. Light Paths > Clamp Indirect defaults to Cycles' 10 (settings.CYCLES_DEFAULTS), where it was
   0 (off). A scene saved before that left it at 0 unless someone set it: it keeps 0.
5. Light Paths > Filter Glossy, with Cycles' default 1 (settings.CYCLES_DEFAULTS). A scene saved
   before it rendered without the blur: it keeps 0 (off).
6. Light Propagation's defaults: Steps 0 (from the new Distance, 32 cells), Damping, Occlude
   First Step, Drop Outward Lights, Travel Re-injection, Unclamped Transfer and Clamp At Walls
   on. A scene saved with the group before kept 8 steps and those off: it keeps them.
7. Instant GI's Render Passes default to 64 (settings.RENDER_PASSES_DEFAULTS), where they were
   4, and its bakes take Bake Passes (``instant_gi.bake_passes``) instead. A scene saved before
   keeps 4 Render Passes unless it set them, and bakes with the passes it rendered with.
8. F12's denoising Prefilter gained Automatic (its default stays Fast: settings.DENOISING_DEFAULTS)
   and Film > Pixel Filter came, with the box of one pixel every earlier layout rendered with. A
   scene saved before keeps Fast unless it set the prefilter.
9. F12's denoising Prefilter defaults to Automatic (settings.DENOISING_DEFAULTS), now that a
   render with a Time Limit sets the denoiser's networks up before it samples. A scene saved
   before keeps Fast unless it set the prefilter.
10. The probe grid's Visibility > Blur defaults to 0.10 rad, where it was 0.15: the narrower
    distance filter lets half as much of a bright room's light through a 10 cm wall
    (docs/methods.md, probe grid). A scene saved before keeps 0.15 unless it set the blur.
11. Instant GI's Final Gather is made by the renderer (before, it lit the first surfaces in
    screen space whatever the setting said) and is on for a new scene
    (settings.FINAL_GATHER_DEFAULTS). A scene saved before rendered without a gather, whatever
    it stored: its Final Gather is turned off.

``upgrade`` takes what a scene stored (its ID properties as a dict: only values someone set are
stored, a default is not) and says what to write where, so that the scene renders with the
values it had. versioning.py applies it when a file opens, as Cycles' versioning.py does.
"""

from dataclasses import dataclass, field

from . import settings

SETTINGS_VERSION = 11

# The method groups that version 2 had: a scene saved then could render only with these, so
# only they keep reading their field directly (groups added later start with their defaults).
GROUPS_BEFORE_3 = ("photon_lattice", "probe_grid")

# Version 1's flat properties of scene.shgi -> (group, property) in version 2.
MOVED_FROM_1 = {
    **{name: ("photon_lattice", name) for name in settings.PHOTON_LATTICE_DEFAULTS},
    "viewport_photon_passes": ("photon_lattice", "viewport_passes"),
    "probe_passes": ("probe_grid", "passes"),
    "viewport_probe_passes": ("probe_grid", "viewport_passes"),
}
# Version 1's defaults of moved properties whose default has changed since: a scene that left
# one at its default stored nothing, and rendered with this value.
DEFAULTS_OF_1 = {"probe_passes": 6}
# Version 1's probe_grid properties that Light Paths sets in version 2 (LIGHT_PATH_VALUES), with
# their version 1 defaults: dropped, with a note when the value differs from what Light Paths
# now gives the probe grid.
DROPPED_FROM_1 = {"bounces": 3, "clamp": 0.0}
# Defaults of scene.shgi's own properties before version 4 that have changed since: a scene that
# left one at its default stored nothing, and rendered with this value.
DEFAULTS_BEFORE_4 = {"clamp_indirect": 0.0}
# Properties added in version 5 with a default other than what a scene saved before rendered
# with (Filter Glossy: no blur).
DEFAULTS_BEFORE_5 = {"filter_glossy": 0.0}
# The Light Propagation group's defaults before version 6 that have changed since. The group came
# in version 3's time: a scene of layout 1 or 2 never had it, and takes today's defaults.
PROPAGATION_DEFAULTS_BEFORE_6 = {"steps": 8, "damping": False, "occlude_first_step": False,
                                 "drop_outward_vpls": False, "travel_reinjection": False,
                                 "unclamped_transfer": False, "clamp_at_surfaces": False}
# The Instant GI group's defaults before version 7 that have changed since. The group came in
# version 3's time, as Light Propagation's.
INSTANT_GI_DEFAULTS_BEFORE_7 = {"passes": 4}
# scene.shgi's own defaults before version 9 that have changed since (every earlier layout
# rendered F12 with these, the denoising settings having come in with their defaults).
DEFAULTS_BEFORE_9 = {"denoising_prefilter": "FAST"}
# The Probe Grid group's defaults before version 10 that have changed since (the group is as
# old as the add-on).
PROBE_GRID_DEFAULTS_BEFORE_10 = {"visibility_blur": 0.15}
# The Instant GI group's values before version 11 that a scene rendered with, whatever it stored
# (its Final Gather was never made). The group came in version 3's time.
INSTANT_GI_RENDERED_BEFORE_11 = {"final_gather": False}


@dataclass
class Upgrade:
    """What to do to one scene's settings."""

    values: dict = field(default_factory=dict)    # {(group or "", property): stored value}
    removed: list = field(default_factory=list)   # [(group or "", name)] of stale ID properties
    notes: list = field(default_factory=list)     # what could not be kept, for the console


def stored_version(stored):
    """The layout version of a scene's stored settings (`stored`: scene.shgi's ID properties as
    a dict): its settings_version, else 1 (saved before versions were stamped)."""
    return int(stored.get("settings_version", 1))



def upgrade(stored):
    """The Upgrade that brings a scene's stored settings (scene.shgi's ID properties as a dict,
    nested groups as dicts) to SETTINGS_VERSION; empty when they are up to date."""
    result = Upgrade()
    version = stored_version(stored)
    if version < 2:
        _upgrade_from_1(stored, result)
    if version < 3:
        for prop in GROUPS_BEFORE_3:
            if "final_gather" not in stored.get(prop, {}):
                result.values[(prop, "final_gather")] = False
    if version < 4:
        for name, old_default in DEFAULTS_BEFORE_4.items():
            if name not in stored:
                result.values[("", name)] = old_default
    if version < 5:
        for name, old_default in DEFAULTS_BEFORE_5.items():
            if name not in stored:
                result.values[("", name)] = old_default
    if 3 <= version < 6:
        group = stored.get("propagation", {})
        for name, old_default in PROPAGATION_DEFAULTS_BEFORE_6.items():
            if name not in group:
                result.values[("propagation", name)] = old_default
    if 3 <= version < 7:
        group = stored.get("instant_gi", {})
        for name, old_default in INSTANT_GI_DEFAULTS_BEFORE_7.items():
            if name not in group:
                result.values[("instant_gi", name)] = old_default
        # Its bakes solved the Render Passes: Bake Passes keep a count the scene set.
        if "passes" in group:
            result.values[("instant_gi", "bake_passes")] = group["passes"]
    if version < 9:
        for name, old_default in DEFAULTS_BEFORE_9.items():
            if name not in stored:
                result.values[("", name)] = old_default
    if version < 10:
        group = stored.get("probe_grid", {})
        for name, old_default in PROBE_GRID_DEFAULTS_BEFORE_10.items():
            if name not in group:
                result.values[("probe_grid", name)] = old_default
    if 3 <= version < 11:
        group = stored.get("instant_gi", {})
        for name, rendered in INSTANT_GI_RENDERED_BEFORE_11.items():
            if name not in group or group[name] != rendered:
                result.values[("instant_gi", name)] = rendered
    return result


def _upgrade_from_1(stored, result):
    """Version 1's flat and dropped properties into `result` (version 2's layout)."""
    for old, target in MOVED_FROM_1.items():
        if old in stored:
            result.values[target] = stored[old]
            result.removed.append(("", old))
        elif old in DEFAULTS_OF_1:
            result.values[target] = DEFAULTS_OF_1[old]
    grid = stored.get("probe_grid", {})
    light_paths = settings.default_properties(**dict(DEFAULTS_BEFORE_4, **{
        name: stored[name] for name in ("diffuse_bounces", "clamp_indirect") if name in stored}))
    follows = settings.light_path_fields(light_paths, settings.METHOD_SETTINGS["PROBE_GRID"],
                                         check=False, gather=False)
    for name, old_default in DROPPED_FROM_1.items():
        value = grid.get(name, old_default)
        if name in grid:
            result.removed.append(("probe_grid", name))
        if value != follows[name]:
            source = settings.LIGHT_PATH_VALUES["ProbeGridSettings"][name].prop
            result.notes.append(
                f"Probe Grid > {name.capitalize()} {value} is now set by "
                f"{settings.SETTING_LABELS[source]} ({getattr(light_paths, source)}), which gives "
                f"the probe grid {follows[name]}")

