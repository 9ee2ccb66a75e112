#include "lattice/sh_lattice.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include <glm/gtx/component_wise.hpp>
#include <glm/gtx/string_cast.hpp>

#include "sh/sh_basis.h"
#include "util/binary_file.h"
#include "util/cell_sort.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/parallel.h"

namespace shgi {
namespace {

constexpr int kMaxResolution = 1024;
constexpr uint64_t kMaxCells = uint64_t(1) << 27;
// Margin around the bounds so that surfaces lying on them (a floor at the scene's lowest z) fall
// inside the lattice: a fraction of the longest side, at least an absolute floor for tiny scenes.
constexpr float kBoundsMarginFraction = 1e-4f;
constexpr float kMinBoundsMargin = 1e-5f;  // m
// A fraction of a cell by which an axis may exceed a whole number of cells before it gets one
// more: the margin then comes from slightly larger cells instead of a nearly empty cell layer.
constexpr double kCellCountSlack = 1e-3;
constexpr int kMaxCoefficients = 9 * 3;  // L2 RGB: the largest cell this lattice stores

// measure_surfaces: triangles per parallel chunk, and chunks whose fragments are held at once
// before they are merged (bounds the transient memory to ~0.5M triangles' fragments).
constexpr uint64_t kTrianglesPerChunk = 2048;
constexpr uint64_t kChunksPerBatch = 256;
// A triangle clipped by the 6 planes of a box gains at most one vertex per plane (convexity);
// the capacity leaves room for rounding producing a near-collinear extra vertex or two.
constexpr int kClipCapacity = 16;
// Slack (in cells) when bounding the cells a triangle's plane crosses in a column: the clipping
// is exact, so visiting one cell too many costs only time, and one too few loses area.
constexpr float kColumnSlackCells = 1e-3f;

// Anchors (update_visible_near) sit this far off their cell's surface, in cells; a surface whose
// front normals cancel (|Σ area × front| below this share of its area) keeps its anchor on it.
constexpr float kAnchorOffsetCells = 0.01f;
constexpr float kAnchorMinFrontShare = 0.05f;

constexpr uint64_t kPhotonsPerChunk = 1 << 16;
constexpr uint64_t kCellsPerChunk = 512;

const char* const kClassName = "ShLattice";

// ---------------------------------------------------------------------------------------------
// Surface measurement

// The part of one triangle inside one cell.
struct SurfaceFragment {
    uint32_t cell;
    uint32_t bin;
    float area;     // m^2
    vec3 normal;    // unit, sign-folded
    vec3 centroid;  // m, world
    vec3 front;     // unit, the triangle's own (unfolded) normal
};

// Per cell, per orientation bin: Σ area and Σ area × sign-folded unit normal.
struct BinSums {
    float area[3] = {0.0f, 0.0f, 0.0f};
    vec3 normal[3] = {vec3(0.0f), vec3(0.0f), vec3(0.0f)};
    vec3 centroid{0.0f};  // Σ area × centroid, all bins
    vec3 front{0.0f};     // Σ area × front normal, all bins

    void add(const SurfaceFragment& fragment) {
        area[fragment.bin] += fragment.area;
        normal[fragment.bin] += fragment.area * fragment.normal;
        centroid += fragment.area * fragment.centroid;
        front += fragment.area * fragment.front;
    }
};

// A convex polygon in a cell's local coordinates ([0, 1)^3 is the cell).
struct ClipPolygon {
    std::array<vec3, kClipCapacity> vertices;
    int count = 0;
};

// Sutherland–Hodgman against one axis-aligned plane. The cell is half-open, [0, 1): the lower
// plane keeps x >= 0 and the upper one keeps x < 1, so a polygon lying exactly on a shared face
// belongs to exactly one of the two cells (the one cell_of() picks), never to both. Returns
// false, leaving `out` untouched, when the plane keeps the whole polygon (the common case).
bool clip_against_plane(const ClipPolygon& in, int axis, bool upper, ClipPolygon& out) {
    auto distance = [&](const vec3& v) { return upper ? 1.0f - v[axis] : v[axis]; };
    auto inside = [&](float s) { return upper ? s > 0.0f : s >= 0.0f; };
    bool all_inside = true;
    for (int i = 0; i < in.count && all_inside; ++i) all_inside = inside(distance(in.vertices[i]));
    if (all_inside) return false;
    auto push = [&](const vec3& v) {
        if (out.count == kClipCapacity)
            throw Internal("ShLattice: a clipped triangle exceeded the polygon capacity");
        out.vertices[out.count++] = v;
    };
    out.count = 0;
    vec3 previous = in.vertices[in.count - 1];
    float s_previous = distance(previous);
    for (int i = 0; i < in.count; ++i) {
        const vec3& current = in.vertices[i];
        const float s_current = distance(current);
        if (inside(s_current) != inside(s_previous)) {
            const float t = s_previous / (s_previous - s_current);
            vec3 crossing = previous + t * (current - previous);
            crossing[axis] = upper ? 1.0f : 0.0f;  // exactly on the plane, whatever the rounding
            push(crossing);
        }
        if (inside(s_current)) push(current);
        previous = current;
        s_previous = s_current;
    }
    return true;
}

// Area (in cells²) of the triangle q0 q1 q2 (cell coordinates) inside cell `cell`, and the
// centroid of that piece (cell coordinates); `unit_normal` is the triangle's.
float clipped_area(const vec3 q[3], const ivec3& cell, const vec3& unit_normal, vec3& centroid) {
    ClipPolygon buffers[2];
    ClipPolygon* polygon = &buffers[0];
    ClipPolygon* clipped = &buffers[1];
    const vec3 corner(cell);
    for (int i = 0; i < 3; ++i) polygon->vertices[i] = q[i] - corner;
    polygon->count = 3;
    for (int plane = 0; plane < 6; ++plane) {
        if (clip_against_plane(*polygon, plane / 2, plane % 2 == 1, *clipped))
            std::swap(polygon, clipped);
        if (polygon->count < 3) return 0.0f;
    }
    vec3 twice_area(0.0f);
    vec3 moment(0.0f);  // Σ (twice the fan triangle's signed area) × its centroid
    float weight = 0.0f;
    const vec3* v = polygon->vertices.data();
    for (int i = 1; i + 1 < polygon->count; ++i) {
        const vec3 twice = glm::cross(v[i] - v[0], v[i + 1] - v[0]);
        twice_area += twice;
        const float w = glm::dot(twice, unit_normal);
        moment += w * (v[0] + v[i] + v[i + 1]) / 3.0f;
        weight += w;
    }
    centroid = corner + (weight != 0.0f ? moment / weight : v[0]);
    return 0.5f * std::fabs(glm::dot(twice_area, unit_normal));
}

int dominant_axis(const vec3& v) {
    const vec3 a = glm::abs(v);
    return a.x >= a.y && a.x >= a.z ? 0 : (a.y >= a.z ? 1 : 2);
}

// Calls emit(cell, area in cells², centroid in cell coordinates) for every cell the triangle
// q0 q1 q2 (cell coordinates) has area in. The cells visited are those of the triangle's
// bounding box, walked column by column along the dominant axis of its normal and limited in
// each column to the span the plane crosses, so the work grows with the cells the triangle
// touches, not with its box's volume.
template <typename Emit>
void for_each_cell_piece(const vec3 q[3], const ivec3& dims, Emit&& emit) {
    const vec3 lo = glm::min(q[0], glm::min(q[1], q[2]));
    const vec3 hi = glm::max(q[0], glm::max(q[1], q[2]));
    const vec3 dims_f(dims);
    if (glm::any(glm::lessThan(hi, vec3(0.0f))) || glm::any(glm::greaterThanEqual(lo, dims_f)))
        return;
    const vec3 m = glm::cross(q[1] - q[0], q[2] - q[0]);
    const float twice_area = glm::length(m);
    if (!(twice_area > 0.0f)) return;  // below float resolution in cell units
    const vec3 unit_normal = m / twice_area;
    const ivec3 first = glm::clamp(ivec3(glm::floor(glm::max(lo, vec3(0.0f)))), ivec3(0), dims - 1);
    const ivec3 last = glm::clamp(ivec3(glm::floor(glm::min(hi, dims_f))), ivec3(0), dims - 1);
    const bool inside_lattice = glm::all(glm::greaterThanEqual(lo, vec3(0.0f))) &&
                                glm::all(glm::lessThan(hi, dims_f));
    if (inside_lattice && first == last) {
        emit(first, 0.5f * twice_area, (q[0] + q[1] + q[2]) / 3.0f);  // all in one cell
        return;
    }
    const int w = dominant_axis(m), u = (w + 1) % 3, v = (w + 2) % 3;
    const float plane = glm::dot(m, q[0]);
    ivec3 cell;
    for (cell[v] = first[v]; cell[v] <= last[v]; ++cell[v]) {
        for (cell[u] = first[u]; cell[u] <= last[u]; ++cell[u]) {
            // The plane's w coordinate over the column's square is extreme at its corners.
            float w_min = std::numeric_limits<float>::max(), w_max = -w_min;
            for (int corner = 0; corner < 4; ++corner) {
                const float cu = float(cell[u] + (corner & 1)), cv = float(cell[v] + (corner >> 1));
                const float cw = (plane - m[u] * cu - m[v] * cv) / m[w];
                w_min = std::min(w_min, cw);
                w_max = std::max(w_max, cw);
            }
            const int k0 = std::max(first[w], int(std::floor(std::max(
                                                  w_min - kColumnSlackCells, float(first[w])))));
            const int k1 = std::min(last[w], int(std::floor(std::min(
                                                 w_max + kColumnSlackCells, float(last[w])))));
            for (cell[w] = k0; cell[w] <= k1; ++cell[w]) {
                vec3 centroid(0.0f);
                const float area = clipped_area(q, cell, unit_normal, centroid);
                if (area > 0.0f) emit(cell, area, centroid);
            }
        }
    }
}

// The instanced triangles of a scene, numbered consecutively instance after instance.
class InstancedTriangles {
  public:
    explicit InstancedTriangles(const Scene& scene) : scene_(scene) {
        first_.reserve(scene.instances().size() + 1);
        uint64_t total = 0;
        for (const Instance& instance : scene.instances()) {
            first_.push_back(total);
            total += scene.meshes()[instance.mesh_id].triangles.size();
        }
        first_.push_back(total);
    }
    uint64_t count() const { return first_.back(); }

