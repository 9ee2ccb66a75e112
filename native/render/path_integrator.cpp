#include "render/path_integrator.h"

#include <algorithm>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "util/cpu_features.h"
#include "util/error.h"
#include "util/owen_sobol.h"
#include "util/sampling.h"
#include "util/timer.h"

namespace shgi {

PixelSample pixel_sample(uint64_t seed, uint64_t pixel, uint64_t sample, bool first_bsdf) {
    const uint32_t base = hash_seed(seed, pixel);
    const uint32_t index = uint32_t(sample);
    PixelSample out{owen_sobol_2d(index, hash_seed(base, 0)),
                    owen_sobol_1d(index, hash_seed(base, 1)),
                    owen_sobol_2d(index, hash_seed(base, 2))};
    if (first_bsdf) {
        // One 3-D sequence: the direction samples of each lobe stay stratified (the plaster's
        // diffuse lobe, 95% of a sun room's first bounces, lost that to an independent u_lobe).
        const vec3 bsdf = owen_sobol_3d(index, hash_seed(base, 4));
        out.u_lobe = bsdf.z;
        out.u_bsdf = vec2(bsdf.x, bsdf.y);
    }
    return out;
}

float gather_number(uint64_t seed, uint64_t pixel, uint64_t sample) {
    // Dimension 5: pixel_sample's take 0, 1, 2 and 4.
    return owen_sobol_1d(uint32_t(sample), hash_seed(hash_seed(seed, pixel), 5));
}

namespace {

#if defined(__SSE2__)
// The 32-bit steps of util/owen_sobol.h on four lanes: SSE2 has no 32-bit multiply (pmulld is
// SSE4.1) nor byte shuffle, so both are built from what it has; the results are the same
// integers.
struct OwenSobol4 {
    // a * b mod 2^32 per lane.
    static __m128i mul(__m128i a, __m128i b) {
        const __m128i even = _mm_mul_epu32(a, b);
        const __m128i odd = _mm_mul_epu32(_mm_srli_epi64(a, 32), _mm_srli_epi64(b, 32));
        return _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)),
                                  _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
    }
    static __m128i swap_bits(__m128i x, int shift, uint32_t mask) {
        const __m128i m = _mm_set1_epi32(int(mask));
        return _mm_or_si128(_mm_and_si128(_mm_srli_epi32(x, shift), m),
                            _mm_slli_epi32(_mm_and_si128(x, m), shift));
    }
    static __m128i reverse_bits(__m128i x) {
        x = _mm_or_si128(_mm_slli_epi32(x, 16), _mm_srli_epi32(x, 16));  // halves
        x = _mm_or_si128(_mm_slli_epi16(x, 8), _mm_srli_epi16(x, 8));    // bytes
        x = swap_bits(x, 4, 0x0F0F0F0Fu);
        x = swap_bits(x, 2, 0x33333333u);
        return swap_bits(x, 1, 0x55555555u);
    }
    static __m128i laine_karras(__m128i x, __m128i seed) {
        x = _mm_add_epi32(x, seed);
        for (const uint32_t k : {0x6c50b47cu, 0xb82f1e52u, 0xc7afe638u, 0x8d22f6e6u})
            x = _mm_xor_si128(x, mul(x, _mm_set1_epi32(int(k))));
        return x;
    }
    // to_unit_float: the top 24 bits are below 2^31, so the signed conversion is exact.
    static __m128 to_unit_float(__m128i x) {
        return _mm_mul_ps(_mm_cvtepi32_ps(_mm_srli_epi32(x, 8)), _mm_set1_ps(0x1p-24f));
    }
    static __m128i load(const uint32_t (&v)[4]) {
        return _mm_loadu_si128(reinterpret_cast<const __m128i*>(v));
    }
    // owen_sobol_1d (y null) or owen_sobol_2d of one index (reversed: reverse_bits(index)) for
    // four sequence seeds.
    static void point(uint32_t reversed_index, const uint32_t (&seeds)[4], __m128* x,
                      __m128* y) {
        uint32_t h1[4], h2[4];
        for (int j = 0; j < 4; ++j) {
            h1[j] = hash_seed(seeds[j], 1);
            if (y != nullptr) h2[j] = hash_seed(seeds[j], 2);
        }
        const __m128i shuffled = reverse_bits(
            laine_karras(_mm_set1_epi32(int(reversed_index)), load(seeds)));
        *x = to_unit_float(reverse_bits(laine_karras(shuffled, load(h1))));
        if (y == nullptr) return;
        *y = to_unit_float(
            reverse_bits(laine_karras(reversed_sobol_dimension1(shuffled), load(h2))));
    }
    // owen_sobol_detail::reversed_sobol_dimension1 per lane.
    static __m128i reversed_sobol_dimension1(__m128i x) {
        x = _mm_xor_si128(x, _mm_and_si128(_mm_srli_epi32(x, 1), _mm_set1_epi32(0x55555555)));
        x = _mm_xor_si128(x, _mm_and_si128(_mm_srli_epi32(x, 2), _mm_set1_epi32(0x33333333)));
        x = _mm_xor_si128(x, _mm_and_si128(_mm_srli_epi32(x, 4), _mm_set1_epi32(0x0F0F0F0F)));
        x = _mm_xor_si128(x, _mm_and_si128(_mm_srli_epi32(x, 8), _mm_set1_epi32(0x00FF00FF)));
        return _mm_xor_si128(x, _mm_srli_epi32(x, 16));
    }
};
#endif

