#include "probes/probe_grid.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_map>

#include <glm/gtc/matrix_transform.hpp>

#include "probes/probe_visibility.h"
#include "render/light_sampler.h"
#include "render/path_integrator.h"
#include "scene/ray.h"
#include "sh/sh_projection.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/parallel.h"
#include "util/rng.h"
#include "util/sampling.h"
#include "util/timer.h"

namespace shgi {
namespace {

// Bytes one probe's state takes in a ProbeGridData (the memory cap and memory_bytes()).
size_t probe_bytes(int visibility_resolution) {
    return sizeof(vec3) + sizeof(uint8_t) + sizeof(ShRgb) + sizeof(float) +
           size_t(visibility_resolution) * size_t(visibility_resolution) * sizeof(vec2);
}
// The memory the probe cap allows at the default visibility maps: a finer map costs probes.
const size_t kMaxProbeBytes = kMaxProbes * probe_bytes(ProbeGridSettings{}.visibility_resolution);
// Relocation: a probe this close (spacings) to a front face steps away from it.
constexpr float kMinFrontDistance = 0.1f;
constexpr int kRelocationSteps = 3;
// Probes are grouped this many per task; each probe traces rays_per_probe paths.
constexpr uint64_t kProbesPerTask = 2;
// A probe's paths between cancel polls within its update: at 2^16 rays a probe, the poll per
// task alone let a cancel wait ~0.3 s.
constexpr uint32_t kRaysPerCancelPoll = 1024;
// Seeds the per-probe rotations apart from the per-ray path streams (same stream ids).
constexpr uint64_t kRotationSeed = 0x9e3779b97f4a7c15ull;

// A fitted volume's axis along which the scene is thinner than this fraction of its longest side
// is flat (see fitted_volume).
constexpr float kFlatFraction = 0.01f;

ProbeVolume fitted_volume(const Scene& scene, float spacing) {
    const Bounds3 bounds = scene.bounds();
    vec3 extent = bounds.extent();
    const float longest = std::max(extent.x, std::max(extent.y, extent.z));
    const float step = spacing > 0.0f ? spacing : longest / 8.0f;
    ProbeVolume volume;
    for (int a = 0; a < 3; ++a) {
        const double count = std::ceil(double(extent[a]) / double(step) - 1e-3);
        if (count > double(kMaxProbesPerAxis))
            throw InvalidArgument(format_message(
                "ProbeGridSettings.spacing ", step, " m puts ", count, " probes along axis ", a,
                " of the scene (", extent[a], " m); use a spacing of at least ",
                extent[a] / float(kMaxProbesPerAxis), " m"));
        // A flat scene (thinner than kFlatFraction of its longest side along this axis) gets a
        // layer of probes on each side of it: one layer in its middle lay on its surfaces, and
        // relocation stepped it off them to one side or the other, so the far side read the
        // light of the near side through the surface (a ground plane under a sky came out 50%
        // too bright). Visibility keeps each side to its own probes.
        const bool flat = count <= 1.0 && extent[a] < kFlatFraction * longest;
        volume.resolution[a] = flat ? 2 : std::max(1, int(count));
        extent[a] = std::max(extent[a], longest > 0.0f ? std::min(step, longest) : step);
    }
    const vec3 centre = 0.5f * (bounds.lower + bounds.upper);
    volume.world_from_volume = glm::translate(mat4(1.0f), centre) *
                               glm::scale(mat4(1.0f), 0.5f * extent);
    return volume;
}

// The probe paths' limits: the renderer's own surface is the first bounce (Cycles' defaults).
PathTracerSettings probe_path_settings(const ProbeGridSettings& settings) {
    PathTracerSettings path;
    path.max_bounces -= 1;
    path.transmission_bounces -= 1;
    path.diffuse_bounces = settings.bounces;
    path.glossy_bounces = settings.bounces;
    path.russian_roulette_depth -= 1;
    path.roulette_survival = RouletteSurvival::Throughput;  // min(1, T), as before
    return path;
}

float max_scene_distance(const Scene& scene, const std::vector<vec3>& positions) {
    Bounds3 bounds = scene.bounds();
    for (const vec3& p : positions) bounds.extend(p);
    return 2.0f * glm::length(bounds.extent()) + 1e-3f;
}

// What placement_rays rays from p meet: the share of back-face hits and the nearest back and
// front faces.
struct Surroundings {
    float backface_fraction = 0.0f;
    float back_t = kInfinity, front_t = kInfinity;
    vec3 back_dir{0.0f}, front_dir{0.0f};
};

Surroundings look_around(const Scene& scene, const std::vector<uint8_t>& closed_instance,
                         const vec3& p, uint32_t rays) {
    Surroundings s;
    uint32_t backfaces = 0;
    for (uint32_t r = 0; r < rays; ++r) {
        Ray ray;
        ray.origin = p;
        ray.direction = fibonacci_sphere(r, rays);
        const Hit hit = scene.intersect(ray);
        if (!hit.valid()) continue;
        if (closed_instance[hit.instance_id] &&
            glm::dot(hit.geometric_normal, ray.direction) > 0.0f) {
            ++backfaces;
            if (hit.t < s.back_t) s.back_t = hit.t, s.back_dir = ray.direction;
        } else if (hit.t < s.front_t) {
            s.front_t = hit.t, s.front_dir = ray.direction;
        }
    }
    s.backface_fraction = float(backfaces) / float(rays);
    return s;
}

}  // namespace

ProbeLookupSettings probe_lookup_settings(const ProbeGridSettings& s) {
    return {s.visibility, s.normal_bias, s.view_bias, s.bleed_bias};
}

void validate_probe_grid_settings(const ProbeGridSettings& s) {
    const char* name = "ProbeGridSettings";
    if (s.order < 1 || s.order > kMaxShOrder)
        throw InvalidArgument(format_message(name, ".order is ", s.order, "; use 1..",
                                             kMaxShOrder));
    if (!s.volumes.empty()) validate_probe_volumes(s.volumes, "ProbeGridSettings.volumes");
    if (!(s.spacing >= 0.0f && s.spacing <= kMaxCoordinate))
        throw InvalidArgument(format_message(name, ".spacing is ", s.spacing,
                                             "; use metres in (0, ", kMaxCoordinate,
                                             "], or 0 for longest side "
                                             "/ 8"));
    if (s.rays_per_probe < 1 || s.rays_per_probe > 65536)
        throw InvalidArgument(format_message(name, ".rays_per_probe is ", s.rays_per_probe,
                                             "; use 1..65536"));
    if (!(s.hysteresis >= 0.0f && s.hysteresis < 1.0f))
        throw InvalidArgument(format_message(name, ".hysteresis is ", s.hysteresis,
                                             "; use a value in [0, 1)"));
    if (!(s.clamp >= 0.0f && std::isfinite(s.clamp)))
        throw InvalidArgument(format_message(name, ".clamp is ", s.clamp, "; use >= 0 (0 = off)"));
    if (s.bounces < 0 || s.bounces > 64)
        throw InvalidArgument(format_message(name, ".bounces is ", s.bounces, "; use 0..64"));
    if (s.light_splits < 1 || s.light_splits > kMaxLightSplits)
        throw InvalidArgument(format_message(name, ".light_splits is ", s.light_splits,
                                             "; use 1..", kMaxLightSplits));
    if (s.visibility_resolution < 1 || s.visibility_resolution > 64)
        throw InvalidArgument(format_message(name, ".visibility_resolution is ",
                                             s.visibility_resolution, "; use 1..64"));
    if (!(s.visibility_blur >= 0.01f && s.visibility_blur <= 2.0f))
        throw InvalidArgument(format_message(name, ".visibility_blur is ", s.visibility_blur,
                                             "; use 0.01..2 (radians)"));
    validate_probe_lookup_settings(probe_lookup_settings(s), name);
    if (!(s.max_offset >= 0.0f && s.max_offset <= 0.5f))
        throw InvalidArgument(format_message(name, ".max_offset is ", s.max_offset,
                                             "; use 0..0.5 probe spacings"));
    if (!(s.backface_threshold > 0.0f && s.backface_threshold <= 1.0f))
        throw InvalidArgument(format_message(name, ".backface_threshold is ",
                                             s.backface_threshold, "; use a value in (0, 1]"));
    if (s.placement_rays < 4 || s.placement_rays > 65536)
        throw InvalidArgument(format_message(name, ".placement_rays is ", s.placement_rays,
                                             "; use 4..65536"));
}

ProbeGrid::ProbeGrid(const Scene& scene, const ProbeGridSettings& settings, Progress* progress)
    : scene_(&scene), settings_(settings) {
    validate_probe_grid_settings(settings_);
    if (!scene.committed())
        throw InvalidArgument("ProbeGrid: the scene is not committed; call commit() first");
    if (scene.empty())
        throw InvalidArgument("ProbeGrid: the scene has no geometry; add a mesh first");
    reset(progress);
}

ProbeGrid::ProbeGrid(const Scene& scene, const ProbeGridSettings& settings,
                     const ProbeGridData& data)
    : scene_(&scene), settings_(settings) {
    validate_probe_grid_settings(settings_);
    validate_probe_grid_data(data);
    if (!scene.committed())
        throw InvalidArgument("ProbeGrid: the scene is not committed; call commit() first");
    settings_.order = data.order;
    settings_.volumes = data.volumes;
    settings_.visibility_resolution = data.visibility_resolution;
    scene_revision_ = scene.revision();
    publish(std::make_shared<ProbeGridData>(data));
}

void ProbeGrid::check_scene(const char* what) const {
    if (scene_->revision() != scene_revision_ || !scene_->committed())
        throw InvalidArgument(format_message(
            "ProbeGrid::", what, ": the scene was edited after the probes were placed "
            "(revision ", scene_revision_, ", now ", scene_->revision(),
            "); commit it and call reset()"));
}

void ProbeGrid::publish(std::shared_ptr<const ProbeGridData> data) {
    auto field = std::make_shared<const ProbeField>(std::move(data),
                                                    probe_lookup_settings(settings_));
    std::lock_guard<std::mutex> lock(field_mutex_);
    field_ = std::move(field);
}

std::shared_ptr<const ProbeField> ProbeGrid::field() const {
    std::lock_guard<std::mutex> lock(field_mutex_);
    return field_;
}

// Waiting for update_mutex_ from the running call's own thread, or from its progress callback
// (which that call waits for, on whichever thread TBB runs it), would never return.
class ProbeGrid::Serial {
  public:
    Serial(ProbeGrid& grid, const char* what, const Progress* progress) : grid_(grid) {
        const Progress* calling_back = Progress::calling_back();
        if (grid.serial_thread_.load() == std::this_thread::get_id() ||
            (calling_back != nullptr && calling_back == grid.serial_progress_.load()))
            throw Error(format_message(
                "ProbeGrid::", what, ": called from inside this grid's running update() or "
                "reset() (its progress callback); call it after that call returns"));
        grid.update_mutex_.lock();
        grid.serial_thread_.store(std::this_thread::get_id());
        grid.serial_progress_.store(progress);
    }
    ~Serial() {
        grid_.serial_progress_.store(nullptr);
        grid_.serial_thread_.store(std::thread::id());
        grid_.update_mutex_.unlock();
    }
    Serial(const Serial&) = delete;
    Serial& operator=(const Serial&) = delete;

