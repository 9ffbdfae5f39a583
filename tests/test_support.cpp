#include "test_support.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

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

std::filesystem::path cli_binary() {
    // The GPU machine runs binaries copied out of the build tree (scripts/gpu_check.sh sets this).
    if (const char* env = std::getenv("NERFPT_CLI"); env && *env) return env;
    return std::filesystem::path(NERFPT_BINARY_DIR) / "nerfpt";
}

std::string read_text(const std::filesystem::path& path) {
    std::ifstream f(path);
    return {std::istreambuf_iterator<char>(f), {}};
}

int spawn_cli(const std::vector<std::string>& args, const std::filesystem::path& log, const std::string& path_env) {
    std::vector<std::string> full = args;
    full.insert(full.begin(), cli_binary().string());
    const pid_t pid = fork();
    if (pid == 0) {
        std::vector<char*> argv;
        for (auto& a : full) argv.push_back(a.data());
        argv.push_back(nullptr);
        const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        dup2(fd, 1);
        dup2(fd, 2);
        if (!path_env.empty()) setenv("PATH", path_env.c_str(), 1);
        execv(argv[0], argv.data());
        _exit(127);
    }
    return int(pid);
}

int wait_exit(int pid) {
    int status = 0;
    waitpid(pid_t(pid), &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

int run_cli(const std::vector<std::string>& args, const std::filesystem::path& log, const std::string& path_env) {
    return wait_exit(spawn_cli(args, log, path_env));
}

}  // namespace npt::test
