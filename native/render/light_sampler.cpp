#include "render/light_sampler.h"

#include <emmintrin.h>

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

// Whether p is on the side the plane through `center` with normal `axis` faces.
bool in_front_of_plane(const vec3& p, const vec3& center, const vec3& axis) {
    return glm::dot(p - center, axis) > 0.0f;
}

}  // namespace

float spot_attenuation(const Light& light, float cos_angle) {
    const float cos_half = std::cos(0.5f * light.spot_size);
    const float t = cos_angle - cos_half;
    if (t <= 0.0f) return 0.0f;
    const float smooth = (1.0f - cos_half) * light.spot_blend;
    const float cone = light.spot_cone_cosine ? cos_angle : 1.0f;
    if (smooth > 0.0f && t < smooth) return cone * smoothstep01(t / smooth);
    return cone;
}

bool is_round(AreaShape shape) { return shape == AreaShape::Disk || shape == AreaShape::Ellipse; }

void area_half_axes(const Light& light, vec3* ex, vec3* ey) {
    const bool square = light.shape == AreaShape::Square || light.shape == AreaShape::Disk;
    const float size_y = square ? light.size_x : light.size_y;
    *ex = vec3(light.world_from_light[0]) * (0.5f * light.size_x);
    *ey = vec3(light.world_from_light[1]) * (0.5f * size_y);
}

bool area_light_crossing(const Light& light, const vec3& p, const vec3& wi, float* t,
                         float* cos_axis) {
    const vec3 center = light.position();
    const vec3 axis = light.direction();
    const float denom = glm::dot(wi, axis);
    if (denom == 0.0f || !std::isfinite(denom)) return false;
    const float distance = glm::dot(center - p, axis) / denom;
    if (!(distance > 0.0f)) return false;
    vec3 ex, ey;
    area_half_axes(light, &ex, &ey);
    const vec3 q = p + distance * wi - center;
    const float s = glm::dot(q, ex) / glm::dot(ex, ex);
    const float r = glm::dot(q, ey) / glm::dot(ey, ey);
    const bool inside = is_round(light.shape) ? s * s + r * r <= 1.0f
                                              : std::fabs(s) <= 1.0f && std::fabs(r) <= 1.0f;
    if (!inside) return false;
    *t = distance;
    *cos_axis = denom;
    return true;
}

std::vector<Portal> scene_portals(const Scene& scene) {
    std::vector<Portal> portals;
    for (uint32_t i = 0; i < scene.lights().size(); ++i) {
        const Light& light = scene.lights()[i];
        const float area = light.portal ? area_light_area(light) : 0.0f;
        if (area > 0.0f) portals.push_back({i, area});
    }
    return portals;
}

bool in_front_of_area_light(const Light& light, const vec3& p) {
    return in_front_of_plane(p, light.position(), light.direction());
}

vec3 area_light_point(const Light& light, const vec2& u) {
    vec3 ex, ey;
    area_half_axes(light, &ex, &ey);
    const vec2 local = is_round(light.shape) ? sample_uniform_disk(u) : 2.0f * u - vec2(1.0f);
    return light.position() + local.x * ex + local.y * ey;
}

float area_light_area(const Light& light) {
    vec3 ex, ey;
    area_half_axes(light, &ex, &ey);
    const float rectangle = 4.0f * glm::length(glm::cross(ex, ey));
    return is_round(light.shape) ? kEllipseAreaFactor * rectangle : rectangle;
}

namespace {

// What the light tree knows of a scene light (LightSampler's constructor skips portals and
// dark lights): its extent, emission cone and intensity along its axis (W/sr, luminance).
LightBounds light_bounds(const Light& light) {
    LightBounds b;
    const float colour = luminance(light.color);
    if (light.type == LightType::Area) {
        vec3 ex, ey;
        area_half_axes(light, &ex, &ey);
        for (const float sx : {-1.0f, 1.0f})
            for (const float sy : {-1.0f, 1.0f}) b.bounds.extend(light.position() + sx * ex + sy * ey);
        b.axis = light.direction();
        b.theta_o = 0.0f;          // one-sided Lambertian emitter
        b.theta_e = kPi / 2.0f;
        b.energy = colour * light.power / 4.0f;  // L A along the axis, L = P / (4 A)
        return b;
    }
    const vec3 r(light.radius);
    b.bounds.extend(light.position() - r);
    b.bounds.extend(light.position() + r);
    b.energy = colour * point_intensity_from_power(light.power);
    if (light.type == LightType::Spot) {
        b.axis = light.direction();
        b.theta_o = std::min(0.5f * light.spot_size, kPi);
        b.theta_e = 0.0f;
    }
    return b;
}

LightBounds triangle_bounds(const EmissiveTriangle& tri) {
    LightBounds b;
    for (const vec3& v : {tri.p0, tri.p1, tri.p2}) b.bounds.extend(v);
    b.energy = luminance(tri.radiance) * tri.area;  // two-sided: omnidirectional cone
    return b;
}

}  // namespace

