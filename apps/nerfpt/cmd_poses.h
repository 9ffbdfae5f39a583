// `nerfpt poses`: camera poses for a folder of frames with COLMAP, written as an instant-ngp transforms.json.
#pragma once

#include <CLI/CLI.hpp>
#include <cstddef>
#include <string>

#include "common.h"

namespace npt::cli {

struct PosesArgs {
    std::string frames;
    std::string output;
    std::string work;  // empty: <output folder>/colmap
    std::string matcher = "sequential";
    std::string quality = "fast";  // capture::PosesQuality: fast, balanced, best
    std::string camera_model = "OPENCV";  // COLMAP's camera model for the one shared camera
    int aabb_scale = 16;
    int max_image_size = 1600;
    double min_registered = 0.5;
    int threads = 0;  // COLMAP's threads; 0: all hardware threads
};

// --poses-quality, shared by `nerfpt poses` and `nerfpt capture`.
void add_poses_quality_option(CLI::App* cmd, std::string& quality, const std::string& prefix);

// --camera-model, shared by `nerfpt poses` and `nerfpt capture`.
void add_camera_model_option(CLI::App* cmd, std::string& model, const std::string& prefix);

CLI::App* add_poses_command(CLI::App& app, PosesArgs& args);
int run_poses(const PosesArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

// What the poses stage found, for `nerfpt capture`'s report.
struct PosesSummary {
    size_t frames = 0, registered = 0, points = 0;
    double reprojection_px = 0;
    size_t path_jumps = 0;  // capture/path_continuity.h
    // extraction, matching, mapping, loop closure, refinement (capture::k_colmap_steps)
    double seconds[5] = {};          // wall
    double cpu_seconds[5] = {};      // the same steps' CPU time (user + system)
    size_t loop_pairs = 0;           // revisiting pairs the loop closure matched
    double refine_threshold_px = 0;  // the refinement's filter (0: not run)
    int max_num_features = 0;       // SIFT budget per frame
    std::string model_folder;       // the COLMAP model transforms.json was written from
};
// The stage itself (COLMAP, checks, transforms.json), printing as `nerfpt poses` does.
PosesSummary poses_stage(const PosesArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
