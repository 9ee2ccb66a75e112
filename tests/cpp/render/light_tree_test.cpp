// Many-light selection (render/light_tree.h, render/light_sampler.h) against its own pdf: the
// tree's choices pass a χ² test against pmf(), its pmfs sum to one, emitters that cannot light a
// point (behind a one-sided area light, outside a spot's cone) get none of its samples, the
// light sampler's selection pdfs sum to one over local and distant emitters, and next-event
// estimation over many lights converges to their analytic irradiance.
#include "render/light_tree.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "render/light_sampler.h"
#include "render/render_test_scenes.h"
#include "support/chi2.h"
#include "util/rng.h"

namespace shgi {
namespace {

using testing::chi2_test;

constexpr int kSamples = 400000;
// Float products of a dozen probabilities sum to one within this.
constexpr double kPmfSumTolerance = 1e-5;

LightBounds point_bounds(const vec3& position, float intensity) {
    LightBounds b;
    b.bounds.extend(position);
    b.energy = intensity;
    return b;
}

LightBounds one_sided(const vec3& centre, const vec3& axis, float half, float intensity) {
    LightBounds b;
    b.bounds.extend(centre - vec3(half));
    b.bounds.extend(centre + vec3(half));
    b.axis = axis;
    b.theta_o = 0.0f;
    b.theta_e = kPi / 2.0f;
    b.energy = intensity;
    return b;
}

// Twenty lights of mixed kinds and intensities scattered over a 20 m box, one facing away from
// everything below it.
std::vector<LightBounds> mixed_lights() {
    std::vector<LightBounds> lights;
    Pcg32 rng(5);
    for (int i = 0; i < 16; ++i) {
        const vec3 p(rng.next_float() * 20.0f - 10.0f, rng.next_float() * 20.0f - 10.0f,
                     rng.next_float() * 5.0f);
        lights.push_back(i % 2 ? point_bounds(p, 1.0f + 100.0f * rng.next_float())
                               : one_sided(p, glm::normalize(vec3(rng.next_float() - 0.5f,
                                                                  rng.next_float() - 0.5f, -1.0f)),
                                           0.3f, 5.0f));
    }
    lights.push_back(one_sided(vec3(0.0f, 0.0f, 8.0f), vec3(0.0f, 0.0f, 1.0f), 0.5f, 1000.0f));
    LightBounds spot = point_bounds(vec3(3.0f, 3.0f, 6.0f), 50.0f);
    spot.axis = vec3(0.0f, 0.0f, -1.0f);
    spot.theta_o = 0.3f;
    spot.theta_e = 0.0f;
    lights.push_back(spot);
    return lights;
}

TEST(LightTree, ChoicesPassChiSquareAgainstPmfWhichSumsToOne) {
    const std::vector<LightBounds> lights = mixed_lights();
    const LightTree tree(lights);
    Pcg32 rng(11);
    for (const vec3& p : {vec3(0.0f), vec3(-8.0f, 4.0f, 1.0f), vec3(3.0f, 3.0f, 0.0f)}) {
        double sum = 0.0;
        std::vector<double> expected(lights.size());
        for (uint32_t i = 0; i < lights.size(); ++i) {
            expected[i] = double(tree.pmf(p, i)) * kSamples;
            sum += tree.pmf(p, i);
        }
        EXPECT_NEAR(sum, 1.0, kPmfSumTolerance) << "at (" << p.x << ", " << p.y << ", " << p.z << ")";
        std::vector<double> observed(lights.size(), 0.0);
        for (int s = 0; s < kSamples; ++s) {
            uint32_t chosen;
            float pmf;
            ASSERT_TRUE(tree.sample(p, rng.next_float(), &chosen, &pmf));
            EXPECT_FLOAT_EQ(pmf, tree.pmf(p, chosen));
            observed[chosen] += 1.0;
        }
        const std::string failure = chi2_test(observed, expected);
        EXPECT_TRUE(failure.empty()) << failure;
    }
}

TEST(LightTree, EmittersThatCannotLightAPointAreNeverChosen) {
    const std::vector<LightBounds> lights = mixed_lights();
    const LightTree tree(lights);
    const uint32_t up_facing = uint32_t(lights.size() - 2), spot = uint32_t(lights.size() - 1);
    // Below the upward-facing area light, and far outside the spot's 0.3 rad cone.
    EXPECT_EQ(tree.pmf(vec3(-9.0f, -9.0f, 0.0f), up_facing), 0.0f);
    EXPECT_EQ(tree.pmf(vec3(-9.0f, -9.0f, 0.0f), spot), 0.0f);
    // Straight under the spot it gets more than its share of the intensity (what selection by
    // power gave it everywhere).
    double total = 0.0;
    for (const LightBounds& light : lights) total += light.energy;
    EXPECT_GT(tree.pmf(vec3(3.0f, 3.0f, 0.0f), spot), lights[spot].energy / total);
}

// Two rooms: a dim lamp here, one 100x brighter 6 m away behind the wall. Selection by power
// gave the far lamp 99% of the samples; the tree gives the near one most of them here.
TEST(LightTree, ANearDimLightTakesMostSamplesFromAFarBrightOne) {
    const LightTree tree({point_bounds(vec3(0.0f, 0.0f, 2.0f), 1.0f),
                          point_bounds(vec3(6.0f, 0.0f, 2.0f), 100.0f)});
    EXPECT_GT(tree.pmf(vec3(0.0f, 0.0f, 1.8f), 0), 0.5f);
}

// A scene with every kind of emitter for LightSampler.
Scene many_light_scene() {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    Material glow = test::lambert(0.0f);
    glow.emission_color = vec3(1.0f, 0.5f, 0.2f);
    glow.emission_strength = 3.0f;
    const uint32_t glow_id = scene.add_material(glow);
    scene.add_instance(scene.add_mesh(test::plane(20.0f)), mat4(1.0f));
    Mesh emitter = test::quad(vec3(4.0f, -1.0f, 3.0f), vec3(1.0f, 0.0f, 0.0f),
                              vec3(0.0f, 1.0f, 0.0f));
    emitter.material_indices.assign(emitter.triangles.size(), glow_id);
    scene.add_instance(scene.add_mesh(emitter), mat4(1.0f));
    for (int i = 0; i < 6; ++i)
        scene.add_light(test::point_light(vec3(-6.0f + 2.5f * float(i), 2.0f, 1.0f + float(i)),
                                          10.0f * float(i + 1)));
    Light area;
    area.type = LightType::Area;
    area.power = 200.0f;
    area.world_from_light = glm::translate(mat4(1.0f), vec3(0.0f, -4.0f, 4.0f));
    scene.add_light(area);
    Light sun;
    sun.type = LightType::Sun;
    sun.strength = 2.0f;
    sun.angle = 0.1f;
    scene.add_light(sun);
    World world;
    world.color = vec3(0.2f);
    scene.set_world(world);
    scene.commit();
    return scene;
}

TEST(LightSampler, SelectionPdfsOfLocalAndDistantEmittersSumToOne) {
    const Scene scene = many_light_scene();
    const LightSampler lights(scene, WorldSampling::Cosine);
    ASSERT_EQ(lights.emitter_count(), 6u + 1u + 1u + 2u + 1u);  // lamps, area, sun, quad, world
    for (const vec3& p : {vec3(0.0f, 0.0f, 0.01f), vec3(5.0f, 5.0f, 0.01f), vec3(-9.0f, 0.0f, 2.0f)}) {
        double sum = 0.0;
        for (uint32_t e = 0; e < lights.emitter_count(); ++e) sum += lights.selection_pdf(e, p);
        EXPECT_NEAR(sum, 1.0, kPmfSumTolerance);
    }
}

// Irradiance on an upward unit normal at p from point lights alone (no occluder between): the
// NEE estimate over many lights converges to sum I cos / d^2.
TEST(LightSampler, NextEventEstimationOverManyPointLightsIsUnbiased) {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    scene.add_instance(scene.add_mesh(test::plane(0.1f)), glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, -5.0f)));
    double expected = 0.0;
    const vec3 p(0.3f, -0.2f, 0.0f), n(0.0f, 0.0f, 1.0f);
    for (int i = 0; i < 12; ++i) {
        const vec3 position(-6.0f + float(i), 0.5f * float(i % 3), 1.0f + 0.3f * float(i));
        const float power = 5.0f + 20.0f * float(i % 4);
        scene.add_light(test::point_light(position, power));
        const vec3 d = position - p;
        expected += point_intensity_from_power(power) * glm::dot(glm::normalize(d), n) / glm::dot(d, d);
    }
    World dark;
    dark.strength = 0.0f;
    scene.set_world(dark);
    scene.commit();
    const LightSampler lights(scene, WorldSampling::Cosine);
    Pcg32 rng(3);
    double sum = 0.0, sum2 = 0.0;
    for (int s = 0; s < kSamples; ++s) {
        LightSample ls;
        double value = 0.0;
        if (lights.sample(p, n, rng.next_float(), rng.next_vec2(), &ls))
            value = ls.radiance.x * std::max(0.0f, glm::dot(ls.wi, n)) / ls.pdf;
        sum += value;
        sum2 += value * value;
    }
    const double mean = sum / kSamples;
    const double error = std::sqrt(std::max(0.0, sum2 / kSamples - mean * mean) / kSamples);
    EXPECT_NEAR(mean, expected, 5.0 * error + 1e-6 * expected);
}

}  // namespace
}  // namespace shgi