#if defined(__x86_64__)
#define SHGI_AVX2 __attribute__((target("avx2")))
#define SHGI_AVX512 __attribute__((target("avx2,avx512f,avx512dq,avx512vl")))
#define SHGI_AVX512_GFNI __attribute__((target("avx2,avx512f,avx512dq,avx512vl,gfni")))
// hash_seed's 64-bit product a * k mod 2^64 on four 64-bit lanes (k a constant). AVX2 has no
// 64-bit multiply: the low 64 bits of the product from three 32-bit ones.
struct Mul64Avx2 {
    SHGI_AVX2 static __m256i mul64(__m256i a, uint64_t k) {
        const __m256i k_lo = _mm256_set1_epi64x(int64_t(k & 0xFFFFFFFFu));
        const __m256i k_hi = _mm256_set1_epi64x(int64_t(k >> 32));
        const __m256i cross = _mm256_add_epi64(_mm256_mul_epu32(_mm256_srli_epi64(a, 32), k_lo),
                                               _mm256_mul_epu32(a, k_hi));
        return _mm256_add_epi64(_mm256_mul_epu32(a, k_lo), _mm256_slli_epi64(cross, 32));
    }
};
// The same product in one instruction (AVX-512DQ's vpmullq on 256-bit registers, AVX-512VL):
// a pixel's 27 seed-hash multiplies built from 32-bit ones were ~45% of its numbers' instructions.
// Inlined only into a function compiled for AVX-512 (pixel_samples_avx512, flattened).
struct Mul64Avx512 {
    SHGI_AVX512 static __m256i mul64(__m256i a, uint64_t k) {
        return _mm256_mullo_epi64(a, _mm256_set1_epi64x(int64_t(k)));
    }
};

// reverse_bits on eight lanes: the bytes of each lane reversed by one shuffle, then each byte's
// bits by two lookups of its reversed nibbles.
struct ReverseAvx2 {
    SHGI_AVX2 static __m256i reverse_bits(__m256i x) {
        const __m256i bytes = _mm256_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12,
                                               3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12);
        const __m256i nibbles = _mm256_setr_epi8(0x0, 0x8, 0x4, 0xC, 0x2, 0xA, 0x6, 0xE, 0x1, 0x9,
                                                 0x5, 0xD, 0x3, 0xB, 0x7, 0xF, 0x0, 0x8, 0x4, 0xC,
                                                 0x2, 0xA, 0x6, 0xE, 0x1, 0x9, 0x5, 0xD, 0x3, 0xB,
                                                 0x7, 0xF);
        const __m256i low_nibble = _mm256_set1_epi8(0x0F);
        x = _mm256_shuffle_epi8(x, bytes);
        const __m256i low = _mm256_shuffle_epi8(nibbles, _mm256_and_si256(x, low_nibble));
        const __m256i high =
            _mm256_shuffle_epi8(nibbles, _mm256_and_si256(_mm256_srli_epi16(x, 4), low_nibble));
        // A reversed low nibble (< 16) moves up within its byte: the 16-bit shift carries nothing
        // into the next byte.
        return _mm256_or_si256(_mm256_slli_epi16(low, 4), high);
    }
};
// The same reversal with GFNI: after the same byte shuffle, each byte's bits by one affine
// transform over GF(2) whose matrix 0x8040201008040201 makes output bit i input bit 7 - i. Two
// instructions where the AVX2 form takes eight, on the dependent chain of each of the eight
// reversals per eight pixels. Inlined only into a function compiled for GFNI
// (pixel_samples_avx512_gfni, flattened).
struct ReverseGfni {
    SHGI_AVX512_GFNI static __m256i reverse_bits(__m256i x) {
        const __m256i bytes = _mm256_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12,
                                               3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12);
        return _mm256_gf2p8affine_epi64_epi8(_mm256_shuffle_epi8(x, bytes),
                                             _mm256_set1_epi64x(int64_t(0x8040201008040201ull)), 0);
    }
};

