// A fresh, empty folder per running test under the build's test_tmp directory.
//
// ctest runs the tests of one binary as parallel processes, so files written by a test must not
// share a name with another test's: the folder is named after the test suite and test.
#pragma once

#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace shgi::testing {

// `area` groups folders by the code under test ("png", "gltf", ...).
inline std::filesystem::path test_folder(const std::string& area) {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    const std::filesystem::path folder = std::filesystem::path(SHGI_TEST_TMPDIR) / area /
                                         (std::string(info->test_suite_name()) + "." +
                                          info->name());
    std::filesystem::remove_all(folder);
    std::filesystem::create_directories(folder);
    return folder;
}

}  // namespace shgi::testing
