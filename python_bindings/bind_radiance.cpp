// Bindings for native/radiance: the RadianceField solver (radiance/radiance_field.h, seed 001)
// and its settings, mirrored field by field with the same names and defaults.
//
// A RadianceField keeps its Scene alive; refine() releases the GIL and reports progress. It is a
// shgi.IndirectField, so shgi.render_preview and the PreviewRenderer take it directly.
#include <pybind11/pybind11.h>

#include <string>

#include "bind_methods.h"
#include "interruptible.h"
#include "radiance/radiance_field.h"
#include "scene_use.h"
#include "struct_fields.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

py::dict timings_to_dict(const RadianceFieldTimings& timings) {
    py::dict out;
    out["voxelise"] = timings.voxelise;
    out["photons"] = timings.photons;
    out["radiance_grid"] = timings.radiance_grid;
    out["sh_field"] = timings.sh_field;
    out["photons_emitted"] = timings.photons_emitted;
    out["hits"] = timings.hits;
    out["sample_points"] = timings.sample_points;
    out["gather_rays"] = timings.gather_rays;
    return out;
}

void bind_settings(py::module_& m) {
    named_values_only(py::enum_<FaceEstimator>(
        m, "FaceEstimator", "How photon flux becomes radiance on the radiance grid's cell faces.")
        .value("PROJECTED_AREA", FaceEstimator::ProjectedArea)
        .value("PAPER", FaceEstimator::Paper));

    using S = RadianceFieldSettings;
    py::class_<S> cls(m, "RadianceFieldSettings",
                      "Settings of the RadianceField solver; every field has a default.");
    def_integer(cls, "photons", &S::photons, "Photons emitted per pass (200000).", 1);
    def_integer(cls, "seed", &S::seed, "Random seed (0).");
    def_integer(cls, "max_bounces", &S::max_bounces,
                "Photon scatterings after emission; 4 matches Cycles' default diffuse bounces.");
    def_integer(cls, "glossy_bounces", &S::glossy_bounces,
                "Photons' glossy scatterings, a budget of their own beside max_bounces, 0..64; 4 "
                "matches Cycles' default glossy bounces.");
    def_integer(cls, "resolution", &S::resolution,
                "SH-grid cells along the bounds' longest side, 1..128 (32, the paper's).");
    def_integer(cls, "gather_rays", &S::gather_rays,
                "Gather rays per sample point and pass, N_sh (400, the paper's).");
    def_integer(cls, "mip_levels", &S::mip_levels,
                "Levels of the radiance grid's mip chain, the finest included (4).");
    def_integer(cls, "diffuse_gather_rays", &S::diffuse_gather_rays,
                "Directions N_d of the diffuse Monte Carlo gather (32, the paper's).");
    def_integer(cls, "glossy_gather_rays", &S::glossy_gather_rays,
                "Directions N_g of the glossy (Phong-lobe) Monte Carlo gather (64, the paper's).");
    def_integer(cls, "obscurance_rays", &S::obscurance_rays,
                "Directions N_d of the obscurance estimate (32, the paper's).");
    cls.def(py::init(&from_kwargs<S>),
            "RadianceFieldSettings(**fields), e.g. RadianceFieldSettings(gather_rays=200).")
        .def_readwrite("specular_roughness", &S::specular_roughness,
                       "Lobes up to this roughness make caustic paths (0.1).")
        .def_readwrite("world_in_field", &S::world_in_field,
                       "Gather rays that leave the scene read the world, and renderers skip the "
                       "world in next-event estimation (False).")
        .def_readwrite("glossy_in_grid", &S::glossy_in_grid,
                       "Rough glossy reflection enters the radiance grid as if diffuse (the "
                       "paper's holds diffuse only) (True).")
        .def_readwrite("face_estimator", &S::face_estimator,
                       "FaceEstimator: PROJECTED_AREA (exact for lit planes) or the paper's PAPER.")
        .def_readwrite("face_sigma", &S::face_sigma,
                       "Standard deviation (rad) of the Gaussian weights of a hit cell's faces "
                       "(0.5).")
        .def_readwrite("use_mips", &S::use_mips,
                       "Read coarser radiance-grid levels for distant hits (True).")
        .def_readwrite("min_footprint_cosine", &S::min_footprint_cosine,
                       "Floor of cos(beta) in a ray's footprint 4 pi d^2 / (N cos beta) (0.1).")
        .def_readwrite("backface_threshold", &S::backface_threshold,
                       "Share of gather rays seeing back faces of closed meshes that marks a "
                       "sample point inside geometry (0.25).")
        .def_readwrite("side_test", &S::side_test,
                       "Skip sample points behind the shading point's tangent plane (True).")
        .def_readwrite("visibility_test", &S::visibility_test,
                       "Skip sample points the distance SH says are hidden (False).")
        .def_readwrite("occlusion_test", &S::occlusion_test,
                       "Skip sample points a surface separates from the shading point (a shadow "
                       "ray per lookup; not in the paper) (True).")
        .def_readwrite("monte_carlo_gathers", &S::monte_carlo_gathers,
                       "Irradiance and glossy light by the paper's Monte Carlo gathers of the SH "
                       "(diffuse_gather_rays, glossy_gather_rays) instead of the closed forms "
                       "(False).")
        .def_readwrite("obscurance", &S::obscurance,
                       "Multiply the field by the paper's obscurance, an ambient-occlusion look "
                       "(False).")
        .def_readwrite("obscurance_weight", &S::obscurance_weight, "w_oc of the obscurance (1).")
        .def_readwrite("obscurance_distance", &S::obscurance_distance,
                       "R_max (m) of the obscurance; 0 = two cells.")
        .def_readwrite("use_bounds", &S::use_bounds,
                       "Use bounds_min/bounds_max instead of the scene's bounds (False).");
    def_vec3(cls, "bounds_min", &S::bounds_min, "Lower corner (m) when use_bounds.");
    def_vec3(cls, "bounds_max", &S::bounds_max, "Upper corner (m) when use_bounds.");
    cls.def("validate", &validate_radiance_field_settings,
            "Raises ValueError naming the first invalid field.");
    register_settings_type<S>("RadianceFieldSettings");
}

