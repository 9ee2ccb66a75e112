#include "bake/texel_rasterizer.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <numeric>
#include <unordered_map>
#include <utility>

#include "render/shading.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/parallel.h"

namespace shgi {
namespace {

using glm::dvec2;
using glm::dvec3;

constexpr uint32_t kMaxSamplesPerAxis = 16;

// A UV triangle is degenerate when twice its area is below this fraction of its longest edge
// squared (about the sine of its smallest angle): float32 UVs resolve ~1e-7 relative, so a
// flatter triangle has no meaningful interior (the same bound validate_mesh uses for positions).
constexpr double kMinRelativeUvArea = 1e-7;

// Intersections of a triangle and a texel below this area (in texels) are clipping round-off
// of triangles that merely touch the texel along an edge or at a corner: coordinates up to
// kMaxLightmapResolution texels carry ~1e-12 absolute error in double.
constexpr double kMinClippedArea = 1e-9;

// A texel counts as overlapping when its triangles' areas sum past 1 by more than this: the
// areas are exact up to float rounding of the weights (~1e-7 each).
constexpr double kOverlapTolerance = 1e-3;

// Triangles per parallel chunk: large enough to amortise scheduling, small enough to poll
// cancel often (a chunk of big triangles at 16384^2 still takes well under 0.2 s per core).
constexpr uint64_t kTrianglesPerChunk = 64;

// Texels per slice of the passes over the whole grid (gathering, coverage): a cancel poll and a
// progress report each, ~10 ms.
constexpr uint64_t kTexelsPerSlice = uint64_t(1) << 20;

// Progress of the rasterizing stage in texels of the triangles' bounding boxes, reported and
// polled for cancel once per texel row of a triangle: one large triangle at 16384^2 would
// otherwise ignore cancel for seconds.
class RowProgress {
  public:
    RowProgress(Progress* progress, uint64_t total) : progress_(progress), total_(total) {}
    void advance(uint64_t texels) {
        if (progress_ == nullptr) return;
        progress_->throw_if_cancelled();
        const uint64_t done = done_.fetch_add(texels, std::memory_order_relaxed) + texels;
        progress_->report(std::min(done, total_), total_);
    }

