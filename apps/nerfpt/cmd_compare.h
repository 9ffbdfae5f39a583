// `nerfpt compare`: error measures between a render and a reference image (relMSE, per-channel means), the
// same numbers the reference tests and benchmarks use.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "common.h"

namespace npt::cli {

struct CompareArgs {
    std::string image;
    std::string reference;
};

CLI::App* add_compare_command(CLI::App& app, CompareArgs& args);
int run_compare(const CompareArgs& args, const GlobalSettings& global);

}  // namespace npt::cli
