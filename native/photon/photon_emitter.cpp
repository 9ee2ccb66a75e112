#include "photon/photon_emitter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "render/light_sampler.h"
#include "render/shading.h"
#include "util/error.h"

namespace shgi {
namespace {

// Sun and world disks sit this many bounding radii from the centre: clear of the sphere (and of
// geometry touching it) by a full radius, so no rounding puts an origin inside the scene.
constexpr float kDiskDistanceInRadii = 2.0f;

// Moments of the smoothstep S(t) = 3t^2 - 2t^3 on [0, 1]: integral of S and of t S.
constexpr float kSmoothstepMean = 0.5f;
constexpr float kSmoothstepFirstMoment = 7.0f / 20.0f;

vec3 light_power(const Light& light, float bounding_radius) {
    if (light.portal) return vec3(0.0f);  // marks an opening, emits nothing
    const float disk_area = kPi * bounding_radius * bounding_radius;
    switch (light.type) {
        case LightType::Point: return light.color * light.power;
        case LightType::Spot: return spot_light_power(light);
        case LightType::Sun: return light.color * (light.strength * disk_area);
        case LightType::Area:
            // Radiance P / (4A) over the area A, Lambertian one-sided: pi L A.
            return light.color * (kPi * light.power / 4.0f);
    }
    return vec3(0.0f);
}

// The selection probabilities of emitters of flux `weights` (luminance) grouped into `lamps`:
// (1 - u) x each one's flux share + u / (lamps) x its flux share within its lamp. With one lamp
// that is the flux share: `weights` are returned as they are (the same distribution, bit for bit).
std::vector<float> lamp_share_weights(const std::vector<float>& weights,
                                      const std::vector<uint64_t>& lamps, float u) {
    std::map<uint64_t, double> lamp_flux;
    double total = 0.0;
    for (size_t i = 0; i < weights.size(); ++i) {
        lamp_flux[lamps[i]] += double(weights[i]);
        total += double(weights[i]);
    }
    if (lamp_flux.size() == 1) return weights;
    const double per_lamp = double(u) / double(lamp_flux.size());
    std::vector<float> mixed(weights.size());
    for (size_t i = 0; i < weights.size(); ++i)
        mixed[i] = float((1.0 - double(u)) * double(weights[i]) / total +
                         per_lamp * double(weights[i]) / lamp_flux[lamps[i]]);
    return mixed;
}

}  // namespace

vec3 spot_light_power(const Light& light) {
    // Integral over the cone of the attenuation, in c = cos(a), with s = smoothstep((c -
    // cos_half) / smooth): with the cone cosine (spot_cone_cosine), c s, which is
    // 2 pi [ smooth (cos_half S0 + smooth S1) + (1 - (cos_half + smooth)^2) / 2 ]; without it, s,
    // which is 2 pi [ smooth S0 + 1 - (cos_half + smooth) ].
    const float cos_half = std::cos(0.5f * light.spot_size);
    const float smooth = (1.0f - cos_half) * light.spot_blend;
    const float edge = cos_half + smooth;
    const float cone_integral =
        light.spot_cone_cosine
            ? kTwoPi * (smooth * (cos_half * kSmoothstepMean + smooth * kSmoothstepFirstMoment) +
                        0.5f * (1.0f - edge * edge))
            : kTwoPi * (smooth * kSmoothstepMean + 1.0f - edge);
    return light.color * (point_intensity_from_power(light.power) * cone_integral);
}

PhotonEmitter::PhotonEmitter(const Scene& scene, float light_share_uniform) : scene_(&scene) {
    if (!scene.committed())
        throw InvalidArgument("PhotonEmitter: the scene is not committed; call commit() first");
    if (!(light_share_uniform >= 0.0f && light_share_uniform <= 1.0f))
        throw InvalidArgument(format_message("PhotonEmitter: light_share_uniform is ",
                                             light_share_uniform, "; it must be in [0, 1]"));
    if (!scene.empty()) {
        const Bounds3 bounds = scene.bounds();
        bounding_center_ = 0.5f * (bounds.lower + bounds.upper);
        bounding_radius_ = scene.bounding_radius();
    }
    std::vector<float> weights;
    // Per emitter, its lamp (see the header): lights and the world one each, an emissive
    // object's triangles one per instance.
    std::vector<uint64_t> lamps;
    auto add = [&](Kind kind, uint32_t index, const vec3& power, uint64_t lamp) {
        const float weight = luminance(power);
        if (!(weight > 0.0f)) return;  // zero flux (or an empty scene's sun and world)
        emitters_.push_back({kind, index, power});
        weights.push_back(weight);
        lamps.push_back(lamp);
        total_power_ += power;
    };
    // Lamp keys: lights by index, emissive objects by instance after them, the world last.
    const uint64_t light_count = scene.lights().size();
    for (uint32_t i = 0; i < scene.lights().size(); ++i)
        add(Kind::Light, i, light_power(scene.lights()[i], bounding_radius_), i);
    portals_ = scene_portals(scene);
    const auto& triangles = scene.emissive_triangles();
    for (uint32_t i = 0; i < triangles.size(); ++i)
        add(Kind::Triangle, i, triangles[i].radiance * (kTwoPi * triangles[i].area),
            light_count + triangles[i].instance_id);
    const float disk_area = kPi * bounding_radius_ * bounding_radius_;
    add(Kind::World, 0, scene.world().radiance() * (kFourPi * disk_area),
        std::numeric_limits<uint64_t>::max());
    if (weights.empty()) return;
    if (light_share_uniform > 0.0f)
        weights = lamp_share_weights(weights, lamps, light_share_uniform);
    distribution_ = DiscreteDistribution(weights);
}

bool PhotonEmitter::emit(uint64_t index, uint64_t count, Pcg32& rng, EmittedPhoton* out) const {
    if (empty()) return false;
    const double stratum = (double(index) + double(rng.next_float())) / double(count);
    const float u_select = std::min(float(stratum), kOneMinusEpsilon);
    const uint32_t chosen = distribution_.sample(u_select);
    if (!sample_emitter(emitters_[chosen], rng, out)) return false;
    out->power /= float(double(count) * double(distribution_.pdf(chosen)));
    return is_finite(out->power) && max_component(out->power) > 0.0f;
}

bool PhotonEmitter::sample_emitter(const Emitter& emitter, Pcg32& rng, EmittedPhoton* out) const {
    *out = EmittedPhoton{};
    switch (emitter.kind) {
        case Kind::Light:
            sample_light(scene_->lights()[emitter.index], emitter.power, rng, out);
            break;
        case Kind::Triangle:
            sample_triangle(scene_->emissive_triangles()[emitter.index], emitter.power, rng, out);
            break;
        case Kind::World:
            sample_world(rng, out);
            break;
    }
    return max_component(out->power) > 0.0f;
}

void PhotonEmitter::sample_light(const Light& light, const vec3& power, Pcg32& rng,
                                 EmittedPhoton* out) const {
    const vec2 u = rng.next_vec2();
    out->power = power;
    switch (light.type) {
        case LightType::Point:
            out->ray.origin = light.position();
            out->ray.direction = sample_uniform_sphere(u);
            break;
        case LightType::Spot: {
            // Uniform in the cone: the sample's flux estimate is I(w) / pdf(w), I the spot's
            // attenuated intensity.
            const float cos_half = std::cos(0.5f * light.spot_size);
            const vec3 local = sample_uniform_cone(u, cos_half);
            out->ray.origin = light.position();
            out->ray.direction = Frame::from_z(light.direction()).to_world(local);
            out->power = light.color * (point_intensity_from_power(light.power) *
                                        spot_attenuation(light, local.z) /
                                        sample_uniform_cone_pdf(cos_half));
            break;
        }
        case LightType::Sun:
            sample_sun(light, u, rng, out);
            break;
        case LightType::Area:
            out->ray.origin = area_light_point(light, u);
            out->ray.direction = Frame::from_z(light.direction())
                                     .to_world(sample_cosine_hemisphere(rng.next_vec2()));
            break;
    }
}

void PhotonEmitter::sample_triangle(const EmissiveTriangle& triangle, const vec3& power,
                                    Pcg32& rng, EmittedPhoton* out) const {
    const vec3 b = sample_uniform_triangle(rng.next_vec2());
    const vec3 position = b.x * triangle.p0 + b.y * triangle.p1 + b.z * triangle.p2;
    vec3 normal = glm::normalize(glm::cross(triangle.p1 - triangle.p0, triangle.p2 - triangle.p0));
    if (rng.next_float() < 0.5f) normal = -normal;  // two-sided: each side emits half
    out->ray.origin = offset_origin(position, normal);  // off its own triangle
    out->ray.direction = Frame::from_z(normal).to_world(sample_cosine_hemisphere(rng.next_vec2()));
    out->power = power;
}

void PhotonEmitter::sample_sun(const Light& light, const vec2& u, Pcg32& rng,
                               EmittedPhoton* out) const {
    const vec3 axis = light.direction();
    const float cos_max = light.angle > 0.0f ? std::cos(0.5f * light.angle) : 1.0f;
    const vec3 direction =
        light.angle > 0.0f ? Frame::from_z(axis).to_world(sample_uniform_cone(u, cos_max)) : axis;
    if (draw_portal_strategy(rng)) {
        const Light& portal = draw_portal(rng);
        const vec3 point = area_light_point(portal, rng.next_vec2());
        if (glm::dot(direction, portal.direction()) <= 0.0f) return;  // cannot enter: wasted
        out->ray = ray_through_point(direction, point);
    } else {
        out->ray = ray_through_bounding_disk(direction, rng.next_vec2());
    }
    // Radiance over the cone's density is the sun's strength S (irradiance facing it).
    const float density = mixed(portal_density(out->ray, false), disk_density(out->ray));
    if (density > 0.0f) out->power = light.color * (light.strength / density);
}

void PhotonEmitter::sample_world(Pcg32& rng, EmittedPhoton* out) const {
    out->from_world = true;
    if (draw_portal_strategy(rng)) {
        const Light& portal = draw_portal(rng);
        const vec3 point = area_light_point(portal, rng.next_vec2());
        const vec3 direction =
            Frame::from_z(portal.direction()).to_world(sample_cosine_hemisphere(rng.next_vec2()));
        out->ray = ray_through_point(direction, point);
    } else {
        const vec3 direction = sample_uniform_sphere(rng.next_vec2());
        out->ray = ray_through_bounding_disk(direction, rng.next_vec2());
    }
    const float density = mixed(portal_density(out->ray, true),
                                disk_density(out->ray) * sample_uniform_sphere_pdf());
    if (density > 0.0f) out->power = scene_->world().radiance() / density;
}

bool PhotonEmitter::draw_portal_strategy(Pcg32& rng) const {
    return !portals_.empty() && rng.next_float() < kPortalFraction;
}

const Light& PhotonEmitter::draw_portal(Pcg32& rng) const {
    const size_t count = portals_.size();
    const size_t k = std::min(size_t(rng.next_float() * float(count)), count - 1);
    return scene_->lights()[portals_[k].light];
}

float PhotonEmitter::disk_density(const Ray& ray) const {
    const vec3 offset = ray.origin - bounding_center_;
    const vec3 across = offset - glm::dot(offset, ray.direction) * ray.direction;
    if (glm::dot(across, across) > bounding_radius_ * bounding_radius_) return 0.0f;
    return 1.0f / (kPi * bounding_radius_ * bounding_radius_);
}

float PhotonEmitter::portal_density(const Ray& ray, bool cosine_directions) const {
    float density = 0.0f;
    for (const Portal& portal : portals_) {
        float t, cos_axis;
        if (!area_light_crossing(scene_->lights()[portal.light], ray.origin, ray.direction, &t,
                                 &cos_axis) ||
            !(cos_axis > 0.0f))
            continue;  // misses it, or crosses it outwards
        density += cosine_directions ? kInvPi / portal.area : 1.0f / (portal.area * cos_axis);
    }
    return density / float(std::max<size_t>(portals_.size(), 1));
}

float PhotonEmitter::mixed(float portal, float disk) const {
    if (portals_.empty()) return disk;
    return kPortalFraction * portal + (1.0f - kPortalFraction) * disk;
}

Ray PhotonEmitter::ray_through_point(const vec3& direction, const vec3& point) const {
    Ray ray;
    ray.origin = point - direction * (glm::dot(point - bounding_center_, direction) +
                                      kDiskDistanceInRadii * bounding_radius_);
    ray.direction = direction;
    return ray;
}

Ray PhotonEmitter::ray_through_bounding_disk(const vec3& direction, const vec2& u) const {
    const Frame frame = Frame::from_z(direction);
    const vec2 d = sample_uniform_disk(u) * bounding_radius_;
    Ray ray;
    ray.origin = bounding_center_ - direction * (kDiskDistanceInRadii * bounding_radius_) +
                 d.x * frame.x + d.y * frame.y;
    ray.direction = direction;
    return ray;
}

}  // namespace shgi
