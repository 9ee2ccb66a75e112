#include "propagation/propagation_volume.h"

#include <algorithm>
#include <cmath>
#include <utility>

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
// Propagation cells per parallel task of the transmittance.
constexpr uint64_t kCellsPerTask = 4096;
// Progress shares of a pass's stages (tracing dominates at the default settings).
constexpr float kTraceShare = 0.6f, kInjectShare = 0.7f;

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
    tracer.store_first_hits = true;
    return tracer;
}

PropagationStencil stencil_of(int order) {
    return order == 1 ? PropagationStencil::Faces6 : PropagationStencil::Neighbours26;
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
    if (glm::any(glm::lessThan(cell, ivec3(0))) ||
        glm::any(glm::greaterThanEqual(cell, volume.counts())))
        return kNoCell;
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
    const ivec3 dims = geometry.dims(), counts = volume.counts();
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
            const ivec3 cell(int(c % uint64_t(counts.x)),
                             int((c / uint64_t(counts.x)) % uint64_t(counts.y)),
                             int(c / (uint64_t(counts.x) * uint64_t(counts.y))));
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

}  // namespace

void validate_propagation_settings(const PropagationSettings& settings) {
    validate_photon_tracer_settings(tracer_settings(settings), kSettings);
    check_range(settings.vpl_bounces, 1, 64, "vpl_bounces");
    check_range(settings.resolution, 2, 256, "resolution");
    check_range(settings.steps, 0, 1024, "steps");
    check_range(settings.order, 1, 2, "order");
    if (!std::isfinite(settings.normal_offset) || settings.normal_offset < 0.0f ||
        settings.normal_offset > 2.0f)
        throw InvalidArgument(format_message(kSettings, ".normal_offset is ",
                                             settings.normal_offset,
                                             "; it must be in [0, 2] cells"));
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
                   std::vector<double>* step_seconds, bool occlude_first_step) {
    // Copies of a large volume take a while (~0.1 s at 97³ L2): a cancel poll after each.
    ShVolume accumulated = injected;
    throw_if_cancelled(progress);
    ShVolume ping = injected;
    throw_if_cancelled(progress);
    ShVolume pong = injected;
    throw_if_cancelled(progress);
    float* acc = accumulated.cell_data(0);
    const size_t floats = accumulated.coefficients().size();
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
        if (step_seconds != nullptr) step_seconds->push_back(seconds_since(start));
        if (progress) progress->report(uint64_t(k + 1), uint64_t(steps));
    }
    return accumulated;
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

void PropagationVolume::reset(Progress* progress) {
    if (!scene_->committed())
        throw InvalidArgument("PropagationVolume: the scene is not committed; call commit() first");
    if (scene_->empty())
        throw InvalidArgument("PropagationVolume: the scene has no geometry; add meshes and "
                              "instances before solving");
    const auto start = now();
    if (progress) progress->begin_stage("geometry volume");
    // The geometry lattice decides the cell size; the propagation cells are offset by half a
    // cell from it, one more per axis, so the lattice's centres are their corners.
    ShLattice geometry(scene_->bounds(), settings_.resolution, 1);
    geometry.measure_surfaces(*scene_, progress);
    const float s = geometry.cell_size();
    ShVolume volume(geometry.origin() - 0.5f * s, s, geometry.dims() + 1, settings_.order);
    // Five volumes (the injection's sum and mean, ping, pong, accumulation) and the
    // transmittances (26 neighbours, and the LPV's 6 beside them).
    require_memory(saturating_add(saturating_mul(volume.coefficients().size() * sizeof(float), 5),
                                  saturating_mul(volume.cell_count(), (26 + 6) * sizeof(float))),
                   format_message("PropagationVolume: resolution ", settings_.resolution,
                                  " gives ", volume.counts().x, " x ", volume.counts().y, " x ",
                                  volume.counts().z, " cells, 5 volumes of them"),
                   "lower the resolution");
    PropagationTransmittance transmittance;
    std::shared_ptr<const NeighbourTransmittance> lookup;
    if (settings_.occlusion) {
        PropagationTransmittance all = geometry_transmittance(
            geometry, scene_->bounds(), volume, PropagationStencil::Neighbours26, progress);
        transmittance = settings_.order == 2
                            ? all
                            : geometry_transmittance(geometry, scene_->bounds(), volume,
                                                     PropagationStencil::Faces6, progress);
        lookup = std::make_shared<const NeighbourTransmittance>(std::move(all.values));
    }
    injected_sum_ = volume;
    injected_ = volume;
    transmittance_ = std::move(transmittance);
    lookup_transmittance_ = std::move(lookup);
    field_ = std::make_shared<PropagationField>();
    passes_ = 0;
    last_vpl_count_ = 0;
    stage_seconds_.clear();
    scene_revision_ = scene_->revision();
    geometry_seconds_ = seconds_since(start);
    if (progress) progress->set_fraction(1.0f);
}

