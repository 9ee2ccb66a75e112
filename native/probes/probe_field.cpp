#include "probes/probe_field.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "probes/probe_visibility.h"
#include "scene/ray.h"
#include "scene/validation.h"
#include "util/error.h"

namespace shgi {
namespace {

// DDGI's constants (Majercik et al. 2019, Listing 1): minimum visibility weight and the level
// below which weights are crushed.
constexpr float kMinVisibility = 0.05f;
constexpr float kCrushThreshold = 0.2f;
constexpr float kBackfaceFloor = 0.2f;

bool finite_sh(const ShRgb& sh) {
    for (int i = 0; i < sh.num_coefficients(); ++i)
        if (!is_finite(sh[i])) return false;
    return true;
}

}  // namespace

void validate_probe_volume(const ProbeVolume& volume, const char* what) {
    // The scene's object-transform checks: probe positions become ray origins, and lookups
    // invert the matrix.
    scene_detail::require_transform(what, "world_from_volume", volume.world_from_volume);
    const mat4& m = volume.world_from_volume;
    const double reach = double(max_abs_component(vec3(m[3]))) + glm::length(vec3(m[0])) +
                         glm::length(vec3(m[1])) + glm::length(vec3(m[2]));
    if (!(reach <= double(kMaxCoordinate)))
        throw InvalidArgument(format_message(
            what, ".world_from_volume reaches ", reach, " m from the origin, beyond ",
            kMaxCoordinate, " m (Embree's float range); make the volume smaller"));
    for (int a = 0; a < 3; ++a) {
        const int r = volume.resolution[a];
        if (r < 1 || r > kMaxProbesPerAxis)
            throw InvalidArgument(format_message(what, ".resolution[", a, "] is ", r,
                                                 "; use 1..", kMaxProbesPerAxis));
    }
}

size_t validate_probe_volumes(const std::vector<ProbeVolume>& volumes, const char* what) {
    if (volumes.empty() || volumes.size() > kMaxProbeVolumes)
        throw InvalidArgument(format_message(what, " holds ", volumes.size(),
                                             " volumes; a probe grid has 1..", kMaxProbeVolumes));
    size_t probes = 0;
    for (size_t v = 0; v < volumes.size(); ++v) {
        const std::string item = format_message(what, "[", v, "]");
        validate_probe_volume(volumes[v], item.c_str());
        const ivec3 r = volumes[v].resolution;
        probes += size_t(r.x) * size_t(r.y) * size_t(r.z);
    }
    if (probes > kMaxProbes)
        throw InvalidArgument(format_message(what, " hold ", probes, " probes; the limit is ",
                                             kMaxProbes, ": lower the resolutions"));
    return probes;
}

vec3 probe_base_position(const ProbeVolume& volume, const ivec3& index) {
    const vec3 local = -1.0f + (2.0f * vec3(index) + 1.0f) / vec3(volume.resolution);
    return vec3(volume.world_from_volume * vec4(local, 1.0f));
}

vec3 probe_spacing(const ProbeVolume& volume) {
    const mat3 m(volume.world_from_volume);
    return vec3(glm::length(m[0]), glm::length(m[1]), glm::length(m[2])) * 2.0f /
           vec3(volume.resolution);
}

void validate_probe_lookup_settings(const ProbeLookupSettings& settings, const char* struct_name) {
    if (!(settings.normal_bias >= 0.0f && settings.normal_bias <= 2.0f))
        throw InvalidArgument(format_message(struct_name, ".normal_bias is ", settings.normal_bias,
                                             "; use 0..2 probe spacings"));
    if (!(settings.view_bias >= 0.0f && settings.view_bias <= 2.0f))
        throw InvalidArgument(format_message(struct_name, ".view_bias is ", settings.view_bias,
                                             "; use 0..2 probe spacings"));
    if (!(settings.bleed_bias >= 0.0f && settings.bleed_bias < 1.0f))
        throw InvalidArgument(format_message(struct_name, ".bleed_bias is ", settings.bleed_bias,
                                             "; use a value in [0, 1)"));
}

size_t ProbeGridData::volume_offset(size_t v) const {
    size_t offset = 0;
    for (size_t i = 0; i < v; ++i) {
        const ivec3 r = volumes[i].resolution;
        offset += size_t(r.x) * r.y * r.z;
    }
    return offset;
}

std::vector<vec3> probe_base_positions(const std::vector<ProbeVolume>& volumes) {
    std::vector<vec3> positions;
    for (const ProbeVolume& volume : volumes) {
        const ivec3 r = volume.resolution;
        for (int k = 0; k < r.z; ++k)
            for (int j = 0; j < r.y; ++j)
                for (int i = 0; i < r.x; ++i)
                    positions.push_back(probe_base_position(volume, ivec3(i, j, k)));
    }
    return positions;
}

void validate_probe_grid_data(const ProbeGridData& data) {
    check_sh_order(data.order, "ProbeGridData.order");
    if (data.order < 1)
        throw InvalidArgument("ProbeGridData.order is 0; probes need order 1..4");
    const size_t count = validate_probe_volumes(data.volumes, "ProbeGridData.volumes");
    const auto check_size = [&](size_t size, size_t expected, const char* name) {
        if (size != expected)
            throw InvalidArgument(format_message("ProbeGridData.", name, " has ", size,
                                                 " entries; the volumes need ", expected));
    };
    check_size(data.positions.size(), count, "positions");
    check_size(data.active.size(), count, "active");
    check_size(data.sh.size(), count, "sh");
    check_size(data.variance.size(), count, "variance");
    if (data.visibility_resolution < 1 || data.visibility_resolution > 64)
        throw InvalidArgument(format_message("ProbeGridData.visibility_resolution is ",
                                             data.visibility_resolution, "; use 1..64"));
    check_size(data.visibility.size(),
               count * size_t(data.visibility_resolution) * data.visibility_resolution,
               "visibility");
    for (size_t i = 0; i < count; ++i) {
        if (!is_finite(data.positions[i]))
            throw InvalidArgument(format_message("ProbeGridData.positions[", i, "] is not finite"));
        if (data.sh[i].order != data.order)
            throw InvalidArgument(format_message("ProbeGridData.sh[", i, "] has order ",
                                                 data.sh[i].order, ", the grid ", data.order));
        if (!finite_sh(data.sh[i]))
            throw InvalidArgument(format_message("ProbeGridData.sh[", i, "] is not finite"));
        if (!(data.variance[i] >= 0.0f))
            throw InvalidArgument(format_message("ProbeGridData.variance[", i, "] is ",
                                                 data.variance[i]));
    }
    for (size_t i = 0; i < data.visibility.size(); ++i)
        if (!is_finite(data.visibility[i]) || data.visibility[i].x < 0.0f)
            throw InvalidArgument(format_message("ProbeGridData.visibility[", i, "] is not a "
                                                 "finite, non-negative distance"));
}

ProbeGridData splice_probes(const ProbeGridData& into, const ProbeGridData& from, size_t first,
                            size_t count) {
    const size_t probes = into.probe_count();
    if (first > probes || count > probes - first)
        throw InvalidArgument(format_message("splice_probes: probes ", first, " .. ",
                                             first + count, " lie beyond the grid's ", probes));
    const auto differ = [](const char* what, auto a, auto b) {
        throw InvalidArgument(format_message("splice_probes: the brick's ", what, " is ", b,
                                             ", the grid's ", a, "; solve every brick of one grid "
                                             "with the same settings and passes"));
    };
    if (from.order != into.order) differ("SH order", into.order, from.order);
    if (from.probe_count() != probes) differ("probe count", probes, from.probe_count());
    if (from.visibility_resolution != into.visibility_resolution)
        differ("visibility resolution", into.visibility_resolution, from.visibility_resolution);
    if (from.passes != into.passes) differ("pass count", into.passes, from.passes);
    if (from.includes_direct != into.includes_direct)
        differ("includes_direct", into.includes_direct, from.includes_direct);
    if (from.volumes.size() != into.volumes.size())
        differ("volume count", into.volumes.size(), from.volumes.size());
    for (size_t i = 0; i < probes; ++i) {
        // Placement is deterministic: the same scene and settings place every probe alike.
        if (from.positions[i] != into.positions[i] || from.active[i] != into.active[i])
            throw InvalidArgument(format_message(
                "splice_probes: probe ", i, " was placed differently in the brick (another "
                "scene or placement settings?)"));
    }
    ProbeGridData out = into;
    const size_t texels = size_t(into.visibility_resolution) * into.visibility_resolution;
    std::copy_n(from.sh.begin() + ptrdiff_t(first), count, out.sh.begin() + ptrdiff_t(first));
    std::copy_n(from.variance.begin() + ptrdiff_t(first), count,
                out.variance.begin() + ptrdiff_t(first));
    std::copy_n(from.visibility.begin() + ptrdiff_t(first * texels), count * texels,
                out.visibility.begin() + ptrdiff_t(first * texels));
    return out;
}

ProbeField::ProbeField(std::shared_ptr<const ProbeGridData> data,
                       const ProbeLookupSettings& settings)
    : data_(std::move(data)), settings_(settings) {
    if (!data_) throw InvalidArgument("ProbeField needs probe data");
    validate_probe_grid_data(*data_);
    validate_probe_lookup_settings(settings_, "ProbeLookupSettings");
    for (size_t v = 0; v < data_->volumes.size(); ++v) {
        const ProbeVolume& volume = data_->volumes[v];
        const vec3 spacing = probe_spacing(volume);
        frames_.push_back({glm::inverse(volume.world_from_volume),
                           0.5f * vec3(volume.resolution),
                           std::min(spacing.x, std::min(spacing.y, spacing.z)),
                           data_->volume_offset(v), volume.resolution});
    }
    constexpr float kReuseShare = 0.25f;
    float spacing = kInfinity;
    for (const VolumeFrame& frame : frames_) spacing = std::min(spacing, frame.min_spacing);
    reuse_distance_ = std::isfinite(spacing) ? kReuseShare * spacing : 0.0f;
}

size_t ProbeField::volume_at(const vec3& p) const {
    if (frames_.size() == 1) return 0;  // the common case: no choice to make per lookup
    size_t best = 0;
    float best_outside = kInfinity, best_spacing = kInfinity;
    for (size_t v = 0; v < frames_.size(); ++v) {
        const vec3 local = vec3(frames_[v].volume_from_world * vec4(p, 1.0f));
        const vec3 clamped = glm::clamp(local, vec3(-1.0f), vec3(1.0f));
        // Distance (m) from p to the volume: 0 inside.
        const vec3 nearest = vec3(data_->volumes[v].world_from_volume * vec4(clamped, 1.0f));
        const float outside = glm::length(nearest - p);
        const bool better = outside < best_outside ||
                            (outside == best_outside && frames_[v].min_spacing < best_spacing);
        if (better) {
            best = v;
            best_outside = outside;
            best_spacing = frames_[v].min_spacing;
        }
    }
    return best;
}

ShRgb ProbeField::radiance_sh(const vec3& p, const vec3& n) const {
    return radiance_sh(p, n, vec3(0.0f));
}

FieldLookup ProbeField::view_lookup(const vec3& p, const vec3& n, const vec3& wo) const {
    return FieldLookup{radiance_sh(p, n, wo), vec3(0.0f)};
}

ShRgb ProbeField::radiance_sh(const vec3& p, const vec3& n, const vec3& wo) const {
    const ProbeGridData& data = *data_;
    const VolumeFrame& frame = frames_[volume_at(p)];
    const vec3 biased =
        p + (n * settings_.normal_bias + wo * settings_.view_bias) * frame.min_spacing;
    const vec3 local = vec3(frame.volume_from_world * vec4(biased, 1.0f));
    const vec3 grid = (local + 1.0f) * frame.grid_scale - 0.5f;
    // One named result for every return, so it is built in the caller's (a second returned
    // object would make the compiler copy the 304-byte record out at the end).
    ShRgb out(data.order);
    // A point or normal that is not finite has no place in the grid (and NaN would survive the
    // clamps below into the probe indices): no light.
    if (!is_finite(grid)) return out;
    ivec3 base;
    vec3 frac;
    for (int a = 0; a < 3; ++a) {
        const int last = frame.resolution[a] - 1;
        const float g = std::clamp(grid[a], 0.0f, float(last));
        base[a] = std::min(int(std::floor(g)), std::max(last - 1, 0));
        frac[a] = last == 0 ? 0.0f : g - float(base[a]);
    }
    const int res = data.visibility_resolution;
    float weight_sum = 0.0f;
    for (int corner = 0; corner < 8; ++corner) {
        const ivec3 offset(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        const ivec3 index = glm::min(base + offset, frame.resolution - 1);
        float trilinear = 1.0f;
        for (int a = 0; a < 3; ++a) trilinear *= offset[a] ? frac[a] : 1.0f - frac[a];
        if (trilinear <= 0.0f) continue;
        const size_t probe = frame.offset + size_t(index.x) +
                             size_t(frame.resolution.x) * (size_t(index.y) +
                                                           size_t(frame.resolution.y) * index.z);
        if (!data.active[probe]) continue;
        float weight = 1.0f;
        if (settings_.visibility) {
            const vec3 probe_pos = data.positions[probe];
            const vec3 to_probe = probe_pos - p;
            const float to_length = glm::length(to_probe);
            if (to_length > 0.0f) {
                const float facing = 0.5f * (1.0f + glm::dot(to_probe / to_length, n));
                weight *= facing * facing + kBackfaceFloor;
            }
            const vec3 from_probe = biased - probe_pos;
            const float distance = glm::length(from_probe);
            if (distance > 0.0f) {
                const vec2 moments =
                    sample_visibility(data.visibility_map(probe), res, from_probe / distance);
                const float visible =
                    chebyshev_visibility(moments, distance, settings_.bleed_bias);
                weight *= std::max(visible * visible * visible, kMinVisibility);
            }
            if (weight < kCrushThreshold)
                weight *= weight * weight / (kCrushThreshold * kCrushThreshold);
        }
        weight *= trilinear;
        sh_add_scaled(out, data.sh[probe], weight);
        weight_sum += weight;
    }
    if (weight_sum > 0.0f) {
        const float inv = 1.0f / weight_sum;
        for (int i = 0; i < out.num_coefficients(); ++i) out[i] *= inv;
    }
    return out;
}

}  // namespace shgi
