// ProbeField: an irradiance volume of SH probes read as an IndirectField (seed 002 §3.3, §4.2.2)
// — what a ProbeGrid (probes/probe_grid.h) produces, what probe files (probes/probe_storage.h)
// hold, and what renderers and bakers query. Immutable once built, so a renderer can keep one
// snapshot while the grid refines the next (seed 002 Fig. 4.1: update decoupled from use).
//
// Layout: one or more volumes. A volume is the cube [-1, 1]^3 of its frame world_from_volume
// (Blender's irradiance volume object); its probes sit at the centres of a resolution.x x .y x .z
// grid of cells: local = -1 + (2 i + 1) / resolution. Probes are numbered volume by volume, x
// fastest, then y, then z. Each probe has a base position (that rule), a position (base plus
// the relocation offset, probes/probe_grid.h), an active flag (inactive: inside geometry), its
// incident radiance as RGB SH (W m^-2 sr^-1, docs/architecture.md's basis, one order for the grid),
// and an octahedral visibility map (probes/probe_visibility.h).
//
// Lookup at (p, n): the volume containing p with the smallest probe spacing (p outside every
// volume: the nearest, clamped to its outer probes); the 8 probes around p + (n * normal_bias +
// wo * view_bias) * spacing, wo towards the viewer when the renderer gives it (trilinear weights from base positions, as DDGI does, so relocation does not distort
// the interpolation); each active probe's weight is the trilinear weight times
//   - a back-face weight ((1 + n·ω)/2)² + 0.2, ω the direction from p to the probe, which
//     favours probes in front of the surface, and
//   - the Chebyshev visibility of the biased point seen from the probe (probes/probe_visibility.h),
//     cubed for contrast and floored at 0.05, with weights below 0.2 crushed (w³ / 0.04) so that
//     a probe behind a wall contributes almost nothing (DDGI's constants and steps);
// SH coefficients are blended with the normalised weights. visibility = false is plain trilinear
// interpolation over the active probes (the leak-prone baseline the tests compare against).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "render/indirect_field.h"
#include "sh/sh_coeffs.h"
#include "util/math.h"

namespace shgi {

struct ProbeVolume {
    mat4 world_from_volume{1.0f};  // the volume is [-1, 1]^3 in this frame
    ivec3 resolution{4, 4, 4};     // probes along each local axis, >= 1
};

// Throws InvalidArgument naming `what` for a non-finite or singular transform or a resolution
// outside 1..kMaxProbesPerAxis.
void validate_probe_volume(const ProbeVolume& volume, const char* what);
inline constexpr int kMaxProbesPerAxis = 256;
// The most volumes and probes (all volumes) a grid may hold, whether from ProbeGridSettings or
// read from a file: the binary format's header admits kMaxProbeVolumes volumes, and 2^21 probes
// with 8 x 8 visibility maps hold ~1.7 GB (a larger request is almost certainly a spacing typed
// in the wrong unit, or a damaged or hostile file).
inline constexpr size_t kMaxProbeVolumes = 4096;
inline constexpr size_t kMaxProbes = size_t(1) << 21;
// Throws InvalidArgument naming `what` unless there are 1..kMaxProbeVolumes volumes, each valid
// (validate_probe_volume, named what[v]), with at most kMaxProbes probes in all; returns that
// count. Every source of volumes (settings, grid data, both file formats) checks them here.
size_t validate_probe_volumes(const std::vector<ProbeVolume>& volumes, const char* what);

// World position of probe (i, j, k) of a volume before relocation.
vec3 probe_base_position(const ProbeVolume& volume, const ivec3& index);
// Distance (m) between neighbouring probes along each local axis (the volume's size along the
// axis over its resolution).
vec3 probe_spacing(const ProbeVolume& volume);

// How shading points read the probes (EEVEE: Bias ~ normal_bias, Bleed Bias ~ bleed_bias).
struct ProbeLookupSettings {
    bool visibility = true;     // back-face and Chebyshev weights; false = plain trilinear
    float normal_bias = 0.25f;  // shading points move this many probe spacings along the normal
    float view_bias = 0.0f;     // ... and this many towards the viewer (renderers' view_lookup)
    float bleed_bias = 0.0f;    // in [0, 1): Chebyshev weights below it become 0
};
void validate_probe_lookup_settings(const ProbeLookupSettings& settings, const char* struct_name);

// Everything a probe grid stores (see the header comment for the layout).
struct ProbeGridData {
    int order = 2;
    std::vector<ProbeVolume> volumes;
    std::vector<vec3> positions;     // per probe, world space, after relocation
    std::vector<uint8_t> active;     // per probe: 0 = inside geometry, never used
    std::vector<ShRgb> sh;           // per probe, incident radiance
    int visibility_resolution = 8;   // texels per side of each probe's octahedral map
    std::vector<vec2> visibility;    // per probe res*res (mean distance, mean squared distance)
    std::vector<float> variance;     // per probe: variance of its DC luminance estimate
    uint64_t passes = 0;             // update passes blended in
    bool includes_direct = false;    // also emitters and world seen straight from the probes

