// Bakes from an interleaved field (IndirectField::Interleave; seed 004 item 7 of issue 50): texel
// (x, y) gathers set (x mod n, y mod m) alone and a filter as wide as the pattern restores the
// whole within the texel's UV chart. Against closed forms: a field whose light is all in one set
// comes back exactly, per texel, where the window lies in the chart; it never crosses a UV seam;
// and against the same VPLs gathered whole at every texel (INSTANT_GI with one set), with the
// same result for any thread count, tile size and shard split.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bake/lightmap_baker.h"
#include "instant/instant_gi.h"
#include "render/render_test_scenes.h"

namespace shgi {
namespace {

// All of the field's light is in set (0, 0): that set holds sets_x * sets_y times the uniform
// radiance L, every other set none; gathered whole (radiance_sh) it is L. Where `lit_below_x`
// is finite, only points with x below it see any light.
class OneSetField : public IndirectField {
  public:
    OneSetField(int sets_x, int sets_y, float radiance, bool filter = true,
                float lit_below_x = INFINITY)
        : sets_x_(sets_x), sets_y_(sets_y), radiance_(radiance), filter_(filter),
          lit_below_x_(lit_below_x) {}
    ShRgb radiance_sh(const vec3& p, const vec3&) const override { return uniform(p, 1.0f); }
    Interleave interleave() const override {
        Interleave pattern;
        pattern.sets_x = sets_x_;
        pattern.sets_y = sets_y_;
        pattern.filter = filter_;
        return pattern;
    }
    ShRgb set_radiance_sh(const vec3& p, const vec3&, int x, int y) const override {
        return uniform(p, x == 0 && y == 0 ? float(sets_x_ * sets_y_) : 0.0f);
    }

