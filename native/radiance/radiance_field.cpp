#include "radiance/radiance_field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <utility>

#include "photon/photon_tracer.h"
#include "render/shading.h"
#include "scene/mesh.h"
#include "sh/sh_basis.h"
#include "sh/sh_projection.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/parallel.h"
#include "util/rng.h"
#include "util/sampling.h"
#include "util/timer.h"

namespace shgi {
namespace {

constexpr const char* kSettings = "RadianceFieldSettings";
constexpr int kFieldOrder = 2;  // L2: the seed's 9 coefficients
constexpr int kFieldCoefficients = sh_num_coefficients(kFieldOrder);
// Gather rays per parallel chunk: a few milliseconds of work, so a cancel lands well within 0.2 s.
constexpr uint64_t kRaysPerChunk = 8192;
constexpr uint64_t kHitsPerChunk = 4096;
// A photon's surface is looked up again by a ray of this length (in cells) back along its path.
constexpr float kRelookCells = 1e-3f;
// Gather rays ignore hits nearer than this (in cells) to their sample point.
constexpr float kSelfHitCells = 1e-4f;
// How far (in cells) a shading point's shadow rays start off its surface.
constexpr float kSideNudge = 1e-3f;
// Default R_max of the obscurance, in cells.
constexpr float kDefaultObscuranceCells = 2.0f;
// Past this many bounces the light left (albedo^64: 6e-7 at 0.8) is invisible.
constexpr int kMaxBounces = 64;
// Above this resolution the dense L2 field alone passes 600 MB.
constexpr int kMaxResolution = 128;

PhotonTracerSettings tracer_settings(const RadianceFieldSettings& s) {
    PhotonTracerSettings tracer;
    tracer.photons = s.photons;
    tracer.seed = s.seed;
    // The field reflects every photon once more where it lands (the faces hold reflected
    // light): photons stored after max_bounces − 1 scatterings give light of max_bounces
    // bounces at the shading point, as a camera path of max_bounces diffuse bounces. With
    // max_bounces = 1 only the first hits count (the tracer's stored photons are dropped).
    tracer.max_bounces = std::max(1, s.max_bounces - 1);
    // Glossy scatterings on their own budget, as the path tracer's Glossy beside Diffuse.
    tracer.max_glossy_bounces = s.glossy_bounces;
    tracer.specular_roughness = s.specular_roughness;
    // The first hits from the world come through first_hits: storing them in the maps as well
    // would count them twice.
    tracer.store_world_direct = false;
    tracer.store_first_hits = true;
    return tracer;
}

void check_int(int value, int lo, int hi, const char* name) {
    if (value < lo || value > hi)
        throw InvalidArgument(format_message(kSettings, ".", name, " is ", value,
                                             "; it must be in [", lo, ", ", hi, "]"));
}

// lo < value <= hi (lo_open) or lo <= value <= hi, and finite.
void check_float(float value, float lo, float hi, bool lo_open, const char* name) {
    const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) && value <= hi;
    if (!ok)
        throw InvalidArgument(format_message(kSettings, ".", name, " is ", value, "; it must be in ",
                                             lo_open ? "(" : "[", lo, ", ", hi, "]"));
}

const RadianceFieldSettings& validated(const RadianceFieldSettings& settings) {
    validate_radiance_field_settings(settings);
    return settings;
}

// Bit of the neighbour at offset (dx, dy, dz) in RadianceField::sees_.
constexpr uint32_t neighbour_bit(const ivec3& offset) {
    return 1u << uint32_t((offset.z + 1) * 9 + (offset.y + 1) * 3 + (offset.x + 1));
}

// True when nothing lies on the segment from `from` to `to` (its ends excluded by a hair).
bool segment_clear(const Scene& scene, const vec3& from, const vec3& to) {
    constexpr float kEndShare = 1e-3f;  // of the segment, at either end
    Ray ray;
    ray.origin = from;
    ray.direction = to - from;
    ray.tmin = kEndShare;
    ray.tmax = 1.0f - kEndShare;
    return !scene.occluded(ray);
}

Bounds3 field_bounds(const Scene& scene, const RadianceFieldSettings& settings) {
    Bounds3 bounds;
    if (settings.use_bounds) {
        bounds.extend(settings.bounds_min);
        bounds.extend(settings.bounds_max);
        return bounds;
    }
    if (scene.empty())
        throw InvalidArgument("RadianceField: the scene has no geometry; add meshes and "
                              "instances (or set use_bounds) before solving");
    return scene.bounds();
}

}  // namespace

