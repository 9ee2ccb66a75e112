#include "lattice/photon_lattice.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "io/image.h"
#include "util/binary_file.h"
#include "util/error.h"
#include "util/memory.h"
#include "util/timer.h"

namespace shgi {
namespace {

// Share of the bounds' diagonal used as the caustic density estimate's radius by default.
constexpr float kDefaultCausticRadiusFraction = 0.02f;

// The file save() writes (little-endian):
//   "SHGILAT\0" | u32 version | the settings, field by field | Bounds3 | u64 passes |
//   f32 caustic_radius | u64 caustic photons injected | the timings | global ShLattice |
//   caustic ShLattice | f32 power_scale, u64 count, Photon[count] of the caustic photon map.
constexpr char kLatticeMagic[8] = {'S', 'H', 'G', 'I', 'L', 'A', 'T', '\0'};
// 2: the lattices hold visibility masks; 3: the settings hold glossy_bounces.
constexpr uint32_t kLatticeFileVersion = 3;
constexpr const char* kLatticeFile = "lattice file";

void write_settings(BinaryWriter& out, const PhotonLatticeSettings& s) {
    out.put(s.photons);
    out.put(s.seed);
    out.put(int32_t(s.max_bounces));
    out.put(s.specular_roughness);
    out.put(uint8_t(s.world_in_field));
    out.put(int32_t(s.resolution));
    out.put(int32_t(s.order));
    out.put(int32_t(s.blur_passes));
    out.put(uint8_t(s.caustics));
    out.put(int32_t(s.caustic_resolution));
    out.put(int32_t(s.caustic_order));
    out.put(int32_t(s.caustic_blur_passes));
    out.put(int32_t(s.caustic_neighbours));
    out.put(s.caustic_radius);
    out.put(uint8_t(s.interpolation));
    out.put(s.normal_offset);
    out.put(uint8_t(s.use_bounds));
    out.put(s.bounds_min);
    out.put(s.bounds_max);
    out.put(int32_t(s.glossy_bounces));
}

// `with_glossy`: the settings hold glossy_bounces (lattice files from version 3, batches);
// without, glossy scatterings counted against max_bounces (-1), as they did.
PhotonLatticeSettings read_settings(BinaryReader& in, bool with_glossy) {
    const char* what = "the settings";
    PhotonLatticeSettings s;
    s.photons = in.get<uint64_t>(what);
    s.seed = in.get<uint64_t>(what);
    s.max_bounces = in.get<int32_t>(what);
    s.specular_roughness = in.get<float>(what);
    s.world_in_field = in.get<uint8_t>(what) != 0;
    s.resolution = in.get<int32_t>(what);
    s.order = in.get<int32_t>(what);
    s.blur_passes = in.get<int32_t>(what);
    const uint8_t caustics = in.get<uint8_t>(what);
    s.caustic_resolution = in.get<int32_t>(what);
    s.caustic_order = in.get<int32_t>(what);
    s.caustic_blur_passes = in.get<int32_t>(what);
    s.caustic_neighbours = in.get<int32_t>(what);
    s.caustic_radius = in.get<float>(what);
    const uint8_t interpolation = in.get<uint8_t>(what);
    s.normal_offset = in.get<float>(what);
    s.use_bounds = in.get<uint8_t>(what) != 0;
    s.bounds_min = in.get<vec3>(what);
    s.bounds_max = in.get<vec3>(what);
    s.glossy_bounces = with_glossy ? in.get<int32_t>(what) : -1;
    if (caustics > uint8_t(CausticMode::PhotonMap) ||
        interpolation > uint8_t(LatticeInterpolation::Cubic))
        throw IoError(format_message(in.kind(), " \"", in.path(), "\" holds caustics ",
                                     int(caustics), ", interpolation ", int(interpolation),
                                     ": no such modes (damaged?)"));
    s.caustics = CausticMode(caustics);
    s.interpolation = LatticeInterpolation(interpolation);
    try {
        validate_photon_lattice_settings(s);
    } catch (const InvalidArgument& e) {
        throw IoError(format_message(in.kind(), " \"", in.path(), "\": ", e.what()));
    }
    return s;
}


Bounds3 lattice_bounds(const Scene& scene, const PhotonLatticeSettings& settings) {
    if (settings.use_bounds) {
        Bounds3 bounds;
        bounds.extend(settings.bounds_min);
        bounds.extend(settings.bounds_max);
        return bounds;
    }
    if (scene.empty())
        throw InvalidArgument("PhotonLattice: the scene has no geometry; add meshes and instances "
                              "(or set use_bounds) before solving");
    return scene.bounds();
}

void check_range(int value, int lo, int hi, const char* name) {
    if (value < lo || value > hi)
        throw InvalidArgument(format_message("PhotonLatticeSettings.", name, " is ", value,
                                             "; it must be in [", lo, ", ", hi, "]"));
}

// a += b over the coefficients both have (orders may differ).
void add_sh(ShRgb& a, const ShRgb& b) {
    const int count = std::min(a.num_coefficients(), b.num_coefficients());
    for (int i = 0; i < count; ++i) a[i] += b[i];
}

// The settings as save() writes them: equal bytes, equal settings (every field, exactly).
std::string settings_bytes(const PhotonLatticeSettings& settings) {
    std::ostringstream out(std::ios::binary);
    BinaryWriter w(out);
    write_settings(w, settings);
    return out.str();
}

template <typename T>
double as_number(T value) {
    if constexpr (std::is_enum_v<T>)
        return double(static_cast<std::underlying_type_t<T>>(value));
    else
        return double(value);
}

// The first field in which `got` differs from `wanted`, for messages.
std::string settings_difference(const PhotonLatticeSettings& got,
                                const PhotonLatticeSettings& wanted) {
#define SHGI_FIELD(name)                                                                   \
    if (!(got.name == wanted.name))                                                        \
        return format_message(#name " ", as_number(got.name), " instead of ",                \
                              as_number(wanted.name));
    SHGI_FIELD(photons)
    SHGI_FIELD(seed)
    SHGI_FIELD(max_bounces)
    SHGI_FIELD(glossy_bounces)
    SHGI_FIELD(specular_roughness)
    SHGI_FIELD(world_in_field)
    SHGI_FIELD(resolution)
    SHGI_FIELD(order)
    SHGI_FIELD(blur_passes)
    SHGI_FIELD(caustics)
    SHGI_FIELD(caustic_resolution)
    SHGI_FIELD(caustic_order)
    SHGI_FIELD(caustic_blur_passes)
    SHGI_FIELD(caustic_neighbours)
    SHGI_FIELD(caustic_radius)
    SHGI_FIELD(interpolation)
    SHGI_FIELD(normal_offset)
    SHGI_FIELD(use_bounds)
#undef SHGI_FIELD
    return "bounds_min/bounds_max differ";
}

// A photon batch's bytes (PhotonBatch::to_bytes, little-endian):
//   "SHGIPHB\0" | u32 version | the settings, field by field | u64 pass, begin, end, emitted,
//   bounces | f64 seconds | global Photon array | caustic Photon array.
constexpr char kBatchMagic[8] = {'S', 'H', 'G', 'I', 'P', 'H', 'B', '\0'};
constexpr uint32_t kBatchVersion = 2;  // 2: the settings hold glossy_bounces
constexpr const char* kBatchKind = "photon batch";

const PhotonLatticeSettings& validated(const PhotonLatticeSettings& settings) {
    validate_photon_lattice_settings(settings);
    return settings;
}

}  // namespace

std::string PhotonBatch::to_bytes() const {
    std::ostringstream out(std::ios::binary);
    BinaryWriter w(out);
    w.header(kBatchMagic, kBatchVersion);
    write_settings(w, settings);
    w.put(pass);
    w.put(begin);
    w.put(end);
    w.put(emitted);
    w.put(bounces);
    w.put(seconds);
    w.array(global);
    w.array(caustic);
    return out.str();
}

PhotonBatch PhotonBatch::from_bytes(const std::string& bytes, const std::string& what) {
    std::istringstream in(bytes, std::ios::binary);
    BinaryReader r(in, what, kBatchKind);
    r.header(kBatchMagic, kBatchVersion, kBatchVersion);
    PhotonBatch batch;
    batch.settings = read_settings(r, true);  // IoError for invalid settings
    batch.pass = r.get<uint64_t>("the header");
    batch.begin = r.get<uint64_t>("the header");
    batch.end = r.get<uint64_t>("the header");
    batch.emitted = r.get<uint64_t>("the header");
    batch.bounces = r.get<uint64_t>("the header");
    batch.seconds = r.get<double>("the header");
    if (batch.begin >= batch.end || batch.end > batch.settings.photons ||
        batch.emitted > batch.end - batch.begin)
        throw IoError(format_message(kBatchKind, " \"", what, "\" holds photons [", batch.begin,
                                     ", ", batch.end, ") (", batch.emitted, " emitted) of ",
                                     batch.settings.photons, " (damaged?)"));
    batch.global = r.array<Photon>("the global photons");
    batch.caustic = r.array<Photon>("the caustic photons");
    if (in.peek() != std::istringstream::traits_type::eof())
        throw IoError(format_message(kBatchKind, " \"", what, "\" has data after its end"));
    return batch;
}

PhotonBatch trace_photon_batch(const Scene& scene, const PhotonLatticeSettings& settings,
                               uint64_t pass, uint64_t begin, uint64_t end, Progress* progress) {
    validate_photon_lattice_settings(settings);
    const auto start = now();
    PhotonMaps maps = trace_photon_range(scene, photon_lattice_tracer_settings(settings), pass,
                                         begin, end, progress, "PhotonLatticeSettings");
    PhotonBatch batch;
    batch.settings = settings;
    batch.pass = pass;
    batch.begin = begin;
    batch.end = end;
    batch.global = std::move(maps.global);
    batch.caustic = std::move(maps.caustic);
    batch.emitted = maps.emitted;
    batch.bounces = maps.bounces;
    batch.seconds = seconds_since(start);
    return batch;
}

PhotonTracerSettings photon_lattice_tracer_settings(const PhotonLatticeSettings& settings) {
    PhotonTracerSettings tracer;
    tracer.photons = settings.photons;
    tracer.seed = settings.seed;
    tracer.max_bounces = settings.max_bounces;
    tracer.max_glossy_bounces = settings.glossy_bounces;
    tracer.specular_roughness = settings.specular_roughness;
    tracer.store_world_direct = settings.world_in_field;
    return tracer;
}

void validate_photon_lattice_settings(const PhotonLatticeSettings& settings) {
    check_range(settings.glossy_bounces, -1, 1024, "glossy_bounces");
    // The tracer's checks, naming the fields as the caller knows them (the names are the same).
    validate_photon_tracer_settings(photon_lattice_tracer_settings(settings),
                                    "PhotonLatticeSettings");
    check_range(settings.resolution, 1, 1024, "resolution");
    check_range(settings.order, 1, 2, "order");
    check_range(settings.blur_passes, 0, 64, "blur_passes");
    check_range(settings.caustic_resolution, 1, 1024, "caustic_resolution");
    check_range(settings.caustic_order, 1, 2, "caustic_order");
    check_range(settings.caustic_blur_passes, 0, 64, "caustic_blur_passes");
    check_range(settings.caustic_neighbours, 1, 100000, "caustic_neighbours");
    if (!std::isfinite(settings.caustic_radius) || settings.caustic_radius < 0.0f)
        throw InvalidArgument(format_message("PhotonLatticeSettings.caustic_radius is ",
                                             settings.caustic_radius,
                                             "; it must be finite and >= 0 (0 = automatic)"));
    if (!std::isfinite(settings.normal_offset) || settings.normal_offset < 0.0f ||
        settings.normal_offset > 2.0f)
        throw InvalidArgument(format_message("PhotonLatticeSettings.normal_offset is ",
                                             settings.normal_offset,
                                             "; it must be in [0, 2] cells"));
    if (settings.use_bounds) {
        if (!is_finite(settings.bounds_min) || !is_finite(settings.bounds_max) ||
            glm::any(glm::greaterThanEqual(settings.bounds_min, settings.bounds_max)))
            throw InvalidArgument(format_message(
                "PhotonLatticeSettings.bounds_min/bounds_max are (", settings.bounds_min.x, ", ",
                settings.bounds_min.y, ", ", settings.bounds_min.z, ") / (", settings.bounds_max.x,
                ", ", settings.bounds_max.y, ", ", settings.bounds_max.z,
                "); they must be finite with min < max on every axis"));
    }
}

PhotonLattice::PhotonLattice(const Scene& scene, const PhotonLatticeSettings& settings,
                             Progress* progress)
    : scene_(&scene), settings_(validated(settings)) {
    reset(progress);
}

PhotonLattice::~PhotonLattice() = default;

void PhotonLattice::reset(Progress* progress) {
    scene();  // a loaded lattice has none
    if (!scene_->committed())
        throw InvalidArgument("PhotonLattice: the scene is not committed; call commit() first");
    bounds_ = lattice_bounds(*scene_, settings_);
    ShLattice global(bounds_, settings_.resolution, settings_.order);
    global.measure_surfaces(*scene_, progress);
    ShLattice caustic;
    if (settings_.caustics == CausticMode::Lattice) {
        caustic = ShLattice(bounds_, settings_.caustic_resolution, settings_.caustic_order);
        caustic.measure_surfaces(*scene_, progress);
    }
    caustic_radius_ = settings_.caustic_radius > 0.0f
                          ? settings_.caustic_radius
                          : kDefaultCausticRadiusFraction * glm::length(bounds_.extent());
    // Each lattice checked its own cells against the memory left when it was made (the caustic
    // one after the global one took its share); the sums over passes are copies of both.
    require_memory(saturating_add(global.memory_bytes(), caustic.memory_bytes()),
                   format_message("PhotonLattice: the per-pass sums beside the lattices (resolution ",
                                  settings_.resolution, ", caustic_resolution ",
                                  settings_.caustic_resolution, ")"),
                   "lower resolution or caustic_resolution");
    global_raw_ = global;
    global_ = std::move(global);
    caustic_raw_ = caustic;
    caustic_ = std::move(caustic);
    caustic_map_ = PhotonMap();
    caustic_photons_injected_ = 0;
    passes_ = 0;
    timings_ = PhotonLatticeTimings{};
    scene_revision_ = scene_->revision();
}

const Scene& PhotonLattice::scene() const {
    if (scene_ == nullptr)
        throw InvalidArgument(format_message(
            "PhotonLattice: this lattice was read from \"", loaded_from_,
            "\" and has no scene to trace photons in; make a new PhotonLattice to solve again"));
    return *scene_;
}

void PhotonLattice::save(const std::string& path) const {
    write_file_atomically(path, [&](const std::string& temp) {
        std::ofstream out(temp, std::ios::binary | std::ios::trunc);
        BinaryWriter w(out);
        w.header(kLatticeMagic, kLatticeFileVersion);
        write_settings(w, settings_);
        w.put(bounds_);
        w.put(uint64_t(passes_));
        w.put(caustic_radius_);
        w.put(caustic_photons_injected_);
        w.put(timings_);
        global_.write(w);
        caustic_.write(w);
        w.put(caustic_map_.power_scale());
        w.array(caustic_map_.photons());
        out.flush();
        if (!out) throw IoError(format_message("cannot write lattice file \"", path, "\""));
    });
}

std::unique_ptr<PhotonLattice> PhotonLattice::load(const std::string& path) {
    require_readable_file(path, kLatticeFile);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(format_message("cannot open lattice file \"", path, "\""));
    BinaryReader r(in, path, kLatticeFile);
    // Versions 1 and 2 (before the visibility masks, before glossy_bounces) still open, and
    // sample as they did.
    const uint32_t version = r.header(kLatticeMagic, 1, kLatticeFileVersion);
    const bool with_visibility = version >= 2;
    std::unique_ptr<PhotonLattice> lattice(new PhotonLattice());
    lattice->loaded_from_ = path;
    lattice->settings_ = read_settings(r, version >= 3);
    lattice->bounds_ = r.get<Bounds3>("the header");
    lattice->passes_ = r.get<uint64_t>("the header");
    lattice->caustic_radius_ = r.get<float>("the header");
    lattice->caustic_photons_injected_ = r.get<uint64_t>("the header");
    lattice->timings_ = r.get<PhotonLatticeTimings>("the timings");
    lattice->global_ = ShLattice::read(r, with_visibility);
    lattice->caustic_ = ShLattice::read(r, with_visibility);
    const float power_scale = r.get<float>("the caustic photons");
    std::vector<Photon> photons = r.array<Photon>("the caustic photons");
    if (in.peek() != std::ifstream::traits_type::eof())
        throw IoError(format_message("lattice file \"", path, "\" has data after its end"));
    try {
        lattice->caustic_map_ = PhotonMap(std::move(photons), power_scale);
    } catch (const InvalidArgument& e) {
        throw IoError(format_message("lattice file \"", path, "\": ", e.what()));
    }
    return lattice;
}

void PhotonLattice::check_scene(const char* what) const {
    scene();  // a loaded lattice has none
    if (scene_->revision() != scene_revision_ || !scene_->committed())
        throw InvalidArgument(format_message(
            "PhotonLattice::", what, ": the scene was edited after the lattices were built "
            "(revision ", scene_revision_, ", now ", scene_->revision(),
            "); commit it and call reset()"));
}

void PhotonLattice::solve(Progress* progress) {
    check_scene("solve");
    if (progress != nullptr) progress->begin_stage("photons", 0.0f, 0.8f);
    // The whole pass as one batch (solve_batches() merges batches into the same photon lists).
    const PhotonBatch batch =
        trace_photon_batch(*scene_, settings_, passes_, 0, settings_.photons, progress);
    PhotonLatticeTimings timings;
    timings.emit_trace = batch.seconds;
    timings.photons_emitted = batch.emitted;
    timings.photons_stored = batch.global.size() + batch.caustic.size();
    timings.bounces = batch.bounces;
    add_pass(batch.global, batch.caustic, timings, progress);
}

void PhotonLattice::solve_batches(const std::vector<PhotonBatch>& batches, Progress* progress) {
    std::vector<const PhotonBatch*> pointers;
    for (const PhotonBatch& batch : batches) pointers.push_back(&batch);
    solve_batches(pointers, progress);
}

void PhotonLattice::solve_batches(const std::vector<const PhotonBatch*>& given,
                                  Progress* progress) {
    check_scene("solve_batches");
    if (given.empty())
        throw InvalidArgument("PhotonLattice::solve_batches: no batches; pass the batches that "
                              "cover the pass's photons [0, settings.photons)");
    const std::string wanted = settings_bytes(settings_);
    for (size_t i = 0; i < given.size(); ++i) {
        if (given[i] == nullptr)
            throw InvalidArgument(format_message("PhotonLattice::solve_batches: batch ", i,
                                                 " is None; pass PhotonBatch objects"));
        const PhotonBatch& batch = *given[i];
        if (settings_bytes(batch.settings) != wanted)
            throw InvalidArgument(format_message(
                "PhotonLattice::solve_batches: batch ", i, " (photons [", batch.begin, ", ",
                batch.end, ")) was traced with other settings than the lattice's (",
                settings_difference(batch.settings, settings_),
                "); trace it with the lattice's settings"));
        if (batch.pass != passes_)
            throw InvalidArgument(format_message(
                "PhotonLattice::solve_batches: batch ", i, " (photons [", batch.begin, ", ",
                batch.end, ")) is of pass ", batch.pass, ", the lattice's next pass is ",
                passes_, "; trace it for pass ", passes_));
    }
    // Photon order; then the ranges must tile [0, photons) exactly.
    std::vector<const PhotonBatch*> batches = given;
    std::stable_sort(
        batches.begin(), batches.end(),
        [](const PhotonBatch* a, const PhotonBatch* b) { return a->begin < b->begin; });
    uint64_t covered = 0;
    for (const PhotonBatch* batch : batches) {
        if (batch->begin != covered || batch->end <= batch->begin)
            throw InvalidArgument(format_message(
                "PhotonLattice::solve_batches: the batches' photon ranges must cover [0, ",
                settings_.photons, ") without gaps or overlaps; after [0, ", covered,
                ") comes a batch of [", batch->begin, ", ", batch->end, ")"));
        covered = batch->end;
    }
    if (covered != settings_.photons)
        throw InvalidArgument(format_message(
            "PhotonLattice::solve_batches: the batches cover photons [0, ", covered, ") of the "
            "pass's ", settings_.photons, "; photons [", covered, ", ", settings_.photons,
            ") are missing"));

    if (progress != nullptr) progress->begin_stage("photons", 0.0f, 0.8f);
    PhotonLatticeTimings timings;
    uint64_t global_count = 0, caustic_count = 0;
    for (const PhotonBatch* batch : batches) {
        timings.emit_trace += batch->seconds;  // the batches' tracing time, wherever it ran
        timings.photons_emitted += batch->emitted;
        timings.bounces += batch->bounces;
        global_count += batch->global.size();
        caustic_count += batch->caustic.size();
    }
    timings.photons_stored = global_count + caustic_count;
    if (batches.size() == 1) {
        add_pass(batches[0]->global, batches[0]->caustic, timings, progress);
        return;
    }
    require_memory(saturating_mul(global_count + caustic_count, sizeof(Photon)),
                   format_message("PhotonLattice::solve_batches: the pass's ",
                                  global_count + caustic_count, " stored photons of ",
                                  sizeof(Photon), " bytes in one list"),
                   "lower PhotonLatticeSettings.photons (or merge fewer at once)");
    std::vector<Photon> global, caustic;
    global.reserve(global_count);
    caustic.reserve(caustic_count);
    for (const PhotonBatch* batch : batches) {
        append_photons(global, batch->global, progress);
        append_photons(caustic, batch->caustic, progress);
    }
    add_pass(global, caustic, timings, progress);
}

void PhotonLattice::add_pass(const std::vector<Photon>& global_photons,
                             const std::vector<Photon>& caustic_photons_of_pass,
                             PhotonLatticeTimings timings, Progress* progress) {
    // Work on copies so that a cancel keeps the previous solution.
    if (progress != nullptr) progress->begin_stage("injection", 0.8f, 0.95f);
    auto start = now();
    ShLattice global_raw = global_raw_;
    global_raw.inject(global_photons, 1.0f, progress);
    ShLattice caustic_raw = caustic_raw_;
    std::vector<Photon> caustic_photons;
    uint64_t caustic_injected = caustic_photons_injected_;
    if (settings_.caustics == CausticMode::Lattice) {
        caustic_injected += caustic_raw.inject(caustic_photons_of_pass, 1.0f, progress);
    } else if (settings_.caustics == CausticMode::PhotonMap) {
        // All passes so far (unscaled; the map may hold 10^7 photons, half a GB), then this one.
        const uint64_t caustic_count = caustic_map_.size() + caustic_photons_of_pass.size();
        require_memory(saturating_mul(caustic_count, sizeof(Photon)),
                       format_message("PhotonLatticeSettings.caustics = PHOTON_MAP after ",
                                      passes_ + 1, " passes: ", caustic_count,
                                      " caustic photons of ", sizeof(Photon), " bytes"),
                       "lower PhotonLatticeSettings.photons or use caustics = LATTICE");
        caustic_photons.reserve(caustic_count);
        append_photons(caustic_photons, caustic_map_.photons(), progress);
        append_photons(caustic_photons, caustic_photons_of_pass, progress);
    }
    timings.injection = seconds_since(start);

    if (progress != nullptr) progress->begin_stage("blur", 0.95f, 1.0f);
    start = now();
    const float average = 1.0f / float(passes_ + 1);
    ShLattice global = global_raw;
    global.scale(average);
    global.blur(settings_.blur_passes);
    ShLattice caustic = caustic_raw;
    if (settings_.caustics == CausticMode::Lattice) {
        caustic.scale(average);
        caustic.blur(settings_.caustic_blur_passes);
    }
    PhotonMap caustic_map;
    if (settings_.caustics == CausticMode::PhotonMap)
        caustic_map = PhotonMap(std::move(caustic_photons), average, progress);
    timings.blur = seconds_since(start);
    throw_if_cancelled(progress);

    global_raw_ = std::move(global_raw);
    caustic_raw_ = std::move(caustic_raw);
    global_ = std::move(global);
    caustic_ = std::move(caustic);
    caustic_map_ = std::move(caustic_map);
    caustic_photons_injected_ = caustic_injected;
    ++passes_;
    timings_ = timings;
    if (progress != nullptr) progress->set_fraction(1.0f);
}

ShRgb PhotonLattice::sample(const ShLattice& lattice, const vec3& p, const vec3& n) const {
    return settings_.interpolation == LatticeInterpolation::Cubic
               ? lattice.sample_cubic(p, n, settings_.normal_offset)
               : lattice.sample_trilinear(p, n, settings_.normal_offset);
}

// Called for every shading point of every preview frame: the global sample is the result (no
// zeroed sum to add it to, no copy: one named result, so that it is built in the caller's
// place), and a caustic lattice without photons is not sampled.
ShRgb PhotonLattice::radiance_sh(const vec3& p, const vec3& n) const {
    const int order = settings_.caustics == CausticMode::Lattice
                          ? std::max(settings_.order, settings_.caustic_order)
                          : settings_.order;
    ShRgb result = passes_ == 0 ? ShRgb(order) : sample(global_, p, n);
    result.order = order;  // at least the global lattice's; the extra coefficients are zero
    if (passes_ > 0 && settings_.caustics == CausticMode::Lattice &&
        caustic_photons_injected_ > 0)
        add_sh(result, sample(caustic_, p, n));
    return result;
}

// One returned prvalue, every member given, so that the lookup is built in the caller's place
// member by member: GCC 12 cleared a named result whole first (a `rep stos` of its 0.34 KB, ~70%
// of this function's CPU samples) before radiance_sh overwrote most of it. radiance_sh
// is called directly (no class derives from PhotonLattice): one indirect call a lookup fewer.
FieldLookup PhotonLattice::lookup(const vec3& p, const vec3& n) const {
    return FieldLookup{PhotonLattice::radiance_sh(p, n), caustic_map_irradiance(p, n),
                       /*diffuse_rays=*/0, /*glossy_rays=*/0, /*gather_key=*/0,
                       /*horizon=*/true};  // each cell holds what its surfaces receive
}

vec3 PhotonLattice::caustic_map_irradiance(const vec3& p, const vec3& n) const {
    if (settings_.caustics != CausticMode::PhotonMap || caustic_map_.size() == 0)
        return vec3(0.0f);
    return caustic_map_.irradiance(p, n, settings_.caustic_neighbours, caustic_radius_);
}

float PhotonLattice::reuse_distance() const {
    constexpr float kReuseShare = 0.25f;
    float distance = global_.cell_size();
    if (settings_.caustics == CausticMode::Lattice && caustic_photons_injected_ > 0)
        distance = std::min(distance, caustic_.cell_size());
    if (settings_.caustics == CausticMode::PhotonMap && caustic_map_.size() > 0)
        distance = std::min(distance, caustic_radius_);
    return kReuseShare * distance;
}

std::shared_ptr<const IndirectField> PhotonLattice::current_field() const {
    // Non-owning: the lattice is its own field, valid until the next solve() or reset().
    return std::shared_ptr<const IndirectField>(std::shared_ptr<const IndirectField>(), this);
}

std::vector<StageSeconds> PhotonLattice::stage_seconds() const {
    return {{"emit_trace", timings_.emit_trace},
            {"injection", timings_.injection},
            {"blur", timings_.blur}};
}

size_t PhotonLattice::memory_bytes() const {
    return global_raw_.memory_bytes() + global_.memory_bytes() + caustic_raw_.memory_bytes() +
           caustic_.memory_bytes() + caustic_map_.size() * sizeof(Photon);
}

}  // namespace shgi
