// LightSampler: next-event estimation and emission lookup for every emitter of a Scene, with
// Cycles' (Blender 3.4) unit conventions, and the pdfs multiple importance sampling needs.
//
// Units, as MEASURED against Cycles 3.4.1 (one-off scripts of the calibration work: an
// orthographic camera looking straight down at a Lambert plane of albedo 0.8, one light, 256
// samples, mean pixel L = 0.8/pi * E; each ratio below is measured / predicted):
// - point, power P (W): radiant intensity I = P / (4 pi) W/sr (P = 100 W at h = 2 m:
//   0.50653 vs 0.50661, ratio 0.9998; the candidate P / (4 pi^2) was off by pi).
//   Radius r > 0: a disk of radius r facing the shading point, radiance I / (pi r^2) (r = 0.5 at
//   h = 2: disk 0.9999, sphere I/h^2 0.9411).
// - spot: the point light's I times smoothstep(0, (1 - cos(size/2)) blend, cos(a) - cos(size/2))
//   times cos(a), a = angle from the spot axis (size 60 deg, blend 0.5 at a = 0/10/20/25 deg:
//   ratios 0.9998/0.9998/0.9998/0.9967 with the cos(a) factor; 0.90 at 25 deg without it).
// - sun, strength S (W/m^2): irradiance S on a surface facing it (S = 3 at 0 and 60 deg
//   incidence: ratio 1.0000). Angle > 0: uniform radiance S / Omega over the cone of solid angle
//   Omega = 2 pi (1 - cos(angle/2)), so E = S (1 + cos(angle/2)) / 2 at normal incidence
//   (angle 20 deg: measured 0.99235 S, predicted 0.99240 S; S / (pi tan^2(angle/2)) gives 0.970 S).
// - area, power P (W), area A (m^2; pi a b / 4 for disk/ellipse): one-sided (emits along the
//   light's -Z) Lambertian radiance L = P / (4 A) (disk d = 1 m at 1 m: 0.9995; ellipse 1 x 0.5:
//   0.9994; rectangle 1 x 0.5: 0.9995; the candidate P / (pi A) gave 0.785 = pi/4).
// - emissive triangles: radiance = emission colour x strength, two-sided (camera sees 2.5 for
//   strength 2.5, ratio 1.0000).
// - world: radiance = colour x strength (0.05 x 0.7 seen as 0.0350; a plane of albedo 0.8
//   under it: 0.0280).
// Lights are not occluders and are invisible from behind (area); BSDF rays that hit a point/spot
// disk, an area light, a sun's cone or the world see their radiance, camera rays only when the
// light has visible_camera (Blender's Object.visible_camera, False by default for lights:
// Cycles' camera then sees through it; measured, case light_camera_default).
//
// Portals (Light.portal, Cycles' area light Portal): they emit nothing, are not seen, and change
// only how the world is sampled. For a shading point in front of at least one portal (on the
// side it faces), a world sample goes through a uniformly chosen facing portal (uniform point on
// it) with probability kPortalFraction, and is cosine (or uniform) otherwise; the world's pdf is
// that mixture, so the estimate stays unbiased for light that enters elsewhere. Suns are not
// affected (their cone is sampled directly).
//
// Selection: one emitter per NEE sample, chosen for the shading point p. Local emitters (point,
// spot and area lights, emissive triangles) are chosen by a light tree (render/light_tree.h:
// their distance, orientation and intensity seen from p), distant ones (suns, the world) by
// their irradiance (util DiscreteDistribution); the two groups are weighed by the tree's root
// importance at p against the distant irradiance. With light_splits > 1 (the path tracer's
// PathTracerSettings.light_splits) a next-event estimate is sample_split(): when the local group
// is chosen, one emitter from each node of the tree's cut at p (LightTree::sample_split: lights
// whose distances from p differ widely each get a shadow ray, so a dim lamp beside p is not
// starved by a bright one behind a wall), and selection_pdf() is that of the split. Returned pdfs include that selection
// probability and are per unit solid angle at the shading point; delta emitters (r = 0
// point/spot, angle = 0 sun) return the incident radiance scale (intensity / d^2 or irradiance)
// with delta = true.
#pragma once

