// Writing a report as JSON (eval's metrics.json, pose-error's --json) so that an interrupt or a full disk
// never leaves half a file.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

namespace npt::cli {

// Written beside `path` and renamed over it. Throws npt::Error naming the file when it cannot be written.
void write_json(const std::filesystem::path& path, const nlohmann::json& j);

}  // namespace npt::cli
