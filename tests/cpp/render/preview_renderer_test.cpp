// PreviewRenderer against closed forms: exact direct light from a point light over a Lambert
// plane (with no field, with a ZeroField, and next to the reference path tracer), indirect light
// from a constant field (DiffInd = the field's radiance), a mirror that shows the field on the
// surface it reflects, and a field that carries the world's direct light; plus progressive
// accumulation, thread-count independence, the screen-space reuse of field lookups, cancel,
// scene edits and settings checks.
//
// Pass definitions (render/film.h): DiffDir and DiffInd are the light reaching the camera through
// the diffuse lobe divided by DiffCol, so on a Lambert surface of albedo rho under a point light
// of intensity I at distance d and incidence angle theta, DiffDir = E / pi with E = I cos(theta)
// / d^2, and under a uniform incident radiance L (SH field) DiffInd = (rho E / pi) / rho = L.
#include "render/preview_renderer.h"
#include "render/path_integrator.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "lattice/photon_lattice.h"
#include "probes/probe_grid.h"
#include "render_test_scenes.h"
#include "support/expect_error.h"
#include "support/noise_stats.h"
#include "util/cpu_features.h"
#include "util/error.h"

namespace shgi {
namespace {

using testing::kSigmas;

// Float rounding of per-pixel sums over a few dozen samples and of SH evaluation.
constexpr double kRoundingTolerance = 1e-5;
// Sub-pixel quadrature points per axis for the expected pixel averages.
constexpr int kPixelQuadrature = 16;

// Uniform incident radiance L from every direction as SH: only L00 = L sqrt(4 pi) (the
// projection of a constant), whose irradiance is pi L at every normal.
class ConstantField : public IndirectField {
  public:
    explicit ConstantField(const vec3& radiance, bool world_direct = false)
        : world_direct_(world_direct) {
        sh_[0] = radiance * std::sqrt(kFourPi);
    }
    ShRgb radiance_sh(const vec3&, const vec3&) const override { return sh_; }
    bool includes_world_direct() const override { return world_direct_; }

  private:
    ShRgb sh_{2};
    bool world_direct_;
};

// Wraps a field and cancels `progress` at its `cancel_at`-th lookup: a cancel in the middle of
// the shading stage, after some samples were accumulated.
class CancellingField : public IndirectField {
  public:
    CancellingField(const IndirectField& inner, Progress& progress, uint64_t cancel_at)
        : inner_(inner), progress_(progress), cancel_at_(cancel_at) {}
    ShRgb radiance_sh(const vec3& p, const vec3& n) const override {
        if (++lookups_ == cancel_at_) progress_.cancel();
        return inner_.radiance_sh(p, n);
    }
    uint64_t lookups() const { return lookups_.load(); }

  private:
    const IndirectField& inner_;
    Progress& progress_;
    uint64_t cancel_at_;
    mutable std::atomic<uint64_t> lookups_{0};
};

// Wraps a field, counts its lookups and allows screen-space reuse within `reuse` metres.
class CountingField : public IndirectField {
  public:
    CountingField(const IndirectField& inner, float reuse) : inner_(inner), reuse_(reuse) {}
    ShRgb radiance_sh(const vec3& p, const vec3& n) const override {
        return inner_.radiance_sh(p, n);
    }
    FieldLookup lookup(const vec3& p, const vec3& n) const override {
        ++lookups_;
        return inner_.lookup(p, n);
    }
    float reuse_distance() const override { return reuse_; }
    uint64_t lookups() const { return lookups_.load(); }

  private:
    const IndirectField& inner_;
    float reuse_;
    mutable std::atomic<uint64_t> lookups_{0};
};

// --- a Lambert plane under a point light ---

constexpr float kPlaneAlbedo = 0.8f;
constexpr float kLightPower = 100.0f;  // W
const vec3 kLightPosition(0.3f, -0.2f, 1.0f);
constexpr uint32_t kPlaneResolution = 8;

// The plane z = 0 seen from above by an orthographic camera covering 2 m: pixels of 0.25 m, over
// which the irradiance varies by a factor of ~8 across the image.
Scene point_light_scene() {
    Scene scene;
    scene.add_material(test::lambert(kPlaneAlbedo));
    scene.add_instance(scene.add_mesh(test::plane(50.0f)), mat4(1.0f));
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 2.0f), 2.0f, kPlaneResolution));
    scene.add_light(test::point_light(kLightPosition, kLightPower));
    scene.commit();
    return scene;
}

// E / pi at a point of the plane: I cos(theta) / (pi d^2), I = P / (4 pi).
double point_light_diffdir(const vec3& p) {
    const glm::dvec3 to_light = glm::dvec3(kLightPosition) - glm::dvec3(p);
    const double d2 = glm::dot(to_light, to_light);
    const double cos_theta = to_light.z / std::sqrt(d2);
    return double(kLightPower) / (4.0 * kPiD) * cos_theta / d2 / kPiD;
}

// The expected DiffDir of each pixel (the average over uniform jitter in the pixel) and the
// standard deviation of one jittered sample, by midpoint quadrature over the pixel.
struct PixelExpectation {
    double mean = 0.0, sample_deviation = 0.0;
};

