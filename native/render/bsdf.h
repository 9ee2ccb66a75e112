// PrincipledBsdf: the closures Cycles builds for Blender 3.4's Principled BSDF (GGX distribution,
// no clearcoat/sheen/subsurface), evaluated and sampled in a local shading frame, and Blender 4's
// layering of them (PrincipledModel::V2, below).
//
// Lobes and their closure weights, as intern/cycles/kernel/svm/closure.h (3.4, principled v1):
//   diffuse      weight = (1 - metallic)(1 - transmission) * base_color; Lambert (1/pi) or
//                Cycles' principled diffuse (Burley 2015 split form: Lambert * (1 - FL/2)(1 - FV/2)
//                plus retro-reflection RR (FL + FV + FL FV (RR - 1)), RR = 2 roughness (L.H)^2)
//   specular     weight = 1 - (1 - metallic) transmission, only when specular or metallic > 0; GGX reflection (alpha = roughness^2,
//                separable Smith G) whose colour is Cycles' interpolate_fresnel_color: the
//                dielectric Fresnel of ior = 2/(1 - sqrt(0.08 specular)) - 1 rescaled between
//                cspec0 = mix(0.08 specular, base_color, metallic) at normal incidence and 1
//   glass refl.  weight = (1 - metallic) transmission * F(N.V, ior); GGX reflection, white
//   refraction   weight = (1 - metallic) transmission * (1 - F(N.V, ior)) * base_color; GGX BTDF
//                (Walter et al. 2007, eq. 21 without the Fresnel term, which is in the weight)
// Diffuse and specular are added, not layered (Cycles 3.x does the same: albedo may exceed 1 by
// the specular's share).
//
// PrincipledModel::V2, Blender 4.0+'s Principled BSDF as Cycles 4 builds it (svm/closure.h,
// closure/bsdf_microfacet.h), changes four things and keeps the lobes above:
//   - the dielectric specular layer (weight (1 - metallic)(1 - transmission), F0 = 0.08 specular)
//     dims the diffuse below it by its estimated albedo toward the camera-side direction v:
//     diffuse weight x (1 - mix(F0, 1, S(roughness, v.z, ior))), S the GGX-weighted mean of the
//     Fresnel curve's blend factor, tabulated as Cycles does (closure_layering_weight);
//   - GGX masking-shadowing is height-correlated, G2 = 1 / (1 + L(wo) + L(wi));
//   - with Multiscatter GGX (Blender 4's default) each specular lobe is scaled by the energy
//     single scattering misses, 1 + Fms (1 - E(v)) / E(v), and its albedo estimate by that over
//     1 / E(v) (microfacet_ggx_preserve_energy);
//   - GlossCol is the specular lobes' albedo estimate, not their closure weight.
// The camera-side direction is wo on camera paths and the scattered wi on light paths
// (PathOrigin): v2 is not reciprocal. Not modelled from Cycles 4: the metallic lobe's F82 Schlick
// curve (3.4's interpolated Fresnel is kept), glass's sqrt(base colour) tint per interface and
// its energy preservation, coat, sheen, subsurface and thin film.
//
// Refraction does not scale radiance by 1/eta^2, as Cycles: a sampled
// smooth refraction has weight 1, and the rough BTDF's sampled weight tends to 1 with alpha.
// Lobes with alpha below kDeltaAlpha are perfectly smooth (Dirac) lobes, as Cycles' threshold.
//
// Frame: +Z is the shading normal flipped to the side of wo (so wo.z > 0); a hit on a back face
// uses ior' = 1/ior. wo and wi point away from the surface. eval() returns f * |cos(wi)| split
// by lobe class (diffuse / glossy / transmission) so passes can be split as Cycles does; pdfs are
// per unit solid angle, for the one-sample lobe mixture (lobe chosen by average closure weight).
#pragma once

#include <array>
#include <cstdint>

#include "scene/material.h"
#include "util/math.h"

