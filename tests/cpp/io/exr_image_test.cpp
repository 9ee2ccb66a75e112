// Tests of io/image.h and io/exr_image.h: bit-exact float round trips, half precision, layer
// names and order, size limits, errors that name the file, and atomic writes.
#include "io/exr_image.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <sys/stat.h>

#include "support/expect_error.h"
#include "support/test_folder.h"
#include "util/error.h"

namespace shgi {
namespace {

namespace fs = std::filesystem;

// Half keeps 11 significant bits: round to nearest is within 2^-11 relative (normal range).
constexpr float kHalfRelativeError = 1.0f / 2048.0f;

using testing::expect_error;


std::vector<std::string> folder_entries(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder)) {
        names.push_back(entry.path().filename().string());
    }
    return names;
}

uint32_t float_bits(float value) {
    uint32_t bits = 0;
    std::memcpy(&bits, &value, sizeof(bits));
    return bits;
}

float float_from_bits(uint32_t bits) {
    float value = 0.0f;
    std::memcpy(&value, &bits, sizeof(value));
    return value;
}

// `count` finite floats from random bit patterns (every exponent, sign and mantissa), with the
// awkward values up front: zeros, denormals, the extremes of the float range.
std::vector<float> awkward_floats(size_t count, uint32_t seed) {
    std::vector<float> values = {0.0f,
                                 -0.0f,
                                 std::numeric_limits<float>::denorm_min(),
                                 -std::numeric_limits<float>::denorm_min(),
                                 float_from_bits(0x007fffffu),  // largest denormal
                                 std::numeric_limits<float>::min(),
                                 std::numeric_limits<float>::max(),
                                 -std::numeric_limits<float>::max(),
                                 1.0e30f,
                                 -3.4e37f,
                                 1.0f,
                                 0.1f};
    std::mt19937 rng(seed);
    while (values.size() < count) {
        const float value = float_from_bits(uint32_t(rng()));
        if (std::isfinite(value)) values.push_back(value);
    }
    values.resize(count);
    return values;
}

void expect_bit_exact(const std::vector<float>& expected, const std::vector<float>& actual,
                      const std::string& what) {
    ASSERT_EQ(expected.size(), actual.size()) << what;
    for (size_t i = 0; i < expected.size(); ++i) {
        ASSERT_EQ(float_bits(expected[i]), float_bits(actual[i]))
            << what << "[" << i << "]: wrote " << expected[i] << ", read " << actual[i];
    }
}

std::vector<std::string> channel_names(const Image& image) {
    std::vector<std::string> names;
    for (const ImageChannel& channel : image.channels()) names.push_back(channel.name);
    return names;
}

TEST(ExrImage, FloatRoundTripIsBitExactForEveryCompression) {
    const fs::path folder = testing::test_folder("exr");
    constexpr int kWidth = 37;  // odd sizes: no accidental alignment with 16-line ZIP blocks
    constexpr int kHeight = 23;
    const size_t pixels = size_t(kWidth) * kHeight;
    Image image(kWidth, kHeight);
    image.add_layer("Combined", {"R", "G", "B", "A"}, awkward_floats(pixels * 4, 1));
    image.add_layer("Depth", {"Z"}, awkward_floats(pixels, 2));
    for (ExrCompression compression : {ExrCompression::None, ExrCompression::Rle,
                                       ExrCompression::Zips, ExrCompression::Zip,
                                       ExrCompression::Piz}) {
        const std::string name = exr_compression_name(compression);
        const std::string path = (folder / (name + ".exr")).string();
        write_exr(path, image, ExrWriteSettings{compression});
        const Image read = read_exr(path);
        ASSERT_EQ(read.width(), kWidth);
        ASSERT_EQ(read.height(), kHeight);
        ASSERT_EQ(channel_names(read), channel_names(image)) << name;
        EXPECT_EQ(read_exr_info(path).compression, name);
        for (size_t c = 0; c < image.channels().size(); ++c) {
            EXPECT_EQ(read.channels()[c].pixel_type, PixelType::Float);
            expect_bit_exact(image.channels()[c].data, read.channels()[c].data,
                             name + " " + image.channels()[c].name);
        }
    }
}

TEST(ExrImage, RowsAreStoredTopRowFirst) {
    const fs::path folder = testing::test_folder("exr");
    // Pixel (x, y) holds 10 * y + x; the first value in the buffer is the top-left pixel.
    Image image(3, 2);
    image.add_channel("Gradient.Z", PixelType::Float, {0, 1, 2, 10, 11, 12});
    const std::string path = (folder / "rows.exr").string();
    write_exr(path, image);
    const Image read = read_exr(path);
    EXPECT_EQ(read.channels()[0].data, image.channels()[0].data);
}

