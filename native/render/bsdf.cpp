#include "render/bsdf.h"

#include <algorithm>
#include <cmath>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "render/normal_map.h"
#include "util/sampling.h"

namespace shgi {
namespace {

// Cycles 4's mean of Schlick's blend (1 - cos)^5 over the cosine-weighted hemisphere,
// 2 ∫ mu (1 - mu)^5 dmu = 1/21: the metallic lobe's single-scattering mean Fresnel is
// mix(base colour, 1, 1/21).
constexpr float kSchlickAverageBlend = 1.0f / 21.0f;

constexpr float kOneThird = 1.0f / 3.0f;
float average(const vec3& v) { return (v.x + v.y + v.z) * kOneThird; }

// (1 - x)^5, the Schlick weight of Burley's diffuse.
float schlick_weight(float x) {
    const float m = std::clamp(1.0f - x, 0.0f, 1.0f);
    const float m2 = m * m;
    return m2 * m2 * m;
}

// Refracts wo (on the +Z side of the microfacet normal h, wo.h > 0) into the medium of relative
// ior eta; false under total internal reflection.
bool refract_local(const vec3& wo, const vec3& h, float eta, vec3* wi) {
    const float cos_i = glm::dot(wo, h);
    const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return false;
    const float cos_t = std::sqrt(1.0f - sin2_t);
    *wi = -wo / eta + (cos_i / eta - cos_t) * h;
    return true;
}

// Half vector of a refraction pair (wo outside, wi inside, relative ior eta), on wo's side.
vec3 refraction_half_vector(const vec3& wo, const vec3& wi, float eta) {
    vec3 h = wo + eta * wi;
    const float length = glm::length(h);
    if (length <= 0.0f) return vec3(0.0f, 0.0f, 1.0f);
    h /= length;
    return h.z < 0.0f ? -h : h;
}

// --- Tables built once, on first use ---
// Every entry is the mean of an integrand over 16 x 16 stratified samples of the unit square.
constexpr int kStrata = 16;

template <typename Integrand>  // integrand(u) -> vec2
vec2 stratified_mean(Integrand integrand) {
    glm::dvec2 sum(0.0);
    for (int a = 0; a < kStrata; ++a)
        for (int b = 0; b < kStrata; ++b)
            sum += glm::dvec2(
                integrand(vec2((float(a) + 0.5f) / kStrata, (float(b) + 0.5f) / kStrata)));
    return vec2(sum / double(kStrata * kStrata));
}

// A table of T over [0, 1]^3 (x fastest), kX x kY x kZ nodes, read with linear interpolation.
// The node counts are template arguments: a shading point reads two of these tables (the field
// lobes' albedos), and with constant counts the index arithmetic folds away (the same float
// operations as with counts read at run time, so the same values).
template <typename T, int kX, int kY, int kZ>
class LinearTable {
  public:
    static_assert(kX >= 1 && kY >= 1 && kZ >= 1, "a table has at least one node per axis");
    // value(x, y, z) at the nodes' coordinates in [0, 1].
    template <typename Value>
    explicit LinearTable(Value value) : entries_(size_t(kX) * size_t(kY) * size_t(kZ)) {
        for (int k = 0; k < kZ; ++k)
            for (int j = 0; j < kY; ++j)
                for (int i = 0; i < kX; ++i)
                    entries_[index(i, j, k)] = value(node(i, kX), node(j, kY), node(k, kZ));
    }

    T lookup(float x, float y = 0.0f, float z = 0.0f) const {
        int i0, j0, k0;
        float tx, ty, tz;
        split(x, kX, &i0, &tx);
        split(y, kY, &j0, &ty);
        const int i1 = std::min(i0 + 1, kX - 1), j1 = std::min(j0 + 1, kY - 1);
        auto plane = [&](int k) {
            const T bottom = glm::mix(entries_[index(i0, j0, k)], entries_[index(i1, j0, k)], tx);
            const T top = glm::mix(entries_[index(i0, j1, k)], entries_[index(i1, j1, k)], tx);
            return glm::mix(bottom, top, ty);
        };
        if constexpr (kZ == 1) {
            return plane(0);
        } else {
            split(z, kZ, &k0, &tz);
            return glm::mix(plane(k0), plane(k0 + 1), tz);
        }
    }

    // The entries, x fastest (field_albedo_lanes reads them itself).
    const T* entries() const { return entries_.data(); }

