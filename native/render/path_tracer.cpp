#include "render/path_tracer.h"

#include <algorithm>
#include <cmath>

#include "render/shading.h"
#include "util/error.h"
#include "util/parallel.h"
#include "util/rng.h"

namespace shgi {
namespace {

float power_heuristic(float pdf_a, float pdf_b) {
    const float a2 = pdf_a * pdf_a;
    const float sum = a2 + pdf_b * pdf_b;
    return sum > 0.0f ? a2 / sum : 0.0f;
}

const Pass kDirectPass[kLobeClassCount] = {Pass::DiffDir, Pass::GlossDir, Pass::TransDir};
const Pass kIndirectPass[kLobeClassCount] = {Pass::DiffInd, Pass::GlossInd, Pass::TransInd};
const Pass kColorPass[kLobeClassCount] = {Pass::DiffCol, Pass::GlossCol, Pass::TransCol};

// One camera path: its state and the pass bookkeeping.
class PathIntegrator {
  public:
    PathIntegrator(const Scene& scene, const LightSampler& lights,
                   const PathTracerSettings& settings, Pcg32& rng, PassValues& out)
        : scene_(scene), lights_(lights), settings_(settings), rng_(rng), out_(out) {}

    void trace(Ray ray);

  private:
    void find_emission(const Ray& ray, const Hit& hit);
    void add_emission(const vec3& radiance, float light_pdf, bool is_world);
    void record_first_hit(const Shading& shading, const Ray& ray, const Hit& hit);
    void sample_direct(const Shading& shading);
    bool scatter(const Shading& shading, Ray* ray);
    void add_light(const vec3& contribution, int lobe_class, bool direct);
    void add_split(const vec3& contribution, bool direct);

    const Scene& scene_;
    const LightSampler& lights_;
    const PathTracerSettings& settings_;
    Pcg32& rng_;
    PassValues& out_;

