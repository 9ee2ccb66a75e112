// PrincipledBsdf::eval_field for four BSDFs at once, in SSE2 lanes.
//
// The preview's light stage evaluates every first surface's field lobes toward its light
// sample (PathIntegrator::direct_from_eval); one eval_field is a dependent chain (the half
// vector's square root and division, the GGX terms' square roots and divisions, the Fresnel's)
// that leaves the CPU waiting on its end (docs/frame-pipeline.md, 2026-11-30, direct16). Here
// four surfaces are the four lanes of SSE2 vectors, so their chains run together. Each lane
// takes eval_field's IEEE operations in its order (glm's dot and normalize, 1 / sqrt then a
// product; ggx_d, ggx_g1, height_correlated_masking, fresnel_dielectric, specular_color and
// diffuse_brdf as bsdf.cpp writes them; no FMA: the build has none, and -ffp-contract=off), and
// each branch of the scalar code becomes a select, so each surface gets the bits eval_field
// gives it (tests/cpp/render/bsdf_lanes_test.cpp compares them over random inputs and edge
// cases). The lanes cover the common lobes, a diffuse lobe (Lambert or principled) and one GGX
// specular lobe of either Smith G; glass lobes, light paths, bent normals and BSDFs without
// lobes go through eval_field (eval_field_in_lanes).
#include "render/bsdf.h"

#include "render/vec3_lanes.h"

#include <cstddef>
#include <cstdint>

namespace shgi {

#if defined(__SSE2__)
namespace {

constexpr int kLanes = 4;

// std::clamp(x, 0, 1), which is std::min(std::max(x, 0), 1): (x < 0) ? 0 : x, then
// (1 < y) ? 1 : y, which MAXPS(0, x) and MINPS(1, y) are, NaN included.
__m128 clamp01_lanes(__m128 x) {
    return _mm_min_ps(_mm_set1_ps(1.0f), _mm_max_ps(_mm_setzero_ps(), x));
}

// (1 - x)^5 as bsdf.cpp's schlick_weight: m = clamp(1 - x), (m^2 m^2) m.
__m128 schlick_weight_lanes(__m128 x) {
    const __m128 m = clamp01_lanes(_mm_sub_ps(_mm_set1_ps(1.0f), x));
    const __m128 m2 = _mm_mul_ps(m, m);
    return _mm_mul_ps(_mm_mul_ps(m2, m2), m);
}

// ggx_g1(w, alpha) from w.z and alpha^2: 2 c / (c + sqrt(a2 + (1 - a2) c c)), c = min(|w.z|, 1),
// 0 unless c > 0.
__m128 ggx_g1_lanes(__m128 wz, __m128 a2) {
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    // std::min(|w.z|, 1.0f) = (1 < c) ? 1 : c.
    const __m128 c = _mm_min_ps(_mm_set1_ps(1.0f), _mm_and_ps(wz, abs_mask));
    const __m128 root = _mm_sqrt_ps(
        _mm_add_ps(a2, _mm_mul_ps(_mm_mul_ps(_mm_sub_ps(_mm_set1_ps(1.0f), a2), c), c)));
    const __m128 g1 = _mm_div_ps(_mm_mul_ps(_mm_set1_ps(2.0f), c), _mm_add_ps(c, root));
    return _mm_and_ps(_mm_cmpgt_ps(c, _mm_setzero_ps()), g1);
}

// fresnel_dielectric(cos_i, eta): 1 where g = eta^2 - 1 + c^2 is not positive.
__m128 fresnel_dielectric_lanes(__m128 cos_i, __m128 eta) {
    const __m128 one = _mm_set1_ps(1.0f);
    const __m128 c = _mm_and_ps(cos_i, _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff)));
    const __m128 g2 = _mm_add_ps(_mm_sub_ps(_mm_mul_ps(eta, eta), one), _mm_mul_ps(c, c));
    const __m128 g = _mm_sqrt_ps(g2);
    const __m128 a_num = _mm_sub_ps(g, c), a_den = _mm_add_ps(g, c);
    const __m128 b_num = _mm_sub_ps(_mm_mul_ps(c, a_den), one);
    const __m128 b_den = _mm_add_ps(_mm_mul_ps(c, a_num), one);
    const __m128 numerator =
        _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(0.5f), a_num), a_num),
                   _mm_add_ps(_mm_mul_ps(b_den, b_den), _mm_mul_ps(b_num, b_num)));
    const __m128 denominator =
        _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(a_den, a_den), b_den), b_den);
    return select_lanes(_mm_cmple_ps(g2, _mm_setzero_ps()), one,
                        _mm_div_ps(numerator, denominator));
}

