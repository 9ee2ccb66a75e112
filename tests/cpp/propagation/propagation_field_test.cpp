// PropagationField (propagation/propagation_field.h): the blend of cascade levels. The single
// volume's lookup is tested with the solver that makes it (propagation_volume_test.cpp).
#include "propagation/propagation_field.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "support/expect_error.h"

namespace shgi {
namespace {

using testing::expect_error;

// Cascades: a finer level is read alone at least kCascadeMarginCells + kCascadeBlendCells inside
// the faces it blends across, the coarser one outside its box, and in the band between them the
// blend is linear in the distance: E = w E_fine + (1 − w) E_coarse, w = (d − margin) / band.
TEST(PropagationField, CascadeLevelsBlendLinearlyAcrossTheBand) {
    // Constant intensities (the DC coefficient only) of different size: a fine level of 0.5 cells
    // over x in [0, 10] blending across its upper x face only, a coarse level of unit cells.
    const auto constant = [](float s, const ivec3& counts, float dc) {
        auto volume = std::make_shared<ShVolume>(vec3(0.0f), s, counts, 2);
        for (size_t c = 0; c < volume->cell_count(); ++c)
            for (int channel = 0; channel < 3; ++channel) volume->cell_data(c)[channel] = dc;
        return std::shared_ptr<const ShVolume>(volume);
    };
    const uint8_t upper_x = 8;
    const PropagationField field({{constant(0.5f, ivec3(21), 1.0f), nullptr, upper_x},
                                  {constant(1.0f, ivec3(21), 3.0f), nullptr, 0}},
                                 0.0f, false, Reinjection::FaceNormal);
    const vec3 n(0.0f, 0.0f, 1.0f);
    const float fine = field.level_field(0).irradiance(vec3(5.0f, 5.0f, 5.0f), n).x;
    const float coarse = field.level_field(1).irradiance(vec3(5.0f, 5.0f, 5.0f), n).x;
    ASSERT_GT(fine, 0.0f);
    ASSERT_GT(coarse, 0.0f);
    // The fine box's upper x face: the volume's far side less half a cell, at x = 10.25.
    const float face = 0.5f * 20.0f + 0.25f;
    for (float d : {0.0f, 0.5f, 1.0f, 1.5f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 8.0f}) {
        const float x = face - 0.5f * d;  // d fine cells inside the face
        const float w = std::clamp((d - kCascadeMarginCells) / kCascadeBlendCells, 0.0f, 1.0f);
        EXPECT_NEAR(field.irradiance(vec3(x, 5.0f, 5.0f), n).x, w * fine + (1.0f - w) * coarse,
                    1e-5f * coarse)
            << "d " << d;
        EXPECT_FLOAT_EQ(field.level_weight(0, vec3(x, 5.0f, 5.0f)), w) << "d " << d;
    }
    // Beyond the fine box, and across its faces that do not blend, the coarse / fine level alone.
    EXPECT_FLOAT_EQ(field.irradiance(vec3(14.0f, 5.0f, 5.0f), n).x, coarse);
    EXPECT_FLOAT_EQ(field.irradiance(vec3(0.3f, 0.3f, 0.3f), n).x, fine);
    // The coarsest level may blend into nothing.
    expect_error<InvalidArgument>(
        [&] {
            PropagationField bad({{constant(1.0f, ivec3(4), 1.0f), nullptr, upper_x}}, 0.0f,
                                 false, Reinjection::FaceNormal);
        },
        {"level 0", "blend faces 8"});
}

}  // namespace
}  // namespace shgi
