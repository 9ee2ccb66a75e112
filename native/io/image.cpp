#include "io/image.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <system_error>
#include <utility>

#include "scene/camera.h"
#include "util/error.h"

namespace shgi {

namespace fs = std::filesystem;

namespace {

InvalidArgument duplicate_channel(const std::string& name) {
    return InvalidArgument(format_message("image channel \"", name,
                                          "\" is already present; channel names must be unique"));
}

}  // namespace

static_assert(kMaxImageDimension == int(kMaxCameraResolution),
              "a camera's largest resolution is an image's largest side");

const char* pixel_type_name(PixelType type) {
    return type == PixelType::Half ? "half" : "float";
}

void check_image_size(int width, int height, const char* what) {
    if (width < 1 || height < 1 || width > kMaxImageDimension || height > kMaxImageDimension) {
        throw InvalidArgument(format_message(what, " size ", width, " x ", height,
                                             " is out of range: width and height must be in [1, ",
                                             kMaxImageDimension, "]"));
    }
    const int64_t pixels = int64_t(width) * int64_t(height);
    if (pixels > kMaxImagePixels) {
        throw InvalidArgument(format_message(what, " size ", width, " x ", height, " = ", pixels,
                                             " pixels exceeds the limit of ", kMaxImagePixels,
                                             " pixels; split it into tiles"));
    }
}

Image::Image(int width, int height) : width_(width), height_(height) {
    check_image_size(width, height);
}

void Image::add_channel(std::string name, PixelType pixel_type, std::vector<float> data) {
    if (name.empty()) {
        throw InvalidArgument(
            "image channel name is empty; use Blender-style names such as \"Combined.R\"");
    }
    if (name.back() == '.') {
        throw InvalidArgument(format_message("image channel name \"", name,
                                             "\" ends with '.'; add a channel suffix (\"",
                                             name, "R\")"));
    }
    if (find_channel(name) != nullptr) throw duplicate_channel(name);
    if (data.size() != pixel_count()) {
        throw InvalidArgument(format_message("image channel \"", name, "\" has ", data.size(),
                                             " values, expected width * height = ", width_, " * ",
                                             height_, " = ", pixel_count()));
    }
    channels_.push_back(ImageChannel{std::move(name), pixel_type, std::move(data)});
}

void Image::add_layer(const std::string& layer, const std::vector<std::string>& suffixes,
                      const std::vector<float>& pixels, PixelType pixel_type) {
    const size_t count = suffixes.size();
    if (count == 0) {
        throw InvalidArgument(format_message("image layer \"", layer,
                                             "\" has no channel suffixes; give e.g. {\"R\", "
                                             "\"G\", \"B\"}"));
    }
    if (pixels.size() != pixel_count() * count) {
        throw InvalidArgument(format_message("image layer \"", layer, "\" has ", pixels.size(),
                                             " values, expected width * height * channels = ",
                                             width_, " * ", height_, " * ", count, " = ",
                                             pixel_count() * count));
    }
    for (const std::string& suffix : suffixes) {
        if (suffix.empty()) {
            throw InvalidArgument(
                format_message("image layer \"", layer, "\" has an empty channel suffix"));
        }
    }
    // Check every name before adding any, so that a failure leaves the image unchanged.
    for (size_t c = 0; c < count; ++c) {
        const std::string name = channel_name(layer, suffixes[c]);
        const bool repeated = std::count(suffixes.begin(), suffixes.end(), suffixes[c]) > 1;
        if (repeated || find_channel(name) != nullptr) throw duplicate_channel(name);
    }
    for (size_t c = 0; c < count; ++c) {
        std::vector<float> data(pixel_count());
        for (size_t i = 0; i < data.size(); ++i) data[i] = pixels[i * count + c];
        add_channel(channel_name(layer, suffixes[c]), pixel_type, std::move(data));
    }
}

const ImageChannel* Image::find_channel(const std::string& name) const {
    for (const ImageChannel& channel : channels_) {
        if (channel.name == name) return &channel;
    }
    return nullptr;
}

std::vector<std::string> Image::layer_names() const {
    std::vector<std::string> layers;
    for (const ImageChannel& channel : channels_) {
        std::string layer = channel_layer(channel.name);
        if (std::find(layers.begin(), layers.end(), layer) == layers.end()) {
            layers.push_back(std::move(layer));
        }
    }
    return layers;
}

std::vector<std::string> Image::layer_suffixes(const std::string& layer) const {
    std::vector<std::string> suffixes;
    for (const ImageChannel& channel : channels_) {
        if (channel_layer(channel.name) == layer) suffixes.push_back(channel_suffix(channel.name));
    }
    return suffixes;
}

std::vector<float> Image::layer_pixels(const std::string& layer) const {
    std::vector<const ImageChannel*> members;
    for (const ImageChannel& channel : channels_) {
        if (channel_layer(channel.name) == layer) members.push_back(&channel);
    }
    if (members.empty()) {
        throw InvalidArgument(format_message("image has no layer \"", layer, "\""));
    }
    const size_t count = members.size();
    std::vector<float> pixels(pixel_count() * count);
    for (size_t c = 0; c < count; ++c) {
        const std::vector<float>& data = members[c]->data;
        for (size_t i = 0; i < data.size(); ++i) pixels[i * count + c] = data[i];
    }
    return pixels;
}

std::string channel_layer(const std::string& name) {
    const size_t dot = name.rfind('.');
    return dot == std::string::npos ? std::string() : name.substr(0, dot);
}

std::string channel_suffix(const std::string& name) {
    const size_t dot = name.rfind('.');
    return dot == std::string::npos ? name : name.substr(dot + 1);
}

std::string channel_name(const std::string& layer, const std::string& suffix) {
    return layer.empty() ? suffix : layer + "." + suffix;
}

namespace {

void require_no_nul(const std::string& path, const char* action) {
    const size_t nul = path.find('\0');
    if (nul == std::string::npos) return;
    throw InvalidArgument(format_message("cannot ", action, " \"", path.substr(0, nul),
                                         "\\0...\": the path holds a NUL byte at position ", nul,
                                         "; file names cannot contain one"));
}

}  // namespace

bool is_special_file(const std::string& path) {
    std::error_code error;
    const fs::file_status status = fs::status(path, error);
    return !error && fs::exists(status) && !fs::is_regular_file(status);
}

void require_readable_file(const std::string& path, const char* what) {
    require_no_nul(path, "read");
    if (!is_special_file(path)) return;
    std::error_code error;
    throw IoError(format_message("cannot read ", what, " \"", path, "\": ",
                                 fs::is_directory(path, error)
                                     ? "it is a folder; pass a file"
                                     : "it is not a regular file (a device, FIFO or socket)"));
}

namespace {

// The folder the file `path` will be written to, checked to exist; `label` names the write in
// messages (write_label).
fs::path checked_parent_folder(const std::string& path, const std::string& label) {
    if (path.empty()) throw IoError("cannot write a file: the path is empty");
    const fs::path target(path);
    if (!target.has_filename()) {
        throw IoError(format_message("cannot write ", label,
                                     ": the path names a folder; add a file name"));
    }
    fs::path parent = target.parent_path();
    if (parent.empty()) parent = ".";
    std::error_code error;
    if (!fs::is_directory(parent, error)) {
        if (fs::exists(parent, error))
            throw IoError(format_message("cannot write ", label, ": \"", parent.string(),
                                         "\" is a file, not a folder; choose another output "
                                         "folder or move the file away"));
        throw IoError(format_message("cannot write ", label, ": folder \"", parent.string(),
                                     "\" does not exist; create it first"));
    }
    if (fs::is_directory(target, error)) {
        throw IoError(format_message("cannot write ", label,
                                     ": a folder of that name exists; choose a file name"));
    }
    const fs::file_status existing = fs::status(target, error);
    if (!error && fs::exists(existing) && !fs::is_regular_file(existing)) {
        throw IoError(format_message("cannot write ", label, ": it exists and is not a "
                                     "regular file (a device, FIFO or socket), which the write "
                                     "would replace; choose a file name"));
    }
    return parent;
}

// Creates a new, empty, hidden temporary file next to `path` and returns its name. Exclusive
// creation ("x") guarantees two writers never share a temporary file.
std::string create_temp_file(const fs::path& parent, const std::string& path,
                             const std::string& label) {
    constexpr int kAttempts = 8;
    std::random_device entropy;
    for (int attempt = 0; attempt < kAttempts; ++attempt) {
        const uint64_t tag = (uint64_t(entropy()) << 32) ^ uint64_t(entropy());
        char suffix[32];
        std::snprintf(suffix, sizeof(suffix), ".%016llx.tmp", (unsigned long long)tag);
        const fs::path temp =
            parent / ("." + fs::path(path).filename().string() + suffix);
        std::FILE* file = std::fopen(temp.string().c_str(), "wbx");
        if (file != nullptr) {
            std::fclose(file);
            return temp.string();
        }
        if (errno != EEXIST) {
            throw IoError(format_message("cannot write ", label, ": cannot create a file in "
                                         "folder \"", parent.string(), "\" (",
                                         std::strerror(errno), "); check its permissions or "
                                         "choose another folder"));
        }
    }
    throw IoError(format_message("cannot write ", label,
                                 ": no free temporary file name in folder \"", parent.string(),
                                 "\""));
}

// Links followed before a write gives up, as the kernel's own limit (ELOOP) for a path.
constexpr int kMaxSymlinkHops = 40;

// The file a write of `path` lands in: at the end of its chain of symbolic links, if it is one
// (a dangling link too: its target is created), so that the rename replaces the file the link
// points to, as writing through the link would, rather than the link itself.
std::string write_destination(const std::string& path) {
    fs::path destination(path);
    for (int hops = 0;; ++hops) {
        std::error_code error;
        if (!fs::is_symlink(fs::symlink_status(destination, error))) return destination.string();
        if (hops == kMaxSymlinkHops)
            throw IoError(format_message("cannot write \"", path, "\": more than ",
                                         kMaxSymlinkHops, " symbolic links in a chain (a loop?); "
                                         "pass the file itself"));
        const fs::path target = fs::read_symlink(destination, error);
        if (error)
            throw IoError(format_message("cannot write \"", path,
                                         "\": reading the symbolic link \"",
                                         destination.string(), "\" failed (", error.message(),
                                         ")"));
        destination = target.is_absolute() ? target : destination.parent_path() / target;
    }
}

// How messages name a write: the caller's path, and the file it lands in when that differs.
std::string write_label(const std::string& path, const std::string& destination) {
    if (destination == path) return format_message("\"", path, "\"");
    return format_message("\"", path, "\" (a link to \"", destination, "\")");
}

}  // namespace

void write_file_atomically(const std::string& path,
                           const std::function<void(const std::string& temp_path)>& write_temp) {
    require_no_nul(path, "write");
    const std::string destination = write_destination(path);
    const std::string label = write_label(path, destination);
    const fs::path parent = checked_parent_folder(destination, label);
    const std::string temp = create_temp_file(parent, destination, label);
    try {
        write_temp(temp);
    } catch (...) {
        std::error_code ignored;
        fs::remove(temp, ignored);
        throw;
    }
    std::error_code error;
    fs::rename(temp, destination, error);
    if (error) {
        std::error_code ignored;
        fs::remove(temp, ignored);
        throw IoError(format_message("cannot write ", label, ": renaming the temporary file \"",
                                     temp, "\" failed (", error.message(), ")"));
    }
}

}  // namespace shgi
