#include "propagation/propagation_field.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <utility>

#include "io/image.h"
#include "sh/sh_irradiance.h"
#include "util/binary_file.h"
#include "util/error.h"
#include "util/memory.h"

namespace shgi {
namespace {

constexpr char kFieldMagic[8] = {'S', 'H', 'G', 'I', 'L', 'P', 'V', '\0'};
constexpr uint32_t kFieldFileVersion = 1;
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
    : accumulated_(std::move(accumulated)),
      transmittance_(std::move(transmittance)),
      normal_offset_(normal_offset),
      damping_(damping),
      reinjection_(reinjection) {
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

void PropagationField::save(const std::string& path) const {
    write_file_atomically(path, [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        BinaryWriter w(out);
        w.header(kFieldMagic, kFieldFileVersion);
        w.put(normal_offset_);
        w.put(uint8_t(damping_));
        w.put(uint8_t(reinjection_));
        w.put(uint8_t(accumulated_ != nullptr));
        if (accumulated_) {
            w.put(accumulated_->origin());
            w.put(accumulated_->cell_size());
            w.put(accumulated_->counts());
            w.put(int32_t(accumulated_->order()));
            w.array(accumulated_->coefficients());
        }
        w.array(transmittance_ ? *transmittance_ : NeighbourTransmittance{});
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
    r.header(kFieldMagic, kFieldFileVersion, kFieldFileVersion);
    const float normal_offset = r.get<float>("the header");
    const uint8_t damping = r.get<uint8_t>("the header");
    const uint8_t reinjection = r.get<uint8_t>("the header");
    const uint8_t has_volume = r.get<uint8_t>("the header");
    if (!std::isfinite(normal_offset) || normal_offset < 0.0f || damping > 1 ||
        reinjection > uint8_t(Reinjection::TravelDirection) || has_volume > 1)
        throw bad("its header is damaged (normal offset ", normal_offset, ", flags ",
                  int(damping), ", ", int(reinjection), ", ", int(has_volume), ")");
    std::shared_ptr<ShVolume> volume;
    if (has_volume) {
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
    }
    auto transmittance =
        std::make_shared<NeighbourTransmittance>(r.array<float>("the transmittance"));
    if (!transmittance->empty()) {
        if (!volume || transmittance->size() != kNeighbours * volume->cell_count())
            throw bad("the transmittance holds ", transmittance->size(), " values for ",
                      volume ? volume->cell_count() : 0, " cells (", kNeighbours, " per cell)");
        for (float t : *transmittance)
            if (!(t >= 0.0f && t <= 1.0f))
                throw bad("the transmittance holds a value outside [0, 1]");
    }
    if (in.peek() != std::ifstream::traits_type::eof()) throw bad("it has data after its end");
    return std::make_unique<PropagationField>(
        std::move(volume), normal_offset, transmittance->empty() ? nullptr : transmittance,
        damping != 0, Reinjection(reinjection));
}

}  // namespace shgi