#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "render/light_tree.h"
#include "scene/scene.h"
#include "util/math.h"
#include "util/sampling.h"

namespace shgi {

// Share of world samples aimed through portals when a shading point faces at least one.
inline constexpr float kPortalFraction = 0.8f;

// A portal light of a scene (Light.portal with a positive area) and its area.
struct Portal {
    uint32_t light;  // index into Scene::lights()
    float area;      // m^2, area_light_area
};
std::vector<Portal> scene_portals(const Scene& scene);

enum class WorldSampling : uint8_t {
    Cosine,   // cosine-weighted around the shading normal (pdf = cos/pi, 0 below)
    Uniform,  // uniform over the sphere (pdf = 1/(4 pi))
};

struct LightSample {
    vec3 wi{0.0f};             // unit direction from the shading point towards the emitter
    float distance = 0.0f;     // to the sampled point; kInfinity for sun and world
    vec3 radiance{0.0f};       // incident radiance (delta emitters: intensity/d^2 or irradiance)
    float pdf = 0.0f;          // solid-angle pdf including selection; selection prob for deltas
    bool delta = false;
};

// Radiance that a ray meets before its scene hit, with the pdf NEE would have used for it.
struct EmissionHit {
    vec3 radiance{0.0f};
    float light_pdf = 0.0f;  // including selection; 0 when NEE cannot produce this direction
};

class LightSampler {
  public:
    // The scene must be committed. Emitters with zero power are left out; so is the world when
    // sample_world is false (escaped rays still see it, with a light pdf of 0), and so are the
    // scene's lights (point, spot, area, sun) and emissive triangles when sample_lights is
    // false (rays still meet them, with a light pdf of 0: a field that carries their direct
    // light, INSTANT_GI's filter_direct). light_splits: the most emitters one next-event
    // estimate samples, in [1, kMaxLightSplits] (1: one, by sample(); more: by sample_split()).
    LightSampler(const Scene& scene, WorldSampling world_sampling, bool sample_world = true,
                 int light_splits = 1, bool sample_lights = true);

    bool empty() const { return emitters_.empty(); }
    // Emitters NEE can choose (selection_pdf's indices run over [0, emitter_count())).
    size_t emitter_count() const { return emitters_.size(); }

    // Samples an emitter for shading point p with (shading) normal n (used by cosine world
    // sampling only). False when the chosen emitter cannot reach p (behind an area light ...).
    // Only for a sampler made with light_splits = 1 (throws Internal otherwise).
    bool sample(const vec3& p, const vec3& n, float u_select, const vec2& u,
                LightSample* out) const;
    // A next-event estimate of up to light_splits() samples (see the header), written to out[];
    // returns how many. Equal to sample() when light_splits() is 1. Each sample's pdf holds
    // its own selection probability; the estimate is the sum over the samples.
    int sample_split(const vec3& p, const vec3& n, float u_select, const vec2& u,
                     LightSample* out) const;
    int light_splits() const { return light_splits_; }
    // Whether sample_split_lanes applies: the sampler's only emitter is a rectangular (or
    // square) area light with finite radiance, and there is no distant one (a room lit by one
    // panel, as the bench rooms are).
    bool samples_one_rectangle() const { return one_rectangle_ != kInvalidId; }
    // sample_split at `count` points p_i = (x[i], y[i], z[i]) with numbers u_select[i] and
    // (ux[i], uy[i]), bit for bit, four at a time on SSE2 lanes (the preview wave's light
    // stage): written[i] is how many samples sample_split writes (0 or 1, that one in out[i]),
    // or -1 where u_select[i] is not below 1, which the tree does not take and sample_split must
    // handle itself. Only when samples_one_rectangle().
    void sample_split_lanes(size_t count, const float* x, const float* y, const float* z,
                            const float* u_select, const float* ux, const float* uy,
                            LightSample* out, int8_t* written) const;

