// PropagationField: the IndirectField of a light propagation volume (seed 003 §3.2.4, eq. 3.4):
// an immutable accumulation volume of intensities (W/sr, propagation/propagation_stencil.h)
// turned into incident radiance at shading points.
//
// A cell's intensity I(ω) is the light in the cell travelling along ω; spread over the cell's
// cross-section it is a radiance, and light arriving at p from direction ω_i (pointing back to
// where it came from) travels along −ω_i:
//     L_i(p, ω_i) = k · I_p(−ω_i) / s²,
// so the irradiance E(n) = ∫ L_i max(0, n·ω_i) dω_i is the intensity against the cosine lobe
// at −n (the seed's text says −n; its eq. 3.4 writes n). I_p is the trilinear interpolation of
// the cells at p moved normal_offset cells along n, each weighted by the geometry's transmittance
// from the cell holding that point (when the solver gives it: occlusion on), the weights
// normalised.
//
// The seed gives no intensity-to-radiance factor k. The accumulation volume sums the light of
// every step, so k is the inverse of the cells light advances per step times the lobes' mean
// cosine, which depends on the stencil. It is fixed by the single-VPL test
// (tests/cpp/propagation/propagation_volume_test.cpp): a VPL of flux Φ in an empty volume must
// light a plane facing it with Φ cos θ / (π r²). Over the near field (r = 1.5–3 cells, θ = 0–60°,
// 24 steps) the unscaled ratio has geometric mean 0.786 for the LPV and 0.465 for the HOLPV
// (its diagonal steps move light farther per step); k is their inverse. Farther out the LPV falls
// below 1/r² (its broad L1 lobes turn propagation into diffusion: 0.70 of the closed form at 4
// cells, 0.34 at 6 after 24 steps), the HOLPV much less (0.93 and 0.84).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "propagation/propagation_stencil.h"
#include "render/indirect_field.h"
#include "sh/sh_volume.h"

namespace shgi {

// k by SH order of the volume (1: LPV's stencil, 2: HOLPV's) and re-injection, see above. With
// Reinjection::TravelDirection the same fit gives 0.992 (LPV) and 0.576 (HOLPV); its near field
// is less even (samples 0.55–1.97 and 0.53–1.63 × the fit, against 0.81–1.27 and 0.88–1.23).
//
// Reinjection::WindowedTravelDirection (band 2 of the HOLPV's beams × w = 4/5) takes the plain
// beams' k. The window changes band 2 only; the light of a room once it has settled is close to
// diffuse, and a diffuse field's irradiance reads bands 0 and 1, which both beams carry alike (the
// same flux and first moment). In the furnace (a closed room whose exact light is the same at
// every wall point, tests/python/test_propagation.py) the windowed beams at the plain k give the
// room 0.97-0.98 of the plain beams' light (defaults, linear transfer, settled). Onto a surface
// facing a single beam, fully directional light, the plain beam's band 2 adds 1/17 of its
// irradiance ((1 + 2 + 5w/4) / 4 at w = 1 against w = 4/5: 17/16); scaled by that ratio instead the
// windowed beams gave the furnace 1.03-1.06 of the plain beams' light and the two rooms 1.14x the
// path tracer's; the near-field fit (1/0.514, the beams' shape rather than the light they
// deliver) gave the rooms 1.11-1.20x.
inline constexpr float kLpvRadianceScale = 1.0f / 0.786f;
inline constexpr float kHolpvRadianceScale = 1.0f / 0.465f;
inline constexpr float kLpvTravelRadianceScale = 1.0f / 0.992f;
inline constexpr float kHolpvTravelRadianceScale = 1.0f / 0.576f;
inline float propagation_radiance_scale(int order,
                                        Reinjection reinjection = Reinjection::FaceNormal) {
    if (reinjection == Reinjection::TravelDirection ||
        reinjection == Reinjection::WindowedTravelDirection)
        return order == 1 ? kLpvTravelRadianceScale : kHolpvTravelRadianceScale;
    return order == 1 ? kLpvRadianceScale : kHolpvRadianceScale;
}

// Per cell of a volume and offset of PropagationStencil::Neighbours26's order
// (propagation_offsets), the transmittance of the geometry from the neighbour at −offset into
// the cell (propagation/propagation_stencil.h's PropagationTransmittance, 26 offsets).
using NeighbourTransmittance = std::vector<float>;

// Cascades (propagation_volume.h, PropagationSettings::cascades): a lookup reads the finest level
// whose box of cells holds the lookup point at least kCascadeMarginCells (its cells) inside the
// faces it shares with the next coarser level (the trilinear footprint, and damping's half-cell
// reach), blended into the coarser one over the next kCascadeBlendCells: weight
// w = clamp((d − margin) / band, 0, 1), d the distance in cells to the nearest such face.
inline constexpr float kCascadeMarginCells = 1.0f;
inline constexpr float kCascadeBlendCells = 4.0f;
// Levels a field may have (PropagationSettings::cascades' limit).
inline constexpr int kMaxPropagationLevels = 8;

// One level of a field: its accumulated volume, the lookup transmittance (may be null), and the
// faces of its box it blends across into the next coarser level (bit a: the lower face on axis
// a, bit 3 + a: the upper; 0 for the coarsest level and a single volume). The level's box is its
// geometry lattice's: the volume without its outer half cells.
struct PropagationLevel {
    std::shared_ptr<const ShVolume> accumulated;
    std::shared_ptr<const NeighbourTransmittance> transmittance;
    uint8_t blend_faces = 0;
};

class PropagationField : public IndirectField {
  public:
    PropagationField() = default;  // no light
    // Copies share the volume. With `transmittance` (26 per cell, may be null) the lookup
    // weights each of its 8 cells by the transmittance from the cell holding the lookup point
    // to it, so that light on the far side of a wall within a cell of the point is not read
    // (the light propagation keeps it out, the interpolation would let it in).
    // With `damping` the lookup is damped by the directional derivative along the normal
    // (seed 003 §3.2.4, Kaplanyan & Dachsbacher 2010): see radiance_sh.
    // `reinjection` picks the radiance scale k of the propagation that made the volume.
    PropagationField(std::shared_ptr<const ShVolume> accumulated, float normal_offset,
                     std::shared_ptr<const NeighbourTransmittance> transmittance = nullptr,
                     bool damping = false, Reinjection reinjection = Reinjection::FaceNormal);
    // A cascaded field: `levels` finest first, the last (the coarsest, covering the scene) with
    // no blend faces; every level of the same SH order. Throws InvalidArgument otherwise.
    PropagationField(std::vector<PropagationLevel> levels, float normal_offset, bool damping,
                     Reinjection reinjection);

