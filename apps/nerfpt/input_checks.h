// Checks on the paths a subcommand is given, made before any slow loading so that a typo fails in
// milliseconds with a message naming the option: inputs that must exist, output folders that must be
// writable.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

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

// One of a command's inputs, named as the command line names it ("DATA", "MODEL", "image of frame 3").
struct InputFile {
    std::string what;
    std::filesystem::path path;
};

// True when `a` and `b` name the same file: the same inode when both exist (symbolic and hard links, "./x",
// "a/../x"), else the same normalised absolute path.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

// No command writes over one of its own inputs, --force or not: throws npt::Error "OPTION 'out': is the input
// WHAT 'in'; write the output elsewhere" when `output` is the same file as one of `inputs`.
void refuse_overwriting_inputs(const std::filesystem::path& output, const std::string& option,
                               const std::vector<InputFile>& inputs);

}  // namespace npt::cli
