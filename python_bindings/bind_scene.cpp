// Bindings for native/scene: Mesh, Material, Texture, Light, World, Camera, Instance and Scene,
// with the C++ names and fields (STYLE.md habit 8).
//
// numpy in and out with explicit shapes and dtypes (numpy_convert.h): positions (N, 3) float,
// triangles (T, 3) int, uv sets (N, 2) float, 4x4 matrices row-major as Blender's matrix_world.
// Argument checks and conversions run with the GIL held; Scene.commit and the batch queries
// release it for the native work, so other Python threads (Blender's UI) keep running.
//
// A Scene must not be edited while another thread commits or queries it: edits made then raise
// RuntimeError instead of racing with the native work (the scene-use table below).
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <unordered_map>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "numpy_convert.h"
#include "struct_fields.h"
#include "interruptible.h"
#include "scene_use.h"
#include "scene/scene.h"
#include "util/parallel.h"
#include "util/progress.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

// --- conversions -------------------------------------------------------------------------------

py::array_t<float> to_numpy_1d(const std::vector<float>& values) {
    py::array_t<float> out(static_cast<py::ssize_t>(values.size()));
    std::copy(values.begin(), values.end(), out.mutable_data());
    return out;
}

py::array_t<uint32_t> to_numpy_1d(const std::vector<uint32_t>& values) {
    py::array_t<uint32_t> out(static_cast<py::ssize_t>(values.size()));
    std::copy(values.begin(), values.end(), out.mutable_data());
    return out;
}

// A mat4 field exposed as a (4, 4) float32 array, row-major like Blender's Matrix.
template <typename T>
void def_mat4(py::class_<T>& cls, const char* name, mat4 T::*field, const char* doc) {
    cls.def_property(
        name, [field](const T& self) { return from_mat4(self.*field); },
        [field, name](T& self, const py::object& value) { self.*field = to_mat4(value, name); },
        doc);
}

// --- meshes ------------------------------------------------------------------------------------

std::vector<UvSet> to_uv_sets(const py::object& uvs) {
    std::vector<UvSet> sets;
    if (uvs.is_none()) return sets;
    if (py::isinstance<py::dict>(uvs)) {
        for (const auto& item : uvs.cast<py::dict>()) {
            const std::string name = py::str(item.first);
            const std::string arg = "uvs['" + name + "']";
            sets.push_back(UvSet{name, to_vec2_array(item.second, arg.c_str())});
        }
        return sets;
    }
    sets.push_back(UvSet{"UVMap", to_vec2_array(uvs, "uvs")});  // Blender's default UV map name
    return sets;
}

py::dict uv_sets_to_dict(const std::vector<UvSet>& sets) {
    py::dict out;
    for (const UvSet& set : sets) out[py::str(set.name)] = to_numpy(set.coords);
    return out;
}

Mesh mesh_from_arrays(const py::object& positions, const py::object& triangles,
                      const py::object& normals, const py::object& uvs,
                      const py::object& material_indices, const std::string& name,
                      const py::object& tangents) {
    Mesh mesh;
    mesh.name = name;
    mesh.positions = to_vec3_array(positions, "positions");
    mesh.triangles = to_uvec3_array(triangles, "triangles");
    if (!normals.is_none()) mesh.normals = to_vec3_array(normals, "normals");
    if (!tangents.is_none()) mesh.tangents = to_vec4_array(tangents, "tangents", true);
    mesh.uv_sets = to_uv_sets(uvs);
    if (!material_indices.is_none())
        mesh.material_indices = to_uint_array(material_indices, "material_indices");
    return mesh;
}

constexpr const char* kMeshArgsDoc =
    "positions: (N, 3) float, object space (m); triangles: (T, 3) int vertex indices, "
    "counter-clockwise = front; normals: (N, 3) float or None; uvs: (N, 2) float (UV map "
    "'UVMap'), a dict {name: (N, 2)} or None; material_indices: (T,) int or None (all 0); "
    "tangents: (N, 4) float (object-space MikkTSpace tangent of the normal map's UV map, then "
    "the bitangent sign +-1) or None; NaN or zero tangents are dropped with a warning (no "
    "normal map there).";