TEST(ExrImage, HalfRoundTripIsWithinHalfPrecision) {
    const fs::path folder = testing::test_folder("exr");
    constexpr int kWidth = 16;
    constexpr int kHeight = 9;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> log2_magnitude(-14.0f, 15.0f);  // half's normal range
    std::vector<float> values(size_t(kWidth) * kHeight * 3);
    for (float& value : values) value = std::exp2(log2_magnitude(rng)) * (rng() % 2 ? 1.0f : -1.0f);
    // Values that half represents exactly come back exactly.
    const std::vector<float> exact = {0.0f, 1.0f, 0.5f, -2.0f, 0.25f, 2048.0f, 65504.0f};
    std::copy(exact.begin(), exact.end(), values.begin());

    Image image(kWidth, kHeight);
    image.add_layer("DiffInd", {"R", "G", "B"}, values, PixelType::Half);
    const std::string path = (folder / "half.exr").string();
    write_exr(path, image);
    const Image read = read_exr(path);
    for (const ImageChannel& channel : read.channels()) {
        EXPECT_EQ(channel.pixel_type, PixelType::Half) << channel.name;
    }
    const std::vector<float> read_values = read.layer_pixels("DiffInd");
    ASSERT_EQ(read_values.size(), values.size());
    for (size_t i = 0; i < values.size(); ++i) {
        EXPECT_LE(std::abs(read_values[i] - values[i]), kHalfRelativeError * std::abs(values[i]))
            << "value " << i << ": wrote " << values[i] << ", read " << read_values[i];
    }
    for (size_t i = 0; i < exact.size(); ++i) EXPECT_EQ(read_values[i], exact[i]);
}

TEST(ExrImage, LayerNamesAndChannelOrderArePreserved) {
    const fs::path folder = testing::test_folder("exr");
    constexpr int kSize = 4;
    const size_t pixels = kSize * kSize;
    Image image(kSize, kSize);
    // Deliberately not in EXR's alphabetical order.
    image.add_layer("ViewLayer.Normal", {"X", "Y", "Z"}, std::vector<float>(pixels * 3, 0.5f));
    image.add_layer("Combined", {"R", "G", "B", "A"}, std::vector<float>(pixels * 4, 1.0f));
    image.add_layer("DiffInd", {"R", "G", "B"}, std::vector<float>(pixels * 3, 2.0f),
                    PixelType::Half);
    image.add_layer("Depth", {"Z"}, std::vector<float>(pixels, 3.0f));
    const std::string path = (folder / "layers.exr").string();
    write_exr(path, image, ExrWriteSettings{ExrCompression::Piz});

    const Image read = read_exr(path);
    EXPECT_EQ(channel_names(read), channel_names(image));
    EXPECT_EQ(read.layer_names(),
              (std::vector<std::string>{"ViewLayer.Normal", "Combined", "DiffInd", "Depth"}));
    EXPECT_EQ(read.layer_suffixes("Combined"), (std::vector<std::string>{"R", "G", "B", "A"}));
    EXPECT_EQ(read.layer_pixels("Depth"), std::vector<float>(pixels, 3.0f));

    const ExrInfo info = read_exr_info(path);
    EXPECT_EQ(info.width, kSize);
    EXPECT_EQ(info.height, kSize);
    EXPECT_EQ(info.compression, "piz");
    ASSERT_EQ(info.channels.size(), image.channels().size());
    for (size_t c = 0; c < info.channels.size(); ++c) {
        EXPECT_EQ(info.channels[c].name, image.channels()[c].name);
        EXPECT_EQ(info.channels[c].pixel_type, image.channels()[c].pixel_type);
    }
}

