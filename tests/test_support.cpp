#include "test_support.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

namespace npt::test {

std::filesystem::path shared_data() {
    if (const char* env = std::getenv("NERFPT_SHARED_DATA")) return env;
    return NERFPT_SHARED_DATA;
}

std::filesystem::path test_data() { return NERFPT_TEST_DATA; }

std::filesystem::path temp_dir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : "test";
    auto dir = std::filesystem::path(NERFPT_BINARY_DIR) / "test_tmp" / name;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir;
}

void write_file(const std::filesystem::path& path, const std::string& content) {
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
    std::ofstream f(path, std::ios::binary);
    f << content;
}

}  // namespace npt::test