std::vector<PixelExpectation> expected_diffdir(const Camera& camera) {
    std::vector<PixelExpectation> pixels;
    for (uint32_t y = 0; y < camera.resolution_y; ++y)
        for (uint32_t x = 0; x < camera.resolution_x; ++x) {
            double sum = 0.0, sum2 = 0.0;
            for (int j = 0; j < kPixelQuadrature; ++j)
                for (int i = 0; i < kPixelQuadrature; ++i) {
                    const vec2 film(float(x) + (float(i) + 0.5f) / kPixelQuadrature,
                                    float(y) + (float(j) + 0.5f) / kPixelQuadrature);
                    const Ray ray = camera.generate_ray(film);
                    const vec3 p = ray.origin - ray.origin.z / ray.direction.z * ray.direction;
                    const double value = point_light_diffdir(p);
                    sum += value;
                    sum2 += value * value;
                }
            const double n = double(kPixelQuadrature * kPixelQuadrature);
            PixelExpectation pixel;
            pixel.mean = sum / n;
            pixel.sample_deviation = std::sqrt(std::max(0.0, sum2 / n - pixel.mean * pixel.mean));
            pixels.push_back(pixel);
        }
    return pixels;
}

PreviewSettings preview_settings(uint32_t samples, uint64_t seed = 7) {
    PreviewSettings settings;
    settings.samples = samples;
    settings.seed = seed;
    return settings;
}

// Every pixel of `diffdir` within kSigmas standard errors of its jitter average.
void expect_point_light_diffdir(const std::vector<float>& diffdir, const Camera& camera,
                                uint32_t samples, const char* what) {
    const std::vector<PixelExpectation> expected = expected_diffdir(camera);
    ASSERT_EQ(diffdir.size(), expected.size() * 3);
    for (size_t i = 0; i < expected.size(); ++i) {
        const double tolerance = kSigmas * expected[i].sample_deviation / std::sqrt(samples) +
                                 kRoundingTolerance * expected[i].mean;
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(diffdir[i * 3 + size_t(c)], expected[i].mean, tolerance)
                << what << ", pixel " << i << " channel " << c;
    }
}

// Every colour channel of a pass is exactly zero (Combined's alpha, always 1, is skipped).
void expect_black(const Film& film, Pass pass, const char* what) {
    const std::vector<float> pixels = film.pixels(pass);
    const size_t channels = pass_suffixes(pass).size();
    for (size_t i = 0; i < pixels.size(); ++i) {
        if (i % channels == 3) continue;
        ASSERT_EQ(pixels[i], 0.0f) << what << " [" << i << "]";
    }
}

// With no field the preview shows direct light only: DiffDir is the point light's irradiance /
// pi at every pixel, the Ind passes are exactly zero, Combined = albedo x DiffDir.
// The preview's FrameMemo gives Frame::from_z's frame bit for bit: normals repeated (its hits),
// new ones (its misses), and -0 and +0 components, whose frames differ in sign bits.
TEST(PreviewRenderer, FrameMemoIsFrameFromZBitForBit) {
    std::vector<vec3> normals = {vec3(0.0f, 0.0f, 1.0f), vec3(-0.0f, 0.0f, 1.0f),
                                 vec3(0.0f, -0.0f, 1.0f), vec3(0.0f, 0.0f, -1.0f),
                                 vec3(-0.0f, -0.0f, -1.0f)};
    Pcg32 rng(3);
    for (int i = 0; i < 200; ++i) {
        const vec3 n = glm::normalize(vec3(rng.next_float(), rng.next_float(), rng.next_float()) -
                                      0.5f);
        for (int k = 0; k <= i % 3; ++k) normals.push_back(n);  // runs of 1 to 3
    }
    normals.insert(normals.end(), normals.begin(), normals.begin() + 5);
    FrameMemo memo;
    for (size_t i = 0; i < normals.size(); ++i) {
        const Frame expected = Frame::from_z(normals[i]);
        const Frame frame = memo.from_z(normals[i]);
        EXPECT_EQ(std::memcmp(&frame, &expected, sizeof(Frame)), 0) << "normal " << i;
    }
}

