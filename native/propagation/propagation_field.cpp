#include "propagation/propagation_field.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <utility>

#include "io/image.h"
#include "sh/sh_irradiance.h"
#include "util/binary_file.h"
#include "util/error.h"
#include "util/memory.h"

namespace shgi {
namespace {

constexpr char kFieldMagic[8] = {'S', 'H', 'G', 'I', 'L', 'P', 'V', '\0'};
// 2: levels (cascades); 1 (read): a single volume.
constexpr uint32_t kFieldFileVersion = 2;
constexpr const char* kFieldFile = "propagation field file";
constexpr int kNeighbours = 26;

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
    : normal_offset_(normal_offset), damping_(damping), reinjection_(reinjection) {
    if (accumulated) levels_.push_back({std::move(accumulated), std::move(transmittance), 0});
}

PropagationField::PropagationField(std::vector<PropagationLevel> levels, float normal_offset,
                                   bool damping, Reinjection reinjection)
    : levels_(std::move(levels)),
      normal_offset_(normal_offset),
      damping_(damping),
      reinjection_(reinjection) {
    for (size_t i = 0; i < levels_.size(); ++i) {
        const PropagationLevel& level = levels_[i];
        if (!level.accumulated)
            throw InvalidArgument(format_message("PropagationField: level ", i, " has no volume"));
        if (level.accumulated->order() != levels_.front().accumulated->order())
            throw InvalidArgument(format_message("PropagationField: level ", i, " is of order ",
                                                 level.accumulated->order(), ", level 0 of ",
                                                 levels_.front().accumulated->order()));
        if (level.transmittance && level.transmittance->size() !=
                                       size_t(kNeighbours) * level.accumulated->cell_count())
            throw InvalidArgument(format_message("PropagationField: level ", i, "'s ",
                                                 "transmittance holds ",
                                                 level.transmittance->size(), " values for ",
                                                 level.accumulated->cell_count(), " cells"));
        if (level.blend_faces > 63 || (i + 1 == levels_.size() && level.blend_faces != 0))
            throw InvalidArgument(format_message("PropagationField: level ", i,
                                                 " has blend faces ", int(level.blend_faces),
                                                 " (6 bits; none on the coarsest level)"));
    }
}

const std::shared_ptr<const ShVolume>& PropagationField::accumulated() const {
    static const std::shared_ptr<const ShVolume> none;
    return levels_.empty() ? none : levels_.back().accumulated;
}

ShRgb PropagationField::weighted_lookup(const PropagationLevel& level, const vec3& q) const {
    const ShVolume& volume = *level.accumulated;
    const NeighbourTransmittance* transmittance = level.transmittance.get();
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
        if (transmittance && cell != home)
            w *= (*transmittance)[index * 26 + size_t(neighbour_index(cell - home))];
        if (!(w > 0.0f)) continue;
        total += w;
        const float* data = volume.cell_data(index);
        for (int i = 0; i < floats; ++i) sh.data()[i] += w * data[i];
    }
    if (!(total > 0.0f)) return ShRgb(volume.order());
    // Normalised, and I(−ω): odd bands change sign. k / s².
    const float s = volume.cell_size();
    const float radiance_scale = propagation_radiance_scale(volume.order(), reinjection_) / (s * s);
    for (int i = 0; i < sh.num_coefficients(); ++i) {
        const bool odd = i >= 1 && i < 4;
        sh[i] *= (odd ? -radiance_scale : radiance_scale) / total;
    }
    return sh;
}

float PropagationField::level_weight(size_t level, const vec3& q) const {
    const PropagationLevel& l = levels_.at(level);
    if (l.blend_faces == 0) return 1.0f;
    const ShVolume& volume = *l.accumulated;
    const float s = volume.cell_size();
    // In cells from the lower corner of the level's box (the volume less its outer half cells).
    const vec3 c = (q - volume.origin()) / s - 0.5f;
    if (!is_finite(c)) return 0.0f;
    const vec3 cells = vec3(volume.counts() - 1);
    float d = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
        if (l.blend_faces & (1u << a)) d = std::min(d, c[a]);
        if (l.blend_faces & (8u << a)) d = std::min(d, cells[a] - c[a]);
    }
    return std::clamp((d - kCascadeMarginCells) / kCascadeBlendCells, 0.0f, 1.0f);
}

