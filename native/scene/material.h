// Materials: the subset of Blender's Principled BSDF that SHGI renders (3.4 semantics, or 4.x's
// layering with principled_model V2), textures for the base colour, and a normal map (Blender's
// Normal Map node: tangent, object or world space, with its Strength; glTF's normalTexture).
//
// Colours are linear Rec.709. `specular` is Principled's 0..1 "Specular" (F0 = 0.08 * specular
// for dielectrics); Blender 4.x's "Specular IOR Level" maps onto it in the exporter. Emitted
// radiance is emission_color x emission_strength (W m^-2 sr^-1), as Cycles' Emission closure:
// a white surface of strength 1 seen by the camera renders as 1.0.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "util/math.h"

namespace shgi {

inline constexpr int32_t kNoTexture = -1;

// The diffuse lobe: Principled BSDF's, or Blender's Diffuse BSDF (which the exporter maps here).
enum class DiffuseModel : uint8_t {
    Principled,  // Cycles 3.4 Principled diffuse (Burley, with roughness retro-reflection)
    Lambert,     // f = albedo / pi (Blender's Diffuse BSDF with roughness 0)
};

// How the Principled BSDF's closures combine, as the Cycles of each Blender builds them.
enum class PrincipledModel : uint8_t {
    // Blender 3.x: the diffuse and specular closures are added (albedo may exceed 1 by the
    // specular's share).
    V1,
    // Blender 4.0+ ("Principled v2"): the dielectric specular layer dims the diffuse below it by
    // its directional albedo toward the viewer (render/bsdf.h), and the Glossy Color pass holds
    // that albedo instead of the closure weight.
    V2,
};

// The microfacet distribution of the specular lobes.
enum class MicrofacetDistribution : uint8_t {
    GGX,
    // Cycles 4's energy-preserving GGX (Blender 4's default for the Principled BSDF): the lobe is
    // scaled by the energy single scattering misses (Kulla and Conty 2017). Used with
    // PrincipledModel::V2; Blender 3.x's Multiscatter GGX (a random walk) is rendered as GGX.
    MultiscatterGGX,
};

// Largest base_color component accepted. A reflectance is in [0, 1]; a little above is an
// artist's choice the renderers tolerate, but a path's throughput multiplies one albedo per
// bounce and must stay finite in float: 1000 per bounce over 12 bounces is 1e36, below the
// 3.4e38 float limit (a base_color of 1e38 rendered inf pixels). Texture texels have the same cap.
inline constexpr float kMaxBaseColor = 1000.0f;

// The space a normal map's texels are in, as Blender's Normal Map node's `space` (TANGENT,
// OBJECT, WORLD, BLENDER_OBJECT, BLENDER_WORLD). Texels hold (n + 1) / 2 per component, read
// as non-colour data.
enum class NormalMapSpace : uint8_t {
    Tangent,  // along the mesh's tangent frame (Mesh::tangents, MikkTSpace; glTF's only space)
    Object,   // object space, mapped to world by the instance's normal transform
    World,
    // Blender's own convention ("Blender Object Space", "Blender World Space", as Blender's
    // internal renderer baked them): n's Y and Z negated, then as Object and World.
    BlenderObject,
    BlenderWorld,
};

// The largest |Distance| of a Bump node accepted (Blender's own limit).
inline constexpr float kMaxBumpDistance = 1000.0f;

// The largest Normal Map Strength accepted (Blender's soft maximum is 10): beyond it the
// extrapolated normal is the texel's direction anyway.
inline constexpr float kMaxNormalStrength = 100.0f;

struct Material {
    std::string name = "default";
    vec3 base_color{0.8f};
    // With a texture the albedo is texture x base_color (glTF's rule); the Blender exporter
    // passes base_color = 1 when a texture drives Principled's Base Color.
    int32_t base_color_texture = kNoTexture;  // index into Scene::textures(), or kNoTexture
    std::string base_color_uv_set;            // UV set used by the texture ("" = first)
    // The normal map: render/normal_map.h. Strength blends from the interpolated normal (0) to
    // the mapped one (1) and beyond, as Blender's Normal Map node; glTF's normalTexture.scale
    // arrives here too (Blender's glTF importer maps it to the node's Strength).
    int32_t normal_texture = kNoTexture;      // index into Scene::textures(), or kNoTexture
    std::string normal_uv_set;                // UV set of the normal map ("" = first)
    float normal_strength = 1.0f;             // 0..kMaxNormalStrength
    NormalMapSpace normal_space = NormalMapSpace::Tangent;
    // The Bump node with an Image Texture as its Height (render/normal_map.h): the height is the
    // texel's luminance; the node's Normal input is the normal map above when there is one.
    // Distance is signed (Invert negates it); Strength blends from the unbumped normal (0).
    int32_t bump_texture = kNoTexture;        // index into Scene::textures(), or kNoTexture
    std::string bump_uv_set;                  // UV set of the height texture ("" = first)
    float bump_strength = 1.0f;               // 0..1
    float bump_distance = 1.0f;               // -kMaxBumpDistance..kMaxBumpDistance
    float roughness = 0.5f;                   // 0..1, GGX alpha = roughness^2
    float metallic = 0.0f;                    // 0..1
    float specular = 0.5f;                    // 0..1 (F0 = 0.08 * specular)
    float transmission = 0.0f;                // 0..1
    float ior = 1.45f;                        // >= 1
    vec3 emission_color{0.0f};
    float emission_strength = 1.0f;           // >= 0; emission_color x it <= kMaxEmittedPower
    DiffuseModel diffuse_model = DiffuseModel::Principled;
    PrincipledModel principled_model = PrincipledModel::V1;
    MicrofacetDistribution distribution = MicrofacetDistribution::GGX;

