// Bindings for native/probes: ProbeGrid (path-traced SH probes, probes/probe_grid.h), its
// settings, the immutable ProbeField snapshots renderers read, and probe files
// (probes/probe_storage.h). Settings mirror the C++ structs field by field.
//
// A ProbeGrid keeps its Scene alive; update() releases the GIL, so one Python thread can refine
// the grid while another renders with a field() snapshot taken earlier (seed 002 Fig. 4.1).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>

#include "numpy_convert.h"
#include "path_arg.h"
#include "bind_methods.h"
#include "probes/probe_grid.h"
#include "probes/probe_storage.h"
#include "render/light_tree.h"
#include "interruptible.h"
#include "scene_use.h"
#include "struct_fields.h"
#include "util/error.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

py::array_t<float> sh_array(const ProbeGridData& data) {
    const int coefficients = sh_num_coefficients(data.order);
    py::array_t<float> out({py::ssize_t(data.probe_count()), py::ssize_t(coefficients),
                            py::ssize_t(3)});
    float* dst = out.mutable_data();
    for (const ShRgb& sh : data.sh) {
        std::memcpy(dst, sh.data(), size_t(coefficients) * 3 * sizeof(float));
        dst += coefficients * 3;
    }
    return out;
}

py::array_t<bool> active_array(const ProbeGridData& data) {
    py::array_t<bool> out(py::ssize_t(data.probe_count()));
    for (size_t i = 0; i < data.probe_count(); ++i) out.mutable_data()[i] = data.active[i] != 0;
    return out;
}

py::array_t<float> float_array(const std::vector<float>& values) {
    py::array_t<float> out(py::ssize_t(values.size()));
    std::memcpy(out.mutable_data(), values.data(), values.size() * sizeof(float));
    return out;
}

// The read-only probe arrays shared by ProbeGrid and ProbeField; get(self) gives a shared_ptr to
// the data, which each read keeps alive.
template <typename Cls, typename GetData>
void def_probe_arrays(Cls& cls, GetData get) {
    cls.def_property_readonly(
           "order", [get](const typename Cls::type& self) { return get(self)->order; },
           "SH order of the probes (1..4).")
        .def_property_readonly(
            "probe_count",
            [get](const typename Cls::type& self) { return get(self)->probe_count(); },
            "Probes in all volumes (active or not).")
        .def_property_readonly(
            "positions",
            [get](const typename Cls::type& self) { return to_numpy(get(self)->positions); },
            "(N, 3) float32 probe positions after relocation (m, world).")
        .def_property_readonly(
            "active", [get](const typename Cls::type& self) { return active_array(*get(self)); },
            "(N,) bool: False for probes inside geometry (never updated or read).")
        .def_property_readonly(
            "sh", [get](const typename Cls::type& self) { return sh_array(*get(self)); },
            "(N, coefficients, 3) float32 incident radiance SH per probe (W m^-2 sr^-1), index "
            "l(l+1)+m, no Condon-Shortley phase.")
        .def_property_readonly(
            "variance",
            [get](const typename Cls::type& self) { return float_array(get(self)->variance); },
            "(N,) float32 variance of each probe's DC luminance estimate.")
        .def_property_readonly(
            "volumes",
            [get](const typename Cls::type& self) { return get(self)->volumes; },
            "The ProbeVolumes, in probe order.")
        .def(
            "save",
            [get](const typename Cls::type& self, const PathArg& path) {
                ProbeGridData data = *get(self);
                py::gil_scoped_release release;
                save_probe_grid(path, data);
            },
            py::arg("path"),
            "Writes the compact binary cache (SH at half precision: 56 bytes per L2 probe).")
        .def(
            "export",
            [get](const typename Cls::type& self, const PathArg& json_path) {
                ProbeGridData data = *get(self);
                py::gil_scoped_release release;
                export_probe_grid(json_path, data);
            },
            py::arg("json_path"),
            "Writes <stem>.json and per volume <stem>_volume<v>.exr (float SH, positions, "
            "active, variance) and <stem>_volume<v>_visibility.exr; the JSON states basis, "
            "units and layout.");
}

