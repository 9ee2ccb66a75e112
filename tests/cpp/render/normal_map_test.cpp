// Normal maps against closed forms: texel decoding through the tangent frame of a plane (also
// rotated, mirrored in its bitangent, in object and world space, with Strength), Cycles'
// below-surface correction and bump shadowing term, a sun over a normal-mapped Lambert plane
// (L = rho / pi x S cos(tilt)), and hostile input: NaN tangents, zero texels, missing UVs.
#include <algorithm>
#include <atomic>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "bake/lightmap_baker.h"
#include "bake/texel_rasterizer.h"
#include "photon/photon_tracer.h"
#include "render/normal_map.h"
#include "render/path_tracer.h"
#include "render/preview_renderer.h"
#include "render/shading.h"
#include "render_test_scenes.h"
#include "support/log_capture.h"
#include "support/noise_stats.h"
#include "util/rng.h"

namespace shgi {
namespace {

// Unit vectors computed in float agree to a few ulps of their largest component.
constexpr float kUnitTolerance = 1e-5f;

// A one-texel texture encoding the unit normal n (n = 2c - 1).
Texture normal_texel(const vec3& n) {
    Texture texture;
    texture.name = "normal";
    texture.width = texture.height = 1;
    texture.texels = {vec4(0.5f * n + vec3(0.5f), 1.0f)};
    return texture;
}

// The plane z = 0, UV = (x, y) / 2 + 0.5, tangent +X with bitangent sign `sign`.
Mesh mapped_plane(float sign) {
    Mesh mesh = test::plane(1.0f);
    UvSet uv{"UVMap", {}};
    for (const vec3& p : mesh.positions) uv.coords.push_back(0.5f * vec2(p) + vec2(0.5f));
    mesh.uv_sets.push_back(uv);
    mesh.tangents.assign(mesh.positions.size(), vec4(1.0f, 0.0f, 0.0f, sign));
    return mesh;
}

struct MappedPlane {
    Scene scene;
    Shading shade(const vec3& direction = vec3(0.0f, 0.0f, -1.0f)) const {
        Ray ray;
        ray.direction = direction;
        ray.origin = vec3(0.1f, 0.2f, 0.0f) - 2.0f * direction;
        ray.tmax = kInfinity;
        const Hit hit = scene.intersect(ray);
        EXPECT_TRUE(hit.valid());
        return make_shading(scene, scene.surface_point(ray, hit), ray.direction);
    }
};

MappedPlane plane_with_map(const vec3& texel_normal, Material material = test::lambert(0.8f),
                           const mat4& world_from_object = mat4(1.0f), float sign = 1.0f,
                           Mesh mesh = mapped_plane(1.0f)) {
    if (sign < 0.0f) mesh = mapped_plane(sign);
    MappedPlane plane;
    material.normal_texture = int32_t(plane.scene.add_texture(normal_texel(texel_normal)));
    plane.scene.add_material(material);
    plane.scene.add_instance(plane.scene.add_mesh(std::move(mesh)), world_from_object);
    plane.scene.commit();
    return plane;
}

void expect_unit_near(const vec3& actual, const vec3& expected, const char* what) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(actual[c], expected[c], kUnitTolerance) << what;
}

// A black world, a sun of `strength` straight above the plane z = 0 and a 4 x 4 px orthographic
// camera looking down at its origin; commits the scene.
void light_from_above(Scene& scene, float strength) {
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.5f), 0.01f, 4));
    Light sun;
    sun.type = LightType::Sun;
    sun.strength = strength;
    scene.add_light(sun);
    scene.commit();
}

TEST(NormalMap, FlatTexelKeepsTheInterpolatedNormal) {
    const MappedPlane plane = plane_with_map(vec3(0.0f, 0.0f, 1.0f));
    expect_unit_near(plane.shade().frame.z, vec3(0.0f, 0.0f, 1.0f), "flat texel");
}

TEST(NormalMap, TangentFrameOfAPlane) {
    const float tilt = 0.4f;
    const vec3 texel(std::sin(tilt), 0.0f, std::cos(tilt));
    expect_unit_near(plane_with_map(texel).shade().frame.z, texel, "tilt along +U");
    // +V is the bitangent sign x cross(N, T) = +Y; a negative sign mirrors it.
    const vec3 along_v(0.0f, std::sin(tilt), std::cos(tilt));
    expect_unit_near(plane_with_map(along_v).shade().frame.z, along_v, "tilt along +V");
    expect_unit_near(plane_with_map(along_v, test::lambert(0.8f), mat4(1.0f), -1.0f)
                         .shade()
                         .frame.z,
                     vec3(0.0f, -along_v.y, along_v.z), "mirrored bitangent");
}

