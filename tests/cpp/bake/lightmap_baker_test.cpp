// The lightmap baker against closed forms: a plane under a uniform sky (E / pi = sky radiance,
// no indirect light, the L1 SH of a uniform hemisphere), a plane under a point light (exact per
// texel: next-event estimation of a delta light has no noise), a quad in an emissive furnace
// (direct Le, indirect a Le / (1 - a)); a field source; determinism over threads and shards;
// cancel; a texel under a wall edge; the edge-aware filter (less noise, no bleeding across UV
// charts) and dilation.
#include "bake/lightmap_baker.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <cmath>
#include <limits>
#include <thread>

#include <glm/gtc/matrix_transform.hpp>

#include "bake/lightmap_filter.h"
#include "bake/unocclude.h"
#include "render/render_test_scenes.h"
#include "support/expect_error.h"
#include "support/latency_clock.h"
#include "util/error.h"

namespace shgi {
namespace {

using testing::expect_error;

constexpr float kY00 = 0.28209479177387814f;
constexpr float kY1 = 0.48860251190291992f;

// A 2 x 2 m floor facing +Z at z = 0 with LightmapUV spanning [0, 1]^2.
Mesh floor_mesh(float half = 1.0f) {
    Mesh floor = test::quad(vec3(-half, -half, 0), vec3(2 * half, 0, 0), vec3(0, 2 * half, 0));
    floor.name = "floor";
    floor.uv_sets = {{"LightmapUV", {{0, 0}, {1, 0}, {1, 1}, {0, 1}}}};
    return floor;
}

World uniform_world(float radiance) {
    World world;
    world.color = vec3(1.0f);
    world.strength = radiance;
    return world;
}

TexelMap rasterize(const Scene& scene, uint32_t instance, uint32_t resolution,
                   uint32_t samples_per_axis = 2) {
    TexelRasterSettings raster;
    raster.width = raster.height = resolution;
    raster.samples_per_axis = samples_per_axis;
    return rasterize_texels(scene, instance, raster);
}

struct Mean {
    vec3 color{0.0f};
    double sh[kLightmapShFloats] = {};
    uint64_t texels = 0;
};

Mean mean_of(const LightmapTexels& texels) {
    Mean mean;
    for (uint64_t t = 0; t < texels.texel_count(); ++t) {
        if (!texels.baked[t]) continue;
        ++mean.texels;
        mean.color += vec3(texels.color[3 * t], texels.color[3 * t + 1], texels.color[3 * t + 2]);
        if (texels.directional)
            for (int c = 0; c < kLightmapShFloats; ++c) mean.sh[c] += texels.sh[kLightmapShFloats * t + c];
    }
    mean.color /= float(mean.texels);
    for (double& c : mean.sh) c /= double(mean.texels);
    return mean;
}

Scene sky_scene(float sky, float albedo = 0.8f) {
    Scene scene;
    scene.add_material(test::lambert(albedo));
    scene.add_instance(scene.add_mesh(floor_mesh()), mat4(1.0f), "Floor");
    scene.set_world(uniform_world(sky));
    scene.commit();
    return scene;
}

TEST(LightmapBaker, PlaneUnderUniformSkyBakesTheSkyRadiance) {
    const float sky = 0.7f;
    const Scene scene = sky_scene(sky);
    const TexelMap map = rasterize(scene, 0, 16);
    LightmapSettings settings;
    settings.samples = 64;
    settings.seed = 3;
    const Mean all = mean_of(bake_lightmap(scene, map, nullptr, settings));
    EXPECT_EQ(all.texels, 256u);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(all.color[c], sky, 0.01f * sky);

    settings.content = LightmapContent::Indirect;  // nothing above the plane reflects light
    const LightmapTexels indirect = bake_lightmap(scene, map, nullptr, settings);
    for (float v : indirect.color) EXPECT_EQ(v, 0.0f);

    settings.content = LightmapContent::Full;  // times DiffCol
    const Mean full = mean_of(bake_lightmap(scene, map, nullptr, settings));
    EXPECT_NEAR(full.color.y, 0.8f * sky, 0.01f * sky);
}

TEST(LightmapBaker, DirectionalDataIsTheL1ShOfTheUniformHemisphere) {
    const float sky = 0.5f;
    const Scene scene = sky_scene(sky);
    const TexelMap map = rasterize(scene, 0, 8);
    LightmapSettings settings;
    settings.samples = 256;
    settings.directional = true;
    const LightmapTexels texels = bake_lightmap(scene, map, nullptr, settings);
    const Mean mean = mean_of(texels);
    // Incident radiance `sky` over the upper hemisphere: c00 = sky 2 pi Y00; c10 (along +Z,
    // index 2) = sky pi Y1; the tangential coefficients vanish.
    for (int rgb = 0; rgb < 3; ++rgb) {
        EXPECT_NEAR(mean.sh[0 * 3 + rgb], sky * kTwoPi * kY00, 0.01 * sky);
        EXPECT_NEAR(mean.sh[2 * 3 + rgb], sky * kPi * kY1, 0.01 * sky);
        EXPECT_NEAR(mean.sh[1 * 3 + rgb], 0.0, 0.02 * sky);
        EXPECT_NEAR(mean.sh[3 * 3 + rgb], 0.0, 0.02 * sky);
    }
    // The plain value stays the exact irradiance with uniform hemisphere sampling too.
    EXPECT_NEAR(mean.color.x, sky, 0.01f * sky);
}

// A sun (a delta light of irradiance S): its SH is S Y(towards the sun), so the L1 vector
// (c11, c1-1, c10) points at the sun with length S Y1 (what normal-mapped shading reads), while
// the plain value stays S cos(zenith) / pi.
TEST(LightmapBaker, DirectionalDataPointsAtTheSun) {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    scene.add_instance(scene.add_mesh(floor_mesh()), mat4(1.0f), "Floor");
    Light sun;
    sun.type = LightType::Sun;
    sun.strength = 3.0f;
    const float zenith = kPi / 3.0f;
    sun.world_from_light = glm::rotate(mat4(1.0f), zenith, vec3(1.0f, 0.0f, 0.0f));
    scene.add_light(sun);
    scene.set_world(test::black_world());
    scene.commit();
    const vec3 towards_sun = -sun.direction();
    const TexelMap map = rasterize(scene, 0, 4);
    LightmapSettings settings;
    settings.samples = 4;
    settings.content = LightmapContent::Direct;
    settings.directional = true;
    const LightmapTexels texels = bake_lightmap(scene, map, nullptr, settings);
    for (uint64_t t = 0; t < texels.texel_count(); ++t) {
        const float* sh = &texels.sh[kLightmapShFloats * t];
        // Green channel: coefficients c0..c3 at sh[3 * c + 1].
        EXPECT_NEAR(sh[1], sun.strength * kY00, 1e-4f);
        const vec3 l1(sh[3 * 3 + 1], sh[1 * 3 + 1], sh[2 * 3 + 1]);
        EXPECT_NEAR(glm::dot(glm::normalize(l1), towards_sun), 1.0f, 1e-5f);
        EXPECT_NEAR(glm::length(l1), sun.strength * kY1, 1e-4f);
        EXPECT_NEAR(texels.color[3 * t + 1], sun.strength * std::cos(zenith) * kInvPi, 1e-5f);
    }
}

TEST(LightmapBaker, PointLightIsExactPerTexel) {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    scene.add_instance(scene.add_mesh(floor_mesh()), mat4(1.0f), "Floor");
    const vec3 light_position(0.3f, -0.2f, 1.5f);
    const float power = 200.0f;
    scene.add_light(test::point_light(light_position, power));
    scene.set_world(test::black_world());
    scene.commit();
    const TexelMap map = rasterize(scene, 0, 8);
    LightmapSettings settings;
    settings.samples = 4;
    settings.content = LightmapContent::Direct;
    const LightmapTexels texels = bake_lightmap(scene, map, nullptr, settings);
    const float intensity = power / (4.0f * kPi);
    for (uint64_t t = 0; t < map.texel_count(); ++t) {
        double expected = 0.0, weight = 0.0;
        for (const TexelSample* s = map.samples_begin(t); s != map.samples_end(t); ++s) {
            const vec3 d = light_position - s->ray_origin;
            const float r2 = glm::dot(d, d);
            expected += s->weight * intensity * (d.z / std::sqrt(r2)) / r2 / kPi;
            weight += s->weight;
        }
        expected /= weight;
        EXPECT_NEAR(texels.color[3 * t], expected, 1e-4 * expected) << "texel " << t;
        EXPECT_NEAR(texels.variance[t], 0.0f, 1e-9f);
    }
}

// A closed emissive box of albedo a and emission Le (black world) with a two-sided quad of the
// same material floating inside it, committed: every point sees radiance Le / (1 - a) from
// everywhere, Le of it straight from an emitter.
struct Furnace {
    Scene scene;
    uint32_t quad = 0;
};

Furnace furnace(float a, float le) {
    Furnace f;
    Material material = test::lambert(a);
    material.emission_color = vec3(1.0f);
    material.emission_strength = le;
    f.scene.add_material(material);
    f.scene.add_instance(f.scene.add_mesh(test::inward_box(1.0f)), mat4(1.0f), "Furnace");
    f.quad = f.scene.add_instance(f.scene.add_mesh(floor_mesh(0.25f)),
                                  glm::translate(mat4(1.0f), vec3(0.1f, 0.0f, -0.2f)), "Quad");
    f.scene.set_world(test::black_world());
    f.scene.commit();
    return f;
}

TEST(LightmapBaker, FurnaceSplitsDirectAndIndirectLight) {
    const float a = 0.5f, le = 1.0f;
    const Furnace f = furnace(a, le);
    const Scene& scene = f.scene;
    const TexelMap map = rasterize(scene, f.quad, 4);
    LightmapSettings settings;
    settings.samples = 1024;
    settings.max_bounces = settings.diffuse_bounces = 64;
    settings.content = LightmapContent::Direct;
    EXPECT_NEAR(mean_of(bake_lightmap(scene, map, nullptr, settings)).color.x, le, 0.02f * le);
    settings.content = LightmapContent::Indirect;
    const float indirect = a * le / (1.0f - a);
    EXPECT_NEAR(mean_of(bake_lightmap(scene, map, nullptr, settings)).color.x, indirect,
                0.03f * indirect);
    // Cycles' bounce limits count the texel's own bounce: 0 diffuse bounces, no indirect light.
    settings.diffuse_bounces = 0;
    for (float v : bake_lightmap(scene, map, nullptr, settings).color) EXPECT_EQ(v, 0.0f);
}

// A field holding uniform incident radiance L everywhere: its irradiance pi L gives E / pi = L.
class UniformField : public IndirectField {
  public:
    explicit UniformField(float radiance) : radiance_(radiance) {}
    ShRgb radiance_sh(const vec3&, const vec3&) const override {
        ShRgb sh(1);
        sh[0] = vec3(radiance_ * std::sqrt(kFourPi));
        return sh;
    }