    // Closest point/spot disk or area light along p + t wi for t in (0, t_max). A camera ray
    // sees only lights with visible_camera.
    bool intersect_lights(const vec3& p, const vec3& wi, float t_max, bool camera_ray,
                          EmissionHit* out) const;
    // Whether intersect_lights can meet any light: an emitting point/spot disk or area light
    // (for a camera ray, one with visible_camera).
    bool has_crossable_lights(bool camera_ray) const {
        return !crossable_lights_[camera_ray ? 1 : 0].empty();
    }
    // What a ray leaving p (normal n) along wi sees when it misses the scene: world and suns
    // (for a camera ray, only suns with visible_camera). Calls add(const EmissionHit&) for each
    // emission separately, so each gets its own MIS weight; nothing is allocated (this runs for
    // every ray that escapes).
    template <typename Add>
    void for_each_escaped(const vec3& p, const vec3& n, const vec3& wi, bool camera_ray,
                          Add&& add) const;
    // The same, collected (tests).
    std::vector<EmissionHit> escaped(const vec3& p, const vec3& n, const vec3& wi,
                                     bool camera_ray) const;
    // An emissive triangle hit at `hit` by a ray from p.
    EmissionHit triangle_emission(const vec3& p, const Hit& hit, const vec3& wi) const;
    // Whether for_each_emission can find any emission along a ray that ends at `hit`: false
    // for a hit on a surface that does not emit where no light can be crossed first (every
    // camera ray of a room whose lamps the camera does not see), which a caller can test
    // inline before the call.
    bool may_emit(const Hit& hit, bool camera_ray) const {
        return !hit.valid() || has_crossable_lights(camera_ray) || instance_emits(hit);
    }
    // Whether the instance `hit` is on holds an emitting triangle (false: triangle_emission is
    // zero there, without a hash lookup).
    bool instance_emits(const Hit& hit) const {
        return hit.instance_id < instance_emits_.size() && instance_emits_[hit.instance_id] != 0;
    }
    // The probability that sample() chooses emitter `emitter` (an index of emitters_) at p.
    float selection_pdf(uint32_t emitter, const vec3& p) const;
    // Whether scene light `light` emits (positive power or strength, not a portal), whether or
    // not next-event estimation samples it.
    bool light_emits(uint32_t light) const { return light_active_[light] != 0; }
    // One sample of scene light `light` alone (no selection: pdf is per unit solid angle, or 1
    // for a delta light) seen from p; false when it cannot reach p. The light must emit.
    bool sample_light(uint32_t light, const vec3& p, const vec2& u, LightSample* out) const;
    // One sample of emissive triangle `triangle` (an index of Scene::emissive_triangles()) alone,
    // a uniform point on it (pdf per unit solid angle, no selection) seen from p; false when it
    // cannot reach p.
    bool sample_emissive_triangle(uint32_t triangle, const vec3& p, const vec2& u,
                                  LightSample* out) const {
        return sample_triangle(scene_->emissive_triangles()[triangle], p, u, out);
    }
    // Everything a ray from p (shading normal n) along wi meets as emission up to its scene hit
    // `hit`: a point/spot disk or area light in front of the hit; else the hit triangle's own
    // emission; else, for a miss, the world and suns (for_each_escaped). Calls
    // add(const EmissionHit&, bool is_world) for each.
    template <typename Add>
    void for_each_emission(const vec3& p, const vec3& n, const vec3& wi, const Hit& hit,
                           bool camera_ray, Add&& add) const;