ShRgb PropagationField::level_radiance_sh(size_t level, const vec3& p, const vec3& n) const {
    const PropagationLevel& l = levels_.at(level);
    const float s = l.accumulated->cell_size();
    const vec3 q = p + normal_offset_ * s * n;
    ShRgb sh = weighted_lookup(l, q);
    if (!damping_) return sh;
    // §3.2.4: the light arriving along −n half a cell in front of q and half a cell behind it.
    // Light from a source in front of the surface weakens towards the surface or stays; where it
    // is stronger behind (towards and into the surface), it is the surface's own light or light
    // from behind a wall, and the lookup is damped by front / back.
    const float front = luminance(sh_irradiance(weighted_lookup(l, q + 0.5f * s * n), n));
    const float back = luminance(sh_irradiance(weighted_lookup(l, q - 0.5f * s * n), n));
    if (!(back > front)) return sh;
    const float factor = std::max(0.0f, front) / back;
    for (int i = 0; i < sh.num_coefficients(); ++i) sh[i] *= factor;
    return sh;
}

ShRgb PropagationField::radiance_sh(const vec3& p, const vec3& n) const {
    if (is_zero()) return ShRgb(1);
    if (levels_.size() == 1) return level_radiance_sh(0, p, n);
    // The finest level that covers p with weight w, the rest from the coarser ones.
    ShRgb sh(levels_.front().accumulated->order());
    float remaining = 1.0f;
    for (size_t level = 0; level < levels_.size() && remaining > 0.0f; ++level) {
        const float s = levels_[level].accumulated->cell_size();
        const float w = level_weight(level, p + normal_offset_ * s * n);
        if (!(w > 0.0f)) continue;
        sh_add_scaled(sh, level_radiance_sh(level, p, n), remaining * w);
        remaining *= 1.0f - w;
    }
    return sh;
}

void PropagationField::save(const std::string& path) const {
    write_file_atomically(path, [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        BinaryWriter w(out);
        w.header(kFieldMagic, kFieldFileVersion);
        w.put(normal_offset_);
        w.put(uint8_t(damping_));
        w.put(uint8_t(reinjection_));
        w.put(uint32_t(levels_.size()));
        for (const PropagationLevel& level : levels_) {
            w.put(level.blend_faces);
            const ShVolume& volume = *level.accumulated;
            w.put(volume.origin());
            w.put(volume.cell_size());
            w.put(volume.counts());
            w.put(int32_t(volume.order()));
            w.array(volume.coefficients());
            w.array(level.transmittance ? *level.transmittance : NeighbourTransmittance{});
        }
        out.flush();
        if (!out) throw IoError(format_message("cannot write ", kFieldFile, " \"", path, "\""));
    });
}