// Multi-part files as Blender 5.0 and other OpenEXR 2 writers make them. They were written with
// Imf::MultiPartOutputFile (OpenEXR 3.1.5, NO_COMPRESSION, 3 x 2 pixels, data window = display
// window = (0, 0) - (2, 1)) and are kept here as bytes because this test executable does not see
// the OpenEXR headers (shgi_io links OpenEXR privately).
//
// kThreePartExr: part 0 "ViewLayer.Combined", scanline, float channels "ViewLayer.Combined.R",
// ".G", ".B", ".A" (Blender 5.0's names: the channel carries the part name); part 1
// "ViewLayer.Depth", scanline, float channel "Z"; part 2 "ViewLayer.DiffInd", tiled 2 x 2, half
// channels "R", "G", "B" (Houdini's names: the part name gives the layer). Taking the channels
// in that order, channel k holds multi_part_value(k, x, y) at pixel (x, y).
constexpr char kThreePartExr[] =
    "v/1\x01\x02\x10\0\0channels\0chlist\0\x95\0\0\0ViewLayer.Combined.A\0\x02\0\0\0\0\0\0\0\x01\0"
    "\0\0\x01\0\0\0ViewLayer.Combined.B\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0ViewLayer.Combined.G"
    "\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0ViewLayer.Combined.R\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01"
    "\0\0\0\0chunkCount\0int\0\x04\0\0\0\x02\0\0\0compression\0compression\0\x01\0\0\0\0dataWindow"
    "\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0displayWindow\0box2i\0\x10\0\0\0\0\0\0"
    "\0\0\0\0\0\x02\0\0\0\x01\0\0\0lineOrder\0lineOrder\0\x01\0\0\0\0name\0string\0\x12\0\0\0ViewLa"
    "yer.CombinedpixelAspectRatio\0float\0\x04\0\0\0\0\0\x80\x3fscreenWindowCenter\0v2f\0\x08\0\0\0"
    "\0\0\0\0\0\0\0\0screenWindowWidth\0float\0\x04\0\0\0\0\0\x80\x3ftype\0string\0\x0d\0\0\0scanli"
    "neimage\0channels\0chlist\0\x13\0\0\0Z\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0\0chunkCount\0in"
    "t\0\x04\0\0\0\x02\0\0\0compression\0compression\0\x01\0\0\0\0dataWindow\0box2i\0\x10\0\0\0\0\0"
    "\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0displayWindow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01"
    "\0\0\0lineOrder\0lineOrder\0\x01\0\0\0\0name\0string\0\x0f\0\0\0ViewLayer.DepthpixelAspectRati"
    "o\0float\0\x04\0\0\0\0\0\x80\x3fscreenWindowCenter\0v2f\0\x08\0\0\0\0\0\0\0\0\0\0\0screenWindo"
    "wWidth\0float\0\x04\0\0\0\0\0\x80\x3ftype\0string\0\x0d\0\0\0scanlineimage\0channels\0chlist"
    "\x00\x37\0\0\0B\0\x01\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0G\0\x01\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0"
    "\0R\0\x01\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0\0chunkCount\0int\0\x04\0\0\0\x02\0\0\0compression"
    "\0compression\0\x01\0\0\0\0dataWindow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0di"
    "splayWindow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0lineOrder\0lineOrder\0\x01\0"
    "\0\0\0name\0string\0\x11\0\0\0ViewLayer.DiffIndpixelAspectRatio\0float\0\x04\0\0\0\0\0\x80\x3f"
    "screenWindowCenter\0v2f\0\x08\0\0\0\0\0\0\0\0\0\0\0screenWindowWidth\0float\0\x04\0\0\0\0\0"
    "\x80\x3ftiles\0tiledesc\0\x09\0\0\0\x02\0\0\0\x02\0\0\0\0type\0string\0\x0a\0\0\0tiledimage\0"
    "\0\x1d\x05\0\0\0\0\0\0Y\x05\0\0\0\0\0\0\x95\x05\0\0\0\0\0\0\xad\x05\0\0\0\0\0\0\xc5\x05\0\0\0"
    "\0\0\0\xf5\x05\0\0\0\0\0\0\0\0\0\0\0\0\0\x00\x30\0\0\0\0@\x96\x43\0\xc0\x96\x43\0@\x97\x43\0"
    "\x80HC\0\x80IC\0\x80JC\0\0\xc9\x42\0\0\xcb\x42\0\0\xcd\x42\0\0\0\x3f\0\0\xc0\x3f\0\0 @\0\0\0\0"
    "\x01\0\0\x00\x30\0\0\0\0@\x9b\x43\0\xc0\x9b\x43\0@\x9c\x43\0\x80RC\0\x80SC\0\x80TC\0\0\xdd\x42"
    "\0\0\xdf\x42\0\0\xe1\x42\0\0(A\0\08A\0\0HA\x01\0\0\0\0\0\0\0\x0c\0\0\0\0@\xc8\x43\0\xc0\xc8"
    "\x43\0@\xc9\x43\x01\0\0\0\x01\0\0\0\x0c\0\0\0\0@\xcd\x43\0\xc0\xcd\x43\0@\xce\x43\x02\0\0\0\0"
    "\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x18\0\0\0ya{a\xb1`\xb3`\xd2_\xd6_\x8d\x61\x8f\x61\xc5`\xc7`\xfa"
    "_\xfe_\x02\0\0\0\x01\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x0c\0\0\0}a\xb5`\xda_\x91\x61\xc9`\x01`";

