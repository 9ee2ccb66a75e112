// Photon injection against the analytic SH of uniform radiance fields.
//
// The photons are synthetic (no tracing): the flux a uniform radiance L arriving from a whole
// hemisphere leaves on a rectangle, cosine-distributed (lattice_test_scenes.h). The density
// estimate Φ Y(ω) / max(D_c(ω), f A_c) then has the expectation
//     L_lm = L ∫ Y_lm(ω) received(ω) / max(D_c(ω), f A_c) dω,
// received(ω) the projected area that actually receives from ω. D_c counts the sides photons
// arrived on, so D_c = received whenever the cell's planes are axis-aligned: the projection of L
// over the directions the cell receives from, except for grazing directions (D_c < f A_c) where
// the floor f A_c weighs photons down; the expected values below include that, so the
// comparison is exact up to Monte Carlo noise, estimated from independent batches. Closed rooms
// (every plane lit on its inner side only) and thin panels (lit on both sides) then give π L
// wherever the light is uniform, up to that floor's small bias.
#include "lattice/sh_lattice.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>
#include <tuple>

#include <tbb/global_control.h>

#include "lattice/lattice_test_scenes.h"
#include "render/render_test_scenes.h"
#include "sh/sh_irradiance.h"
#include "sh/sphere_quadrature.h"
#include "support/noise_stats.h"