namespace shgi {

// Cycles' pass classes of a closure.
enum class LobeClass : uint8_t { Diffuse = 0, Glossy = 1, Transmission = 2 };
inline constexpr int kLobeClassCount = 3;

// Alpha below which GGX becomes a perfect mirror / smooth refraction (Cycles: 1e-4).
inline constexpr float kDeltaAlpha = 1e-4f;

// GGX alpha at or below which a lobe counts as specular for the denoiser's guides: Cycles'
// film_write_denoising_features_surface compares the closure's alpha_x alpha_y with 0.075^2.
inline constexpr float kDenoisingSpecularAlpha = 0.075f;

// What a surface gives the denoiser's guides (Cycles' film_write_denoising_features_surface):
// the albedo of its non-specular lobes, that of its specular lobes (alpha <=
// kDenoisingSpecularAlpha, the tint a path through them carries on to the next surface), and
// the lobes' sampling weights, all and non-specular. The surface writes the guides when its
// non-specular lobes hold more than a quarter of the weight, or it has no lobes.
struct DenoisingFeature {
    vec3 albedo{0.0f};
    vec3 specular_albedo{0.0f};
    float weight = 0.0f;
    float nonspecular_weight = 0.0f;
    bool writes_guides() const { return weight == 0.0f || nonspecular_weight * 4.0f > weight; }
};

// f * |cos(wi)| per lobe class, RGB.
struct BsdfEval {
    std::array<vec3, kLobeClassCount> by_class{vec3(0.0f), vec3(0.0f), vec3(0.0f)};
    vec3 total() const { return by_class[0] + by_class[1] + by_class[2]; }
};

struct BsdfSample {
    vec3 wi{0.0f};           // local frame
    vec3 weight{0.0f};       // f |cos| / pdf, or the closure weight for a Dirac lobe
    float pdf = 0.0f;        // mixture pdf (sr^-1); 0 for a Dirac lobe
    bool delta = false;
    LobeClass lobe_class = LobeClass::Diffuse;
    BsdfEval eval;           // f |cos| split by class (for a Dirac lobe: weight in its class)
};

// --- GGX pieces (Walter et al. 2007; Heitz 2018 visible-normal sampling), local frame ---
float ggx_d(const vec3& h, float alpha);
float ggx_g1(const vec3& w, float alpha);
// Samples a visible normal for view direction w (w.z > 0), Heitz 2018 "Sampling the GGX
// Distribution of Visible Normals", JCGT 7(4). pdf(h) = G1(w) max(0, w.h) D(h) / w.z.
vec3 sample_ggx_visible_normal(const vec3& w, float alpha, const vec2& u);
// Height-correlated Smith masking of wi given wo's, G2 / G1(wo) with G2 = 1 / (1 + L(wo) +
// L(wi)), from the two G1 (Cycles 4; 0 when either is 0).
float height_correlated_masking(float g1_o, float g1_i);
// Dielectric Fresnel reflectance for cos_i = cos of the incident angle and relative ior eta;
// 1 under total internal reflection (Cycles' fresnel_dielectric_cos).
float fresnel_dielectric(float cos_i, float eta);

// The field lobes' tabulated directional albedos (32 x 32 nodes over cos(N.V) and roughness, read
// bilinearly): Cycles' principled diffuse (Burley, with retro-reflection; Lambert's is 1), and a
// GGX reflection lobe's with colour 1 (x) and with the colour fh of interpolate_fresnel_color
// for Specular 0.5 (y). field_diffuse and field_glossy_lobes read them toward wo.
float burley_albedo(float cos_nv, float roughness);
vec2 ggx_albedo(float cos_nv, float roughness);

// burley_albedo(cos_nv[k], diffuse_roughness[k]) and ggx_albedo(cos_nv[k], glossy_roughness[k])
// for four views k at once: the field lobes of a 2 x 2 quad's pixels (render/quad_glossy.h).
// Each read is a dependent chain (the split by cos(N.V), the loads, three mixes) at the end of a
// pixel's field light; here the four chains run in SSE2 lanes, each lane the scalar read's IEEE
// operations in its order (no FMA), so each is the scalar value bit for bit
// (tests/cpp/render/bsdf_test.cpp). Inputs must not be NaN (nor are the scalar reads').
struct FieldAlbedoLanes {
    alignas(16) float burley[4];
    alignas(16) float ggx[2][4];  // ggx_albedo's x and y
};
void field_albedo_lanes(const float cos_nv[4], const float diffuse_roughness[4],
                        const float glossy_roughness[4], FieldAlbedoLanes* out);

// Which end of a path the BSDF scatters for. Cycles 4's layered Principled BSDF is not reciprocal:
// its diffuse is dimmed by the specular layer's albedo toward the camera-side direction, which is
// wo on paths from the camera and the scattered wi on paths from a light (photons).
enum class PathOrigin : uint8_t { Camera, Light };

class PrincipledBsdf {
  public:
    // base_color is the material's base colour times its texture at the hit. back_face: the ray
    // hit the back of the surface (ior inverted). cos_nv: wo.z in the shading frame.
    // The diffuse lobe follows material.diffuse_model, the layering material.principled_model.
    // Every constructor defers the lobe selection (the selection probabilities and the albedo
    // estimate, which weigh the specular lobe by its Fresnel colour toward wo: a square root and
    // a division) to the first call that reads it (pdf, sample, sample_traced,
    // denoising_feature, albedo_estimate), which runs it once on the same values: a preview pixel
    // whose lobes are all field lobes never does. A BSDF is therefore not to be read by two
    // threads at once before such a call (a Shading belongs to one path).
    PrincipledBsdf(const Material& material, const vec3& base_color, bool back_face,
                   float cos_nv, PathOrigin origin = PathOrigin::Camera);
    // The same BSDF from the material's terms computed beforehand (terms ==
    // material_terms(material), as Scene::material_terms() keeps them): what tracers use.
    PrincipledBsdf(const Material& material, const MaterialTerms& terms, const vec3& base_color,
                   bool back_face, float cos_nv, PathOrigin origin = PathOrigin::Camera);
    // No lobes (black: eval 0, sample fails); a placeholder in arrays of Shading to assign later.
    PrincipledBsdf() = default;

