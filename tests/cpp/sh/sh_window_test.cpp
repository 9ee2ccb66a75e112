// Windowing factors (Sloan 2008, §"Windowing").
#include "sh/sh_window.h"

#include <gtest/gtest.h>

#include <cmath>

#include "util/error.h"

namespace shgi {
namespace {

constexpr float kExact = 1e-6f;

TEST(ShWindow, NoneIsIdentity) {
    const BandFactors f = sh_window_factors(ShWindow::None, 4);
    for (int l = 0; l <= 4; ++l) EXPECT_EQ(f[l], 1.0f);
}

TEST(ShWindow, HanningAndLanczosClosedForms) {
    // Default width = order + 1 = 3 for L2.
    const BandFactors hanning = sh_window_factors(ShWindow::Hanning, 2);
    EXPECT_NEAR(hanning[0], 1.0f, kExact);
    EXPECT_NEAR(hanning[1], 0.75f, kExact);  // (1 + cos(π/3)) / 2
    EXPECT_NEAR(hanning[2], 0.25f, kExact);  // (1 + cos(2π/3)) / 2
    EXPECT_EQ(hanning[3], 0.0f);             // above the order
    const BandFactors lanczos = sh_window_factors(ShWindow::Lanczos, 2);
    EXPECT_NEAR(lanczos[0], 1.0f, kExact);
    EXPECT_NEAR(lanczos[1], std::sin(kPi / 3.0f) / (kPi / 3.0f), kExact);
    EXPECT_NEAR(lanczos[2], std::sin(2.0f * kPi / 3.0f) / (2.0f * kPi / 3.0f), kExact);
    // An explicit narrow width cuts bands at and beyond it.
    const BandFactors narrow = sh_window_factors(ShWindow::Hanning, 4, 2.0f);
    EXPECT_NEAR(narrow[1], 0.5f, kExact);
    EXPECT_EQ(narrow[2], 0.0f);
    EXPECT_EQ(narrow[4], 0.0f);
}

TEST(ShWindow, FactorsDecreaseAndKeepTheMean) {
    for (ShWindow window : {ShWindow::Hanning, ShWindow::Lanczos}) {
        const BandFactors f = sh_window_factors(window, 4);
        EXPECT_EQ(f[0], 1.0f);
        for (int l = 1; l <= 4; ++l) {
            EXPECT_LT(f[l], f[l - 1]);
            EXPECT_GT(f[l], 0.0f);
        }
    }
}

TEST(ShWindow, ApplyScalesEachBand) {
    ShRgb sh(2);
    for (int i = 0; i < 9; ++i) sh.coeffs[i] = vec3(1.0f);
    sh_apply_window(sh, ShWindow::Hanning);
    EXPECT_NEAR(sh.coeffs[0].x, 1.0f, kExact);
    EXPECT_NEAR(sh.coeffs[sh_index(1, -1)].y, 0.75f, kExact);
    EXPECT_NEAR(sh.coeffs[sh_index(2, 2)].z, 0.25f, kExact);
}

TEST(ShWindow, NamesRoundTripAndBadInputIsRejected) {
    for (ShWindow window : {ShWindow::None, ShWindow::Hanning, ShWindow::Lanczos})
        EXPECT_EQ(parse_sh_window(sh_window_name(window)), window);
    EXPECT_THROW(parse_sh_window("hamming"), InvalidArgument);
    EXPECT_THROW(sh_window_factors(ShWindow::Hanning, 5), InvalidArgument);
    EXPECT_THROW(sh_window_factors(ShWindow::Hanning, 2, NAN), InvalidArgument);
}

}  // namespace
}  // namespace shgi
