#include "scene/scene.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <new>
#include <tuple>
#include <type_traits>

#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

#include "scene/embree_scene.h"
#include "scene/validation.h"
#include "util/error.h"
#include "util/log.h"
#include "util/memory.h"
#include "util/parallel.h"

namespace shgi {
namespace {

using namespace scene_detail;

// add_material runs before textures may have been added; commit() checks the real count.
constexpr uint32_t kAnyTextureCount = std::numeric_limits<uint32_t>::max();

// CommitSettings::memory_budget_bytes = 0 leaves a quarter of what the process may still
// allocate (util/memory.h) to Blender and the rest of SHGI; an explicit budget is capped by it.
constexpr double kDefaultBudgetFraction = 0.75;

uint64_t resolve_budget(uint64_t requested) {
    const MemoryLimits limits = memory_limits();
    if (requested > 0) return std::min(requested, limits.allowed());
    const uint64_t allowed = limits.allowed();
    return allowed == std::numeric_limits<uint64_t>::max()
               ? allowed
               : uint64_t(double(allowed) * kDefaultBudgetFraction);
}

std::string instance_label(const std::vector<Instance>& instances, size_t i) {
    const std::string& name = instances[i].name;
    return name.empty() ? format_message("instance ", i)
                        : format_message("instance ", i, " '", name, "'");
}

// `name` is a const char* so that the per-ray call of a valid ray builds no string.
void check_ray(const Ray& ray, const char* name, const RayLimits& limits,
               const std::string& limit_reason) {
    if (is_valid_ray(ray, limits)) return;  // branch-free; ray_problem only to name the fault
    bool out_of_range = false;
    const char* problem = ray_problem(ray, limits, &out_of_range);
    const std::string shortest =
        limits.min_direction > 0.0f
            ? format_message(", the largest above ", limits.min_direction)
            : std::string();
    const std::string range =
        out_of_range ? format_message("; this scene traces origins up to ", limits.origin,
                                      " and directions up to ", limits.direction,
                                      " per component", shortest, limit_reason)
                     : std::string();
    throw InvalidArgument(format_message(name, ": ", problem, " (origin ", to_string(ray.origin),
                                         ", direction ", to_string(ray.direction), ", tmin ",
                                         ray.tmin, ", tmax ", ray.tmax, ")", range));
}

// Validates every ray before any is traced, so the message names the first bad one whatever
// the chunking.
void check_rays(const std::vector<Ray>& rays, const RayLimits& limits,
                const std::string& limit_reason) {
    // The first invalid ray, found four rays at a time; check_ray then names its problem.
    const size_t i = first_invalid_ray(rays.data(), rays.size(), limits);
    if (i < rays.size())
        check_ray(rays[i], format_message("rays[", i, "]").c_str(), limits, limit_reason);
}

// Embree's float triangle test (the Pluecker test of RTC_SCENE_FLAG_ROBUST) in a mesh's own
// coordinates, for a ray (o, d) there and a triangle with vertices v_k and edges e_k: the edge
// tests dot(cross(v_i + v_j - 2o, e_k), d) sum to at most 6 P L |d|, the normal
// Ng = 2 cross(e_i, e_j) is at most 2 L^2, den = dot(Ng, d) at most 2 L^2 |d| and
// T = dot(v_0 - o, Ng) at most 2 P L^2 (Cauchy-Schwarz; L the mesh's longest edge, P the largest
// |v - o|); the hit distance T / den is the world distance to the hit over |d|. Past float's
// 3.4e38 these overflow to inf: hits at t = inf, or misses. Each is kept below this bound.
constexpr double kTriangleTestBound = std::numeric_limits<float>::max() / 4.0;
constexpr double kSqrt3 = 1.7320508075688772;
// Direction components the triangle-test limits always leave (those of a unit direction, with
// room to spare), where they lower the origins' limit instead.
constexpr double kShortDirections = 2.0;

// What lowered one of the scene's ray limits.
enum class RayLimitCause { None, Magnification, TriangleTest };

struct RayLimit {
    double value = kMaxRayComponent;
    RayLimitCause cause = RayLimitCause::None;
    size_t instance = 0;

