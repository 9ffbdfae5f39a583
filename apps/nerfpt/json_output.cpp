#include "json_output.h"

#include <fstream>

#include "core/error.h"

namespace npt::cli {
namespace fs = std::filesystem;

void write_json(const fs::path& path, const nlohmann::json& j) {
    const fs::path tmp = path.string() + ".tmp";
    {
        std::ofstream f(tmp);
        f << j.dump(2) << "\n";
        if (!f) throw Error(path.string() + ": cannot write (is the disk full?)");
    }
    std::error_code ec;
    fs::rename(tmp, path, ec);
    if (ec) throw Error(path.string() + ": cannot write (" + ec.message() + ")");
}

}  // namespace npt::cli
