// `nerfpt train`: fit a NeRF to posed images (transforms.json) on the CPU and write a model file, with
// checkpoints every few hundred steps and on Ctrl-C, and --resume to continue exactly where it stopped.
#pragma once

#include <CLI/CLI.hpp>
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "common.h"
#include "core/vec.h"
#include "live_training.h"
#include "nerf/training_observer.h"
#include "relight_stage.h"

namespace npt::cli {

// The surface-smoothness loss's weight when --relightable trains a new model (docs/relighting.md: normals 9.5 ->
// 4.8 degrees on dev with the prefiltered fit and Burley's diffuse, relit views +0.7 dB; docs/benchmarks.md).
constexpr float k_relightable_surface_smoothness = 0.3f;

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
    // < 0: k_relightable_surface_smoothness with --relightable and no --config, else the config's
    // loss.surface_smoothness.
    float surface_smoothness = -1.0f;
    bool resume = false;
    bool relightable = false;        // run the relight stage after training (relight_stage.h)
    RelightStageOptions relight;  // --relight-*; steps, points and batch of 0 are the stage's defaults
    std::string relight_normals = "depth";  // depth | density (nerf::NormalEstimator)
    std::string relight_specular = "prefiltered";  // prefiltered | sampled (nerf::SpecularEstimate)
    std::string relight_diffuse;                // sampled | ratio (nerf::DiffuseEstimate); "": as the specular
    std::string relight_diffuse_lobe = "burley";  // burley | layered (nerf::IntrinsicDiffuse)
    bool force = false;
    // The command that continues after an interrupt, printed then; empty: this train command with --resume.
    std::string resume_hint;
    // The corners of a box that holds the subject, in the data's world (nerfpt capture: the object stage's
    // box): training.subject_rays of each step's rays are drawn where the training images see it
    // (subject_focus.h).
    std::optional<std::array<Vec3, 8>> subject_box;
    LiveServeArgs serve;  // --serve: the live-training page (live_training.h)
    // Watches the training instead of a page of its own (nerfpt capture --serve passes its page's); not owned.
    nerf::TrainingObserver* observer = nullptr;
};

CLI::App* add_train_command(CLI::App& app, TrainArgs& args);
int run_train(const TrainArgs& args, const GlobalSettings& global, InterruptGuard& interrupts);

}  // namespace npt::cli
