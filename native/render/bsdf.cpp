#include "render/bsdf.h"

#include <algorithm>
#include <cmath>

#include "util/sampling.h"

namespace shgi {
namespace {

// Principled's "Specular" 0..1 maps to F0 = kSpecularF0Scale * specular (Blender manual).
constexpr float kSpecularF0Scale = 0.08f;
// Lobes whose closure weight averages below this are dropped (Cycles' CLOSURE_WEIGHT_CUTOFF).
constexpr float kClosureWeightCutoff = 1e-5f;

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

// Directional albedos tabulated over cos(N.V) x roughness (32 x 32), each entry the mean of an
// integrand over 16 x 16 stratified samples, looked up bilinearly. Built once, on first use.
constexpr int kAlbedoTableSize = 32;
constexpr int kAlbedoTableStrata = 16;

class AlbedoTable {
  public:
    // integrand(wo, roughness, u) -> up to two albedo estimates for one sample.
    template <typename Integrand>
    explicit AlbedoTable(Integrand integrand) {
        for (int i = 0; i < kAlbedoTableSize; ++i) {
            const float cos_nv = std::max(float(i) / float(kAlbedoTableSize - 1), 1e-3f);
            const vec3 wo(std::sqrt(1.0f - cos_nv * cos_nv), 0.0f, cos_nv);
            for (int j = 0; j < kAlbedoTableSize; ++j) {
                const float roughness = float(j) / float(kAlbedoTableSize - 1);
                glm::dvec2 sum(0.0);
                for (int a = 0; a < kAlbedoTableStrata; ++a)
                    for (int b = 0; b < kAlbedoTableStrata; ++b)
                        sum += glm::dvec2(integrand(wo, roughness,
                                                    vec2((float(a) + 0.5f) / kAlbedoTableStrata,
                                                         (float(b) + 0.5f) / kAlbedoTableStrata)));
                entries_[i][j] = vec2(sum / double(kAlbedoTableStrata * kAlbedoTableStrata));
            }
        }
    }

    vec2 lookup(float cos_nv, float roughness) const {
        const float x = std::clamp(cos_nv, 0.0f, 1.0f) * float(kAlbedoTableSize - 1);
        const float y = std::clamp(roughness, 0.0f, 1.0f) * float(kAlbedoTableSize - 1);
        const int x0 = std::min(int(x), kAlbedoTableSize - 2);
        const int y0 = std::min(int(y), kAlbedoTableSize - 2);
        const float tx = x - float(x0), ty = y - float(y0);
        const vec2 bottom = glm::mix(entries_[x0][y0], entries_[x0 + 1][y0], tx);
        const vec2 top = glm::mix(entries_[x0][y0 + 1], entries_[x0 + 1][y0 + 1], tx);
        return glm::mix(bottom, top, ty);
    }