// A vec3 as (x, y, z, 0), reading its 12 bytes alone, a float at a time: the light stage has
// just written the directions by component, and a wider load of narrower stores is not
// forwarded.
__m128 load_vec3(const vec3& v) {
    const __m128 xy = _mm_unpacklo_ps(_mm_load_ss(&v.x), _mm_load_ss(&v.y));
    return _mm_movelh_ps(xy, _mm_load_ss(&v.z));
}

// Four rows (one per lane) of three or four floats to per-component lanes.
Vec3Lanes transpose3(__m128 r0, __m128 r1, __m128 r2, __m128 r3) {
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    return {r0, r1, r2};
}

// The lane mask of bits b (lane k all ones where bit k is set): a table read rather than four
// scalars moved into a vector.
__m128 mask_lanes(int bits) {
    alignas(16) static constexpr uint32_t kMasks[16][4] = {
        {0, 0, 0, 0},   {~0u, 0, 0, 0},   {0, ~0u, 0, 0},   {~0u, ~0u, 0, 0},
        {0, 0, ~0u, 0}, {~0u, 0, ~0u, 0}, {0, ~0u, ~0u, 0}, {~0u, ~0u, ~0u, 0},
        {0, 0, 0, ~0u}, {~0u, 0, 0, ~0u}, {0, ~0u, 0, ~0u}, {~0u, ~0u, 0, ~0u},
        {0, 0, ~0u, ~0u}, {~0u, 0, ~0u, ~0u}, {0, ~0u, ~0u, ~0u}, {~0u, ~0u, ~0u, ~0u}};
    return _mm_load_ps(reinterpret_cast<const float*>(kMasks[bits]));
}

}  // namespace
#endif

