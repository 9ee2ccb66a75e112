// PathIntegrator: one camera path with Cycles' pass bookkeeping, shared by the reference path
// tracer (render/path_tracer.h) and the preview renderer (render/preview_renderer.h).
//
// Without a field it is the reference estimator: NEE + BSDF sampling with MIS at every vertex.
// With an IndirectField (preview), each vertex splits its BSDF (render/bsdf.h): the field lobes
// (non-Dirac diffuse and glossy reflection) get direct light by NEE alone (weight 1: the field
// holds no direct light, so there is no second strategy to weight against) and indirect light
// from the field — diffuse closure weight x E(p, n) / pi, and per glossy lobe its directional
// albedo x the field's pre-filtered glossy radiance — while the traced lobes (Dirac lobes,
// refraction) continue the path, which then sees emitters with weight 1. Field light has
// scattered at least twice on its way to the camera, so it lands in the Ind passes.
//
// Not thread-safe: one integrator per path, on one thread.
#pragma once

#include "render/bsdf.h"
#include "render/film.h"
#include "render/indirect_field.h"
#include "render/light_sampler.h"
#include "render/path_tracer.h"
#include "render/shading.h"
#include "scene/scene.h"
#include "util/rng.h"

namespace shgi {

// Seconds spent by one thread in the direct-light and indirect-light parts of its paths.
struct IntegratorClock {
    double direct = 0.0;
    double indirect = 0.0;
};

class PathIntegrator {
  public:
    // `field` null: reference path tracing. `clock` null: no timing.
    PathIntegrator(const Scene& scene, const LightSampler& lights,
                   const PathTracerSettings& settings, const IndirectField* field, Pcg32& rng,
                   PassValues& out, IntegratorClock* clock = nullptr)
        : scene_(scene), lights_(lights), settings_(settings), field_(field), rng_(rng),
          out_(out), clock_(clock) {}

    // Traces a camera ray.
    void trace(const Ray& ray);
    // Traces a camera ray whose first hit is already known (batched primary rays).
    void trace(const Ray& ray, const Hit& first_hit);

  private:
    void find_emission(const Ray& ray, const Hit& hit);
    void add_emission(const vec3& radiance, float light_pdf, bool is_world);
    void record_first_hit(const Shading& shading, const Ray& ray, const Hit& hit);
    void sample_direct(const Shading& shading);
    void add_field(const Shading& shading);
    bool scatter(const Shading& shading, Ray* ray);
    void add_light(const vec3& contribution, int lobe_class, bool direct);
    void add_split(const vec3& contribution, bool direct);

    const Scene& scene_;
    const LightSampler& lights_;
    const PathTracerSettings& settings_;
    const IndirectField* field_;
    Pcg32& rng_;
    PassValues& out_;
    IntegratorClock* clock_;

    vec3 throughput_{1.0f};
    int vertex_ = 0;                   // surfaces shaded so far
    int bounces_[kLobeClassCount] = {0, 0, 0};
    bool last_delta_ = true;           // camera rays and Dirac lobes take no MIS weight
    float last_pdf_ = 0.0f;
    vec3 last_normal_{0.0f, 0.0f, 1.0f};
    float class_fraction_[kLobeClassCount] = {0.0f, 0.0f, 0.0f};  // of the first scattering
};

}  // namespace shgi
