// Photon tracing (seed 000 §5.1–5.2, §6.2–6.3): photons are emitted from every emitter of a Scene
// in proportion to its power with Cycles' light units (render/light_sampler.h), traced through
// the scene with the same Principled BSDF sampling as the path tracer (Lambert/Principled
// diffuse, GGX glossy, mirror, refraction with IOR and Fresnel) and Russian roulette by albedo,
// and stored where they land.
//
// Emission: photon/photon_emitter.h (each emitter's flux, how its photons leave it, portals, and
// the stratified choice of emitter).
//
// Storage: the first surface a photon hits after emission is not stored in the maps (the
// renderers compute direct light exactly); with store_first_hits it is recorded apart, as a
// PhotonFirstHit (photon/photon.h), for every photon whose first ray hits a surface, whatever its
// BSDF; each later hit on a surface whose BSDF has a non-Dirac lobe stores a
// Photon (the power arriving there) before the photon scatters on. A stored photon whose path
// since emission bounced only on specular surfaces (Dirac lobes, or lobes with roughness <=
// specular_roughness), at least once, goes to the caustic map (L S+ D); every other stored
// photon to the global map. Paths end after max_bounces scatterings, by Russian roulette
// (survival = min(1, max component of PrincipledBsdf::albedo_estimate()), drawn before the BSDF
// sample so that absorbed photons skip it; the survivor's power is divided by it) or when they
// leave the scene. A survivor scatters as a camera path does (PrincipledBsdf::sample: a lobe
// chosen in proportion to the lobes' selection weights draws the direction, the whole BSDF
// weighs it, and the bounce counts in the drawing lobe's class).
//
// Tracing is a wavefront (stream) per chunk of photons: all photons of a chunk are in flight
// together, each step intersects all their rays with one batch query (Embree ray streams), then
// shades, stores and scatters every hit and keeps the survivors for the next step. Hits are
// shaded in small batches, one stage (set-up, store, BSDF sample, roulette) at a time, and each
// worker reuses its buffers from chunk to chunk.
//
// Determinism: photon i of pass k uses RNG stream stream_id(k, i) (util/rng.h) and meets the same
// random numbers and operations as if traced alone. The maps list stored photons by photon index,
// each photon's stores in bounce order; chunks are fixed and concatenated in chunk order, so the
// maps are bit-identical whatever the thread count. Multithreaded with util/parallel.h,
// cancellable and with progress (polled between chunks).
#pragma once

#include <cstdint>
#include <vector>

#include "photon/photon.h"
#include "scene/scene.h"
#include "util/progress.h"