  private:
    Progress* progress_;
    uint64_t total_;
    std::atomic<uint64_t> done_{0};
};

std::string mesh_label(const Mesh& mesh) {
    return mesh.name.empty() ? std::string("mesh (unnamed)") : "mesh '" + mesh.name + "'";
}

// --- input checks ---------------------------------------------------------------------------

void check_settings(const TexelRasterSettings& settings) {
    check_lightmap_side("TexelRasterSettings.width", settings.width);
    check_lightmap_side("TexelRasterSettings.height", settings.height);
    if (settings.samples_per_axis < 1 || settings.samples_per_axis > kMaxSamplesPerAxis)
        throw InvalidArgument(format_message("TexelRasterSettings.samples_per_axis = ",
                                             settings.samples_per_axis, " is outside [1, ",
                                             kMaxSamplesPerAxis, "]"));
}

const UvSet& find_uv_set(const Mesh& mesh, const std::string& name) {
    for (const UvSet& uv_set : mesh.uv_sets)
        if (uv_set.name == name) return uv_set;
    std::string available;
    for (const UvSet& uv_set : mesh.uv_sets)
        available += (available.empty() ? "'" : ", '") + uv_set.name + "'";
    throw InvalidArgument(format_message(
        mesh_label(mesh), " has no UV set '", name, "' (",
        available.empty() ? "it has no UV sets" : "its UV sets: " + available,
        "); add a UV map of that name in Blender (Object Data > UV Maps, or UV > Lightmap Pack) "
        "or set uv_set to one of its UV sets"));
}

template <typename Vec>
void check_finite(const Mesh& mesh, const std::string& array, const std::vector<Vec>& values) {
    for (size_t i = 0; i < values.size(); ++i)
        if (!is_finite(values[i]))
            throw InvalidArgument(format_message(mesh_label(mesh), ": ", array, "[", i,
                                                 "] is not finite (NaN or Inf)"));
}

void check_mesh(const Mesh& mesh, const UvSet& uv_set, const mat4& world_from_object) {
    const size_t vertices = mesh.positions.size();
    if (uv_set.coords.size() != vertices)
        throw InvalidArgument(format_message(mesh_label(mesh), ": uv set '", uv_set.name,
                                             "' has ", uv_set.coords.size(),
                                             " elements but positions has ", vertices,
                                             "; give one UV per vertex"));
    if (!mesh.normals.empty() && mesh.normals.size() != vertices)
        throw InvalidArgument(format_message(mesh_label(mesh), ": normals has ",
                                             mesh.normals.size(), " elements but positions has ",
                                             vertices, "; give one normal per vertex or none"));
    for (size_t i = 0; i < mesh.triangles.size(); ++i)
        for (int k = 0; k < 3; ++k)
            if (mesh.triangles[i][k] >= vertices)
                throw InvalidArgument(format_message(mesh_label(mesh), ": triangles[", i,
                                                     "] indexes vertex ", mesh.triangles[i][k],
                                                     " but the mesh has ", vertices,
                                                     " vertices"));
    check_finite(mesh, "positions", mesh.positions);
    check_finite(mesh, "normals", mesh.normals);
    check_finite(mesh, "uv set '" + uv_set.name + "'", uv_set.coords);
    const double det = glm::determinant(glm::dmat3(mat3(world_from_object)));
    if (!is_finite(world_from_object) || det == 0.0)
        throw InvalidArgument(format_message(
            mesh_label(mesh), ": world_from_object is not finite or is singular (determinant ",
            det, "); apply a non-zero scale"));
}

// --- 2D geometry in texel space (u * width, v * height) -------------------------------------

double orient(const dvec2& a, const dvec2& b, const dvec2& p) {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// orient() evaluated with the edge's endpoints in a fixed (lexicographic) order and the sign
// fixed up afterwards: the two triangles sharing an edge then get exactly opposite values, so
// the tie rule below gives every position on the edge to exactly one of them.
double edge_function(const dvec2& a, const dvec2& b, const dvec2& p) {
    const bool ordered = a.x < b.x || (a.x == b.x && a.y < b.y);
    return ordered ? orient(a, b, p) : -orient(b, a, p);
}

// Tie rule for positions exactly on an edge: antisymmetric in the edge's direction, so of the
// two opposite directed edges exactly one wins (the "top-left" rule of GPU rasterizers).
bool owns_edge(const dvec2& a, const dvec2& b) {
    const dvec2 d = b - a;
    return d.y > 0.0 || (d.y == 0.0 && d.x < 0.0);
}

// A UV triangle in texel space, counter-clockwise; vertex k of the UV triangle is vertex
// corner[k] (0..2) of the mesh triangle (mirrored UV islands are wound clockwise).
struct UvTriangle {
    std::array<dvec2, 3> p;
    std::array<int, 3> corner;
};

// Edge functions of p against the three edges, in the order of the opposite vertices: e[k] is
// twice the area of the sub-triangle opposite vertex k (its unnormalised barycentric).
dvec3 edge_values(const UvTriangle& tri, const dvec2& p) {
    return dvec3(edge_function(tri.p[1], tri.p[2], p), edge_function(tri.p[2], tri.p[0], p),
                 edge_function(tri.p[0], tri.p[1], p));
}

bool contains(const UvTriangle& tri, const dvec2& p) {
    const dvec3 e = edge_values(tri, p);
    for (int k = 0; k < 3; ++k) {
        if (e[k] < 0.0) return false;
        if (e[k] == 0.0 && !owns_edge(tri.p[(k + 1) % 3], tri.p[(k + 2) % 3])) return false;
    }
    return true;
}

// A convex polygon of at most 7 vertices: a triangle clipped by the 4 sides of a square.
struct Polygon {
    std::array<dvec2, 8> v;
    int n = 0;
};

// Sutherland-Hodgman against one side of the unit square: keeps the part with
// sign * (coordinate `axis` - bound) <= 0.
Polygon clip(const Polygon& in, int axis, double bound, double sign) {
    Polygon out;
    for (int i = 0; i < in.n; ++i) {
        const dvec2& a = in.v[i];
        const dvec2& b = in.v[(i + 1) % in.n];
        const double da = sign * (a[axis] - bound), db = sign * (b[axis] - bound);
        if (da <= 0.0) out.v[out.n++] = a;
        if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0)) {
            dvec2 crossing = a + (b - a) * (da / (da - db));
            crossing[axis] = bound;  // exactly on the side, whatever the rounding
            out.v[out.n++] = crossing;
        }
    }
    return out;
}

// The triangle (already translated so the texel is [0, 1]^2) clipped to the texel.
Polygon clip_to_texel(const std::array<dvec2, 3>& local) {
    Polygon polygon;
    polygon.n = 3;
    std::copy(local.begin(), local.end(), polygon.v.begin());
    polygon = clip(polygon, 0, 0.0, -1.0);
    polygon = clip(polygon, 0, 1.0, 1.0);
    polygon = clip(polygon, 1, 0.0, -1.0);
    return clip(polygon, 1, 1.0, 1.0);
}

double area(const Polygon& polygon) {
    double twice = 0.0;
    for (int i = 0; i < polygon.n; ++i) {
        const dvec2& a = polygon.v[i];
        const dvec2& b = polygon.v[(i + 1) % polygon.n];
        twice += a.x * b.y - b.x * a.y;
    }
    return 0.5 * twice;
}

dvec2 closest_on_segment(const dvec2& a, const dvec2& b, const dvec2& p) {
    const dvec2 d = b - a;
    const double length2 = glm::dot(d, d);
    const double t = length2 > 0.0 ? std::clamp(glm::dot(p - a, d) / length2, 0.0, 1.0) : 0.0;
    return a + t * d;
}

// The point of a counter-clockwise convex polygon closest to p.
dvec2 closest_on_polygon(const Polygon& polygon, const dvec2& p) {
    bool inside = true;
    for (int i = 0; i < polygon.n; ++i)
        inside = inside && orient(polygon.v[i], polygon.v[(i + 1) % polygon.n], p) >= 0.0;
    if (inside) return p;
    dvec2 best = polygon.v[0];
    double best_distance2 = kInfinity;
    for (int i = 0; i < polygon.n; ++i) {
        const dvec2 q = closest_on_segment(polygon.v[i], polygon.v[(i + 1) % polygon.n], p);
        const double distance2 = glm::dot(q - p, q - p);
        if (distance2 < best_distance2) {
            best = q;
            best_distance2 = distance2;
        }
    }
    return best;
}

// --- one triangle --------------------------------------------------------------------------

// A mesh triangle in world space, its vertices in the UV triangle's vertex order.
struct WorldTriangle {
    std::array<dvec3, 3> position;
    std::array<vec3, 3> normal;  // world space, not normalised; unused without vertex normals
    std::array<int, 3> corner;   // the mesh triangle's corner of each vertex
    bool has_normals = false;
    vec3 geometric_normal;
    uint32_t triangle_id;
    float texel_size;
};

struct Fragment {
    uint64_t texel;
    TexelSample sample;
};

// What rasterizing one triangle produced, merged in triangle order afterwards.
struct TriangleResult {
    std::vector<Fragment> fragments;
    bool degenerate_uv = false, degenerate_world = false, clipped = false;
    uint64_t conservative_samples = 0;
};

TexelSample make_sample(const WorldTriangle& world, const dvec3& edges, const dvec2& p_texel,
                        const TexelRasterSettings& settings) {
    // Rounding can leave a conservative point a hair outside its triangle: clamp, renormalise.
    const dvec3 clamped = glm::max(edges, dvec3(0.0));
    const dvec3 b = clamped / (clamped.x + clamped.y + clamped.z);
    TexelSample sample;
    sample.position = vec3(b.x * world.position[0] + b.y * world.position[1] +
                           b.z * world.position[2]);
    sample.geometric_normal = world.geometric_normal;
    sample.normal = world.geometric_normal;
    if (world.has_normals) {
        const vec3 n = float(b.x) * world.normal[0] + float(b.y) * world.normal[1] +
                       float(b.z) * world.normal[2];
        const float length = glm::length(n);
        // Opposite vertex normals can cancel out; the face normal is then the best guess.
        if (length > 0.0f) sample.normal = n / length;
    }
    sample.ray_origin = offset_origin(sample.position, sample.geometric_normal);
    float mesh_order[3];
    for (int k = 0; k < 3; ++k) mesh_order[world.corner[k]] = float(b[k]);
    sample.barycentrics = vec2(mesh_order[1], mesh_order[2]);
    sample.uv = vec2(float(p_texel.x / settings.width), float(p_texel.y / settings.height));
    sample.triangle_id = world.triangle_id;
    sample.texel_size = world.texel_size;
    return sample;
}

// Samples of one texel (tx, ty) that the triangle overlaps with clipped area `area`.
void sample_texel(const UvTriangle& uv, const WorldTriangle& world, const Polygon& clipped,
                  double clipped_area, uint32_t tx, uint32_t ty,
                  const TexelRasterSettings& settings, TriangleResult& result) {
    const uint32_t n = settings.samples_per_axis;
    const uint64_t texel = uint64_t(ty) * settings.width + tx;
    const size_t first = result.fragments.size();
    for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i) {
            const dvec2 p(tx + (i + 0.5) / n, ty + (j + 0.5) / n);
            if (contains(uv, p))
                result.fragments.push_back(
                    {texel, make_sample(world, edge_values(uv, p), p, settings)});
        }
    if (result.fragments.size() == first) {
        // A sliver between the sample positions: one sample at its point nearest the centre.
        const dvec2 origin(tx, ty);
        const dvec2 p = origin + closest_on_polygon(clipped, dvec2(0.5));
        result.fragments.push_back({texel, make_sample(world, edge_values(uv, p), p, settings)});
        ++result.conservative_samples;
    }
    const float weight = float(clipped_area / double(result.fragments.size() - first));
    for (size_t k = first; k < result.fragments.size(); ++k)
        result.fragments[k].sample.weight = weight;
}