void validate_radiance_field_settings(const RadianceFieldSettings& s) {
    check_int(s.glossy_bounces, 0, kMaxBounces, "glossy_bounces");
    validate_photon_tracer_settings(tracer_settings(s), kSettings);
    check_int(s.max_bounces, 1, kMaxBounces, "max_bounces");
    check_int(s.resolution, 1, kMaxResolution, "resolution");
    check_int(s.gather_rays, 1, 1 << 20, "gather_rays");
    if (s.face_estimator != FaceEstimator::ProjectedArea && s.face_estimator != FaceEstimator::Paper)
        throw InvalidArgument(format_message(kSettings, ".face_estimator is ",
                                             int(s.face_estimator),
                                             "; use PROJECTED_AREA or PAPER"));
    check_float(s.face_sigma, 0.0f, kPi, true, "face_sigma");
    check_int(s.mip_levels, 1, 16, "mip_levels");
    check_float(s.min_footprint_cosine, 0.0f, 1.0f, true, "min_footprint_cosine");
    check_float(s.backface_threshold, 0.0f, 1.0f, true, "backface_threshold");
    check_float(s.obscurance_weight, 0.0f, 1e6f, true, "obscurance_weight");
    check_float(s.obscurance_distance, 0.0f, kMaxCoordinate, false, "obscurance_distance");
    check_int(s.obscurance_rays, 1, 4096, "obscurance_rays");
    check_int(s.diffuse_gather_rays, 1, 1 << 16, "diffuse_gather_rays");
    check_int(s.glossy_gather_rays, 1, 1 << 16, "glossy_gather_rays");
    if (s.use_bounds && (!is_finite(s.bounds_min) || !is_finite(s.bounds_max) ||
                         glm::any(glm::greaterThanEqual(s.bounds_min, s.bounds_max))))
        throw InvalidArgument(format_message(
            kSettings, ".bounds_min/bounds_max are (", s.bounds_min.x, ", ", s.bounds_min.y, ", ",
            s.bounds_min.z, ") / (", s.bounds_max.x, ", ", s.bounds_max.y, ", ", s.bounds_max.z,
            "); they must be finite with min < max on every axis"));
}

// One pass's gather, per sample point (in sample_cells_ order).
struct RadianceField::Gathered {
    std::vector<ShRgb> radiance;
    std::vector<std::array<float, kFieldCoefficients>> distance;
    std::vector<uint32_t> backfaces;
    uint64_t rays = 0;
};

RadianceField::RadianceField(const Scene& scene, const RadianceFieldSettings& settings,
                             Progress* progress)
    : scene_(&scene), settings_(validated(settings)) {
    reset(progress);
}

RadianceField::~RadianceField() = default;

