// Image: a width x height raster made of named float channels, the in-memory form of what SHGI
// writes to EXR (lightmaps, render passes, probe volumes) and PNG (previews).
//
// Conventions:
// - Rows are stored top row first, row-major: pixel (x, y) of a channel is data[y * width + x]
//   with y = 0 the TOP row, as EXR and PNG files store them. Blender's image buffers start at the
//   bottom row; the Blender side flips rows when it copies pixels in or out.
// - Channel names follow Blender's multilayer EXR style "<layer>.<channel>": "Combined.R",
//   "Combined.A", "DiffInd.G", "Depth.Z", "ViewLayer.Combined.R". The layer is everything before
//   the last '.', the channel suffix everything after it; a name without '.' ("R") belongs to
//   the unnamed layer "".
// - Values are linear scene-referred floats (colour: Rec.709 RGB). A channel's pixel type only
//   says how it is stored in a file: Half keeps 11 significant bits, Float is exact.
// - Channels keep the order in which they were added.
//
// Files are written atomically (write_file_atomically): a reader never sees a half-written file,
// and a failed write leaves no temporary file behind.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace shgi {

// Largest width or height accepted; far above any GPU texture or lightmap size (32768), small
// enough that width * height * channels cannot overflow 64-bit sizes.
inline constexpr int kMaxImageDimension = 1 << 20;
// Largest width * height accepted when building an Image: 2^31 pixels (8 GiB per float channel).
inline constexpr int64_t kMaxImagePixels = int64_t(1) << 31;

// Throws InvalidArgument unless 1 <= width, height <= kMaxImageDimension and
// width * height <= kMaxImagePixels; `what` names the image in the message.
void check_image_size(int width, int height, const char* what = "image");

// How a channel is stored in a file. In memory every channel is float.
enum class PixelType { Half, Float };

// "half" or "float".
const char* pixel_type_name(PixelType type);

struct ImageChannel {
    std::string name;                          // full name, e.g. "Combined.R"
    PixelType pixel_type = PixelType::Float;   // storage type in the file
    std::vector<float> data;                   // width * height values, top row first
};

class Image {
  public:
    // Throws InvalidArgument for sizes check_image_size rejects.
    Image(int width, int height);

    int width() const { return width_; }
    int height() const { return height_; }
    size_t pixel_count() const { return size_t(width_) * size_t(height_); }
    const std::vector<ImageChannel>& channels() const { return channels_; }

    // Appends one channel. Throws InvalidArgument for an empty name, a name ending in '.', a
    // name already present, or data whose size is not width * height.
    void add_channel(std::string name, PixelType pixel_type, std::vector<float> data);

    // Appends the channels "<layer>.<suffix>" for each suffix (e.g. {"R", "G", "B", "A"}) from
    // interleaved pixels: pixels[(y * width + x) * suffixes.size() + c]. An empty layer name
    // gives bare suffix names ("R"). Throws InvalidArgument if pixels.size() is not
    // width * height * suffixes.size(), or for the add_channel errors.
    void add_layer(const std::string& layer, const std::vector<std::string>& suffixes,
                   const std::vector<float>& pixels, PixelType pixel_type = PixelType::Float);

    // The channel called `name`, or nullptr.
    const ImageChannel* find_channel(const std::string& name) const;

    // Layer names in order of their first channel ("" for channels without a layer).
    std::vector<std::string> layer_names() const;
    // Channel suffixes of `layer` in channel order, e.g. {"R", "G", "B", "A"}.
    std::vector<std::string> layer_suffixes(const std::string& layer) const;
    // Interleaved pixels of `layer` in layer_suffixes() order (the inverse of add_layer).
    // Throws InvalidArgument if the image has no such layer.
    std::vector<float> layer_pixels(const std::string& layer) const;

  private:
    int width_ = 0;
    int height_ = 0;
    std::vector<ImageChannel> channels_;
};

// Splits "ViewLayer.Combined.R" into layer "ViewLayer.Combined" and suffix "R" at the last '.';
// a name without '.' gives layer "".
std::string channel_layer(const std::string& name);
std::string channel_suffix(const std::string& name);
// Joins a layer and a suffix ("" layer -> the bare suffix).
std::string channel_name(const std::string& layer, const std::string& suffix);

// True when `path` exists and is not a regular file (a folder, device, FIFO or socket): what a
// reader should not open, as a read could block, never end, or make no sense.
bool is_special_file(const std::string& path);

// Throws before a reader opens `path` (`what` names the kind of file, "EXR", "probe file"): an
// IoError for a folder, or a device, FIFO or socket (a read could block or never end), and an
// InvalidArgument for a path holding a NUL byte (the C library would read the name only up to
// it, i.e. another file). A missing or unreadable file is left to the reader's own message.
void require_readable_file(const std::string& path, const char* what);

// Writes `path` atomically: calls write_temp(temp_path) with a new, empty file in the same
// folder, then renames it over `path` (atomic on POSIX filesystems). If write_temp throws, or
// the rename fails, the temporary file is removed and the error propagates. Throws IoError
// naming the path when its folder does not exist or is not writable, or when `path` is a
// folder or another non-regular file (a device such as /dev/null would be replaced by the
// rename); InvalidArgument when it holds a NUL byte. A symbolic link is followed (to the end of
// its chain): the file it points to is replaced and the link stays a link.
void write_file_atomically(const std::string& path,
                           const std::function<void(const std::string& temp_path)>& write_temp);

}  // namespace shgi
