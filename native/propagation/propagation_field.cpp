#include "propagation/propagation_field.h"

#include <algorithm>
#include <utility>

#include "sh/sh_irradiance.h"

namespace shgi {
namespace {

// Index of offset d (each component −1, 0 or 1, not all 0) in propagation_offsets(Neighbours26)'s
// order: z, then y, then x from −1 to 1, the zero offset left out.
int neighbour_index(const ivec3& d) {
    const int flat = (d.z + 1) * 9 + (d.y + 1) * 3 + (d.x + 1);
    return flat < 13 ? flat : flat - 1;
}

}  // namespace

PropagationField::PropagationField(std::shared_ptr<const ShVolume> accumulated,
                                   float normal_offset,
                                   std::shared_ptr<const NeighbourTransmittance> transmittance,
                                   bool damping, Reinjection reinjection)
    : accumulated_(std::move(accumulated)),
      transmittance_(std::move(transmittance)),
      normal_offset_(normal_offset),
      damping_(damping) {
    if (!accumulated_) return;
    const float s = accumulated_->cell_size();
    radiance_scale_ = propagation_radiance_scale(accumulated_->order(), reinjection) / (s * s);
}

ShRgb PropagationField::weighted_lookup(const vec3& q) const {
    const ShVolume& volume = *accumulated_;
    ShRgb sh(volume.order());
    if (!is_finite(q)) return sh;
    // ShVolume::sample_trilinear's cells and weights, each times the transmittance from the
    // cell holding q.
    const ivec3 counts = volume.counts();
    const vec3 f = glm::clamp((q - volume.origin()) / volume.cell_size() - 0.5f, vec3(0.0f),
                              vec3(counts - 1));
    const ivec3 base = glm::clamp(ivec3(glm::floor(f)), ivec3(0), glm::max(counts - 2, 0));
    const vec3 t = f - vec3(base);
    const ivec3 top = glm::min(base + 1, counts - 1);
    const ivec3 home = glm::clamp(ivec3(glm::floor(f + 0.5f)), base, top);
    float total = 0.0f;
    const int floats = volume.floats_per_cell();
    for (int corner = 0; corner < 8; ++corner) {
        const ivec3 bit(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        const vec3 w3 = glm::mix(vec3(1.0f) - t, t, vec3(bit));
        float w = w3.x * w3.y * w3.z;
        if (!(w > 0.0f)) continue;
        const ivec3 cell = glm::mix(base, top, glm::equal(bit, ivec3(1)));
        const size_t index = volume.cell_index(cell);
        if (transmittance_ && cell != home)
            w *= (*transmittance_)[index * 26 + size_t(neighbour_index(cell - home))];
        if (!(w > 0.0f)) continue;
        total += w;
        const float* data = volume.cell_data(index);
        for (int i = 0; i < floats; ++i) sh.data()[i] += w * data[i];
    }
    if (!(total > 0.0f)) return ShRgb(volume.order());
    // Normalised, and I(−ω): odd bands change sign.
    for (int i = 0; i < sh.num_coefficients(); ++i) {
        const bool odd = i >= 1 && i < 4;
        sh[i] *= (odd ? -radiance_scale_ : radiance_scale_) / total;
    }
    return sh;
}

ShRgb PropagationField::radiance_sh(const vec3& p, const vec3& n) const {
    if (is_zero()) return ShRgb(1);
    const float s = accumulated_->cell_size();
    const vec3 q = p + normal_offset_ * s * n;
    ShRgb sh = weighted_lookup(q);
    if (!damping_) return sh;
    // §3.2.4: the light arriving along −n half a cell in front of q and half a cell behind it.
    // Light from a source in front of the surface weakens towards the surface or stays; where it
    // is stronger behind (towards and into the surface), it is the surface's own light or light
    // from behind a wall, and the lookup is damped by front / back.
    const float front = luminance(sh_irradiance(weighted_lookup(q + 0.5f * s * n), n));
    const float back = luminance(sh_irradiance(weighted_lookup(q - 0.5f * s * n), n));
    if (!(back > front)) return sh;
    const float factor = std::max(0.0f, front) / back;
    for (int i = 0; i < sh.num_coefficients(); ++i) sh[i] *= factor;
    return sh;
}

}  // namespace shgi
