// dilate: after `padding` passes exactly the empty texels within Chebyshev distance `padding`
// of a covered texel are filled (none beyond), each with the average of its filled
// 8-neighbours; covered texels never change; the result is independent of the thread count.
#include "bake/dilation.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdlib>
#include <vector>

#include "bake/texel_rasterizer.h"
#include "scene/scene_test_meshes.h"
#include "support/expect_error.h"
#include "util/error.h"
#include "util/rng.h"

namespace shgi {
namespace {

using testing::expect_contains;
using testing::rejection;

// Chebyshev distance from texel (x, y) to the nearest covered texel (brute force).
uint32_t distance_to_covered(const std::vector<uint8_t>& covered, uint32_t width,
                             uint32_t height, uint32_t x, uint32_t y) {
    uint32_t best = 0xFFFFFFFFu;
    for (uint32_t cy = 0; cy < height; ++cy)
        for (uint32_t cx = 0; cx < width; ++cx)
            if (covered[cy * width + cx])
                best = std::min(best, uint32_t(std::max(std::abs(int(cx) - int(x)),
                                                        std::abs(int(cy) - int(y)))));
    return best;
}

TEST(Dilation, FillsEveryEmptyTexelWithinThePaddingAndNoneBeyond) {
    const uint32_t width = 24, height = 20, channels = 3, padding = 3;
    std::vector<uint8_t> covered(width * height, 0);
    // A lone texel, a 3 x 2 block and a texel on the border.
    for (auto [x, y] : {std::pair{4u, 4u}, {15u, 12u}, {16u, 12u}, {17u, 12u}, {15u, 13u},
                        {16u, 13u}, {17u, 13u}, {23u, 0u}})
        covered[y * width + x] = 1;
    const vec3 radiance(0.25f, 0.5f, 2.0f);  // every covered texel the same: fills must match
    std::vector<float> values(width * height * channels, 0.0f);
    for (uint32_t t = 0; t < width * height; ++t)
        if (covered[t])
            for (uint32_t c = 0; c < channels; ++c) values[t * channels + c] = radiance[c];

    std::vector<uint8_t> filled = covered;
    DilationSettings settings;
    settings.padding = padding;
    const uint64_t count = dilate(width, height, channels, values, filled, settings);

    uint64_t expected_count = 0;
    for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x) {
            const uint32_t t = y * width + x;
            const uint32_t distance = distance_to_covered(covered, width, height, x, y);
            const bool within = distance <= padding;
            expected_count += within && distance > 0;
            EXPECT_EQ(filled[t], within ? 1 : 0) << "texel (" << x << ", " << y << ")";
            for (uint32_t c = 0; c < channels; ++c)
                EXPECT_EQ(values[t * channels + c], within ? radiance[c] : 0.0f)
                    << "texel (" << x << ", " << y << ")";
        }
    EXPECT_EQ(count, expected_count);
}

TEST(Dilation, AveragesTheFilledEightNeighbours) {
    // 3 x 3, covered: left column 1, 2, 3 (bottom to top), right-top corner 10.
    std::vector<float> values = {1, 0, 0, 2, 0, 0, 3, 0, 10};
    std::vector<uint8_t> filled = {1, 0, 0, 1, 0, 0, 1, 0, 1};
    DilationSettings settings;
    settings.padding = 1;
    EXPECT_EQ(dilate(3, 3, 1, values, filled, settings), 4u);
    EXPECT_FLOAT_EQ(values[1], (1.0f + 2.0f) / 2.0f);                 // (1, 0)
    EXPECT_FLOAT_EQ(values[4], (1.0f + 2.0f + 3.0f + 10.0f) / 4.0f);  // centre: diagonals too
    EXPECT_FLOAT_EQ(values[7], (2.0f + 3.0f + 10.0f) / 3.0f);         // (1, 2)
    EXPECT_FLOAT_EQ(values[5], 10.0f);                                // (2, 1): the corner
    EXPECT_FLOAT_EQ(values[2], 0.0f);  // (2, 0): no filled neighbour before this pass...
    EXPECT_EQ(filled[2], 0);
    EXPECT_EQ(filled[8], 1);
    // ...and is filled by the next pass from (1, 0), (1, 1) and (2, 1).
    EXPECT_EQ(dilate(3, 3, 1, values, filled, settings), 1u);
    EXPECT_FLOAT_EQ(values[2], (values[1] + values[4] + values[5]) / 3.0f);
}

TEST(Dilation, CoveredTexelsAndZeroPaddingLeaveEverythingAlone) {
    std::vector<float> values = {1, 2, 3, 4};
    std::vector<uint8_t> filled = {1, 0, 0, 1};
    DilationSettings settings;
    settings.padding = 0;
    EXPECT_EQ(dilate(2, 2, 1, values, filled, settings), 0u);
    EXPECT_EQ(values, (std::vector<float>{1, 2, 3, 4}));
    settings.padding = 5;
    EXPECT_EQ(dilate(2, 2, 1, values, filled, settings), 2u);
    EXPECT_EQ(values[0], 1.0f);
    EXPECT_EQ(values[3], 4.0f);
}

TEST(Dilation, PadsARasterizedChartSoBilinearReadsNoEmptyTexel) {
    // A triangle's lightmap coverage, dilated by one texel: every texel a bilinear lookup at a
    // sample inside the triangle reads (the 2 x 2 around it) is filled.
    Mesh mesh = test::unit_quad();
    mesh.triangles = {{0, 1, 2}};
    mesh.uv_sets[0].coords = {{0.2f, 0.2f}, {0.8f, 0.3f}, {0.4f, 0.75f}, {0.0f, 0.0f}};
    TexelRasterSettings raster;
    raster.width = raster.height = 32;
    raster.uv_set = "UVMap";
    const TexelMap map = rasterize_texels(mesh, mat4(1.0f), raster);
    std::vector<uint8_t> filled(map.texel_count());
    for (uint64_t t = 0; t < map.texel_count(); ++t) filled[t] = map.covered(t);
    std::vector<float> values(map.texel_count(), 0.0f);
    for (uint64_t t = 0; t < map.texel_count(); ++t) values[t] = filled[t] ? 1.0f : 0.0f;
    DilationSettings settings;
    settings.padding = 1;
    dilate(map.width, map.height, 1, values, filled, settings);
    for (const TexelSample& sample : map.samples) {
        const vec2 texel = sample.uv * 32.0f - 0.5f;  // bilinear footprint's lower-left texel
        const int x0 = int(std::floor(texel.x)), y0 = int(std::floor(texel.y));
        for (int y = y0; y <= y0 + 1; ++y)
            for (int x = x0; x <= x0 + 1; ++x) EXPECT_EQ(values[y * 32 + x], 1.0f);
    }
}

TEST(Dilation, IdenticalForAnyThreadCount) {
    const uint32_t width = 64, height = 48, channels = 4;
    Pcg32 rng(7);
    std::vector<float> values(width * height * channels);
    std::vector<uint8_t> covered(width * height);
    for (uint8_t& c : covered) c = rng.next_float() < 0.05f;
    for (float& v : values) v = rng.next_float();
    const auto run = [&](int threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        std::vector<float> out = values;
        std::vector<uint8_t> filled = covered;
        dilate(width, height, channels, out, filled, DilationSettings{});
        return std::pair{out, filled};
    };
    EXPECT_EQ(run(1), run(8));
}

TEST(Dilation, RejectsSizesThatDoNotMatch) {
    std::vector<float> values(12);
    std::vector<uint8_t> filled(4);
    expect_contains(rejection([&] { dilate(2, 2, 2, values, filled, DilationSettings{}); }),
                    "values has 12 floats but width * height * channels = 8");
    expect_contains(rejection([&] { dilate(2, 3, 2, values, filled, DilationSettings{}); }),
                    "filled has 4 flags but width * height = 6");
    expect_contains(rejection([&] { dilate(0, 2, 2, values, filled, DilationSettings{}); }),
                    "width = 0");
}

}  // namespace
}  // namespace shgi