// The same integer steps on eight lanes (AVX2: 32-bit multiplies and byte shuffles),
// and hash_seed on four 64-bit lanes per register, its products by Mul (Mul64Avx2 or
// Mul64Avx512) and its bit reversals by Reverse (ReverseAvx2 or ReverseGfni): the same bits.
template <class Mul, class Reverse>
struct OwenSobol8 {
    SHGI_AVX2 static __m256i mul64(__m256i a, uint64_t k) { return Mul::mul64(a, k); }
    // The SplitMix64 finaliser of hash_seed from z, the high 32 bits left in each 64-bit lane.
    SHGI_AVX2 static __m256i finalise(__m256i z) {
        z = mul64(_mm256_xor_si256(z, _mm256_srli_epi64(z, 30)), 0xBF58476D1CE4E5B9ull);
        z = mul64(_mm256_xor_si256(z, _mm256_srli_epi64(z, 27)), 0x94D049BB133111EBull);
        return _mm256_xor_si256(z, _mm256_srli_epi64(z, 31));
    }
    // The high halves of two registers of four 64-bit lanes as eight 32-bit lanes, in order.
    SHGI_AVX2 static __m256i high_halves(__m256i low4, __m256i high4) {
        const __m256 mixed = _mm256_shuffle_ps(_mm256_castsi256_ps(low4),
                                               _mm256_castsi256_ps(high4), _MM_SHUFFLE(3, 1, 3, 1));
        return _mm256_permute4x64_epi64(_mm256_castps_si256(mixed), _MM_SHUFFLE(3, 1, 2, 0));
    }
    // hash_seed(a[j], b) for four 32-bit a (zero-extended to 64 bits), the sum b + c given.
    SHGI_AVX2 static __m256i hash4(__m128i a, __m256i b_plus_c) {
        return finalise(
            _mm256_add_epi64(mul64(_mm256_cvtepu32_epi64(a), 0x9E3779B97F4A7C15ull), b_plus_c));
    }
    // hash_seed(a[j], b) for eight 32-bit a.
    SHGI_AVX2 static __m256i hash(__m256i a, uint64_t b) {
        const __m256i b_plus_c = _mm256_set1_epi64x(int64_t(b + 0x632BE59BD9B4E019ull));
        return high_halves(hash4(_mm256_castsi256_si128(a), b_plus_c),
                           hash4(_mm256_extracti128_si256(a, 1), b_plus_c));
    }
    // hash_seed(a, b[j]) for one 64-bit a and eight 32-bit b: a's product is the same in every
    // lane, and (a k + b) + c = (a k + c) + b modulo 2^64.
    SHGI_AVX2 static __m256i hash(uint64_t a, __m256i b) {
        const __m256i ak_plus_c =
            _mm256_set1_epi64x(int64_t(a * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull));
        const __m256i low = _mm256_cvtepu32_epi64(_mm256_castsi256_si128(b));
        const __m256i high = _mm256_cvtepu32_epi64(_mm256_extracti128_si256(b, 1));
        return high_halves(finalise(_mm256_add_epi64(low, ak_plus_c)),
                           finalise(_mm256_add_epi64(high, ak_plus_c)));
    }
    SHGI_AVX2 static __m256i reverse_bits(__m256i x) { return Reverse::reverse_bits(x); }
    SHGI_AVX2 static __m256i laine_karras(__m256i x, __m256i seed) {
        x = _mm256_add_epi32(x, seed);
        for (const uint32_t k : {0x6c50b47cu, 0xb82f1e52u, 0xc7afe638u, 0x8d22f6e6u})
            x = _mm256_xor_si256(x, _mm256_mullo_epi32(x, _mm256_set1_epi32(int(k))));
        return x;
    }
    SHGI_AVX2 static __m256 to_unit_float(__m256i x) {
        return _mm256_mul_ps(_mm256_cvtepi32_ps(_mm256_srli_epi32(x, 8)), _mm256_set1_ps(0x1p-24f));
    }
    // owen_sobol_detail::reversed_sobol_dimension1 per lane: five shift-and-XOR steps where
    // sobol_dimension1's byte tables took four gathers and a reversal (the gathers held ~20% of
    // the AVX-512 loop's CPU samples).
    SHGI_AVX2 static __m256i reversed_sobol_dimension1(__m256i x) {
        x = _mm256_xor_si256(
            x, _mm256_and_si256(_mm256_srli_epi32(x, 1), _mm256_set1_epi32(0x55555555)));
        x = _mm256_xor_si256(
            x, _mm256_and_si256(_mm256_srli_epi32(x, 2), _mm256_set1_epi32(0x33333333)));
        x = _mm256_xor_si256(
            x, _mm256_and_si256(_mm256_srli_epi32(x, 4), _mm256_set1_epi32(0x0F0F0F0F)));
        x = _mm256_xor_si256(
            x, _mm256_and_si256(_mm256_srli_epi32(x, 8), _mm256_set1_epi32(0x00FF00FF)));
        return _mm256_xor_si256(x, _mm256_srli_epi32(x, 16));
    }
    // OwenSobol4::point on eight sequence seeds.
    SHGI_AVX2 static void point(uint32_t reversed_index, __m256i seeds, __m256* x, __m256* y) {
        const __m256i shuffled =
            reverse_bits(laine_karras(_mm256_set1_epi32(int(reversed_index)), seeds));
        *x = to_unit_float(reverse_bits(laine_karras(shuffled, hash(seeds, 1))));
        if (y == nullptr) return;
        *y = to_unit_float(
            reverse_bits(laine_karras(reversed_sobol_dimension1(shuffled), hash(seeds, 2))));
    }
};

// pixel_samples' loop over whole groups of eight pixels; returns how many pixels it did.
static_assert(sizeof(PixelSample) == 32 && offsetof(PixelSample, u_select) == 8 &&
                  offsetof(PixelSample, u_light) == 12 && offsetof(PixelSample, u_lobe) == 20 &&
                  offsetof(PixelSample, u_bsdf) == 24,
              "pixel_samples_lanes writes a PixelSample as eight packed floats");