// Maps mesh normals to world space as Scene does (its cofactor times sign(det) is |det| times
// the inverse-transpose): under a mirroring transform the normal stays on the side the object's
// front faces, although the world-space winding turns clockwise.
mat3 normal_from_object(const mat4& world_from_object) {
    return glm::transpose(glm::inverse(mat3(world_from_object)));
}

bool is_degenerate(const UvTriangle& tri, double twice_area) {
    double longest2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        const dvec2 e = tri.p[(k + 1) % 3] - tri.p[k];
        longest2 = std::max(longest2, glm::dot(e, e));
    }
    return !(std::abs(twice_area) > kMinRelativeUvArea * longest2);
}

// The mesh triangle's UV triangle in texel space, counter-clockwise, and twice its area;
// twice_area is 0 for a degenerate (collapsed) UV triangle.
UvTriangle uv_triangle(const UvSet& uv_set, const uvec3& indices,
                       const TexelRasterSettings& settings, double* twice_area) {
    const dvec2 scale(settings.width, settings.height);
    UvTriangle uv{};
    for (int k = 0; k < 3; ++k) {
        uv.p[k] = dvec2(uv_set.coords[indices[k]]) * scale;
        uv.corner[k] = k;
    }
    *twice_area = orient(uv.p[0], uv.p[1], uv.p[2]);
    if (is_degenerate(uv, *twice_area)) {
        *twice_area = 0.0;
    } else if (*twice_area < 0.0) {  // mirrored UVs: make it counter-clockwise
        std::swap(uv.p[1], uv.p[2]);
        std::swap(uv.corner[1], uv.corner[2]);
        *twice_area = -*twice_area;
    }
    return uv;
}