    vec3 throughput_{1.0f};
    int vertex_ = 0;                   // surfaces shaded so far
    int bounces_[kLobeClassCount] = {0, 0, 0};
    bool last_delta_ = true;           // camera rays and Dirac lobes take no MIS weight
    float last_pdf_ = 0.0f;
    vec3 last_normal_{0.0f, 0.0f, 1.0f};
    float class_fraction_[kLobeClassCount] = {0.0f, 0.0f, 0.0f};  // of the first scattering
};

void PathIntegrator::trace(Ray ray) {
    bool terminate_on_next_surface = false;
    for (;;) {
        const Hit hit = scene_.intersect(ray);
        find_emission(ray, hit);
        if (!hit.valid() || terminate_on_next_surface) break;
        const SurfacePoint sp = scene_.surface_point(ray, hit);
        const Shading shading = make_shading(scene_, sp, ray.direction);
        if (vertex_ == 0) record_first_hit(shading, ray, hit);
        if (shading.bsdf.has_smooth_lobes()) sample_direct(shading);
        if (!scatter(shading, &ray)) break;
        const int total = bounces_[0] + bounces_[1] + bounces_[2];
        terminate_on_next_surface = total > settings_.max_bounces ||
                                    bounces_[0] > settings_.diffuse_bounces ||
                                    bounces_[1] > settings_.glossy_bounces ||
                                    bounces_[2] > settings_.transmission_bounces;
        if (vertex_ >= settings_.russian_roulette_depth && !terminate_on_next_surface) {
            const float survive = std::min(1.0f, max_component(throughput_));
            if (rng_.next_float() >= survive) break;
            throughput_ /= survive;
        }
    }
}

// Adds what the ray meets: point/spot disks and area lights in front of the hit, the hit's own
// emission, or the world and suns when it escapes.
void PathIntegrator::find_emission(const Ray& ray, const Hit& hit) {
    EmissionHit light_hit;
    const bool camera_ray = vertex_ == 0;
    if (lights_.intersect_lights(ray.origin, ray.direction, hit.valid() ? hit.t : kInfinity,
                                 camera_ray, &light_hit)) {
        add_emission(light_hit.radiance, light_hit.light_pdf, false);
    } else if (hit.valid()) {
        const EmissionHit surface = lights_.triangle_emission(hit, ray.direction);
        if (max_component(surface.radiance) > 0.0f)
            add_emission(surface.radiance, surface.light_pdf, false);
    } else {
        for (const EmissionHit& escaped : lights_.escaped(last_normal_, ray.direction, camera_ray))
            add_emission(escaped.radiance, escaped.light_pdf, true);
    }
}

void PathIntegrator::add_emission(const vec3& radiance, float light_pdf, bool is_world) {
    const float weight = last_delta_ ? 1.0f : power_heuristic(last_pdf_, light_pdf);
    const vec3 contribution = throughput_ * radiance * weight;
    if (vertex_ == 0) {
        out_[is_world ? Pass::Env : Pass::Emit] += contribution;
        out_[Pass::Combined] += contribution;
        return;
    }
    add_split(contribution, vertex_ == 1);
}

// A contribution reaching the camera through the first scattering: split by the class
// fractions of that scattering into Dir (one scattering) or Ind passes.
void PathIntegrator::add_split(const vec3& contribution, bool direct) {
    for (int c = 0; c < kLobeClassCount; ++c)
        if (class_fraction_[c] > 0.0f) add_light(contribution * class_fraction_[c], c, direct);
}

void PathIntegrator::add_light(const vec3& contribution, int lobe_class, bool direct) {
    vec3 value = contribution;
    if (!direct && settings_.clamp_indirect > 0.0f) {
        const float peak = max_component(value);
        if (peak > settings_.clamp_indirect) value *= settings_.clamp_indirect / peak;
    }
    if (!is_finite(value)) return;
    out_[direct ? kDirectPass[lobe_class] : kIndirectPass[lobe_class]] += value;
    out_[Pass::Combined] += value;
}

void PathIntegrator::record_first_hit(const Shading& shading, const Ray& ray, const Hit& hit) {
    for (int c = 0; c < kLobeClassCount; ++c)
        out_[kColorPass[c]] += shading.bsdf.class_color(LobeClass(c));
    out_[Pass::Normal] += shading.frame.z;
    const Camera& camera = scene_.camera();
    const vec3 forward = glm::normalize(-vec3(camera.world_from_camera[2]));
    const vec3 position = ray.origin + hit.t * ray.direction;
    out_[Pass::Depth].x += glm::dot(position - vec3(camera.world_from_camera[3]), forward);
}

// Next-event estimation at one surface, MIS-weighted against BSDF sampling.
void PathIntegrator::sample_direct(const Shading& shading) {
    LightSample ls;
    const float u_select = rng_.next_float();
    const vec2 u = rng_.next_vec2();
    if (!lights_.sample(shading.position, shading.frame.z, u_select, u, &ls)) return;
    const vec3 wi = shading.frame.to_local(ls.wi);
    const bool geometric_above = glm::dot(ls.wi, shading.geometric_normal) > 0.0f;
    if (geometric_above != (wi.z > 0.0f)) return;  // shading and geometric normals disagree
    const BsdfEval eval = shading.bsdf.eval(shading.wo, wi);
    if (max_component(eval.total()) <= 0.0f) return;
    Ray shadow;
    shadow.origin = offset_origin(shading.position,
                                  geometric_above ? shading.geometric_normal
                                                  : -shading.geometric_normal);
    shadow.direction = ls.wi;
    shadow.tmax = std::isinf(ls.distance) ? kInfinity : ls.distance * (1.0f - kShadowShorten);
    if (scene_.occluded(shadow)) return;
    const float weight = ls.delta ? 1.0f : power_heuristic(ls.pdf, shading.bsdf.pdf(shading.wo, wi));
    const vec3 scale = throughput_ * ls.radiance * (weight / ls.pdf);
    if (vertex_ == 0) {  // direct light at the first surface, split by the lobes it lit
        for (int c = 0; c < kLobeClassCount; ++c) add_light(eval.by_class[c] * scale, c, true);
        return;
    }
    add_split(eval.total() * scale, false);
}

// Samples the BSDF, updates throughput, bounce counts and MIS state; false ends the path.
bool PathIntegrator::scatter(const Shading& shading, Ray* ray) {
    BsdfSample bs;
    const float u_lobe = rng_.next_float();
    const vec2 u = rng_.next_vec2();
    if (!shading.bsdf.sample(shading.wo, u_lobe, u, &bs)) return false;
    const vec3 wi = shading.frame.to_world(bs.wi);
    const bool geometric_above = glm::dot(wi, shading.geometric_normal) > 0.0f;
    if (geometric_above != (bs.wi.z > 0.0f)) return false;
    if (vertex_ == 0) {
        // Cycles' pass_diffuse_weight / pass_glossy_weight: the classes' shares of the BSDF.
        const vec3 total = bs.eval.total();
        const float sum = total.x + total.y + total.z;
        for (int c = 0; c < kLobeClassCount; ++c) {
            const vec3 part = bs.eval.by_class[c];
            class_fraction_[c] = sum > 0.0f ? (part.x + part.y + part.z) / sum : 0.0f;
        }
    }
    ++bounces_[int(bs.lobe_class)];
    throughput_ *= bs.weight;
    last_delta_ = bs.delta;
    last_pdf_ = bs.pdf;
    last_normal_ = shading.frame.z;
    ++vertex_;
    ray->origin = offset_origin(shading.position, geometric_above ? shading.geometric_normal
                                                                  : -shading.geometric_normal);
    ray->direction = wi;
    ray->tmin = 0.0f;
    ray->tmax = kInfinity;
    return max_component(throughput_) > 0.0f;
}

const PathTracerSettings& validated(const PathTracerSettings& settings) {
    validate_path_tracer_settings(settings);
    return settings;
}

}  // namespace

void validate_path_tracer_settings(const PathTracerSettings& settings) {
    auto check_non_negative = [](int value, const char* name) {
        if (value < 0)
            throw InvalidArgument(format_message("PathTracerSettings.", name, " is ", value,
                                                 "; it must be >= 0"));
    };
    check_non_negative(settings.max_bounces, "max_bounces");
    check_non_negative(settings.diffuse_bounces, "diffuse_bounces");
    check_non_negative(settings.glossy_bounces, "glossy_bounces");
    check_non_negative(settings.transmission_bounces, "transmission_bounces");
    check_non_negative(settings.russian_roulette_depth, "russian_roulette_depth");
    if (settings.samples == 0 || settings.samples > kMaxPathTracerSamples)
        throw InvalidArgument(format_message("PathTracerSettings.samples is ", settings.samples,
                                             "; it must be in [1, ", kMaxPathTracerSamples, "]"));
    if (!std::isfinite(settings.clamp_indirect) || settings.clamp_indirect < 0.0f)
        throw InvalidArgument(format_message("PathTracerSettings.clamp_indirect is ",
                                             settings.clamp_indirect,
                                             "; it must be finite and >= 0 (0 = off)"));
    if (settings.tile_size < 1)
        throw InvalidArgument(format_message("PathTracerSettings.tile_size is ",
                                             settings.tile_size, "; it must be >= 1"));
}

PathTracer::PathTracer(const Scene& scene, const PathTracerSettings& settings)
    : scene_(&scene),
      scene_revision_(scene.revision()),
      settings_(validated(settings)),
      lights_(scene, settings.world_sampling) {
    const Camera& camera = scene.camera();
    film_ = Film(int(camera.resolution_x), int(camera.resolution_y));
}

void PathTracer::render(uint32_t samples, Progress* progress) {
    if (scene_->revision() != scene_revision_ || !scene_->committed())
        throw InvalidArgument(format_message(
            "PathTracer::render: the scene was edited after this PathTracer was created "
            "(revision ", scene_revision_, ", now ", scene_->revision(),
            "); commit it and create a new PathTracer"));
    const uint64_t first = film_.samples();
    if (samples == 0) return;
    if (first + samples > kMaxPathTracerSamples)
        throw InvalidArgument(format_message("PathTracer::render: ", first, " + ", samples,
                                             " samples exceed the limit of ",
                                             kMaxPathTracerSamples, " per pixel"));
    const Camera& camera = scene_->camera();
    const int width = film_.width(), height = film_.height(), tile = settings_.tile_size;
    const int tiles_x = (width + tile - 1) / tile, tiles_y = (height + tile - 1) / tile;
    Film scratch = film_;  // committed only when every tile finished
    auto render_tile = [&](uint64_t begin, uint64_t end) {
        for (uint64_t t = begin; t < end; ++t) {
            const int x0 = int(t % uint64_t(tiles_x)) * tile, y0 = int(t / uint64_t(tiles_x)) * tile;
            for (int y = y0; y < std::min(y0 + tile, height); ++y) {
                for (int x = x0; x < std::min(x0 + tile, width); ++x) {
                    const uint64_t pixel = uint64_t(y) * uint64_t(width) + uint64_t(x);
                    for (uint64_t s = first; s < first + samples; ++s) {
                        throw_if_cancelled(progress);  // one relaxed atomic load per path
                        Pcg32 rng(settings_.seed, stream_id(s, pixel));
                        const vec2 jitter = rng.next_vec2();
                        PassValues values;
                        PathIntegrator integrator(*scene_, lights_, settings_, rng, values);
                        integrator.trace(camera.generate_ray(vec2(float(x), float(y)) + jitter));
                        scratch.add(x, y, values);
                    }
                }
            }
        }
    };
    parallel_for(0, uint64_t(tiles_x) * uint64_t(tiles_y), 1, render_tile, progress);
    scratch.set_samples(uint32_t(first + samples));
    film_ = std::move(scratch);
}

Image render_path_traced(const Scene& scene, const PathTracerSettings& settings,
                         Progress* progress) {
    PathTracer tracer(scene, settings);
    tracer.render(settings.samples, progress);
    return tracer.image();
}

}  // namespace shgi
