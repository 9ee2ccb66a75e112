// Triangle meshes: indexed vertices with optional normals, tangents and UV sets, one material per
// triangle.
//
// Positions are in object space (metres). Normals, when given, are per vertex (the Blender
// exporter splits vertices where split normals, tangents or UVs differ, as glTF does). Tangents,
// when given, are per vertex too: xyz the object-space tangent along +U of the UV set the normal
// maps read (MikkTSpace, as Blender's Mesh.calc_tangents and glTF's TANGENT), w the bitangent
// sign (+1 or -1): bitangent = w * cross(normal, tangent), as Cycles' Normal Map node builds it. Material indices are
// per triangle and index Scene::materials(). Mesh::validate() is the input boundary: it rejects
// NaN/Inf and out-of-range indices with an InvalidArgument naming the array and element, and drops
// degenerate triangles (repeated index or zero area), counting them in the report.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "util/math.h"

namespace shgi {

struct UvSet {
    std::string name;          // Blender's UV map name, e.g. "UVMap", "LightmapUV"
    std::vector<vec2> coords;  // one per vertex
};

struct Mesh {
    std::string name;
    std::vector<vec3> positions;
    std::vector<uvec3> triangles;             // vertex indices, counter-clockwise = front
    std::vector<vec3> normals;                // empty, or one per vertex
    std::vector<vec4> tangents;               // empty, or one per vertex (xyz tangent, w sign)
    std::vector<UvSet> uv_sets;               // each with one coordinate per vertex
    std::vector<uint32_t> material_indices;   // empty (all use material 0), or one per triangle
};

struct MeshReport {
    uint64_t dropped_degenerate = 0;  // triangles removed for repeated indices or zero area
    uint64_t fixed_normals = 0;       // zero-length normals replaced by the face normal
    // Non-finite or zero-length tangents set to zero: a tangent-space normal map leaves the
    // triangles that use them shaded by their interpolated normal (a warning, not an error).
    uint64_t dropped_tangents = 0;
    // The longest edge of the kept triangles, in object space (m): it bounds Embree's
    // triangle-test arithmetic (Scene::ray_limits).
    double longest_edge = 0.0;
};

// Checks and cleans a mesh in place; `material_count` bounds the material indices (Scene passes
// kAnyMaterialCount while materials may still be added, and checks again at commit).
// Throws InvalidArgument naming the mesh, the array and the first bad element: NaN/Inf or
// |coordinate| > 1e12 (beyond Embree's float range), array sizes that differ from the vertex or
// triangle count, vertex or material indices out of range. Degenerate triangles are dropped (with
// their material index); zero-length normals are replaced by the adjacent face normals; NaN or
// zero-length tangents are zeroed (MeshReport::dropped_tangents) and their signs made +-1.
MeshReport validate_mesh(Mesh& mesh, uint32_t material_count);

inline constexpr uint32_t kAnyMaterialCount = 0xFFFFFFFFu;

// Throws InvalidArgument if a material index is >= material_count (used again at commit time).
void check_material_indices(const Mesh& mesh, uint32_t material_count);

// Area of triangle `i` in object space.
float triangle_area(const Mesh& mesh, uint32_t triangle);

// True when every edge of the mesh (vertices welded by exact position, as split normals and UV
// seams duplicate them) is shared by exactly one other triangle running it the other way: a
// closed, consistently wound surface, whose back faces mean "inside". Single-sided walls and
// planes are open: which way they face is an accident of modelling (Cycles shades both sides
// alike), so their back faces say nothing about being inside.
bool is_closed_surface(const Mesh& mesh);

}  // namespace shgi
