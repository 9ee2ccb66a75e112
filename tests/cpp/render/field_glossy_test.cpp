// FieldLookup::glossy for a field whose SH holds light from above the horizon only
// (FieldLookup::horizon, the photon lattice): radiance L arriving evenly from the upper
// hemisphere, projected exactly to SH of each order, reads L at every view angle and roughness;
// without the flag the truncated step reads about half at grazing views and more than L along
// the normal, which is what the flag corrects; fields without it read as before.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "render/indirect_field.h"
#include "sh/ggx_zh.h"
#include "sh/sh_projection.h"
#include "sh/sphere_quadrature.h"

namespace shgi {
namespace {

// The quadrature is exact for the step at the horizon (a rule over [0, 1] in cos θ): what
// remains is float rounding of sums of a few dozen terms.
constexpr float kTolerance = 1e-4f;

// L (per channel) from every direction above the horizon of n, none from below, in SH of `order`.
ShRgb upper_hemisphere(int order, const vec3& n, const vec3& radiance) {
    const SphereQuadrature rule = sphere_quadrature(64, 128, 0.0, 1.0);
    const Frame frame = Frame::from_z(n);
    std::vector<vec3> directions, values;
    std::vector<float> weights;
    for (size_t j = 0; j < rule.directions.size(); ++j) {
        directions.push_back(glm::normalize(frame.to_world(vec3(rule.directions[j]))));
        values.push_back(radiance);
        weights.push_back(float(rule.weights[j]));
    }
    return sh_project(order, directions.data(), values.data(), weights.data(), directions.size());
}

// A view `angle` radians from n (in the plane of n and a tangent).
vec3 view_at(const vec3& n, float angle) {
    const Frame frame = Frame::from_z(n);
    return frame.to_world(vec3(std::sin(angle), 0.0f, std::cos(angle)));
}

TEST(FieldGlossy, HorizonReadsEvenLightAsItselfAtEveryAngle) {
    const vec3 n = glm::normalize(vec3(0.3f, -0.5f, 0.8f));
    const vec3 radiance(2.0f, 1.0f, 0.5f);
    for (int order = 1; order <= kMaxShOrder; ++order) {
        FieldLookup lookup{upper_hemisphere(order, n, radiance), vec3(0.0f)};
        lookup.horizon = true;
        for (float roughness : {0.0f, 0.2f, 0.5f, 0.8f, 1.0f}) {
            GgxZhMemo memo;
            for (float degrees = 0.0f; degrees <= 89.0f; degrees += 8.9f) {
                const vec3 wo = view_at(n, glm::radians(degrees));
                for (const vec3 read :
                     {lookup.glossy(n, wo, roughness), lookup.glossy(n, wo, roughness, &memo)}) {
                    for (int c = 0; c < 3; ++c)
                        EXPECT_NEAR(read[c] / radiance[c], 1.0f, kTolerance)
                            << "order " << order << ", roughness " << roughness << ", "
                            << degrees << " degrees, channel " << c;
                }
            }
        }
    }
}

// What the flag corrects: the same SH read as a field of the whole sphere.
TEST(FieldGlossy, WithoutHorizonTheTruncatedStepReadsHalfAtGrazingViews) {
    const vec3 n(0.0f, 0.0f, 1.0f);
    const FieldLookup lookup{upper_hemisphere(2, n, vec3(1.0f)), vec3(0.0f)};
    ASSERT_FALSE(lookup.horizon);  // the default: fields of the whole sphere
    const float normal = lookup.glossy(n, view_at(n, 0.0f), 0.5f).x;
    const float grazing = lookup.glossy(n, view_at(n, glm::radians(85.0f)), 0.5f).x;
    EXPECT_GT(normal, 1.1f);
    EXPECT_LT(grazing, 0.6f);
    // The unflagged read is the split-sum's prefiltered radiance as it was.
    const vec3 wo = view_at(n, glm::radians(40.0f));
    const vec3 reflected = 2.0f * glm::dot(wo, n) * n - wo;
    const vec3 expected = sh_specular_radiance(lookup.radiance, reflected, 0.5f);
    EXPECT_EQ(lookup.glossy(n, wo, 0.5f), expected);
}

}  // namespace
}  // namespace shgi
