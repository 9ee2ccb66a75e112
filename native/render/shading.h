// Shading a surface hit: the facing normals, shading frame and Principled BSDF at a hit, and the
// ray-spawning conventions every tracer shares (path tracer, preview renderer, photon tracer).
//
// Normals are flipped to the side the ray came from; the BSDF sees a back-face hit with the
// inverted ior. Spawned rays start kRayOffset (relative to the coordinates' magnitude) off the
// surface along the geometric normal, on the side they leave towards.
#pragma once

#include <cstring>
#include <new>
#include <type_traits>
#include <vector>

#include "render/bsdf.h"
#include "scene/scene.h"
#include "util/math.h"

namespace shgi {

// Spawned rays start this far (relative to the coordinates' magnitude) off the surface along
// the geometric normal: float32 hit points are accurate to ~1e-7 relative, 1e-4 keeps clear of
// self-intersection on metre-scale scenes without visible light leaks.
inline constexpr float kRayOffset = 1e-4f;
// Shadow rays stop this fraction short of the light sample so the emitter's own triangle does
// not occlude it.
inline constexpr float kShadowShorten = 1e-3f;

// The shadow ray from `origin` along unit `wi` to a light sample `distance` away (kInfinity for
// the world or a sun), stopping kShadowShorten short of it.
inline Ray light_shadow_ray(const vec3& origin, const vec3& wi, float distance) {
    Ray ray;
    ray.origin = origin;
    ray.direction = wi;
    ray.tmax = std::isinf(distance) ? kInfinity : distance * (1.0f - kShadowShorten);
    return ray;
}

// Light Paths > Clamp, as Cycles clamps a contribution (film_clamp_light, with the panel's
// value times three as its scene/integrator.cpp stores it): v scaled down so that the mean of
// its components' magnitudes is at most `limit`, one factor for all three (the hue is kept);
// limit <= 0: off, v unchanged.
inline vec3 clamp_contribution(const vec3& v, float limit) {
    const float sum = std::fabs(v.x) + std::fabs(v.y) + std::fabs(v.z);
    return limit > 0.0f && sum > 3.0f * limit ? v * (3.0f * limit / sum) : v;
}

// p moved off its surface along `normal` (the side the new ray leaves towards).
vec3 offset_origin(const vec3& p, const vec3& normal);

// Bilinear lookup with repeat wrapping; v = 0 is the bottom row (Texture's convention).
vec3 texture_bilinear(const Texture& texture, const vec2& uv);

// A surface hit prepared for shading: facing normals, shading frame, BSDF.
struct Shading {
    vec3 position, geometric_normal;  // normal flipped to the side the ray came from
    Frame frame;
    vec3 wo;                          // towards the ray's origin, local frame (wo.z > 0)
    PrincipledBsdf bsdf;