// The tangent turns with the object: a quarter turn about Z sends a +U tilt towards +Y; a
// non-uniform scale transforms the object-space combination by the inverse transpose, as Cycles.
TEST(NormalMap, TangentFrameFollowsTheInstance) {
    const float tilt = 0.4f;
    const vec3 texel(std::sin(tilt), 0.0f, std::cos(tilt));
    const mat4 turn = glm::rotate(mat4(1.0f), 0.5f * kPi, vec3(0.0f, 0.0f, 1.0f));
    expect_unit_near(plane_with_map(texel, test::lambert(0.8f), turn).shade().frame.z,
                     vec3(0.0f, std::sin(tilt), std::cos(tilt)), "turned");
    const mat4 stretch = glm::scale(mat4(1.0f), vec3(2.0f, 1.0f, 1.0f));
    // Inverse transpose of diag(2, 1, 1) applied to (sin, 0, cos): (sin / 2, 0, cos).
    expect_unit_near(plane_with_map(texel, test::lambert(0.8f), stretch).shade().frame.z,
                     glm::normalize(vec3(0.5f * std::sin(tilt), 0.0f, std::cos(tilt))),
                     "stretched");
}

TEST(NormalMap, ObjectAndWorldSpace) {
    const vec3 texel = glm::normalize(vec3(0.3f, -0.2f, 0.9f));
    const mat4 turn = glm::rotate(mat4(1.0f), 0.5f * kPi, vec3(0.0f, 0.0f, 1.0f));
    Material material = test::lambert(0.8f);
    material.normal_space = NormalMapSpace::Object;
    expect_unit_near(plane_with_map(texel, material, turn).shade().frame.z,
                     vec3(-texel.y, texel.x, texel.z), "object space, turned");
    material.normal_space = NormalMapSpace::World;
    expect_unit_near(plane_with_map(texel, material, turn).shade().frame.z, texel,
                     "world space ignores the instance");
}

// Blender's own object and world spaces read the texel's Y and Z negated (Cycles'
// node_normal_map: "strange blender convention"): a texel pointing down and back along -Z, -Y
// is the normal up and forward.
TEST(NormalMap, BlenderObjectAndWorldSpaceNegateYAndZ) {
    const vec3 texel = glm::normalize(vec3(0.3f, 0.2f, -0.9f));
    const vec3 blender(texel.x, -texel.y, -texel.z);
    const mat4 turn = glm::rotate(mat4(1.0f), 0.5f * kPi, vec3(0.0f, 0.0f, 1.0f));
    Material material = test::lambert(0.8f);
    material.normal_space = NormalMapSpace::BlenderObject;
    expect_unit_near(plane_with_map(texel, material, turn).shade().frame.z,
                     vec3(-blender.y, blender.x, blender.z), "Blender object space, turned");
    material.normal_space = NormalMapSpace::BlenderWorld;
    expect_unit_near(plane_with_map(texel, material, turn).shade().frame.z, blender,
                     "Blender world space ignores the instance");
}

// (A gentle texel: extrapolated twice it stays clear of the below-surface correction.)
TEST(NormalMap, StrengthBlendsWithTheInterpolatedNormal) {
    const vec3 texel = glm::normalize(vec3(0.2f, 0.0f, 0.98f));
    for (const float strength : {0.0f, 0.5f, 2.0f}) {
        Material material = test::lambert(0.8f);
        material.normal_strength = strength;
        const vec3 expected = glm::normalize(vec3(0, 0, 1) + strength * (texel - vec3(0, 0, 1)));
        expect_unit_near(plane_with_map(texel, material).shade().frame.z, expected, "strength");
    }
}

// Seen from below, the back face's normal map is flipped with the surface.
TEST(NormalMap, BackFaceFlipsTheMappedNormal) {
    const vec3 texel = glm::normalize(vec3(0.3f, 0.0f, 0.9f));
    expect_unit_near(plane_with_map(texel).shade(vec3(0.0f, 0.0f, 1.0f)).frame.z, -texel,
                     "back face");
}

