// rasterize_texels against exact answers: a unit quad filling UV [0,1]^2 covers every texel
// exactly with world positions equal to its UVs, a triangle's coverage sums to its UV area,
// slivers own the texels they touch, mirrored/outside/collapsed/overlapping UVs are handled as
// documented, bad input is rejected by name, and the map does not depend on the thread count.
#include "bake/texel_rasterizer.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "render/render_test_scenes.h"
#include "scene/scene_test_meshes.h"
#include "support/expect_error.h"
#include "util/error.h"

namespace shgi {
namespace {

using testing::expect_contains;
using testing::rejection;

// Positions, weights and coverages come from double arithmetic rounded once to float.
constexpr float kFloatTolerance = 1e-6f;

TexelRasterSettings settings_for(uint32_t width, uint32_t height, uint32_t samples_per_axis,
                                 const std::string& uv_set = "UVMap") {
    TexelRasterSettings settings;
    settings.width = width;
    settings.height = height;
    settings.samples_per_axis = samples_per_axis;
    settings.uv_set = uv_set;
    return settings;
}

double total_coverage(const TexelMap& map) {
    double sum = 0.0;
    for (float c : map.coverage) sum += c;
    return sum;
}

double total_weight(const TexelMap& map) {
    double sum = 0.0;
    for (const TexelSample& sample : map.samples) sum += sample.weight;
    return sum;
}

// Twice the signed area of the triangle a, b, c.
float twice_area(const vec2& a, const vec2& b, const vec2& c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

TEST(TexelRasterizer, UnitQuadCoversEveryTexelExactly) {
    const Mesh quad = test::unit_quad();
    // n = 2 puts the stratum centres (0.25, 0.25) and (0.75, 0.75) of the diagonal texels on the
    // shared diagonal: the tie rule must give each to exactly one triangle.
    const TexelMap map = rasterize_texels(quad, mat4(1.0f), settings_for(8, 4, 2));
    ASSERT_EQ(map.texel_count(), 32u);
    ASSERT_EQ(map.sample_offsets.size(), 33u);
    for (uint64_t t = 0; t < map.texel_count(); ++t) {
        EXPECT_FLOAT_EQ(map.coverage[t], 1.0f) << "texel " << t;
        EXPECT_EQ(map.sample_count(t), 4u) << "texel " << t;
    }
    EXPECT_NEAR(total_coverage(map), 32.0, 32 * kFloatTolerance);
    EXPECT_NEAR(total_weight(map), 32.0, 32 * kFloatTolerance);
    EXPECT_EQ(map.report.triangles, 2u);
    EXPECT_EQ(map.report.conservative_samples, 0u);
    EXPECT_EQ(map.report.clipped_triangles, 0u);
    EXPECT_EQ(map.report.overlapping_texels, 0u);
    for (const TexelSample& sample : map.samples) {
        // The quad's positions equal its UVs: every sample lies where its UV says.
        EXPECT_NEAR(sample.position.x, sample.uv.x, kFloatTolerance);
        EXPECT_NEAR(sample.position.y, sample.uv.y, kFloatTolerance);
        EXPECT_EQ(sample.position.z, 0.0f);
        EXPECT_EQ(sample.normal, vec3(0, 0, 1));
        EXPECT_EQ(sample.geometric_normal, vec3(0, 0, 1));
        EXPECT_GT(sample.weight, 0.0f);
        EXPECT_GT(sample.ray_origin.z, 0.0f);  // off the surface, on the front side
    }
    // Texel (x, y) covers UV [x/8, (x+1)/8] x [y/4, (y+1)/4]; row 0 is at v = 0.
    const TexelSample* first = map.samples_begin(map.texel_index(5, 2));
    EXPECT_NEAR(first->uv.x, 5.25f / 8.0f, kFloatTolerance);
    EXPECT_NEAR(first->uv.y, 2.25f / 4.0f, kFloatTolerance);
}

TEST(TexelRasterizer, WorldPositionsAtTexelCentresFollowTheTransform) {
    const Mesh quad = test::unit_quad();
    const mat4 world_from_object = glm::translate(mat4(1.0f), vec3(1.0f, -2.0f, 3.0f)) *
                                   glm::scale(mat4(1.0f), vec3(2.0f, 4.0f, 1.0f));
    const TexelMap map = rasterize_texels(quad, world_from_object, settings_for(4, 4, 1));
    // One sample per texel at its centre, except on the diagonal where the triangle that does
    // not own the centre adds its conservative sample at the same point.
    EXPECT_EQ(map.report.conservative_samples, 4u);
    for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 4; ++x) {
            const uint64_t t = map.texel_index(x, y);
            EXPECT_EQ(map.sample_count(t), x == y ? 2u : 1u);
            const vec3 expected(1.0f + 2.0f * (x + 0.5f) / 4.0f, -2.0f + 4.0f * (y + 0.5f) / 4.0f,
                                3.0f);
            for (const TexelSample* s = map.samples_begin(t); s != map.samples_end(t); ++s) {
                EXPECT_NEAR(glm::length(s->position - expected), 0.0f, 4 * kFloatTolerance)
                    << "texel (" << x << ", " << y << ")";
                // 2 m x 4 m over 4 x 4 texels: each texel is 0.5 m x 1 m, sqrt(0.5) m on average.
                EXPECT_FLOAT_EQ(s->texel_size, std::sqrt(0.5f));
                EXPECT_EQ(s->normal, vec3(0, 0, 1));
            }
            EXPECT_FLOAT_EQ(map.coverage[t], 1.0f);
        }
}

TEST(TexelRasterizer, CoveredAreaOfATriangleEqualsItsUvArea) {
    Mesh mesh = test::triangle(vec3(0, 0, 0), vec3(2, 0, 0), vec3(0, 3, 1));
    const vec2 a(0.11f, 0.13f), b(0.83f, 0.27f), c(0.35f, 0.91f);
    mesh.uv_sets = {{"LightmapUV", {a, b, c}}};
    const uint32_t resolution = 64, n = 3;
    TexelRasterSettings settings = settings_for(resolution, resolution, n, "LightmapUV");
    const TexelMap map = rasterize_texels(mesh, mat4(1.0f), settings);
    const double uv_area = 0.5 * twice_area(a, b, c);
    const double texels = double(resolution) * resolution;
    // Weights are exact clipped areas: the sum matches to float rounding, not sampling error.
    EXPECT_NEAR(total_weight(map) / texels, uv_area, 1e-6);
    EXPECT_NEAR(total_coverage(map) / texels, uv_area, 1e-6);
    // The sample count estimates the area to within the samples along the border.
    const double sampled = double(map.samples.size() - map.report.conservative_samples) /
                           (texels * n * n);
    const double perimeter = glm::length(b - a) + glm::length(c - b) + glm::length(a - c);
    EXPECT_NEAR(sampled, uv_area, perimeter / (resolution * n));
    // Every sample lies in its texel and inside the triangle, at the world point its UV maps to.
    const vec3 world_normal = glm::normalize(vec3(0, -2, 6));  // (2,0,0) x (0,3,1) = (0,-2,6)
    for (uint64_t t = 0; t < map.texel_count(); ++t) {
        const float x = float(t % resolution), y = float(t / resolution);
        for (const TexelSample* s = map.samples_begin(t); s != map.samples_end(t); ++s) {
            const vec2 texel_uv = s->uv * float(resolution);
            EXPECT_TRUE(texel_uv.x >= x && texel_uv.x <= x + 1 && texel_uv.y >= y &&
                        texel_uv.y <= y + 1);
            const float area = twice_area(a, b, c);
            const float b1 = twice_area(a, s->uv, c) / area, b2 = twice_area(a, b, s->uv) / area;
            EXPECT_GE(std::min({b1, b2, 1.0f - b1 - b2}), -1e-5f);
            const vec3 expected = b1 * vec3(2, 0, 0) + b2 * vec3(0, 3, 1);
            EXPECT_LT(glm::length(s->position - expected), 1e-5f);
            EXPECT_LT(glm::length(s->geometric_normal - world_normal), 1e-6f);
        }
    }
}

// A sliver in texel row 8 of a 16 x 16 map, between v = 8.1 and 8.12 texels: thinner than the
// spacing of the 2 x 2 sample positions (at 8.25 and 8.75), from u = 1.6 to 14.4 texels.
TEST(TexelRasterizer, ThinTriangleOwnsEveryTexelItTouches) {
    Mesh mesh = test::triangle(vec3(0, 0, 0), vec3(1, 0, 0), vec3(1, 0.02f, 0));
    const float s = 1.0f / 16.0f;
    mesh.uv_sets = {
        {"UVMap", {{1.6f * s, 8.1f * s}, {14.4f * s, 8.1f * s}, {14.4f * s, 8.12f * s}}}};
    const TexelMap map = rasterize_texels(mesh, mat4(1.0f), settings_for(16, 16, 2));
    EXPECT_EQ(map.report.conservative_samples, 14u);
    for (uint32_t y = 0; y < 16; ++y)
        for (uint32_t x = 0; x < 16; ++x) {
            const uint64_t t = map.texel_index(x, y);
            const bool touched = y == 8 && x >= 1 && x <= 14;
            ASSERT_EQ(map.sample_count(t), touched ? 1u : 0u) << "texel (" << x << ", " << y << ")";
            if (!touched) continue;
            const TexelSample& sample = *map.samples_begin(t);
            // The point of the sliver nearest the texel centre: on its top edge, inside the texel.
            EXPECT_GE(sample.uv.x * 16.0f, float(x) - 1e-5f);
            EXPECT_LE(sample.uv.x * 16.0f, float(x + 1) + 1e-5f);
            EXPECT_GT(sample.uv.y * 16.0f, 8.1f - 1e-4f);
            EXPECT_LT(sample.uv.y * 16.0f, 8.12f + 1e-4f);
            EXPECT_GT(sample.weight, 0.0f);
            EXPECT_LT(sample.weight, 0.02f);
        }
    const double uv_area_texels = 0.5 * 12.8 * 0.02;
    EXPECT_NEAR(total_weight(map), uv_area_texels, 1e-5);
}

TEST(TexelRasterizer, MirroredUvsCoverTheSameTexelsAndKeepTheFrontSide) {
    Mesh quad = test::unit_quad();
    for (vec2& uv : quad.uv_sets[0].coords) uv.x = 1.0f - uv.x;  // a mirrored UV island
    const TexelMap map = rasterize_texels(quad, mat4(1.0f), settings_for(8, 8, 2));
    for (uint64_t t = 0; t < map.texel_count(); ++t) EXPECT_FLOAT_EQ(map.coverage[t], 1.0f);
    for (const TexelSample& sample : map.samples) {
        EXPECT_NEAR(sample.position.x, 1.0f - sample.uv.x, kFloatTolerance);
        EXPECT_EQ(sample.geometric_normal, vec3(0, 0, 1));  // world winding, not UV winding
    }
}

TEST(TexelRasterizer, MirroringTransformKeepsTheFrontSide) {
    Mesh quad = test::unit_quad();
    const TexelMap map =
        rasterize_texels(quad, glm::scale(mat4(1.0f), vec3(-1, 1, 1)), settings_for(4, 4, 1));
    for (const TexelSample& sample : map.samples) {
        EXPECT_EQ(sample.geometric_normal, vec3(0, 0, 1));
        EXPECT_EQ(sample.normal, vec3(0, 0, 1));
    }
}

TEST(TexelRasterizer, UvsOutsideTheUnitSquareAreClippedNotWrapped) {
    Mesh quad = test::unit_quad();
    quad.uv_sets[0].coords = {{-0.5f, -0.5f}, {1.5f, -0.5f}, {1.5f, 1.5f}, {-0.5f, 1.5f}};
    const TexelMap map = rasterize_texels(quad, mat4(1.0f), settings_for(4, 4, 2));
    EXPECT_EQ(map.report.clipped_triangles, 2u);
    EXPECT_EQ(map.report.overlapping_texels, 0u);
    EXPECT_NEAR(total_coverage(map), 16.0, 16 * kFloatTolerance);
    // Only the middle half of the quad lands in the lightmap: world x = (u + 0.5) / 2.
    for (const TexelSample& sample : map.samples) {
        EXPECT_NEAR(sample.position.x, (sample.uv.x + 0.5f) / 2.0f, kFloatTolerance);
        EXPECT_NEAR(sample.position.y, (sample.uv.y + 0.5f) / 2.0f, kFloatTolerance);
    }
}

TEST(TexelRasterizer, CollapsedUvTrianglesAreSkippedAndCounted) {
    Mesh mesh = test::unit_quad();
    // Triangle 1: a proper triangle in world space whose three UVs are the same point.
    mesh.positions.insert(mesh.positions.end(), {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}});
    mesh.normals.insert(mesh.normals.end(), 3, vec3(0, 0, 1));
    mesh.uv_sets[0].coords.insert(mesh.uv_sets[0].coords.end(), 3, vec2(0.5f));
    mesh.triangles = {{0, 1, 2}, {4, 5, 6}};
    const TexelMap map = rasterize_texels(mesh, mat4(1.0f), settings_for(4, 4, 1));
    EXPECT_EQ(map.report.triangles, 2u);
    EXPECT_EQ(map.report.degenerate_uv, 1u);
    EXPECT_FALSE(map.samples.empty());
    for (const TexelSample& sample : map.samples) EXPECT_EQ(sample.triangle_id, 0u);
}

TEST(TexelRasterizer, OverlappingUvsKeepBothAndAreCounted) {
    Mesh quad = test::unit_quad();
    quad.triangles.push_back(quad.triangles[0]);
    quad.triangles.push_back(quad.triangles[1]);
    const TexelMap map = rasterize_texels(quad, mat4(1.0f), settings_for(4, 4, 2));
    EXPECT_EQ(map.report.overlapping_texels, 16u);
    for (uint64_t t = 0; t < map.texel_count(); ++t) {
        EXPECT_EQ(map.coverage[t], 1.0f);
        EXPECT_EQ(map.sample_count(t), 8u);
        // Ordered by triangle id within the texel.
        for (const TexelSample* s = map.samples_begin(t) + 1; s != map.samples_end(t); ++s)
            EXPECT_LE((s - 1)->triangle_id, s->triangle_id);
    }
}

TEST(TexelRasterizer, MissingUvSetNamesTheMeshAndTheFix) {
    const Mesh quad = test::unit_quad("Floor");
    const std::string message =
        rejection([&] { rasterize_texels(quad, mat4(1.0f), settings_for(4, 4, 1, "LightmapUV")); });
    expect_contains(message, "mesh 'Floor' has no UV set 'LightmapUV'");
    expect_contains(message, "its UV sets: 'UVMap'");
    expect_contains(message, "Lightmap Pack");

    Mesh bare = test::unit_quad("Floor");
    bare.uv_sets.clear();
    expect_contains(rejection([&] { rasterize_texels(bare, mat4(1.0f), settings_for(4, 4, 1)); }),
                    "it has no UV sets");
}

TEST(TexelRasterizer, RejectsBadMeshesAndSettings) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const auto message = [](const Mesh& mesh, const TexelRasterSettings& settings,
                            const mat4& transform = mat4(1.0f)) {
        return rejection([&] { rasterize_texels(mesh, transform, settings); });
    };
    const TexelRasterSettings good = settings_for(4, 4, 1);

