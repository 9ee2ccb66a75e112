// ProbeGrid against closed forms: a probe over a lit ground plane (open scene) and a probe in an
// emissive furnace converge to their analytic SH; placement moves probes out of geometry or
// disables them; results are bit-identical for any thread count; cancel keeps the state.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

#include "probes/probe_grid.h"
#include "render/render_test_scenes.h"
#include "support/expect_error.h"

namespace shgi {
namespace {

using test::inward_box;
using test::lambert;
using test::plane;
using testing::expect_error;

constexpr float kY00 = 0.28209479177387814f;
constexpr float kY10 = 0.48860251190291992f;

// One probe at `centre` (a 1x1x1 volume).
ProbeVolume single_probe(const vec3& centre) {
    ProbeVolume volume;
    volume.world_from_volume = glm::translate(mat4(1.0f), centre) *
                               glm::scale(mat4(1.0f), vec3(0.25f));
    volume.resolution = ivec3(1);
    return volume;
}

ShRgb converged_probe(const Scene& scene, ProbeGridSettings settings, int passes) {
    ProbeGrid grid(scene, settings);
    for (int i = 0; i < passes; ++i) grid.update();
    EXPECT_EQ(grid.passes(), uint64_t(passes));
    return grid.data().sh[0];
}

// A 1 km Lambert ground plane of albedo a under a uniform sky of radiance L: every ground point
// sees the whole sky, so its radiance is a L; a probe 1 m above sees it over the lower
// hemisphere (to 0.1% of the solid angle). Indirect SH: c_l0 = a L 2 pi ∫_{-1}^{0} Y_l0(z) dz, so
// c00 = a L sqrt(pi), c10 = -a L pi Y10 / ... (below), c20 = 0, c_lm = 0 for m != 0.
Scene ground_under_sky(float albedo, float sky) {
    Scene scene;
    scene.add_material(lambert(albedo));
    scene.add_instance(scene.add_mesh(plane(500.0f)), mat4(1.0f));
    World world;
    world.color = vec3(sky);
    world.strength = 1.0f;
    scene.set_world(world);
    scene.commit();
    return scene;
}

TEST(ProbeGrid, OpenSceneProbeConvergesToAnalyticSh) {
    const float a = 0.5f, sky = 2.0f;
    const Scene scene = ground_under_sky(a, sky);
    ProbeGridSettings settings;
    settings.volumes = {single_probe(vec3(0.0f, 0.0f, 1.0f))};
    settings.rays_per_probe = 4096;
    settings.seed = 3;
    const ShRgb sh = converged_probe(scene, settings, 4);
    const float ground = a * sky;
    const float c00 = ground * kTwoPi * kY00;          // 2 pi Y00 ∫_{-1}^{0} dz
    const float c10 = ground * kTwoPi * kY10 * -0.5f;  // 2 pi Y10 ∫_{-1}^{0} z dz
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(sh[0][c], c00, 0.01f * c00);
        EXPECT_NEAR(sh[2][c], c10, 0.01f * c00);
        EXPECT_NEAR(sh[6][c], 0.0f, 0.01f * c00);  // Y20: ∫_{-1}^{0} (3z^2 - 1) dz = 0
        for (int i : {1, 3, 4, 5, 7, 8}) EXPECT_NEAR(sh[i][c], 0.0f, 0.01f * c00) << i;
    }

    // With direct light kept, the sky fills the upper hemisphere too.
    settings.include_direct = true;
    const ShRgb total = converged_probe(scene, settings, 2);
    const float total_c00 = (ground + sky) * kTwoPi * kY00;
    const float total_c10 = (sky - ground) * kTwoPi * kY10 * 0.5f;
    EXPECT_NEAR(total[0].x, total_c00, 0.01f * total_c00);
    EXPECT_NEAR(total[2].x, total_c10, 0.01f * total_c00);
}

// Closed box, every face emitting Le with albedo a: incident radiance is Le / (1 - a)
// everywhere, of which a Le / (1 - a) has scattered at least once.
TEST(ProbeGrid, FurnaceProbeConvergesToLeOverOneMinusAlbedo) {
    const float a = 0.5f, le = 1.5f;
    const Scene scene = test::emissive_furnace(a, vec3(1.0f), le);
    ProbeGridSettings settings;
    settings.volumes = {single_probe(vec3(0.1f, -0.2f, 0.3f))};
    settings.rays_per_probe = 1024;
    settings.bounces = 64;  // the series to a^11 (the path limit): 5e-4 short of the sum
    settings.seed = 7;
    settings.order = 1;
    const ShRgb indirect = converged_probe(scene, settings, 8);
    const float expected = std::sqrt(kFourPi) * a * le / (1.0f - a);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(indirect[0][c], expected, 0.015f * expected);
        for (int i = 1; i < 4; ++i) EXPECT_NEAR(indirect[i][c], 0.0f, 0.03f * expected);
    }
    settings.include_direct = true;
    const ShRgb total = converged_probe(scene, settings, 8);
    const float expected_total = std::sqrt(kFourPi) * le / (1.0f - a);
    EXPECT_NEAR(total[0].y, expected_total, 0.015f * expected_total);
}

