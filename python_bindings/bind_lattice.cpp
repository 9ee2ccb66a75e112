// Bindings for native/lattice: the PhotonLattice solver (lattice/photon_lattice.h) and its
// settings, mirrored field by field with the same names and defaults.
//
// A PhotonLattice keeps its Scene alive; solve() releases the GIL and reports progress. It is a
// shgi.IndirectField, so shgi.render_preview and the PreviewRenderer take it directly.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "bind_methods.h"
#include "lattice/photon_lattice.h"
#include "numpy_convert.h"
#include "interruptible.h"
#include "path_arg.h"
#include "scene_use.h"
#include "struct_fields.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

py::dict lattice_dict(const ShLattice& lattice) {
    py::dict d;
    const vec3 origin = lattice.origin();
    const ivec3 dims = lattice.dims();
    d["origin"] = py::make_tuple(origin.x, origin.y, origin.z);
    d["cell_size"] = lattice.cell_size();
    d["dims"] = py::make_tuple(dims.x, dims.y, dims.z);
    d["order"] = lattice.order();
    const std::vector<float>& c = lattice.coefficients();
    if (c.size() != lattice.cell_count() * size_t(lattice.num_coefficients()) * 3)
        throw std::runtime_error("PhotonLattice.lattices: the lattice is not built yet");
    py::array_t<float> sh({py::ssize_t(dims.z), py::ssize_t(dims.y), py::ssize_t(dims.x),
                           py::ssize_t(lattice.num_coefficients()), py::ssize_t(3)});
    std::copy(c.begin(), c.end(), sh.mutable_data());
    d["sh"] = sh;
    return d;
}

py::dict timings_to_dict(const PhotonLatticeTimings& timings) {
    py::dict out;
    out["emit_trace"] = timings.emit_trace;
    out["injection"] = timings.injection;
    out["blur"] = timings.blur;
    out["photons_emitted"] = timings.photons_emitted;
    out["photons_stored"] = timings.photons_stored;
    out["bounces"] = timings.bounces;
    return out;
}

void bind_settings(py::module_& m) {
    named_values_only(py::enum_<CausticMode>(
        m, "CausticMode", "Where caustic photons (light → specular+ → diffuse) go.")
        .value("OFF", CausticMode::Off)
        .value("LATTICE", CausticMode::Lattice)
        .value("PHOTON_MAP", CausticMode::PhotonMap));
    named_values_only(
        py::enum_<LatticeInterpolation>(m, "LatticeInterpolation", "How lattices are sampled.")
        .value("TRILINEAR", LatticeInterpolation::Trilinear)
        .value("CUBIC", LatticeInterpolation::Cubic));

    using S = PhotonLatticeSettings;
    py::class_<S> cls(m, "PhotonLatticeSettings",
                      "Settings of the PhotonLattice solver; every field has a default.");
    def_integer(cls, "photons", &S::photons, "Photons emitted per solve() (200000).", 1);
    def_integer(cls, "seed", &S::seed, "Random seed (0).");
    def_integer(cls, "max_bounces", &S::max_bounces,
                "Photon scatterings after emission; 4 matches Cycles' default diffuse "
                "bounces (4).");
    def_integer(cls, "glossy_bounces", &S::glossy_bounces,
                "Photon glossy scatterings, a budget apart from max_bounces as Cycles' Glossy "
                "bounces (4); -1: counted against max_bounces.");
    def_integer(cls, "resolution", &S::resolution,
                "Global lattice: cells along the bounds' longest side (16).");
    def_integer(cls, "order", &S::order, "Global lattice SH order, 1 or 2 (2).");
    def_integer(cls, "blur_passes", &S::blur_passes,
                "3x3x3 blurs of the global lattice (0: blurring darkens corners).");
    def_integer(cls, "caustic_resolution", &S::caustic_resolution,
                "Caustic lattice: cells along the longest side (64).");
    def_integer(cls, "caustic_order", &S::caustic_order, "Caustic lattice SH order (1).");
    def_integer(cls, "caustic_blur_passes", &S::caustic_blur_passes,
                "3x3x3 blurs of the caustic lattice (0).");
    def_integer(cls, "caustic_neighbours", &S::caustic_neighbours,
                "Photons per density estimate, PHOTON_MAP mode (50).");
    cls.def(py::init(&from_kwargs<S>),
            "PhotonLatticeSettings(**fields), e.g. PhotonLatticeSettings(photons=100000).")
        .def_readwrite("specular_roughness", &S::specular_roughness,
                       "Lobes up to this roughness make caustic paths (0.1).")
        .def_readwrite("world_in_field", &S::world_in_field,
                       "The lattices carry the world's direct light; renderers skip the world "
                       "in next-event estimation; that light then lands in the Ind passes (False).")
        .def_readwrite("caustics", &S::caustics, "CausticMode (LATTICE).")
        .def_readwrite("caustic_radius", &S::caustic_radius,
                       "Max radius (m) of the density estimate; 0 = 2% of the bounds' diagonal.")
        .def_readwrite("interpolation", &S::interpolation, "LatticeInterpolation (CUBIC).")
        .def_readwrite("normal_offset", &S::normal_offset,
                       "Cells along the normal before sampling, against self-lighting (0.25).")
        .def_readwrite("use_bounds", &S::use_bounds,
                       "Use bounds_min/bounds_max instead of the scene's bounds (False).");
    def_vec3(cls, "bounds_min", &S::bounds_min, "Lower corner (m) when use_bounds.");
    def_vec3(cls, "bounds_max", &S::bounds_max, "Upper corner (m) when use_bounds.");
    cls.def("validate", &validate_photon_lattice_settings,
            "Raises ValueError naming the first invalid field.");
    register_settings_type<S>("PhotonLatticeSettings");
}

