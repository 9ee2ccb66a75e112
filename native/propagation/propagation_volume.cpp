#include "propagation/propagation_volume.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <glm/gtx/string_cast.hpp>

#include "photon/photon_tracer.h"
#include "render/shading.h"
#include "util/cell_sort.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/parallel.h"
#include "util/timer.h"

namespace shgi {
namespace {

constexpr const char* kSettings = "PropagationSettings";
// VPLs whose albedo is found per parallel task (one short ray each).
constexpr uint64_t kVplsPerTask = 4096;
// How far before a hit the ray back onto its surface starts with glossy_vpls, m (Instant GI's).
constexpr float kGlossyReach = 1e-3f;
// Propagation cells per parallel task of the transmittance.
constexpr uint64_t kCellsPerTask = 4096;
// Progress shares of a pass's stages (tracing dominates at the default settings).
constexpr float kTraceShare = 0.6f, kInjectShare = 0.7f;
// The smallest resolution with cascades (see validate_propagation_settings).
constexpr int kMinCascadeResolution = 16;
// The longest propagation distance, cells (at most 560 LPV steps).
constexpr float kMaxDistanceCells = 512.0f;
// A cell centre this close to the scene's bounds (in cells) is not inside them
// (extend_to_bounds): the walls at the bounds run through such cells.
constexpr float kBoundsToleranceCells = 1e-4f;

// Where a cascade level's geometry lattice lies: its grid (the propagation volume is offset by
// half a cell and has one more cell per axis) and the faces it blends into the next coarser level.
struct LevelGrid {
    vec3 origin{0.0f};
    float cell_size = 1.0f;
    ivec3 dims{1};
    ivec3 start{0};  // its first cell on its own grid over the scene
    uint8_t blend_faces = 0;
};

// The levels' grids, finest first, from the coarsest level's (the scene's lattice at
// `resolution`: origin, cell size S, dims D): level l (of n) has cells of S / 2^(n−1−l), on the
// same grid subdivided, and at most `resolution` of them per axis around the centre, kept inside
// the subdivided D.
std::vector<LevelGrid> level_grids(const vec3& origin, float cell_size, const ivec3& dims,
                                   const PropagationSettings& settings, const vec3& center) {
    const int n = settings.cascades;
    std::vector<LevelGrid> grids(static_cast<size_t>(n));
    for (int level = 0; level < n; ++level) {
        const int factor = 1 << (n - 1 - level);
        LevelGrid& grid = grids[size_t(level)];
        grid.cell_size = cell_size / float(factor);
        const ivec3 full = dims * factor;
        grid.dims = level + 1 == n ? dims : glm::min(ivec3(settings.resolution), full);
        // The cell holding the centre (clamped far outside first: the cast must not overflow).
        const vec3 at = glm::clamp(glm::floor((center - origin) / grid.cell_size),
                                   vec3(-1.0f), vec3(full));
        const ivec3 start = glm::clamp(ivec3(at) - grid.dims / 2, ivec3(0), full - grid.dims);
        grid.origin = origin + vec3(start) * grid.cell_size;
        grid.start = start;
        for (int a = 0; a < 3; ++a) {
            if (start[a] > 0) grid.blend_faces |= uint8_t(1u << a);
            if (start[a] + grid.dims[a] < full[a]) grid.blend_faces |= uint8_t(8u << a);
        }
    }
    return grids;
}

// Bytes a level of `dims` lattice cells holds: five volumes (the injection's sum and mean, ping,
// pong, accumulation) of one more cell per axis, and the transmittances (26 neighbours, and the
// LPV's 6 beside them).
uint64_t level_bytes(const ivec3& dims, int order) {
    const uint64_t cells = uint64_t(dims.x + 1) * uint64_t(dims.y + 1) * uint64_t(dims.z + 1);
    const uint64_t floats = uint64_t(3 * sh_num_coefficients(order));
    return saturating_add(saturating_mul(cells, floats * sizeof(float) * 5),
                          saturating_mul(cells, (26 + 6) * sizeof(float)));
}

// Bytes the levels of `grids` hold together (level_bytes).
uint64_t levels_bytes(const std::vector<LevelGrid>& grids, int order) {
    uint64_t bytes = 0;
    for (const LevelGrid& grid : grids) bytes = saturating_add(bytes, level_bytes(grid.dims, order));
    return bytes;
}

void check_range(int value, int lo, int hi, const char* name) {
    if (value < lo || value > hi)
        throw InvalidArgument(format_message(kSettings, ".", name, " is ", value,
                                             "; it must be in [", lo, ", ", hi, "]"));
}

PhotonTracerSettings tracer_settings(const PropagationSettings& settings) {
    PhotonTracerSettings tracer;
    tracer.photons = settings.photons;
    tracer.seed = settings.seed;
    // First hits are recorded before any scattering; a photon stored after m scatterings is
    // the (m + 1)-th hit of its path.
    tracer.max_bounces = std::max(1, settings.vpl_bounces - 1);
    tracer.max_glossy_bounces = settings.glossy_bounces;
    tracer.store_first_hits = true;
    tracer.light_share_uniform = settings.light_share_uniform;
    return tracer;
}

PropagationStencil stencil_of(int order) {
    return order == 1 ? PropagationStencil::Faces6 : PropagationStencil::Neighbours26;
}

Reinjection reinjection_of(const PropagationSettings& settings) {
    if (!settings.travel_reinjection) return Reinjection::FaceNormal;
    return settings.windowed_reinjection ? Reinjection::WindowedTravelDirection
                                         : Reinjection::TravelDirection;
}

LobeClamp clamp_of(const PropagationSettings& settings) {
    // Per transfer is the HOLPV's alone (see PropagationSettings::clamp_per_transfer).
    const bool per_transfer = settings.clamp_per_transfer && settings.order == 2;
    return !settings.unclamped_transfer ? LobeClamp::Rescaled
           : !settings.clamp_at_surfaces ? LobeClamp::None
           : per_transfer                ? LobeClamp::AtBlockedTransfers
                                         : LobeClamp::AtSurfaces;
}

PropagationStep step_of(const PropagationSettings& settings) {
    return PropagationStep(stencil_of(settings.order), settings.order, clamp_of(settings),
                           reinjection_of(settings));
}

const PropagationSettings& validated(const PropagationSettings& settings) {
    validate_propagation_settings(settings);
    return settings;
}

// The cell of `volume` holding p, or kNoCell.
uint32_t cell_of(const ShVolume& volume, const vec3& p) {
    const vec3 q = (p - volume.origin()) / volume.cell_size();
    if (!is_finite(q)) return kNoCell;
    const ivec3 cell(glm::floor(q));
    if (!volume.contains(cell)) return kNoCell;
    return uint32_t(volume.cell_index(cell));
}

// Per propagation cell and stencil offset, 1 − the geometry's blocking potential between the
// cell and its source (see the header): the lattice's cell centres are the volume's corners.
PropagationTransmittance geometry_transmittance(const ShLattice& geometry, const Bounds3& bounds,
                                                const ShVolume& volume, PropagationStencil stencil,
                                                Progress* progress) {
    const std::vector<ivec3> offsets = propagation_offsets(stencil);
    PropagationTransmittance transmittance;
    transmittance.offsets = int(offsets.size());
    transmittance.values.assign(volume.cell_count() * offsets.size(), 1.0f);
    const ivec3 dims = geometry.dims();
    const float s = geometry.cell_size();
    // The cross-section a wall can have in lattice cell g, perpendicular to `axis`: the cell
    // clipped to the scene's bounds (the lattice overhangs them: the two rooms' floor and
    // ceiling layers are 2/3 inside, and their wall, which fills the inside, blocked only 2/3
    // there: 17% of the bright room's light near its floor and ceiling crossed the wall).
    const auto cross_section = [&](const ivec3& g, int axis) {
        const vec3 lo = geometry.origin() + vec3(g) * s;
        const vec3 extent = glm::max(glm::min(lo + s, bounds.upper) - glm::max(lo, bounds.lower),
                                     vec3(0.0f));
        return extent[(axis + 1) % 3] * extent[(axis + 2) % 3];
    };
    parallel_for(0, volume.cell_count(), kCellsPerTask, [&](uint64_t begin, uint64_t end) {
        throw_if_cancelled(progress);
        for (uint64_t c = begin; c < end; ++c) {
            const ivec3 cell = volume.cell_at(c);
            for (size_t o = 0; o < offsets.size(); ++o) {
                // The midpoint of this cell's centre and its source's, in lattice coordinates
                // (lattice cell centres at integers; this cell's centre is at cell − ½).
                const vec3 q = vec3(cell) - 0.5f - 0.5f * vec3(offsets[o]);
                const vec3 dir = glm::normalize(vec3(offsets[o]));
                // What a wall across the transfer shows of a cell: its face perpendicular to an
                // axis of the offset, seen along dir (s² for face neighbours, s²/√2 and s²/√3
                // across edges and corners). With s² alone a wall blocked only 71% and 58% of
                // the edge and corner transfers, and the HOLPV's light went through walls.
                const float largest = max_abs_component(dir);
                const ivec3 lo(glm::floor(q));
                const vec3 f = q - vec3(lo);
                float blocking = 0.0f;
                for (int corner = 0; corner < 8; ++corner) {
                    const ivec3 bit(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
                    const vec3 w3 = glm::mix(vec3(1.0f) - f, f, vec3(bit));
                    const float w = w3.x * w3.y * w3.z;
                    const ivec3 g = lo + bit;
                    if (w == 0.0f || glm::any(glm::lessThan(g, ivec3(0))) ||
                        glm::any(glm::greaterThanEqual(g, dims)))
                        continue;
                    // The smallest of the walls across the transfer's dominant axes. Where the
                    // scene's bounds are flat across an axis (a single plane: its bounds have no
                    // height), no wall fits inside them and the whole face s² stands in: else
                    // the plane blocked no transfer along that axis (a plane under a sky read
                    // 5% bright in the conformance test).
                    float full_wall = kInfinity;
                    for (int axis = 0; axis < 3; ++axis) {
                        if (std::fabs(dir[axis]) != largest) continue;
                        const float wall = cross_section(g, axis);
                        full_wall = std::min(full_wall, (wall > 0.0f ? wall : s * s) * largest);
                    }
                    if (!(full_wall > 0.0f)) continue;
                    const float d = geometry.projected_area(geometry.cell_index(g), dir);
                    blocking += w * std::min(1.0f, d / full_wall);
                }
                transmittance.values[c * offsets.size() + o] = 1.0f - blocking;
            }
        }
    });
    return transmittance;
}

// With glossy_vpls: a VPL at every hit of `maps` (its first hits, and with vpl_bounces > 1 the
// later ones) of the flux its surface scatters with its diffuse and rough glossy lobes, found by
// a short ray back onto it (photon_tracer.h's scattered_flux, as Instant GI's VPLs); hits that
// scatter nothing are left out. Deterministic: one flux per hit, in hit order.
std::vector<VirtualPointLight> scattering_vpls(const Scene& scene, const PhotonMaps& maps,
                                               const PropagationSettings& settings,
                                               Progress* progress) {
    const std::vector<Photon> hits = vpl_hits(maps, settings.vpl_bounces > 1);
    std::vector<vec3> scattered(hits.size(), vec3(0.0f));
    const float rough = tracer_settings(settings).specular_roughness;
    parallel_for(0, hits.size(), kVplsPerTask, [&](uint64_t begin, uint64_t end) {
        throw_if_cancelled(progress);
        for (uint64_t i = begin; i < end; ++i)
            scattered[i] = scattered_flux(scene, hits[i].position, hits[i].normal,
                                          hits[i].direction, hits[i].power, kGlossyReach, rough);
    });
    std::vector<VirtualPointLight> vpls;
    vpls.reserve(hits.size());
    for (size_t i = 0; i < hits.size(); ++i)
        if (scattered[i] != vec3(0.0f) && is_finite(scattered[i]))
            vpls.push_back({hits[i].position, hits[i].normal, scattered[i]});
    return vpls;
}

}  // namespace

void validate_propagation_settings(const PropagationSettings& settings) {
    // Before the tracer's, which names it max_glossy_bounces.
    check_range(settings.glossy_bounces, -1, 64, "glossy_bounces");
    validate_photon_tracer_settings(tracer_settings(settings), kSettings);
    check_range(settings.vpl_bounces, 1, 64, "vpl_bounces");
    check_range(settings.resolution, 2, 256, "resolution");
    check_range(settings.steps, 0, 1024, "steps");
    if (!std::isfinite(settings.distance) || settings.distance < 0.0f ||
        settings.distance > kMaxDistanceCells)
        throw InvalidArgument(format_message(kSettings, ".distance is ", settings.distance,
                                             "; it must be in [0, ", kMaxDistanceCells,
                                             "] cells"));
    if (!(settings.settle_fraction >= 0.0f && settings.settle_fraction < 1.0f))
        throw InvalidArgument(format_message(kSettings, ".settle_fraction is ",
                                             settings.settle_fraction,
                                             "; it must be in [0, 1) (0: off)"));
    check_range(settings.order, 1, 2, "order");
    if (settings.furnace_scale && !settings.travel_reinjection)
        throw InvalidArgument(format_message(kSettings, ".furnace_scale needs travel_reinjection "
                                             "(the scale is measured for the travel "
                                             "re-injection only); turn one of them off"));
    check_range(settings.cascades, 1, kMaxPropagationLevels, "cascades");
    // A finer level needs cells inside its blend band: at 16 cells, 6 per axis read it alone.
    if (settings.cascades > 1) check_range(settings.resolution, kMinCascadeResolution, 256,
                                           "resolution (with cascades)");
    if (!is_finite(settings.cascade_center))
        throw InvalidArgument(format_message(kSettings, ".cascade_center is ",
                                             glm::to_string(settings.cascade_center),
                                             "; it must be a finite point"));
    if (!std::isfinite(settings.normal_offset) || settings.normal_offset < 0.0f ||
        settings.normal_offset > 2.0f)
        throw InvalidArgument(format_message(kSettings, ".normal_offset is ",
                                             settings.normal_offset,
                                             "; it must be in [0, 2] cells"));
}

float settled_room_excess(int order, LobeClamp clamp, Reinjection reinjection) {
    if (reinjection == Reinjection::FaceNormal || (order != 1 && order != 2) ||
        (clamp != LobeClamp::Rescaled && clamp != LobeClamp::None &&
         clamp != LobeClamp::AtSurfaces && clamp != LobeClamp::AtBlockedTransfers))
        throw InvalidArgument(format_message(
            "settled_room_excess: measured for the travel re-injections and the flux-keeping "
            "transfers of orders 1 and 2 only (order ", order, ")"));
    const int c = clamp == LobeClamp::Rescaled     ? 0
                  : clamp == LobeClamp::None         ? 1
                  : clamp == LobeClamp::AtSurfaces   ? 2
                                                     : 3;
    // [transfer: LPV, HOLPV plain beams, HOLPV windowed beams]
    // [Rescaled, None, AtSurfaces, AtBlockedTransfers]
    // (the LPV's beams have no band 2: windowed is plain).
    static constexpr float kExcess[3][4] = {{1.2250f, 1.3707f, 1.2850f, 1.2705f},
                                            {1.3164f, 1.2850f, 1.2535f, 1.2664f},
                                            {1.2777f, 1.2650f, 1.2210f, 1.2331f}};
    const int t = order == 1 ? 0 : reinjection == Reinjection::WindowedTravelDirection ? 2 : 1;
    return kExcess[t][c];
}

int propagation_steps(const PropagationSettings& settings) {
    if (settings.steps > 0) return settings.steps;
    return int(std::lround(double(settings.distance) /
                           propagation_speed(stencil_of(settings.order))));
}

void inject_vpls(ShVolume& volume, const std::vector<VirtualPointLight>& vpls,
                 Progress* progress) {
    if (vpls.size() >= kNoCell)
        throw InvalidArgument(format_message("inject_vpls: ", vpls.size(),
                                             " VPLs; at most ", kNoCell - 1, " per call"));
    const float half_cell = 0.5f * volume.cell_size();
    std::vector<uint32_t> item_cell(vpls.size());
    for_each_slice(vpls.size(), uint64_t(1) << 20, progress, [&](uint64_t begin, uint64_t end) {
        for (uint64_t i = begin; i < end; ++i)
            item_cell[i] = cell_of(volume, vpls[i].position + half_cell * vpls[i].normal);
    });
    const ItemsByCell sorted = sort_by_cell(item_cell, volume.cell_count(), progress);
    const int order = volume.order();
    for_each_cell(sorted, [&](size_t cell, const uint32_t* items, uint32_t count) {
        throw_if_cancelled(progress);
        float* data = volume.cell_data(cell);
        for (uint32_t k = 0; k < count; ++k) {
            const VirtualPointLight& vpl = vpls[items[k]];
            add_cosine_lobe(data, order, vpl.normal, vpl.power);
        }
    });
}

ShVolume propagate(const ShVolume& injected, const PropagationStep& step, int steps,
                   const PropagationTransmittance* transmittance, Progress* progress,
                   std::vector<double>* step_seconds, bool occlude_first_step,
                   float settle_fraction) {
    // Copies of a large volume take a while (~0.1 s at 97³ L2): a cancel poll after each.
    ShVolume accumulated = injected;
    throw_if_cancelled(progress);
    ShVolume ping = injected;
    throw_if_cancelled(progress);
    ShVolume pong = injected;
    throw_if_cancelled(progress);
    float* acc = accumulated.cell_data(0);
    const size_t floats = accumulated.coefficients().size();
    // The light in a volume, Σ |band 0| over cells and channels (in cell order: the same sum for
    // any thread count).
    const auto light_of = [](const ShVolume& volume) {
        double sum = 0.0;
        for (size_t c = 0; c < volume.cell_count(); ++c) {
            const float* data = volume.cell_data(c);
            sum += double(std::fabs(data[0])) + double(std::fabs(data[1])) +
                   double(std::fabs(data[2]));
        }
        return sum;
    };
    const double settled = settle_fraction > 0.0f ? settle_fraction * light_of(injected) : 0.0;
    for (int k = 0; k < steps; ++k) {
        const auto start = now();
        // §3.2.3: no occlusion on the first step, whose light leaves the VPLs' own surfaces
        // (unless occlude_first_step).
        step(ping, pong, k == 0 && !occlude_first_step ? nullptr : transmittance, progress);
        const float* next = pong.cell_data(0);
        for_each_slice(floats, uint64_t(1) << 22, progress, [&](uint64_t begin, uint64_t end) {
            for (uint64_t i = begin; i < end; ++i) acc[i] += next[i];
        });
        std::swap(ping, pong);
        const bool done = settled > 0.0 && light_of(ping) <= settled;
        if (step_seconds != nullptr) step_seconds->push_back(seconds_since(start));
        if (progress) progress->report(uint64_t(k + 1), uint64_t(steps));
        if (done) break;
    }
    return accumulated;
}

void extend_to_bounds(ShVolume& volume, const Bounds3& bounds) {
    // The inside cells' index range per axis: centres origin + (i + ½) s strictly inside.
    const ivec3 counts = volume.counts();
    const float s = volume.cell_size();
    const float tolerance = kBoundsToleranceCells * s;
    ivec3 first(0), last(-1);
    for (int a = 0; a < 3; ++a) {
        first[a] = counts[a];
        for (int i = 0; i < counts[a]; ++i) {
            const float centre = volume.origin()[a] + (float(i) + 0.5f) * s;
            if (centre <= bounds.lower[a] + tolerance || centre >= bounds.upper[a] - tolerance)
                continue;
            first[a] = std::min(first[a], i);
            last[a] = std::max(last[a], i);
        }
        if (last[a] < first[a]) first[a] = 0, last[a] = counts[a] - 1;  // flat: leave the axis
    }
    const int floats = volume.floats_per_cell();
    for (size_t c = 0; c < volume.cell_count(); ++c) {
        const ivec3 cell = volume.cell_at(c);
        const ivec3 from = glm::clamp(cell, first, last);
        if (from == cell) continue;
        const float* src = volume.cell_data(volume.cell_index(from));
        std::copy(src, src + floats, volume.cell_data(c));
    }
}

PropagationVolume::PropagationVolume(const Scene& scene, const PropagationSettings& settings,
                                     Progress* progress)
    : scene_(&scene), settings_(validated(settings)) {
    reset(progress);
}

PropagationVolume::~PropagationVolume() = default;

void PropagationVolume::check_scene(const char* what) const {
    if (!scene_->committed() || scene_->revision() != scene_revision_)
        throw InvalidArgument(format_message("PropagationVolume.", what,
                                             ": the scene was edited since the volume was made; "
                                             "commit() it and call reset() first"));
}

size_t PropagationVolume::estimate_memory_bytes(const Scene& scene,
                                                const PropagationSettings& settings) {
    validate_propagation_settings(settings);
    // The coarsest level's cells per axis as the lattice's rule gives them (within its margin).
    const vec3 extent = scene.bounds().extent();
    const float longest = max_component(extent);
    if (!(longest > 0.0f) || !std::isfinite(longest)) return 0;
    const ivec3 dims = glm::max(ivec3(glm::ceil(extent / longest * float(settings.resolution))),
                                ivec3(1));
    // The centre moves the finer levels, not their sizes.
    const uint64_t bytes = levels_bytes(
        level_grids(vec3(0.0f), 1.0f, dims, settings, vec3(0.0f)), settings.order);
    return size_t(std::min<uint64_t>(bytes, std::numeric_limits<size_t>::max()));
}

PropagationVolume::Level PropagationVolume::make_level(ShLattice geometry, uint8_t blend_faces,
                                                       Progress* progress) const {
    geometry.measure_surfaces(*scene_, progress);
    const float s = geometry.cell_size();
    ShVolume volume(geometry.origin() - 0.5f * s, s, geometry.dims() + 1, settings_.order);
    Level level;
    if (settings_.occlusion) {
        PropagationTransmittance all = geometry_transmittance(
            geometry, scene_->bounds(), volume, PropagationStencil::Neighbours26, progress);
        level.transmittance = settings_.order == 2
                                  ? all
                                  : geometry_transmittance(geometry, scene_->bounds(), volume,
                                                           PropagationStencil::Faces6, progress);
        level.lookup_transmittance =
            std::make_shared<const NeighbourTransmittance>(std::move(all.values));
    }
    level.injected_sum = volume;
    level.injected = std::move(volume);
    level.blend_faces = blend_faces;
    return level;
}

void PropagationVolume::reset(Progress* progress) {
    if (!scene_->committed())
        throw InvalidArgument("PropagationVolume: the scene is not committed; call commit() first");
    if (scene_->empty())
        throw InvalidArgument("PropagationVolume: the scene has no geometry; add meshes and "
                              "instances before solving");
    const int n = settings_.cascades;
    // The geometry lattice decides the cell size; the propagation cells are offset by half a
    // cell from it, one more per axis, so the lattice's centres are their corners.
    ShLattice coarsest(scene_->bounds(), settings_.resolution, 1);
    const vec3 center = settings_.cascade_follow_camera && scene_->has_camera()
                            ? vec3(scene_->camera().world_from_camera[3])
                            : settings_.cascade_center;
    const std::vector<LevelGrid> grids = level_grids(coarsest.origin(), coarsest.cell_size(),
                                                     coarsest.dims(), settings_, center);
    require_memory(levels_bytes(grids, settings_.order),
                   format_message("PropagationVolume: resolution ", settings_.resolution,
                                  " gives ", coarsest.dims().x + 1, " x ",
                                  coarsest.dims().y + 1, " x ", coarsest.dims().z + 1,
                                  " cells", n > 1 ? format_message(" and ", n - 1,
                                                                   " finer cascade levels")
                                                  : std::string(),
                                  ", 5 volumes of each level"),
                   n > 1 ? "lower the resolution or the cascades" : "lower the resolution");
    std::vector<Level> levels(grids.size());
    for (int level = n - 1; level >= 0; --level) {
        const auto start = now();
        const LevelGrid& grid = grids[size_t(level)];
        if (progress)
            progress->begin_stage(n > 1 ? format_message("geometry volume, level ", level)
                                        : std::string("geometry volume"),
                                  float(n - 1 - level) / float(n), float(n - level) / float(n));
        levels[size_t(level)] =
            make_level(level + 1 == n ? std::move(coarsest)
                                      : ShLattice(grid.origin, grid.cell_size, grid.dims, 1),
                       grid.blend_faces, progress);
        levels[size_t(level)].geometry_seconds = seconds_since(start);
        levels[size_t(level)].start = grid.start;
    }
    levels_ = std::move(levels);
    coarse_origin_ = grids.back().origin;
    coarse_cell_size_ = grids.back().cell_size;
    coarse_dims_ = grids.back().dims;
    field_ = std::make_shared<PropagationField>();
    passes_ = 0;
    last_vpl_count_ = 0;
    stage_seconds_.clear();
    scene_revision_ = scene_->revision();
    if (progress) progress->set_fraction(1.0f);
}

std::vector<VirtualPointLight> PropagationVolume::trace_vpls(uint64_t pass, Progress* progress,
                                                             double* reflect_seconds) const {
    PhotonMaps maps = trace_photons(*scene_, tracer_settings(settings_), pass, progress,
                                    kSettings);
    // With drop_outward_vpls, a VPL whose lit half-space holds nothing of the scene's bounds (a
    // surface on the bounds facing out: a sunlit roof or outer wall) is dropped: it can light no
    // surface, and injected it lit the cells its surface runs through, which interior lookups
    // read (the sun room with its window shut).
    const Bounds3 bounds = scene_->bounds();
    const float tolerance = 1e-4f * max_component(bounds.upper - bounds.lower);
    const auto lights_the_scene = [&](const vec3& position, const vec3& normal) {
        if (!settings_.drop_outward_vpls) return true;
        const vec3 farthest = glm::mix(bounds.lower, bounds.upper,
                                       vec3(glm::greaterThan(normal, vec3(0.0f))));
        return glm::dot(normal, farthest - position) > tolerance;
    };
    std::vector<VirtualPointLight> vpls;
    vpls.reserve(maps.first_hits.size() +
                 (settings_.vpl_bounces > 1 ? maps.global.size() + maps.caustic.size() : 0));
    if (settings_.glossy_vpls) {
        const auto start = now();
        for (VirtualPointLight& vpl : scattering_vpls(*scene_, maps, settings_, progress))
            if (lights_the_scene(vpl.position, vpl.normal)) vpls.push_back(vpl);
        *reflect_seconds = seconds_since(start);
        return vpls;
    }
    for (const PhotonFirstHit& hit : maps.first_hits)
        if (hit.reflected_power != vec3(0.0f) && lights_the_scene(hit.position, hit.normal))
            vpls.push_back({hit.position, hit.normal, hit.reflected_power});
    if (settings_.vpl_bounces == 1) return vpls;
    // Later hits carry the power arriving; the surface scatters its diffuse albedo of it, which
    // a short ray back onto the stored point finds (the photon maps keep no material).
    std::vector<Photon> later = std::move(maps.global);
    later.insert(later.end(), maps.caustic.begin(), maps.caustic.end());
    std::vector<vec3> reflected(later.size(), vec3(0.0f));
    const auto start = now();
    parallel_for(0, later.size(), kVplsPerTask, [&](uint64_t begin, uint64_t end) {
        throw_if_cancelled(progress);
        for (uint64_t i = begin; i < end; ++i) {
            const Photon& photon = later[i];
            Ray ray;
            ray.origin = offset_origin(photon.position, photon.normal);
            ray.direction = -photon.direction;
            const Hit hit = scene_->intersect(ray);
            if (!hit.valid()) continue;
            const Shading shading = make_shading(*scene_, scene_->surface_point(ray, hit),
                                                 ray.direction, PathOrigin::Light);
            // At a shading normal, times the adjoint's correction (render/shading.h).
            reflected[i] = shading.bsdf.field_diffuse(shading.wo) * photon.power *
                           particle_diffuse_arrival(shading, photon.direction);
        }
    });
    for (size_t i = 0; i < later.size(); ++i)
        if (reflected[i] != vec3(0.0f) && lights_the_scene(later[i].position, later[i].normal))
            vpls.push_back({later[i].position, later[i].normal, reflected[i]});
    *reflect_seconds = seconds_since(start);
    return vpls;
}

void PropagationVolume::finish_accumulation(ShVolume& accumulated) const {
    if (settings_.extend_to_bounds) extend_to_bounds(accumulated, scene_->bounds());
    if (!settings_.furnace_scale) return;
    float* data = accumulated.cell_data(0);
    const float scale = 1.0f / settled_room_excess(settings_.order, clamp_of(settings_),
                                                   reinjection_of(settings_));
    for_each_slice(accumulated.coefficients().size(), uint64_t(1) << 22, nullptr,
                   [&](uint64_t begin, uint64_t end) {
                       for (uint64_t i = begin; i < end; ++i) data[i] *= scale;
                   });
}

PropagationLevel PropagationVolume::pass_level(size_t level,
                                              const std::vector<VirtualPointLight>& vpls,
                                              const PropagationStep& step, Progress* progress,
                                              std::vector<StageSeconds>& stages, ShVolume& sum,
                                              ShVolume& mean) const {
    const Level& l = levels_[level];
    const size_t n = levels_.size();
    // This level's share of the progress after tracing; its stage names' prefix with cascades.
    const float lo = kTraceShare + (1.0f - kTraceShare) * float(level) / float(n);
    const float span = (1.0f - kTraceShare) / float(n);
    const float inject_end = lo + span * (kInjectShare - kTraceShare) / (1.0f - kTraceShare);
    const std::string prefix = n > 1 ? format_message("level_", level, "_") : std::string();
    const auto start = now();
    if (progress)
        progress->begin_stage(n > 1 ? format_message("injecting VPLs, level ", level)
                                    : std::string("injecting VPLs"),
                              lo, inject_end);
    ShVolume pass(l.injected.origin(), l.injected.cell_size(), l.injected.counts(),
                  settings_.order);
    inject_vpls(pass, vpls, progress);
    throw_if_cancelled(progress);
    sum = l.injected_sum;
    throw_if_cancelled(progress);
    mean = l.injected;
    throw_if_cancelled(progress);
    const float inv_passes = 1.0f / float(passes_ + 1);
    float* sum_data = sum.cell_data(0);
    float* mean_data = mean.cell_data(0);
    const float* pass_data = pass.cell_data(0);
    for_each_slice(sum.coefficients().size(), uint64_t(1) << 22, progress,
                   [&](uint64_t begin, uint64_t end) {
                       for (uint64_t i = begin; i < end; ++i) {
                           sum_data[i] += pass_data[i];
                           mean_data[i] = sum_data[i] * inv_passes;
                       }
                   });
    stages.push_back({prefix + "injection", seconds_since(start)});
    stages.push_back({prefix + "geometry_volume", l.geometry_seconds});

    if (progress)
        progress->begin_stage(n > 1 ? format_message("propagating, level ", level)
                                    : std::string("propagating"),
                              inject_end, lo + span);
    std::vector<double> step_seconds;
    ShVolume accumulated =
        propagate(mean, step, propagation_steps(settings_),
                  settings_.occlusion ? &l.transmittance : nullptr, progress, &step_seconds,
                  settings_.occlude_first_step, settings_.settle_fraction);
    finish_accumulation(accumulated);
    for (size_t k = 0; k < step_seconds.size(); ++k)
        stages.push_back({format_message(prefix, "propagation_step_", k + 1), step_seconds[k]});
    return {std::make_shared<const ShVolume>(std::move(accumulated)), l.lookup_transmittance,
            l.blend_faces};
}

void PropagationVolume::refine(Progress* progress) {
    check_scene("refine");
    std::vector<StageSeconds> stages;  // the solver's once the pass is committed
    auto start = now();
    if (progress) progress->begin_stage("tracing VPLs", 0.0f, kTraceShare);
    double reflect_seconds = 0.0;
    const std::vector<VirtualPointLight> vpls = trace_vpls(passes_, progress, &reflect_seconds);
    stages.push_back({"vpl_trace", seconds_since(start) - reflect_seconds});
    if (settings_.vpl_bounces > 1) stages.push_back({"vpl_reflect", reflect_seconds});

    const Reinjection reinjection = reinjection_of(settings_);
    const PropagationStep step = step_of(settings_);
    const size_t n = levels_.size();
    std::vector<ShVolume> sums(n), means(n);
    std::vector<PropagationLevel> field_levels(n);
    for (size_t level = 0; level < n; ++level)
        field_levels[level] =
            pass_level(level, vpls, step, progress, stages, sums[level], means[level]);

    // Nothing above changed the solver: commit the pass.
    for (size_t level = 0; level < n; ++level) {
        levels_[level].injected_sum = std::move(sums[level]);
        levels_[level].injected = std::move(means[level]);
    }
    field_ = std::make_shared<PropagationField>(std::move(field_levels),
                                                settings_.normal_offset, settings_.damping,
                                                reinjection);
    last_vpl_count_ = vpls.size();
    stage_seconds_ = std::move(stages);
    ++passes_;
    if (progress) progress->set_fraction(1.0f);
}

std::vector<int> PropagationVolume::recenter(const vec3& point, Progress* progress) {
    if (!is_finite(point))
        throw InvalidArgument(format_message("PropagationVolume.recenter: the point ",
                                             glm::to_string(point), " must be finite"));
    check_scene("recenter");
    const size_t n = levels_.size();
    if (n < 2) return {};
    const std::vector<LevelGrid> grids =
        level_grids(coarse_origin_, coarse_cell_size_, coarse_dims_, settings_, point);
    std::vector<int> moved;
    for (size_t level = 0; level + 1 < n; ++level) {
        const Level& l = levels_[level];
        const LevelGrid& grid = grids[level];
        if (grid.start == l.start) continue;  // already there, or held against the bounds
        // The inner region: the middle half of the level's box along each axis.
        const vec3 lower = l.injected.origin() + 0.5f * l.injected.cell_size();
        const vec3 extent = vec3(l.injected.counts() - 1) * l.injected.cell_size();
        const vec3 from = (point - lower) / extent;
        if (glm::all(glm::greaterThanEqual(from, vec3(0.25f))) &&
            glm::all(glm::lessThanEqual(from, vec3(0.75f))))
            continue;
        moved.push_back(int(level));
    }
    if (moved.empty()) return moved;

    // Everything below is built aside and committed at the end: a cancel keeps the solver.
    std::vector<Level> rebuilt;
    for (size_t k = 0; k < moved.size(); ++k) {
        const LevelGrid& grid = grids[size_t(moved[k])];
        if (progress)
            progress->begin_stage(format_message("geometry volume, level ", moved[k]),
                                  0.5f * float(k) / float(moved.size()),
                                  0.5f * float(k + 1) / float(moved.size()));
        const auto start = now();
        rebuilt.push_back(make_level(ShLattice(grid.origin, grid.cell_size, grid.dims, 1),
                                     grid.blend_faces, progress));
        rebuilt.back().geometry_seconds = seconds_since(start);
        rebuilt.back().start = grid.start;
    }
    std::vector<PropagationLevel> field_levels = field_->levels();
    if (passes_ > 0) {
        // Every pass's VPLs again (each pass's own seed), summed in pass order as refine()
        // summed them, then the mean and the propagation of the last pass.
        for (uint64_t pass = 0; pass < passes_; ++pass) {
            if (progress)
                progress->begin_stage(format_message("re-injecting VPLs, pass ", pass + 1),
                                      0.5f + 0.4f * float(pass) / float(passes_),
                                      0.5f + 0.4f * float(pass + 1) / float(passes_));
            double reflect_seconds = 0.0;
            const std::vector<VirtualPointLight> vpls =
                trace_vpls(pass, progress, &reflect_seconds);
            for (Level& l : rebuilt) {
                ShVolume injection(l.injected.origin(), l.injected.cell_size(),
                                   l.injected.counts(), settings_.order);
                inject_vpls(injection, vpls, progress);
                float* sum_data = l.injected_sum.cell_data(0);
                const float* pass_data = injection.cell_data(0);
                for_each_slice(l.injected_sum.coefficients().size(), uint64_t(1) << 22, progress,
                               [&](uint64_t begin, uint64_t end) {
                                   for (uint64_t i = begin; i < end; ++i)
                                       sum_data[i] += pass_data[i];
                               });
            }
        }
        const float inv_passes = 1.0f / float(passes_);
        const PropagationStep step = step_of(settings_);
        for (size_t k = 0; k < moved.size(); ++k) {
            Level& l = rebuilt[k];
            const float* sum_data = l.injected_sum.cell_data(0);
            float* mean_data = l.injected.cell_data(0);
            for_each_slice(l.injected.coefficients().size(), uint64_t(1) << 22, progress,
                           [&](uint64_t begin, uint64_t end) {
                               for (uint64_t i = begin; i < end; ++i)
                                   mean_data[i] = sum_data[i] * inv_passes;
                           });
            if (progress)
                progress->begin_stage(format_message("propagating, level ", moved[k]),
                                      0.9f + 0.1f * float(k) / float(moved.size()),
                                      0.9f + 0.1f * float(k + 1) / float(moved.size()));
            ShVolume accumulated = propagate(
                l.injected, step, propagation_steps(settings_),
                settings_.occlusion ? &l.transmittance : nullptr, progress, nullptr,
                settings_.occlude_first_step, settings_.settle_fraction);
            finish_accumulation(accumulated);
            field_levels.at(size_t(moved[k])) = {
                std::make_shared<const ShVolume>(std::move(accumulated)), l.lookup_transmittance,
                l.blend_faces};
        }
    }

    // Nothing above changed the solver: commit the moved levels.
    for (size_t k = 0; k < moved.size(); ++k) levels_[size_t(moved[k])] = std::move(rebuilt[k]);
    if (passes_ > 0)
        field_ = std::make_shared<PropagationField>(std::move(field_levels),
                                                    settings_.normal_offset, settings_.damping,
                                                    reinjection_of(settings_));
    if (progress) progress->set_fraction(1.0f);
    return moved;
}

size_t PropagationVolume::memory_bytes() const {
    size_t bytes = field_ ? field_->memory_bytes() : 0;
    for (const Level& l : levels_)
        bytes += (l.injected_sum.coefficients().size() + l.injected.coefficients().size()) *
                     sizeof(float) +
                 l.transmittance.values.size() * sizeof(float) +
                 (l.lookup_transmittance ? l.lookup_transmittance->size() * sizeof(float) : 0);
    return bytes;
}

}  // namespace shgi
