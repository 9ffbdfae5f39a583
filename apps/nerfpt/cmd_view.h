// `nerfpt view`: novel views of a trained model on its own: one data-set camera to a PNG, or an orbit around
// the model to an .mp4 (through ffmpeg) or numbered PNGs.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "common.h"

namespace npt::cli {

struct ViewArgs {
    std::string model;
    std::string output;
    std::string camera;  // "DATA:INDEX"; empty: orbit
    std::string split = "test";
    int orbit = 0;    // frames; 0: not given (120 when there is no --camera)
    std::string res;  // "WxH"; empty: the camera's, or 800x800 for an orbit
    float fov = 0;    // horizontal, degrees; 0: the camera's, or 40 for an orbit
    float elevation = 30.0f;
    float distance = 0;  // world units; 0: from the model's scale
    float fps = 30.0f;
    bool object = false;  // only the object box of a captured model (its object frame); an orbit circles it
    int threads = 0;
    std::string backend;  // "", cpu or cuda (backend_option.h)
};

CLI::App* add_view_command(CLI::App& app, ViewArgs& args);
int run_view(const ViewArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
