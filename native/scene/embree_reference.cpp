#include "scene/embree_reference.h"

#include <vector>

#include "scene/embree_scene.h"
#include "scene/scene.h"
#include "util/error.h"

namespace shgi {

struct EmbreeReference::Impl {
    EmbreeScene embree;
};

EmbreeReference::EmbreeReference(const Scene& scene) : impl_(std::make_unique<Impl>()) {
    if (!scene.committed())
        throw InvalidArgument("EmbreeReference: the scene was edited or never committed; call "
                              "commit() first");
    // No mesh keeps a BVH of its own: every instance is flattened into the one level.
    const std::vector<uint8_t> instanced(scene.meshes().size(), 0);
    const std::vector<uint8_t> flattened(scene.instances().size(), 1);
    impl_->embree.build_meshes(scene.meshes(), instanced, nullptr);
    impl_->embree.build_instances(scene.meshes(), scene.instances(), flattened, nullptr);
}

EmbreeReference::~EmbreeReference() = default;

void EmbreeReference::intersect(const Ray* rays, Hit* hits, size_t count,
                                RayCoherence coherence) const {
    impl_->embree.intersect(rays, hits, count, coherence);
}

void EmbreeReference::occluded(const Ray* rays, uint8_t* occluded, size_t count,
                               RayCoherence coherence) const {
    impl_->embree.occluded(rays, occluded, count, coherence);
}

}  // namespace shgi