template <class Mul, class Reverse>
SHGI_AVX2 size_t pixel_samples_lanes(uint64_t seed, const uint32_t* pixels, size_t count,
                                     uint64_t sample, PixelSample* out) {
    using Lanes = OwenSobol8<Mul, Reverse>;
    const uint32_t reversed = owen_sobol_detail::reverse_bits(uint32_t(sample));
    size_t i = 0;
    for (; i + 8 <= count; i += 8) {
        const __m256i base =
            Lanes::hash(seed, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(pixels + i)));
        __m256 jitter_x, jitter_y, select, light_x, light_y;
        Lanes::point(reversed, Lanes::hash(base, 0), &jitter_x, &jitter_y);
        Lanes::point(reversed, Lanes::hash(base, 1), &select, nullptr);
        Lanes::point(reversed, Lanes::hash(base, 2), &light_x, &light_y);
        // The eight PixelSamples (eight floats each; u_lobe and u_bsdf zero) by an 8 x 8
        // transpose whose last three rows are zero, where each pixel took scalar stores.
        const __m256 zero = _mm256_setzero_ps();
        const __m256 t0 = _mm256_unpacklo_ps(jitter_x, jitter_y);
        const __m256 t1 = _mm256_unpackhi_ps(jitter_x, jitter_y);
        const __m256 t2 = _mm256_unpacklo_ps(select, light_x);
        const __m256 t3 = _mm256_unpackhi_ps(select, light_x);
        const __m256 t4 = _mm256_unpacklo_ps(light_y, zero);
        const __m256 t5 = _mm256_unpackhi_ps(light_y, zero);
        const __m256 front[4] = {_mm256_shuffle_ps(t0, t2, 0x44), _mm256_shuffle_ps(t0, t2, 0xEE),
                                 _mm256_shuffle_ps(t1, t3, 0x44), _mm256_shuffle_ps(t1, t3, 0xEE)};
        const __m256 back[4] = {_mm256_shuffle_ps(t4, zero, 0x44), _mm256_shuffle_ps(t4, zero, 0xEE),
                                _mm256_shuffle_ps(t5, zero, 0x44), _mm256_shuffle_ps(t5, zero, 0xEE)};
        for (int j = 0; j < 4; ++j) {
            const __m256 low = _mm256_permute2f128_ps(front[j], back[j], 0x20);
            const __m256 high = _mm256_permute2f128_ps(front[j], back[j], 0x31);
            std::memcpy(static_cast<void*>(&out[i + size_t(j)]), &low, sizeof(PixelSample));
            std::memcpy(static_cast<void*>(&out[i + size_t(j) + 4]), &high, sizeof(PixelSample));
        }
    }
    return i;
}

SHGI_AVX2 size_t pixel_samples_avx2(uint64_t seed, const uint32_t* pixels, size_t count,
                                    uint64_t sample, PixelSample* out) {
    return pixel_samples_lanes<Mul64Avx2, ReverseAvx2>(seed, pixels, count, sample, out);
}

// flatten: every call inlined into this AVX-512 function, Mul64Avx512::mul64 included (GCC
// inlines a function only into one compiled for at least its instruction sets).
SHGI_AVX512 __attribute__((flatten)) size_t pixel_samples_avx512(uint64_t seed,
                                                                 const uint32_t* pixels,
                                                                 size_t count, uint64_t sample,
                                                                 PixelSample* out) {
    return pixel_samples_lanes<Mul64Avx512, ReverseAvx2>(seed, pixels, count, sample, out);
}

// pixel_samples_avx512 with GFNI's bit reversal, flattened alike.
SHGI_AVX512_GFNI __attribute__((flatten)) size_t pixel_samples_avx512_gfni(
    uint64_t seed, const uint32_t* pixels, size_t count, uint64_t sample, PixelSample* out) {
    return pixel_samples_lanes<Mul64Avx512, ReverseGfni>(seed, pixels, count, sample, out);
}
#undef SHGI_AVX512_GFNI
#undef SHGI_AVX512
#undef SHGI_AVX2
#endif

}  // namespace

void pixel_samples(uint64_t seed, const uint32_t* pixels, size_t count, uint64_t sample,
                   PixelSample* out, PixelSamplesIsa isa) {
    size_t i = 0;
    if (isa == PixelSamplesIsa::Avx2 && !cpu_has_avx2())
        throw InvalidArgument("pixel_samples: AVX2 was asked for on a CPU without it");
    if (isa == PixelSamplesIsa::Avx512 && !cpu_has_avx512dq_vl())
        throw InvalidArgument(
            "pixel_samples: AVX-512 (DQ and VL) was asked for on a CPU without it");
    if (isa == PixelSamplesIsa::Avx512Gfni && !cpu_has_avx512dq_vl_gfni())
        throw InvalidArgument(
            "pixel_samples: AVX-512 (DQ and VL) with GFNI was asked for on a CPU without them");
#if defined(__x86_64__)
    if (isa == PixelSamplesIsa::Avx512Gfni ||
        (isa == PixelSamplesIsa::Auto && cpu_has_avx512dq_vl_gfni()))
        i = pixel_samples_avx512_gfni(seed, pixels, count, sample, out);
    else if (isa == PixelSamplesIsa::Avx512 ||
             (isa == PixelSamplesIsa::Auto && cpu_has_avx512dq_vl()))
        i = pixel_samples_avx512(seed, pixels, count, sample, out);
    else if (isa == PixelSamplesIsa::Avx2 || (isa == PixelSamplesIsa::Auto && cpu_has_avx2()))
        i = pixel_samples_avx2(seed, pixels, count, sample, out);
#endif
#if defined(__SSE2__)
    using owen_sobol_detail::reverse_bits;
    const uint32_t index = uint32_t(sample);
    const uint32_t reversed = reverse_bits(index);
    for (; i + 4 <= count; i += 4) {
        uint32_t seeds[3][4];
        for (int j = 0; j < 4; ++j) {
            const uint32_t base = hash_seed(seed, pixels[i + size_t(j)]);
            for (int d = 0; d < 3; ++d) seeds[d][j] = hash_seed(base, uint64_t(d));
        }
        alignas(16) float jitter_x[4], jitter_y[4], select[4], light_x[4], light_y[4];
        __m128 x, y;
        OwenSobol4::point(reversed, seeds[0], &x, &y);
        _mm_store_ps(jitter_x, x);
        _mm_store_ps(jitter_y, y);
        OwenSobol4::point(reversed, seeds[1], &x, nullptr);
        _mm_store_ps(select, x);
        OwenSobol4::point(reversed, seeds[2], &x, &y);
        _mm_store_ps(light_x, x);
        _mm_store_ps(light_y, y);
        for (int j = 0; j < 4; ++j)
            out[i + size_t(j)] = PixelSample{vec2(jitter_x[j], jitter_y[j]), select[j],
                                             vec2(light_x[j], light_y[j])};
    }
#endif
    for (; i < count; ++i) out[i] = pixel_sample(seed, pixels[i], sample);
}

