// Dilation: spreads lightmap values from covered texels into the empty texels around them, so
// that bilinear filtering (and mip-mapping) near a UV chart's border never reads an empty,
// black texel (the bake's `padding`, docs/baking.md step 4).
//
// Each pass fills every empty texel that has at least one filled 8-neighbour with the plain
// average of those neighbours, reading only what the previous passes left (Jacobi order), so
// the result does not depend on the traversal order or the thread count. After `padding` passes
// exactly the empty texels within Chebyshev distance `padding` of a covered texel are filled;
// texels farther away keep their values (usually 0) and stay empty.
//
// Layout: row-major texels (index y * width + x, the texel grid of bake/texel_rasterizer.h),
// `channels` interleaved floats per texel (e.g. 3 for RGB radiance, 12 for L1 SH RGB).
#pragma once

#include <cstdint>
#include <vector>

#include "util/progress.h"

namespace shgi {

struct DilationSettings {
    // Passes, i.e. how many texels beyond the charts get filled. Bilinear filtering needs 1;
    // each mip level halves the padding, so 2^levels texels keep that many levels clean.
    uint32_t padding = 4;
};

// Dilates `values` (width * height * channels floats) in place; `filled` (width * height, 0 or
// 1) marks the covered texels on input and the covered-or-filled ones on output. Returns the
// number of texels filled. Throws InvalidArgument for sizes that do not match; polls `progress`
// once per pass (Cancelled).
uint64_t dilate(uint32_t width, uint32_t height, uint32_t channels, std::vector<float>& values,
                std::vector<uint8_t>& filled, const DilationSettings& settings,
                Progress* progress = nullptr);

}  // namespace shgi
