// PropagationStencil: the faces light crosses in one step of a light propagation volume (seed 003
// §3.2.3, §4.2 and Appendix A), and one gather step over a dense SH volume of intensities.
//
// Units and conventions: a propagation volume (sh/sh_volume.h) stores per cell the radiant
// intensity I(ω) in W/sr of the light in the cell, ω the direction the light travels; its
// integral over the sphere is the cell's flux (W). Cells are unit cubes here (solid angles do not
// depend on the cell size). A clamped-cosine lobe of flux Φ pointing along n is the expansion of
// (Φ/π) max(0, n·ω): coefficient i of band l is (Φ/π) Â_l Y_i(n) with Â_l = π, 2π/3, π/4
// (seed 003 eq. 3.2 with Z₀ = √π/2, Z₁ = √(π/3), Z₂ = √(5π)/8; §4.1.1 misprints Z₂ as √(5π/8)).
//
// Stencils, the source cell at the origin, destination cells at integer offsets d:
//   Faces6 (LPV, §3.2.3): the 6 face neighbours, each with its 5 faces that do not touch the
//       source (30 faces): front 0.4006697 sr, side 0.4234314 sr (the 0.4234413544 copied into
//       many shaders is wrong).
//   Neighbours26 (HOLPV, §4.2): all 26 neighbours and the 54 outer faces of the 3×3×3 block:
//       face-centred 0.4006697, edge 0.2506920, corner 0.1727394 sr.
// Each stencil's faces partition the sphere seen from the source centre (every ray leaves the
// source cell into exactly one neighbour and leaves that through exactly one listed face), so
// their solid angles sum to 4π. Solid angles are exact (rectangle_solid_angle, with atan2).
//
// One step (gather form, §3.3 and §4.3): every destination cell sums, over the stencil's faces
// f and their source cells c − d_f, the light Ω_f I_src(ω_f) T_f crossing face f, re-injected as
// a cosine lobe of that flux along the face's outward normal n_f; ω_f points from the source
// centre to the face centre and T_f is the transmittance of the geometry between (1 without
// occlusion). Two corrections to eq. 3.3:
//   - eq. 3.3 scales by Ω_f/4π, but the light crossing the face is Ω_f I(ω_f) and a cosine lobe
//     (Φ/π) max(0, n·ω) holds Φ: the lobe re-injected for that light has Φ_f = Ω_f I(ω_f), i.e.
//     the thesis' lobe Φ' max(0, n·ω) with Φ' = (Ω_f/π) I(ω_f). With Ω_f/4π three quarters of the
//     flux are lost at every step;
//   - an L1/L2 expansion of a lobe is negative behind it; clamping those samples at zero adds
//     energy (+12.5% per step for an L1 cosine lobe). LobeClamp::Rescaled clamps, then scales
//     the source cell's clamped fluxes to its unclamped total Σ_f Ω_f I(ω_f), which equals
//     ∫ I dω (the stencils integrate bands 0..2 exactly by their symmetry): no energy is made.
//
// Re-injection. The seed re-injects the light crossing face f as a cosine lobe along the face's
// normal n_f (Reinjection::FaceNormal): every face re-emits like a Lambertian surface. Such a
// lobe of flux Φ has first moment ∫ I ω dω = (2/3) Φ n_f, so each step keeps only part of the
// light's momentum (one unclamped step keeps 0.37 (LPV) and 0.55 (HOLPV) of a cosine lobe's):
// the light random-walks, a transport closer to diffusion than to straight flight. In a closed
// box it lingers long before the walls absorb it, and the accumulation keeps growing with the
// steps (docs/methods.md, "Why the accumulation does not converge").
// Reinjection::TravelDirection re-injects it as the projection of a beam along its travel
// direction ω_f, coefficients Φ_f Y_i(ω_f): one unclamped step then keeps the source's flux and
// its first moment Σ_f Ω_f I(ω_f) ω_f = ∫ I ω dω exactly (I ω is of bands 0..3; the stencils
// integrate the even bands up to 2 exactly and the odd ones to 0 like the sphere).
// Reinjection::WindowedTravelDirection scales that beam's band 2 by kBeamBand2Window = 4/5 (L2
// only; at L1 it is TravelDirection). The L2 projection of a beam along ω is positive straight
// behind it, 1/3 of its peak ((1 − 3 + 5)/(1 + 3 + 5)), a back lobe that each step sends part of
// the light back the way it came; its irradiance on a surface the beam leaves (facing along ω)
// is 1/17 of what a surface facing the beam receives ((1 − 2 + 5/4)/(1 + 2 + 5/4), the clamped
// cosine's bands π, 2π/3, π/4). Scaled by w, band 2 gives that surface (1 − 2 + 5w/4): 0 at
// w = 4/5, the window: the re-injected light lights nothing behind it (its intensity straight
// behind, 1 − 3 + 4 = 2 against a peak of 8, is offset by the negative ring around it). Bands 0
// and 1, so the flux and the first moment, are kept. The price: light passing a surface
// edge-on lights it with 1/8 of a facing surface's irradiance, against 1/11.3 unwindowed. A
// band-2 weight of 2/5 would zero the intensity straight behind instead, leaving a negative
// irradiance there (−1/7 of the facing one). Hanning or Lanczos windows (Sloan, "Stupid
// Spherical Harmonics Tricks") lower band 1 too, so the light's momentum decays each step
// (docs/methods.md, "The HOLPV's self-lighting").
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "sh/sh_volume.h"
#include "util/math.h"
#include "util/progress.h"

