// A hook in the training loop for whoever watches it (the live-training page of `nerfpt train --serve`,
// src/serve/training_monitor.h): a few numbers after every step and, at most every few seconds, the model's
// parameters. Without an observer the loop does nothing more; the observer keeps every call short (a lock and a
// copy) and does its own work (renders, encoding, the network) on its own thread.
#pragma once

#include <cstdint>
#include <string>

#include "nerf/backend/nerf_backend.h"
#include "nerf/dataset.h"
#include "nerf/nerf_model.h"
#include "nerf/trainer.h"

namespace npt::nerf {

struct TrainingStart {
    const Dataset* data = nullptr;  // the training set; outlives the training
    std::string data_path;          // DATA as given (a folder or a transforms.json)
    std::string split;              // the training split; the observer looks for held-out views beside it
    int downscale = 1;
    Mat4 world_to_model;  // the model's (the live page orbits around its box)
    Backend backend = Backend::cpu;
    std::string device;
    uint64_t start_step = 0;       // > 0 when resuming
    uint64_t target_steps = 0;     // UINT64_MAX: until target_seconds
    double target_seconds = 0;     // 0: no time limit
};

class TrainingObserver {
  public:
    virtual ~TrainingObserver() = default;
    virtual void on_start(const TrainingStart& start) = 0;
    // After every step, on the training thread: `elapsed` seconds of training in total, `fraction` done.
    virtual void on_step(const StepStats& stats, double elapsed, double fraction) = 0;
    // Polled after every step: true when the observer wants the parameters now (the loop then syncs the model
    // and calls on_snapshot). Cheap: a clock and a flag.
    virtual bool snapshot_due() = 0;
    // The model with its parameters and occupancy grid synced: copy what is needed and return.
    virtual void on_snapshot(const NerfModel& model, uint64_t step) = 0;
    // Training stopped (its model is saved); `interrupted` by Ctrl-C.
    virtual void on_finish(uint64_t steps, double elapsed, bool interrupted) = 0;
};

}  // namespace npt::nerf
