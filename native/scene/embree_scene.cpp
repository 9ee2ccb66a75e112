#include "scene/embree_scene.h"

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <iterator>
#if defined(__SSE2__)
#include <xmmintrin.h>
#include <emmintrin.h>
#endif

#include "scene/embree_device.h"
#include "scene/scene.h"
#include "scene/validation.h"
#include "util/error.h"

namespace shgi {
namespace {

static_assert(sizeof(vec3) == 3 * sizeof(float), "Embree's FLOAT3 vertex buffer layout");
static_assert(sizeof(uvec3) == 3 * sizeof(uint32_t), "Embree's UINT3 index buffer layout");

// Lower bounds for estimate_bvh_bytes, from Embree 3's smallest layouts: a triangle costs at
// least its share of a BVH4 node plus a Triangle4 leaf slot (measured ~60 bytes per triangle for
// MEDIUM quality; 32 keeps the estimate a bound), an instance its geometry object and a leaf.
constexpr uint64_t kMinBvhBytesPerTriangle = 32;
constexpr uint64_t kMinBytesPerInstance = 256;

// Instance geometries attached between cancel polls in the top-level build.
constexpr size_t kInstancesPerPoll = 4096;

// Steps per mesh in the progress of build_meshes (Embree reports a build as a fraction).
constexpr uint64_t kProgressSteps = 1000;

struct SceneDeleter {
    void operator()(RTCScene scene) const { rtcReleaseScene(scene); }
};
struct GeometryDeleter {
    void operator()(RTCGeometry geometry) const { rtcReleaseGeometry(geometry); }
};
using SceneHandle = std::unique_ptr<RTCSceneTy, SceneDeleter>;
using GeometryHandle = std::unique_ptr<RTCGeometryTy, GeometryDeleter>;

// Where a build stands, for Embree's progress monitor: build `index` of `count`.
struct BuildMonitor {
    Progress* progress = nullptr;
    uint64_t index = 0, count = 1;
};

// Embree calls this from its builder threads; returning false cancels the build (the commit then
// fails with RTC_ERROR_CANCELLED, which EmbreeDevice turns into Cancelled).
bool on_build_progress(void* pointer, double fraction) {
    const auto* monitor = static_cast<const BuildMonitor*>(pointer);
    if (!monitor->progress) return true;
    if (monitor->progress->cancelled()) return false;
    const double clamped = std::clamp(fraction, 0.0, 1.0);
    monitor->progress->report(
        monitor->index * kProgressSteps + static_cast<uint64_t>(clamped * kProgressSteps),
        monitor->count * kProgressSteps);
    return true;
}

void to_embree(const Ray& ray, RTCRay& out) {
    out.org_x = ray.origin.x;
    out.org_y = ray.origin.y;
    out.org_z = ray.origin.z;
    out.tnear = ray.tmin;
    out.dir_x = ray.direction.x;
    out.dir_y = ray.direction.y;
    out.dir_z = ray.direction.z;
    out.time = 0.0f;
    out.tfar = ray.tmax;
    out.mask = 0xFFFFFFFFu;
    out.id = 0;
    out.flags = 0;
}

void to_embree(const Ray& ray, RTCRayHit& out) {
    to_embree(ray, out.ray);
    out.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    out.hit.primID = RTC_INVALID_GEOMETRY_ID;
    out.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

// Embree marks an occluded ray by setting its tfar to -inf.
uint8_t occluded_flag(float tfar) { return tfar < 0.0f ? 1 : 0; }

// The top level's geometry i is instance i (EmbreeScene::build_instances): a hit in an
// instanced mesh names it in instID, a hit on a flattened mesh in geomID.
uint32_t instance_of(uint32_t geometry_id, uint32_t instance_id) {
    return instance_id == RTC_INVALID_GEOMETRY_ID ? geometry_id : instance_id;
}

Hit from_embree(const RTCRayHit& in) {
    Hit hit;
    if (in.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.t = in.ray.tfar;
    hit.instance_id = instance_of(in.hit.geomID, in.hit.instID[0]);
    hit.triangle_id = in.hit.primID;
    hit.barycentrics = vec2(in.hit.u, in.hit.v);
    hit.geometric_normal = vec3(in.hit.Ng_x, in.hit.Ng_y, in.hit.Ng_z);
    return hit;
}

// Coherent rays go through Embree's packet traversal, 16 neighbouring rays at a time
// (rtcIntersect16/rtcOccluded16, valid at any CPU's SIMD width). Not the stream API's coherent
// flag: on Debian's Embree 3.13.5, rtcOccluded1M with RTC_INTERSECT_CONTEXT_FLAG_COHERENT never
// returned for a stream of point-light shadow rays in an instanced scene (a PreviewRenderer
// test).
constexpr unsigned kPacket = 16;

#if defined(__SSE2__)
// The packet's lanes from `size` rays (1..kPacket), four lanes at a time: a Ray is eight packed
// floats (origin, direction, tmin, tmax), so a 4 x 4 transpose of four rays' first halves gives
// four lanes of org_x, org_y, org_z and dir_x, one of their second halves dir_y, dir_z, tnear and
// tfar. Lanes past `size` repeat the last ray, so Embree never reads uninitialised values. Only
// loads, shuffles and stores: the same bits as one scalar store per field and lane, in a quarter
// of the instructions (the packing is on every coherent ray's path).
void set_lanes(RTCRay16& packet, const Ray* rays, size_t size) {
    static_assert(sizeof(Ray) == 8 * sizeof(float), "Ray is eight packed floats");
    const __m128 zero = _mm_setzero_ps();
    const __m128 all_ones = _mm_castsi128_ps(_mm_set1_epi32(-1));
    for (unsigned lane = 0; lane < kPacket; lane += 4) {
        const auto* r0 = reinterpret_cast<const float*>(&rays[std::min<size_t>(lane, size - 1)]);
        const auto* r1 =
            reinterpret_cast<const float*>(&rays[std::min<size_t>(lane + 1, size - 1)]);
        const auto* r2 =
            reinterpret_cast<const float*>(&rays[std::min<size_t>(lane + 2, size - 1)]);
        const auto* r3 =
            reinterpret_cast<const float*>(&rays[std::min<size_t>(lane + 3, size - 1)]);
        __m128 a0 = _mm_loadu_ps(r0), a1 = _mm_loadu_ps(r1), a2 = _mm_loadu_ps(r2),
               a3 = _mm_loadu_ps(r3);
        _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
        _mm_store_ps(packet.org_x + lane, a0);
        _mm_store_ps(packet.org_y + lane, a1);
        _mm_store_ps(packet.org_z + lane, a2);
        _mm_store_ps(packet.dir_x + lane, a3);
        __m128 b0 = _mm_loadu_ps(r0 + 4), b1 = _mm_loadu_ps(r1 + 4), b2 = _mm_loadu_ps(r2 + 4),
               b3 = _mm_loadu_ps(r3 + 4);
        _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
        _mm_store_ps(packet.dir_y + lane, b0);
        _mm_store_ps(packet.dir_z + lane, b1);
        _mm_store_ps(packet.tnear + lane, b2);
        _mm_store_ps(packet.tfar + lane, b3);
        _mm_store_ps(packet.time + lane, zero);
        _mm_store_ps(reinterpret_cast<float*>(packet.mask + lane), all_ones);
        _mm_store_ps(reinterpret_cast<float*>(packet.id + lane), zero);
        _mm_store_ps(reinterpret_cast<float*>(packet.flags + lane), zero);
    }
}
#else
// Lane `lane` of a packet, written field by field into Embree's structure-of-arrays layout.
void set_lane(RTCRay16& packet, unsigned lane, const Ray& ray) {
    packet.org_x[lane] = ray.origin.x;
    packet.org_y[lane] = ray.origin.y;
    packet.org_z[lane] = ray.origin.z;
    packet.tnear[lane] = ray.tmin;
    packet.dir_x[lane] = ray.direction.x;
    packet.dir_y[lane] = ray.direction.y;
    packet.dir_z[lane] = ray.direction.z;
    packet.time[lane] = 0.0f;
    packet.tfar[lane] = ray.tmax;
    packet.mask[lane] = 0xFFFFFFFFu;
    packet.id[lane] = 0;
    packet.flags[lane] = 0;
}

// The packet's lanes from `size` rays (1..kPacket); lanes past `size` repeat the last ray, so
// Embree never reads uninitialised values.
void set_lanes(RTCRay16& packet, const Ray* rays, size_t size) {
    for (unsigned lane = 0; lane < kPacket; ++lane)
        set_lane(packet, lane, rays[std::min<size_t>(lane, size - 1)]);
}
#endif

Hit hit_of_lane(const RTCRayHit16& packet, unsigned lane) {
    Hit hit;
    if (packet.hit.geomID[lane] == RTC_INVALID_GEOMETRY_ID) return hit;
    hit.t = packet.ray.tfar[lane];
    hit.instance_id = instance_of(packet.hit.geomID[lane], packet.hit.instID[0][lane]);
    hit.triangle_id = packet.hit.primID[lane];
    hit.barycentrics = vec2(packet.hit.u[lane], packet.hit.v[lane]);
    hit.geometric_normal =
        vec3(packet.hit.Ng_x[lane], packet.hit.Ng_y[lane], packet.hit.Ng_z[lane]);
    return hit;
}

// The packet's first `size` hits, as hit_of_lane gives them. In SSE2 four lanes at a time: a
// Hit is eight packed 32-bit words (t, instance, triangle, u, v, Ng), so the lanes' words are
// chosen (a miss's are Hit{}'s, instance_of's choice between instID and geomID) with masks and
// turned into four Hits by two 4 x 4 transposes: only moves, the same bits as hit_of_lane.
void read_hits(const RTCRayHit16& packet, Hit* hits, size_t size) {
    unsigned lane = 0;
#if defined(__SSE2__)
    static_assert(sizeof(Hit) == 8 * sizeof(float) && offsetof(Hit, t) == 0 &&
                      offsetof(Hit, instance_id) == 4 && offsetof(Hit, triangle_id) == 8 &&
                      offsetof(Hit, barycentrics) == 12 && offsetof(Hit, geometric_normal) == 20,
                  "Hit is eight packed words: t, instance, triangle, u, v, Ng");
    static_assert(kInvalidId == RTC_INVALID_GEOMETRY_ID, "a miss's ids are Embree's invalid id");
    const __m128 invalid = _mm_castsi128_ps(_mm_set1_epi32(int(RTC_INVALID_GEOMETRY_ID)));
    const __m128 infinity = _mm_set1_ps(Hit{}.t);
    // mask ? a : b, bit by bit.
    const auto select = [](__m128 mask, __m128 a, __m128 b) {
        return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
    };
    const auto words = [](const auto* lanes) {
        return _mm_load_ps(reinterpret_cast<const float*>(lanes));
    };
    for (; lane + 4 <= size; lane += 4) {
        const __m128 geometry = words(packet.hit.geomID + lane);
        const __m128 instance = words(packet.hit.instID[0] + lane);
        const __m128 miss = _mm_castsi128_ps(
            _mm_cmpeq_epi32(_mm_castps_si128(geometry), _mm_castps_si128(invalid)));
        const __m128 flattened = _mm_castsi128_ps(
            _mm_cmpeq_epi32(_mm_castps_si128(instance), _mm_castps_si128(invalid)));
        __m128 t = select(miss, infinity, words(packet.ray.tfar + lane));
        __m128 id = select(miss, invalid, select(flattened, geometry, instance));
        __m128 triangle = select(miss, invalid, words(packet.hit.primID + lane));
        __m128 u = _mm_andnot_ps(miss, words(packet.hit.u + lane));
        __m128 v = _mm_andnot_ps(miss, words(packet.hit.v + lane));
        __m128 nx = _mm_andnot_ps(miss, words(packet.hit.Ng_x + lane));
        __m128 ny = _mm_andnot_ps(miss, words(packet.hit.Ng_y + lane));
        __m128 nz = _mm_andnot_ps(miss, words(packet.hit.Ng_z + lane));
        _MM_TRANSPOSE4_PS(t, id, triangle, u);
        _MM_TRANSPOSE4_PS(v, nx, ny, nz);
        auto* out = reinterpret_cast<float*>(hits + lane);
        _mm_storeu_ps(out, t);
        _mm_storeu_ps(out + 4, v);
        _mm_storeu_ps(out + 8, id);
        _mm_storeu_ps(out + 12, nx);
        _mm_storeu_ps(out + 16, triangle);
        _mm_storeu_ps(out + 20, ny);
        _mm_storeu_ps(out + 24, u);
        _mm_storeu_ps(out + 28, nz);
    }
#endif
    for (; lane < size; ++lane) hits[lane] = hit_of_lane(packet, lane);
}

// For each packet of up to kPacket consecutive rays: fill(rays, size) sets its lanes
// (set_lanes), trace(valid), then read(begin, size) takes the results of rays
// [begin, begin + size).
template <typename Fill, typename Trace, typename Read>
void for_each_packet(const Ray* rays, size_t count, Fill&& fill, Trace&& trace, Read&& read) {
    alignas(64) int valid[kPacket];
    for (size_t begin = 0; begin < count; begin += kPacket) {
        const size_t size = std::min<size_t>(kPacket, count - begin);
        for (unsigned lane = 0; lane < kPacket; ++lane) valid[lane] = lane < size ? -1 : 0;
        fill(rays + begin, size);
        trace(valid);
        read(begin, size);
    }
}

void intersect_packets(RTCScene scene, RTCIntersectContext* context, const Ray* rays, Hit* hits,
                       size_t count) {
    alignas(64) RTCRayHit16 packet;
    for_each_packet(
        rays, count,
        [&](const Ray* first, size_t size) {
            set_lanes(packet.ray, first, size);
            std::fill(std::begin(packet.hit.geomID), std::end(packet.hit.geomID),
                      RTC_INVALID_GEOMETRY_ID);
            std::fill(std::begin(packet.hit.instID[0]), std::end(packet.hit.instID[0]),
                      RTC_INVALID_GEOMETRY_ID);
        },
        [&](const int* valid) { rtcIntersect16(valid, scene, context, &packet); },
        [&](size_t begin, size_t size) { read_hits(packet, hits + begin, size); });
}

void occluded_packets(RTCScene scene, RTCIntersectContext* context, const Ray* rays,
                      uint8_t* occluded, size_t count) {
    alignas(64) RTCRay16 packet;
    for_each_packet(
        rays, count, [&](const Ray* first, size_t size) { set_lanes(packet, first, size); },
        [&](const int* valid) { rtcOccluded16(valid, scene, context, &packet); },
        [&](size_t begin, size_t size) {
            for (unsigned lane = 0; lane < size; ++lane)
                occluded[begin + lane] = occluded_flag(packet.tfar[lane]);
        });
}

// What a top-level build is called in errors: the flattened meshes' triangles are built there,
// so a scene of one flattened mesh names that mesh, as its own BVH build would.
std::string top_level_operation(const std::vector<Mesh>& meshes,
                                const std::vector<Instance>& instances,
                                const std::vector<uint8_t>& flattened) {
    size_t flat = 0, largest = 0;
    for (size_t i = 0; i < instances.size(); ++i) {
        if (!flattened[i]) continue;
        const size_t triangles = meshes[instances[i].mesh_id].triangles.size();
        if (flat++ == 0 || triangles > meshes[instances[largest].mesh_id].triangles.size())
            largest = i;
    }
    if (flat == 0) return "building the top-level BVH over the instances";
    const std::string mesh = scene_detail::label("mesh", meshes[instances[largest].mesh_id].name);
    if (flat == instances.size() && flat == 1) return "building the BVH of " + mesh;
    return format_message("building the top-level BVH over the instances (", flat,
                          " meshes flattened into it, the largest ", mesh, ")");
}

}  // namespace

uint64_t estimate_bvh_bytes(const std::vector<Mesh>& meshes,
                            const std::vector<Instance>& instances) {
    uint64_t bytes = 0;
    for (const Mesh& mesh : meshes) {
        if (mesh.triangles.empty()) continue;
        bytes += mesh.positions.size() * sizeof(vec3) + mesh.triangles.size() * sizeof(uvec3);
        bytes += mesh.triangles.size() * kMinBvhBytesPerTriangle;
    }
    return bytes + instances.size() * kMinBytesPerInstance;
}

struct EmbreeScene::Impl {
    EmbreeDevice device;                   // declared first: released last
    std::vector<SceneHandle> mesh_scenes;  // null for meshes without a BVH of their own
    SceneHandle top;
    std::vector<GeometryHandle> top_geometries;  // per instance; null for those left out
    std::vector<uint8_t> top_flattened;          // per instance, as build_instances was told

    // Throws if Embree recorded an error during `operation`, or returned null without one.
    template <typename T>
    T* require(T* object, const std::string& operation) {
        device.throw_if_error(operation);
        if (!object) throw Internal(format_message(operation, ": Embree returned null"));
        return object;
    }

    SceneHandle new_scene(const std::string& operation) {
        SceneHandle scene(require(rtcNewScene(device.get()), operation));
        // Robust traversal: no missed hits on shared edges, which photons and shadow rays would
        // turn into light leaks.
        rtcSetSceneFlags(scene.get(), RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(scene.get(), RTC_BUILD_QUALITY_MEDIUM);
        return scene;
    }

    void commit_scene(RTCScene scene, BuildMonitor& monitor, const std::string& operation) {
        rtcSetSceneProgressMonitorFunction(scene, &on_build_progress, &monitor);
        rtcCommitScene(scene);
        rtcSetSceneProgressMonitorFunction(scene, nullptr, nullptr);
        device.throw_if_error(operation);
    }

    // A committed triangle geometry of `mesh`, in world space when world_from_object is given.
    GeometryHandle new_triangles(const Mesh& mesh, const mat4* world_from_object,
                                 const std::string& operation);
    SceneHandle build_mesh(const Mesh& mesh, BuildMonitor& monitor);
    GeometryHandle new_instance(const Instance& instance);
};

GeometryHandle EmbreeScene::Impl::new_triangles(const Mesh& mesh, const mat4* world_from_object,
                                                const std::string& operation) {
    GeometryHandle geometry(
        require(rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE), operation));
    auto* vertices = static_cast<vec3*>(
        require(rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0,
                                        RTC_FORMAT_FLOAT3, sizeof(vec3), mesh.positions.size()),
                operation));
    if (world_from_object) {
        // Transformed as Scene::surface_point transforms a hit's position, so a flattened
        // mesh's triangles lie where an instanced one's hit points do.
        for (size_t i = 0; i < mesh.positions.size(); ++i)
            vertices[i] = vec3(*world_from_object * vec4(mesh.positions[i], 1.0f));
    } else {
        std::memcpy(vertices, mesh.positions.data(), mesh.positions.size() * sizeof(vec3));
    }
    void* indices =
        require(rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_INDEX, 0,
                                        RTC_FORMAT_UINT3, sizeof(uvec3), mesh.triangles.size()),
                operation);
    std::memcpy(indices, mesh.triangles.data(), mesh.triangles.size() * sizeof(uvec3));
    rtcCommitGeometry(geometry.get());
    return geometry;
}

SceneHandle EmbreeScene::Impl::build_mesh(const Mesh& mesh, BuildMonitor& monitor) {
    const std::string operation =
        "building the BVH of " + scene_detail::label("mesh", mesh.name);
    SceneHandle scene = new_scene(operation);
    GeometryHandle geometry = new_triangles(mesh, nullptr, operation);
    rtcAttachGeometryByID(scene.get(), geometry.get(), 0);
    device.throw_if_error(operation);
    commit_scene(scene.get(), monitor, operation);
    return scene;
}

GeometryHandle EmbreeScene::Impl::new_instance(const Instance& instance) {
    GeometryHandle geometry(rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_INSTANCE));
    if (!geometry) return geometry;  // the caller's throw_if_error reports why
    rtcSetGeometryInstancedScene(geometry.get(), mesh_scenes[instance.mesh_id].get());
    // GLM stores column-major, which is Embree's FLOAT4X4_COLUMN_MAJOR layout.
    rtcSetGeometryTransform(geometry.get(), 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR,
                            &instance.world_from_object[0][0]);
    rtcCommitGeometry(geometry.get());
    return geometry;
}

