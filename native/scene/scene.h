// Scene: meshes, instances, materials, textures, lights, world and camera, plus the Embree BVH
// that answers ray queries.
//
// Building: add_* validates each item at this boundary (NaN/Inf, ranges, index bounds; degenerate
// triangles are dropped and counted) and throws InvalidArgument naming the item and field.
// commit() checks cross references (instance -> mesh, triangle -> material, material -> texture;
// a scene without materials gets one default Material so every triangle has one), gathers
// emissive triangles, refuses emitted power beyond kMaxEmittedPower (naming the brightest
// emitter), and builds the BVH (scene/embree_scene.h): a mesh used by one instance is flattened
// into the top-level BVH in world space (rays pay no instance transform), and so are small meshes
// used by several while all their copies hold at most kMaxFlattenedCopyTriangles (the Cornell
// box's two blocks: a copy costs less than the instance transform every ray would pay); a mesh
// used by several keeps one BVH of its own, instanced once per Instance, so a mesh used a
// thousand times is stored once (so is a mesh whose instance enlarges it beyond the ray range
// the rest of the scene allows: flattening must not narrow the rays a scene traces). Any edit un-commits
// the scene. set_instance_transform() marks the scene as moving: from its next commit every mesh
// is instanced (one build of the per-mesh BVHs), and each move then rebuilds only the small top
// level, as Cycles keeps a dynamic BVH in its viewport; a static scene (final renders, bakes,
// a viewport where only lights and materials change) keeps the flattened layout. set_mesh() (a
// mesh replaced for all its instances) rebuilds the per-mesh BVHs. Light, material and texture
// edits rebuild no BVH.
//
// Queries: intersect/occluded for single rays and for batches (Embree ray streams), callable
// from many threads at once on a committed scene. Every ray is validated first; an invalid ray
// throws InvalidArgument (Debian's Embree aborts the process on a non-finite ray).
//
// Memory: commit() enforces CommitSettings::memory_budget_bytes through Embree's memory monitor
// and fails with OutOfMemory and a message giving the sizes, instead of the process being killed.
//
// Normals: a hit's geometric normal is the object-space cross(p1 - p0, p2 - p0) mapped by the
// cofactor of world_from_object times sign(det) (= |det| * inverse-transpose): its length is twice
// the world-space area, and a mirroring (negative-determinant) transform keeps the object's front
// side as the front, as Cycles does for negatively scaled objects.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "scene/camera.h"
#include "scene/light.h"
#include "scene/material.h"
#include "scene/mesh.h"
#include "scene/ray.h"
#include "util/math.h"
#include "util/progress.h"

namespace shgi {

struct Instance {
    std::string name;
    uint32_t mesh_id = 0;
    mat4 world_from_object{1.0f};
};

struct Bounds3 {
    vec3 lower{kInfinity};
    vec3 upper{-kInfinity};

