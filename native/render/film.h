// Film: per-pixel sums of every render pass, and their conversion to Blender-style images.
//
// Passes and their meaning follow Cycles (Blender manual, "Render Passes"):
// - Combined: everything the camera sees; alpha is 1 (an opaque film, Cycles' default).
// - Diff/Gloss/Trans Dir: light that reached the first surface straight from an emitter (NEE and
//   MIS-weighted BSDF hits of emitters) and left towards the camera through that lobe class;
//   Ind: light after two or more scatterings, attributed to the lobe class sampled at the first
//   surface. Stored, as in Cycles, divided by the matching Col pass (sum over samples / sum over
//   samples), so that Combined = (DiffDir + DiffInd) DiffCol + (GlossDir + GlossInd) GlossCol +
//   (TransDir + TransInd) TransCol + Emit + Env wherever the Col passes are non-zero.
// - Diff/Gloss/TransCol: the first surface's closure weights per class (sample mean).
// - Emit: emitters seen directly by the camera (surfaces, lights); Env: the world seen directly.
// - Normal: first hit's shading normal, world space, facing the camera (sample mean, 0 on miss).
// - Depth: distance of the first hit along the camera's view axis (Cycles' z-depth), averaged
//   over samples with misses counting 0, and 1e10 where nothing was hit, as Cycles writes it.
// - Denoising Albedo / Denoising Normal: the denoiser's guides as Cycles writes them
//   (kernel/film/denoising_passes.h): at the first surface that is not (nearly) perfectly
//   specular, i.e. whose non-specular lobes hold more than a quarter of its lobes' sampling
//   weight, a lobe being specular when its GGX alpha is at most kDenoisingSpecularAlpha
//   (render/bsdf.h). Through specular surfaces (clear glass, mirrors, polished metal) the path's
//   own bounce is followed and the albedo is multiplied by their albedo (their tint), so the
//   guides show what is seen through or in them. Albedo: that surface's non-specular closure
//   weights (as DiffCol + GlossCol + TransCol); normal: its shading normal, world space, facing
//   the ray (sample means; 0 where a path left before reaching such a surface).
// Channel names: "Combined.R/G/B/A", "DiffDir.R/G/B", ..., "Normal.X/Y/Z", "Depth.Z",
// "Denoising Albedo.R/G/B", "Denoising Normal.X/Y/Z".
//
// A film sums every pass (F12, render_preview) or only Combined (FilmPasses::CombinedOnly: what
// the viewport shows; the sums of 16 passes are 192 bytes a pixel, ~44 MB read and written per
// 640 x 360 frame, where Combined alone is 12 bytes). Sums are stored pixel by pixel, each
// pixel's passes together: a sample's 16 sums then go to three adjacent cache lines instead of
// 16 lines in 16 planes.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "io/image.h"
#include "util/math.h"

namespace shgi {

enum class Pass : uint8_t {
    Combined, DiffDir, DiffInd, DiffCol, GlossDir, GlossInd, GlossCol,
    TransDir, TransInd, TransCol, Emit, Env, Normal, Depth, DenoisingAlbedo, DenoisingNormal,
};
inline constexpr int kPassCount = 16;

// The passes a film sums.
enum class FilmPasses : uint8_t { All, CombinedOnly };

// "Combined", "DiffDir", ...
const char* pass_name(Pass pass);
// Channel suffixes of a pass as written: {"R","G","B","A"} for Combined, {"Z"} for Depth...
std::vector<std::string> pass_suffixes(Pass pass);

// One sample's value for every pass (Depth in .x), before normalisation.
struct PassValues {
    std::array<vec3, kPassCount> value{};
    vec3& operator[](Pass pass) { return value[size_t(pass)]; }
    const vec3& operator[](Pass pass) const { return value[size_t(pass)]; }
};

class Film {
  public:
    Film() = default;
    Film(int width, int height, FilmPasses passes = FilmPasses::All);

    int width() const { return width_; }
    int height() const { return height_; }
    uint32_t samples() const { return samples_; }
    FilmPasses passes() const { return passes_; }
    bool has_pass(Pass pass) const {
        return passes_ == FilmPasses::All || pass == Pass::Combined;
    }

