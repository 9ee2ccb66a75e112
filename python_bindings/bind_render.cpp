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
#include <memory>
#include <optional>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "numpy_convert.h"
#include "struct_fields.h"
#include "interruptible.h"
#include "scene_use.h"
#include "render/indirect_field.h"
#include "render/path_tracer.h"
#include "render/preview_renderer.h"
#include "util/error.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

// The passes named in `names` (a sequence of pass names; None: every pass the film sums).
std::vector<Pass> requested_passes(const Film& film, const py::object& names) {
    std::vector<Pass> passes;
    if (names.is_none()) {
        for (int p = 0; p < kPassCount; ++p)
            if (film.has_pass(Pass(p))) passes.push_back(Pass(p));
        return passes;
    }
    if (py::isinstance<py::str>(names))
        throw_value_error("names", "must be a sequence of pass names, e.g. ['Combined'], not "
                                   "a string");
    for (const py::handle item : py::iter(names)) {
        const std::string name = py::str(item);
        int found = -1;
        for (int p = 0; p < kPassCount && found < 0; ++p)
            if (name == pass_name(Pass(p))) found = p;
        if (found < 0) {
            std::string known;
            for (int p = 0; p < kPassCount; ++p)
                known += std::string(p ? ", " : "") + pass_name(Pass(p));
            throw_value_error("names", "'" + name + "' is not a pass; passes are " + known);
        }
        if (!film.has_pass(Pass(found)))
            throw_value_error("names", "'" + name + "' is not summed by this renderer, which "
                                       "keeps only Combined (PreviewSettings.combined_only)");
        passes.push_back(Pass(found));
    }
    return passes;
}

py::dict passes_to_dict(const Film& film, const py::object& names = py::none()) {
    py::dict out;
    for (const Pass pass : requested_passes(film, names)) {
        const std::vector<float> pixels = film.pixels(pass);
        const py::ssize_t channels = py::ssize_t(pass_suffixes(pass).size());
        py::array_t<float> array({py::ssize_t(film.height()), py::ssize_t(film.width()), channels});
        std::memcpy(array.mutable_data(), pixels.data(), pixels.size() * sizeof(float));
        out[pass_name(pass)] = std::move(array);
    }
    return out;
}

// Renderer.passes(names=None) of a PathTracer or PreviewRenderer (`type`), refused while a
// render of that renderer runs in another thread.
template <typename Renderer>
auto passes_method(const char* type) {
    return [type](const Renderer& renderer, const py::object& names) {
        const ObjectUse film = renderer_use(&renderer, type, "passes", false);
        return passes_to_dict(renderer.film(), names);
    };
}

// A render() call's sample count: any integer in [1, kMaxPathTracerSamples].
uint32_t checked_samples(const py::handle& samples) {
    return checked_integer<uint32_t>(samples, "samples", 1u, uint32_t(kMaxPathTracerSamples));
}

