#include "scene/mesh.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "scene/validation.h"
#include "util/error.h"

namespace shgi {
namespace {

using scene_detail::to_string;

// A triangle is degenerate when twice its area is below this fraction of its longest edge
// squared (the sine of its smallest angle, roughly). 1e-7 is float32's resolution: the normal of
// a flatter triangle is rounding noise, and Embree would report hits with meaningless normals.
constexpr double kMinRelativeArea = 1e-7;

// A normal shorter than this cannot be normalised reliably (Blender writes unit normals; zero
// ones come from broken importers or collapsed geometry).
constexpr float kMinNormalLength = 1e-6f;

std::string mesh_label(const Mesh& mesh) { return scene_detail::label("mesh", mesh.name); }

void check_count(const Mesh& mesh, const char* array, size_t count, const char* reference,
                 size_t expected, const char* fix) {
    if (count != expected)
        throw InvalidArgument(format_message(mesh_label(mesh), ": ", array, " has ", count,
                                             " elements but ", reference, " has ", expected,
                                             "; ", fix));
}

void check_sizes(const Mesh& mesh) {
    const size_t vertices = mesh.positions.size();
    if (!mesh.normals.empty())
        check_count(mesh, "normals", mesh.normals.size(), "positions", vertices,
                    "give one normal per vertex or none");
    if (!mesh.tangents.empty())
        check_count(mesh, "tangents", mesh.tangents.size(), "positions", vertices,
                    "give one tangent (x, y, z, sign) per vertex or none");
    for (const UvSet& uv_set : mesh.uv_sets)
        check_count(mesh, ("uv set '" + uv_set.name + "'").c_str(), uv_set.coords.size(),
                    "positions", vertices, "give one UV per vertex");
    if (!mesh.material_indices.empty())
        check_count(mesh, "material_indices", mesh.material_indices.size(), "triangles",
                    mesh.triangles.size(), "give one material index per triangle or none");
    if (vertices >= kAnyMaterialCount)
        throw InvalidArgument(format_message(mesh_label(mesh), ": ", vertices,
                                             " vertices exceed the 32-bit index range"));
}

template <typename Vec>
void check_finite(const Mesh& mesh, const std::string& array, const std::vector<Vec>& values) {
    for (size_t i = 0; i < values.size(); ++i)
        if (!is_finite(values[i]))
            throw InvalidArgument(format_message(mesh_label(mesh), ": ", array, "[", i,
                                                 "] = ", to_string(values[i]),
                                                 " is not finite"));
}

void check_values(const Mesh& mesh) {
    check_finite(mesh, "positions", mesh.positions);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const vec3& p = mesh.positions[i];
        if (glm::any(glm::greaterThan(glm::abs(p), vec3(kMaxCoordinate))))
            throw InvalidArgument(format_message(
                mesh_label(mesh), ": positions[", i, "] = ", to_string(p), " exceeds ",
                kMaxCoordinate, " m in magnitude (beyond Embree's float range); apply a scale"));
    }
    check_finite(mesh, "normals", mesh.normals);
    for (const UvSet& uv_set : mesh.uv_sets)
        check_finite(mesh, "uv set '" + uv_set.name + "'", uv_set.coords);
}

void check_triangle_indices(const Mesh& mesh) {
    const size_t vertices = mesh.positions.size();
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
        const uvec3& tri = mesh.triangles[i];
        for (int k = 0; k < 3; ++k)
            if (tri[k] >= vertices)
                throw InvalidArgument(format_message(
                    mesh_label(mesh), ": triangles[", i, "] = (", tri.x, ", ", tri.y, ", ",
                    tri.z, ") indexes vertex ", tri[k], " but the mesh has ", vertices,
                    " vertices"));
    }
}

bool is_degenerate(const Mesh& mesh, const uvec3& tri) {
    if (tri.x == tri.y || tri.y == tri.z || tri.x == tri.z) return true;
    const glm::dvec3 p0(mesh.positions[tri.x]);
    const glm::dvec3 e1 = glm::dvec3(mesh.positions[tri.y]) - p0;
    const glm::dvec3 e2 = glm::dvec3(mesh.positions[tri.z]) - p0;
    const glm::dvec3 e3 = e2 - e1;
    const double longest_squared =
        std::max({glm::dot(e1, e1), glm::dot(e2, e2), glm::dot(e3, e3)});
    const double twice_area = glm::length(glm::cross(e1, e2));
    return !(twice_area > kMinRelativeArea * longest_squared);
}

// Removes degenerate triangles (and their material indices) in place, keeping the order.
uint64_t drop_degenerate(Mesh& mesh) {
    const bool has_materials = !mesh.material_indices.empty();
    size_t kept = 0;
    for (size_t i = 0; i < mesh.triangles.size(); ++i) {
        if (is_degenerate(mesh, mesh.triangles[i])) continue;
        mesh.triangles[kept] = mesh.triangles[i];
        if (has_materials) mesh.material_indices[kept] = mesh.material_indices[i];
        ++kept;
    }
    const uint64_t dropped = mesh.triangles.size() - kept;
    mesh.triangles.resize(kept);
    if (has_materials) mesh.material_indices.resize(kept);
    return dropped;
}