void RadianceField::reset(Progress* progress) {
    if (!scene_->committed())
        throw InvalidArgument("RadianceField: the scene is not committed; call commit() first");
    const auto start = now();
    if (progress != nullptr) progress->begin_stage("voxelise", 0.0f, 1.0f);
    ShLattice surfaces(field_bounds(*scene_, settings_), settings_.resolution, 1);
    surfaces.measure_surfaces(*scene_, progress);
    const ivec3 dims = surfaces.dims();
    // Sample points: boundary cells and their 26 neighbours (§3.4.2).
    std::vector<uint8_t> near(surfaces.cell_count(), 0);
    for (int z = 0; z < dims.z; ++z)
        for (int y = 0; y < dims.y; ++y)
            for (int x = 0; x < dims.x; ++x) {
                if (!(surfaces.surface_area(surfaces.cell_index(ivec3(x, y, z))) > 0.0f)) continue;
                for (int dz = -1; dz <= 1; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            const ivec3 c(x + dx, y + dy, z + dz);
                            if (glm::all(glm::greaterThanEqual(c, ivec3(0))) &&
                                glm::all(glm::lessThan(c, dims)))
                                near[surfaces.cell_index(c)] = 1;
                        }
            }
    std::vector<uint32_t> sample_cells;
    for (size_t c = 0; c < near.size(); ++c)
        if (near[c]) sample_cells.push_back(uint32_t(c));
    // The sample points' mutual visibility, for the occlusion test.
    std::vector<uint32_t> sees(settings_.occlusion_test ? near.size() : 0, 0);
    if (settings_.occlusion_test) {
        const float s = surfaces.cell_size();
        const vec3 origin = surfaces.origin();
        parallel_for(
            0, sample_cells.size(), 256,
            [&](uint64_t begin, uint64_t end) {
                for (uint64_t i = begin; i < end; ++i) {
                    const uint32_t c = sample_cells[i];
                    const ivec3 cell(int(c % uint32_t(dims.x)),
                                     int((c / uint32_t(dims.x)) % uint32_t(dims.y)),
                                     int(c / (uint32_t(dims.x) * uint32_t(dims.y))));
                    const vec3 centre = origin + (vec3(cell) + 0.5f) * s;
                    uint32_t mask = neighbour_bit(ivec3(0));
                    for (int dz = -1; dz <= 1; ++dz)
                        for (int dy = -1; dy <= 1; ++dy)
                            for (int dx = -1; dx <= 1; ++dx) {
                                const ivec3 o(dx, dy, dz);
                                const ivec3 n = cell + o;
                                if (o == ivec3(0) || glm::any(glm::lessThan(n, ivec3(0))) ||
                                    glm::any(glm::greaterThanEqual(n, dims)) ||
                                    !near[surfaces.cell_index(n)])
                                    continue;
                                if (segment_clear(*scene_, centre, origin + (vec3(n) + 0.5f) * s))
                                    mask |= neighbour_bit(o);
                            }
                    sees[c] = mask;
                }
            },
            progress);
    }
    ShVolume field(surfaces.origin(), surfaces.cell_size(), dims, kFieldOrder);
    ShVolume field_sum = field;
    std::vector<uint8_t> closed(scene_->instances().size());
    for (size_t i = 0; i < closed.size(); ++i)
        closed[i] = is_closed_surface(scene_->meshes()[scene_->instances()[i].mesh_id]) ? 1 : 0;
    RadianceGrid grid(std::move(surfaces), settings_.use_mips ? settings_.mip_levels : 1,
                      settings_.face_estimator);

    grid_ = std::move(grid);
    sample_cells_ = std::move(sample_cells);
    active_.assign(near.size(), 0);
    sees_ = std::move(sees);
    field_ = std::move(field);
    field_sum_ = std::move(field_sum);
    distance_.assign(near.size() * kFieldCoefficients, 0.0f);
    distance_sum_ = distance_;
    inside_votes_.assign(sample_cells_.size(), 0);
    closed_instance_ = std::move(closed);
    passes_ = 0;
    timings_ = RadianceFieldTimings{};
    timings_.voxelise = seconds_since(start);
    scene_revision_ = scene_->revision();
    if (progress != nullptr) progress->set_fraction(1.0f);
}

void RadianceField::check_scene() const {
    if (scene_->revision() != scene_revision_ || !scene_->committed())
        throw InvalidArgument(format_message(
            "RadianceField::refine: the scene was edited after it was voxelised (revision ",
            scene_revision_, ", now ", scene_->revision(), "); commit it and call reset()"));
}

