// Bindings for the scene loaders of native/io: shgi.load_gltf and shgi.load_obj.
//
// Both return a shgi.Scene (bound in bind_scene.cpp, which module.cpp registers first). Options
// are keyword arguments named like the fields of GltfLoadOptions / ObjLoadOptions, their enum
// values spelled as Blender's importers spell them ("SPEC", "Y"). Arguments are checked with the
// GIL held; the GIL is released while the file is read and converted.
#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include <pybind11/pybind11.h>

#include "io/gltf_loader.h"
#include "io/obj_loader.h"
#include "interruptible.h"
#include "path_arg.h"
#include "scene/scene.h"

namespace py = pybind11;

namespace shgi::python {
namespace {

GltfLightingMode lighting_mode_from_name(const std::string& name) {
    if (name == "SPEC") return GltfLightingMode::Spec;
    if (name == "COMPAT") return GltfLightingMode::Compat;
    if (name == "RAW") return GltfLightingMode::Raw;
    throw py::value_error("lighting_mode: expected 'SPEC', 'COMPAT' or 'RAW', got '" + name +
                          "'");
}

ObjUpAxis up_axis_from_name(const std::string& name) {
    if (name == "Y") return ObjUpAxis::Y;
    if (name == "Z") return ObjUpAxis::Z;
    throw py::value_error("up_axis: expected 'Y' or 'Z', got '" + name + "'");
}

}  // namespace

void bind_loaders(py::module_& m) {
    m.def(
        "load_gltf",
        [](const PathArg& path, const std::string& lighting_mode,
           bool import_lights, bool import_camera, bool import_textures, float light_radius,
           float sun_angle, Progress* progress) {
            if (!(light_radius >= 0.0f) || !std::isfinite(light_radius))
                throw py::value_error("light_radius: must be a finite value >= 0 (m), got " +
                                      std::to_string(light_radius));
            if (!(sun_angle >= 0.0f) || !(sun_angle < kPi))
                throw py::value_error("sun_angle: must be in [0, pi) (rad), got " +
                                      std::to_string(sun_angle));
            GltfLoadOptions options;
            options.lighting_mode = lighting_mode_from_name(lighting_mode);
            options.import_lights = import_lights;
            options.import_camera = import_camera;
            options.import_textures = import_textures;
            options.light_radius = light_radius;
            options.sun_angle = sun_angle;
            return run_interruptible(
                progress, [&](Progress* used) { return load_gltf(path.value, options, used); });
        },
        py::arg("path"), py::kw_only(), py::arg("lighting_mode") = "SPEC",
        py::arg("import_lights") = true, py::arg("import_camera") = true,
        py::arg("import_textures") = true, py::arg("light_radius") = kBlenderDefaultLightRadius,
        py::arg("sun_angle") = kBlenderDefaultSunAngle, py::arg("progress") = py::none(),
        R"doc(
Loads the default scene of a glTF 2.0 file (.gltf or .glb) into a new, uncommitted Scene, as
Blender 3.4's glTF importer would import it.

Y-up glTF becomes Z-up ((x, y, z) -> (x, -z, y)); UV v becomes 1 - v; each glTF mesh is
one mesh (its TRIANGLES primitives merged, a material per triangle, as Blender's material
slots), instanced once per node that uses it; TEXCOORD_n are UV sets "UVMap", "UVMap.001",
...; the base colour texture is decoded to linear RGBA; the first camera node sets the camera.
lighting_mode: how KHR_lights_punctual intensities become Blender units, as the importer's
    "Lighting Mode": "SPEC" (point/spot W = cd * 4 pi / 683, sun W/m^2 = lux / 683), "COMPAT"
    (W = cd * 4 pi, sun = lux) or "RAW" (values copied).
import_lights, import_camera, import_textures: skip those parts when False.
light_radius (m), sun_angle (rad): what glTF's punctual lights lack; the defaults are Blender's
    new-light defaults (0.25 m, 0.526 degrees), which its importer keeps. 0 gives point lights.
Raises OSError naming the file when it is missing, malformed or uses unsupported required
extensions; problems that only cost a part (an undecodable image, a non-triangle primitive) are
logged as warnings.)doc");

    m.def(
        "load_obj",
        [](const PathArg& path, const std::string& up_axis, Progress* progress) {
            ObjLoadOptions options;
            options.up_axis = up_axis_from_name(up_axis);
            return run_interruptible(
                progress, [&](Progress* used) { return load_obj(path.value, options, used); });
        },
        py::arg("path"), py::kw_only(), py::arg("up_axis") = "Y", py::arg("progress") = py::none(),
        R"doc(
Loads a Wavefront OBJ file and the .mtl files it names (looked up beside it) into a new,
uncommitted Scene, as Blender 3.4's OBJ importer would import it.

One mesh per OBJ object/group, each instanced once with the identity transform; polygons are
triangulated; vt coordinates become UV set "UVMap". MTL statements map to materials as Blender
maps them: Kd base colour, Ke emission, Ks specular, Ns roughness = 1 - sqrt(Ns / 1000),
Ni IOR, Pr/Pm (PBR extension) roughness/metallic; d/Tr are ignored.
up_axis: "Y" (the importer's default: forward -Z, up Y, converted to Z-up) or "Z" (no change).
Raises OSError naming the file when it is missing or malformed, or when a face refers to a
vertex, normal or UV that does not exist; a missing .mtl is logged as a warning.
progress: a shgi.Progress ("reading", then "importing" shape by shape); its cancel, or Ctrl-C,
    stops the load with shgi.Cancelled (KeyboardInterrupt) between shapes.)doc");
}

}  // namespace shgi::python