TEST(PreviewRenderer, NullFieldGivesExactDirectLightAndNoIndirect) {
    const Scene scene = point_light_scene();
    const uint32_t samples = 16;
    PreviewRenderer renderer(scene, preview_settings(samples));
    renderer.render(nullptr, samples);
    const Film& film = renderer.film();
    EXPECT_EQ(film.samples(), samples);
    const std::vector<float> diffdir = film.pixels(Pass::DiffDir);
    expect_point_light_diffdir(diffdir, scene.camera(), samples, "preview DiffDir");
    for (Pass pass : {Pass::DiffInd, Pass::GlossInd, Pass::TransInd, Pass::GlossDir, Pass::Emit,
                      Pass::Env})
        expect_black(film, pass, pass_name(pass));
    const std::vector<float> combined = film.pixels(Pass::Combined);
    for (size_t i = 0; i < diffdir.size() / 3; ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(combined[i * 4 + size_t(c)], kPlaneAlbedo * diffdir[i * 3 + size_t(c)],
                        kRoundingTolerance * diffdir[i * 3 + size_t(c)]);
}

// The preview's direct light is the reference path tracer's: both match the closed form pixel by
// pixel, and their image means agree within the jitter noise.
TEST(PreviewRenderer, DirectLightAgreesWithThePathTracer) {
    const Scene scene = point_light_scene();
    const uint32_t samples = 16;
    PreviewRenderer preview(scene, preview_settings(samples, 3));
    preview.render(nullptr, samples);
    PathTracerSettings path_settings = test::settings_with_samples(samples);
    path_settings.seed = 11;  // independent of the preview's samples
    PathTracer tracer(scene, path_settings);
    tracer.render(samples);
    const std::vector<float> reference = tracer.film().pixels(Pass::DiffDir);
    expect_point_light_diffdir(reference, scene.camera(), samples, "path tracer DiffDir");

    const std::vector<float> diffdir = preview.film().pixels(Pass::DiffDir);
    const std::vector<PixelExpectation> expected = expected_diffdir(scene.camera());
    double difference = 0.0, variance = 0.0;
    for (size_t i = 0; i < expected.size(); ++i) {
        difference += double(diffdir[i * 3]) - double(reference[i * 3]);
        variance += 2.0 * std::pow(expected[i].sample_deviation, 2) / samples;
    }
    const double n = double(expected.size());
    EXPECT_NEAR(difference / n, 0.0, kSigmas * std::sqrt(variance) / n);
}

// ZeroField is what a null field means: every pass is bit-identical.
TEST(PreviewRenderer, ZeroFieldEqualsNullField) {
    const Scene scene = point_light_scene();
    const ZeroField zero;
    PreviewRenderer with_null(scene, preview_settings(4));
    with_null.render(nullptr, 4);
    PreviewRenderer with_zero(scene, preview_settings(4));
    with_zero.render(&zero, 4);
    for (int p = 0; p < kPassCount; ++p)
        EXPECT_EQ(with_zero.film().pixels(Pass(p)), with_null.film().pixels(Pass(p)))
            << pass_name(Pass(p));
    expect_black(with_zero.film(), Pass::DiffInd, "DiffInd");
}

// A uniform incident radiance L gives irradiance pi L on the plane, so DiffInd = L exactly; the
// direct light is unchanged (the field draws no random numbers) and Combined = albedo x (DiffDir
// + DiffInd).
TEST(PreviewRenderer, ConstantFieldGivesDiffIndEqualToItsRadiance) {
    const Scene scene = point_light_scene();
    const vec3 radiance(0.3f, 0.6f, 0.9f);
    const ConstantField field(radiance);
    PreviewRenderer lit(scene, preview_settings(4));
    lit.render(&field, 4);
    PreviewRenderer direct_only(scene, preview_settings(4));
    direct_only.render(nullptr, 4);
    const Film& film = lit.film();
    EXPECT_EQ(film.pixels(Pass::DiffDir), direct_only.film().pixels(Pass::DiffDir));
    const std::vector<float> diffind = film.pixels(Pass::DiffInd);
    const std::vector<float> diffdir = film.pixels(Pass::DiffDir);
    const std::vector<float> combined = film.pixels(Pass::Combined);
    for (size_t i = 0; i < diffind.size() / 3; ++i)
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(diffind[i * 3 + size_t(c)], radiance[c],
                        kRoundingTolerance * radiance[c])
                << "pixel " << i << " channel " << c;
            const double expected =
                kPlaneAlbedo * (double(diffdir[i * 3 + size_t(c)]) + radiance[c]);
            EXPECT_NEAR(combined[i * 4 + size_t(c)], expected, kRoundingTolerance * expected);
        }
    expect_black(film, Pass::GlossInd, "GlossInd");
}

// A field carrying the world's direct light takes the world out of next-event estimation: under
// a uniform world of radiance Lw the plane's DiffDir is Lw (cosine-sampled world: every sample is
// exactly Lw) without it, and exactly zero with it.
TEST(PreviewRenderer, FieldCarryingWorldLightTakesTheWorldOutOfDirectLight) {
    Scene scene;
    scene.add_material(test::lambert(kPlaneAlbedo));
    scene.add_instance(scene.add_mesh(test::plane(50.0f)), mat4(1.0f));
    World world;
    world.color = vec3(0.2f, 0.4f, 0.6f);
    world.strength = 1.5f;
    scene.set_world(world);
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 1.0f), 1.0f, 4));
    scene.commit();
    const ConstantField without_world(vec3(0.0f), false), with_world(vec3(0.0f), true);
    PreviewRenderer nee(scene, preview_settings(4));
    nee.render(&without_world, 4);
    const std::vector<float> diffdir = nee.film().pixels(Pass::DiffDir);
    for (size_t i = 0; i < diffdir.size(); ++i)
        EXPECT_NEAR(diffdir[i], world.radiance()[int(i % 3)],
                    kRoundingTolerance * world.radiance()[int(i % 3)])
            << "[" << i << "]";
    PreviewRenderer field_only(scene, preview_settings(4));
    field_only.render(&with_world, 4);
    expect_black(field_only.film(), Pass::DiffDir, "DiffDir with world in the field");
    expect_black(field_only.film(), Pass::Combined, "Combined with world in the field");
}