// The corrected normal lies in the plane of ng and n, between them, and its reflection of wo
// leaves the surface at exactly the threshold elevation; a normal whose reflection is already
// above the threshold is kept. Random configurations over the hemisphere.
TEST(NormalMap, EnsureValidReflection) {
    Pcg32 rng(7);
    const vec3 ng(0.0f, 0.0f, 1.0f);
    int corrected = 0;
    for (int i = 0; i < 2000; ++i) {
        const float cos_wo = 0.02f + 0.98f * rng.next_float();
        const float phi_wo = kTwoPi * rng.next_float();
        const vec3 wo = spherical_direction(std::sqrt(1.0f - cos_wo * cos_wo), cos_wo, phi_wo);
        const float cos_n = 0.05f + 0.95f * rng.next_float();
        const vec3 n = spherical_direction(std::sqrt(1.0f - cos_n * cos_n), cos_n,
                                           kTwoPi * rng.next_float());
        const vec3 result = ensure_valid_reflection(ng, wo, n);
        EXPECT_NEAR(glm::length(result), 1.0f, kUnitTolerance);
        const float threshold =
            std::min(kReflectionCosineShare * cos_wo, kMinReflectionCosine);
        const vec3 reflected = 2.0f * glm::dot(result, wo) * result - wo;
        const vec3 original = 2.0f * glm::dot(n, wo) * n - wo;
        if (glm::dot(original, ng) >= threshold) {
            EXPECT_EQ(result, n);
            continue;
        }
        ++corrected;
        EXPECT_NEAR(glm::dot(reflected, ng), threshold, 1e-4f) << "case " << i;
        EXPECT_NEAR(glm::dot(glm::cross(ng, n), result), 0.0f, 1e-5f) << "in the plane";
        EXPECT_GE(result.z, n.z - 1e-6f) << "tilted towards ng, not away";
    }
    EXPECT_GT(corrected, 100) << "the random cases must exercise the correction";
}

// Chiang et al.'s term: 1 with no bend or light above the bent horizon's reach, 0 at the
// interpolated horizon, and g = 0.5 gives -g^3 + g^2 + g = 0.625.
TEST(NormalMap, BumpShadowingTerm) {
    const vec3 smooth(0.0f, 0.0f, 1.0f);
    EXPECT_EQ(bump_shadowing_term(smooth, smooth, glm::normalize(vec3(1.0f, 0.0f, 0.2f))), 1.0f);
    const float bend = 0.5f;
    const vec3 bent(std::sin(bend), 0.0f, std::cos(bend));
    EXPECT_EQ(bump_shadowing_term(smooth, bent, vec3(0.0f, 0.0f, 1.0f)), 1.0f);
    EXPECT_EQ(bump_shadowing_term(smooth, bent, vec3(1.0f, 0.0f, 0.0f)), 0.0f);
    // g = cos(wi, smooth) / (cos(wi, bent) cos(bend)): pick wi's elevation so g = 1/2.
    // With wi = (sin a, 0, cos a): cos a / (cos(a - bend) cos bend) = 1/2.
    float a = 0.0f;
    float lo = 0.0f, hi = 0.5f * kPi;
    for (int step = 0; step < 40; ++step) {  // bisection: 2^-40 of the interval, below float's
        a = 0.5f * (lo + hi);
        const float g = std::cos(a) / (std::cos(a - bend) * std::cos(bend));
        (g > 0.5f ? lo : hi) = a;
    }
    EXPECT_NEAR(bump_shadowing_term(smooth, bent, vec3(std::sin(a), 0.0f, std::cos(a))), 0.625f,
                1e-4f);
}

// Cycles 4+'s microfacet term: 1 without a bend, 0 below the interpolated horizon, and GGX's
// Smith G1 with alpha^2 = tan^2(bend) / 8 in between, which falls as the light grazes.
TEST(NormalMap, BumpShadowingMicrofacet) {
    const vec3 smooth(0.0f, 0.0f, 1.0f);
    const vec3 grazing = glm::normalize(vec3(1.0f, 0.0f, 0.1f));
    EXPECT_EQ(bump_shadowing_microfacet(smooth, smooth, grazing), 1.0f);
    const float bend = 0.6f;
    const vec3 bent(std::sin(bend), 0.0f, std::cos(bend));
    EXPECT_EQ(bump_shadowing_microfacet(smooth, bent, glm::normalize(vec3(1.0f, 0.0f, -0.1f))),
              0.0f);
    const float tan_bend = std::tan(bend), cos_i = 0.1f;
    const float alpha2 = tan_bend * tan_bend / 8.0f;
    const float tan2_i = (1.0f - cos_i * cos_i) / (cos_i * cos_i);
    const vec3 wi(std::sqrt(1.0f - cos_i * cos_i), 0.0f, cos_i);
    EXPECT_NEAR(bump_shadowing_microfacet(smooth, bent, wi),
                2.0f / (1.0f + std::sqrt(1.0f + alpha2 * tan2_i)), 1e-5f);
    EXPECT_LT(bump_shadowing_microfacet(smooth, bent, wi),
              bump_shadowing_microfacet(smooth, bent, glm::normalize(vec3(1.0f, 0.0f, 1.0f))));
}

