#include "render/film.h"

#include <algorithm>
#include <utility>

#include "util/error.h"
#include "util/memory.h"

namespace shgi {
namespace {

// A film may take at most this share of what the process may still allocate: a progressive
// renderer holds two (ProgressiveFilm), and its passes' images are as large again. Past it the
// system would kill the host while the sums are zeroed, before any allocation could fail.
constexpr uint64_t kFilmCopies = 4;

// Cycles writes this depth where no sample hit anything (film_get_pass_pixel_depth).
constexpr float kMissDepth = 1e10f;

constexpr const char* kPassNames[kPassCount] = {
    "Combined", "DiffDir", "DiffInd", "DiffCol", "GlossDir", "GlossInd", "GlossCol",
    "TransDir", "TransInd", "TransCol", "Emit",    "Env",     "Normal",   "Depth",
    "Denoising Albedo", "Denoising Normal",
};

// The colour pass a light pass is divided by, or the pass itself when it is not divided.
Pass divisor_of(Pass pass) {
    switch (pass) {
        case Pass::DiffDir:
        case Pass::DiffInd: return Pass::DiffCol;
        case Pass::GlossDir:
        case Pass::GlossInd: return Pass::GlossCol;
        case Pass::TransDir:
        case Pass::TransInd: return Pass::TransCol;
        default: return pass;
    }
}

float safe_divide(float a, float b) { return b != 0.0f ? a / b : 0.0f; }

}  // namespace

const char* pass_name(Pass pass) { return kPassNames[size_t(pass)]; }

std::vector<std::string> pass_suffixes(Pass pass) {
    switch (pass) {
        case Pass::Combined: return {"R", "G", "B", "A"};
        case Pass::Normal:
        case Pass::DenoisingNormal: return {"X", "Y", "Z"};
        case Pass::Depth: return {"Z"};
        default: return {"R", "G", "B"};
    }
}

Film::Film(int width, int height, FilmPasses passes)
    : width_(width), height_(height), passes_(passes),
      pass_count_(passes == FilmPasses::All ? size_t(kPassCount) : 1) {
    check_image_size(width, height, "film");
    const uint64_t bytes = uint64_t(pass_count_) * pixel_count() * sizeof(vec3);
    require_memory(saturating_mul(bytes, kFilmCopies),
                   format_message("the camera resolution (film) ", width, " x ", height,
                                  " pixels with ", pass_count_, " passes (", kFilmCopies,
                                  " copies: two films and their images)"),
                   "lower the camera's resolution_x / resolution_y (or Blender's resolution %)");
    sums_.assign(pass_count_ * pixel_count(), vec3(0.0f));
}

void Film::add(int x, int y, const PassValues& values) {
    accumulate(x, y, *this, values);
}

void Film::clear() {
    std::fill(sums_.begin(), sums_.end(), vec3(0.0f));
    samples_ = 0;
}

vec3 Film::normalised(Pass pass, size_t pixel) const {
    const vec3& s = sum(pass, pixel);
    const Pass divisor = divisor_of(pass);
    if (divisor != pass) {
        const vec3& c = sum(divisor, pixel);
        return vec3(safe_divide(s.x, c.x), safe_divide(s.y, c.y), safe_divide(s.z, c.z));
    }
    const float scale = samples_ > 0 ? 1.0f / float(samples_) : 0.0f;
    if (pass == Pass::Depth) return vec3(s.x != 0.0f ? s.x * scale : kMissDepth, 0.0f, 0.0f);
    return s * scale;
}

std::vector<float> Film::pixels(Pass pass) const {
    if (!has_pass(pass))
        throw InvalidArgument(format_message("Film::pixels: the film sums only Combined, not ",
                                             pass_name(pass), "; render with every pass"));
    const size_t channels = pass_suffixes(pass).size();
    std::vector<float> out(pixel_count() * channels);
    for (size_t i = 0; i < pixel_count(); ++i) {
        const vec3 v = normalised(pass, i);
        for (size_t c = 0; c < channels; ++c) out[i * channels + c] = c < 3 ? v[int(c)] : 1.0f;
    }
    return out;
}

Image Film::image() const {
    Image image(width_, height_);
    for (size_t p = 0; p < pass_count_; ++p)
        image.add_layer(pass_name(Pass(p)), pass_suffixes(Pass(p)), pixels(Pass(p)));
    return image;
}

ProgressiveFilm::ProgressiveFilm(int width, int height, FilmPasses passes)
    : film_(width, height, passes) {}

Film& ProgressiveFilm::begin() {
    in_place_ = film_.samples() == 0;
    if (in_place_) return film_;
    if (next_.width() != film_.width() || next_.height() != film_.height() ||
        next_.passes() != film_.passes())
        next_ = Film(film_.width(), film_.height(), film_.passes());
    return next_;
}

void ProgressiveFilm::commit(uint32_t samples) {
    Film& target = in_place_ ? film_ : next_;
    target.set_samples(samples);
    if (!in_place_) std::swap(film_, next_);
}

void ProgressiveFilm::abandon() {
    if (in_place_) film_.clear();
}

}  // namespace shgi