    void lower(double to, RayLimitCause why, size_t i) {
        if (to >= value) return;
        value = to;
        cause = why;
        instance = i;
    }
    bool same_cause(const RayLimit& other) const {
        return cause == other.cause && instance == other.instance;
    }
};

// One instance as its object-space ray sees it: A = M^-1 (M the linear part of
// world_from_object, t its translation) maps a world ray to (A (o - t), A d).
struct InstanceRange {
    double magnification;  // max_j sum_k |A_jk|: |(A x)_j| <= magnification * max_k |x_k|
    double stretch;        // >= the spectral norm of A: |A x| <= stretch |x|
    double reach;          // max_k |t_k|
    double longest_edge;   // of its mesh, object space (MeshReport)
};

// The largest row sum of |m|: |(m x)_j| <= inf_norm(m) max_k |x_k|.
double inf_norm(const glm::dmat3& m) {
    double norm = 0.0;
    for (int row = 0; row < 3; ++row)
        norm = std::max(norm, std::fabs(m[0][row]) + std::fabs(m[1][row]) + std::fabs(m[2][row]));
    return norm;
}

// An upper bound on the spectral norm of m: |m|_2^2 is the largest eigenvalue of X = m^T m, at
// most |X^16|_inf^(1/16): within 3^(1/32) (3.5%) of it, and exact for rotations and axis scales.
double spectral_bound(const glm::dmat3& m) {
    glm::dmat3 power = glm::transpose(m) * m;
    // X^(2^k) = (scale * norm)^(2^k) * (power / norm), renormalised at each squaring.
    double scale = 1.0;
    for (int squaring = 0; squaring <= 4; ++squaring) {
        const double norm = inf_norm(power);
        if (!(norm > 0.0) || !std::isfinite(norm)) break;
        scale *= std::pow(norm, 1.0 / double(1 << squaring));
        if (squaring == 4) return std::sqrt(scale);
        power /= norm;
        power = power * power;
    }
    return std::numeric_limits<double>::max();
}

InstanceRange instance_range(const Instance& instance, const MeshReport& report) {
    const glm::dmat4 transform(instance.world_from_object);
    const glm::dmat3 inverse = glm::inverse(glm::dmat3(transform));
    InstanceRange range{inf_norm(inverse), 0.0, 0.0, report.longest_edge};
    if (!std::isfinite(range.magnification))
        range.magnification = std::numeric_limits<double>::max();
    range.stretch = spectral_bound(inverse);
    range.reach = std::max({std::fabs(transform[3].x), std::fabs(transform[3].y),
                            std::fabs(transform[3].z)});
    return range;
}

// A flattened instance as Embree sees it: world-space triangles and untransformed rays, its
// edges up to |M|_2 times the mesh's longest.
InstanceRange flattened_range(const Instance& instance, const MeshReport& report) {
    const double scale = spectral_bound(glm::dmat3(glm::dmat4(instance.world_from_object)));
    return InstanceRange{1.0, 1.0, 0.0, scale * report.longest_edge};
}

// The scene's ray limits, and what set them.
struct SceneRayLimits {
    RayLimit origin, direction;
    double min_direction = 0.0;
    RayLimit embree_origin, embree_direction;  // Embree's range alone (cause Magnification)
    double depth_origin = 0.0;     // the origins' limit after the depth tests
    double first_direction = 0.0;  // the directions' limit before the edge tests from origins
};

// Embree maps a ray into an instance's object space and checks it against its range again
// (kMaxRayComponent): origins within kMaxRayComponent / magnification - reach and directions
// within kMaxRayComponent / magnification stay in range. Its triangle test (above) then bounds
// origins and directions jointly: with |o - w| <= |o| + world_reach for any world vertex w, an
// origin of component limit O and a direction of component limit D give, in the mesh's
// coordinates, P <= stretch (sqrt(3) O + world_reach) and |d| <= stretch sqrt(3) D. The
// shortest direction keeps hit distances from origins within the limit finite. Instances of
// meshes without triangles (longest_edge 0: the triangles validate_mesh keeps have non-zero
// area) are not in Embree's scene and do not count.
SceneRayLimits ray_limits_of(const std::vector<Instance>& instances,
                             const std::vector<MeshReport>& reports, double world_reach) {
    std::vector<std::tuple<size_t, InstanceRange, RayLimitCause>> ranges;
    for (size_t i = 0; i < instances.size(); ++i) {
        const MeshReport& report = reports[instances[i].mesh_id];
        if (report.longest_edge > 0.0)
            ranges.emplace_back(i, instance_range(instances[i], report),
                                RayLimitCause::TriangleTest);
    }
    SceneRayLimits result;
    for (const auto& [i, r, cause] : ranges) {
        result.embree_origin.lower(kMaxRayComponent / r.magnification - r.reach,
                                   RayLimitCause::Magnification, i);
        result.embree_direction.lower(kMaxRayComponent / r.magnification,
                                      RayLimitCause::Magnification, i);
    }
    // Origins: Embree's range and the depth test, which do not depend on the direction.
    RayLimit origin = result.embree_origin;
    for (const auto& [i, r, cause] : ranges) {
        const double depth_test = kTriangleTestBound / (2.0 * r.longest_edge * r.longest_edge);
        origin.lower((depth_test / r.stretch - world_reach) / kSqrt3, cause, i);
    }
    // Directions: Embree's range, den, and the edge tests from those origins; but never below
    // kShortDirections, in which case the edge tests lower the origins instead (a camera or a
    // light outside the scene's geometry needs origins beyond its extent more than any ray
    // needs a long direction).
    result.depth_origin = origin.value;
    result.direction = result.embree_direction;
    for (const auto& [i, r, cause] : ranges)
        result.direction.lower(kTriangleTestBound /
                                   (2.0 * r.longest_edge * r.longest_edge * r.stretch * kSqrt3),
                               cause, i);
    result.first_direction = result.direction.value;
    RayLimit from_origins = result.direction;
    for (const auto& [i, r, cause] : ranges) {
        const double p = r.stretch * (kSqrt3 * std::max(origin.value, 0.0) + world_reach);
        from_origins.lower(kTriangleTestBound / (6.0 * p * r.longest_edge * r.stretch * kSqrt3),
                           cause, i);
    }
    if (from_origins.value >= kShortDirections)
        result.direction = from_origins;
    else
        result.direction.lower(kShortDirections, from_origins.cause,
                               from_origins.instance);
    // Origins whose edge tests pass with directions up to that.
    for (const auto& [i, r, cause] : ranges) {
        const double edge_tests = kTriangleTestBound / (6.0 * r.longest_edge * r.stretch *
                                                        kSqrt3 * result.direction.value);
        origin.lower((edge_tests / r.stretch - world_reach) / kSqrt3, cause, i);
    }
    result.origin = origin;
    result.origin.value = std::max(result.origin.value, 0.0);
    result.min_direction = (kSqrt3 * result.origin.value + world_reach) / kTriangleTestBound;
    return result;
}

// Whether flattening an instance (flattened_range: its triangles in world space, rays not
// transformed) would lower `limits`, which the scene's instanced meshes set: each of
// ray_limits_of's stages for this range alone, against the value that stage reached. Only an
// instance that enlarges its mesh can; it then stays instanced, so flattening never narrows the
// rays a scene traces.
bool lowers_limits(const InstanceRange& r, const SceneRayLimits& limits, double world_reach) {
    const double edge = r.longest_edge;
    const double depth_test = kTriangleTestBound / (2.0 * edge * edge);
    if ((depth_test - world_reach) / kSqrt3 < limits.depth_origin) return true;
    if (kTriangleTestBound / (2.0 * edge * edge * kSqrt3) < limits.first_direction) return true;
    const double p = kSqrt3 * std::max(limits.depth_origin, 0.0) + world_reach;
    const double from_origins = kTriangleTestBound / (6.0 * p * edge * kSqrt3);
    if (from_origins < std::max(limits.direction.value, kShortDirections)) return true;
    const double edge_tests =
        kTriangleTestBound / (6.0 * edge * kSqrt3 * limits.direction.value);
    return (edge_tests - world_reach) / kSqrt3 < limits.origin.value;
}

// Why `limit` is below Embree's own range, for messages.
std::string ray_limit_cause(const RayLimit& limit, const std::vector<Instance>& instances,
                            const std::vector<MeshReport>& reports) {
    if (limit.cause == RayLimitCause::None) return std::string();
    const Instance& instance = instances[limit.instance];
    const std::string label = instance_label(instances, limit.instance);
    if (limit.cause == RayLimitCause::Magnification)
        return format_message(label, " shrinks its mesh by up to ",
                              instance_range(instance, reports[instance.mesh_id]).magnification,
                              "x, and Embree's range of ", kMaxRayComponent,
                              " applies in the mesh's coordinates");
    return format_message(label, "'s mesh has triangle edges up to ",
                          reports[instance.mesh_id].longest_edge,
                          " m in its own coordinates, where Embree's triangle test in float "
                          "overflows for rays from farther away or longer");
}

// det(M) * M^-T, whose columns are cross products of M's columns; times sign(det) so that a
// mirroring transform keeps the front side (see scene.h, "Normals").
mat3 normal_matrix(const mat4& world_from_object) {
    const mat3 m(world_from_object);
    const mat3 cofactor(glm::cross(m[1], m[2]), glm::cross(m[2], m[0]), glm::cross(m[0], m[1]));
    return glm::determinant(m) < 0.0f ? -cofactor : cofactor;
}

Bounds3 instance_bounds(const Mesh& mesh, const mat4& world_from_object) {
    Bounds3 bounds;
    if (mesh.triangles.empty()) return bounds;
    for (const vec3& p : mesh.positions) bounds.extend(vec3(world_from_object * vec4(p, 1.0f)));
    return bounds;
}

// The UV set named `name` on a mesh with at least one set, else the first (as Blender's Image
// Texture without a UV Map node uses the active render UV map, which the exporter puts first).
const UvSet& named_uv_set(const Mesh& mesh, const std::string& name) {
    if (!name.empty())
        for (const UvSet& set : mesh.uv_sets)
            if (set.name == name) return set;
    return mesh.uv_sets.front();
}

vec2 interpolate_uv(const UvSet& set, const uvec3& tri, float b0, float b1, float b2) {
    return b0 * set.coords[tri.x] + b1 * set.coords[tri.y] + b2 * set.coords[tri.z];
}

// Scene::bounding_radius of non-empty bounds.
float radius_of(const Bounds3& bounds) {
    return std::max(0.5f * glm::length(bounds.extent()), 1e-3f);
}

}  // namespace

uint64_t Scene::next_uid() {
    static std::atomic<uint64_t> counter{0};
    return counter.fetch_add(1, std::memory_order_relaxed) + 1;
}

uint64_t Scene::mesh_revision(uint32_t mesh_id) const {
    if (mesh_id >= mesh_revisions_.size())
        throw InvalidArgument(format_message("mesh_revision: mesh_id = ", mesh_id,
                                             " but the scene has ", meshes_.size(), " meshes"));
    return mesh_revisions_[mesh_id];
}

Scene::Scene() = default;
Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

void Scene::invalidate() {
    committed_ = false;
    ++revision_;
}

namespace {

// A mesh whose tangents were dropped renders those triangles without their normal map.
void warn_dropped_tangents(const Mesh& mesh, const MeshReport& report) {
    if (report.dropped_tangents > 0)
        log_warning(scene_detail::label("mesh", mesh.name), ": ", report.dropped_tangents, " of ",
                    mesh.tangents.size(),
                    " tangents are NaN, infinite or zero; the triangles using them are shaded "
                    "without their normal map (recompute the tangents from a valid UV map)");
}

}  // namespace

uint32_t Scene::add_mesh(Mesh mesh) {
    MeshReport report = validate_mesh(mesh, kAnyMaterialCount);
    warn_dropped_tangents(mesh, report);
    meshes_.push_back(std::move(mesh));
    mesh_reports_.push_back(report);
    geometry_dirty_ = true;
    invalidate();
    mesh_revisions_.push_back(revision_);
    return static_cast<uint32_t>(meshes_.size() - 1);
}

void Scene::set_mesh(uint32_t mesh_id, Mesh mesh) {
    if (mesh_id >= meshes_.size())
        throw InvalidArgument(format_message("set_mesh: mesh_id = ", mesh_id, " but the scene has ",
                                             meshes_.size(), " meshes; add_mesh() adds a new one"));
    // Validated before anything changes, so a rejected mesh leaves the scene as it was.
    const MeshReport report = validate_mesh(mesh, kAnyMaterialCount);
    warn_dropped_tangents(mesh, report);
    meshes_[mesh_id] = std::move(mesh);
    mesh_reports_[mesh_id] = report;
    geometry_dirty_ = true;
    invalidate();
    mesh_revisions_[mesh_id] = revision_;
}

uint32_t Scene::add_instance(uint32_t mesh_id, const mat4& world_from_object, std::string name) {
    const std::string item = name.empty() ? format_message("instance ", instances_.size())
                                          : format_message("instance '", name, "'");
    if (mesh_id >= meshes_.size())
        throw InvalidArgument(format_message(item, ": mesh_id = ", mesh_id, " but the scene has ",
                                             meshes_.size(), " meshes; add the mesh first"));
    require_transform(item, "world_from_object", world_from_object);
    instances_.push_back(Instance{std::move(name), mesh_id, world_from_object});
    instances_dirty_ = true;
    invalidate();
    return static_cast<uint32_t>(instances_.size() - 1);
}

uint32_t Scene::add_material(Material material) {
    validate_material(material, kAnyTextureCount);
    materials_.push_back(std::move(material));
    invalidate();
    return static_cast<uint32_t>(materials_.size() - 1);
}

uint32_t Scene::add_texture(Texture texture) {
    validate_texture(texture);
    textures_.push_back(std::move(texture));
    invalidate();
    return static_cast<uint32_t>(textures_.size() - 1);
}

void Scene::set_light(uint32_t light_id, Light light) {
    if (light_id >= lights_.size())
        throw InvalidArgument(format_message("set_light: light_id = ", light_id,
                                             " but the scene has ", lights_.size(), " lights"));
    validate_light(light);
    lights_[light_id] = std::move(light);
    invalidate();
}

void Scene::set_lights(std::vector<Light> lights) {
    for (const Light& light : lights) validate_light(light);
    lights_ = std::move(lights);
    invalidate();
}

void Scene::set_material(uint32_t material_id, Material material) {
    if (material_id >= materials_.size())
        throw InvalidArgument(format_message("set_material: material_id = ", material_id,
                                             " but the scene has ", materials_.size(),
                                             " materials"));
    validate_material(material, kAnyTextureCount);
    materials_[material_id] = std::move(material);
    invalidate();
}

void Scene::set_texture(uint32_t texture_id, Texture texture) {
    if (texture_id >= textures_.size())
        throw InvalidArgument(format_message("set_texture: texture_id = ", texture_id,
                                             " but the scene has ", textures_.size(),
                                             " textures"));
    validate_texture(texture);
    textures_[texture_id] = std::move(texture);
    invalidate();
}

uint32_t Scene::add_light(Light light) {
    validate_light(light);
    lights_.push_back(std::move(light));
    invalidate();
    return static_cast<uint32_t>(lights_.size() - 1);
}

void Scene::set_world(const World& world) {
    validate_world(world);
    world_ = world;
    invalidate();
}

void Scene::set_camera(const Camera& camera) {
    validate_camera(camera);
    camera_ = camera;
    has_camera_ = true;
    invalidate();
}

void Scene::set_instance_transform(uint32_t instance_id, const mat4& world_from_object) {
    if (instance_id >= instances_.size())
        throw InvalidArgument(format_message("set_instance_transform: instance_id = ",
                                             instance_id, " but the scene has ",
                                             instances_.size(), " instances"));
    require_transform(instance_label(instances_, instance_id), "world_from_object",
                      world_from_object);
    instances_[instance_id].world_from_object = world_from_object;
    moved_.push_back(instance_id);  // the per-mesh BVHs stay: only the top level changes
    // A scene whose objects move (a viewport) instances every mesh from now on, as Cycles keeps
    // a dynamic BVH in its viewport: a move then rebuilds the small top level over instances,
    // not one over every flattened triangle (250 ms with the 502k-triangle bench sphere).
    moving_ = true;
    invalidate();
}

const Camera& Scene::camera() const {
    if (!has_camera_)
        throw InvalidArgument("the scene has no camera; call set_camera() first");
    return camera_;
}

void Scene::check_references() {
    if (materials_.empty()) materials_.push_back(Material{});
    const auto material_count = static_cast<uint32_t>(materials_.size());
    for (const Material& material : materials_)
        validate_material(material, static_cast<uint32_t>(textures_.size()));
    for (const Mesh& mesh : meshes_) check_material_indices(mesh, material_count);
}

// Tangent-space normal maps need tangents and UVs, bump maps UVs; a mesh without them is shaded
// with its interpolated normals, and the artist is told which mesh and material.
void Scene::warn_missing_tangent_frames() const {
    const auto tangent_mapped = [](const Material& material) {
        return material.normal_texture != kNoTexture &&
               material.normal_space == NormalMapSpace::Tangent;
    };
    const auto bumped = [](const Material& material) {
        return material.bump_texture != kNoTexture;
    };
    if (std::none_of(materials_.begin(), materials_.end(), tangent_mapped) &&
        std::none_of(materials_.begin(), materials_.end(), bumped))
        return;
    for (const Mesh& mesh : meshes_) {
        if (!mesh.tangents.empty() && !mesh.uv_sets.empty()) continue;
        std::vector<uint8_t> used(materials_.size(), 0);
        if (mesh.material_indices.empty()) used[0] = 1;
        for (uint32_t index : mesh.material_indices) used[index] = 1;
        for (size_t m = 0; m < materials_.size(); ++m) {
            const Material& material = materials_[m];
            if (!used[m]) continue;
            if (tangent_mapped(material))
                log_warning(scene_detail::label("mesh", mesh.name), ": material '", material.name,
                            "' has a tangent-space normal map but the mesh has no ",
                            mesh.uv_sets.empty() ? "UV map" : "tangents",
                            "; it is shaded with its interpolated normals (give the mesh a UV "
                            "map and tangents)");
            if (bumped(material) && mesh.uv_sets.empty())
                log_warning(scene_detail::label("mesh", mesh.name), ": material '", material.name,
                            "' has a bump map but the mesh has no UV map; it is shaded without "
                            "its bumps (give the mesh a UV map)");
        }
    }
}

Bounds3 Scene::compute_bounds() const {
    Bounds3 bounds;
    for (size_t i = 0; i < instances_.size(); ++i) {
        const Bounds3 b =
            instance_bounds(meshes_[instances_[i].mesh_id], instances_[i].world_from_object);
        if (b.empty()) continue;
        const vec3 magnitude = glm::max(glm::abs(b.lower), glm::abs(b.upper));
        if (glm::any(glm::greaterThan(magnitude, vec3(kMaxCoordinate))))
            throw InvalidArgument(format_message(
                instance_label(instances_, i), ": world-space bounds ", to_string(b.lower),
                " to ", to_string(b.upper), " exceed ", kMaxCoordinate,
                " m (beyond Embree's float range); scale the object down"));
        bounds.extend(b.lower);
        bounds.extend(b.upper);
    }
    return bounds;
}

void Scene::set_ray_limits() {
    // Rays leave the scene's own surfaces, which must lie within the range (and directions of
    // length 1 with them).
    const double extent = bounds_.empty() ? 0.0
                                          : std::max(max_abs_component(bounds_.lower),
                                                     max_abs_component(bounds_.upper));
    const double world_reach = bounds_.empty()
                                   ? 0.0
                                   : glm::length(glm::max(glm::abs(glm::dvec3(bounds_.lower)),
                                                          glm::abs(glm::dvec3(bounds_.upper))));
    const double needed = std::max(extent, 1.0);
    const SceneRayLimits found = ray_limits_of(instances_, mesh_reports_, world_reach);
    enlarging_.assign(instances_.size(), 0);
    for (size_t i = 0; i < instances_.size(); ++i) {
        const MeshReport& report = mesh_reports_[instances_[i].mesh_id];
        const InstanceRange world = flattened_range(instances_[i], report);
        if (report.longest_edge > 0.0 && world.longest_edge > report.longest_edge)
            enlarging_[i] = lowers_limits(world, found, world_reach) ? 1 : 0;
    }
    ray_limits_.origin = float(found.origin.value);
    ray_limits_.direction = float(found.direction.value);
    ray_limits_.min_direction = float(found.min_direction);
    ray_limit_reason_.clear();
    std::string causes = ray_limit_cause(found.origin, instances_, mesh_reports_);
    if (!found.direction.same_cause(found.origin)) {
        const std::string direction_cause =
            ray_limit_cause(found.direction, instances_, mesh_reports_);
        if (!direction_cause.empty()) causes += (causes.empty() ? "" : "; ") + direction_cause;
    }
    if (!causes.empty()) ray_limit_reason_ = " (" + causes + ")";
    if (found.origin.value >= needed && found.direction.value >= 1.0) return;
    // Embree's range alone may already fail: its message names the scale.
    const bool range_fails = found.embree_origin.value < needed ||
                             found.embree_direction.value < 1.0;
    const RayLimit& limit =
        range_fails ? (found.embree_origin.value < needed ? found.embree_origin
                                                          : found.embree_direction)
                    : (found.origin.value < needed ? found.origin : found.direction);
    const std::string label = instance_label(instances_, limit.instance);
    const Instance& instance = instances_[limit.instance];
    const MeshReport& report = mesh_reports_[instance.mesh_id];
    if (range_fails)
        throw InvalidArgument(format_message(
            label, ": its transform shrinks the mesh by up to ",
            instance_range(instance, report).magnification, "x, so rays from the scene's extent (", extent, " m) would pass Embree's range of ",
            kMaxRayComponent, " in the mesh's own coordinates, where Debian's Embree aborts; "
            "apply the scale to the mesh's vertices (Blender: Apply Scale) or move the object "
            "nearer the origin"));
    throw InvalidArgument(format_message(
        label, ": its mesh has triangle edges up to ", report.longest_edge, " m in its own coordinates, so rays from the scene's extent (", extent,
        " m) would overflow Embree's triangle test in float (hits at infinite distance); apply "
        "the object's scale to the mesh's vertices (Blender: Apply Scale), split its largest "
        "faces, or keep the scene smaller"));
}

void Scene::gather_emissive() {
    emissive_.clear();
    for (size_t i = 0; i < instances_.size(); ++i) {
        const Mesh& mesh = meshes_[instances_[i].mesh_id];
        const mat4& world_from_object = instances_[i].world_from_object;
        for (size_t t = 0; t < mesh.triangles.size(); ++t) {
            const uint32_t material_id = mesh.material_indices.empty() ? 0
                                                                       : mesh.material_indices[t];
            const Material& material = materials_[material_id];
            if (!material.is_emissive()) continue;
            EmissiveTriangle emissive;
            emissive.instance_id = static_cast<uint32_t>(i);
            emissive.triangle_id = static_cast<uint32_t>(t);
            const uvec3& tri = mesh.triangles[t];
            emissive.p0 = vec3(world_from_object * vec4(mesh.positions[tri.x], 1.0f));
            emissive.p1 = vec3(world_from_object * vec4(mesh.positions[tri.y], 1.0f));
            emissive.p2 = vec3(world_from_object * vec4(mesh.positions[tri.z], 1.0f));
            const vec3 twice_area_normal =
                glm::cross(emissive.p1 - emissive.p0, emissive.p2 - emissive.p0);
            // In double: the squared length of a cross product of 1e12 m edges overflows float.
            emissive.area = float(0.5 * glm::length(glm::dvec3(twice_area_normal)));
            emissive.radiance = material.emission();
            emissive_.push_back(emissive);
        }
    }
}

void Scene::check_emitted_power() const {
    // Upper bounds of what LightSampler and PhotonEmitter weigh each emitter by: the sun and the
    // world cover the disk of bounding_radius() (of bounds_: the scene is not committed yet).
    const double radius = empty() ? 1.0 : double(radius_of(bounds_));
    const double cross_section = double(kPi) * radius * radius;
    enum class Kind { World, Light, Triangle };
    struct Emitter {
        Kind kind;
        size_t index;
        double power;
    };
    Emitter brightest{Kind::World, 0,
                      max_component(world_.radiance()) * double(kFourPi) * cross_section};
    double total = brightest.power;
    auto add = [&](Kind kind, size_t index, double power) {
        total += power;
        if (power > brightest.power) brightest = {kind, index, power};
    };
    for (size_t i = 0; i < lights_.size(); ++i) {
        const Light& light = lights_[i];
        if (light.portal) continue;  // emits nothing
        const double colour = max_component(light.color);
        add(Kind::Light, i,
            light.type == LightType::Sun ? colour * light.strength * cross_section
                                         : colour * light.power);
    }
    for (size_t i = 0; i < emissive_.size(); ++i)
        add(Kind::Triangle, i,
            max_component(emissive_[i].radiance) * double(kTwoPi) * emissive_[i].area);
    if (total <= kMaxEmittedPower) return;

    std::string source;  // what the brightest emitter's power comes from, and the fix
    if (brightest.kind == Kind::Light) {
        const Light& light = lights_[brightest.index];
        source = light.type == LightType::Sun
                     ? format_message(label("light", light.name), " (strength ", light.strength,
                                      " W/m^2 over the scene's cross-section of ", cross_section,
                                      " m^2): lower its strength")
                     : format_message(label("light", light.name), " (power ", light.power,
                                      " W): lower its power");
    } else if (brightest.kind == Kind::Triangle) {
        const EmissiveTriangle& triangle = emissive_[brightest.index];
        source = format_message("triangle ", triangle.triangle_id, " of ",
                                instance_label(instances_, triangle.instance_id), " (emission ",
                                max_component(triangle.radiance), " W m^-2 sr^-1 over ",
                                triangle.area, " m^2): lower its material's emission strength");
    } else {
        source = format_message("the world (", max_component(world_.radiance()),
                                " W m^-2 sr^-1 around the scene's cross-section of ",
                                cross_section, " m^2): lower its strength");
    }
    throw InvalidArgument(format_message(
        "the scene emits ", total, " W, beyond the ", kMaxEmittedPower,
        " W that light sampling carries in single precision; the brightest emitter, with ",
        brightest.power, " W, is ", source));
}

void Scene::commit(const CommitSettings& settings, Progress* progress) {
    committed_ = false;
    if (progress) progress->begin_stage("checking scene", 0.0f, 0.05f);
    check_references();
    material_terms_.clear();
    for (const Material& material : materials_)
        material_terms_.push_back(shgi::material_terms(material));
    bounds_ = compute_bounds();
    set_ray_limits();
    if (choose_flattened(settings.flatten_single_use_meshes)) geometry_dirty_ = true;
    gather_emissive();
    check_emitted_power();  // before the BVH is built for nothing
    if (geometry_dirty_) warn_missing_tangent_frames();
    const uint64_t budget = resolve_budget(settings.memory_budget_bytes);
    const uint64_t estimate = estimate_bvh_bytes(meshes_, instances_);
    if (estimate > budget)
        throw OutOfMemory(format_message(
            "the scene's BVH needs at least ", estimate, " bytes (", stats().triangles,
            " triangles in ", meshes_.size(), " meshes, ", instances_.size(),
            " instances) but the memory budget is ", budget, " bytes (", format_bytes(budget),
            "; memory_budget_bytes = ", settings.memory_budget_bytes,
            ", capped by what this process may still allocate: RLIMIT_AS / cgroup / free "
            "memory); raise memory_budget_bytes (0 = 75% of what the process may allocate), "
            "free memory or simplify the scene"));
    if (!embree_) embree_ = std::make_unique<EmbreeScene>();
    embree_->set_memory_budget(budget);
    embree_->reset_peak();
    build_bvh(progress);
    if (progress) progress->begin_stage("instance normals", 0.95f, 1.0f);
    normal_from_object_.clear();
    normal_from_embree_.clear();
    for (size_t i = 0; i < instances_.size(); ++i) {
        const mat4& world_from_object = instances_[i].world_from_object;
        normal_from_object_.push_back(normal_matrix(world_from_object));
        const float sign = glm::determinant(mat3(world_from_object)) < 0.0f ? -1.0f : 1.0f;
        normal_from_embree_.push_back(flattened_[i] ? mat3(sign) : normal_from_object_.back());
    }
    if (empty()) log_warning("scene has no triangles: every ray misses");
    committed_ = true;
    if (progress) progress->set_fraction(1.0f);
}

bool Scene::choose_flattened(bool flatten) {
    std::vector<uint64_t> uses(meshes_.size(), 0);
    for (const Instance& instance : instances_) ++uses[instance.mesh_id];
    std::vector<uint8_t> instanced(meshes_.size());
    // Shared meshes are copied in mesh order while the copies fit the scene's one budget, so a
    // thousand small shared meshes cannot copy a thousand budgets' worth of triangles.
    uint64_t copy_budget = kMaxFlattenedCopyTriangles;
    for (size_t m = 0; m < meshes_.size(); ++m) {
        const uint64_t copies = uses[m] * meshes_[m].triangles.size();
        const bool copied = uses[m] > 1 && copies <= copy_budget;
        if (flatten && !moving_ && copied) copy_budget -= copies;
        instanced[m] = uses[m] > 0 && (!flatten || moving_ || (uses[m] > 1 && !copied)) ? 1 : 0;
    }
    for (size_t i = 0; i < instances_.size(); ++i)
        if (enlarging_[i]) instanced[instances_[i].mesh_id] = 1;
    flattened_.resize(instances_.size());
    for (size_t i = 0; i < instances_.size(); ++i)
        flattened_[i] = !instanced[instances_[i].mesh_id] &&
                        !meshes_[instances_[i].mesh_id].triangles.empty();
    if (instanced == mesh_instanced_) return false;
    mesh_instanced_ = std::move(instanced);
    instances_dirty_ = true;  // flattened instances enter or leave the top level
    return true;
}

void Scene::build_bvh(Progress* progress) {
    try {
        if (geometry_dirty_) {
            if (progress) progress->begin_stage("building mesh BVHs", 0.05f, 0.85f);
            bvh_builds_ += embree_->build_meshes(meshes_, mesh_instanced_, progress);
            geometry_dirty_ = false;
            instances_dirty_ = true;  // build_meshes released the top level
        }
        if (instances_dirty_) {
            if (progress) progress->begin_stage("building the top-level BVH", 0.85f, 0.95f);
            embree_->build_instances(meshes_, instances_, flattened_, progress);
            ++bvh_builds_;
            bvh_bytes_ = embree_->peak_bytes();
        } else if (!moved_.empty()) {
            if (progress) progress->begin_stage("moving instances", 0.85f, 0.95f);
            embree_->move_instances(instances_, moved_, progress);
            ++bvh_builds_;
        }
        instances_dirty_ = false;
        moved_.clear();
    } catch (...) {
        embree_->clear();
        geometry_dirty_ = instances_dirty_ = true;
        throw;
    }
}

bool Scene::empty() const {
    for (const Instance& instance : instances_)
        if (!meshes_[instance.mesh_id].triangles.empty()) return false;
    return true;
}

Bounds3 Scene::bounds() const {
    if (empty())
        throw InvalidArgument("the scene has no triangles, so it has no bounds; add a mesh and "
                              "an instance of it");
    return committed_ ? bounds_ : compute_bounds();
}

float Scene::bounding_radius() const { return empty() ? 1.0f : radius_of(bounds()); }

SceneStats Scene::stats() const {
    SceneStats stats;
    stats.meshes = meshes_.size();
    stats.instances = instances_.size();
    for (size_t i = 0; i < meshes_.size(); ++i) {
        stats.triangles += meshes_[i].triangles.size();
        stats.dropped_degenerate += mesh_reports_[i].dropped_degenerate;
    }
    for (const Instance& instance : instances_)
        stats.instanced_triangles += meshes_[instance.mesh_id].triangles.size();
    stats.emissive_triangles = emissive_.size();
    stats.lights = lights_.size();
    stats.bvh_bytes = bvh_bytes_;
    stats.bvh_builds = bvh_builds_;
    for (uint8_t flat : flattened_) stats.flattened_instances += flat;
    return stats;
}

void Scene::require_committed(const char* query) const {
    if (!committed_)
        throw InvalidArgument(format_message(
            "Scene::", query, ": the scene was edited or never committed; call commit() first"));
}

void Scene::finish_hit(Hit& hit) const {
    if (hit.valid())
        hit.geometric_normal =
            transform_normal(normal_from_embree_[hit.instance_id], hit.geometric_normal);
}

Hit Scene::intersect(const Ray& ray) const {
    require_committed("intersect");
    check_ray(ray, "ray", ray_limits_, ray_limit_reason_);
    Hit hit;
    if (empty()) return hit;
    embree_->intersect(&ray, &hit, 1);
    finish_hit(hit);
    return hit;
}

bool Scene::occluded(const Ray& ray) const {
    require_committed("occluded");
    check_ray(ray, "ray", ray_limits_, ray_limit_reason_);
    if (empty()) return false;
    uint8_t result = 0;
    embree_->occluded(&ray, &result, 1);
    return result != 0;
}

void Scene::intersect(const std::vector<Ray>& rays, std::vector<Hit>& hits,
                      Progress* progress, RayCoherence coherence) const {
    require_committed("intersect");
    check_rays(rays, ray_limits_, ray_limit_reason_);
    if (empty()) {
        hits.assign(rays.size(), Hit{});
        throw_if_cancelled(progress);
        return;
    }
    hits.resize(rays.size());  // every hit is written by the trace below
    const auto trace = [&](uint64_t begin, uint64_t end) {
        embree_->intersect(&rays[begin], &hits[begin], end - begin, coherence);
        for (uint64_t i = begin; i < end; ++i) finish_hit(hits[i]);
    };
    // One chunk's worth (a renderer's tile) is traced on the calling thread: a parallel_for's
    // task set-up would cost more than its rays (a 640 x 360 frame makes ~1,800 such calls).
    if (rays.size() <= kRaysPerChunk) {
        throw_if_cancelled(progress);
        trace(0, rays.size());
        if (progress) progress->report(rays.size(), rays.size());
        return;
    }
    parallel_for(0, rays.size(), kRaysPerChunk, trace, progress);
}

void Scene::occluded(const std::vector<Ray>& rays, std::vector<uint8_t>& occluded,
                     Progress* progress, RayCoherence coherence) const {
    require_committed("occluded");
    check_rays(rays, ray_limits_, ray_limit_reason_);
    occluded.assign(rays.size(), 0);
    if (empty()) {
        throw_if_cancelled(progress);
        return;
    }
    const auto trace = [&](uint64_t begin, uint64_t end) {
        embree_->occluded(&rays[begin], &occluded[begin], end - begin, coherence);
    };
    if (rays.size() <= kRaysPerChunk) {  // as in intersect
        throw_if_cancelled(progress);
        trace(0, rays.size());
        if (progress) progress->report(rays.size(), rays.size());
        return;
    }
    parallel_for(0, rays.size(), kRaysPerChunk, trace, progress);
}

namespace {

// The world geometric normal of the hit's triangle (p0, p1, p2 in object space), from `memo`
// when it holds this triangle's, else computed (and stored in it).
inline vec3 triangle_normal(const Hit& hit, const vec3& p0, const vec3& p1, const vec3& p2,
                            const mat3& normal_from_object, TriangleNormalMemo* memo) {
    if (memo != nullptr && memo->instance_id == hit.instance_id &&
        memo->triangle_id == hit.triangle_id)
        return memo->normal;
    const vec3 normal = glm::normalize(normal_from_object * glm::cross(p1 - p0, p2 - p0));
    if (memo != nullptr) *memo = TriangleNormalMemo{hit.instance_id, hit.triangle_id, normal};
    return normal;
}

}  // namespace

// The ray is not needed: positions come from the barycentrics, which stay on the triangle,
// unlike origin + t * direction (whose rounding error grows with t).
SurfacePoint Scene::surface_point(const Ray& ray, const Hit& hit) const {
    return surface_point(ray, hit, nullptr);
}

SurfacePoint Scene::surface_point(const Ray& /*ray*/, const Hit& hit,
                                  TriangleNormalMemo* memo) const {
    if (!committed_) require_committed("surface_point");  // the test inline: a call a hit
    if (!hit.valid()) throw InvalidArgument("surface_point: the hit is a miss (no instance)");
    if (hit.instance_id >= instances_.size())
        throw InvalidArgument(format_message("surface_point: hit.instance_id = ", hit.instance_id,
                                             " but the scene has ", instances_.size(),
                                             " instances"));
    const Instance& instance = instances_[hit.instance_id];
    const Mesh& mesh = meshes_[instance.mesh_id];
    if (hit.triangle_id >= mesh.triangles.size())
        throw InvalidArgument(format_message("surface_point: hit.triangle_id = ", hit.triangle_id,
                                             " but its mesh has ", mesh.triangles.size(),
                                             " triangles"));
    const uvec3& tri = mesh.triangles[hit.triangle_id];
    const float b1 = hit.barycentrics.x, b2 = hit.barycentrics.y, b0 = 1.0f - b1 - b2;
    const vec3& p0 = mesh.positions[tri.x];
    const vec3& p1 = mesh.positions[tri.y];
    const vec3& p2 = mesh.positions[tri.z];
    const mat3& normal_from_object = normal_from_object_[hit.instance_id];

    SurfacePoint point;
    point.instance_id = hit.instance_id;
    point.triangle_id = hit.triangle_id;
    point.position = vec3(instance.world_from_object * vec4(b0 * p0 + b1 * p1 + b2 * p2, 1.0f));
    point.geometric_normal = triangle_normal(hit, p0, p1, p2, normal_from_object, memo);
    point.shading_normal = point.geometric_normal;
    if (!mesh.normals.empty()) {
        const vec3 n = normal_from_object * (b0 * mesh.normals[tri.x] + b1 * mesh.normals[tri.y] +
                                             b2 * mesh.normals[tri.z]);
        const float length = glm::length(n);
        // Opposite vertex normals can cancel out; the face normal is then the best guess.
        if (length > 0.0f) point.shading_normal = n / length;
    }
    point.material_id = mesh.material_indices.empty() ? 0 : mesh.material_indices[hit.triangle_id];
    const Material& material = materials_[point.material_id];
    if (!mesh.uv_sets.empty()) {
        point.uv = interpolate_uv(named_uv_set(mesh, material.base_color_uv_set), tri, b0, b1, b2);
        if (material.normal_texture != kNoTexture)
            point.normal_uv = interpolate_uv(named_uv_set(mesh, material.normal_uv_set), tri, b0,
                                             b1, b2);
    }
    if (material.normal_texture != kNoTexture &&
        material.normal_space == NormalMapSpace::Tangent && !mesh.tangents.empty())
        tangent_frame(mesh, tri, vec3(b0, b1, b2), normal_from_object, &point);
    if (material.bump_texture != kNoTexture && !mesh.uv_sets.empty()) {
        const UvSet& set = named_uv_set(mesh, material.bump_uv_set);
        point.bump_uv = interpolate_uv(set, tri, b0, b1, b2);
        // p1 - p0 = du1 dP/du + dv1 dP/dv, p2 - p0 = du2 dP/du + dv2 dP/dv, solved.
        const vec2 d1 = set.coords[tri.y] - set.coords[tri.x];
        const vec2 d2 = set.coords[tri.z] - set.coords[tri.x];
        const float det = d1.x * d2.y - d1.y * d2.x;
        if (std::fabs(det) > 1e-12f) {
            const mat3 world_from_object(instance.world_from_object);
            const vec3 e1 = world_from_object * (p1 - p0), e2 = world_from_object * (p2 - p0);
            point.dpdu = (d2.y * e1 - d1.y * e2) / det;
            point.dpdv = (d1.x * e2 - d2.x * e1) / det;
        }
    }
    return point;
}

static_assert(std::is_trivially_destructible_v<SurfacePoint>,
              "surface_point_lanes builds points over the caller's without destroying them");

void Scene::surface_point_lanes(const Hit* hits, SurfacePoint* points,
                                TriangleNormalMemo* memo) const {
#if defined(__SSE2__)
    // Lanes only where surface_point would neither throw nor read more than the triangle's
    // positions and material: one committed instance, a mesh without normals, UVs or tangents
    // (so no normal map frame and no bump derivatives), triangle ids in range.
    const uint32_t instance_id = hits[0].instance_id;
    bool flat = committed_ && instance_id < instances_.size();
    const Instance* instance = flat ? &instances_[instance_id] : nullptr;
    const Mesh* mesh = flat ? &meshes_[instance->mesh_id] : nullptr;
    flat = flat && mesh->normals.empty() && mesh->uv_sets.empty() && mesh->tangents.empty();
    for (int j = 0; j < 4 && flat; ++j)
        flat = hits[j].instance_id == instance_id &&
               hits[j].triangle_id < mesh->triangles.size();
    if (flat) {
        // The three vertices' coordinates, lane j the triangle of hits[j].
        alignas(16) float vertex[3][3][4];
        alignas(16) float b1[4], b2[4];
        const uvec3* tris[4];
        for (int j = 0; j < 4; ++j) {
            const uvec3& tri = mesh->triangles[hits[j].triangle_id];
            tris[j] = &tri;
            for (int v = 0; v < 3; ++v) {
                const vec3& p = mesh->positions[tri[v]];
                vertex[v][0][j] = p.x;
                vertex[v][1][j] = p.y;
                vertex[v][2][j] = p.z;
            }
            b1[j] = hits[j].barycentrics.x;
            b2[j] = hits[j].barycentrics.y;
        }
        // surface_point's b0 = 1 - b1 - b2, then b0 p0 + b1 p1 + b2 p2 summed left to right.
        const __m128 l1 = _mm_load_ps(b1), l2 = _mm_load_ps(b2);
        const __m128 l0 = _mm_sub_ps(_mm_sub_ps(_mm_set1_ps(1.0f), l1), l2);
        __m128 object[3];
        for (int a = 0; a < 3; ++a)
            object[a] = _mm_add_ps(_mm_add_ps(_mm_mul_ps(l0, _mm_load_ps(vertex[0][a])),
                                              _mm_mul_ps(l1, _mm_load_ps(vertex[1][a]))),
                                   _mm_mul_ps(l2, _mm_load_ps(vertex[2][a])));
        // glm's mat4 x vec4(p, 1): (m0 x + m1 y) + (m2 z + m3 w), where m3 w is m3 (w = 1).
        const mat4& m = instance->world_from_object;
        alignas(16) float world[3][4];
        for (int r = 0; r < 3; ++r) {
            const __m128 xy = _mm_add_ps(_mm_mul_ps(_mm_set1_ps(m[0][r]), object[0]),
                                         _mm_mul_ps(_mm_set1_ps(m[1][r]), object[1]));
            const __m128 zw =
                _mm_add_ps(_mm_mul_ps(_mm_set1_ps(m[2][r]), object[2]), _mm_set1_ps(m[3][r]));
            _mm_store_ps(world[r], _mm_add_ps(xy, zw));
        }
        const mat3& normal_from_object = normal_from_object_[instance_id];
        for (int j = 0; j < 4; ++j) {
            const Hit& hit = hits[j];
            const uvec3& tri = *tris[j];
            SurfacePoint& point = *::new (&points[j]) SurfacePoint();
            point.instance_id = hit.instance_id;
            point.triangle_id = hit.triangle_id;
            point.position = vec3(world[0][j], world[1][j], world[2][j]);
            point.geometric_normal =
                triangle_normal(hit, mesh->positions[tri.x], mesh->positions[tri.y],
                                mesh->positions[tri.z], normal_from_object, memo);
            point.shading_normal = point.geometric_normal;
            point.material_id =
                mesh->material_indices.empty() ? 0 : mesh->material_indices[hit.triangle_id];
        }
        return;
    }
#endif
    for (int j = 0; j < 4; ++j)
        if (hits[j].valid()) ::new (&points[j]) SurfacePoint(surface_point(Ray{}, hits[j], memo));
}

// SurfacePoint::tangent and bitangent from the unnormalised interpolated object-space tangent,
// sign and normal (the face normal on a mesh without normals), as Cycles' Normal Map node reads
// them. Left zero where a vertex's tangent was dropped (validate_mesh) or the frame collapses.
void Scene::tangent_frame(const Mesh& mesh, const uvec3& tri, const vec3& b,
                          const mat3& normal_from_object, SurfacePoint* point) const {
    const vec4& t0 = mesh.tangents[tri.x];
    const vec4& t1 = mesh.tangents[tri.y];
    const vec4& t2 = mesh.tangents[tri.z];
    if (t0.w == 0.0f || t1.w == 0.0f || t2.w == 0.0f) return;  // dropped: no frame
    const vec3 tangent = b.x * vec3(t0) + b.y * vec3(t1) + b.z * vec3(t2);
    const float sign = b.x * t0.w + b.y * t1.w + b.z * t2.w < 0.0f ? -1.0f : 1.0f;
    vec3 normal;
    if (mesh.normals.empty()) {
        const vec3& p0 = mesh.positions[tri.x];
        normal = glm::normalize(glm::cross(mesh.positions[tri.y] - p0, mesh.positions[tri.z] - p0));
    } else {
        normal = b.x * mesh.normals[tri.x] + b.y * mesh.normals[tri.y] + b.z * mesh.normals[tri.z];
    }
    const float scale = glm::length(normal_from_object * normal);
    if (!(scale > 0.0f)) return;
    point->tangent = normal_from_object * tangent / scale;
    point->bitangent = normal_from_object * (sign * glm::cross(normal, tangent)) / scale;
}

}  // namespace shgi
