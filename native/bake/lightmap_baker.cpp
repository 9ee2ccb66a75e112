#include "bake/lightmap_baker.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include "bake/lightmap_filter.h"
#include "render/bump_irradiance.h"
#include "render/interleave_window.h"
#include "render/light_sampler.h"
#include "render/path_integrator.h"
#include "render/shading.h"
#include "sh/sh_irradiance.h"
#include "sh/sh_projection.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/parallel.h"
#include "util/rng.h"
#include "util/sampling.h"

namespace shgi {

namespace {

constexpr uint32_t kMaxSamples = 1u << 20;
// Mixed into the seed with the instance id, so that objects baked with one seed do not share
// their noise pattern (texel indices restart at 0 on every object).
constexpr uint64_t kInstanceSeedMix = 0x9e3779b97f4a7c15ull;
// A texel's samples between cancel polls: a few milliseconds of paths with a bounce or two.
constexpr uint32_t kSamplesPerCancelPoll = 256;
// Interleaved fields: a neighbour texel joins the filter only within this many texel sizes of
// the texel's plane (with the normal test, it lies on the same surface).
constexpr float kInterleavePlaneTexels = 1.0f;

const char* const kContentNames[] = {"INDIRECT", "DIRECT", "DIRECT_INDIRECT", "FULL"};

bool wants_direct(LightmapContent content) { return content != LightmapContent::Indirect; }
bool wants_indirect(LightmapContent content) { return content != LightmapContent::Direct; }

// What the path continues with after the texel's own (diffuse) bounce: every limit one lower,
// as the PathIntegrator counts the first surface it meets as its first bounce.
PathTracerSettings continuation_settings(const LightmapSettings& settings) {
    PathTracerSettings path;
    path.max_bounces = settings.max_bounces - 1;
    path.diffuse_bounces = settings.diffuse_bounces - 1;
    path.glossy_bounces = settings.glossy_bounces;
    path.transmission_bounces = settings.transmission_bounces;
    path.russian_roulette_depth = std::max(0, path.russian_roulette_depth - 1);
    path.roulette_survival = RouletteSurvival::Throughput;  // min(1, T), as before
    path.filter_glossy = settings.filter_glossy;
    return path;  // clamp_indirect applies to the whole continuation (path_radiance), not inside
}

// The texel's surface as Cycles' bake sees it: a camera ray along the shading normal.
struct TexelSurface {
    Frame frame;            // shading frame (z = shading normal, on the front side)
    vec3 geometric_normal;  // front side
    PrincipledBsdf bsdf;
    vec3 wo{0.0f, 0.0f, 1.0f};
    vec3 diffuse_color{0.0f};  // DiffCol
    int color_channel = -1;    // the channel the diffuse response is read from; -1: Lambert
    // Where a normal map bent the shading normal: the diffuse lobe's bump shadowing, whose
    // smooth_normal places the field's lookup (field_lookup_normal, render/bump_irradiance.h).
    bool bumped = false;
    DiffuseBump bump;

    vec3 lookup_normal() const { return bumped ? bump.smooth_normal : frame.z; }

