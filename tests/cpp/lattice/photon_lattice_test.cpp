// PhotonLattice against closed forms: the emissive white furnace (every wall of a closed box
// emits Le and reflects albedo a), where the indirect light is uniform and known bounce by bounce;
// plus interactive passes, reset, scene edits, cancel, thread-count independence, caustic modes
// and settings checks.
//
// Furnace: the box [-1, 1]^3 seen from inside, Lambert albedo a, emission Le on the inner side of
// every wall (emissive triangles also emit from their outer side; those photons leave the scene).
// The radiance leaving every wall is Le / (1 - a) (with unlimited bounces). The photon tracer
// does not store the first hit after emission (that is direct light, which renderers compute
// exactly), and stores a photon after each of its m = 1..M scatterings (M = max_bounces), so the
// field holds the uniform incident radiance
//     L_ind = Le (a + a^2 + ... + a^M)
// over each wall's hemisphere and the lattice irradiance at any wall point is pi L_ind.
//
// Noise is estimated from independent solves (seeds), each averaged over many probe points;
// comparisons allow kSigmas standard errors of that mean plus the density estimate's documented
// grazing-floor bias (lattice/sh_lattice.h: at most pi L f / 4, f = kMinProjectedFraction).
#include "lattice/photon_lattice.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "lattice/lattice_test_scenes.h"
#include "render/render_test_scenes.h"
#include "support/expect_error.h"
#include "support/noise_stats.h"
#include "support/test_folder.h"
#include "util/error.h"