  private:
    ShRgb uniform(const vec3& p, float scale) const {
        ShRgb sh(2);
        if (p.x < lit_below_x_) sh[0] = vec3(scale * radiance_ * std::sqrt(kFourPi));
        return sh;
    }
    int sets_x_, sets_y_;
    float radiance_;
    bool filter_;
    float lit_below_x_;
};

TexelMap rasterize(const Scene& scene, uint32_t instance, uint32_t resolution) {
    TexelRasterSettings raster;
    raster.width = raster.height = resolution;
    raster.samples_per_axis = 2;
    return rasterize_texels(scene, instance, raster);
}

// A 2 x 2 m floor with LightmapUV over [0, 1]^2, no lights: only the field's light is baked.
Scene dark_floor() {
    Scene scene;
    scene.add_material(test::lambert(0.8f));
    Mesh floor = test::quad(vec3(-1, -1, 0), vec3(2, 0, 0), vec3(0, 2, 0));
    floor.uv_sets = {{"LightmapUV", {{0, 0}, {1, 0}, {1, 1}, {0, 1}}}};
    scene.add_instance(scene.add_mesh(floor), mat4(1.0f), "Floor");
    scene.set_world(test::black_world());
    scene.commit();
    return scene;
}

float red(const LightmapTexels& texels, const TexelMap& map, uint32_t x, uint32_t y) {
    return texels.color[3 * map.texel_index(x, y)];
}

// Even (4: five taps, half-weight ends) and odd (3) periods restore the set's light exactly at
// every texel, the chart's edges included (a set cut off is read a period nearer the centre);
// without the filter the pattern stays.
TEST(InterleavedBake, TheFilterRestoresEverySetsLight) {
    const Scene scene = dark_floor();
    const TexelMap map = rasterize(scene, 0, 24);
    LightmapSettings settings;
    settings.samples = 1;
    settings.content = LightmapContent::Indirect;
    const float radiance = 0.3f;
    for (const auto& [n, m] : {std::pair{4, 4}, std::pair{3, 2}, std::pair{1, 3}}) {
        SCOPED_TRACE(testing::Message() << n << " x " << m << " sets");
        const OneSetField field(n, m, radiance);
        const LightmapTexels texels = bake_lightmap(scene, map, &field, settings);
        for (uint32_t y = 0; y < map.height; ++y)
            for (uint32_t x = 0; x < map.width; ++x)
                ASSERT_NEAR(red(texels, map, x, y), radiance, 1e-5f) << x << ", " << y;

        const OneSetField unfiltered(n, m, radiance, false);
        const LightmapTexels raw = bake_lightmap(scene, map, &unfiltered, settings);
        for (uint32_t y = 0; y < map.height; ++y)
            for (uint32_t x = 0; x < map.width; ++x)
                ASSERT_NEAR(red(raw, map, x, y),
                            x % uint32_t(n) == 0 && y % uint32_t(m) == 0 ? radiance * float(n * m)
                                                                         : 0.0f,
                            1e-4f);
    }
}

// Two charts side by side in UV space but 50 m apart in the world, the field lit only on the
// first: the second chart's texels next to the seam stay exactly dark. The first chart's texels
// whose window the seam cuts short read the sets cut off at their next texels on the near side
// (InterleaveWindow): set (0, 0) holds all the light, and every texel of the first chart, up to
// the seam, still comes back exactly lit.
TEST(InterleavedBake, NeverCrossesUvCharts) {
    Scene scene;
    scene.add_material(test::lambert(0.8f));
    scene.add_instance(scene.add_mesh(test::two_charts()), mat4(1.0f), "TwoCharts");
    scene.set_world(test::black_world());
    scene.commit();
    const TexelMap map = rasterize(scene, 0, 16);
    ASSERT_EQ(map.chart_count, 2u);
    ASSERT_NE(map.chart[map.texel_index(7, 8)], map.chart[map.texel_index(8, 8)]);
    LightmapSettings settings;
    settings.samples = 1;
    settings.content = LightmapContent::Indirect;
    const float radiance = 0.3f;
    const OneSetField field(4, 4, radiance, true, 25.0f);
    const LightmapTexels texels = bake_lightmap(scene, map, &field, settings);
    for (uint32_t y = 0; y < 16; ++y) {
        SCOPED_TRACE(y);
        for (uint32_t x = 0; x < 8; ++x) EXPECT_NEAR(red(texels, map, x, y), radiance, 1e-5f) << x;
        for (uint32_t x = 8; x < 16; ++x) EXPECT_EQ(red(texels, map, x, y), 0.0f) << x;
    }
}

// A lit room corner (floor, wall, a box on the floor, a point light) with INSTANT_GI's VPLs.
struct Room {
    Scene scene;
    uint32_t floor = 0;
};

Room room() {
    Room r;
    r.scene.add_material(test::lambert(0.7f));
    Mesh floor = test::quad(vec3(-1, -1, 0), vec3(2, 0, 0), vec3(0, 2, 0));
    floor.uv_sets = {{"LightmapUV", {{0, 0}, {1, 0}, {1, 1}, {0, 1}}}};
    r.floor = r.scene.add_instance(r.scene.add_mesh(floor), mat4(1.0f), "Floor");
    r.scene.add_instance(r.scene.add_mesh(test::quad(vec3(-1, 1, 0), vec3(2, 0, 0), vec3(0, 0, 2))),
                         mat4(1.0f), "Wall");
    r.scene.add_instance(
        r.scene.add_mesh(test::quad(vec3(-1, -1, 0), vec3(0, 2, 0), vec3(0, 0, 2))), mat4(1.0f),
        "SideWall");
    r.scene.add_light(test::point_light(vec3(0.3f, 0.2f, 1.2f), 100.0f));
    r.scene.set_world(test::black_world());
    r.scene.commit();
    return r;
}

std::shared_ptr<const IndirectField> solve(const Scene& scene, int sets, uint64_t photons_per_set,
                                           int passes,
                                           InstantGiFilter filter = InstantGiFilter::Sh) {
    InstantGiSettings settings;
    settings.filter_mode = filter;
    settings.sets_x = settings.sets_y = sets;
    settings.photons_per_set = photons_per_set;
    settings.seed = 3;
    InstantGi solver(scene, settings);
    for (int i = 0; i < passes; ++i) solver.refine();
    return solver.current_field();
}

double mean_red(const LightmapTexels& texels) {
    double sum = 0.0;
    uint64_t count = 0;
    for (uint64_t t = 0; t < texels.texel_count(); ++t)
        if (texels.baked[t]) sum += texels.color[3 * t], ++count;
    return sum / double(count);
}

// Relative RMS difference of the baked texels' red channel.
double relative_rms(const LightmapTexels& a, const LightmapTexels& b) {
    double error2 = 0.0, value2 = 0.0;
    for (uint64_t t = 0; t < a.texel_count(); ++t)
        if (b.baked[t]) {
            const double d = double(a.color[3 * t]) - b.color[3 * t];
            error2 += d * d;
            value2 += double(b.color[3 * t]) * b.color[3 * t];
        }
    return std::sqrt(error2 / value2);
}

// The same photons (16 sets of P, or one set of 16 P) baked interleaved and gathered whole at
// every texel: the floor's mean indirect light agrees; per texel, the filter takes the
// interleave's error against the whole gather to under half of what each texel's own set alone
// leaves (filter_mode None). Interleaving costs 1/16 of the shadow rays.
TEST(InterleavedBake, AgreesWithTheWholeGatherOfTheSameVpls) {
    const Room r = room();
    const TexelMap map = rasterize(r.scene, r.floor, 32);
    LightmapSettings settings;
    settings.samples = 1;
    settings.content = LightmapContent::Indirect;
    const auto interleaved = solve(r.scene, 4, 64, 2);
    const auto own_set = solve(r.scene, 4, 64, 2, InstantGiFilter::None);
    const auto whole = solve(r.scene, 1, 16 * 64, 2);
    ASSERT_TRUE(interleaved->interleave().interleaved());
    ASSERT_FALSE(whole->interleave().interleaved());
    const LightmapTexels a = bake_lightmap(r.scene, map, interleaved.get(), settings);
    const LightmapTexels raw = bake_lightmap(r.scene, map, own_set.get(), settings);
    const LightmapTexels b = bake_lightmap(r.scene, map, whole.get(), settings);
    const double mean_a = mean_red(a), mean_raw = mean_red(raw), mean_b = mean_red(b);
    ASSERT_GT(mean_b, 0.0);
    EXPECT_NEAR(mean_a / mean_b, 1.0, 0.02);
    EXPECT_NEAR(mean_raw / mean_b, 1.0, 0.02);
    const double filtered_error = relative_rms(a, b), raw_error = relative_rms(raw, b);
    std::printf("interleaved bake against the whole gather: relative RMS %.3f filtered, %.3f "
                "each texel's own set\n",
                filtered_error, raw_error);
    EXPECT_LT(filtered_error, 0.5 * raw_error);
}

bool same_texels(const LightmapTexels& a, const LightmapTexels& b) {
    return a.color == b.color && a.sh == b.sh && a.variance == b.variance && a.baked == b.baked;
}

// The window reaches into neighbouring tiles; each tile gathers its halo itself, so a texel's
// value does not depend on the tile size, the thread count or the shard it is baked in.
TEST(InterleavedBake, SameResultForAnyThreadCountTileSizeAndShardSplit) {
    const Room r = room();
    const TexelMap map = rasterize(r.scene, r.floor, 24);
    const auto field = solve(r.scene, 4, 16, 1);
    LightmapSettings settings;
    settings.samples = 4;
    settings.directional = true;
    settings.tile_size = 8;
    const LightmapTexels all = bake_lightmap(r.scene, map, field.get(), settings);
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        EXPECT_TRUE(same_texels(bake_lightmap(r.scene, map, field.get(), settings), all));
    }
    const uint32_t shards = 3;
    LightmapTexels merged = bake_lightmap(
        r.scene, map, field.get(), settings,
        lightmap_shard_tiles(map.width, map.height, settings.tile_size, 0, shards));
    for (uint32_t shard = 1; shard < shards; ++shard)
        merge_lightmap(merged, bake_lightmap(r.scene, map, field.get(), settings,
                                             lightmap_shard_tiles(map.width, map.height,
                                                                  settings.tile_size, shard,
                                                                  shards)));
    EXPECT_TRUE(same_texels(merged, all));
    // What a shard reads: its tiles and every tile the filter's window reaches (a period, 4
    // texels: the 8-texel tiles next to them); without an interleave, its own.
    EXPECT_EQ(lightmap_read_tiles(map.width, map.height, settings.tile_size, {0}, field.get()),
              (std::vector<uint32_t>{0, 1, 3, 4}));
    EXPECT_EQ(lightmap_read_tiles(map.width, map.height, settings.tile_size, {4}, field.get()),
              (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7, 8}));
    EXPECT_EQ(lightmap_read_tiles(map.width, map.height, settings.tile_size, {4}, nullptr),
              std::vector<uint32_t>{4});
    EXPECT_TRUE(lightmap_read_tiles(map.width, map.height, settings.tile_size, {}, field.get())
                    .empty());
    LightmapSettings other_tiles = settings;
    other_tiles.tile_size = 5;
    EXPECT_TRUE(same_texels(bake_lightmap(r.scene, map, field.get(), other_tiles), all));
}

}  // namespace
}  // namespace shgi