    // f_diffuse |cos| / DiffCol for world direction wi (Lambert: cos / pi).
    float diffuse_response(const vec3& wi) const {
        const vec3 local = frame.to_local(wi);
        if (local.z <= 0.0f) return 0.0f;
        if (color_channel < 0) return local.z * kInvPi;
        const BsdfEval eval = bsdf.eval(wo, local);
        return eval.by_class[0][color_channel] / diffuse_color[color_channel];
    }
};

TexelSurface texel_surface(const Scene& scene, uint32_t instance, const TexelSample& sample) {
    Hit hit;
    hit.instance_id = instance;
    hit.triangle_id = sample.triangle_id;
    hit.barycentrics = sample.barycentrics;
    hit.geometric_normal = sample.geometric_normal;
    hit.t = 1e-3f;
    Ray ray;
    ray.origin = sample.position + 1e-3f * sample.normal;
    ray.direction = -sample.normal;
    const Shading shading = make_shading(scene, scene.surface_point(ray, hit), ray.direction);
    TexelSurface surface{shading.frame, shading.geometric_normal, shading.bsdf, shading.wo};
    surface.diffuse_color = shading.bsdf.class_color(LobeClass::Diffuse);
    surface.bumped = diffuse_bump(shading, &surface.bump);
    const float peak = max_component(surface.diffuse_color);
    if (peak > 0.0f && shading.wo.z > 0.0f)
        surface.color_channel = surface.diffuse_color.x == peak   ? 0
                                : surface.diffuse_color.y == peak ? 1
                                                                  : 2;
    return surface;
}

// a += scale b, at the larger of the two orders (coefficients past an order are zero).
void add_sh(ShRgb& a, const ShRgb& b, float scale) {
    a.order = std::max(a.order, b.order);
    for (int i = 0; i < b.num_coefficients(); ++i) a.coeffs[i] += scale * b.coeffs[i];
}

// Sums of one sample position.
struct PositionSums {
    vec3 value{0.0f};
    ShRgb sh{1};  // at the bake's SH order
    double luminance = 0.0, luminance2 = 0.0;
};

class TexelBaker {
  public:
    TexelBaker(const Scene& scene, const TexelMap& map, const IndirectField* field,
               const LightmapSettings& settings)
        : scene_(scene), map_(map), field_(field), settings_(settings),
          // A field that carries direct light stands in for next-event estimation of it only
          // where the bake reads the field (content with indirect light): a DIRECT bake samples
          // every emitter.
          lights_(scene, WorldSampling::Cosine,
                  field == nullptr || !wants_indirect(settings.content) ||
                      !field->includes_world_direct(),
                  settings.light_splits,
                  field == nullptr || !wants_indirect(settings.content) ||
                      !field->includes_lights_direct()),
          path_settings_(continuation_settings(settings)),
          seed_(settings.seed ^ (kInstanceSeedMix * (uint64_t(map.instance_id) + 1))),
          direct_(wants_direct(settings.content)),
          indirect_(wants_indirect(settings.content) && settings.max_bounces > 0 &&
                    settings.diffuse_bounces > 0),
          gather_(field != nullptr && settings.final_gather),
          interleave_(field != nullptr ? field->interleave() : IndirectField::Interleave{}) {
        if (interleave_.interleaved() && (interleave_.sets_x < 1 || interleave_.sets_y < 1))
            throw Internal("an interleaved field with no sets along an axis");
    }

    // Whether texels read an interleaved field's sets (interleaved_sh) instead of looking the
    // field up at each sample position.
    bool interleaved() const { return interleave_.interleaved() && reads_field(); }