    bool empty() const { return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z; }
    void extend(const vec3& p) {
        lower = glm::min(lower, p);
        upper = glm::max(upper, p);
    }
    vec3 extent() const { return upper - lower; }
};

// The most power (W, in an emitter's brightest channel, summed over the scene's lights, emissive
// triangles and world) that commit() accepts. The samplers weigh emitters and photons by their
// power in float (3.4e38 at most): below this a sum or product of them stays finite. A sun of
// 1000 W/m^2 over a scene kMaxCoordinate across emits ~1e27 W.
inline constexpr double kMaxEmittedPower = 1e36;

// A triangle whose material emits: the "emissive triangles" light type.
struct EmissiveTriangle {
    uint32_t instance_id;
    uint32_t triangle_id;
    vec3 p0, p1, p2;   // world space
    float area;        // m^2
    vec3 radiance;     // W m^-2 sr^-1 (emission colour x strength)
};

// Where a ray hit, with everything shading needs. Normals are unit length, world space;
// `shading_normal` is interpolated from vertex normals (or equals the geometric one); a normal
// map bends it in render/shading.h (render/normal_map.h).
struct SurfacePoint {
    vec3 position{0.0f};
    vec3 geometric_normal{0.0f, 0.0f, 1.0f};
    vec3 shading_normal{0.0f, 0.0f, 1.0f};
    // The tangent frame of a tangent-space normal map, world space: the interpolated object-space
    // tangent and bitangent (sign x cross(normal, tangent)) mapped by the instance's normal
    // transform, with the scale that makes the mapped interpolated normal unit (shading_normal),
    // so x tangent + y bitangent + z shading_normal is Cycles' object-space combination mapped to
    // world. Zero when the mesh has no tangents or the material no tangent-space normal map.
    vec3 tangent{0.0f};
    vec3 bitangent{0.0f};
    // The UV set the material's texture names (Material::base_color_uv_set), else the first;
    // (0,0) when the mesh has none.
    vec2 uv{0.0f};
    vec2 normal_uv{0.0f};  // the same for the normal map (Material::normal_uv_set)
    // The bump map's UV (Material::bump_uv_set) and the surface's derivatives along it, world
    // space (the triangle's dP/du, dP/dv); zero without a bump map or where the UVs collapse.
    vec2 bump_uv{0.0f};
    vec3 dpdu{0.0f}, dpdv{0.0f};
    uint32_t material_id = 0;
    uint32_t instance_id = kInvalidId;
    uint32_t triangle_id = kInvalidId;

    // The defaults above, member by member: with the defaulted constructor GCC cleared the whole
    // point with a `rep stos` (slow to start) before Scene::surface_point overwrote most of it.
    SurfacePoint() {}
};

// The last triangle whose geometric normal Scene::surface_point computed for a caller, and that
// normal (world space, unit, before any flip toward the ray).
struct TriangleNormalMemo {
    uint32_t instance_id = kInvalidId;
    uint32_t triangle_id = kInvalidId;
    vec3 normal{0.0f, 0.0f, 1.0f};

    void reset() { instance_id = triangle_id = kInvalidId; }
};

// Meshes used by several instances are flattened (copied into the top level once per instance)
// while all their copies together hold at most this many triangles (taken in mesh order).
inline constexpr uint64_t kMaxFlattenedCopyTriangles = uint64_t(1) << 16;

struct CommitSettings {
    // Upper bound on the memory Embree may allocate for the BVH (bytes); 0 = 75% of what the
    // process may still allocate (util/memory.h: RLIMIT_AS, cgroup limit, free memory), which
    // also caps an explicit budget.
    uint64_t memory_budget_bytes = 0;
    // Meshes used by one instance, and small meshes used by several (kMaxFlattenedCopyTriangles),
    // go into the top-level BVH in world space (faster rays, the same hits); false instances
    // every mesh, as a reference for tests.
    bool flatten_single_use_meshes = true;
};

struct SceneStats {
    uint64_t meshes = 0, instances = 0, triangles = 0, instanced_triangles = 0;
    uint64_t dropped_degenerate = 0, emissive_triangles = 0, lights = 0;
    uint64_t bvh_bytes = 0;  // peak Embree allocation during the last commit
    uint64_t bvh_builds = 0; // Embree builds (per-mesh and top-level) over the scene's life
    uint64_t flattened_instances = 0;  // instances whose mesh is in the top-level BVH itself
};

class EmbreeScene;  // scene/embree_scene.h: the only place that sees Embree

class Scene {
  public:
    Scene();
    ~Scene();
    Scene(Scene&&) noexcept;
    Scene& operator=(Scene&&) noexcept;
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    // --- building (each returns the new item's id) ---
    uint32_t add_mesh(Mesh mesh);
    uint32_t add_instance(uint32_t mesh_id, const mat4& world_from_object, std::string name = "");
    uint32_t add_material(Material material);
    uint32_t add_texture(Texture texture);
    uint32_t add_light(Light light);
    void set_world(const World& world);
    void set_camera(const Camera& camera);
    void set_instance_transform(uint32_t instance_id, const mat4& world_from_object);
    // Replaces mesh `mesh_id` (validated and cleaned as add_mesh does; its MeshReport replaced)
    // in every instance of it, e.g. by one with a new lightmap UV set. The next commit()
    // rebuilds the per-mesh BVHs.
    void set_mesh(uint32_t mesh_id, Mesh mesh);
    // Edits in place that leave every BVH as it is: the next commit() recomputes the material
    // terms, emissive triangles and power checks only (a light or material edit in the viewport
    // starts its next frame without a BVH build). set_lights replaces the whole list (lights may
    // come and go); the ids stay those of the new list.
    void set_light(uint32_t light_id, Light light);
    void set_lights(std::vector<Light> lights);
    void set_material(uint32_t material_id, Material material);
    void set_texture(uint32_t texture_id, Texture texture);

