// `nerfpt isolate`: the object alone in a captured model (issue 25): its occupancy grid cut to the object's
// box above the supporting plane, floaters (small connected components) removed (nerf/object_isolation.h).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "common.h"
#include "nerf/object_isolation.h"

namespace npt::cli {

struct IsolateArgs {
    std::string model;
    std::string output;
    nerf::IsolationSettings settings;
};

CLI::App* add_isolate_command(CLI::App& app, IsolateArgs& args);
int run_isolate(const IsolateArgs& args, const GlobalSettings& global);

}  // namespace npt::cli