    size_t probe_count() const { return positions.size(); }
    // Index of the first probe of volume v.
    size_t volume_offset(size_t v) const;
    const vec2* visibility_map(size_t probe) const {
        return visibility.data() + probe * size_t(visibility_resolution) * visibility_resolution;
    }
};

// Probes of the volumes, their base positions in order (the layout's numbering).
std::vector<vec3> probe_base_positions(const std::vector<ProbeVolume>& volumes);

// Throws InvalidArgument naming the first inconsistent or non-finite item (more than
// kMaxProbeVolumes volumes or kMaxProbes probes, array sizes that disagree with the volumes, SH
// of another order, NaN values...): data read from files passes through here before any lookup.
void validate_probe_grid_data(const ProbeGridData& data);

// `into` with the updated state (SH, variance, visibility) of probes first .. first + count - 1
// taken from `from`: the merge of a probe-grid solve split into bricks (ProbeGrid::
// update_probes). Both must be the same grid after the same passes (order, volumes, positions,
// active flags, visibility resolution, passes, includes_direct); InvalidArgument names the first
// difference, or a range beyond the probes.
ProbeGridData splice_probes(const ProbeGridData& into, const ProbeGridData& from, size_t first,
                            size_t count);

class ProbeField : public IndirectField {
  public:
    // Validates both arguments.
    ProbeField(std::shared_ptr<const ProbeGridData> data, const ProbeLookupSettings& settings);

    const ProbeGridData& data() const { return *data_; }
    std::shared_ptr<const ProbeGridData> shared_data() const { return data_; }
    const ProbeLookupSettings& lookup_settings() const { return settings_; }

    ShRgb radiance_sh(const vec3& p, const vec3& n) const override;
    FieldLookup view_lookup(const vec3& p, const vec3& n, const vec3& wo) const override;
    // radiance_sh with the view bias: wo unit towards the viewer (zero: no view bias).
    ShRgb radiance_sh(const vec3& p, const vec3& n, const vec3& wo) const;

    // The volume whose probes light p (see the header comment).
    size_t volume_at(const vec3& p) const;
    // A quarter of the smallest probe spacing of any volume: the trilinear, back-face and
    // Chebyshev weights change little over it on one surface.
    float reuse_distance() const override { return reuse_distance_; }

  private:
    struct VolumeFrame {
        mat4 volume_from_world;
        vec3 grid_scale;      // local -> grid coordinates: (local + 1) * grid_scale - 0.5
        float min_spacing;    // m
        size_t offset;        // first probe
        ivec3 resolution;
    };

    std::shared_ptr<const ProbeGridData> data_;
    ProbeLookupSettings settings_;
    std::vector<VolumeFrame> frames_;
    float reuse_distance_ = 0.0f;
};

}  // namespace shgi