namespace shgi {

enum class PropagationStencil : uint8_t {
    Faces6,        // LPV: 6 face neighbours × 5 faces
    Neighbours26,  // HOLPV: 26 neighbours, the 54 outer faces of the 3×3×3 block
};

enum class Reinjection : uint8_t {
    FaceNormal,       // a cosine lobe along the face's outward normal (the seed, §3.3)
    TravelDirection,  // a beam along ω_f, projected (keeps the light's first moment)
    // As TravelDirection with the beam's band 2 scaled by kBeamBand2Window (lights nothing
    // behind it; keeps flux and first moment).
    WindowedTravelDirection,
};

// The band-2 weight of Reinjection::WindowedTravelDirection's beams (see above).
inline constexpr float kBeamBand2Window = 0.8f;

// The coefficients (i < 9) of a beam of flux 1 along unit `direction` as `reinjection` re-injects
// it: Y_i(direction), band 2 scaled by kBeamBand2Window when windowed. FaceNormal: not a beam,
// throws InvalidArgument.
void reinjected_beam(int order, Reinjection reinjection, const vec3& direction, float* out);

enum class LobeClamp : uint8_t {
    Rescaled,  // clamp negative samples, then rescale to the unclamped total (conserves flux)
    Clamped,   // clamp only (the published method: gains energy each step)
    None,      // no clamp (linear; conserves flux; may carry negative intensity)
    // Linear in free space; where a wall stops part of a source cell's light (any of its
    // transfers has transmittance < 1) clamped, and scaled so that the flux the cell's transfers
    // carry past the walls is the smaller of the linear step's and the Rescaled step's (at least
    // 0): unclamped, a wall stops a lobe's negative half like its positive light, and stopping
    // negative flux makes light; rescaled to the cell's total, the truncated lobe's back part
    // (an L2 beam's positive back lobe) walks away from a wall the light went into, so walls
    // return light (a beam into a wall: 0.135 of it at L2, 0.0625 at L1) that they should absorb
    // (the VPLs' later bounces carry what surfaces reflect).
    AtSurfaces,
    // AtSurfaces' first form, kept to measure against: Rescaled (to the cell's total) where a
    // wall stops part of the light. Walls make no light but return the back lobes' share.
    AtSurfacesToTotal,
    // As AtSurfaces, but in such a cell only the transfers a wall stops in part (transmittance
    // < 1) are clamped; the others stay linear, as in free space. The clamped transfers are
    // rescaled to their own unclamped total, and pass the walls no more than the linear step's
    // share. Only where neither the blocked transfers' flux nor the others' is negative: a
    // negative part into the walls, stopped, would make light, and a negative part along or
    // away from them (a beam into a wall leaves its negative ring behind) would send negative
    // light back into the room; those cells are clamped whole, as AtSurfaces. Clamping every
    // transfer of the cells along a wall spreads the L2 lobes there (their negative ring gone,
    // the rest rescaled) and moves light from a room's edges into its middle (the furnace's
    // ramp, docs/methods.md); a transfer along or away from the wall is left as free space
    // carries it. The HOLPV's 26 neighbours cross edges and corners diagonally, so per cell
    // the clamp takes in far more of its transfers than the LPV's 6.
    AtBlockedTransfers,
};

// Solid angle (sr) of the rectangle [x0, x1] × [y0, y1] in the plane at `distance` > 0 from the
// viewpoint, x and y measured from the viewpoint's foot on that plane (Appendix A, with atan2 so
// that every quadrant is right).
double rectangle_solid_angle(double x0, double x1, double y0, double y1, double distance);

// One face of a stencil: where its light goes and how much of the sphere it takes.
struct PropagationFace {
    ivec3 offset{0};       // destination cell − source cell
    vec3 direction{0.0f};  // unit, source centre → face centre (ω_f)
    vec3 normal{0.0f};     // the face's outward unit normal (axis-aligned)
    double solid_angle = 0.0;  // Ω_f, sr, seen from the source centre
};

// Faces of the largest stencil (Neighbours26's; Faces6 has 30).
inline constexpr size_t kMaxStencilFaces = 54;

// The faces of a stencil, grouped by offset (offsets in a fixed order).
std::vector<PropagationFace> propagation_faces(PropagationStencil stencil);
// The distinct offsets of a stencil, in the order of propagation_faces.
std::vector<ivec3> propagation_offsets(PropagationStencil stencil);

// How far one step carries light, in cells: the distance a beam's flux moves along it in one
// unclamped step, (3/4π) Σ_f Ω_f (ω_f·x̂)(d_f·x̂) (the same along every direction by the stencils'
// symmetry, and for L1 and L2: the band-2 part of a beam moves no flux on average). With the
// travel re-injection, which keeps the light's first moment, the flux-weighted centre of any
// light moves this times its first moment over its flux every step. Faces6 (LPV) 0.9146,
// Neighbours26 (HOLPV) 1.4154: the HOLPV's diagonal steps carry light farther.
double propagation_speed(PropagationStencil stencil);

// Adds to `cell` (floats_per_cell of an order-`order` volume, [coeff][rgb]) a clamped-cosine lobe
// along unit `normal` holding flux `power` (W per channel).
void add_cosine_lobe(float* cell, int order, const vec3& normal, const vec3& power);

// Flux (W per channel) of a cell's intensity expansion: ∫ I dω = √(4π) c₀.
vec3 cell_flux(const float* cell);

// Per destination cell and stencil offset, the transmittance of the transfer from the source
// cell (destination − offset): transmittance[cell · offsets + o]. Empty: no occlusion.
struct PropagationTransmittance {
    std::vector<float> values;
    int offsets = 0;
};

// One propagation step: `destination` = the light of `source` moved by one step (gather form).
// Both volumes have the same layout; light leaving the volume is lost. Parallel over destination
// cells, each summed in a fixed order: bit-identical for any thread count. Cancellable (polled
// per 4096 cells; no progress is reported: a step is one unit of the caller's stage); throws InvalidArgument for volumes of different layouts or a
// transmittance of the wrong size.
class PropagationStep {
  public:
    PropagationStep(PropagationStencil stencil, int order, LobeClamp clamp,
                    Reinjection reinjection = Reinjection::FaceNormal);
    void operator()(const ShVolume& source, ShVolume& destination,
                    const PropagationTransmittance* transmittance = nullptr,
                    Progress* progress = nullptr) const;
    int offset_count() const { return int(offsets_.size()); }