TEST(ProbeGrid, VarianceFallsAsPassesAccumulate) {
    const Scene scene = test::emissive_furnace(0.5f, vec3(1.0f), 1.0f);
    ProbeGridSettings settings;
    settings.volumes = {single_probe(vec3(0.0f))};
    settings.rays_per_probe = 64;
    settings.hysteresis = 0.99f;
    ProbeGrid grid(scene, settings);
    EXPECT_TRUE(std::isinf(grid.relative_error()[0]));
    grid.update();
    const float one = grid.relative_error()[0];
    for (int i = 0; i < 15; ++i) grid.update();
    const float sixteen = grid.relative_error()[0];
    EXPECT_GT(one, 0.0f);
    // The running mean of 16 equal passes: a quarter of one pass's standard error (the passes'
    // own variance estimates scatter, hence the margin).
    EXPECT_NEAR(sixteen / one, 0.25f, 0.1f);
}

// A unit box of solid geometry (outward faces) with a 3x3x3 grid around it: the centre probe is
// inside. With relocation it cannot get out within 0.45 spacings (the box is 1 m, spacing
// 0.8 m) and is disabled; a probe that is just inside a thin slab steps out of it.
TEST(ProbeGrid, ProbesInsideGeometryAreMovedOutOrDisabled) {
    Scene scene;
    scene.add_material(lambert(0.5f));
    Mesh box = inward_box(0.5f);
    for (uvec3& t : box.triangles) std::swap(t.y, t.z);  // outward faces: a solid block
    scene.add_instance(scene.add_mesh(box), mat4(1.0f));
    scene.add_instance(scene.add_mesh(box),
                       glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, -1.2f)) *
                           glm::scale(mat4(1.0f), vec3(4.0f, 4.0f, 0.1f)));  // slab 0.1 m thick
    scene.commit();

    ProbeGridSettings settings;
    ProbeVolume volume;
    volume.world_from_volume = glm::scale(mat4(1.0f), vec3(1.2f));
    volume.resolution = ivec3(3);  // probes at -0.8, 0, 0.8; the slab spans z in [-1.25, -1.15]
    settings.volumes = {volume};
    volume.world_from_volume = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, -1.18f)) *
                               glm::scale(mat4(1.0f), vec3(0.4f));
    volume.resolution = ivec3(1);  // one probe inside the slab, 0.03 m under its top
    settings.volumes.push_back(volume);
    const ProbeGrid grid(scene, settings);
    const ProbeGridData& data = grid.data();
    ASSERT_EQ(data.probe_count(), 28u);
    EXPECT_EQ(data.active[13], 0) << "the probe at the block's centre stays inside";
    EXPECT_EQ(data.active[27], 1) << "the probe inside the slab steps out";
    EXPECT_GT(data.positions[27].z, -1.15f) << "it leaves through the nearest face, the top";
    EXPECT_LT(data.positions[27].z, -1.18f + 0.45f * 0.8f + 1e-4f);
    EXPECT_EQ(grid.active_count(), 27u);
    for (size_t i = 0; i < 27; ++i)
        if (i != 13) {
            EXPECT_EQ(data.active[i], 1) << i;
        }

    settings.relocate = false;
    const ProbeGrid fixed(scene, settings);
    EXPECT_EQ(fixed.data().active[27], 0);
    EXPECT_EQ(fixed.data().positions[27], probe_base_positions(settings.volumes)[27]);
}