// Blender 4+ (PrincipledModel::V2) Lambert-only material: Cycles leaves the bent normal
// uncorrected, even facing away from the viewer; so does SHGI. Blender 3.x corrects it.
TEST(NormalMap, BlenderFourKeepsTheBentNormalOfALambertMaterial) {
    const vec3 texel = glm::normalize(vec3(-0.6f, 0.0f, 0.8f));  // tilted away from the viewer
    const vec3 grazing = glm::normalize(vec3(-1.0f, 0.0f, -0.15f));
    Material v2 = test::lambert(0.8f);
    v2.principled_model = PrincipledModel::V2;
    const Shading kept = plane_with_map(texel, v2).shade(grazing);
    expect_unit_near(kept.frame.z, texel, "V2 keeps the bent normal");
    EXPECT_GT(kept.wo.z, 0.0f);
    const Shading corrected = plane_with_map(texel).shade(grazing);
    const vec3 wo = -grazing;
    const vec3 reflected = 2.0f * glm::dot(corrected.frame.z, wo) * corrected.frame.z - wo;
    EXPECT_NEAR(reflected.z, std::min(kReflectionCosineShare * wo.z, kMinReflectionCosine), 1e-4f)
        << "V1 corrects it";
}

// A 100 m Lambert plane of `albedo` at z = 0 whose normal map tilts every normal by `tilt`
// towards +x.
void add_tilted_lambert_plane(Scene& scene, float albedo, float tilt) {
    Material material = test::lambert(albedo);
    material.normal_texture =
        int32_t(scene.add_texture(normal_texel(vec3(std::sin(tilt), 0.0f, std::cos(tilt)))));
    scene.add_material(material);
    Mesh mesh = mapped_plane(1.0f);
    for (vec3& p : mesh.positions) p *= 50.0f;
    scene.add_instance(scene.add_mesh(mesh), mat4(1.0f));
}

// A sun straight above a Lambert plane whose normal map tilts every normal by `tilt`:
// L = rho / pi x S cos(tilt) (no correction: the view's reflection stays well above the surface;
// no bump shadowing: the light is above both horizons). The Normal pass holds the tilted normal.
TEST(NormalMap, SunOverNormalMappedPlane) {
    const float albedo = 0.5f, strength = 3.0f, tilt = 0.5f;
    Scene scene;
    add_tilted_lambert_plane(scene, albedo, tilt);
    light_from_above(scene, strength);
    PathTracer tracer(scene, test::settings_with_samples(4));
    tracer.render(4);
    const test::PixelStats stats = test::pixel_stats(tracer.film(), Pass::Combined);
    const double expected = albedo * kInvPi * strength * std::cos(tilt);
    testing::expect_within_noise(stats.mean, stats.standard_error, expected, 2e-3 * expected,
                                 "normal-mapped sun");
    EXPECT_NEAR(test::pixel_stats(tracer.film(), Pass::Normal, 0).mean, std::sin(tilt), 1e-5);
    EXPECT_NEAR(test::pixel_stats(tracer.film(), Pass::Normal, 2).mean, std::cos(tilt), 1e-5);
}

// Uniform radiance, recording how far the normals it is looked up for lean from +z.
class NormalRecordingField : public IndirectField {
  public:
    ShRgb radiance_sh(const vec3&, const vec3& n) const override {
        ++lookups_;
        const int lean = int(std::lround(1e6f * (1.0f - n.z)));
        int seen = largest_lean_.load();
        while (lean > seen && !largest_lean_.compare_exchange_weak(seen, lean)) {}
        ShRgb sh(2);
        sh[0] = vec3(std::sqrt(kFourPi));
        return sh;
    }
    uint64_t lookups() const { return lookups_.load(); }
    float largest_lean() const { return 1e-6f * float(largest_lean_.load()); }

  private:
    mutable std::atomic<uint64_t> lookups_{0};
    mutable std::atomic<int> largest_lean_{0};
};

// A field is looked up for the surface's interpolated normal, not the bent one: fields place
// their lookup by it (a light propagation volume moves it normal_offset cells along it and damps
// by the light behind it, a probe grid biases it), and a bent normal moved the lookup sideways
// and towards the surface (on test_instant_gi.py's striped floor the propagation volume read
// 1.10x its flat floor's ratio to the path tracer, 1.08x looked up for the interpolated normal).
// The diffuse lobe itself is still gathered about the bent normal.
TEST(NormalMap, FieldLookupsUseTheInterpolatedNormal) {
    Scene scene;
    add_tilted_lambert_plane(scene, 0.5f, 0.5f);
    light_from_above(scene, 0.0f);
    const NormalRecordingField field;
    PreviewSettings settings;
    settings.samples = 2;
    render_preview(scene, &field, settings);
    EXPECT_GT(field.lookups(), 0u);
    EXPECT_LT(field.largest_lean(), 1e-5f);  // the bent normal leans 1 - cos 0.5 = 0.12
}

