// Flattening (scene/embree_scene.h): a mesh used by one instance is copied into the top-level
// BVH in world space, a mesh used by several stays instanced, and callers cannot tell the
// difference: the same rays give the same instance and triangle ids, the same t, barycentrics
// and world-space geometric normals (within float rounding: a flattened triangle's vertices are
// rounded once more, in world space) as with every mesh instanced, also after instances move.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "render/render_test_scenes.h"
#include "scene/embree_reference.h"
#include "scene/scene.h"

namespace shgi {
namespace {

// Relative difference allowed between a flattened and an instanced hit: both run Embree's float
// triangle test, on vertices and rays rounded differently (world space against object space),
// a few ulps (1.2e-7 each) apart.
constexpr float kRounding = 1e-4f;
constexpr int kRays = 4000;

// A room, a rotated and unevenly scaled sphere, a mirrored box (negative determinant: Embree's
// normal on its world-space copy faces the other way) and a small box used twice.
Scene mixed_scene(bool flatten) {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    scene.add_instance(scene.add_mesh(test::inward_box(3.0f)), mat4(1.0f), "room");
    const mat4 sphere = glm::scale(glm::rotate(glm::translate(mat4(1.0f), vec3(1.0f, 0.2f, 0.0f)),
                                               0.7f, glm::normalize(vec3(1.0f, 2.0f, 3.0f))),
                                   vec3(1.0f, 0.7f, 1.3f));
    scene.add_instance(scene.add_mesh(test::uv_sphere(0.6f)), sphere, "sphere");
    scene.add_instance(scene.add_mesh(test::inward_box(0.4f)),
                       glm::scale(glm::translate(mat4(1.0f), vec3(-1.2f, 1.0f, 0.3f)),
                                  vec3(-1.0f, 1.5f, 1.0f)),
                       "mirrored");
    const uint32_t shared = scene.add_mesh(test::inward_box(0.3f));
    scene.add_instance(shared, glm::translate(mat4(1.0f), vec3(0.0f, -1.5f, 0.5f)), "left");
    scene.add_instance(shared,
                       glm::rotate(glm::translate(mat4(1.0f), vec3(0.5f, 1.8f, -0.8f)), 0.4f,
                                   vec3(0.0f, 0.0f, 1.0f)),
                       "right");
    CommitSettings settings;
    settings.flatten_single_use_meshes = flatten;
    scene.commit(settings);
    return scene;
}

std::vector<Ray> random_rays(uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::vector<Ray> rays(kRays);
    for (Ray& ray : rays) {
        ray.origin = 2.5f * vec3(unit(random), unit(random), unit(random));
        ray.direction = vec3(unit(random), unit(random), unit(random));
    }
    return rays;
}

void expect_same_hit(const Hit& flat, const Hit& instanced, size_t i) {
    ASSERT_EQ(flat.valid(), instanced.valid()) << "ray " << i;
    if (!flat.valid()) return;
    ASSERT_EQ(flat.instance_id, instanced.instance_id) << "ray " << i;
    ASSERT_EQ(flat.triangle_id, instanced.triangle_id) << "ray " << i;
    EXPECT_NEAR(flat.t, instanced.t, kRounding * std::max(instanced.t, 1.0f)) << "ray " << i;
    EXPECT_NEAR(flat.barycentrics.x, instanced.barycentrics.x, kRounding) << "ray " << i;
    EXPECT_NEAR(flat.barycentrics.y, instanced.barycentrics.y, kRounding) << "ray " << i;
    const float length = glm::length(instanced.geometric_normal);
    EXPECT_LT(glm::length(flat.geometric_normal - instanced.geometric_normal), kRounding * length)
        << "ray " << i;
}

// Every query path (single rays, incoherent and coherent batches, occlusion) agrees.
void expect_same_hits(const Scene& flat, const Scene& instanced, uint32_t seed) {
    const std::vector<Ray> rays = random_rays(seed);
    for (RayCoherence coherence : {RayCoherence::Incoherent, RayCoherence::Coherent}) {
        std::vector<Hit> flat_hits, instanced_hits;
        flat.intersect(rays, flat_hits, nullptr, coherence);
        instanced.intersect(rays, instanced_hits, nullptr, coherence);
        for (size_t i = 0; i < rays.size(); ++i)
            expect_same_hit(flat_hits[i], instanced_hits[i], i);
        std::vector<uint8_t> flat_occluded, instanced_occluded;
        flat.occluded(rays, flat_occluded, nullptr, coherence);
        instanced.occluded(rays, instanced_occluded, nullptr, coherence);
        EXPECT_EQ(flat_occluded, instanced_occluded);
    }
    for (size_t i = 0; i < 100; ++i)
        expect_same_hit(flat.intersect(rays[i]), instanced.intersect(rays[i]), i);
}

TEST(SceneFlatten, SingleUseAndSmallSharedMeshesAreFlattened) {
    const Scene flat = mixed_scene(true);
    const Scene instanced = mixed_scene(false);
    EXPECT_EQ(flat.stats().flattened_instances, 5u)
        << "room, sphere, mirrored box and both copies of the small shared box";
    EXPECT_EQ(instanced.stats().flattened_instances, 0u);
    EXPECT_EQ(flat.stats().bvh_builds, 1u) << "the top level only";
    EXPECT_EQ(instanced.stats().bvh_builds, 5u) << "four mesh BVHs and the top level";
}

// A shared mesh whose copies would hold more than kMaxFlattenedCopyTriangles keeps one BVH,
// instanced per use; at the limit it is copied.
TEST(SceneFlatten, LargeSharedMeshesStayInstanced) {
    // 2 * rings * segments triangles, less the poles' degenerate ones.
    for (const int rings : {128, 64}) {
        SCOPED_TRACE(rings);
        Scene scene;
        const uint32_t mesh = scene.add_mesh(test::uv_sphere(0.5f, rings, 256));
        scene.add_instance(mesh, mat4(1.0f));
        scene.add_instance(mesh, glm::translate(mat4(1.0f), vec3(2.0f, 0.0f, 0.0f)));
        scene.commit();
        const uint64_t copies = 2 * scene.meshes()[mesh].triangles.size();
        EXPECT_EQ(copies > kMaxFlattenedCopyTriangles, rings == 128) << copies;
        EXPECT_EQ(scene.stats().flattened_instances, rings == 128 ? 0u : 2u);
    }
}

TEST(SceneFlatten, FlattenedAndInstancedMeshesGiveTheSameHits) {
    const Scene flat = mixed_scene(true);
    const Scene instanced = mixed_scene(false);
    expect_same_hits(flat, instanced, 1);
    // Hits on every kind of instance were compared, so no kind went untested.
    std::vector<Hit> hits;
    flat.intersect(random_rays(1), hits);
    std::vector<int> per_instance(5, 0);
    for (const Hit& hit : hits)
        if (hit.valid()) ++per_instance[hit.instance_id];
    for (int count : per_instance) EXPECT_GT(count, 0);
}

// A moved flattened instance is rebuilt: its scene instances every mesh from then on (a move
// then rebuilds only the top level), and hits stay those of the instanced scene.
TEST(SceneFlatten, MovedInstancesGiveTheSameHitsAsInstancedOnes) {
    Scene flat = mixed_scene(true);
    Scene instanced = mixed_scene(false);
    const mat4 moved_sphere = glm::rotate(glm::translate(mat4(1.0f), vec3(-0.5f, -0.6f, -1.0f)),
                                          1.1f, vec3(0.0f, 1.0f, 0.0f));
    const mat4 moved_box = glm::translate(mat4(1.0f), vec3(1.5f, -1.0f, 1.0f));
    for (Scene* scene : {&flat, &instanced}) {
        scene->set_instance_transform(1, moved_sphere);  // flattened in `flat`
        scene->set_instance_transform(3, moved_box);     // instanced in both
    }
    flat.commit();
    CommitSettings every_mesh_instanced;
    every_mesh_instanced.flatten_single_use_meshes = false;
    instanced.commit(every_mesh_instanced);
    EXPECT_EQ(flat.stats().flattened_instances, 0u) << "a moving scene instances every mesh";
    expect_same_hits(flat, instanced, 2);
    // A ray through the sphere's new centre hits it there.
    const Hit hit = flat.intersect(Ray{vec3(-0.5f, -0.6f, 2.9f), vec3(0.0f, 0.0f, -1.0f)});
    EXPECT_EQ(hit.instance_id, 1u);
    EXPECT_NEAR(hit.t, 2.9f + 1.0f - 0.6f, 1e-2f) << "the sphere's top, radius 0.6";
}

// The copy budget is the scene's, not each mesh's: two shared meshes whose copies each fit it
// but not together, the first (in mesh order) is copied and the second instanced.
TEST(SceneFlatten, SharedMeshesShareOneCopyBudget) {
    Scene scene;
    for (int mesh = 0; mesh < 2; ++mesh) {
        const uint32_t id = scene.add_mesh(test::uv_sphere(0.5f, 64, 256));
        for (int copy = 0; copy < 2; ++copy)
            scene.add_instance(id, glm::translate(mat4(1.0f), vec3(2.0f * copy, 2.0f * mesh, 0)));
    }
    scene.commit();
    const uint64_t copies = 2 * scene.meshes()[0].triangles.size();
    ASSERT_LE(copies, kMaxFlattenedCopyTriangles);
    ASSERT_GT(2 * copies, kMaxFlattenedCopyTriangles);
    EXPECT_EQ(scene.stats().flattened_instances, 2u);
    EXPECT_TRUE(scene.intersect(Ray{vec3(0.0f, 2.0f, 2.0f), vec3(0.0f, 0.0f, -1.0f)}).valid());
}

TEST(SceneFlatten, ALargeMeshGainingASecondInstanceBecomesInstanced) {
    Scene scene = mixed_scene(true);
    const uint32_t large = scene.add_mesh(test::uv_sphere(0.5f, 128, 256));
    scene.add_instance(large, glm::translate(mat4(1.0f), vec3(-2.0f, -2.0f, 0.0f)), "large");
    scene.commit();
    EXPECT_EQ(scene.stats().flattened_instances, 6u);
    const Ray ray{vec3(2.0f, 2.0f, 2.0f), vec3(0.0f, 0.0f, -1.0f)};
    scene.add_instance(large, glm::translate(mat4(1.0f), vec3(2.0f, 2.0f, 0.0f)), "second");
    scene.commit();
    EXPECT_EQ(scene.stats().flattened_instances, 5u) << "all but the large sphere's copies";
    const Hit hit = scene.intersect(ray);
    EXPECT_EQ(hit.instance_id, 6u) << "the second large sphere, in the top level as an instance";
    EXPECT_EQ(scene.instances()[hit.instance_id].mesh_id, large);
}

// Flattening must not narrow the rays a scene traces: a quad enlarged 10x would put 10x larger
// numbers into Embree's float triangle test in world space than in its own, so it stays
// instanced and the scene keeps Embree's whole direction range; unscaled, it is flattened.
TEST(SceneFlatten, AnInstanceThatWouldNarrowTheRayRangeStaysInstanced) {
    for (const float scale : {10.0f, 1.0f}) {
        SCOPED_TRACE(scale);
        Scene scene;
        scene.add_instance(scene.add_mesh(test::inward_box(0.5f)),
                           glm::scale(mat4(1.0f), vec3(scale)));
        scene.commit();
        CommitSettings every_mesh_instanced;
        every_mesh_instanced.flatten_single_use_meshes = false;
        Scene instanced;
        instanced.add_instance(instanced.add_mesh(test::inward_box(0.5f)),
                               glm::scale(mat4(1.0f), vec3(scale)));
        instanced.commit(every_mesh_instanced);
        EXPECT_EQ(scene.stats().flattened_instances, scale > 1.0f ? 0u : 1u);
        EXPECT_EQ(scene.ray_limits().origin, instanced.ray_limits().origin);
        EXPECT_EQ(scene.ray_limits().direction, instanced.ray_limits().direction);
        EXPECT_EQ(scene.ray_limits().min_direction, instanced.ray_limits().min_direction);
    }
}

TEST(SceneFlatten, ReferenceSceneGivesTheSameHitsAsScene) {
    const Scene scene = mixed_scene(true);
    const EmbreeReference reference(scene);
    const std::vector<Ray> rays = random_rays(3);
    std::vector<Hit> hits, reference_hits(rays.size());
    scene.intersect(rays, hits, nullptr, RayCoherence::Coherent);
    reference.intersect(rays.data(), reference_hits.data(), rays.size(),
                        RayCoherence::Coherent);
    for (size_t i = 0; i < rays.size(); ++i) {
        ASSERT_EQ(hits[i].instance_id, reference_hits[i].instance_id) << "ray " << i;
        if (!hits[i].valid()) continue;
        EXPECT_NEAR(hits[i].t, reference_hits[i].t, kRounding * std::max(hits[i].t, 1.0f)) << "ray " << i;
    }
}

}  // namespace
}  // namespace shgi
