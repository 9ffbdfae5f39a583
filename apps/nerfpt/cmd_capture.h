// `nerfpt capture`: a phone video to a trained NeRF in one command — curate, poses (COLMAP), a held-out
// split, train, eval on the held-out frames, a turntable video and a report — in one work folder. Each stage
// records its result in WORKDIR/capture.json when it finishes, so running the same command again after a
// crash or Ctrl-C continues with the first unfinished stage (training resumes from its checkpoint).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>

#include "common.h"
#include "live_training.h"
#include "relight_stage.h"

namespace npt::cli {

struct CaptureArgs {
    std::string video;
    std::string output;
    // curate
    int64_t max_frames = 0;
    int target_frames = 100;
    std::string hsv_min, hsv_max;
    // poses
    std::string matcher = "sequential";
    std::string poses_quality = "fast";  // capture::PosesQuality
    std::string camera_model = "OPENCV";  // poses: COLMAP's camera model
    int aabb_scale = 16;
    double min_registered = 0.5;
    // object
    bool relightable = false;  // train: the relight stage after the NeRF (nerfpt train --relightable)
    uint64_t relight_steps = RelightStageOptions{}.steps;
    int relight_points = 0;  // 0: the relight stage's default for the backend
    int relight_pixels = -1;  // borrowing pixels; -1: the relight stage's default for the backend
    double height_m = 0;  // the object's real height in metres; 0: the object frame stays in capture units
    bool keep_scene = false;  // isolate: keep the whole-scene model as model_scene.npt
    // split, train, eval
    int holdout_every = 8;  // 0: train on every frame, no held-out PSNR
    double train_seconds = 600;
    uint64_t train_steps = 0;  // 0: --train-time decides
    int downscale = 0;         // 0: automatic, longest side at most k_auto_train_side
    std::string config;
    // turntable
    int turntable_frames = 60;  // 0: none (2 s at 30 fps: CPU rendering of a capture is slow)
    std::string turntable_res;  // empty: the training image size
    int threads = 0;
    std::string backend;  // train/eval/turntable: "", cpu or cuda (backend_option.h)
    bool force = false;
    LiveServeArgs serve;  // --serve: the live page (training, and the stages as they finish)
};

CLI::App* add_capture_command(CLI::App& app, CaptureArgs& args);
int run_capture(const CaptureArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