void bind_mesh(py::module_& m) {
    py::class_<Mesh> cls(m, "Mesh", "A triangle mesh in object space (see scene/mesh.h).");
    cls.def(py::init(&mesh_from_arrays), py::arg("positions"), py::arg("triangles"),
            py::arg("normals") = py::none(), py::arg("uvs") = py::none(),
            py::arg("material_indices") = py::none(), py::arg("name") = "",
            py::arg("tangents") = py::none(),
            (std::string("Builds a mesh from numpy arrays. ") + kMeshArgsDoc).c_str())
        .def_readwrite("name", &Mesh::name, "The mesh's name (Blender's mesh data name).")
        .def_property(
            "positions", [](const Mesh& mesh) { return to_numpy(mesh.positions); },
            [](Mesh& mesh, const py::object& v) { mesh.positions = to_vec3_array(v, "positions"); },
            "(N, 3) float32 vertex positions, object space (m).")
        .def_property(
            "triangles", [](const Mesh& mesh) { return to_numpy(mesh.triangles); },
            [](Mesh& mesh, const py::object& v) {
                mesh.triangles = to_uvec3_array(v, "triangles");
            },
            "(T, 3) uint32 vertex indices per triangle.")
        .def_property(
            "normals", [](const Mesh& mesh) { return to_numpy(mesh.normals); },
            [](Mesh& mesh, const py::object& v) {
                mesh.normals = v.is_none() ? std::vector<vec3>{} : to_vec3_array(v, "normals");
            },
            "(N, 3) float32 vertex normals, or (0, 3) when the mesh has none.")
        .def_property(
            "tangents", [](const Mesh& mesh) { return to_numpy(mesh.tangents); },
            [](Mesh& mesh, const py::object& v) {
                mesh.tangents =
                    v.is_none() ? std::vector<vec4>{} : to_vec4_array(v, "tangents", true);
            },
            "(N, 4) float32 vertex tangents (xyz object space, w bitangent sign), or (0, 4).")
        .def_property(
            "uv_sets", [](const Mesh& mesh) { return uv_sets_to_dict(mesh.uv_sets); },
            [](Mesh& mesh, const py::object& v) { mesh.uv_sets = to_uv_sets(v); },
            "Dict {uv map name: (N, 2) float32}, in order (the first is used for textures).")
        .def_property(
            "material_indices",
            [](const Mesh& mesh) { return to_numpy_1d(mesh.material_indices); },
            [](Mesh& mesh, const py::object& v) {
                mesh.material_indices = v.is_none() ? std::vector<uint32_t>{}
                                                    : to_uint_array(v, "material_indices");
            },
            "(T,) uint32 material index per triangle, or empty (all use material 0).")
        .def(
            "__repr__",
            [](const Mesh& mesh) {
                return "<shgi.Mesh '" + mesh.name + "': " +
                       std::to_string(mesh.positions.size()) + " vertices, " +
                       std::to_string(mesh.triangles.size()) + " triangles>";
            },
            "Name and sizes.");
}

// --- materials and textures --------------------------------------------------------------------