void PrincipledBsdf::eval_field_lanes(const PrincipledBsdf* const bsdf[4],
                                      const vec3* const wo[4], const vec3* const wi[4],
                                      BsdfEval* const out[4]) {
#if defined(__SSE2__)
    // The lanes' inputs, gathered by whole rows and transposed: 16-byte loads of each BSDF's
    // members (which their layout allows, checked below) rather than scalar stores read back as
    // vectors, which cannot be forwarded and stalled each group (`perf annotate`: ~16% of
    // this function's samples on the first vector after such a gather).
    static_assert(offsetof(Lobe, alpha) == offsetof(Lobe, weight) + 3 * sizeof(float));
    static_assert(offsetof(PrincipledBsdf, specular_ior_) ==
                  offsetof(PrincipledBsdf, cspec0_) + 3 * sizeof(float));
    static_assert(offsetof(PrincipledBsdf, inv_one_minus_f0_) ==
                      offsetof(PrincipledBsdf, specular_f0_) + sizeof(float) &&
                  offsetof(PrincipledBsdf, roughness_) ==
                      offsetof(PrincipledBsdf, specular_f0_) + 3 * sizeof(float));
    // Per lane: its diffuse lobe is lobes_[0] and its specular lobe the last one (add_lobe's
    // order; eval_field_in_lanes: one or two lobes, diffuse and specular). A lane without one
    // of them reads the other lobe's row and drops what it computes from it.
    __m128 diffuse_rows[4], specular_rows[4], color_rows[4], fresnel_rows[4];
    int has_diffuse = 0, has_specular = 0, lambert = 0, correlated = 0;  // bit k: lane k
    for (int k = 0; k < kLanes; ++k) {
        const PrincipledBsdf& b = *bsdf[k];
        const Lobe& first = b.lobes_[0];
        const Lobe& last = b.lobes_[b.lobe_count_ - 1];
        has_diffuse |= int(first.kind == LobeKind::Diffuse) << k;
        // eval_field skips a traced (Dirac) specular lobe.
        has_specular |= int(last.kind == LobeKind::Specular && !last.delta()) << k;
        lambert |= int(b.diffuse_model_ == DiffuseModel::Lambert) << k;
        correlated |= int(b.height_correlated_) << k;
        diffuse_rows[k] = _mm_loadu_ps(&first.weight.x);   // weight, alpha
        specular_rows[k] = _mm_loadu_ps(&last.weight.x);   // weight, alpha
        color_rows[k] = _mm_loadu_ps(&b.cspec0_.x);        // cspec0, specular_ior_
        fresnel_rows[k] = _mm_loadu_ps(&b.specular_f0_);   // f0, 1 / (1 - f0), eta, roughness
    }
    const Vec3Lanes wo_lanes =
        transpose3(load_vec3(*wo[0]), load_vec3(*wo[1]), load_vec3(*wo[2]), load_vec3(*wo[3]));
    const Vec3Lanes wi_lanes =
        transpose3(load_vec3(*wi[0]), load_vec3(*wi[1]), load_vec3(*wi[2]), load_vec3(*wi[3]));
    const Vec3Lanes diffuse_weight =
        transpose3(diffuse_rows[0], diffuse_rows[1], diffuse_rows[2], diffuse_rows[3]);
    __m128 s0 = specular_rows[0], s1 = specular_rows[1], s2 = specular_rows[2],
           s3 = specular_rows[3];
    _MM_TRANSPOSE4_PS(s0, s1, s2, s3);
    const Vec3Lanes specular_weight = {s0, s1, s2};
    const __m128 alpha = s3;
    __m128 c0 = color_rows[0], c1 = color_rows[1], c2_row = color_rows[2], c3 = color_rows[3];
    _MM_TRANSPOSE4_PS(c0, c1, c2_row, c3);
    const Vec3Lanes cspec0 = {c0, c1, c2_row};
    const __m128 ior = c3;
    __m128 f0 = fresnel_rows[0], inv_one_minus_f0 = fresnel_rows[1], eta = fresnel_rows[2],
           roughness = fresnel_rows[3];
    _MM_TRANSPOSE4_PS(f0, inv_one_minus_f0, eta, roughness);
    (void)eta;  // the glass lobes' ior, which no lobe in the lanes reads
    const __m128 lambert_mask = mask_lanes(lambert), correlated_mask = mask_lanes(correlated);
    const __m128 diffuse_mask = mask_lanes(has_diffuse), specular_mask = mask_lanes(has_specular);
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    // eval_field's early return: wo.z <= 0 (false for NaN) or !(wi.z > 0) gives zero.
    const __m128 valid =
        _mm_and_ps(_mm_cmpnle_ps(wo_lanes.z, zero), _mm_cmpgt_ps(wi_lanes.z, zero));
    // h = normalize(wo + wi) as glm: s * (1 / sqrt(dot(s, s))).
    const Vec3Lanes s = {_mm_add_ps(wo_lanes.x, wi_lanes.x), _mm_add_ps(wo_lanes.y, wi_lanes.y),
                         _mm_add_ps(wo_lanes.z, wi_lanes.z)};
    const __m128 inv_length = _mm_div_ps(one, _mm_sqrt_ps(dot_lanes(s, s)));
    const Vec3Lanes h = {_mm_mul_ps(s.x, inv_length), _mm_mul_ps(s.y, inv_length),
                         _mm_mul_ps(s.z, inv_length)};
    const __m128 cos_ih = dot_lanes(wi_lanes, h);

    // The diffuse lobe: diffuse_brdf(wo, wi, cos_ih) wi.z, Lambert's 1/pi or Burley's.
    const __m128 fl = schlick_weight_lanes(wi_lanes.z);
    const __m128 fv = schlick_weight_lanes(wo_lanes.z);
    const __m128 rr = _mm_mul_ps(
        _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(2.0f), roughness), cos_ih), cos_ih);
    const __m128 half = _mm_set1_ps(0.5f);
    const __m128 lambert_term = _mm_mul_ps(_mm_sub_ps(one, _mm_mul_ps(half, fl)),
                                      _mm_sub_ps(one, _mm_mul_ps(half, fv)));
    const __m128 retro = _mm_mul_ps(
        rr, _mm_add_ps(_mm_add_ps(fl, fv), _mm_mul_ps(_mm_mul_ps(fl, fv), _mm_sub_ps(rr, one))));
    const __m128 inv_pi = _mm_set1_ps(kInvPi);
    const __m128 brdf = select_lanes(lambert_mask, inv_pi,
                                     _mm_mul_ps(inv_pi, _mm_add_ps(lambert_term, retro)));
    const __m128 cos_factor = _mm_mul_ps(brdf, wi_lanes.z);
    const __m128 diffuse = _mm_and_ps(valid, diffuse_mask);

    // The specular lobe: D G1(wo) / (4 wo.z) times the masking of wi, times its colour.
    const __m128 a2 = _mm_mul_ps(alpha, alpha);
    const __m128 c2 = _mm_mul_ps(h.z, h.z);
    const __m128 denom = _mm_add_ps(_mm_mul_ps(c2, _mm_sub_ps(a2, one)), one);
    const __m128 d = _mm_and_ps(
        _mm_cmpnle_ps(h.z, zero),  // ggx_d: 0 where h.z <= 0 (not where it is NaN)
        _mm_div_ps(a2, _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(kPi), denom), denom)));
    const __m128 g1_o = ggx_g1_lanes(wo_lanes.z, a2);
    const __m128 g1_i = ggx_g1_lanes(wi_lanes.z, a2);
    const __m128 pdf = _mm_div_ps(_mm_mul_ps(g1_o, d), _mm_mul_ps(_mm_set1_ps(4.0f), wo_lanes.z));
    // height_correlated_masking (0 unless both G1 are positive), where a lane's BSDF has it:
    // its three divisions only when one does.
    __m128 masking = g1_i;
    if (correlated != 0) {
        const __m128 correlated_masking = _mm_and_ps(
            _mm_and_ps(_mm_cmpgt_ps(g1_i, zero), _mm_cmpgt_ps(g1_o, zero)),
            _mm_div_ps(one, _mm_mul_ps(g1_o, _mm_sub_ps(_mm_add_ps(_mm_div_ps(one, g1_o),
                                                                   _mm_div_ps(one, g1_i)),
                                                        one))));
        masking = select_lanes(correlated_mask, correlated_masking, g1_i);
    }
    // specular_color(cos_ih): 1 where F0 >= 1, else cspec0 (1 - fh) + fh.
    const __m128 fh = _mm_mul_ps(_mm_sub_ps(fresnel_dielectric_lanes(cos_ih, ior), f0),
                                 inv_one_minus_f0);
    const __m128 white = _mm_cmpge_ps(f0, one);
    const __m128 specular = _mm_and_ps(valid, specular_mask);

    const __m128 one_minus_fh = _mm_sub_ps(one, fh);
    const __m128 pdf_masking = _mm_mul_ps(pdf, masking);
    // by_class starts at 0 and each lobe adds to it: 0 + x (which turns -0 into +0).
    const auto diffuse_value = [&](__m128 weight) {
        return _mm_and_ps(diffuse, _mm_add_ps(zero, _mm_mul_ps(weight, cos_factor)));
    };
    const auto glossy_value = [&](__m128 weight, __m128 cspec0_c) {
        const __m128 color =
            select_lanes(white, one, _mm_add_ps(_mm_mul_ps(cspec0_c, one_minus_fh), fh));
        return _mm_and_ps(specular,
                          _mm_add_ps(zero, _mm_mul_ps(_mm_mul_ps(weight, color), pdf_masking)));
    };
    // Back to rows: each BsdfEval is nine floats, (diffuse rgb, glossy r) then (glossy gb, 0, 0)
    // then the transmission's last 0.
    __m128 r0 = diffuse_value(diffuse_weight.x), r1 = diffuse_value(diffuse_weight.y),
           r2 = diffuse_value(diffuse_weight.z), r3 = glossy_value(specular_weight.x, cspec0.x);
    _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
    __m128 t0 = glossy_value(specular_weight.y, cspec0.y),
           t1 = glossy_value(specular_weight.z, cspec0.z), t2 = zero, t3 = zero;
    _MM_TRANSPOSE4_PS(t0, t1, t2, t3);
    const __m128 rows[4] = {r0, r1, r2, r3}, tails[4] = {t0, t1, t2, t3};
    static_assert(sizeof(BsdfEval) == 9 * sizeof(float));
    for (int k = 0; k < kLanes; ++k) {
        float* eval = &out[k]->by_class[0].x;
        _mm_storeu_ps(eval, rows[k]);
        _mm_storeu_ps(eval + 4, tails[k]);
        eval[8] = 0.0f;
    }
#else
    for (int k = 0; k < 4; ++k) *out[k] = bsdf[k]->eval_field(*wo[k], *wi[k]);
#endif
}

}  // namespace shgi