    // Calls body(p0, p1, p2) with the world-space vertices of triangles [begin, end).
    template <typename Body>
    void for_each(uint64_t begin, uint64_t end, Body&& body) const {
        size_t instance = size_t(std::upper_bound(first_.begin(), first_.end(), begin) -
                                 first_.begin()) - 1;
        for (uint64_t t = begin; t < end; ++t) {
            while (t >= first_[instance + 1]) ++instance;
            const Instance& inst = scene_.instances()[instance];
            const Mesh& mesh = scene_.meshes()[inst.mesh_id];
            const uvec3& tri = mesh.triangles[t - first_[instance]];
            const mat4& world_from_object = inst.world_from_object;
            body(vec3(world_from_object * vec4(mesh.positions[tri.x], 1.0f)),
                 vec3(world_from_object * vec4(mesh.positions[tri.y], 1.0f)),
                 vec3(world_from_object * vec4(mesh.positions[tri.z], 1.0f)));
        }
    }

  private:
    const Scene& scene_;
    std::vector<uint64_t> first_;  // first global triangle of each instance, then the total
};

// The pieces of instanced triangles [begin, end) in the cells of `lattice`, in triangle order.
// Triangle normals are sign-folded: flipped so that their dominant component, which names the
// orientation bin, is positive.
void clip_triangles(const InstancedTriangles& triangles, uint64_t begin, uint64_t end,
                    const ShLattice& lattice, std::vector<SurfaceFragment>& out) {
    out.clear();
    const vec3 origin = lattice.origin();
    const float cell_size = lattice.cell_size();
    const float cell_face = cell_size * cell_size;
    triangles.for_each(begin, end, [&](const vec3& p0, const vec3& p1, const vec3& p2) {
        vec3 normal = glm::cross(p1 - p0, p2 - p0);
        const float length = glm::length(normal);
        if (!(length > 0.0f) || !std::isfinite(length)) return;  // degenerate in world space
        normal /= length;
        const vec3 front = normal;
        const int bin = dominant_axis(normal);
        if (normal[bin] < 0.0f) normal = -normal;
        const vec3 q[3] = {(p0 - origin) / cell_size, (p1 - origin) / cell_size,
                           (p2 - origin) / cell_size};
        for_each_cell_piece(q, lattice.dims(), [&](const ivec3& cell, float area_cells,
                                                   const vec3& centroid_cells) {
            out.push_back({uint32_t(lattice.cell_index(cell)), uint32_t(bin),
                           area_cells * cell_face, normal, origin + centroid_cells * cell_size,
                           front});
        });
    });
}

// ---------------------------------------------------------------------------------------------
// Injection

// ---------------------------------------------------------------------------------------------
// Sampling
//
// A lookup runs for every shading point of every preview frame and visits up to 27 cells, so it
// avoids work that cannot change its result: no heap allocation (fixed-size sums), cells outside
// the filter's reach tested first (three multiplications), then cells without surface or facing
// away from n (D_c(n) = 0, one load and three dot products), and the filter weight (a square root)
// computed last; ShLattice::sample_* also return at once when no cell of the neighbourhood holds
// radiance. Only exactly-zero terms are left out, so results are those of the plain weighted sum.

// All zero, of the lattice's order (validated at construction, so ShRgb's checking constructor,
// which is not inline, is not needed).
ShRgb zero_radiance(int order) {
    ShRgb radiance;
    radiance.order = order;
    return radiance;
}

// The cells a sample reads with their weights w_c (filter weight x D_c(n)), in visiting order;
// cells whose weight is not positive are left out. At most 27 (the cubic filter's block).
struct CellWeights {
    static constexpr int kCapacity = 27;
    int count = 0;
    std::array<size_t, kCapacity> cell;
    std::array<float, kCapacity> weight;

