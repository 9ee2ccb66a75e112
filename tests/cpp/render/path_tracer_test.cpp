// Path tracer against closed forms: white furnaces, a point light, a sun and a disk light over a
// Lambert plane; plus determinism, progressive accumulation, cancel and settings checks.
//
// Noisy estimates are compared with a tolerance of kSigmas standard errors of the pixel mean
// (pixels are independent samples of the same expectation in these scenes), plus a small
// relative floor for float accumulation.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <thread>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "render/bsdf.h"
#include "render/path_integrator.h"
#include "render/path_tracer.h"
#include "render/shading.h"
#include "render_test_scenes.h"
#include "support/expect_error.h"
#include "support/latency_clock.h"
#include "support/noise_stats.h"
#include "util/error.h"

namespace shgi {
namespace {

using test::PixelStats;

// Float accumulation and the deterministic parts (jitter inside a tiny view) stay below this.
constexpr double kRelativeFloor = 2e-3;
// The bright furnace's standard error with min(1, sqrt(T)) survival at most this share of
// min(1, T)'s (measured share: see SqrtRouletteKeepsTheMeanAndLowersTheNoiseOfABrightRoom).
constexpr double kSqrtRouletteNoiseShare = 0.9;

void expect_near_stats(const PixelStats& stats, double expected, const char* what) {
    testing::expect_within_noise(stats.mean, stats.standard_error, expected,
                                 kRelativeFloor * std::fabs(expected), what);
}

// Closed box, uniform emission Le and Lambert albedo a on every wall: L = Le / (1 - a) everywhere.
TEST(PathTracer, WhiteFurnaceClosedBox) {
    const float albedo = 0.5f, emission = 0.3f;
    const Scene scene = test::emissive_furnace(
        albedo, vec3(1.0f), emission, test::ortho_camera_down(vec3(0.1f, 0.2f, 0.3f), 1.0f, 16));
    PathTracerSettings settings = test::settings_with_samples(16);
    settings.max_bounces = settings.diffuse_bounces = 64;  // a^65 is far below the noise
    PathTracer tracer(scene, settings);
    tracer.render(settings.samples);
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::Combined), emission / (1.0 - albedo),
                      "furnace Combined");
    // Camera sees the emission directly; the rest arrives through the diffuse lobe.
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::Emit), emission, "furnace Emit");
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::DiffDir), emission,
                      "furnace DiffDir (lighting / colour)");
}

// Russian roulette's survival: both rules keep the furnace's L = Le / (1 - a), and in a bright
// closed room (albedo 0.8: a path's throughput falls slowly, light keeps arriving at every
// bounce) Cycles' min(1, sqrt(T)) leaves less noise than min(1, T), which ended paths that still
// carried a large share of the pixel. Same seed and samples for both; measured standard errors of
// the pixel mean 0.00482 (sqrt) against 0.00566 (T), a share of 0.85.
TEST(PathTracer, SqrtRouletteKeepsTheMeanAndLowersTheNoiseOfABrightRoom) {
    const float albedo = 0.8f, emission = 0.2f;
    const Scene scene = test::emissive_furnace(
        albedo, vec3(1.0f), emission, test::ortho_camera_down(vec3(0.1f, 0.2f, 0.3f), 1.0f, 64));
    PixelStats stats[2];
    for (RouletteSurvival rule : {RouletteSurvival::SqrtThroughput, RouletteSurvival::Throughput}) {
        PathTracerSettings settings = test::settings_with_samples(4);
        settings.max_bounces = settings.diffuse_bounces = 64;  // 0.8^65 is far below the noise
        settings.roulette_survival = rule;
        PathTracer tracer(scene, settings);
        tracer.render(settings.samples);
        stats[int(rule)] = test::pixel_stats(tracer.film(), Pass::Combined);
        expect_near_stats(stats[int(rule)], emission / (1.0 - albedo), "furnace Combined");
    }
    std::printf("standard error of the pixel mean: sqrt(T) %.5f, T %.5f\n",
                stats[0].standard_error, stats[1].standard_error);
    EXPECT_LT(stats[0].standard_error, kSqrtRouletteNoiseShare * stats[1].standard_error);
}