namespace shgi {
namespace {

using test::kFloorBias;
using testing::BatchStats;

constexpr int kBatches = 16;
constexpr int kPhotonsPerBatch = 40000;
// Float sums of 2e4 photons and the quadrature of the expected values stay below this
// (relative to the radiance).
constexpr double kRelativeFloor = 1e-4;

const vec3 kRadiance(1.0f, 2.0f, 0.5f);  // W m^-2 sr^-1

// Batch mean i within the noise of the batches plus float accumulation (kRelativeFloor of
// `scale`).
void expect_near_stats(const BatchStats& stats, size_t i, double expected, double scale,
                       const std::string& what) {
    testing::expect_within_noise(stats.mean(i), stats.standard_error(i), expected,
                                 kRelativeFloor * scale, what);
}

// The photons of one batch go into one inject() call: the sides they mark apply to all of them
// (a call is one complete estimate, see sh_lattice.h).
void append(std::vector<Photon>& photons, const std::vector<Photon>& more) {
    photons.insert(photons.end(), more.begin(), more.end());
}

// The lattice's coefficients followed by the irradiance at each of `normals`.
std::vector<float> batch_result(const ShLattice& lattice, const std::vector<vec3>& normals) {
    const ShRgb radiance = lattice.cell_radiance(0);
    std::vector<float> result(radiance.data(), radiance.data() + 3 * radiance.num_coefficients());
    for (const vec3& n : normals) {
        const vec3 irradiance = sh_irradiance(radiance, n);
        result.insert(result.end(), {irradiance.x, irradiance.y, irradiance.z});
    }
    return result;
}

void expect_field(const BatchStats& stats, const ShRgb& expected,
                  const std::vector<vec3>& normals) {
    const int n = expected.num_coefficients();
    for (int i = 0; i < n; ++i)
        for (int ch = 0; ch < 3; ++ch)
            expect_near_stats(stats, size_t(3 * i + ch), expected[i][ch], kRadiance[ch],
                              "coefficient " + std::to_string(i) + " channel " +
                                  std::to_string(ch));
    for (size_t k = 0; k < normals.size(); ++k) {
        const vec3 irradiance = sh_irradiance(expected, normals[k]);
        for (int ch = 0; ch < 3; ++ch)
            expect_near_stats(stats, size_t(3 * n) + 3 * k + size_t(ch), irradiance[ch],
                              kPi * kRadiance[ch],
                              "irradiance at normal " + std::to_string(k) + " channel " +
                                  std::to_string(ch));
    }
}

// The expected SH of one cell, L_lm = ∫ Y_lm(ω) L(ω) D(ω) / max(D(ω), f A_c) dω, by quadrature;
// `radiance(ω)` is the incident radiance from ω and `received(ω)` the projected area of the
// cell's surface that receives from ω.
template <typename Radiance, typename Received>
ShRgb expected_projection(Radiance&& radiance, Received&& received, double cell_area) {
    const double floor = kMinProjectedFraction * cell_area;
    const SphereQuadrature rule = sphere_quadrature(256, 512);
    std::array<glm::dvec3, 9> projection{};
    for (size_t k = 0; k < rule.directions.size(); ++k) {
        const glm::dvec3& w = rule.directions[k];
        const double seen = received(w);
        if (seen <= 0.0) continue;
        const glm::dvec3 weighted =
            rule.weights[k] * seen / std::max(seen, floor) * glm::dvec3(radiance(w));
        float basis[9];
        sh_eval(2, vec3(w), basis);
        for (int i = 0; i < 9; ++i) projection[size_t(i)] += weighted * double(basis[i]);
    }
    ShRgb expected(2);
    for (int i = 0; i < 9; ++i) expected[i] = vec3(projection[size_t(i)]);
    return expected;
}

// |E − π L| within the floor's bias, relative to π `bias_scale` (the radiance the floor weighs
// down: the brightest that reaches the cell).
void expect_near_pi_radiance(const vec3& irradiance, const vec3& radiance, const vec3& bias_scale,
                             const std::string& what) {
    for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(irradiance[ch], kPi * radiance[ch], kFloorBias * kPi * bias_scale[ch])
            << what << " channel " << ch
            << ": E / (π L) = " << irradiance[ch] / (kPi * radiance[ch]);
}

// One plane of area A in one cell, lit by uniform L from its hemisphere. Expected: the zonal
// projection L 2π ∫_0^1 Y_l0(μ) min(1, μ/f) dμ (f = kMinProjectedFraction), zero for m ≠ 0, and
// irradiance at the normal within π L f/4 of π L (the floor's bias, seen by L0 only).
TEST(ShLatticeInjection, UniformFieldOnAPlaneGivesTheHemisphereProjection) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(1.0f)}, 1, 2);
    const vec3 corner(0.1f, 0.1f, 0.5f), edge_u(0.8f, 0, 0), edge_v(0, 0.8f, 0), up(0, 0, 1);
    lattice.measure_surfaces(test::committed_scene({test::quad(corner, edge_u, edge_v)}));
    ASSERT_EQ(lattice.cell_count(), 1u);

    const std::vector<vec3> normals = {up};
    BatchStats stats;
    for (int batch = 0; batch < kBatches; ++batch) {
        lattice.clear();
        const std::vector<Photon> photons = test::uniform_field_photons(
            corner, edge_u, edge_v, up, kRadiance, kPhotonsPerBatch, uint64_t(batch));
        ASSERT_EQ(lattice.inject(photons, 1.0f), uint64_t(kPhotonsPerBatch));
        stats.add(batch_result(lattice, normals));
    }

    const double f = kMinProjectedFraction;
    const ZhCoeffs grazing = project_zonal([f](double mu) { return mu / f; }, 0.0, f, 8);
    const ZhCoeffs rest = project_zonal([](double) { return 1.0; }, f, 1.0, 8);
    ShRgb expected(2);
    for (int l = 0; l <= 2; ++l) expected[sh_index(l, 0)] = (grazing[l] + rest[l]) * kRadiance;
    expect_field(stats, expected, normals);
    const vec3 expected_irradiance = sh_irradiance(expected, up);
    for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(expected_irradiance[ch], kPi * kRadiance[ch], kPi * kRadiance[ch] * f / 4.0);
}

