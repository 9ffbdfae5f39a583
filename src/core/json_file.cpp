#include "core/json_file.h"

#include <fstream>
#include <string>
#include <system_error>

#include "core/error.h"

namespace npt {

nlohmann::json read_json_file(const std::filesystem::path& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw Error(path.string() + ": no such file");
    std::ifstream in(path);
    if (!in) throw Error(path.string() + ": cannot read");
    try {
        return nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {  // syntax errors, and number overflow such as 1e999
        throw Error(path.string() + ": not valid JSON (" + e.what() + ")");
    }
}

}  // namespace npt