vec3 path_radiance(const PassValues& values, bool include_direct, float clamp) {
    vec3 radiance = values[Pass::Combined];
    if (!include_direct) radiance -= values[Pass::Emit] + values[Pass::Env];
    radiance = clamp_contribution(glm::max(radiance, vec3(0.0f)), clamp);
    return is_finite(radiance) ? radiance : vec3(0.0f);
}

namespace {

const Pass kDirectPass[kLobeClassCount] = {Pass::DiffDir, Pass::GlossDir, Pass::TransDir};
const Pass kIndirectPass[kLobeClassCount] = {Pass::DiffInd, Pass::GlossInd, Pass::TransInd};
const Pass kColorPass[kLobeClassCount] = {Pass::DiffCol, Pass::GlossCol, Pass::TransCol};

}  // namespace

void PathIntegrator::trace(const Ray& ray) { trace(ray, scene_.intersect(ray)); }

void PathIntegrator::trace(const Ray& camera_ray, const Hit& first_hit) {
    if (!begin(camera_ray, first_hit)) return;
    sample_direct();
    finish();
}

bool PathIntegrator::begin(const Ray& camera_ray, const Hit& first_hit) {
    ray_ = camera_ray;
    return enter_surface(first_hit);
}

bool PathIntegrator::begin(const Ray& camera_ray, const Hit& first_hit,
                           const SurfacePoint& first_point) {
    ray_ = camera_ray;
    return enter_surface(first_hit, &first_point);
}

// What ray_ meets up to `hit`, then the shading of that surface (at `point` when given: the
// hit's surface point); false when the path ends here.
bool PathIntegrator::enter_surface(const Hit& hit, const SurfacePoint* point) {
    // The test before the call answers the common case (a surface that does not emit, no
    // lamp the ray can cross) without find_emission's register saves.
    if (lights_.may_emit(hit, vertex_ == 0)) find_emission(ray_, hit);
    if (!hit.valid() || terminate_on_next_surface_) return false;
    // Both memos may be null (no set_shading_memo): each callee then computes afresh.
    const bool memo = shading_memo_ != nullptr;
    FrameMemo* frames = memo ? &shading_memo_->frame : nullptr;
    if (point != nullptr)
        make_shading_in(&shading_.value, scene_, *point, ray_.direction, PathOrigin::Camera,
                        material_lobes_, frames);
    else
        make_shading_in(&shading_.value, scene_,
                        scene_.surface_point(ray_, hit, memo ? &shading_memo_->triangle : nullptr),
                        ray_.direction, PathOrigin::Camera, material_lobes_, frames);
    blur_glossy(&shading_.value);
    if (vertex_ == 0 && !combined_only_) record_first_hit(shading_.value, ray_, hit);
    if (write_denoising_features_) record_denoising_features(shading_.value);
    return true;
}

// Cycles' Filter Glossy (surface_shader_prepare_closures): after a bounce of pdf below
// filter_glossy, the surface's microfacet lobes widen to alpha sqrt(1 - pdf / filter_glossy) / 2.
void PathIntegrator::blur_glossy(Shading* shading) const {
    if (!(settings_.filter_glossy > 0.0f)) return;
    const float blur_pdf = (1.0f / settings_.filter_glossy) * min_ray_pdf_;  // Cycles' order
    if (blur_pdf < 1.0f) shading->bsdf.blur(std::sqrt(1.0f - blur_pdf) * 0.5f);
}

