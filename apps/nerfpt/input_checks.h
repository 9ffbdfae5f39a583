// Checks on the paths a subcommand is given, made before any slow loading so that a typo fails in
// milliseconds with a message naming the option: inputs that must exist, output folders that must be
// writable.
#pragma once

#include <filesystem>
#include <string>

namespace npt::cli {

// `what` names the argument in messages ("MODEL", "DATA"). Throws npt::Error when `path` does not exist, or
// (for require_file) is a folder.
void require_file(const std::filesystem::path& path, const std::string& what);
void require_path(const std::filesystem::path& path, const std::string& what);

// Creates `dir` (and its parents) when missing; throws npt::Error when that fails, when it is a file, or when
// it is not writable.
void prepare_output_folder(const std::filesystem::path& dir, const std::string& what);

// Throws npt::Error when the folder that would hold `file` does not exist or is not writable, or `file` is a
// folder.
void require_writable_parent(const std::filesystem::path& file, const std::string& what);

}  // namespace npt::cli