// Light Paths > Clamp as Cycles' film_clamp_light: the sum of a contribution's |RGB| against three
// times the panel's value, one factor for all three components. A saturated contribution is
// clamped by its mean, not its peak: (12, 0, 0) passes a limit of 5, which a peak clamp would
// cut to (5, 0, 0).
TEST(PathTracer, ClampScalesAContributionAsCycles) {
    EXPECT_EQ(clamp_contribution(vec3(12.0f, 0.0f, 0.0f), 5.0f), vec3(12.0f, 0.0f, 0.0f));
    const vec3 clamped = clamp_contribution(vec3(30.0f, 3.0f, 0.0f), 10.0f);
    EXPECT_NEAR(clamped.x, 30.0f * 30.0f / 33.0f, 1e-5f);
    EXPECT_NEAR(clamped.y, 3.0f * 30.0f / 33.0f, 1e-6f);
    EXPECT_EQ(clamped.z, 0.0f);
    EXPECT_NEAR((clamped.x + clamped.y + clamped.z) / 3.0f, 10.0f, 1e-5f);
    const vec3 white = clamp_contribution(vec3(12.0f), 10.0f);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(white[c], 10.0f, 1e-5f);
    EXPECT_EQ(clamp_contribution(vec3(-6.0f, 0.0f, 0.0f), 1.0f), vec3(-3.0f, 0.0f, 0.0f));
    EXPECT_EQ(clamp_contribution(vec3(1e6f, 2.0f, 3.0f), 0.0f), vec3(1e6f, 2.0f, 3.0f));  // off
}

// Bounce limits: max_bounces = 1 keeps Le (1 + a + a^2).
TEST(PathTracer, FurnaceTruncatedByMaxBounces) {
    const float albedo = 0.5f, emission = 1.0f;
    const Scene scene = test::emissive_furnace(albedo, vec3(1.0f), emission,
                                               test::ortho_camera_down(vec3(0.0f), 1.0f, 16));
    PathTracerSettings settings = test::settings_with_samples(16);
    settings.max_bounces = 1;
    PathTracer tracer(scene, settings);
    tracer.render(settings.samples);
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::Combined),
                      emission * (1.0 + albedo + albedo * albedo), "max_bounces = 1");
}

// Nothing but the world: every pixel is the world radiance, in Combined and Env.
TEST(PathTracer, WorldSeenDirectly) {
    Scene scene;
    World world;
    world.color = vec3(0.2f, 0.4f, 0.6f);
    world.strength = 1.5f;
    scene.set_world(world);
    scene.set_camera(test::ortho_camera_down(vec3(0.0f), 1.0f, 4));
    scene.commit();
    const Image image = render_path_traced(scene, test::settings_with_samples(2));
    const std::vector<float> combined = image.layer_pixels("Combined");
    const std::vector<float> env = image.layer_pixels("Env");
    for (size_t i = 0; i < 16; ++i)
        for (int c = 0; c < 3; ++c) {
            EXPECT_FLOAT_EQ(combined[i * 4 + size_t(c)], world.radiance()[c]);
            EXPECT_FLOAT_EQ(env[i * 3 + size_t(c)], world.radiance()[c]);
        }
}

// A convex Lambert sphere of albedo 1 under a uniform world reflects exactly the world radiance.
TEST(PathTracer, WhiteSphereUnderUniformWorld) {
    Scene scene;
    scene.add_material(test::lambert(1.0f));
    scene.add_instance(scene.add_mesh(test::uv_sphere(1.0f)), mat4(1.0f));
    World world;
    world.color = vec3(1.0f);
    world.strength = 0.7f;
    scene.set_world(world);
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 3.0f), 0.8f, 12));
    scene.commit();
    for (WorldSampling sampling : {WorldSampling::Cosine, WorldSampling::Uniform}) {
        PathTracerSettings settings = test::settings_with_samples(16);
        settings.world_sampling = sampling;
        PathTracer tracer(scene, settings);
        tracer.render(settings.samples);
        expect_near_stats(test::pixel_stats(tracer.film(), Pass::Combined), 0.7, "white sphere");
    }
}

// Point light of power P at height h over a plane of albedo rho, measured from Cycles 3.4:
// L = rho / pi * P / (4 pi h^2).
TEST(PathTracer, PointLightOverLambertPlane) {
    const float albedo = 0.8f, power = 100.0f, height = 2.0f;
    Scene scene = test::plane_scene(albedo);
    scene.add_light(test::point_light(vec3(0.0f, 0.0f, height), power));
    scene.commit();
    PathTracer tracer(scene, test::settings_with_samples(4));
    tracer.render(4);
    const double expected = albedo * kInvPi * power * kInvFourPi / (height * height);
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::Combined), expected, "point");
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::DiffDir), expected / albedo,
                      "point DiffDir");
}