namespace shgi {
namespace {

using test::kFloorBias;
using testing::BatchStats;

constexpr float kFurnaceAlbedo = 0.5f;
constexpr int kFurnaceBounces = 4;
const vec3 kFurnaceEmission(1.0f, 0.5f, 0.25f);  // Le, W m^-2 sr^-1
constexpr int kFurnaceResolution = 8;            // cells of 0.25 m
constexpr uint64_t kFurnacePhotons = 100000;
constexpr int kFurnaceSolves = 6;                // independent seeds for the standard error

// Le (a + ... + a^M): the incident radiance of light that scattered 1..M times.
vec3 furnace_indirect_radiance(float albedo, const vec3& emission, int max_bounces) {
    double sum = 0.0;
    for (int m = 1; m <= max_bounces; ++m) sum += std::pow(double(albedo), m);
    return emission * float(sum);
}

PhotonLatticeSettings furnace_settings(uint64_t seed) {
    PhotonLatticeSettings settings;
    settings.photons = kFurnacePhotons;
    settings.seed = seed;
    settings.max_bounces = kFurnaceBounces;
    settings.resolution = kFurnaceResolution;
    return settings;
}

struct Probe {
    vec3 position;
    vec3 normal;  // into the box
};

// Points on the inner side of every wall of the box [-1, 1]^3 at in-wall coordinates (u, v) for
// every pair in `uv` (the same on all six walls).
std::vector<Probe> wall_probes(const std::vector<vec2>& uv) {
    std::vector<Probe> probes;
    for (int axis = 0; axis < 3; ++axis)
        for (float side : {-1.0f, 1.0f})
            for (const vec2& coords : uv) {
                Probe probe;
                probe.position[axis] = side;
                probe.position[(axis + 1) % 3] = coords.x;
                probe.position[(axis + 2) % 3] = coords.y;
                probe.normal = vec3(0.0f);
                probe.normal[axis] = -side;
                probes.push_back(probe);
            }
    return probes;
}

// 3 x 3 points per wall, at least 2.5 cells (0.625 m) from every edge at resolution 8: their
// cubic neighbourhoods hold cells of that wall only.
std::vector<Probe> face_centre_probes() {
    std::vector<vec2> uv;
    for (float u : {-0.375f, 0.0f, 0.375f})
        for (float v : {-0.375f, 0.0f, 0.375f}) uv.push_back(vec2(u, v));
    return wall_probes(uv);
}

// Per wall, 3 points along each of its 4 edges, 0.1 m (0.4 cells) from the edge: their cells
// also hold the neighbouring wall.
std::vector<Probe> edge_probes() {
    std::vector<vec2> uv;
    for (float along : {-0.375f, 0.0f, 0.375f})
        for (float edge : {-0.9f, 0.9f}) {
            uv.push_back(vec2(edge, along));
            uv.push_back(vec2(along, edge));
        }
    return wall_probes(uv);
}

// Per wall, its 4 corners at 0.1 m (0.4 cells) from both edges: their cells hold three walls.
std::vector<Probe> corner_probes() {
    std::vector<vec2> uv;
    for (float u : {-0.9f, 0.9f})
        for (float v : {-0.9f, 0.9f}) uv.push_back(vec2(u, v));
    return wall_probes(uv);
}

vec3 mean_irradiance(const IndirectField& field, const std::vector<Probe>& probes) {
    glm::dvec3 sum(0.0);
    for (const Probe& probe : probes)
        sum += glm::dvec3(field.irradiance(probe.position, probe.normal));
    return vec3(sum / double(probes.size()));
}

// The probe-averaged irradiance of kFurnaceSolves independently seeded one-pass lattices, per
// channel.
BatchStats furnace_irradiance(const Scene& scene, const std::vector<Probe>& probes) {
    BatchStats stats;
    for (int solve = 0; solve < kFurnaceSolves; ++solve) {
        PhotonLattice lattice(scene, furnace_settings(uint64_t(solve) + 1));
        lattice.solve();
        stats.add(mean_irradiance(lattice, probes));
    }
    return stats;
}

void expect_furnace_irradiance(const BatchStats& stats, const char* where) {
    const vec3 expected =
        kPi * furnace_indirect_radiance(kFurnaceAlbedo, kFurnaceEmission, kFurnaceBounces);
    for (int c = 0; c < 3; ++c) {
        testing::expect_within_noise(stats.mean(c), stats.standard_error(c), expected[c],
                                     kFloorBias * expected[c],
                                     std::string(where) + ", channel " + std::to_string(c) +
                                         ": measured/expected = " +
                                         std::to_string(stats.mean(c) / expected[c]));
    }
}

TEST(PhotonLattice, FurnaceIrradianceAtFaceCentres) {
    const Scene scene = test::emissive_furnace(kFurnaceAlbedo, kFurnaceEmission, 1.0f);
    expect_furnace_irradiance(furnace_irradiance(scene, face_centre_probes()), "face centres");
}

// The furnace's indirect light is uniform, so points next to an edge, whose lattice cells also
// hold the perpendicular wall, must receive pi L_ind as well.
TEST(PhotonLattice, FurnaceIrradianceNextToEdges) {
    const Scene scene = test::emissive_furnace(kFurnaceAlbedo, kFurnaceEmission, 1.0f);
    expect_furnace_irradiance(furnace_irradiance(scene, edge_probes()), "next to edges");
}

// Likewise at the corners, where three walls share a cell.
TEST(PhotonLattice, FurnaceIrradianceNextToCorners) {
    const Scene scene = test::emissive_furnace(kFurnaceAlbedo, kFurnaceEmission, 1.0f);
    expect_furnace_irradiance(furnace_irradiance(scene, corner_probes()), "next to corners");
}

// --- settings and scene checks ---

// A closed room with a point light and a mirror sphere (caustic photons), diffuse walls.
Scene room_with_mirror_sphere() {
    Scene scene;
    scene.add_material(test::lambert(0.7f));
    scene.add_material(test::mirror(1.0f));
    scene.add_instance(scene.add_mesh(test::inward_box(1.0f)), mat4(1.0f));
    Mesh sphere = test::uv_sphere(0.3f, 8, 16);
    sphere.material_indices.assign(sphere.triangles.size(), 1);
    scene.add_instance(scene.add_mesh(sphere), glm::translate(mat4(1.0f), vec3(0.2f, 0.0f, -0.5f)));
    scene.add_light(test::point_light(vec3(-0.1f, 0.2f, 0.6f), 100.0f));
    scene.set_world(test::black_world());
    scene.commit();
    return scene;
}

PhotonLatticeSettings small_settings() {
    PhotonLatticeSettings settings;
    settings.photons = 20000;
    settings.seed = 3;
    settings.resolution = 8;
    settings.caustic_resolution = 16;
    return settings;
}

TEST(PhotonLattice, RejectsInvalidSettingsNamingTheField) {
    const Scene scene = room_with_mirror_sphere();
    // Each edit of small_settings() must be rejected by the validator and by the constructor, with
    // a message containing `expected`.
    const struct {
        std::function<void(PhotonLatticeSettings&)> edit;
        const char* expected;
    } cases[] = {
        {[](PhotonLatticeSettings& s) { s.order = 3; }, "PhotonLatticeSettings.order is 3"},
        {[](PhotonLatticeSettings& s) { s.order = 0; }, "PhotonLatticeSettings.order is 0"},
        {[](PhotonLatticeSettings& s) { s.resolution = 0; },
         "PhotonLatticeSettings.resolution is 0"},
        {[](PhotonLatticeSettings& s) { s.resolution = 1025; },
         "PhotonLatticeSettings.resolution is 1025"},
        {[](PhotonLatticeSettings& s) { s.blur_passes = -1; }, "PhotonLatticeSettings.blur_passes"},
        {[](PhotonLatticeSettings& s) { s.caustic_resolution = 0; },
         "PhotonLatticeSettings.caustic_resolution"},
        {[](PhotonLatticeSettings& s) { s.caustic_order = 3; },
         "PhotonLatticeSettings.caustic_order"},
        {[](PhotonLatticeSettings& s) { s.caustic_blur_passes = 65; },
         "PhotonLatticeSettings.caustic_blur_passes"},
        {[](PhotonLatticeSettings& s) { s.caustic_neighbours = 0; },
         "PhotonLatticeSettings.caustic_neighbours"},
        {[](PhotonLatticeSettings& s) { s.caustic_radius = -1.0f; },
         "PhotonLatticeSettings.caustic_radius"},
        {[](PhotonLatticeSettings& s) { s.caustic_radius = std::nanf(""); },
         "PhotonLatticeSettings.caustic_radius"},
        {[](PhotonLatticeSettings& s) { s.normal_offset = 2.5f; },
         "PhotonLatticeSettings.normal_offset"},
        {[](PhotonLatticeSettings& s) {
             s.use_bounds = true;
             s.bounds_min = vec3(0.0f);
             s.bounds_max = vec3(1.0f, 0.0f, 1.0f);  // empty along y
         },
         "PhotonLatticeSettings.bounds_min/bounds_max"},
        // Fields forwarded to the photon tracer: the caller sets PhotonLatticeSettings (in C++,
        // Python and the add-on), so the message names them under that name too (STYLE.md,
        // habit 6: errors name the bad input).
        {[](PhotonLatticeSettings& s) { s.photons = 0; }, "PhotonLatticeSettings.photons"},
        {[](PhotonLatticeSettings& s) { s.max_bounces = 0; }, "PhotonLatticeSettings.max_bounces"},
        {[](PhotonLatticeSettings& s) { s.glossy_bounces = -2; },
         "PhotonLatticeSettings.glossy_bounces"},
        {[](PhotonLatticeSettings& s) { s.specular_roughness = 1.5f; },
         "PhotonLatticeSettings.specular_roughness"},
        {[](PhotonLatticeSettings& s) { s.specular_roughness = -0.5f; },
         "PhotonLatticeSettings.specular_roughness"},
    };
    for (const auto& c : cases) {
        PhotonLatticeSettings settings = small_settings();
        c.edit(settings);
        testing::expect_invalid_argument([&] { validate_photon_lattice_settings(settings); },
                                         c.expected);
        testing::expect_invalid_argument([&] { PhotonLattice lattice(scene, settings); },
                                         c.expected);
    }
}

TEST(PhotonLattice, RefusesEmptyAndUncommittedScenes) {
    Scene empty;
    empty.commit();
    testing::expect_invalid_argument([&] { PhotonLattice lattice(empty, small_settings()); },
                                     "no geometry");
    Scene uncommitted;
    uncommitted.add_material(test::lambert(0.5f));
    uncommitted.add_instance(uncommitted.add_mesh(test::inward_box(1.0f)), mat4(1.0f));
    testing::expect_invalid_argument(
        [&] { PhotonLattice lattice(uncommitted, small_settings()); }, "commit");
}

// --- passes, determinism, reset, edits, cancel ---

std::vector<float> global_coefficients(const PhotonLattice& lattice) {
    return lattice.global_lattice().coefficients();
}

// Two passes with 1 and with 2 threads: every lattice coefficient and the caustic photon map's
// density estimate are bit-identical (docs/architecture.md, "Determinism").
TEST(PhotonLattice, BitIdenticalForAnyThreadCount) {
    const Scene scene = room_with_mirror_sphere();
    const std::vector<Probe> probes = face_centre_probes();
    for (CausticMode mode : {CausticMode::Lattice, CausticMode::PhotonMap}) {
        PhotonLatticeSettings settings = small_settings();
        settings.caustics = mode;
        const auto solve_twice = [&](int threads) {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                      size_t(threads));
            auto lattice = std::make_unique<PhotonLattice>(scene, settings);
            lattice->solve();
            lattice->solve();
            return lattice;
        };
        const auto one = solve_twice(1);
        const auto two = solve_twice(2);
        EXPECT_EQ(one->passes(), 2u);
        EXPECT_EQ(global_coefficients(*one), global_coefficients(*two));
        EXPECT_EQ(one->caustic_lattice().coefficients(), two->caustic_lattice().coefficients());
        EXPECT_EQ(one->caustic_map().size(), two->caustic_map().size());
        // The mirror sphere focuses caustic photons into the caustic lattice or map.
        if (mode == CausticMode::Lattice) {
            const std::vector<float>& caustic = one->caustic_lattice().coefficients();
            EXPECT_TRUE(std::any_of(caustic.begin(), caustic.end(),
                                    [](float c) { return c != 0.0f; }));
        } else {
            EXPECT_GT(one->caustic_map().size(), 0u);
        }
        for (const Probe& probe : probes) {
            const FieldLookup a = one->lookup(probe.position, probe.normal);
            const FieldLookup b = two->lookup(probe.position, probe.normal);
            EXPECT_EQ(a.extra_irradiance, b.extra_irradiance);
            EXPECT_EQ(a.irradiance(probe.normal), b.irradiance(probe.normal));
        }
    }
}

// A solved lattice saved and loaded back looks up the same light at every probe: bit for bit
// with a caustic lattice; with a caustic photon map, whose k-d tree is rebuilt, within float
// rounding of its sums. The loaded lattice keeps settings, passes and timings, has no scene
// (solve() names the file), and a truncated or foreign file is refused by name.
TEST(PhotonLattice, SavedAndLoadedLookUpTheSameLight) {
    // Relative rounding of a density estimate summed in another order (float32, ~50 photons).
    constexpr float kRebuiltMapTolerance = 1e-5f;
    const Scene scene = room_with_mirror_sphere();
    for (CausticMode mode : {CausticMode::Lattice, CausticMode::PhotonMap}) {
        PhotonLatticeSettings settings = small_settings();
        settings.caustics = mode;
        PhotonLattice solved(scene, settings);
        solved.solve();
        solved.solve();
        const std::string path = testing::test_file_path(
            "lattice", mode == CausticMode::Lattice ? "lattice.shlattice" : "map.shlattice");
        solved.save(path);
        const std::unique_ptr<PhotonLattice> loaded = PhotonLattice::load(path);
        EXPECT_EQ(loaded->passes(), 2u);
        EXPECT_EQ(loaded->settings().caustics, mode);
        EXPECT_EQ(loaded->timings().photons_emitted, solved.timings().photons_emitted);
        EXPECT_EQ(global_coefficients(*loaded), global_coefficients(solved));
        EXPECT_EQ(loaded->caustic_map().size(), solved.caustic_map().size());
        EXPECT_EQ(loaded->reuse_distance(), solved.reuse_distance());
        for (const Probe& probe : face_centre_probes()) {
            const FieldLookup a = solved.lookup(probe.position, probe.normal);
            const FieldLookup b = loaded->lookup(probe.position, probe.normal);
            ASSERT_EQ(a.radiance.order, b.radiance.order);
            for (int i = 0; i < 3 * a.radiance.num_coefficients(); ++i)
                EXPECT_EQ(a.radiance.data()[i], b.radiance.data()[i]);
            for (int k = 0; k < 3; ++k)
                EXPECT_NEAR(a.extra_irradiance[k], b.extra_irradiance[k],
                            kRebuiltMapTolerance * std::abs(a.extra_irradiance[k]));
        }
        testing::expect_invalid_argument([&] { loaded->solve(); }, path);
    }
    const std::string truncated = testing::test_file_path("lattice", "truncated.shlattice");
    testing::write_file(truncated, "SHGILAT");
    testing::expect_error<IoError>([&] { PhotonLattice::load(truncated); },
                                   {truncated, "ends inside the header"});
    const std::string foreign = testing::test_file_path("lattice", "foreign.shlattice");
    testing::write_file(foreign, "not a lattice at all");
    testing::expect_error<IoError>([&] { PhotonLattice::load(foreign); },
                                   {foreign, "not an SHGI lattice file"});
}

// The lattices hold the average of all passes: two solves equal (bit for bit) the two photon
// passes of trace_photons injected into one lattice, halved and blurred, and differ from one pass.
TEST(PhotonLattice, InteractivePassesHoldTheAverageOfAllPasses) {
    const Scene scene = room_with_mirror_sphere();
    const PhotonLatticeSettings settings = small_settings();
    PhotonLattice lattice(scene, settings);
    lattice.solve();
    const std::vector<float> one_pass = global_coefficients(lattice);
    lattice.solve();
    EXPECT_EQ(lattice.passes(), 2u);
    EXPECT_EQ(lattice.timings().photons_emitted, settings.photons);
    EXPECT_NE(global_coefficients(lattice), one_pass);

    const PhotonTracerSettings tracer = photon_lattice_tracer_settings(settings);
    ShLattice expected(scene.bounds(), settings.resolution, settings.order);
    expected.measure_surfaces(scene);
    for (uint64_t pass = 0; pass < 2; ++pass)
        expected.inject(trace_photons(scene, tracer, pass).global, 1.0f);
    expected.scale(0.5f);
    expected.blur(settings.blur_passes);
    EXPECT_EQ(global_coefficients(lattice), expected.coefficients());
}

// Statistically, two passes of N photons are one pass of 2N: the furnace's mean face-centre
// irradiance agrees within the noise (estimated from the spread of the six walls' means), and
// both agree with pi L_ind.
TEST(PhotonLattice, TwoPassesOfNPhotonsMatchOnePassOf2N) {
    const Scene scene = test::emissive_furnace(kFurnaceAlbedo, kFurnaceEmission, 1.0f);
    const std::vector<Probe> probes = face_centre_probes();
    const size_t per_wall = probes.size() / 6;
    const auto wall_means = [&](const PhotonLattice& lattice) {
        std::vector<double> means(6, 0.0);
        for (size_t i = 0; i < probes.size(); ++i)
            means[i / per_wall] +=
                lattice.irradiance(probes[i].position, probes[i].normal).x / double(per_wall);
        return means;
    };
    PhotonLattice two_passes(scene, furnace_settings(11));
    two_passes.solve();
    two_passes.solve();
    PhotonLatticeSettings doubled = furnace_settings(11);
    doubled.photons *= 2;
    PhotonLattice one_pass(scene, doubled);
    one_pass.solve();

    const std::vector<double> a = wall_means(two_passes), b = wall_means(one_pass);
    double sum_a = 0, sum_b = 0, sum_d2 = 0;
    for (int w = 0; w < 6; ++w) {
        sum_a += a[w];
        sum_b += b[w];
    }
    const double mean_a = sum_a / 6.0, mean_b = sum_b / 6.0;
    for (int w = 0; w < 6; ++w) sum_d2 += std::pow((a[w] - b[w]) - (mean_a - mean_b), 2);
    const double standard_error = std::sqrt(sum_d2 / 5.0 / 6.0);
    EXPECT_NE(mean_a, mean_b);
    testing::expect_within_noise(mean_a, standard_error, mean_b, 0.0,
                                 "two passes vs one pass of 2N");
    const double expected =
        kPi * furnace_indirect_radiance(kFurnaceAlbedo, kFurnaceEmission, kFurnaceBounces).x;
    for (double measured : {mean_a, mean_b})
        testing::expect_within_noise(measured, standard_error, expected, kFloorBias * expected,
                                     "mean face-centre irradiance");
}

TEST(PhotonLattice, ResetForgetsEveryPass) {
    const Scene scene = room_with_mirror_sphere();
    PhotonLattice lattice(scene, small_settings());
    lattice.solve();
    const std::vector<float> first = global_coefficients(lattice);
    lattice.solve();
    lattice.reset();
    EXPECT_EQ(lattice.passes(), 0u);
    for (float c : global_coefficients(lattice)) ASSERT_EQ(c, 0.0f);
    for (float c : lattice.caustic_lattice().coefficients()) ASSERT_EQ(c, 0.0f);
    for (const Probe& probe : face_centre_probes())
        EXPECT_EQ(lattice.irradiance(probe.position, probe.normal), vec3(0.0f));
    // The pass count starts over, so the next solve repeats the first pass exactly.
    lattice.solve();
    EXPECT_EQ(lattice.passes(), 1u);
    EXPECT_EQ(global_coefficients(lattice), first);
}

TEST(PhotonLattice, SolveAfterASceneEditThrowsUntilReset) {
    Scene scene = room_with_mirror_sphere();
    PhotonLattice lattice(scene, small_settings());
    lattice.solve();
    const std::vector<float> before = global_coefficients(lattice);
    Light extra;
    extra.world_from_light = glm::translate(mat4(1.0f), vec3(0.5f, 0.5f, 0.5f));
    scene.add_light(extra);  // un-commits the scene
    testing::expect_invalid_argument([&] { lattice.solve(); }, "edited");
    scene.commit();
    testing::expect_invalid_argument([&] { lattice.solve(); }, "call reset()");
    EXPECT_EQ(lattice.passes(), 1u);
    EXPECT_EQ(global_coefficients(lattice), before);
    lattice.reset();
    lattice.solve();
    EXPECT_EQ(lattice.passes(), 1u);
    EXPECT_NE(global_coefficients(lattice), before);  // the extra light adds photons
}

// A cancel in any stage of solve() throws Cancelled and keeps the previous solution bit for bit;
// the next solve then continues as if the cancelled one never happened.
TEST(PhotonLattice, CancelKeepsThePreviousSolution) {
    const Scene scene = room_with_mirror_sphere();
    PhotonLatticeSettings settings = small_settings();
    PhotonLattice reference(scene, settings);
    reference.solve();
    reference.solve();
    for (const char* stage : {"photons", "injection", "blur"}) {
        PhotonLattice lattice(scene, settings);
        lattice.solve();
        const std::vector<float> before = global_coefficients(lattice);
        const std::vector<float> caustic_before = lattice.caustic_lattice().coefficients();
        Progress* self = nullptr;
        Progress progress([&](float, const std::string& name) {
            if (name == stage) self->cancel();
        });
        self = &progress;
        EXPECT_THROW(lattice.solve(&progress), Cancelled) << "stage " << stage;
        EXPECT_EQ(lattice.passes(), 1u) << "stage " << stage;
        EXPECT_EQ(global_coefficients(lattice), before) << "stage " << stage;
        EXPECT_EQ(lattice.caustic_lattice().coefficients(), caustic_before) << "stage " << stage;
        lattice.solve();
        EXPECT_EQ(global_coefficients(lattice), global_coefficients(reference))
            << "stage " << stage;
    }
}

// Without specular surfaces there are no caustic photons: Off, Lattice and PhotonMap give the
// same global lattice and the same irradiance everywhere, with no extra irradiance.
TEST(PhotonLattice, CausticModesAgreeWithoutSpecularSurfaces) {
    const Scene scene = test::emissive_furnace(kFurnaceAlbedo, kFurnaceEmission, 1.0f);
    std::vector<std::unique_ptr<PhotonLattice>> lattices;
    for (CausticMode mode : {CausticMode::Off, CausticMode::Lattice, CausticMode::PhotonMap}) {
        PhotonLatticeSettings settings = furnace_settings(5);
        settings.photons = 20000;
        settings.caustics = mode;
        lattices.push_back(std::make_unique<PhotonLattice>(scene, settings));
        lattices.back()->solve();
    }
    EXPECT_EQ(lattices[2]->caustic_map().size(), 0u);
    const std::vector<Probe> probes = edge_probes();
    for (size_t m = 1; m < lattices.size(); ++m) {
        EXPECT_EQ(global_coefficients(*lattices[m]), global_coefficients(*lattices[0]));
        for (const Probe& probe : probes) {
            const FieldLookup lookup = lattices[m]->lookup(probe.position, probe.normal);
            EXPECT_EQ(lookup.extra_irradiance, vec3(0.0f));
            EXPECT_EQ(lookup.irradiance(probe.normal),
                      lattices[0]->irradiance(probe.position, probe.normal))
                << "mode " << m;
        }
    }
}

// Photon lists equal byte for byte (positions, powers, normals, directions).
bool same_photons(const std::vector<Photon>& a, const std::vector<Photon>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Photon)) == 0);
}

