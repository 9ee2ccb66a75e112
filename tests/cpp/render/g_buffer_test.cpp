// GBuffer against analytic values: a Lambert plane z = 0 under an orthographic camera looking
// straight down from z = 2 m, filled by the preview renderer's primary stage. Every pixel sees
// the plane at depth 2 m, with both normals +Z, albedo the base colour, the material's roughness,
// and a position whose projection falls inside the pixel itself (the sample's jitter). A sphere
// above the plane gives a second object and material, and a pixel beyond the plane a miss.
#include "render/g_buffer.h"

#include <gtest/gtest.h>

#include <cstring>

#include <glm/gtc/matrix_transform.hpp>

#include "render/preview_renderer.h"
#include "render_test_scenes.h"

namespace shgi {
namespace {

constexpr float kAlbedo = 0.8f;
constexpr float kCameraHeight = 2.0f;  // m above the plane
constexpr uint32_t kResolution = 8;
// float32 positions of metre-scale hits are good to ~1e-7 relative; the depth subtracts the
// camera's position, so allow a few ulps of 2 m.
constexpr float kPositionTolerance = 1e-5f;

Scene plane_under_camera(float plane_half) {
    Scene scene;
    scene.add_material(test::lambert(kAlbedo));
    scene.add_instance(scene.add_mesh(test::plane(plane_half)), mat4(1.0f));
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, kCameraHeight), 2.0f, kResolution));
    scene.commit();
    return scene;
}

TEST(GBuffer, StartsAsMisses) {
    const GBuffer g_buffer(3, 2);
    ASSERT_EQ(g_buffer.pixel_count(), 6u);
    for (size_t i = 0; i < g_buffer.pixel_count(); ++i) {
        EXPECT_FALSE(g_buffer.has_surface(i));
        EXPECT_EQ(g_buffer.material_id[i], GBuffer::kNoSurface);
    }
    EXPECT_EQ(g_buffer.index(2, 1), 5u);
}

TEST(GBuffer, PlaneSeenFromAboveHasAnalyticDepthNormalAndAlbedo) {
    const Scene scene = plane_under_camera(50.0f);
    PreviewSettings settings;
    settings.tile_size = 2;  // many tiles: every one must write its own pixels
    PreviewRenderer renderer(scene, settings);
    renderer.render(nullptr, 3);
    const GBuffer& g = renderer.g_buffer();
    ASSERT_EQ(g.width(), int(kResolution));
    ASSERT_EQ(g.height(), int(kResolution));
    const float roughness = scene.materials()[0].roughness;
    for (int y = 0; y < g.height(); ++y)
        for (int x = 0; x < g.width(); ++x) {
            const size_t i = g.index(x, y);
            ASSERT_TRUE(g.has_surface(i)) << x << ", " << y;
            EXPECT_NEAR(g.depth[i], kCameraHeight, kPositionTolerance);
            EXPECT_NEAR(g.position[i].z, 0.0f, kPositionTolerance);
            EXPECT_EQ(g.shading_normal[i], vec3(0.0f, 0.0f, 1.0f));
            EXPECT_EQ(g.geometric_normal[i], vec3(0.0f, 0.0f, 1.0f));
            EXPECT_EQ(g.albedo[i], vec3(kAlbedo));
            EXPECT_EQ(g.roughness[i], roughness);
            EXPECT_EQ(g.object_id[i], 0u);
            EXPECT_EQ(g.material_id[i], 0u);
            vec2 film;
            ASSERT_TRUE(scene.camera().project(g.position[i], &film));
            EXPECT_GE(film.x, float(x) - kPositionTolerance);
            EXPECT_LE(film.x, float(x + 1) + kPositionTolerance);
            EXPECT_GE(film.y, float(y) - kPositionTolerance);
            EXPECT_LE(film.y, float(y + 1) + kPositionTolerance);
        }
}

// A plane of half size 0.5 m covers the middle half of the 2 m view: the outer ring of pixels
// (film x or y < 2 or >= 6) sees nothing, the inner 4 x 4 sees the plane.
TEST(GBuffer, PixelsBeyondThePlaneAreMisses) {
    const Scene scene = plane_under_camera(0.5f);
    PreviewRenderer renderer(scene, PreviewSettings{});
    renderer.render(nullptr, 1);
    const GBuffer& g = renderer.g_buffer();
    for (int y = 0; y < g.height(); ++y)
        for (int x = 0; x < g.width(); ++x) {
            const bool inside = x >= 2 && x < 6 && y >= 2 && y < 6;
            const size_t i = g.index(x, y);
            EXPECT_EQ(g.has_surface(i), inside) << x << ", " << y;
            if (!inside) {
                EXPECT_EQ(g.depth[i], 0.0f);
                EXPECT_EQ(g.albedo[i], vec3(0.0f));
            }
        }
}


// The albedo the preview writes from its MaterialLobeTable is the bits every hit's own BSDF
// would give (class_color_sum), on either side and at any view; materials whose lobes change
// from hit to hit (a glass) have no entry and are summed per hit.
TEST(GBuffer, MaterialTableAlbedoIsEveryHitsClassColorSum) {
    Scene scene = plane_under_camera(50.0f);
    Material plastic = test::lambert(0.3f);
    plastic.diffuse_model = DiffuseModel::Principled;
    plastic.specular = 0.5f;
    plastic.roughness = 0.4f;
    plastic.base_color = vec3(0.9f, 0.3f, 0.1f);
    plastic.name = "plastic";
    Material metal = plastic;
    metal.name = "metal";
    metal.metallic = 0.7f;
    Material glass = plastic;
    glass.name = "glass";
    glass.transmission = 1.0f;
    for (const Material& m : {plastic, metal, glass}) scene.add_material(m);
    scene.commit();
    const MaterialLobeTable table(scene);
    int with_entry = 0;
    for (uint32_t m = 0; m < scene.materials().size(); ++m) {
        const vec3* albedo = table.albedo(m);
        if (albedo == nullptr) continue;
        ++with_entry;
        const Material& material = scene.materials()[m];
        for (bool back_face : {false, true})
            for (float cos_nv : {1.0f, 0.5f, 0.05f}) {
                const vec3 sum = PrincipledBsdf(material, scene.material_terms()[m],
                                                material.base_color, back_face, cos_nv)
                                     .class_color_sum();
                EXPECT_EQ(std::memcmp(albedo, &sum, sizeof(vec3)), 0) << m;
            }
    }
    EXPECT_EQ(with_entry, 3);  // all but the glass
    EXPECT_EQ(table.albedo(3), nullptr);
}

}  // namespace
}  // namespace shgi
