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

// Defined here, inline: a preview pixel makes nine hashes and five scrambles a sample, each a
// chain of dependent multiplies; inlined into pixel_sample() (render/path_integrator.cpp) the
// independent chains overlap, whereas calls into another file they ran one after the other.
namespace owen_sobol_detail {

// The byte order reversed by one bswap, then the bits within each byte by three swaps: two steps
// fewer than five swaps, on a path that reverses five times per 2-D sample.
inline uint32_t reverse_bits(uint32_t x) {
    x = __builtin_bswap32(x);
    x = ((x >> 4) & 0x0F0F0F0Fu) | ((x & 0x0F0F0F0Fu) << 4);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    return ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
}

// Laine and Karras' hash: each output bit depends only on itself and the bits below it, which is
// what makes the reversed application below an Owen (nested uniform) scramble.
inline uint32_t laine_karras_permutation(uint32_t x, uint32_t seed) {
    x += seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// Owen scramble of the binary fraction x / 2^32 (bits read from the most significant).
inline uint32_t nested_uniform_scramble(uint32_t x, uint32_t seed) {
    return reverse_bits(laine_karras_permutation(reverse_bits(x), seed));
}

// The second Sobol' dimension as a 32-bit binary fraction (the first is reverse_bits(index)).
// It is linear over GF(2) in the index's bits: index bit i contributes the direction number
// v_i (v_0 = 2^31, v_(i+1) = v_i ^ (v_i >> 1)). The indices renderers pass are scrambled, so all
// 32 bits are random; a loop over them mispredicts a branch on every other bit. Instead the
// contributions are summed per byte of the index in four 256-entry tables.
struct SobolDimension1Tables {
    uint32_t byte[4][256];

    SobolDimension1Tables() : byte{} {
        uint32_t v[32];
        v[0] = 1u << 31;
        for (int i = 1; i < 32; ++i) v[i] = v[i - 1] ^ (v[i - 1] >> 1);
        for (int k = 0; k < 4; ++k)
            for (uint32_t b = 0; b < 256; ++b)
                for (int j = 0; j < 8; ++j)
                    if (b & (1u << j)) byte[k][b] ^= v[8 * k + j];
    }
};

// The tables, built on first use.
inline const SobolDimension1Tables& sobol_dimension1_tables() {
    static const SobolDimension1Tables tables;
    return tables;
}

inline uint32_t sobol_dimension1(uint32_t index) {
    const SobolDimension1Tables& tables = sobol_dimension1_tables();
    return tables.byte[0][index & 0xFFu] ^ tables.byte[1][(index >> 8) & 0xFFu] ^
           tables.byte[2][(index >> 16) & 0xFFu] ^ tables.byte[3][index >> 24];
}

// reverse_bits(sobol_dimension1(index)) without tables, for lanes, where the tables took four
// gathers (slow, and the longest latency of the preview's pixel numbers). Reversed, direction
// number v_i has bit j set where C(i, j) is odd, that is (Lucas's theorem) where j's bits are a
// subset of i's: bit j of the result is the XOR of the index bits at the positions whose bits are
// a superset of j's. That sum over supersets takes one shift-and-XOR step per bit of a position
// (five), as a fast zeta transform does.
inline uint32_t reversed_sobol_dimension1(uint32_t index) {
    index ^= (index >> 1) & 0x55555555u;
    index ^= (index >> 2) & 0x33333333u;
    index ^= (index >> 4) & 0x0F0F0F0Fu;
    index ^= (index >> 8) & 0x00FF00FFu;
    return index ^ (index >> 16);
}

// The third Sobol' dimension (Joe and Kuo's: primitive polynomial x^2 + x + 1, m = 1, 3), by
// the same per-byte tables: direction numbers v_0 = 2^31, v_1 = 3 * 2^30 and
// v_(i+2) = v_(i+1) ^ v_i ^ (v_i >> 2).
struct SobolDimension2Tables {
    uint32_t byte[4][256];

    SobolDimension2Tables() : byte{} {
        uint32_t v[32];
        v[0] = 1u << 31;
        v[1] = 3u << 30;
        for (int i = 2; i < 32; ++i) v[i] = v[i - 1] ^ v[i - 2] ^ (v[i - 2] >> 2);
        for (int k = 0; k < 4; ++k)
            for (uint32_t b = 0; b < 256; ++b)
                for (int j = 0; j < 8; ++j)
                    if (b & (1u << j)) byte[k][b] ^= v[8 * k + j];
    }
};

inline uint32_t sobol_dimension2(uint32_t index) {
    static const SobolDimension2Tables tables;
    return tables.byte[0][index & 0xFFu] ^ tables.byte[1][(index >> 8) & 0xFFu] ^
           tables.byte[2][(index >> 16) & 0xFFu] ^ tables.byte[3][index >> 24];
}

// Dimension 0 is the bit reversal of the index, so its scramble reverse(LK(reverse(reverse(i))))
// is reverse(LK(i)): two reversals fewer on the renderers' per-sample path.
inline uint32_t scrambled_dimension0(uint32_t shuffled, uint32_t seed) {
    return reverse_bits(laine_karras_permutation(shuffled, seed));
}

inline float to_unit_float(uint32_t fraction) { return float(fraction >> 8) * 0x1p-24f; }

}  // namespace owen_sobol_detail

// A 32-bit hash of (a, b) for deriving sequence seeds (e.g. pixel index and dimension pair).
inline uint32_t hash_seed(uint64_t a, uint64_t b) {
    // SplitMix64 finaliser over a combination of both.
    uint64_t z = a * 0x9E3779B97F4A7C15ull + b + 0x632BE59BD9B4E019ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return uint32_t((z ^ (z >> 31)) >> 32);
}

inline float owen_sobol_1d(uint32_t index, uint32_t seed) {
    using namespace owen_sobol_detail;
    const uint32_t shuffled = nested_uniform_scramble(index, seed);
    return to_unit_float(scrambled_dimension0(shuffled, hash_seed(seed, 1)));
}

inline vec2 owen_sobol_2d(uint32_t index, uint32_t seed) {
    using namespace owen_sobol_detail;
    const uint32_t shuffled = nested_uniform_scramble(index, seed);
    return vec2(
        to_unit_float(scrambled_dimension0(shuffled, hash_seed(seed, 1))),
        to_unit_float(nested_uniform_scramble(sobol_dimension1(shuffled), hash_seed(seed, 2))));
}

// Point `index` of a 3-D sequence: x and y are owen_sobol_2d(index, seed)'s, z the third
// Sobol' dimension of the same shuffled index with its own scramble. The three are stratified
// together (Sobol's first three dimensions are a (1, 3)-sequence: in every aligned block of 2^m
// indices each elementary box of volume 2^(1-m) holds two points), so the points that a range of
// z selects (a BSDF lobe chosen by z) keep their (x, y) stratified, which two separate
// sequences do not.
inline vec3 owen_sobol_3d(uint32_t index, uint32_t seed) {
    using namespace owen_sobol_detail;
    const uint32_t shuffled = nested_uniform_scramble(index, seed);
    return vec3(
        to_unit_float(scrambled_dimension0(shuffled, hash_seed(seed, 1))),
        to_unit_float(nested_uniform_scramble(sobol_dimension1(shuffled), hash_seed(seed, 2))),
        to_unit_float(nested_uniform_scramble(sobol_dimension2(shuffled), hash_seed(seed, 3))));
}

}  // namespace shgi
