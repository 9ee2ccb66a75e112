// PrincipledBsdf::eval_field_lanes (render/bsdf_lanes.cpp) gives each lane the bits eval_field
// gives it: over random materials the lanes cover (Lambert and principled diffuse, Specular and
// Metallic from 0 to 1, both Smith G, roughness 0 to 1, blurred lobes), four different ones a
// group, and random directions; and at the edge cases: views and light from below the surface
// and grazing (z = 0, z of 1e-7, -0), a light straight opposite the view (a zero half vector),
// roughness 0 (a Dirac specular lobe, which eval_field skips) and 1, and NaN directions.
// eval_field_in_lanes leaves out glass, light paths and bent normals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "render/bsdf.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {
namespace {

bool same_bits(const BsdfEval& a, const BsdfEval& b) {
    return std::memcmp(&a, &b, sizeof(BsdfEval)) == 0;
}

Material random_material(Pcg32& rng) {
    Material material;
    material.base_color = vec3(rng.next_float(), rng.next_float(), rng.next_float());
    const float corner[] = {0.0f, 1.0f};
    // Each term at one of its ends a quarter of the time each, else anywhere between.
    const auto term = [&]() {
        const float u = rng.next_float();
        return u < 0.5f ? corner[u < 0.25f ? 0 : 1] : rng.next_float();
    };
    material.metallic = term();
    material.specular = term();
    material.roughness = term();
    material.ior = 1.0f + 2.0f * rng.next_float();
    material.diffuse_model = rng.next_float() < 0.5f ? DiffuseModel::Lambert
                                                     : DiffuseModel::Principled;
    if (rng.next_float() < 0.5f) {
        material.principled_model = PrincipledModel::V2;
        material.distribution = rng.next_float() < 0.5f ? MicrofacetDistribution::MultiscatterGGX
                                                        : MicrofacetDistribution::GGX;
    }
    return material;
}

PrincipledBsdf random_bsdf(Pcg32& rng, float cos_nv) {
    const Material material = random_material(rng);
    PrincipledBsdf bsdf(material, material.base_color, rng.next_float() < 0.2f, cos_nv);
    if (rng.next_float() < 0.1f) bsdf.blur(rng.next_float());
    return bsdf;
}

// Evaluates four queries in lanes and compares each with eval_field.
void expect_lanes_bits(const PrincipledBsdf* const bsdf[4], const vec3 wo[4], const vec3 wi[4],
                       int* nonzero) {
    BsdfEval lanes[4];
    const vec3* wo_of[4] = {&wo[0], &wo[1], &wo[2], &wo[3]};
    const vec3* wi_of[4] = {&wi[0], &wi[1], &wi[2], &wi[3]};
    BsdfEval* out[4] = {&lanes[0], &lanes[1], &lanes[2], &lanes[3]};
    PrincipledBsdf::eval_field_lanes(bsdf, wo_of, wi_of, out);
    for (int k = 0; k < 4; ++k) {
        ASSERT_TRUE(bsdf[k]->eval_field_in_lanes());
        const BsdfEval scalar = bsdf[k]->eval_field(wo[k], wi[k]);
        EXPECT_TRUE(same_bits(lanes[k], scalar))
            << "lane " << k << " wo (" << wo[k].x << ", " << wo[k].y << ", " << wo[k].z
            << ") wi (" << wi[k].x << ", " << wi[k].y << ", " << wi[k].z << "): diffuse ("
            << lanes[k].by_class[0].x << ", " << lanes[k].by_class[0].y << ", "
            << lanes[k].by_class[0].z << ") against (" << scalar.by_class[0].x << ", "
            << scalar.by_class[0].y << ", " << scalar.by_class[0].z << "), glossy ("
            << lanes[k].by_class[1].x << ", " << lanes[k].by_class[1].y << ", "
            << lanes[k].by_class[1].z << ") against (" << scalar.by_class[1].x << ", "
            << scalar.by_class[1].y << ", " << scalar.by_class[1].z << ")";
        *nonzero += max_component(scalar.total()) > 0.0f;
    }
}

TEST(BsdfLanes, LanesAreEvalFieldBitForBit) {
    Pcg32 rng(47, 17);
    int nonzero = 0, groups = 0;
    while (groups < 5000) {
        vec3 wo[4], wi[4];
        std::vector<PrincipledBsdf> bsdfs;
        for (int k = 0; k < 4; ++k) {
            wo[k] = sample_uniform_sphere(rng.next_vec2());
            if (wo[k].z < 0.0f && rng.next_float() < 0.8f) wo[k].z = -wo[k].z;  // mostly above
            wi[k] = sample_uniform_sphere(rng.next_vec2());
            if (wi[k].z < 0.0f && rng.next_float() < 0.8f) wi[k].z = -wi[k].z;
            bsdfs.push_back(random_bsdf(rng, wo[k].z));
        }
        const PrincipledBsdf* bsdf[4] = {&bsdfs[0], &bsdfs[1], &bsdfs[2], &bsdfs[3]};
        expect_lanes_bits(bsdf, wo, wi, &nonzero);
        ++groups;
    }
    EXPECT_GT(nonzero, groups * 4 / 2);  // the comparison is not of zeros
}

TEST(BsdfLanes, EdgeCasesAreEvalFieldBitForBit) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const vec3 wo_up(0.0f, 0.0f, 1.0f), wo_oblique = glm::normalize(vec3(0.6f, -0.3f, 0.5f));
    const std::vector<vec3> directions = {
        wo_up,
        wo_oblique,
        vec3(1.0f, 0.0f, 0.0f),                            // grazing
        vec3(0.0f, 1.0f, -0.0f),                           // grazing, -0
        glm::normalize(vec3(1.0f, 0.0f, 1e-7f)),           // just above
        glm::normalize(vec3(-1.0f, 0.2f, 1e-7f)),          // just above, the other side
        glm::normalize(vec3(0.3f, 0.1f, -0.9f)),           // below
        vec3(0.0f, 0.0f, -1.0f),                           // straight below
        -wo_oblique,                                       // opposite the view: h = 0 / 0
        vec3(-wo_oblique.x, -wo_oblique.y, wo_oblique.z),  // mirror of the view
        vec3(wo_oblique.x, wo_oblique.y, nan),
        vec3(nan, 0.0f, 1.0f),
    };
    std::vector<PrincipledBsdf> bsdfs;
    for (float roughness : {0.0f, 0.005f, 0.01f, 0.5f, 1.0f})
        for (float metallic : {0.0f, 1.0f})
            for (float specular : {0.0f, 0.5f, 1.0f})
                for (DiffuseModel diffuse : {DiffuseModel::Lambert, DiffuseModel::Principled})
                    for (PrincipledModel model : {PrincipledModel::V1, PrincipledModel::V2}) {
                        Material material;
                        material.base_color = vec3(0.8f, 0.4f, 0.1f);
                        material.roughness = roughness;
                        material.metallic = metallic;
                        material.specular = specular;
                        material.diffuse_model = diffuse;
                        material.principled_model = model;
                        material.distribution = MicrofacetDistribution::MultiscatterGGX;
                        bsdfs.emplace_back(material, material.base_color, false, 0.5f);
                    }
    int nonzero = 0;
    for (size_t b = 0; b < bsdfs.size(); ++b)
        for (const vec3& wo : directions)
            for (size_t i = 0; i < directions.size(); i += 4) {
                // Four lights a group, each lane another BSDF of the list.
                const PrincipledBsdf* bsdf[4];
                vec3 wos[4], wis[4];
                for (int k = 0; k < 4; ++k) {
                    bsdf[k] = &bsdfs[(b + size_t(k) * 7) % bsdfs.size()];
                    wos[k] = wo;
                    wis[k] = directions[(i + size_t(k)) % directions.size()];
                }
                expect_lanes_bits(bsdf, wos, wis, &nonzero);
            }
    EXPECT_GT(nonzero, 0);
}

TEST(BsdfLanes, GlassLightPathsAndBentNormalsGoScalar) {
    Material material;
    EXPECT_TRUE(PrincipledBsdf(material, material.base_color, false, 0.5f).eval_field_in_lanes());
    Material glass = material;
    glass.transmission = 1.0f;
    EXPECT_FALSE(PrincipledBsdf(glass, glass.base_color, false, 0.5f).eval_field_in_lanes());
    Material layered = material;
    layered.principled_model = PrincipledModel::V2;
    EXPECT_FALSE(PrincipledBsdf(layered, layered.base_color, false, 0.5f, PathOrigin::Light)
                     .eval_field_in_lanes());
    PrincipledBsdf bent(material, material.base_color, false, 0.5f);
    bent.set_smooth_normal(glm::normalize(vec3(0.3f, -0.2f, 1.0f)), true);
    EXPECT_FALSE(bent.eval_field_in_lanes());
}

}  // namespace
}  // namespace shgi
