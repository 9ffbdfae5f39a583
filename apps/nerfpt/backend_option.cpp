#include "backend_option.h"

#include <spdlog/spdlog.h>

namespace npt::cli {

void add_backend_option(CLI::App* cmd, std::string& backend) {
    cmd->add_option("--backend", backend,
                    "Where the NeRF runs: cuda (a GPU) or cpu (default: cuda when this nerfpt has CUDA and a GPU "
                    "is present, else cpu)")
        ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
}

void check_requested_backend(const std::string& requested) {
    if (requested == "cuda") nerf::choose_backend(requested);
}

nerf::Backend resolve_backend(const std::string& requested) {
    const nerf::BackendChoice c = nerf::choose_backend(requested);
    if (!c.note.empty()) spdlog::info("{}", c.note);
    return c.backend;
}

}  // namespace npt::cli
