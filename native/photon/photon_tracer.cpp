#include "photon/photon_tracer.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "photon/photon_emitter.h"
#include "render/shading.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/parallel.h"
#include "util/rng.h"

namespace shgi {
namespace {

// Upper bound on photons per pass: stream_id(pass, index) keeps streams distinct below 2^40.
constexpr uint64_t kMaxPhotonsPerPass = uint64_t(1) << 40;
// Photons per chunk of work: fixed, so chunk boundaries (and the order in which the chunks'
// photons are concatenated) never depend on the thread count; ~10^4-10^5 rays, a few ms, so a
// cancel is noticed quickly. A chunk is also one wavefront: all its photons are in flight at
// once, so each step hands Embree a ray stream of up to this many rays.
constexpr uint64_t kPhotonsPerChunk = 4096;
// Chunks traced per block: the chunks' results are held until their block is merged into the
// maps, so their records take memory in proportion to a block (~4M photons), not to the whole
// pass (2^40 photons would need 15 GB of records before the first photon).
constexpr uint64_t kChunksPerBlock = 1024;
// Chunks of the first block: a pilot whose stored photons per emitted photon project the whole
// pass's maps, so that a pass far too large for memory is refused within a fraction of a second
// instead of after tens of seconds of tracing. Chunk boundaries (and so the result) do not
// depend on the blocks.
constexpr uint64_t kPilotChunks = 64;
// Stored photons may take at most this share of what the process could allocate when the pass
// began (util/memory.h); past it the trace stops with OutOfMemory instead of the system killing
// the host.
constexpr double kStoredPhotonsMemoryFraction = 0.5;
// Growing the maps holds a map's old and new buffers at once: old, new and the other map's
// buffer may take at most this share.
constexpr double kGrowingPhotonsMemoryFraction = 0.75;

// Photons shaded per stage: shade_all runs each stage (set-up, store, BSDF sample, roulette and
// next ray) over this many photons before the next stage. A photon's shading is one long chain
// of dependent square roots and divisions; a short loop over independent photons lets the
// processor overlap some of the chains of neighbouring photons (~4% faster than photon by
// photon on the bench scenes), and the batch's Shading and BsdfSample records stay in the L1
// cache between stages.
constexpr size_t kShadeBatch = 32;

// Russian roulette by albedo: the probability that a photon arriving at a surface with this
// BSDF scatters on (its power is then divided by it).
float survival_probability(const PrincipledBsdf& bsdf) {
    return std::min(1.0f, max_component(bsdf.albedo_estimate()));
}

// A stored photon and the photon of its chunk (index from the chunk's start) that stored it.
struct StagedPhoton {
    Photon photon;
    uint32_t owner;
};

// What one chunk of photons produced, in the order a photon-by-photon trace stores them: by
// photon index, then by bounce. Merged in chunk order.
struct ChunkResult {
    std::vector<Photon> global;
    std::vector<Photon> caustic;
    std::vector<PhotonFirstHit> first_hits;  // in photon order (made in the first step)
    uint64_t bounces = 0;
};

// One photon in flight: its own RNG stream and the state of its path.
struct PhotonState {
    Pcg32 rng;
    vec3 power{0.0f};
    uint32_t owner = 0;          // index from the chunk's start
    int scatterings = 0;         // counted against max_bounces
    int glossy_scatterings = 0;  // with max_glossy_bounces >= 0: glossy ones, not in the above
    bool specular_path = true;   // every scattering so far was specular
    bool from_world = false;
};

// Traces the photons of one chunk as a wavefront (seed 000 §5.2's paths, breadth first): each
// step intersects the current ray of every photon still in flight with one batch query (an
// Embree ray stream), then shades each hit, stores the photon there and scatters it, and
// compacts the survivors with their next rays. A photon meets the same random numbers and the
// same operations as when traced alone (path by path), so the maps come out bit-identical to a
// path-by-path trace once the stores, made bounce by bounce, are put back in photon order.
// A ChunkTracer is reused for many chunks (trace_photons keeps one per worker), so its buffers
// are allocated once.
class ChunkTracer {
  public:
    ChunkTracer(const Scene& scene, const PhotonTracerSettings& settings,
                const PhotonEmitter& emitter)
        : scene_(scene), settings_(settings), emitter_(emitter) {}

    ChunkResult trace(uint64_t pass, uint64_t begin, uint64_t end);

