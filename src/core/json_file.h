// Reading a JSON file with the project's one-line errors, for the small JSON files the capture stages pass
// along (transforms.json, capture.json).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

namespace npt {

// Throws npt::Error: "PATH: no such file", "PATH: cannot read", "PATH: not valid JSON (parser's reason)".
nlohmann::json read_json_file(const std::filesystem::path& path);

}  // namespace npt
