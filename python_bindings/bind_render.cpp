// Bindings for native/render: the reference path tracer (render/path_tracer.h).
//
// shgi.PathTracerSettings mirrors the C++ struct field by field (same names, same defaults);
// shgi.PathTracer renders progressively into its film; shgi.render_path_traced is the one-shot
// form. Passes come back as a dict {pass name: float32 array (H, W, C)}, top row first, with
// Cycles' pass names and meaning (render/film.h). Settings are checked with the GIL held; the
// GIL is released while rendering, and the progress callback takes it back itself.
//
// The PathTracer keeps its Scene alive, but the scene must not be edited or re-committed while
// a render runs in another thread.
#include <cstring>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "numpy_convert.h"
#include "scene_use.h"
#include "render/path_tracer.h"
#include "util/error.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

py::dict passes_to_dict(const Film& film) {
    py::dict out;
    for (int p = 0; p < kPassCount; ++p) {
        const Pass pass = Pass(p);
        const std::vector<float> pixels = film.pixels(pass);
        const py::ssize_t channels = py::ssize_t(pass_suffixes(pass).size());
        py::array_t<float> array({py::ssize_t(film.height()), py::ssize_t(film.width()), channels});
        std::memcpy(array.mutable_data(), pixels.data(), pixels.size() * sizeof(float));
        out[pass_name(pass)] = std::move(array);
    }
    return out;
}

uint32_t checked_samples(int64_t samples, const char* arg_name) {
    if (samples < 1 || uint64_t(samples) > kMaxPathTracerSamples)
        throw_value_error(arg_name, format_message("must be in [1, ", kMaxPathTracerSamples,
                                                   "], got ", samples));
    return uint32_t(samples);
}

void bind_settings(py::module_& m) {
    py::enum_<WorldSampling>(m, "WorldSampling", "How next-event estimation samples the world.")
        .value("COSINE", WorldSampling::Cosine)
        .value("UNIFORM", WorldSampling::Uniform);
    using S = PathTracerSettings;
    py::class_<S> cls(m, "PathTracerSettings",
                      "Settings of the reference path tracer; every field has a default.");
    cls.def(py::init([](const py::kwargs& kwargs) {
                S settings;
                py::object self = py::cast(settings);
                for (const auto& item : kwargs) {
                    const std::string key = py::str(item.first);
                    if (!py::hasattr(self, key.c_str()))
                        throw_value_error(key.c_str(), "is not a PathTracerSettings field");
                    self.attr(key.c_str()) = item.second;
                }
                return self.cast<S>();
            }),
            "PathTracerSettings(**fields), e.g. PathTracerSettings(samples=16, seed=3).")
        .def_property(
            "samples", [](const S& s) { return s.samples; },
            [](S& s, int64_t v) { s.samples = checked_samples(v, "samples"); },
            "Samples per pixel rendered by render_path_traced (default 64).")
        .def_property(
            "seed", [](const S& s) { return s.seed; },
            [](S& s, int64_t v) {
                if (v < 0) throw_value_error("seed", "must be >= 0, got " + std::to_string(v));
                s.seed = uint64_t(v);
            },
            "Random seed; the image is a pure function of it (default 0).")
        .def_readwrite("max_bounces", &S::max_bounces, "Total bounce limit, Cycles' (12).")
        .def_readwrite("diffuse_bounces", &S::diffuse_bounces, "Diffuse bounce limit (4).")
        .def_readwrite("glossy_bounces", &S::glossy_bounces, "Glossy bounce limit (4).")
        .def_readwrite("transmission_bounces", &S::transmission_bounces,
                       "Transmission bounce limit (12).")
        .def_readwrite("russian_roulette_depth", &S::russian_roulette_depth,
                       "Surfaces before Russian roulette may end a path (3).")
        .def_readwrite("clamp_indirect", &S::clamp_indirect,
                       "Max component of an indirect sample's contribution; 0 = off (0).")
        .def_readwrite("world_sampling", &S::world_sampling, "WorldSampling (COSINE).")
        .def_readwrite("tile_size", &S::tile_size, "Tile side in pixels (16).")
        .def("validate", &validate_path_tracer_settings,
             "Raises ValueError naming the first invalid field.");
}

void bind_path_tracer(py::module_& m) {
    py::class_<PathTracer>(m, "PathTracer", R"doc(
Progressive reference path tracer over a committed Scene with a camera.

render(samples) adds samples to the film; passes() returns every pass so far. The result
depends only on the seed and the total sample count, not on threads or how the samples
were split between render() calls.)doc")
        .def(py::init([](const Scene& scene, const PathTracerSettings& settings) {
                 return std::make_unique<PathTracer>(scene, settings);
             }),
             py::arg("scene"), py::arg("settings") = PathTracerSettings{}, py::keep_alive<1, 2>(),
             "Checks the settings (ValueError) and prepares light sampling.")
        .def(
            "render",
            [](PathTracer& tracer, const py::object& samples, Progress* progress) {
                const uint32_t count =
                    samples.is_none() ? tracer.settings().samples
                                      : checked_samples(samples.cast<int64_t>(), "samples");
                SceneUse use(tracer.scene(), SceneUse::Kind::Query, "render (PathTracer)");
                py::gil_scoped_release release;
                tracer.render(count, progress);
            },
            py::arg("samples") = py::none(), py::arg("progress") = py::none(),
            "Adds `samples` samples per pixel (default settings.samples) with the GIL released. "
            "Raises shgi.Cancelled when progress.cancel() is called; the film is then unchanged.")
        .def("passes", [](const PathTracer& tracer) { return passes_to_dict(tracer.film()); },
             "{pass name: float32 array (H, W, C)}: Combined (RGBA), DiffDir, ..., Normal (XYZ), "
             "Depth (1 channel), with Cycles' meaning.")
        .def_property_readonly("samples_done", &PathTracer::samples_done,
                               "Samples per pixel accumulated so far.");

    m.def(
        "render_path_traced",
        [](const Scene& scene, const PathTracerSettings& settings, Progress* progress) {
            validate_path_tracer_settings(settings);
            PathTracer tracer(scene, settings);
            {
                SceneUse use(scene, SceneUse::Kind::Query, "render (render_path_traced)");
                py::gil_scoped_release release;
                tracer.render(settings.samples, progress);
            }
            return passes_to_dict(tracer.film());
        },
        py::arg("scene"), py::arg("settings") = PathTracerSettings{},
        py::arg("progress") = py::none(),
        "Renders settings.samples samples per pixel of the scene's camera; returns "
        "{pass name: float32 array (H, W, C)}.");
}

}  // namespace

void bind_render(py::module_& m) {
    bind_settings(m);
    bind_path_tracer(m);
}

}  // namespace shgi::python
