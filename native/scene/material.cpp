#include "scene/material.h"

#include <algorithm>
#include <cmath>

#include "scene/scene.h"
#include "scene/validation.h"
#include "util/error.h"

namespace shgi {

using namespace scene_detail;

namespace {

void require_texture_id(const std::string& item, const char* field, int32_t texture,
                        uint32_t texture_count) {
    if (texture < 0 && texture != kNoTexture)
        throw InvalidArgument(format_message(item, ": ", field, " = ", texture,
                                             " is negative; use -1 for none or the id "
                                             "add_texture returned"));
    if (texture != kNoTexture && static_cast<uint32_t>(texture) >= texture_count)
        throw InvalidArgument(format_message(item, ": ", field, " = ", texture,
                                             " but the scene has ", texture_count,
                                             " textures (use -1 for none)"));
}

}  // namespace

void validate_material(const Material& material, uint32_t texture_count) {
    const std::string item = label("material", material.name);
    require_non_negative(item, "base_color", material.base_color);
    for (int c = 0; c < 3; ++c)
        if (material.base_color[c] > kMaxBaseColor)
            throw InvalidArgument(format_message(
                item, ": base_color = ", to_string(material.base_color), " has component ",
                material.base_color[c], " above ", kMaxBaseColor,
                "; a reflectance is in [0, 1] (Blender's Base Color); a surface that glows "
                "takes emission_color and emission_strength"));
    require_in_range(item, "roughness", material.roughness, 0.0f, 1.0f);
    require_in_range(item, "metallic", material.metallic, 0.0f, 1.0f);
    require_in_range(item, "specular", material.specular, 0.0f, 1.0f);
    require_in_range(item, "transmission", material.transmission, 0.0f, 1.0f);
    require_finite(item, "ior", material.ior);
    if (material.ior < 1.0f)
        throw InvalidArgument(format_message(item, ": ior = ", material.ior, " must be >= 1"));
    require_non_negative(item, "emission_color", material.emission_color);
    require_non_negative(item, "emission_strength", material.emission_strength);
    const float brightest_emission = std::max(
        material.emission_color.x, std::max(material.emission_color.y, material.emission_color.z));
    const double radiance = double(brightest_emission) * double(material.emission_strength);
    if (!(radiance <= kMaxEmittedPower))
        throw InvalidArgument(format_message(
            item, ": emission_color = ", to_string(material.emission_color),
            " times emission_strength = ", material.emission_strength, " is ", radiance,
            " W m^-2 sr^-1, beyond the ", kMaxEmittedPower,
            " that single precision carries; give emission_color in [0, 1] and the "
            "brightness in emission_strength"));
    require_texture_id(item, "base_color_texture", material.base_color_texture, texture_count);
    require_texture_id(item, "normal_texture", material.normal_texture, texture_count);
    require_in_range(item, "normal_strength", material.normal_strength, 0.0f, kMaxNormalStrength);
    require_texture_id(item, "bump_texture", material.bump_texture, texture_count);
    require_in_range(item, "bump_strength", material.bump_strength, 0.0f, 1.0f);
    require_in_range(item, "bump_distance", material.bump_distance, -kMaxBumpDistance,
                     kMaxBumpDistance);
}

MaterialTerms material_terms(const Material& material) {
    MaterialTerms terms;
    const float metallic = std::clamp(material.metallic, 0.0f, 1.0f);
    const float transmission = std::clamp(material.transmission, 0.0f, 1.0f);
    terms.metallic = metallic;
    terms.transmission = (1.0f - metallic) * transmission;
    terms.diffuse_scale = (1.0f - metallic) * (1.0f - transmission);
    terms.alpha = material.roughness * material.roughness;
    const float f0 = kSpecularF0Scale * std::clamp(material.specular, 0.0f, 1.0f);
    terms.specular_f0 = f0;
    terms.inv_one_minus_f0 = f0 < 1.0f ? 1.0f / (1.0f - f0) : 0.0f;
    terms.specular_ior = 2.0f / (1.0f - std::sqrt(f0)) - 1.0f;
    terms.dielectric_weight = f0 > 0.0f ? terms.diffuse_scale : 0.0f;
    terms.inv_ior = 1.0f / material.ior;
    terms.specular = material.specular > kClosureWeightCutoff || metallic > kClosureWeightCutoff;
    return terms;
}

void validate_texture(const Texture& texture) {
    const std::string item = label("texture", texture.name);
    if (texture.width == 0 || texture.height == 0)
        throw InvalidArgument(format_message(item, ": size ", texture.width, " x ",
                                             texture.height, " is empty"));
    const uint64_t expected = static_cast<uint64_t>(texture.width) * texture.height;
    if (texture.texels.size() != expected)
        throw InvalidArgument(format_message(item, ": texels has ", texture.texels.size(),
                                             " elements but width x height = ", expected));
    for (size_t i = 0; i < texture.texels.size(); ++i) {
        const vec4& texel = texture.texels[i];
        if (!is_finite(vec3(texel)) || !std::isfinite(texel.w))
            throw InvalidArgument(format_message(item, ": texels[", i, "] = (", texel.x, ", ",
                                                 texel.y, ", ", texel.z, ", ", texel.w,
                                                 ") is not finite"));
        if (std::max(texel.x, std::max(texel.y, texel.z)) > kMaxBaseColor)
            throw InvalidArgument(format_message(
                item, ": texels[", i, "] = (", texel.x, ", ", texel.y, ", ", texel.z,
                ") has a component above ", kMaxBaseColor,
                "; base colour textures hold reflectances in [0, 1]"));
    }
}

}  // namespace shgi
