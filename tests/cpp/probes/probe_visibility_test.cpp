// Visibility and leak prevention: the octahedral map round-trips directions, Chebyshev's bound
// behaves as stated, and in a two-room fixture the probe behind the wall contributes nothing.
#include <gtest/gtest.h>

#include <glm/gtc/matrix_transform.hpp>

#include "probes/probe_grid.h"
#include "probes/probe_visibility.h"
#include "render/render_test_scenes.h"
#include "util/sampling.h"

namespace shgi {
namespace {

TEST(ProbeVisibility, OctahedralMapRoundTripsDirections) {
    for (uint32_t i = 0; i < 1000; ++i) {
        const vec3 dir = fibonacci_sphere(i, 1000);
        const vec2 uv = octahedral_encode(dir);
        EXPECT_GE(uv.x, 0.0f);
        EXPECT_LE(uv.y, 1.0f);
        EXPECT_LT(glm::length(octahedral_decode(uv) - dir), 1e-5f) << i;
    }
}

TEST(ProbeVisibility, ChebyshevBound) {
    // Every sample at 2 m: visible up to 2 m, nothing beyond.
    EXPECT_EQ(chebyshev_visibility(vec2(2.0f, 4.0f), 1.5f, 0.0f), 1.0f);
    EXPECT_LT(chebyshev_visibility(vec2(2.0f, 4.0f), 2.5f, 0.0f), 1e-6f);
    // Mean 2, variance 1: at 3 m the bound is 1 / (1 + 1) = 0.5; bleed_bias 0.2 rescales it.
    EXPECT_FLOAT_EQ(chebyshev_visibility(vec2(2.0f, 5.0f), 3.0f, 0.0f), 0.5f);
    EXPECT_FLOAT_EQ(chebyshev_visibility(vec2(2.0f, 5.0f), 3.0f, 0.2f), 0.3f / 0.8f);
}

TEST(ProbeVisibility, FilterAveragesDistancesAroundEachTexel) {
    VisibilityFilter filter(4, 0.3f);
    for (uint32_t i = 0; i < 256; ++i) {
        const vec3 dir = fibonacci_sphere(i, 256);
        filter.add(dir, dir.z > 0.0f ? 1.0f : 3.0f);
    }
    std::vector<vec2> fallback(16, vec2(-1.0f)), moments(16);
    filter.moments(fallback.data(), moments.data());
    const vec2 up = sample_visibility(moments.data(), 4, vec3(0.0f, 0.0f, 1.0f));
    const vec2 down = sample_visibility(moments.data(), 4, vec3(0.0f, 0.0f, -1.0f));
    EXPECT_NEAR(up.x, 1.0f, 0.05f);
    EXPECT_NEAR(down.x, 3.0f, 0.05f);
    EXPECT_GE(down.y, down.x * down.x - 1e-4f);  // E[d^2] >= E[d]^2
}

// Two rooms, x in [-2, 0] and [0, 2], split by a solid wall 0.1 m thick at x = 0 (thinner than
// the 1 m probe spacing). Probes at x = -1.5, -0.5, 0.5, 1.5. A point on the right face of the
// wall lies between the probes at -0.5 (left room) and 0.5 (right room).
TEST(ProbeVisibility, ChebyshevKillsTheProbeBehindAWall) {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    Mesh room = test::inward_box(1.0f);
    scene.add_instance(scene.add_mesh(room), glm::scale(mat4(1.0f), vec3(2.0f, 1.0f, 1.0f)));
    Mesh wall = test::inward_box(1.0f);
    for (uvec3& t : wall.triangles) std::swap(t.y, t.z);  // outward faces: solid
    scene.add_instance(scene.add_mesh(wall), glm::scale(mat4(1.0f), vec3(0.05f, 1.0f, 1.0f)));
    scene.add_light(test::point_light(vec3(-1.0f, 0.0f, 0.5f), 100.0f));
    scene.commit();

    ProbeGridSettings settings;
    ProbeVolume volume;
    volume.world_from_volume = glm::scale(mat4(1.0f), vec3(2.0f, 1.0f, 1.0f));
    volume.resolution = ivec3(4, 1, 1);
    settings.volumes = {volume};
    settings.rays_per_probe = 512;
    ProbeGrid grid(scene, settings);
    grid.update();
    ASSERT_EQ(grid.active_count(), 4u);

    // Probe radiance replaced by markers: the left-room probes 100, the right-room ones 1.
    ProbeGridData marked = grid.data();
    for (size_t i = 0; i < 4; ++i) {
        marked.sh[i] = ShRgb(marked.order);
        marked.sh[i][0] = vec3(i < 2 ? 100.0f : 1.0f);
    }
    const auto data = std::make_shared<const ProbeGridData>(marked);
    const vec3 p(0.05f, 0.3f, -0.2f), n(1.0f, 0.0f, 0.0f);
    const float with_visibility = ProbeField(data, ProbeLookupSettings{}).radiance_sh(p, n)[0].x;
    ProbeLookupSettings plain;
    plain.visibility = false;
    const float trilinear = ProbeField(data, plain).radiance_sh(p, n)[0].x;
    EXPECT_NEAR(with_visibility, 1.0f, 0.01f) << "the left-room probe leaks through the wall";
    EXPECT_GT(trilinear, 20.0f) << "plain trilinear interpolation should leak here";
}

// Two probes 1 m apart along x read at the midpoint: the view bias moves the lookup half a
// spacing towards the viewer, onto the second probe.
TEST(ProbeField, ViewBiasMovesTheLookupTowardsTheViewer) {
    ProbeGridData data;
    data.order = 1;
    ProbeVolume volume;
    volume.resolution = ivec3(2, 1, 1);  // probes at x = -0.5 and 0.5 (spacing 1 m)
    data.volumes = {volume};
    data.positions = probe_base_positions(data.volumes);
    data.active = {1, 1};
    data.sh = {ShRgb(1), ShRgb(1)};
    data.sh[1][0] = vec3(1.0f);
    data.variance = {0.0f, 0.0f};
    data.visibility_resolution = 1;
    data.visibility = {vec2(10.0f, 100.0f), vec2(10.0f, 100.0f)};
    const auto shared = std::make_shared<const ProbeGridData>(data);
    ProbeLookupSettings lookup;
    lookup.visibility = false;
    lookup.view_bias = 0.5f;
    const ProbeField field(shared, lookup);
    const vec3 p(0.0f), n(0.0f, 0.0f, 1.0f);
    EXPECT_FLOAT_EQ(field.radiance_sh(p, n)[0].x, 0.5f);
    EXPECT_FLOAT_EQ(field.view_lookup(p, n, vec3(1.0f, 0.0f, 0.0f)).radiance[0].x, 1.0f);
    EXPECT_FLOAT_EQ(field.view_lookup(p, n, vec3(-1.0f, 0.0f, 0.0f)).radiance[0].x, 0.0f);
}

}  // namespace
}  // namespace shgi
