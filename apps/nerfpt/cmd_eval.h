// `nerfpt eval`: render a trained model from a data set's held-out cameras and score it against the ground
// truth with PSNR and SSIM as the NeRF papers do (white background, sRGB-encoded values), optionally writing
// the renders, side-by-side comparisons and metrics.json; with ground-truth object masks, also mask IoU,
// boundary F and leak of the model's alpha, and the alpha maps themselves.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "common.h"

namespace npt::cli {

struct EvalArgs {
    std::string model;
    std::string data;
    std::string split = "test";
    std::string output;  // folder; empty: print the metrics only
    int every = 1;
    int downscale = 1;
    int threads = 0;
    std::string backend;  // "", cpu or cuda (backend_option.h)
    bool alpha = false;   // write NAME_alpha.png (needs output)
    std::string masks;    // folder of ground-truth masks, DIR/<image stem>.png; empty: no mask metrics
    bool object = false;  // render only the model's object box (its object frame), as placement "object" does
};

CLI::App* add_eval_command(CLI::App& app, EvalArgs& args);
int run_eval(const EvalArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
