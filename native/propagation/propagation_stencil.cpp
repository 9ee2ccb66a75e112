#include "propagation/propagation_stencil.h"

#include <algorithm>
#include <cmath>

#include "sh/sh_basis.h"
#include "util/error.h"
#include "util/parallel.h"

namespace shgi {
namespace {

// Â_l = √(4π/(2l+1)) Z_l of the clamped cosine (sh/sh_irradiance.h), bands 0..2.
constexpr float kCosineBand[3] = {kPi, 2.0f * kPi / 3.0f, kPi / 4.0f};
constexpr int kBandOf[9] = {0, 1, 1, 1, 2, 2, 2, 2, 2};
// √(4π): ∫ Y₀₀ dω, so a cell's flux is √(4π) c₀.
constexpr float kSqrtFourPi = 3.5449077018110318f;
// Destination cells per parallel task: a 64³ volume is 256 tasks per step, each well under the
// 0.2 s cancel budget. The tasks poll cancel but report no progress: the caller reports per step.
constexpr uint64_t kCellsPerTask = 1024;

// Index in lobes_ of an axis-aligned unit normal: 2·axis + (negative ? 1 : 0).
int normal_index(const vec3& normal) {
    for (int axis = 0; axis < 3; ++axis)
        if (normal[axis] != 0.0f) return 2 * axis + (normal[axis] < 0.0f ? 1 : 0);
    return 0;
}

bool same_layout(const ShVolume& a, const ShVolume& b) {
    return a.counts() == b.counts() && a.order() == b.order();
}

// One channel of a cell's clamped lobe rescaled to its unclamped flux `total` from `clamped`
// (Rescaled). A cell whose unclamped total is not positive sends nothing (its clamped samples
// are noise of the truncation).
float rescale_factor(float total, float clamped) {
    return total > 0.0f && clamped > 0.0f ? total / clamped : 0.0f;
}

// AtSurfaces: of the rescaled lobe's light past the walls (`clamped_passed` before the rescale),
// no more than the linear step's (`passed`, which the light going into a wall does not reach
// past it), and not below 0.
float at_surfaces_factor(float total, float clamped, float passed, float clamped_passed) {
    return clamped_passed > 0.0f
               ? std::max(0.0f, std::min(rescale_factor(total, clamped), passed / clamped_passed))
               : 0.0f;
}

}  // namespace

double rectangle_solid_angle(double x0, double x1, double y0, double y1, double distance) {
    // Ω of [0, x] × [0, y] (signed by the quadrant) is atan2(x y, d √(x² + y² + d²)); the
    // rectangle is the inclusion–exclusion of its four corners.
    const auto corner = [distance](double x, double y) {
        return std::atan2(x * y, distance * std::sqrt(x * x + y * y + distance * distance));
    };
    return corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0);
}

std::vector<PropagationFace> propagation_faces(PropagationStencil stencil) {
    std::vector<PropagationFace> faces;
    for (const ivec3& d : propagation_offsets(stencil)) {
        for (int axis = 0; axis < 3; ++axis) {
            for (int sign : {1, -1}) {
                // LPV: every face of the destination that does not touch the source (normal ·
                // d >= 0); HOLPV: the faces on the outside of the 3×3×3 block (d_axis = sign).
                const bool outer = stencil == PropagationStencil::Faces6
                                       ? sign * d[axis] >= 0
                                       : d[axis] == sign;
                if (!outer) continue;
                PropagationFace face;
                face.offset = d;
                face.normal = vec3(0.0f);
                face.normal[axis] = float(sign);
                const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                const double plane = double(d[axis]) + 0.5 * sign;
                face.solid_angle = rectangle_solid_angle(d[u] - 0.5, d[u] + 0.5, d[v] - 0.5,
                                                         d[v] + 0.5, std::fabs(plane));
                vec3 centre = vec3(d);
                centre[axis] = float(plane);
                face.direction = glm::normalize(centre);
                faces.push_back(face);
            }
        }
    }
    return faces;
}

std::vector<ivec3> propagation_offsets(PropagationStencil stencil) {
    std::vector<ivec3> offsets;
    for (int z = -1; z <= 1; ++z)
        for (int y = -1; y <= 1; ++y)
            for (int x = -1; x <= 1; ++x) {
                const int nonzero = (x != 0) + (y != 0) + (z != 0);
                if (nonzero == 0) continue;
                if (stencil == PropagationStencil::Faces6 && nonzero != 1) continue;
                offsets.emplace_back(x, y, z);
            }
    return offsets;
}

