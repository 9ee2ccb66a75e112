// PhotonEmitter: where photons start. Every emitter of a Scene (lights, emissive triangles, the
// world) with its exact flux in Cycles' units (render/light_sampler.h), chosen per photon in
// proportion to that flux (seed 000 §5.1), and a sampler of one photon's ray and power.
//
// Flux of each emitter (linear RGB, W) and how a photon leaves it:
//   point   colour x P; from the light's position, uniform over the sphere (radius ignored)
//   spot    colour x P/(4 pi) x integral of spot_attenuation over the cone; uniform in the cone,
//           each photon weighted by the attenuation in its direction
//   sun     colour x S x pi R^2; direction uniform in the sun's cone (its axis when angle = 0),
//           origin uniform on a disk of radius R perpendicular to that direction, outside the
//           scene's bounding sphere (centre c, radius R). A disk per direction covers the whole
//           sphere for every direction, and a surface facing the sun receives S (1 + cos)/2 as
//           Cycles' (the mean cosine over the cone)
//   area    colour x P/(4A) x pi A; uniform point on the rectangle or ellipse, cosine-weighted
//           around the light's -Z (one-sided)
//   emissive triangle  2 pi Le A; uniform point, either side with probability 1/2, cosine
//           weighted around that side's normal
//   world   Lw x 4 pi x pi R^2; direction uniform over the sphere, origin on a disk of radius R
//           perpendicular to it outside the bounding sphere
// Portals (Light.portal) emit nothing. With portals in the scene, a sun or world photon takes,
// with probability kPortalFraction (render/light_sampler.h), a uniformly chosen portal's way in:
// a uniform point on it, the direction from the sun's cone (sun) or cosine-weighted into the
// room (world), the ray started on the same far plane as the disk's; otherwise the disk's way.
// Its power is the radiance over the mixture's density of that ray (per unit area across the
// ray and per unit solid angle), so photons are unbiased for light entering anywhere, and most
// of them come through the window instead of landing on the building's outside.
// Emitters with zero flux are left out; an empty scene has no bounding sphere, so its sun and
// world emit nothing.
//
// Photon i of N picks its emitter with u = (i + xi) / N through the flux distribution (stratified)
// and carries power = flux estimate of its sample / (N x selection probability): the N photons'
// powers sum to an unbiased estimate of total_power().
//
// Lamp share (light_share_uniform = u in [0, 1], 0 by default): the selection probability is
// (1 - u) x the flux share plus u x a uniform share per lamp, a lamp being a light, an emissive
// object (its triangles, by flux within it) or the world. A dim lamp beside a bright one then
// gets at least u / lamps of the photons instead of its flux share (the two rooms' 20 W lamp got
// 1%); the power divides by the mixed probability, so the estimate stays unbiased. With u = 0
// the flux distribution is the one above, bit for bit.
#pragma once

#include <cstdint>
#include <vector>

#include "render/light_sampler.h"
#include "scene/scene.h"
#include "util/math.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {

struct EmittedPhoton {
    Ray ray;             // unit direction, starting on (or just off) the emitter
    vec3 power{0.0f};    // W
    bool from_world = false;
};

class PhotonEmitter {
  public:
    // The scene must be committed (InvalidArgument otherwise); light_share_uniform in [0, 1]
    // (see above; InvalidArgument otherwise).
    explicit PhotonEmitter(const Scene& scene, float light_share_uniform = 0.0f);

    bool empty() const { return emitters_.empty(); }
    // Exact sum of the emitters' flux (W).
    vec3 total_power() const { return total_power_; }

    // Photon `index` of `count` (index < count), its random numbers drawn from `rng`. False when
    // the sample carries no power (a spot photon at the cone's edge) or there is no emitter.
    bool emit(uint64_t index, uint64_t count, Pcg32& rng, EmittedPhoton* out) const;

  private:
    enum class Kind : uint8_t { Light, Triangle, World };
    struct Emitter {
        Kind kind;
        uint32_t index;  // into scene lights / emissive triangles
        vec3 power;      // flux, W
    };

    // A sample of one emitter: ray and an unbiased estimate of that emitter's whole flux.
    bool sample_emitter(const Emitter& emitter, Pcg32& rng, EmittedPhoton* out) const;
    void sample_light(const Light& light, const vec3& power, Pcg32& rng,
                      EmittedPhoton* out) const;
    void sample_triangle(const EmissiveTriangle& triangle, const vec3& power, Pcg32& rng,
                         EmittedPhoton* out) const;
    // A ray along `direction` from a uniform point of the disk of radius R perpendicular to
    // it, outside the bounding sphere.
    Ray ray_through_bounding_disk(const vec3& direction, const vec2& u) const;
    // The ray along `direction` through `point`, starting on the plane of those disks.
    Ray ray_through_point(const vec3& direction, const vec3& point) const;
    // Sun and world photons (see above): ray and power.
    void sample_sun(const Light& light, const vec2& u, Pcg32& rng, EmittedPhoton* out) const;
    void sample_world(Pcg32& rng, EmittedPhoton* out) const;
    // Whether the portal strategy is drawn for this photon, and which portal (uniform).
    bool draw_portal_strategy(Pcg32& rng) const;
    const Light& draw_portal(Pcg32& rng) const;
    // Densities of each strategy for a ray, per m^2 across the ray: the disk's (uniform over
    // its area, 0 for rays outside it) and the portals' (1/K per portal the ray enters through,
    // over its projected area A cos; with cosine_directions, times the direction density
    // cos / pi, i.e. 1 / (pi A)). mixed() combines them with kPortalFraction.
    float disk_density(const Ray& ray) const;
    float portal_density(const Ray& ray, bool cosine_directions) const;
    float mixed(float portal, float disk) const;

    const Scene* scene_;
    vec3 bounding_center_{0.0f};
    float bounding_radius_ = 0.0f;  // m; 0 for an empty scene
    std::vector<Emitter> emitters_;
    std::vector<Portal> portals_;
    DiscreteDistribution distribution_;
    vec3 total_power_{0.0f};
};

// Flux (W) of a spot light: colour x P/(4 pi) x the integral of spot_attenuation over its cone.
vec3 spot_light_power(const Light& light);

}  // namespace shgi
