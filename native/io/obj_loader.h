// Wavefront OBJ + MTL loading into a shgi::Scene, following Blender 3.4's OBJ importer
// (source/blender/io/wavefront_obj) so that a file loaded here and the same file imported into
// Blender and exported by the add-on agree.
//
// Geometry: one Mesh per OBJ shape (o/g groups, as tinyobjloader splits them), each instanced
// once with the identity transform and named after the shape. Polygons are triangulated as fans
// (exact for convex polygons, which is what OBJ exporters write). Face corners are welded into
// vertices by their (v, vt, vn) triple. Normals are kept when every corner has one; UVs when any
// corner has one (corners without get (0, 0)), as UV set "UVMap". OBJ's UV origin is the
// bottom-left corner, like Blender's: no flip.
//
// Axes: the importer's defaults, forward -Z and up +Y, i.e. (x, y, z)_obj -> (x, -z, y)_blender,
// the same change as glTF's (io/gltf_loader.h). ObjUpAxis::Z reads the file as already Z-up.
// Blender keeps the conversion in the object's transform; here it is applied to the mesh data
// and the instance transform is the identity: the world-space geometry is the same.
//
// Materials (MTL), as Blender 3.4's importer maps them onto the Principled BSDF
// (obj_import_mtl.cc, set_bsdf_socket_values); "illum" selects highlight/reflection/glass modes:
//   Kd -> base_color;  Ke -> emission_color (strength 1);  Ks (mean) -> specular;
//   Ns -> roughness = 1 - sqrt(clamp(Ns, 0, 1000) / 1000);
//   Ka (mean) -> metallic for reflective illum (3-8), else metallic 0;
//   Ni -> ior (clamped to >= 1);  d / Tr -> ignored (Blender maps them to Alpha, which SHGI
//   does not render; transmission stays 0).
// The PBR extension, when present, overrides: Pr -> roughness, Pm -> metallic (as Blender
// 3.4.1 does; the test file's values were checked against its importer). Texture maps (map_Kd, ...) are not loaded: a warning names them.
// Statements missing from a material leave Blender's fallbacks (e.g. no Ns -> roughness 1, or
// 0 with illum 2). Faces without a material get a default Material.
//
// Errors: a missing or unparsable file, or a face index outside the vertex, normal or UV lists,
// throws IoError naming the file and the shape; a missing .mtl is a log_warning().
#pragma once

#include <cstdint>
#include <string>

#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

// Mirrors the importer's up_axis (its forward_axis follows: -Z for Y up, Y for Z up).
enum class ObjUpAxis : uint8_t { Y, Z };

struct ObjLoadOptions {
    ObjUpAxis up_axis = ObjUpAxis::Y;
};

// Throws IoError naming `path` on any failure; .mtl files are looked up beside the .obj.
// Progress: "reading" (tinyobjloader parses the file in one call: cancel is polled before and
// after it) then "importing" (shape by shape); Cancelled within one shape.
Scene load_obj(const std::string& path, const ObjLoadOptions& options = {},
               Progress* progress = nullptr);

// Blender's specular-exponent to roughness mapping (see above).
float obj_roughness_from_exponent(float ns);

}  // namespace shgi