// Each vertex: direct light (already done for the current surface when this is called), field
// light, then the BSDF chooses whether and where the path continues.
void PathIntegrator::finish() {
    for (;;) {
        const bool field_vertex = vertex_field() != nullptr;
        if (field_vertex) add_field(shading_.value);
        if (field_vertex && !shading_.value.bsdf.has_traced_lobes()) {
            // scatter() would fail (sample_traced: the path ends at a preview's matte and
            // glossy surfaces), so it is not called: its three numbers are skipped rather than
            // drawn, for callers that go on with the same generator.
            rng_.advance(3);
            return;
        }
        if (!scatter(shading_.value, &ray_)) return;
        const int total = bounces_[0] + bounces_[1] + bounces_[2];
        terminate_on_next_surface_ = total > settings_.max_bounces ||
                                     bounces_[0] > settings_.diffuse_bounces ||
                                     bounces_[1] > settings_.glossy_bounces ||
                                     bounces_[2] > settings_.transmission_bounces;
        if (vertex_ >= settings_.russian_roulette_depth && !terminate_on_next_surface_) {
            const float largest = max_component(throughput_);
            const float survive = std::min(
                1.0f, settings_.roulette_survival == RouletteSurvival::SqrtThroughput
                          ? std::sqrt(largest)
                          : largest);
            if (rng_.next_float() >= survive) return;
            throughput_ /= survive;
        }
        if (clock_ != nullptr) ++clock_->rays;
        if (!enter_surface(scene_.intersect(ray_))) return;
        sample_direct();
    }
}

// Adds what the ray meets: point/spot disks and area lights in front of the hit, the hit's own
// emission, or the world and suns when it escapes.
void PathIntegrator::find_emission(const Ray& ray, const Hit& hit) {
    lights_.for_each_emission(ray.origin, last_normal_, ray.direction, hit, vertex_ == 0,
                              [&](const EmissionHit& emission, bool is_world) {
                                  add_emission(emission.radiance, emission.light_pdf, is_world);
                              });
}

void PathIntegrator::add_emission(const vec3& radiance, float light_pdf, bool is_world) {
    const float weight = last_delta_ ? 1.0f : power_heuristic(last_pdf_, light_pdf);
    const vec3 contribution = throughput_ * radiance * weight;
    if (vertex_ == 0) {
        if (!combined_only_) out_[is_world ? Pass::Env : Pass::Emit] += contribution;
        out_[Pass::Combined] += contribution;
        return;
    }
    add_split(contribution, vertex_ == 1);
}

// A contribution reaching the camera through the first scattering: clamped whole, as Cycles
// clamps one contribution before it writes its passes, then split by the class fractions of
// that scattering into Dir (one scattering) or Ind passes.
void PathIntegrator::add_split(const vec3& contribution, bool direct) {
    const vec3 value =
        direct ? contribution : clamp_contribution(contribution, settings_.clamp_indirect);
    for (int c = 0; c < kLobeClassCount; ++c)
        if (class_fraction_[c] > 0.0f) add_to_passes(value * class_fraction_[c], c, direct);
}

void PathIntegrator::add_light(const vec3& contribution, int lobe_class, bool direct) {
    add_to_passes(
        direct ? contribution : clamp_contribution(contribution, settings_.clamp_indirect),
        lobe_class, direct);
}

void PathIntegrator::add_to_passes(const vec3& value, int lobe_class, bool direct) {
    if (!is_finite(value)) return;
    if (!combined_only_)
        out_[direct ? kDirectPass[lobe_class] : kIndirectPass[lobe_class]] += value;
    out_[Pass::Combined] += value;
}

void PathIntegrator::record_first_hit(const Shading& shading, const Ray& ray, const Hit& hit) {
    for (int c = 0; c < kLobeClassCount; ++c)
        out_[kColorPass[c]] += shading.bsdf.class_color(LobeClass(c));
    out_[Pass::Normal] += shading.frame.z;
    const vec3 forward = glm::normalize(-vec3(camera_.world_from_camera[2]));
    const vec3 position = ray.origin + hit.t * ray.direction;
    out_[Pass::Depth].x += glm::dot(position - vec3(camera_.world_from_camera[3]), forward);
}

// Cycles' film_write_denoising_features_surface: a surface whose lobes are mostly specular
// passes its tint on to the next surface the path meets (along the path's own bounce, which
// scatter() samples as before: no random number is drawn here), the first other one writes the
// guides.
void PathIntegrator::record_denoising_features(const Shading& shading) {
    const DenoisingFeature feature = shading.bsdf.denoising_feature(shading.wo.z);
    if (!feature.writes_guides()) {
        denoising_throughput_ *= feature.specular_albedo;
        return;
    }
    const vec3 albedo = denoising_throughput_ * feature.albedo;
    if (is_finite(albedo)) out_[Pass::DenoisingAlbedo] += albedo;
    if (feature.weight > 0.0f) out_[Pass::DenoisingNormal] += shading.frame.z;
    write_denoising_features_ = false;
}

// Next-event estimation at the current surface, MIS-weighted against BSDF sampling.
void PathIntegrator::sample_direct() {
    ScopedTimer timer(clock_ != nullptr && clock_->time_direct ? &clock_->direct : nullptr);
    Ray shadows[kMaxLightSplits];
    const int count = prepare_direct(shadows);
    for (int k = 0; k < count; ++k) {
        if (clock_ != nullptr) ++clock_->rays;
        if (!scene_.occluded(shadows[k])) add_direct(k);
    }
}

