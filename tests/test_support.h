// Helpers shared by tests: where the shared data and the test data live, temporary folders.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <initializer_list>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/vec.h"

namespace npt::test {

// ../shared/data (or $NERFPT_SHARED_DATA). Tests that need it call GTEST_SKIP when it is missing.
std::filesystem::path shared_data();
// tests/data in the source tree.
std::filesystem::path test_data();
// A fresh, empty folder under the build tree, named after the running test.
std::filesystem::path temp_dir();
// Writes `content` to `path` (binary), creating parent folders.
void write_file(const std::filesystem::path& path, const std::string& content);

// The nerfpt binary of this build (tests that run it skip when it is not built).
std::filesystem::path cli_binary();
// The whole file as text ("" when it cannot be read).
std::string read_text(const std::filesystem::path& path);
// Starts the nerfpt binary with `args` (not including the binary), stdout and stderr into `log`, PATH replaced
// by `path_env` when it is not empty.
int spawn_cli(const std::vector<std::string>& args, const std::filesystem::path& log,
              const std::string& path_env = "");
// Waits for a spawned process: its exit code, or 128 + the signal that killed it.
int wait_exit(int pid);
// spawn_cli + wait_exit.
int run_cli(const std::vector<std::string>& args, const std::filesystem::path& log,
            const std::string& path_env = "");

// Runs `fn` and expects an npt::Error whose message is one line and contains every one of `parts` (the file,
// the field...): the project's rule for errors a user sees.
template <typename Fn>
void expect_error_message(Fn&& fn, std::initializer_list<std::string> parts) {
    try {
        fn();
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        for (const auto& p : parts)
            EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
    }
}

inline void expect_near(Vec3 a, Vec3 b, float tol = 1e-5f) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

}  // namespace npt::test

// Skips the current test with a clear message when a shared data path is missing.
#define NPT_REQUIRE_SHARED(path)                                                                             \
    do {                                                                                                     \
        if (!std::filesystem::exists(path))                                                                  \
            GTEST_SKIP() << "shared data missing: " << (path).string() << " (see ../shared/data/README.md)"; \
    } while (0)
