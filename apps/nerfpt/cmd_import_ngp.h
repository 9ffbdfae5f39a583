// `nerfpt import-ngp`: convert an instant-ngp snapshot (.msgpack or .ingp) into a nerfpt model file, so that
// a NeRF trained on a GPU with instant-ngp can be rendered, baked and evaluated here.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "common.h"

namespace npt::cli {

struct ImportNgpArgs {
    std::string snapshot;
    std::string output;
};

CLI::App* add_import_ngp_command(CLI::App& app, ImportNgpArgs& args);
int run_import_ngp(const ImportNgpArgs& args, const GlobalSettings& global);

}  // namespace npt::cli
