// Bindings for native/propagation: the PropagationVolume solver (light propagation volumes, LPV
// and HOLPV, seed 003; propagation/propagation_volume.h) and its settings, mirrored field by
// field with the same names and defaults, and the PropagationField snapshots it renders from.
//
// A PropagationVolume keeps its Scene alive; refine() and reset() release the GIL and report
// progress. Its field is an immutable snapshot: renders may read one while the next refine()
// runs.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>

#include "bind_methods.h"
#include "interruptible.h"
#include "numpy_convert.h"
#include "propagation/propagation_volume.h"
#include "scene_use.h"
#include "struct_fields.h"
#include "util/error.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

void bind_settings(py::module_& m) {
    using S = PropagationSettings;
    py::class_<S> cls(m, "PropagationSettings",
                      "Settings of the PropagationVolume solver (light propagation volumes); "
                      "every field has a default.");
    def_integer(cls, "photons", &S::photons,
                "Light paths traced per pass; their surface hits are the VPLs (100000).", 1);
    def_integer(cls, "seed", &S::seed, "Random seed (0).");
    def_integer(cls, "vpl_bounces", &S::vpl_bounces,
                "Surface hits per light path that become VPLs: 1 is the published single "
                "bounce, n gives n bounces of indirect light (4).");
    def_integer(cls, "glossy_bounces", &S::glossy_bounces,
                "Glossy scatterings of a light path, a budget of their own beside vpl_bounces, "
                "-1..64; -1: they count against vpl_bounces (-1).");
    def_integer(cls, "resolution", &S::resolution,
                "Cells along the longest side of the scene (32).");
    def_integer(cls, "steps", &S::steps,
                "Propagation steps; 0 takes them from distance (0).");
    def_integer(cls, "order", &S::order,
                "1: LPV (L1 SH, 6 directions); 2: HOLPV (L2 SH, 26 directions) (2).");
    cls.def(py::init(&from_kwargs<S>),
            "PropagationSettings(**fields), e.g. PropagationSettings(order=1, steps=16).")
        .def_readwrite("distance", &S::distance,
                       "How far the light travels, in cells, when steps is 0: each order takes "
                       "the steps its stencil needs to carry light this far (the LPV's steps "
                       "move light 0.915 cells, the HOLPV's 1.415) (32.0).")
        .def_readwrite("settle_fraction", &S::settle_fraction,
                       "Stop propagating once the light in flight is at most this fraction of "
                       "the injected light (the accumulation has settled); steps or distance "
                       "are then the most it takes; 0: off (0.0).")
        .def_readwrite("glossy_vpls", &S::glossy_vpls,
                       "A VPL's surface scatters with its rough glossy lobes too, as if "
                       "diffuse; False: its diffuse lobe only, and the volume misses the light "
                       "a glossy layer reflects onto other surfaces (False).")
        .def_readwrite("furnace_scale", &S::furnace_scale,
                       "Scale the light to what a closed room reads once its light has settled "
                       "(the furnace, an exact answer) instead of a single VPL's near field: "
                       "divided by the furnace's reading of the transfer, 1.22-1.37; needs "
                       "travel_reinjection (False).")
        .def_readwrite("occlusion", &S::occlusion,
                       "Geometry volume blocking from the second step on, or the first with "
                       "occlude_first_step (True).")
        .def_readwrite("normal_offset", &S::normal_offset,
                       "Cells along the surface's interpolated normal before the lookup, against "
                       "self-lighting and leaks through walls (1.0).")
        .def_readwrite("damping", &S::damping,
                       "Damp the lookup where the light arriving against the normal is stronger "
                       "half a cell behind the lookup point than in front of it (seed 003 "
                       "§3.2.4's directional derivative, against self-lighting and bleeding) "
                       "(True).")
        .def_readwrite("occlude_first_step", &S::occlude_first_step,
                       "Geometry volume blocking on the first step too (the seed skips it): "
                       "keeps the light of VPLs next to a thin wall from crossing it (True).")
        .def_readwrite("drop_outward_vpls", &S::drop_outward_vpls,
                       "Drop the VPLs that light nothing: on the scene's bounds facing out (a "
                       "sunlit roof or outer wall), whose light otherwise reaches the interior "
                       "through the cells their surface runs through (True).")
        .def_readwrite("travel_reinjection", &S::travel_reinjection,
                       "Re-inject the light crossing each face along its travel direction "
                       "(keeps its momentum: less diffusion, converges in fewer steps) instead "
                       "of as a cosine lobe along the face's normal (the seed) (True).")
        .def_readwrite("windowed_reinjection", &S::windowed_reinjection,
                       "With travel_reinjection and order 2: scale the re-injected beam's band 2 "
                       "by 4/5 so that its light does not come back onto the surface it left "
                       "(the HOLPV's self-lighting at bright surfaces; docs/methods.md) (True).")
        .def_readwrite("extend_to_bounds", &S::extend_to_bounds,
                       "Give the cells whose centres lie outside the scene's bounds the light of "
                       "the inside cell next to them, against a dark strip along the edges of "
                       "rooms whose walls are the bounds; not the default: the HOLPV's two rooms "
                       "then read 1.12x the path tracer (docs/methods.md) (False).")
        .def_readwrite("unclamped_transfer", &S::unclamped_transfer,
                       "Propagate the lobes unclamped (a linear transfer per neighbour offset) "
                       "instead of clamping each source lobe at zero and rescaling it to its "
                       "flux (True).")
        .def_readwrite("clamp_at_surfaces", &S::clamp_at_surfaces,
                       "With unclamped_transfer: clamp the lobes of the cells whose light a wall "
                       "stops in part, linear elsewhere, so that walls neither make light nor "
                       "return what goes into them; no effect without unclamped_transfer "
                       "(True).")
        .def_readwrite("clamp_per_transfer", &S::clamp_per_transfer,
                       "HOLPV (order 2) only, with clamp_at_surfaces: clamp only the transfers a "
                       "wall stops in part, not every transfer of such a cell, so that the "
                       "higher-order lobes keep their light at a room's edges; the LPV ignores "
                       "it (True).")
        .def_readwrite("light_share_uniform", &S::light_share_uniform,
                       "Share of the photons spread evenly over the lamps (a light, an emissive "
                       "object, the world), the rest by flux; each photon's power is divided by "
                       "its probability, so the light stays unbiased; 0..1 (0.5).");
    def_integer(cls, "cascades", &S::cascades,
                "Nested volumes around cascade_center, each finer level with half the cells' "
                "size and `resolution` cells per axis; 1: one volume over the scene (1).");
    def_vec3(cls, "cascade_center", &S::cascade_center,
             "The point the finer cascade levels are centred on without the camera "
             "(cascade_follow_camera off, or a scene without one): a point of interest for a "
             "bake ((0, 0, 0)).");
    cls.def_readwrite("cascade_follow_camera", &S::cascade_follow_camera,
                      "Centre the finer cascade levels on the scene's camera (its position when "
                      "the volume is reset) when the scene has one (True).");
    cls.def("validate", &validate_propagation_settings,
            "Raises ValueError naming the first invalid field.");
    m.def(
        "propagation_steps",
        [](const S& settings) {
            validate_propagation_settings(settings);
            return propagation_steps(settings);
        },
        py::arg("settings"),
        "The steps a PropagationVolume of these settings propagates: settings.steps, or with "
        "steps 0 settings.distance over the order's cells per step (LPV 0.915, HOLPV 1.415), "
        "rounded. Raises ValueError for invalid settings.");
    register_settings_type<S>("PropagationSettings");
}