// kMismatchedWindowExr: part 0 "ViewLayer.Combined" (channel "ViewLayer.Combined.R", data window
// (0, 0) - (2, 1)) and part 1 "ViewLayer.Depth" (channel "ViewLayer.Depth.Z", one column wider:
// (0, 0) - (3, 1)).
constexpr char kMismatchedWindowExr[] =
    "v/1\x01\x02\x10\0\0channels\0chlist\0&\0\0\0ViewLayer.Combined.R\0\x02\0\0\0\0\0\0\0\x01\0\0\0"
    "\x01\0\0\0\0chunkCount\0int\0\x04\0\0\0\x02\0\0\0compression\0compression\0\x01\0\0\0\0dataWin"
    "dow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0displayWindow\0box2i\0\x10\0\0\0\0\0"
    "\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0lineOrder\0lineOrder\0\x01\0\0\0\0name\0string\0\x12\0\0\0View"
    "Layer.CombinedpixelAspectRatio\0float\0\x04\0\0\0\0\0\x80\x3fscreenWindowCenter\0v2f\0\x08\0\0"
    "\0\0\0\0\0\0\0\0\0screenWindowWidth\0float\0\x04\0\0\0\0\0\x80\x3ftype\0string\0\x0d\0\0\0scan"
    "lineimage\0channels\0chlist\0#\0\0\0ViewLayer.Depth.Z\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0"
    "\0chunkCount\0int\0\x04\0\0\0\x02\0\0\0compression\0compression\0\x01\0\0\0\0dataWindow\0box2i"
    "\0\x10\0\0\0\0\0\0\0\0\0\0\0\x03\0\0\0\x01\0\0\0displayWindow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0"
    "\0\x02\0\0\0\x01\0\0\0lineOrder\0lineOrder\0\x01\0\0\0\0name\0string\0\x0f\0\0\0ViewLayer.Dept"
    "hpixelAspectRatio\0float\0\x04\0\0\0\0\0\x80\x3fscreenWindowCenter\0v2f\0\x08\0\0\0\0\0\0\0\0"
    "\0\0\0screenWindowWidth\0float\0\x04\0\0\0\0\0\x80\x3ftype\0string\0\x0d\0\0\0scanlineimage\0"
    "\0\x0f\x03\0\0\0\0\0\0'\x03\0\0\0\0\0\0\x3f\x03\0\0\0\0\0\0[\x03\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
    "\x0c\0\0\0\0\0\x80\x3f\0\0\x80\x3f\0\0\x80\x3f\0\0\0\0\x01\0\0\0\x0c\0\0\0\0\0\x80\x3f\0\0\x80"
    "\x3f\0\0\x80\x3f\x01\0\0\0\0\0\0\0\x10\0\0\0\0\0\0@\0\0\0@\0\0\0@\0\0\0@\x01\0\0\0\x01\0\0\0"
    "\x10\0\0\0\0\0\0@\0\0\0@\0\0\0@\0\0\0@";

// kDeepPartExr: part 0 "ViewLayer.Combined" (channel "ViewLayer.Combined.R") and part 1 "Deep",
// a deep scanline part (channel "Z", no samples).
constexpr char kDeepPartExr[] =
    "v/1\x01\x02\x18\0\0channels\0chlist\0&\0\0\0ViewLayer.Combined.R\0\x02\0\0\0\0\0\0\0\x01\0\0\0"
    "\x01\0\0\0\0chunkCount\0int\0\x04\0\0\0\x02\0\0\0compression\0compression\0\x01\0\0\0\0dataWin"
    "dow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0displayWindow\0box2i\0\x10\0\0\0\0\0"
    "\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0lineOrder\0lineOrder\0\x01\0\0\0\0name\0string\0\x12\0\0\0View"
    "Layer.CombinedpixelAspectRatio\0float\0\x04\0\0\0\0\0\x80\x3fscreenWindowCenter\0v2f\0\x08\0\0"
    "\0\0\0\0\0\0\0\0\0screenWindowWidth\0float\0\x04\0\0\0\0\0\x80\x3ftype\0string\0\x0d\0\0\0scan"
    "lineimage\0channels\0chlist\0\x13\0\0\0Z\0\x02\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0\0chunkCount\0"
    "int\0\x04\0\0\0\x02\0\0\0compression\0compression\0\x01\0\0\0\0dataWindow\0box2i\0\x10\0\0\0\0"
    "\0\0\0\0\0\0\0\x02\0\0\0\x01\0\0\0displayWindow\0box2i\0\x10\0\0\0\0\0\0\0\0\0\0\0\x02\0\0\0"
    "\x01\0\0\0lineOrder\0lineOrder\0\x01\0\0\0\0name\0string\0\x04\0\0\0DeeppixelAspectRatio\0floa"
    "t\0\x04\0\0\0\0\0\x80\x3fscreenWindowCenter\0v2f\0\x08\0\0\0\0\0\0\0\0\0\0\0screenWindowWidth"
    "\0float\0\x04\0\0\0\0\0\x80\x3ftype\0string\0\x0c\0\0\0deepscanlineversion\0int\0\x04\0\0\0"
    "\x01\0\0\0\0\0\x07\x03\0\0\0\0\0\0\x1f\x03\0\0\0\0\0\x00\x37\x03\0\0\0\0\0\0c\x03\0\0\0\0\0\0"
    "\0\0\0\0\0\0\0\0\x0c\0\0\0\0\0\x80\x3f\0\0\x80\x3f\0\0\x80\x3f\0\0\0\0\x01\0\0\0\x0c\0\0\0\0\0"
    "\x80\x3f\0\0\x80\x3f\0\0\x80\x3f\x01\0\0\0\0\0\0\0\x0c\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
    "\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x01\0\0\0\x01\0\0\0\x0c\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0"
    "\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0";

constexpr int kMultiPartWidth = 3;  // of every fixture above
constexpr int kMultiPartHeight = 2;

// The value kThreePartExr holds in its channel k at pixel (x, y); exact in half and float.
float multi_part_value(int k, int x, int y) { return 100.0f * k + 10.0f * y + x + 0.5f; }