ObjectUse field_use_of(const RadianceField& field, ObjectUse::Kind kind, const char* method) {
    return field_use(static_cast<const IndirectField*>(&field), kind,
                     std::string("RadianceField.") + method);
}

// A read-only property, refused while a pass of the field runs in another thread.
template <typename Read>
void def_idle_property(py::class_<RadianceField, IndirectField, GiSolver>& cls, const char* name,
                       Read read, const char* doc) {
    cls.def_property_readonly(
        name,
        [name, read](const RadianceField& field) {
            const ObjectUse reads = field_use_of(field, ObjectUse::Kind::Check, name);
            return read(field);
        },
        doc);
}

void bind_radiance_field(py::module_& m) {
    py::class_<RadianceField, IndirectField, GiSolver> cls(m, "RadianceField", R"doc(
The radiance-field solver (seed 001): photons on a face radiance grid, SH field by gather rays.

Each refine() traces `photons` more, adds their reflected flux to the grid and gathers the SH
field again (the field is the mean of all passes). After editing and re-committing the scene,
call reset().)doc");
    cls.def(py::init([](const Scene& scene, const RadianceFieldSettings& settings,
                         Progress* progress) {
                 validate_radiance_field_settings(settings);
                 SceneUse use(scene, SceneUse::Kind::Query, "RadianceField");
                 return run_interruptible(progress, [&](Progress* used) {
                     return std::make_unique<RadianceField>(scene, settings, used);
                 });
             }),
             py::arg("scene"), py::arg("settings") = RadianceFieldSettings{},
             py::arg("progress") = py::none(), py::keep_alive<1, 2>(),
             "Voxelises the scene: cells, their surfaces and sample points (the scene must be "
             "committed).")
        .def(
            "refine",
            [](RadianceField& field, Progress* progress) {
                const ObjectUse writes = field_use_of(field, ObjectUse::Kind::Write, "refine");
                SceneUse use(field.scene(), SceneUse::Kind::Query, "refine (RadianceField)");
                run_interruptible(progress, [&](Progress* used) { field.refine(used); });
            },
            py::arg("progress") = py::none(),
            "Traces one more pass of photons, updates the radiance grid and gathers the SH field "
            "(GIL released). Raises shgi.Cancelled on cancel, keeping the previous solution.")
        .def(
            "current_field", [](py::object self) { return self; },
            "The solver itself: it is its own IndirectField (not to be read while a pass runs).")
        .def(
            "reset",
            [](RadianceField& field, Progress* progress) {
                const ObjectUse writes = field_use_of(field, ObjectUse::Kind::Write, "reset");
                SceneUse use(field.scene(), SceneUse::Kind::Query, "reset (RadianceField)");
                run_interruptible(progress, [&](Progress* used) { field.reset(used); });
            },
            py::arg("progress") = py::none(),
            "Forgets every pass and voxelises the (re-committed) scene again.")
        .def_property_readonly("settings", &RadianceField::settings, "A copy of the settings.");
    def_idle_property(cls, "passes", [](const RadianceField& f) { return f.passes(); },
                      "Passes averaged so far.");
    def_idle_property(cls, "timings",
                      [](const RadianceField& f) { return timings_to_dict(f.timings()); },
                      "The last pass: seconds of voxelise (construction/reset), photons, "
                      "radiance_grid, sh_field; photons_emitted, hits, sample_points, "
                      "gather_rays.");
    def_idle_property(cls, "stage_seconds",
                      [](const RadianceField& f) { return stage_list(f.stage_seconds()); },
                      "[(stage, seconds)] of the last pass.");
    def_idle_property(cls, "memory_bytes", [](const RadianceField& f) { return f.memory_bytes(); },
                      "Bytes held by the grids and the SH field.");
}

}  // namespace

void bind_radiance(py::module_& m) {
    bind_settings(m);
    bind_radiance_field(m);
}

}  // namespace shgi::python