// The bake reads a field as the preview does: looked up for the interpolated normal, its light
// gathered about the bent normal with the diffuse lobe's bump shadowing. In light from every
// direction the plain cosine gathers pi whatever the normal (the bake read exactly 1 before);
// with the shadowing term less, and the bake's Indirect texels (E / pi) times the albedo equal
// the preview's field light.
TEST(NormalMap, LightmapBakeReadsTheFieldAsThePreviewDoes) {
    const float albedo = 0.5f;
    Scene scene;
    add_tilted_lambert_plane(scene, albedo, 0.5f);
    light_from_above(scene, 0.0f);
    const NormalRecordingField field;
    TexelRasterSettings raster;
    raster.width = raster.height = 8;
    raster.uv_set = "UVMap";
    LightmapSettings bake;
    bake.samples = 4;
    bake.content = LightmapContent::Indirect;
    const LightmapTexels texels =
        bake_lightmap(scene, rasterize_texels(scene, 0, raster), &field, bake);
    EXPECT_GT(field.lookups(), 0u);
    EXPECT_LT(field.largest_lean(), 1e-5f);
    double sum = 0.0;
    uint64_t baked = 0;
    for (uint64_t t = 0; t < texels.texel_count(); ++t) {
        if (!texels.baked[t]) continue;
        sum += texels.color[3 * t];
        ++baked;
    }
    ASSERT_GT(baked, 0u);
    const double texel_mean = sum / double(baked);
    EXPECT_LT(texel_mean, 0.99);  // the shadowing term takes light near the horizon

    PreviewSettings settings;
    settings.samples = 2;
    const Image image = render_preview(scene, &field, settings);
    const std::vector<float> combined = image.layer_pixels("Combined");
    const size_t channels = combined.size() / image.pixel_count();
    double preview = 0.0;
    for (size_t i = 0; i < image.pixel_count(); ++i) preview += combined[channels * i];
    preview /= double(image.pixel_count());
    EXPECT_NEAR(albedo * texel_mean, preview, 1e-4 * preview);
}

// Photons onto a normal-mapped Lambert plane under a sun at angle `sun_angle` from the zenith
// (towards +x) against the path tracer looking straight down: a first hit's reflected_power is
// the flux the surface scatters, which for a Lambert surface is pi x the radiance the camera
// path reads, per arriving photon power spread by the geometric cosine (Veach 1997 §5.3):
// reflected / arriving = pi L / (E cos(ng, wl)). Tilted normals (tilt towards +x): light from
// the far side (cosine to the bent normal 0.62 against 0.92 to the geometric one), from the
// tilt's side low enough for the bump shadowing term (S ~ 0.67), and from below the bent
// normal's horizon (nothing, as the camera path rejects it).
void expect_first_hits_match_the_path_tracer(float sun_angle) {
    constexpr double kFloatRounding = 1e-4;  // relative: float cosines, BSDF and film sums
    const float albedo = 0.5f, strength = 3.0f, tilt = 0.5f;
    Scene scene;
    add_tilted_lambert_plane(scene, albedo, tilt);
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.5f), 0.01f, 4));
    Light sun;
    sun.type = LightType::Sun;
    sun.strength = strength;
    sun.world_from_light = glm::rotate(mat4(1.0f), sun_angle, vec3(0.0f, 1.0f, 0.0f));
    scene.add_light(sun);
    scene.commit();

    PathTracer tracer(scene, test::settings_with_samples(4));
    tracer.render(4);
    const test::PixelStats camera = test::pixel_stats(tracer.film(), Pass::Combined);

    PhotonTracerSettings settings;
    settings.photons = 256;
    settings.seed = 3;
    settings.store_first_hits = true;
    const PhotonMaps maps = trace_photons(scene, settings, 0);
    ASSERT_GT(maps.first_hits.size(), 0u);
    for (const PhotonFirstHit& hit : maps.first_hits) {
        const float cos_geometric = glm::dot(hit.normal, hit.direction);
        ASSERT_GT(cos_geometric, 0.0f);
        const double ratio = double(hit.reflected_power.x) / double(hit.power.x);
        const double expected = kPi * camera.mean / (strength * cos_geometric);
        const double error = kPi * camera.standard_error / (strength * cos_geometric);
        testing::expect_within_noise(ratio, error, expected, kFloatRounding * expected,
                                     "first hit on the normal-mapped plane");
    }
}