  private:
    ProbeGrid& grid_;
};

void ProbeGrid::reset(Progress* progress) {
    const Serial serial(*this, "reset", progress);
    if (!scene_->committed())
        throw InvalidArgument("ProbeGrid::reset: the scene is not committed; call commit() first");
    if (scene_->empty())
        throw InvalidArgument("ProbeGrid: the scene has no geometry; add a mesh first");
    if (settings_.volumes.empty()) {
        settings_.volumes.push_back(fitted_volume(*scene_, settings_.spacing));
        fitted_ = true;
    } else if (fitted_) {
        settings_.volumes[0] = fitted_volume(*scene_, settings_.spacing);
    }
    const auto start = now();
    auto data = std::make_shared<ProbeGridData>(place(progress));
    timings_.placement = seconds_since(start);
    scene_revision_ = scene_->revision();
    publish(std::move(data));
}

ProbeGridData ProbeGrid::place(Progress* progress) const {
    ProbeGridData data;
    data.order = settings_.order;
    data.volumes = settings_.volumes;
    data.visibility_resolution = settings_.visibility_resolution;
    data.includes_direct = settings_.include_direct;
    // The artist's volumes were checked with the settings; a fitted one is checked here.
    const size_t probes = validate_probe_volumes(data.volumes, "ProbeGridSettings.volumes");
    const double bytes = double(probes) * double(probe_bytes(data.visibility_resolution));
    if (bytes > double(kMaxProbeBytes))
        throw InvalidArgument(format_message(
            "ProbeGridSettings: ", probes, " probes with visibility_resolution ",
            data.visibility_resolution, " need ", bytes / 1e9, " GB; the limit is ",
            double(kMaxProbeBytes) / 1e9, " GB: lower visibility_resolution or the resolutions"));
    require_memory(uint64_t(bytes),
                   format_message("ProbeGridSettings: ", probes, " probes with "
                                  "visibility_resolution ", data.visibility_resolution, " (",
                                  probe_bytes(data.visibility_resolution), " bytes each)"),
                   "lower visibility_resolution or the volumes' resolutions");
    const std::vector<vec3> base = probe_base_positions(data.volumes);
    const size_t count = base.size();
    data.positions = base;
    data.active.assign(count, 1);
    data.sh.assign(count, ShRgb(data.order));
    data.variance.assign(count, std::numeric_limits<float>::infinity());
    const float far = max_scene_distance(*scene_, base);
    data.visibility.assign(count * size_t(data.visibility_resolution) * data.visibility_resolution,
                           vec2(far, far * far));

    // Volume of each probe, for its spacing and axes.
    std::vector<uint32_t> volume_of(count);
    for (size_t v = 0, i = 0; v < data.volumes.size(); ++v) {
        const ivec3 r = data.volumes[v].resolution;
        for (size_t k = 0; k < size_t(r.x) * r.y * r.z; ++k) volume_of[i++] = uint32_t(v);
    }
    std::vector<uint8_t> closed_mesh(scene_->meshes().size());
    for (size_t m = 0; m < closed_mesh.size(); ++m)
        closed_mesh[m] = is_closed_surface(scene_->meshes()[m]) ? 1 : 0;
    std::vector<uint8_t> closed_instance;
    for (const Instance& instance : scene_->instances())
        closed_instance.push_back(closed_mesh[instance.mesh_id]);
    if (progress) progress->begin_stage("placing probes");
    parallel_for(
        0, count, 16,
        [&](uint64_t begin, uint64_t end) {
            for (uint64_t i = begin; i < end; ++i) {
                const ProbeVolume& volume = data.volumes[volume_of[i]];
                const vec3 spacing = probe_spacing(volume);
                const float min_spacing = std::min(spacing.x, std::min(spacing.y, spacing.z));
                const mat3 axes(volume.world_from_volume);
                const mat3 local_from_world = glm::inverse(axes);
                // Bound on the offset in the volume's local units (its axes span [-1, 1]).
                const vec3 bound = settings_.max_offset * 2.0f / vec3(volume.resolution);
                vec3 offset(0.0f);
                Surroundings s = look_around(*scene_, closed_instance, base[i], settings_.placement_rays);
                for (int step = 0; settings_.relocate && step < kRelocationSteps; ++step) {
                    vec3 move(0.0f);
                    if (s.backface_fraction > settings_.backface_threshold && s.back_t < kInfinity)
                        move = s.back_dir * (s.back_t + kMinFrontDistance * min_spacing);
                    else if (s.front_t < kMinFrontDistance * min_spacing)
                        move = -s.front_dir * (kMinFrontDistance * min_spacing - s.front_t);
                    else
                        break;
                    const vec3 local = glm::clamp(local_from_world * (offset + move), -bound, bound);
                    offset = axes * local;
                    s = look_around(*scene_, closed_instance, base[i] + offset,
                                    settings_.placement_rays);
                }
                data.positions[i] = base[i] + offset;
                data.active[i] = s.backface_fraction > settings_.backface_threshold ? 0 : 1;
            }
        },
        progress);
    return data;
}

void ProbeGrid::update(Progress* progress) {
    update_probes(0, std::numeric_limits<uint64_t>::max(), progress);
}

void ProbeGrid::update_probes(uint64_t first, uint64_t count, Progress* progress) {
    const Serial serial(*this, "update", progress);
    check_scene("update");
    const auto start = now();
    const std::shared_ptr<const ProbeField> current = field();
    const ProbeGridData& old = current->data();
    auto next = std::make_shared<ProbeGridData>(old);
    const uint64_t pass = old.passes;
    const float a = std::max(1.0f - settings_.hysteresis, 1.0f / float(pass + 1));
    const uint32_t n = settings_.rays_per_probe;
    const float far = max_scene_distance(*scene_, old.positions);
    const LightSampler lights(*scene_, WorldSampling::Cosine, true, settings_.light_splits);
    const PathTracerSettings path_settings = probe_path_settings(settings_);
    const Camera camera;  // probe rays are not camera rays; only the unused Depth pass reads it
    const int vis_texels = old.visibility_resolution * old.visibility_resolution;
    const float sample_weight = kFourPi / float(n);
    constexpr float kDcScale = 0.28209479177387814f * kFourPi;  // Y00 * 4 pi

    std::atomic<uint64_t> paths{0}, rays{0};
    if (progress) progress->begin_stage("updating probes");
    const uint64_t begin_probe = std::min<uint64_t>(first, old.probe_count());
    const uint64_t end_probe =
        begin_probe + std::min<uint64_t>(count, old.probe_count() - begin_probe);
    parallel_for(
        begin_probe, end_probe, kProbesPerTask,
        [&](uint64_t begin, uint64_t end) {
            VisibilityFilter filter(old.visibility_resolution, settings_.visibility_blur);
            IntegratorClock clock;  // counts the paths' rays; their time is not split
            clock.time_direct = false;
            std::vector<vec2> moments(vis_texels);
            for (uint64_t probe = begin; probe < end; ++probe) {
                if (!old.active[probe]) continue;
                Pcg32 rotation_rng(settings_.seed ^ kRotationSeed, stream_id(pass, probe));
                const mat3 rotation = sample_uniform_rotation(
                    vec3(rotation_rng.next_float(), rotation_rng.next_float(),
                         rotation_rng.next_float()));
                ShRgb estimate(old.order);
                double dc_sum = 0.0, dc_sum2 = 0.0;
                filter.clear();
                for (uint32_t r = 0; r < n; ++r) {
                    if (r % kRaysPerCancelPoll == kRaysPerCancelPoll - 1)
                        throw_if_cancelled(progress);
                    Ray ray;
                    ray.origin = old.positions[probe];
                    ray.direction = glm::normalize(rotation * fibonacci_sphere(r, n));
                    const Hit hit = scene_->intersect(ray);
                    filter.add(ray.direction, hit.valid() ? hit.t : far);
                    Pcg32 rng(settings_.seed, stream_id(pass, probe * n + r));
                    PassValues values;
                    PathIntegrator(*scene_, camera, lights, path_settings, nullptr, rng, values,
                                   &clock)
                        .trace(ray, hit);
                    const vec3 radiance =
                        path_radiance(values, settings_.include_direct, settings_.clamp);
                    sh_add_sample(estimate, ray.direction, radiance * sample_weight);
                    const double dc = double(kDcScale * luminance(radiance));
                    dc_sum += dc;
                    dc_sum2 += dc * dc;
                }
                paths.fetch_add(n, std::memory_order_relaxed);
                rays.fetch_add(n + clock.rays, std::memory_order_relaxed);  // + probe rays
                clock.rays = 0;

                ShRgb& sh = next->sh[probe];
                for (int i = 0; i < sh.num_coefficients(); ++i)
                    sh[i] = (1.0f - a) * sh[i] + a * estimate[i];
                const double mean = dc_sum / n;
                const double sample_variance =
                    n > 1 ? std::max(0.0, (dc_sum2 - dc_sum * mean) / (n - 1)) : 0.0;
                const float old_variance = pass == 0 ? 0.0f : old.variance[probe];
                next->variance[probe] = (1.0f - a) * (1.0f - a) * old_variance +
                                        a * a * float(sample_variance / n);
                const vec2* old_map = old.visibility_map(probe);
                filter.moments(old_map, moments.data());
                vec2* map = next->visibility.data() + probe * size_t(vis_texels);
                for (int t = 0; t < vis_texels; ++t)
                    map[t] = pass == 0 ? moments[t] : (1.0f - a) * old_map[t] + a * moments[t];
            }
        },
        progress);
    next->passes = pass + 1;
    timings_.update = seconds_since(start);
    timings_.paths = paths.load();
    timings_.rays = rays.load();
    publish(std::move(next));
}

size_t ProbeGrid::active_count() const {
    const std::shared_ptr<const ProbeField> current = field();
    const ProbeGridData& d = current->data();
    return size_t(std::count(d.active.begin(), d.active.end(), uint8_t(1)));
}

std::vector<float> ProbeGrid::relative_error() const {
    const std::shared_ptr<const ProbeField> current = field();
    const ProbeGridData& d = current->data();
    std::vector<float> out(d.probe_count());
    for (size_t i = 0; i < out.size(); ++i) {
        if (d.passes == 0) {
            out[i] = std::numeric_limits<float>::infinity();
            continue;
        }
        const float dc = luminance(d.sh[i][0]);
        out[i] = dc > 0.0f ? std::sqrt(d.variance[i]) / dc : 0.0f;
    }
    return out;
}

std::vector<StageSeconds> ProbeGrid::stage_seconds() const {
    return {{"placement", timings_.placement}, {"update", timings_.update}};
}

size_t ProbeGrid::memory_bytes() const {
    const std::shared_ptr<const ProbeField> current = field();
    const ProbeGridData& d = current->data();
    return d.probe_count() * probe_bytes(d.visibility_resolution);
}

// A snapshot per lookup, so that an update() on another thread cannot free the probes being
// read (see the header).
ShRgb ProbeGrid::radiance_sh(const vec3& p, const vec3& n) const {
    return field()->radiance_sh(p, n);
}

FieldLookup ProbeGrid::view_lookup(const vec3& p, const vec3& n, const vec3& wo) const {
    return field()->view_lookup(p, n, wo);
}

}  // namespace shgi
