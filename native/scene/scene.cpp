#include "scene/scene.h"

#include <cmath>
#include <limits>

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

// CommitSettings::memory_budget_bytes = 0 leaves a quarter of the machine's RAM to Blender and
// the rest of SHGI.
constexpr double kDefaultBudgetFraction = 0.75;

uint64_t resolve_budget(uint64_t requested) {
    return requested > 0 ? requested : physical_memory_share(kDefaultBudgetFraction);
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
    const std::string range =
        out_of_range ? format_message("; this scene traces origins up to ", limits.origin,
                                      " and directions up to ", limits.direction,
                                      " per component", limit_reason)
                     : std::string();
    throw InvalidArgument(format_message(name, ": ", problem, " (origin ", to_string(ray.origin),
                                         ", direction ", to_string(ray.direction), ", tmin ",
                                         ray.tmin, ", tmax ", ray.tmax, ")", range));
}

// Validates every ray before any is traced, so the message names the first bad one whatever
// the chunking.
void check_rays(const std::vector<Ray>& rays, const RayLimits& limits,
                const std::string& limit_reason) {
    for (size_t i = 0; i < rays.size(); ++i)
        if (!is_valid_ray(rays[i], limits))
            check_ray(rays[i], format_message("rays[", i, "]").c_str(), limits, limit_reason);
}

// The ray limits of a scene and the instance that sets the origin's (magnification 1: none).
struct SceneRayLimits {
    RayLimits limits;
    size_t instance = 0;
    double magnification = 1.0;  // that instance's
};

// Embree maps a ray into an instance's object space as M^-1 (o - t) and M^-1 d (M the linear
// part of world_from_object, t its translation), then checks it against its range again. Per
// component |(M^-1 x)_j| <= K max_k |x_k|, K the largest row sum of |M^-1| (the magnification):
// origins within kMaxRayComponent / K - max|t| and directions within kMaxRayComponent / K stay
// in range. Instances of meshes without triangles are not in Embree's scene and do not count.
SceneRayLimits ray_limits_of(const std::vector<Instance>& instances,
                             const std::vector<Mesh>& meshes) {
    SceneRayLimits result;
    double origin = kMaxRayComponent, direction = kMaxRayComponent;
    for (size_t i = 0; i < instances.size(); ++i) {
        if (meshes[instances[i].mesh_id].triangles.empty()) continue;
        const glm::dmat4 transform(instances[i].world_from_object);
        const glm::dmat3 inverse = glm::inverse(glm::dmat3(transform));
        double magnification = 0.0;
        for (int row = 0; row < 3; ++row)
            magnification = std::max(magnification, std::fabs(inverse[0][row]) +
                                                         std::fabs(inverse[1][row]) +
                                                         std::fabs(inverse[2][row]));
        if (!std::isfinite(magnification)) magnification = std::numeric_limits<double>::max();
        const double reach = std::max({std::fabs(transform[3].x), std::fabs(transform[3].y),
                                       std::fabs(transform[3].z)});
        const double instance_origin = kMaxRayComponent / magnification - reach;
        direction = std::min(direction, kMaxRayComponent / magnification);
        if (instance_origin < origin) {
            origin = instance_origin;
            result.instance = i;
            result.magnification = magnification;
        }
    }
    result.limits.origin = float(std::max(origin, 0.0));
    result.limits.direction = float(direction);
    return result;
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

// The UV set a material's texture reads on a mesh with at least one set: the one it names, else
// the first (as Blender's Image Texture without a UV Map node uses the active render UV map,
// which the exporter puts first).
const UvSet& texture_uv_set(const Mesh& mesh, const Material& material) {
    if (!material.base_color_uv_set.empty())
        for (const UvSet& set : mesh.uv_sets)
            if (set.name == material.base_color_uv_set) return set;
    return mesh.uv_sets.front();
}

// Scene::bounding_radius of non-empty bounds.
float radius_of(const Bounds3& bounds) {
    return std::max(0.5f * glm::length(bounds.extent()), 1e-3f);
}

}  // namespace

Scene::Scene() = default;
Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

void Scene::invalidate() {
    committed_ = false;
    ++revision_;
}

uint32_t Scene::add_mesh(Mesh mesh) {
    MeshReport report = validate_mesh(mesh, kAnyMaterialCount);
    meshes_.push_back(std::move(mesh));
    mesh_reports_.push_back(report);
    geometry_dirty_ = true;
    invalidate();
    return static_cast<uint32_t>(meshes_.size() - 1);
}

void Scene::set_mesh(uint32_t mesh_id, Mesh mesh) {
    if (mesh_id >= meshes_.size())
        throw InvalidArgument(format_message("set_mesh: mesh_id = ", mesh_id, " but the scene has ",
                                             meshes_.size(), " meshes; add_mesh() adds a new one"));
    // Validated before anything changes, so a rejected mesh leaves the scene as it was.
    const MeshReport report = validate_mesh(mesh, kAnyMaterialCount);
    meshes_[mesh_id] = std::move(mesh);
    mesh_reports_[mesh_id] = report;
    geometry_dirty_ = true;
    invalidate();
}