// Photons [cuts[i], cuts[i + 1]) of pass `pass`, each batch traced apart and carried through its
// bytes (as between the machines of a farm), handed over last batch first.
std::vector<PhotonBatch> traced_batches(const Scene& scene, const PhotonLatticeSettings& settings,
                                        uint64_t pass, const std::vector<uint64_t>& cuts) {
    std::vector<PhotonBatch> batches;
    for (size_t i = cuts.size() - 1; i > 0; --i)
        batches.push_back(PhotonBatch::from_bytes(
            trace_photon_batch(scene, settings, pass, cuts[i - 1], cuts[i]).to_bytes()));
    return batches;
}

// A solve split over machines: each pass's photons in batches of consecutive photons, traced
// apart and merged by solve_batches(), equal the single solve bit for bit, for splits on and off
// the tracer's 4096-photon chunks (a batch of one photon too), with 1 and 2 threads, with a
// caustic lattice and a caustic photon map. The batches hold the pass's photons exactly.
TEST(PhotonLattice, AnyBatchSplitEqualsTheWholeSolve) {
    const Scene scene = room_with_mirror_sphere();
    const std::vector<Probe> probes = face_centre_probes();
    for (CausticMode mode : {CausticMode::Lattice, CausticMode::PhotonMap}) {
        PhotonLatticeSettings settings = small_settings();  // 20000 photons
        settings.caustics = mode;
        for (int threads : {1, 2}) {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                                      size_t(threads));
            PhotonLattice whole(scene, settings);
            whole.solve();
            whole.solve();
            PhotonLattice merged(scene, settings);
            const std::vector<PhotonBatch> first =
                traced_batches(scene, settings, 0, {0, 1, 4096, 9001, 12288, 20000});
            // The batches' photons, in photon order, are the whole pass's photon lists.
            const PhotonMaps maps =
                trace_photons(scene, photon_lattice_tracer_settings(settings), 0);
            std::vector<Photon> global, caustic;
            for (auto batch = first.rbegin(); batch != first.rend(); ++batch) {
                global.insert(global.end(), batch->global.begin(), batch->global.end());
                caustic.insert(caustic.end(), batch->caustic.begin(), batch->caustic.end());
            }
            EXPECT_TRUE(same_photons(global, maps.global));
            EXPECT_TRUE(same_photons(caustic, maps.caustic));
            EXPECT_GT(caustic.size(), 0u);  // the mirror sphere's caustics are in the batches
            merged.solve_batches(first);
            merged.solve_batches(traced_batches(scene, settings, 1, {0, 7000, 20000}));
            EXPECT_EQ(merged.passes(), 2u);
            EXPECT_EQ(merged.timings().photons_emitted, whole.timings().photons_emitted);
            EXPECT_EQ(merged.timings().photons_stored, whole.timings().photons_stored);
            EXPECT_EQ(merged.timings().bounces, whole.timings().bounces);
            EXPECT_EQ(global_coefficients(merged), global_coefficients(whole))
                << "threads " << threads;
            EXPECT_EQ(merged.caustic_lattice().coefficients(),
                      whole.caustic_lattice().coefficients());
            EXPECT_TRUE(
                same_photons(merged.caustic_map().photons(), whole.caustic_map().photons()));
            EXPECT_EQ(merged.caustic_map().power_scale(), whole.caustic_map().power_scale());
            for (const Probe& probe : probes) {
                const FieldLookup a = merged.lookup(probe.position, probe.normal);
                const FieldLookup b = whole.lookup(probe.position, probe.normal);
                EXPECT_EQ(a.extra_irradiance, b.extra_irradiance);
                EXPECT_EQ(a.irradiance(probe.normal), b.irradiance(probe.normal));
            }
        }
    }
}

