#include "bake/lightmap_filter.h"

#include <cmath>

#include "util/error.h"
#include "util/math.h"
#include "util/parallel.h"

namespace shgi {

namespace {

constexpr uint64_t kRowsPerChunk = 8;
constexpr float kKernel[5] = {1.0f / 16.0f, 1.0f / 4.0f, 3.0f / 8.0f, 1.0f / 4.0f, 1.0f / 16.0f};
// Keeps the luminance weight finite where the variance is 0 (a noise-free texel).
constexpr float kLuminanceEpsilon = 1e-4f;

}  // namespace

TexelGeometry texel_geometry(const TexelMap& map, uint64_t texel) {
    TexelGeometry g;
    double weight = 0.0;
    vec3 position(0.0f), normal(0.0f);
    float texel_size = 0.0f;
    for (const TexelSample* s = map.samples_begin(texel); s != map.samples_end(texel); ++s) {
        position += s->position * s->weight;
        normal += s->normal * s->weight;
        texel_size += s->texel_size * s->weight;
        weight += s->weight;
    }
    if (weight > 0.0) {
        g.position = position / float(weight);
        g.texel_size = texel_size / float(weight);
        const float length = glm::length(normal);
        if (length > 0.0f) g.normal = normal / length;
    }
    return g;
}

std::vector<TexelGeometry> texel_geometry(const TexelMap& map) {
    std::vector<TexelGeometry> out(map.texel_count());
    for (uint64_t t = 0; t < map.texel_count(); ++t) out[t] = texel_geometry(map, t);
    return out;
}

void validate_lightmap_filter_settings(const LightmapFilterSettings& s) {
    if (s.iterations > 10)
        throw InvalidArgument(format_message("LightmapFilterSettings.iterations = ", s.iterations,
                                             ": use 0 (off) .. 10"));
    const std::pair<const char*, float> positive[] = {{"normal_power", s.normal_power},
                                                      {"position_sigma", s.position_sigma},
                                                      {"luminance_sigma", s.luminance_sigma}};
    for (const auto& [name, value] : positive)
        if (!(value > 0.0f) || !std::isfinite(value))
            throw InvalidArgument(format_message("LightmapFilterSettings.", name, " = ", value,
                                                 ": use a positive value"));
}

void filter_lightmap(const TexelMap& map, LightmapTexels& texels,
                     const LightmapFilterSettings& settings, Progress* progress) {
    validate_lightmap_filter_settings(settings);
    if (texels.width != map.width || texels.height != map.height ||
        map.chart.size() != map.texel_count())
        throw InvalidArgument(format_message("filter_lightmap: a ", texels.width, " x ",
                                             texels.height, " lightmap does not fit its ",
                                             map.width, " x ", map.height, " texel map"));
    if (settings.iterations == 0) return;
    if (progress) progress->begin_stage("filtering lightmap");
    const std::vector<TexelGeometry> geometry = texel_geometry(map);
    const int sh_floats = texels.sh_floats();
    const int w = int(texels.width), h = int(texels.height);
    for (uint32_t pass = 0; pass < settings.iterations; ++pass) {
        const int step = 1 << pass;
        const LightmapTexels in = texels;  // Jacobi: read the previous pass only
        parallel_for(0, uint64_t(h), kRowsPerChunk, [&](uint64_t begin, uint64_t end) {
            for (int y = int(begin); y < int(end); ++y)
                for (int x = 0; x < w; ++x) {
                    const uint64_t p = uint64_t(y) * w + x;
                    if (!in.baked[p]) continue;
                    const TexelGeometry& gp = geometry[p];
                    const float lp = luminance(vec3(in.color[3 * p], in.color[3 * p + 1],
                                                    in.color[3 * p + 2]));
                    const float luminance_scale =
                        settings.luminance_sigma * std::sqrt(in.variance[p]) + kLuminanceEpsilon;
                    const float position_scale =
                        settings.position_sigma * std::max(gp.texel_size, 1e-6f);
                    double weight_sum = 0.0, variance = 0.0;
                    double color[3] = {0.0, 0.0, 0.0};
                    double sh[kLightmapMaxShFloats] = {};
                    for (int dy = -2; dy <= 2; ++dy) {
                        const int qy = y + dy * step;
                        if (qy < 0 || qy >= h) continue;
                        for (int dx = -2; dx <= 2; ++dx) {
                            const int qx = x + dx * step;
                            if (qx < 0 || qx >= w) continue;
                            const uint64_t q = uint64_t(qy) * w + qx;
                            if (!in.baked[q] || map.chart[q] != map.chart[p]) continue;
                            const TexelGeometry& gq = geometry[q];
                            const float lq = luminance(vec3(in.color[3 * q], in.color[3 * q + 1],
                                                            in.color[3 * q + 2]));
                            const float plane =
                                std::abs(glm::dot(gq.position - gp.position, gp.normal));
                            const float weight =
                                kKernel[dx + 2] * kKernel[dy + 2] *
                                std::pow(std::max(0.0f, glm::dot(gp.normal, gq.normal)),
                                         settings.normal_power) *
                                std::exp(-plane / position_scale -
                                         std::abs(lq - lp) / luminance_scale);
                            if (!(weight > 0.0f)) continue;
                            weight_sum += weight;
                            variance += double(weight) * weight * in.variance[q];
                            for (int c = 0; c < 3; ++c) color[c] += weight * in.color[3 * q + c];
                            for (int c = 0; c < sh_floats; ++c)
                                sh[c] += weight * in.sh[size_t(sh_floats) * q + c];
                        }
                    }
                    // The centre texel always counts (weight h(0)^2 > 0).
                    for (int c = 0; c < 3; ++c) texels.color[3 * p + c] = float(color[c] / weight_sum);
                    for (int c = 0; c < sh_floats; ++c)
                        texels.sh[size_t(sh_floats) * p + c] = float(sh[c] / weight_sum);
                    texels.variance[p] = float(variance / (weight_sum * weight_sum));
                }
        }, progress);
        if (progress) progress->report(pass + 1, settings.iterations);
    }
}

std::vector<uint8_t> dilate_lightmap(LightmapTexels& texels, const DilationSettings& settings,
                                     Progress* progress) {
    const uint64_t n = texels.texel_count();
    const int sh_floats = texels.sh_floats();
    const uint32_t channels = 3 + sh_floats + 1;
    std::vector<float> values(n * channels);
    for (uint64_t t = 0; t < n; ++t) {
        float* v = &values[t * channels];
        for (int c = 0; c < 3; ++c) v[c] = texels.color[3 * t + c];
        for (int c = 0; c < sh_floats; ++c) v[3 + c] = texels.sh[size_t(sh_floats) * t + c];
        v[3 + sh_floats] = texels.variance[t];
    }
    std::vector<uint8_t> filled = texels.baked;
    dilate(texels.width, texels.height, channels, values, filled, settings, progress);
    for (uint64_t t = 0; t < n; ++t) {
        const float* v = &values[t * channels];
        for (int c = 0; c < 3; ++c) texels.color[3 * t + c] = v[c];
        for (int c = 0; c < sh_floats; ++c) texels.sh[size_t(sh_floats) * t + c] = v[3 + c];
        texels.variance[t] = v[3 + sh_floats];
    }
    return filled;
}

}  // namespace shgi
