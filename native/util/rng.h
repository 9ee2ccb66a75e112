// Random numbers: PCG32 (O'Neill 2014) from Debian's pcg-cpp, with an explicit (seed, stream).
//
// Determinism (docs/architecture.md): every unit of work (a photon, a probe, a pixel sample, a
// texel) gets its own stream, derived from the user's seed and the unit's index, never from a
// thread id. The result therefore does not depend on the thread count or on how work is split into
// shards.
#pragma once

#include <cstdint>

#include <pcg_random.hpp>

#include "util/math.h"

namespace shgi {

class Pcg32 {
  public:
    // Streams with different `stream` values are independent sequences for the same seed.
    explicit Pcg32(uint64_t seed = 0, uint64_t stream = 0) : engine_(seed, stream) {}

    uint32_t next_u32() { return engine_(); }

    // Uniform integer in [0, bound) without modulo bias.
    uint32_t next_u32(uint32_t bound) { return engine_(bound); }

    // Uniform float in [0, 1): 24 random mantissa bits, so 1.0 is never returned.
    float next_float() { return static_cast<float>(engine_() >> 8) * 0x1p-24f; }

    vec2 next_vec2() {
        const float a = next_float();
        return vec2(a, next_float());
    }

    // Skips `delta` outputs in O(log delta): lets shards start where the previous one stopped.
    void advance(uint64_t delta) { engine_.advance(delta); }

  private:
    pcg32 engine_;
};

// A stream id for unit `index` of a pass: mixes so that (pass, index) pairs never collide for
// index < 2^40 and pass < 2^24.
inline uint64_t stream_id(uint64_t pass, uint64_t index) { return (pass << 40) ^ index; }

}  // namespace shgi
