// PrincipledBsdf: energy (sampled albedo <= 1 where Cycles' closures conserve energy),
// reciprocity of the reflection lobes, and sample/pdf/eval consistency: the sampled estimator
// E[f cos / pdf] must equal the quadrature of f cos, and the pdf must integrate to the fraction
// of valid samples. The fast Fresnel and Smith G1 forms are checked against the textbook ones.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "render/bsdf.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {
namespace {

constexpr int kSamples = 200000;
// Quadrature grid over the sphere in (cos theta, phi): midpoint rule, error ~1e-3 for the
// smooth lobes used here (roughness >= 0.3).
constexpr int kThetaSteps = 400, kPhiSteps = 800;
// Monte Carlo estimates with kSamples samples and weights of order 1: 5 sigma < 0.01.
constexpr float kMonteCarloTolerance = 0.01f;

Material make_material(float metallic, float transmission, float roughness) {
    Material material;
    material.base_color = vec3(1.0f);
    material.metallic = metallic;
    material.transmission = transmission;
    material.roughness = roughness;
    material.ior = 1.5f;
    material.diffuse_model = DiffuseModel::Lambert;
    return material;
}

vec3 direction_from_angle(float theta) { return vec3(std::sin(theta), 0.0f, std::cos(theta)); }

struct Estimates {
    vec3 sampled_albedo{0.0f};
    float valid_fraction = 0.0f;
};

Estimates sample_estimates(const PrincipledBsdf& bsdf, const vec3& wo) {
    Pcg32 rng(1, 2);
    Estimates e;
    int valid = 0;
    for (int i = 0; i < kSamples; ++i) {
        BsdfSample s;
        const float u_lobe = rng.next_float();
        const vec2 u = rng.next_vec2();
        if (!bsdf.sample(wo, u_lobe, u, &s)) continue;
        e.sampled_albedo += s.weight;
        ++valid;
    }
    e.sampled_albedo /= float(kSamples);
    e.valid_fraction = float(valid) / float(kSamples);
    return e;
}

// Integral over the sphere of eval (f cos) and of the pdf.
void quadrature(const PrincipledBsdf& bsdf, const vec3& wo, vec3* albedo, float* pdf_integral) {
    const double cell = (2.0 / kThetaSteps) * (kTwoPi / kPhiSteps);
    glm::dvec3 sum(0.0);
    double pdf_sum = 0.0;
    for (int i = 0; i < kThetaSteps; ++i) {
        const float cos_theta = -1.0f + 2.0f * (float(i) + 0.5f) / kThetaSteps;
        const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
        for (int j = 0; j < kPhiSteps; ++j) {
            const vec3 wi = spherical_direction(sin_theta, cos_theta,
                                                kTwoPi * (float(j) + 0.5f) / kPhiSteps);
            sum += glm::dvec3(bsdf.eval(wo, wi).total());
            pdf_sum += bsdf.pdf(wo, wi);
        }
    }
    *albedo = vec3(sum * cell);
    *pdf_integral = float(pdf_sum * cell);
}

struct Case {
    const char* name;
    float metallic, transmission, roughness;
    PrincipledModel model = PrincipledModel::V1;
    MicrofacetDistribution distribution = MicrofacetDistribution::GGX;
    PathOrigin origin = PathOrigin::Camera;
};

class BsdfConsistency : public ::testing::TestWithParam<Case> {};

TEST_P(BsdfConsistency, SampledWeightsMatchQuadratureAndPdfIntegratesToValidFraction) {
    const Case c = GetParam();
    for (float theta : {0.2f, 0.8f, 1.3f}) {
        const vec3 wo = direction_from_angle(theta);
        Material material = make_material(c.metallic, c.transmission, c.roughness);
        material.principled_model = c.model;
        material.distribution = c.distribution;
        const PrincipledBsdf bsdf(material, vec3(1.0f), false, wo.z, c.origin);
        const Estimates e = sample_estimates(bsdf, wo);
        vec3 albedo;
        float pdf_integral;
        quadrature(bsdf, wo, &albedo, &pdf_integral);
        EXPECT_NEAR(e.sampled_albedo.x, albedo.x, kMonteCarloTolerance) << c.name << " " << theta;
        EXPECT_NEAR(pdf_integral, e.valid_fraction, kMonteCarloTolerance) << c.name << " " << theta;
        if (c.metallic == 1.0f || c.transmission == 1.0f) {
            EXPECT_LE(albedo.x, 1.0f + kMonteCarloTolerance) << c.name << " " << theta;
        }
    }
}

INSTANTIATE_TEST_SUITE_P(Lobes, BsdfConsistency,
                         ::testing::Values(Case{"metal_rough", 1.0f, 0.0f, 0.5f},
                                           Case{"metal_glossy", 1.0f, 0.0f, 0.3f},
                                           Case{"plastic", 0.0f, 0.0f, 0.4f},
                                           Case{"rough_glass", 0.0f, 1.0f, 0.5f},
                                           Case{"plastic_v2", 0.0f, 0.0f, 0.4f,
                                                PrincipledModel::V2,
                                                MicrofacetDistribution::MultiscatterGGX},
                                           Case{"plastic_v2_from_light", 0.0f, 0.0f, 0.4f,
                                                PrincipledModel::V2,
                                                MicrofacetDistribution::MultiscatterGGX,
                                                PathOrigin::Light},
                                           Case{"metal_v2", 1.0f, 0.0f, 0.5f,
                                                PrincipledModel::V2,
                                                MicrofacetDistribution::MultiscatterGGX},
                                           Case{"rough_glass_v2", 0.0f, 1.0f, 0.5f,
                                                PrincipledModel::V2}),
                         [](const auto& test_info) { return std::string(test_info.param.name); });

TEST(Bsdf, LambertAlbedoIsBaseColor) {
    Material material = make_material(0.0f, 0.0f, 0.5f);
    material.specular = 0.0f;
    const vec3 wo = direction_from_angle(0.7f);
    const PrincipledBsdf bsdf(material, vec3(0.6f), false, wo.z);
    vec3 albedo;
    float pdf_integral;
    quadrature(bsdf, wo, &albedo, &pdf_integral);
    EXPECT_NEAR(albedo.x, 0.6f, 2e-3f);
    EXPECT_NEAR(pdf_integral, 1.0f, 2e-3f);
}

TEST(Bsdf, ReflectionIsReciprocal) {
    for (DiffuseModel model : {DiffuseModel::Lambert, DiffuseModel::Principled}) {
        Material material = make_material(0.3f, 0.0f, 0.4f);
        material.diffuse_model = model;
        Pcg32 rng(3, 4);
        for (int i = 0; i < 100; ++i) {
            const vec3 a = sample_uniform_hemisphere(rng.next_vec2());
            const vec3 b = sample_uniform_hemisphere(rng.next_vec2());
            // The Fresnel of the glass lobes depends on N.V; none here, so any cos_nv works.
            const PrincipledBsdf bsdf(material, vec3(0.5f, 0.7f, 0.9f), false, 1.0f);
            const vec3 f_ab = bsdf.eval(a, b).total() / b.z;
            const vec3 f_ba = bsdf.eval(b, a).total() / a.z;
            EXPECT_NEAR(f_ab.y, f_ba.y, 1e-4f * (1.0f + f_ab.y));
        }
    }
}

TEST(Bsdf, SmoothGlassSplitsByFresnel) {
    const vec3 wo = direction_from_angle(0.5f);
    const PrincipledBsdf bsdf(make_material(0.0f, 1.0f, 0.0f), vec3(1.0f), false, wo.z);
    EXPECT_FALSE(bsdf.has_smooth_lobes());
    const float fresnel = fresnel_dielectric(wo.z, 1.5f);
    EXPECT_NEAR(bsdf.class_color(LobeClass::Glossy).x, fresnel, 1e-6f);
    EXPECT_NEAR(bsdf.class_color(LobeClass::Transmission).x, 1.0f - fresnel, 1e-6f);
    const Estimates e = sample_estimates(bsdf, wo);
    EXPECT_NEAR(e.sampled_albedo.x, 1.0f, 1e-4f);  // Dirac lobes: weights sum to exactly 1
}

TEST(Bsdf, FresnelAtNormalIncidence) {
    // ((n - 1) / (n + 1))^2 for n = 1.5 is 0.04.
    EXPECT_NEAR(fresnel_dielectric(1.0f, 1.5f), 0.04f, 1e-6f);
    EXPECT_FLOAT_EQ(fresnel_dielectric(0.1f, 1.0f / 1.5f), 1.0f);  // total internal reflection
}

// fresnel_dielectric and ggx_g1 are written for speed (one division each); these check them
// against the textbook forms evaluated in double. Float rounding of the fast forms stays within
// a few ulps of the result: 1e-5 relative leaves a margin of ~100.
constexpr double kFastFormTolerance = 1e-5;

TEST(Bsdf, FresnelMatchesTextbookForm) {
    for (float eta_f : {1.0f / 1.5f, 1.0f / 1.1f, 1.1f, 1.45f, 1.5f, 2.4f}) {
        const double eta = eta_f;
        for (int i = 0; i <= 100; ++i) {
            const float c_f = float(i) / 100.0f;
            const double c = c_f;
            const double g2 = eta * eta - 1.0 + c * c;
            double expected = 1.0;  // total internal reflection
            if (g2 > 0.0) {
                const double g = std::sqrt(g2);
                const double a = (g - c) / (g + c);
                const double b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
                expected = 0.5 * a * a * (1.0 + b * b);
            }
            EXPECT_NEAR(fresnel_dielectric(c_f, eta_f), expected,
                        kFastFormTolerance * expected)
                << "cos " << c << ", eta " << eta;
        }
    }
}

TEST(Bsdf, SmithG1MatchesTangentForm) {
    for (float alpha : {kDeltaAlpha, 0.01f, 0.25f, 0.64f, 1.0f}) {
        for (int i = 1; i <= 100; ++i) {
            const float c_f = float(i) / 100.0f;
            const double c = c_f;
            const double tan2 = (1.0 - c * c) / (c * c);
            const double expected = 2.0 / (1.0 + std::sqrt(1.0 + double(alpha) * alpha * tan2));
            const vec3 w(std::sqrt(1.0f - c_f * c_f), 0.0f, c_f);
            EXPECT_NEAR(ggx_g1(w, alpha), expected, kFastFormTolerance * expected)
                << "cos " << c << ", alpha " << alpha;
            // Refracted directions are below the surface: G1 depends on |cos| only.
            EXPECT_EQ(ggx_g1(vec3(w.x, w.y, -w.z), alpha), ggx_g1(w, alpha));
        }
        EXPECT_EQ(ggx_g1(vec3(1.0f, 0.0f, 0.0f), alpha), 0.0f);  // grazing
    }
}

// sample() computes f |cos| and the pdf of its direction in one pass over the lobes; they must
// be what eval() and pdf() give for that direction.
TEST(Bsdf, SampleAgreesWithEvalAndPdf) {
    for (const Case& c : {Case{"plastic", 0.0f, 0.0f, 0.4f}, Case{"rough_glass", 0.0f, 1.0f, 0.5f},
                          Case{"half_metal", 0.5f, 0.0f, 0.3f}}) {
        Material material = make_material(c.metallic, c.transmission, c.roughness);
        material.diffuse_model = DiffuseModel::Principled;
        const vec3 wo = direction_from_angle(0.8f);
        const PrincipledBsdf bsdf(material, vec3(0.5f, 0.7f, 0.9f), false, wo.z);
        Pcg32 rng(7, 8);
        int checked = 0;
        for (int i = 0; i < 1000; ++i) {
            BsdfSample s;
            const float u_lobe = rng.next_float();
            if (!bsdf.sample(wo, u_lobe, rng.next_vec2(), &s) || s.delta) continue;
            const float pdf = bsdf.pdf(wo, s.wi);
            const vec3 f = bsdf.eval(wo, s.wi).total();
            EXPECT_FLOAT_EQ(s.pdf, pdf) << c.name;
            EXPECT_NEAR(s.weight.y, f.y / pdf, 1e-5f * (1.0f + s.weight.y)) << c.name;
            ++checked;
        }
        EXPECT_GT(checked, 500) << c.name;
    }
}

// Filter Glossy (Cycles' bsdf_blur): blur(a) gives every microfacet lobe alpha max(alpha, a) and
// changes nothing else, so a smooth mirror or glass blurred to a is, lobe for lobe, the same
// material at roughness sqrt(a) (3.4's model with a Lambert diffuse: no term reads the roughness
// besides the lobes' alpha), and a blur below the lobes' alpha changes nothing, bit for bit.
TEST(Bsdf, BlurWidensMicrofacetLobesToTheGivenAlpha) {
    const float alpha = 0.2f;
    for (const Case& c : {Case{"mirror", 1.0f, 0.0f, 0.0f}, Case{"plastic", 0.0f, 0.0f, 0.05f},
                          Case{"glass", 0.0f, 1.0f, 0.0f}}) {
        const Material sharp = make_material(c.metallic, c.transmission, c.roughness);
        const Material rough = make_material(c.metallic, c.transmission, std::sqrt(alpha));
        const vec3 wo = direction_from_angle(0.6f);
        const vec3 base(0.5f, 0.7f, 0.9f);
        PrincipledBsdf blurred(sharp, base, false, wo.z);
        if (c.metallic == 1.0f) {
            EXPECT_FALSE(blurred.has_smooth_lobes()) << "a Dirac mirror";
        }
        blurred.blur(alpha);
        const PrincipledBsdf expected(rough, base, false, wo.z);
        EXPECT_TRUE(blurred.has_smooth_lobes()) << c.name;
        Pcg32 rng(3, 4);
        for (int i = 0; i < 200; ++i) {
            const vec3 wi = sample_uniform_sphere(rng.next_vec2());
            const vec3 f = blurred.eval(wo, wi).total(), g = expected.eval(wo, wi).total();
            for (int k = 0; k < 3; ++k) EXPECT_NEAR(f[k], g[k], 1e-5f * (1.0f + g[k])) << c.name;
            EXPECT_NEAR(blurred.pdf(wo, wi), expected.pdf(wo, wi),
                        1e-5f * (1.0f + expected.pdf(wo, wi))) << c.name;
        }
        const PrincipledBsdf unblurred(sharp, base, false, wo.z);
        for (const LobeClass lobe :
             {LobeClass::Diffuse, LobeClass::Glossy, LobeClass::Transmission})
            EXPECT_EQ(blurred.class_color(lobe), unblurred.class_color(lobe)) << c.name;
        PrincipledBsdf::GlossyLobe lobes[2];
        if (blurred.field_glossy_lobes(wo, lobes) > 0) {
            EXPECT_FLOAT_EQ(lobes[0].roughness, std::sqrt(alpha)) << c.name;
        }
        // A blur below the lobes' alpha leaves them exactly as they were.
        PrincipledBsdf untouched(rough, base, false, wo.z);
        untouched.blur(0.5f * alpha);
        for (int i = 0; i < 50; ++i) {
            const vec3 wi = sample_uniform_sphere(rng.next_vec2());
            EXPECT_EQ(untouched.eval(wo, wi).total(), expected.eval(wo, wi).total()) << c.name;
            EXPECT_EQ(untouched.pdf(wo, wi), expected.pdf(wo, wi)) << c.name;
        }
    }
    // The diffuse lobe has no alpha to widen.
    Material matte = make_material(0.0f, 0.0f, 0.0f);
    matte.specular = 0.0f;  // no specular closure
    PrincipledBsdf diffuse(matte, vec3(0.8f), false, 0.7f);
    diffuse.blur(0.5f);
    const vec3 wo = direction_from_angle(0.8f), wi = direction_from_angle(-0.3f);
    EXPECT_EQ(diffuse.eval(wo, wi).total(),
              PrincipledBsdf(matte, vec3(0.8f), false, 0.7f).eval(wo, wi).total());
}

TEST(Bsdf, DefaultConstructedIsBlack) {
    const PrincipledBsdf bsdf{};
    const vec3 wo(0.0f, 0.0f, 1.0f), wi = direction_from_angle(0.3f);
    EXPECT_EQ(bsdf.eval(wo, wi).total(), vec3(0.0f));
    EXPECT_EQ(bsdf.pdf(wo, wi), 0.0f);
    BsdfSample s;
    EXPECT_FALSE(bsdf.sample(wo, 0.5f, vec2(0.5f), &s));
    EXPECT_FALSE(bsdf.has_smooth_lobes());
}

// Cycles 3.4 adds the specular closure only when Specular or Metallic is above its cutoff: a
// Specular-0 dielectric has no glossy colour and no grazing-angle reflection.
TEST(Bsdf, NoSpecularClosureWithoutSpecularOrMetallic) {
    const vec3 grazing = direction_from_angle(1.45f);
    const vec3 mirror(-grazing.x, -grazing.y, grazing.z);
    Material material = make_material(0.0f, 0.0f, 0.3f);
    material.specular = 0.0f;
    const PrincipledBsdf matte(material, vec3(0.5f), false, grazing.z);
    EXPECT_EQ(matte.class_color(LobeClass::Glossy), vec3(0.0f));
    EXPECT_EQ(matte.eval(grazing, mirror).by_class[int(LobeClass::Glossy)], vec3(0.0f));

    material.specular = 0.5f;
    const PrincipledBsdf plastic(material, vec3(0.5f), false, grazing.z);
    EXPECT_EQ(plastic.class_color(LobeClass::Glossy), vec3(1.0f));
    EXPECT_GT(plastic.eval(grazing, mirror).by_class[int(LobeClass::Glossy)].x, 0.0f);

    material.specular = 0.0f;
    material.metallic = 1.0f;
    const PrincipledBsdf metal(material, vec3(0.5f), false, grazing.z);
    EXPECT_EQ(metal.class_color(LobeClass::Glossy), vec3(1.0f));
}

// The photon tracer's roulette survival: a matte surface scatters its base colour; a smooth
// metal its specular colour toward wo, which is what its mirror sample carries; smooth glass
// all of it (Fresnel reflection plus the white refraction).
TEST(Bsdf, AlbedoEstimateIsWhatTheSurfaceScatters) {
    Material material = make_material(0.0f, 0.0f, 0.5f);
    material.specular = 0.0f;
    const vec3 base(0.2f, 0.5f, 0.8f);
    const PrincipledBsdf matte(material, base, false, 0.7f);
    EXPECT_EQ(matte.albedo_estimate(), base);

    material = make_material(1.0f, 0.0f, 0.0f);
    const vec3 wo = direction_from_angle(0.6f);
    const PrincipledBsdf metal(material, base, false, wo.z);
    BsdfSample s;
    ASSERT_TRUE(metal.sample(wo, 0.5f, vec2(0.5f), &s));
    ASSERT_TRUE(s.delta);
    EXPECT_NEAR(metal.albedo_estimate().x, s.weight.x, 1e-6f);
    EXPECT_NEAR(metal.albedo_estimate().z, s.weight.z, 1e-6f);

    const PrincipledBsdf glass(make_material(0.0f, 1.0f, 0.0f), vec3(1.0f), false, wo.z);
    EXPECT_NEAR(glass.albedo_estimate().y, 1.0f, 1e-6f);
}

// --- PrincipledModel::V2 (Cycles 4's layering) ---

Material v2_material(float roughness, MicrofacetDistribution distribution) {
    Material material = make_material(0.0f, 0.0f, roughness);
    material.specular = 0.5f;  // F0 0.04, ior 1.5
    material.principled_model = PrincipledModel::V2;
    material.distribution = distribution;
    return material;
}

// A smooth dielectric layer reflects F(cos) toward the viewer, so the diffuse below it gets
// 1 - F(cos): exact at normal view (F0 = 0.04 whatever the table's ior interpolation) and within
// the table's linear interpolation in ior elsewhere (cos = 0.4 is one of its nodes in N.V).
TEST(BsdfV2, SmoothLayerDimsDiffuseByFresnel) {
    const Material material = v2_material(0.0f, MicrofacetDistribution::GGX);
    const PrincipledBsdf normal(material, vec3(1.0f), false, 1.0f);
    EXPECT_NEAR(normal.class_color(LobeClass::Diffuse).x, 0.96f, 1e-4f);
    EXPECT_NEAR(normal.class_color(LobeClass::Glossy).x, 0.04f, 1e-4f);
    const PrincipledBsdf oblique(material, vec3(1.0f), false, 0.4f);
    const float fresnel = fresnel_dielectric(0.4f, 1.5f);
    EXPECT_NEAR(oblique.class_color(LobeClass::Diffuse).x, 1.0f - fresnel, 2e-3f);
    EXPECT_NEAR(oblique.class_color(LobeClass::Glossy).x, fresnel, 2e-3f);

    Material v1 = material;
    v1.principled_model = PrincipledModel::V1;
    EXPECT_EQ(PrincipledBsdf(v1, vec3(1.0f), false, 0.4f).class_color(LobeClass::Diffuse),
              vec3(1.0f));
}

// A smooth metal's GlossCol is its reflectance at the view: Schlick's F(1) = base colour.
TEST(BsdfV2, MetalGlossColorIsItsReflectance) {
    Material material = v2_material(0.0f, MicrofacetDistribution::GGX);
    material.metallic = 1.0f;
    const PrincipledBsdf metal(material, vec3(0.5f, 0.6f, 0.7f), false, 1.0f);
    const vec3 gloss = metal.class_color(LobeClass::Glossy);
    EXPECT_NEAR(gloss.x, 0.5f, 1e-4f);
    EXPECT_NEAR(gloss.z, 0.7f, 1e-4f);
    EXPECT_EQ(metal.class_color(LobeClass::Diffuse), vec3(0.0f));
}

// With Multiscatter GGX a white v2 plastic reflects all the light it receives: the specular
// layer takes exactly what it dims the diffuse by (its albedo with the energy-preservation
// scale), so f cos integrates to 1 at every view angle and roughness, up to the tables'
// interpolation. Single-scattering GGX loses the energy of the paths it misses; v1 adds the
// specular on top of a full diffuse and exceeds 1.
TEST(BsdfV2, WhiteMultiscatterPlasticConservesEnergy) {
    for (float roughness : {0.2f, 0.5f, 0.9f}) {
        for (float theta : {0.1f, 0.7f, 1.2f}) {
            const vec3 wo = direction_from_angle(theta);
            vec3 albedo;
            float pdf_integral;
            const Material multiscatter =
                v2_material(roughness, MicrofacetDistribution::MultiscatterGGX);
            quadrature(PrincipledBsdf(multiscatter, vec3(1.0f), false, wo.z), wo, &albedo,
                       &pdf_integral);
            EXPECT_NEAR(albedo.x, 1.0f, 5e-3f) << roughness << " " << theta;

            quadrature(PrincipledBsdf(v2_material(roughness, MicrofacetDistribution::GGX),
                                      vec3(1.0f), false, wo.z),
                       wo, &albedo, &pdf_integral);
            EXPECT_LT(albedo.x, 1.0f + 2e-3f) << roughness << " " << theta;
            EXPECT_GT(albedo.x, 0.95f) << roughness << " " << theta;

            Material v1 = multiscatter;
            v1.principled_model = PrincipledModel::V1;
            quadrature(PrincipledBsdf(v1, vec3(1.0f), false, wo.z), wo, &albedo, &pdf_integral);
            EXPECT_GT(albedo.x, 1.01f) << roughness << " " << theta;  // + the specular's ~2-10%
        }
    }
}

// v2 is not reciprocal; a light path's BSDF is the camera path's with the directions swapped:
// f_light(a -> b) = f_camera(b -> a), where the camera side is b.
TEST(BsdfV2, LightPathsUseTheAdjointBsdf) {
    Material material = v2_material(0.4f, MicrofacetDistribution::MultiscatterGGX);
    material.metallic = 0.3f;
    const vec3 color(0.5f, 0.7f, 0.9f);
    Pcg32 rng(5, 6);
    float largest_asymmetry = 0.0f;
    for (int i = 0; i < 100; ++i) {
        const vec3 a = sample_uniform_hemisphere(rng.next_vec2());
        const vec3 b = sample_uniform_hemisphere(rng.next_vec2());
        const PrincipledBsdf from_light(material, color, false, a.z, PathOrigin::Light);
        const PrincipledBsdf from_camera(material, color, false, b.z, PathOrigin::Camera);
        const vec3 f_light = from_light.eval(a, b).total() / b.z;
        const vec3 f_camera = from_camera.eval(b, a).total() / a.z;
        EXPECT_NEAR(f_light.y, f_camera.y, 1e-4f * (1.0f + f_camera.y));
        const PrincipledBsdf camera_at_a(material, color, false, a.z, PathOrigin::Camera);
        const vec3 f_ab = camera_at_a.eval(a, b).total() / b.z;
        largest_asymmetry = std::max(largest_asymmetry, std::fabs(f_ab.y - f_camera.y));
    }
    EXPECT_GT(largest_asymmetry, 1e-3f);  // the swap matters
}


// field_diffuse sums the diffuse lobes' weights itself (not through class_color, for the
// latency): Lambert's field lobe is class_color(Diffuse) bit for bit, Burley's the same colour
// times one albedo for the three channels, for any view and roughness, the grazing and the
// clamped table edges too.
TEST(Bsdf, FieldDiffuseIsTheDiffuseClassColourTimesOneAlbedo) {
    auto same = [](const vec3& a, const vec3& b) { return std::memcmp(&a, &b, sizeof(vec3)) == 0; };
    for (DiffuseModel model : {DiffuseModel::Lambert, DiffuseModel::Principled})
        for (float metallic : {0.0f, 0.4f, 1.0f})
            for (float roughness : {0.0f, 0.3f, 1.0f}) {
                Material material = make_material(metallic, 0.0f, roughness);
                material.base_color = vec3(0.7f, 0.2f, 0.05f);
                material.diffuse_model = model;
                const MaterialTerms terms = material_terms(material);
                for (float angle : {0.0f, 0.4f, 1.1f, 1.5707f, 1.58f}) {
                    const vec3 wo = direction_from_angle(angle);
                    const PrincipledBsdf bsdf(material, terms, material.base_color, false,
                                              std::max(wo.z, 0.0f));
                    const vec3 color = bsdf.class_color(LobeClass::Diffuse);
                    const vec3 field = bsdf.field_diffuse(wo);
                    if (metallic == 1.0f) {  // no diffuse lobe
                        EXPECT_TRUE(same(field, vec3(0.0f)));
                        continue;
                    }
                    if (model == DiffuseModel::Lambert) {
                        EXPECT_TRUE(same(field, color));
                        continue;
                    }
                    const float albedo = field.x / color.x;
                    EXPECT_GT(albedo, 0.25f);  // Burley: 0.49 (smooth, grazing) to 1.53 (rough, grazing)
                    EXPECT_LT(albedo, 2.0f);
                    EXPECT_NEAR(field.y, color.y * albedo, 1e-6f);
                    EXPECT_NEAR(field.z, color.z * albedo, 1e-6f);
                }
            }
}

// field_albedo_lanes reads the two albedo tables in SSE2 lanes: each lane is burley_albedo's and
// ggx_albedo's value bit for bit, over random views and roughnesses and at the tables' edges
// (every node of cos(N.V) and roughness and the floats beside it, views from below and past 1,
// -0, roughness 0 and 1).
TEST(Bsdf, FieldAlbedoLanesAreTheTablesBitForBit) {
    auto check = [](const float cos_nv[4], const float diffuse[4], const float glossy[4]) {
        FieldAlbedoLanes lanes;
        field_albedo_lanes(cos_nv, diffuse, glossy, &lanes);
        for (int k = 0; k < 4; ++k) {
            const float burley = burley_albedo(cos_nv[k], diffuse[k]);
            const vec2 ggx = ggx_albedo(cos_nv[k], glossy[k]);
            EXPECT_EQ(std::memcmp(&lanes.burley[k], &burley, sizeof(float)), 0)
                << "cos " << cos_nv[k] << " roughness " << diffuse[k] << ": " << lanes.burley[k]
                << " against " << burley;
            EXPECT_EQ(std::memcmp(&lanes.ggx[0][k], &ggx.x, sizeof(float)), 0)
                << "cos " << cos_nv[k] << " roughness " << glossy[k] << ": " << lanes.ggx[0][k]
                << " against " << ggx.x;
            EXPECT_EQ(std::memcmp(&lanes.ggx[1][k], &ggx.y, sizeof(float)), 0)
                << "cos " << cos_nv[k] << " roughness " << glossy[k] << ": " << lanes.ggx[1][k]
                << " against " << ggx.y;
        }
    };
    std::vector<float> edges = {-1.0f, -0.5f, -1e-8f, -0.0f, 1e-3f, 1.0f + 1e-7f, 2.0f};
    for (int node = 0; node < 32; ++node) {
        const float x = float(node) / 31.0f;
        edges.push_back(x);
        edges.push_back(std::nextafter(x, -1.0f));
        edges.push_back(std::nextafter(x, 2.0f));
    }
    // Every edge as cos(N.V) against every edge as either roughness, four at a time.
    for (size_t a = 0; a < edges.size(); ++a)
        for (size_t b = 0; b < edges.size(); b += 4) {
            float cos_nv[4], diffuse[4], glossy[4];
            for (int k = 0; k < 4; ++k) {
                cos_nv[k] = edges[a];
                diffuse[k] = edges[(b + k) % edges.size()];
                glossy[k] = edges[(b + 3 * k + 1) % edges.size()];
            }
            check(cos_nv, diffuse, glossy);
            check(diffuse, glossy, cos_nv);
            if (HasFailure()) return;
        }
    Pcg32 rng(47, 17);
    for (int trial = 0; trial < 20000; ++trial) {
        float cos_nv[4], diffuse[4], glossy[4];
        for (int k = 0; k < 4; ++k) {
            const float pick = rng.next_float();
            cos_nv[k] = pick < 0.1f ? rng.next_float() * 1e-2f : rng.next_float();  // grazing
            diffuse[k] = rng.next_float();
            glossy[k] = pick > 0.9f ? float(k % 2) : rng.next_float();  // roughness 0 and 1
        }
        check(cos_nv, diffuse, glossy);
        if (HasFailure()) return;
    }
}

// field_lobes_with, given the tables' reads toward wo, is field_diffuse and field_glossy_lobes
// bit for bit (Lambert and Burley, metals, glass, V2, blurred lobes, grazing views).
TEST(Bsdf, FieldLobesWithTheirAlbedosAreTheFieldLobes) {
    auto same = [](const vec3& a, const vec3& b) { return std::memcmp(&a, &b, sizeof(vec3)) == 0; };
    std::vector<Material> materials;
    for (DiffuseModel model : {DiffuseModel::Lambert, DiffuseModel::Principled})
        for (PrincipledModel principled : {PrincipledModel::V1, PrincipledModel::V2})
            for (float metallic : {0.0f, 0.4f, 1.0f})
                for (float transmission : {0.0f, 0.5f})
                    for (float roughness : {0.0f, 0.3f, 1.0f}) {
                        Material material = make_material(metallic, transmission, roughness);
                        material.base_color = vec3(0.7f, 0.2f, 0.05f);
                        material.diffuse_model = model;
                        material.principled_model = principled;
                        materials.push_back(material);
                    }
    for (const Material& material : materials)
        for (float blur : {0.0f, 0.5f})
            for (float angle : {0.0f, 0.4f, 1.1f, 1.5707f}) {
                const vec3 wo = direction_from_angle(angle);
                PrincipledBsdf bsdf(material, material.base_color, false, wo.z);
                if (blur > 0.0f) bsdf.blur(blur);
                const float burley = burley_albedo(wo.z, bsdf.field_diffuse_roughness());
                const vec2 ggx = ggx_albedo(wo.z, bsdf.field_glossy_roughness());
                PrincipledBsdf::GlossyLobe lobes[2], with[2];
                vec3 diffuse;
                const int count = bsdf.field_glossy_lobes(wo, lobes);
                ASSERT_EQ(count, bsdf.field_lobes_with(burley, ggx, &diffuse, with));
                ASSERT_TRUE(same(bsdf.field_diffuse(wo), diffuse));
                for (int i = 0; i < count; ++i) {
                    ASSERT_TRUE(same(lobes[i].albedo, with[i].albedo));
                    ASSERT_EQ(lobes[i].roughness, with[i].roughness);
                }
            }
}

// A material whose lobes are the same at every hit: its BSDF finished from material_lobes is the
// full constructor's for every side and view, bit for bit (eval, pdf, samples, colours, field
// lobes, albedo estimate), so tracers that keep the lobes per material render the same image.
TEST(Bsdf, MaterialLobesFinishToTheFullConstructorBitForBit) {
    auto same = [](const vec3& a, const vec3& b) { return std::memcmp(&a, &b, sizeof(vec3)) == 0; };
    std::vector<Material> materials;
    for (float metallic : {0.0f, 0.4f, 1.0f})
        for (float specular : {0.0f, 0.5f, 1.0f})
            for (float roughness : {0.0f, 0.3f, 0.8f}) {
                Material material = make_material(metallic, 0.0f, roughness);
                material.base_color = vec3(0.7f, 0.2f, 0.05f);
                material.specular = specular;
                material.diffuse_model =
                    roughness > 0.5f ? DiffuseModel::Principled : DiffuseModel::Lambert;
                materials.push_back(material);
            }
    Material matte_v2 = make_material(0.0f, 0.0f, 0.5f);
    matte_v2.principled_model = PrincipledModel::V2;
    matte_v2.specular = 0.0f;
    materials.push_back(matte_v2);
    int checked = 0;
    for (const Material& material : materials) {
        const MaterialTerms terms = material_terms(material);
        ASSERT_TRUE(PrincipledBsdf::lobes_depend_on_hit_only_by_view(material, terms));
        const PrincipledBsdf lobes = PrincipledBsdf::material_lobes(material, terms);
        for (bool back_face : {false, true})
            for (float angle : {0.0f, 0.4f, 1.1f, 1.5f}) {
                const vec3 wo = direction_from_angle(angle);
                const PrincipledBsdf full(material, terms, material.base_color, back_face, wo.z);
                const PrincipledBsdf finished(lobes, material, terms, back_face, wo.z);
                ASSERT_TRUE(same(full.albedo_estimate(), finished.albedo_estimate()));
                ASSERT_TRUE(same(full.class_color_sum(), finished.class_color_sum()));
                ASSERT_TRUE(same(full.field_diffuse(wo), finished.field_diffuse(wo)));
                PrincipledBsdf::GlossyLobe full_glossy[2], finished_glossy[2];
                const int glossy = full.field_glossy_lobes(wo, full_glossy);
                ASSERT_EQ(glossy, finished.field_glossy_lobes(wo, finished_glossy));
                for (int i = 0; i < glossy; ++i)
                    ASSERT_TRUE(same(full_glossy[i].albedo, finished_glossy[i].albedo));
                Pcg32 rng(7, uint64_t(checked));
                for (int k = 0; k < 16; ++k) {
                    const vec3 wi = sample_uniform_sphere(rng.next_vec2());
                    ASSERT_TRUE(same(full.eval(wo, wi).total(), finished.eval(wo, wi).total()));
                    ASSERT_EQ(full.pdf(wo, wi), finished.pdf(wo, wi));
                    const float u_lobe = rng.next_float();
                    const vec2 u = rng.next_vec2();
                    BsdfSample a, b;
                    ASSERT_EQ(full.sample(wo, u_lobe, u, &a), finished.sample(wo, u_lobe, u, &b));
                    ASSERT_TRUE(same(a.wi, b.wi) && same(a.weight, b.weight));
                    ASSERT_EQ(a.pdf, b.pdf);
                }
                // The finished BSDF defers its lobe selection to the first reader: each reader
                // called first, on a fresh one, gives the full constructor's bits.
                const vec3 wi = direction_from_angle(0.7f);
                const float u_lobe = 0.6f;
                const vec2 u(0.3f, 0.8f);
                EXPECT_EQ(full.pdf(wo, wi),
                          PrincipledBsdf(lobes, material, terms, back_face, wo.z).pdf(wo, wi));
                BsdfSample a, b;
                ASSERT_EQ(full.sample(wo, u_lobe, u, &a),
                          PrincipledBsdf(lobes, material, terms, back_face, wo.z)
                              .sample(wo, u_lobe, u, &b));
                EXPECT_TRUE(same(a.wi, b.wi) && same(a.weight, b.weight) && a.pdf == b.pdf);
                ASSERT_EQ(full.sample_traced(wo, u_lobe, u, &a),
                          PrincipledBsdf(lobes, material, terms, back_face, wo.z)
                              .sample_traced(wo, u_lobe, u, &b));
                EXPECT_TRUE(same(a.wi, b.wi) && same(a.weight, b.weight) && a.pdf == b.pdf);
                const DenoisingFeature full_feature = full.denoising_feature(wo.z);
                const DenoisingFeature finished_feature =
                    PrincipledBsdf(lobes, material, terms, back_face, wo.z).denoising_feature(wo.z);
                EXPECT_TRUE(same(full_feature.albedo, finished_feature.albedo) &&
                            same(full_feature.specular_albedo, finished_feature.specular_albedo));
                EXPECT_EQ(full_feature.weight, finished_feature.weight);
                EXPECT_EQ(full_feature.nonspecular_weight, finished_feature.nonspecular_weight);
                // eval() does not select; a later pdf() still does, on the same bits.
                const PrincipledBsdf evaluated(lobes, material, terms, back_face, wo.z);
                EXPECT_TRUE(same(full.eval(wo, wi).total(), evaluated.eval(wo, wi).total()));
                EXPECT_EQ(full.pdf(wo, wi), evaluated.pdf(wo, wi));
                ++checked;
            }
    }
    EXPECT_EQ(checked, 28 * 8);

    // Lobes that change from hit to hit are not kept per material.
    Material textured = make_material(0.0f, 0.0f, 0.5f);
    textured.base_color_texture = 0;
    EXPECT_FALSE(PrincipledBsdf::lobes_depend_on_hit_only_by_view(textured,
                                                                  material_terms(textured)));
    const Material glass = make_material(0.0f, 1.0f, 0.0f);
    EXPECT_FALSE(PrincipledBsdf::lobes_depend_on_hit_only_by_view(glass, material_terms(glass)));
    Material layered = make_material(0.0f, 0.0f, 0.5f);
    layered.principled_model = PrincipledModel::V2;
    EXPECT_FALSE(PrincipledBsdf::lobes_depend_on_hit_only_by_view(layered,
                                                                  material_terms(layered)));
}

// eval_field is eval() over the field lobes alone: every field lobe reflects and every traced
// lobe's f is zero off its Dirac direction, so above the surface the two agree bit for bit, class
// by class, and below it eval_field is zero (its refraction lobes are traced) — for smooth and
// rough, metal, glass, PrincipledModel::V2 camera and light paths, and bent normals.
TEST(Bsdf, EvalFieldIsEvalOfTheFieldLobesBitForBit) {
    auto same = [](const vec3& a, const vec3& b) { return std::memcmp(&a, &b, sizeof(vec3)) == 0; };
    std::vector<Material> materials;
    for (float metallic : {0.0f, 1.0f})
        for (float transmission : {0.0f, 1.0f})
            for (float roughness : {0.0f, 0.3f, 0.8f})
                for (bool v2 : {false, true}) {
                    Material material = make_material(metallic, transmission, roughness);
                    material.base_color = vec3(0.7f, 0.2f, 0.05f);
                    material.diffuse_model =
                        roughness > 0.5f ? DiffuseModel::Principled : DiffuseModel::Lambert;
                    if (v2) {
                        material.principled_model = PrincipledModel::V2;
                        material.distribution = MicrofacetDistribution::MultiscatterGGX;
                    }
                    materials.push_back(material);
                }
    int checked = 0, nonzero = 0;
    for (const Material& material : materials)
        for (PathOrigin origin : {PathOrigin::Camera, PathOrigin::Light})
            for (bool bent : {false, true})
                for (float angle : {0.0f, 0.7f, 1.4f}) {
                    const vec3 wo = direction_from_angle(angle);
                    PrincipledBsdf bsdf(material, material.base_color, false, wo.z, origin);
                    if (bent) bsdf.set_smooth_normal(glm::normalize(vec3(0.3f, -0.2f, 1.0f)), true);
                    Pcg32 rng(11, uint64_t(checked));
                    for (int k = 0; k < 32; ++k) {
                        const vec3 wi = sample_uniform_sphere(rng.next_vec2());
                        const BsdfEval field = bsdf.eval_field(wo, wi);
                        const BsdfEval all = wi.z > 0.0f ? bsdf.eval(wo, wi) : BsdfEval{};
                        for (int c = 0; c < kLobeClassCount; ++c)
                            ASSERT_TRUE(same(field.by_class[c], all.by_class[c]))
                                << "material " << checked / 12 << " class " << c;
                        nonzero += max_component(field.total()) > 0.0f;
                    }
                    ++checked;
                }
    EXPECT_EQ(checked, 24 * 12);
    EXPECT_GT(nonzero, checked * 8);  // the comparison is not of zeros
}

}  // namespace
}  // namespace shgi
