#include "render/indirect_field.h"

#include "sh/ggx_zh.h"
#include "sh/sh_irradiance.h"

namespace shgi {

vec3 FieldLookup::irradiance(const vec3& n) const {
    return glm::max(sh_irradiance(radiance, n), vec3(0.0f)) + extra_irradiance;
}

vec3 FieldLookup::glossy(const vec3& n, const vec3& wo, float roughness) const {
    const vec3 reflected = 2.0f * glm::dot(wo, n) * n - wo;
    return sh_specular_radiance(radiance, reflected, roughness);
}

FieldLookup IndirectField::lookup(const vec3& p, const vec3& n) const {
    return FieldLookup{radiance_sh(p, n), vec3(0.0f)};
}

}  // namespace shgi