void bind_material(py::module_& m) {
    named_values_only(py::enum_<DiffuseModel>(m, "DiffuseModel", "The diffuse lobe of a Material.")
        .value("PRINCIPLED", DiffuseModel::Principled,
               "Principled BSDF's diffuse (Burley, with retro-reflection at high roughness)")
        .value("LAMBERT", DiffuseModel::Lambert, "Lambert, as Blender's Diffuse BSDF"));
    named_values_only(py::enum_<PrincipledModel>(m, "PrincipledModel",
                               "How a Material's closures combine, as each Blender's Cycles.")
        .value("V1", PrincipledModel::V1, "Blender 3.x: diffuse and specular added")
        .value("V2", PrincipledModel::V2,
               "Blender 4.0+: the specular layer dims the diffuse by its albedo; Glossy Color "
               "holds that albedo"));
    named_values_only(py::enum_<MicrofacetDistribution>(m, "MicrofacetDistribution",
                                      "The microfacet distribution of a Material's specular.")
        .value("GGX", MicrofacetDistribution::GGX, "GGX, single scattering")
        .value("MULTISCATTER_GGX", MicrofacetDistribution::MultiscatterGGX,
               "Cycles 4's energy-preserving GGX (with principled_model V2)"));
    py::class_<Material> cls(m, "Material",
                             "Principled BSDF subset (Blender 3.4 semantics, or 4.x's with "
                             "principled_model V2), linear Rec.709.");
    named_values_only(py::enum_<NormalMapSpace>(m, "NormalMapSpace",
                                                "The space of a Material's normal map texels.")
        .value("TANGENT", NormalMapSpace::Tangent,
               "along the mesh's tangents (Mesh.tangents; glTF's normalTexture)")
        .value("OBJECT", NormalMapSpace::Object, "object space")
        .value("WORLD", NormalMapSpace::World, "world space")
        .value("BLENDER_OBJECT", NormalMapSpace::BlenderObject,
               "Blender's object space (Y and Z negated)")
        .value("BLENDER_WORLD", NormalMapSpace::BlenderWorld,
               "Blender's world space (Y and Z negated)"));
    def_integer(cls, "base_color_texture", &Material::base_color_texture,
                "Index into the scene's textures, or -1 for none.");
    def_integer(cls, "normal_texture", &Material::normal_texture,
                "Normal map: index into the scene's textures (non-colour data), or -1 for none.");
    def_integer(cls, "bump_texture", &Material::bump_texture,
                "Bump node's Height: index into the scene's textures (its luminance is the "
                "height), or -1 for none.");
    cls.def(py::init(&from_kwargs<Material>),
            "Material(**fields): a default material with the given fields set, e.g. "
            "Material(name='Red', base_color=(0.8, 0.1, 0.1), roughness=0.3).")
        .def_readwrite("name", &Material::name, "Blender's material name.")
        .def_readwrite("base_color_uv_set", &Material::base_color_uv_set,
                       "UV map used by the texture ('' = the first).")
        .def_readwrite("normal_uv_set", &Material::normal_uv_set,
                       "UV map used by the normal map ('' = the first).")
        .def_readwrite("normal_strength", &Material::normal_strength,
                       "Normal Map Strength, 0..100 (0: the interpolated normal, 1: the map's).")
        .def_readwrite("normal_space", &Material::normal_space,
                       "NormalMapSpace of the normal map (TANGENT).")
        .def_readwrite("bump_uv_set", &Material::bump_uv_set,
                       "UV map used by the bump map ('' = the first).")
        .def_readwrite("bump_strength", &Material::bump_strength,
                       "Bump Strength, 0..1 (0: the unbumped normal).")
        .def_readwrite("bump_distance", &Material::bump_distance,
                       "Bump Distance in scene units, -1000..1000 (negative: Invert).")
        .def_readwrite("roughness", &Material::roughness, "0..1 (GGX alpha = roughness^2).")
        .def_readwrite("metallic", &Material::metallic, "0..1.")
        .def_readwrite("specular", &Material::specular, "0..1 (F0 = 0.08 * specular).")
        .def_readwrite("transmission", &Material::transmission, "0..1.")
        .def_readwrite("ior", &Material::ior, "Index of refraction, >= 1.")
        .def_readwrite("emission_strength", &Material::emission_strength, ">= 0.")
        .def_readwrite("diffuse_model", &Material::diffuse_model,
                       "DiffuseModel (PRINCIPLED; the exporter sets LAMBERT for a Diffuse BSDF).")
        .def_readwrite("principled_model", &Material::principled_model,
                       "PrincipledModel (V1; the exporter sets V2 from Blender 4.0).")
        .def_readwrite("distribution", &Material::distribution,
                       "MicrofacetDistribution (GGX; Blender 4's default is MULTISCATTER_GGX).")
        .def("is_emissive", &Material::is_emissive, "True if the material emits light.");
    def_vec3(cls, "base_color", &Material::base_color, "Linear RGB albedo.");
    def_vec3(cls, "emission_color", &Material::emission_color,
             "Linear RGB; emitted radiance = emission_color * emission_strength (W m^-2 sr^-1).");

    py::class_<Texture>(m, "Texture", "A linear RGBA image; row 0 is the bottom row (Blender).")
        .def(py::init([](const py::object& pixels, const std::string& name) {
                 py::array array = py::array::ensure(pixels);
                 if (!array || array.ndim() != 3 || (array.shape(2) != 3 && array.shape(2) != 4))
                     throw_value_error("pixels", "expected shape (H, W, 4) or (H, W, 3)");
                 const auto height = static_cast<uint32_t>(array.shape(0));
                 const auto width = static_cast<uint32_t>(array.shape(1));
                 const int channels = static_cast<int>(array.shape(2));
                 const std::vector<float> rows = to_float_rows(
                     array.reshape({static_cast<py::ssize_t>(width) * height,
                                    static_cast<py::ssize_t>(channels)}),
                     "pixels", channels);
                 Texture texture;
                 texture.name = name;
                 texture.width = width;
                 texture.height = height;
                 texture.texels.resize(rows.size() / channels);
                 for (size_t i = 0; i < texture.texels.size(); ++i) {
                     const float* p = &rows[i * channels];
                     texture.texels[i] = vec4(p[0], p[1], p[2], channels == 4 ? p[3] : 1.0f);
                 }
                 return texture;
             }),
             py::arg("pixels"), py::arg("name") = "",
             "Builds a texture from an (H, W, 4) or (H, W, 3) float array of linear values, "
             "row 0 at the bottom as in Blender's Image.pixels (alpha 1 when absent).")
        .def_readwrite("name", &Texture::name, "The image name.")
        .def_readonly("width", &Texture::width, "Width in pixels.")
        .def_readonly("height", &Texture::height, "Height in pixels.")
        .def_property_readonly(
            "pixels",
            [](const Texture& texture) {
                py::array_t<float> out({static_cast<py::ssize_t>(texture.height),
                                        static_cast<py::ssize_t>(texture.width),
                                        static_cast<py::ssize_t>(4)});
                float* data = out.mutable_data();
                for (size_t i = 0; i < texture.texels.size(); ++i)
                    for (int c = 0; c < 4; ++c) data[4 * i + c] = texture.texels[i][c];
                return out;
            },
            "(H, W, 4) float32 copy of the texels.");
}

// --- lights, world, camera ---------------------------------------------------------------------

