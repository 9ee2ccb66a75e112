// A stored photon (seed 000 Table 3): power, position, surface normal and incoming direction;
// and a light path's first surface hit (PhotonFirstHit), which the photon maps leave out.
//
// Units: `power` is the photon's flux in W (linear RGB) such that the photons of one tracing
// pass of N emitted photons sum to an unbiased estimate of the flux that arrives at the stored
// surfaces. `normal` is the geometric normal of the hit surface flipped to the side the photon
// arrived from; `direction` points from the surface back towards where the photon came from
// (the incident direction ω_i of the radiance it carries), so dot(normal, direction) > 0.
//
// PhotonFirstHit records where light arrives straight from an emitter (seed 001 §3.2–3.3: the
// radiance grid is built from the diffusely reflected flux of photon hits, and a method that
// wants the light's first reflection in its grid needs these). `power` is the flux arriving, in
// the same estimate as Photon::power, so one pass's first hits sum to an estimate of the emitted
// flux that reaches surfaces; `reflected_power` = the hit BSDF's diffuse albedo toward
// `direction` × power (Lambert: base colour × (1 − metallic)(1 − transmission)), the flux the
// surface scatters diffusely. `normal` and `direction` follow Photon's conventions.
#pragma once

#include "util/math.h"

namespace shgi {

struct Photon {
    vec3 position{0.0f};   // world space, m
    vec3 power{0.0f};      // W
    vec3 normal{0.0f, 0.0f, 1.0f};
    vec3 direction{0.0f, 0.0f, 1.0f};
};

struct PhotonFirstHit {
    vec3 position{0.0f};         // world space, m
    vec3 normal{0.0f, 0.0f, 1.0f};
    vec3 direction{0.0f, 0.0f, 1.0f};
    vec3 power{0.0f};            // W arriving
    vec3 reflected_power{0.0f};  // W scattered by the diffuse lobe: diffuse albedo × power
};

}  // namespace shgi
