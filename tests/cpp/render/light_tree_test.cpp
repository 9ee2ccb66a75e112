// Many-light selection (render/light_tree.h, render/light_sampler.h) against its own pdf: the
// tree's choices pass a χ² test against pmf(), its pmfs sum to one, emitters that cannot light a
// point (behind a one-sided area light, outside a spot's cone) get none of its samples, split
// sampling (one emitter per node of a cut) passes the same test against its own pmf and gives
// the lamp of the two rooms' seen room a shadow ray at every point, the
// light sampler's selection pdfs sum to one over local and distant emitters, and next-event
// estimation over many lights converges to their analytic irradiance.
#include "render/light_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "render/light_sampler.h"
#include "render/render_test_scenes.h"
#include "support/chi2.h"
#include "util/error.h"
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
        EXPECT_NEAR(sum, 1.0, kPmfSumTolerance)
            << "at (" << p.x << ", " << p.y << ", " << p.z << ")";
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

// A node's importance (the header's formula, computed without trigonometry) against the same
// formula written with the angles themselves, for a box with an orientation cone seen from
// points all around it: inside the cone, beyond it by less than theta_e, and past theta_e.
TEST(LightTree, ImportanceEqualsTheAngleFormula) {
    LightBounds b;
    b.bounds.extend(vec3(-0.3f, -0.2f, 0.9f));
    b.bounds.extend(vec3(0.3f, 0.2f, 1.1f));
    b.axis = glm::normalize(vec3(0.2f, 0.0f, -1.0f));
    b.theta_o = 0.4f;
    b.theta_e = kPi / 2.0f;
    b.energy = 7.0f;
    const LightTree tree({b});
    const vec3 centre = 0.5f * (b.bounds.lower + b.bounds.upper);
    const float radius = 0.5f * glm::length(b.bounds.upper - b.bounds.lower);
    Pcg32 rng(11);
    int lit = 0, unlit = 0;
    for (int i = 0; i < 2000; ++i) {
        const vec3 p = centre + vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f,
                                     rng.next_float() - 0.5f) * 8.0f;
        const vec3 to_p = p - centre;
        const float d = glm::length(to_p);
        if (d <= radius * 1.001f) continue;  // inside the box: energy / r^2, no angles
        const float theta_u = std::asin(radius / d);
        const float theta = std::acos(std::clamp(glm::dot(b.axis, to_p / d), -1.0f, 1.0f));
        const float theta_prime = std::max(0.0f, theta - b.theta_o - theta_u);
        const float expected = theta_prime > b.theta_e ? 0.0f
                                                       : b.energy * std::cos(theta_prime) / (d * d);
        const float got = tree.importance(p);
        if (std::fabs(theta_prime - b.theta_e) < 1e-3f) continue;  // the cut-off's own rounding
        EXPECT_NEAR(got, expected, 1e-4f * b.energy / (d * d) + 1e-5f * expected) << "at " << i;
        (expected > 0.0f ? lit : unlit) += 1;
    }
    EXPECT_GT(lit, 100);
    EXPECT_GT(unlit, 100);
}

// Two rooms: a dim lamp here, one 100x brighter 6 m away behind the wall. Selection by power
// gave the far lamp 99% of the samples; the tree gives the near one most of them here.
TEST(LightTree, ANearDimLightTakesMostSamplesFromAFarBrightOne) {
    const LightTree tree({point_bounds(vec3(0.0f, 0.0f, 2.0f), 1.0f),
                          point_bounds(vec3(6.0f, 0.0f, 2.0f), 100.0f)});
    EXPECT_GT(tree.pmf(vec3(0.0f, 0.0f, 1.8f), 0), 0.5f);
}

