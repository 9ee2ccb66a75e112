#include "render/shading.h"

#include <algorithm>
#include <cmath>

#include "render/normal_map.h"

namespace shgi {
namespace {

// wo.z of a mirrored view direction that lies in the bent normal's tangent plane: positive, as
// the lobes require, and irrelevant to a Lambert lobe's value.
constexpr float kMinLambertCosine = 1e-6f;

}  // namespace

vec3 offset_origin(const vec3& p, const vec3& normal) {
    const float scale = 1.0f + max_abs_component(p);
    return p + normal * (kRayOffset * scale);
}

vec3 texture_bilinear(const Texture& texture, const vec2& uv) {
    const float x = uv.x * float(texture.width) - 0.5f;
    const float y = uv.y * float(texture.height) - 0.5f;
    const float fx = std::floor(x), fy = std::floor(y);
    const float tx = x - fx, ty = y - fy;
    auto texel = [&](float ix, float iy) {
        const int64_t w = texture.width, h = texture.height;
        const int64_t cx = ((int64_t(ix) % w) + w) % w, cy = ((int64_t(iy) % h) + h) % h;
        return vec3(texture.texels[size_t(cy * w + cx)]);
    };
    const vec3 bottom = glm::mix(texel(fx, fy), texel(fx + 1.0f, fy), tx);
    const vec3 top = glm::mix(texel(fx, fy + 1.0f), texel(fx + 1.0f, fy + 1.0f), tx);
    return glm::mix(bottom, top, ty);
}

MaterialLobeTable::MaterialLobeTable(const Scene& scene) {
    // The terms are the committed scene's (none before its first commit: then no entry).
    const std::vector<Material>& materials = scene.materials();
    const size_t count = std::min(materials.size(), scene.material_terms().size());
    lobes_.resize(count);
    albedo_.assign(count, vec3(0.0f));
    has_lobes_.assign(count, 0);
    for (size_t m = 0; m < count; ++m) {
        const MaterialTerms& terms = scene.material_terms()[m];
        if (!PrincipledBsdf::lobes_depend_on_hit_only_by_view(materials[m], terms)) continue;
        lobes_[m] = PrincipledBsdf::material_lobes(materials[m], terms);
        albedo_[m] = lobes_[m].class_color_sum();
        has_lobes_[m] = 1;
    }
}

Shading make_shading(const Scene& scene, const SurfacePoint& sp, const vec3& ray_direction,
                     PathOrigin origin, const MaterialLobeTable* lobes, FrameMemo* frames) {
    vec3 ng = sp.geometric_normal, ns = sp.shading_normal;
    const bool back_face = glm::dot(ray_direction, ng) > 0.0f;
    if (back_face) {
        ng = -ng;
        ns = -ns;
    }
    const Material& material = scene.materials()[sp.material_id];
    const MaterialTerms& terms = scene.material_terms()[sp.material_id];
    // A normal map bends the interpolated normal; Cycles then keeps the view ray's mirror image
    // above the geometric surface (render/normal_map.h): Cycles 3.x for every closure, Cycles 4+
    // for the specular closures only. SHGI's lobes share one frame: it is corrected unless the
    // material is a Blender 4+ one with only its (Lambert) diffuse lobe, which keeps the bent
    // normal even facing away from the viewer: Cycles shades it as it is, and a Lambert lobe
    // does not depend on wo, so wo is mirrored to the normal's side below (the lobes' convention
    // wo.z > 0) without changing a value.
    // A Bump node bends the result once more (its Normal input is the normal map's output), and
    // its normal takes the same guards.
    const vec3 smooth = ns;
    bool bent = false, keep_bent = false;
    if (material.normal_texture != kNoTexture)
        ns = mapped_normal(material, scene.textures()[size_t(material.normal_texture)], sp, ns,
                           back_face, scene.normal_from_object(sp.instance_id));
    if (material.bump_texture != kNoTexture)
        ns = bumped_normal(material, scene.textures()[size_t(material.bump_texture)], sp, ns);
    if (ns != smooth) {
        bent = true;
        const bool lambert_only = material.diffuse_model == DiffuseModel::Lambert &&
                                  !terms.specular && terms.transmission <= 0.0f;
        // A particle's arrival is a camera path's light side, where Cycles keeps the bent
        // normal (the guard above is for the view): a particle from below it brings nothing
        // (particle_arrival_ratio), as a camera path rejects such light.
        keep_bent = (material.principled_model == PrincipledModel::V2 && lambert_only) ||
                    origin == PathOrigin::Light;
        if (!keep_bent) ns = ensure_valid_reflection(ng, -ray_direction, ns);
    }
    // An interpolated normal facing away from the viewer would make wo.z <= 0: fall back.
    if (glm::dot(ns, -ray_direction) <= 0.0f && !keep_bent) ns = ng;
    const Frame frame = frames != nullptr ? frames->from_z(ns) : Frame::from_z(ns);
    vec3 wo = frame.to_local(-ray_direction);
    if (keep_bent) wo.z = std::max(std::fabs(wo.z), kMinLambertCosine);
    vec3 base_color = material.base_color;
    if (material.base_color_texture != kNoTexture)
        base_color *= texture_bilinear(scene.textures()[size_t(material.base_color_texture)], sp.uv);
    const PrincipledBsdf* material_lobes = lobes != nullptr ? lobes->find(sp.material_id) : nullptr;
    Shading shading{sp.position, ng, frame, wo,
                    material_lobes != nullptr
                        ? PrincipledBsdf(*material_lobes, material, terms, back_face, wo.z)
                        : PrincipledBsdf(material, terms, base_color, back_face, wo.z, origin)};
    // Cycles fades a diffuse closure whose normal differs from the interpolated one; a normal
    // that fell back to the geometric one above is not such a closure.
    if (bent && ns != ng)
        shading.bsdf.set_smooth_normal(frame.to_local(smooth),
                                       material.principled_model == PrincipledModel::V2);
    return shading;
}

float particle_arrival_ratio(const Shading& shading, const vec3& wl) {
    if (shading.frame.z == shading.geometric_normal) return 1.0f;
    const float cos_geometric = glm::dot(wl, shading.geometric_normal);
    if (!(cos_geometric > 0.0f)) return 0.0f;
    return std::max(glm::dot(wl, shading.frame.z), 0.0f) / cos_geometric;
}

float particle_diffuse_arrival(const Shading& shading, const vec3& wl) {
    if (shading.frame.z == shading.geometric_normal) return 1.0f;
    return particle_arrival_ratio(shading, wl) *
           shading.bsdf.diffuse_bump_shadowing(shading.frame.to_local(wl));
}

vec3 particle_scatter_weight(const Shading& shading, const vec3& wl, const BsdfSample& bs,
                             const vec3& wi) {
    if (shading.frame.z == shading.geometric_normal) return bs.weight;
    const float cos_shading = std::fabs(bs.wi.z);
    if (!(cos_shading > 0.0f)) return vec3(0.0f);
    vec3 weight = bs.weight;
    // The diffuse lobe's share of the weight was shadowed toward wi; the camera path shadows it
    // toward the light, wl. (A Dirac lobe has no diffuse share.)
    const float shadowed_toward_wi = shading.bsdf.diffuse_bump_shadowing(bs.wi);
    if (!bs.delta && shadowed_toward_wi > 0.0f) {
        const float swap =
            shading.bsdf.diffuse_bump_shadowing(shading.frame.to_local(wl)) / shadowed_toward_wi;
        if (swap != 1.0f)
            weight += bs.eval.by_class[int(LobeClass::Diffuse)] * ((swap - 1.0f) / bs.pdf);
    }
    return weight * (particle_arrival_ratio(shading, wl) *
                     std::fabs(glm::dot(wi, shading.geometric_normal)) / cos_shading);
}

vec3 Shading::spawn_origin(const vec3& wi) const {
    return offset_origin(position, glm::dot(wi, geometric_normal) > 0.0f ? geometric_normal
                                                                         : -geometric_normal);
}

}  // namespace shgi