    // The filtered radiance SH of the texels of tile [x0, x1) x [y0, y1), row-major: each texel
    // takes the mean over the sets of each set's nearest texels that lie in its UV chart on its
    // surface (InterleaveWindow, reaching a period into neighbouring tiles), where texel (x, y)
    // holds its own set (x mod sets_x, y mod sets_y) alone, gathered at its sample positions
    // (their weighted mean). A set's gather is made only for the texels a window reads (within
    // half a period, unless an edge cuts the window), once per tile. A texel's value depends only
    // on its neighbourhood, not on the tile or shard it is baked in.
    std::vector<ShRgb> interleaved_sh(uint32_t x0, uint32_t y0, uint32_t x1, uint32_t y1,
                                      const Progress* progress) const {
        const int hx = interleave_.filter ? InterleaveWindow::reach(interleave_.sets_x) : 0;
        const int hy = interleave_.filter ? InterleaveWindow::reach(interleave_.sets_y) : 0;
        const uint32_t ax = uint32_t(std::max(0, int(x0) - hx));
        const uint32_t ay = uint32_t(std::max(0, int(y0) - hy));
        const uint32_t bx = std::min(map_.width, x1 + uint32_t(hx));
        const uint32_t by = std::min(map_.height, y1 + uint32_t(hy));
        const uint32_t w = bx - ax;
        std::vector<TexelGeometry> geometry(size_t(w) * (by - ay));
        for (uint32_t y = ay; y < by; ++y)
            for (uint32_t x = ax; x < bx; ++x) {
                const uint64_t t = map_.texel_index(x, y);
                if (map_.covered(t))
                    geometry[size_t(y - ay) * w + (x - ax)] = texel_geometry(map_, t);
            }
        std::vector<ShRgb> raw(geometry.size(), ShRgb(0));
        std::vector<uint8_t> gathered(geometry.size(), 0);
        // Texel (x, y)'s own set, gathered on first use.
        const auto own_set = [&](uint32_t x, uint32_t y) -> const ShRgb& {
            const size_t i = size_t(y - ay) * w + (x - ax);
            if (gathered[i]) return raw[i];
            throw_if_cancelled(progress);
            const uint64_t t = map_.texel_index(x, y);
            double weight_sum = 0.0;
            for (const TexelSample* s = map_.samples_begin(t); s != map_.samples_end(t); ++s)
                weight_sum += s->weight;
            for (const TexelSample* s = map_.samples_begin(t); s != map_.samples_end(t); ++s)
                add_sh(raw[i],
                       field_->set_radiance_sh(s->ray_origin, s->geometric_normal,
                                               int(x % uint32_t(interleave_.sets_x)),
                                               int(y % uint32_t(interleave_.sets_y))),
                       float(s->weight / weight_sum));
            gathered[i] = 1;
            return raw[i];
        };
        std::vector<ShRgb> out(size_t(x1 - x0) * (y1 - y0), ShRgb(0));
        InterleaveWindow window(interleave_.sets_x, interleave_.sets_y);
        for (uint32_t y = y0; y < y1; ++y)
            for (uint32_t x = x0; x < x1; ++x) {
                const uint64_t t = map_.texel_index(x, y);
                if (!map_.covered(t)) continue;
                const TexelGeometry& gp = geometry[size_t(y - ay) * w + (x - ax)];
                ShRgb& sh = out[size_t(y - y0) * (x1 - x0) + (x - x0)];
                if (!interleave_.filter) {
                    sh = own_set(x, y);
                    continue;
                }
                // The halo is the window's reach, so every tap lies in [ax, bx) x [ay, by).
                window.visit(
                    int(x), int(y), int(map_.width), int(map_.height),
                    [&](int u, int v) {
                        const uint64_t tq = map_.texel_index(uint32_t(u), uint32_t(v));
                        if (!map_.covered(tq) || map_.chart[tq] != map_.chart[t]) return false;
                        const TexelGeometry& gq =
                            geometry[size_t(v - int(ay)) * w + size_t(u - int(ax))];
                        return glm::dot(gq.normal, gp.normal) >= interleave_.normal_threshold &&
                               std::abs(glm::dot(gq.position - gp.position, gp.normal)) <=
                                   kInterleavePlaneTexels * std::max(gp.texel_size, gq.texel_size);
                    },
                    [&](int u, int v, float weight) {
                        add_sh(sh, own_set(uint32_t(u), uint32_t(v)), weight);
                    });
            }
        return out;
    }

