// `nerfpt curate`: pick the sharp, subject-centred frames of a video for pose recovery (first stage of the
// phone-video workflow, issue 7). The work is in capture/curate.h; this file is options and progress.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "capture/curate.h"
#include "common.h"

namespace npt::cli {

struct CurateArgs {
    std::string video;
    std::string output;
    int64_t max_frames = 0;
    int target_frames = 100;
    std::string rule = "window";
    std::string hsv_min;
    std::string hsv_max;
};

CLI::App* add_curate_command(CLI::App& app, CurateArgs& args);
int run_curate(const CurateArgs& args, const GlobalSettings& global);
// The stage itself, with progress bars and the summary line; `nerfpt capture` runs it too.
capture::CurateReport curate_stage(const CurateArgs& args, const GlobalSettings& global);

}  // namespace npt::cli
