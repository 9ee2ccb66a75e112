#include "instant/instant_gi.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "photon/photon_tracer.h"
#include "render/film.h"
#include "render/g_buffer.h"
#include "render/shading.h"
#include "sh/sh_basis.h"
#include "sh/sh_irradiance.h"
#include "util/cell_sort.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/parallel.h"
#include "util/rng.h"
#include "util/sampling.h"
#include "util/timer.h"

namespace shgi {
namespace {

constexpr const char* kSettings = "InstantGiSettings";
constexpr int kOrder = 2;
constexpr int kCoeffs = 9;
// VPLs whose albedo is found per parallel task (one short ray each).
constexpr uint64_t kVplsPerTask = 4096;
// Shadow rays per batch of the gather: rows are gathered a few at a time, so a cancel is polled
// every ~10^5 rays (~10 ms on one core).
constexpr uint64_t kRaysPerBatch = 1 << 17;

void check_int(int64_t value, int64_t lo, int64_t hi, const char* name) {
    if (value < lo || value > hi)
        throw InvalidArgument(format_message(kSettings, ".", name, " is ", value,
                                             "; it must be in [", lo, ", ", hi, "]"));
}

void check_float(float value, float lo, float hi, const char* name) {
    if (!std::isfinite(value) || value < lo || value > hi)
        throw InvalidArgument(format_message(kSettings, ".", name, " is ", value,
                                             "; it must be finite and in [", lo, ", ", hi, "]"));
}

PhotonTracerSettings tracer_settings(const InstantGiSettings& s) {
    PhotonTracerSettings tracer;
    tracer.photons = uint64_t(s.sets_x) * uint64_t(s.sets_y) * s.photons_per_set;
    tracer.seed = s.seed;
    // First hits are recorded before any scattering; a photon stored after k scatterings is the
    // (k + 1)-th hit of its path.
    tracer.max_bounces = std::max(1, s.vpl_bounces - 1);
    tracer.max_glossy_bounces = s.glossy_bounces;
    tracer.store_first_hits = true;
    return tracer;
}

// Whether neighbour q joins pixel p's filter: same object, depths within the relative threshold,
// geometric normals (and shading normals when `strict`) within the normal threshold.
bool joins(const GBuffer& g, size_t p, size_t q, const InstantGiSettings& s, bool strict) {
    if (!g.has_surface(q) || g.object_id[q] != g.object_id[p]) return false;
    if (std::abs(g.depth[q] - g.depth[p]) > s.depth_threshold * std::max(g.depth[p], 1e-6f))
        return false;
    if (glm::dot(g.geometric_normal[q], g.geometric_normal[p]) < s.normal_threshold) return false;
    if (strict && glm::dot(g.shading_normal[q], g.shading_normal[p]) < s.normal_threshold)
        return false;
    return true;
}

// visit(q, dx, dy), row by row, for each pixel q of pixel (x, y)'s filter window (half_x,
// half_y taps each side) that lies inside the image and joins it (itself included); returns how
// many of the window's taps lie inside the image.
template <class Visit>
int visit_window(const GBuffer& g, int x, int y, int half_x, int half_y,
                 const InstantGiSettings& s, bool strict, const Visit& visit) {
    const size_t p = g.index(x, y);
    int taps = 0;
    for (int dy = -half_y; dy <= half_y; ++dy) {
        const int qy = y + dy;
        if (qy < 0 || qy >= g.height()) continue;
        for (int dx = -half_x; dx <= half_x; ++dx) {
            const int qx = x + dx;
            if (qx < 0 || qx >= g.width()) continue;
            ++taps;
            const size_t q = g.index(qx, qy);
            if (q != p && !joins(g, p, q, s, strict)) continue;
            visit(q, dx, dy);
        }
    }
    return taps;
}

// Per pixel, 1 where a tap of its filter window inside the image does not join it: an edge
// cuts its window (gather_cut_windows).
// Calls fn(x, y, p) for every pixel p = (x, y) with a surface, rows in parallel.
template <class Fn>
void for_each_surface_pixel(const GBuffer& g, Fn&& fn) {
    parallel_for(0, uint64_t(g.height()), 8, [&](uint64_t y0, uint64_t y1) {
        for (uint64_t y = y0; y < y1; ++y)
            for (int x = 0; x < g.width(); ++x) {
                const size_t p = g.index(x, int(y));
                if (g.has_surface(p)) fn(x, int(y), p);
            }
    });
}

std::vector<uint8_t> cut_window_pixels(const GBuffer& g, const InstantGiSettings& s, int half_x,
                                       int half_y) {
    const bool strict = s.filter_mode == InstantGiFilter::Strict;
    std::vector<uint8_t> cut(g.pixel_count(), 0);
    for_each_surface_pixel(g, [&](int x, int y, size_t p) {
        int joined = 0;
        const int taps = visit_window(g, x, y, half_x, half_y, s, strict,
                                      [&joined](size_t, int, int) { ++joined; });
        cut[p] = joined < taps ? 1 : 0;
    });
    return cut;
}

float distance2(const vec3& a, const vec3& b) {
    const vec3 d = a - b;
    return glm::dot(d, d);
}

// near_field_reach: pixels along a row whose near fields are found together (one pass over
// the VPLs per run: a box test per VPL and run instead of a distance per VPL and pixel).
constexpr int kNearRun = 8;

// near_field_reach's limit: a reach of 64 windows is brute force's cost at any resolution.
constexpr float kMaxNearFieldReach = 64.0f;

// near_field_reach's cap: a pixel's near field holds at most (near_field_reach /
// kNearCapReach)² of a set's VPLs (a quarter at the default reach 4), the nearest ones: its
// radius shrinks to the (cap + 1)-th nearest VPL's distance where more lie within the reach.
// The radius follows the window's footprint, so on a small frame, where a window covers more of
// the scene, the near field held more VPLs than the far gather (the 128 x 128 Cornell box: its
// near rays 1.6 x the far gather's, the frame 2.9 x the paper's filter; at 640 x 360 1.3%). The
// nearest VPLs are the ones whose light changes most across the window. The cap is found as the
// gather reads the run's VPLs (no search of its own). With reach 64 it is 64 sets' VPLs: every
// VPL of up to 64 sets.
constexpr float kNearCapReach = 8.0f;

// The near gather reads a quarter, then half of the radius first where the cells around a run
// hold more than kNearTrialExcess × the cap: then a quarter of the radius (a sixteenth of its
// area) likely holds more than the cap. Below, the trials cost more than they save (every
// third run at 640 x 360 held more than the cap: its frames 1.29 x the paper's filter's CPU
// with a trial for each, 1.11-1.19 x with this, as without the cap; the 128 x 128 Cornell box 1.50 x and 1.48 x, 1.81 x
// without trials). It changes no result, only where the nearest VPLs are looked for.
constexpr size_t kNearTrialExcess = 16;

// Per pixel, the squared radius of its near field (near_field_reach): near_field_reach × the
// distance to the farthest pixel of its filter window that joins it; 0 without a surface.
std::vector<float> near_field_radii(const GBuffer& g, const InstantGiSettings& s, int half_x,
                                    int half_y) {
    const bool strict = s.filter_mode == InstantGiFilter::Strict;
    const float reach2 = s.near_field_reach * s.near_field_reach;
    std::vector<float> radius2(g.pixel_count(), 0.0f);
    for_each_surface_pixel(g, [&](int x, int y, size_t p) {
        float farthest2 = 0.0f;
        visit_window(g, x, y, half_x, half_y, s, strict, [&](size_t q, int, int) {
            farthest2 = std::max(farthest2, distance2(g.position[q], g.position[p]));
        });
        radius2[p] = reach2 * farthest2;
    });
    return radius2;
}

// near_field_reach: a uniform grid over the VPLs a frame gathers, so a pixel's near field
// visits the cells around it instead of every VPL. Cells at least as wide as the median near
// radius, at most kMaxNearGridCells across.
constexpr int kMaxNearGridCells = 64;
class NearVplGrid {
  public:
    // refs: (set, VPL) of every VPL gathered, positions[i] refs[i]'s position.
    NearVplGrid(std::vector<std::pair<uint32_t, uint32_t>> refs,
                const std::vector<vec3>& positions, float cell_width)
        : refs_(std::move(refs)) {
        vec3 hi(-kInfinity);
        lo_ = vec3(kInfinity);
        for (const vec3& q : positions) lo_ = glm::min(lo_, q), hi = glm::max(hi, q);
        if (refs_.empty()) return;
        const float extent = max_component(hi - lo_);
        cell_ = std::max({cell_width, extent / float(kMaxNearGridCells), 1e-6f});
        dims_ = glm::min(ivec3((hi - lo_) / cell_) + 1, ivec3(kMaxNearGridCells));
        std::vector<uint32_t> item_cell(refs_.size());
        for (size_t i = 0; i < refs_.size(); ++i)
            item_cell[i] = uint32_t(linear(cell_of(positions[i])));
        cells_ = sort_by_cell(item_cell, size_t(dims_.x) * size_t(dims_.y) * size_t(dims_.z));
    }
    // visit(set, vpl) for the VPLs in the cells the box [lo, hi] overlaps, cell by cell.
    template <class Visit>
    void visit_box(const vec3& lo, const vec3& hi, const Visit& visit) const {
        if (refs_.empty()) return;
        const ivec3 a = cell_of(lo), b = cell_of(hi);
        for (int z = a.z; z <= b.z; ++z)
            for (int y = a.y; y <= b.y; ++y)
                for (int x = a.x; x <= b.x; ++x) {
                    const size_t cell = linear(ivec3(x, y, z));
                    const uint32_t* items = cells_.items(cell);
                    for (uint32_t i = 0; i < cells_.count(cell); ++i)
                        visit(refs_[items[i]].first, refs_[items[i]].second);
                }
    }
    // How many VPLs the cells the box [lo, hi] overlaps hold: at least those in the box.
    size_t count_box(const vec3& lo, const vec3& hi) const {
        if (refs_.empty()) return 0;
        const ivec3 a = cell_of(lo), b = cell_of(hi);
        size_t count = 0;
        for (int z = a.z; z <= b.z; ++z)
            for (int y = a.y; y <= b.y; ++y)
                for (int x = a.x; x <= b.x; ++x) count += cells_.count(linear(ivec3(x, y, z)));
        return count;
    }