void bind_settings(py::module_& m) {
    py::class_<ProbeVolume> volume(m, "ProbeVolume", R"doc(
A box of probes: the cube [-1, 1]^3 of world_from_volume (like Blender's irradiance volume
object), with resolution probes along each local axis at the cell centres.)doc");
    volume
        .def(py::init(&from_kwargs<ProbeVolume>),
             "ProbeVolume(world_from_volume=4x4, resolution=(nx, ny, nz)).")
        .def_property(
            "world_from_volume",
            [](const ProbeVolume& v) { return from_mat4(v.world_from_volume); },
            [](ProbeVolume& v, const py::object& matrix) {
                v.world_from_volume = to_mat4(matrix, "world_from_volume");
            },
            "4x4 matrix (row-major, Blender's matrix_world) mapping [-1,1]^3 to the world.")
        .def_property(
            "resolution",
            [](const ProbeVolume& v) {
                return py::make_tuple(v.resolution.x, v.resolution.y, v.resolution.z);
            },
            [](ProbeVolume& v, const py::sequence& r) {
                if (r.size() != 3) throw_value_error("resolution", "needs 3 integers");
                v.resolution = ivec3(checked_integer<int>(r[0], "resolution[0]"),
                                     checked_integer<int>(r[1], "resolution[1]"),
                                     checked_integer<int>(r[2], "resolution[2]"));
            },
            "Probes along the local x, y, z axes, each >= 1.")
        .def("__repr__", [](const ProbeVolume& v) {
            return format_message("ProbeVolume(resolution=(", v.resolution.x, ", ",
                                  v.resolution.y, ", ", v.resolution.z, "))");
        });

    using L = ProbeLookupSettings;
    py::class_<L> lookup(m, "ProbeLookupSettings",
                         "How shading points read probes (EEVEE: Bias, Bleed Bias).");
    lookup.def(py::init(&from_kwargs<L>), "ProbeLookupSettings(**fields).")
        .def_readwrite("visibility", &L::visibility,
                       "Back-face and Chebyshev visibility weights; False = plain trilinear (True).")
        .def_readwrite("normal_bias", &L::normal_bias,
                       "Probe spacings the shading point moves along its normal (0.25).")
        .def_readwrite("view_bias", &L::view_bias,
                       "Probe spacings the shading point moves towards the viewer (0).")
        .def_readwrite("bleed_bias", &L::bleed_bias,
                       "Chebyshev weights below it become 0, against light bleeding (0).");

    using S = ProbeGridSettings;
    py::class_<S> cls(m, "ProbeGridSettings",
                      "Settings of the ProbeGrid solver; every field has a default.");
    def_integer(cls, "seed", &S::seed, "Random seed (0).");
    def_integer(cls, "rays_per_probe", &S::rays_per_probe, "Paths per probe per update (256).");
    def_integer(cls, "placement_rays", &S::placement_rays, "Rays per probe for placement (128).");
    def_integer(cls, "order", &S::order, "SH order of the probes, 1..4 (2).");
    def_integer(cls, "bounces", &S::bounces,
                "Diffuse and glossy scatterings along a probe path (3: with the "
                "renderer's surface, Cycles' default 4).");
    def_integer(cls, "light_splits", &S::light_splits,
                "Most emitters one next-event estimate on a probe path samples, as "
                "PathTracerSettings.light_splits (4).",
                1, kMaxLightSplits);
    def_integer(cls, "visibility_resolution", &S::visibility_resolution,
                "Octahedral visibility texels per side per probe (8).");
    cls.def(py::init(&from_kwargs<S>), "ProbeGridSettings(**fields), e.g. ProbeGridSettings(order=1).")
        .def_readwrite("volumes", &S::volumes,
                       "List of ProbeVolume; empty: one volume fitted to the scene bounds.")
        .def_readwrite("spacing", &S::spacing,
                       "Probe spacing (m) of the fitted volume; 0 = longest side / 8.")
        .def_readwrite("hysteresis", &S::hysteresis,
                       "History weight of the exponential blend, in [0, 1) (0.95).")
        .def_readwrite("clamp", &S::clamp,
                       "A radiance sample whose components average more than this is scaled "
                       "down to it (Light Paths > Clamp Indirect, as Cycles clamps); 0 = off (0).")
        .def_readwrite("include_direct", &S::include_direct,
                       "Keep emitters and world seen straight from the probes (False).")
        .def_readwrite("visibility", &S::visibility, "Leak prevention weights (True).")
        .def_readwrite("visibility_blur", &S::visibility_blur,
                       "Angular radius (rad) of the distance filter (0.10; EEVEE's Blur).")
        .def_readwrite("normal_bias", &S::normal_bias,
                       "Probe spacings along the surface's interpolated normal (0.25; EEVEE's "
                       "Bias).")
        .def_readwrite("view_bias", &S::view_bias,
                       "Probe spacings towards the viewer (0; DDGI's view bias).")
        .def_readwrite("bleed_bias", &S::bleed_bias, "Chebyshev cut-off (0; EEVEE's Bleed Bias).")
        .def_readwrite("relocate", &S::relocate,
                       "Move probes out of geometry before disabling them (True).")
        .def_readwrite("max_offset", &S::max_offset,
                       "Largest relocation, in probe spacings per axis (0.45).")
        .def_readwrite("backface_threshold", &S::backface_threshold,
                       "Share of back-face hits marking a probe as inside geometry (0.25).")
        .def("validate", &validate_probe_grid_settings,
             "Raises ValueError naming the first invalid field.");
    register_settings_type<S>("ProbeGridSettings");
}