void bind_light(py::module_& m) {
    named_values_only(py::enum_<LightType>(m, "LightType", "Blender's light types.")
        .value("POINT", LightType::Point)
        .value("SPOT", LightType::Spot)
        .value("SUN", LightType::Sun)
        .value("AREA", LightType::Area));
    named_values_only(py::enum_<AreaShape>(m, "AreaShape", "Blender's area light shapes.")
        .value("SQUARE", AreaShape::Square)
        .value("RECTANGLE", AreaShape::Rectangle)
        .value("DISK", AreaShape::Disk)
        .value("ELLIPSE", AreaShape::Ellipse));
    py::class_<Light> cls(m, "Light", "A Blender light with Cycles' units (see scene/light.h).");
    cls.def(py::init(&from_kwargs<Light>),
            "Light(**fields): a default point light with the given fields set.")
        .def_readwrite("name", &Light::name, "Blender's light object name.")
        .def_readwrite("type", &Light::type, "LightType.")
        .def_readwrite("power", &Light::power, "W (point, spot, area).")
        .def_readwrite("strength", &Light::strength, "W/m^2 (sun).")
        .def_readwrite("radius", &Light::radius, "m: point/spot radius (0 = a true point).")
        .def_readwrite("spot_size", &Light::spot_size, "rad: full cone angle, (0, pi].")
        .def_readwrite("spot_blend", &Light::spot_blend, "[0, 1].")
        .def_readwrite("spot_cone_cosine", &Light::spot_cone_cosine,
                       "True (Blender 3.x): the spot's falloff includes cos(angle to its axis); "
                       "the exporter sets False from Blender 4.0, whose Cycles drops it.")
        .def_readwrite("angle", &Light::angle, "rad: sun's angular diameter, [0, pi).")
        .def_readwrite("shape", &Light::shape, "AreaShape.")
        .def_readwrite("size_x", &Light::size_x, "m: area light size along local X.")
        .def_readwrite("size_y", &Light::size_y, "m: area light size along local Y.")
        .def_readwrite("visible_camera", &Light::visible_camera,
                       "Blender's Object.visible_camera: camera rays see the light (False, as "
                       "Blender's lights).")
        .def_readwrite("portal", &Light::portal,
                       "Cycles' area light Portal: emits nothing, aims world light through an "
                       "opening (area lights only).");
    def_vec3(cls, "color", &Light::color, "Linear RGB, each >= 0.");
    def_mat4(cls, "world_from_light", &Light::world_from_light,
             "(4, 4) row-major matrix_world; the light emits along its local -Z.");

    py::class_<World> world(m, "World", "Uniform background light: color * strength.");
    world.def(py::init(&from_kwargs<World>), "World(**fields), e.g. World(strength=2.0).")
        .def_readwrite("strength", &World::strength, ">= 0.");
    def_vec3(world, "color", &World::color, "Linear RGB background colour.");
}

// Camera rays are cheap: large chunks keep the scheduling overhead negligible.
constexpr uint64_t kFilmPointsPerChunk = 16384;

void bind_camera(py::module_& m) {
    named_values_only(py::enum_<CameraType>(m, "CameraType", "Perspective or orthographic.")
        .value("PERSPECTIVE", CameraType::Perspective)
        .value("ORTHOGRAPHIC", CameraType::Orthographic));
    named_values_only(py::enum_<SensorFit>(m, "SensorFit", "Blender's camera sensor fit.")
        .value("AUTO", SensorFit::Auto)
        .value("HORIZONTAL", SensorFit::Horizontal)
        .value("VERTICAL", SensorFit::Vertical));
    py::class_<Camera> cls(m, "Camera", "A Blender camera (see scene/camera.h).");
    def_integer(cls, "resolution_x", &Camera::resolution_x, "Render width in pixels.");
    def_integer(cls, "resolution_y", &Camera::resolution_y, "Render height in pixels.");
    cls.def(py::init(&from_kwargs<Camera>), "Camera(**fields): Blender's default camera data.")
        .def_readwrite("type", &Camera::type, "CameraType.")
        .def_readwrite("lens", &Camera::lens, "Focal length in mm (perspective).")
        .def_readwrite("sensor_width", &Camera::sensor_width, "mm.")
        .def_readwrite("sensor_height", &Camera::sensor_height, "mm.")
        .def_readwrite("sensor_fit", &Camera::sensor_fit, "SensorFit.")
        .def_readwrite("ortho_scale", &Camera::ortho_scale, "m across the fitted axis.")
        .def_readwrite("shift_x", &Camera::shift_x, "In units of the fitted dimension.")
        .def_readwrite("shift_y", &Camera::shift_y, "In units of the fitted dimension.")
        .def_readwrite("clip_start", &Camera::clip_start, "m.")
        .def_readwrite("clip_end", &Camera::clip_end, "m.")
        .def(
            "generate_ray",
            [](const Camera& camera, float x, float y) {
                validate_camera(camera);
                const Ray ray =
                    camera.generate_ray(vec2(checked_finite(x, "x"), checked_finite(y, "y")));
                return py::make_tuple(to_tuple(ray.origin), to_tuple(ray.direction), ray.tmin,
                                      ray.tmax);
            },
            py::arg("x"), py::arg("y"),
            "(origin, direction, tmin, tmax) of the ray through film point (x, y) in pixels "
            "from the top-left corner; direction is unit length, tmin/tmax the clip distances.")
        .def(
            "generate_rays",
            [](const Camera& camera, const py::object& film_points) {
                validate_camera(camera);
                const std::vector<vec2> film = to_vec2_array(film_points, "film");
                std::vector<vec3> origins(film.size()), directions(film.size());
                {
                    py::gil_scoped_release release;
                    parallel_for(0, film.size(), kFilmPointsPerChunk, [&](uint64_t lo, uint64_t hi) {
                        for (uint64_t i = lo; i < hi; ++i) {
                            const Ray ray = camera.generate_ray(film[i]);
                            origins[i] = ray.origin;
                            directions[i] = ray.direction;
                        }
                    });
                }
                return py::make_tuple(to_numpy(origins), to_numpy(directions));
            },
            py::arg("film"),
            "(origins (N, 3), directions (N, 3)) of the rays through film points (N, 2) in pixels "
            "from the top-left corner (pixel centres at +0.5); directions are unit length.")
        .def(
            "project",
            [](const Camera& camera, const py::object& point) -> py::object {
                validate_camera(camera);
                vec2 film;
                if (!camera.project(to_vec3(point, "point"), &film)) return py::none();
                return py::make_tuple(film.x, film.y);
            },
            py::arg("point"),
            "Film position (x, y) in pixels of a world point, or None when it is behind.");
    def_mat4(cls, "world_from_camera", &Camera::world_from_camera,
             "(4, 4) row-major matrix_world; the camera looks down its local -Z, +Y up.");
}