// Sun of strength S at 60 degrees from the zenith: L = rho / pi * S cos(60).
TEST(PathTracer, SunOverLambertPlane) {
    const float albedo = 0.5f, strength = 3.0f, zenith = kPi / 3.0f;
    Scene scene = test::plane_scene(albedo);
    Light light;
    light.type = LightType::Sun;
    light.strength = strength;
    light.world_from_light = glm::rotate(mat4(1.0f), zenith, vec3(1.0f, 0.0f, 0.0f));
    scene.add_light(light);
    scene.commit();
    PathTracer tracer(scene, test::settings_with_samples(4));
    tracer.render(4);
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::Combined),
                      albedo * kInvPi * strength * std::cos(zenith), "sun");
}

// Disk area light of power P, diameter d, on axis at height h: E = pi L sin^2(theta) with
// L = P / (4 A) and sin^2(theta) = R^2 / (R^2 + h^2).
TEST(PathTracer, DiskAreaLightOnAxis) {
    const float albedo = 0.8f, power = 100.0f, radius = 0.5f, height = 1.0f;
    Scene scene = test::plane_scene(albedo, 8);
    Light light;
    light.type = LightType::Area;
    light.shape = AreaShape::Disk;
    light.size_x = 2.0f * radius;
    light.power = power;
    light.world_from_light = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, height));
    scene.add_light(light);
    scene.commit();
    PathTracer tracer(scene, test::settings_with_samples(64));
    tracer.render(64);
    const double radiance = power / (4.0 * kPiD * radius * radius);
    const double irradiance = kPiD * radiance * radius * radius / (radius * radius + height * height);
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::Combined), albedo / kPiD * irradiance,
                      "disk light");
}

// An emissive quad seen straight on: Emit = emission colour x strength.
TEST(PathTracer, EmissionSeenByCamera) {
    Scene scene;
    Material material = test::lambert(0.0f);
    material.emission_color = vec3(1.0f, 0.5f, 0.25f);
    material.emission_strength = 2.5f;
    scene.add_material(material);
    scene.add_instance(scene.add_mesh(test::plane(10.0f)), mat4(1.0f));
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 1.0f), 1.0f, 4));
    scene.commit();
    PathTracer tracer(scene, test::settings_with_samples(2));
    tracer.render(2);
    const std::vector<float> emit = tracer.film().pixels(Pass::Emit);
    EXPECT_FLOAT_EQ(emit[0], 2.5f);
    EXPECT_FLOAT_EQ(emit[1], 1.25f);
    EXPECT_FLOAT_EQ(emit[2], 0.625f);
    const std::vector<float> depth = tracer.film().pixels(Pass::Depth);
    EXPECT_NEAR(depth[0], 1.0f, 1e-5f);
}

// Lights facing the camera from in front of an unlit plane: the camera sees their radiance only
// with visible_camera (Blender's default for lights is off); otherwise it sees through them.
TEST(PathTracer, CameraSeesLightsOnlyWhenVisibleToCamera) {
    const float power = 50.0f, radius = 0.1f;
    Light area;
    area.type = LightType::Area;
    area.shape = AreaShape::Disk;
    area.size_x = 2.0f * radius;
    area.power = power;
    // Emits along its local -Z, turned to face +Z (the camera above).
    area.world_from_light = glm::rotate(glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, 0.25f)), kPi,
                                        vec3(1.0f, 0.0f, 0.0f));
    Light point = test::point_light(vec3(0.0f, 0.0f, 0.25f), power);
    point.radius = radius;
    const float disk_area = kPi * radius * radius;
    const struct {
        Light light;
        float radiance;
    } cases[] = {{area, power / (4.0f * disk_area)},
                 {point, power * kInvFourPi / disk_area}};
    for (const auto& c : cases) {
        for (bool visible : {false, true}) {
            Scene scene = test::plane_scene(0.0f);  // black plane: only the light can be seen
            Light light = c.light;
            light.visible_camera = visible;
            scene.add_light(light);
            scene.commit();
            PathTracer tracer(scene, test::settings_with_samples(2));
            tracer.render(2);
            const float expected = visible ? c.radiance : 0.0f;
            for (float emit : tracer.film().pixels(Pass::Emit))
                EXPECT_NEAR(emit, expected, 1e-4f * c.radiance)
                    << "light type " << int(light.type) << " visible " << visible;
        }
    }
}

