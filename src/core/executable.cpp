#include "core/executable.h"

#include <unistd.h>

#include <cstdlib>
#include <string_view>
#include <system_error>

namespace npt {
namespace fs = std::filesystem;

namespace {

bool is_executable_file(const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
}

}  // namespace

fs::path find_executable(const std::string& name) {
    if (name.empty()) return {};
    if (name.find('/') != std::string::npos) return is_executable_file(name) ? fs::path(name) : fs::path();
    const char* path = std::getenv("PATH");
    std::string_view rest = path ? path : "";
    while (!rest.empty()) {
        const size_t colon = rest.find(':');
        const std::string dir(rest.substr(0, colon));
        rest = colon == std::string_view::npos ? std::string_view() : rest.substr(colon + 1);
        const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
        if (is_executable_file(candidate)) return candidate;
    }
    return {};
}

}  // namespace npt