LightSampler::LightSampler(const Scene& scene, WorldSampling world_sampling, bool sample_world,
                           int light_splits, bool sample_lights)
    : scene_(&scene), world_sampling_(world_sampling), light_splits_(light_splits) {
    if (!scene.committed())
        throw InvalidArgument("LightSampler: the scene is not committed; call commit() first");
    if (light_splits < 1 || light_splits > kMaxLightSplits)
        throw InvalidArgument(format_message("LightSampler: light_splits is ", light_splits,
                                             "; it must be in [1, ", kMaxLightSplits, "]"));
    // Weights only steer selection; any positive weights keep the estimator unbiased. Local
    // emitters weigh by intensity (the tree divides by distance squared), distant ones by
    // irradiance, so the two compare as irradiance estimates at the shading point.
    light_emitter_.assign(scene.lights().size(), kInvalidId);
    light_active_.assign(scene.lights().size(), 0);
    area_emission_.resize(scene.lights().size());
    for (uint32_t i = 0; i < scene.lights().size(); ++i) {
        const Light& light = scene.lights()[i];
        if (light.portal) continue;  // marks an opening: see scene_portals
        const bool sun = light.type == LightType::Sun;
        const LightBounds bounds = sun ? LightBounds{} : light_bounds(light);
        const float weight = sun ? luminance(light.color) * light.strength : bounds.energy;
        if (!(weight > 0.0f)) continue;
        light_active_[i] = 1;
        if (sample_lights) {
            light_emitter_[i] = uint32_t(emitters_.size());
            if (sun)
                add_distant(Kind::Light, i, weight);
            else
                add_local(Kind::Light, i, bounds);
        }
        if (light.type != LightType::Area) continue;
        AreaEmission& emission = area_emission_[i];
        emission.normal = area_emit_normal(light);
        emission.area = area_light_area(light);
        emission.radiance = light.color * area_radiance_from_power(light.power, emission.area);
    }
    for (uint32_t i = 0; i < scene.lights().size(); ++i) {
        const Light& light = scene.lights()[i];
        const bool disk = (light.type == LightType::Point || light.type == LightType::Spot) &&
                          light.radius > 0.0f;
        if (!light_active_[i] || !(disk || light.type == LightType::Area)) continue;
        crossable_lights_[0].push_back(i);
        if (light.visible_camera) crossable_lights_[1].push_back(i);
    }
    const auto& triangles = scene.emissive_triangles();
    triangle_emitter_.assign(triangles.size(), kInvalidId);
    instance_emits_.assign(scene.instances().size(), 0);
    for (uint32_t i = 0; i < triangles.size(); ++i) {
        const LightBounds bounds = triangle_bounds(triangles[i]);
        if (!(bounds.energy > 0.0f)) continue;
        emissive_index_[triangle_key(triangles[i].instance_id, triangles[i].triangle_id)] = i;
        instance_emits_[triangles[i].instance_id] = 1;
        if (!sample_lights) continue;
        triangle_emitter_[i] = uint32_t(emitters_.size());
        add_local(Kind::Triangle, i, bounds);
    }
    // The world's irradiance on a surface open to it.
    const float world_weight = luminance(scene.world().radiance()) * kPi;
    if (world_weight > 0.0f && sample_world) {
        world_emitter_ = uint32_t(emitters_.size());
        add_distant(Kind::World, 0, world_weight);
    }
    portals_ = scene_portals(scene);
    tree_ = LightTree(local_bounds_);
    if (!distant_weights_.empty()) distant_ = DiscreteDistribution(distant_weights_);
    // sample_split_lanes' case: local_probability() is 1, the tree's one leaf a rectangle.
    const uint32_t only = tree_.only_emitter();
    if (only != kInvalidId && distant_total_ <= 0.0f) {
        const Emitter& emitter = emitters_[local_emitter_[only]];
        if (emitter.kind == Kind::Light) {
            const Light& light = scene.lights()[emitter.index];
            if (light.type == LightType::Area && !is_round(light.shape) &&
                is_finite(area_emission_[emitter.index].radiance))
                one_rectangle_ = emitter.index;
        }
    }
}