// A floor and a wall meeting in one cell, both open on both sides to a uniform field L: every
// side of every plane receives π L. D_c(ω) = A (|ω_z| + |ω_x|) is exactly the area receiving
// from ω, so the reconstruction is the constant L (up to the floor near ±Y, where
// |ω_z| + |ω_x| < 2f) and the irradiance is π L at both normals.
TEST(ShLatticeInjection, UniformFieldOnTwoPlanesInACellGivesPiLAtBothNormals) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(1.0f)}, 1, 2);
    const vec3 corner(0.2f), x(0.7f, 0, 0), y(0, 0.7f, 0), z(0, 0, 0.7f);
    lattice.measure_surfaces(
        test::committed_scene({test::quad(corner, x, y), test::quad(corner, y, z)}));
    const vec3 up(0, 0, 1), east(1, 0, 0);

    const std::vector<vec3> normals = {up, east};
    BatchStats stats;
    for (int batch = 0; batch < kBatches; ++batch) {
        lattice.clear();
        const int per_side = kPhotonsPerBatch / 4;
        const uint64_t seed = 100 + 4 * uint64_t(batch);
        std::vector<Photon> photons;
        for (const auto& [a, b, n, s] :
             {std::tuple(x, y, up, seed), std::tuple(x, y, -up, seed + 1),
              std::tuple(y, z, east, seed + 2), std::tuple(y, z, -east, seed + 3)})
            append(photons, test::uniform_field_photons(corner, a, b, n, kRadiance, per_side, s));
        lattice.inject(photons, 1.0f);
        stats.add(batch_result(lattice, normals));
    }

    // Per unit area: received(ω) = |ω_z| + |ω_x|, A_c = 2.
    const ShRgb expected = expected_projection(
        [](const glm::dvec3&) { return kRadiance; },
        [](const glm::dvec3& w) { return std::fabs(w.z) + std::fabs(w.x); }, 2.0);
    expect_field(stats, expected, normals);
    for (const vec3& n : normals) {
        const vec3 irradiance = sh_irradiance(expected, n);
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(irradiance[ch], kPi * kRadiance[ch], 2e-3 * kPi * kRadiance[ch]);
    }
}

// A room's edge in one cell: floor and wall lit by a uniform L on their inner sides only (+Z and
// +X). A photon reaching the floor while travelling away from the wall could not have reached
// the wall's inner side, so D_c(ω) = A (max(0, ω_z) + max(0, ω_x)) and the cell holds L over the
// directions either plane receives from: π L at both normals. (Counting both sides of both
// planes, D_c = A (|ω_z| + |ω_x|), gave 0.81 π L.)
TEST(ShLatticeInjection, RoomEdgeLitOnItsInnerSidesGivesPiLAtBothNormals) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(1.0f)}, 1, 2);
    const vec3 corner(0.2f), x(0.7f, 0, 0), y(0, 0.7f, 0), z(0, 0, 0.7f);
    lattice.measure_surfaces(
        test::committed_scene({test::quad(corner, x, y), test::quad(corner, y, z)}));
    const vec3 up(0, 0, 1), east(1, 0, 0);

    const std::vector<vec3> normals = {up, east};
    BatchStats stats;
    for (int batch = 0; batch < kBatches; ++batch) {
        lattice.clear();
        const uint64_t seed = 300 + 2 * uint64_t(batch);
        std::vector<Photon> photons;
        for (const auto& [a, b, n, s] :
             {std::tuple(x, y, up, seed), std::tuple(y, z, east, seed + 1)})
            append(photons, test::uniform_field_photons(corner, a, b, n, kRadiance,
                                                        kPhotonsPerBatch / 2, s));
        lattice.inject(photons, 1.0f);
        ASSERT_EQ(lattice.receiving_sides(0),
                  ShLattice::side_bit(2, true) | ShLattice::side_bit(0, true));
        stats.add(batch_result(lattice, normals));
    }

    const ShRgb expected = expected_projection(
        [](const glm::dvec3&) { return kRadiance; },
        [](const glm::dvec3& w) { return std::max(0.0, w.z) + std::max(0.0, w.x); }, 2.0);
    expect_field(stats, expected, normals);
    expect_near_pi_radiance(sh_irradiance(expected, up), kRadiance, kRadiance, "floor");
    expect_near_pi_radiance(sh_irradiance(expected, east), kRadiance, kRadiance, "wall");
}