std::vector<ReflectedHit> RadianceField::reflected_hits(Progress* progress,
                                                        RadianceFieldTimings* timings) {
    const PhotonMaps maps =
        trace_photons(*scene_, tracer_settings(settings_), passes_, progress, kSettings);
    timings->photons_emitted = maps.emitted;
    const size_t first = maps.first_hits.size();
    const size_t stored =
        settings_.max_bounces > 1 ? maps.global.size() + maps.caustic.size() : 0;
    require_memory(saturating_mul(first + stored, sizeof(ReflectedHit)),
                   format_message(kSettings, ".photons = ", settings_.photons, ": ",
                                  first + stored, " reflected hits"),
                   "lower RadianceFieldSettings.photons");
    std::vector<ReflectedHit> hits(first + stored);
    const float reach = kRelookCells * grid_.cell_size(0);
    parallel_for(
        0, first + stored, kHitsPerChunk,
        [&](uint64_t begin, uint64_t end) {
            for (uint64_t i = begin; i < end; ++i) {
                ReflectedHit& hit = hits[i];
                vec3 power;
                if (i < first) {
                    const PhotonFirstHit& h = maps.first_hits[i];
                    hit = {h.position, h.normal, h.direction, h.reflected_power};
                    if (!settings_.glossy_in_grid) continue;  // the tracer's diffuse share
                    power = h.power;
                } else {
                    const size_t k = i - first;
                    const Photon& p = k < maps.global.size() ? maps.global[k]
                                                             : maps.caustic[k - maps.global.size()];
                    hit = {p.position, p.normal, p.direction, vec3(0.0f)};
                    power = p.power;
                }
                // The diffuse lobe always; with glossy_in_grid the rough glossy lobes too (see
                // the header).
                hit.reflected_power = scattered_flux(
                    *scene_, hit.position, hit.normal, hit.direction, power, reach,
                    settings_.glossy_in_grid ? settings_.specular_roughness : -1.0f);
            }
        },
        progress);
    return hits;
}

RadianceField::Gathered RadianceField::gather(uint64_t pass, Progress* progress) const {
    const uint32_t n = uint32_t(settings_.gather_rays);
    Gathered out;
    const size_t points = sample_cells_.size();
    out.radiance.assign(points, ShRgb(kFieldOrder));
    out.distance.assign(points, {});
    out.backfaces.assign(points, 0);
    // The Fibonacci set under one rotation per pass (§3.4.2's uniform directions; passes see
    // different directions, so their mean converges).
    Pcg32 rng(settings_.seed, stream_id(pass, 0));
    const vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
    const mat3 rotation = sample_uniform_rotation(u);
    std::vector<vec3> directions(n);
    for (uint32_t r = 0; r < n; ++r) directions[r] = glm::normalize(rotation * fibonacci_sphere(r, n));
    const float weight = kFourPi / float(n);
    const float base_area = grid_.cell_size(0) * grid_.cell_size(0);
    const float far = glm::length(vec3(grid_.dims(0)) * grid_.cell_size(0));
    const vec3 world = settings_.world_in_field ? scene_->world().radiance() : vec3(0.0f);
    const ivec3 dims = grid_.dims(0);
    parallel_for(
        0, points, std::max<uint64_t>(1, kRaysPerChunk / n),
        [&](uint64_t begin, uint64_t end) {
            float y[kFieldCoefficients];
            for (uint64_t i = begin; i < end; ++i) {
                const uint32_t c = sample_cells_[i];
                const ivec3 cell(int(c % uint32_t(dims.x)), int((c / uint32_t(dims.x)) % uint32_t(dims.y)),
                                 int(c / (uint32_t(dims.x) * uint32_t(dims.y))));
                const vec3 x = field_.cell_centre(cell);
                ShRgb& sh = out.radiance[i];
                auto& distance = out.distance[i];
                for (uint32_t r = 0; r < n; ++r) {
                    const vec3& d = directions[r];
                    Ray ray;
                    ray.origin = x;
                    ray.direction = d;
                    // A sample point on a surface (a flat scene's single layer of cells is
                    // centred on it) must not see that surface at t = 0 in every direction.
                    ray.tmin = kSelfHitCells * grid_.cell_size(0);
                    const Hit hit = scene_->intersect(ray);
                    vec3 radiance = world;
                    float t = far;
                    if (hit.valid()) {
                        t = std::min(hit.t, far);
                        radiance = vec3(0.0f);
                        const vec3 normal = glm::normalize(hit.geometric_normal);
                        const float facing = glm::dot(normal, d);
                        if (closed_instance_[hit.instance_id] && facing > 0.0f) {
                            ++out.backfaces[i];  // inside a solid: no light there
                        } else {
                            bool lit = false;
                            // Footprint 4πd²/(N cos β) against the finest face (§3.4.3).
                            const float cosine =
                                std::max(std::fabs(facing), settings_.min_footprint_cosine);
                            const float footprint = weight * hit.t * hit.t / cosine;
                            const float level =
                                settings_.use_mips
                                    ? std::max(0.0f, 0.5f * std::log2(footprint / base_area))
                                    : 0.0f;
                            // The side of the surface the ray sees (its normal towards x).
                            const vec3 side = facing > 0.0f ? -normal : normal;
                            radiance = grid_.radiance_toward(x, x + hit.t * d, d, side, level,
                                                             settings_.face_sigma, &lit);
                            // The unlit side of an open surface counts as a back face: a point
                            // beyond a room's single-sided wall sees the wall's outside.
                            if (!lit) ++out.backfaces[i];
                        }
                    }
                    sh_eval(kFieldOrder, d, y);
                    for (int k = 0; k < kFieldCoefficients; ++k) {
                        sh[k] += (weight * y[k]) * radiance;
                        distance[size_t(k)] += (weight * y[k]) * t;
                    }
                }
            }
        },
        progress);
    out.rays = uint64_t(points) * n;
    return out;
}

