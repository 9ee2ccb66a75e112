#include "propagation/propagation_field.h"

#include <utility>

namespace shgi {

PropagationField::PropagationField(std::shared_ptr<const ShVolume> accumulated,
                                   float normal_offset)
    : accumulated_(std::move(accumulated)), normal_offset_(normal_offset) {
    if (!accumulated_) return;
    const float s = accumulated_->cell_size();
    radiance_scale_ = propagation_radiance_scale(accumulated_->order()) / (s * s);
}

ShRgb PropagationField::radiance_sh(const vec3& p, const vec3& n) const {
    if (is_zero()) return ShRgb(1);
    ShRgb sh =
        accumulated_->sample_trilinear(p + normal_offset_ * accumulated_->cell_size() * n);
    // I(−ω): odd bands change sign.
    for (int i = 0; i < sh.num_coefficients(); ++i) {
        const bool odd = i >= 1 && i < 4;
        sh[i] *= odd ? -radiance_scale_ : radiance_scale_;
    }
    return sh;
}

}  // namespace shgi