    // Whether the material's lobes and closure weights are the same at every hit (no base
    // colour texture, no glass lobes, no Blender 4 specular layer), so that only the lobe
    // selection, which weighs the specular lobe by its colour toward wo, and the ior's side
    // change from hit to hit.
    static bool lobes_depend_on_hit_only_by_view(const Material& material,
                                                 const MaterialTerms& terms);
    // For such a material: its lobes before their selection, to be finished per hit by the
    // constructor below (kept per scene by MaterialLobeTable, render/shading.h).
    static PrincipledBsdf material_lobes(const Material& material, const MaterialTerms& terms);
    // The BSDF the full constructor builds for the same material (material.base_color), side
    // and view, from material_lobes(material, terms): the same operations on the same values
    // for the parts that depend on the hit, so the same bits (the lobe selection deferred as
    // above).
    PrincipledBsdf(const PrincipledBsdf& material_lobes, const Material& material,
                   const MaterialTerms& terms, bool back_face, float cos_nv);

    // The interpolated normal, in the local frame, when the frame's normal was bent by a normal
    // map: the diffuse lobe is then scaled by bump_shadowing_term (render/normal_map.h), as
    // Cycles scales a diffuse closure whose normal differs from the interpolated one.
    // microfacet: Cycles 4+'s term instead of Cycles 3.x's (render/normal_map.h).
    void set_smooth_normal(const vec3& local_smooth_normal, bool microfacet) {
        smooth_normal_ = local_smooth_normal;
        bent_ = true;
        microfacet_bump_ = microfacet;
    }
    // The factor the diffuse lobe takes for light from local direction `wi` (the camera path's
    // light side): the bump shadowing term above, 1 unless set_smooth_normal was called.
    float diffuse_bump_shadowing(const vec3& wi) const;
    // Whether set_smooth_normal was called; the interpolated normal (local frame) and the term
    // it set (field consumers fold the shadowing into their irradiance: render/bump_irradiance.h).
    bool has_smooth_normal() const { return bent_; }
    const vec3& smooth_normal() const { return smooth_normal_; }
    bool microfacet_bump() const { return microfacet_bump_; }

