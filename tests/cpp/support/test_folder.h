// A fresh, empty folder per running test under the build's test_tmp directory, and files in it.
//
// ctest runs the tests of one binary as parallel processes, so files written by a test must not
// share a name with another test's: the folder is named after the test suite and test.
#pragma once

#include <filesystem>
#include <fstream>
#include <map>
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

// Path of the file `name` in the folder test_folder(area) made by this process's first call for
// `area`; later calls reuse that folder, so files written earlier are kept.
inline std::string test_file_path(const std::string& area, const std::string& name) {
    static std::map<std::string, std::string> folders;
    auto folder = folders.find(area);
    if (folder == folders.end()) folder = folders.emplace(area, test_folder(area).string()).first;
    return folder->second + "/" + name;
}

// Writes `contents` to `path` byte for byte, failing the test if that does not succeed.
inline void write_file(const std::string& path, const std::string& contents) {
    std::ofstream file(path, std::ios::binary);
    file << contents;
    ASSERT_TRUE(file.good()) << path;
}

}  // namespace shgi::testing
