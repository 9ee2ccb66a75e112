// Tests of io/png_image.h: the sRGB transfer function at its defining points, and PNG files
// decoded back with libpng to the expected 8-bit levels.
#include "io/png_image.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <png.h>

#include "support/expect_error.h"
#include "support/test_folder.h"
#include "util/error.h"

namespace shgi {
namespace {

namespace fs = std::filesystem;

// One float ulp near 1 is 6e-8; the curve is evaluated in double and rounded once.
constexpr float kCurveTolerance = 1.0e-7f;


TEST(Srgb, CurveIsExactAtItsDefiningPoints) {
    EXPECT_EQ(srgb_from_linear(0.0f), 0.0f);
    EXPECT_EQ(srgb_from_linear(1.0f), 1.0f);
    // The linear segment ends at 0.0031308 with slope 12.92.
    EXPECT_NEAR(srgb_from_linear(0.0031308f), 12.92f * 0.0031308f, kCurveTolerance);
    EXPECT_NEAR(srgb_from_linear(0.001f), 0.01292f, kCurveTolerance);
    // 1.055 * 0.5^(1/2.4) - 0.055 = 0.735356983...
    EXPECT_NEAR(srgb_from_linear(0.5f), 0.7353569831f, kCurveTolerance);
    EXPECT_NEAR(srgb_from_linear(0.18f), 0.4613561f, kCurveTolerance);
    // The two segments meet (IEC 61966-2-1 is continuous to about 1e-7 there).
    const float above = std::nextafter(0.0031308f, 1.0f);
    EXPECT_NEAR(srgb_from_linear(above), srgb_from_linear(0.0031308f), 2.0e-7f);
}

TEST(Srgb, OutOfRangeInputIsClamped) {
    EXPECT_EQ(srgb_from_linear(-0.5f), 0.0f);
    EXPECT_EQ(srgb_from_linear(7.0f), 1.0f);
    EXPECT_EQ(srgb_from_linear(std::numeric_limits<float>::infinity()), 1.0f);
    EXPECT_EQ(srgb_from_linear(std::numeric_limits<float>::quiet_NaN()), 0.0f);
}

TEST(Srgb, DecodeInvertsEncode) {
    EXPECT_NEAR(linear_from_srgb(0.7353569831f), 0.5f, kCurveTolerance);
    EXPECT_NEAR(linear_from_srgb(0.04045f), 0.04045f / 12.92f, kCurveTolerance);
    for (int i = 0; i <= 1000; ++i) {
        const float linear = float(i) / 1000.0f;
        EXPECT_NEAR(linear_from_srgb(srgb_from_linear(linear)), linear, 4.0f * kCurveTolerance)
            << "linear " << linear;
    }
}

TEST(Srgb, EightBitLevelsRoundToNearest) {
    EXPECT_EQ(srgb8_from_linear(0.0f), 0);
    EXPECT_EQ(srgb8_from_linear(1.0f), 255);
    EXPECT_EQ(srgb8_from_linear(0.5f), 188);        // 0.73536 * 255 = 187.52
    EXPECT_EQ(srgb8_from_linear(0.18f), 118);       // 0.46136 * 255 = 117.65
    EXPECT_EQ(srgb8_from_linear(0.0031308f), 10);   // 0.04045 * 255 = 10.31
}

struct DecodedPng {
    int width = 0;
    int height = 0;
    int channels = 0;
    std::vector<uint8_t> levels;
};

// Decodes a PNG with libpng's simplified reader, in the file's own format.
DecodedPng decode_png(const std::string& path) {
    png_image image;
    std::memset(&image, 0, sizeof(image));
    image.version = PNG_IMAGE_VERSION;
    if (png_image_begin_read_from_file(&image, path.c_str()) == 0) {
        ADD_FAILURE() << "libpng cannot open " << path << ": " << image.message;
        return {};
    }
    DecodedPng decoded;
    decoded.width = int(image.width);
    decoded.height = int(image.height);
    decoded.channels = int(PNG_IMAGE_PIXEL_CHANNELS(image.format));
    decoded.levels.resize(PNG_IMAGE_SIZE(image));
    if (png_image_finish_read(&image, nullptr, decoded.levels.data(), 0, nullptr) == 0) {
        ADD_FAILURE() << "libpng cannot decode " << path << ": " << image.message;
    }
    png_image_free(&image);
    return decoded;
}

std::string file_bytes(const std::string& path) {
    std::ifstream file(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(file), {});
}

TEST(PngImage, RgbFileDecodesToSrgbLevels) {
    const fs::path folder = testing::test_folder("png");
    // 3 x 2, top row first: black, white, mid grey / 0.18 grey, over-white (clamped), negative.
    const std::vector<float> pixels = {0, 0, 0,        1, 1, 1,  0.5f, 0.5f, 0.5f,
                                       0.18f, 0.5f, 1, 4, 2, 1,  -1, 0.0031308f, 0.5f};
    const std::string path = (folder / "rgb.png").string();
    write_png(path, pixels, 3, 2, 3);
    const DecodedPng png = decode_png(path);
    EXPECT_EQ(png.width, 3);
    EXPECT_EQ(png.height, 2);
    EXPECT_EQ(png.channels, 3);
    EXPECT_EQ(png.levels, (std::vector<uint8_t>{0, 0, 0, 255, 255, 255, 188, 188, 188,
                                                118, 188, 255, 255, 255, 255, 0, 10, 188}));
    EXPECT_NE(file_bytes(path).find("sRGB"), std::string::npos) << "no sRGB chunk";
    EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 1)
        << "a temporary file was left behind";
}

TEST(PngImage, ExposureAndPremultipliedAlpha) {
    const fs::path folder = testing::test_folder("png");
    // Premultiplied 0.125 at alpha 0.5 is straight 0.25; one stop of exposure makes it 0.5.
    const std::vector<float> pixels = {0.125f, 0.125f, 0.125f, 0.5f,  0.3f, 0.2f, 0.1f, 0.0f};
    const std::string path = (folder / "rgba.png").string();
    write_png(path, pixels, 2, 1, 4, PngWriteSettings{1.0f, true});
    DecodedPng png = decode_png(path);
    EXPECT_EQ(png.channels, 4);
    // Alpha 0.5 * 255 = 127.5 rounds to 128; fully transparent colour stays 0.
    EXPECT_EQ(png.levels, (std::vector<uint8_t>{188, 188, 188, 128, 0, 0, 0, 0}));

    // Straight alpha: colour is not divided; exposure -1 halves 1.0 to 0.5.
    const std::vector<float> straight = {1.0f, 1.0f, 1.0f, 0.5f};
    write_png(path, straight, 1, 1, 4, PngWriteSettings{-1.0f, false});
    png = decode_png(path);
    EXPECT_EQ(png.levels, (std::vector<uint8_t>{188, 188, 188, 128}));
}

TEST(PngImage, BadInputIsRejectedWithTheReason) {
    const fs::path folder = testing::test_folder("png");
    const std::string path = (folder / "bad.png").string();
    const std::vector<float> rgb(12, 0.5f);
    EXPECT_THROW(write_png(path, rgb, 2, 2, 2), InvalidArgument);     // 2 channels
    EXPECT_THROW(write_png(path, rgb, 2, 1, 3), InvalidArgument);     // 12 values for 6
    EXPECT_THROW(write_png(path, rgb, 0, 4, 3), InvalidArgument);     // zero width
    EXPECT_THROW(write_png(path, rgb, 2, 2, 3, PngWriteSettings{std::nanf(""), true}),
                 InvalidArgument);
    const std::string no_folder = (folder / "missing" / "out.png").string();
    testing::expect_error<IoError>([&] { write_png(no_folder, rgb, 2, 2, 3); }, {no_folder});
    EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 0);
}

}  // namespace
}  // namespace shgi
