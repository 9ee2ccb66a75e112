// EmbreeReference: raw Embree on a Scene's triangles, the floor the benchmarks measure Scene's
// queries against (docs/benchmarks.md). Every instance is flattened into one one-level RTCScene
// (world-space vertices, geometry i = instance i, no instancing even for shared meshes), and the
// queries do only what any caller of Embree must: pack rays (rtcIntersect16/rtcOccluded16 over
// 16 consecutive rays for coherent batches, rtcIntersect1/rtcOccluded1 for incoherent ones,
// through EmbreeScene's packing, which stores each lane's fields straight into Embree's layout)
// and copy the hit out. No validation, no normal mapping, no threads: the caller times it on the
// same rays, the same threads and the same chunks as Scene.
//
// A benchmark tool, not a query path: rays must be valid (Debian's Embree aborts on a NaN), and
// hits report Embree's world-space normal with geometry ids as instance ids.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

#include "scene/ray.h"

namespace shgi {

class Scene;

class EmbreeReference {
  public:
    // Copies the triangles of every instance of a committed `scene` (InvalidArgument otherwise)
    // in world space and builds one BVH over them at Scene's quality and flags.
    explicit EmbreeReference(const Scene& scene);
    ~EmbreeReference();
    EmbreeReference(const EmbreeReference&) = delete;
    EmbreeReference& operator=(const EmbreeReference&) = delete;

    // Thread-safe.
    void intersect(const Ray* rays, Hit* hits, size_t count, RayCoherence coherence) const;
    void occluded(const Ray* rays, uint8_t* occluded, size_t count,
                  RayCoherence coherence) const;

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace shgi
