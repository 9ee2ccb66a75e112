// Light portals (Light.portal, Cycles' area light Portal) against closed forms: a closed room lit
// only by a uniform sky through a square opening in its ceiling. Next-event estimation of the
// floor's irradiance and the photons' flux through the opening must be unbiased with and without
// the portal, and much less noisy with it.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "photon/photon_emitter.h"
#include "render/light_sampler.h"
#include "render/render_test_scenes.h"
#include "support/noise_stats.h"
#include "util/error.h"
#include "util/rng.h"

namespace shgi {
namespace {

constexpr float kRoomHalf = 1.0f;    // room [-1, 1]^2 x [0, 2]
constexpr float kRoomHeight = 2.0f;
constexpr float kHoleHalf = 0.25f;   // opening [-0.25, 0.25]^2 in the ceiling
constexpr float kSky = 1.0f;         // world radiance

// The room (black walls facing inwards: the front of test::quad(corner, u, v) is u x v) under a
// uniform sky; with `portal`, a portal fills the opening, facing down into the room.
Scene room_with_skylight(bool portal) {
    Scene scene;
    scene.add_material(test::lambert(0.0f));
    const float a = kRoomHalf, h = kRoomHeight, b = kHoleHalf;
    const Mesh parts[] = {
        test::quad({-a, -a, 0}, {2 * a, 0, 0}, {0, 2 * a, 0}),   // floor
        test::quad({-a, -a, 0}, {0, 2 * a, 0}, {0, 0, h}),       // x = -a
        test::quad({a, -a, 0}, {0, 0, h}, {0, 2 * a, 0}),        // x = +a
        test::quad({-a, -a, 0}, {0, 0, h}, {2 * a, 0, 0}),       // y = -a
        test::quad({-a, a, 0}, {2 * a, 0, 0}, {0, 0, h}),        // y = +a
        // Ceiling (facing down) around the opening.
        test::quad({-a, -a, h}, {0, 2 * a, 0}, {a - b, 0, 0}),
        test::quad({b, -a, h}, {0, 2 * a, 0}, {a - b, 0, 0}),
        test::quad({-b, -a, h}, {0, a - b, 0}, {2 * b, 0, 0}),
        test::quad({-b, b, h}, {0, a - b, 0}, {2 * b, 0, 0}),
    };
    for (const Mesh& part : parts) scene.add_instance(scene.add_mesh(part), mat4(1.0f));
    World world;
    world.color = vec3(kSky);
    world.strength = 1.0f;
    scene.set_world(world);
    if (portal) {
        Light light;
        light.name = "skylight";
        light.type = LightType::Area;
        light.portal = true;
        light.size_x = 2.0f * kHoleHalf;
        light.world_from_light = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, h));  // emits down
        scene.add_light(light);
    }
    scene.commit();
    return scene;
}

// Irradiance at p (normal n) from a polygon of uniform radiance L (Lambert's formula).
double polygon_irradiance(const vec3& p, const vec3& n, const std::vector<vec3>& polygon,
                          double radiance) {
    double sum = 0.0;
    for (size_t i = 0; i < polygon.size(); ++i) {
        const glm::dvec3 r0 = glm::normalize(glm::dvec3(polygon[i] - p));
        const glm::dvec3 r1 = glm::normalize(glm::dvec3(polygon[(i + 1) % polygon.size()] - p));
        const glm::dvec3 c = glm::cross(r0, r1);
        sum += std::acos(glm::clamp(glm::dot(r0, r1), -1.0, 1.0)) *
               glm::dot(glm::dvec3(n), c / glm::length(c));
    }
    return 0.5 * radiance * std::fabs(sum);
}

struct Estimate {
    double mean = 0.0, error = 0.0;  // and its standard error
};

// Next-event estimate of the irradiance at p from the world (NEE only, as the preview does).
Estimate floor_irradiance(const Scene& scene, const vec3& p, int samples) {
    const LightSampler lights(scene, WorldSampling::Cosine);
    const vec3 n(0.0f, 0.0f, 1.0f);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < samples; ++i) {
        Pcg32 rng(7, stream_id(0, uint64_t(i)));
        LightSample sample;
        double value = 0.0;
        const float u_select = rng.next_float();
        if (lights.sample(p, n, u_select, rng.next_vec2(), &sample)) {
            Ray shadow;
            shadow.origin = p + 1e-4f * n;
            shadow.direction = sample.wi;
            if (!scene.occluded(shadow))
                value = double(sample.radiance.x) * std::max(0.0f, sample.wi.z) / sample.pdf;
            // The pdf NEE used is the one MIS sees for a BSDF ray in that direction.
            const std::vector<EmissionHit> escaped = lights.escaped(p, n, sample.wi, false);
            EXPECT_EQ(escaped.size(), 1u);
            if (!escaped.empty()) {
                EXPECT_NEAR(escaped[0].light_pdf, sample.pdf, 1e-4f * sample.pdf);
            }
        }
        sum += value;
        sum2 += value * value;
    }
    const double mean = sum / samples;
    return {mean, std::sqrt(std::max(0.0, sum2 / samples - mean * mean) / samples)};
}