namespace shgi {

struct PhotonTracerSettings {
    uint64_t photons = 200000;          // emitted per pass
    uint64_t seed = 0;
    int max_bounces = 8;                // scatterings after emission before a path ends
    // -1: every scattering counts against max_bounces. >= 0: glossy scatterings (LobeClass::
    // Glossy) have a budget of their own, as a camera path's Light Paths > Glossy beside
    // Diffuse, and max_bounces counts the others. A spent budget turns its lobes off, as a
    // path tracer's Light Paths do: a photon that has used up max_bounces still reflects
    // glossily while glossy bounces are left, and one that picks a spent lobe ends. A path
    // tracer's Diffuse 4 / Glossy 4 lets a path reflect diffusely 4 times however often it
    // reflected glossily between or after; counting those glossy reflections against the 4 lost
    // the radiance field 2-3% of its indirect light in white rooms, and stopping at the 4th
    // diffuse one lost the photon lattice another 5% in the two-room scene (docs/methods.md).
    int max_glossy_bounces = -1;
    float specular_roughness = 0.1f;    // lobes up to this roughness count as specular (caustics)
    // Store photons from the world at their first hit too (global map): the maps then carry the
    // world's direct light, which consumers leave out of next-event estimation.
    bool store_world_direct = false;
    // Also record each light path's first surface hit in PhotonMaps::first_hits (the maps do
    // not change). Off by default: it costs up to 60 bytes per emitted photon.
    bool store_first_hits = false;
    // The uniform share of the choice of lamp per photon, in [0, 1] (photon_emitter.h: a dim
    // lamp beside a bright one gets at least this over the lamps' count of the photons, their
    // power divided by the mixed probability). 0: by flux alone.
    float light_share_uniform = 0.0f;
};

// Throws InvalidArgument naming the field (photons 0 or > 2^40, max_bounces < 1, roughness or
// light_share_uniform outside [0, 1] or NaN).
// `struct_name` names the settings in messages: PhotonLatticeSettings forwards these fields.
void validate_photon_tracer_settings(const PhotonTracerSettings& settings,
                                     const char* struct_name = "PhotonTracerSettings");

struct PhotonMaps {
    std::vector<Photon> global;
    std::vector<Photon> caustic;
    uint64_t emitted = 0;            // photons emitted in this pass (settings.photons)
    vec3 emitted_power{0.0f};        // W: exact total flux of the emitters (photon_emitter.h);
                                     // the emitted photons' powers sum to an estimate of it
    uint64_t bounces = 0;            // surface interactions traced (rays cast), for benchmarks
    // With PhotonTracerSettings::store_first_hits: the first surface hit of every photon whose
    // first ray hits one, in photon order (at most one per photon). Empty otherwise.
    std::vector<PhotonFirstHit> first_hits;
};

// Traces pass `pass` (0, 1, 2, ...: independent RNG streams) on a committed scene (else
// InvalidArgument). An empty scene or one without emitters returns empty maps (emitted = 0).
// Throws Cancelled on cancel.
// Memory (docs/robustness-memory.md): the first block is a short pilot of 2^18 photons; from
// the photons it stored, the whole pass's stored photons are projected and a pass whose maps
// would not fit what the process may allocate (util/memory.h) is refused with OutOfMemory
// naming `settings_name`.photons before the rest is traced. Later blocks re-check the
// projection and the maps' growth. With store_first_hits, room for one first hit per photon is
// checked and reserved before tracing (pages never written are not backed by memory).
PhotonMaps trace_photons(const Scene& scene, const PhotonTracerSettings& settings, uint64_t pass,
                         Progress* progress = nullptr,
                         const char* settings_name = "PhotonTracerSettings");

// Photons [begin, end) of pass `pass` of a pass of settings.photons photons (each photon's
// emission depends on its index and on the pass's total, settings.photons, not on the range), as
// trace_photons traces them: the whole pass's maps are the maps of consecutive ranges
// concatenated in range order, bit for bit (a farm's photon batches, lattice/photon_lattice.h).
// emitted = end - begin; bounces counts the range's rays; emitted_power is the whole pass's.
// InvalidArgument unless begin < end <= settings.photons; otherwise as trace_photons.
PhotonMaps trace_photon_range(const Scene& scene, const PhotonTracerSettings& settings,
                              uint64_t pass, uint64_t begin, uint64_t end,
                              Progress* progress = nullptr,
                              const char* settings_name = "PhotonTracerSettings");

// The hits of a pass that VPL methods light from (Instant GI, Light Propagation), as photons in
// order: the first hits, then (later_hits) the stored global and caustic photons.
std::vector<Photon> vpl_hits(const PhotonMaps& maps, bool later_hits);

// The flux the surface under a photon hit scatters (its position, normal, unit direction
// towards the source and arriving power): the surface is found again by a ray back along the
// photon's path over 2 x `reach` m (from `reach` before the hit; a grazing photon: along the
// normal), since a stored Photon keeps no material; zero when it is not found. The diffuse
// lobe's albedo always; with glossy_min_roughness >= 0 also the albedo of the glossy lobes
// rougher than it (spread as if diffuse: the radiance field's glossy_in_grid, Instant GI's
// glossy_vpls). Times the power.
vec3 scattered_flux(const Scene& scene, const vec3& position, const vec3& normal,
                    const vec3& direction, const vec3& power, float reach,
                    float glossy_min_roughness);

// Appends `from` to `to` in slices of 2^20 photons (48 MB, ~10 ms) with a cancel poll before
// each: maps of 10^7+ photons take long to copy, and a cancel should not wait for it.
void append_photons(std::vector<Photon>& to, const std::vector<Photon>& from,
                    const Progress* progress);

}  // namespace shgi