void bind_field(py::module_& m) {
    py::class_<ProbeField, IndirectField> cls(m, "ProbeField", R"doc(
An immutable snapshot of SH probes, read as an IndirectField (render_preview, PreviewRenderer).
From ProbeGrid.field(), ProbeField.load(path) or ProbeField.import_exr(json_path).)doc");
    def_probe_arrays(cls, [](const ProbeField& f) { return f.shared_data(); });
    cls.def_property_readonly("passes", [](const ProbeField& f) { return f.data().passes; },
                              "Update passes blended into these probes.")
        .def_static(
            "load",
            [](const PathArg& path, const ProbeLookupSettings& lookup) {
                auto data = std::make_shared<const ProbeGridData>([&] {
                    py::gil_scoped_release release;
                    return load_probe_grid(path);
                }());
                return std::make_unique<ProbeField>(data, lookup);
            },
            py::arg("path"), py::arg("lookup") = ProbeLookupSettings{},
            "Reads a binary cache written by save() (OSError naming a bad file).")
        .def_static(
            "import_exr",
            [](const PathArg& json_path, const ProbeLookupSettings& lookup) {
                auto data = std::make_shared<const ProbeGridData>([&] {
                    py::gil_scoped_release release;
                    return import_probe_grid(json_path);
                }());
                return std::make_unique<ProbeField>(data, lookup);
            },
            py::arg("json_path"), py::arg("lookup") = ProbeLookupSettings{},
            "Reads an EXR + JSON export written by export().")
        .def(
            "with_lookup",
            [](const ProbeField& f, const ProbeLookupSettings& lookup) {
                return std::make_unique<ProbeField>(f.shared_data(), lookup);
            },
            py::arg("lookup"), "The same probes read with other lookup settings.")
        .def(
            "splice",
            [](const ProbeField& f, const ProbeField& brick, const IndexInt& first_arg,
               const IndexInt& count_arg) {
                const size_t first = int_arg<size_t>(first_arg, "first");
                const size_t count = int_arg<size_t>(count_arg, "count");
                auto data = std::make_shared<const ProbeGridData>([&] {
                    py::gil_scoped_release release;
                    return splice_probes(f.data(), brick.data(), first, count);
                }());
                return std::make_unique<ProbeField>(data, f.lookup_settings());
            },
            py::arg("brick"), py::arg("first"), py::arg("count"),
            "These probes with probes first .. first + count - 1 (their SH, variance and "
            "visibility) taken from `brick`, the same grid after the same passes whose probes "
            "there were updated apart (ProbeGrid.update_probes): the merge of a solve split "
            "into bricks. ValueError names the first difference between the two grids.");
}

py::dict timings_to_dict(const ProbeGridTimings& timings) {
    py::dict out;
    out["placement"] = timings.placement;
    out["update"] = timings.update;
    out["paths"] = timings.paths;
    out["rays"] = timings.rays;
    return out;
}