EmbreeScene::EmbreeScene() : impl_(std::make_unique<Impl>()) {}
EmbreeScene::~EmbreeScene() = default;

void EmbreeScene::set_memory_budget(uint64_t bytes) { impl_->device.set_memory_budget(bytes); }
uint64_t EmbreeScene::peak_bytes() const { return impl_->device.peak_bytes(); }
void EmbreeScene::reset_peak() { impl_->device.reset_peak(); }

void EmbreeScene::clear() {
    impl_->top.reset();
    impl_->top_geometries.clear();
    impl_->mesh_scenes.clear();
}

uint64_t EmbreeScene::build_meshes(const std::vector<Mesh>& meshes,
                                   const std::vector<uint8_t>& instanced, Progress* progress) {
    clear();
    impl_->device.clear_error();
    BuildMonitor monitor{progress, 0, std::max<uint64_t>(meshes.size(), 1)};
    uint64_t built = 0;
    try {
        for (size_t i = 0; i < meshes.size(); ++i) {
            throw_if_cancelled(progress);
            const bool needed = instanced[i] && !meshes[i].triangles.empty();
            impl_->mesh_scenes.push_back(needed ? impl_->build_mesh(meshes[i], monitor)
                                                : SceneHandle());
            built += needed ? 1 : 0;
            ++monitor.index;
        }
    } catch (...) {
        clear();
        throw;
    }
    return built;
}

