// The --backend option of the NeRF commands (train, eval, view, bake, capture): cpu or cuda, and what happens
// when it is left out (cuda where this binary has it and a GPU is present; otherwise cpu, with one info line).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "nerf/backend/nerf_backend.h"

namespace npt::cli {

void add_backend_option(CLI::App* cmd, std::string& backend);

// An explicit --backend cuda without a usable GPU fails here, before any input is loaded (no note is logged).
void check_requested_backend(const std::string& requested);

// Resolves the option and logs the CPU fallback's reason once. Throws npt::Error for --backend cuda without a
// usable GPU.
nerf::Backend resolve_backend(const std::string& requested);

}  // namespace npt::cli
