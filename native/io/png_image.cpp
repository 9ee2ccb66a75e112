#include "io/png_image.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <png.h>

#include "io/image.h"
#include "util/error.h"

namespace shgi {

namespace {

constexpr double kMaxLevel = 255.0;  // 8-bit output
constexpr int kRgb = 3;
constexpr int kRgba = 4;

// NaN -> 0, otherwise clamped to [0, 1].
double clamp_unit(double value) {
    if (!(value > 0.0)) return 0.0;  // also catches NaN
    return std::min(value, 1.0);
}

uint8_t to_level(double unit) { return uint8_t(std::lround(clamp_unit(unit) * kMaxLevel)); }

// Releases libpng's state for a png_image however the write ends.
class PngImageGuard {
  public:
    explicit PngImageGuard(png_image& image) : image_(image) {}
    ~PngImageGuard() { png_image_free(&image_); }
    PngImageGuard(const PngImageGuard&) = delete;
    PngImageGuard& operator=(const PngImageGuard&) = delete;

  private:
    png_image& image_;
};

void check_png_input(const std::vector<float>& pixels, int width, int height, int channels,
                     const PngWriteSettings& settings) {
    check_image_size(width, height, "PNG image");
    if (channels != kRgb && channels != kRgba) {
        throw InvalidArgument(format_message("PNG image has ", channels,
                                             " channels; give 3 (RGB) or 4 (RGBA)"));
    }
    const size_t expected = size_t(width) * size_t(height) * size_t(channels);
    if (pixels.size() != expected) {
        throw InvalidArgument(format_message("PNG image has ", pixels.size(),
                                             " values, expected width * height * channels = ",
                                             width, " * ", height, " * ", channels, " = ",
                                             expected));
    }
    if (!std::isfinite(settings.exposure)) {
        throw InvalidArgument(format_message("PNG exposure is ", settings.exposure,
                                             "; give a finite number of stops"));
    }
}

// Linear float pixels -> interleaved 8-bit sRGB (colour) and linear (alpha) levels.
std::vector<uint8_t> encode_pixels(const std::vector<float>& pixels, int channels,
                                   const PngWriteSettings& settings) {
    const double scale = std::exp2(double(settings.exposure));
    const bool unpremultiply = channels == kRgba && settings.premultiplied;
    std::vector<uint8_t> levels(pixels.size());
    for (size_t first = 0; first < pixels.size(); first += size_t(channels)) {
        double colour_scale = scale;
        if (channels == kRgba) {
            const double alpha = clamp_unit(pixels[first + kRgb]);
            levels[first + kRgb] = to_level(alpha);
            // Fully transparent premultiplied colour is zero; keep it zero.
            if (unpremultiply) colour_scale = alpha > 0.0 ? scale / alpha : 0.0;
        }
        for (int c = 0; c < kRgb; ++c) {
            const double linear = double(pixels[first + size_t(c)]) * colour_scale;
            levels[first + size_t(c)] = srgb8_from_linear(float(linear));
        }
    }
    return levels;
}

void write_png_file(const std::string& file_path, const std::string& path,
                    const std::vector<uint8_t>& levels, int width, int height, int channels) {
    png_image image;
    std::memset(&image, 0, sizeof(image));
    image.version = PNG_IMAGE_VERSION;
    image.width = png_uint_32(width);
    image.height = png_uint_32(height);
    image.format = channels == kRgba ? PNG_FORMAT_RGBA : PNG_FORMAT_RGB;
    PngImageGuard guard(image);
    const png_int_32 row_stride = png_int_32(width * channels);  // in components, top row first
    const int written = png_image_write_to_file(&image, file_path.c_str(), 0, levels.data(),
                                                row_stride, nullptr);
    if (written == 0 || PNG_IMAGE_FAILED(image)) {
        throw IoError(format_message("cannot write PNG \"", path, "\": libpng: ", image.message));
    }
}

}  // namespace

float srgb_from_linear(float linear) {
    const double x = clamp_unit(linear);
    if (x <= kSrgbLinearThreshold) return float(kSrgbLinearSlope * x);
    return float(clamp_unit(kSrgbScale * std::pow(x, 1.0 / kSrgbGamma) - kSrgbOffset));
}

float linear_from_srgb(float encoded) {
    const double x = clamp_unit(encoded);
    if (x <= kSrgbEncodedThreshold) return float(x / kSrgbLinearSlope);
    return float(clamp_unit(std::pow((x + kSrgbOffset) / kSrgbScale, kSrgbGamma)));
}

uint8_t srgb8_from_linear(float linear) { return to_level(srgb_from_linear(linear)); }

void write_png(const std::string& path, const std::vector<float>& pixels, int width, int height,
               int channels, const PngWriteSettings& settings) {
    check_png_input(pixels, width, height, channels, settings);
    const std::vector<uint8_t> levels = encode_pixels(pixels, channels, settings);
    write_file_atomically(path, [&](const std::string& temp_path) {
        write_png_file(temp_path, path, levels, width, height, channels);
    });
}

}  // namespace shgi