// The mesh triangle in world space, in the UV triangle's vertex order; false when it has no
// area in world space (a mesh that did not go through validate_mesh).
bool world_triangle(const Mesh& mesh, const mat4& world_from_object,
                    const mat3& normals_to_world, uint32_t triangle_id, const UvTriangle& uv,
                    double uv_twice_area, WorldTriangle* world) {
    const uvec3& indices = mesh.triangles[triangle_id];
    for (int k = 0; k < 3; ++k) {
        const uint32_t vertex = indices[uv.corner[k]];
        world->corner[k] = uv.corner[k];
        world->position[k] = dvec3(world_from_object * vec4(mesh.positions[vertex], 1.0f));
        if (!mesh.normals.empty()) world->normal[k] = normals_to_world * mesh.normals[vertex];
    }
    world->has_normals = !mesh.normals.empty();
    // The face normal from the mesh's own winding (the UV triangle may have been reordered).
    const vec3 p0 = mesh.positions[indices.x];
    const vec3 face = normals_to_world *
                      glm::cross(mesh.positions[indices.y] - p0, mesh.positions[indices.z] - p0);
    const double area = 0.5 * glm::length(glm::cross(world->position[1] - world->position[0],
                                                     world->position[2] - world->position[0]));
    if (!(glm::length(face) > 0.0f) || !(area > 0.0)) return false;
    world->geometric_normal = glm::normalize(face);
    world->triangle_id = triangle_id;
    world->texel_size = float(std::sqrt(area / (0.5 * uv_twice_area)));
    return true;
}

