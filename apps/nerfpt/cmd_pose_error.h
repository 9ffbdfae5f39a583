// `nerfpt pose-error`: how far camera poses (a transforms.json or a COLMAP model) are from a reference, after
// a similarity alignment.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "common.h"

namespace npt::cli {

struct PoseErrorArgs {
    std::string estimate;
    std::string reference;
    std::string match = "name";
    std::string json;                // empty: no report file
    std::vector<double> known_rate;  // {a, b} with --match rate: no search
    bool pieces = false;             // also align each continuous piece of the reference alone
};

CLI::App* add_pose_error_command(CLI::App& app, PoseErrorArgs& args);
int run_pose_error(const PoseErrorArgs& args, const GlobalSettings& global);

}  // namespace npt::cli
