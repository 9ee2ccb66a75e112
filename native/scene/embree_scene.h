// The Embree BVH behind Scene, all on one device per Scene (scene/embree_device.h) whose memory
// monitor enforces the commit's budget. Two ways into the top-level RTCScene, as in Cycles:
//  - flattened: an instance whose mesh no other instance uses becomes a triangle geometry of the
//    top level itself, its vertices copied in world space. Rays then traverse one BVH with no
//    instance transform: the common case (most objects are used once) costs what Embree costs.
//  - instanced: a mesh used by several instances keeps one BVH of its own in its own RTCScene,
//    referenced by one RTC_GEOMETRY_TYPE_INSTANCE per instance, so it is stored once.
// Either way, instance i is geometry i of the top level, so a hit names its instance the same.
//
// This header shows SHGI types only, so scene.cpp and everything else never see Embree
// (STYLE.md habit 7). Rays must already be validated (is_valid_ray): Embree is not told about
// invalid ones. Hits come back with Embree's geometric normal, cross(p1 - p0, p2 - p0)
// unnormalised, in the space the triangle was built in: object space for an instanced mesh,
// world space for a flattened one; Scene maps both to its world-space convention.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "scene/mesh.h"
#include "scene/ray.h"
#include "util/progress.h"

namespace shgi {

struct Instance;

// A lower bound on the bytes Embree allocates for these meshes and instances (vertex and index
// buffers plus the smallest BVH Embree builds per triangle): commit() refuses up front a scene
// that cannot fit its budget, before spending time on a build that would fail.
uint64_t estimate_bvh_bytes(const std::vector<Mesh>& meshes,
                            const std::vector<Instance>& instances);

class EmbreeScene {
  public:
    EmbreeScene();
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    void set_memory_budget(uint64_t bytes);
    // Peak bytes Embree held since the last reset_peak() (Scene resets it as a commit begins).
    uint64_t peak_bytes() const;
    void reset_peak();

    // (Re)builds one BVH per mesh with instanced[mesh] != 0; the other meshes (flattened, or
    // without triangles) get none. Releases the top level. Returns the number of BVHs built.
    // Throws OutOfMemory, Cancelled (progress) or Internal; on failure everything is released.
    uint64_t build_meshes(const std::vector<Mesh>& meshes, const std::vector<uint8_t>& instanced,
                          Progress* progress);
    // (Re)builds the top level, keeping the per-mesh BVHs: instance i becomes geometry i, a copy
    // of its mesh in world space when flattened[i] != 0, else an Embree instance of its mesh's
    // BVH (which build_meshes must have built). Instances of meshes without triangles are left
    // out.
    void build_instances(const std::vector<Mesh>& meshes, const std::vector<Instance>& instances,
                         const std::vector<uint8_t>& flattened, Progress* progress);
    // Moves instances `moved` (ids into `instances`, whose transforms changed; none of them
    // flattened) in the built top level and commits it again, keeping the per-mesh BVHs.
    void move_instances(const std::vector<Instance>& instances,
                        const std::vector<uint32_t>& moved, Progress* progress);
    // Releases every Embree object (after a failed build).
    void clear();

    // `count` rays at once (an Embree ray stream); thread-safe after a build.
    void intersect(const Ray* rays, Hit* hits, size_t count,
                   RayCoherence coherence = RayCoherence::Incoherent) const;
    void occluded(const Ray* rays, uint8_t* occluded, size_t count,
                  RayCoherence coherence = RayCoherence::Incoherent) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace shgi