TriangleResult rasterize_triangle(const Mesh& mesh, const UvSet& uv_set,
                                  const mat4& world_from_object, const mat3& normals_to_world,
                                  uint32_t triangle_id, const TexelRasterSettings& settings,
                                  RowProgress& rows) {
    TriangleResult result;
    double twice_area = 0.0;
    const UvTriangle uv = uv_triangle(uv_set, mesh.triangles[triangle_id], settings, &twice_area);
    if (twice_area == 0.0) {
        result.degenerate_uv = true;
        return result;
    }
    WorldTriangle world{};
    if (!world_triangle(mesh, world_from_object, normals_to_world, triangle_id, uv, twice_area,
                        &world)) {
        result.degenerate_world = true;
        return result;
    }

    // Texels whose squares overlap the triangle's bounding box, clamped to the grid.
    const dvec2 grid(settings.width, settings.height);
    dvec2 lower = glm::min(uv.p[0], glm::min(uv.p[1], uv.p[2]));
    dvec2 upper = glm::max(uv.p[0], glm::max(uv.p[1], uv.p[2]));
    result.clipped = lower.x < 0.0 || lower.y < 0.0 || upper.x > grid.x || upper.y > grid.y;
    lower = glm::max(glm::floor(lower), dvec2(0.0));
    upper = glm::min(glm::ceil(upper), grid);
    for (double ty = lower.y; ty < upper.y; ++ty) {
        rows.advance(uint64_t(std::max(upper.x - lower.x, 0.0)));
        for (double tx = lower.x; tx < upper.x; ++tx) {
            const dvec2 origin(tx, ty);
            const Polygon clipped =
                clip_to_texel({uv.p[0] - origin, uv.p[1] - origin, uv.p[2] - origin});
            const double clipped_area = area(clipped);
            if (clipped_area > kMinClippedArea)
                sample_texel(uv, world, clipped, clipped_area, uint32_t(tx), uint32_t(ty),
                             settings, result);
        }
    }
    return result;
}

// A corner's identity for chart building: the bits of its position and lightmap UV (with -0
// made +0, so the two zeros match).
struct CornerKey {
    std::array<uint32_t, 5> bits;
    bool operator==(const CornerKey& other) const { return bits == other.bits; }
};
struct CornerKeyHash {
    size_t operator()(const CornerKey& key) const {
        uint64_t h = 0x9e3779b97f4a7c15ull;
        for (uint32_t b : key.bits) h = (h ^ b) * 0x100000001b3ull;
        return size_t(h ^ (h >> 29));
    }
};
uint32_t float_bits(float value) {
    value += 0.0f;
    uint32_t bits;
    std::memcpy(&bits, &value, sizeof bits);
    return bits;
}