  private:
    enum class Kind : uint8_t { Light, Triangle, World };
    struct Emitter {
        Kind kind;
        uint32_t index;  // into scene lights / emissive triangles
        uint32_t group_index = 0;  // in the light tree (local) or distant_ (suns, world)
        bool distant = false;
    };
    // The probability of choosing a local emitter (the tree) rather than a distant one at p.
    float local_probability(const vec3& p) const;
    void add_local(Kind kind, uint32_t index, const LightBounds& bounds);
    void add_distant(Kind kind, uint32_t index, float irradiance);  // W/m^2

    // selection_pdf of scene light `light`'s emitter; 0 when next-event estimation leaves it
    // out (sample_lights false).
    float light_selection_pdf(uint32_t light, const vec3& p) const {
        return light_emitter_[light] != kInvalidId ? selection_pdf(light_emitter_[light], p)
                                                   : 0.0f;
    }
    bool sample_point(const Light& light, const vec3& p, const vec2& u, LightSample* out) const;
    bool sample_area(uint32_t index, const vec3& p, const vec2& u, LightSample* out) const;
    bool sample_sun(const Light& light, const vec2& u, LightSample* out) const;
    bool sample_triangle(const EmissiveTriangle& tri, const vec3& p, const vec2& u,
                         LightSample* out) const;
    bool sample_world(const vec3& p, const vec3& n, vec2 u, LightSample* out) const;
    float world_pdf(const vec3& p, const vec3& n, const vec3& wi) const;
    // Portals whose facing side p is on, in scene order; facing_portal(p, k) is the k-th.
    uint32_t facing_portal_count(const vec3& p) const;
    const Light& facing_portal(const vec3& p, uint32_t k) const;

    bool sample_emitter(uint32_t chosen, const vec3& p, const vec3& n, const vec2& u,
                        LightSample* out) const;