  private:
    void emit(uint64_t pass, uint64_t begin, uint64_t end);
    // Shades the hit of every photon in flight; the survivors move to the front with their next
    // rays, in the same order. Misses leave the scene.
    void shade_all();
    // The stages of shade_all for photons [begin, end), whose batch records are shadings_[i -
    // begin] and samples_[i - begin]; survivors are compacted to *alive onwards.
    void shade_batch(size_t begin, size_t end, size_t* alive);
    void store(const PhotonState& photon, const Shading& shading, const Ray& ray);
    void record_first_hit(const PhotonState& photon, const Shading& shading, const Ray& ray);
    // The chunk's stores (bounce-major) in photon order: a stable counting sort on their owner
    // keeps each photon's stores in bounce order.
    std::vector<Photon> in_photon_order(const std::vector<StagedPhoton>& staged,
                                        size_t photon_count);
    // Whether a photon may scatter again: a budget of max_bounces (or of glossy bounces, when
    // they have their own) is left.
    bool can_scatter(const PhotonState& photon) const {
        return photon.scatterings < settings_.max_bounces ||
               (settings_.max_glossy_bounces >= 0 &&
                photon.glossy_scatterings < settings_.max_glossy_bounces);
    }
    // Moves a photon that survived the roulette and whose BSDF sample `bs` succeeded: its power
    // and its next ray. False ends the path.
    bool scatter(PhotonState& photon, const Shading& shading, const Material& material,
                 const BsdfSample& bs, Ray* ray);

