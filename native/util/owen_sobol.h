// Owen-scrambled Sobol' points for progressive sampling (Burley 2020, "Practical Hash-based Owen
// Scrambling", JCGT 9(4)): point `index` of a sequence named by `seed`.
//
// Every point is uniformly distributed (so estimators stay unbiased), and for every m the points
// with indices in an aligned block of 2^m (in particular the first 2^m) form a (0, m, 2)-net:
// each elementary box of area 2^-m holds exactly one of them. Renderers use one sequence per
// pixel and per pair of dimensions (pixel jitter, light sample, ...): the seeds differ, and the
// index is shuffled per seed, so the pairs are decorrelated. Sample s of a progressive render is
// index s, so adding samples later continues the same stratified set.
#pragma once

#include <cstdint>

#include "util/math.h"

namespace shgi {

// A 32-bit hash of (a, b) for deriving sequence seeds (e.g. pixel index and dimension pair).
uint32_t hash_seed(uint64_t a, uint64_t b);

float owen_sobol_1d(uint32_t index, uint32_t seed);
vec2 owen_sobol_2d(uint32_t index, uint32_t seed);

}  // namespace shgi