// Writes the bytes of a fixture (without the literal's terminating '\0') to `path`.
template <size_t N>
void write_fixture(const std::string& path, const char (&bytes)[N]) {
    std::ofstream(path, std::ios::binary).write(bytes, std::streamsize(N - 1));
}

TEST(ExrImage, MultiPartFilesReadEveryPartUnderItsLayerName) {
    const fs::path folder = testing::test_folder("exr");
    const std::string path = (folder / "three_parts.exr").string();
    write_fixture(path, kThreePartExr);
    const Image read = read_exr(path);
    ASSERT_EQ(read.width(), kMultiPartWidth);
    ASSERT_EQ(read.height(), kMultiPartHeight);
    // The names and order of the single-part file with the same passes (Blender's interleaved
    // multilayer EXR).
    const std::vector<std::string> names = {
        "ViewLayer.Combined.R", "ViewLayer.Combined.G", "ViewLayer.Combined.B",
        "ViewLayer.Combined.A", "ViewLayer.Depth.Z",    "ViewLayer.DiffInd.R",
        "ViewLayer.DiffInd.G",  "ViewLayer.DiffInd.B"};
    ASSERT_EQ(channel_names(read), names);
    EXPECT_EQ(read.layer_names(),
              (std::vector<std::string>{"ViewLayer.Combined", "ViewLayer.Depth",
                                        "ViewLayer.DiffInd"}));
    const size_t float_channels = 5;  // Combined and Depth; DiffInd is half
    for (int k = 0; k < int(names.size()); ++k) {
        const ImageChannel& channel = read.channels()[size_t(k)];
        EXPECT_EQ(channel.pixel_type,
                  size_t(k) < float_channels ? PixelType::Float : PixelType::Half)
            << channel.name;
        for (int y = 0; y < kMultiPartHeight; ++y) {
            for (int x = 0; x < kMultiPartWidth; ++x) {
                EXPECT_EQ(channel.data[size_t(y * kMultiPartWidth + x)], multi_part_value(k, x, y))
                    << channel.name << " at (" << x << ", " << y << ")";
            }
        }
    }
    // The budget counts the pixels once, however many parts hold them.
    expect_error<IoError>([&] { read_exr(path, 5); }, {path, "6 pixels", "max_pixels = 5"});
    EXPECT_EQ(read_exr(path, 6).channels().size(), names.size());
}

TEST(ExrImage, ReadExrInfoListsTheChannelsOfEveryPart) {
    const fs::path folder = testing::test_folder("exr");
    const std::string path = (folder / "three_parts.exr").string();
    write_fixture(path, kThreePartExr);
    const ExrInfo info = read_exr_info(path);
    EXPECT_EQ(info.width, kMultiPartWidth);
    EXPECT_EQ(info.height, kMultiPartHeight);
    EXPECT_EQ(info.compression, "none");
    const Image read = read_exr(path);
    ASSERT_EQ(info.channels.size(), read.channels().size());
    for (size_t c = 0; c < info.channels.size(); ++c) {
        EXPECT_EQ(info.channels[c].name, read.channels()[c].name);
        EXPECT_EQ(info.channels[c].pixel_type, read.channels()[c].pixel_type);
    }
}

TEST(ExrImage, PartsWithAnotherDataWindowAreRejectedNamingBothParts) {
    const fs::path folder = testing::test_folder("exr");
    const std::string path = (folder / "mismatched_window.exr").string();
    write_fixture(path, kMismatchedWindowExr);
    const std::vector<std::string> expected = {
        path, "part 1 \"ViewLayer.Depth\"", "(0, 0) - (3, 1)", "part 0 \"ViewLayer.Combined\"",
        "(0, 0) - (2, 1)"};
    expect_error<IoError>([&] { read_exr(path); }, expected);
    expect_error<IoError>([&] { read_exr_info(path); }, expected);
}

TEST(ExrImage, DeepPartsAreRejectedNamingThePart) {
    const fs::path folder = testing::test_folder("exr");
    const std::string path = (folder / "deep_part.exr").string();
    write_fixture(path, kDeepPartExr);
    expect_error<IoError>([&] { read_exr(path); }, {path, "part 1 \"Deep\"", "deep data"});
    expect_error<IoError>([&] { read_exr_info(path); }, {path, "part 1 \"Deep\"", "deep data"});
}

TEST(ExrImage, LayerPixelsInvertsAddLayer) {
    Image image(2, 1);
    const std::vector<float> rgba = {1, 2, 3, 4, 5, 6, 7, 8};
    image.add_layer("", {"R", "G", "B", "A"}, rgba);
    EXPECT_EQ(channel_names(image), (std::vector<std::string>{"R", "G", "B", "A"}));
    EXPECT_EQ(image.find_channel("G")->data, (std::vector<float>{2, 6}));
    EXPECT_EQ(image.layer_pixels(""), rgba);
    EXPECT_THROW(image.layer_pixels("Combined"), InvalidArgument);
}