    // Adds one sample's values to pixel (x, y) (y = 0 is the top row); values of passes the
    // film does not sum are ignored.
    void add(int x, int y, const PassValues& values);
    // Sets pixel (x, y) to `base`'s sums there plus one sample's values (base may be this film;
    // it must have the same size and passes). A render that must leave its film untouched until
    // it completes sums into a second film this way (ProgressiveFilm), without first copying
    // the whole film.
    // Inline: the preview calls it once a pixel and sample, and a Combined-only film's loop is
    // one addition (a call cost more than the work).
    void accumulate(int x, int y, const Film& base, const PassValues& values) {
        const size_t first = (size_t(y) * size_t(width_) + size_t(x)) * pass_count_;
        const vec3* from = base.sums_.data() + first;
        vec3* to = sums_.data() + first;
        for (size_t p = 0; p < pass_count_; ++p) to[p] = from[p] + values.value[p];
    }
    // Starts loading the cache lines accumulate(x, y, base, ...) reads and writes, for a caller
    // with enough work before that call to hide a miss (the preview shades the pixel's path in
    // between). The two films are ~2.7 MB each at 640 x 360 Combined-only, past a core's L2:
    // the preview's accumulate waited on them (~15% of the render loop's own CPU samples).
    void prefetch(int x, int y, const Film& base) const {
        const size_t first = (size_t(y) * size_t(width_) + size_t(x)) * pass_count_;
        const char* from = reinterpret_cast<const char*>(base.sums_.data() + first);
        const char* to = reinterpret_cast<const char*>(sums_.data() + first);
        // The lines of the pixel's first and last bytes: all of a Combined-only film's pixel.
        const size_t last = pass_count_ * sizeof(vec3) - 1;
        __builtin_prefetch(from, 0);
        __builtin_prefetch(from + last, 0);
        __builtin_prefetch(to, 1);
        __builtin_prefetch(to + last, 1);
    }
    void set_samples(uint32_t samples) { samples_ = samples; }
    // Every sum back to zero, samples() to 0.
    void clear();

    // Normalised pixels of one pass, interleaved (height, width, channels) top row first.
    // InvalidArgument for a pass the film does not sum.
    std::vector<float> pixels(Pass pass) const;
    // Every pass the film sums as Blender-style layers, Float channels.
    Image image() const;

  private:
    const vec3& sum(Pass pass, size_t pixel) const {
        return sums_[pixel * pass_count_ + size_t(pass)];
    }
    size_t pixel_count() const { return size_t(width_) * size_t(height_); }
    vec3 normalised(Pass pass, size_t pixel) const;

    int width_ = 0, height_ = 0;
    uint32_t samples_ = 0;
    FilmPasses passes_ = FilmPasses::All;
    size_t pass_count_ = 0;   // passes summed: kPassCount, or 1 (Combined)
    std::vector<vec3> sums_;  // [pixel][pass]
};

// The film of a progressive renderer, whose render() adds samples to it and must leave it as it
// was when it fails or is cancelled, without copying it: an empty film is summed in place (and
// cleared again on failure); a film that holds samples is summed, pixel by pixel, with the new
// samples into a second film (Film::accumulate on base()), which takes its place when the render
// completes. The two films are swapped, never copied, and both are kept between renders.
class ProgressiveFilm {
  public:
    ProgressiveFilm() = default;
    ProgressiveFilm(int width, int height, FilmPasses passes = FilmPasses::All);

    const Film& film() const { return film_; }
    // Starts a render: the film the new samples go to. Each pixel's first new sample is
    // accumulated onto base(), the following ones added.
    Film& begin();
    const Film& base() const { return film_; }
    // Every pixel has its new samples: the target becomes the film, holding `samples` per pixel.
    void commit(uint32_t samples);
    // The render failed: the film is as it was before begin().
    void abandon();

  private:
    Film film_;
    Film next_;
    bool in_place_ = true;
};

}  // namespace shgi