void EmbreeScene::build_instances(const std::vector<Mesh>& meshes,
                                  const std::vector<Instance>& instances,
                                  const std::vector<uint8_t>& flattened, Progress* progress) {
    impl_->top.reset();
    impl_->top_geometries.clear();
    impl_->device.clear_error();
    const std::string operation = top_level_operation(meshes, instances, flattened);
    // Kept per instance so that move_instances edits them in place. Not RTC_SCENE_FLAG_DYNAMIC:
    // on Debian's Embree 3.13 it did not make the commit after a move any cheaper (a moved
    // block still cost a rebuild over the flattened 502k-triangle sphere, bench/
    // scene_query_bench.cpp); Scene instances every mesh of a moving scene instead.
    SceneHandle top = impl_->new_scene(operation);
    std::vector<GeometryHandle> geometries(instances.size());
    for (size_t i = 0; i < instances.size(); ++i) {
        if (i % kInstancesPerPoll == 0) throw_if_cancelled(progress);
        const Instance& instance = instances[i];
        if (meshes[instance.mesh_id].triangles.empty()) continue;
        if (!flattened[i] && (instance.mesh_id >= impl_->mesh_scenes.size() ||
                              !impl_->mesh_scenes[instance.mesh_id]))
            throw Internal(format_message(operation, ": instance ", i, " uses mesh ",
                                          instance.mesh_id, " which has no BVH; build_meshes first"));
        geometries[i] = flattened[i] ? impl_->new_triangles(meshes[instance.mesh_id],
                                                            &instance.world_from_object, operation)
                                     : impl_->new_instance(instance);
        if (geometries[i]) rtcAttachGeometryByID(top.get(), geometries[i].get(), uint32_t(i));
    }
    impl_->device.throw_if_error(operation);
    BuildMonitor monitor{progress, 0, 1};
    impl_->commit_scene(top.get(), monitor, operation);
    impl_->top = std::move(top);
    impl_->top_geometries = std::move(geometries);
    impl_->top_flattened = flattened;
}