void bind_settings(py::module_& m) {
    named_values_only(py::enum_<WorldSampling>(m, "WorldSampling",
                                               "How next-event estimation samples the world.")
        .value("COSINE", WorldSampling::Cosine)
        .value("UNIFORM", WorldSampling::Uniform));
    named_values_only(py::enum_<RouletteSurvival>(m, "RouletteSurvival",
                                                  "Russian roulette's survival probability "
                                                  "for a path of throughput T (largest "
                                                  "component).")
        .value("SQRT_THROUGHPUT", RouletteSurvival::SqrtThroughput)
        .value("THROUGHPUT", RouletteSurvival::Throughput));
    named_values_only(py::enum_<PixelFilterType>(m, "PixelFilter",
                                                 "Film > Pixel Filter as Cycles' (its Type).")
        .value("BOX", PixelFilterType::Box)
        .value("GAUSSIAN", PixelFilterType::Gaussian)
        .value("BLACKMAN_HARRIS", PixelFilterType::BlackmanHarris));
    using S = PathTracerSettings;
    py::class_<S> cls(m, "PathTracerSettings",
                      "Settings of the reference path tracer; every field has a default.");
    def_integer(cls, "seed", &S::seed,
                "Random seed; the image is a pure function of it (default 0).");
    def_integer(cls, "samples", &S::samples,
                "Samples per pixel rendered by render_path_traced (default 64).", 1,
                uint32_t(kMaxPathTracerSamples));
    def_integer(cls, "max_bounces", &S::max_bounces, "Total bounce limit, Cycles' (12).");
    def_integer(cls, "diffuse_bounces", &S::diffuse_bounces, "Diffuse bounce limit (4).");
    def_integer(cls, "glossy_bounces", &S::glossy_bounces, "Glossy bounce limit (4).");
    def_integer(cls, "transmission_bounces", &S::transmission_bounces,
                "Transmission bounce limit (12).");
    def_integer(cls, "russian_roulette_depth", &S::russian_roulette_depth,
                "Surfaces before Russian roulette may end a path (3).");
    def_integer(cls, "light_splits", &S::light_splits,
                "Most emitters one next-event estimate samples: the light tree's splitting, "
                "one shadow ray each (4; 1 = one emitter per shadow ray).",
                1, kMaxLightSplits);
    def_integer(cls, "tile_size", &S::tile_size, "Tile side in pixels (16).");
    cls.def(py::init(&from_kwargs<S>),
            "PathTracerSettings(**fields), e.g. PathTracerSettings(samples=16, seed=3).")
        .def_readwrite("clamp_indirect", &S::clamp_indirect,
                       kClampIndirectDoc)
        .def_readwrite("filter_glossy", &S::filter_glossy, kFilterGlossyDoc)
        .def_readwrite("pixel_filter", &S::pixel_filter, kPixelFilterDoc)
        .def_readwrite("filter_width", &S::filter_width, kFilterWidthDoc)
        .def_readwrite("world_sampling", &S::world_sampling, "WorldSampling (COSINE).")
        .def_readwrite("roulette_survival", &S::roulette_survival,
                       "RouletteSurvival (SQRT_THROUGHPUT: min(1, sqrt(T)), Cycles'; THROUGHPUT: "
                       "min(1, T)).")
        .def("validate", &validate_path_tracer_settings,
             "Raises ValueError naming the first invalid field.");
}

// A preview renderer of the scene's camera, or of `camera` when given (validates the settings).
std::unique_ptr<PreviewRenderer> make_preview_renderer(const Scene& scene,
                                                       const PreviewSettings& settings,
                                                       const Camera* camera) {
    return std::make_unique<PreviewRenderer>(scene, camera != nullptr ? *camera : scene.camera(),
                                             settings);
}