    const Scene* scene_;
    WorldSampling world_sampling_;
    int light_splits_ = 1;
    std::vector<Emitter> emitters_;
    std::vector<uint32_t> light_emitter_;  // scene light index -> emitter index (or kInvalidId)
    std::vector<uint8_t> light_active_;    // scene light index -> emits (sampled or not)
    // Per scene light (used for area lights): what sample_area needs that depends on the light
    // alone, computed once instead of per sample.
    struct AreaEmission {
        vec3 normal{0.0f};    // emission axis, light.direction()
        float area = 0.0f;    // m^2, area_light_area
        vec3 radiance{0.0f};  // W m^-2 sr^-1
    };
    std::vector<AreaEmission> area_emission_;
    // (instance << 32 | tri) -> index of Scene::emissive_triangles(), for triangles that emit.
    std::unordered_map<uint64_t, uint32_t> emissive_index_;
    // Per scene instance: 1 when emissive_index_ holds one of its triangles. A hit on any other
    // instance (every hit, in a scene without emissive triangles) skips the hash lookup.
    std::vector<uint8_t> instance_emits_;
    // The scene lights intersect_lights can meet, in scene order: [0] for any ray (emitting
    // point/spot disks and area lights), [1] for camera rays (those of [0] with
    // visible_camera). Rays skip the loop where the list is empty: camera rays in a room whose
    // lamps the camera does not see (Blender's default).
    std::vector<uint32_t> crossable_lights_[2];
    // Per emissive triangle: its emitter, or kInvalidId when next-event estimation leaves it out
    // (no power, or sample_lights false).
    std::vector<uint32_t> triangle_emitter_;
    uint32_t world_emitter_ = kInvalidId;
    std::vector<Portal> portals_;
    LightTree tree_;                          // local emitters
    std::vector<LightBounds> local_bounds_;   // what the tree is built from
    std::vector<uint32_t> local_emitter_;     // tree index -> emitter index
    DiscreteDistribution distant_;            // suns and the world, by irradiance
    std::vector<float> distant_weights_;
    std::vector<uint32_t> distant_emitter_;   // distant_ index -> emitter index
    float distant_total_ = 0.0f;              // W/m^2
    // The scene light sample_split_lanes samples (samples_one_rectangle()), else kInvalidId.
    uint32_t one_rectangle_ = kInvalidId;
};

template <typename Add>
void LightSampler::for_each_escaped(const vec3& p, const vec3& n, const vec3& wi, bool camera_ray,
                                    Add&& add) const {
    const vec3 world = scene_->world().radiance();
    if (glm::any(glm::greaterThan(world, vec3(0.0f))))
        add(EmissionHit{world, world_emitter_ != kInvalidId
                                   ? selection_pdf(world_emitter_, p) * world_pdf(p, n, wi)
                                   : 0.0f});
    for (uint32_t i = 0; i < scene_->lights().size(); ++i) {
        const Light& light = scene_->lights()[i];
        if (!light_active_[i] || light.type != LightType::Sun || light.angle <= 0.0f) continue;
        if (camera_ray && !light.visible_camera) continue;
        const float cos_max = std::cos(0.5f * light.angle);
        if (glm::dot(wi, -light.direction()) < cos_max) continue;
        const float solid_angle = kTwoPi * (1.0f - cos_max);
        add(EmissionHit{light.color * (light.strength / solid_angle),
                        light_selection_pdf(i, p) / solid_angle});
    }
}

template <typename Add>
void LightSampler::for_each_emission(const vec3& p, const vec3& n, const vec3& wi, const Hit& hit,
                                     bool camera_ray, Add&& add) const {
    EmissionHit light_hit;
    // The two tests in front of the calls (has_crossable_lights, instance_emits) answer a
    // camera ray of a room lit by lamps it does not see, on surfaces that do not emit, inline:
    // the calls and their returned hits were ~2% of a preview frame's instructions.
    if (has_crossable_lights(camera_ray) &&
        intersect_lights(p, wi, hit.valid() ? hit.t : kInfinity, camera_ray, &light_hit)) {
        add(light_hit, false);
    } else if (hit.valid()) {
        if (!instance_emits(hit)) return;
        const EmissionHit surface = triangle_emission(p, hit, wi);
        if (surface.radiance.x > 0.0f || surface.radiance.y > 0.0f || surface.radiance.z > 0.0f)
            add(surface, false);
    } else {
        for_each_escaped(p, n, wi, camera_ray,
                         [&](const EmissionHit& escaped) { add(escaped, true); });
    }
}

// --- Cycles' light unit conversions (see the measurements above) ---
// Radiant intensity (W/sr) of a point or spot light of power P (W).
inline float point_intensity_from_power(float power) { return power * kInvFourPi; }
// Radiance (W m^-2 sr^-1) of an area light of power P (W) and area A (m^2).
inline float area_radiance_from_power(float power, float area) { return power / (4.0f * area); }
// Spot attenuation for cos_angle = cos(angle from the spot axis): smoothstep times cos_angle.
float spot_attenuation(const Light& light, float cos_angle);
// Area (m^2) of an area light including its transform's scale.
float area_light_area(const Light& light);
// Disk and ellipse area lights (their surface is the ellipse inscribed in the half axes).
bool is_round(AreaShape shape);
// Where the line p + t wi (t > 0) crosses the area light's surface: *t, and the cosine
// dot(wi, light.direction()) (< 0 when the ray meets its emitting front). False when the line is
// parallel to it, crosses behind p, or misses the rectangle/ellipse.
bool area_light_crossing(const Light& light, const vec3& p, const vec3& wi, float* t,
                         float* cos_axis);
// Whether p is on the side an area light (or portal) faces.
bool in_front_of_area_light(const Light& light, const vec3& p);
// A uniform point on an area light's surface (u in [0, 1)^2).
vec3 area_light_point(const Light& light, const vec2& u);
// Half extents of an area light along its local X and Y, in world space (object scale included,
// as Cycles multiplies the light's size by its transform).
void area_half_axes(const Light& light, vec3* ex, vec3* ey);

}  // namespace shgi
