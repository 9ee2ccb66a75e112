// A stored photon (seed 000 Table 3): power, position, surface normal and incoming direction.
//
// Units: `power` is the photon's flux in W (linear RGB) such that the photons of one tracing
// pass of N emitted photons sum to an unbiased estimate of the flux that arrives at the stored
// surfaces. `normal` is the geometric normal of the hit surface flipped to the side the photon
// arrived from; `direction` points from the surface back towards where the photon came from
// (the incident direction ω_i of the radiance it carries), so dot(normal, direction) > 0.
#pragma once


#include "util/math.h"

namespace shgi {

struct Photon {
    vec3 position{0.0f};   // world space, m
    vec3 power{0.0f};      // W
    vec3 normal{0.0f, 0.0f, 1.0f};
    vec3 direction{0.0f, 0.0f, 1.0f};
};

}  // namespace shgi