double propagation_speed(PropagationStencil stencil) {
    double sum = 0.0;
    for (const PropagationFace& face : propagation_faces(stencil))
        sum += face.solid_angle * double(face.direction.x) * double(face.offset.x);
    return 3.0 / (4.0 * kPiD) * sum;
}

void add_cosine_lobe(float* cell, int order, const vec3& normal, const vec3& power) {
    float basis[9];
    sh_eval(order, normal, basis);
    const vec3 scale = power * kInvPi;
    for (int i = 0; i < sh_num_coefficients(order); ++i) {
        const float w = kCosineBand[kBandOf[i]] * basis[i];
        cell[3 * i + 0] += w * scale.x;
        cell[3 * i + 1] += w * scale.y;
        cell[3 * i + 2] += w * scale.z;
    }
}

void reinjected_beam(int order, Reinjection reinjection, const vec3& direction, float* out) {
    if (reinjection == Reinjection::FaceNormal)
        throw InvalidArgument("reinjected_beam: the face-normal re-injection is a cosine lobe, "
                              "not a beam");
    sh_eval(order, direction, out);
    if (reinjection == Reinjection::WindowedTravelDirection)
        for (int i = 4; i < sh_num_coefficients(order); ++i) out[i] *= kBeamBand2Window;
}

vec3 cell_flux(const float* cell) { return kSqrtFourPi * vec3(cell[0], cell[1], cell[2]); }

PropagationStep::PropagationStep(PropagationStencil stencil, int order, LobeClamp clamp,
                                 Reinjection reinjection)
    : order_(order), coefficients_(sh_num_coefficients(order)), clamp_(clamp),
      reinjection_(reinjection) {
    if (order < 1 || order > 2)
        throw InvalidArgument(format_message("PropagationStep: order ", order,
                                             " must be 1 (L1, LPV) or 2 (L2, HOLPV)"));
    for (int n = 0; n < 6; ++n) {
        vec3 normal(0.0f);
        normal[n / 2] = n % 2 == 0 ? 1.0f : -1.0f;
        float basis[9];
        sh_eval(order, normal, basis);
        for (int i = 0; i < coefficients_; ++i)
            lobes_[n][i] = kCosineBand[kBandOf[i]] * basis[i] * kInvPi;
    }
    int faces = 0;
    for (const PropagationFace& f : propagation_faces(stencil)) {
        if (offsets_.empty() || offsets_.back().offset != f.offset) offsets_.push_back({f.offset, {}});
        Face face;
        face.flux_factor = float(f.solid_angle / kPiD);
        sh_eval(order, f.direction, face.basis);
        face.normal_index = normal_index(f.normal);
        if (reinjection != Reinjection::FaceNormal)
            reinjected_beam(order, reinjection, f.direction, face.beam);
        face.index = faces++;
        offsets_.back().faces.push_back(face);
    }
    // The per-face fluxes of a TravelDirection step live in kMaxStencilFaces slots.
    if (faces > int(kMaxStencilFaces))
        throw Internal(format_message("PropagationStep: a stencil of ", faces, " faces"));
}

vec3 PropagationStep::face_intensity(const float* cell, const Face& face) const {
    vec3 intensity(0.0f);
    for (int i = 0; i < coefficients_; ++i)
        intensity += face.basis[i] * vec3(cell[3 * i], cell[3 * i + 1], cell[3 * i + 2]);
    return intensity;
}

