// unocclude on a floor with a closed box standing on it: a floor texel whose centre lies under
// the box's edge gets its ray origin moved out of the box (so it sees the light instead of the
// box's inside), texels outside the box or deep under it keep theirs, and the pass is
// deterministic, idempotent and rejects bad input.
#include "bake/unocclude.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "bake/texel_rasterizer.h"
#include "render/render_test_scenes.h"
#include "render/shading.h"
#include "support/expect_error.h"
#include "util/error.h"

namespace shgi {
namespace {

using testing::expect_contains;
using testing::rejection;

// Floor [-1, 1]^2 at z = 0 facing +Z, lightmap UV = (x + 1) / 2, (y + 1) / 2; rasterized at
// 16 x 16 with one sample per texel, texels are 0.125 m and texel i's centre is at
// -1 + (i + 0.5) * 0.125. A closed, outward-facing box x in [0.03, 0.5], y in [-0.5, 0.5],
// z in [0, 0.5] stands on it: its left face x = 0.03 crosses texel column 8 ([0, 0.125]),
// whose centre 0.0625 lies under the box.
constexpr float kWallX = 0.03f;
constexpr float kTexelSize = 0.125f;
constexpr uint32_t kResolution = 16;

struct FloorWithBox {
    Scene scene;
    uint32_t floor = 0;
};

FloorWithBox floor_with_box() {
    FloorWithBox fixture;
    Mesh floor = test::quad(vec3(-1, -1, 0), vec3(2, 0, 0), vec3(0, 2, 0));
    floor.name = "floor";
    floor.uv_sets = {{"LightmapUV", {{0, 0}, {1, 0}, {1, 1}, {0, 1}}}};
    fixture.floor = fixture.scene.add_instance(fixture.scene.add_mesh(floor), mat4(1.0f), "Floor");
    Mesh box = test::inward_box(1.0f);
    for (uvec3& t : box.triangles) std::swap(t.y, t.z);  // outward faces: a solid box
    const vec3 lower(kWallX, -0.5f, 0.0f), upper(0.5f, 0.5f, 0.5f);
    const mat4 world_from_box = glm::translate(mat4(1.0f), 0.5f * (lower + upper)) *
                                glm::scale(mat4(1.0f), 0.5f * (upper - lower));
    fixture.scene.add_instance(fixture.scene.add_mesh(box), world_from_box, "Box");
    fixture.scene.commit();
    return fixture;
}

TexelMap rasterize_floor(const FloorWithBox& fixture) {
    TexelRasterSettings settings;
    settings.width = settings.height = kResolution;
    settings.samples_per_axis = 1;
    return rasterize_texels(fixture.scene, fixture.floor, settings);
}

const TexelSample& texel_sample(const TexelMap& map, uint32_t x, uint32_t y) {
    return *map.samples_begin(map.texel_index(x, y));
}

TEST(Unocclude, FloorTexelUnderAWallEdgeIsMovedOutOfTheWall) {
    const FloorWithBox fixture = floor_with_box();
    TexelMap map = rasterize_floor(fixture);
    const TexelSample before = texel_sample(map, 8, 8);
    ASSERT_NEAR(before.position.x, 0.0625f, 1e-6f);
    ASSERT_NEAR(before.texel_size, kTexelSize, 1e-6f);
    // A light above and to the left of the box: hidden from the origin inside the box.
    const vec3 light(-0.5f, 0.0625f, 1.0f);
    const auto sees_light = [&](const vec3& origin) {
        Ray ray;
        ray.origin = origin;
        ray.direction = light - origin;
        ray.tmax = 1.0f;
        return !fixture.scene.occluded(ray);
    };
    EXPECT_FALSE(sees_light(before.ray_origin));

    const UnoccludeReport report = unocclude(fixture.scene, map, UnoccludeSettings{});
    const TexelSample& after = texel_sample(map, 8, 8);
    EXPECT_LT(after.ray_origin.x, kWallX);  // out of the box, past its left face
    EXPECT_GT(after.ray_origin.x, kWallX - kTexelSize);
    EXPECT_GT(after.ray_origin.z, 0.0f);  // still above the floor
    EXPECT_LT(after.ray_origin.z, 0.01f);
    // Bounded: within search_radius + push_distance texels (plus the normal offset).
    EXPECT_LT(glm::length(after.ray_origin - before.position), 1.1f * kTexelSize);
    EXPECT_TRUE(sees_light(after.ray_origin));
    // Position and normals stay on the surface: only where rays start changes.
    EXPECT_EQ(after.position, before.position);
    EXPECT_EQ(after.normal, before.normal);
    // Exactly the samples under the box within reach of its sides move: those in its outermost
    // texel ring (0.03 to 0.0625 m from a side); the next ring lies 0.19 m = 1.5 texels inside.
    uint64_t expected_moved = 0;
    for (const TexelSample& sample : map.samples) {
        const vec2 p(sample.position);
        const bool under_box = p.x > kWallX && p.x < 0.5f && std::abs(p.y) < 0.5f;
        const float to_side = std::min({p.x - kWallX, 0.5f - p.x, 0.5f - std::abs(p.y)});
        const bool moves = under_box && to_side < 0.1f;
        expected_moved += moves;
        const bool moved =
            sample.ray_origin != offset_origin(sample.position, sample.geometric_normal);
        EXPECT_EQ(moved, moves) << "sample at (" << p.x << ", " << p.y << ")";
    }
    EXPECT_EQ(report.samples, map.samples.size());
    EXPECT_EQ(report.moved_samples, expected_moved);
    EXPECT_GE(expected_moved, 20u);  // 8 + 8 + 2 + 2 texels of the ring, and their duplicates
}

TEST(Unocclude, KeepsSamplesOutsideTheWallAndDeepUnderIt) {
    const FloorWithBox fixture = floor_with_box();
    TexelMap map = rasterize_floor(fixture);
    unocclude(fixture.scene, map, UnoccludeSettings{});
    // Column 7 (centre x = -0.0625) sees the box's outside within one texel: a front face,
    // a real occluder. Column 10 (centre 0.3125) lies 1.5 texels from every side of the box.
    for (uint32_t x : {7u, 10u}) {
        const TexelSample& sample = texel_sample(map, x, 8);
        EXPECT_EQ(sample.ray_origin, offset_origin(sample.position, sample.geometric_normal))
            << "column " << x;
    }
}

TEST(Unocclude, DeterministicAndIdempotent) {
    const FloorWithBox fixture = floor_with_box();
    const auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        TexelMap map = rasterize_floor(fixture);
        unocclude(fixture.scene, map, UnoccludeSettings{});
        return map;
    };
    const TexelMap one = run(1);
    TexelMap many = run(8);
    const auto origins = [](const TexelMap& map) {
        std::vector<vec3> result;
        for (const TexelSample& sample : map.samples) result.push_back(sample.ray_origin);
        return result;
    };
    EXPECT_EQ(origins(one), origins(many));
    unocclude(fixture.scene, many, UnoccludeSettings{});  // a second pass moves nothing further
    EXPECT_EQ(origins(one), origins(many));
}

TEST(Unocclude, TilesMoveTheirSamplesAsAWholeUnoccludeAndNoOthers) {
    // A shard unoccludes only its tiles: tiles 1 and 2 of 8-texel tiles (columns 8..15 of rows
    // 0..7, and columns 0..7 of rows 8..15) of the 16 x 16 floor, whose column 8 lies under
    // the wall's edge.
    const FloorWithBox fixture = floor_with_box();
    TexelMap whole = rasterize_floor(fixture);
    unocclude(fixture.scene, whole, UnoccludeSettings{});
    TexelMap part = rasterize_floor(fixture);
    const TexelMap untouched = part;
    constexpr uint32_t kTile = 8;
    const UnoccludeReport report =
        unocclude(fixture.scene, part, UnoccludeSettings{}, {1, 2}, kTile);
    EXPECT_EQ(report.samples, 2u * kTile * kTile);  // one sample per texel
    EXPECT_GT(report.moved_samples, 0u);
    for (uint32_t y = 0; y < kResolution; ++y) {
        for (uint32_t x = 0; x < kResolution; ++x) {
            const uint32_t tile = (y / kTile) * (kResolution / kTile) + x / kTile;
            const bool in_tiles = tile == 1 || tile == 2;
            const vec3 expected = texel_sample(in_tiles ? whole : untouched, x, y).ray_origin;
            EXPECT_EQ(texel_sample(part, x, y).ray_origin, expected) << x << ", " << y;
        }
    }
    expect_contains(
        rejection([&] { unocclude(fixture.scene, part, UnoccludeSettings{}, {4}, kTile); }),
        "tile 4 but a 16 x 16 lightmap has 4 tiles of 8 texels");
}

TEST(Unocclude, RejectsAnUncommittedSceneAndBadSettings) {
    FloorWithBox fixture = floor_with_box();
    TexelMap map = rasterize_floor(fixture);
    const auto message = [&](const UnoccludeSettings& settings) {
        return rejection([&] { unocclude(fixture.scene, map, settings); });
    };
    UnoccludeSettings bad;
    bad.ray_count = 0;
    expect_contains(message(bad), "UnoccludeSettings.ray_count = 0 is outside [1, 64]");
    bad = UnoccludeSettings{};
    bad.search_radius = -1.0f;
    expect_contains(message(bad), "UnoccludeSettings.search_radius = -1");
    bad = UnoccludeSettings{};
    bad.push_distance = std::numeric_limits<float>::quiet_NaN();
    expect_contains(message(bad), "UnoccludeSettings.push_distance = nan");
    // Finite but far: 1e38 texels put ray origins out of Embree's range.
    bad.push_distance = 1e38f;
    expect_contains(message(bad), "UnoccludeSettings.push_distance = 1e+38 must be in [0, 16]");
    bad = UnoccludeSettings{};
    bad.search_radius = 17.0f;
    expect_contains(message(bad), "UnoccludeSettings.search_radius = 17 must be in (0, 16]");
    bad.search_radius = 16.0f;
    bad.push_distance = 16.0f;
    EXPECT_NO_THROW(unocclude(fixture.scene, map, bad));

    fixture.scene.set_instance_transform(fixture.floor, mat4(1.0f));  // un-commits
    expect_contains(message(UnoccludeSettings{}), "call Scene::commit() first");
}

TEST(Unocclude, CancelStopsWithCancelled) {
    const FloorWithBox fixture = floor_with_box();
    TexelMap map = rasterize_floor(fixture);
    Progress progress;
    progress.cancel();
    EXPECT_THROW(unocclude(fixture.scene, map, UnoccludeSettings{}, &progress), Cancelled);
}

}  // namespace
}  // namespace shgi
