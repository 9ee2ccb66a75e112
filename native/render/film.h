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
// Channel names: "Combined.R/G/B/A", "DiffDir.R/G/B", ..., "Normal.X/Y/Z", "Depth.Z".
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
    TransDir, TransInd, TransCol, Emit, Env, Normal, Depth,
};
inline constexpr int kPassCount = 14;

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
    Film(int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }
    uint32_t samples() const { return samples_; }

    // Adds one sample's values to pixel (x, y) (y = 0 is the top row).
    void add(int x, int y, const PassValues& values);
    // Sets pixel (x, y) to `base`'s sums there plus one sample's values (base may be this film;
    // it must have the same size). A render that must leave its film untouched until it
    // completes sums into a second film this way, without first copying the whole film.
    void accumulate(int x, int y, const Film& base, const PassValues& values);
    void set_samples(uint32_t samples) { samples_ = samples; }
    // Every sum back to zero, samples() to 0.
    void clear();

    // Normalised pixels of one pass, interleaved (height, width, channels) top row first.
    std::vector<float> pixels(Pass pass) const;
    // Every pass as Blender-style layers, Float channels.
    Image image() const;

  private:
    const vec3& sum(Pass pass, size_t pixel) const {
        return sums_[size_t(pass) * pixel_count() + pixel];
    }
    size_t pixel_count() const { return size_t(width_) * size_t(height_); }
    vec3 normalised(Pass pass, size_t pixel) const;

    int width_ = 0, height_ = 0;
    uint32_t samples_ = 0;
    std::vector<vec3> sums_;  // [pass][pixel]
};

}  // namespace shgi