int PathIntegrator::prepare_direct(Ray* shadows) {
    const Shading& shading = shading_.value;
    if (!shading.bsdf.has_smooth_lobes()) return 0;  // a Dirac lobe never meets a light sample
    // Left unset: sample_split() writes every sample it returns (zeroing all kMaxLightSplits
    // of them cost more than the one a one-lamp room uses).
    Uninitialized<LightSample[kMaxLightSplits]> samples;
    float u_select, u_x, u_y;
    if (vertex_ == 0 && first_light_sample_) {
        // The three numbers the stratified ones replace are skipped, not drawn: the same state
        // for the rest of the path (PCG's advance by a constant folds to one multiply-add).
        rng_.advance(3);
        u_select = first_light_sample_->u_select;
        u_x = first_light_sample_->u.x;
        u_y = first_light_sample_->u.y;
    } else {
        u_select = rng_.next_float();
        u_x = rng_.next_float();
        u_y = rng_.next_float();
    }
    const vec2 u(u_x, u_y);
    const int sampled = lights_.sample_split(shading.position, shading.frame.z, u_select, u,
                                             samples.value);
    return direct_from_samples(shadows, samples.value, sampled);
}

bool PathIntegrator::begin_direct(const LightSample* samples, int sampled, vec3* wi) {
    if (vertex_ != 0 || !first_light_sample_ || sampled > 1)
        throw Internal("PathIntegrator::begin_direct: only at the first surface of a path with "
                       "set_first_light_sample, for at most one light sample");
    if (!shading_.value.bsdf.has_smooth_lobes()) return false;
    rng_.advance(3);  // as prepare_direct(shadows): the numbers the stratified ones replace
    return sampled == 1 && light_direction(samples[0], wi);
}

int PathIntegrator::finish_direct(Ray* shadows, const LightSample& sample, const vec3& wi,
                                  const BsdfEval& eval) {
    return add_pending_direct(shadows, 0, sample, wi, eval) ? 1 : 0;
}

bool PathIntegrator::light_direction(const LightSample& ls, vec3* wi) const {
    const Shading& shading = shading_.value;
    *wi = shading.frame.to_local(ls.wi);
    const bool geometric_above = glm::dot(ls.wi, shading.geometric_normal) > 0.0f;
    return geometric_above == (wi->z > 0.0f);
}

bool PathIntegrator::add_pending_direct(Ray* shadows, int k, const LightSample& ls,
                                        const vec3& wi, const BsdfEval& eval) {
    if (max_component(eval.total()) <= 0.0f) return false;
    shadows[k] = light_shadow_ray(shading_.value.spawn_origin(ls.wi), ls.wi, ls.distance);
    ::new (&pending_[k].value) PendingDirect{ls, wi, eval};
    return true;
}

// The BSDF toward each light sample and the shadow rays of those it lets through.
int PathIntegrator::direct_from_samples(Ray* shadows, const LightSample* samples, int sampled) {
    const Shading& shading = shading_.value;
    int count = 0;
    for (int i = 0; i < sampled; ++i) {
        const LightSample& ls = samples[i];
        vec3 wi;
        if (!light_direction(ls, &wi)) continue;
        const BsdfEval eval = vertex_field() != nullptr ? shading.bsdf.eval_field(shading.wo, wi)
                                                        : shading.bsdf.eval(shading.wo, wi);
        if (add_pending_direct(shadows, count, ls, wi, eval)) ++count;
    }
    return count;
}

void PathIntegrator::add_direct(int k) {
    const Shading& shading = shading_.value;
    const PendingDirect& pending = pending_[k].value;
    const LightSample& ls = pending.light;
    const bool mis = !ls.delta && vertex_field() == nullptr;
    const float weight =
        mis ? power_heuristic(ls.pdf, shading.bsdf.pdf(shading.wo, pending.wi)) : 1.0f;
    const vec3 scale = throughput_ * ls.radiance * (weight / ls.pdf);
    if (vertex_ == 0) {  // direct light at the first surface, split by the lobes it lit
        for (int c = 0; c < kLobeClassCount; ++c)
            add_light(pending.eval.by_class[c] * scale, c, true);
        return;
    }
    add_split(pending.eval.total() * scale, false);
}

// Indirect light from the field through the field lobes (see the header).
void PathIntegrator::add_field(const Shading& shading) {
    if (field_->is_zero()) return;  // every term below would be zero
    // The first surface of a quad's pixel: the quad read its pixels' albedo tables in four
    // lanes (QuadGlossy::burley_albedo, the same bits), so the four table chains overlap.
    QuadGlossy* quad = vertex_ == 0 && shared_lookup_ != nullptr ? joined_quad() : nullptr;
    FieldLobes lobes;
    if (quad != nullptr) {
        lobes.glossy_count = shading.bsdf.field_lobes_with(quad->burley_albedo(glossy_slot_),
                                                           quad->ggx_albedo(glossy_slot_),
                                                           &lobes.diffuse, lobes.glossy);
    } else {
        lobes.diffuse = shading.bsdf.field_diffuse(shading.wo);
        lobes.glossy_count = shading.bsdf.field_glossy_lobes(shading.wo, lobes.glossy);
    }
    lobes.bumped = diffuse_bump(shading, &lobes.bump);
    if (max_component(lobes.diffuse) <= 0.0f && lobes.glossy_count == 0) return;
    if (vertex_ == 0 && shared_lookup_ != nullptr) {
        // The quad's query holds wo already (join_quad_glossy: the same bits).
        const vec3 wo =
            quad != nullptr ? quad->wo(glossy_slot_) : shading.frame.to_world(shading.wo);
        add_field_light(*shared_lookup_, lobes, shading.frame.z, wo, shared_irradiance_, quad);
        return;
    }
    const vec3 wo = shading.frame.to_world(shading.wo);
    // The lookup's result binds to the parameter directly: no copy of its SH. Behind a final
    // gather's bounces, one estimate of the field serves (gather_lookup).
    // Placed by the interpolated normal (field_lookup_normal, which the bump already holds).
    const vec3 n = lobes.bumped ? lobes.bump.smooth_normal : shading.frame.z;
    add_field_light(field_from_ > 0 ? field_->gather_lookup(shading.position, n, wo, gather_u_)
                                    : field_->view_lookup(shading.position, n, wo),
                    lobes, shading.frame.z, wo);
}

