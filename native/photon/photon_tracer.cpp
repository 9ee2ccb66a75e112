#include "photon/photon_tracer.h"

#include <algorithm>
#include <cmath>

#include "photon/photon_emitter.h"
#include "render/shading.h"
#include "util/error.h"
#include "util/parallel.h"
#include "util/rng.h"

namespace shgi {
namespace {

// Upper bound on photons per pass: stream_id(pass, index) keeps streams distinct below 2^40.
constexpr uint64_t kMaxPhotonsPerPass = uint64_t(1) << 40;
// Photons per chunk of work: fixed, so chunk boundaries (and the order in which the chunks'
// photons are concatenated) never depend on the thread count; ~10^4-10^5 rays, a few ms, so a
// cancel is noticed quickly.
constexpr uint64_t kPhotonsPerChunk = 4096;

// What one chunk of photons produced, merged in chunk order.
struct ChunkResult {
    std::vector<Photon> global;
    std::vector<Photon> caustic;
    uint64_t bounces = 0;
};

// Follows one photon from its emitter until it is absorbed, leaves the scene or reaches
// max_bounces scatterings, storing it at every surface after the first that has a non-Dirac lobe.
class PhotonPath {
  public:
    PhotonPath(const Scene& scene, const PhotonTracerSettings& settings, Pcg32& rng,
               ChunkResult& out)
        : scene_(scene), settings_(settings), rng_(rng), out_(out) {}

    void trace(const EmittedPhoton& emitted);

  private:
    void store(const Shading& shading, const Ray& ray);
    bool scatter(const Shading& shading, const Material& material, Ray* ray);

    const Scene& scene_;
    const PhotonTracerSettings& settings_;
    Pcg32& rng_;
    ChunkResult& out_;

