// Bindings for native/bake: texel maps of lightmap UVs (bake/texel_rasterizer.h), unocclude,
// the lightmap baker (bake/lightmap_baker.h), its filter and dilation (bake/lightmap_filter.h).
// The orchestration (objects, files, shards) is Python: shgi.bake.
//
// Arrays: lightmaps are numpy arrays (height, width, ...) whose row 0 is v = 0, the bottom of
// the image, as Blender's Image.pixels stores it (files written by shgi.bake flip them to the
// top-row-first order of EXR and PNG).
//
// Settings are taken by value: the functions read them with the GIL released, when a progress
// callback or another thread may be editing the Python object (past the checks made at the start).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>

#include "bake/lightmap_baker.h"
#include "bake/lightmap_filter.h"
#include "render/light_tree.h"
#include "bake/texel_rasterizer.h"
#include "bake/unocclude.h"
#include "numpy_convert.h"
#include "interruptible.h"
#include "scene_use.h"
#include "struct_fields.h"
#include "util/error.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

template <typename T, typename Stored>
py::array_t<T> grid_array(const std::vector<Stored>& values, uint32_t width, uint32_t height,
                          std::vector<py::ssize_t> inner = {}) {
    std::vector<py::ssize_t> shape = {py::ssize_t(height), py::ssize_t(width)};
    shape.insert(shape.end(), inner.begin(), inner.end());
    py::array_t<T> out(shape);
    T* dst = out.mutable_data();
    for (size_t i = 0; i < values.size(); ++i) dst[i] = T(values[i]);
    return out;
}

// Copies a numpy array of exactly `count` values (any float dtype) into `out`.
template <typename T>
void copy_in(const py::handle& obj, const char* name, size_t count, std::vector<T>& out) {
    const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
    if (!array || size_t(array.size()) != count)
        throw_value_error(name, "must hold " + std::to_string(count) + " values, got " +
                                    (array ? describe_array(array) : std::string("not an array")));
    out.resize(count);
    const double* src = array.data();
    for (size_t i = 0; i < count; ++i) out[i] = T(src[i]);
}

py::array_t<float> texel_geometry_array(const TexelMap& map, bool normals) {
    const std::vector<TexelGeometry> geometry = texel_geometry(map);
    py::array_t<float> out({py::ssize_t(map.height), py::ssize_t(map.width), py::ssize_t(3)});
    float* dst = out.mutable_data();
    for (const TexelGeometry& g : geometry) {
        const vec3& v = normals ? g.normal : g.position;
        *dst++ = v.x;
        *dst++ = v.y;
        *dst++ = v.z;
    }
    return out;
}

py::dict raster_report(const TexelRasterReport& r) {
    py::dict d;
    d["triangles"] = r.triangles;
    d["degenerate_uv"] = r.degenerate_uv;
    d["degenerate_world"] = r.degenerate_world;
    d["clipped_triangles"] = r.clipped_triangles;
    d["conservative_samples"] = r.conservative_samples;
    d["overlapping_texels"] = r.overlapping_texels;
    return d;
}