TEST(NormalMap, PhotonFirstHitsScatterWhatTheCameraPathReads) {
    expect_first_hits_match_the_path_tracer(-0.4f);  // beyond the tilt: cos ratio 0.68
    expect_first_hits_match_the_path_tracer(1.2f);   // on the tilt's side: bump shadowing
    expect_first_hits_match_the_path_tracer(-1.2f);  // below the bent normal's horizon: zero
}

// A photon scattered off the normal-mapped plane carries the adjoint BSDF's weight: for each
// sampled direction wi, weight x pdf / |wi.ng| is what the camera path looking back along wi
// reads from light at wl, f cos(wl, ns) S(wl), over cos(wl, ng) (Veach 1997 §5.3), whatever the
// photon's own shading evaluated towards wi. Pairs where the camera's view bends the normal
// back (Cycles' correction, which the view decides) are skipped; most are not.
TEST(NormalMap, PhotonScatterWeightIsTheCameraPathsAdjoint) {
    constexpr float kTilt = 0.5f;
    constexpr float kRelativeRounding = 1e-4f;  // float cosines and BSDF terms
    const MappedPlane plane =
        plane_with_map(vec3(std::sin(kTilt), 0.0f, std::cos(kTilt)), test::lambert(0.5f));
    const vec3 origin(0.1f, 0.2f, 0.0f);
    const auto shade_from = [&](const vec3& toward, PathOrigin path_origin) {
        Ray ray;
        ray.direction = -toward;
        ray.origin = origin + 2.0f * toward;
        ray.tmax = kInfinity;
        const Hit hit = plane.scene.intersect(ray);
        EXPECT_TRUE(hit.valid());
        return make_shading(plane.scene, plane.scene.surface_point(ray, hit), ray.direction,
                            path_origin);
    };
    int checked = 0, pairs = 0;
    for (const float light_angle : {-0.4f, 1.2f}) {  // beyond the tilt; bump shadowing
        const vec3 wl(std::sin(light_angle), 0.0f, std::cos(light_angle));
        const Shading photon = shade_from(wl, PathOrigin::Light);
        for (int j = 0; j < 4; ++j)
            for (int i = 0; i < 4; ++i) {
                BsdfSample bs;
                const vec2 u((float(i) + 0.5f) / 4.0f, (float(j) + 0.5f) / 4.0f);
                if (!photon.bsdf.sample(photon.wo, 0.5f, u, &bs)) continue;
                const vec3 wi = glm::normalize(photon.frame.to_world(bs.wi));
                if (wi.z <= 0.0f) continue;  // below the geometric surface: the tracer drops it
                ++pairs;
                const Shading camera = shade_from(wi, PathOrigin::Camera);
                if (glm::distance(camera.frame.z, photon.frame.z) > kUnitTolerance) continue;
                const vec3 weight = particle_scatter_weight(photon, wl, bs, wi);
                const vec3 f_cos = camera.bsdf.eval(camera.wo, camera.frame.to_local(wl)).total();
                const float expected = f_cos.x * wi.z / (wl.z * bs.pdf);
                EXPECT_NEAR(weight.x, expected, kRelativeRounding * expected)
                    << "light angle " << light_angle << ", u " << u.x << " " << u.y;
                ++checked;
            }
    }
    EXPECT_GT(checked, pairs / 2);
}

// --- hostile input: the map is skipped where it cannot apply, with a warning, never a crash.

TEST(NormalMap, NanTangentFallsBackWithAWarning) {
    Mesh mesh = mapped_plane(1.0f);
    mesh.tangents[0] = vec4(std::nanf(""), 0.0f, 0.0f, 1.0f);
    mesh.tangents[2] = vec4(0.0f);  // zero length: no direction either
    testing::LogCapture log;
    const MappedPlane plane =
        plane_with_map(glm::normalize(vec3(0.5f, 0.0f, 0.8f)), test::lambert(0.8f), mat4(1.0f),
                       1.0f, mesh);
    EXPECT_EQ(plane.scene.mesh_reports()[0].dropped_tangents, 2u);
    EXPECT_NE(log.warnings.find("2 of 4 tangents are NaN, infinite or zero"), std::string::npos)
        << log.warnings;
    // Both triangles use vertex 0 or 2: shaded by the interpolated normal.
    expect_unit_near(plane.shade().frame.z, vec3(0.0f, 0.0f, 1.0f), "dropped tangent");
}

TEST(NormalMap, ZeroTexelFallsBackToTheInterpolatedNormal) {
    const MappedPlane plane = plane_with_map(vec3(0.0f));  // a (0.5, 0.5, 0.5) grey texel
    expect_unit_near(plane.shade().frame.z, vec3(0.0f, 0.0f, 1.0f), "zero texel");
}