void RadianceField::refine(Progress* progress) {
    check_scene();
    RadianceFieldTimings timings;
    timings.voxelise = timings_.voxelise;
    auto start = now();
    if (progress != nullptr) progress->begin_stage("photons", 0.0f, 0.45f);
    const std::vector<ReflectedHit> hits = reflected_hits(progress, &timings);
    timings.photons = seconds_since(start);
    timings.hits = hits.size();

    // On a copy, so that a cancel keeps the previous solution.
    if (progress != nullptr) progress->begin_stage("radiance_grid", 0.45f, 0.5f);
    start = now();
    RadianceGrid grid = grid_;
    grid.add_pass(hits, progress);
    timings.radiance_grid = seconds_since(start);

    if (progress != nullptr) progress->begin_stage("sh_field", 0.5f, 1.0f);
    start = now();
    std::swap(grid, grid_);  // gather() reads grid_
    Gathered gathered;
    try {
        gathered = gather(passes_, progress);
    } catch (...) {
        std::swap(grid, grid_);
        throw;
    }
    timings.sh_field = seconds_since(start);
    timings.gather_rays = gathered.rays;

    ++passes_;
    timings.sample_points = fold_in(gathered);
    timings_ = timings;
    if (progress != nullptr) progress->set_fraction(1.0f);
}

uint64_t RadianceField::fold_in(const Gathered& gathered) {
    const float mean = 1.0f / float(passes_);
    const float inside_rays =
        settings_.backface_threshold * float(settings_.gather_rays) * float(passes_);
    uint64_t active = 0;
    for (size_t i = 0; i < sample_cells_.size(); ++i) {
        const size_t c = sample_cells_[i];
        float* sum = field_sum_.cell_data(c);
        float* value = field_.cell_data(c);
        for (int k = 0; k < kFieldCoefficients; ++k)
            for (int ch = 0; ch < 3; ++ch) {
                sum[k * 3 + ch] += gathered.radiance[i][k][ch];
                value[k * 3 + ch] = sum[k * 3 + ch] * mean;
            }
        for (int k = 0; k < kFieldCoefficients; ++k) {
            const size_t f = c * kFieldCoefficients + size_t(k);
            distance_sum_[f] += gathered.distance[i][size_t(k)];
            distance_[f] = distance_sum_[f] * mean;
        }
        inside_votes_[i] += gathered.backfaces[i];
        active_[c] = float(inside_votes_[i]) <= inside_rays ? 1 : 0;
        active += active_[c];
    }
    return active;
}