// --- scene building ----------------------------------------------------------------------------

uint32_t add_mesh(Scene& scene, const py::object& mesh, const py::object& positions,
                  const py::object& triangles, const py::object& normals, const py::object& uvs,
                  const py::object& material_indices, const std::string& name,
                  const py::object& tangents) {
    SceneUse use(scene, SceneUse::Kind::Edit, "add_mesh");
    if (!mesh.is_none()) {
        if (!py::isinstance<Mesh>(mesh))
            throw py::type_error("mesh: expected an shgi.Mesh, got " +
                                 std::string(py::str(py::type::handle_of(mesh).attr("__name__"))));
        if (!positions.is_none() || !triangles.is_none())
            throw_value_error("mesh", "pass either a Mesh or positions=/triangles=, not both");
        return scene.add_mesh(mesh.cast<Mesh>());
    }
    if (positions.is_none() || triangles.is_none())
        throw_value_error("positions", "add_mesh needs a Mesh, or both positions= and triangles=");
    return scene.add_mesh(
        mesh_from_arrays(positions, triangles, normals, uvs, material_indices, name, tangents));
}

// An edit method: checks nobody is committing or querying, then forwards.
template <typename Result, typename... Args>
auto edit(const char* method, Result (Scene::*function)(Args...)) {
    return [method, function](Scene& scene, Args... args) {
        SceneUse use(scene, SceneUse::Kind::Edit, method);
        return (scene.*function)(std::forward<Args>(args)...);
    };
}

// An edit of the item with id `id_name` (set_light(light_id, light), ...): the id checked
// as an index (int_arg), the scene held as edit() holds it.
template <typename Item>
auto edit_by_id(const char* method, const char* id_name,
                void (Scene::*function)(uint32_t, Item)) {
    return [method, id_name, function](Scene& scene, const IndexInt& id, const Item& item) {
        SceneUse use(scene, SceneUse::Kind::Edit, method);
        (scene.*function)(int_arg<uint32_t>(id, id_name), item);
    };
}

// A read accessor: copies the result while no other thread commits the scene.
template <typename Result>
auto read(const char* method, Result (Scene::*function)() const) {
    return [method, function](const Scene& scene) {
        SceneUse use(scene, SceneUse::Kind::Query, method);
        std::decay_t<Result> copy = (scene.*function)();
        return copy;
    };
}