    BsdfEval eval(const vec3& wo, const vec3& wi) const;
    float pdf(const vec3& wo, const vec3& wi) const;
    // u_lobe picks the lobe, u the direction. False when the sample is invalid (below the
    // surface for a reflection lobe, total internal reflection, zero weight).
    bool sample(const vec3& wo, float u_lobe, const vec2& u, BsdfSample* out) const;

    // Sum of closure weights per class: Cycles' DiffCol / GlossCol / TransCol for this hit
    // (PrincipledModel::V2: GlossCol is the specular lobes' estimated albedo toward wo, as
    // Cycles 4 writes it).
    vec3 class_color(LobeClass lobe_class) const;
    // DiffCol + GlossCol + TransCol, summed as class_color(Diffuse) + class_color(Glossy) +
    // class_color(Transmission) are (the same value, bit for bit) in one pass over the lobes:
    // the G-buffer's albedo of every preview pixel.
    vec3 class_color_sum() const;
    // The surface's share in the denoiser's guides (DenoisingFeature) seen from wo (wo.z =
    // cos_nv): non-specular lobes' albedo as class_color gives it (their sum equals DiffCol +
    // GlossCol + TransCol when no lobe is specular); a specular lobe's albedo is its closure
    // weight, the specular lobe's times its Fresnel colour toward wo (PrincipledModel::V2: its
    // estimated albedo, GlossCol); weights are the lobes' selection probabilities.
    DenoisingFeature denoising_feature(float cos_nv) const;
    // True when at least one lobe is not a Dirac lobe (light sampling can help). Inline (as
    // has_traced_lobes): a preview path asks both once a pixel.
    bool has_smooth_lobes() const {
        for (int i = 0; i < lobe_count_; ++i)
            if (!lobes_[i].delta()) return true;
        return false;
    }
    // True when at least one lobe is traced (see sample_traced below): without one,
    // sample_traced fails whatever its numbers.
    bool has_traced_lobes() const {
        for (int i = 0; i < lobe_count_; ++i)
            if (lobes_[i].traced()) return true;
        return false;
    }
    // Light Paths > Filter Glossy (Cycles' bsdf_blur): every microfacet lobe (specular, glass
    // reflection, refraction) widens to a GGX alpha of at least `alpha`, so a mirror seen through
    // a diffuse bounce is a rough reflection that light sampling reaches. Only the lobes' alpha
    // changes, as in Cycles: their weights, selection probabilities, Multiscatter GGX energy
    // scale and Blender 4 layering stay those of the material's roughness ("TODO: Recompute
    // energy preservation after blur?" in Cycles). A lobe left below kDeltaAlpha stays a Dirac
    // lobe. The field lobes' glossy roughness follows the widened alpha (field_glossy_lobes).
    void blur(float alpha);
    // The sum of the lobes' closure weights, the specular lobe's times its colour toward wo: how
    // much of the light arriving from wo the surface scatters, roughly (it leaves out the
    // lobes' directional albedos and, on light paths of PrincipledModel::V2, the layer's
    // dimming of the diffuse). The photon tracer's Russian roulette survival.
    const vec3& albedo_estimate() const {
        ensure_selected();
        return albedo_estimate_;
    }