void LightSampler::add_local(Kind kind, uint32_t index, const LightBounds& bounds) {
    emitters_.push_back({kind, index, uint32_t(local_bounds_.size()), false});
    local_bounds_.push_back(bounds);
    local_emitter_.push_back(uint32_t(emitters_.size() - 1));
}

void LightSampler::add_distant(Kind kind, uint32_t index, float irradiance) {
    emitters_.push_back({kind, index, uint32_t(distant_weights_.size()), true});
    distant_weights_.push_back(irradiance);
    distant_emitter_.push_back(uint32_t(emitters_.size() - 1));
    distant_total_ += irradiance;
}

float LightSampler::local_probability(const vec3& p) const {
    if (tree_.empty()) return 0.0f;
    if (distant_total_ <= 0.0f) return 1.0f;
    const float local = tree_.importance(p);
    return local / (local + distant_total_);
}

float LightSampler::selection_pdf(uint32_t emitter, const vec3& p) const {
    const Emitter& e = emitters_[emitter];
    if (e.distant) return (1.0f - local_probability(p)) * distant_.pdf(e.group_index);
    return local_probability(p) * tree_.pmf(p, e.group_index, light_splits_);
}

bool LightSampler::sample(const vec3& p, const vec3& n, float u_select, const vec2& u,
                          LightSample* out) const {
    if (light_splits_ != 1)
        throw Internal("LightSampler::sample on a sampler with light_splits > 1: its selection "
                       "pdfs are those of sample_split");
    return sample_split(p, n, u_select, u, out) == 1;
}

int LightSampler::sample_split(const vec3& p, const vec3& n, float u_select, const vec2& u,
                               LightSample* out) const {
    if (empty()) return 0;
    const float p_local = local_probability(p);
    if (u_select < p_local) {
        uint32_t local[kMaxLightSplits];
        float pmf[kMaxLightSplits];
        const int count = tree_.sample_split(p, std::min(u_select / p_local, kOneMinusEpsilon),
                                             light_splits_, local, pmf);
        int written = 0;
        for (int i = 0; i < count; ++i) {
            if (!sample_emitter(local_emitter_[local[i]], p, n, u, &out[written])) continue;
            out[written].pdf *= p_local * pmf[i];
            if (out[written].pdf > 0.0f && is_finite(out[written].radiance)) ++written;
        }
        return written;
    }
    const float u_distant = std::min((u_select - p_local) / (1.0f - p_local), kOneMinusEpsilon);
    const uint32_t distant = distant_.sample(u_distant);
    if (!sample_emitter(distant_emitter_[distant], p, n, u, out)) return 0;
    out->pdf *= (1.0f - p_local) * distant_.pdf(distant);
    return out->pdf > 0.0f && is_finite(out->radiance) ? 1 : 0;
}

