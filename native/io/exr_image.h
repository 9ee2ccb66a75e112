// OpenEXR files: write an Image as a single-part scanline EXR and read one back (OpenEXR 3.1).
//
// Layout of the files written:
// - data window = display window = (0, 0) .. (width - 1, height - 1), INCREASING_Y line order:
//   the first row in the file is the top row, matching Image's top-row-first buffers.
// - one channel per Image channel, with its name ("Combined.R", "Depth.Z") and pixel type. Float
//   channels round-trip bit-exactly (NaN payloads included); Half channels are rounded to the
//   nearest half (values beyond +-65504 become +-inf, as in every EXR writer).
// - compression: lossless only. The default is ZIP (16-scanline zlib blocks, Blender's default
//   EXR codec): it compresses the smooth, noise-free data SHGI writes (bakes, SH volumes) best
//   and decodes fastest. PIZ (wavelet) is better for noisy renders; ZIPS, RLE and NONE exist.
// - EXR sorts channels by name inside the file; the writer also stores the Image's channel order
//   in a string-vector attribute "shgiChannelOrder" so read_exr returns channels in the order
//   they were added. Files from other writers come back in layer order (as stored: sorted by
//   name) with the channels of each layer in Blender's order R, G, B, A, then X, Y, Z, W, then
//   U, V, then any other suffix by name.
//
// Reading accepts single-part and multi-part files (OpenEXR 2), their parts scanline or tiled,
// with HALF or FLOAT channels at full resolution. Every part is read; all must share the data
// window of the first. Blender 5.0 writes a multilayer EXR as one part per pass (part
// "ViewLayer.Combined" holding "ViewLayer.Combined.R", ...), other writers leave the layer to
// the part name (part "ViewLayer.Depth" holding "Z"): a channel of a multi-part file is named
// "<part name>.<channel name>" unless its name already starts with "<part name>." (as Blender's
// reader does), and the channels of all parts come back in the order described above, so a
// multi-part file reads exactly as the single-part file with the same passes (what Blender
// writes with "interleave" on, and Blender 3.4 always).
// Single-part files keep their channel names, and "shgiChannelOrder" is read from the first
// part. UINT or subsampled channels, deep parts, parts with another data window, two parts
// giving the same channel name, and images larger than a caller-given pixel budget are rejected
// with an IoError naming the file (and the part). Every OpenEXR exception becomes an
// shgi::IoError naming the path.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "io/image.h"

namespace shgi {

enum class ExrCompression { None, Rle, Zips, Zip, Piz };

// "none", "rle", "zips", "zip", "piz".
const char* exr_compression_name(ExrCompression compression);
// The inverse of exr_compression_name; throws InvalidArgument listing the valid names.
ExrCompression exr_compression_from_name(const std::string& name);

// Default read budget: 2^28 pixels (16384 x 16384), 1 GiB per float channel.
inline constexpr int64_t kDefaultMaxExrPixels = int64_t(1) << 28;
// read_exr also caps the total number of values at this many times max_pixels (e.g. four RGBA
// layers at the full pixel budget), so that a small, malicious header with thousands of
// channels cannot make the reader allocate terabytes.
inline constexpr int64_t kMaxExrValuesPerPixel = 16;
// read_exr and read_exr_info refuse files with more channels than this (in all parts together):
// an image's channels are found by name, so reading thousands of them took time quadratic in
// their number (40,000 channels of one pixel: 6.9 s). Blender's multilayer files hold tens to a
// few hundred.
inline constexpr size_t kMaxExrChannels = 4096;

struct ExrWriteSettings {
    ExrCompression compression = ExrCompression::Zip;
};

struct ExrChannelInfo {
    std::string name;
    PixelType pixel_type = PixelType::Float;
};

// What the header of an EXR file says, without reading its pixels.
struct ExrInfo {
    int width = 0;   // of the data window
    int height = 0;
    // Of the first part: "zip", "piz", ... or a lossy codec of another writer ("dwaa").
    std::string compression;
    std::vector<ExrChannelInfo> channels;  // of every part, in the order read_exr returns them
};

// Writes `image` to `path` atomically (a temporary file in the same folder, then a rename).
// Throws InvalidArgument for an image without channels, IoError naming the path when the file
// cannot be written.
void write_exr(const std::string& path, const Image& image, const ExrWriteSettings& settings = {});

// Reads every channel of every part of `path`. Throws IoError naming the path for a missing,
// unreadable or corrupt file, for unsupported channels or parts, and when width * height exceeds
// max_pixels (raise it only for trusted files), the channels of all parts together exceed
// kMaxExrValuesPerPixel * max_pixels, or there are more than kMaxExrChannels channels.
Image read_exr(const std::string& path, int64_t max_pixels = kDefaultMaxExrPixels);

// Reads only the header of `path` (same errors as read_exr, without the pixel and value
// budgets).
ExrInfo read_exr_info(const std::string& path);

}  // namespace shgi