    ShRgb radiance_sh(const vec3& p, const vec3& n) const override;
    bool is_zero() const override {
        return levels_.empty() || !levels_.back().accumulated ||
               levels_.back().accumulated->cell_count() == 0;
    }
    // A quarter of the finest cell: the trilinear lookup changes little over it.
    float reuse_distance() const override {
        return is_zero() ? 0.0f : 0.25f * levels_.front().accumulated->cell_size();
    }

    // The coarsest level's volume (the only one without cascades); null before the first pass.
    const std::shared_ptr<const ShVolume>& accumulated() const;
    const std::vector<PropagationLevel>& levels() const { return levels_; }
    // The weight of `level` (not the coarsest) at lookup point q (see kCascadeBlendCells).
    float level_weight(size_t level, const vec3& q) const;
    // One level as a field of its own (as if it covered the scene: no blending).
    PropagationField level_field(size_t level) const {
        const PropagationLevel& l = levels_.at(level);
        return PropagationField(l.accumulated, normal_offset_, l.transmittance, damping_,
                                reinjection_);
    }
    // The lookup of one level alone (its radiance SH at p, n: offset, damping), as if it covered
    // the scene; radiance_sh blends these.
    ShRgb level_radiance_sh(size_t level, const vec3& p, const vec3& n) const;

    // SHGI's binary file of the field (".shlpv": the accumulated volume, the transmittance, the
    // lookup's settings; little-endian, float32 as held), written atomically; a field loaded
    // back looks up exactly the same values. load throws IoError naming the file for one that
    // is not a field (magic, version, truncation, sizes that do not match, values that are not
    // finite or out of range) and OutOfMemory before allocating past the budget.
    void save(const std::string& path) const;
    static std::unique_ptr<PropagationField> load(const std::string& path);
    // Bytes of the levels' volumes.
    size_t memory_bytes() const {
        size_t bytes = 0;
        for (const PropagationLevel& level : levels_)
            bytes += (level.accumulated ? level.accumulated->coefficients().size() : 0) *
                     sizeof(float);
        return bytes;
    }

  private:
    // The radiance SH at q from one level: the transmittance-weighted trilinear lookup, scaled
    // to radiance.
    ShRgb weighted_lookup(const PropagationLevel& level, const vec3& q) const;

    std::vector<PropagationLevel> levels_;  // finest first; empty: no light
    float normal_offset_ = 1.0f;
    bool damping_ = false;
    Reinjection reinjection_ = Reinjection::FaceNormal;
};

}  // namespace shgi