ObjectUse volume_use(const PropagationVolume& volume, ObjectUse::Kind kind, const char* method) {
    return ObjectUse(&volume, kind, std::string("PropagationVolume.") + method,
                     kind == ObjectUse::Kind::Write
                         ? "the volume is in use in another thread; wait for that call to return"
                         : "a refine() or reset() of this volume is running in another thread; "
                           "wait for it to return");
}

void bind_volume(py::module_& m) {
    py::class_<PropagationField, IndirectField>(
        m, "PropagationField",
        "An immutable light propagation volume as an IndirectField (its accumulated light).")
        .def_property_readonly(
            "memory_bytes", &PropagationField::memory_bytes, "Bytes of its volumes.")
        .def_property_readonly(
            "level_count", [](const PropagationField& field) { return field.levels().size(); },
            "Cascade levels (1 without cascades; 0 before the first pass), the finest first.")
        .def(
            "level_field",
            [](const PropagationField& field, const IndexInt& index) {
                const int64_t level = int_arg<int64_t>(index, "level");
                if (level < 0 || uint64_t(level) >= field.levels().size())
                    throw py::index_error(format_message(
                        "PropagationField.level_field: level ", level, " of ",
                        field.levels().size(), " levels; it must be in [0, ",
                        field.levels().size(), ")"));
                return std::make_unique<PropagationField>(field.level_field(size_t(level)));
            },
            py::arg("level"),
            "Cascade level `level` alone (0 the finest) as a field of its own, unblended.")
        .def(
            "save",
            [](const PropagationField& field, const std::string& path) {
                py::gil_scoped_release release;
                field.save(path);
            },
            py::arg("path"),
            "Writes the field to an SHGI .shlpv file (atomically); load() reads it back.")
        .def_static(
            "load",
            [](const std::string& path) {
                py::gil_scoped_release release;
                return PropagationField::load(path);
            },
            py::arg("path"),
            "The field a save() wrote; OSError naming the file when it is not one.");

    py::class_<PropagationVolume, GiSolver> cls(m, "PropagationVolume", R"doc(
Light propagation volumes (seed 003): VPLs from traced light paths, injected as cosine lobes
into an SH grid and propagated step by step (LPV: 6 directions, L1; HOLPV: 26 directions, L2).

Each refine() traces `photons` more light paths and propagates the mean of every pass's VPLs.
current_field() is an immutable snapshot. After editing and re-committing the scene, call
reset().)doc");
    cls.def(py::init([](const Scene& scene, const PropagationSettings& settings,
                         Progress* progress) {
                 validate_propagation_settings(settings);
                 SceneUse use(scene, SceneUse::Kind::Query, "PropagationVolume");
                 return run_interruptible(progress, [&](Progress* used) {
                     return std::make_unique<PropagationVolume>(scene, settings, used);
                 });
             }),
             py::arg("scene"), py::arg("settings") = PropagationSettings{},
             py::arg("progress") = py::none(), py::keep_alive<1, 2>(),
             "Builds the geometry volume (the scene must be committed).")
        .def(
            "refine",
            [](PropagationVolume& volume, Progress* progress) {
                const ObjectUse writes = volume_use(volume, ObjectUse::Kind::Write, "refine");
                run_interruptible(progress, [&](Progress* used) { volume.refine(used); });
            },
            py::arg("progress") = py::none(),
            "One pass: traces VPLs, injects, propagates (GIL released). Raises shgi.Cancelled on "
            "cancel, keeping the previous field.")
        .def(
            "reset",
            [](PropagationVolume& volume, Progress* progress) {
                const ObjectUse writes = volume_use(volume, ObjectUse::Kind::Write, "reset");
                run_interruptible(progress, [&](Progress* used) { volume.reset(used); });
            },
            py::arg("progress") = py::none(),
            "Forgets every pass and rebuilds the geometry volume of the (re-committed) scene.")
        .def(
            "recenter",
            [](PropagationVolume& volume, const py::handle& point, Progress* progress) {
                const vec3 p = to_vec3(point, "point");
                const ObjectUse writes = volume_use(volume, ObjectUse::Kind::Write, "recenter");
                return run_interruptible(progress,
                                         [&](Progress* used) { return volume.recenter(p, used); });
            },
            py::arg("point"), py::arg("progress") = py::none(),
            "Cascades that follow a moving camera: moves every finer level whose inner region "
            "(the middle half of its box per axis) no longer holds `point` to be centred on it "
            "(snapped to its cells, inside the scene) and rebuilds those levels alone: geometry, "
            "every pass's VPLs traced again, propagation (GIL released) - the field a volume "
            "reset there gives after as many passes. Returns the levels moved, finest first "
            "([] without cascades). Raises shgi.Cancelled on cancel, keeping the volume as it "
            "was; ValueError for a point that is not finite.")
        .def(
            "current_field",
            [](const PropagationVolume& volume) {
                const ObjectUse reads =
                    volume_use(volume, ObjectUse::Kind::Check, "current_field");
                return std::make_unique<PropagationField>(*volume.field());
            },
            "The PropagationField of the last pass (safe to render while refine() runs).")
        .def_property_readonly(
            "passes",
            [](const PropagationVolume& v) {
                const ObjectUse reads = volume_use(v, ObjectUse::Kind::Check, "passes");
                return v.passes();
            },
            "Passes averaged so far.")
        .def_property_readonly(
            "stage_seconds",
            [](const PropagationVolume& v) {
                const ObjectUse reads = volume_use(v, ObjectUse::Kind::Check, "stage_seconds");
                return stage_list(v.stage_seconds());
            },
            "[(stage, seconds)] of the last pass: vpl_trace, vpl_reflect, injection, "
            "geometry_volume (of the last reset), propagation_step_1 ... N; with cascades, the "
            "last four per level prefixed level_<l>_ (0 the finest).")
        .def_property_readonly(
            "memory_bytes",
            [](const PropagationVolume& v) {
                const ObjectUse reads = volume_use(v, ObjectUse::Kind::Check, "memory_bytes");
                return v.memory_bytes();
            },
            "Bytes held by the volumes.")
        .def_property_readonly(
            "vpl_count",
            [](const PropagationVolume& v) {
                const ObjectUse reads = volume_use(v, ObjectUse::Kind::Check, "vpl_count");
                return v.last_vpl_count();
            },
            "VPLs injected by the last pass.")
        .def_property_readonly("settings", &PropagationVolume::settings,
                               "A copy of the settings.")
        .def_static(
            "estimate_memory_bytes",
            [](const Scene& scene, const PropagationSettings& settings) {
                SceneUse use(scene, SceneUse::Kind::Query, "PropagationVolume");
                return PropagationVolume::estimate_memory_bytes(scene, settings);
            },
            py::arg("scene"), py::arg("settings"),
            "Bytes the volumes and transmittances of these settings take for the scene (all "
            "cascade levels), before anything is allocated; ValueError for bad settings.");
}

}  // namespace

void bind_propagation(py::module_& m) {
    bind_settings(m);
    bind_volume(m);
}

}  // namespace shgi::python