// Replaces zero-length vertex normals by the area-weighted sum of the adjacent face normals
// (the face normal itself for a vertex used once); +Z for a vertex no triangle uses.
uint64_t fix_normals(Mesh& mesh) {
    const auto is_zero = [](const vec3& n) { return !(glm::length(n) >= kMinNormalLength); };
    if (std::none_of(mesh.normals.begin(), mesh.normals.end(), is_zero)) return 0;
    std::vector<vec3> face_sum(mesh.positions.size(), vec3(0.0f));
    for (const uvec3& tri : mesh.triangles) {
        const vec3 n = glm::cross(mesh.positions[tri.y] - mesh.positions[tri.x],
                                  mesh.positions[tri.z] - mesh.positions[tri.x]);
        for (int k = 0; k < 3; ++k) face_sum[tri[k]] += n;
    }
    uint64_t fixed = 0;
    for (size_t i = 0; i < mesh.normals.size(); ++i) {
        if (!is_zero(mesh.normals[i])) continue;
        const float length = glm::length(face_sum[i]);
        mesh.normals[i] = length > 0.0f ? face_sum[i] / length : vec3(0.0f, 0.0f, 1.0f);
        ++fixed;
    }
    return fixed;
}

// Zeroes tangents that cannot orient a normal map (NaN, infinite, or too short to normalise:
// broken importers, UV maps collapsed to a point) and makes every sign +-1. A zero tangent is
// what surface_point reads as "no tangent frame here": the normal map is skipped, as Cycles
// renders a Normal Map node without a usable tangent.
uint64_t fix_tangents(Mesh& mesh) {
    uint64_t dropped = 0;
    for (vec4& tangent : mesh.tangents) {
        const vec3 t(tangent);
        if (!is_finite(t) || !std::isfinite(tangent.w) || !(glm::length(t) >= kMinNormalLength)) {
            tangent = vec4(0.0f);
            ++dropped;
            continue;
        }
        tangent.w = tangent.w < 0.0f ? -1.0f : 1.0f;
    }
    return dropped;
}

}  // namespace

void check_material_indices(const Mesh& mesh, uint32_t material_count) {
    for (size_t i = 0; i < mesh.material_indices.size(); ++i)
        if (mesh.material_indices[i] >= material_count)
            throw InvalidArgument(format_message(
                mesh_label(mesh), ": material_indices[", i, "] = ", mesh.material_indices[i],
                " but the scene has ", material_count, " materials"));
}

MeshReport validate_mesh(Mesh& mesh, uint32_t material_count) {
    check_sizes(mesh);
    check_values(mesh);
    check_triangle_indices(mesh);
    check_material_indices(mesh, material_count);
    MeshReport report;
    report.dropped_degenerate = drop_degenerate(mesh);
    report.fixed_normals = fix_normals(mesh);
    report.dropped_tangents = fix_tangents(mesh);
    // Squared lengths (in double: a float square of 1e12 m edges is close to float's range),
    // one square root at the end.
    double edge2 = 0.0;
    for (const uvec3& tri : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const glm::dvec3 edge =
                glm::dvec3(mesh.positions[tri[(k + 1) % 3]]) - glm::dvec3(mesh.positions[tri[k]]);
            edge2 = std::max(edge2, glm::dot(edge, edge));
        }
    report.longest_edge = std::sqrt(edge2);
    return report;
}

float triangle_area(const Mesh& mesh, uint32_t triangle) {
    if (triangle >= mesh.triangles.size())
        throw InvalidArgument(format_message(mesh_label(mesh), ": triangle ", triangle,
                                             " is out of range (", mesh.triangles.size(),
                                             " triangles)"));
    const uvec3& tri = mesh.triangles[triangle];
    const vec3& p0 = mesh.positions[tri.x];
    return 0.5f * glm::length(glm::cross(mesh.positions[tri.y] - p0, mesh.positions[tri.z] - p0));
}

bool is_closed_surface(const Mesh& mesh) {
    std::unordered_map<uint64_t, uint32_t> welded;
    std::vector<uint32_t> vertex(mesh.positions.size());
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const vec3& p = mesh.positions[i];
        uint32_t bits[3];
        std::memcpy(bits, &p, sizeof(bits));
        const uint64_t key = (uint64_t(bits[0]) * 0x9e3779b97f4a7c15ull) ^
                             (uint64_t(bits[1]) * 0xc2b2ae3d27d4eb4full) ^
                             (uint64_t(bits[2]) * 0x165667b19e3779f9ull);
        // Hash collisions of distinct points would only merge two vertices: a mesh could then
        // be taken as open (its back faces ignored), never the other way round in practice.
        vertex[i] = welded.emplace(key, uint32_t(welded.size())).first->second;
    }
    std::unordered_map<uint64_t, int> edges;  // directed edge -> count (reverse subtracts)
    for (const uvec3& t : mesh.triangles) {
        const uint32_t v[3] = {vertex[t.x], vertex[t.y], vertex[t.z]};
        for (int e = 0; e < 3; ++e) {
            const uint32_t a = v[e], b = v[(e + 1) % 3];
            if (a == b) return false;
            const uint64_t forward = (uint64_t(a) << 32) | b;
            const uint64_t backward = (uint64_t(b) << 32) | a;
            auto it = edges.find(backward);
            if (it != edges.end()) {
                if (--it->second == 0) edges.erase(it);
            } else if (++edges[forward] > 1) {
                return false;  // the same edge twice the same way: inconsistent winding
            }
        }
    }
    return edges.empty() && !mesh.triangles.empty();
}

}  // namespace shgi