    // Polls `progress` every kSamplesPerCancelPoll samples. `field_sh`: the texel's radiance
    // SH from an interleaved field (interleaved_sh), read instead of the field.
    void bake_texel(uint64_t texel, LightmapTexels& out, const Progress* progress,
                    const ShRgb* field_sh = nullptr) const {
        const uint64_t positions = map_.sample_count(texel);
        if (positions == 0) return;
        const uint32_t per_position = uint32_t(std::max<uint64_t>(1, settings_.samples / positions));
        const TexelSample* samples = map_.samples_begin(texel);
        double weight_sum = 0.0;
        for (uint64_t k = 0; k < positions; ++k) weight_sum += samples[k].weight;
        vec3 color(0.0f);
        ShRgb sh(sh_order_);
        double variance = 0.0;
        for (uint64_t k = 0; k < positions; ++k) {
            // The sample's global index in the map names its random streams.
            const PositionSums sums = bake_position(samples[k], map_.sample_offsets[texel] + k,
                                                    per_position, progress, field_sh);
            const float w = float(samples[k].weight / weight_sum);
            const float scale = w / float(per_position);
            color += sums.value * scale;
            sh_add_scaled(sh, sums.sh, scale);
            const double mean = sums.luminance / per_position;
            const double sample_variance =
                per_position > 1
                    ? std::max(0.0, (sums.luminance2 - sums.luminance * mean) / (per_position - 1))
                    : 0.0;
            variance += double(w) * w * sample_variance / per_position;
        }
        float* c = &out.color[3 * texel];
        for (int i = 0; i < 3; ++i) c[i] = color[i];
        out.variance[texel] = float(variance);
        if (settings_.directional) {
            const int coefficients = out.sh_coefficients();
            float* s = &out.sh[size_t(3 * coefficients) * texel];
            for (int j = 0; j < coefficients; ++j)
                for (int i = 0; i < 3; ++i) s[3 * j + i] = sh[j][i];
        }
        out.baked[texel] = 1;
    }

  private:
    bool reads_field() const {
        return field_ != nullptr && indirect_ && !gather_ && !field_->is_zero();
    }