std::unique_ptr<PropagationField> PropagationField::load(const std::string& path) {
    require_readable_file(path, kFieldFile);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(format_message("cannot open ", kFieldFile, " \"", path, "\""));
    BinaryReader r(in, path, kFieldFile);
    const auto bad = [&](const auto&... what) {
        return IoError(format_message(kFieldFile, " \"", path, "\": ", what...));
    };
    // Version 1: a single volume (a flag, then the volume), its transmittance after it.
    const uint32_t version = r.header(kFieldMagic, 1, kFieldFileVersion);
    const float normal_offset = r.get<float>("the header");
    const uint8_t damping = r.get<uint8_t>("the header");
    const uint8_t reinjection = r.get<uint8_t>("the header");
    const uint32_t count = version == 1 ? uint32_t(r.get<uint8_t>("the header"))
                                        : r.get<uint32_t>("the header");
    if (!std::isfinite(normal_offset) || normal_offset < 0.0f || damping > 1 ||
        reinjection > uint8_t(Reinjection::WindowedTravelDirection) ||
        count > (version == 1 ? 1u : uint32_t(kMaxPropagationLevels)))
        throw bad("its header is damaged (normal offset ", normal_offset, ", flags ",
                  int(damping), ", ", int(reinjection), ", ", count, " levels)");
    const auto read_volume = [&]() {
        const vec3 origin = r.get<vec3>("the volume");
        const float cell_size = r.get<float>("the volume");
        const ivec3 counts = r.get<ivec3>("the volume");
        const int32_t order = r.get<int32_t>("the volume");
        // The coefficients must be in the file before the volume is allocated for them.
        if (counts.x <= 0 || counts.y <= 0 || counts.z <= 0 || order < 0 || order > 4)
            throw bad("its volume has ", counts.x, " x ", counts.y, " x ", counts.z,
                      " cells of order ", order);
        const uint64_t floats = saturating_mul(
            saturating_mul(uint64_t(counts.x) * uint64_t(counts.y), uint64_t(counts.z)),
            uint64_t(3 * sh_num_coefficients(order)));
        if (floats > r.remaining_bytes() / sizeof(float))
            throw bad("its ", counts.x, " x ", counts.y, " x ", counts.z,
                      " cells need more coefficients than the file holds (truncated?)");
        std::shared_ptr<ShVolume> volume;
        try {
            volume = std::make_shared<ShVolume>(origin, cell_size, counts, order);
        } catch (const InvalidArgument& e) {
            throw bad("its volume is not valid: ", e.what());
        }
        const std::vector<float> coefficients = r.array<float>("the volume's coefficients");
        if (coefficients.size() != volume->coefficients().size())
            throw bad("the volume holds ", coefficients.size(), " coefficients, its ",
                      counts.x, " x ", counts.y, " x ", counts.z, " cells need ",
                      volume->coefficients().size());
        for (float c : coefficients)
            if (!std::isfinite(c)) throw bad("the volume holds a coefficient that is not finite");
        if (!coefficients.empty())
            std::memcpy(volume->cell_data(0), coefficients.data(),
                        coefficients.size() * sizeof(float));
        return volume;
    };
    const auto read_transmittance = [&](const std::shared_ptr<ShVolume>& volume)
        -> std::shared_ptr<const NeighbourTransmittance> {
        auto transmittance =
            std::make_shared<NeighbourTransmittance>(r.array<float>("the transmittance"));
        if (transmittance->empty()) return nullptr;
        if (!volume || transmittance->size() != kNeighbours * volume->cell_count())
            throw bad("the transmittance holds ", transmittance->size(), " values for ",
                      volume ? volume->cell_count() : 0, " cells (", kNeighbours, " per cell)");
        for (float t : *transmittance)
            if (!(t >= 0.0f && t <= 1.0f))
                throw bad("the transmittance holds a value outside [0, 1]");
        return transmittance;
    };
    std::vector<PropagationLevel> levels;
    if (version == 1) {
        std::shared_ptr<ShVolume> volume = count ? read_volume() : nullptr;
        auto transmittance = read_transmittance(volume);
        if (volume) levels.push_back({std::move(volume), std::move(transmittance), 0});
    } else {
        for (uint32_t i = 0; i < count; ++i) {
            const uint8_t faces = r.get<uint8_t>("a level");
            std::shared_ptr<ShVolume> volume = read_volume();
            auto transmittance = read_transmittance(volume);
            levels.push_back({std::move(volume), std::move(transmittance), faces});
        }
    }
    if (in.peek() != std::ifstream::traits_type::eof()) throw bad("it has data after its end");
    try {
        return std::make_unique<PropagationField>(std::move(levels), normal_offset, damping != 0,
                                                  Reinjection(reinjection));
    } catch (const InvalidArgument& e) {
        throw bad("its levels do not fit together: ", e.what());
    }
}

}  // namespace shgi
