#include "render/path_integrator.h"

#include <algorithm>
#include <cmath>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "util/owen_sobol.h"
#include "util/sampling.h"
#include "util/timer.h"

namespace shgi {

PixelSample pixel_sample(uint64_t seed, uint64_t pixel, uint64_t sample, bool first_bsdf) {
    const uint32_t base = hash_seed(seed, pixel);
    const uint32_t index = uint32_t(sample);
    PixelSample out{owen_sobol_2d(index, hash_seed(base, 0)),
                    owen_sobol_1d(index, hash_seed(base, 1)),
                    owen_sobol_2d(index, hash_seed(base, 2))};
    if (first_bsdf) {
        // One 3-D sequence: the direction samples of each lobe stay stratified (the plaster's
        // diffuse lobe, 95% of a sun room's first bounces, lost that to an independent u_lobe).
        const vec3 bsdf = owen_sobol_3d(index, hash_seed(base, 4));
        out.u_lobe = bsdf.z;
        out.u_bsdf = vec2(bsdf.x, bsdf.y);
    }
    return out;
}
namespace {

#if defined(__SSE2__)
// The 32-bit steps of util/owen_sobol.h on four lanes: SSE2 has no 32-bit multiply (pmulld is
// SSE4.1) nor byte shuffle, so both are built from what it has; the results are the same
// integers.
struct OwenSobol4 {
    // a * b mod 2^32 per lane.
    static __m128i mul(__m128i a, __m128i b) {
        const __m128i even = _mm_mul_epu32(a, b);
        const __m128i odd = _mm_mul_epu32(_mm_srli_epi64(a, 32), _mm_srli_epi64(b, 32));
        return _mm_unpacklo_epi32(_mm_shuffle_epi32(even, _MM_SHUFFLE(0, 0, 2, 0)),
                                  _mm_shuffle_epi32(odd, _MM_SHUFFLE(0, 0, 2, 0)));
    }
    static __m128i swap_bits(__m128i x, int shift, uint32_t mask) {
        const __m128i m = _mm_set1_epi32(int(mask));
        return _mm_or_si128(_mm_and_si128(_mm_srli_epi32(x, shift), m),
                            _mm_slli_epi32(_mm_and_si128(x, m), shift));
    }
    static __m128i reverse_bits(__m128i x) {
        x = _mm_or_si128(_mm_slli_epi32(x, 16), _mm_srli_epi32(x, 16));  // halves
        x = _mm_or_si128(_mm_slli_epi16(x, 8), _mm_srli_epi16(x, 8));    // bytes
        x = swap_bits(x, 4, 0x0F0F0F0Fu);
        x = swap_bits(x, 2, 0x33333333u);
        return swap_bits(x, 1, 0x55555555u);
    }
    static __m128i laine_karras(__m128i x, __m128i seed) {
        x = _mm_add_epi32(x, seed);
        for (const uint32_t k : {0x6c50b47cu, 0xb82f1e52u, 0xc7afe638u, 0x8d22f6e6u})
            x = _mm_xor_si128(x, mul(x, _mm_set1_epi32(int(k))));
        return x;
    }
    // to_unit_float: the top 24 bits are below 2^31, so the signed conversion is exact.
    static __m128 to_unit_float(__m128i x) {
        return _mm_mul_ps(_mm_cvtepi32_ps(_mm_srli_epi32(x, 8)), _mm_set1_ps(0x1p-24f));
    }
    static __m128i load(const uint32_t (&v)[4]) {
        return _mm_loadu_si128(reinterpret_cast<const __m128i*>(v));
    }
    // owen_sobol_1d (y null) or owen_sobol_2d of one index (reversed: reverse_bits(index)) for
    // four sequence seeds.
    static void point(uint32_t reversed_index, const uint32_t (&seeds)[4], __m128* x,
                      __m128* y) {
        uint32_t h1[4], h2[4];
        for (int j = 0; j < 4; ++j) {
            h1[j] = hash_seed(seeds[j], 1);
            if (y != nullptr) h2[j] = hash_seed(seeds[j], 2);
        }
        const __m128i shuffled = reverse_bits(
            laine_karras(_mm_set1_epi32(int(reversed_index)), load(seeds)));
        *x = to_unit_float(reverse_bits(laine_karras(shuffled, load(h1))));
        if (y == nullptr) return;
        alignas(16) uint32_t lanes[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(lanes), shuffled);
        for (uint32_t& lane : lanes) lane = owen_sobol_detail::sobol_dimension1(lane);
        const __m128i dimension1 = _mm_load_si128(reinterpret_cast<const __m128i*>(lanes));
        *y = to_unit_float(
            reverse_bits(laine_karras(reverse_bits(dimension1), load(h2))));
    }
};
#endif

}  // namespace

void pixel_samples(uint64_t seed, const uint32_t* pixels, size_t count, uint64_t sample,
                   PixelSample* out) {
    size_t i = 0;
#if defined(__SSE2__)
    using owen_sobol_detail::reverse_bits;
    const uint32_t index = uint32_t(sample);
    const uint32_t reversed = reverse_bits(index);
    for (; i + 4 <= count; i += 4) {
        uint32_t seeds[3][4];
        for (int j = 0; j < 4; ++j) {
            const uint32_t base = hash_seed(seed, pixels[i + size_t(j)]);
            for (int d = 0; d < 3; ++d) seeds[d][j] = hash_seed(base, uint64_t(d));
        }
        alignas(16) float jitter_x[4], jitter_y[4], select[4], light_x[4], light_y[4];
        __m128 x, y;
        OwenSobol4::point(reversed, seeds[0], &x, &y);
        _mm_store_ps(jitter_x, x);
        _mm_store_ps(jitter_y, y);
        OwenSobol4::point(reversed, seeds[1], &x, nullptr);
        _mm_store_ps(select, x);
        OwenSobol4::point(reversed, seeds[2], &x, &y);
        _mm_store_ps(light_x, x);
        _mm_store_ps(light_y, y);
        for (int j = 0; j < 4; ++j)
            out[i + size_t(j)] = PixelSample{vec2(jitter_x[j], jitter_y[j]), select[j],
                                             vec2(light_x[j], light_y[j])};
    }
#endif
    for (; i < count; ++i) out[i] = pixel_sample(seed, pixels[i], sample);
}

vec3 path_radiance(const PassValues& values, bool include_direct, float clamp) {
    vec3 radiance = values[Pass::Combined];
    if (!include_direct) radiance -= values[Pass::Emit] + values[Pass::Env];
    radiance = clamp_contribution(glm::max(radiance, vec3(0.0f)), clamp);
    return is_finite(radiance) ? radiance : vec3(0.0f);
}

namespace {

const Pass kDirectPass[kLobeClassCount] = {Pass::DiffDir, Pass::GlossDir, Pass::TransDir};
const Pass kIndirectPass[kLobeClassCount] = {Pass::DiffInd, Pass::GlossInd, Pass::TransInd};
const Pass kColorPass[kLobeClassCount] = {Pass::DiffCol, Pass::GlossCol, Pass::TransCol};

}  // namespace

void PathIntegrator::trace(const Ray& ray) { trace(ray, scene_.intersect(ray)); }

void PathIntegrator::trace(const Ray& camera_ray, const Hit& first_hit) {
    if (!begin(camera_ray, first_hit)) return;
    sample_direct();
    finish();
}

bool PathIntegrator::begin(const Ray& camera_ray, const Hit& first_hit) {
    ray_ = camera_ray;
    return enter_surface(first_hit);
}

// What ray_ meets up to `hit`, then the shading of that surface; false when the path ends here.
bool PathIntegrator::enter_surface(const Hit& hit) {
    find_emission(ray_, hit);
    if (!hit.valid() || terminate_on_next_surface_) return false;
    make_shading_in(&shading_.value, scene_, scene_.surface_point(ray_, hit), ray_.direction);
    blur_glossy(&shading_.value);
    if (vertex_ == 0 && !combined_only_) record_first_hit(shading_.value, ray_, hit);
    if (write_denoising_features_) record_denoising_features(shading_.value);
    return true;
}

// Cycles' Filter Glossy (surface_shader_prepare_closures): after a bounce of pdf below
// filter_glossy, the surface's microfacet lobes widen to alpha sqrt(1 - pdf / filter_glossy) / 2.
void PathIntegrator::blur_glossy(Shading* shading) const {
    if (!(settings_.filter_glossy > 0.0f)) return;
    const float blur_pdf = (1.0f / settings_.filter_glossy) * min_ray_pdf_;  // Cycles' order
    if (blur_pdf < 1.0f) shading->bsdf.blur(std::sqrt(1.0f - blur_pdf) * 0.5f);
}

// Each vertex: direct light (already done for the current surface when this is called), field
// light, then the BSDF chooses whether and where the path continues.
void PathIntegrator::finish() {
    for (;;) {
        if (vertex_field() != nullptr) add_field(shading_.value);
        if (!scatter(shading_.value, &ray_)) return;
        const int total = bounces_[0] + bounces_[1] + bounces_[2];
        terminate_on_next_surface_ = total > settings_.max_bounces ||
                                     bounces_[0] > settings_.diffuse_bounces ||
                                     bounces_[1] > settings_.glossy_bounces ||
                                     bounces_[2] > settings_.transmission_bounces;
        if (vertex_ >= settings_.russian_roulette_depth && !terminate_on_next_surface_) {
            const float largest = max_component(throughput_);
            const float survive = std::min(
                1.0f, settings_.roulette_survival == RouletteSurvival::SqrtThroughput
                          ? std::sqrt(largest)
                          : largest);
            if (rng_.next_float() >= survive) return;
            throughput_ /= survive;
        }
        if (clock_ != nullptr) ++clock_->rays;
        if (!enter_surface(scene_.intersect(ray_))) return;
        sample_direct();
    }
}

// Adds what the ray meets: point/spot disks and area lights in front of the hit, the hit's own
// emission, or the world and suns when it escapes.
void PathIntegrator::find_emission(const Ray& ray, const Hit& hit) {
    lights_.for_each_emission(ray.origin, last_normal_, ray.direction, hit, vertex_ == 0,
                              [&](const EmissionHit& emission, bool is_world) {
                                  add_emission(emission.radiance, emission.light_pdf, is_world);
                              });
}

void PathIntegrator::add_emission(const vec3& radiance, float light_pdf, bool is_world) {
    const float weight = last_delta_ ? 1.0f : power_heuristic(last_pdf_, light_pdf);
    const vec3 contribution = throughput_ * radiance * weight;
    if (vertex_ == 0) {
        out_[is_world ? Pass::Env : Pass::Emit] += contribution;
        out_[Pass::Combined] += contribution;
        return;
    }
    add_split(contribution, vertex_ == 1);
}

// A contribution reaching the camera through the first scattering: clamped whole, as Cycles
// clamps one contribution before it writes its passes, then split by the class fractions of
// that scattering into Dir (one scattering) or Ind passes.
void PathIntegrator::add_split(const vec3& contribution, bool direct) {
    const vec3 value =
        direct ? contribution : clamp_contribution(contribution, settings_.clamp_indirect);
    for (int c = 0; c < kLobeClassCount; ++c)
        if (class_fraction_[c] > 0.0f) add_to_passes(value * class_fraction_[c], c, direct);
}

void PathIntegrator::add_light(const vec3& contribution, int lobe_class, bool direct) {
    add_to_passes(
        direct ? contribution : clamp_contribution(contribution, settings_.clamp_indirect),
        lobe_class, direct);
}

void PathIntegrator::add_to_passes(const vec3& value, int lobe_class, bool direct) {
    if (!is_finite(value)) return;
    out_[direct ? kDirectPass[lobe_class] : kIndirectPass[lobe_class]] += value;
    out_[Pass::Combined] += value;
}

void PathIntegrator::record_first_hit(const Shading& shading, const Ray& ray, const Hit& hit) {
    for (int c = 0; c < kLobeClassCount; ++c)
        out_[kColorPass[c]] += shading.bsdf.class_color(LobeClass(c));
    out_[Pass::Normal] += shading.frame.z;
    const vec3 forward = glm::normalize(-vec3(camera_.world_from_camera[2]));
    const vec3 position = ray.origin + hit.t * ray.direction;
    out_[Pass::Depth].x += glm::dot(position - vec3(camera_.world_from_camera[3]), forward);
}

// Cycles' film_write_denoising_features_surface: a surface whose lobes are mostly specular
// passes its tint on to the next surface the path meets (along the path's own bounce, which
// scatter() samples as before: no random number is drawn here), the first other one writes the
// guides.
void PathIntegrator::record_denoising_features(const Shading& shading) {
    const DenoisingFeature feature = shading.bsdf.denoising_feature(shading.wo.z);
    if (!feature.writes_guides()) {
        denoising_throughput_ *= feature.specular_albedo;
        return;
    }
    const vec3 albedo = denoising_throughput_ * feature.albedo;
    if (is_finite(albedo)) out_[Pass::DenoisingAlbedo] += albedo;
    if (feature.weight > 0.0f) out_[Pass::DenoisingNormal] += shading.frame.z;
    write_denoising_features_ = false;
}

// Next-event estimation at the current surface, MIS-weighted against BSDF sampling.
void PathIntegrator::sample_direct() {
    ScopedTimer timer(clock_ != nullptr && clock_->time_direct ? &clock_->direct : nullptr);
    Ray shadows[kMaxLightSplits];
    const int count = prepare_direct(shadows);
    for (int k = 0; k < count; ++k) {
        if (clock_ != nullptr) ++clock_->rays;
        if (!scene_.occluded(shadows[k])) add_direct(k);
    }
}

int PathIntegrator::prepare_direct(Ray* shadows) {
    const Shading& shading = shading_.value;
    if (!shading.bsdf.has_smooth_lobes()) return 0;  // a Dirac lobe never meets a light sample
    // Left unset: sample_split() writes every sample it returns (zeroing all kMaxLightSplits
    // of them cost more than the one a one-lamp room uses).
    Uninitialized<LightSample[kMaxLightSplits]> samples;
    float u_select = rng_.next_float();
    vec2 u = rng_.next_vec2();
    if (vertex_ == 0 && first_light_sample_) {
        u_select = first_light_sample_->u_select;
        u = first_light_sample_->u;
    }
    const int sampled = lights_.sample_split(shading.position, shading.frame.z, u_select, u,
                                             samples.value);
    int count = 0;
    for (int i = 0; i < sampled; ++i) {
        const LightSample& ls = samples.value[i];
        const vec3 wi = shading.frame.to_local(ls.wi);
        const bool geometric_above = glm::dot(ls.wi, shading.geometric_normal) > 0.0f;
        if (geometric_above != (wi.z > 0.0f)) continue;  // shading and geometric normals disagree
        const BsdfEval eval = vertex_field() != nullptr ? shading.bsdf.eval_field(shading.wo, wi)
                                                        : shading.bsdf.eval(shading.wo, wi);
        if (max_component(eval.total()) <= 0.0f) continue;
        shadows[count] = light_shadow_ray(shading.spawn_origin(ls.wi), ls.wi, ls.distance);
        ::new (&pending_[count].value) PendingDirect{ls, wi, eval};
        ++count;
    }
    return count;
}

void PathIntegrator::add_direct(int k) {
    const Shading& shading = shading_.value;
    const PendingDirect& pending = pending_[k].value;
    const LightSample& ls = pending.light;
    const bool mis = !ls.delta && vertex_field() == nullptr;
    const float weight =
        mis ? power_heuristic(ls.pdf, shading.bsdf.pdf(shading.wo, pending.wi)) : 1.0f;
    const vec3 scale = throughput_ * ls.radiance * (weight / ls.pdf);
    if (vertex_ == 0) {  // direct light at the first surface, split by the lobes it lit
        for (int c = 0; c < kLobeClassCount; ++c)
            add_light(pending.eval.by_class[c] * scale, c, true);
        return;
    }
    add_split(pending.eval.total() * scale, false);
}

// Indirect light from the field through the field lobes (see the header).
void PathIntegrator::add_field(const Shading& shading) {
    if (field_->is_zero()) return;  // every term below would be zero
    FieldLobes lobes;
    lobes.diffuse = shading.bsdf.field_diffuse(shading.wo);
    lobes.glossy_count = shading.bsdf.field_glossy_lobes(shading.wo, lobes.glossy);
    if (max_component(lobes.diffuse) <= 0.0f && lobes.glossy_count == 0) return;
    const vec3 wo = shading.frame.to_world(shading.wo);
    if (vertex_ == 0 && shared_lookup_ != nullptr) {
        add_field_light(*shared_lookup_, lobes, shading.frame.z, wo, shared_irradiance_);
        return;
    }
    // The lookup's result binds to the parameter directly: no copy of its SH.
    add_field_light(field_->view_lookup(shading.position, shading.frame.z, wo), lobes,
                    shading.frame.z, wo);
}

void PathIntegrator::add_field_light(const FieldLookup& field, const FieldLobes& lobes,
                                     const vec3& n, const vec3& wo, IrradianceMemo* irradiance) {
    const vec3 e = irradiance != nullptr ? irradiance->irradiance(field, n) : field.irradiance(n);
    vec3 by_class[2] = {lobes.diffuse * e * kInvPi, vec3(0.0f)};
    for (int i = 0; i < lobes.glossy_count; ++i)
        by_class[1] += lobes.glossy[i].albedo * field.glossy(n, wo, lobes.glossy[i].roughness);
    if (vertex_ == 0) {
        for (int c = 0; c < 2; ++c) add_light(throughput_ * by_class[c], c, false);
        return;
    }
    add_split(throughput_ * (by_class[0] + by_class[1]), false);
}

bool PathIntegrator::first_field_query(vec3* position, vec3* normal, vec3* wo) const {
    if (vertex_field() == nullptr || field_->is_zero() || vertex_ != 0) return false;
    *position = shading_.value.position;
    *normal = shading_.value.frame.z;
    *wo = shading_.value.frame.to_world(shading_.value.wo);
    return true;
}

// Samples the BSDF, updates throughput, bounce counts and MIS state; false ends the path.
bool PathIntegrator::scatter(const Shading& shading, Ray* ray) {
    BsdfSample bs;
    float u_lobe = rng_.next_float();
    vec2 u = rng_.next_vec2();
    if (vertex_ == 0 && first_bsdf_sample_) {
        u_lobe = first_bsdf_sample_->u_select;
        u = first_bsdf_sample_->u;
    }
    const bool field_vertex = vertex_field() != nullptr;
    const bool sampled = field_vertex ? shading.bsdf.sample_traced(shading.wo, u_lobe, u, &bs)
                                      : shading.bsdf.sample(shading.wo, u_lobe, u, &bs);
    if (!sampled) return false;
    const vec3 wi = shading.frame.to_world(bs.wi);
    const bool geometric_above = glm::dot(wi, shading.geometric_normal) > 0.0f;
    if (geometric_above != (bs.wi.z > 0.0f)) return false;
    if (vertex_ == 0) {
        // Cycles' pass_diffuse_weight / pass_glossy_weight: the classes' shares of the BSDF.
        const vec3 total = bs.eval.total();
        const float sum = total.x + total.y + total.z;
        for (int c = 0; c < kLobeClassCount; ++c) {
            const vec3 part = bs.eval.by_class[c];
            class_fraction_[c] = sum > 0.0f ? (part.x + part.y + part.z) / sum : 0.0f;
        }
    }
    ++bounces_[int(bs.lobe_class)];
    throughput_ *= bs.weight;
    last_delta_ = bs.delta || field_vertex;  // a field vertex's NEE skips traced lobes
    if (!bs.delta) {
        ++smooth_bounces_;
        // Cycles' min_ray_pdf takes the whole BSDF's pdf, which a field vertex's sample (of
        // the traced lobes alone) does not give.
        if (settings_.filter_glossy > 0.0f)
            min_ray_pdf_ = std::min(
                min_ray_pdf_, field_vertex ? shading.bsdf.pdf(shading.wo, bs.wi) : bs.pdf);
    }
    last_pdf_ = bs.pdf;
    last_normal_ = shading.frame.z;
    ++vertex_;
    ray->origin = shading.spawn_origin(wi);
    ray->direction = wi;
    ray->tmin = 0.0f;
    ray->tmax = kInfinity;
    return max_component(throughput_) > 0.0f;
}

}  // namespace shgi