// A glossy + diffuse scene used by the determinism and pass tests.
Scene mixed_scene() {
    Scene scene;
    Material floor = test::lambert(0.7f);
    floor.specular = 0.5f;
    floor.roughness = 0.3f;
    Material glass;
    glass.transmission = 1.0f;
    glass.roughness = 0.2f;
    scene.add_material(floor);
    scene.add_material(glass);
    Mesh sphere = test::uv_sphere(0.5f, 12, 24);
    sphere.material_indices.assign(sphere.triangles.size(), 1);
    scene.add_instance(scene.add_mesh(test::plane(5.0f)), mat4(1.0f));
    scene.add_instance(scene.add_mesh(sphere), glm::translate(mat4(1.0f), vec3(0, 0, 0.6f)));
    Light light;
    light.type = LightType::Area;
    light.power = 200.0f;
    light.world_from_light = glm::translate(mat4(1.0f), vec3(0.5f, 0.0f, 3.0f));
    scene.add_light(light);
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 4.0f), 3.0f, 12));
    scene.commit();
    return scene;
}

std::vector<float> render_combined(const Scene& scene, int threads, uint32_t samples) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    PathTracerSettings settings;
    settings.samples = samples;
    settings.seed = 7;
    settings.tile_size = threads == 1 ? 16 : 5;  // a different tile split must not matter
    return render_path_traced(scene, settings).layer_pixels("Combined");
}

// PathIntegrator::restart (the preview's wave re-arms one integrator per slot): paths traced
// one after another by one restarted integrator, into one rng and one values entry, give the
// bits of paths each traced by a new integrator with the same setters, Combined only or not,
// with and without a final gather.
TEST(PathTracer, RestartedIntegratorTracesAsANewOne) {
    const Scene scene = mixed_scene();
    PathTracerSettings settings;
    const LightSampler lights(scene, settings.world_sampling, true, settings.light_splits);
    const Camera& camera = scene.camera();
    const CameraRayGenerator camera_rays(camera);
    for (const bool combined_only : {false, true})
        for (const int final_gather : {0, 1}) {
            Pcg32 kept_rng(1, 0);
            PassValues kept_values;
            std::optional<PathIntegrator> kept;
            int lit = 0;
            for (uint64_t pixel = 0; pixel < 144; ++pixel) {
                const vec2 film(float(pixel % 12) + 0.5f, float(pixel / 12) + 0.5f);
                const Ray ray = camera_rays.generate_ray(film);
                const PixelSample sample = pixel_sample(7, pixel, 0);
                const auto setup = [&](PathIntegrator& path) {
                    path.set_first_light_sample(sample.u_select, sample.u_light);
                    path.set_gather_number(0.25f);
                };
                Pcg32 rng(7, stream_id(0, pixel));
                PassValues values;
                PathIntegrator fresh(scene, camera, lights, settings, nullptr, rng, values);
                fresh.set_final_gather(final_gather);
                if (combined_only) fresh.set_combined_only();
                setup(fresh);
                fresh.trace(ray);

                kept_rng = Pcg32(7, stream_id(0, pixel));
                kept_values = PassValues{};
                if (kept) {
                    kept->restart();
                } else {
                    kept.emplace(scene, camera, lights, settings, nullptr, kept_rng, kept_values);
                    kept->set_final_gather(final_gather);
                    if (combined_only) kept->set_combined_only();
                }
                setup(*kept);
                kept->trace(ray);
                ASSERT_EQ(std::memcmp(&values, &kept_values, sizeof(PassValues)), 0)
                    << "pixel " << pixel << " combined_only " << combined_only
                    << " final_gather " << final_gather;
                if (values[Pass::Combined].x > 0.0f) ++lit;
            }
            EXPECT_GT(lit, 100);  // the paths met lit surfaces, not only misses
        }
}

// The first bounce's lobe choice and direction are one 3-D stratified point: among a pixel's
// first 64 samples those whose u_lobe picks the first half of the lobes still cover the
// direction square evenly (two in each of its 16 quarter-by-quarter cells), so a lobe's
// directions stay stratified. With an independent u_lobe the chosen half is a random subset.
TEST(PathTracer, FirstBsdfSampleKeepsEachLobeStratified) {
    for (uint64_t pixel : {0u, 17u, 4095u}) {
        int cells[16] = {};
        for (uint32_t s = 0; s < 64; ++s) {
            const PixelSample sample = pixel_sample(5, pixel, s, true);
            if (sample.u_lobe >= 0.5f) continue;
            ++cells[int(sample.u_bsdf.x * 4.0f) * 4 + int(sample.u_bsdf.y * 4.0f)];
        }
        for (int cell = 0; cell < 16; ++cell)
            EXPECT_EQ(cells[cell], 2) << "pixel " << pixel << " cell " << cell;
    }
}

