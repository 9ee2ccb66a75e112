#include "render/quad_glossy.h"

#include "render/vec3_lanes.h"
#include "sh/ggx_zh.h"

namespace shgi {
namespace {

#if defined(__SSE2__)
// The queries' inputs, one lane per slot; factors[l] holds each lane's k_l.
struct GlossyLanes {
    Vec3Lanes n, wo;
    __m128 roughness;
    __m128 factors[3];
};

// FieldLookup::glossy's closed form for an SH of order kOrder <= 2, in the same operations per
// lane: the reflected direction, for a horizon field the dominant direction
// (glossy_dominant_direction) and the upper hemisphere's read (indirect_field.cpp's
// upper_hemisphere_read, whose band-3 term orders up to 2 lack), the nine-term sums per channel
// (sh_evaluate_scaled with sh_eval_low_bands' basis) and the clamp at 0.
template <int kOrder>
void glossy_closed_form(const ShRgb& radiance, bool horizon, const GlossyLanes& in,
                        __m128 out[3]) {
    const __m128 zero = _mm_setzero_ps();
    const __m128 two_cos = _mm_mul_ps(_mm_set1_ps(2.0f), dot_lanes(in.wo, in.n));
    Vec3Lanes dir = {_mm_sub_ps(_mm_mul_ps(two_cos, in.n.x), in.wo.x),
                     _mm_sub_ps(_mm_mul_ps(two_cos, in.n.y), in.wo.y),
                     _mm_sub_ps(_mm_mul_ps(two_cos, in.n.z), in.wo.z)};
    const bool dominant = horizon && kOrder >= 1;
    if (dominant) {
        const __m128 alpha = _mm_mul_ps(in.roughness, in.roughness);
        const __m128 one_minus = _mm_sub_ps(_mm_set1_ps(1.0f), alpha);
        const __m128 lean = _mm_mul_ps(one_minus, _mm_add_ps(_mm_sqrt_ps(one_minus), alpha));
        const Vec3Lanes towards = {
            _mm_add_ps(in.n.x, _mm_mul_ps(lean, _mm_sub_ps(dir.x, in.n.x))),
            _mm_add_ps(in.n.y, _mm_mul_ps(lean, _mm_sub_ps(dir.y, in.n.y))),
            _mm_add_ps(in.n.z, _mm_mul_ps(lean, _mm_sub_ps(dir.z, in.n.z)))};
        const __m128 length2 = dot_lanes(towards, towards);
        const __m128 length = _mm_sqrt_ps(length2);
        // glossy_dominant_direction's threshold: below it (a view from below n) the direction is n.
        const __m128 long_enough = _mm_cmpgt_ps(length2, _mm_set1_ps(1e-12f));
        dir = {select_lanes(long_enough, _mm_div_ps(towards.x, length), in.n.x),
               select_lanes(long_enough, _mm_div_ps(towards.y, length), in.n.y),
               select_lanes(long_enough, _mm_div_ps(towards.z, length), in.n.z)};
    }
    // sh_eval_low_bands' expressions.
    __m128 basis[9];
    basis[0] = _mm_set1_ps(kShY00);
    if constexpr (kOrder >= 1) {
        const __m128 y1 = _mm_set1_ps(kShY1);
        basis[1] = _mm_mul_ps(y1, dir.y);
        basis[2] = _mm_mul_ps(y1, dir.z);
        basis[3] = _mm_mul_ps(y1, dir.x);
    }
    if constexpr (kOrder >= 2) {
        const __m128 xy = _mm_set1_ps(kShY2xy);
        basis[4] = _mm_mul_ps(_mm_mul_ps(xy, dir.x), dir.y);
        basis[5] = _mm_mul_ps(_mm_mul_ps(xy, dir.y), dir.z);
        basis[6] = _mm_mul_ps(
            _mm_set1_ps(kShY20),
            _mm_sub_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(3.0f), dir.z), dir.z), _mm_set1_ps(1.0f)));
        basis[7] = _mm_mul_ps(_mm_mul_ps(xy, dir.x), dir.z);
        basis[8] = _mm_mul_ps(_mm_set1_ps(kShY22),
                              _mm_sub_ps(_mm_mul_ps(dir.x, dir.x), _mm_mul_ps(dir.y, dir.y)));
    }
    __m128 read = _mm_setzero_ps();
    if (dominant) {
        const __m128 cosine = _mm_max_ps(zero, dot_lanes(in.n, dir));  // std::max(c, 0)
        read = _mm_add_ps(_mm_set1_ps(0.5f),
                          _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(0.75f), in.factors[1]), cosine));
    }
    const float* coeffs = radiance.data();
    for (int channel = 0; channel < 3; ++channel) {
        __m128 sum = zero;
        for (int l = 0; l <= kOrder; ++l)
            for (int i = l * l; i <= l * (l + 2); ++i)
                sum = _mm_add_ps(sum, _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(coeffs[3 * i + channel]),
                                                            in.factors[l]),
                                                 basis[i]));
        // glm::max(sum, 0): (sum < 0) ? 0 : sum, which MAXPS(0, sum) is, NaN and -0 included.
        sum = _mm_max_ps(zero, sum);
        out[channel] = dominant ? _mm_div_ps(sum, read) : sum;
    }
}
#endif

}  // namespace