    PositionSums bake_position(const TexelSample& sample, uint64_t stream, uint32_t count,
                               const Progress* progress, const ShRgb* texel_sh) const {
        const TexelSurface surface = texel_surface(scene_, map_.instance_id, sample);
        const vec3 n = surface.frame.z;
        const vec3 color_scale =
            settings_.content == LightmapContent::Full ? surface.diffuse_color : vec3(1.0f);
        PositionSums sums;
        sums.sh = ShRgb(sh_order_);
        // The field's light is the same for every sample of the position.
        vec3 field_value(0.0f);
        ShRgb field_sh(sh_order_);
        if (reads_field()) {
            FieldLookup lookup;
            if (texel_sh != nullptr)
                lookup.radiance = *texel_sh;
            else
                lookup = field_->lookup(sample.ray_origin, surface.lookup_normal());
            // About the bent normal with its bump shadowing, as the preview's field light.
            const vec3 irradiance =
                surface.bumped ? lookup.irradiance(n, surface.bump) : lookup.irradiance(n);
            const float response = surface.color_channel < 0
                                       ? 1.0f
                                       : surface.bsdf.field_diffuse(surface.wo)[surface.color_channel] /
                                             surface.diffuse_color[surface.color_channel];
            field_value = irradiance * (kInvPi * response);
            if (settings_.directional) {
                const int carried =
                    std::min(field_sh.num_coefficients(), lookup.radiance.num_coefficients());
                for (int j = 0; j < carried; ++j) field_sh[j] = lookup.radiance[j];
                // Irradiance the SH does not carry (caustics): as uniform radiance E / pi over the
                // upper hemisphere, whose L1 SH is (E / pi) (2 pi Y00, pi k1 n) (its band 2 is
                // zero: the integral of P2 over a hemisphere vanishes).
                const vec3 extra = lookup.extra_irradiance * kInvPi;
                field_sh[0] += extra * (kTwoPi * 0.28209479177387814f);
                const float k1 = kPi * 0.4886025119029199f;
                field_sh[1] += extra * (k1 * n.y);
                field_sh[2] += extra * (k1 * n.z);
                field_sh[3] += extra * (k1 * n.x);
            }
        }
        const bool trace_hemisphere = (field_ == nullptr || gather_) && (indirect_ || direct_);
        const Camera camera;  // the continuation's Depth pass is not read
        for (uint32_t i = 0; i < count; ++i) {
            if (i % kSamplesPerCancelPoll == kSamplesPerCancelPoll - 1) throw_if_cancelled(progress);
            const PixelSample ps = pixel_sample(seed_, stream, i);
            Pcg32 rng(seed_, stream_id(i, stream));
            vec3 value = field_value;
            ShRgb* sh = settings_.directional ? &sums.sh : nullptr;
            if (sh) sh_add_scaled(*sh, field_sh, 1.0f);
            // Hemisphere direction (needed first: NEE's MIS weight uses its pdf).
            const auto hemisphere_pdf = [&](float cos_theta) {
                return settings_.directional ? sample_uniform_hemisphere_pdf()
                                             : sample_cosine_hemisphere_pdf(cos_theta);
            };
            if (direct_) {
                // One emitter from each node of the light tree's cut (light_splits), a shadow
                // ray each; each sample's pdf is that of its own choice (PathIntegrator's NEE).
                LightSample samples[kMaxLightSplits];
                const int sampled =
                    lights_.sample_split(sample.ray_origin, n, ps.u_select, ps.u_light, samples);
                for (int k = 0; k < sampled; ++k) {
                    const LightSample& ls = samples[k];
                    if (!(glm::dot(ls.wi, surface.geometric_normal) > 0.0f)) continue;
                    const float cos_theta = glm::dot(ls.wi, n);
                    if (!(cos_theta > 0.0f)) continue;
                    if (scene_.occluded(light_shadow_ray(sample.ray_origin, ls.wi, ls.distance)))
                        continue;
                    const float mis = ls.delta || !trace_hemisphere
                                          ? 1.0f
                                          : power_heuristic(ls.pdf, hemisphere_pdf(cos_theta));
                    const vec3 incident = ls.radiance * (mis / ls.pdf);
                    value += incident * surface.diffuse_response(ls.wi);
                    if (sh) sh_add_sample(*sh, ls.wi, incident);
                }
            }
            if (trace_hemisphere) {
                const vec3 local = settings_.directional ? sample_uniform_hemisphere(ps.jitter)
                                                         : sample_cosine_hemisphere(ps.jitter);
                const float pdf = hemisphere_pdf(local.z);
                const vec3 wi = glm::normalize(surface.frame.to_world(local));
                if (pdf > 0.0f && glm::dot(wi, surface.geometric_normal) > 0.0f) {
                    Ray ray;
                    ray.origin = sample.ray_origin;
                    ray.direction = wi;
                    const Hit hit = scene_.intersect(ray);
                    vec3 radiance(0.0f);
                    if (direct_) radiance += emission(ray, hit, n, pdf);
                    if (indirect_) radiance += continuation(ray, hit, pdf, camera, rng);
                    const vec3 incident = radiance / pdf;
                    value += incident * surface.diffuse_response(wi);
                    if (sh) sh_add_sample(*sh, wi, incident);
                }
            }
            if (!is_finite(value)) value = vec3(0.0f);
            value *= color_scale;
            sums.value += value;
            const double y = luminance(value);
            sums.luminance += y;
            sums.luminance2 += y * y;
        }
        if (settings_.directional)
            for (int j = 0; j < sums.sh.num_coefficients(); ++j) {
                sums.sh[j] *= color_scale;
                if (!is_finite(sums.sh[j])) sums.sh[j] = vec3(0.0f);
            }
        return sums;
    }

    // Emitters the hemisphere ray meets first, weighted against next-event estimation.
    vec3 emission(const Ray& ray, const Hit& hit, const vec3& n, float pdf) const {
        vec3 sum(0.0f);
        lights_.for_each_emission(ray.origin, n, ray.direction, hit, false,
                                  [&](const EmissionHit& e, bool) {
                                      sum += e.radiance * power_heuristic(pdf, e.light_pdf);
                                  });
        return sum;
    }

    // Light that scattered at least once and arrives along the ray: the reference path from
    // its first hit (with final gather, a field vertex there), less what that path's first
    // segment sees directly. `pdf`: the hemisphere ray's, the path's first bounce (Filter Glossy).
    vec3 continuation(const Ray& ray, const Hit& hit, float pdf, const Camera& camera,
                      Pcg32& rng) const {
        if (!hit.valid()) return vec3(0.0f);
        PassValues values;
        PathIntegrator path(scene_, camera, lights_, path_settings_, gather_ ? field_ : nullptr,
                            rng, values);
        path.set_first_ray_pdf(pdf);
        path.trace(ray, hit);
        return path_radiance(values, false, settings_.clamp_indirect);
    }