// Splitting: one emitter from each node of the cut; each choice has the probability pmf(p, e, K)
// claims, the pmfs sum to the cut's size, and the cut has more than one node near the lights.
TEST(LightTree, SplitChoicesPassChiSquareAgainstTheirPmf) {
    const std::vector<LightBounds> lights = mixed_lights();
    const LightTree tree(lights);
    constexpr int kSplits = 4;
    Pcg32 rng(12);
    for (const vec3& p : {vec3(0.0f), vec3(-8.0f, 4.0f, 1.0f), vec3(3.0f, 3.0f, 0.0f)}) {
        uint32_t nodes[kMaxLightSplits];
        const int cut = tree.cut(p, kSplits, nodes);
        EXPECT_GT(cut, 1) << "at (" << p.x << ", " << p.y << ", " << p.z << ")";
        EXPECT_LE(cut, kSplits);
        double sum = 0.0;
        std::vector<double> expected(lights.size());
        for (uint32_t i = 0; i < lights.size(); ++i) {
            expected[i] = double(tree.pmf(p, i, kSplits)) * kSamples;
            sum += tree.pmf(p, i, kSplits);
        }
        EXPECT_NEAR(sum, double(cut), kPmfSumTolerance * cut);
        std::vector<double> observed(lights.size(), 0.0);
        for (int s = 0; s < kSamples; ++s) {
            uint32_t chosen[kMaxLightSplits];
            float pmf[kMaxLightSplits];
            const int count = tree.sample_split(p, rng.next_float(), kSplits, chosen, pmf);
            ASSERT_EQ(count, cut);
            for (int k = 0; k < count; ++k) {
                EXPECT_FLOAT_EQ(pmf[k], tree.pmf(p, chosen[k], kSplits));
                observed[chosen[k]] += 1.0;
            }
        }
        // Independent multinomials, one per cut node: their bins pooled are the same test.
        const std::string failure = chi2_test(observed, expected);
        EXPECT_TRUE(failure.empty()) << failure;
    }
}

// The two rooms of examples/scenes.two_rooms: a 20 W lamp at x = 1.5 in the room the camera sees
// (x in [0.05, 3]), a 2000 W lamp at x = -1.5 beyond the 0.1 m wall. Without splitting the tree
// sends the seen lamp a few percent of the shadow rays from the seen room (measured over a
// 0.25 m grid of it: 6.1% on average, under 5% at 1004 of 1716 points); with splitting every
// next-event estimate there samples it.
TEST(LightTree, SplittingGivesTheSeenRoomsLampAShadowRayEverywhereInIt) {
    const LightTree tree({point_bounds(vec3(-1.5f, 1.5f, 2.0f), 2000.0f / (4.0f * kPi)),
                          point_bounds(vec3(1.5f, 1.5f, 2.0f), 20.0f / (4.0f * kPi))});
    constexpr uint32_t kSeenLamp = 1;
    double share = 0.0;
    int points = 0, starved = 0;  // points where the seen lamp gets under 5% of the rays
    for (float x = 0.05f; x <= 3.0f; x += 0.25f)
        for (float y = 0.0f; y <= 3.0f; y += 0.25f)
            for (float z = 0.0f; z <= 2.5f; z += 0.25f) {
                const vec3 p(x, y, z);
                const float pmf = tree.pmf(p, kSeenLamp);
                share += pmf;
                starved += pmf < 0.05f;
                ++points;
                EXPECT_EQ(tree.pmf(p, kSeenLamp, 4), 1.0f)
                    << "at (" << x << ", " << y << ", " << z << ")";
            }
    share /= points;
    EXPECT_LT(share, 0.1);
    EXPECT_GT(starved, points / 2);
    std::printf("seen lamp's share of shadow rays in the seen room without splitting: %.3f mean, "
                "under 0.05 at %d of %d points; with splitting 1 at every point\n", share,
                starved, points);
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
    for (const vec3& p :
         {vec3(0.0f, 0.0f, 0.01f), vec3(5.0f, 5.0f, 0.01f), vec3(-9.0f, 0.0f, 2.0f)}) {
        double sum = 0.0;
        for (uint32_t e = 0; e < lights.emitter_count(); ++e) sum += lights.selection_pdf(e, p);
        EXPECT_NEAR(sum, 1.0, kPmfSumTolerance);
    }
}