    const Scene& scene_;
    const PhotonTracerSettings& settings_;
    const PhotonEmitter& emitter_;
    // In flight: photons_[i] travels along rays_[i], which hit hits_[i] at points_[i].
    std::vector<PhotonState> photons_;
    std::vector<Ray> rays_;
    std::vector<Hit> hits_;
    std::vector<SurfacePoint> points_;
    // One shade batch: shadings_[k] and samples_[k] (valid when sampled_[k]) for photon begin + k.
    std::array<Shading, kShadeBatch> shadings_;
    std::array<BsdfSample, kShadeBatch> samples_;
    std::array<bool, kShadeBatch> sampled_{};
    // Stores in the order made (bounce-major) and the counting sort's offsets: kept from chunk
    // to chunk, so only the results' exactly sized vectors are new memory.
    std::vector<StagedPhoton> global_, caustic_;
    std::vector<PhotonFirstHit> first_hits_;
    std::vector<uint32_t> offsets_;
    uint64_t bounces_ = 0;
};

ChunkResult ChunkTracer::trace(uint64_t pass, uint64_t begin, uint64_t end) {
    global_.clear();
    caustic_.clear();
    first_hits_.clear();
    bounces_ = 0;
    emit(pass, begin, end);
    while (!rays_.empty()) {
        // A parallel_for of its own, nested in trace_photons' (TBB allows it); as long as
        // kPhotonsPerChunk <= Scene::kRaysPerChunk the wavefront is one piece of it, traced on
        // this thread.
        scene_.intersect(rays_, hits_);
        bounces_ += rays_.size();
        shade_all();
    }
    ChunkResult result;
    result.global = in_photon_order(global_, size_t(end - begin));
    result.caustic = in_photon_order(caustic_, size_t(end - begin));
    result.first_hits = first_hits_;
    result.bounces = bounces_;
    return result;
}

std::vector<Photon> ChunkTracer::in_photon_order(const std::vector<StagedPhoton>& staged,
                                                 size_t photon_count) {
    offsets_.assign(photon_count + 1, 0);
    for (const StagedPhoton& s : staged) ++offsets_[s.owner + 1];
    for (size_t i = 1; i <= photon_count; ++i) offsets_[i] += offsets_[i - 1];
    std::vector<Photon> photons(staged.size());
    for (const StagedPhoton& s : staged) photons[offsets_[s.owner]++] = s.photon;
    return photons;
}

// Photons [begin, end) of the pass, each on its own RNG stream.
void ChunkTracer::emit(uint64_t pass, uint64_t begin, uint64_t end) {
    photons_.clear();
    rays_.clear();
    for (uint64_t i = begin; i < end; ++i) {
        PhotonState photon;
        photon.rng = Pcg32(settings_.seed, stream_id(pass, i));
        EmittedPhoton emitted;
        if (!emitter_.emit(i, settings_.photons, photon.rng, &emitted)) continue;
        photon.power = emitted.power;
        photon.from_world = emitted.from_world;
        photon.owner = uint32_t(i - begin);
        photons_.push_back(photon);
        rays_.push_back(emitted.ray);
    }
}

void ChunkTracer::shade_all() {
    // Surface points first, in a loop of their own: on a large mesh each one misses the cache
    // (vertex data), and a short loop lets the processor overlap those misses.
    points_.resize(photons_.size());
    for (size_t i = 0; i < photons_.size(); ++i)
        if (hits_[i].valid()) points_[i] = scene_.surface_point(rays_[i], hits_[i]);
    size_t alive = 0;
    for (size_t begin = 0; begin < photons_.size(); begin += kShadeBatch)
        shade_batch(begin, std::min(begin + kShadeBatch, photons_.size()), &alive);
    photons_.resize(alive);
    rays_.resize(alive);
}

void ChunkTracer::shade_batch(size_t begin, size_t end, size_t* alive) {
    // Set-up and store. The first hit is direct light, which every consumer computes exactly.
    for (size_t i = begin; i < end; ++i) {
        sampled_[i - begin] = false;
        if (!hits_[i].valid()) continue;  // left the scene
        PhotonState& photon = photons_[i];
        const Shading& shading = make_shading_in(&shadings_[i - begin], scene_, points_[i],
                                                 rays_[i].direction, PathOrigin::Light);
        // From the light unscattered (glossy scatterings count here even on their own budget).
        const bool first = photon.scatterings == 0 && photon.glossy_scatterings == 0;
        const bool direct = first && !(photon.from_world && settings_.store_world_direct);
        if (!direct && shading.bsdf.has_smooth_lobes()) store(photon, shading, rays_[i]);
        // The first step's photons are in photon order (emit), so these are too.
        if (first && settings_.store_first_hits)
            record_first_hit(photon, shading, rays_[i]);
        sampled_[i - begin] = can_scatter(photon);
    }
    // Russian roulette by albedo, then the survivors' BSDF sample towards their next direction
    // (wo = towards where the photon came from; the BSDF evaluates its non-reciprocal Principled
    // v2 terms toward the sampled direction). Absorbed photons skip the sample. The weight is
    // the whole BSDF over the mixture pdf, and the bounce counts as the class of the lobe that
    // drew it, as a camera path's does (PathIntegrator::scatter): the bounce budgets then cut
    // the same light from both. With the picked lobe's weight alone (seed 000 §5.1's one bounce
    // type) a diffuse-drawn photon carried only the diffuse lobe's light, and the lattice read
    // the two-room scene's glossy plaster 2.3% too bright at Glossy 0 and 2.5% too dark at
    // Glossy 4 (bench/lattice_glossy_budget.py).
    for (size_t i = begin; i < end; ++i) {
        if (!sampled_[i - begin]) continue;
        PhotonState& photon = photons_[i];
        const Shading& shading = shadings_[i - begin];
        const float survive = survival_probability(shading.bsdf);
        if (!(survive > 0.0f) || photon.rng.next_float() >= survive) {
            sampled_[i - begin] = false;
            continue;
        }
        const float u_lobe = photon.rng.next_float();
        const vec2 u = photon.rng.next_vec2();
        sampled_[i - begin] =
            shading.bsdf.sample(shading.wo, u_lobe, u, &samples_[i - begin]);
    }
    // Next rays; survivors move to the front, in order.
    for (size_t i = begin; i < end; ++i) {
        if (!sampled_[i - begin]) continue;
        Ray ray = rays_[i];
        const Material& material = scene_.materials()[points_[i].material_id];
        if (!scatter(photons_[i], shadings_[i - begin], material, samples_[i - begin], &ray))
            continue;
        photons_[*alive] = photons_[i];
        rays_[*alive] = ray;
        ++*alive;
    }
}

void ChunkTracer::store(const PhotonState& photon, const Shading& shading, const Ray& ray) {
    StagedPhoton staged;
    staged.photon.position = shading.position;
    staged.photon.power = photon.power;
    staged.photon.normal = shading.geometric_normal;  // already flipped to the arrival side
    staged.photon.direction = -ray.direction;
    staged.owner = photon.owner;
    // Only specular scatterings since emission: a caustic path L S+ D.
    (photon.specular_path ? caustic_ : global_).push_back(staged);
}

void ChunkTracer::record_first_hit(const PhotonState& photon, const Shading& shading,
                                   const Ray& ray) {
    PhotonFirstHit hit;
    hit.position = shading.position;
    hit.normal = shading.geometric_normal;  // already flipped to the arrival side
    hit.direction = -ray.direction;
    hit.power = photon.power;
    // The diffuse lobe's directional albedo toward the light (reciprocity: the share of the
    // arriving flux it scatters).
    // At a shading normal, times the adjoint's correction (render/shading.h).
    hit.reflected_power = shading.bsdf.field_diffuse(shading.wo) * photon.power *
                          particle_diffuse_arrival(shading, hit.direction);
    first_hits_.push_back(hit);
}

bool ChunkTracer::scatter(PhotonState& photon, const Shading& shading, const Material& material,
                          const BsdfSample& bs, Ray* ray) {
    const vec3 wi = glm::normalize(shading.frame.to_world(bs.wi));
    if (!is_finite(wi)) return false;
    const bool geometric_above = glm::dot(wi, shading.geometric_normal) > 0.0f;
    if (geometric_above != (bs.wi.z > 0.0f)) return false;  // shading/geometric normals disagree
    // PrincipledBsdf gives every glossy and refraction lobe the material's roughness.
    const bool specular = bs.delta || (bs.lobe_class != LobeClass::Diffuse &&
                                       material.roughness <= settings_.specular_roughness);
    photon.specular_path = photon.specular_path && specular;
    // The adjoint BSDF's weight at a shading normal (render/shading.h): bs.weight elsewhere.
    photon.power *= particle_scatter_weight(shading, -ray->direction, bs, wi) /
                    survival_probability(shading.bsdf);
    if (!is_finite(photon.power) || !(max_component(photon.power) > 0.0f)) return false;
    // Past its budget a lobe is off, as a camera path's closures are past theirs: a photon that
    // has used up max_bounces still reflects glossily, and one that picked the spent lobe ends
    // (the pick's 1/probability weight keeps the others unbiased).
    if (settings_.max_glossy_bounces >= 0 && bs.lobe_class == LobeClass::Glossy) {
        if (++photon.glossy_scatterings > settings_.max_glossy_bounces) return false;
    } else if (++photon.scatterings > settings_.max_bounces) {
        return false;
    }
    ray->origin = shading.spawn_origin(wi);
    ray->direction = wi;
    ray->tmin = 0.0f;
    ray->tmax = kInfinity;
    return true;
}

// Tracers for the workers of one trace_photons call: each chunk borrows one (and its buffers)
// for as long as it runs.
class ChunkTracerPool {
  public:
    ChunkTracerPool(const Scene& scene, const PhotonTracerSettings& settings,
                    const PhotonEmitter& emitter)
        : scene_(scene), settings_(settings), emitter_(emitter) {}