// The chart of every triangle (see TexelMap::chart), by union-find over shared corners.
std::vector<uint32_t> triangle_charts(const Mesh& mesh, const UvSet& uv_set, uint32_t* count,
                                      const Progress* progress) {
    const size_t n = mesh.triangles.size();
    std::vector<uint32_t> parent(n);
    std::iota(parent.begin(), parent.end(), 0u);
    auto find = [&](uint32_t t) {
        while (parent[t] != t) t = parent[t] = parent[parent[t]];
        return t;
    };
    std::unordered_map<CornerKey, uint32_t, CornerKeyHash> first_triangle;
    first_triangle.reserve(mesh.positions.size());
    for (uint32_t t = 0; t < n; ++t)
        for (int k = 0; k < 3; ++k) {
            if (k == 0 && (t & 0xffffu) == 0) throw_if_cancelled(progress);
            const uint32_t v = mesh.triangles[t][k];
            const vec3& p = mesh.positions[v];
            const vec2& uv = uv_set.coords[v];
            const CornerKey key{{float_bits(p.x), float_bits(p.y), float_bits(p.z),
                                 float_bits(uv.x), float_bits(uv.y)}};
            const auto [it, inserted] = first_triangle.emplace(key, t);
            if (inserted) continue;
            const uint32_t a = find(it->second), b = find(t);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the root is the lowest id
        }
    std::vector<uint32_t> chart(n), label(n, kInvalidId);
    uint32_t next = 0;
    for (uint32_t t = 0; t < n; ++t) {
        const uint32_t root = find(t);
        if (label[root] == kInvalidId) label[root] = next++;
        chart[t] = label[root];
    }
    *count = next;
    return chart;
}

// Sorts the fragments into texels (stable: by triangle, then stratum) and sums the coverage.
TexelMap gather(std::vector<TriangleResult>& results, const TexelRasterSettings& settings,
                const std::vector<uint32_t>& charts, Progress* progress) {
    TexelMap map;
    map.width = settings.width;
    map.height = settings.height;
    const uint64_t texels = map.texel_count();
    map.sample_offsets.assign(texels + 1, 0);
    for (const TriangleResult& result : results)
        for (const Fragment& fragment : result.fragments) ++map.sample_offsets[fragment.texel + 1];
    throw_if_cancelled(progress);
    for (uint64_t t = 0; t < texels; ++t) map.sample_offsets[t + 1] += map.sample_offsets[t];
    throw_if_cancelled(progress);
    map.samples.resize(map.sample_offsets[texels]);
    std::vector<uint64_t> next(map.sample_offsets.begin(), map.sample_offsets.end() - 1);
    uint64_t moved = 0;
    for (TriangleResult& result : results) {
        if (progress && (moved += result.fragments.size() + 1) >= kTexelsPerSlice) {
            moved = 0;
            progress->throw_if_cancelled();
        }
        for (Fragment& fragment : result.fragments)
            map.samples[next[fragment.texel]++] = fragment.sample;
        result.fragments = {};  // release as we go: keeps the peak near one copy of the samples
    }

    map.coverage.assign(texels, 0.0f);
    map.chart.assign(texels, kInvalidId);
    for (uint64_t t = 0; t < texels; ++t) {
        if ((t & (kTexelsPerSlice - 1)) == 0 && progress) {
            progress->throw_if_cancelled();
            progress->report(t, texels);
        }
        double sum = 0.0;
        float heaviest = -1.0f;
        for (const TexelSample* s = map.samples_begin(t); s != map.samples_end(t); ++s) {
            sum += s->weight;
            if (s->weight > heaviest) {
                heaviest = s->weight;
                map.chart[t] = charts[s->triangle_id];
            }
        }
        map.coverage[t] = float(std::min(sum, 1.0));
        if (sum > 1.0 + kOverlapTolerance) ++map.report.overlapping_texels;
    }
    return map;
}


// What rasterize_texels will hold, estimated before anything is allocated.
struct RasterEstimate {
    double uv_area = 0.0;      // sum of the UV triangles' areas in texels, each clamped to grid
    uint64_t samples = 0;      // expected samples: uv_area * samples_per_axis^2 + 1 a triangle
    uint64_t box_texels = 0;   // texels of the triangles' bounding boxes (the work, for progress)
    uint64_t bytes = 0;        // peak bytes
};

