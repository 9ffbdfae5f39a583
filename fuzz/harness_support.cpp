#include "harness_support.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>

namespace npt::fuzz {
namespace fs = std::filesystem;

const fs::path& scratch() {
    static const fs::path dir = [] {
        spdlog::set_level(spdlog::level::off);
        std::string pattern = (fs::temp_directory_path() / "nerfpt-fuzz-XXXXXX").string();
        if (!mkdtemp(pattern.data())) std::abort();
        fs::current_path(pattern);
        std::atexit([] {
            std::error_code ec;
            fs::current_path(fs::temp_directory_path(), ec);
            fs::remove_all(scratch(), ec);
        });
        return fs::path(pattern);
    }();
    return dir;
}

fs::path put(const std::string& name, const uint8_t* data, size_t size) {
    const fs::path p = scratch() / name;
    std::ofstream(p, std::ios::binary | std::ios::trunc)
        .write(reinterpret_cast<const char*>(data), std::streamsize(size));
    return p;
}

fs::path put(const std::string& name, std::string_view text) {
    return put(name, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

}  // namespace npt::fuzz
