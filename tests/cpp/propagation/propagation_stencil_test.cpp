// The propagation stencils against their closed forms (seed 003 Appendix A) and one step's energy
// balance: the faces of each stencil tile the sphere (solid angles summing to 4π), the solid
// angles are the exact values (not the 0.4234413544 copied into many shaders), and a step moves
// all of a cell's flux to its neighbours — exactly without clamping, exactly with clamp-then-
// rescale, and with a gain when clamping alone (the error the rescale corrects).
#include "propagation/propagation_stencil.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "sh/sh_basis.h"
#include "util/error.h"
#include "util/math.h"

namespace shgi {
namespace {

// Solid angles are computed in double: their sum meets 4π to rounding.
constexpr double kSolidAngleSumTolerance = 1e-6;
// Appendix A's values are given to 7 digits.
constexpr double kPublishedDigits = 5e-8;
// A step's flux is summed in float over ~10³ cells of ~10 coefficients.
constexpr double kFluxTolerance = 1e-5;

double total_solid_angle(PropagationStencil stencil) {
    double sum = 0.0;
    for (const PropagationFace& face : propagation_faces(stencil)) sum += face.solid_angle;
    return sum;
}

TEST(PropagationStencil, FacesTileTheSphere) {
    EXPECT_EQ(propagation_faces(PropagationStencil::Faces6).size(), 30u);
    EXPECT_EQ(propagation_faces(PropagationStencil::Neighbours26).size(), 54u);
    EXPECT_NEAR(total_solid_angle(PropagationStencil::Faces6), 4.0 * kPiD,
                kSolidAngleSumTolerance);
    EXPECT_NEAR(total_solid_angle(PropagationStencil::Neighbours26), 4.0 * kPiD,
                kSolidAngleSumTolerance);
}

TEST(PropagationStencil, ExactSolidAngles) {
    // LPV, destination (0, 0, 1): the front face at z = 1.5 and a side face at x = 0.5.
    for (const PropagationFace& face : propagation_faces(PropagationStencil::Faces6)) {
        if (face.offset != ivec3(0, 0, 1)) continue;
        const double expected = face.normal.z > 0.0f ? 0.4006697 : 0.4234314;
        EXPECT_NEAR(face.solid_angle, expected, kPublishedDigits)
            << "normal " << face.normal.x << " " << face.normal.y << " " << face.normal.z;
        EXPECT_GT(std::fabs(face.solid_angle - 0.4234413544), 9e-6) << "the shaders' value";
    }
    // HOLPV: face-, edge- and corner-cell faces by how many offset components are non-zero.
    const double expected[4] = {0.0, 0.4006697, 0.2506920, 0.1727394};
    for (const PropagationFace& face : propagation_faces(PropagationStencil::Neighbours26)) {
        const int nonzero = (face.offset.x != 0) + (face.offset.y != 0) + (face.offset.z != 0);
        EXPECT_NEAR(face.solid_angle, expected[nonzero], kPublishedDigits) << nonzero;
    }
    // The formula against a direct case: a square of side 2a at distance d seen from its axis
    // subtends 4 asin(a² / (a² + d²)).
    const double a = 0.7, d = 1.3;
    EXPECT_NEAR(rectangle_solid_angle(-a, a, -a, a, d), 4.0 * std::asin(a * a / (a * a + d * d)),
                1e-12);
}

// Faces point away from the source: ω_f from the source centre to the face, the normal outwards.
TEST(PropagationStencil, FacesLookOutward) {
    for (PropagationStencil stencil :
         {PropagationStencil::Faces6, PropagationStencil::Neighbours26}) {
        for (const PropagationFace& face : propagation_faces(stencil)) {
            EXPECT_NEAR(glm::length(face.direction), 1.0f, 1e-6f);
            EXPECT_GT(glm::dot(face.direction, face.normal), 0.0f);
            EXPECT_GE(glm::dot(vec3(face.offset), face.normal), 0.0f);
        }
    }
}

struct StepCase {
    PropagationStencil stencil;
    int order;
};

// Total flux of a volume: Σ_c √(4π) c₀.
vec3 volume_flux(const ShVolume& volume) {
    vec3 sum(0.0f);
    for (size_t c = 0; c < volume.cell_count(); ++c) sum += cell_flux(volume.cell_data(c));
    return sum;
}

// A 5³ volume with one cosine lobe (and a dimmer one along another normal) in its centre cell.
ShVolume lobe_in_centre(int order) {
    ShVolume volume(vec3(0.0f), 1.0f, ivec3(5), order);
    float* centre = volume.cell_data(volume.cell_index(ivec3(2)));
    add_cosine_lobe(centre, order, glm::normalize(vec3(0.3f, -0.5f, 0.8f)), vec3(1.0f, 2.0f, 0.5f));
    add_cosine_lobe(centre, order, glm::normalize(vec3(-0.9f, 0.1f, 0.2f)), vec3(0.4f));
    return volume;
}

// Relative flux change of one step from the centre cell (no light reaches the volume's sides).
vec3 one_step_gain(const StepCase& c, LobeClamp clamp,
                   Reinjection reinjection = Reinjection::FaceNormal) {
    const ShVolume source = lobe_in_centre(c.order);
    ShVolume destination(source.origin(), source.cell_size(), source.counts(), c.order);
    PropagationStep(c.stencil, c.order, clamp, reinjection)(source, destination);
    return volume_flux(destination) / volume_flux(source) - 1.0f;
}

// First moment ∫ I(ω) ω dω of a volume's first channel, summed over its cells: only band 1
// contributes, Y_i(ω) = a e_i·ω, and ∫ a (e_i·ω) ω dω = (4π/3) a e_i = (4π/3) (Y_i(x̂), Y_i(ŷ), Y_i(ẑ)).
glm::dvec3 volume_moment(const ShVolume& volume) {
    float axes[3][9];
    for (int j = 0; j < 3; ++j) {
        vec3 axis(0.0f);
        axis[j] = 1.0f;
        sh_eval(volume.order(), axis, axes[j]);
    }
    glm::dvec3 moment(0.0);
    for (size_t c = 0; c < volume.cell_count(); ++c) {
        const float* cell = volume.cell_data(c);
        for (int i = 1; i < 4; ++i)
            for (int j = 0; j < 3; ++j)
                moment[j] += 4.0 * kPiD / 3.0 * double(cell[3 * i]) * double(axes[j][i]);
    }
    return moment;
}

// The share of the source's first moment (along it) one unclamped step keeps.
double one_step_momentum(const StepCase& c, Reinjection reinjection) {
    const ShVolume source = lobe_in_centre(c.order);
    ShVolume destination(source.origin(), source.cell_size(), source.counts(), c.order);
    PropagationStep(c.stencil, c.order, LobeClamp::None, reinjection)(source, destination);
    const glm::dvec3 before = volume_moment(source), after = volume_moment(destination);
    return glm::dot(after, before) / glm::dot(before, before);
}

TEST(PropagationStep, UnclampedAndRescaledStepsConserveFlux) {
    for (const StepCase& c : {StepCase{PropagationStencil::Faces6, 1},
                              StepCase{PropagationStencil::Faces6, 2},
                              StepCase{PropagationStencil::Neighbours26, 1},
                              StepCase{PropagationStencil::Neighbours26, 2}}) {
        for (LobeClamp clamp : {LobeClamp::None, LobeClamp::Rescaled}) {
            const vec3 gain = one_step_gain(c, clamp);
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(gain[ch], 0.0, kFluxTolerance)
                    << "stencil " << int(c.stencil) << " order " << c.order << " clamp "
                    << int(clamp) << " channel " << ch;
        }
    }
}

// Re-injected along its travel direction, the light keeps its flux like the seed's lobes do,
// and its first moment too (the stencils integrate I(ω) ω exactly); the seed's cosine lobes along
// the face normals keep about half of it: every face re-emits like a Lambertian surface, and the
// light random-walks (diffusion) instead of moving on. Measured share kept by one face-normal
// step (lobe_in_centre, first channel): printed.
TEST(PropagationStep, TravelReinjectionKeepsFluxAndMomentum) {
    for (const StepCase& c : {StepCase{PropagationStencil::Faces6, 1},
                              StepCase{PropagationStencil::Faces6, 2},
                              StepCase{PropagationStencil::Neighbours26, 1},
                              StepCase{PropagationStencil::Neighbours26, 2}}) {
        for (Reinjection reinjection :
             {Reinjection::TravelDirection, Reinjection::WindowedTravelDirection}) {
            for (LobeClamp clamp : {LobeClamp::None, LobeClamp::Rescaled}) {
                const vec3 gain = one_step_gain(c, clamp, reinjection);
                for (int ch = 0; ch < 3; ++ch)
                    EXPECT_NEAR(gain[ch], 0.0, kFluxTolerance)
                        << "stencil " << int(c.stencil) << " order " << c.order << " clamp "
                        << int(clamp) << " channel " << ch << " re-injection "
                        << int(reinjection);
            }
            // The window leaves band 1, so the first moment, as it is.
            EXPECT_NEAR(one_step_momentum(c, reinjection), 1.0, kFluxTolerance)
                << "stencil " << int(c.stencil) << " order " << c.order << " re-injection "
                << int(reinjection);
        }
        const double travel = one_step_momentum(c, Reinjection::TravelDirection);
        const double normal = one_step_momentum(c, Reinjection::FaceNormal);
        std::printf("stencil %d order %d: first moment kept by one unclamped step: face normal "
                    "%.4f, travel direction %.6f\n",
                    int(c.stencil), c.order, normal, travel);
        EXPECT_NEAR(travel, 1.0, kFluxTolerance) << "stencil " << int(c.stencil) << " order "
                                                 << c.order;
        EXPECT_LT(normal, 0.75) << "stencil " << int(c.stencil) << " order " << c.order;
    }
}

// The re-injected beam's light on two surfaces: one ahead of it facing it, one behind it facing
// along it (the surface the light left, whose exact irradiance from it is 0). Light travelling
// along ω with intensity I lights a surface of normal n with E(n) = ∫ I(ω) max(0, −n·ω) dω =
// Σ_i Â_l c_i Y_i(−n) (the clamped cosine's bands π, 2π/3, π/4). The plain L2 beam lights the
// surface behind with 1/17 of the facing surface's irradiance (its back lobe); windowed (band 2
// × 4/5) with none, its flux and first moment (bands 0 and 1) unchanged, and a surface the light
// passes edge-on gets more; at L1 the window does nothing (no band 2).
TEST(PropagationStep, WindowedBeamLightsNothingBehindIt) {
    constexpr double kBand[3] = {kPiD, 2.0 * kPiD / 3.0, kPiD / 4.0};
    constexpr int kBandOf[9] = {0, 1, 1, 1, 2, 2, 2, 2, 2};
    const auto irradiance = [&](const float* beam, int order, const vec3& normal) {
        float y[9];
        sh_eval(order, -normal, y);
        double e = 0.0;
        for (int i = 0; i < sh_num_coefficients(order); ++i)
            e += kBand[kBandOf[i]] * double(beam[i]) * double(y[i]);
        return e;
    };
    for (const vec3& d : {vec3(0.0f, 0.0f, 1.0f), glm::normalize(vec3(1.0f, -2.0f, 2.0f))}) {
        float plain[9], windowed[9], plain1[9], windowed1[9];
        reinjected_beam(2, Reinjection::TravelDirection, d, plain);
        reinjected_beam(2, Reinjection::WindowedTravelDirection, d, windowed);
        const double front = irradiance(plain, 2, -d);
        EXPECT_NEAR(irradiance(plain, 2, d) / front, 1.0 / 17.0, 1e-6);
        EXPECT_NEAR(irradiance(windowed, 2, d) / front, 0.0, 1e-6);
        EXPECT_NEAR(irradiance(windowed, 2, -d) / front, 4.0 / 4.25, 1e-6);
        // The price: a surface the light passes edge-on gets 1/8 of the facing irradiance
        // (exactly 0), against 1/11.3 (0.375 / 4.25) unwindowed.
        const vec3 edge_on = glm::normalize(glm::cross(d, vec3(1.0f, 0.0f, 0.0f)));
        EXPECT_NEAR(irradiance(plain, 2, edge_on) / front, 0.375 / 4.25, 1e-6);
        EXPECT_NEAR(irradiance(windowed, 2, edge_on) / irradiance(windowed, 2, -d), 1.0 / 8.0,
                    1e-6);
        for (int i = 0; i < 4; ++i) EXPECT_EQ(windowed[i], plain[i]) << "coefficient " << i;
        for (int i = 4; i < 9; ++i)
            EXPECT_FLOAT_EQ(windowed[i], kBeamBand2Window * plain[i]) << "coefficient " << i;
        reinjected_beam(1, Reinjection::TravelDirection, d, plain1);
        reinjected_beam(1, Reinjection::WindowedTravelDirection, d, windowed1);
        for (int i = 0; i < 4; ++i) EXPECT_EQ(windowed1[i], plain1[i]) << "coefficient " << i;
    }
    float beam[9];
    EXPECT_THROW(reinjected_beam(2, Reinjection::FaceNormal, vec3(0.0f, 0.0f, 1.0f), beam),
                 InvalidArgument);
}

// Clamping alone makes energy: the L1 lobe's negative back (−π/8 of its π) sampled at zero.
// The continuous gain is 12.5%; the stencils sample it at 30 or 54 directions.
TEST(PropagationStep, ClampingAloneGainsEnergy) {
    for (PropagationStencil stencil :
         {PropagationStencil::Faces6, PropagationStencil::Neighbours26}) {
        ShVolume source(vec3(0.0f), 1.0f, ivec3(3), 1);
        add_cosine_lobe(source.cell_data(source.cell_index(ivec3(1))), 1, vec3(0.0f, 0.0f, 1.0f),
                        vec3(1.0f));
        ShVolume destination(source.origin(), 1.0f, source.counts(), 1);
        PropagationStep(stencil, 1, LobeClamp::Clamped)(source, destination);
        const float gain = volume_flux(destination).x / volume_flux(source).x - 1.0f;
        EXPECT_GT(gain, 0.05f) << "stencil " << int(stencil);
        EXPECT_LT(gain, 0.2f) << "stencil " << int(stencil);
    }
}

TEST(PropagationStep, CosineLobeHoldsItsFlux) {
    for (int order : {1, 2}) {
        std::vector<float> cell(size_t(3 * sh_num_coefficients(order)), 0.0f);
        add_cosine_lobe(cell.data(), order, glm::normalize(vec3(1.0f, 2.0f, -2.0f)),
                        vec3(3.0f, 1.0f, 0.5f));
        const vec3 flux = cell_flux(cell.data());
        EXPECT_NEAR(flux.x, 3.0f, 1e-6f);
        EXPECT_NEAR(flux.y, 1.0f, 1e-6f);
        EXPECT_NEAR(flux.z, 0.5f, 1e-6f);
    }
}

// How far a step carries light (propagation_speed, what PropagationSettings.distance counts
// in): a beam propagated unclamped in empty space with the travel re-injection, which keeps its
// first moment, has its flux-weighted centre move propagation_speed cells along it every step,
// along an axis and a slant alike, at L1 and L2. Face-normal re-injection keeps only part of the
// moment, so its light slows step by step (printed).
TEST(PropagationStep, LightMovesTheStencilsSpeedPerStep) {
    EXPECT_NEAR(propagation_speed(PropagationStencil::Faces6), 0.9146, 1e-4);
    EXPECT_NEAR(propagation_speed(PropagationStencil::Neighbours26), 1.4154, 1e-4);
    constexpr int kSide = 25, kSteps = 8;
    for (const StepCase& c : {StepCase{PropagationStencil::Faces6, 1},
                              StepCase{PropagationStencil::Faces6, 2},
                              StepCase{PropagationStencil::Neighbours26, 1},
                              StepCase{PropagationStencil::Neighbours26, 2}}) {
        const double speed = propagation_speed(c.stencil);
        for (const vec3& direction : {vec3(1.0f, 0.0f, 0.0f),
                                      glm::normalize(vec3(1.0f, -2.0f, 3.0f))}) {
            for (Reinjection reinjection :
                 {Reinjection::TravelDirection, Reinjection::FaceNormal}) {
                ShVolume ping(vec3(0.0f), 1.0f, ivec3(kSide), c.order);
                float basis[9];
                sh_eval(c.order, direction, basis);
                float* centre = ping.cell_data(ping.cell_index(ivec3(kSide / 2)));
                for (int i = 0; i < sh_num_coefficients(c.order); ++i) centre[3 * i] = basis[i];
                ShVolume pong = ping;
                const PropagationStep step(c.stencil, c.order, LobeClamp::None, reinjection);
                const auto centroid = [](const ShVolume& volume) {
                    glm::dvec3 sum(0.0);
                    double flux = 0.0;
                    for (size_t k = 0; k < volume.cell_count(); ++k) {
                        const double f = double(cell_flux(volume.cell_data(k)).x);
                        sum += f * glm::dvec3(volume.cell_at(k));
                        flux += f;
                    }
                    return sum / flux;
                };
                const glm::dvec3 start = centroid(ping);
                double moved = 0.0;
                for (int k = 1; k <= kSteps; ++k) {
                    step(ping, pong);
                    std::swap(ping, pong);
                    moved = glm::dot(centroid(ping) - start, glm::dvec3(direction));
                    if (reinjection == Reinjection::TravelDirection) {
                        EXPECT_NEAR(moved, k * speed, 1e-3 * k)
                            << "stencil " << int(c.stencil) << " order " << c.order << " step "
                            << k;
                        EXPECT_NEAR(glm::length(centroid(ping) - start), k * speed, 1e-3 * k);
                    }
                }
                std::printf("stencil %d, order %d, %s: after %d steps the light moved %.3f cells "
                            "(%.4f a step)\n",
                            int(c.stencil), c.order,
                            reinjection == Reinjection::TravelDirection ? "travel" : "face normal",
                            kSteps, moved, moved / kSteps);
            }
        }
    }
}

}  // namespace
}  // namespace shgi