void bind_texel_map(py::module_& m) {
    using S = TexelRasterSettings;
    py::class_<S> raster_cls(m, "TexelRasterSettings",
                           "Where lightmap texels lie: resolution, UV map and samples per texel.");
    def_integer(raster_cls, "width", &S::width, "Texels along u (256).");
    def_integer(raster_cls, "height", &S::height, "Texels along v (256).");
    def_integer(raster_cls, "samples_per_axis", &S::samples_per_axis,
                "Sample positions per texel side, 1..16 (2: 4 per texel).");
    raster_cls.def(py::init(&from_kwargs<S>), "TexelRasterSettings(**fields)")
        .def_readwrite("uv_set", &S::uv_set, "The lightmap UV map's name ('LightmapUV').");

    py::class_<TexelMap>(m, "TexelMap", R"doc(
The sample positions of every texel of one object's lightmap (rasterize_texels). Arrays are
(height, width) with row 0 at v = 0.)doc")
        .def_readonly("width", &TexelMap::width)
        .def_readonly("height", &TexelMap::height)
        .def_readonly("instance_id", &TexelMap::instance_id)
        .def_readonly("chart_count", &TexelMap::chart_count, "UV charts (islands) of the mesh.")
        .def_property_readonly(
            "coverage",
            [](const TexelMap& map) { return grid_array<float>(map.coverage, map.width, map.height); },
            "(H, W) float32 fraction of each texel the UV layout covers.")
        .def_property_readonly(
            "chart",
            [](const TexelMap& map) {
                std::vector<int32_t> chart(map.chart.size());
                for (size_t i = 0; i < chart.size(); ++i)
                    chart[i] = map.chart[i] == kInvalidId ? -1 : int32_t(map.chart[i]);
                return grid_array<int32_t>(chart, map.width, map.height);
            },
            "(H, W) int32 UV chart of each texel, -1 where nothing is covered.")
        .def_property_readonly(
            "normals",
            [](const TexelMap& map) { return texel_geometry_array(map, true); },
            "(H, W, 3) float32 mean shading normal of each texel (+Z where nothing is covered): "
            "a denoiser's normal guide.")
        .def_property_readonly(
            "positions",
            [](const TexelMap& map) { return texel_geometry_array(map, false); },
            "(H, W, 3) float32 mean world position (m) of each texel (0 where nothing is "
            "covered).")
        .def_property_readonly("sample_count",
                               [](const TexelMap& map) { return map.samples.size(); })
        .def_property_readonly("report",
                               [](const TexelMap& map) { return raster_report(map.report); },
                               "What rasterizing skipped or clipped (dict of counts).");

    m.def(
        "rasterize_texels",
        [](const Scene& scene, const IndexInt& instance, const S settings, Progress* progress) {
            const uint32_t id = int_arg<uint32_t>(instance, "instance");
            SceneUse use(scene, SceneUse::Kind::Query, "rasterize_texels");
            return run_interruptible(progress, [&](Progress* used) {
                return rasterize_texels(scene, id, settings, used);
            });
        },
        py::arg("scene"), py::arg("instance"), py::arg("settings") = S{},
        py::arg("progress") = py::none(),
        "Rasterizes instance `instance`'s lightmap UV map; ValueError naming the object when the "
        "UV map is missing (listing the ones it has) or the mesh is bad.");

    using U = UnoccludeSettings;
    py::class_<U> unocclude_settings(m, "UnoccludeSettings",
                                     "Moving texel samples out of walls (Godot's unocclude).");
    def_integer(unocclude_settings, "ray_count", &U::ray_count,
                "Tangent-plane rays per sample (8).");
    unocclude_settings.def(py::init(&from_kwargs<U>), "UnoccludeSettings(**fields)")
        .def_readwrite("search_radius", &U::search_radius,
                       "Texels searched for walls, (0, 16] (1).")
        .def_readwrite("push_distance", &U::push_distance,
                       "Texels past the wall, [0, 16] (0.05).");
    m.def(
        "unocclude",
        [](const Scene& scene, TexelMap& map, const U settings, Progress* progress,
           const std::vector<IndexInt>& tile_args, const IndexInt& tile_size_arg) {
            std::vector<uint32_t> tiles(tile_args.size());
            for (size_t i = 0; i < tiles.size(); ++i)
                tiles[i] = int_arg<uint32_t>(tile_args[i],
                                             ("tiles[" + std::to_string(i) + "]").c_str());
            const uint32_t tile_size = int_arg<uint32_t>(tile_size_arg, "tile_size");
            SceneUse use(scene, SceneUse::Kind::Query, "unocclude");
            UnoccludeReport report;
            report = run_interruptible(progress, [&](Progress* used) {
                    return unocclude(scene, map, settings, tiles, tile_size, used);
                });
            py::dict d;
            d["samples"] = report.samples;
            d["moved_samples"] = report.moved_samples;
            return d;
        },
        py::arg("scene"), py::arg("map"), py::arg("settings") = U{},
        py::arg("progress") = py::none(), py::arg("tiles") = std::vector<IndexInt>{},
        py::arg("tile_size") = IndexInt{py::int_(LightmapSettings{}.tile_size)},
        "Moves the ray origins of samples inside other geometry out of it; returns counts. "
        "`tiles` (lightmap tiles of `tile_size` texels, as bake_lightmap numbers them; empty: "
        "all): only their texels' samples, each moved exactly as by a whole unocclude (what a "
        "shard bakes).");
}