  private:
    struct Face {
        float flux_factor = 0.0f;                   // Ω_f / π
        float basis[9] = {};                        // Y_i(ω_f), i < 9
        float beam[9] = {};  // the re-injected beam of flux 1 (reinjected_beam), travel only
        int normal_index = 0;                       // index into lobes_
        int index = 0;  // among all the stencil's faces (TravelDirection's per-face flux)
    };
    struct Offset {
        ivec3 offset{0};
        std::vector<Face> faces;
    };
    // Per source cell and channel, the factor its clamped face intensities are scaled by
    // (Rescaled: to the unclamped total; AtSurfaces, AtSurfacesToTotal and AtBlockedTransfers:
    // see LobeClamp, only for the cells `blocked` marks, which this fills: non-zero where a
    // transfer out of the cell is blocked in part; AtBlockedTransfers: 2 where only those
    // transfers are clamped, 1 where the whole cell is), else 1.
    void rescale_factors(const ShVolume& source, const PropagationTransmittance* transmittance,
                         std::vector<vec3>& factors, std::vector<uint8_t>& blocked,
                         Progress* progress) const;
    vec3 face_intensity(const float* cell, const Face& face) const;

    int order_ = 1;
    int coefficients_ = 4;
    LobeClamp clamp_ = LobeClamp::Rescaled;
    Reinjection reinjection_ = Reinjection::FaceNormal;
    std::vector<Offset> offsets_;
    float lobes_[6][9] = {};  // cosine lobe Â_l Y_i(n)/π along ±x, ±y, ±z (flux 1)
};

}  // namespace shgi
