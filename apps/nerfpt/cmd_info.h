// `nerfpt info`: print what a scene file holds after loading, as the renderer will see it.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "common.h"

namespace npt::cli {

struct InfoArgs {
    std::string scene;
    std::string camera;
};

CLI::App* add_info_command(CLI::App& app, InfoArgs& args);
int run_info(const InfoArgs& args, const GlobalSettings& global);

}  // namespace npt::cli