  private:
    vec2 entries_[kAlbedoTableSize][kAlbedoTableSize];  // [cos_nv][roughness]
};

// Directional albedo of a GGX reflection lobe: x with colour 1, y with the colour fh of
// interpolate_fresnel_color (for Specular 0.5: ior 1.5, F0 0.04), by visible-normal sampling
// (f cos / pdf = G1(wi) for separable Smith GGX).
vec2 ggx_albedo(float cos_nv, float roughness) {
    static const AlbedoTable table([](const vec3& wo, float r, const vec2& u) {
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
    return table.lookup(cos_nv, roughness);
}

// Directional albedo of Cycles' principled diffuse (Burley, with retro-reflection), by cosine
// sampling; Lambert's is 1.
float burley_albedo(float cos_nv, float roughness) {
    static const AlbedoTable table([](const vec3& wo, float r, const vec2& u) {
        const vec3 wi = sample_cosine_hemisphere(u);
        const float fl = schlick_weight(wi.z), fv = schlick_weight(wo.z);
        const float cos_lh = glm::dot(wi, glm::normalize(wo + wi));
        const float rr = 2.0f * r * cos_lh * cos_lh;
        return vec2((1.0f - 0.5f * fl) * (1.0f - 0.5f * fv) + rr * (fl + fv + fl * fv * (rr - 1.0f)),
                    0.0f);
    });
    return table.lookup(cos_nv, roughness).x;
}

}  // namespace

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
                               float cos_nv)
    : roughness_(material.roughness), diffuse_model_(material.diffuse_model) {
    const float metallic = std::clamp(material.metallic, 0.0f, 1.0f);
    const float transmission = (1.0f - metallic) * std::clamp(material.transmission, 0.0f, 1.0f);
    const float alpha = material.roughness * material.roughness;
    eta_ = back_face ? 1.0f / material.ior : material.ior;

    const float f0_dielectric = kSpecularF0Scale * std::clamp(material.specular, 0.0f, 1.0f);
    specular_f0_ = f0_dielectric;
    inv_one_minus_f0_ = f0_dielectric < 1.0f ? 1.0f / (1.0f - f0_dielectric) : 0.0f;
    specular_ior_ = 2.0f / (1.0f - std::sqrt(f0_dielectric)) - 1.0f;
    cspec0_ = glm::mix(vec3(f0_dielectric), base_color, metallic);

    add_lobe(LobeKind::Diffuse, (1.0f - metallic) * (1.0f - material.transmission) * base_color,
             alpha);
    // Cycles adds no specular closure to a surface with Specular 0 and Metallic 0 (its GlossCol
    // is 0 and it has no grazing-angle reflection).
    if (material.specular > kClosureWeightCutoff || metallic > kClosureWeightCutoff)
        add_lobe(LobeKind::Specular, vec3(1.0f - transmission), alpha);
    // Both glass lobes have zero weight without transmission (add_lobe would drop them): skip
    // their Fresnel term, the common case.
    if (transmission > 0.0f) {
        const float fresnel = fresnel_dielectric(cos_nv, eta_);
        add_lobe(LobeKind::GlassReflection, vec3(transmission * fresnel), alpha);
        add_lobe(LobeKind::Refraction, transmission * (1.0f - fresnel) * base_color, alpha);
    }

    // Lobe selection by average closure weight as Cycles, except that the specular lobe is
    // weighted by its colour at normal view so a 4% dielectric coat does not take half the samples.
    float total = 0.0f;
    for (int i = 0; i < lobe_count_; ++i) {
        Lobe& lobe = lobes_[i];
        lobe.select_prob = average(lobe.weight);
        if (lobe.kind == LobeKind::Specular) lobe.select_prob *= average(specular_color(cos_nv));
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
};

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
        *f = lobe.weight * (diffuse_brdf(wo, wi, terms->cos_ih) * wi.z);
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
        *f = lobe.weight * (visible * terms->g1_i * jacobian);
        *pdf = visible * jacobian;
        return;
    }
    // Reflection: D G1(wo) G1(wi) / (4 wo.z); the visible-normal pdf is D G1(wo) / (4 wo.z).
    *pdf = terms->g1_o * terms->d / (4.0f * wo.z);
    const vec3 color = lobe.kind == LobeKind::Specular ? specular_color(terms->cos_ih) : vec3(1.0f);
    *f = lobe.weight * color * (*pdf * terms->g1_i);
}

void PrincipledBsdf::eval_pdf(const vec3& wo, const vec3& wi, bool field_only, BsdfEval* eval,
                              float* pdf) const {
    *eval = BsdfEval{};
    *pdf = 0.0f;
    PairTerms terms;
    if (!pair_terms(wo, wi, &terms)) return;
    for (int i = 0; i < lobe_count_; ++i) {
        const Lobe& lobe = lobes_[i];
        if (field_only && lobe.traced()) continue;
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
    eval_pdf(wo, wi, false, &result, &pdf);
    return result;
}

float PrincipledBsdf::pdf(const vec3& wo, const vec3& wi) const {
    BsdfEval eval;
    float pdf;
    eval_pdf(wo, wi, false, &eval, &pdf);
    return pdf;
}

bool PrincipledBsdf::sample(const vec3& wo, float u_lobe, const vec2& u, BsdfSample* out) const {
    if (wo.z <= 0.0f || lobe_count_ == 0) return false;
    int chosen = lobe_count_ - 1;
    for (int i = 0; i < lobe_count_; ++i) {
        if (u_lobe < lobes_[i].select_prob) {
            chosen = i;
            break;
        }
        u_lobe -= lobes_[i].select_prob;
    }
    const Lobe& lobe = lobes_[chosen];
    if (lobe.select_prob <= 0.0f) return false;
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
        eval_pdf(wo, out->wi, false, &out->eval, &out->pdf);
        if (out->pdf <= 0.0f) return false;
        out->weight = out->eval.total() * (1.0f / out->pdf);
    }
    return is_finite(out->weight) && glm::any(glm::greaterThan(out->weight, vec3(0.0f)));
}

vec3 PrincipledBsdf::class_color(LobeClass lobe_class) const {
    vec3 color(0.0f);
    for (int i = 0; i < lobe_count_; ++i)
        if (lobes_[i].lobe_class() == lobe_class) color += lobes_[i].weight;
    return color;
}

bool PrincipledBsdf::has_smooth_lobes() const {
    for (int i = 0; i < lobe_count_; ++i)
        if (!lobes_[i].delta()) return true;
    return false;
}

bool PrincipledBsdf::sample_traced(const vec3& wo, float u_lobe, const vec2& u,
                                   BsdfSample* out) const {
    if (wo.z <= 0.0f) return false;
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

vec3 PrincipledBsdf::field_diffuse(const vec3& wo) const {
    const vec3 weight = class_color(LobeClass::Diffuse);
    if (diffuse_model_ == DiffuseModel::Lambert) return weight;
    return weight * burley_albedo(wo.z, roughness_);
}

BsdfEval PrincipledBsdf::eval_field(const vec3& wo, const vec3& wi) const {
    BsdfEval result;
    float pdf;
    eval_pdf(wo, wi, true, &result, &pdf);
    return result;
}

int PrincipledBsdf::field_glossy_lobes(const vec3& wo, GlossyLobe out[2]) const {
    int count = 0;
    for (int i = 0; i < lobe_count_ && count < 2; ++i) {
        const Lobe& lobe = lobes_[i];
        if (lobe.traced() || lobe.kind == LobeKind::Diffuse) continue;
        const vec2 albedo = ggx_albedo(wo.z, roughness_);  // (colour 1, colour fh)
        // Specular colour = cspec0 (1 - fh) + fh, so its albedo is cspec0 (a - a_fh) + a_fh.
        const vec3 color = lobe.kind == LobeKind::Specular
                               ? cspec0_ * (albedo.x - albedo.y) + vec3(albedo.y)
                               : vec3(albedo.x);
        out[count++] = GlossyLobe{lobe.weight * color, roughness_};
    }
    return count;
}

}  // namespace shgi