TEST(NormalMap, MeshWithoutUvsWarnsAndRendersUnmapped) {
    Mesh mesh = test::plane(1.0f);  // no UVs, no tangents
    testing::LogCapture log;
    const MappedPlane plane = plane_with_map(glm::normalize(vec3(0.5f, 0.0f, 0.8f)),
                                             test::lambert(0.8f), mat4(1.0f), 1.0f, mesh);
    EXPECT_NE(log.warnings.find("has a tangent-space normal map but the mesh has no UV map"),
              std::string::npos)
        << log.warnings;
    expect_unit_near(plane.shade().frame.z, vec3(0.0f, 0.0f, 1.0f), "no UVs");
}

TEST(NormalMap, RejectsBadMaterialFields) {
    Scene scene;
    Material material;
    material.name = "Bumpy";
    material.normal_texture = 0;
    EXPECT_THROW(
        {
            try {
                scene.add_material(material);
                scene.add_instance(scene.add_mesh(test::plane(1.0f)), mat4(1.0f));
                scene.commit();
            } catch (const InvalidArgument& error) {
                EXPECT_NE(std::string(error.what()).find(
                              "material 'Bumpy': normal_texture = 0 but the scene has 0 textures"),
                          std::string::npos)
                    << error.what();
                throw;
            }
        },
        InvalidArgument);
    material.normal_texture = kNoTexture;
    material.normal_strength = std::nanf("");
    EXPECT_THROW(scene.add_material(material), InvalidArgument);
    material.normal_strength = -1.0f;
    EXPECT_THROW(scene.add_material(material), InvalidArgument);
}

// --- the Bump node: normalize(N - distance grad h), grad h along the surface (Cycles'
// svm_node_set_bump), on the plane z = 0 with UV = (x, y) / 2 + 0.5 (du/dx = dv/dy = 1/2).

// A height texture rising linearly by `rise` across it along u (along_u) or v: bilinear lookups
// between the first and last texel centres give h exactly, and grad h = rise / 2 per unit of x
// (or y) on the plane. `colour` weights the rise per channel (the height is the luminance).
Texture height_ramp(float rise, bool along_u, const vec3& colour = vec3(1.0f)) {
    constexpr uint32_t kTexels = 64;
    Texture texture;
    texture.name = "height";
    texture.width = along_u ? kTexels : 1;
    texture.height = along_u ? 1 : kTexels;
    for (uint32_t i = 0; i < kTexels; ++i)
        texture.texels.push_back(vec4(colour * (rise * (float(i) + 0.5f) / float(kTexels)), 1.0f));
    return texture;
}

MappedPlane bumped_plane(const Texture& height, float distance, float strength = 1.0f,
                         const mat4& world_from_object = mat4(1.0f),
                         Mesh mesh = mapped_plane(1.0f), Material material = test::lambert(0.8f)) {
    MappedPlane plane;
    material.bump_texture = int32_t(plane.scene.add_texture(height));
    material.bump_distance = distance;
    material.bump_strength = strength;
    plane.scene.add_material(material);
    plane.scene.add_instance(plane.scene.add_mesh(std::move(mesh)), world_from_object);
    plane.scene.commit();
    return plane;
}

TEST(BumpMap, LinearRampTiltsTheNormalAgainstItsGradient) {
    const float rise = 1.0f, distance = 0.3f;
    // grad h = (rise / 2, 0, 0): N - distance grad h.
    expect_unit_near(bumped_plane(height_ramp(rise, true), distance).shade().frame.z,
                     glm::normalize(vec3(-distance * 0.5f * rise, 0.0f, 1.0f)), "ramp along u");
    expect_unit_near(bumped_plane(height_ramp(rise, false), distance).shade().frame.z,
                     glm::normalize(vec3(0.0f, -distance * 0.5f * rise, 1.0f)), "ramp along v");
    // Invert: a negative distance bends the other way.
    expect_unit_near(bumped_plane(height_ramp(rise, true), -distance).shade().frame.z,
                     glm::normalize(vec3(distance * 0.5f * rise, 0.0f, 1.0f)), "inverted");
}

TEST(BumpMap, StrengthBlendsWithTheUnbumpedNormal) {
    const vec3 full = glm::normalize(vec3(-0.3f * 0.5f, 0.0f, 1.0f));
    expect_unit_near(bumped_plane(height_ramp(1.0f, true), 0.3f, 0.4f).shade().frame.z,
                     glm::normalize(0.4f * full + 0.6f * vec3(0.0f, 0.0f, 1.0f)), "strength 0.4");
    expect_unit_near(bumped_plane(height_ramp(1.0f, true), 0.3f, 0.0f).shade().frame.z,
                     vec3(0.0f, 0.0f, 1.0f), "strength 0");
}