void bind_scene_building(py::class_<Scene>& cls) {
    cls.def(py::init<>(), "An empty scene.")
        .def("add_mesh", &add_mesh, py::arg("mesh") = py::none(), py::kw_only(),
             py::arg("positions") = py::none(), py::arg("triangles") = py::none(),
             py::arg("normals") = py::none(), py::arg("uvs") = py::none(),
             py::arg("material_indices") = py::none(), py::arg("name") = "",
             py::arg("tangents") = py::none(),
             (std::string("Adds a mesh (an shgi.Mesh, or keyword arrays) and returns its id. "
                          "Degenerate triangles are dropped (see stats()). ") +
              kMeshArgsDoc)
                 .c_str())
        .def(
            "add_instance",
            [](Scene& scene, const IndexInt& mesh_id, const py::object& world_from_object,
               std::string name) {
                SceneUse use(scene, SceneUse::Kind::Edit, "add_instance");
                const mat4 matrix = world_from_object.is_none()
                                        ? mat4(1.0f)
                                        : to_mat4(world_from_object, "world_from_object");
                return scene.add_instance(int_arg<uint32_t>(mesh_id, "mesh_id"), matrix,
                                          std::move(name));
            },
            py::arg("mesh_id"), py::arg("world_from_object") = py::none(), py::arg("name") = "",
            "Places mesh `mesh_id` with a (4, 4) row-major matrix (Blender's matrix_world; None "
            "= identity); returns the instance id.")
        .def("add_material", edit("add_material", &Scene::add_material), py::arg("material"),
             "Adds a Material; returns its id (the index triangles' material_indices use).")
        .def("add_texture", edit("add_texture", &Scene::add_texture), py::arg("texture"),
             "Adds a Texture; returns its id (Material.base_color_texture).")
        .def("add_light", edit("add_light", &Scene::add_light), py::arg("light"),
             "Adds a Light; returns its id.")
        .def("set_world", edit("set_world", &Scene::set_world), py::arg("world"),
             "Sets the World (uniform background light).")
        .def("set_camera", edit("set_camera", &Scene::set_camera), py::arg("camera"),
             "Sets the Camera.")
        .def(
            "set_instance_transform",
            [](Scene& scene, const IndexInt& instance_id, const py::object& world_from_object) {
                SceneUse use(scene, SceneUse::Kind::Edit, "set_instance_transform");
                scene.set_instance_transform(int_arg<uint32_t>(instance_id, "instance_id"),
                                             to_mat4(world_from_object, "world_from_object"));
            },
            py::arg("instance_id"), py::arg("world_from_object"),
            "Moves an instance; the next commit() rebuilds only the top-level BVH.")
        .def("set_light", edit_by_id("set_light", "light_id", &Scene::set_light),
             py::arg("light_id"), py::arg("light"),
             "Replaces a Light; the next commit() rebuilds no BVH.")
        .def("set_lights", edit("set_lights", &Scene::set_lights), py::arg("lights"),
             "Replaces every Light (ids are the list's indices); the next commit() rebuilds no "
             "BVH.")
        .def("set_material", edit_by_id("set_material", "material_id", &Scene::set_material),
             py::arg("material_id"), py::arg("material"),
             "Replaces a Material (triangles keep their material ids); the next commit() "
             "rebuilds no BVH.")
        .def("set_texture", edit_by_id("set_texture", "texture_id", &Scene::set_texture),
             py::arg("texture_id"), py::arg("texture"),
             "Replaces a Texture; the next commit() rebuilds no BVH.")
        .def("set_mesh", edit_by_id("set_mesh", "mesh_id", &Scene::set_mesh),
             py::arg("mesh_id"), py::arg("mesh"),
             "Replaces mesh `mesh_id` (an shgi.Mesh, checked and cleaned as add_mesh does) for "
             "every instance of it, e.g. with one that has a new lightmap UV map; the next "
             "commit() rebuilds its BVH. ValueError naming the id and the mesh count for a bad "
             "mesh_id.");
}

// --- commit, inspection ------------------------------------------------------------------------

py::dict stats_to_dict(const SceneStats& stats) {
    py::dict out;
    out["meshes"] = stats.meshes;
    out["instances"] = stats.instances;
    out["triangles"] = stats.triangles;
    out["instanced_triangles"] = stats.instanced_triangles;
    out["dropped_degenerate"] = stats.dropped_degenerate;
    out["emissive_triangles"] = stats.emissive_triangles;
    out["lights"] = stats.lights;
    out["bvh_bytes"] = stats.bvh_bytes;
    out["bvh_builds"] = stats.bvh_builds;
    out["flattened_instances"] = stats.flattened_instances;
    return out;
}

py::dict emissive_to_dict(const std::vector<EmissiveTriangle>& triangles) {
    std::vector<vec3> p0, p1, p2, radiance;
    std::vector<float> area;
    std::vector<uint32_t> instance_id, triangle_id;
    for (const EmissiveTriangle& e : triangles) {
        p0.push_back(e.p0);
        p1.push_back(e.p1);
        p2.push_back(e.p2);
        radiance.push_back(e.radiance);
        area.push_back(e.area);
        instance_id.push_back(e.instance_id);
        triangle_id.push_back(e.triangle_id);
    }
    py::dict out;
    out["p0"] = to_numpy(p0);
    out["p1"] = to_numpy(p1);
    out["p2"] = to_numpy(p2);
    out["area"] = to_numpy_1d(area);
    out["radiance"] = to_numpy(radiance);
    out["instance_id"] = to_numpy_1d(instance_id);
    out["triangle_id"] = to_numpy_1d(triangle_id);
    return out;
}

