// PhotonEmitter against closed forms: every emitter type's flux (Cycles' units), and the flux its
// photons carry onto a surface of known solid angle or projected area.
#include "photon/photon_emitter.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include <glm/gtc/matrix_transform.hpp>

#include "render/light_sampler.h"
#include "render/render_test_scenes.h"
#include "support/noise_stats.h"
#include "util/error.h"

namespace shgi {
namespace {

using testing::kSigmas;
using testing::standard_error_of_sum;

// Float accumulation of 10^5 photon powers stays well below this relative error.
constexpr double kRelativeFloor = 1e-4;
constexpr uint64_t kPhotons = 100000;

// Sums of the emitted photons' power (red channel), all of them and those whose ray hits the
// scene, with the standard errors of those sums (the photons are independent; stratified
// selection only lowers the variance, so these errors are upper bounds).
struct Tally {
    double total = 0.0, total_error = 0.0;
    double hit = 0.0, hit_error = 0.0;
    uint64_t emitted = 0;
};

Tally emit_photons(const Scene& scene, uint64_t count,
                   const std::function<void(const EmittedPhoton&)>& visit = {},
                   float light_share_uniform = 0.0f) {
    const PhotonEmitter emitter(scene, light_share_uniform);
    double total = 0.0, total2 = 0.0, hit = 0.0, hit2 = 0.0;
    Tally tally;
    for (uint64_t i = 0; i < count; ++i) {
        Pcg32 rng(3, stream_id(0, i));
        EmittedPhoton photon;
        if (!emitter.emit(i, count, rng, &photon)) continue;
        ++tally.emitted;
        if (visit) visit(photon);
        const double power = photon.power.x;
        total += power;
        total2 += power * power;
        if (scene.intersect(photon.ray).valid()) {
            hit += power;
            hit2 += power * power;
        }
    }
    tally.total = total;
    tally.total_error = standard_error_of_sum(total, total2, count);
    tally.hit = hit;
    tally.hit_error = standard_error_of_sum(hit, hit2, count);
    return tally;
}

// A photon power sum within the noise of its photons plus float accumulation (kRelativeFloor).
void expect_within_noise(double value, double error, double expected, const char* what) {
    testing::expect_within_noise(value, error, expected, kRelativeFloor * std::fabs(expected),
                                 what);
}

// A black square of half-width `half` at z = 0 facing +Z: the surface photons are counted on.
Scene floor_scene(float half) {
    Scene scene;
    scene.add_material(test::lambert(0.0f));
    scene.add_instance(scene.add_mesh(test::plane(half)), mat4(1.0f));
    scene.set_world(test::black_world());
    return scene;
}

// A white-emitting square of half-width 1 at z = 0 (two triangles, area 4) of emission
// `strength`, under a black world: 2 pi strength 4 W.
Scene emissive_square_scene(float strength) {
    Scene scene;
    Material emissive = test::lambert(0.5f);
    emissive.emission_color = vec3(1.0f);
    emissive.emission_strength = strength;
    scene.add_material(emissive);
    scene.add_instance(scene.add_mesh(test::plane(1.0f)), mat4(1.0f));
    scene.set_world(test::black_world());
    return scene;
}

Light light_at(LightType type, const vec3& position) {
    Light light;
    light.type = type;
    light.world_from_light = glm::translate(mat4(1.0f), position);  // emits along -Z: down
    return light;
}

// Point light at height h over the centre of a square of half-width a: the square subtends
// 4 atan(a^2 / (h sqrt(2 a^2 + h^2))) = 2 pi / 3 for a = h, so it receives P / 6.
TEST(PhotonEmitter, PointLightFluxAndSolidAngle) {
    Scene scene = floor_scene(1.0f);
    Light light = light_at(LightType::Point, vec3(0.0f, 0.0f, 1.0f));
    light.power = 60.0f;
    light.color = vec3(0.5f, 1.0f, 2.0f);
    scene.add_light(light);
    scene.commit();
    const PhotonEmitter emitter(scene);
    EXPECT_FLOAT_EQ(emitter.total_power().x, 30.0f);
    EXPECT_FLOAT_EQ(emitter.total_power().z, 120.0f);
    const Tally tally = emit_photons(scene, kPhotons, [&](const EmittedPhoton& photon) {
        EXPECT_EQ(photon.ray.origin, light.position());
        EXPECT_NEAR(glm::length(photon.ray.direction), 1.0f, 1e-5f);
    });
    EXPECT_EQ(tally.emitted, kPhotons);
    expect_within_noise(tally.total, tally.total_error, 30.0, "point total");
    expect_within_noise(tally.hit, tally.hit_error, 30.0 / 6.0, "point onto the square");
}

// Spot: colour x P/(4 pi) x the integral of Cycles' attenuation over the cone (with Cycles 3.x's
// cone cosine and without it, as Cycles 4), here checked against a midpoint quadrature in
// cos(angle); a large floor below catches every photon.
TEST(PhotonEmitter, SpotLightFluxIsTheAttenuationIntegral) {
    for (bool cone_cosine : {true, false}) {
        SCOPED_TRACE(cone_cosine ? "cone cosine" : "smoothstep only");
        Scene scene = floor_scene(100.0f);
        Light light = light_at(LightType::Spot, vec3(0.0f, 0.0f, 1.0f));
        light.power = 40.0f;
        light.spot_size = 1.2f;
        light.spot_blend = 0.4f;
        light.spot_cone_cosine = cone_cosine;
        scene.add_light(light);
        scene.commit();
        const int steps = 100000;
        const double cos_half = std::cos(0.5 * light.spot_size);
        double integral = 0.0;
        for (int i = 0; i < steps; ++i) {
            const double c = cos_half + (1.0 - cos_half) * (i + 0.5) / steps;
            integral += spot_attenuation(light, float(c)) * (1.0 - cos_half) / steps;
        }
        const double expected = light.power / (4.0 * kPiD) * 2.0 * kPiD * integral;
        EXPECT_NEAR(spot_light_power(light).x, expected, 1e-4 * expected);
        const Tally tally = emit_photons(scene, kPhotons, [&](const EmittedPhoton& photon) {
            EXPECT_GE(-photon.ray.direction.z, float(cos_half) - 1e-5f);  // inside the cone
        });
        expect_within_noise(tally.total, tally.total_error, expected, "spot total");
        expect_within_noise(tally.hit, tally.hit_error, expected, "spot onto the floor");
    }
}

// Sun of strength S at 60 degrees from the zenith: a square of area A receives S A cos(60).
// With an angular diameter the mean cosine over the cone scales it by (1 + cos(angle/2)) / 2.
TEST(PhotonEmitter, SunLightIrradianceOnATiltedSquare) {
    for (const float angle : {0.0f, 0.6f}) {
        Scene scene = floor_scene(1.0f);
        Light light;
        light.type = LightType::Sun;
        light.strength = 3.0f;
        light.angle = angle;
        const float zenith = kPi / 3.0f;
        light.world_from_light = glm::rotate(mat4(1.0f), zenith, vec3(1.0f, 0.0f, 0.0f));
        scene.add_light(light);
        scene.commit();
        const float radius = std::sqrt(2.0f);  // bounding sphere of the 2 x 2 square
        const double disk_area = kPiD * radius * radius;
        EXPECT_NEAR(PhotonEmitter(scene).total_power().x, light.strength * disk_area, 1e-5);
        const Tally tally = emit_photons(scene, kPhotons, [&](const EmittedPhoton& photon) {
            // Each photon starts outside the bounding sphere, moving towards it.
            EXPECT_GT(glm::length(photon.ray.origin), radius);
            EXPECT_LT(glm::dot(photon.ray.origin, photon.ray.direction), 0.0f);
        });
        const double cone_mean_cos = 0.5 * (1.0 + std::cos(0.5 * angle));
        const double expected = light.strength * 4.0 * std::cos(zenith) * cone_mean_cos;
        expect_within_noise(tally.total, tally.total_error, light.strength * disk_area,
                            "sun total");
        expect_within_noise(tally.hit, tally.hit_error, expected, "sun onto the square");
    }
}

// Area light of power P: radiance P/(4A), one-sided Lambertian, flux pi P / 4; every photon
// leaves from the light's surface towards its -Z.
TEST(PhotonEmitter, AreaLightFluxAndShape) {
    for (const AreaShape shape : {AreaShape::Rectangle, AreaShape::Ellipse}) {
        Scene scene = floor_scene(100.0f);
        Light light = light_at(LightType::Area, vec3(0.0f, 0.0f, 1.0f));
        light.shape = shape;
        light.size_x = 0.5f;
        light.size_y = 0.25f;
        light.power = 20.0f;
        scene.add_light(light);
        scene.commit();
        double mean_cos = 0.0;
        const Tally tally = emit_photons(scene, kPhotons, [&](const EmittedPhoton& photon) {
            const vec3 p = photon.ray.origin - light.position();
            EXPECT_NEAR(p.z, 0.0f, 1e-6f);
            const float x = p.x / 0.25f, y = p.y / 0.125f;
            if (shape == AreaShape::Ellipse) {
                EXPECT_LE(x * x + y * y, 1.0f + 1e-5f);
            }
            EXPECT_LE(std::fabs(x), 1.0f + 1e-5f);
            EXPECT_LE(std::fabs(y), 1.0f + 1e-5f);
            EXPECT_LT(photon.ray.direction.z, 0.0f);
            mean_cos += -photon.ray.direction.z / double(kPhotons);
        });
        const double expected = kPiD * light.power / 4.0;
        expect_within_noise(tally.total, tally.total_error, expected, "area total");
        expect_within_noise(tally.hit, tally.hit_error, expected, "area onto the floor");
        // Cosine-weighted directions: E[cos] = 2/3; cos has standard deviation ~0.24.
        EXPECT_NEAR(mean_cos, 2.0 / 3.0, kSigmas * 0.24 / std::sqrt(double(kPhotons)));
    }
}

// An emissive triangle of radiance Le and area A emits 2 pi Le A, half from each side.
TEST(PhotonEmitter, EmissiveTriangleFluxBothSides) {
    Scene scene;
    Material material = test::lambert(0.5f);
    material.emission_color = vec3(1.0f, 0.5f, 0.25f);
    material.emission_strength = 4.0f;
    scene.add_material(material);
    Mesh triangle;
    triangle.positions = {{0, 0, 0}, {2, 0, 0}, {0, 1, 0}};  // area 1, normal +Z
    triangle.triangles = {{0, 1, 2}};
    scene.add_instance(scene.add_mesh(triangle), mat4(1.0f));
    scene.set_world(test::black_world());
    scene.commit();
    const double expected = 2.0 * kPiD * 4.0 * 1.0;
    EXPECT_NEAR(PhotonEmitter(scene).total_power().x, expected, 1e-5 * expected);
    EXPECT_NEAR(PhotonEmitter(scene).total_power().z, 0.25 * expected, 1e-5 * expected);
    uint64_t upward = 0;
    const Tally tally = emit_photons(scene, kPhotons, [&](const EmittedPhoton& photon) {
        const vec3& o = photon.ray.origin;
        EXPECT_NEAR(o.z, 0.0f, 1e-3f);
        EXPECT_GE(o.x, -1e-3f);
        EXPECT_GE(o.y, -1e-3f);
        EXPECT_LE(o.x + 2.0f * o.y, 2.0f + 1e-3f);
        // Leaves on the side it was offset to.
        EXPECT_GT(o.z * photon.ray.direction.z, 0.0f);
        if (photon.ray.direction.z > 0.0f) ++upward;
    });
    expect_within_noise(tally.total, tally.total_error, expected, "triangle total");
    EXPECT_EQ(tally.hit, 0.0) << "a photon hit its own triangle";
    EXPECT_NEAR(double(upward) / kPhotons, 0.5, kSigmas * 0.5 / std::sqrt(double(kPhotons)));
}

// Uniform world radiance Lw: each side of a square of area A receives pi Lw A.
TEST(PhotonEmitter, WorldIrradianceOnBothSidesOfASquare) {
    Scene scene;
    scene.add_material(test::lambert(0.0f));
    scene.add_instance(scene.add_mesh(test::plane(1.0f)), mat4(1.0f));
    World world;
    world.color = vec3(0.2f, 0.3f, 0.4f);
    world.strength = 2.0f;
    scene.set_world(world);
    scene.commit();
    const double radiance = 0.4, radius2 = 2.0;
    EXPECT_NEAR(PhotonEmitter(scene).total_power().x, radiance * 4.0 * kPiD * kPiD * radius2,
                1e-4);
    const Tally tally = emit_photons(scene, kPhotons);
    expect_within_noise(tally.total, tally.total_error, radiance * 4.0 * kPiD * kPiD * radius2,
                        "world total");
    expect_within_noise(tally.hit, tally.hit_error, 2.0 * kPiD * radiance * 4.0,
                        "world onto both sides");
}

// All emitter types at once: the flux distribution picks each in proportion to its power, so the
// photons still sum to the total; zero-power lights are skipped.
TEST(PhotonEmitter, MixedEmittersSumToTotalPower) {
    Scene scene;
    Material emissive = test::lambert(0.5f);
    emissive.emission_color = vec3(1.0f);
    emissive.emission_strength = 0.5f;
    scene.add_material(test::lambert(0.5f));
    scene.add_material(emissive);
    Mesh mesh = test::plane(1.0f);
    mesh.material_indices = {0, 1};  // one of the two triangles emits (area 2)
    scene.add_instance(scene.add_mesh(mesh), mat4(1.0f));
    World world;
    world.color = vec3(0.1f);
    scene.set_world(world);
    Light point = light_at(LightType::Point, vec3(0.0f, 0.0f, 1.0f));
    point.power = 30.0f;
    Light dark = point;
    dark.power = 0.0f;
    Light sun;
    sun.type = LightType::Sun;
    sun.strength = 2.0f;
    Light area = light_at(LightType::Area, vec3(0.0f, 0.0f, 1.0f));
    area.power = 8.0f;
    for (const Light& light : {point, dark, sun, area}) scene.add_light(light);
    scene.commit();
    const double disk = kPiD * 2.0;  // bounding radius sqrt(2)
    const double expected = 30.0 + 2.0 * disk + kPiD * 8.0 / 4.0 + 2.0 * kPiD * 0.5 * 2.0 +
                            0.1 * 4.0 * kPiD * disk;
    EXPECT_NEAR(PhotonEmitter(scene).total_power().x, expected, 1e-5 * expected);
    const Tally tally = emit_photons(scene, kPhotons);
    expect_within_noise(tally.total, tally.total_error, expected, "mixed total");
}

// A lamp share: two point lights of 1000 W and 10 W (as the two rooms' bright and dim lamps)
// and an emissive square, each lamp's photons counted apart. By flux the dim lamp gets ~1% of
// them; with light_share_uniform u, (1 - u) x its flux share + u / 3. Each lamp's photons still
// sum to its flux, and so do all of them (the power is divided by the mixed probability).
TEST(PhotonEmitter, LampShareKeepsEachLampsFlux) {
    Scene scene = emissive_square_scene(0.5f);  // 2 pi 0.5 4 = 12.6 W
    Light bright = light_at(LightType::Point, vec3(-1.0f, 0.0f, 1.0f));
    bright.power = 1000.0f;
    Light dim = light_at(LightType::Point, vec3(1.0f, 0.0f, 1.0f));
    dim.power = 10.0f;
    scene.add_light(bright);
    scene.add_light(dim);
    scene.commit();
    const double square = 2.0 * kPiD * 0.5 * 4.0;
    const double total = 1010.0 + square;
    for (float u : {0.0f, 0.5f, 1.0f}) {
        SCOPED_TRACE(u);
        // Per lamp (by the photon's origin): the photons, their power and its square.
        double count[3] = {}, sum[3] = {}, sum2[3] = {};
        const Tally tally = emit_photons(
            scene, kPhotons,
            [&](const EmittedPhoton& photon) {
                const int lamp = photon.ray.origin == bright.position() ? 0
                                 : photon.ray.origin == dim.position()  ? 1
                                                                        : 2;
                const double power = photon.power.x;
                count[lamp] += 1.0;
                sum[lamp] += power;
                sum2[lamp] += power * power;
            },
            u);
        expect_within_noise(tally.total, tally.total_error, total, "all lamps");
        const double flux[3] = {1000.0, 10.0, square};
        for (int lamp = 0; lamp < 3; ++lamp) {
            const double share = (1.0 - u) * flux[lamp] / total + u / 3.0;
            // Stratified selection: each lamp's count is its share within a photon or two.
            EXPECT_NEAR(count[lamp], share * double(kPhotons), 2.0) << "lamp " << lamp;
            expect_within_noise(sum[lamp], standard_error_of_sum(sum[lamp], sum2[lamp], kPhotons),
                                flux[lamp], "one lamp's photons");
        }
    }
}

// An emissive object's triangles are one lamp: its share is split among them by flux.
TEST(PhotonEmitter, LampShareTreatsAnEmissiveObjectAsOneLamp) {
    Scene scene = emissive_square_scene(1.0f);  // two triangles
    Light point = light_at(LightType::Point, vec3(0.0f, 0.0f, 1.0f));
    point.power = 10000.0f;
    scene.add_light(point);
    scene.commit();
    double from_square = 0.0;
    emit_photons(
        scene, kPhotons,
        [&](const EmittedPhoton& photon) {
            if (photon.ray.origin != point.position()) from_square += 1.0;
        },
        1.0f);
    // Uniform over two lamps (the light, the square), not over three emitters.
    EXPECT_NEAR(from_square, 0.5 * double(kPhotons), 2.0);
}

// u = 0 is the flux distribution bit for bit; u outside [0, 1] or NaN throws.
TEST(PhotonEmitter, LampShareZeroIsByFluxAndInvalidSharesThrow) {
    Scene scene = floor_scene(1.0f);
    Light bright = light_at(LightType::Point, vec3(0.0f, 0.0f, 1.0f));
    bright.power = 100.0f;
    Light dim = light_at(LightType::Spot, vec3(0.5f, 0.0f, 1.0f));
    dim.power = 3.0f;
    scene.add_light(bright);
    scene.add_light(dim);
    scene.commit();
    const PhotonEmitter by_flux(scene), zero_share(scene, 0.0f);
    for (uint64_t i = 0; i < 1000; ++i) {
        Pcg32 rng_a(3, stream_id(0, i)), rng_b(3, stream_id(0, i));
        EmittedPhoton a, b;
        ASSERT_EQ(by_flux.emit(i, 1000, rng_a, &a), zero_share.emit(i, 1000, rng_b, &b));
        EXPECT_EQ(a.power, b.power);
        EXPECT_EQ(a.ray.origin, b.ray.origin);
        EXPECT_EQ(a.ray.direction, b.ray.direction);
    }
    for (float u : {-0.1f, 1.5f, std::nanf("")})
        EXPECT_THROW(PhotonEmitter(scene, u), InvalidArgument) << u;
}

TEST(PhotonEmitter, SceneWithoutEmittersIsEmpty) {
    Scene scene = floor_scene(1.0f);
    scene.commit();
    const PhotonEmitter emitter(scene);
    EXPECT_TRUE(emitter.empty());
    EXPECT_EQ(emitter.total_power(), vec3(0.0f));
    Pcg32 rng;
    EmittedPhoton photon;
    EXPECT_FALSE(emitter.emit(0, 1, rng, &photon));
}

TEST(PhotonEmitter, UncommittedSceneThrows) {
    Scene scene = floor_scene(1.0f);
    EXPECT_THROW(PhotonEmitter{scene}, InvalidArgument);
}

}  // namespace
}  // namespace shgi