  private:
    float radiance_;
};

TEST(LightmapBaker, FieldSourceAddsTheFieldsIrradiance) {
    const float sky = 0.4f, field_radiance = 0.25f;
    const Scene scene = sky_scene(sky);
    const TexelMap map = rasterize(scene, 0, 8);
    const UniformField field(field_radiance);
    LightmapSettings settings;
    settings.samples = 64;
    settings.content = LightmapContent::Indirect;
    const Mean indirect = mean_of(bake_lightmap(scene, map, &field, settings));
    EXPECT_NEAR(indirect.color.x, field_radiance, 1e-4f);
    settings.content = LightmapContent::DirectIndirect;
    const Mean both = mean_of(bake_lightmap(scene, map, &field, settings));
    EXPECT_NEAR(both.color.x, field_radiance + sky, 0.02f * sky);
    const ZeroField zero;
    const Mean direct = mean_of(bake_lightmap(scene, map, &zero, settings));
    EXPECT_NEAR(direct.color.x, sky, 0.02f * sky);
}

// Final gather in the emissive furnace of FurnaceSplitsDirectAndIndirectLight with a uniform
// field of radiance Lf: the gather ray lands on a wall, which adds its direct light a Le (next-
// event estimation of the emissive walls) and the field's light a Lf; read at the texel, the
// field gives Lf. With Lf = a Le / (1 - a), the true indirect radiance there, both give it.
TEST(LightmapBaker, FinalGatherReadsTheFieldWhereTheGatherRayLands) {
    const float a = 0.5f, le = 1.0f;
    const Furnace f = furnace(a, le);
    const Scene& scene = f.scene;
    const TexelMap map = rasterize(scene, f.quad, 4);
    LightmapSettings settings;
    settings.samples = 1024;
    settings.content = LightmapContent::Indirect;
    for (const float lf : {0.3f, a * le / (1.0f - a)}) {
        SCOPED_TRACE(lf);
        const UniformField field(lf);
        settings.final_gather = false;
        EXPECT_NEAR(mean_of(bake_lightmap(scene, map, &field, settings)).color.x, lf, 1e-4f);
        settings.final_gather = true;
        const float gathered = a * le + a * lf;
        EXPECT_NEAR(mean_of(bake_lightmap(scene, map, &field, settings)).color.x, gathered,
                    0.03f * gathered);
    }
    // Direct light with final gather is the path tracer's estimator: Le.
    settings.content = LightmapContent::Direct;
    const UniformField field(0.3f);
    EXPECT_NEAR(mean_of(bake_lightmap(scene, map, &field, settings)).color.x, le, 0.02f * le);
}

// A lit room corner: floor, a wall and a box standing on the floor, lit by a point light; noisy
// enough that the tests below see every texel's own random numbers.
struct Room {
    Scene scene;
    uint32_t floor = 0;
};

Room room() {
    Room r;
    r.scene.add_material(test::lambert(0.7f));
    r.floor = r.scene.add_instance(r.scene.add_mesh(floor_mesh()), mat4(1.0f), "Floor");
    r.scene.add_instance(r.scene.add_mesh(test::quad(vec3(-1, 1, 0), vec3(2, 0, 0), vec3(0, 0, 2))),
                         mat4(1.0f), "Wall");
    Mesh box = test::inward_box(1.0f);
    for (uvec3& t : box.triangles) std::swap(t.y, t.z);  // outward: a solid box
    r.scene.add_instance(r.scene.add_mesh(box),
                         glm::translate(mat4(1.0f), vec3(0.03f + 0.25f, 0.0f, 0.25f)) *
                             glm::scale(mat4(1.0f), vec3(0.25f)),
                         "Box");
    r.scene.add_light(test::point_light(vec3(-0.5f, -0.3f, 1.2f), 100.0f));
    r.scene.set_world(uniform_world(0.05f));
    r.scene.commit();
    return r;
}

bool same_texels(const LightmapTexels& a, const LightmapTexels& b) {
    return a.color == b.color && a.sh == b.sh && a.variance == b.variance && a.baked == b.baked;
}

TEST(LightmapBaker, SameResultForAnyThreadCountAndShardSplit) {
    const Room r = room();
    const TexelMap map = rasterize(r.scene, r.floor, 32);
    LightmapSettings settings;
    settings.samples = 16;
    settings.directional = true;
    settings.tile_size = 8;
    LightmapTexels one_thread;
    {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
        one_thread = bake_lightmap(r.scene, map, nullptr, settings);
    }
    const LightmapTexels all = bake_lightmap(r.scene, map, nullptr, settings);
    EXPECT_TRUE(same_texels(one_thread, all));

    const uint32_t shards = 4;
    LightmapTexels merged = bake_lightmap(
        r.scene, map, nullptr, settings,
        lightmap_shard_tiles(map.width, map.height, settings.tile_size, 0, shards));
    for (uint32_t shard = 1; shard < shards; ++shard)
        merge_lightmap(merged, bake_lightmap(r.scene, map, nullptr, settings,
                                             lightmap_shard_tiles(map.width, map.height,
                                                                  settings.tile_size, shard,
                                                                  shards)));
    EXPECT_TRUE(same_texels(merged, all));
    // Merging a shard twice is an error, not a silent overwrite.
    expect_error<InvalidArgument>(
        [&] {
            merge_lightmap(merged, bake_lightmap(r.scene, map, nullptr, settings, {0}));
        },
        {"baked twice"});
}

TEST(LightmapBaker, CancelStopsPromptly) {
    const Room r = room();
    const TexelMap map = rasterize(r.scene, r.floor, 256);
    LightmapSettings settings;
    settings.samples = 4096;
    Progress progress;
    // Timed from the cancel itself: on a loaded machine the canceller may wake well after its
    // 0.2 s, which is not the bake's latency.
    testing::LatencyClock clock;
    std::thread canceller([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        clock.start();
        progress.cancel();
    });
    EXPECT_THROW(bake_lightmap(r.scene, map, nullptr, settings, {}, &progress), Cancelled);
    canceller.join();  // it ended at the cancel
    const testing::Latency latency = clock.read();
    // docs/architecture.md: a cancelled call returns within 0.2 s
    EXPECT_LT(latency.seconds(), 0.2) << latency.describe();
}

TEST(LightmapBaker, TexelUnderAWallEdgeIsNotBlackAfterUnocclude) {
    const Room r = room();
    TexelMap map = rasterize(r.scene, r.floor, 16, 1);
    // Texel column 8 spans x in [0, 0.125]; the box's face at x = 0.03 crosses it and its
    // centre (0.0625) lies under the box.
    const uint64_t texel = map.texel_index(8, 8);
    LightmapSettings settings;
    settings.samples = 64;
    settings.content = LightmapContent::Direct;
    const LightmapTexels before = bake_lightmap(r.scene, map, nullptr, settings);
    EXPECT_EQ(before.color[3 * texel], 0.0f);  // inside the box: black
    const UnoccludeReport report = unocclude(r.scene, map, UnoccludeSettings{});
    EXPECT_GT(report.moved_samples, 0u);
    const LightmapTexels after = bake_lightmap(r.scene, map, nullptr, settings);
    // Now lit like its unoccluded neighbour on the lit side.
    const float neighbour = after.color[3 * map.texel_index(7, 8)];
    EXPECT_GT(after.color[3 * texel], 0.5f * neighbour);
}

// Filter Glossy in a bake: the texel's own (diffuse) bounce is the path's first, so the surface
// its hemisphere ray meets is widened. A floor under a mirror ceiling lit by a point light beside
// them: the light's caustic through the mirror (light -> mirror -> floor) no path of an
// unfiltered bake carries (a hemisphere ray never meets a point light, a light sample never
// finds a Dirac mirror); with Filter Glossy 1 the mirror is a rough one whose light samples do,
// so the floor's indirect light grows, texel by texel. Direct light, which no path past the texel
// carries, is bit for bit the same.
TEST(LightmapBaker, FilterGlossyWidensTheSurfaceTheTexelsRayMeets) {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    scene.add_material(test::mirror(0.8f));
    scene.add_instance(scene.add_mesh(floor_mesh()), mat4(1.0f), "Floor");
    Mesh ceiling = test::plane(5.0f);
    ceiling.material_indices.assign(ceiling.triangles.size(), 1);
    scene.add_instance(scene.add_mesh(ceiling), glm::translate(mat4(1.0f), vec3(0, 0, 1.0f)),
                       "Mirror");
    scene.add_light(test::point_light(vec3(2.0f, 0.0f, 0.5f), 200.0f));
    scene.set_world(test::black_world());
    scene.commit();
    const TexelMap map = rasterize(scene, 0, 8);
    LightmapSettings settings;
    settings.samples = 64;
    settings.content = LightmapContent::Indirect;
    const LightmapTexels off = bake_lightmap(scene, map, nullptr, settings);
    settings.filter_glossy = 1.0f;
    const LightmapTexels on = bake_lightmap(scene, map, nullptr, settings);
    double sum = 0.0, sum2 = 0.0;
    uint64_t n = 0;
    for (uint64_t t = 0; t < map.texel_count(); ++t) {
        if (!off.baked[t]) continue;
        const double gain = double(on.color[3 * t]) - double(off.color[3 * t]);
        sum += gain;
        sum2 += gain * gain;
        ++n;
    }
    ASSERT_GT(n, 1u);
    const double mean = sum / double(n);
    const double error = std::sqrt(std::max(0.0, sum2 / double(n) - mean * mean) / double(n - 1));
    EXPECT_GT(mean, 5.0 * error) << "indirect light gained " << mean << " +- " << error;
    settings.content = LightmapContent::Direct;
    const LightmapTexels direct_on = bake_lightmap(scene, map, nullptr, settings);
    settings.filter_glossy = 0.0f;
    EXPECT_EQ(direct_on.color, bake_lightmap(scene, map, nullptr, settings).color);
}

TEST(LightmapBaker, RejectsBadInput) {
    const Scene scene = sky_scene(1.0f);
    const TexelMap map = rasterize(scene, 0, 8);
    LightmapSettings settings;
    settings.samples = 0;
    expect_error<InvalidArgument>([&] { bake_lightmap(scene, map, nullptr, settings); },
                                  {"samples = 0"});
    settings = {};
    expect_error<InvalidArgument>([&] { bake_lightmap(scene, map, nullptr, settings, {99}); },
                                  {"tile 99"});
    TexelMap other = map;
    other.instance_id = 5;
    expect_error<InvalidArgument>([&] { bake_lightmap(scene, other, nullptr, settings); },
                                  {"instance 5"});
    expect_error<InvalidArgument>([] { lightmap_shard_tiles(8, 8, 4, 2, 2); }, {"shard 2/2"});
    // Sides past the rasterizer's: the tile count used to wrap in 32 bits (65536^2 one-texel
    // tiles gave 0) and a 2^31-texel side listed 2^31 tiles (8 GB) before failing.
    expect_error<InvalidArgument>([] { lightmap_tile_count(65536, 65536, 1); },
                                  {"lightmap width = 65536 is outside [1, 16384]"});
    expect_error<InvalidArgument>([] { lightmap_shard_tiles(1, 0x80000000u, 1, 0, 1); },
                                  {"lightmap height = 2147483648"});
    expect_error<InvalidArgument>([] { lightmap_tile_count(0, 8, 4); }, {"lightmap width = 0"});
    EXPECT_EQ(lightmap_tile_count(16384, 16384, 1), 16384u * 16384u);
    expect_error<InvalidArgument>([] { lightmap_content_from_name("COLOR"); }, {"DIRECT_INDIRECT"});
    for (const float bad : {-1.0f, std::nanf(""), std::numeric_limits<float>::infinity()}) {
        settings = {};
        settings.filter_glossy = bad;
        expect_error<InvalidArgument>([&] { bake_lightmap(scene, map, nullptr, settings); },
                                      {"LightmapSettings.filter_glossy"});
    }
}

double rms_difference(const LightmapTexels& a, const LightmapTexels& b) {
    double sum = 0.0;
    uint64_t n = 0;
    for (uint64_t t = 0; t < a.texel_count(); ++t) {
        if (!a.baked[t]) continue;
        const double e = luminance(vec3(a.color[3 * t], a.color[3 * t + 1], a.color[3 * t + 2])) -
                         luminance(vec3(b.color[3 * t], b.color[3 * t + 1], b.color[3 * t + 2]));
        sum += e * e;
        ++n;
    }
    return std::sqrt(sum / double(n));
}

TEST(LightmapFilter, RemovesNoiseOnTheRoomFloor) {
    const Room r = room();
    TexelMap map = rasterize(r.scene, r.floor, 48, 1);
    unocclude(r.scene, map, UnoccludeSettings{});
    LightmapSettings settings;
    settings.samples = 8;
    LightmapTexels texels = bake_lightmap(r.scene, map, nullptr, settings);
    settings.samples = 256;
    settings.seed = 99;
    const LightmapTexels reference = bake_lightmap(r.scene, map, nullptr, settings);
    const double raw = rms_difference(texels, reference);
    filter_lightmap(map, texels, LightmapFilterSettings{});
    const double filtered = rms_difference(texels, reference);
    std::printf("lightmap filter, room floor 48 x 48, 8 spp: RMS error %.4f raw, %.4f filtered\n",
                raw, filtered);
    EXPECT_LT(filtered, 0.6 * raw);
}

// Two UV charts side by side in the lightmap (left half: a lit floor, right half: a floor far
// away in the dark): filtering must not carry light across the seam between them.
TEST(LightmapFilter, NeverCrossesUvCharts) {
    Scene scene;
    scene.add_material(test::lambert(0.8f));
    scene.add_instance(scene.add_mesh(test::two_charts()), mat4(1.0f), "TwoCharts");
    scene.add_light(test::point_light(vec3(-0.5f, 0.0f, 1.0f), 100.0f));
    scene.set_world(test::black_world());
    scene.commit();
    const TexelMap map = rasterize(scene, 0, 16, 1);
    ASSERT_EQ(map.chart_count, 2u);
    EXPECT_NE(map.chart[map.texel_index(7, 8)], map.chart[map.texel_index(8, 8)]);
    LightmapSettings settings;
    settings.samples = 8;
    LightmapTexels texels = bake_lightmap(scene, map, nullptr, settings);
    // The far chart is lit only faintly; its values must stay its own.
    std::vector<float> far_before;
    for (uint32_t y = 0; y < 16; ++y) far_before.push_back(texels.color[3 * map.texel_index(8, y)]);
    LightmapFilterSettings filter;
    filter.luminance_sigma = 1e6f;  // no luminance edge-stopping: only the chart test separates
    filter_lightmap(map, texels, filter);
    for (uint32_t y = 0; y < 16; ++y) {
        const float lit = texels.color[3 * map.texel_index(7, y)];
        const float dark = texels.color[3 * map.texel_index(8, y)];
        EXPECT_GT(lit, 100.0f * std::max(dark, 1e-6f));
        EXPECT_LE(dark, 2.0f * *std::max_element(far_before.begin(), far_before.end()) + 1e-6f);
    }
}

TEST(LightmapFilter, DilationFillsThePadding) {
    Scene scene;
    scene.add_material(test::lambert(0.8f));
    Mesh floor = floor_mesh();
    floor.uv_sets[0].coords = {{0.25f, 0.25f}, {0.75f, 0.25f}, {0.75f, 0.75f}, {0.25f, 0.75f}};
    scene.add_instance(scene.add_mesh(floor), mat4(1.0f), "Floor");
    scene.set_world(uniform_world(1.0f));
    scene.commit();
    const TexelMap map = rasterize(scene, 0, 32, 1);
    LightmapSettings settings;
    settings.samples = 4;
    LightmapTexels texels = bake_lightmap(scene, map, nullptr, settings);
    DilationSettings dilation;
    dilation.padding = 3;
    const std::vector<uint8_t> filled = dilate_lightmap(texels, dilation);
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) {
            // Covered: texels 8..23; within 3 of them must be filled, farther ones stay empty.
            const int distance = std::max(std::max(8 - x, x - 23), std::max(8 - y, y - 23));
            const uint64_t t = map.texel_index(x, y);
            EXPECT_EQ(filled[t] != 0, distance <= 3) << x << ", " << y;
            if (filled[t]) {
                EXPECT_GT(texels.color[3 * t], 0.5f);
            }
        }
}

}  // namespace
}  // namespace shgi