// The lattice as an IndirectField (the key renders and lookups guard it by).
ObjectUse lattice_use(const PhotonLattice& lattice, ObjectUse::Kind kind, const char* method) {
    return field_use(static_cast<const IndirectField*>(&lattice), kind,
                     std::string("PhotonLattice.") + method);
}

// A read-only property `name` = read(lattice), refused while a solve() or reset() of the lattice
// runs in another thread (they replace what it reads).
template <typename Read>
void def_idle_property(py::class_<PhotonLattice, IndirectField, GiSolver>& cls, const char* name,
                       Read read, const char* doc) {
    cls.def_property_readonly(
        name,
        [name, read](const PhotonLattice& lattice) {
            const ObjectUse reads = lattice_use(lattice, ObjectUse::Kind::Check, name);
            return read(lattice);
        },
        doc);
}

void bind_photon_lattice(py::module_& m) {
    py::class_<PhotonLattice, IndirectField, GiSolver> cls(m, "PhotonLattice", R"doc(
The ISLLPM solver (seed 000): photons traced from the lights, injected into SH lattices.

Interactive: call refine() repeatedly; each call traces `photons` more and the lattices
average all passes. Non-interactive: one refine() with many photons, then render any camera.
After editing and re-committing the scene, call reset().)doc");
    // refine() and its older name solve(), each named as called in the messages.
    const auto pass_named = [](const char* name) {
        return [name](PhotonLattice& lattice, Progress* progress) {
            const ObjectUse writes = lattice_use(lattice, ObjectUse::Kind::Write, name);
            SceneUse use(lattice.scene(), SceneUse::Kind::Query,
                         (std::string(name) + " (PhotonLattice)").c_str());
            run_interruptible(progress, [&](Progress* used) { lattice.refine(used); });
        };
    };
    cls.def(py::init([](const Scene& scene, const PhotonLatticeSettings& settings,
                         Progress* progress) {
                 validate_photon_lattice_settings(settings);
                 SceneUse use(scene, SceneUse::Kind::Query, "PhotonLattice");
                 return run_interruptible(progress, [&](Progress* used) {
                     return std::make_unique<PhotonLattice>(scene, settings, used);
                 });
             }),
             py::arg("scene"), py::arg("settings") = PhotonLatticeSettings{},
             py::arg("progress") = py::none(), py::keep_alive<1, 2>(),
             "Measures the surface inside the lattices' cells (the scene must be committed).")
        .def("refine", pass_named("refine"), py::arg("progress") = py::none(),
             "Traces one more pass of photons and rebuilds the lattices (GIL released). Raises "
             "shgi.Cancelled on cancel, keeping the previous solution.")
        .def("solve", pass_named("solve"), py::arg("progress") = py::none(),
             "The same as refine().")
        .def(
            "solve_batches",
            [](PhotonLattice& lattice, const std::vector<const PhotonBatch*>& batches,
               Progress* progress) {
                const ObjectUse writes = lattice_use(lattice, ObjectUse::Kind::Write,
                                                     "solve_batches");
                SceneUse use(lattice.scene(), SceneUse::Kind::Query,
                             "solve_batches (PhotonLattice)");
                run_interruptible(progress, [&](Progress* used) {
                    lattice.solve_batches(batches, used);
                });
            },
            py::arg("batches"), py::arg("progress") = py::none(),
            "The next pass from PhotonBatch objects traced apart (shgi.trace_photon_batch) that "
            "together cover its photons [0, settings.photons), in any order: the lattice then "
            "equals the one solve() makes, bit for bit (GIL released). ValueError, changing "
            "nothing, for a batch with other settings, of another pass, or ranges with gaps or "
            "overlaps; shgi.Cancelled keeps the previous solution.")
        .def(
            "current_field", [](py::object self) { return self; },
            "The lattice itself: it is its own IndirectField (not to be read while a pass runs).")
        .def(
            "reset",
            [](PhotonLattice& lattice, Progress* progress) {
                const ObjectUse writes = lattice_use(lattice, ObjectUse::Kind::Write, "reset");
                SceneUse use(lattice.scene(), SceneUse::Kind::Query, "reset (PhotonLattice)");
                run_interruptible(progress, [&](Progress* used) { lattice.reset(used); });
            },
            py::arg("progress") = py::none(),
            "Forgets every pass and re-measures the (re-committed) scene.")
        .def_property_readonly("settings", &PhotonLattice::settings, "A copy of the settings.")
        .def(
            "save",
            [](const PhotonLattice& lattice, const PathArg& path) {
                const ObjectUse reads = lattice_use(lattice, ObjectUse::Kind::Read, "save");
                py::gil_scoped_release release;
                lattice.save(path);
            },
            py::arg("path"),
            "Writes the solved lattices, their settings, caustic photons and timings to a binary "
            "file (float32 as held, so load() looks up the same light; OSError naming a path "
            "that cannot be written).")
        .def_static(
            "load",
            [](const PathArg& path) {
                py::gil_scoped_release release;
                return PhotonLattice::load(path);
            },
            py::arg("path"),
            "A PhotonLattice read from save()'s file: it renders and reports as the saved one, "
            "but has no scene, so refine() and reset() raise ValueError (OSError naming a bad "
            "file).");
    def_idle_property(cls, "passes", [](const PhotonLattice& l) { return l.passes(); },
                      "Solve passes averaged so far.");
    def_idle_property(cls, "timings",
                      [](const PhotonLattice& l) { return timings_to_dict(l.timings()); },
                      "The last solve: seconds of emit_trace, injection, blur; photons_emitted, "
                      "photons_stored, bounces.");
    def_idle_property(cls, "stage_seconds",
                      [](const PhotonLattice& l) { return stage_list(l.stage_seconds()); },
                      "[(stage, seconds)] of the last pass.");
    def_idle_property(cls, "memory_bytes", [](const PhotonLattice& l) { return l.memory_bytes(); },
                      "Bytes held by the lattices and photon map.");
    def_idle_property(
        cls, "lattices",
        [](const PhotonLattice& l) {
            py::dict out;
            out["global"] = lattice_dict(l.global_lattice());
            out["caustic"] = lattice_dict(l.caustic_lattice());
            return out;
        },
        "The solved (averaged, blurred) lattices as {'global': ..., 'caustic': ...}, each a "
        "dict: origin (x, y, z) of the lower corner (m), cell_size (m), dims (nx, ny, nz), "
        "order, sh: float32 array (nz, ny, nx, coefficients, 3) of incident radiance "
        "(W m^-2 sr^-1, index l(l+1)+m, no Condon-Shortley phase), cell (i, j, k) centred at "
        "origin + (i + 0.5, j + 0.5, k + 0.5) cell_size.");
}