TEST(Portal, NextEventEstimationThroughASkylightIsUnbiasedAndLessNoisy) {
    const vec3 p(0.3f, 0.1f, 0.0f);
    const float h = kRoomHeight, b = kHoleHalf;
    const double exact = polygon_irradiance(
        p, vec3(0, 0, 1), {{-b, -b, h}, {b, -b, h}, {b, b, h}, {-b, b, h}}, kSky);
    const Estimate plain = floor_irradiance(room_with_skylight(false), p, 200000);
    const Estimate portal = floor_irradiance(room_with_skylight(true), p, 200000);
    testing::expect_within_noise(plain.mean, plain.error, exact, 0.0, "without portal");
    testing::expect_within_noise(portal.mean, portal.error, exact, 0.0, "with portal");
    EXPECT_LT(portal.error, 0.2 * plain.error);
}

TEST(Portal, WorldPdfIntegratesToOneOverTheSphere) {
    const Scene scene = room_with_skylight(true);
    const LightSampler lights(scene, WorldSampling::Cosine);
    const vec3 p(0.3f, 0.1f, 0.0f), n(0.0f, 0.0f, 1.0f);
    // The world is the only emitter, so the escaped pdf is the world's (selection 1).
    double sum = 0.0;
    const int count = 400000;
    for (int i = 0; i < count; ++i) {
        Pcg32 rng(11, stream_id(0, uint64_t(i)));
        const vec3 wi = sample_uniform_sphere(rng.next_vec2());
        sum += lights.escaped(p, n, wi, false)[0].light_pdf / sample_uniform_sphere_pdf();
    }
    EXPECT_NEAR(sum / count, 1.0, 0.02);
}

// Sum of the photons' power (red) that enter the room through the opening, and its error.
Estimate flux_through_opening(const Scene& scene, uint64_t count) {
    const PhotonEmitter emitter(scene);
    Light opening;  // the opening as an area light, to test crossings with
    opening.type = LightType::Area;
    opening.size_x = 2.0f * kHoleHalf;
    opening.world_from_light = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, kRoomHeight));
    double sum = 0.0, sum2 = 0.0;
    for (uint64_t i = 0; i < count; ++i) {
        Pcg32 rng(5, stream_id(0, i));
        EmittedPhoton photon;
        if (!emitter.emit(i, count, rng, &photon)) continue;
        float t, cos_axis;
        if (!area_light_crossing(opening, photon.ray.origin, photon.ray.direction, &t,
                                 &cos_axis) ||
            !(cos_axis > 0.0f))
            continue;
        sum += photon.power.x;
        sum2 += double(photon.power.x) * photon.power.x;
    }
    return {sum, testing::standard_error_of_sum(sum, sum2, count)};
}

TEST(Portal, WorldPhotonsCarryTheSkyFluxThroughTheOpening) {
    const double area = 4.0 * kHoleHalf * kHoleHalf;
    const double exact = kPiD * kSky * area;  // a uniform sky over the whole upper hemisphere
    const Estimate plain = flux_through_opening(room_with_skylight(false), 200000);
    const Estimate portal = flux_through_opening(room_with_skylight(true), 200000);
    testing::expect_within_noise(plain.mean, plain.error, exact, 0.0, "without portal");
    testing::expect_within_noise(portal.mean, portal.error, exact, 0.0, "with portal");
    EXPECT_LT(portal.error, 0.2 * plain.error);
    // Portals emit nothing: the total flux is the world's alone.
    EXPECT_FLOAT_EQ(PhotonEmitter(room_with_skylight(true)).total_power().x,
                    PhotonEmitter(room_with_skylight(false)).total_power().x);
}

TEST(Portal, SunPhotonsThroughTheOpeningCarryItsIrradianceTimesArea) {
    for (const bool portal : {false, true}) {
        Scene scene = room_with_skylight(portal);
        scene.set_world(test::black_world());
        Light sun;
        sun.type = LightType::Sun;
        sun.strength = 3.0f;
        const float zenith = 0.4f;
        sun.world_from_light = glm::rotate(mat4(1.0f), zenith, vec3(1.0f, 0.0f, 0.0f));
        scene.add_light(sun);
        scene.commit();
        const double exact = sun.strength * 4.0 * kHoleHalf * kHoleHalf * std::cos(zenith);
        const Estimate flux = flux_through_opening(scene, 100000);
        testing::expect_within_noise(flux.mean, flux.error, exact, 1e-4 * exact,
                                     "portal " + std::to_string(portal));
    }
}

TEST(Portal, OnlyAreaLightsCanBePortals) {
    Light light;
    light.type = LightType::Point;
    light.portal = true;
    EXPECT_THROW(validate_light(light), InvalidArgument);
    light.type = LightType::Area;
    EXPECT_NO_THROW(validate_light(light));
}

}  // namespace
}  // namespace shgi
