#include "io/exr_image.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <limits>
#include <map>
#include <tuple>
#include <utility>

#include <Iex.h>
#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputPart.h>
#include <ImfMultiPartInputFile.h>
#include <ImfOutputFile.h>
#include <ImfPartType.h>
#include <ImfStringVectorAttribute.h>
#include <half.h>

#include "util/error.h"

namespace shgi {

namespace {

// OpenEXR 3.1 sizes an attribute's value from its 32-bit size field and fills it before it meets
// the end of the file: a damaged size field (2^31 in an 830-byte file, found by fuzzing) made it
// allocate and zero-fill ~2 GB for a few seconds before "Early end of file". So the headers are
// walked first (name, type, size, value per attribute; an empty name ends a header; in a
// multi-part file an empty header ends the list) and a size the rest of the file cannot hold is
// refused. Anything else malformed is left to OpenEXR, which reports it.
void check_header_attribute_sizes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return;  // OpenEXR names the failure
    in.seekg(0, std::ios::end);
    const int64_t file_size = int64_t(in.tellg());
    in.seekg(0);
    uint8_t preamble[8];
    if (!in.read(reinterpret_cast<char*>(preamble), sizeof(preamble))) return;
    constexpr uint8_t kMagic[4] = {0x76, 0x2f, 0x31, 0x01};
    if (!std::equal(kMagic, kMagic + 4, preamble)) return;
    const bool multi_part = (preamble[5] & 0x10) != 0;  // version flag bit 12
    // A name or type (at most 255 bytes with the long-names flag); false at the end of the file
    // or past 255 bytes.
    const auto read_string = [&](std::string& out) {
        out.clear();
        for (char c; in.get(c);) {
            if (c == '\0') return true;
            if (out.size() == 255) return false;
            out.push_back(c);
        }
        return false;
    };
    std::string name, type;
    while (read_string(name)) {
        if (name.empty()) {  // the end of a header: the last one, or an empty one follows
            if (!multi_part || in.peek() == '\0' || in.peek() == EOF) return;
            continue;
        }
        uint8_t size_bytes[4];
        if (!read_string(type) || !in.read(reinterpret_cast<char*>(size_bytes), 4)) return;
        const int32_t size = int32_t(uint32_t(size_bytes[0]) | uint32_t(size_bytes[1]) << 8 |
                                     uint32_t(size_bytes[2]) << 16 | uint32_t(size_bytes[3]) << 24);
        const int64_t remaining = file_size - int64_t(in.tellg());
        if (size < 0 || int64_t(size) > remaining) {
            throw IoError(format_message(
                "cannot read EXR \"", path, "\": the file is damaged: its header attribute \"",
                name, "\" (", type, ") claims ", size, " bytes, but ", remaining,
                " bytes are left in the file"));
        }
        in.seekg(size, std::ios::cur);
    }
}

// Header attribute holding the channel names in the order they were added to the Image.
constexpr const char* kChannelOrderAttribute = "shgiChannelOrder";

struct CompressionName {
    Imf::Compression imf;
    const char* name;
};

// Every OpenEXR 3.1 codec by name; the first five are the ones SHGI writes (ExrCompression).
constexpr std::array<CompressionName, 10> kCompressionNames = {{
    {Imf::NO_COMPRESSION, "none"},
    {Imf::RLE_COMPRESSION, "rle"},
    {Imf::ZIPS_COMPRESSION, "zips"},
    {Imf::ZIP_COMPRESSION, "zip"},
    {Imf::PIZ_COMPRESSION, "piz"},
    {Imf::PXR24_COMPRESSION, "pxr24"},
    {Imf::B44_COMPRESSION, "b44"},
    {Imf::B44A_COMPRESSION, "b44a"},
    {Imf::DWAA_COMPRESSION, "dwaa"},
    {Imf::DWAB_COMPRESSION, "dwab"},
}};

Imf::Compression to_imf(ExrCompression compression) {
    switch (compression) {
        case ExrCompression::None: return Imf::NO_COMPRESSION;
        case ExrCompression::Rle: return Imf::RLE_COMPRESSION;
        case ExrCompression::Zips: return Imf::ZIPS_COMPRESSION;
        case ExrCompression::Zip: return Imf::ZIP_COMPRESSION;
        case ExrCompression::Piz: return Imf::PIZ_COMPRESSION;
    }
    throw Internal(format_message("unknown ExrCompression ", int(compression)));
}

const char* imf_compression_name(Imf::Compression compression) {
    for (const CompressionName& entry : kCompressionNames) {
        if (entry.imf == compression) return entry.name;
    }
    return "unknown";
}

// Position of a channel suffix in Blender's order: R G B A, X Y Z W, U V, then the rest.
int suffix_rank(const std::string& suffix) {
    static const std::array<const char*, 10> kOrder = {"R", "G", "B", "A", "X",
                                                       "Y", "Z", "W", "U", "V"};
    for (size_t i = 0; i < kOrder.size(); ++i) {
        if (suffix == kOrder[i]) return int(i);
    }
    return int(kOrder.size());
}

// Channels of a file from another writer: layers in order of first appearance in the (sorted)
// channel list, each layer's channels in Blender's suffix order, then by name.
void sort_channels_blender_style(std::vector<ExrChannelInfo>& channels) {
    std::vector<std::string> layers;
    for (const ExrChannelInfo& channel : channels) {
        const std::string layer = channel_layer(channel.name);
        if (std::find(layers.begin(), layers.end(), layer) == layers.end()) layers.push_back(layer);
    }
    auto key = [&layers](const ExrChannelInfo& channel) {
        const std::string suffix = channel_suffix(channel.name);
        const auto layer = std::find(layers.begin(), layers.end(), channel_layer(channel.name));
        return std::make_tuple(layer - layers.begin(), suffix_rank(suffix), suffix);
    };
    std::stable_sort(channels.begin(), channels.end(),
                     [&key](const ExrChannelInfo& a, const ExrChannelInfo& b) {
                         return key(a) < key(b);
                     });
}

// Puts `channels` in the order SHGI wrote them when the header records it and names exactly
// these channels; otherwise in Blender's order.
void order_channels(const Imf::Header& header, std::vector<ExrChannelInfo>& channels) {
    const auto* order = header.findTypedAttribute<Imf::StringVectorAttribute>(
        kChannelOrderAttribute);
    if (order != nullptr && order->value().size() == channels.size()) {
        std::vector<ExrChannelInfo> ordered;
        for (const std::string& name : order->value()) {
            const auto found = std::find_if(channels.begin(), channels.end(),
                                            [&name](const ExrChannelInfo& c) {
                                                return c.name == name;
                                            });
            if (found == channels.end()) break;
            ordered.push_back(*found);
        }
        if (ordered.size() == channels.size()) {
            channels = std::move(ordered);
            return;
        }
    }
    sort_channels_blender_style(channels);
}

// "part 2 \"ViewLayer.Depth\"" for error messages; parts need not have a name.
std::string part_label(const Imf::Header& header, int part) {
    if (!header.hasName()) return format_message("part ", part);
    return format_message("part ", part, " \"", header.name(), "\"");
}

std::string format_window(const Imath::Box2i& window) {
    return format_message("(", window.min.x, ", ", window.min.y, ") - (", window.max.x, ", ",
                          window.max.y, ")");
}

// The name read_exr gives channel `name` of a part called `part_name`. Blender 5.0 writes one
// part per pass, named "ViewLayer.Combined", whose channels carry the full name
// "ViewLayer.Combined.R"; other writers (Houdini) name the channel "R" and leave the layer to
// the part name. Like Blender's reader, prefix the part name unless the channel already has it,
// so that both give the names of the single-part file with the same passes.
std::string layer_channel_name(const std::string& part_name, const std::string& name) {
    if (part_name.empty() || name.rfind(part_name + ".", 0) == 0) return name;
    return part_name + "." + name;
}

// Throws unless SHGI can read `channel`: half or float, not subsampled.
void check_readable_channel(const std::string& path, const std::string& name,
                            const Imf::Channel& channel) {
    if (channel.type != Imf::HALF && channel.type != Imf::FLOAT) {
        throw IoError(format_message("cannot read EXR \"", path, "\": channel \"", name,
                                     "\" holds unsigned integers; SHGI reads only half and "
                                     "float channels"));
    }
    if (channel.xSampling != 1 || channel.ySampling != 1) {
        throw IoError(format_message("cannot read EXR \"", path, "\": channel \"", name,
                                     "\" is subsampled (", channel.xSampling, " x ",
                                     channel.ySampling, "); SHGI reads only full-resolution "
                                     "channels"));
    }
}

// Throws unless part `part` holds flat (scanline or tiled) pixels in the data window of part 0.
void check_readable_part(const std::string& path, const Imf::MultiPartInputFile& file,
                         int part) {
    const Imf::Header& header = file.header(part);
    if (header.hasType() && Imf::isDeepData(header.type())) {
        throw IoError(format_message("cannot read EXR \"", path, "\": ",
                                     part_label(header, part), " holds deep data (",
                                     header.type(), "); SHGI reads only flat scanline and tiled "
                                     "images, one value per channel and pixel"));
    }
    const Imath::Box2i& window = header.dataWindow();
    const Imath::Box2i& first_window = file.header(0).dataWindow();
    if (window != first_window) {
        throw IoError(format_message(
            "cannot read EXR \"", path, "\": ", part_label(header, part), " has the data window ",
            format_window(window), " but ", part_label(file.header(0), 0), " has ",
            format_window(first_window), "; SHGI reads only files whose parts share one data "
            "window (crop or pad the passes to one size when writing)"));
    }
}

// Where the pixels of one channel of read_exr's Image are in the file.
struct ChannelSource {
    int part = 0;
    std::string name_in_part;  // without the part-name prefix layer_channel_name may add
};

// The channels of every part of a file, checked readable and named as read_exr returns them.
struct ExrLayout {
    Imath::Box2i data_window;              // the same in every part
    std::vector<ExrChannelInfo> channels;  // in read order
    std::map<std::string, ChannelSource> sources;  // by ExrChannelInfo::name
};

ExrLayout read_layout(const std::string& path, const Imf::MultiPartInputFile& file) {
    ExrLayout layout;
    layout.data_window = file.header(0).dataWindow();
    // A single-part file keeps its channel names whatever its name attribute says, so files
    // SHGI and Blender 3.4 write read as before.
    const bool prefix_part_names = file.parts() > 1;
    for (int part = 0; part < file.parts(); ++part) {
        check_readable_part(path, file, part);
        const Imf::Header& header = file.header(part);
        const std::string part_name =
            prefix_part_names && header.hasName() ? header.name() : std::string();
        for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
            if (layout.channels.size() == kMaxExrChannels)
                throw IoError(format_message("cannot read EXR \"", path, "\": it has more than ",
                                             kMaxExrChannels, " channels, the most SHGI reads"));
            const std::string name = layer_channel_name(part_name, it.name());
            check_readable_channel(path, name, it.channel());
            const auto [found, inserted] =
                layout.sources.emplace(name, ChannelSource{part, it.name()});
            if (!inserted) {
                throw IoError(format_message(
                    "cannot read EXR \"", path, "\": channel \"", name, "\" is in both ",
                    part_label(file.header(found->second.part), found->second.part), " and ",
                    part_label(header, part), "; SHGI needs unique channel names: rename one "
                    "when writing the file"));
            }
            layout.channels.push_back(ExrChannelInfo{
                name, it.channel().type == Imf::HALF ? PixelType::Half : PixelType::Float});
        }
    }
    // By name, as the channel list of a single-part file with these channels is, then in the
    // order SHGI wrote them or in Blender's: a multi-part file reads as its single-part twin.
    std::sort(layout.channels.begin(), layout.channels.end(),
              [](const ExrChannelInfo& a, const ExrChannelInfo& b) { return a.name < b.name; });
    order_channels(file.header(0), layout.channels);
    return layout;
}