void bind_scene_inspection(py::class_<Scene>& cls) {
    cls.def(
           "commit",
           [](Scene& scene, const IndexInt& memory_budget_bytes, Progress* progress,
              bool flatten_single_use_meshes) {
               // 0 = 75% of what the process may still allocate
               CommitSettings settings;
               settings.memory_budget_bytes =
                   int_arg<uint64_t>(memory_budget_bytes, "memory_budget_bytes");
               settings.flatten_single_use_meshes = flatten_single_use_meshes;
               SceneUse use(scene, SceneUse::Kind::Commit, "commit");
               run_interruptible(progress, [&](Progress* used) {
                   scene.commit(settings, used);
               });
           },
           py::arg("memory_budget_bytes") = 0, py::arg("progress") = py::none(),
           py::arg("flatten_single_use_meshes") = true,
           "Checks cross references and builds the BVH, with the GIL released: a mesh used by "
           "one instance goes into the top-level BVH in world space (flatten_single_use_meshes; "
           "False instances every mesh, with the same hits), a mesh used by several is "
           "instanced. Raises "
           "MemoryError when the BVH would exceed memory_budget_bytes (0 = 75% of what the process "
           "may still allocate: RLIMIT_AS, cgroup limit, free memory), "
           "shgi.Cancelled when progress.cancel() is called.")
        .def_property_readonly("committed", read("committed", &Scene::committed),
                               "True after a successful commit.")
        .def_property_readonly("empty", read("empty", &Scene::empty),
                               "True when no instance has triangles.")
        .def_property_readonly("has_camera", read("has_camera", &Scene::has_camera),
                               "True once set_camera ran.")
        .def_property_readonly("camera", read("camera", &Scene::camera),
                               "A copy of the Camera (ValueError if none was set).")
        .def_property_readonly("world", read("world", &Scene::world), "A copy of the World.")
        .def_property_readonly("meshes", read("meshes", &Scene::meshes),
                               "Copies of the (cleaned) meshes.")
        .def_property_readonly("instances", read("instances", &Scene::instances),
                               "Copies of the instances.")
        .def_property_readonly("materials", read("materials", &Scene::materials),
                               "Copies of the materials.")
        .def_property_readonly("textures", read("textures", &Scene::textures),
                               "Copies of the textures.")
        .def_property_readonly("lights", read("lights", &Scene::lights), "Copies of the lights.")
        .def(
            "stats",
            [](const Scene& scene) { return stats_to_dict(read("stats", &Scene::stats)(scene)); },
            "Dict of counts: meshes, instances, triangles, instanced_triangles, "
            "dropped_degenerate, emissive_triangles, lights, bvh_bytes (peak of the last commit "
            "that built a BVH), bvh_builds (Embree builds so far: per-mesh and top-level), "
            "flattened_instances (instances whose mesh is in the top-level BVH itself).")
        .def(
            "bounds",
            [](const Scene& scene) {
                const Bounds3 bounds = read("bounds", &Scene::bounds)(scene);
                return py::make_tuple(to_tuple(bounds.lower), to_tuple(bounds.upper));
            },
            "World-space bounds ((x0, y0, z0), (x1, y1, z1)); ValueError for an empty scene.")
        .def(
            "emissive_triangles",
            [](const Scene& scene) {
                return emissive_to_dict(
                    read("emissive_triangles", &Scene::emissive_triangles)(scene));
            },
            "Emissive triangles gathered at commit: dict of p0, p1, p2 (K, 3) world space, "
            "area (K,) m^2, radiance (K, 3), instance_id and triangle_id (K,).");
}

// --- batch queries -----------------------------------------------------------------------------

// A scalar (the same for every ray) or an (N,) array.
std::vector<float> per_ray_values(const py::object& obj, const char* arg_name, size_t count) {
    const py::array array = py::array::ensure(obj);
    if (PyFloat_Check(obj.ptr()) || PyLong_Check(obj.ptr()) || (array && array.ndim() == 0)) {
        float value = 0.0f;
        try {
            value = obj.cast<float>();
        } catch (const py::cast_error&) {  // a string, or another 0-d array that is no number
            throw_value_error(arg_name, "expected a number or an (N,) array of numbers, got " +
                                            py::repr(obj).cast<std::string>());
        }
        return std::vector<float>(count, value);
    }
    // Non-finite values are allowed here (tmax = inf); the rays' own check rejects NaN.
    std::vector<float> values = to_float_rows(obj, arg_name, 0, /*allow_non_finite=*/true);
    if (values.size() != count)
        throw_value_error(arg_name, "has " + std::to_string(values.size()) +
                                        " values but there are " + std::to_string(count) +
                                        " rays");
    return values;
}

std::vector<Ray> rays_from_arrays(const py::object& origins, const py::object& directions,
                                  const py::object& tmin, const py::object& tmax) {
    const std::vector<vec3> o = to_vec3_array(origins, "origins");
    const std::vector<vec3> d = to_vec3_array(directions, "directions");
    if (o.size() != d.size())
        throw_value_error("directions", "has " + std::to_string(d.size()) +
                                            " rows but origins has " + std::to_string(o.size()));
    const std::vector<float> near = per_ray_values(tmin, "tmin", o.size());
    const std::vector<float> far = per_ray_values(tmax, "tmax", o.size());
    std::vector<Ray> rays(o.size());
    for (size_t i = 0; i < rays.size(); ++i) rays[i] = Ray{o[i], d[i], near[i], far[i]};
    return rays;
}