// A perfect mirror floor (metallic, roughness 0, white) under a Lambert ceiling facing down, no
// lights: the camera sees the ceiling's field light through the mirror, albedo x L, in the glossy
// passes; with max_specular_bounces = 0 the mirror is not followed and the image is black.
TEST(PreviewRenderer, MirrorShowsTheFieldOnTheSurfaceItReflects) {
    const float ceiling_albedo = 0.5f;
    Scene scene;
    scene.add_material(test::mirror(1.0f));
    scene.add_material(test::lambert(ceiling_albedo));
    scene.add_instance(scene.add_mesh(test::plane(50.0f)), mat4(1.0f));
    Mesh ceiling = test::plane(50.0f);
    ceiling.material_indices.assign(ceiling.triangles.size(), 1);
    scene.add_instance(scene.add_mesh(ceiling),
                       glm::rotate(glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, 1.0f)), kPi,
                                   vec3(1.0f, 0.0f, 0.0f)));
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.5f), 1.0f, 4));
    scene.commit();
    const vec3 radiance(0.3f, 0.6f, 0.9f);
    const ConstantField field(radiance);

    PreviewRenderer renderer(scene, preview_settings(4));
    renderer.render(&field, 4);
    const std::vector<float> combined = renderer.film().pixels(Pass::Combined);
    const std::vector<float> glossind = renderer.film().pixels(Pass::GlossInd);
    const std::vector<float> glosscol = renderer.film().pixels(Pass::GlossCol);
    for (size_t i = 0; i < combined.size() / 4; ++i)
        for (int c = 0; c < 3; ++c) {
            const double expected = ceiling_albedo * radiance[c];
            EXPECT_NEAR(combined[i * 4 + size_t(c)], expected, kRoundingTolerance * expected)
                << "pixel " << i << " channel " << c;
            EXPECT_NEAR(double(glossind[i * 3 + size_t(c)]) * glosscol[i * 3 + size_t(c)],
                        expected, kRoundingTolerance * expected);
        }
    expect_black(renderer.film(), Pass::DiffInd, "DiffInd");

    PreviewSettings no_chains = preview_settings(4);
    no_chains.max_specular_bounces = 0;
    PreviewRenderer unfollowed(scene, no_chains);
    unfollowed.render(&field, 4);
    expect_black(unfollowed.film(), Pass::Combined, "Combined without specular bounces");
}

// --- a room lit by a point light, its indirect light from a solved PhotonLattice ---

// Closed box [-1, 1]^3 (diffuse + glossy walls), a mirror sphere and a point light; an
// orthographic camera inside the box looking down at the floor.
Scene room_scene() {
    Scene scene;
    Material walls = test::lambert(0.7f);
    walls.specular = 0.5f;  // a glossy lobe too: GlossDir / GlossInd are exercised
    walls.roughness = 0.4f;
    scene.add_material(walls);
    scene.add_material(test::mirror(0.9f));
    scene.add_instance(scene.add_mesh(test::inward_box(1.0f)), mat4(1.0f));
    Mesh sphere = test::uv_sphere(0.3f, 8, 16);
    sphere.material_indices.assign(sphere.triangles.size(), 1);
    scene.add_instance(scene.add_mesh(sphere),
                       glm::translate(mat4(1.0f), vec3(0.2f, 0.0f, -0.7f)));
    scene.add_light(test::point_light(vec3(-0.1f, 0.2f, 0.6f), 100.0f));
    scene.set_world(test::black_world());
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.9f), 1.8f, 12));
    scene.commit();
    return scene;
}

std::unique_ptr<PhotonLattice> solved_lattice(const Scene& scene) {
    PhotonLatticeSettings settings;
    settings.photons = 20000;
    settings.seed = 2;
    settings.resolution = 8;
    settings.caustic_resolution = 16;
    auto lattice = std::make_unique<PhotonLattice>(scene, settings);
    lattice->solve();
    return lattice;
}

void expect_same_film(const Film& a, const Film& b) {
    EXPECT_EQ(a.samples(), b.samples());
    for (int p = 0; p < kPassCount; ++p)
        EXPECT_EQ(a.pixels(Pass(p)), b.pixels(Pass(p))) << pass_name(Pass(p));
}