    const std::vector<Mesh>& meshes() const { return meshes_; }
    const std::vector<MeshReport>& mesh_reports() const { return mesh_reports_; }
    const std::vector<Instance>& instances() const { return instances_; }
    const std::vector<Material>& materials() const { return materials_; }
    // material_terms(materials()[i]) for every material, computed by commit() (empty before).
    const std::vector<MaterialTerms>& material_terms() const { return material_terms_; }
    const std::vector<Texture>& textures() const { return textures_; }
    const std::vector<Light>& lights() const { return lights_; }
    const World& world() const { return world_; }
    bool has_camera() const { return has_camera_; }
    const Camera& camera() const;  // throws InvalidArgument when no camera was set

    // --- BVH ---
    void commit(const CommitSettings& settings = {}, Progress* progress = nullptr);
    bool committed() const { return committed_; }
    // Increases with every edit. Consumers that cache data derived from a committed scene (light
    // tables, films sized to the camera) keep the revision they saw and refuse a changed scene.
    uint64_t revision() const { return revision_; }
    // Unique among the Scene objects of this process (never reused; a moved-to Scene takes the
    // source's): data derived from one scene (a TexelMap) records it and refuses another.
    uint64_t uid() const { return uid_; }
    // The revision() at which mesh `mesh_id` was last added or replaced (set_mesh); throws
    // InvalidArgument for an id out of range.
    uint64_t mesh_revision(uint32_t mesh_id) const;
    // True when the scene has no triangles (after dropping degenerate ones).
    bool empty() const;
    // World-space bounds of all instances; throws InvalidArgument for an empty scene.
    Bounds3 bounds() const;
    // Radius of the bounding sphere, at least 1 mm (1 m for an empty scene): the sun and the
    // world are weighed over the disk of this radius (LightSampler, PhotonEmitter, commit's power
    // check).
    float bounding_radius() const;
    SceneStats stats() const;
    const std::vector<EmissiveTriangle>& emissive_triangles() const { return emissive_; }

    // --- queries (scene must be committed: otherwise InvalidArgument "call commit() first") ---
    // A ray failing is_valid_ray(ray, ray_limits()) throws InvalidArgument naming the ray
    // (index), its values and the limits.
    Hit intersect(const Ray& ray) const;
    bool occluded(const Ray& ray) const;
    // Batches: hits/occluded are resized to rays.size(). All rays are validated before any is
    // traced; the work is then split into chunks of kRaysPerChunk that poll `progress`.
    void intersect(const std::vector<Ray>& rays, std::vector<Hit>& hits,
                   Progress* progress = nullptr,
                   RayCoherence coherence = RayCoherence::Incoherent) const;
    void occluded(const std::vector<Ray>& rays, std::vector<uint8_t>& occluded,
                  Progress* progress = nullptr,
                  RayCoherence coherence = RayCoherence::Incoherent) const;
    // Shading data at a valid hit (InvalidArgument for a miss or ids out of range).
    SurfacePoint surface_point(const Ray& ray, const Hit& hit) const;
    // The same, the triangle's geometric normal taken from `memo` when it holds this triangle's
    // (and stored in it otherwise): a caller shading many hits in a row on one thread (the
    // preview's wave) mostly meets the triangle its last hit met. The normal is a function of
    // the triangle alone, so the point is the one above, bit for bit. The memo belongs to this
    // scene as committed: reset() it for another scene or revision.
    SurfacePoint surface_point(const Ray& ray, const Hit& hit, TriangleNormalMemo* memo) const;
    // points[j] = surface_point(ray, hits[j], memo) for the four hits[0, 4) that are valid (a
    // miss's point is left as it was), bit for bit. Four hits on one instance of a flat mesh (no
    // vertex normals, UVs or tangents: the preview's wave on a Cornell box) are interpolated and
    // moved to world space in four SSE2 lanes, each lane the scalar operations in their order;
    // any other four take surface_point one by one.
    void surface_point_lanes(const Hit* hits, SurfacePoint* points,
                             TriangleNormalMemo* memo) const;
    // What maps instance `instance_id`'s object-space normals to world (scene.h, "Normals");
    // valid on a committed scene (object-space normal maps read it).
    const mat3& normal_from_object(uint32_t instance_id) const {
        return normal_from_object_[instance_id];
    }