TEST(PathTracer, DeterministicAcrossThreadsAndTiles) {
    const Scene scene = mixed_scene();
    EXPECT_EQ(render_combined(scene, 1, 4), render_combined(scene, 2, 4));
}

TEST(PathTracer, ProgressiveEqualsOneShot) {
    const Scene scene = mixed_scene();
    PathTracerSettings settings;
    settings.seed = 7;
    PathTracer progressive(scene, settings);
    progressive.render(1);
    progressive.render(3);
    EXPECT_EQ(progressive.samples_done(), 4u);
    PathTracer one_shot(scene, settings);
    one_shot.render(4);
    EXPECT_EQ(progressive.film().pixels(Pass::Combined), one_shot.film().pixels(Pass::Combined));
}

// Combined = sum of the light passes times their colours, plus Emit and Env (Cycles' recipe).
TEST(PathTracer, PassesRecombineToCombined) {
    const Scene scene = mixed_scene();
    PathTracerSettings settings;
    settings.samples = 4;
    PathTracer tracer(scene, settings);
    tracer.render(settings.samples);
    const Film& film = tracer.film();
    auto get = [&](Pass pass) { return film.pixels(pass); };
    const auto combined = get(Pass::Combined), emit = get(Pass::Emit), env = get(Pass::Env);
    const Pass groups[3][3] = {{Pass::DiffDir, Pass::DiffInd, Pass::DiffCol},
                               {Pass::GlossDir, Pass::GlossInd, Pass::GlossCol},
                               {Pass::TransDir, Pass::TransInd, Pass::TransCol}};
    std::vector<double> sum(combined.size() / 4 * 3, 0.0);
    for (size_t i = 0; i < sum.size(); ++i) sum[i] = double(emit[i]) + double(env[i]);
    for (const auto& group : groups) {
        const auto dir = get(group[0]), ind = get(group[1]), col = get(group[2]);
        for (size_t i = 0; i < sum.size(); ++i) sum[i] += (double(dir[i]) + ind[i]) * col[i];
    }
    // The colour passes are per-pixel sample means: exact while the first-hit colour does not
    // change inside a pixel; edge pixels (floor / sphere) may mix, so compare the image sums.
    double total_combined = 0.0, total_sum = 0.0;
    for (size_t i = 0; i < sum.size(); ++i) {
        total_combined += combined[i / 3 * 4 + i % 3];
        total_sum += sum[i];
    }
    EXPECT_GT(total_combined, 0.0);
    EXPECT_NEAR(total_sum, total_combined, 0.05 * total_combined);
    const Image image = tracer.image();
    for (const char* name : {"Combined.A", "DiffDir.R", "GlossInd.G", "TransCol.B", "Emit.R",
                             "Env.B", "Normal.X", "Normal.Z", "Depth.Z"})
        EXPECT_NE(image.find_channel(name), nullptr) << name;
}

TEST(PathTracer, CancelThrowsPromptly) {
    const Scene scene = mixed_scene();
    PathTracerSettings settings;
    settings.samples = 1u << 16;  // minutes of work if not cancelled
    Progress progress;
    testing::LatencyClock clock;
    std::thread canceller([&] {
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        clock.start();
        progress.cancel();
    });
    PathTracer tracer(scene, settings);
    EXPECT_THROW(tracer.render(settings.samples, &progress), Cancelled);
    canceller.join();  // it ended at the cancel
    const testing::Latency latency = clock.read();
    EXPECT_LT(latency.seconds(), 0.2) << latency.describe();  // docs/architecture.md: within 0.2 s
    EXPECT_EQ(tracer.samples_done(), 0u);  // the film is left as it was
}