// render(1) + render(3) adds the same samples in the same order as render(4): bit-identical, and
// render_preview returns the same passes.
TEST(PreviewRenderer, ProgressiveEqualsOneShot) {
    const Scene scene = room_scene();
    const auto lattice = solved_lattice(scene);
    PreviewRenderer progressive(scene, preview_settings(4));
    progressive.render(lattice.get(), 1);
    progressive.render(lattice.get(), 0);  // adds nothing
    progressive.render(lattice.get(), 3);
    PreviewRenderer one_shot(scene, preview_settings(4));
    one_shot.render(lattice.get(), 4);
    expect_same_film(progressive.film(), one_shot.film());
    std::vector<float> diffind = one_shot.film().pixels(Pass::DiffInd);
    EXPECT_GT(*std::max_element(diffind.begin(), diffind.end()), 0.0f);

    const Image image = render_preview(scene, lattice.get(), preview_settings(4));
    const Image progressive_image = progressive.image();
    for (int p = 0; p < kPassCount; ++p) {
        const char* name = pass_name(Pass(p));
        EXPECT_EQ(image.layer_pixels(name), progressive_image.layer_pixels(name)) << name;
    }
}

TEST(PreviewRenderer, BitIdenticalForAnyThreadCountAndTileSize) {
    const Scene scene = room_scene();
    const auto lattice = solved_lattice(scene);
    const auto render = [&](int threads, int tile_size) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        PreviewSettings settings = preview_settings(4);
        settings.tile_size = tile_size;
        auto renderer = std::make_unique<PreviewRenderer>(scene, settings);
        renderer->render(lattice.get(), 4);
        return renderer;
    };
    const auto one = render(1, 16);
    const auto two = render(2, 5);
    expect_same_film(one->film(), two->film());
    // One tile holding the whole image (a side past any image's is cut before it is made even).
    expect_same_film(one->film(), render(2, std::numeric_limits<int>::max())->film());
}

// A thread keeps its wave's paths from one work unit to the next within a frame and builds them
// again for another frame's scene, field and settings: on one thread, frames of two renderers
// (other cameras, the photon lattice and no field, all passes and Combined only) rendered in
// turn, one sample each, equal those of each renderer alone on a new thread (whose wave is new).
TEST(PreviewRenderer, FramesOfRenderersInTurnEqualEachRendererAlone) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(1));
    const Scene room = room_scene();
    Scene fine = room_scene();
    fine.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.9f), 1.8f, 40));
    fine.commit();
    const auto lattice = solved_lattice(room);
    PreviewSettings combined_only = preview_settings(1);
    combined_only.combined_only = true;
    PreviewRenderer alone_a(room, preview_settings(1)), alone_b(fine, combined_only);
    std::thread([&] {
        for (int s = 0; s < 3; ++s) alone_a.render(lattice.get(), 1);
    }).join();
    std::thread([&] {
        for (int s = 0; s < 3; ++s) alone_b.render(nullptr, 1);
    }).join();
    PreviewRenderer a(room, preview_settings(1)), b(fine, combined_only);
    for (int s = 0; s < 3; ++s) {
        a.render(lattice.get(), 1);
        b.render(nullptr, 1);
    }
    expect_same_film(alone_a.film(), a.film());
    EXPECT_EQ(alone_b.film().samples(), b.film().samples());
    EXPECT_EQ(alone_b.film().pixels(Pass::Combined), b.film().pixels(Pass::Combined));
}

// The lookup sharing stage reads its quads from the frame-wide G-buffer: on the fine room with the
// photon lattice (where sharing is active: the frame differs from one lookup per pixel), frames
// are bit-identical for tile sizes 2, 16 and 64 on one thread and on two.
TEST(PreviewRenderer, LookupSharingIdenticalForAnyTileSizeAndThreadCount) {
    Scene scene = room_scene();
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.9f), 1.8f, 40));
    scene.commit();
    const auto lattice = solved_lattice(scene);
    ASSERT_GT(lattice->reuse_distance(), 0.0f);
    const auto render = [&](int threads, int tile_size, bool reuse) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
        PreviewSettings settings = preview_settings(4);
        settings.tile_size = tile_size;
        settings.reuse_field_lookups = reuse;
        auto renderer = std::make_unique<PreviewRenderer>(scene, settings);
        renderer->render(lattice.get(), 4);
        return renderer;
    };
    const auto reference = render(1, 16, true);
    EXPECT_NE(reference->film().pixels(Pass::DiffInd),
              render(1, 16, false)->film().pixels(Pass::DiffInd));
    for (const int threads : {1, 2})
        for (const int tile_size : {2, 16, 64}) {
            SCOPED_TRACE(::testing::Message() << threads << " threads, tile " << tile_size);
            expect_same_film(reference->film(), render(threads, tile_size, true)->film());
        }
}

// Screen-space reuse on one flat surface: the pixels of each 2 x 2 quad share one lookup (an
// 8 x 8 image has 16 quads), and a constant field gives the same DiffInd either way. Reuse
// within a distance shorter than any two hits' gives one lookup per pixel, as does
// reuse_field_lookups = false.
TEST(PreviewRenderer, ReuseSharesOneLookupPerQuadOnOneSurface) {
    const Scene scene = point_light_scene();
    const ConstantField constant(vec3(0.5f, 0.25f, 0.125f));
    const uint64_t pixels = kPlaneResolution * kPlaneResolution;
    const auto render = [&](float reuse, bool setting) {
        const CountingField field(constant, reuse);
        PreviewSettings settings = preview_settings(3);
        settings.reuse_field_lookups = setting;
        const Image image = render_preview(scene, &field, settings);
        EXPECT_EQ(field.lookups(), (reuse > 1.0f && setting ? pixels / 4 : pixels) * 3)
            << "reuse " << reuse << (setting ? "" : ", off");
        return image.layer_pixels("DiffInd");
    };
    const std::vector<float> shared = render(100.0f, true);
    EXPECT_EQ(shared, render(1e-6f, true));
    EXPECT_EQ(shared, render(100.0f, false));
    for (size_t i = 0; i < shared.size(); i += 3)
        EXPECT_NEAR(shared[i], 0.5f, 0.5f * kRoundingTolerance) << "pixel " << i / 3;
}