    vec3 emission() const { return emission_color * emission_strength; }
    bool is_emissive() const {
        return emission_strength > 0.0f && glm::any(glm::greaterThan(emission_color, vec3(0.0f)));
    }
};

// Throws InvalidArgument naming the material and field for NaN/Inf or out-of-range values.
void validate_material(const Material& material, uint32_t texture_count);

// Principled's "Specular" 0..1 maps to F0 = kSpecularF0Scale * specular (Blender manual).
inline constexpr float kSpecularF0Scale = 0.08f;
// Closures whose weight averages below this are left out (Cycles' CLOSURE_WEIGHT_CUTOFF).
inline constexpr float kClosureWeightCutoff = 1e-5f;

// What shading derives from a Material alone, whatever the hit: Scene::commit() computes them
// once per material (Scene::material_terms()), so the BSDF built at every hit
// (render/bsdf.h) does not redo a square root, up to three divisions and a handful of clamps.
struct MaterialTerms {
    float metallic = 0.0f;           // clamped to [0, 1]
    float transmission = 0.0f;       // (1 - metallic) x clamped transmission: the glass lobes'
    float diffuse_scale = 0.0f;      // (1 - metallic)(1 - transmission): the diffuse lobe's
    float dielectric_weight = 0.0f;  // the dielectric specular layer's; 0 with Specular 0
    float alpha = 0.0f;              // GGX alpha = roughness^2
    float specular_f0 = 0.0f;        // kSpecularF0Scale x clamped specular
    float inv_one_minus_f0 = 0.0f;   // 1 / (1 - specular_f0), 0 when specular_f0 >= 1
    float specular_ior = 1.0f;       // the ior whose Fresnel at normal incidence is specular_f0
    float inv_ior = 1.0f;            // the relative ior seen from a back face, 1 / ior
    bool specular = false;           // Cycles adds a specular closure (Specular or Metallic > 0)
};

MaterialTerms material_terms(const Material& material);

struct Texture {
    std::string name;
    uint32_t width = 0, height = 0;
    std::vector<vec4> texels;  // linear RGBA, row 0 at the bottom (Blender's image convention)
};

void validate_texture(const Texture& texture);

}  // namespace shgi