// Width and height of the data window, checked to be a valid, non-empty box.
std::pair<int64_t, int64_t> data_window_size(const std::string& path,
                                             const Imath::Box2i& window) {
    const int64_t width = int64_t(window.max.x) - int64_t(window.min.x) + 1;
    const int64_t height = int64_t(window.max.y) - int64_t(window.min.y) + 1;
    if (width < 1 || height < 1 || width > kMaxImageDimension || height > kMaxImageDimension) {
        throw IoError(format_message("cannot read EXR \"", path, "\": its data window is ", width,
                                     " x ", height, " pixels; SHGI reads sizes from 1 to ",
                                     kMaxImageDimension));
    }
    return {width, height};
}

// a * b for non-negative a, b, or INT64_MAX where that overflows: budgets near 2^63 (a caller's
// "no limit") must not wrap round to refuse, or admit, everything.
int64_t saturating_product(int64_t a, int64_t b) {
    if (a != 0 && b > std::numeric_limits<int64_t>::max() / a)
        return std::numeric_limits<int64_t>::max();
    return a * b;
}

void check_read_budget(const std::string& path, int64_t width, int64_t height,
                       size_t channel_count, int64_t max_pixels) {
    const int64_t pixels = saturating_product(width, height);
    if (pixels > max_pixels) {
        throw IoError(format_message("cannot read EXR \"", path, "\": it is ", width, " x ", height,
                                     " = ", pixels, " pixels, more than max_pixels = ", max_pixels,
                                     "; raise max_pixels if the file is trusted"));
    }
    const int64_t values = saturating_product(pixels, int64_t(channel_count));
    const int64_t max_values = saturating_product(kMaxExrValuesPerPixel, max_pixels);
    if (values > max_values) {
        throw IoError(format_message("cannot read EXR \"", path, "\": its ", channel_count,
                                     " channels of ", pixels, " pixels hold ", values,
                                     " values, more than ", kMaxExrValuesPerPixel,
                                     " * max_pixels = ", max_values,
                                     "; raise max_pixels if the file is trusted"));
    }
}