py::dict hits_to_dict(const std::vector<Hit>& hits) {
    const auto n = static_cast<py::ssize_t>(hits.size());
    py::array_t<float> t(n), barycentrics({n, py::ssize_t(2)}), normal({n, py::ssize_t(3)});
    py::array_t<uint32_t> instance_id(n), triangle_id(n);
    py::array_t<bool> hit(n);
    float* t_data = t.mutable_data();
    float* b_data = barycentrics.mutable_data();
    float* n_data = normal.mutable_data();
    for (py::ssize_t i = 0; i < n; ++i) {
        const Hit& h = hits[i];
        t_data[i] = h.t;
        instance_id.mutable_data()[i] = h.instance_id;
        triangle_id.mutable_data()[i] = h.triangle_id;
        hit.mutable_data()[i] = h.valid();
        b_data[2 * i] = h.barycentrics.x;
        b_data[2 * i + 1] = h.barycentrics.y;
        const vec3 unit = h.valid() ? glm::normalize(h.geometric_normal) : vec3(0.0f);
        for (int k = 0; k < 3; ++k) n_data[3 * i + k] = unit[k];
    }
    py::dict out;
    out["hit"] = hit;
    out["t"] = t;
    out["instance_id"] = instance_id;
    out["triangle_id"] = triangle_id;
    out["barycentrics"] = barycentrics;
    out["normal"] = normal;
    return out;
}

constexpr const char* kRayArgsDoc =
    "origins, directions: (N, 3) float (directions need not be unit: t is in units of their "
    "length); tmin, tmax: scalars or (N,) arrays (tmax may be inf). The GIL is released; "
    "progress (shgi.Progress) reports and cancels (shgi.Cancelled). ValueError names the first "
    "invalid ray (NaN, zero direction, tmax < tmin).";

void bind_scene_queries(py::class_<Scene>& cls) {
    cls.def(
           "intersect",
           [](const Scene& scene, const py::object& origins, const py::object& directions,
              const py::object& tmin, const py::object& tmax, Progress* progress) {
               const std::vector<Ray> rays = rays_from_arrays(origins, directions, tmin, tmax);
               std::vector<Hit> hits;
               {
                   SceneUse use(scene, SceneUse::Kind::Query, "intersect");
                   run_interruptible(progress, [&](Progress* used) {
                       scene.intersect(rays, hits, used);
                   });
               }
               return hits_to_dict(hits);
           },
           py::arg("origins"), py::arg("directions"), py::arg("tmin") = 0.0f,
           py::arg("tmax") = std::numeric_limits<float>::infinity(),
           py::arg("progress") = py::none(),
           (std::string("Closest hits of a batch of rays: dict of hit (N,) bool, t (N,) float32 "
                        "(inf on a miss), instance_id and triangle_id (N,) uint32 (0xFFFFFFFF "
                        "on a miss), barycentrics (N, 2) float32 (b1, b2), normal (N, 3) unit "
                        "world-space geometric normal (0 on a miss). ") +
            kRayArgsDoc)
               .c_str())
        .def(
            "occluded",
            [](const Scene& scene, const py::object& origins, const py::object& directions,
               const py::object& tmin, const py::object& tmax, Progress* progress) {
                const std::vector<Ray> rays = rays_from_arrays(origins, directions, tmin, tmax);
                std::vector<uint8_t> occluded;
                {
                    SceneUse use(scene, SceneUse::Kind::Query, "occluded");
                    run_interruptible(progress, [&](Progress* used) {
                        scene.occluded(rays, occluded, used);
                    });
                }
                py::array_t<bool> out(static_cast<py::ssize_t>(occluded.size()));
                for (size_t i = 0; i < occluded.size(); ++i) out.mutable_data()[i] = occluded[i];
                return out;
            },
            py::arg("origins"), py::arg("directions"), py::arg("tmin") = 0.0f,
            py::arg("tmax") = std::numeric_limits<float>::infinity(),
            py::arg("progress") = py::none(),
            (std::string("(N,) bool: True where something lies between tmin and tmax. ") +
             kRayArgsDoc)
                .c_str());
}

void bind_scene_class(py::module_& m) {
    py::class_<Scene> cls(m, "Scene", R"doc(
Meshes, instances, materials, textures, lights, world and camera, plus the Embree BVH that
answers ray queries. Build it with add_*, call commit(), then query. Any edit un-commits.
Editing while another thread commits or queries the scene raises RuntimeError.)doc");
    bind_scene_building(cls);
    bind_scene_inspection(cls);
    bind_scene_queries(cls);
}

}  // namespace

void bind_scene(py::module_& m) {
    bind_mesh(m);
    bind_material(m);
    bind_light(m);
    bind_camera(m);
    py::class_<Instance> instance(m, "Instance", "A placement of a mesh in the world.");
    instance.def_readonly("name", &Instance::name, "The object's name.")
        .def_readonly("mesh_id", &Instance::mesh_id, "Index of the instanced mesh.")
        .def_property_readonly(
            "world_from_object",
            [](const Instance& self) { return from_mat4(self.world_from_object); },
            "(4, 4) row-major matrix_world.");
    bind_scene_class(m);
    // The largest |coordinate| a scene holds (m): the export checks vertices against it before
    // it computes their normals, where a larger one would overflow.
    m.attr("MAX_COORDINATE") = kMaxCoordinate;
}

}  // namespace shgi::python
