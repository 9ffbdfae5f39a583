// `nerfpt train`: fit a NeRF to posed images (transforms.json) on the CPU and write a model file, with
// checkpoints every few hundred steps and on Ctrl-C, and --resume to continue exactly where it stopped.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "common.h"

namespace npt::cli {

struct TrainArgs {
    std::string data;
    std::string output;
    std::string split = "train";
    std::string config;
    uint64_t steps = 0;    // total steps; 0: until --time, or the default
    double seconds = 0;    // total training seconds; 0: no limit
    int downscale = 1;
    int threads = 0;
    std::string backend;  // "", cpu or cuda (backend_option.h)
    int checkpoint_every = 0;  // 0: the config's
    bool resume = false;
    bool relightable = false;        // run the relight stage after training (relight_stage.h)
    uint64_t relight_steps = 1500;
    int relight_points = 0;      // 0: the backend's default (relight_stage.h)
    int relight_directions = 16;
    int relight_batch = 0;       // 0: the backend's default
    float relight_smoothing = 0.02f;
    std::string relight_normals = "depth";  // depth | density (nerf::NormalEstimator)
    bool force = false;
    // The command that continues after an interrupt, printed then; empty: this train command with --resume.
    std::string resume_hint;
};

CLI::App* add_train_command(CLI::App& app, TrainArgs& args);
int run_train(const TrainArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
