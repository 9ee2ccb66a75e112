#include "render/light_sampler.h"

#include <algorithm>
#include <cmath>

#include "util/error.h"

namespace shgi {
namespace {

// Disk and ellipse area lights cover pi/4 of their bounding rectangle.
constexpr float kEllipseAreaFactor = kPi / 4.0f;

float smoothstep01(float x) {
    x = std::clamp(x, 0.0f, 1.0f);
    return x * x * (3.0f - 2.0f * x);
}

uint64_t triangle_key(uint32_t instance_id, uint32_t triangle_id) {
    return (uint64_t(instance_id) << 32) | triangle_id;
}

vec3 area_emit_normal(const Light& light) { return light.direction(); }

float scene_radius(const Scene& scene) {
    if (scene.empty()) return 1.0f;
    return std::max(0.5f * glm::length(scene.bounds().extent()), 1e-3f);
}

}  // namespace

float spot_attenuation(const Light& light, float cos_angle) {
    const float cos_half = std::cos(0.5f * light.spot_size);
    const float t = cos_angle - cos_half;
    if (t <= 0.0f) return 0.0f;
    const float smooth = (1.0f - cos_half) * light.spot_blend;
    if (smooth > 0.0f && t < smooth) return cos_angle * smoothstep01(t / smooth);
    return cos_angle;
}

bool is_round(AreaShape shape) { return shape == AreaShape::Disk || shape == AreaShape::Ellipse; }

void area_half_axes(const Light& light, vec3* ex, vec3* ey) {
    const bool square = light.shape == AreaShape::Square || light.shape == AreaShape::Disk;
    const float size_y = square ? light.size_x : light.size_y;
    *ex = vec3(light.world_from_light[0]) * (0.5f * light.size_x);
    *ey = vec3(light.world_from_light[1]) * (0.5f * size_y);
}

float area_light_area(const Light& light) {
    vec3 ex, ey;
    area_half_axes(light, &ex, &ey);
    const float rectangle = 4.0f * glm::length(glm::cross(ex, ey));
    return is_round(light.shape) ? kEllipseAreaFactor * rectangle : rectangle;
}

LightSampler::LightSampler(const Scene& scene, WorldSampling world_sampling, bool sample_world)
    : scene_(&scene), world_sampling_(world_sampling) {
    if (!scene.committed())
        throw InvalidArgument("LightSampler: the scene is not committed; call commit() first");
    // Power estimates only steer selection; any positive weights keep the estimator unbiased.
    const float radius = scene_radius(scene);
    const float disk_area = kPi * radius * radius;
    std::vector<float> weights;
    light_emitter_.assign(scene.lights().size(), kInvalidId);
    for (uint32_t i = 0; i < scene.lights().size(); ++i) {
        const Light& light = scene.lights()[i];
        const float power = light.type == LightType::Sun
                                ? light.strength * disk_area
                                : light.power;
        const float weight = luminance(light.color) * power;
        if (!(weight > 0.0f)) continue;
        light_emitter_[i] = uint32_t(emitters_.size());
        emitters_.push_back({Kind::Light, i});
        weights.push_back(weight);
    }
    const auto& triangles = scene.emissive_triangles();
    for (uint32_t i = 0; i < triangles.size(); ++i) {
        const float weight = luminance(triangles[i].radiance) * kPi * triangles[i].area;
        if (!(weight > 0.0f)) continue;
        triangle_emitter_[triangle_key(triangles[i].instance_id, triangles[i].triangle_id)] =
            uint32_t(emitters_.size());
        emitters_.push_back({Kind::Triangle, i});
        weights.push_back(weight);
    }
    const float world_weight = luminance(scene.world().radiance()) * kPi * 4.0f * disk_area;
    if (world_weight > 0.0f && sample_world) {
        world_emitter_ = uint32_t(emitters_.size());
        emitters_.push_back({Kind::World, 0});
        weights.push_back(world_weight);
    }
    if (!weights.empty()) distribution_ = DiscreteDistribution(weights);
}

bool LightSampler::sample(const vec3& p, const vec3& n, float u_select, const vec2& u,
                          LightSample* out) const {
    if (empty()) return false;
    const uint32_t chosen = distribution_.sample(u_select);
    const Emitter& emitter = emitters_[chosen];
    bool ok = false;
    if (emitter.kind == Kind::Light) {
        ok = sample_light(scene_->lights()[emitter.index], p, u, out);
    } else if (emitter.kind == Kind::Triangle) {
        ok = sample_triangle(scene_->emissive_triangles()[emitter.index], p, u, out);
    } else {
        const vec3 local = world_sampling_ == WorldSampling::Cosine ? sample_cosine_hemisphere(u)
                                                                    : sample_uniform_sphere(u);
        out->wi = Frame::from_z(n).to_world(local);
        out->distance = kInfinity;
        out->radiance = scene_->world().radiance();
        out->pdf = world_pdf(n, out->wi);
        out->delta = false;
        ok = out->pdf > 0.0f;
    }
    if (!ok) return false;
    out->pdf *= selection_pdf(chosen);
    return out->pdf > 0.0f && is_finite(out->radiance);
}

bool LightSampler::sample_light(const Light& light, const vec3& p, const vec2& u,
                                LightSample* out) const {
    switch (light.type) {
        case LightType::Point:
        case LightType::Spot: return sample_point(light, p, u, out);
        case LightType::Area: return sample_area(light, p, u, out);
        case LightType::Sun: return sample_sun(light, u, out);
    }
    return false;
}

bool LightSampler::sample_point(const Light& light, const vec3& p, const vec2& u,
                                LightSample* out) const {
    const vec3 to_center = light.position() - p;
    const float center_distance = glm::length(to_center);
    if (!(center_distance > light.radius)) return false;
    const vec3 intensity = light.color * point_intensity_from_power(light.power);
    vec3 target = light.position();
    float pdf = 1.0f;
    vec3 radiance;
    if (light.radius > 0.0f) {
        // Cycles 3.4: a disk of the light's radius facing the shading point.
        const vec3 axis = -to_center / center_distance;
        const vec2 d = sample_uniform_disk(u) * light.radius;
        const Frame frame = Frame::from_z(axis);
        target += d.x * frame.x + d.y * frame.y;
        radiance = intensity / (kPi * light.radius * light.radius);
    }
    const vec3 offset = target - p;
    out->distance = glm::length(offset);
    out->wi = offset / out->distance;
    if (light.radius > 0.0f) {
        const float cos_light = glm::dot(out->wi, to_center / center_distance);
        if (cos_light <= 0.0f) return false;
        pdf = out->distance * out->distance /
              (cos_light * kPi * light.radius * light.radius);
    } else {
        radiance = intensity / (out->distance * out->distance);
    }
    if (light.type == LightType::Spot)
        radiance *= spot_attenuation(light, glm::dot(light.direction(), -out->wi));
    out->radiance = radiance;
    out->pdf = pdf;
    out->delta = light.radius <= 0.0f;
    return true;
}

bool LightSampler::sample_area(const Light& light, const vec3& p, const vec2& u,
                               LightSample* out) const {
    const vec3 normal = area_emit_normal(light);
    const vec3 center = light.position();
    if (glm::dot(p - center, normal) <= 0.0f) return false;  // behind the one-sided emitter
    vec3 ex, ey;
    area_half_axes(light, &ex, &ey);
    const vec2 local = is_round(light.shape) ? sample_uniform_disk(u) : 2.0f * u - vec2(1.0f);
    const vec3 offset = center + local.x * ex + local.y * ey - p;
    out->distance = glm::length(offset);
    out->wi = offset / out->distance;
    const float cos_light = -glm::dot(out->wi, normal);
    if (cos_light <= 0.0f) return false;
    const float area = area_light_area(light);
    out->radiance = light.color * area_radiance_from_power(light.power, area);
    out->pdf = out->distance * out->distance / (cos_light * area);
    out->delta = false;
    return true;
}

bool LightSampler::sample_sun(const Light& light, const vec2& u, LightSample* out) const {
    const vec3 to_sun = -light.direction();
    out->distance = kInfinity;
    if (light.angle <= 0.0f) {
        out->wi = to_sun;
        out->radiance = light.color * light.strength;
        out->pdf = 1.0f;
        out->delta = true;
        return true;
    }
    const float cos_max = std::cos(0.5f * light.angle);
    out->wi = Frame::from_z(to_sun).to_world(sample_uniform_cone(u, cos_max));
    const float solid_angle = kTwoPi * (1.0f - cos_max);
    out->radiance = light.color * (light.strength / solid_angle);
    out->pdf = 1.0f / solid_angle;
    out->delta = false;
    return true;
}

bool LightSampler::sample_triangle(const EmissiveTriangle& tri, const vec3& p, const vec2& u,
                                   LightSample* out) const {
    const vec3 b = sample_uniform_triangle(u);
    const vec3 q = b.x * tri.p0 + b.y * tri.p1 + b.z * tri.p2;
    const vec3 offset = q - p;
    out->distance = glm::length(offset);
    if (!(out->distance > 0.0f)) return false;
    out->wi = offset / out->distance;
    const vec3 normal = glm::normalize(glm::cross(tri.p1 - tri.p0, tri.p2 - tri.p0));
    const float cos_light = std::fabs(glm::dot(out->wi, normal));  // two-sided emission
    if (cos_light <= 0.0f) return false;
    out->radiance = tri.radiance;
    out->pdf = out->distance * out->distance / (cos_light * tri.area);
    out->delta = false;
    return true;
}

float LightSampler::world_pdf(const vec3& n, const vec3& wi) const {
    if (world_sampling_ == WorldSampling::Uniform) return sample_uniform_sphere_pdf();
    return std::max(0.0f, glm::dot(n, wi)) * kInvPi;
}

bool LightSampler::intersect_lights(const vec3& p, const vec3& wi, float t_max, bool camera_ray,
                                    EmissionHit* out) const {
    float best_t = t_max;
    bool found = false;
    for (uint32_t i = 0; i < scene_->lights().size(); ++i) {
        if (light_emitter_[i] == kInvalidId) continue;
        const Light& light = scene_->lights()[i];
        if (camera_ray && !light.visible_camera) continue;
        const bool disk = (light.type == LightType::Point || light.type == LightType::Spot) &&
                          light.radius > 0.0f;
        if (!disk && light.type != LightType::Area) continue;
        const vec3 center = light.position();
        const vec3 normal = disk ? glm::normalize(p - center) : area_emit_normal(light);
        const float denom = glm::dot(wi, normal);
        if (!(denom < 0.0f)) continue;  // parallel, or the back of an area light
        const float t = glm::dot(center - p, normal) / denom;
        if (!(t > 0.0f && t < best_t)) continue;
        const vec3 q = p + t * wi - center;
        float area;
        vec3 radiance;
        if (disk) {
            if (glm::dot(q, q) > light.radius * light.radius) continue;
            area = kPi * light.radius * light.radius;
            radiance = light.color * point_intensity_from_power(light.power) / area;
            if (light.type == LightType::Spot)
                radiance *= spot_attenuation(light, glm::dot(light.direction(), -wi));
        } else {
            vec3 ex, ey;
            area_half_axes(light, &ex, &ey);
            const float s = glm::dot(q, ex) / glm::dot(ex, ex);
            const float r = glm::dot(q, ey) / glm::dot(ey, ey);
            const bool inside = is_round(light.shape) ? s * s + r * r <= 1.0f
                                                      : std::fabs(s) <= 1.0f && std::fabs(r) <= 1.0f;
            if (!inside) continue;
            area = area_light_area(light);
            radiance = light.color * area_radiance_from_power(light.power, area);
        }
        best_t = t;
        found = true;
        out->radiance = radiance;
        out->light_pdf = selection_pdf(light_emitter_[i]) * t * t / (-denom * area);
    }
    return found;
}

std::vector<EmissionHit> LightSampler::escaped(const vec3& n, const vec3& wi,
                                               bool camera_ray) const {
    std::vector<EmissionHit> hits;
    const vec3 world = scene_->world().radiance();
    if (glm::any(glm::greaterThan(world, vec3(0.0f))))
        hits.push_back({world, world_emitter_ != kInvalidId
                                   ? selection_pdf(world_emitter_) * world_pdf(n, wi)
                                   : 0.0f});
    for (uint32_t i = 0; i < scene_->lights().size(); ++i) {
        const Light& light = scene_->lights()[i];
        if (light_emitter_[i] == kInvalidId || light.type != LightType::Sun || light.angle <= 0.0f)
            continue;
        if (camera_ray && !light.visible_camera) continue;
        const float cos_max = std::cos(0.5f * light.angle);
        if (glm::dot(wi, -light.direction()) < cos_max) continue;
        const float solid_angle = kTwoPi * (1.0f - cos_max);
        hits.push_back({light.color * (light.strength / solid_angle),
                        selection_pdf(light_emitter_[i]) / solid_angle});
    }
    return hits;
}

EmissionHit LightSampler::triangle_emission(const Hit& hit, const vec3& wi) const {
    const auto found = triangle_emitter_.find(triangle_key(hit.instance_id, hit.triangle_id));
    if (found == triangle_emitter_.end()) return {};
    const EmissiveTriangle& tri = scene_->emissive_triangles()[emitters_[found->second].index];
    const float cos_light = std::fabs(glm::dot(wi, glm::normalize(hit.geometric_normal)));
    if (cos_light <= 0.0f) return {};
    return {tri.radiance, selection_pdf(found->second) * hit.t * hit.t / (cos_light * tri.area)};
}

}  // namespace shgi
