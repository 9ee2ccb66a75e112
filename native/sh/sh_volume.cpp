#include "sh/sh_volume.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "util/error.h"
#include "util/memory.h"

namespace shgi {
namespace {

constexpr int kMaxFloatsPerCell = 3 * sh_num_coefficients(kMaxShVolumeOrder);
const char* const kClassName = "ShVolume";

std::string format_vec(const vec3& v) { return format_message("(", v.x, ", ", v.y, ", ", v.z, ")"); }
std::string format_vec(const ivec3& v) {
    return format_message("(", v.x, ", ", v.y, ", ", v.z, ")");
}

// Weighted sum of cells, kept in a fixed-size array (no heap on the sampling path).
class CellBlend {
  public:
    explicit CellBlend(const ShVolume& volume) : volume_(volume), floats_(volume.floats_per_cell()) {}

    void add(size_t cell, float weight) {
        const float* data = volume_.cell_data(cell);
        for (int i = 0; i < floats_; ++i) sum_[i] += weight * data[i];
        total_ += weight;
    }
    // Σ w_c L(c) / Σ w_c, or zero when no weight was positive.
    ShRgb normalised() const {
        ShRgb out(volume_.order());
        if (!(total_ > 0.0f)) return out;
        const float inv_total = 1.0f / total_;
        float* data = out.data();
        for (int i = 0; i < floats_; ++i) data[i] = sum_[i] * inv_total;
        return out;
    }

  private:
    const ShVolume& volume_;
    int floats_;
    std::array<float, kMaxFloatsPerCell> sum_{};
    float total_ = 0.0f;
};

}  // namespace

ShVolume::ShVolume(const vec3& origin, float cell_size, const ivec3& counts, int order)
    : origin_(origin), cell_size_(cell_size), counts_(counts), order_(order) {
    if (!is_finite(origin))
        throw InvalidArgument(format_message(kClassName, ": origin = ", format_vec(origin),
                                             " must be finite"));
    if (!std::isfinite(cell_size) || !(cell_size > 0.0f))
        throw InvalidArgument(format_message(kClassName, ": cell_size = ", cell_size,
                                             " m must be finite and positive"));
    if (glm::any(glm::lessThan(counts, ivec3(1))))
        throw InvalidArgument(format_message(kClassName, ": counts = ", format_vec(counts),
                                             " must each be at least 1"));
    const uint64_t cells = uint64_t(counts.x) * uint64_t(counts.y) * uint64_t(counts.z);
    if (cells > kMaxShVolumeCells)
        throw InvalidArgument(format_message(kClassName, ": counts = ", format_vec(counts),
                                             " make ", cells, " cells; at most ",
                                             kMaxShVolumeCells, " are allowed (use larger cells)"));
    const vec3 far_corner = origin + vec3(counts) * cell_size;
    if (!is_finite(far_corner))
        throw InvalidArgument(format_message(kClassName, ": origin = ", format_vec(origin),
                                             " + counts × cell_size = ", format_vec(far_corner),
                                             " must be finite"));
    if (order < 0 || order > kMaxShVolumeOrder)
        throw InvalidArgument(format_message(kClassName, ": order = ", order, " must be 0, 1 or ",
                                             kMaxShVolumeOrder, " (1 to 3 SH bands)"));
    const uint64_t floats = cells * uint64_t(floats_per_cell());
    require_memory(saturating_mul(floats, sizeof(float)),
                   format_message(kClassName, " counts = ", format_vec(counts), " at order ",
                                  order),
                   "use larger cells or a lower order");
    coefficients_.assign(floats, 0.0f);
}

void ShVolume::check_cell(const ivec3& cell, const char* what) const {
    if (!contains(cell))
        throw InvalidArgument(format_message(kClassName, "::", what, ": cell = ",
                                             format_vec(cell), " is outside counts = ",
                                             format_vec(counts_)));
}

ShRgb ShVolume::cell_coefficients(const ivec3& cell) const {
    check_cell(cell, "cell_coefficients");
    ShRgb out(order_);
    std::copy_n(cell_data(cell_index(cell)), floats_per_cell(), out.data());
    return out;
}

void ShVolume::set_cell_coefficients(const ivec3& cell, const ShRgb& coefficients) {
    check_cell(cell, "set_cell_coefficients");
    if (coefficients.order != order_)
        throw InvalidArgument(format_message(kClassName, "::set_cell_coefficients: coefficients "
                                             "of order ", coefficients.order,
                                             " given to a volume of order ", order_));
    std::copy_n(coefficients.data(), floats_per_cell(), cell_data(cell_index(cell)));
}

// Cell centres sit at half-integer cell coordinates; f = q − ½ puts them on integers, clamped to
// [0, n − 1] so that outside points take the boundary values. base is the lower of the two
// centres on each axis (n − 2 at the upper end, so t reaches 1 there; 0 with t = 0 for n = 1).
ShRgb ShVolume::sample_trilinear(const vec3& p) const {
    if (!is_finite(p) || coefficients_.empty()) return ShRgb(order_);
    const vec3 upper(counts_ - 1);
    const vec3 f = glm::clamp((p - origin_) / cell_size_ - 0.5f, vec3(0.0f), upper);
    const ivec3 base = glm::clamp(ivec3(glm::floor(f)), ivec3(0), glm::max(counts_ - 2, 0));
    const vec3 t = f - vec3(base);
    const ivec3 top = glm::min(base + 1, counts_ - 1);
    CellBlend blend(*this);
    for (int dz = 0; dz < 2; ++dz) {
        const float wz = dz == 0 ? 1.0f - t.z : t.z;
        for (int dy = 0; dy < 2; ++dy) {
            const float wyz = (dy == 0 ? 1.0f - t.y : t.y) * wz;
            for (int dx = 0; dx < 2; ++dx) {
                const float w = (dx == 0 ? 1.0f - t.x : t.x) * wyz;
                if (!(w > 0.0f)) continue;  // also skips the missing upper cell when n = 1
                const ivec3 cell(dx ? top.x : base.x, dy ? top.y : base.y, dz ? top.z : base.z);
                blend.add(cell_index(cell), w);
            }
        }
    }
    return blend.normalised();
}

// The block around the cell holding q; q is clamped into [0, n] (the far faces belong to the
// last cell), so that block is never empty and the normalisation never divides by zero.
ShRgb ShVolume::sample_cubic(const vec3& p) const {
    if (!is_finite(p) || coefficients_.empty()) return ShRgb(order_);
    const vec3 q = glm::clamp((p - origin_) / cell_size_, vec3(0.0f), vec3(counts_));
    const ivec3 centre = glm::min(ivec3(glm::floor(q)), counts_ - 1);
    const ivec3 lo = glm::max(centre - 1, ivec3(0));
    const ivec3 hi = glm::min(centre + 1, counts_ - 1);
    CellBlend blend(*this);
    ivec3 cell;
    for (cell.z = lo.z; cell.z <= hi.z; ++cell.z)
        for (cell.y = lo.y; cell.y <= hi.y; ++cell.y)
            for (cell.x = lo.x; cell.x <= hi.x; ++cell.x) {
                const float d = glm::length(q - (vec3(cell) + 0.5f));
                const float w = cubic_falloff(d);
                if (w > 0.0f) blend.add(cell_index(cell), w);
            }
    return blend.normalised();
}

}  // namespace shgi