void bind_lightmap(py::module_& m) {
    using S = LightmapSettings;
    py::class_<S> settings_cls(m, "LightmapSettings", R"doc(
What and how a lightmap is baked; every field has a default. Content (Cycles' DIFFUSE bake):
'DIRECT_INDIRECT' (pass_filter {DIRECT, INDIRECT}), 'DIRECT', 'INDIRECT', or 'FULL' (also COLOR).)doc");
    def_integer(settings_cls, "seed", &S::seed, "Random seed (0).");
    def_integer(settings_cls, "samples", &S::samples, "Samples per texel (256).");
    def_integer(settings_cls, "sh_order", &S::sh_order,
                "SH order of the directional data: 1 (L1, 4 coefficients per channel) or 2 "
                "(L2, 9) (1).");
    def_integer(settings_cls, "tile_size", &S::tile_size,
                "Texels per tile side: the unit of work and of shards (16).");
    def_integer(settings_cls, "max_bounces", &S::max_bounces, "Cycles' Total bounces (12).");
    def_integer(settings_cls, "diffuse_bounces", &S::diffuse_bounces,
                "Cycles' Diffuse bounces (4).");
    def_integer(settings_cls, "glossy_bounces", &S::glossy_bounces, "Cycles' Glossy bounces (4).");
    def_integer(settings_cls, "transmission_bounces", &S::transmission_bounces,
                "Cycles' Transmission bounces (12).");
    def_integer(settings_cls, "light_splits", &S::light_splits,
                "Most emitters one next-event estimate samples, as "
                "PathTracerSettings.light_splits (4).",
                1, kMaxLightSplits);
    settings_cls.def(py::init(&from_kwargs<S>), "LightmapSettings(**fields)")
        .def_property(
            "content", [](const S& s) { return std::string(lightmap_content_name(s.content)); },
            [](S& s, const std::string& name) { s.content = lightmap_content_from_name(name); },
            "'DIRECT_INDIRECT' (default), 'DIRECT', 'INDIRECT' or 'FULL'.")
        .def_readwrite("directional", &S::directional,
                       "Also bake the SH of the incident radiance, of order sh_order (False).")
        .def_readwrite("clamp_indirect", &S::clamp_indirect,
                       kClampIndirectDoc)
        .def_readwrite("filter_glossy", &S::filter_glossy, kFilterGlossyDoc)
        .def_readwrite("final_gather", &S::final_gather,
                       "With a field: each sample traces one ray that reads the field where it "
                       "lands, with direct light there, instead of reading it at the texel: "
                       "the field's blocks and leaks are one bounce further away (False).")
        .def("validate", &validate_lightmap_settings,
             "Raises ValueError naming the first invalid field.");

    py::class_<LightmapTexels>(m, "LightmapTexels", R"doc(
A baked lightmap: arrays (height, width, ...) with row 0 at v = 0 (Blender's Image.pixels order).
LightmapTexels(color, variance, baked, sh=None) rebuilds one from its arrays (a shard file); sh
(height, width, 4, 3) is L1, (height, width, 9, 3) L2.)doc")
        .def(py::init([](const py::array& color, const py::array& variance, const py::array& baked,
                         const py::object& sh) {
                 if (color.ndim() != 3 || color.shape(2) != 3)
                     throw_value_error("color", "must be (height, width, 3), got " +
                                                    describe_array(color));
                 auto texels = std::make_unique<LightmapTexels>();
                 texels->height = uint32_t(color.shape(0));
                 texels->width = uint32_t(color.shape(1));
                 const size_t n = texels->texel_count();
                 copy_in(color, "color", 3 * n, texels->color);
                 copy_in(variance, "variance", n, texels->variance);
                 copy_in(baked, "baked", n, texels->baked);
                 texels->directional = !sh.is_none();
                 if (texels->directional) {
                     const auto array = py::array::ensure(sh);
                     const size_t size = array ? size_t(array.size()) : 0;
                     // L2 when it holds 9 coefficients per channel; otherwise L1 (copy_in names
                     // the mismatch).
                     texels->sh_order = n > 0 && size == size_t(kLightmapMaxShFloats) * n ? 2 : 1;
                     copy_in(sh, "sh", size_t(texels->sh_floats()) * n, texels->sh);
                 }
                 return texels;
             }),
             py::arg("color"), py::arg("variance"), py::arg("baked"), py::arg("sh") = py::none())
        .def_readonly("width", &LightmapTexels::width)
        .def_readonly("height", &LightmapTexels::height)
        .def_readonly("directional", &LightmapTexels::directional)
        .def_property_readonly(
            "sh_order",
            [](const LightmapTexels& t) -> py::object {
                if (!t.directional) return py::none();
                return py::int_(t.sh_order);
            },
            "SH order of the directional data (1: L1, 2: L2), or None without it.")
        .def_property_readonly(
            "color",
            [](const LightmapTexels& t) { return grid_array<float>(t.color, t.width, t.height, {3}); },
            "(H, W, 3) float32 light per texel (units: LightmapSettings.content).")
        .def_property_readonly(
            "sh",
            [](const LightmapTexels& t) -> py::object {
                if (!t.directional) return py::none();
                return grid_array<float>(t.sh, t.width, t.height,
                                         {py::ssize_t(t.sh_coefficients()), 3});
            },
            "(H, W, 4, 3) float32 L1 SH of incident radiance (index l(l+1)+m) — (H, W, 9, 3) "
            "at L2 — or None.")
        .def_property_readonly(
            "variance",
            [](const LightmapTexels& t) { return grid_array<float>(t.variance, t.width, t.height); },
            "(H, W) float32 variance of each texel's luminance (confidence).")
        .def_property_readonly(
            "baked",
            [](const LightmapTexels& t) { return grid_array<bool>(t.baked, t.width, t.height); },
            "(H, W) bool: texels this bake computed.");

    m.def(
        "lightmap_tile_count",
        [](const IndexInt& width, const IndexInt& height, const IndexInt& tile_size) {
            return lightmap_tile_count(int_arg<uint32_t>(width, "width"),
                                       int_arg<uint32_t>(height, "height"),
                                       int_arg<uint32_t>(tile_size, "tile_size"));
        },
        py::arg("width"), py::arg("height"), py::arg("tile_size"));
    m.def(
        "lightmap_shard_tiles",
        [](const IndexInt& width, const IndexInt& height, const IndexInt& tile_size,
           const IndexInt& shard, const IndexInt& shards) {
            return lightmap_shard_tiles(
                int_arg<uint32_t>(width, "width"), int_arg<uint32_t>(height, "height"),
                int_arg<uint32_t>(tile_size, "tile_size"), int_arg<uint32_t>(shard, "shard"),
                int_arg<uint32_t>(shards, "shards"));
        },
        py::arg("width"), py::arg("height"), py::arg("tile_size"), py::arg("shard"),
        py::arg("shards"), "Tiles shard i of N bakes: every tile t with t % N == i.");
    m.def(
        "lightmap_read_tiles",
        [](const IndexInt& width, const IndexInt& height, const IndexInt& tile_size,
           const std::vector<IndexInt>& tile_args, const IndirectField* field) {
            std::vector<uint32_t> tiles(tile_args.size());
            for (size_t i = 0; i < tiles.size(); ++i)
                tiles[i] = int_arg<uint32_t>(tile_args[i],
                                             ("tiles[" + std::to_string(i) + "]").c_str());
            const ObjectUse reads = field_use(field, ObjectUse::Kind::Read, "lightmap_read_tiles");
            return lightmap_read_tiles(int_arg<uint32_t>(width, "width"),
                                       int_arg<uint32_t>(height, "height"),
                                       int_arg<uint32_t>(tile_size, "tile_size"), tiles, field);
        },
        py::arg("width"), py::arg("height"), py::arg("tile_size"), py::arg("tiles"),
        py::arg("field") = py::none(),
        "The tiles whose texels a bake of `tiles` with `field` reads (an interleaved field's "
        "filter reaches into neighbouring tiles): a shard unoccludes these. Empty for all.");
    m.def(
        "bake_lightmap",
        [](const Scene& scene, const TexelMap& map, const S settings, const IndirectField* field,
           const std::vector<IndexInt>& tile_args, Progress* progress) {
            std::vector<uint32_t> tiles(tile_args.size());
            for (size_t i = 0; i < tiles.size(); ++i)
                tiles[i] = int_arg<uint32_t>(tile_args[i],
                                             ("tiles[" + std::to_string(i) + "]").c_str());
            const ObjectUse reads = field_use(field, ObjectUse::Kind::Read, "bake_lightmap");
            SceneUse use(scene, SceneUse::Kind::Query, "bake_lightmap");
            return run_interruptible(progress, [&](Progress* used) {
                return bake_lightmap(scene, map, field, settings, tiles, used);
            });
        },
        py::arg("scene"), py::arg("map"), py::arg("settings") = S{},
        py::arg("field") = py::none(), py::arg("tiles") = std::vector<IndexInt>{},
        py::arg("progress") = py::none(),
        "Bakes `tiles` (all when empty) of the texel map: with the path tracer when `field` is "
        "None, else with the field's indirect light.");
    m.def("merge_lightmap", &merge_lightmap, py::arg("into"), py::arg("part"),
          "Copies the texels `part` baked into `into` (ValueError when shards overlap).");

    using F = LightmapFilterSettings;
    py::class_<F> filter(m, "LightmapFilterSettings",
                         "Edge-aware a-trous filter that never crosses UV charts.");
    def_integer(filter, "iterations", &F::iterations, "A-trous passes, 0 = off (2).");
    filter.def(py::init(&from_kwargs<F>), "LightmapFilterSettings(**fields)")
        .def_readwrite("normal_power", &F::normal_power, "Normal weight sharpness (64).")
        .def_readwrite("position_sigma", &F::position_sigma,
                       "Texels off the texel's plane before weight 1/e (1).")
        .def_readwrite("luminance_sigma", &F::luminance_sigma,
                       "Standard deviations of luminance before weight 1/e (4).");
    m.def(
        "filter_lightmap",
        [](const TexelMap& map, LightmapTexels& texels, const F settings, Progress* progress) {
            run_interruptible(progress, [&](Progress* used) {
                filter_lightmap(map, texels, settings, used);
            });
        },
        py::arg("map"), py::arg("texels"), py::arg("settings") = F{},
        py::arg("progress") = py::none(), "Filters the baked texels in place.");
    m.def(
        "dilate_lightmap",
        [](LightmapTexels& texels, const IndexInt& padding, Progress* progress) {
            std::vector<uint8_t> filled;
            DilationSettings dilation;
            dilation.padding = int_arg<uint32_t>(padding, "padding");
            filled = run_interruptible(progress, [&](Progress* used) {
                    return dilate_lightmap(texels, dilation, used);
                });
            return grid_array<bool>(filled, texels.width, texels.height);
        },
        py::arg("texels"), py::arg("padding") = 4, py::arg("progress") = py::none(),
        "Spreads every layer `padding` texels beyond the charts in place; returns the (H, W) "
        "bool mask of texels holding a value.");
}

}  // namespace

void bind_bake(py::module_& m) {
    // The largest lightmap side the bake accepts: the add-on's Resolution property ends here.
    m.attr("MAX_LIGHTMAP_RESOLUTION") = kMaxLightmapResolution;
    bind_texel_map(m);
    bind_lightmap(m);
}

}  // namespace shgi::python
