// Bindings for native/instant: the InstantGi solver (instant GI with a discontinuity-aware
// screen-space SH filter, seed 004; instant/instant_gi.h) and its settings, mirrored field by
// field with the same names and defaults, and the InstantGiField snapshots it renders from.
//
// An InstantGi keeps its Scene alive; refine() and reset() release the GIL and report progress.
// Its field is an immutable snapshot of the VPL sets: renders (render_preview, PreviewRenderer)
// may read one while the next refine() runs. The field lights the camera's first surfaces in a
// frame-wide stage of the preview renderer (IndirectField.shades_first_surfaces).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>

#include "bind_methods.h"
#include "instant/instant_gi.h"
#include "interruptible.h"
#include "scene_use.h"
#include "struct_fields.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

void bind_settings(py::module_& m) {
    named_values_only(py::enum_<InstantGiFilter>(
        m, "InstantGiFilter", "What the Instant GI's screen-space filter blends between pixels.")
        .value("SH", InstantGiFilter::Sh)
        .value("IRRADIANCE", InstantGiFilter::Irradiance)
        .value("STRICT", InstantGiFilter::Strict)
        .value("NONE", InstantGiFilter::None));

    using S = InstantGiSettings;
    py::class_<S> cls(m, "InstantGiSettings",
                      "Settings of the InstantGi solver (seed 004); every field has a default.");
    def_integer(cls, "sets_x", &S::sets_x,
                "n: VPL sets across; pixel (x, y) uses set (x mod n, y mod m), 1..16 (4).");
    def_integer(cls, "sets_y", &S::sets_y, "m: VPL sets down, 1..16 (4).");
    def_integer(cls, "photons_per_set", &S::photons_per_set,
                "Light paths traced per set and pass; each leaves a VPL at its first "
                "vpl_bounces hits (16).", 1);
    def_integer(cls, "vpl_bounces", &S::vpl_bounces,
                "Hits of a light path that leave a VPL: 1 is one bounce of indirect light (4).");
    def_integer(cls, "glossy_bounces", &S::glossy_bounces,
                "Glossy scatterings of a light path, a budget of their own beside vpl_bounces, "
                "0..64; 4 matches Cycles' default glossy bounces.");
    def_integer(cls, "passes_per_sample", &S::passes_per_sample,
                "Passes of VPLs a preview sample gathers, 1..65536: sample i gathers the k "
                "passes after sample i - 1's (around the solve's passes), so a frame's samples "
                "average more passes than one gathers; with no more passes than this, every "
                "sample gathers them all (4).");
    def_integer(cls, "seed", &S::seed, "Random seed (0).");
    cls.def(py::init(&from_kwargs<S>),
            "InstantGiSettings(**fields), e.g. InstantGiSettings(sets_x=3, sets_y=3).")
        .def_readwrite("clamp_distance", &S::clamp_distance,
                       "m: a VPL closer than this counts as this far (the 1/d^2 spike's clamp; "
                       "0 = off) (0.05).")
        .def_readwrite("filter_mode", &S::filter_mode,
                       "InstantGiFilter: SH (the paper's), IRRADIANCE (each pixel's irradiance, "
                       "same edges), STRICT (irradiance, also stopping at shading-normal "
                       "changes), NONE (each pixel its own set).")
        .def_readwrite("depth_threshold", &S::depth_threshold,
                       "Neighbours whose depth differs by more than this fraction are not "
                       "blended (0.1).")
        .def_readwrite("normal_threshold", &S::normal_threshold,
                       "Neighbours whose geometric normals' cosine is below this are not "
                       "blended (0.9).")
        .def_readwrite("glossy_vpls", &S::glossy_vpls,
                       "A VPL's surface scatters with its rough glossy lobes too, as if "
                       "diffuse; False: its diffuse lobe only (True).")
        .def_readwrite("filter_direct", &S::filter_direct,
                       "Direct light through the SH filter, as the paper filters it: the "
                       "world's as directional VPLs (photons_per_set per set and pass), the "
                       "point, spot, area and sun lights' as samples per set (one for a delta "
                       "light, photons_per_set per pass for one with extent) and the emissive "
                       "triangles' as photons_per_set samples per set and pass (each triangle "
                       "by its power), each with its exact shadow ray; next-event estimation "
                       "then leaves them out (False).")
        .def_readwrite("glossy_from_vpls", &S::glossy_from_vpls,
                       "Glossy lobes of roughness 0.3 and above weigh each VPL by the lobe "
                       "itself instead of reading the L2 SH: sharper glossy light, the same "
                       "mean (False).")
        .def_readwrite("gather_cut_windows", &S::gather_cut_windows,
                       "Pixels whose filter window an edge cuts gather every set themselves "
                       "and skip the filter: no blur of light across the edge's side, at "
                       "sets_x x sets_y times those pixels' shadow rays (False).")
        .def_readwrite("near_field_reach", &S::near_field_reach,
                       "VPLs nearer to a pixel than this many times its filter window's reach "
                       "(the farthest neighbour it blends) are gathered from every set and kept "
                       "out of the filter, whose blur they would bias; 0..64, 0 = off (4).")
        .def_readwrite("gather_near_radius", &S::gather_near_radius,
                       "Final gather: where a gather ray lands, VPLs nearer than this (m) are "
                       "read from every set, the farther ones from the ray's one set: less "
                       "noise at the same mean; 0 = off (0.25).");
    cls.def("validate", &validate_instant_gi_settings,
            "Raises ValueError naming the first invalid field.");
    register_settings_type<S>("InstantGiSettings");
}