void RadianceField::rebuild_field(Progress* progress) {
    const Gathered gathered = gather(0, progress);
    std::fill(field_sum_.cell_data(0), field_sum_.cell_data(0) + field_sum_.coefficients().size(),
              0.0f);
    std::fill(distance_sum_.begin(), distance_sum_.end(), 0.0f);
    std::fill(inside_votes_.begin(), inside_votes_.end(), 0u);
    passes_ = 1;
    fold_in(gathered);
}

ShRgb RadianceField::sample_point_sh(const ivec3& cell) const {
    return field_.cell_coefficients(cell);
}

bool RadianceField::is_sample_point(const ivec3& cell) const {
    const ivec3 dims = field_.counts();
    if (glm::any(glm::lessThan(cell, ivec3(0))) || glm::any(glm::greaterThanEqual(cell, dims)))
        return false;
    return active_[field_.cell_index(cell)] != 0;
}

template <typename Visit>
bool RadianceField::for_each_neighbour(const vec3& p, const vec3& n, bool tests,
                                       Visit&& visit) const {
    const float s = field_.cell_size();
    const ivec3 dims = field_.counts();
    const vec3 q = (p - field_.origin()) / s;
    const ivec3 base = glm::clamp(ivec3(glm::floor(q)), ivec3(0), dims - 1);
    struct Candidate {
        size_t index;
        ivec3 cell;
        float weight;
    };
    std::array<Candidate, 27> picked;
    int count = 0;
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const ivec3 c = base + ivec3(dx, dy, dz);
                if (glm::any(glm::lessThan(c, ivec3(0))) || glm::any(glm::greaterThanEqual(c, dims)))
                    continue;
                const size_t index = field_.cell_index(c);
                if (!active_[index]) continue;
                const float w = cubic_falloff(glm::length(q - (vec3(c) + 0.5f)));
                if (!(w > 0.0f)) continue;
                const vec3 centre = field_.cell_centre(c);
                if (tests && settings_.side_test && glm::dot(centre - p, n) < 0.0f) continue;
                if (tests && settings_.visibility_test && hidden_by_distance(index, centre, p))
                    continue;
                picked[size_t(count++)] = {index, c, w};
            }
    if (tests && settings_.occlusion_test && count > 0) {
        // The anchor: the heaviest sample point p sees; the others must see the anchor.
        std::sort(picked.begin(), picked.begin() + count,
                  [](const Candidate& a, const Candidate& b) {
                      return a.weight > b.weight || (a.weight == b.weight && a.index < b.index);
                  });
        const vec3 from = p + n * (kSideNudge * s);
        int anchor = -1;
        for (int i = 0; i < count && anchor < 0; ++i)
            if (segment_clear(*scene_, from, field_.cell_centre(picked[size_t(i)].cell)))
                anchor = i;
        if (anchor >= 0) {
            const Candidate a = picked[size_t(anchor)];
            const uint32_t mask = sees_[a.index];
            int kept = 0;
            for (int i = 0; i < count; ++i)
                if (mask & neighbour_bit(picked[size_t(i)].cell - a.cell))
                    picked[size_t(kept++)] = picked[size_t(i)];
            count = kept;
        }
    }
    float total = 0.0f;
    for (int i = 0; i < count; ++i) total += picked[size_t(i)].weight;
    if (!(total > 0.0f)) return false;
    for (int i = 0; i < count; ++i) visit(picked[size_t(i)].index, picked[size_t(i)].weight / total);
    return true;
}

bool RadianceField::hidden_by_distance(size_t index, const vec3& centre, const vec3& p) const {
    const vec3 to_p = p - centre;
    const float length = glm::length(to_p);
    const float s = field_.cell_size();
    if (!(length > s)) return false;
    float y[kFieldCoefficients];
    sh_eval(kFieldOrder, to_p / length, y);
    float seen = 0.0f;
    for (int k = 0; k < kFieldCoefficients; ++k)
        seen += y[k] * distance_[index * kFieldCoefficients + size_t(k)];
    return seen < length - s;  // a surface lies between
}