// sample_split's path for one rectangle (local_probability 1, the tree's one leaf with pmf 1
// where its importance is positive, sample_area with its half axes from area_light_point), each
// lane the scalar operations in their order.
void LightSampler::sample_split_lanes(size_t count, const float* x, const float* y,
                                      const float* z, const float* u_select, const float* ux,
                                      const float* uy, LightSample* out, int8_t* written) const {
    if (one_rectangle_ == kInvalidId)
        throw Internal("LightSampler::sample_split_lanes on a sampler that is not one rectangle");
    const Light& light = scene_->lights()[one_rectangle_];
    const AreaEmission& emission = area_emission_[one_rectangle_];
    vec3 ex, ey;
    area_half_axes(light, &ex, &ey);
    const vec3 center = light.position();
    const __m128 nx = _mm_set1_ps(emission.normal.x), ny = _mm_set1_ps(emission.normal.y),
                 nz = _mm_set1_ps(emission.normal.z);
    const __m128 cx = _mm_set1_ps(center.x), cy = _mm_set1_ps(center.y),
                 cz = _mm_set1_ps(center.z);
    const __m128 zero = _mm_setzero_ps(), two = _mm_set1_ps(2.0f), one = _mm_set1_ps(1.0f);
    const __m128 area = _mm_set1_ps(emission.area), sign = _mm_set1_ps(-0.0f);
    // p_local * pmf as sample_split multiplies the pdf by it: 1 * 1.
    const __m128 selection = _mm_set1_ps(1.0f * 1.0f);
    // area_light_point: (position + local.x ex) + local.y ey, local = 2 u - 1.
    const auto point = [](float c, float e_x, float e_y, __m128 lx, __m128 ly) {
        return _mm_add_ps(_mm_add_ps(_mm_set1_ps(c), _mm_mul_ps(lx, _mm_set1_ps(e_x))),
                          _mm_mul_ps(ly, _mm_set1_ps(e_y)));
    };
    for (size_t j = 0; j < count; j += 4) {
        // A short last group repeats its last lane.
        alignas(16) float tail[6][4];
        const float* in[6] = {x + j, y + j, z + j, ux + j, uy + j, u_select + j};
        const size_t used = std::min<size_t>(4, count - j);
        if (used < 4) {
            for (int c = 0; c < 6; ++c) {
                for (size_t k = 0; k < 4; ++k) tail[c][k] = in[c][std::min(k, used - 1)];
                in[c] = tail[c];
            }
        }
        alignas(16) float importance[4];
        tree_.importance4(in[0], in[1], in[2], importance);
        const __m128 px = _mm_loadu_ps(in[0]), py = _mm_loadu_ps(in[1]),
                     pz = _mm_loadu_ps(in[2]);
        // in_front_of_plane: glm::dot(p - center, normal) > 0.
        const __m128 front = _mm_cmpgt_ps(
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_sub_ps(px, cx), nx),
                                  _mm_mul_ps(_mm_sub_ps(py, cy), ny)),
                       _mm_mul_ps(_mm_sub_ps(pz, cz), nz)),
            zero);
        const __m128 lx = _mm_sub_ps(_mm_mul_ps(two, _mm_loadu_ps(in[3])), one);
        const __m128 ly = _mm_sub_ps(_mm_mul_ps(two, _mm_loadu_ps(in[4])), one);
        const __m128 ox = _mm_sub_ps(point(center.x, ex.x, ey.x, lx, ly), px);
        const __m128 oy = _mm_sub_ps(point(center.y, ex.y, ey.y, lx, ly), py);
        const __m128 oz = _mm_sub_ps(point(center.z, ex.z, ey.z, lx, ly), pz);
        const __m128 distance = _mm_sqrt_ps(
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(ox, ox), _mm_mul_ps(oy, oy)), _mm_mul_ps(oz, oz)));
        const __m128 wx = _mm_div_ps(ox, distance), wy = _mm_div_ps(oy, distance),
                     wz = _mm_div_ps(oz, distance);
        // -glm::dot(wi, normal): a sign flip, exact.
        const __m128 cos_light = _mm_xor_ps(
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(wx, nx), _mm_mul_ps(wy, ny)), _mm_mul_ps(wz, nz)),
            sign);
        const __m128 pdf = _mm_mul_ps(
            _mm_div_ps(_mm_mul_ps(distance, distance), _mm_mul_ps(cos_light, area)), selection);
        // sample_area fails behind the light or where cos_light <= 0 (NaN goes on), the tree
        // where the importance is not positive, sample_split drops a pdf that is not positive.
        const __m128 kept = _mm_and_ps(
            _mm_and_ps(_mm_and_ps(front, _mm_cmpnle_ps(cos_light, zero)),
                       _mm_cmpgt_ps(_mm_load_ps(importance), zero)),
            _mm_cmpgt_ps(pdf, zero));
        // The tree's choice needs u_select below p_local (1): another lane is sample_split's.
        const __m128 tree = _mm_cmplt_ps(_mm_loadu_ps(in[5]), one);
        alignas(16) float sx[4], sy[4], sz[4], sd[4], spdf[4];
        _mm_store_ps(sx, wx);
        _mm_store_ps(sy, wy);
        _mm_store_ps(sz, wz);
        _mm_store_ps(sd, distance);
        _mm_store_ps(spdf, pdf);
        const int kept_mask = _mm_movemask_ps(kept), tree_mask = _mm_movemask_ps(tree);
        for (size_t k = 0; k < used; ++k) {
            if (((tree_mask >> k) & 1) == 0) {
                written[j + k] = -1;
                continue;
            }
            written[j + k] = int8_t((kept_mask >> k) & 1);
            if (written[j + k] == 0) continue;
            LightSample& sample = out[j + k];
            sample.wi = vec3(sx[k], sy[k], sz[k]);
            sample.distance = sd[k];
            sample.radiance = emission.radiance;
            sample.pdf = spdf[k];
            sample.delta = false;
        }
    }
}