TEST(ProbeGrid, BitIdenticalForAnyThreadCount) {
    const Scene scene = test::emissive_furnace(0.6f, vec3(1.0f, 0.5f, 0.25f), 1.0f);
    ProbeGridSettings settings;
    ProbeVolume volume;
    volume.world_from_volume = glm::scale(mat4(1.0f), vec3(0.8f));
    volume.resolution = ivec3(3, 2, 2);
    settings.volumes = {volume};
    settings.rays_per_probe = 32;
    const auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        ProbeGrid grid(scene, settings);
        grid.update();
        grid.update();
        return grid.data();
    };
    const ProbeGridData one = run(1), two = run(2);
    ASSERT_EQ(one.probe_count(), two.probe_count());
    for (size_t i = 0; i < one.probe_count(); ++i) {
        for (int c = 0; c < sh_num_coefficients(one.order); ++c) EXPECT_EQ(one.sh[i][c], two.sh[i][c]);
        EXPECT_EQ(one.variance[i], two.variance[i]);
    }
    EXPECT_EQ(one.visibility, two.visibility);
}

TEST(ProbeGrid, BricksUpdatedApartAndSplicedEqualTheWholeGrid) {
    // A solve split over machines: 4 bricks of probes, each updated by a grid of its own for the
    // same passes (ProbeGrid::update_probes), spliced into one grid that must equal the grid
    // updated whole, bit for bit.
    const Scene scene = test::emissive_furnace(0.6f, vec3(1.0f, 0.5f, 0.25f), 1.0f);
    ProbeGridSettings settings;
    ProbeVolume volume;
    volume.world_from_volume = glm::scale(mat4(1.0f), vec3(0.8f));
    volume.resolution = ivec3(3, 2, 2);  // 12 probes: bricks of 3
    settings.volumes = {volume};
    settings.rays_per_probe = 32;
    constexpr int kPasses = 2;
    ProbeGrid whole(scene, settings);
    for (int pass = 0; pass < kPasses; ++pass) whole.update();
    const size_t probes = whole.probe_count(), brick = 3;
    const ProbeGridData placed = ProbeGrid(scene, settings).data();
    ProbeGridData merged = placed;
    merged.passes = kPasses;  // the untouched base: every brick's probes replace its own
    for (size_t first = 0; first < probes; first += brick) {
        ProbeGrid part(scene, settings);
        for (int pass = 0; pass < kPasses; ++pass) part.update_probes(first, brick);
        EXPECT_EQ(part.passes(), uint64_t(kPasses));
        // Probes outside the brick keep their placement state.
        const size_t outside = (first + brick) % probes;
        EXPECT_EQ(part.data().variance[outside], placed.variance[outside]);
        merged = splice_probes(merged, part.data(), first, brick);
    }
    const ProbeGridData& expected = whole.data();
    for (size_t i = 0; i < probes; ++i) {
        for (int c = 0; c < sh_num_coefficients(expected.order); ++c)
            EXPECT_EQ(merged.sh[i][c], expected.sh[i][c]) << "probe " << i;
        EXPECT_EQ(merged.variance[i], expected.variance[i]) << "probe " << i;
    }
    EXPECT_EQ(merged.visibility, expected.visibility);
    EXPECT_EQ(merged.passes, expected.passes);

    // Bricks of another grid, or beyond the probes, are refused.
    ProbeGrid once(scene, settings);
    once.update_probes(0, brick);
    testing::expect_invalid_argument([&] { splice_probes(merged, once.data(), 0, brick); },
                                  "pass count is 1, the grid's 2");
    testing::expect_invalid_argument([&] { splice_probes(merged, merged, probes - 1, 2); },
                                  "beyond the grid's 12");
    ProbeGridSettings other = settings;
    other.volumes[0].resolution = ivec3(2, 2, 2);
    testing::expect_invalid_argument(
        [&] { splice_probes(merged, ProbeGrid(scene, other).data(), 0, 1); }, "probe count");
}