    // --- The split the preview renderer uses (render/preview_renderer.h). "Field lobes" are the
    // non-Dirac diffuse and glossy reflection lobes, whose indirect light comes from an
    // IndirectField; "traced lobes" are every Dirac lobe and every refraction lobe, which the
    // renderer follows by tracing a ray.
    // Samples one traced lobe, chosen in proportion to the selection weights of the traced lobes;
    // weight = that lobe's f |cos| / (choice probability x its pdf), or its closure weight over
    // the choice probability for a Dirac lobe. False without traced lobes or for an invalid
    // sample.
    bool sample_traced(const vec3& wo, float u_lobe, const vec2& u, BsdfSample* out) const;
    // Outgoing radiance of the diffuse lobe under uniform incident radiance 1/pi (i.e. per unit
    // irradiance): the closure weight times the lobe's directional albedo for wo (1 for
    // Lambert; tabulated for the principled diffuse, which darkens at grazing views).
    vec3 field_diffuse(const vec3& wo) const;
    // The roughness field_diffuse reads Burley's albedo at.
    float field_diffuse_roughness() const { return roughness_; }
    // f |cos(wi)| of the field lobes only (transmission class is always zero).
    BsdfEval eval_field(const vec3& wo, const vec3& wi) const;
    // Whether eval_field_lanes covers this BSDF: its field lobes are a diffuse lobe and/or one
    // GGX specular lobe (no glass lobes), on a camera path, its normal not bent. The rest goes
    // through eval_field, chosen per BSDF.
    // Inline: the light stage asks once a path.
    bool eval_field_in_lanes() const {
        if (v2_.from_light || bent_ || lobe_count_ == 0) return false;
        for (int i = 0; i < lobe_count_; ++i)  // add_lobe adds at most one lobe of each kind
            if (lobes_[i].kind != LobeKind::Diffuse && lobes_[i].kind != LobeKind::Specular)
                return false;
        return true;
    }
    // out[k] = bsdf[k]->eval_field(*wo[k], wi[k]) for four BSDFs that eval_field_in_lanes(),
    // bit for bit, evaluated together in SSE2 lanes (render/bsdf_lanes.cpp) so that the four
    // dependent chains (normalize, GGX square roots and divisions) overlap.
    static void eval_field_lanes(const PrincipledBsdf* const bsdf[4], const vec3* const wo[4],
                                 const vec3* const wi[4], BsdfEval* const out[4]);
    // The non-Dirac glossy reflection lobes with their directional albedo for wo (∫ f cos dwi,
    // from a tabulated GGX albedo; the Fresnel curve of the specular colour is the default
    // Specular 0.5 one) and roughness. Returns how many were written (at most 2).
    struct GlossyLobe {
        vec3 albedo{0.0f};
        float roughness = 0.0f;
    };
    int field_glossy_lobes(const vec3& wo, GlossyLobe out[2]) const;
    // field_diffuse(wo) into *diffuse and field_glossy_lobes(wo, glossy) (returned: the count)
    // in one pass over the lobes, given their table reads toward wo, burley_albedo(wo.z,
    // field_diffuse_roughness()) (not read for a Lambert diffuse) and ggx_albedo(wo.z,
    // field_glossy_roughness()) (not read without a glossy field lobe), e.g. from
    // field_albedo_lanes: the same bits.
    int field_lobes_with(float burley, const vec2& ggx, vec3* diffuse, GlossyLobe glossy[2]) const;
    // The roughness every lobe field_glossy_lobes writes has (whether or not it writes one).
    float field_glossy_roughness() const { return glossy_roughness_; }

  private:
    enum class LobeKind : uint8_t { Diffuse, Specular, GlassReflection, Refraction };
    struct Lobe {
        LobeKind kind;
        vec3 weight;        // closure weight
        float alpha;        // GGX alpha (unused for diffuse)
        // Probability of sampling this lobe; mutable for the deferred selection (ensure_selected).
        mutable float select_prob;
        bool delta() const { return kind != LobeKind::Diffuse && alpha < kDeltaAlpha; }
        bool traced() const { return delta() || kind == LobeKind::Refraction; }
        LobeClass lobe_class() const;
    };

    // The lobe u_lobe picks in proportion to the selection probabilities, or nullptr (no lobe,
    // or one that cannot be chosen).
    const Lobe* choose_lobe(float u_lobe) const;
    bool sample_lobe(const Lobe& lobe, float choice_prob, const vec3& wo, const vec2& u,
                     BsdfSample* out) const;