// Renders `scene` at 8 spp with `field` with and without screen-space reuse: the share of
// lookups reuse makes, DiffInd's mean with reuse over its mean without, and the RMS of their
// per-pixel difference over that mean.
struct ReuseEffect {
    double lookup_share = 0.0, mean_ratio = 0.0, relative_rms = 0.0;
};
ReuseEffect reuse_effect(const Scene& scene, const IndirectField& field) {
    const auto render = [&](bool reuse, uint64_t* lookups) {
        const CountingField counting(field, field.reuse_distance());
        PreviewSettings settings = preview_settings(8);
        settings.reuse_field_lookups = reuse;
        const Image image = render_preview(scene, &counting, settings);
        *lookups = counting.lookups();
        return image.layer_pixels("DiffInd");
    };
    uint64_t shared_lookups = 0, own_lookups = 0;
    const std::vector<float> shared = render(true, &shared_lookups);
    const std::vector<float> own = render(false, &own_lookups);
    double sum_shared = 0.0, sum_own = 0.0, sum_d2 = 0.0;
    for (size_t i = 0; i < own.size(); ++i) {
        sum_shared += shared[i];
        sum_own += own[i];
        sum_d2 += double(shared[i] - own[i]) * double(shared[i] - own[i]);
    }
    ReuseEffect effect;
    effect.lookup_share = double(shared_lookups) / double(own_lookups);
    effect.mean_ratio = sum_shared / sum_own;
    effect.relative_rms = std::sqrt(sum_d2 / double(own.size())) / (sum_own / double(own.size()));
    return effect;
}

// The room at 96 x 96: pixels of 1.9 cm.
Scene fine_room_scene() {
    Scene scene = room_scene();
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.9f), 1.8f, 96));
    scene.commit();
    return scene;
}

// With the photon lattice (the bench's preview), reuse changes the picture by far less than the
// preview's own difference from the path tracer: on the fine room (the lattices' reuse distance
// 3 cm, 8 spp), DiffInd's mean moves by under 0.1% and its pixels by under 1% RMS of the mean,
// while the lattice makes at most half the lookups (edges, the sphere and the mirror's
// reflections make their own).
TEST(PreviewRenderer, ReuseOnTheLatticeChangesTheImageLittle) {
    const Scene scene = fine_room_scene();
    const auto lattice = solved_lattice(scene);
    ASSERT_GT(lattice->reuse_distance(), 0.0f);
    const ReuseEffect effect = reuse_effect(scene, *lattice);
    EXPECT_LE(effect.lookup_share, 0.5);            // measured: 0.45
    EXPECT_NEAR(effect.mean_ratio, 1.0, 0.001);     // measured: 1 + 1e-5
    EXPECT_LT(effect.relative_rms, 0.01);           // measured: 0.0036
}

// The same for a probe grid (4 x 4 x 4 probes 0.5 m apart, visibility-weighted lookups: reuse
// within 12.5 cm on one surface).
TEST(PreviewRenderer, ReuseOnAProbeGridChangesTheImageLittle) {
    const Scene scene = fine_room_scene();
    ProbeGridSettings settings;
    ProbeVolume volume;
    volume.world_from_volume = glm::scale(mat4(1.0f), vec3(0.99f));
    volume.resolution = ivec3(4);
    settings.volumes = {volume};
    settings.rays_per_probe = 64;
    ProbeGrid grid(scene, settings);
    grid.update();
    const std::shared_ptr<const ProbeField> field = grid.field();
    EXPECT_NEAR(field->reuse_distance(), 0.25f * 0.495f, 1e-4f);
    const ReuseEffect effect = reuse_effect(scene, *field);
    EXPECT_LE(effect.lookup_share, 0.5);         // measured: 0.34
    EXPECT_NEAR(effect.mean_ratio, 1.0, 0.001);  // measured: 1 - 6e-6
    EXPECT_LT(effect.relative_rms, 0.01);        // measured: 0.0066
}