void PathIntegrator::add_field_light(const FieldLookup& field, const FieldLobes& lobes,
                                     const vec3& n, const vec3& wo, IrradianceMemo* irradiance,
                                     QuadGlossy* glossy) {
    const vec3 e = lobes.bumped          ? field.irradiance(n, lobes.bump)
                   : irradiance != nullptr ? irradiance->irradiance(field, n)
                                           : field.irradiance(n);
    vec3 by_class[2] = {lobes.diffuse * e * kInvPi, vec3(0.0f)};
    for (int i = 0; i < lobes.glossy_count; ++i) {
        const float roughness = lobes.glossy[i].roughness;
        const float slot_roughness =
            glossy != nullptr ? glossy->roughness(glossy_slot_) : roughness;
        // Bits, not ==: a NaN roughness must reach field.glossy's check.
        const bool shared = glossy != nullptr &&
                            std::memcmp(&roughness, &slot_roughness, sizeof(float)) == 0;
        by_class[1] += lobes.glossy[i].albedo *
                       (shared ? glossy->radiance(glossy_slot_, field, glossy_memo_)
                               : field.glossy(n, wo, roughness, glossy_memo_));
    }
    if (vertex_ == 0) {
        for (int c = 0; c < 2; ++c) add_light(throughput_ * by_class[c], c, false);
        return;
    }
    add_split(throughput_ * (by_class[0] + by_class[1]), false);
}

bool PathIntegrator::first_field_query(vec3* position, vec3* normal, vec3* wo) const {
    if (vertex_field() == nullptr || field_->is_zero() || vertex_ != 0) return false;
    *position = shading_.value.position;
    *normal = shgi::field_lookup_normal(shading_.value);
    *wo = shading_.value.frame.to_world(shading_.value.wo);
    return true;
}

// Samples the BSDF, updates throughput, bounce counts and MIS state; false ends the path. At a
// field vertex only where the BSDF has a traced lobe (finish() ends the path otherwise).
bool PathIntegrator::scatter(const Shading& shading, Ray* ray) {
    const bool field_vertex = vertex_field() != nullptr;  // with a traced lobe (finish())
    BsdfSample bs;
    float u_lobe = rng_.next_float();
    vec2 u = rng_.next_vec2();
    if (vertex_ == 0 && first_bsdf_sample_) {
        u_lobe = first_bsdf_sample_->u_select;
        u = first_bsdf_sample_->u;
    }
    const bool sampled = field_vertex ? shading.bsdf.sample_traced(shading.wo, u_lobe, u, &bs)
                                      : shading.bsdf.sample(shading.wo, u_lobe, u, &bs);
    if (!sampled) return false;
    const vec3 wi = shading.frame.to_world(bs.wi);
    const bool geometric_above = glm::dot(wi, shading.geometric_normal) > 0.0f;
    if (geometric_above != (bs.wi.z > 0.0f)) return false;
    if (vertex_ == 0) {
        // Cycles' pass_diffuse_weight / pass_glossy_weight: the classes' shares of the BSDF.
        const vec3 total = bs.eval.total();
        const float sum = total.x + total.y + total.z;
        for (int c = 0; c < kLobeClassCount; ++c) {
            const vec3 part = bs.eval.by_class[c];
            class_fraction_[c] = sum > 0.0f ? (part.x + part.y + part.z) / sum : 0.0f;
        }
    }
    ++bounces_[int(bs.lobe_class)];
    throughput_ *= bs.weight;
    last_delta_ = bs.delta || field_vertex;  // a field vertex's NEE skips traced lobes
    if (!bs.delta) {
        // Cycles' min_ray_pdf takes the whole BSDF's pdf, which a field vertex's sample (of
        // the traced lobes alone) does not give.
        if (settings_.filter_glossy > 0.0f)
            min_ray_pdf_ = std::min(
                min_ray_pdf_, field_vertex ? shading.bsdf.pdf(shading.wo, bs.wi) : bs.pdf);
    }
    last_pdf_ = bs.pdf;
    last_normal_ = shading.frame.z;
    ++vertex_;
    ray->origin = shading.spawn_origin(wi);
    ray->direction = wi;
    ray->tmin = 0.0f;
    ray->tmax = kInfinity;
    return max_component(throughput_) > 0.0f;
}

}  // namespace shgi