// sample_lights = false (a field carrying the lights' and emissive triangles' direct light,
// INSTANT_GI's filter_direct): next-event estimation chooses the world alone, while rays still
// meet the area light, the sun's cone and the emissive quad, with their radiance and a light pdf
// of 0 (so a BSDF-sampled ray counts them whole); sample_light and sample_emissive_triangle
// still sample any light or triangle by itself.
TEST(LightSampler, WithoutLightsSamplesOnlyTheWorldButRaysStillSeeLightsAndTriangles) {
    const Scene scene = many_light_scene();
    const LightSampler all(scene, WorldSampling::Cosine);
    const LightSampler without(scene, WorldSampling::Cosine, true, 1, false);
    ASSERT_EQ(without.emitter_count(), 1u);  // the world
    const vec3 p(0.0f, -4.0f, 0.01f), n(0.0f, 0.0f, 1.0f);
    double sum = 0.0;
    for (uint32_t e = 0; e < without.emitter_count(); ++e) sum += without.selection_pdf(e, p);
    EXPECT_NEAR(sum, 1.0, kPmfSumTolerance);
    for (uint32_t i = 0; i < scene.lights().size(); ++i) EXPECT_TRUE(without.light_emits(i));
    // Straight up into the area light 4 m above.
    EmissionHit seen_all, seen_without;
    ASSERT_TRUE(all.intersect_lights(p, n, kInfinity, false, &seen_all));
    ASSERT_TRUE(without.intersect_lights(p, n, kInfinity, false, &seen_without));
    EXPECT_EQ(seen_without.radiance, seen_all.radiance);
    EXPECT_GT(seen_all.light_pdf, 0.0f);
    EXPECT_EQ(seen_without.light_pdf, 0.0f);
    // Escaping straight up from elsewhere: the world and the sun's cone, the sun at pdf 0.
    const vec3 q(9.0f, 9.0f, 0.01f);
    const std::vector<EmissionHit> escaped_all = all.escaped(q, n, n, false);
    const std::vector<EmissionHit> escaped_without = without.escaped(q, n, n, false);
    ASSERT_EQ(escaped_all.size(), 2u);
    ASSERT_EQ(escaped_without.size(), 2u);
    EXPECT_EQ(escaped_without[1].radiance, escaped_all[1].radiance);
    EXPECT_GT(escaped_all[1].light_pdf, 0.0f);
    EXPECT_EQ(escaped_without[1].light_pdf, 0.0f);
    EXPECT_GT(escaped_without[0].light_pdf, 0.0f);  // the world is still sampled
    // A light sampled by itself: the area light seen from p, with its solid-angle pdf.
    LightSample sample;
    ASSERT_TRUE(without.sample_light(6, p, vec2(0.5f), &sample));
    EXPECT_NEAR(sample.wi.z, 1.0f, 1e-4f);
    EXPECT_GT(sample.pdf, 0.0f);
    EXPECT_FALSE(sample.delta);
    // Straight up into the emissive quad (x 4..5, y -1..0, 3 m up): its radiance, pdf 0.
    Ray up;
    up.origin = vec3(4.5f, -0.5f, 0.01f);
    up.direction = n;
    const Hit hit = scene.intersect(up);
    ASSERT_TRUE(hit.valid());
    const EmissionHit quad_all = all.triangle_emission(up.origin, hit, n);
    const EmissionHit quad_without = without.triangle_emission(up.origin, hit, n);
    EXPECT_EQ(quad_all.radiance, vec3(3.0f, 1.5f, 0.6f));
    EXPECT_EQ(quad_without.radiance, quad_all.radiance);
    EXPECT_GT(quad_all.light_pdf, 0.0f);
    EXPECT_EQ(quad_without.light_pdf, 0.0f);
    // A triangle sampled by itself: straight up, its solid-angle pdf d^2 / (cos area).
    ASSERT_EQ(scene.emissive_triangles().size(), 2u);
    LightSample on_quad;
    ASSERT_TRUE(without.sample_emissive_triangle(0, up.origin, vec2(0.3f, 0.4f), &on_quad));
    EXPECT_EQ(on_quad.radiance, quad_all.radiance);
    const float cos_light = std::fabs(on_quad.wi.z);
    EXPECT_NEAR(on_quad.pdf,
                on_quad.distance * on_quad.distance /
                    (cos_light * scene.emissive_triangles()[0].area),
                1e-4f * on_quad.pdf);
    EXPECT_FALSE(on_quad.delta);
}