void PropagationStep::rescale_factors(const ShVolume& source,
                                      const PropagationTransmittance* transmittance,
                                      std::vector<vec3>& factors, std::vector<uint8_t>& blocked,
                                      Progress* progress) const {
    factors.assign(source.cell_count(), vec3(1.0f));
    blocked.assign(source.cell_count(), 0);
    const bool per_transfer = clamp_ == LobeClamp::AtBlockedTransfers;
    const bool at_surfaces = clamp_ == LobeClamp::AtSurfaces ||
                             clamp_ == LobeClamp::AtSurfacesToTotal || per_transfer;
    if (clamp_ != LobeClamp::Rescaled && !at_surfaces) return;
    if (at_surfaces && transmittance == nullptr) return;  // no wall: linear everywhere
    parallel_for(
        0, source.cell_count(), kCellsPerTask,
        [&](uint64_t begin, uint64_t end) {
            throw_if_cancelled(progress);
            std::vector<float> t(offsets_.size(), 1.0f);
            for (uint64_t c = begin; c < end; ++c) {
                if (at_surfaces) {
                    // The transmittance of each transfer out of the cell (light leaving the
                    // volume is not stopped by a wall: 1).
                    const ivec3 cell = source.cell_at(c);
                    bool any = false;
                    for (size_t o = 0; o < offsets_.size(); ++o) {
                        const ivec3 to = cell + offsets_[o].offset;
                        t[o] = source.contains(to)
                                   ? transmittance->values[source.cell_index(to) *
                                                               offsets_.size() + o]
                                   : 1.0f;
                        any = any || t[o] < 1.0f;
                    }
                    if (!any) continue;
                    blocked[c] = 1;
                }
                const float* cell = source.cell_data(c);
                if (per_transfer) {
                    // Over the blocked transfers' faces: the unclamped and clamped fluxes and
                    // what of each passes the walls; over the free ones the (linear) flux; over
                    // all, AtSurfaces' sums for the cells it falls back to.
                    vec3 wall(0.0f), wall_clamped(0.0f), wall_passed(0.0f),
                        wall_clamped_passed(0.0f), free(0.0f), clamped(0.0f);
                    for (size_t o = 0; o < offsets_.size(); ++o)
                        for (const Face& face : offsets_[o].faces) {
                            const vec3 flux = face.flux_factor * face_intensity(cell, face);
                            const vec3 positive = glm::max(flux, vec3(0.0f));
                            clamped += positive;
                            if (t[o] >= 1.0f) {
                                free += flux;
                                continue;
                            }
                            wall += flux;
                            wall_clamped += positive;
                            wall_passed += t[o] * flux;
                            wall_clamped_passed += t[o] * positive;
                        }
                    // Per transfer only where neither part is negative: a negative part into
                    // the walls, stopped, would make light; a negative part along or away from
                    // them (a beam going into a wall leaves its negative ring behind) would
                    // send negative light back into the room. Elsewhere clamp the whole cell.
                    const bool split = glm::all(glm::greaterThanEqual(wall, vec3(0.0f))) &&
                                       glm::all(glm::greaterThanEqual(free, vec3(0.0f)));
                    blocked[c] = split ? 2 : 1;
                    const vec3 passed = free + wall_passed;
                    const vec3 clamped_passed =
                        wall_clamped_passed + glm::max(clamped - wall_clamped, vec3(0.0f));
                    // Split: the clamped transfers rescaled to their own total, passing the walls
                    // no more than the linear step's share. Else AtSurfaces' factor over all
                    // of them (the free transfers pass t = 1).
                    for (int ch = 0; ch < 3; ++ch)
                        factors[c][ch] =
                            split ? at_surfaces_factor(wall[ch], wall_clamped[ch], wall_passed[ch],
                                                       wall_clamped_passed[ch])
                                  : at_surfaces_factor(wall[ch] + free[ch], clamped[ch],
                                                       passed[ch], clamped_passed[ch]);
                    continue;
                }
                // Over the faces: the unclamped and clamped fluxes, and what of each passes the
                // walls.
                vec3 total(0.0f), clamped(0.0f), passed(0.0f), clamped_passed(0.0f);
                for (size_t o = 0; o < offsets_.size(); ++o)
                    for (const Face& face : offsets_[o].faces) {
                        const vec3 flux = face.flux_factor * face_intensity(cell, face);
                        const vec3 positive = glm::max(flux, vec3(0.0f));
                        total += flux;
                        clamped += positive;
                        passed += t[o] * flux;
                        clamped_passed += t[o] * positive;
                    }
                for (int ch = 0; ch < 3; ++ch)
                    factors[c][ch] = clamp_ == LobeClamp::AtSurfaces
                                         ? at_surfaces_factor(total[ch], clamped[ch], passed[ch],
                                                              clamped_passed[ch])
                                         : rescale_factor(total[ch], clamped[ch]);
            }
        });
}