// A thin panel lit from above by L_top and from below by L_bottom: both sides receive, and each
// side's irradiance is π times its own radiance (the SH is L_top over the upper hemisphere and
// L_bottom over the lower one, whose L1 and L2 bands reconstruct hemispherical irradiance).
TEST(ShLatticeInjection, ThinPanelLitFromBothSidesGivesEachSideItsIrradiance) {
    ShLattice lattice(Bounds3{vec3(0.0f), vec3(1.0f)}, 1, 2);
    const vec3 corner(0.1f, 0.1f, 0.5f), edge_u(0.8f, 0, 0), edge_v(0, 0.8f, 0), up(0, 0, 1);
    lattice.measure_surfaces(test::committed_scene({test::quad(corner, edge_u, edge_v)}));
    const vec3 top = kRadiance, bottom(0.25f, 3.0f, 1.5f);

    const std::vector<vec3> normals = {up, -up};
    BatchStats stats;
    for (int batch = 0; batch < kBatches; ++batch) {
        lattice.clear();
        const uint64_t seed = 500 + 2 * uint64_t(batch);
        std::vector<Photon> photons = test::uniform_field_photons(
            corner, edge_u, edge_v, up, top, kPhotonsPerBatch / 2, seed);
        append(photons, test::uniform_field_photons(corner, edge_u, edge_v, -up, bottom,
                                                    kPhotonsPerBatch / 2, seed + 1));
        lattice.inject(photons, 1.0f);
        ASSERT_EQ(lattice.receiving_sides(0),
                  ShLattice::side_bit(2, true) | ShLattice::side_bit(2, false));
        stats.add(batch_result(lattice, normals));
    }

    // Per unit area: received(ω) = |ω_z|, A_c = 1.
    const ShRgb expected = expected_projection(
        [&](const glm::dvec3& w) { return w.z > 0.0 ? top : bottom; },
        [](const glm::dvec3& w) { return std::fabs(w.z); }, 1.0);
    expect_field(stats, expected, normals);
    // The floor removes grazing flux from both sides, and its bias reaches the other side's
    // irradiance through the L0 and L2 bands: bounded relative to the brighter side.
    const vec3 brighter = glm::max(top, bottom);
    expect_near_pi_radiance(sh_irradiance(expected, up), top, brighter, "top side");
    expect_near_pi_radiance(sh_irradiance(expected, -up), bottom, brighter, "bottom side");
}

// A closed room: the box [-1, 1]^3 seen from inside, every wall lit on its inner side by a
// uniform L. Points at face centres, next to edges and next to corners (whose cells hold two or
// three walls, each receiving on one side) all get π L, sampled either way. (Counting both sides
// of every wall gave 0.81 π L next to edges and 0.72 π L in corner cells.)
TEST(ShLatticeInjection, ClosedBoxInAUniformFieldGivesPiLAtFacesEdgesAndCorners) {
    const Scene scene = test::committed_scene({test::inward_box(1.0f)});
    ShLattice lattice(scene.bounds(), 4, 2);
    lattice.measure_surfaces(scene);
    constexpr float kNormalOffset = 0.25f;  // cells, PhotonLatticeSettings' default

    struct Wall {
        vec3 corner, edge_u, edge_v, normal;  // normal into the box
    };
    std::vector<Wall> walls;
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.0f, 1.0f}) {
            vec3 u(0.0f), v(0.0f), normal(0.0f);
            u[(axis + 1) % 3] = 2.0f;
            v[(axis + 2) % 3] = 2.0f;
            normal[axis] = -side;
            walls.push_back({-normal - 0.5f * (u + v), u, v, normal});
        }
    // In-wall coordinates: a face centre, two points 0.1 m from an edge, two 0.1 m from a corner.
    const vec2 in_wall[] = {{0.1f, -0.2f}, {0.9f, 0.2f}, {-0.3f, -0.9f}, {0.9f, 0.9f},
                            {-0.9f, 0.9f}};
    const auto sampled_irradiance = [&]() {
        std::vector<float> result;
        for (const Wall& wall : walls)
            for (const vec2& uv : in_wall) {
                const vec3 p = -wall.normal + 0.5f * (uv.x * wall.edge_u + uv.y * wall.edge_v);
                for (const ShRgb& radiance :
                     {lattice.sample_cubic(p, wall.normal, kNormalOffset),
                      lattice.sample_trilinear(p, wall.normal, kNormalOffset)}) {
                    const vec3 irradiance = sh_irradiance(radiance, wall.normal);
                    result.insert(result.end(), {irradiance.x, irradiance.y, irradiance.z});
                }
            }
        return result;
    };

    BatchStats stats;
    for (int batch = 0; batch < kBatches; ++batch) {
        lattice.clear();
        std::vector<Photon> photons;
        for (size_t w = 0; w < walls.size(); ++w)
            append(photons, test::uniform_field_photons(walls[w].corner, walls[w].edge_u,
                                                        walls[w].edge_v, walls[w].normal,
                                                        kRadiance, kPhotonsPerBatch,
                                                        700 + 6 * uint64_t(batch) + w));
        lattice.inject(photons, 1.0f);
        stats.add(sampled_irradiance());
    }
    EXPECT_EQ(lattice.receiving_sides(0), ShLattice::side_bit(0, true) |
                                              ShLattice::side_bit(1, true) |
                                              ShLattice::side_bit(2, true));

    const char* const kPlaces[] = {"face centre", "edge", "edge", "corner", "corner"};
    size_t i = 0;
    for (size_t w = 0; w < walls.size(); ++w)
        for (const char* place : kPlaces)
            for (const char* method : {"cubic", "trilinear"})
                for (int ch = 0; ch < 3; ++ch, ++i) {
                    const double expected = kPi * kRadiance[ch];
                    testing::expect_within_noise(
                        stats.mean(i), stats.standard_error(i), expected, kFloorBias * expected,
                        "wall " + std::to_string(w) + ", " + place + ", " + method +
                            ", channel " + std::to_string(ch) +
                            ": E / (π L) = " + std::to_string(stats.mean(i) / expected));
                }
}