bool LightSampler::sample_emitter(uint32_t chosen, const vec3& p, const vec3& n, const vec2& u,
                                  LightSample* out) const {
    const Emitter& emitter = emitters_[chosen];
    if (emitter.kind == Kind::Light) return sample_light(emitter.index, p, u, out);
    if (emitter.kind == Kind::Triangle)
        return sample_triangle(scene_->emissive_triangles()[emitter.index], p, u, out);
    return sample_world(p, n, u, out);
}

bool LightSampler::sample_light(uint32_t index, const vec3& p, const vec2& u,
                                LightSample* out) const {
    const Light& light = scene_->lights()[index];
    switch (light.type) {
        case LightType::Point:
        case LightType::Spot: return sample_point(light, p, u, out);
        case LightType::Area: return sample_area(index, p, u, out);
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

bool LightSampler::sample_area(uint32_t index, const vec3& p, const vec2& u,
                               LightSample* out) const {
    const Light& light = scene_->lights()[index];
    const AreaEmission& emission = area_emission_[index];
    // Behind the one-sided emitter (in_front_of_area_light with the axis computed once).
    if (!in_front_of_plane(p, light.position(), emission.normal)) return false;
    const vec3 offset = area_light_point(light, u) - p;
    out->distance = glm::length(offset);
    out->wi = offset / out->distance;
    const float cos_light = -glm::dot(out->wi, emission.normal);
    if (cos_light <= 0.0f) return false;
    out->radiance = emission.radiance;
    out->pdf = out->distance * out->distance / (cos_light * emission.area);
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

bool LightSampler::sample_world(const vec3& p, const vec3& n, vec2 u, LightSample* out) const {
    const uint32_t facing = facing_portal_count(p);
    if (facing > 0 && u.x < kPortalFraction) {
        // Through the k-th facing portal, u.x rescaled to pick k and then reused.
        const float scaled = u.x / kPortalFraction * float(facing);
        const uint32_t k = std::min(uint32_t(scaled), facing - 1);
        u.x = std::min(scaled - float(k), kOneMinusEpsilon);
        const vec3 offset = area_light_point(facing_portal(p, k), u) - p;
        const float distance = glm::length(offset);
        if (!(distance > 0.0f)) return false;
        out->wi = offset / distance;
    } else {
        if (facing > 0)
            u.x = std::min((u.x - kPortalFraction) / (1.0f - kPortalFraction), kOneMinusEpsilon);
        const vec3 local = world_sampling_ == WorldSampling::Cosine ? sample_cosine_hemisphere(u)
                                                                    : sample_uniform_sphere(u);
        out->wi = Frame::from_z(n).to_world(local);
    }
    out->distance = kInfinity;
    out->radiance = scene_->world().radiance();
    out->pdf = world_pdf(p, n, out->wi);
    out->delta = false;
    return out->pdf > 0.0f;
}

uint32_t LightSampler::facing_portal_count(const vec3& p) const {
    uint32_t count = 0;
    for (const Portal& portal : portals_)
        count += in_front_of_area_light(scene_->lights()[portal.light], p);
    return count;
}

const Light& LightSampler::facing_portal(const vec3& p, uint32_t k) const {
    for (const Portal& portal : portals_) {
        const Light& light = scene_->lights()[portal.light];
        if (in_front_of_area_light(light, p) && k-- == 0) return light;
    }
    throw Internal("LightSampler::facing_portal: fewer facing portals than counted");
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

float LightSampler::world_pdf(const vec3& p, const vec3& n, const vec3& wi) const {
    const float base = world_sampling_ == WorldSampling::Uniform
                           ? sample_uniform_sphere_pdf()
                           : std::max(0.0f, glm::dot(n, wi)) * kInvPi;
    uint32_t facing = 0;
    float through_portals = 0.0f;  // sum over facing portals of their solid-angle pdfs
    for (const Portal& portal : portals_) {
        const Light& light = scene_->lights()[portal.light];
        if (!in_front_of_area_light(light, p)) continue;
        ++facing;
        float t, cos_axis;
        if (area_light_crossing(light, p, wi, &t, &cos_axis) && cos_axis < 0.0f)
            through_portals += t * t / (-cos_axis * portal.area);
    }
    if (facing == 0) return base;
    return kPortalFraction * through_portals / float(facing) + (1.0f - kPortalFraction) * base;
}

bool LightSampler::intersect_lights(const vec3& p, const vec3& wi, float t_max, bool camera_ray,
                                    EmissionHit* out) const {
    float best_t = t_max;
    bool found = false;
    // Only the lights this loop can meet (emitting disks and area lights; for a camera ray,
    // those it sees), in scene order: the others were skipped at the loop's top.
    for (const uint32_t i : crossable_lights_[camera_ray ? 1 : 0]) {
        const Light& light = scene_->lights()[i];  // portals do not emit: not listed
        const bool disk = (light.type == LightType::Point || light.type == LightType::Spot) &&
                          light.radius > 0.0f;
        float t, cos_light, area;
        vec3 radiance;
        if (disk) {
            // The disk faces p: its plane is perpendicular to p - centre.
            const vec3 center = light.position();
            const vec3 normal = glm::normalize(p - center);
            const float denom = glm::dot(wi, normal);
            if (!(denom < 0.0f)) continue;
            t = glm::dot(center - p, normal) / denom;
            const vec3 q = p + t * wi - center;
            if (glm::dot(q, q) > light.radius * light.radius) continue;
            cos_light = -denom;
            area = kPi * light.radius * light.radius;
            radiance = light.color * point_intensity_from_power(light.power) / area;
            if (light.type == LightType::Spot)
                radiance *= spot_attenuation(light, glm::dot(light.direction(), -wi));
        } else if (light.type == LightType::Area) {
            float cos_axis;
            if (!area_light_crossing(light, p, wi, &t, &cos_axis) || !(cos_axis < 0.0f))
                continue;  // missed, or met from behind (one-sided)
            cos_light = -cos_axis;
            area = area_light_area(light);
            radiance = light.color * area_radiance_from_power(light.power, area);
        } else {
            continue;
        }
        if (!(t > 0.0f && t < best_t)) continue;
        best_t = t;
        found = true;
        out->radiance = radiance;
        out->light_pdf = light_selection_pdf(i, p) * t * t / (cos_light * area);
    }
    return found;
}

std::vector<EmissionHit> LightSampler::escaped(const vec3& p, const vec3& n, const vec3& wi,
                                               bool camera_ray) const {
    std::vector<EmissionHit> hits;
    for_each_escaped(p, n, wi, camera_ray, [&](const EmissionHit& hit) { hits.push_back(hit); });
    return hits;
}

EmissionHit LightSampler::triangle_emission(const vec3& p, const Hit& hit, const vec3& wi) const {
    if (!instance_emits(hit)) return {};  // spares a hash lookup per hit on other instances
    const auto found = emissive_index_.find(triangle_key(hit.instance_id, hit.triangle_id));
    if (found == emissive_index_.end()) return {};
    const EmissiveTriangle& tri = scene_->emissive_triangles()[found->second];
    const float cos_light = std::fabs(glm::dot(wi, glm::normalize(hit.geometric_normal)));
    if (cos_light <= 0.0f) return {};
    const uint32_t emitter = triangle_emitter_[found->second];
    if (emitter == kInvalidId) return {tri.radiance, 0.0f};  // not sampled (sample_lights)
    return {tri.radiance, selection_pdf(emitter, p) * hit.t * hit.t / (cos_light * tri.area)};
}

}  // namespace shgi