RasterEstimate estimate_raster(const Mesh& mesh, const UvSet& uv_set,
                               const TexelRasterSettings& settings) {
    RasterEstimate estimate;
    const dvec2 grid(settings.width, settings.height);
    const double grid_area = grid.x * grid.y;
    const uint64_t per_texel = uint64_t(settings.samples_per_axis) * settings.samples_per_axis;
    double samples = 0.0;
    for (const uvec3& indices : mesh.triangles) {
        double twice_area = 0.0;
        const UvTriangle uv = uv_triangle(uv_set, indices, settings, &twice_area);
        if (twice_area == 0.0) continue;
        const double area = std::min(0.5 * twice_area, grid_area);
        estimate.uv_area += area;
        samples += area * double(per_texel) + 1.0;
        const dvec2 lower = glm::max(glm::floor(glm::min(uv.p[0], glm::min(uv.p[1], uv.p[2]))),
                                     dvec2(0.0));
        const dvec2 upper = glm::min(glm::ceil(glm::max(uv.p[0], glm::max(uv.p[1], uv.p[2]))),
                                     grid);
        if (upper.x > lower.x && upper.y > lower.y)
            estimate.box_texels += uint64_t((upper.x - lower.x) * (upper.y - lower.y));
    }
    estimate.box_texels = std::max<uint64_t>(estimate.box_texels, 1);
    estimate.samples = samples >= 1.8e19 ? UINT64_MAX : uint64_t(samples);
    // Per texel: sample_offsets and gather's cursor (8 + 8), coverage and chart (4 + 4). Per
    // sample: its Fragment while rasterizing and its TexelSample in the map, both held while
    // gathering. Per triangle: its TriangleResult and chart.
    const uint64_t texels = uint64_t(settings.width) * settings.height;
    estimate.bytes = saturating_add(
        saturating_mul(texels, 24),
        saturating_add(saturating_mul(estimate.samples, sizeof(Fragment) + sizeof(TexelSample)),
                       saturating_mul(mesh.triangles.size(), sizeof(TriangleResult) + 8)));
    return estimate;
}

void require_raster_memory(const Mesh& mesh, const TexelRasterSettings& settings,
                           const RasterEstimate& estimate) {
    const uint32_t n = settings.samples_per_axis;
    const double grid_area = double(settings.width) * double(settings.height);
    require_memory(
        estimate.bytes,
        format_message("TexelRasterSettings.width x height = ", settings.width, " x ",
                       settings.height, " with ", n * n, " samples per texel (samples_per_axis = ",
                       n, "; the UV triangles of ", mesh_label(mesh), " cover ",
                       100.0 * estimate.uv_area / grid_area, "% of the lightmap: about ",
                       estimate.samples, " samples of ", sizeof(Fragment) + sizeof(TexelSample),
                       " bytes while rasterizing)"),
        "lower the resolution (width, height) or samples_per_axis, or bake in tiles");
}

}  // namespace

void check_lightmap_side(const char* what, uint32_t side) {
    if (side < 1 || side > kMaxLightmapResolution)
        throw InvalidArgument(format_message(what, " = ", side, " is outside [1, ",
                                             kMaxLightmapResolution,
                                             "]; bake larger lightmaps in tiles"));
}