    std::unique_ptr<ChunkTracer> acquire() {
        {
            const std::lock_guard<std::mutex> lock(mutex_);
            if (!free_.empty()) {
                std::unique_ptr<ChunkTracer> tracer = std::move(free_.back());
                free_.pop_back();
                return tracer;
            }
        }
        return std::make_unique<ChunkTracer>(scene_, settings_, emitter_);
    }
    void release(std::unique_ptr<ChunkTracer> tracer) {
        const std::lock_guard<std::mutex> lock(mutex_);
        free_.push_back(std::move(tracer));
    }

  private:
    const Scene& scene_;
    const PhotonTracerSettings& settings_;
    const PhotonEmitter& emitter_;
    std::mutex mutex_;
    std::vector<std::unique_ptr<ChunkTracer>> free_;
};

// Capacity for `count` photons: exact for the first block (most passes have one), doubling after
// (an exact fit per block would copy the whole map at every block), but not past `limit` photons
// unless `count` is.
size_t grown_capacity(size_t capacity, size_t count, size_t limit) {
    if (count <= capacity) return capacity;
    if (capacity == 0) return count;
    return std::max(count, std::min(2 * capacity, limit));
}

// Moves the map to a buffer of `capacity` photons when larger than its own (cancellable: the
// map can hold 10^8 photons).
void grow_to(std::vector<Photon>& photons, size_t capacity, const Progress* progress) {
    if (capacity <= photons.capacity()) return;
    std::vector<Photon> grown;
    grown.reserve(capacity);
    advise_huge_pages(grown.data(), grown.capacity() * sizeof(Photon));
    append_photons(grown, photons, progress);
    photons.swap(grown);
}

// Appends the first `count` chunks' photons to the maps in chunk order, releasing them; the
// appends poll cancel (the first writes to fresh pages of a block's ~10^7 photons take a few
// hundred ms in all).
// Growing a map holds its old and new buffers at once: when that would pass `transient_budget`
// bytes for both maps, throws OutOfMemory (naming how far the pass got) before allocating.
void merge(std::vector<ChunkResult>& chunks, uint64_t count, PhotonMaps& maps,
           uint64_t transient_budget, const PhotonTracerSettings& settings, uint64_t traced,
           const Progress* progress) {
    size_t global_count = maps.global.size(), caustic_count = maps.caustic.size();
    for (uint64_t c = 0; c < count; ++c) {
        global_count += chunks[c].global.size();
        caustic_count += chunks[c].caustic.size();
    }
    const size_t limit = size_t(transient_budget / sizeof(Photon) / 2);
    const size_t global_capacity = grown_capacity(maps.global.capacity(), global_count, limit);
    const size_t caustic_capacity = grown_capacity(maps.caustic.capacity(), caustic_count, limit);
    // The global map grows first (beside the caustic map's old buffer), then the caustic map
    // (beside the global map's new one).
    const uint64_t old_global = maps.global.capacity(), old_caustic = maps.caustic.capacity();
    const uint64_t global_peak =
        global_capacity > old_global ? old_global + global_capacity + old_caustic : 0;
    const uint64_t caustic_peak =
        caustic_capacity > old_caustic ? global_capacity + old_caustic + caustic_capacity : 0;
    const uint64_t transient = std::max(global_peak, caustic_peak) * sizeof(Photon);
    if (transient > transient_budget)
        throw OutOfMemory(format_message(
            "trace_photons: after ", traced, " of ", settings.photons, " photons, growing the "
            "photon maps would hold ", transient, " bytes at once (old and new buffers), past "
            "three quarters of what this process could allocate when the pass began (",
            format_bytes(uint64_t(double(transient_budget) / kGrowingPhotonsMemoryFraction)),
            ": RLIMIT_AS / cgroup / free memory); lower the photon count"));
    grow_to(maps.global, global_capacity, progress);
    grow_to(maps.caustic, caustic_capacity, progress);
    for (uint64_t c = 0; c < count; ++c) {
        append_photons(maps.global, chunks[c].global, progress);
        append_photons(maps.caustic, chunks[c].caustic, progress);
        maps.first_hits.insert(maps.first_hits.end(), chunks[c].first_hits.begin(),
                               chunks[c].first_hits.end());  // within the reserved capacity
        maps.bounces += chunks[c].bounces;
        chunks[c] = ChunkResult{};  // release as we go: the maps may be large
    }
}

}  // namespace

void append_photons(std::vector<Photon>& to, const std::vector<Photon>& from,
                    const Progress* progress) {
    constexpr uint64_t kPhotonsPerSlice = uint64_t(1) << 20;
    for_each_slice(from.size(), kPhotonsPerSlice, progress, [&](uint64_t begin, uint64_t end) {
        to.insert(to.end(), from.begin() + ptrdiff_t(begin), from.begin() + ptrdiff_t(end));
    });
}

void validate_photon_tracer_settings(const PhotonTracerSettings& settings,
                                     const char* struct_name) {
    if (settings.photons == 0 || settings.photons > kMaxPhotonsPerPass)
        throw InvalidArgument(format_message(struct_name, ".photons is ", settings.photons,
                                             "; it must be in [1, 2^40]"));
    if (settings.max_bounces < 1)
        throw InvalidArgument(format_message(struct_name, ".max_bounces is ",
                                             settings.max_bounces, "; it must be >= 1"));
    if (settings.max_glossy_bounces < -1)
        throw InvalidArgument(format_message(struct_name, ".max_glossy_bounces is ",
                                             settings.max_glossy_bounces,
                                             "; it must be >= 0, or -1 (no budget of its own)"));
    if (!(settings.specular_roughness >= 0.0f && settings.specular_roughness <= 1.0f))
        throw InvalidArgument(format_message(struct_name, ".specular_roughness is ",
                                             settings.specular_roughness,
                                             "; it must be in [0, 1]"));
    if (!(settings.light_share_uniform >= 0.0f && settings.light_share_uniform <= 1.0f))
        throw InvalidArgument(format_message(struct_name, ".light_share_uniform is ",
                                             settings.light_share_uniform,
                                             "; it must be in [0, 1] (0: lamps by power alone)"));
}

PhotonMaps trace_photons(const Scene& scene, const PhotonTracerSettings& settings, uint64_t pass,
                         Progress* progress, const char* settings_name) {
    validate_photon_tracer_settings(settings, settings_name);
    return trace_photon_range(scene, settings, pass, 0, settings.photons, progress,
                              settings_name);
}

PhotonMaps trace_photon_range(const Scene& scene, const PhotonTracerSettings& settings,
                              uint64_t pass, uint64_t begin, uint64_t end, Progress* progress,
                              const char* settings_name) {
    validate_photon_tracer_settings(settings, settings_name);
    if (begin >= end || end > settings.photons)
        throw InvalidArgument(format_message(
            "trace_photon_range: photons [", begin, ", ", end, ") of a pass of ",
            settings.photons, " (", settings_name, ".photons); it needs begin < end <= ",
            settings.photons));
    if (!scene.committed())
        throw InvalidArgument("trace_photons: the scene is not committed; call commit() first");
    throw_if_cancelled(progress);
    PhotonMaps maps;
    const PhotonEmitter emitter(scene, settings.light_share_uniform);
    if (scene.empty() || emitter.empty()) return maps;
    // The chunks are those of the whole pass (photon c * kPhotonsPerChunk onwards), cut to the
    // range: a range that starts and ends on chunk boundaries traces exactly the whole pass's
    // chunks. (A photon's path does not depend on its chunk's other photons either way: the
    // wavefront's rays are intersected one by one, Scene::intersect's incoherent default.)
    const uint64_t photons = end - begin;
    const uint64_t first_chunk = begin / kPhotonsPerChunk;
    const uint64_t chunk_count = (end + kPhotonsPerChunk - 1) / kPhotonsPerChunk - first_chunk;
    if (settings.store_first_hits) {
        // At most one per photon, reserved at once (no growth copies); before the allowance is
        // read, so an address-space limit counts it.
        require_memory(saturating_mul(photons, sizeof(PhotonFirstHit)),
                       format_message(settings_name, ".photons = ", settings.photons,
                                      " with store_first_hits (up to one first hit of ",
                                      sizeof(PhotonFirstHit), " bytes per photon)"),
                       format_message("lower ", settings_name, ".photons (or trace more passes "
                                      "of fewer photons)"));
        maps.first_hits.reserve(size_t(photons));
    }
    // The allowance is read once: it shrinks as the maps grow.
    const MemoryLimits limits = memory_limits();
    const uint64_t allowed = limits.allowed();
    const bool unlimited = allowed == std::numeric_limits<uint64_t>::max();
    const uint64_t budget =
        unlimited ? allowed : uint64_t(double(allowed) * kStoredPhotonsMemoryFraction);
    const uint64_t transient_budget =
        unlimited ? allowed : uint64_t(double(allowed) * kGrowingPhotonsMemoryFraction);
    ChunkTracerPool pool(scene, settings, emitter);
    std::vector<ChunkResult> chunks(std::min(chunk_count, kChunksPerBlock));
    std::atomic<uint64_t> chunks_done{0};
    // Photons of the range before chunk c (of the range) begins.
    const auto traced_before = [&](uint64_t c) {
        return std::min(end, std::max(begin, (first_chunk + c) * kPhotonsPerChunk)) - begin;
    };
    for (uint64_t block = 0; block < chunk_count;) {
        const uint64_t traced = traced_before(block);
        const uint64_t stored = maps.global.size() + maps.caustic.size();
        const uint64_t stored_bytes = stored * sizeof(Photon);
        if (stored_bytes > budget)
            throw OutOfMemory(format_message(
                "trace_photons: after ", traced, " of ", photons,
                " photons the stored photons take ", stored_bytes, " bytes, past half of what "
                "this process could allocate when the pass began (", format_bytes(allowed),
                ": RLIMIT_AS / cgroup / free memory); lower ", settings_name, ".photons"));
        if (traced > 0 && stored > 0) {
            // The maps at the end of the pass, at the rate the traced photons stored, and the
            // growth that holds old and new buffers at once: refused now, not tens of seconds
            // (and gigabytes) later.
            const double per_photon = double(stored) / double(traced);
            const double projected = per_photon * double(photons) * sizeof(Photon);
            const uint64_t need = projected >= 1.8e19 ? std::numeric_limits<uint64_t>::max()
                                                      : uint64_t(projected);
            require_memory(
                saturating_mul(need, 2),
                format_message(settings_name, ".photons = ", settings.photons, " (the first ",
                               traced, " photons",
                               photons == settings.photons
                                   ? std::string()
                                   : format_message(" of a batch of ", photons),
                               " stored ", per_photon,
                               " photons each, so about ", uint64_t(per_photon *
                               double(photons)), " stored photons of ",
                               sizeof(Photon), " bytes, twice: stored photons may take half of the "
                               "memory, as growing a map holds its old and new buffers)"),
                format_message("lower ", settings_name, ".photons (or trace more passes of "
                               "fewer photons)"),
                limits);
        }
        const uint64_t block_chunks =
            std::min(block == 0 ? kPilotChunks : kChunksPerBlock, chunk_count - block);
        // Grain 1 over chunk indices: each body call traces whole chunks, whatever the split.
        // Progress counts chunks over the whole pass (parallel_for's own would restart at each
        // block), so the body polls the cancel flag itself.
        parallel_for(0, block_chunks, 1, [&](uint64_t chunk_begin, uint64_t chunk_end) {
            std::unique_ptr<ChunkTracer> tracer = pool.acquire();
            for (uint64_t c = chunk_begin; c < chunk_end; ++c) {
                throw_if_cancelled(progress);
                chunks[c] = tracer->trace(pass, begin + traced_before(block + c),
                                          begin + traced_before(block + c + 1));
                if (progress) progress->report(chunks_done.fetch_add(1) + 1, chunk_count);
            }
            pool.release(std::move(tracer));
        });
        merge(chunks, block_chunks, maps, transient_budget, settings,
              traced_before(block + block_chunks), progress);
        block += block_chunks;
    }
    maps.emitted = photons;
    maps.emitted_power = emitter.total_power();
    return maps;
}

std::vector<Photon> vpl_hits(const PhotonMaps& maps, bool later_hits) {
    std::vector<Photon> hits;
    hits.reserve(maps.first_hits.size() + maps.global.size() + maps.caustic.size());
    for (const PhotonFirstHit& h : maps.first_hits)
        hits.push_back({h.position, h.power, h.normal, h.direction});
    if (later_hits) {
        hits.insert(hits.end(), maps.global.begin(), maps.global.end());
        hits.insert(hits.end(), maps.caustic.begin(), maps.caustic.end());
    }
    return hits;
}

vec3 scattered_flux(const Scene& scene, const vec3& position, const vec3& normal,
                    const vec3& direction, const vec3& power, float reach,
                    float glossy_min_roughness) {
    Ray ray;
    ray.origin = position + direction * reach;
    ray.direction = -direction;
    ray.tmax = 2.0f * reach;
    Hit hit = scene.intersect(ray);
    if (!hit.valid()) {  // a grazing photon: come back along the normal instead
        ray.origin = position + normal * reach;
        ray.direction = -normal;
        hit = scene.intersect(ray);
        if (!hit.valid()) return vec3(0.0f);
    }
    const Shading shading =
        make_shading(scene, scene.surface_point(ray, hit), ray.direction, PathOrigin::Light);
    // At a shading normal, the albedos take the adjoint's correction (render/shading.h).
    vec3 albedo =
        shading.bsdf.field_diffuse(shading.wo) * particle_diffuse_arrival(shading, -ray.direction);
    if (glossy_min_roughness >= 0.0f) {
        PrincipledBsdf::GlossyLobe lobes[2];
        const int count = shading.bsdf.field_glossy_lobes(shading.wo, lobes);
        const float ratio = particle_arrival_ratio(shading, -ray.direction);
        for (int i = 0; i < count; ++i)
            if (lobes[i].roughness > glossy_min_roughness) albedo += lobes[i].albedo * ratio;
    }
    return albedo * power;
}

}  // namespace shgi