    void add(size_t c, float w) {
        if (!(w > 0.0f)) return;
        cell[count] = c;
        weight[count] = w;
        ++count;
    }
};

// Σ w_c L(c) / Σ w_c. Done after every weight is known, so that the loop over cells holds only
// the sums, which then stay in vector registers: kFloats (3 x coefficients) is a compile-time
// count and the inner loop is unrolled completely. The pragma makes sure it is: without it,
// GCC 12 at -O3 jams the inner loops of two cells into one scalar loop over memory (unroll and
// jam), three times the instructions. The sums are taken in visiting order.
template <int kFloats>
ShRgb blend_cells(int order, const float* coefficients, const CellWeights& cells) {
    static_assert(kFloats <= kMaxCoefficients, "the unroll count below covers every cell size");
    std::array<float, kFloats> sum{};
    float total = 0.0f;
    for (int k = 0; k < cells.count; ++k) {
        const float weight = cells.weight[k];
        const float* cell = coefficients + cells.cell[k] * kFloats;
#pragma GCC unroll 27
        for (int i = 0; i < kFloats; ++i) sum[i] += weight * cell[i];
        total += weight;
    }
    ShRgb radiance = zero_radiance(order);
    if (total <= 0.0f) return radiance;
    const float inv_total = 1.0f / total;
    float* out = radiance.data();
    for (int i = 0; i < kFloats; ++i) out[i] = sum[i] * inv_total;
    return radiance;
}

// Lattice coordinates in cells of the sample point and their floor (the cell holding it), or
// false for a non-finite point: the coordinates of trilinear and cubic samples alike. Far-away
// points are clamped (keeping them outside) so the integer conversions cannot overflow; the
// floor is exact for the clamped cells (|x| < 2^24). With SSE2 the three axes run in one
// register: one division where the scalar code made three in a row on the divider, and an
// integer floor (truncate, then one less where that rounded up) of ~8 instructions where
// glm::floor without SSE4.1 took ~13 an axis. The same IEEE operations per axis as the scalar
// code, so the same cells.
inline bool sample_coordinates(const vec3& p, const vec3& n, float normal_offset,
                               const vec3& origin, float cell_size, const ivec3& dims,
                               vec3& cells, ivec3& centre) {
#if defined(__SSE2__)
    const __m128 n_lanes = _mm_setr_ps(n.x, n.y, n.z, 0.0f);
    const __m128 q = _mm_add_ps(_mm_setr_ps(p.x, p.y, p.z, 0.0f),
                                _mm_mul_ps(_mm_set1_ps(normal_offset * cell_size), n_lanes));
    // x - x is 0 exactly for finite x, NaN for infinities and NaN (std::isfinite per axis).
    if ((_mm_movemask_ps(_mm_cmpeq_ps(_mm_sub_ps(q, q), _mm_setzero_ps())) & 0x7) != 0x7)
        return false;
    const vec3 upper = vec3(dims) + 4.0f;
    const __m128 origin_lanes = _mm_setr_ps(origin.x, origin.y, origin.z, 0.0f);
    const __m128 scaled = _mm_div_ps(_mm_sub_ps(q, origin_lanes), _mm_set1_ps(cell_size));
    const __m128 clamped = _mm_min_ps(_mm_max_ps(scaled, _mm_set1_ps(-4.0f)),
                                      _mm_setr_ps(upper.x, upper.y, upper.z, 0.0f));
    const __m128i truncated = _mm_cvttps_epi32(clamped);
    const __m128i rounded_up = _mm_castps_si128(_mm_cmplt_ps(clamped, _mm_cvtepi32_ps(truncated)));
    alignas(16) std::array<float, 4> cell_lanes;
    alignas(16) std::array<int32_t, 4> floor_lanes;
    _mm_store_ps(cell_lanes.data(), clamped);
    _mm_store_si128(reinterpret_cast<__m128i*>(floor_lanes.data()),
                    _mm_add_epi32(truncated, rounded_up));  // rounded_up is -1 or 0
    cells = vec3(cell_lanes[0], cell_lanes[1], cell_lanes[2]);
    centre = ivec3(floor_lanes[0], floor_lanes[1], floor_lanes[2]);
#else
    const vec3 q = p + (normal_offset * cell_size) * n;
    if (!is_finite(q)) return false;
    cells = glm::clamp((q - origin) / cell_size, vec3(-4.0f), vec3(dims) + 4.0f);
    centre = ivec3(glm::floor(cells));
#endif
    return true;
}

// visit(cell index, trilinear weight × facing(cell)) for the lattice cells among the 8 whose
// centres surround `cells` and that face the normal (facing(cell) > 0).
// `seen` is the block mask (below) of the cells around floor(cells) the sample may read.
template <typename Facing, typename Visit>
void for_each_trilinear_cell(const vec3& cells, const ivec3& dims, uint32_t seen, Facing&& facing,
                             Visit&& visit) {
    const vec3 f = cells - 0.5f;  // relative to cell centres
    const ivec3 base(glm::floor(f));
    const ivec3 centre(glm::floor(cells));  // base or base + 1 on each axis
    const vec3 t = f - vec3(base);
    const ivec3 lo = glm::max(base, ivec3(0)), hi = glm::min(base + 1, dims - 1);
    for (int z = lo.z; z <= hi.z; ++z) {
        const float wz = z == base.z ? 1.0f - t.z : t.z;
        for (int y = lo.y; y <= hi.y; ++y) {
            const float wyz = (y == base.y ? 1.0f - t.y : t.y) * wz;
            const size_t row = size_t(dims.x) * (size_t(y) + size_t(dims.y) * size_t(z));
            for (int x = lo.x; x <= hi.x; ++x) {
                const int bit =
                    (z - centre.z + 1) * 9 + (y - centre.y + 1) * 3 + (x - centre.x + 1);
                if (!(seen & (uint32_t(1) << bit))) continue;
                const size_t cell = row + size_t(x);
                const float density = facing(cell);
                if (density > 0.0f) visit(cell, (x == base.x ? 1.0f - t.x : t.x) * wyz * density);
            }
        }
    }
}

// Bit k of a block mask (ShLattice::surface_near_) stands for the block's cell at offset
// (kBlockOffset[k % 3], kBlockOffset[k / 3 % 3], kBlockOffset[k / 9]) from its centre: bits in
// increasing order visit the 3x3x3 block z-major, then y, then x.
constexpr int kBlockOffset[3] = {-1, 0, 1};
constexpr uint32_t block_bit(int dx, int dy, int dz) {
    return uint32_t(1) << ((dz + 1) * 9 + (dy + 1) * 3 + (dx + 1));
}
// (k % 3, k / 3 % 3, k / 9) of each block bit k: a lookup instead of three divisions by 3 for
// every cell a cubic sample visits.
struct BlockDigits {
    uint8_t x, y, z;
};
constexpr std::array<BlockDigits, 27> kBlockDigits = [] {
    std::array<BlockDigits, 27> digits{};
    for (int k = 0; k < 27; ++k)
        digits[size_t(k)] = BlockDigits{uint8_t(k % 3), uint8_t(k / 3 % 3), uint8_t(k / 9)};
    return digits;
}();

// D_c(n) of the cells of one 3x3x3 block for one normal, per block bit k, computed as the walk
// needs them and kept for the next sample of the same lattice surfaces, block and normal (the
// bits of n), with the list of the cells of the last block mask walked that face n: the pixels
// of a wall read the same block with the same normal for several lookups in a row, and finding
// those cells (the block bit's cell index and D_c(n), two loads and a dot product per bin) was
// half of a cubic sample's cell walk. Each thread has its own (sample_cubic), so lookups stay
// independent of the thread count; the values are those facing(cell) gives, visited in the same
// order, so results are bit for bit those without it.
struct FacingMemo {
    uint64_t surfaces_id = 0;  // ShLattice::surfaces_id_; 0 holds nothing
    size_t block = 0;
    std::array<uint32_t, 3> normal{};  // the bits of n
    uint32_t known = 0;     // block bits whose D_c(n) is in density
    uint32_t positive = 0;  // block bits whose D_c(n) > 0
    std::array<float, 27> density;
    // The cells of block mask list_mask that face n, in block-bit order (list_count of them; a
    // list_mask of 0 holds none).
    uint32_t list_mask = 0;
    int list_count = 0;
    std::array<BlockDigits, 27> list_digits;
    std::array<size_t, 27> list_cell;
    std::array<float, 27> list_density;