TexelMap rasterize_texels(const Mesh& mesh, const mat4& world_from_object,
                          const TexelRasterSettings& settings, Progress* progress) {
    check_settings(settings);
    const UvSet& uv_set = find_uv_set(mesh, settings.uv_set);
    check_mesh(mesh, uv_set, world_from_object);
    const mat3 normals_to_world = normal_from_object(world_from_object);
    const RasterEstimate estimate = estimate_raster(mesh, uv_set, settings);
    require_raster_memory(mesh, settings, estimate);

    // Triangles in parallel, each into its own result: the merge in triangle order makes the
    // map independent of the thread count.
    if (progress) progress->begin_stage("rasterizing texels", 0.0f, 0.8f);
    RowProgress rows(progress, estimate.box_texels);
    std::vector<TriangleResult> results(mesh.triangles.size());
    parallel_for(0, mesh.triangles.size(), kTrianglesPerChunk,
                 [&](uint64_t begin, uint64_t end) {
                     throw_if_cancelled(progress);
                     for (uint64_t t = begin; t < end; ++t)
                         results[t] =
                             rasterize_triangle(mesh, uv_set, world_from_object,
                                                normals_to_world, uint32_t(t), settings, rows);
                 });

    TexelRasterReport report;
    report.triangles = mesh.triangles.size();
    for (const TriangleResult& result : results) {
        report.degenerate_uv += result.degenerate_uv;
        report.degenerate_world += result.degenerate_world;
        report.clipped_triangles += result.clipped;
        report.conservative_samples += result.conservative_samples;
    }
    uint32_t chart_count = 0;
    if (progress) progress->begin_stage("gathering texel samples", 0.8f, 1.0f);
    const std::vector<uint32_t> charts = triangle_charts(mesh, uv_set, &chart_count, progress);
    TexelMap map = gather(results, settings, charts, progress);
    if (progress) progress->report(1, 1);
    map.chart_count = chart_count;
    report.overlapping_texels = map.report.overlapping_texels;
    map.report = report;
    return map;
}

TexelMap rasterize_texels(const Scene& scene, uint32_t instance_id,
                          const TexelRasterSettings& settings, Progress* progress) {
    if (instance_id >= scene.instances().size())
        throw InvalidArgument(format_message("rasterize_texels: instance_id = ", instance_id,
                                             " but the scene has ", scene.instances().size(),
                                             " instances"));
    const Instance& instance = scene.instances()[instance_id];
    TexelMap map;
    try {
        map = rasterize_texels(scene.meshes()[instance.mesh_id], instance.world_from_object,
                               settings, progress);
    } catch (const InvalidArgument& error) {
        // The artist knows the object (instance) name better than its mesh data's name.
        const std::string object = instance.name.empty()
                                       ? format_message("instance #", instance_id)
                                       : "instance '" + instance.name + "'";
        throw InvalidArgument(object + ": " + error.what());
    }
    map.instance_id = instance_id;
    map.scene_uid = scene.uid();
    map.mesh_id = instance.mesh_id;
    map.mesh_revision = scene.mesh_revision(instance.mesh_id);
    map.world_from_object = instance.world_from_object;
    return map;
}

void check_texel_map(const Scene& scene, const TexelMap& map, const char* operation) {
    const char* again = "; call rasterize_texels(scene, instance_id, settings) again for the "
                        "scene as it is now";
    if (map.scene_uid == 0 || map.instance_id == kInvalidId)
        throw InvalidArgument(format_message(operation, ": the texel map was rasterized from a "
                                             "bare mesh, not from an instance of this scene",
                                             again));
    if (map.scene_uid != scene.uid())
        throw InvalidArgument(format_message(operation, ": the texel map was made for another "
                                             "scene (of instance ", map.instance_id, ")",
                                             again));
    if (map.instance_id >= scene.instances().size())
        throw InvalidArgument(format_message(
            operation, ": the texel map is of instance ", map.instance_id, " but the scene has ",
            scene.instances().size(), " instances", again));
    const Instance& instance = scene.instances()[map.instance_id];
    const std::string object = instance.name.empty()
                                   ? format_message("instance ", map.instance_id)
                                   : format_message("instance ", map.instance_id, " '",
                                                    instance.name, "'");
    if (instance.mesh_id != map.mesh_id || scene.mesh_revision(map.mesh_id) != map.mesh_revision)
        throw InvalidArgument(format_message(
            operation, ": the texel map was made before the mesh of ", object,
            " changed (set_mesh)", again));
    if (instance.world_from_object != map.world_from_object)
        throw InvalidArgument(format_message(
            operation, ": the texel map was made before ", object,
            " moved (set_instance_transform changed its world_from_object)", again));
}

}  // namespace shgi