uint32_t Scene::add_instance(uint32_t mesh_id, const mat4& world_from_object, std::string name) {
    const std::string item = name.empty() ? format_message("instance ", instances_.size())
                                          : format_message("instance '", name, "'");
    if (mesh_id >= meshes_.size())
        throw InvalidArgument(format_message(item, ": mesh_id = ", mesh_id, " but the scene has ",
                                             meshes_.size(), " meshes; add the mesh first"));
    require_transform(item, "world_from_object", world_from_object);
    instances_.push_back(Instance{std::move(name), mesh_id, world_from_object});
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
    invalidate();  // the per-mesh BVHs stay: only the top level is rebuilt
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
    const SceneRayLimits found = ray_limits_of(instances_, meshes_);
    ray_limits_ = found.limits;
    ray_limit_reason_.clear();
    if (!(found.magnification > 1.0)) return;  // Embree's own range holds
    const std::string label = instance_label(instances_, found.instance);
    ray_limit_reason_ = format_message(" (", label, " shrinks its mesh by up to ",
                                       found.magnification, "x, and Embree's range of ",
                                       kMaxRayComponent, " applies in the mesh's coordinates)");
    // Rays leave the scene's own surfaces, which must lie within the range (and directions of
    // length 1 with them: their limit is at least the origins').
    const float extent = bounds_.empty() ? 0.0f
                                         : std::max(max_abs_component(bounds_.lower),
                                                    max_abs_component(bounds_.upper));
    if (ray_limits_.origin < std::max(extent, 1.0f))
        throw InvalidArgument(format_message(
            label, ": its transform shrinks the mesh by up to ", found.magnification,
            "x, so rays from the scene's extent (", extent, " m) would pass Embree's range of ",
            kMaxRayComponent, " in the mesh's own coordinates, where Debian's Embree aborts; "
            "apply the scale to the mesh's vertices (Blender: Apply Scale) or move the object "
            "nearer the origin"));
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
    gather_emissive();
    check_emitted_power();  // before the BVH is built for nothing
    const uint64_t budget = resolve_budget(settings.memory_budget_bytes);
    const uint64_t estimate = estimate_bvh_bytes(meshes_, instances_);
    if (estimate > budget)
        throw OutOfMemory(format_message(
            "the scene's BVH needs at least ", estimate, " bytes (", stats().triangles,
            " triangles in ", meshes_.size(), " meshes, ", instances_.size(),
            " instances) but the memory budget is ", budget,
            " bytes; raise memory_budget_bytes (0 = 75% of physical RAM) or simplify the scene"));
    if (!embree_) embree_ = std::make_unique<EmbreeScene>();
    embree_->set_memory_budget(budget);
    embree_->reset_peak();
    try {
        if (geometry_dirty_) {
            if (progress) progress->begin_stage("building mesh BVHs", 0.05f, 0.85f);
            embree_->build_meshes(meshes_, progress);
            geometry_dirty_ = false;
        }
        if (progress) progress->begin_stage("building instance BVH", 0.85f, 0.95f);
        embree_->build_instances(instances_, progress);
    } catch (...) {
        embree_->clear();
        geometry_dirty_ = true;
        throw;
    }
    bvh_bytes_ = embree_->peak_bytes();
    if (progress) progress->begin_stage("instance normals", 0.95f, 1.0f);
    normal_from_object_.clear();
    for (const Instance& instance : instances_)
        normal_from_object_.push_back(normal_matrix(instance.world_from_object));
    if (empty()) log_warning("scene has no triangles: every ray misses");
    committed_ = true;
    if (progress) progress->set_fraction(1.0f);
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
    return stats;
}

void Scene::require_committed(const char* query) const {
    if (!committed_)
        throw InvalidArgument(format_message(
            "Scene::", query, ": the scene was edited or never committed; call commit() first"));
}

void Scene::finish_hit(Hit& hit) const {
    if (hit.valid())
        hit.geometric_normal = normal_from_object_[hit.instance_id] * hit.geometric_normal;
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
    hits.assign(rays.size(), Hit{});
    if (empty()) {
        throw_if_cancelled(progress);
        return;
    }
    parallel_for(
        0, rays.size(), kRaysPerChunk,
        [&](uint64_t begin, uint64_t end) {
            embree_->intersect(&rays[begin], &hits[begin], end - begin, coherence);
            for (uint64_t i = begin; i < end; ++i) finish_hit(hits[i]);
        },
        progress);
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
    parallel_for(
        0, rays.size(), kRaysPerChunk,
        [&](uint64_t begin, uint64_t end) {
            embree_->occluded(&rays[begin], &occluded[begin], end - begin, coherence);
        },
        progress);
}

// The ray is not needed: positions come from the barycentrics, which stay on the triangle,
// unlike origin + t * direction (whose rounding error grows with t).
SurfacePoint Scene::surface_point(const Ray& /*ray*/, const Hit& hit) const {
    require_committed("surface_point");
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
    point.geometric_normal = glm::normalize(normal_from_object * glm::cross(p1 - p0, p2 - p0));
    point.shading_normal = point.geometric_normal;
    if (!mesh.normals.empty()) {
        const vec3 n = normal_from_object * (b0 * mesh.normals[tri.x] + b1 * mesh.normals[tri.y] +
                                             b2 * mesh.normals[tri.z]);
        const float length = glm::length(n);
        // Opposite vertex normals can cancel out; the face normal is then the best guess.
        if (length > 0.0f) point.shading_normal = n / length;
    }
    point.material_id = mesh.material_indices.empty() ? 0 : mesh.material_indices[hit.triangle_id];
    if (!mesh.uv_sets.empty()) {
        const std::vector<vec2>& uv = texture_uv_set(mesh, materials_[point.material_id]).coords;
        point.uv = b0 * uv[tri.x] + b1 * uv[tri.y] + b2 * uv[tri.z];
    }
    return point;
}

}  // namespace shgi