TEST(ExrImage, ChannelNamesSplitAtTheLastDot) {
    EXPECT_EQ(channel_layer("ViewLayer.Combined.R"), "ViewLayer.Combined");
    EXPECT_EQ(channel_suffix("ViewLayer.Combined.R"), "R");
    EXPECT_EQ(channel_layer("R"), "");
    EXPECT_EQ(channel_suffix("R"), "R");
    EXPECT_EQ(channel_name("", "Z"), "Z");
    EXPECT_EQ(channel_name("Depth", "Z"), "Depth.Z");
}

TEST(ExrImage, InvalidImagesAreRejectedWithTheReason) {
    expect_error<InvalidArgument>([] { Image(0, 5); }, {"0 x 5"});
    expect_error<InvalidArgument>([] { Image(5, -1); }, {"5 x -1"});
    expect_error<InvalidArgument>([] { Image(kMaxImageDimension + 1, 1); }, {"out of range"});
    expect_error<InvalidArgument>([] { Image(kMaxImageDimension, kMaxImageDimension); },
                                  {"exceeds the limit"});
    Image image(2, 2);
    expect_error<InvalidArgument>([&] { image.add_channel("", PixelType::Float, {0, 0, 0, 0}); },
                                  {"empty"});
    expect_error<InvalidArgument>(
        [&] { image.add_channel("Combined.", PixelType::Float, {0, 0, 0, 0}); }, {"Combined."});
    expect_error<InvalidArgument>([&] { image.add_channel("Depth.Z", PixelType::Float, {0}); },
                                  {"Depth.Z", "1 values", "4"});
    image.add_channel("Depth.Z", PixelType::Float, {0, 0, 0, 0});
    expect_error<InvalidArgument>(
        [&] { image.add_channel("Depth.Z", PixelType::Half, {0, 0, 0, 0}); },
        {"Depth.Z", "already present"});
    expect_error<InvalidArgument>(
        [&] { image.add_layer("Combined", {"R", "G"}, std::vector<float>(7)); },
        {"Combined", "7 values", "8"});
    expect_error<InvalidArgument>(
        [&] { image.add_layer("Combined", {"R", "R"}, std::vector<float>(8)); },
        {"Combined.R", "already present"});
    EXPECT_EQ(image.channels().size(), 1u) << "a failed add_layer must leave the image unchanged";
    expect_error<InvalidArgument>([] { write_exr("unused.exr", Image(1, 1)); },
                                  {"without channels"});
    // Names OpenEXR would cut short (past 255 bytes, or at a NUL), which used to merge a layer's
    // channels into one truncated channel without a word.
    Image long_name(1, 1);
    long_name.add_layer(std::string(300, 'x'), {"R", "G"}, std::vector<float>(2));
    expect_error<InvalidArgument>([&] { write_exr("unused.exr", long_name); },
                                  {"is 302 bytes; OpenEXR stores at most 255"});
    Image nul_name(1, 1);
    nul_name.add_layer(std::string("a\0b", 3), {"R"}, std::vector<float>(1));
    expect_error<InvalidArgument>([&] { write_exr("unused.exr", nul_name); },
                                  {"EXR channel name \"a\" contains a NUL byte"});
    Image longest(1, 1);
    longest.add_layer(std::string(253, 'x'), {"R"}, std::vector<float>(1));  // 255 bytes
    const std::string path = ::testing::TempDir() + "longest_name.exr";
    write_exr(path, longest);
    EXPECT_EQ(read_exr(path).channels().front().name, std::string(253, 'x') + ".R");
}

Image small_image() {
    Image image(8, 8);
    image.add_layer("Combined", {"R", "G", "B", "A"}, std::vector<float>(8 * 8 * 4, 0.25f));
    return image;
}

TEST(ExrImage, MissingAndCorruptFilesRaiseIoErrorNamingThePath) {
    const fs::path folder = testing::test_folder("exr");
    const std::string missing = (folder / "missing.exr").string();
    expect_error<IoError>([&] { read_exr(missing); }, {missing});
    expect_error<IoError>([&] { read_exr_info(missing); }, {missing});

    const std::string garbage = (folder / "garbage.exr").string();
    std::ofstream(garbage, std::ios::binary) << "this is not an OpenEXR file at all";
    expect_error<IoError>([&] { read_exr(garbage); }, {garbage});

    // A valid file cut in half: the header parses, the pixel data is missing.
    const std::string truncated = (folder / "truncated.exr").string();
    write_exr(truncated, small_image(), ExrWriteSettings{ExrCompression::None});
    fs::resize_file(truncated, fs::file_size(truncated) / 2);
    expect_error<IoError>([&] { read_exr(truncated); }, {truncated});
}