    Mesh mesh = test::unit_quad();
    mesh.uv_sets[0].coords[2] = vec2(nan, 0.5f);
    expect_contains(message(mesh, good), "mesh 'Quad': uv set 'UVMap'[2] is not finite");

    mesh = test::unit_quad();
    mesh.uv_sets[0].coords.pop_back();
    expect_contains(message(mesh, good), "uv set 'UVMap' has 3 elements but positions has 4");

    mesh = test::unit_quad();
    mesh.triangles[1] = uvec3(0, 2, 7);
    expect_contains(message(mesh, good), "triangles[1] indexes vertex 7 but the mesh has 4");

    expect_contains(message(test::unit_quad(), good, glm::scale(mat4(1.0f), vec3(1, 0, 1))),
                    "world_from_object is not finite or is singular");

    TexelRasterSettings bad = good;
    bad.width = 0;
    expect_contains(message(test::unit_quad(), bad), "TexelRasterSettings.width = 0");
    bad = good;
    bad.height = 20000;
    expect_contains(message(test::unit_quad(), bad), "TexelRasterSettings.height = 20000");
    bad = good;
    bad.samples_per_axis = 17;
    expect_contains(message(test::unit_quad(), bad), "TexelRasterSettings.samples_per_axis = 17");
}

TEST(TexelRasterizer, SceneInstanceErrorsNameTheObject) {
    Scene scene;
    scene.add_instance(scene.add_mesh(test::unit_quad("FloorMesh")), mat4(1.0f), "Floor");
    expect_contains(rejection([&] { rasterize_texels(scene, 3, settings_for(4, 4, 1)); }),
                    "instance_id = 3 but the scene has 1 instances");
    expect_contains(
        rejection([&] { rasterize_texels(scene, 0, settings_for(4, 4, 1, "LightmapUV")); }),
        "instance 'Floor': mesh 'FloorMesh' has no UV set 'LightmapUV'");
    const TexelMap map = rasterize_texels(scene, 0, settings_for(4, 4, 1));
    EXPECT_EQ(map.instance_id, 0u);
}