// The viewport's film sums only Combined: the same Combined bits as a film with every pass, and
// no other pass to read.
TEST(PreviewRenderer, CombinedOnlyGivesTheSameCombined) {
    const Scene scene = room_scene();
    const auto lattice = solved_lattice(scene);
    PreviewSettings settings = preview_settings(2);
    PreviewRenderer all(scene, settings);
    settings.combined_only = true;
    PreviewRenderer combined(scene, settings);
    for (int round = 0; round < 2; ++round) {  // in place, then onto a film holding samples
        all.render(lattice.get(), 1);
        combined.render(lattice.get(), 1);
        EXPECT_EQ(combined.film().samples(), all.film().samples());
        EXPECT_EQ(combined.film().pixels(Pass::Combined), all.film().pixels(Pass::Combined));
    }
    EXPECT_FALSE(combined.film().has_pass(Pass::DiffInd));
    testing::expect_invalid_argument([&] { combined.film().pixels(Pass::DiffInd); },
                                     "only Combined");
    const Image image = combined.image();
    EXPECT_NE(image.find_channel("Combined.R"), nullptr);
    EXPECT_EQ(image.find_channel("DiffInd.R"), nullptr);
}

// A cancel before the first chunk, or in the middle of shading (some samples already summed),
// throws Cancelled and leaves the film as it was; rendering then continues as if it never
// happened.
TEST(PreviewRenderer, CancelLeavesTheFilmUnchanged) {
    const Scene scene = room_scene();
    const auto lattice = solved_lattice(scene);
    PreviewRenderer reference(scene, preview_settings(3));
    reference.render(lattice.get(), 3);

    PreviewRenderer renderer(scene, preview_settings(3));
    renderer.render(lattice.get(), 1);
    const Film before = renderer.film();
    Progress cancelled;
    cancelled.cancel();
    EXPECT_THROW(renderer.render(lattice.get(), 2, &cancelled), Cancelled);
    expect_same_film(renderer.film(), before);

    Progress progress;
    const uint64_t pixels = 12 * 12;
    const CancellingField cancelling(*lattice, progress, pixels / 2);
    EXPECT_THROW(renderer.render(&cancelling, 2, &progress), Cancelled);
    EXPECT_GE(cancelling.lookups(), pixels / 2);
    expect_same_film(renderer.film(), before);

    renderer.render(lattice.get(), 2);
    expect_same_film(renderer.film(), reference.film());
}

// A renderer caches light tables and a film sized for the scene it was built on; after an edit it
// refuses to render and keeps its film.
TEST(PreviewRenderer, RefusesASceneEditedAfterConstruction) {
    Scene scene = point_light_scene();
    PreviewRenderer renderer(scene, preview_settings(1));
    renderer.render(nullptr, 1);
    const Film before = renderer.film();
    Light extra;
    extra.world_from_light = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, 3.0f));
    scene.add_light(extra);
    for (bool commit : {false, true}) {
        if (commit) scene.commit();
        SCOPED_TRACE(commit ? "edited and committed" : "edited");
        testing::expect_invalid_argument([&] { renderer.render(nullptr, 1); },
                                         "edited after this renderer");
        expect_same_film(renderer.film(), before);
    }
}

// Filter Glossy reaches the preview's paths. With final gather and no field, the gather ray's
// first surface is where the path would read the field: a mirror floor seen in its own
// reflection of a Lambert ceiling is, without the filter, a Dirac lobe that light samples never
// reach; with Filter Glossy 1 the ceiling's diffuse bounce widens it to a field lobe that next-
// event estimation lights (GlossInd: light of more than one scattering), while what the first
// scattering sees (GlossDir) stays bit for bit.
TEST(PreviewRenderer, FilterGlossyWidensTheSurfacesAfterTheGatherBounce) {
    Scene scene;
    test::add_mirror_under_ceiling(&scene);
    scene.add_light(test::point_light(vec3(2.0f, 0.0f, 0.5f), 200.0f));
    scene.set_camera(test::ortho_camera_down(vec3(0.0f, 0.0f, 0.5f), 0.5f, 8));
    scene.commit();
    PreviewSettings settings = preview_settings(256);
    settings.final_gather = true;
    PreviewRenderer off(scene, settings);
    off.render(nullptr, settings.samples);
    settings.filter_glossy = 1.0f;
    PreviewRenderer on(scene, settings);
    on.render(nullptr, settings.samples);
    // Pixel by pixel (the light varies across the view): the mean gain and its standard error.
    const std::vector<float> a = off.film().pixels(Pass::GlossInd);
    const std::vector<float> b = on.film().pixels(Pass::GlossInd);
    double sum = 0.0, sum2 = 0.0, base = 0.0;
    const size_t n = a.size() / 3;
    for (size_t i = 0; i < a.size(); i += 3) {
        const double gain = double(b[i]) - double(a[i]);
        sum += gain;
        sum2 += gain * gain;
        base += a[i];
    }
    const double mean = sum / double(n);
    const double error = std::sqrt(std::max(0.0, sum2 / double(n) - mean * mean) / double(n - 1));
    EXPECT_GT(mean, 5.0 * error) << "GlossInd " << base / double(n) << " unfiltered";
    EXPECT_EQ(on.film().pixels(Pass::GlossDir), off.film().pixels(Pass::GlossDir));
}