  private:
    static float node(int i, int n) { return n > 1 ? float(i) / float(n - 1) : 0.0f; }
    static void split(float x, int n, int* i0, float* t) {
        const float f = std::clamp(x, 0.0f, 1.0f) * float(n - 1);
        *i0 = std::min(int(f), std::max(n - 2, 0));
        *t = n > 1 ? f - float(*i0) : 0.0f;
    }
    static size_t index(int i, int j, int k) {
        return (size_t(k) * size_t(kY) + size_t(j)) * size_t(kX) + size_t(i);
    }
    std::vector<T> entries_;
};

// The view direction at cos(N.V) in the XZ plane.
vec3 view_at(float cos_nv) {
    return vec3(std::sqrt(std::max(0.0f, 1.0f - cos_nv * cos_nv)), 0.0f, cos_nv);
}

// --- Directional albedos of 3.4's lobes, over cos(N.V) x roughness (32 x 32; cos >= 1e-3) ---
constexpr int kAlbedoTableSize = 32;

using AlbedoTable = LinearTable<vec2, kAlbedoTableSize, kAlbedoTableSize, 1>;

template <typename Integrand>  // integrand(wo, roughness, u) -> vec2
AlbedoTable albedo_table(Integrand integrand) {
    return AlbedoTable([&](float x, float y, float) {
        const vec3 wo = view_at(std::max(x, 1e-3f));
        return stratified_mean([&](const vec2& u) { return integrand(wo, y, u); });
    });
}

// Directional albedo of a GGX reflection lobe: x with colour 1, y with the colour fh of
// interpolate_fresnel_color (for Specular 0.5: ior 1.5, F0 0.04), by visible-normal sampling
// (f cos / pdf = G1(wi) for separable Smith GGX).
const AlbedoTable& ggx_albedo_table() {
    static const AlbedoTable table = albedo_table([](const vec3& wo, float r, const vec2& u) {
        const float f0 = kSpecularF0Scale * 0.5f;
        const float ior = 2.0f / (1.0f - std::sqrt(f0)) - 1.0f;
        const float alpha = std::max(r * r, kDeltaAlpha);
        const vec3 h = sample_ggx_visible_normal(wo, alpha, u);
        const vec3 wi = 2.0f * glm::dot(wo, h) * h - wo;
        if (wi.z <= 0.0f) return vec2(0.0f);
        const float weight = ggx_g1(wi, alpha);
        const float fh = (fresnel_dielectric(glm::dot(wi, h), ior) - f0) / (1.0f - f0);
        return vec2(weight, weight * fh);
    });
    return table;
}

// Directional albedo of Cycles' principled diffuse (Burley, with retro-reflection), by cosine
// sampling; Lambert's is 1.
const AlbedoTable& burley_albedo_table() {
    static const AlbedoTable table = albedo_table([](const vec3& wo, float r, const vec2& u) {
        const vec3 wi = sample_cosine_hemisphere(u);
        const float fl = schlick_weight(wi.z), fv = schlick_weight(wo.z);
        const float cos_lh = glm::dot(wi, glm::normalize(wo + wi));
        const float rr = 2.0f * r * cos_lh * cos_lh;
        return vec2((1.0f - 0.5f * fl) * (1.0f - 0.5f * fv) + rr * (fl + fv + fl * fv * (rr - 1.0f)),
                    0.0f);
    });
    return table;
}

// --- Cycles 4's Principled v2 terms (PrincipledModel::V2) ---
// Cycles 4 estimates a GGX reflection lobe's directional albedo, when its Fresnel term blends
// F0..F90 by s(cos_ih), as mix(F0, F90, S) with S the lobe-weighted mean of s
// (bsdf_microfacet_estimate_albedo; the lobe itself is assumed to keep all its energy), and its
// energy-preserving GGX scales the single-scattering lobe by E's complement (Kulla and Conty
// 2017). S, the single-scattering albedo E and its cosine-weighted mean E_avg are tabulated on
// Cycles' grids (cycles_precompute.cpp: S 16 nodes per axis over roughness, cos(N.V) and a Fresnel
// parameter z; E 32 x 32; E_avg 32; roughness and cos(N.V) clamped to >= 1e-4), read with linear
// interpolation as Cycles reads them. Every entry is integrated here by visible-normal sampling
// with Cycles' height-correlated Smith G2, whose sample weight is G2 / G1(wo).
constexpr float kTableMin = 1e-4f;

float clamp_node(float x) { return std::clamp(x, kTableMin, 1.0f); }

// Cycles' Fresnel table parameter z = sqrt((eta - 1) / (eta + 1)) (so z^4 = F0), and the eta of a
// node z (clamped to 0.99).
float fresnel_table_z(float eta) { return std::sqrt(std::fabs((eta - 1.0f) / (eta + 1.0f))); }
float node_eta(float z) {
    const float z2 = std::min(z, 0.99f) * std::min(z, 0.99f);
    return (1.0f + z2) / (1.0f - z2);
}

// E (x: mean sample weight) and S (y: the weight-averaged blend) of a GGX reflection lobe.
template <typename Blend>  // blend(cos_ih) -> s in [0, 1]
vec2 ggx_moments(float roughness, float cos_nv, Blend blend) {
    const vec3 wo = view_at(cos_nv);
    const float alpha = roughness * roughness;
    const float g1_o = ggx_g1(wo, alpha);
    const vec2 mean = stratified_mean([&](const vec2& u) {
        const vec3 h = sample_ggx_visible_normal(wo, alpha, u);
        const float cos_oh = glm::dot(wo, h);
        const vec3 wi = 2.0f * cos_oh * h - wo;
        if (wi.z <= 0.0f) return vec2(0.0f);
        const float w = height_correlated_masking(g1_o, ggx_g1(wi, alpha));
        return vec2(w, w * blend(cos_oh));
    });
    return vec2(mean.x, mean.x > 0.0f ? mean.y / mean.x : 0.0f);
}

// S for the dielectric curve s = (F(cos_ih, eta) - F0(eta)) / (1 - F0(eta)) (Cycles' generalized
// Schlick with a negative exponent), over fresnel_table_z (clamped to [1e-4, 0.99]).
float dielectric_fresnel_blend(float roughness, float cos_nv, float eta) {
    static const LinearTable<float, 16, 16, 16> table([](float x, float y, float z) {
        const float zc = std::clamp(z, kTableMin, 0.99f);
        const float f0 = zc * zc * zc * zc;
        const float eta_z = node_eta(zc);
        return ggx_moments(clamp_node(x), clamp_node(y), [&](float cos_ih) {
                   return std::clamp((fresnel_dielectric(cos_ih, eta_z) - f0) / (1.0f - f0),
                                     0.0f, 1.0f);
               }).y;
    });
    return table.lookup(roughness, cos_nv, fresnel_table_z(eta));
}

// S for Schlick's curve, which Cycles 4 uses for the metallic lobe's estimate: it reads its
// exponent table (z = 1 / (0.2 exponent + 1), 16 nodes) at z = 0.5, halfway between the nodes of
// exponents 40/7 and 35/8, so those two curves are tabulated and averaged here.
float schlick_fresnel_blend(float roughness, float cos_nv) {
    static const LinearTable<float, 16, 16, 2> table([](float x, float y, float z) {
        const float exponent = z == 0.0f ? 40.0f / 7.0f : 35.0f / 8.0f;
        return ggx_moments(clamp_node(x), clamp_node(y), [&](float cos_ih) {
                   return std::pow(std::clamp(1.0f - cos_ih, 0.0f, 1.0f), exponent);
               }).y;
    });
    return table.lookup(roughness, cos_nv, 0.5f);
}

float no_blend(float) { return 0.0f; }

// Single-scattering GGX albedo E(roughness, cos_nv) and its cosine-weighted mean E_avg(roughness)
// = 2 ∫ E(mu) mu dmu (32 midpoints in mu).
float ggx_single_albedo(float roughness, float cos_nv) {
    static const LinearTable<float, 32, 32, 1> table([](float x, float y, float) {
        return ggx_moments(clamp_node(x), clamp_node(y), no_blend).x;
    });
    return table.lookup(roughness, cos_nv);
}

// The cosine-weighted hemispherical mean 2 ∫ f(mu) mu dmu, by the midpoint rule.
template <typename F>
float hemispherical_mean(int steps, F f) {
    double sum = 0.0;
    for (int m = 0; m < steps; ++m) {
        const float mu = (float(m) + 0.5f) / float(steps);
        sum += 2.0 * mu * f(mu);
    }
    return float(sum / steps);
}

float ggx_average_albedo(float roughness) {
    static const LinearTable<float, 32, 1, 1> table([](float x, float, float) {
        return hemispherical_mean(32, [&](float mu) {
            return ggx_moments(clamp_node(x), mu, no_blend).x;
        });
    });
    return table.lookup(roughness);
}

// The hemispherical mean of the dielectric Fresnel (256 midpoints), over fresnel_table_z (64
// nodes) so that shading a hit costs one lookup.
float dielectric_average_fresnel(float eta) {
    static const LinearTable<float, 64, 1, 1> table([](float z, float, float) {
        const float eta_z = node_eta(z);
        return hemispherical_mean(256, [&](float mu) { return fresnel_dielectric(mu, eta_z); });
    });
    return table.lookup(fresnel_table_z(eta));
}

// Cycles 4's energy-preserving GGX (microfacet_ggx_preserve_energy) toward the camera-side
// direction: the share single scattering misses, (1 - E) / E, and E_avg.
struct GgxEnergy {
    float missing = 0.0f;
    float e_avg = 1.0f;
};

GgxEnergy ggx_energy(float roughness, float cos_camera) {
    const float e = std::max(ggx_single_albedo(roughness, cos_camera), 1e-4f);
    return GgxEnergy{(1.0f - e) / e, ggx_average_albedo(roughness)};
}

// A lobe of single-scattering mean Fresnel fss is scaled by 1 + Fms (1 - E) / E; `darkening`
// (that scale over 1 + (1 - E) / E) is what multiplies its closure weight, hence its albedo
// estimate.
struct EnergyPreservation {
    vec3 scale{1.0f};
    vec3 darkening{1.0f};
};

EnergyPreservation energy_preservation(const GgxEnergy& energy, const vec3& fss) {
    const vec3 fms = fss * energy.e_avg / (vec3(1.0f) - fss * (1.0f - energy.e_avg));
    EnergyPreservation result;
    result.scale = vec3(1.0f) + fms * energy.missing;
    result.darkening = result.scale / (1.0f + energy.missing);
    return result;
}

}  // namespace

float burley_albedo(float cos_nv, float roughness) {
    return burley_albedo_table().lookup(cos_nv, roughness).x;
}

vec2 ggx_albedo(float cos_nv, float roughness) {
    return ggx_albedo_table().lookup(cos_nv, roughness);
}

#if defined(__SSE2__)
namespace {

// The entry index of a node pair is row * 32 + column: a shift.
constexpr int kAlbedoTableShift = 5;
static_assert(1 << kAlbedoTableShift == kAlbedoTableSize, "the albedo tables' rows are a shift");

// LinearTable::split of one axis of an AlbedoTable, per lane: the node at or below the clamped
// coordinate and the fraction past it.
struct AxisLanes {
    __m128i node;
    __m128 t;
};

AxisLanes split_lanes(__m128 x) {
    // std::clamp(x, 0, 1) is (x < 0) ? 0 : ((1 < x) ? 1 : x): MAXPS(0, x) is (0 > x) ? 0 : x and
    // MINPS(1, c) is (1 < c) ? 1 : c, the same comparisons (-0 stays -0).
    const __m128 clamped = _mm_min_ps(_mm_set1_ps(1.0f), _mm_max_ps(_mm_setzero_ps(), x));
    const __m128 f = _mm_mul_ps(clamped, _mm_set1_ps(float(kAlbedoTableSize - 1)));
    // std::min(int(f), kAlbedoTableSize - 2), int() truncating as CVTTPS2DQ does.
    const __m128i truncated = _mm_cvttps_epi32(f);
    const __m128i last = _mm_set1_epi32(kAlbedoTableSize - 2);
    const __m128i past = _mm_cmpgt_epi32(truncated, last);
    const __m128i node = _mm_or_si128(_mm_and_si128(past, last), _mm_andnot_si128(past, truncated));
    return {node, _mm_sub_ps(f, _mm_cvtepi32_ps(node))};
}

// glm::mix(a, b, t): a (1 - t) + b t.
__m128 mix_lanes(__m128 a, __m128 b, __m128 t) {
    return _mm_add_ps(_mm_mul_ps(a, _mm_sub_ps(_mm_set1_ps(1.0f), t)), _mm_mul_ps(b, t));
}

// AlbedoTable::lookup(x, y) per lane, both components (out[0]: x, out[1]: y); `column` is the
// split of x, which the field's two tables share.
void lookup_lanes(const AlbedoTable& table, const AxisLanes& column, __m128 y, __m128 out[2]) {
    const AxisLanes row = split_lanes(y);
    alignas(16) int32_t corner[4];  // each lane's (i0, j0) entry
    _mm_store_si128(reinterpret_cast<__m128i*>(corner),
                    _mm_add_epi32(_mm_slli_epi32(row.node, kAlbedoTableShift), column.node));
    // Entries (i0, j) and (i1, j) = (i0 + 1, j) are adjacent: one load holds a row's two
    // corners, (x, y) each; rows j0 and j1 = j0 + 1 are a table width apart.
    const float* entries = reinterpret_cast<const float*>(table.entries());
    __m128 bottom[4], top[4];
    for (int k = 0; k < 4; ++k) {
        const float* at = entries + 2 * corner[k];
        bottom[k] = _mm_loadu_ps(at);
        top[k] = _mm_loadu_ps(at + 2 * kAlbedoTableSize);
    }
    // By lane: the (i0, x), (i0, y), (i1, x), (i1, y) values.
    _MM_TRANSPOSE4_PS(bottom[0], bottom[1], bottom[2], bottom[3]);
    _MM_TRANSPOSE4_PS(top[0], top[1], top[2], top[3]);
    for (int c = 0; c < 2; ++c)
        out[c] = mix_lanes(mix_lanes(bottom[c], bottom[2 + c], column.t),
                           mix_lanes(top[c], top[2 + c], column.t), row.t);
}

}  // namespace
#endif

void field_albedo_lanes(const float cos_nv[4], const float diffuse_roughness[4],
                        const float glossy_roughness[4], FieldAlbedoLanes* out) {
#if defined(__SSE2__)
    const AxisLanes view = split_lanes(_mm_loadu_ps(cos_nv));
    __m128 burley[2], ggx[2];
    lookup_lanes(burley_albedo_table(), view, _mm_loadu_ps(diffuse_roughness), burley);
    lookup_lanes(ggx_albedo_table(), view, _mm_loadu_ps(glossy_roughness), ggx);
    _mm_store_ps(out->burley, burley[0]);
    _mm_store_ps(out->ggx[0], ggx[0]);
    _mm_store_ps(out->ggx[1], ggx[1]);
#else
    for (int k = 0; k < 4; ++k) {
        out->burley[k] = burley_albedo(cos_nv[k], diffuse_roughness[k]);
        const vec2 ggx = ggx_albedo(cos_nv[k], glossy_roughness[k]);
        out->ggx[0][k] = ggx.x;
        out->ggx[1][k] = ggx.y;
    }
#endif
}

float ggx_d(const vec3& h, float alpha) {
    if (h.z <= 0.0f) return 0.0f;
    const float a2 = alpha * alpha;
    const float c2 = h.z * h.z;
    const float denom = c2 * (a2 - 1.0f) + 1.0f;
    return a2 / (kPi * denom * denom);
}

float ggx_g1(const vec3& w, float alpha) {
    // 2 / (1 + sqrt(1 + alpha^2 tan^2)) with tan^2 = (1 - c^2) / c^2, multiplied through by c:
    // one division instead of two.
    const float c = std::min(std::fabs(w.z), 1.0f);
    if (!(c > 0.0f)) return 0.0f;
    const float a2 = alpha * alpha;
    return 2.0f * c / (c + std::sqrt(a2 + (1.0f - a2) * c * c));
}

vec3 sample_ggx_visible_normal(const vec3& w, float alpha, const vec2& u) {
    const vec3 vh = glm::normalize(vec3(alpha * w.x, alpha * w.y, w.z));
    const float length2 = vh.x * vh.x + vh.y * vh.y;
    const vec3 t1 = length2 > 0.0f ? vec3(-vh.y, vh.x, 0.0f) / std::sqrt(length2)
                                   : vec3(1.0f, 0.0f, 0.0f);
    const vec3 t2 = glm::cross(vh, t1);
    const float r = std::sqrt(u.x);
    const float phi = kTwoPi * u.y;
    const float p1 = r * std::cos(phi);
    const float s = 0.5f * (1.0f + vh.z);
    const float p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * r * std::sin(phi);
    const vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
    return glm::normalize(vec3(alpha * nh.x, alpha * nh.y, std::max(0.0f, nh.z)));
}

float fresnel_dielectric(float cos_i, float eta) {
    const float c = std::fabs(cos_i);
    float g = eta * eta - 1.0f + c * c;
    if (g <= 0.0f) return 1.0f;
    g = std::sqrt(g);
    // 0.5 a^2 (1 + b^2) with a = (g - c) / (g + c) and b = (c (g + c) - 1) / (c (g - c) + 1),
    // over one common denominator: one division instead of two on every shading's critical path.
    const float a_num = g - c, a_den = g + c;
    const float b_num = c * a_den - 1.0f, b_den = c * a_num + 1.0f;
    return 0.5f * a_num * a_num * (b_den * b_den + b_num * b_num) /
           (a_den * a_den * b_den * b_den);
}

LobeClass PrincipledBsdf::Lobe::lobe_class() const {
    switch (kind) {
        case LobeKind::Diffuse: return LobeClass::Diffuse;
        case LobeKind::Refraction: return LobeClass::Transmission;
        default: return LobeClass::Glossy;
    }
}

PrincipledBsdf::PrincipledBsdf(const Material& material, const vec3& base_color, bool back_face,
                               float cos_nv, PathOrigin origin)
    : PrincipledBsdf(material, material_terms(material), base_color, back_face, cos_nv, origin) {}

PrincipledBsdf::PrincipledBsdf(const Material& material, const MaterialTerms& terms,
                               const vec3& base_color, bool back_face, float cos_nv,
                               PathOrigin origin)
    : roughness_(material.roughness),
      glossy_roughness_(material.roughness),
      diffuse_model_(material.diffuse_model),
      height_correlated_(material.principled_model == PrincipledModel::V2) {
    add_material_lobes(material, terms, base_color, back_face, cos_nv, origin);
    selection_cos_nv_ = cos_nv;  // select_lobes on first use (ensure_selected)
    selection_pending_ = true;
}

bool PrincipledBsdf::lobes_depend_on_hit_only_by_view(const Material& material,
                                                      const MaterialTerms& terms) {
    // A base colour texture changes the weights per hit; Blender 4's specular layer and the
    // glass lobes' Fresnel weigh the lobes by the view angle.
    return material.base_color_texture == kNoTexture && terms.transmission <= 0.0f &&
           !(material.principled_model == PrincipledModel::V2 && terms.specular);
}

PrincipledBsdf PrincipledBsdf::material_lobes(const Material& material,
                                              const MaterialTerms& terms) {
    PrincipledBsdf lobes;
    lobes.roughness_ = material.roughness;
    lobes.glossy_roughness_ = material.roughness;
    lobes.diffuse_model_ = material.diffuse_model;
    lobes.height_correlated_ = material.principled_model == PrincipledModel::V2;
    // cos_nv and origin are not read for such a material (no V2 layer, no glass lobes).
    lobes.add_material_lobes(material, terms, material.base_color, false, 1.0f,
                             PathOrigin::Camera);
    return lobes;
}

PrincipledBsdf::PrincipledBsdf(const PrincipledBsdf& material_lobes, const Material& material,
                               const MaterialTerms& terms, bool back_face, float cos_nv)
    : PrincipledBsdf(material_lobes) {
    eta_ = back_face ? terms.inv_ior : material.ior;
    selection_cos_nv_ = cos_nv;
    selection_pending_ = true;
}

// The closure weights of the lobes (Cycles' principled closure set-up), before their selection
// probabilities.
void PrincipledBsdf::add_material_lobes(const Material& material, const MaterialTerms& terms,
                                        const vec3& base_color, bool back_face, float cos_nv,
                                        PathOrigin origin) {
    const float metallic = terms.metallic;
    const float transmission = terms.transmission;
    const float alpha = terms.alpha;
    eta_ = back_face ? terms.inv_ior : material.ior;
    specular_f0_ = terms.specular_f0;
    inv_one_minus_f0_ = terms.inv_one_minus_f0;
    specular_ior_ = terms.specular_ior;
    cspec0_ = glm::mix(vec3(terms.specular_f0), base_color, metallic);

    // Cycles adds no specular closure to a surface with Specular 0 and Metallic 0 (its GlossCol
    // is 0 and it has no grazing-angle reflection).
    const bool specular = terms.specular;
    vec3 diffuse_weight = terms.diffuse_scale * base_color;
    vec3 specular_weight(1.0f - transmission);
    if (material.principled_model == PrincipledModel::V2 && specular) {
        // Cycles 4 splits 3.4's specular closure into a metallic one (weight metallic, F0 = base
        // colour) and a dielectric layer (weight (1 - metallic)(1 - transmission), F0 =
        // specular_f0_, the Fresnel of specular_ior_); their sum is the lobe used here. The
        // dielectric layer dims everything below it by its albedo toward the camera-side
        // direction (closure_layering_weight), Multiscatter GGX scales both lobes by the energy
        // single scattering misses, and GlossCol holds both lobes' albedo estimates.
        v2_.active = true;
        v2_.from_light = origin == PathOrigin::Light;
        v2_.multiscatter = material.distribution == MicrofacetDistribution::MultiscatterGGX;
        v2_.metallic = metallic;
        v2_.dielectric_weight = terms.dielectric_weight;
        v2_.metal_fss = glm::mix(base_color, vec3(1.0f), kSchlickAverageBlend);
        if (v2_.multiscatter) v2_.dielectric_fss = dielectric_average_fresnel(specular_ior_);
        // On light paths wo is not the camera side: the factors are applied per scattered wi
        // (lobe_eval_pdf), and GlossCol, a camera pass, is not needed.
        if (!v2_.from_light) {
            const CameraSide side = camera_side(cos_nv);
            diffuse_weight *= side.layer_transmittance;
            specular_weight *= side.specular_scale;
            glossy_albedo_ = vec3(v2_.dielectric_weight * (1.0f - side.layer_transmittance));
            if (metallic > 0.0f)
                glossy_albedo_ += metallic * side.metal_darkening *
                                  glm::mix(base_color, vec3(1.0f),
                                           schlick_fresnel_blend(roughness_, cos_nv));
        }
    }
    add_lobe(LobeKind::Diffuse, diffuse_weight, alpha);
    if (specular) add_lobe(LobeKind::Specular, specular_weight, alpha);
    // Both glass lobes have zero weight without transmission (add_lobe would drop them): skip
    // their Fresnel term, the common case.
    if (transmission > 0.0f) {
        const float fresnel = fresnel_dielectric(cos_nv, eta_);
        add_lobe(LobeKind::GlassReflection, vec3(transmission * fresnel), alpha);
        add_lobe(LobeKind::Refraction, transmission * (1.0f - fresnel) * base_color, alpha);
    }
}

// Lobe selection probabilities and the albedo estimate toward wo (wo.z = cos_nv).
void PrincipledBsdf::select_lobes(float cos_nv) const {
    // Lobe selection by average closure weight as Cycles, except that the specular lobe is
    // weighted by its colour at normal view so a 4% dielectric coat does not take half the samples.
    float total = 0.0f;
    for (int i = 0; i < lobe_count_; ++i) {
        const Lobe& lobe = lobes_[i];
        lobe.select_prob = average(lobe.weight);
        if (lobe.kind == LobeKind::Specular) {
            const vec3 color = specular_color(cos_nv);
            lobe.select_prob *= average(color);
            albedo_estimate_ += lobe.weight * color;
        } else {
            albedo_estimate_ += lobe.weight;
        }
        total += lobe.select_prob;
    }
    const float inv_total = total > 0.0f ? 1.0f / total : 0.0f;
    for (int i = 0; i < lobe_count_; ++i) lobes_[i].select_prob *= inv_total;
}

void PrincipledBsdf::add_lobe(LobeKind kind, const vec3& weight, float alpha) {
    if (average(weight) <= kClosureWeightCutoff) return;
    Lobe& lobe = lobes_[lobe_count_++];
    lobe.kind = kind;
    lobe.weight = weight;
    lobe.alpha = alpha;
    // Set by select_lobes, which runs on first use: zero until then, so that eval(), which
    // computes a pdf it drops, reads defined values.
    lobe.select_prob = 0.0f;
}

PrincipledBsdf::CameraSide PrincipledBsdf::camera_side(float cos_camera) const {
    CameraSide side;
    EnergyPreservation metal, dielectric;
    if (v2_.multiscatter) {
        const GgxEnergy energy = ggx_energy(roughness_, cos_camera);
        metal = energy_preservation(energy, v2_.metal_fss);
        dielectric = energy_preservation(energy, vec3(v2_.dielectric_fss));
        side.metal_darkening = metal.darkening;
        // Each lobe's own scale, weighted by its share of the combined lobe's mean Fresnel
        // (exact when the surface is wholly metallic or wholly dielectric).
        const vec3 metal_share = v2_.metallic * v2_.metal_fss;
        const vec3 dielectric_share(v2_.dielectric_weight * v2_.dielectric_fss);
        const vec3 total = metal_share + dielectric_share;
        if (max_component(total) > 0.0f)
            side.specular_scale =
                (metal_share * metal.scale + dielectric_share * dielectric.scale) /
                glm::max(total, vec3(1e-20f));
    }
    if (v2_.dielectric_weight > 0.0f) {
        // Cycles: weight * saturate(1 - albedo / weight), albedo / weight = darkening
        // mix(F0, 1, S).
        const float albedo =
            glm::mix(specular_f0_, 1.0f,
                     dielectric_fresnel_blend(roughness_, cos_camera, specular_ior_)) *
            dielectric.darkening.x;
        side.layer_transmittance = std::clamp(1.0f - albedo, 0.0f, 1.0f);
    }
    return side;
}

vec3 PrincipledBsdf::specular_color(float cos_lh) const {
    // Cycles' interpolate_fresnel_color: Fresnel of specular_ior_, renormalised to [F0, 1].
    if (specular_f0_ >= 1.0f) return vec3(1.0f);
    const float fh = (fresnel_dielectric(cos_lh, specular_ior_) - specular_f0_) * inv_one_minus_f0_;
    return cspec0_ * (1.0f - fh) + vec3(fh);
}

float PrincipledBsdf::diffuse_brdf(const vec3& wo, const vec3& wi, float cos_lh) const {
    if (diffuse_model_ == DiffuseModel::Lambert) return kInvPi;
    const float fl = schlick_weight(wi.z);
    const float fv = schlick_weight(wo.z);
    const float rr = 2.0f * roughness_ * cos_lh * cos_lh;
    const float lambert = (1.0f - 0.5f * fl) * (1.0f - 0.5f * fv);
    const float retro = rr * (fl + fv + fl * fv * (rr - 1.0f));
    return kInvPi * (lambert + retro);
}

// What every non-Dirac lobe's f |cos| and pdf share for one pair (wo, wi): the half vector and
// the GGX terms (all GGX lobes of a PrincipledBsdf have the same alpha), computed once.
struct PrincipledBsdf::PairTerms {
    bool reflection = false;  // wi above the surface (reflection lobes), else below (refraction)
    vec3 h{0.0f};             // half vector on wo's side (the refraction one below the surface)
    float cos_oh = 0.0f, cos_ih = 0.0f;
    bool ggx_ready = false;
    float d = 0.0f, g1_o = 0.0f, g1_i = 0.0f;
    float refraction_denom = 0.0f;  // cos_oh + eta cos_ih (refraction only)
    bool camera_side_ready = false;  // light paths of PrincipledModel::V2: camera_side(wi.z)
    CameraSide camera_side;
};

const PrincipledBsdf::CameraSide& PrincipledBsdf::light_path_side(const vec3& wi,
                                                                  PairTerms* terms) const {
    if (!terms->camera_side_ready) {
        terms->camera_side = camera_side(wi.z);
        terms->camera_side_ready = true;
    }
    return terms->camera_side;
}

// Fills `terms` for the pair; false when no non-Dirac lobe can be non-zero (grazing wi, or a
// refraction pair without a valid half vector).
bool PrincipledBsdf::pair_terms(const vec3& wo, const vec3& wi, PairTerms* terms) const {
    if (wo.z <= 0.0f || wi.z == 0.0f) return false;
    terms->reflection = wi.z > 0.0f;
    if (terms->reflection) {
        terms->h = glm::normalize(wo + wi);
        terms->cos_ih = glm::dot(wi, terms->h);
        return true;
    }
    terms->h = refraction_half_vector(wo, wi, eta_);
    terms->cos_oh = glm::dot(wo, terms->h);
    terms->cos_ih = glm::dot(wi, terms->h);
    if (terms->cos_oh <= 0.0f || terms->cos_ih >= 0.0f) return false;
    terms->refraction_denom = terms->cos_oh + eta_ * terms->cos_ih;
    return true;
}

float height_correlated_masking(float g1_o, float g1_i) {
    // G2 / G1(wo) with G2 = 1 / (1 + L(wo) + L(wi)) and 1 + L = 1 / G1.
    if (!(g1_i > 0.0f) || !(g1_o > 0.0f)) return 0.0f;
    return 1.0f / (g1_o * (1.0f / g1_o + 1.0f / g1_i - 1.0f));
}

float PrincipledBsdf::masking_given_o(const PairTerms& terms) const {
    return height_correlated_ ? height_correlated_masking(terms.g1_o, terms.g1_i) : terms.g1_i;
}

void PrincipledBsdf::ggx_terms(const vec3& wo, const vec3& wi, float alpha,
                               PairTerms* terms) const {
    if (terms->ggx_ready) return;
    terms->d = ggx_d(terms->h, alpha);
    terms->g1_o = ggx_g1(wo, alpha);
    terms->g1_i = ggx_g1(wi, alpha);
    terms->ggx_ready = true;
}

// One lobe's f |cos| and pdf (not yet times its selection probability) for the pair.
void PrincipledBsdf::lobe_eval_pdf(const Lobe& lobe, const vec3& wo, const vec3& wi,
                                   PairTerms* terms, vec3* f, float* pdf) const {
    *f = vec3(0.0f);
    *pdf = 0.0f;
    if (lobe.delta() || terms->reflection != (lobe.kind != LobeKind::Refraction)) return;
    if (lobe.kind == LobeKind::Diffuse) {
        float cos_factor = diffuse_brdf(wo, wi, terms->cos_ih) * wi.z;
        if (v2_.from_light) cos_factor *= light_path_side(wi, terms).layer_transmittance;
        if (bent_) cos_factor *= diffuse_bump_shadowing(wi);
        *f = lobe.weight * cos_factor;
        *pdf = wi.z * kInvPi;
        return;
    }
    ggx_terms(wo, wi, lobe.alpha, terms);
    if (lobe.kind == LobeKind::Refraction) {
        // Walter et al. 2007 eq. 21 (Fresnel in the weight) and the visible-normal pdf mapped
        // through the refraction Jacobian.
        const float jacobian = eta_ * eta_ * std::fabs(terms->cos_ih) /
                               (terms->refraction_denom * terms->refraction_denom);
        const float visible = terms->g1_o * terms->d * terms->cos_oh / wo.z;
        *f = lobe.weight * (visible * masking_given_o(*terms) * jacobian);
        *pdf = visible * jacobian;
        return;
    }
    // Reflection: D G1(wo) G1(wi) / (4 wo.z); the visible-normal pdf is D G1(wo) / (4 wo.z).
    *pdf = terms->g1_o * terms->d / (4.0f * wo.z);
    vec3 color = vec3(1.0f);
    if (lobe.kind == LobeKind::Specular) {
        color = specular_color(terms->cos_ih);
        if (v2_.from_light) color *= light_path_side(wi, terms).specular_scale;
    }
    *f = lobe.weight * color * (*pdf * masking_given_o(*terms));
}

void PrincipledBsdf::eval_pdf(const vec3& wo, const vec3& wi, BsdfEval* eval, float* pdf) const {
    *eval = BsdfEval{};
    *pdf = 0.0f;
    PairTerms terms;
    if (!pair_terms(wo, wi, &terms)) return;
    for (int i = 0; i < lobe_count_; ++i) {
        const Lobe& lobe = lobes_[i];
        vec3 f;
        float lobe_pdf;
        lobe_eval_pdf(lobe, wo, wi, &terms, &f, &lobe_pdf);
        eval->by_class[int(lobe.lobe_class())] += f;
        *pdf += lobe.select_prob * lobe_pdf;
    }
}

bool PrincipledBsdf::lobe_sample(const Lobe& lobe, const vec3& wo, const vec2& u,
                                 vec3* wi) const {
    if (lobe.kind == LobeKind::Diffuse) {
        *wi = sample_cosine_hemisphere(u);
        return wi->z > 0.0f;
    }
    const vec3 h = lobe.delta() ? vec3(0.0f, 0.0f, 1.0f)
                                : sample_ggx_visible_normal(wo, lobe.alpha, u);
    if (lobe.kind == LobeKind::Refraction) {
        if (!refract_local(wo, h, eta_, wi)) return false;
        return wi->z < 0.0f;
    }
    *wi = 2.0f * glm::dot(wo, h) * h - wo;
    return wi->z > 0.0f;
}

BsdfEval PrincipledBsdf::eval(const vec3& wo, const vec3& wi) const {
    BsdfEval result;
    float pdf;
    eval_pdf(wo, wi, &result, &pdf);
    return result;
}

float PrincipledBsdf::pdf(const vec3& wo, const vec3& wi) const {
    ensure_selected();
    BsdfEval eval;
    float pdf;
    eval_pdf(wo, wi, &eval, &pdf);
    return pdf;
}

const PrincipledBsdf::Lobe* PrincipledBsdf::choose_lobe(float u_lobe) const {
    if (lobe_count_ == 0) return nullptr;
    int chosen = lobe_count_ - 1;
    for (int i = 0; i < lobe_count_; ++i) {
        if (u_lobe < lobes_[i].select_prob) {
            chosen = i;
            break;
        }
        u_lobe -= lobes_[i].select_prob;
    }
    const Lobe& lobe = lobes_[chosen];
    return lobe.select_prob > 0.0f ? &lobe : nullptr;
}

bool PrincipledBsdf::sample(const vec3& wo, float u_lobe, const vec2& u, BsdfSample* out) const {
    if (wo.z <= 0.0f) return false;
    ensure_selected();
    const Lobe* chosen = choose_lobe(u_lobe);
    if (chosen == nullptr) return false;
    const Lobe& lobe = *chosen;
    if (!lobe_sample(lobe, wo, u, &out->wi)) return false;
    out->lobe_class = lobe.lobe_class();
    out->delta = lobe.delta();
    out->eval = BsdfEval{};
    if (out->delta) {
        const vec3 color = lobe.kind == LobeKind::Specular ? specular_color(wo.z) : vec3(1.0f);
        out->weight = lobe.weight * color / lobe.select_prob;
        out->pdf = 0.0f;
        out->eval.by_class[int(out->lobe_class)] = out->weight;
    } else {
        eval_pdf(wo, out->wi, &out->eval, &out->pdf);
        if (out->pdf <= 0.0f) return false;
        out->weight = out->eval.total() * (1.0f / out->pdf);
    }
    return is_finite(out->weight) && glm::any(glm::greaterThan(out->weight, vec3(0.0f)));
}

vec3 PrincipledBsdf::class_color(LobeClass lobe_class) const {
    vec3 color(0.0f);
    for (int i = 0; i < lobe_count_; ++i) {
        const Lobe& lobe = lobes_[i];
        if (lobe.lobe_class() != lobe_class) continue;
        color += lobe.kind == LobeKind::Specular && v2_.active ? glossy_albedo_ : lobe.weight;
    }
    return color;
}

vec3 PrincipledBsdf::class_color_sum() const {
    vec3 color[kLobeClassCount] = {vec3(0.0f), vec3(0.0f), vec3(0.0f)};
    for (int i = 0; i < lobe_count_; ++i) {
        const Lobe& lobe = lobes_[i];
        color[int(lobe.lobe_class())] +=
            lobe.kind == LobeKind::Specular && v2_.active ? glossy_albedo_ : lobe.weight;
    }
    return color[int(LobeClass::Diffuse)] + color[int(LobeClass::Glossy)] +
           color[int(LobeClass::Transmission)];
}

DenoisingFeature PrincipledBsdf::denoising_feature(float cos_nv) const {
    ensure_selected();
    DenoisingFeature feature;
    for (int i = 0; i < lobe_count_; ++i) {
        const Lobe& lobe = lobes_[i];
        feature.weight += lobe.select_prob;
        const bool specular_lobe = lobe.kind == LobeKind::Specular;
        if (lobe.kind == LobeKind::Diffuse || lobe.alpha > kDenoisingSpecularAlpha) {
            feature.nonspecular_weight += lobe.select_prob;
            feature.albedo += specular_lobe && v2_.active ? glossy_albedo_ : lobe.weight;
        } else if (specular_lobe) {
            feature.specular_albedo +=
                v2_.active ? glossy_albedo_ : lobe.weight * specular_color(cos_nv);
        } else {
            feature.specular_albedo += lobe.weight;
        }
    }
    return feature;
}

void PrincipledBsdf::blur(float alpha) {
    for (int i = 0; i < lobe_count_; ++i) {
        Lobe& lobe = lobes_[i];
        if (lobe.kind == LobeKind::Diffuse || !(alpha > lobe.alpha)) continue;
        lobe.alpha = alpha;
        glossy_roughness_ = std::sqrt(alpha);  // every GGX lobe shares one alpha
    }
}

bool PrincipledBsdf::sample_traced(const vec3& wo, float u_lobe, const vec2& u,
                                   BsdfSample* out) const {
    if (wo.z <= 0.0f) return false;
    ensure_selected();
    float total = 0.0f;
    for (int i = 0; i < lobe_count_; ++i)
        if (lobes_[i].traced()) total += lobes_[i].select_prob;
    if (!(total > 0.0f)) return false;
    u_lobe *= total;
    const Lobe* chosen = nullptr;
    for (int i = 0; i < lobe_count_; ++i) {
        if (!lobes_[i].traced()) continue;
        chosen = &lobes_[i];
        if (u_lobe < lobes_[i].select_prob) break;
        u_lobe -= lobes_[i].select_prob;
    }
    return sample_lobe(*chosen, chosen->select_prob / total, wo, u, out);
}

bool PrincipledBsdf::sample_lobe(const Lobe& lobe, float choice_prob, const vec3& wo,
                                 const vec2& u, BsdfSample* out) const {
    if (!lobe_sample(lobe, wo, u, &out->wi)) return false;
    out->lobe_class = lobe.lobe_class();
    out->delta = lobe.delta();
    out->eval = BsdfEval{};
    if (out->delta) {
        const vec3 color = lobe.kind == LobeKind::Specular ? specular_color(wo.z) : vec3(1.0f);
        out->weight = lobe.weight * color / choice_prob;
        out->pdf = 0.0f;
    } else {
        PairTerms terms;
        if (!pair_terms(wo, out->wi, &terms)) return false;
        vec3 f;
        lobe_eval_pdf(lobe, wo, out->wi, &terms, &f, &out->pdf);
        out->pdf *= choice_prob;
        if (!(out->pdf > 0.0f)) return false;
        out->weight = f / out->pdf;
    }
    out->eval.by_class[int(out->lobe_class)] = out->weight;
    return is_finite(out->weight) && glm::any(glm::greaterThan(out->weight, vec3(0.0f)));
}

float PrincipledBsdf::diffuse_bump_shadowing(const vec3& wi) const {
    if (!bent_) return 1.0f;
    const vec3 bent(0.0f, 0.0f, 1.0f);
    return microfacet_bump_ ? bump_shadowing_microfacet(smooth_normal_, bent, wi)
                            : bump_shadowing_term(smooth_normal_, bent, wi);
}

// class_color(Diffuse) times Burley's albedo (Lambert's: 1, and w * 1 is w, bit for bit). Every
// preview pixel with a field comes here (field_lobes_with). The sum is kept in three floats: as a
// glm vec3 through class_color, GCC kept it on the stack, and both models' results met there
// too, so each pixel waited on store-to-load round trips after the table read (`perf
// annotate`: ~27% of the function's samples on them). The table read comes first: it depends
// on wo alone, so its chain runs while the lobes are summed.
vec3 PrincipledBsdf::field_diffuse(const vec3& wo) const {
    vec3 diffuse;
    GlossyLobe unused[2];
    field_lobes_with(
        diffuse_model_ == DiffuseModel::Lambert ? 1.0f : burley_albedo(wo.z, roughness_),
        vec2(0.0f), &diffuse, unused);
    return diffuse;
}

// eval_pdf over the field lobes alone, without its pdf, in one pass: every field lobe reflects,
// so a pair with wi on or below the surface is zero (eval_pdf's refraction half vector then
// serves no field lobe), and each lobe's f is lobe_eval_pdf's reflection branch, the same
// operations in the same order (bit for bit; tests/cpp/render/bsdf_test.cpp compares the two).
// The light samples of every preview pixel with a field come here: the shared PairTerms, the
// out-of-line lobe calls and the pdf sums were half its instructions.
BsdfEval PrincipledBsdf::eval_field(const vec3& wo, const vec3& wi) const {
    BsdfEval result;
    if (wo.z <= 0.0f || !(wi.z > 0.0f)) return result;
    PairTerms terms;
    terms.reflection = true;
    terms.h = glm::normalize(wo + wi);
    terms.cos_ih = glm::dot(wi, terms.h);
    for (int i = 0; i < lobe_count_; ++i) {
        const Lobe& lobe = lobes_[i];
        if (lobe.traced()) continue;
        if (lobe.kind == LobeKind::Diffuse) {
            float cos_factor = diffuse_brdf(wo, wi, terms.cos_ih) * wi.z;
            if (v2_.from_light) cos_factor *= light_path_side(wi, &terms).layer_transmittance;
            if (bent_) cos_factor *= diffuse_bump_shadowing(wi);
            result.by_class[int(LobeClass::Diffuse)] += lobe.weight * cos_factor;
            continue;
        }
        ggx_terms(wo, wi, lobe.alpha, &terms);
        const float pdf = terms.g1_o * terms.d / (4.0f * wo.z);
        vec3 color = vec3(1.0f);
        if (lobe.kind == LobeKind::Specular) {
            color = specular_color(terms.cos_ih);
            if (v2_.from_light) color *= light_path_side(wi, &terms).specular_scale;
        }
        result.by_class[int(LobeClass::Glossy)] +=
            lobe.weight * color * (pdf * masking_given_o(terms));
    }
    return result;
}

int PrincipledBsdf::field_glossy_lobes(const vec3& wo, GlossyLobe out[2]) const {
    // The table is read only where a glossy field lobe is (one read serves both).
    vec3 unused;
    for (int i = 0; i < lobe_count_; ++i)
        if (!lobes_[i].traced() && lobes_[i].kind != LobeKind::Diffuse)
            return field_lobes_with(1.0f, ggx_albedo(wo.z, glossy_roughness_), &unused, out);
    return 0;
}

// One pass for both kinds of field lobe: a quad's pixels (PathIntegrator::add_field) read them
// together, and two passes were two calls and two walks over the lobes a pixel.
int PrincipledBsdf::field_lobes_with(float burley, const vec2& ggx, vec3* diffuse,
                                     GlossyLobe glossy[2]) const {
    float r = 0.0f, g = 0.0f, b = 0.0f;  // class_color(Diffuse)'s order: from 0, lobe by lobe
    int count = 0;
    for (int i = 0; i < lobe_count_; ++i) {
        const Lobe& lobe = lobes_[i];
        if (lobe.kind == LobeKind::Diffuse) {  // lobe_class() == LobeClass::Diffuse
            r += lobe.weight.x;
            g += lobe.weight.y;
            b += lobe.weight.z;
            continue;
        }
        if (lobe.traced() || count == 2) continue;
        // Specular colour = cspec0 (1 - fh) + fh, so its albedo is cspec0 (a - a_fh) + a_fh
        // (ggx: colour 1, colour fh).
        const vec3 color = lobe.kind == LobeKind::Specular
                               ? cspec0_ * (ggx.x - ggx.y) + vec3(ggx.y)
                               : vec3(ggx.x);
        glossy[count++] = GlossyLobe{lobe.weight * color, glossy_roughness_};
    }
    const float albedo = diffuse_model_ == DiffuseModel::Lambert ? 1.0f : burley;
    *diffuse = vec3(r * albedo, g * albedo, b * albedo);
    return count;
}

}  // namespace shgi