    // Keyed on (surfaces, block, n): the entries of another key are dropped.
    void key(uint64_t surfaces, size_t block_index, const vec3& n) {
        std::array<uint32_t, 3> bits;
        std::memcpy(bits.data(), &n[0], sizeof(bits));
        if (surfaces == surfaces_id && block_index == block && bits == normal) return;
        surfaces_id = surfaces;
        block = block_index;
        normal = bits;
        known = positive = list_mask = 0;
    }
};

FacingMemo& thread_facing_memo() {
    static thread_local FacingMemo memo;
    return memo;
}

// visit(cell index, w(d) × D_c(n)) for the cells of the 3x3x3 block around `centre` (the cell
// holding `cells`, at most one cell outside the lattice) that `mask`, the centre's block mask,
// marks as lattice cells with surface, that face the normal (D_c(n) > 0, from `memo`, which
// facing(cell) fills for the bits of `mask` it lacks) and whose centres are closer than
// kCubicRadiusCells, in block-bit order. Cells without surface would get D_c(n) = 0 and be left
// out anyway; not visiting them saves a load and a branch each, which goes both ways at random: a
// point on a wall has surface in about a third of its block.
template <typename Facing, typename Visit>
void for_each_cubic_cell(const vec3& cells, const ivec3& centre, uint32_t mask, const ivec3& dims,
                         FacingMemo& memo, Facing&& facing, Visit&& visit) {
    if (mask == 0) return;
    if (mask != memo.list_mask) {
        // Signed: the centre may lie just outside the lattice; the cells the mask marks lie
        // inside.
        const ptrdiff_t row = dims.x, slice = ptrdiff_t(dims.x) * ptrdiff_t(dims.y);
        const ptrdiff_t centre_cell = centre.x + row * centre.y + slice * centre.z;
        const auto cell_of_bit = [&](int k) {
            const BlockDigits digits = kBlockDigits[size_t(k)];
            return size_t(centre_cell + kBlockOffset[digits.x] + kBlockOffset[digits.y] * row +
                          kBlockOffset[digits.z] * slice);
        };
        for (uint32_t missing = mask & ~memo.known; missing != 0; missing &= missing - 1) {
            const int k = __builtin_ctz(missing);
            const float density = facing(cell_of_bit(k));
            memo.density[size_t(k)] = density;
            if (density > 0.0f) memo.positive |= uint32_t(1) << k;
        }
        memo.known |= mask;
        memo.list_mask = mask;
        memo.list_count = 0;
        for (uint32_t facing_n = mask & memo.positive; facing_n != 0; facing_n &= facing_n - 1) {
            const int k = __builtin_ctz(facing_n);
            const size_t at = size_t(memo.list_count++);
            memo.list_digits[at] = kBlockDigits[size_t(k)];
            memo.list_cell[at] = cell_of_bit(k);
            memo.list_density[at] = memo.density[size_t(k)];
        }
    }
    if (memo.list_count == 0) return;
    constexpr float r2 = kCubicRadiusCells * kCubicRadiusCells;
    float d2_along[3][3];  // [axis][offset + 1]: squared distance to that row's centres
    for (int a = 0; a < 3; ++a)
        for (int i = 0; i < 3; ++i) {
            const float d = cells[a] - (float(centre[a] + kBlockOffset[i]) + 0.5f);
            d2_along[a][i] = d * d;
        }
    for (int i = 0; i < memo.list_count; ++i) {
        const BlockDigits digits = memo.list_digits[size_t(i)];
        const float d2 = d2_along[0][digits.x] + (d2_along[1][digits.y] + d2_along[2][digits.z]);
        if (d2 >= r2) continue;
        visit(memo.list_cell[size_t(i)],
              cubic_falloff(std::sqrt(d2)) * memo.list_density[size_t(i)]);
    }
}

// The process-wide source of ShLattice::surfaces_id_ (0 is no lattice's).
std::atomic<uint64_t> next_surfaces_id{1};

// out[c] = in[c - 1] | in[c] | in[c + 1] along `axis` (cells outside the lattice count as 0).
void dilate_along(const std::vector<uint8_t>& in, const ivec3& dims, int axis,
                  std::vector<uint8_t>& out) {
    const size_t stride =
        axis == 0 ? 1 : axis == 1 ? size_t(dims.x) : size_t(dims.x) * size_t(dims.y);
    const size_t length = size_t(dims[axis]);
    for (size_t c = 0; c < in.size(); ++c) {
        const size_t i = (c / stride) % length;  // c's coordinate along the axis
        uint8_t near = in[c];
        if (i > 0) near |= in[c - stride];
        if (i + 1 < length) near |= in[c + stride];
        out[c] = near;
    }
}

}  // namespace

// ---------------------------------------------------------------------------------------------

ShLattice::ShLattice(const Bounds3& bounds, int resolution, int order) : order_(order) {
    if (resolution < 1 || resolution > kMaxResolution)
        throw InvalidArgument(format_message(kClassName, ": resolution = ", resolution,
                                             " must be in [1, ", kMaxResolution, "]"));
    if (order < 1 || order > 2)
        throw InvalidArgument(format_message(kClassName, ": order = ", order,
                                             " must be 1 (L1, 4 coefficients) or 2 (L2, 9)"));
    if (bounds.empty())
        throw InvalidArgument(format_message(kClassName, ": bounds are empty (lower ",
                                             glm::to_string(bounds.lower), " exceeds upper ",
                                             glm::to_string(bounds.upper), ")"));
    if (!is_finite(bounds.lower) || !is_finite(bounds.upper) || !is_finite(bounds.extent()))
        throw InvalidArgument(format_message(kClassName, ": bounds ", glm::to_string(bounds.lower),
                                             " to ", glm::to_string(bounds.upper),
                                             " are not finite"));
    // Cell size from the longest side grown by the margin; per axis, just enough cells to hold
    // the extent (an extent of exactly k cells gets k, not k + 1 for its margin); then the cells
    // grow by the tiny amount that gives every axis the margin, and the grid is centred.
    const vec3 extent = bounds.extent();
    const double longest = glm::compMax(extent);
    const double margin =
        std::max(double(kBoundsMarginFraction) * longest, double(kMinBoundsMargin));
    const double base_cell_size = (longest + 2.0 * margin) / resolution;
    double cell_size = base_cell_size;
    uint64_t cells = 1;
    for (int a = 0; a < 3; ++a) {
        const double count = std::ceil(double(extent[a]) / base_cell_size - kCellCountSlack);
        dims_[a] = std::max(1, int(count));
        cell_size = std::max(cell_size, (double(extent[a]) + 2.0 * margin) / dims_[a]);
        cells *= uint64_t(dims_[a]);
    }
    cell_size_ = float(cell_size);
    const glm::dvec3 centre = 0.5 * (glm::dvec3(bounds.lower) + glm::dvec3(bounds.upper));
    origin_ = vec3(centre - 0.5 * cell_size * glm::dvec3(dims_));
    if (cells > kMaxCells)
        throw InvalidArgument(format_message(
            kClassName, ": resolution = ", resolution, " over bounds of extent ",
            glm::to_string(extent), " gives ", dims_.x, " x ", dims_.y, " x ", dims_.z, " = ",
            cells, " cells, more than ", kMaxCells, "; lower the resolution"));
    allocate(format_message(kClassName, ": resolution = ", resolution, " gives"));
}

ShLattice::ShLattice(const vec3& origin, float cell_size, const ivec3& dims, int order)
    : order_(order), dims_(dims), origin_(origin), cell_size_(cell_size) {
    if (order < 1 || order > 2)
        throw InvalidArgument(format_message(kClassName, ": order = ", order,
                                             " must be 1 (L1, 4 coefficients) or 2 (L2, 9)"));
    if (!is_finite(origin) || !std::isfinite(cell_size) || !(cell_size > 0.0f))
        throw InvalidArgument(format_message(kClassName, ": origin ", glm::to_string(origin),
                                             " and cell size ", cell_size,
                                             " must be finite, the cell size positive"));
    if (dims.x < 1 || dims.y < 1 || dims.z < 1)
        throw InvalidArgument(format_message(kClassName, ": dims ", glm::to_string(dims),
                                             " must be at least 1 per axis"));
    const uint64_t cells = uint64_t(dims.x) * uint64_t(dims.y) * uint64_t(dims.z);
    if (cells > kMaxCells)
        throw InvalidArgument(format_message(kClassName, ": dims ", glm::to_string(dims),
                                             " give ", cells, " cells, more than ", kMaxCells));
    allocate(format_message(kClassName, ": a grid of"));
}

void ShLattice::allocate(const std::string& what) {
    const uint64_t cells = uint64_t(cell_count());
    const uint64_t cell_bytes = uint64_t(num_coefficients()) * 3 * sizeof(float) +
                                sizeof(uint32_t) * 2 + sizeof(uint8_t);
    require_memory(saturating_mul(cells, cell_bytes),
                   format_message(what, " ", dims_.x, " x ", dims_.y, " x ", dims_.z, " = ",
                                  cells, " cells of ", cell_bytes, " bytes (order ", order_, ")"),
                   "lower the resolution");
    coeffs_.assign(cells * size_t(num_coefficients()) * 3, 0.0f);
    surface_index_.assign(cells, kNoSurface);
    surface_near_.assign(size_t(dims_.x + 2) * size_t(dims_.y + 2) * size_t(dims_.z + 2), 0u);
    visible_near_.assign(surface_near_.size(), kFullBlock);
    radiance_near_.assign(cells, 0);
    renew_surfaces_id();
}

ivec3 ShLattice::cell_of(const vec3& p) const {
    const ivec3 outside(-1);
    if (!is_finite(p)) return outside;
    const vec3 f = (p - origin_) / cell_size_;
    if (glm::any(glm::lessThan(f, vec3(0.0f))) || glm::any(glm::greaterThanEqual(f, vec3(dims_))))
        return outside;
    return ivec3(glm::floor(f));
}

void ShLattice::check_cell(size_t cell, const char* what) const {
    if (cell >= cell_count())
        throw InvalidArgument(format_message(kClassName, "::", what, ": cell = ", cell,
                                             " but the lattice has ", cell_count(), " cells"));
}

float ShLattice::surface_area(size_t cell) const {
    check_cell(cell, "surface_area");
    return cell_area(cell);
}

float ShLattice::projected_area(size_t cell, const vec3& dir) const {
    check_cell(cell, "projected_area");
    const CellSurface* surface = cell_surface(cell);
    return surface ? surface->projected_area(dir) : 0.0f;
}

uint8_t ShLattice::receiving_sides(size_t cell) const {
    check_cell(cell, "receiving_sides");
    const CellSurface* surface = cell_surface(cell);
    return surface ? surface->receiving : 0;
}

// Compares cosines, |n̄_b · normal| = |projected_b · normal| / |projected_b|, so that a bin's
// area does not decide; a photon's normal is that of the triangle it hit, up to its sign and
// rounding, so the bin holding that triangle wins unless another bin's mean is nearly parallel.
std::array<float, 3> ShLattice::CellSurface::bin_lengths() const {
    return {glm::length(projected[0]), glm::length(projected[1]), glm::length(projected[2])};
}

uint8_t ShLattice::CellSurface::side_facing(const vec3& normal,
                                            const std::array<float, 3>& lengths) const {
    uint8_t side = 0;
    float best = 0.0f;
    for (int b = 0; b < 3; ++b) {
        const float length = lengths[b];
        if (!(length > 0.0f)) continue;
        const float cosine = glm::dot(projected[b], normal) / length;
        if (std::fabs(cosine) > best) {
            best = std::fabs(cosine);
            side = side_bit(b, cosine > 0.0f);
        }
    }
    return side;
}

// Triangles are clipped in parallel chunks; each chunk lists its fragments in triangle order and
// the chunks are merged in chunk order, so the float sums do not depend on the thread count.
// Chunks are processed in batches to bound the fragments held at once.
void ShLattice::measure_surfaces(const Scene& scene, Progress* progress, bool visibility) {
    if (!scene.committed())
        throw InvalidArgument(format_message(kClassName, "::measure_surfaces: the scene was edited "
                                             "or never committed; call commit() first"));
    const InstancedTriangles triangles(scene);
    const uint64_t total = cell_count() == 0 ? 0 : triangles.count();  // default-constructed
    const uint64_t chunk_count = (total + kTrianglesPerChunk - 1) / kTrianglesPerChunk;
    std::vector<uint32_t> surface_index(cell_count(), kNoSurface);
    std::vector<BinSums> sums;  // per cell with surface, in order of its first fragment
    std::vector<std::vector<SurfaceFragment>> fragments(std::min(chunk_count, kChunksPerBatch));
    std::atomic<uint64_t> done{0};
    // Progress: the triangles' clipping, then (with visibility) the visibility rays, which take
    // as long or longer: each half of the range.
    const uint64_t span = visibility ? 2 * total : total;

    for (uint64_t batch = 0; batch < chunk_count; batch += kChunksPerBatch) {
        const uint64_t batch_end = std::min(chunk_count, batch + kChunksPerBatch);
        parallel_for(batch, batch_end, 1, [&](uint64_t begin, uint64_t end) {
            throw_if_cancelled(progress);
            for (uint64_t chunk = begin; chunk < end; ++chunk) {
                const uint64_t first = chunk * kTrianglesPerChunk;
                const uint64_t last = std::min(total, first + kTrianglesPerChunk);
                clip_triangles(triangles, first, last, *this, fragments[chunk - batch]);
                if (progress) progress->report(done += last - first, span);
            }
        });
        for (uint64_t chunk = batch; chunk < batch_end; ++chunk) {
            for (const SurfaceFragment& fragment : fragments[chunk - batch]) {
                uint32_t& index = surface_index[fragment.cell];
                if (index == kNoSurface) {
                    index = uint32_t(sums.size());
                    sums.emplace_back();
                }
                sums[index].add(fragment);
            }
        }
    }
    // Stored in cell order, so that neighbouring cells' surfaces, which a lookup reads together,
    // are close in memory too.
    std::vector<CellSurface> surfaces;
    std::vector<vec3> anchors;  // per surface: the point its visibility is tested from
    surfaces.reserve(sums.size());
    anchors.reserve(sums.size());
    const float anchor_offset = kAnchorOffsetCells * cell_size_;
    for (uint32_t& index : surface_index) {
        if (index == kNoSurface) continue;
        const BinSums& sum = sums[index];
        CellSurface surface;
        for (int b = 0; b < 3; ++b) {
            const float length = glm::length(sum.normal[b]);
            if (length > 0.0f) surface.projected[b] = sum.normal[b] * (sum.area[b] / length);
            if (surface.projected[b] != vec3(0.0f)) surface.bins |= uint8_t(1u << b);
            surface.area += sum.area[b];
        }
        // The surface's area-weighted centroid, moved off it along its mean front normal (to the
        // side its triangles face), where light it receives comes from.
        vec3 anchor = sum.centroid / surface.area;
        const float front = glm::length(sum.front);
        if (front > kAnchorMinFrontShare * surface.area)
            anchor += (anchor_offset / front) * sum.front;
        index = uint32_t(surfaces.size());
        surfaces.push_back(surface);
        anchors.push_back(anchor);
    }
    // Cancel keeps the previous surfaces: the new ones are measured aside, then swapped in.
    std::vector<uint32_t> previous_index = std::move(surface_index_);
    std::vector<CellSurface> previous_surfaces = std::move(surfaces_);
    std::vector<uint32_t> previous_near = surface_near_, previous_visible = visible_near_;
    surface_index_ = std::move(surface_index);
    surfaces_ = std::move(surfaces);
    update_surface_near();
    try {
        if (visibility)
            update_visible_near(scene, anchors, progress, total, span);
        else
            visible_near_.assign(surface_near_.size(), kFullBlock);
    } catch (const Cancelled&) {
        surface_index_ = std::move(previous_index);
        surfaces_ = std::move(previous_surfaces);
        surface_near_ = std::move(previous_near);
        visible_near_ = std::move(previous_visible);
        renew_surfaces_id();
        throw;
    }
    renew_surfaces_id();
    if (progress) progress->set_fraction(1.0f);
}

// Per block centre, the block's surface cells whose anchors the centre's anchor sees (the segment
// between them hits nothing). A centre's anchor is its surface's (anchors[surface index]) or, for
// a cell without surface, its middle. Each segment is traced from the anchor of the cell with the
// lower padded index, so that two surface cells see each other or not both ways, whatever the
// thread count.
void ShLattice::update_visible_near(const Scene& scene, const std::vector<vec3>& anchors,
                                    Progress* progress, uint64_t reported, uint64_t span) {
    const ivec3 padded = dims_ + 2;
    const size_t count = surface_near_.size();
    std::atomic<uint64_t> cells_done{0};
    visible_near_.assign(count, 0u);
    const auto anchor_of = [&](const ivec3& at) {
        const bool inside = glm::all(glm::greaterThanEqual(at, ivec3(0))) &&
                            glm::all(glm::lessThan(at, dims_));
        if (inside) {
            const uint32_t index = surface_index_[cell_index(at)];
            if (index != kNoSurface) return anchors[index];
        }
        return origin_ + (vec3(at) + 0.5f) * cell_size_;
    };
    parallel_for(0, count, kCellsPerChunk, [&](uint64_t begin, uint64_t end) {
        throw_if_cancelled(progress);
        for (size_t pc = begin; pc < end; ++pc) {
            uint32_t mask = surface_near_[pc];
            if (mask == 0) continue;
            const ivec3 at(int(pc % size_t(padded.x)) - 1,
                           int((pc / size_t(padded.x)) % size_t(padded.y)) - 1,
                           int(pc / (size_t(padded.x) * size_t(padded.y))) - 1);
            const vec3 from = anchor_of(at);
            uint32_t seen = 0;
            while (mask != 0) {
                const int k = __builtin_ctz(mask);
                mask &= mask - 1;
                const ivec3 offset(kBlockOffset[k % 3], kBlockOffset[k / 3 % 3],
                                   kBlockOffset[k / 9]);
                if (offset == ivec3(0)) {
                    seen |= uint32_t(1) << k;
                    continue;
                }
                const ivec3 other = at + offset;
                const vec3 to = anchors[surface_index_[cell_index(other)]];
                const bool forward = padded_index(other) > pc;
                const vec3 a = forward ? from : to, b = forward ? to : from;
                const float distance = glm::length(b - a);
                if (!(distance > 0.0f)) {
                    seen |= uint32_t(1) << k;
                    continue;
                }
                Ray ray;
                ray.origin = a;
                ray.direction = (b - a) / distance;
                ray.tmax = distance;
                if (!scene.occluded(ray)) seen |= uint32_t(1) << k;
            }
            visible_near_[pc] = seen;
        }
        if (progress) {
            const double share = double(cells_done += end - begin) / double(count);
            progress->report(reported + uint64_t(share * double(span - reported)), span);
        }
    });
}

// Photons are counting-sorted by cell (stable, so each cell keeps photon order) and each cell
// marks its sides and sums its photons alone: the result is the same for any thread count.
uint64_t ShLattice::inject(const std::vector<Photon>& photons, float scale, Progress* progress) {
    if (!std::isfinite(scale))
        throw InvalidArgument(format_message(kClassName, "::inject: scale = ", scale,
                                             " must be finite"));
    if (photons.size() >= kNoCell)
        throw InvalidArgument(format_message(kClassName, "::inject: ", photons.size(),
                                             " photons in one call; pass fewer than ", kNoCell));
    throw_if_cancelled(progress);
    const size_t cells = cell_count();
    std::vector<uint32_t> photon_cell(photons.size());
    // Cancel is polled by hand in these two passes (their parallel_for would report progress,
    // which belongs to the injection below).
    parallel_for(0, photons.size(), kPhotonsPerChunk, [&](uint64_t begin, uint64_t end) {
        throw_if_cancelled(progress);
        for (uint64_t i = begin; i < end; ++i) {
            const Photon& photon = photons[i];
            const ivec3 cell = cell_of(photon.position);
            photon_cell[i] = kNoCell;
            if (cell.x < 0 || !is_finite(photon.power) || !is_finite(photon.direction)) continue;
            const size_t index = cell_index(cell);
            if (cell_surface(index)) photon_cell[i] = uint32_t(index);
        }
    });

    const ItemsByCell sorted = sort_by_cell(photon_cell, cells, progress);
    photon_cell = {};

    try {
        for_each_cell(
            sorted,
            [&](size_t cell, const uint32_t* order, uint32_t count) {
                inject_cell(cell, photons, order, count, scale);
            },
            progress);
    } catch (const Cancelled&) {
        update_radiance_near();  // some cells already hold their photons
        renew_surfaces_id();     // and have marked their sides
        throw;
    }
    update_radiance_near();
    renew_surfaces_id();  // the sides the photons arrived on
    return sorted.order.size();
}

// The cell's sides first (an OR, so photon order does not matter), then the estimate with D_c
// over every side known to receive, summed in double in photon order.
void ShLattice::inject_cell(size_t cell, const std::vector<Photon>& photons, const uint32_t* order,
                            uint32_t count, float scale) {
    CellSurface& surface = *cell_surface(cell);
    const std::array<float, 3> lengths = surface.bin_lengths();
    for (uint32_t k = 0; k < count; ++k)
        surface.receiving |= surface.side_facing(photons[order[k]].normal, lengths);
    const float min_projected = kMinProjectedFraction * surface.area;
    const int n_coeffs = num_coefficients();
    std::array<double, kMaxCoefficients> sum{};
    for (uint32_t k = 0; k < count; ++k) {
        const Photon& photon = photons[order[k]];
        const float projected = std::max(surface.projected_area(photon.direction), min_projected);
        const vec3 weighted = (scale / projected) * photon.power;
        float basis[kMaxShCoefficients];
        sh_eval(order_, photon.direction, basis);
        for (int i = 0; i < n_coeffs; ++i)
            for (int c = 0; c < 3; ++c) sum[3 * i + c] += double(weighted[c]) * double(basis[i]);
    }
    float* out = coeffs_.data() + cell * size_t(n_coeffs) * 3;
    for (int i = 0; i < 3 * n_coeffs; ++i) out[i] += float(sum[i]);
}

void ShLattice::clear() {
    std::fill(coeffs_.begin(), coeffs_.end(), 0.0f);
    std::fill(radiance_near_.begin(), radiance_near_.end(), uint8_t(0));
    for (CellSurface& surface : surfaces_) surface.receiving = 0;
    renew_surfaces_id();
}

void ShLattice::scale(float factor) {
    if (!std::isfinite(factor))
        throw InvalidArgument(format_message(kClassName, "::scale: factor = ", factor,
                                             " must be finite"));
    for (float& c : coeffs_) c *= factor;
}

// One pass: L'(c) = Σ_{n≠c} P_cn L(n) + (1 − Σ_{n≠c} P_cn) L(c), P_cn = A_n min(1/S_c, 1/S_n)
// over the neighbours n with c's receiving sides (header comment). A_c, the sides and 1/S_c do
// not change between passes and are computed once.
void ShLattice::blur(int passes) {
    if (passes < 0)
        throw InvalidArgument(format_message(kClassName, "::blur: passes = ", passes,
                                             " must be >= 0"));
    const size_t cells = cell_count();
    if (passes == 0 || cells == 0) return;
    std::vector<float> area(cells), inv_neighbourhood(cells, 0.0f);
    std::vector<uint8_t> sides(cells, 0);
    for (size_t c = 0; c < cells; ++c) {
        area[c] = cell_area(c);
        if (const CellSurface* surface = cell_surface(c)) sides[c] = surface->receiving;
    }

    // Calls body(neighbour index) for the cells of c's 3x3x3 block, c included, that have
    // surface and the same receiving sides as c.
    auto for_each_like_neighbour = [&](size_t c, auto&& body) {
        const ivec3 cell(int(c % size_t(dims_.x)), int((c / size_t(dims_.x)) % size_t(dims_.y)),
                         int(c / (size_t(dims_.x) * size_t(dims_.y))));
        const uint32_t seen = visible_near_[padded_index(cell)];  // symmetric between cells
        const ivec3 lo = glm::max(cell - 1, ivec3(0)), hi = glm::min(cell + 1, dims_ - 1);
        for (int z = lo.z; z <= hi.z; ++z)
            for (int y = lo.y; y <= hi.y; ++y)
                for (int x = lo.x; x <= hi.x; ++x) {
                    const size_t n = cell_index(ivec3(x, y, z));
                    const int bit = (z - cell.z + 1) * 9 + (y - cell.y + 1) * 3 + (x - cell.x + 1);
                    if (area[n] > 0.0f && sides[n] == sides[c] &&
                        (seen & (uint32_t(1) << bit)))
                        body(n);
                }
    };
    parallel_for(0, cells, kCellsPerChunk, [&](uint64_t begin, uint64_t end) {
        for (size_t c = begin; c < end; ++c) {
            if (area[c] <= 0.0f) continue;
            float sum = 0.0f;
            for_each_like_neighbour(c, [&](size_t n) { sum += area[n]; });
            inv_neighbourhood[c] = 1.0f / sum;
        }
    });

    const size_t stride = size_t(num_coefficients()) * 3;
    std::vector<float> next(coeffs_.size());
    for (int pass = 0; pass < passes; ++pass) {
        parallel_for(0, cells, kCellsPerChunk, [&](uint64_t begin, uint64_t end) {
            for (size_t c = begin; c < end; ++c) {
                float* out = next.data() + c * stride;
                std::fill(out, out + stride, 0.0f);
                if (area[c] <= 0.0f) continue;  // cells without surface stay empty
                // In double: P_cc = 1 − Σ P_cn cancels most of its digits.
                double others = 0.0;
                for_each_like_neighbour(c, [&](size_t n) {
                    if (n == c) return;
                    const float weight =
                        area[n] * std::min(inv_neighbourhood[c], inv_neighbourhood[n]);
                    const float* in = coeffs_.data() + n * stride;
                    for (size_t i = 0; i < stride; ++i) out[i] += weight * in[i];
                    others += weight;
                });
                const float self = float(1.0 - others);
                const float* in = coeffs_.data() + c * stride;
                for (size_t i = 0; i < stride; ++i) out[i] += self * in[i];
            }
        });
        coeffs_.swap(next);
    }
    update_radiance_near();
}

ShRgb ShLattice::cell_radiance(size_t cell) const {
    check_cell(cell, "cell_radiance");
    ShRgb radiance(order_);
    std::copy_n(cell_coefficients(cell), num_coefficients() * 3, radiance.data());
    return radiance;
}

void ShLattice::set_cell_radiance(size_t cell, const ShRgb& radiance) {
    check_cell(cell, "set_cell_radiance");
    if (radiance.order != order_)
        throw InvalidArgument(format_message(kClassName, "::set_cell_radiance: radiance.order = ",
                                             radiance.order, " but the lattice has order ",
                                             order_));
    const size_t stride = size_t(num_coefficients()) * 3;
    std::copy_n(radiance.data(), stride, coeffs_.data() + cell * stride);
    // Mark the 3x3x3 block; a zero radiance leaves the marks (they may be conservative).
    if (std::all_of(radiance.data(), radiance.data() + stride, [](float x) { return x == 0.0f; }))
        return;
    const ivec3 at(int(cell % size_t(dims_.x)), int((cell / size_t(dims_.x)) % size_t(dims_.y)),
                   int(cell / (size_t(dims_.x) * size_t(dims_.y))));
    const ivec3 lo = glm::max(at - 1, ivec3(0)), hi = glm::min(at + 1, dims_ - 1);
    for (int z = lo.z; z <= hi.z; ++z)
        for (int y = lo.y; y <= hi.y; ++y)
            for (int x = lo.x; x <= hi.x; ++x) radiance_near_[cell_index(ivec3(x, y, z))] = 1;
}

template <typename ForEachCell>
ShRgb ShLattice::blend(const vec3& n, uint32_t near, uint32_t seen,
                       ForEachCell&& for_each_cell) const {
    const auto facing = [&](size_t cell) {  // D_c(n)
        const CellSurface* surface = cell_surface(cell);
        return surface ? surface->projected_area(n) : 0.0f;
    };
    CellWeights cells;
    const auto visit = [&](size_t cell, float weight) { cells.add(cell, weight); };
    for_each_cell(seen, facing, visit);
    // No visible cell faces n (an anchor on the wrong side of a surface whose normals face away
    // from its light): every cell of the block, as without visibility, rather than black.
    if (cells.count == 0 && seen != near) for_each_cell(near, facing, visit);
    if (order_ == 1) return blend_cells<4 * 3>(order_, coeffs_.data(), cells);
    return blend_cells<9 * 3>(order_, coeffs_.data(), cells);
}

inline bool ShLattice::radiance_near_block(const ivec3& centre) const {
    if (radiance_near_.empty()) return false;
    // Trilinear and cubic samples read cells of the 3x3x3 block around `centre`, their cell;
    // clamped into the lattice, that block's flag covers every lattice cell they read.
    return radiance_near_[cell_index(glm::clamp(centre, ivec3(0), dims_ - 1))] != 0;
}

ShRgb ShLattice::sample_trilinear(const vec3& p, const vec3& n, float normal_offset) const {
    vec3 cells(0.0f);
    ivec3 centre(0);
    if (!sample_coordinates(p, n, normal_offset, origin_, cell_size_, dims_, cells, centre) ||
        !radiance_near_block(centre))
        return zero_radiance(order_);
    const bool in_padded = glm::all(glm::greaterThanEqual(centre, ivec3(-1))) &&
                           glm::all(glm::lessThanEqual(centre, dims_));
    const uint32_t seen = in_padded ? visible_near_[padded_index(centre)] : kFullBlock;
    return blend(n, kFullBlock, seen, [&](uint32_t mask, auto&& facing, auto&& visit) {
        for_each_trilinear_cell(cells, dims_, mask, facing, visit);
    });
}

ShRgb ShLattice::sample_cubic(const vec3& p, const vec3& n, float normal_offset) const {
    vec3 cells(0.0f);
    ivec3 centre(0);
    if (!sample_coordinates(p, n, normal_offset, origin_, cell_size_, dims_, cells, centre) ||
        !radiance_near_block(centre))
        return zero_radiance(order_);
    if (glm::any(glm::lessThan(centre, ivec3(-1))) || glm::any(glm::greaterThan(centre, dims_)))
        return zero_radiance(order_);  // the block holds no lattice cell
    const size_t block = padded_index(centre);
    const uint32_t near = surface_near_[block];
    FacingMemo& memo = thread_facing_memo();
    memo.key(surfaces_id_, block, n);
    return blend(n, near, near & visible_near_[block],
                 [&](uint32_t mask, auto&& facing, auto&& visit) {
                     for_each_cubic_cell(cells, centre, mask, dims_, memo, facing, visit);
                 });
}

void ShLattice::renew_surfaces_id() { surfaces_id_ = next_surfaces_id.fetch_add(1); }

size_t ShLattice::padded_index(const ivec3& cell) const {
    const ivec3 at = cell + 1;
    return size_t(at.x) + size_t(dims_.x + 2) * (size_t(at.y) + size_t(dims_.y + 2) * size_t(at.z));
}

void ShLattice::update_surface_near() {
    std::fill(surface_near_.begin(), surface_near_.end(), 0u);
    for (int z = 0; z < dims_.z; ++z)
        for (int y = 0; y < dims_.y; ++y)
            for (int x = 0; x < dims_.x; ++x) {
                const ivec3 at(x, y, z);
                if (surface_index_[cell_index(at)] == kNoSurface) continue;
                // Each block centre q = at + d (inside the padded lattice) has it at offset -d.
                for (int dz = -1; dz <= 1; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx)
                            surface_near_[padded_index(at + ivec3(dx, dy, dz))] |=
                                block_bit(-dx, -dy, -dz);
            }
}

// Sequential: inject() also calls it from its handler for Cancelled.
void ShLattice::update_radiance_near() {
    const size_t cells = cell_count();
    const size_t stride = size_t(num_coefficients()) * 3;
    std::vector<uint8_t> lit(cells), dilated(cells);
    for (size_t c = 0; c < cells; ++c) {
        const float* coefficients = cell_coefficients(c);
        lit[c] = std::any_of(coefficients, coefficients + stride,
                             [](float x) { return x != 0.0f; });
    }
    dilate_along(lit, dims_, 0, dilated);
    dilate_along(dilated, dims_, 1, lit);
    dilate_along(lit, dims_, 2, dilated);
    radiance_near_ = std::move(dilated);
}

void ShLattice::write(BinaryWriter& out) const {
    out.put(int32_t(order_));
    out.put(dims_);
    out.put(origin_);
    out.put(cell_size_);
    out.array(coeffs_);
    out.array(surface_index_);
    out.array(visible_near_);
    out.put(uint64_t(surfaces_.size()));
    for (const CellSurface& surface : surfaces_) {  // field by field: no padding bytes
        out.put(surface.area);
        for (const vec3& projected : surface.projected) out.put(projected);
        out.put(surface.bins);
        out.put(surface.receiving);
    }
}

ShLattice ShLattice::read(BinaryReader& in, bool with_visibility) {
    const auto refuse = [&](const std::string& problem) {
        return IoError(format_message(in.kind(), " \"", in.path(), "\": ", problem));
    };
    ShLattice lattice;
    lattice.renew_surfaces_id();
    lattice.order_ = in.get<int32_t>("a lattice header");
    lattice.dims_ = in.get<ivec3>("a lattice header");
    lattice.origin_ = in.get<vec3>("a lattice header");
    lattice.cell_size_ = in.get<float>("a lattice header");
    const ivec3 dims = lattice.dims_;
    const bool empty = dims == ivec3(0);  // a default ShLattice (no caustic lattice)
    const bool dims_valid =
        empty || (glm::all(glm::greaterThanEqual(dims, ivec3(1))) &&
                  uint64_t(dims.x) * uint64_t(dims.y) * uint64_t(dims.z) <= kMaxCells);
    if (lattice.order_ < 1 || lattice.order_ > 2 || !dims_valid || !is_finite(lattice.origin_) ||
        !(lattice.cell_size_ > 0.0f) || !std::isfinite(lattice.cell_size_))
        throw refuse(format_message("a lattice header holds order ", lattice.order_, ", ", dims.x,
                                    " x ", dims.y, " x ", dims.z, " cells of ", lattice.cell_size_,
                                    " m (damaged?)"));
    const size_t cells = lattice.cell_count();
    lattice.coeffs_ = in.array<float>("the lattice coefficients");
    lattice.surface_index_ = in.array<uint32_t>("the lattice cells");
    if (with_visibility) lattice.visible_near_ = in.array<uint32_t>("the lattice visibility");
    if (lattice.coeffs_.size() != cells * size_t(lattice.num_coefficients()) * 3 ||
        lattice.surface_index_.size() != cells)
        throw refuse(format_message("a lattice of ", cells, " cells holds ",
                                    lattice.coeffs_.size(), " coefficients and ",
                                    lattice.surface_index_.size(), " cell entries (damaged?)"));
    const uint64_t surfaces = in.get<uint64_t>("the lattice surfaces");
    if (surfaces > cells) throw refuse(format_message(surfaces, " surfaces in ", cells, " cells"));
    lattice.surfaces_.resize(surfaces);
    for (CellSurface& surface : lattice.surfaces_) {
        surface.area = in.get<float>("the lattice surfaces");
        for (vec3& projected : surface.projected) projected = in.get<vec3>("the lattice surfaces");
        surface.bins = in.get<uint8_t>("the lattice surfaces");
        surface.receiving = in.get<uint8_t>("the lattice surfaces");
    }
    for (const uint32_t index : lattice.surface_index_)
        if (index != kNoSurface && index >= surfaces)
            throw refuse(format_message("a cell names surface ", index, " of ", surfaces));
    const size_t padded_cells =
        empty ? 0 : size_t(dims.x + 2) * size_t(dims.y + 2) * size_t(dims.z + 2);
    if (!with_visibility) lattice.visible_near_.assign(padded_cells, kFullBlock);
    if (lattice.visible_near_.size() != padded_cells)
        throw refuse(format_message("a lattice of ", cells, " cells holds ",
                                    lattice.visible_near_.size(), " visibility masks, not ",
                                    padded_cells, " (damaged?)"));
    if (empty) return lattice;
    lattice.surface_near_.assign(size_t(dims.x + 2) * size_t(dims.y + 2) * size_t(dims.z + 2),
                                 0u);
    lattice.update_surface_near();
    lattice.update_radiance_near();
    return lattice;
}

size_t ShLattice::memory_bytes() const {
    return sizeof(*this) + coeffs_.capacity() * sizeof(float) +
           (surface_index_.capacity() + surface_near_.capacity() + visible_near_.capacity()) *
               sizeof(uint32_t) +
           surfaces_.capacity() * sizeof(CellSurface) + radiance_near_.capacity();
}

}  // namespace shgi
