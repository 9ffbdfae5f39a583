#include "input_checks.h"

#include <unistd.h>

#include "core/error.h"

namespace npt::cli {
namespace fs = std::filesystem;

void require_path(const fs::path& path, const std::string& what) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(what + " '" + path.string() + "': no such file or folder");
}

void require_file(const fs::path& path, const std::string& what) {
    std::error_code ec;
    if (!fs::exists(path, ec)) throw Error(what + " '" + path.string() + "': file not found");
    if (fs::is_directory(path, ec)) throw Error(what + " '" + path.string() + "': is a folder, not a file");
}

void prepare_output_folder(const fs::path& dir, const std::string& what) {
    std::error_code ec;
    if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
        throw Error(what + " '" + dir.string() + "': exists and is not a folder");
    fs::create_directories(dir, ec);
    if (ec) throw Error(what + " '" + dir.string() + "': cannot create the folder (" + ec.message() + ")");
    if (access(dir.c_str(), W_OK) != 0) throw Error(what + " '" + dir.string() + "': folder is not writable");
}

void require_writable_parent(const fs::path& file, const std::string& what) {
    const fs::path dir = file.parent_path().empty() ? fs::path(".") : file.parent_path();
    std::error_code ec;
    if (!fs::is_directory(dir, ec))
        throw Error(what + " '" + file.string() + "': folder '" + dir.string() +
                    "' does not exist (create it first)");
    if (access(dir.c_str(), W_OK) != 0)
        throw Error(what + " '" + file.string() + "': folder '" + dir.string() + "' is not writable");
    if (fs::is_directory(file, ec)) throw Error(what + " '" + file.string() + "': is a folder");
}

}  // namespace npt::cli