// The file at `path` with the 32-bit size field of the last attribute named `name` (a name and
// type of that attribute: "name\0type\0") set to `size`.
void set_attribute_size(const std::string& path, const std::string& name_and_type, int32_t size) {
    std::string bytes;
    {
        std::ifstream in(path, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const size_t at = bytes.rfind(name_and_type);
    ASSERT_NE(at, std::string::npos) << name_and_type;
    std::memcpy(&bytes[at + name_and_type.size()], &size, sizeof(size));  // little-endian x86
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// A damaged attribute size is refused before OpenEXR reads the header: it would allocate and fill
// that many bytes (up to 2 GB) before meeting the end of the file.
TEST(ExrImage, DamagedHeaderAttributeSizesAreRefusedNamingTheAttribute) {
    const fs::path folder = testing::test_folder("exr");
    const std::string single = (folder / "damaged_size.exr").string();
    const std::string order("shgiChannelOrder\0stringvector\0", 30);
    for (int32_t size : {int32_t(1) << 30, -5}) {
        write_exr(single, small_image(), ExrWriteSettings{ExrCompression::None});
        set_attribute_size(single, order, size);
        for (const auto& read : {std::function<void()>([&] { read_exr(single); }),
                                 std::function<void()>([&] { read_exr_info(single); })})
            expect_error<IoError>(read, {single, "damaged", "shgiChannelOrder",
                                         std::to_string(size) + " bytes"});
    }
    // In a multi-part file, the last part's header is walked too.
    const std::string parts = (folder / "damaged_part.exr").string();
    write_fixture(parts, kThreePartExr);
    set_attribute_size(parts, std::string("type\0string\0", 12), int32_t(1) << 30);
    expect_error<IoError>([&] { read_exr(parts); }, {parts, "damaged", "\"type\" (string)"});
    // Intact files of both kinds still read (the walk stops where the headers end).
    write_exr(single, small_image(), ExrWriteSettings{ExrCompression::None});
    EXPECT_EQ(read_exr(single).pixel_count(), 64u);
    write_fixture(parts, kThreePartExr);
    EXPECT_EQ(read_exr(parts).channels().size(), 8u);
}

TEST(ExrImage, ReadEnforcesThePixelBudget) {
    const fs::path folder = testing::test_folder("exr");
    const std::string path = (folder / "budget.exr").string();
    write_exr(path, small_image());
    expect_error<IoError>([&] { read_exr(path, 63); }, {path, "64 pixels", "max_pixels = 63"});
    EXPECT_EQ(read_exr(path, 64).pixel_count(), 64u);

    // The value budget: more than kMaxExrValuesPerPixel channels at the full pixel budget.
    Image wide(8, 8);
    for (int64_t c = 0; c <= kMaxExrValuesPerPixel; ++c) {
        wide.add_channel("Lattice.c" + std::to_string(c), PixelType::Half, std::vector<float>(64));
    }
    const std::string wide_path = (folder / "wide.exr").string();
    write_exr(wide_path, wide);
    expect_error<IoError>([&] { read_exr(wide_path, 64); }, {wide_path, "17 channels"});
    EXPECT_EQ(read_exr(wide_path, 128).channels().size(), size_t(kMaxExrValuesPerPixel + 1));

    // The channel cap, whatever the pixel budget: refused from the header, before any pixel.
    Image many(1, 1);
    for (size_t c = 0; c <= kMaxExrChannels; ++c)
        many.add_channel("c" + std::to_string(c), PixelType::Half, {0.0f});
    const std::string many_path = (folder / "many.exr").string();
    write_exr(many_path, many);
    expect_error<IoError>([&] { read_exr(many_path); }, {many_path, "more than 4096 channels"});
    expect_error<IoError>([&] { read_exr_info(many_path); }, {"more than 4096 channels"});
}

TEST(ExrImage, WritesAreAtomicAndLeaveNoTemporaryFile) {
    const fs::path folder = testing::test_folder("exr");
    const std::string path = (folder / "atomic.exr").string();
    write_exr(path, small_image());
    write_exr(path, small_image());  // overwrites in place
    EXPECT_EQ(folder_entries(folder), std::vector<std::string>{"atomic.exr"});

    // A writer that fails half-way: the old file survives, the temporary file is removed.
    const auto old_size = fs::file_size(path);
    EXPECT_THROW(write_file_atomically(path,
                                       [](const std::string& temp_path) {
                                           std::ofstream(temp_path) << "partial";
                                           throw IoError("disk full");
                                       }),
                 IoError);
    EXPECT_EQ(folder_entries(folder), std::vector<std::string>{"atomic.exr"});
    EXPECT_EQ(fs::file_size(path), old_size);
}

TEST(ExrImage, UnwritablePathsRaiseIoErrorNamingThePath) {
    const fs::path folder = testing::test_folder("exr");
    const std::string no_folder = (folder / "no_such_folder" / "out.exr").string();
    expect_error<IoError>([&] { write_exr(no_folder, small_image()); },
                          {no_folder, "does not exist"});
    expect_error<IoError>([&] { write_exr(folder.string(), small_image()); },
                          {folder.string(), "folder"});
    expect_error<IoError>([&] { write_exr("", small_image()); }, {"empty"});
    EXPECT_TRUE(folder_entries(folder).empty());
}

// Paths that are not files: refused by name before a reader opens them (a folder used to throw a
// stream error, a FIFO would block) or before a write's rename replaces them (a device such as
// /dev/null); a NUL byte would silently name another file.
TEST(ExrImage, FoldersSpecialFilesAndNulBytesAreRefused) {
    const fs::path folder = testing::test_folder("exr");
    expect_error<IoError>([&] { read_exr(folder.string()); }, {folder.string(), "is a folder"});
    expect_error<IoError>([&] { read_exr_info(folder.string()); }, {"is a folder"});
    const std::string fifo = (folder / "fifo").string();
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    expect_error<IoError>([&] { read_exr(fifo); }, {fifo, "not a regular file"});
    expect_error<IoError>([&] { write_exr(fifo, small_image()); },
                          {fifo, "not a regular file", "would replace"});
    EXPECT_TRUE(fs::is_fifo(fifo));
    fs::remove(fifo);
    const std::string real = (folder / "a.exr").string();
    write_exr(real, small_image());
    const std::string cut = real + std::string(1, '\0') + "b";  // the C library would read a.exr
    expect_error<InvalidArgument>([&] { read_exr(cut); }, {"NUL byte at position"});
    expect_error<InvalidArgument>([&] { write_exr(cut, small_image()); }, {"NUL byte"});
    // A missing file keeps the reader's own message.
    expect_error<IoError>([&] { read_exr((folder / "missing.exr").string()); }, {"missing.exr"});
    fs::remove(real);
    EXPECT_TRUE(folder_entries(folder).empty());
}

// A write through a symbolic link replaces the file it points to and keeps the link, as opening
// the link for writing would; the rename used to replace the link with a file.
TEST(ExrImage, WritesFollowSymbolicLinks) {
    const fs::path folder = testing::test_folder("exr");
    const fs::path real = folder / "real.exr";
    write_exr(real.string(), small_image());
    const fs::path link = folder / "link.exr";
    fs::create_symlink("real.exr", link);  // relative to the link's folder
    const fs::path chain = folder / "chain.exr";
    fs::create_symlink(link, chain);  // absolute, to another link
    Image changed(8, 8);
    changed.add_layer("Combined", {"R", "G", "B", "A"}, std::vector<float>(8 * 8 * 4, 42.0f));
    write_exr(chain.string(), changed);
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(chain)));
    EXPECT_EQ(read_exr(real.string()).layer_pixels("Combined")[0], 42.0f);
    // A dangling link: its target is created.
    const fs::path dangling = folder / "dangling.exr";
    fs::create_symlink("created.exr", dangling);
    write_exr(dangling.string(), small_image());
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dangling)));
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(folder / "created.exr")));
    // A relative target resolves against its link's folder, not the working folder.
    const fs::path sub = folder / "sub";
    fs::create_directory(sub);
    const fs::path up = sub / "up.exr";
    fs::create_symlink("../real.exr", up);
    Image again(8, 8);
    again.add_layer("Combined", {"R", "G", "B", "A"}, std::vector<float>(8 * 8 * 4, 7.0f));
    write_exr(up.string(), again);
    EXPECT_EQ(read_exr(real.string()).layer_pixels("Combined")[0], 7.0f);
    // 40 links, the kernel's own limit, are followed; a 41st is refused.
    std::vector<fs::path> hops;
    for (int i = 0; i < 41; ++i) {
        hops.push_back(folder / ("hop" + std::to_string(i) + ".exr"));
        fs::create_symlink(i == 0 ? fs::path("real.exr") : hops[size_t(i) - 1].filename(),
                           hops.back());
    }
    write_exr(hops[39].string(), small_image());
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(hops[39])));
    expect_error<IoError>([&] { write_exr(hops[40].string(), small_image()); },
                          {"more than 40 symbolic links"});
    // A link to a missing folder, a loop, a link to a FIFO: refused by name, nothing replaced.
    const fs::path nowhere = folder / "nowhere.exr";
    fs::create_symlink("missing/x.exr", nowhere);
    expect_error<IoError>([&] { write_exr(nowhere.string(), small_image()); },
                          {nowhere.string(), "a link to", "missing", "does not exist"});
    const fs::path loop = folder / "loop.exr";
    fs::create_symlink("loop.exr", loop);
    expect_error<IoError>([&] { write_exr(loop.string(), small_image()); },
                          {loop.string(), "symbolic links in a chain"});
    const fs::path fifo = folder / "fifo";
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    const fs::path to_fifo = folder / "to_fifo.exr";
    fs::create_symlink("fifo", to_fifo);
    expect_error<IoError>([&] { write_exr(to_fifo.string(), small_image()); },
                          {to_fifo.string(), "a link to", "not a regular file"});
    EXPECT_TRUE(fs::is_fifo(fifo));
    for (const fs::path& p : {real, link, chain, dangling, folder / "created.exr", nowhere, loop,
                              fifo, to_fifo, up, sub})
        fs::remove(p);
    for (const fs::path& p : hops) fs::remove(p);
    EXPECT_TRUE(folder_entries(folder).empty());  // no temporary file left behind
}

}  // namespace
}  // namespace shgi