void bind_path_tracer(py::module_& m) {
    py::class_<PathTracer>(m, "PathTracer", R"doc(
Progressive reference path tracer over a committed Scene with a camera.

render(samples) adds samples to the film; passes() returns every pass so far. The result
depends only on the seed and the total sample count, not on threads or how the samples
were split between render() calls.)doc")
        .def(py::init([](const Scene& scene, const PathTracerSettings& settings) {
                 // The tracer reads the scene (lights, camera, revision): not mid-commit.
                 SceneUse use(scene, SceneUse::Kind::Query, "PathTracer");
                 return std::make_unique<PathTracer>(scene, settings);
             }),
             py::arg("scene"), py::arg("settings") = PathTracerSettings{}, py::keep_alive<1, 2>(),
             "Checks the settings (ValueError) and prepares light sampling.")
        .def(
            "render",
            [](PathTracer& tracer, const py::object& samples, Progress* progress) {
                const uint32_t count =
                    samples.is_none() ? tracer.settings().samples
                                      : checked_samples(samples);
                const ObjectUse film = renderer_use(&tracer, "PathTracer", "render", true);
                SceneUse use(tracer.scene(), SceneUse::Kind::Query, "render (PathTracer)");
                run_interruptible(progress, [&](Progress* used) {
                    tracer.render(count, used);
                });
            },
            py::arg("samples") = py::none(), py::arg("progress") = py::none(),
            "Adds `samples` samples per pixel (default settings.samples) with the GIL released. "
            "Raises shgi.Cancelled when progress.cancel() is called; the film is then unchanged.")
        .def(
            "passes",
            passes_method<PathTracer>("PathTracer"),
            py::arg("names") = py::none(),
            "{pass name: float32 array (H, W, C)}: Combined (RGBA), DiffDir, ..., Normal (XYZ), "
            "Depth (1 channel), Denoising Albedo, Denoising Normal (the denoiser's guides, "
            "through specular surfaces as Cycles'), with Cycles' meaning; names, e.g. "
            "['Combined'], converts only those (a viewport needs Combined alone).")
        .def_property_readonly(
            "samples_done",
            [](const PathTracer& tracer) {
                const ObjectUse film = renderer_use(&tracer, "PathTracer", "samples_done", false);
                return tracer.samples_done();
            },
            "Samples per pixel accumulated so far.");

    m.def(
        "render_path_traced",
        [](const Scene& scene, const PathTracerSettings& settings, Progress* progress) {
            std::optional<PathTracer> tracer;
            {
                SceneUse use(scene, SceneUse::Kind::Query, "render (render_path_traced)");
                tracer.emplace(scene, settings);  // validates the settings
                run_interruptible(progress, [&](Progress* used) {
                    tracer->render(settings.samples, used);
                });
            }
            return passes_to_dict(tracer->film());
        },
        py::arg("scene"), py::arg("settings") = PathTracerSettings{},
        py::arg("progress") = py::none(),
        "Renders settings.samples samples per pixel of the scene's camera; returns "
        "{pass name: float32 array (H, W, C)}.");
}

// Field queries at scene points: within the coordinates a scene may hold (kMaxCoordinate; beyond
// them distances overflow float), with normals that have a direction. Errors name the argument,
// and the row of an array argument (`row` kNoRow for a single vector).
constexpr size_t kNoRow = ~size_t(0);

[[noreturn]] void throw_query_error(const char* name, size_t row, const vec3& v,
                                    const std::string& problem) {
    const std::string what =
        row == kNoRow ? std::string(name) : format_message(name, "[", row, "]");
    throw_value_error(what.c_str(),
                      format_message("(", v.x, ", ", v.y, ", ", v.z, ") ", problem));
}

void check_query_point(const vec3& p, const char* name, size_t row = kNoRow) {
    if (max_abs_component(p) > kMaxCoordinate)
        throw_query_error(name, row, p,
                          format_message("is beyond ", kMaxCoordinate, " m from the origin"));
}

vec3 query_normal(const vec3& n, const char* name, size_t row = kNoRow) {
    const vec3 unit = glm::normalize(n);
    if (!is_finite(unit))
        throw_query_error(name, row, n, "has no direction; pass a non-zero normal");
    return unit;
}

py::dict timings_to_dict(const PreviewTimings& timings) {
    py::dict out;
    out["primary"] = timings.primary;
    out["direct"] = timings.direct;
    out["indirect"] = timings.indirect;
    out["frame_stages"] = timings.frame_stages;
    out["total"] = timings.total;
    return out;
}