// OpenEXR stores channel names of at most 255 bytes, NUL-terminated: a longer name, or one with
// a NUL inside, would be cut short in the file, and the layer's channels merged into one.
constexpr size_t kMaxExrNameBytes = 255;

void check_writable(const Image& image) {
    if (image.channels().empty()) {
        throw InvalidArgument("cannot write an EXR image without channels; add a layer first");
    }
    for (const ImageChannel& channel : image.channels()) {
        const std::string& name = channel.name;
        if (name.find('\0') != std::string::npos)  // shown up to the NUL
            throw InvalidArgument(format_message("EXR channel name \"", name.c_str(),
                                                 "\" contains a NUL byte, which OpenEXR would "
                                                 "cut the name at; remove it from the layer name"));
        if (name.size() > kMaxExrNameBytes)
            throw InvalidArgument(format_message("EXR channel name \"", name.substr(0, 40),
                                                 "...\" is ", name.size(),
                                                 " bytes; OpenEXR stores at most ",
                                                 kMaxExrNameBytes, ", so shorten the layer name"));
    }
}

// Writes `image` to `file_path` (the temporary file); `path` is the name the caller asked for.
void write_exr_file(const std::string& file_path, const Image& image,
                    const ExrWriteSettings& settings) {
    Imf::Header header(image.width(), image.height());
    header.compression() = to_imf(settings.compression);
    header.lineOrder() = Imf::INCREASING_Y;
    Imf::StringVector order;
    Imf::FrameBuffer frame_buffer;
    // Half channels need converted copies that live until writePixels returns.
    std::vector<std::vector<half>> half_copies;
    half_copies.reserve(image.channels().size());
    const size_t width = size_t(image.width());
    for (const ImageChannel& channel : image.channels()) {
        order.push_back(channel.name);
        if (channel.pixel_type == PixelType::Float) {
            header.channels().insert(channel.name, Imf::Channel(Imf::FLOAT));
            // OpenEXR's Slice takes char* for reading and writing alike; it only reads here.
            char* base = reinterpret_cast<char*>(const_cast<float*>(channel.data.data()));
            frame_buffer.insert(channel.name, Imf::Slice(Imf::FLOAT, base, sizeof(float),
                                                         sizeof(float) * width));
        } else {
            header.channels().insert(channel.name, Imf::Channel(Imf::HALF));
            half_copies.emplace_back(channel.data.begin(), channel.data.end());
            char* base = reinterpret_cast<char*>(half_copies.back().data());
            frame_buffer.insert(channel.name,
                                Imf::Slice(Imf::HALF, base, sizeof(half), sizeof(half) * width));
        }
    }
    header.insert(kChannelOrderAttribute, Imf::StringVectorAttribute(order));
    Imf::OutputFile file(file_path.c_str(), header);
    file.setFrameBuffer(frame_buffer);
    file.writePixels(image.height());
}

}  // namespace

