// Photon injection against the analytic SH of uniform radiance fields.
//
// The photons are synthetic (no tracing): the flux a uniform radiance L arriving from a whole
// hemisphere leaves on a rectangle, cosine-distributed (lattice_test_scenes.h). The density
// estimate Φ Y(ω) / max(D_c(ω), f A_c) then has the expectation
//     L_lm = L ∫ Y_lm(ω) received(ω) / max(D_c(ω), f A_c) dω,
// received(ω) the projected area that actually receives from ω. For one plane this is the
// hemisphere projection, except for grazing directions (cos θ < f) where the floor f A_c weighs
// photons down; the expected values below include that, so the comparison is exact up to Monte
// Carlo noise, estimated from independent batches.
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

namespace shgi {
namespace {

// Five standard errors: a false failure has probability ~6e-7 per comparison.
constexpr double kSigmas = 5.0;
constexpr int kBatches = 16;
constexpr int kPhotonsPerBatch = 40000;
// Float sums of 2e4 photons and the quadrature of the expected values stay below this
// (relative to the radiance).
constexpr double kRelativeFloor = 1e-4;

const vec3 kRadiance(1.0f, 2.0f, 0.5f);  // W m^-2 sr^-1

// Mean and standard error of the mean of independent batch results, per float.
struct BatchStats {
    std::vector<double> sum, sum2;
    int batches = 0;

    void add(const std::vector<float>& values) {
        sum.resize(values.size(), 0.0);
        sum2.resize(values.size(), 0.0);
        for (size_t i = 0; i < values.size(); ++i) {
            sum[i] += values[i];
            sum2[i] += double(values[i]) * values[i];
        }
        ++batches;
    }
    double mean(size_t i) const { return sum[i] / batches; }
    double standard_error(size_t i) const {
        const double m = mean(i);
        return std::sqrt(std::max(0.0, sum2[i] / batches - m * m) / (batches - 1));
    }
};

void expect_near_stats(const BatchStats& stats, size_t i, double expected, double scale,
                       const std::string& what) {
    EXPECT_NEAR(stats.mean(i), expected, kSigmas * stats.standard_error(i) + kRelativeFloor * scale)
        << what << ": standard error " << stats.standard_error(i);
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
        for (const auto& [a, b, n, s] :
             {std::tuple(x, y, up, seed), std::tuple(x, y, -up, seed + 1),
              std::tuple(y, z, east, seed + 2), std::tuple(y, z, -east, seed + 3)})
            lattice.inject(test::uniform_field_photons(corner, a, b, n, kRadiance, per_side, s),
                           1.0f);
        stats.add(batch_result(lattice, normals));
    }

    // L ∫ Y(ω) r(ω) dω, r = (|ω_z| + |ω_x|) / max(|ω_z| + |ω_x|, 2f), by quadrature.
    const double f = kMinProjectedFraction;
    const SphereQuadrature rule = sphere_quadrature(256, 512);
    std::array<double, 9> projection{};
    for (size_t k = 0; k < rule.directions.size(); ++k) {
        const glm::dvec3& w = rule.directions[k];
        const double seen = std::fabs(w.z) + std::fabs(w.x);
        const double r = seen / std::max(seen, 2.0 * f);
        float basis[9];
        sh_eval(2, vec3(w), basis);
        for (int i = 0; i < 9; ++i) projection[size_t(i)] += rule.weights[k] * r * basis[i];
    }
    ShRgb expected(2);
    for (int i = 0; i < 9; ++i) expected[i] = float(projection[size_t(i)]) * kRadiance;
    expect_field(stats, expected, normals);
    for (const vec3& n : normals) {
        const vec3 irradiance = sh_irradiance(expected, n);
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(irradiance[ch], kPi * kRadiance[ch], 2e-3 * kPi * kRadiance[ch]);
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