// A cancel while the film already holds samples (summed into the second film, not in place)
// leaves it as it was, and rendering continues as if the cancelled call never happened.
TEST(PathTracer, CancelLeavesAFilmWithSamplesUnchanged) {
    const Scene scene = mixed_scene();
    PathTracerSettings settings;
    settings.seed = 3;
    PathTracer tracer(scene, settings);
    tracer.render(1);
    const std::vector<float> before = tracer.film().pixels(Pass::Combined);
    Progress cancelled;
    cancelled.cancel();
    EXPECT_THROW(tracer.render(2, &cancelled), Cancelled);
    EXPECT_EQ(tracer.samples_done(), 1u);
    EXPECT_EQ(tracer.film().pixels(Pass::Combined), before);
    tracer.render(2);
    PathTracer one_shot(scene, settings);
    one_shot.render(3);
    EXPECT_EQ(tracer.film().pixels(Pass::Combined), one_shot.film().pixels(Pass::Combined));
}

// A tracer caches light tables and a film sized for the scene it was built on; after an edit
// (here: one more light, recommitted) it must refuse to render rather than index stale tables.
TEST(PathTracer, RefusesASceneEditedAfterConstruction) {
    Scene scene = mixed_scene();
    PathTracerSettings settings;
    settings.samples = 1;
    PathTracer tracer(scene, settings);
    tracer.render(1);
    scene.add_light(Light{});
    scene.commit();
    testing::expect_invalid_argument([&] { tracer.render(1); }, "edited after this PathTracer");
    EXPECT_EQ(tracer.samples_done(), 1u);
}

TEST(PathTracer, RejectsInvalidSettings) {
    const Scene scene = mixed_scene();
    auto expect_message = [&](PathTracerSettings settings, const std::string& field) {
        testing::expect_invalid_argument([&] { PathTracer tracer(scene, settings); }, field);
    };
    PathTracerSettings s;
    s.max_bounces = -1;
    expect_message(s, "max_bounces");
    s = {};
    s.samples = 0;
    expect_message(s, "samples");
    s = {};
    s.clamp_indirect = -1.0f;
    expect_message(s, "clamp_indirect");
    s = {};
    s.tile_size = 0;
    expect_message(s, "tile_size");
    for (const float bad : {-1.0f, std::nanf(""), kInfinity}) {
        s = {};
        s.filter_glossy = bad;
        expect_message(s, "PathTracerSettings.filter_glossy");
    }
    Scene uncommitted;
    EXPECT_THROW(PathTracer(uncommitted, PathTracerSettings{}), InvalidArgument);
}

// --- Light Paths > Filter Glossy (PathTracerSettings.filter_glossy) ---

Image render_filtered(const Scene& scene, float filter_glossy, uint32_t samples, int threads = 2) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    PathTracerSettings settings;
    settings.samples = samples;
    settings.seed = 11;
    settings.filter_glossy = filter_glossy;
    settings.tile_size = threads == 1 ? 16 : 5;
    return render_path_traced(scene, settings);
}

// The blur acts only after a bounce of low pdf: light that reaches the camera after one
// scattering (the first surface's NEE and the emitters its BSDF ray meets) is bit for bit what it
// is without the filter, so the first surface (a glossy floor, alpha 0.09, and rough glass) is
// never widened, while the indirect light, whose later surfaces are widened, changes.
TEST(PathTracer, FilterGlossyLeavesTheFirstScatteringAlone) {
    const Scene scene = mixed_scene();
    const Image off = render_filtered(scene, 0.0f, 8);
    const Image on = render_filtered(scene, 1.0f, 8);
    for (const char* pass : {"DiffDir", "GlossDir", "TransDir", "Emit", "Env", "DiffCol",
                             "GlossCol", "TransCol", "Normal", "Depth"})
        EXPECT_EQ(on.layer_pixels(pass), off.layer_pixels(pass)) << pass;
    EXPECT_NE(on.layer_pixels("GlossInd"), off.layer_pixels("GlossInd"));
}

// A filter no bounce's pdf falls under changes nothing: tracking the path's lowest pdf draws no
// random number and touches no sum, so the image is bit-identical to the unfiltered one.
TEST(PathTracer, FilterGlossyBelowEveryPdfIsBitIdenticalToOff) {
    const Scene scene = mixed_scene();
    EXPECT_EQ(render_filtered(scene, 1e-30f, 4).layer_pixels("Combined"),
              render_filtered(scene, 0.0f, 4).layer_pixels("Combined"));
}

TEST(PathTracer, FilterGlossyIsDeterministicAcrossThreadsAndTiles) {
    const Scene scene = mixed_scene();
    EXPECT_EQ(render_filtered(scene, 1.0f, 4, 1).layer_pixels("Combined"),
              render_filtered(scene, 1.0f, 4, 2).layer_pixels("Combined"));
}

