// Edits in place: lights, materials and textures change without any BVH build (a light edit in
// the viewport starts its next frame at once), moved instances rebuild the top level only, and
// mesh edits rebuild their BVHs; what the edits change (emissive triangles, light values) is
// seen by the next commit, and bad ids are refused naming the id and the count.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "render/render_test_scenes.h"
#include "scene/scene.h"
#include "support/expect_error.h"

namespace shgi {
namespace {

using testing::expect_error;

Scene two_boxes() {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    scene.add_material(test::lambert(0.8f));
    const uint32_t box = scene.add_mesh(test::inward_box(1.0f));
    scene.add_instance(box, mat4(1.0f), "a");
    scene.add_instance(box, glm::translate(mat4(1.0f), vec3(5.0f, 0.0f, 0.0f)), "b");
    scene.add_light(test::point_light(vec3(0.0f), 10.0f));
    scene.commit();
    return scene;
}

TEST(SceneEdits, LightsMaterialsAndTexturesChangeWithoutABvhBuild) {
    Scene scene = two_boxes();
    const uint64_t builds = scene.stats().bvh_builds;
    EXPECT_EQ(builds, 1u) << "the top level, the small shared box copied into it twice";
    const Hit before = scene.intersect(Ray{vec3(0.0f), vec3(1.0f, 0.0f, 0.0f)});

    Light brighter = scene.lights()[0];
    brighter.power = 500.0f;
    scene.set_light(0, brighter);
    Material glow = test::lambert(0.5f);
    glow.emission_color = vec3(1.0f);
    glow.emission_strength = 2.0f;
    scene.set_material(0, glow);
    EXPECT_FALSE(scene.committed());
    scene.commit();
    EXPECT_EQ(scene.stats().bvh_builds, builds);
    EXPECT_EQ(scene.lights()[0].power, 500.0f);
    EXPECT_EQ(scene.emissive_triangles().size(), 2u * 12u) << "both boxes now glow";
    const Hit after = scene.intersect(Ray{vec3(0.0f), vec3(1.0f, 0.0f, 0.0f)});
    EXPECT_EQ(after.t, before.t);
    EXPECT_EQ(after.triangle_id, before.triangle_id);

    scene.set_lights({test::point_light(vec3(1.0f), 1.0f), test::point_light(vec3(2.0f), 2.0f)});
    scene.commit();
    EXPECT_EQ(scene.lights().size(), 2u);
    EXPECT_EQ(scene.stats().bvh_builds, builds);
}

TEST(SceneEdits, MovedInstancesRebuildTheTopLevelOnlyAndMeshEditsTheirBvhs) {
    Scene scene = two_boxes();
    const uint64_t builds = scene.stats().bvh_builds;
    // The first move turns the scene to instancing: the box's BVH, then the top level.
    scene.set_instance_transform(1, glm::translate(mat4(1.0f), vec3(0.0f, 7.0f, 0.0f)));
    scene.commit();
    EXPECT_EQ(scene.stats().flattened_instances, 0u);
    EXPECT_EQ(scene.stats().bvh_builds, builds + 2);
    EXPECT_NEAR(scene.intersect(Ray{vec3(0.0f, 7.0f, 0.0f), vec3(1.0f, 0.0f, 0.0f)}).t, 1.0f,
                1e-5f);
    // Later moves rebuild the top level only.
    scene.set_instance_transform(1, glm::translate(mat4(1.0f), vec3(0.0f, 9.0f, 0.0f)));
    scene.commit();
    EXPECT_EQ(scene.stats().bvh_builds, builds + 3);
    EXPECT_NEAR(scene.intersect(Ray{vec3(0.0f, 9.0f, 0.0f), vec3(1.0f, 0.0f, 0.0f)}).t, 1.0f,
                1e-5f);
    scene.set_mesh(0, test::inward_box(2.0f));
    scene.commit();
    EXPECT_EQ(scene.stats().bvh_builds, builds + 3 + 2);
}

TEST(SceneEdits, BadIdsAreRefusedNamingTheCount) {
    Scene scene = two_boxes();
    expect_error<InvalidArgument>([&] { scene.set_light(3, Light{}); },
                                  {"light_id = 3", "1 lights"});
    expect_error<InvalidArgument>([&] { scene.set_material(2, Material{}); },
                                  {"material_id = 2", "2 materials"});
    expect_error<InvalidArgument>([&] { scene.set_texture(0, Texture{}); },
                                  {"texture_id = 0", "0 textures"});
    Light bad;
    bad.power = -1.0f;
    expect_error<InvalidArgument>([&] { scene.set_lights({Light{}, bad}); }, {"power"});
    EXPECT_EQ(scene.lights().size(), 1u) << "a refused list leaves the lights as they were";
}

}  // namespace
}  // namespace shgi