void bind_grid(py::module_& m) {
    py::class_<ProbeGrid, IndirectField, GiSolver> cls(m, "ProbeGrid", R"doc(
SH probe grids updated by path tracing (seed 002), with DDGI-style relocation and visibility.

Each refine() (or update(), its older name) traces rays_per_probe paths per active probe and blends them into the probes
(running mean, then an exponential blend with `hysteresis`). field() returns a snapshot for
rendering that later updates leave untouched. After editing and re-committing the scene, call
reset().)doc");
    // A snapshot per read: update() on another thread may replace the grid's data.
    def_probe_arrays(cls, [](const ProbeGrid& g) { return g.field()->shared_data(); });
    const auto update = [](ProbeGrid& grid, Progress* progress) {
        SceneUse use(grid.scene(), SceneUse::Kind::Query, "refine (ProbeGrid)");
        run_interruptible(progress, [&](Progress* used) { grid.refine(used); });
    };
    const auto field_of = [](const ProbeGrid& grid) {
        const auto snapshot = grid.field();
        return std::make_unique<ProbeField>(snapshot->shared_data(), snapshot->lookup_settings());
    };
    cls.def(py::init([](const Scene& scene, const ProbeGridSettings& settings,
                         Progress* progress) {
                 validate_probe_grid_settings(settings);
                 SceneUse use(scene, SceneUse::Kind::Query, "ProbeGrid");
                 return run_interruptible(progress, [&](Progress* used) {
                     return std::make_unique<ProbeGrid>(scene, settings, used);
                 });
             }),
             py::arg("scene"), py::arg("settings") = ProbeGridSettings{},
             py::arg("progress") = py::none(), py::keep_alive<1, 2>(),
             "Places the probes (the scene must be committed).")
        .def_static(
            "from_field",
            [](const Scene& scene, const ProbeGridSettings& settings, const ProbeField& field) {
                SceneUse use(scene, SceneUse::Kind::Query, "ProbeGrid.from_field");
                return std::make_unique<ProbeGrid>(scene, settings, field.data());
            },
            py::arg("scene"), py::arg("settings"), py::arg("field"), py::keep_alive<0, 1>(),
            "Continues refining stored probes (their volumes and order replace the settings').")
        .def("refine", update, py::arg("progress") = py::none(),
             "One update pass (GIL released). Raises shgi.Cancelled on cancel, keeping the "
             "previous probes.")
        .def("update", update, py::arg("progress") = py::none(), "The same as refine().")
        .def(
            "update_probes",
            [](ProbeGrid& grid, const IndexInt& first_arg, const IndexInt& count_arg,
               Progress* progress) {
                const uint64_t first = int_arg<uint64_t>(first_arg, "first");
                const uint64_t count = int_arg<uint64_t>(count_arg, "count");
                SceneUse use(grid.scene(), SceneUse::Kind::Query, "update_probes (ProbeGrid)");
                run_interruptible(progress,
                                  [&](Progress* used) { grid.update_probes(first, count, used); });
            },
            py::arg("first"), py::arg("count"), py::arg("progress") = py::none(),
            "One update pass over probes first .. first + count - 1 only (a brick of a solve "
            "split over machines); the others keep their state, the pass counts. Bricks "
            "updated apart and merged with ProbeField.splice equal update() bit for bit.")
        .def(
            "reset",
            [](ProbeGrid& grid, Progress* progress) {
                SceneUse use(grid.scene(), SceneUse::Kind::Query, "reset (ProbeGrid)");
                run_interruptible(progress, [&](Progress* used) { grid.reset(used); });
            },
            py::arg("progress") = py::none(), "Forgets every pass and re-places the probes.")
        .def("field", field_of, "An immutable ProbeField of the current probes (safe to render "
                             "while refine() runs on another thread).")
        .def("current_field", field_of, "The same as field().")
        .def_property_readonly(
            "stage_seconds", [](const ProbeGrid& g) { return stage_list(g.stage_seconds()); },
            "[(stage, seconds)] of the last placement and pass.")
        .def_property_readonly("passes", &ProbeGrid::passes, "Update passes blended in.")
        .def_property_readonly("active_count", &ProbeGrid::active_count,
                               "Probes outside geometry.")
        .def_property_readonly("settings", &ProbeGrid::settings, "A copy of the settings.")
        .def_property_readonly(
            "timings", [](const ProbeGrid& g) { return timings_to_dict(g.timings()); },
            "Seconds of the last placement and update; paths (and rays) of the last update.")
        .def(
            "relative_error", [](const ProbeGrid& g) { return float_array(g.relative_error()); },
            "(N,) sqrt(variance) / DC luminance per probe (inf before the first update).")
        .def_property_readonly("memory_bytes", &ProbeGrid::memory_bytes,
                               "Bytes held by the probes.");
}

}  // namespace

void bind_probes(py::module_& m) {
    bind_settings(m);
    bind_field(m);
    bind_grid(m);
}

}  // namespace shgi::python
