// PhotonMap's density estimate: exact on hand-placed photons, unbiased (to O(1/k)) on photons
// spread uniformly over a plane of known irradiance, and blind to photons on the other side.
#include "photon/photon_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "util/error.h"
#include "util/progress.h"
#include "util/rng.h"

namespace shgi {
namespace {

const vec3 kUp(0.0f, 0.0f, 1.0f);

Photon photon_at(const vec3& position, float power, const vec3& normal = kUp) {
    Photon photon;
    photon.position = position;
    photon.power = vec3(power);
    photon.normal = normal;
    photon.direction = normal;
    return photon;
}

// Photons of total power E A uniformly on the square [-1, 1]^2 at z = 0 (area A = 4), facing
// `normal`: irradiance E on that side.
std::vector<Photon> uniform_plane(size_t count, float irradiance, const vec3& normal,
                                  uint64_t stream) {
    Pcg32 rng(5, stream);
    std::vector<Photon> photons;
    const float power = irradiance * 4.0f / float(count);
    for (size_t i = 0; i < count; ++i) {
        const vec2 u = rng.next_vec2();
        photons.push_back(photon_at(vec3(2.0f * u - 1.0f, 0.0f), power, normal));
    }
    return photons;
}

// Mean estimate over a 10 x 10 grid of query points inside [-0.5, 0.5]^2 (away from the edges).
vec3 mean_irradiance(const PhotonMap& map, const vec3& n, int k) {
    vec3 sum(0.0f);
    for (int y = 0; y < 10; ++y)
        for (int x = 0; x < 10; ++x)
            sum += map.irradiance(vec3(-0.45f + 0.1f * x, -0.45f + 0.1f * y, 0.0f), n, k, 0.5f);
    return sum / 100.0f;
}

// With k photons in the disk, E[k / (pi r_k^2)] = density k / (k - 1); the averaged relative
// noise is about 1/sqrt(100 k) = 1%, so 4% covers bias and noise.
constexpr float kDensityTolerance = 0.04f;
constexpr int kNeighbours = 100;

TEST(PhotonMap, UniformPlaneGivesItsIrradiance) {
    const float irradiance = 3.0f;
    const PhotonMap map(uniform_plane(40000, irradiance, kUp, 1));
    EXPECT_EQ(map.size(), 40000u);
    const vec3 estimate = mean_irradiance(map, kUp, kNeighbours);
    EXPECT_NEAR(estimate.x, irradiance, kDensityTolerance * irradiance);
    EXPECT_EQ(estimate.x, estimate.z);
}

// Photons on both sides of a thin wall, interleaved: each side sees only its own irradiance.
TEST(PhotonMap, NormalFilterSeparatesTheTwoSides) {
    std::vector<Photon> photons = uniform_plane(40000, 2.0f, kUp, 1);
    const std::vector<Photon> below = uniform_plane(40000, 6.0f, -kUp, 2);
    photons.insert(photons.end(), below.begin(), below.end());
    const PhotonMap map(std::move(photons));
    EXPECT_NEAR(mean_irradiance(map, kUp, 2 * kNeighbours).x, 2.0f, kDensityTolerance * 2.0f);
    EXPECT_NEAR(mean_irradiance(map, -kUp, 2 * kNeighbours).x, 6.0f, kDensityTolerance * 6.0f);
    // A surface edge-on to both sees neither.
    EXPECT_EQ(map.irradiance(vec3(0.0f), vec3(1.0f, 0.0f, 0.0f), kNeighbours, 0.5f), vec3(0.0f));
}

// Hand-placed photons: the disk is the k-th nearest's, or max_radius when fewer lie within it.
TEST(PhotonMap, DiskRadiusRule) {
    std::vector<Photon> photons = {photon_at({0.1f, 0, 0}, 1.0f), photon_at({0, 0.2f, 0}, 2.0f),
                                   photon_at({-0.3f, 0, 0}, 4.0f), photon_at({0, -0.4f, 0}, 8.0f),
                                   photon_at({2.0f, 0, 0}, 16.0f)};
    const float scale = 0.5f;
    const PhotonMap map(photons, scale);
    const vec3 p(0.0f);
    // k = 3: the three nearest, r = 0.3.
    EXPECT_NEAR(map.irradiance(p, kUp, 3, 1.0f).x, scale * 7.0f / (kPi * 0.09f), 1e-4f);
    // k = 10 but only four within 1: r = max_radius.
    EXPECT_NEAR(map.irradiance(p, kUp, 10, 1.0f).x, scale * 15.0f / kPi, 1e-4f);
    // max_radius cuts the k nearest short: two within 0.25.
    EXPECT_NEAR(map.irradiance(p, kUp, 3, 0.25f).x, scale * 3.0f / (kPi * 0.0625f), 1e-3f);
    // Back-facing photons count towards k (they fill the disk) but add no power.
    photons[0].normal = -kUp;
    const PhotonMap flipped(photons, scale);
    EXPECT_NEAR(flipped.irradiance(p, kUp, 3, 1.0f).x, scale * 6.0f / (kPi * 0.09f), 1e-4f);
}

// The k nearest photons within max_radius by brute force, the way PhotonMap::irradiance counts
// them (facing n, disk of the k-th nearest or max_radius).
vec3 brute_force_irradiance(const std::vector<Photon>& photons, const vec3& p, const vec3& n, int k,
                            float max_radius) {
    std::vector<std::pair<float, size_t>> within;
    for (size_t i = 0; i < photons.size(); ++i) {
        const vec3 d = photons[i].position - p;
        const float distance_squared = glm::dot(d, d);
        if (distance_squared < max_radius * max_radius) within.emplace_back(distance_squared, i);
    }
    const size_t count = std::min(within.size(), size_t(k));
    std::partial_sort(within.begin(), within.begin() + ptrdiff_t(count), within.end());
    vec3 power(0.0f);
    for (size_t j = 0; j < count; ++j)
        if (glm::dot(photons[within[j].second].normal, n) > 0.0f)
            power += photons[within[j].second].power;
    const float radius_squared =
        count == size_t(k) ? within[count - 1].first : max_radius * max_radius;
    return power / (kPi * radius_squared);
}

// A map past one shard (2^18 photons) is split at medians into several k-d trees; a query that
// straddles a split must still find the exact k nearest, as one tree over all photons would.
// Photons on both sides of a plane with random normals and powers, queried on a grid that crosses
// the splits, against a brute-force search.
TEST(PhotonMap, ShardedMapFindsTheExactNearest) {
    Pcg32 rng(9, 0);
    std::vector<Photon> photons(600000);
    for (Photon& photon : photons) {
        const vec2 u = rng.next_vec2();
        photon = photon_at(vec3(2.0f * u - 1.0f, 0.02f * rng.next_float()), 1.0f + rng.next_float(),
                           rng.next_float() < 0.5f ? kUp : -kUp);
    }
    const PhotonMap map(photons);
    ASSERT_GE(map.shard_count(), 4u);
    for (int y = 0; y < 5; ++y)
        for (int x = 0; x < 5; ++x) {
            // Through 0 on both axes, where the first median splits fall.
            const vec3 p(-0.5f + 0.25f * x, -0.5f + 0.25f * y, 0.01f);
            for (int k : {1, 50, 400}) {
                const vec3 expected = brute_force_irradiance(photons, p, kUp, k, 0.5f);
                const vec3 got = map.irradiance(p, kUp, k, 0.5f);
                EXPECT_NEAR(got.x, expected.x, 1e-5f * expected.x) << x << "," << y << " k " << k;
            }
        }
    // The radius cap still holds across shards: nothing beyond 1e-4 m of an empty spot.
    EXPECT_EQ(map.irradiance(vec3(5.0f, 5.0f, 0.0f), kUp, 50, 1e-4f), vec3(0.0f));
}

// The build of a large map stops at a cancel: the map is never half built.
TEST(PhotonMap, BuildStopsOnCancel) {
    std::vector<Photon> photons = uniform_plane(600000, 1.0f, kUp, 3);
    Progress progress;
    progress.cancel();
    EXPECT_THROW(PhotonMap(photons, 1.0f, &progress), Cancelled);
    // Uncancelled, the same photons build fully.
    Progress fresh;
    const PhotonMap map(std::move(photons), 1.0f, &fresh);
    EXPECT_EQ(map.size(), 600000u);
}

TEST(PhotonMap, EmptyAndMovedMaps) {
    const PhotonMap empty;
    EXPECT_EQ(empty.irradiance(vec3(0.0f), kUp, 10, 1.0f), vec3(0.0f));
    PhotonMap original({photon_at(vec3(0.0f), 1.0f)});
    const vec3 before = original.irradiance(vec3(0.0f), kUp, 5, 1.0f);
    EXPECT_NEAR(before.x, 1.0f / kPi, 1e-6f);
    PhotonMap moved(std::move(original));
    EXPECT_EQ(moved.irradiance(vec3(0.0f), kUp, 5, 1.0f), before);
    PhotonMap assigned;
    assigned = std::move(moved);
    EXPECT_EQ(assigned.irradiance(vec3(0.0f), kUp, 5, 1.0f), before);
}

TEST(PhotonMap, BadArgumentsThrow) {
    const PhotonMap map({photon_at(vec3(0.0f), 1.0f)});
    EXPECT_THROW(map.irradiance(vec3(0.0f), kUp, 0, 1.0f), InvalidArgument);
    EXPECT_THROW(map.irradiance(vec3(0.0f), kUp, 5, 0.0f), InvalidArgument);
    EXPECT_THROW(map.irradiance(vec3(0.0f), kUp, 5, std::nanf("")), InvalidArgument);
    EXPECT_THROW(PhotonMap({photon_at(vec3(0.0f), 1.0f)}, -1.0f), InvalidArgument);
    EXPECT_THROW(PhotonMap({photon_at(vec3(std::nanf(""), 0.0f, 0.0f), 1.0f)}), InvalidArgument);
}

}  // namespace
}  // namespace shgi
