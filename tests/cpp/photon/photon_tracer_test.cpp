// trace_photons against closed forms: the flux a furnace stores bounce by bounce (Russian
// roulette must not bias it), the caustic/global split behind a mirror sphere, determinism across
// thread counts, cancel and bad settings.
#include "photon/photon_tracer.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <string>
#include <utility>

#include <glm/gtc/matrix_transform.hpp>

#include "photon/photon_emitter.h"
#include "render/render_test_scenes.h"
#include "support/expect_error.h"
#include "support/noise_stats.h"
#include "util/error.h"

namespace shgi {
namespace {

using test::point_light;

double total_power(const std::vector<Photon>& photons) {
    double sum = 0.0;
    for (const Photon& photon : photons) sum += photon.power.x;
    return sum;
}

// Closed box [-1, 1]^3 seen from inside, Lambert albedo `albedo`, a point light in it.
Scene furnace(float albedo, float power) {
    Scene scene;
    scene.add_material(test::lambert(albedo));
    scene.add_instance(scene.add_mesh(test::inward_box(1.0f)), mat4(1.0f));
    scene.set_world(test::black_world());
    scene.add_light(point_light(vec3(0.1f, -0.2f, 0.3f), power));
    scene.commit();
    return scene;
}

// In the furnace every photon carries Phi/N; it is stored after its k-th scattering with
// probability a^k (k = 1..M), so the stored total is Phi sum a^k and the count K of a photon's
// stored copies has E[K] = sum a^k, E[K^2] = sum (2k - 1) a^k.
void expect_furnace_total(float albedo, int max_bounces, uint64_t photons) {
    const float power = 100.0f;
    const Scene scene = furnace(albedo, power);
    PhotonTracerSettings settings;
    settings.photons = photons;
    settings.max_bounces = max_bounces;
    const PhotonMaps maps = trace_photons(scene, settings, 0);
    double mean = 0.0, mean_square = 0.0;
    for (int k = 1; k <= max_bounces; ++k) {
        mean += std::pow(albedo, k);
        mean_square += (2.0 * k - 1.0) * std::pow(albedo, k);
    }
    const double error = power * std::sqrt((mean_square - mean * mean) / double(photons));
    testing::expect_within_noise(total_power(maps.global), error, power * mean, 0.0,
                                 "albedo " + std::to_string(albedo) + ", max_bounces " +
                                     std::to_string(max_bounces));
    EXPECT_TRUE(maps.caustic.empty()) << "diffuse-only scene stored caustic photons";
    EXPECT_EQ(maps.emitted, photons);
    EXPECT_EQ(maps.emitted_power, vec3(power));
    for (const Photon& photon : maps.global) {
        // On a wall, its normal facing into the box, arriving from inside.
        EXPECT_NEAR(std::max({std::fabs(photon.position.x), std::fabs(photon.position.y),
                              std::fabs(photon.position.z)}),
                    1.0f, 1e-4f);
        EXPECT_LT(glm::dot(photon.normal, photon.position), 0.0f);
        EXPECT_GT(glm::dot(photon.normal, photon.direction), 0.0f);
        EXPECT_NEAR(glm::length(photon.direction), 1.0f, 1e-5f);
    }
}

// Albedo 0.5, no practical bounce limit: Phi (a + a^2 + ...) = Phi a / (1 - a) = Phi.
TEST(PhotonTracer, FurnaceStoresGeometricSeriesUnderRussianRoulette) {
    expect_furnace_total(0.5f, 64, 40000);
}

// The sum truncated by max_bounces: Phi (a + a^2) for M = 2.
TEST(PhotonTracer, FurnaceTruncatedByMaxBounces) {
    expect_furnace_total(0.7f, 2, 20000);
    expect_furnace_total(0.7f, 1, 20000);
}

// Past one block of 1024 chunks of 4096 photons: the second block's merge moves the ~2.9M photons
// of the first to a larger buffer in slices of 2^20; a lost or repeated slice would move the total
// by a third.
TEST(PhotonTracer, FurnaceTotalHoldsAcrossBlocks) {
    expect_furnace_total(0.7f, 1, 1024 * 4096 + 4096);
}

TEST(PhotonTracer, BlackSurfacesStoreNothing) {
    const Scene scene = furnace(0.0f, 10.0f);
    PhotonTracerSettings settings;
    settings.photons = 5000;
    const PhotonMaps maps = trace_photons(scene, settings, 0);
    EXPECT_TRUE(maps.global.empty());
    EXPECT_TRUE(maps.caustic.empty());
    EXPECT_EQ(maps.bounces, settings.photons);  // one ray each, absorbed at the first wall
    EXPECT_EQ(maps.emitted_power, vec3(10.0f));
}

// A diffuse floor at z = 0 (albedo 0.5), a metal sphere of radius 0.5 at (0, 0, 1) with the
// given roughness, and a point light beside it.
constexpr float kSphereRadius = 0.5f;
const vec3 kSphereCenter(0.0f, 0.0f, 1.0f);
const vec3 kLightPosition(1.5f, 0.0f, 1.5f);

Scene sphere_over_floor(float roughness) {
    Scene scene;
    scene.add_material(test::lambert(0.5f));
    Material metal;
    metal.base_color = vec3(1.0f);
    metal.metallic = 1.0f;
    metal.roughness = roughness;
    const uint32_t metal_id = scene.add_material(metal);
    scene.add_instance(scene.add_mesh(test::plane(5.0f)), mat4(1.0f), "floor");
    Mesh sphere = test::uv_sphere(kSphereRadius, 48, 96);
    sphere.material_indices.assign(sphere.triangles.size(), metal_id);
    scene.add_instance(scene.add_mesh(sphere), glm::translate(mat4(1.0f), kSphereCenter),
                       "sphere");
    scene.set_world(test::black_world());
    scene.add_light(point_light(kLightPosition, 100.0f));
    scene.commit();
    return scene;
}

constexpr uint32_t kSphereInstance = 1;
// Below this |cos| to the sphere's normal a retraced ray grazes the sphere (~84 degrees).
constexpr float kGrazingCos = 0.1f;

// A mirror reflects light to the floor: those photons (L S D) are caustic; photons that reach
// the floor again after a diffuse bounce and the mirror (L D S D) are global. Both arrive from
// the sphere, which is checked by tracing back along their `direction`; reflecting that
// direction in the sphere's shading normal must lead to the light for caustic photons and back
// down to the floor for global ones.
TEST(PhotonTracer, MirrorSphereCausticsAndGlobalPhotons) {
    const Scene scene = sphere_over_floor(0.0f);
    PhotonTracerSettings settings;
    settings.photons = 100000;
    const PhotonMaps maps = trace_photons(scene, settings, 0);
    ASSERT_GT(maps.caustic.size(), 100u);
    ASSERT_GT(maps.global.size(), 100u);
    size_t reflections_checked = 0;
    auto check = [&](const Photon& photon, bool caustic) {
        // A Dirac sphere stores nothing: every photon lies on the floor, seen from above.
        EXPECT_NEAR(photon.position.z, 0.0f, 1e-5f);
        EXPECT_EQ(photon.normal, vec3(0.0f, 0.0f, 1.0f));
        EXPECT_GT(photon.direction.z, 0.0f);
        Ray back;
        back.origin = photon.position + 1e-4f * photon.normal;
        back.direction = photon.direction;
        const Hit hit = scene.intersect(back);
        ASSERT_TRUE(hit.valid());
        ASSERT_EQ(hit.instance_id, kSphereInstance);
        const SurfacePoint sp = scene.surface_point(back, hit);
        const vec3 n = sp.shading_normal;
        const vec3 out = -photon.direction;  // the direction it left the sphere in
        const vec3 in = glm::reflect(out, n);  // reversed: towards where it came from
        const vec3 from = -in;
        // Tracing back along a direction that grazes the faceted sphere can land on a
        // neighbouring facet (another interpolated normal): check the reflection elsewhere.
        if (std::fabs(glm::dot(n, photon.direction)) < kGrazingCos) return;
        ++reflections_checked;
        if (caustic) {
            EXPECT_GT(glm::dot(from, glm::normalize(kLightPosition - sp.position)), 0.9999f);
        } else {
            EXPECT_LT(from.z, 0.0f);  // arrived at the sphere from the floor below
        }
    };
    for (const Photon& photon : maps.caustic) check(photon, true);
    for (const Photon& photon : maps.global) check(photon, false);
    EXPECT_GT(reflections_checked, (maps.caustic.size() + maps.global.size()) * 9 / 10);
}

// Glossy metal of roughness 0.05 counts as specular for specular_roughness 0.1 and as diffuse
// for 0: the same photons (same RNG streams), only classified differently.
TEST(PhotonTracer, SpecularRoughnessDecidesCaustics) {
    const Scene scene = sphere_over_floor(0.05f);
    PhotonTracerSettings settings;
    settings.photons = 40000;
    settings.specular_roughness = 0.1f;
    const PhotonMaps glossy_caustics = trace_photons(scene, settings, 0);
    settings.specular_roughness = 0.0f;
    const PhotonMaps no_caustics = trace_photons(scene, settings, 0);
    EXPECT_GT(glossy_caustics.caustic.size(), 100u);
    EXPECT_TRUE(no_caustics.caustic.empty());
    EXPECT_EQ(no_caustics.global.size(),
              glossy_caustics.global.size() + glossy_caustics.caustic.size());
    // The glossy sphere now has a non-Dirac lobe: light reaching it after the floor is stored.
    size_t on_sphere = 0;
    for (const Photon& photon : no_caustics.global)
        if (glm::distance(photon.position, kSphereCenter) < kSphereRadius + 1e-3f) ++on_sphere;
    EXPECT_GT(on_sphere, 0u);
}

bool same_photons(const std::vector<Photon>& a, const std::vector<Photon>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
        if (a[i].position != b[i].position || a[i].power != b[i].power ||
            a[i].normal != b[i].normal || a[i].direction != b[i].direction)
            return false;
    return true;
}

PhotonMaps trace_with_threads(const Scene& scene, int threads, uint64_t pass) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    PhotonTracerSettings settings;
    settings.photons = 2 * 4096 + 123;  // three chunks, the last one partial
    settings.seed = 11;
    return trace_photons(scene, settings, pass);
}

// Every emitter kind and every lobe kind: a closed room with a rough metal and a glass sphere,
// lit by a point and an area light inside and by the world outside.
Scene mixed_scene() {
    Scene scene;
    scene.add_material(test::lambert(0.6f));
    Material metal;
    metal.metallic = 1.0f;
    metal.roughness = 0.3f;
    Material glass;
    glass.transmission = 1.0f;
    glass.roughness = 0.0f;
    const uint32_t metal_id = scene.add_material(metal), glass_id = scene.add_material(glass);
    scene.add_instance(scene.add_mesh(test::inward_box(3.0f)), mat4(1.0f));
    for (const auto& [material_id, center] : {std::pair(metal_id, vec3(0.0f, 0.0f, -2.0f)),
                                              std::pair(glass_id, vec3(1.5f, 1.0f, -2.0f))}) {
        Mesh sphere = test::uv_sphere(0.7f);
        sphere.material_indices.assign(sphere.triangles.size(), material_id);
        scene.add_instance(scene.add_mesh(sphere), glm::translate(mat4(1.0f), center));
    }
    World world;
    world.color = vec3(0.2f);
    scene.set_world(world);
    scene.add_light(point_light(vec3(1.0f, -1.0f, 1.0f), 100.0f));
    Light area;
    area.type = LightType::Area;
    area.power = 50.0f;
    area.world_from_light = glm::translate(mat4(1.0f), vec3(-1.0f, 0.5f, 2.5f));
    scene.add_light(area);
    scene.commit();
    return scene;
}

TEST(PhotonTracer, DeterministicAcrossThreadCounts) {
    const Scene scene = mixed_scene();
    const PhotonMaps one = trace_with_threads(scene, 1, 0);
    const PhotonMaps two = trace_with_threads(scene, 2, 0);
    EXPECT_GT(one.global.size(), 1000u);
    EXPECT_GT(one.caustic.size(), 10u);
    EXPECT_TRUE(same_photons(one.global, two.global));
    EXPECT_TRUE(same_photons(one.caustic, two.caustic));
    EXPECT_EQ(one.bounces, two.bounces);
    EXPECT_EQ(one.emitted_power, two.emitted_power);
    // Another pass draws other streams.
    const PhotonMaps next = trace_with_threads(scene, 2, 1);
    EXPECT_FALSE(same_photons(one.global, next.global));
}

// max_glossy_bounces gives glossy scatterings a budget of their own. A diffuse-only furnace has
// none: its maps are bit-identical with or without the budget. Over the mirror sphere (a glossy
// Dirac lobe) with max_bounces 2: without a budget a photon's path L S D D ends there; with it
// the mirror does not count, so paths L S D S D store on the floor after one diffuse
// and two glossy scatterings (more global photons, the caustics unchanged); a budget of
// 0 ends every photon the mirror reflects (no caustics at all).
TEST(PhotonTracer, GlossyBudgetCountsGlossyScatteringsApart) {
    const Scene furnace_scene = furnace(0.7f, 10.0f);
    PhotonTracerSettings settings;
    settings.photons = 20000;
    settings.max_bounces = 2;
    const PhotonMaps plain = trace_photons(furnace_scene, settings, 0);
    settings.max_glossy_bounces = 4;
    const PhotonMaps budget = trace_photons(furnace_scene, settings, 0);
    EXPECT_TRUE(same_photons(plain.global, budget.global));

    const Scene scene = sphere_over_floor(0.0f);
    settings.photons = 100000;
    settings.max_glossy_bounces = -1;
    const PhotonMaps shared = trace_photons(scene, settings, 0);
    settings.max_glossy_bounces = 4;
    const PhotonMaps apart = trace_photons(scene, settings, 0);
    settings.max_glossy_bounces = 0;
    const PhotonMaps none = trace_photons(scene, settings, 0);
    ASSERT_GT(shared.caustic.size(), 100u);
    EXPECT_EQ(apart.caustic.size(), shared.caustic.size());
    EXPECT_GT(apart.global.size(), shared.global.size());
    EXPECT_TRUE(none.caustic.empty());
}

// A spent diffuse budget turns only the diffuse lobe off, as a path tracer's Light Paths do.
// With a floor and a mirror sphere alone, a global photon must have scattered on the floor
// (L D S D, L S D S D): with max_bounces 1 that scattering spends the budget, so only a photon
// that still reflects off the mirror afterwards reaches the floor again. Without a glossy budget
// of its own the mirror counts against the 1 and no global photon is stored; with one they are,
// each arriving from the sphere.
TEST(PhotonTracer, SpentDiffuseBudgetStillReflectsGlossily) {
    const Scene scene = sphere_over_floor(0.0f);
    PhotonTracerSettings settings;
    settings.photons = 100000;
    settings.max_bounces = 1;
    settings.max_glossy_bounces = -1;
    EXPECT_TRUE(trace_photons(scene, settings, 0).global.empty());
    settings.max_glossy_bounces = 2;
    const PhotonMaps maps = trace_photons(scene, settings, 0);
    ASSERT_GT(maps.global.size(), 100u);
    for (const Photon& photon : maps.global) {
        Ray back;
        back.origin = photon.position + 1e-3f * photon.normal;
        back.direction = photon.direction;
        const Hit hit = scene.intersect(back);
        ASSERT_TRUE(hit.valid());
        EXPECT_EQ(hit.instance_id, kSphereInstance);
    }
}

// The tracer keeps a whole chunk of photons in flight and stores them bounce by bounce; the maps
// must still list each photon's stores together, in photon order. With a single point light
// photon i follows the same path whatever the pass's photon count (its stratum picks the only
// emitter), and its power is the light's divided by the count, so the 64 photons of a small pass
// are, bit for bit and in the same order, the start of a two-chunk pass of 8192 with 128 times
// less power each (a power of two: the scaling is exact).
TEST(PhotonTracer, StoresComeOutInPhotonOrder) {
    const Scene scene = furnace(0.8f, 10.0f);
    PhotonTracerSettings settings;
    settings.seed = 5;
    settings.photons = 64;
    const PhotonMaps few = trace_photons(scene, settings, 0);
    settings.photons = 2 * 4096;
    const PhotonMaps many = trace_photons(scene, settings, 0);
    ASSERT_GT(few.global.size(), 64u);  // several bounces per photon at albedo 0.8
    ASSERT_GT(many.global.size(), few.global.size());
    for (size_t i = 0; i < few.global.size(); ++i) {
        const Photon& a = few.global[i];
        const Photon& b = many.global[i];
        ASSERT_EQ(a.position, b.position) << "stored photon " << i;
        ASSERT_EQ(a.direction, b.direction) << "stored photon " << i;
        ASSERT_EQ(a.normal, b.normal) << "stored photon " << i;
        ASSERT_EQ(a.power, b.power * 128.0f) << "stored photon " << i;
    }
}

TEST(PhotonTracer, EmptySceneAndSceneWithoutEmittersGiveEmptyMaps) {
    Scene lights_only;
    lights_only.add_light(point_light(vec3(0.0f), 10.0f));
    lights_only.commit();
    PhotonTracerSettings settings;
    settings.photons = 100;
    PhotonMaps maps = trace_photons(lights_only, settings, 0);
    EXPECT_TRUE(maps.global.empty() && maps.caustic.empty());
    EXPECT_EQ(maps.emitted, 0u);

    Scene dark;
    dark.add_material(test::lambert(0.5f));
    dark.add_instance(dark.add_mesh(test::inward_box(1.0f)), mat4(1.0f));
    dark.set_world(test::black_world());
    dark.commit();
    maps = trace_photons(dark, settings, 0);
    EXPECT_TRUE(maps.global.empty() && maps.caustic.empty());
    EXPECT_EQ(maps.emitted_power, vec3(0.0f));
}

TEST(PhotonTracer, CancelledProgressThrowsCancelled) {
    const Scene scene = furnace(0.5f, 10.0f);
    PhotonTracerSettings settings;
    settings.photons = 8 * 4096;  // chunks left to skip after the first report
    Progress cancelled_before;
    cancelled_before.cancel();
    EXPECT_THROW(trace_photons(scene, settings, 0, &cancelled_before), Cancelled);
    // Cancelled by the first progress report, while chunks are being traced.
    Progress* self = nullptr;
    Progress cancelled_during([&](float, const std::string&) { self->cancel(); }, 0.0);
    self = &cancelled_during;
    EXPECT_THROW(trace_photons(scene, settings, 0, &cancelled_during), Cancelled);
}

// ---------------------------------------------------------------------------------------------
// First hits (PhotonTracerSettings::store_first_hits)

PhotonTracerSettings first_hit_settings(uint64_t photons) {
    PhotonTracerSettings settings;
    settings.photons = photons;
    settings.seed = 3;
    settings.store_first_hits = true;
    return settings;
}

// Every first hit lies on the lit surface facing its light, and reflects albedo × arriving.
void expect_first_hits_on_lambert(const std::vector<PhotonFirstHit>& hits, float albedo) {
    for (const PhotonFirstHit& hit : hits) {
        EXPECT_GT(glm::dot(hit.normal, hit.direction), 0.0f);
        EXPECT_NEAR(glm::length(hit.direction), 1.0f, 1e-5f);
        EXPECT_EQ(hit.reflected_power, albedo * hit.power);  // Lambert: exactly base colour × Φ
        EXPECT_GT(hit.power.x, 0.0f);
    }
}

// A point light (Φ = 100 W) at height h over a Lambert square [-a, a]² (albedo 0.6): the flux
// reaching it is Φ Ω / 4π with Ω = 4 asin(a² / (a² + h²)), the square's solid angle. Each
// photon carries Φ/N and reaches it with probability p = Ω / 4π, so the sum's standard error is
// at most Φ √(p(1 − p)/N) (stratified emission only lowers it).
TEST(PhotonTracerFirstHits, SumToTheEmittedFluxReachingALitPlane) {
    constexpr float kPower = 100.0f, kHalf = 1.0f, kHeight = 0.8f, kAlbedo = 0.6f;
    constexpr uint64_t kPhotons = 50000;
    Scene scene;
    scene.add_material(test::lambert(kAlbedo));
    scene.add_instance(scene.add_mesh(test::plane(kHalf)), mat4(1.0f));
    scene.set_world(test::black_world());
    scene.add_light(point_light(vec3(0.0f, 0.0f, kHeight), kPower));
    scene.commit();
    const PhotonMaps maps = trace_photons(scene, first_hit_settings(kPhotons), 0);

    const double solid_angle = 4.0 * std::asin(double(kHalf * kHalf) /
                                               double(kHalf * kHalf + kHeight * kHeight));
    const double p = solid_angle / (4.0 * M_PI);
    double arriving = 0.0, reflected = 0.0;
    for (const PhotonFirstHit& hit : maps.first_hits) {
        arriving += hit.power.x;
        reflected += hit.reflected_power.y;
        EXPECT_NEAR(hit.position.z, 0.0f, 1e-5f);
        EXPECT_LE(std::max(std::fabs(hit.position.x), std::fabs(hit.position.y)), kHalf + 1e-5f);
        EXPECT_EQ(hit.normal, vec3(0.0f, 0.0f, 1.0f));  // flipped to the lit side
    }
    expect_first_hits_on_lambert(maps.first_hits, kAlbedo);
    const double error = kPower * std::sqrt(p * (1.0 - p) / double(kPhotons));
    testing::expect_within_noise(arriving, error, kPower * p, 0.0, "first hits' arriving flux");
    testing::expect_within_noise(reflected, kAlbedo * error, kAlbedo * kPower * p, 0.0,
                                 "first hits' reflected flux");
    EXPECT_NEAR(double(maps.first_hits.size()), p * double(kPhotons),
                testing::kSigmas * std::sqrt(p * (1.0 - p) * double(kPhotons)));
}

// In a closed box every photon's first ray hits a wall: one first hit per photon, in photon
// order, and their flux is the light's to float rounding (each carries exactly Φ/N).
TEST(PhotonTracerFirstHits, FurnaceRecordsOnePerPhotonSummingToTheEmittedFlux) {
    constexpr float kPower = 10.0f, kAlbedo = 0.5f;
    constexpr double kRoundingTolerance = 1e-5;  // relative: float Φ/N, summed in double
    const Scene scene = furnace(kAlbedo, kPower);
    const PhotonMaps maps = trace_photons(scene, first_hit_settings(3 * 4096 + 7), 0);
    ASSERT_EQ(maps.first_hits.size(), maps.emitted);
    double arriving = 0.0;
    for (const PhotonFirstHit& hit : maps.first_hits) {
        arriving += hit.power.z;
        EXPECT_LT(glm::dot(hit.normal, hit.position), 0.0f);  // on a wall, facing inwards
    }
    EXPECT_NEAR(arriving, kPower, kPower * kRoundingTolerance);
    expect_first_hits_on_lambert(maps.first_hits, kAlbedo);
    // Photon order: the first 64 of a 64-photon pass are those of this pass, scaled by N / 64.
    PhotonTracerSettings few = first_hit_settings(64);
    const PhotonMaps small = trace_photons(scene, few, 0);
    ASSERT_EQ(small.first_hits.size(), 64u);
    for (size_t i = 0; i < small.first_hits.size(); ++i) {
        EXPECT_EQ(small.first_hits[i].position, maps.first_hits[i].position) << "photon " << i;
        EXPECT_EQ(small.first_hits[i].direction, maps.first_hits[i].direction) << "photon " << i;
    }
}

// Recording first hits changes nothing else (maps, bounces), is off by default (no first hits),
// and its output is bit-identical for 1 and 2 threads.
TEST(PhotonTracerFirstHits, MapsUnchangedAndDeterministic) {
    const Scene scene = mixed_scene();
    EXPECT_FALSE(PhotonTracerSettings{}.store_first_hits);
    const PhotonMaps off = trace_with_threads(scene, 2, 0);
    EXPECT_TRUE(off.first_hits.empty());
    PhotonMaps on[2];
    for (int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        PhotonTracerSettings settings;
        settings.photons = 2 * 4096 + 123;  // as trace_with_threads
        settings.seed = 11;
        settings.store_first_hits = true;
        on[threads - 1] = trace_photons(scene, settings, 0);
    }
    for (const PhotonMaps& maps : on) {
        EXPECT_TRUE(same_photons(off.global, maps.global));
        EXPECT_TRUE(same_photons(off.caustic, maps.caustic));
        EXPECT_EQ(off.bounces, maps.bounces);
    }
    // Photons of the lights inside the room all hit; some of the world's, aimed at the scene's
    // bounds from outside, miss the box.
    ASSERT_GT(on[0].first_hits.size(), 5000u);
    ASSERT_LT(on[0].first_hits.size(), size_t(on[0].emitted));
    ASSERT_EQ(on[0].first_hits.size(), on[1].first_hits.size());
    for (size_t i = 0; i < on[0].first_hits.size(); ++i) {
        const PhotonFirstHit& a = on[0].first_hits[i];
        const PhotonFirstHit& b = on[1].first_hits[i];
        ASSERT_TRUE(a.position == b.position && a.normal == b.normal &&
                    a.direction == b.direction && a.power == b.power &&
                    a.reflected_power == b.reflected_power)
            << "first hit " << i;
    }
    // Glass and metal have no diffuse lobe: some first hits reflect nothing diffusely.
    size_t without_diffuse = 0;
    for (const PhotonFirstHit& hit : on[0].first_hits)
        without_diffuse += hit.reflected_power == vec3(0.0f) ? 1 : 0;
    EXPECT_GT(without_diffuse, 0u);
    EXPECT_LT(without_diffuse, on[0].first_hits.size());
}

void expect_invalid(const PhotonTracerSettings& settings, const std::string& expected) {
    testing::expect_invalid_argument([&] { validate_photon_tracer_settings(settings); }, expected);
}

TEST(PhotonTracer, BadSettingsNameTheField) {
    PhotonTracerSettings settings;
    settings.photons = 0;
    expect_invalid(settings, "PhotonTracerSettings.photons is 0; it must be in [1, 2^40]");
    settings.photons = (uint64_t(1) << 40) + 1;
    expect_invalid(settings, "PhotonTracerSettings.photons is 1099511627777");
    settings = PhotonTracerSettings{};
    settings.max_bounces = 0;
    expect_invalid(settings, "PhotonTracerSettings.max_bounces is 0");
    settings = PhotonTracerSettings{};
    settings.max_glossy_bounces = -2;
    expect_invalid(settings, "PhotonTracerSettings.max_glossy_bounces is -2");
    settings = PhotonTracerSettings{};
    settings.specular_roughness = std::nanf("");
    expect_invalid(settings, "PhotonTracerSettings.specular_roughness is nan");
    settings.specular_roughness = 1.5f;
    expect_invalid(settings, "PhotonTracerSettings.specular_roughness is 1.5");
    EXPECT_NO_THROW(validate_photon_tracer_settings(PhotonTracerSettings{}));

    const Scene scene = furnace(0.5f, 1.0f);
    settings.specular_roughness = -0.5f;
    EXPECT_THROW(trace_photons(scene, settings, 0), InvalidArgument);
    Scene uncommitted;
    EXPECT_THROW(trace_photons(uncommitted, PhotonTracerSettings{}, 0), InvalidArgument);
}

}  // namespace
}  // namespace shgi
