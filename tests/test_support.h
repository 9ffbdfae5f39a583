// Helpers shared by tests: where the shared data and the test data live, temporary folders.
#pragma once

#include <filesystem>
#include <string>

namespace npt::test {

// ../shared/data (or $NERFPT_SHARED_DATA). Tests that need it call GTEST_SKIP when it is missing.
std::filesystem::path shared_data();
// tests/data in the source tree.
std::filesystem::path test_data();
// A fresh, empty folder under the build tree, named after the running test.
std::filesystem::path temp_dir();
// Writes `content` to `path` (binary), creating parent folders.
void write_file(const std::filesystem::path& path, const std::string& content);

}  // namespace npt::test

// Skips the current test with a clear message when a shared data path is missing.
#define NPT_REQUIRE_SHARED(path)                                                                      \
    do {                                                                                              \
        if (!std::filesystem::exists(path))                                                           \
            GTEST_SKIP() << "shared data missing: " << (path).string() << " (see ../shared/data/README.md)"; \
    } while (0)
