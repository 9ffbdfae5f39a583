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

bool same_file(const fs::path& a, const fs::path& b) {
    std::error_code ec;
    if (fs::exists(a, ec) && fs::exists(b, ec)) {
        const bool same = fs::equivalent(a, b, ec);
        if (!ec) return same;
    }
    const fs::path ca = fs::weakly_canonical(fs::absolute(a, ec), ec);
    const fs::path cb = fs::weakly_canonical(fs::absolute(b, ec), ec);
    return !ca.empty() && ca == cb;
}

void refuse_overwriting_inputs(const fs::path& output, const std::string& option,
                               const std::vector<InputFile>& inputs) {
    for (const InputFile& in : inputs)
        if (!in.path.empty() && same_file(output, in.path))
            throw Error(
                option + " '" + output.string() + "': is the input " + in.what + " '" + in.path.string() +
                "'; write the output elsewhere (no command replaces its own input, even with --force)");
}

}  // namespace npt::cli