// A UV sphere whose grid UVs fill [0, 1]^2: many triangles of every shape and orientation.
Scene sphere_scene() {
    Mesh sphere = test::uv_sphere(1.5f, 12, 24);
    UvSet uv_set{"LightmapUV", {}};
    const uint32_t row = 25;
    for (uint32_t i = 0; i < sphere.positions.size(); ++i)
        uv_set.coords.push_back(vec2(float(i % row) / 24.0f, float(i / row) / 12.0f));
    sphere.uv_sets = {uv_set};
    Scene scene;
    scene.add_instance(scene.add_mesh(sphere), glm::translate(mat4(1.0f), vec3(0, 0, 2)));
    return scene;
}

TEST(TexelRasterizer, SphereUvGridCoversTheLightmap) {
    // The pole triangles that collapse in world space were dropped by the Scene: their texels
    // (along v = 0 and v = 1) are half covered, every other texel fully.
    const Scene scene = sphere_scene();
    const TexelMap map = rasterize_texels(scene, 0, settings_for(48, 48, 2, "LightmapUV"));
    EXPECT_EQ(map.report.degenerate_uv, 0u);
    EXPECT_EQ(map.report.degenerate_world, 0u);
    EXPECT_EQ(map.report.overlapping_texels, 0u);
    for (uint32_t y = 4; y < 44; ++y)
        for (uint32_t x = 0; x < 48; ++x)
            EXPECT_NEAR(map.coverage[map.texel_index(x, y)], 1.0f, 1e-5f);
    for (const TexelSample& sample : map.samples) {
        EXPECT_NEAR(glm::length(sample.position - vec3(0, 0, 2)), 1.5f, 0.05f);  // chordal
        EXPECT_NEAR(glm::length(sample.normal), 1.0f, 1e-5f);
    }
}

