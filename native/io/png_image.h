// PNG output: linear scene-referred floats -> 8-bit sRGB PNG, the one place where SHGI applies a
// display transform (docs/architecture.md, "Colour").
//
// Encoding, per pixel: colour * 2^exposure (stops, as Blender's Film exposure), divided by alpha
// when the input is premultiplied (PNG stores straight alpha), clamped to [0, 1], encoded with
// the exact sRGB transfer function of IEC 61966-2-1 (not a 2.2 gamma), then rounded to the
// nearest of 256 levels. Alpha is linear: clamped and rounded, never exposed or sRGB-encoded.
// NaN encodes as 0. The file carries an sRGB chunk. Pixels are interleaved RGB or RGBA, top row
// first (as in Image). Written through libpng's simplified API (png_image_write_to_file), whose
// setjmp/longjmp error handling stays inside libpng, and atomically (temporary file + rename).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace shgi {

// sRGB transfer function (OETF) breakpoints, IEC 61966-2-1:1999.
inline constexpr double kSrgbLinearThreshold = 0.0031308;  // linear side
inline constexpr double kSrgbEncodedThreshold = 0.04045;   // encoded side
inline constexpr double kSrgbLinearSlope = 12.92;
inline constexpr double kSrgbGamma = 2.4;
inline constexpr double kSrgbScale = 1.055;
inline constexpr double kSrgbOffset = 0.055;

// Linear [0, 1] -> sRGB-encoded [0, 1]: 12.92 x up to 0.0031308, 1.055 x^(1/2.4) - 0.055 above.
// Input outside [0, 1] is clamped; NaN gives 0. Evaluated in double, rounded once to float.
float srgb_from_linear(float linear);
// The inverse: x / 12.92 up to 0.04045, ((x + 0.055) / 1.055)^2.4 above; same clamping.
float linear_from_srgb(float encoded);
// srgb_from_linear, then rounded to the nearest 8-bit level (0..255).
uint8_t srgb8_from_linear(float linear);

struct PngWriteSettings {
    float exposure = 0.0f;       // stops; colour is scaled by 2^exposure before encoding
    bool premultiplied = true;   // RGBA input has colour premultiplied by alpha (SHGI and Cycles
                                 // renders do); ignored for RGB input
};

// Writes `pixels` (width * height * channels linear floats, channels 3 = RGB or 4 = RGBA,
// interleaved, top row first) as an 8-bit sRGB PNG. Throws InvalidArgument for a bad size,
// channel count, pixel count or a non-finite exposure, IoError naming the path when the file
// cannot be written.
void write_png(const std::string& path, const std::vector<float>& pixels, int width, int height,
               int channels, const PngWriteSettings& settings = {});

}  // namespace shgi
