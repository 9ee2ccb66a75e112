#include "render/pixel_filter.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"

namespace shgi {
namespace {

constexpr double kTwoPi = 6.283185307179586;

// Half the span the filter is tabulated over, from Cycles' width (filter_table's pre-scale:
// Gaussian x3, Blackman-Harris x2, over [-width / 2, width / 2]).
float half_span_of(PixelFilterType type, float width) {
    switch (type) {
        case PixelFilterType::Gaussian: return 1.5f * width;
        case PixelFilterType::BlackmanHarris: return width;
        case PixelFilterType::Box: break;
    }
    return 0.5f * width;
}

// The filter's weight at offset v from the pixel centre (Cycles' filter_func_*, with the span's
// width), unnormalised.
double weight(PixelFilterType type, double v, double half_span) {
    const double span = 2.0 * half_span;
    switch (type) {
        case PixelFilterType::Gaussian: {
            const double t = v * 6.0 / span;
            return std::exp(-2.0 * t * t);
        }
        case PixelFilterType::BlackmanHarris: {
            const double a = kTwoPi * (v / span + 0.5);
            return 0.35875 - 0.48829 * std::cos(a) + 0.14128 * std::cos(2.0 * a) -
                   0.01168 * std::cos(3.0 * a);
        }
        case PixelFilterType::Box: break;
    }
    return 1.0;
}

}  // namespace

void validate_filter_width(float width, const char* owner) {
    if (!std::isfinite(width) || width < kMinFilterWidth || width > kMaxFilterWidth)
        throw InvalidArgument(format_message(owner, ".filter_width is ", width,
                                             "; it must be in [", kMinFilterWidth, ", ",
                                             kMaxFilterWidth, "] pixels (Cycles' Filter Size)"));
}

PixelFilter::PixelFilter(PixelFilterType type, float width)
    : type_(type),
      identity_(type == PixelFilterType::Box && width == 1.0f),
      half_span_(half_span_of(type, width)) {
    validate_filter_width(width, "PixelFilter");
    if (type == PixelFilterType::Box) return;  // uniform: offset() needs no table
    // Running sums of the bins' weights (each the filter at the bin's centre), then normalised.
    std::vector<double> sums(size_t(kPixelFilterTableSize) + 1, 0.0);
    const double bin = 2.0 * double(half_span_) / kPixelFilterTableSize;
    for (int i = 0; i < kPixelFilterTableSize; ++i) {
        const double centre = -double(half_span_) + (i + 0.5) * bin;
        sums[size_t(i) + 1] = sums[size_t(i)] + std::max(0.0, weight(type, centre, half_span_));
    }
    cdf_.resize(sums.size());
    for (size_t i = 0; i < cdf_.size(); ++i) cdf_[i] = float(sums[i] / sums.back());
    cdf_.back() = 1.0f;
}

float PixelFilter::offset(float u) const {
    if (type_ == PixelFilterType::Box) return (u - 0.5f) * (2.0f * half_span_);
    // The bin holding u: cdf_[i] <= u < cdf_[i + 1] (empty bins are skipped by upper_bound).
    const auto above = std::upper_bound(cdf_.begin() + 1, cdf_.end() - 1, u);
    const size_t i = size_t(above - cdf_.begin()) - 1;
    const float low = cdf_[i], high = cdf_[i + 1];
    const float t = high > low ? std::clamp((u - low) / (high - low), 0.0f, 1.0f) : 0.5f;
    const float bin = 2.0f * half_span_ / float(kPixelFilterTableSize);
    return -half_span_ + (float(i) + t) * bin;
}

float PixelFilter::density(float offset) const {
    if (!(std::fabs(offset) <= half_span_)) return 0.0f;
    if (type_ == PixelFilterType::Box) return 0.5f / half_span_;
    const float bin = 2.0f * half_span_ / float(kPixelFilterTableSize);
    const int i = std::min(kPixelFilterTableSize - 1, int((offset + half_span_) / bin));
    return (cdf_[size_t(i) + 1] - cdf_[size_t(i)]) / bin;
}

}  // namespace shgi