TEST(ProbeGrid, CancelKeepsThePreviousState) {
    const Scene scene = test::emissive_furnace(0.5f, vec3(1.0f), 1.0f);
    ProbeGridSettings settings;
    settings.rays_per_probe = 16;
    ProbeGrid grid(scene, settings);
    grid.update();
    const auto snapshot = grid.field();
    const ShRgb before = grid.data().sh[5];
    Progress progress;
    progress.cancel();
    EXPECT_THROW(grid.update(&progress), Cancelled);
    EXPECT_EQ(grid.passes(), 1u);
    EXPECT_EQ(grid.data().sh[5][0], before[0]);
    grid.update();
    // A snapshot taken before an update still reads the old probes.
    EXPECT_EQ(snapshot->data().passes, 1u);
    EXPECT_EQ(grid.passes(), 2u);
    // Renderers pin the grid through snapshot(): the current probes, held for the render, and
    // read exactly as the grid itself reads them.
    const PinnedField pinned(&grid);
    ASSERT_NE(pinned.get(), &grid);
    EXPECT_EQ(dynamic_cast<const ProbeField&>(*pinned.get()).shared_data(),
              grid.field()->shared_data());
    grid.update();
    EXPECT_EQ(dynamic_cast<const ProbeField&>(*pinned.get()).data().passes, 2u);
    const vec3 p(0.1f, 0.2f, 0.3f), n(0.0f, 0.0f, 1.0f);
    const ShRgb direct = grid.radiance_sh(p, n);
    const ShRgb via_snapshot = PinnedField(&grid).get()->radiance_sh(p, n);
    for (int i = 0; i < direct.num_coefficients(); ++i) EXPECT_EQ(direct[i], via_snapshot[i]);
    // Fields that are read directly have no snapshot.
    const ZeroField zero;
    EXPECT_EQ(PinnedField(&zero).get(), &zero);
}

TEST(ProbeGrid, RejectsBadSettingsAndEditedScenes) {
    Scene scene = test::emissive_furnace(0.5f, vec3(1.0f), 1.0f);
    ProbeGridSettings settings;
    settings.order = 5;
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); }, {"order"});
    settings = {};
    settings.hysteresis = 1.0f;
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); }, {"hysteresis is 1"});
    settings = {};
    settings.spacing = 1e-4f;
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); }, {"spacing", "at least"});
    // Named as the spacing, not as the non-finite ray origin it once became.
    settings.spacing = 1e30f;
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); },
                                  {"ProbeGridSettings.spacing is 1e+30", "(0, 1e+12]"});
    // Larger than the scene: one probe per axis in a volume the size of the scene.
    settings.spacing = 1e11f;
    const ProbeGrid single(scene, settings);
    ASSERT_EQ(single.field()->data().probe_count(), 1u);
    const vec3 extent = scene.bounds().extent();
    const mat4& m = single.field()->data().volumes[0].world_from_volume;
    for (int a = 0; a < 3; ++a) EXPECT_FLOAT_EQ(2.0f * m[a][a], extent[a]);
    settings = {};
    ProbeVolume flat;
    flat.world_from_volume = glm::scale(mat4(1.0f), vec3(1.0f, 1.0f, 0.0f));
    settings.volumes = {flat};
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); },
                                  {"volumes[0]: world_from_volume is singular"});
    // Lookups invert the matrix and probe positions become ray origins: no projective bottom
    // row, nothing beyond Embree's range.
    ProbeVolume projective;
    projective.world_from_volume[3].w = 0.0f;
    settings.volumes = {projective};
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); },
                                  {"volumes[0]: world_from_volume has the bottom row"});
    ProbeVolume huge;
    huge.world_from_volume = glm::scale(mat4(1.0f), vec3(1e30f));
    settings.volumes = {huge};
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); },
                                  {"volumes[0].world_from_volume reaches", "make the volume smaller"});
    // Too many probes, and (within the probe cap) maps too fine for the memory cap: refused by
    // name before anything is allocated, not a bad_alloc.
    ProbeVolume dense;
    dense.resolution = ivec3(256, 256, 64);
    settings.volumes = {dense};
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); },
                                  {"4194304 probes; the limit is 2097152"});
    dense.resolution = ivec3(128, 128, 64);
    settings.volumes = {dense};
    settings.visibility_resolution = 64;
    expect_error<InvalidArgument>(
        [&] { ProbeGrid(scene, settings); },
        {"1048576 probes with visibility_resolution 64 need", "lower visibility_resolution"});
    // More volumes than the probe file's header admits: a grid that could not be saved (and
    // whose lookups scan every volume).
    settings = {};
    settings.volumes.assign(kMaxProbeVolumes + 1, ProbeVolume{});
    for (ProbeVolume& volume : settings.volumes) volume.resolution = ivec3(1);
    expect_error<InvalidArgument>([&] { ProbeGrid(scene, settings); },
                                  {"ProbeGridSettings.volumes holds 4097 volumes",
                                   "a probe grid has 1..4096"});
    settings = {};
    ProbeGrid grid(scene, settings);
    scene.set_world(World{});
    expect_error<InvalidArgument>([&] { grid.update(); }, {"edited", "reset()"});
    Scene empty;
    empty.commit();
    expect_error<InvalidArgument>([&] { ProbeGrid(empty, ProbeGridSettings{}); }, {"no geometry"});
}

}  // namespace
}  // namespace shgi