TEST(PreviewRenderer, RejectsInvalidSettingsNamingTheField) {
    const Scene scene = point_light_scene();
    const auto expect_message = [&](const PreviewSettings& settings, const std::string& name) {
        testing::expect_invalid_argument([&] { validate_preview_settings(settings); }, name);
        testing::expect_invalid_argument([&] { PreviewRenderer renderer(scene, settings); }, name);
        testing::expect_invalid_argument([&] { render_preview(scene, nullptr, settings); }, name);
    };
    PreviewSettings s;
    s.samples = 0;
    expect_message(s, "PreviewSettings.samples is 0");
    s = {};
    s.samples = uint32_t(kMaxPathTracerSamples + 1);
    expect_message(s, "PreviewSettings.samples");
    s = {};
    s.max_specular_bounces = -1;
    expect_message(s, "PreviewSettings.max_specular_bounces is -1");
    s = {};
    s.clamp_indirect = -1.0f;
    expect_message(s, "PreviewSettings.clamp_indirect");
    s = {};
    s.clamp_indirect = std::nanf("");
    expect_message(s, "PreviewSettings.clamp_indirect");
    for (const float bad : {-1.0f, std::nanf(""), kInfinity}) {
        s = {};
        s.filter_glossy = bad;
        expect_message(s, "PreviewSettings.filter_glossy");
    }
    s = {};
    s.tile_size = 0;
    expect_message(s, "PreviewSettings.tile_size is 0");

    // More samples than a film may hold, in two calls.
    PreviewRenderer renderer(scene, preview_settings(1));
    renderer.render(nullptr, 1);
    testing::expect_invalid_argument(
        [&] { renderer.render(nullptr, uint32_t(kMaxPathTracerSamples)); }, "exceed");
    EXPECT_EQ(renderer.film().samples(), 1u);

    Camera camera = scene.camera();
    camera.resolution_x = 0;
    EXPECT_THROW(PreviewRenderer(scene, camera, PreviewSettings{}), InvalidArgument);
}

}  // namespace
// The wave's Owen-scrambled Sobol' numbers (eight pixels at a time in AVX2 where the CPU has it,
// its 64-bit products in one AVX-512DQ instruction where it has that too, its bit reversals by
// GFNI where it has that as well, four in SSE2, the rest one by one) are pixel_sample's, bit for
// bit, on every instruction set this CPU runs: for wave sizes with and without a remainder,
// scattered and large pixel indices, early and late sample indices (all 32 index bits) and
// several seeds.
TEST(PreviewRenderer, PixelSamplesOfAWaveArePixelSampleBitForBit) {
    std::vector<PixelSamplesIsa> isas = {PixelSamplesIsa::Auto, PixelSamplesIsa::Sse2};
    if (cpu_has_avx2())
        isas.push_back(PixelSamplesIsa::Avx2);
    else
        EXPECT_THROW(pixel_samples(0, nullptr, 0, 0, nullptr, PixelSamplesIsa::Avx2),
                     InvalidArgument);
    if (cpu_has_avx512dq_vl())
        isas.push_back(PixelSamplesIsa::Avx512);
    else
        EXPECT_THROW(pixel_samples(0, nullptr, 0, 0, nullptr, PixelSamplesIsa::Avx512),
                     InvalidArgument);
    if (cpu_has_avx512dq_vl_gfni())
        isas.push_back(PixelSamplesIsa::Avx512Gfni);
    else
        EXPECT_THROW(pixel_samples(0, nullptr, 0, 0, nullptr, PixelSamplesIsa::Avx512Gfni),
                     InvalidArgument);
    std::vector<uint32_t> pixels;
    uint32_t x = 12345u;
    for (int i = 0; i < 263; ++i) {
        x = x * 1664525u + 1013904223u;  // any spread of indices, including large ones
        pixels.push_back(i < 8 ? uint32_t(i) : x);
    }
    for (const uint64_t seed : {uint64_t(0), uint64_t(7), uint64_t(0xFFFFFFFFFFFFull)})
        for (const uint64_t sample : {uint64_t(0), uint64_t(1), uint64_t(5), uint64_t(1023),
                                      uint64_t(0xFFFFFFFFu)})
            for (const size_t count : {size_t(0), size_t(3), size_t(4), size_t(13), size_t(263)})
                for (const PixelSamplesIsa isa : isas) {
                    std::vector<PixelSample> wave(count);
                    pixel_samples(seed, pixels.data(), count, sample, wave.data(), isa);
                    for (size_t i = 0; i < count; ++i) {
                        const PixelSample one = pixel_sample(seed, pixels[i], sample);
                        const auto same = [](float a, float b) {
                            return std::memcmp(&a, &b, sizeof(float)) == 0;
                        };
                        ASSERT_TRUE(same(wave[i].jitter.x, one.jitter.x) &&
                                    same(wave[i].jitter.y, one.jitter.y) &&
                                    same(wave[i].u_select, one.u_select) &&
                                    same(wave[i].u_light.x, one.u_light.x) &&
                                    same(wave[i].u_light.y, one.u_light.y) &&
                                    wave[i].u_lobe == 0.0f && wave[i].u_bsdf == vec2(0.0f))
                            << "seed " << seed << ", sample " << sample << ", pixel " << pixels[i]
                            << ", instruction set " << int(isa);
                    }
                }
}

}  // namespace shgi