  private:
    ivec3 cell_of(const vec3& q) const {
        return glm::clamp(ivec3(glm::floor((q - lo_) / cell_)), ivec3(0), dims_ - 1);
    }
    size_t linear(const ivec3& c) const {
        return (size_t(c.z) * size_t(dims_.y) + size_t(c.y)) * size_t(dims_.x) + size_t(c.x);
    }
    std::vector<std::pair<uint32_t, uint32_t>> refs_;
    vec3 lo_{0.0f};
    float cell_ = 1.0f;
    ivec3 dims_{1};
    ItemsByCell cells_;
};

// InstantGiSettings.glossy_bounces' limit (the radiance field's).
constexpr int kMaxGlossyBounces = 64;

// InstantGiSettings.passes_per_sample's limit: far beyond any solve's passes.
constexpr int kMaxPassesPerSample = 1 << 16;

// Lobes up to this roughness are mirror-like: their light is not spread as if diffuse.
constexpr float kSpecularRoughness = 0.1f;

// glossy_from_vpls: lobes at least this rough read the VPLs directly (narrower lobes would see
// each VPL as a spike).
constexpr float kGlossyVplRoughness = 0.3f;

// The prefiltering GGX lobe of ggx_zh.h, D_GGX(cos(θ/2); α = roughness²) max(cos θ, 0), at the
// cosine between a direction and the reflected view direction.
float glossy_lobe(float cos_theta, float alpha) {
    if (cos_theta <= 0.0f) return 0.0f;
    const float c2 = 0.5f * (1.0f + cos_theta);  // cos²(θ/2)
    const float a2 = alpha * alpha;
    const float d = c2 * (a2 - 1.0f) + 1.0f;
    return a2 / (kPi * d * d) * cos_theta;
}

// 1 / the lobe's integral over the hemisphere above the surface, for a lobe about an axis r
// (the clipped lobe's dominant direction) at cosine `cos_rn` from the normal: the VPLs below the horizon are culled
// (vpl_delta), so the lobe normalised there reads evenly lit upper hemisphere as itself, as the
// SH's closed form does (FieldLookup::horizon). Tabulated over roughness [kGlossyVplRoughness, 1]
// and cos_rn [0, 1] (midpoint rule in theta from r; the azimuths above the horizon at each theta
// in closed form: cos(theta) c + sin(theta) s cos(phi) > 0 for c = cos_rn, s = sin).
float glossy_lobe_norm(float roughness, float cos_rn) {
    constexpr int kRoughEntries = 64, kCosEntries = 32, kSteps = 2048;
    static const std::vector<float> table = [] {
        std::vector<float> t(size_t(kRoughEntries + 1) * (kCosEntries + 1));
        for (int i = 0; i <= kRoughEntries; ++i) {
            const float r = kGlossyVplRoughness + (1.0f - kGlossyVplRoughness) * float(i) /
                                                      float(kRoughEntries);
            for (int j = 0; j <= kCosEntries; ++j) {
                const double c = double(j) / kCosEntries, s = std::sqrt(1.0 - c * c);
                double sum = 0.0;
                for (int k = 0; k < kSteps; ++k) {
                    const double theta = (k + 0.5) * (0.5 * kPi) / kSteps;
                    const double sin_t = std::sin(theta), cos_t = std::cos(theta);
                    const double x = s * sin_t > 0.0 ? -cos_t * c / (s * sin_t)
                                     : cos_t * c > 0.0 ? -2.0 : 2.0;
                    const double azimuths = 2.0 * std::acos(std::clamp(x, -1.0, 1.0));
                    sum += glossy_lobe(float(cos_t), r * r) * sin_t * azimuths;
                }
                t[size_t(i) * (kCosEntries + 1) + size_t(j)] =
                    float(1.0 / (sum * (0.5 * kPi) / kSteps));
            }
        }
        return t;
    }();
    const float x = std::clamp((roughness - kGlossyVplRoughness) / (1.0f - kGlossyVplRoughness),
                               0.0f, 1.0f) * float(kRoughEntries);
    const float y = std::clamp(cos_rn, 0.0f, 1.0f) * float(kCosEntries);
    const int i = std::min(int(x), kRoughEntries - 1), j = std::min(int(y), kCosEntries - 1);
    const float fx = x - float(i), fy = y - float(j);
    const auto at = [&](int a, int b) { return table[size_t(a) * (kCosEntries + 1) + size_t(b)]; };
    return (1.0f - fy) * ((1.0f - fx) * at(i, j) + fx * at(i + 1, j)) +
           fy * ((1.0f - fx) * at(i, j + 1) + fx * at(i + 1, j + 1));
}

// The reach of the ray back along a photon's path that finds its surface (scattered_flux).
constexpr float kReach = 1e-3f;

// Pixel p's irradiance (>= 0) from the radiance SH `sh` about its shading normal, through its
// diffuse lobe's bump shadowing where a normal map bent the normal (render/bump_irradiance.h),
// as the path tracer weighs each light; elsewhere the plain cosine convolution, as before.
vec3 pixel_irradiance(const GBuffer& g, size_t p, const ShRgb& sh) {
    if (!g.has_field_lobes() || g.diffuse_bump[p].smooth_normal == vec3(0.0f))
        return glm::max(sh_irradiance(sh, g.shading_normal[p]), vec3(0.0f));
    return glm::max(sh_bump_irradiance(sh, g.shading_normal[p], g.diffuse_bump[p]), vec3(0.0f));
}

}  // namespace

void validate_instant_gi_settings(const InstantGiSettings& s) {
    check_int(s.sets_x, 1, 16, "sets_x");
    check_int(s.sets_y, 1, 16, "sets_y");
    if (s.photons_per_set == 0 || s.photons_per_set > (uint64_t(1) << 24))
        throw InvalidArgument(format_message(kSettings, ".photons_per_set is ", s.photons_per_set,
                                             "; it must be in [1, 2^24]"));
    check_int(s.vpl_bounces, 1, 16, "vpl_bounces");
    check_int(s.glossy_bounces, 0, kMaxGlossyBounces, "glossy_bounces");
    check_float(s.clamp_distance, 0.0f, 1e6f, "clamp_distance");
    const int filter = int(s.filter_mode);
    if (filter < 0 || filter > int(InstantGiFilter::None))
        throw InvalidArgument(format_message(kSettings, ".filter_mode is ", filter,
                                             "; it must be Sh, Irradiance, Strict or None"));
    check_float(s.depth_threshold, 0.0f, 1e6f, "depth_threshold");
    check_float(s.normal_threshold, -1.0f, 1.0f, "normal_threshold");
    check_int(s.passes_per_sample, 1, kMaxPassesPerSample, "passes_per_sample");
    check_float(s.near_field_reach, 0.0f, kMaxNearFieldReach, "near_field_reach");
    check_float(s.gather_near_radius, 0.0f, 1e6f, "gather_near_radius");
}

namespace {

// The delta's weight (zero when the VPL faces away or lies below the surface) and direction.
vec3 vpl_delta(const vec3& p, const vec3& ng, const InstantVpl& vpl, float scale,
               float clamp_distance, vec3* direction) {
    const vec3 d = vpl.position - p;
    const float dist2 = glm::dot(d, d);
    if (!(dist2 > 0.0f)) return vec3(0.0f);
    const vec3 w = d / std::sqrt(dist2);
    const float cos_vpl = -glm::dot(vpl.normal, w);
    if (cos_vpl <= 0.0f || glm::dot(ng, w) <= 0.0f) return vec3(0.0f);
    *direction = w;
    return vpl.power *
           (scale * cos_vpl * kInvPi / std::max(dist2, clamp_distance * clamp_distance));
}

// The shadow ray from `origin` (a surface point offset off it) to a VPL at `target`, stopping
// short of it; false when the two coincide.
bool shadow_ray(const vec3& origin, const vec3& target, Ray* ray) {
    const vec3 d = target - origin;
    const float dist = glm::length(d);
    if (!(dist > 0.0f)) return false;
    ray->origin = origin;
    ray->direction = d / dist;
    ray->tmax = dist * (1.0f - kShadowShorten);
    return true;
}

// A pixel's SH holds the light of the VPLs, lamp samples and sky directions above its surface
// (vpl_delta, lamp_delta and the sky's test cull the rest): zero below the horizon, as the photon
// lattice's cells, so glossy lobes read it about their dominant direction (FieldLookup::horizon;
// the Cornell box's glossy indirect light read 0.72 of the path tracer's without).
FieldLookup upper_hemisphere_lookup(ShRgb radiance) {
    FieldLookup lookup{std::move(radiance), vec3(0.0f)};
    lookup.horizon = true;
    return lookup;
}

void add_delta(vec3* sh, const vec3& e, const vec3& w) {
    float basis[kCoeffs];
    sh_eval(kOrder, w, basis);
    for (int i = 0; i < kCoeffs; ++i) sh[i] += e * basis[i];
}

}  // namespace

bool add_vpl_sh(ShRgb& sh, const vec3& p, const vec3& ng, const InstantVpl& vpl, float scale,
                float clamp_distance) {
    vec3 w;
    const vec3 e = vpl_delta(p, ng, vpl, scale, clamp_distance, &w);
    if (e == vec3(0.0f)) return false;
    add_delta(sh.coeffs.data(), e, w);
    return true;
}

// ---------------------------------------------------------------------------------------------
// InstantGiField

InstantGiField::InstantGiField(const Scene& scene, const InstantGiSettings& settings,
                               std::vector<std::vector<InstantVpl>> sets, uint64_t passes,
                               std::vector<std::vector<vec3>> sky_sets,
                               std::vector<std::vector<InstantLampSample>> lamp_sets,
                               std::shared_ptr<const LightSampler> lamps,
                               std::vector<std::vector<uint64_t>> pass_ends,
                               std::vector<std::vector<uint64_t>> lamp_pass_ends)
    : scene_(&scene), settings_(settings), sets_(std::move(sets)), sky_sets_(std::move(sky_sets)),
      lamp_sets_(std::move(lamp_sets)), pass_ends_(std::move(pass_ends)),
      lamp_pass_ends_(std::move(lamp_pass_ends)), lamps_(std::move(lamps)), passes_(passes),
      timings_(std::make_shared<InstantGiFrameTimings>()),
      lookup_counter_(std::make_shared<LookupCounter>()) {
    if (!pass_ends_.empty()) {
        if (pass_ends_.size() != sets_.size())
            throw Internal("InstantGiField: pass_ends and sets differ in count");
        for (size_t s = 0; s < sets_.size(); ++s)
            if (pass_ends_[s].size() != passes_ ||
                (passes_ > 0 && pass_ends_[s].back() != sets_[s].size()) ||
                !std::is_sorted(pass_ends_[s].begin(), pass_ends_[s].end()))
                throw Internal("InstantGiField: a set's pass_ends do not split its VPLs");
    }
    if (!sky_sets_.empty()) {
        if (sky_sets_.size() != sets_.size())
            throw Internal("InstantGiField: sky_sets and sets differ in count");
        for (const auto& set : sky_sets_)
            if (passes_ == 0 || set.size() % passes_ != 0)
                throw Internal("InstantGiField: a sky set's directions are not so many per pass");
    }
    if (!lamp_sets_.empty() && !pass_ends_.empty() && lamp_pass_ends_.empty())
        throw Internal("InstantGiField: lamp_sets and pass_ends without lamp_pass_ends");
    if (!lamp_pass_ends_.empty()) {
        if (pass_ends_.empty() || lamp_pass_ends_.size() != lamp_sets_.size())
            throw Internal("InstantGiField: lamp_pass_ends without pass_ends or lamp_sets");
        for (size_t s = 0; s < lamp_sets_.size(); ++s)
            if (lamp_pass_ends_[s].size() != passes_ ||
                lamp_pass_ends_[s].back() != lamp_sets_[s].size() ||
                !std::is_sorted(lamp_pass_ends_[s].begin(), lamp_pass_ends_[s].end()))
                throw Internal("InstantGiField: a set's lamp_pass_ends do not split its samples");
    }
    if (!lamp_sets_.empty()) {
        if (lamp_sets_.size() != sets_.size())
            throw Internal("InstantGiField: lamp_sets and sets differ in count");
        if (!lamps_) throw Internal("InstantGiField: lamp_sets without a LightSampler");
        // Every set holds as many samples of each light: count them in the first.
        std::vector<uint32_t> per_set(scene.lights().size(), 0);
        uint32_t triangles = 0;
        for (const InstantLampSample& sample : lamp_sets_[0]) {
            if (sample.light >= (sample.triangle ? scene.emissive_triangles().size()
                                                 : per_set.size()))
                throw Internal("InstantGiField: a lamp sample of a light the scene lacks");
            if (sample.triangle)
                ++triangles;
            else
                ++per_set[sample.light];
        }
        triangle_samples_ = triangles;
        lamp_samples_ = std::move(per_set);
    }
    for (const auto& set : sets_) vpl_count_ += set.size();
    for (const auto& set : sky_sets_) sky_count_ += set.size();
    for (const auto& set : lamp_sets_) lamp_count_ += set.size();
    set_scale_ = passes_ > 0 ? float(sets_.size()) / float(passes_) : 0.0f;
}

InstantGiFrameTimings InstantGiField::frame_timings() const { return *timings_; }

uint64_t InstantGiField::range_count(const std::vector<VplRange>& ranges) {
    uint64_t total = 0;
    for (const VplRange& range : ranges) total += range.end - range.begin;
    return total;
}

InstantGiLookupCounts InstantGiField::lookup_counts() const {
    return {lookup_counter_->lookups.load(std::memory_order_relaxed),
            lookup_counter_->vpls.load(std::memory_order_relaxed)};
}

std::vector<uint64_t> InstantGiField::sample_passes(uint64_t sample) const {
    const uint64_t k = uint64_t(settings_.passes_per_sample);
    std::vector<uint64_t> passes;
    if (pass_ends_.empty() || passes_ <= k) {
        for (uint64_t i = 0; i < passes_; ++i) passes.push_back(i);
        return passes;
    }
    // Sample i's k passes follow sample i - 1's, around the field's passes: over
    // passes / gcd(passes, k) samples every pass is gathered equally often.
    const uint64_t first = (sample % passes_) * k % passes_;
    for (uint64_t j = 0; j < k; ++j) passes.push_back((first + j) % passes_);
    return passes;
}

InstantGiField::SampleGather InstantGiField::sample_gather(uint64_t sample) const {
    const std::vector<uint64_t> passes = sample_passes(sample);
    SampleGather gather;
    gather.passes = passes.size();
    gather.vpl_scale = float(sets_.size()) / float(std::max<size_t>(passes.size(), 1));
    gather.vpls.resize(sets_.size());
    gather.sky.resize(sky_sets_.size());
    gather.lamps.resize(lamp_sets_.size());
    if (passes.size() == passes_) {  // every pass, in the sets' order
        for (size_t s = 0; s < sets_.size(); ++s) gather.vpls[s].push_back({0, sets_[s].size()});
        for (size_t s = 0; s < sky_sets_.size(); ++s)
            gather.sky[s].push_back({0, sky_sets_[s].size()});
        for (size_t s = 0; s < lamp_sets_.size(); ++s)
            gather.lamps[s].push_back({0, lamp_sets_[s].size()});
        return gather;
    }
    const bool first_pass = std::find(passes.begin(), passes.end(), 0) != passes.end();
    const auto range = [](const std::vector<uint64_t>& ends, uint64_t k) {
        return VplRange{k == 0 ? 0 : ends[k - 1], ends[k]};
    };
    for (size_t s = 0; s < sets_.size(); ++s) {
        // Every pass adds as many sky directions to a set.
        const uint64_t directions = sky_sets_.empty() ? 0 : sky_sets_[s].size() / passes_;
        for (const uint64_t k : passes) {
            gather.vpls[s].push_back(range(pass_ends_[s], k));
            if (!sky_sets_.empty()) gather.sky[s].push_back({k * directions, (k + 1) * directions});
            if (!lamp_sets_.empty()) gather.lamps[s].push_back(range(lamp_pass_ends_[s], k));
        }
        // The delta lights' samples, made at the first pass, in every sample.
        if (!lamp_sets_.empty() && !first_pass)
            gather.lamps[s].push_back({0, lamp_pass_ends_[s][0], true});
    }
    return gather;
}

vec3 InstantGiField::lamp_delta(const InstantLampSample& sample, const vec3& p, const vec3& ng,
                                float lamp_scale, uint64_t passes, vec3* direction,
                                float* distance) const {
    LightSample ls;
    // The sample's share of its light: 1 / that light's samples among the passes gathered
    // (as many in every pass; a delta light's one sample is always gathered).
    const auto share_of = [&](uint64_t samples) {
        return 1.0f / float(sample.delta ? samples : samples / passes_ * passes);
    };
    float share;
    if (sample.triangle) {
        if (!lamps_->sample_emissive_triangle(sample.light, p, sample.u, &ls)) return vec3(0.0f);
        share = share_of(triangle_samples_) / sample.selection;
    } else {
        if (!lamps_->light_emits(sample.light) ||
            !lamps_->sample_light(sample.light, p, sample.u, &ls))
            return vec3(0.0f);
        share = share_of(lamp_samples_[sample.light]);
    }
    if (!(ls.pdf > 0.0f) || glm::dot(ls.wi, ng) <= 0.0f) return vec3(0.0f);
    const vec3 e = ls.radiance * (lamp_scale * share / ls.pdf);
    if (!is_finite(e)) return vec3(0.0f);
    *direction = ls.wi;
    *distance = ls.distance;
    return e;
}

void InstantGiField::add_vpl(ShRgb& sh, const vec3& origin, const vec3& p, const vec3& n,
                             const InstantVpl& vpl, float vpl_scale) const {
    vec3 w;
    const vec3 e = vpl_delta(p, n, vpl, vpl_scale, settings_.clamp_distance, &w);
    Ray ray;
    if (e == vec3(0.0f) || !shadow_ray(origin, vpl.position, &ray) || scene_->occluded(ray))
        return;
    add_delta(sh.coeffs.data(), e, w);
}

void InstantGiField::gather_set(ShRgb& sh, const vec3& p, const vec3& n, size_t set,
                                const SampleGather* gather, float vpl_scale,
                                const vec3& sky_weight, float lamp_scale,
                                float near_radius2) const {
    const vec3 origin = offset_origin(p, n);
    uint64_t read = 0;
    // visit(i) for every index of `ranges` (every one of [0, size) when there are none) and,
    // within a deltas_only range, the delta lights' samples alone (`is_delta`).
    const auto each = [&read](const std::vector<VplRange>* ranges, uint64_t size,
                              const auto& is_delta, const auto& visit) {
        if (ranges == nullptr) {
            read += size;
            for (uint64_t i = 0; i < size; ++i) visit(i);
            return;
        }
        for (const VplRange& range : *ranges)
            for (uint64_t i = range.begin; i < range.end; ++i)
                if (!range.deltas_only || is_delta(i)) {
                    ++read;
                    visit(i);
                }
    };
    const auto no_delta = [](uint64_t) { return false; };
    const std::vector<InstantVpl>& vpls = sets_[set];
    each(gather ? &gather->vpls[set] : nullptr, vpls.size(), no_delta, [&](uint64_t i) {
        if (near_radius2 > 0.0f && distance2(p, vpls[i].position) < near_radius2) {
            --read;  // the caller's near VPLs, not read here
            return;
        }
        add_vpl(sh, origin, p, n, vpls[i], vpl_scale);
    });
    // filter_direct: the lights' direct light from the set's lamp samples.
    if (!lamp_sets_.empty()) {
        const std::vector<InstantLampSample>& lamps = lamp_sets_[set];
        const uint64_t passes = gather ? gather->passes : passes_;
        each(gather ? &gather->lamps[set] : nullptr, lamps.size(),
             [&](uint64_t i) { return lamps[i].delta; }, [&](uint64_t i) {
                 vec3 w;
                 float distance;
                 const vec3 e = lamp_delta(lamps[i], p, n, lamp_scale, passes, &w, &distance);
                 if (e == vec3(0.0f) ||
                     scene_->occluded(light_shadow_ray(origin, w, distance)))
                     return;
                 add_delta(sh.coeffs.data(), e, w);
             });
    }
    // filter_direct: the world's direct light from the set's directional VPLs.
    if (!sky_sets_.empty() && sky_weight != vec3(0.0f)) {
        const std::vector<vec3>& sky = sky_sets_[set];
        each(gather ? &gather->sky[set] : nullptr, sky.size(), no_delta, [&](uint64_t i) {
            const vec3& w = sky[i];
            if (glm::dot(w, n) <= 0.0f) return;
            Ray ray;
            ray.origin = origin;
            ray.direction = w;
            ray.tmax = kInfinity;
            if (scene_->occluded(ray)) return;
            add_delta(sh.coeffs.data(), sky_weight, w);
        });
    }
    lookup_counter_->vpls.fetch_add(read, std::memory_order_relaxed);
}

ShRgb InstantGiField::radiance_sh(const vec3& p, const vec3& n) const {
    ShRgb sh(kOrder);
    if (is_zero()) return sh;
    // Every set: the sum over sets of set_scale × set / sets = all VPLs / passes; the sky's
    // directions of every set share 4 pi.
    const vec3 sky = sky_count_ > 0
                         ? scene_->world().radiance() * (kFourPi / float(sky_count_))
                         : vec3(0.0f);
    const float lamp_scale = 1.0f / float(sets_.size());
    lookup_counter_->lookups.fetch_add(1, std::memory_order_relaxed);
    for (size_t s = 0; s < sets_.size(); ++s)
        gather_set(sh, p, n, s, nullptr, 1.0f / float(passes_), sky, lamp_scale);
    return sh;
}

// A preview sample's view (sample_view): lookups gather the sample's passes of every set.
class InstantGiField::SampleView : public IndirectField {
  public:
    SampleView(const InstantGiField& field, uint64_t sample)
        : field_(field), gather_(field.sample_gather(sample)) {
        // As radiance_sh, over the passes gathered: each VPL 1 / those passes, the sky's
        // directions gathered sharing 4 pi, each lamp sample 1 / (sets x its light's samples
        // among those passes).
        vpl_scale_ = 1.0f / float(std::max<uint64_t>(gather_.passes, 1));
        uint64_t directions = 0;
        for (const auto& ranges : gather_.sky) directions += range_count(ranges);
        if (directions > 0)
            sky_ = field.scene_->world().radiance() * (kFourPi / float(directions));
        lamp_scale_ = 1.0f / float(std::max<size_t>(field.sets_.size(), 1));
        // gather_near_radius: a grid over every set's VPLs of the sample's passes, so a gather
        // lookup finds the near ones in the cells around its hit.
        const float radius = field.settings_.gather_near_radius;
        if (radius > 0.0f && field.sets_.size() > 1) {
            std::vector<std::pair<uint32_t, uint32_t>> refs;
            std::vector<vec3> positions;
            for (size_t s = 0; s < field.sets_.size(); ++s)
                for (const VplRange& range : gather_.vpls[s])
                    for (uint64_t v = range.begin; v < range.end; ++v) {
                        refs.push_back({uint32_t(s), uint32_t(v)});
                        positions.push_back(field.sets_[s][v].position);
                    }
            near_grid_ = std::make_unique<NearVplGrid>(std::move(refs), positions, radius);
            near_radius2_ = radius * radius;
        }
    }

