#include "radiance/radiance_grid.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "photon/photon.h"
#include "util/cell_sort.h"
#include "util/error.h"
#include "util/memory.h"

namespace shgi {
namespace {

// How far (in cells) a surface point is nudged to find the cell on its side: far above float
// rounding of hit points, far below any surface detail a cell resolves.
constexpr float kSideNudgeCells = 1e-3f;

// One cell's six faces' estimator numerators (W sr⁻¹), summed in hit order.
struct FaceFlux {
    std::array<vec3, kFaceCount> flux{};
    FaceFlux& operator+=(const FaceFlux& other) {
        for (int j = 0; j < kFaceCount; ++j) flux[size_t(j)] += other.flux[size_t(j)];
        return *this;
    }
};

// The hit's contribution to each face's numerator (see the header's estimators).
FaceFlux face_flux(const ReflectedHit& hit, FaceEstimator estimator) {
    FaceFlux out;
    const vec3 scattered = hit.reflected_power * kInvPi;
    if (estimator == FaceEstimator::ProjectedArea) {
        for (int j = 0; j < kFaceCount; ++j)
            out.flux[size_t(j)] = scattered * std::max(0.0f, glm::dot(hit.normal, face_normal(j)));
        return out;
    }
    // The seed's outgoing direction: the incoming one mirrored about the normal.
    const vec3 outgoing = 2.0f * glm::dot(hit.normal, hit.direction) * hit.normal - hit.direction;
    for (int j = 0; j < kFaceCount; ++j) {
        const float c = glm::dot(outgoing, face_normal(j));
        if (c > 0.0f) out.flux[size_t(j)] = scattered * (c * c);
    }
    return out;
}

}  // namespace

vec3 face_normal(int face) {
    vec3 n(0.0f);
    n[face / 2] = (face % 2 == 0) ? 1.0f : -1.0f;
    return n;
}

RadianceGrid::RadianceGrid(ShLattice surfaces, int levels, FaceEstimator estimator)
    : surfaces_(std::move(surfaces)), estimator_(estimator) {
    if (levels < 1)
        throw InvalidArgument(format_message("RadianceGrid: levels is ", levels,
                                             "; it must be >= 1"));
    const ivec3 dims0 = surfaces_.dims();
    // Per level: 6 areas and 18 radiance floats per cell; the sums another 18 at level 0. The
    // mips add at most 1/7 of level 0.
    const uint64_t cells = surfaces_.cell_count();
    require_memory(saturating_mul(cells, (6 + 18 + 18) * sizeof(float) * 8 / 7 + 1),
                   format_message("RadianceGrid: faces of ", cells, " cells"),
                   "lower RadianceFieldSettings.resolution");
    flux_sums_.assign(size_t(cells) * kFaceCount * 3, 0.0f);
    ivec3 dims = dims0;
    float cell_size = surfaces_.cell_size();
    for (int m = 0; m < levels; ++m) {
        Level level;
        level.dims = dims;
        level.cell_size = cell_size;
        const size_t count = size_t(dims.x) * size_t(dims.y) * size_t(dims.z);
        level.area.assign(count * kFaceCount, 0.0f);
        level.radiance.assign(count * kFaceCount * 3, 0.0f);
        levels_.push_back(std::move(level));
        if (dims == ivec3(1)) break;  // coarser levels would repeat this one
        dims = glm::max((dims + 1) / 2, ivec3(1));
        cell_size *= 2.0f;
    }
    update_levels(nullptr);  // the faces' areas; no radiance before the first pass
}

void RadianceGrid::clear() {
    std::fill(flux_sums_.begin(), flux_sums_.end(), 0.0f);
    surfaces_.clear();
    passes_ = 0;
    update_levels(nullptr);
}

ivec3 RadianceGrid::surface_cell(const vec3& p, const vec3& toward) const {
    const float nudge = kSideNudgeCells * surfaces_.cell_size();
    const ivec3 front = surfaces_.cell_of(p + toward * nudge);
    if (front.x >= 0 && surfaces_.surface_area(surfaces_.cell_index(front)) > 0.0f) return front;
    const ivec3 back = surfaces_.cell_of(p - toward * nudge);
    if (back.x >= 0 && surfaces_.surface_area(surfaces_.cell_index(back)) > 0.0f) return back;
    return front.x >= 0 ? front : back;
}

void RadianceGrid::add_pass(const std::vector<ReflectedHit>& hits, Progress* progress) {
    // The receiving sides first (ShLattice::inject with scale 0 only marks them): D_c counts the
    // sides light reaches.
    // Each hit is placed at the centre of the cell surface_cell() picks, so that the side it
    // marks is in the cell its flux goes to (a hit on a cell boundary could otherwise mark one
    // cell and feed another).
    std::vector<uint32_t> hit_cell(hits.size(), kNoCell);
    std::vector<Photon> arrivals;
    arrivals.reserve(hits.size());
    for (size_t i = 0; i < hits.size(); ++i) {
        const ivec3 cell = surface_cell(hits[i].position, hits[i].normal);
        if (cell.x < 0) continue;
        hit_cell[i] = uint32_t(surfaces_.cell_index(cell));
        const vec3 centre = origin() + (vec3(cell) + 0.5f) * surfaces_.cell_size();
        arrivals.push_back({centre, vec3(0.0f), hits[i].normal, hits[i].direction});
    }
    surfaces_.inject(arrivals, 0.0f, progress);
    arrivals = {};
    const ItemsByCell sorted = sort_by_cell(hit_cell, surfaces_.cell_count(), progress);
    const std::vector<FaceFlux> sums = sum_by_cell(
        sorted, FaceFlux{}, [&](uint32_t i) { return face_flux(hits[i], estimator_); }, progress,
        "RadianceGrid");
    for (size_t c = 0; c < sums.size(); ++c)
        for (int j = 0; j < kFaceCount; ++j)
            for (int k = 0; k < 3; ++k)
                flux_sums_[(c * kFaceCount + size_t(j)) * 3 + size_t(k)] += sums[c].flux[size_t(j)][k];
    ++passes_;
    update_levels(progress);
}

void RadianceGrid::update_levels(Progress* progress) {
    Level& level = levels_[0];
    const float mean = passes_ > 0 ? 1.0f / float(passes_) : 0.0f;
    const float face_area = level.cell_size * level.cell_size;
    for_each_slice(surfaces_.cell_count(), 4096, progress, [&](uint64_t begin, uint64_t end) {
        for (size_t c = size_t(begin); c < size_t(end); ++c) {
            const float surface = surfaces_.surface_area(c);
            for (int j = 0; j < kFaceCount; ++j) {
                const size_t f = c * kFaceCount + size_t(j);
                const float d = surface > 0.0f ? surfaces_.projected_area(c, face_normal(j)) : 0.0f;
                level.area[f] = d;
                const float denominator = estimator_ == FaceEstimator::ProjectedArea
                                              ? std::max(d, kMinProjectedFraction * surface)
                                              : face_area;
                const float scale = d > 0.0f ? mean / denominator : 0.0f;
                for (int k = 0; k < 3; ++k) level.radiance[f * 3 + size_t(k)] = flux_sums_[f * 3 + size_t(k)] * scale;
            }
        }
    });
    build_mips();
}

void RadianceGrid::build_mips() {
    for (size_t m = 1; m < levels_.size(); ++m) {
        const Level& child = levels_[m - 1];
        Level& parent = levels_[m];
        std::fill(parent.area.begin(), parent.area.end(), 0.0f);
        std::fill(parent.radiance.begin(), parent.radiance.end(), 0.0f);
        // Children in index order (a fixed summation order), each added to its parent.
        for (int z = 0; z < child.dims.z; ++z)
            for (int y = 0; y < child.dims.y; ++y)
                for (int x = 0; x < child.dims.x; ++x) {
                    const size_t from = child.index(ivec3(x, y, z));
                    const size_t to = parent.index(ivec3(x / 2, y / 2, z / 2));
                    for (int j = 0; j < kFaceCount; ++j) {
                        const float d = child.area[from * kFaceCount + size_t(j)];
                        if (!(d > 0.0f)) continue;
                        parent.area[to * kFaceCount + size_t(j)] += d;
                        for (int k = 0; k < 3; ++k)
                            parent.radiance[(to * kFaceCount + size_t(j)) * 3 + size_t(k)] +=
                                d * child.radiance[(from * kFaceCount + size_t(j)) * 3 + size_t(k)];
                    }
                }
        for (size_t f = 0; f < parent.area.size(); ++f) {
            const float d = parent.area[f];
            if (d > 0.0f)
                for (int k = 0; k < 3; ++k) parent.radiance[f * 3 + size_t(k)] /= d;
        }
    }
}

vec3 RadianceGrid::face_radiance(int level, const ivec3& cell, int face) const {
    const Level& l = levels_[size_t(level)];
    const size_t f = l.index(cell) * kFaceCount + size_t(face);
    return vec3(l.radiance[f * 3], l.radiance[f * 3 + 1], l.radiance[f * 3 + 2]);
}

float RadianceGrid::face_area(int level, const ivec3& cell, int face) const {
    const Level& l = levels_[size_t(level)];
    return l.area[l.index(cell) * kFaceCount + size_t(face)];
}

void RadianceGrid::set_face_radiance(const ivec3& cell, int face, const vec3& radiance) {
    Level& l = levels_[0];
    if (glm::any(glm::lessThan(cell, ivec3(0))) || glm::any(glm::greaterThanEqual(cell, l.dims)) ||
        face < 0 || face >= kFaceCount)
        throw InvalidArgument(format_message("RadianceGrid::set_face_radiance: cell (", cell.x,
                                             ", ", cell.y, ", ", cell.z, ") face ", face,
                                             " is outside the grid"));
    const size_t f = l.index(cell) * kFaceCount + size_t(face);
    for (int k = 0; k < 3; ++k) l.radiance[f * 3 + size_t(k)] = radiance[k];
    build_mips();
}

vec3 RadianceGrid::read_level(int level, const ivec3& cell0, const vec3& x, const vec3& d,
                              const vec3& side, float sigma, bool* lit) const {
    const Level& l = levels_[size_t(level)];
    const ivec3 cell = glm::min(cell0 / (1 << level), l.dims - 1);
    const size_t base = l.index(cell) * kFaceCount;
    const vec3 centre = origin() + (vec3(cell) + 0.5f) * l.cell_size;
    const float inv_two_sigma2 = 1.0f / (2.0f * sigma * sigma);
    vec3 sum(0.0f);
    float weights = 0.0f;
    for (int j = 0; j < kFaceCount; ++j) {
        if (!(l.area[base + size_t(j)] > 0.0f)) continue;  // no surface faces that way
        const vec3 n = face_normal(j);
        // Only faces the side the ray hit reflects through: a cell may also hold a side x cannot
        // see (the sunlit outside of a wall in a floor-and-wall crease cell), whose face points
        // towards x all the same.
        if (glm::dot(side, n) <= 0.0f) continue;
        // β from the ray itself rather than from the face's centre: x may lie in the hit cell or
        // beside it (a sample point over a floor), where the direction to a face's centre says
        // nothing about which side of the surface x sees.
        const float cos_beta = -glm::dot(n, d);
        if (cos_beta <= 0.0f) continue;  // the face looks away from x
        const vec3 to_face = centre + 0.5f * l.cell_size * n - x;
        const float distance = glm::length(to_face);
        const float alpha =
            distance > 0.0f ? std::acos(std::clamp(glm::dot(d, to_face) / distance, -1.0f, 1.0f))
                            : 0.0f;
        const float w = std::exp(-alpha * alpha * inv_two_sigma2) * cos_beta * l.area[base + size_t(j)];
        const size_t f = (base + size_t(j)) * 3;
        sum += w * vec3(l.radiance[f], l.radiance[f + 1], l.radiance[f + 2]);
        weights += w;
    }
    if (lit != nullptr) *lit = weights > 0.0f;
    return weights > 0.0f ? sum / weights : vec3(0.0f);
}

vec3 RadianceGrid::radiance_toward(const vec3& x, const vec3& hit, const vec3& d,
                                   const vec3& side, float level, float sigma, bool* lit) const {
    const ivec3 cell0 = surface_cell(hit, -d);
    if (lit != nullptr) *lit = false;
    if (cell0.x < 0) return vec3(0.0f);
    if (lit != nullptr) read_level(0, cell0, x, d, side, sigma, lit);
    const float clamped = std::clamp(level, 0.0f, float(levels() - 1));
    const int lo = int(clamped);
    const float t = clamped - float(lo);
    const vec3 fine = read_level(lo, cell0, x, d, side, sigma, nullptr);
    if (t <= 0.0f || lo + 1 >= levels()) return fine;
    return (1.0f - t) * fine + t * read_level(lo + 1, cell0, x, d, side, sigma, nullptr);
}

size_t RadianceGrid::memory_bytes() const {
    size_t bytes = surfaces_.memory_bytes() + flux_sums_.size() * sizeof(float);
    for (const Level& l : levels_) bytes += (l.area.size() + l.radiance.size()) * sizeof(float);
    return bytes;
}

}  // namespace shgi
