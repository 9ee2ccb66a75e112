// Test helper: reproducible random RGB SH fields with coefficients uniform in [-1, 1).
#pragma once

#include <cstdint>

#include "sh/sh_coeffs.h"
#include "util/rng.h"

namespace shgi::testing {

inline ShRgb random_sh_field(int order, uint64_t seed) {
    Pcg32 rng(seed, 3);
    ShRgb sh(order);
    for (int i = 0; i < sh.num_coefficients(); ++i)
        sh.coeffs[i] = vec3(rng.next_float(), rng.next_float(), rng.next_float()) * 2.0f - 1.0f;
    return sh;
}

}  // namespace shgi::testing