void bind_indirect_field(py::module_& m) {
    py::class_<IndirectField>(m, "IndirectField", R"doc(
Indirect incident light solved by a solver (PhotonLattice, ...), read by the renderers.

Units: radiance W m^-2 sr^-1, irradiance W m^-2; only indirect light (direct light is computed
exactly by the consumer). Queries take arrays of points and unit normals.)doc")
        .def(
            "irradiance",
            [](const IndirectField& field, const py::object& points, const py::object& normals) {
                const std::vector<vec3> p = to_vec3_array(points, "points");
                const std::vector<vec3> n = to_vec3_array(normals, "normals");
                if (p.size() != n.size())
                    throw_value_error("normals", format_message("has ", n.size(),
                                                                " rows but points has ", p.size()));
                std::vector<vec3> unit(n.size());
                for (size_t i = 0; i < p.size(); ++i) {
                    check_query_point(p[i], "points", i);
                    unit[i] = query_normal(n[i], "normals", i);
                }
                std::vector<vec3> out(p.size());
                {
                    const ObjectUse reads =
                        field_use(&field, ObjectUse::Kind::Read, "IndirectField.irradiance");
                    py::gil_scoped_release release;
                    const PinnedField pinned(&field);
                    for (size_t i = 0; i < p.size(); ++i)
                        out[i] = pinned.get()->irradiance(p[i], unit[i]);
                }
                return to_numpy(out);
            },
            py::arg("points"), py::arg("normals"),
            "(N, 3) irradiance in W/m^2 at points (N, 3) on surfaces with normals (N, 3).")
        .def(
            "radiance_sh",
            [](const IndirectField& field, const py::object& point, const py::object& normal) {
                const vec3 p = to_vec3(point, "point");
                check_query_point(p, "point");
                const ObjectUse reads =
                    field_use(&field, ObjectUse::Kind::Check, "IndirectField.radiance_sh");
                const ShRgb sh =
                    field.radiance_sh(p, query_normal(to_vec3(normal, "normal"), "normal"));
                py::array_t<float> out({py::ssize_t(sh.num_coefficients()), py::ssize_t(3)});
                std::memcpy(out.mutable_data(), sh.data(),
                            size_t(sh.num_coefficients()) * 3 * sizeof(float));
                return out;
            },
            py::arg("point"), py::arg("normal"),
            "Incident radiance SH at a point for a surface with that normal: float32 "
            "(coefficients, 3), index l(l+1)+m, coefficient-major RGB.");
}