TEST(TexelRasterizer, IdenticalForAnyThreadCount) {
    const Scene scene = sphere_scene();
    const TexelRasterSettings settings = settings_for(96, 64, 3, "LightmapUV");
    const auto rasterize = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        return rasterize_texels(scene, 0, settings);
    };
    const TexelMap one = rasterize(1), many = rasterize(8);
    ASSERT_EQ(one.samples.size(), many.samples.size());
    EXPECT_EQ(one.sample_offsets, many.sample_offsets);
    EXPECT_EQ(one.coverage, many.coverage);
    EXPECT_EQ(one.chart, many.chart);
    // TexelSample holds only 4-byte fields, so it has no padding: compare the bytes.
    static_assert(sizeof(TexelSample) == 19 * 4, "TexelSample gained padding or a field");
    EXPECT_EQ(std::memcmp(one.samples.data(), many.samples.data(),
                          one.samples.size() * sizeof(TexelSample)),
              0);
}

TEST(TexelRasterizer, CancelStopsWithCancelled) {
    const Scene scene = sphere_scene();
    Progress progress;
    progress.cancel();
    EXPECT_THROW(rasterize_texels(scene, 0, settings_for(64, 64, 2, "LightmapUV"), &progress),
                 Cancelled);
}

TEST(TexelRasterizer, MapsRecordTheirSceneAndAreRefusedWhenStale) {
    Scene scene;
    const uint32_t mesh = scene.add_mesh(test::unit_quad("FloorMesh"));
    scene.add_instance(mesh, mat4(1.0f), "Floor");
    const TexelMap map = rasterize_texels(scene, 0, settings_for(4, 4, 1));
    EXPECT_EQ(map.scene_uid, scene.uid());
    EXPECT_NO_THROW(check_texel_map(scene, map, "bake_lightmap"));
    Scene other;
    other.add_instance(other.add_mesh(test::unit_quad("FloorMesh")), mat4(1.0f), "Floor");
    EXPECT_NE(other.uid(), scene.uid());
    expect_contains(rejection([&] { check_texel_map(other, map, "bake_lightmap"); }),
                    "bake_lightmap: the texel map was made for another scene");
    scene.set_instance_transform(0, glm::translate(mat4(1.0f), vec3(0, 0, 1)));
    expect_contains(rejection([&] { check_texel_map(scene, map, "unocclude"); }),
                    "unocclude: the texel map was made before instance 0 'Floor' moved");
    scene.set_instance_transform(0, mat4(1.0f));
    EXPECT_NO_THROW(check_texel_map(scene, map, "unocclude"));
    scene.set_mesh(mesh, test::unit_quad("FloorMesh"));
    expect_contains(rejection([&] { check_texel_map(scene, map, "bake_lightmap"); }),
                    "the texel map was made before the mesh of instance 0 'Floor' changed");
    const Mesh& quad = scene.meshes()[mesh];
    const TexelMap bare = rasterize_texels(quad, mat4(1.0f), settings_for(4, 4, 1));
    expect_contains(rejection([&] { check_texel_map(scene, bare, "bake_lightmap"); }),
                    "rasterized from a bare mesh");
}

TEST(TexelRasterizer, BeyondMemoryIsRefusedNamingTheSettings) {
    Scene scene;
    scene.add_instance(scene.add_mesh(test::unit_quad("FloorMesh")), mat4(1.0f), "Floor");
    // 16384^2 texels with 256 samples each: ~11 TB of samples, refused before allocating.
    const std::string message = rejection<OutOfMemory>(
        [&] { rasterize_texels(scene, 0, settings_for(16384, 16384, 16)); });
    expect_contains(message,
                    "TexelRasterSettings.width x height = 16384 x 16384 with 256 samples per "
                    "texel (samples_per_axis = 16");
    expect_contains(message, "this process may use");
    expect_contains(message, "lower the resolution (width, height) or samples_per_axis");
}

}  // namespace
}  // namespace shgi