// A mirror floor under a Lambert ceiling, lit by a point light between them 2 m to the side (the
// half-metre view's light changes little across it), seen in the mirror. A path tracer cannot
// carry the light's caustic (light -> mirror -> ceiling): no BSDF ray meets a point light and no
// light sample finds a Dirac mirror. After the ceiling's diffuse bounce (pdf <= 1/pi) Filter
// Glossy 1 widens the mirror to alpha >= sqrt(1 - 1/pi) / 2 = 0.41, whose light samples do reach
// the light: the ceiling, seen in the mirror, brightens (GlossInd, light that scattered more than
// once), and only light after the ceiling's bounce changes.
TEST(PathTracer, FilterGlossyLetsLightSamplesReachAMirrorAfterADiffuseBounce) {
    Scene scene;
    test::add_mirror_under_ceiling(&scene);
    scene.add_light(test::point_light(vec3(2.0f, 0.0f, 0.5f), 200.0f));
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.5f), 0.5f, 8));
    scene.commit();
    PathTracerSettings settings = test::settings_with_samples(64);
    settings.max_bounces = settings.glossy_bounces = settings.diffuse_bounces = 2;
    PathTracer off(scene, settings);
    off.render(settings.samples);
    settings.filter_glossy = 1.0f;
    PathTracer on(scene, settings);
    on.render(settings.samples);
    const PixelStats unfiltered = test::pixel_stats(off.film(), Pass::GlossInd);
    const PixelStats filtered = test::pixel_stats(on.film(), Pass::GlossInd);
    EXPECT_GT(filtered.mean - unfiltered.mean,
              5.0 * std::hypot(filtered.standard_error, unfiltered.standard_error))
        << "GlossInd " << unfiltered.mean << " unfiltered, " << filtered.mean << " filtered";
    EXPECT_EQ(on.film().pixels(Pass::GlossDir), off.film().pixels(Pass::GlossDir));
}

// --- The denoiser's guides (Denoising Albedo / Normal), as Cycles writes them ---

// Lambert floor (albedo `floor_albedo`, z = 0) seen from above through an orthographic camera at
// z = 0.5 and, when `cover` is given, through a 2 x 2 m pane of it at z = 0.25; black world.
Scene guide_scene(float floor_albedo, const std::optional<Material>& cover, uint32_t resolution,
                  float cover_height = 0.25f) {
    Scene scene;
    scene.add_material(test::lambert(floor_albedo));
    scene.add_instance(scene.add_mesh(test::plane(5.0f)), mat4(1.0f));
    if (cover) {
        scene.add_material(*cover);
        Mesh pane = test::plane(1.0f);
        pane.material_indices.assign(pane.triangles.size(), 1);
        scene.add_instance(scene.add_mesh(pane),
                           glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, cover_height)));
    }
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.5f), 1.0f, resolution));
    scene.commit();
    return scene;
}

// Where the first surface is not specular, the guides are its closure weights and its normal:
// DiffCol + GlossCol + TransCol and the Normal pass (a rough glossy floor, alpha 0.09).
TEST(PathTracer, DenoisingGuidesOfARoughSurfaceAreItsOwn) {
    Material rough_glossy = test::lambert(0.6f);
    rough_glossy.specular = 0.5f;
    rough_glossy.roughness = 0.3f;
    rough_glossy.diffuse_model = DiffuseModel::Principled;
    const Scene scene = guide_scene(0.5f, rough_glossy, 8);
    PathTracer tracer(scene, test::settings_with_samples(4));
    tracer.render(4);
    const Film& film = tracer.film();
    const std::vector<float> albedo = film.pixels(Pass::DenoisingAlbedo);
    const std::vector<float> normal = film.pixels(Pass::DenoisingNormal);
    const std::vector<float> diff = film.pixels(Pass::DiffCol);
    const std::vector<float> gloss = film.pixels(Pass::GlossCol);
    const std::vector<float> trans = film.pixels(Pass::TransCol);
    EXPECT_EQ(normal, film.pixels(Pass::Normal));
    for (size_t i = 0; i < albedo.size(); ++i)
        EXPECT_NEAR(albedo[i], diff[i] + gloss[i] + trans[i], 1e-5f) << i;
    EXPECT_GT(gloss[0], 0.0f);
}

