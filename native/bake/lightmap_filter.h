// Finishing a baked lightmap: an optional edge-aware denoising filter that never crosses UV
// charts, then dilation into the padding (bake/dilation.h).
//
// The filter is an edge-avoiding a-trous wavelet filter (Dammertz et al. 2010, "Edge-Avoiding
// A-Trous Wavelet Transform for fast Global Illumination Filtering"), with SVGF's luminance
// weight scaled by the estimated standard deviation (Schied et al. 2017), run in texel space:
// `iterations` passes of the 5 x 5 B3-spline kernel with holes 1, 2, 4, ... texels apart. A
// neighbour q of texel p counts only when it was baked, lies in the same UV chart
// (TexelMap::chart: texels of different charts are neighbours only in UV space, so a seam never
// bleeds) and with weight
//   h(dx) h(dy) * max(0, n_p . n_q)^normal_power
//              * exp(-|(x_q - x_p) . n_p| / (position_sigma * texel_size_p))
//              * exp(-|l_q - l_p| / (luminance_sigma * sqrt(var_p) + epsilon)),
// n, x = the texel's mean sample normal and position, l = luminance, var = the texel's variance
// (filtered along, as SVGF does: var' = sum w^2 var / (sum w)^2). Following seed 004 (Segovia &
// Wald), the directional data is filtered as incident-radiance SH with the same weights rather
// than as irradiance, so normal-mapped shading keeps its detail.
//
// Deterministic (Jacobi passes, fixed order of additions), any thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "bake/dilation.h"
#include "bake/lightmap_baker.h"
#include "bake/texel_rasterizer.h"
#include "util/progress.h"

namespace shgi {

// A texel's samples averaged by weight: position (m), unit normal and texel size (m); zero
// position and +Z normal where nothing is covered.
struct TexelGeometry {
    vec3 position{0.0f};
    vec3 normal{0.0f, 0.0f, 1.0f};
    float texel_size = 0.0f;
};
std::vector<TexelGeometry> texel_geometry(const TexelMap& map);
TexelGeometry texel_geometry(const TexelMap& map, uint64_t texel);  // one texel's

struct LightmapFilterSettings {
    // A-trous passes, 0 = off; k passes span 4 * 2^k - 3 texels. Two keep the light's own
    // gradients (a blur is a bias where the light changes within a few texels).
    uint32_t iterations = 2;
    float normal_power = 64.0f;   // sharpness of the normal weight
    float position_sigma = 1.0f;  // texels of distance off the texel's plane before 1/e
    float luminance_sigma = 4.0f;  // standard deviations of luminance difference before 1/e
};

void validate_lightmap_filter_settings(const LightmapFilterSettings& settings);

// Filters `texels` in place (color, sh, variance of the baked texels). `map` is the texel map
// they were baked from. Throws InvalidArgument for sizes that do not match or bad settings.
void filter_lightmap(const TexelMap& map, LightmapTexels& texels,
                     const LightmapFilterSettings& settings, Progress* progress = nullptr);

// Dilates color, sh and variance of `texels` in place from the baked texels into the padding;
// returns the mask of texels that hold a value (baked or filled).
std::vector<uint8_t> dilate_lightmap(LightmapTexels& texels, const DilationSettings& settings,
                                     Progress* progress = nullptr);

}  // namespace shgi