ShRgb RadianceField::radiance_sh(const vec3& p, const vec3& n) const {
    ShRgb result(kFieldOrder);
    if (passes_ == 0 || !is_finite(p) || !is_finite(n)) return result;
    const auto add = [&](size_t index, float w) {
        const float* c = field_.cell_data(index);
        for (int k = 0; k < kFieldCoefficients; ++k)
            result[k] += w * vec3(c[k * 3], c[k * 3 + 1], c[k * 3 + 2]);
    };
    if (!for_each_neighbour(p, n, true, add)) for_each_neighbour(p, n, false, add);
    if (settings_.obscurance) {
        const float o = obscurance(p, n);
        for (int k = 0; k < kFieldCoefficients; ++k) result[k] *= o;
    }
    return result;
}

FieldLookup RadianceField::lookup(const vec3& p, const vec3& n) const {
    FieldLookup out{radiance_sh(p, n), vec3(0.0f)};
    if (settings_.monte_carlo_gathers) {
        out.diffuse_rays = uint32_t(settings_.diffuse_gather_rays);
        out.glossy_rays = uint32_t(settings_.glossy_gather_rays);
        // The point's bits and the seed, mixed (splitmix64's finaliser): the same point gathers
        // the same directions in every run and on every thread.
        uint64_t key = settings_.seed;
        for (int a = 0; a < 3; ++a) {
            uint32_t bits = 0;
            std::memcpy(&bits, &p[a], sizeof bits);
            key = (key ^ bits) * 0x9e3779b97f4a7c15ull;
            key ^= key >> 31;
        }
        out.gather_key = key;
    }
    return out;
}

float RadianceField::obscurance(const vec3& p, const vec3& n) const {
    if (passes_ == 0) return 1.0f;
    std::array<float, kFieldCoefficients> distance{};
    const auto add = [&](size_t index, float w) {
        for (int k = 0; k < kFieldCoefficients; ++k)
            distance[size_t(k)] += w * distance_[index * kFieldCoefficients + size_t(k)];
    };
    if (!for_each_neighbour(p, n, true, add) && !for_each_neighbour(p, n, false, add)) return 1.0f;
    const float r_max = settings_.obscurance_distance > 0.0f
                            ? settings_.obscurance_distance
                            : kDefaultObscuranceCells * field_.cell_size();
    const uint32_t sphere = 2u * uint32_t(settings_.obscurance_rays);
    float sum = 0.0f;
    float y[kFieldCoefficients];
    for (uint32_t i = 0; i < sphere; ++i) {
        const vec3 w = fibonacci_sphere(i, sphere);
        const float cosine = glm::dot(n, w);
        if (cosine <= 0.0f) continue;
        sh_eval(kFieldOrder, w, y);
        float d = 0.0f;
        for (int k = 0; k < kFieldCoefficients; ++k) d += y[k] * distance[size_t(k)];
        sum += std::min(settings_.obscurance_weight * std::max(d, 0.0f) / r_max, 1.0f) * cosine;
    }
    return std::clamp(2.0f * sum / float(settings_.obscurance_rays), 0.0f, 1.0f);
}

float RadianceField::reuse_distance() const {
    constexpr float kReuseShare = 0.25f;  // of a cell: small beside the cubic filter's 1.75
    return kReuseShare * field_.cell_size();
}

std::shared_ptr<const IndirectField> RadianceField::current_field() const {
    // Non-owning: the solver is its own field, valid until the next refine() or reset().
    return std::shared_ptr<const IndirectField>(std::shared_ptr<const IndirectField>(), this);
}

std::vector<StageSeconds> RadianceField::stage_seconds() const {
    return {{"voxelise", timings_.voxelise},
            {"photons", timings_.photons},
            {"radiance_grid", timings_.radiance_grid},
            {"sh_field", timings_.sh_field}};
}

size_t RadianceField::memory_bytes() const {
    return grid_.memory_bytes() +
           (field_.coefficients().size() + field_sum_.coefficients().size() + distance_.size() +
            distance_sum_.size()) *
               sizeof(float) +
           sample_cells_.size() * (sizeof(uint32_t) * 2) + active_.size();
}

}  // namespace shgi