void bind_photon_batch(py::module_& m) {
    py::class_<PhotonBatch> cls(m, "PhotonBatch", R"doc(
Photons [begin, end) of one pass of a PhotonLattice, traced apart (shgi.trace_photon_batch, on
any machine with the same scene): the stored photons in photon order. PhotonLattice.solve_batches
merges the batches of a pass into exactly the lattice solve() makes (shgi.farm traces them as
tasks of a Dask cluster). Pickles as to_bytes().)doc");
    cls.def_property_readonly(
           "settings", [](const PhotonBatch& b) { return b.settings; },
           "The PhotonLatticeSettings it was traced with.")
        .def_readonly("pass_index", &PhotonBatch::pass, "The pass (0, 1, ...) it belongs to.")
        .def_readonly("begin", &PhotonBatch::begin, "Its first photon index.")
        .def_readonly("end", &PhotonBatch::end, "One past its last photon index.")
        .def_readonly("emitted", &PhotonBatch::emitted,
                      "Photons emitted (end - begin; 0 in a scene without emitters).")
        .def_readonly("bounces", &PhotonBatch::bounces, "Rays traced.")
        .def_readonly("seconds", &PhotonBatch::seconds, "Tracing time.")
        .def_property_readonly(
            "photons_stored",
            [](const PhotonBatch& b) { return b.global.size() + b.caustic.size(); },
            "Stored photons (global and caustic).")
        .def(
            "to_bytes",
            [](const PhotonBatch& b) {
                std::string bytes;
                {
                    py::gil_scoped_release release;
                    bytes = b.to_bytes();
                }
                return py::bytes(bytes);
            },
            "The batch as bytes (exact: float32 as held; 48 bytes per stored photon).")
        .def_static(
            "from_bytes",
            [](const py::bytes& data, const std::string& what) {
                std::string bytes = data;
                py::gil_scoped_release release;
                return PhotonBatch::from_bytes(bytes, what);
            },
            py::arg("data"), py::arg("what") = "bytes",
            "The batch to_bytes() made; OSError naming `what` for bytes that are not one.")
        .def(py::pickle(
            [](const PhotonBatch& b) { return py::bytes(b.to_bytes()); },
            [](const py::bytes& data) { return PhotonBatch::from_bytes(data, "a pickled batch"); }))
        .def("__repr__", [](const PhotonBatch& b) {
            return "PhotonBatch(pass_index=" + std::to_string(b.pass) + ", photons [" +
                   std::to_string(b.begin) + ", " + std::to_string(b.end) + "), " +
                   std::to_string(b.global.size() + b.caustic.size()) + " stored)";
        });
    m.def(
        "trace_photon_batch",
        [](const Scene& scene, const PhotonLatticeSettings& settings, const IndexInt& pass_arg,
           const IndexInt& begin_arg, const IndexInt& end_arg, Progress* progress) {
            const uint64_t pass = int_arg<uint64_t>(pass_arg, "pass_index");
            const uint64_t begin = int_arg<uint64_t>(begin_arg, "begin");
            const uint64_t end = int_arg<uint64_t>(end_arg, "end");
            validate_photon_lattice_settings(settings);
            SceneUse use(scene, SceneUse::Kind::Query, "trace_photon_batch");
            return run_interruptible(progress, [&](Progress* used) {
                return trace_photon_batch(scene, settings, pass, begin, end, used);
            });
        },
        py::arg("scene"), py::arg("settings"), py::arg("pass_index"), py::arg("begin"),
        py::arg("end"), py::arg("progress") = py::none(),
        "Photons [begin, end) of pass `pass_index` of a PhotonLattice with `settings` on the "
        "committed scene, as a PhotonBatch (GIL released; shgi.Cancelled on cancel; ValueError "
        "unless begin < end <= settings.photons). Each photon's path depends only on the seed, "
        "the pass, its index and settings.photons, so any split merges into the single solve.");
}

}  // namespace

void bind_lattice(py::module_& m) {
    bind_settings(m);
    bind_photon_batch(m);  // before PhotonLattice.solve_batches names it in its signature
    bind_photon_lattice(m);
}

}  // namespace shgi::python