// LightSampler::may_emit, the test a path makes before looking for emission where its ray
// ends (for_each_emission): against the scene itself, a ray it answers false for crosses no
// emitting disk or area light before its hit (none the camera sees, for a camera ray) and hits
// no emissive triangle; rays that do meet the quad, the area light or a lamp's disk are all
// answered true. Lamps hidden from the camera (the default) leave camera rays nothing to cross.
TEST(LightSampler, RaysSkipEmissionOnlyWhereTheyCanMeetNone) {
    // A lamp with a disk (light 2), which rays can cross; `shown`: the area light (6) seen by
    // the camera.
    const auto make = [](bool shown) {
        Scene scene = many_light_scene();
        Light disk = scene.lights()[2];
        disk.radius = 0.5f;
        scene.set_light(2, disk);
        Light area = scene.lights()[6];
        area.visible_camera = shown;
        scene.set_light(6, area);
        scene.commit();
        return scene;
    };
    const Scene scene = make(false), shown_scene = make(true);
    ASSERT_EQ(scene.lights()[6].type, LightType::Area);
    const LightSampler hidden(scene, WorldSampling::Cosine);
    EXPECT_TRUE(hidden.has_crossable_lights(false));
    EXPECT_FALSE(hidden.has_crossable_lights(true));
    const LightSampler shown(shown_scene, WorldSampling::Cosine);
    EXPECT_TRUE(shown.has_crossable_lights(true));
    // The reference: what the ray meets, from the scene's own lists.
    const auto meets = [&](const Scene& s, const Ray& ray, const Hit& hit, bool camera) {
        for (const EmissiveTriangle& tri : s.emissive_triangles())
            if (hit.valid() && tri.instance_id == hit.instance_id &&
                tri.triangle_id == hit.triangle_id && luminance(tri.radiance) > 0.0f)
                return true;
        for (const Light& light : s.lights()) {
            if (camera && !light.visible_camera) continue;
            if (light.type == LightType::Area) {
                float t, cos_axis;
                if (area_light_crossing(light, ray.origin, ray.direction, &t, &cos_axis) &&
                    cos_axis < 0.0f && t < hit.t)
                    return true;
            } else if (light.type == LightType::Point && light.radius > 0.0f) {
                // The disk facing the ray's origin: within the radius of the line's closest
                // approach to the centre, in front of the hit (a conservative test).
                const vec3 to_center = light.position() - ray.origin;
                const float along = glm::dot(to_center, ray.direction);
                const vec3 off = to_center - along * ray.direction;
                if (along > 0.0f && glm::dot(off, off) <= light.radius * light.radius &&
                    along - light.radius < hit.t)
                    return true;
            }
        }
        return false;
    };
    Pcg32 rng(11);
    int skipped = 0, met[2] = {0, 0};
    for (int i = 0; i < 40000; ++i) {
        Ray ray;
        const bool down = i % 2 == 0;  // from above the lights, or from the floor
        ray.origin = vec3(16.0f * rng.next_float() - 8.0f, 16.0f * rng.next_float() - 8.0f,
                          down ? 7.0f : 0.01f);
        const vec3 d = sample_uniform_sphere(rng.next_vec2());
        ray.direction = vec3(d.x, d.y, down ? -std::fabs(d.z) : std::fabs(d.z));
        for (const LightSampler* lights : {&hidden, &shown}) {
            const Scene& s = lights == &hidden ? scene : shown_scene;
            const Hit hit = s.intersect(ray);
            for (const bool camera : {false, true}) {
                int added = 0;
                lights->for_each_emission(ray.origin, vec3(0.0f, 0.0f, 1.0f), ray.direction, hit,
                                          camera, [&](const EmissionHit&, bool) { ++added; });
                if (!lights->may_emit(hit, camera)) {
                    ++skipped;
                    EXPECT_EQ(added, 0);
                    EXPECT_FALSE(meets(s, ray, hit, camera)) << "ray " << i;
                } else if (hit.valid() && meets(s, ray, hit, camera)) {
                    ++met[camera ? 1 : 0];
                }
            }
        }
    }
    std::printf("rays skipped %d; rays meeting an emitter %d, camera rays %d\n", skipped, met[0],
                met[1]);
    // Every branch was taken: skipped rays, and rays that meet emitters, camera rays included.
    EXPECT_GT(skipped, 1000);
    EXPECT_GT(met[0], 100);
    EXPECT_GT(met[1], 10);
}