// The height is in texture space, the gradient in world space: an instance stretched twice along
// X halves du/dx and so the slope.
TEST(BumpMap, GradientFollowsTheInstanceScale) {
    const mat4 stretch = glm::scale(mat4(1.0f), vec3(2.0f, 1.0f, 1.0f));
    expect_unit_near(bumped_plane(height_ramp(1.0f, true), 0.3f, 1.0f, stretch).shade().frame.z,
                     glm::normalize(vec3(-0.3f * 0.25f, 0.0f, 1.0f)), "stretched");
}

// Blender converts the texture's colour to the Height float by its luminance.
TEST(BumpMap, HeightIsTheTexelsLuminance) {
    const float red_only = luminance(vec3(1.0f, 0.0f, 0.0f));
    expect_unit_near(
        bumped_plane(height_ramp(1.0f, true, vec3(1.0f, 0.0f, 0.0f)), 0.3f).shade().frame.z,
        glm::normalize(vec3(-0.3f * 0.5f * red_only, 0.0f, 1.0f)), "red ramp");
}

// The Bump node's Normal input is the normal map's output: a flat height keeps it.
TEST(BumpMap, FlatHeightKeepsTheNormalMapsNormal) {
    const float tilt = 0.4f;
    const vec3 texel(std::sin(tilt), 0.0f, std::cos(tilt));
    Material material = test::lambert(0.8f);
    MappedPlane plane;
    material.normal_texture = int32_t(plane.scene.add_texture(normal_texel(texel)));
    material.bump_texture = int32_t(plane.scene.add_texture(height_ramp(0.0f, true)));
    plane.scene.add_material(material);
    plane.scene.add_instance(plane.scene.add_mesh(mapped_plane(1.0f)), mat4(1.0f));
    plane.scene.commit();
    expect_unit_near(plane.shade().frame.z, texel, "flat bump over a normal map");
}

// A sun straight above a Lambert plane bumped by a ramp: L = rho / pi x S cos(tilt), the tilt
// atan(distance x rise / 2).
TEST(BumpMap, SunOverBumpedPlane) {
    const float albedo = 0.5f, strength = 3.0f, distance = 0.6f, rise = 1.0f;
    Scene scene;
    Material material = test::lambert(albedo);
    material.bump_texture = int32_t(scene.add_texture(height_ramp(rise, true)));
    material.bump_distance = distance;
    scene.add_material(material);
    scene.add_instance(scene.add_mesh(mapped_plane(1.0f)), mat4(1.0f));
    light_from_above(scene, strength);
    PathTracer tracer(scene, test::settings_with_samples(4));
    tracer.render(4);
    const test::PixelStats stats = test::pixel_stats(tracer.film(), Pass::Combined);
    const double expected = albedo * kInvPi * strength * std::cos(std::atan(distance * rise * 0.5));
    testing::expect_within_noise(stats.mean, stats.standard_error, expected, 2e-3 * expected,
                                 "bumped sun");
}

TEST(BumpMap, MeshWithoutUvsWarnsAndRendersUnbumped) {
    testing::LogCapture log;
    const MappedPlane plane = bumped_plane(height_ramp(1.0f, true), 0.3f, 1.0f, mat4(1.0f),
                                           test::plane(1.0f));
    EXPECT_NE(log.warnings.find("has a bump map but the mesh has no UV map"), std::string::npos)
        << log.warnings;
    expect_unit_near(plane.shade().frame.z, vec3(0.0f, 0.0f, 1.0f), "no UVs");
}

TEST(BumpMap, RejectsBadMaterialFields) {
    Scene scene;
    Material material;
    material.name = "Bumpy";
    material.bump_texture = 3;
    try {
        scene.add_material(material);
        scene.add_instance(scene.add_mesh(test::plane(1.0f)), mat4(1.0f));
        scene.commit();
        ADD_FAILURE() << "a bump_texture past the scene's textures was accepted";
    } catch (const InvalidArgument& error) {
        EXPECT_NE(std::string(error.what()).find(
                      "material 'Bumpy': bump_texture = 3 but the scene has 0 textures"),
                  std::string::npos)
            << error.what();
    }
    Scene other;
    material.bump_texture = kNoTexture;
    for (const float strength : {std::nanf(""), -0.1f, 1.5f}) {
        material.bump_strength = strength;
        EXPECT_THROW(other.add_material(material), InvalidArgument) << strength;
    }
    material.bump_strength = 1.0f;
    for (const float distance : {std::nanf(""), INFINITY, -2000.0f, 1e6f}) {
        material.bump_distance = distance;
        EXPECT_THROW(other.add_material(material), InvalidArgument) << distance;
    }
}

}  // namespace
}  // namespace shgi