    vec3 power_{0.0f};
    int scatterings_ = 0;
    bool specular_path_ = true;  // every scattering so far was specular
    bool from_world_ = false;
};

void PhotonPath::trace(const EmittedPhoton& emitted) {
    power_ = emitted.power;
    from_world_ = emitted.from_world;
    Ray ray = emitted.ray;
    for (;;) {
        const Hit hit = scene_.intersect(ray);
        ++out_.bounces;
        if (!hit.valid()) return;
        const SurfacePoint sp = scene_.surface_point(ray, hit);
        const Shading shading = make_shading(scene_, sp, ray.direction);
        // The first hit is direct light, which every consumer computes exactly.
        const bool direct = scatterings_ == 0 && !(from_world_ && settings_.store_world_direct);
        if (!direct && shading.bsdf.has_smooth_lobes()) store(shading, ray);
        if (scatterings_ >= settings_.max_bounces) return;
        if (!scatter(shading, scene_.materials()[sp.material_id], &ray)) return;
    }
}

void PhotonPath::store(const Shading& shading, const Ray& ray) {
    Photon photon;
    photon.position = shading.position;
    photon.power = power_;
    photon.normal = shading.geometric_normal;  // already flipped to the arrival side
    photon.direction = -ray.direction;
    // Only specular scatterings since emission: a caustic path L S+ D.
    (specular_path_ ? out_.caustic : out_.global).push_back(photon);
}

// Samples the BSDF towards the photon's next direction (wo = towards where it came from, which
// the BSDF's reciprocity allows), applies Russian roulette and moves the ray. False ends the path.
bool PhotonPath::scatter(const Shading& shading, const Material& material, Ray* ray) {
    BsdfSample bs;
    const float u_lobe = rng_.next_float();
    const vec2 u = rng_.next_vec2();
    if (!shading.bsdf.sample(shading.wo, u_lobe, u, &bs)) return false;
    const vec3 wi = glm::normalize(shading.frame.to_world(bs.wi));
    if (!is_finite(wi)) return false;
    const bool geometric_above = glm::dot(wi, shading.geometric_normal) > 0.0f;
    if (geometric_above != (bs.wi.z > 0.0f)) return false;  // shading/geometric normals disagree
    // PrincipledBsdf gives every glossy and refraction lobe the material's roughness.
    const bool specular = bs.delta || (bs.lobe_class != LobeClass::Diffuse &&
                                       material.roughness <= settings_.specular_roughness);
    specular_path_ = specular_path_ && specular;
    const float survive = std::min(1.0f, max_component(bs.weight));
    if (!(survive > 0.0f) || rng_.next_float() >= survive) return false;
    power_ *= bs.weight / survive;
    if (!is_finite(power_) || !(max_component(power_) > 0.0f)) return false;
    ++scatterings_;
    ray->origin = shading.spawn_origin(wi);
    ray->direction = wi;
    ray->tmin = 0.0f;
    ray->tmax = kInfinity;
    return true;
}

// Photons [begin, end) of the pass, each on its own RNG stream.
ChunkResult trace_chunk(const Scene& scene, const PhotonTracerSettings& settings,
                        const PhotonEmitter& emitter, uint64_t pass, uint64_t begin,
                        uint64_t end) {
    ChunkResult result;
    for (uint64_t i = begin; i < end; ++i) {
        Pcg32 rng(settings.seed, stream_id(pass, i));
        EmittedPhoton emitted;
        if (!emitter.emit(i, settings.photons, rng, &emitted)) continue;
        PhotonPath(scene, settings, rng, result).trace(emitted);
    }
    return result;
}

void append(std::vector<Photon>& to, const std::vector<Photon>& from) {
    to.insert(to.end(), from.begin(), from.end());
}

}  // namespace

void validate_photon_tracer_settings(const PhotonTracerSettings& settings) {
    if (settings.photons == 0 || settings.photons > kMaxPhotonsPerPass)
        throw InvalidArgument(format_message("PhotonTracerSettings.photons is ", settings.photons,
                                             "; it must be in [1, 2^40]"));
    if (settings.max_bounces < 1)
        throw InvalidArgument(format_message("PhotonTracerSettings.max_bounces is ",
                                             settings.max_bounces, "; it must be >= 1"));
    if (!(settings.specular_roughness >= 0.0f && settings.specular_roughness <= 1.0f))
        throw InvalidArgument(format_message("PhotonTracerSettings.specular_roughness is ",
                                             settings.specular_roughness,
                                             "; it must be in [0, 1]"));
}

PhotonMaps trace_photons(const Scene& scene, const PhotonTracerSettings& settings, uint64_t pass,
                         Progress* progress) {
    validate_photon_tracer_settings(settings);
    if (!scene.committed())
        throw InvalidArgument("trace_photons: the scene is not committed; call commit() first");
    throw_if_cancelled(progress);
    PhotonMaps maps;
    const PhotonEmitter emitter(scene);
    if (scene.empty() || emitter.empty()) return maps;
    const uint64_t chunk_count = (settings.photons + kPhotonsPerChunk - 1) / kPhotonsPerChunk;
    std::vector<ChunkResult> chunks(chunk_count);
    // Grain 1 over chunk indices: each body call traces whole chunks, whatever the split.
    parallel_for(
        0, chunk_count, 1,
        [&](uint64_t chunk_begin, uint64_t chunk_end) {
            for (uint64_t c = chunk_begin; c < chunk_end; ++c) {
                const uint64_t begin = c * kPhotonsPerChunk;
                const uint64_t end = std::min(begin + kPhotonsPerChunk, settings.photons);
                chunks[c] = trace_chunk(scene, settings, emitter, pass, begin, end);
            }
        },
        progress);
    size_t global_count = 0, caustic_count = 0;
    for (const ChunkResult& chunk : chunks) {
        global_count += chunk.global.size();
        caustic_count += chunk.caustic.size();
    }
    maps.global.reserve(global_count);
    maps.caustic.reserve(caustic_count);
    for (ChunkResult& chunk : chunks) {
        append(maps.global, chunk.global);
        append(maps.caustic, chunk.caustic);
        maps.bounces += chunk.bounces;
        chunk = ChunkResult{};  // release as we go: the maps may be large
    }
    maps.emitted = settings.photons;
    maps.emitted_power = emitter.total_power();
    return maps;
}

}  // namespace shgi