    // Origin for a ray leaving along world direction `wi` (offset to the side it leaves to).
    vec3 spawn_origin(const vec3& wi) const;
};

// --- Particles (photons, VPLs) at a shading normal: the adjoint BSDF (Veach 1997, §5.3) ---
// A camera path weighs light arriving from wl by its cosine to the shading normal ns (the BSDF's
// |cos| in the shading frame, times the diffuse lobe's bump shadowing toward wl), while the
// particles arriving along wl are spread over the surface by their cosine to the geometric
// normal ng. A particle's flux then reaches the BSDF times cos(wl, ns)+ / cos(wl, ng), and a
// photon scattered towards wi leaves through the geometric surface, |wi.ng| (eq. 5.17 with
// Cycles' convention that only the light side's cosine is the shading normal's). The helpers
// take wl in world space, unit, towards the particle's source, on the side of the Shading's ray.
// Where the frame's normal is the geometric one they return their input unchanged, bit for bit.

// The factor on a particle's power for the diffuse lobe it lights (reflected_power, the VPLs'
// scattered_flux): cos(wl, ns)+ / cos(wl, ng) times the lobe's bump shadowing toward wl.
float particle_arrival_ratio(const Shading& shading, const vec3& wl);
float particle_diffuse_arrival(const Shading& shading, const vec3& wl);

// A photon's weight for its BSDF sample `bs` (drawn with the photon's arrival as wo) towards
// world direction `wi`: bs.weight (f |bs.wi.z| / pdf, with the diffuse lobe's bump shadowing
// toward wi) made the adjoint's, f cos(wl, ns)+ |wi.ng| / (cos(wl, ng) pdf) with the shadowing
// toward wl.
vec3 particle_scatter_weight(const Shading& shading, const vec3& wl, const BsdfSample& bs,
                             const vec3& wi);

// Each material's PrincipledBsdf lobes where they are the same at every hit
// (PrincipledBsdf::material_lobes), built once per scene revision by tracers that shade many
// hits: make_shading then finishes a copy per hit instead of setting the lobes up again (~40% of
// the BSDF's set-up at a preview pixel), with the same bits.
class MaterialLobeTable {
  public:
    MaterialLobeTable() = default;
    explicit MaterialLobeTable(const Scene& scene);
    // The material's lobes, or null when they depend on the hit (or the id is out of range).
    const PrincipledBsdf* find(uint32_t material_id) const {
        return has(material_id) ? &lobes_[material_id] : nullptr;
    }
    // Their class_color_sum() (the G-buffer's albedo), which every hit's BSDF finished from
    // them shares (its lobes' weights are the material's), or null as find().
    const vec3* albedo(uint32_t material_id) const {
        return has(material_id) ? &albedo_[material_id] : nullptr;
    }

  private:
    bool has(uint32_t material_id) const {
        return material_id < has_lobes_.size() && has_lobes_[material_id];
    }
    std::vector<PrincipledBsdf> lobes_;
    std::vector<vec3> albedo_;
    std::vector<uint8_t> has_lobes_;
};

// Frame::from_z of the last shading normal asked for, compared by bits (-0 and +0 give
// different frames). Neighbouring hits on one flat triangle have the same normal's bits, and the
// frame is a function of the normal alone, so a hit gets the frame a new call would give.
class FrameMemo {
  public:
    const Frame& from_z(const vec3& n) {
        if (!valid_ || std::memcmp(&n, &frame_.z, sizeof(vec3)) != 0) {
            frame_ = Frame::from_z(n);
            valid_ = true;
        }
        return frame_;
    }
    void reset() { valid_ = false; }

  private:
    bool valid_ = false;
    Frame frame_;
};

// What a tracer that shades many hits in a row on one thread (the preview's wave) keeps between
// them: the last triangle's geometric normal (Scene::surface_point) and the last shading
// frame (make_shading). Reset it whenever the scene or its revision changes.
struct ShadingMemo {
    TriangleNormalMemo triangle;
    FrameMemo frame;

    void reset() {
        triangle.reset();
        frame.reset();
    }
};

// origin: which end of the path the ray came from (PathOrigin::Light for photons). `lobes`
// (optional): the scene's MaterialLobeTable; `frames` (optional): the caller's FrameMemo (both
// give the same Shading, made faster).
Shading make_shading(const Scene& scene, const SurfacePoint& sp, const vec3& ray_direction,
                     PathOrigin origin = PathOrigin::Camera,
                     const MaterialLobeTable* lobes = nullptr, FrameMemo* frames = nullptr);

// make_shading built in `slot`, over the Shading it held (the tracers' per-hit records):
// assigning make_shading's result would copy the 260-byte record (a `rep movsq`, ~4% of the
// photon trace's time on the bench's Cornell box).
static_assert(std::is_trivially_destructible_v<Shading>, "make_shading_in skips the destructor");
inline Shading& make_shading_in(Shading* slot, const Scene& scene, const SurfacePoint& sp,
                                const vec3& ray_direction, PathOrigin origin = PathOrigin::Camera,
                                const MaterialLobeTable* lobes = nullptr,
                                FrameMemo* frames = nullptr) {
    return *::new (slot) Shading(make_shading(scene, sp, ray_direction, origin, lobes, frames));
}

}  // namespace shgi