    ShRgb radiance_sh(const vec3& p, const vec3& n) const override {
        ShRgb sh(kOrder);
        if (field_.is_zero()) return sh;
        field_.lookup_counter_->lookups.fetch_add(1, std::memory_order_relaxed);
        for (size_t s = 0; s < field_.sets_.size(); ++s)
            field_.gather_set(sh, p, n, s, &gather_, vpl_scale_, sky_, lamp_scale_);
        return sh;
    }
    FieldLookup lookup(const vec3& p, const vec3& n) const override {
        return upper_hemisphere_lookup(radiance_sh(p, n));
    }
    // One set of the sample's passes, scaled by the sets (each VPL sets / passes gathered), its
    // sky directions gathered sharing 4 pi, each lamp sample whole among its light's in the set.
    FieldLookup gather_lookup(const vec3& p, const vec3& n, const vec3& wo,
                              float u) const override {
        static_cast<void>(wo);
        FieldLookup out = upper_hemisphere_lookup(ShRgb(kOrder));
        if (field_.is_zero()) return out;
        const size_t s = field_.gather_set_index(u);
        const uint64_t directions = gather_.sky.empty() ? 0 : range_count(gather_.sky[s]);
        const vec3 sky = directions > 0
                             ? field_.scene_->world().radiance() * (kFourPi / float(directions))
                             : vec3(0.0f);
        field_.lookup_counter_->lookups.fetch_add(1, std::memory_order_relaxed);
        // gather_near_radius: the set's VPLs beyond the radius, scaled by the sets, and every
        // set's within it, each as the whole view scales it (1 / the passes gathered).
        field_.gather_set(out.radiance, p, n, s, &gather_, gather_.vpl_scale, sky, 1.0f,
                          near_radius2_);
        if (near_grid_) {
            const vec3 origin = offset_origin(p, n);
            const vec3 reach(std::sqrt(near_radius2_));
            uint64_t near = 0;
            near_grid_->visit_box(p - reach, p + reach, [&](uint32_t set, uint32_t v) {
                const InstantVpl& vpl = field_.sets_[set][v];
                if (distance2(p, vpl.position) >= near_radius2_) return;
                ++near;
                field_.add_vpl(out.radiance, origin, p, n, vpl, vpl_scale_);
            });
            field_.lookup_counter_->vpls.fetch_add(near, std::memory_order_relaxed);
        }
        return out;
    }
    // The rest is the field's.
    float reuse_distance() const override { return field_.reuse_distance(); }
    bool includes_world_direct() const override { return field_.includes_world_direct(); }
    bool includes_lights_direct() const override { return field_.includes_lights_direct(); }
    std::shared_ptr<const IndirectField> without_direct() const override {
        return field_.without_direct();
    }
    bool is_zero() const override { return field_.is_zero(); }
    bool shades_first_surfaces() const override { return field_.shades_first_surfaces(); }
    void shade_first_surfaces(const GBuffer& g_buffer, const vec3& camera_position,
                              float clamp_indirect, Film& film, uint64_t first, uint64_t count,
                              Progress* progress) const override {
        field_.shade_first_surfaces(g_buffer, camera_position, clamp_indirect, film, first,
                                    count, progress);
    }
    Interleave interleave() const override { return field_.interleave(); }
    ShRgb set_radiance_sh(const vec3& p, const vec3& n, int set_x, int set_y) const override {
        return field_.set_radiance_sh(p, n, set_x, set_y);
    }