void EmbreeScene::move_instances(const std::vector<Instance>& instances,
                                 const std::vector<uint32_t>& moved, Progress* progress) {
    impl_->device.clear_error();
    const std::string operation = "moving instances in the top-level BVH";
    if (!impl_->top || impl_->top_geometries.size() != instances.size())
        throw Internal(operation + ": the top level was not built; build_instances first");
    for (uint32_t i : moved) {
        RTCGeometry geometry = impl_->top_geometries[i].get();
        if (!geometry) continue;  // a mesh without triangles
        if (impl_->top_flattened[i])
            throw Internal(format_message(operation, ": instance ", i,
                                          " is flattened; build_instances instead"));
        rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT4X4_COLUMN_MAJOR,
                                &instances[i].world_from_object[0][0]);
        rtcCommitGeometry(geometry);
    }
    impl_->device.throw_if_error(operation);
    BuildMonitor monitor{progress, 0, 1};
    impl_->commit_scene(impl_->top.get(), monitor, operation);
}

// Incoherent rays one by one (rtcIntersect1/rtcOccluded1): Embree 3 traces an incoherent ray
// stream ray by ray anyway, after copying it, so the stream API would add only the copy.
void EmbreeScene::intersect(const Ray* rays, Hit* hits, size_t count,
                            RayCoherence coherence) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (coherence == RayCoherence::Coherent && count > 1) {
        intersect_packets(impl_->top.get(), &context, rays, hits, count);
        return;
    }
    RTCRayHit ray_hit;
    for (size_t i = 0; i < count; ++i) {
        to_embree(rays[i], ray_hit);
        rtcIntersect1(impl_->top.get(), &context, &ray_hit);
        hits[i] = from_embree(ray_hit);
    }
}

void EmbreeScene::occluded(const Ray* rays, uint8_t* occluded, size_t count,
                           RayCoherence coherence) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    if (coherence == RayCoherence::Coherent && count > 1) {
        occluded_packets(impl_->top.get(), &context, rays, occluded, count);
        return;
    }
    RTCRay ray;
    for (size_t i = 0; i < count; ++i) {
        to_embree(rays[i], ray);
        rtcOccluded1(impl_->top.get(), &context, &ray);
        occluded[i] = occluded_flag(ray.tfar);
    }
}

}  // namespace shgi