// Twelve point lights of four powers above a small plane 5 m below, the world dark, committed;
// *irradiance: the analytic irradiance sum I cos / d^2 they give at p on unit normal n.
Scene twelve_point_lights(const vec3& p, const vec3& n, double* irradiance) {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    scene.add_instance(scene.add_mesh(test::plane(0.1f)),
                       glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, -5.0f)));
    *irradiance = 0.0;
    for (int i = 0; i < 12; ++i) {
        const vec3 position(-6.0f + float(i), 0.5f * float(i % 3), 1.0f + 0.3f * float(i));
        const float power = 5.0f + 20.0f * float(i % 4);
        scene.add_light(test::point_light(position, power));
        const vec3 d = position - p;
        *irradiance += point_intensity_from_power(power) * glm::dot(glm::normalize(d), n) /
                       glm::dot(d, d);
    }
    World dark;
    dark.strength = 0.0f;
    scene.set_world(dark);
    scene.commit();
    return scene;
}

// Irradiance on an upward unit normal at p from point lights alone (no occluder between): the
// NEE estimate over many lights converges to sum I cos / d^2.
TEST(LightSampler, NextEventEstimationOverManyPointLightsIsUnbiased) {
    const vec3 p(0.3f, -0.2f, 0.0f), n(0.0f, 0.0f, 1.0f);
    double expected = 0.0;
    const Scene scene = twelve_point_lights(p, n, &expected);
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

// The same with the tree's splitting: the estimate (the sum over one next-event estimate's
// samples) still converges to the analytic irradiance, and selection pdfs of the local emitters
// sum to the cut's size.
TEST(LightSampler, NextEventEstimationWithSplitsIsUnbiased) {
    const vec3 p(0.3f, -0.2f, 0.0f), n(0.0f, 0.0f, 1.0f);
    double expected = 0.0;
    const Scene scene = twelve_point_lights(p, n, &expected);
    constexpr int kSplits = 4;
    const LightSampler lights(scene, WorldSampling::Cosine, true, kSplits);
    double pmf_sum = 0.0;
    for (uint32_t e = 0; e < lights.emitter_count(); ++e) pmf_sum += lights.selection_pdf(e, p);
    EXPECT_GT(pmf_sum, 1.5);  // split here
    EXPECT_LE(pmf_sum, kSplits + kPmfSumTolerance);
    EXPECT_NEAR(pmf_sum, std::round(pmf_sum), kPmfSumTolerance * kSplits);
    Pcg32 rng(3);
    double sum = 0.0, sum2 = 0.0;
    for (int s = 0; s < kSamples; ++s) {
        LightSample ls[kMaxLightSplits];
        double value = 0.0;
        const int count = lights.sample_split(p, n, rng.next_float(), rng.next_vec2(), ls);
        for (int k = 0; k < count; ++k)
            value += ls[k].radiance.x * std::max(0.0f, glm::dot(ls[k].wi, n)) / ls[k].pdf;
        sum += value;
        sum2 += value * value;
    }
    const double mean = sum / kSamples;
    const double error = std::sqrt(std::max(0.0, sum2 / kSamples - mean * mean) / kSamples);
    EXPECT_NEAR(mean, expected, 5.0 * error + 1e-6 * expected);
    LightSample one;
    EXPECT_THROW(lights.sample(p, n, 0.5f, vec2(0.5f), &one), Internal);
    EXPECT_THROW(LightSampler(scene, WorldSampling::Cosine, true, kMaxLightSplits + 1),
                 InvalidArgument);
}

// importance4 runs importance() on four SSE2 lanes: the same bits at every point, inside a
// node's box, behind a one-sided emitter, outside a spot's cone, far away and at NaN.
TEST(LightTree, Importance4IsImportanceBitForBit) {
    LightBounds spot = point_bounds(vec3(1.0f, 2.0f, 3.0f), 5.0f);
    spot.axis = glm::normalize(vec3(0.2f, -0.3f, -1.0f));
    spot.theta_o = 0.4f;
    spot.theta_e = 0.3f;
    LightBounds panel;
    panel.bounds.extend(vec3(-0.5f, -0.5f, 2.0f));
    panel.bounds.extend(vec3(0.5f, 0.5f, 2.0f));
    panel.energy = 40.0f;
    panel.axis = vec3(0.0f, 0.0f, -1.0f);
    panel.theta_o = 0.0f;
    panel.theta_e = kPi / 2.0f;
    const std::vector<LightTree> trees = {
        LightTree({panel}), LightTree({spot}),
        LightTree({panel, spot, point_bounds(vec3(-3.0f, 0.0f, 1.0f), 2.0f)})};
    Pcg32 rng(7, 1);
    int compared = 0;
    for (const LightTree& tree : trees) {
        for (int n = 0; n < 20000; ++n) {
            float x[4], y[4], z[4], out[4];
            for (int k = 0; k < 4; ++k) {
                const float scale = (n % 3 == 0) ? 0.6f : 6.0f;  // inside the boxes, or around
                x[k] = (rng.next_float() * 2.0f - 1.0f) * scale;
                y[k] = (rng.next_float() * 2.0f - 1.0f) * scale;
                z[k] = 2.0f + (rng.next_float() * 2.0f - 1.0f) * scale;
            }
            if (n == 0) x[1] = std::nanf("");
            if (n == 1) z[2] = 2.0f;  // on the panel's plane
            tree.importance4(x, y, z, out);
            for (int k = 0; k < 4; ++k) {
                const float expected = tree.importance(vec3(x[k], y[k], z[k]));
                ASSERT_EQ(std::memcmp(&out[k], &expected, sizeof(float)), 0)
                    << out[k] << " vs " << expected << " at (" << x[k] << ", " << y[k] << ", "
                    << z[k] << ")";
                ++compared;
            }
        }
    }
    EXPECT_EQ(compared, 3 * 20000 * 4);
}

// A room lit by one rectangle: sample_split_lanes gives sample_split's samples, bit for bit, at
// points in front of the light, behind it, beside it and on its plane (a count that leaves a
// short last group); a lane whose u_select is 1 is left to sample_split; a sampler with another
// emitter (or a disk) does not take that path.
TEST(LightSampler, SampleSplitLanesIsSampleSplitBitForBit) {
    for (const AreaShape shape : {AreaShape::Square, AreaShape::Rectangle}) {
        Scene scene;
        scene.add_material(test::lambert(0.5f));
        scene.add_instance(scene.add_mesh(test::plane(20.0f)), mat4(1.0f));
        Light area;
        area.type = LightType::Area;
        area.shape = shape;
        area.size_x = 0.7f;
        area.size_y = 0.3f;
        area.power = 150.0f;
        area.world_from_light =
            glm::rotate(glm::translate(mat4(1.0f), vec3(0.3f, -0.2f, 2.0f)), 0.5f,
                        glm::normalize(vec3(1.0f, 0.4f, 0.2f)));
        scene.add_light(area);
        World world;
        world.strength = 0.0f;
        scene.set_world(world);
        scene.commit();
        for (const int splits : {1, 4}) {
            const LightSampler lights(scene, WorldSampling::Cosine, true, splits);
            ASSERT_TRUE(lights.samples_one_rectangle());
            Pcg32 rng(11, uint64_t(splits));
            constexpr size_t kCount = 80003;
            std::vector<float> x(kCount), y(kCount), z(kCount), u_select(kCount), ux(kCount),
                uy(kCount);
            for (size_t i = 0; i < kCount; ++i) {
                x[i] = rng.next_float() * 6.0f - 3.0f;
                y[i] = rng.next_float() * 6.0f - 3.0f;
                z[i] = rng.next_float() * 4.0f;
                u_select[i] = rng.next_float();
                ux[i] = rng.next_float();
                uy[i] = rng.next_float();
            }
            x[3] = area.position().x;  // on the light
            y[3] = area.position().y;
            z[3] = area.position().z;
            u_select[5] = 1.0f;  // not the tree's
            std::vector<LightSample> out(kCount);
            std::vector<int8_t> written(kCount);
            lights.sample_split_lanes(kCount, x.data(), y.data(), z.data(), u_select.data(),
                                      ux.data(), uy.data(), out.data(), written.data());
            EXPECT_EQ(written[5], -1);
            size_t sampled = 0;
            for (size_t i = 0; i < kCount; ++i) {
                if (i == 5) continue;
                LightSample expected[kMaxLightSplits];
                const vec3 p(x[i], y[i], z[i]);
                const int count = lights.sample_split(p, vec3(0.0f, 0.0f, 1.0f), u_select[i],
                                                      vec2(ux[i], uy[i]), expected);
                ASSERT_EQ(int(written[i]), count) << "at point " << i;
                if (count == 0) continue;
                ++sampled;
                EXPECT_EQ(std::memcmp(&out[i].wi, &expected[0].wi, sizeof(vec3)), 0);
                EXPECT_EQ(std::memcmp(&out[i].distance, &expected[0].distance, 4), 0);
                EXPECT_EQ(std::memcmp(&out[i].radiance, &expected[0].radiance, sizeof(vec3)), 0);
                EXPECT_EQ(std::memcmp(&out[i].pdf, &expected[0].pdf, 4), 0);
                EXPECT_EQ(out[i].delta, expected[0].delta);
            }
            EXPECT_GT(sampled, kCount / 4);  // most points lie in front of the light
            EXPECT_LT(sampled, kCount - 1);  // and some behind it
        }
    }
    const Scene many = many_light_scene();
    EXPECT_FALSE(LightSampler(many, WorldSampling::Cosine).samples_one_rectangle());
    Scene disk;
    disk.add_material(test::lambert(0.5f));
    disk.add_instance(disk.add_mesh(test::plane(20.0f)), mat4(1.0f));
    Light round;
    round.type = LightType::Area;
    round.shape = AreaShape::Disk;
    round.power = 100.0f;
    round.world_from_light = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, 2.0f));
    disk.add_light(round);
    World black;
    black.strength = 0.0f;
    disk.set_world(black);
    disk.commit();
    const LightSampler disk_lights(disk, WorldSampling::Cosine);
    EXPECT_FALSE(disk_lights.samples_one_rectangle());
    const float half = 0.5f;
    LightSample out;
    int8_t written;
    EXPECT_THROW(disk_lights.sample_split_lanes(1, &half, &half, &half, &half, &half, &half,
                                                &out, &written),
                 Internal);
}

}  // namespace
}  // namespace shgi