  private:
    const InstantGiField& field_;
    SampleGather gather_;
    float vpl_scale_ = 0.0f, lamp_scale_ = 0.0f;
    vec3 sky_{0.0f};
    std::unique_ptr<NearVplGrid> near_grid_;  // gather_near_radius's; null when off
    float near_radius2_ = 0.0f;
};

std::unique_ptr<const IndirectField> InstantGiField::sample_view(uint64_t sample) const {
    lookup_counter_->lookups.store(0, std::memory_order_relaxed);
    lookup_counter_->vpls.store(0, std::memory_order_relaxed);
    return std::make_unique<SampleView>(*this, sample);
}

std::shared_ptr<const IndirectField> InstantGiField::without_direct() const {
    if (!settings_.filter_direct) return nullptr;
    InstantGiSettings indirect = settings_;
    indirect.filter_direct = false;
    return std::make_shared<InstantGiField>(*scene_, indirect, sets_, passes_,
                                            std::vector<std::vector<vec3>>{},
                                            std::vector<std::vector<InstantLampSample>>{},
                                            nullptr, pass_ends_);
}

IndirectField::Interleave InstantGiField::interleave() const {
    Interleave pattern;
    pattern.sets_x = settings_.sets_x;
    pattern.sets_y = settings_.sets_y;
    pattern.normal_threshold = settings_.normal_threshold;
    pattern.filter = settings_.filter_mode != InstantGiFilter::None;
    return pattern;
}

ShRgb InstantGiField::set_radiance_sh(const vec3& p, const vec3& n, int set_x, int set_y) const {
    ShRgb sh(kOrder);
    if (is_zero()) return sh;
    if (set_x < 0 || set_x >= settings_.sets_x || set_y < 0 || set_y >= settings_.sets_y)
        throw InvalidArgument(format_message("InstantGiField.set_radiance_sh: set (", set_x, ", ",
                                             set_y, ") of ", settings_.sets_x, " x ",
                                             settings_.sets_y, " sets"));
    // One set alone, scaled as the frame-wide stage scales it: set_scale × the set's VPLs, its
    // sky directions sharing 4 pi.
    const size_t s = size_t(set_y) * size_t(settings_.sets_x) + size_t(set_x);
    const size_t directions = sky_sets_.empty() ? 0 : sky_sets_[s].size();
    const vec3 sky = directions > 0
                         ? scene_->world().radiance() * (kFourPi / float(directions))
                         : vec3(0.0f);
    lookup_counter_->lookups.fetch_add(1, std::memory_order_relaxed);
    gather_set(sh, p, n, s, nullptr, set_scale_, sky, 1.0f);
    return sh;
}

size_t InstantGiField::gather_set_index(float u) const {
    const float scaled = u > 0.0f ? u * float(sets_.size()) : 0.0f;  // NaN: the first set
    return std::min(size_t(scaled), sets_.size() - 1);
}

FieldLookup InstantGiField::gather_lookup(const vec3& p, const vec3& n, const vec3& wo,
                                          float u) const {
    static_cast<void>(wo);
    if (is_zero()) return upper_hemisphere_lookup(ShRgb(kOrder));
    const int s = int(gather_set_index(u));
    return upper_hemisphere_lookup(set_radiance_sh(p, n, s % settings_.sets_x, s / settings_.sets_x));
}

FieldLookup InstantGiField::lookup(const vec3& p, const vec3& n) const {
    return upper_hemisphere_lookup(radiance_sh(p, n));
}

void InstantGiField::shade_first_surfaces(const GBuffer& g, const vec3& camera_position,
                                          float clamp_indirect, Film& film, uint64_t first,
                                          uint64_t count, Progress* progress) const {
    *timings_ = InstantGiFrameTimings{};
    if (is_zero() || count == 0) return;
    const int width = g.width(), height = g.height();
    const size_t pixels = g.pixel_count();
    const int n = settings_.sets_x, m = settings_.sets_y;
    const bool sky = !sky_sets_.empty() && scene_->world().radiance() != vec3(0.0f);
    const bool lamps = !lamp_sets_.empty();
    const bool direct = sky || lamps;  // filter_direct's plane
    // near_field_reach: a plane more, the near fields'.
    const bool near_planes =
        settings_.near_field_reach > 0.0f && settings_.filter_mode != InstantGiFilter::None;
    require_memory(saturating_mul(uint64_t(pixels), uint64_t(((direct ? 4 : 2) + near_planes) *
                                                             kCoeffs * sizeof(vec3))),
                   format_message("the SH planes of ", width, " x ", height, " pixels"),
                   "lower the camera's resolution_x / resolution_y");
    // 1. gather: the pixel's set as L2 SH, visibility by exact shadow rays.
    TimePoint start = now();
    std::vector<vec3> raw(pixels * kCoeffs, vec3(0.0f));
    // filter_direct: the sky's and lights' direct light, a plane of its own (DiffDir /
    // GlossDir).
    std::vector<vec3> raw_direct(direct ? pixels * kCoeffs : 0, vec3(0.0f));
    // glossy_from_vpls: per pixel and lobe, the lobe's axis (the dominant direction of the GGX
    // lobe clipped at the horizon, as FieldLookup::glossy reads the SH), its GGX alpha and
    // 1 / its integral above the horizon (alpha 0: the lobe reads the SH); a plane per lobe.
    const bool lobes_from_vpls = settings_.glossy_from_vpls && g.has_field_lobes();
    std::vector<vec3> lobe_axes[2], raw_glossy[2];
    std::vector<vec2> glossy_lobes[2];  // (alpha, 1 / integral above the horizon)
    if (lobes_from_vpls) {
        for (int k = 0; k < 2; ++k) {
            lobe_axes[k].assign(pixels, vec3(0.0f));
            raw_glossy[k].assign(pixels, vec3(0.0f));
            glossy_lobes[k].assign(pixels, vec2(0.0f));
        }
        parallel_for(0, uint64_t(pixels), 4096, [&](uint64_t b, uint64_t e) {
            for (uint64_t p = b; p < e; ++p) {
                if (!g.has_surface(p)) continue;
                const vec3 normal = g.shading_normal[p];
                const vec3 wo = glm::normalize(camera_position - g.position[p]);
                const vec3 reflected = glm::reflect(-wo, normal);
                for (int k = 0; k < 2; ++k) {
                    const float r = g.glossy_roughness[k][p];
                    if (!(max_component(g.glossy_albedo[k][p]) > 0.0f && r >= kGlossyVplRoughness))
                        continue;
                    lobe_axes[k][p] = glossy_dominant_direction(normal, reflected, r);
                    glossy_lobes[k][p] =
                        vec2(r * r, glossy_lobe_norm(r, glm::dot(lobe_axes[k][p], normal)));
                }
            }
        });
    }
    const SampleGather gather = sample_gather(first);
    const float vpl_scale = gather.vpl_scale;
    size_t largest_set = 1;
    for (size_t s = 0; s < sets_.size(); ++s)
        largest_set = std::max(largest_set, size_t(range_count(gather.vpls[s]) +
                                                   (sky ? range_count(gather.sky[s]) : 0) +
                                                   (lamps ? range_count(gather.lamps[s]) : 0)));
    const uint64_t rows_per_task =
        std::max<uint64_t>(1, kRaysPerBatch / (uint64_t(std::max(width, 1)) * largest_set));
    // gather_cut_windows: the pixels whose filter window an edge cuts gather every set
    // themselves, each scaled by 1 / the sets, and skip the filter.
    const InstantGiFilter mode = settings_.filter_mode;
    const int half_x = Interleave::half_width(n), half_y = Interleave::half_width(m);
    const std::vector<uint8_t> cut =
        settings_.gather_cut_windows && mode != InstantGiFilter::None
            ? cut_window_pixels(g, settings_, half_x, half_y)
            : std::vector<uint8_t>{};
    const float all_sets = 1.0f / float(sets_.size());
    // near_field_reach: per pixel, the squared radius within which it gathers every set's
    // VPLs into a plane of their own that the filter leaves alone (0: none). The cut pixels of
    // gather_cut_windows split theirs too, so that the windows that read them read no near
    // field twice.
    const std::vector<float> near_radius2 =
        near_planes ? near_field_radii(g, settings_, half_x, half_y) : std::vector<float>{};
    const bool near = !near_radius2.empty();
    // The near radii after the cap (kNearCapReach), each written by the task gathering its row
    // before the row's far gather reads it.
    std::vector<float> near_cap2 = near_radius2;
    size_t near_cap = 0;
    std::unique_ptr<NearVplGrid> near_grid;
    if (near) {
        std::vector<float> radii;
        for (const float r2 : near_radius2)
            if (r2 > 0.0f) radii.push_back(std::sqrt(r2));
        std::nth_element(radii.begin(), radii.begin() + ptrdiff_t(radii.size() / 2), radii.end());
        std::vector<std::pair<uint32_t, uint32_t>> refs;
        std::vector<vec3> positions;
        for (size_t s = 0; s < sets_.size(); ++s)
            for (const VplRange& range : gather.vpls[s])
                for (uint64_t v = range.begin; v < range.end; ++v) {
                    refs.push_back({uint32_t(s), uint32_t(v)});
                    positions.push_back(sets_[s][v].position);
                }
        const size_t gathered = refs.size();
        near_grid = std::make_unique<NearVplGrid>(
            std::move(refs), positions, radii.empty() ? 0.0f : radii[radii.size() / 2]);
        const double share = double(settings_.near_field_reach / kNearCapReach);
        near_cap = size_t(std::min(share * share * double(gathered) / double(sets_.size()),
                                   double(gathered)));
    }
    // glossy_from_vpls: pixels with a lobe that reads the VPLs keep their near field's glossy
    // part whole: the VPLs the cap leaves to the far gather still reach those lobes from every
    // set (rays of their own), the lobe's light as without the cap; their SH stays capped.
    const auto glossy_whole = [&](size_t p) {
        return lobes_from_vpls && (glossy_lobes[0][p].x > 0.0f || glossy_lobes[1][p].x > 0.0f);
    };
    std::vector<vec3> raw_near(near ? pixels * kCoeffs : 0, vec3(0.0f));
    std::vector<vec3> raw_glossy_near[2];
    for (int k = 0; k < 2 && near; ++k)
        raw_glossy_near[k].assign(raw_glossy[k].size(), vec3(0.0f));
    // The plane a ray's light goes to: the indirect light to filter, filter_direct's, the near
    // field; glossy_whole's rays to a VPL the cap left out: its SH alone to the filter (far), its
    // glossy lobes' light alone to the near field.
    enum RayPlane : uint8_t { kIndirect, kDirect, kNear, kIndirectShOnly, kNearGlossyOnly };
    parallel_for(0, uint64_t(height), rows_per_task, [&](uint64_t y0, uint64_t y1) {
        throw_if_cancelled(progress);
        std::vector<Ray> rays;
        std::vector<uint32_t> ray_pixel;
        std::vector<vec3> weights, directions;
        std::vector<uint8_t> occluded, ray_plane;
        // A VPL's shadow ray from pixel p, its weight scaled by `scale`, into `plane`.
        const auto add_vpl_ray = [&](size_t p, const InstantVpl& vpl, float scale,
                                     RayPlane plane) {
            const vec3 pos = g.position[p], ng = g.geometric_normal[p];
            vec3 w;
            const vec3 e =
                vpl_delta(pos, ng, vpl, vpl_scale * scale, settings_.clamp_distance, &w);
            if (e == vec3(0.0f)) return;
            Ray ray;
            if (!shadow_ray(offset_origin(pos, ng), vpl.position, &ray)) return;
            rays.push_back(ray);
            ray_pixel.push_back(uint32_t(p));
            weights.push_back(e);
            directions.push_back(w);
            ray_plane.push_back(plane);
        };
        // near_field_reach: the near fields of row y's pixels x0 .. x0 + kNearRun - 1: every
        // set's VPLs (of the passes gathered) inside the box around those pixels grown by
        // their largest near radius, then those within each pixel's own radius, the nearest
        // near_cap of them where more lie there (near_cap2). Where the cap likely binds, the box
        // is grown by a quarter, then half of the radii first: a pixel with more than near_cap VPLs
        // within that share of its radius has its nearest ones there, and the rest of the box
        // is not read (a pixel keeps its VPLs' order: the boxes' cells are read in one order).
        // glossy_whole's pixels read the whole radius.
        std::vector<std::pair<uint32_t, uint32_t>> near_vpls;  // (set, VPL)
        // Per pixel of the run: (squared distance, index into near_vpls) of the VPLs within its
        // trial radius, and that radius squared (-1: none).
        std::vector<std::pair<float, uint32_t>> within[kNearRun];
        float trial2[kNearRun];
        std::vector<float> nearest;  // a pixel's squared distances, for the cap
        const auto gather_near_fields = [&](int y, int x0) {
            const int x1 = std::min(width, x0 + kNearRun);
            uint32_t open = 0;  // bit x - x0: the pixel's near field is still to gather
            vec3 lo(kInfinity), hi(-kInfinity);
            float radius2 = 0.0f;
            for (int x = x0; x < x1; ++x) {
                const size_t p = g.index(x, y);
                if (near_radius2[p] <= 0.0f) continue;
                open |= 1u << (x - x0);
                lo = glm::min(lo, g.position[p]), hi = glm::max(hi, g.position[p]);
                radius2 = std::max(radius2, near_radius2[p]);
            }
            if (open == 0) return;
            // No pixel of the run holds more VPLs than the cells around it: where they hold
            // few, the cap binds at most near the whole radius, read at once.
            const vec3 reach(std::sqrt(radius2));
            const bool trials =
                near_grid->count_box(lo - reach, hi + reach) > kNearTrialExcess * near_cap;
            for (const float fraction : {0.25f, 0.5f, 1.0f}) {
                if (open == 0) break;
                if (fraction < 1.0f && !trials) continue;
                const float fraction2 = fraction * fraction;
                vec3 box_lo(kInfinity), box_hi(-kInfinity);
                float largest2 = 0.0f;
                for (int x = x0; x < x1; ++x) {
                    if (!(open >> (x - x0) & 1u)) continue;
                    const size_t p = g.index(x, y);
                    box_lo = glm::min(box_lo, g.position[p]);
                    box_hi = glm::max(box_hi, g.position[p]);
                    largest2 = std::max(largest2, fraction2 * near_radius2[p]);
                }
                box_lo -= vec3(std::sqrt(largest2)), box_hi += vec3(std::sqrt(largest2));
                near_vpls.clear();
                near_grid->visit_box(box_lo, box_hi, [&](uint32_t s, uint32_t v) {
                    const vec3& q = sets_[s][v].position;
                    if (glm::all(glm::greaterThanEqual(q, box_lo)) &&
                        glm::all(glm::lessThanEqual(q, box_hi)))
                        near_vpls.push_back({s, v});
                });
                // Per pixel, the VPLs within its trial radius in near_vpls' order (VPL by VPL, a
                // run of pixels at a time, as a distance test per VPL and pixel) and their
                // squared distances.
                for (int x = x0; x < x1; ++x) {
                    within[size_t(x - x0)].clear();
                    trial2[size_t(x - x0)] =
                        open >> (x - x0) & 1u ? fraction2 * near_radius2[g.index(x, y)] : -1.0f;
                }
                for (uint32_t i = 0; i < uint32_t(near_vpls.size()); ++i) {
                    const vec3& q = sets_[near_vpls[i].first][near_vpls[i].second].position;
                    for (int x = x0; x < x1; ++x) {
                        const float d2 = distance2(g.position[g.index(x, y)], q);
                        if (d2 < trial2[size_t(x - x0)]) within[size_t(x - x0)].push_back({d2, i});
                    }
                }
                uint32_t settled = 0;
                for (int x = x0; x < x1; ++x) {
                    if (!(open >> (x - x0) & 1u)) continue;
                    const size_t p = g.index(x, y);
                    const auto& mine = within[size_t(x - x0)];
                    if (fraction < 1.0f && (mine.size() <= near_cap || glossy_whole(p)))
                        continue;  // look further
                    settled |= 1u << (x - x0);
                    if (mine.size() > near_cap) {  // the (near_cap + 1)-th nearest's distance
                        nearest.clear();
                        for (const auto& [d2, i] : mine) nearest.push_back(d2);
                        std::nth_element(nearest.begin(), nearest.begin() + ptrdiff_t(near_cap),
                                         nearest.end());
                        near_cap2[p] = nearest[near_cap];
                    }
                    for (const auto& [d2, i] : mine) {
                        const InstantVpl& vpl = sets_[near_vpls[i].first][near_vpls[i].second];
                        if (d2 < near_cap2[p])
                            add_vpl_ray(p, vpl, all_sets, kNear);
                        else if (glossy_whole(p))
                            add_vpl_ray(p, vpl, all_sets, kNearGlossyOnly);
                    }
                }
                open &= ~settled;
            }
        };
        // The row's pixels that gather set s, each with its scale: the set's own pixels
        // (x = sx mod n in a row of the set's row phase) at 1, the cut ones at 1 / the sets.
        std::vector<std::pair<int, float>> row_pixels;
        std::vector<int> cut_pixels;
        // Rays set by set, VPL by VPL, pixel by pixel along the row: the pixels of one set
        // sending rays to one VPL after another are neighbours, a coherent stream.
        for (uint64_t y = y0; y < y1; ++y) {
            // The row's near fields first, a run of pixels at a time: they settle the capped
            // radii the far gather reads (each plane sums its rays in the same order as before).
            for (int x0 = 0; x0 < width && near; x0 += kNearRun) gather_near_fields(int(y), x0);
            cut_pixels.clear();
            if (!cut.empty())
                for (int x = 0; x < width; ++x)
                    if (cut[g.index(x, int(y))]) cut_pixels.push_back(x);
            // The row's own sets first (sx = 0 .. n - 1), then, for its cut pixels, the others.
            const size_t row_sets = size_t(int(y) % m) * size_t(n);
            for (size_t k = 0; k < sets_.size(); ++k) {
                const size_t s = (row_sets + k) % sets_.size();
                const int sx = k < size_t(n) ? int(s % size_t(n)) : -1;  // -1: not the row's
                if (sx >= width) continue;
                row_pixels.clear();
                if (sx >= 0)
                    for (int x = sx; x < width; x += n)
                        if (cut.empty() || !cut[g.index(x, int(y))])
                            row_pixels.push_back({x, 1.0f});
                for (const int x : cut_pixels) row_pixels.push_back({x, all_sets});
                if (row_pixels.empty()) continue;
                for (const VplRange& range : gather.vpls[s])
                    for (uint64_t v = range.begin; v < range.end; ++v) {
                        const InstantVpl& vpl = sets_[s][v];
                        for (const auto& [x, scale] : row_pixels) {
                            const size_t p = g.index(x, int(y));
                            if (!g.has_surface(p)) continue;
                            // In the pixel's near field: gathered from every set above.
                            RayPlane plane = kIndirect;
                            if (near) {
                                const float d2 = distance2(g.position[p], vpl.position);
                                if (d2 < near_cap2[p]) continue;
                                if (d2 < near_radius2[p] && glossy_whole(p))
                                    plane = kIndirectShOnly;
                            }
                            add_vpl_ray(p, vpl, scale, plane);
                        }
                    }
                // The set's lamp samples: each light's incident radiance / pdf along its
                // sample, to the sampled point.
                if (lamps)
                    for (const VplRange& range : gather.lamps[s])
                        for (uint64_t i = range.begin; i < range.end; ++i) {
                            const InstantLampSample& sample = lamp_sets_[s][i];
                            if (range.deltas_only && !sample.delta) continue;
                            for (const auto& [x, scale] : row_pixels) {
                                const size_t p = g.index(x, int(y));
                                if (!g.has_surface(p)) continue;
                                const vec3 pos = g.position[p], ng = g.geometric_normal[p];
                                vec3 w;
                                float distance;
                                const vec3 e = lamp_delta(sample, pos, ng, scale, gather.passes,
                                                          &w, &distance);
                                if (e == vec3(0.0f)) continue;
                                rays.push_back(
                                    light_shadow_ray(offset_origin(pos, ng), w, distance));
                                ray_pixel.push_back(uint32_t(p));
                                weights.push_back(e);
                                directions.push_back(w);
                                ray_plane.push_back(kDirect);
                            }
                        }
                if (!sky) continue;
                // The set's directional VPLs: the world seen along each, to infinity.
                const uint64_t sky_directions = range_count(gather.sky[s]);
                if (sky_directions == 0) continue;
                const vec3 e = scene_->world().radiance() * (kFourPi / float(sky_directions));
                for (const VplRange& range : gather.sky[s])
                    for (uint64_t i = range.begin; i < range.end; ++i) {
                        const vec3 w = sky_sets_[s][i];
                        for (const auto& [x, scale] : row_pixels) {
                            const size_t p = g.index(x, int(y));
                            if (!g.has_surface(p)) continue;
                            const vec3 ng = g.geometric_normal[p];
                            if (glm::dot(w, ng) <= 0.0f) continue;
                            Ray ray;
                            ray.origin = offset_origin(g.position[p], ng);
                            ray.direction = w;
                            ray.tmax = kInfinity;
                            rays.push_back(ray);
                            ray_pixel.push_back(uint32_t(p));
                            weights.push_back(e * scale);
                            directions.push_back(w);
                            ray_plane.push_back(kDirect);
                        }
                    }
            }
        }
        if (rays.empty()) return;
        scene_->occluded(rays, occluded, nullptr, RayCoherence::Coherent);
        for (size_t r = 0; r < rays.size(); ++r) {  // in ray order: a fixed sum per pixel
            if (occluded[r]) continue;
            const RayPlane kind = RayPlane(ray_plane[r]);
            const bool near_plane = kind == kNear || kind == kNearGlossyOnly;
            const size_t p = ray_pixel[r];
            if (kind != kNearGlossyOnly) {
                std::vector<vec3>& plane =
                    kind == kNear ? raw_near : kind == kDirect ? raw_direct : raw;
                add_delta(&plane[p * kCoeffs], weights[r], directions[r]);
            }
            if (!lobes_from_vpls || kind == kDirect || kind == kIndirectShOnly) continue;
            for (int k = 0; k < 2; ++k) {
                const vec2 lobe = glossy_lobes[k][p];
                std::vector<vec3>& glossy = near_plane ? raw_glossy_near[k] : raw_glossy[k];
                if (lobe.x > 0.0f)
                    glossy[p] += weights[r] * (glossy_lobe(glm::dot(directions[r], lobe_axes[k][p]),
                                                           lobe.x) *
                                               lobe.y);
            }
        }
    }, progress);
    timings_->gather = seconds_since(start);

    // 2. filter.
    start = now();
    const bool filter_sh = mode == InstantGiFilter::Sh;
    const bool filter_irradiance =
        mode == InstantGiFilter::Irradiance || mode == InstantGiFilter::Strict;
    // The interleave-wide window over `source` (stride vec3 per pixel) into `out_plane`.
    const auto filter_window = [&](const std::vector<vec3>& source, int stride, bool strict,
                                   std::vector<vec3>& out_plane) {
        out_plane.assign(pixels * size_t(stride), vec3(0.0f));
        parallel_for(0, uint64_t(height), 8, [&](uint64_t y0, uint64_t y1) {
            throw_if_cancelled(progress);
            for (uint64_t y = y0; y < y1; ++y)
                for (int x = 0; x < width; ++x) {
                    const size_t p = g.index(x, int(y));
                    if (!g.has_surface(p)) continue;
                    vec3* out = &out_plane[p * size_t(stride)];
                    if (!cut.empty() && cut[p]) {  // gathered every set: kept as it is
                        std::copy_n(&source[p * size_t(stride)], stride, out);
                        continue;
                    }
                    float total = 0.0f;
                    visit_window(g, x, int(y), half_x, half_y, settings_, strict,
                                 [&](size_t q, int dx, int dy) {
                                     const float w = Interleave::tap_weight(n, dx) *
                                                     Interleave::tap_weight(m, dy);
                                     const vec3* in = &source[q * size_t(stride)];
                                     for (int i = 0; i < stride; ++i) out[i] += w * in[i];
                                     total += w;
                                 });
                    for (int i = 0; i < stride; ++i) out[i] /= total;
                }
        }, progress);
    };
    // One plane (indirect, or filter_direct's sky) through the filter: SH (mode Sh) or E
    // (Irradiance, Strict) into `out_plane`.
    const auto filter_plane = [&](const std::vector<vec3>& plane, std::vector<vec3>& out_plane) {
        std::vector<vec3> irradiance;
        if (filter_irradiance) {
            irradiance.assign(pixels, vec3(0.0f));
            parallel_for(0, uint64_t(pixels), 4096, [&](uint64_t b, uint64_t e) {
                for (uint64_t p = b; p < e; ++p) {
                    if (!g.has_surface(p)) continue;
                    ShRgb sh(kOrder);
                    std::copy_n(&plane[p * kCoeffs], kCoeffs, sh.coeffs.begin());
                    irradiance[p] = pixel_irradiance(g, p, sh);
                }
            });
        }
        if (filter_sh || filter_irradiance)
            filter_window(filter_sh ? plane : irradiance, filter_sh ? kCoeffs : 1,
                          mode == InstantGiFilter::Strict, out_plane);
    };
    std::vector<vec3> filtered, filtered_direct;
    filter_plane(raw, filtered);
    // near_field_reach: the near fields join the filtered light (SH), or the filtered
    // irradiance and the pixel's own SH its glossy lobes read (Irradiance, Strict).
    if (near) {
        std::vector<vec3>& sh = filter_sh ? filtered : raw;
        for (size_t i = 0; i < raw_near.size(); ++i) sh[i] += raw_near[i];
        if (filter_irradiance)
            parallel_for(0, uint64_t(pixels), 4096, [&](uint64_t b, uint64_t e) {
                for (uint64_t p = b; p < e; ++p) {
                    if (!g.has_surface(p)) continue;
                    ShRgb near_sh(kOrder);
                    std::copy_n(&raw_near[p * kCoeffs], kCoeffs, near_sh.coeffs.begin());
                    filtered[p] += pixel_irradiance(g, p, near_sh);
                }
            });
    }
    if (direct) filter_plane(raw_direct, filtered_direct);
    // glossy_from_vpls: each lobe's plane through the window too (unless filter_mode None).
    std::vector<vec3> filtered_glossy[2];
    for (int k = 0; k < 2; ++k)
        if (!raw_glossy[k].empty()) {
            if (mode == InstantGiFilter::None)
                filtered_glossy[k] = raw_glossy[k];
            else
                filter_window(raw_glossy[k], 1, mode == InstantGiFilter::Strict,
                              filtered_glossy[k]);
            for (size_t p = 0; p < raw_glossy_near[k].size(); ++p)
                filtered_glossy[k][p] += raw_glossy_near[k][p];
        }
    timings_->filter = seconds_since(start);

    // 3. shade: SH dot products with the pixel's shading normal, into the film.
    start = now();
    const std::vector<vec3>& sh_source = filter_sh ? filtered : raw;
    const std::vector<vec3>& sh_direct = filter_sh ? filtered_direct : raw_direct;
    const float samples = float(count);
    const bool lobes = g.has_field_lobes();
    parallel_for(0, uint64_t(height), 16, [&](uint64_t y0, uint64_t y1) {
        for (uint64_t y = y0; y < y1; ++y)
            for (int x = 0; x < width; ++x) {
                const size_t p = g.index(x, int(y));
                if (!g.has_surface(p) || !lobes) continue;
                const vec3 ns = g.shading_normal[p];
                const vec3 wo = glm::normalize(camera_position - g.position[p]);
                // Whether lobe k of the indirect plane reads the VPLs directly.
                const auto direct_lobe = [&](int k, bool indirect) {
                    return indirect && lobes_from_vpls && glossy_lobes[k][p].x > 0.0f;
                };
                // The pixel's diffuse and glossy light from one plane's SH (or filtered E).
                const auto shade = [&](const std::vector<vec3>& sh,
                                       const std::vector<vec3>& e_plane, vec3& diffuse,
                                       vec3& glossy) {
                    FieldLookup lookup = upper_hemisphere_lookup(ShRgb(kOrder));
                    std::copy_n(&sh[p * kCoeffs], kCoeffs, lookup.radiance.coeffs.begin());
                    const DiffuseBump& bump = g.diffuse_bump[p];
                    const vec3 e = filter_irradiance ? e_plane[p]
                                   : bump.smooth_normal == vec3(0.0f)
                                       ? lookup.irradiance(ns)
                                       : lookup.irradiance(ns, bump);
                    diffuse = g.field_diffuse[p] * e * kInvPi;
                    glossy = vec3(0.0f);
                    for (int k = 0; k < 2; ++k)
                        if (max_component(g.glossy_albedo[k][p]) > 0.0f)
                            glossy += g.glossy_albedo[k][p] *
                                      (direct_lobe(k, &sh == &sh_source)
                                           ? filtered_glossy[k][p]
                                           : lookup.glossy(ns, wo, g.glossy_roughness[k][p]));
                };
                vec3 diffuse, glossy;
                shade(sh_source, filtered, diffuse, glossy);
                // Light Paths > Clamp, per lobe class and sample, as PathIntegrator::add_light.
                diffuse = clamp_contribution(diffuse, clamp_indirect);
                glossy = clamp_contribution(glossy, clamp_indirect);
                vec3 diffuse_direct(0.0f), glossy_direct(0.0f);
                if (direct) shade(sh_direct, filtered_direct, diffuse_direct, glossy_direct);
                if (!is_finite(diffuse) || !is_finite(glossy) || !is_finite(diffuse_direct) ||
                    !is_finite(glossy_direct))
                    continue;
                PassValues values;
                values[Pass::DiffInd] = diffuse * samples;
                values[Pass::GlossInd] = glossy * samples;
                values[Pass::Combined] =
                    (diffuse + glossy + diffuse_direct + glossy_direct) * samples;
                if (direct) {
                    values[Pass::DiffDir] = diffuse_direct * samples;
                    values[Pass::GlossDir] = glossy_direct * samples;
                }
                film.add(x, int(y), values);
            }
    });
    timings_->shade = seconds_since(start);
}

// ---------------------------------------------------------------------------------------------
// InstantGi

InstantGi::InstantGi(const Scene& scene, const InstantGiSettings& settings, Progress* progress)
    : scene_(&scene), settings_(settings) {
    validate_instant_gi_settings(settings_);
    reset(progress);
}

void InstantGi::check_scene(const char* what) const {
    if (!scene_->committed() || scene_->revision() != scene_revision_)
        throw InvalidArgument(format_message("InstantGi.", what,
                                             ": the scene was edited since the solver was made; "
                                             "commit() it and call reset() first"));
}

void InstantGi::reset(Progress* progress) {
    if (!scene_->committed())
        throw InvalidArgument("InstantGi: the scene is not committed; call commit() first");
    scene_revision_ = scene_->revision();
    passes_ = 0;
    stage_seconds_.clear();
    lamps_ = settings_.filter_direct ? std::make_shared<const LightSampler>(
                                           *scene_, WorldSampling::Cosine, false, 1, false)
                                     : nullptr;
    triangle_power_ = DiscreteDistribution();
    if (settings_.filter_direct && !scene_->emissive_triangles().empty()) {
        std::vector<float> power;  // W / pi: area x luminance, two-sided
        for (const EmissiveTriangle& tri : scene_->emissive_triangles())
            power.push_back(std::max(0.0f, tri.area * luminance(tri.radiance)));
        triangle_power_ = DiscreteDistribution(power);
    }
    field_ = std::make_shared<InstantGiField>(
        *scene_, settings_,
        std::vector<std::vector<InstantVpl>>(size_t(settings_.sets_x) * size_t(settings_.sets_y)),
        0);
    if (progress) progress->set_fraction(1.0f);
}

void InstantGi::refine(Progress* progress) {
    check_scene("refine");
    TimePoint start = now();
    if (progress) progress->begin_stage("tracing VPLs", 0.0f, 0.8f);
    PhotonMaps maps = trace_photons(*scene_, tracer_settings(settings_), passes_, progress,
                                    kSettings);
    // Every hit as a photon: first hits, then (vpl_bounces > 1) the stored later hits.
    const std::vector<Photon> hits = vpl_hits(maps, settings_.vpl_bounces > 1);
    const double trace_seconds = seconds_since(start);
    start = now();
    if (progress) progress->begin_stage("reflecting VPLs", 0.8f, 1.0f);
    std::vector<vec3> reflected(hits.size(), vec3(0.0f));
    const bool glossy = settings_.glossy_vpls;
    parallel_for(0, hits.size(), kVplsPerTask, [&](uint64_t begin, uint64_t end) {
        throw_if_cancelled(progress);
        for (uint64_t i = begin; i < end; ++i) {
            const Photon& h = hits[i];
            reflected[i] = scattered_flux(*scene_, h.position, h.normal, h.direction, h.power,
                                         kReach, glossy ? kSpecularRoughness : -1.0f);
        }
    }, progress);
    std::vector<InstantVpl> vpls;
    vpls.reserve(hits.size());
    for (size_t i = 0; i < hits.size(); ++i)
        if (reflected[i] != vec3(0.0f) && is_finite(reflected[i]))
            vpls.push_back({hits[i].position, hits[i].normal, reflected[i]});
    throw_if_cancelled(progress);
    // Deal the pass's VPLs into the sets in turn, after the earlier passes' ones.
    std::vector<std::vector<InstantVpl>> sets = field_->sets();
    const size_t set_count = sets.size();
    for (size_t i = 0; i < vpls.size(); ++i) sets[i % set_count].push_back(vpls[i]);
    std::vector<std::vector<uint64_t>> pass_ends = field_->pass_ends();
    pass_ends.resize(set_count);
    for (size_t s = 0; s < set_count; ++s) pass_ends[s].push_back(uint64_t(sets[s].size()));
    // filter_direct: photons_per_set directional VPLs for the world per set and pass, uniform
    // over the sphere (one random stream per pass and set: the same for any thread count).
    std::vector<std::vector<vec3>> sky_sets;
    if (settings_.filter_direct) {
        sky_sets = field_->sky_sets();
        sky_sets.resize(set_count);
        for (size_t s = 0; s < set_count; ++s) {
            Pcg32 rng(settings_.seed ^ 0x5b1d5ca7e5u, passes_ * set_count + s);
            for (uint64_t k = 0; k < settings_.photons_per_set; ++k)
                sky_sets[s].push_back(sample_uniform_sphere(rng.next_vec2()));
        }
    }
    // filter_direct: samples of each emitting light per set, one for a delta light (at the
    // first pass), photons_per_set more per pass for a light with extent (one random stream per
    // pass and set).
    std::vector<std::vector<InstantLampSample>> lamp_sets;
    if (settings_.filter_direct) {
        lamp_sets = field_->lamp_sets();
        lamp_sets.resize(set_count);
        for (size_t s = 0; s < set_count; ++s) {
            Pcg32 rng(settings_.seed ^ 0x1a3b5c7d9e2fu, passes_ * set_count + s);
            for (uint32_t i = 0; i < scene_->lights().size(); ++i) {
                if (!lamps_->light_emits(i)) continue;
                const Light& light = scene_->lights()[i];
                const bool delta = light.type == LightType::Sun
                                       ? light.angle <= 0.0f
                                       : light.type != LightType::Area && light.radius <= 0.0f;
                const uint64_t count = delta ? (passes_ == 0 ? 1 : 0) : settings_.photons_per_set;
                for (uint64_t k = 0; k < count; ++k)
                    lamp_sets[s].push_back({i, rng.next_vec2(), false, 1.0f, delta});
            }
            // The emissive triangles: photons_per_set samples, each triangle by its power.
            if (triangle_power_.empty()) continue;
            for (uint64_t k = 0; k < settings_.photons_per_set; ++k) {
                const uint32_t t = triangle_power_.sample(rng.next_float());
                lamp_sets[s].push_back({t, rng.next_vec2(), true, triangle_power_.pdf(t)});
            }
        }
        if (std::all_of(lamp_sets.begin(), lamp_sets.end(),
                        [](const auto& set) { return set.empty(); }))
            lamp_sets.clear();
    }
    // The end of the pass's lamp samples in each set: a preview sample gathers its passes'.
    std::vector<std::vector<uint64_t>> lamp_pass_ends;
    if (!lamp_sets.empty()) {
        lamp_pass_ends = field_->lamp_pass_ends();
        lamp_pass_ends.resize(set_count);
        for (size_t s = 0; s < set_count; ++s)
            lamp_pass_ends[s].push_back(uint64_t(lamp_sets[s].size()));
    }
    const double deal_seconds = seconds_since(start);
    field_ = std::make_shared<InstantGiField>(*scene_, settings_, std::move(sets), passes_ + 1,
                                              std::move(sky_sets), std::move(lamp_sets), lamps_,
                                              std::move(pass_ends), std::move(lamp_pass_ends));
    ++passes_;
    stage_seconds_ = {{"vpl_trace", trace_seconds}, {"vpl_sets", deal_seconds}};
    if (progress) progress->set_fraction(1.0f);
}

size_t InstantGi::memory_bytes() const {
    return size_t(field_->vpl_count()) * sizeof(InstantVpl) +
           size_t(field_->sets().size() + field_->lamp_pass_ends().size()) *
               size_t(field_->passes()) * sizeof(uint64_t) +
           size_t(field_->sky_count()) * sizeof(vec3) +
           size_t(field_->lamp_count()) * sizeof(InstantLampSample);
}

}  // namespace shgi
