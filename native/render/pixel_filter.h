// Film > Pixel Filter as Cycles' (scene/film.cpp): where around its pixel a camera sample lands.
//
// Filter importance sampling: a sample's film offset is drawn from the filter along x and along
// y separately (the 2-D filter is the product of two 1-D ones, as Cycles'), and every sample
// counts once in its own pixel, so a pixel's mean is the image convolved with the filter.
// Widths mean what Cycles' Filter Size means (filter_table's pre-scale): Box of width w spans
// [-w/2, w/2]; Gaussian of width w has sigma w/4 and is cut at +-1.5 w (exp(-2 (6 v / 3w)^2));
// Blackman-Harris of width w spans [-w, w] (0.35875 - 0.48829 cos + 0.14128 cos 2 - 0.01168 cos 3
// over that span). Cycles' default, Blackman-Harris 1.5, spans three pixels; SHGI's native
// default stays the box of one pixel, whose offset is the stratified jitter itself (bit for bit
// the images before the filter existed).
//
// Sampling: the forward CDF of the filter is tabulated on kPixelFilterTableSize uniform bins of
// the span (each bin's density the filter at its centre) and inverted by binary search and
// linear interpolation, which samples that piecewise-constant density exactly. (Cycles tables
// the inverse CDF on a uniform grid of u instead, which over-fills the near-zero tails.)
#pragma once

#include <cstdint>
#include <vector>

#include "util/math.h"

namespace shgi {

enum class PixelFilterType : uint8_t { Box, Gaussian, BlackmanHarris };

// Cycles' Filter Size range (pixels).
inline constexpr float kMinFilterWidth = 0.01f;
inline constexpr float kMaxFilterWidth = 10.0f;
inline constexpr int kPixelFilterTableSize = 1024;

// Throws InvalidArgument naming `owner`.filter_width when width is not finite or outside
// [kMinFilterWidth, kMaxFilterWidth].
void validate_filter_width(float width, const char* owner);

class PixelFilter {
  public:
    explicit PixelFilter(PixelFilterType type = PixelFilterType::Box, float width = 1.0f);

    // The film offset from a pixel's corner of a sample whose stratified numbers are `u` (in
    // [0, 1)^2): `u` itself for the box of one pixel, else 0.5 + an offset drawn from the
    // filter per axis.
    vec2 film_offset(const vec2& u) const {
        if (identity_) return u;
        return vec2(0.5f + offset(u.x), 0.5f + offset(u.y));
    }
    // One axis's offset from the pixel's centre, in [-half_span(), half_span()].
    float offset(float u) const;
    // Half the filter's span in pixels.
    float half_span() const { return half_span_; }
    // The sampled 1-D density at `offset` (normalised over the span; 0 outside it).
    float density(float offset) const;

  private:
    PixelFilterType type_;
    bool identity_;      // the box of one pixel: the jitter is the offset
    float half_span_;
    std::vector<float> cdf_;  // kPixelFilterTableSize + 1 values, 0 to 1 (not the box's)
};

}  // namespace shgi
