// The Embree BVH behind Scene: one triangle geometry per mesh in its own RTCScene, instanced
// (RTC_GEOMETRY_TYPE_INSTANCE) once per Instance into a top-level RTCScene, all on one device
// per Scene (scene/embree_device.h) whose memory monitor enforces the commit's budget.
//
// This header shows SHGI types only, so scene.cpp and everything else never see Embree
// (STYLE.md habit 7). Rays must already be validated (is_valid_ray): Embree is not told about
// invalid ones. Hits come back with the geometric normal in the mesh's object space (Embree's
// cross(p1 - p0, p2 - p0), unnormalised); Scene maps it to world space.
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

    // (Re)builds one BVH per mesh; meshes without triangles get none. Releases the top level.
    // Throws OutOfMemory, Cancelled (progress) or Internal; on failure everything is released.
    void build_meshes(const std::vector<Mesh>& meshes, Progress* progress);
    // (Re)builds the top level over the per-mesh BVHs, keeping them. Instance i gets Embree
    // instance id i; instances of meshes without triangles are left out.
    void build_instances(const std::vector<Instance>& instances, Progress* progress);
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