    void add_lobe(LobeKind kind, const vec3& weight, float alpha);
    void add_material_lobes(const Material& material, const MaterialTerms& terms,
                            const vec3& base_color, bool back_face, float cos_nv,
                            PathOrigin origin);
    // Sets the selection probabilities and the albedo estimate toward wo (wo.z = cos_nv). const
    // for ensure_selected: it writes only those mutable members.
    void select_lobes(float cos_nv) const;
    // Runs the selection the constructor deferred, once; a no-op after.
    void ensure_selected() const {
        if (selection_pending_) {
            selection_pending_ = false;
            select_lobes(selection_cos_nv_);
        }
    }
    // f |cos| and pdf share their half vector and GGX terms: eval(), pdf() and sample() all go
    // through eval_pdf, which computes both in one pass over the lobes (eval_field, f alone
    // over the field lobes, follows the same steps).
    struct PairTerms;
    bool pair_terms(const vec3& wo, const vec3& wi, PairTerms* terms) const;
    void ggx_terms(const vec3& wo, const vec3& wi, float alpha, PairTerms* terms) const;
    // The masking of wi given wo's: G1(wi) (separable Smith, Cycles 3.4) or G2 / G1(wo)
    // (height-correlated, Cycles 4).
    float masking_given_o(const PairTerms& terms) const;
    void lobe_eval_pdf(const Lobe& lobe, const vec3& wo, const vec3& wi, PairTerms* terms,
                       vec3* f, float* pdf) const;
    void eval_pdf(const vec3& wo, const vec3& wi, BsdfEval* eval, float* pdf) const;
    bool lobe_sample(const Lobe& lobe, const vec3& wo, const vec2& u, vec3* wi) const;
    vec3 specular_color(float cos_lh) const;
    // PrincipledModel::V2's factors toward the camera-side direction (cos_camera to the normal),
    // from one lookup of the GGX energy tables: the share of light the dielectric specular layer
    // passes to the diffuse (1 - its estimated albedo); with Multiscatter GGX the specular lobe's
    // energy-preservation scale and the metallic lobe's albedo darkening (1 otherwise).
    struct CameraSide {
        float layer_transmittance = 1.0f;
        vec3 specular_scale{1.0f};
        vec3 metal_darkening{1.0f};
    };
    CameraSide camera_side(float cos_camera) const;
    // camera_side(wi.z) for a light path's pair, computed once per pair (both lobes read it).
    const CameraSide& light_path_side(const vec3& wi, PairTerms* terms) const;
    // cos_lh: cosine between wi and the reflection half vector.
    float diffuse_brdf(const vec3& wo, const vec3& wi, float cos_lh) const;

    // Only lobes_[0, lobe_count_) are ever read, and every field of those is written first
    // (add_lobe, then the constructor's selection probabilities): left uninitialised, as zeroing
    // the 96 bytes was a `rep stosq` in every constructor (~1% of the photon trace's time).
    std::array<Lobe, 4> lobes_;
    int lobe_count_ = 0;
    vec3 cspec0_{0.0f};
    float specular_ior_ = 1.0f;  // ior whose Fresnel drives the specular colour
    float specular_f0_ = 0.0f;
    float inv_one_minus_f0_ = 1.0f;  // 1 / (1 - specular_f0_), for specular_color
    float eta_ = 1.45f;          // relative ior across the surface (inverted on back faces)
    float roughness_ = 0.5f;
    // The microfacet lobes' roughness (sqrt of their alpha): roughness_ until blur() widens them.
    float glossy_roughness_ = 0.5f;
    DiffuseModel diffuse_model_ = DiffuseModel::Principled;
    bool height_correlated_ = false;  // PrincipledModel::V2's Smith G2
    // PrincipledModel::V2 terms, which depend on the camera-side direction: folded into the lobe
    // weights for PathOrigin::Camera, applied per scattered wi for PathOrigin::Light.
    struct V2Terms {
        bool active = false;       // V2 with a specular lobe
        bool from_light = false;
        bool multiscatter = false;
        float metallic = 0.0f;
        float dielectric_weight = 0.0f;  // of the dielectric layer; 0 without one (Specular 0)
        float dielectric_fss = 0.0f;     // single-scattering mean Fresnel of each lobe
        vec3 metal_fss{0.0f};
    } v2_;
    vec3 glossy_albedo_{0.0f};  // V2: GlossCol of the specular lobe (toward wo)
    vec3 smooth_normal_{0.0f, 0.0f, 1.0f};  // set_smooth_normal
    bool bent_ = false;
    bool microfacet_bump_ = false;
    mutable vec3 albedo_estimate_{0.0f};  // select_lobes
    // The deferred lobe selection's view (see the constructors).
    float selection_cos_nv_ = 1.0f;
    mutable bool selection_pending_ = false;
};

}  // namespace shgi