void PropagationStep::operator()(const ShVolume& source, ShVolume& destination,
                                 const PropagationTransmittance* transmittance,
                                 Progress* progress) const {
    if (!same_layout(source, destination) || source.order() != order_)
        throw InvalidArgument(format_message(
            "PropagationStep: source and destination volumes must both be order ", order_,
            " with the same counts (orders ", source.order(), ", ", destination.order(), ")"));
    if (transmittance != nullptr &&
        (transmittance->offsets != offset_count() ||
         transmittance->values.size() != source.cell_count() * size_t(offset_count())))
        throw InvalidArgument(format_message(
            "PropagationStep: transmittance has ", transmittance->values.size(), " values for ",
            transmittance->offsets, " offsets; expected ", source.cell_count(), " cells × ",
            offset_count(), " offsets"));
    const bool per_transfer = clamp_ == LobeClamp::AtBlockedTransfers;
    const bool at_surfaces = clamp_ == LobeClamp::AtSurfaces ||
                             clamp_ == LobeClamp::AtSurfacesToTotal || per_transfer;
    std::vector<uint8_t> blocked;
    std::vector<vec3> factors;
    rescale_factors(source, transmittance, factors, blocked, progress);
    const bool clamp_all = clamp_ == LobeClamp::Rescaled || clamp_ == LobeClamp::Clamped;
    const bool travel = reinjection_ != Reinjection::FaceNormal;
    const int floats = source.floats_per_cell();
    parallel_for(
        0, source.cell_count(), kCellsPerTask,
        [&](uint64_t begin, uint64_t end) {
            throw_if_cancelled(progress);
            for (uint64_t c = begin; c < end; ++c) {
                const ivec3 cell = source.cell_at(c);
                // Flux re-injected along each of the 6 axis normals, then one lobe per normal
                // (FaceNormal); or per face, then one beam per face (TravelDirection).
                vec3 flux[6] = {};
                std::array<vec3, kMaxStencilFaces> face_flux{};
                for (int o = 0; o < offset_count(); ++o) {
                    const Offset& offset = offsets_[size_t(o)];
                    const ivec3 from = cell - offset.offset;
                    if (!source.contains(from)) continue;
                    const float t = transmittance != nullptr
                                        ? transmittance->values[c * size_t(offset_count()) + size_t(o)]
                                        : 1.0f;
                    if (t <= 0.0f) continue;
                    const size_t s = source.cell_index(from);
                    const float* src = source.cell_data(s);
                    // AtBlockedTransfers clamps only the transfers a wall stops in part
                    // (t < 1) of the cells it splits (blocked 2).
                    const bool clamp_here =
                        clamp_all || (at_surfaces && blocked[s] != 0 &&
                                      (blocked[s] == 1 || t < 1.0f));
                    for (const Face& face : offset.faces) {
                        vec3 intensity = face_intensity(src, face);
                        if (clamp_here)
                            intensity = glm::max(intensity, vec3(0.0f)) * factors[s];
                        const vec3 crossing = (face.flux_factor * kPi * t) * intensity;
                        if (travel)
                            face_flux[size_t(face.index)] += crossing;
                        else
                            flux[face.normal_index] += crossing;
                    }
                }
                float* dst = destination.cell_data(c);
                std::fill(dst, dst + floats, 0.0f);
                if (travel) {
                    // Each face's flux as a beam along its direction: Y_i(ω_f) × flux (band 2
                    // windowed with WindowedTravelDirection).
                    for (const Offset& offset : offsets_)
                        for (const Face& face : offset.faces) {
                            const vec3& phi = face_flux[size_t(face.index)];
                            if (phi == vec3(0.0f)) continue;
                            for (int i = 0; i < coefficients_; ++i) {
                                dst[3 * i + 0] += face.beam[i] * phi.x;
                                dst[3 * i + 1] += face.beam[i] * phi.y;
                                dst[3 * i + 2] += face.beam[i] * phi.z;
                            }
                        }
                    continue;
                }
                for (int n = 0; n < 6; ++n) {
                    if (flux[n] == vec3(0.0f)) continue;
                    for (int i = 0; i < coefficients_; ++i) {
                        dst[3 * i + 0] += lobes_[n][i] * flux[n].x;
                        dst[3 * i + 1] += lobes_[n][i] * flux[n].y;
                        dst[3 * i + 2] += lobes_[n][i] * flux[n].z;
                    }
                }
            }
        });
}

}  // namespace shgi