    static constexpr uint64_t kRaysPerChunk = 4096;
    // The origin and direction components the committed scene traces: kMaxRayComponent, less
    // where an instance shrinks its mesh (scene/ray.h, RayLimits). commit() refuses an instance
    // that would leave the scene's own surfaces out of range.
    const RayLimits& ray_limits() const { return ray_limits_; }

  private:
    void invalidate();
    void require_committed(const char* query) const;
    void check_references();
    void warn_missing_tangent_frames() const;  // after check_references
    Bounds3 compute_bounds() const;
    void set_ray_limits();  // from the instances and bounds_
    void gather_emissive();
    void check_emitted_power() const;  // after gather_emissive and compute_bounds
    void finish_hit(Hit& hit) const;
    void tangent_frame(const Mesh& mesh, const uvec3& tri, const vec3& barycentrics,
                       const mat3& normal_from_object, SurfacePoint* point) const;
    // Which meshes keep a BVH of their own (large and used by several instances, or flattening
    // is off); true when that changed since the per-mesh BVHs were built.
    bool choose_flattened(bool flatten);
    void build_bvh(Progress* progress);

    std::vector<Mesh> meshes_;
    std::vector<MeshReport> mesh_reports_;
    std::vector<Instance> instances_;
    std::vector<Material> materials_;
    std::vector<MaterialTerms> material_terms_;
    std::vector<Texture> textures_;
    std::vector<Light> lights_;
    World world_;
    Camera camera_;
    bool has_camera_ = false;
    bool committed_ = false;
    uint64_t revision_ = 0;
    uint64_t uid_ = next_uid();
    std::vector<uint64_t> mesh_revisions_;  // per mesh: revision_ when it was added or set
    static uint64_t next_uid();
    bool geometry_dirty_ = true;   // meshes changed: per-mesh BVHs must be rebuilt
    bool instances_dirty_ = true;  // instances added: the top level must be rebuilt
    std::vector<uint32_t> moved_;  // instances moved since the last commit (may repeat)
    bool moving_ = false;          // set_instance_transform was called: flatten nothing
    uint64_t bvh_builds_ = 0;
    std::vector<EmissiveTriangle> emissive_;
    std::vector<uint8_t> mesh_instanced_;  // per mesh: has its own BVH (embree_scene.h)
    std::vector<uint8_t> flattened_;       // per instance: its mesh is copied into the top level
    // Per instance: flattening it would lower ray_limits_ (it enlarges its mesh, and Embree's
    // float triangle test would then see larger numbers), so it stays instanced.
    std::vector<uint8_t> enlarging_;
    // Per instance, world_from_object's cofactor times sign(det): maps object normals to world.
    std::vector<mat3> normal_from_object_;
    // Per instance, what maps Embree's normal to world (scene.h, "Normals"): normal_from_object_
    // for an instanced mesh; for a flattened one, whose normal Embree computes from world-space
    // vertices (the cofactor times the object normal), just sign(det).
    std::vector<mat3> normal_from_embree_;
    Bounds3 bounds_;  // world bounds of the instanced triangles, cached at commit
    RayLimits ray_limits_;
    std::string ray_limit_reason_;  // why ray_limits_ is below kMaxRayComponent, for messages
    uint64_t bvh_bytes_ = 0;
    std::unique_ptr<EmbreeScene> embree_;
};

}  // namespace shgi