void bind_preview(py::module_& m) {
    using S = PreviewSettings;
    py::class_<S> cls(m, "PreviewSettings",
                      "Settings of the preview renderer; every field has a default.");
    def_integer(cls, "seed", &S::seed, "Random seed (default 0).");
    def_integer(cls, "samples", &S::samples,
                "Samples per pixel rendered by render_preview (default 16).", 1,
                uint32_t(kMaxPathTracerSamples));
    def_integer(cls, "max_specular_bounces", &S::max_specular_bounces,
                "Mirror/glass bounces followed per path (8).");
    def_integer(cls, "tile_size", &S::tile_size,
                "Tile side in pixels (16), rounded up to an even number.");
    def_integer(cls, "light_splits", &S::light_splits,
                "Most emitters one next-event estimate samples, as "
                "PathTracerSettings.light_splits (4).",
                1, kMaxLightSplits);
    cls.def(py::init(&from_kwargs<S>),
            "PreviewSettings(**fields), e.g. PreviewSettings(samples=4, seed=1).")
        .def_readwrite("clamp_indirect", &S::clamp_indirect,
                       kClampIndirectDoc)
        .def_readwrite("filter_glossy", &S::filter_glossy, kFilterGlossyDoc)
        .def_readwrite("pixel_filter", &S::pixel_filter, kPixelFilterDoc)
        .def_readwrite("filter_width", &S::filter_width, kFilterWidthDoc)
        .def_readwrite("world_sampling", &S::world_sampling, "WorldSampling (COSINE).")
        .def_readwrite("combined_only", &S::combined_only,
                       "Sum only the Combined pass (False): what a viewport shows, without the "
                       "other 13 passes' film traffic.")
        .def_readwrite("reuse_field_lookups", &S::reuse_field_lookups,
                       "Share one field lookup among the pixels of a 2 x 2 quad whose first "
                       "surfaces lie within the field's reuse distance and whose normals agree "
                       "(True); False: one lookup per pixel.")
        .def_readwrite("final_gather", &S::final_gather,
                       "Final gather (False): the first surface sends one BSDF-sampled ray per "
                       "sample and the field is read where it lands after a diffuse bounce (a "
                       "glossy one goes on as a reference path), so the field's blocks and "
                       "leaks reach the picture only through one more bounce.")
        .def("validate", &validate_preview_settings,
             "Raises ValueError naming the first invalid field.");

    py::class_<PreviewRenderer>(m, "PreviewRenderer", R"doc(
Progressive preview frames: exact direct light, indirect light from an IndirectField.

render(field, samples) adds samples; passes() returns the passes (as the path tracer's);
timings is the last render's stage times in seconds (primary, direct, indirect, total).)doc")
        .def(py::init([](const Scene& scene, const PreviewSettings& settings,
                         const Camera* camera) {
                 SceneUse use(scene, SceneUse::Kind::Query, "PreviewRenderer");
                 return make_preview_renderer(scene, settings, camera);
             }),
             py::arg("scene"), py::arg("settings") = PreviewSettings{},
             py::arg("camera") = py::none(), py::keep_alive<1, 2>(),
             "camera: a shgi.Camera replacing the scene's (any view of a solved field).")
        .def(
            "render",
            [](PreviewRenderer& renderer, const IndirectField* field, const py::object& samples,
               Progress* progress) {
                const uint32_t count =
                    samples.is_none() ? 1u : checked_samples(samples);
                const ObjectUse film = renderer_use(&renderer, "PreviewRenderer", "render", true);
                const ObjectUse reads =
                    field_use(field, ObjectUse::Kind::Read, "PreviewRenderer.render");
                SceneUse use(renderer.scene(), SceneUse::Kind::Query, "render (PreviewRenderer)");
                run_interruptible(progress, [&](Progress* used) {
                    renderer.render(field, count, used);
                });
            },
            py::arg("field"), py::arg("samples") = py::none(), py::arg("progress") = py::none(),
            "Adds `samples` samples per pixel (default 1) lit indirectly by `field` (None: "
            "direct light only). The field must have been solved on the renderer's scene.")
        .def(
            "passes",
            passes_method<PreviewRenderer>("PreviewRenderer"),
            py::arg("names") = py::none(),
            "{pass name: float32 array (H, W, C)}, as PathTracer.passes(): every pass the "
            "renderer sums (only Combined with settings.combined_only), or those in `names`.")
        .def_property_readonly(
            "timings",
            [](const PreviewRenderer& r) {
                const ObjectUse film = renderer_use(&r, "PreviewRenderer", "timings", false);
                return timings_to_dict(r.timings());
            },
            "Seconds of the last render: primary, direct, indirect, total.");

    m.def(
        "render_preview",
        [](const Scene& scene, const IndirectField* field, const PreviewSettings& settings,
           const Camera* camera, Progress* progress) {
            std::unique_ptr<PreviewRenderer> renderer;
            {
                const ObjectUse reads = field_use(field, ObjectUse::Kind::Read, "render_preview");
                SceneUse use(scene, SceneUse::Kind::Query, "render (render_preview)");
                renderer = make_preview_renderer(scene, settings, camera);  // validates
                run_interruptible(progress, [&](Progress* used) {
                    renderer->render(field, settings.samples, used);
                });
            }
            py::dict passes = passes_to_dict(renderer->film());
            return py::make_tuple(passes, timings_to_dict(renderer->timings()));
        },
        py::arg("scene"), py::arg("field"), py::arg("settings") = PreviewSettings{},
        py::arg("camera") = py::none(), py::arg("progress") = py::none(),
        "Renders settings.samples samples per pixel with indirect light from `field` (None: "
        "direct only); returns (passes dict, timings dict in seconds).");
}

}  // namespace

void bind_render(py::module_& m) {
    bind_settings(m);
    bind_path_tracer(m);
    bind_indirect_field(m);
    bind_preview(m);
}

}  // namespace shgi::python