const char* exr_compression_name(ExrCompression compression) {
    return imf_compression_name(to_imf(compression));
}

ExrCompression exr_compression_from_name(const std::string& name) {
    for (ExrCompression compression : {ExrCompression::None, ExrCompression::Rle,
                                       ExrCompression::Zips, ExrCompression::Zip,
                                       ExrCompression::Piz}) {
        if (name == exr_compression_name(compression)) return compression;
    }
    throw InvalidArgument(format_message("unknown EXR compression \"", name,
                                         "\"; use one of none, rle, zips, zip, piz"));
}

void write_exr(const std::string& path, const Image& image, const ExrWriteSettings& settings) {
    check_writable(image);
    write_file_atomically(path, [&](const std::string& temp_path) {
        try {
            write_exr_file(temp_path, image, settings);
        } catch (const Iex::BaseExc& error) {
            throw IoError(format_message("cannot write EXR \"", path, "\": ", error.what()));
        }
    });
}

Image read_exr(const std::string& path, int64_t max_pixels) {
    require_readable_file(path, "EXR");
    check_header_attribute_sizes(path);
    try {
        Imf::MultiPartInputFile file(path.c_str());
        const ExrLayout layout = read_layout(path, file);
        const Imath::Box2i& window = layout.data_window;
        const auto [width, height] = data_window_size(path, window);
        const std::vector<ExrChannelInfo>& channels = layout.channels;
        check_read_budget(path, width, height, channels.size(), max_pixels);

        // One frame buffer per part; OpenEXR converts half channels to the float slices.
        std::vector<std::vector<float>> buffers(channels.size());
        std::vector<Imf::FrameBuffer> frame_buffers(size_t(file.parts()));
        for (size_t c = 0; c < channels.size(); ++c) {
            buffers[c].resize(size_t(width * height));
            const ChannelSource& source = layout.sources.at(channels[c].name);
            frame_buffers[size_t(source.part)].insert(
                source.name_in_part, Imf::Slice::Make(Imf::FLOAT, buffers[c].data(), window));
        }
        for (int part = 0; part < file.parts(); ++part) {
            const Imf::FrameBuffer& frame_buffer = frame_buffers[size_t(part)];
            if (frame_buffer.begin() == frame_buffer.end()) continue;  // a part without channels
            Imf::InputPart input(file, part);
            input.setFrameBuffer(frame_buffer);
            input.readPixels(window.min.y, window.max.y);
        }

        Image image(static_cast<int>(width), static_cast<int>(height));
        for (size_t c = 0; c < channels.size(); ++c) {
            image.add_channel(channels[c].name, channels[c].pixel_type, std::move(buffers[c]));
        }
        return image;
    } catch (const Iex::BaseExc& error) {
        throw IoError(format_message("cannot read EXR \"", path, "\": ", error.what()));
    } catch (const InvalidArgument& error) {  // e.g. a channel name Image does not accept
        throw IoError(format_message("cannot read EXR \"", path, "\": ", error.what()));
    }
}

ExrInfo read_exr_info(const std::string& path) {
    require_readable_file(path, "EXR");
    check_header_attribute_sizes(path);
    try {
        Imf::MultiPartInputFile file(path.c_str());
        const ExrLayout layout = read_layout(path, file);
        const auto [width, height] = data_window_size(path, layout.data_window);
        ExrInfo info;
        info.width = int(width);
        info.height = int(height);
        info.compression = imf_compression_name(file.header(0).compression());
        info.channels = layout.channels;
        return info;
    } catch (const Iex::BaseExc& error) {
        throw IoError(format_message("cannot read EXR \"", path, "\": ", error.what()));
    }
}

}  // namespace shgi