void QuadGlossy::read_albedos() {
    albedos_read_ = true;
    // Lanes past count_ repeat slot 0 (their results are not read).
    for (int k = count_; k < kSlots && count_ > 0; ++k) {
        cos_nv_[k] = cos_nv_[0];
        diffuse_roughness_[k] = diffuse_roughness_[0];
        roughness_[k] = roughness_[0];
    }
    field_albedo_lanes(cos_nv_, diffuse_roughness_, roughness_, &albedos_);
}

void QuadGlossy::evaluate(const FieldLookup& lookup, GgxZhMemo* zh) {
    evaluated_ = true;
    const int order = lookup.radiance.order;
#if defined(__SSE2__)
    if (lookup.glossy_rays == 0 && order <= 2 && count_ > 0) {
        // Lanes past count_ repeat slot 0 (their results are not read).
        for (int k = count_; k < kSlots; ++k) {
            for (int c = 0; c < 3; ++c) {
                n_[c][k] = n_[c][0];
                wo_[c][k] = wo_[c][0];
            }
            roughness_[k] = roughness_[0];
        }
        const __m128 roughness = _mm_load_ps(roughness_);
        // The band factors FieldLookup::glossy reads: a quad's pixels mostly share one
        // material, hence one roughness (compared as bits).
        const __m128i bits = _mm_castps_si128(roughness);
        const bool one_roughness =
            _mm_movemask_epi8(_mm_cmpeq_epi32(bits, _mm_shuffle_epi32(bits, 0))) == 0xFFFF;
        __m128 factors[3];
        if (one_roughness) {
            const BandFactors band = ggx_specular_zh_factors(roughness_[0], zh);
            for (int l = 0; l < 3; ++l) factors[l] = _mm_set1_ps(band[l]);
        } else {
            alignas(16) float lanes[3][kSlots];
            for (int k = 0; k < kSlots; ++k) {
                const BandFactors band = ggx_specular_zh_factors(roughness_[k], zh);
                for (int l = 0; l < 3; ++l) lanes[l][k] = band[l];
            }
            for (int l = 0; l < 3; ++l) factors[l] = _mm_load_ps(lanes[l]);
        }
        const GlossyLanes in = {{_mm_load_ps(n_[0]), _mm_load_ps(n_[1]), _mm_load_ps(n_[2])},
                                {_mm_load_ps(wo_[0]), _mm_load_ps(wo_[1]), _mm_load_ps(wo_[2])},
                                roughness,
                                {factors[0], factors[1], factors[2]}};
        __m128 out[3];
        switch (order) {
            case 0: glossy_closed_form<0>(lookup.radiance, lookup.horizon, in, out); break;
            case 1: glossy_closed_form<1>(lookup.radiance, lookup.horizon, in, out); break;
            default: glossy_closed_form<2>(lookup.radiance, lookup.horizon, in, out); break;
        }
        for (int c = 0; c < 3; ++c) _mm_store_ps(radiance_[c], out[c]);
        return;
    }
#endif
    for (int k = 0; k < count_; ++k) {
        const vec3 n(n_[0][k], n_[1][k], n_[2][k]);
        const vec3 radiance = lookup.glossy(n, wo(k), roughness_[k], zh);
        for (int c = 0; c < 3; ++c) radiance_[c][k] = radiance[c];
    }
}

}  // namespace shgi