    const Scene& scene_;
    const TexelMap& map_;
    const IndirectField* field_;
    const LightmapSettings& settings_;
    const int sh_order_ = settings_.directional ? settings_.sh_order : 1;
    LightSampler lights_;
    PathTracerSettings path_settings_;
    uint64_t seed_;
    bool direct_, indirect_;
    bool gather_;  // final gather: the hemisphere ray reads the field where it lands
    IndirectField::Interleave interleave_;
};

uint32_t tiles_along(uint32_t texels, uint32_t tile_size) {
    return (texels + tile_size - 1) / tile_size;
}

}  // namespace

const char* lightmap_content_name(LightmapContent content) {
    return kContentNames[size_t(content)];
}

LightmapContent lightmap_content_from_name(const std::string& name) {
    for (size_t i = 0; i < std::size(kContentNames); ++i)
        if (name == kContentNames[i]) return LightmapContent(i);
    throw InvalidArgument(format_message("lightmap content '", name,
                                         "' is not one of INDIRECT, DIRECT, DIRECT_INDIRECT, FULL"));
}

void validate_lightmap_settings(const LightmapSettings& s) {
    if (s.sh_order < 1 || s.sh_order > kLightmapMaxShOrder)
        throw InvalidArgument(format_message("LightmapSettings.sh_order = ", s.sh_order,
                                             ": use 1 (L1, 4 coefficients) or 2 (L2, 9)"));
    if (s.samples < 1 || s.samples > kMaxSamples)
        throw InvalidArgument(format_message("LightmapSettings.samples = ", s.samples,
                                             ": use 1 .. ", kMaxSamples));
    if (s.tile_size < 4 || s.tile_size > 1024)
        throw InvalidArgument(format_message("LightmapSettings.tile_size = ", s.tile_size,
                                             ": use 4 .. 1024 texels"));
    const std::pair<const char*, int> limits[] = {{"max_bounces", s.max_bounces},
                                                   {"diffuse_bounces", s.diffuse_bounces},
                                                   {"glossy_bounces", s.glossy_bounces},
                                                   {"transmission_bounces", s.transmission_bounces}};
    for (const auto& [name, value] : limits)
        if (value < 0 || value > 1024)
            throw InvalidArgument(
                format_message("LightmapSettings.", name, " = ", value, ": use 0 .. 1024"));
    if (!(s.clamp_indirect >= 0.0f) || !std::isfinite(s.clamp_indirect))
        throw InvalidArgument(format_message("LightmapSettings.clamp_indirect = ",
                                             s.clamp_indirect, ": use 0 (off) or a positive value"));
    if (!(s.filter_glossy >= 0.0f) || !std::isfinite(s.filter_glossy))
        throw InvalidArgument(format_message("LightmapSettings.filter_glossy = ",
                                             s.filter_glossy, ": use 0 (off) or a positive value"));
    if (size_t(s.content) >= std::size(kContentNames))
        throw InvalidArgument("LightmapSettings.content is not a LightmapContent");
    if (s.light_splits < 1 || s.light_splits > kMaxLightSplits)
        throw InvalidArgument(format_message("LightmapSettings.light_splits = ", s.light_splits,
                                             ": use 1 .. ", kMaxLightSplits));
}

uint32_t lightmap_tile_count(uint32_t width, uint32_t height, uint32_t tile_size) {
    if (tile_size == 0) throw InvalidArgument("lightmap tile_size must be positive");
    // Within the rasterizer's sides, the count fits 32 bits (at most 16384^2 one-texel tiles).
    check_lightmap_side("lightmap width", width);
    check_lightmap_side("lightmap height", height);
    return tiles_along(width, tile_size) * tiles_along(height, tile_size);
}

std::vector<uint32_t> lightmap_shard_tiles(uint32_t width, uint32_t height, uint32_t tile_size,
                                           uint32_t shard, uint32_t shards) {
    if (shards == 0 || shard >= shards)
        throw InvalidArgument(format_message("shard ", shard, "/", shards,
                                             ": use i/N with N >= 1 and 0 <= i < N"));
    std::vector<uint32_t> tiles;
    const uint32_t count = lightmap_tile_count(width, height, tile_size);
    for (uint32_t i = shard; i < count; i += shards) tiles.push_back(i);
    return tiles;
}

std::vector<uint32_t> lightmap_read_tiles(uint32_t width, uint32_t height, uint32_t tile_size,
                                          const std::vector<uint32_t>& tiles,
                                          const IndirectField* field) {
    const uint32_t count = lightmap_tile_count(width, height, tile_size);
    for (uint32_t tile : tiles)
        if (tile >= count)
            throw InvalidArgument(format_message("lightmap_read_tiles: tile ", tile, " but a ",
                                                 width, " x ", height, " lightmap has ", count,
                                                 " tiles of ", tile_size, " texels"));
    const PinnedField pinned(field);
    const IndirectField::Interleave pattern =
        pinned.get() != nullptr ? pinned.get()->interleave() : IndirectField::Interleave{};
    if (tiles.empty() || !pattern.interleaved() || !pattern.filter) return tiles;
    const auto reach = [&](int sets) {
        return int(tiles_along(uint32_t(InterleaveWindow::reach(sets)), tile_size));
    };
    const int reach_x = reach(pattern.sets_x), reach_y = reach(pattern.sets_y);
    const int tiles_x = int(tiles_along(width, tile_size));
    const int tiles_y = int(tiles_along(height, tile_size));
    std::vector<uint8_t> read(count, 0);
    for (uint32_t tile : tiles) {
        const int tx = int(tile) % tiles_x, ty = int(tile) / tiles_x;
        for (int y = std::max(0, ty - reach_y); y <= std::min(tiles_y - 1, ty + reach_y); ++y)
            for (int x = std::max(0, tx - reach_x); x <= std::min(tiles_x - 1, tx + reach_x); ++x)
                read[size_t(y) * size_t(tiles_x) + size_t(x)] = 1;
    }
    std::vector<uint32_t> out;
    for (uint32_t i = 0; i < count; ++i)
        if (read[i]) out.push_back(i);
    return out;
}

LightmapTexels bake_lightmap(const Scene& scene, const TexelMap& map, const IndirectField* field,
                             const LightmapSettings& settings, const std::vector<uint32_t>& tiles,
                             Progress* progress) {
    validate_lightmap_settings(settings);
    if (!scene.committed()) throw InvalidArgument("bake_lightmap: commit the scene first");
    check_texel_map(scene, map, "bake_lightmap");
    if (map.sample_offsets.size() != map.texel_count() + 1)
        throw InvalidArgument("bake_lightmap: the texel map is incomplete");
    const uint32_t tile_count = lightmap_tile_count(map.width, map.height, settings.tile_size);
    std::vector<uint32_t> work = tiles;
    if (work.empty())
        for (uint32_t i = 0; i < tile_count; ++i) work.push_back(i);
    for (uint32_t tile : work)
        if (tile >= tile_count)
            throw InvalidArgument(format_message("bake_lightmap: tile ", tile, " but a ", map.width,
                                                 " x ", map.height, " lightmap has ", tile_count,
                                                 " tiles of ", settings.tile_size, " texels"));

    LightmapTexels out;
    out.width = map.width;
    out.height = map.height;
    out.directional = settings.directional;
    out.sh_order = settings.directional ? settings.sh_order : 1;
    const uint64_t texel_bytes = 3 * sizeof(float) + sizeof(float) + sizeof(uint8_t) +
                                 uint64_t(out.sh_floats()) * sizeof(float);
    require_memory(saturating_mul(map.texel_count(), texel_bytes),
                   format_message("bake_lightmap: a ", map.width, " x ", map.height, " lightmap",
                                  settings.directional ? " (LightmapSettings.directional)" : "",
                                  " at ", texel_bytes, " bytes per texel"),
                   "rasterize a lower resolution (TexelRasterSettings.width, height) or bake "
                   "in tiles");
    out.color.assign(3 * map.texel_count(), 0.0f);
    if (settings.directional) out.sh.assign(size_t(out.sh_floats()) * map.texel_count(), 0.0f);
    out.variance.assign(map.texel_count(), 0.0f);
    out.baked.assign(map.texel_count(), 0);

    const PinnedField pinned(field);  // one state of the field for the whole bake
    // An INDIRECT bake over a field that carries direct light (INSTANT_GI's filter_direct)
    // reads the field without it, where the field can separate the two.
    std::shared_ptr<const IndirectField> indirect_only;
    if (pinned.get() != nullptr && !wants_direct(settings.content) &&
        (pinned.get()->includes_world_direct() || pinned.get()->includes_lights_direct()))
        indirect_only = pinned.get()->without_direct();
    const TexelBaker baker(scene, map, indirect_only ? indirect_only.get() : pinned.get(),
                           settings);
    const uint32_t tiles_x = tiles_along(map.width, settings.tile_size);
    std::atomic<uint64_t> done{0};
    if (progress) progress->begin_stage("baking lightmap");
    parallel_for(
        0, work.size(), 1,
        [&](uint64_t begin, uint64_t end) {
            for (uint64_t w = begin; w < end; ++w) {
                const uint32_t tile = work[w];
                const uint32_t x0 = (tile % tiles_x) * settings.tile_size;
                const uint32_t y0 = (tile / tiles_x) * settings.tile_size;
                const uint32_t x1 = std::min(map.width, x0 + settings.tile_size);
                const uint32_t y1 = std::min(map.height, y0 + settings.tile_size);
                // Polled per texel, and within a texel every kSamplesPerCancelPoll samples: a
                // row of a tile at thousands of samples per texel, or one texel at a million,
                // takes longer than the 0.2 s a cancel may take.
                const std::vector<ShRgb> field_sh =
                    baker.interleaved() ? baker.interleaved_sh(x0, y0, x1, y1, progress)
                                        : std::vector<ShRgb>{};
                for (uint32_t y = y0; y < y1; ++y)
                    for (uint32_t x = x0; x < x1; ++x) {
                        throw_if_cancelled(progress);
                        baker.bake_texel(map.texel_index(x, y), out, progress,
                                         field_sh.empty()
                                             ? nullptr
                                             : &field_sh[size_t(y - y0) * (x1 - x0) + (x - x0)]);
                    }
                const uint64_t finished = done.fetch_add(1) + 1;
                if (progress) progress->report(finished, work.size());
            }
        },
        progress);
    return out;
}

void merge_lightmap(LightmapTexels& into, const LightmapTexels& part) {
    if (into.width != part.width || into.height != part.height ||
        into.directional != part.directional ||
        (into.directional && into.sh_order != part.sh_order))
        throw InvalidArgument(format_message(
            "merge_lightmap: a ", part.width, " x ", part.height,
            part.directional ? (part.sh_order == 2 ? " L2 directional" : " directional") : "",
            " part does not fit a ", into.width, " x ", into.height,
            into.directional ? (into.sh_order == 2 ? " L2 directional" : " directional") : "",
            " lightmap"));
    for (uint64_t t = 0; t < part.texel_count(); ++t) {
        if (!part.baked[t]) continue;
        if (into.baked[t])
            throw InvalidArgument(format_message("merge_lightmap: texel ", t % part.width, ", ",
                                                 t / part.width,
                                                 " was baked twice; shards must not overlap"));
        into.baked[t] = 1;
        std::copy_n(&part.color[3 * t], 3, &into.color[3 * t]);
        into.variance[t] = part.variance[t];
        const size_t floats = size_t(part.sh_floats());
        if (part.directional) std::copy_n(&part.sh[floats * t], floats, &into.sh[floats * t]);
    }
}

}  // namespace shgi