// A perfect mirror (metallic, roughness 0, reflectance 0.8) facing up under a Lambert ceiling of
// albedo 0.6 at z = 1: every camera ray reflects straight up, so the guides are the ceiling's,
// albedo 0.6 x 0.8 and normal -Z, in every pixel and sample, while the first-hit passes stay the
// mirror's.
TEST(PathTracer, DenoisingGuidesFollowAMirror) {
    Scene scene;
    test::add_mirror_under_ceiling(&scene);
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.5f), 1.0f, 8));
    scene.commit();
    PathTracer tracer(scene, test::settings_with_samples(4));
    tracer.render(4);
    const std::vector<float> albedo = tracer.film().pixels(Pass::DenoisingAlbedo);
    const std::vector<float> normal = tracer.film().pixels(Pass::DenoisingNormal);
    const std::vector<float> first_normal = tracer.film().pixels(Pass::Normal);
    const std::vector<float> gloss = tracer.film().pixels(Pass::GlossCol);
    for (size_t i = 0; i < albedo.size(); i += 3) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(albedo[i + size_t(c)], 0.6f * 0.8f, 1e-5f) << i;
        EXPECT_NEAR(normal[i + 2], -1.0f, 1e-5f) << i;
        EXPECT_NEAR(first_normal[i + 2], 1.0f, 1e-5f) << i;
        EXPECT_NEAR(gloss[i], 1.0f, 1e-5f) << i;  // the mirror's closure weight
    }
}

// Clear tinted glass (roughness 0, ior 1.45, tint t) over a Lambert floor of albedo 0.5, seen at
// normal incidence. The pane's lobes are glass reflection (weight F) and refraction (weight
// (1 - F) t), both specular, so a sample takes the refraction with probability p = avg((1 - F) t)
// / (F + avg((1 - F) t)) and reaches the floor, whose albedo it writes times the pane's albedo
// F + (1 - F) t; a reflected sample escapes to the world and writes nothing (as in Cycles). So
// the guides' means are p 0.5 (F + (1 - F) t) and a normal of p (0, 0, 1).
TEST(PathTracer, DenoisingGuidesSeeThroughClearGlass) {
    const vec3 tint(0.9f, 0.7f, 0.5f);
    const float ior = 1.45f;
    Material glass;
    glass.base_color = tint;
    glass.transmission = 1.0f;
    glass.roughness = 0.0f;
    glass.ior = ior;
    const Scene scene = guide_scene(0.5f, glass, 16);
    PathTracer tracer(scene, test::settings_with_samples(64));
    tracer.render(64);
    const float fresnel = fresnel_dielectric(1.0f, ior);
    const vec3 refraction = (1.0f - fresnel) * tint;
    const float refraction_mean = (refraction.x + refraction.y + refraction.z) / 3.0f;
    const float p = refraction_mean / (fresnel + refraction_mean);
    for (int c = 0; c < 3; ++c)
        expect_near_stats(test::pixel_stats(tracer.film(), Pass::DenoisingAlbedo, c),
                          p * 0.5f * (fresnel + refraction[c]), "albedo through the glass");
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::DenoisingNormal, 2), p,
                      "normal through the glass");
    // The first-hit passes stay the pane's: TransCol its refraction weight, Normal up.
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::TransCol, 0), refraction.x,
                      "TransCol");
    expect_near_stats(test::pixel_stats(tracer.film(), Pass::Normal, 2), 1.0, "Normal");
}

// A rough pane (roughness 0.5, alpha 0.25 > kDenoisingSpecularAlpha) stops the guides at itself.
TEST(PathTracer, DenoisingGuidesStopAtRoughGlass) {
    Material frosted;
    frosted.transmission = 1.0f;
    frosted.roughness = 0.5f;
    const Scene scene = guide_scene(0.5f, frosted, 8);
    PathTracer tracer(scene, test::settings_with_samples(4));
    tracer.render(4);
    EXPECT_EQ(tracer.film().pixels(Pass::DenoisingNormal), tracer.film().pixels(Pass::Normal));
    const std::vector<float> albedo = tracer.film().pixels(Pass::DenoisingAlbedo);
    const std::vector<float> trans = tracer.film().pixels(Pass::TransCol);
    const std::vector<float> gloss = tracer.film().pixels(Pass::GlossCol);
    for (size_t i = 0; i < albedo.size(); ++i)
        EXPECT_NEAR(albedo[i], trans[i] + gloss[i], 1e-5f) << i;
}

}  // namespace
}  // namespace shgi