std::vector<VirtualPointLight> PropagationVolume::trace_vpls(Progress* progress,
                                                             double* reflect_seconds) {
    PhotonMaps maps = trace_photons(*scene_, tracer_settings(settings_), passes_, progress,
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
            reflected[i] = shading.bsdf.field_diffuse(shading.wo) * photon.power;
        }
    });
    for (size_t i = 0; i < later.size(); ++i)
        if (reflected[i] != vec3(0.0f) && lights_the_scene(later[i].position, later[i].normal))
            vpls.push_back({later[i].position, later[i].normal, reflected[i]});
    *reflect_seconds = seconds_since(start);
    return vpls;
}

void PropagationVolume::refine(Progress* progress) {
    check_scene("refine");
    std::vector<StageSeconds> stages;  // the solver's once the pass is committed
    auto start = now();
    if (progress) progress->begin_stage("tracing VPLs", 0.0f, kTraceShare);
    double reflect_seconds = 0.0;
    const std::vector<VirtualPointLight> vpls = trace_vpls(progress, &reflect_seconds);
    stages.push_back({"vpl_trace", seconds_since(start) - reflect_seconds});
    if (settings_.vpl_bounces > 1) stages.push_back({"vpl_reflect", reflect_seconds});

    start = now();
    if (progress) progress->begin_stage("injecting VPLs", kTraceShare, kInjectShare);
    ShVolume pass(injected_.origin(), injected_.cell_size(), injected_.counts(), settings_.order);
    inject_vpls(pass, vpls, progress);
    throw_if_cancelled(progress);
    ShVolume sum = injected_sum_;
    throw_if_cancelled(progress);
    ShVolume mean = injected_;
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
    stages.push_back({"injection", seconds_since(start)});
    stages.push_back({"geometry_volume", geometry_seconds_});

    if (progress) progress->begin_stage("propagating", kInjectShare, 1.0f);
    const Reinjection reinjection = settings_.travel_reinjection ? Reinjection::TravelDirection
                                                                 : Reinjection::FaceNormal;
    const PropagationStep step(stencil_of(settings_.order), settings_.order, LobeClamp::Rescaled,
                               reinjection);
    std::vector<double> step_seconds;
    ShVolume accumulated =
        propagate(mean, step, settings_.steps, settings_.occlusion ? &transmittance_ : nullptr,
                  progress, &step_seconds, settings_.occlude_first_step);
    for (size_t k = 0; k < step_seconds.size(); ++k)
        stages.push_back({format_message("propagation_step_", k + 1), step_seconds[k]});

    // Nothing above changed the solver: commit the pass.
    injected_sum_ = std::move(sum);
    injected_ = std::move(mean);
    field_ = std::make_shared<PropagationField>(
        std::make_shared<const ShVolume>(std::move(accumulated)), settings_.normal_offset,
        lookup_transmittance_, settings_.damping, reinjection);
    last_vpl_count_ = vpls.size();
    stage_seconds_ = std::move(stages);
    ++passes_;
    if (progress) progress->set_fraction(1.0f);
}

size_t PropagationVolume::memory_bytes() const {
    return (injected_sum_.coefficients().size() + injected_.coefficients().size()) *
               sizeof(float) +
           transmittance_.values.size() * sizeof(float) +
           (lookup_transmittance_ ? lookup_transmittance_->size() * sizeof(float) : 0) +
           (field_ ? field_->memory_bytes() : 0);
}

}  // namespace shgi