// Photons anywhere in and around a box: those outside the lattice or in cells without surface
// are skipped, the rest counted; the sums do not depend on the thread count; scale multiplies.
TEST(ShLatticeInjection, SkipsPhotonsWithoutSurfaceAndIsIndependentOfThreadCount) {
    const Scene scene = test::committed_scene({test::inward_box(1.0f)});
    Pcg32 rng(21, 0);
    std::vector<Photon> photons(300000);
    for (Photon& photon : photons) {
        photon.position = 2.4f * vec3(rng.next_float(), rng.next_float(), rng.next_float()) - 1.2f;
        photon.power = vec3(rng.next_float(), rng.next_float(), rng.next_float());
        photon.direction = sample_uniform_sphere(rng.next_vec2());
        photon.normal = photon.direction;
    }
    const auto inject = [&](int threads, float scale, uint64_t* injected) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        ShLattice lattice(scene.bounds(), 8, 2);
        lattice.measure_surfaces(scene);
        *injected = lattice.inject(photons, scale);
        return lattice;
    };
    uint64_t injected_1 = 0, injected_2 = 0, injected_scaled = 0;
    const ShLattice one = inject(1, 1.0f, &injected_1);
    const ShLattice two = inject(2, 1.0f, &injected_2);
    const ShLattice scaled = inject(2, 2.0f, &injected_scaled);

    uint64_t expected = 0;
    for (const Photon& photon : photons) {
        const ivec3 cell = one.cell_of(photon.position);
        expected += cell.x >= 0 && one.surface_area(one.cell_index(cell)) > 0.0f;
    }
    EXPECT_EQ(injected_1, expected);
    EXPECT_EQ(injected_2, expected);
    EXPECT_GT(expected, 0u);
    EXPECT_LT(expected, photons.size());
    EXPECT_EQ(one.coefficients(), two.coefficients());
    for (size_t i = 0; i < one.coefficients().size(); ++i)
        ASSERT_EQ(scaled.coefficients()[i], 2.0f * one.coefficients()[i]);
    const ivec3 inside_cell(3, 3, 3);  // no surface in the middle of the box
    ASSERT_EQ(one.surface_area(one.cell_index(inside_cell)), 0.0f);
    EXPECT_EQ(one.cell_radiance(one.cell_index(inside_cell))[0], vec3(0.0f));
}

}  // namespace
}  // namespace shgi