// solve_batches() takes only the batches of its own next pass, with its settings, covering its
// photons exactly; a refused merge changes nothing. Damaged bytes are refused by name.
TEST(PhotonLattice, SolveBatchesRefusesBatchesThatDoNotMakeThePass) {
    const Scene scene = room_with_mirror_sphere();
    const PhotonLatticeSettings settings = small_settings();
    PhotonLattice lattice(scene, settings);
    lattice.solve();
    const std::vector<float> before = global_coefficients(lattice);
    PhotonLatticeSettings other = settings;
    other.resolution = 9;  // the same photons, but not this lattice's settings
    testing::expect_invalid_argument(
        [&] { lattice.solve_batches(traced_batches(scene, other, 1, {0, 20000})); },
        "other settings than the lattice's (resolution 9 instead of 8)");
    testing::expect_invalid_argument(
        [&] { lattice.solve_batches(traced_batches(scene, settings, 0, {0, 20000})); },
        "is of pass 0, the lattice's next pass is 1");
    std::vector<PhotonBatch> gap = traced_batches(scene, settings, 1, {0, 5000});
    gap.push_back(trace_photon_batch(scene, settings, 1, 6000, 20000));
    testing::expect_invalid_argument([&] { lattice.solve_batches(gap); },
                                     "after [0, 5000) comes a batch of [6000, 20000)");
    std::vector<PhotonBatch> overlap = traced_batches(scene, settings, 1, {0, 5000, 20000});
    overlap.push_back(trace_photon_batch(scene, settings, 1, 4000, 5000));
    testing::expect_invalid_argument([&] { lattice.solve_batches(overlap); },
                                     "without gaps or overlaps");
    testing::expect_invalid_argument(
        [&] { lattice.solve_batches(traced_batches(scene, settings, 1, {0, 19999})); },
        "photons [19999, 20000) are missing");
    testing::expect_invalid_argument(
        [&] { lattice.solve_batches(std::vector<PhotonBatch>{}); }, "no batches");
    testing::expect_invalid_argument([&] { trace_photon_batch(scene, settings, 1, 5, 5); },
                                     "it needs begin < end <= 20000");
    testing::expect_invalid_argument([&] { trace_photon_batch(scene, settings, 1, 0, 20001); },
                                     "it needs begin < end <= 20000");
    EXPECT_EQ(lattice.passes(), 1u);
    EXPECT_EQ(global_coefficients(lattice), before);

    // A cancel while merging keeps the previous solution too.
    Progress cancelled;
    cancelled.cancel();
    EXPECT_THROW(lattice.solve_batches(traced_batches(scene, settings, 1, {0, 20000}), &cancelled),
                 Cancelled);
    EXPECT_THROW(trace_photon_batch(scene, settings, 1, 0, 20000, &cancelled), Cancelled);
    EXPECT_EQ(lattice.passes(), 1u);
    EXPECT_EQ(global_coefficients(lattice), before);

    const std::string bytes = trace_photon_batch(scene, settings, 1, 0, 100).to_bytes();
    testing::expect_error<IoError>(
        [&] { PhotonBatch::from_bytes(bytes.substr(0, bytes.size() - 1), "batch 3"); },
        {"batch 3", "the caustic photons", "truncated?"});
    testing::expect_error<IoError>([&] { PhotonBatch::from_bytes(bytes + "x", "batch 3"); },
                                   {"batch 3", "data after its end"});
    testing::expect_error<IoError>([&] { PhotonBatch::from_bytes("a lattice?", "batch 3"); },
                                   {"batch 3", "not an SHGI photon batch"});
}

}  // namespace
}  // namespace shgi