ObjectUse solver_use(const InstantGi& solver, ObjectUse::Kind kind, const char* method) {
    return ObjectUse(&solver, kind, std::string("InstantGi.") + method,
                     kind == ObjectUse::Kind::Write
                         ? "the solver is in use in another thread; wait for that call to return"
                         : "a refine() or reset() of this solver is running in another thread; "
                           "wait for it to return");
}

py::dict frame_timings(const InstantGiField& field) {
    const InstantGiFrameTimings t = field.frame_timings();
    py::dict out;
    out["gather"] = t.gather;
    out["filter"] = t.filter;
    out["shade"] = t.shade;
    return out;
}

void bind_solver(py::module_& m) {
    py::class_<InstantGiField, IndirectField>(
        m, "InstantGiField",
        "Immutable VPL sets as an IndirectField: the preview renderer's first surfaces are lit "
        "by the interleaved sets and the screen-space filter; lookups elsewhere gather every "
        "VPL.")
        .def_property_readonly("vpl_count", &InstantGiField::vpl_count, "VPLs in all sets.")
        .def_property_readonly("passes", &InstantGiField::passes, "Passes of VPLs it holds.")
        .def(
            "sample_passes",
            [](const InstantGiField& f, const IndexInt& sample) {
                return f.sample_passes(int_arg<uint64_t>(sample, "sample"));
            },
            py::arg("sample"),
             "The passes preview sample `sample` gathers (passes_per_sample), in order.")
        .def_property_readonly(
            "set_sizes",
            [](const InstantGiField& f) {
                std::vector<size_t> sizes;
                for (const auto& set : f.sets()) sizes.push_back(set.size());
                return sizes;
            },
            "VPLs per set, set (i, j) at index j * sets_x + i.")
        .def_property_readonly(
            "frame_timings", &frame_timings,
            "{gather, filter, shade}: seconds of the latest frame this field lit.")
        .def_property_readonly(
            "lookup_counts",
            [](const InstantGiField& f) {
                const InstantGiLookupCounts c = f.lookup_counts();
                py::dict out;
                out["lookups"] = c.lookups;
                out["vpls"] = c.vpls;
                return out;
            },
            "{lookups, vpls}: the field's lookups beyond the first surfaces (through glass and "
            "mirrors; bakes' too) and the VPLs, sky directions and lamp samples they read (a "
            "shadow ray each at most), since the preview renderer's latest frame with it began "
            "(or since the field was made).");

    py::class_<InstantGi, GiSolver> cls(m, "InstantGi", R"doc(
Instant GI with a discontinuity-aware screen-space SH filter (seed 004): VPLs from traced light
paths, dealt into sets_x x sets_y interleaved sets; each pixel gathers its set's VPLs as L2 SH of
the incident radiance with exact shadow rays, the SH is blended over an interleave-wide window
that stops at depth, geometric-normal and object edges, and each pixel is shaded with its own
shading normal (normal-map detail kept).

Each refine() adds a pass of new VPLs to every set. current_field() is an immutable snapshot.
After editing and re-committing the scene, call reset().)doc");
    cls.def(py::init([](const Scene& scene, const InstantGiSettings& settings,
                         Progress* progress) {
                 validate_instant_gi_settings(settings);
                 SceneUse use(scene, SceneUse::Kind::Query, "InstantGi");
                 return run_interruptible(progress, [&](Progress* used) {
                     return std::make_unique<InstantGi>(scene, settings, used);
                 });
             }),
             py::arg("scene"), py::arg("settings") = InstantGiSettings{},
             py::arg("progress") = py::none(), py::keep_alive<1, 2>(),
             "A solver with no VPLs yet (the scene must be committed).")
        .def(
            "refine",
            [](InstantGi& solver, Progress* progress) {
                const ObjectUse writes = solver_use(solver, ObjectUse::Kind::Write, "refine");
                run_interruptible(progress, [&](Progress* used) { solver.refine(used); });
            },
            py::arg("progress") = py::none(),
            "One pass: traces light paths and adds their VPLs to the sets (GIL released). "
            "Raises shgi.Cancelled on cancel, keeping the previous sets.")
        .def(
            "reset",
            [](InstantGi& solver, Progress* progress) {
                const ObjectUse writes = solver_use(solver, ObjectUse::Kind::Write, "reset");
                run_interruptible(progress, [&](Progress* used) { solver.reset(used); });
            },
            py::arg("progress") = py::none(), "Forgets every pass (re-reads the scene).")
        .def(
            "current_field",
            [](const InstantGi& solver) {
                const ObjectUse reads = solver_use(solver, ObjectUse::Kind::Check, "current_field");
                return std::make_unique<InstantGiField>(*solver.field());
            },
            "The InstantGiField of the last pass (safe to render while refine() runs).")
        .def_property_readonly(
            "passes",
            [](const InstantGi& s) {
                const ObjectUse reads = solver_use(s, ObjectUse::Kind::Check, "passes");
                return s.passes();
            },
            "Passes so far.")
        .def_property_readonly(
            "stage_seconds",
            [](const InstantGi& s) {
                const ObjectUse reads = solver_use(s, ObjectUse::Kind::Check, "stage_seconds");
                return stage_list(s.stage_seconds());
            },
            "[(stage, seconds)] of the last pass: vpl_trace, vpl_sets (reflection of later "
            "hits and dealing into sets).")
        .def_property_readonly(
            "memory_bytes",
            [](const InstantGi& s) {
                const ObjectUse reads = solver_use(s, ObjectUse::Kind::Check, "memory_bytes");
                return s.memory_bytes();
            },
            "Bytes held by the VPL sets.")
        .def_property_readonly("settings", &InstantGi::settings, "A copy of the settings.");
}

}  // namespace

void bind_instant(py::module_& m) {
    bind_settings(m);
    bind_solver(m);
}

}  // namespace shgi::python
